"""The JSON report of a run: its outcome record, the report dict, an atomic write.

A run hands on everything its report says as one frozen record,
:class:`RunOutcome` (in metres, seconds and radians, as measured), and
:func:`report_of` turns that record into the report dict (schema
``cablecheck.report/1``, lengths in scene units, the SPEC's keys in their
order): the same record always gives the same dict. :func:`write_report`
writes a report dict (the run's, or the sweep's and the study's) as JSON to
a temporary file in the target folder, flushes and fsyncs it, then renames
it over the target, so a reader never sees a half-written report and an
earlier report is replaced only by a complete one. Numbers become plain
floats rounded to 1e-12, and non-finite values become null: JSON has no NaN.

A run that diverged carries its `physics_error` (`cablecheck.run.divergence.PhysicsError`:
when, the cable or body, the likely cause) and one that failed its `error`
(:class:`RunError`: type, message, traceback); both are marked incomplete.
:func:`failed_report` is the report of a run that failed before it had
anything to report but the error.

This module does not run, measure or decide anything: what is hard, taut or
bent too far is in the record already. It does not import MuJoCo.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from cablecheck.about import mujoco_version, version
from cablecheck.checker.events import Phase
from cablecheck.checker.interference.margins import per_cable
from cablecheck.checker.records import PairType, Severity
from cablecheck.report.baseline import resolved_rows

if TYPE_CHECKING:
    from cablecheck.checker.events import AllowedWorst, Event, PairWorst
    from cablecheck.checker.interference.excused import ExcusedWorst
    from cablecheck.checker.interference.margins import Closest
    from cablecheck.checker.scene_state import CheckConfig
    from cablecheck.checker.validation import ValidationSummary
    from cablecheck.checker.wear import CableWear
    from cablecheck.report.baseline import Comparison
    from cablecheck.report.evidence import HtmlEvidence
    from cablecheck.report.review import ReviewMatch
    from cablecheck.run.divergence import PhysicsError
    from cablecheck.scene.records import Scene

SCHEMA = "cablecheck.report/1"

STAGES = ("sim", "check", "validate", "record", "wear")
"""The timed stages of a run, in the report's order."""


@dataclass(frozen=True)
class TwistProfile:
    """The simulated rod's twist along one cable over the run (metres).

    Attributes:
      s: (V,) arc length of each interior vertex along the cable's rest shape.
      max_moment: (V,) the largest torsional moment there, N m.
      max_rate: (V,) the largest twist per length there, radians per metre.
    """

    s: np.ndarray
    max_moment: np.ndarray
    max_rate: np.ndarray


@dataclass(frozen=True)
class CableOutcome:
    """One cable over the run (metres; None where no step was checked).

    Attributes:
      name: the cable.
      length: rest length.
      radius: the cable's radius.
      segments: elements, a clamp's short held edge included.
      max_strain: the largest absolute strain, signed (compression negative).
      taut: stretched past `cablecheck.checker.cable.TAUT_STRAIN` at some checked step.
      min_bend_radius: the least bend radius.
      bend_violation: the bend radius went below the cable's limit.
      rest_points, final_points: (n, 3) body centres at the first and last
        checked step, or None.
      wear: the cable's wear map.
      max_twist: largest absolute twist end to end, radians: with dynamics
        the simulated rod's (every cable), without it the one its clamped
        ends' frames wind in (None unless clamped at both ends).
      max_twist_moment: N m: with dynamics the largest torsional moment
        anywhere along the rod; without, G J max_twist / L; or None.
      twist: with dynamics, the twist along the cable (`TwistProfile`), else None.
    """

    name: str
    length: float
    radius: float
    segments: int
    max_strain: float | None
    taut: bool
    min_bend_radius: float | None
    bend_violation: bool
    rest_points: np.ndarray | None
    final_points: np.ndarray | None
    wear: CableWear
    max_twist: float | None
    max_twist_moment: float | None
    twist: TwistProfile | None = None


@dataclass(frozen=True)
class AdvanceOutcome:
    """How the skip rule (`cablecheck.checker.advance`) spared full checks.

    Attributes:
      horizon, stretch: the rule's distances, metres.
      full_checks: steps checked in full.
      proven_clear_steps: steps proven clear without a full check.
    """

    horizon: float
    stretch: float
    full_checks: int
    proven_clear_steps: int


