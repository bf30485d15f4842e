"""Scale: harness-like scenes of 1-64 cables among 10-1,000 parts, side by side in one run.

Scenes come from :func:`cablecheck.bench.harness.harness_scene` (cables of ``--segments``
elements threaded through non-overlapping parts, a few within the
clearance, one carriage rising and falling once over the run; with
``--layout crossing`` the runs table's come from
:func:`cablecheck.bench.crossing.crossing_scene` instead: two families of
cables crossing and resting on each other among parts scattered at random,
a third of them with their bounding spheres within 6 mm of a route), settled for
``--settle`` seconds before t = 0 (default :data:`cablecheck.bench.harness.SETTLE`, which
brings the 64 x 1,000 harness to rest; ``--settle 0`` runs them from their
drooped routes, every cable falling into its sag over the first 0.2 s and
swinging after). Four tables and a profile, every number measured in this
run on this machine:

1. ``build``: the part set (surfaces, trees, probes) of N harness parts,
   built by this checkout and by ``--before`` (a git revision, exported to a
   temporary folder), each in its own process: seconds and peak resident
   memory (``ru_maxrss`` of the process, so the interpreter and imports are
   included: the ``import`` row is that baseline).
2. ``runs``: ``cablecheck run`` of each grid scene in its own process
   (address space capped by ``--mem-limit-gb``), by this checkout and by
   ``--before``: the report's ``timing``
   split into simulation / check / validation / recording per simulated
   second, peak resident memory, recording size per simulated second (and,
   with ``--rec-growth``, its growth per simulated second without what is
   written once: the same run cut at half the duration, subtracted).
3. ``queries``: the same cable-part state (t = 0) checked by the checker
   (``points`` and ``exact``), by MuJoCo's ``mj_collision`` on the detection
   model and by python-fcl (:func:`cablecheck.bench.fcl.fcl_queries`), each
   in one process per scene.
4. ``static``: a static check (dynamics and validation off, ``--static C,P``
   cables x parts, default 100 x 300) run by ``cablecheck run``, which then
   builds no MuJoCo model (every way into one raises in that process),
   beside the same scene run through a MuJoCo build, each in its own
   process; in the first process, on the same state, the checker's
   cable-part and cable-cable queries (``points``) beside python-fcl's
   (update + query), and their ratio.
5. ``profile`` (``--profile C P``): cProfile's top functions and
   tracemalloc's top allocation sites of one run.

Run: python benchmarks/bench_scale.py [--quick] [--cables 1,16,64] [--parts 10,100,1000]
       [--duration S] [--settle S] [--harness] [--tables build,runs,queries,static] [--static C,P]
       [--profile C P] [--out DIR] [--before REV] [--rec-growth]

``--quick`` runs a small subset (seconds to a minute). Timings depend on the
machine and its load: compare rows of one run, not runs of different days.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from relayout import export

REPO = Path(__file__).resolve().parents[1]

BEFORE = "99b3d34"
"""Default ``--before``: the last revision building part trees recursively in Python."""


PSS_EVERY = 0.25
"""Seconds between two samples of a child's memory (`_tree_pss_mb`)."""


def _tree_pss_mb(pid: int) -> float:
    """The proportional set size (MB) of process `pid` and its descendants
    now, from Linux's /proc (0 for what cannot be read): what they hold of
    the machine's memory together, each page shared between them counted
    once. A run whose simulation steps in a process of its own
    (`cablecheck.run.apart`) is two processes, and ``ru_maxrss`` gives the
    larger of the two, counting their shared pages in each: the sum of
    their resident sizes counts them twice."""
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        try:
            with open(f"/proc/{p}/smaps_rollup") as f:
                total += next(int(line.split()[1]) for line in f if line.startswith("Pss:"))
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children") as f:
                    todo += [int(c) for c in f.read().split()]
        except (OSError, ValueError, StopIteration):
            continue
    return total / 1024.0


