"""The checker's view of a built scene: part shapes, the rigid part set, assembly selections.

A built scene (:class:`cablecheck.build.stages.Built`) names its parts in MuJoCo's terms
(geom types, sizes, MuJoCo's own mesh vertices, bodies); the checker takes
:class:`cablecheck.checker.shapes.Shape` objects (placed at t = 0 by
`start_part_poses`) and a prepared
:class:`cablecheck.checker.partset.PartSet`. Both the run's checks (`cablecheck.run.stepcheck`)
and the sweep command (`cablecheck.run.sweep`) translate through here, so they see the
same parts, grouped into the same rigid groups, at the same precision.

`selection` turns an assembly path (a part name or a "/"-separated prefix)
into the parts it covers; a path that covers none raises `OptionError`
naming the command-line option it came from.

This module does not check, step, move or report anything, and parses no
options of its own: the commands (`cablecheck.run.runner`, `cablecheck.run.sweep`) do.
"""

from __future__ import annotations

import difflib

import mujoco
import numpy as np

from cablecheck.build.built import BodyTree, Built
from cablecheck.checker.partset import PartSet
from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape
from cablecheck.run.kinematic import KinematicSimulation
from cablecheck.run.motion import Motion

DEFAULT_PRECISION_M = 5e-4
"""Default precision: 0.5 mm (as in the sweep-verification paper), in metres."""


class OptionError(ValueError):
    """A command-line option that cannot be used with this scene; `option`
    names it (e.g. ``--only``), `problem` says why."""

    def __init__(self, option: str, problem: str):
        super().__init__(f"{option}: {problem}")
        self.option = option
        self.problem = problem


def part_shapes(built: Built) -> list[Shape]:
    """The checker's shape of every built part (geom frame, metres)."""
    out = []
    for p in built.parts:
        if p.shape == "mesh":
            out.append(mesh_shape(p.vertices, p.faces))
        else:
            out.append(Shape(ShapeType(p.shape), p.size))
    return out


def start_part_poses(built: Built) -> np.ndarray:
    """(P, 4, 4) scene-world pose of every part at t = 0, as the run's first
    state puts it (the routed state with the script at its t = 0 pose): a
    MuJoCo build's through `mj_kinematics`, a build without MuJoCo through
    its own placing (`cablecheck.run.kinematic`)."""
    if isinstance(built.model, BodyTree):
        sim = KinematicSimulation(built)
        sim.reset()
        return sim.state(0).part_poses
    d = mujoco.MjData(built.model)
    d.qpos[:] = built.qpos0
    Motion(built).apply(d, 0.0, frozen=True)
    mujoco.mj_kinematics(built.model, d)
    geoms = np.array([p.geom_id for p in built.parts], np.int64)
    poses = np.zeros((len(geoms), 4, 4))
    poses[:, :3, :3] = d.geom_xmat[geoms].reshape(-1, 3, 3)
    poses[:, :3, 3] = d.geom_xpos[geoms] + built.origin
    poses[:, 3, 3] = 1.0
    return poses


def rigid_groups(built: Built) -> list[str]:
    """Per part, the rigid group it moves with: the top body of its weld group
    (MuJoCo's ``body_weldid``: bodies joined without a joint move as one)."""
    m = built.model
    out = []
    for p in built.parts:
        weld = int(m.body_weldid[int(m.geom_bodyid[p.geom_id])])
        out.append(m.body(weld).name or "world")
    return out


def part_set(built: Built, tolerance: float, shapes: list[Shape] | None = None) -> PartSet:
    """The built parts prepared for sweeps and part-part checks (``shapes``: already built ones)."""
    return PartSet.build([p.name for p in built.parts], shapes or part_shapes(built),
                         groups=rigid_groups(built),
                         keepout=[p.keepout for p in built.parts], tolerance=tolerance)


def selection(parts: PartSet, path: str, option: str) -> np.ndarray:
    """(P,) bool of the parts at ``path`` (a part name or assembly prefix);
    OptionError for ``option`` when it names none."""
    sel = parts.select(path)
    if not sel.any():
        close = difflib.get_close_matches(path, list(parts.names), n=3, cutoff=0.5)
        hint = f" (did you mean {', '.join(map(repr, close))}?)" if close else \
            f" (parts: {', '.join(list(parts.names)[:8])}{', ...' if len(parts.names) > 8 else ''})"
        raise OptionError(option, f"no part or assembly named {path!r}{hint}")
    return sel
