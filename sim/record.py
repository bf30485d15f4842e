"""The rerun recording of a run: a clash review on a `sim_time` timeline.

Entity tree (mirrors the scene, in the scene's units, z up):
- `world/parts/<assembly path>`: each part's shape (filled), logged once as
  static in its own frame; its pose is static for parts on the world and
  logged per frame for parts riding a moving body. While any clash is shown
  the parts turn translucent, so a spot inside a panel stays visible. A
  plane is drawn as a rectangle: its given size, else sized to cover the
  scene.
- `world/visual/<body>/<geom>`: the mjcf model's visual geoms (those MuJoCo
  never collides), in their own colours (translucent too while a clash is
  shown), static in their body's frame; the body's pose
  (`world/visual/<body>`) comes from the frame's qpos through MuJoCo's
  kinematics, once per moving body. Drawn, never checked.
- `world/cables/<name>`: the cable's centreline at its true radius, one
  strip per run of elements in one state, so only the elements near a
  clash's worst place take its state colour (soft, hard); the rest stays
  the clear colour.
- `world/interference/<type>/<a>/<b>`: the spot, in a colour no cable or
  part uses: a wire sphere round the worst place on cable a labelled with
  the pair and its distance, and (`.../gap`) the segment to the closest point
  on the other side (`checker.spot`); `world/mujoco_contacts`: MuJoCo's
  contact points.
- `checks/<type>/<a>/<b>/distance` (scene units): every pair below the
  clearance, and, at full checks, every pair the checker evaluated up to its
  horizon (the approach before a clash); a pair's line breaks (NaN) where it
  is not known. `checks/limits/{clearance,zero}`: reference lines.
- `cables/strain/<name>` (percent), `cables/bend_radius/<name>` (scene
  units, with `<name>_limit` lines), `cables/twist/<name>` (degrees, cables
  clamped at both ends), `validation/agreement` and, where the mjcf model's
  joints move, `joints/<name>` (each moving joint's value, degrees or scene
  units, named with its unit).
- `lanes/<type>/<a>/<b>`: the pair's state (clear / soft / hard) as state
  changes, one lane per pair.
- `events`: one text entry at the start and one at the end of each event,
  level by severity; `clashes`: the clash list, one row per event at its
  worst time (type, pair, severity, phase, start, end, worst distance and
  time, joint values where given), so selecting a row's time jumps there;
  `summary`: a text document at t = 0.
- `wear_map/<cable>` and `wear/<cable>/<measure>`: the wear map
  (`checker.wear`) as a colour along the cable's rest shape and a profile
  per measure over the arc-length bins.

Cost: per frame the recorder only copies arrays into buffers; everything is
sent in columns (`send_columns`, one call per entity for the whole run)
when the recorder is closed, so recording costs a fraction of a step. The
blueprint (views, a saved viewpoint per clash, opening on the worst, and
the whole scene framed; plot ranges) is written then too, when the run's
extent is known. The
recording id is new for every run (the scene name is the application id
and the recording name), the `log_time` timeline is not written, and the
recording's properties hold the units, clearance, scene file and product
version. The `.rrd` is written to a temporary file beside the target and
moved into place when the recorder is closed, so an interrupted run still
leaves a complete, readable recording and never a half-written one.

This module does not decide what is interference or wear; it shows what it
is given.
"""

from __future__ import annotations

import os
import uuid
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from checker.shapes import Shape
from checker import spot
from sim.build import Built, PartModel

CLEAR = (70, 160, 255)
SOFT = (255, 190, 40)
HARD = (230, 40, 40)
STATE_COLOURS = {"clear": CLEAR, "soft": SOFT, "hard": HARD}
STATES = ("clear", "soft", "hard")
SPOT = (255, 0, 230)
"""The spot's colour: used by no cable state, part or contact."""
PART_COLOUR = (160, 160, 170)
PART_DIMMED = (160, 160, 170, 70)
KEEPOUT_COLOUR = (255, 140, 0, 90)
CONTACT_COLOUR = (40, 220, 120)
CLASH_COLUMNS = ("type", "pair", "severity", "phase", "start_s", "end_s", "worst_distance", "worst_time_s",
                 "units", "joints")
"""The clash list's columns, in order."""
VIEWPOINTS = 6
"""Clashes (worst first) that get a saved viewpoint of their own."""
_VIRIDIS = np.array([(68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37)], float)
_UNWORN = (200, 200, 200)


def part_path(name: str) -> str:
    """Entity path of a part: its assembly levels become tree levels."""
    return "world/parts/" + "/".join(_escape(p) for p in name.split("/"))


def visual_paths(body: str, name: str) -> tuple[str, str]:
    """Entity paths of a visual geom of the mjcf model: its body's and its own
    (`name` is `<body>/<geom>`)."""
    body_path = "world/visual/" + _escape(body)
    rest = name[len(body) + 1:] if name.startswith(body + "/") else name
    return body_path, body_path + "/" + "/".join(_escape(p) for p in rest.split("/"))


def _escape(level: str) -> str:
    # rerun separates entity path levels with "/" and treats a few characters specially.
    return "".join(c if (c.isalnum() or c in "-_.") else "_" for c in level) or "_"


def plane_half_sizes(size: np.ndarray, pose: np.ndarray, scene_points: np.ndarray) -> np.ndarray:
    """(2,) half-sizes (metres) of the rectangle that draws a plane part.

    The plane is infinite; MuJoCo's size (x, y half-sizes) says how much to
    draw. Where it is 0, the rectangle covers `scene_points` (n, 3) seen
    along the plane's normal, plus a fifth on each side, and is at least a
    tenth as wide as it is long; 1 m with nothing to cover."""
    size = np.asarray(size, float)
    if len(size) >= 2 and size[0] > 0 and size[1] > 0:
        return size[:2].copy()
    if not len(scene_points):
        return np.ones(2)
    local = (np.asarray(scene_points, float) - pose[:3, 3]) @ pose[:3, :3]
    half = 1.2 * np.abs(local[:, :2]).max(axis=0)
    return np.maximum(half, 0.1 * half.max()) if half.max() > 0 else np.ones(2)