def _child(args: list[str], env_path: Path, mem_gb: float, timeout: float
           ) -> tuple[int, float, float, str, str, float]:
    """Run ``python args`` with PYTHONPATH=env_path; (exit status, wall s, peak RSS MB, stdout, stderr,
    peak PSS MB of the child and its own children together, sampled every `PSS_EVERY` s)."""
    limit = int(mem_gb * 2 ** 30)

    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    env = dict(os.environ, PYTHONPATH=str(env_path))
    t0 = time.perf_counter()
    pss = 0.0
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen([sys.executable, *args], stdout=out, stderr=err, env=env,
                                preexec_fn=cap, cwd=str(env_path))
        try:
            while True:
                done, status, usage = os.wait4(proc.pid, os.WNOHANG)
                if done:
                    break
                pss = max(pss, _tree_pss_mb(proc.pid))
                time.sleep(PSS_EVERY)
        except KeyboardInterrupt:
            proc.kill()
            raise
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return proc.returncode, wall, usage.ru_maxrss / 1024.0, out.read(), err.read(), pss


# -- in-process modes (run in a child) ------------------------------------------------

def _mode_build(parts_file: str) -> None:
    """Build the part set of the parts in a JSON file (names, types, sizes in m); print JSON.
    Imports only ``checker`` (so that older revisions run it too)."""
    import numpy as np

    from cablecheck.checker.partset import PartSet
    from cablecheck.checker.shapes import Shape, ShapeType

    data = json.loads(Path(parts_file).read_text())
    shapes = [Shape(ShapeType(t), np.array(s)) for t, s in zip(data["types"], data["sizes"])]
    t0 = time.perf_counter()
    ps = PartSet.build(data["names"], shapes, tolerance=5e-4)
    dt = time.perf_counter() - t0
    print(json.dumps({"seconds": dt, "triangles": int(len(ps.tris)), "parts": len(shapes)}))


def _mode_queries(scene_path: str, repeat: int) -> None:
    """The checker, mj_collision and python-fcl on the same state; print JSON."""
    from cablecheck.bench.fcl import fcl_queries
    from cablecheck.bench.sim_tables import mujoco_side
    from cablecheck.checker.scene_state import CheckConfig
    from cablecheck.scene.load import load_scene

    scene = load_scene(scene_path)
    out = mujoco_side(scene, repeat)
    # python-fcl on the same cable-part (and cable-cable) queries of the same state
    from cablecheck.build.checkview import part_shapes
    from cablecheck.build.stages import build
    from cablecheck.checker.scene_state import PartState
    from cablecheck.run.loop import Simulation
    from cablecheck.run.stepcheck import cable_states

    built = build(scene, detect=False)
    sim = Simulation(built)
    sim.reset()
    state = sim.state(0, contacts=False)
    cables = cable_states(built, state.cables)
    parts = [PartState(p.name, sh, pose, p.keepout)
             for p, sh, pose in zip(built.parts, part_shapes(built), state.part_poses)]
    try:
        for method in ("points", "exact"):
            upd, qry, _ = fcl_queries(cables, parts, CheckConfig(method, scene.check.spacing,
                                                                 scene.check.clearance), 3)
            out[f"fcl_{method}"] = upd + qry
    except ImportError:
        out["fcl_points"] = out["fcl_exact"] = None
    print(json.dumps(out))


