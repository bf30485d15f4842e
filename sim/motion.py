"""Scripted motion: keyframes interpolated in time and applied to the model.

Bodies (`[[bodies]]`, mocap in MuJoCo) follow their keys' world poses:
position linearly, orientation by spherical linear interpolation. Joints of
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
    """Keyframes of one mocap body. times (k,), pos (k, 3) metres, quat (k, 4)."""

    mocap_id: int
    times: np.ndarray
    pos: np.ndarray
    quat: np.ndarray

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """World position and quaternion at time t."""
        i = int(np.searchsorted(self.times, t, side="right")) - 1
        if i < 0:
            return self.pos[0], self.quat[0]
        if i >= len(self.times) - 1:
            return self.pos[-1], self.quat[-1]
        u = (t - self.times[i]) / (self.times[i + 1] - self.times[i])
        return (self.pos[i] + u * (self.pos[i + 1] - self.pos[i]),
                slerp(self.quat[i], self.quat[i + 1], u))


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
                pos = np.array([k.pos for k in m.keys], float)
                quat = np.array([_quat(euler_matrix(k.euler)) for k in m.keys])
                self.bodies.append(BodyTrack(built.mocap[m.body], times, pos, quat))
                keyed.add(m.body)
            else:
                drive = built.joints[m.joint]
                values = np.array([k.value for k in m.keys], float) * drive.scale
                self.joints.append(JointTrack(drive.qpos_adr, drive.dof_adr, times, values))
        for b in scene.bodies:
            if b.name not in keyed:
                self.bodies.append(BodyTrack(built.mocap[b.name], np.zeros(1),
                                             np.array([b.pos], float),
                                             np.array([_quat(euler_matrix(b.euler))])))
        self.base_qpos_adr = built.base_qpos_adr
        self.base_dof_adr = built.base_dof_adr
        self.base_qpos0 = built.model.qpos0[built.base_qpos_adr].copy()

    def apply(self, data: mujoco.MjData, t: float) -> None:
        """Put every scripted target at its time-t pose (and velocity for joints)."""
        for track in self.bodies:
            data.mocap_pos[track.mocap_id], data.mocap_quat[track.mocap_id] = track.at(t)
        data.qpos[self.base_qpos_adr] = self.base_qpos0
        data.qvel[self.base_dof_adr] = 0.0
        for track in self.joints:
            data.qpos[track.qpos_adr], data.qvel[track.dof_adr] = track.at(t)

    @property
    def is_static(self) -> bool:
        """True when nothing moves after t = 0."""
        return all(len(t.times) == 1 for t in self.bodies) and not self.joints
