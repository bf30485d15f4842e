"""`[[bodies]]` and `[[parts]]`: scripted bodies, structure parts and the
bodies they ride on; mesh files loaded (once each) to check they are usable.

A glTF / GLB mesh part expands into one part per mesh node of the file,
named ``<name>/<node path>`` (`cablecheck.scene.meshfile`). Meshes are loaded with
trimesh only to check that they exist, load and (for keep-out parts) are
closed; the builder loads them again. Cables and motions: `cablecheck.scene.cables`,
`cablecheck.scene.motion`.
"""

from __future__ import annotations

import difflib
from dataclasses import replace
from pathlib import Path
from typing import Any

from cablecheck.scene.errors import describe
from cablecheck.scene.format import BODY_KEYS, PART_KEYS, SHAPE_SIZES
from cablecheck.scene.frames import euler_matrix, frame
from cablecheck.scene.meshfile import MeshFileError, is_tree, mesh_nodes
from cablecheck.scene.reader import Reader
from cablecheck.scene.records import BodyDef, PartDef

_SIZE_HELP = {"box": "half-extents x, y, z", "sphere": "radius",
              "cylinder": "radius, half-length", "capsule": "radius, half-length",
              "ellipsoid": "semi-axes x, y, z"}


def read_body(r: Reader, value: dict, where: str) -> BodyDef:
    """A `[[bodies]]` entry; its frame at t = 0 joins the reader's frames."""
    t = r.table(value, where, BODY_KEYS, ("name",))
    name = r.name(t["name"], f"{where}.name")
    if name == "world":
        raise r.error(f"{where}.name", "'world' is the fixed world frame; "
                                       "choose another name")
    if name in r.body_index:
        raise r.error(f"{where}.name", f"duplicate body name {name!r} "
                                       f"(also {r.body_index[name]})")
    if name in r.frames:
        raise r.error(f"{where}.name", f"{name!r} is already a body of the mjcf "
                                       "model; choose another name")
    r.body_index[name] = where
    body = BodyDef(name=name, pos=r.position(t.get("pos", [0, 0, 0]), f"{where}.pos"),
                   euler=r.vector(t.get("euler", [0, 0, 0]), f"{where}.euler"))
    r.frames[name] = frame(body.pos, euler_matrix(body.euler))
    return body


def body_ref(r: Reader, value: Any, where: str) -> str:
    """A body a part or anchor rides on: world, a [[bodies]] body or an mjcf body."""
    name = r.name(value, where)
    if name not in r.frames:
        known = sorted(r.frames)
        close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}?" if close else "known: " + ", ".join(known)
        raise r.error(where, f"no body named {name!r} in [[bodies]]"
                             f"{' or the mjcf model' if r.mjcf else ''} ({hint})")
    return name