def _mode_static(scene_path: str, with_model: bool, repeat: int) -> None:
    """One static run; without ``with_model`` every way into a MuJoCo model
    raises, and the checker and python-fcl then answer the same queries on
    the run's state; print JSON."""
    import mujoco
    import numpy as np

    import cablecheck.run.runner
    from cablecheck.build.checkview import part_shapes
    from cablecheck.checker.interference import Checker
    from cablecheck.checker.scene_state import CheckConfig, PartState
    from cablecheck.run.runner import RunOptions, run_scene
    from cablecheck.scene.load import load_scene

    def refuse(*args, **kwargs):
        raise RuntimeError("a MuJoCo model was built for a static check")

    if with_model:
        cablecheck.run.runner.needs_model = lambda scene: True      # the run as it was: a MuJoCo build
    else:
        for owner, name in ((mujoco.MjSpec, "compile"), (mujoco.MjSpec, "from_string"),
                            (mujoco.MjSpec, "from_file"), (mujoco.MjModel, "from_xml_string"),
                            (mujoco.MjModel, "from_xml_path")):
            setattr(owner, name, refuse)
    scene = load_scene(scene_path)
    folder = Path(tempfile.mkdtemp(prefix="bench_scale_static_"))
    report = run_scene(scene, RunOptions(report=folder / "r.json", record=None))
    out = {"timing": report["timing"], "events": len(report["events"]), "pairs": len(report["pairs"])}
    if not with_model:
        from cablecheck.bench.fcl import fcl_queries
        from cablecheck.build.static import build_static
        from cablecheck.run.kinematic import KinematicSimulation
        from cablecheck.run.stepcheck import cable_states

        built = build_static(scene)
        run = KinematicSimulation(built)
        run.reset()
        state = run.state(0)
        cables = cable_states(built, state.cables)
        parts = [PartState(p.name, sh, pose, p.keepout)
                 for p, sh, pose in zip(built.parts, part_shapes(built), state.part_poses)]
        config = CheckConfig("points", scene.check.spacing, scene.check.clearance)
        checker = Checker(parts, config)
        times = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            checker.check(cables, state.part_poses)
            times.append(time.perf_counter() - t0)
        out["checker_points"] = float(np.median(times))
        out["n_points"] = int(sum(len(c.points) for c in cables))
        try:
            upd, qry, _ = fcl_queries(cables, parts, config, repeat)
            out["fcl_points"] = upd + qry
        except ImportError:
            out["fcl_points"] = None
    print(json.dumps(out))


def _mode_profile(scene_path: str, top: int) -> None:
    """cProfile and tracemalloc of one run; print both tops."""
    import cProfile
    import io
    import pstats
    import tracemalloc

    from cablecheck.run.runner import RunOptions, run_scene
    from cablecheck.scene.load import load_scene

    scene = load_scene(scene_path)
    folder = Path(tempfile.mkdtemp())
    opts = RunOptions(report=folder / "r.json", record=folder / "r.rrd")
    prof = cProfile.Profile()
    prof.enable()
    report = run_scene(scene, opts)
    prof.disable()
    s = io.StringIO()
    pstats.Stats(prof, stream=s).sort_stats("cumulative").print_stats(top)
    print("== cProfile, cumulative ==")
    print(s.getvalue())
    s = io.StringIO()
    pstats.Stats(prof, stream=s).sort_stats("tottime").print_stats(top)
    print("== cProfile, own time ==")
    print(s.getvalue())
    print("timing:", json.dumps(report["timing"]))
    # allocation sites at the traced peak: a snapshot whenever the traced memory
    # passes the last snapshot's by a tenth (at the run's progress calls)
    best = {"bytes": 0, "snap": None, "stage": ""}

    def progress(stage, done, total):
        cur = tracemalloc.get_traced_memory()[0]
        if cur > 1.1 * best["bytes"]:
            best.update(bytes=cur, snap=tracemalloc.take_snapshot(), stage=f"{stage} {done:.3g}/{total:.3g}")

    tracemalloc.start(1)
    run_scene(scene, opts, progress=progress)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    print(f"== tracemalloc (second run): peak traced {peak / 2 ** 20:.1f} MB; largest snapshot "
          f"{best['bytes'] / 2 ** 20:.1f} MB at '{best['stage']}', its top sites ==")
    if best["snap"] is not None:
        for st in best["snap"].statistics("lineno")[:top]:
            print(st)


# -- the tables ------------------------------------------------------------------------

def _table(title: str, cols: list[str], rows: list[list]) -> str:
    def fmt(v):
        if v is None:
            return "-"
        if isinstance(v, float):
            return f"{v:.3g}" if abs(v) < 1000 else f"{v:,.0f}"
        return str(v)

    cells = [[fmt(v) for v in r] for r in rows]
    width = [max(len(c), *(len(r[k]) for r in cells)) if cells else len(c) for k, c in enumerate(cols)]
    lines = [title, "  ".join(c.rjust(w) for c, w in zip(cols, width))]
    lines += ["  ".join(v.rjust(w) for v, w in zip(r, width)) for r in cells]
    return "\n".join(lines)


