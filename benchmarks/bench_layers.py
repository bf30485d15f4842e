"""Speed layers against their removal: the skip rule, the detection patches and the name codes.

Each layer is an optimisation that should leave a run's answers as they
are and make it cheaper; this measures, scene by scene, what each one
saves against what the run costs without it. Every scene runs in this
process (``cablecheck.run.runner.run_scene``, no recording) once with every
layer and once with each layer taken out, the variants of one scene one
after the other (so a change of the machine's load falls on all of them
alike), each run with its own report:

- ``all``: the product as it is.
- ``-skip``: the skip rule (``cablecheck.checker.advance``, used by
  ``cablecheck.run.stepcheck``) off: ``RunOptions(advance=False)``, what
  ``cablecheck run --full-every-step`` does: every step checked in full.
- ``-reach``: the detection patches (``cablecheck.detection.surfacereach``)
  off: the run's ``Detector`` is built with ``reach=False``
  (``cablecheck.run.runner.Detector`` replaced for the run by
  ``Detector(built, reach=False)``: every concave mesh surface patch is in
  every state's collision pass). Only scenes whose detection model has
  surface patches (concave meshes) and that validate have anything to
  leave out (the ``patches`` column: how many; 0 or ``-``: the layer is
  idle there).
- ``-codes``: the name codes (contacts numbered through the reader's shared
  name table, ``cablecheck.checker.validation.shared_codes``, read by
  ``SimulatorPairs.many`` and ``cablecheck.detection.hullgap.HullGaps``)
  off: ``shared_codes`` replaced in both modules by one that answers None,
  so both take their plain path (the contacts' names numbered per batch by
  ``np.unique``; the hull gaps' names looked up by binary search), as
  contacts without codes are read. The reader still writes the codes
  (what deleting the layer would also save is not counted: a few
  microseconds a batch). Only scenes that validate use them.

Columns per scene and variant: the report's ``timing`` (CPU seconds of the
run's stages: ``check_s``, ``validate_s``, ``sim_s``), (check + validate) /
sim, and for each variant without a layer the ratio of its check +
validate to the all-layers run's (above 1: the layer pays), and whether
its events (the report's ``events``, exactly) and its pairs and MuJoCo
comparison (``pairs``, ``validation``) are the all-layers run's. A
group line sums each group's check + validate.

Scenes: the examples (``scenes/*.toml``), the robot zoo written by
``benchmarks/bench_robots.py --keep DIR`` (``--zoo DIR``, default
/tmp/zoo_doc2: ``*.toml`` there but the 100 Hz variant, their CSV programs
beside them) and the 64-cable x 1,000-part harness
(``cablecheck.bench.harness``, settled ``SETTLE`` s, run ``--harness-duration``
s, default 0.5), as ``benchmarks/bench_scale.py --harness`` builds it.

Run: python benchmarks/bench_layers.py [--groups examples,zoo,harness] [--zoo DIR]
       [--layers skip,reach,codes] [--harness-duration S] [--repeat N] [--out DIR]

With ``--repeat N`` each variant runs N times, each round of a scene's
variants starting at the next one (a scene's first run is often the
slowest), and its smallest stage times are kept (events compared on
every run; ``stable`` false if a repeat's differ). Timings depend on the
machine and its load: compare rows of one run, not runs of different days.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import os
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

LAYERS = ("skip", "reach", "codes")
"""The layers, in the table's order."""


class _DetectorSpy:
    """Stands in for ``cablecheck.run.runner.Detector``: builds the real one
    (with ``reach`` as given) and notes how many surface patches its reach
    test can leave out (0: none; None: no detector was built)."""

    def __init__(self, reach: bool):
        from cablecheck.detection.detector import Detector

        self.cls, self.reach, self.patches = Detector, reach, None

    def __call__(self, built):
        det = self.cls(built, reach=self.reach)
        if self.reach:
            self.patches = 0 if det.reach is None else len(det.reach)
        else:
            from cablecheck.detection.surfacereach import SurfaceReach

            self.patches = len(SurfaceReach(built.detect))   # what the layer would have had to leave out
        return det


@contextlib.contextmanager
def _patched(module, name: str, value):
    old = getattr(module, name)
    setattr(module, name, value)
    try:
        yield
    finally:
        setattr(module, name, old)


