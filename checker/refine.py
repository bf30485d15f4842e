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
clear where the points found a record. Records farther than the error from
touching keep the points' value: their class cannot change.

:func:`near_miss_records` does the same on the clearance's side: a pair
the points read at or past the clearance by less than their error is
measured with method ``exact`` too, and becomes a soft record where exact
finds it inside.

Not here: which records a state has (:mod:`cablecheck.checker.interference`),
cable-cable and self records.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from cablecheck.checker.recheck import Recheck, exact_records_many
from cablecheck.checker.records import PART_TYPES, Interference, NearMiss, PairType, Severity
from cablecheck.checker.scene_state import CableState

_ROUNDING = 1.0 + 1e-9
"""A record at the error bound itself (a corner touching the cable half way between two points)
is measured again, however its last bits round."""


def refined_records(records: Sequence[Sequence[Interference]], cables: Callable[[int], Mapping[str, CableState]],
                    poses: np.ndarray, recheck: Recheck, errors: Mapping[str, float]
                    ) -> list[dict[int, Interference]]:
    """Per state, the replacements {id(points record): exact record} of its
    soft cable-part records within their cable's error of touching (at it too).

    Args:
        records: per state (S), its cable records by method points.
        cables: state index -> its cables by name (asked only for states
            with a record to refine).
        poses: (S, K, 4, 4) the checked parts' poses, in ``recheck``'s order.
        recheck: the exact one-part checkers (the run's exclusion windows).
        errors: cable name -> the points' error bound (``points_error``).
    """
    out: list[dict[int, Interference]] = [{} for _ in records]
    wanted: dict[tuple[PairType, str, str], list[tuple[int, Interference]]] = {}
    for i, recs in enumerate(records):
        for r in recs:                                                  # a state's few records
            if PairType(r.type) in PART_TYPES and r.severity is Severity.SOFT and r.min_distance <= errors[r.a] * _ROUNDING:
                wanted.setdefault((PairType(r.type), r.a, r.b), []).append((i, r))
    for found, exact in _measured(wanted, cables, poses, recheck, lambda r: r.min_distance):   # near touching
        for (i, r), e in zip(found, exact):
            if e is not None and e.min_distance <= r.min_distance:
                out[i][id(r)] = e
    return out


def _measured(wanted: dict, cables: Callable[[int], Mapping[str, CableState]], poses: np.ndarray,
              recheck: Recheck, below: Callable, span: Callable | None = None):
    """For each pair (type, a, b) of ``wanted`` and its [(state, item)]: the
    items and method exact's records of the pair at their states, in one
    pass a pair (`exact_records_many`, each state measured below
    ``below(item)``, and between the arc lengths ``span(item)``)."""
    asked: dict[int, Mapping[str, CableState]] = {}
    for key, found in wanted.items():
        _, a, b = key
        k = recheck.index[b]
        rows = [i for i, _ in found]
        for i in rows:
            if i not in asked:
                asked[i] = cables(i)
        spans = None if span is None else np.array([span(x) for _, x in found], float)
        yield found, exact_records_many(recheck.exact_checker(k), [asked[i][a] for i in rows], poses[rows, k],
                                        recheck.exclusions, key, below=[below(x) for _, x in found], spans=spans)


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
