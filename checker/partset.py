"""Rigid parts prepared once for sweeps and part-part checks, and placed per pose set.

:class:`PartSet` holds, for every part, its triangle surface in its own frame
(:mod:`cablecheck.checker.tessellate`), outward normals and edge pseudonormals per
triangle, containment probes, its box in its frame and one
:class:`~cablecheck.checker.bvh.TriangleForest` over all parts' triangles. It is built
once; a new set of poses only needs :meth:`PartSet.place`, which computes the
oriented boxes in the assembly (world) frame, their world AABBs and the
assembly boxes. Queries reuse both.

Containment probes: every vertex, and every triangle's centroid moved inward
along its normal by ``PROBE_DEPTH`` of the part's size. A probe strictly
inside another part (its signed distance below ``-TOUCH`` of the size) means the
two overlap; coincident parts and parts inside parts are found this way
without a crossing of surfaces. Parts sharing a face from opposite sides put
no probe inside each other, so they only touch.

Not here: the contact tests themselves (:mod:`cablecheck.checker.sweep`,
:mod:`cablecheck.checker.parts`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from cablecheck.checker.arrays import ranges
from cablecheck.checker.bvh import Assemblies, TriangleForest, assembly_boxes, transformed_aabb
from cablecheck.checker.convex import CONVEX
from cablecheck.checker.shapes import Shape, ShapeType, signed_distance, signed_distance_batch
from cablecheck.checker.tessellate import part_surfaces

TOUCH = 1e-6
"""Touching tolerance, relative to a part's box diagonal: surfaces closer than
this count as touching, overlaps thinner than this are not overlaps. MuJoCo
stores mesh vertices as float32 (about 1e-7 relative), so parts meshed to sit
flush on each other touch rather than overlap."""

PROBE_DEPTH = 10 * TOUCH
"""Inward offset of the centroid probes, relative to the part's box diagonal."""


