"""The base MuJoCo model of a scene (`[scene] mjcf`): compiled once, to know
its bodies, joints and keyframes, and which of its joints a motion drives.

`base_model` keeps the compiled file for the process (while the file is
unchanged), so the droop's obstacles (`cablecheck.build.obstacles`) read the same model
instead of compiling it again. The builder compiles the file again into its
own models (`cablecheck.build.stages`); nothing here builds a simulation or moves the
model (the frames at t = 0: `cablecheck.scene.frames`).

Every model made from the file leaves out what MuJoCo only draws
(`lean_spec`: MuJoCo's own `discard_visual`, the compiler's
`discardvisual`): geoms that never collide and nothing refers to, the
meshes only they use, materials and textures, a body's mass kept where
it came from them. A robot's visual meshes are most of what compiling it
costs (robosuite's Panda 0.61 s, 0.01 s without its 50 visual meshes;
UR5e 0.57, Sawyer 0.65), and neither the checks nor the simulation use
them; the recording draws them from the file compiled whole
(`cablecheck.build.drawn`).
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

SHAPES = {int(mujoco.mjtGeom.mjGEOM_PLANE): "plane", int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere",
           int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule", int(mujoco.mjtGeom.mjGEOM_ELLIPSOID): "ellipsoid",
           int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder", int(mujoco.mjtGeom.mjGEOM_BOX): "box",
           int(mujoco.mjtGeom.mjGEOM_MESH): "mesh"}
"""Geom types that are parts (the checker's shapes), by MuJoCo type: heightfields and SDFs are not."""


@dataclass(frozen=True)
class MjcfInfo:
    """What the loader needs of the base mjcf model."""

    model: mujoco.MjModel
    bodies: dict[str, int]   # name -> body id
    joints: dict[str, int]   # name -> joint id
    keyframes: dict[str, int]   # name -> keyframe id
    parts: tuple[str, ...] = ()   # the colliding geoms' part names, as the builder names them

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
    return MjcfInfo(model=model, bodies=bodies, joints=joints, keyframes=keyframes,
                    parts=tuple(colliding_parts(model).values()))


def base_model(path: Path) -> mujoco.MjModel:
    """The model the mjcf file `path` compiles to, compiled once per process
    while the file keeps its content and modification time (`compile_mjcf`
    and `cablecheck.build.obstacles` share it). Shared: read it, never change it."""
    path = Path(path).resolve()
    digest = hashlib.blake2b(path.read_bytes(), digest_size=16).digest()
    return _compiled(str(path), path.stat().st_mtime_ns, digest)


@lru_cache(maxsize=8)
def _compiled(path: str, mtime_ns: int, digest: bytes) -> mujoco.MjModel:
    return lean_spec(Path(path)).compile()


def lean_spec(path: Path) -> mujoco.MjSpec:
    """The mjcf file `path` as an MjSpec without what MuJoCo only draws
    (module docstring): `MjSpec.discard_visual`, which keeps a geom some
    other element names (a contact pair, a sensor) and gives a body whose
    mass came from a discarded geom that mass as an explicit inertial.
    Under `<compiler inertiafromgeom="true">` MuJoCo cannot keep it so,
    and the spec stays whole. Raises what MuJoCo raises for a file it
    cannot read."""
    spec = mujoco.MjSpec.from_file(str(path))
    if spec.compiler.inertiafromgeom != mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE:
        spec.discard_visual()
    return spec


def body_name(m: mujoco.MjModel, bid: int) -> str:
    return m.body(bid).name or ("world" if bid == 0 else f"body{bid}")


def geom_names(m: mujoco.MjModel, geoms: list[int]) -> list[str]:
    """Names of one body's geoms (all colliding, or all visual), in model order:
    `<body>/<geom name>`, else `<body>/<mesh name>`, else `<body>/<type><k>`
    with k the geom's index among `geoms`; names that would repeat within the
    body fall back to `<type><k>` for each of them. Counting within the
    colliding geoms only keeps part names when visual geoms come or go."""
    if not geoms:
        return []
    bname = body_name(m, int(m.geom_bodyid[geoms[0]]))
    own = []
    for g in geoms:
        name = m.geom(g).name
        if not name and int(m.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_MESH):
            name = m.mesh(int(m.geom_dataid[g])).name
        own.append(name)
    counts: dict[str, int] = {}
    for name in own:
        counts[name] = counts.get(name, 0) + 1
    return [f"{bname}/{name}" if name and counts[name] == 1 else f"{bname}/{SHAPES[int(m.geom_type[g])]}{k}"
            for k, (g, name) in enumerate(zip(geoms, own))]


def colliding_parts(m: mujoco.MjModel) -> dict[int, str]:
    """Geom id -> part name of the model's colliding geoms (contype or conaffinity written non-zero, a
    type in `SHAPES`), in geom order, named as the builder names them (`geom_names`, per body)."""
    per_body: dict[int, list[int]] = {}
    for g in range(m.ngeom):
        if int(m.geom_type[g]) in SHAPES and (m.geom_contype[g] != 0 or m.geom_conaffinity[g] != 0):
            per_body.setdefault(int(m.geom_bodyid[g]), []).append(g)
    named = {g: n for geoms in per_body.values() for g, n in zip(geoms, geom_names(m, geoms))}
    return dict(sorted(named.items()))
