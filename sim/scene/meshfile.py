"""Mesh files as users have them: STL, OBJ, PLY (one mesh) and glTF / GLB (a node tree).

`mesh_nodes` reads a file with trimesh and returns its triangle meshes: one
for single-mesh formats (STL, OBJ, PLY, ...: everything trimesh reads, its
parts concatenated), and for glTF / GLB one per node that holds geometry,
named by its path in the node tree (``"frame/left/rail"``, the names of the
node and its ancestors joined by "/"), with the node's transform applied,
so that the file's layout is kept. The scene loader turns each node into a
part named ``<part name>/<node path>``, which makes the glTF tree the parts'
assembly paths.

Coordinates are the file's own (multiply by the part's ``scale``). This module
does not decide whether a mesh is closed (see `cablecheck.checker.shapes.MeshData` and
`cablecheck.checker.partset`), and raises `MeshFileError` for unreadable files.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

GLTF_SUFFIXES = (".glb", ".gltf")
"""File suffixes read as a node tree."""


class MeshFileError(Exception):
    """A mesh file that cannot be read or holds no triangles."""


@dataclass(frozen=True, eq=False)
class MeshNode:
    """One triangle mesh of a file.

    Attributes:
        path: node path in a glTF tree ("/"-separated), or "" for a single-mesh file.
        vertices: (V, 3) float, file coordinates with the node's transform applied.
        faces: (F, 3) int.
    """

    path: str
    vertices: np.ndarray
    faces: np.ndarray


def is_tree(path: Path) -> bool:
    """True for files whose nodes become separate parts (glTF, GLB)."""
    return Path(path).suffix.lower() in GLTF_SUFFIXES


def stl_problem(path: Path) -> str | None:
    """What is wrong with an STL file that cannot hold triangles, or None.

    An STL file is either ASCII (starting with ``solid`` and holding ``facet``
    records) or binary (an 80-byte header, a triangle count n, then exactly
    50 bytes per triangle); trimesh, given neither, falls back to decoding
    the bytes as text and fails with an error about that, not the file.
    Checking the binary layout here (two numbers) lets the message say what
    is wrong with the file."""
    data = Path(path).read_bytes()
    head = data[:512].lstrip()
    if head[:5].lower() == b"solid" and b"facet" in data[:100_000]:
        return None   # ASCII STL: trimesh says what is wrong with its records
    if len(data) < 84:
        return f"is {len(data)} bytes, too short for an STL file (binary STL needs 84 or more)"
    count = int(np.frombuffer(data[80:84], "<u4")[0])
    expected = 84 + 50 * count
    if expected == len(data):
        return None
    return (f"is neither ASCII STL (no 'solid' ... 'facet' records) nor binary STL: its header "
            f"declares {count} triangles, which take {expected} bytes, but the file has "
            f"{len(data)} (a truncated or corrupt file, or another format named .stl)")


def mesh_nodes(path: Path) -> list[MeshNode]:
    """The meshes of a file (see the module docstring), glTF nodes sorted by path."""
    import trimesh  # half a second to import: only a scene with a mesh part pays it

    path = Path(path)
    if path.suffix.lower() == ".stl":
        problem = stl_problem(path)
        if problem is not None:
            raise MeshFileError(f"{path.name} {problem}")
    try:
        if not is_tree(path):
            mesh = trimesh.load(str(path), force="mesh")
            if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
                raise MeshFileError(f"{path.name} holds no triangles (trimesh read it as "
                                    f"{path.suffix.lstrip('.').upper() or 'a mesh'} and found no faces)")
            return [MeshNode("", np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int64))]
        scene = trimesh.load(str(path), force="scene")
    except MeshFileError:
        raise
    except Exception as e:   # trimesh raises many types for unreadable files
        raise MeshFileError(f"trimesh cannot load {path.name}: {type(e).__name__}: {e}") from None
    parents = scene.graph.transforms.parents
    out = []
    for node in scene.graph.nodes_geometry:
        transform, geom_name = scene.graph[node]
        geom = scene.geometry.get(geom_name)
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue      # points, lines and empty meshes are no parts
        chain = []
        n = node
        while n is not None and n != scene.graph.base_frame:
            chain.append(str(n).replace("/", "_"))
            n = parents.get(n)
        v = trimesh.transform_points(np.asarray(geom.vertices, float), transform)
        out.append(MeshNode("/".join(reversed(chain)), v, np.asarray(geom.faces, np.int64)))
    if not out:
        raise MeshFileError(f"{path.name} holds no triangle meshes")
    out.sort(key=lambda m: m.path)
    names = [m.path for m in out]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise MeshFileError(f"{path.name}: several nodes share the path {dup[0]!r}; name them apart")
    return out
