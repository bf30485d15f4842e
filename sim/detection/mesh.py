"""Concave mesh parts seen by the detection model as their true surface.

MuJoCo collides a mesh geom as its convex hull (computation chapter,
"Convex decomposition"), so a cable in a concave mesh's pocket or notch
touches the hull where the checker, which checks the mesh itself, finds it
clear. The detection model (see `cablecheck.build.stages`) is never stepped: it only has
to see the geometry the checker checks. There, each colliding mesh geom
that is not convex is joined by rigid flexes of its triangles (every vertex
on the geom's body: MuJoCo's documented way to collide a general
non-convex mesh, XMLreference "flex/body"), and the geom itself stops
meeting the cables, so a cable's contacts with that part are flex-flex
contacts with the mesh's own triangles, margin contacts included (the
detection model collides nothing but the cables, `cablecheck.build.contactbits`,
so the geom itself then meets nothing).

Why a rigid flex and not a convex decomposition (CoACD, V-HACD): the flex
is the mesh itself, to MuJoCo's float precision, with no tolerance, no
parameters and no cache; a decomposition approximates the surface (by a
concavity tolerance), takes seconds to minutes per mesh and would need a
cache on disk. The price is MuJoCo's time: every mj_flex places each
flex's vertices, element boxes and tree (in proportion to the
triangles) and the cable elements are tested against the triangles near
them, where a hull is one convex test. So a surface is cut into patches
of at most `PATCH_TRIANGLES` triangles (halving its triangles at the
median of their centroids along the longest side of their box, a k-d
split), each a rigid flex of its own on the same body, and a patch no
cable can reach at a state is left out of that state's pass
(`cablecheck.detection.surfacereach`): the cost follows the triangles near the cables,
not the size of the meshes they pass. MuJoCo tests a cable element
against each triangle on its own (an element pair, never a flex as a
whole), and a triangle keeps its vertices' coordinates, so the patches
give the contacts the whole surface gives (tests/test_detection_mesh.py);
`benchmarks/bench_detection_mesh.py` measures hulls and surfaces side by
side.

A 2D flex element is a triangle with a radius that must be positive:
`SURFACE_RADIUS` is tiny, and `ContactReader` adds it back to MuJoCo's
distance, so the distance is the triangle's. The flex is a surface: a
cable buried deeper than the margin inside a closed mesh touches no
triangle (the hull geom would have reported it); the checker decides
containment itself.

This module does not step or read the simulation; `cablecheck.detection.contacts` names
the contacts (`surface_geoms`), `cablecheck.detection.surfacereach` chooses a state's
surfaces.
"""

from __future__ import annotations

import mujoco
import numpy as np

SURFACE_PREFIX = "detect/surface:"
"""Name prefix of the rigid flexes; the geom id follows, then `/` and the
patch's index (`surface_geoms`)."""

PATCH_TRIANGLES = 256
"""Most triangles in one flex of a surface. Smaller patches follow the
cables more closely but each flex costs MuJoCo a little in every pass (its
tree root, its broadphase entry). On the robot cell's meshes (60,608
triangles), measured side by side: patches of 1,024 keep twice the
triangles of 256 in reach, patches of 64 (1,290 flexes) make the
collision pass slower than whole meshes; 128 and 256 cost about the same."""

SURFACE_RADIUS = 1e-6
"""Radius of the surface flexes' triangles, metres (MuJoCo needs a positive
one in 2D); added back to MuJoCo's distances by `cablecheck.detection.contacts`."""


def is_convex(vertices: np.ndarray, faces: np.ndarray) -> bool:
    """The mesh is a closed convex surface (trimesh: watertight, and every
    vertex behind every face's plane): its hull is itself."""
    import trimesh  # a third of a second to import: only a scene with a mesh part pays it

    mesh = trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces, int), process=False)
    return bool(mesh.is_convex)


def _surface_meshes(spec: mujoco.MjSpec, like: mujoco.MjModel
                    ) -> list[tuple[mujoco.MjsGeom, int, int, np.ndarray, np.ndarray]]:
    """(spec geom, its id, its body's id, vertices in that body's frame, faces) of
    each colliding, non-convex mesh geom of `spec` as it stands (its contact
    bits set), the meshes read from `like`: a model compiled from a spec of
    the same structure (the simulation's), which MuJoCo's compiler numbers
    as `spec` lists them (`check_surfaces` confirms it after the compile).
    So the detection model compiles once, not once more to read its own
    meshes."""
    out = []
    geoms = spec.geoms
    if len(geoms) != like.ngeom:
        raise RuntimeError(f"the detection model's geoms ({len(geoms)}) are not the simulation's ({like.ngeom})")
    for gid, g in enumerate(geoms):
        if int(g.type) != int(like.geom_type[gid]):
            raise RuntimeError(f"the detection model's geom {gid} is not the simulation's")
        if int(g.type) != int(mujoco.mjtGeom.mjGEOM_MESH) or not (g.contype or g.conaffinity):
            continue  # visual, or no mesh
        mid = int(like.geom_dataid[gid])
        va, vn = int(like.mesh_vertadr[mid]), int(like.mesh_vertnum[mid])
        fa, fn = int(like.mesh_faceadr[mid]), int(like.mesh_facenum[mid])
        verts = like.mesh_vert[va:va + vn].astype(float)
        faces = like.mesh_face[fa:fa + fn].astype(int)
        if is_convex(verts, faces):
            continue
        # a face naming one vertex twice (MuJoCo merges an STL's repeated
        # vertices) is a segment or a point: a flex refuses it, and it adds
        # nothing its neighbours do not cover
        faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])]
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, like.geom_quat[gid])
        out.append((g, gid, int(like.geom_bodyid[gid]), verts @ rot.reshape(3, 3).T + like.geom_pos[gid], faces))
    return out


