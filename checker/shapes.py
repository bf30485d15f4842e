"""Rigid part shapes and their signed distances, for points and for segments.

A :class:`Shape` is a part's geometry in its own frame, with sizes in MuJoCo's
convention: box half-extents, sphere radius, cylinder and capsule
``(radius, half_length)`` along local z, ellipsoid radii, a plane as the solid
half-space ``z < 0``, or a triangle mesh. Two questions are answered for whole
batches at once:

- :func:`signed_distance`: points -> signed distance to the surface (negative
  inside) and the closest surface point. Box, sphere, cylinder, capsule and
  plane are closed-form; the ellipsoid solves its one-dimensional Lagrange
  equation by safeguarded Newton iteration to about 1e-12 of its largest
  radius; meshes find the exact nearest triangle through a k-d tree over
  triangle centroids with a proven cut-off, and take the sign from the angle
  weighted pseudonormal of the closest feature (Baerentzen and Aanaes 2005),
  which is exact for closed, consistently oriented meshes.
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
over several parts: that is :mod:`checker.interference`'s job.
"""

from __future__ import annotations

import itertools

from dataclasses import dataclass, field
from enum import Enum

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from checker.closest import (
    REGION_EDGE_AB,
    REGION_VERT_A,
    cross,
    point_segment,
    point_triangle,
    row_norm,
    segment_segment,
    segment_triangle,
)


class ShapeType(str, Enum):
    """Primitive or mesh; the values are MuJoCo's geom type names."""

    BOX = "box"
    SPHERE = "sphere"
    CYLINDER = "cylinder"
    CAPSULE = "capsule"
    ELLIPSOID = "ellipsoid"
    PLANE = "plane"
    MESH = "mesh"


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

# Golden-section iterations for segment distances to convex shapes:
# 0.618**62 ~ 1e-13 of the segment's length.
_GOLDEN_ITERS = 62
_INVPHI = (np.sqrt(5.0) - 1.0) / 2.0


@dataclass(frozen=True, eq=False)
class MeshData:
    """Acceleration data of one triangle mesh, built once per shape.

    Attributes:
        a, b, c: (F, 3) triangle corners.
        face_normals: (F, 3) unit normals (outward when ``closed``).
        edge_normals: (F, 3, 3) pseudonormal of edge k (corner k to k+1) of
            each face: the sum of the unit normals of the faces sharing it.
        vertex_normals: (V, 3) angle-weighted pseudonormals.
        faces: (F, 3) corner indices into ``vertices``.
        vertices: (V, 3).
        centroids: (F, 3) triangle centroids.
        reach: float, largest distance from a centroid to its corners.
        tree: k-d tree over ``centroids``.
        levels: the faces split by their own reach (centroid to farthest
            corner) into halving classes, each ``(bound, face indices, k-d
            tree over their centroids)``: a query for every triangle that
            may come within r of a point asks each class for centroids
            within r + its bound, so the few long slivers of a CAD
            tessellation no longer widen the search for all the others.
        closed: the mesh is watertight and consistently wound, so inside and
            outside are defined and distances are signed.
        lo, hi: (3,) bounding box corners.
        tri_lo, tri_hi: (F, 3) each triangle's bounding box.
        bound: the :class:`_BoundGrid` of lower bounds for :func:`signed_distance`'s ``limit``.
    """

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    face_normals: np.ndarray
    edge_normals: np.ndarray
    vertex_normals: np.ndarray
    faces: np.ndarray
    vertices: np.ndarray
    centroids: np.ndarray
    reach: float
    tree: cKDTree
    levels: tuple
    closed: bool
    lo: np.ndarray
    hi: np.ndarray
    tri_lo: np.ndarray
    tri_hi: np.ndarray
    bound: "_BoundGrid" = field(default=None, repr=False)

    @staticmethod
    def build(vertices: np.ndarray, faces: np.ndarray) -> "MeshData":
        """Check closure with trimesh, orient outward, precompute normals and tree."""
        tm = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
        closed = bool(tm.is_watertight and tm.is_winding_consistent)
        if closed and tm.volume < 0:
            tm.invert()
        v = np.ascontiguousarray(tm.vertices, dtype=float)
        f = np.ascontiguousarray(tm.faces, dtype=np.int64)
        a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
        n = cross(b - a, c - a)
        nlen = row_norm(n)
        fn = n / np.where(nlen > 0, nlen, 1.0)[:, None]
        # Edge pseudonormals: sum of the normals of the faces on each edge.
        e_lo = np.minimum(f, np.roll(f, -1, axis=1)).ravel()
        e_hi = np.maximum(f, np.roll(f, -1, axis=1)).ravel()
        _, inv = np.unique(e_lo * len(v) + e_hi, return_inverse=True)
        esum = np.zeros((inv.max() + 1 if len(inv) else 0, 3))
        np.add.at(esum, inv, np.repeat(fn, 3, axis=0))
        edge_normals = esum[inv].reshape(len(f), 3, 3)
        # Vertex pseudonormals: face normals weighted by the corner angle.
        corners = np.stack([a, b, c], axis=1)
        u = np.roll(corners, -1, axis=1) - corners
        w = np.roll(corners, 1, axis=1) - corners
        cosang = np.einsum("fkj,fkj->fk", u, w) / np.maximum(
            np.linalg.norm(u, axis=2) * np.linalg.norm(w, axis=2), np.finfo(float).tiny
        )
        ang = np.arccos(np.clip(cosang, -1.0, 1.0))
        vn = np.zeros_like(v)
        np.add.at(vn, f.ravel(), (ang[:, :, None] * fn[:, None, :]).reshape(-1, 3))
        centroids = (a + b + c) / 3.0
        face_reach = np.max(np.linalg.norm(corners - centroids[:, None, :], axis=2), axis=1) \
            if len(f) else np.zeros(0)
        reach = float(face_reach.max()) if len(f) else 0.0
        return MeshData(
            a=a, b=b, c=c, face_normals=fn, edge_normals=edge_normals, vertex_normals=vn,
            faces=f, vertices=v, centroids=centroids, reach=reach,
            tree=cKDTree(centroids), levels=_reach_levels(centroids, face_reach, reach), closed=closed, lo=v.min(axis=0), hi=v.max(axis=0),
            tri_lo=np.minimum(np.minimum(a, b), c), tri_hi=np.maximum(np.maximum(a, b), c),
            bound=_BoundGrid(v.min(axis=0), v.max(axis=0)),
        )


REACH_LEVELS = 6
"""Classes of :attr:`MeshData.levels`: a face of reach r goes to class
floor(log2(reach_max / r)), the last class taking every face below
reach_max / 2^5."""


