"""The exact nearest triangle of a mesh for query points, by its k-d trees.

A mesh's :class:`~cablecheck.checker.meshdata.MeshData` keeps a k-d tree over its
triangle centroids and the same split by the triangles' reach; here the k
nearest centroids give a first answer that a proven cut-off either accepts
or widens to every triangle that may beat it (:func:`faces_within`); a
small mesh bounds every triangle by its box instead. The sign of a distance
comes from the angle-weighted pseudonormal of the closest feature
(Baerentzen and Aanaes 2005).

Not here: the lazily filled grid that answers most repeated queries
(:mod:`cablecheck.checker.meshgrid`), signed distances as the checker asks them
(:mod:`cablecheck.checker.meshdata`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cablecheck.checker.closest import REGION_EDGE_AB, REGION_VERT_A, point_triangle

if TYPE_CHECKING:
    from cablecheck.checker.meshdata import MeshData


def faces_within(m: MeshData, q: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rows, faces): for each query point q[i], every face whose triangle may
    come within radius[i] of it: those whose box does (the mesh's box tree,
    :attr:`MeshData.forest`, lists the boxes meeting each point's cube,
    which the ball then cuts). A superset, exact to filter."""
    r = np.asarray(radius, float) * (1 + 1e-12) + 1e-300
    rows, faces = m.forest.query(np.zeros(len(q), np.int64), q - r[:, None], q + r[:, None])
    # A triangle is no nearer than its box: cheaper than the exact test it saves.
    qr = q[rows]
    gap = np.maximum(np.maximum(m.tri_lo[faces] - qr, qr - m.tri_hi[faces]), 0.0)
    keep = np.einsum("ij,ij->i", gap, gap) <= np.square(r[rows])
    return rows[keep], faces[keep]


def mesh_nearest(m: MeshData, p: np.ndarray, k: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exact nearest triangle of a mesh for points ``p`` (n, 3).

    Takes the k nearest centroids; a triangle whose centroid is farther than
    the k-th one cannot beat the best found if ``best <= d_k - reach``. Points
    failing that bound are redone with every triangle that may come within
    ``best`` (:func:`faces_within`: its centroid within ``best`` plus its
    reach class's bound).

    A small mesh (up to ``BOX_FACES`` triangles, ``n * F`` up to
    ``BOX_PAIRS``) takes another road, exact
    too: the triangle of the nearest centroid gives an upper bound, and
    every triangle whose bounding box is no farther is a candidate (few for
    the large, uneven triangles of a low-poly CAD part, where the
    centroids say little).

    Returns dist (n,), closest (n, 3), face index (n,), region code (n,).
    """
    nf = len(m.faces)
    if nf <= BOX_FACES and len(p) * nf <= BOX_PAIRS:
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
        local, fi2 = faces_within(m, p[redo], best[redo])
        rows2 = redo[local]
        d2, cl2, reg2 = point_triangle(p[rows2], m.a[fi2], m.b[fi2], m.c[fi2])
        # Least per point: sort by (row, distance) and take each row's first (ties to the lowest face).
        o = np.lexsort((fi2, d2, rows2))
        first = o[np.r_[True, rows2[o][1:] != rows2[o][:-1]]]
        r = rows2[first]
        better = d2[first] < best[r]
        r, first = r[better], first[better]
        best[r] = d2[first]
        out_cl[r] = cl2[first]
        out_f[r] = fi2[first]
        out_r[r] = reg2[first]
    return best, out_cl, out_f, out_r


BOX_FACES = 64
"""Meshes up to this many triangles: :func:`_mesh_nearest_small` (timed
faster on a 20-triangle bracket, slower from a few hundred triangles)."""

BOX_PAIRS = 1 << 17
"""Point-triangle pairs up to which :func:`mesh_nearest` bounds every pair
by the triangles' boxes (memory: a few MB)."""


def _mesh_nearest_small(m: MeshData, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`mesh_nearest` by triangle boxes against every point (see there)."""
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


def mesh_sign(m: MeshData, p: np.ndarray, cl: np.ndarray, face: np.ndarray, region: np.ndarray) -> np.ndarray:
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