def pair_path(kind: str, a: str, b: str) -> str:
    """Entity path of a checked pair."""
    return f"{kind}/{_escape(a)}/{_escape(b)}"


def _pair_text(a: str, b: str) -> str:
    return a if a == b else f"{a} / {b}"


@dataclass(frozen=True)
class Mark:
    """One clash shown at a frame: the pair and where.

    Attributes:
      kind, a, b: the pair (type value, names).
      distance: signed distance, metres.
      state: "soft" or "hard".
      where: (3,) worst place on cable a, metres.
      s: arc length there on cable a, metres.
      s_b: arc length on cable b (self, cable-cable) or None.
    """

    kind: str
    a: str
    b: str
    distance: float
    state: str
    where: np.ndarray
    s: float
    s_b: float | None


@dataclass(frozen=True)
class Settings:
    """What the recording's properties and summary say about the run.

    Attributes:
      units: the scene's units ("m" or "mm").
      clearance: metres.
      scene_file: the scene file's path.
      version: the product version.
    """

    units: str
    clearance: float
    scene_file: str
    version: str


class _Series:
    """A scalar series buffered by frame; a NaN breaks its line."""

    def __init__(self):
        self.frames: list[int] = []
        self.values: list[float] = []

    def add(self, frame: int, value: float) -> None:
        if self.frames and self.frames[-1] == frame:
            self.values[-1] = min(self.values[-1], value)
            return
        self.frames.append(frame)
        self.values.append(value)

    def gap(self, frame: int) -> None:
        """Not known from this frame on: the line stops here."""
        if self.frames and self.frames[-1] < frame and not np.isnan(self.values[-1]):
            self.frames.append(frame)
            self.values.append(np.nan)


