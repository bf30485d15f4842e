"""End-to-end tests of `cablecheck run`: outputs, exit codes, bad input, interruption."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from rerun.chunk import RrdReader

from cablecheck.cli.main import main
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import load_scene

ROOT = Path(__file__).resolve().parents[1]

SMALL = """
[scene]
name = "small"
units = "mm"
duration = 0.2
settle = 0.2

[effects]
contact = ["cable-structure"]

[[bodies]]
name = "slider"

[[parts]]
name = "frame/floor"
shape = "box"
size = [300, 100, 5]
pos = [150, 0, -5]

[[cables]]
name = "lead"
radius = 3.0
start = { pos = [0, 0, 100] }
end = { body = "slider", pos = [200, 0, 100] }
length = 260.0
segments = 12

[[motion]]
body = "slider"
keys = [ { t = 0.0, pos = [0, 0, 0] }, { t = 0.2, pos = [20, 0, 0] } ]
"""


@pytest.fixture
def small_scene(tmp_path: Path) -> Path:
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    return path


def test_run_writes_report_and_recording(small_scene: Path, tmp_path: Path, capsys):
    record = tmp_path / "out" / "small.rrd"
    code = main(["run", str(small_scene), "--record", str(record)])
    assert code == 0
    report = json.loads(record.with_suffix(".json").read_text())
    for key in ("schema", "scene", "units", "complete", "mujoco", "settings", "cables", "timing"):
        assert key in report
    assert report["schema"] == "cablecheck.report/1"
    assert report["complete"] is True and report["units"] == "mm"
    assert report["settings"]["steps"] == 100
    cable = report["cables"][0]
    assert cable["name"] == "lead"
    assert cable["length"] == pytest.approx(260.0, rel=1e-3)
    # 12 elements and, at each clamped end, the short held edge (cablecheck.build.cableplan.clamp_edges)
    assert len(cable["rest_points"]) == 15 and len(cable["final_points"]) == 15
    # the end rides the slider: it moved 20 mm in x
    assert cable["final_points"][-1][0] - cable["rest_points"][-1][0] == pytest.approx(20.0, abs=0.5)
    assert cable["rest_points"][0] == pytest.approx([0, 0, 100], abs=1e-6)
    assert abs(cable["max_strain"]) < 0.01
    assert report["recording"] == str(record)
    assert record.exists() and not list(record.parent.glob(".*.tmp"))
    out = capsys.readouterr().out
    assert "small: complete" in out and "cable lead" in out


def test_no_record_writes_only_the_report(small_scene: Path, tmp_path: Path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(small_scene), "--no-record", "--quiet"]) == 0
    assert (tmp_path / "recordings" / "small.json").exists()
    assert not list((tmp_path / "recordings").glob("*.rrd"))


@pytest.mark.parametrize("text, key", [
    (SMALL.replace("radius = 3.0", "radius = -3.0"), "cables[0].radius"),
    (SMALL.replace('units = "mm"', 'units = "inch"'), "scene.units"),
    (SMALL.replace('body = "slider", pos', 'body = "sled", pos'), "cables[0].end.body"),
    (SMALL + "\n[bogus]\nx = 1\n", "bogus"),
])
def test_bad_input_exits_2_naming_file_and_key(tmp_path: Path, text: str, key: str):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    proc = subprocess.run([sys.executable, "-m", "cablecheck.cli.main", "run", str(path), "--no-record"],
                          capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 2
    assert str(path) in proc.stderr and key in proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout
    assert not (tmp_path / "recordings").exists()


def test_missing_scene_file_exits_2(tmp_path: Path, capsys):
    assert main(["run", str(tmp_path / "nope.toml"), "--no-record"]) == 2
    assert "nope.toml" in capsys.readouterr().err


def test_bad_spacing_option_exits_2(small_scene: Path):
    with pytest.raises(SystemExit) as e:
        main(["run", str(small_scene), "--spacing", "-1"])
    assert e.value.code == 2


def test_interrupted_run_leaves_incomplete_report_and_readable_recording(small_scene: Path, tmp_path: Path):
    scene = load_scene(small_scene)
    record, report_path = tmp_path / "r.rrd", tmp_path / "r.json"
    report_path.write_text('{"old": true}')  # an earlier report is replaced only by a complete file

    def interrupt(stage, done, total):
        if stage == "run" and done >= 30:
            raise KeyboardInterrupt

    report = run_scene(scene, RunOptions(report=report_path, record=record), progress=interrupt)
    assert report["complete"] is False
    written = json.loads(report_path.read_text())
    assert written["complete"] is False and 30 <= written["settings"]["steps"] < 100
    assert record.exists()
    _assert_rrd_has(record, ["/world/cables/lead", "/world/parts/frame/floor"])


def _rerun_cli() -> str | None:
    exe = Path(sys.executable).with_name("rerun")
    return str(exe) if exe.exists() else shutil.which("rerun")


def _assert_rrd_has(path: Path, entities: list[str], timelines=("sim_time",)) -> None:
    """Open the recording with rerun's own loader (`rerun rrd print`) and look for entities."""
    exe = _rerun_cli()
    assert exe, "the rerun command ships with rerun-sdk"
    env = dict(os.environ, XDG_CONFIG_HOME=str(path.parent / ".xdg"))
    subprocess.run([exe, "analytics", "disable"], env=env, capture_output=True)
    verify = subprocess.run([exe, "rrd", "verify", str(path)], env=env, capture_output=True, text=True)
    assert verify.returncode == 0, verify.stderr
    printed = subprocess.run([exe, "rrd", "print", "-vv", str(path)], env=env,
                             capture_output=True, text=True)
    assert printed.returncode == 0, printed.stderr
    for entity in entities:
        assert entity in printed.stdout, f"{entity} missing from {path}"
    for timeline in timelines:
        assert timeline in printed.stdout


