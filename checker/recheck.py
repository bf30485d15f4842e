"""Second opinions on one pair at one state, to explain a validation disagreement.

When the checker and the simulator class a pair differently, a reason is
given only after it is checked: the pair is computed again another way and
the new distance must class the pair as the simulator did.

- :meth:`StateRecheck.exact`: the pair with method ``exact`` (capsule
  distances along the whole centreline): explains a contact or crossing
  that fell between the discrete points of method ``points``.
- :meth:`StateRecheck.hull`: a cable against the convex hull of a mesh part
  (method ``exact``, or ``points`` first, cheaper): MuJoCo collides meshes
  as their convex hulls, so a concave mesh's pocket or hole is solid to it.
- :meth:`StateRecheck.near`: the pair with method ``exact`` found up to a
  limit beyond the clearance: the distance of a side that is clear, to show
  a disagreement lies at the clearance's boundary.

Only the cables and the part of the pair are checked, with the run's
clearance and exclusion windows; the per-part checkers and hull shapes are
built on first use and kept. This module decides nothing: the comparison
(:mod:`cablecheck.checker.validation`) takes the distances. It knows no simulator.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

from cablecheck.checker.interference import Checker
from cablecheck.checker.arrays import ranges
from cablecheck.checker.cable import polyline_arc_lengths
from cablecheck.checker.closest import row_norm
from cablecheck.checker.interference.discrete import discretise
from cablecheck.checker.interference.hits import TYPE_ORDER, Hits
from cablecheck.checker.interference.cablepairs import closest_elements
from cablecheck.checker.interference.pipeline import cable_cable_exact
from cablecheck.checker.interference.structure import PartTable, structure_exact_pairs
from cablecheck.checker.records import PART_TYPES, Interference, PairType, severity_of
from cablecheck.checker.scene_state import CableState, CheckConfig, Exclusion, PartState
from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape


def convex_hull_shape(shape: Shape) -> Shape:
    """The convex hull of a mesh shape, as a closed mesh shape (trimesh's
    Qhull wrapper)."""
    import trimesh  # a third of a second to import: only a mesh part's hull pays it

    hull = trimesh.convex.convex_hull(np.asarray(shape.vertices, float))
    return mesh_shape(np.asarray(hull.vertices), np.asarray(hull.faces))


class Recheck:
    """Per-part exact checkers and hulls, built on first use.

    Args:
        parts: the checked parts (names, shapes, keep-out flags), in the
            order of the poses given to :meth:`at`.
        config: the run's settings (spacing and clearance are kept).
        exclusions: the run's exclusion windows.
    """

    def __init__(self, parts: Sequence[PartState], config: CheckConfig, exclusions: Sequence[Exclusion],
                 held: Sequence[Exclusion] = ()):
        """``held``: windows over each cable's elements with a vertex held by
        a body, against that body's parts (:meth:`StateRecheck.held_clear`)."""
        self.parts = list(parts)
        self._held: dict[tuple[str, str], list[Exclusion]] = {}
        for e in held:
            self._held.setdefault((e.cable, e.part), []).append(e)
        self.index = {p.name: k for k, p in enumerate(self.parts)}
        self.config = CheckConfig(method="exact", spacing=config.spacing, clearance=config.clearance)
        self.points = CheckConfig(method="points", spacing=config.spacing, clearance=config.clearance)
        self.exclusions = list(exclusions)
        self._checkers: dict[tuple[int, bool, bool], Checker] = {}
        self._hulls: dict[int, Shape] = {}
        self._cables = Checker([], self.config)

    def held_for(self, key: tuple[str, str, str]) -> list[Exclusion]:
        """The held-element windows of the pair (type, cable, part); none for other pairs."""
        return self._held.get((key[1], key[2]), []) if key[0] in PART_TYPES else []

    def is_mesh(self, name: str) -> bool:
        """The part `name` is a mesh."""
        k = self.index.get(name)
        return k is not None and self.parts[k].shape.type is ShapeType.MESH

    def at(self, cables: Sequence[CableState], poses: np.ndarray) -> "StateRecheck":
        """The second opinions at one state: its cables and the parts' poses (K, 4, 4)."""
        return StateRecheck(self, {c.name: c for c in cables}, np.asarray(poses, float))

    def many(self, cables: Sequence[Sequence[CableState]], poses: np.ndarray) -> "BatchRecheck":
        """The second opinions at S consecutive states: each state's cables
        and the parts' poses (S, K, 4, 4)."""
        return BatchRecheck(self, [{c.name: c for c in cs} for cs in cables], np.asarray(poses, float))

    def many_points(self, cables: Sequence[CableState], points: np.ndarray, poses: np.ndarray) -> "BatchRecheck":
        """:meth:`many` from arrays: the cables as at any one state (names,
        radii, rest coordinates), every state's body centres (S, N, 3), the
        cables' concatenated, and the parts' poses (S, K, 4, 4). A state's
        cable is made only when a second opinion asks for it."""
        points = np.asarray(points, float)
        states = cables_by_state(cables, points)
        spans = states[0].spans if states else {}
        return BatchRecheck(self, states, np.asarray(poses, float), (points, spans))

    def exact_checker(self, k: int) -> Checker:
        """Part k's one-part checker with method exact at the run's settings."""
        return self._checker(k, False, True)

    def _checker(self, k: int, hull: bool, exact: bool = True, config: CheckConfig | None = None) -> Checker:
        """Part k's one-part checker: its shape or hull, method exact or
        points at the run's settings, or at ``config`` (kept by its
        clearance: one per limit asked)."""
        key = (k, hull, exact) if config is None else (k, hull, exact, config.clearance)
        if key not in self._checkers:
            p = self.parts[k]
            if hull and k not in self._hulls:
                self._hulls[k] = convex_hull_shape(p.shape)
            shape = self._hulls[k] if hull else p.shape
            if config is None:
                config = self.config if exact else self.points
            self._checkers[key] = Checker([PartState(p.name, shape, np.eye(4), p.keepout)], config)
        return self._checkers[key]


