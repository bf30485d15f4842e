"""What a study's parallel run saves: the example study's 8 variants on 2 workers against one after another.

The example study (scenes/studies/drawer_length_study.toml: the drawer's power
cable at 8 lengths) is run three ways, side by side in one run:

- serial processes: `cablecheck run` of each variant, one after another,
  each a fresh process (what a study replaces: run after run by hand);
- serial in one process: `sim.run.run_scene` of each variant, one after
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

Run: python benchmarks/bench_study.py [--workers N]
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from checker.cable import TAUT_STRAIN
from sim.run import RunOptions, run_scene
from sim.scene import load_scene, parse_scene
from sim.study import check_variants, load_study, variants
from sim.studyresult import COLUMNS, length_window, row_from_report
from sim.studyplot import results_csv

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "scenes" / "studies" / "drawer_length_study.toml"
TARGET = 0.6


def largest_end_distance(scene) -> float:
    """Largest distance between the first cable's ends over the motion keys
    (scene units); the drawer only translates, linearly between keys."""
    cable = scene.cables[0]
    (motion,) = scene.motions
    ends = np.array([np.asarray(k.pos) + np.asarray(cable.end.pos) for k in motion.keys])
    return float(np.max(np.linalg.norm(ends - np.asarray(cable.start.pos), axis=1))) / scene.scale


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    study = load_study(STUDY)
    found = variants(study)
    check_variants(study, found)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    cli = [sys.executable, "-m", "sim.cli"]
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