def _export(rev: str) -> Path:
    """The checker and sim packages of git revision ``rev`` in a temporary folder, importable there as
    ``cablecheck`` (a revision from before the move into stage packages rewritten: benchmarks/relayout.py)."""
    return export(REPO, rev, prefix="bench_scale_before_")


def build_table(parts: list[int], before: str | None, mem_gb: float) -> tuple[str, list[dict]]:
    trees = [("this checkout", REPO)]
    if before:
        trees.append((f"before ({before})", _export(before)))
    rows, found = [], []
    me = str(Path(__file__).resolve())
    for label, path in trees:
        code, wall, rss, out, err, _ = _child(["-c", "import numpy, scipy, trimesh"], path, mem_gb, 600)
        rows.append([label, "import", None, None, None, rss])
    from cablecheck.bench.harness import harness_scene

    for n in parts:
        data = harness_scene(64, n, duration=0.0, dynamics=False)
        spec = Path(tempfile.mkdtemp(prefix="bench_scale_parts_")) / "parts.json"
        spec.write_text(json.dumps({"names": [q["name"] for q in data["parts"]],
                                    "types": [q["shape"] for q in data["parts"]],
                                    "sizes": [[1e-3 * x for x in q["size"]] for q in data["parts"]]}))
        for label, path in trees:
            code, wall, rss, out, err, _ = _child([me, "--mode-build", str(spec)], path, mem_gb, 1800)
            if code == 0:
                res = json.loads(out.strip().splitlines()[-1])
                rows.append([label, res["parts"], res["triangles"], res["seconds"], wall, rss])
                found.append({"tree": label, **res, "peak_rss_mb": rss})
            else:
                last = (err.strip().splitlines() or ["?"])[-1]
                rows.append([label, n, None, f"failed ({code}): {last[:80]}", wall, rss])
    return _table("Part set build (harness parts, tolerance 0.5 mm), one process per row",
                  ["code", "parts", "triangles", "build_s", "process_s", "peak_rss_mb"], rows), found


