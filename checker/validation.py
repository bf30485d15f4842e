"""Cross-check of the checker against the simulator's own contacts.

At each checked step both sides are reduced to one signed distance per pair
(type, a, b) below the clearance, and every pair either side saw is classed
hard (< 0), soft (< clearance) or clear by each side, exactly as events are.
Simulator contacts are first filtered with the checker's own rules: contacts
of elements inside an attachment window (`Exclusion`, aligned to elements by
the caller so both sides leave out the same piece of cable) are expected, and
self contacts
between places closer along the cable than `self_pair_excluded` allows are
near neighbours, not interference. The position of a contact along a cable
is found by projecting the contact point onto its element.

Every disagreement gets a reason, chosen from what is known about the two
methods (a mesh the simulator collides as its convex hull, a crossing that
falls between discrete points, distances that agree but straddle a class
boundary, ...). Counts are kept for the whole run with the largest distance
difference on pairs both sides saw, and the first `keep` disagreements are
kept with their details.

This module takes plain arrays: it does not know MuJoCo's data structures
(the simulation side maps contacts to names) and does not compute geometry
beyond projecting a contact point onto a segment.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from checker.cable import polyline_arc_lengths, self_pair_excluded, tile_offsets
from checker.closest import point_segment, row_norm
from checker.records import Interference, PairType
from checker.scene_state import Exclusion

COMPARED_TYPES = (PairType.SELF.value, PairType.CABLE_CABLE.value,
                  PairType.CABLE_STRUCTURE.value, PairType.KEEPOUT.value)
"""Pair types both sides report (bend and taut are the checker's alone)."""


def classify(distance: float | None, clearance: float) -> str:
    """"hard", "soft" or "clear" for a signed distance (None: clear)."""
    if distance is None or distance >= clearance:
        return "clear"
    return "hard" if distance < 0.0 else "soft"


@dataclass(frozen=True)
class SimContacts:
    """Simulator contacts of one step as parallel arrays (n,).

    Attributes:
      kind: pair type value per contact.
      a, b: names (a is a cable for every type compared here).
      elem_a, elem_b: element index along cable a / b (-1 for a part; -2 - v
        for a contact at vertex v, as MuJoCo gives flex-plane contacts).
      dist: signed surface distance.
      pos: (n, 3) contact points.
    """

    kind: np.ndarray
    a: np.ndarray
    b: np.ndarray
    elem_a: np.ndarray
    elem_b: np.ndarray
    dist: np.ndarray
    pos: np.ndarray


def simulator_pairs(contacts: SimContacts, cables: dict[str, tuple[np.ndarray, float]],
                    exclusions: Sequence[Exclusion],
                    clearance: float) -> dict[tuple[str, str, str], tuple[float, np.ndarray]]:
    """Least distance and its contact point per pair, after the checker's filters.

    `cables`: name -> (points (n, 3), radius) at this step; `clearance` as
    the checker's (it widens the self-exclusion window). See
    :class:`SimulatorPairs` for many steps with the same windows."""
    return SimulatorPairs(exclusions, clearance)(contacts, cables)


class SimulatorPairs:
    """:func:`simulator_pairs` with the attachment windows prepared once;
    :meth:`many` for many states at once."""

    def __init__(self, exclusions: Sequence[Exclusion], clearance: float):
        self.clearance = float(clearance)
        self._ex_cable = np.array([e.cable for e in exclusions], dtype=object)
        self._ex_part = np.array([e.part for e in exclusions], dtype=object)
        self._ex_lo = np.array([min(e.s_min, e.s_max) for e in exclusions], dtype=float)
        self._ex_hi = np.array([max(e.s_min, e.s_max) for e in exclusions], dtype=float)

    def __call__(self, contacts: SimContacts, cables: dict[str, tuple[np.ndarray, float]]
                 ) -> dict[tuple[str, str, str], tuple[float, np.ndarray]]:
        """One state: `cables` maps name -> (points (n, 3), radius)."""
        names = list(cables)
        if not names:
            return {}
        pts = np.concatenate([np.asarray(cables[c][0], float).reshape(-1, 3) for c in names])
        offsets = np.concatenate([[0], np.cumsum([len(cables[c][0]) for c in names])])
        return self.many([contacts], names, np.array([cables[c][1] for c in names], float), pts[None], offsets)[0]

    def many(self, contacts: Sequence[SimContacts], names: Sequence[str], radii: np.ndarray,
             pts: np.ndarray, offsets: np.ndarray) -> list[dict[tuple[str, str, str], tuple[float, np.ndarray]]]:
        """:meth:`__call__` for S states at once: their contacts (S,), the
        cables' names and radii (C,), every state's body centres (S, N, 3),
        cables concatenated from ``offsets`` (C + 1,). One pass for all
        states (a state's few contacts cost numpy's per-call overhead)."""
        n_s, n = pts.shape[:2]
        out: list[dict] = [{} for _ in range(n_s)]
        counts = np.array([len(c.dist) for c in contacts], np.int64)
        if counts.sum() == 0:
            return out
        def cat(field: str) -> np.ndarray:
            return np.concatenate([np.asarray(getattr(c, field)) for c in contacts])

        kind, a, b = cat("kind"), cat("a"), cat("b")
        elem_a, elem_b, dist = cat("elem_a"), cat("elem_b"), cat("dist")
        pos = np.concatenate([np.asarray(c.pos, float).reshape(-1, 3) for c in contacts])
        st = np.repeat(np.arange(n_s), counts)
        keep = (elem_a != -1) & np.logical_or.reduce([kind == k for k in COMPARED_TYPES])
        if not keep.any():
            return out
        kind, a, b, elem_a, elem_b, dist, pos, st = (x[keep] for x in (kind, a, b, elem_a, elem_b, dist, pos, st))
        code = {name: i for i, name in enumerate(names)}
        offsets = np.asarray(offsets, np.int64)
        ca = np.array([code[x] for x in a.tolist()], np.int64)
        cb = np.array([code.get(x, -1) for x in b.tolist()], np.int64)
        # arc lengths of every state's cables, each on its own (arc_length's bits)
        flat = pts.reshape(-1, 3)
        s_all = polyline_arc_lengths(row_norm(np.diff(flat, axis=0)), tile_offsets(offsets, n_s))

        def place(cab, elem):
            """(arc length of the projection, element start, element end) on cable cab."""
            g = st * n + offsets[cab] + np.clip(elem, 0, offsets[cab + 1] - offsets[cab] - 2)
            _, t, _ = point_segment(pos, flat[g], flat[g + 1])
            return s_all[g] + t * (s_all[g + 1] - s_all[g]), s_all[g], s_all[g + 1]

        vertex = elem_a <= -2                      # a contact at a vertex: a span of no length there
        vert = -2 - elem_a
        elem_a = np.where(vertex, np.maximum(vert - 1, 0), elem_a)
        s_a, elem_lo, elem_hi = place(ca, elem_a)
        if vertex.any():
            at = s_all[st * n + offsets[ca] + np.clip(vert, 0, offsets[ca + 1] - offsets[ca] - 1)]
            s_a, elem_lo, elem_hi = (np.where(vertex, at, x) for x in (s_a, elem_lo, elem_hi))
        on_b = (cb >= 0) & (elem_b >= 0)
        s_b = np.where(on_b, place(np.maximum(cb, 0), np.maximum(elem_b, 0))[0], 0.0)
        drop = (kind == PairType.SELF.value) & self_pair_excluded(s_a, s_b, np.asarray(radii, float)[ca],
                                                                   self.clearance)
        if len(self._ex_lo):
            slack = (0.25 * (elem_hi - elem_lo))[:, None]
            structure = (kind == PairType.CABLE_STRUCTURE.value) | (kind == PairType.KEEPOUT.value)
            inside = ((a[:, None] == self._ex_cable) & (b[:, None] == self._ex_part)
                      & (elem_lo[:, None] >= self._ex_lo - slack) & (elem_hi[:, None] <= self._ex_hi + slack))
            drop |= structure & inside.any(axis=1)
        keep = ~drop
        kind, a, b, dist, pos, st = kind[keep], a[keep], b[keep], dist[keep], pos[keep], st[keep]
        if len(dist) == 0:
            return out
        swap = (kind == PairType.CABLE_CABLE.value) & (a.astype(str) > b.astype(str))
        a, b = np.where(swap, b, a), np.where(swap, a, b)
        # the first least distance per (state, kind, a, b), as __call__ keeps
        _, key = np.unique(np.stack([kind.astype(str), a.astype(str), b.astype(str)], axis=1), axis=0,
                           return_inverse=True)
        o = np.lexsort((np.arange(len(dist)), dist, key.ravel(), st))
        head = o[np.r_[True, (st[o][1:] != st[o][:-1]) | (key.ravel()[o][1:] != key.ravel()[o][:-1])]]
        for i in head.tolist():
            out[st[i]][(str(kind[i]), str(a[i]), str(b[i]))] = (float(dist[i]), pos[i])
        return out


@dataclass(frozen=True)
class Disagreement:
    """One (step, pair) the two sides classed differently."""

    t: float
    type: str
    a: str
    b: str
    checker: float | None
    mujoco: float | None
    reason: str


@dataclass
class Validation:
    """Run-long comparison counts (see the module docstring).

    Attributes:
      clearance: soft-interference distance.
      method: the checker's method ("points" or "exact").
      mesh_parts: names of parts that are meshes (the simulator collides
        their convex hulls).
      keep: how many disagreements to keep in detail.
      unit, unit_name: distances in reasons are written divided by `unit`
        and followed by `unit_name` (the report's units).
    """

    clearance: float
    method: str
    mesh_parts: frozenset[str] = frozenset()
    keep: int = 50
    unit: float = 1.0
    unit_name: str = ""
    compared_steps: int = 0
    pair_steps: int = 0
    agree: int = 0
    checker_only: int = 0
    mujoco_only: int = 0
    severity_differs: int = 0
    max_distance_error: float = 0.0
    disagreements: list[Disagreement] = field(default_factory=list)
    reasons: Counter = field(default_factory=Counter)

    def compare(self, t: float, records: Sequence[Interference],
                sim: dict[tuple[str, str, str], tuple[float, np.ndarray]]) -> float:
        """Compare one step; return its agreement (1.0 when no pair is seen)."""
        mine = {}
        for r in records:
            kind = PairType(r.type).value
            if kind in COMPARED_TYPES:
                a, b = (r.a, r.b) if not (kind == PairType.CABLE_CABLE.value and r.a > r.b) else (r.b, r.a)
                mine[(kind, a, b)] = float(r.min_distance)
        self.compared_steps += 1
        agree = 0
        keys = set(mine) | set(sim)
        for k in keys:
            dc = mine.get(k)
            dm = sim[k][0] if k in sim else None
            cc, cm = classify(dc, self.clearance), classify(dm, self.clearance)
            if dc is not None and dm is not None:
                self.max_distance_error = max(self.max_distance_error, abs(dc - dm))
            if cc == cm:
                agree += 1
                continue
            if cm == "clear":
                self.checker_only += 1
            elif cc == "clear":
                self.mujoco_only += 1
            else:
                self.severity_differs += 1
            reason = self.reason(k, dc, dm)
            self.reasons[reason.split(":")[0]] += 1
            if len(self.disagreements) < self.keep:
                self.disagreements.append(Disagreement(t, k[0], k[1], k[2], dc, dm, reason))
        self.pair_steps += len(keys)
        self.agree += agree
        return agree / len(keys) if keys else 1.0

    def reason(self, key: tuple[str, str, str], dc: float | None, dm: float | None) -> str:
        """Why the two sides disagree on this pair, from what is known of both methods."""
        kind, _, b = key
        c = self.clearance
        if kind in (PairType.CABLE_STRUCTURE.value, PairType.KEEPOUT.value) and b in self.mesh_parts \
                and (dc is None or (dm is not None and dm < dc)):
            return f"mesh convex hull: MuJoCo collides mesh '{b}' as its convex hull, which is nearer than the mesh"
        if self.method == "points" and dm is not None and (dc is None or dm < dc):
            what = "crossing" if kind in (PairType.SELF.value, PairType.CABLE_CABLE.value) else "contact"
            return f"between points: the {what} falls between discrete points (method points)"
        if dc is not None and dm is not None and abs(dc - dm) <= 0.02 * max(c, 1e-12):
            return (f"at a boundary: distances agree within {self._len(abs(dc - dm))} but straddle "
                    f"{'0' if min(dc, dm) < 0 <= max(dc, dm) else 'the clearance'}")
        if dm is None and dc is not None and dc >= 0:
            return "no simulator contact: MuJoCo generated no contact for this soft pair within its margin"
        if dm is None:
            return "no simulator contact: MuJoCo generated no contact for this overlapping pair"
        if dc is None:
            return "checker clear: the checker found this pair clear of the clearance"
        return f"distance differs: checker {self._len(dc)}, MuJoCo {self._len(dm)}"

    def _len(self, value: float) -> str:
        return f"{value / self.unit:.4g}{' ' + self.unit_name if self.unit_name else ''}"

    @property
    def agreement(self) -> float:
        """Fraction of (step, pair) classifications that match (1.0 when none)."""
        return self.agree / self.pair_steps if self.pair_steps else 1.0
