"""Triangle-triangle tests for whole arrays of pairs: crossing, distance, swept contact.

- :func:`triangles_cross`: do two triangles cross *properly*, i.e. share a
  segment of positive length that runs through both triangles' insides? Each
  triangle must have corners strictly on both sides of the other's plane and
  the two intervals cut on the planes' common line must overlap by more than
  a tolerance (Moeller's interval test). Touching is not crossing: a corner
  on the other triangle, an edge lying on it, edges meeting at one point, and
  coplanar triangles (faces lying on each other) all answer False. This is
  the boundary rule of the rigid-part checks: parts whose surfaces only touch
  are at distance 0 (soft when a clearance is set, never hard).
- :func:`edge_piercings`: where the edges of one triangle pass through the
  other (strictly from one side of its plane to the other, at a point of
  the closed triangle): the part-part check cuts an edge at its piercings
  of a part's surface to find points inside that part (the
  steel-structure paper's outline edges against faces).
- :func:`triangle_distance`: the distance between non-crossing triangles as
  the least of the 6 corner-triangle and 9 edge-edge distances, with the
  closest points.
- :func:`vertex_face_contact` and :func:`edge_edge_contact`: exact
  translational first contact. A point moving along ``D`` meets a triangle at
  the travel ``t`` solving ``p + t D = a + u (b - a) + v (c - a)``; two edges
  meet at ``a0 + s ea + t D = b0 + u eb``; both are 3x3 linear systems solved
  by Cramer's rule, no sampling of positions.

Tolerances are relative to the coordinates involved (``EPS`` times the
largest coordinate magnitude of the pair), so answers do not change when a
scene is translated or rescaled. Not here: which triangles to pair (see
:mod:`cablecheck.checker.bvh`), parts, poses, records.
"""

from __future__ import annotations

import numpy as np

from cablecheck.checker.closest import point_triangle, segment_segment

EPS = 1e-9
"""Relative tolerance separating touching from crossing and bounding contact parameters."""


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", u, v)


def _scale(*arrays: np.ndarray) -> np.ndarray:
    """(n,) largest coordinate magnitude over the given (n, k, 3) or (n, 3) arrays, at least 1e-300."""
    m = np.zeros(len(arrays[0]))
    if not len(m):
        return m
    for a in arrays:
        flat = np.abs(a.reshape(len(a), -1))
        for k in range(flat.shape[1]):      # column by column: numpy reduces a short row slowly
            m = np.maximum(m, flat[:, k])
    return np.maximum(m, 1e-300)


