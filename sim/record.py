"""The rerun recording of a run: parts, cables and checks on a `sim_time` timeline.

Entity tree (mirrors the scene, in the scene's units, z up):
- `world/parts/<assembly path>`: each part's shape, logged once as static in
  its own frame (a plane as a rectangle: its given size, else sized to cover
  the scene); its pose is static for parts on the world and logged per
  step for parts riding a moving body.
- `world/visual/<body>/<geom>`: the mjcf model's visual geoms (those MuJoCo
  never collides), in their own colours, static in their body's frame; the
  body's pose (`world/visual/<body>`) comes from the step's qpos through
  MuJoCo's kinematics, once per moving body. Drawn, never checked.
- `world/cables/<name>`: the cable's centreline as a line strip of its true
  radius, coloured by its worst state at that step (clear, soft, hard).
- `world/interference/<type>/<a>/<b>`: a marker at the worst point of each
  pair below the clearance; `world/mujoco_contacts`: MuJoCo's contact points.
- `cables/strain/<name>` (percent), `cables/bend_radius/<name>` (scene
  units), `cables/twist/<name>` (degrees, cables clamped at both ends), `checks/<type>/<a>/<b>/distance` (scene units) and
  `validation/agreement` (fraction of pairs classed alike by the checker
  and MuJoCo) and, where the mjcf model's joints move, `joints/<name>` (each
  moving joint's value, degrees or scene units, named with its unit): time
  series, one view each, since their scales differ.
- `events`: one text entry per interference event at its start time.

Geometry is logged in batches (one call per cable per step), never per point.
The `.rrd` is written to a temporary file beside the target and moved into
place when the recorder is closed, so an interrupted run still leaves a
complete, readable recording and never a half-written one.

This module does not decide what is interference; it logs what it is given.
"""

from __future__ import annotations

import os
from pathlib import Path

import mujoco
import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from sim.build import Built, PartModel
from sim.motion import moving_joints

CLEAR = (70, 160, 255)
SOFT = (255, 190, 40)
HARD = (230, 40, 40)
STATE_COLOURS = {"clear": CLEAR, "soft": SOFT, "hard": HARD}
PART_COLOUR = (160, 160, 170)
KEEPOUT_COLOUR = (255, 140, 0, 90)


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


def _blueprint(joints: bool = False) -> rrb.Blueprint:
    """The views; `joints`: with a view of the moving joints' values."""
    joint_view = [rrb.TimeSeriesView(name="Joint values", origin="joints")] if joints else []
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(name="Scene", origin="world"),
            rrb.Vertical(
                rrb.TimeSeriesView(name="Pair distances (scene units)", origin="checks"),
                *joint_view,
                rrb.Horizontal(
                    rrb.TimeSeriesView(name="Strain (%)", origin="cables/strain"),
                    rrb.TimeSeriesView(name="Min bend radius (scene units)", origin="cables/bend_radius"),
                    rrb.TimeSeriesView(name="Twist (deg)", origin="cables/twist"),
                ),
                rrb.TimeSeriesView(name="Agreement with MuJoCo", origin="validation"),
                rrb.TextLogView(name="Events", origin="events"),
                row_shares=[3, *([2] if joints else []), 2, 1, 2],
            ),
            column_shares=[3, 2],
        ),
        collapse_panels=False,
    )


