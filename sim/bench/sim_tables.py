"""The bench tables that run MuJoCo: the cable model against analytic
references (``physics``), the checker beside python-fcl and MuJoCo's own
collision (``side_by_side``) and the per-step cost of the example scenes
(``example_scenes``).

The sizes come from a `BenchSizes` (`cablecheck.bench.command`). The tables of the checker
alone are in `cablecheck.bench.checker_tables`; nothing here changes a setting of a run or
asserts a time.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from cablecheck.bench import reference
from cablecheck.bench.fcl import INSTALL, FclMissing, fcl_queries
from cablecheck.bench.physics_cases import settled
from cablecheck.bench.scenes import make_scene, synthetic_scene
from cablecheck.bench.table import Table, median_time
from cablecheck.build.checkview import part_shapes
from cablecheck.build.stages import build
from cablecheck.checker.interference import Checker
from cablecheck.checker.scene_state import CheckConfig, PartState
from cablecheck.run.loop import Simulation
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import load_scene

if TYPE_CHECKING:   # the sizes live with the bench that orders the tables
    from cablecheck.bench.command import BenchSizes

REPO = Path(__file__).resolve().parents[2]   # sim/bench/ -> the repository (its scenes/)
"""The repository root (the example scenes live in ``scenes/``)."""


def example_names() -> list[str]:
    """The example scenes in ``scenes/``: drawer and arm first, then the rest by name."""
    first = ["drawer", "arm"]
    return first + sorted(p.stem for p in (REPO / "scenes").glob("*.toml") if p.stem not in first)


def physics_table(sizes: BenchSizes) -> Table:
    """Elements and timestep against the catenary and the cantilever."""
    table = Table("physics", "Physics resolution: error against analytic references, cost per simulated second",
                  ["reference", "elements", "elements_per_m", "timestep_ms", "error_pct",
                   "ms_per_sim_s", "warnings"])
    grid = {"catenary": sizes.catenary, "cantilever": sizes.cantilever}
    cat = reference.CATENARY
    sag_ref = reference.catenary_sag(cat["span"], cat["length"])
    for n, dt in grid["catenary"]:
        scene = reference.catenary_scene(n, timestep=dt, settle=3.0)
        _, sim, state, wall_per_s = settled(scene)
        sag = cat["height"] - state.cables[0][:, 2].min()
        table.add("catenary", n, n / cat["length"], 1e3 * dt, 100 * (sag / sag_ref - 1.0),
                  1e3 * wall_per_s, ",".join(sim.warnings()) or "")
    can = reference.CANTILEVER
    tip_ref = reference.cantilever_tip(can["length"], can["radius"], can["density"], can["young"])
    for n, dt in grid["cantilever"]:
        scene = reference.cantilever_scene(n, timestep=dt, settle=1.0)
        _, sim, state, wall_per_s = settled(scene)
        tip = can["height"] - state.cables[0][-1, 2]
        table.add("cantilever", n, n / can["length"], 1e3 * dt, 100 * (tip / tip_ref - 1.0),
                  1e3 * wall_per_s, ",".join(sim.warnings()) or "")
    table.notes += [
        f"catenary: limp cable (young 1 Pa) of {cat['length']} m over a {cat['span']} m span, "
        f"reference sag {sag_ref * 1e3:.2f} mm, 3 s settled; cantilever: {can['length']} m rod, "
        f"r {can['radius'] * 1e3:g} mm, E {can['young']:.0e} Pa, w L^4/8EI = {tip_ref * 1e3:.3f} mm, 1 s settled.",
        "error_pct: signed, measured minus reference over reference. Clamps hold a short edge "
        "(cablecheck.build.cableplan.clamp_edges); docs/physics.md has the full validation table.",
        "ms_per_sim_s: wall time of settling divided by simulated seconds (mj_step only).",
    ]
    return table


def mujoco_side(scene, repeat: int) -> dict:
    """Checker time beside the detection model's mj_kinematics + mj_collision on one state."""
    built = build(scene, detect=True)
    sim = Simulation(built)
    sim.reset()
    sim.settle()
    state = sim.state(0, contacts=False)
    shapes = part_shapes(built)
    parts = [PartState(p.name, sh, pose, p.keepout) for p, sh, pose in zip(built.parts, shapes, state.part_poses)]
    from cablecheck.run.stepcheck import cable_states  # the run's own CableStates
    cables = cable_states(built, state.cables)
    out = {"n_cables": len(cables), "n_points": sum(len(c.points) for c in cables), "n_parts": len(parts)}
    for method in ("points", "exact"):
        cfg = CheckConfig(method, scene.check.spacing, scene.check.clearance)
        checker = Checker(parts, cfg)
        out[method] = median_time(lambda: checker.check(cables, state.part_poses), repeat)
    d = sim.data
    m2, d2 = built.detect, sim.detector.detect_data
    d2.qpos[:] = d.qpos
    mujoco.mj_kinematics(m2, d2)
    mujoco.mj_flex(m2, d2)
    out["mj_collision"] = median_time(lambda: mujoco.mj_collision(m2, d2), repeat)
    out["detect"] = median_time(lambda: sim.detector.detect(d), repeat)
    out["contacts"] = int(d2.ncon)
    return out


