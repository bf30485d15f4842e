"""Primitive point distances (checker.primitives, through checker.shapes):
consistency, optimality against dense surface samples, exact zeros, degenerate
points, half-space, face planes, translation and scale."""

import numpy as np
import pytest
import trimesh
from shaperefs import SIZES

from checker.shapes import Shape, ShapeType, face_plane_distance, signed_distance

pytestmark = pytest.mark.filterwarnings("error")


def _inside(stype, size, p):
    x, y, z = p.T
    if stype is ShapeType.BOX:
        return np.all(np.abs(p) < size, axis=1)
    if stype is ShapeType.SPHERE:
        return np.linalg.norm(p, axis=1) < size[0]
    if stype is ShapeType.CYLINDER:
        return (np.hypot(x, y) < size[0]) & (np.abs(z) < size[1])
    if stype is ShapeType.CAPSULE:
        zc = np.clip(z, -size[1], size[1])
        return np.sqrt(x**2 + y**2 + (z - zc) ** 2) < size[0]
    if stype is ShapeType.ELLIPSOID:
        return np.sum((p / size) ** 2, axis=1) < 1
    raise AssertionError


def _surface_residual(stype, size, c):
    """How far the closest point is from satisfying the surface equation."""
    x, y, z = c.T
    if stype is ShapeType.BOX:
        q = np.abs(c) - size
        return np.abs(np.max(q, axis=1))  # on the surface: max(|c|-h) == 0
    if stype is ShapeType.SPHERE:
        return np.abs(np.linalg.norm(c, axis=1) - size[0])
    if stype is ShapeType.CYLINDER:
        return np.abs(np.maximum(np.hypot(x, y) - size[0], np.abs(z) - size[1]))
    if stype is ShapeType.CAPSULE:
        zc = np.clip(z, -size[1], size[1])
        return np.abs(np.sqrt(x**2 + y**2 + (z - zc) ** 2) - size[0])
    return np.abs(np.sqrt(np.sum((c / size) ** 2, axis=1)) - 1) * min(size)


def _surface_samples(stype, size, n=60000, seed=0):
    """Dense points on the surface, from a fine mesh of the shape."""
    if stype is ShapeType.BOX:
        m = trimesh.creation.box(extents=2 * np.array(size))
    elif stype is ShapeType.SPHERE:
        m = trimesh.creation.icosphere(5, radius=size[0])
    elif stype is ShapeType.CYLINDER:
        m = trimesh.creation.cylinder(size[0], 2 * size[1], sections=256)
    elif stype is ShapeType.CAPSULE:
        m = trimesh.creation.capsule(2 * size[1], size[0], count=[128, 128])
    else:
        m = trimesh.creation.icosphere(5)
        m.vertices *= size
    pts, _ = trimesh.sample.sample_surface_even(m, n, seed=seed)
    pts = np.concatenate([pts, m.vertices])
    # Faces are chords of curved surfaces: push the samples onto the surface.
    if stype is ShapeType.SPHERE:
        pts *= size[0] / np.linalg.norm(pts, axis=1)[:, None]
    elif stype is ShapeType.ELLIPSOID:
        pts /= np.sqrt(np.sum((pts / size) ** 2, axis=1))[:, None]
    elif stype is ShapeType.CYLINDER:
        side = np.abs(pts[:, 2]) < size[1] - 1e-9
        pts[side, :2] *= size[0] / np.linalg.norm(pts[side, :2], axis=1)[:, None]
    elif stype is ShapeType.CAPSULE:
        axis = np.zeros_like(pts)
        axis[:, 2] = np.clip(pts[:, 2], -size[1], size[1])
        off = pts - axis
        pts = axis + size[0] * off / np.linalg.norm(off, axis=1)[:, None]
    return pts


