"""A compiled model read back as a `Built`: parts and their names, cables, joints.

Parts are the scene's `[[parts]]` and the mjcf model's colliding geoms, in
geom order, named `<body>/<geom name>`, else `<body>/<mesh name>`, else
`<body>/<type><k>`; the mjcf model's visual geoms are no parts (the
models leave most of them out, `cablecheck.scene.mjcf.lean_spec`; the
recording draws them all from the file compiled whole, `cablecheck.build.drawn`). Mesh parts carry MuJoCo's own vertices (MuJoCo recentres
and reorients meshes: the geom frame is MuJoCo's). Cables get their flex's
addresses and their routed shape written into qpos0; the base model's
hinge and slide joints become the script's `JointDrive`s.

This module does not write or compile models (see `cablecheck.build.mjspec`).
"""

from __future__ import annotations

import mujoco
import numpy as np

from cablecheck.build.built import CABLE_PREFIX, Built, EndRoll, JointDrive, PartModel, end_roll_body, vertex_body
from cablecheck.build.cableplan import CablePlan, cable_model
from cablecheck.scene.errors import SceneError
from cablecheck.scene.mjcf import SHAPES, body_name, geom_names
from cablecheck.scene.records import Scene


def mesh_arrays(m: mujoco.MjModel, g: int) -> tuple[np.ndarray | None, np.ndarray | None]:
    """MuJoCo's own vertices (geom frame) and faces of a mesh geom, else None, None."""
    if int(m.geom_type[g]) != int(mujoco.mjtGeom.mjGEOM_MESH):
        return None, None
    mid = int(m.geom_dataid[g])
    va, vn = int(m.mesh_vertadr[mid]), int(m.mesh_vertnum[mid])
    fa, fn = int(m.mesh_faceadr[mid]), int(m.mesh_facenum[mid])
    return m.mesh_vert[va:va + vn].astype(float).copy(), m.mesh_face[fa:fa + fn].astype(int).copy()


def _geom_parts(scene: Scene, m: mujoco.MjModel, own_bits: np.ndarray) -> list[PartModel]:
    """The scene's parts and the mjcf model's colliding geoms in model order;
    not the mjcf model's visual geoms (contype = conaffinity = 0 as written)
    that MuJoCo kept (some other element names them)."""
    scene_parts = {p.name: p for p in scene.parts}
    named: dict[int, tuple[str, str, bool]] = {}   # geom id -> (name, body, keepout)
    visual: set[int] = set()
    per_body: dict[tuple[int, bool], list[int]] = {}
    for g in range(m.ngeom):
        if int(m.geom_type[g]) not in SHAPES:
            continue  # heightfields and SDFs are not parts the checker knows
        gname = m.geom(g).name
        if gname in scene_parts:
            sp = scene_parts[gname]
            named[g] = (sp.name, sp.body, sp.keepout)
            continue
        if m.body(int(m.geom_bodyid[g])).name.startswith(CABLE_PREFIX):
            continue
        is_visual = not own_bits[g].any()
        if is_visual:
            visual.add(g)
        per_body.setdefault((int(m.geom_bodyid[g]), is_visual), []).append(g)
    for (bid, _), geoms in per_body.items():
        for g, name in zip(geoms, geom_names(m, geoms)):
            named[g] = (name, body_name(m, bid), False)
    parts, seen = [], {}
    for g in sorted(named):
        if g in visual:
            continue
        name, body, keepout = named[g]
        if name in seen:
            raise SceneError(scene.path, "parts", f"two parts are named {name!r} (a scene part and a "
                                                  f"geom of the mjcf model); rename the scene part")
        seen[name] = g
        verts, faces = mesh_arrays(m, g)
        gtype = int(m.geom_type[g])
        parts.append(PartModel(name, g, body, SHAPES[gtype], m.geom_size[g].copy(), verts, faces, keepout))
    return parts


