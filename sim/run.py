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

from checker.advance import Advancement, part_pair_bounds
from checker.cable import TAUT_STRAIN, CableMeasures, taut_margin
from checker.events import EventTracker
from checker.interference import Checker
from checker.parts import PartChecker
from checker.records import PairType, Severity
from checker.report import SCHEMA, write_report
from checker.scene_state import CableState, CheckConfig, Exclusion, PartState
from checker.validation import Validation, simulator_pairs
from sim.build import Built, build
from sim.loop import Simulation
from sim.record import Recorder, pair_path
from sim.scene import Scene
from sim.sweep import DEFAULT_PRECISION_M, part_set, part_shapes, selection

_PAIRWISE = (PairType.SELF, PairType.CABLE_CABLE, PairType.CABLE_STRUCTURE, PairType.KEEPOUT)

RECORD_RATE = 100.0
"""Recorded frames per simulated second (checks still run at every checked step)."""


@dataclass(frozen=True)
class RunOptions:
    """How to run a scene.

    Attributes:
      report: report path.
      record: recording path, or None for no recording.
      method, spacing: override the scene's `[check]` values when not None.
      only: check only interference involving the parts of this assembly
        path (a part name or "/"-separated prefix): its parts against the
        other parts, and cables against its parts (cable-structure and
        keep-out). Checks that involve none of its parts (self, cable-cable,
        bend, taut) are skipped. None checks everything.
      advance: skip the pairwise checks and the validation on steps where
        no pair can have come within the clearance since the last full check
        (:mod:`checker.advance`; the same events and pairs as checking every
        step). False checks every step in full.
    """

    report: Path
    record: Path | None
    method: str | None = None
    spacing: float | None = None
    only: str | None = None
    advance: bool = True


ADVANCE_HORIZON_RADII = 2.0
"""Conservative advancement: candidates are evaluated up to the clearance
plus this many (largest) cable radii at a full check..."""

ADVANCE_STRETCH_RADII = 0.25
"""... and up to this many (smallest) cable radii of arc length inside the
exclusion windows (the total change of element lengths a skipped step allows)."""


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


def part_pairs_skipped(built: Built) -> np.ndarray:
    """(P, P) bool: part pairs the part-part check leaves out, as MuJoCo does.

    - parts of a child body and of its parent body (other than the world
      body itself) when a joint joins them: arm links overlap at their joints
      by design;
    - two geoms of the base mjcf model in the same rigid (weld) group: the
      model author's layout, never colliding in MuJoCo either.
    Scene `[[parts]]` on one body are checked against each other (once, at
    t = 0)."""
    m = built.model
    scene_names = {p.name for p in built.scene.parts}
    body = np.array([int(m.geom_bodyid[p.geom_id]) for p in built.parts], np.int64)
    weld = m.body_weldid[body]
    parent = m.body_parentid[body]
    base = np.array([p.name not in scene_names for p in built.parts], bool)
    jointed = (m.body_weldid[np.arange(m.nbody)] == np.arange(m.nbody))   # top of a weld group
    child_of = (parent[:, None] == body[None, :]) & (parent[:, None] != 0) & jointed[body][:, None]
    skip = child_of | child_of.T
    skip |= (weld[:, None] == weld[None, :]) & base[:, None] & base[None, :]
    np.fill_diagonal(skip, True)
    return skip


def attachment_exclusions(built: Built) -> list[Exclusion]:
    """Arc-length windows where a cable touching a part is expected.

    Around every held vertex (start, end, clip), `check.attach_zone` cable
    radii either side, widened to whole elements (so that MuJoCo's contacts,
    one per element, can be filtered by the same window), against every part
    riding the same body."""
    zone = built.scene.check.attach_zone
    parts_on: dict[str, list[str]] = {}
    for p in built.parts:
        parts_on.setdefault(p.body, []).append(p.name)
    out = []
    for c in built.cables:
        for att in c.attachments:
            for part in parts_on.get(att.body, ()):
                lo = c.rest_s[np.searchsorted(c.rest_s, att.s - zone * c.radius, side="right") - 1] \
                    if att.s - zone * c.radius > 0 else 0.0
                hi = c.rest_s[min(np.searchsorted(c.rest_s, att.s + zone * c.radius), c.count - 1)]
                out.append(Exclusion(c.name, part, float(lo), float(hi)))
    return sorted(set(out), key=lambda e: (e.cable, e.part, e.s_min))


def _cable_states(built: Built, points: list[np.ndarray]) -> list[CableState]:
    return [CableState(c.name, p, c.radius, c.min_bend_radius, c.length)
            for c, p in zip(built.cables, points)]