def test_recording_holds_parts_cables_and_series(small_scene: Path, tmp_path: Path):
    record = tmp_path / "small.rrd"
    assert main(["run", str(small_scene), "--record", str(record), "--quiet"]) == 0
    _assert_rrd_has(record, ["/world/cables/lead", "/world/parts/frame/floor",
                             "/cables/strain/lead", "/cables/bend_radius/lead"])


def test_recording_of_an_interfering_scene_holds_checks_and_events(tmp_path: Path):
    """scenes/drawer_pinch.toml: the drawer's back panel sweeps through a cable loop."""
    record = tmp_path / "pinch.rrd"
    assert main(["run", str(ROOT / "scenes" / "drawer_pinch.toml"), "--record", str(record),
                 "--quiet", "--fail-on", "never"]) == 0
    report = json.loads(record.with_suffix(".json").read_text())
    assert [(e["type"], e["a"], e["b"]) for e in report["events"]] == \
        [("cable-structure", "loop", "drawer/back")]
    _assert_rrd_has(record, [
        "/world/interference/cable-structure/loop/drawer_back",   # marker at the worst point
        "/checks/cable-structure/loop/drawer_back/distance",      # per-pair distance series
        "/validation/agreement",                                       # per-step agreement series
        "/world/mujoco_contacts",                                  # MuJoCo's contact points
        "/events",                                                 # event log entries
        "/world/parts/drawer/back", "/world/cables/loop",
        "TextLog",
    ])


@pytest.mark.parametrize("name", sorted(p.name for p in (ROOT / "scenes").glob("*.toml")))
def test_example_scenes_run(name: str, tmp_path: Path):
    path = ROOT / "scenes" / name
    if name == "robot_cell.toml":
        # its first 1.2 s, as tests/test_scenes.py runs it (benchmarks/bench_robot_cell.py runs all 5 s)
        shutil.copytree(ROOT / "scenes" / "robot_cell", tmp_path / "robot_cell")
        text = path.read_text()
        assert "duration = 5.0" in text
        path = tmp_path / name
        path.write_text(text.replace("duration = 5.0", "duration = 1.2"))
    code = main(["run", str(path), "--no-record", "--quiet",
                 "--report", str(tmp_path / "r.json"), "--fail-on", "never"])
    assert code == 0
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["complete"] and not report["warnings"]


