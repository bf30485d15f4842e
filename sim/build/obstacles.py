"""The parts a cable's initial droop stays clear of, placed at t = 0.

A cable longer than its route droops (`cablecheck.build.route.initial_shape`); with
`cable-structure` contact on, it must not droop into the parts it collides
with, or the first steps would only push it back out. `Obstacles.measure`
gives the droop a depth function: how far a cable of a given radius would
sink into the nearest such part.

This module does not route cables (see `cablecheck.build.cableplan`); it reads an mjcf
base model (compiled once, `cablecheck.scene.mjcf.base_model`) only to know its
geoms' local poses and sizes.
"""

from __future__ import annotations

import mujoco
import numpy as np

from cablecheck.build.modelread import mesh_arrays
from cablecheck.build.startframes import Frames
from cablecheck.checker.arrays import all_columns
from cablecheck.checker.shapes import Shape, ShapeType, least_signed_distance, mesh_shape
from cablecheck.scene.frames import euler_matrix
from cablecheck.scene.mjcf import SHAPES, base_model, colliding_parts
from cablecheck.scene.records import Scene


class Obstacles:
    """The parts a scene's cables collide with, placed at t = 0 in model
    coordinates: what an initial shape must not droop into (`cablecheck.build.route`).

    Scene parts that are not keep-outs, and the base mjcf model's colliding
    geoms (the model the scene reader compiled, for their local poses and sizes)
    on the bodies whose t = 0 frames the scene knows, each with its part
    name (`names`). Only built when `cable-structure` contact is on: for a
    cable with slack to droop, or to find a route through a part
    (`cablecheck.build.routecheck`)."""

    def __init__(self, scene: Scene, frames: Frames, meshes: dict):
        shapes: list[Shape | tuple[np.ndarray, np.ndarray]] = []   # a mesh as its arrays until asked for
        rot, pos, names = [], [], []

        def place(body: str, local_pos, local_rot) -> None:
            p, r = frames.poses[body]
            r = np.asarray(r, float)
            rot.append(r @ local_rot)
            pos.append(np.asarray(p, float) - frames.origin + r @ np.asarray(local_pos, float))

        for part in scene.parts:
            if part.keepout:
                continue
            if part.shape == "mesh":
                shapes.append(meshes[part.name])
            else:
                shapes.append(Shape(ShapeType(part.shape), np.asarray(part.size, float) if part.size else np.zeros(3)))
            place(part.body, part.pos, euler_matrix(part.euler))
            names.append(part.name)
        if scene.mjcf is not None:
            m = base_model(scene.mjcf)
            geom_name = colliding_parts(m)     # the builder's part names
            for g in range(m.ngeom):
                gtype = int(m.geom_type[g])
                body = m.body(int(m.geom_bodyid[g])).name or "world"
                if gtype not in SHAPES or body not in frames.poses:
                    continue
                if m.geom_contype[g] == 0 and m.geom_conaffinity[g] == 0:
                    continue    # visual geoms never collide
                if gtype == int(mujoco.mjtGeom.mjGEOM_MESH):
                    shapes.append(mesh_arrays(m, g))
                else:
                    shapes.append(Shape(ShapeType(SHAPES[gtype]), m.geom_size[g].copy()))
                local = np.zeros(9)
                mujoco.mju_quat2Mat(local, m.geom_quat[g])
                place(body, m.geom_pos[g], local.reshape(3, 3))
                names.append(geom_name[g])
        self._shapes = shapes
        self.names = names
        self.rot = np.asarray(rot, float).reshape(-1, 3, 3)
        self.pos = np.asarray(pos, float).reshape(-1, 3)
        # world boxes (a plane's is infinite): only parts whose box comes
        # near the queried points are measured
        self.lo = np.full((len(shapes), 3), -np.inf)
        self.hi = np.full((len(shapes), 3), np.inf)
        for k, sh in enumerate(shapes):
            if isinstance(sh, tuple) or sh.type is not ShapeType.PLANE:
                lo, hi = (np.min(sh[0], axis=0), np.max(sh[0], axis=0)) if isinstance(sh, tuple) \
                    else sh.local_bounds()
                corners = np.array(np.meshgrid(*zip(lo, hi), indexing="ij")).reshape(3, -1).T
                world = corners @ self.rot[k].T + self.pos[k]
                self.lo[k], self.hi[k] = world.min(axis=0), world.max(axis=0)

    def shape(self, k: int) -> Shape:
        """Part k's shape; a mesh's prepared (`mesh_shape`: its trees, about 36 ms for an arm
        link) the first time it is asked for: a droop or a route meets a few of an arm's links."""
        sh = self._shapes[k]
        if isinstance(sh, tuple):
            sh = self._shapes[k] = mesh_shape(*sh)
        return sh

    def measure(self, radius: float):
        """depth(points) for a cable of `radius`: radius less the signed
        distance, exact where a vertex reaches into a part; a vertex clear
        of every part gets some value of 0 or less (-inf where no part's box
        comes within the radius), which is all `cablecheck.build.route` asks."""
        def depth(points: np.ndarray) -> np.ndarray:
            lo, hi = points.min(axis=0) - radius, points.max(axis=0) + radius
            near = np.flatnonzero(all_columns((self.lo <= hi) & (self.hi >= lo)))
            shapes = [self.shape(k) for k in near.tolist()]
            return radius - least_signed_distance(shapes, self.rot[near], self.pos[near], points, limit=radius,
                                                  bounds=(self.lo[near], self.hi[near]))
        return depth
