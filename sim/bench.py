"""`cablecheck bench`: what accuracy costs in time, measured in one run.

Tables (printed, and written as CSV into the output folder with a PNG plot):

- ``discretisation``: method ``points`` at spacing 4r, 2r, r, r/2, the
  paper's face-plane distance (``|BP . N|``, spacing 2r) and method
  ``exact`` on randomised cable-and-part scenes. The reference answer is the
  exact method (segment distances: capsules against capsules and part
  surfaces); it is itself cross-checked against dense points (spacing r/8).
  Per configuration: time per check (on the randomised scenes and on a
  20,000-point scene), missed hard pairs, missed pairs, false alarms and the
  worst distance error on pairs both report.
- ``physics``: elements and timestep of the cable model against the analytic
  catenary sag and small-deflection cantilever (:mod:`sim.reference`): error
  and wall time per simulated second.
- ``scale``: time per check from 1 to 200 cables and 10 to 2,000 parts, with
  time per point and the fitted growth exponent.
- ``side_by_side``: the checker beside python-fcl (same cable-part and
  cable-cable close-pair queries) and beside MuJoCo's own ``mj_collision`` on
  the detection model of the same scene, with ratios.
- ``paper``: the discrete-point paper's simple and complex cases in kind, our time beside
  the paper's 0.008-6.3 s (cable-cable) and 0.24-12.4 s (cable-structure).
- ``example_scenes``: per-step cost of scenes/drawer.toml and scenes/arm.toml
  (check, validation, recording against ``mj_step``) and real-time factor
  with recording on.
- ``targets``: the performance targets, met or not, from the numbers
  above.

Timings are medians of repeats measured side by side in the same process;
this module asserts no time. It does not change any setting of a run and is
not used by `cablecheck run`.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from checker.benchscene import fcl_queries, make_scene
from checker.interference import Checker
from checker.records import PairType
from checker.scene_state import CheckConfig, PartState
from sim import reference
from sim.build import build
from sim.loop import Simulation
from sim.scene import load_scene, parse_scene
from sim.sweep import part_shapes
from sim.validation import settled

REPO = Path(__file__).resolve().parents[1]
"""The repository root (the example scenes live in ``scenes/``)."""

PAPER_CABLE_CABLE_S = (0.008, 6.3)
PAPER_CABLE_STRUCTURE_S = (0.24, 12.4)
"""The discrete-point paper's reported range of check times (2016 desktop), seconds."""

_DISTANCE_TYPES = (PairType.SELF, PairType.CABLE_CABLE, PairType.CABLE_STRUCTURE, PairType.KEEPOUT)


@dataclass
class Table:
    """One result table: a CSV file ``<name>.csv`` and a printed block."""

    name: str
    title: str
    columns: list[str]
    rows: list[list] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def add(self, *row) -> None:
        if len(row) != len(self.columns):
            raise ValueError(f"{self.name}: row of {len(row)} values for {len(self.columns)} columns")
        self.rows.append(list(row))

    def column(self, name: str) -> list:
        i = self.columns.index(name)
        return [r[i] for r in self.rows]

    def text(self) -> str:
        cells = [[_fmt(v) for v in r] for r in self.rows]
        widths = [max([len(c)] + [len(r[i]) for r in cells]) for i, c in enumerate(self.columns)]
        out = io.StringIO()
        out.write(f"\n{self.title}\n")
        out.write("  " + "  ".join(c.rjust(w) for c, w in zip(self.columns, widths)) + "\n")
        for r in cells:
            out.write("  " + "  ".join(v.rjust(w) for v, w in zip(r, widths)) + "\n")
        for n in self.notes:
            out.write(f"  - {n}\n")
        return out.getvalue()

    def write_csv(self, folder: Path) -> Path:
        path = folder / f"{self.name}.csv"
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(self.columns)
            for r in self.rows:
                w.writerow(["" if v is None else (f"{v:.6g}" if isinstance(v, float) else v) for v in r])
        return path


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if v == 0.0 or not math.isfinite(v):
            return f"{v:g}"
        return f"{v:.3g}" if abs(v) < 1e4 else f"{v:.0f}"
    return str(v)