def _model_skip(scene: Scene, m: mujoco.MjModel, parts: list[PartModel], own_bits: np.ndarray) -> np.ndarray:
    """(P, P) bool: part pairs MuJoCo is told never to collide, which the
    checker leaves out too: two geoms of the mjcf model whose own bits never
    meet as written ((type1 & aff2) | (type2 & aff1) == 0), and any two parts
    on a body pair of the model's `<contact><exclude>`. The parent-child and
    same-body filters are `cablecheck.run.stepcheck.part_pairs_skipped`'s."""
    scene_names = {p.name for p in scene.parts}
    gid = np.array([p.geom_id for p in parts], np.int64)
    base = np.array([p.name not in scene_names for p in parts], bool)
    ct, ca = own_bits[gid, 0], own_bits[gid, 1]
    meet = ((ct[:, None] & ca[None, :]) | (ca[:, None] & ct[None, :])) != 0
    skip = ~meet & base[:, None] & base[None, :]
    if m.nexclude:
        body = m.geom_bodyid[gid].astype(np.int64)
        sig = m.exclude_signature.astype(np.int64)
        pair = np.zeros((m.nbody, m.nbody), bool)
        pair[sig >> 16, sig & 0xFFFF] = True
        pair |= pair.T
        skip |= pair[body[:, None], body[None, :]]
    return skip


def read_built(scene: Scene, m: mujoco.MjModel, det: mujoco.MjModel | None,
            plans: list[CablePlan], origin: np.ndarray, own_bits: np.ndarray) -> Built:
    parts = _geom_parts(scene, m, own_bits)
    model_skip = _model_skip(scene, m, parts, own_bits)
    cables = []
    qpos0 = m.qpos0.copy()
    for plan in plans:
        c = plan.cable
        fid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_FLEX, f"{CABLE_PREFIX}{c.name}")
        n = len(plan.routed)
        for v in range(n):
            # by MuJoCo's name table (m.body(name) searched 27 us a vertex: a fifth of a second for
            # a harness's 2,752)
            bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, vertex_body(c.name, v))
            if bid < 0:
                continue  # pinned to the world
            ja = int(m.body_jntadr[bid])
            # The three slides run along the parent's (the world's) x, y, z axes.
            qpos0[m.jnt_qposadr[ja:ja + 3]] += plan.routed[v] - plan.straight[v]
        cables.append(cable_model(plan, fid, int(m.flex_vertadr[fid]), origin))

    scene_bodies = {b.name for b in scene.bodies}
    free = {}
    for b in scene_bodies:
        j = int(m.body_jntadr[m.body(b).id])
        free[b] = (int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j]))
    body_ids = {"world": 0}
    for i in range(1, m.nbody):
        name = m.body(i).name
        if name and not name.startswith(CABLE_PREFIX):
            body_ids[name] = i
    base_joints = [j for j in range(m.njnt) if not m.joint(j).name.startswith(CABLE_PREFIX)
                   and not m.body(int(m.jnt_bodyid[j])).name.startswith(CABLE_PREFIX)
                   and m.body(int(m.jnt_bodyid[j])).name not in scene_bodies]
    qadr_list, dadr_list, joints = [], [], {}
    nq_of = {int(mujoco.mjtJoint.mjJNT_FREE): 7, int(mujoco.mjtJoint.mjJNT_BALL): 4}
    nv_of = {int(mujoco.mjtJoint.mjJNT_FREE): 6, int(mujoco.mjtJoint.mjJNT_BALL): 3}
    for j in base_joints:
        jt = int(m.jnt_type[j])
        qa, da = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
        qadr_list += range(qa, qa + nq_of.get(jt, 1))
        dadr_list += range(da, da + nv_of.get(jt, 1))
        name = m.joint(j).name
        if name and jt in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            scale = np.pi / 180.0 if jt == int(mujoco.mjtJoint.mjJNT_HINGE) else scene.scale
            joints[name] = JointDrive(name, jt, qa, da, scale)
    rolls = []
    for c in cables:
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, end_roll_body(c.name))
        if j >= 0:
            rolls.append(EndRoll(c.name, int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])))
    return Built(scene, m, det, cables, parts, free, body_ids,
                 np.array(qadr_list, int), np.array(dadr_list, int), joints, qpos0, origin,
                 model_skip=model_skip, end_rolls=tuple(rolls))