@dataclass(frozen=True)
class Timing:
    """Seconds: `total` the whole run's wall-clock time; each of `STAGES` the
    CPU time of the thread that ran it (the simulation may step ahead in a
    process of its own, `cablecheck.run.apart`, or on a thread,
    `cablecheck.run.ahead`: stages overlap, and waiting for the other side is
    no stage's time); `collision`: MuJoCo's own collision
    passes on the detection model (their CPU time), a part of the validate stage
    (what validation costs at least), or None when the run does not
    validate; `loop`: the wall-clock time of the step loop (checking,
    validating, the wear map and the recording to its close, and the
    simulating they wait for: the run without building; the simulation
    may have settled and stepped ahead on its own while the run was still
    building), or None where not measured."""

    total: float
    stages: dict[str, float]
    collision: float | None = None
    loop: float | None = None
    divergence: float | None = None
    """CPU seconds of the divergence scan (`cablecheck.run.divergence`), a part of the
    check stage, or None where the simulation does not step."""


@dataclass(frozen=True)
class RunError:
    """An error that ended a run.

    Attributes:
      type: the exception's class name.
      message: its message.
      traceback: the traceback, as Python prints it.
      t: the time of the last checked step when it was raised, or None
        (raised before any step was checked).
    """

    type: str
    message: str
    traceback: str
    t: float | None


@dataclass(frozen=True)
class RunOutcome:
    """Everything one run's report says, as the run found it.

    Attributes:
      scene: the scene run (name, units, settings, effects).
      config: the check settings used (method, spacing in radii, clearance).
      scene_file, version: the scene file's path and the product version.
      mujoco: MuJoCo's version.
      complete: the run reached its end; `interrupted` names the signal
        that stopped it, or None.
      steps, checked, t_end: the last step simulated, the steps checked and
        the time of the last checked step.
      cables: per cable, in scene order.
      events: the events by start time; `event_joints`: per event, the
        joint fields (`cablecheck.run.jointspace.JointLog.event_fields`) where the
        scene moves joints of an mjcf model, else None; `joint_units` then
        maps each moving joint to its unit.
      pairs, allowed: every pair that came below the clearance / allowed
        pair, with its worst moment (an allowed part-part pair's over the
        states it was measured at, every `allowed_interval` simulated seconds).
      excused: every attachment window whose piece of cable came below the
        clearance of a part it excuses, with its worst moment.
      closest: every pair's closest approach within `margin_reach`
        (`cablecheck.checker.interference.margins`: sampled every `margin_interval`
        simulated seconds and refined around each pair's best sample; a pair
        that came below the clearance as its worst event has it).
      review: with `--review`, the reviewer's notes against the events
        (`cablecheck.report.review`): each event's note and the notes that cover none.
      baseline: with `--baseline`, this run's events against an earlier
        run's (`cablecheck.report.baseline`): each event's status and the resolved ones.
      event_hold: seconds a pair must stay clear before its event closes.
      validation: the comparison with MuJoCo's contacts, or None when the
        scene does not validate.
      advance: the skip rule's counts, or None when every step was checked
        in full.
      warnings: MuJoCo's warnings by name and count.
      part_warnings, physics_warnings: what the part checks and the model
        builder warned about.
      substeps: simulation substeps per timestep.
      timing: the run's wall-clock seconds and its stages' CPU seconds.
      recording: the recording's path, or None.
      physics_error: where and why the simulation diverged, or None.
      error: the error that ended the run, or None.
    """

    scene: Scene
    config: CheckConfig
    scene_file: str
    version: str
    mujoco: str
    complete: bool
    interrupted: str | None
    steps: int
    checked: int
    t_end: float
    cables: tuple[CableOutcome, ...]
    events: tuple[Event, ...]
    event_joints: tuple[dict, ...] | None
    joint_units: dict[str, str] | None
    pairs: tuple[PairWorst, ...]
    allowed: tuple[AllowedWorst, ...]
    excused: tuple[ExcusedWorst, ...]
    event_hold: float
    validation: ValidationSummary | None
    advance: AdvanceOutcome | None
    warnings: dict[str, int]
    part_warnings: tuple[str, ...]
    physics_warnings: tuple[str, ...]
    substeps: int
    timing: Timing
    recording: Path | None
    physics_error: PhysicsError | None = None
    error: RunError | None = None
    baseline: Comparison | None = None
    closest: tuple[Closest, ...] = ()
    margin_reach: float = 0.0
    margin_interval: float = 0.0
    allowed_interval: float = 0.0
    review: ReviewMatch | None = None
    html: HtmlEvidence | None = None
    """With `--html`: per event its worst state and distance history, and the
    pictures (`cablecheck.report.evidence`); None otherwise."""


