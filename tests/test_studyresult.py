"""A study's answer (cablecheck.study.result): rows reduced from reports, and the
window of cable lengths free of hard events with its recommendation."""

from __future__ import annotations

from cablecheck.study.result import Row, Status, length_window, row_from_report


def _row(length, taut=False, hard=0, bend=False, soft=0):
    return Row(id=str(length), values=(length,), status=Status.DONE, hard=hard, soft=soft,
               taut=taut, bend_violation=bend)


def test_length_window_bounds_and_recommendation():
    rows = [_row(540, taut=True, hard=1), _row(580, taut=True, hard=1), _row(620), _row(660),
            _row(700), _row(740, hard=1), _row(780, bend=True),
            Row(id="x", values=(800,), status=Status.FAILED, error="boom")]
    w = length_window(rows)
    assert (w.shortest, w.below, w.longest, w.above) == (620, 580, 700, 740)
    assert w.clean == (620, 660, 700) and w.recommended == 660
    # soft contact at the long end: the recommendation keeps to the lengths with no event
    w = length_window([_row(600, taut=True, hard=1), _row(650), _row(700), _row(750),
                       _row(800, soft=2), _row(850, soft=1), _row(900, hard=1)])
    assert (w.shortest, w.longest, w.quiet) == (650, 850, (650, 700, 750))
    assert w.recommended == 750
    w = length_window([_row(600), _row(700), _row(800)])
    assert w.recommended == 700 and w.below is None and w.above is None
    w = length_window([_row(600), _row(700)])
    assert w.recommended == 600   # two as near: the shorter
    assert length_window([_row(600, taut=True), _row(700, taut=True)]).shortest is None
    w = length_window([_row(600, taut=True, hard=1), _row(700, hard=1)])
    assert w.shortest == 700 and w.longest is None and not w.exists


def test_row_from_report_reduces_the_report():
    report = {"summary": {"hard": 1, "soft": 2},
              "pairs": [{"type": "taut", "min_distance": -30.0},
                        {"type": "cable-structure", "min_distance": -2.5},
                        {"type": "self", "min_distance": 1.0}],
              "events": [{"type": "cable-structure", "a": "hose", "b": "frame", "severity": "hard"},
                         {"type": "cable-cable", "a": "hose", "b": "lead", "severity": "soft"},
                         {"type": "self", "a": "lead", "b": "lead", "severity": "soft"},
                         {"type": "taut", "a": "lead", "b": "lead", "severity": "hard"}],
              "closest": {"reach": 15.0, "pairs": [], "cables": [
                  {"cable": "hose", "other": "frame", "min_distance": -2.5},
                  {"cable": "lead", "other": None, "min_distance": None}]},
              "cables": [{"name": "hose", "max_strain": 0.01, "min_bend_radius": 40.0, "taut": False,
                          "bend_violation": False, "max_twist": 12.0,
                          "wear": {"most_worn": {"sliding": 4.0}}},
                         {"name": "lead", "max_strain": -0.03, "min_bend_radius": None, "taut": True,
                          "bend_violation": False, "wear": {"most_worn": None}}],
              "validation": {"agreement": 0.99}, "timing": {"total_s": 1.5}}
    r = row_from_report("007", (650,), report)
    hose, lead = r.cables
    assert (hose.name, hose.hard, hose.soft, hose.closest, hose.closest_to) == ("hose", 1, 1, -2.5, "frame")
    assert (hose.max_twist, hose.wear, hose.taut) == (12.0, 4.0, False)
    assert (lead.hard, lead.soft, lead.closest, lead.wear, lead.taut) == (0, 2, None, None, True)   # taut is a flag
    # the window of one cable: the lead's contact is not the hose's answer
    assert length_window([r], cable="lead").longest == 650 and length_window([r]).longest is None
    assert (r.exit_status, r.hard, r.soft, r.worst_distance) == (1, 1, 2, -2.5)
    assert (r.max_strain, r.min_bend_radius, r.taut, r.bend_violation) == (-0.03, 40.0, True, False)
    assert (r.agreement, r.run_time_s, r.status) == (0.99, 1.5, Status.DONE)
    r = row_from_report("008", (650,), {**report, "complete": False, "interrupted": "SIGINT"})
    assert r.status is Status.FAILED and "SIGINT" in r.error and r.exit_status is None