EXACT_WINDOW = 16
"""States whose exact opinion of a pair `BatchRecheck` finds in one pass."""


class BatchRecheck:
    """Second opinions at consecutive states (:meth:`Recheck.many`): a pair's
    hull by discrete points or exact, or its exact distance, once asked at one
    state, is found for every state of the batch in one call (a pair that disagrees at one step mostly
    does at the next ones too); the answers are those of each state alone."""

    def __init__(self, owner: Recheck, cables: list[Mapping[str, CableState]], poses: np.ndarray,
                 points: tuple[np.ndarray, dict[str, tuple[int, int]]] | None = None):
        self.owner, self.cables, self.poses = owner, cables, poses
        self._points = points
        self._hull_points: dict[tuple[str, str, str], list[float | None]] = {}
        self._exact: dict[tuple[str, str, str], dict[int, float | None]] = {}
        self._hull_exact: dict[tuple[str, str, str], dict[int, float | None]] = {}
        self._held_exact: dict[tuple[str, str, str], dict[int, float | None]] = {}

    def at(self, i: int) -> "StateRecheck":
        """The second opinions at the batch's state i."""
        return StateRecheck(self.owner, self.cables[i], self.poses[i], self, i)

    def exact_part(self, key: tuple[str, str, str], i: int) -> float | None:
        """The cable-part pair's distance with method exact at state i, found
        with the next `EXACT_WINDOW` states' in one pass: the copies of the
        cable, each against its own state's pose of the part (each element
        against its own state's part only; the same distances as each state's
        check alone)."""
        return self._windowed(self._exact, key, i, hull=False)

    def exact_cables(self, key: tuple[str, str, str], i: int) -> float | None:
        """The cable-cable pair's distance with method exact at state i (the
        least distance between the two cables' elements as capsules, when
        below the clearance: :func:`cable_cable_exact`'s value), found with the
        next `EXACT_WINDOW` states' in one pass (`closest_elements`)."""
        found = self._exact.setdefault(key, {})
        if i not in found:
            _, a, b = key
            rows = [j for j in range(i, min(i + EXACT_WINDOW, len(self.cables))) if j not in found]
            ra, rb = self.cables[i][a].radius, self.cables[i][b].radius
            pa = np.stack([np.asarray(self.cables[j][a].points, float) for j in rows])
            pb = np.stack([np.asarray(self.cables[j][b].points, float) for j in rows])
            clearance = self.owner.config.clearance
            d = closest_elements(pa, pb, np.full(len(rows), clearance + ra + rb))[0] - ra - rb
            found.update((j, float(v) if v < clearance else None) for j, v in zip(rows, d))
        return found[i]

    def held_exact(self, key: tuple[str, str, str], i: int) -> float | None:
        """:meth:`exact_part` with the pair's held elements left out too
        (`Recheck.held_for`), by the same windows of states."""
        return self._windowed(self._held_exact, key, i, hull=False,
                              exclusions=self.owner.exclusions + self.owner.held_for(key))

    def hull_exact(self, key: tuple[str, str, str], i: int) -> float | None:
        """The cable-part pair's distance to the part's convex hull with
        method exact at state i (:meth:`exact_part` on the hull)."""
        return self._windowed(self._hull_exact, key, i, hull=True)

    def _windowed(self, cache: dict, key: tuple[str, str, str], i: int, hull: bool,
                  exclusions: Sequence[Exclusion] | None = None) -> float | None:
        """Exact opinions of a pair by windows of states: the states from i
        on not yet found, `EXACT_WINDOW` of them, in one `exact_many` call
        (a pair disagreeing at one state mostly does at the next few; the
        exact check of a mesh costs in proportion to the states asked);
        `exclusions`: the run's (None) or those given."""
        found = cache.setdefault(key, {})
        if i not in found:
            _, a, b = key
            k = self.owner.index[b]
            rows = [j for j in range(i, min(i + EXACT_WINDOW, len(self.cables))) if j not in found]
            values = exact_many(self.owner._checker(k, hull, True), [self.cables[j].get(a) for j in rows],
                                self.poses[rows, k], self.owner.exclusions if exclusions is None else exclusions,
                                key)
            found.update(zip(rows, values))
        return found[i]

    def hull_points(self, key: tuple[str, str, str]) -> list[float | None]:
        """The pair's distance to the hull by discrete points at every state."""
        if key not in self._hull_points:
            _, a, b = key
            k = self.owner.index[b]
            first = self.cables[0][a]
            n = len(first.points)
            checker = self.owner._checker(k, True, False)
            if self._points is not None:
                all_pts, spans = self._points
                pts = all_pts[:, spans[a][0]:spans[a][1]]
            else:
                pts = np.stack([np.asarray(c[a].points, float) for c in self.cables])
            dense = checker.densify_many(pts, np.array([0, n]), np.array([first.radius]), first.rest_s)
            found = checker.structure_many([a], np.array([first.radius]), dense, self.poses[:, k][:, None],
                                           self.owner.exclusions, (np.arange(n), np.zeros(n, np.int64)))
            self._hull_points[key] = [_distance(f, key) for f in found]
        return self._hull_points[key]