def _reach_levels(centroids: np.ndarray, face_reach: np.ndarray, reach: float,
                  levels: int = REACH_LEVELS, ratio: float = 2.0) -> tuple:
    if not len(face_reach) or reach <= 0:
        return ((reach, np.arange(len(face_reach)), cKDTree(centroids)),) if len(face_reach) else ()
    floor = reach * ratio ** -(levels - 1)
    cls = np.minimum(np.floor(np.log(reach / np.maximum(face_reach, floor)) / np.log(ratio)),
                     levels - 1).astype(np.int64)
    out = []
    for j in range(levels):
        idx = np.flatnonzero(cls == j)
        if len(idx):
            # the class's own largest reach is its bound
            out.append((float(face_reach[idx].max()), idx, cKDTree(centroids[idx])))
    return tuple(out)


_GRID_CELLS = 72
"""Cells of :class:`_BoundGrid` along the mesh's longest side."""

_GRID_PAD = 16
"""Cells of :class:`_BoundGrid` beyond the mesh's box on every side (a
quarter of the mesh's longest side: a cable's radius, clearance and skip
horizon together stay within it on arm links, so their queries need not
fall back to the k-d tree)."""


class _BoundGrid:
    """A coarse grid over a mesh, filled lazily, for bounds and short candidate lists.

    Lower bounds: the signed distance to a closed mesh (and the unsigned one
    to an open mesh) is 1-Lipschitz, so the exact value ``v`` at a cell's
    centre ``c`` bounds it at any point ``p`` from below by ``v - |p - c|``;
    outside the mesh's box the distance to the box is a bound too (and the
    only one beyond the grid). :func:`signed_distance` with a ``limit``
    skips the nearest-triangle search for points that provably lie beyond it.

    Candidates: the triangle nearest to a point p of the cell is within
    ``|v| + 2 h`` of the centre (``h`` the cell's half diagonal: it is within
    ``|v| + h`` of p), so the triangles :func:`_faces_within` that radius of
    the centre hold it, listed nearest first by their boxes; a point's own
    upper bound (the centre's value plus its way to the centre) takes a
    prefix of that list and cuts it by the triangles' boxes.
    Used for cells within ``_GRID_NEAR`` cells of the surface (farther ones
    would list too many triangles).

    Everything is computed exactly the first time a cell is met and kept: a
    memo, so no answer depends on which cells were filled before.
    """

    def __init__(self, lo: np.ndarray, hi: np.ndarray):
        self.lo, self.hi = lo, hi
        ext = hi - lo
        self.h = float(max(ext.max(), np.finfo(float).tiny)) / _GRID_CELLS
        self.half_diag = 0.5 * np.sqrt(3.0) * self.h
        self.origin = lo - _GRID_PAD * self.h
        self.dims = (np.ceil(ext / self.h).astype(np.int64) + 2 * _GRID_PAD).clip(1)
        self.values = None      # allocated on first use: most meshes of a scene are never near a cable

    def _allocate(self) -> None:
        n = int(np.prod(self.dims))
        self.values = np.full(n, np.nan)
        self.start = np.zeros(n, np.int64)
        self.count = np.full(n, -1, np.int32)
        self.list_id = np.zeros(n, np.int32)
        self.quantum = self.h * 2.0 ** -20
        self.flat = np.zeros(1024, np.int64)     # the cells' lists, one after the other
        self.flat_key = np.zeros(1024, np.int64)  # each entry's list and quantised box distance
        self.lists = 0                            # lists made so far (their keys' high bits)
        self.used = 0

    def _cells(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(inside (n,) bool, flat cell index and cell centre of the points inside)."""
        if self.values is None:
            self._allocate()
        ijk = np.floor((p - self.origin) / self.h).astype(np.int64)
        inside = np.all((ijk >= 0) & (ijk < self.dims), axis=1)
        ijk = ijk[inside]
        return inside, np.ravel_multi_index(ijk.T, self.dims), self.origin + (ijk + 0.5) * self.h

    def _fill(self, m: "MeshData", flat: np.ndarray) -> None:
        missing = np.isnan(self.values[flat])
        if missing.any():
            todo = np.unique(flat[missing])
            c = self.origin + (np.stack(np.unravel_index(todo, self.dims), axis=1) + 0.5) * self.h
            d, cl, face, region = _mesh_nearest(m, c, 8)
            self.values[todo] = _mesh_sign(m, c, cl, face, region) * d

    def _list(self, m: "MeshData", flat: np.ndarray) -> None:
        missing = self.count[flat] < 0
        if not missing.any():
            return
        todo = np.unique(flat[missing])
        c = self.origin + (np.stack(np.unravel_index(todo, self.dims), axis=1) + 0.5) * self.h
        radius = np.abs(self.values[todo]) + 2.0 * self.half_diag * (1 + 1e-9)
        rows, faces = _faces_within(m, c, radius)
        cr = c[rows]
        g = np.maximum(np.maximum(m.tri_lo[faces] - cr, cr - m.tri_hi[faces]), 0.0)
        box = np.sqrt(np.einsum("ij,ij->i", g, g))
        # each list nearest first by the triangles' boxes (seen from the centre)
        o = np.lexsort((faces, box, rows))
        cnt = np.bincount(rows, minlength=len(todo))
        need = self.used + len(faces)
        if need > len(self.flat):
            size = max(need, 2 * len(self.flat))
            self.flat = np.concatenate([self.flat[: self.used], np.zeros(size - self.used, np.int64)])
            self.flat_key = np.concatenate([self.flat_key[: self.used], np.zeros(size - self.used, np.int64)])
        self.flat[self.used: need] = faces[o]
        # keys ascend along the lists (list number, then box): one
        # searchsorted finds every point's prefix (see `nearest`)
        ids = self.lists + np.arange(len(todo), dtype=np.int64)
        self.flat_key[self.used: need] = (ids[rows[o]] << _KEY_BITS) | self._quantise(box[o])
        self.start[todo] = self.used + np.cumsum(cnt) - cnt
        self.count[todo] = cnt
        self.list_id[todo] = ids
        self.lists += len(todo)
        self.used = need

    def _quantise(self, x: np.ndarray) -> np.ndarray:
        """floor(x / quantum), clipped to the key's low bits: monotone, so
        x <= y implies quantise(x) <= quantise(y)."""
        return np.minimum(np.floor(x / self.quantum), float(_KEY_MAX)).astype(np.int64)

    def lower(self, m: "MeshData", p: np.ndarray) -> np.ndarray:
        """(n,) lower bounds on the signed distance at points p (-inf where none)."""
        return self.bounds(m, p)[0]

    def bounds(self, m: "MeshData", p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n,) lower and upper bounds on the signed distance at points p
        (-inf and inf where none; the upper bound ``v + |p - c|`` is the
        same Lipschitz argument)."""
        gap = np.maximum(np.maximum(self.lo - p, p - self.hi), 0.0)
        box = np.sqrt(np.einsum("ij,ij->i", gap, gap))
        lo = np.where(box > 0.0, box, -np.inf)
        hi = np.full(len(p), np.inf)
        inside, flat, centre = self._cells(p)
        if not len(flat):
            return lo, hi
        self._fill(m, flat)
        v = self.values[flat]
        r = row_norm(p[inside] - centre)
        # rounding: the centre's value and the distance each err by a few ulp
        slack = 1e-9 * (np.abs(v) + self.h)
        lo[inside] = np.maximum(lo[inside], v - r - slack)
        hi[inside] = v + r + slack
        return lo, hi

    def nearest(self, m: "MeshData", p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:func:`_mesh_nearest` for points p (n, 3): through the cells' lists
        where the point's cell is near the surface, else the k-d tree."""
        inside, flat, centre = self._cells(p)
        rows_in = np.flatnonzero(inside)
        if len(flat):
            self._fill(m, flat)
            close = np.abs(self.values[flat]) <= _GRID_NEAR * self.h
            rows_in, flat, centre = rows_in[close], flat[close], centre[close]
        if not len(rows_in):
            return _mesh_nearest(m, p, 8)
        self._list(m, flat)
        q = p[rows_in]
        # An upper bound on the distance at q: the centre's (exact) plus the
        # way to it (1-Lipschitz), with the rounding slack of `bounds`.
        r = row_norm(q - centre)
        v = np.abs(self.values[flat])
        ub = v + r + 1e-9 * (v + self.h)
        # A triangle within ub of q has its box within ub + |q - c| of the
        # centre (box distance is 1-Lipschitz): a prefix of the cell's list,
        # found for all points at once by the lists' sorted keys.
        reach = (ub + r) * (1 + 1e-12) + 1e-300
        key = (self.list_id[flat].astype(np.int64) << _KEY_BITS) | self._quantise(reach)
        start = self.start[flat]
        cnt = np.searchsorted(self.flat_key[: self.used], key, side="right") - start
        rows = np.repeat(np.arange(len(q)), cnt)
        first = np.cumsum(cnt) - cnt
        faces = self.flat[start[rows] + np.arange(len(rows)) - first[rows]]
        qr = q[rows]
        g = np.maximum(np.maximum(m.tri_lo[faces] - qr, qr - m.tri_hi[faces]), 0.0)
        keep = np.einsum("ij,ij->i", g, g) <= np.square(ub[rows] * (1 + 1e-12) + 1e-300)
        rows, faces = rows[keep], faces[keep]
        d, cl, reg = point_triangle(q[rows], m.a[faces], m.b[faces], m.c[faces])
        # the least per point; ties to the lowest face index
        o = np.lexsort((faces, d, rows))
        head = o[np.r_[True, rows[o][1:] != rows[o][:-1]]]
        out_d = np.empty(len(p))
        out_cl = np.empty((len(p), 3))
        out_f = np.empty(len(p), np.int64)
        out_r = np.empty(len(p), reg.dtype)
        out_d[rows_in], out_cl[rows_in], out_f[rows_in], out_r[rows_in] = d[head], cl[head], faces[head], reg[head]
        rest = np.ones(len(p), bool)
        rest[rows_in] = False
        rest = np.flatnonzero(rest)
        if len(rest):
            out_d[rest], out_cl[rest], out_f[rest], out_r[rest] = _mesh_nearest(m, p[rest], 8)
        return out_d, out_cl, out_f, out_r


_KEY_BITS = 40
"""Low bits of a :class:`_BoundGrid` list entry's key: its box distance in
units of 2^-20 cell sides (clipped: far entries share the largest key)."""

_KEY_MAX = (1 << _KEY_BITS) - 1

_GRID_NEAR = 16
"""Cells of :class:`_BoundGrid` whose centre lies within this many cell
sides of the surface answer nearest-triangle queries from their lists."""


def _faces_within(m: "MeshData", q: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rows, faces): for each query point q[i], every face whose triangle may
    come within radius[i] of it (its centroid within radius plus the face's
    reach class bound; see :attr:`MeshData.levels`). A superset, exact to
    filter."""
    rows, faces = [], []
    for bound, idx, tree in m.levels:
        lists = tree.query_ball_point(q, radius + bound * (1 + 1e-12) + 1e-300)
        cnt = np.fromiter(map(len, lists), dtype=np.int64, count=len(q))
        flat = np.fromiter(itertools.chain.from_iterable(lists), dtype=np.int64, count=int(cnt.sum()))
        rows.append(np.repeat(np.arange(len(q)), cnt))
        faces.append(idx[flat])
    if not rows:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    rows, faces = np.concatenate(rows), np.concatenate(faces)
    # A triangle is no nearer than its box: cheaper than the exact test it saves.
    qr = q[rows]
    gap = np.maximum(np.maximum(m.tri_lo[faces] - qr, qr - m.tri_hi[faces]), 0.0)
    keep = np.einsum("ij,ij->i", gap, gap) <= np.square(radius[rows] * (1 + 1e-12) + 1e-300)
    return rows[keep], faces[keep]


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
        s = self.size
        if self.type is ShapeType.MESH:
            return self.mesh.lo, self.mesh.hi
        if self.type is ShapeType.PLANE:
            return np.array([-np.inf, -np.inf, -np.inf]), np.array([np.inf, np.inf, 0.0])
        if self.type is ShapeType.SPHERE:
            half = np.repeat(s[0], 3)
        elif self.type is ShapeType.CYLINDER:
            half = np.array([s[0], s[0], s[1]])
        elif self.type is ShapeType.CAPSULE:
            half = np.array([s[0], s[0], s[1] + s[0]])
        else:  # box, ellipsoid
            half = s[:3].copy()
        return -half, half


def mesh_shape(vertices: np.ndarray, faces: np.ndarray) -> Shape:
    """A mesh shape from vertices (V, 3) and faces (F, 3), cleaned by trimesh.

    Duplicate vertices are merged (STL files repeat them per face) and
    degenerate or duplicate faces dropped before closure is decided. A closed
    mesh (watertight and consistently wound) is oriented outward and has a
    signed distance, negative inside. An open mesh is a surface without an
    inside: its distance is unsigned (never negative), so a cable can only
    touch it, never be inside it.
    """
    tm = trimesh.Trimesh(vertices=np.asarray(vertices, dtype=float), faces=np.asarray(faces), process=True)
    tm.update_faces(tm.nondegenerate_faces())
    tm.update_faces(tm.unique_faces())
    tm.remove_unreferenced_vertices()
    return Shape(ShapeType.MESH, np.zeros(0), vertices=np.asarray(tm.vertices), faces=np.asarray(tm.faces))


# ---------------------------------------------------------------------------
# Point queries, batched by type with one size row per point.


def _unit_or(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Rows of v normalised; rows of zero length take ``fallback`` (3,)."""
    n = row_norm(v)
    ok = n > 0
    return np.where(ok[:, None], v / np.where(ok, n, 1.0)[:, None], fallback)


_EX = np.array([1.0, 0.0, 0.0])


def _sd_box_value(h: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed distance to boxes without the closest point: (d, q, inside)."""
    q = np.abs(p) - h
    outside = row_norm(np.maximum(q, 0.0))
    inside = np.max(q, axis=1)
    return np.where(inside > 0.0, outside, inside), q, inside


def _sd_box(h: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d, q, inside = _sd_box_value(h, p)
    # Closest point: clamp outside; inside, move to the nearest face.
    cl = np.clip(p, -h, h)
    k = np.argmax(q, axis=1)
    rows = np.arange(len(p))
    face = cl.copy()
    face[rows, k] = np.where(p[rows, k] >= 0.0, h[rows, k], -h[rows, k])
    cl = np.where((inside <= 0.0)[:, None], face, cl)
    return d, cl


def _sd_box_face_plane(h: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The paper's face-plane distance: least |BP . N| over the six face planes.

    Inside points keep the true (negative) distance; outside, the distance to
    the nearest face *plane*, which underestimates near edges and corners.
    """
    q = np.abs(p) - h
    inside = np.max(q, axis=1)
    return np.where(inside > 0.0, np.min(np.abs(q), axis=1), inside)


def _sd_sphere(rad: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = row_norm(p)
    return n - rad, rad[:, None] * _unit_or(p, _EX)


def _sd_capsule(rad: np.ndarray, half: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    z = np.clip(p[:, 2], -half, half)
    axis = np.zeros_like(p)
    axis[:, 2] = z
    off = p - axis
    n = row_norm(off)
    return n - rad, axis + rad[:, None] * _unit_or(off, _EX)


def _sd_cylinder_value(rad: np.ndarray, half: np.ndarray, p: np.ndarray) -> tuple:
    """Signed distance to cylinders without the closest point: (d, rho, dr, dz, inside)."""
    rho = np.hypot(p[:, 0], p[:, 1])
    dr = rho - rad
    dz = np.abs(p[:, 2]) - half
    inside = np.maximum(dr, dz)
    outside = np.hypot(np.maximum(dr, 0.0), np.maximum(dz, 0.0))
    return np.where(inside > 0.0, outside, inside), rho, dr, dz, inside


def _sd_cylinder(rad: np.ndarray, half: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d, rho, dr, dz, inside = _sd_cylinder_value(rad, half, p)
    ok = rho > 0
    ux = np.where(ok, p[:, 0], 1.0) / np.where(ok, rho, 1.0)
    uy = np.where(ok, p[:, 1], 0.0) / np.where(ok, rho, 1.0)
    zs = np.where(p[:, 2] >= 0.0, half, -half)
    r_out = np.minimum(rho, rad)
    z_out = np.clip(p[:, 2], -half, half)
    side = dr >= dz  # inside: nearer to the side than to a cap
    r_cl = np.where(inside > 0.0, r_out, np.where(side, rad, rho))
    z_cl = np.where(inside > 0.0, z_out, np.where(side, p[:, 2], zs))
    return d, np.stack([r_cl * ux, r_cl * uy, z_cl], axis=1)


def _sd_plane(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    cl = p.copy()
    cl[:, 2] = 0.0
    return p[:, 2].copy(), cl


def _sd_ellipsoid(e: np.ndarray, p: np.ndarray, t0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed distance to ellipsoids with radii ``e`` (m, 3).

    The closest point is ``x_i = e_i^2 y_i / (t + e_i^2)`` where ``t`` is the
    root of ``F(t) = sum (e_i y_i / (t + e_i^2))^2 - 1`` above ``-min e_i^2``
    (Eberly, "Distance from a point to an ellipse, an ellipsoid, or a
    hyperellipsoid"), solved in the first octant by Newton steps kept inside a
    shrinking bracket (bisection when a step leaves it) until the step is below
    1e-14 of the problem's squared scale. ``F`` is convex and decreasing, so
    from the bracket's lower end Newton converges monotonically; ``t0`` (a
    previous root for a nearby point) warm-starts it. The component along the
    smallest radius is taken from the surface equation near the pole (points
    inside, near the plane of the two larger radii: the degenerate case).

    Returns (d (m,), closest (m, 3), t (m,)).
    """
    sgn = np.where(p >= 0.0, 1.0, -1.0)
    y = np.abs(p)
    order = np.argsort(-e, axis=1)
    es = np.take_along_axis(e, order, axis=1)
    ys = np.take_along_axis(y, order, axis=1)
    e2 = es * es
    emin2 = e2[:, 2]
    ey = es * ys
    lo = np.maximum(np.max(ey - e2, axis=1), -emin2)
    hi = np.maximum(-emin2 + row_norm(ey), lo)
    tol = 1e-14 * np.maximum(e2[:, 0], np.max(ey, axis=1))
    t = lo.copy() if t0 is None else np.clip(t0, lo, hi)
    act = np.nonzero(hi - lo > tol)[0]
    for _ in range(200):
        if len(act) == 0:
            break
        ta, e2a, eya = t[act], e2[act], ey[act]
        den = ta[:, None] + e2a
        ok = den > 0
        r = np.where(ok, eya, 0.0) / np.where(ok, den, 1.0)
        f = np.sum(r * r, axis=1) - 1.0
        df = -2.0 * np.sum(r * r / np.where(ok, den, 1.0), axis=1)
        # At the pole with y_min > 0, F is +inf.
        pole = np.any(~ok & (eya > 0), axis=1)
        lo_a = np.where((f > 0) | pole, ta, lo[act])
        hi_a = np.where((f <= 0) & ~pole, ta, hi[act])
        step_ok = ~pole & (df < 0)
        tn = ta - np.where(step_ok, f, 0.0) / np.where(step_ok, df, -1.0)
        mid = 0.5 * (lo_a + hi_a)
        # a tiny Newton step far from the root (F steep near the pole: a point
        # on a principal plane by rounding) is no convergence: bisect instead
        stalled = (np.abs(tn - ta) <= tol[act]) & (np.abs(f) > 1e-10)
        tn = np.where(~step_ok | (tn < lo_a) | (tn > hi_a) | stalled, mid, tn)
        conv = ((np.abs(tn - ta) <= tol[act]) & ~stalled) | (hi_a - lo_a <= tol[act])
        t[act], lo[act], hi[act] = tn, lo_a, hi_a
        act = act[~conv]
    den = t[:, None] + e2
    ok = den > 0.0
    x = np.where(ok, e2 * ys, 0.0) / np.where(ok, den, 1.0)
    # The smallest axis at or near the pole (points inside, near the plane of
    # the larger radii) is better taken from the surface equation.
    rest = 1.0 - (x[:, 0] / es[:, 0]) ** 2 - (x[:, 1] / es[:, 1]) ** 2
    use_eq = (rest >= 0.25) | (den[:, 2] <= 1e-6 * e2[:, 2])
    x[:, 2] = np.where(use_eq, es[:, 2] * np.sqrt(np.maximum(rest, 0.0)), x[:, 2])
    inv = np.argsort(order, axis=1)
    cl = np.take_along_axis(x, inv, axis=1) * sgn
    d = row_norm(p - cl)
    inside = np.sum((p / e) ** 2, axis=1) < 1.0
    return np.where(inside, -d, d), cl, t


def _mesh_nearest(m: MeshData, p: np.ndarray, k: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exact nearest triangle of a mesh for points ``p`` (n, 3).

    Takes the k nearest centroids; a triangle whose centroid is farther than
    the k-th one cannot beat the best found if ``best <= d_k - reach``. Points
    failing that bound are redone with every triangle that may come within
    ``best`` (:func:`_faces_within`: its centroid within ``best`` plus its
    reach class's bound).

    A small mesh (up to ``_BOX_FACES`` triangles, ``n * F`` up to
    ``_BOX_PAIRS``) takes another road, exact
    too: the triangle of the nearest centroid gives an upper bound, and
    every triangle whose bounding box is no farther is a candidate (few for
    the large, uneven triangles of a low-poly CAD part, where the
    centroids say little).

    Returns dist (n,), closest (n, 3), face index (n,), region code (n,).
    """
    nf = len(m.faces)
    if nf <= _BOX_FACES and len(p) * nf <= _BOX_PAIRS:
        return _mesh_nearest_small(m, p)
    k = min(k, nf)
    dk, idx = m.tree.query(p, k=k)
    dk = dk.reshape(len(p), k)
    idx = idx.reshape(len(p), k)
    n = len(p)
    rows = np.repeat(np.arange(n), k)
    fi = idx.ravel()
    d, cl, reg = point_triangle(p[rows], m.a[fi], m.b[fi], m.c[fi])
    d = d.reshape(n, k)
    j = np.argmin(d, axis=1)
    best = d[np.arange(n), j]
    sel = np.arange(n) * k + j
    out_cl = cl[sel]
    out_f = fi[sel]
    out_r = reg[sel]
    redo = np.nonzero((k < nf) & (best > dk[:, -1] - m.reach))[0]
    if len(redo):
        local, fi2 = _faces_within(m, p[redo], best[redo])
        rows2 = redo[local]
        d2, cl2, reg2 = point_triangle(p[rows2], m.a[fi2], m.b[fi2], m.c[fi2])
        # Least per point: sort by (row, distance) and take each row's first.
        o = np.lexsort((d2, rows2))
        first = o[np.r_[True, rows2[o][1:] != rows2[o][:-1]]]
        r = rows2[first]
        better = d2[first] < best[r]
        r, first = r[better], first[better]
        best[r] = d2[first]
        out_cl[r] = cl2[first]
        out_f[r] = fi2[first]
        out_r[r] = reg2[first]
    return best, out_cl, out_f, out_r


_BOX_FACES = 64
"""Meshes up to this many triangles: :func:`_mesh_nearest_small` (three
times faster on a 20-triangle bracket, slower from a few hundred)."""

_BOX_PAIRS = 1 << 17
"""Point-triangle pairs up to which :func:`_mesh_nearest` bounds every pair
by the triangles' boxes (memory: a few MB)."""


def _mesh_nearest_small(m: MeshData, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_mesh_nearest` by triangle boxes against every point (see there)."""
    n = len(p)
    _, i0 = m.tree.query(p, k=1)
    i0 = np.asarray(i0, np.int64).reshape(n)
    d0, _, _ = point_triangle(p, m.a[i0], m.b[i0], m.c[i0])
    gap = np.maximum(np.maximum(m.tri_lo[None] - p[:, None], p[:, None] - m.tri_hi[None]), 0.0)
    lb = np.sqrt(np.einsum("nfi,nfi->nf", gap, gap))
    rows, fi = np.nonzero(lb <= (d0 * (1.0 + 1e-12) + 1e-300)[:, None])
    d, cl, reg = point_triangle(p[rows], m.a[fi], m.b[fi], m.c[fi])
    # the least per point; ties to the lowest face index
    o = np.lexsort((fi, d, rows))
    first = o[np.r_[True, rows[o][1:] != rows[o][:-1]]]
    return d[first], cl[first], fi[first], reg[first]


def _mesh_sign(m: MeshData, p: np.ndarray, cl: np.ndarray, face: np.ndarray, region: np.ndarray) -> np.ndarray:
    """+1 outside, -1 inside, from the pseudonormal of the closest feature."""
    if not m.closed:
        return np.ones(len(p))
    nrm = m.face_normals[face].copy()
    is_edge = (region >= REGION_EDGE_AB) & (region < REGION_VERT_A)
    is_vert = region >= REGION_VERT_A
    ke = np.clip(region - REGION_EDGE_AB, 0, 2)
    nrm = np.where(is_edge[:, None], m.edge_normals[face, ke], nrm)
    kv = np.clip(region - REGION_VERT_A, 0, 2)
    nrm = np.where(is_vert[:, None], m.vertex_normals[m.faces[face, kv]], nrm)
    side = np.einsum("ij,ij->i", p - cl, nrm)
    return np.where(side < 0.0, -1.0, 1.0)


def _sd_mesh(m: MeshData, p: np.ndarray, limit: np.ndarray | None = None,
             grid: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance and closest points of a mesh; ``grid`` False: the
    k-d tree alone, for one-off queries that would only fill the bound grid."""
    if len(p) == 0:
        return np.zeros(0), np.zeros((0, 3))
    if limit is not None:
        lb = m.bound.lower(m, p)
        far = lb > limit + 1e-9 * (np.abs(limit) + m.bound.h)   # the caller's own comparison stays safe
        if far.any():
            d = lb.copy()
            cl = np.full((len(p), 3), np.nan)
            near = np.flatnonzero(~far)
            if len(near):
                d[near], cl[near] = _sd_mesh(m, p[near])
            return d, cl
    d, cl, face, region = m.bound.nearest(m, p) if grid else _mesh_nearest(m, p, 8)
    sign = _mesh_sign(m, p, cl, face, region)
    return sign * d, cl


def _sd_mesh_face_plane(m: MeshData, p: np.ndarray) -> np.ndarray:
    """The paper's face-plane distance for meshes: least |BP . N| over all faces.

    Inside points (closed meshes) keep the true negative distance.
    """
    d, _ = _sd_mesh(m, p)
    if len(p) == 0:
        return d
    plane = np.min(np.abs(np.einsum("nfj,fj->nf", p[:, None, :] - m.a[None, :, :], m.face_normals)), axis=1)
    return np.where(d < 0.0, d, plane)


def signed_distance_batch(stype: ShapeType, size: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance of points to primitives of one type with per-point sizes.

    Args:
        stype: any type but MESH.
        size: (n, k) sizes per point (k as in :class:`Shape`; plane ignores it).
        points: (n, 3) points in each shape's frame.

    Returns:
        d: (n,) signed distance, negative inside.
        closest: (n, 3) closest surface point, in the shape frame.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    s = np.asarray(size, dtype=float).reshape(len(p), -1)
    if stype is ShapeType.BOX:
        return _sd_box(s[:, :3], p)
    if stype is ShapeType.SPHERE:
        return _sd_sphere(s[:, 0], p)
    if stype is ShapeType.CAPSULE:
        return _sd_capsule(s[:, 0], s[:, 1], p)
    if stype is ShapeType.CYLINDER:
        return _sd_cylinder(s[:, 0], s[:, 1], p)
    if stype is ShapeType.ELLIPSOID:
        return _sd_ellipsoid(s[:, :3], p)[:2]
    if stype is ShapeType.PLANE:
        return _sd_plane(p)
    raise ValueError(f"signed_distance_batch does not take {stype}")


def signed_distance_value_batch(stype: ShapeType, size: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The distance (n,) of :func:`signed_distance_batch` alone (boxes and
    cylinders skip their closest points; the values are the same)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    s = np.asarray(size, dtype=float).reshape(len(p), -1)
    if stype is ShapeType.BOX:
        return _sd_box_value(s[:, :3], p)[0]
    if stype is ShapeType.CYLINDER:
        return _sd_cylinder_value(s[:, 0], s[:, 1], p)[0]
    return signed_distance_batch(stype, s, p)[0]


def signed_distance(shape: Shape, points: np.ndarray,
                    limit: np.ndarray | float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance from points to a shape's surface, negative inside.

    Args:
        shape: the shape.
        points: (n, 3) points in the shape's frame.
        limit: None, or a value per point (or one for all) at and beyond
            which the caller needs no exact distance: a mesh then answers a
            point that provably lies at least that far with a lower bound
            (>= limit) and a NaN closest point instead of searching its
            nearest triangle (:class:`_BoundGrid`). Points below the limit,
            and every primitive, get the exact answer.

    Returns:
        d: (n,) signed distance (unsigned for open meshes).
        closest: (n, 3) closest surface point in the shape's frame.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if shape.type is ShapeType.MESH:
        return _sd_mesh(shape.mesh, p, None if limit is None else np.broadcast_to(np.asarray(limit, float), len(p)))
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


def face_plane_distance_batch(stype: ShapeType, size: np.ndarray, points: np.ndarray) -> np.ndarray:
    """:func:`face_plane_distance` for primitives of one type with per-point sizes, (n,)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if stype is ShapeType.BOX:
        return _sd_box_face_plane(np.asarray(size, dtype=float).reshape(len(p), -1)[:, :3], p)
    return signed_distance_batch(stype, size, p)[0]


def face_plane_distance(shape: Shape, points: np.ndarray) -> np.ndarray:
    """The paper's distance ``|BP . N|`` to the nearest face plane, (n,).

    Only boxes, planes and meshes have faces; curved primitives return their
    true signed distance (the paper measures curved surfaces exactly too).
    Inside points return the true negative distance: the paper decides
    containment first.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if shape.type is ShapeType.MESH:
        return _sd_mesh_face_plane(shape.mesh, p)
    return face_plane_distance_batch(shape.type, np.broadcast_to(shape.size, (len(p), len(shape.size))), p)


# ---------------------------------------------------------------------------
# Segment queries (capsule axes against shapes).


def _golden_min(f, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Minimise n convex functions f(t) (vectorised, t (n,)) over [0, 1].

    Golden-section search keeps a bracket of the minimiser; the ends 0 and 1
    are evaluated too so a minimum at an end is exact.
    Returns (value (n,), t (n,)).
    """
    a = np.zeros(n)
    b = np.ones(n)
    c = b - _INVPHI
    d = _INVPHI * np.ones(n)
    fc = f(c)
    fd = f(d)
    for _ in range(_GOLDEN_ITERS):
        # Minimiser in [a, d] (left) or [c, b]; the surviving inner point is
        # reused and one new point is evaluated.
        left = fc < fd
        b = np.where(left, d, b)
        a = np.where(left, a, c)
        c_new = np.where(left, b - _INVPHI * (b - a), d)
        d_new = np.where(left, c, a + _INVPHI * (b - a))
        f_new = f(np.where(left, c_new, d_new))
        fc, fd = np.where(left, f_new, fd), np.where(left, fc, f_new)
        c, d = c_new, d_new
    tm = np.where(fc < fd, c, d)
    fm = np.minimum(fc, fd)
    f0 = f(np.zeros(n))
    f1 = f(np.ones(n))
    val = np.minimum(fm, np.minimum(f0, f1))
    t = np.where(val == f0, 0.0, np.where(val == f1, 1.0, tm))
    return val, t


def _derivative_min(fg, n: int, tol: float = 1e-14, max_iter: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """Minimise n convex functions over [0, 1] from their (sub)derivatives.

    ``fg(t, rows)`` returns the values and derivatives at ``t`` of the
    functions ``rows``. A minimum at an end is taken when the derivative
    there points outward; otherwise the minimiser stays bracketed by the
    derivative's sign change. Steps are secant steps on the derivative
    through the last two iterates (superlinear where the function is smooth);
    when one leaves the bracket, or the bracket failed to halve over two
    steps, the step goes to where the tangent lines at the bracket's ends
    cross (which finds a kink, as inside the solid), or halves the bracket if
    that point is not inside it. Iteration stops when the bracket or the
    step is below ``tol``. The ends are compared with the interior answer, as
    in a line search. Returns (value (n,), t (n,)).
    """
    rows = np.arange(n)
    f0, g0 = fg(np.zeros(n), rows)
    f1, g1 = fg(np.ones(n), rows)
    t = np.where(g0 >= 0.0, 0.0, 1.0)
    fm = np.where(g0 >= 0.0, f0, f1)
    act = np.nonzero((g0 < 0.0) & (g1 > 0.0))[0]
    m = len(act)
    lo, flo, glo = np.zeros(m), f0[act], g0[act]
    hi, fhi, ghi = np.ones(m), f1[act], g1[act]
    ta, ga = lo.copy(), glo.copy()  # previous iterate
    tb, gb = hi.copy(), ghi.copy()  # last iterate
    width = np.ones(m)  # bracket width two steps ago
    fc = np.zeros(m)
    for it in range(max_iter):
        if len(act) == 0:
            break
        den = gb - ga
        ok = den != 0.0
        tn = tb - np.where(ok, gb, 0.0) * (tb - ta) / np.where(ok, den, 1.0)
        slow = (it % 2 == 1) & (hi - lo > 0.5 * width)
        if it % 2 == 1:
            width = hi - lo
        bad = ~ok | ~((tn > lo) & (tn < hi)) | slow
        cross = (fhi - flo + glo * lo - ghi * hi) / (glo - ghi)
        cross = np.where((cross > lo) & (cross < hi), cross, 0.5 * (lo + hi))
        tn = np.where(bad, cross, tn)
        fn, gn = fg(tn, act)
        step = np.abs(tn - tb)
        right = gn > 0.0
        lo, flo, glo = np.where(right, lo, tn), np.where(right, flo, fn), np.where(right, glo, gn)
        hi, fhi, ghi = np.where(right, tn, hi), np.where(right, fn, fhi), np.where(right, gn, ghi)
        ta, ga, tb, gb, fc = tb, gb, tn, gn, fn
        done = (gn == 0.0) | (hi - lo <= tol) | (step <= tol)
        t[act[done]], fm[act[done]] = tb[done], fc[done]
        keep = ~done
        act, lo, flo, glo, hi, fhi, ghi, ta, ga, tb, gb, width, fc = (
            x[keep] for x in (act, lo, flo, glo, hi, fhi, ghi, ta, ga, tb, gb, width, fc))
    if len(act):
        t[act], fm[act] = tb, fc
    val = np.minimum(fm, np.minimum(f0, f1))
    t = np.where(val == f0, 0.0, np.where(val == f1, 1.0, t))
    return val, t


def segment_signed_distance_batch(
    stype: ShapeType, size: np.ndarray, a: np.ndarray, b: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Least signed distance over segments ``a b`` to primitives of one type.

    Args:
        stype: any type but MESH.
        size: (n, k) sizes per segment.
        a, b: (n, 3) segment ends in each shape's frame.

    Returns:
        d: (n,) least signed distance along the segment (negative: the
            segment enters the solid).
        t: (n,) parameter where it is reached, point ``a + t (b - a)``.
    """
    a = np.asarray(a, dtype=float).reshape(-1, 3)
    b = np.asarray(b, dtype=float).reshape(-1, 3)
    n = len(a)
    s = np.asarray(size, dtype=float).reshape(n, -1)
    if n == 0:
        return np.zeros(0), np.zeros(0)
    if stype is ShapeType.SPHERE:
        d, t, _ = point_segment(np.zeros_like(a), a, b)
        return d - s[:, 0], t
    if stype is ShapeType.CAPSULE:
        p0 = np.zeros_like(a)
        p1 = np.zeros_like(a)
        p0[:, 2] = -s[:, 1]
        p1[:, 2] = s[:, 1]
        d, t, _, _, _ = segment_segment(a, b, p0, p1)
        return d - s[:, 0], t
    if stype is ShapeType.PLANE:
        lower_b = b[:, 2] < a[:, 2]
        return np.minimum(a[:, 2], b[:, 2]), np.where(lower_b, 1.0, 0.0)
    ab = b - a
    if stype is ShapeType.ELLIPSOID:
        # The derivative along the segment is the outward normal at the
        # closest point (the gradient of the signed distance) dotted with the
        # segment. Each solve is warm-started from the row's previous one.
        e = s[:, :3]
        lam = np.full(n, np.nan)

        def fg(t, rows):
            er = e[rows]
            prev = lam[rows]
            d, cl, lam[rows] = _sd_ellipsoid(er, a[rows] + t[:, None] * ab[rows],
                                             None if np.isnan(prev).any() else prev)
            nrm = cl / (er * er)
            g = np.einsum("ij,ij->i", nrm, ab[rows]) / row_norm(nrm)
            return d, g

        return _derivative_min(fg, n)
    else:
        def f(t):
            return signed_distance_value_batch(stype, s, a + t[:, None] * ab)

    return _golden_min(f, n)


_GOLDEN_TYPES = (ShapeType.BOX, ShapeType.CYLINDER)


def segment_signed_distance_mixed(
    types: np.ndarray, size: np.ndarray, a: np.ndarray, b: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`segment_signed_distance_batch` for rows of several primitive types.

    ``types`` (n,) holds each row's type as its index in ``list(ShapeType)``
    (not MESH). Rows whose type needs a line search (box, cylinder) share one
    golden-section loop; the answers are those of
    :func:`segment_signed_distance_batch` row for row.
    """
    a = np.asarray(a, dtype=float).reshape(-1, 3)
    b = np.asarray(b, dtype=float).reshape(-1, 3)
    n = len(a)
    s = np.asarray(size, dtype=float).reshape(n, -1)
    types = np.asarray(types, dtype=np.int64).reshape(n)
    d = np.full(n, np.inf)
    t = np.zeros(n)
    golden = []
    all_types = list(ShapeType)
    for code in np.unique(types):
        stype = all_types[code]
        rows = np.nonzero(types == code)[0]
        if stype in _GOLDEN_TYPES:
            golden.append((stype, rows))
        else:
            d[rows], t[rows] = segment_signed_distance_batch(stype, s[rows], a[rows], b[rows])
    if golden:
        rows = np.concatenate([r for _, r in golden])
        ga, gab = a[rows], b[rows] - a[rows]
        parts = []
        start = 0
        for stype, r in golden:
            parts.append((stype, slice(start, start + len(r)), s[r]))
            start += len(r)

        def f(u):
            x = ga + u[:, None] * gab
            out = np.empty(len(u))
            for stype, sl, sz in parts:
                out[sl] = signed_distance_value_batch(stype, sz, x[sl])
            return out

        d[rows], t[rows] = _golden_min(f, len(rows))
    return d, t


def _mesh_segment_unsigned(m: MeshData, a: np.ndarray, b: np.ndarray,
                           k: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact unsigned distance from segments to a mesh, its parameter and face.

    Same cut-off as :func:`_mesh_nearest`, queried from the segment midpoint
    with the half length added to the triangle reach.
    """
    n = len(a)
    nf = len(m.faces)
    k = min(k, nf)
    mid = 0.5 * (a + b)
    half = 0.5 * row_norm(b - a)
    dk, idx = m.tree.query(mid, k=k)
    dk = dk.reshape(n, k)
    fi = idx.reshape(n, k).ravel()
    rows = np.repeat(np.arange(n), k)
    d, t, _ = segment_triangle(a[rows], b[rows], m.a[fi], m.b[fi], m.c[fi])
    d = d.reshape(n, k)
    t = t.reshape(n, k)
    j = np.argmin(d, axis=1)
    best = d[np.arange(n), j]
    tb = t[np.arange(n), j]
    fb = fi[np.arange(n) * k + j]
    redo = np.nonzero((k < nf) & (best > dk[:, -1] - m.reach - half))[0]
    if len(redo):
        local, fi2 = _faces_within(m, mid[redo], best[redo] + half[redo])
        rows2 = redo[local]
        d2, t2, _ = segment_triangle(a[rows2], b[rows2], m.a[fi2], m.b[fi2], m.c[fi2])
        o = np.lexsort((d2, rows2))
        first = o[np.r_[True, rows2[o][1:] != rows2[o][:-1]]]
        r = rows2[first]
        better = d2[first] < best[r]
        best[r[better]] = d2[first[better]]
        tb[r[better]] = t2[first[better]]
        fb[r[better]] = fi2[first[better]]
    return best, tb, fb


_MESH_SAMPLES = np.linspace(0.0, 1.0, 9)


def _segment_sd_mesh(m: MeshData, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = len(a)
    if n == 0:
        return np.zeros(0), np.zeros(0)
    du, tu, face = _mesh_segment_unsigned(m, a, b)
    if not m.closed:
        return du, tu
    # Penetration: the segment touches the surface, or lies inside. A segment
    # clear of the surface is wholly on one side, decided at its nearest
    # point by the pseudonormal of the nearest triangle's closest feature
    # (that triangle is also the nearest one to that point).
    ts = _MESH_SAMPLES
    x = a + tu[:, None] * (b - a)
    _, cl, reg = point_triangle(x, m.a[face], m.b[face], m.c[face])
    inside = _mesh_sign(m, x, cl, face, reg) < 0.0
    cand = np.nonzero((du <= 0.0) | inside)[0]
    d = du.copy()
    t = tu.copy()
    if len(cand):
        pts = a[cand, None, :] + ts[None, :, None] * (b - a)[cand, None, :]
        ds, _ = _sd_mesh(m, pts.reshape(-1, 3))
        ds = ds.reshape(len(cand), len(ts))
        j = np.argmin(ds, axis=1)
        dmin = ds[np.arange(len(cand)), j]
        d[cand] = np.minimum(dmin, 0.0)
        t[cand] = np.where(dmin < 0.0, ts[j], tu[cand])
    return d, t


def segment_signed_distance(shape: Shape, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least signed distance from segments ``a b`` (n, 3) to a shape, in its frame.

    Returns ``(d (n,), t (n,))``: the signed distance of the segment (of a
    capsule's axis) to the shape and the parameter of its deepest or nearest
    point. See the module docstring for the accuracy of each type.
    """
    a = np.asarray(a, dtype=float).reshape(-1, 3)
    b = np.asarray(b, dtype=float).reshape(-1, 3)
    if shape.type is ShapeType.MESH:
        return _segment_sd_mesh(shape.mesh, a, b)
    return segment_signed_distance_batch(shape.type, np.broadcast_to(shape.size, (len(a), len(shape.size))), a, b)


def least_signed_distance(shapes: list[Shape], rotations: np.ndarray, positions: np.ndarray,
                          points: np.ndarray, limit: float | None = None) -> np.ndarray:
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

    Every point is taken into every part's frame at once; primitives of one
    type are answered in one batched call and each mesh in one call (its
    k-d tree, not its bound grid: these points are seldom asked again). No
    broad phase (meant for a few parts and points, e.g. placing a cable's
    initial shape; :mod:`checker.interference` prunes for the per-step
    checks). No parts: +inf.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    out = np.full(len(p), np.inf)
    if not shapes or not len(p):
        return out
    rot = np.asarray(rotations, float).reshape(-1, 3, 3)
    pos = np.asarray(positions, float).reshape(-1, 3)
    local = np.einsum("pji,pnj->pni", rot, p[None, :, :] - pos[:, None, :])   # (P, n, 3)
    kinds: dict = {}
    for k, sh in enumerate(shapes):     # group parts: one call per type or mesh
        kinds.setdefault(("mesh", id(sh)) if sh.mesh is not None else sh.type, []).append(k)
    for key, members in kinds.items():
        members = np.asarray(members)
        sh = shapes[members[0]]
        loc = local[members].reshape(-1, 3)
        if sh.mesh is not None:
            d = _mesh_least(sh.mesh, loc, limit)
        else:
            size = np.repeat(np.stack([shapes[m].size for m in members]), len(p), axis=0)
            d = signed_distance_value_batch(sh.type, size, loc)
        out = np.minimum(out, d.reshape(len(members), len(p)).min(axis=0))
    return out


def _mesh_least(m: MeshData, p: np.ndarray, limit: float | None) -> np.ndarray:
    """Signed distance (n,) of one-off points to a mesh by its k-d tree (no
    grid to fill), points beyond ``limit`` of its box answered by the box
    distance (see :func:`least_signed_distance`)."""
    if limit is None:
        return _sd_mesh(m, p, grid=False)[0]
    gap = np.maximum(np.maximum(m.lo - p, p - m.hi), 0.0)
    d = np.sqrt(np.einsum("ij,ij->i", gap, gap))
    near = np.flatnonzero(~(d > limit))
    if len(near):
        d[near] = _sd_mesh(m, p[near], grid=False)[0]
    return d