def _worst_by_cable(records, names: list[str]) -> list[str]:
    """"hard", "soft" or "clear" per cable from the step's records."""
    rank = {"clear": 0, "soft": 1, "hard": 2}
    state = dict.fromkeys(names, "clear")
    for r in records:
        sev = Severity(r.severity).value
        for name in {r.a, r.b}:
            if name in state and rank[sev] > rank[state[name]]:
                state[name] = sev
    return [state[n] for n in names]


def run_scene(scene: Scene, options: RunOptions, progress: Progress | None = None) -> dict:
    """Run `scene`; write the report (and recording); return the report dict."""
    start = time.perf_counter()
    validate = scene.check.validate
    built = build(scene, detect=validate)
    sim = Simulation(built)
    sim.reset()
    if progress:
        progress("settle", 0, max(sim.settle_steps, 1))
    sim.settle(None if progress is None else
               (lambda k: progress("settle", k, sim.settle_steps) if k % 50 == 0 else None))
    recorder = Recorder(built, options.record) if options.record else None
    timer = _Timer()
    config = CheckConfig(method=options.method or scene.check.method,
                         spacing=options.spacing or scene.check.spacing,
                         clearance=scene.check.clearance)
    shapes = part_shapes(built)
    # Rigid parts against each other: prepared once, same-body pairs checked once.
    rigid = part_set(built, tolerance=DEFAULT_PRECISION_M, shapes=shapes)
    focus = selection(rigid, options.only, "--only") if options.only is not None else None
    skipped_pairs = part_pairs_skipped(built)
    part_checker = PartChecker(rigid, scene.check.clearance, focus, skipped_pairs)
    exclusions = attachment_exclusions(built)
    # Parts prepared once; each step passes their poses (identity until then).
    # With --only, cables are checked against that assembly's parts alone.
    checked_parts = np.ones(len(built.parts), bool) if focus is None else np.asarray(focus, bool)
    offsets = np.concatenate([[0], np.cumsum([c.count for c in built.cables])])  # cable starts in pts
    radii = np.array([c.radius for c in built.cables], float)
    horizon = ADVANCE_HORIZON_RADII * float(radii.max()) if (options.advance and len(radii)) else 0.0
    stretch = ADVANCE_STRETCH_RADII * float(radii.min()) if len(radii) else 0.0
    checker = Checker([PartState(p.name, sh, np.eye(4), p.keepout)
                       for p, sh, keep in zip(built.parts, shapes, checked_parts) if keep], config,
                      horizon=horizon, stretch=stretch)
    advance = None
    if checker.bounds_gaps:
        corner = np.maximum(np.abs(rigid.lo), np.abs(rigid.hi))
        rho = np.sqrt(np.einsum("ij,ij->i", corner, corner))     # inf for planes
        rho[checked_parts] = np.maximum(rho[checked_parts], checker.part_radius())
        box_lo = np.full((len(built.parts), 3), -np.inf)
        box_hi = np.full((len(built.parts), 3), np.inf)
        box_lo[checked_parts], box_hi[checked_parts] = checker.part_bounds()
        advance = Advancement(offsets, config.spacing * radii, rho, config.clearance, stretch, radii,
                              (box_lo, box_hi))
        # part pairs that can move relative to each other (PartChecker's moving pairs)
        gname = {g: k for k, g in enumerate(dict.fromkeys(rigid.groups))}
        grp = np.array([gname[g] for g in rigid.groups], np.int64)
        pi, pj = np.triu_indices(len(grp), 1)
        keep = (grp[pi] != grp[pj]) & ~skipped_pairs[pi, pj]
        moving_pairs = (pi[keep], pj[keep])
        part_index = {name: k for k, name in enumerate(rigid.names)}
        gap_part = np.full(len(built.parts), np.inf)
        checked_index = np.nonzero(checked_parts)[0]
    static_parts = False  # same-body part records exist (replayed every step)
    horizon_next = True
    focus_names = None if focus is None else {p.name for p, keep in zip(built.parts, checked_parts) if keep}
    names = [c.name for c in built.cables]
    every = scene.check.every
    tracker = EventTracker(hold=3 * every * scene.timestep)
    validation = Validation(scene.check.clearance, config.method,
                            frozenset(p.name for p in built.parts if p.shape == "mesh"),
                            unit=scene.scale, unit_name=scene.units)
    n = len(built.cables)
    measures = CableMeasures(offsets)
    rest_length = np.array([c.length for c in built.cables], float)
    min_bend_radius = np.array([np.inf if c.min_bend_radius is None else c.min_bend_radius
                                for c in built.cables], float)
    has_bend_limit = np.isfinite(min_bend_radius)
    max_strain = np.full(n, -np.inf)
    min_bend = np.full(n, np.inf)
    rest_points: list[np.ndarray] = []
    final_points: list[np.ndarray] = []
    steps = checked = 0
    t_last = 0.0
    complete = False
    markers: set[str] = set()
    # The recording samples the checked steps at about RECORD_RATE (and at
    # every step where an event starts or ends): a viewer needs no 500 Hz.
    record_stride = max(1, int(round(1.0 / (RECORD_RATE * every * scene.timestep))))
    try:
        for state in sim.steps(contacts=False, every=every):
            timer.lap("sim")
            if state.step == 0:
                rest_points = state.cables
                if recorder:
                    recorder.log_static(state.part_poses)
            poses = state.part_poses
            pts = np.concatenate(state.cables) if state.cables else np.zeros((0, 3))
            skip = advance is not None and advance.proven_clear(pts, poses)
            lengths, bend = measures(pts, advance.seg if skip else None)
            strain = lengths / rest_length - 1.0
            if skip:
                # no pair can be within the clearance: what a full check
                # returns is the single-cable records (none unless a bend is
                # within the clearance of its limit or a cable is taut) and
                # replayed same-body ones
                single = bool(np.any((bend - min_bend_radius < config.clearance) & has_bend_limit)
                              or np.any(taut_margin(lengths, rest_length) < 0.0))
                cable_records = checker.check_single(_cable_states(built, state.cables)) if single else []
                part_records = part_checker.check(poses) if static_parts else []
            else:
                cables = _cable_states(built, state.cables)
                # The horizon costs candidates: only worth it when the last
                # full check found no pair below the clearance (else no skip).
                cable_records = checker.check(cables, poses[checked_parts], exclusions,
                                              None if horizon_next else 0.0)
                # moving part pairs still provably apart: only same-body records
                if advance is not None and state.step > 0 and advance.part_pairs_clear(poses):
                    part_records = part_checker.check(poses) if static_parts else []
                else:
                    part_records = part_checker.check(poses)
                if advance is not None:
                    horizon_next = not any(r.type in _PAIRWISE for r in cable_records)
                    if state.step == 0:
                        static_parts = any(grp[part_index[r.a]] == grp[part_index[r.b]] for r in part_records)
                    if checker.gaps is not None:
                        gap_cable, gap_checked = checker.gaps
                        gap_part[checked_parts] = gap_checked
                        bound = part_pair_bounds(rigid, rigid.place(poses), *moving_pairs)
                        cab, s_c, part, value = checker.part_candidates
                        advance.start(pts, poses, gap_cable, gap_part, moving_pairs, bound,
                                      (cab, s_c, checked_index[part], value), horizon,
                                      checker.cable_candidates)
                    else:
                        advance.stop()
            if focus_names is not None:
                cable_records = [r for r in cable_records if r.b in focus_names
                                 and PairType(r.type) in (PairType.CABLE_STRUCTURE, PairType.KEEPOUT)]
            records = cable_records + part_records
            max_strain = np.maximum(max_strain, strain)
            min_bend = np.minimum(min_bend, bend)
            started, closed = tracker.update(state.t, records)
            timer.lap("check")
            agreement = None
            contacts = None
            if validate and not skip:
                # MuJoCo's detection (timed with the simulation, as before)
                contacts = sim.detect(sim.data)
                timer.lap("sim")
                seen = simulator_pairs(contacts, {c.name: (c.points, c.radius) for c in cables},
                                       exclusions, config.clearance)
                if focus_names is not None:
                    seen = {k: v for k, v in seen.items() if k[2] in focus_names
                            and k[0] in (PairType.CABLE_STRUCTURE.value, PairType.KEEPOUT.value)}
                agreement = validation.compare(state.t, cable_records, seen)
                timer.lap("validate")
            if recorder and (checked % record_stride == 0 or started or closed
                             or state.step == sim.total_steps):
                _record_step(recorder, state, contacts, records, names, strain, bend, agreement,
                             started, closed, tracker, markers, scene.scale)
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
        still_open = set(tracker.open_pairs())
        events = tracker.finish()
        if recorder:
            for ev in events:  # events running at the end get their entry too
                if (ev.type, ev.a, ev.b) in still_open:
                    recorder.log_event(ev.t_end, f"{ev.type} {ev.a} / {ev.b} still present at the end: "
                                       f"{ev.severity}, worst {ev.min_distance / scene.scale:.4g} at "
                                       f"t = {ev.t_worst:.3f} s", "INFO")
            recorder.close()
            timer.lap("record")
    total = time.perf_counter() - start
    report = _report(scene, built, config, complete, steps, checked, t_last, max_strain, min_bend,
                     rest_points, final_points, timer, total, sim, events, tracker, validation, options)
    report["settings"]["advance"] = None if advance is None else {
        "horizon": horizon / scene.scale, "stretch": stretch / scene.scale,
        "full_checks": advance.full, "proven_clear_steps": advance.skipped}
    report["part_warnings"] = list(rigid.warnings)
    write_report(report, options.report)
    return report


