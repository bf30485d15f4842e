"""The shape front (cablecheck.checker.shapes): the least signed distance over posed
shapes, and the memo of mesh shapes. Point and segment distances are tested
with their modules (test_primitives, test_meshnearest, test_meshdata,
test_meshgrid, test_segments)."""

import numpy as np
import pytest
import trimesh
from helpers import examples
from hypothesis import given, settings, strategies as st

from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape, signed_distance

pytestmark = pytest.mark.filterwarnings("error")


def test_least_signed_distance_over_posed_shapes_matches_one_by_one():
    from cablecheck.checker.shapes import least_signed_distance
    rng = np.random.default_rng(7)
    shapes = [Shape(ShapeType.BOX, [0.1, 0.2, 0.05]), Shape(ShapeType.SPHERE, [0.1]),
              Shape(ShapeType.BOX, [0.3, 0.1, 0.1]), Shape(ShapeType.PLANE, [0, 0, 0]),
              Shape(ShapeType.CAPSULE, [0.05, 0.2])]
    box = trimesh.creation.box([0.2, 0.3, 0.4])
    shapes.append(mesh_shape(box.vertices, box.faces))
    rot = []
    for _ in shapes:
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        rot.append(q * np.sign(np.linalg.det(q)))
    rot = np.array(rot)
    pos = rng.normal(size=(len(shapes), 3))
    pos[3] = [0.0, 0.0, -2.0]
    pts = rng.normal(size=(200, 3))
    one_by_one = np.min([signed_distance(s, (pts - p) @ r)[0] for s, r, p in zip(shapes, rot, pos)], axis=0)
    assert np.allclose(least_signed_distance(shapes, rot, pos, pts), one_by_one, atol=1e-12)
    assert np.all(np.isinf(least_signed_distance([], np.zeros((0, 3, 3)), np.zeros((0, 3)), pts)))


def test_least_signed_distance_with_a_limit_is_exact_below_it():
    """Values below the limit are the exact ones; beyond it a mesh may
    answer with a lower bound, still beyond the limit."""
    from cablecheck.checker.shapes import least_signed_distance
    rng = np.random.default_rng(11)
    torus = trimesh.creation.torus(0.3, 0.08)
    shapes = [mesh_shape(torus.vertices, torus.faces), Shape(ShapeType.SPHERE, [0.1])]
    rot = np.array([np.eye(3), np.eye(3)])
    pos = np.array([[0.0, 0.0, 0.0], [0.8, 0.0, 0.0]])
    pts = rng.uniform(-1.0, 1.0, (400, 3))
    exact = least_signed_distance(shapes, rot, pos, pts)
    limit = 0.1
    got = least_signed_distance(shapes, rot, pos, pts, limit=limit)
    below = exact < limit
    assert below.any() and (~below).any()
    assert np.array_equal(got[below], exact[below])
    assert np.all(got[~below] >= limit) and np.all(got[~below] <= exact[~below])


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), limit=st.floats(0.01, 0.5))
def test_least_signed_distance_with_bounds_measures_only_near_pairs(seed, limit):
    """With the parts' world boxes, only points within the limit of a box
    are measured against that part: drawn parts (a plane among them) and
    points, the values below the limit the same as one by one; a point
    beyond the limit of every box gets +inf, any other value stays beyond
    the limit."""
    from cablecheck.checker.shapes import least_signed_distance
    rng = np.random.default_rng(seed)
    kinds = [ShapeType.BOX, ShapeType.SPHERE, ShapeType.CAPSULE, ShapeType.CYLINDER, ShapeType.ELLIPSOID]
    shapes = [Shape(kinds[k % 5], rng.uniform(0.02, 0.3, 3)[: 1 if kinds[k % 5] is ShapeType.SPHERE else
                                                            2 if kinds[k % 5] in (ShapeType.CAPSULE, ShapeType.CYLINDER) else 3])
              for k in range(int(rng.integers(1, 12)))]
    box = trimesh.creation.box([0.2, 0.3, 0.4])
    shapes.append(mesh_shape(box.vertices, box.faces))
    if rng.random() < 0.5:
        shapes.append(Shape(ShapeType.PLANE, [0, 0, 0]))
    rot = []
    for _ in shapes:
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        rot.append(q * np.sign(np.linalg.det(q)))
    rot = np.array(rot)
    pos = rng.uniform(-2.0, 2.0, (len(shapes), 3))
    pos[-1, 2] -= 2.5
    lo, hi = np.full((len(shapes), 3), -np.inf), np.full((len(shapes), 3), np.inf)
    for k, sh in enumerate(shapes):
        if sh.type is not ShapeType.PLANE:
            a, b = sh.local_bounds()
            corners = np.array(np.meshgrid(*zip(a, b), indexing="ij")).reshape(3, -1).T @ rot[k].T + pos[k]
            lo[k], hi[k] = corners.min(axis=0), corners.max(axis=0)
    pts = rng.uniform(-2.5, 2.5, (300, 3))
    one_by_one = np.min([signed_distance(s, (pts - p) @ r)[0] for s, r, p in zip(shapes, rot, pos)], axis=0)
    got = least_signed_distance(shapes, rot, pos, pts, limit=limit, bounds=(lo, hi))
    below = one_by_one < limit
    assert np.allclose(got[below], one_by_one[below], rtol=0, atol=1e-12)
    assert np.all(got[~below] >= limit)
    gap = np.maximum(np.maximum(lo[:, None] - pts[None], pts[None] - hi[:, None]), 0.0)
    far = np.all(np.linalg.norm(gap, axis=2) > limit * np.sqrt(3), axis=0)
    assert np.all(np.isinf(got[far]))


