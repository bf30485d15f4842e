"""Where the recording's fixed cost goes: the recorder's close, split, and what rerun's own parts of it cost.

On a short scene the recording's cost per step is mostly its close
(``Recorder.close``, once per run: it sends the buffered columns and the
blueprint and finishes the file; ``benchmarks/bench_record.py`` gives the
per-step totals). This splits the close of each example scene, run by
``cablecheck run --record`` in a fresh interpreter per run (as a user runs
it), into (ms, wall):

- ``data``: the ``send_columns`` calls (rerun's Python wrapper and its
  native hand-over of each chunk);
- ``layout``: building the blueprint (``cablecheck.record.layout.blueprint``);
- ``blueprint``: rerun's ``send_blueprint`` (a blueprint stream of its own,
  one logged entry per view, container, view property and panel, handed
  over to the recording);
- ``finish``: rerun's ``disconnect``: what is still pending is encoded
  (each chunk as Arrow IPC, LZ4-compressed), the footer (rerun's manifest
  of every chunk, for random access) is built and written, the file closed;
- ``replace``: moving the finished file into place (``os.replace``);
- ``own``: the rest, our Python building the columns (the close minus the
  parts above);

and ``cpu``: the close in CPU time of the whole process (every thread:
rerun encodes on threads of its own), which the machine's load moves less.

Two variants of the same run show what rerun's parts cost, side by side
(neither is how cablecheck writes a recording): ``no footer``
(``write_footer=False``: rerun warns that the file then lacks its
manifest) and ``no blueprint`` (the blueprint built but not sent). The
difference to ``as is`` is what the footer, or the blueprint with its
share of the footer, costs.

Run: python benchmarks/bench_record_close.py [--scenes a,b] [--repeat N] [--out DIR]

Times are each the best (lowest) of the repeats, ``cpu`` the median;
compare rows of one run, not runs of different days.
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

REPO = Path(__file__).resolve().parents[1]
VARIANTS = ("as is", "no footer", "no blueprint")
PARTS = ("data", "layout", "blueprint", "finish", "replace")

_CHILD = """
import json, os, sys, time
import rerun as rr
import cablecheck.record.recorder as R
variant = sys.argv[1]
wall = {k: 0.0 for k in ("close", "data", "layout", "blueprint", "finish", "replace")}
cpu = {"close": 0.0}
inside = [False]
def timed(owner, name, part, replacement=None):
    f = getattr(owner, name)
    g = replacement or f
    def clocked(*a, **k):
        if not inside[0]:
            return f(*a, **k)
        t = time.perf_counter()
        try:
            return g(*a, **k)
        finally:
            wall[part] += time.perf_counter() - t
    setattr(owner, name, clocked)
timed(rr.RecordingStream, "send_columns", "data")
timed(R, "blueprint", "layout")
timed(rr.RecordingStream, "send_blueprint", "blueprint",
      (lambda *a, **k: None) if variant == "no blueprint" else None)
timed(rr.RecordingStream, "disconnect", "finish")
timed(R.os, "replace", "replace")
if variant == "no footer":
    save = rr.RecordingStream.save
    rr.RecordingStream.save = lambda self, path, *a, **k: save(self, path, *a, **dict(k, write_footer=False))
close = R.Recorder.close
def closing(self):
    inside[0] = True
    t, c = time.perf_counter(), time.process_time()
    try:
        return close(self)
    finally:
        wall["close"] += time.perf_counter() - t
        cpu["close"] += time.process_time() - c
        inside[0] = False
R.Recorder.close = closing
from cablecheck.cli.main import main
code = main(sys.argv[2:])
print(json.dumps({"wall": wall, "cpu": cpu}))
sys.exit(code)
"""
"""The child: ``cablecheck`` with the recorder's close and rerun's calls in it timed (``variant``: see the module docstring)."""


def _run(scene: Path, variant: str, out: Path) -> dict | None:
    """One recorded run of `scene`: the close's parts (ms) and the recording's size, or None."""
    report, record = out / f"{scene.stem}.json", out / f"{scene.stem}.rrd"
    proc = subprocess.run([sys.executable, "-P", "-c", _CHILD, variant, "run", str(scene), "--report", str(report),
                           "--record", str(record), "--quiet", "--fail-on", "never"],
                          cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO)), capture_output=True, text=True,
                          check=False)
    if proc.returncode != 0 or not record.exists():
        print(f"{scene.stem} ({variant}) failed ({proc.returncode}): "
              f"{(proc.stderr.strip().splitlines() or ['?'])[-1]}", file=sys.stderr)
        return None
    child = json.loads(proc.stdout.strip().splitlines()[-1])
    ms = {k: v * 1e3 for k, v in child["wall"].items()}
    ms["own"] = ms["close"] - sum(ms[p] for p in PARTS)
    ms["cpu"] = child["cpu"]["close"] * 1e3
    ms["mb"] = record.stat().st_size / 2 ** 20
    return ms


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=5, help="runs per scene and variant")
    ap.add_argument("--scenes", default="", help="comma-separated scene stems (default: every example)")
    ap.add_argument("--out", type=Path, default=None, help="folder for the reports and recordings")
    a = ap.parse_args(argv)
    scenes = sorted((REPO / "scenes").glob("*.toml"))
    if a.scenes:
        scenes = [s for s in scenes if s.stem in a.scenes.split(",")]
    out = a.out or Path(tempfile.mkdtemp(prefix="bench_record_close_"))
    cols = ["scene", "variant", "close", "cpu", "data", "layout", "blueprint", "finish", "replace", "own", "mb"]
    rows = []
    for scene in scenes:
        runs: dict[str, list[dict]] = {v: [] for v in VARIANTS}
        for _ in range(a.repeat):
            for variant in VARIANTS:                       # in turn: every variant sees the same load
                folder = out / variant.replace(" ", "_")
                folder.mkdir(parents=True, exist_ok=True)
                r = _run(scene, variant, folder)
                if r is not None:
                    runs[variant].append(r)
        for variant, rs in runs.items():
            if not rs:
                rows.append([scene.stem, variant] + [None] * (len(cols) - 2))
                continue
            best = {k: min(r[k] for r in rs) for k in ("close", *PARTS, "own")}
            rows.append([scene.stem, variant, best["close"], statistics.median(r["cpu"] for r in rs),
                         *(best[p] for p in PARTS), best["own"], rs[-1]["mb"]])
        print(f"{scene.stem}: measured", file=sys.stderr, flush=True)
    load = os.getloadavg()
    text = (f"The recorder's close, ms per run (wall, best of {a.repeat}; cpu: the whole process's CPU time, "
            f"median), one process per run, variants in turn; no footer / no blueprint: the same run with rerun's "
            f"footer not written / the blueprint not sent (not how cablecheck writes)\n" + text_table(cols, rows)
            + f"\nmachine: {os.cpu_count()} cores, load average {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f} "
              f"at the end; python {sys.version.split()[0]}")
    print(text)
    (out / "bench_record_close.txt").write_text(text + "\n")
    print(f"written: {out / 'bench_record_close.txt'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
