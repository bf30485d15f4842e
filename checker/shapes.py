"""Rigid part shapes and their signed distances, for points and for segments.

A :class:`Shape` is a part's geometry in its own frame, with sizes in MuJoCo's
convention: box half-extents, sphere radius, cylinder and capsule
``(radius, half_length)`` along local z, ellipsoid radii, a plane as the solid
half-space ``z < 0``, or a triangle mesh. Two questions are answered for whole
batches at once:

- :func:`signed_distance`: points -> signed distance to the surface (negative
  inside) and the closest surface point. Box, sphere, cylinder, capsule and
  plane are closed-form; the ellipsoid solves its one-dimensional Lagrange
  equation by safeguarded Newton iteration to a few units in the last place
  (next to its centre too); meshes find the exact nearest triangle through a
  k-d tree over triangle centroids with a proven cut-off, and take the sign
  from the angle weighted pseudonormal of the closest feature (Baerentzen and
  Aanaes 2005), which is exact for closed, consistently oriented meshes.
- :func:`segment_signed_distance`: segments -> the least signed distance over
  the segment and the parameter where it is reached, i.e. the signed distance
  between a capsule's axis and the part. For convex shapes the signed distance
  is a convex function along the segment: sphere, capsule and plane are
  closed-form; box and cylinder use a golden-section search that brackets the
  minimiser to 1e-13 of the segment's length; the ellipsoid finds the root of
  the derivative (the outward normal at the closest point dotted with the
  segment) by safeguarded secant steps to 1e-14 of the segment's length, which
  places the minimiser more precisely than comparing values can. Meshes are
  exact while the segment stays outside; a penetrating segment's depth is the
  deepest of nine evenly spaced samples (a lower bound on the true depth).

Batches may mix sizes (one row of ``size`` per query), so callers can answer
every part of one shape type in one call; the ``*_batch`` functions are that
interface. :func:`least_signed_distance` answers world points against a few
posed shapes without any pruning. Nothing else here knows about poses, and
nothing here knows cables or interference records or builds a broad phase
over several parts: that is :mod:`cablecheck.checker.interference`'s job.

This module holds the :class:`Shape` and the per-shape entry points; the
work is done by :mod:`cablecheck.checker.primitives` (primitive point distances),
:mod:`cablecheck.checker.meshdata`, :mod:`cablecheck.checker.meshgrid` and
:mod:`cablecheck.checker.meshnearest` (mesh point distances) and
:mod:`cablecheck.checker.segments` (segment distances), whose batch functions are
re-exported here.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from cablecheck.checker.arrays import all_columns, ranges

# The modules below do the work; their public names are re-exported here,
# where the rest of the checker has always imported them from.
from cablecheck.checker.meshdata import MeshData, sd_mesh, sd_mesh_face_plane
from cablecheck.checker.primitives import (
    ShapeType,
    face_plane_distance_batch,
    signed_distance_batch,
    signed_distance_value_batch,
)
from cablecheck.checker.segments import (
    segment_sd_mesh,
    segment_signed_distance_batch,
    segment_signed_distance_mixed,
)

__all__ = [
    "SHAPE_CODE", "MeshData", "Shape", "ShapeType", "distance_bounds", "face_plane_distance", "face_plane_distance_batch",
    "least_signed_distance", "mesh_shape", "primitive_bounds", "segment_signed_distance", "size_rows", "segment_signed_distance_batch",
    "segment_signed_distance_mixed", "signed_distance", "signed_distance_batch", "signed_distance_value_batch",
]

# Number of size entries for each primitive type.
_SIZE_LEN = {
    ShapeType.BOX: 3,
    ShapeType.SPHERE: 1,
    ShapeType.CYLINDER: 2,
    ShapeType.CAPSULE: 2,
    ShapeType.ELLIPSOID: 3,
    ShapeType.PLANE: 0,
    ShapeType.MESH: 0,
}


@dataclass(frozen=True, eq=False)
class Shape:
    """A part's geometry in its own frame.

    Attributes:
        type: the shape type.
        size: MuJoCo sizes: box half-extents (3,), sphere (1,) radius,
            cylinder / capsule (radius, half_length) along local z, ellipsoid
            radii (3,); ignored for plane (solid is local z < 0) and mesh.
        vertices: mesh only, (V, 3) in the part frame.
        faces: mesh only, (F, 3) int.
        mesh: mesh only, the acceleration data built at construction.
    """

    type: ShapeType
    size: np.ndarray
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None
    mesh: MeshData | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        stype = ShapeType(self.type)
        object.__setattr__(self, "type", stype)
        size = np.atleast_1d(np.asarray(self.size, dtype=float)).ravel()
        need = _SIZE_LEN[stype]
        if len(size) < need:
            raise ValueError(f"{stype.value} needs {need} size values, got {len(size)}")
        if need and not (np.all(np.isfinite(size[:need])) and np.all(size[:need] > 0)):
            raise ValueError(f"{stype.value} sizes must be finite and positive, got {size[:need]}")
        object.__setattr__(self, "size", size)
        if stype is ShapeType.MESH:
            if self.vertices is None or self.faces is None:
                raise ValueError("a mesh shape needs vertices and faces")
            v = np.asarray(self.vertices, dtype=float).reshape(-1, 3)
            f = np.asarray(self.faces, dtype=np.int64).reshape(-1, 3)
            if len(f) == 0 or f.min() < 0 or f.max() >= len(v) or not np.all(np.isfinite(v)):
                raise ValueError("mesh faces must index finite vertices and be non-empty")
            object.__setattr__(self, "vertices", v)
            object.__setattr__(self, "faces", f)
            object.__setattr__(self, "mesh", MeshData.build(v, f))

    @property
    def closed(self) -> bool:
        """Inside is defined: every primitive, and watertight consistent meshes."""
        return self.mesh.closed if self.mesh is not None else True

    def local_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) (3,) axis-aligned bounds in the part frame (infinite for a plane)."""
        if self.type is ShapeType.MESH:
            return self.mesh.lo, self.mesh.hi
        lo, hi = primitive_bounds(np.array([SHAPE_CODE[self.type]]), self.size[None, :3])
        return lo[0], hi[0]