def run_table(grid: list[tuple[int, int]], duration: float, segments: int, mem_gb: float, out: Path,
              validate: bool, before: str | None = None, growth_too: bool = False,
              settle: float = 0.0, layout: str = "lattice") -> tuple[str, list[dict]]:
    """Each grid scene run by this checkout and, with ``before``, by that git
    revision (the same scene file, one process each, rows side by side),
    settled ``settle`` seconds before t = 0 (not timed per simulated second:
    the report's timing starts after it). ``layout``: "lattice"
    (:func:`cablecheck.bench.harness.harness_scene`, each cable in its own
    channel) or "crossing" (:func:`cablecheck.bench.crossing.crossing_scene`,
    cables crossing and resting on each other among scattered parts)."""
    from cablecheck.bench.crossing import crossing_scene
    from cablecheck.bench.harness import harness_scene, write_scene

    make = (lambda c, p, **kw: crossing_scene(max(c, 2), p, **kw)) if layout == "crossing" else harness_scene

    trees = [("this checkout", REPO)]
    if before:
        trees.append((f"before ({before})", _export(before)))
    rows, found = [], []
    for c, p in grid:
        data = make(c, p, segments=segments, duration=duration, settle=settle)
        data["check"]["validate"] = validate
        scene = write_scene(data, out / f"{layout}_{c}x{p}.toml")
        for k, (label, path) in enumerate(trees):
            tag = "" if k == 0 else "_before"
            rep, rec = out / f"{layout}_{c}x{p}{tag}.json", out / f"{layout}_{c}x{p}{tag}.rrd"
            rep.unlink(missing_ok=True)
            code, wall, rss, so, se, pss = _child(["-m", "cablecheck.cli.main", "run", str(scene), "--report", str(rep),
                                              "--record", str(rec)], path, mem_gb, 3600)
            if code in (0, 1) and rep.exists():
                t = json.loads(rep.read_text())["timing"]
                per = 1.0 / duration
                size = rec.stat().st_size / 2 ** 20 if rec.exists() else None
                growth = _growth(data, size, duration, out / f"half_{c}x{p}{tag}", path, mem_gb) \
                    if (growth_too and size is not None) else None
                # check + validation + recording against the simulation, per step alike
                ratio = (t["check_s"] + t["validate_s"] + t["record_s"]) / t["sim_s"] if t["sim_s"] else None
                row = {"code": label, "cables": c, "parts": p, "settle_s": settle, "sim_s": t["sim_s"] * per,
                       "check_s": t["check_s"] * per, "validate_s": t["validate_s"] * per,
                       "record_s": t["record_s"] * per, "cvr_over_sim": ratio,
                       "total_s": t["total_s"] * per, "process_s": wall,
                       "peak_rss_mb": rss, "peak_pss_mb": pss,
                       "recording_mb_per_s": None if size is None else size * per,
                       "recording_growth_mb_per_s": growth}
                found.append(row)
                rows.append([label, c, p, row["sim_s"], row["check_s"], row["validate_s"], row["record_s"],
                             ratio, row["total_s"], wall, rss, pss, row["recording_mb_per_s"], growth])
            else:
                last = (se.strip().splitlines() or ["?"])[-1]
                rows.append([label, c, p, None, None, None, None, None, None, wall, rss, pss, None,
                             f"failed ({code}): {last[:80]}"])
                found.append({"code": label, "cables": c, "parts": p, "failed": last, "peak_rss_mb": rss,
                              "peak_pss_mb": pss})
    title = (f"Runs ({layout} layout): seconds per simulated second ({duration} s simulated after {settle} s of settling, "
             f"{segments} elements per cable, "
             f"validation {'on' if validate else 'off'}), one process per row, address space <= {mem_gb} GB")
    if growth_too:
        title += ("; rec_growth: the recording's growth per simulated second, (size - size of the same "
                  "run at half the duration) / (half the duration), without what is written once")
    title += ("; (c+v+r)/sim: check + validate + record over sim; peak_rss_mb: the larger process's "
              f"(ru_maxrss), peak_pss_mb: the run's processes together, sampled every {PSS_EVERY:g} s")
    return _table(title, ["code", "cables", "parts", "sim", "check", "validate", "record", "(c+v+r)/sim",
                          "total", "process_s",
                          "peak_rss_mb", "peak_pss_mb", "rec_mb_per_s", "rec_growth"], rows), found


def _growth(data: dict, size: float, duration: float, stem: Path, path: Path, mem_gb: float) -> float | None:
    """MB per simulated second by which the recording grows: the same scene
    run again for half the duration (validation off: it records nothing)."""
    from cablecheck.bench.harness import write_scene

    half = json.loads(json.dumps(data))
    half["scene"]["duration"] = 0.5 * duration
    half["check"]["validate"] = False
    scene = write_scene(half, stem.with_suffix(".toml"))
    rec = stem.with_suffix(".rrd")
    code, *_ = _child(["-m", "cablecheck.cli.main", "run", str(scene), "--report", str(stem.with_suffix(".json")),
                       "--record", str(rec)], path, mem_gb, 3600)
    if code not in (0, 1) or not rec.exists():
        return None
    return (size - rec.stat().st_size / 2 ** 20) / (0.5 * duration)


def query_table(grid: list[tuple[int, int]], segments: int, mem_gb: float, out: Path) -> tuple[str, list[dict]]:
    from cablecheck.bench.harness import harness_scene, write_scene

    rows, found = [], []
    me = str(Path(__file__).resolve())
    for c, p in grid:
        scene = write_scene(harness_scene(c, p, segments=segments, duration=1.0), out / f"query_{c}x{p}.toml")
        code, wall, rss, so, se, _ = _child([me, "--mode-queries", str(scene)], REPO, mem_gb, 3600)
        if code != 0:
            rows.append([c, p, None, None, None, None, None, None, None, f"failed: {(se.strip().splitlines() or ['?'])[-1][:80]}"])
            continue
        r = json.loads(so.strip().splitlines()[-1])
        found.append({"cables": c, "parts": p, **r})
        ms = lambda v: None if v is None else 1e3 * v
        rows.append([c, p, r["n_points"], ms(r["points"]), ms(r["exact"]), ms(r["mj_collision"]),
                     ms(r["detect"]), ms(r["fcl_points"]), ms(r["fcl_exact"]),
                     None if r["fcl_exact"] is None else r["fcl_exact"] / r["exact"]])
    return _table("Queries on one state (t = 0), ms: the checker, MuJoCo's mj_collision (detection model), "
                  "python-fcl (update + query)",
                  ["cables", "parts", "centres", "checker_points", "checker_exact", "mj_collision",
                   "mj_detect", "fcl_points", "fcl_exact", "fcl/exact"], rows), found


