"""One `cablecheck sweep`: a scene's parts at t = 0, one part or assembly moved along a line.

`sweep_scene` builds the scene's MuJoCo model (without the detection model),
reads every part's geometry and its pose at t = 0 from it (so parts of an
mjcf base model work like `[[parts]]`), prepares the parts once
(`checker.partset.PartSet`) and runs `checker.sweep.sweep`. It returns the
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

from checker.partset import PartSet
from sim.report import write_report
from checker.shapes import Shape, ShapeType, mesh_shape
from checker.sweep import sweep
from sim.build import Built, build
from sim.loop import Simulation
from sim.scene import Scene

SCHEMA = "cablecheck.sweep/1"
"""The sweep report's schema name."""

DEFAULT_PRECISION_M = 5e-4
"""Default precision: 0.5 mm (as in the sweep-verification paper), in metres."""


class SweepInputError(ValueError):
    """A sweep option that cannot be used; `option` names it (e.g. ``--part``)."""

    def __init__(self, option: str, problem: str):
        super().__init__(f"{option}: {problem}")
        self.option = option
        self.problem = problem


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


def part_shapes(built: Built) -> list[Shape]:
    """The checker's shape of every built part (geom frame, metres)."""
    out = []
    for p in built.parts:
        if p.shape == "mesh":
            out.append(mesh_shape(p.vertices, p.faces))
        else:
            out.append(Shape(ShapeType(p.shape), p.size))
    return out


def start_poses(built: Built) -> np.ndarray:
    """(P, 4, 4) world poses of the parts at t = 0 (motion's first keys, no settling needed)."""
    sim = Simulation(built)
    sim.reset()
    return sim.state(0, contacts=False).part_poses


def rigid_groups(built: Built) -> list[str]:
    """Per part, the rigid group it moves with: the top body of its weld group
    (MuJoCo's ``body_weldid``: bodies joined without a joint move as one)."""
    m = built.model
    out = []
    for p in built.parts:
        weld = int(m.body_weldid[int(m.geom_bodyid[p.geom_id])])
        out.append(m.body(weld).name or "world")
    return out


def part_set(built: Built, tolerance: float, shapes: list[Shape] | None = None) -> PartSet:
    """The built parts prepared for sweeps and part-part checks (``shapes``: already built ones)."""
    return PartSet.build([p.name for p in built.parts], shapes or part_shapes(built),
                         groups=rigid_groups(built),
                         keepout=[p.keepout for p in built.parts], tolerance=tolerance)


def selection(parts: PartSet, path: str, option: str) -> np.ndarray:
    """(P,) bool of the parts at ``path`` (a part name or assembly prefix), or SweepInputError."""
    sel = parts.select(path)
    if not sel.any():
        import difflib
        close = difflib.get_close_matches(path, list(parts.names), n=3, cutoff=0.5)
        hint = f" (did you mean {', '.join(map(repr, close))}?)" if close else \
            f" (parts: {', '.join(list(parts.names)[:8])}{', ...' if len(parts.names) > 8 else ''})"
        raise SweepInputError(option, f"no part or assembly named {path!r}{hint}")
    return sel


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
    moving = selection(parts, options.part, "--part")
    if (moving & parts.plane).any():
        raise SweepInputError("--part", f"{options.part!r} includes an infinite plane, which cannot move")
    against = None
    if options.only is not None:
        against = selection(parts, options.only, "--only")
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
