"""Body frames at t = 0: euler angles to rotations, anchors to and from
world coordinates, and the mjcf bodies' frames at the motions' first samples.

"At t = 0" is the pose the motion script gives (see `cablecheck.scene`). Frames
are (origin (3,), rotation (3, 3)) pairs, read-only. Nothing here reads a
scene table.
"""

from __future__ import annotations

import mujoco
import numpy as np

from cablecheck.scene.mjcf import MjcfInfo
from cablecheck.scene.records import Anchor, MotionDef


def euler_matrix(euler_deg) -> np.ndarray:
    """(3, 3) rotation of MuJoCo's default euler sequence (intrinsic x, y, z), degrees."""
    a, b, c = np.radians(np.asarray(euler_deg, float))
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
    return rx @ ry @ rz


def frame(origin, rotation) -> tuple[np.ndarray, np.ndarray]:
    """A read-only (origin (3,), rotation (3, 3)) pair."""
    origin, rotation = np.array(origin, float), np.array(rotation, float)
    origin.setflags(write=False)
    rotation.setflags(write=False)
    return origin, rotation


def to_world(frames: dict, anchor: Anchor) -> np.ndarray:
    """The anchor's world position at t = 0, metres."""
    origin, rotation = frames[anchor.body]
    return origin + rotation @ np.asarray(anchor.pos)


def from_world(frames: dict, body: str, point: np.ndarray) -> tuple[float, float, float]:
    """A world point at t = 0 in the frame of `body`, metres."""
    origin, rotation = frames[body]
    return tuple(float(v) for v in rotation.T @ (point - origin))


def mjcf_frames(mjcf: MjcfInfo, motions: tuple[MotionDef, ...]) -> dict:
    """World frames of the mjcf bodies at t = 0: qpos0, driven joints at their first sample."""
    model = mjcf.model
    data = mujoco.MjData(model)
    for m in motions:
        for j, name in enumerate(m.trajectory.joints):
            data.qpos[model.jnt_qposadr[mjcf.joints[name]]] = m.trajectory.joint_values[0, j]
    mujoco.mj_kinematics(model, data)
    return {name: frame(data.xpos[i], data.xmat[i].reshape(3, 3))
            for name, i in mjcf.bodies.items()}
