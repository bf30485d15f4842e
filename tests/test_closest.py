"""Closest points between segments and triangles against independent references."""

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st
from hypothesis.extra.numpy import arrays

from cablecheck.checker.closest import (
    point_segment,
    point_triangle,
    segment_parameter,
    segment_segment,
    segment_segment_apart,
    segment_triangle,
)

pytestmark = pytest.mark.filterwarnings("error")

coord = st.floats(-10, 10, allow_nan=False, allow_subnormal=False, width=64)
vec = arrays(np.float64, 3, elements=coord)


def _pt_seg_ref(p, a, b):
    """Point-segment distance by the normal equation, written independently."""
    d = b - a
    L2 = d @ d
    if L2 == 0:
        return np.linalg.norm(p - a)
    t = min(1.0, max(0.0, (p - a) @ d / L2))
    return np.linalg.norm(a + t * d - p)


def _seg_seg_ref(p0, p1, q0, q1):
    """Minimum of the convex quadratic over the unit square: interior
    stationary point if it lies inside, else the best of the four edges."""
    cands = [_pt_seg_ref(p0, q0, q1), _pt_seg_ref(p1, q0, q1), _pt_seg_ref(q0, p0, p1), _pt_seg_ref(q1, p0, p1)]
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    A = np.array([[d1 @ d1, -d1 @ d2], [-d1 @ d2, d2 @ d2]])
    # The 2x2 determinant written out: np.linalg.det warns (an error under
    # pytest) on the tiny magnitudes hypothesis finds.
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    if abs(det) > 1e-12 * (d1 @ d1) * (d2 @ d2) and (d1 @ d1) > 0 and (d2 @ d2) > 0:
        # Cramer's rule with that determinant (np.linalg.solve's LU can still
        # call such a matrix exactly singular and raise)
        b0, b1 = -d1 @ r, d2 @ r
        s = (b0 * A[1, 1] - A[0, 1] * b1) / det
        t = (A[0, 0] * b1 - A[1, 0] * b0) / det
        if 0 <= s <= 1 and 0 <= t <= 1:
            cands.append(np.linalg.norm(p0 + s * d1 - q0 - t * d2))
    return min(cands)


@settings(max_examples=300, deadline=None)
@given(vec, vec, vec, vec)
def test_segment_segment_matches_reference(p0, p1, q0, q1):
    d, s, t, cp, cq = segment_segment(p0[None], p1[None], q0[None], q1[None])
    ref = _seg_seg_ref(p0, p1, q0, q1)
    scale = 1 + np.max(np.abs([p0, p1, q0, q1]))
    assert abs(d[0] - ref) <= 1e-9 * scale
    assert 0 <= s[0] <= 1 and 0 <= t[0] <= 1
    assert np.allclose(cp[0], p0 + s[0] * (p1 - p0)) and np.allclose(cq[0], q0 + t[0] * (q1 - q0))


def test_segment_segment_degenerate_cases():
    z = np.zeros(3)
    x = np.array([1.0, 0, 0])
    y = np.array([0, 1.0, 0])
    cases = [
        (z, x, z + y, x + y, 1.0),  # parallel, overlapping
        (z, x, 2 * x + y, 3 * x + y, np.hypot(1, 1)),  # parallel, disjoint
        (z, z, y, y, 1.0),  # two points
        (z, z, -x + y, x + y, 1.0),  # point and segment
        (-x, x, -y, y, 0.0),  # crossing
        (z, x, z, x, 0.0),  # identical
        (z, x, x, z, 0.0),  # reversed
    ]
    for p0, p1, q0, q1, ref in cases:
        d = segment_segment(p0[None], p1[None], q0[None], q1[None])[0]
        assert np.isfinite(d).all() and abs(d[0] - ref) < 1e-15


def test_segment_segment_far_from_origin_and_scaled():
    rng = np.random.default_rng(3)
    P = rng.normal(size=(200, 4, 3))
    d0 = segment_segment(*(P[:, k] for k in range(4)))[0]
    d1 = segment_segment(*(P[:, k] + 1e4 for k in range(4)))[0]
    d2 = segment_segment(*(P[:, k] * 1000 for k in range(4)))[0]
    assert np.allclose(d0, d1, rtol=0, atol=1e-9)
    assert np.allclose(d0 * 1000, d2, rtol=1e-12, atol=1e-9)


def _pt_tri_ref(p, a, b, c):
    """Interior stationary point of the barycentric quadratic, else the edges."""
    e0, e1 = b - a, c - a
    G = np.array([[e0 @ e0, e0 @ e1], [e0 @ e1, e1 @ e1]])
    cands = [_pt_seg_ref(p, a, b), _pt_seg_ref(p, b, c), _pt_seg_ref(p, c, a)]
    # a degenerate (flat) triangle's nearest point lies on an edge; the relative
    # test alone is fooled by subnormal products (e.g. an edge of 1e-163)
    if abs(G[0, 0] * G[1, 1] - G[0, 1] * G[1, 0]) > 1e-12 * G[0, 0] * G[1, 1]:
        try:
            u, v = np.linalg.solve(G, [(p - a) @ e0, (p - a) @ e1])
        except np.linalg.LinAlgError:
            return min(cands)
        if u >= 0 and v >= 0 and u + v <= 1:
            cands.append(np.linalg.norm(a + u * e0 + v * e1 - p))
    return min(cands)


