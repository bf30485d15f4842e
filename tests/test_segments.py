"""Segment signed distances (cablecheck.checker.segments, through cablecheck.checker.shapes) against
exact candidates (box), a dense grid refined by Brent's method (curved
primitives), the box primitive (box mesh) and a closed form (plane)."""

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings, strategies as st
from scipy.optimize import minimize_scalar
from helpers import examples
from shaperefs import SIZES

from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape, segment_signed_distance, signed_distance

pytestmark = pytest.mark.filterwarnings("error")


def _seg_ref_box(h, a, b):
    """Exact segment-box signed distance, by candidates: outside, the minimum
    is at an end against the box or on one of the 12 edges; inside, the
    piecewise-linear max(|x_k| - h_k) is least at an end or where two of its
    six lines cross."""
    box = Shape(ShapeType.BOX, h)
    from cablecheck.checker.closest import segment_segment

    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
    edges = [(i, j) for i in range(8) for j in range(i + 1, 8) if np.sum(corners[i] != corners[j]) == 1]
    cands = list(signed_distance(box, np.stack([a, b]))[0])
    for i, j in edges:
        cands.append(segment_segment(a[None], b[None], corners[i][None], corners[j][None])[0][0])
    # Lines g(t) = sigma (a_k + t u_k) - h_k.
    u = b - a
    lines = [(sg * u[k], sg * a[k] - h[k]) for k in range(3) for sg in (-1, 1)]
    ts = []
    for m in range(6):
        for n in range(m + 1, 6):
            s1, c1 = lines[m]
            s2, c2 = lines[n]
            if s1 != s2:
                t = (c2 - c1) / (s1 - s2)
                if 0 <= t <= 1:
                    ts.append(t)
    if ts:
        cands += list(signed_distance(box, a + np.array(ts)[:, None] * u)[0])
    # Edge candidates are distances to the surface: only valid when the
    # segment stays outside, which the inside candidates then dominate.
    inside_min = min(cands[:2] + cands[2 + len(edges):])
    return inside_min if inside_min < 0 else min(cands)


def _seg_ref_scalar(shape, a, b):
    """Dense grid along the segment, then Brent's method in the best cell."""
    ts = np.linspace(0, 1, 20001)
    v = signed_distance(shape, a + ts[:, None] * (b - a))[0]
    k = int(np.argmin(v))

    def f(t):
        return signed_distance(shape, (a + t * (b - a))[None])[0][0]

    lo, hi = ts[max(k - 1, 0)], ts[min(k + 1, len(ts) - 1)]
    r = minimize_scalar(f, bounds=(lo, hi), method="bounded", options={"xatol": 1e-15, "maxiter": 500})
    return min(r.fun, v[k])


seg_coords = st.lists(st.floats(-0.6, 0.6, allow_nan=False, allow_subnormal=False), min_size=6, max_size=6)


@settings(max_examples=150, deadline=None)
@given(seg_coords)
def test_segment_box_exact(c):
    h = np.array([0.3, 0.2, 0.1])
    a, b = np.array(c[:3]), np.array(c[3:])
    d, t = segment_signed_distance(Shape(ShapeType.BOX, h), a[None], b[None])
    ref = _seg_ref_box(h, a, b)
    assert abs(d[0] - ref) <= 1e-9
    at_t = signed_distance(Shape(ShapeType.BOX, h), (a + t[0] * (b - a))[None])[0][0]
    assert abs(at_t - d[0]) <= 1e-9


