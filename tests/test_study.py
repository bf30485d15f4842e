"""Tests of `cablecheck study`: the study file (paths, ranges, grid and zip, bad
input named by study file and key), free variants, and execution
(cablecheck.study.execute, cablecheck.study.plot) on an embedded local cluster and on a
scheduler with two workers started here on 127.0.0.1. The files that travel
with a task are tested in test_bundle, the length window in test_studyresult."""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from helpers import write_text

from cablecheck.checker.cable import TAUT_STRAIN
from cablecheck.cli.main import main
from cablecheck.scene.load import load_scene
from cablecheck.study.bundle import make_bundle
from cablecheck.study.definition import Mode, StudyError, check_variants, load_study, resolve, variants
from cablecheck.study.result import Row, Status, length_window, row_from_report

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
EXAMPLE = SCENES / "studies" / "drawer_length_study.toml"


def _study(tmp: Path, vary: str, head: str = "", scene: str = "drawer.toml") -> Path:
    """A study file in `tmp` on a copy of the drawer scene."""
    shutil.copy(SCENES / "drawer.toml", tmp / "drawer.toml")
    return write_text(tmp / "s.toml", f'[study]\nname = "s"\nscene = "{scene}"\n{head}\n{vary}')


# -- the study file -----------------------------------------------------------------------------

def test_paths_resolve_by_name_index_and_dotted_names():
    data = {"cables": [{"name": "power", "clips": [{"pos": [1, 2, 3]}, {"pos": [4, 5, 6]}]}],
            "parts": [{"name": "cabinet/rail.v2", "pos": [0, 0, 0]}],
            "motion": [{"body": "drawer", "keys": []}, {"joint": "elbow", "keys": []},
                       {"file": "pick.csv"}]}
    assert resolve(data, "cables.power.length") == (["cables", 0, "length"], "cables[0].length")
    assert resolve(data, "cables.power.clips.1.pos")[1] == "cables[0].clips[1].pos"
    assert resolve(data, "cables.power.clips.0.pos.2")[1] == "cables[0].clips[0].pos[2]"
    assert resolve(data, "parts.cabinet/rail.v2.pos")[1] == "parts[0].pos"   # a name with a dot
    assert resolve(data, "motion.elbow.time_scale")[1] == "motion[1].time_scale"
    assert resolve(data, "motion.drawer.time_scale")[1] == "motion[0].time_scale"
    assert resolve(data, "motion.pick.csv.time_scale")[1] == "motion[2].time_scale"
    assert resolve(data, "motion.2.time_scale")[1] == "motion[2].time_scale"
    assert resolve(data, "check.clearance") == (["check", "clearance"], "check.clearance")
    for key, words in (("cables.powr.length", "did you mean 'power'"),
                       ("cables.power.clips.5.pos", "past the end"),
                       ("cables.power.clips.0.pos.x", "give a 0-based index"),
                       ("cables.power", "is a table"),
                       ("cables..length", "empty step")):
        with pytest.raises(KeyError, match=words):
            resolve(data, key)


def test_ranges_grid_and_zip(tmp_path):
    path = _study(tmp_path, '[[vary]]\nkey = "cables.power.length"\nfrom = 600\nto = 700\ncount = 5\n'
                            '[[vary]]\nkey = "scene.settle"\nvalues = [0.5, 1.0]\n')
    study = load_study(path)
    assert study.mode is Mode.GRID
    assert study.vary[0].values == (600.0, 625.0, 650.0, 675.0, 700.0)
    found = variants(study)
    assert [v.values for v in found[:3]] == [(600.0, 0.5), (600.0, 1.0), (625.0, 0.5)]
    assert len(found) == 10 and [v.id for v in found] == [f"{k:03d}" for k in range(10)]
    assert found[3].data["cables"][0]["length"] == 625.0 and found[3].data["scene"]["settle"] == 1.0
    assert study.scene_data["cables"][0]["length"] == 650.0      # the scene itself is left alone
    scenes = check_variants(study, found)
    assert scenes[9].cables[0].length == pytest.approx(0.7) and scenes[9].settle == 1.0

    path = _study(tmp_path, '[[vary]]\nkey = "cables.power.length"\nvalues = [600, 700]\n'
                            '[[vary]]\nkey = "scene.settle"\nvalues = [0.5, 1.0]\n', 'mode = "zip"')
    assert [v.values for v in variants(load_study(path))] == [(600, 0.5), (700, 1.0)]
    path = _study(tmp_path, '[[vary]]\nkey = "cables.power.end.pos"\nfrom = [285, 0, 300]\n'
                            'to = [285, 0, 320]\ncount = 3\n')
    assert load_study(path).vary[0].values == ([285.0, 0.0, 300.0], [285.0, 0.0, 310.0],
                                               [285.0, 0.0, 320.0])


