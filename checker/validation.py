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

from checker.cable import arc_length, self_pair_excluded
from checker.closest import point_segment
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
      elem_a, elem_b: element index along cable a / b (-1 for a part).
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


def contact_arc_length(points: np.ndarray, elem: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """Arc length along a polyline of the projection of `pos` onto element `elem`.

    points (n, 3); elem (k,) element indices (i joins points i and i+1);
    pos (k, 3). Returns (k,)."""
    elem = np.clip(np.asarray(elem, int), 0, len(points) - 2)
    s = arc_length(points)
    _, t, _ = point_segment(np.asarray(pos, float), points[elem], points[elem + 1])
    return s[elem] + t * (s[elem + 1] - s[elem])


def simulator_pairs(contacts: SimContacts, cables: dict[str, tuple[np.ndarray, float]],
                    exclusions: Sequence[Exclusion],
                    clearance: float) -> dict[tuple[str, str, str], tuple[float, np.ndarray]]:
    """Least distance and its contact point per pair, after the checker's filters.

    `cables`: name -> (points (n, 3), radius) at this step; `clearance` as
    the checker's (it widens the self-exclusion window)."""
    # a cable on side a (a part touching a keep-out part is a part-part matter)
    keep = np.isin(contacts.kind, COMPARED_TYPES) & (np.asarray(contacts.elem_a) >= 0)
    idx = np.flatnonzero(keep)
    if len(idx) == 0:
        return {}
    kind, a, b = contacts.kind[idx], contacts.a[idx], contacts.b[idx]
    s_a = np.zeros(len(idx))
    s_b = np.zeros(len(idx))
    elem_lo = np.zeros(len(idx))  # arc length span of each contact's element on cable a
    elem_hi = np.zeros(len(idx))
    elem_len = np.zeros(len(idx))
    for name in np.unique(a):  # per cable, vectorised over its contacts
        pts, _ = cables[name]
        on_a = a == name
        s_a[on_a] = contact_arc_length(pts, contacts.elem_a[idx][on_a], contacts.pos[idx][on_a])
        s_pts = arc_length(pts)
        e = np.clip(contacts.elem_a[idx][on_a], 0, len(pts) - 2)
        elem_lo[on_a], elem_hi[on_a] = s_pts[e], s_pts[e + 1]
        elem_len[on_a] = s_pts[e + 1] - s_pts[e]
        on_b = (b == name) & (contacts.elem_b[idx] >= 0)
        if on_b.any():
            s_b[on_b] = contact_arc_length(pts, contacts.elem_b[idx][on_b], contacts.pos[idx][on_b])
    drop = np.zeros(len(idx), bool)
    self_rows = kind == PairType.SELF.value
    if self_rows.any():
        radius = np.array([cables[n][1] for n in a[self_rows]])
        drop[self_rows] = self_pair_excluded(s_a[self_rows], s_b[self_rows], radius, clearance)
    # A simulator contact stands for its whole element: drop it when the element
    # lies in the window (windows are aligned to elements by the caller; a
    # quarter element absorbs the cable's stretch since rest).
    slack = 0.25 * elem_len
    for e in exclusions:
        lo, hi = min(e.s_min, e.s_max), max(e.s_min, e.s_max)
        drop |= (a == e.cable) & (b == e.part) & (elem_lo >= lo - slack) & (elem_hi <= hi + slack) & \
            np.isin(kind, (PairType.CABLE_STRUCTURE.value, PairType.KEEPOUT.value))
    out: dict[tuple[str, str, str], tuple[float, np.ndarray]] = {}
    dist, pos = contacts.dist[idx], contacts.pos[idx]
    for i in np.flatnonzero(~drop):
        k = (str(kind[i]), str(a[i]), str(b[i]))
        if k[0] == PairType.CABLE_CABLE.value and k[1] > k[2]:
            k = (k[0], k[2], k[1])
        if k not in out or dist[i] < out[k][0]:
            out[k] = (float(dist[i]), pos[i])
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