SHAPE_CODE = {t: n for n, t in enumerate(ShapeType)}
"""Each shape type's integer code, for shape types held in arrays."""


def size_rows(shapes: Sequence[Shape]) -> np.ndarray:
    """(K, 3) the shapes' sizes padded with zeros to three columns: one kind
    may be given with 2 or 3 numbers (a plane), so rows stack whatever each gave."""
    rows = np.zeros((len(shapes), 3))
    for r, sh in enumerate(shapes):
        rows[r, : min(3, len(sh.size))] = sh.size[:3]
    return rows


def primitive_bounds(codes: np.ndarray, sizes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) (K, 3) part-frame bounds of primitives from their type codes
    (K,) and sizes (K, <=3); a plane's are infinite but for its top at z = 0.
    Mesh rows get zeros: their bounds are the mesh's own (``Shape.local_bounds``)."""
    k = len(codes)
    sz = np.zeros((k, 3))
    sz[:, : sizes.shape[1]] = sizes[:, :3]
    half = sz.copy()
    o = codes == SHAPE_CODE[ShapeType.SPHERE]
    half[o] = sz[o, :1]
    for kind, cap in ((ShapeType.CYLINDER, False), (ShapeType.CAPSULE, True)):
        o = codes == SHAPE_CODE[kind]
        half[o, 1] = sz[o, 0]
        half[o, 2] = sz[o, 1] + sz[o, 0] if cap else sz[o, 1]
    half[codes == SHAPE_CODE[ShapeType.MESH]] = 0.0
    lo, hi = -half, half.copy()
    o = codes == SHAPE_CODE[ShapeType.PLANE]
    lo[o] = -np.inf
    hi[o] = [np.inf, np.inf, 0.0]
    return lo, hi


def mesh_shape(vertices: np.ndarray, faces: np.ndarray) -> Shape:
    """A mesh shape from vertices (V, 3) and faces (F, 3), cleaned by trimesh.

    Duplicate vertices are merged (STL files repeat them per face) and
    degenerate or duplicate faces dropped before closure is decided. A closed
    mesh (watertight and consistently wound) is oriented outward and has a
    signed distance, negative inside. An open mesh is a surface without an
    inside: its distance is unsigned (never negative), so a cable can only
    touch it, never be inside it.

    The meshes made last are kept by content (per thread: a bound grid fills
    itself as it is asked, so a shape is never shared between threads), up
    to ``MESH_MEMO_TRIANGLES`` triangles in all (at least the last one): a
    run asks for each part's mesh more than once (routing, its warnings,
    the checks), and the same shape then shares its search structures and
    bound grid (a memo of exact values, so sharing changes no answer). A
    budget in triangles, not a count: the passes go over every mesh part in
    turn, so a memo holding fewer than a scene's meshes kept none of them
    for the next pass (robosuite's Tiago, 18 collision meshes, built its
    mesh data 35 times in one run, 0.5 s, when eight were kept).
    """
    v = np.ascontiguousarray(vertices, dtype=float)
    f = np.ascontiguousarray(faces)
    key = (v.shape, f.shape, f.dtype.str, hashlib.blake2b(v.tobytes() + f.tobytes(), digest_size=20).digest())
    memo = getattr(_MESH_MEMO, "shapes", None)
    if memo is None:
        memo = _MESH_MEMO.shapes = OrderedDict()
    shape = memo.get(key)
    if shape is None:
        import trimesh  # a third of a second to import: only a mesh part pays it

        tm = trimesh.Trimesh(vertices=v, faces=f, process=True)
        tm.update_faces(tm.nondegenerate_faces())
        tm.update_faces(tm.unique_faces())
        tm.remove_unreferenced_vertices()
        shape = Shape(ShapeType.MESH, np.zeros(0), vertices=np.asarray(tm.vertices), faces=np.asarray(tm.faces))
        memo[key] = shape
        held = sum(len(sh.faces) for sh in memo.values())
        while len(memo) > 1 and held > MESH_MEMO_TRIANGLES:
            _, gone = memo.popitem(last=False)
            held -= len(gone.faces)
    else:
        memo.move_to_end(key)
    return shape


