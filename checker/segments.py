"""Least signed distance along segments (capsule axes) to shapes.

For convex shapes the signed distance is a convex function along the
segment: sphere, capsule and plane are closed-form; box and cylinder use a
golden-section search that brackets the minimiser to 1e-13 of the
segment's length; the ellipsoid finds the root of the derivative (the
outward normal at the closest point dotted with the segment) by
safeguarded secant steps to 1e-14 of the segment's length. Meshes are
exact while the segment stays outside; a penetrating segment's depth is
searched from the deepest of nine evenly spaced samples between its
neighbours: inside a convex mesh (:attr:`MeshData.convex`), where the depth
is the least of the face planes' distances, by the crossings of the
tangents at the bracket's ends (exact at the kink, a few passes); in any
other by golden section (exact, 1e-13 of that stretch, where the depth is
concave along the segment). Never shallower than the samples (in a concave
mesh the deepest point between other samples can be missed). Not here: point queries (:mod:`cablecheck.checker.primitives`,
:mod:`cablecheck.checker.meshdata`), poses (:mod:`cablecheck.checker.shapes`).
"""

from __future__ import annotations

import numpy as np

from cablecheck.checker.closest import (
    point_segment,
    point_triangle,
    row_norm,
    segment_segment,
    segment_triangle,
)
from cablecheck.checker.meshdata import MeshData, sd_mesh
from cablecheck.checker.meshnearest import mesh_sign
from cablecheck.checker.primitives import ShapeType, sd_ellipsoid, signed_distance_value_batch

# Golden-section iterations for segment distances to convex shapes:
# 0.618**62 ~ 1e-13 of the segment's length.
_GOLDEN_ITERS = 62
_INVPHI = (np.sqrt(5.0) - 1.0) / 2.0


# ---------------------------------------------------------------------------
# Segment queries (capsule axes against shapes).