def test_ctrl_c_leaves_incomplete_report_and_readable_recording(tmp_path: Path):
    """A real SIGINT to the command, as Ctrl-C sends it."""
    import signal
    import time

    scene = tmp_path / "long.toml"
    scene.write_text(SMALL.replace("duration = 0.2", "duration = 600.0"))
    record = tmp_path / "long.rrd"
    proc = subprocess.Popen([sys.executable, "-m", "cablecheck.cli.main", "run", str(scene), "--record", str(record)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 60
    while not list(tmp_path.glob(".long.rrd.*.tmp")) and time.monotonic() < deadline:
        time.sleep(0.1)
    time.sleep(1.0)  # let it simulate a while
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in out + err and "INTERRUPTED" in out
    report = json.loads(record.with_suffix(".json").read_text())
    assert report["complete"] is False and report["settings"]["steps"] > 0
    _assert_rrd_has(record, ["/world/cables/lead"])


def test_only_restricts_a_run_to_one_assembly(tmp_path: Path):
    """--only PATH: the cable against that assembly's parts; nothing else is checked."""
    # the arm's first 1.25 s: the hose on the forearm throughout and near the upper
    # arm from 1.12 s (its run of 3 s adds the shoulder's housing at 2.2 s)
    shutil.copy(ROOT / "scenes" / "arm.xml", tmp_path / "arm.xml")
    (tmp_path / "arm.toml").write_text((ROOT / "scenes" / "arm.toml").read_text().replace("duration = 3.0",
                                                                                         "duration = 1.25"))

    def events(scene: str, *extra: str) -> set:
        out = tmp_path / "r.json"
        path = tmp_path / scene if (tmp_path / scene).exists() else ROOT / "scenes" / scene
        main(["run", str(path), "--no-record", "--quiet", "--fail-on", "never",
              "--report", str(out), *extra])
        report = json.loads(out.read_text())
        assert report["validation"]["agreement"] >= 0.99
        return {(e["type"], e["a"], e["b"]) for e in report["events"]}

    assert events("keepout_bolt.toml", "--only", "plate") == {("keepout", "lead", "plate/bolt_wrench_space")}
    assert events("keepout_bolt.toml", "--only", "plate/base") == set()
    # mjcf bodies are assemblies too: each --only run keeps exactly that body's events.
    # With the cable physics of docs/physics.md the hose comes near the upper arm
    # only, with a single pair whose steps at the clearance's edge are a larger
    # share of the comparison: method exact (segment distances) leaves no
    # between-points disagreements there.
    everything = events("arm.toml", "--method", "exact")
    upper = events("arm.toml", "--only", "upper_arm", "--method", "exact")
    assert len(everything) == 2 and upper and upper == {e for e in everything if e[2] == "upper_arm/upper_link"}
    assert events("arm.toml", "--only", "forearm", "--method", "exact") == \
        {e for e in everything if e[2] == "forearm/fore_link"}


def test_only_unknown_assembly_exits_2(small_scene: Path, capsys):
    assert main(["run", str(small_scene), "--no-record", "--only", "nope"]) == 2
    assert "--only" in capsys.readouterr().err


def test_full_every_step_checks_and_compares_every_step(small_scene: Path, tmp_path: Path, capsys):
    fast, full = tmp_path / "fast.json", tmp_path / "full.json"
    assert main(["run", str(small_scene), "--no-record", "--report", str(fast)]) == 0
    out = capsys.readouterr().out
    assert main(["run", str(small_scene), "--no-record", "--full-every-step", "--report", str(full)]) == 0
    out_full = capsys.readouterr().out
    a, b = json.loads(fast.read_text()), json.loads(full.read_text())
    assert a["settings"]["advance"]["proven_clear_steps"] > 0 and "proven clear" in out
    assert b["settings"]["advance"] is None and "proven clear" not in out_full
    assert a["validation"]["compared_steps"] == b["validation"]["compared_steps"] == b["settings"]["checked_steps"]
    assert a["events"] == b["events"] and a["pairs"] == b["pairs"] and a["validation"] == b["validation"]


def test_ctrl_c_stops_after_the_batch_and_a_second_stops_at_once(small_scene: Path, tmp_path: Path):
    """SIGINT asks the run to stop: the states already simulated are checked
    and reported (the simulation, stepping ahead on its own, may have
    simulated them all by then); a second SIGINT raises at once (the batch
    is left out)."""
    import signal

    scene = load_scene(small_scene)
    sent = []
    # the handler the run found (Python's own; SIG_IGN where the tests were started in the
    # background of a shell without job control, which ignores SIGINT for them)
    found = signal.getsignal(signal.SIGINT)

    def once(stage, done, total):
        if stage == "run" and done >= 10 and not sent:
            sent.append(done)
            signal.raise_signal(signal.SIGINT)

    report = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None), progress=once)
    total = round(scene.duration / scene.timestep)
    assert report["complete"] is False and 10 <= report["settings"]["steps"] <= total
    assert report["settings"]["checked_steps"] == report["settings"]["steps"] + 1
    assert report["validation"]["compared_steps"] == report["settings"]["checked_steps"]
    assert signal.getsignal(signal.SIGINT) is found   # handler put back

    def twice(stage, done, total):
        if stage == "run" and done >= 10 and len(sent) < 3:
            sent.append(done)
            signal.raise_signal(signal.SIGINT)

    report = run_scene(scene, RunOptions(report=tmp_path / "b.json", record=None), progress=twice)
    assert report["complete"] is False and report["settings"]["steps"] < total


