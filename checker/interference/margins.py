"""Closest approaches: how near each cable came to every part and other cable, clash or not.

A clear run must still say what margin it kept. :class:`MarginLog` measures,
at sampled states, every cable element against every part and every element
of another cable that lie within ``reach`` of each other, exactly (segment
distances less the cable radii, as method ``exact`` measures), and keeps each
pair's least distance with when and where. Around a pair's best sample in a
batch it measures that pair again at every state between the neighbouring
samples (the elements near its closest place at the sample, a few either
side), so the least distance is found at the states' resolution wherever the
distance has one minimum between two samples; a close pass that stays beyond
``reach`` at both samples around it is missed. Cost: the sampled states'
elements near the parts (a grid of element spheres, the samples side by
side), never the points times the parts at every state.

Elements inside an attachment window are left out against that window's part
(``excused`` lists them, :mod:`cablecheck.checker.interference.excused`).

Deliberately not here: which states are sampled (the caller's interval),
self pairs and part-part pairs (a run's pairs that came below the clearance
give those), events and severities.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cablecheck.checker.arrays import first_least, ranges
from cablecheck.checker.cellgrid import CellGrid
from cablecheck.checker.closest import segment_segment
from cablecheck.checker.interference.structure import (
    PartTable,
    point_distances,
    segment_distances,
    segments_within,
    to_local,
)
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import CheckConfig, Exclusion, PartState

_APPROACHES = frozenset({PairType.SELF, PairType.CABLE_CABLE, PairType.CABLE_STRUCTURE, PairType.KEEPOUT,
                         PairType.PART_PART})

NEIGHBOURS = 3
"""A pair measured between samples: the elements near its closest place at
its best sample and this many either side along the cable."""


@dataclass(frozen=True)
class Closest:
    """A pair's closest approach over a run.

    Attributes:
        type: cable-structure, keepout or cable-cable.
        a: the cable; b: the part or the other cable.
        min_distance: least surface distance (centreline distances less the
            radii; negative inside), metres.
        t: when (the first measured state at that distance), seconds.
        where: (3,) the place on cable ``a``'s centreline, world.
        s: its material coordinate (rest arc length) along ``a``.
        s_b: for a cable pair, the material coordinate along ``b``; else None.
    """

    type: PairType
    a: str
    b: str
    min_distance: float
    t: float
    where: np.ndarray
    s: float
    s_b: float | None = None


def point_row_distances(tab: PartTable, pk: np.ndarray, a: np.ndarray, b: np.ndarray,
                        step: np.ndarray, limit: np.ndarray,
                        group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least signed distance (n,) to parts ``pk`` over points at most
    ``step`` (n,) apart along each local segment ``a b`` (n, 3), ends
    included, and the parameter (n,) of that point. Only each ``group``'s
    (n,) least below ``limit`` (n,) is sure to be exact: a mesh may answer
    the other rows with bounds above it."""
    n = np.maximum(np.ceil(np.sqrt(np.einsum("ni,ni->n", b - a, b - a)) / step), 1).astype(np.int64)
    row = np.repeat(np.arange(len(pk)), n + 1)
    t = (np.arange(len(row)) - np.repeat(np.cumsum(n + 1) - (n + 1), n + 1)) / n[row]
    d = point_distances(tab, pk[row], a[row] + t[:, None] * (b[row] - a[row]), False, limit[row], group[row])
    best = first_least(np.zeros(len(row), np.int64), row, d, len(pk))
    return d[best], t[best]


