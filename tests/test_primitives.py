"""Primitive point distances (cablecheck.checker.primitives, through cablecheck.checker.shapes):
consistency, optimality against dense surface samples, exact zeros, degenerate
points, half-space, face planes, translation and scale."""

from decimal import Decimal, localcontext

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings, strategies as st
from shaperefs import SIZES

from cablecheck.checker.shapes import Shape, ShapeType, face_plane_distance, signed_distance

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


# ---------------------------------------------------------------------------
# The ellipsoid against an independent reference: points near the centre, on
# the axes and principal planes, with equal, nearly equal and distinct radii.


def _ellipsoid_reference(e, p) -> float:
    """Signed distance to the ellipsoid of radii ``e`` in 80-digit decimal
    arithmetic: Eberly's Lagrange root ``t`` of
    ``sum (e_i y_i / (t + e_i^2))^2 = 1`` above ``-m^2`` (``m`` the smallest
    radius) by bisection in ``t`` itself (at 80 digits ``t + e_i^2`` keeps
    its digits for points 1e-20 of ``m`` from the centre). A point inside
    with no component along the smallest radii, where the sum stays below 1
    at ``t = -m^2``, has its closest point at ``t = -m^2``, the smallest
    radii's component from the surface equation."""
    with localcontext() as ctx:
        ctx.prec = 80
        es = [Decimal(float(v)) for v in e]
        y = [abs(Decimal(float(v))) for v in p]
        m2 = min(es) ** 2
        terms = [i for i in range(3) if y[i] != 0]
        inside = sum((yi / ei) ** 2 for yi, ei in zip(y, es)) < 1
        if not terms:
            return -float(min(es))

        def excess(t):
            return sum((es[i] * y[i] / (t + es[i] ** 2)) ** 2 for i in terms) - 1

        pole = [i for i in range(3) if es[i] ** 2 == m2]
        if all(y[i] == 0 for i in pole) and excess(-m2) <= 0:
            x = [es[i] ** 2 * y[i] / (es[i] ** 2 - m2) if i not in pole else Decimal(0) for i in range(3)]
            rest = 1 - sum((x[i] / es[i]) ** 2 for i in range(3))
            d2 = sum((x[i] - y[i]) ** 2 for i in range(3)) + m2 * max(rest, Decimal(0))
            return -float(d2.sqrt())
        lo = -m2
        hi = -m2 + sum((es[i] * y[i]) ** 2 for i in terms).sqrt()
        for _ in range(400):
            mid = (lo + hi) / 2
            if excess(mid) > 0:
                lo = mid
            else:
                hi = mid
        t = (lo + hi) / 2
        d = sum((es[i] ** 2 * y[i] / (t + es[i] ** 2) - y[i]) ** 2 for i in range(3)).sqrt()
        return -float(d) if inside else float(d)


@st.composite
def _radii(draw):
    """Ellipsoid radii in m or mm: distinct, two or three equal (shortest,
    longest or all), or two nearly equal (a few ulps to 1e-3 apart)."""
    base = draw(st.floats(0.003, 0.04)) * draw(st.sampled_from([1.0, 1000.0]))
    e = [base * draw(st.floats(0.5, 2.0)) for _ in range(3)]
    kind = draw(st.sampled_from(["distinct", "equal2", "equal3", "near"]))
    i, j = draw(st.permutations(range(3)))[:2]
    if kind == "equal3":
        e = [e[0]] * 3
    elif kind == "equal2":
        e[j] = e[i]
    elif kind == "near":
        if draw(st.booleans()):
            e[j] = e[i] * (1.0 + draw(st.integers(1, 8)) * 2.0**-52)
        else:
            e[j] = e[i] * (1.0 + 10.0 ** draw(st.floats(-12.0, -3.0)))
    return np.array(e)


@st.composite
def _near_points(draw, e):
    """Points near the centre (1e-16 to 1e-3 of the smallest radius), some
    on an axis or a principal plane (coordinates exactly 0), and a few
    anywhere inside or outside."""
    pts = []
    for _ in range(draw(st.integers(1, 6))):
        # each coordinate 0 (on an axis or a plane) or 1e-3 to 1 of the scale
        v = np.array([draw(st.sampled_from([0.0, 1.0, -1.0, 1.0, -1.0])) * draw(st.floats(1e-3, 1.0))
                      for _ in range(3)])
        scale = 10.0 ** draw(st.floats(-16.0, -3.0)) * min(e)
        pts.append(v * scale)
    for _ in range(draw(st.integers(0, 2))):
        v = np.array([draw(st.floats(-2.0, 2.0)) for _ in range(3)])
        pts.append(np.where(np.abs(v) < 1e-3, 0.0, v) * e)
    return np.array(pts)


