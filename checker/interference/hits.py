"""Candidate values reduced to one interference record per pair, and the gaps.

Every pass (cable pairs, cables against parts, single-cable checks) adds its
candidates to :class:`Hits`; :func:`worst_records` turns the worst value per
(state, type, a, b) into one :class:`~cablecheck.checker.records.Interference`, ties
going to the smallest arc lengths so the answer does not depend on the order
the candidates were found in. The single-state check and the batched passes
(``*_many``) reduce through it alike. With a horizon, the candidates also
give how far every pair stays from the clearance: a :class:`Gaps` record,
what the skip rule of :mod:`cablecheck.checker.advance` starts from.

Deliberately not here: finding candidates or computing distances.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from cablecheck.checker.records import Interference, NearMiss, PairType, severity_of

TYPE_ORDER = list(PairType)
CABLE_PAIR_CODES = (TYPE_ORDER.index(PairType.SELF), TYPE_ORDER.index(PairType.CABLE_CABLE))
PART_CODES = (TYPE_ORDER.index(PairType.CABLE_STRUCTURE), TYPE_ORDER.index(PairType.KEEPOUT))


def record_order(r: Interference) -> tuple:
    """Sort key of records: worst first, then type, a, b."""
    return (r.min_distance, TYPE_ORDER.index(r.type), r.a, r.b)


class PartCandidates(NamedTuple):
    """Cable-structure and keep-out candidates of a check with a horizon, (n,) each.

    Attributes:
        cable: cable index; s: arc length along it; part: part index;
        value: the candidate's value minus the clearance.
    """

    cable: np.ndarray
    s: np.ndarray
    part: np.ndarray
    value: np.ndarray


class CableCandidates(NamedTuple):
    """Self and cable-cable candidates of a check with a horizon, (n,) each.

    Attributes:
        cable_a, s_a, cable_b, s_b: the two places (cable index, arc length);
        value: the candidate's value minus the clearance.
    """

    cable_a: np.ndarray
    s_a: np.ndarray
    cable_b: np.ndarray
    s_b: np.ndarray
    value: np.ndarray


@dataclass(frozen=True)
class Gaps:
    """How far every pair stayed from the clearance at one check, up to a horizon.

    A pair of places (or a place and a part) with no candidate was at least
    ``horizon`` beyond the clearance (or deeper than the check's ``stretch``
    inside its exclusion window).

    Attributes:
        horizon: candidates were evaluated up to ``clearance + horizon``.
        cable: the least value minus the clearance over self and
            cable-cable candidates, at most ``horizon``.
        part: (K,) per part, the least value minus the clearance over its
            cable-structure and keep-out candidates, at most ``horizon``
            (inf for a part that was not checked).
        part_candidates: every cable-structure and keep-out candidate, or
            None (then only ``part`` is known).
        cable_candidates: every self and cable-cable candidate, or None
            (then only ``cable`` is known).
    """

    horizon: float
    cable: float
    part: np.ndarray
    part_candidates: PartCandidates | None = None
    cable_candidates: CableCandidates | None = None

    def on_parts(self, index: np.ndarray, n_parts: int) -> Gaps:
        """These gaps with part k renumbered ``index[k]`` among ``n_parts``
        parts; the parts no k maps to get inf (not checked)."""
        part = np.full(n_parts, np.inf)
        part[index] = self.part
        pc = self.part_candidates
        if pc is not None:
            pc = pc._replace(part=np.asarray(index)[pc.part])
        return replace(self, part=part, part_candidates=pc)


def worst_records(states: int, state: np.ndarray, t: np.ndarray, a: np.ndarray, b: np.ndarray,
                  value: np.ndarray, where: np.ndarray, s: np.ndarray, s_b: np.ndarray, clearance: float,
                  a_names: Sequence[str], b_names: Callable[[PairType], Sequence[str]]) -> list[list[Interference]]:
    """One record per (state, type, a, b) with a candidate below the clearance, per state, worst first.

    Args:
        states: S, the number of states.
        state, t, a, b: (n,) each candidate's state, type (index into
            ``TYPE_ORDER``) and pair (indices into ``a_names`` and ``b_names(type)``).
        value, where, s, s_b: (n,) its value, (n, 3) its place, (n,) the arc
            lengths of its two places (``s_b`` nan for a part or one place).
        clearance: candidates at or above it are no records.

    Returns:
        per state, its records sorted by :func:`record_order`.
    """
    out: list[list[Interference]] = [[] for _ in range(states)]
    keep = value < clearance
    state, t, a, b, v, w, s, sb = (x[keep] for x in (state, t, a, b, value, where, s, s_b))
    if len(v) == 0:
        return out
    # Ties in value go to the smallest arc lengths, so the answer does
    # not depend on the order the broad phase found the candidates in.
    n_a, n_b = int(a.max()) + 1, int(b.max()) + 1
    if states * len(TYPE_ORDER) * n_a * n_b < 2 ** 62:
        # (state, type, a, b) as one key: the same order in fewer passes
        pair = ((state * len(TYPE_ORDER) + t) * n_a + a) * n_b + b
        o = np.lexsort((np.nan_to_num(sb, nan=-np.inf), s, v, pair))
    else:
        o = np.lexsort((np.nan_to_num(sb, nan=-np.inf), s, v, b, a, t, state))
    state, t, a, b = state[o], t[o], a[o], b[o]
    first = np.r_[True, (state[1:] != state[:-1]) | (t[1:] != t[:-1]) | (a[1:] != a[:-1]) | (b[1:] != b[:-1])]
    idx = o[first]
    # One record per pair (a few hundred at most): plain Python values.
    rows = zip(state[first].tolist(), t[first].tolist(), a[first].tolist(), b[first].tolist(),
               v[idx].tolist(), s[idx].tolist(), sb[idx].tolist(), w[idx])
    for st_i, t_i, a_i, b_i, d, s_i, sb_i, w_i in rows:
        ptype = TYPE_ORDER[t_i]
        out[st_i].append(Interference(
            type=ptype, a=a_names[a_i], b=b_names(ptype)[b_i], min_distance=d,
            severity=severity_of(d, clearance), where=w_i, s=s_i, s_b=None if math.isnan(sb_i) else sb_i))
    for recs in out:
        recs.sort(key=record_order)
    return out


def near_misses_of(states: int, state: np.ndarray, t: np.ndarray, a: np.ndarray, b: np.ndarray,
                   value: np.ndarray, s: np.ndarray, clearance: float, errors: np.ndarray,
                   a_names: Sequence[str], b_names: Sequence[str]) -> list[list[NearMiss]]:
    """Per state, its near misses among cable-part candidates: the (state,
    type, a, b) pairs with no candidate below the clearance (no record) and
    some below the clearance plus their ``errors`` (n,), each with its least
    value (ties to the smallest arc length) and the span of arc lengths of
    those candidates."""
    out: list[list[NearMiss]] = [[] for _ in range(states)]
    near = value < clearance + errors
    if not near.any():
        return out
    key = np.stack([state, t, a, b])
    key = np.ravel_multi_index(key, key.max(axis=1) + 1)      # one number per pair
    below = value < clearance
    if below.any():
        near &= ~np.isin(key, key[below])
    idx = np.flatnonzero(near)
    if not len(idx):
        return out
    o = idx[np.lexsort((s[idx], value[idx], key[idx]))]
    first = np.r_[0, np.flatnonzero(np.diff(key[o])) + 1]
    s_lo, s_hi = np.minimum.reduceat(s[o], first), np.maximum.reduceat(s[o], first)
    head = o[first]
    for i, st, lo, hi in zip(head.tolist(), state[head].tolist(), s_lo.tolist(), s_hi.tolist()):
        out[st].append(NearMiss(TYPE_ORDER[t[i]], a_names[a[i]], b_names[b[i]], float(value[i]), lo, hi))
    return out


class Hits:
    """Accumulates candidate values; reduces to the worst per (type, a, b)."""

    def __init__(self):
        self.parts: list[tuple] = []
        self.near: list[tuple] = []  # (type, a, b, value, s, s_b): every candidate, for the gaps

    def add(self, ptype: PairType, a, b, value, where, s, s_b=None, record=None):
        """Candidates; ``record`` (n,) bool marks those that may become records
        (the others, e.g. just inside an exclusion, only bound the gaps)."""
        if len(value) == 0:
            return
        code = TYPE_ORDER.index(ptype)
        self.near.append((code, a, b, value, s, s_b))
        if record is not None:
            a, b, value, where, s = a[record], b[record], value[record], where[record], s[record]
            s_b = None if s_b is None else s_b[record]
            if len(value) == 0:
                return
        n = len(value)
        s_b = np.full(n, np.nan) if s_b is None else s_b
        self.parts.append((np.full(n, code), a, b, value, where, s, s_b))

    def gaps(self, clearance: float, horizon: float, n_parts: int, part_errors: np.ndarray | None = None) -> Gaps:
        """Smallest candidate value minus the clearance: over cable pairs (self
        and cable-cable), and per part (cable-structure and keep-out), at most
        ``horizon`` (candidates are found up to clearance + horizon); with
        every candidate behind them. ``part_errors`` (C,): a cable-part
        candidate's is counted from the clearance plus its cable's (the
        points' error: a pair kept past that is past the clearance by method
        exact too; its candidates must then be found that much farther)."""
        cc = horizon
        for code, _, _, value, _, _ in self.near:
            if code in CABLE_PAIR_CODES:
                cc = min(cc, float(value.min()) - clearance)
        pc = self._part_candidates(clearance, part_errors)
        part = np.full(n_parts, horizon)
        np.minimum.at(part, pc.part, pc.value)
        if part_errors is not None:     # found farther by the errors: past the horizon is no candidate
            keep = pc.value < horizon
            pc = PartCandidates(pc.cable[keep], pc.s[keep], pc.part[keep], pc.value[keep])
        return Gaps(horizon, cc, part, pc, self._cable_candidates(clearance))

    def _part_candidates(self, clearance: float, part_errors: np.ndarray | None = None) -> PartCandidates:
        """Every cable-structure and keep-out candidate: (cable, s, part,
        value - clearance, less its cable's ``part_errors``), for gaps per
        cable place (:mod:`cablecheck.checker.advance`)."""
        rows = [(a, s, b, value - clearance - (0.0 if part_errors is None else part_errors[a]))
                for code, a, b, value, s, _ in self.near if code in PART_CODES]
        if not rows:
            return PartCandidates(np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64), np.zeros(0))
        return PartCandidates(*(np.concatenate(x) for x in zip(*rows)))

    def _cable_candidates(self, clearance: float) -> CableCandidates:
        """Every self and cable-cable candidate: (cable a, s_a, cable b, s_b,
        value - clearance), for gaps per pair of cable places (:mod:`cablecheck.checker.advance`)."""
        rows = [(a, s, b, s_b, value - clearance) for code, a, b, value, s, s_b in self.near
                if code in CABLE_PAIR_CODES]
        if not rows:
            z = np.zeros(0, np.int64)
            return CableCandidates(z, np.zeros(0), z, np.zeros(0), np.zeros(0))
        return CableCandidates(*(np.concatenate(x) for x in zip(*rows)))

    def near_misses(self, clearance: float, errors: np.ndarray, cable_names: Sequence[str],
                    part_names: Sequence[str]) -> list[NearMiss]:
        """The cable-structure and keep-out pairs at or past the clearance but
        within their cable's ``errors`` (C,) of it (what method ``points``
        may over-state: :func:`~cablecheck.checker.interference.discrete.points_error`):
        pairs an exact measure may find inside the clearance, no records
        themselves (:func:`near_misses_of`)."""
        rows = [x for x in self.parts if x[0][0] in PART_CODES]
        if not rows:
            return []
        t, a, b, v, _, s, _ = (np.concatenate(x) for x in zip(*rows))
        return near_misses_of(1, np.zeros(len(v), np.int64), t, a, b, v, s, clearance,
                              np.asarray(errors, float)[a], cable_names, part_names)[0]

    def records(self, clearance: float, cable_names: Sequence[str],
                b_names: Callable[[PairType], Sequence[str]]) -> list[Interference]:
        """The worst candidate per (type, a, b) below the clearance as a record, worst first."""
        if not self.parts:
            return []
        t, a, b, v, w, s, sb = (np.concatenate(x) for x in zip(*self.parts))
        return worst_records(1, np.zeros(len(v), np.int64), t, a, b, v, w, s, sb, clearance, cable_names, b_names)[0]