class MarginLog:
    """Every pair's least distance within ``reach`` over the states it is given.

    Args:
        parts: the checked parts (shapes; poses come with each batch).
        cables: the cables' names, in the order of ``offsets``.
        offsets: (C + 1,) each cable's first body centre.
        rest: (N,) every body centre's material coordinate.
        radii: (C,) cable radii.
        exclusions: the attachment windows.
        reach: pairs farther apart than this are not kept, metres.
        config: the run's method and spacing: with method ``points`` an
            element is measured against a part at discrete points at most
            ``spacing`` radii apart (what the checks measure; a mesh costs
            a segment search a hundred times a point's), with ``exact``
            along its whole length.
    """

    def __init__(self, parts: Sequence[PartState], cables: Sequence[str], offsets: np.ndarray,
                 rest: np.ndarray, radii: np.ndarray, exclusions: Sequence[Exclusion], reach: float,
                 config: CheckConfig = CheckConfig()):
        self.reach = float(reach)
        self.config = config
        self.parts = [p.name for p in parts]
        self.cables = list(cables)
        self._keepout = np.array([bool(p.keepout) for p in parts], bool)
        self._tab = PartTable(list(parts)) if len(parts) else None
        offsets = np.asarray(offsets, np.int64)
        n = int(offsets[-1]) if len(offsets) else 0
        cable = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
        self._e0 = e0 = np.flatnonzero(cable[:-1] == cable[1:]) if n > 1 else np.zeros(0, np.int64)
        self._ec = cable[e0]                                 # each element's cable
        self._er = np.asarray(radii, float)[self._ec]        # ... and radius
        self._rest = np.asarray(rest, float)
        n_k = len(self.parts)
        # (element, part) pairs inside a window: left out (they are excused)
        index = {name: k for k, name in enumerate(self.parts)}
        cidx = {name: j for j, name in enumerate(self.cables)}
        mid = 0.5 * (self._rest[e0] + self._rest[e0 + 1]) if len(e0) else np.zeros(0)
        out = []
        for w in exclusions:        # a few windows, once per run
            if w.part in index and w.cable in cidx:
                e = np.flatnonzero((self._ec == cidx[w.cable]) & (mid >= min(w.s_min, w.s_max))
                                   & (mid <= max(w.s_min, w.s_max)))
                out.append(e * max(n_k, 1) + index[w.part])
        self._windows = np.unique(np.concatenate(out)) if out else np.zeros(0, np.int64)
        self._n_k = n_k
        self._n_c = len(self.cables)
        # each pair's best: sorted keys (cable * K + part, then C * K + cable a * C + cable b)
        self._key = np.zeros(0, np.int64)
        self._value = np.zeros(0)
        self._t = np.zeros(0)
        self._where = np.zeros((0, 3))
        self._s = np.zeros(0)
        self._s_b = np.zeros(0)

    def add(self, times: np.ndarray, pts: np.ndarray, poses: np.ndarray, samples: np.ndarray) -> None:
        """States at ``times`` (S,): body centres ``pts`` (S, N, 3), the
        parts' poses (S, K, 4, 4); ``samples``: the increasing indices of the
        states sampled."""
        samples = np.asarray(samples, np.int64)
        if len(samples) == 0 or len(self._e0) == 0:
            return
        times = np.asarray(times, float)
        rows = self._sampled(pts[samples], poses[samples])
        if rows is None or len(rows[1]) == 0:
            return
        sample, key, value, elem, other, param = rows
        # each pair's best sample in this batch, where it improves on the run's
        pick = first_least(np.zeros(len(key), np.int64), key, value, int(key.max()) + 1)
        old = self._lookup(key[pick])
        better = pick[value[pick] < old]
        if len(better) == 0:
            return
        # the pairs again at every state between the samples around their best
        bk, at = key[better], sample[better]                  # keys ascending
        lo = np.where(at > 0, samples[np.maximum(at - 1, 0)] + 1, 0)
        hi = np.where(at < len(samples) - 1, samples[np.minimum(at + 1, len(samples) - 1)], len(times))
        found = self._between(pts, poses, bk, lo, hi, bk, elem[better], other[better])
        state = np.concatenate([samples[at], found[0]])
        k2 = np.concatenate([bk, found[1]])
        v2 = np.concatenate([value[better], found[2]])
        e2 = np.concatenate([elem[better], found[3]])
        o2 = np.concatenate([other[better], found[4]])
        p2 = np.concatenate([param[better], found[5]])
        # the least over the states, the earliest on a tie
        o = np.lexsort((state, v2, k2))
        lead = o[np.r_[True, k2[o][1:] != k2[o][:-1]]]
        st, el = state[lead], e2[lead]
        self._store(k2[lead], v2[lead], times[st], pts[st, self._e0[el]], pts[st, self._e0[el] + 1],
                    el, o2[lead], p2[lead])

    def _sampled(self, pts: np.ndarray, poses: np.ndarray):
        """Every pair's rows within reach at the sampled states: (sample,
        key, value, element, other element or part, parameters (n, 2))."""
        n_s = len(pts)
        e0, er = self._e0, self._er
        a, b = pts[:, e0], pts[:, e0 + 1]                              # (S, E, 3)
        mid = 0.5 * (a + b)
        rad = 0.5 * np.sqrt(np.einsum("sei,sei->se", b - a, b - a)) + er   # element sphere
        # the samples side by side along x, so one grid serves them all
        tab = self._tab
        span = float(np.abs(mid).max() + rad.max())
        if tab is not None and len(tab.finite):
            fin = tab.finite
            placed = poses[:, fin]
            c_world = np.einsum("skij,kj->ski", placed[..., :3, :3], tab.c_loc) + placed[..., :3, 3]
            span = max(span, float(np.abs(c_world).max() + tab.half_diag.max()))
        shift = 4.0 * (span + self.reach) + 1.0
        off = (shift * np.arange(n_s))[:, None]
        x = mid.reshape(-1, 3).copy()
        x[:, 0] += np.repeat(off[:, 0], len(e0))
        r = rad.ravel()
        grid = CellGrid(x, 2.0 * float(r.max()) + self.reach)
        out = []
        n_e = len(e0)
        if tab is not None:
            qs, qk = [], []
            if len(tab.finite):
                cw = c_world.reshape(-1, 3).copy()
                cw[:, 0] += np.repeat(off[:, 0], len(fin))
                reach = np.tile(tab.half_diag, n_s) + self.reach + float(r.max())
                q, i = grid.near(cw, reach)
                ok = np.sqrt(np.einsum("ni,ni->n", x[i] - cw[q], x[i] - cw[q])) <= (
                    np.tile(tab.half_diag, n_s)[q] + self.reach + r[i]) * (1 + 1e-9) + 1e-12 * shift * n_s
                qs.append(i[ok])
                qk.append(fin[q[ok] % len(fin)])
            for k in tab.planes.tolist():       # a plane meets every element (a few planes a scene)
                qs.append(np.arange(n_s * n_e))
                qk.append(np.full(n_s * n_e, k))
            i, k = np.concatenate(qs), np.concatenate(qk)
            found = self._part_rows(i // n_e, i % n_e, k, pts, poses)
            if found is not None:
                out.append(found)
        if self._n_c > 1:
            i, j = grid.pairs(2.0 * float(r.max()) + self.reach)
            si = i // n_e
            ei, ej = i % n_e, j % n_e
            keep = ((si == j // n_e) & (self._ec[ei] != self._ec[ej])
                    & (np.sqrt(np.einsum("ni,ni->n", x[i] - x[j], x[i] - x[j])) <= (r[i] + r[j] + self.reach)
                       * (1 + 1e-9) + 1e-12 * shift * n_s))
            found = self._cable_rows(si[keep], ei[keep], ej[keep], pts)
            if found is not None:
                out.append(found)
        if not out:
            return None
        return tuple(np.concatenate(c) for c in zip(*out))

    def _part_rows(self, state, elem, part, pts, poses):
        """(state, element, part) rows within reach, measured; an element
        inside a window of its part is left out."""
        keep = ~np.isin(elem * max(self._n_k, 1) + part, self._windows)
        state, elem, part = state[keep], elem[keep], part[keep]
        if len(elem) == 0:
            return None
        tab = self._tab
        e0 = self._e0[elem]
        rot, trans = poses[state, part, :3, :3], poses[state, part, :3, 3]
        a = to_local(pts[state, e0], trans, rot)
        b = to_local(pts[state, e0 + 1], trans, rot)
        rad = self._er[elem]
        key = self._ec[elem] * self._n_k + part
        if self.config.method == "exact":
            idx, mid = segments_within(tab, part, a, b, rad, self.reach, midpoints=True)
            d, t = segment_distances(tab, part[idx], a[idx], b[idx], mid)
        else:
            thr = (rad + self.reach)[:, None]
            idx = np.flatnonzero(np.all((np.maximum(a, b) >= tab.lo[part] - thr)
                                        & (np.minimum(a, b) <= tab.hi[part] + thr), axis=1))
            # only each pair's least over these states, and only below the
            # run's best, need be exact: a mesh answers the rest by bounds
            # above it (an exact mesh query costs a hundred primitive ones)
            group = np.unique(key[idx], return_inverse=True)[1]
            limit = np.minimum(self.reach, self._lookup(key[idx])) + rad[idx]
            d, t = point_row_distances(tab, part[idx], a[idx], b[idx], self.config.spacing * rad[idx],
                                       limit, group)
        value = d - rad[idx]
        near = value < self.reach
        idx, value, t = idx[near], value[near], t[near]
        key = key[idx]
        return state[idx], key, value, elem[idx], part[idx], np.stack([t, np.zeros(len(t))], axis=1)

    def _cable_rows(self, state, ei, ej, pts, poses=None):
        """(state, element, element) rows of two cables within reach, measured;
        the lower cable first."""
        if len(ei) == 0:
            return None
        swap = self._ec[ei] > self._ec[ej]
        ei, ej = np.where(swap, ej, ei), np.where(swap, ei, ej)
        a0, b0 = self._e0[ei], self._e0[ej]
        d, u, v, _, _ = segment_segment(pts[state, a0], pts[state, a0 + 1], pts[state, b0], pts[state, b0 + 1])
        value = d - self._er[ei] - self._er[ej]
        near = value < self.reach
        ca, cb = self._ec[ei[near]], self._ec[ej[near]]
        key = self._n_c * self._n_k + ca * self._n_c + cb
        return state[near], key, value[near], ei[near], ej[near], np.stack([u[near], v[near]], axis=1)

    def _between(self, pts, poses, keys, lo, hi, row_key, row_elem, row_other):
        """Pairs ``keys`` (ascending) at every state lo[i] <= state < hi[i],
        on the elements near their closest places at their best sample
        (``row_*``: key, element and part or other element there)."""
        empty = (np.zeros(0, np.int64),) * 2 + (np.zeros(0),) + (np.zeros(0, np.int64),) * 2 + (np.zeros((0, 2)),)
        count = hi - lo
        if count.sum() == 0 or len(row_key) == 0:
            return empty
        n_e = len(self._e0)
        spread = np.arange(-NEIGHBOURS, NEIGHBOURS + 1)
        # each pair's elements near its closest places (same cable), and their partner
        ek = np.repeat(row_key, len(spread))
        ee = (row_elem[:, None] + spread).ravel()
        eo = np.repeat(row_other, len(spread))
        is_cable = ek >= self._n_c * self._n_k
        same = (ee >= 0) & (ee < n_e)
        same &= self._ec[np.clip(ee, 0, n_e - 1)] == self._ec[np.repeat(row_elem, len(spread))]
        ek, ee, eo, is_cable = ek[same], ee[same], eo[same], is_cable[same]
        # for cable pairs, spread the partner element too
        ck = np.repeat(ek[is_cable], len(spread))
        ce = np.repeat(ee[is_cable], len(spread))
        co = (eo[is_cable][:, None] + spread).ravel()
        ok = (co >= 0) & (co < n_e)
        ok &= self._ec[np.clip(co, 0, n_e - 1)] == self._ec[np.repeat(eo[is_cable], len(spread))]
        part_rows = np.unique(np.stack([ek[~is_cable], ee[~is_cable], eo[~is_cable]], axis=1), axis=0)
        cable_rows = np.unique(np.stack([ck[ok], ce[ok], co[ok]], axis=1), axis=0)
        out = []
        for rows, measure in ((part_rows, self._part_rows), (cable_rows, self._cable_rows)):
            if len(rows) == 0:
                continue
            which = np.searchsorted(keys, rows[:, 0])
            n = count[which]
            state = ranges(lo[which], n)
            r = np.repeat(np.arange(len(rows)), n)
            found = measure(state, rows[r, 1], rows[r, 2], pts, poses)
            if found is not None:
                out.append(found)
        if not out:
            return empty
        return tuple(np.concatenate(c) for c in zip(*out))

    def _lookup(self, keys: np.ndarray) -> np.ndarray:
        """The run's best so far for ``keys`` (inf where none)."""
        if not len(self._key):
            return np.full(len(keys), np.inf)
        at = np.minimum(np.searchsorted(self._key, keys), len(self._key) - 1)
        return np.where(self._key[at] == keys, self._value[at], np.inf)

    def _store(self, keys, value, t, a, b, elem, other, param) -> None:
        """Keep these pairs' least values where they improve on the run's
        (``a``, ``b``: the ends of each one's element on cable a)."""
        better = value < self._lookup(keys)
        keys, value, t, a, b = keys[better], value[better], t[better], a[better], b[better]
        elem, other, param = elem[better], other[better], param[better]
        if len(keys) == 0:
            return
        e0, rest = self._e0, self._rest
        where = a + param[:, :1] * (b - a)
        s = rest[e0[elem]] + param[:, 0] * (rest[e0[elem] + 1] - rest[e0[elem]])
        is_cable = keys >= self._n_c * self._n_k
        o = np.where(is_cable, other, 0)
        s_b = np.where(is_cable, rest[e0[o]] + param[:, 1] * (rest[e0[o] + 1] - rest[e0[o]]), np.nan)
        merged = np.union1d(self._key, keys)
        fresh = [np.full(len(merged), np.inf), np.zeros(len(merged)), np.zeros((len(merged), 3)),
                 np.zeros(len(merged)), np.full(len(merged), np.nan)]
        old = np.searchsorted(merged, self._key)
        new = np.searchsorted(merged, keys)
        for arr, prev, cur in zip(fresh, (self._value, self._t, self._where, self._s, self._s_b),
                                  (value, t, where, s, s_b)):
            arr[old] = prev
            arr[new] = cur
        self._key = merged
        self._value, self._t, self._where, self._s, self._s_b = fresh

    def closest(self) -> tuple[Closest, ...]:
        """Every pair that came within reach, nearest first."""
        n_k, n_c = self._n_k, self._n_c
        out = []
        for j in np.argsort(self._value, kind="stable").tolist():
            key = int(self._key[j])
            if key < n_c * n_k:
                c, k = divmod(key, n_k)
                kind = PairType.KEEPOUT if self._keepout[k] else PairType.CABLE_STRUCTURE
                b, s_b = self.parts[k], None
            else:
                c, cb = divmod(key - n_c * n_k, n_c)
                kind, b, s_b = PairType.CABLE_CABLE, self.cables[cb], float(self._s_b[j])
            out.append(Closest(kind, self.cables[c], b, float(self._value[j]), float(self._t[j]),
                               self._where[j].copy(), float(self._s[j]), s_b))
        return tuple(out)


def with_events(closest: Sequence[Closest], events: Sequence) -> tuple[Closest, ...]:
    """The pairs' closest approaches with the run's events: a pair that came
    below the clearance takes its worst event's distance, time and place
    where that is as near or nearer (the events measure every checked
    state, by the run's method; self and part-part pairs have only those),
    nearest first."""
    rows = {(c.type, c.a, c.b): c for c in closest}
    for e in events:
        k = (PairType(e.type), e.a, e.b)
        if k[0] not in _APPROACHES:
            continue            # bend and taut: no distance between two things
        c = rows.get(k)
        if c is None or e.min_distance <= c.min_distance:      # a tie: the event's place, as the events list it
            s_b = e.s_b if k[0] is PairType.CABLE_CABLE else None     # the other cable's place too
            rows[k] = Closest(k[0], e.a, e.b, float(e.min_distance), float(e.t_worst),
                              np.asarray(e.where, float), float(e.s), None if s_b is None else float(s_b))
    return tuple(sorted(rows.values(), key=lambda c: (c.min_distance, c.t, c.a, c.b)))


@dataclass(frozen=True)
class CableClosest:
    """A cable's closest approach to anything (a part or a cable, itself included).

    Attributes:
        cable, other: the cable and what it came nearest; type: the pair's kind.
        min_distance, t: how near (metres) and when (seconds).
        s: where along ``cable`` (material coordinate).
    """

    cable: str
    other: str
    type: PairType
    min_distance: float
    t: float
    s: float


def per_cable(closest: Sequence[Closest], cables: Sequence[str]) -> tuple[CableClosest | None, ...]:
    """Each cable's nearest approach among ``closest`` (None: nothing came
    within reach), in the order of ``cables``."""
    best: dict[str, CableClosest] = {}
    for c in closest:          # nearest first: each cable's first row is its least
        if c.type is PairType.PART_PART:
            continue
        best.setdefault(c.a, CableClosest(c.a, c.b, c.type, c.min_distance, c.t, c.s))
        if c.type is PairType.CABLE_CABLE and c.s_b is not None:
            best.setdefault(c.b, CableClosest(c.b, c.a, c.type, c.min_distance, c.t, c.s_b))
    return tuple(best.get(name) for name in cables)
