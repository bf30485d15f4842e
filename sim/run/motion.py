"""Scripted motion: the scene's trajectories, interpolated in time and applied to the model.

Every `[[motion]]` arrives as a `Trajectory` (keys, the model's keyframes or
a CSV file, in MuJoCo units on scene time). Its channels are interpolated
by `cablecheck.run.curves` ("cubic": shape-preserving, continuous velocity; "linear"),
and all channels of all motions are merged into one `Curve`, so a step
evaluates every joint and body at once (two vectorised polynomial
evaluations, no loop over joints).

- Joints of the base mjcf model are driven kinematically: before each step
  every base joint's qpos and qvel are set (the velocity is the derivative
  of the interpolant), so the robot follows the script exactly and the
  cable's reaction does not push it around. Joints without a motion hold the
  model's own `qpos0` (MuJoCo's reference pose, the joints' `ref`).
- `[[bodies]]` (free bodies in MuJoCo) follow their positions and euler
  angles. Each angle is a channel of its own, interpolated as the numbers
  are written (keys 0, 270, -270 turn +270 degrees, then 540 back: no
  wrapping, no short way, no slerp), and only then turned into the body's
  quaternion, at each time; the angular velocity handed to MuJoCo is the
  body-frame rate of those angles. A body without a motion holds its
  `[[bodies]]` pose.

Before its first sample and after its last one a motion holds that sample.
This module does not step the simulation; the loop calls `apply` each step.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from cablecheck.build.built import Built, JointDrive
from cablecheck.run.curves import Curve, interpolant, merge


def body_rate(euler, rate) -> tuple[float, float, float]:
    """Body-frame angular velocity of the rotation Rx(a) Ry(b) Rz(c) (MuJoCo's
    intrinsic x-y-z euler sequence) at angles `euler` (3,) changing at `rate`
    (3,), radians and radians per second:
    omega = Rz^T Ry^T (a' e_x) + Rz^T (b' e_y) + c' e_z."""
    _, b, c = euler
    da, db, dc = rate
    cb, sb, cc, sc = math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    return (da * cb * cc + db * sc, db * cc - da * cb * sc, da * sb + dc)


def moving_joints(scene) -> tuple[str, ...]:
    """Names of the mjcf joints whose scripted value changes, in motion order."""
    return tuple(j for m in scene.motions
                 for j, values in zip(m.trajectory.joints, m.trajectory.joint_values.T)
                 if np.ptp(values) > 0)


