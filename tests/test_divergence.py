"""A run that diverges or fails says so (cablecheck.run.divergence, cablecheck.run.mjlog, cablecheck.run.runner, cablecheck.cli.main):
a metre scene with a millimetre value through the command line (exit 3,
`physics_error` naming time, cable and cause, no MUJOCO_LOG.TXT), MuJoCo's
instability warning named down to the cable vertex, the scan of a batch on
drawn states, the likely causes, an error forced into a run (exit 4, the
error in an incomplete report, a readable recording) and a sound scene not
flagged."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from cablecheck.build.stages import build
from cablecheck.cli.main import EXIT_DIVERGED, EXIT_ERROR, main
from cablecheck.run.divergence import Cause, DivergenceWatch, PhysicsError, Sign, likely_cause, unit_outliers
from cablecheck.run.loop import Simulation
from cablecheck.run.mjlog import MujocoMessages, message_kind, warning_counts
from cablecheck.scene.load import load_scene
from cablecheck.study.result import row_from_report
from tests.test_cli import SMALL, _assert_rrd_has
from tests.test_record import _rows

ROOT = Path(__file__).resolve().parents[1]

# SMALL in metres, the slider's key written in millimetres: it drags the
# cable's end 250 m in 0.2 s (meant: 250 mm). Today's code went NaN on it
# (MuJoCo's mjWARN_BADQACC at t = 0.109 s) and reported it complete.
UNITS_MIXED = """
[scene]
name = "units-mixed"
units = "m"
duration = 0.2
settle = 0.2

[effects]
contact = ["cable-structure"]

[[bodies]]
name = "slider"

[[parts]]
name = "frame/floor"
shape = "box"
size = [0.3, 0.1, 0.005]
pos = [0.15, 0, -0.005]

[[cables]]
name = "lead"
radius = 0.003
start = { pos = [0, 0, 0.1] }
end = { body = "slider", pos = [0.2, 0, 0.1] }
length = 0.26
segments = 12