def _catches(pid: int, signum: int) -> bool:
    """Has process `pid` installed a handler for `signum` (Linux: SigCgt in /proc)?"""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("SigCgt:"):
            return bool(int(line.split()[1], 16) >> (signum - 1) & 1)
    return False


@pytest.mark.parametrize("delay", [0.0, 0.6, 2.5])
def test_sigterm_at_any_moment_leaves_incomplete_report_and_readable_recording(tmp_path: Path, delay: float):
    """SIGTERM (what `timeout` and schedulers send) while starting up (numpy, MuJoCo
    and the scene still loading), settling or simulating: exit 143, an incomplete
    report, a verified recording, no temp files. The delays count from the moment
    the command takes the signal (before that, Python itself is still starting)."""
    import signal
    import time

    scene = tmp_path / "long.toml"
    scene.write_text(SMALL.replace("duration = 0.2", "duration = 600.0").replace("settle = 0.2", "settle = 1.5"))
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "cablecheck.cli.main", "run", str(scene), "--record",
                             str(out / "long.rrd"), "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    deadline = time.monotonic() + 60
    while not _catches(proc.pid, signal.SIGTERM) and time.monotonic() < deadline:
        time.sleep(0.002)
    time.sleep(delay)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert "Traceback" not in err
    report = json.loads((out / "long.json").read_text())
    assert report["complete"] is False and report["interrupted"] == "SIGTERM"
    _assert_rrd_has(out / "long.rrd", [], timelines=())
    assert not [p for p in out.iterdir() if p.name.endswith(".tmp")]


@pytest.mark.parametrize("option", ["--report", "--record"])
def test_output_path_naming_a_folder_fails_before_running(small_scene: Path, tmp_path: Path, option, capsys):
    folder = tmp_path / "d"
    folder.mkdir()
    assert main(["run", str(small_scene), option, str(folder)]) == 2
    err = capsys.readouterr().err
    assert f"{option} {folder}: is a folder" in err and ".tmp" not in err
    assert list(folder.iterdir()) == [] and not (tmp_path / "recordings").exists()


def test_output_path_under_a_file_fails_before_running(small_scene: Path, tmp_path: Path, capsys):
    blocker = tmp_path / "afile"
    blocker.write_text("")
    assert main(["run", str(small_scene), "--report", str(blocker / "r.json"), "--no-record"]) == 2
    assert f"{blocker} is a file, not a folder" in capsys.readouterr().err


