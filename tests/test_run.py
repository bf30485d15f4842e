"""One run end to end (cablecheck.run.runner): the report of small scenes with analytic
answers, complete and interrupted runs, the outputs left behind, and the
outcome record behind the report."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cablecheck.report.document import plain, report_of
from cablecheck.run.runner import RunOptions, run_outcome, run_scene
from cablecheck.run.stop import StopRequest
from cablecheck.scene.load import load_scene

# A block on a body moving straight down at SPEED onto a straight cable
# routed along x (no dynamics: the cable stays as routed). The block's bottom
# face starts at BOTTOM and spans x in [0.05, 0.15]; the cable's surface is
# at height + radius, so the surface distance is
#   d(t) = BOTTOM - SPEED t - (height + radius)
# while the bottom face is the block's nearest (a centreline below 0.02 m:
# the block is 0.02 m thick and ends 0.03 m lower).
PRESS = """
[scene]
name = "press"
units = "m"
duration = 0.2
settle = 0.0

[effects]
dynamics = false
contact = []

[check]
method = "{method}"
clearance = 0.005

[[bodies]]
name = "press"

[[parts]]
name = "press/block"
body = "press"
shape = "box"
size = [0.05, 0.05, 0.01]
pos = [0.1, 0, 0.05]

[[cables]]
name = "lead"
radius = {radius}
start = {{ pos = [0, 0, {height}] }}
end = {{ pos = [0.2, 0, {height}] }}
length = 0.2
segments = 20

[[motion]]
body = "press"
interpolation = "linear"
keys = [ {{ t = 0.0, pos = [0, 0, 0] }}, {{ t = 0.2, pos = [0, 0, -0.03] }} ]
"""
BOTTOM, SPEED, CLEARANCE, DT, STEPS = 0.04, 0.15, 0.005, 0.002, 100


def _press(tmp_path: Path, method: str = "points", height: float = 0.02, radius: float = 0.002):
    path = tmp_path / f"press-{method}.toml"
    path.write_text(PRESS.format(method=method, height=height, radius=radius))
    return load_scene(path)


def _text(report: dict) -> str:
    return json.dumps(plain({k: v for k, v in report.items() if k != "timing"}), indent=1)


def _first_step_below(value: float) -> float:
    """The first checked time at which d(t) < value (steps of DT)."""
    k = int(np.floor((BOTTOM - value) / SPEED / DT + 1e-9)) + 1
    return k * DT


@pytest.mark.parametrize("method", ["points", "exact"])
def test_block_pressing_on_a_cable_gives_the_analytic_event(tmp_path: Path, method: str):
    height, radius = 0.02, 0.002
    report = run_scene(_press(tmp_path, method, height, radius),
                       RunOptions(report=tmp_path / "r.json", record=None))
    assert report["complete"] is True and report["interrupted"] is None
    s = report["settings"]
    assert s["method"] == method and s["steps"] == STEPS and s["checked_steps"] == STEPS + 1
    assert s["t_end"] == pytest.approx(0.2) and s["spacing"] == pytest.approx(2 * radius)
    (event,) = report["events"]
    gap = BOTTOM - height - radius
    assert (event["type"], event["a"], event["b"]) == ("cable-structure", "lead", "press/block")
    assert (event["severity"], event["phase"]) == ("hard", "dynamic")
    assert event["t_start"] == pytest.approx(_first_step_below(height + radius + CLEARANCE))
    assert event["t_end"] == event["t_worst"] == pytest.approx(0.2)
    assert event["min_distance"] == pytest.approx(gap - SPEED * 0.2, abs=1e-9)
    assert 0.05 - 1e-9 <= event["where"][0] <= 0.15 + 1e-9 and event["where"][2] == pytest.approx(height)
    assert report["summary"] == {"hard": 1, "soft": 0, "static": 0, "dynamic": 1, "excused": 0}
    assert [(p["type"], p["min_distance"]) for p in report["pairs"]] == [
        ("cable-structure", pytest.approx(gap - SPEED * 0.2, abs=1e-9))]
    cable = report["cables"][0]
    assert cable["length"] == pytest.approx(0.2) and cable["segments"] == 22   # 20 + a held edge per clamp
    assert cable["max_strain"] == pytest.approx(0.0, abs=1e-9) and not cable["taut"]
    assert np.allclose(cable["rest_points"], cable["final_points"])            # routed, not stepped
    assert report["validation"]["agreement"] == 1.0
    # the file says what the run returned
    assert (tmp_path / "r.json").read_text() == json.dumps(plain(report), indent=1) + "\n"


@settings(max_examples=5, deadline=None)
@given(height=st.floats(0.005, 0.018), radius=st.floats(0.0005, 0.003))
def test_event_start_and_depth_follow_the_drawn_geometry(tmp_path_factory, height, radius):
    """Any cable height and radius under the press: the event starts at the
    first step within the clearance and ends as deep as the geometry says;
    hard from the step the surfaces meet."""
    tmp = tmp_path_factory.mktemp("press")
    report = run_scene(_press(tmp, "exact", height, radius), RunOptions(report=tmp / "r.json", record=None))
    (event,) = report["events"]
    gap = BOTTOM - height - radius
    assert event["t_start"] == pytest.approx(_first_step_below(height + radius + CLEARANCE), abs=1e-9)
    assert event["min_distance"] == pytest.approx(gap - SPEED * 0.2, abs=1e-9)
    assert event["severity"] == ("hard" if gap - SPEED * 0.2 < 0.0 else "soft")
    assert event["phase"] == ("static" if gap < CLEARANCE else "dynamic")


def test_stopped_run_reports_incomplete_and_leaves_no_temp_files(tmp_path: Path):
    """A stop asked (SIGTERM) after 30 steps: what was simulated is checked,
    the report says incomplete and names the signal, the recording is in
    place and nothing else is left in the folder."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "r.json").write_text('{"old": true}')
    stop = StopRequest()

    def progress(stage, done, total):
        if stage == "run" and done >= 30 and not stop.asked:
            stop.asked, stop.signal_name = True, "SIGTERM"

    report = run_scene(_press(tmp_path), RunOptions(report=out / "r.json", record=out / "r.rrd"),
                       progress=progress, stop=stop)
    written = json.loads((out / "r.json").read_text())
    assert written["complete"] is False and written["interrupted"] == "SIGTERM"
    assert 30 <= written["settings"]["steps"] < STEPS and written["events"] == []   # stopped before the press
    assert written["recording"] == str(out / "r.rrd")
    assert sorted(p.name for p in out.iterdir()) == ["r.json", "r.rrd"]
    assert _text(written) == _text(json.loads(json.dumps(plain(report))))