[[motion]]
body = "slider"
keys = [ { t = 0.0, pos = [0, 0, 0] }, { t = 0.2, pos = [%s, 0, 0] } ]
"""


UNDAMPED = SMALL.replace("segments = 12\n", "segments = 12\ndamping = 0.0\n")


def _scene(tmp_path: Path, text: str, name: str = "scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_divergent_scene_exits_3_naming_time_cable_and_units(tmp_path: Path):
    scene = _scene(tmp_path, UNITS_MIXED % "250")
    report, record = tmp_path / "out" / "r.json", tmp_path / "out" / "r.rrd"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("CABLECHECK_TRACEBACK", None)
    done = subprocess.run([sys.executable, "-m", "cablecheck.cli.main", "run", str(scene), "--record", str(record),
                           "--report", str(report), "--quiet"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == EXIT_DIVERGED, done.stderr
    r = json.loads(report.read_text())
    assert r["complete"] is False and r["error"] is None
    e = r["physics_error"]
    assert e["cable"] == "lead" and 0 <= e["vertex"] <= 13
    assert 0.0 < e["t"] <= 0.2 and not e["settling"]
    assert e["sign"] in {s.value for s in Sign} and e["cause"] == "units"
    assert "motion[0]" in e["detail"] and "250" in e["detail"]
    # the run stopped at the divergence: nothing after it was checked
    assert r["settings"]["t_end"] < e["t"] and r["settings"]["steps"] < e["step"]
    assert "diverged" in done.stderr and "Traceback" not in done.stderr
    assert not list(tmp_path.rglob("MUJOCO_LOG.TXT"))
    # the recording is finished and says why it stopped, when
    (entry,) = [x for x in _rows(record, "/events") if "diverged" in x["TextLog:text"][0]]
    assert entry["TextLog:text"] == [e["message"]] and entry["TextLog:level"] == ["ERROR"]
    assert entry["t"] == pytest.approx(e["t"])
    assert e["message"] in _rows(record, "/summary")[0]["TextDocument:text"][0]
    row = row_from_report("v0", (250,), r)       # as a study's variant
    assert row.exit_status == EXIT_DIVERGED and row.error == e["message"]


@pytest.fixture
def log_file_on():
    """MuJoCo's default handler writes MUJOCO_LOG.TXT again for the test
    (the tests keep it off, tests/conftest.py)."""
    from cablecheck.run.mjlog import _set_log_file

    old = _set_log_file(True)
    yield
    _set_log_file(old)


def test_mujoco_instability_names_the_vertex_and_writes_no_log(tmp_path: Path, monkeypatch, log_file_on):
    """A NaN velocity injected into one cable vertex after settling: the
    simulation stops at the step MuJoCo finds it unstable (no reset to the
    routed shape), the scan names that cable vertex, the warnings are
    counted by kind and nothing is written to the working directory."""
    monkeypatch.chdir(tmp_path)
    # damping 0: the scene step in one simulation step (no damping need, cablecheck.build.substeps),
    # so the NaN has not spread along the cable when the scan reads it
    built = build(load_scene(_scene(tmp_path, UNDAMPED)), detect=False)
    with MujocoMessages() as messages:
        sim = Simulation(built)
        sim.reset()
        sim.settle()
        c = built.cables[0]
        body = int(built.model.flex_vertbodyid[c.vert_adr + 5])
        dof = int(built.model.body_dofadr[body])
        states = []
        for state in sim.steps(contacts=False):
            states.append(state)
            if state.step == 3:
                sim.data.qvel[dof] = np.nan
        counts = warning_counts([sim.data], messages)
    assert states[-1].unstable is not None and all(s.unstable is None for s in states[:-1])
    assert states[-1].step == 4 < sim.total_steps
    assert not np.isfinite(sim.data.qpos).all()          # left as it is, not reset
    found = DivergenceWatch(built, built.scene.settle).scan(states)
    assert found is not None and found[0] == len(states) - 1
    e = found[1]
    assert e.sign is Sign.UNSTABLE and e.warning.startswith("mjWARN_BADQ")
    assert (e.cable, e.vertex) == ("lead", 5) and e.t == pytest.approx(states[-1].t)
    assert counts.get(e.warning, 0) >= 1
    assert not list(tmp_path.glob("MUJOCO_LOG.TXT"))


def test_without_the_messages_taken_mujoco_writes_its_log(tmp_path: Path, monkeypatch, log_file_on):
    """The control of the test above: MuJoCo's default handler leaves the file."""
    monkeypatch.chdir(tmp_path)
    m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><body><freejoint/><geom size=".1"/></body>'
                                       '</worldbody></mujoco>')
    d = mujoco.MjData(m)
    d.qpos[0] = np.nan
    mujoco.mj_step(m, d)
    assert (tmp_path / "MUJOCO_LOG.TXT").exists()


class _State:
    """What the scan reads of a `cablecheck.run.loop.StepState`."""

    def __init__(self, step, t, cables, poses, qpos, unstable=None):
        self.step, self.t, self.cables, self.part_poses, self.qpos = step, t, cables, poses, qpos
        self.unstable = unstable


@pytest.fixture(scope="module")
def small_built(tmp_path_factory):
    return build(load_scene(_scene(tmp_path_factory.mktemp("small"), SMALL)), detect=False)


def _states(built, n: int, dt: float = 0.002) -> list:
    rest = [c.routed.copy() for c in built.cables]
    poses = np.tile(np.eye(4), (len(built.parts), 1, 1))
    # a slow sag: sound
    return [_State(k, k * dt, [p + [0.0, 0.0, -1e-4 * k] for p in rest], poses.copy(), np.zeros(built.model.nq))
            for k in range(n)]