def static_table(cases: list[tuple[int, int]], segments: int, mem_gb: float, out: Path) -> tuple[str, list[dict]]:
    """Static checks (dynamics and validation off) without and with a MuJoCo
    model, and the checker beside python-fcl on the same state (see the
    module docstring)."""
    from cablecheck.bench.harness import harness_scene, write_scene

    rows, found = [], []
    me = str(Path(__file__).resolve())
    for c, p in cases:
        data = harness_scene(c, p, segments=segments, duration=0.0, dynamics=False)
        data["check"]["validate"] = False
        scene = write_scene(data, out / f"static_{c}x{p}.toml")
        res = {}
        for label, extra in (("no model", []), ("MuJoCo model", ["--with-model"])):
            code, wall, rss, so, se, _ = _child([me, "--mode-static", str(scene), *extra], REPO, mem_gb, 3600)
            if code != 0:
                rows.append([c, p, label, None, None, None, None, None, None, None, wall, rss,
                             f"failed: {(se.strip().splitlines() or ['?'])[-1][:80]}"])
                continue
            r = json.loads(so.strip().splitlines()[-1])
            res[label] = r
            t = r["timing"]
            fcl, chk = r.get("fcl_points"), r.get("checker_points")
            rows.append([c, p, label, t["total_s"], t["sim_s"], t["check_s"], r["events"],
                         None if chk is None else 1e3 * chk, None if fcl is None else 1e3 * fcl,
                         None if (fcl is None or chk is None) else fcl / chk, wall, rss, None])
        found.append({"cables": c, "parts": p, **{k.replace(" ", "_"): v for k, v in res.items()}})
    return _table("Static checks (dynamics and validation off, t = 0 only): the run with no MuJoCo model "
                  "beside the run through a MuJoCo build, one process each; total / sim (build and "
                  "preparing the checks) / check: the report's seconds; checker_ms: the checker's "
                  "cable-part and cable-cable queries (points) on the run's state, fcl_ms: python-fcl's "
                  "(update + query) on the same state, in the same process",
                  ["cables", "parts", "run", "total_s", "sim_s", "check_s", "events", "checker_ms",
                   "fcl_ms", "fcl/checker", "process_s", "peak_rss_mb", "note"], rows), found


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="a small subset")
    ap.add_argument("--cables", default=None, help="comma-separated cable counts (default 1,4,16,64)")
    ap.add_argument("--parts", default=None, help="comma-separated part counts (default 10,100,1000)")
    ap.add_argument("--build-parts", default=None, help="part counts of the build table (default 100,1000,3000)")
    ap.add_argument("--segments", type=int, default=40)
    ap.add_argument("--duration", type=float, default=None, help="simulated seconds (default 0.5; quick 0.1)")
    ap.add_argument("--settle", type=float, default=None,
                    help="seconds settled before t = 0 in the runs and the profile (default cablecheck.bench.harness.SETTLE)")
    ap.add_argument("--harness", action="store_true", help="also run the 64 x 1,000 harness scene")
    ap.add_argument("--layout", choices=("lattice", "crossing"), default="lattice",
                    help="the runs table's scenes: each cable in its own channel through a lattice of parts "
                         "(cablecheck.bench.harness), or two families crossing and resting on each other among "
                         "scattered parts (cablecheck.bench.crossing)")
    ap.add_argument("--rec-growth", action="store_true",
                    help="also run each scene for half the duration: the recording's growth per simulated second")
    ap.add_argument("--no-validate", action="store_true", help="runs without the MuJoCo comparison")
    ap.add_argument("--before", default=BEFORE, help="git revision for the build and run tables' 'before' rows ('' for none)")
    ap.add_argument("--tables", default="build,runs,queries,static", help="which tables (comma-separated)")
    ap.add_argument("--static", default="100,300", help="cables,parts of the static table's scene")
    ap.add_argument("--mem-limit-gb", type=float, default=8.0)
    ap.add_argument("--profile", nargs=2, type=int, metavar=("CABLES", "PARTS"), help="profile one run instead")
    ap.add_argument("--out", type=Path, default=REPO / "recordings" / "bench_scale")
    # modes of the child processes
    ap.add_argument("--mode-build", help=argparse.SUPPRESS)
    ap.add_argument("--mode-queries", help=argparse.SUPPRESS)
    ap.add_argument("--mode-profile", help=argparse.SUPPRESS)
    ap.add_argument("--mode-static", help=argparse.SUPPRESS)
    ap.add_argument("--with-model", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.mode_build:
        _mode_build(a.mode_build)
        return 0
    if a.mode_queries:
        _mode_queries(a.mode_queries, 3)
        return 0
    if a.mode_static:
        _mode_static(a.mode_static, a.with_model, 9)
        return 0
    if a.mode_profile:
        _mode_profile(a.mode_profile, 40)
        return 0
    sys.path.insert(0, str(REPO))            # the parent uses this checkout (children: PYTHONPATH)
    a.out.mkdir(parents=True, exist_ok=True)
    duration = a.duration if a.duration is not None else (0.1 if a.quick else 0.5)
    from cablecheck.bench.harness import SETTLE
    settle = SETTLE if a.settle is None else a.settle
    if a.profile:
        from cablecheck.bench.harness import harness_scene, write_scene
        c, p = a.profile
        data = harness_scene(c, p, segments=a.segments, duration=duration, settle=settle)
        data["check"]["validate"] = not a.no_validate
        scene = write_scene(data, a.out / f"profile_{c}x{p}.toml")
        code, wall, rss, so, se, _ = _child([str(Path(__file__).resolve()), "--mode-profile", str(scene)], REPO,
                                         a.mem_limit_gb, 3600)
        print(so)
        print(f"exit {code}, {wall:.1f} s, peak RSS {rss:.0f} MB (profiled; one run + one traced run)")
        if code:
            print(se[-3000:])
        return code
    ints = lambda s: [int(x) for x in s.split(",") if x]
    cables = ints(a.cables) if a.cables else ([1, 16] if a.quick else [1, 4, 16, 64])
    parts = ints(a.parts) if a.parts else ([10, 100] if a.quick else [10, 100, 1000])
    build_parts = ints(a.build_parts) if a.build_parts else ([100, 1000] if a.quick else [100, 1000, 3000])
    grid = [(c, p) for c in cables for p in parts]
    if a.harness:
        grid.append((64, 1000))
    results, texts = {}, []
    for name, fn in (("build", lambda: build_table(build_parts, a.before or None, a.mem_limit_gb)),
                     ("runs", lambda: run_table(grid, duration, a.segments, a.mem_limit_gb, a.out,
                                                not a.no_validate, a.before or None, a.rec_growth,
                                                settle, a.layout)),
                     ("queries", lambda: query_table(grid, a.segments, a.mem_limit_gb, a.out)),
                     ("static", lambda: static_table([tuple(ints(a.static))], a.segments, a.mem_limit_gb, a.out))):
        if name not in a.tables.split(","):
            continue
        text, found = fn()
        print(text + "\n", flush=True)
        texts.append(text)
        results[name] = found
    load = os.getloadavg()
    note = (f"machine: {os.cpu_count()} cores, load average {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f} "
            f"at the end; python {sys.version.split()[0]}")
    print(note)
    (a.out / "bench_scale.txt").write_text("\n\n".join(texts + [note]) + "\n")
    (a.out / "bench_scale.json").write_text(json.dumps(results, indent=1))
    print(f"written: {a.out / 'bench_scale.txt'}, {a.out / 'bench_scale.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