class Recorder:
    """Writes one run's recording to `path` (see the module docstring).

    Args:
      built: the built scene.
      path: the .rrd to write.
      shapes: the checker's shape of every built part (for the other side of a spot).
      settings: units, clearance, scene file and version (properties and summary).
    """

    def __init__(self, built: Built, path: Path, shapes: list[Shape] | None = None,
                 settings: Settings | None = None):
        scene = built.scene
        self.built = built
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.tmp")
        self.unit = scene.scale  # metres per scene unit
        self.settings = settings or Settings(scene.units, scene.check.clearance, str(scene.path), "unknown")
        self.shapes = shapes
        self.rec = rr.RecordingStream(application_id=scene.name, recording_id=uuid.uuid4())
        self.rec.set_log_time_enabled(False)
        self.rec.set_log_tick_enabled(False)
        self.rec.save(str(self.tmp))
        self.rec.send_recording_name(scene.name)
        s = self.settings
        self.rec.send_property("cablecheck", rr.AnyValues(
            units=s.units, clearance=s.clearance / self.unit, scene_file=s.scene_file, version=s.version))
        body_of_part = [p.body for p in built.parts]
        moving = {name for name in built.body_ids if name != "world"}
        self.moving_parts = np.array([b in moving for b in body_of_part], bool)
        m = built.model
        visuals = getattr(built, "visuals", ())
        vis_body = np.array([int(m.geom_bodyid[v.geom_id]) for v in visuals], int)
        self._vis_bodies = np.unique(vis_body)
        self._vis_body_paths = {}
        for v, b in zip(visuals, vis_body):
            self._vis_body_paths[int(b)] = visual_paths(v.body, v.name)[0]
        self.moving_visual_bodies = self._vis_bodies[m.body_weldid[self._vis_bodies] != 0]
        self._kin = mujoco.MjData(m) if len(self._vis_bodies) else None
        self._vis_poses: list[np.ndarray] = []
        self._closed = False
        self._labels: dict[str, str] = {}
        self._series: dict[str, _Series] = {}
        self._times: list[float] = []
        self._cables: list[list[np.ndarray]] = [[] for _ in built.cables]
        self._colours: list[list[np.ndarray]] = [[] for _ in built.cables]
        self._poses: list[np.ndarray] = []
        self._contacts: list[np.ndarray | None] = []
        self._marks: dict[str, list[tuple[int, np.ndarray, np.ndarray, str, str]]] = {}
        # part index -> (rows of _marks, row, where (world, m), part pose): closest points still to find
        self._part_spots: dict[int, list[tuple]] = {}
        self._lane: dict[str, str] = {}
        self._near_paths: set[str] = set()
        self._alive: set[str] = set()
        self._dimmed = False
        self._dim_changes: list[tuple[int, bool]] = []
        self._rest: list[np.ndarray] | None = None
        self._poses0: np.ndarray | None = None
        self._bounds: tuple[np.ndarray, np.ndarray] | None = None
        self._events: list = []
        self._event_joints: list[dict] = []
        self._wear: list = []
        self._summary = ""
        self._cable_index = {c.name: i for i, c in enumerate(built.cables)}
        self._part_index = {p.name: k for k, p in enumerate(built.parts)}
        self._element_s = [0.5 * (c.rest_s[1:] + c.rest_s[:-1]) for c in built.cables]
        self._near = [max(2.0 * c.element_length, 3.0 * c.radius) for c in built.cables]

    # -- static content ---------------------------------------------------
    def log_static(self, part_poses: np.ndarray, cables: list[np.ndarray] | None = None,
                   qpos: np.ndarray | None = None) -> None:
        """Parts' and visual geoms' shapes (and poses of those that never
        move), once; `cables` (the rest state's body centres, metres) size the
        floor and frame the camera; `qpos` (the simulation's, at t = 0) poses
        the visual geoms."""
        rec = self.rec
        self._rest = [np.asarray(c, float) for c in cables] if cables is not None else None
        self._poses0 = np.asarray(part_poses, float)
        self._bounds = self._scene_bounds(part_poses)
        rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        rec.set_time("sim_time", duration=0.0)
        for k, part in enumerate(self.built.parts):
            path = part_path(part.name)
            rec.log(path, self._shape(part, part_poses[k]), static=True)
            if not self.moving_parts[k]:
                rec.log(path, self._transform(part_poses[k]), static=True)
            # colours on the timeline (static data would shadow the dimming)
            rec.log(path, self._colour(part, KEEPOUT_COLOUR if part.keepout else PART_COLOUR))
        self._log_visuals(qpos)
        for i, cable in enumerate(self.built.cables):
            rec.log(f"world/cables/{_escape(cable.name)}",
                    rr.LineStrips3D.from_fields(radii=[cable.radius / self.unit]), static=True)
        rec.log("world/mujoco_contacts", rr.Points3D.from_fields(radii=[-3.0], colors=[CONTACT_COLOUR]),
                static=True)

    def _log_visuals(self, qpos: np.ndarray | None) -> None:
        """The mjcf model's visual geoms: shapes static in their body's frame,
        colours on the timeline (dimmed with the parts), fixed bodies' poses."""
        if self._kin is None:
            return
        rec, m = self.rec, self.built.model
        for vis in self.built.visuals:
            g = vis.geom_id
            local = np.eye(4)
            mat = np.zeros(9)
            mujoco.mju_quat2Mat(mat, m.geom_quat[g])
            local[:3, :3], local[:3, 3] = mat.reshape(3, 3), m.geom_pos[g]
            path = visual_paths(vis.body, vis.name)[1]
            rec.log(path, self._shape(vis, np.eye(4)), static=True)
            rec.log(path, self._transform(local), static=True)
            rec.log(path, self._colour(vis, self._visual_colour(g)))
        poses = self._body_poses(self.built.qpos0 if qpos is None else qpos, self._vis_bodies)
        for b, pose in zip(self._vis_bodies, poses):
            if m.body_weldid[b] == 0:
                rec.log(self._vis_body_paths[int(b)], self._transform(pose), static=True)

    def _body_poses(self, qpos: np.ndarray, bodies: np.ndarray) -> np.ndarray:
        """(B, 4, 4) scene-world poses of `bodies` at `qpos` (MuJoCo's kinematics)."""
        m, d = self.built.model, self._kin
        d.qpos[:] = qpos
        mujoco.mj_kinematics(m, d)
        poses = np.zeros((len(bodies), 4, 4))
        poses[:, :3, :3] = d.xmat[bodies].reshape(-1, 3, 3)
        poses[:, :3, 3] = d.xpos[bodies] + self.built.origin
        poses[:, 3, 3] = 1.0
        return poses

    def _visual_colour(self, g: int) -> tuple[int, ...]:
        """The geom's colour as MuJoCo draws it: its material's, else its own rgba."""
        m = self.built.model
        mat = int(m.geom_matid[g])
        rgba = m.mat_rgba[mat] if mat >= 0 else m.geom_rgba[g]
        return tuple(int(round(255 * float(c))) for c in np.clip(rgba, 0.0, 1.0))

    def _scene_bounds(self, part_poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) of the scene's points (:meth:`_scene_points`), metres."""
        pts = self._scene_points(part_poses)
        if not len(pts):
            return np.full(3, -0.5), np.full(3, 0.5)
        return pts.min(axis=0), pts.max(axis=0)

    def _scene_points(self, part_poses: np.ndarray) -> np.ndarray:
        """(n, 3) points that span the scene at t = 0 (metres): the cables
        (at rest when given, else as routed) and the corners of the other
        parts' boxes."""
        pts = list(self._rest) if self._rest is not None else [c.routed for c in self.built.cables]
        for part, pose in zip(self.built.parts, part_poses):
            if part.shape == "plane":
                continue
            if part.shape == "mesh":
                corners = part.vertices
            else:
                r = part.size[0]
                half = {"sphere": [r, r, r], "capsule": [r, r, part.size[1] + r],
                        "cylinder": [r, r, part.size[1]]}.get(part.shape, part.size[:3])
                corners = np.array(np.meshgrid(*[[-h, h] for h in half], indexing="ij")).reshape(3, -1).T
            pts.append(corners @ pose[:3, :3].T + pose[:3, 3])
        return np.concatenate(pts) if pts else np.zeros((0, 3))

    def _shape(self, part: PartModel, pose: np.ndarray):
        u = self.unit
        size = np.asarray(part.size, float) / u
        if part.shape == "box":
            return rr.Boxes3D(half_sizes=[size], fill_mode="solid")
        if part.shape == "sphere":
            return rr.Ellipsoids3D(half_sizes=[[size[0]] * 3], fill_mode="solid")
        if part.shape == "ellipsoid":
            return rr.Ellipsoids3D(half_sizes=[size], fill_mode="solid")
        if part.shape == "capsule":
            return rr.Capsules3D(lengths=[2 * size[1]], radii=[size[0]],
                                 translations=[[0, 0, -size[1]]], fill_mode="solid")
        if part.shape == "cylinder":
            return rr.Cylinders3D(lengths=[2 * size[1]], radii=[size[0]], fill_mode="solid")
        if part.shape == "plane":
            return self._floor(part, pose)
        return rr.Mesh3D(vertex_positions=part.vertices / u, triangle_indices=part.faces)

    @staticmethod
    def _colour(part: PartModel, colour):
        """A part's colour alone, as an update of its shape."""
        kind = {"box": rr.Boxes3D, "plane": rr.Boxes3D, "sphere": rr.Ellipsoids3D,
                "ellipsoid": rr.Ellipsoids3D, "capsule": rr.Capsules3D, "cylinder": rr.Cylinders3D}.get(part.shape)
        return kind.from_fields(colors=[colour]) if kind is not None else rr.Mesh3D.from_fields(albedo_factor=colour)

    def _floor(self, part: PartModel, pose: np.ndarray) -> rr.Boxes3D:
        """A plane as a filled rectangle: its size, else sized to the scene (:func:`plane_half_sizes`)."""
        half = plane_half_sizes(part.size, pose, self._scene_points(self._poses0)) / self.unit
        return rr.Boxes3D(half_sizes=[[half[0], half[1], 0.0]], fill_mode="solid")

    def _dim(self, on: bool) -> None:
        """Parts translucent (while a clash is shown) or opaque again, at the current time."""
        if on == self._dimmed:
            return
        self._dimmed = on
        # kept as (frame, on) and sent in columns when closed: one chunk per
        # part for the whole run, not one per part at every change
        self._dim_changes.append((len(self._times) - 1, on))

    def _send_dim(self, index) -> None:
        """Every part's (and visual geom's) colour at each change of :meth:`_dim`, one column per entity."""
        if not self._dim_changes:
            return
        frames = [f for f, _ in self._dim_changes]
        on = np.array([o for _, o in self._dim_changes], bool)
        dimmed, plain = np.array(PART_DIMMED, np.uint8), np.array((*PART_COLOUR, 255), np.uint8)
        parts_rgba = np.where(on[:, None], dimmed[None], plain[None])
        for part in self.built.parts:
            if part.keepout or part.shape == "plane":
                continue
            self.rec.send_columns(part_path(part.name), indexes=index(frames),
                                  columns=self._colour_columns(part, parts_rgba))
        for vis in getattr(self.built, "visuals", ()):
            colour = np.array(self._visual_colour(vis.geom_id), np.uint8)
            faded = np.array([*colour[:3], min(colour[3], PART_DIMMED[3])], np.uint8)
            rgba = np.where(on[:, None], faded[None], colour[None])
            self.rec.send_columns(visual_paths(vis.body, vis.name)[1], indexes=index(frames),
                                  columns=self._colour_columns(vis, rgba))

    @staticmethod
    def _colour_columns(part, colours: np.ndarray):
        """:meth:`_colour` as columns, one colour (T, 4) per row."""
        kind = {"box": rr.Boxes3D, "plane": rr.Boxes3D, "sphere": rr.Ellipsoids3D,
                "ellipsoid": rr.Ellipsoids3D, "capsule": rr.Capsules3D, "cylinder": rr.Cylinders3D}.get(part.shape)
        return kind.columns(colors=colours) if kind is not None else rr.Mesh3D.columns(albedo_factor=colours)

    def _transform(self, pose: np.ndarray) -> rr.Transform3D:
        return rr.Transform3D(translation=pose[:3, 3] / self.unit, mat3x3=pose[:3, :3])

    # -- per frame --------------------------------------------------------
    def log_step(self, t: float, cables: list[np.ndarray], part_poses: np.ndarray,
                 marks: list[Mark], strain: np.ndarray, bend: np.ndarray,
                 near: dict[tuple[str, str, str], float] | None = None,
                 qpos: np.ndarray | None = None) -> None:
        """One frame: moving parts' poses, cables (coloured near the clashes),
        the clashes' spots, per-cable series and pair distances. `near`: the
        pairs a full check since the last frame evaluated up to its horizon,
        (type, a, b) -> distance in metres (a pair's distance line runs while
        it is below the clearance or in the last full check's list, and breaks
        when it leaves both). Starts the frame the other `log_*` calls of
        this time add to."""
        u = self.unit
        frame = len(self._times)
        self._times.append(float(t))
        self.rec.set_time("sim_time", duration=t)
        self._poses.append(np.asarray(part_poses)[self.moving_parts])
        if len(self.moving_visual_bodies):
            self._vis_poses.append(self._body_poses(self.built.qpos0 if qpos is None else qpos,
                                                    self.moving_visual_bodies))
        self._contacts.append(None)
        rank = {s: n for n, s in enumerate(STATES)}
        colour = [np.zeros(len(c.rest_s) - 1, np.uint8) for c in self.built.cables]
        for m in marks:
            self._colour_near(colour, m.a, m.s, rank[m.state], whole=(m.kind == "taut"))
            if m.s_b is not None and m.b in self._cable_index:
                self._colour_near(colour, m.b, m.s_b, rank[m.state], whole=False)
        for i, (cable, pts) in enumerate(zip(self.built.cables, cables)):
            self._cables[i].append(np.asarray(pts, float) / u)
            self._colours[i].append(colour[i])
            name = _escape(cable.name)
            self.log_scalar(f"cables/strain/{name}", 100.0 * float(strain[i]), label=f"{cable.name} strain (%)")
            if np.isfinite(bend[i]):
                self.log_scalar(f"cables/bend_radius/{name}", float(bend[i] / u),
                                label=f"{cable.name} min bend radius ({self.settings.units})")
        self._log_marks(frame, marks, cables, part_poses)
        if near is not None:
            self._near_paths = set()
            for (kind, a, b), d in near.items():
                path = f"checks/{pair_path(kind, a, b)}/distance"
                self._near_paths.add(path)
                self.log_scalar(path, d / u, label=f"{kind}: {_pair_text(a, b)}")
        known = self._near_paths | {f"checks/{pair_path(m.kind, m.a, m.b)}/distance" for m in marks}
        for path in self._alive - known:
            self._series[path].gap(frame)
        self._alive = known

    def _colour_near(self, colour, cable: str, s: float, state: int, whole: bool) -> None:
        i = self._cable_index.get(cable)
        if i is None:
            return
        near = np.ones(len(colour[i]), bool) if whole else np.abs(self._element_s[i] - s) <= self._near[i]
        colour[i][near] = np.maximum(colour[i][near], state)

    def _log_marks(self, frame: int, marks: list[Mark], cables: list[np.ndarray], poses: np.ndarray) -> None:
        u, units = self.unit, self.settings.units
        now = set()
        for m in marks:
            path = pair_path(m.kind, m.a, m.b)
            now.add(path)
            other = self._other_side(m, cables, poses)
            label = f"{_pair_text(m.a, m.b)}: {m.distance / u:.3g} {units}"
            rows = self._marks.setdefault(path, [])
            if isinstance(other, int):     # a part: its closest point found with the others at the end
                self._part_spots.setdefault(other, []).append((rows, len(rows), np.asarray(m.where, float),
                                                               np.asarray(poses[other], float)))
                other = None
            rows.append((frame, np.asarray(m.where, float) / u, None if other is None else other / u, label, m.a))
            self.log_scalar(f"checks/{path}/distance", m.distance / u, label=f"{m.kind}: {_pair_text(m.a, m.b)}")
            if path not in self._lane:
                self.rec.log(f"lanes/{path}", rr.StateConfiguration(
                    values=list(STATES), colors=[STATE_COLOURS[x] for x in STATES]), static=True)
            if self._lane.get(path) != m.state:
                self._lane[path] = m.state
                self.rec.log(f"lanes/{path}", rr.StateChange(state=m.state))
        for path in [p for p, s in self._lane.items() if p not in now and s != "clear"]:
            self._lane[path] = "clear"
            self.rec.log(f"lanes/{path}", rr.StateChange(state="clear"))
        self._dim(bool(now))

    def _other_side(self, m: Mark, cables: list[np.ndarray], poses: np.ndarray) -> np.ndarray | int | None:
        """Closest point on the other side of a clash, metres; for a part,
        its index (the point is found for all of a part's marks at once, by
        :meth:`_resolve_part_spots`); None (bend, taut, part-part)."""
        if m.kind in ("self", "cable-cable") and m.s_b is not None and m.b in self._cable_index:
            return spot.on_cable(cables[self._cable_index[m.b]], m.s_b, m.where)
        if m.kind in ("cable-structure", "keepout") and self.shapes is not None:
            k = self._part_index.get(m.b)
            if k is not None:
                return int(k)
        return None

    def _resolve_part_spots(self) -> None:
        """The other side of every part mark: one query per part for the whole run."""
        u = self.unit
        for k, spots in self._part_spots.items():
            found = spot.on_part_many(self.shapes[k], np.stack([s[3] for s in spots]),
                                      np.stack([s[2] for s in spots])) / u
            for (rows, i, _, _), other in zip(spots, found):
                frame, where, _, label, a = rows[i]
                rows[i] = (frame, where, other, label, a)
        self._part_spots = {}

    def log_twist(self, twist_deg: np.ndarray) -> None:
        """Each cable's twist (degrees) at the current frame; NaN: not measured."""
        for cable, value in zip(self.built.cables, twist_deg):
            if np.isfinite(value):
                self.log_scalar(f"cables/twist/{_escape(cable.name)}", float(value),
                                label=f"{cable.name} twist (deg)")

    def log_joints(self, names: list[str], units: list[str], values: np.ndarray) -> None:
        """The moving joints' values at the current frame, one series each."""
        for name, unit, value in zip(names, units, values):
            self.log_scalar(f"joints/{_escape(name)}", value, label=f"{name} ({unit})")

    def log_contacts(self, points: np.ndarray) -> None:
        """MuJoCo's contact points at this frame."""
        self._contacts[-1] = np.asarray(points, float).reshape(-1, 3) / self.unit

    def log_scalar(self, path: str, value: float, label: str | None = None) -> None:
        """A time series value at the current frame; `label` names the series
        in plot legends (the first one given)."""
        if label is not None and path not in self._labels:
            self._labels[path] = label
        frame = max(len(self._times) - 1, 0)
        self._series.setdefault(path, _Series()).add(frame, float(value))

    def log_event(self, t: float, text: str, level: str) -> None:
        """An event as a text log entry at time t."""
        self.rec.set_time("sim_time", duration=t)
        self.rec.log("events", rr.TextLog(text, level=level))

    # -- at the end -------------------------------------------------------
    def finish(self, events: list, wear: list, summary: str, joints: list[dict] | None = None) -> None:
        """The run's events (clash list and viewpoints), wear map
        (:class:`checker.wear.CableWear` per cable), summary text and, where
        the mjcf model's joints move, each event's joint values at its worst
        time (name -> value, in the events' order)."""
        self._events = list(events)
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
            self.rec.flush()
            self.rec.disconnect()
            os.replace(self.tmp, self.path)

    def _send(self) -> None:
        rec, u = self.rec, self.unit
        times = np.asarray(self._times, float)
        index = lambda frames: [rr.TimeColumn("sim_time", duration=times[np.asarray(frames, int)])]
        n_f = len(times)
        if n_f:
            state_rgb = np.array([STATE_COLOURS[s] for s in STATES], np.uint8)
            for i, cable in enumerate(self.built.cables):
                strips, colours, counts = _runs(self._cables[i], self._colours[i])
                rec.send_columns(f"world/cables/{_escape(cable.name)}", indexes=index(range(n_f)),
                                 columns=rr.LineStrips3D.columns(strips=strips, colors=state_rgb[colours])
                                 .partition(counts))
            moving = np.flatnonzero(self.moving_parts)
            if len(moving):
                poses = np.stack(self._poses)                                     # (F, M, 4, 4)
                for j, k in enumerate(moving):
                    rec.send_columns(part_path(self.built.parts[k].name), indexes=index(range(n_f)),
                                     columns=rr.Transform3D.columns(translation=poses[:, j, :3, 3] / u,
                                                                    mat3x3=poses[:, j, :3, :3]))
            if self._vis_poses:
                poses = np.stack(self._vis_poses)                                 # (F, B, 4, 4)
                for j, b in enumerate(self.moving_visual_bodies):
                    rec.send_columns(self._vis_body_paths[int(b)], indexes=index(range(n_f)),
                                     columns=rr.Transform3D.columns(translation=poses[:, j, :3, 3] / u,
                                                                    mat3x3=poses[:, j, :3, :3]))
            self._send_contacts(index)
            self._resolve_part_spots()
            self._send_dim(index)
            self._send_marks(index, n_f)
            for path, series in self._series.items():
                if path in self._labels:
                    rec.log(path, rr.SeriesLines(names=[self._labels[path]]), static=True)
                rec.send_columns(path, indexes=index(series.frames),
                                 columns=rr.Scalars.columns(scalars=np.asarray(series.values)))
            self._limit_lines(times)
        self._send_events()
        self._send_wear()
        rec.set_time("sim_time", duration=0.0)
        rec.log("summary", rr.TextDocument(self._summary, media_type="text/markdown"))
        rec.send_blueprint(self._blueprint(), make_active=True, make_default=True)

    def _send_contacts(self, index) -> None:
        found = [(f, c) for f, c in enumerate(self._contacts) if c is not None]
        if not found:
            return
        frames = [f for f, _ in found]
        pts = np.concatenate([c for _, c in found])
        self.rec.send_columns("world/mujoco_contacts", indexes=index(frames),
                              columns=rr.Points3D.columns(positions=pts).partition([len(c) for _, c in found]))

    def _send_marks(self, index, n_f: int) -> None:
        """Per pair: its spot at the frames it is shown, emptied at the frame after each run of them."""
        u = self.unit
        for path, rows in self._marks.items():
            frames, centres, labels, segs, seg_frames = [], [], [], [], []
            last = -2
            for frame, where, other, label, a in rows:
                if frame > last + 1 and last >= 0 and last + 1 < n_f:
                    frames.append(last + 1)
                    centres.append(None)
                    labels.append(None)
                frames.append(frame)
                centres.append(where)
                labels.append(label)
                segs.append(None if other is None else np.stack([where, other]))
                seg_frames.append(frame)
                last = frame
            if last + 1 < n_f:
                frames.append(last + 1)
                centres.append(None)
                labels.append(None)
            cable = self.built.cables[self._cable_index[rows[0][4]]] if rows[0][4] in self._cable_index else None
            # a wire sphere round the cable at the spot (the cable, the gap and the part
            # stay visible inside it), standing out of it, at least 1 % of the scene across
            lo, hi = self._bounds if self._bounds is not None else (np.zeros(3), np.ones(3))
            radius = max(2.5 * (cable.radius if cable else 0.0) + 0.5 * self.settings.clearance,
                         0.01 * float(np.linalg.norm(hi - lo))) / u
            lengths = [0 if c is None else 1 for c in centres]
            pts = np.array([c for c in centres if c is not None]).reshape(-1, 3)
            text = [x for x in labels if x is not None]
            self.rec.log(f"world/interference/{path}",
                         rr.Ellipsoids3D.from_fields(colors=[SPOT], line_radii=[-2.5],
                                                     fill_mode="MajorWireframe", show_labels=True), static=True)
            # the sizes go with the centres: an empty row has no sphere at all (a size
            # without a centre would draw one at the origin)
            self.rec.send_columns(f"world/interference/{path}", indexes=index(frames),
                                  columns=[*rr.Ellipsoids3D.columns(centers=pts, half_sizes=np.full((len(pts), 3), radius))
                                           .partition(lengths),
                                           *rr.Ellipsoids3D.columns(labels=text).partition(lengths)])
            # the segment to the other side, emptied with the marker
            seg_lengths, seg_rows = [], []
            seg_at = dict(zip(seg_frames, segs))
            for f, c in zip(frames, centres):
                seg = seg_at.get(f) if c is not None else None
                seg_lengths.append(0 if seg is None else 1)
                if seg is not None:
                    seg_rows.append(seg)
            if seg_rows:
                self.rec.log(f"world/interference/{path}/gap",
                             rr.LineStrips3D.from_fields(radii=[0.35 * radius], colors=[SPOT]), static=True)
                self.rec.send_columns(f"world/interference/{path}/gap", indexes=index(frames),
                                      columns=rr.LineStrips3D.columns(strips=np.stack(seg_rows))
                                      .partition(seg_lengths))

    def _limit_lines(self, times: np.ndarray) -> None:
        """Clearance and zero lines on the distance plot, bend-radius limits on the bend plot."""
        u, units = self.unit, self.settings.units
        ends = [rr.TimeColumn("sim_time", duration=[times[0], times[-1]])]
        lines = [("checks/limits/clearance", self.settings.clearance / u, f"clearance ({units})", (120, 120, 120)),
                 ("checks/limits/zero", 0.0, "touching", (60, 60, 60))]
        for cable in self.built.cables:
            if cable.min_bend_radius is not None:
                lines.append((f"cables/bend_radius/{_escape(cable.name)}_limit", cable.min_bend_radius / u,
                              f"{cable.name} bend limit ({units})", HARD))
        for path, value, name, colour in lines:
            self.rec.log(path, rr.SeriesLines(names=[name], colors=[colour], widths=[1.0]), static=True)
            self.rec.send_columns(path, indexes=ends, columns=rr.Scalars.columns(scalars=[value, value]))

    def _send_events(self) -> None:
        """The clash list: one row per event, at its worst time."""
        u, units = self.unit, self.settings.units
        for ev, joints in zip(self._events, self._event_joints):
            self.rec.set_time("sim_time", duration=ev.t_worst)
            self.rec.log("clashes", rr.AnyValues(
                type=ev.type, pair=_pair_text(ev.a, ev.b), severity=ev.severity, phase=ev.phase,
                start_s=float(ev.t_start), end_s=float(ev.t_end),
                worst_distance=float(ev.min_distance / u), worst_time_s=float(ev.t_worst), units=units,
                joints=", ".join(f"{k} {v:.4g}" for k, v in joints.items()) or "-"))

    def _send_wear(self) -> None:
        """The wear map: colour along each cable's rest shape, and a profile per measure."""
        u = self.unit
        for i, w in enumerate(self._wear):
            name = _escape(w.name)
            edges = np.append(w.s, w.length) / u
            for measure, values in (("contact_time", w.contact_time), ("sliding", w.sliding / u),
                                    ("bend_cycles", w.bend_cycles)):
                self.rec.log(f"wear/{name}/{measure}", rr.BarChart(np.asarray(values, float), abscissa=edges[:-1],
                                                                   widths=np.diff(edges)), static=True)
            rest = self._rest[i] if self._rest is not None else self.built.cables[i].routed
            pts = np.asarray(rest, float) / u
            strips = np.stack([pts[:-1], pts[1:]], axis=1)
            self.rec.log(f"wear_map/{name}", rr.LineStrips3D(
                strips, radii=[self.built.cables[i].radius / u], colors=wear_colours(w.sliding, w.contact_time)),
                static=True)

    # -- layout -----------------------------------------------------------
    def _eye(self, target: np.ndarray, distance: float) -> rrb.EyeControls3D:
        lo, hi = self._bounds if self._bounds is not None else (np.zeros(3), np.ones(3))
        centre = 0.5 * (lo + hi)
        away = target - centre
        away[2] = 0.0
        n = float(np.linalg.norm(away))
        side = away / n if n > 1e-9 * max(distance, 1e-12) else np.array([0.6, -0.8, 0.0])
        direction = side + np.array([0.0, 0.0, 0.6]) + np.array([0.3, -0.5, 0.0])
        direction /= np.linalg.norm(direction)
        u = self.unit
        return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(target + distance * direction) / u,
                                 look_target=target / u, eye_up=[0.0, 0.0, 1.0])

    def _scene_eye(self) -> rrb.EyeControls3D:
        lo, hi = self._bounds if self._bounds is not None else (np.zeros(3), np.ones(3))
        centre = 0.5 * (lo + hi)
        diag = float(np.linalg.norm(hi - lo)) or 1.0
        direction = np.array([0.55, -0.75, 0.45])
        direction /= np.linalg.norm(direction)
        u = self.unit
        return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(centre + 0.85 * diag * direction) / u,
                                 look_target=centre / u, eye_up=[0.0, 0.0, 1.0])

    def _blueprint(self) -> rrb.Blueprint:
        units = self.settings.units
        u = self.unit
        hide = ["- /world/wear_map/**"]
        scene = rrb.Spatial3DView(name="Scene", origin="world", eye_controls=self._scene_eye(),
                                  contents=["$origin/**", *hide])
        tabs = [scene]
        worst = sorted(self._events, key=lambda e: (e.severity != "hard", e.min_distance))[:VIEWPOINTS]
        for n, ev in enumerate(worst, 1):
            cable = self.built.cables[self._cable_index[ev.a]] if ev.a in self._cable_index else None
            reach = 12.0 * ((cable.radius if cable else 0.01) + self.settings.clearance)
            lo, hi = self._bounds if self._bounds is not None else (np.zeros(3), np.ones(3))
            reach = max(reach, 0.25 * float(np.linalg.norm(hi - lo)))
            tabs.append(rrb.Spatial3DView(
                name=f"#{n} {ev.severity} {_pair_text(ev.a, ev.b)} @ {ev.t_worst:.3f} s", origin="world",
                eye_controls=self._eye(np.asarray(ev.where, float), reach), contents=["$origin/**", *hide]))
        if self._wear:
            tabs.append(rrb.Spatial3DView(name="Wear map (sliding; grey: no contact)", origin="wear_map"))
        clear = self.settings.clearance / u
        lows = [s.values for p, s in self._series.items() if p.startswith("checks/") and s.values]
        low = min([float(np.nanmin(v)) for v in lows if np.isfinite(v).any()] + [0.0])
        dist_range = (min(low * 1.1, -0.1 * clear), 4.0 * clear)
        plots = [
            rrb.TimeSeriesView(name=f"Pair distances ({units})", origin="checks",
                               axis_y=rrb.ScalarAxis(range=dist_range, zoom_lock=False),
                               plot_legend=rrb.PlotLegend(corner="LeftTop", visible=True)),
            rrb.TimeSeriesView(name=f"Min bend radius ({units})", origin="cables/bend_radius",
                               axis_y=self._bend_axis()),
            rrb.TimeSeriesView(name="Strain (%)", origin="cables/strain"),
            *([rrb.TimeSeriesView(name="Twist (deg)", origin="cables/twist")]
              if any(p.startswith("cables/twist/") for p in self._series) else []),
            rrb.TimeSeriesView(name="Agreement with MuJoCo (fraction of pairs)", origin="validation",
                               axis_y=rrb.ScalarAxis(range=(0.0, 1.05))),
            *self._extra_plots(),
            *[rrb.BarChartView(name=f"Wear {w.name}: {m} per bin ({unit})", origin=f"wear/{_escape(w.name)}/{m}")
              for w in self._wear
              for m, unit in (("contact_time", "s"), ("sliding", units), ("bend_cycles", "cycles"))],
        ]
        lists = rrb.Tabs(
            rrb.DataframeView(name="Clash list (select a row's time to jump)", origin="clashes",
                              query=rrb.archetypes.DataframeQuery(
                                  timeline="sim_time",
                                  select=["sim_time", *[f"/clashes:{c}" for c in CLASH_COLUMNS]])),
            rrb.TextLogView(name="Events", origin="events"),
            rrb.TextDocumentView(name="Summary", origin="summary"),
        )
        return rrb.Blueprint(
            rrb.Horizontal(
                rrb.Vertical(rrb.Tabs(*tabs, active_tab=1 if worst else 0),   # opens on the worst clash
                             rrb.StateTimelineView(name="Pair states (clear / soft / hard)", origin="lanes"),
                             row_shares=[5, 1]),
                rrb.Vertical(rrb.Tabs(*plots), lists, row_shares=[3, 2]),
                column_shares=[3, 2],
            ),
            rrb.BlueprintPanel(state="collapsed"),
            rrb.SelectionPanel(state="collapsed"),
            rrb.TimePanel(state="collapsed", timeline="sim_time"),
        )

    def _bend_axis(self) -> rrb.ScalarAxis | None:
        limits = [c.min_bend_radius for c in self.built.cables if c.min_bend_radius is not None]
        if not limits:
            return None
        return rrb.ScalarAxis(range=(0.0, 5.0 * max(limits) / self.unit))

    def _extra_plots(self) -> list:
        """A plot for every other series root (e.g. joint values logged by the run)."""
        known = {"checks", "cables", "validation"}
        roots = sorted({p.split("/")[0] for p in self._series} - known)
        titles = {"joints": "Joint values (deg, or scene units for slides)"}
        return [rrb.TimeSeriesView(name=titles.get(root, root), origin=root) for root in roots]


