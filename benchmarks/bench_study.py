"""What a study's parallel run saves: the example study's 8 variants on 2 workers against one after another.

The example study (scenes/studies/drawer_length_study.toml: the drawer's power
cable at 8 lengths) is run three ways, side by side in one run:

- serial processes: `cablecheck run` of each variant, one after another,
  each a fresh process (what a study replaces: run after run by hand);
- serial in one process: `cablecheck.run.runner.run_scene` of each variant, one after
  another (no start-up per run: the strictest baseline);
- the study: `cablecheck study --workers 2` (one process: reading and
  checking the variants, the embedded Dask cluster's start-up, the runs,
  the tables and the plot).

Every way writes reports and recordings. Printed: wall times, the study's
ratio to each baseline (target: at most 0.6 of running them one after
another), whether the study's rows equal the in-process runs' rows, and
the interference-free window against the geometry: the largest distance
between the cable's ends over the drawer's motion (a shorter cable must be
stretched, taut beyond 1 %).

``--scaling`` instead times the study itself on one worker and on two
(`cablecheck study --workers 1` and `--workers 2`, whole commands,
alternating, ``--repeat`` times each, reports and recordings written) and
prints the ratio (target: two workers at least 1.6 times as fast as one on
a 2-core machine, issue 27), the same for the variants alone (the sum of the
tasks' wall times on the busiest worker, from each `variant.json`), the date, the load (``uptime``) before and
after, the command, and what a variant costs on its worker beyond its run
(`variant.json`'s ``task_s`` less the report's ``timing.total_s``: the
files written, the scene parsed, the outputs read back), the first variant
of each worker apart from the rest (the rest show that a worker keeps its
imports loaded between variants; and the same variant three times on one
fresh worker). ``--doc FILE`` writes that block into
FILE between ``<!-- bench_study -->`` and ``<!-- /bench_study -->``.

Run: python benchmarks/bench_study.py [--workers N]
     python benchmarks/bench_study.py --scaling [--repeat N] [--doc docs/performance.md]
"""

from __future__ import annotations

import argparse
import csv
import datetime
import json
import os
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from cablecheck.checker.cable import TAUT_STRAIN
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import load_scene, parse_scene
from cablecheck.study.definition import check_variants, load_study, variants
from cablecheck.study.plot import results_csv
from cablecheck.study.result import COLUMNS, length_window, row_from_report

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "scenes" / "studies" / "drawer_length_study.toml"
TARGET = 0.6
SCALING_TARGET = 1.6
"""Two workers at least this many times as fast as one (issue 27, on 2 cores)."""
BEGIN, END = "<!-- bench_study -->", "<!-- /bench_study -->"


def largest_end_distance(scene) -> float:
    """Largest distance between the first cable's ends over the motion keys
    (scene units); the drawer only translates, linearly between keys."""
    cable = scene.cables[0]
    (motion,) = scene.motions
    ends = np.array([np.asarray(k.pos) + np.asarray(cable.end.pos) for k in motion.keys])
    return float(np.max(np.linalg.norm(ends - np.asarray(cable.start.pos), axis=1))) / scene.scale


def load() -> str:
    """`uptime`'s load averages."""
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip().split("load average: ")[-1]


def _children_cpu() -> float:
    """CPU seconds of the finished child processes (the study's, its workers' included)."""
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def busiest(folder: Path) -> float:
    """The variants' wall time on the busiest worker of a finished study
    (sum of its tasks' `task_s`): the study's run phase without start-up,
    scheduling gaps or outputs."""
    per: dict[int, float] = {}
    for sub in (folder / "variants").iterdir():
        stored = json.loads((sub / "variant.json").read_text())
        per[stored["worker_pid"]] = per.get(stored["worker_pid"], 0.0) + stored["task_s"]
    return max(per.values())


def overheads(folder: Path) -> tuple[list[float], list[float]]:
    """Per variant of a finished study folder, its task's wall time on its
    worker less its run's own (seconds): (first variant of each worker, the rest)."""
    first, rest, seen = [], [], set()
    for sub in sorted((folder / "variants").iterdir()):
        stored = json.loads((sub / "variant.json").read_text())
        report = json.loads((sub / "report.json").read_text())
        extra = stored["task_s"] - report["timing"]["total_s"]
        (rest if stored["worker_pid"] in seen else first).append(extra)
        seen.add(stored["worker_pid"])
    return first, rest


