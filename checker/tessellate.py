"""Triangle surfaces of parts, for the rigid-part checks (sweep, part-part).

:func:`part_surface` turns a :class:`~checker.shapes.Shape` into a closed,
outward-wound triangle surface in the part frame, and says how far that surface
may lie from the true one:

- box: its 12 triangles, exact (error 0);
- mesh: its own triangles, exact; ``closed`` says whether inside and outside
  are defined (trimesh's watertight and winding-consistent test);
- sphere, ellipsoid, cylinder, capsule: tessellated with every vertex on the
  true surface (the polyhedron is inscribed), fine enough that no point of the
  true surface is farther than ``tolerance`` from the polyhedron. The bound
  used: a triangle whose corners lie within a spherical cap of angular radius
  ``a`` stays within ``r (1 - cos a)`` of a sphere of radius ``r``; for the
  ellipsoid ``r`` is its largest radius. The count of segments is capped at
  ``MAX_SEGMENTS``; the achieved bound is returned as ``error``;
- plane: no triangles (an infinite half-space is handled analytically by the
  callers), ``error`` 0.

Not here: poses, bounding volumes, contact tests.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import trimesh

from checker.shapes import Shape, ShapeType

MAX_SEGMENTS = 256
"""Most segments around a curved primitive (caps the triangle count near 130k)."""

MIN_SEGMENTS = 12
"""Fewest segments around a curved primitive."""


@dataclass(frozen=True, eq=False)
class Surface:
    """A part's triangle surface in its own frame.

    Attributes:
        vertices: (V, 3) float.
        faces: (F, 3) int, wound outward when ``closed``.
        closed: inside and outside are defined.
        error: largest distance from the true surface to this one (0: exact).
        plane: the part is the half-space z < 0 (no triangles).
    """

    vertices: np.ndarray
    faces: np.ndarray
    closed: bool
    error: float
    plane: bool = False


def _segments_for(radius: float, tolerance: float, angle_factor: float) -> tuple[int, float]:
    """Segments around a circle so that r (1 - cos(angle_factor * pi / n)) <= tolerance."""
    if tolerance >= radius:
        n = MIN_SEGMENTS
    else:
        half = np.arccos(1.0 - tolerance / radius)
        n = int(np.ceil(angle_factor * np.pi / half))
    n = int(min(max(n, MIN_SEGMENTS), MAX_SEGMENTS))
    n += n % 2
    return n, float(radius * (1.0 - np.cos(angle_factor * np.pi / n)))


def _sphere_grid(n: int) -> trimesh.Trimesh:
    """Unit UV sphere with n segments around and n / 2 rings."""
    return trimesh.creation.uv_sphere(radius=1.0, count=[n // 2 + 1, n])


def _clean(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """Merged, non-degenerate, outward-wound triangles; and whether they close a volume."""
    tm = trimesh.Trimesh(vertices=vertices, faces=faces, process=True)
    tm.update_faces(tm.nondegenerate_faces())
    tm.remove_unreferenced_vertices()
    if tm.volume < 0:
        tm.invert()
    return np.asarray(tm.vertices, float), np.asarray(tm.faces, np.int64), bool(tm.is_watertight)


@lru_cache(maxsize=None)
def _template(kind: ShapeType, n: int) -> tuple[np.ndarray, np.ndarray, bool]:
    """Unit surface of a curved primitive with ``n`` segments, built once per (kind, n).

    Sphere and ellipsoid: the unit sphere (scaled per axis by the radii).
    Cylinder: radius 1, half length 1 (scaled by radius, radius, half length).
    Capsule: radius 1, half length 1; a vertex (x, y, z) of it becomes
    ``(r x, r y, sign(z) (h + r (|z| - 1)))`` (each cap moved as a whole).
    Scaling by positive factors keeps the faces non-degenerate, the winding
    outward and the surface closed, so the per-part surfaces need no cleaning."""
    if kind in (ShapeType.SPHERE, ShapeType.ELLIPSOID):
        tm = _sphere_grid(n)
    elif kind is ShapeType.CYLINDER:
        tm = trimesh.creation.cylinder(radius=1.0, height=2.0, sections=n)
    else:
        tm = trimesh.creation.capsule(height=2.0, radius=1.0, count=[n, n])
    v, f, closed = _clean(np.asarray(tm.vertices), np.asarray(tm.faces))
    v.setflags(write=False)
    f.setflags(write=False)
    return v, f, closed


def _segments_of(shape: Shape, tolerance: float) -> tuple[int, float]:
    """Template segments and the error bound of a curved primitive (see the module docstring)."""
    s = shape.size
    # Quads of the UV grid span 2 pi / n around and pi / (n / 2) along a
    # meridian: their corners lie in a cap of angular radius (pi / n) sqrt(2)
    # (half the diagonal), hence the factor sqrt(2) for spheres and capsules.
    if shape.type is ShapeType.SPHERE:
        return _segments_for(float(s[0]), tolerance, np.sqrt(2.0))
    if shape.type is ShapeType.ELLIPSOID:
        return _segments_for(float(np.max(s[:3])), tolerance, np.sqrt(2.0))
    if shape.type is ShapeType.CYLINDER:
        return _segments_for(float(s[0]), tolerance, 1.0)
    return _segments_for(float(s[0]), tolerance, np.sqrt(2.0))


def _scaled(kind: ShapeType, v: np.ndarray, size: np.ndarray) -> np.ndarray:
    """Template vertices (V, 3) for parts of sizes (k, m) -> (k, V, 3)."""
    if kind is ShapeType.SPHERE:
        return v[None] * size[:, None, :1]
    if kind is ShapeType.ELLIPSOID:
        return v[None] * size[:, None, :3]
    r, h = size[:, None, 0:1], size[:, None, 1:2]
    if kind is ShapeType.CYLINDER:
        return v[None] * np.concatenate([r, r, h], axis=2)
    z = np.sign(v[None, :, 2:]) * (h + r * (np.abs(v[None, :, 2:]) - 1.0))
    return np.concatenate([v[None, :, :2] * r, z], axis=2)


@dataclass(frozen=True, eq=False)
class Surfaces:
    """Many parts' surfaces in their own frames, concatenated.

    Attributes:
        vertices: (V, 3); part k's are ``vertices[vert_start[k]:vert_start[k + 1]]``.
        faces: (F, 3) indices into ``vertices`` (global); part k's are
            ``faces[face_start[k]:face_start[k + 1]]``.
        vert_start, face_start: (P + 1,).
        closed, plane: (P,) bool; error: (P,) as :class:`Surface`.
    """

    vertices: np.ndarray
    faces: np.ndarray
    vert_start: np.ndarray
    face_start: np.ndarray
    closed: np.ndarray
    plane: np.ndarray
    error: np.ndarray


def part_surfaces(shapes: list[Shape], tolerance: float) -> Surfaces:
    """The surfaces of many parts at once (as :func:`part_surface` gives them one by one).

    Curved primitives of one kind and segment count share one template
    (:func:`_template`), scaled for all of them in one numpy operation;
    boxes share the unit cube; meshes bring their own triangles. Memory is
    that of the output triangles."""
    if not tolerance > 0:
        raise ValueError(f"tolerance must be positive, got {tolerance}")
    n = len(shapes)
    closed = np.ones(n, bool)
    plane = np.zeros(n, bool)
    error = np.zeros(n)
    key: list[tuple] = []
    for k, sh in enumerate(shapes):    # one key per part; the geometry is made per group below
        st = sh.type
        if st is ShapeType.PLANE:
            plane[k] = True
            key.append(("plane",))
        elif st is ShapeType.MESH:
            key.append(("mesh", k))
        elif st is ShapeType.BOX:
            key.append(("box",))
        else:
            seg, error[k] = _segments_of(sh, tolerance)
            key.append((st, seg))
    groups: dict[tuple, list[int]] = {}
    for k, kk in enumerate(key):
        groups.setdefault(kk, []).append(k)
    verts: list[np.ndarray | None] = [None] * n
    faces: list[np.ndarray | None] = [None] * n
    for kk, members in groups.items():     # one pass per template (a handful), not per part
        idx = np.array(members)
        if kk[0] == "plane":
            for k in members:
                verts[k], faces[k] = np.zeros((0, 3)), np.zeros((0, 3), np.int64)
            continue
        if kk[0] == "mesh":
            surf = part_surface(shapes[kk[1]], tolerance)
            verts[kk[1]], faces[kk[1]] = surf.vertices, surf.faces
            closed[kk[1]], error[kk[1]] = surf.closed, surf.error
            continue
        size = np.stack([np.pad(shapes[k].size[:3], (0, 3 - min(3, len(shapes[k].size))))
                         for k in members])
        if kk[0] == "box":
            v, f, c = _unit_box()
            vv = v[None] * size[:, None, :]
        else:
            v, f, c = _template(kk[0], kk[1])
            vv = _scaled(kk[0], v, size)
        closed[idx] = c
        for row, k in enumerate(members):
            verts[k], faces[k] = vv[row], f
    vcount = np.array([len(v) for v in verts], np.int64)
    fcount = np.array([len(f) for f in faces], np.int64)
    vert_start = np.r_[0, np.cumsum(vcount)]
    face_start = np.r_[0, np.cumsum(fcount)]
    all_v = np.concatenate(verts) if n else np.zeros((0, 3))
    all_f = (np.concatenate(faces) + np.repeat(vert_start[:-1], fcount)[:, None]) if n \
        else np.zeros((0, 3), np.int64)
    return Surfaces(all_v.reshape(-1, 3), all_f.reshape(-1, 3).astype(np.int64), vert_start, face_start,
                    closed, plane, error)


@lru_cache(maxsize=None)
def _unit_box() -> tuple[np.ndarray, np.ndarray, bool]:
    tm = trimesh.creation.box(extents=[2.0, 2.0, 2.0])
    v, f = np.asarray(tm.vertices, float), np.asarray(tm.faces, np.int64)
    v.setflags(write=False)
    f.setflags(write=False)
    return v, f, True


def part_surface(shape: Shape, tolerance: float) -> Surface:
    """The triangle surface of ``shape`` (see the module docstring for the error bound).

    Args:
        shape: the part's shape in its own frame.
        tolerance: wanted largest distance between a curved primitive's true
            surface and its tessellation (same units as the shape), > 0.
    """
    if not tolerance > 0:
        raise ValueError(f"tolerance must be positive, got {tolerance}")
    s = shape.size
    st = shape.type
    if st is ShapeType.PLANE:
        return Surface(np.zeros((0, 3)), np.zeros((0, 3), np.int64), True, 0.0, plane=True)
    if st is ShapeType.MESH:
        return Surface(shape.mesh.vertices, shape.mesh.faces, shape.mesh.closed, 0.0)
    if st is ShapeType.BOX:
        v, f, _ = _unit_box()
        return Surface(v * s[:3], f, True, 0.0)
    n, err = _segments_of(shape, tolerance)
    v, f, closed = _template(st, n)
    size = np.pad(s[:3], (0, 3 - min(3, len(s))))[None]
    return Surface(_scaled(st, v, size)[0], f, closed, err)