def _interval(tri: np.ndarray, d: np.ndarray, line: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Interval on the line (direction ``line``) cut by each triangle whose corners lie
    at signed distances ``d`` (n, 3) from the other plane (straddling assumed)."""
    proj = _dot(tri, line[:, None, :])                     # (n, 3)
    # the lone corner: the one whose sign differs from the other two
    sgn = np.sign(d)
    lone = np.where(sgn[:, 0] * sgn[:, 1] > 0, 2, np.where(sgn[:, 0] * sgn[:, 2] > 0, 1, 0))
    # a corner on the plane (d == 0) with the other two on opposite sides:
    # either non-zero corner serves (its two edges end at the crossing points)
    zero = sgn == 0
    lone = np.where(zero.any(axis=1), np.argmax(~zero, axis=1), lone)
    rows = np.arange(len(tri))
    o1, o2 = (lone + 1) % 3, (lone + 2) % 3
    pl, p1, p2 = proj[rows, lone], proj[rows, o1], proj[rows, o2]
    dl, d1, d2 = d[rows, lone], d[rows, o1], d[rows, o2]
    x1 = p1 + (pl - p1) * (d1 / np.where(d1 - dl == 0, 1.0, d1 - dl))
    x2 = p2 + (pl - p2) * (d2 / np.where(d2 - dl == 0, 1.0, d2 - dl))
    x1 = np.where(d1 - dl == 0, pl, x1)
    x2 = np.where(d2 - dl == 0, pl, x2)
    return np.minimum(x1, x2), np.maximum(x1, x2)


def triangles_cross(t1: np.ndarray, t2: np.ndarray, tol: np.ndarray | float | None = None) -> np.ndarray:
    """(n,) True where triangles t1[i] and t2[i] (each (n, 3, 3)) cross properly.

    See the module docstring for the rule; zero-area triangles never cross.
    ``tol``: absolute touching tolerance (scalar or (n,)); default ``EPS`` of
    the coordinates' magnitude. Corners within ``tol`` of the other plane
    count as on it, and the cut intervals must overlap by more than ``tol``."""
    n = len(t1)
    if n == 0:
        return np.zeros(0, bool)
    scale = _scale(t1, t2)
    tol = EPS * scale if tol is None else np.maximum(np.broadcast_to(tol, (n,)), EPS * scale)
    n1 = np.cross(t1[:, 1] - t1[:, 0], t1[:, 2] - t1[:, 0])
    n2 = np.cross(t2[:, 1] - t2[:, 0], t2[:, 2] - t2[:, 0])
    l1 = np.linalg.norm(n1, axis=1)
    l2 = np.linalg.norm(n2, axis=1)
    ok = (l1 > 0) & (l2 > 0)
    u1 = n1 / np.where(ok, l1, 1.0)[:, None]
    u2 = n2 / np.where(ok, l2, 1.0)[:, None]
    d1 = _dot(t1 - t2[:, None, 0], u2[:, None, :])          # t1 corners vs plane 2
    d2 = _dot(t2 - t1[:, None, 0], u1[:, None, :])
    d1 = np.where(np.abs(d1) <= tol[:, None], 0.0, d1)
    d2 = np.where(np.abs(d2) <= tol[:, None], 0.0, d2)
    straddle1 = (d1.max(axis=1) > 0) & (d1.min(axis=1) < 0)
    straddle2 = (d2.max(axis=1) > 0) & (d2.min(axis=1) < 0)
    ok &= straddle1 & straddle2
    # the common line and the intervals only for the pairs that straddle
    # (most candidate pairs do not; each row's arithmetic is its own)
    rows = np.flatnonzero(ok)
    out = np.zeros(n, bool)
    if not len(rows):
        return out
    line = np.cross(u1[rows], u2[rows])
    ll = np.linalg.norm(line, axis=1)
    good = ll > 1e-12
    line = line / np.where(good, ll, 1.0)[:, None]
    a_lo, a_hi = _interval(t1[rows], d1[rows], line)
    b_lo, b_hi = _interval(t2[rows], d2[rows], line)
    overlap = np.minimum(a_hi, b_hi) - np.maximum(a_lo, b_lo)
    out[rows] = good & (overlap > tol[rows])
    return out


def edge_piercings(src: np.ndarray, dst: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where edges of triangles ``src`` pass through triangles ``dst`` (both (n, 3, 3)).

    Edge k of ``src[m]`` runs from corner k to corner k + 1. It pierces
    ``dst[m]`` when its ends lie strictly on opposite sides of the plane of
    ``dst[m]`` and the crossing point lies in the closed triangle (edge-side
    tests with the unnormalised normal, so no tolerance and no division but
    the one along the edge). An edge in the plane, or ending on it, does not
    pierce it; a zero-area ``dst`` is never pierced.

    Returns:
        pair, edge: (k,) the row m and the edge (0, 1, 2) of each piercing.
        s: (k,) its parameter along the edge, in (0, 1).
    """
    n = len(src)
    if n == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
    k = np.arange(3)
    p0, p1 = src[:, k], src[:, (k + 1) % 3]                    # (n, 3, 3): edge, coordinate
    d0, d1, d2 = dst[:, 0], dst[:, 1], dst[:, 2]
    nrm = np.cross(d1 - d0, d2 - d0)
    h0 = np.einsum("nkj,nj->nk", p0 - d0[:, None], nrm)
    h1 = np.einsum("nkj,nj->nk", p1 - d0[:, None], nrm)
    cut = (np.sign(h0) * np.sign(h1) < 0) & (np.einsum("nj,nj->n", nrm, nrm) > 0)[:, None]
    s = np.where(cut, h0 / np.where(cut, h0 - h1, 1.0), 0.0)
    x = p0 + s[..., None] * (p1 - p0)
    for u, v in ((d0, d1), (d1, d2), (d2, d0)):
        cut &= np.einsum("nkj,nj->nk", np.cross((v - u)[:, None, :], x - u[:, None, :]), nrm) >= 0.0
    pair, edge = np.nonzero(cut)
    return pair, edge, s[pair, edge]


def triangle_distance(t1: np.ndarray, t2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distance between triangles t1[i], t2[i] (n, 3, 3) that do not cross.

    The least of corner-to-triangle (both ways) and edge-to-edge distances;
    for crossing triangles the answer is meaningless (use
    :func:`triangles_cross` first).

    Returns:
        dist: (n,).
        p1, p2: (n, 3) closest points on t1 and t2.
    """
    n = len(t1)
    cands_d, cands_p, cands_q = [], [], []
    for k in range(3):
        d, cl, _ = point_triangle(t1[:, k], t2[:, 0], t2[:, 1], t2[:, 2])
        cands_d.append(d), cands_p.append(t1[:, k]), cands_q.append(cl)
        d, cl, _ = point_triangle(t2[:, k], t1[:, 0], t1[:, 1], t1[:, 2])
        cands_d.append(d), cands_p.append(cl), cands_q.append(t2[:, k])
    # nine edge pairs in one batch
    i = np.repeat(np.arange(3), 3)
    j = np.tile(np.arange(3), 3)
    p0 = t1[:, i].reshape(-1, 3)
    p1 = t1[:, (i + 1) % 3].reshape(-1, 3)
    q0 = t2[:, j].reshape(-1, 3)
    q1 = t2[:, (j + 1) % 3].reshape(-1, 3)
    d, _, _, cp, cq = segment_segment(p0, p1, q0, q1)
    d = d.reshape(n, 9)
    cp = cp.reshape(n, 9, 3)
    cq = cq.reshape(n, 9, 3)
    all_d = np.concatenate([np.stack(cands_d, axis=1), d], axis=1)
    all_p = np.concatenate([np.stack(cands_p, axis=1), cp], axis=1)
    all_q = np.concatenate([np.stack(cands_q, axis=1), cq], axis=1)
    best = np.argmin(all_d, axis=1)
    rows = np.arange(n)
    return all_d[rows, best], all_p[rows, best], all_q[rows, best]


def vertex_face_contact(p: np.ndarray, tri: np.ndarray, direction: np.ndarray,
                        t_min: np.ndarray, t_max: float) -> np.ndarray:
    """Travel at which points ``p`` (n, 3) moving along ``direction`` (3,) meet triangles (n, 3, 3).

    Closed triangles (edges and corners included, within ``EPS``) and travels
    in ``[t_min, t_max]``; ``np.inf`` where they do not meet or where the
    direction lies in the triangle's plane (sliding along a face is not a
    contact here; the edges' own tests see those cases).
    """
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    e1, e2 = b - a, c - a
    h = np.cross(direction[None, :], e2)
    det = _dot(e1, h)
    scale = _scale(tri, p)
    area = np.linalg.norm(np.cross(e1, e2), axis=1)
    good = np.abs(det) > 1e-12 * area
    inv = 1.0 / np.where(good, det, 1.0)
    s = p - a
    u = _dot(s, h) * inv
    q = np.cross(s, e1)
    v = _dot(direction[None, :], q) * inv
    t = _dot(e2, q) * inv
    tol = EPS
    inside = (u >= -tol) & (v >= -tol) & (u + v <= 1 + tol)
    t_tol = EPS * scale
    ok = good & inside & (t >= t_min - t_tol) & (t <= t_max + t_tol)
    return np.where(ok, np.maximum(t, np.maximum(t_min, 0.0)), np.inf)


def edge_edge_contact(a0: np.ndarray, a1: np.ndarray, b0: np.ndarray, b1: np.ndarray,
                      direction: np.ndarray, t_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Travel at which edges ``a0 a1`` moving along ``direction`` meet edges ``b0 b1`` (n, 3).

    Solves ``a0 + s ea + t D = b0 + u eb`` for (s, u, t); a contact needs s
    and u in [0, 1] and t in [0, t_max] (within ``EPS``). Parallel edges, or
    edges whose plane contains ``D``, give ``np.inf`` (their contacts start
    at an end point, which the vertex-face tests find).

    Returns:
        t: (n,) travel or ``np.inf``.
        point: (n, 3) contact point on edge b.
    """
    ea = a1 - a0
    eb = b1 - b0
    m = np.cross(ea, eb)
    det = -_dot(m, direction[None, :])              # det [ea, -eb, D]
    scale = _scale(a0, a1, b0, b1)
    norm = np.linalg.norm(ea, axis=1) * np.linalg.norm(eb, axis=1)
    good = np.abs(det) > 1e-9 * norm
    inv = 1.0 / np.where(good, det, 1.0)
    r = b0 - a0
    # Cramer: replace one column of [ea, -eb, D] by r
    s = _dot(np.cross(r, -eb), direction[None, :]) * inv
    u = _dot(np.cross(ea, r), direction[None, :]) * inv
    t = _dot(np.cross(ea, -eb), r) * inv
    tol = EPS
    t_tol = EPS * scale
    ok = good & (s >= -tol) & (s <= 1 + tol) & (u >= -tol) & (u <= 1 + tol) \
        & (t >= -t_tol) & (t <= t_max + t_tol)
    point = b0 + np.clip(u, 0.0, 1.0)[:, None] * eb
    return np.where(ok, np.maximum(t, 0.0), np.inf), point