def same_variant_thrice(study) -> list[float]:
    """The example's variant 002 three times, one after another, on one
    fresh worker of an embedded cluster: each task's wall time on the worker."""
    from cablecheck.study.bundle import make_bundle
    from cablecheck.study.cluster import cluster
    from cablecheck.study.execute import VariantTask, run_variant

    found = variants(study)
    bundle, datas = make_bundle(study.scene_path, [v.data for v in found])
    with cluster(1, None) as cl:
        task = VariantTask(id=found[2].id, data=datas[2], record=True, temp_root=cl.temp_root)
        return [cl.client.submit(run_variant, task, bundle, pure=False).result().task_s for _ in range(3)]


def scaling(repeat: int, doc: Path | None) -> None:
    """`--scaling`: the study on one worker against two (see the module docstring)."""
    study = load_study(STUDY)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    times: dict[int, list[float]] = {1: [], 2: []}
    phase: dict[int, list[float]] = {1: [], 2: []}
    cores: dict[int, list[float]] = {1: [], 2: []}
    extra: dict[int, tuple[list[float], list[float]]] = {1: ([], []), 2: ([], [])}
    before = load()
    started = datetime.datetime.now().astimezone()
    with tempfile.TemporaryDirectory(prefix="bench-study-") as tmp:
        for k in range(repeat):
            for n in (1, 2) if k % 2 == 0 else (2, 1):
                out = Path(tmp) / f"w{n}-{k}"
                t0, c0 = time.perf_counter(), _children_cpu()
                subprocess.run([sys.executable, "-m", "cablecheck.cli.main", "study", str(STUDY), "--workers", str(n),
                                "--out", str(out), "--quiet", "--fail-on", "never"], env=env, check=True)
                times[n].append(time.perf_counter() - t0)
                cores[n].append((_children_cpu() - c0) / times[n][-1])
                phase[n].append(busiest(out / study.name))
                first, rest = overheads(out / study.name)
                extra[n][0].extend(first)
                extra[n][1].extend(rest)
    warm = same_variant_thrice(study)
    after = load()
    one, two = statistics.median(times[1]), statistics.median(times[2])
    busy = max(float(x.strip(",")) for x in (before.split()[0], after.split()[0]))
    lines = [
        f"Measured {started:%Y-%m-%d %H:%M %Z} on {os.cpu_count()} cores: `cablecheck study` of "
        f"{STUDY.relative_to(ROOT)} ({len(variants(study))} variants of the drawer, 4 s each, reports "
        f"and recordings), whole commands, {repeat} of each alternating; load before `{before}`, "
        f"after `{after}`" + (" (not quiet)" if busy > 0.5 else "") + ".",
        f"Command: `python benchmarks/bench_study.py {shlex.join(sys.argv[1:])}`",
        "",
        "| workers | study, median s | min s | max s | speed-up | variants on the busiest worker, median s | speed-up "
        "| cores used (CPU s / wall s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    ph1 = statistics.median(phase[1])
    for n in (1, 2):
        lines.append(f"| {n} | {statistics.median(times[n]):.1f} | {min(times[n]):.1f} | {max(times[n]):.1f} | "
                     f"{one / statistics.median(times[n]):.2f} | {statistics.median(phase[n]):.1f} | "
                     f"{ph1 / statistics.median(phase[n]):.2f} | {statistics.median(cores[n]):.2f} |")
    firsts = extra[1][0] + extra[2][0]
    rests = extra[1][1] + extra[2][1]
    lines += ["", f"Two workers: the study {one / two:.2f} times as fast as one (target {SCALING_TARGET}), its "
              f"variants {ph1 / statistics.median(phase[2]):.2f} times (the rest of a study, the same on one "
              "worker or two: Python's start, reading and checking the variants, the cluster's start, each "
              "worker's first imports, the tables and the plot). A variant's "
              f"cost on its worker beyond its run: first variant of a worker median "
              f"{statistics.median(firsts):.2f} s (n = {len(firsts)}), every later one "
              f"{statistics.median(rests):.2f} s (n = {len(rests)}, max {max(rests):.2f} s). The same "
              f"variant three times on one fresh worker: {', '.join(f'{t:.2f}' for t in warm)} s (the first "
              "pays the imports; the worker keeps them)."]
    text = "\n".join(lines)
    print(text)
    print(json.dumps({"times": times, "busiest_worker_s": phase, "cores": cores, "first_extra_s": firsts, "later_extra_s": rests, "same_variant_s": warm}))
    if doc is not None:
        old = doc.read_text()
        block = f"{BEGIN}\n{text}\n{END}"
        if BEGIN in old and END in old:
            head, rest = old.split(BEGIN, 1)
            doc.write_text(head + block + rest.split(END, 1)[1])
        else:
            doc.write_text(old.rstrip("\n") + "\n\n" + block + "\n")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--scaling", action="store_true", help="time the study on one worker against two")
    ap.add_argument("--repeat", type=int, default=3, help="--scaling: runs of each")
    ap.add_argument("--doc", type=Path, default=None, help="--scaling: write the figures into this Markdown file")
    args = ap.parse_args()
    if args.scaling:
        scaling(args.repeat, args.doc)
        return
    study = load_study(STUDY)
    found = variants(study)
    check_variants(study, found)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    cli = [sys.executable, "-m", "cablecheck.cli.main"]
    print(f"{STUDY.name}: {len(found)} variants of {study.scene_path.name} "
          f"({study.vary[0].key} = {', '.join(f'{v.values[0]:g}' for v in found)}), "
          f"{os.cpu_count()} cores")
    with tempfile.TemporaryDirectory(prefix="bench-study-") as tmp:
        tmp = Path(tmp)
        # serial, a process per variant: the variant's scene as a file beside the original
        text = study.scene_path.read_text()
        t0 = time.perf_counter()
        for v in found:
            scene = study.scene_path.with_name(f".bench-study-{v.id}.toml")
            variant_text = text.replace("length = 650.0", f"length = {v.values[0]!r}")
            assert variant_text != text or v.values[0] == 650.0
            scene.write_text(variant_text)
            try:
                subprocess.run([*cli, "run", str(scene), "--quiet", "--report", str(tmp / f"p{v.id}.json"),
                                "--record", str(tmp / f"p{v.id}.rrd")], env=env, check=False)
            finally:
                scene.unlink()
        processes_s = time.perf_counter() - t0
        # serial, in this process
        t0 = time.perf_counter()
        serial_rows = []
        for v in found:
            run_scene(parse_scene(v.data, study.scene_path),
                      RunOptions(report=tmp / f"s{v.id}.json", record=tmp / f"s{v.id}.rrd"))
            # the row as the report file gives it, as the study reads it
            report = json.loads((tmp / f"s{v.id}.json").read_text())
            serial_rows.append(row_from_report(v.id, v.values, report))
        inprocess_s = time.perf_counter() - t0
        # the study
        t0 = time.perf_counter()
        done = subprocess.run([*cli, "study", str(STUDY), "--workers", str(args.workers), "--out",
                               str(tmp / "out"), "--quiet"], env=env)
        study_s = time.perf_counter() - t0
        with open(tmp / "out" / study.name / "results.csv", newline="") as f:
            study_rows = list(csv.DictReader(f))
    compared = [c for c in COLUMNS if c != "run_time_s"]
    serial_table = list(csv.DictReader(results_csv(study, serial_rows).splitlines()))
    same = all(a[c] == b[c] for a, b in zip(study_rows, serial_table) for c in compared)
    print(f"  serial, a `cablecheck run` process each : {processes_s:7.1f} s")
    print(f"  serial, one process (run_scene)         : {inprocess_s:7.1f} s")
    print(f"  cablecheck study --workers {args.workers}             : {study_s:7.1f} s  (exit {done.returncode})")
    print(f"  ratio study / serial processes          : {study_s / processes_s:7.2f}  "
          f"(target <= {TARGET})")
    print(f"  ratio study / serial in one process     : {study_s / inprocess_s:7.2f}  "
          f"(target <= {TARGET})")
    print(f"  study rows equal the serial runs' rows  : {'yes' if same else 'NO'}")
    reach = largest_end_distance(load_scene(study.scene_path))
    w = length_window(serial_rows)
    taut_below = all(r.taut for r in serial_rows if r.values[0] < reach / (1 + TAUT_STRAIN))
    print(f"  largest distance between the ends over the motion: {reach:g} mm; a cable shorter "
          f"than {reach / (1 + TAUT_STRAIN):.1f} mm stretches beyond {100 * TAUT_STRAIN:g} %")
    print(f"  window: {w.shortest:g} (taut at {w.below}) to {w.longest:g} mm "
          f"(hard or bend at {w.above}), recommended {w.recommended:g} mm; every tried length below "
          f"the reach taut: {'yes' if taut_below else 'NO'}; window starts at or above it: "
          f"{'yes' if w.shortest is not None and w.shortest >= reach / (1 + TAUT_STRAIN) else 'NO'}")
    print(json.dumps({"processes_s": processes_s, "inprocess_s": inprocess_s, "study_s": study_s,
                      "workers": args.workers, "same_rows": same}))


if __name__ == "__main__":
    main()
