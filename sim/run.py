"""One `cablecheck run`: build, settle, step, measure, record and report.

Data flows one way: scene -> models -> steps -> (cable body centres, part
poses, MuJoCo contacts) -> per-cable measures and checks -> report and
recording. `run_scene` owns the order of those stages, their timing, and
what happens on Ctrl-C: the loop stops, the recording is finished and moved
into place, and the report is written with `"complete": false`.

This module does not parse arguments or print (see `cli`), and holds no
geometry of its own: distances come from `checker`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from checker.curve import bend_radius
from checker.report import SCHEMA, write_report
from sim.build import Built, build
from sim.loop import Simulation
from sim.record import Recorder
from sim.scene import Scene

TAUT_STRAIN = 0.01
"""Stretch beyond which a cable is reported taut (SPEC: 1 %)."""


@dataclass(frozen=True)
class RunOptions:
    """How to run a scene.

    Attributes:
      report: report path.
      record: recording path, or None for no recording.
      method, spacing: override the scene's `[check]` values when not None.
    """

    report: Path
    record: Path | None
    method: str | None = None
    spacing: float | None = None


Progress = Callable[[str, float, float], None]
"""progress(stage, done, total): called as a run advances."""


class _Timer:
    """Wall-clock seconds per stage."""

    def __init__(self):
        self.total = {"sim": 0.0, "check": 0.0, "validate": 0.0, "record": 0.0}
        self._t = time.perf_counter()

    def lap(self, stage: str) -> None:
        now = time.perf_counter()
        self.total[stage] += now - self._t
        self._t = now


def _min_bend(points: np.ndarray) -> float:
    radii = bend_radius(points)
    return float(np.min(radii)) if len(radii) else float("inf")


def run_scene(scene: Scene, options: RunOptions, progress: Progress | None = None) -> dict:
    """Run `scene`; write the report (and recording); return the report dict."""
    start = time.perf_counter()
    built = build(scene, detect=scene.check.validate)
    sim = Simulation(built)
    sim.reset()
    if progress:
        progress("settle", 0, max(sim.settle_steps, 1))
    sim.settle(None if progress is None else
               (lambda k: progress("settle", k, sim.settle_steps) if k % 50 == 0 else None))
    recorder = Recorder(built, options.record) if options.record else None
    timer = _Timer()
    cables = built.cables
    n = len(cables)
    max_strain = np.full(n, -np.inf)
    min_bend = np.full(n, np.inf)
    rest_points: list[np.ndarray] = []
    final_points: list[np.ndarray] = []
    steps = checked = 0
    t_last = 0.0
    complete = False
    try:
        for state in sim.steps(contacts=False, every=scene.check.every):
            timer.lap("sim")
            if state.step == 0:
                rest_points = state.cables
                if recorder:
                    recorder.log_static(state.part_poses)
            strain = np.array([np.linalg.norm(np.diff(p, axis=0), axis=1).sum() / c.length - 1.0
                               for p, c in zip(state.cables, cables)])
            bend = np.array([_min_bend(p) for p in state.cables])
            max_strain = np.maximum(max_strain, strain)
            min_bend = np.minimum(min_bend, bend)
            timer.lap("check")
            if recorder:
                recorder.log_step(state.t, state.cables, state.part_poses, strain=strain, bend=bend)
                timer.lap("record")
            final_points = state.cables
            steps, t_last = state.step, state.t
            checked += 1
            if progress:
                progress("run", state.step, sim.total_steps)
        complete = True
    except KeyboardInterrupt:
        complete = False
    finally:
        if recorder:
            recorder.close()
            timer.lap("record")
    total = time.perf_counter() - start
    report = _report(scene, built, options, complete, steps, checked, t_last,
                     max_strain, min_bend, rest_points, final_points, timer, total, sim)
    write_report(report, options.report)
    return report


def _report(scene: Scene, built: Built, options: RunOptions, complete: bool, steps: int,
            checked: int, t_last: float, max_strain, min_bend, rest_points, final_points,
            timer: _Timer, total: float, sim: Simulation) -> dict:
    u = scene.scale
    method = options.method or scene.check.method
    spacing = options.spacing or scene.check.spacing
    radii = [c.radius for c in built.cables]
    cables = []
    for i, c in enumerate(built.cables):
        limit = c.min_bend_radius
        cables.append({
            "name": c.name,
            "length": c.length / u,
            "segments": c.count - 1,
            "max_strain": max_strain[i] if checked else None,
            "taut": bool(checked and max_strain[i] > TAUT_STRAIN),
            "min_bend_radius": min_bend[i] / u if checked else None,
            "bend_violation": bool(limit is not None and checked and min_bend[i] < limit),
            "rest_points": (np.asarray(rest_points[i]) / u) if rest_points else [],
            "final_points": (np.asarray(final_points[i]) / u) if final_points else [],
        })
    check_steps = max(checked, 1)
    return {
        "schema": SCHEMA,
        "scene": scene.name,
        "units": scene.units,
        "complete": complete,
        "mujoco": mujoco.__version__,
        "settings": {
            "method": method,
            # discrete-point spacing in scene units for the thinnest cable
            "spacing": (spacing * min(radii) / u) if radii else None,
            "spacing_radii": spacing,
            "clearance": scene.check.clearance / u,
            "timestep": scene.timestep,
            "settle": scene.settle,
            "duration": scene.duration,
            "dynamics": scene.effects.dynamics,
            "gravity": scene.effects.gravity,
            "contact": sorted(scene.effects.contact),
            "steps": steps,
            "checked_steps": checked,
            "t_end": t_last,
        },
        "cables": cables,
        "warnings": sim.warnings(),
        "timing": {
            "total_s": total,
            "sim_s": timer.total["sim"],
            "check_s": timer.total["check"],
            "validate_s": timer.total["validate"],
            "record_s": timer.total["record"],
            "check_ms_per_step": 1e3 * timer.total["check"] / check_steps,
            "sim_ms_per_step": 1e3 * timer.total["sim"] / max(steps, 1),
        },
        "recording": str(options.record) if options.record else None,
    }