def test_mesh_shape_is_kept_by_content_and_bounded(monkeypatch):
    """The same vertices and faces give the same shape (its grid shared);
    other content gives another; the last made are kept up to
    MESH_MEMO_TRIANGLES triangles, a scene's meshes asked for in turn all
    stay, and a mesh larger than the budget alone is still kept."""
    from cablecheck.checker import shapes
    box = trimesh.creation.box([0.2, 0.3, 0.4])        # 12 triangles
    monkeypatch.setattr(shapes, "MESH_MEMO_TRIANGLES", 12 * 20)
    a = mesh_shape(box.vertices, box.faces)
    assert mesh_shape(box.vertices.copy(), box.faces.copy()) is a
    moved = mesh_shape(box.vertices + 1.0, box.faces)
    assert moved is not a
    # eighteen more asked for twice in turn (a run's passes over its parts): each made once, all twenty kept
    made = [mesh_shape(box.vertices * (2.0 + k), box.faces) for k in range(18)]
    assert all(mesh_shape(box.vertices * (2.0 + k), box.faces) is made[k] for k in range(18))
    assert len(shapes._MESH_MEMO.shapes) == 20
    mesh_shape(box.vertices * 30.0, box.faces)        # one more: the least recent (a) goes
    assert len(shapes._MESH_MEMO.shapes) == 20
    big = trimesh.creation.icosphere(subdivisions=3)   # 1,280 triangles, over the budget alone
    kept = mesh_shape(big.vertices, big.faces)
    assert list(shapes._MESH_MEMO.shapes.values()) == [kept] and mesh_shape(big.vertices, big.faces) is kept
    again = mesh_shape(box.vertices, box.faces)
    assert again is not a
    p = np.array([[0.5, 0.0, 0.0], [0.0, 0.0, 0.0]])
    assert np.array_equal(signed_distance(again, p)[0], signed_distance(a, p)[0])
    # another thread makes its own (a bound grid fills itself as it is asked)
    import threading
    seen = []
    worker = threading.Thread(target=lambda: seen.append(mesh_shape(box.vertices, box.faces)))
    worker.start()
    worker.join()
    assert seen[0] is not again and mesh_shape(box.vertices, box.faces) is again


@settings(max_examples=60, deadline=None)
@given(st.sampled_from([ShapeType.BOX, ShapeType.SPHERE, ShapeType.CYLINDER, ShapeType.CAPSULE, ShapeType.ELLIPSOID]),
       st.lists(st.floats(1e-4, 10.0), min_size=3, max_size=3))
def test_primitive_bounds_touch_the_surface_on_every_axis(kind, size):
    """primitive_bounds (the one bounds formula, for arrays of parts) is tight:
    the extreme point on each axis lies on the surface, as Shape.local_bounds says."""
    from cablecheck.checker.shapes import SHAPE_CODE, primitive_bounds, signed_distance
    shape = Shape(kind, np.array(size))
    lo, hi = primitive_bounds(np.array([SHAPE_CODE[kind]]), shape.size[None, :3])
    assert np.array_equal(lo[0], shape.local_bounds()[0]) and np.array_equal(hi[0], shape.local_bounds()[1])
    extremes = np.concatenate([np.diag(hi[0]), np.diag(lo[0])])
    d = signed_distance(shape, extremes)[0]
    assert np.all(np.abs(d) <= 1e-9 * (1 + np.max(size)))


@settings(max_examples=examples(30), deadline=None)
@given(seed=st.integers(0, 2**32 - 1), limit=st.sampled_from([0.0, 1e-3, 0.05, 0.4]), scale=st.sampled_from([1.0, 1e3]))
def test_points_in_boxes_are_the_every_pair_test(seed, limit, scale):
    """The (box, point) pairs within the limit of each box, found by sorting
    the points along x, are those of testing every point in every box, in
    the same order: drawn boxes (a plane's infinite one among them) and
    points, some exactly on a box's grown face."""
    from cablecheck.checker.shapes import _in_boxes
    rng = np.random.default_rng(seed)
    n_p, n_b = int(rng.integers(0, 60)), int(rng.integers(0, 12))
    lo = rng.uniform(-1.0, 1.0, (n_b, 3)) * scale
    hi = lo + rng.uniform(0.0, 0.8, (n_b, 3)) * scale
    if n_b and rng.random() < 0.5:
        lo[0], hi[0] = -np.inf, np.inf
    p = rng.uniform(-1.5, 1.5, (n_p, 3)) * scale
    if n_p and n_b and np.isfinite(lo[-1, 0]):       # on the grown faces, exactly
        p[: n_p // 3, 0] = hi[-1, 0] + limit * scale
        p[n_p // 3: n_p // 2, 1] = lo[-1, 1] - limit * scale
    dense = np.all((p[None] >= lo[:, None] - limit * scale) & (p[None] <= hi[:, None] + limit * scale), axis=2)
    pi, ni = _in_boxes(p, lo, hi, limit * scale)
    want_i, want_n = np.nonzero(dense)
    assert np.array_equal(pi, want_i) and np.array_equal(ni, want_n)