def side_by_side_table(sizes: BenchSizes) -> tuple[Table, dict]:
    """The checker beside python-fcl and MuJoCo's collision on the same queries and models.

    The found dict holds the times (s) by name and ``scene``: (points,
    parts) of the randomised scene the targets are stated for."""
    repeat = sizes.side_repeat
    table = Table("side_by_side", "Side by side: the checker, python-fcl and MuJoCo's mj_collision",
                  ["scene", "method", "points", "parts", "checker_ms", "other", "other_ms", "ratio"])
    found = {}
    n_cables, n_points, n_prims, n_meshes = sizes.side_scene
    cables, parts = make_scene(n_cables=n_cables, n_points=n_points, n_prims=n_prims, n_meshes=n_meshes)
    n_pts = sum(len(c.points) for c in cables)
    found["scene"] = (n_pts, len(parts))
    label = f"random {n_cables}x{n_points}/{len(parts)}"
    poses = np.array([p.pose for p in parts]).reshape(-1, 4, 4)
    for method in ("points", "exact"):
        checker = Checker(parts, CheckConfig(method))
        t = median_time(lambda: checker.check(cables, poses), repeat)
        found[f"checker_{method}"] = t
        try:
            upd, qry, _ = fcl_queries(cables, parts, CheckConfig(method), sizes.fcl_repeat)
        except FclMissing:
            table.add(label, method, n_pts, len(parts), 1e3 * t,
                      f"python-fcl not installed ({INSTALL})", None, None)
            continue
        found[f"fcl_{method}"] = upd + qry
        table.add(label, method, n_pts, len(parts), 1e3 * t, "fcl update+query",
                  1e3 * (upd + qry), (upd + qry) / t)
        table.add(label, method, n_pts, len(parts), 1e3 * t, "fcl query only",
                  1e3 * qry, qry / t)
    scenes = [(f"synthetic {n} cables/{p} parts", synthetic_scene(n, s, p)) for n, s, p in sizes.synthetic]
    scenes += [(name, load_scene(REPO / "scenes" / f"{name}.toml")) for name in sizes.side_examples]
    for label, scene in scenes:
        res = mujoco_side(scene, 5 * repeat)
        for method in ("points", "exact"):
            table.add(label, method, res["n_points"], res["n_parts"], 1e3 * res[method], "mj_collision",
                      1e3 * res["mj_collision"], res["mj_collision"] / res[method])
        table.add(label, "points", res["n_points"], res["n_parts"], 1e3 * res["points"],
                  "detect (kinematics+collision)", 1e3 * res["detect"], res["detect"] / res["points"])
        found[label] = res
    table.notes += [
        "ratio: the other tool's time over the checker's (above 1: the checker is faster).",
        "fcl: spheres at the discrete points (points) or capsules per element (exact), inflated by "
        "half the clearance, in a dynamic AABB tree; update = moving every piece, query = cable-part "
        "and cable-cable collide calls with a narrow test per broad-phase pair (pairs only, no distances).",
        "mj_collision: MuJoCo's broad and narrow phase on the detection model (every interaction "
        "enabled, margin from the clearance) at the same state; detect adds mj_kinematics, "
        "mj_flex and reading the contacts, as every validated step does.",
    ]
    return table, found