def _golden_min(f, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Minimise n convex functions f(t) (vectorised, t (n,)) over [0, 1].

    Golden-section search keeps a bracket of the minimiser; the ends 0 and 1
    are evaluated too so a minimum at an end is exact.
    Returns (value (n,), t (n,)).
    """
    a = np.zeros(n)
    b = np.ones(n)
    c = b - _INVPHI
    d = _INVPHI * np.ones(n)
    fc = f(c)
    fd = f(d)
    for _ in range(_GOLDEN_ITERS):
        # Minimiser in [a, d] (left) or [c, b]; the surviving inner point is
        # reused and one new point is evaluated.
        left = fc < fd
        b = np.where(left, d, b)
        a = np.where(left, a, c)
        c_new = np.where(left, b - _INVPHI * (b - a), d)
        d_new = np.where(left, c, a + _INVPHI * (b - a))
        f_new = f(np.where(left, c_new, d_new))
        fc, fd = np.where(left, f_new, fd), np.where(left, fc, f_new)
        c, d = c_new, d_new
    tm = np.where(fc < fd, c, d)
    fm = np.minimum(fc, fd)
    f0 = f(np.zeros(n))
    f1 = f(np.ones(n))
    val = np.minimum(fm, np.minimum(f0, f1))
    t = np.where(val == f0, 0.0, np.where(val == f1, 1.0, tm))
    return val, t


def _derivative_min(fg, n: int, tol: float = 1e-14, max_iter: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """Minimise n convex functions over [0, 1] from their (sub)derivatives.

    ``fg(t, rows)`` returns the values and derivatives at ``t`` of the
    functions ``rows``. A minimum at an end is taken when the derivative
    there points outward; otherwise the minimiser stays bracketed by the
    derivative's sign change. Steps are secant steps on the derivative
    through the last two iterates (superlinear where the function is smooth);
    when one leaves the bracket, or the bracket failed to halve over two
    steps, the step goes to where the tangent lines at the bracket's ends
    cross (which finds a kink, as inside the solid), or halves the bracket if
    that point is not inside it. Iteration stops when the bracket or the
    step is below ``tol``. The ends are compared with the interior answer, as
    in a line search. Returns (value (n,), t (n,)).
    """
    rows = np.arange(n)
    f0, g0 = fg(np.zeros(n), rows)
    f1, g1 = fg(np.ones(n), rows)
    t = np.where(g0 >= 0.0, 0.0, 1.0)
    fm = np.where(g0 >= 0.0, f0, f1)
    act = np.nonzero((g0 < 0.0) & (g1 > 0.0))[0]
    m = len(act)
    lo, flo, glo = np.zeros(m), f0[act], g0[act]
    hi, fhi, ghi = np.ones(m), f1[act], g1[act]
    ta, ga = lo.copy(), glo.copy()  # previous iterate
    tb, gb = hi.copy(), ghi.copy()  # last iterate
    width = np.ones(m)  # bracket width two steps ago
    fc = np.zeros(m)
    for it in range(max_iter):
        if len(act) == 0:
            break
        den = gb - ga
        ok = den != 0.0
        tn = tb - np.where(ok, gb, 0.0) * (tb - ta) / np.where(ok, den, 1.0)
        slow = (it % 2 == 1) & (hi - lo > 0.5 * width)
        if it % 2 == 1:
            width = hi - lo
        bad = ~ok | ~((tn > lo) & (tn < hi)) | slow
        cross = (fhi - flo + glo * lo - ghi * hi) / (glo - ghi)
        cross = np.where((cross > lo) & (cross < hi), cross, 0.5 * (lo + hi))
        tn = np.where(bad, cross, tn)
        fn, gn = fg(tn, act)
        step = np.abs(tn - tb)
        right = gn > 0.0
        lo, flo, glo = np.where(right, lo, tn), np.where(right, flo, fn), np.where(right, glo, gn)
        hi, fhi, ghi = np.where(right, tn, hi), np.where(right, fn, fhi), np.where(right, gn, ghi)
        ta, ga, tb, gb, fc = tb, gb, tn, gn, fn
        done = (gn == 0.0) | (hi - lo <= tol) | (step <= tol)
        t[act[done]], fm[act[done]] = tb[done], fc[done]
        keep = ~done
        act, lo, flo, glo, hi, fhi, ghi, ta, ga, tb, gb, width, fc = (
            x[keep] for x in (act, lo, flo, glo, hi, fhi, ghi, ta, ga, tb, gb, width, fc))
    if len(act):
        t[act], fm[act] = tb, fc
    val = np.minimum(fm, np.minimum(f0, f1))
    t = np.where(val == f0, 0.0, np.where(val == f1, 1.0, t))
    return val, t


def segment_signed_distance_batch(
    stype: ShapeType, size: np.ndarray, a: np.ndarray, b: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Least signed distance over segments ``a b`` to primitives of one type.

    Args:
        stype: any type but MESH.
        size: (n, k) sizes per segment.
        a, b: (n, 3) segment ends in each shape's frame.

    Returns:
        d: (n,) least signed distance along the segment (negative: the
            segment enters the solid).
        t: (n,) parameter where it is reached, point ``a + t (b - a)``.
    """
    a = np.asarray(a, dtype=float).reshape(-1, 3)
    b = np.asarray(b, dtype=float).reshape(-1, 3)
    n = len(a)
    s = np.asarray(size, dtype=float).reshape(n, -1)
    if n == 0:
        return np.zeros(0), np.zeros(0)
    if stype is ShapeType.SPHERE:
        d, t, _ = point_segment(np.zeros_like(a), a, b)
        return d - s[:, 0], t
    if stype is ShapeType.CAPSULE:
        p0 = np.zeros_like(a)
        p1 = np.zeros_like(a)
        p0[:, 2] = -s[:, 1]
        p1[:, 2] = s[:, 1]
        d, t, _, _, _ = segment_segment(a, b, p0, p1)
        return d - s[:, 0], t
    if stype is ShapeType.PLANE:
        lower_b = b[:, 2] < a[:, 2]
        return np.minimum(a[:, 2], b[:, 2]), np.where(lower_b, 1.0, 0.0)
    ab = b - a
    if stype is ShapeType.ELLIPSOID:
        # The derivative along the segment is the outward normal at the
        # closest point (the gradient of the signed distance) dotted with the
        # segment. Each solve is warm-started from the row's previous one.
        e = s[:, :3]
        lam = np.full(n, np.nan)

        def fg(t, rows):
            er = e[rows]
            prev = lam[rows]
            d, cl, lam[rows] = sd_ellipsoid(er, a[rows] + t[:, None] * ab[rows],
                                             None if np.isnan(prev).any() else prev)
            nrm = cl / (er * er)
            g = np.einsum("ij,ij->i", nrm, ab[rows]) / row_norm(nrm)
            return d, g

        return _derivative_min(fg, n)
    else:
        def f(t):
            return signed_distance_value_batch(stype, s, a + t[:, None] * ab)

    return _golden_min(f, n)


_GOLDEN_TYPES = (ShapeType.BOX, ShapeType.CYLINDER)


def segment_signed_distance_mixed(
    types: np.ndarray, size: np.ndarray, a: np.ndarray, b: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`segment_signed_distance_batch` for rows of several primitive types.

    ``types`` (n,) holds each row's type as its index in ``list(ShapeType)``
    (not MESH). Rows whose type needs a line search (box, cylinder) share one
    golden-section loop; the answers are those of
    :func:`segment_signed_distance_batch` row for row.
    """
    a = np.asarray(a, dtype=float).reshape(-1, 3)
    b = np.asarray(b, dtype=float).reshape(-1, 3)
    n = len(a)
    s = np.asarray(size, dtype=float).reshape(n, -1)
    types = np.asarray(types, dtype=np.int64).reshape(n)
    d = np.full(n, np.inf)
    t = np.zeros(n)
    golden = []
    all_types = list(ShapeType)
    for code in np.unique(types):
        stype = all_types[code]
        rows = np.nonzero(types == code)[0]
        if stype in _GOLDEN_TYPES:
            golden.append((stype, rows))
        else:
            d[rows], t[rows] = segment_signed_distance_batch(stype, s[rows], a[rows], b[rows])
    if golden:
        rows = np.concatenate([r for _, r in golden])
        ga, gab = a[rows], b[rows] - a[rows]
        parts = []
        start = 0
        for stype, r in golden:
            parts.append((stype, slice(start, start + len(r)), s[r]))
            start += len(r)

        def f(u):
            x = ga + u[:, None] * gab
            out = np.empty(len(u))
            for stype, sl, sz in parts:
                out[sl] = signed_distance_value_batch(stype, sz, x[sl])
            return out

        d[rows], t[rows] = _golden_min(f, len(rows))
    return d, t


def mesh_segment_unsigned(m: MeshData, a: np.ndarray, b: np.ndarray, k: int = 8,
                          upper: np.ndarray | None = None,
                          cap: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact unsigned distance from segments to a mesh, its parameter and face.

    Same cut-off as :func:`mesh_nearest`, queried from the segment midpoint
    with the half length added to the triangle reach; a segment it does not
    settle is measured against every face whose box comes within its best
    so far of the segment's box (:attr:`MeshData.forest`). ``upper`` (n,): an
    upper bound on each segment's distance the caller has already (a point
    of it measured: the midpoint's distance to the surface): every face
    that may come within it is measured at once, without the k nearest
    faces' first answer. ``cap`` (n,), with ``upper``: the caller keeps a
    distance only below it; a segment whose ``upper`` is positive (its
    midpoint outside a closed mesh) and no face comes within ``cap`` of is
    answered ``cap`` (it is at least that far, wholly outside: a segment
    crossing the surface is at 0 from it), with parameter 0 and face -1.
    """
    n = len(a)
    nf = len(m.faces)
    k = min(k, nf)
    if upper is not None and n:
        # widened past the bound's own rounding (a point query's few ulp)
        upper = np.asarray(upper, float)
        bound = np.abs(upper) * (1 + 1e-9) + 1e-9 * m.bound.h
        capped = np.zeros(n, bool) if cap is None else (np.asarray(cap, float) < bound) & (upper > 0.0)
        if capped.any():
            bound = np.where(capped, cap, bound)
        best, tb, fb = _segment_faces(m, a, b, np.arange(n), bound,
                                      np.full(n, np.inf), np.zeros(n), np.zeros(n, np.int64))
        beyond = capped & (best > bound)             # no face within the cap: at least that far
        best[beyond], tb[beyond], fb[beyond] = bound[beyond], 0.0, -1
        lost = np.flatnonzero((best > bound) & ~beyond)   # a bound that was none: measured the usual way
        if len(lost):
            best[lost], tb[lost], fb[lost] = mesh_segment_unsigned(m, a[lost], b[lost], k)
        return best, tb, fb
    mid = 0.5 * (a + b)
    half = 0.5 * row_norm(b - a)
    dk, idx = m.tree.query(mid, k=k)
    dk = dk.reshape(n, k)
    fi = idx.reshape(n, k).ravel()
    rows = np.repeat(np.arange(n), k)
    d, t, _ = segment_triangle(a[rows], b[rows], m.a[fi], m.b[fi], m.c[fi])
    d = d.reshape(n, k)
    t = t.reshape(n, k)
    j = np.argmin(d, axis=1)
    best = d[np.arange(n), j]
    tb = t[np.arange(n), j]
    fb = fi[np.arange(n) * k + j]
    redo = np.nonzero((k < nf) & (best > dk[:, -1] - m.reach - half))[0]
    if len(redo):
        return _segment_faces(m, a, b, redo, best[redo], best, tb, fb)
    return best, tb, fb


def _segment_faces(m: MeshData, a: np.ndarray, b: np.ndarray, redo: np.ndarray, bound: np.ndarray,
                   best: np.ndarray, tb: np.ndarray, fb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Segments ``redo`` measured against every face that may come within
    ``bound`` (len(redo),) of them, their ``best``, ``tb``, ``fb`` (n,)
    improved in place and returned."""
    # a face within `bound` of the segment has its box within `bound` of the segment's box: a
    # segment lying along a face (a cable resting on it) meets the faces beside it, not the
    # whole ball about its midpoint; the mesh's box tree lists them for all segments at once
    reach = bound[:, None] * (1 + 1e-12) + 1e-300
    lo, hi = np.minimum(a[redo], b[redo]) - reach, np.maximum(a[redo], b[redo]) + reach
    local, fi2 = m.forest.query(np.zeros(len(redo), np.int64), lo, hi)
    if not len(local):            # no face within the bound of any (a cap below every face)
        return best, tb, fb
    rows2 = redo[local]
    d2, t2, _ = segment_triangle(a[rows2], b[rows2], m.a[fi2], m.b[fi2], m.c[fi2])
    o = np.lexsort((d2, rows2))
    first = o[np.r_[True, rows2[o][1:] != rows2[o][:-1]]]
    r = rows2[first]
    better = d2[first] < best[r]
    best[r[better]] = d2[first[better]]
    tb[r[better]] = t2[first[better]]
    fb[r[better]] = fi2[first[better]]
    return best, tb, fb


_MESH_SAMPLES = np.linspace(0.0, 1.0, 9)


def segment_sd_mesh(m: MeshData, a: np.ndarray, b: np.ndarray, upper: np.ndarray | None = None,
                    cap: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    n = len(a)
    if n == 0:
        return np.zeros(0), np.zeros(0)
    du, tu, face = mesh_segment_unsigned(m, a, b, upper=upper, cap=cap)
    if not m.closed:
        return du, tu
    # Penetration: the segment touches the surface, or lies inside. A segment
    # clear of the surface is wholly on one side, decided at its nearest
    # point by the pseudonormal of the nearest triangle's closest feature
    # (that triangle is also the nearest one to that point).
    ts = _MESH_SAMPLES
    # (a segment answered at its cap is wholly outside: mesh_segment_unsigned)
    found = np.flatnonzero(face >= 0)
    inside = np.zeros(n, bool)
    x = a[found] + tu[found, None] * (b[found] - a[found])
    f = face[found]
    _, cl, reg = point_triangle(x, m.a[f], m.b[f], m.c[f])
    inside[found] = mesh_sign(m, x, cl, f, reg) < 0.0
    cand = np.nonzero((du <= 0.0) | inside)[0]
    d = du.copy()
    t = tu.copy()
    if len(cand):
        pts = a[cand, None, :] + ts[None, :, None] * (b - a)[cand, None, :]
        ds, _ = sd_mesh(m, pts.reshape(-1, 3))
        ds = ds.reshape(len(cand), len(ts))
        j = np.argmin(ds, axis=1)
        dmin = ds[np.arange(len(cand)), j]
        tmin = ts[j]
        # the deepest sample's neighbours bracket the deepest point where the
        # depth is concave along the segment; a search there finds it, never
        # shallower than the sample
        lo, hi = ts[np.maximum(j - 1, 0)], ts[np.minimum(j + 1, len(ts) - 1)]
        ca, cd = a[cand], (b - a)[cand]
        span = (hi - lo)[:, None] * cd                  # the bracket along each segment

        def depth(u, rows):
            # the signed distance and its derivative along the bracket: the unit vector from the
            # closest point, outward (a subgradient where two faces are equally near)
            x = ca[rows] + lo[rows, None] * cd[rows] + u[:, None] * span[rows]
            ds, cl = sd_mesh(m, x)
            v = x - cl
            size = row_norm(v)
            slope = np.einsum("ij,ij->i", v, span[rows]) / np.where(size > 0.0, size, 1.0)
            return ds, np.where(ds < 0.0, -slope, slope)

        if m.convex:
            # inside a convex mesh the depth is the least of its face planes' distances, piecewise
            # linear: the tangents at the bracket's ends cross at its kink, found in a few passes
            dg, ug = _derivative_min(depth, len(cand))
        else:
            # a concave one: golden section, 1e-13 of the bracket, which on a depth not concave
            # along the segment finds a deeper point than the tangents more often than not
            dg, ug = _golden_min(lambda u: depth(u, np.arange(len(cand)))[0], len(cand))
        deeper = dg < dmin
        dmin, tmin = np.where(deeper, dg, dmin), np.where(deeper, lo + ug * (hi - lo), tmin)
        d[cand] = np.minimum(dmin, 0.0)
        t[cand] = np.where(dmin < 0.0, tmin, tu[cand])
    return d, t