def _median_time(fn: Callable[[], object], repeat: int) -> float:
    """Median wall seconds of `fn()` over `repeat` calls after one warm-up call."""
    fn()
    ts = []
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


def _poses(parts: Sequence[PartState]) -> np.ndarray:
    return np.array([p.pose for p in parts]).reshape(-1, 4, 4)


# -- discretisation -----------------------------------------------------------

RADIUS = 0.004
"""Cable radius of the randomised scenes, m."""


def _pairs(records) -> dict:
    return {(r.type, r.a, r.b): r.min_distance for r in records if r.type in _DISTANCE_TYPES}


def _compare(ref: dict, got: dict) -> tuple[int, int, int, float]:
    """(missed hard, missed any, false alarms, worst |distance error| on shared pairs)."""
    missed_hard = sum(1 for k, d in ref.items() if d < 0 and not (k in got and got[k] < 0))
    missed = sum(1 for k in ref if k not in got)
    false = sum(1 for k, d in got.items() if k not in ref or (d < 0 <= ref[k]))
    shared = [abs(got[k] - ref[k]) for k in got if k in ref]
    return missed_hard, missed, false, (max(shared) if shared else 0.0)


def discretisation_table(quick: bool) -> Table:
    """Spacing and method against the exact method on randomised scenes."""
    n_seeds = 4 if quick else 12
    repeat = 3 if quick else 7
    r = RADIUS
    # Elements 6r long, so that spacing 4r, 2r, r and r/2 all insert points.
    scenes = [make_scene(seed=1000 + s, n_cables=12, n_points=40, n_prims=40, n_meshes=2,
                         room=(0.4, 0.4, 0.25), step=6 * r) for s in range(n_seeds)]
    large = make_scene(seed=0, n_points=100, step=4 * r)  # 10,000 body centres, elements 4r
    n_large = sum(len(c.points) for c in large[0])
    configs = [
        ("points 4r", CheckConfig("points", 4.0)),
        ("points 2r", CheckConfig("points", 2.0)),
        ("points r", CheckConfig("points", 1.0)),
        ("points r/2", CheckConfig("points", 0.5)),
        ("face-plane 2r", CheckConfig("points", 2.0, face_plane=True)),
        ("exact", CheckConfig("exact")),
    ]
    refs = [_pairs(Checker(parts, CheckConfig("exact")).check(cables)) for cables, parts in scenes]
    table = Table("discretisation", "Discretisation: accuracy against exact geometry, time per check",
                  ["config", "spacing_r", "ms_per_check", "ms_large", "pairs", "ref_pairs",
                   "ref_hard", "missed_hard", "missed", "false_alarms", "worst_error_mm"])
    for label, cfg in configs:
        tot = [0, 0, 0, 0]
        worst = 0.0
        n_pairs = 0
        secs = 0.0
        for (cables, parts), ref in zip(scenes, refs):
            checker = Checker(parts, cfg)
            got = _pairs(checker.check(cables))
            mh, m, fa, err = _compare(ref, got)
            tot[0] += mh
            tot[1] += m
            tot[2] += fa
            worst = max(worst, err)
            n_pairs += len(got)
            secs += _median_time(lambda: checker.check(cables), repeat)
        big = Checker(large[1], cfg)
        t_large = _median_time(lambda: big.check(large[0]), max(2, repeat // 2))
        table.add(label, cfg.spacing if cfg.method == "points" else None, 1e3 * secs / len(scenes),
                  1e3 * t_large, n_pairs, sum(len(x) for x in refs),
                  sum(1 for x in refs for d in x.values() if d < 0), tot[0], tot[1], tot[2], 1e3 * worst)
    # The reference itself against dense points: points only over-estimate a
    # distance (they sample the centreline), so dense points bound it from above.
    dense = CheckConfig("points", 0.125)
    dmax = 0.0
    below = 0.0
    for (cables, parts), ref in zip(scenes, refs):
        got = _pairs(Checker(parts, dense).check(cables))
        for k in set(got) & set(ref):
            dmax = max(dmax, abs(got[k] - ref[k]))
            below = max(below, ref[k] - got[k])
    n_body = sum(len(c.points) for cables, _ in scenes for c in cables)
    table.notes += [
        f"{n_seeds} randomised scenes of 12 cables x 40 body centres (elements 6r, r = {r * 1e3:g} mm) and "
        f"40 primitives + 2 meshes in a 0.4 x 0.4 x 0.25 m box ({n_body} body centres in all); "
        "clearance 5 mm; pairs = self, cable-cable, cable-structure and keep-out pairs below the clearance.",
        "reference: method exact (segment distances to capsules and part surfaces); "
        f"dense points at r/8 agree with it within {dmax * 1e3:.3g} mm "
        f"(never below it by more than {max(below, 0.0) * 1e3:.2g} mm).",
        f"ms_large: the same configuration on a {len(large[0])}-cable scene of {n_large} body centres "
        f"(elements 4r) against {len(large[1])} parts.",
        "missed: reference pairs a configuration does not report; false alarms: pairs it reports that "
        "the reference does not, or hard where the reference is not.",
    ]
    return table


# -- physics resolution -------------------------------------------------------


def physics_table(quick: bool) -> Table:
    """Elements and timestep against the catenary and the cantilever."""
    table = Table("physics", "Physics resolution: error against analytic references, cost per simulated second",
                  ["reference", "elements", "elements_per_m", "timestep_ms", "error_pct",
                   "ms_per_sim_s", "warnings"])
    if quick:
        grid = {"catenary": [(20, 0.002), (40, 0.002), (40, 0.001)],
                "cantilever": [(20, 0.002), (40, 0.002), (40, 0.001)]}
    else:
        grid = {"catenary": [(10, 0.002), (20, 0.002), (40, 0.002), (80, 0.002), (40, 0.004),
                             (40, 0.001), (80, 0.001)],
                "cantilever": [(10, 0.002), (20, 0.002), (30, 0.002), (45, 0.002), (40, 0.004),
                               (40, 0.001), (45, 0.001)]}
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
        "(sim.build._clamp_edges); docs/physics.md has the full validation table.",
        "ms_per_sim_s: wall time of settling divided by simulated seconds (mj_step only).",
    ]
    return table


# -- scale -------------------------------------------------------------------

def _fit_exponent(x: Sequence[float], y: Sequence[float]) -> float:
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])


