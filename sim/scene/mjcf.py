"""The base MuJoCo model of a scene (`[scene] mjcf`): compiled once, to know
its bodies, joints and keyframes, and which of its joints a motion drives.

`base_model` keeps the compiled file for the process (while the file is
unchanged), so the droop's obstacles (`cablecheck.build.obstacles`) read the same model
instead of compiling it again. The builder compiles the file again into its
own models (`cablecheck.build.stages`); nothing here builds a simulation or moves the
model (the frames at t = 0: `cablecheck.scene.frames`).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import mujoco

from cablecheck.scene.errors import SceneError

HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)
DRIVEN = (HINGE, int(mujoco.mjtJoint.mjJNT_SLIDE))
"""Joint types a motion drives by a value: hinge and slide."""


@dataclass(frozen=True)
class MjcfInfo:
    """What the loader needs of the base mjcf model."""

    model: mujoco.MjModel
    bodies: dict[str, int]   # name -> body id
    joints: dict[str, int]   # name -> joint id
    keyframes: dict[str, int]   # name -> keyframe id

    def driven_joints(self) -> list[str]:
        """Named hinge and slide joints, in model order."""
        return [name for name, j in sorted(self.joints.items(), key=lambda item: item[1])
                if int(self.model.jnt_type[j]) in DRIVEN]


def compile_mjcf(file: Path, path: Path) -> MjcfInfo:
    """Compile the model `path` named by scene `file`; a failure is the file's (`scene.mjcf`)."""
    try:
        model = base_model(path)
    except Exception as e:   # MuJoCo raises ValueError; any failure is the file's
        message = " ".join(str(e).split())
        raise SceneError(file, "scene.mjcf", f"MuJoCo cannot compile {path.name}: "
                                             f"{message}") from None
    bodies = {model.body(i).name: i for i in range(model.nbody) if model.body(i).name}
    joints = {model.joint(i).name: i for i in range(model.njnt) if model.joint(i).name}
    keyframes = {model.key(i).name: i for i in range(model.nkey) if model.key(i).name}
    return MjcfInfo(model=model, bodies=bodies, joints=joints, keyframes=keyframes)


def base_model(path: Path) -> mujoco.MjModel:
    """The model the mjcf file `path` compiles to, compiled once per process
    while the file keeps its content and modification time (`compile_mjcf`
    and `cablecheck.build.obstacles` share it). Shared: read it, never change it."""
    path = Path(path).resolve()
    digest = hashlib.blake2b(path.read_bytes(), digest_size=16).digest()
    return _compiled(str(path), path.stat().st_mtime_ns, digest)


@lru_cache(maxsize=8)
def _compiled(path: str, mtime_ns: int, digest: bytes) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(path)