def add_surfaces(spec: mujoco.MjSpec, like: mujoco.MjModel, cable_bit: int) -> list[tuple[mujoco.MjsGeom, int]]:
    """Add to the detection model's `spec`, before it compiles, each colliding
    non-convex mesh geom's surface as rigid flexes (its patches, `patches`)
    meeting the cables, and stop the geom itself meeting them; its meshes
    read from `like` (`_surface_meshes`). Returns those geoms and the ids
    they were read under, for `check_surfaces` after the compile.
    `cable_bit` is the cables' contype bit."""
    found = _surface_meshes(spec, like)
    for g, gid, body_id, verts, faces in found:
        body = g.parent
        if not body.name:  # a flex names its body; the detection model's body names are not read
            body.name = f"{SURFACE_PREFIX}body{body_id}"
        for k, tri in enumerate(patches(verts[faces].mean(axis=1), PATCH_TRIANGLES)):
            used, local = np.unique(faces[tri], return_inverse=True)    # the patch's own vertices
            f = spec.add_flex()
            f.name = f"{SURFACE_PREFIX}{gid}/{k}"
            f.dim = 2
            f.radius = SURFACE_RADIUS
            f.vertbody = [body.name]
            f.vert = verts[used].ravel().tolist()
            f.elem = local.ravel().tolist()
            f.contype, f.conaffinity = 0, cable_bit
            f.margin = 0.0  # MuJoCo adds the two flexes' margins; the cable's is the clearance
            f.selfcollide = mujoco.mjtFlexSelf.mjFLEXSELF_NONE
        g.conaffinity = int(g.conaffinity) & ~cable_bit
    return [(g, gid) for g, gid, *_ in found]


def check_surfaces(added: list[tuple[mujoco.MjsGeom, int]]) -> None:
    """After the compile: each geom `add_surfaces` gave a surface has the
    id its mesh was read under (RuntimeError otherwise: the surfaces would
    be another geom's)."""
    for g, gid in added:
        if g.id != gid:
            raise RuntimeError(f"the detection model numbers geom {gid} as {g.id}: its surface would be another's")


def patches(centroids: np.ndarray, most: int) -> list[np.ndarray]:
    """Triangle indices (ascending) of the patches of a surface whose
    triangles have `centroids` (T, 3): halved at the median centroid along
    the longest side of their box until no patch has more than `most`
    (a k-d split; each level is one sort per patch, not per triangle)."""
    out, todo = [], [np.arange(len(centroids))]
    while todo:
        idx = todo.pop()
        if len(idx) <= most:
            out.append(np.sort(idx))
            continue
        c = centroids[idx]
        axis = int(np.argmax(c.max(axis=0) - c.min(axis=0)))
        order = idx[np.argsort(c[:, axis], kind="stable")]
        half = len(order) // 2
        todo += [order[half:], order[:half]]
    return out


def surface_geoms(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """(flex ids, geom ids) of the surface flexes (patches) of a detection
    model; a geom has one row per patch."""
    flexes, geoms = [], []
    for f in range(model.nflex):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_FLEX, f) or ""
        if name.startswith(SURFACE_PREFIX):
            flexes.append(f)
            geoms.append(int(name[len(SURFACE_PREFIX):].split("/")[0]))
    return np.array(flexes, np.int64), np.array(geoms, np.int64)


def hull_parts(parts, detect: mujoco.MjModel | None) -> frozenset[str]:
    """Names of the mesh parts (`cablecheck.build.stages.PartModel`) that MuJoCo's
    detection collides with the cables as their convex hull: those without a
    surface flex in `detect` (every mesh part when there is no detection
    model). Only for these can the hull explain a disagreement."""
    surfaced = set(surface_geoms(detect)[1].tolist()) if detect is not None else set()
    return frozenset(p.name for p in parts if p.shape == "mesh" and p.geom_id not in surfaced)