def read_part(r: Reader, value: dict, where: str) -> PartDef:
    """A `[[parts]]` entry: shape and size in metres, the mesh file checked."""
    t = r.table(value, where, PART_KEYS, ("name", "shape"))
    name = r.name(t["name"], f"{where}.name")
    if any(not level.strip() for level in name.split("/")):
        raise r.error(f"{where}.name", f"empty assembly level in {name!r} "
                                       "('/' separates non-empty levels)")
    shape = r.string(t["shape"], f"{where}.shape", tuple(SHAPE_SIZES))
    arity = SHAPE_SIZES[shape]
    if shape == "plane":
        size = plane_size(r, t.get("size"), f"{where}.size")
    elif arity == 0:
        if "size" in t:
            raise r.error(f"{where}.size", f"not used by shape {shape!r} (see file, scale)")
        size = ()
    else:
        if "size" not in t:
            raise r.error(f"{where}.size", f"missing (required for shape {shape!r})")
        raw = t["size"]
        if isinstance(raw, list) and len(raw) != arity:
            raise r.error(f"{where}.size", f"shape {shape!r} takes {arity} "
                          f"number{'s' if arity > 1 else ''} ({_SIZE_HELP[shape]}), "
                          f"got {len(raw)}")
        size = tuple(r.length(v, f"{where}.size[{i}]", positive=True)
                     for i, v in enumerate(r.vector(raw, f"{where}.size", arity)))
    for key in ("file", "scale"):
        if key in t and shape != "mesh":
            raise r.error(f"{where}.{key}", f"only for shape 'mesh', not {shape!r}")
    keepout = r.boolean(t.get("keepout", False), f"{where}.keepout")
    file, mesh_scale = None, 1.0
    if shape == "mesh":
        if "file" not in t:
            raise r.error(f"{where}.file", "missing (required for shape 'mesh')")
        file = r.file_path(t["file"], f"{where}.file")
        mesh_scale = r.number(t.get("scale", 1.0), f"{where}.scale",
                              positive=True) * r.scale
        check_mesh(r, file, f"{where}.file", closed=keepout)
    return PartDef(name=name, body=body_ref(r, t.get("body", "world"), f"{where}.body"),
                   shape=shape, size=size,
                   pos=r.position(t.get("pos", [0, 0, 0]), f"{where}.pos"),
                   euler=r.vector(t.get("euler", [0, 0, 0]), f"{where}.euler"),
                   file=file, mesh_scale=mesh_scale, keepout=keepout,
                   friction=(r.number(t["friction"], f"{where}.friction", nonnegative=True)
                             if "friction" in t else None))


def plane_size(r: Reader, value: Any, where: str) -> tuple[float, ...]:
    """A plane's optional drawing size in metres (MuJoCo's: half-sizes x,
    y and optionally the grid spacing); () when absent.

    The plane is the infinite half-space below its local z = 0 for the
    simulation and the checker whatever the size; the size only says how
    much of it a recording draws (0 or absent: sized to the scene)."""
    if value is None:
        return ()
    if not isinstance(value, list) or len(value) not in (2, 3):
        got = f"{len(value)}" if isinstance(value, list) else describe(value)
        raise r.error(where, "shape 'plane' takes 2 or 3 numbers (drawn half-sizes x, y "
                             f"and grid spacing; the plane itself is infinite), got {got}")
    size = tuple(r.length(v, f"{where}[{i}]", nonnegative=True)
                 for i, v in enumerate(r.vector(value, where, len(value))))
    if len(size) == 3 and size[2] == 0:
        raise r.error(f"{where}[2]", "the grid spacing must be positive (MuJoCo's rule)")
    return size


def read_mesh_nodes(r: Reader, path: Path, where: str) -> list:
    """The meshes of a file, read once however many parts use it."""
    if path not in r.meshes:
        try:
            r.meshes[path] = mesh_nodes(path)
        except MeshFileError as e:
            raise r.error(where, str(e)) from None
    return r.meshes[path]


def check_mesh(r: Reader, path: Path, where: str, closed: bool) -> None:
    nodes = read_mesh_nodes(r, path, where)
    if not closed:
        return
    import trimesh  # loaded already by mesh_nodes (cablecheck.scene.meshfile): only a scene with meshes imports it

    for node in nodes:
        if not trimesh.Trimesh(node.vertices, node.faces).is_watertight:
            label = f"{path.name}" + (f" node {node.path!r}" if node.path else "")
            raise r.error(where, f"{label} is not a closed surface (keepout zones "
                                 "need an inside); close its holes")


def expand_nodes(r: Reader, part: PartDef, where: str) -> list[PartDef]:
    """A glTF / GLB mesh part becomes one part per mesh node, named
    ``<name>/<node path>``; any other part stays as it is."""
    if part.shape != "mesh" or not is_tree(part.file):
        return [part]
    nodes = read_mesh_nodes(r, part.file, f"{where}.file")
    return [replace(part, name=f"{part.name}/{n.path}", node=n.path) for n in nodes]