def _record_step(recorder: Recorder, state, contacts, records, names, strain, bend, agreement,
                 started, closed, tracker: EventTracker, markers: set[str], unit: float) -> None:
    recorder.log_step(state.t, state.cables, state.part_poses, _worst_by_cable(records, names),
                      strain=strain, bend=bend)
    now = {}
    for r in records:
        path = pair_path(PairType(r.type).value, r.a, r.b)
        now[path] = (r.where, Severity(r.severity).value)
        recorder.log_scalar(f"checks/{path}/distance", r.min_distance / unit,
                            label=f"{PairType(r.type).value}: {r.a} / {r.b}")
    recorder.log_markers(now)
    recorder.clear_markers(markers - set(now))
    markers.clear()
    markers.update(now)
    if contacts is not None:
        recorder.log_contacts(contacts.pos)
    if agreement is not None:
        recorder.log_scalar("validation/agreement", agreement)
    for key in started:
        worst = tracker.pairs[key]
        recorder.log_event(state.t, f"{key[0]} {key[1]} / {key[2]} starts (distance "
                           f"{worst.min_distance / unit:.4g})", "WARN")
    for ev in closed:
        recorder.log_event(ev.t_end, f"{ev.type} {ev.a} / {ev.b} ends: {ev.severity}, worst "
                           f"{ev.min_distance / unit:.4g} at t = {ev.t_worst:.3f} s", "INFO")


