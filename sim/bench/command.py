"""`cablecheck bench`: what accuracy costs in time, measured in one run.

Tables (printed, and written as CSV into the output folder with a PNG plot;
the sizes are those of `FULL`):

- ``discretisation``: method ``points`` at spacing 4r, 2r, r, r/2, the
  paper's face-plane distance (``|BP . N|``, spacing 2r) and method
  ``exact`` on randomised cable-and-part scenes. The reference answer is the
  exact method (segment distances: capsules against capsules and part
  surfaces); it is itself cross-checked against dense points (spacing r/8).
  Per configuration: time per check (on the randomised scenes and on a
  20,000-point scene), missed hard pairs, missed pairs, false alarms and the
  worst distance error on pairs both report.
- ``physics``: elements and timestep of the cable model against the analytic
  catenary sag and small-deflection cantilever (:mod:`cablecheck.bench.reference`): error
  and wall time per simulated second.
- ``scale``: time per check from 1 to 200 cables and 10 to 2,000 parts, with
  time per point and the fitted growth exponent.
- ``side_by_side``: the checker beside python-fcl (same cable-part and
  cable-cable close-pair queries) and beside MuJoCo's own ``mj_collision`` on
  the detection model of the same scene, with ratios.
- ``paper``: the discrete-point paper's simple and complex cases in kind, our time beside
  the paper's 0.008-6.3 s (cable-cable) and 0.24-12.4 s (cable-structure).
- ``example_scenes``: per-step cost of every scene in ``scenes/``, drawer
  and arm first (check, validation, recording against ``mj_step``) and
  real-time factor with recording on.
- ``targets``: the performance targets, met or not, from the numbers
  above.

Timings are medians of repeats measured side by side in the same process;
nothing asserts a time. The sizes of every table are one `BenchSizes`:
`FULL` (``cablecheck bench``), `QUICK` (``--quick``) or a caller's own (the
tests run a tiny one). This module holds the sizes, the targets and the
order of the run; the tables are measured in `cablecheck.bench.checker_tables` (the checker
alone) and `cablecheck.bench.sim_tables` (with MuJoCo), on the scenes of `cablecheck.bench.scenes`,
and drawn by `cablecheck.bench.plot`. It does not change any setting of a run and
is not used by `cablecheck run`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from cablecheck.bench.checker_tables import discretisation_table, paper_table, scale_table
from cablecheck.bench.plot import plot
from cablecheck.bench.sim_tables import example_scenes_table, physics_table, side_by_side_table
from cablecheck.bench.table import Table


@dataclass(frozen=True)
class BenchSizes:
    """How much each table measures: the scenes, their sizes and the repeats.

    Attributes:
      name: printed in the bench's first line ("full", "quick", ...).
      repeat: timed repeats per cell of the discretisation, scale and paper tables.
      disc_scenes: randomised scenes of the discretisation table.
      large_cables: cables (of 100 body centres) of its large scene.
      catenary, cantilever: (elements, timestep s) of the physics table.
      scale_cables, scale_parts: the two axes of the scale table, at least
        three values each (the growth is fitted from the second up);
        scale_held_parts and scale_held_cables hold the other axis.
      side_scene: (cables, points per cable, primitives, meshes) of the
        randomised scene the checker, python-fcl and the targets are timed on.
      side_repeat, fcl_repeat: repeats of the side-by-side table (MuJoCo's
        side five times as many) and of the fcl queries.
      synthetic: (cables, segments, parts) of the synthetic scenes timed
        beside mj_collision; side_examples: example scenes timed so too.
      paper_cases: (case, cables, parts) of the paper table.
      examples: the example scenes of the per-step table; () for all of them.
      example_seconds: simulated seconds of each, at most; None: the whole scene.
    """

    name: str
    repeat: int
    disc_scenes: int
    large_cables: int
    catenary: tuple[tuple[int, float], ...]
    cantilever: tuple[tuple[int, float], ...]
    scale_cables: tuple[int, ...]
    scale_parts: tuple[int, ...]
    scale_held_parts: int
    scale_held_cables: int
    side_scene: tuple[int, int, int, int]
    side_repeat: int
    fcl_repeat: int
    synthetic: tuple[tuple[int, int, int], ...]
    side_examples: tuple[str, ...]
    paper_cases: tuple[tuple[str, int, int], ...]
    examples: tuple[str, ...]
    example_seconds: float | None


TARGET_SCENE = (100, 200, 300, 10)
"""The randomised scene the time targets are stated for: 100 cables x 200
body centres (20,000 points) among 300 primitives and 10 meshes."""

FULL = BenchSizes(
    name="full", repeat=7, disc_scenes=12, large_cables=100,
    catenary=((10, 0.002), (20, 0.002), (40, 0.002), (80, 0.002), (40, 0.004), (40, 0.001), (80, 0.001)),
    cantilever=((10, 0.002), (20, 0.002), (30, 0.002), (45, 0.002), (40, 0.004), (40, 0.001), (45, 0.001)),
    scale_cables=(1, 10, 50, 100, 200), scale_parts=(10, 100, 310, 1000, 2000),
    scale_held_parts=310, scale_held_cables=100,
    side_scene=TARGET_SCENE, side_repeat=9, fcl_repeat=6,
    synthetic=((10, 40, 50), (60, 60, 300)), side_examples=("drawer", "arm"),
    paper_cases=(("simple", 5, 20), ("simple", 50, 100), ("complex", 120, 250), ("complex", 200, 2000)),
    examples=(), example_seconds=None)
"""`cablecheck bench`."""

QUICK = BenchSizes(
    name="quick", repeat=3, disc_scenes=4, large_cables=100,
    catenary=((20, 0.002), (40, 0.002), (40, 0.001)),
    cantilever=((20, 0.002), (40, 0.002), (40, 0.001)),
    scale_cables=FULL.scale_cables, scale_parts=FULL.scale_parts,
    scale_held_parts=310, scale_held_cables=100,
    side_scene=TARGET_SCENE, side_repeat=3, fcl_repeat=3,
    synthetic=((10, 40, 50),), side_examples=("drawer", "arm"),
    paper_cases=FULL.paper_cases, examples=(), example_seconds=1.0)
"""`cablecheck bench --quick`: fewer repeats and references, each example
scene's first simulated second."""