def cables_by_state(cables: Sequence[CableState], points: np.ndarray) -> list[Mapping[str, CableState]]:
    """Each state's cables by name from arrays: the cables as at any one
    state (names, radii, rest coordinates) and every state's body centres
    (S, N, 3), the cables' concatenated. A state's cable is made when first
    asked for, and is the same object when asked again (copies of one cable
    share its discrete points, `exact_records_pairs`)."""
    ends = np.cumsum([len(c.points) for c in cables])
    spans = {c.name: (int(e) - len(c.points), int(e)) for c, e in zip(cables, ends)}
    template = {c.name: c for c in cables}
    return [_StateCables(template, spans, x) for x in np.asarray(points, float)]


class _StateCables(Mapping):
    """One state's cables by name, each made from the state's body centres
    when first asked for (`cables_by_state`)."""

    def __init__(self, template: dict[str, CableState], spans: dict[str, tuple[int, int]], points: np.ndarray):
        self._template, self.spans, self._points = template, spans, points
        self._made: dict[str, CableState] = {}

    def __getitem__(self, name: str) -> CableState:
        if name not in self._made:
            lo, hi = self.spans[name]
            self._made[name] = self._template[name].with_points(self._points[lo:hi])
        return self._made[name]

    def __contains__(self, name: object) -> bool:
        return name in self._template

    def __iter__(self):
        return iter(self._template)

    def __len__(self) -> int:
        return len(self._template)