def _worst_first(rows):
    return sorted(rows, key=lambda p: (p.min_distance, p.type, p.a, p.b))


def _scaled(x, u: float):
    return None if x is None else x / u


def _wear_row(w: CableWear, u: float) -> dict:
    worn = w.most_worn()
    return {
        "s": w.s / u, "contact_time": w.contact_time, "sliding": w.sliding / u, "bend_cycles": w.bend_cycles,
        "most_worn": None if worn is None else {
            "s": w.s[worn] / u, "touches": w.touches[worn], "contact_time": w.contact_time[worn],
            "sliding": w.sliding[worn] / u},
    }


def _cable_row(c: CableOutcome, u: float) -> dict:
    return {
        "name": c.name,
        "length": c.length / u,
        "segments": c.segments,
        "max_strain": c.max_strain,
        "taut": c.taut,
        "min_bend_radius": _scaled(c.min_bend_radius, u),
        "bend_violation": c.bend_violation,
        "rest_points": [] if c.rest_points is None else np.asarray(c.rest_points) / u,
        "final_points": [] if c.final_points is None else np.asarray(c.final_points) / u,
        "wear": _wear_row(c.wear, u),
        "max_twist": None if c.max_twist is None else float(np.degrees(c.max_twist)),
        "max_twist_moment": c.max_twist_moment,
        "twist_from": None if c.max_twist is None else "ends" if c.twist is None else "rod",
        "twist": None if c.twist is None else {
            "s": c.twist.s / u, "max_moment": c.twist.max_moment,
            "max_rate": np.degrees(c.twist.max_rate) * u},
    }


def _closest(o: RunOutcome, u: float) -> dict:
    """Closest approaches: how far and how often they were measured, every
    pair within reach (nearest first) and each cable's nearest (None: nothing
    within reach)."""
    cables = per_cable(o.closest, [c.name for c in o.cables])
    return {
        "reach": o.margin_reach / u,
        "sampled_every_s": o.margin_interval,
        "pairs": [{"type": c.type, "a": c.a, "b": c.b, "min_distance": c.min_distance / u, "t": c.t,
                   "where": np.asarray(c.where) / u, "s": c.s / u, "s_b": _scaled(c.s_b, u)}
                  for c in o.closest],
        "cables": [{"cable": c.name, "other": None, "type": None, "min_distance": None, "t": None, "s": None}
                   if x is None else
                   {"cable": x.cable, "other": x.other, "type": x.type, "min_distance": x.min_distance / u,
                    "t": x.t, "s": x.s / u}
                   for c, x in zip(o.cables, cables)],
    }


def _validation(v: ValidationSummary, u: float) -> dict:
    return {
        "compared_steps": v.compared_steps, "pair_steps": v.pair_steps, "agree": v.agree,
        "checker_only": v.checker_only, "mujoco_only": v.mujoco_only,
        "severity_differs": v.severity_differs, "agreement": v.agreement,
        "max_distance_error": v.max_distance_error / u,
        "unexplained": v.unexplained, "allowed_pair_steps": v.allowed_pair_steps,
        "reasons": dict(v.reasons),
        "disagreements": [{"type": d.type, "a": d.a, "b": d.b, "t": d.t_worst, "t_start": d.t_start,
                           "t_end": d.t_end, "t_worst": d.t_worst, "steps": d.steps,
                           "checker": _scaled(d.checker, u), "mujoco": _scaled(d.mujoco, u),
                           "reason": d.reason, "second": _scaled(d.second, u)}
                          for d in v.disagreements],
    }