def targets_table(side: dict, examples: dict) -> Table:
    """The performance targets against this run's numbers.

    The check-time targets are stated for `TARGET_SCENE`; measured on a
    scene of another size they are shown but neither met nor missed."""
    table = Table("targets", "Performance targets on this machine", ["target", "measured", "met"])
    tp, te = side["checker_points"], side["checker_exact"]
    n_pts, n_parts = side["scene"]
    at_size = (n_pts, n_parts) == (TARGET_SCENE[0] * TARGET_SCENE[1], TARGET_SCENE[2] + TARGET_SCENE[3])
    on = "" if at_size else f" (measured on {n_pts:,} points x {n_parts} parts)"
    table.add("20,000 points x 310 parts, points < 10 ms", f"{tp * 1e3:.2f} ms{on}",
              tp < 0.010 if at_size else None)
    table.add("20,000 points x 310 parts, exact < 30 ms", f"{te * 1e3:.2f} ms{on}",
              te < 0.030 if at_size else None)
    for method in ("points", "exact"):
        if f"fcl_{method}" in side:
            ratio = side[f"fcl_{method}"] / side[f"checker_{method}"]
            table.add(f"checker >= 5x faster than python-fcl ({method})", f"{ratio:.1f}x", ratio >= 5)
        else:
            table.add(f"checker >= 5x faster than python-fcl ({method})", "python-fcl not installed", None)
    d = examples.get("drawer")
    if d is None:
        table.add("drawer: check + validation per step < mj_step", "drawer not run", None)
        table.add("drawer faster than real time with recording", "drawer not run", None)
        return table
    table.add("drawer: check + validation per step < mj_step",
              f"{d['cv']:.3f} ms vs {d['mj']:.3f} ms", d["cv"] < d["mj"])
    table.add("drawer faster than real time with recording", f"{d['rtf']:.2f}x real time", d["rtf"] > 1.0)
    return table


def run_bench(sizes: BenchSizes = FULL, out: Path = Path("recordings/bench"),
              echo: Callable[[str], None] = print) -> dict[str, Table]:
    """Measure everything at `sizes`, print each table as it completes, write
    CSVs and the plot into `out`."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    tables: dict[str, Table] = {}

    def done(table: Table) -> None:
        tables[table.name] = table
        table.write_csv(out)
        echo(table.text())

    echo(f"cablecheck bench ({sizes.name} sizes): MuJoCo {mujoco.__version__}, "
         f"numpy {np.__version__}; medians of repeats, one process")
    done(discretisation_table(sizes))
    done(physics_table(sizes))
    done(scale_table(sizes))
    side, side_found = side_by_side_table(sizes)
    done(side)
    done(paper_table(sizes))
    ex, ex_found = example_scenes_table(sizes, out)
    done(ex)
    done(targets_table(side_found, ex_found))
    png = plot(tables, out / "bench.png")
    echo(f"\nwrote {', '.join(sorted(t + '.csv' for t in tables))} and {png.name} into {out} "
         f"({time.perf_counter() - t0:.1f} s)")
    return tables
