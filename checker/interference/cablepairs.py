"""Cables against cables: self and cable-cable pairs, one state or many.

Method ``points`` (the discrete-point distance method, Ju et al., 2016):
two points of one cable closer than ``2r`` interfere unless
:func:`cablecheck.checker.cable.self_pair_excluded` says they are neighbours along the
cable; second pass, a point against the midpoint of every element it is not
a neighbour of. Two cables: the least distance over all point pairs, against
``r1 + r2``. Method ``exact``: element pairs as capsules, exact
segment-segment distances; along one cable the least distance over the two
elements' places that the same rule keeps (at least the window apart in arc
length, :func:`cablecheck.checker.closest.segment_segment_apart`), so exact finds every
self pair points finds, at a distance no larger, the window's edge included.

Pairs along one cable within a few places of each other (the near field)
are taken by shifting the point arrays against themselves, one offset at a
time, after cuts that drop what cannot be a hit (the self rule's arc-length
reach; with points, whole windows whose arc exceeds their chord too little
to fold back within the hit distance; with elements, a chord-minus-arc bound
per pair). Everything farther apart (other cables, loops of the same cable)
comes from chunk pairs of :mod:`cablecheck.checker.interference.broad`. A plain tree
over the points would mostly return each point's own neighbours along its
cable, all of which the self rule then drops. Both halves keep only
candidates that can be below the clearance and compute their values
exactly as a direct pair loop would. :func:`cable_pairs_many` takes given
pairs of body centres over many states at once and shares
:func:`point_pair_rows` with the single-state pass. :func:`closest_elements`
measures one pair of cables as capsules at many states at once (a second
look at a pair the points read: refinement, validation's second opinion).

Deliberately not here: parts, bend and taut, the reduction to records.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cablecheck.checker.arrays import products
from cablecheck.checker.cable import element_pairs_within, self_pair_excluded, self_pair_window
from cablecheck.checker.closest import row_norm, segment_segment, segment_segment_apart
from cablecheck.checker.interference.broad import (
    NEAR,
    SLACK,
    Chunks,
    reach_squared,
    rows_within,
    within_reach,
    within_reach_t,
)
from cablecheck.checker.interference.discrete import DenseStates, Discrete
from cablecheck.checker.interference.hits import TYPE_ORDER, Hits, worst_records
from cablecheck.checker.records import Interference, PairType


def _near_windows(pt, s, cab, last, reach, lim) -> np.ndarray:
    """Points that start a window of ``NEAR + 1`` elements which may hold a self hit.

    In a window from point i to point j (``NEAR + 1`` places on, or the
    cable's end) two places x, y of the polyline are at least as far apart
    as the chord of the window minus the arc length outside them:
    ``|x - y| >= |p_j - p_i| - (s_j - s_i) + |s_x - s_y|``. A self hit needs
    ``|s_x - s_y| >= reach`` (the self rule) and ``|x - y| < lim``, so a
    window whose arc exceeds its chord by no more than ``reach - lim`` holds
    none. Every near-field pair (first pass, or a point against an element's
    midpoint) lies in the window starting at its lower index.

    Args:
        pt: (3, n) the points, coordinate-major; s, cab: (n,) their arc
            lengths and cables; last: (C,) each cable's last point.
    """
    n = pt.shape[1]
    w = NEAR + 1
    if n <= w:
        return np.arange(n)
    # Windows reaching past their cable's end end there instead.
    j = np.minimum(np.arange(w, n + w), last.take(cab))
    d = pt.take(j, axis=1)
    d -= pt
    d *= d
    chord = np.sqrt((d[0] + d[1]) + d[2])
    sj = s.take(j)
    arc = sj - s
    slack = SLACK * (np.abs(sj) + reach + lim)
    return np.flatnonzero(arc - chord > reach - lim - slack)


def _near_field(pt, s, cab, start, reach, lim):
    """The near field's candidates from the windows starting at ``start``:
    first-pass pairs (a, b), then points against elements' midpoints (q, e),
    for b = a + 1 .. a + NEAR on a's cable (see :func:`cable_pairs_points`)."""
    n = pt.shape[1]
    k = np.arange(1, NEAR + 1)
    at = start[:, None] + np.arange(NEAR + 2)            # a .. a + NEAR and the end of element a + NEAR
    on = (at < n) & (cab.take(np.minimum(at, n - 1)) == cab.take(start)[:, None])
    at = np.minimum(at, n - 1)
    w = pt.take(at, axis=1)                               # (3, m, NEAR + 2)
    mid = 0.5 * (w[:, :, :-1] + w[:, :, 1:])              # midpoints of elements a + 0 .. a + NEAR
    sw = s.take(at)
    sm = 0.5 * (sw[:, :-1] + sw[:, 1:])
    ra = reach.take(start)[:, None]
    lim2 = reach_squared(lim.take(start)[:, None] * (1 + SLACK))
    tol = SLACK * (ra + np.abs(sw[:, 1:-1]))
    sa, sb = sw[:, :1], sw[:, 1:-1]                       # a; b = a + k

    def close(x, y):
        d = x - y
        d *= d
        return (d[0] + d[1]) + d[2] < lim2

    valid = on[:, 1:-1]
    first = valid & (sb - sa > ra - tol) & close(w[:, :, :1], w[:, :, 1:-1])
    # a against element b (b + 1 on the cable), b against element a (k >= 2)
    a_eb = on[:, 2:] & (sm[:, 1:] - sa > ra - tol) & close(w[:, :, :1], mid[:, :, 1:])
    b_ea = valid & (k >= 2) & (sb - sm[:, :1] > ra - tol) & close(w[:, :, 1:-1], mid[:, :, :1])
    out = []
    for mask in (first, a_eb, b_ea):
        r, c = np.nonzero(mask)
        a = start.take(r)
        out.append((a, a + k.take(c)))
    (fa, fb), (qa, ea), (eb, qb) = out
    return fa, fb, np.r_[qa, qb], np.r_[ea, eb]


def cable_pairs_points(dp: Discrete, ch: Chunks, clearance: float, hits: Hits,
                        limit: float | None = None, stretch: float = 0.0) -> None:
    """Point-point pairs (self and cable-cable) and the self midpoint pass.

    Candidates: cable-cable point pairs within ``r1 + r2 + clearance``; self
    point pairs within ``2r + clearance``; a point against the midpoint of an
    element not touching it within ``2r + clearance``. Self candidates the
    rule of :func:`~cablecheck.checker.cable.self_pair_excluded` drops are dropped.

    With ``limit`` (>= clearance) candidates are found up to ``limit``
    instead of the clearance, and self pairs up to ``stretch`` of arc length
    inside the exclusion window are kept too; those only bound the gaps
    (:meth:`Hits.gaps`): records are still the pairs below the clearance
    outside the window tied to the clearance.
    """
    p, s, cab, rad = dp.p, dp.s, dp.cable, dp.radius
    limit = clearance if limit is None else limit
    n = len(p)
    has_next = ch.has_next
    pt = np.ascontiguousarray(p.T)

    def mid(e):  # midpoints of elements e (e + 1 on the same cable)
        return 0.5 * (p.take(e, axis=0) + p.take(e + 1, axis=0))

    lim_self = 2.0 * rad + limit
    e0 = np.zeros(0, np.int64)
    fi, fj, sq, se = [e0], [e0], [e0], [e0]  # self first pass (i < j); second pass (point q, element e)
    # Near field: offsets 1..NEAR along one cable, from the window starts
    # that can hold a hit at all (see _near_windows).
    reach = self_pair_window(rad, clearance) - stretch
    start = _near_windows(pt, s, cab, np.flatnonzero(~has_next), reach, lim_self)
    if len(start):
        a, b, q, e = _near_field(pt, s, cab, start, reach, lim_self)
        fi.append(a)
        fj.append(b)
        sq.append(q)
        se.append(e)
    # Far field: chunk pairs.
    ca, cb = ch.pairs(2.0 * float(rad.max()) + limit)
    ci, cj = np.zeros(0, np.int64), np.zeros(0, np.int64)
    if len(ca):
        same = ch.cable.take(ca) == ch.cable.take(cb)
        i, j = ch.expand(ca.compress(~same), cb.compress(~same))
        ok = rows_within(p, i, j, rad.take(i) + rad.take(j) + limit)
        i, j = i.compress(ok), j.compress(ok)
        ci, cj = np.minimum(i, j), np.maximum(i, j)
        i, j = ch.expand(ca.compress(same), cb.compress(same))
        far = np.abs(i - j) > NEAR
        i, j = i.compress(far), j.compress(far)
        ok = rows_within(p, i, j, lim_self.take(i))
        fi.append(np.minimum(i[ok], j[ok]))
        fj.append(np.maximum(i[ok], j[ok]))
        for q, e in ((i, j), (j, i)):
            ok = has_next.take(e) & within_reach(p.take(q, axis=0), mid(np.minimum(e, n - 2)), lim_self.take(q))
            sq.append(q[ok])
            se.append(e[ok])
    rows = point_pair_rows(p, s, cab, rad, reach, clearance, limit, (ci, cj),
                           (np.concatenate(fi), np.concatenate(fj)), (np.concatenate(sq), np.concatenate(se)))
    for kind, a, b, v, i, s_b, rec in rows:
        hits.add(kind, a, b, v, p.take(i, axis=0), s.take(i), s_b, rec)


def point_pair_rows(p: np.ndarray, s: np.ndarray, cab: np.ndarray, rad: np.ndarray, reach: np.ndarray,
                    clearance: float, limit: float, cable_cable: tuple[np.ndarray, np.ndarray],
                    self_points: tuple[np.ndarray, np.ndarray],
                    self_mids: tuple[np.ndarray, np.ndarray]) -> list[tuple]:
    """Values of candidate pairs of discrete places: the one kernel of
    :func:`cable_pairs_points` and :func:`cable_pairs_many`.

    Three kinds of candidates, each (n,) index arrays into the points
    ``p`` (with arc lengths ``s``, cables ``cab``, radii ``rad``):
    ``cable_cable`` (i, j), i < j on two cables, valued ``|p_i - p_j| - r_i
    - r_j``; ``self_points`` (i, j), i < j on one cable, and ``self_mids``
    (q, e), point q against the midpoint of element (e, e + 1) of its
    cable, valued ``|p_i - x| - 2 r_i``. Candidates at or above ``limit``,
    and self pairs less than ``reach`` (per point) apart along the cable,
    are dropped; a self candidate is a record only outside the self rule's
    window (:func:`~cablecheck.checker.cable.self_pair_excluded` at ``clearance``).

    Returns:
        per kind, (type, cable a, cable b, value, place index i (the place
        on a: where and s), arc length on b, record mask or None for all).
    """
    i, j = cable_cable
    v = row_norm(p[i] - p[j]) - rad[i] - rad[j]
    o = v < limit
    i, j = i[o], j[o]
    rows = [(PairType.CABLE_CABLE, cab[i], cab[j], v[o], i, s[j], None)]
    i, j = self_points
    v = row_norm(p[i] - p[j]) - 2 * rad[i]
    o = (v < limit) & ~(np.abs(s[i] - s[j]) < reach[i])
    i, j = i[o], j[o]
    rows.append((PairType.SELF, cab[i], cab[i], v[o], i, s[j], ~self_pair_excluded(s[i], s[j], rad[i], clearance)))
    q, e = self_mids
    mid = 0.5 * (p[e] + p[e + 1])
    sm = 0.5 * (s[e] + s[e + 1])
    v = row_norm(p[q] - mid) - 2 * rad[q]
    o = (v < limit) & ~(np.abs(s[q] - sm) < reach[q])
    q, sm = q[o], sm[o]
    rows.append((PairType.SELF, cab[q], cab[q], v[o], q, sm, ~self_pair_excluded(s[q], sm, rad[q], clearance)))
    return rows


def cable_pairs_exact(dp: Discrete, ch: Chunks, clearance: float, hits: Hits, self_pairs: bool = True) -> None:
    """Element-element pairs (capsule chains), self and cable-cable (with
    ``self_pairs`` False, cable-cable alone: the same candidates, bits
    included, without the search along each cable).

    Element pairs are pruned by lower bounds on their distance before the
    exact segment-segment distance: the midpoints' distance minus the half
    lengths; along one cable also the chord between the pair's outer ends
    minus the arc length between them, plus the arc-length separation the
    self rule requires.

    Along one cable the value is the least distance between places of the
    two elements at least :func:`~cablecheck.checker.cable.self_pair_window` apart in
    arc length (:func:`~cablecheck.checker.closest.segment_segment_apart`), not the
    elements' own closest places filtered by the rule: those may lie inside
    the window while other places of the same elements, outside it, are
    within the clearance (a tight bend's legs just past the window's edge).
    """
    p, s, cab, rad, seg = dp.p, dp.s, dp.cable, dp.radius, dp.seg
    if len(seg) == 0:
        return
    n = len(p)
    mid = 0.5 * (p[:-1] + p[1:])
    half = 0.5 * (s[1:] - s[:-1])  # half element lengths (arc = chord per element)
    lim_self = 2.0 * rad + clearance
    reach = self_pair_window(rad, clearance)

    def self_ok(e, f):
        """Element pairs e < f of one cable that may hold a self hit."""
        lim = lim_self[e] + half[e] + half[f]
        arc = s[f + 1] - s[e]
        tol = SLACK * (np.abs(s[f + 1]) + reach[e] + lim_self[e])
        bound = lim_self[e] + arc - reach[e] + tol
        return ((arc > reach[e] - tol) & (bound > 0) & within_reach(mid[e], mid[f], lim)
                & within_reach(p[e], p[f + 1], np.maximum(bound, 0.0)))

    ea, eb = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
    pt = np.ascontiguousarray(p.T)
    for k in range(1, min(NEAR, n - 2) + 1 if self_pairs else 1):
        # Elements e and e + k: the cheap arc-length test and the chord bound
        # on whole slices, the rest on the few survivors.
        m = n - k - 1
        arc = s[k + 1:] - s[:m]
        tol = SLACK * (np.abs(s[k + 1:]) + reach[:m] + lim_self[:m])
        bound = lim_self[:m] + arc - reach[:m] + tol
        ok = (cab[:m] == cab[k + 1:]) & (arc > reach[:m] - tol) & (bound > 0)
        if not ok.any():
            continue
        e = np.nonzero(ok & within_reach_t(pt[:, :m], pt[:, k + 1:], np.maximum(bound, 0.0)))[0]
        e = e[self_ok(e, e + k)]
        ea.append(e)
        eb.append(e + k)
    ca, cb = ch.pairs(2.0 * float(rad.max()) + clearance)
    if len(ca):
        same = ch.cable[ca] == ch.cable[cb]
        i, j = ch.expand(ca[~same], cb[~same])
        ok = within_reach(mid[i], mid[j], rad[i] + rad[j] + clearance + half[i] + half[j])
        ea.append(np.minimum(i[ok], j[ok]))
        eb.append(np.maximum(i[ok], j[ok]))
        same &= self_pairs
        i, j = ch.expand(ca[same], cb[same])
        i, j = np.minimum(i, j), np.maximum(i, j)
        o = j - i > NEAR
        i, j = i[o], j[o]
        o = self_ok(i, j)
        ea.append(i[o])
        eb.append(j[o])
    ia, ib = np.concatenate(ea), np.concatenate(eb)
    if len(ia) == 0:
        return
    same = cab[ia] == cab[ib]
    o = ~same
    i, j = ia[o], ib[o]
    d, ta, tb, ca_, _ = segment_segment(p[i], p[i + 1], p[j], p[j + 1])
    sa = s[i] + ta * (s[i + 1] - s[i])
    sb = s[j] + tb * (s[j + 1] - s[j])
    hits.add(PairType.CABLE_CABLE, cab[i], cab[j], d - rad[i] - rad[j], ca_, sa, sb)
    # one cable (i < j): the least distance over the places of the two
    # elements at least the self rule's window apart along it, wherever
    # the elements' own closest places are (those may lie inside the window
    # while places of the same elements outside it are within the clearance)
    i, j = ia[same], ib[same]
    d, ta, tb, ca_, _ = segment_segment_apart(p[i], p[i + 1], p[j], p[j + 1], s[i], s[i + 1], s[j], s[j + 1],
                                              reach[i])
    sa = s[i] + ta * (s[i + 1] - s[i])
    sb = s[j] + tb * (s[j + 1] - s[j])
    o = np.isfinite(d)          # allowed by construction (the rule, to the bit at the window's edge)
    hits.add(PairType.SELF, cab[i[o]], cab[i[o]], d[o] - 2 * rad[i[o]], ca_[o], sa[o], sb[o])


def cable_pairs_many(clearance: float, names: Sequence[str], radii: np.ndarray, dense: DenseStates,
                     active: tuple[np.ndarray, np.ndarray]) -> list[list[Interference]]:
    """The full check's self and cable-cable records at many states at
    once, from the discrete places next to given pairs of body centres
    (method ``points``; to the bit).

    For each active pair of centres (i, j) every discrete point next to
    i (i itself, the points inside its two elements) is paired with
    every one next to j, and on one cable also with the midpoint of
    every piece next to j (and the other way round); a record is the
    worst of those (the caller knows the others to be clear). Every
    state must split each element into as many pieces as the first. The
    points may be those of some centres only (``densify_many``'s
    ``keep``): every entry's centre and both its neighbours must be
    present.

    Args:
        names, radii: the cables' names and radii (C,).
        dense: the states' discrete points (:meth:`densify_many`).
        active: (centre i, centre j) arrays.

    Returns:
        per state, its records (worst first).
    """
    n_s, n, n_c = dense.states, dense.centres, dense.cables
    out: list[list[Interference]] = [[] for _ in range(n_s)]
    ci, cj = (np.asarray(x, np.int64) for x in active)
    if n_s == 0 or len(ci) == 0:
        return out
    radii = np.asarray(radii, float)
    p, s, poly, src, own = dense.p, dense.s, dense.poly, dense.src, dense.own
    cab, rad = poly % n_c, radii[poly % n_c]
    m = len(p) // n_s                                  # points per state (the same in each)
    if m * n_s != len(p) or not np.all(src.reshape(n_s, m) - n * np.arange(n_s)[:, None] == src[:m]):
        raise ValueError("every state must split its elements into as many pieces as the first")
    # One state's layout in atoms: a centre's own point (atom 2c) and the
    # points inside the element after it (atom 2c + 1), each a run of the
    # layout; the points next to centre c are those of atoms 2c - 1, 2c and
    # 2c + 1. A piece (two consecutive points of one element, or an
    # element's last and its far end; never across centres left out,
    # densify_many's keep) belongs to the element of its first point; the
    # pieces next to centre c are those of elements c - 1 and c. The active
    # centre pairs give distinct atom pairs (and point atom, piece element
    # pairs); in each state those whose bounding spheres lie beyond the
    # limit are dropped (a lower bound, with a margin against rounding), and
    # only then are their points paired: each point pair the product of the
    # points next to the active centres holds, once, less those the bound
    # puts beyond the limit (no record, no candidate).
    c0, own0 = src[:m], own[:m]
    atom = 2 * c0 + (~own0).astype(np.int64)
    if np.any(atom[1:] < atom[:-1]):
        raise ValueError("every state's points must run along its centres")
    a_first = np.searchsorted(atom, np.arange(2 * n), "left")
    a_count = np.searchsorted(atom, np.arange(2 * n), "right") - a_first
    piece0 = np.r_[(poly[1:m] == poly[:m - 1]) & (c0[1:] - c0[:-1] <= 1), False]
    pieces = np.flatnonzero(piece0)                     # each piece by its first point
    e_first = np.searchsorted(c0[pieces], np.arange(n), "left")
    e_count = np.searchsorted(c0[pieces], np.arange(n), "right") - e_first
    centre_cable = np.zeros(n, np.int64)
    centre_cable[c0] = cab[:m]

    def runs_spheres(values: np.ndarray, first: np.ndarray, count: np.ndarray) -> np.ndarray:
        """(S, K) per state the farthest of each run's values (S, rows) from the run's first."""
        live = np.flatnonzero(count)
        run = np.repeat(live, count[live])
        far = row_norm((values - values[:, first[run]]).reshape(-1, 3)).reshape(n_s, -1)
        rad = np.zeros((n_s, len(first)))
        rad[:, live] = np.maximum.reduceat(far, first[live] - first[live[0]], axis=1) if len(live) else 0.0
        return rad

    pts = p.reshape(n_s, m, 3)
    a_rad = runs_spheres(pts, a_first, a_count)                             # (S, 2n)
    mids = 0.5 * (pts[:, pieces] + pts[:, pieces + 1])                      # (S, pieces, 3)
    e_rad = runs_spheres(mids, e_first, e_count) if len(pieces) else np.zeros((n_s, n))

    def combos(x: np.ndarray, y: np.ndarray, size_y: int, ordered: bool) -> tuple[np.ndarray, np.ndarray]:
        """The distinct (x, y) of rows of candidates x (E, k) and y (E, l) of each entry."""
        x, y = np.repeat(x, y.shape[1], axis=1).ravel(), np.tile(y, (1, x.shape[1])).ravel()
        if not ordered:
            x, y = np.minimum(x, y), np.maximum(x, y)
        key = np.unique((x + 1) * (size_y + 2) + (y + 1))      # -1 (no such centre) included
        return key // (size_y + 2) - 1, key % (size_y + 2) - 1

    def kept(ref_a: np.ndarray, ref_b: np.ndarray, lim: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(state, index) of the (S, K) pairs whose references (S, K, 3) are within lim (S, K)."""
        if lim.size == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        near = within_reach(ref_a.reshape(-1, 3), ref_b.reshape(-1, 3), lim.ravel())
        return np.divmod(np.flatnonzero(near), lim.shape[1])

    def product(st, a0, na, b0, nb):
        """Every (x, y), x in rows a0 .. a0 + na - 1 and y in b0 .. b0 + nb - 1 of state st (global rows)."""
        k, x, y = products(na, nb)
        off = m * st[k]
        return a0[k] + x + off, b0[k] + y + off

    near_atoms = np.stack([2 * ci - 1, 2 * ci, 2 * ci + 1], axis=1)
    near_atoms_j = np.stack([2 * cj - 1, 2 * cj, 2 * cj + 1], axis=1)
    x, y = combos(near_atoms, near_atoms_j, 2 * n, ordered=False)
    ok = (x >= 0) & (y < 2 * n)
    x, y = x[ok], y[ok]
    ok = (a_count[x] > 0) & (a_count[y] > 0)
    x, y = x[ok], y[ok]
    rx, ry = a_first[x], a_first[y]
    lim = clearance + a_rad[:, x] + a_rad[:, y] + radii[centre_cable[x // 2]] + radii[centre_cable[y // 2]]
    st, k = kept(pts[:, rx], pts[:, ry], lim)
    lo, hi = product(st, rx[k], a_count[x[k]], ry[k], a_count[y[k]])
    keep = lo < hi                                      # one atom with itself: each pair once
    lo, hi = lo[keep], hi[keep]
    same = cab[lo] == cab[hi]
    # most points of two cables' near atoms lie beyond the limit: pruned as the full check prunes
    # its pairs, before their values are taken (a harness keeps one in fourteen; valuing them all
    # cost twice the test)
    two_i, two_j = lo[~same], hi[~same]
    near = rows_within(p, two_i, two_j, rad[two_i] + rad[two_j] + clearance)
    two_i, two_j = two_i[near], two_j[near]
    # a point against the midpoint of a piece of its own cable not touching it
    near_elems = np.stack([ci - 1, ci], axis=1)
    near_elems_j = np.stack([cj - 1, cj], axis=1)
    qa, qe = combos(np.r_[near_atoms, near_atoms_j], np.r_[near_elems_j, near_elems], n, ordered=True)
    ok = (qa >= 0) & (qa < 2 * n) & (qe >= 0)
    qa, qe = qa[ok], qe[ok]
    ok = (a_count[qa] > 0) & (e_count[qe] > 0) & (centre_cable[qa // 2] == centre_cable[qe])
    qa, qe = qa[ok], qe[ok]
    lim = clearance + a_rad[:, qa] + e_rad[:, qe] + 2 * radii[centre_cable[qe]]
    st, k = kept(pts[:, a_first[qa]], mids[:, e_first[qe]], lim)
    q, e = product(st, a_first[qa[k]], a_count[qa[k]], e_first[qe[k]], e_count[qe[k]])
    e = pieces[e - m * (q // m)] + m * (q // m)         # piece numbers to their first points' rows
    keep = (q != e) & (q != e + 1)
    rows = point_pair_rows(p, s, cab, rad, self_pair_window(rad, clearance), clearance, clearance,
                           (two_i, two_j), (lo[same], hi[same]), (q[keep], e[keep]))
    t, a, b, v, w, sb = ([] for _ in range(6))
    for kind, a_k, b_k, v_k, w_k, sb_k, rec in rows:
        o = slice(None) if rec is None else rec
        t.append(np.full(len(v_k[o]), TYPE_ORDER.index(kind)))
        for acc, x in zip((a, b, v, w, sb), (a_k, b_k, v_k, w_k, sb_k)):
            acc.append(x[o])
    t, a, b, v, w, sb = (np.concatenate(x) for x in (t, a, b, v, w, sb))
    return worst_records(n_s, w // m, t, a, b, v, p[w], s[w], sb, clearance, names, lambda _: names)


def closest_elements(pa: np.ndarray, pb: np.ndarray, upper: np.ndarray):
    """Per state k, the least segment distance between the elements of
    polylines pa[k] (na, 3) and pb[k] (nb, 3), looking only at element
    pairs whose bounding spheres come within ``upper[k]`` (inf where none
    does; `element_pairs_within`): (distance, element of a, element of b,
    parameter on a, parameter on b), one row a state; the least by
    distance, then by the elements' order (a tie goes to the first pair
    along a, then b)."""
    n_s = len(pa)
    k, ia, ib, _ = element_pairs_within(pa, pb, upper)
    d, u, v, _, _ = segment_segment(pa[k, ia], pa[k, ia + 1], pb[k, ib], pb[k, ib + 1])
    best = np.full(n_s, np.inf)
    out_a, out_b = np.zeros(n_s, np.int64), np.zeros(n_s, np.int64)
    out_u, out_v = np.zeros(n_s), np.zeros(n_s)
    if len(k):
        o = np.lexsort((ib, ia, d, k))
        head = o[np.r_[True, k[o][1:] != k[o][:-1]]]
        best[k[head]] = d[head]
        out_a[k[head]], out_b[k[head]], out_u[k[head]], out_v[k[head]] = ia[head], ib[head], u[head], v[head]
    return best, out_a, out_b, out_u, out_v
