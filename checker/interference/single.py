"""Single-cable checks: bend radius below its limit, and taut (stretch beyond 1 %).

:func:`single_cable` adds one state's bend and taut candidates to the hits
of a check; :func:`single_records_many` gives the same records for many
states at once. Both take their values from one kernel, :func:`single_rows`.

Deliberately not here: anything between two places (cable pairs, parts).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from checker.cable import (
    arc_length,
    bend_radius,
    polyline_arc_lengths,
    taut_margin,
    tile_offsets,
)
from checker.closest import row_norm
from checker.interference.hits import TYPE_ORDER, Hits
from checker.records import Interference, PairType, severity_of
from checker.scene_state import CableState


def single_cable(cables: Sequence[CableState], clearance: float, hits: Hits) -> None:
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
        recs.sort(key=lambda r: (r.min_distance, TYPE_ORDER.index(r.type), r.a, r.b))
    return out
