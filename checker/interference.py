"""Interference of one scene state: self, cable-cable, cable-structure, keep-out.

:func:`check_state` runs the discrete-point distance algorithm (Ju et al., 2016) on all cables and
parts of one instant and returns one :class:`~checker.records.Interference`
per interfering pair. :class:`Checker` does the same step after step for one
set of parts, preparing what depends only on the parts once; each call then
takes the cables and the parts' poses.

Method ``points`` (the paper): each cable's body centres are densified so no
element is longer than ``spacing * r`` (:func:`checker.cable.densify_batch`).

- Self: two points of one cable closer than ``2r`` interfere, unless
  :func:`checker.cable.self_pair_excluded` says they are neighbours along the
  cable; second pass, a point against the midpoint of every element it is not
  a neighbour of.
- Cable-cable: the least distance over all point pairs, against ``r1 + r2``.
- Cable-structure and keep-out: a point's signed distance to the part's
  surface (negative inside: containment comes for free), against ``r``.

Method ``exact``: the same polylines are taken as chains of capsules. Element
pairs use exact segment-segment distances, elements against parts the least
signed distance along the segment (:mod:`checker.shapes`), so contact between
two discrete points is never missed. For self pairs the exclusion rule is
applied at the closest points' arc lengths.

Broad phase. The points (or elements) of every cable are cut into chunks of
a few consecutive ones, each with a bounding sphere (around the chord's
midpoint, of half the arc length), and one k-d tree is built over pairs of
consecutive chunks. Cable against cable: places within a few points of each
other along one cable (the near field) never come from the tree; they are
taken by index offset, after cuts that drop what cannot be a hit (the self
rule's arc-length reach; with points, whole windows whose arc exceeds their
chord too little to fold back within the hit distance; with elements, a
chord-minus-arc bound per pair). Everything else (other cables, loops of the
same cable) comes from chunk pairs found through the tree. Element pairs are
further cut by lower bounds on their distance before the exact segment
distance. Cable against parts: every part's bounding sphere meets the tree,
then the chunks' spheres; the items of the chunks met are cut to the part's
inflated local box before any exact work. Narrow phases are batched per shape
type (all primitives' segment searches in one call); meshes per mesh, with the
parts sharing one mesh in one call through the mesh's own tree. Cost therefore
grows with the number of close pairs, not with points x parts. Of several
candidates with the same value, the one at the smallest arc lengths is
reported, so the answer does not depend on the broad phase's order.

Deliberately not done here: part-part interference (``PairType.PART_PART``,
left to MuJoCo or a later sweep module), events over time and comparison with
MuJoCo.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from checker.arrays import ranges, within
from checker.cable import (arc_length, bend_radius, densify_batch, material_coordinates, polyline_arc_lengths,
                           self_pair_excluded, self_pair_window, taut_margin, tile_offsets)
from checker.closest import row_norm, segment_segment
from checker.records import Interference, PairType, severity_of
from checker.scene_state import CableState, CheckConfig, Exclusion, PartState
from checker.shapes import (
    ShapeType,
    distance_bounds,
    face_plane_distance,
    face_plane_distance_batch,
    segment_signed_distance,
    segment_signed_distance_mixed,
    signed_distance,
    signed_distance_value_batch,
)

_TYPE_ORDER = list(PairType)
_TYPE_CODE = {t: n for n, t in enumerate(ShapeType)}
_EYE3 = np.eye(3)
_CABLE_PAIR_CODES = (_TYPE_ORDER.index(PairType.SELF), _TYPE_ORDER.index(PairType.CABLE_CABLE))
_PART_CODES = (_TYPE_ORDER.index(PairType.CABLE_STRUCTURE), _TYPE_ORDER.index(PairType.KEEPOUT))


# ---------------------------------------------------------------------------
# Discretisation


class _Discrete:
    """All cables' discrete points, concatenated (a plain bundle of arrays).

    Attributes:
        p: (M, 3) points.
        s: (M,) arc length along the point's cable.
        m: (M,) material coordinate (:attr:`CableState.rest_s`; ``s`` itself
            when no cable has one): exclusion windows are measured in it.
        cable: (M,) cable index.
        radius: (M,) the point's cable radius.
        seg: (E,) index i of each element (p[i], p[i + 1]) within one cable.
    """

    def __init__(self, p, s, m, cable, radius):
        self.p = p
        self.s = s
        self.m = m
        self.cable = cable
        self.radius = radius
        self.seg = np.nonzero(cable[:-1] == cable[1:])[0]


def _rest_table(cables: Sequence[CableState]) -> tuple[np.ndarray, np.ndarray]:
    """(C,) bool, the cable has rest coordinates; (N,) all cables' rest
    coordinates concatenated (0 where a cable has none)."""
    has = np.array([c.rest_s is not None for c in cables], bool)
    rest = np.concatenate([c.rest_s if c.rest_s is not None else np.zeros(len(c.points)) for c in cables]) \
        if len(cables) else np.zeros(0)
    return has, rest


def _discretise(
    cables: Sequence[CableState], config: CheckConfig, cuts: tuple[np.ndarray, np.ndarray]
) -> _Discrete:
    """Densify every cable; add points at the material coordinates ``cuts`` = (cable, m)."""
    radii = np.array([c.radius for c in cables], dtype=float)
    pts = np.concatenate([c.points for c in cables])
    offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
    p, s, cable, _, src, _, frac = densify_batch(pts, offsets, config.spacing * radii, source=True)
    has, rest = _rest_table(cables)
    m = material_coordinates(s, src, frac, has[cable], rest)
    cut_c, cut_m = cuts
    if len(cut_c):
        p, s, m, cable = _insert_at_material(p, s, m, cable, cut_c, cut_m)
    return _Discrete(p, s, m, cable, radii[cable])


def _insert_at_material(p, s, m, cable, cut_c, cut_m):
    """Insert points on the polylines at material coordinates ``cut_m`` of
    cables ``cut_c`` (``m`` may be ``s`` itself: then at arc lengths).

    Cuts outside a cable's length or on an existing point are dropped.
    """
    n_c = int(cable.max()) + 1
    stop = np.searchsorted(cable, np.arange(n_c), side="right")
    length = m[stop - 1]
    first = m[np.r_[0, stop[:-1]]]
    keep = (cut_c >= 0) & (cut_m > first[np.maximum(cut_c, 0)]) & (cut_m < length[np.maximum(cut_c, 0)])
    cut_c, cut_m = cut_c[keep], cut_m[keep]
    # Find the element of each cut: order all points and cuts by (cable, m).
    order = np.lexsort((np.r_[m, cut_m], np.r_[cable, cut_c]))
    is_cut = order >= len(m)
    # For each cut, the last original point before it in that order.
    last_pt = np.maximum.accumulate(np.where(is_cut, -1, order))
    k = last_pt[is_cut]
    ci = order[is_cut] - len(m)
    cm = cut_m[ci]
    dm = m[k + 1] - m[k]
    u = np.where(dm > 0, cm - m[k], 0.0) / np.where(dm > 0, dm, 1.0)
    new_p = p[k] + u[:, None] * (p[k + 1] - p[k])
    new_s = cm if m is s else s[k] + u * (s[k + 1] - s[k])
    fresh = (cm > m[k]) & (cm < m[k + 1])
    new_p, new_s, cm, new_c = new_p[fresh], new_s[fresh], cm[fresh], cut_c[ci][fresh]
    allp = np.concatenate([p, new_p])
    alls = np.concatenate([s, new_s])
    allm = alls if m is s else np.concatenate([m, cm])
    allc = np.concatenate([cable, new_c])
    o = np.lexsort((allm, allc))
    return allp[o], alls[o], allm[o], allc[o]


# ---------------------------------------------------------------------------
# Reduction of candidate values to one record per pair


class _Hits:
    """Accumulates candidate values; reduces to the worst per (type, a, b)."""

    def __init__(self):
        self.parts: list[tuple] = []
        self.near: list[tuple] = []  # (type, a, b, value, s, s_b): every candidate, for the gaps

    def add(self, ptype: PairType, a, b, value, where, s, s_b=None, record=None):
        """Candidates; ``record`` (n,) bool marks those that may become records
        (the others, e.g. just inside an exclusion, only bound the gaps)."""
        if len(value) == 0:
            return
        code = _TYPE_ORDER.index(ptype)
        self.near.append((code, a, b, value, s, s_b))
        if record is not None:
            a, b, value, where, s = a[record], b[record], value[record], where[record], s[record]
            s_b = None if s_b is None else s_b[record]
            if len(value) == 0:
                return
        n = len(value)
        s_b = np.full(n, np.nan) if s_b is None else s_b
        self.parts.append((np.full(n, code), a, b, value, where, s, s_b))

    def gaps(self, clearance: float, horizon: float, n_parts: int) -> tuple[float, np.ndarray]:
        """Smallest candidate value minus the clearance: over cable pairs (self
        and cable-cable), and per part (cable-structure and keep-out), at most
        ``horizon`` (candidates are found up to clearance + horizon)."""
        cc = horizon
        part = np.full(n_parts, horizon)
        for code, _, b, value, _, _ in self.near:
            if code in _CABLE_PAIR_CODES:
                cc = min(cc, float(value.min()) - clearance)
            elif code in _PART_CODES:
                np.minimum.at(part, b, value - clearance)
        return cc, part

    def part_candidates(self, clearance: float) -> tuple[np.ndarray, ...]:
        """Every cable-structure and keep-out candidate: (cable, s, part,
        value - clearance), for gaps per cable place (:mod:`checker.advance`)."""
        rows = [(a, s, b, value - clearance) for code, a, b, value, s, _ in self.near if code in _PART_CODES]
        if not rows:
            return np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64), np.zeros(0)
        return tuple(np.concatenate(x) for x in zip(*rows))

    def cable_candidates(self, clearance: float) -> tuple[np.ndarray, ...]:
        """Every self and cable-cable candidate: (cable a, s_a, cable b, s_b,
        value - clearance), for gaps per pair of cable places (:mod:`checker.advance`)."""
        rows = [(a, s, b, s_b, value - clearance) for code, a, b, value, s, s_b in self.near
                if code in _CABLE_PAIR_CODES]
        if not rows:
            z = np.zeros(0, np.int64)
            return z, np.zeros(0), z, np.zeros(0), np.zeros(0)
        return tuple(np.concatenate(x) for x in zip(*rows))

    def reduce(self, clearance, cable_names, b_names_by_type) -> list[Interference]:
        if not self.parts:
            return []
        t, a, b, v, w, s, sb = (np.concatenate(x) for x in zip(*self.parts))
        keep = v < clearance
        t, a, b, v, w, s, sb = t[keep], a[keep], b[keep], v[keep], w[keep], s[keep], sb[keep]
        if len(v) == 0:
            return []
        # Ties in value go to the smallest arc lengths, so the answer does
        # not depend on the order the broad phase found the candidates in.
        o = np.lexsort((np.nan_to_num(sb, nan=-np.inf), s, v, b, a, t))
        t, a, b = t[o], a[o], b[o]
        first = np.r_[True, (t[1:] != t[:-1]) | (a[1:] != a[:-1]) | (b[1:] != b[:-1])]
        idx = o[first]
        # One record per pair (a few hundred at most): plain Python values.
        ts, as_, bs = t[first].tolist(), a[first].tolist(), b[first].tolist()
        vs, ss, sbs = v[idx].tolist(), s[idx].tolist(), sb[idx].tolist()
        ws = w[idx]
        out = []
        for n, ptype_i in enumerate(ts):
            ptype = _TYPE_ORDER[ptype_i]
            d = vs[n]
            sb_n = sbs[n]
            out.append(Interference(
                type=ptype, a=cable_names[as_[n]], b=b_names_by_type(ptype)[bs[n]],
                min_distance=d, severity=severity_of(d, clearance), where=ws[n],
                s=ss[n], s_b=None if sb_n != sb_n else sb_n,
            ))
        return out


# ---------------------------------------------------------------------------
# Cables against cables
#
# Pairs along one cable within a few places of each other (the near field)
# are taken by shifting the point arrays against themselves, one offset at a
# time; everything farther apart (other cables, and loops of the same cable)
# comes from a k-d tree over chunks of _CHUNK consecutive items, each with a
# bounding sphere. A plain tree over the points would mostly return each
# point's own neighbours along its cable, all of which the self rule then
# drops. Both halves keep only candidates that can be below the clearance and
# compute their values exactly as a direct pair loop would.

_CHUNK = 4
_NEAR = 2 * _CHUNK - 1  # offsets along a cable covered by the near field
_SLACK = 1e-9  # relative margin of the pruning bounds against rounding


class _Chunks:
    """Runs of up to ``_CHUNK`` consecutive items of one cable with bounding spheres.

    Item ``i`` (an index into the points) stands for the piece from ``p[i]``
    to ``p[i + 1]`` when the next point is on the same cable (a point and the
    element after it, or an element), else for ``p[i]`` alone.

    Attributes:
        idx: (C, _CHUNK) item indices, -1 padded.
        cable: (C,) cable of each chunk; chunk ids are consecutive along a cable.
        centre, radius: bounding spheres.
        sub: (S, 2) the chunks of each super chunk (two consecutive chunks of
            one cable), -1 padded; sup_centre, sup_radius: their spheres.
        tree: k-d tree over the super chunks' centres.
        has_next: (M,) point i + 1 is on point i's cable.
    """

    def __init__(self, p, s, cable, has_next, items):
        ic = cable[items]
        n = len(items)
        # Position of each item along its cable's run of items.
        new_cable = np.r_[True, ic[1:] != ic[:-1]]
        run_start = np.nonzero(new_cable)[0]
        local = np.arange(n) - np.repeat(run_start, np.diff(np.r_[run_start, n]))
        slot = local % _CHUNK
        first = slot == 0
        cid = np.cumsum(first) - 1
        starts = np.nonzero(first)[0]
        self.idx = np.full((len(starts), _CHUNK), -1, dtype=np.int64)
        self.idx[cid, slot] = items
        self.cable = ic[starts]
        # A chunk's pieces form a polyline from a to b of arc length L; every
        # point x of it lies within L / 2 of the chord's midpoint, since
        # |x - a| + |x - b| <= L.
        a = items[starts]
        last = items[np.r_[starts[1:], n] - 1]
        b = np.where(has_next[last], last + 1, last)
        self.centre = 0.5 * (p[a] + p[b])
        self.radius = 0.5 * (s[b] - s[a])
        self.has_next = has_next
        # Pairs of consecutive chunks of one cable ("super chunks") hold the
        # tree for chunk pairs: half as many spheres to pair up.
        nc = len(starts)
        new_sup = np.r_[True, self.cable[1:] != self.cable[:-1]]
        run = np.nonzero(new_sup)[0]
        local = np.arange(nc) - np.repeat(run, np.diff(np.r_[run, nc]))
        first = local % 2 == 0
        sid = np.cumsum(first) - 1
        sup_start = np.nonzero(first)[0]
        self.sub = np.full((len(sup_start), 2), -1, dtype=np.int64)
        self.sub[sid, local % 2] = np.arange(nc)
        sa = a[sup_start]
        sb = b[np.r_[sup_start[1:], nc] - 1]
        self.sup_centre = 0.5 * (p[sa] + p[sb])
        self.sup_radius = 0.5 * (s[sb] - s[sa])
        self.tree = cKDTree(self.sup_centre, balanced_tree=False, compact_nodes=False)

    def pairs(self, reach: float) -> tuple[np.ndarray, np.ndarray]:
        """Chunk pairs (A < B) whose spheres come within ``reach``, except
        chunks of one cable that are the same or adjacent (the near field)."""
        none = np.zeros(0, np.int64), np.zeros(0, np.int64)
        if len(self.sup_radius) < 2:
            return none  # one super chunk: its two chunks are adjacent
        # Super chunk pairs first (the two chunks of one are adjacent), then
        # their chunks' 2 x 2 combinations against the chunks' own spheres.
        rmax = float(self.sup_radius.max())
        pr = self.tree.query_pairs((reach + 2.0 * rmax) * (1 + _SLACK), output_type="ndarray")
        if len(pr) == 0:
            return none
        a = np.repeat(self.sub[pr[:, 0]], 2, axis=1).ravel()
        b = np.tile(self.sub[pr[:, 1]], (1, 2)).ravel()
        ok = (a >= 0) & (b >= 0)
        a, b = a[ok], b[ok]
        a, b = np.minimum(a, b), np.maximum(a, b)
        lim = reach + self.radius[a] + self.radius[b]
        keep = _within(self.centre[a], self.centre[b], lim) & ~((self.cable[a] == self.cable[b]) & (b - a <= 1))
        return a[keep], b[keep]

    def expand(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """All item pairs (i in chunk a, j in chunk b), flattened, padding dropped."""
        i = np.repeat(self.idx[a], _CHUNK, axis=1).ravel()
        j = np.tile(self.idx[b], (1, _CHUNK)).ravel()
        ok = (i >= 0) & (j >= 0)
        return i[ok], j[ok]


def _within(x: np.ndarray, y: np.ndarray, lim: np.ndarray) -> np.ndarray:
    """|x - y| < lim for rows of (n, 3) arrays, with a margin (pruning only)."""
    t = x - y
    lim = lim * (1 + _SLACK)
    return np.einsum("ij,ij->i", t, t) < lim * lim


def _within_t(x: np.ndarray, y: np.ndarray, lim: np.ndarray) -> np.ndarray:
    """:func:`_within` for coordinate-major (3, n) arrays (contiguous slices)."""
    t = x - y
    t *= t
    lim = lim * (1 + _SLACK)
    return t[0] + t[1] + t[2] < lim * lim


def _near_windows(p, s, cab, reach, lim) -> np.ndarray:
    """Points that start a window of ``_NEAR + 1`` elements which may hold a self hit.

    In a window from point i to point j (``_NEAR + 1`` places on, or the
    cable's end) two places x, y of the polyline are at least as far apart
    as the chord of the window minus the arc length outside them:
    ``|x - y| >= |p_j - p_i| - (s_j - s_i) + |s_x - s_y|``. A self hit needs
    ``|s_x - s_y| >= reach`` (the self rule) and ``|x - y| < lim``, so a
    window whose arc exceeds its chord by no more than ``reach - lim`` holds
    none. Every near-field pair (first pass, or a point against an element's
    midpoint) lies in the window starting at its lower index.
    """
    n = len(p)
    w = _NEAR + 1
    if n <= w:
        return np.arange(n)
    # Windows reaching past their cable's end end there instead.
    j = np.arange(w, n + w)
    j[n - w:] = n - 1
    cut = np.nonzero(cab[j] != cab)[0]
    j[cut] = np.searchsorted(cab, cab[cut], side="right") - 1
    d = np.empty_like(p)
    d[: n - w] = p[w:] - p[: n - w]
    d[cut] = p[j[cut]] - p[cut]
    d[n - w:] = p[j[n - w:]] - p[n - w:]
    chord = np.sqrt(np.einsum("ij,ij->i", d, d))
    arc = s[j] - s
    slack = _SLACK * (np.abs(s[j]) + reach + lim)
    return np.nonzero(arc - chord > reach - lim - slack)[0]


def _cable_pairs_points(dp: _Discrete, ch: _Chunks, clearance: float, hits: _Hits,
                        limit: float | None = None, stretch: float = 0.0) -> None:
    """Point-point pairs (self and cable-cable) and the self midpoint pass.

    Candidates: cable-cable point pairs within ``r1 + r2 + clearance``; self
    point pairs within ``2r + clearance``; a point against the midpoint of an
    element not touching it within ``2r + clearance``. Self candidates the
    rule of :func:`~checker.cable.self_pair_excluded` drops are dropped.

    With ``limit`` (>= clearance) candidates are found up to ``limit``
    instead of the clearance, and self pairs up to ``stretch`` of arc length
    inside the exclusion window are kept too; those only bound the gaps
    (:meth:`_Hits.gaps`): records are still the pairs below the clearance
    outside the window tied to the clearance.
    """
    p, s, cab, rad = dp.p, dp.s, dp.cable, dp.radius
    limit = clearance if limit is None else limit
    n = len(p)
    has_next = ch.has_next

    def mid(e):  # midpoints of elements e (e + 1 on the same cable)
        return 0.5 * (p[e] + p[e + 1])

    lim_self = 2.0 * rad + limit
    e0 = np.zeros(0, np.int64)
    fi, fj, sq, se = [e0], [e0], [e0], [e0]  # self first pass (i < j); second pass (point q, element e)
    # Near field: offsets 1.._NEAR along one cable, from the window starts
    # that can hold a hit at all (see _near_windows).
    reach = self_pair_window(rad, clearance) - stretch
    start = _near_windows(p, s, cab, reach, lim_self)
    if len(start):
        k = np.tile(np.arange(1, _NEAR + 1), len(start))
        a = np.repeat(start, _NEAR)
        b = a + k
        ok = b < n
        a, b, k = a[ok], b[ok], k[ok]
        ok = cab[b] == cab[a]
        a, b, k = a[ok], b[ok], k[ok]
        tol = _SLACK * (reach[a] + np.abs(s[b]))
        # First pass (a, b); second pass a against element b (when b + 1 is
        # on the cable) and b against element a (two or more places apart).
        o = (s[b] - s[a] > reach[a] - tol) & _within(p[a], p[b], lim_self[a])
        fi.append(a[o])
        fj.append(b[o])
        e_ok = has_next[b]
        eb = np.minimum(b, n - 2)
        o = e_ok & (0.5 * (s[eb] + s[eb + 1]) - s[a] > reach[a] - tol) & _within(p[a], mid(eb), lim_self[a])
        sq.append(a[o])
        se.append(b[o])
        o = (k >= 2) & (s[b] - 0.5 * (s[a] + s[a + 1]) > reach[b] - tol) & _within(p[b], mid(a), lim_self[b])
        sq.append(b[o])
        se.append(a[o])
    # Far field: chunk pairs.
    ca, cb = ch.pairs(2.0 * float(rad.max()) + limit)
    ci, cj = np.zeros(0, np.int64), np.zeros(0, np.int64)
    if len(ca):
        same = ch.cable[ca] == ch.cable[cb]
        i, j = ch.expand(ca[~same], cb[~same])
        ok = _within(p[i], p[j], rad[i] + rad[j] + limit)
        ci, cj = np.minimum(i[ok], j[ok]), np.maximum(i[ok], j[ok])
        i, j = ch.expand(ca[same], cb[same])
        far = np.abs(i - j) > _NEAR
        i, j = i[far], j[far]
        ok = _within(p[i], p[j], lim_self[i])
        fi.append(np.minimum(i[ok], j[ok]))
        fj.append(np.maximum(i[ok], j[ok]))
        for q, e in ((i, j), (j, i)):
            ok = has_next[e] & _within(p[q], mid(np.minimum(e, n - 2)), lim_self[q])
            sq.append(q[ok])
            se.append(e[ok])
    if len(ci):
        d = row_norm(p[ci] - p[cj])
        v = d - rad[ci] - rad[cj]
        o = v < limit
        ci, cj = ci[o], cj[o]
        hits.add(PairType.CABLE_CABLE, cab[ci], cab[cj], v[o], p[ci], s[ci], s[cj])
    si, sj = np.concatenate(fi), np.concatenate(fj)
    if len(si):
        v = row_norm(p[si] - p[sj]) - 2 * rad[si]
        o = (v < limit) & ~(np.abs(s[si] - s[sj]) < reach[si])
        si, sj = si[o], sj[o]
        rec = ~self_pair_excluded(s[si], s[sj], rad[si], clearance)
        hits.add(PairType.SELF, cab[si], cab[si], v[o], p[si], s[si], s[sj], rec)
    q, e0 = np.concatenate(sq), np.concatenate(se)
    if len(q):
        m = mid(e0)
        sm = 0.5 * (s[e0] + s[e0 + 1])
        v = row_norm(p[q] - m) - 2 * rad[q]
        o = (v < limit) & ~(np.abs(s[q] - sm) < reach[q])
        q = q[o]
        rec = ~self_pair_excluded(s[q], sm[o], rad[q], clearance)
        hits.add(PairType.SELF, cab[q], cab[q], v[o], p[q], s[q], sm[o], rec)


def _cable_pairs_exact(dp: _Discrete, ch: _Chunks, clearance: float, hits: _Hits) -> None:
    """Element-element pairs (capsule chains), self and cable-cable.

    Element pairs are pruned by lower bounds on their distance before the
    exact segment-segment distance: the midpoints' distance minus the half
    lengths; along one cable also the chord between the pair's outer ends
    minus the arc length between them, plus the arc-length separation the
    self rule requires (closest points nearer along the cable are excluded).
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
        tol = _SLACK * (np.abs(s[f + 1]) + reach[e] + lim_self[e])
        bound = lim_self[e] + arc - reach[e] + tol
        return ((arc > reach[e] - tol) & (bound > 0) & _within(mid[e], mid[f], lim)
                & _within(p[e], p[f + 1], np.maximum(bound, 0.0)))

    ea, eb = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
    pt = np.ascontiguousarray(p.T)
    for k in range(1, min(_NEAR, n - 2) + 1):
        # Elements e and e + k: the cheap arc-length test and the chord bound
        # on whole slices, the rest on the few survivors.
        m = n - k - 1
        arc = s[k + 1:] - s[:m]
        tol = _SLACK * (np.abs(s[k + 1:]) + reach[:m] + lim_self[:m])
        bound = lim_self[:m] + arc - reach[:m] + tol
        ok = (cab[:m] == cab[k + 1:]) & (arc > reach[:m] - tol) & (bound > 0)
        if not ok.any():
            continue
        e = np.nonzero(ok & _within_t(pt[:, :m], pt[:, k + 1:], np.maximum(bound, 0.0)))[0]
        e = e[self_ok(e, e + k)]
        ea.append(e)
        eb.append(e + k)
    ca, cb = ch.pairs(2.0 * float(rad.max()) + clearance)
    if len(ca):
        same = ch.cable[ca] == ch.cable[cb]
        i, j = ch.expand(ca[~same], cb[~same])
        ok = _within(mid[i], mid[j], rad[i] + rad[j] + clearance + half[i] + half[j])
        ea.append(np.minimum(i[ok], j[ok]))
        eb.append(np.maximum(i[ok], j[ok]))
        i, j = ch.expand(ca[same], cb[same])
        i, j = np.minimum(i, j), np.maximum(i, j)
        o = j - i > _NEAR
        i, j = i[o], j[o]
        o = self_ok(i, j)
        ea.append(i[o])
        eb.append(j[o])
    ia, ib = np.concatenate(ea), np.concatenate(eb)
    if len(ia) == 0:
        return
    d, ta, tb, ca_, _ = segment_segment(p[ia], p[ia + 1], p[ib], p[ib + 1])
    sa = s[ia] + ta * (s[ia + 1] - s[ia])
    sb = s[ib] + tb * (s[ib + 1] - s[ib])
    same = cab[ia] == cab[ib]
    o = ~same
    hits.add(PairType.CABLE_CABLE, cab[ia[o]], cab[ib[o]], d[o] - rad[ia[o]] - rad[ib[o]], ca_[o], sa[o], sb[o])
    o = same & ~self_pair_excluded(sa, sb, rad[ia], clearance)
    hits.add(PairType.SELF, cab[ia[o]], cab[ia[o]], d[o] - 2 * rad[ia[o]], ca_[o], sa[o], sb[o])


# ---------------------------------------------------------------------------
# Cables against parts


class _PartTable:
    """Parts as arrays: what does not change between calls (shapes, bounds,
    keep-out flags) is built once; :meth:`posed` adds rotations and
    translations for one call."""

    def __init__(self, parts: Sequence[PartState]):
        k = len(parts)
        self.parts = parts
        self.names = [pt.name for pt in parts]
        self.size = np.zeros((k, 3))
        for n, pt in enumerate(parts):
            sz = pt.shape.size[:3]
            self.size[n, : len(sz)] = sz
        self.type = np.array([_TYPE_CODE[pt.shape.type] for pt in parts], dtype=np.int64).reshape(k)
        # Shape.local_bounds for all parts at once (the same arithmetic).
        sz, t = self.size, self.type
        half = sz.copy()
        half[t == _TYPE_CODE[ShapeType.SPHERE]] = sz[t == _TYPE_CODE[ShapeType.SPHERE], :1]
        for st, extra in ((ShapeType.CYLINDER, False), (ShapeType.CAPSULE, True)):
            o = t == _TYPE_CODE[st]
            half[o, 1] = sz[o, 0]
            half[o, 2] = sz[o, 1] + sz[o, 0] if extra else sz[o, 1]
        self.lo, self.hi = -half, half.copy()
        o = t == _TYPE_CODE[ShapeType.PLANE]
        self.lo[o] = -np.inf
        self.hi[o] = [np.inf, np.inf, 0.0]
        for n in np.nonzero(t == _TYPE_CODE[ShapeType.MESH])[0]:
            self.lo[n], self.hi[n] = parts[n].shape.local_bounds()
        self.keepout = np.array([pt.keepout for pt in parts], dtype=bool)
        # Parts sharing one mesh are answered in one call: group id per part.
        groups: dict[int, int] = {}
        self.mesh_group = np.array([groups.setdefault(id(pt.shape.mesh), len(groups)) if pt.shape.mesh is not None
                                    else -1 for pt in parts], dtype=np.int64).reshape(k)
        self.mesh_shapes = [None] * len(groups)
        for pt in parts:
            if pt.shape.mesh is not None:
                self.mesh_shapes[groups[id(pt.shape.mesh)]] = pt.shape
        self.is_plane = self.type == _TYPE_CODE[ShapeType.PLANE]
        # Bounding spheres of the finite parts, in their own frames.
        self.finite = np.nonzero(~self.is_plane)[0]
        self.planes = np.nonzero(self.is_plane)[0]
        fin = self.finite
        self.c_loc = 0.5 * (self.lo[fin] + self.hi[fin])
        self.half_diag = 0.5 * row_norm(self.hi[fin] - self.lo[fin])
        self.rot = np.array([pt.pose[:3, :3] for pt in parts]).reshape(k, 3, 3)
        self.trans = np.array([pt.pose[:3, 3] for pt in parts]).reshape(k, 3)

    def posed(self, poses: np.ndarray | None) -> "_PartTable":
        """This table with poses (K, 4, 4) (None: the parts' own poses)."""
        if poses is None:
            return self
        out = copy.copy(self)
        out.rot = np.ascontiguousarray(poses[:, :3, :3])
        out.trans = np.ascontiguousarray(poses[:, :3, 3])
        return out

    def to_local(self, k: np.ndarray, x: np.ndarray) -> np.ndarray:
        """World points x (n, 3) into the frames of parts k (n,)."""
        return np.einsum("ni,nij->nj", x - self.trans[k], self.rot[k])


def _part_candidates(tab: _PartTable, ch: _Chunks, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """(item, part) pairs where the item may lie within ``margin`` of the part.

    Each finite part's bounding sphere, grown by ``margin``, is met with the
    super chunks' spheres through their tree, then with their chunks'
    spheres; the items of every chunk met are candidates. Planes take every item.
    Returns item indices (into the points) and part indices, both (n,).
    """
    items, parts = [], []
    fin = tab.finite
    if len(fin) and len(ch.radius):
        c_world = np.einsum("nij,nj->ni", tab.rot[fin], tab.c_loc) + tab.trans[fin]
        rad = tab.half_diag + margin
        lists = ch.tree.query_ball_point(c_world, (rad + float(ch.sup_radius.max())) * (1 + _SLACK),
                                         return_sorted=False)
        cnt = np.fromiter((len(x) for x in lists), dtype=np.int64, count=len(fin))
        sup = np.fromiter((i for x in lists for i in x), dtype=np.int64, count=int(cnt.sum()))
        c = ch.sub[sup].ravel()
        k = np.repeat(np.arange(len(fin)), 2 * cnt)
        ok = c >= 0
        c, k = c[ok], k[ok]
        ok = _within(ch.centre[c], c_world[k], rad[k] + ch.radius[c])
        c, k = c[ok], k[ok]
        it = ch.idx[c].ravel()
        pk = np.repeat(fin[k], _CHUNK)
        ok = it >= 0
        items.append(it[ok])
        parts.append(pk[ok])
    if len(tab.planes):
        every = ch.idx[ch.idx >= 0]
        items.append(np.tile(every, len(tab.planes)))
        parts.append(np.repeat(tab.planes, len(every)))
    if not items:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(items), np.concatenate(parts)


def _excluded(cable: np.ndarray, part: np.ndarray, s: np.ndarray, excl: tuple) -> np.ndarray:
    """True where (cable, part, material coordinate s) falls in an exclusion window."""
    key_e, smin, smax, n_parts = excl
    out = np.zeros(len(s), dtype=bool)
    if len(key_e) == 0 or len(s) == 0:
        return out
    key = cable * n_parts + part
    lo = np.searchsorted(key_e, key, side="left")
    hi = np.searchsorted(key_e, key, side="right")
    cnt = hi - lo
    if cnt.sum() == 0:
        return out
    rows = np.repeat(np.arange(len(s)), cnt)
    first = np.cumsum(cnt) - cnt
    w = lo[rows] + np.arange(len(rows)) - first[rows]
    inside = (s[rows] >= smin[w]) & (s[rows] <= smax[w])
    return np.bincount(rows, weights=inside, minlength=len(s)) > 0


def _point_distances(tab: _PartTable, pk: np.ndarray, loc: np.ndarray, face_plane: bool,
                     limit: np.ndarray | None = None, group: np.ndarray | None = None) -> np.ndarray:
    """Signed distance (n,) of local points ``loc`` to parts ``pk``, batched by type.

    With ``limit`` (n,): a mesh may answer a point that provably lies beyond
    its limit with a lower bound above it instead (see
    :func:`checker.shapes.signed_distance`); callers keep only values below.
    With ``group`` (n,) ids too (each group against one part), the caller
    wants only each group's least value exact: a mesh point whose lower
    bound exceeds another point's upper bound in its group may likewise be
    answered by a bound, above the group's least value."""
    d = np.full(len(pk), np.inf)
    types = list(ShapeType)
    for code in np.unique(tab.type[pk]):
        stype = types[code]
        sel = np.nonzero(tab.type[pk] == code)[0]
        if stype is ShapeType.MESH:
            grp = tab.mesh_group[pk[sel]]
            for g in np.unique(grp):
                sk = sel[grp == g]
                shape = tab.mesh_shapes[g]
                lim = None if limit is None else limit[sk]
                if lim is not None and group is not None and not face_plane:
                    # each group's most promising point (least upper bound)
                    # exactly first: the others then need be exact only below it
                    _, hi = distance_bounds(shape, loc[sk])
                    ids, inv = np.unique(group[sk], return_inverse=True)
                    o = np.lexsort((hi, inv))
                    lead = o[np.r_[True, inv[o][1:] != inv[o][:-1]]]
                    lead = lead[hi[lead] < lim[lead]]
                    d[sk[lead]] = signed_distance(shape, loc[sk[lead]])[0]
                    least = np.full(len(ids), np.inf)
                    least[inv[lead]] = d[sk[lead]]
                    lim = np.minimum(lim, least[inv])
                    rest = np.ones(len(sk), bool)
                    rest[lead] = False
                    sk, lim = sk[rest], lim[rest]
                d[sk] = face_plane_distance(shape, loc[sk]) if face_plane else signed_distance(shape, loc[sk], lim)[0]
        elif face_plane:
            d[sel] = face_plane_distance_batch(stype, tab.size[pk[sel]], loc[sel])
        else:
            d[sel] = signed_distance_value_batch(stype, tab.size[pk[sel]], loc[sel])
    return d


def _structure_points(dp, ch, tab, config, excl, hits, limit=None, excl_near=None) -> None:
    """Signed distance of every candidate point to its part, minus r.

    With ``limit`` (>= clearance), candidates up to ``limit``; with
    ``excl_near`` (narrower windows), points inside ``excl`` but outside
    ``excl_near`` are kept too: both only bound the gaps, never records."""
    limit = config.clearance if limit is None else limit
    margin = float(dp.radius.max()) + limit
    it, pk = _part_candidates(tab, ch, margin)
    if len(it) == 0:
        return
    loc = tab.to_local(pk, dp.p[it])
    thr = (dp.radius[it] + limit)[:, None]
    box_ok = np.all((loc >= tab.lo[pk] - thr) & (loc <= tab.hi[pk] + thr), axis=1)
    box_ok &= ~_excluded(dp.cable[it], pk, dp.m[it], excl if excl_near is None else excl_near)
    it, pk, loc = it[box_ok], pk[box_ok], loc[box_ok]
    rec = None if excl_near is None else ~_excluded(dp.cable[it], pk, dp.m[it], excl)
    d = _point_distances(tab, pk, loc, config.face_plane, dp.radius[it] + limit)
    v = d - dp.radius[it]
    o = v < limit
    it, pk, v = it[o], pk[o], v[o]
    rec = None if rec is None else rec[o]
    _add_structure(hits, tab, dp.cable[it], pk, v, dp.p[it], dp.s[it], rec)


def _structure_exact(dp, ch, tab, config, excl, hits) -> None:
    """Least signed distance along every candidate element to its part, minus r."""
    p, s, seg = dp.p, dp.s, dp.seg
    if len(seg) == 0:
        return
    # Chunk spheres hold whole elements: the margin needs no half length.
    margin = float(dp.radius.max()) + config.clearance
    i0, pk = _part_candidates(tab, ch, margin)
    it = i0
    if len(it) == 0:
        return
    a = tab.to_local(pk, p[i0])
    b = tab.to_local(pk, p[i0 + 1])
    thr = (dp.radius[i0] + config.clearance)[:, None]
    box_ok = np.all((np.maximum(a, b) >= tab.lo[pk] - thr) & (np.minimum(a, b) <= tab.hi[pk] + thr), axis=1)
    # Cuts were inserted at the window ends, so an element is in a window
    # exactly when its midpoint is.
    box_ok &= ~_excluded(dp.cable[i0], pk, 0.5 * (dp.m[i0] + dp.m[i0 + 1]), excl)
    it, pk, i0, a, b = it[box_ok], pk[box_ok], i0[box_ok], a[box_ok], b[box_ok]
    # Signed distance is 1-Lipschitz: the midpoint's distance minus the half
    # length bounds the segment's from below, so far segments skip the search.
    half = 0.5 * row_norm(b - a)
    mid = _point_distances(tab, pk, 0.5 * (a + b), False, config.clearance + half + dp.radius[i0])
    near = mid - half - dp.radius[i0] < config.clearance
    it, pk, i0, a, b = it[near], pk[near], i0[near], a[near], b[near]
    d = np.full(len(it), np.inf)
    t = np.zeros(len(it))
    is_mesh = tab.type[pk] == _TYPE_CODE[ShapeType.MESH]
    sel = np.nonzero(is_mesh)[0]
    grp = tab.mesh_group[pk[sel]]
    for g in np.unique(grp):
        sk = sel[grp == g]
        d[sk], t[sk] = segment_signed_distance(tab.mesh_shapes[g], a[sk], b[sk])
    # All primitives in one call (box and cylinder share one line search).
    sel = np.nonzero(~is_mesh)[0]
    if len(sel):
        d[sel], t[sel] = segment_signed_distance_mixed(
            tab.type[pk[sel]], tab.size[pk[sel]], a[sel], b[sel])
    where = p[i0] + t[:, None] * (p[i0 + 1] - p[i0])
    s_at = s[i0] + t * (s[i0 + 1] - s[i0])
    _add_structure(hits, tab, dp.cable[i0], pk, d - dp.radius[i0], where, s_at)


def _add_structure(hits, tab, cable, part, value, where, s, record=None) -> None:
    ko = tab.keepout[part]
    for kind, o in ((PairType.CABLE_STRUCTURE, ~ko), (PairType.KEEPOUT, ko)):
        hits.add(kind, cable[o], part[o], value[o], where[o], s[o], None, None if record is None else record[o])


# ---------------------------------------------------------------------------
# Single-cable checks


def _single_cable(cables: Sequence[CableState], clearance: float, hits: _Hits) -> None:
    """Bend radius below the limit and stretch beyond 1 %, per cable."""
    for c, cab in enumerate(cables):
        s = None
        if cab.min_bend_radius is not None:
            r = bend_radius(cab.points)
            k = int(np.argmin(r))
            if np.isfinite(r[k]):
                s = arc_length(cab.points)
                hits.add(PairType.BEND, np.array([c]), np.array([c]), np.array([r[k] - cab.min_bend_radius]),
                         cab.points[k][None], np.array([s[k]]))
        if cab.rest_length is not None:
            s = arc_length(cab.points) if s is None else s
            value = taut_margin(s[-1], cab.rest_length)
            # Taut is a stretch beyond 1 %, hard only: a length clearance has no
            # meaning for a stretch (a 0.3 m cable's whole 1 % is 3 mm).
            if value >= 0.0:
                continue
            hits.add(PairType.TAUT, np.array([c]), np.array([c]), np.array([value]), cab.points[-1][None],
                     np.array([s[-1]]))


@dataclass(frozen=True)
class DenseStates:
    """The discrete points of S states at once (:meth:`Checker.densify_many`).

    Attributes:
        p, s: (M, 3) points and (M,) their arc lengths.
        poly: (M,) polyline: state * cables + cable.
        src, own: (M,) the body centre (counted over all states) each point
            starts from, and whether it is that centre itself.
        m: (M,) material coordinate of each point (exclusion windows).
        states, centres, cables: S, body centres per state, cables.
    """

    p: np.ndarray
    s: np.ndarray
    m: np.ndarray
    poly: np.ndarray
    src: np.ndarray
    own: np.ndarray
    states: int
    centres: int
    cables: int


def single_records_many(names: Sequence[str], pts: np.ndarray, offsets: np.ndarray,
                        radius_at: np.ndarray, rest_length: np.ndarray, bend_limit: np.ndarray,
                        clearance: float) -> list[list[Interference]]:
    """The full check's bend and taut records for many states at once, to the bit.

    Args:
        names: the cables' names (C,).
        pts: (S, N, 3) every state's body centres, cables concatenated.
        offsets: (C + 1,) start of each cable in a state's centres.
        radius_at: (S, N) the bend radius at every centre (:func:`bend_radius`'s
            bits, as :meth:`CableMeasures.many` gives them).
        rest_length: (C,) rest lengths.
        bend_limit: (C,) smallest allowed bend radius, nan for none.
    """
    n_s, n = pts.shape[:2]
    out: list[list[Interference]] = [[] for _ in range(n_s)]
    n_c = len(names)
    if n_s == 0 or n_c == 0:
        return out
    tiled = tile_offsets(offsets, n_s)
    starts, ends = tiled[:-1], tiled[1:] - 1
    flat = pts.reshape(-1, 3)
    s = polyline_arc_lengths(row_norm(np.diff(flat, axis=0)), tiled)
    cab = np.tile(np.arange(n_c), n_s)
    state = np.repeat(np.arange(n_s), n_c)
    # bend: the first place of the least radius per (state, cable), when finite
    r = radius_at.ravel()
    least = np.minimum.reduceat(r, starts)
    counts = ends - starts + 1
    at = np.flatnonzero(r == np.repeat(least, counts))
    poly = np.searchsorted(starts, at, side="right") - 1
    k = at[np.r_[True, poly[1:] != poly[:-1]]]
    bend = np.isfinite(least) & ~np.isnan(bend_limit[cab])
    value_b = least - bend_limit[cab]
    value_t = taut_margin(s[ends], rest_length[cab])
    rows = []
    for i in np.flatnonzero(bend & (value_b < clearance)):
        rows.append((state[i], PairType.BEND, cab[i], float(value_b[i]), flat[k[i]], float(s[k[i]])))
    for i in np.flatnonzero(value_t < 0.0):
        rows.append((state[i], PairType.TAUT, cab[i], float(value_t[i]), flat[ends[i]], float(s[ends[i]])))
    for st_i, kind, c, d, where, s_i in rows:
        out[st_i].append(Interference(type=kind, a=names[c], b=names[c], min_distance=d,
                                      severity=severity_of(d, clearance), where=where, s=s_i, s_b=None))
    for recs in out:
        recs.sort(key=lambda r: (r.min_distance, _TYPE_ORDER.index(r.type), r.a, r.b))
    return out


# ---------------------------------------------------------------------------


class Checker:
    """A reusable checker for one set of parts: :func:`check_state` step after step.

    What depends only on the parts (their shapes, bounds, keep-out flags,
    mesh grouping) is prepared once; each :meth:`check` takes the cables and
    the parts' poses of one instant. ``Checker(parts, config).check(cables,
    None, exclusions)`` is exactly ``check_state(cables, parts, config,
    exclusions)``.

    Args:
        parts: the parts (names, shapes, keep-out flags; their poses are the
            default for :meth:`check`).
        config: method, spacing, clearance.
        horizon: with method ``points`` (not face-plane), candidates are also
            evaluated up to ``clearance + horizon`` (and self pairs and
            attachment windows up to ``stretch`` of arc length inside their
            exclusion), only to leave in :attr:`gaps` how far every pair
            stays from the clearance; the records do not change (severity
            and the exclusion windows stay tied to the clearance). See
            :mod:`checker.advance` for the use.
        stretch: see ``horizon``.

    Attributes:
        gaps: after a :meth:`check` with a horizon, (cable, parts): the least
            value minus the clearance over self and cable-cable candidates,
            and per part (K,) over cable-structure and keep-out candidates,
            each at most ``horizon``; None when not available (method
            ``exact``, face-plane, or no horizon).
        part_candidates: with :attr:`gaps`, every cable-structure and
            keep-out candidate behind them: (cable, arc length s, part,
            value - clearance) arrays; a point not among them is at least
            ``horizon`` beyond the clearance from that part.
        cable_candidates: with :attr:`gaps`, every self and cable-cable
            candidate behind them: (cable a, s_a, cable b, s_b, value -
            clearance) arrays; a checked pair of places not among them is at
            least ``horizon`` beyond the clearance (or deep in its exclusion).
    """

    def __init__(self, parts: Sequence[PartState], config: CheckConfig = CheckConfig(),
                 horizon: float = 0.0, stretch: float = 0.0):
        self.parts = list(parts)
        self.config = config
        self._tab = _PartTable(self.parts) if self.parts else None
        self._pidx = {p.name: i for i, p in enumerate(self.parts)}
        self.horizon = float(horizon)
        self.stretch = float(stretch)
        self.gaps: tuple[float, np.ndarray] | None = None
        self.part_candidates: tuple[np.ndarray, ...] | None = None
        self.cable_candidates: tuple[np.ndarray, ...] | None = None
        self._excl_cache: tuple | None = None

    @property
    def bounds_gaps(self) -> bool:
        """True when :meth:`check` leaves :attr:`gaps` (points, not face-plane, horizon > 0)."""
        return self.config.method == "points" and not self.config.face_plane and self.horizon > 0.0

    def part_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """((K, 3), (K, 3)): each part's axis-aligned bounds in its own frame
        (a plane: lo -inf, hi (inf, inf, 0))."""
        if self._tab is None:
            return np.zeros((0, 3)), np.zeros((0, 3))
        return self._tab.lo.copy(), self._tab.hi.copy()

    def part_radius(self) -> np.ndarray:
        """(K,) largest distance of any point of each part from its frame's
        origin (inf for planes): a rotation by R moves it at most ||R - R0|| times this."""
        lo, hi = self.part_bounds()
        corner = np.maximum(np.abs(lo), np.abs(hi))
        return np.sqrt(np.einsum("ij,ij->i", corner, corner))

    def _exclusion_table(self, cable_names: Sequence[str], exclusions: Sequence[Exclusion]) -> tuple:
        """Exclusions as arrays: ((key, lo, hi, n_parts) sorted by key =
        cable * n_parts + part, cable, lo, hi) for these cables and parts."""
        # a run passes the same windows at every full check: built once per
        # (cables, windows) and kept (with the windows, so their id stays theirs)
        names = tuple(cable_names)
        cached = self._excl_cache
        if cached is not None and cached[0] is exclusions and cached[1] == names and cached[2] == len(exclusions):
            return cached[3]
        cidx = {n: i for i, n in enumerate(names)}
        pidx = self._pidx
        ex_c = np.array([cidx.get(e.cable, -1) for e in exclusions], dtype=np.int64)
        ex_p = np.array([pidx.get(e.part, -1) for e in exclusions], dtype=np.int64)
        s_min = np.array([e.s_min for e in exclusions], dtype=float)
        s_max = np.array([e.s_max for e in exclusions], dtype=float)
        mine = (ex_c >= 0) & (ex_p >= 0)
        ex_c, ex_p, s_min, s_max = ex_c[mine], ex_p[mine], s_min[mine], s_max[mine]
        ex_lo, ex_hi = np.minimum(s_min, s_max), np.maximum(s_min, s_max)
        n_parts = max(len(self.parts), 1)
        key = ex_c * n_parts + ex_p
        o = np.argsort(key, kind="stable")
        table = (key[o], ex_lo[o], ex_hi[o], n_parts), ex_c, ex_lo, ex_hi
        if isinstance(exclusions, (list, tuple)):
            self._excl_cache = (exclusions, names, len(exclusions), table)
        return table

    def densify_many(self, pts: np.ndarray, offsets: np.ndarray, radii: np.ndarray,
                     rest: np.ndarray | None = None) -> DenseStates:
        """The discrete points of S states (S, N, 3) at once, each cable of
        each state a polyline of its own (the bits of :meth:`check`'s own
        discretisation of each state), for :meth:`structure_many` and
        :meth:`cable_pairs_many`. ``rest``: (N,) the centres' material
        coordinates (:attr:`CableState.rest_s` of every cable, concatenated),
        or None (the current arc lengths)."""
        n_s, n = pts.shape[:2]
        radii = np.asarray(radii, float)
        p, s, poly, _, src, own, frac = densify_batch(pts.reshape(-1, 3), tile_offsets(offsets, n_s),
                                                      np.tile(self.config.spacing * radii, n_s), source=True)
        if rest is None:
            m = s
        else:
            m = material_coordinates(s, src, frac, np.ones(len(s), bool), np.tile(np.asarray(rest, float), n_s))
        return DenseStates(p, s, m, poly, src, own, n_s, n, len(radii))

    def structure_many(self, names: Sequence[str], radii: np.ndarray, dense: DenseStates,
                       poses: np.ndarray, exclusions: Sequence[Exclusion],
                       active: tuple[np.ndarray, np.ndarray]) -> list[list[Interference]]:
        """The full check's cable-structure and keep-out records at many
        states at once, from the discrete points next to given body centres
        (method ``points``; to the bit).

        Against part k only the points on elements next to an active
        (centre, k) entry are evaluated: the centre itself and the points
        inside its two elements. A record is the worst of those places (the
        caller knows the others to be clear).

        Args:
            names, radii: the cables' names and radii (C,).
            dense: the states' discrete points (:meth:`densify_many`).
            poses: (S, K, 4, 4) the parts' poses at every state.
            exclusions: as for :meth:`check`.
            active: (centre index in a state, part index) arrays.

        Returns:
            per state, its records (worst first).
        """
        config = self.config
        n_s, n, n_c, n_k = dense.states, dense.centres, dense.cables, len(self.parts)
        out: list[list[Interference]] = [[] for _ in range(n_s)]
        ci, pi = (np.asarray(x, np.int64) for x in active)
        if n_s == 0 or len(ci) == 0 or self._tab is None:
            return out
        radii = np.asarray(radii, float)
        p, s, src, own = dense.p, dense.s, dense.src, dense.own
        state, cab = dense.poly // n_c, dense.poly % n_c
        # each point against the parts it is active for: its own centre's, or
        # (inside an element) either end's
        parts, row = np.unique(pi, return_inverse=True)
        mark = np.zeros((len(parts), n + 1), bool)
        mark[row, ci] = True
        centre = src % n
        need = mark[:, centre] | (~own & mark[:, centre + 1])
        kk, it = np.nonzero(need)
        k = parts[kk]
        q = state[it] * n_k + k
        rot = np.ascontiguousarray(poses[:, :, :3, :3]).reshape(-1, 3, 3)
        trans = np.ascontiguousarray(poses[:, :, :3, 3]).reshape(-1, 3)
        tab = self._tab
        loc = np.einsum("ni,nij->nj", p[it] - trans[q], rot[q])      # _PartTable.to_local's arithmetic
        rad = radii[cab[it]]
        thr = (rad + config.clearance)[:, None]
        keep = np.all((loc >= tab.lo[k] - thr) & (loc <= tab.hi[k] + thr), axis=1)
        excl = self._exclusion_table(names, exclusions)[0]
        keep &= ~_excluded(cab[it], k, dense.m[it], excl)
        it, k, loc, rad = it[keep], k[keep], loc[keep], rad[keep]
        # only the worst place per (state, cable, part) becomes a record
        group = (state[it] * n_c + cab[it]) * n_k + k
        v = _point_distances(tab, k, loc, config.face_plane, rad + config.clearance, group) - rad
        keep = v < config.clearance
        it, k, v = it[keep], k[keep], v[keep]
        if len(v) == 0:
            return out
        # the worst place per (state, cable, part); ties to the smallest arc length
        o = np.lexsort((s[it], v, k, cab[it], state[it]))
        it, k, v = it[o], k[o], v[o]
        head = np.r_[True, (state[it][1:] != state[it][:-1]) | (cab[it][1:] != cab[it][:-1]) | (k[1:] != k[:-1])]
        it, k = it[head], k[head]
        rows = zip(state[it].tolist(), cab[it].tolist(), k.tolist(), v[head].tolist(), s[it].tolist(), p[it])
        for st_i, c, part, d, s_i, where in rows:
            kind = PairType.KEEPOUT if tab.keepout[part] else PairType.CABLE_STRUCTURE
            out[st_i].append(Interference(type=kind, a=names[c], b=self.parts[part].name, min_distance=d,
                                          severity=severity_of(d, config.clearance), where=where,
                                          s=s_i, s_b=None))
        for recs in out:
            recs.sort(key=lambda r: (r.min_distance, _TYPE_ORDER.index(r.type), r.a, r.b))
        return out

    def cable_pairs_many(self, names: Sequence[str], radii: np.ndarray, dense: DenseStates,
                         active: tuple[np.ndarray, np.ndarray]) -> list[list[Interference]]:
        """The full check's self and cable-cable records at many states at
        once, from the discrete places next to given pairs of body centres
        (method ``points``; to the bit).

        For each active pair of centres (i, j) every discrete point next to
        i (i itself, the points inside its two elements) is paired with
        every one next to j, and on one cable also with the midpoint of
        every piece next to j (and the other way round); a record is the
        worst of those (the caller knows the others to be clear). Every
        state must split each element into as many pieces as the first.

        Args:
            names, radii: the cables' names and radii (C,).
            dense: the states' discrete points (:meth:`densify_many`).
            active: (centre i, centre j) arrays.

        Returns:
            per state, its records (worst first).
        """
        config = self.config
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
        # one state's layout: the points next to each centre (its own point,
        # the points inside its two elements) and the pieces inside them
        c0, own0 = src[:m], own[:m]
        piece0 = np.r_[poly[1:m] == poly[:m - 1], False]
        pt_c = np.concatenate([c0[own0], c0[~own0], c0[~own0] + 1])           # centre each point is next to
        pt_i = np.concatenate([np.flatnonzero(own0), np.flatnonzero(~own0), np.flatnonzero(~own0)])
        pc_c = np.concatenate([c0[piece0], c0[piece0] + 1])                  # centre each piece is next to
        pc_i = np.concatenate([np.flatnonzero(piece0)] * 2)

        def around(centres, of_c, of_i):
            """(which entry, item index) for the items next to each centre."""
            o = np.argsort(of_c, kind="stable")
            of_c, of_i = of_c[o], of_i[o]
            lo = np.searchsorted(of_c, centres, "left")
            cnt = np.searchsorted(of_c, centres, "right") - lo
            entry = np.repeat(np.arange(len(centres)), cnt)
            return entry, of_i[ranges(lo, cnt)]

        def product(ea, xa, eb, xb):
            """Every (x, y) with x from side a and y from side b of one entry."""
            oa, ob = np.argsort(ea, kind="stable"), np.argsort(eb, kind="stable")
            ea, xa, eb, xb = ea[oa], xa[oa], eb[ob], xb[ob]
            na = np.bincount(ea, minlength=len(ci))
            nb = np.bincount(eb, minlength=len(ci))
            fa, fb = np.cumsum(na) - na, np.cumsum(nb) - nb
            per = na * nb
            e = np.repeat(np.arange(len(ci)), per)
            r = within(per)
            return xa[fa[e] + r // np.maximum(nb[e], 1)], xb[fb[e] + r % np.maximum(nb[e], 1)]

        def tiled(x, y):
            """Unique (x, y) of one state, for every state."""
            key = np.unique(x * m + y)
            off = (m * np.arange(n_s))[:, None]
            return ((key // m)[None] + off).ravel(), ((key % m)[None] + off).ravel()

        ia, xa = around(ci, pt_c, pt_i)
        ib, xb = around(cj, pt_c, pt_i)
        x, y = product(ia, xa, ib, xb)
        lo, hi = tiled(np.minimum(x, y), np.maximum(x, y))
        keep = lo != hi
        lo, hi = lo[keep], hi[keep]
        clear = config.clearance
        same = cab[lo] == cab[hi]
        # cable-cable: the lower index is cable a (the full check's order)
        d = row_norm(p[lo] - p[hi]) - rad[lo] - rad[hi]
        o = ~same & (d < clear)
        rows = [(PairType.CABLE_CABLE, lo[o], hi[o], d[o], s[hi[o]])]
        # self, point against point
        d = row_norm(p[lo] - p[hi]) - 2 * rad[lo]
        o = same & (d < clear) & ~self_pair_excluded(s[lo], s[hi], rad[lo], clear)
        rows.append((PairType.SELF, lo[o], lo[o], d[o], s[hi[o]]))
        # self, a point against the midpoint of a piece not touching it
        pa, qa = around(ci, pc_c, pc_i)
        pb, qb = around(cj, pc_c, pc_i)
        q1, e1 = product(ia, xa, pb, qb)
        q2, e2 = product(ib, xb, pa, qa)
        q, e = tiled(np.r_[q1, q2], np.r_[e1, e2])
        keep = (cab[q] == cab[e]) & (q != e) & (q != e + 1)
        q, e = q[keep], e[keep]
        mid = 0.5 * (p[e] + p[e + 1])
        sm = 0.5 * (s[e] + s[e + 1])
        d = row_norm(p[q] - mid) - 2 * rad[q]
        o = (d < clear) & ~self_pair_excluded(s[q], sm, rad[q], clear)
        rows.append((PairType.SELF, q[o], q[o], d[o], sm[o]))
        t = np.concatenate([np.full(len(r[1]), _TYPE_ORDER.index(r[0])) for r in rows])
        w, wb, v, sb = (np.concatenate([r[k] for r in rows]) for k in (1, 2, 3, 4))
        if len(v) == 0:
            return out
        st, a, b, sa = w // m, cab[w], cab[wb], s[w]
        # the worst per (state, type, a, b); ties to the smallest arc lengths (_Hits.reduce)
        o = np.lexsort((sb, sa, v, b, a, t, st))
        head = np.r_[True, (st[o][1:] != st[o][:-1]) | (t[o][1:] != t[o][:-1]) | (a[o][1:] != a[o][:-1])
                     | (b[o][1:] != b[o][:-1])]
        o = o[head]
        for st_i, t_i, a_i, b_i, d_i, s_i, sb_i, where in zip(st[o].tolist(), t[o].tolist(), a[o].tolist(),
                                                             b[o].tolist(), v[o].tolist(), sa[o].tolist(),
                                                             sb[o].tolist(), p[w[o]]):
            out[st_i].append(Interference(type=_TYPE_ORDER[t_i], a=names[a_i], b=names[b_i], min_distance=d_i,
                                          severity=severity_of(d_i, clear), where=where, s=s_i, s_b=sb_i))
        for recs in out:
            recs.sort(key=lambda r: (r.min_distance, _TYPE_ORDER.index(r.type), r.a, r.b))
        return out

    def check(
        self,
        cables: Sequence[CableState],
        poses: np.ndarray | Sequence[np.ndarray] | None = None,
        exclusions: Sequence[Exclusion] = (),
        horizon: float | None = None,
    ) -> list[Interference]:
        """Check one scene state; see :func:`check_state`.

        Args:
            cables: the cables' centrelines.
            poses: (K, 4, 4) part -> world transforms in the order of the
                parts, or None for the parts' own poses. Rotations must be
                orthonormal (as :class:`~checker.scene_state.PartState`
                requires).
            exclusions: arc-length windows where a cable may touch a part.
            horizon: this call's horizon instead of the checker's (0: no
                gaps, the plain check).
        """
        config = self.config
        horizon = self.horizon if horizon is None else float(horizon)
        bounds = self.bounds_gaps and horizon > 0.0
        parts = self.parts
        tab = None
        if self._tab is not None:
            if poses is not None:
                poses = np.asarray(poses, dtype=float).reshape(-1, 4, 4)
                if len(poses) != len(parts) or not np.all(np.isfinite(poses)):
                    raise ValueError(f"poses must be {len(parts)} finite 4x4 matrices")
                rot = poses[:, :3, :3]
                # np.allclose(R^T R, I, atol=1e-9) without its per-call overhead
                err = np.abs(np.einsum("kji,kjl->kil", rot, rot) - _EYE3)
                if not np.all(err <= 1e-9 + 1e-5 * _EYE3):
                    raise ValueError("a pose rotation is not orthonormal")
            tab = self._tab.posed(poses)
        hits = _Hits()
        cable_names = [c.name for c in cables]
        part_names = [p.name for p in parts]
        if len(set(cable_names)) != len(cable_names):
            raise ValueError("cable names must be unique")
        if cables:
            excl, ex_c, ex_lo, ex_hi = self._exclusion_table(cable_names, exclusions)
            exact = config.method == "exact"
            cuts = (np.concatenate([ex_c, ex_c]), np.concatenate([ex_lo, ex_hi])) if exact \
                else (np.zeros(0, np.int64), np.zeros(0))
            dp = _discretise(cables, config, cuts)
            has_next = np.concatenate([dp.cable[:-1] == dp.cable[1:], [False]])
            gaps = bounds
            limit = config.clearance + (horizon if gaps else 0.0)
            if exact:
                ch = _Chunks(dp.p, dp.s, dp.cable, has_next, dp.seg)
                _cable_pairs_exact(dp, ch, config.clearance, hits)
            else:
                ch = _Chunks(dp.p, dp.s, dp.cable, has_next, np.arange(len(dp.p)))
                _cable_pairs_points(dp, ch, config.clearance, hits, limit, self.stretch if gaps else 0.0)
            if tab is not None:
                if exact:
                    _structure_exact(dp, ch, tab, config, excl, hits)
                else:
                    # windows narrowed by the stretch: points that may enter
                    # or leave a window bound the gaps too
                    near = (excl[0], excl[1] + self.stretch, excl[2] - self.stretch, excl[3]) if gaps else None
                    _structure_points(dp, ch, tab, config, excl, hits, limit, near)
            _single_cable(cables, config.clearance, hits)
            self.gaps = hits.gaps(config.clearance, horizon, len(parts)) if gaps else None
            self.part_candidates = hits.part_candidates(config.clearance) if gaps else None
            self.cable_candidates = hits.cable_candidates(config.clearance) if gaps else None
        else:
            self.gaps = (horizon, np.full(len(parts), horizon)) if bounds else None
            self.part_candidates = self.cable_candidates = None

        def names(ptype: PairType) -> list[str]:
            return part_names if ptype in (PairType.CABLE_STRUCTURE, PairType.KEEPOUT) else cable_names

        out = hits.reduce(config.clearance, cable_names, names)
        out.sort(key=lambda r: (r.min_distance, _TYPE_ORDER.index(r.type), r.a, r.b))
        return out


def check_state(
    cables: Sequence[CableState],
    parts: Sequence[PartState],
    config: CheckConfig = CheckConfig(),
    exclusions: Sequence[Exclusion] = (),
) -> list[Interference]:
    """Check one scene state; one record per interfering (type, a, b) pair.

    A pair interferes when its signed ``min_distance`` (SPEC "Report") is
    below ``config.clearance``: hard below 0, soft from 0 up to the
    clearance. Records are sorted worst first. To check many states of the
    same parts, :class:`Checker` prepares the parts once.

    Args:
        cables: the cables' centrelines.
        parts: posed parts (keep-out parts give ``keepout`` records).
        config: method, spacing, clearance.
        exclusions: arc-length windows where a cable may touch a part.

    Returns:
        list of :class:`~checker.records.Interference`.
    """
    return Checker(parts, config).check(cables, None, exclusions)