def _mj_step_ms(scene, steps: int) -> float:
    """Median per-step time of mj_step alone on the scene's simulation model (after settling)."""
    built = build(scene, detect=False)
    sim = Simulation(built)
    sim.reset()
    sim.settle()
    m, d = built.model, sim.data
    ts = []
    for k in range(steps):
        sim.motion.apply(d, k * scene.timestep)
        t0 = time.perf_counter()
        mujoco.mj_step(m, d)
        ts.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(ts))


def example_scenes_table(sizes: BenchSizes, out: Path) -> tuple[Table, dict]:
    """Per-step cost of the example scenes from a full run with recording on."""

    table = Table("example_scenes", "Per-step cost on the example scenes (recording on)",
                  ["scene", "steps", "mj_step_ms", "sim_ms", "check_ms", "validate_ms",
                   "check_plus_validate_ms", "record_ms", "cost_over_mj_step", "realtime_factor",
                   "realtime_factor_total", "full_checks", "proven_clear"])
    found = {}
    names = sizes.examples or example_names()
    for name in names:
        scene = load_scene(REPO / "scenes" / f"{name}.toml")
        if sizes.example_seconds is not None:
            scene = dataclasses.replace(scene, duration=min(scene.duration, sizes.example_seconds))
        rep = run_scene(scene, RunOptions(report=out / f"{name}.json", record=out / f"{name}.rrd"))
        t = rep["timing"]
        steps = rep["settings"]["steps"]
        loop = t["loop_s"]
        mj = _mj_step_ms(scene, min(steps, 500))
        cv = t["check_ms_per_step"] + t["validate_ms_per_step"]
        row = dict(mj=mj, cv=cv, rtf=scene.duration / loop, rtf_total=scene.duration / t["total_s"])
        found[name] = row
        table.add(name, steps, mj, t["sim_ms_per_step"], t["check_ms_per_step"], t["validate_ms_per_step"],
                  cv, t["record_ms_per_step"], cv / mj, row["rtf"], row["rtf_total"],
                  *((adv["full_checks"], adv["proven_clear_steps"]) if (adv := rep["settings"]["advance"])
                    else (rep["settings"]["checked_steps"], 0)))
    table.notes += [
        "mj_step_ms: median of mj_step alone on the simulation model; sim_ms: the run's simulation "
        "stage per step (mj_step and positions).",
        "check: cable and part-part checks, strain and bend per step; validate: the detection model's "
        "collision pass (mj_kinematics, mj_flex, mj_collision) and comparing its contacts; record: rerun logging (sampled at 100 frames per simulated second).",
        "realtime_factor: simulated seconds over the step loop's wall time (the report's loop_s: the "
        "simulation stepping ahead in a process of its own while the checks run; it settles and starts stepping "
        "while the run still builds, so the loop is shorter than the simulation); _total is the whole run's.",
        "full_checks / proven_clear: checked steps run in full and steps the skip rule (cablecheck.checker.advance) "
        "proved clear; a pair inside the clearance (or whose own bound fails) is then checked on its own.",
    ] + ([f"each scene runs its first {sizes.example_seconds:g} simulated second(s) only."]
         if sizes.example_seconds is not None else [])
    return table, found
