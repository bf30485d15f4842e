"""`cablecheck.cli.printing`: what the command line prints from a finished report.

Reports here are built by hand with only the fields the printers read; the
end-to-end output of real runs is checked in tests/test_cli.py."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from hypothesis import given, strategies as st

from cablecheck.cli import printing as cliprint
from cablecheck.cli.printing import POSITION_DECIMALS, ProgressBar, print_summary, print_sweep


@given(st.lists(st.floats(min_value=-1e9, max_value=1e9), min_size=3, max_size=3),
       st.sampled_from(sorted(POSITION_DECIMALS)))
def test_positions_keep_their_decimals_wherever_they_lie(xyz, units):
    text = cliprint._position(xyz, units)
    cells = text.split(", ")
    assert len(cells) == 3 and "e" not in text
    for cell, x in zip(cells, xyz):
        assert len(cell.split(".")[1]) == POSITION_DECIMALS[units]
        assert abs(float(cell) - x) <= 0.5 * 10.0 ** -POSITION_DECIMALS[units] * (1 + 1e-6) + 1e-7 * abs(x)


def _event(k: int, severity: str, distance: float) -> dict:
    return {"a": f"c{k}", "b": "wall", "severity": severity, "phase": "static", "type": "cable-structure",
            "t_start": 0.0, "t_end": 0.1, "min_distance": distance, "t_worst": 0.05,
            "where": [1.0, 2.0, 3.0], "s": 0.5}


def _report(events: list[dict]) -> dict:
    hard = sum(e["severity"] == "hard" for e in events)
    return {"scene": "demo", "units": "mm", "complete": True,
            "settings": {"steps": 10, "t_end": 0.02, "checked_steps": 10, "method": "points"},
            "cables": [{"name": "c0", "length": 100.0, "max_strain": 0.001, "min_bend_radius": None,
                        "taut": False, "bend_violation": False}],
            "summary": {"hard": hard, "soft": len(events) - hard, "static": len(events), "dynamic": 0},
            "events": events,
            "timing": {"total_s": 1.0, "sim_s": 0.5, "check_s": 0.2, "validate_s": 0.1, "record_s": 0.0}}


def test_the_summary_lists_events_worst_first_and_at_most_ten(capsys):
    events = [_event(k, "soft", 1.0 + k) for k in range(12)] + [_event(99, "hard", -0.5)]
    print_summary(_report(events), Path("out.json"))
    out = capsys.readouterr().out
    rows = [line for line in out.splitlines() if line.startswith("    ") and ": t " in line]
    assert len(rows) == 10
    assert rows[0].split()[0] == "HARD" and "c99" in rows[0]
    assert "c0 / wall" in rows[1] and "c8 / wall" in rows[-1]
    assert "... 3 more in the report" in out
    assert "13 interference event(s): 1 hard, 12 soft" in out
    assert "(1.00, 2.00, 3.00)" in out and "report: out.json" in out


def test_a_clean_run_says_no_interference(capsys):
    print_summary(_report([]), Path("r.json"))
    out = capsys.readouterr().out
    assert "no interference" in out and "min bend radius straight" in out


def test_a_cables_torsion_is_printed_where_it_was_largest(capsys):
    """With the simulated rod's twist, the line says the largest moment and where along the
    cable it was; a cable that carried none reads as before."""
    report = _report([])
    report["cables"][0].update(max_twist=33.8, max_twist_moment=0.0154,
                               twist={"s": [0.1, 0.5, 0.9], "max_moment": [0.002, 0.0154, 0.004], "max_rate": [1, 2, 3]})
    print_summary(report, Path("r.json"))
    assert "max twist 33.8 deg (torsion up to 0.0154 N m, at 0.5 mm along)" in capsys.readouterr().out
    report["cables"][0].update(max_twist=0.0, max_twist_moment=0.0)
    print_summary(report, Path("r.json"))
    out = capsys.readouterr().out
    assert "max twist 0 deg" in out and "torsion" not in out


def test_an_interrupted_run_says_so(capsys):
    report = _report([])
    report["complete"] = False
    print_summary(report, Path("r.json"))
    assert "INTERRUPTED" in capsys.readouterr().out


def test_the_sweep_table(capsys):
    report = {"scene": "demo", "part": "drawer", "direction": [1.0, 0.0, 0.0], "distance": 50.0,
              "units": "mm", "precision": 0.5, "hits": [{"part": "frame/stop", "distance": 12.25,
                                                         "where": [10.0, 0.0, 5.0]}],
              "overlapping": ["frame/rail"], "warnings": []}
    print_sweep(report, Path("s.json"))
    out = capsys.readouterr().out
    assert "frame/stop" in out and "12.25" in out and "(10.00, 0.00, 5.00)" in out
    assert "overlapping at the start: frame/rail" in out


@pytest.mark.parametrize("enabled", [True, False])
def test_progress_off_a_terminal_is_a_line_per_quarter(capsys, enabled):
    bar = ProgressBar(enabled=enabled)
    bar.tty = False
    for k in range(101):
        bar("settle", k, 100)
        bar("run", k, 100)
    bar.done()
    lines = capsys.readouterr().err.splitlines()
    assert lines == ([f"simulating: {p}%" for p in (0, 25, 50, 75, 100)] if enabled else [])


def test_a_runs_progress_says_simulated_time_rate_and_time_left(capsys, monkeypatch):
    """100 steps of 10 ms, a step every 0.1 s of wall clock (0.1x real time):
    past 2 s of running the line says where it is, how fast and how long is left."""
    clock = [0.0]
    monkeypatch.setattr(time, "monotonic", lambda: clock[0])
    bar = ProgressBar(enabled=True, timestep=0.01)
    bar.tty = False
    for k in range(101):
        clock[0] = 0.1 * k
        bar("run", k, 100)
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "simulating: 0%, t = 0 of 1 s"
    assert lines[2] == "simulating: 50%, t = 0.5 of 1 s, 0.1x real time, 5 s left"
    assert lines[-1] == "simulating: 100%, t = 1 of 1 s, 0.1x real time, 0 s left"


def test_a_run_stopped_before_its_first_step_prints_without_a_traceback(tmp_path: Path, capsys):
    """A stop asked while building or settling: the real report (no step
    checked, strain and bend unmeasured) prints as such."""
    from cablecheck.run.runner import RunOptions, run_scene
    from cablecheck.run.stop import StopRequest
    from cablecheck.scene.load import load_scene

    stop = StopRequest()
    stop.asked, stop.signal_name = True, "SIGINT"
    scene = load_scene(Path(__file__).resolve().parents[1] / "scenes" / "crossing.toml")
    report = run_scene(scene, RunOptions(report=tmp_path / "r.json", record=None), stop=stop)
    print_summary(report, tmp_path / "r.json")
    out = capsys.readouterr().out
    assert "INTERRUPTED" in out and out.count("no step checked") == len(report["cables"]) > 0