@pytest.mark.parametrize("stype", [ShapeType.SPHERE, ShapeType.CAPSULE, ShapeType.CYLINDER, ShapeType.ELLIPSOID])
def test_segment_curved_primitives(stype):
    shape = Shape(stype, SIZES[stype])
    rng = np.random.default_rng(5)
    a = rng.uniform(-0.6, 0.6, size=(40, 3))
    b = rng.uniform(-0.6, 0.6, size=(40, 3))
    b[:3] = a[:3]  # zero length
    b[3] = -a[3]  # through the centre
    d, t = segment_signed_distance(shape, a, b)
    ref = np.array([_seg_ref_scalar(shape, a[i], b[i]) for i in range(len(a))])
    # The value is attained at t (so it is not below the true minimum) and is
    # at least as low as an independent minimiser's (Brent at kinks inside
    # the solid is only good to a few 1e-9; golden section does better).
    at_t = signed_distance(shape, a + t[:, None] * (b - a))[0]
    assert np.allclose(at_t, d, rtol=0, atol=1e-13)
    assert np.all(d <= ref + 1e-13)
    assert np.allclose(d, ref, rtol=0, atol=1e-8)


def test_segment_plane_and_mesh():
    plane = Shape(ShapeType.PLANE, [0.0])
    d, t = segment_signed_distance(plane, np.array([[0, 0, 1.0]]), np.array([[1, 0, -2.0]]))
    assert d[0] == -2.0 and t[0] == 1.0
    h = np.array([0.3, 0.2, 0.1])
    m = trimesh.creation.box(extents=2 * h)
    mesh = mesh_shape(m.vertices, m.faces)
    rng = np.random.default_rng(6)
    a = rng.uniform(-0.6, 0.6, size=(60, 3))
    b = a + rng.normal(size=(60, 3)) * 0.05
    dm, _ = segment_signed_distance(mesh, a, b)
    db, _ = segment_signed_distance(Shape(ShapeType.BOX, h), a, b)
    outside = db > 0
    assert np.allclose(dm[outside], db[outside], atol=1e-12)
    # Penetration: never reported clear, and no deeper than the truth.
    assert np.all(dm[~outside] <= 0) and np.all(dm[~outside] >= db[~outside] - 1e-12)


def _box_sd(x: np.ndarray, half: np.ndarray) -> np.ndarray:
    q = np.abs(x) - half
    return np.linalg.norm(np.maximum(q, 0.0), axis=-1) + np.minimum(q.max(axis=-1), 0.0)


@settings(max_examples=examples(20), deadline=None)     # 40 segments and a scipy search each: 0.1 s a draw
@given(seed=st.integers(0, 2**32 - 1), scale=st.sampled_from([1.0, 1e3]))
def test_segment_through_a_convex_mesh_is_measured_at_its_deepest_point(seed, scale):
    """A box mesh's depth along segments through it, against the box's closed
    form minimised along the segment by scipy (the depth inside a convex
    mesh is concave along a segment, so one bounded search finds it): nine
    samples alone missed up to a few per cent of the depth."""
    rng = np.random.default_rng(seed)
    half = rng.uniform(0.01, 0.05, 3) * scale
    box = trimesh.creation.box(extents=2 * half)
    shape = mesh_shape(np.asarray(box.vertices), np.asarray(box.faces))
    a = rng.uniform(-1.5, 1.5, (40, 3)) * half
    b = a + rng.normal(scale=0.04 * scale, size=(40, 3))
    d, t = segment_signed_distance(shape, a, b)
    for i in range(len(a)):
        f = lambda s: float(_box_sd(a[i] + s * (b[i] - a[i]), half))  # noqa: E731
        r = minimize_scalar(f, bounds=(0.0, 1.0), method="bounded", options={"xatol": 1e-13})
        ref = min(r.fun, f(0.0), f(1.0))
        assert d[i] == pytest.approx(ref, abs=1e-9 * scale), (i, d[i], ref)
        # the reported place is at that depth
        assert f(t[i]) == pytest.approx(d[i], abs=1e-9 * scale)


