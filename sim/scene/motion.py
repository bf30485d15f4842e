"""`[[motion]]`: what a motion drives (a `[[bodies]]` body, a joint of the
mjcf model, the model's keyframes, or the columns of a CSV file) and its keys.

The samples become a `Trajectory` in `cablecheck.scene.trajectory`; the CSV file
is read by `cablecheck.scene.samples`. Every sample of a joint with a range must
lie in it.
"""

from __future__ import annotations

import difflib
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from cablecheck.scene.errors import SceneError, describe, fmt
from cablecheck.scene.format import (
    ANGLES,
    BODY_AXES,
    BODY_KEY_KEYS,
    INTERPOLATIONS,
    JOINT_KEY_KEYS,
    MOTION_KEYS,
)
from cablecheck.scene.mjcf import DRIVEN
from cablecheck.scene.reader import Reader
from cablecheck.scene.records import BodyDef, BodyKey, JointKey, KeyframeKey, MotionDef, Trajectory
from cablecheck.scene.samples import read_samples
from cablecheck.scene.trajectory import check_ranges, joint_scale, keys_trajectory, make_trajectory


def read_motion(r: Reader, value: dict, where: str, bodies: dict[str, BodyDef]) -> MotionDef:
    """A `[[motion]]` entry with its samples as a `Trajectory`."""
    t = r.table(value, where, MOTION_KEYS)
    targets = [k for k in ("body", "joint", "file") if k in t]
    if "file" in t and "keys" in t:
        raise r.error(f"{where}.keys", "not allowed with 'file' (the file holds "
                                       "the samples)")
    if "file" not in t and "keys" not in t:
        raise r.error(f"{where}.keys", "missing (required unless 'file' gives "
                                       "the samples)")
    keys_raw = t.get("keys", [])
    if "keys" in t:
        if (not isinstance(keys_raw, list)
                or not all(isinstance(k, dict) for k in keys_raw)):
            raise r.error(f"{where}.keys", f"expected an array of tables "
                                           f"({{ t = ..., ... }}), got {describe(keys_raw)}")
        if not keys_raw:
            raise r.error(f"{where}.keys", "empty: give at least one keyframe")
    keyframes_only = not targets and all("key" in k for k in keys_raw)
    if len(targets) > 1 or not (targets or keyframes_only):
        raise r.error(where, "give exactly one of 'body' (a [[bodies]] name), 'joint' "
                             "(a joint of the mjcf model) and 'file' (a CSV file of "
                             "samples), or keys that all name keyframes of the mjcf "
                             "model ({ t = ..., key = \"home\" })")
    interpolation = r.string(t.get("interpolation", INTERPOLATIONS[0]),
                             f"{where}.interpolation", INTERPOLATIONS)
    time_scale = r.number(t.get("time_scale", 1.0), f"{where}.time_scale", positive=True)
    if "angles" in t and "body" in t:
        raise r.error(f"{where}.angles", "not used by a body's motion (its euler "
                                         "angles are degrees, as in [[bodies]])")
    angles = r.string(t.get("angles", "deg"), f"{where}.angles", tuple(ANGLES))
    body = joint = file = None
    keys: tuple = ()
    if "body" in t:
        body = motion_body(r, t["body"], f"{where}.body", bodies)
        home = bodies[body]
        keys = tuple(read_body_key(r, k, f"{where}.keys[{i}]", home)
                     for i, k in enumerate(keys_raw))
    elif "joint" in t:
        joint = motion_joint(r, t["joint"], f"{where}.joint")
        keys = tuple(read_joint_key(r, k, f"{where}.keys[{i}]") for i, k in enumerate(keys_raw))
    elif keyframes_only:
        if r.mjcf is None:
            raise r.error(f"{where}.keys[0].key", "no mjcf model in [scene]; "
                                                  "keyframes come from it")
        keys = tuple(read_joint_key(r, k, f"{where}.keys[{i}]") for i, k in enumerate(keys_raw))
    for i in range(1, len(keys)):
        if keys[i].t <= keys[i - 1].t:
            raise r.error(f"{where}.keys[{i}].t",
                          f"times must increase strictly: {fmt(keys[i].t)} after "
                          f"{fmt(keys[i - 1].t)}")
    if "file" in t:
        file = r.file_path(t["file"], f"{where}.file")
        trajectory = file_trajectory(r, file, t["file"], where, bodies, angles,
                                        interpolation, time_scale)
    else:
        trajectory = keys_trajectory(r, keys, body, joint, where, angles, interpolation,
                                        time_scale)
    return MotionDef(body=body, joint=joint, keys=keys, file=file, angles=angles,
                     interpolation=interpolation, time_scale=time_scale,
                     trajectory=trajectory)


def motion_body(r: Reader, value: Any, where: str, bodies: dict[str, BodyDef]) -> str:
    """A body a motion may drive: a [[bodies]] body."""
    body = r.name(value, where)
    if body not in bodies:
        if body == "world":
            problem = "the world frame cannot move"
        elif r.mjcf and body in r.mjcf.bodies:
            problem = (f"{body!r} is a body of the mjcf model, which cannot be "
                       "keyframed by pose; drive its joints (joint = ...)")
        else:
            problem = f"no [[bodies]] entry named {body!r}"
        raise r.error(where, problem)
    return body