@pytest.mark.parametrize("kind", ["nan", "far", "fast", "stretch"])
@pytest.mark.parametrize("at", [0, 3, 7])
def test_scan_finds_the_first_bad_state_and_vertex(small_built, kind: str, at: int):
    states = _states(small_built, 10)
    watch = DivergenceWatch(small_built, 0.2)
    assert watch.scan(states[:2]) is None               # sound, and remembered for speeds
    states = states[2:]
    n = small_built.cables[0].count
    v = 7
    if kind == "nan":
        states[at].cables[0][v, 1] = np.nan
    elif kind == "far":      # beyond ten times the scene's reach, at a sound speed over a long gap
        states[at].cables[0][v] += [0.0, 0.0, 1e4]
        for s in states[at:]:
            s.t += 1e3
    elif kind == "fast":     # the whole cable, within the reach but at 2 km/s
        states[at].cables[0][:] += [0.0, 0.0, 2000.0 * 0.002]
    else:                    # an element three and a half times its rest length, slowly
        states[at].cables[0][v + 1:] += [0.0, 3.5 * small_built.cables[0].element_length, 0.0]
        for s in states[at:]:
            s.t += 10.0
    later = states[at + 1:]
    for s in later:          # later states worse still: the first one is named
        s.cables[0][:] = np.nan
    found = watch.scan(states)
    assert found is not None
    k, e = found
    assert k == at and isinstance(e, PhysicsError) and e.cable == "lead"
    assert e.sign is {"nan": Sign.NON_FINITE, "far": Sign.FAR, "fast": Sign.FAST,
                      "stretch": Sign.STRETCHED}[kind]
    if kind == "fast":       # every vertex alike
        assert e.value == pytest.approx(2000.0, rel=1e-3)
    else:
        assert e.vertex == v
    assert 0 <= e.vertex < n and e.t == states[at].t


def test_scan_passes_sound_states_and_a_carried_cable(small_built):
    """A cable carried far by its held end (a long travel) is no runaway."""
    states = _states(small_built, 40)
    for s in states:
        s.cables[0] = s.cables[0] + [50.0 * s.t, 0.0, 0.0]   # 50 m/s, all of it
    watch = DivergenceWatch(small_built, 0.2)
    assert watch.scan(states[:20]) is None and watch.scan(states[20:]) is None


def test_likely_causes(tmp_path: Path):
    units = load_scene(_scene(tmp_path, UNITS_MIXED % "250", "u.toml"))
    built = build(units, detect=False)
    assert unit_outliers(units, built)[0][1].startswith("motion[0]")
    assert likely_cause(built, "lead")[0] is Cause.UNITS
    # 2 m in 4 ms, in proportion with the cable but faster than 64 substeps can follow
    fast = load_scene(_scene(tmp_path, (UNITS_MIXED % "2").replace("t = 0.2, pos", "t = 0.004, pos"), "f.toml"))
    built = build(fast, detect=False)
    assert built.substeps.capped and not unit_outliers(fast, built)
    cause, detail = likely_cause(built, "lead")
    assert cause is Cause.TELEPORT and "'slider'" in detail
    stiff = load_scene(_scene(tmp_path, (UNITS_MIXED % "0.02").replace(
        "segments = 12", "segments = 60\nyoung = 5e14").replace("settle = 0.2", "settle = 0.2\ntimestep = 0.01"),
        "s.toml"))
    built = build(stiff, detect=False)
    assert built.substeps.capped
    assert likely_cause(built, "lead")[0] is Cause.STIFFNESS
    sound = load_scene(_scene(tmp_path, SMALL, "ok.toml"))
    assert likely_cause(build(sound, detect=False), "lead")[0] is Cause.UNKNOWN


def test_message_kinds_and_handler_restored():
    assert message_kind(mujoco.mju_warningText(int(mujoco.mjtWarning.mjWARN_BADQACC), 12)
                        + " Time = 0.3093.") == "mjWARN_BADQACC"
    assert message_kind("Linesearch objective is not convex") == "Linesearch objective is not convex"
    assert message_kind("Something at 12 went 3.5e-3 wrong. Time = 1.0.") == "Something at # went # wrong."
    before, logged = mujoco.get_mju_user_warning(), mujoco.MjLogConfig.get().logto_file
    with MujocoMessages() as m:
        assert not mujoco.MjLogConfig.get().logto_file
        m._take("Linesearch objective is not convex")
        m._take("Linesearch objective is not convex")
    assert mujoco.get_mju_user_warning() is before and mujoco.MjLogConfig.get().logto_file == logged
    assert warning_counts([], m) == {"Linesearch objective is not convex": 2}


