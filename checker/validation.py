"""Cross-check of the checker against the simulator's own contacts.

At each checked step both sides are reduced to one signed distance per pair
(type, a, b) below the clearance, and every pair either side saw is classed
hard (< 0), soft (< clearance) or clear by each side with the records' own
rule (`cablecheck.checker.records.severity_of`), so exactly as events are.
Simulator contacts are first filtered with the checker's own rules: contacts
of elements inside an attachment window (`Exclusion`, aligned to elements by
the caller so both sides leave out the same piece of cable) are expected, and
self contacts are held to the checker's self rule (two places of one cable
count only when at least `self_pair_window` apart along it). The position of
a contact along a cable is found by projecting the contact point onto its
element. A simulator measures an element pair once, at its closest places:
where those lie inside the self window while other places of the same two
elements lie outside it, the pair is measured again over those places alone
(on the simulator's own elements, its distance plus how much farther apart
they are), and kept only where they overlap, as the simulator reports self
contacts (see :attr:`Reason.SELF_NO_MARGIN`).

Every disagreement gets a reason (:class:`Reason`) only once its claim is
checked (the claims and their checks are listed there); any other
disagreement is ``unexplained`` and counted apart. Counts are kept for the
whole run with the largest distance difference on pairs both sides saw, and
every disagreement is kept as an interval per pair (consecutive compared
steps with one reason: start, end, worst).

Pairs the scene allows (``[[allow]]``) are left out of the comparison (they
are never reported as interference, so there is nothing to agree on) and
counted apart.

This module takes plain arrays: it does not know MuJoCo's data structures
(the simulation side maps contacts to names) and computes no geometry beyond
projecting a contact point onto a segment and measuring a self contact's two
elements again (:mod:`cablecheck.checker.closest`); the second opinions come from
:mod:`cablecheck.checker.recheck` through the caller.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from enum import StrEnum
from typing import Protocol

import numpy as np

from cablecheck.checker.arrays import first_least, ranges
from cablecheck.checker.cable import polyline_arc_lengths, self_pair_excluded, self_pair_window, tile_offsets
from cablecheck.checker.closest import row_norm, segment_parameter, segment_segment, segment_segment_apart
from cablecheck.checker.events import AllowList
from cablecheck.checker.records import PART_TYPES, Interference, PairType, severity_of
from cablecheck.checker.scene_state import Exclusion

COMPARED_TYPES = (PairType.SELF, PairType.CABLE_CABLE, PairType.CABLE_STRUCTURE, PairType.KEEPOUT)
"""Pair types both sides report (bend and taut are the checker's alone)."""


@dataclass(frozen=True, eq=False)
class NameTable:
    """The tables integer contact codes index (:attr:`SimContacts.codes`):
    the pair types' values and the names (either may appear more than once:
    equal strings are one kind or name)."""

    kinds: np.ndarray
    names: np.ndarray


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
      codes, table: optionally, the same kinds and names as (n, 3) integer
        codes (kind, a, b) into ``table`` (a simulator's contacts already
        numbered: :meth:`SimulatorPairs.many` then reads no string); None:
        the names alone.
    """

    kind: np.ndarray
    a: np.ndarray
    b: np.ndarray
    elem_a: np.ndarray
    elem_b: np.ndarray
    dist: np.ndarray
    pos: np.ndarray
    codes: np.ndarray | None = None
    table: NameTable | None = None


def shared_codes(contacts: Sequence[SimContacts]) -> tuple[NameTable, np.ndarray] | None:
    """The contacts' (kind, a, b) codes, (n, 3) over all of them in order,
    and the one name table they index, when every one carries codes into
    the same table (a simulator's reader numbers them so); else None (read
    their names)."""
    table = contacts[0].table if len(contacts) else None
    if table is None or not all(c.table is table and c.codes is not None for c in contacts):
        return None
    return table, np.concatenate([np.asarray(c.codes, np.int64).reshape(-1, 3) for c in contacts])


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
        # windows sorted by (cable, part) codes: a contact finds its own by a
        # binary search (memory in proportion to the contacts, not contacts x windows)
        self._cable_code: dict[str, int] = {}
        self._part_code: dict[str, int] = {}
        for e in exclusions:
            self._cable_code.setdefault(e.cable, len(self._cable_code))
            self._part_code.setdefault(e.part, len(self._part_code))
        self._n_part = max(len(self._part_code), 1)
        key = np.array([self._cable_code[e.cable] * self._n_part + self._part_code[e.part] for e in exclusions],
                       np.int64)
        lo = np.array([min(e.s_min, e.s_max) for e in exclusions], dtype=float)
        hi = np.array([max(e.s_min, e.s_max) for e in exclusions], dtype=float)
        o = np.argsort(key, kind="stable")
        self._ex_key, self._ex_lo, self._ex_hi = key[o], lo[o], hi[o]
        self._cache: tuple | None = None

    def _in_window(self, ca: np.ndarray, pb: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                   slack: np.ndarray) -> np.ndarray:
        """(n,) True where cable a's span [lo, hi] (material coordinates) lies
        in a window of cable a against part b (their window codes, -1 for a
        name no window has), each end given ``slack``."""
        key = np.where((ca >= 0) & (pb >= 0), ca * self._n_part + pb, -1)
        first = np.searchsorted(self._ex_key, key, "left")
        count = np.searchsorted(self._ex_key, key, "right") - first
        count[key < 0] = 0
        out = np.zeros(len(ca), bool)
        if count.sum() == 0:
            return out
        row = np.repeat(np.arange(len(ca)), count)
        w = ranges(first, count)
        hit = (lo[row] >= self._ex_lo[w] - slack[row]) & (hi[row] <= self._ex_hi[w] + slack[row])
        out[row[hit]] = True
        return out

    def __call__(self, contacts: SimContacts, cables: dict[str, tuple[np.ndarray, float]],
                 rest: dict[str, np.ndarray] | None = None
                 ) -> dict[tuple[str, str, str], tuple[float, np.ndarray]]:
        """One state: `cables` maps name -> (points (n, 3), radius); `rest`
        name -> (n,) material coordinates of the points (None: arc lengths)."""
        names = list(cables)
        if not names:
            return {}
        pts = np.concatenate([np.asarray(cables[c][0], float).reshape(-1, 3) for c in names])
        offsets = np.concatenate([[0], np.cumsum([len(cables[c][0]) for c in names])])
        mat = None if rest is None else np.concatenate([np.asarray(rest[c], float) for c in names])
        return self.many([contacts], names, np.array([cables[c][1] for c in names], float), pts[None], offsets,
                         mat)[0]

    def many(self, contacts: Sequence[SimContacts], names: Sequence[str], radii: np.ndarray,
             pts: np.ndarray, offsets: np.ndarray, rest: np.ndarray | None = None
             ) -> list[dict[tuple[str, str, str], tuple[float, np.ndarray]]]:
        """:meth:`__call__` for S states at once: their contacts (S,), the
        cables' names and radii (C,), every state's body centres (S, N, 3),
        cables concatenated from ``offsets`` (C + 1,), and the centres'
        material coordinates (N,) (the attachment windows' measure; None:
        each state's arc lengths). One pass for all states (a state's few
        contacts cost numpy's per-call overhead)."""
        n_s, n = pts.shape[:2]
        rest = None if rest is None else np.asarray(rest, float)
        out: list[dict] = [{} for _ in range(n_s)]
        counts = np.array([len(c.dist) for c in contacts], np.int64)
        if counts.sum() == 0:
            return out
        def cat(field: str) -> np.ndarray:
            return np.concatenate([np.asarray(getattr(c, field)) for c in contacts])

        table, codes = self._codes(contacts, cat)
        look = self._lookups(table, names)
        kind, a, b = look.kind[codes[:, 0]], look.name[codes[:, 1]], look.name[codes[:, 2]]
        elem_a, elem_b, dist = cat("elem_a"), cat("elem_b"), cat("dist")
        pos = np.concatenate([np.asarray(c.pos, float).reshape(-1, 3) for c in contacts])
        st = np.repeat(np.arange(n_s), counts)
        keep = (elem_a != -1) & look.compared[kind]
        if not keep.any():
            return out
        kind, a, b, elem_a, elem_b, dist, pos, st = (x[keep] for x in (kind, a, b, elem_a, elem_b, dist, pos, st))
        offsets = np.asarray(offsets, np.int64)
        ca, cb = look.cable[a], look.cable[b]
        if (ca < 0).any():
            raise KeyError(look.names[a[ca < 0][0]])        # side a of a compared contact is a cable
        # arc lengths of every state's cables, each on its own (arc_length's bits)
        flat = pts.reshape(-1, 3)
        s_all = polyline_arc_lengths(row_norm(np.diff(flat, axis=0)), tile_offsets(offsets, n_s))

        def place(cab, elem, rows=slice(None)):
            """(arc length of the projection, element start, element end) on
            cable cab for the contacts `rows`; the element's ends in material
            coordinates."""
            i = offsets.take(cab) + np.clip(elem, 0, offsets.take(cab + 1) - offsets.take(cab) - 2)
            g = st[rows] * n + i
            t = segment_parameter(pos[rows], flat.take(g, axis=0), flat.take(g + 1, axis=0))
            at, after = s_all.take(g), s_all.take(g + 1)
            lo, hi = (at, after) if rest is None else (rest.take(i), rest.take(i + 1))
            return at + t * (after - at), lo, hi

        vertex = elem_a <= -2                      # a contact at a vertex: a span of no length there
        vert = -2 - elem_a
        elem_a = np.where(vertex, np.maximum(vert - 1, 0), elem_a)
        s_a, elem_lo, elem_hi = place(ca, elem_a)
        if vertex.any():
            at = s_all[st * n + offsets[ca] + np.clip(vert, 0, offsets[ca + 1] - offsets[ca] - 1)]
            s_a, elem_lo, elem_hi = (np.where(vertex, at, x) for x in (s_a, elem_lo, elem_hi))
        on_b = np.flatnonzero((cb >= 0) & (elem_b >= 0))   # on a cable's element: cable-cable and self
        s_b = np.zeros(len(cb))
        s_b[on_b] = place(cb[on_b], elem_b[on_b], on_b)[0]
        radius = np.asarray(radii, float)[ca]
        drop = (kind == look.self_kind) & self_pair_excluded(s_a, s_b, radius, self.clearance)
        # the self rule's places, not the element pair's closest ones: a
        # dropped self contact whose elements reach past the window is
        # measured again over the places outside it
        edge = np.flatnonzero(drop & ~vertex & (elem_b >= 0) & (cb == ca))
        if len(edge):
            def start(rows, elem):       # global index of each row's element start
                cab = ca[rows]
                return st[rows] * n + offsets.take(cab) + np.clip(elem[rows], 0, offsets.take(cab + 1)
                                                                  - offsets.take(cab) - 2)
            d_new, at = past_window(flat, s_all, start(edge, elem_a), start(edge, elem_b), dist[edge],
                                    self_pair_window(radius[edge], self.clearance))
            kept = d_new < 0.0
            rows = edge[kept]
            dist, pos = dist.copy(), pos.copy()
            dist[rows], pos[rows] = d_new[kept], at[kept]
            drop[rows] = False
        if len(self._ex_lo):
            structure = look.structure[kind]
            if structure.any():
                w = np.nonzero(structure)[0]
                drop[w[self._in_window(look.window_cable[a[w]], look.window_part[b[w]], elem_lo[w], elem_hi[w],
                                       0.25 * (elem_hi[w] - elem_lo[w]))]] = True
        keep = ~drop
        kind, a, b, dist, pos, st = kind[keep], a[keep], b[keep], dist[keep], pos[keep], st[keep]
        if len(dist) == 0:
            return out
        swap = (kind == look.cable_kind) & (a > b)         # names are numbered in sorted order
        a, b = np.where(swap, b, a), np.where(swap, a, b)
        # the first least distance per (state, kind, a, b), as __call__ keeps
        u = len(look.names)
        head = first_least(st, (kind * u + a) * u + b, dist, len(look.kinds) * u * u)
        for i, k, x, y in zip(head.tolist(), kind[head].tolist(), a[head].tolist(), b[head].tolist()):
            out[st[i]][(look.kinds[k], look.names[x], look.names[y])] = (float(dist[i]), pos[i])
        return out

    @staticmethod
    def _codes(contacts: Sequence[SimContacts], cat) -> tuple[NameTable, np.ndarray]:
        """The contacts' (kind, a, b) as (n, 3) codes into one table: their
        own when they all share one, else the names numbered here."""
        shared = shared_codes(contacts)
        if shared is not None:
            return shared
        kinds, kind = np.unique(cat("kind").astype(str), return_inverse=True)
        names, ab = np.unique(np.concatenate([cat("a"), cat("b")]).astype(str), return_inverse=True)
        ab = ab.reshape(2, -1)
        return NameTable(kinds, names), np.stack([kind.ravel(), ab[0], ab[1]], axis=1).astype(np.int64)

    def _lookups(self, table: NameTable, cables: Sequence[str]) -> _Lookups:
        """Per code of `table`: its distinct name's number (in sorted order),
        the cable, window cable and window part it is; per kind code: its
        type. Kept for the last table and cables (a simulator's is the same
        at every batch)."""
        cached = self._cache
        if cached is not None and cached[0] is table and cached[1] == list(cables):
            return cached[2]
        kinds, kind = np.unique(np.asarray(table.kinds).astype(str), return_inverse=True)
        names, name = np.unique(np.asarray(table.names).astype(str), return_inverse=True)
        kinds, names = kinds.tolist(), names.tolist()
        cable_of = {c: i for i, c in enumerate(cables)}
        n_kinds = len(kinds)
        value = {t.value: t for t in PairType}
        types = [value.get(k) for k in kinds]
        look = _Lookups(
            kinds=kinds + [PairType.SELF.value, PairType.CABLE_CABLE.value], names=names,
            kind=kind.ravel().astype(np.int64), name=name.ravel().astype(np.int64),
            compared=np.array([t in COMPARED_TYPES for t in types] + [False, False], bool),
            structure=np.array([t in PART_TYPES for t in types] + [False, False]),
            cable=np.array([cable_of.get(x, -1) for x in names], np.int64),
            window_cable=np.array([self._cable_code.get(x, -1) for x in names], np.int64),
            window_part=np.array([self._part_code.get(x, -1) for x in names], np.int64),
            self_kind=kinds.index(PairType.SELF.value) if PairType.SELF.value in kinds else n_kinds,
            cable_kind=(kinds.index(PairType.CABLE_CABLE.value) if PairType.CABLE_CABLE.value in kinds
                        else n_kinds + 1))
        self._cache = (table, list(cables), look)
        return look


@dataclass(frozen=True, eq=False)
class _Lookups:
    """A name table's codes mapped for :meth:`SimulatorPairs.many` (see ``_lookups``)."""

    kinds: list[str]
    names: list[str]
    kind: np.ndarray
    name: np.ndarray
    compared: np.ndarray
    structure: np.ndarray
    cable: np.ndarray
    window_cable: np.ndarray
    window_part: np.ndarray
    self_kind: int
    cable_kind: int


def past_window(flat: np.ndarray, s: np.ndarray, ga: np.ndarray, gb: np.ndarray, dist: np.ndarray,
                window: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Self contacts measured over the self rule's places alone.

    A simulator reports one distance per element pair, at the pair's closest
    places. For contacts whose two elements, (``flat[ga]``, ``flat[ga + 1]``)
    and (``flat[gb]``, ``flat[gb + 1]``) with arc lengths ``s``, hold places
    at least ``window`` apart along the cable, this is the contact's
    ``dist`` plus how much farther apart the nearest such places are than
    the elements' closest ones (both measured on these elements,
    :func:`~cablecheck.checker.closest.segment_segment_apart`), and the midpoint of
    those places; inf where no such places exist.

    Args:
        flat: (N, 3) every state's body centres; s: (N,) their arc lengths.
        ga, gb: (n,) each contact's two elements, by their first centre.
        dist: (n,) the contacts' distances; window: (n,) the self window.

    Returns:
        (n,) distances and (n, 3) places.
    """
    lo, hi = np.minimum(ga, gb), np.maximum(ga, gb)
    p0, p1, q0, q1 = flat.take(lo, axis=0), flat.take(lo + 1, axis=0), flat.take(hi, axis=0), flat.take(hi + 1, axis=0)
    plain = segment_segment(p0, p1, q0, q1)[0]
    d, _, _, cp, cq = segment_segment_apart(p0, p1, q0, q1, s.take(lo), s.take(lo + 1), s.take(hi),
                                            s.take(hi + 1), window)
    return dist + (d - plain), 0.5 * (cp + cq)


BOUNDARY_SHARE = 0.02
"""A disagreement is at a boundary when the distances lie within this share
of the clearance of the class boundary they fall either side of."""


class Reason(StrEnum):
    """Why the two sides class a pair differently. Each is a claim, given only
    once it is checked (:meth:`Validation.explain`, which says in which
    order); the values are the report's. ``tol`` is :data:`BOUNDARY_SHARE`
    of the clearance ``c``.

    - ``at a boundary``: the pair lies within ``tol`` of the class boundary
      the two sides fall either side of. Both distances known: they differ
      by at most ``tol`` (so each is within ``tol`` of the 0 or ``c`` between
      them). One side clear (no record, or no contact, below ``c``): the other
      side's distance is within ``tol`` below ``c``, and the pair's distance
      by method exact, found up to ``c + tol``, is within ``tol`` of ``c``
      too (with method points a pair exact classes as MuJoCo does is
      ``between points`` first).
    - ``convex hull``: MuJoCo collides a mesh as its convex hull, and the
      cable's distance to the hull classes the pair as MuJoCo does.
    - ``between points`` (method points): the contact or crossing falls
      between discrete points: method exact classes the pair as MuJoCo does
      and finds it nearer than the discrete points did (they missed it, or
      found it farther).
    - ``self, no margin``: a self pair the checker finds within the clearance
      and MuJoCo not at all, and method exact's distance (the checker's own
      with method exact) is within the clearance without overlap (``0 <= d <
      c``): MuJoCo 4's flex self-collision reports a cable's contacts with
      itself only where its elements overlap (no margin: measured, crossings
      of one cable 2, 0.3 and 0.01 mm apart gave no contact, 0.3 mm deep
      gave one at -0.3 mm).
    - ``held element``: a cable-part pair the checker finds within the
      clearance and MuJoCo clear of it, clear by method exact once the
      cable's elements with a vertex held by the part's own body are left
      out: MuJoCo collides no flex element with the geoms of a body that
      holds one of its vertices (measured: a sphere 1 mm from the middle of
      a cable's first long element, whose inner end the world holds, on the
      world and on a scene body, gave no contact; 1 mm from a free element,
      one).
    - ``unexplained``: no check explains it.
    """

    AT_BOUNDARY = "at a boundary"
    CONVEX_HULL = "convex hull"
    BETWEEN_POINTS = "between points"
    SELF_NO_MARGIN = "self, no margin"
    HELD_ELEMENT = "held element"
    UNEXPLAINED = "unexplained"


class Recheck(Protocol):
    """Second opinions on a pair at one state (:class:`cablecheck.checker.recheck.StateRecheck`):
    its signed distance when below the clearance, else None."""

    def exact(self, key: tuple[str, str, str]) -> float | None: ...

    def hull(self, key: tuple[str, str, str], exact: bool = True) -> float | None: ...

    def near(self, key: tuple[str, str, str], limit: float) -> float | None:
        """Method exact's distance when below ``limit`` (>= the clearance), else None."""
        ...

    def held_clear(self, key: tuple[str, str, str]) -> bool:
        """The cable-part pair clear by method exact without the cable's
        elements with a vertex held by the part's body (False where it has none)."""
        ...


@dataclass(frozen=True)
class Disagreement:
    """A run of consecutive compared steps over which the two sides classed
    one pair differently for the same reason.

    Attributes:
      type, a, b: the pair.
      t_start, t_end: first and last compared time of the run, s.
      t_worst: the time at which either side's distance was smallest.
      checker, mujoco: the two distances at ``t_worst`` (None: clear).
      reason: the checked explanation.
      second: the distance that explains it at ``t_worst`` (method exact,
        or to the convex hull), or None.
      steps: compared steps in the run.
    """

    type: PairType
    a: str
    b: str
    t_start: float
    t_end: float
    t_worst: float
    checker: float | None
    mujoco: float | None
    reason: Reason
    second: float | None
    steps: int

    @property
    def t(self) -> float:
        """The worst time (the report's ``t``)."""
        return self.t_worst


def _least(dc: float | None, dm: float | None) -> float:
    """The smaller of the two distances (inf when both are clear)."""
    return min(np.inf if dc is None else dc, np.inf if dm is None else dm)


@dataclass(frozen=True)
class ValidationSummary:
    """A run's comparison as it stood at the end (:meth:`Validation.summary`).

    Attributes:
      compared_steps: steps compared.
      pair_steps: (step, pair) classifications compared; ``agree`` of them
        matched, ``checker_only`` / ``mujoco_only`` were seen by one side
        only, ``severity_differs`` were classed hard by one and soft by the
        other.
      agreement: agree / pair_steps (1.0 when none).
      max_distance_error: largest distance difference on pairs both sides saw.
      unexplained: (step, pair) disagreements no check explains.
      allowed_pair_steps: (step, pair) classifications left out as allowed.
      reasons: (step, pair) disagreements per reason, in the order first given.
      disagreements: the disagreement intervals by start time and pair.
    """

    compared_steps: int
    pair_steps: int
    agree: int
    checker_only: int
    mujoco_only: int
    severity_differs: int
    agreement: float
    max_distance_error: float
    unexplained: int
    allowed_pair_steps: int
    reasons: tuple[tuple[Reason, int], ...]
    disagreements: tuple[Disagreement, ...]


@dataclass
class Validation:
    """Run-long comparison counts and disagreement intervals (module docstring).

    Attributes:
      clearance: soft-interference distance.
      method: the checker's method ("points" or "exact").
      mesh_parts: names of parts that are meshes (the simulator collides
        their convex hulls).
      allow: pairs the scene allows (``[[allow]]``): left out of the
        comparison and counted in ``allowed_pair_steps``.
      unexplained: (step, pair) disagreements no check explains.
    """

    clearance: float
    method: str
    mesh_parts: frozenset[str] = frozenset()
    allow: AllowList = field(default_factory=AllowList)
    compared_steps: int = 0
    pair_steps: int = 0
    agree: int = 0
    checker_only: int = 0
    mujoco_only: int = 0
    severity_differs: int = 0
    unexplained: int = 0
    allowed_pair_steps: int = 0
    max_distance_error: float = 0.0
    reasons: Counter = field(default_factory=Counter)
    _closed: list[Disagreement] = field(default_factory=list)
    _open: dict[tuple[str, str, str], Disagreement] = field(default_factory=dict)

    def compare(self, t: float, records: Sequence[Interference],
                sim: dict[tuple[str, str, str], tuple[float, np.ndarray]],
                recheck: Callable[[], Recheck] | None = None) -> float:
        """Compare one step; return its agreement (1.0 when no pair is seen).

        ``recheck``: builds the second opinions at this state (called at
        most once, on the first disagreement); None: nothing can be checked
        but the distances themselves."""
        mine = {}
        for r in records:
            kind = PairType(r.type)
            if kind in COMPARED_TYPES:
                a, b = (r.a, r.b) if not (kind is PairType.CABLE_CABLE and r.a > r.b) else (r.b, r.a)
                mine[(kind, a, b)] = float(r.min_distance)
        self.compared_steps += 1
        agree = 0
        keys = set(mine) | set(sim)
        if self.allow:
            allowed = {k for k in keys if self.allow.match(k) is not None}
            self.allowed_pair_steps += len(allowed)
            keys -= allowed
        opinions: list[Recheck] = []

        def second() -> Recheck | None:
            if recheck is None:
                return None
            if not opinions:
                opinions.append(recheck())
            return opinions[0]

        now = set()
        for k in sorted(keys):
            dc = mine.get(k)
            dm = sim[k][0] if k in sim else None
            cc, cm = severity_of(dc, self.clearance), severity_of(dm, self.clearance)
            if dc is not None and dm is not None:
                self.max_distance_error = max(self.max_distance_error, abs(dc - dm))
            if cc == cm:
                agree += 1
                continue
            if cm is None:
                self.checker_only += 1
            elif cc is None:
                self.mujoco_only += 1
            else:
                self.severity_differs += 1
            reason, value = self.explain(k, dc, dm, second)
            self.reasons[reason] += 1
            self.unexplained += reason is Reason.UNEXPLAINED
            self._extend(k, t, dc, dm, reason, value)
            now.add(k)
        for k in [k for k in self._open if k not in now]:
            self._closed.append(self._open.pop(k))
        self.pair_steps += len(keys)
        self.agree += agree
        return agree / len(keys) if keys else 1.0

    def _extend(self, k, t, dc, dm, reason: Reason, value) -> None:
        run = self._open.get(k)
        if run is not None and run.reason is not reason:
            self._closed.append(self._open.pop(k))
            run = None
        if run is None:
            self._open[k] = Disagreement(PairType(k[0]), k[1], k[2], t, t, t, dc, dm, reason, value, 1)
            return
        worse = _least(dc, dm) < _least(run.checker, run.mujoco)
        self._open[k] = replace(run, t_end=t, steps=run.steps + 1,
                                **({"t_worst": t, "checker": dc, "mujoco": dm, "second": value} if worse else {}))

    def explain(self, key: tuple[str, str, str], dc: float | None, dm: float | None,
                second: Callable[[], Recheck | None] = lambda: None) -> tuple[Reason, float | None]:
        """Why the two sides disagree on this pair (checker ``dc``, MuJoCo
        ``dm``; None: clear), and the distance that shows it (None where the
        two distances themselves do): each claim of :class:`Reason` is
        checked in turn, the most specific first: at a boundary with both
        distances known, convex hull (by discrete points), between points,
        convex hull (by method exact: credited only where the mesh's own exact
        distance did not explain it), at a boundary with one side clear, self
        with no margin, held element; else unexplained. ``second``
        gives the second opinions (None: nothing can be checked but the
        distances themselves)."""
        c = self.clearance
        tol = BOUNDARY_SHARE * max(c, 1e-12)
        cm = severity_of(dm, c)
        kind, _, b = key
        if dc is not None and dm is not None and abs(dc - dm) <= tol:
            return Reason.AT_BOUNDARY, None
        opinion = second()
        exact = dc if self.method == "exact" else None
        if opinion is not None:
            hulled = kind in PART_TYPES and b in self.mesh_parts
            # the hull by discrete points first (cheaper, often enough); by exact only once the
            # mesh's own exact distance does not explain it (a convex mesh is its own hull)
            if hulled and severity_of(d := opinion.hull(key, False), c) == cm:
                return Reason.CONVEX_HULL, d
            if self.method == "points":
                exact = opinion.exact(key)
                if severity_of(exact, c) == cm and _least(exact, None) < _least(dc, None):
                    return Reason.BETWEEN_POINTS, exact
            if hulled and severity_of(d := opinion.hull(key, True), c) == cm:
                return Reason.CONVEX_HULL, d
            # one side clear, the other just below the clearance: the pair's
            # distance by method exact, found up to c + tol, within tol of c
            if (dc is None) != (dm is None) and c - tol <= _least(dc, dm):
                d = opinion.near(key, c + tol)
                if d is not None and abs(d - c) <= tol:
                    return Reason.AT_BOUNDARY, d
        if (kind == PairType.SELF and dm is None and dc is not None and exact is not None
                and 0.0 <= exact < c and 0.0 <= dc):
            return Reason.SELF_NO_MARGIN, exact
        if opinion is not None and kind in PART_TYPES and cm is None and dc is not None and opinion.held_clear(key):
            return Reason.HELD_ELEMENT, None
        return Reason.UNEXPLAINED, None

    @property
    def disagreements(self) -> list[Disagreement]:
        """Every disagreement interval so far (open ones as they stand), by
        start time and pair."""
        return sorted(self._closed + list(self._open.values()), key=lambda d: (d.t_start, d.type, d.a, d.b))

    @property
    def agreement(self) -> float:
        """Fraction of (step, pair) classifications that match (1.0 when none)."""
        return self.agree / self.pair_steps if self.pair_steps else 1.0

    def summary(self) -> ValidationSummary:
        """The comparison so far as a frozen record (open intervals as they stand)."""
        return ValidationSummary(
            compared_steps=self.compared_steps, pair_steps=self.pair_steps, agree=self.agree,
            checker_only=self.checker_only, mujoco_only=self.mujoco_only,
            severity_differs=self.severity_differs, agreement=self.agreement,
            max_distance_error=self.max_distance_error, unexplained=self.unexplained,
            allowed_pair_steps=self.allowed_pair_steps, reasons=tuple(self.reasons.items()),
            disagreements=tuple(self.disagreements))
