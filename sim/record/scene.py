"""The scene in the review recording: parts, visual geoms and their motion.

Each part's shape (filled) and, for parts on the world, its pose are one
static entry per part in its own frame (`world/parts/<assembly path>`); a
part riding a moving body gets its pose per frame. Many parts of one kind
under one assembly level are the instances of one entity instead
(`cablecheck.record.batches`). The mjcf model's visual
geoms (`world/visual/<body>/<geom>`, those MuJoCo never collides) are drawn
in their own colours, static in their body's frame, the body's pose coming
from the frame's qpos through MuJoCo's kinematics. Colours live on the
timeline, one column per entity: opaque from t = 0, translucent while a
clash is shown (so a spot inside a panel stays visible). A plane is drawn
as a rectangle: its given size, else sized to cover the scene; a floor is
always translucent (what lies under it shows), more so while a clash is
shown.

Not here: cables, clashes, plots (the other modules of `cablecheck.record`); what
is interference.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np
import rerun as rr

from cablecheck.build.built import Built, PartModel
from cablecheck.build.drawn import DrawnGeom
from cablecheck.record.batches import alone, batches, placement, static_columns
from cablecheck.record.columns import Column, column, mat3, rgba, vec3
from cablecheck.record.style import (
    FLOOR,
    FLOOR_DIMMED,
    KEEPOUT_COLOUR,
    PART_COLOUR,
    PART_DIMMED,
    part_path,
    visual_paths,
)

_KINDS = {"box": rr.Boxes3D, "plane": rr.Boxes3D, "sphere": rr.Ellipsoids3D,
          "ellipsoid": rr.Ellipsoids3D, "capsule": rr.Capsules3D, "cylinder": rr.Cylinders3D}
"""The archetype that draws each shape (meshes: `Mesh3D`)."""


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


def scene_points(built: Built, part_poses: np.ndarray, rest: list[np.ndarray] | None) -> np.ndarray:
    """(n, 3) points that span the scene at t = 0 (metres): the cables (at
    rest when given, else as routed) and the corners of the other parts' boxes."""
    pts = list(rest) if rest is not None else [c.routed for c in built.cables]
    for part, pose in zip(built.parts, part_poses):
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


def transform(pose: np.ndarray, unit: float) -> rr.Transform3D:
    """A pose (metres) in scene units."""
    return rr.Transform3D(translation=pose[:3, 3] / unit, mat3x3=pose[:3, :3])


def _colour_columns(part, colours: np.ndarray) -> list[Column]:
    """A part's colour alone, one (4,) colour per row, as a column of its shape's archetype."""
    kind = _KINDS.get(part.shape)
    descriptor = kind.descriptor_colors() if kind is not None else rr.Mesh3D.descriptor_albedo_factor()
    return [column(descriptor, rgba(colours))]


