"""A motion's samples in MuJoCo units on scene time (`Trajectory`): from
keys (values, poses or the mjcf model's keyframes), with every joint sample
checked against its joint's range.

Both interpolations (`cablecheck.run.curves`) stay between neighbouring samples, so
the samples bound the whole motion. Reading the `[[motion]]` table and its
CSV file is `cablecheck.scene.motion`'s; playing the motion, `cablecheck.run.motion`'s.
"""

from __future__ import annotations

import mujoco
import numpy as np

from cablecheck.scene.errors import fmt
from cablecheck.scene.format import ANGLES
from cablecheck.scene.mjcf import HINGE
from cablecheck.scene.reader import Reader
from cablecheck.scene.records import KeyframeKey, Trajectory


def make_trajectory(times, joints, values, bodies, pos, euler, interpolation) -> Trajectory:
    """A read-only Trajectory. Euler angles stay as written, never wrapped
    nor unwrapped: keys 0, 270, -270 turn 270 degrees one way, then 540 back
    (a turntable, a rotary axis or a cable drum may turn past 180 degrees
    between two samples)."""
    arrays = [np.array(a, float) for a in (times, values, pos, euler)]
    for a in arrays:
        a.setflags(write=False)
    times, values, pos, euler = arrays
    return Trajectory(times=times, joints=tuple(joints), joint_values=values,
                      bodies=tuple(bodies), body_pos=pos, body_euler=euler,
                      interpolation=interpolation)


def keyframe_qpos(r: Reader, name: str, where: str) -> np.ndarray:
    """The qpos of keyframe `name`; it may move only named hinge and slide joints."""
    model = r.mjcf.model
    qpos = model.key_qpos[r.mjcf.keyframes[name]]
    driven = {r.mjcf.joints[j] for j in r.mjcf.driven_joints()}
    sizes = {int(mujoco.mjtJoint.mjJNT_FREE): 7, int(mujoco.mjtJoint.mjJNT_BALL): 4}
    for j in range(model.njnt):
        if j in driven:
            continue
        a = int(model.jnt_qposadr[j])
        n = sizes.get(int(model.jnt_type[j]), 1)
        if not np.allclose(qpos[a:a + n], model.qpos0[a:a + n], rtol=0.0, atol=1e-12):
            body = model.body(int(model.jnt_bodyid[j])).name
            label = model.joint(j).name or f"#{j} (unnamed, on body {body!r})"
            raise r.error(where, f"keyframe {name!r} moves joint {label}; only named hinge "
                                 "and slide joints are driven")
    return qpos


def joint_scale(r: Reader, joint: str, angles: str) -> float:
    """Multiplies a written value of `joint` into MuJoCo units."""
    hinge = int(r.mjcf.model.jnt_type[r.mjcf.joints[joint]]) == HINGE
    return ANGLES[angles] if hinge else r.scale


def keys_trajectory(r: Reader, keys: tuple, body: str | None, joint: str | None, where: str,
                    angles: str, interpolation: str, time_scale: float) -> Trajectory:
    """The samples of a motion's keys, in MuJoCo units on scene time."""
    times = np.array([k.t for k in keys], float) / time_scale
    none = np.zeros((len(keys), 0))
    if body is not None:
        pos = np.array([k.pos for k in keys], float)[:, None, :]
        euler = np.array([k.euler for k in keys], float)[:, None, :]
        return make_trajectory(times, (), none, (body,), pos, euler, interpolation)
    joints = (joint,) if joint is not None else tuple(r.mjcf.driven_joints())
    adr = r.mjcf.model.jnt_qposadr[[r.mjcf.joints[j] for j in joints]]
    values = np.zeros((len(keys), len(joints)))
    for i, k in enumerate(keys):
        if isinstance(k, KeyframeKey):
            values[i] = keyframe_qpos(r, k.key, f"{where}.keys[{i}].key")[adr]
        else:
            values[i] = k.value * joint_scale(r, joint, angles)
    no_bodies = np.zeros((len(keys), 0, 3))
    trajectory = make_trajectory(times, joints, values, (), no_bodies, no_bodies, interpolation)
    check_ranges(r, trajectory, angles, lambda i: (
        f"{where}.keys[{i}].{'key' if isinstance(keys[i], KeyframeKey) else 'value'}",
        f"t = {fmt(keys[i].t)} s"))
    return trajectory


def check_ranges(r: Reader, trajectory: Trajectory, angles: str, sample) -> None:
    """Every joint sample inside its joint's range, when the joint is
    limited. `sample(i)` gives (key path, "where in the source") of sample i.
    The interpolants stay between neighbouring samples (`cablecheck.run.curves`), so
    the samples bound the whole motion."""
    model = r.mjcf.model if r.mjcf else None
    for j, name in enumerate(trajectory.joints):
        jid = r.mjcf.joints[name]
        if not model.jnt_limited[jid]:
            continue
        lo, hi = (float(v) for v in model.jnt_range[jid])
        tol = 1e-9 * max(1.0, abs(lo), abs(hi))
        values = trajectory.joint_values[:, j]
        out = np.flatnonzero((values < lo - tol) | (values > hi + tol))
        if not len(out):
            continue
        i = out[0]
        hinge = int(model.jnt_type[jid]) == HINGE
        unit = angles if hinge else r.unit_name()
        per = ANGLES[angles] if hinge else r.scale
        key, source = sample(i)
        raise r.error(key, f"{source}: joint {name!r} at {fmt(values[i] / per)} {unit} is "
                           f"outside its range {fmt(lo / per)}..{fmt(hi / per)} {unit}")