def test_forced_error_exits_4_with_the_error_in_an_incomplete_report(tmp_path: Path, monkeypatch, capsys):
    import cablecheck.run.stepcheck

    calls = []

    def boom(self, batch):
        calls.append(len(batch))
        if len(calls) == 2:
            raise IndexError("index 7 is out of bounds\n  for axis 0 with size 7")
        return real(self, batch)

    real = cablecheck.run.stepcheck.StepChecks.run
    monkeypatch.setattr(cablecheck.run.stepcheck.StepChecks, "run", boom)
    monkeypatch.delenv("CABLECHECK_TRACEBACK", raising=False)
    monkeypatch.chdir(tmp_path)
    scene = _scene(tmp_path, SMALL.replace("duration = 0.2", "duration = 1.0"))
    record, report = tmp_path / "r.rrd", tmp_path / "r.json"
    assert main(["run", str(scene), "--record", str(record), "--report", str(report), "--quiet"]) == EXIT_ERROR
    r = json.loads(report.read_text())
    assert r["complete"] is False and r["physics_error"] is None
    assert r["error"]["type"] == "IndexError" and "out of bounds" in r["error"]["message"]
    assert "Traceback" in r["error"]["traceback"] and "boom" in r["error"]["traceback"]
    assert r["settings"]["checked_steps"] == calls[0] and r["error"]["t"] == pytest.approx(r["settings"]["t_end"])
    err = capsys.readouterr().err
    assert "IndexError" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    _assert_rrd_has(record, ["/world/cables/lead"])
    failed = [x for x in _rows(record, "/events") if "the run failed: IndexError" in x["TextLog:text"][0]]
    assert len(failed) == 1 and failed[0]["t"] == pytest.approx(r["error"]["t"])
    assert not list(tmp_path.glob("MUJOCO_LOG.TXT"))


def test_error_before_any_step_exits_4_with_a_report(tmp_path: Path, monkeypatch, capsys):
    import cablecheck.run.runner

    def broken(*a, **k):
        raise RuntimeError("the model builder broke")

    monkeypatch.setattr(cablecheck.run.runner, "build_simulation", broken)
    monkeypatch.setenv("CABLECHECK_TRACEBACK", "1")
    report = tmp_path / "r.json"
    assert main(["run", str(_scene(tmp_path, SMALL)), "--no-record", "--report", str(report),
                 "--quiet"]) == EXIT_ERROR
    r = json.loads(report.read_text())
    assert r["complete"] is False and r["error"]["type"] == "RuntimeError"
    assert r["events"] == [] and r["settings"]["checked_steps"] == 0
    err = capsys.readouterr().err
    assert "Traceback" in err and "the model builder broke" in err     # asked for, with the env var


def test_error_before_any_step_is_printed_as_such(tmp_path: Path, monkeypatch, capsys):
    # without --quiet: the summary says where the run stopped, the error is one line (no KeyError
    # of a summary that looked for a last step)
    import cablecheck.run.runner

    def broken(*a, **k):
        raise RuntimeError("the model builder broke")

    monkeypatch.setattr(cablecheck.run.runner, "build_simulation", broken)
    monkeypatch.delenv("CABLECHECK_TRACEBACK", raising=False)
    report = tmp_path / "r.json"
    assert main(["run", str(_scene(tmp_path, SMALL)), "--no-record", "--report", str(report)]) == EXIT_ERROR
    out, err = capsys.readouterr()
    assert "FAILED (report marked incomplete) before its first step" in out and str(report) in out
    assert "RuntimeError: the model builder broke" in err and "KeyError" not in err + out
    assert "Traceback" not in err


def test_a_mujoco_of_another_major_version_is_named(tmp_path: Path, monkeypatch, capsys):
    # a package depending on `mujoco` 3.x replaces mujoco-core 4's module: the run says so, exit 4
    import mujoco
    monkeypatch.setattr(mujoco, "__version__", "3.17.0")
    monkeypatch.delenv("CABLECHECK_TRACEBACK", raising=False)
    report = tmp_path / "r.json"
    assert main(["run", str(_scene(tmp_path, SMALL)), "--no-record", "--report", str(report)]) == EXIT_ERROR
    err = capsys.readouterr().err
    assert "cablecheck needs MuJoCo 4" in err and "MuJoCo 3.17.0" in err and "Traceback" not in err
    assert json.loads(report.read_text())["complete"] is False