def _scene_for(n_cables: int, n_parts: int, seed: int = 0):
    n_meshes = max(1, round(n_parts / 31))
    return make_scene(seed=seed, n_cables=n_cables, n_points=200, n_prims=n_parts - n_meshes,
                      n_meshes=n_meshes)


def scale_table(quick: bool) -> Table:
    """Time per check as cables and parts grow."""
    repeat = 3 if quick else 7
    cable_axis = [1, 10, 50, 100, 200]
    part_axis = [10, 100, 310, 1000, 2000]
    table = Table("scale", "Scale: time per check against cables and parts (200 body centres per cable)",
                  ["axis", "cables", "points", "parts", "ms_points", "ms_exact", "us_per_point_points",
                   "us_per_point_exact"])
    fits = {}
    for axis, values in (("cables", cable_axis), ("parts", part_axis)):
        xs, tp, te = [], [], []
        for v in values:
            cables, parts = _scene_for(v, 310) if axis == "cables" else _scene_for(100, v)
            n_pts = sum(len(c.points) for c in cables)
            cp, ce = Checker(parts, CheckConfig("points")), Checker(parts, CheckConfig("exact"))
            t_p = _median_time(lambda: cp.check(cables), repeat)
            t_e = _median_time(lambda: ce.check(cables), repeat)
            table.add(axis, len(cables), n_pts, len(parts), 1e3 * t_p, 1e3 * t_e, 1e6 * t_p / n_pts,
                      1e6 * t_e / n_pts)
            xs.append(n_pts if axis == "cables" else len(parts))
            tp.append(t_p)
            te.append(t_e)
        # Growth fitted from the second value up (one cable or ten parts is mostly fixed cost).
        fits[axis] = (_fit_exponent(xs[1:], tp[1:]), _fit_exponent(xs[1:], te[1:]))
    table.notes += [
        f"fitted exponent of time against points (10 to 200 cables, 310 parts): points "
        f"{fits['cables'][0]:.2f}, exact {fits['cables'][1]:.2f} (1 = linear).",
        f"fitted exponent of time against parts (100 to 2,000 parts, 100 cables): points "
        f"{fits['parts'][0]:.2f}, exact {fits['parts'][1]:.2f}; the cable-cable work is a fixed share.",
        "parts: one torus mesh (2,000 triangles) per 31 parts, the rest primitives, in a 2 x 2 x 1 m room.",
    ]
    return table


