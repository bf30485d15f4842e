"""The step loop of a scene built without MuJoCo: the script moves the bodies, nothing is simulated.

`KinematicSimulation` offers what a run reads of `cablecheck.run.loop.Simulation`
(`reset`, `settle`, `steps`, `state`, `motion`, `warnings`, the step
counts) for a scene of `cablecheck.build.static`: no mjcf model, no dynamics, no
MuJoCo comparison. The script (`cablecheck.run.motion`) writes the `[[bodies]]`' free
joints into a qpos vector laid out as MuJoCo's; a free body hangs from the
world, so its pose is its joint's, and each part's pose follows from its
body's as in MuJoCo's `mj_kinematics`. The cables stay exactly as routed,
as with `effects.dynamics = false` in a MuJoCo build.

Parts are placed with MuJoCo's own quaternion and matrix functions, one
call per part: MuJoCo's compiled arithmetic fuses multiply-adds where
numpy rounds twice, and only its own functions put a part where a MuJoCo
build does to the last bit (reports of both builds are byte-identical).
The world's parts are placed once, a body's parts again only when the body
has moved.

This module does not build, check or record anything.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import mujoco
import numpy as np

from cablecheck.build.built import Built
from cablecheck.build.mjspec import euler_quat
from cablecheck.run.loop import StepState
from cablecheck.run.motion import Motion


@dataclass
class _Joints:
    """The script's target: the bodies' free joints (what `Motion.apply` sets)."""

    qpos: np.ndarray
    qvel: np.ndarray


FRAME_EPS = 1e-6
"""MuJoCo's compiler takes a part's frame as its body's (`mjtSameFrame`)
when its position and quaternion are within this of the body's, element by
element; the kinematics then copies the body's frame."""


def same_frame(pos: np.ndarray, quat: np.ndarray) -> mujoco.mjtSameFrame:
    """What MuJoCo's compiler makes of a part's frame (`pos`, `quat` in its
    body): the body's frame, the body's orientation only, or neither."""
    rot = bool(np.all(np.abs(quat - (1.0, 0.0, 0.0, 0.0)) < FRAME_EPS)
               or np.all(np.abs(quat + (1.0, 0.0, 0.0, 0.0)) < FRAME_EPS))
    if rot and np.all(np.abs(pos) < FRAME_EPS):
        return mujoco.mjtSameFrame.mjSAMEFRAME_BODY
    return mujoco.mjtSameFrame.mjSAMEFRAME_BODYROT if rot else mujoco.mjtSameFrame.mjSAMEFRAME_NONE


def compiled_quat(quat: np.ndarray) -> np.ndarray:
    """A frame's quaternion as MuJoCo's compiler stores it: divided by its
    norm unless that is within 1e-14 of 1."""
    norm = float(np.sqrt(np.sum(np.square(quat))))
    return quat / norm if abs(norm - 1.0) > 1e-14 else quat


def place(xpos: np.ndarray, xquat: np.ndarray, xmat: np.ndarray, pos: np.ndarray, quat: np.ndarray,
          frame: mujoco.mjtSameFrame, out: np.ndarray) -> None:
    """Write into `out` (4, 4) the world pose of a frame at `pos`, `quat` in a
    body at `xpos`, `xquat` (`xmat` its matrix): MuJoCo's `mj_local2Global`
    step by step (`frame`: see `same_frame`), with MuJoCo's own functions
    (its compiled arithmetic fuses multiply-adds where numpy rounds twice,
    so only these agree to the bit)."""
    out[3, 3] = 1.0
    if frame == mujoco.mjtSameFrame.mjSAMEFRAME_BODY:
        out[:3, :3] = xmat.reshape(3, 3)
        out[:3, 3] = xpos
        return
    p = np.zeros(3)
    mujoco.mju_mulMatVec3(p, xmat, pos)
    out[:3, 3] = p + xpos
    if frame == mujoco.mjtSameFrame.mjSAMEFRAME_BODYROT:
        out[:3, :3] = xmat.reshape(3, 3)
        return
    q = np.zeros(4)
    mujoco.mju_mulQuat(q, xquat, quat)
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, q)
    out[:3, :3] = mat.reshape(3, 3)