class StateRecheck:
    """Second opinions at one state (:meth:`Recheck.at`). Each returns the
    pair's signed distance when below the clearance, else None (clear), as
    the checker's records do."""

    def __init__(self, owner: Recheck, cables: Mapping[str, CableState], poses: np.ndarray,
                 batch: BatchRecheck | None = None, index: int = 0):
        self.owner, self.cables, self.poses = owner, cables, poses
        self.batch, self.index = batch, index

    def exact(self, key: tuple[str, str, str]) -> float | None:
        """The pair (type, a, b) with method exact."""
        kind, a, b = key
        if kind in PART_TYPES:
            return self._part(key, hull=False)
        names = [a] if kind == PairType.SELF else [a, b]
        if any(n not in self.cables for n in names):
            return None
        if kind == PairType.CABLE_CABLE:
            if self.batch is not None:
                return self.batch.exact_cables(key, self.index)
            return _distance(cable_cable_exact([self.cables[n] for n in names], self.owner.config), key)
        found = self.owner._cables.check([self.cables[n] for n in names])
        return _distance(found, key)

    def held_clear(self, key: tuple[str, str, str]) -> bool:
        """The cable-part pair clear with method exact once the cable's
        elements with a vertex held by the part's own body (`Recheck.held_for`)
        are left out; False where it has none: what MuJoCo sees of the pair,
        as it collides no flex element with the geoms of a body holding one
        of its vertices."""
        _, a, b = key
        held = self.owner.held_for(key)
        k = self.owner.index.get(b)
        if not held or k is None or a not in self.cables:
            return False
        if self.batch is not None:
            return self.batch.held_exact(key, self.index) is None
        found = self.owner._checker(k, False, True).check([self.cables[a]], self.poses[k][None],
                                                          self.owner.exclusions + held)
        return _distance(found, key) is None

    def hull(self, key: tuple[str, str, str], exact: bool = True) -> float | None:
        """A cable against the convex hull of the mesh part b, with method
        exact (or, cheaper, points at the run's spacing)."""
        return self._part(key, hull=True, exact=exact) if key[0] in PART_TYPES else None

    def near(self, key: tuple[str, str, str], limit: float) -> float | None:
        """The pair (type, a, b) with method exact, its distance when below
        ``limit`` (>= the clearance) rather than below the clearance. The
        check runs with ``limit`` as its clearance: attachment windows stay
        as given, the self rule's window grows by ``limit - clearance`` (a
        self pair just past the run's window may then be missed, never one
        invented)."""
        kind, a, b = key
        cfg = replace(self.owner.config, clearance=max(float(limit), self.owner.config.clearance))
        if kind in PART_TYPES:
            k = self.owner.index.get(b)
            if k is None or a not in self.cables:
                return None
            found = self.owner._checker(k, False, True, cfg).check([self.cables[a]], self.poses[k][None],
                                                                  self.owner.exclusions)
            return _distance(found, key)
        names = [a] if kind == PairType.SELF else [a, b]
        if any(n not in self.cables for n in names):
            return None
        return _distance(Checker([], cfg).check([self.cables[n] for n in names]), key)

    def _part(self, key: tuple[str, str, str], hull: bool, exact: bool = True) -> float | None:
        _, a, b = key
        k = self.owner.index.get(b)
        if k is None or a not in self.cables:
            return None
        if hull and not exact and self.batch is not None:
            return self.batch.hull_points(key)[self.index]
        if hull and exact and self.batch is not None:
            return self.batch.hull_exact(key, self.index)
        if not hull and exact and self.batch is not None:
            return self.batch.exact_part(key, self.index)
        checker = self.owner._checker(k, hull, exact)
        cable = self.cables[a]
        if exact:
            found = checker.check([cable], self.poses[k][None], self.owner.exclusions)
        else:
            # method points against one part: the full check's cable-structure
            # record from every discrete point (Checker.structure_many, to the
            # bit), without the self checks a full check would add
            n = len(cable.points)
            dense = checker.densify_many(np.asarray(cable.points, float)[None], np.array([0, n]),
                                         np.array([cable.radius]), cable.rest_s)
            found = checker.structure_many([a], np.array([cable.radius]), dense, self.poses[k][None, None],
                                           self.owner.exclusions, (np.arange(n), np.zeros(n, np.int64)))[0]
        return _distance(found, key)