@settings(max_examples=300, deadline=None)
@given(st.data())
def test_ellipsoid_matches_a_high_precision_reference_near_the_centre(data):
    from cablecheck.checker.primitives import sd_ellipsoid

    e = data.draw(_radii())
    p = data.draw(_near_points(e))
    d, cl, _ = sd_ellipsoid(np.broadcast_to(e, p.shape), p)
    ref = np.array([_ellipsoid_reference(e, q) for q in p])
    assert np.all(np.isfinite(d)) and np.all(np.isfinite(cl))
    assert np.all(np.abs(d - ref) <= 2e-15 * max(e)), (e, p, d, ref)
    # the closest point is on the surface and at |d|
    assert np.all(np.abs(np.linalg.norm(p - cl, axis=1) - np.abs(d)) <= 2e-15 * max(e))
    assert np.all(np.abs(np.sqrt(np.sum((cl / e) ** 2, axis=1)) - 1.0) <= 2e-15)


@given(st.floats(0.003, 40.0), st.floats(1.0, 3.0), st.floats(-16.0, -3.0), st.floats(0.0, 2 * np.pi),
       st.floats(-1.0, 1.0))
@settings(max_examples=200, deadline=None)
def test_ellipsoid_closed_forms_near_the_centre(b, ratio, lg, ang, w):
    """A ball: d = |p| - r. A prolate spheroid (two shortest radii b equal,
    the third a >= b): on its equal radii's plane d = |p| - b; on its long
    axis, d = -b sqrt(1 - y^2 / (a^2 - b^2)) inside the medial segment
    (|y| < (a^2 - b^2) / a), |y| - a past it."""
    from cablecheck.checker.primitives import sd_ellipsoid

    r = 10.0**lg * b
    ball = np.array([[b, b, b]] * 3)
    p = np.array([[r * np.cos(ang), r * np.sin(ang), 0.0], [r * w, 0.0, r * np.sqrt(1 - w * w)], [0.0, 0.0, r]])
    assert np.all(np.abs(sd_ellipsoid(ball, p)[0] - (np.linalg.norm(p, axis=1) - b)) <= 1e-15 * b)
    a = ratio * b
    for k in range(3):                    # the long axis along x, y or z
        e = np.full(3, b)
        e[k] = a
        plane = np.zeros((2, 3))
        plane[:, [(k + 1) % 3, (k + 2) % 3]] = [[r * np.cos(ang), r * np.sin(ang)], [r, 0.0]]
        d = sd_ellipsoid(np.broadcast_to(e, plane.shape), plane)[0]
        assert np.all(np.abs(d - (np.linalg.norm(plane, axis=1) - b)) <= 1e-15 * a)
        on = np.zeros((1, 3))
        on[0, k] = r * w
        d = sd_ellipsoid(e[None], on)[0]
        c = (a - b) * (a + b)
        # inside the medial segment (|y| < c / a) off the axis; past it, the pole
        ref = -b * np.sqrt(1.0 - (r * w) ** 2 / c) if abs(r * w) < c / a else abs(r * w) - a
        assert abs(d[0] - ref) <= 1e-15 * a


def test_ellipsoid_with_equal_shortest_radii_is_exact_next_to_its_centre():
    """The regression: a ball read -1.0000221 at (1e-12, 0, 1e-14), and a
    spheroid [0.02, 0.04, 0.02] was off by up to 1e-3 m next to its centre
    (5e-5 at (-5, -4, -3) 1e-16, 3e-6 at (8, 0, -3) 1e-15)."""
    ball = Shape(ShapeType.ELLIPSOID, np.array([1.0, 1.0, 1.0]))
    p = np.array([[1e-12, 0.0, 1e-14], [0.0, 0.0, 0.0], [1e-15, 0.0, 0.0], [0.0, -1e-300, 0.0]])
    d, cl = signed_distance(ball, p)
    assert np.all(np.abs(d - (np.linalg.norm(p, axis=1) - 1.0)) <= 2.3e-16)   # an ulp of 1
    assert np.allclose(np.linalg.norm(cl, axis=1), 1.0, rtol=0, atol=1e-16)
    egg = Shape(ShapeType.ELLIPSOID, np.array([0.02, 0.04, 0.02]))
    for s in (1e-18, 1e-16, 1e-15, 1e-14, 1e-12, 1e-9, 1e-6):
        q = np.array([[s, 0.0, 0.0], [0.0, 0.0, s], [s, 0.0, s], [s, s, s], [0.0, s, 0.0], [-s, 0.0, 3 * s],
                      [-5 * s, -4 * s, -3 * s], [8 * s, 0.0, -3 * s], [0.2 * s, 1.8 * s, 0.1 * s]])
        d, _ = signed_distance(egg, q)
        ref = np.array([_ellipsoid_reference([0.02, 0.04, 0.02], x) for x in q])
        assert np.all(np.abs(d - ref) <= 1e-17), (s, d - ref)
        # in mm
        d, _ = signed_distance(Shape(ShapeType.ELLIPSOID, np.array([20.0, 40.0, 20.0])), q * 1000)
        assert np.all(np.abs(d - ref * 1000) <= 1e-14), (s, d - ref * 1000)