def test_version(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out.startswith("cablecheck ")


def test_check_validates_without_simulating(small_scene: Path, tmp_path: Path, capsys):
    assert main(["check", str(small_scene)]) == 0
    assert "valid scene 'small'" in capsys.readouterr().out
    bad = tmp_path / "bad.toml"
    bad.write_text(SMALL.replace("radius = 3.0", "radius = -3.0"))
    assert main(["check", str(bad)]) == 2
    assert "cables[0].radius" in capsys.readouterr().err


def test_event_positions_print_at_the_scene_units_precision_far_from_the_origin(tmp_path: Path, capsys):
    """12 km out in mm, %g would print 1.2e+07 for every place; fixed decimals keep 10 um."""
    far = SMALL.replace("[[cables]]", "[[parts]]\nname = \"post\"\nshape = \"box\"\nsize = [5, 50, 150]\n"
                        "pos = [100, 0, 0]\n\n[[cables]]")
    near, shifted = tmp_path / "near.toml", tmp_path / "far.toml"
    near.write_text(far)
    offset = 12_345_678.0
    text = far
    for old, new in (("pos = [150, 0, -5]", f"pos = [{150 + offset}, 0, -5]"),
                     ("pos = [100, 0, 0]", f"pos = [{100 + offset}, 0, 0]"),
                     ("start = { pos = [0, 0, 100] }", f"start = {{ pos = [{offset}, 0, 100] }}"),
                     ("name = \"slider\"\n", f"name = \"slider\"\npos = [{offset}, 0, 0]\n"),
                     ("pos = [0, 0, 0] }, { t = 0.2, pos = [20, 0, 0]",
                      f"pos = [{offset}, 0, 0] }}, {{ t = 0.2, pos = [{offset + 20}, 0, 0]")):
        assert old in text
        text = text.replace(old, new)
    shifted.write_text(text)
    assert main(["run", str(near), "--no-record", "--report", str(tmp_path / "n.json"), "--fail-on", "never"]) == 0
    out_near = capsys.readouterr().out
    assert main(["run", str(shifted), "--no-record", "--report", str(tmp_path / "f.json"),
                 "--fail-on", "never"]) == 0
    out_far = capsys.readouterr().out
    assert "cable-structure" in out_near and "e+07" not in out_far
    row = next(line for line in out_far.splitlines() if "post" in line and "cable-structure" in line)
    x = float(row.split("(")[1].split(",")[0])
    assert abs(x - offset) < 1000 and len(row.split("(")[1].split(",")[0].split(".")[1]) == 2


def test_the_console_script_exits_at_once_after_what_an_exit_must_do(tmp_path: Path):
    """`exit_at_once`: the status given, the standard streams flushed (a line without its newline
    too), a thread that is no daemon waited for, and the exit handlers run (one writes a file) before
    the process ends without the interpreter's teardown."""
    script = f"""
import atexit, sys, threading, time
from pathlib import Path
from cablecheck.cli.main import exit_at_once
atexit.register(lambda: Path({str(tmp_path / 'handler')!r}).write_text("ran"))
worker = threading.Thread(target=lambda: (time.sleep(0.3), Path({str(tmp_path / 'thread')!r}).write_text("done")))
worker.start()
print("no newline", end="")
print("on stderr", end="", file=sys.stderr)
exit_at_once(3)
print("never")
"""
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert proc.returncode == 3
    assert proc.stdout == "no newline" and proc.stderr == "on stderr"
    assert (tmp_path / "handler").read_text() == "ran" and (tmp_path / "thread").read_text() == "done"


def test_the_console_script_runs_a_scene_to_its_report(tmp_path: Path):
    """The installed entry point (`cablecheck.cli.main:console`) end to end: its exit status the
    command's, the report and the recording whole."""
    scene = tmp_path / "drawer.toml"
    scene.write_text((ROOT / "scenes" / "drawer_pinch.toml").read_text())
    proc = subprocess.run([sys.executable, "-c", "from cablecheck.cli.main import console; console()", "run",
                           str(scene), "--record", str(tmp_path / "d.rrd"), "--quiet"],
                          capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr                    # drawer_pinch has a hard event
    report = json.loads((tmp_path / "d.json").read_text())
    assert report["complete"] and report["summary"]["hard"] == 1
    assert [c.entity_path for c in RrdReader(tmp_path / "d.rrd").stream()]