def exact_many(checker: Checker, cables: Sequence[CableState | None], poses: np.ndarray,
                exclusions: Sequence[Exclusion], key: tuple[str, str, str]) -> list[float | None]:
    """A cable against a one-part exact checker's part at S states (poses
    (S, 4, 4)), as ``checker.check([cable], pose, exclusions)`` classes the
    pair at each (None: clear, or no cable there): :func:`exact_records_many`'s distances."""
    return [None if r is None else float(r.min_distance)
            for r in exact_records_many(checker, cables, poses, exclusions, key)]


def exact_records_many(checker: Checker, cables: Sequence[CableState | None], poses: np.ndarray,
                       exclusions: Sequence[Exclusion], key: tuple[str, str, str],
                       below: Sequence[float] | None = None,
                       spans: np.ndarray | None = None) -> list[Interference | None]:
    """The record ``checker.check([cable], pose, exclusions)`` gives the pair
    ``key`` of a cable against a one-part exact checker's part at each of S
    states (poses (S, 4, 4); None: clear, or no cable there), in one pass
    (:func:`exact_records_pairs` with that checker and pair for every state)."""
    n = len(cables)
    return exact_records_pairs([checker] * n, [key] * n, cables, poses, exclusions, below, spans)


def exact_records_pairs(checkers: Sequence[Checker], keys: Sequence[tuple[str, str, str]],
                        cables: Sequence[CableState | None], poses: np.ndarray, exclusions: Sequence[Exclusion],
                        below: Sequence[float] | None = None,
                        spans: np.ndarray | None = None) -> list[Interference | None]:
    """For each of S copies, the record ``checkers[s].check([cables[s]],
    poses[s], exclusions)`` gives the pair ``keys[s]`` (a cable against a
    one-part exact checker's part posed at poses (S, 4, 4); None: clear, or
    no cable there), in one pass, whichever parts and pairs the copies hold
    (a batch of states' records of many pairs). ``below`` (S,): only the
    elements that may come below a copy's value are measured, so its record
    is the same where the pair comes below it, and may be missing or not the
    pair's least where it does not. ``spans`` (S, 2): only the elements of
    cable s between those arc lengths (along it as it lies) are measured.

    Copies of one cable object with no attachment window against their part
    share its discrete points (a cable resting on many parts is discretised
    once; each on its own, the same bits as alone). A copy measures only the
    discrete elements within the arc-length span of its cable's elements
    whose bounding spheres come within its limit of the part's bounding
    sphere (the others cannot come below it: a superset of what the full
    check's broad phase keeps, so the same records), and a cable is
    densified only over the run of its centres its copies' spans cover
    (`_kept_centres`: the same points)."""
    out: list[Interference | None] = [None] * len(cables)
    rows = [i for i, c in enumerate(cables) if c is not None and checkers[i]._tab is not None]
    if not rows:
        return out
    n = len(rows)
    # the few checkers the copies share (a pair's every state asks its own), each copy's one of them
    distinct: dict[int, int] = {}
    first: list[Checker] = []
    which = np.empty(n, np.int64)
    for c, i in enumerate(rows):
        k = distinct.get(id(checkers[i]))
        if k is None:
            k = distinct[id(checkers[i])] = len(first)
            first.append(checkers[i])
        which[c] = k
    config = first[0].config
    if any(ch.config != config for ch in first):
        raise ValueError("the copies' checkers must share one configuration")
    tab = PartTable([ch.parts[0] for ch in first]).rows(which).posed(np.ascontiguousarray(poses[rows], dtype=float))
    # each copy's windows against its part (copy s against part s), a table per checker and cable
    tables: dict[tuple[int, str], object] = {}
    ones = []
    for i in rows:
        at = (id(checkers[i]), keys[i][1])
        if at not in tables:
            tables[at] = checkers[i]._exclusion_table([keys[i][1]], exclusions)
        ones.append(tables[at])
    # the polylines to discretise: one per cable object without windows, one per copy with them
    shared: dict[int, int] = {}
    polys: list[CableState] = []
    poly_of = np.empty(n, np.int64)
    for c, (i, one) in enumerate(zip(rows, ones)):
        if len(one.cable) == 0 and id(cables[i]) in shared:
            poly_of[c] = shared[id(cables[i])]
            continue
        poly_of[c] = len(polys)
        if len(one.cable) == 0:
            shared[id(cables[i])] = len(polys)
        polys.append(cables[i])
    counts = np.array([len(one.excl[0]) for one in ones], np.int64)
    copy = np.repeat(np.arange(n), counts)
    cat = lambda xs: np.concatenate(xs) if xs else np.zeros(0)
    excl = (poly_of[copy] * n + copy, cat([one.excl[1] for one in ones]), cat([one.excl[2] for one in ones]), n)
    order = np.argsort(excl[0], kind="stable")
    excl = (excl[0][order], excl[1][order], excl[2][order], n)
    cut_c = np.repeat(poly_of, [len(one.cable) for one in ones])
    cuts = (np.concatenate([cut_c, cut_c]), np.concatenate([cat([one.lo for one in ones]), cat([one.hi for one in ones])]))
    limit = np.full(n, config.clearance) if below is None else \
        np.minimum(np.asarray(below, float)[rows], config.clearance)
    lo, hi = _sphere_spans([cables[i] for i in rows], tab, limit)
    if spans is not None:
        span = np.asarray(spans, float)[rows]
        lo, hi = np.maximum(lo, span[:, 0]), np.minimum(hi, span[:, 1])
    # only the centres of the elements some copy of a polyline may measure are densified (the same
    # points: a cable resting on one part is a few of its elements there); a polyline with windows whole
    windowed = np.zeros(len(polys), bool)
    windowed[cut_c] = True
    centres = np.concatenate([c.points for c in polys])
    keep = _kept_centres(polys, centres, poly_of, lo, hi, windowed)
    dp = discretise(polys, config, cuts, keep, centres)
    # each copy's discrete elements reaching into its span (a generous pad: a superset is
    # the same records), found in the elements ordered by polyline and arc length
    seg = dp.seg
    length = np.r_[0.0, np.maximum.reduceat(dp.s, np.r_[0, np.flatnonzero(np.diff(dp.cable)) + 1])]
    shift = np.cumsum(length + 1.0)[:-1]                          # polyline k's arc lengths from shift[k]
    pad = 1e-6 * (1.0 + np.abs(dp.s).max(initial=0.0))
    start = dp.s[seg] + shift[dp.cable[seg]]
    stop = dp.s[seg + 1] + shift[dp.cable[seg]]
    live = hi >= lo
    first = np.searchsorted(stop, lo + shift[poly_of] - pad, "left")
    last = np.searchsorted(start, hi + shift[poly_of] + pad, "right")
    many = np.where(live, np.maximum(last - first, 0), 0)
    i0 = seg[ranges(first, many)]
    pk = np.repeat(np.arange(n), many)
    own = dp.cable[i0] == poly_of[pk]
    i0, pk = i0[own], pk[own]
    hits = Hits()
    structure_exact_pairs(dp, tab, config, excl, hits, i0, pk, None if below is None else limit[pk])
    if hits.parts:
        t, _, b, v, w, s_at, sb = (np.concatenate(x) for x in zip(*hits.parts))
        for c, rec in _worst_of_each(b, t, v, w, s_at, sb, config.clearance, [keys[i] for i in rows]):
            out[rows[c]] = rec
    return out