def run_variant(path: Path, variant: str, out: Path) -> dict:
    """One run of the scene at `path` with `variant` ("all" or a layer
    taken out): its timing, events, pairs, validation and what the layer had
    to work on."""
    from cablecheck.checker import validation
    from cablecheck.detection import hullgap
    from cablecheck.run import runner
    from cablecheck.scene.load import load_scene

    spy = _DetectorSpy(reach=variant != "reach")
    options = runner.RunOptions(report=out / f"{path.stem}.{variant}.json", record=None,
                                advance=variant != "skip")
    with contextlib.ExitStack() as stack:
        stack.enter_context(_patched(runner, "Detector", spy))
        if variant == "codes":
            stack.enter_context(_patched(validation, "shared_codes", lambda contacts: None))
            stack.enter_context(_patched(hullgap, "shared_codes", lambda contacts: None))
        t0 = time.perf_counter()
        rep = runner.run_scene(load_scene(path), options)
        wall = time.perf_counter() - t0
    rep = json.loads(options.report.read_text())     # as written: plain lists, compared exactly
    t = rep["timing"]
    adv = (rep.get("settings") or {}).get("advance")
    val = rep.get("validation")
    return {"check": t["check_s"], "validate": t["validate_s"], "sim": t["sim_s"], "wall": wall,
            "complete": rep["complete"], "events": rep["events"], "pairs": rep["pairs"],
            "validation": val, "validates": val is not None, "patches": spy.patches,
            "full_checks": None if adv is None else adv.get("full_checks"),
            "steps": None if val is None else val.get("compared_steps")}


def run_scene_variants(path: Path, variants: list[str], repeat: int, out: Path) -> dict[str, dict]:
    """Every variant of one scene, `repeat` times each (interleaved, each
    round starting at the next variant: a scene's first run can be the
    slowest); the smallest stage times kept, events compared on every run."""
    found: dict[str, dict] = {}
    for k in range(repeat):
        for v in variants[k % len(variants):] + variants[:k % len(variants)]:   # a new one first each time
            r = run_variant(path, v, out)
            if v not in found:
                found[v] = r
                continue
            f = found[v]
            for k in ("check", "validate", "sim", "wall"):
                f[k] = min(f[k], r[k])
            f["stable"] = f.get("stable", True) and r["events"] == f["events"]
    return found


def _same(a: dict, b: dict) -> tuple[bool, bool]:
    """(events identical, pairs and validation identical)."""
    return a["events"] == b["events"], (a["pairs"] == b["pairs"] and a["validation"] == b["validation"])


def _f(x, fmt="{:.2f}") -> str:
    return "-" if x is None else fmt.format(x)


def table(rows: list[tuple[str, str, dict[str, dict]]], layers: list[str]) -> str:
    """The per-scene table and each group's sums."""
    head = ["group", "scene", "variant", "sim_s", "check_s", "validate_s", "(c+v)/sim", "c+v vs all",
            "events same", "pairs+val same", "note"]
    lines = []
    groups: dict[str, dict[str, list[float]]] = {}
    for group, name, found in rows:
        base = found["all"]
        cv0 = base["check"] + base["validate"]
        g = groups.setdefault(group, {})
        for v in ["all"] + [f"-{x}" for x in layers]:
            key = "all" if v == "all" else v[1:]
            r = found.get(key)
            if r is None:
                continue
            cv = r["check"] + r["validate"]
            g.setdefault(v, [0.0, 0.0, 0])
            g[v][0] += cv
            g[v][1] += r["sim"]
            if v == "all":
                ev = pv = ""
                note = "; ".join(x for x in (
                    f"full checks {r['full_checks']}" if r["full_checks"] is not None else "",
                    f"patches {_f(r['patches'], '{}')}" if r["validates"] else "no validation") if x)
            else:
                e, p = _same(base, r)
                ev, pv = ("yes" if e else "NO"), ("yes" if p else "NO")
                g[v][2] += 0 if e else 1
                note = {"skip": f"full checks {r['full_checks'] if r['full_checks'] is not None else 'all'}",
                        "reach": f"patches {_f(r['patches'], '{}')}" if r["validates"] else "no validation",
                        "codes": "" if r["validates"] else "no validation"}[key]
            if r.get("stable") is False:
                note += "; events differ between repeats"
            if not r["complete"]:
                note += "; INCOMPLETE"
            lines.append([group, name, v, _f(r["sim"]), _f(r["check"]), _f(r["validate"]),
                          _f(cv / r["sim"] if r["sim"] else None), _f(cv / cv0 if cv0 else None, "{:.3f}"),
                          ev, pv, note])
    out = [head] + lines
    widths = [max(len(str(r[i])) for r in out) for i in range(len(head))]
    text = ["  ".join(str(c).ljust(w) for c, w in zip(r, widths)).rstrip() for r in out]
    text.insert(1, "  ".join("-" * w for w in widths))
    text.append("")
    text.append("Per group: check + validate summed over its scenes (s), against all layers; "
                "scenes whose events differ")
    sums = [["group", "variant", "c+v sum", "sim sum", "(c+v)/sim", "vs all", "events differ in"]]
    for group, g in groups.items():
        cv0 = g["all"][0]
        for v, (cv, sim, bad) in g.items():
            sums.append([group, v, f"{cv:.2f}", f"{sim:.2f}", _f(cv / sim if sim else None),
                         _f(cv / cv0 if cv0 else None, "{:.3f}"), "" if v == "all" else str(bad)])
    widths = [max(len(str(r[i])) for r in sums) for i in range(len(sums[0]))]
    text += ["  ".join(str(c).ljust(w) for c, w in zip(r, widths)).rstrip() for r in sums]
    return "\n".join(text)


