"""Triangle surfaces of parts, for the rigid-part checks (sweep, part-part).

:func:`part_surface` turns a :class:`~cablecheck.checker.shapes.Shape` into a closed,
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

from cablecheck.checker.shapes import Shape, ShapeType

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


MERGE_DIGITS = 8
"""Template vertices equal to this many decimals are one vertex (trimesh's
merge tolerance, 1e-8: the poles of a revolved profile, its seam)."""


def _revolved(profile: np.ndarray, sections: int) -> tuple[np.ndarray, np.ndarray]:
    """The closed surface of revolution of ``profile`` (m, 2: radius, z,
    from the bottom pole up) about z, in ``sections`` slices: vertices
    slice by slice, profile point by profile point; in each slice, between
    profile points k and k + 1, triangles (k, k + m, k + 1) and (k + 1, k +
    m, k + m + 1), the last slice closing on the first; then coincident
    vertices merged (`_merged`). The same vertices, faces and order as
    trimesh's ``creation`` primitives cleaned (tests/test_tessellate.py
    compares every template), without importing trimesh."""
    theta = np.linspace(0.0, 2.0 * np.pi, sections + 1)[:-1]
    r, z = profile[:, 0], profile[:, 1]
    v = np.column_stack([(np.cos(theta)[:, None] * r[None, :]).ravel(),
                         (np.sin(theta)[:, None] * r[None, :]).ravel(), np.tile(z, sections)])
    m = len(profile)
    k = np.arange(m - 1)
    quads = np.stack([np.stack([k, k + m, k + 1], axis=1), np.stack([k + 1, k + m, k + m + 1], axis=1)],
                     axis=1).reshape(-1, 3)
    f = ((quads[None] + (m * np.arange(sections))[:, None, None]) % len(v)).reshape(-1, 3)
    return _merged(v, f)


def _merged(v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices equal to ``MERGE_DIGITS`` decimals made one (the first of
    them kept, in order of first use), and the faces left with three
    distinct corners."""
    key = np.round(v * 10.0 ** MERGE_DIGITS).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    f = rank[inverse.ravel()][f]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
    return v[first[order]], f


def _outward(v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, bool]:
    """Faces wound outward (reversed if their signed volume is negative), and
    whether they close a volume (every edge on exactly two faces)."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    if np.einsum("ij,ij->", a, np.cross(b, c)) < 0:
        f = f[:, ::-1]
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    _, count = np.unique(edges, axis=0, return_counts=True)
    return np.ascontiguousarray(f, np.int64), bool(len(f)) and bool(np.all(count == 2))


def _profile(kind: ShapeType, n: int) -> tuple[np.ndarray, int]:
    """The profile (radius, z) and the slices around of a curved primitive's
    template with ``n`` segments (see `_template`)."""
    if kind in (ShapeType.SPHERE, ShapeType.ELLIPSOID):
        rings = n // 2 + 1
        t = np.linspace(0.0, np.pi, rings + rings % 2)
        return np.column_stack([np.sin(t), -np.cos(t)]), 2 * n
    if kind is ShapeType.CYLINDER:
        return np.array([[0.0, -1.0], [1.0, -1.0], [1.0, 1.0], [0.0, 1.0]]), n
    t = np.concatenate([np.linspace(-0.5 * np.pi, 0.0, n // 2 + 1), np.linspace(0.0, 0.5 * np.pi, n // 2 + 1)])
    profile = np.column_stack([np.cos(t), np.sin(t)])
    half = len(profile) // 2
    profile[:half, 1] -= 1.0
    profile[half:, 1] += 1.0
    return profile, n


@lru_cache(maxsize=None)
def _template(kind: ShapeType, n: int) -> tuple[np.ndarray, np.ndarray, bool]:
    """Unit surface of a curved primitive with ``n`` segments, built once per (kind, n).

    Sphere and ellipsoid: the unit sphere, ``n // 2 + 1`` meridian points
    (rounded up to even) pole to pole and ``2 n`` slices around (scaled per
    axis by the radii). Cylinder: radius 1, half length 1, ``n`` slices
    (scaled by radius, radius, half length). Capsule: radius 1, half length
    1, ``n // 2 + 1`` points per quarter circle of each cap, ``n`` slices; a
    vertex (x, y, z) of it becomes ``(r x, r y, sign(z) (h + r (|z| - 1)))``
    (each cap moved as a whole). Scaling by positive factors keeps the faces
    non-degenerate, the winding outward and the surface closed, so the
    per-part surfaces need no cleaning."""
    v, f = _revolved(*_profile(kind, n))
    f, closed = _outward(v, f)
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


_BOX_FACES = ((1, 3, 0), (4, 1, 0), (0, 3, 2), (2, 4, 0), (1, 7, 3), (5, 1, 4),
              (5, 7, 1), (3, 7, 2), (6, 4, 2), (2, 7, 6), (6, 5, 4), (7, 5, 6))
"""The cube's 12 outward triangles over its corners in binary order (x, y, z
from -1 to 1): trimesh's ``creation.box``, written out so that a scene of
boxes does not import trimesh (tests/test_tessellate.py holds them equal)."""


@lru_cache(maxsize=None)
def _unit_box() -> tuple[np.ndarray, np.ndarray, bool]:
    """The cube [-1, 1]^3: vertices (8, 3), faces (12, 3), closed."""
    v = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
    f = np.array(_BOX_FACES, np.int64)
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