def _runs(points: list[np.ndarray], states: list[np.ndarray]) -> tuple[list[np.ndarray], np.ndarray, list[int]]:
    """A cable's frames as line strips, one per run of elements of one state:
    (strips, (R,) state per strip, strips per frame). A clear cable is one
    strip of its body centres; a clash adds two breaks."""
    strips, colours, counts = [], [], []
    for pts, state in zip(points, states):
        if len(state) == 0:
            counts.append(0)
            continue
        cuts = np.flatnonzero(state[1:] != state[:-1]) + 1
        starts, ends = np.r_[0, cuts], np.r_[cuts, len(state)]
        strips += [pts[a:b + 1] for a, b in zip(starts.tolist(), ends.tolist())]
        colours.append(state[starts])
        counts.append(len(starts))
    return strips, (np.concatenate(colours) if colours else np.zeros(0, np.uint8)), counts


def wear_colours(sliding: np.ndarray, contact_time: np.ndarray) -> np.ndarray:
    """(B, 3) uint8 colours of wear bins: grey where nothing touched, else
    viridis over sliding (or over contact time when nothing slid)."""
    values = np.asarray(sliding, float)
    touched = np.asarray(contact_time, float) > 0.0
    if not (values[touched] > 0).any():
        values = np.asarray(contact_time, float)
    top = float(values.max()) if values.size else 0.0
    x = np.clip(values / top, 0.0, 1.0) if top > 0 else np.zeros_like(values)
    pos = x * (len(_VIRIDIS) - 1)
    lo = np.minimum(np.floor(pos).astype(int), len(_VIRIDIS) - 2)
    f = (pos - lo)[:, None]
    rgb = (1 - f) * _VIRIDIS[lo] + f * _VIRIDIS[lo + 1]
    rgb[~touched] = _UNWORN
    return np.round(rgb).astype(np.uint8)