def _worst_of_each(copy: np.ndarray, t: np.ndarray, value: np.ndarray, where: np.ndarray, s: np.ndarray,
                   s_b: np.ndarray, clearance: float, keys: Sequence[tuple[str, str, str]]):
    """(copy, record) of each copy whose candidates (copy, type, value, place, arc
    lengths) hold one below the clearance of its key's type (type, cable, part):
    what `worst_records` gives each copy, taken as a state of its own, of that
    pair, at once. A copy's one part gives all its candidates one type (a
    keep-out's or a structure part's), so the copy alone is the pair."""
    keep = value < clearance
    copy, t, v, w, s, sb = (x[keep] for x in (copy, t, value, where, s, s_b))
    if not len(v):
        return
    # worst_records' order: the least value, ties to the smallest arc lengths
    o = np.lexsort((np.nan_to_num(sb, nan=-np.inf), s, v, copy))
    head = o[np.r_[True, copy[o][1:] != copy[o][:-1]]]
    for c, t_i, d, s_i, sb_i, w_i in zip(copy[head].tolist(), t[head].tolist(), v[head].tolist(),
                                         s[head].tolist(), sb[head].tolist(), w[head]):
        kind, a, b = keys[c]
        ptype = TYPE_ORDER[t_i]
        if ptype == kind:
            yield c, Interference(type=ptype, a=a, b=b, min_distance=d, severity=severity_of(d, clearance),
                                  where=w_i, s=s_i, s_b=None if math.isnan(sb_i) else sb_i)


