"""Method ``points``' cable-part records near touching, measured again with method ``exact``.

Discrete points only ever over-state a cable's distance to a part, by at
most :func:`cablecheck.checker.interference.discrete.points_error` (a corner
of the part touching the cable's surface half way between two points): a
soft record within that error of touching may be hard, and a cable resting
on a part (what a dress pack does on the links it rides) reads a fraction
of a millimetre off it where MuJoCo's contact, and the exact capsules, say
it touches. :func:`refined_records` measures those records again, the cable
against that part alone with method ``exact`` (every state asking for one
pair in one pass, only the elements that may come below the points' value),
and the exact record replaces the points' one: the same or nearer, never
clear where the points found a record. Soft records farther than the
error from touching keep the points' value: their class cannot change (a
hard record's depth: below).

:func:`near_miss_records` does the same on the clearance's side: a pair
the points read at or past the clearance by less than their error is
measured with method ``exact`` too, and becomes a soft record where exact
finds it inside.

:func:`refined_cable_records` does the first for two cables: the points
over-state two capsules' distance too (a pair of points a cable's spacing
apart either side of where they cross), and two hoses pressed together read
a few hundredths of a millimetre apart where both capsules and MuJoCo say
they overlap. Every soft cable-cable record is measured again, its two
cables' elements as capsules, and exact's record replaces it.

:func:`refined_self_records` does it for a cable against itself (a
coil pressed on its own turns): method ``exact`` of that cable alone, its
places kept at least the self window apart along it as the points' are.

A hard record's depth: the points may read it shallower than it is by up
to half the gap between two points (a cable straight through a sheet
thinner than that gap reads the nearest point's depth: 2.4 mm for exact's
5.5 through a 1 mm plate, at a 5 mm radius). :func:`deepest_candidates`
picks, state by state, each pair's hard records that are its deepest by
the points so far; the three functions above measure those again too, so
an event's worst depth and place are method exact's at the state the
points read deepest.

Not here: which records a state has (:mod:`cablecheck.checker.interference`),
and cable-cable or self pairs the points read past the clearance.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence

import numpy as np

from cablecheck.checker.cable import arc_length
from cablecheck.checker.interference import Checker
from cablecheck.checker.interference.cablepairs import closest_elements
from cablecheck.checker.recheck import Recheck, exact_records_pairs
from cablecheck.checker.records import PART_TYPES, Interference, NearMiss, PairType, Severity, severity_of
from cablecheck.checker.scene_state import CableState, CheckConfig

_ROUNDING = 1.0 + 1e-9
"""A record at the error bound itself (a corner touching the cable half way between two points)
is measured again, however its last bits round."""


def deepest_candidates(records: Sequence[Sequence[Interference]], types: Collection,
                       least: Mapping[tuple, float] | None = None) -> tuple[list[set[int]], dict[tuple, float]]:
    """Per state (in time order), the ids of its hard records of `types`
    that are their pair's deepest by the points so far in its run of states
    with a record (at or below the least before them; `least`: as the
    states before these left it), and that ``least`` after these states (a
    pair with no record at a state starts a new run). Taken in time order
    with the least carried over, any batching of the states takes the same
    records.

    Measured again with method exact, these make an event's worst exact's
    at the state the points read deepest. Exact's own least may lie at
    another state, by at most the points' error deeper (half a piece a
    cable: every place of a centreline has a point within half a piece,
    and a distance changes no faster than the place it is measured from);
    taking every hard record within that bound of the least would find it
    too, at the cost of measuring nearly every state of a lasting hard
    contact again (the zoo's Fetch: checks 2.3 -> 3.2 s)."""
    least = dict(least or {})
    out: list[set[int]] = []
    for recs in records:
        taken: set[int] = set()
        present = set()
        for r in recs:
            key = (r.type, r.a, r.b)
            present.add(key)
            if r.severity is Severity.HARD and PairType(r.type) in types and r.min_distance <= least.get(key, np.inf):
                least[key] = r.min_distance
                taken.add(id(r))
        for key in [k for k in least if k not in present]:      # clear at this state: its run ends
            del least[key]
        out.append(taken)
    return out, least


def refined_records(records: Sequence[Sequence[Interference]], cables: Callable[[int], Mapping[str, CableState]],
                    poses: np.ndarray, recheck: Recheck, errors: Mapping[str, float],
                    deepest: Sequence[set[int]] | None = None) -> list[dict[int, Interference]]:
    """Per state, the replacements {id(points record): exact record} of its
    soft cable-part records within their cable's error of touching (at it
    too), and of its hard ones named in `deepest` (:func:`deepest_candidates`).

    Args:
        records: per state (S), its cable records by method points.
        cables: state index -> its cables by name (asked only for states
            with a record to refine).
        poses: (S, K, 4, 4) the checked parts' poses, in ``recheck``'s order.
        recheck: the exact one-part checkers (the run's exclusion windows).
        errors: cable name -> the points' error bound (``points_error``).
        deepest: per state, ids of hard records to measure again too.
    """
    out: list[dict[int, Interference]] = [{} for _ in records]
    wanted: dict[tuple[PairType, str, str], list[tuple[int, Interference]]] = {}
    for i, recs in enumerate(records):
        deep = deepest[i] if deepest is not None else ()
        for r in recs:                                                  # a state's few records
            if PairType(r.type) in PART_TYPES and (
                    (r.severity is Severity.SOFT and r.min_distance <= errors[r.a] * _ROUNDING) or id(r) in deep):
                wanted.setdefault((PairType(r.type), r.a, r.b), []).append((i, r))
    for found, exact in _measured(wanted, cables, poses, recheck, lambda r: r.min_distance):   # near touching
        for (i, r), e in zip(found, exact):
            if e is not None and e.min_distance <= r.min_distance:
                out[i][id(r)] = e
    return out


def _measured(wanted: dict, cables: Callable[[int], Mapping[str, CableState]], poses: np.ndarray,
              recheck: Recheck, below: Callable, span: Callable | None = None):
    """For each pair (type, a, b) of ``wanted`` and its [(state, item)]: the
    items and method exact's records of the pair at their states, every
    pair at every state in one pass (`exact_records_pairs`, each state
    measured below ``below(item)``, and between the arc lengths
    ``span(item)``)."""
    asked: dict[int, Mapping[str, CableState]] = {}
    checkers, keys, states, items, parts = [], [], [], [], []
    for key, found in wanted.items():
        k = recheck.index[key[2]]
        for i, x in found:
            if i not in asked:
                asked[i] = cables(i)
            checkers.append(recheck.exact_checker(k))
            keys.append(key)
            states.append(i)
            items.append(x)
            parts.append(k)
    if not items:
        return
    spans = None if span is None else np.array([span(x) for x in items], float)
    exact = exact_records_pairs(checkers, keys, [asked[i][key[1]] for i, key in zip(states, keys)],
                                poses[states, parts], recheck.exclusions, below=[below(x) for x in items], spans=spans)
    at = 0
    for found in wanted.values():
        yield found, exact[at:at + len(found)]
        at += len(found)


def near_miss_records(near: Sequence[Sequence[NearMiss]], cables: Callable[[int], Mapping[str, CableState]],
                      poses: np.ndarray, recheck: Recheck) -> list[list[Interference]]:
    """Per state, the records method ``exact`` finds of its near misses: the
    cable-part pairs the points read at or past the clearance by less than
    their own error (:class:`~cablecheck.checker.records.NearMiss`), each
    measured against its part alone (every state asking for one pair in one
    pass, only the elements where its points read below the clearance plus
    the error: elsewhere none can come inside). A pair exact finds inside the
    clearance gets exact's record (soft, or hard where the clearance is under
    the points' error); the others stay clear.

    Args:
        near: per state (S), its near misses.
        cables, poses, recheck: as :func:`refined_records`.
    """
    out: list[list[Interference]] = [[] for _ in near]
    wanted: dict[tuple[PairType, str, str], list[tuple[int, NearMiss]]] = {}
    for i, misses in enumerate(near):
        for m in misses:                                                # a state's few near misses
            wanted.setdefault((PairType(m.type), m.a, m.b), []).append((i, m))
    clearance = recheck.config.clearance
    for found, exact in _measured(wanted, cables, poses, recheck, lambda m: clearance, lambda m: (m.s_lo, m.s_hi)):
        for (i, _), e in zip(found, exact):
            if e is not None and e.min_distance < clearance:
                out[i].append(e)
    return out


def refined_cable_records(records: Sequence[Sequence[Interference]], cables: Callable[[int], Mapping[str, CableState]],
                          clearance: float, deepest: Sequence[set[int]] | None = None) -> list[dict[int, Interference]]:
    """Per state, the replacements {id(points record): exact record} of its
    soft cable-cable records, and of its hard ones named in `deepest`
    (:func:`deepest_candidates`): the least distance between the two cables'
    elements as capsules (segment distances less both radii, method
    ``exact``'s measure), its place on cable a and both arc lengths.

    The points lie on the centrelines, so their value bounds exact's from
    above: only element pairs whose bounding spheres come within it are
    measured (`closest_elements`), every pair at every state in one pass
    for each pair of cable sizes.

    Args:
        records: per state (S), its cable records by method points.
        cables: state index -> its cables by name (asked only for states
            with a record to refine).
        clearance: soft below it (the severity of exact's value).
    """
    out: list[dict[int, Interference]] = [{} for _ in records]
    found: list[tuple[int, Interference, CableState, CableState]] = []
    asked: dict[int, Mapping[str, CableState]] = {}
    for i, recs in enumerate(records):
        deep = deepest[i] if deepest is not None else ()
        for r in recs:                                                  # a state's few records
            if PairType(r.type) is PairType.CABLE_CABLE and (r.severity is Severity.SOFT or id(r) in deep):
                if i not in asked:
                    asked[i] = cables(i)
                found.append((i, r, asked[i][r.a], asked[i][r.b]))
    # every pair at every state at once, stacked by the two cables' numbers of centres
    shapes: dict[tuple[int, int], list[int]] = {}
    for k, (_, _, ca, cb) in enumerate(found):
        shapes.setdefault((len(ca.points), len(cb.points)), []).append(k)
    for group in shapes.values():
        pa = np.stack([np.asarray(found[k][2].points, float) for k in group])      # (S, na, 3)
        pb = np.stack([np.asarray(found[k][3].points, float) for k in group])
        ra = np.array([found[k][2].radius for k in group], float)
        rb = np.array([found[k][3].radius for k in group], float)
        value = np.array([found[k][1].min_distance for k in group], float)
        d, ea, eb, u, v = closest_elements(pa, pb, value + ra + rb)
        arc_a, arc_b = arc_length(pa), arc_length(pb)
        # every row's record at once (a row with no element pair within reach: element 0, dropped below)
        rows = np.arange(len(group))
        dist = d - ra - rb
        where = pa[rows, ea] + u[:, None] * (pa[rows, ea + 1] - pa[rows, ea])
        s_a = arc_a[rows, ea] + u * (arc_a[rows, ea + 1] - arc_a[rows, ea])
        s_b = arc_b[rows, eb] + v * (arc_b[rows, eb + 1] - arc_b[rows, eb])
        kept = np.isfinite(d) & (dist <= value)                       # rounding: never above the points'
        for row, x, sa, sb in zip(np.flatnonzero(kept).tolist(), dist[kept].tolist(), s_a[kept].tolist(),
                                  s_b[kept].tolist()):
            i, r = found[group[row]][:2]
            out[i][id(r)] = Interference(PairType.CABLE_CABLE, r.a, r.b, x, severity_of(x, clearance),
                                         where[row], sa, sb)
    return out


def refined_self_records(records: Sequence[Sequence[Interference]], cables: Callable[[int], Mapping[str, CableState]],
                         clearance: float, deepest: Sequence[set[int]] | None = None) -> list[dict[int, Interference]]:
    """Per state, the replacements {id(points record): exact record} of its
    soft self records, and of its hard ones named in `deepest`
    (:func:`deepest_candidates`): method ``exact``'s self record of that cable alone
    (its elements as capsules, two places at least the self window apart
    along it: never farther than the points' value), where it is no farther
    than the points' value.

    Args:
        records: per state (S), its cable records by method points.
        cables: state index -> its cables by name (asked only for states
            with a record to refine).
        clearance: the run's clearance.
    """
    out: list[dict[int, Interference]] = [{} for _ in records]
    exact = None
    for i, recs in enumerate(records):
        deep = deepest[i] if deepest is not None else ()
        for r in recs:                                                  # a state's few records
            if PairType(r.type) is not PairType.SELF or (r.severity is not Severity.SOFT and id(r) not in deep):
                continue
            if exact is None:
                exact = Checker([], CheckConfig(method="exact", clearance=clearance))
            found = [e for e in exact.check([cables(i)[r.a]]) if PairType(e.type) is PairType.SELF]
            if found and found[0].min_distance <= r.min_distance:
                out[i][id(r)] = found[0]
    return out