def motion_joint(r: Reader, value: Any, where: str) -> str:
    """A joint a motion may drive: a hinge or slide joint of the mjcf model."""
    joint = r.name(value, where)
    if r.mjcf is None:
        raise r.error(where, "no mjcf model in [scene]; joints come from it")
    if joint not in r.mjcf.joints:
        close = difflib.get_close_matches(joint, list(r.mjcf.joints), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise r.error(where, f"no joint named {joint!r} in the mjcf model{hint}")
    kind = int(r.mjcf.model.jnt_type[r.mjcf.joints[joint]])
    if kind not in DRIVEN:
        raise r.error(where, f"{joint!r} is a {mujoco.mjtJoint(kind).name[6:].lower()} "
                             "joint; only hinge and slide joints are driven by a value")
    return joint


def read_body_key(r: Reader, value: dict, where: str, home: BodyDef) -> BodyKey:
    """A keyframe of a body; pos and euler default to the body's `[[bodies]]` pose."""
    t = r.table(value, where, BODY_KEY_KEYS, ("t",))
    return BodyKey(t=r.number(t["t"], f"{where}.t", nonnegative=True),
                   pos=r.position(t["pos"], f"{where}.pos") if "pos" in t else home.pos,
                   euler=(r.vector(t["euler"], f"{where}.euler") if "euler" in t
                          else home.euler))


def read_joint_key(r: Reader, value: dict, where: str) -> JointKey | KeyframeKey:
    """A keyframe of a joint: a value, or a keyframe of the mjcf model by name."""
    t = r.table(value, where, JOINT_KEY_KEYS, ("t",))
    time = r.number(t["t"], f"{where}.t", nonnegative=True)
    if ("value" in t) == ("key" in t):
        raise r.error(f"{where}.value" if "value" not in t else where,
                      "missing (required unless 'key' names a keyframe of the mjcf "
                      "model)" if "value" not in t else "give 'value' or 'key', not both")
    if "value" in t:
        return JointKey(t=time, value=r.number(t["value"], f"{where}.value"))
    name = r.name(t["key"], f"{where}.key")
    if r.mjcf is None:
        raise r.error(f"{where}.key", "no mjcf model in [scene]; keyframes come from it")
    if name not in r.mjcf.keyframes:
        known = sorted(r.mjcf.keyframes)
        raise r.error(f"{where}.key", f"no keyframe named {name!r} in the mjcf model "
                                      f"(known: {', '.join(known) or 'none'})")
    return KeyframeKey(t=time, key=name)


def file_trajectory(r: Reader, path: Path, written: str, where: str, bodies: dict[str, BodyDef],
                    angles: str, interpolation: str, time_scale: float) -> Trajectory:
    """The samples of a CSV motion file (see `read_samples`)."""
    where = f"{where}.file"
    header, table, lines = read_samples(r.file, path, written, where)
    joints: list[str] = []
    body_axes: dict[str, dict[str, int]] = {}
    for c, name in enumerate(header[1:], start=1):
        body, _, axis = name.rpartition(".")
        try:
            if r.mjcf is not None and name in r.mjcf.joints:
                joints.append(motion_joint(r, name, where))
                continue
            if body and axis in BODY_AXES:
                motion_body(r, body, where, bodies)
                body_axes.setdefault(body, {})[axis] = c
                continue
        except SceneError as e:
            raise r.error(where, f"{written} column {name!r}: {e.problem}") from None
        known = sorted(r.mjcf.joints if r.mjcf else []) + [
            f"{b}.{a}" for b in bodies for a in BODY_AXES]
        close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise r.error(where, f"{written} column {name!r}: neither a joint of the mjcf "
                             f"model nor <body>.x/.y/.z/.rx/.ry/.rz of a [[bodies]] "
                             f"body{hint}")
    n = len(table)
    columns = [header.index(j) for j in joints]
    values = table[:, columns] * np.array([joint_scale(r, j, angles) for j in joints])
    names = tuple(body_axes)
    pos = np.zeros((n, len(names), 3))
    euler = np.zeros((n, len(names), 3))
    for b, (name, axes) in enumerate(body_axes.items()):
        home = bodies[name]
        for k, axis in enumerate(BODY_AXES):
            target, index = (pos, k) if k < 3 else (euler, k - 3)
            default = home.pos[k] if k < 3 else home.euler[k - 3]
            target[:, b, index] = (table[:, axes[axis]] * (r.scale if k < 3 else 1.0)
                                   if axis in axes else default)
    times = table[:, 0] / time_scale
    trajectory = make_trajectory(times, tuple(joints), values, names, pos, euler, interpolation)
    check_ranges(r, trajectory, angles, lambda i: (
        where, f"{written} line {lines[i]}, t = {fmt(table[i, 0])} s"))
    return trajectory
