"""A coarse grid over a mesh for lower bounds and short nearest-triangle candidate lists.

Filled lazily (cells are computed exactly the first time a query meets
them and kept), so a run pays only for the cells its cables come near.
Not here: the k-d tree search it falls back to and fills its cells with
(:mod:`cablecheck.checker.meshnearest`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cablecheck.checker.arrays import all_columns
from cablecheck.checker.closest import point_triangle, row_norm
from cablecheck.checker.meshnearest import faces_within, mesh_nearest, mesh_sign

if TYPE_CHECKING:
    from cablecheck.checker.meshdata import MeshData


_GRID_CELLS = 72
"""Cells of :class:`BoundGrid` along the mesh's longest side."""

_GRID_PAD = 16
"""Cells of :class:`BoundGrid` beyond the mesh's box on every side (a
quarter of the mesh's longest side: a cable's radius, clearance and skip
horizon together stay within it on arm links, so their queries need not
fall back to the k-d tree)."""


class BoundGrid:
    """A coarse grid over a mesh, filled lazily, for bounds and short candidate lists.

    Lower bounds: the signed distance to a closed mesh (and the unsigned one
    to an open mesh) is 1-Lipschitz, so the exact value ``v`` at a cell's
    centre ``c`` bounds it at any point ``p`` from below by ``v - |p - c|``;
    outside the mesh's box the distance to the box is a bound too (and the
    only one beyond the grid). :func:`signed_distance` with a ``limit``
    skips the nearest-triangle search for points that provably lie beyond it.

    Candidates: the triangle nearest to a point p of the cell is within
    ``|v| + 2 h`` of the centre (``h`` the cell's half diagonal: it is within
    ``|v| + h`` of p), so the triangles :func:`faces_within` that radius of
    the centre hold it, listed nearest first by their boxes; a point's own
    upper bound (its distance to the centre's closest surface point, kept
    with the cell) takes a prefix of that list and cuts it by the
    triangles' boxes.
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
        self.closest = np.zeros((n, 3))          # each centre's closest surface point
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
        inside = all_columns((ijk >= 0) & (ijk < self.dims))
        ijk = ijk[inside]
        return inside, np.ravel_multi_index(ijk.T, self.dims), self.origin + (ijk + 0.5) * self.h

    def _fill(self, m: MeshData, flat: np.ndarray) -> None:
        missing = np.isnan(self.values[flat])
        if missing.any():
            todo = np.unique(flat[missing])
            c = self.origin + (np.stack(np.unravel_index(todo, self.dims), axis=1) + 0.5) * self.h
            d, cl, face, region = mesh_nearest(m, c, 8)
            self.values[todo] = mesh_sign(m, c, cl, face, region) * d
            self.closest[todo] = cl

    def _list(self, m: MeshData, flat: np.ndarray) -> None:
        missing = self.count[flat] < 0
        if not missing.any():
            return
        todo = np.unique(flat[missing])
        c = self.origin + (np.stack(np.unravel_index(todo, self.dims), axis=1) + 0.5) * self.h
        radius = np.abs(self.values[todo]) + 2.0 * self.half_diag * (1 + 1e-9)
        rows, faces = faces_within(m, c, radius)
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

    def lower(self, m: MeshData, p: np.ndarray) -> np.ndarray:
        """(n,) lower bounds on the signed distance at points p (-inf where none)."""
        return self.bounds(m, p)[0]

    def bounds(self, m: MeshData, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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

    def nearest(self, m: MeshData, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:func:`mesh_nearest` for points p (n, 3): through the cells' lists
        where the point's cell is near the surface, else the k-d tree."""
        inside, flat, centre = self._cells(p)
        rows_in = np.flatnonzero(inside)
        if len(flat):
            self._fill(m, flat)
            close = np.abs(self.values[flat]) <= _GRID_NEAR * self.h
            rows_in, flat, centre = rows_in[close], flat[close], centre[close]
        if not len(rows_in):
            return mesh_nearest(m, p, 8)
        self._list(m, flat)
        q = p[rows_in]
        # An upper bound on the distance at q: its way to the centre's
        # closest surface point (with the rounding slack of `bounds`).
        r = row_norm(q - centre)
        ub = row_norm(q - self.closest[flat]) + 1e-9 * (np.abs(self.values[flat]) + self.h)
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
        qr = q.take(rows, axis=0)                      # take: rows of (n, 3) arrays, faster than indexing
        g = np.maximum(np.maximum(m.tri_lo.take(faces, axis=0) - qr, qr - m.tri_hi.take(faces, axis=0)), 0.0)
        keep = np.einsum("ij,ij->i", g, g) <= np.square(ub[rows] * (1 + 1e-12) + 1e-300)
        rows, faces = rows[keep], faces[keep]
        d, cl, reg = point_triangle(q.take(rows, axis=0), m.a.take(faces, axis=0), m.b.take(faces, axis=0),
                                    m.c.take(faces, axis=0))
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
            out_d[rest], out_cl[rest], out_f[rest], out_r[rest] = mesh_nearest(m, p[rest], 8)
        return out_d, out_cl, out_f, out_r


_KEY_BITS = 40
"""Low bits of a :class:`BoundGrid` list entry's key: its box distance in
units of 2^-20 cell sides (clipped: far entries share the largest key)."""

_KEY_MAX = (1 << _KEY_BITS) - 1

_GRID_NEAR = 16
"""Cells of :class:`BoundGrid` whose centre lies within this many cell
sides of the surface answer nearest-triangle queries from their lists."""
