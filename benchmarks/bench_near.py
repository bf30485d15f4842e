"""A hose lying within the clearance of many primitive parts: what a checked step costs.

Issue 29's first deliverable: "one hose within the clearance of 10-20
primitive parts: a checked step well under 0.1 ms", and a cost that follows
what is near, not what is there. Each scene here is a 5 mm hose clamped at
both ends on a rig that turns and rocks, lying across ``N`` primitive parts
on that rig (boxes, capsules, cylinders, spheres, ellipsoids in turn, their
tops 1 mm below the hose's underside), with ``F`` more parts on the rig
200 mm to the side of it, never near
(:func:`cablecheck.bench.scenes.resting_hose_text`). Nothing can be skipped for the near
pairs: the hose rests on them for the whole run.

Each scene runs in this process (`run_scene`, no recording, validation on)
and prints: the parts the hose came within the clearance of (its events),
checked steps, full checks, and the report's CPU times per checked step
(check, MuJoCo's comparison, simulation) with (check + validation) /
simulation. One row per scene, one after the other; the machine, the load
(``uptime``) before and after and the date are printed with them.

Run: python benchmarks/bench_near.py [--near 4,8,16] [--far 0,64] [--duration 3.0] [--quick]

Deliberately not a test: nothing here asserts a time (tests/test_bench_near.py
runs --quick and checks what the rows say about the scenes).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

def run_row(near: int, far: int, duration: float, folder: Path) -> dict:
    """One scene's row: what it came near, and its CPU per checked step."""
    from cablecheck.bench.scenes import resting_hose_text
    from cablecheck.run.runner import RunOptions, run_scene
    from cablecheck.scene.load import load_scene

    path = folder / f"near{near}_far{far}.toml"
    path.write_text(resting_hose_text(near, far, duration))
    r = run_scene(load_scene(path), RunOptions(report=path.with_suffix(".json"), record=None))
    t, adv = r["timing"], r["settings"]["advance"] or {}
    touched = sorted({e["b"] for e in r["events"] if e["type"] == "cable-structure"})
    return {"near": near, "far": far, "touched": len(touched), "far_touched": sum(int(p.split("/p")[1]) >= near
                                                                                     for p in touched),
            "steps": r["settings"]["checked_steps"], "full": adv.get("full_checks"),
            "check_ms": t["check_ms_per_step"], "validate_ms": t["validate_ms_per_step"],
            "sim_ms": t["sim_ms_per_step"], "ratio": (t["check_s"] + t["validate_s"]) / max(t["sim_s"], 1e-12),
            "agreement": r["validation"]["agreement"], "complete": r["complete"]}


def table(rows: list[dict]) -> str:
    lines = ["| near parts | far parts | parts within the clearance | checked steps | full checks "
             "| check ms / step | validation ms / step | simulation ms / step | (c+v)/sim | agreement |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for w in rows:
        lines.append(f"| {w['near']} | {w['far']} | {w['touched']} | {w['steps']} | {w['full']} | "
                     f"{w['check_ms']:.3f} | {w['validate_ms']:.3f} | {w['sim_ms']:.3f} | {w['ratio']:.2f} | "
                     f"{100 * w['agreement']:.2f} % |")
    return "\n".join(lines)


def _uptime() -> str:
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True, check=False).stdout.strip()
    except OSError:
        return "(no uptime)"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--near", default="4,8,16", help="counts of parts under the hose, comma-separated")
    ap.add_argument("--far", default="0,64", help="counts of parts beside it, never near, comma-separated")
    ap.add_argument("--duration", type=float, default=3.0, help="simulated seconds of each scene")
    ap.add_argument("--quick", action="store_true", help="near 2, far 0 and 4, 0.2 s (the test's)")
    ap.add_argument("--json", type=Path, help="also write the rows here")
    args = ap.parse_args(argv)
    near = [2] if args.quick else [int(x) for x in args.near.split(",")]
    far = [0, 4] if args.quick else [int(x) for x in args.far.split(",")]
    duration = 0.2 if args.quick else args.duration
    before = _uptime()
    with tempfile.TemporaryDirectory(prefix="bench_near_") as tmp:
        rows = [run_row(n, f, duration, Path(tmp)) for f in far for n in near]
    print(f"Measured {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC on {platform.node()} "
          f"({os.cpu_count()} cores, Python {platform.python_version()}); {duration} s of each scene, "
          f"one after the other.\n\nLoad before: `{before}`; after: `{_uptime()}`.\n")
    print(table(rows))
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0 if all(w["complete"] for w in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