class KinematicSimulation:
    """A built scene without MuJoCo, moved by its script (see the module docstring)."""

    def __init__(self, built: Built):
        scene = built.scene
        self.built = built
        self.motion = Motion(built)
        self.timestep = scene.timestep
        self.settle_steps = 0
        self.total_steps = int(round(scene.duration / scene.timestep))
        nb = len(scene.bodies)
        self._joints = _Joints(built.qpos0.copy(), np.zeros(6 * nb))
        adr = np.array([built.free[b.name][0] for b in scene.bodies], int).reshape(-1, 1)
        self._pos_adr = adr + np.arange(3)
        self._quat_adr = adr + np.arange(3, 7)
        self._part_body = np.asarray(built.model.geom_bodyid, int)
        # each part's frame in its body's as the build writes it (MuJoCo's
        # compiler keeps it): the world's parts in model coordinates (the
        # scene's world less the origin)
        defs = {p.name: p for p in scene.parts}
        self._local_pos = np.array([np.asarray(defs[p.name].pos, float) - (built.origin if p.body == "world" else 0.0)
                                    for p in built.parts], float).reshape(-1, 3)
        self._local_quat = np.array([compiled_quat(euler_quat(defs[p.name].euler)) for p in built.parts],
                                    float).reshape(-1, 4)
        self._frame = [same_frame(pos, quat) for pos, quat in zip(self._local_pos, self._local_quat)]
        self._parts_of = [np.flatnonzero(self._part_body == b) for b in range(nb + 1)]
        self._end_bodies = np.array([[built.body_ids[c.start.body], built.body_ids[c.end.body]]
                                     for c in scene.cables], int).reshape(-1, 2)
        self._xpos = np.zeros((nb + 1, 3))
        self._xquat = np.tile([1.0, 0.0, 0.0, 0.0], (nb + 1, 1))
        self._xmat = np.tile(np.eye(3).ravel(), (nb + 1, 1))
        self._poses = np.zeros((len(built.parts), 4, 4))   # model coordinates
        self._placed = np.zeros(nb + 1, bool)              # body's parts placed at its current pose
        self._place_parts(0)

    def reset(self) -> None:
        """Scripted targets at t = 0."""
        self.motion.apply(self._joints, 0.0, frozen=True)

    def settle(self, progress=None, stop=None) -> None:
        """Nothing settles: the cables are not simulated."""

    def steps(self, contacts: bool = True, every: int = 1) -> Iterator[StepState]:
        """Yield the state at t = 0, then every `every`-th step until the duration."""
        yield self.state(0, contacts)
        for k in range(1, self.total_steps + 1):
            self.motion.apply(self._joints, k * self.timestep)
            if k % every == 0 or k == self.total_steps:
                yield self.state(k, contacts)

    def _place_parts(self, body: int) -> None:
        """Pose every part of `body` at the body's current pose."""
        xpos, xquat, xmat = self._xpos[body], self._xquat[body], self._xmat[body]
        for k in self._parts_of[body]:
            place(xpos, xquat, xmat, self._local_pos[k], self._local_quat[k], self._frame[k], self._poses[k])
        self._placed[body] = True

    def _move_bodies(self) -> None:
        """Each body at its free joint (model coordinates), as `mj_kinematics`
        puts a free body: the joint's position, its quaternion normalised; the
        parts of the bodies that moved placed again."""
        q = self._joints.qpos
        for i in range(1, len(self._xpos)):
            pos = q[self._pos_adr[i - 1]]
            quat = q[self._quat_adr[i - 1]].copy()
            mujoco.mju_normalize4(quat)   # the free joint's, then the body's
            mujoco.mju_normalize4(quat)
            if np.array_equal(pos, self._xpos[i]) and np.array_equal(quat, self._xquat[i]) and self._placed[i]:
                continue
            self._xpos[i], self._xquat[i] = pos, quat
            mujoco.mju_quat2Mat(self._xmat[i], quat)
            self._place_parts(i)

    def state(self, step: int, contacts: bool = False) -> StepState:
        """The current state (contacts are never detected: there is no MuJoCo model)."""
        self._move_bodies()
        poses = self._poses.copy()
        poses[:, :3, 3] += self.built.origin
        cables = [c.routed.copy() for c in self.built.cables]
        end_rot = self._xmat[self._end_bodies.ravel()].reshape(-1, 2, 3, 3)
        return StepState(step, step * self.timestep, cables, poses, None, np.zeros(2),
                         self._joints.qpos.copy(), end_rot)

    def warnings(self) -> dict[str, int]:
        """MuJoCo's warnings: none, nothing runs in MuJoCo."""
        return {}