# -- side by side ----------------------------------------------------------------

def _synthetic_scene(n_cables: int, segments: int, n_parts: int, seed: int = 7):
    """A scene (through the real parser and builder) of routed cables among primitive parts.

    Cables run through random-walk `via` points in a 1 x 1 x 0.5 m room, as
    routed (dynamics off); parts are boxes, cylinders, capsules, spheres and
    ellipsoids at random poses."""
    rng = np.random.default_rng(seed)
    room = np.array([1.0, 1.0, 0.5])
    r = RADIUS
    cables = []
    for c in range(n_cables):
        p = rng.uniform(0.1 * room, 0.9 * room)
        d = rng.normal(size=3)
        pts = [p]
        for _ in range(5):
            d = d / np.linalg.norm(d) + 0.5 * rng.normal(size=3)
            d /= np.linalg.norm(d)
            p = np.clip(p + 0.08 * d, 0.0, room)
            pts.append(p)
        pts = np.array(pts)
        cables.append({"name": f"c{c}", "radius": r,
                       "start": {"body": "world", "pos": pts[0].tolist()},
                       "end": {"body": "world", "pos": pts[-1].tolist()},
                       "via": pts[1:-1].tolist(),
                       # elements at least 2r long, as MuJoCo's flex needs them longer than r
                       "segments": int(min(segments, np.linalg.norm(np.diff(pts, axis=0), axis=1).sum()
                                           // (2 * r)))})
    kinds = ["box", "cylinder", "capsule", "sphere", "ellipsoid"]
    parts = []
    for k in range(n_parts):
        kind = kinds[k % len(kinds)]
        s = rng.uniform(0.01, 0.04, size=3)
        size = {"box": s, "ellipsoid": s, "sphere": s[:1], "cylinder": s[:2], "capsule": s[:2]}[kind]
        parts.append({"name": f"part{k}", "shape": kind, "size": [float(x) for x in size],
                      "pos": rng.uniform(0.0, room).tolist(),
                      "euler": rng.uniform(-180, 180, size=3).tolist()})
    data = {"scene": {"name": f"synthetic{n_cables}x{segments}", "units": "m", "duration": 0.0},
            "effects": {"dynamics": False},
            "parts": parts, "cables": cables}
    return parse_scene(data, Path(f"/virtual/synthetic{n_cables}.toml"))


def _mujoco_side(scene, repeat: int) -> dict:
    """Checker time beside the detection model's mj_kinematics + mj_collision on one state."""
    built = build(scene, detect=True)
    sim = Simulation(built)
    sim.reset()
    sim.settle()
    state = sim.state(0, contacts=False)
    shapes = part_shapes(built)
    parts = [PartState(p.name, sh, pose, p.keepout) for p, sh, pose in zip(built.parts, shapes, state.part_poses)]
    from sim.stepcheck import cable_states  # the run's own CableStates
    cables = cable_states(built, state.cables)
    out = {"n_cables": len(cables), "n_points": sum(len(c.points) for c in cables), "n_parts": len(parts)}
    for method in ("points", "exact"):
        cfg = CheckConfig(method, scene.check.spacing, scene.check.clearance)
        checker = Checker(parts, cfg)
        out[method] = _median_time(lambda: checker.check(cables, state.part_poses), repeat)
    d = sim.data
    m2, d2 = built.detect, sim.detect_data
    d2.qpos[:] = d.qpos
    mujoco.mj_kinematics(m2, d2)
    mujoco.mj_comPos(m2, d2)
    mujoco.mj_flex(m2, d2)
    out["mj_collision"] = _median_time(lambda: mujoco.mj_collision(m2, d2), repeat)
    out["detect"] = _median_time(lambda: sim.detect(d), repeat)
    out["contacts"] = int(d2.ncon)
    return out


def side_by_side_table(quick: bool) -> tuple[Table, dict]:
    """The checker beside python-fcl and MuJoCo's collision on the same queries and models."""
    repeat = 3 if quick else 9
    table = Table("side_by_side", "Side by side: the checker, python-fcl and MuJoCo's mj_collision",
                  ["scene", "method", "points", "parts", "checker_ms", "other", "other_ms", "ratio"])
    found = {}
    cables, parts = make_scene()
    n_pts = sum(len(c.points) for c in cables)
    poses = _poses(parts)
    for method in ("points", "exact"):
        checker = Checker(parts, CheckConfig(method))
        t = _median_time(lambda: checker.check(cables, poses), repeat)
        found[f"checker_{method}"] = t
        try:
            upd, qry, _ = fcl_queries(cables, parts, CheckConfig(method), 3 if quick else 6)
        except ImportError:
            table.add("issue3 100x200/310", method, n_pts, len(parts), 1e3 * t,
                      "python-fcl not installed (pip install 'cablecheck[bench]')", None, None)
            continue
        found[f"fcl_{method}"] = upd + qry
        table.add("issue3 100x200/310", method, n_pts, len(parts), 1e3 * t, "fcl update+query",
                  1e3 * (upd + qry), (upd + qry) / t)
        table.add("issue3 100x200/310", method, n_pts, len(parts), 1e3 * t, "fcl query only",
                  1e3 * qry, qry / t)
    sizes = [(10, 40, 50)] if quick else [(10, 40, 50), (60, 60, 300)]
    scenes = [(f"synthetic {n} cables/{p} parts", _synthetic_scene(n, s, p)) for n, s, p in sizes]
    scenes += [(name, load_scene(REPO / "scenes" / f"{name}.toml")) for name in ("drawer", "arm")]
    for label, scene in scenes:
        res = _mujoco_side(scene, 5 * repeat)
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
        "enabled, margin from the clearance) at the same state; detect adds mj_kinematics, mj_comPos, "
        "mj_flex and reading the contacts, as every validated step does.",
    ]
    return table, found


# -- the discrete-point paper ---------------------------------------------------

def paper_table(quick: bool) -> Table:
    """The discrete-point paper's simple and complex cases in kind."""
    repeat = 3 if quick else 7
    cases = [("simple", 5, 20), ("simple", 50, 100), ("complex", 120, 250), ("complex", 200, 2000)]
    table = Table("paper", "The discrete-point paper (Ju et al., 2016) in kind: our time per check beside the paper's",
                  ["case", "cables", "points", "parts", "cable_cable_s", "cable_structure_s",
                   "full_check_s", "paper_cable_cable_s", "paper_cable_structure_s"])
    for case, n_c, n_p in cases:
        cables, parts = _scene_for(n_c, n_p, seed=3)
        cfg = CheckConfig("points")
        alone = Checker([], cfg)
        full = Checker(parts, cfg)
        t_cc = _median_time(lambda: alone.check(cables), repeat)
        t_full = _median_time(lambda: full.check(cables), repeat)
        table.add(case, len(cables), sum(len(c.points) for c in cables), len(parts), t_cc,
                  max(t_full - t_cc, 0.0), t_full, f"{PAPER_CABLE_CABLE_S[0]}-{PAPER_CABLE_CABLE_S[1]}",
                  f"{PAPER_CABLE_STRUCTURE_S[0]}-{PAPER_CABLE_STRUCTURE_S[1]}")
    table.notes += [
        "method points at 2r, 200 body centres per cable; cable_cable_s: the check without parts "
        "(self and cable-cable); cable_structure_s: the full check minus that; this machine, one core.",
        "paper: 8 cases up to over 100 cables and over 200 parts on a 2016 desktop; its per-case "
        "sizes are not given, so the comparison is by range.",
    ]
    return table


# -- example scenes ---------------------------------------------------------------

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


def example_scenes_table(quick: bool, out: Path) -> tuple[Table, dict]:
    """Per-step cost of the example scenes from a full run with recording on."""
    from sim.run import RunOptions, run_scene

    table = Table("example_scenes", "Per-step cost on the example scenes (recording on)",
                  ["scene", "steps", "mj_step_ms", "sim_ms", "check_ms", "validate_ms",
                   "check_plus_validate_ms", "record_ms", "cost_over_mj_step", "realtime_factor",
                   "realtime_factor_total", "full_checks", "proven_clear"])
    found = {}
    names = ["drawer", "arm"] + sorted(p.stem for p in (REPO / "scenes").glob("*.toml")
                                       if p.stem not in ("drawer", "arm"))
    for name in names:
        scene = load_scene(REPO / "scenes" / f"{name}.toml")
        if quick:
            scene = dataclasses.replace(scene, duration=min(scene.duration, 1.0))
        rep = run_scene(scene, RunOptions(report=out / f"{name}.json", record=out / f"{name}.rrd"))
        t = rep["timing"]
        steps = rep["settings"]["steps"]
        loop = t["sim_s"] + t["check_s"] + t["validate_s"] + t["record_s"] + t.get("wear_s", 0.0)
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
        "stage per step (mj_step, positions and the detection model's mj_collision for validation).",
        "check: cable and part-part checks, strain and bend per step; validate: comparing with MuJoCo's "
        "contacts; record: rerun logging (sampled at 100 frames per simulated second).",
        "realtime_factor: simulated seconds over the step loop's wall time (the wear map's too); _total adds "
        "building and settling.",
        "full_checks / proven_clear: checked steps run in full and steps the skip rule (checker.advance) "
        "proved clear; a cable-structure pair inside the clearance is then checked on its own, but a "
        "self or cable-cable pair inside it (crossing, coil_self) keeps every step a full check.",
    ] + (["--quick: each scene runs its first simulated second only."] if quick else [])
    return table, found


# -- targets and plot ----------------------------------------------------------------

def targets_table(side: dict, examples: dict) -> Table:
    """The performance targets against this run's numbers."""
    table = Table("targets", "Performance targets on this machine", ["target", "measured", "met"])
    tp, te = side["checker_points"], side["checker_exact"]
    table.add("20,000 points x 310 parts, points < 10 ms", f"{tp * 1e3:.2f} ms", tp < 0.010)
    table.add("20,000 points x 310 parts, exact < 30 ms", f"{te * 1e3:.2f} ms", te < 0.030)
    for method in ("points", "exact"):
        if f"fcl_{method}" in side:
            ratio = side[f"fcl_{method}"] / side[f"checker_{method}"]
            table.add(f"checker >= 5x faster than python-fcl ({method})", f"{ratio:.1f}x", ratio >= 5)
        else:
            table.add(f"checker >= 5x faster than python-fcl ({method})", "python-fcl not installed", None)
    d = examples["drawer"]
    table.add("drawer: check + validation per step < mj_step",
              f"{d['cv']:.3f} ms vs {d['mj']:.3f} ms", d["cv"] < d["mj"])
    table.add("drawer faster than real time with recording", f"{d['rtf']:.2f}x real time", d["rtf"] > 1.0)
    return table


def plot(tables: dict[str, Table], path: Path) -> Path:
    """A 2 x 2 PNG: discretisation, physics, scale and side by side."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(11, 8), dpi=72)
    t = tables["discretisation"]
    a = ax[0, 0]
    for k, (label, ms, err, miss) in enumerate(zip(t.column("config"), t.column("ms_large"),
                                                   t.column("worst_error_mm"), t.column("missed"))):
        a.scatter(ms, err, s=40)
        a.annotate(f"{label} ({miss} missed)", (ms, err), fontsize=8,
                   xytext=(6, 10 - 12 * (k % 3)), textcoords="offset points")
    a.set_xscale("log")
    a.set_xlabel("ms per check (10,000 body centres, 310 parts)")
    a.set_ylabel("worst distance error, mm")
    a.set_title("Discretisation vs exact geometry")
    t = tables["physics"]
    a = ax[0, 1]
    for ref, marker in (("catenary", "o"), ("cantilever", "s")):
        for dt in sorted({r[3] for r in t.rows if r[0] == ref}):
            rows = [r for r in t.rows if r[0] == ref and r[3] == dt]
            a.plot([r[5] for r in rows], [abs(r[4]) for r in rows], marker=marker,
                   label=f"{ref}, dt {dt:g} ms")
            for r in rows:
                a.annotate(str(r[1]), (r[5], abs(r[4])), fontsize=7, xytext=(3, 3), textcoords="offset points")
    a.set_xscale("log")
    a.set_yscale("log")
    a.set_xlabel("ms wall per simulated second (labels: elements)")
    a.set_ylabel("|error| %")
    a.set_title("Physics resolution vs analytic references")
    a.legend(fontsize=7)
    t = tables["scale"]
    a = ax[1, 0]
    for axis, col in (("cables", "points"), ("parts", "parts")):
        rows = [r for r in t.rows if r[0] == axis]
        x = [r[t.columns.index(col)] for r in rows]
        a.plot(x, [r[4] for r in rows], "o-", label=f"points, vs {col}")
        a.plot(x, [r[5] for r in rows], "s--", label=f"exact, vs {col}")
    a.set_xscale("log")
    a.set_yscale("log")
    a.set_xlabel("cable points (310 parts) / parts (20,000 points)")
    a.set_ylabel("ms per check")
    a.set_title("Scale")
    a.legend(fontsize=7)
    t = tables["side_by_side"]
    a = ax[1, 1]
    labels, ours, other = [], [], []
    for r in t.rows:
        if r[6] is None or r[5] == "fcl query only" or r[5].startswith("detect"):
            continue
        labels.append(f"{r[0]}\n{r[1]} vs {r[5].split()[0]}")
        ours.append(r[4])
        other.append(r[6])
    y = np.arange(len(labels))
    a.barh(y - 0.2, ours, 0.4, label="checker")
    a.barh(y + 0.2, other, 0.4, label="other (fcl / mj_collision)")
    a.set_yticks(y, labels, fontsize=6)
    a.set_xscale("log")
    a.set_xlabel("ms per check / per collision pass")
    a.set_title("Side by side")
    a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def run_bench(quick: bool = False, out: Path = Path("recordings/bench"),
              echo: Callable[[str], None] = print) -> dict[str, Table]:
    """Measure everything, print each table as it completes, write CSVs and the plot into `out`."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    tables: dict[str, Table] = {}

    def done(table: Table) -> None:
        tables[table.name] = table
        table.write_csv(out)
        echo(table.text())

    echo(f"cablecheck bench{' --quick' if quick else ''}: MuJoCo {mujoco.__version__}, "
         f"numpy {np.__version__}; medians of repeats, one process")
    disc = discretisation_table(quick)
    done(disc)
    done(physics_table(quick))
    scale = scale_table(quick)
    done(scale)
    side, side_found = side_by_side_table(quick)
    done(side)
    done(paper_table(quick))
    ex, ex_found = example_scenes_table(quick, out)
    done(ex)
    done(targets_table(side_found, ex_found))
    png = plot(tables, out / "bench.png")
    echo(f"\nwrote {', '.join(sorted(t + '.csv' for t in tables))} and {png.name} into {out} "
         f"({time.perf_counter() - t0:.1f} s)")
    return tables
