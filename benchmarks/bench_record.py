"""Recording cost per step on the example scenes, this checkout against revisions, side by side.

Every example scene (``scenes/*.toml``) is run with ``cablecheck run
--record`` in its own process (a fresh interpreter each time, as a user
runs it: one-time costs such as lazy imports count), in turn by this
checkout and by each ``--before`` revision (exported to a temporary
folder), ``--repeat`` times each. Per scene and code the table gives:

- ``rec``: the report's ``timing.record_ms_per_step``, the recording's
  whole wall time in the run's `record` stage (every frame and the close,
  which sends the buffered columns, the blueprint and finishes the file)
  per checked step; split into ``close`` (ms, once per run: the fixed
  part) and ``frame`` (the rest per checked step);
- ``open``: ms spent opening the recording and logging the static scene
  (the recorder's constructor and ``log_static``), which the run's stages
  leave out of ``record`` (the constructor is not timed, the static scene
  falls in ``check``), stated so that nothing moved there goes unseen;
- ``sim``: ``timing.sim_ms_per_step`` (MuJoCo's per step: stepping only,
  building its model is left out);
- ``build``: ms spent building the MuJoCo models (`cablecheck.build.stages.build`, or its
  halves `build_simulation` and `with_detection` since 5974050, once per run),
  MuJoCo's own fixed cost, beside the recording's (open + close);
- ``ratio`` = rec / sim (the close spread over the run's steps),
  ``frame_ratio`` = frame / sim (per step, both sides without their
  once-per-run costs), and ``with_open`` = (record + open) / sim over the
  run;
- ``cpu_ratio``: rec / sim in CPU time (the process's, all threads, per
  run stage), which the machine's load moves much less than wall time;
- ``mb``: the recording's size.

Times are each the best (lowest) of the repeats; ``cpu_ratio`` the median.
The target: recording at most half of MuJoCo's time per step on every
scene, and no more per step than before the clash review (``c5dc43e``).
Both verdicts are printed: per step (``frame_ratio <= 0.5``) and with the
close spread over the steps (``ratio <= 0.5``), which a short scene misses
by its fixed close alone.

``--harness D1,D2`` measures instead the recording's size on the harness
scene (``cablecheck.bench.harness``: 64 cables among 1,000 parts), run by this checkout
for each duration D (simulated seconds, one process each): the file's size,
its size per simulated second and its growth per simulated second between
consecutive durations (what is written once, such as the parts' shapes and
one chunk per entity with its schema, drops out of the growth).

Run: python benchmarks/bench_record.py [--before REV[,REV]] [--repeat N] [--scenes a,b] [--out DIR]
     python benchmarks/bench_record.py --harness 1,2 [--out DIR]

Timings depend on the machine and its load: compare rows of one run, not
runs of different days.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from cablecheck.bench.table import text_table
from relayout import export

REPO = Path(__file__).resolve().parents[1]
BEFORE = "c5dc43e,ab65c56"
"""Default ``--before``: the recording before the clash review and wear map
(``c5dc43e``: what "no more per step than today" compares with), and with them
before its cost was first cut (``ab65c56``: pyarrow's compute module imported
for the wear bar charts, lanes and log entries logged row by row)."""


def _export(rev: str) -> Path:
    """The checker and sim packages of git revision ``rev`` in a temporary folder, importable there as
    ``cablecheck`` (a revision from before the move into stage packages rewritten: benchmarks/relayout.py)."""
    return export(REPO, rev, prefix="bench_record_before_")


_CHILD = """
import json, sys, time
import cablecheck.run.runner
from cablecheck.cli.main import main
try:
    from cablecheck.record.recorder import Recorder as R
except ModuleNotFoundError:     # a revision whose recorder was the single module sim/record.py
    from cablecheck.record import Recorder as R
cpu, wall = {}, {"open": 0.0, "close": 0.0, "build": 0.0}
Timer = cablecheck.run.runner._Timer
lap = Timer.lap
def timed(self, stage):
    now = time.process_time()
    cpu[stage] = cpu.get(stage, 0.0) + now - getattr(self, "_cpu", now)
    self._cpu = now
    lap(self, stage)
Timer.lap = timed
if hasattr(Timer, "skip"):
    skip = Timer.skip
    def skipped(self):
        self._cpu = time.process_time()
        skip(self)
    Timer.skip = skipped