@dataclass(frozen=True, eq=False)
class Placement:
    """Parts placed by one set of poses.

    Attributes:
        rot: (P, 3, 3) part-to-world rotations.
        pos: (P, 3) part origins in the world.
        centre: (P, 3) OBB centres in the world.
        lo, hi: (P, 3) world AABBs of the OBBs (infinite for planes).
        asm_lo, asm_hi: (A, 3) world AABBs of the assemblies.
    """

    rot: np.ndarray
    pos: np.ndarray
    centre: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    asm_lo: np.ndarray
    asm_hi: np.ndarray

    def world(self, part: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Points (n, ..., 3) of parts ``part`` (n,) from their frames to the world."""
        r = self.rot[part]
        shape = points.shape
        p = points.reshape(len(part), int(np.prod(shape[1:-1], dtype=np.int64)), 3)
        return (np.einsum("nij,nkj->nki", r, p) + self.pos[part][:, None, :]).reshape(shape)

    def local(self, part: np.ndarray, points: np.ndarray) -> np.ndarray:
        """World points (n, ..., 3) into the frames of parts ``part`` (n,)."""
        r = self.rot[part]
        shape = points.shape
        p = points.reshape(len(part), int(np.prod(shape[1:-1], dtype=np.int64)), 3) - self.pos[part][:, None, :]
        return np.einsum("nji,nkj->nki", r, p).reshape(shape)


@dataclass(frozen=True, eq=False)
class PartSet:
    """Parts' surfaces, trees and probes in their own frames; built once.

    Attributes:
        names: part names ("/"-separated assembly paths).
        groups: the rigid body each part rides on (parts of one group never
            move relative to each other).
        keepout: (P,) bool, keep-out zones.
        closed: (P,) bool, inside and outside are defined.
        plane: (P,) bool, the part is the half-space local z < 0.
        error: (P,) tessellation error bound (0 for boxes and meshes).
        shapes: the exact shapes (containment uses their signed distances).
        tris: (T, 3, 3) triangles in their part's frame, grouped by part.
        tri_part: (T,) part of each triangle.
        normals: (T, 3) unit outward normals.
        edge_normals: (T, 3, 3) pseudonormal of edge k (corner k to k + 1).
        vertices: (V, 3) all parts' vertices; vert_part (V,) their part.
        probes: (Q, 3) containment probes; probe_part (Q,) their part.
        lo, hi: (P, 3) boxes in the part frames.
        size: (P,) box diagonals (0 for planes).
        forest: triangle trees.
        assemblies: the assembly prefixes of ``names``.
        warnings: human-readable notes (open meshes).
    """

    names: tuple[str, ...]
    groups: tuple[str, ...]
    keepout: np.ndarray
    closed: np.ndarray
    plane: np.ndarray
    error: np.ndarray
    shapes: tuple[Shape, ...]
    tris: np.ndarray
    tri_part: np.ndarray
    normals: np.ndarray
    edge_normals: np.ndarray
    vertices: np.ndarray
    vert_part: np.ndarray
    probes: np.ndarray
    probe_part: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    size: np.ndarray
    forest: TriangleForest
    assemblies: Assemblies
    warnings: tuple[str, ...]

    @staticmethod
    def build(names: list[str], shapes: list[Shape], groups: list[str] | None = None,
              keepout: list[bool] | None = None, tolerance: float = 2.5e-4) -> "PartSet":
        """Tessellate, index and probe every part.

        Args:
            names, shapes: one per part.
            groups: rigid body per part (default: every part its own).
            keepout: keep-out flag per part (default: none).
            tolerance: tessellation tolerance of curved primitives (shape units).
        """
        n = len(names)
        groups = list(groups) if groups is not None else list(names)
        keepout = np.array(keepout if keepout is not None else [False] * n, bool)
        surf = part_surfaces(list(shapes), tolerance)
        closed, plane, error = surf.closed, surf.plane, surf.error
        warnings = tuple(f"part {names[i]!r}: open or non-manifold mesh, inside and outside "
                         "cannot be decided; only its surface is checked (crossings and "
                         "distances), not containment" for i in np.flatnonzero(~closed & ~plane))
        v, f = surf.vertices, surf.faces
        vcount = np.diff(surf.vert_start)
        fcount = np.diff(surf.face_start)
        vert_part = np.repeat(np.arange(n), vcount)
        tri_part = np.repeat(np.arange(n), fcount)
        tris = v[f]
        nrm = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        ln = np.linalg.norm(nrm, axis=1)
        nrm = nrm / np.where(ln > 0, ln, 1.0)[:, None]
        lo = np.full((n, 3), -np.inf)
        hi = np.full((n, 3), np.inf)
        has = np.flatnonzero(vcount > 0)
        if len(has):
            lo[has] = np.minimum.reduceat(v, surf.vert_start[has], axis=0)
            hi[has] = np.maximum.reduceat(v, surf.vert_start[has], axis=0)
        # boxes of the true shapes: a curved part's surface lies within its error of the triangles
        lo -= error[:, None]
        hi += error[:, None]
        size = np.where(plane, 0.0, np.linalg.norm(np.where(plane[:, None], 0.0, hi - lo), axis=1))
        # probes: every vertex, then every triangle's centroid moved inward, grouped by part
        depth = PROBE_DEPTH * size
        cen = tris.mean(axis=1) - depth[tri_part][:, None] * nrm
        probe_part = np.concatenate([vert_part, tri_part])
        order = np.argsort(probe_part, kind="stable")
        probes = np.concatenate([v, cen])[order]
        forest = TriangleForest.build(tris.min(axis=1), tris.max(axis=1), tri_part, n)
        return PartSet(tuple(names), tuple(groups), keepout, closed, plane, error, tuple(shapes),
                       tris, tri_part, nrm, _edge_pseudonormals(f, nrm, len(v)),
                       v, vert_part, probes, probe_part[order],
                       lo, hi, size, forest, Assemblies.of(list(names)), warnings)

    def tiled(self, idx: np.ndarray, copies: int) -> "PartSet":
        """The parts ``idx`` (K,) laid out ``copies`` times: part ``c K + k``
        of the result is part ``idx[k]`` (its surface, probes and tree, in
        the same order, gathered without tessellating again), so that one
        set of poses can place the same parts at many states at once."""
        idx = np.tile(np.asarray(idx, np.int64), copies)
        n = len(idx)

        def gather(part_of: np.ndarray, *arrays: np.ndarray):
            start = np.searchsorted(part_of, np.arange(len(self.names) + 1))
            first, cnt = start[idx], start[idx + 1] - start[idx]
            rows = ranges(first, cnt)
            return (np.repeat(np.arange(n), cnt),) + tuple(a[rows] for a in arrays)

        tri_part, tris, normals, edge_n = gather(self.tri_part, self.tris, self.normals, self.edge_normals)
        vert_part, verts = gather(self.vert_part, self.vertices)
        probe_part, probes = gather(self.probe_part, self.probes)
        forest = self.forest.tiled(idx)
        names = tuple(self.names[k] for k in idx)
        return PartSet(names, tuple(self.groups[k] for k in idx), self.keepout[idx], self.closed[idx],
                       self.plane[idx], self.error[idx], tuple(self.shapes[k] for k in idx), tris, tri_part,
                       normals, edge_n, verts, vert_part, probes, probe_part, self.lo[idx], self.hi[idx],
                       self.size[idx], forest, Assemblies.of(list(names)), ())

    def place(self, poses: np.ndarray) -> Placement:
        """World boxes of every part for poses (P, 4, 4)."""
        poses = np.asarray(poses, float)
        rot, pos = poses[:, :3, :3], poses[:, :3, 3]
        fin = ~self.plane
        lo = np.full((len(self.names), 3), -np.inf)
        hi = np.full((len(self.names), 3), np.inf)
        centre = pos.copy()
        if fin.any():
            lo[fin], hi[fin] = transformed_aabb(self.lo[fin], self.hi[fin], rot[fin], pos[fin])
            c = 0.5 * (self.lo[fin] + self.hi[fin])
            centre[fin] = np.einsum("nij,nj->ni", rot[fin], c) + pos[fin]
        # planes are left out of the assembly boxes (they would make them infinite)
        a_lo, a_hi = assembly_boxes(self.assemblies, np.where(fin[:, None], lo, np.inf),
                                    np.where(fin[:, None], hi, -np.inf))
        return Placement(rot, pos, centre, lo, hi, a_lo, a_hi)

    @cached_property
    def group_index(self) -> np.ndarray:
        """(P,) each part's rigid group (``groups``) numbered in order of first appearance."""
        number = {g: k for k, g in enumerate(dict.fromkeys(self.groups))}
        return np.array([number[g] for g in self.groups], np.int64)

    @cached_property
    def probe_start(self) -> np.ndarray:
        """(P + 1,) part k's probes are ``probes[probe_start[k]:probe_start[k + 1]]``."""
        return np.searchsorted(self.probe_part, np.arange(len(self.names) + 1))

    @cached_property
    def sd_groups(self) -> tuple[np.ndarray, tuple[tuple[ShapeType, Shape | None], ...], np.ndarray]:
        """Parts grouped for batched signed distances: key (P,) into kinds, kinds
        ((type, None) per primitive type, (MESH, a shape) per distinct mesh),
        and sizes (P, 3) (zero-padded)."""
        index: dict = {}
        kinds = []
        key = np.zeros(len(self.names), np.int64)
        size = np.zeros((len(self.names), 3))
        for k, sh in enumerate(self.shapes):
            tag = ("mesh", id(sh.mesh)) if sh.mesh is not None else sh.type
            if tag not in index:
                index[tag] = len(kinds)
                kinds.append((sh.type, sh if sh.mesh is not None else None))
            key[k] = index[tag]
            size[k, :min(3, len(sh.size))] = sh.size[:3]
        return key, tuple(kinds), size

    @cached_property
    def _hulls(self) -> dict[int, np.ndarray]:
        """Part -> its convex hull's vertices, filled as :meth:`hull_points` asks."""
        return {}

    def hull_points(self, part: int) -> np.ndarray:
        """(h, 3) the vertices of part ``part``'s convex hull in its frame
        (its triangles' corners where qhull cannot hull them: flat, or fewer
        than four), computed once: the hull is the same, its support a pass
        over fewer points (:mod:`cablecheck.checker.hullbound`)."""
        kept = self._hulls.get(part)
        if kept is None:
            from scipy.spatial import ConvexHull, QhullError  # loaded already by trimesh (meshes)

            start = np.searchsorted(self.vert_part, [part, part + 1])
            v = self.vertices[start[0]:start[1]]
            try:
                kept = v[ConvexHull(v).vertices] if len(v) > 4 else v
            except QhullError:
                kept = v
            self._hulls[part] = kept
        return kept

    @cached_property
    def convex_kind(self) -> np.ndarray:
        """(P,) index into :data:`cablecheck.checker.convex.CONVEX` of each primitive part, -1 for meshes and planes."""
        index = {t: k for k, t in enumerate(CONVEX)}
        return np.array([index.get(sh.type, -1) for sh in self.shapes], np.int64)

    @cached_property
    def axial(self) -> np.ndarray:
        """(P,) bool: the part is unchanged by any turn about its frame's z
        axis (a sphere, capsule or cylinder, an ellipsoid with equal x and
        y radii), as the part-part check measures it (true shapes, or a
        tessellation within ``error`` of them)."""
        kind = self.convex_kind
        size = self.sd_groups[2]
        types = [CONVEX.index(t) for t in (ShapeType.SPHERE, ShapeType.CAPSULE, ShapeType.CYLINDER)]
        round_ellipsoid = (kind == CONVEX.index(ShapeType.ELLIPSOID)) & (size[:, 0] == size[:, 1])
        return np.isin(kind, types) | round_ellipsoid

    def signed_distance(self, part: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Signed distances (n,) of points (n, 3), each in the frame of its
        part ``part`` (n,), to that part's true shape (negative inside; an
        open mesh's are unsigned), and the closest surface points (n, 3) in
        the same frames: one call per primitive type and per distinct mesh
        (:attr:`sd_groups`)."""
        part = np.asarray(part, np.int64)
        points = np.asarray(points, float).reshape(-1, 3)
        key, kinds, size = self.sd_groups
        kb = key[part]
        sd = np.empty(len(part))
        closest = np.empty((len(part), 3))
        for k in np.unique(kb):     # one call per primitive type or distinct mesh
            sel = np.flatnonzero(kb == k)
            stype, shape = kinds[k]
            if shape is not None:
                sd[sel], closest[sel] = signed_distance(shape, points[sel])
            else:
                sd[sel], closest[sel] = signed_distance_batch(stype, size[part[sel]], points[sel])
        return sd, closest

    def touch(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Touching tolerance (absolute) of part pairs ``a``, ``b`` (n,)."""
        return TOUCH * np.maximum(self.size[a], self.size[b])

    def half(self) -> np.ndarray:
        """(P, 3) half extents of the parts' boxes (0 for planes)."""
        return np.where(self.plane[:, None], 0.0, 0.5 * (self.hi - self.lo))

    def select(self, prefix: str) -> np.ndarray:
        """(P,) bool: parts named ``prefix`` or inside the assembly ``prefix``."""
        p = prefix.rstrip("/")
        return np.array([n == p or n.startswith(p + "/") for n in self.names], bool)


def _edge_pseudonormals(faces: np.ndarray, normals: np.ndarray, nverts: int) -> np.ndarray:
    """(F, 3, 3): for edge k of each face, the sum of the normals of the faces on it."""
    if not len(faces):
        return np.zeros((0, 3, 3))
    a = faces
    b = np.roll(faces, -1, axis=1)
    key = (np.minimum(a, b) * np.int64(nverts) + np.maximum(a, b)).ravel()
    _, inv = np.unique(key, return_inverse=True)
    rep = np.repeat(normals, 3, axis=0)
    acc = np.stack([np.bincount(inv, rep[:, k], minlength=inv.max() + 1) for k in range(3)], axis=1)
    return acc[inv].reshape(len(faces), 3, 3)