@settings(max_examples=examples(6), deadline=None)     # 60 segments and a linear program each
@given(seed=st.integers(0, 2**32 - 1), scale=st.sampled_from([1.0, 1e-3, 1e3]), far=st.sampled_from([0.0, 1e3]))
def test_depth_inside_a_convex_hull_is_its_linear_programs(seed, scale, far):
    """Inside a convex mesh (here the hull of random points, in m or mm, at
    the origin or a kilometre out) the signed distance is the greatest of
    the face planes' distances, so a segment's deepest point solves a linear
    program: least z with every face's distance at (a + t (b - a)) at most
    z, 0 <= t <= 1 (scipy's linprog). The tangents' crossings
    (segment_sd_mesh on a convex mesh) give its depth and a place at it."""
    from scipy.optimize import linprog
    rng = np.random.default_rng(seed)
    hull = trimesh.convex.convex_hull(rng.normal(size=(int(rng.integers(8, 120)), 3)))
    offset = np.array([far, -far, 0.5 * far])
    shape = mesh_shape(np.asarray(hull.vertices) * scale + offset, np.asarray(hull.faces))
    m = shape.mesh
    assert m.convex
    a = rng.normal(scale=0.6, size=(60, 3)) * scale + offset
    b = a + rng.normal(scale=0.8, size=(60, 3)) * scale
    d, t = segment_signed_distance(shape, a, b)
    n, on = m.face_normals, m.a
    checked = 0
    for i in range(len(a)):
        # z >= n . (a + t (b - a) - on) for every face
        rows = np.c_[n @ (b[i] - a[i]), -np.ones(len(n))]
        lp = linprog([0.0, 1.0], A_ub=rows, b_ub=-np.einsum("fj,fj->f", n, a[i] - on),
                     bounds=[(0.0, 1.0), (None, None)], method="highs")
        if lp.fun > -1e-6 * scale:          # not inside: exact's unsigned search answers it
            continue
        checked += 1
        assert d[i] == pytest.approx(lp.fun, abs=1e-9 * scale), (i, d[i], lp.fun)
        at = a[i] + t[i] * (b[i] - a[i])
        assert np.max(n @ at - np.einsum("fj,fj->f", n, on)) == pytest.approx(d[i], abs=1e-9 * scale)
    assert checked >= 5


def test_a_mesh_is_convex_when_closed_with_no_fold_inward():
    box = trimesh.creation.box([2.0, 1.0, 3.0])
    assert mesh_shape(box.vertices, box.faces).mesh.convex
    ring = trimesh.creation.annulus(r_min=0.5, r_max=1.0, height=0.6)
    assert not mesh_shape(ring.vertices, ring.faces).mesh.convex
    # closed but open: one face less
    assert not mesh_shape(box.vertices, box.faces[1:]).mesh.convex


def test_a_cap_below_every_face_answers_the_cap():
    """mesh_segment_unsigned with an upper bound and a cap: segments outside a
    closed box mesh whose caps come within no face are answered at the cap
    (face -1), one whose cap reaches the box exactly; before, a call where no
    segment's cap reached any face failed on its empty list of faces."""
    from cablecheck.checker.segments import mesh_segment_unsigned
    box = trimesh.creation.box([2.0, 2.0, 2.0])
    m = mesh_shape(box.vertices, box.faces).mesh
    a = np.array([[5.0, -1.0, 0.0], [0.0, 0.0, 4.0]])
    b = np.array([[5.0, 1.0, 0.0], [0.0, 0.5, 4.0]])
    gap = np.array([4.0, 3.0])                       # each segment's distance to the box
    d, t, face = mesh_segment_unsigned(m, a, b, upper=gap + 0.5, cap=np.array([1.0, 1.0]))
    assert np.allclose(d, 1.0) and np.all(face == -1)
    d, t, face = mesh_segment_unsigned(m, a, b, upper=gap + 0.5, cap=np.array([1.0, 3.5]))
    assert d[0] == pytest.approx(1.0) and face[0] == -1
    assert d[1] == pytest.approx(3.0, abs=1e-12) and face[1] >= 0
