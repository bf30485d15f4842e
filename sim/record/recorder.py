"""The recorder: one run's review recording, frame by frame, written when closed.

The run hands each recorded frame to :meth:`Recorder.log_step` (and the
other `log_*` calls of that time), and at the end its events, wear and
summary to :meth:`Recorder.finish`. Per frame the recorder only copies
arrays into buffers; :meth:`Recorder.close` sends everything in columns
(`send_columns`, one chunk per entity for the whole run), then the
blueprint, and moves the file into place.

The recording id is new for every run (the scene name is the application
id and the recording name), the `log_time` timeline is not written, and
the recording's properties hold the units, clearance, scene file and
product version. The `.rrd` is written to a temporary file beside the
target and moved into place when the recorder is closed, so an interrupted
run still leaves a complete, readable recording and never a half-written
one.

Not here: what is shown where (`cablecheck.record.scene`, `.cables`, `.marks`,
`.series`, `.clashes`, `.wearview`, `.layout`); what is interference.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Sequence
from functools import cache
from pathlib import Path

import numpy as np
import rerun as rr

from cablecheck.build.built import Built
from cablecheck.build.drawn import DrawnGeom
from cablecheck.checker.shapes import Shape
from cablecheck.record.batches import alone, batches, static_columns
from cablecheck.record.cables import CableFrames
from cablecheck.record.clashes import Settings, send_clash_list, send_log
from cablecheck.record.columns import Once, column, floats, named, rgba, strings, times as sim_time, vec3
from cablecheck.record.layout import Extent, blueprint
from cablecheck.record.marks import ClashMarks, Mark
from cablecheck.record.scene import SceneGeometry
from cablecheck.record.series import SeriesSet, send_limit_lines
from cablecheck.record.style import CONTACT_COLOUR, cable_colour, escape, pair_path, pair_text
from cablecheck.record.wearview import (
    WearScale,
    charted,
    charts_note,
    send_bars,
    send_wear,
    wear_scale,
    worn_amounts,
)


@cache
def _distance_path(kind: str, a: str, b: str) -> str:
    return f"checks/{pair_path(kind, a, b)}/distance"


class Recorder:
    """Writes one run's recording to `path` (see the module docstring).

    Args:
      built: the built scene.
      path: the .rrd to write.
      shapes: the checker's shape of every built part (for the other side of a spot).
      settings: units, clearance, scene file and version (properties and summary).
      drawn: the mjcf model's visual geoms (`cablecheck.build.drawn.DrawnLoad`).
    """

    def __init__(self, built: Built, path: Path, shapes: list[Shape] | None = None,
                 settings: Settings | None = None, drawn: Sequence[DrawnGeom] = ()):
        scene = built.scene
        self.built = built
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.tmp")
        self.unit = scene.scale  # metres per scene unit
        self.settings = settings or Settings(scene.units, scene.check.clearance, str(scene.path), "unknown")
        self.rec = rr.RecordingStream(application_id=scene.name, recording_id=uuid.uuid4())
        self.rec.set_log_time_enabled(False)
        self.rec.set_log_tick_enabled(False)
        self.rec.save(str(self.tmp))
        self.rec.send_recording_name(scene.name)
        s = self.settings
        self.rec.send_property("cablecheck", named({
            "units": strings([s.units]), "clearance": floats([s.clearance / self.unit]),
            "scene_file": strings([s.scene_file]), "version": strings([s.version])}))
        self.scene = SceneGeometry(built, self.unit, drawn)
        self.cables = CableFrames(built, self.unit)
        self.marks = ClashMarks(built, self.unit, s.units, shapes)
        self.series = SeriesSet()
        units = s.units
        # per cable: (strain path, label, bend path, label), and twist's (path, label)
        self._cable_series = [(f"cables/strain/{escape(c.name)}", f"{c.name} strain (%)",
                               f"cables/bend_radius/{escape(c.name)}", f"{c.name} min bend radius ({units})")
                              for c in built.cables]
        self._twist_series = [(f"cables/twist/{escape(c.name)}", f"{c.name} twist (deg)") for c in built.cables]
        for i, ((strain_path, _, bend_path, _), (twist_path, _)) in enumerate(zip(self._cable_series,
                                                                                 self._twist_series)):
            for path in (strain_path, bend_path, twist_path):      # a cable's plots in its own colour
                self.series.colours[path] = cable_colour(i)
        self._closed = False
        self._sampled = True
        self._times: list[float] = []
        self._poses: list[np.ndarray] = []
        self._vis_poses: list[np.ndarray] = []
        self._contacts: list[np.ndarray | None] = []
        self._near_paths: set[str] = set()
        self._alive: set[str] = set()
        self._dimmed = False
        self._dim_changes: list[tuple[int, bool]] = []
        self._log: list[tuple[float, str, str]] = []
        self._rest: list[np.ndarray] | None = None
        self._poses0: np.ndarray | None = None
        self._events: list = []
        self._event_joints: list[dict] = []
        self._event_status: list[str] | None = None
        self._wear: list = []
        self._twist: list = []
        self._summary = ""

    # -- static content ---------------------------------------------------
    def log_static(self, part_poses: np.ndarray, cables: list[np.ndarray] | None = None,
                   qpos: np.ndarray | None = None) -> None:
        """Parts' and visual geoms' shapes (and poses of those that never
        move), once; `cables` (the rest state's body centres, metres) size the
        floor and frame the camera; `qpos` (the simulation's, at t = 0) poses
        the visual geoms."""
        self._rest = [np.asarray(c, float) for c in cables] if cables is not None else None
        self._poses0 = np.asarray(part_poses, float)
        self.rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        self.scene.log_static(self.rec, np.asarray(part_poses, float), self._rest, qpos)

    # -- per frame --------------------------------------------------------
    def log_step(self, t: float, cables: list[np.ndarray], part_poses: np.ndarray,
                 marks: list[Mark], strain: np.ndarray, bend: np.ndarray,
                 near: dict[tuple[str, str, str], float] | None = None,
                 qpos: np.ndarray | None = None, sampled: bool = True,
                 update: set[tuple[str, str, str]] | None = None, shapes: bool = True) -> None:
        """One frame: moving parts' poses, cables (coloured near the clashes),
        the clashes' spots, per-cable series and pair distances. `sampled`:
        one of the run's regular samples; False for a frame recorded only
        because an event starts or ends there, where a cable's shape is kept
        only if its state colours change and its measures (strain, bend
        radius, twist) are not kept. `near`: the
        pairs a full check since the last frame evaluated up to its horizon,
        (type, a, b) -> distance in metres (a pair's distance line runs while
        it is below the clearance or in the last full check's list, and breaks
        when it leaves both). `update`: at a frame between the regular
        samples (an event's worst instant, its start or its end), the pairs (kind, a,
        b) whose spots, distances and cables are given there; the other
        clashes stand as last given (`ClashMarks.add`). None: every one.
        `shapes` False (a regular sample of a scene of many cable elements,
        `cablecheck.run.runner.CABLE_SHAPES`): the cables of no updated pair
        stand as last given. Starts the frame the other `log_*` calls of
        this time add to."""
        u = self.unit
        frame = len(self._times)
        self._times.append(float(t))
        self._poses.append(np.asarray(part_poses)[self.scene.moving_parts])
        vis = self.scene.visual_body_poses(qpos)
        if vis is not None:
            self._vis_poses.append(vis)
        self._contacts.append(None)
        shown, updated = self.marks.add(frame, marks, cables, part_poses, update)
        keep = None if update is None else {n for _, a, b in updated | update for n in (a, b)}
        self.cables.add(frame, cables, marks, sampled, keep if shapes else (keep or set()))
        self._sampled = sampled
        add = self.series.add
        for (strain_path, strain_label, bend_path, bend_label), e, b in zip(self._cable_series, strain, bend):
            if sampled:
                add(strain_path, frame, 100.0 * float(e), strain_label)
            if sampled and np.isfinite(b):
                add(bend_path, frame, float(b / u), bend_label)
        if shown != self._dimmed:      # parts translucent while a clash is shown
            self._dimmed = shown
            self._dim_changes.append((frame, shown))
        known = set()
        for m in marks:
            path = _distance_path(m.kind, m.a, m.b)
            known.add(path)
            if update is None or (m.kind, m.a, m.b) in updated:
                add(path, frame, m.distance / u, f"{m.kind}: {pair_text(m.a, m.b)}")
        if near is not None:
            self._near_paths = set()
            for (kind, a, b), d in near.items():
                path = _distance_path(kind, a, b)
                self._near_paths.add(path)
                add(path, frame, d / u, f"{kind}: {pair_text(a, b)}")
        known |= self._near_paths
        for path in self._alive - known:
            self.series.series[path].gap(frame)
        self._alive = known

    def log_twist(self, twist_deg: np.ndarray) -> None:
        """Each cable's twist (degrees) at the current frame (if sampled); NaN: not measured."""
        if not self._sampled:
            return
        for (path, label), value in zip(self._twist_series, twist_deg):
            if np.isfinite(value):
                self.log_scalar(path, float(value), label=label)

    def log_joints(self, names: list[str], units: list[str], values: np.ndarray) -> None:
        """The moving joints' values at the current frame, one series each."""
        for name, unit, value in zip(names, units, values):
            self.log_scalar(f"joints/{escape(name)}", value, label=f"{name} ({unit})")

    def log_contacts(self, points: np.ndarray) -> None:
        """MuJoCo's contact points at this frame."""
        self._contacts[-1] = np.asarray(points, float).reshape(-1, 3) / self.unit

    def log_scalar(self, path: str, value: float, label: str | None = None) -> None:
        """A time series value at the current frame; `label` names the series
        in plot legends (the first one given)."""
        self.series.add(path, max(len(self._times) - 1, 0), value, label)

    def log_event(self, t: float, text: str, level: str) -> None:
        """An event as a text log entry at time t."""
        self._log.append((float(t), text, level))

    # -- at the end -------------------------------------------------------
    def finish(self, events: list, wear: list, summary: str, joints: list[dict] | None = None,
               status: list[str] | None = None, twist: list | None = None) -> None:
        """The run's events (clash list and viewpoints), wear map
        (:class:`cablecheck.checker.wear.CableWear` per cable), summary text and, where
        the mjcf model's joints move, each event's joint values at its worst
        time (name -> value, in the events' order), against a baseline
        run, each event's status (new or present), and per cable the
        simulated rod's twist along it (`cablecheck.report.document.TwistProfile`
        or None)."""
        self._twist = list(twist or [])
        self._events = list(events)
        self._event_status = status
        self._wear = list(wear)
        self._summary = summary
        self._event_joints = joints or [{} for _ in self._events]

    def close(self) -> None:
        """Send the buffered columns and the blueprint, finish the file and
        move it into place (safe to call twice)."""
        if self._closed:
            return
        self._closed = True
        try:
            self._send()
        finally:
            self.rec.disconnect()       # sends what is buffered and closes the file
            os.replace(self.tmp, self.path)

    def _send(self) -> None:
        rec = self.rec
        times = np.asarray(self._times, float)
        bounds = self.scene.bounds if self.scene.bounds is not None else (np.zeros(3), np.ones(3))
        if len(times):
            every = [rr.TimeColumn("sim_time", duration=times)]
            self.cables.send(rec, times)
            self.scene.send_motion(rec, every, self._poses, self._vis_poses)
            self._send_contacts(times)
            dim = [(0.0, False)] + [(times[f], on) for f, on in self._dim_changes]
            self.scene.send_colours(rec, np.array([t for t, _ in dim]), np.array([on for _, on in dim]))
            self.marks.send(rec, times, bounds, self.settings.clearance)
            self.series.send(rec, times)
            send_limit_lines(rec, self.built, times, self.settings.clearance, self.unit, self.settings.units)
        send_log(rec, self._log)
        names = self.names
        send_clash_list(rec, self._events, self._event_joints, self.unit, self.settings.units, self._event_status,
                        names)
        scale = self.wear_scale()
        worn = charted([w.name for w in self._wear], worn_amounts(self._wear, scale))
        send_wear(rec, self.built, self._wear, self._rest, self.unit, scale, *self._touched_parts(), charts=worn)
        # the cables whose rod carried twist, the most twisted: a chart of it along each
        profiles = [(c.name, p) for c, p in zip(self.built.cables, self._twist) if p is not None and len(p.s)]
        twisted = charted([n for n, _ in profiles], [float(p.max_moment.max()) for _, p in profiles])
        for name, p in profiles:
            if name in twisted:
                send_bars(rec, f"twist/{escape(name)}/max_moment", p.s / self.unit, p.max_moment)
        doc = rr.TextDocument
        rec.send_columns("summary", indexes=[sim_time(np.zeros(1))],
                         columns=[column(doc.descriptor_text(), strings([self._summary + charts_note(
                             len(self._wear), worn, len(profiles), twisted)])),
                                  column(doc.descriptor_media_type(), strings(["text/markdown"]))])
        extent = Extent(bounds, self.series.lowest("checks/"), frozenset(p.split("/")[0] for p in self.series.series),
                        any(p.startswith("cables/twist/") for p in self.series.series), twisted, worn)
        rec.send_blueprint(blueprint(self.built, self._events, self._wear, extent, self.settings.clearance, scale,
                                     self.unit, self.settings.units, self._event_status is not None, names),
                           make_active=True, make_default=True)

    def wear_scale(self) -> WearScale:
        """The wear map's one scale for the run (its rounding floor from the
        run's steps and the scene's largest coordinate)."""
        scene = self.built.scene
        steps = int(np.ceil(float(getattr(scene, "duration", 0.0)) / float(getattr(scene, "timestep", 1.0))))
        bounds = self.scene.bounds
        extent = float(np.abs(np.concatenate(bounds)).max()) if bounds is not None else 1.0
        return wear_scale(self._wear, self.unit, self.settings.units, steps, extent)

    def _touched_parts(self) -> tuple[dict, list]:
        """The parts some cable's wear names as touched, as at t = 0: name ->
        (shape, pose) of those drawn alone, and (entity path, archetype, columns) of the
        batches of many (`cablecheck.record.batches`)."""
        touched = {t for w in self._wear for t in w.touches if t is not None}
        if self._poses0 is None:
            return {}, []
        which = np.array([p.name in touched for p in self.built.parts], bool)
        parts = [p for p, t in zip(self.built.parts, which) if t]
        poses = self._poses0[which]
        found = batches(parts, np.zeros(len(parts), bool), "wear_map/parts")
        own = alone(len(parts), found)
        return ({p.name: (self.scene.shape(p, pose), pose) for p, pose, a in zip(parts, poses, own) if a},
                [(b.path, b.archetype, static_columns(b, parts, poses, self.unit)) for b in found])

    @property
    def names(self) -> list[str]:
        """The scene's cables' and parts' names (the clash list's short names are told apart among them)."""
        return [c.name for c in self.built.cables] + [p.name for p in self.built.parts]

    def _send_contacts(self, times: np.ndarray) -> None:
        """MuJoCo's contact points, one column, their style (3 px, the
        contacts' colour) in the first row."""
        found = [(f, c) for f, c in enumerate(self._contacts) if c is not None]
        if not found:
            return
        p = rr.Points3D
        self.rec.send_columns("world/mujoco_contacts", indexes=[sim_time(times[[f for f, _ in found]])], columns=[
            column(p.descriptor_positions(), vec3(np.concatenate([c for _, c in found])), [len(c) for _, c in found]),
            Once(p.descriptor_radii(), floats([-3.0], np.float32), len(found)),
            Once(p.descriptor_colors(), rgba([CONTACT_COLOUR]), len(found))])