class SceneGeometry:
    """Parts and visual geoms of one built scene, and their poses per frame.

    Args:
      built: the built scene.
      unit: metres per scene unit.
      drawn: the mjcf model's visual geoms (`cablecheck.build.drawn`), drawn
        by their bodies' poses in the simulation model.
    """

    def __init__(self, built: Built, unit: float, drawn: Sequence[DrawnGeom] = ()):
        self.built, self.unit = built, unit
        moving = {name for name in built.body_ids if name != "world"}
        self.moving_parts = np.array([p.body in moving for p in built.parts], bool)
        self.batches = batches(built.parts, self.moving_parts, "world/parts")
        self._alone = alone(len(built.parts), self.batches)     # parts drawn as entities of their own
        m = built.model
        self.visuals = tuple(drawn)
        visuals = self.visuals
        vis_body = np.array([v.body_id for v in visuals], int)
        self._vis_bodies = np.unique(vis_body)
        self._vis_body_paths = {int(b): visual_paths(v.body, v.name)[0] for v, b in zip(visuals, vis_body)}
        self.moving_visual_bodies = self._vis_bodies[m.body_weldid[self._vis_bodies] != 0]
        self._kin = mujoco.MjData(m) if len(self._vis_bodies) else None
        self.bounds: tuple[np.ndarray, np.ndarray] | None = None
        self._points: np.ndarray | None = None

    def log_static(self, rec: rr.RecordingStream, part_poses: np.ndarray, rest: list[np.ndarray] | None,
                   qpos: np.ndarray | None) -> None:
        """Every part's and visual geom's shape (with the pose of those that
        never move) as one static entry each; `rest` (the cables' rest
        shapes, metres) sizes the floor and the scene's bounds."""
        u = self.unit
        self._points = scene_points(self.built, part_poses, rest)
        self.bounds = ((self._points.min(axis=0), self._points.max(axis=0)) if len(self._points)
                       else (np.full(3, -0.5), np.full(3, 0.5)))
        for b in self.batches:
            rec.send_columns(b.path, indexes=[], columns=static_columns(b, self.built.parts, part_poses, u))
        for k in np.flatnonzero(self._alone):
            part = self.built.parts[k]
            shape = self.shape(part, part_poses[k])
            if self.moving_parts[k]:
                rec.log(part_path(part.name), shape, static=True)
            else:
                rec.log(part_path(part.name), shape, transform(part_poses[k], u), static=True)
        if self._kin is None:
            return
        m = self.built.model
        for vis in self.visuals:
            rec.log(visual_paths(vis.body, vis.name)[1], self.shape(vis, np.eye(4)), transform(vis.local, u),
                    static=True)
        poses = self.body_poses(self.built.qpos0 if qpos is None else qpos, self._vis_bodies)
        for b, pose in zip(self._vis_bodies, poses):
            if m.body_weldid[b] == 0:
                rec.log(self._vis_body_paths[int(b)], transform(pose, u), static=True)

    def shape(self, part: PartModel | DrawnGeom, pose: np.ndarray):
        """The archetype drawing a part (or visual geom) in its own frame, filled."""
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
            points = self._points if self._points is not None else np.zeros((0, 3))
            half = plane_half_sizes(part.size, pose, points) / u
            return rr.Boxes3D(half_sizes=[[half[0], half[1], 0.0]], fill_mode="solid")
        return rr.Mesh3D(vertex_positions=part.vertices / u, triangle_indices=part.faces)

    def body_poses(self, qpos: np.ndarray, bodies: np.ndarray) -> np.ndarray:
        """(B, 4, 4) scene-world poses of `bodies` at `qpos` (MuJoCo's kinematics)."""
        m, d = self.built.model, self._kin
        d.qpos[:] = qpos
        mujoco.mj_kinematics(m, d)
        poses = np.zeros((len(bodies), 4, 4))
        poses[:, :3, :3] = d.xmat[bodies].reshape(-1, 3, 3)
        poses[:, :3, 3] = d.xpos[bodies] + self.built.origin
        poses[:, 3, 3] = 1.0
        return poses

    def visual_body_poses(self, qpos: np.ndarray | None) -> np.ndarray | None:
        """(B, 4, 4) poses of the moving visual bodies at `qpos`, or None if there are none."""
        if not len(self.moving_visual_bodies):
            return None
        return self.body_poses(self.built.qpos0 if qpos is None else qpos, self.moving_visual_bodies)

    def send_motion(self, rec: rr.RecordingStream, index: list, poses: list[np.ndarray],
                    vis_poses: list[np.ndarray]) -> None:
        """Poses of the moving parts (F, M, 4, 4) and visual bodies (F, B, 4, 4), one column per entity
        (a batch of parts: a row of its instances' poses per frame)."""
        u = self.unit
        stacks, paths = [], []
        if poses:
            every_part = np.stack(poses)                                        # (F, M, 4, 4)
            slot = np.cumsum(self.moving_parts) - 1                 # part index -> index among the moving
            for b in self.batches:
                if b.moving:
                    rec.send_columns(b.path, indexes=index, columns=placement(
                        b.archetype, [self.built.parts[k] for k in b.members], every_part[:, slot[b.members]], u))
            stacks.append(every_part[:, self._alone[self.moving_parts]])
            paths += [part_path(self.built.parts[k].name) for k in np.flatnonzero(self.moving_parts & self._alone)]
        if vis_poses:
            stacks.append(np.stack(vis_poses))                                  # (F, B, 4, 4)
            paths += [self._vis_body_paths[int(b)] for b in self.moving_visual_bodies]
        if not paths:
            return
        every = np.concatenate(stacks, axis=1)                                  # (F, M + B, 4, 4)
        t = rr.Transform3D
        for j, path in enumerate(paths):
            rec.send_columns(path, indexes=index, columns=[column(t.descriptor_translation(), vec3(every[:, j, :3, 3] / u)),
                                                           column(t.descriptor_mat3x3(), mat3(every[:, j, :3, :3]))])

    def send_colours(self, rec: rr.RecordingStream, times: np.ndarray, dimmed: np.ndarray) -> None:
        """Every part's and visual geom's colour, one column per entity: its
        own at `times[0]`, then dimmed (translucent) or not at each later
        time as `dimmed` (T,) says (keep-outs never change; planes are
        translucent throughout, more so while dimmed)."""
        index = [rr.TimeColumn("sim_time", duration=times)]
        on = np.asarray(dimmed, bool)
        plain = np.array((*PART_COLOUR, 255), np.uint8)
        parts_rgba = np.where(on[:, None], np.array(PART_DIMMED, np.uint8)[None], plain[None])
        floor_rgba = np.where(on[:, None], np.array(FLOOR_DIMMED, np.uint8)[None], np.array(FLOOR, np.uint8)[None])
        first = [rr.TimeColumn("sim_time", duration=times[:1])]
        for b in self.batches:      # one colour a row, every instance's
            rec.send_columns(b.path, indexes=index, columns=[column(b.archetype.descriptor_colors(), rgba(parts_rgba))])
        for part in (p for p, own in zip(self.built.parts, self._alone) if own):
            if part.keepout:
                own = np.array(KEEPOUT_COLOUR, np.uint8)[None]
                rec.send_columns(part_path(part.name), indexes=first, columns=_colour_columns(part, own))
            elif part.shape == "plane":
                rec.send_columns(part_path(part.name), indexes=index, columns=_colour_columns(part, floor_rgba))
            else:
                rec.send_columns(part_path(part.name), indexes=index, columns=_colour_columns(part, parts_rgba))
        for vis in self.visuals:
            colour = np.array(vis.rgba, np.uint8)
            if vis.shape == "plane":                      # a floor: translucent throughout
                colour[3] = min(colour[3], FLOOR[3])
            faded = np.array([*colour[:3], min(colour[3], PART_DIMMED[3] if vis.shape != "plane" else FLOOR_DIMMED[3])],
                             np.uint8)
            shade = np.where(on[:, None], faded[None], colour[None])
            rec.send_columns(visual_paths(vis.body, vis.name)[1], indexes=index, columns=_colour_columns(vis, shade))
