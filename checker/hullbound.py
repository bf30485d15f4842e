"""Lower bounds on the distance between two point sets' convex hulls, for whole arrays of pairs.

A part's triangles lie in the convex hull of its vertices, so the distance
between two hulls never exceeds the distance between the parts' triangles:
a lower bound that costs a few passes over the vertices, where the exact
distance between two meshes within reach of each other costs every pair of
their triangles within that reach (thousands for two arm links beside a
joint). The part-pair condition of the skip rule needs only a lower bound
(`cablecheck.checker.parts.pair_values`); where the bound is too low to
prove a pair apart (concave parts, overlapping hulls), the caller measures
the triangles.

The bound comes from the GJK iteration (Gilbert, Johnson and Keerthi
1988) on the Minkowski difference ``D = A - B`` of the two vertex sets: the
point ``v`` of the hull of a simplex of D's points nearest the origin moves
to take in D's support point along ``-v``, the simplex keeping the points
that hold ``v`` (found among all its faces: four points at most, fifteen
faces). Every direction ``u = v / |v|`` visited proves the hulls at least
``min_a u.a - max_b u.b`` apart (their projections on ``u`` are separated
by that much), whatever the iteration; ``|v|`` is at least the distance, so
the iteration stops once the two meet within the tolerance. The best
separation seen is returned: never above the hulls' distance, 0 or less
where they may overlap.

Why by hand: the convex-primitive refinement (:mod:`cablecheck.checker.convex`)
takes shapes by kind and size, not vertex sets; coal and python-fcl answer
one pair per call and bring native dependencies this package does not have.

Not here: which pairs, triangles, records (:mod:`cablecheck.checker.parts`).
"""

from __future__ import annotations

import numpy as np

HULL_ITERS = 64
"""GJK iterations at most: each proves a bound, the last the best."""

_FACES = tuple(np.array(f) for f in (
    [[0], [1], [2], [3]],
    [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]],
    [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]],
    [[0, 1, 2, 3]]))
"""The faces of a simplex of four slots, by size (a slot repeating another makes its faces degenerate)."""


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.einsum("...j,...j->...", u, v)