def _timing(t: Timing, steps: int, checked: int) -> dict:
    per_check = max(checked, 1)
    out = {"total_s": t.total}
    if t.loop is not None:
        out["loop_s"] = t.loop
    out.update({f"{k}_s": t.stages[k] for k in STAGES})
    out.update({f"{k}_ms_per_step": 1e3 * t.stages[k] / per_check for k in ("check", "validate", "record", "wear")})
    out["sim_ms_per_step"] = 1e3 * t.stages["sim"] / max(steps, 1)
    if t.collision is not None:
        out["validate_collision_s"] = t.collision
        out["validate_collision_ms_per_step"] = 1e3 * t.collision / per_check
    if t.divergence is not None:
        out["divergence_s"] = t.divergence
        out["divergence_ms_per_step"] = 1e3 * t.divergence / per_check
    return out


_SCALED_SIGNS = ("runaway-far", "runaway-speed")
"""Signs of a divergence whose value is a length (or a length per second)."""


def _physics_error(e: PhysicsError, u: float) -> dict:
    """The report's `physics_error` (`value`: a distance or a speed in scene
    units, or a stretch ratio)."""
    return {"t": e.t, "step": e.step, "settling": e.settling, "sign": e.sign, "cable": e.cable,
            "vertex": e.vertex, "body": e.body, "warning": e.warning,
            "value": None if e.value is None else e.value / u if e.sign in _SCALED_SIGNS else e.value,
            "cause": e.cause, "detail": e.detail,
            "message": e.message()}


def _error(e: RunError) -> dict:
    return {"type": e.type, "message": e.message, "t": e.t, "traceback": e.traceback}


def failed_report(scene: Scene, error: RunError, warnings: dict[str, int], total: float,
                  recording: Path | None) -> dict:
    """The report of a run that failed before any step was checked: the
    scene, `"complete": false`, the error and MuJoCo's warnings, every
    list empty (the recording, if named, may not exist)."""
    return {
        "schema": SCHEMA, "scene": scene.name, "units": scene.units, "complete": False,
        "mujoco": mujoco_version(),
        "settings": {"units": scene.units, "clearance": scene.check.clearance / scene.scale,
                     "timestep": scene.timestep, "duration": scene.duration, "steps": 0, "checked_steps": 0,
                     "scene_file": str(scene.path), "version": version()},
        "summary": {"hard": 0, "soft": 0, "static": 0, "dynamic": 0, "excused": 0},
        "events": [], "pairs": [], "allowed": [], "excused": [], "cables": [],
        "warnings": dict(warnings), "timing": {"total_s": total},
        "recording": str(recording) if recording else None,
        "interrupted": None, "physics_error": None, "error": _error(error),
    }



