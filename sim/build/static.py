"""A scene built without MuJoCo, for a static check.

A run needs a MuJoCo model to simulate the cables (`effects.dynamics`), to
compare with MuJoCo's own contacts (`check.validate`) or to read an mjcf
base model (its bodies, joints, geoms and meshes are MuJoCo's). Without all
three nothing does (`needs_model`): the cables keep their routed shapes
(`cablecheck.build.cableplan`, the same plans a MuJoCo build starts from), the parts are
the scene's own, and the script moves `[[bodies]]`, free bodies whose
poses follow from the script alone (`cablecheck.run.kinematic`). `build_static` gives
the `Built` a MuJoCo build would give, its model replaced by the bodies'
tree (`cablecheck.build.built.BodyTree`), without writing or compiling anything.

Parts are numbered as MuJoCo numbers geoms (the world's parts first, then
each body's, in scene order) with MuJoCo's three size numbers, so checks,
events and reports come out as from a MuJoCo build. Mesh parts keep their
file's vertices in the part's own frame, in double precision, where MuJoCo
recentres them and stores them in single precision: distances to a mesh
differ from a MuJoCo build's by that rounding (about 1e-7 of its size).

This module does not step, check or record anything, and never builds a
MuJoCo model (see `cablecheck.build.stages` for that).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from cablecheck.build.built import BodyTree, Built, PartModel
from cablecheck.build.cableplan import cable_model
from cablecheck.build.mjspec import euler_quat, part_size
from cablecheck.build.stages import plan_cables
from cablecheck.build.substeps import choose_substeps
from cablecheck.scene.records import Scene


def needs_model(scene: Scene) -> bool:
    """A run of `scene` needs a MuJoCo model (see the module docstring)."""
    return scene.effects.dynamics or scene.check.validate or scene.mjcf is not None


def build_static(scene: Scene) -> Built:
    """The built scene without a MuJoCo model (`needs_model` must be False)."""
    if needs_model(scene):
        raise ValueError(f"{scene.path}: the scene needs a MuJoCo model (dynamics, validation or an mjcf model)")
    frames, meshes, plans = plan_cables(scene)
    origin = frames.origin
    body_index = {"world": 0} | {b.name: i + 1 for i, b in enumerate(scene.bodies)}
    order = sorted(range(len(scene.parts)), key=lambda k: (body_index[scene.parts[k].body], k))
    parts = []
    for geom, k in enumerate(order):
        part = scene.parts[k]
        if part.shape == "mesh":
            vertices, faces = meshes[part.name]
            size = 0.5 * (vertices.max(axis=0) - vertices.min(axis=0))
        else:
            vertices = faces = None
            size = np.array(part_size(part), float)
        parts.append(PartModel(part.name, geom, part.body, part.shape, size, vertices, faces, part.keepout))
    nb = len(scene.bodies)
    qpos0 = np.zeros(7 * nb)
    for i, b in enumerate(scene.bodies):
        qpos0[7 * i:7 * i + 3] = np.asarray(b.pos, float) - origin
        qpos0[7 * i + 3:7 * i + 7] = euler_quat(b.euler)
    tree = BodyTree(body_names=("world",) + tuple(b.name for b in scene.bodies),
                    body_parentid=np.zeros(nb + 1, np.int32), body_weldid=np.arange(nb + 1, dtype=np.int32),
                    body_jntnum=np.concatenate([[0], np.ones(nb)]).astype(np.int32),
                    jnt_bodyid=np.arange(1, nb + 1, dtype=np.int32),
                    joint_names=tuple(f"{b.name}/free" for b in scene.bodies),
                    geom_bodyid=np.array([body_index[p.body] for p in parts], np.int32).reshape(-1),
                    qpos0=qpos0)
    counts = np.array([len(p.routed) for p in plans], int)
    vert_adr = np.concatenate([[0], np.cumsum(counts)])[:-1]
    cables = [cable_model(plan, i, int(adr), origin) for i, (plan, adr) in enumerate(zip(plans, vert_adr))]
    empty = np.zeros(0, int)
    built = Built(scene, tree, None, cables, parts, {b.name: (7 * i, 6 * i) for i, b in enumerate(scene.bodies)},
                  dict(body_index), empty, empty, {}, qpos0, origin,
                  np.zeros((len(parts), len(parts)), bool))
    # without dynamics one step per scene step and nothing to tunnel (cablecheck.build.substeps)
    return replace(built, substeps=choose_substeps(built))
