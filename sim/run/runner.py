"""One `cablecheck run`: build, settle, step, measure, record and report.

Data flows one way: scene -> models -> steps -> (cable body centres, part
poses) -> per-cable measures, checks and MuJoCo's contacts (`cablecheck.run.stepcheck`,
a batch of consecutive steps at a time) -> events, report and recording.
With dynamics the simulation settles and steps in a process of its own
(`cablecheck.run.apart`; on a thread where there is no fork, `cablecheck.run.ahead`)
from the moment its model is built, while this thread builds
the detection model (`cablecheck.build.stages.with_detection`, `cablecheck.detection.detector`) and
prepares the checks and the recording; the states come out in order, the
same as on one thread. `run_scene` owns the order of those stages, their
timing, and what happens on Ctrl-C: the loop stops after the step being
simulated (its batch is checked first), the recording is finished and
moved into place, and the report is written with `"complete": false`. The run hands on what it found
as one frozen record (`cablecheck.report.document.RunOutcome`), which `cablecheck.report.document` turns
into the report and writes.

A run never ends in a bare traceback or a wrong "complete". Each batch of
states is first scanned for a diverged simulation (`cablecheck.run.divergence`): the
states before the first diverged one are checked, the run stops there and
its outcome carries the `PhysicsError`. An error raised while stepping or
checking stops the run the same way, its outcome carrying the error
(`cablecheck.report.document.RunError`: type, message, traceback); `run_scene` also writes
a report for an error raised before the first step (bad input, the
scene's `SceneError` and the options' errors, is still raised). In every
case the recording is finished and moved into place and the report is
marked incomplete. MuJoCo's own messages are taken for the whole run
(`cablecheck.run.mjlog`): counted by kind in the report, never printed or written to
`MUJOCO_LOG.TXT`.

This module does not parse arguments or print (see `cli`), holds no
geometry of its own (distances come from `checker`) and does not lay out
the report.
"""

from __future__ import annotations

import gc
import math
import time
import traceback
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from cablecheck.about import version
from cablecheck.build.built import Built
from cablecheck.build.cablephysics import BEND_READ_FACTOR, BEND_RESOLUTION, COMPRESSION_TOLERANCE, shear_modulus
from cablecheck.build.checkview import OptionError
from cablecheck.build.drawn import DrawnLoad
from cablecheck.build.rodtwist import TwistReader
from cablecheck.build.routecheck import route_warnings
from cablecheck.build.stages import build_simulation, plan_cables, with_detection
from cablecheck.build.static import build_static, needs_model
from cablecheck.checker.arrays import ranges
from cablecheck.checker.cable import TAUT_STRAIN
from cablecheck.checker.events import Event, EventTracker
from cablecheck.checker.interference.margins import with_events
from cablecheck.checker.records import PairType, Severity
from cablecheck.checker.scene_state import CheckConfig
from cablecheck.checker.twist import RodTwistMeter, TwistMeter, update_many
from cablecheck.checker.wear import CableWear, WearMap
from cablecheck.detection.detector import Detector
from cablecheck.report.baseline import BaselineError, compare, load_baseline
from cablecheck.report.document import (
    STAGES,
    CableOutcome,
    RunError,
    RunOutcome,
    Timing,
    TwistProfile,
    failed_report,
    report_of,
    write_report,
)
from cablecheck.report.evidence import EvidenceKeeper, HtmlEvidence, Pictures
from cablecheck.report.html import write_html
from cablecheck.report.outputs import OutputPathError
from cablecheck.report.render import Spot, render_spots
from cablecheck.report.review import ReviewError, load_review, match
from cablecheck.run.ahead import StepsAhead, depth_for, thread_cpu
from cablecheck.run.apart import StepsApart
from cablecheck.run.apart import available as apart_available
from cablecheck.run.divergence import DivergenceWatch, PhysicsError
from cablecheck.run.jointspace import JointLog
from cablecheck.run.kinematic import KinematicSimulation
from cablecheck.run.loop import Simulation
from cablecheck.run.mjlog import MujocoMessages, data_warnings, warning_counts
from cablecheck.run.stepcheck import BATCH, BATCH_MAX, StepChecks, next_batch
from cablecheck.run.stop import StopRequest
from cablecheck.scene.allow import check_allow_names
from cablecheck.scene.cables import check_fastened_names
from cablecheck.scene.errors import SceneError, written
from cablecheck.scene.records import Scene

if TYPE_CHECKING:
    from cablecheck.record.recorder import Recorder

AHEAD_IN_A_PROCESS = True
"""A run with dynamics steps its simulation ahead in a process of its own
where fork is (`cablecheck.run.apart`), else on a thread
(`cablecheck.run.ahead`); tests set it False to run the thread here too."""

RECORD_RATE = 100.0
"""Recorded frames per simulated second (checks still run at every checked step)."""

LOOP_GC_YOUNG = 20_000
"""Allocations between collections of Python's youngest generation while
the states are checked (Python's default: 700; set back after the loop)."""

