"""Candidate values reduced to one interference record per pair.

Every pass (cable pairs, cables against parts, single-cable checks) adds its
candidates to :class:`Hits`: the worst value per (type, a, b) becomes one
:class:`~checker.records.Interference`, ties going to the smallest arc
lengths so the answer does not depend on the order candidates were found in.
With a horizon, the candidates also give how far every pair stays from the
clearance (the gaps the skip rule of :mod:`checker.advance` needs).

Deliberately not here: finding candidates or computing distances.
"""

from __future__ import annotations

import numpy as np

from checker.records import Interference, PairType, severity_of

TYPE_ORDER = list(PairType)
CABLE_PAIR_CODES = (TYPE_ORDER.index(PairType.SELF), TYPE_ORDER.index(PairType.CABLE_CABLE))
PART_CODES = (TYPE_ORDER.index(PairType.CABLE_STRUCTURE), TYPE_ORDER.index(PairType.KEEPOUT))


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

    def gaps(self, clearance: float, horizon: float, n_parts: int) -> tuple[float, np.ndarray]:
        """Smallest candidate value minus the clearance: over cable pairs (self
        and cable-cable), and per part (cable-structure and keep-out), at most
        ``horizon`` (candidates are found up to clearance + horizon)."""
        cc = horizon
        part = np.full(n_parts, horizon)
        for code, _, b, value, _, _ in self.near:
            if code in CABLE_PAIR_CODES:
                cc = min(cc, float(value.min()) - clearance)
            elif code in PART_CODES:
                np.minimum.at(part, b, value - clearance)
        return cc, part

    def part_candidates(self, clearance: float) -> tuple[np.ndarray, ...]:
        """Every cable-structure and keep-out candidate: (cable, s, part,
        value - clearance), for gaps per cable place (:mod:`checker.advance`)."""
        rows = [(a, s, b, value - clearance) for code, a, b, value, s, _ in self.near if code in PART_CODES]
        if not rows:
            return np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64), np.zeros(0)
        return tuple(np.concatenate(x) for x in zip(*rows))

    def cable_candidates(self, clearance: float) -> tuple[np.ndarray, ...]:
        """Every self and cable-cable candidate: (cable a, s_a, cable b, s_b,
        value - clearance), for gaps per pair of cable places (:mod:`checker.advance`)."""
        rows = [(a, s, b, s_b, value - clearance) for code, a, b, value, s, s_b in self.near
                if code in CABLE_PAIR_CODES]
        if not rows:
            z = np.zeros(0, np.int64)
            return z, np.zeros(0), z, np.zeros(0), np.zeros(0)
        return tuple(np.concatenate(x) for x in zip(*rows))

    def reduce(self, clearance, cable_names, b_names_by_type) -> list[Interference]:
        if not self.parts:
            return []
        t, a, b, v, w, s, sb = (np.concatenate(x) for x in zip(*self.parts))
        keep = v < clearance
        t, a, b, v, w, s, sb = t[keep], a[keep], b[keep], v[keep], w[keep], s[keep], sb[keep]
        if len(v) == 0:
            return []
        # Ties in value go to the smallest arc lengths, so the answer does
        # not depend on the order the broad phase found the candidates in.
        o = np.lexsort((np.nan_to_num(sb, nan=-np.inf), s, v, b, a, t))
        t, a, b = t[o], a[o], b[o]
        first = np.r_[True, (t[1:] != t[:-1]) | (a[1:] != a[:-1]) | (b[1:] != b[:-1])]
        idx = o[first]
        # One record per pair (a few hundred at most): plain Python values.
        ts, as_, bs = t[first].tolist(), a[first].tolist(), b[first].tolist()
        vs, ss, sbs = v[idx].tolist(), s[idx].tolist(), sb[idx].tolist()
        ws = w[idx]
        out = []
        for n, ptype_i in enumerate(ts):
            ptype = TYPE_ORDER[ptype_i]
            d = vs[n]
            sb_n = sbs[n]
            out.append(Interference(
                type=ptype, a=cable_names[as_[n]], b=b_names_by_type(ptype)[bs[n]],
                min_distance=d, severity=severity_of(d, clearance), where=ws[n],
                s=ss[n], s_b=None if sb_n != sb_n else sb_n,
            ))
        return out
