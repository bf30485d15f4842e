"""Candidates to records (cablecheck.checker.interference.hits): the worst per pair, ties to the smallest arc lengths; the gaps."""

import numpy as np
import pytest

from cablecheck.checker.interference.hits import TYPE_ORDER, Gaps, Hits, PartCandidates, worst_records
from cablecheck.checker.records import PairType, Severity

pytestmark = pytest.mark.filterwarnings("error")

_SELF = TYPE_ORDER.index(PairType.SELF)
_STRUCT = TYPE_ORDER.index(PairType.CABLE_STRUCTURE)


def test_worst_records_one_per_state_and_pair_worst_first():
    state = np.array([0, 0, 0, 1, 1])
    t = np.array([_SELF, _SELF, _STRUCT, _STRUCT, _STRUCT])
    a = np.array([0, 0, 0, 0, 1])
    b = np.array([0, 0, 1, 1, 0])
    v = np.array([0.002, -0.001, 0.004, 0.003, 0.02])            # the last is above the clearance
    where = np.arange(15.0).reshape(5, 3)
    s = np.array([0.1, 0.2, 0.3, 0.4, 0.5])
    sb = np.array([0.5, 0.6, np.nan, np.nan, np.nan])
    out = worst_records(2, state, t, a, b, v, where, s, sb, 0.005, ["c0", "c1"],
                        lambda ptype: ["p0", "p1"] if ptype is PairType.CABLE_STRUCTURE else ["c0", "c1"])
    assert [(r.type, r.a, r.b, r.min_distance, r.s, r.s_b, r.severity) for r in out[0]] == [
        (PairType.SELF, "c0", "c0", -0.001, 0.2, 0.6, Severity.HARD),
        (PairType.CABLE_STRUCTURE, "c0", "p1", 0.004, 0.3, None, Severity.SOFT)]
    assert np.array_equal(out[0][0].where, where[1])
    assert [(r.a, r.b, r.min_distance) for r in out[1]] == [("c0", "p1", 0.003)]


def test_ties_go_to_the_smallest_arc_lengths_whatever_the_order():
    """Equal values: the candidate at the smallest s (then s_b) is the record, in any input order."""
    v = np.full(4, 0.001)
    s = np.array([0.3, 0.1, 0.1, 0.2])
    sb = np.array([0.9, 0.8, 0.7, 0.6])
    for order in ([0, 1, 2, 3], [3, 2, 1, 0], [2, 0, 3, 1]):
        o = np.array(order)
        out = worst_records(1, np.zeros(4, np.int64), np.full(4, _SELF), np.zeros(4, np.int64),
                            np.zeros(4, np.int64), v[o], np.zeros((4, 3)), s[o], sb[o], 0.005, ["c"],
                            lambda _: ["c"])[0]
        assert [(r.s, r.s_b) for r in out] == [(0.1, 0.7)]


def test_hits_gaps_and_candidates():
    """Gaps: the least value minus the clearance, per part and over cable
    pairs, at most the horizon; candidates that are no records still count."""
    hits = Hits()
    hits.add(PairType.CABLE_STRUCTURE, np.array([0, 0]), np.array([1, 1]), np.array([0.012, 0.009]),
             np.zeros((2, 3)), np.array([0.1, 0.2]))
    hits.add(PairType.SELF, np.array([0]), np.array([0]), np.array([0.004]), np.zeros((1, 3)), np.array([0.1]),
             np.array([0.4]), record=np.array([False]))
    gaps = hits.gaps(0.005, 0.01, 3)
    assert gaps.horizon == 0.01 and gaps.cable == pytest.approx(-0.001)
    assert gaps.part.tolist() == pytest.approx([0.01, 0.004, 0.01])
    assert gaps.part_candidates.part.tolist() == [1, 1]
    assert gaps.cable_candidates.value.tolist() == pytest.approx([-0.001])
    assert hits.records(0.005, ["c0"], lambda _: ["p0", "p1", "p2"]) == []   # the self candidate is no record


def test_gaps_on_parts_renumbers_and_fills_the_others():
    gaps = Gaps(0.1, 0.05, np.array([0.01, 0.02]),
                PartCandidates(np.array([0, 0]), np.array([0.1, 0.2]), np.array([1, 0]), np.array([0.02, 0.01])))
    wide = gaps.on_parts(np.array([3, 1]), 5)
    assert wide.part.tolist() == [np.inf, 0.02, np.inf, 0.01, np.inf]
    assert wide.part_candidates.part.tolist() == [1, 3]
    assert wide.cable == 0.05 and wide.horizon == 0.1 and gaps.part.tolist() == [0.01, 0.02]
