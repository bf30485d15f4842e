"""The scene at t = 0 in model coordinates: the model's origin, body frames, mesh parts.

MuJoCo is given coordinates relative to `scene_origin`, so scenes far from
their world origin simulate with the same rounding as scenes near it;
`Frames` holds every body's pose at t = 0 in those coordinates (the
scene's `start_frames` less the origin) and carries points between a body's
frame and the model's world; `part_meshes` reads each mesh part's file
once.

This module does not route cables (see `cablecheck.build.cableplan`) nor write the model
(see `cablecheck.build.mjspec`); it compiles nothing but, for a cable held on a body of an
mjcf model, that model on its own to know its bodies at qpos0.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from cablecheck.scene.frames import euler_matrix
from cablecheck.scene.meshfile import mesh_nodes
from cablecheck.scene.mjcf import base_model
from cablecheck.scene.records import Scene

if TYPE_CHECKING:
    from cablecheck.build.cableplan import CablePlan


def scene_origin(scene: Scene) -> np.ndarray:
    """Where the model's origin sits in the scene's world, metres.

    MuJoCo is given coordinates relative to this point (the mean of the
    cables' routes, else of the parts' and bodies' positions), so a scene
    placed far from its world origin (plant coordinates, CAD assemblies at
    1e4 mm) simulates with the same rounding as one near it: measured on a
    cable following a moving body 2.2e4 m out, the unshifted model settled
    2.6 mm away from the same scene at the origin, the shifted one 1e-12 m.
    Everything read back out is shifted back."""
    points = [np.asarray(c.route, float) for c in scene.cables if c.route is not None]
    if not points:
        points = [np.asarray([p.pos for p in scene.parts if p.body == "world"], float).reshape(-1, 3),
                  np.asarray([b.pos for b in scene.bodies], float).reshape(-1, 3)]
    stacked = np.concatenate(points) if points else np.zeros((0, 3))
    return stacked.mean(axis=0) if len(stacked) else np.zeros(3)


class Frames:
    """Pose of every body at t = 0 (`Scene.start_frames`), in model coordinates
    (the scene's world less `origin`)."""

    def __init__(self, scene: Scene, origin: np.ndarray, poses=None):
        self.poses = scene.start_frames if poses is None else poses
        self.origin = origin

    def at_qpos0(self, scene: Scene, plans: list["CablePlan"]) -> "Frames":
        """The same frames where the compiled model has its bodies at qpos0:
        `[[bodies]]` at their `[[bodies]]` pose (their first key may differ),
        the mjcf model's bodies at its qpos0 (its first motion sample may
        differ). Where a cable's rest shape is placed (`compile_model`'s `rest`)."""
        poses = dict(self.poses)
        for b in scene.bodies:
            poses[b.name] = (np.asarray(b.pos, float), euler_matrix(b.euler))
        held = {h.body for plan in plans for h in plan.held}
        if scene.mjcf is not None and held & self._mjcf_names(scene):
            model = base_model(scene.mjcf)   # compiled once per run (the scene's check compiled it)
            data = mujoco.MjData(model)
            mujoco.mj_kinematics(model, data)
            for i in range(1, model.nbody):
                name = model.body(i).name
                if name in poses:
                    poses[name] = (data.xpos[i].copy(), data.xmat[i].reshape(3, 3).copy())
        return Frames(scene, self.origin, poses)

    @staticmethod
    def _mjcf_names(scene: Scene) -> set:
        return set(scene.start_frames) - {"world"} - {b.name for b in scene.bodies}

    def to_world(self, body: str, pos) -> np.ndarray:
        p, r = self.poses[body]
        return np.asarray(p, float) - self.origin + np.asarray(r, float) @ np.asarray(pos, float)

    def to_local(self, body: str, point) -> np.ndarray:
        """A model-coordinate point in the frame of `body` as built in the model."""
        if body == "world":  # the model's world frame is the model origin itself
            return np.asarray(point, float)
        p, r = self.poses[body]
        return np.asarray(r, float).T @ (np.asarray(point, float) + self.origin - np.asarray(p, float))


def part_meshes(scene: Scene) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Mesh part name -> (vertices in metres, faces), reading each file once
    (a glTF file holds the meshes of several parts; both models use them)."""
    files: dict = {}
    out = {}
    for part in scene.parts:
        if part.shape != "mesh":
            continue
        if part.file not in files:
            files[part.file] = {m.path: m for m in mesh_nodes(part.file)}
        nodes = files[part.file]
        mesh = nodes[part.node] if part.node is not None else next(iter(nodes.values()))
        out[part.name] = (np.asarray(mesh.vertices, float) * part.mesh_scale, np.asarray(mesh.faces, int))
    return out
