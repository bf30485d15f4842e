"""Wear map: where along each cable it lies in contact, slides and bends back and forth.

Each cable is split into arc-length bins, one per element of the built cable
(bin ``j`` runs between the rest arc lengths of body centres ``j`` and
``j + 1``: a material piece of the cable, whatever its shape). Over the
checked steps of a run, per bin:

- ``contact_time``: seconds the element was within the clearance of a part
  or of a cable (another one, or a loop of itself), by the rectangle rule
  over checked steps (a step's contact counts from the previous checked
  step).
- ``sliding``: the distance the element's contact point moved along the
  surface it touches, relative to that surface, while in contact at both
  ends of a step: the element's material point (at the segment parameter of
  its closest approach) is taken at both steps in the frame of the part it
  touches (or against the other cable's material point), and the component
  of its displacement along the contact normal is removed. Archard's wear
  law takes worn volume proportional to sliding distance times load, so
  this is the cable's share of that product that geometry alone can give.
- ``bend_cycles``: bending reversals counted by hysteresis on the discrete
  curvature vector (Bergou et al., "Discrete Elastic Rods", 2008:
  ``2 e0 x e1 / (|e0||e1| + e0.e1)`` over the Voronoi length) at each body
  centre: a reversal is counted when the curvature, having moved away from
  its last turning point, comes back towards it by more than
  :data:`REVERSAL_STRAIN` of surface strain (``radius * change of
  curvature``); ``bend_cycles`` is half the reversals (a full swing back
  and forth is one cycle), the larger of the element's two ends.

Where contact comes from: the step's interference records name every pair
below the clearance (at every checked step, proven-clear steps included, so
a pair in contact is never missed). For each named cable-structure pair the
cable's elements whose box meets the part's are measured against it (exact
segment to shape distance, :func:`cablecheck.checker.shapes.segment_signed_distance`;
for a mesh the element's ends and middle); for cable-cable and self pairs
the element pairs whose bounding spheres meet, exactly (self: the checker's
self rule, the nearest of the two elements' places at least
:func:`cablecheck.checker.cable.self_pair_window` apart along the cable). Keep-outs
are clearance zones, not surfaces, and make no wear; an attachment window
(the cable held in a part) is not contact either. Cost: for a batch of
steps, one distance call for every cable-part pair in contact (all
primitives at once, each mesh on its own) and one per cable pair in
contact; nothing when nothing touches. Contact may be measured at every `stride`-th step only (the run
measures it at the recording's rate), each measurement counting for the
time since the last; bends are followed at every step.

Limits: contact is geometric (within the clearance), not load: a cable
resting with no force and one pressed hard count alike. Sliding between two
measurements is the straight-line displacement, so a contact that slides
back and forth faster than they are taken is undercounted, and a contact
shorter than the time between two is missed.

This module does not know MuJoCo, events or the report's layout.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from cablecheck.checker.arrays import all_columns, within
from cablecheck.checker.cable import arc_length, element_pairs_within, self_pair_window
from cablecheck.checker.closest import row_norm, segment_segment, segment_segment_apart
from cablecheck.checker.interference.structure import PartTable
from cablecheck.checker.primitives import signed_distance_batch
from cablecheck.checker.records import Interference, PairType
from cablecheck.checker.scene_state import Exclusion, PartState
from cablecheck.checker.segments import segment_signed_distance_mixed
from cablecheck.checker.shapes import SHAPE_CODE, Shape, ShapeType, segment_signed_distance, signed_distance

_ALL_TYPES = list(ShapeType)
"""Shape types by their codes (`SHAPE_CODE`, `PartTable.type`)."""

REVERSAL_STRAIN = 1e-3
"""Surface bending strain (radius times change of curvature) a bend must swing
back by to count as a reversal: smaller wiggles (solver noise, vibration of a
few micrometres) are no fatigue cycles."""


@dataclass(frozen=True)
class CableWear:
    """One cable's wear map, per arc-length bin.

    Attributes:
      name: the cable.
      s: (B,) bin starts along the rest length, metres (bin ``j`` ends at ``s[j + 1]``,
        the last at ``length``).
      length: the cable's rest length, metres.
      contact_time: (B,) seconds in contact.
      sliding: (B,) distance slid while in contact, metres.
      bend_cycles: (B,) bending cycles (half the reversals).
      touches: per bin, the name of what it was in contact with longest, or None.
    """

    name: str
    s: np.ndarray
    length: float
    contact_time: np.ndarray
    sliding: np.ndarray
    bend_cycles: np.ndarray
    touches: tuple[str | None, ...]

    def most_worn(self) -> int | None:
        """Index of the bin that slid farthest (or, with no sliding, lay longest
        in contact), None when the cable touched nothing."""
        if self.sliding.size and self.sliding.max() > 0.0:
            return int(np.argmax(self.sliding))
        if self.contact_time.size and self.contact_time.max() > 0.0:
            return int(np.argmax(self.contact_time))
        return None


def curvature_vectors(points: np.ndarray) -> np.ndarray:
    """(n, 3) discrete curvature vector at each point of a polyline (Bergou et
    al. 2008), zero at both ends and at degenerate (zero-length) elements."""
    p = np.asarray(points, float)
    interior = np.zeros(len(p), bool)
    interior[1:-1] = True
    return curvature_many(p[None], interior)[0]


def curvature_many(points: np.ndarray, interior: np.ndarray) -> np.ndarray:
    """(S, N, 3) curvature vectors of polylines laid one after the other in
    (S, N, 3) `points`; `interior` (N,) marks the points that have both
    neighbours on their own polyline (the others get zero)."""
    p = np.asarray(points, float)
    out = np.zeros_like(p)
    if p.shape[1] < 3:
        return out
    e = p[:, 1:] - p[:, :-1]
    e0, e1 = e[:, :-1], e[:, 1:]
    l0, l1 = row_norm(e0), row_norm(e1)
    den = (l0 * l1 + np.einsum("sij,sij->si", e0, e1)) * (0.5 * (l0 + l1))
    ok = (den > 1e-300) & (l0 > 0.0) & (l1 > 0.0) & interior[None, 1:-1]
    cross = np.stack([e0[..., 1] * e1[..., 2] - e0[..., 2] * e1[..., 1],
                      e0[..., 2] * e1[..., 0] - e0[..., 0] * e1[..., 2],
                      e0[..., 0] * e1[..., 1] - e0[..., 1] * e1[..., 0]], axis=-1)
    out[:, 1:-1] = np.where(ok[..., None], 2.0 * cross / np.where(ok, den, 1.0)[..., None], 0.0)
    return out


class WearMap:
    """Accumulates the wear map over a run's checked steps (see the module docstring).

    Args:
      names: the cables' names (C,).
      rest_s: per cable, (n,) rest arc length of each body centre, metres.
      radii: (C,) cable radii, metres.
      parts: the parts as (name, shape in its own frame); poses given per step.
      clearance: contact distance, metres.
      exclusions: attachment windows (cable, part, s range) that are no contact.
      stride: contact is measured at every `stride`-th step taken (each
        measurement counting the time since the last one); bends at every step.
    """

    def __init__(self, names: Sequence[str], rest_s: Sequence[np.ndarray], radii: Sequence[float],
                 parts: Sequence[tuple[str, Shape]], clearance: float,
                 exclusions: Iterable[Exclusion] = (), stride: int = 1):
        self.stride = max(int(stride), 1)
        self._count = 0
        self.names = list(names)
        self.index = {n: i for i, n in enumerate(self.names)}
        self.rest_s = [np.asarray(s, float) for s in rest_s]
        self.radii = np.asarray(radii, float)
        self.shapes = {name: (k, shape) for k, (name, shape) in enumerate(parts)}
        # the parts as arrays (types, sizes, each one's box in its own frame: infinite for planes)
        self._shapes = [shape for _, shape in parts]
        self._tab = PartTable([PartState(name, shape, np.eye(4)) for name, shape in parts])
        self._mesh = self._tab.type == SHAPE_CODE[ShapeType.MESH]
        self.clearance = float(clearance)
        mid = [0.5 * (s[1:] + s[:-1]) for s in self.rest_s]
        self._excluded: dict[tuple[int, str], np.ndarray] = {}
        for e in exclusions:
            c = self.index.get(e.cable)
            if c is None:
                continue
            mask = (mid[c] >= e.s_min) & (mid[c] <= e.s_max)
            key = (c, e.part)
            self._excluded[key] = self._excluded.get(key, np.zeros(len(mid[c]), bool)) | mask
        n_el = [max(len(s) - 1, 0) for s in self.rest_s]
        self.contact_time = [np.zeros(n) for n in n_el]
        self.sliding = [np.zeros(n) for n in n_el]
        self._touch_prev = [np.zeros(n, bool) for n in n_el]
        self._partner_time: list[dict[str, np.ndarray]] = [{} for _ in n_el]
        # bending reversals, all body centres of all cables in one array
        self._offsets = np.concatenate([[0], np.cumsum([len(s) for s in self.rest_s])]).astype(int)
        n_v = int(self._offsets[-1])
        self._threshold = np.repeat(REVERSAL_STRAIN / np.maximum(self.radii, 1e-300),
                                    [len(s) for s in self.rest_s])
        self._anchor = np.zeros((n_v, 3))
        self._peak = np.zeros((n_v, 3))
        self._peak_dist = np.zeros(n_v)
        self._reversals = np.zeros(n_v, np.int64)
        self._interior = np.ones(n_v, bool)
        self._interior[self._offsets[:-1]] = False
        self._interior[np.maximum(self._offsets[1:] - 1, 0)] = False
        self._started = False
        self._prev: tuple[float, np.ndarray, np.ndarray] | None = None

    def update(self, t: float, points: Sequence[np.ndarray], poses: np.ndarray,
               records: Iterable[Interference]) -> None:
        """Take one checked step: time t (s), each cable's (n, 3) body centres,
        the parts' (P, 4, 4) poses, and the step's interference records."""
        flat = np.concatenate([np.asarray(p, float) for p in points]) if len(points) else np.zeros((0, 3))
        self.update_many([t], flat[None], np.asarray(poses, float)[None], [list(records)])

    def update_many(self, times: Sequence[float], points: np.ndarray, poses: np.ndarray,
                    records: Sequence[Sequence[Interference]]) -> None:
        """Take consecutive checked steps (oldest first): times (S,), the
        cables' body centres (S, N, 3) one cable after the other, the parts'
        poses (S, P, 4, 4) and each step's records. The bends of all steps are
        measured in one vectorised pass; contact pair by pair, for all the
        steps whose records name the pair at once."""
        points = np.asarray(points, float)
        poses = np.asarray(poses, float)
        n_s = len(points)
        if n_s == 0:
            return
        self._bend_many(points)
        first = self._count
        self._count += n_s
        sel = np.flatnonzero((first + np.arange(n_s)) % self.stride == 0)
        if not len(sel):
            return
        points, poses = points[sel], poses[sel]
        records = [records[i] for i in sel]
        n_s = len(sel)
        t = np.asarray(times, float)[sel]
        if self._prev is None:     # the first step: contact without time or slip
            self._prev = (float(t[0]), points[0], poses[0])
        t0, p0, q0 = self._prev
        dt = np.diff(np.r_[t0, t])
        prev_points = np.concatenate([p0[None], points[:-1]])
        prev_poses = np.concatenate([q0[None], poses[:-1]])
        self._prev = (float(t[-1]), points[-1], poses[-1])
        groups: dict[tuple[int, str, str], list[int]] = {}
        for i, recs in enumerate(records):
            for r in recs:
                kind = PairType(r.type)
                if r.a not in self.index:
                    continue
                if kind is PairType.CABLE_STRUCTURE and r.b in self.shapes:
                    groups.setdefault((self.index[r.a], "part", r.b), []).append(i)
                elif kind in (PairType.CABLE_CABLE, PairType.SELF) and r.b in self.index:
                    groups.setdefault((self.index[r.a], "cable", r.b), []).append(i)
        n_el = [len(c) for c in self.contact_time]
        if not groups:
            self._touch_prev = [np.zeros(n, bool) for n in n_el]
            return
        touch = [np.zeros((n_s, n), bool) for n in n_el]
        slide = [np.zeros((n_s, n)) for n in n_el]
        o = self._offsets
        span = lambda c: slice(o[c], o[c + 1])
        on_parts = [(c, other, np.asarray(idx)) for (c, what, other), idx in groups.items() if what == "part"]
        for (c, other, idx), (hit, moved) in zip(on_parts, self._against_parts(on_parts, points, prev_points,
                                                                               poses, prev_poses)):
            self._take(c, other, idx, hit, moved, touch, slide, dt)
        for (c, what, other), idx in groups.items():
            idx = np.asarray(idx)
            if what == "cable":
                b = self.index[other]
                hit_a, moved_a, hit_b, moved_b = self._against_cable(
                    c, b, points[idx][:, span(c)], points[idx][:, span(b)],
                    prev_points[idx][:, span(c)], prev_points[idx][:, span(b)])
                self._take(c, other, idx, hit_a, moved_a, touch, slide, dt)
                if b != c:
                    self._take(b, self.names[c], idx, hit_b, moved_b, touch, slide, dt)
        for c in range(len(touch)):
            before = np.concatenate([self._touch_prev[c][None], touch[c][:-1]])
            self.contact_time[c] += (dt[:, None] * touch[c]).sum(axis=0)
            self.sliding[c] += np.where(touch[c] & before, slide[c], 0.0).sum(axis=0)
            self._touch_prev[c] = touch[c][-1].copy()

    def _take(self, c: int, partner: str, idx: np.ndarray, hit: np.ndarray, moved: np.ndarray,
              touch, slide, dt: np.ndarray) -> None:
        """Steps `idx`' (m, B) contact and slip against `partner` into the batch's."""
        if not hit.any():
            return
        touch[c][idx] |= hit
        slide[c][idx] = np.maximum(slide[c][idx], np.where(hit, moved, 0.0))
        acc = self._partner_time[c].setdefault(partner, np.zeros(hit.shape[1]))
        acc += (dt[idx, None] * hit).sum(axis=0)

    def _against_parts(self, groups: list[tuple[int, str, np.ndarray]], points: np.ndarray, prev: np.ndarray,
                       poses: np.ndarray, prev_poses: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """For each (cable c, part, steps idx (m,)) of ``groups``: (m, B) the
        cable's elements within the clearance of the part at those steps, and
        the tangential slip of each since the step before. points, prev (S, N,
        3), poses, prev_poses (S, P, 4, 4). Every pair's elements at every
        step in one pass (primitives in one distance call, each mesh in one),
        the values of measuring each pair on its own."""
        if not groups:
            return []
        o = self._offsets
        cab = np.array([c for c, _, _ in groups], np.int64)
        part = np.array([self.shapes[name][0] for _, name, _ in groups], np.int64)
        steps = np.array([len(idx) for _, _, idx in groups], np.int64)
        n_el = o[cab + 1] - o[cab] - 1
        # one row per (pair, step), then one per (pair, step, element), pair after pair
        pair = np.repeat(np.arange(len(groups)), steps)
        step = np.concatenate([idx for _, _, idx in groups])
        count = n_el[pair]
        row = np.repeat(np.arange(len(pair)), count)
        elem = within(count)
        first = o[cab[pair]][row] + elem
        k = part[pair][row]
        st = step[row]

        def local(pts, pose, rows):
            """R^T (p - o): the element ends of ``rows`` in their part's frame."""
            q = pose[st[rows], k[rows]]
            return [np.einsum("ni,nij->nj", pts[st[rows], first[rows] + end] - q[:, :3, 3], q[:, :3, :3])
                    for end in (0, 1)]

        a, b = local(points, poses, slice(None))
        rad = self.radii[cab[pair]][row]
        grow = (rad + self.clearance)[:, None]
        keep = all_columns((np.minimum(a, b) <= self._tab.hi[k] + grow) & (np.maximum(a, b) >= self._tab.lo[k] - grow))
        ends = np.cumsum(steps * n_el)
        for g, (c, name, idx) in enumerate(groups):             # the few pairs with an attachment window
            excluded = self._excluded.get((c, name))
            if excluded is not None:
                keep[ends[g] - len(idx) * n_el[g]:ends[g]] &= ~np.tile(excluded, len(idx))
        cand = np.flatnonzero(keep)
        d, u = self._element_distances(k[cand], a[cand], b[cand], rad[cand] + self.clearance)
        near = (d - rad[cand]) < self.clearance
        hit = np.zeros(len(a), bool)
        moved = np.zeros(len(a))
        i, u = cand[near], u[near]
        hit[i] = True
        if len(i):
            pa, pb = local(prev, prev_poses, i)
            now = a[i] + u[:, None] * (b[i] - a[i])
            then = pa + u[:, None] * (pb - pa)
            moved[i] = _tangential(now - then, now - self._closest(k[i], now))
        return [(h.reshape(len(idx), -1), m.reshape(len(idx), -1))
                for (_, _, idx), h, m in zip(groups, np.split(hit, ends[:-1]), np.split(moved, ends[:-1]))]

    def _element_distances(self, k: np.ndarray, a: np.ndarray, b: np.ndarray,
                           limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:func:`_element_distance` of elements ``a b`` (n, 3) against parts
        ``k`` (n,), each in its part's frame: all primitives in one call, each
        mesh in one."""
        d, t = np.full(len(k), np.inf), np.zeros(len(k))
        mesh = self._mesh[k]
        sel = np.flatnonzero(~mesh)
        if len(sel):
            d[sel], t[sel] = segment_signed_distance_mixed(self._tab.type[k[sel]], self._tab.size[k[sel]], a[sel], b[sel])
        for part in np.unique(k[mesh]):
            sel = np.flatnonzero(k == part)
            d[sel], t[sel] = _element_distance(self._shapes[part], a[sel], b[sel], limit[sel])
        return d, t

    def _closest(self, k: np.ndarray, x: np.ndarray) -> np.ndarray:
        """(n, 3) the nearest surface points of parts ``k`` (n,) to points ``x`` in their frames."""
        out = np.zeros_like(x)
        for part in np.unique(k[self._mesh[k]]):
            sel = np.flatnonzero(k == part)
            out[sel] = signed_distance(self._shapes[part], x[sel])[1]
        codes = self._tab.type[k]
        for code in np.unique(codes[~self._mesh[k]]):
            sel = np.flatnonzero((codes == code) & ~self._mesh[k])
            out[sel] = signed_distance_batch(_ALL_TYPES[code], self._tab.size[k[sel]], x[sel])[1]
        return out

    def _against_cable(self, c: int, b: int, pa: np.ndarray, pb: np.ndarray, qa: np.ndarray,
                       qb: np.ndarray) -> tuple[np.ndarray, ...]:
        """Elements of cables c and b within the clearance of each other at m
        steps (for a self pair, of the same cable's far part), (m, Ba) and
        (m, Bb), and their relative slip since the step before; pa, pb now and
        qa, qb before, (m, n, 3)."""
        m, na, nb = len(pa), pa.shape[1] - 1, pb.shape[1] - 1
        # element pairs whose bounding spheres come within the clearance, then exact
        limit = self.radii[c] + self.radii[b] + self.clearance
        st, ia, ib, gap = element_pairs_within(pa, pb, np.full(m, limit))
        near = gap < limit
        st, ia, ib = st[near], ia[near], ib[near]
        if b == c:
            # the checker's self rule (cablecheck.checker.cable.self_pair_excluded): only
            # places at least the window apart along the cable's centreline
            # count, the nearest such places of each element pair
            # (segment_segment_apart), wherever the elements' own closest
            # places lie; elements wholly within the window are its own bends
            s = arc_length(pa)
            w = self_pair_window(self.radii[c], self.clearance)
            lo, hi = np.minimum(ia, ib), np.maximum(ia, ib)
            reach = s[st, hi + 1] - s[st, lo] >= w
            st, ia, ib, lo, hi = st[reach], ia[reach], ib[reach], lo[reach], hi[reach]
            dist, u, v, cp, cq = segment_segment_apart(
                pa[st, lo], pa[st, lo + 1], pa[st, hi], pa[st, hi + 1], s[st, lo], s[st, lo + 1], s[st, hi],
                s[st, hi + 1], np.full(len(st), w))
            swap = ia > ib                   # the pair as asked: element ia first
            u, v = np.where(swap, v, u), np.where(swap, u, v)
            cp, cq = np.where(swap[:, None], cq, cp), np.where(swap[:, None], cp, cq)
        else:
            dist, u, v, cp, cq = segment_segment(pa[st, ia], pa[st, ia + 1], pb[st, ib], pb[st, ib + 1])
        near = (dist - self.radii[c] - self.radii[b]) < self.clearance
        st, ia, ib, u, v, cp, cq = st[near], ia[near], ib[near], u[near], v[near], cp[near], cq[near]
        hit_a, hit_b = np.zeros((m, na), bool), np.zeros((m, nb), bool)
        moved_a, moved_b = np.zeros((m, na)), np.zeros((m, nb))
        if len(st):
            then_a = qa[st, ia] + u[:, None] * (qa[st, ia + 1] - qa[st, ia])
            then_b = qb[st, ib] + v[:, None] * (qb[st, ib + 1] - qb[st, ib])
            slip = _tangential((cp - then_a) - (cq - then_b), cp - cq)
            hit_a[st, ia] = True
            hit_b[st, ib] = True
            np.maximum.at(moved_a, (st, ia), slip)
            np.maximum.at(moved_b, (st, ib), slip)
        return hit_a, moved_a, hit_b, moved_b

    def _bend_many(self, points: np.ndarray) -> None:
        """Hysteresis turning points of every body centre's curvature vector,
        step after step (S, N, 3)."""
        if points.shape[1] == 0:
            return
        k = curvature_many(points, self._interior)
        start = 0
        if not self._started:     # the first step: its bend is the first turning point
            self._anchor[:] = k[0]
            self._peak[:] = k[0]
            self._started = True
            start = 1
        anchor, peak, peak_dist, thr = self._anchor, self._peak, self._peak_dist, self._threshold
        for kk in k[start:]:       # sequential: each step's reversals depend on the last
            away = row_norm(kk - anchor)
            further = away >= peak_dist
            np.copyto(peak, kk, where=further[:, None])
            np.fmax(peak_dist, away, out=peak_dist)          # away where further, else as it was (NaN too)
            back = ~further & (peak_dist > thr)
            if back.any():
                back &= row_norm(kk - peak) > thr
                if back.any():
                    self._reversals[back] += 1
                    anchor[back] = peak[back]
                    peak[back] = kk[back]
                    peak_dist[back] = row_norm(kk[back] - anchor[back])

    def result(self) -> list[CableWear]:
        """The wear map so far, per cable."""
        out = []
        for c, name in enumerate(self.names):
            s = self.rest_s[c]
            rev = self._reversals[self._offsets[c]:self._offsets[c + 1]]
            cycles = 0.5 * np.maximum(rev[:-1], rev[1:]) if len(rev) > 1 else np.zeros(0)
            partners = self._partner_time[c]
            if partners:
                names = sorted(partners)
                table = np.stack([partners[n] for n in names])
                best = np.argmax(table, axis=0)
                touches = tuple(names[j] if table[j, i] > 0.0 else None for i, j in enumerate(best))
            else:
                touches = (None,) * (len(s) - 1)
            out.append(CableWear(name, s[:-1].copy(), float(s[-1]) if len(s) else 0.0,
                                 self.contact_time[c].copy(), self.sliding[c].copy(), cycles, touches))
        return out


def _element_distance(shape: Shape, a: np.ndarray, b: np.ndarray,
                      limit: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance of elements `a b` (n, 3) to a shape in its frame and
    the parameter of the nearest place: exact for primitives
    (:func:`cablecheck.checker.shapes.segment_signed_distance`); for a mesh, the least
    of the element's ends and middle (its exact segment search costs a
    millisecond an element on a CAD mesh; elements are a few radii long, so
    this errs by at most the element's sag over half its length). With
    ``limit`` (one, or one an element), a mesh's sample that provably lies beyond it may be answered
    by a lower bound above it (the caller keeps elements below it only)."""
    if shape.type is not ShapeType.MESH:
        return segment_signed_distance(shape, a, b)
    n = len(a)
    lim = None if limit is None else np.tile(np.broadcast_to(np.asarray(limit, float), (n,)), 3)
    d, _ = signed_distance(shape, np.concatenate([a, 0.5 * (a + b), b]), lim)
    d = d.reshape(3, n)
    k = np.argmin(d, axis=0)
    return d[k, np.arange(n)], 0.5 * k


def _tangential(displacement: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """|displacement with its component along `normal` removed|, per row
    (the whole displacement where the normal is degenerate)."""
    n_len = row_norm(normal)
    ok = n_len > 0.0
    unit = np.zeros_like(normal)
    unit[ok] = normal[ok] / n_len[ok, None]
    along = np.einsum("ij,ij->i", displacement, unit)
    return row_norm(displacement - along[:, None] * unit)
