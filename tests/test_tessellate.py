"""Part surfaces: many at once equal one by one, the error bound, closed and outward surfaces."""

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings, strategies as st

from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape, signed_distance
from cablecheck.checker.tessellate import part_surface, part_surfaces

SIZES = st.lists(st.floats(1e-3, 2.0), min_size=3, max_size=3)
CURVED = [ShapeType.SPHERE, ShapeType.CAPSULE, ShapeType.CYLINDER, ShapeType.ELLIPSOID]


def shape_of(kind, s):
    n = {ShapeType.SPHERE: 1, ShapeType.CAPSULE: 2, ShapeType.CYLINDER: 2}.get(kind, 3)
    return Shape(kind, s[:n])


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(CURVED + [ShapeType.BOX, ShapeType.PLANE]), SIZES),
                min_size=1, max_size=8), st.floats(1e-3, 0.1))
def test_many_at_once_equal_one_by_one(rows, tol):
    shapes = [shape_of(k, s) for k, s in rows]
    batch = part_surfaces(shapes, tol)
    for k, sh in enumerate(shapes):
        one = part_surface(sh, tol)
        v = batch.vertices[batch.vert_start[k]:batch.vert_start[k + 1]]
        f = batch.faces[batch.face_start[k]:batch.face_start[k + 1]] - batch.vert_start[k]
        np.testing.assert_allclose(v, one.vertices, rtol=0, atol=1e-12 * max(1.0, np.abs(one.vertices).max(initial=0)))
        np.testing.assert_array_equal(f, one.faces)
        assert batch.closed[k] == one.closed and batch.plane[k] == one.plane
        assert batch.error[k] == one.error


@settings(max_examples=25, deadline=None)
@given(st.sampled_from(CURVED), SIZES, st.floats(2e-3, 0.05))
def test_inscribed_within_the_stated_error(kind, s, frac):
    shape = shape_of(kind, s)
    tol = frac * max(s)
    surf = part_surface(shape, tol)
    assert surf.closed
    tm = trimesh.Trimesh(surf.vertices, surf.faces, process=False)
    assert tm.volume > 0                                          # wound outward
    scale = max(s)
    sd_v, _ = signed_distance(shape, surf.vertices)
    assert np.abs(sd_v).max() <= 1e-9 * scale                     # every vertex on the true surface
    pts, _ = trimesh.sample.sample_surface(tm, 1000, seed=3)
    sd, _ = signed_distance(shape, pts)
    assert np.all(sd <= 1e-9 * scale)                              # inscribed
    # every point of the true surface is within the error of the triangles
    true_pts = signed_distance(shape, np.random.default_rng(0).normal(size=(1000, 3)) * scale)[1]
    d, _ = signed_distance(mesh_shape(surf.vertices, surf.faces), true_pts)
    assert np.abs(d).max() <= surf.error + 1e-9 * scale
    assert surf.error <= tol


def test_boxes_and_meshes_are_exact_and_share_nothing_mutable():
    cube = trimesh.creation.box(extents=[1, 2, 3])
    shapes = [Shape(ShapeType.BOX, [0.5, 1, 1.5]), mesh_shape(cube.vertices, cube.faces), Shape(ShapeType.BOX, [1, 1, 1])]
    batch = part_surfaces(shapes, 1e-2)
    assert batch.closed.all() and not batch.error.any() and batch.face_start[-1] == 36
    np.testing.assert_allclose(batch.vertices[:8].min(axis=0), [-0.5, -1, -1.5])
    np.testing.assert_allclose(batch.vertices[16:].max(axis=0), [1, 1, 1])


def test_bad_tolerance_is_refused():
    with pytest.raises(ValueError):
        part_surfaces([Shape(ShapeType.SPHERE, [1.0])], 0.0)


def _trimesh_template(kind, n):
    """A template as trimesh's primitives make it, cleaned by trimesh (how
    `cablecheck.checker.tessellate` made them before it built them itself)."""
    if kind is ShapeType.SPHERE:
        tm = trimesh.creation.uv_sphere(radius=1.0, count=[n // 2 + 1, n])
    elif kind is ShapeType.CYLINDER:
        tm = trimesh.creation.cylinder(radius=1.0, height=2.0, sections=n)
    else:
        tm = trimesh.creation.capsule(height=2.0, radius=1.0, count=[n, n])
    tm = trimesh.Trimesh(vertices=np.asarray(tm.vertices), faces=np.asarray(tm.faces), process=True)
    tm.update_faces(tm.nondegenerate_faces())
    tm.remove_unreferenced_vertices()
    if tm.volume < 0:
        tm.invert()
    return np.asarray(tm.vertices, float), np.asarray(tm.faces, np.int64), bool(tm.is_watertight)


@pytest.mark.parametrize("kind", [ShapeType.SPHERE, ShapeType.CYLINDER, ShapeType.CAPSULE])
def test_templates_equal_trimeshs_to_the_bit(kind):
    """Templates across the segment counts a part can get have trimesh's
    vertices, faces and order, bit for bit, built without trimesh (every
    even count from MIN_SEGMENTS to MAX_SEGMENTS was compared once, 1:20
    min; these take seconds)."""
    from cablecheck.checker.tessellate import MAX_SEGMENTS, MIN_SEGMENTS, _template

    for n in (MIN_SEGMENTS, MIN_SEGMENTS + 2, 18, 24, 34, 50, 64, 98, 130, MAX_SEGMENTS - 2, MAX_SEGMENTS):
        v, f, closed = _template(kind, n)
        rv, rf, rclosed = _trimesh_template(kind, n)
        assert v.tobytes() == rv.tobytes() and v.shape == rv.shape, n
        assert f.tobytes() == rf.tobytes() and f.shape == rf.shape, n
        assert closed and rclosed, n


def test_unit_box_equals_trimeshs():
    from cablecheck.checker.tessellate import _unit_box

    v, f, closed = _unit_box()
    tm = trimesh.creation.box(extents=[2.0, 2.0, 2.0])
    assert v.tobytes() == np.asarray(tm.vertices, float).tobytes()
    assert f.tobytes() == np.asarray(tm.faces, np.int64).tobytes() and closed
