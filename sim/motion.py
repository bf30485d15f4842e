"""Scripted motion: keyframes interpolated in time and applied to the model.

Bodies (`[[bodies]]`, free bodies in MuJoCo) follow their keys' world poses:
position linearly, orientation by spherical linear interpolation, and get
the matching linear and angular velocity. Joints of
the base mjcf model follow their keys linearly, and every base joint, keyed
or not, is driven kinematically: its qpos and qvel are set before each step
(held at qpos0 when it has no keys), so the robot follows the script exactly
and the cable's reaction does not push it around.

Before the first key and after the last one a target holds that key's pose.
This module does not step the simulation; the loop calls `apply` each step.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from sim.build import Built
from sim.scene import euler_matrix


def _quat(rot: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(rot).ravel())
    return q


def slerp(q0: np.ndarray, q1: np.ndarray, u: float) -> np.ndarray:
    """Unit quaternion between q0 (u = 0) and q1 (u = 1) along the short arc."""
    dot = float(np.dot(q0, q1))
    if dot < 0.0:
        q1, dot = -q1, -dot
    if dot > 0.9995:  # nearly parallel: normalised lerp avoids 0/0
        q = q0 + u * (q1 - q0)
        return q / np.linalg.norm(q)
    theta = np.arccos(dot)
    return (np.sin((1.0 - u) * theta) * q0 + np.sin(u * theta) * q1) / np.sin(theta)


@dataclass(frozen=True, eq=False)
class BodyTrack:
    """Keyframes of one scripted body. times (k,), pos (k, 3) metres, quat (k, 4)."""

    qpos_adr: int
    dof_adr: int
    times: np.ndarray
    pos: np.ndarray
    quat: np.ndarray

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """World position, quaternion, linear velocity (world) and angular
        velocity (body frame, as MuJoCo's free joint) at time t."""
        i = int(np.searchsorted(self.times, t, side="right")) - 1
        still = np.zeros(3)
        if i < 0:
            return self.pos[0], self.quat[0], still, still
        if i >= len(self.times) - 1:
            return self.pos[-1], self.quat[-1], still, still
        dt = self.times[i + 1] - self.times[i]
        u = (t - self.times[i]) / dt
        q0, q1 = self.quat[i], self.quat[i + 1]
        if np.dot(q0, q1) < 0.0:
            q1 = -q1
        omega = np.zeros(3)
        mujoco.mju_subQuat(omega, q1, q0)  # q0 * exp(omega) = q1, in q0's frame
        return (self.pos[i] + u * (self.pos[i + 1] - self.pos[i]), slerp(q0, q1, u),
                (self.pos[i + 1] - self.pos[i]) / dt, omega / dt)


@dataclass(frozen=True, eq=False)
class JointTrack:
    """Keyframes of one base-model joint: times (k,), values (k,) in MuJoCo units."""

    qpos_adr: int
    dof_adr: int
    times: np.ndarray
    values: np.ndarray

    def at(self, t: float) -> tuple[float, float]:
        """Joint value and velocity at time t."""
        value = float(np.interp(t, self.times, self.values))
        i = int(np.searchsorted(self.times, t, side="right")) - 1
        if i < 0 or i >= len(self.times) - 1:
            return value, 0.0
        return value, float((self.values[i + 1] - self.values[i]) / (self.times[i + 1] - self.times[i]))


class Motion:
    """All scripted targets of a built scene."""

    def __init__(self, built: Built):
        scene = built.scene
        self.bodies: list[BodyTrack] = []
        self.joints: list[JointTrack] = []
        keyed = set()
        for m in scene.motions:
            times = np.array([k.t for k in m.keys], float)
            if m.body is not None:
                pos = np.array([k.pos for k in m.keys], float) - built.origin
                quat = np.array([_quat(euler_matrix(k.euler)) for k in m.keys])
                self.bodies.append(BodyTrack(*built.free[m.body], times, pos, quat))
                keyed.add(m.body)
            else:
                drive = built.joints[m.joint]
                values = np.array([k.value for k in m.keys], float) * drive.scale
                self.joints.append(JointTrack(drive.qpos_adr, drive.dof_adr, times, values))
        for b in scene.bodies:
            if b.name not in keyed:
                self.bodies.append(BodyTrack(*built.free[b.name], np.zeros(1),
                                             np.array([b.pos], float) - built.origin,
                                             np.array([_quat(euler_matrix(b.euler))])))
        self.base_qpos_adr = built.base_qpos_adr
        self.base_dof_adr = built.base_dof_adr
        self.base_qpos0 = built.model.qpos0[built.base_qpos_adr].copy()

    def apply(self, data: mujoco.MjData, t: float, frozen: bool = False) -> None:
        """Put every scripted target at its time-t pose and velocity.

        `frozen`: hold the pose with zero velocity (settling before t = 0)."""
        for track in self.bodies:
            pos, quat, vel, omega = track.at(t)
            data.qpos[track.qpos_adr:track.qpos_adr + 3] = pos
            data.qpos[track.qpos_adr + 3:track.qpos_adr + 7] = quat
            data.qvel[track.dof_adr:track.dof_adr + 3] = 0.0 if frozen else vel
            data.qvel[track.dof_adr + 3:track.dof_adr + 6] = 0.0 if frozen else omega
        data.qpos[self.base_qpos_adr] = self.base_qpos0
        data.qvel[self.base_dof_adr] = 0.0
        for track in self.joints:
            data.qpos[track.qpos_adr], velocity = track.at(t)
            data.qvel[track.dof_adr] = 0.0 if frozen else velocity