def summary_text(scene: str, settings: Settings, events: list, wear: list, unit: float,
                 complete: bool = True) -> str:
    """The run's summary as markdown: settings, the clashes worst first, the
    most worn place of each cable and what it touches."""
    units = settings.units
    lines = [f"# {scene}", "",
             f"- scene file: `{settings.scene_file}`", f"- units: {units}, clearance "
             f"{settings.clearance / unit:.4g} {units}", f"- cablecheck {settings.version}"
             + ("" if complete else " (run interrupted: incomplete)"), ""]
    if events:
        hard = sum(e.severity == "hard" for e in events)
        lines += [f"## {len(events)} clash(es): {hard} hard, {len(events) - hard} soft", "",
                  "| # | severity | type | pair | phase | start s | end s | worst | at s |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for n, e in enumerate(sorted(events, key=lambda e: (e.severity != "hard", e.min_distance)), 1):
            lines.append(f"| {n} | {e.severity} | {e.type} | {_pair_text(e.a, e.b)} | {e.phase} | "
                         f"{e.t_start:.3f} | {e.t_end:.3f} | {e.min_distance / unit:.4g} {units} | "
                         f"{e.t_worst:.3f} |")
    else:
        lines.append("## No interference")
    lines += ["", "## Wear (per arc-length bin of each cable)", ""]
    for w in wear:
        k = w.most_worn()
        cyc = int(np.argmax(w.bend_cycles)) if w.bend_cycles.size else None
        bend = ("" if cyc is None or w.bend_cycles[cyc] == 0 else
                f"; most bending cycles {w.bend_cycles[cyc]:g} at s = {w.s[cyc] / unit:.4g} {units}")
        if k is None:
            lines.append(f"- {w.name}: touches nothing" + bend)
        else:
            lines.append(f"- {w.name}: most worn at s = {w.s[k] / unit:.4g} {units} (of "
                         f"{w.length / unit:.4g}), touching {w.touches[k]}: in contact "
                         f"{w.contact_time[k]:.3g} s, slid {w.sliding[k] / unit:.3g} {units}" + bend)
    return "\n".join(lines) + "\n"
