"""Single-cable checks: bend radius below its limit, and taut (stretch beyond 1 %).

:func:`single_cable` adds one state's bend and taut candidates to the hits
of a check; :func:`single_records_many` gives the same records for many
states at once. Both take their values from one kernel, :func:`single_rows`.

Deliberately not here: anything between two places (cable pairs, parts).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cablecheck.checker.cable import bend_radius, polyline_arc_lengths, taut_margin, tile_offsets
from cablecheck.checker.closest import row_norm
from cablecheck.checker.interference.hits import TYPE_ORDER, Hits, worst_records
from cablecheck.checker.records import Interference, PairType
from cablecheck.checker.scene_state import CableState

_BEND, _TAUT = TYPE_ORDER.index(PairType.BEND), TYPE_ORDER.index(PairType.TAUT)


def single_rows(flat: np.ndarray, offsets: np.ndarray, radius_at: np.ndarray, bend_limit: np.ndarray,
                rest_length: np.ndarray) -> tuple[np.ndarray, ...]:
    """Bend and taut candidates of polylines: the one kernel of both passes.

    Bend: the first place of the least bend radius of each polyline, when
    finite and the polyline has a limit; its value is that radius minus the
    limit (a record below the clearance). Taut: the stretch beyond 1 %
    (:func:`cablecheck.checker.cable.taut_margin`) at the polyline's end, only when
    negative: hard only, a length clearance has no meaning for a stretch (a
    0.3 m cable's whole 1 % is 3 mm).

    Args:
        flat: (N, 3) the polylines' points, concatenated.
        offsets: (P + 1,) start of each polyline in ``flat``.
        radius_at: (N,) the bend radius at every point (:func:`bend_radius`'s bits).
        bend_limit: (P,) smallest allowed bend radius, nan for none.
        rest_length: (P,) rest lengths, nan for none.

    Returns:
        (poly, type, value, at, s): per candidate its polyline, type (index
        into ``TYPE_ORDER``), value, point index in ``flat`` and arc length there.
    """
    starts, ends = offsets[:-1], offsets[1:] - 1
    s = polyline_arc_lengths(row_norm(np.diff(flat, axis=0)), offsets)
    least = np.minimum.reduceat(radius_at, starts)
    at = np.flatnonzero(radius_at == np.repeat(least, ends - starts + 1))
    poly = np.searchsorted(starts, at, side="right") - 1
    k = at[np.r_[True, poly[1:] != poly[:-1]]]
    bend = np.flatnonzero(np.isfinite(least) & ~np.isnan(bend_limit))
    value_t = taut_margin(s[ends], rest_length)
    taut = np.flatnonzero(value_t < 0.0)
    poly = np.concatenate([bend, taut])
    at = np.concatenate([k[bend], ends[taut]])
    kind = np.repeat([_BEND, _TAUT], [len(bend), len(taut)])
    value = np.concatenate([least[bend] - bend_limit[bend], value_t[taut]])
    return poly, kind, value, at, s[at]


def single_cable(cables: Sequence[CableState], clearance: float, hits: Hits) -> None:
    """Bend radius below the limit and stretch beyond 1 %, per cable of one state."""
    bend_limit = np.array([np.nan if c.min_bend_radius is None else c.min_bend_radius for c in cables], float)
    rest_length = np.array([np.nan if c.rest_length is None else c.rest_length for c in cables], float)
    if np.isnan(bend_limit).all() and np.isnan(rest_length).all():
        return
    flat = np.concatenate([c.points for c in cables])
    offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
    radius_at = np.concatenate([bend_radius(c.points) if c.min_bend_radius is not None else np.full(len(c.points), np.inf)
                                for c in cables])
    poly, kind, value, at, s = single_rows(flat, offsets, radius_at, bend_limit, rest_length)
    for code in (_BEND, _TAUT):
        o = kind == code
        hits.add(TYPE_ORDER[code], poly[o], poly[o], value[o], flat[at[o]], s[o])


def single_records_many(names: Sequence[str], pts: np.ndarray, offsets: np.ndarray,
                        radius_at: np.ndarray, rest_length: np.ndarray, bend_limit: np.ndarray,
                        clearance: float) -> list[list[Interference]]:
    """The full check's bend and taut records for many states at once (:func:`single_rows`).

    Args:
        names: the cables' names (C,).
        pts: (S, N, 3) every state's body centres, cables concatenated.
        offsets: (C + 1,) start of each cable in a state's centres.
        radius_at: (S, N) the bend radius at every centre (:func:`bend_radius`'s
            bits, as :meth:`CableMeasures.many` gives them).
        rest_length: (C,) rest lengths.
        bend_limit: (C,) smallest allowed bend radius, nan for none.
        clearance: bend records below it.

    Returns:
        per state, its records (worst first).
    """
    n_s = len(pts)
    n_c = len(names)
    if n_s == 0 or n_c == 0:
        return [[] for _ in range(n_s)]
    flat = pts.reshape(-1, 3)
    poly, kind, value, at, s = single_rows(flat, tile_offsets(offsets, n_s), radius_at.ravel(),
                                           np.tile(bend_limit, n_s), np.tile(rest_length, n_s))
    cab = poly % n_c
    return worst_records(n_s, poly // n_c, kind, cab, cab, value, flat[at], s, np.full(len(s), np.nan),
                         clearance, names, lambda _: names)
