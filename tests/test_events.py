"""Events over time and allowed pairs (cablecheck.checker.events)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cablecheck.checker.events import AllowList, AllowRule, EventTracker, Phase, covered, phase_of
from cablecheck.checker.records import Interference, PairType, Severity, severity_of


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


def test_event_fields_are_enums_with_the_reports_strings():
    tracker = EventTracker(hold=0.003)
    tracker.update(0.0, [_rec(PairType.SELF, "c", "c", 0.002)])
    started, _ = tracker.update(0.001, [_rec(PairType.SELF, "c", "c", -0.001),
                                        _rec(PairType.CABLE_CABLE, "c", "d", 0.001)])
    assert started == [("cable-cable", "c", "d")]
    standing = tracker.standing(("self", "c", "c"))       # a plain-string key finds it
    assert standing.severity is Severity.HARD and standing.min_distance == -0.001
    (self_ev, pair_ev) = tracker.finish()
    assert (self_ev.type, self_ev.severity, self_ev.phase) == (PairType.SELF, Severity.HARD, Phase.STATIC)
    assert (pair_ev.type, pair_ev.severity, pair_ev.phase) == (PairType.CABLE_CABLE, Severity.SOFT, Phase.DYNAMIC)
    assert [f"{e.type} {e.severity} {e.phase}" for e in (self_ev, pair_ev)] == [
        "self hard static", "cable-cable soft dynamic"]
    assert phase_of(0.0) is Phase.STATIC and phase_of(1e-9) is Phase.DYNAMIC


def _brute_force_events(distances, dt, hold_steps, clearance):
    """Maximal runs of steps below the clearance, two runs joined when the
    later starts at most `hold_steps` steps after the earlier's last:
    (t_start, t_end, t_worst, min, hard, static, index of the worst)."""
    below = [i for i, d in enumerate(distances) if d < clearance]
    groups: list[list[int]] = []
    for i in below:
        if groups and i - groups[-1][-1] <= hold_steps:
            groups[-1].append(i)
        else:
            groups.append([i])
    out = []
    for g in groups:
        worst = min(g, key=lambda i: (distances[i], i))      # the first of the least
        out.append((g[0] * dt, g[-1] * dt, worst * dt, distances[worst], distances[worst] < 0.0, g[0] == 0, worst))
    return out


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.floats(-0.01, 0.02, allow_nan=False),
                          st.tuples(*[st.floats(-10.0, 10.0, allow_nan=False)] * 3)), min_size=1, max_size=40),
       st.integers(1, 4))
def test_events_are_the_brute_force_intervals(steps, hold_steps):
    """A pair's distance and worst place drawn per step: the events are the
    runs below the clearance, joined across gaps shorter than the hold; each
    is hard when its least distance is negative, static when it holds t = 0,
    and keeps the worst distance, time and place."""
    clearance, dt = 0.005, 0.001
    tracker = EventTracker(hold=hold_steps * dt)
    for i, (d, where) in enumerate(steps):
        rec = Interference(PairType.CABLE_STRUCTURE, "c", "p", d, severity_of(d, clearance), np.array(where), 0.1)
        tracker.update(i * dt, [rec] if rec.severity is not None else [])
    got = tracker.finish()
    expected = _brute_force_events([d for d, _ in steps], dt, hold_steps, clearance)
    assert len(got) == len(expected)
    for e, (t0, t1, tw, dmin, hard, static, worst) in zip(got, expected):
        assert (e.t_start, e.t_end, e.t_worst, e.min_distance) == pytest.approx((t0, t1, tw, dmin), abs=1e-15)
        assert e.severity is (Severity.HARD if hard else Severity.SOFT)
        assert e.phase is (Phase.STATIC if static else Phase.DYNAMIC)
        assert np.array_equal(e.where, steps[worst][1])
    if expected:
        assert tracker.pairs[("cable-structure", "c", "p")].min_distance == min(x[3] for x in expected)
