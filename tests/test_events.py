"""Events over time and allowed pairs (checker.events)."""

from __future__ import annotations

import numpy as np

from checker.events import AllowList, AllowRule, EventTracker, covered
from checker.records import Interference, PairType, Severity, severity_of


def _rec(kind, a, b, d, clearance=0.005):
    return Interference(kind, a, b, d, severity_of(d, clearance), np.array([d, 0.0, 0.0]), 0.1)


def test_covered_by_name_or_assembly_path():
    assert covered("cell/table", "cell/table") and covered("cell/table", "cell/table/top")
    assert not covered("cell/table", "cell/tablet") and not covered("cell/table/top", "cell/table")


def test_allow_list_matches_either_way_round_and_never_bend_or_taut():
    allow = AllowList([AllowRule("cell/table", "robot", "bolted"), AllowRule("hose", "hose", "coiled")])
    assert allow.match(("part-part", "cell/table/top", "robot/base")).reason == "bolted"
    assert allow.match(("part-part", "robot/base", "cell/table/top")).reason == "bolted"
    assert allow.match(("part-part", "cell/fence", "robot/base")) is None
    assert allow.match(("self", "hose", "hose")).reason == "coiled"
    assert allow.match(("bend", "hose", "hose")) is None and allow.match(("taut", "hose", "hose")) is None
    assert not AllowList() and allow


def test_allowed_pair_is_never_an_event_and_keeps_its_worst():
    allow = AllowList([AllowRule("cell/table", "robot", "robot base bolted to the table")])
    tracker = EventTracker(hold=0.003, allow=allow)
    for k, d in enumerate([-0.001, -0.004, -0.002, 0.003]):
        tracker.update(0.001 * k, [_rec(PairType.PART_PART, "robot/base", "cell/table/top", d),
                                   _rec(PairType.CABLE_STRUCTURE, "hose", "cell/table/top", 0.002)])
    events = tracker.finish()
    assert [(e.a, e.b) for e in events] == [("hose", "cell/table/top")]
    assert list(tracker.pairs) == [("cable-structure", "hose", "cell/table/top")]
    worst = tracker.allowed[("part-part", "robot/base", "cell/table/top")]
    assert worst.min_distance == -0.004 and worst.t == 0.001
    assert worst.reason == "robot base bolted to the table" and np.allclose(worst.where, [-0.004, 0, 0])


def test_events_without_allowed_pairs_unchanged():
    """The same records with and without an allow list that matches none
    of them: the same events and pairs."""
    runs = []
    for allow in (AllowList(), AllowList([AllowRule("x", "y", "unrelated")])):
        tracker = EventTracker(hold=0.003, allow=allow)
        r = np.random.default_rng(1)
        for k in range(200):
            recs = [_rec(PairType.CABLE_STRUCTURE, "c", f"p{j}", float(r.normal(0.006, 0.004))) for j in range(3)]
            tracker.update(0.001 * k, [x for x in recs if x.severity is not None])
        runs.append(([(e.a, e.b, e.t_start, e.t_end, e.min_distance, e.severity) for e in tracker.finish()],
                     dict(tracker.pairs), tracker.allowed))
    assert runs[0][0] == runs[1][0] and runs[0][1].keys() == runs[1][1].keys()
    assert not runs[1][2]
    assert Severity.HARD in {Severity(e[5]) for e in runs[0][0]}