def test_stop_asked_before_the_start_runs_nothing_but_the_report(tmp_path: Path):
    stop = StopRequest()
    stop.asked, stop.signal_name = True, "SIGINT"
    report = run_scene(_press(tmp_path), RunOptions(report=tmp_path / "r.json", record=None), stop=stop)
    assert report["complete"] is False and report["interrupted"] == "SIGINT"
    assert report["settings"]["checked_steps"] == 0 and report["events"] == []
    cable = json.loads((tmp_path / "r.json").read_text())["cables"][0]
    assert cable["max_strain"] is None and cable["rest_points"] == [] and cable["final_points"] == []


def test_outcome_record_gives_the_report(tmp_path: Path):
    """`run_outcome` writes no report; its record gives the same report every
    time, and the same as `run_scene` on the same scene apart from timing."""
    scene = _press(tmp_path)
    outcome = run_outcome(scene, RunOptions(report=tmp_path / "never.json", record=None))
    assert not (tmp_path / "never.json").exists()
    first = json.dumps(plain(report_of(outcome)), indent=1)
    assert first == json.dumps(plain(report_of(outcome)), indent=1)
    assert outcome.complete and len(outcome.events) == 1 and outcome.checked == STEPS + 1
    report = run_scene(scene, RunOptions(report=tmp_path / "r.json", record=None))
    assert _text(report) == _text(report_of(outcome))


EXAMPLES = Path(__file__).resolve().parents[1] / "scenes"


@pytest.mark.parametrize("in_a_process", [True, False])
def test_simulating_ahead_gives_the_same_report(tmp_path: Path, monkeypatch, in_a_process: bool):
    """A dynamic scene with contact, validation and recording: stepping the
    simulation ahead in a process of its own (cablecheck.run.apart) or on a
    thread (cablecheck.run.ahead) gives the report of the run on one thread,
    timing apart."""
    import cablecheck.run.runner as runner

    monkeypatch.setattr(runner, "AHEAD_IN_A_PROCESS", in_a_process)
    scene = load_scene(EXAMPLES / "crossing.toml")
    one = run_scene(scene, RunOptions(report=tmp_path / "one.json", record=tmp_path / "one.rrd", overlap=False))
    two = run_scene(scene, RunOptions(report=tmp_path / "two.json", record=tmp_path / "two.rrd"))
    assert one["events"] and one["validation"]["compared_steps"] > 0
    assert _text(two) == _text(one).replace("one.rrd", "two.rrd")
    assert two["timing"]["sim_s"] > 0