def _report(scene: Scene, built: Built, config: CheckConfig, complete: bool, steps: int,
            checked: int, t_last: float, max_strain, min_bend, rest_points, final_points,
            timer: _Timer, total: float, sim: Simulation, events, tracker: EventTracker,
            validation: Validation, options: RunOptions) -> dict:
    u = scene.scale
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
    event_rows = [{
        "type": e.type, "a": e.a, "b": e.b, "severity": e.severity, "phase": e.phase,
        "t_start": e.t_start, "t_end": e.t_end, "t_worst": e.t_worst,
        "min_distance": e.min_distance / u, "where": np.asarray(e.where) / u, "s": e.s / u,
    } for e in events]
    pair_rows = [{"type": p.type, "a": p.a, "b": p.b, "min_distance": p.min_distance / u, "t": p.t}
                 for p in sorted(tracker.pairs.values(), key=lambda p: (p.min_distance, p.type, p.a, p.b))]
    summary = {
        "hard": sum(e.severity == "hard" for e in events),
        "soft": sum(e.severity == "soft" for e in events),
        "static": sum(e.phase == "static" for e in events),
        "dynamic": sum(e.phase == "dynamic" for e in events),
    }
    report = {
        "schema": SCHEMA,
        "scene": scene.name,
        "units": scene.units,
        "complete": complete,
        "mujoco": mujoco.__version__,
        "settings": {
            "method": config.method,
            # discrete-point spacing in scene units for the thinnest cable
            "spacing": (config.spacing * min(radii) / u) if radii else None,
            "spacing_radii": config.spacing,
            "clearance": scene.check.clearance / u,
            "attach_zone_radii": scene.check.attach_zone,
            "event_hold_s": tracker.hold,
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
        "summary": summary,
        "events": event_rows,
        "pairs": pair_rows,
    }
    if scene.check.validate:
        v = validation
        report["validation"] = {
            "compared_steps": v.compared_steps, "pair_steps": v.pair_steps, "agree": v.agree,
            "checker_only": v.checker_only, "mujoco_only": v.mujoco_only,
            "severity_differs": v.severity_differs, "agreement": v.agreement,
            "max_distance_error": v.max_distance_error / u,
            "reasons": dict(v.reasons),
            "disagreements": [{"t": d.t, "type": d.type, "a": d.a, "b": d.b,
                               "checker": None if d.checker is None else d.checker / u,
                               "mujoco": None if d.mujoco is None else d.mujoco / u,
                               "reason": d.reason} for d in v.disagreements],
        }
    report.update({
        "cables": cables,
        "warnings": sim.warnings(),
        "timing": {
            "total_s": total,
            "sim_s": timer.total["sim"],
            "check_s": timer.total["check"],
            "validate_s": timer.total["validate"],
            "record_s": timer.total["record"],
            "check_ms_per_step": 1e3 * timer.total["check"] / check_steps,
            "validate_ms_per_step": 1e3 * timer.total["validate"] / check_steps,
            "record_ms_per_step": 1e3 * timer.total["record"] / check_steps,
            "sim_ms_per_step": 1e3 * timer.total["sim"] / max(steps, 1),
        },
        "recording": str(options.record) if options.record else None,
    })
    return report