class Motion:
    """All scripted targets of a built scene, merged into one curve.

    Attributes:
      curve: every channel: driven joints' values (MuJoCo units), then each
        body's position (model coordinates, metres) and euler angles (radians).
      joints: the driven joints, in channel order.
      bodies: names of the `[[bodies]]`, in channel order (scripted or held).
      moving: names of the driven joints whose value changes over the script.
    """

    def __init__(self, built: Built):
        scene = built.scene
        polys, samples, joints, bodies = [], [], [], []
        for m in scene.motions:
            tr = m.trajectory
            n = len(tr.times)
            columns = np.hstack([tr.joint_values, (tr.body_pos - built.origin).reshape(n, -1),
                                 np.radians(tr.body_euler).reshape(n, -1)])
            polys.append(interpolant(tr.times, columns, tr.interpolation))
            samples.append(columns)
            joints.append([built.joints[j] for j in tr.joints])
            bodies.append(list(tr.bodies))
        driven = {b for names in bodies for b in names}
        for b in scene.bodies:
            if b.name not in driven:
                pose = np.concatenate([np.asarray(b.pos, float) - built.origin, np.radians(b.euler)])
                polys.append(interpolant(np.zeros(1), pose[None, :], "linear"))
                samples.append(pose[None, :])
                joints.append([])
                bodies.append([b.name])
        if not polys:
            polys.append(interpolant(np.zeros(1), np.zeros((1, 0)), "linear"))
            samples.append(np.zeros((1, 0)))
        merged = merge(polys, samples)
        # Channel order in the merged curve: per motion [joints, body pos, body euler];
        # gather the indices of each kind once, so apply() indexes arrays.
        joint_idx, pos_idx, rot_idx = [], [], []
        offset = 0
        for js, bs in zip(joints, bodies):
            joint_idx += range(offset, offset + len(js))
            offset += len(js)
            pos_idx += [range(offset + 3 * k, offset + 3 * k + 3) for k in range(len(bs))]
            offset += 3 * len(bs)
            rot_idx += [range(offset + 3 * k, offset + 3 * k + 3) for k in range(len(bs))]
            offset += 3 * len(bs)
        self.curve: Curve = merged
        self.joints: list[JointDrive] = [j for js in joints for j in js]
        self.bodies: list[str] = [b for bs in bodies for b in bs]
        self.moving: tuple[str, ...] = moving_joints(scene)
        self._joint_idx = np.array(joint_idx, int)
        self._pos_idx = np.array(pos_idx, int).reshape(-1, 3)
        self._rot_idx = np.array(rot_idx, int).reshape(-1, 3)
        self._joint_qadr = np.array([j.qpos_adr for j in self.joints], int)
        self._joint_dadr = np.array([j.dof_adr for j in self.joints], int)
        free = np.array([built.free[b] for b in self.bodies], int).reshape(-1, 2)
        self._body_qadr = free[:, :1] + np.arange(7)     # (B, 7): position, quaternion
        self._body_dadr = free[:, 1:] + np.arange(6)     # (B, 6): linear, angular velocity
        self._quat = np.zeros(4)
        self.base_qpos_adr = built.base_qpos_adr
        self.base_dof_adr = built.base_dof_adr
        self.base_qpos0 = built.model.qpos0[built.base_qpos_adr].copy()
        # the clamped ends' hinges, held where they start their cables untwisted (cablecheck.build.untwist)
        self._roll_qadr = np.array([r.qpos_adr for r in built.end_rolls], int)
        self._roll_dadr = np.array([r.dof_adr for r in built.end_rolls], int)
        self._roll = np.array([r.angle for r in built.end_rolls], float)

    def joint_values(self, times: np.ndarray, names: list[str]) -> np.ndarray:
        """(m, J) scripted values (MuJoCo units) of the driven joints `names` at `times` (m,)."""
        channel = {j.name: int(k) for j, k in zip(self.joints, self._joint_idx)}
        return self.curve.sample(times)[:, [channel[n] for n in names]]

    def apply(self, data: mujoco.MjData, t: float, frozen: bool = False) -> None:
        """Put every scripted target at its time-t pose and velocity.

        `frozen`: hold the pose with zero velocity (settling before t = 0)."""
        value, rate = self.curve.at(t)
        if frozen:
            rate = np.zeros_like(rate)
        self.apply_values(data, value, rate)

    def apply_values(self, data: mujoco.MjData, value: np.ndarray, rate: np.ndarray) -> None:
        """Put every scripted target at `value` with `rate` (one time's
        `Curve.at`, or a row of `Curve.at_many`: the loop evaluates a block
        of steps' times at once)."""
        data.qpos[self.base_qpos_adr] = self.base_qpos0
        data.qvel[self.base_dof_adr] = 0.0
        data.qpos[self._roll_qadr] = self._roll
        data.qvel[self._roll_dadr] = 0.0
        data.qpos[self._joint_qadr] = value[self._joint_idx]
        data.qvel[self._joint_dadr] = rate[self._joint_idx]
        if len(self.bodies):
            qpos, qvel = data.qpos, data.qvel
            qpos[self._body_qadr[:, :3]] = value[self._pos_idx]
            qvel[self._body_dadr[:, :3]] = rate[self._pos_idx]
            euler, euler_rate = value[self._rot_idx], rate[self._rot_idx]
            # A handful of scripted bodies: MuJoCo's own euler conversion per body
            # costs less than numpy's per-call overhead on 3-vectors would.
            for k in range(len(self.bodies)):
                mujoco.mju_euler2Quat(self._quat, euler[k], "xyz")
                qpos[self._body_qadr[k, 3:]] = self._quat
                qvel[self._body_dadr[k, 3:]] = body_rate(euler[k], euler_rate[k])
