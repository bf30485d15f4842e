"""Closest points between elementary primitives: points, segments, triangles.

Every function takes whole batches of queries as arrays with one row per query
and answers them with numpy arithmetic, no Python loop over rows. These are the
building blocks of the shapes' signed distances and of the exact (capsule)
method; they return distances, the closest points and the parameters along the
segments, so that callers can report where and at which arc length.

Degenerate input is part of the contract: zero-length segments, parallel
segments, points exactly on a segment, zero-area triangles. None of these gives
NaN, infinities or numpy warnings; the tolerance that decides "nearly
parallel" is relative to the squared lengths involved, so results do not
change when a whole scene is translated or rescaled. Only exactly zero-length
segments and zero-area triangles take the degenerate branches: nearly
degenerate ones go through the general formulas, whose clamped answers remain
actual points of the primitives.

Two row-wise helpers, :func:`row_norm` and :func:`cross`, do what
``np.linalg.norm(v, axis=1)`` and ``np.cross`` do for (n, 3) arrays, with the
same operations in the same order (the same bits) but less overhead; the other
checker modules use them too.

Deliberately not here: anything about shapes, poses, cables or interference;
broad phases; signed distances (a triangle has no inside).
"""

from __future__ import annotations

import numpy as np

# Below this relative determinant (sin^2 of the angle) two segments count as
# nearly parallel and their end-against-segment answers are tried too.
_NEAR_PARALLEL = 1e-6

# A triangle whose doubled area is below this fraction of its longest edge
# squared (its height below 2e-12 of that edge) counts as flat: it has no
# inside, only edges, which lie within that height of it. The face's own
# edge-side tests would cross 1e-300-sized products there, which round to
# zero and pass every point on the line of an edge as inside.
_FLAT = 1e-12


def row_norm(v: np.ndarray) -> np.ndarray:
    """Euclidean length of each row of (..., 3) ``v``.

    The same floating-point operations, in the same order, as
    ``np.linalg.norm(v, axis=-1)`` (so the same bits), without the slow
    reduction over a length-3 axis.
    """
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return np.sqrt((x * x + y * y) + z * z)


def cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (n, 3) arrays: ``np.cross``'s formula and bits, faster."""
    out = np.empty(np.broadcast_shapes(u.shape, v.shape))
    u0, u1, u2 = u[..., 0], u[..., 1], u[..., 2]
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    np.subtract(u1 * v2, u2 * v1, out=out[..., 0])
    np.subtract(u2 * v0, u0 * v2, out=out[..., 1])
    np.subtract(u0 * v1, u1 * v0, out=out[..., 2])
    return out


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Row-wise dot product of (n, 3) arrays -> (n,)."""
    return np.einsum("ij,ij->i", u, v)


def _safe_div(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """num / den where den != 0, else 0 (no warnings)."""
    ok = den != 0.0
    return np.where(ok, num, 0.0) / np.where(ok, den, 1.0)


def point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest point on segments ``a b`` to points ``p``.

    Projects ``p - a`` on ``b - a`` and clamps the parameter to [0, 1]. A
    zero-length segment gives parameter 0 (its only point).

    Args:
        p, a, b: (n, 3) query points and segment ends.

    Returns:
        dist: (n,) Euclidean distance.
        t: (n,) parameter of the closest point, ``c = a + t (b - a)``.
        c: (n, 3) closest point on the segment.
    """
    d = b - a
    dd = _dot(d, d)
    t = np.clip(_safe_div(_dot(p - a, d), dd), 0.0, 1.0)
    c = a + t[:, None] * d
    return row_norm(p - c), t, c


