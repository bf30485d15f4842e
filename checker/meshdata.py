"""A triangle mesh's acceleration data, built once per shape, and its signed distance.

:class:`MeshData` checks closure with trimesh, orients the mesh outward and
keeps the normals, pseudonormals, k-d tree, box tree and bound grid the queries
use; :func:`sd_mesh` answers points with them (through the bound grid,
exact nearest triangle, sign from the pseudonormals). Not here: segment
queries (:mod:`cablecheck.checker.segments`), poses (:mod:`cablecheck.checker.shapes`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from cablecheck.checker.bvh import TriangleForest
from cablecheck.checker.closest import cross, row_norm
from cablecheck.checker.meshgrid import BoundGrid
from cablecheck.checker.meshnearest import mesh_nearest, mesh_sign

if TYPE_CHECKING:
    from scipy.spatial import cKDTree


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
        closed: the mesh is watertight and consistently wound, so inside and
            outside are defined and distances are signed.
        lo, hi: (3,) bounding box corners.
        tri_lo, tri_hi: (F, 3) each triangle's bounding box.
        bound: the :class:`BoundGrid` of lower bounds for :func:`signed_distance`'s ``limit``.
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
    closed: bool
    lo: np.ndarray
    hi: np.ndarray
    tri_lo: np.ndarray
    tri_hi: np.ndarray
    bound: BoundGrid = field(default=None, repr=False)

    @cached_property
    def forest(self) -> TriangleForest:
        """A box tree over the triangles (built the first time a segment
        asks: most meshes of a scene never meet a cable): every triangle
        whose box meets a box, for many boxes in one pass."""
        return TriangleForest.build(self.tri_lo, self.tri_hi, np.zeros(len(self.faces), np.int64), 1)

    @cached_property
    def convex(self) -> bool:
        """The mesh is closed and convex (trimesh's test: no two faces meet
        at an edge folded inward beyond its tolerance), asked the first time
        a segment goes inside it: its depth along a segment is then the least
        of its face planes' distances (:func:`cablecheck.checker.segments.segment_sd_mesh`)."""
        import trimesh  # loaded already by build

        return self.closed and bool(trimesh.Trimesh(vertices=self.vertices, faces=self.faces, process=False).is_convex)

    @staticmethod
    def build(vertices: np.ndarray, faces: np.ndarray) -> MeshData:
        """Check closure with trimesh, orient outward, precompute normals and tree."""
        import trimesh  # a third of a second to import: only a mesh part pays it
        from scipy.spatial import cKDTree  # loaded already by trimesh

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
            tree=cKDTree(centroids), closed=closed, lo=v.min(axis=0), hi=v.max(axis=0),
            tri_lo=np.minimum(np.minimum(a, b), c), tri_hi=np.maximum(np.maximum(a, b), c),
            bound=BoundGrid(v.min(axis=0), v.max(axis=0)),
        )


def sd_mesh(m: MeshData, p: np.ndarray, limit: np.ndarray | None = None,
             grid: bool = True, lower: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance and closest points of a mesh; ``grid`` False: the
    k-d tree alone, for one-off queries that would only fill the bound grid;
    ``lower``: with ``limit``, the bound grid's lower bounds at p when the
    caller has them already (:meth:`BoundGrid.bounds`)."""
    if len(p) == 0:
        return np.zeros(0), np.zeros((0, 3))
    if limit is not None:
        lb = m.bound.lower(m, p) if lower is None else lower
        far = lb > limit + 1e-9 * (np.abs(limit) + m.bound.h)   # the caller's own comparison stays safe
        if far.any():
            d = lb.copy()
            cl = np.full((len(p), 3), np.nan)
            near = np.flatnonzero(~far)
            if len(near):
                d[near], cl[near] = sd_mesh(m, p[near])
            return d, cl
    d, cl, face, region = m.bound.nearest(m, p) if grid else mesh_nearest(m, p, 8)
    sign = mesh_sign(m, p, cl, face, region)
    return sign * d, cl


def sd_mesh_face_plane(m: MeshData, p: np.ndarray) -> np.ndarray:
    """The paper's face-plane distance for meshes: least |BP . N| over all faces.

    Inside points (closed meshes) keep the true negative distance.
    """
    d, _ = sd_mesh(m, p)
    if len(p) == 0:
        return d
    plane = np.min(np.abs(np.einsum("nfj,fj->nf", p[:, None, :] - m.a[None, :, :], m.face_normals)), axis=1)
    return np.where(d < 0.0, d, plane)