def test_bad_input_still_exits_2(tmp_path: Path, capsys):
    bad = _scene(tmp_path, SMALL.replace("radius = 3.0", "radius = -3.0"))
    assert main(["run", str(bad), "--no-record", "--report", str(tmp_path / "r.json")]) == 2
    assert "cables[0].radius" in capsys.readouterr().err
    assert not (tmp_path / "r.json").exists()


def test_sound_scene_is_not_flagged(tmp_path: Path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    report = tmp_path / "r.json"
    assert main(["run", str(_scene(tmp_path, SMALL)), "--no-record", "--report", str(report), "--quiet"]) in (0, 1)
    r = json.loads(report.read_text())
    assert r["complete"] is True and r["physics_error"] is None and r["error"] is None
    assert r["timing"]["divergence_s"] >= 0.0 and r["warnings"] == {}
    assert not list(tmp_path.glob("MUJOCO_LOG.TXT"))


def test_a_command_that_fails_prints_one_line_and_exits_4(tmp_path: Path, monkeypatch, capsys):
    import cablecheck.run.sweep

    def broken(*a, **k):
        raise ValueError("a bug, not an option")

    monkeypatch.setattr(cablecheck.run.sweep, "sweep_scene", broken)
    monkeypatch.delenv("CABLECHECK_TRACEBACK", raising=False)
    code = main(["sweep", str(_scene(tmp_path, SMALL)), "--part", "frame/floor", "--direction", "0,0,1",
                 "--distance", "10", "--report", str(tmp_path / "s.json")])
    err = capsys.readouterr().err
    assert code == EXIT_ERROR and "ValueError: a bug, not an option" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_run_stopped_by_mujocos_instability_counts_it(tmp_path: Path, monkeypatch, log_file_on):
    """End to end through the command: a NaN velocity left in one cable
    vertex after settling; MuJoCo finds the first step unstable, the run
    stops there (exit 3) with the warning named and counted, the rest
    state checked, and no MUJOCO_LOG.TXT although the default handler
    would write one."""
    import cablecheck.run.loop

    settle = cablecheck.run.loop.Simulation.settle

    def poisoned(self, *a, **k):
        settle(self, *a, **k)
        c = self.built.cables[0]
        self.data.qvel[int(self.model.body_dofadr[int(self.model.flex_vertbodyid[c.vert_adr + 5])])] = np.nan

    monkeypatch.setattr(cablecheck.run.loop.Simulation, "settle", poisoned)
    monkeypatch.chdir(tmp_path)
    report = tmp_path / "r.json"
    assert main(["run", str(_scene(tmp_path, UNDAMPED)), "--no-record", "--report", str(report),
                 "--quiet"]) == EXIT_DIVERGED
    r = json.loads(report.read_text())
    e = r["physics_error"]
    assert r["complete"] is False and e["sign"] == "mujoco-unstable"
    assert (e["cable"], e["vertex"], e["step"]) == ("lead", 5, 1) and e["t"] == pytest.approx(0.002)
    assert e["warning"].startswith("mjWARN_BADQ") and r["warnings"].get(e["warning"], 0) >= 1
    assert e["cause"] == "unknown"                     # nothing in the scene explains it
    assert r["settings"]["checked_steps"] == 1 and r["cables"][0]["rest_points"]
    assert not list(tmp_path.glob("MUJOCO_LOG.TXT"))


@pytest.mark.parametrize("sign", list(Sign))
def test_every_sign_has_its_one_line(sign: Sign):
    value = None if sign in (Sign.UNSTABLE, Sign.NON_FINITE) else 12.5
    warning = "mjWARN_BADQACC" if sign is Sign.UNSTABLE else None
    e = PhysicsError(-0.1, 0, True, sign, None, None, "slider", warning, value, Cause.TELEPORT, "too fast")
    line = e.message()
    assert "\n" not in line and "while settling (t = -0.1 s)" in line and "body 'slider'" in line
    assert line.endswith("likely cause: teleport: too fast")
    assert ("12.5" in line) == (value is not None) and ((warning or "") in line)


def test_error_on_the_simulation_thread_exits_4(tmp_path: Path, monkeypatch):
    """Raised while the simulation steps ahead on its own thread (cablecheck.run.ahead):
    handed to the run, which checks the states made before it and stops."""
    import cablecheck.run.loop

    state = cablecheck.run.loop.Simulation.state

    def broken(self, step, contacts):
        if step == 40:
            raise IndexError("a stock arm's mesh link")
        return state(self, step, contacts)

    monkeypatch.setattr(cablecheck.run.loop.Simulation, "state", broken)
    report = tmp_path / "r.json"
    assert main(["run", str(_scene(tmp_path, SMALL)), "--no-record", "--report", str(report),
                 "--quiet"]) == EXIT_ERROR
    r = json.loads(report.read_text())
    assert r["complete"] is False and r["error"]["type"] == "IndexError"
    assert "sim/run/loop.py" in r["error"]["traceback"] or "sim\\loop.py" in r["error"]["traceback"]
    assert r["settings"]["checked_steps"] <= 40 and r["settings"]["steps"] < 40


def test_a_held_end_pressed_into_a_part_of_another_body_is_named_as_the_cause(tmp_path):
    """`held_pinch` reads MuJoCo's own contacts: an end held on the slider inside a block on the world is
    named, with the block, its depth and the hold; the same block riding the slider (what the end is
    fastened to) is no pinch, nor is a block clear of the cable."""
    from buildscenes import slider_scene

    from cablecheck.build.stages import build
    from cablecheck.build.pinch import contacts_at, held_pinch
    from cablecheck.scene.load import parse_scene

    def pinch(block: dict):
        data = slider_scene(tmp_path)
        data["parts"] = [block]
        built = build(parse_scene(data, tmp_path / "s.toml"), detect=False)
        return held_pinch(built, contacts_at(built, built.qpos0), 0, None)

    found = pinch({"name": "frame/block", "shape": "box", "size": [0.03, 0.03, 0.03], "pos": [0.6, 0.0, 0.5]})
    assert found is not None and "held at vertex" in found and "(its end on 'slider')" in found
    assert "'frame/block'" in found and "pressed 0.0" in found
    assert pinch({"name": "frame/block", "body": "slider", "shape": "box", "size": [0.03, 0.03, 0.03],
                  "pos": [0.6, 0.0, 0.5]}) is None
    assert pinch({"name": "frame/block", "shape": "box", "size": [0.03, 0.03, 0.03],
                  "pos": [0.6, 0.0, 0.9]}) is None


def test_a_run_diverged_before_its_first_checked_state_is_judged_from_its_routed_start(tmp_path):
    """Settling that blows up leaves no sound state checked before the first
    diverged one: the routed start (`Built.qpos0`) is the last sound state,
    so an end held inside a part of another body is named as the cause
    there too (a route drawn through a robot's shoulder next to the hose's
    start diverged with cause unknown). The same block clear of the cable
    leaves the cause unknown."""
    from buildscenes import slider_scene

    from cablecheck.scene.load import parse_scene

    def first_state_stretched(block: dict):
        data = slider_scene(tmp_path)
        data["parts"] = [block]
        built = build(parse_scene(data, tmp_path / "s.toml"), detect=False)
        c = built.cables[0]
        near_end = c.count - 3                      # within the pinch's reach of the held end
        state = _states(built, 1)[0]
        state.cables[0][near_end + 1:] += [0.0, 3.5 * c.element_length, 0.0]
        found = DivergenceWatch(built, built.scene.settle).scan([state])
        assert found is not None and found[0] == 0
        e = found[1]
        assert e.sign is Sign.STRETCHED and (e.cable, e.vertex) == ("c", near_end)
        return e

    e = first_state_stretched({"name": "frame/block", "shape": "box", "size": [0.03, 0.03, 0.03],
                               "pos": [0.6, 0.0, 0.5]})
    assert e.cause is Cause.PINCHED
    assert "(its end on 'slider')" in e.detail and "'frame/block'" in e.detail
    e = first_state_stretched({"name": "frame/block", "shape": "box", "size": [0.03, 0.03, 0.03],
                               "pos": [0.6, 0.0, 0.9]})
    assert e.cause is Cause.UNKNOWN