def clock(part, f):
    def clocked(*a, **k):
        t = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            wall[part] += time.perf_counter() - t
    return clocked
R.__init__, R.log_static, R.close = clock("open", R.__init__), clock("open", R.log_static), clock("close", R.close)
for name in ("build", "build_simulation", "with_detection"):    # one build, or the two halves (since 5974050)
    if hasattr(cablecheck.run.runner, name):
        setattr(cablecheck.run.runner, name, clock("build", getattr(cablecheck.run.runner, name)))
code = main(sys.argv[1:])
print(json.dumps({"cpu": cpu, "wall": wall}))
sys.exit(code)
"""
"""The child: ``cablecheck`` with the run's stage timer also adding up CPU
time per stage, and the recorder's opening (its constructor and the static
scene, which the run's `record` stage does not count) and closing timed,
and MuJoCo's model build (once per run, in no stage; since 5974050 the
run's `build_simulation` and `with_detection` together) beside them."""


def _run(scene: Path, tree: Path, out: Path) -> dict | None:
    """One recorded run of `scene` by the code in `tree`: its timing and recording size, or None."""
    report, record = out / f"{scene.stem}.json", out / f"{scene.stem}.rrd"
    report.unlink(missing_ok=True)
    # -P and the tree as the working folder: `cablecheck` comes from PYTHONPATH, never from the
    # folder the benchmark was started in
    proc = subprocess.run([sys.executable, "-P", "-c", _CHILD, "run", str(scene), "--report", str(report),
                           "--record", str(record), "--quiet", "--fail-on", "never"],
                          cwd=tree, env=dict(os.environ, PYTHONPATH=str(tree)), capture_output=True, text=True,
                          check=False)
    if proc.returncode != 0 or not report.exists():
        print(f"{scene.stem} failed ({proc.returncode}): {(proc.stderr.strip().splitlines() or ['?'])[-1]}")
        return None
    t = json.loads(report.read_text())["timing"]
    child = json.loads(proc.stdout.strip().splitlines()[-1])
    cpu, wall = child["cpu"], child["wall"]
    steps = t["record_s"] * 1e3 / t["record_ms_per_step"] if t["record_ms_per_step"] else 0
    return {"rec": t["record_ms_per_step"], "sim": t["sim_ms_per_step"], "close": wall["close"] * 1e3,
            "frame": (t["record_s"] - wall["close"]) * 1e3 / steps if steps else None,
            "open": wall["open"] * 1e3, "build": wall.get("build", 0.0) * 1e3, "with_open": (t["record_s"] + wall["open"]) / t["sim_s"],
            "cpu_ratio": cpu.get("record", 0.0) / cpu["sim"] * t["sim_s"] / t["record_s"]
            * t["record_ms_per_step"] / t["sim_ms_per_step"] if t["record_s"] and cpu.get("sim") else None,
            "mb": record.stat().st_size / 2 ** 20}


COLUMNS = ("rec", "close", "frame", "open", "build", "sim", "ratio", "frame_ratio", "with_open", "cpu_ratio", "mb")


def harness(durations: list[float], out: Path) -> str:
    """The harness scene's recording size per simulated second (see the module docstring)."""
    from cablecheck.bench.harness import harness_scene, write_scene

    rows, sizes = [], {}
    for d in durations:
        scene = write_scene(harness_scene(64, 1000, duration=d), out / f"harness_{d:g}s.toml")
        report, record = out / f"harness_{d:g}s.json", out / f"harness_{d:g}s.rrd"
        proc = subprocess.run([sys.executable, "-P", "-m", "cablecheck.cli.main", "run", str(scene), "--report", str(report),
                               "--record", str(record), "--quiet", "--fail-on", "never"], cwd=REPO,
                              env=dict(os.environ, PYTHONPATH=str(REPO)), capture_output=True, text=True, check=False)
        if proc.returncode != 0 or not record.exists():
            rows.append([f"{d:g}", None, None, None, None, f"failed ({proc.returncode})"])
            continue
        t = json.loads(report.read_text())["timing"]
        sizes[d] = record.stat().st_size / 2 ** 20
        done = [k for k in sorted(sizes) if k < d]
        growth = (sizes[d] - sizes[done[-1]]) / (d - done[-1]) if done else None
        rows.append([f"{d:g}", sizes[d], sizes[d] / d, growth, t["record_s"] / d, ""])
        print(f"harness {d:g} s: measured", file=sys.stderr, flush=True)
    return ("Harness scene (64 cables, 1,000 parts): the recording's size; mb_per_s = size / duration; "
            "growth = (size - size of the previous duration) / (difference of durations); record_s_per_s: "
            "the report's record_s per simulated second\n"
            + text_table(["duration_s", "mb", "mb_per_s", "growth_mb_per_s", "record_s_per_s", "note"], rows))