def _layout(polys: Sequence[CableState], centres: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Polylines' centres (concatenated, ``centres``) laid out: each one's
    count of centres, each centre's polyline, the elements (element e joins
    centres e and e + 1 of one polyline), their lengths (0 between two
    polylines) and each centre's arc length along its own polyline from 0
    (`polyline_arc_lengths`)."""
    count = np.array([len(c.points) for c in polys], np.int64)
    owner = np.repeat(np.arange(len(polys)), count)
    e = np.flatnonzero(owner[:-1] == owner[1:])
    step = np.zeros(max(len(centres) - 1, 0))
    step[e] = row_norm(centres[e + 1] - centres[e])
    return count, owner, e, step, polyline_arc_lengths(step, np.r_[0, np.cumsum(count)])


def _kept_centres(polys: Sequence[CableState], centres: np.ndarray, poly_of: np.ndarray, lo: np.ndarray,
                  hi: np.ndarray, whole: np.ndarray) -> np.ndarray:
    """(N,) bool over the polylines' centres (concatenated): for each
    polyline, the contiguous run of centres from the start of the first to
    the end of the last of its elements that meet some of its copies' spans
    [lo, hi] (arc lengths as it lies), grown by twice the pad the span search
    uses (`exact_records_pairs`) so every discrete element that search can
    take is densified; every centre of a polyline in ``whole``, and the first
    of one no span meets (a polyline keeps a point)."""
    count, owner, e, step, s = _layout(polys, centres)
    offsets = np.r_[0, np.cumsum(count)]
    live = hi >= lo
    lo_p = np.full(len(polys), np.inf)
    hi_p = np.full(len(polys), -np.inf)
    np.minimum.at(lo_p, poly_of[live], lo[live])
    np.maximum.at(hi_p, poly_of[live], hi[live])
    pad = 2e-6 * (1.0 + float(np.abs(s).max(initial=0.0)))
    k = owner[e]
    meets = whole[k] | ((s[e + 1] >= lo_p[k] - pad) & (s[e] <= hi_p[k] + pad))
    first = offsets[:-1].copy()                                    # no element meets: the first centre alone
    last = offsets[:-1].copy()
    hit = e[meets]
    if len(hit):
        has = np.zeros(len(polys), bool)
        has[owner[hit]] = True
        lowest = np.full(len(polys), len(centres))
        highest = np.full(len(polys), -1)
        np.minimum.at(lowest, owner[hit], hit)
        np.maximum.at(highest, owner[hit], hit + 1)
        first = np.where(has, lowest, first)
        last = np.where(has, highest, last)
    keep = np.zeros(len(centres), bool)
    keep[ranges(first, last - first + 1)] = True
    return keep


def _sphere_spans(cables: Sequence[CableState], tab: PartTable, limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) (S,) per copy the arc lengths, along its cable as it lies,
    of the first and last of its elements whose bounding sphere (about its
    middle, half its length across, grown by the radius) comes within
    ``limit`` of part s's bounding sphere (a plane's: everywhere); lo > hi
    where none does. Each cable object's elements and arc lengths (each
    from 0 on its own, `polyline_arc_lengths`) are laid out once, however
    many copies share it (a state's cable against each part it rests on)."""
    n = len(cables)
    index: dict[int, int] = {}
    uniq: list[CableState] = []
    of = np.empty(n, np.int64)
    for c, cab in enumerate(cables):
        k = index.get(id(cab))
        if k is None:
            k = index[id(cab)] = len(uniq)
            uniq.append(cab)
        of[c] = k
    pts = np.concatenate([np.asarray(c.points, float) for c in uniq])
    count, owner, e, step, s = _layout(uniq, pts)
    mid = 0.5 * (pts[e] + pts[e + 1])
    half = 0.5 * step[e]
    scale = np.abs(pts[e]).max(axis=1)
    radius = np.array([c.radius for c in uniq], float)[of]
    # each copy's elements: its cable's, in order
    elems = np.maximum(count - 1, 0)
    first = np.r_[0, np.cumsum(elems)][:-1]
    rows = ranges(first[of], elems[of])
    k = np.repeat(np.arange(n), elems[of])
    centre = np.zeros((n, 3))
    reach = np.full(n, np.inf)
    fin = tab.finite
    centre[fin] = np.einsum("kij,kj->ki", tab.rot[fin], tab.c_loc) + tab.trans[fin]
    reach[fin] = tab.half_diag
    gap = row_norm(mid[rows] - centre[k]) - half[rows] - reach[k] - radius[k]
    near = ~(gap > limit[k] + 1e-9 * (1.0 + np.abs(limit[k]) + scale[rows]))   # rounding
    lo, hi = np.full(n, np.inf), np.full(n, -np.inf)
    np.minimum.at(lo, k[near], s[e[rows[near]]])
    np.maximum.at(hi, k[near], s[e[rows[near]] + 1])
    return lo, hi


def _record(records, key: tuple[str, str, str]) -> Interference | None:
    kind, a, b = key
    for r in records:
        ra, rb = (r.a, r.b) if not (r.type == PairType.CABLE_CABLE and r.a > r.b) else (r.b, r.a)
        if PairType(r.type) == kind and ra == a and rb == b:
            return r
    return None


def _distance(records, key: tuple[str, str, str]) -> float | None:
    r = _record(records, key)
    return None if r is None else float(r.min_distance)
