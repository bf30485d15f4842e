"""One `cablecheck sweep`: a scene's parts at t = 0, one part or assembly moved along a line.

`sweep_scene` builds the scene's MuJoCo model (without the detection model),
reads every part's geometry and its pose at t = 0 from it (so parts of an
mjcf base model work like `[[parts]]`), prepares the parts once through the
checker's view of the scene (`cablecheck.build.checkview`, as a run does) and runs
`cablecheck.checker.sweep.sweep`. It returns the
report dict (schema ``cablecheck.sweep/1``) and writes it atomically.

Units: the geometry is in metres inside; the report and the options are in
scene units. Precision: curved primitives are tessellated within a quarter of
the precision, and a contact must lead to overlap within a quarter of the
precision to count as a hit; first-contact travels are exact for the
tessellated surfaces (boxes and meshes are exact).

This module does not parse arguments or print (see `cli`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cablecheck.build.built import Built
from cablecheck.build.checkview import DEFAULT_PRECISION_M, OptionError, part_set, selection
from cablecheck.build.stages import build
from cablecheck.checker.sweep import sweep
from cablecheck.report.document import write_report
from cablecheck.run.loop import Simulation
from cablecheck.scene.records import Scene

SCHEMA = "cablecheck.sweep/1"
"""The sweep report's schema name."""


class SweepInputError(OptionError):
    """A sweep option that cannot be used; `option` names it (e.g. ``--part``)."""


@dataclass(frozen=True)
class SweepOptions:
    """What to sweep.

    Attributes:
      part: part name or assembly path prefix.
      direction: (3,) direction in scene (world) axes.
      distance: travel, scene units.
      precision: scene units, or None for 0.5 mm.
      only: restrict the parts tested to this assembly path (and the mover), or None.
      report: JSON path, or None for no file.
    """

    part: str
    direction: tuple[float, float, float]
    distance: float
    precision: float | None = None
    only: str | None = None
    report: Path | None = None


def start_poses(built: Built) -> np.ndarray:
    """(P, 4, 4) world poses of the parts at t = 0 (motion's first keys, no settling needed)."""
    sim = Simulation(built)
    sim.reset()
    return sim.state(0, contacts=False).part_poses


def _selection(parts, path: str, option: str) -> np.ndarray:
    """`cablecheck.build.checkview.selection`, its error as the sweep's."""
    try:
        return selection(parts, path, option)
    except OptionError as e:
        raise SweepInputError(e.option, e.problem) from None


def sweep_scene(scene: Scene, options: SweepOptions) -> dict:
    """Run the sweep; write the report when asked; return the report dict."""
    u = scene.scale
    d = np.asarray(options.direction, float)
    if d.shape != (3,) or not np.all(np.isfinite(d)) or not np.linalg.norm(d) > 0:
        raise SweepInputError("--direction", f"must be a finite non-zero X,Y,Z vector, got {options.direction}")
    if not (np.isfinite(options.distance) and options.distance >= 0):
        raise SweepInputError("--distance", f"must be a non-negative number, got {options.distance}")
    precision_m = DEFAULT_PRECISION_M if options.precision is None else options.precision * u
    if not (np.isfinite(precision_m) and precision_m > 0):
        raise SweepInputError("--precision", f"must be a positive number, got {options.precision}")
    built = build(scene, detect=False)
    parts = part_set(built, tolerance=0.25 * precision_m)
    moving = _selection(parts, options.part, "--part")
    if (moving & parts.plane).any():
        raise SweepInputError("--part", f"{options.part!r} includes an infinite plane, which cannot move")
    against = None if options.only is None else _selection(parts, options.only, "--only")
    placed = parts.place(start_poses(built))
    result = sweep(parts, placed, moving, d, options.distance * u, against=against,
                   step=0.25 * precision_m)
    unit = d / np.linalg.norm(d)
    report = {
        "schema": SCHEMA,
        "scene": scene.name,
        "units": scene.units,
        "part": options.part,
        "moving": [n for n, m in zip(parts.names, moving) if m],
        "direction": unit,
        "distance": options.distance,
        "precision": precision_m / u,
        "only": options.only,
        "hits": [{"part": h.part, "distance": h.distance / u, "where": h.where / u, "by": h.by}
                 for h in result.hits],
        "overlapping": list(result.overlapping),
        "tessellation_error": {n: float(e) / u for n, e in zip(parts.names, parts.error) if e > 0},
        "warnings": list(result.warnings),
        "candidates": result.candidates,
    }
    if options.report is not None:
        write_report(report, options.report)
    return report