def test_time_scale_is_addressed_on_the_motion_entry(tmp_path):
    """`motion.<body>.time_scale` sets the key on that [[motion]] entry; the
    scene parser, not the study, decides whether it is accepted."""
    path = _study(tmp_path, '[[vary]]\nkey = "motion.drawer.time_scale"\nvalues = [0.5, 2.0]\n')
    study = load_study(path)
    assert study.vary[0].path == "motion[0].time_scale"
    found = variants(study)
    assert [v.data["motion"][0]["time_scale"] for v in found] == [0.5, 2.0]
    assert [s.motions[0].time_scale for s in check_variants(study, found)] == [0.5, 2.0]


@pytest.mark.parametrize("vary, head, key, words", [
    ('[[vary]]\nkey = "cables.hose.length"\nvalues = [600]\n', "", "vary[0].key",
     "no entry of cables named 'hose'"),
    ('[[vary]]\nkey = "cables.power.length"\n', "", "vary[0]", "give either 'values'"),
    ('[[vary]]\nkey = "cables.power.length"\nfrom = 600\nto = 700\ncount = 0\n', "",
     "vary[0].count", "positive integer"),
    ('[[vary]]\nkey = "cables.power.length"\nvalues = [600, 700]\n'
     '[[vary]]\nkey = "scene.settle"\nvalues = [1.0]\n', 'mode = "zip"', "vary[1]", "as many values"),
    ('[[vary]]\nkey = "cables.power.length"\nvalues = [600]\nstep = 5\n', "", "vary[0].step",
     "unknown key"),
    ('[[vary]]\nkey = "cables.power.length"\nvalues = [600]\n', 'mode = "all"', "study.mode",
     "'grid' or 'zip'"),
])
def test_bad_study_exits_2_naming_file_and_key(tmp_path, capsys, vary, head, key, words):
    path = _study(tmp_path, vary, head)
    assert main(["study", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{path}: {key}" in err and words in err and "Traceback" not in err
    assert not (tmp_path / "out" / "s").exists()


def test_bad_value_names_study_key_value_and_scene_problem(tmp_path, capsys):
    """A length shorter than the route (the ends are 325 mm apart) is refused
    before anything runs, naming the study file, the key, the value and the
    scene parser's complaint."""
    path = _study(tmp_path, '[[vary]]\nkey = "cables.power.length"\nvalues = [650, 300]\n'
                            '[[vary]]\nkey = "scene.settle"\nvalues = [1.0]\n')
    assert main(["study", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{path}: vary[0] cables.power.length = 300: scene " in err
    assert "cables[0].length: 300 mm is shorter than the route" in err
    assert "scene.settle" not in err          # the value to blame, not every value
    with pytest.raises(StudyError):
        check_variants(load_study(path), variants(load_study(path)))
    path = _study(tmp_path, '[[vary]]\nkey = "motion.drawer.tiem_scale"\nvalues = [2.0]\n')
    assert main(["study", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "vary[0] motion.drawer.tiem_scale = 2" in err and "motion[0].tiem_scale: unknown key" in err


def test_a_length_shorter_than_the_route_through_the_clips_is_refused(tmp_path, capsys):
    """The drawer's cable clipped at (100, 0, 450): its route runs 443.35 mm
    through the clip, though its ends are 325 mm apart. 400 mm passes the
    scene parser, and a run would take the route's length instead: refused
    before anything runs, naming the value; 450 mm is accepted."""
    path = _study(tmp_path, '[[vary]]\nkey = "cables.power.length"\nvalues = [450, 400]\n')
    scene = tmp_path / "drawer.toml"
    text = scene.read_text()
    start = 'start = { body = "world", pos = [-40, 0, 300] }\n'
    assert start in text
    scene.write_text(text.replace(start, start + 'clips = [ { body = "world", pos = [100, 0, 450] } ]\n'))
    assert main(["study", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{path}: vary[0] cables.power.length = 400: scene " in err and "Traceback" not in err
    assert "cables[0].length: 400 mm is shorter than the route through its clips at t = 0 (443.353 mm)" in err
    study = load_study(path)
    assert check_variants(study, variants(study)[:1])[0].cables[0].length == pytest.approx(0.45)


# -- execution ----------------------------------------------------------------------------------

TINY_VALUES = (600.0, 700.0)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """A short drawer scene with a mesh part (its file must travel) and a
    study of two lengths."""
    folder = tmp_path_factory.mktemp("tiny")
    text = (SCENES / "drawer.toml").read_text()
    text = text.replace("duration = 4.0", "duration = 0.3").replace("settle = 1.0", "settle = 0.1")
    text += ('\n[[parts]]\nname = "bracket"\nshape = "mesh"\nfile = "meshes/l_bracket.stl"\n'
             'pos = [200, -150, 20]\n')
    write_text(folder / "scene" / "tiny.toml", text)
    shutil.copytree(SCENES / "meshes", folder / "scene" / "meshes")
    values = ", ".join(f"{v:g}" for v in TINY_VALUES)
    study = write_text(folder / "tiny_study.toml", '[study]\nname = "tiny"\nscene = "scene/tiny.toml"\n'
                   f'[[vary]]\nkey = "cables.power.length"\nvalues = [{values}]\n')
    return study


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


SCHEDULER_ARGS = ("--host", "127.0.0.1", "--no-dashboard", "--dashboard-address", "127.0.0.1:0")
WORKER_ARGS = ("--host", "127.0.0.1", "--nthreads", "1", "--no-dashboard", "--dashboard-address", "127.0.0.1:0")
"""The README's: every socket on 127.0.0.1 (the HTTP servers too)."""


@pytest.fixture(scope="module")
def scheduler():
    """`dask scheduler` and two `dask worker` processes on 127.0.0.1 (as the README starts
    them, without the nanny), stopped afterwards."""
    from distributed import Client

    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    quiet = dict(env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    procs = [subprocess.Popen([sys.executable, "-m", "dask", "scheduler", *SCHEDULER_ARGS, "--port", str(port)],
                              **quiet)]
    try:
        procs += [subprocess.Popen([sys.executable, "-m", "dask", "worker", address, *WORKER_ARGS, "--no-nanny"],
                                   **quiet)
                  for _ in range(2)]
        deadline = time.monotonic() + 60
        while True:
            try:
                with Client(address, timeout="2s") as client:
                    client.wait_for_workers(2, timeout=max(1.0, deadline - time.monotonic()))
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.3)
        yield address
    finally:
        _stop(procs)


def _rows(folder: Path) -> list[dict]:
    with open(folder / "results.csv", newline="") as f:
        return list(csv.DictReader(f))


COMPARED = ("id", "cables.power.length", "status", "exit_status", "hard", "soft", "worst_distance",
            "max_strain", "min_bend_radius", "taut", "bend_violation", "agreement", "error")
"""Every results.csv column but the run time."""


@pytest.fixture(scope="module")
def local_run(tiny, tmp_path_factory):
    """The tiny study on the embedded cluster, its temporary folders in a
    folder of its own: empty again at the end."""
    import tempfile

    out = tmp_path_factory.mktemp("local")
    temp = tmp_path_factory.mktemp("temp")
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(tempfile, "tempdir", str(temp))
        assert main(["study", str(tiny), "--workers", "2", "--out", str(out), "--quiet"]) == 0
    # the embedded cluster's folder, with the variants', is gone; left: multiprocessing's folder of
    # this (pytest's) process, made when the first fork server here starts (this study's, unless an
    # earlier test's in the same worker started one before) and removed when the process exits
    assert not [p for p in temp.iterdir() if not p.name.startswith("pymp-")]
    return out / "tiny"


def test_local_cluster_writes_rows_reports_recordings_and_plot(local_run):
    rows = _rows(local_run)
    assert [float(r["cables.power.length"]) for r in rows] == list(TINY_VALUES)
    assert all(r["status"] == "done" and r["error"] == "" for r in rows)
    doc = json.loads((local_run / "study.json").read_text())
    assert doc["complete"] is True and doc["vary"][0]["scene_key"] == "cables[0].length"
    for r, d in zip(rows, doc["rows"]):
        report = json.loads(Path(d["report"]).read_text())
        assert Path(d["report"]).parent == local_run / "variants" / r["id"]
        assert report["recording"] == d["recording"] and Path(d["recording"]).stat().st_size > 0
        assert report["cables"][0]["length"] == pytest.approx(float(r["cables.power.length"]))
        assert d["values"] == {"cables.power.length": float(r["cables.power.length"])}
    assert (local_run / "study.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert doc["window"]["key"] == "cables.power.length"


def test_scheduler_with_two_workers_gives_the_same_rows(tiny, local_run, scheduler, tmp_path):
    assert main(["study", str(tiny), "--scheduler", scheduler, "--out", str(tmp_path),
                 "--quiet"]) == 0
    remote = _rows(tmp_path / "tiny")
    assert [{k: r[k] for k in COMPARED} for r in remote] == \
           [{k: r[k] for k in COMPARED} for r in _rows(local_run)]


def test_each_row_equals_running_that_variant_alone(tiny, local_run, tmp_path):
    rows = _rows(local_run)
    scene = tiny.parent / "scene" / "tiny.toml"
    for r in rows:
        alone = scene.with_name(f"alone_{r['id']}.toml")
        alone.write_text(scene.read_text().replace("length = 650.0",
                                                   f"length = {r['cables.power.length']}"))
        report = tmp_path / f"{r['id']}.json"
        status = main(["run", str(alone), "--report", str(report), "--no-record", "--quiet"])
        single = row_from_report(r["id"], (float(r["cables.power.length"]),),
                                 json.loads(report.read_text()))
        assert str(status) == r["exit_status"]
        for field in ("hard", "soft", "worst_distance", "max_strain", "min_bend_radius", "taut",
                      "bend_violation", "agreement"):
            value = getattr(single, field)
            text = "" if value is None else ("true" if value is True else "false" if value is False
                                            else repr(value) if isinstance(value, float) else str(value))
            assert text == r[field], field


def test_a_failing_variant_is_a_row_with_its_error(tiny, scheduler, tmp_path):
    """A variant whose task raises (here: its mesh did not travel with it)
    is a failed row; the other variant still runs."""
    from cablecheck.study.execute import VariantTask, run_variants

    study = load_study(tiny)
    found = variants(study)
    bundle, datas = make_bundle(study.scene_path, [v.data for v in found])
    broken = replace(bundle, files=tuple((n, b) for n, b in bundle.files if not n.endswith(".stl")))
    tasks = [VariantTask(id=v.id, data=d, record=False) for v, d in zip(found, datas)]
    datas[1]["parts"][-1]["file"] = "meshes/missing.stl"
    tasks[1] = VariantTask(id=found[1].id, data=datas[1], record=False)
    rows, complete = run_variants(tasks, {v.id: v.values for v in found}, broken, tmp_path,
                                  scheduler=scheduler)
    assert complete
    assert rows[0].status is Status.FAILED and "l_bracket.stl" in rows[0].error
    assert rows[1].status is Status.FAILED and "missing.stl" in rows[1].error
    rows, _ = run_variants(tasks[:1], {found[0].id: found[0].values}, bundle, tmp_path,
                           scheduler=scheduler)
    assert rows[0].status is Status.DONE


def test_spare_work_runs_once_on_a_thread_of_its_own_while_a_core_is_idle(tiny, scheduler, tmp_path,
                                                                          monkeypatch):
    """`spare` (a study's plot imports): once, on a daemon thread of its own, when fewer variants run
    than the machine has cores (three cores, two workers: from the start); on a machine of one core two
    workers never leave one idle: not at all."""
    import threading

    from cablecheck.study.execute import VariantTask, run_variants

    study = load_study(tiny)
    found = variants(study)
    bundle, datas = make_bundle(study.scene_path, [v.data for v in found])
    tasks = [VariantTask(id=v.id, data=d, record=False) for v, d in zip(found, datas)]
    values = {v.id: v.values for v in found}
    calls = []

    def spare():
        calls.append((threading.current_thread().name, threading.current_thread().daemon))

    def ran() -> list:
        for t in threading.enumerate():
            if t.name == "cablecheck-spare":
                t.join()
        return list(calls)

    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1, 2})
    rows, complete = run_variants(tasks, values, bundle, tmp_path, scheduler=scheduler, spare=spare)
    assert complete and all(r.status is Status.DONE for r in rows)
    assert ran() == [("cablecheck-spare", True)]
    calls.clear()
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0})
    rows, complete = run_variants(tasks, values, bundle, tmp_path, scheduler=scheduler, spare=spare)
    assert complete and ran() == []


def _largest_end_distance(scene) -> float:
    """The largest distance between the power cable's ends over the drawer's
    keyframes (scene units): the start rides on the world, the end on the
    drawer, which moves by translation only, piecewise linearly between keys,
    so the distance is largest at a key."""
    cable = scene.cables[0]
    start = np.asarray(cable.start.pos)
    (motion,) = scene.motions
    ends = np.array([np.asarray(k.pos) + np.asarray(cable.end.pos) for k in motion.keys])
    return float(np.max(np.linalg.norm(ends - start, axis=1))) / scene.scale


def test_example_window_matches_the_geometry(scheduler, tmp_path, capsys):
    """The example study (at half its count of lengths over the same range, for
    CI's time): a length shorter than the largest distance between the ends
    over the motion (less the 1 % allowance) must be taut, so the window cannot
    start below it; and the printed answer is the window."""
    text = EXAMPLE.read_text()
    assert 'scene = "../drawer.toml"' in text and "count = 8" in text
    path = write_text(tmp_path / "example.toml", text.replace('"../drawer.toml"', f'"{EXAMPLE.parent.parent}/drawer.toml"')
                      .replace("count = 8", "count = 4"))
    assert main(["study", str(path), "--scheduler", scheduler, "--out", str(tmp_path),
                 "--no-record"]) == 1
    printed = capsys.readouterr().out
    study = load_study(path)
    reach = _largest_end_distance(load_scene(study.scene_path))
    assert reach == pytest.approx(575.0)
    rows = [Row(id=r["id"], values=(float(r["cables.power.length"]),), status=Status(r["status"]),
                hard=int(r["hard"]), soft=int(r["soft"]), taut=r["taut"] == "true",
                bend_violation=r["bend_violation"] == "true")
            for r in _rows(tmp_path / study.name)]
    for r in rows:
        if r.values[0] < reach / (1 + TAUT_STRAIN):
            assert r.taut, r
    w = length_window(rows)
    assert w.exists and w.shortest >= reach / (1 + TAUT_STRAIN)
    assert f"recommended: {w.recommended:g} mm:" in printed
    assert f"window of cables.power.length: {w.shortest:g}" in printed


def test_ctrl_c_keeps_finished_variants(tiny, tmp_path):
    """SIGINT to the whole process group (as a terminal's Ctrl-C) once the
    first variant is in: the study cancels the rest, closes its cluster and
    writes the tables with what finished, marked incomplete; exit 130."""
    study = write_text(tmp_path / "s.toml", f'[study]\nname = "int"\nscene = "{tiny.parent}/scene/tiny.toml"\n'
                   'mode = "zip"\n[[vary]]\nkey = "scene.duration"\nvalues = [0.1, 60.0, 60.0]\n'
                   '[[vary]]\nkey = "cables.power.length"\nvalues = [650, 651, 652]\n')
    with _study_running([str(study), "--workers", "1", "--out", str(tmp_path / "out"), "--no-record"],
                        _env()) as proc:
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "INTERRUPTED" in out
    rows = _rows(tmp_path / "out" / "int")
    assert [r["status"] for r in rows] == ["done", "not run", "not run"]
    assert json.loads((tmp_path / "out" / "int" / "study.json").read_text())["complete"] is False


def _worker_sees(conn) -> None:
    """In a process forked from the fork server: what a worker starts with."""
    import signal as sig
    conn.send({k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "MALLOC_TRIM_THRESHOLD_")}
              | {"sigint_ignored": sig.getsignal(sig.SIGINT) == sig.SIG_IGN,
                 "runner_loaded": "cablecheck.run.runner" in sys.modules})
    conn.close()


def test_the_fork_server_gives_its_workers_dasks_environment_their_modules_and_no_ctrl_c():
    import multiprocessing

    from cablecheck.study import cluster
    before = dict(os.environ)
    if not cluster.start_forkserver():
        pytest.skip("no fork server on this platform")
    try:
        assert dict(os.environ) == before        # this process's environment as it was
        ctx = multiprocessing.get_context("forkserver")
        here, there = ctx.Pipe(duplex=False)
        p = ctx.Process(target=_worker_sees, args=(there,))
        p.start()
        seen = here.recv()
        p.join(30)
        assert seen == {"OMP_NUM_THREADS": "1", "MALLOC_TRIM_THRESHOLD_": "65536", "sigint_ignored": True,
                        "runner_loaded": True}
    finally:
        cluster._stop_forkserver()


def test_killing_the_embedded_clusters_only_worker_loses_no_variant(tiny, tmp_path):
    """The embedded cluster's worker is forked from its fork server
    (cablecheck.study.cluster.start_forkserver); killed (SIGKILL) mid-variant,
    its nanny starts another and every variant finishes; when the study
    ends, no process of it is left (the fork server is stopped with the
    cluster) and neither are its temporary folders."""
    import psutil

    study = write_text(tmp_path / "s.toml", f'[study]\nname = "kf"\nscene = "{tiny.parent}/scene/tiny.toml"\n'
                       'mode = "zip"\n[[vary]]\nkey = "scene.duration"\nvalues = [0.1, 0.5, 0.1]\n'
                       '[[vary]]\nkey = "cables.power.length"\nvalues = [650, 651, 652]\n')
    with _study_running([str(study), "--workers", "1", "--out", str(tmp_path / "out"), "--no-record"],
                        {**_env(), "TMPDIR": str(tmp_path)}) as proc:
        (server,) = [c for c in psutil.Process(proc.pid).children() if "forkserver" in " ".join(c.cmdline())]
        (worker,) = server.children()
        worker.kill()
        out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    rows = _rows(tmp_path / "out" / "kf")
    assert [r["status"] for r in rows] == ["done"] * 3 and all(r["error"] == "" for r in rows)
    assert not server.is_running() or server.status() == psutil.STATUS_ZOMBIE
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(("cablecheck-", "pymp-"))]


def test_a_search_answers_with_the_best_variant_and_its_margin(tiny, tmp_path, capsys):
    """A search over the tiny drawer's cable length that must never be
    taut and should be as short as possible: every run is kept, and the
    answer is the shortest run that is not taut, with its margin."""
    study = write_text(tmp_path / "s.toml", f'[study]\nname = "short"\nscene = "{tiny.parent}/scene/tiny.toml"\n'
                       '[[vary]]\nkey = "cables.power.length"\nfrom = 540\nto = 700\n'
                       '[[require]]\ntaut = false\n[goal]\nminimise = "length"\n'
                       '[search]\nmethod = "optimise"\nbudget = 4\n')
    assert main(["study", str(study), "--workers", "2", "--out", str(tmp_path), "--no-record",
                 "--fail-on", "never"]) == 0
    printed = capsys.readouterr().out
    rows = _rows(tmp_path / "short")
    assert len(rows) == 4 and all(r["status"] == "done" for r in rows)
    assert all(540 <= float(r["cables.power.length"]) <= 700 for r in rows)
    for r in rows:    # the margin: the strain left before taut, times the length
        report = json.loads((tmp_path / "short" / "variants" / r["id"] / "report.json").read_text())
        (cable,) = report["cables"]
        left = (TAUT_STRAIN - cable["max_strain"]) * cable["length"]
        assert float(r["margin: never taut"]) == pytest.approx(left)
        assert (r["satisfied"] == "true") == (left >= 0) == (not cable["taut"])
    kept = [r for r in rows if r["satisfied"] == "true"]
    shortest = min(kept, key=lambda r: float(r["cables.power.length"]))
    doc = json.loads((tmp_path / "short" / "study.json").read_text())
    assert doc["runs"] == 4 and doc["search"] == {"method": "optimise", "budget": 4}
    assert doc["best"]["id"] == shortest["id"] and doc["best"]["satisfied"] is True
    assert doc["best"]["values"] == {"cables.power.length": float(shortest["cables.power.length"])}
    assert doc["requirements"] == ["never taut"] and doc["goal"] == "least length"
    assert f"answer: cables.power.length = {float(shortest['cables.power.length']):.10g} keeps every requirement" \
        in printed


@pytest.mark.parametrize("vary, search, key, words", [
    ('key = "cables.power.length"\nvalues = [600, 700]', 'method = "optimise"\nbudget = 4', "vary[0].from", "missing"),
    ('key = "cables.power.length"\nfrom = 600\nto = 700\ncount = 3', 'method = "optimise"\nbudget = 4',
     "vary[0].count", "picks its own values"),
    ('key = "cables.power.length"\nfrom = 700\nto = 600', 'method = "optimise"\nbudget = 4', "vary[0].to", "above"),
    ('key = "cables.power.length"\nfrom = 600\nto = 700', 'method = "optimise"', "search.budget", "at least 2"),
    ('key = "cables.power.length"\nvalues = [600]', 'budget = 4', "search.budget", "only a search"),
    ('key = "cables.power.length"\nvalues = [600]', 'method = "bayes"', "search.method", "'optimise'"),
])
def test_a_bad_search_exits_2_naming_its_key(tmp_path, capsys, vary, search, key, words):
    path = _study(tmp_path, f"[[vary]]\n{vary}\n[search]\n{search}\n")
    assert main(["study", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert key in err and words in err and "Traceback" not in err


def test_a_requirement_naming_nothing_in_the_scene_exits_2(tmp_path, capsys):
    path = _study(tmp_path, '[[vary]]\nkey = "cables.power.length"\nvalues = [600]\n'
                            '[[require]]\nclearance = 5\nbetween = ["power", "drawr"]\n')
    assert main(["study", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "require[0].between" in err and "'drawr' names no cable or part" in err


# -- robust execution (issue 27 item 5) ----------------------------------------------------------

@contextmanager
def _study_running(args: list[str], env: dict, after: str = "variants: 1/3"):
    """`cablecheck study ARGS` in a session of its own (a signal to its
    group reaches no test), once its progress has said `after`; the whole
    session killed on leaving if it still runs."""
    proc = subprocess.Popen([sys.executable, "-m", "cablecheck.cli.main", "study", *args], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        for line in proc.stderr:
            if line.startswith(after):
                break
        yield proc
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def _env() -> dict:
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}


def _worker(address: str, tmp: Path) -> subprocess.Popen:
    """A `dask worker` without a nanny (a SIGKILL ends it for good), its temporary folder `tmp`."""
    return subprocess.Popen([sys.executable, "-m", "dask", "worker", address, *WORKER_ARGS, "--no-nanny"],
                            env={**_env(), "TMPDIR": str(tmp)}, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)


def _stop(procs: list[subprocess.Popen]) -> None:
    for p in reversed(procs):
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
    for p in procs:
        try:    # a worker without its nanny at times outlives SIGTERM (Dask's, not under test here)
            p.wait(timeout=1)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


def test_killing_the_only_worker_loses_no_variant(tiny, tmp_path):
    """A scheduler with one worker, killed (SIGKILL) once the first of three
    variants is in; a new worker joins: every variant finishes, as the
    embedded cluster gives it, and the killed worker's temporary folder is
    gone (the new worker, on the same machine, removes it). Before, the
    scene's files had been scattered to the dead worker alone and every
    remaining variant failed."""
    study = write_text(tmp_path / "s.toml", f'[study]\nname = "k"\nscene = "{tiny.parent}/scene/tiny.toml"\n'
                       '[[vary]]\nkey = "cables.power.length"\nvalues = [600, 650, 700]\n')
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    temp = tmp_path / "worker-tmp"
    temp.mkdir()
    procs = [subprocess.Popen([sys.executable, "-m", "dask", "scheduler", *SCHEDULER_ARGS, "--port", str(port)],
                              env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        procs.append(_worker(address, temp))
        proc = subprocess.Popen([sys.executable, "-m", "cablecheck.cli.main", "study", str(study), "--scheduler", address,
                                 "--out", str(tmp_path / "out"), "--no-record"], env=_env(),
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        procs.append(proc)
        for line in proc.stderr:
            if line.startswith("variants: 1/3"):
                break
        procs[1].kill()   # SIGKILL: the worker dies mid-variant, its temporary folder left behind
        procs[1].wait()
        procs.append(_worker(address, temp))
        out, err = proc.communicate(timeout=120)
    finally:
        _stop(procs)
    assert proc.returncode == 0, err
    rows = _rows(tmp_path / "out" / "k")
    assert [r["status"] for r in rows] == ["done"] * 3 and all(r["error"] == "" for r in rows)
    assert [r["cables.power.length"] for r in rows] == ["600", "650", "700"]
    assert not list(temp.glob("cablecheck-variant-*"))


def test_resume_keeps_finished_variants_and_gives_the_same_rows(tiny, local_run, scheduler, tmp_path):
    """A study stopped once its first variant is in (the others cancelled,
    or stopped where they run): no window and no recommendation; run again
    with --resume, only what had not finished runs, and the rows are those
    of the straight run; a variant whose scene changed since (its stored
    hash differs) runs again."""
    from cablecheck.cli.args import build_parser
    from cablecheck.cli.main import _cmd_study, version

    folder = tmp_path / "tiny"

    class StopOnceOneIsIn:   # as Ctrl-C would, once a variant's outputs are written
        signal_name = None

        @property
        def asked(self):
            return any(folder.glob("variants/*/variant.json"))

    args = build_parser(version()).parse_args(["study", str(tiny), "--scheduler", scheduler, "--out",
                                               str(tmp_path), "--quiet"])
    status = _cmd_study(args, StopOnceOneIsIn())
    doc = json.loads((folder / "study.json").read_text())
    finished = {r["id"]: (folder / "variants" / r["id"] / "report.json").stat().st_mtime_ns
                for r in doc["rows"] if r["status"] == "done"}
    assert finished and (status == 130) == (len(finished) < 2)   # usually 1 of 2: stopped
    if status == 130:
        assert doc["complete"] is False and doc["window"] is None and doc["best"] is None
    assert main(["study", str(tiny), "--scheduler", scheduler, "--out", str(tmp_path), "--quiet",
                 "--resume"]) == 0
    assert {i: (folder / "variants" / i / "report.json").stat().st_mtime_ns for i in finished} == finished
    assert [{k: r[k] for k in COMPARED} for r in _rows(folder)] == \
           [{k: r[k] for k in COMPARED} for r in _rows(local_run)]
    stored = folder / "variants" / "000" / "variant.json"
    stored.write_text(stored.read_text().replace('"scene_sha256": "', '"scene_sha256": "0'))
    kept = folder / "variants" / "000" / "report.json"
    before = kept.stat().st_mtime_ns
    done = (folder / "variants" / "001" / "report.json").stat().st_mtime_ns
    assert main(["study", str(tiny), "--scheduler", scheduler, "--out", str(tmp_path), "--quiet",
                 "--no-record", "--resume"]) == 0
    assert kept.stat().st_mtime_ns != before                          # its hash differed: run again
    assert not (folder / "variants" / "000" / "recording.rrd").exists()
    assert (folder / "variants" / "001" / "report.json").stat().st_mtime_ns == done
    assert [{k: r[k] for k in COMPARED} for r in _rows(folder)] == \
           [{k: r[k] for k in COMPARED} for r in _rows(local_run)]


@pytest.fixture()
def silent_port():
    """A port on 127.0.0.1 that accepts connections and never answers."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(8)
        yield s.getsockname()[1]


def test_bad_scheduler_addresses_exit_2_naming_the_option(tiny, tmp_path, capsys, monkeypatch, silent_port):
    import dask

    from cablecheck.study import cluster as studycluster

    monkeypatch.setattr(studycluster, "CONNECT_TIMEOUT_S", 1.0)
    for key in list(os.environ):
        if key.startswith("DASK_DISTRIBUTED__COMM__TLS"):
            monkeypatch.delenv(key)
    cases = [("foo", "no port"), ("http://127.0.0.1:8786", "not a Dask scheduler's"),
             ("tcp://127.0.0.1:99999", "not a number from 1 to 65535"),
             ("tcp://no-such-host.invalid:8786", "cannot be resolved"),
             ("tls://127.0.0.1:8786", "needs Dask's TLS configuration"),
             (f"tcp://127.0.0.1:{silent_port}", "no answer within 1 s")]
    with dask.config.set({"distributed.comm.tls.ca-file": None, "distributed.comm.tls.client.cert": None}):
        for address, words in cases:
            t0 = time.monotonic()
            assert main(["study", str(tiny), "--scheduler", address, "--out", str(tmp_path), "--quiet"]) == 2
            err = capsys.readouterr().err
            assert f"--scheduler {address!r}: " in err and words in err and "Traceback" not in err, err
            assert time.monotonic() - t0 < 8, address
    assert not (tmp_path / "tiny").exists()


def test_ctrl_c_while_connecting_is_honoured(tiny, tmp_path, silent_port):
    """A scheduler address that accepts and never answers: Ctrl-C ends the
    study at once (exit 130), within the connect timeout's 10 s."""
    proc = subprocess.Popen([sys.executable, "-m", "cablecheck.cli.main", "study", str(tiny), "--scheduler",
                             f"tcp://127.0.0.1:{silent_port}", "--out", str(tmp_path)], env=_env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().startswith("study tiny: ")   # connecting now
        time.sleep(0.5)
        t0 = time.monotonic()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=20)
        waited = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130 and "interrupted" in err and "Traceback" not in err, err
    assert waited < 5


def test_stale_temporary_folders_of_dead_processes_are_removed(tmp_path):
    from cablecheck.study.execute import TEMP_PREFIX, _host, remove_stale_temp

    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    mine = f"{TEMP_PREFIX}{_host()}-"
    (tmp_path / f"{mine}{dead.pid}-001-abc" / "scene").mkdir(parents=True)
    (tmp_path / f"{mine}{os.getpid()}-002-abc").mkdir()
    (tmp_path / f"{TEMP_PREFIX}otherhost-{dead.pid}-003-abc").mkdir()
    assert remove_stale_temp(tmp_path) == [tmp_path / f"{mine}{dead.pid}-001-abc"]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [f"{mine}{os.getpid()}-002-abc", f"{TEMP_PREFIX}otherhost-{dead.pid}-003-abc"])