@pytest.mark.parametrize("stype", list(SIZES))
def test_primitive_point_distance_is_consistent_and_optimal(stype):
    size = np.array(SIZES[stype])
    rng = np.random.default_rng(1)
    p = rng.normal(size=(400, 3)) * 0.3
    d, cl = signed_distance(Shape(stype, size), p)
    assert np.all(np.isfinite(d)) and np.all(np.isfinite(cl))
    # |d| is the distance to the returned point, which lies on the surface.
    assert np.allclose(np.abs(d), np.linalg.norm(p - cl, axis=1), rtol=0, atol=1e-12)
    assert np.max(_surface_residual(stype, size, cl)) < 1e-12
    # Negative exactly inside.
    inside = _inside(stype, size, p)
    assert np.array_equal(d < 0, inside)
    # No surface sample is nearer than the closest point found.
    samples = _surface_samples(stype, size)
    from scipy.spatial import cKDTree

    nearest = cKDTree(samples).query(p)[0]
    assert np.all(np.abs(d) <= nearest + 1e-12)
    assert np.all(np.abs(d) >= nearest - 0.01)  # sampling resolution


def test_box_faces_edges_corners_are_exactly_zero():
    h = np.array([1.0, 2.0, 3.0])
    box = Shape(ShapeType.BOX, h)
    on = np.array([[1.0, 0, 0], [1.0, 2.0, 0], [1.0, 2.0, 3.0], [-1.0, -2.0, -3.0], [0, 0, 3.0]])
    d, cl = signed_distance(box, on)
    assert np.all(d == 0.0) and np.allclose(cl, on)
    d, _ = signed_distance(box, np.array([[0.0, 0, 0], [2.0, 3.0, 4.0], [2.0, 0, 0]]))
    assert np.allclose(d, [-1.0, np.sqrt(3.0), 1.0])


def test_degenerate_points_on_axes_and_centres():
    pts = np.array([[0.0, 0, 0], [0, 0, 0.1], [0, 0, 0.35], [0, 0, 1.0], [0.4, 0, 0], [0, 0, -0.1]])
    for stype, size in SIZES.items():
        d, cl = signed_distance(Shape(stype, size), pts)
        assert np.all(np.isfinite(d)) and np.all(np.isfinite(cl))
        assert np.allclose(np.abs(d), np.linalg.norm(pts - cl, axis=1), atol=1e-12)
    d, _ = signed_distance(Shape(ShapeType.ELLIPSOID, [3.0, 2.0, 1.0]), np.zeros((1, 3)))
    assert d[0] == pytest.approx(-1.0, abs=1e-12)
    # Degenerate (spheroid, on the axis, inside): min over x of
    # (x - 1/2)^2 + 1 - x^2/4 is at x = 2/3, distance sqrt(33/36).
    d, _ = signed_distance(Shape(ShapeType.ELLIPSOID, [2.0, 1.0, 1.0]), np.array([[0.5, 0, 0]]))
    assert d[0] == pytest.approx(-np.sqrt(33 / 36), abs=1e-12)


def test_plane_is_a_half_space():
    d, cl = signed_distance(Shape(ShapeType.PLANE, [0.0]), np.array([[5.0, -3.0, 2.0], [1.0, 1.0, -0.5]]))
    assert np.allclose(d, [2.0, -0.5]) and np.allclose(cl[:, 2], 0)


def test_face_plane_distance_underestimates_near_edges():
    box = Shape(ShapeType.BOX, [1.0, 1.0, 1.0])
    p = np.array([[2.0, 2.0, 0.0], [1.5, 0.0, 0.0], [0.5, 0, 0]])
    assert np.allclose(signed_distance(box, p)[0], [np.sqrt(2), 0.5, -0.5])
    assert np.allclose(face_plane_distance(box, p), [1.0, 0.5, -0.5])


def test_translation_and_scale_invariance_of_point_distances():
    rng = np.random.default_rng(7)
    p = rng.normal(size=(200, 3)) * 0.3
    for stype, size in SIZES.items():
        d0, _ = signed_distance(Shape(stype, size), p)
        d1, _ = signed_distance(Shape(stype, np.array(size) * 1000), p * 1000)
        assert np.allclose(d1, d0 * 1000, rtol=1e-12, atol=1e-9)