CABLE_SHAPES = 100_000
"""Element shapes per simulated second the regular samples record at most:
a scene of more cable elements than CABLE_SHAPES / RECORD_RATE (1,000)
gives its cables' shapes at every second, third, ... regular sample only
(28 bytes an element a frame: 64 hoses of 40 elements at 100 Hz alone were
7 MB a simulated second). Its events' worst instants, starts and ends still
give their own cables' shapes."""


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
      advance: skip the full pairwise check on steps where no pair but
        those already near the clearance (checked on their own) can have
        come within it since the last full check (:mod:`cablecheck.checker.advance`;
        the same events, pairs and MuJoCo comparison as checking every step
        in full). False checks every step in full.
      overlap: simulate the next steps in a process of their own while the
        last ones are checked (`cablecheck.run.apart`, or on a thread where
        there is no fork, `cablecheck.run.ahead`: the same states, events and
        report; on two cores the run takes about the larger side's time,
        not the sum). False runs every stage on the calling thread (a study
        worker, which is one core's share already).
    """

    report: Path
    record: Path | None
    method: str | None = None
    spacing: float | None = None
    only: str | None = None
    advance: bool = True
    overlap: bool = True
    baseline: Path | None = None
    review: Path | None = None
    html: Path | None = None
    """With a path: the run keeps each clash's worst state and distance
    history, renders its spot (`cablecheck.report.render`) and writes the
    HTML report there beside the JSON one (`cablecheck.report.html`)."""


Progress = Callable[[str, float, float], None]
"""progress(stage, done, total): called as a run advances."""


class _Timer:
    """CPU seconds per stage of the thread that runs the stages (the
    simulation may run in another process or thread, `cablecheck.run.apart`,
    `cablecheck.run.ahead`, which counts its own; waiting for it is no stage's
    time)."""

    def __init__(self):
        self.total = dict.fromkeys(STAGES, 0.0)
        self._t = thread_cpu()

    def skip(self) -> None:
        """Start the next stage now, the time since the last lap counted nowhere."""
        self._t = thread_cpu()

    def lap(self, stage: str) -> None:
        now = thread_cpu()
        self.total[stage] += now - self._t
        self._t = now


def run_scene(scene: Scene, options: RunOptions, progress: Progress | None = None,
              stop: StopRequest | None = None, warn: Callable[[str], None] | None = None) -> dict:
    """Run `scene`; write the report (and recording); return the report dict
    (`cablecheck.report.document.report_of` of the run's outcome).

    SIGINT (Ctrl-C) and SIGTERM at any moment stop the run cleanly: what was
    simulated is checked, the recording is finished and the report is written
    with ``"complete": false`` and ``"interrupted"`` naming the signal. A
    caller that listens from earlier on (the command line, from its start)
    passes its `stop`; a stop already asked runs nothing but the report.
    `warn` is given each physics warning (`cablecheck.build.stages.Built.warnings`: a part
    too fast for the timestep, ...) before the simulation starts.

    A diverged simulation or an error while stepping or checking ends the
    run with its report marked incomplete and holding `physics_error` or
    `error` (module docstring); an error raised before the first step
    does too, unless it is bad input (`SceneError`, the options'
    `OptionError`, `OutputPathError`, a `--baseline` that is no report:
    `BaselineError`, `--review` notes that cannot be used: `ReviewError`),
    which is raised."""
    start = time.perf_counter()

    def reported(stop: StopRequest) -> dict:
        outcome = None
        with MujocoMessages() as messages:
            try:
                outcome = _run(scene, options, progress, stop, start, warn, messages)
                report = report_of(outcome)
            except Exception as exc:
                if _bad_input(exc):
                    raise
                report = failed_report(scene, run_error(exc), warning_counts([], messages),
                                       time.perf_counter() - start, options.record)
        write_report(report, options.report)   # still under the stop request: a first signal waits
        if options.html is not None:           # from the same report dict: the two never disagree
            write_html(report, options.html, None if outcome is None else outcome.html)
        return report

    if stop is not None:
        return reported(stop)
    with StopRequest() as stop:
        return reported(stop)


def run_outcome(scene: Scene, options: RunOptions, progress: Progress | None = None,
                stop: StopRequest | None = None, warn: Callable[[str], None] | None = None) -> RunOutcome:
    """`run_scene` without the report: run `scene`, write its recording (when
    `options.record`) and return the run's outcome record (`options.report`
    is not written). An error raised before the first step is raised."""
    start = time.perf_counter()
    with MujocoMessages() as messages:
        if stop is not None:
            return _run(scene, options, progress, stop, start, warn, messages)
        with StopRequest() as stop:
            return _run(scene, options, progress, stop, start, warn, messages)


def _bad_input(exc: BaseException) -> bool:
    """`exc` is the scene's or the options' fault (the command line's exit status 2)."""
    return isinstance(exc, (SceneError, OptionError, OutputPathError, BaselineError, ReviewError))


def run_error(exc: BaseException, t: float | None = None) -> RunError:
    """`exc` as the report holds it: type, message, traceback and when."""
    return RunError(type(exc).__name__, str(exc),
                    "".join(traceback.format_exception(type(exc), exc, exc.__traceback__)), t)


def _run(scene: Scene, options: RunOptions, progress: Progress | None, stop: StopRequest,
         start: float, warn: Callable[[str], None] | None, messages: MujocoMessages) -> RunOutcome:
    baseline = load_baseline(options.baseline) if options.baseline is not None else None   # bad input first
    notes = load_review(options.review) if options.review is not None else None
    validate = scene.check.validate
    static = not needs_model(scene)     # nothing calls for MuJoCo: no model is built (cablecheck.build.static)
    planned = None if static else plan_cables(scene)
    noted = scene.warnings
    # the simulation model first: the detection model is compiled while it settles
    built = build_static(scene) if static else build_simulation(scene, planned)
    check_allow_names(scene, [p.name for p in built.parts] + [c.name for c in built.cables])
    check_fastened_names(scene, [p.name for p in built.parts])
    if warn is not None:
        for w in noted + tuple(built.warnings):
            warn(w)
    sim = KinematicSimulation(built) if static else Simulation(built, validate=validate)
    sim.reset()
    # only a simulation that steps can diverge
    watch = DivergenceWatch(built, scene.settle) if scene.effects.dynamics and not static else None
    if progress:
        progress("settle", 0, max(sim.settle_steps, 1))

    def asked() -> bool:
        return stop.asked

    def settle(report: Progress | None = progress, halted: Callable[[], bool] = asked) -> None:
        if not halted():
            sim.settle(None if report is None else
                       (lambda k: report("settle", k, sim.settle_steps) if k % 50 == 0 else None),
                       stop=halted)

    every = scene.check.every
    # the states until a stop is asked (polled before each state is made)
    states = _until(sim.steps(contacts=False, every=every), asked)
    ahead: StepsApart | StepsAhead | None = None
    if options.overlap and scene.effects.dynamics and not static:
        # dynamics: the simulation settles and steps ahead in a process of its own (cablecheck.run.apart;
        # on a thread where there is no fork, cablecheck.run.ahead) while the detection model and the
        # checks are prepared here
        depth = depth_for(sim.state_bytes())
        if AHEAD_IN_A_PROCESS and apart_available():
            gc.freeze()      # what the set-up made so far: out of both processes' collections (below, the loop)
            try:
                ahead = StepsApart(states, depth, before=settle, progress=progress,
                                   finish=_simulation_messages(sim, messages), halted=asked)
            except BaseException:
                gc.unfreeze()
                raise
        else:
            ahead = StepsAhead(states, depth, before=settle)
    else:
        settle()
    # the mjcf model's visual geoms, which only the recording draws, compiled on a thread of their own
    # (started after the simulation's process is forked: no compile is under way in the fork)
    drawn = DrawnLoad(scene) if options.record and not static else None
    try:
        # the routed shapes against the parts they collide with, while the simulation settles
        routes = () if static else route_warnings(scene, *planned)
        if warn is not None:
            for w in routes:
                warn(w)
        noted += routes
        detector = None
        if validate and not static:
            built = with_detection(built, planned)
            detector = Detector(built)
        timer = _Timer()
        config = CheckConfig(method=options.method or scene.check.method,
                             spacing=options.spacing or scene.check.spacing,
                             clearance=scene.check.clearance)
        checks = StepChecks(built, config, options.only, options.advance, detector, timer.lap)
        timer.skip()          # preparing the checks is set-up, as building the model is: no stage's
        scene_file, product = str(scene.path), version()
        recorder = None
        if options.record:
            # rerun loads (half a second) only for a run that records
            from cablecheck.record.clashes import Settings
            from cablecheck.record.recorder import Recorder

            settings = Settings(scene.units, scene.check.clearance, scene_file, product)
            recorder = Recorder(built, options.record, checks.shapes, settings,
                                drawn.result() if drawn is not None else ())
        # The recording samples the checked steps at about RECORD_RATE (and at
        # every step where an event starts or ends): a viewer needs no 500 Hz.
        # The wear map measures contact at the same rate (bends at every step).
        record_stride = max(1, int(round(1.0 / (RECORD_RATE * every * scene.timestep))))
        wear = WearMap([c.name for c in built.cables], [c.rest_s for c in built.cables],
                       [c.radius for c in built.cables],
                       [(p.name, shape) for p, shape in zip(built.parts, checks.shapes)],
                       scene.check.clearance, checks.exclusions, stride=record_stride)
        timer.skip()          # opening the recording is no step's cost (it was never timed)
        tracker = EventTracker(hold=3 * every * scene.timestep, allow=checks.allow)
        joints = JointLog(built, sim.motion)
        elements = sum(len(c.rest_s) - 1 for c in built.cables)
        shape_every = max(1, math.ceil(elements * RECORD_RATE / CABLE_SHAPES))
        out = _Checked(built, tracker, recorder, timer, progress, record_stride, sim.total_steps, joints, wear,
                       checks.exclusions, evidence=options.html is not None, shape_every=shape_every)
    except BaseException:
        gc.unfreeze()
        if ahead is not None:
            ahead.close()
        raise
    complete = False
    diverged: PhysicsError | None = None
    error: RunError | None = None
    batch: list = []
    size = BATCH
    # The set-up's objects (the models, parts, meshes' structures, imports) out of Python's
    # collections until the loop ends (gc.freeze; before the fork too, so the simulation's
    # process does not copy their pages to collect them): each full collection in the loop
    # traversed them all. Collecting took 0.20 s of the Tiago's run, 0.075 s so (a 64 x 1,000
    # harness's first 0.3 s: 0.71 -> 0.21 s). Unfrozen after the loop, so a process running
    # many scenes (a study's worker) collects them as before. And the youngest generation is
    # collected after LOOP_GC_YOUNG allocations, not Python's 700: the loop's records and
    # arrays mostly die young, before a collection need look at them (the harness's first
    # 0.3 s: 0.30 -> 0.18 s of collecting; the Tiago's 0.08 -> 0.06 s).
    gc.freeze()
    thresholds = gc.get_threshold()
    gc.set_threshold(LOOP_GC_YOUNG, *thresholds[1:])
    loop_start = time.perf_counter()
    try:
        for state in (states if ahead is None else ahead):
            # states are checked BATCH at a time at first, then each batch
            # twice the last up to BATCH_MAX, shrinking towards the run's end
            # (cablecheck.run.stepcheck.next_batch): the last state
            # of the run closes its batch, and an interrupted run's last
            # states are checked after the loop; an unstable simulation's
            # last state closes its batch at once
            batch.append(state)
            if len(batch) < size and state.step < sim.total_steps and state.unstable is None:
                continue
            diverged = _check_batch(batch, checks, out, timer, ahead, watch)
            batch = []
            if diverged is not None:
                break
            size = next_batch(size, sim.total_steps - state.step, every, BATCH, max(BATCH, BATCH_MAX))
        if batch:
            diverged = _check_batch(batch, checks, out, timer, ahead, watch)
        complete = not stop.asked and diverged is None
    except KeyboardInterrupt:
        complete = False    # a second Ctrl-C: the batch being checked is left out
    except Exception as exc:   # the run ends with the error in its report
        complete = False
        error = run_error(exc, out.t_last if out.checked else None)
    finally:
        gc.unfreeze()
        gc.set_threshold(*thresholds)
        if ahead is not None:
            ahead.close()
            timer.total["sim"] += ahead.cpu
            if isinstance(ahead, StepsApart) and ahead.finished is not None:
                messages.add(*ahead.finished[1:])     # MuJoCo's messages while it stepped in its process
        closed = {id(ev) for ev in tracker.events}
        events = tuple(tracker.finish())
        worn = wear.result()
        excused = checks.excused.worst()
        compared = (compare(events, {c.name: c.radius for c in built.cables}, baseline)
                    if baseline is not None else None)
        # where the mjcf model's joints move: their values per event
        event_joints = (tuple(joints.event_fields(e.t_start, e.t_end, e.t_worst, e.a, e.b) for e in events)
                        if joints else None)
        if recorder:
            timer.lap("check")
            for ev in events:  # each event still open at the end gets its one end entry
                if id(ev) not in closed:
                    _log_end(recorder, ev, scene.scale, scene.units, at_end=True)
            from cablecheck.record.clashes import (
                summary_text,  # loaded with the Recorder above
            )

            summary = summary_text(scene.name, settings, events, worn, scene.scale, complete,
                                   tuple(tracker.allowed.values()), excused, compared)
            stopped = _stopped_entry(diverged, error, out.t_last)
            if stopped is not None:          # why the run stopped: in the log and the summary
                recorder.log_event(stopped[0], stopped[1], "ERROR")
                summary += f"\n\n**{stopped[1]}**\n"
            recorder.finish(list(events), worn, summary,
                            None if event_joints is None else [f["joints"] for f in event_joints],
                            None if compared is None else [s.value for s in compared.status],
                            out.twist_profiles())
            recorder.close()
            timer.lap("record")
        loop_s = time.perf_counter() - loop_start
    ends = checks.outcome(validated=scene.check.validate)
    html = None if out.keeper is None else _html_evidence(built, events, out.keeper)
    return RunOutcome(
        scene=scene, config=config, scene_file=scene_file, version=product,
        mujoco=mujoco.__version__, complete=complete, interrupted=stop.signal_name,
        steps=out.steps, checked=out.checked, t_end=out.t_last, cables=out.cables(worn),
        events=events, event_joints=event_joints,
        joint_units=dict(zip(joints.names, joints.units)) if joints else None,
        pairs=tuple(tracker.pairs.values()), allowed=tuple(tracker.allowed.values()), excused=excused,
        closest=with_events(ends.closest, events), margin_reach=ends.margin_reach,
        margin_interval=ends.margin_interval, allowed_interval=ends.allowed_interval,
        event_hold=tracker.hold, baseline=compared,
        review=None if notes is None else match(options.review, notes, events),
        validation=ends.validation, advance=ends.advance,
        warnings=warning_counts([_stepped_warnings(sim, ahead),   # a static check has none
                                 detector.detect_data if detector else None], messages),
        part_warnings=ends.part_warnings,
        physics_warnings=noted + tuple(built.warnings) + ends.hull_warnings + out.compression_warnings() + out.bend_warnings(),
        substeps=built.substeps.count if built.substeps else 1,
        timing=Timing(time.perf_counter() - start, dict(timer.total),
                      detector.collision_seconds() if detector is not None else None, loop_s,
                      watch.seconds if watch is not None else None),
        recording=options.record, physics_error=diverged, error=error, html=html)


def _simulation_messages(sim: Simulation, messages: MujocoMessages) -> Callable[[], tuple]:
    """What a simulation stepped in another process (`StepsApart`) raised
    there, taken at its end: its data's warning counters and MuJoCo's
    messages since it was forked (those before are this process's)."""
    counts, first = Counter(messages.counts), dict(messages.first)
    return lambda: (data_warnings(sim.data), dict(messages.counts - counts),
                    {k: v for k, v in messages.first.items() if k not in first})


def _stepped_warnings(sim, ahead) -> dict[str, int] | mujoco.MjData | None:
    """The stepped simulation's warning counters (`warning_counts`): its own
    data's, or, stepped in a process of its own, those it sent at its end
    (none when it died: the run's error says so)."""
    if not isinstance(sim, Simulation):
        return None
    if isinstance(ahead, StepsApart):
        return ahead.finished[0] if ahead.finished is not None else {}
    return sim.data


def _stopped_entry(diverged: PhysicsError | None, error: RunError | None, t_last: float
                   ) -> tuple[float, str] | None:
    """The recording's entry for a run stopped by a divergence or an error: (time, text)."""
    if diverged is not None:
        return max(diverged.t, 0.0), diverged.message()
    if error is not None:
        return (error.t if error.t is not None else t_last), f"the run failed: {error.type}: {error.message}"
    return None


def _until(states: Iterator, stop: Callable[[], bool]) -> Iterator:
    """`states` until `stop()` (asked before each state is made, the first too)."""
    if stop():
        return
    for state in states:
        yield state
        if stop():
            return


def _check_batch(batch: list, checks: StepChecks, out: _Checked, timer: _Timer,
                 ahead: StepsApart | StepsAhead | None, watch: DivergenceWatch | None) -> PhysicsError | None:
    """Check a batch of states and take it in, up to its first diverged
    state (`cablecheck.run.divergence`), which is returned; the time since the last
    lap was the simulation's, or with `ahead` the wait for it (no stage's).
    The divergence scan is part of the check stage."""
    if ahead is None:
        timer.lap("sim")
    else:
        timer.skip()
    found = watch.scan(batch) if watch is not None else None
    if found is not None:
        batch = batch[:found[0]]
    if batch:
        out.take(batch, checks.run(batch))
    return None if found is None else found[1]


def _clamped(anchor) -> bool:
    """The end holds the cable's tangent and roll (the default `hold`)."""
    return getattr(anchor, "hold", "clamp") == "clamp"


class _Checked:
    """What the run keeps of its checked steps, taken in order: events,
    strain and bend extremes, first and last cable shapes, twist, the
    recording and progress."""

    def __init__(self, built: Built, tracker: EventTracker, recorder: Recorder | None, timer: _Timer,
                 progress: Progress | None, record_stride: int, total_steps: int, joints: JointLog,
                 wear: WearMap, exclusions=(), evidence: bool = False, shape_every: int = 1):
        self.built, self.tracker, self.recorder, self.timer = built, tracker, recorder, timer
        self.shape_every = shape_every          # regular samples per one giving every cable's shape
        self.joints = joints
        self.wear = wear
        self.near = _NearPairs(built, exclusions, built.scene.check.clearance)
        # --html: each event's worst state and each pair's distances (cablecheck.report.evidence)
        self.keeper = EvidenceKeeper(self.near.distances) if evidence else None
        self.pending_near = None
        self.progress, self.record_stride, self.total_steps = progress, record_stride, total_steps
        self.names = [c.name for c in built.cables]
        n = len(built.cables)
        self.max_strain = np.zeros(n)   # signed, largest in magnitude (compression negative)
        self.max_stretch = np.full(n, -np.inf)
        self.least_strain = np.full(n, np.inf)       # most compressed, and when (scene time)
        self.least_t = np.full(n, np.nan)
        self.first_short = np.full(n, np.nan)       # first checked time below -COMPRESSION_TOLERANCE
        self.min_bend = np.full(n, np.inf)
        self.min_bend_t = np.full(n, np.nan)        # when (scene time)
        self.rest_points: list[np.ndarray] = []
        self.final_points: list[np.ndarray] = []
        self.steps = self.checked = 0
        self.t_last = 0.0
        self.clamped = [_clamped(c.start) and _clamped(c.end) for c in built.scene.cables]
        self.twist: list[TwistMeter | RodTwistMeter | None] = [None] * n
        self.rods = TwistReader.of(built)

    def take_twist(self, states, points: np.ndarray | None) -> None:
        """Each cable's twist over the batch, in degrees (`batch_twist`):
        with dynamics, as the simulated rod carries it (`RodTwistMeter`);
        without, wound in by the frames of ends clamped at both ends
        (`TwistMeter`; the first state, t = 0, is the reference). `points`:
        (S, N, 3) all cables' points of each state, in order."""
        self.batch_twist = np.full((len(states), len(self.clamped)), np.nan)
        if not states:
            return
        if states[0].rod is not None:
            twists = self.rods.read_many([s.rod for s in states], points, np.stack([s.qpos for s in states]))
            for i, (rod, twist) in enumerate(zip(self.built.rods, twists)):
                if rod is None:
                    continue
                if self.twist[i] is None:
                    self.twist[i] = RodTwistMeter(rod.stiffness, rod.length)
                self.batch_twist[:, i] = np.degrees(self.twist[i].take(twist))
            return
        if states[0].end_rot is None:
            return
        cables = [i for i, clamped in enumerate(self.clamped) if clamped]
        if not cables:
            return
        pts = [np.stack([s.cables[i] for s in states]) for i in cables]
        rot = [np.stack([s.end_rot[i] for s in states]) for i in cables]
        for i, p, r in zip(cables, pts, rot):
            if self.twist[i] is None:
                self.twist[i] = TwistMeter(p[0], r[0, 0], r[0, 1])
        twists = update_many([self.twist[i] for i in cables], pts, [r[:, 0] for r in rot], [r[:, 1] for r in rot])
        for i, twist in zip(cables, twists):
            self.batch_twist[:, i] = np.degrees(twist)

    def take(self, states, results) -> None:
        """The checked states (oldest first) and their results."""
        recorder, scale = self.recorder, self.built.scene.scale
        # every cable's points of each state, for the twist and the wear
        points = (np.stack([np.concatenate(s.cables) if s.cables else np.zeros((0, 3)) for s in states])
                  if len(states) else None)
        self.take_twist(states, points)
        self.timer.lap("check")
        if len(states):
            self.wear.update_many([s.t for s in states], points,
                                  np.stack([s.part_poses for s in states]), [r.records for r in results])
            self.timer.lap("wear")
        if len(results):
            # the batch's extremes in one pass (the first of equal magnitudes, as state by state)
            strain = np.stack([r.strain for r in results])
            first = strain[np.argmax(np.abs(strain), axis=0), np.arange(strain.shape[1])]
            self.max_strain = np.where(np.abs(first) > np.abs(self.max_strain), first, self.max_strain)
            self.max_stretch = np.maximum(self.max_stretch, strain.max(axis=0))
            times = np.array([st.t for st in states[:len(results)]], float)
            k = np.argmin(strain, axis=0)
            least = strain[k, np.arange(strain.shape[1])]
            deeper = least < self.least_strain
            self.least_strain = np.where(deeper, least, self.least_strain)
            self.least_t = np.where(deeper, times[k], self.least_t)
            short = strain < -COMPRESSION_TOLERANCE
            first = np.where(short.any(axis=0), times[np.argmax(short, axis=0)], np.nan)
            self.first_short = np.where(np.isnan(self.first_short), first, self.first_short)
            bend = np.stack([r.bend for r in results])
            k = np.argmin(bend, axis=0)
            least = bend[k, np.arange(bend.shape[1])]
            tighter = least < self.min_bend
            self.min_bend = np.where(tighter, least, self.min_bend)
            self.min_bend_t = np.where(tighter, times[k], self.min_bend_t)
        # the events first, the whole batch: the last state at which each event's worst
        # deepened within the batch is then recorded too (its worst instant, as the report has it)
        changes = []
        deepest: dict[tuple, int] = {}    # (pair, t_start) -> the batch's state where that event last deepened
        for k, (state, res) in enumerate(zip(states, results)):
            started, closed = self.tracker.update(state.t, res.records)
            changes.append(([self.tracker.standing(key) for key in started], closed))
            if (recorder or self.keeper is not None) and (res.records or closed):
                for event in self.tracker.worst_at(state.t):
                    deepest[event] = k
        deepest_at: dict[int, set[tuple[str, str, str]]] = {}     # state -> the pairs whose worst is there
        for (pair, _), k in deepest.items():
            deepest_at.setdefault(k, set()).add((PairType(pair[0]).value, pair[1], pair[2]))
        if self.keeper is not None:
            self.keeper.take(states, results, deepest)
        self.timer.lap("check")
        for k, (state, res) in enumerate(zip(states, results)):
            if state.step == 0:
                self.rest_points = state.cables
                if recorder:
                    self.timer.lap("check")
                    recorder.log_static(state.part_poses, state.cables, state.qpos)
                    self.timer.lap("record")      # the scene's static data: recording, not checking
            started, closed = changes[k]
            if res.near is not None:
                self.pending_near = res.near     # a full check's candidates, shown at the next frame
            self.timer.lap("check")
            # a regular sample or the last step: a whole frame; an event's worst so far, or
            # a start or an end, between them: a frame of those events' pairs (the others stand)
            last = state.step == self.total_steps
            regular = self.checked % self.record_stride == 0 or last
            shapes = last or (self.checked // self.record_stride) % self.shape_every == 0
            sampled = regular or k in deepest_at
            if recorder and (sampled or started or closed):
                update = None if regular else (
                    deepest_at.get(k, set()) | {(PairType(e.type).value, e.a, e.b) for e in (*started, *closed)})
                allow = self.tracker.allow   # allowed pairs are drawn as clear
                shown = (replace(res, records=[r for r in res.records if not allow.match(self.tracker.key(r))])
                         if allow else res)
                _record_step(recorder, state, shown, started, closed, self.near,
                             self.pending_near, scale, self.built.scene.units, sampled, update, shapes)
                self.pending_near = None
                if self.joints:
                    recorder.log_joints(self.joints.names, self.joints.units, self.joints.values(state.t)[0])
                recorder.log_twist(self.batch_twist[k])
                self.timer.lap("record")
            self.final_points = state.cables
            self.steps, self.t_last = state.step, state.t
            self.checked += 1
            if self.progress:
                self.progress("run", state.step, self.total_steps)

    def compression_warnings(self) -> tuple[str, ...]:
        """The cables shorter than their length by more than
        `COMPRESSION_TOLERANCE` at some checked step: the edges held the
        length no better (docs/physics.md, Length in compression)."""
        out = []
        for i, name in enumerate(self.names):
            if not np.isnan(self.first_short[i]):
                out.append(f"cable {name!r} is shorter than its length by more than "
                           f"{100 * COMPRESSION_TOLERANCE:g} % (the length the simulation holds to): "
                           f"from t = {self.first_short[i]:.4g} s, most at t = {self.least_t[i]:.4g} s, "
                           f"strain {100 * self.least_strain[i]:.3g} %: it carried more compression than "
                           f"the buckling load of its held runs, under which its elements give with the "
                           f"step squared (a smaller scene.timestep gives less; docs/physics.md, Length in "
                           f"compression)")
        return tuple(out)

    def bend_warnings(self) -> tuple[str, ...]:
        """The cables with a bend limit whose least bend radius spans fewer
        than `BEND_RESOLUTION` of their elements, near enough to the limit
        to hide a bend past it (`BEND_READ_FACTOR`): the rod reads such a
        bend larger than it is (docs/physics.md, Bends the elements cannot resolve)."""
        out = []
        for i, c in enumerate(self.built.cables):
            r, step, limit = float(self.min_bend[i]), c.element_length, c.min_bend_radius
            if limit is None or not np.isfinite(r) or r >= BEND_RESOLUTION * step or r >= BEND_READ_FACTOR * limit:
                continue
            need = int(np.ceil(BEND_RESOLUTION * c.length / max(r, 1e-12)))
            scene = self.built.scene      # lengths in the scene's own units, as every warning gives them
            out.append(f"cable {c.name!r}: its least bend radius, {written(scene, r)} at t = "
                       f"{self.min_bend_t[i]:.4g} s, spans fewer than {BEND_RESOLUTION:g} of its elements "
                       f"({written(scene, step)} each): the simulated rod cannot resolve a bend that tight and reads "
                       f"it larger than it is (its limit is {written(scene, c.min_bend_radius)}); to see it, "
                       f"segments = {need} at least, and again finer until it settles (docs/physics.md, Bends the "
                       "elements cannot resolve)")
        return tuple(out)

    def twist_profiles(self) -> list[TwistProfile | None]:
        """Per cable, the simulated rod's twist along it (None: not simulated)."""
        rods = self.built.rods or (None,) * len(self.twist)
        return [_twist_profile(meter, rod) for meter, rod in zip(self.twist, rods)]

    def cables(self, wear: list[CableWear]) -> tuple[CableOutcome, ...]:
        """Each cable over the checked steps, with its wear map."""
        checked = self.checked > 0
        profiles = self.twist_profiles()
        out = []
        for i, (c, defn) in enumerate(zip(self.built.cables, self.built.scene.cables)):
            limit = c.min_bend_radius
            meter = self.twist[i]
            out.append(CableOutcome(
                name=c.name, length=c.length, radius=c.radius,
                segments=c.count - 1,   # every element, a clamp's short held edge included
                max_strain=self.max_strain[i] if checked else None,
                taut=bool(checked and self.max_stretch[i] > TAUT_STRAIN),
                min_bend_radius=self.min_bend[i] if checked else None,
                bend_violation=bool(limit is not None and checked and self.min_bend[i] < limit),
                rest_points=np.asarray(self.rest_points[i]) if self.rest_points else None,
                final_points=np.asarray(self.final_points[i]) if self.final_points else None,
                wear=wear[i],
                max_twist=None if meter is None else float(meter.max_abs),
                max_twist_moment=(None if meter is None else float(meter.max_moment.max(initial=0.0))
                                  if isinstance(meter, RodTwistMeter)
                                  else _twist_moment(defn, c.radius, c.length, meter.max_abs)),
                twist=profiles[i]))
        return tuple(out)


def _html_evidence(built: Built, events: tuple[Event, ...], keeper: EvidenceKeeper) -> HtmlEvidence:
    """What the HTML report shows of each event: its kept state, distance
    history and a picture of its spot at its worst state (a static check,
    with no MuJoCo model, has none: said in the pictures' warnings)."""
    clashes = keeper.result(events)
    if not isinstance(built.model, mujoco.MjModel):
        return HtmlEvidence(clashes, Pictures((None,) * len(events), None, (
            "no clash pictures: a static check builds no MuJoCo model to render",) if events else ()))
    geoms = {p.name: p.geom_id for p in built.parts}
    flexes = {c.name: (c.flex_id, c.radius) for c in built.cables}
    least = min((c.radius for c in built.cables), default=0.005)
    spots = []
    for e, c in zip(events, clashes):
        names = {e.a, e.b}
        spots.append(Spot(qpos=c.qpos, where=np.asarray(e.where, float) - built.origin,
                          geoms=tuple(geoms[n] for n in names if n in geoms),
                          flexes=tuple(flexes[n][0] for n in names if n in flexes),
                          size=flexes[e.a][1] if e.a in flexes else least))
    try:
        pictures = render_spots(built.model, spots)
    except Exception as exc:   # a picture is never worth the run: said in the report and the HTML
        pictures = Pictures((None,) * len(events), None,
                            (f"no clash pictures: rendering failed: {type(exc).__name__}: {exc}",))
    return HtmlEvidence(clashes, pictures)


def _twist_profile(meter, rod) -> TwistProfile | None:
    """Where along the cable the simulated rod's twist was largest, or None (not simulated)."""
    if not isinstance(meter, RodTwistMeter):
        return None
    return TwistProfile(rod.s, meter.max_moment, meter.max_rate)


def _twist_moment(defn, radius: float, length: float, twist: float) -> float:
    """N m: G J twist / L, the torsional moment a straight cable of that
    twist (radians over the cable) carries, G its `shear_modulus`."""
    return float(shear_modulus(defn) * np.pi * radius ** 4 / 2.0 * twist / length)


def _record_step(recorder: Recorder, state, res, started, closed, near: _NearPairs, pending,
                 unit: float, units: str, sampled: bool = True, update: set | None = None,
                 shapes: bool = True) -> None:
    """One recorded frame: the step's clashes as marks, the pairs evaluated
    near the clearance (approach history), contacts, agreement, event entries
    (`started`: the events starting here, as they started). `update`: at a
    frame between the regular samples, the pairs given there (`Recorder.log_step`);
    MuJoCo's contacts are then not given again (those of the last sample stand).
    `shapes`: at a regular sample, whether every cable's shape is given
    (`CABLE_SHAPES`)."""
    from cablecheck.record.marks import (
        Mark,  # imported already by the run's Recorder (a recording run)
    )

    marks = [Mark(_KIND[r.type], r.a, r.b, float(r.min_distance), _STATE[r.severity],
                  np.asarray(r.where), float(r.s), r.s_b) for r in res.records]
    recorder.log_step(state.t, state.cables, state.part_poses, marks, strain=res.strain, bend=res.bend,
                      near=None if pending is None else near.distances(pending), qpos=state.qpos, sampled=sampled,
                      update=update, shapes=shapes)
    if res.contacts is not None and update is None:
        recorder.log_contacts(res.contacts.pos)
    if res.agreement is not None:
        recorder.log_scalar("validation/agreement", res.agreement, label="agreement with MuJoCo")
    for ev in started:
        recorder.log_event(state.t, f"{ev.type} {_pair(ev.a, ev.b)} starts: distance "
                           f"{ev.min_distance / unit:.4g} {units}", _LEVEL[ev.severity])
    for ev in closed:
        _log_end(recorder, ev, unit, units, at_end=False)


_KIND = {**{t: t.value for t in PairType}, **{t.value: t.value for t in PairType}}
_STATE = {**{v: v.value for v in Severity}, **{v.value: v.value for v in Severity}}
"""A record's type and severity (a member or its value) as the recording's plain strings: a dict's
lookup, not the enum's constructor (a quarter of a harness frame's marks cost: 250 records a frame)."""

_LEVEL = {Severity.HARD: "ERROR", Severity.SOFT: "WARN"}
"""Text log level of an event's entries by severity."""


def _pair(a: str, b: str) -> str:
    return a if a == b else f"{a} / {b}"


def _log_end(recorder: Recorder, ev: Event, unit: float, units: str, at_end: bool) -> None:
    how = "still present at the end of the run" if at_end else "ends"
    recorder.log_event(ev.t_end, f"{ev.type} {_pair(ev.a, ev.b)} {how}: {ev.severity} {ev.phase}, "
                       f"{ev.t_start:.3f}-{ev.t_end:.3f} s, worst {ev.min_distance / unit:.4g} {units} "
                       f"at t = {ev.t_worst:.3f} s", _LEVEL[ev.severity])


class _NearPairs:
    """Per pair, the least distance among a full check's candidates (up to its
    horizon), leaving out the places inside attachment windows: the approach
    history of pairs not (yet) below the clearance."""

    def __init__(self, built: Built, exclusions, clearance: float):
        self.clearance = clearance
        self.cables = [c.name for c in built.cables]
        self.parts = [p.name for p in built.parts]
        self.keepout = np.array([p.keepout for p in built.parts], bool)
        index = {n: i for i, n in enumerate(self.cables)}
        part_index = {n: k for k, n in enumerate(self.parts)}
        rows = [(index[e.cable], part_index[e.part], e.s_min, e.s_max) for e in exclusions
                if e.cable in index and e.part in part_index]
        excl = np.array(rows, float).reshape(-1, 4)
        # windows sorted by (cable, part) key: a candidate finds its own by a
        # binary search (a harness holds every cable end against every part of its body)
        self._n_k = max(len(self.parts), 1)
        key = excl[:, 0].astype(np.int64) * self._n_k + excl[:, 1].astype(np.int64)
        o = np.argsort(key, kind="stable")
        self._ex_key, self._ex_lo, self._ex_hi = key[o], excl[o, 2], excl[o, 3]

    def _outside(self, cab: np.ndarray, part: np.ndarray, s: np.ndarray) -> np.ndarray:
        """(n,) True where a candidate lies in no attachment window of its (cable, part)."""
        key = np.asarray(cab, np.int64) * self._n_k + np.asarray(part, np.int64)
        first = np.searchsorted(self._ex_key, key, "left")
        count = np.searchsorted(self._ex_key, key, "right") - first
        keep = np.ones(len(key), bool)
        if count.sum():
            row = np.repeat(np.arange(len(key)), count)
            w = ranges(first, count)
            inside = (s[row] >= self._ex_lo[w]) & (s[row] <= self._ex_hi[w])
            keep[row[inside]] = False
        return keep

    def distances(self, near: tuple) -> dict[tuple[str, str, str], float]:
        (cab, s, part, value), cable_pairs = near
        clearance = self.clearance     # the candidates' values are relative to it
        out: dict[tuple[str, str, str], float] = {}
        if len(cab):
            keep = self._outside(cab, part, s)
            n_k = max(len(self.parts), 1)
            key = cab[keep] * n_k + part[keep]
            if len(key):
                uniq, inv = np.unique(key, return_inverse=True)
                least = np.full(len(uniq), np.inf)
                np.minimum.at(least, inv, value[keep])
                for k, v in zip(uniq.tolist(), least.tolist()):
                    c, p = divmod(k, n_k)
                    kind = PairType.KEEPOUT if self.keepout[p] else PairType.CABLE_STRUCTURE
                    out[(kind.value, self.cables[c], self.parts[p])] = v + clearance
        ca, _, cb, _, c_value = cable_pairs
        if len(ca):
            lo_c, hi_c = np.minimum(ca, cb), np.maximum(ca, cb)
            n_c = max(len(self.cables), 1)
            uniq, inv = np.unique(lo_c * n_c + hi_c, return_inverse=True)
            least = np.full(len(uniq), np.inf)
            np.minimum.at(least, inv, c_value)
            for k, v in zip(uniq.tolist(), least.tolist()):
                a, b = divmod(k, n_c)
                kind = PairType.SELF if a == b else PairType.CABLE_CABLE
                out[(kind.value, self.cables[a], self.cables[b])] = v + clearance
        return out
