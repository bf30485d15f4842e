"""Recording cost per step on the example scenes, this checkout against a revision, side by side.

Every example scene (``scenes/*.toml``) is run with ``cablecheck run
--record`` in its own process (a fresh interpreter each time, as a user
runs it: one-time costs such as lazy imports count), alternately by this
checkout and by ``--before`` (a git revision exported to a temporary
folder), ``--repeat`` times each. Per scene and code the table gives the
report's ``timing.record_ms_per_step``
(recording's wall time per checked step), ``timing.sim_ms_per_step``
(MuJoCo's per step), each the best (lowest) of the repeats, their ratio,
and the recording's size. On a loaded machine wall times swing with the
load; the ``cpu_ratio`` columns give the same ratio in CPU time (the
process's, all threads, per run stage: the run's stage timer also reads
``time.process_time``), which the load moves much less. The target:
recording at most half of MuJoCo's time per step (ratio <= 0.5) on every
scene.

Run: python benchmarks/bench_record.py [--before REV] [--repeat N] [--scenes a,b] [--out DIR]

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

REPO = Path(__file__).resolve().parents[1]
BEFORE = "ab65c56"
"""Default ``--before``: the recording as it was before its cost was cut (pyarrow's compute
module imported for the wear bar charts, lanes and log entries logged row by row)."""


def _export(rev: str) -> Path:
    """The checker and sim packages of git revision ``rev`` in a temporary folder."""
    folder = Path(tempfile.mkdtemp(prefix="bench_record_before_"))
    archive = subprocess.run(["git", "-C", str(REPO), "archive", rev, "checker", "sim"],
                             check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder


_CHILD = """
import json, sys, time
import sim.run
from sim.cli import main
cpu = {}
lap = sim.run._Timer.lap
def timed(self, stage):
    now = time.process_time()
    cpu[stage] = cpu.get(stage, 0.0) + now - getattr(self, "_cpu", now)
    self._cpu = now
    lap(self, stage)
skip = sim.run._Timer.skip
def skipped(self):
    self._cpu = time.process_time()
    skip(self)
sim.run._Timer.lap, sim.run._Timer.skip = timed, skipped
code = main(sys.argv[1:])
print(json.dumps(cpu))
sys.exit(code)
"""
"""The child: ``cablecheck`` with the run's stage timer also adding up CPU time per stage."""


def _run(scene: Path, tree: Path, out: Path) -> dict | None:
    """One recorded run of `scene` by the code in `tree`: its timing and recording size, or None."""
    report, record = out / f"{scene.stem}.json", out / f"{scene.stem}.rrd"
    report.unlink(missing_ok=True)
    # -P and the tree as the working folder: `sim` comes from PYTHONPATH, never from the
    # folder the benchmark was started in
    proc = subprocess.run([sys.executable, "-P", "-c", _CHILD, "run", str(scene), "--report", str(report),
                           "--record", str(record), "--quiet", "--fail-on", "never"],
                          cwd=tree, env=dict(os.environ, PYTHONPATH=str(tree)), capture_output=True, text=True,
                          check=False)
    if proc.returncode != 0 or not report.exists():
        print(f"{scene.stem} failed ({proc.returncode}): {(proc.stderr.strip().splitlines() or ['?'])[-1]}")
        return None
    t = json.loads(report.read_text())["timing"]
    cpu = json.loads(proc.stdout.strip().splitlines()[-1])
    return {"record": t["record_ms_per_step"], "sim": t["sim_ms_per_step"],
            "cpu_ratio": cpu.get("record", 0.0) / t["record_s"] * t["record_ms_per_step"]
            / (cpu["sim"] / t["sim_s"] * t["sim_ms_per_step"]) if t["record_s"] and cpu.get("sim") else None,
            "mb": record.stat().st_size / 2 ** 20}


def _table(cols: list[str], rows: list[list]) -> str:
    fmt = lambda v: "-" if v is None else (f"{v:.3f}" if isinstance(v, float) else str(v))
    cells = [[fmt(v) for v in r] for r in rows]
    width = [max(len(c), *(len(r[k]) for r in cells)) for k, c in enumerate(cols)]
    return "\n".join(["  ".join(c.rjust(w) for c, w in zip(cols, width))]
                     + ["  ".join(v.rjust(w) for v, w in zip(r, width)) for r in cells])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--before", default=BEFORE, help="git revision to compare with ('' for none)")
    ap.add_argument("--repeat", type=int, default=3, help="runs per scene and code (medians are shown)")
    ap.add_argument("--scenes", default="", help="comma-separated scene stems (default: every example)")
    ap.add_argument("--out", type=Path, default=None, help="folder for the reports and recordings")
    a = ap.parse_args(argv)
    scenes = sorted((REPO / "scenes").glob("*.toml"))
    if a.scenes:
        scenes = [s for s in scenes if s.stem in a.scenes.split(",")]
    trees = [("this checkout", REPO)] + ([(f"before ({a.before})", _export(a.before))] if a.before else [])
    out = a.out or Path(tempfile.mkdtemp(prefix="bench_record_"))
    rows, found = [], {}
    for scene in scenes:
        runs: dict[str, list[dict]] = {label: [] for label, _ in trees}
        for _ in range(a.repeat):
            for label, tree in trees:                      # alternately: both see the same load
                folder = out / label.split()[0]
                folder.mkdir(parents=True, exist_ok=True)
                r = _run(scene, tree, folder)
                if r is not None:
                    runs[label].append(r)
        med = {label: {"record": min(r["record"] for r in rs), "sim": min(r["sim"] for r in rs),
                       "cpu_ratio": statistics.median(r["cpu_ratio"] for r in rs), "mb": rs[-1]["mb"]}
               for label, rs in runs.items() if rs}
        for m in med.values():
            m["ratio"] = m["record"] / m["sim"]
        found[scene.stem] = med
        now = med.get(trees[0][0])
        then = med.get(trees[1][0]) if len(trees) > 1 else None
        row = [scene.stem]
        for m in (then, now):
            row += [None] * 5 if m is None else [m["record"], m["sim"], m["ratio"], m["cpu_ratio"], m["mb"]]
        row.append(None if not (now and then) else now["record"] / then["record"])
        row.append("-" if now is None else ("yes" if now["ratio"] <= 0.5 else "NO"))
        rows.append(row if len(trees) > 1 else [row[0], *row[6:11], row[-1]])
        print(f"{scene.stem}: measured", file=sys.stderr, flush=True)
    cols = (["scene", "before_rec", "before_sim", "before_ratio", "before_cpu_ratio", "before_mb",
             "rec", "sim", "ratio", "cpu_ratio", "mb", "rec/before", "ratio<=0.5"] if len(trees) > 1
            else ["scene", "rec", "sim", "ratio", "cpu_ratio", "mb", "ratio<=0.5"])
    load = os.getloadavg()
    text = (f"Recording per checked step (ms) against MuJoCo's per step (ms), best of {a.repeat} runs each, "
            f"one process per run, codes alternating; ratio = rec / sim; cpu_ratio: the same in CPU time "
            f"(median of the runs)\n" + _table(cols, rows)
            + f"\nmachine: {os.cpu_count()} cores, load average {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f} "
              f"at the end; python {sys.version.split()[0]}")
    print(text)
    (out / "bench_record.txt").write_text(text + "\n")
    (out / "bench_record.json").write_text(json.dumps(found, indent=1))
    print(f"written: {out / 'bench_record.txt'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