class Recorder:
    """Writes one run's recording to `path` (see the module docstring)."""

    def __init__(self, built: Built, path: Path):
        self.built = built
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.tmp")
        self.unit = built.scene.scale  # metres per scene unit
        self.rec = rr.RecordingStream(application_id="cablecheck",
                                      recording_id=f"{built.scene.name}")
        self.rec.save(str(self.tmp), default_blueprint=_blueprint(bool(moving_joints(built.scene))))
        body_of_part = [p.body for p in built.parts]
        moving = {name for name in built.body_ids if name != "world"}
        self.moving_parts = np.array([b in moving for b in body_of_part], bool)
        m = built.model
        vis_body = np.array([int(m.geom_bodyid[v.geom_id]) for v in built.visuals], int)
        self._vis_bodies = np.unique(vis_body)
        self._vis_body_paths = {}
        for v, b in zip(built.visuals, vis_body):
            self._vis_body_paths[int(b)] = visual_paths(v.body, v.name)[0]
        self.moving_visual_bodies = self._vis_bodies[m.body_weldid[self._vis_bodies] != 0]
        self._kin = mujoco.MjData(m) if len(self._vis_bodies) else None
        self._closed = False
        self._labelled: set[str] = set()

    # -- static content ---------------------------------------------------
    def log_static(self, part_poses: np.ndarray, qpos: np.ndarray | None = None) -> None:
        """Parts' and visual geoms' shapes (and poses of those that never
        move), once; `qpos` (the simulation's, at t = 0) poses the visual geoms."""
        rec = self.rec
        rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        scene_points = self._scene_points(part_poses)
        for k, part in enumerate(self.built.parts):
            path = part_path(part.name)
            if part.shape == "plane":
                rec.log(path, self._plane(part, part_poses[k], scene_points), static=True)
                continue
            rec.log(path, self._shape(part), static=True)
            if not self.moving_parts[k]:
                rec.log(path, self._transform(part_poses[k]), static=True)
        if self._kin is None:
            return
        m = self.built.model
        for vis in self.built.visuals:
            g = vis.geom_id
            local = np.eye(4)
            mat = np.zeros(9)
            mujoco.mju_quat2Mat(mat, m.geom_quat[g])
            local[:3, :3], local[:3, 3] = mat.reshape(3, 3), m.geom_pos[g]
            path = visual_paths(vis.body, vis.name)[1]
            rec.log(path, self._shape(vis, self._visual_colour(g)), static=True)
            rec.log(path, self._transform(local), static=True)
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

    def _shape(self, part: PartModel, colour=None):
        u = self.unit
        if colour is None:
            colour = KEEPOUT_COLOUR if part.keepout else PART_COLOUR
        size = np.asarray(part.size, float) / u
        if part.shape == "box":
            return rr.Boxes3D(half_sizes=[size], colors=[colour], fill_mode="solid")
        if part.shape == "sphere":
            return rr.Ellipsoids3D(half_sizes=[[size[0]] * 3], colors=[colour], fill_mode="solid")
        if part.shape == "ellipsoid":
            return rr.Ellipsoids3D(half_sizes=[size], colors=[colour], fill_mode="solid")
        if part.shape == "capsule":
            return rr.Capsules3D(lengths=[2 * size[1]], radii=[size[0]],
                                 translations=[[0, 0, -size[1]]], colors=[colour])
        if part.shape == "cylinder":
            return rr.Cylinders3D(lengths=[2 * size[1]], radii=[size[0]], colors=[colour],
                                  fill_mode="solid")
        return rr.Mesh3D(vertex_positions=part.vertices / u, triangle_indices=part.faces,
                         albedo_factor=colour)

    def _scene_points(self, part_poses: np.ndarray) -> np.ndarray:
        """(n, 3) points that span the scene at t = 0 (metres): the cables'
        routes and the corners of the other parts' boxes."""
        pts = [c.routed for c in self.built.cables]
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

    def _plane(self, part: PartModel, pose: np.ndarray, scene_points: np.ndarray) -> rr.Boxes3D:
        colour = KEEPOUT_COLOUR if part.keepout else PART_COLOUR
        half = plane_half_sizes(part.size, pose, scene_points) / self.unit
        return rr.Boxes3D(half_sizes=[[half[0], half[1], 0.0]], colors=[colour], fill_mode="solid")

    def _transform(self, pose: np.ndarray) -> rr.Transform3D:
        return rr.Transform3D(translation=pose[:3, 3] / self.unit, mat3x3=pose[:3, :3])

    # -- per step ---------------------------------------------------------
    def log_step(self, t: float, cables: list[np.ndarray], part_poses: np.ndarray,
                 cable_states: list[str], strain: np.ndarray, bend: np.ndarray,
                 qpos: np.ndarray | None = None) -> None:
        """One step: moving parts' and (given `qpos`) visual geoms' poses,
        cables (coloured by state) and per-cable series."""
        rec, u = self.rec, self.unit
        rec.set_time("sim_time", duration=t)
        for k in np.flatnonzero(self.moving_parts):
            rec.log(part_path(self.built.parts[k].name), self._transform(part_poses[k]))
        if qpos is not None and len(self.moving_visual_bodies):
            poses = self._body_poses(qpos, self.moving_visual_bodies)
            for b, pose in zip(self.moving_visual_bodies, poses):
                rec.log(self._vis_body_paths[int(b)], self._transform(pose))
        for i, (cable, pts) in enumerate(zip(self.built.cables, cables)):
            rec.log(f"world/cables/{_escape(cable.name)}",
                    rr.LineStrips3D([pts / u], radii=[cable.radius / u],
                                    colors=[STATE_COLOURS[cable_states[i]]]))
            rec.log(f"cables/strain/{_escape(cable.name)}", rr.Scalars(100.0 * float(strain[i])))
            if np.isfinite(bend[i]):
                rec.log(f"cables/bend_radius/{_escape(cable.name)}", rr.Scalars(float(bend[i] / u)))

    def log_twist(self, twist_deg: np.ndarray) -> None:
        """Each cable's twist (degrees) at the current time; NaN: not measured."""
        for cable, value in zip(self.built.cables, twist_deg):
            if np.isfinite(value):
                self.rec.log(f"cables/twist/{_escape(cable.name)}", rr.Scalars(float(value)))

    def log_markers(self, markers: dict[str, tuple[np.ndarray, str]]) -> None:
        """Interference markers at worst points: entity path -> (point, state)."""
        for path, (point, state) in markers.items():
            self.rec.log(f"world/interference/{path}",
                         rr.Points3D([np.asarray(point) / self.unit], radii=[-6.0],
                                     colors=[STATE_COLOURS[state]]))

    def clear_markers(self, paths) -> None:
        """Remove markers of pairs that are clear again."""
        for path in paths:
            self.rec.log(f"world/interference/{path}", rr.Clear(recursive=False))

    def log_contacts(self, points: np.ndarray) -> None:
        """MuJoCo's contact points at this step."""
        self.rec.log("world/mujoco_contacts",
                     rr.Points3D(np.asarray(points).reshape(-1, 3) / self.unit, radii=[-3.0],
                                 colors=[(40, 220, 120)]))

    def log_scalar(self, path: str, value: float, label: str | None = None) -> None:
        """A time series value at the current time; `label` names the series
        in plot legends (set once per path)."""
        if label is not None and path not in self._labelled:
            self._labelled.add(path)
            self.rec.log(path, rr.SeriesLines(names=[label]), static=True)
        self.rec.log(path, rr.Scalars(float(value)))

    def log_joints(self, names: list[str], units: list[str], values: np.ndarray) -> None:
        """The moving joints' values at the current time, one series each."""
        for name, unit, value in zip(names, units, values):
            self.log_scalar(f"joints/{_escape(name)}", value, label=f"{name} ({unit})")

    def log_event(self, t: float, text: str, level: str) -> None:
        """An event as a text log entry at time t."""
        self.rec.set_time("sim_time", duration=t)
        self.rec.log("events", rr.TextLog(text, level=level))

    def close(self) -> None:
        """Finish the file and move it into place (safe to call twice)."""
        if self._closed:
            return
        self._closed = True
        self.rec.flush()
        self.rec.disconnect()
        os.replace(self.tmp, self.path)