def harness_path(out: Path, duration: float) -> Path:
    """The 64 x 1,000 harness scene, settled, written under `out`."""
    from cablecheck.bench.harness import SETTLE, harness_scene, write_scene

    data = harness_scene(64, 1000, duration=duration, settle=SETTLE)
    return write_scene(data, out / "harness_64x1000.toml")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--groups", default="examples,zoo,harness", help="examples, zoo, harness (comma-separated)")
    ap.add_argument("--zoo", type=Path, default=Path("/tmp/zoo_doc2"),
                    help="folder of zoo scenes (bench_robots.py --keep DIR)")
    ap.add_argument("--layers", default=",".join(LAYERS), help="layers to take out, one at a time")
    ap.add_argument("--harness-duration", type=float, default=0.5, help="simulated seconds of the harness run")
    ap.add_argument("--repeat", type=int, default=1, help="runs per variant; the smallest times kept")
    ap.add_argument("--only", default="", help="scene stems to run (comma-separated; default all)")
    ap.add_argument("--out", type=Path, default=None, help="folder for the reports (default: a temporary one)")
    a = ap.parse_args(argv)
    layers = [x for x in a.layers.split(",") if x]
    if set(layers) - set(LAYERS):
        ap.error(f"unknown layers {sorted(set(layers) - set(LAYERS))}; known: {', '.join(LAYERS)}")
    groups = [x for x in a.groups.split(",") if x]
    only = {x for x in a.only.split(",") if x}
    out = a.out or Path(tempfile.mkdtemp(prefix="bench_layers_"))
    out.mkdir(parents=True, exist_ok=True)
    started = datetime.datetime.now(datetime.UTC)
    load0 = os.getloadavg()
    scenes: list[tuple[str, Path]] = []
    if "examples" in groups:
        scenes += [("examples", p) for p in sorted((REPO / "scenes").glob("*.toml"))]
    if "zoo" in groups:
        zoo = sorted(p for p in a.zoo.glob("*.toml") if not p.stem.endswith("_100hz"))
        if not zoo:
            print(f"no zoo scenes in {a.zoo} (benchmarks/bench_robots.py --keep DIR writes them)", file=sys.stderr)
        scenes += [("zoo", p) for p in zoo]
    if "harness" in groups:
        scenes.append(("harness", harness_path(out, a.harness_duration)))
    if only:
        scenes = [(g, p) for g, p in scenes if p.stem in only]
    variants = ["all"] + layers
    rows = []
    for group, path in scenes:
        t0 = time.perf_counter()
        found = run_scene_variants(path, variants, a.repeat, out)
        rows.append((group, path.stem, found))
        base = found["all"]
        same = " ".join(f"-{v}:{'same' if _same(base, found[v])[0] else 'DIFFERENT'}" for v in layers)
        print(f"[{group}] {path.stem}: " + " ".join(
            f"{v} c+v {found[v]['check'] + found[v]['validate']:.2f}" for v in variants)
            + f"  events {same}  ({time.perf_counter() - t0:.0f} s)", flush=True)
    print()
    print(table(rows, layers))
    load1 = os.getloadavg()
    print()
    print(f"{started:%Y-%m-%d %H:%M} UTC; machine: {os.cpu_count()} cores; load average "
          f"{load0[0]:.2f} / {load0[1]:.2f} / {load0[2]:.2f} at the start, "
          f"{load1[0]:.2f} / {load1[1]:.2f} / {load1[2]:.2f} at the end; python {sys.version.split()[0]}; "
          f"repeat {a.repeat}; reports in {out}")
    print("command: python benchmarks/bench_layers.py " + " ".join(sys.argv[1:] if argv is None else argv))
    return 0


if __name__ == "__main__":
    sys.exit(main())