def _affine_nearest(p0: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The point nearest the origin of the faces ``p0 + sum t_i e_i``
    (p0 (..., 3), edges e (..., m, 3), m = 0 to 3) where it lies inside the
    face (t_i >= 0, sum <= 1) and the face is not degenerate: (x (..., 3),
    ok (...)). Closed forms (Cramer's rule) by the face's size."""
    m = e.shape[-2]
    if m == 0:
        return p0, np.ones(p0.shape[:-1], bool)
    if m == 1:
        a = e[..., 0, :]
        aa = _dot(a, a)
        good = aa > 0.0
        t = -_dot(a, p0) / np.where(good, aa, 1.0)
        return p0 + t[..., None] * a, good & (t >= 0.0) & (t <= 1.0)
    if m == 2:
        a, b = e[..., 0, :], e[..., 1, :]
        aa, ab, bb = _dot(a, a), _dot(a, b), _dot(b, b)
        r0, r1 = -_dot(a, p0), -_dot(b, p0)
        det = aa * bb - ab * ab
        good = det > 1e-12 * (aa * bb)
        det = np.where(good, det, 1.0)
        t0, t1 = (bb * r0 - ab * r1) / det, (aa * r1 - ab * r0) / det
        x = p0 + t0[..., None] * a + t1[..., None] * b
        return x, good & (t0 >= 0.0) & (t1 >= 0.0) & (t0 + t1 <= 1.0)
    a, b, c = e[..., 0, :], e[..., 1, :], e[..., 2, :]      # a tetrahedron: the origin inside it, or not
    bc = np.cross(b, c)
    det = _dot(a, bc)
    scale = np.sqrt(_dot(a, a) * _dot(b, b) * _dot(c, c))
    good = np.abs(det) > 1e-12 * scale
    det = np.where(good, det, 1.0)
    t0 = -_dot(p0, bc) / det
    t1 = -_dot(a, np.cross(p0, c)) / det
    t2 = -_dot(a, np.cross(b, p0)) / det
    x = p0 + t0[..., None] * a + t1[..., None] * b + t2[..., None] * c
    return x, good & (t0 >= 0.0) & (t1 >= 0.0) & (t2 >= 0.0) & (t0 + t1 + t2 <= 1.0)


def _nearest_on_simplex(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The point (n, 3) of the hull of w (n, 4, 3) nearest the origin and
    the slots (n, 4) bool that hold it: of the faces whose affine hull's
    nearest point lies inside them (barycentric weights >= 0, the face
    not degenerate), the nearest; a single point always qualifies. The
    faces of one size in one pass."""
    n = len(w)
    best = np.full(n, np.inf)
    point = w[:, 0].copy()
    slots = np.zeros((n, 4), bool)
    for faces in _FACES:
        f = len(faces)
        p = w[:, faces]                                            # (n, f, m, 3)
        p0 = p[:, :, 0]
        x, ok = _affine_nearest(p0, p[:, :, 1:] - p0[:, :, None])
        d = np.where(ok, np.einsum("nfj,nfj->nf", x, x), np.inf)
        k = d.argmin(axis=1)
        r = np.arange(n)
        take = d[r, k] < best
        best = np.where(take, d[r, k], best)
        point = np.where(take[:, None], x[r, k], point)
        held = np.zeros((f, 4), bool)
        np.put_along_axis(held, faces, True, axis=1)
        slots = np.where(take[:, None], held[k], slots)
    return point, slots


def hull_lower_bounds(va: np.ndarray, vb: np.ndarray, tol: np.ndarray | float) -> np.ndarray:
    """(n,) lower bounds on the distance between the convex hulls of the
    point sets va[k] (n, m, 3) and vb[k] (n, q, 3) (a set padded with
    copies of one of its points: the hull is the same), within ``tol``
    (scalar or (n,)) of the hulls' distance once converged; 0 or less where
    the hulls may overlap."""
    return hull_separations(va, vb, tol)[0]


def hull_separations(va: np.ndarray, vb: np.ndarray,
                     tol: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`hull_lower_bounds` and the unit directions (n, 3) that prove
    them, pointing from b's hull to a's: ``min_a u.a - max_b u.b`` is the
    bound (zero rows where none was proven)."""
    n = len(va)
    best = np.full(n, -np.inf)
    best_u = np.zeros((n, 3))
    if not n:
        return np.zeros(0), best_u
    tol = np.broadcast_to(np.asarray(tol, float), (n,))
    w = np.repeat((va[:, :1] - vb[:, :1]), 4, axis=1)            # the simplex: one point, repeated
    act = np.arange(n)
    for _ in range(HULL_ITERS):
        v, slots = _nearest_on_simplex(w[act])
        ln = np.sqrt(np.einsum("ij,ij->i", v, v))
        live = ln > 0                                             # the origin in the hull: overlap
        act, v, ln, slots = act[live], v[live], ln[live], slots[live]
        if not len(act):
            break
        u = v / ln[:, None]
        pa = np.einsum("nmj,nj->nm", va[act], u)
        pb = np.einsum("nmj,nj->nm", vb[act], u)
        r = np.arange(len(act))
        ka, kb = pa.argmin(axis=1), pb.argmax(axis=1)
        sep = pa[r, ka] - pb[r, kb]
        better = sep > best[act]
        best[act[better]] = sep[better]
        best_u[act[better]] = u[better]
        go = ln - sep > tol[act]
        # the simplex: the slots holding v, then D's support point along -v, repeated into the rest
        kept = w[act]
        first = slots.argmax(axis=1)
        fill = np.where(slots[..., None], kept, kept[r, first][:, None])
        order = np.argsort(~slots, axis=1, kind="stable")
        fill = np.take_along_axis(fill, order[..., None], axis=1)
        count = slots.sum(axis=1)
        new = va[act, ka] - vb[act, kb]
        at = np.arange(4)[None] >= count[:, None]
        w[act] = np.where(at[..., None], new[:, None], fill)
        act = act[go & (count < 4)]
        if not len(act):
            break
    return np.where(np.isfinite(best), best, 0.0), best_u