@settings(max_examples=300, deadline=None)
@given(vec, vec, vec, vec)
@example(np.zeros(3), np.zeros(3), np.full(3, 2.0), np.full(3, 3.91480476e-163))
# a sliver (an edge of 3e-159): its face tests round to zero; the product read 0 for a point 1.73 away (CI)
@example(np.full(3, -2.0), np.array([3.27447586e-159, 0.0, 0.0]), np.zeros(3), np.full(3, -1.0))
def test_point_triangle_matches_reference(p, a, b, c):
    d, cl, region = point_triangle(p[None], a[None], b[None], c[None])
    ref = _pt_tri_ref(p, a, b, c)
    scale = 1 + np.max(np.abs([p, a, b, c]))
    assert abs(d[0] - ref) <= 1e-9 * scale
    assert abs(np.linalg.norm(cl[0] - p) - d[0]) <= 1e-9 * scale
    assert 0 <= region[0] <= 6


def test_point_triangle_on_face_edge_and_corner():
    a, b, c = np.array([0.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    P = np.array([[0.25, 0.25, 0.0], [0.5, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.25, 0.25, 2.0]])
    n = len(P)
    d, cl, region = point_triangle(P, np.tile(a, (n, 1)), np.tile(b, (n, 1)), np.tile(c, (n, 1)))
    assert np.allclose(d, [0, 0, 0, 0, 0, 2])
    assert region[-1] == 0


@settings(max_examples=200, deadline=None)
@given(vec, vec, vec, vec, vec)
def test_segment_triangle_matches_sampling_bound(p0, p1, a, b, c):
    d, t, crossing = segment_triangle(p0[None], p1[None], a[None], b[None], c[None])
    ts = np.linspace(0, 1, 201)
    pts = p0 + ts[:, None] * (p1 - p0)
    n = len(ts)
    ds = point_triangle(pts, np.tile(a, (n, 1)), np.tile(b, (n, 1)), np.tile(c, (n, 1)))[0]
    scale = 1 + np.max(np.abs([p0, p1, a, b, c]))
    # Exact value is a lower bound of sampled values, and within the sampling
    # step's Lipschitz bound of their minimum.
    assert d[0] <= ds.min() + 1e-9 * scale
    assert d[0] >= ds.min() - np.linalg.norm(p1 - p0) / 200 - 1e-9 * scale
    at_t = point_triangle((p0 + t[0] * (p1 - p0))[None], a[None], b[None], c[None])[0][0]
    assert abs(at_t - d[0]) <= 1e-7 * scale


def test_point_segment_zero_length():
    d, t, c = point_segment(np.array([[1.0, 1, 1]]), np.zeros((1, 3)), np.zeros((1, 3)))
    assert d[0] == pytest.approx(np.sqrt(3)) and t[0] == 0


def test_segment_parameter_is_point_segments_parameter_bit_for_bit():
    rng = np.random.default_rng(3)
    p, a, b = rng.normal(size=(3, 500, 3))
    b[:20] = a[:20]                                   # zero-length segments: parameter 0
    t = segment_parameter(p, a, b)
    assert np.array_equal(t, point_segment(p, a, b)[1]) and (t[:20] == 0.0).all()


def _edge_min(p0, p1, q0, q1, a, b):
    """Least |P(s) - Q(t)| along the straight edge from parameters a = (s, t)
    to b in the unit square: the difference is linear in the edge's own
    parameter, so its least length is a 1-D quadratic's clamped minimum."""
    def diff(w):
        return (p0 + w[0] * (p1 - p0)) - (q0 + w[1] * (q1 - q0))
    da, db = diff(a), diff(b)
    g = db - da
    gg = g @ g
    lam = 0.0 if gg == 0 else min(1.0, max(0.0, -(da @ g) / gg))
    return np.linalg.norm(da + lam * g)


def seg_seg_apart_ref(p0, p1, q0, q1, u0, u1, v0, v1, gap):
    """Least distance between points of two segments whose coordinates
    (u along the first, v along the second, linear) satisfy v - u >= gap,
    written independently of the product: the allowed parameter pairs are
    the unit square cut by a half-plane, a convex polygon (clipped here
    corner by corner); the convex quadratic's least value over it is at its
    interior stationary point when that is allowed, else on one of the
    polygon's edges. inf when nothing is allowed."""
    def h(w):       # >= 0: allowed
        return (v0 + w[1] * (v1 - v0)) - (u0 + w[0] * (u1 - u0)) - gap
    square = [np.array(c, float) for c in ((0, 0), (1, 0), (1, 1), (0, 1))]
    poly = []
    for k in range(4):
        a, b = square[k], square[(k + 1) % 4]
        ha, hb = h(a), h(b)
        if ha >= 0:
            poly.append(a)
        if (ha >= 0) != (hb >= 0):
            poly.append(a + (ha / (ha - hb)) * (b - a))
    if not poly:
        return np.inf
    cands = [_edge_min(p0, p1, q0, q1, poly[k], poly[(k + 1) % len(poly)]) for k in range(len(poly))]
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    A = np.array([[d1 @ d1, -d1 @ d2], [-d1 @ d2, d2 @ d2]])
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    if abs(det) > 1e-12 * (d1 @ d1) * (d2 @ d2) and (d1 @ d1) > 0 and (d2 @ d2) > 0:
        b0, b1 = -d1 @ r, d2 @ r
        s = (b0 * A[1, 1] - A[0, 1] * b1) / det
        t = (A[0, 0] * b1 - A[1, 0] * b0) / det
        if 0 <= s <= 1 and 0 <= t <= 1 and h((s, t)) >= 0:
            cands.append(np.linalg.norm(p0 + s * d1 - q0 - t * d2))
    return min(cands)


start = st.floats(0, 10, allow_nan=False, allow_subnormal=False, width=64)
span = st.one_of(st.just(0.0), st.floats(1e-3, 10, width=64))


@settings(max_examples=300, deadline=None)
@given(vec, vec, vec, vec, start, span, start, span, st.floats(-5, 25, width=64))
def test_segment_segment_apart_matches_reference(p0, p1, q0, q1, u0, du, v0, dv, gap):
    """The least distance over the allowed pairs against the polygon
    reference; the closest points are allowed, on the segments and that far
    apart; it is never below the unconstrained distance. (A coordinate that
    does not grow along a segment comes with a segment of no length, the
    function's precondition, as arc length along a polyline has it.)"""
    p1 = p0 if du == 0 else p1
    q1 = q0 if dv == 0 else q1
    a = [np.array([x], float) for x in (u0, u0 + du, v0, v0 + dv, gap)]
    d, s, t, cp, cq = segment_segment_apart(p0[None], p1[None], q0[None], q1[None], *a)
    ref = seg_seg_apart_ref(p0, p1, q0, q1, u0, u0 + du, v0, v0 + dv, gap)
    scale = 1 + np.max(np.abs([p0, p1, q0, q1]))
    if np.isinf(ref):
        assert np.isinf(d[0])
        return
    assert abs(d[0] - ref) <= 1e-9 * scale
    assert 0 <= s[0] <= 1 and 0 <= t[0] <= 1
    assert np.allclose(cp[0], p0 + s[0] * (p1 - p0)) and np.allclose(cq[0], q0 + t[0] * (q1 - q0))
    assert abs(np.linalg.norm(cp[0] - cq[0]) - d[0]) <= 1e-12 * scale
    # the closest pair is allowed (to rounding of the coordinates)
    assert (v0 + t[0] * dv) - (u0 + s[0] * du) >= gap - 1e-12 * (1 + abs(gap) + u0 + du + v0 + dv)
    assert d[0] >= segment_segment(p0[None], p1[None], q0[None], q1[None])[0][0] - 1e-12 * scale


def test_segment_segment_apart_at_the_windows_edge():
    """Two parallel unit segments 1 apart, coordinates 0..1 and 1.5..2.5:
    with gap 2 the allowed pairs have t - s >= 0.5, the nearest of them
    hypot(0.5, 1) apart on the half-plane's edge (the plain closest points,
    1 apart at t = s, are not allowed); with gap 0.5 they are; with gap 3
    nothing is (v - u is at most 2.5)."""
    p0, p1 = np.array([[0.0, 0, 0]]), np.array([[1.0, 0, 0]])
    q0, q1 = np.array([[0.0, 1, 0]]), np.array([[1.0, 1, 0]])
    u0, u1, v0, v1 = (np.array([x]) for x in (0.0, 1.0, 1.5, 2.5))
    d, s, t, _, _ = segment_segment_apart(p0, p1, q0, q1, u0, u1, v0, v1, np.array([2.0]))
    # allowed: t - s >= 0.5; least |(s - t, -1)| = hypot(0.5, 1)
    assert d[0] == pytest.approx(np.hypot(0.5, 1.0), abs=1e-15) and t[0] - s[0] == pytest.approx(0.5)
    d, s, t, _, _ = segment_segment_apart(p0, p1, q0, q1, u0, u1, v0, v1, np.array([0.5]))
    assert d[0] == pytest.approx(1.0, abs=1e-15)
    d, *_ = segment_segment_apart(p0, p1, q0, q1, u0, u1, v0, v1, np.array([3.0]))
    assert np.isinf(d[0])