def segment_parameter(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The parameter ``t`` alone of :func:`point_segment` (the same
    operations, so the same bits), for callers that need neither the
    distance nor the closest point."""
    d = b - a
    return np.clip(_safe_div(_dot(p - a, d), _dot(d, d)), 0.0, 1.0)


def segment_segment(
    p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Closest points between segments ``p0 p1`` and ``q0 q1``.

    Minimises the convex quadratic ``|p(s) - q(t)|^2`` over the unit square
    (Ericson, Real-Time Collision Detection, 5.1.9): the unconstrained
    optimum for ``s`` is clamped, ``t`` follows from it and is clamped, and
    ``s`` is recomputed when ``t`` was clamped. Parallel segments take
    ``s = 0`` first; nearly parallel ones (sin^2 of the angle below 1e-6)
    also try each end against the other segment, since cancellation spoils
    the formula there. Zero-length segments reduce to point-segment queries.

    Args:
        p0, p1, q0, q1: (n, 3) segment ends.

    Returns:
        dist: (n,) distance between the segments.
        s: (n,) parameter on the first segment.
        t: (n,) parameter on the second segment.
        cp: (n, 3) closest point on the first segment.
        cq: (n, 3) closest point on the second segment.
    """
    d1 = p1 - p0
    d2 = q1 - q0
    r = p0 - q0
    a = _dot(d1, d1)
    e = _dot(d2, d2)
    f = _dot(d2, r)
    c = _dot(d1, r)
    b = _dot(d1, d2)
    # Only exactly zero-length segments are points; tiny ones go through the
    # general formulas, whose clamped answers are still points on the segments.
    deg1 = a == 0.0
    deg2 = e == 0.0
    denom = a * e - b * b
    parallel = denom <= 0.0
    s = np.where(parallel, 0.0, np.clip(_safe_div(b * f - c * e, denom), 0.0, 1.0))
    s = np.where(deg1, 0.0, s)
    # t from s, then clamp and recompute s where t was clamped.
    t_raw = _safe_div(b * s + f, e)
    t = np.clip(t_raw, 0.0, 1.0)
    s_lo = np.clip(_safe_div(-c, a), 0.0, 1.0)
    s_hi = np.clip(_safe_div(b - c, a), 0.0, 1.0)
    s = np.where(t_raw < 0.0, s_lo, np.where(t_raw > 1.0, s_hi, s))
    s = np.where(deg1, 0.0, s)
    # Degenerate second segment: t = 0, s from projecting q0 on the first.
    t = np.where(deg2, 0.0, t)
    s = np.where(deg2 & ~deg1, s_lo, s)
    cp = p0 + s[:, None] * d1
    cq = q0 + t[:, None] * d2
    dist = row_norm(cp - cq)
    # Nearly parallel pairs: the formula above loses precision to
    # cancellation; an end of one segment against the other is then (nearly)
    # optimal, so take the best of the four such answers as well.
    near = np.nonzero(~deg1 & ~deg2 & (denom <= _NEAR_PARALLEL * a * e))[0]
    if len(near):
        P0, P1, Q0, Q1 = p0[near], p1[near], q0[near], q1[near]
        cands = [point_segment(P0, Q0, Q1), point_segment(P1, Q0, Q1), point_segment(Q0, P0, P1), point_segment(Q1, P0, P1)]
        ds = np.stack([x[0] for x in cands], axis=1)
        k = np.argmin(ds, axis=1)
        rows = np.arange(len(near))
        better = ds[rows, k] < dist[near]
        u = np.stack([x[1] for x in cands], axis=1)[rows, k]
        s_new = np.select([k == 0, k == 1], [0.0, 1.0], u)
        t_new = np.select([k == 0, k == 1, k == 2], [u, u, 0.0], 1.0)
        idx = near[better]
        s[idx], t[idx] = s_new[better], t_new[better]
        cp[idx] = p0[idx] + s[idx, None] * d1[idx]
        cq[idx] = q0[idx] + t[idx, None] * d2[idx]
        dist[idx] = ds[rows, k][better]
    return dist, s, t, cp, cq



def segment_segment_apart(
    p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray,
    u0: np.ndarray, u1: np.ndarray, v0: np.ndarray, v1: np.ndarray, gap: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Closest points between segments ``p0 p1`` and ``q0 q1`` among the
    pairs of points at least ``gap`` apart in a coordinate along them.

    The coordinate runs linearly along each segment: ``u`` from ``u0`` at
    ``p0`` to ``u1 >= u0`` at ``p1``, ``v`` from ``v0`` at ``q0`` to ``v1 >=
    v0`` at ``q1``; only pairs with ``v - u >= gap`` count (for two elements
    of one polyline, u and v its arc length: places at least ``gap`` apart
    along it). The squared distance is a convex quadratic over the unit
    square of parameters and the allowed pairs are a half-plane of it, so:
    when :func:`segment_segment`'s closest points are allowed they are the
    answer; otherwise the least distance over the allowed pairs lies on the
    half-plane's edge ``v - u = gap`` (a convex function has no other local
    minimum on a convex set that misses its global one), a segment of
    parameter pairs along which the difference of the two points is linear:
    its least length is a point-segment distance (from the origin). When no
    pair is allowed (``u0 + gap > v1``) the distance is ``inf`` and the
    closest points are ``p0`` and ``q1``.

    Args:
        p0, p1, q0, q1: (n, 3) segment ends.
        u0, u1, v0, v1, gap: (n,) the coordinates at the ends and the least
            separation: finite, ``u1 > u0`` unless ``p0 == p1`` (the
            coordinate grows along a segment that has length, as arc length
            does), and likewise ``v1 > v0`` unless ``q0 == q1``.

    Returns:
        dist: (n,) least distance between allowed points (inf: none allowed).
        s, t: (n,) parameters of the closest points on the first / second segment.
        cp, cq: (n, 3) the closest points.
    """
    dist, s, t, cp, cq = segment_segment(p0, p1, q0, q1)
    du, dv = u1 - u0, v1 - v0
    u = u0 + s * du
    v = v0 + t * dv
    off = np.nonzero(~(v - u >= gap))[0]
    if len(off) == 0:
        return dist, s, t, cp, cq
    P0, P1, Q0, Q1 = p0[off], p1[off], q0[off], q1[off]
    U0, DU, V0, DV, G = u0[off], du[off], v0[off], dv[off], gap[off]
    # allowed pairs on the edge: u in [lo, hi], v = u + gap
    lo = np.maximum(U0, V0 - G)
    hi = np.minimum(U0 + DU, V0 + DV - G)
    empty = ~(lo <= hi)
    hi = np.where(empty, lo, hi)

    def params(x):       # parameters on both segments of the edge's pair at u = x
        return (np.clip(_safe_div(x - U0, DU), 0.0, 1.0),
                np.clip(_safe_div(x + G - V0, DV), 0.0, 1.0))

    s_lo, t_lo = params(lo)
    s_hi, t_hi = params(hi)
    a_lo = P0 + s_lo[:, None] * (P1 - P0) - (Q0 + t_lo[:, None] * (Q1 - Q0))
    a_hi = P0 + s_hi[:, None] * (P1 - P0) - (Q0 + t_hi[:, None] * (Q1 - Q0))
    _, lam, _ = point_segment(np.zeros_like(a_lo), a_lo, a_hi)
    s_e = s_lo + lam * (s_hi - s_lo)
    t_e = t_lo + lam * (t_hi - t_lo)
    s_e = np.where(empty, 0.0, s_e)
    t_e = np.where(empty, 1.0, t_e)
    cp_e = P0 + s_e[:, None] * (P1 - P0)
    cq_e = Q0 + t_e[:, None] * (Q1 - Q0)
    dist, s, t, cp, cq = dist.copy(), s.copy(), t.copy(), cp.copy(), cq.copy()
    dist[off] = np.where(empty, np.inf, row_norm(cp_e - cq_e))
    s[off], t[off], cp[off], cq[off] = s_e, t_e, cp_e, cq_e
    return dist, s, t, cp, cq

# Region codes of point_triangle: where on the triangle the closest point lies.
REGION_FACE = 0
REGION_EDGE_AB, REGION_EDGE_BC, REGION_EDGE_CA = 1, 2, 3
REGION_VERT_A, REGION_VERT_B, REGION_VERT_C = 4, 5, 6


def point_triangle(
    p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest point on triangles ``a b c`` to points ``p``.

    If the projection of ``p`` on the triangle's plane falls inside the
    triangle (edge-side tests with the unnormalised normal), that projection is
    the answer; otherwise the closest point lies on the boundary and is the
    nearest of the three point-segment answers. Zero-area triangles have no
    inside and are handled by their edges, and so are slivers whose area is
    below 1e-12 of their longest edge squared (`_FLAT`).

    Args:
        p, a, b, c: (n, 3) query points and triangle corners.

    Returns:
        dist: (n,) distance.
        cl: (n, 3) closest point.
        region: (n,) int, one of the ``REGION_*`` codes (face, edge or vertex),
            used to pick the pseudonormal that decides inside / outside.
    """
    n = cross(b - a, c - a)
    nn = _dot(n, n)
    longest = np.maximum(np.maximum(_dot(b - a, b - a), _dot(c - b, c - b)), _dot(a - c, a - c))
    flat = np.sqrt(nn) <= _FLAT * longest
    h = _safe_div(_dot(p - a, n), nn)
    q = p - h[:, None] * n
    inside = (
        ~flat
        & (_dot(cross(b - a, q - a), n) >= 0.0)
        & (_dot(cross(c - b, q - b), n) >= 0.0)
        & (_dot(cross(a - c, q - c), n) >= 0.0)
    )
    d_ab, t_ab, c_ab = point_segment(p, a, b)
    d_bc, t_bc, c_bc = point_segment(p, b, c)
    d_ca, t_ca, c_ca = point_segment(p, c, a)
    ds = np.stack([d_ab, d_bc, d_ca], axis=1)
    k = np.argmin(ds, axis=1)
    rows = np.arange(len(p))
    ts = np.stack([t_ab, t_bc, t_ca], axis=1)[rows, k]
    cs = np.stack([c_ab, c_bc, c_ca], axis=1)[rows, k]
    # Edge k runs from corner k to corner (k+1)%3; clamped ends are corners.
    region = np.where(ts <= 0.0, REGION_VERT_A + k, np.where(ts >= 1.0, REGION_VERT_A + (k + 1) % 3, REGION_EDGE_AB + k))
    cl = np.where(inside[:, None], q, cs)
    dist = np.where(inside, row_norm(p - q), ds[rows, k])
    region = np.where(inside, REGION_FACE, region)
    return dist, cl, region


def segment_triangle(
    p0: np.ndarray, p1: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest points between segments ``p0 p1`` and triangles ``a b c``.

    A segment that pierces the triangle has distance 0 at the piercing point.
    Otherwise the minimum is attained with an end of the segment against the
    triangle, or with the segment against one of the triangle's edges (a
    segment parallel to the face slides to one of these without changing the
    distance), so the answer is the least of those five queries.

    Args:
        p0, p1: (n, 3) segment ends.
        a, b, c: (n, 3) triangle corners.

    Returns:
        dist: (n,) distance.
        t: (n,) parameter of the closest point on the segment.
        crossing: (n,) bool, the segment pierces the triangle's interior or
            boundary transversally.
    """
    d0, _, _ = point_triangle(p0, a, b, c)
    d1, _, _ = point_triangle(p1, a, b, c)
    e0, s0, _, _, _ = segment_segment(p0, p1, a, b)
    e1, s1, _, _, _ = segment_segment(p0, p1, b, c)
    e2, s2, _, _, _ = segment_segment(p0, p1, c, a)
    ds = np.stack([d0, d1, e0, e1, e2], axis=1)
    ts = np.stack([np.zeros_like(d0), np.ones_like(d1), s0, s1, s2], axis=1)
    k = np.argmin(ds, axis=1)
    rows = np.arange(len(p0))
    dist = ds[rows, k]
    t = ts[rows, k]
    # Transversal piercing: ends on opposite sides of the plane, the crossing
    # point inside the triangle.
    n = cross(b - a, c - a)
    h0 = _dot(p0 - a, n)
    h1 = _dot(p1 - a, n)
    # Signs, not the product, which underflows for tiny triangles.
    opposite = (np.sign(h0) * np.sign(h1) <= 0.0) & (h0 != h1) & (_dot(n, n) > 0.0)
    tc = np.clip(_safe_div(h0, h0 - h1), 0.0, 1.0)
    q = p0 + tc[:, None] * (p1 - p0)
    inside = (
        opposite
        & (_dot(cross(b - a, q - a), n) >= 0.0)
        & (_dot(cross(c - b, q - b), n) >= 0.0)
        & (_dot(cross(a - c, q - c), n) >= 0.0)
    )
    dist = np.where(inside, 0.0, dist)
    t = np.where(inside, tc, t)
    return dist, t, inside