def test_mujocos_messages_while_stepping_reach_the_report(tmp_path: Path, monkeypatch):
    """A message MuJoCo raises while the simulation steps in a process of its
    own (cablecheck.run.apart) is counted in the report's warnings, once."""
    import mujoco

    import cablecheck.run.loop as loop

    steps = loop.Simulation.steps

    def talking(self, *a, **k):
        for state in steps(self, *a, **k):
            if state.step == 3:
                mujoco.get_mju_user_warning()("Solver said 1.5 things. Time = 0.006.")
            yield state

    monkeypatch.setattr(loop.Simulation, "steps", talking)
    report = run_scene(load_scene(EXAMPLES / "crossing.toml"),
                       RunOptions(report=tmp_path / "r.json", record=None))
    assert report["complete"] and report["warnings"] == {"Solver said # things.": 1}


@pytest.mark.parametrize("how", ["complete", "stopped", "failed set-up"])
def test_the_set_ups_objects_are_left_out_of_collections_during_the_loop_alone(tmp_path: Path, monkeypatch,
                                                                              how: str):
    """The objects the set-up made (the models, parts, imports) are frozen out
    of Python's collections while the states are checked (gc.freeze: a full
    collection in the loop no longer traverses them all), and the youngest
    generation collected less often (LOOP_GC_YOUNG); both given back however
    the run ends: complete, stopped, or failed before its loop (a process
    running many scenes, a study's worker, collects as before)."""
    import gc

    import cablecheck.run.runner as runner

    scene = load_scene(EXAMPLES / "crossing.toml")
    frozen, check_batch = [], runner._check_batch

    def counting(*a, **k):
        frozen.append(gc.get_freeze_count())
        assert gc.get_threshold()[0] == runner.LOOP_GC_YOUNG
        return check_batch(*a, **k)

    monkeypatch.setattr(runner, "_check_batch", counting)
    stop = StopRequest()
    if how == "failed set-up":
        def failing(*a, **k):
            raise RuntimeError("no checks")
        monkeypatch.setattr(runner, "StepChecks", failing)

    def progress(stage, done, total):
        if how == "stopped" and stage == "run" and done >= 10:
            stop.asked = True

    assert gc.get_freeze_count() == 0
    before = gc.get_threshold()
    report = run_scene(scene, RunOptions(report=tmp_path / "r.json", record=None), progress=progress, stop=stop)
    assert gc.get_freeze_count() == 0 and gc.get_threshold() == before
    if how == "failed set-up":
        assert not frozen and report["complete"] is False and "no checks" in json.dumps(report["error"])
    else:
        assert frozen and min(frozen) > 10_000 and report["complete"] is (how == "complete")


def test_a_stopped_run_checks_every_step_simulated_ahead(tmp_path: Path):
    """A stop asked while the simulation runs ahead of the checks (it may
    have simulated them all by then): every step simulated is checked."""
    scene = load_scene(EXAMPLES / "crossing.toml")
    stop = StopRequest()

    def progress(stage, done, total):
        if stage == "run" and done >= 30 and not stop.asked:
            stop.asked, stop.signal_name = True, "SIGINT"

    report = run_scene(scene, RunOptions(report=tmp_path / "r.json", record=None), progress=progress, stop=stop)
    assert report["complete"] is False and report["interrupted"] == "SIGINT"
    steps = report["settings"]["steps"]
    assert 30 <= steps <= round(scene.duration / scene.timestep)
    assert report["settings"]["checked_steps"] == steps + 1


@pytest.mark.parametrize("method", ["points", "exact"])
def test_a_clear_run_reports_its_closest_approach(tmp_path: Path, method: str, capsys):
    # the block stops 8 mm above the cable's surface at t = 0.2 s: no event,
    # its closest approach there, in closed form
    height, radius = 0.0, 0.002
    report = run_scene(_press(tmp_path, method, height, radius), RunOptions(report=tmp_path / "r.json", record=None))
    assert report["events"] == []
    closest = report["closest"]
    assert closest["reach"] == pytest.approx(3 * CLEARANCE)
    (pair,) = closest["pairs"]
    gap = BOTTOM - SPEED * 0.2 - height - radius
    assert (pair["type"], pair["a"], pair["b"]) == ("cable-structure", "lead", "press/block")
    assert pair["min_distance"] == pytest.approx(gap, abs=1e-9) and pair["t"] == pytest.approx(0.2)
    assert 0.05 - 1e-9 <= pair["where"][0] <= 0.15 + 1e-9 and pair["s"] == pytest.approx(pair["where"][0])
    (cable,) = closest["cables"]
    assert (cable["cable"], cable["other"], cable["min_distance"]) == ("lead", "press/block", pair["min_distance"])


def test_a_run_farther_than_the_reach_says_nothing_came_near(tmp_path: Path):
    report = run_scene(_press(tmp_path, "points", -0.03, 0.002), RunOptions(report=tmp_path / "r.json", record=None))
    assert report["closest"]["pairs"] == []
    assert report["closest"]["cables"] == [{"cable": "lead", "other": None, "type": None, "min_distance": None,
                                            "t": None, "s": None}]