MESH_MEMO_TRIANGLES = 500_000
"""Triangles of the meshes :func:`mesh_shape` keeps (each with its search
structures, about 0.4 kB a triangle), least recently asked for dropped
first: a robot's collision meshes (the zoo's: 7,558-103,590 triangles an
arm) stay while a run asks for them again."""

_MESH_MEMO = threading.local()
"""``shapes``: this thread's meshes by content, an OrderedDict (least recent first)."""


def signed_distance(shape: Shape, points: np.ndarray, limit: np.ndarray | float | None = None,
                    lower: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance from points to a shape's surface, negative inside.

    Args:
        shape: the shape.
        points: (n, 3) points in the shape's frame.
        limit: None, or a value per point (or one for all) at and beyond
            which the caller needs no exact distance: a mesh then answers a
            point that provably lies at least that far with a lower bound
            (>= limit) and a NaN closest point instead of searching its
            nearest triangle (:class:`BoundGrid`). Points below the limit,
            and every primitive, get the exact answer.
        lower: with ``limit`` on a mesh, the lower bounds of
            :func:`distance_bounds` at the points when the caller has them
            (not computed again).

    Returns:
        d: (n,) signed distance (unsigned for open meshes).
        closest: (n, 3) closest surface point in the shape's frame.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if shape.type is ShapeType.MESH:
        return sd_mesh(shape.mesh, p, None if limit is None else np.broadcast_to(np.asarray(limit, float), len(p)),
                       lower=lower)
    return signed_distance_batch(shape.type, np.broadcast_to(shape.size, (len(p), len(shape.size))), p)


def distance_bounds(shape: Shape, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cheap lower and upper bounds (n,) on :func:`signed_distance` at points
    (n, 3) in the shape's frame: from a mesh's bound grid (-inf / inf where
    it has none); a primitive's exact value, which costs no more."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if shape.type is ShapeType.MESH:
        return shape.mesh.bound.bounds(shape.mesh, p) if len(p) else (np.zeros(0), np.zeros(0))
    d = signed_distance(shape, p)[0]
    return d, d


def face_plane_distance(shape: Shape, points: np.ndarray) -> np.ndarray:
    """The paper's distance ``|BP . N|`` to the nearest face plane, (n,).

    Only boxes, planes and meshes have faces; curved primitives return their
    true signed distance (the paper measures curved surfaces exactly too).
    Inside points return the true negative distance: the paper decides
    containment first.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if shape.type is ShapeType.MESH:
        return sd_mesh_face_plane(shape.mesh, p)
    return face_plane_distance_batch(shape.type, np.broadcast_to(shape.size, (len(p), len(shape.size))), p)


def segment_signed_distance(shape: Shape, a: np.ndarray, b: np.ndarray, upper: np.ndarray | None = None,
                            cap: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Least signed distance from segments ``a b`` (n, 3) to a shape, in its frame.

    Returns ``(d (n,), t (n,))``: the signed distance of the segment (of a
    capsule's axis) to the shape and the parameter of its deepest or nearest
    point. See the module docstring for the accuracy of each type.
    ``upper`` (n,): a mesh's segments' unsigned distances are at most these
    (the caller measured a point of each: the same answers, found sooner);
    ``cap`` (n,), with it: distances the caller does not keep, a mesh may
    answer at the cap (`cablecheck.checker.segments.mesh_segment_unsigned`).
    """
    a = np.asarray(a, dtype=float).reshape(-1, 3)
    b = np.asarray(b, dtype=float).reshape(-1, 3)
    if shape.type is ShapeType.MESH:
        return segment_sd_mesh(shape.mesh, a, b, upper, cap)
    return segment_signed_distance_batch(shape.type, np.broadcast_to(shape.size, (len(a), len(shape.size))), a, b)


def least_signed_distance(shapes: list[Shape], rotations: np.ndarray, positions: np.ndarray,
                          points: np.ndarray, limit: float | None = None,
                          bounds: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Least signed distance (n,) from world points to shapes placed in the world.

    Args:
        shapes: P shapes, each in its own frame.
        rotations: (P, 3, 3) part-to-world rotations.
        positions: (P, 3) part origins in the world.
        points: (n, 3) world points.
        limit: None, or a distance at and beyond which the caller needs no
            exact value: a point whose distance to a mesh's bounding box
            exceeds it is answered with that box distance (a lower bound,
            above the limit) for that mesh instead of searching its
            triangles. Values below the limit are always exact.
        bounds: None, or (lo, hi) (P, 3) the parts' world boxes (infinite
            for a plane), with a limit: only the (part, point) pairs whose
            point lies within the limit of the part's box are measured, any
            other part being beyond the limit of that point; a point with no
            such part gets +inf. Without it every part meets every point.

    The measured pairs' points are taken into their parts' frames at once;
    primitives of one type are answered in one batched call and each mesh
    in one call (its k-d tree, not its bound grid: these points are seldom
    asked again). No broad phase beyond `bounds` (meant for placing a
    cable's initial shape; :mod:`cablecheck.checker.interference` prunes for
    the per-step checks). No parts: +inf.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    out = np.full(len(p), np.inf)
    if not shapes or not len(p):
        return out
    rot = np.asarray(rotations, float).reshape(-1, 3, 3)
    pos = np.asarray(positions, float).reshape(-1, 3)
    if bounds is not None and limit is not None:
        pi, ni = _in_boxes(p, *(np.asarray(b, float).reshape(-1, 3) for b in bounds), limit)
    else:
        pi, ni = np.repeat(np.arange(len(shapes)), len(p)), np.tile(np.arange(len(p)), len(shapes))
    if not len(pi):
        return out
    local = np.einsum("kji,kj->ki", rot[pi], p[ni] - pos[pi])        # each pair's point in its part's frame
    kinds: dict = {}
    for k, sh in enumerate(shapes):     # group parts: one call per type or mesh
        kinds.setdefault(("mesh", id(sh)) if sh.mesh is not None else sh.type, []).append(k)
    group = np.empty(len(shapes), int)
    for g, members in enumerate(kinds.values()):
        group[members] = g
    sizes = size_rows(shapes)
    pair_group = group[pi]
    for g, members in enumerate(kinds.values()):
        sel = np.flatnonzero(pair_group == g)
        if not len(sel):
            continue
        sh = shapes[members[0]]
        if sh.mesh is not None:
            d = _mesh_least(sh.mesh, local[sel], limit)
        else:
            d = signed_distance_value_batch(sh.type, sizes[pi[sel]], local[sel])
        np.minimum.at(out, ni[sel], d)
    return out


def _in_boxes(p: np.ndarray, lo: np.ndarray, hi: np.ndarray, limit: float) -> tuple[np.ndarray, np.ndarray]:
    """(box, point) index pairs, by box then point, of the points (n, 3) inside
    boxes lo .. hi (P, 3) grown by ``limit`` (infinite for a plane): every
    box's run of points sorted along x, then its y and z tested; the pairs of
    testing every point in every box (P x n: half a harness's start-up at
    1,000 parts), found from the few each box's slab of x holds."""
    order = np.argsort(p[:, 0], kind="stable")
    x = p[order, 0]
    first = np.searchsorted(x, lo[:, 0] - limit, "left")
    last = np.searchsorted(x, hi[:, 0] + limit, "right")
    count = np.maximum(last - first, 0)
    pi = np.repeat(np.arange(len(lo)), count)
    ni = order[ranges(first, count)]
    q = p[ni]
    keep = all_columns((q >= lo[pi] - limit) & (q <= hi[pi] + limit))
    pi, ni = pi[keep], ni[keep]
    o = np.lexsort((ni, pi))
    return pi[o], ni[o]


def _mesh_least(m: MeshData, p: np.ndarray, limit: float | None) -> np.ndarray:
    """Signed distance (n,) of one-off points to a mesh by its k-d tree (no
    grid to fill), points beyond ``limit`` of its box answered by the box
    distance (see :func:`least_signed_distance`)."""
    if limit is None:
        return sd_mesh(m, p, grid=False)[0]
    gap = np.maximum(np.maximum(m.lo - p, p - m.hi), 0.0)
    d = np.sqrt(np.einsum("ij,ij->i", gap, gap))
    near = np.flatnonzero(~(d > limit))
    if len(near):
        d[near] = sd_mesh(m, p[near], grid=False)[0]
    return d