def _machine() -> str:
    load = os.getloadavg()
    return (f"\nmachine: {os.cpu_count()} cores, load average {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f} "
            f"at the end; python {sys.version.split()[0]}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--before", default=BEFORE, help="git revisions to compare with, comma-separated ('' for none)")
    ap.add_argument("--repeat", type=int, default=3, help="runs per scene and code")
    ap.add_argument("--scenes", default="", help="comma-separated scene stems (default: every example)")
    ap.add_argument("--out", type=Path, default=None, help="folder for the reports and recordings")
    ap.add_argument("--harness", default="", help="durations (s, comma-separated): the harness recording's size")
    a = ap.parse_args(argv)
    if a.harness:
        out = a.out or Path(tempfile.mkdtemp(prefix="bench_record_"))
        out.mkdir(parents=True, exist_ok=True)
        sys.path.insert(0, str(REPO))
        text = harness([float(x) for x in a.harness.split(",")], out) + _machine()
        print(text)
        (out / "bench_record_harness.txt").write_text(text + "\n")
        return 0
    scenes = sorted((REPO / "scenes").glob("*.toml"))
    if a.scenes:
        scenes = [s for s in scenes if s.stem in a.scenes.split(",")]
    trees = [("now", REPO)] + [(rev, _export(rev)) for rev in a.before.split(",") if rev]
    out = a.out or Path(tempfile.mkdtemp(prefix="bench_record_"))
    rows, found = [], {}
    for scene in scenes:
        runs: dict[str, list[dict]] = {label: [] for label, _ in trees}
        for _ in range(a.repeat):
            for label, tree in trees:                      # in turn: every code sees the same load
                folder = out / label
                folder.mkdir(parents=True, exist_ok=True)
                r = _run(scene, tree, folder)
                if r is not None:
                    runs[label].append(r)
        best = {}
        for label, rs in runs.items():
            if not rs:
                continue
            m = {k: min(r[k] for r in rs if r[k] is not None) if any(r[k] is not None for r in rs) else None
                 for k in ("rec", "close", "frame", "open", "build", "sim", "with_open")}
            m["ratio"] = m["rec"] / m["sim"]
            m["frame_ratio"] = None if m["frame"] is None else m["frame"] / m["sim"]
            ratios = [r["cpu_ratio"] for r in rs if r["cpu_ratio"] is not None]
            m["cpu_ratio"] = statistics.median(ratios) if ratios else None
            m["mb"] = rs[-1]["mb"]
            best[label] = m
        found[scene.stem] = best
        now = best.get("now")
        for label, _ in trees:
            m = best.get(label)
            row = [scene.stem, label] + [None if m is None else m[k] for k in COLUMNS]
            row.append(None if label == "now" or not (m and now) else now["rec"] / m["rec"])
            row.append(("yes" if m["frame_ratio"] is not None and m["frame_ratio"] <= 0.5 else "NO") if m else "-")
            row.append(("yes" if m["ratio"] <= 0.5 else "NO") if m else "-")
            rows.append(row)
        print(f"{scene.stem}: measured", file=sys.stderr, flush=True)
    cols = ["scene", "code", *COLUMNS, "now/this", "frame_ratio<=0.5", "ratio<=0.5"]
    text = (f"Recording against MuJoCo, ms per checked step unless named (close, open: ms per run), best of "
            f"{a.repeat} runs each, one process per run, codes in turn; build: MuJoCo's model build, ms per run; "
            f"ratio = rec / sim; frame_ratio = frame / sim; with_open = "
            f"(record + open) / sim; cpu_ratio: rec / sim in CPU time (median); now/this: this checkout's rec "
            f"over the row's\n" + text_table(cols, rows)
            + _machine())
    print(text)
    (out / "bench_record.txt").write_text(text + "\n")
    (out / "bench_record.json").write_text(json.dumps(found, indent=1))
    print(f"written: {out / 'bench_record.txt'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