def report_of(o: RunOutcome) -> dict:
    """The report dict of a run's outcome (lengths in scene units; numpy
    values and enums as they are: :func:`write_report` makes them plain)."""
    scene = o.scene
    u = scene.scale
    radii = [c.radius for c in o.cables]
    events = []
    for k, e in enumerate(o.events):
        row = {"type": e.type, "a": e.a, "b": e.b, "severity": e.severity, "phase": e.phase,
               "t_start": e.t_start, "t_end": e.t_end, "t_worst": e.t_worst,
               "min_distance": e.min_distance / u, "where": np.asarray(e.where) / u, "s": e.s / u}
        if o.event_joints is not None:
            row.update(o.event_joints[k])
        if o.baseline is not None:
            row["status"] = o.baseline.status[k].value
        if o.review is not None:
            note = o.review.per_event[k]
            row["review"] = None if note is None else {"status": note.status.value, "comment": note.comment}
        events.append(row)
    report = {
        "schema": SCHEMA,
        "scene": scene.name,
        "units": scene.units,
        "complete": o.complete,
        "mujoco": o.mujoco,
        "settings": {
            "method": o.config.method,
            # discrete-point spacing in scene units for the thinnest cable
            "spacing": (o.config.spacing * min(radii) / u) if radii else None,
            "spacing_radii": o.config.spacing,
            "clearance": scene.check.clearance / u,
            "attach_zone_radii": scene.check.attach_zone,
            "event_hold_s": o.event_hold,
            "timestep": scene.timestep,
            "settle": scene.settle,
            "duration": scene.duration,
            "dynamics": scene.effects.dynamics,
            "gravity": scene.effects.gravity,
            "contact": sorted(scene.effects.contact),
            "steps": o.steps,
            "checked_steps": o.checked,
            "t_end": o.t_end,
            "units": scene.units,
            "scene_file": o.scene_file,
            "version": o.version,
            "advance": None if o.advance is None else {
                "horizon": o.advance.horizon / u, "stretch": o.advance.stretch / u,
                "full_checks": o.advance.full_checks, "proven_clear_steps": o.advance.proven_clear_steps},
            "substeps": o.substeps,
        },
        "summary": {
            "hard": sum(e.severity is Severity.HARD for e in o.events),
            "soft": sum(e.severity is Severity.SOFT for e in o.events),
            "static": sum(e.phase is Phase.STATIC for e in o.events),
            "dynamic": sum(e.phase is Phase.DYNAMIC for e in o.events),
            "excused": len(o.excused),
        },
        "events": events,
        "pairs": [{"type": p.type, "a": p.a, "b": p.b, "min_distance": p.min_distance / u, "t": p.t}
                  for p in _worst_first(o.pairs)],
        "allowed": [{"type": p.type, "a": p.a, "b": p.b, "min_distance": p.min_distance / u, "t": p.t,
                     "reason": p.reason,
                     # a part-part pair is measured every allowed_interval alone (cablecheck.run.stepcheck)
                     "sampled_every_s": o.allowed_interval if p.type == PairType.PART_PART else None}
                    for p in _worst_first(o.allowed)],
        "excused": [{"type": x.type, "a": x.a, "b": x.b, "window": x.window, "min_distance": x.min_distance / u,
                     "t_worst": x.t, "where": np.asarray(x.where) / u, "s": x.s / u}
                    for x in _worst_first(o.excused)],
    }
    report["closest"] = _closest(o, u)
    if o.review is not None:          # the reviewer's notes (--review): those about no clash too
        report["review"] = {"file": str(o.review.path), "notes": len(o.review.notes),
                            "on_events": sum(n is not None for n in o.review.per_event),
                            "unmatched": [{"a": n.a, "b": n.b, "status": n.status.value, "comment": n.comment,
                                           "index": n.index} for n in o.review.unmatched]}
    if o.baseline is not None:        # the clashes against an earlier run (--baseline)
        report["baseline"] = {"report": str(o.baseline.path), **o.baseline.counts(),
                              "resolved_events": resolved_rows(o.baseline, u)}
    if o.html is not None:            # the HTML report's pictures (--html): how they were made, what is missing
        report["html"] = {"renderer": o.html.pictures.renderer,
                          "pictures": sum(p is not None for p in o.html.pictures.png),
                          "warnings": list(o.html.pictures.warnings)}
    if o.validation is not None:
        report["validation"] = _validation(o.validation, u)
    report.update({
        "cables": [_cable_row(c, u) for c in o.cables],
        "warnings": dict(o.warnings),
        "timing": _timing(o.timing, o.steps, o.checked),
        "recording": str(o.recording) if o.recording else None,
    })
    if o.joint_units is not None:
        report["joint_units"] = dict(o.joint_units)
    report.update({
        "part_warnings": list(o.part_warnings),
        "interrupted": o.interrupted,
        "physics_warnings": list(o.physics_warnings),
        "physics_error": None if o.physics_error is None else _physics_error(o.physics_error, u),
        "error": None if o.error is None else _error(o.error),
    })
    return report


def plain(value: Any) -> Any:
    """`value` with numpy scalars/arrays, tuples, paths and enums made JSON-ready."""
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, np.ndarray):
        if value.dtype.kind == "f":           # most of a report: rounded without a call per number
            return _rounded(value.tolist(), value.ndim)
        return plain(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        f = float(value)
        return round(f, 12) if math.isfinite(f) else None
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "value") and isinstance(getattr(value, "value"), str):  # str enums
        return value.value
    return value


def _rounded(values: Any, ndim: int) -> Any:
    """Nested lists of floats (`ndim` deep) as `plain` makes each float."""
    if ndim > 1:
        return [_rounded(v, ndim - 1) for v in values]
    if ndim == 0:
        return round(values, 12) if math.isfinite(values) else None
    return [round(f, 12) if math.isfinite(f) else None for f in values]


def write_report(report: dict, path: Path) -> None:
    """Write `report` as JSON to `path` atomically (no temporary file is left)."""
    write_text(json.dumps(plain(report), indent=1, allow_nan=False) + "\n", Path(path))


def write_text(text: str, path: Path) -> None:
    """Write `text` (UTF-8) to `path` atomically: a temporary file in the
    target folder, flushed, fsynced and renamed over `path`."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes it private; a report is not
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
