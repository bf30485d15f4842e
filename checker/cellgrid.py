"""Points near points: a uniform grid of cubic cells, :class:`CellGrid`.

The points are binned into cells of one side and sorted by cell, the cells
ordered by (row, column, x) where x is the axis of largest extent: the cells
of one (row, column) "strip" that cover an interval of x then hold one
contiguous run of the sorted points. Two small tables say where each cell's
points start: one over the strips (rows x columns) and, per occupied strip,
one entry per x-cell between its first and last point. A query (a centre
and a radius r) reads off, for every strip within r, the run of points in
the x-cells within r: a handful of array operations per query, no tree and
no search. When either table would be large against the number of points
(few points spread far apart), the runs are found by binary search in the
sorted cell keys instead: the same runs, so memory stays proportional to the
points, not to the grid's volume. A few points (up to 64 by default) are
not binned at all: every pair is a candidate, which costs less than a grid.
Every candidate is then tested with the exact squared
distance, so the answer is an exact set: the pairs whose squared distance,
computed as ``(dx*dx + dy*dy) + dz*dz``, is at most ``r * r``.

Written by hand because scipy's ``cKDTree.query_pairs`` compares every point
of two nearby leaves with each other, which on the checker's chunks of cable
points costs several times this grid. Cell indices are computed with a
margin that covers their rounding (the cell side is at least 2**-20 of the
largest extent), so no pair within the radius is missed however far the
points are from the origin.

Deliberately not here: what the points stand for (chunks of cables, parts),
spheres of different radii (callers query with their largest and test
their own bound after).
"""

from __future__ import annotations

import numpy as np

from cablecheck.checker.arrays import within

_AXIS_CELLS = 2.0 ** 20
"""At most this many cells along an axis: keys fit in int64 and index rounding stays below _ROUND."""
_ROUND = 2.0 ** -30
"""Bound on the rounding of a cell coordinate (in cells) and of a difference of two."""
_UNDERFLOW = 1e-150
"""Below this distance a squared distance may underflow to 0: the least radius and cell side."""
_TABLE_PER_POINT = 64
"""The tables are used up to this many entries per point (plus _TABLE_MIN)."""
_TABLE_MIN = 4096
_BRUTE = 64
"""Up to this many points every pair is a candidate (no grid)."""


class CellGrid:
    """Points binned into cubic cells for fixed-radius neighbour queries.

    Args:
        x: (n, 3) finite points.
        cell: the cell side wanted (>= 0): queries of radius up to it look
            at the 3 x 3 x 3 cells around a point. The side actually used is
            a little larger (rounding margin), at least 2**-20 of the
            points' largest extent and at least 1e-150. Queries of a radius
            r look at about (2 r / cell + 1)**2 strips around a point.
        max_table: largest table (default: 64 entries per point plus
            4096); beyond it runs are found by binary search (the same
            answers).
        brute: up to this many points, no grid: every pair is a candidate
            (the same answers).
    """

    def __init__(self, x: np.ndarray, cell: float, max_table: int | None = None, brute: int = _BRUTE):
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        n = len(x)
        self.n = n
        xt = np.ascontiguousarray(x.T)                  # coordinate-major: fast column arithmetic
        if n:
            lo, hi = xt.min(axis=1), xt.max(axis=1)
            if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
                raise ValueError("cell grid points must be finite")
        else:
            lo = hi = np.zeros(3)
        self.brute = n <= brute
        if self.brute:
            self.order, self.xs, self.table = np.arange(n), xt, None
            return
        ext = hi - lo
        # the strips run along the axis of largest extent (x, last)
        ax = int(np.argmax(ext))
        self.axes = [a for a in range(3) if a != ax] + [ax]
        self.lo = lo[self.axes]
        self.h = max(float(cell), float(ext.max()) / _AXIS_CELLS, _UNDERFLOW) * (1.0 + 2.0 ** -28)
        self.dims = np.floor(ext[self.axes] / self.h).astype(np.int64) + 1
        q = self._cells(xt[self.axes])                      # (3, n) cell coordinates
        strip = q[0] * self.dims[1] + q[1]
        key = strip * self.dims[2] + q[2]
        order = np.argsort(key)
        self.order = order
        self.key = key.take(order)                          # cell keys, increasing
        self.xs = xt.take(order, axis=1)                    # points in sorted order, (3, n), original axes
        q = q.take(order, axis=1)
        self.q = q                                          # cell coordinates in sorted order
        strip = strip.take(order)
        # runs of one strip: its first and last x-cell, and a table of the
        # start of every x-cell from the first to one past the last
        first = np.empty(n, bool)
        first[:1] = True
        np.not_equal(strip[1:], strip[:-1], out=first[1:])
        run_start = np.flatnonzero(first)
        run = np.cumsum(first) - 1
        self.strips = strip.take(run_start)                 # occupied strips, increasing
        self.x_first = q[2].take(run_start)
        self.x_last = q[2].take(np.r_[run_start[1:], n] - 1) if n else np.zeros(0, np.int64)
        width = self.x_last - self.x_first + 2
        limit = _TABLE_PER_POINT * n + _TABLE_MIN if max_table is None else max_table
        n_strips = int(self.dims[0] * self.dims[1])
        if n_strips > limit or int(width.sum()) > limit:
            self.table = None
            return
        self.offset = np.cumsum(width) - width
        slot = self.offset.take(run) + q[2] - self.x_first.take(run)
        self.table = np.zeros(int(width.sum()) + 1, np.int64)
        np.cumsum(np.bincount(slot, minlength=len(self.table) - 1), out=self.table[1:])
        # one more run, empty, for the strips no point is in
        empty = len(self.strips)
        self.x_first = np.r_[self.x_first, 0]
        self.x_last = np.r_[self.x_last, -1]
        self.offset = np.r_[self.offset, 0]
        self.strip_run = np.full(n_strips, empty, np.int64)
        self.strip_run[self.strips] = np.arange(empty)

    def _cells(self, f: np.ndarray) -> np.ndarray:
        """Cell coordinates (3, n) of points (3, n) given in the grid's axis order."""
        return np.floor((f - self.lo[:, None]) / self.h).astype(np.int64)

    def _runs(self, strip: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Sorted positions (start, end) of the points in x-cells lo .. hi
        (inclusive) of strips ``strip`` (valid strip numbers, or -1 for
        none; any lo, hi)."""
        if self.table is None:
            # the same runs by binary search in the sorted keys
            base = strip * self.dims[2]
            s = np.searchsorted(self.key, base + np.maximum(lo, 0))
            e = np.searchsorted(self.key, base + np.minimum(hi, self.dims[2] - 1) + 1)
            none = strip < 0
            s[none] = e[none] = 0
            return s, e
        run = np.where(strip >= 0, self.strip_run.take(np.maximum(strip, 0)), len(self.strips))
        x0 = self.x_first.take(run)
        x1 = self.x_last.take(run) + 1
        base = self.offset.take(run) - x0
        return self.table.take(base + np.clip(lo, x0, x1)), self.table.take(base + np.clip(hi + 1, x0, x1))

    def _reach(self, r: np.ndarray | float) -> np.ndarray:
        """Cells to look at on either side for radius r (rounding included;
        below 1e-150 a squared distance may underflow to 0, so at least that)."""
        return np.ceil(np.maximum(np.asarray(r, float), _UNDERFLOW) / self.h * (1.0 + 2.0 ** -40) + _ROUND)

    def pairs(self, reach: float) -> tuple[np.ndarray, np.ndarray]:
        """All pairs i < j (indices into ``x``) with squared distance <= reach**2."""
        none = np.zeros(0, np.int64), np.zeros(0, np.int64)
        n = self.n
        if n < 2 or not reach >= 0.0:
            return none
        if self.brute:
            i, j = np.triu_indices(n, 1)
            ok = self._close(self.xs.take(i, axis=1), j, reach * reach)
            return i.compress(ok), j.compress(ok)
        m = int(min(self._reach(reach), self.dims.max()))
        # half of the strips around each point (rows ahead, or this row and
        # columns ahead, or this strip and positions after the point): every
        # pair once
        m0, m1 = min(m, int(self.dims[0]) - 1), min(m, int(self.dims[1]) - 1)
        d0, d1 = np.divmod(np.arange((m0 + 1) * (2 * m1 + 1)), 2 * m1 + 1)
        d1 -= m1
        keep = (d0 > 0) | (d1 >= 0)
        d0, d1 = d0[keep], d1[keep]
        q0, q1, q2 = self.q
        r0 = q0 + d0[:, None]                               # (offsets, n): rows, columns, x-cells
        r1 = q1 + d1[:, None]
        valid = (r0 < self.dims[0]) & (r1 >= 0) & (r1 < self.dims[1])
        strip = np.where(valid, r0 * self.dims[1] + r1, -1).ravel()
        x = np.broadcast_to(q2, r0.shape).ravel()
        s, e = self._runs(strip, x - m, x + m)
        s, e = s.reshape(r0.shape), e.reshape(r0.shape)
        np.maximum(s[0], np.arange(1, n + 1), out=s[0])    # (0, 0) first: this strip, the points after this one
        cnt = np.maximum(e - s, 0).ravel()
        row = np.repeat(np.arange(len(cnt)), cnt)
        first = np.cumsum(cnt) - cnt
        i = row % n
        j = (s.ravel() - first).take(row) + np.arange(len(row))
        ok = self._close(self.xs.take(i, axis=1), j, reach * reach)
        i, j = self.order.take(i.compress(ok)), self.order.take(j.compress(ok))
        return np.minimum(i, j), np.maximum(i, j)

    def near(self, centres: np.ndarray, radius: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Pairs (query k, point i) with squared distance from ``centres[k]``
        to ``x[i]`` at most ``radius[k]**2`` (centres (K, 3) finite; radius
        (K,) or one for all, >= 0)."""
        c = np.asarray(centres, dtype=float).reshape(-1, 3)
        k_n = len(c)
        none = np.zeros(0, np.int64), np.zeros(0, np.int64)
        if k_n == 0 or self.n == 0:
            return none
        rad = np.broadcast_to(np.asarray(radius, float), (k_n,))
        ct = np.ascontiguousarray(c.T)
        if self.brute:
            k = np.repeat(np.arange(k_n), self.n)
            j = np.tile(np.arange(self.n), k_n)
            r = rad.take(k)
            ok = self._close(ct.take(k, axis=1), j, r * r)
            return k.compress(ok), j.compress(ok)
        f = (ct[self.axes] - self.lo[:, None]) / self.h
        dims = self.dims[:, None].astype(float)
        m = np.minimum(self._reach(rad), float(self.dims.max()) + 1.0)
        centre = np.floor(np.clip(f, -1.0, dims))          # clipping only widens the window
        lo = np.maximum(centre - m, 0.0)
        hi = np.minimum(centre + m, dims - 1.0)
        w = np.maximum(hi - lo + 1.0, 0.0).astype(np.int64)
        lo = lo.astype(np.int64)
        strips = w[0] * w[1] * (w[2] > 0)
        # a window over more strips than are occupied takes the occupied ones
        wide = strips > len(self.strips)
        narrow = np.where(wide, 0, strips)
        k = np.repeat(np.arange(k_n), narrow)
        t = within(narrow)
        t0, t1 = np.divmod(t, w[1].take(k))
        strip = (lo[0].take(k) + t0) * self.dims[1] + lo[1].take(k) + t1
        if wide.any():
            kw = np.repeat(np.flatnonzero(wide), len(self.strips))
            sw = np.tile(self.strips, int(wide.sum()))
            row, col = np.divmod(sw, self.dims[1])
            ok = (row >= lo[0].take(kw)) & (row < lo[0].take(kw) + w[0].take(kw)) \
                & (col >= lo[1].take(kw)) & (col < lo[1].take(kw) + w[1].take(kw))
            k, strip = np.r_[k, kw[ok]], np.r_[strip, sw[ok]]
        x0 = lo[2].take(k)
        s, e = self._runs(strip, x0, x0 + w[2].take(k) - 1)
        cnt = e - s
        row = np.repeat(np.arange(len(cnt)), cnt)
        j = (s - (np.cumsum(cnt) - cnt)).take(row) + np.arange(len(row))
        k = k.take(row)
        r = rad.take(k)
        ok = self._close(ct.take(k, axis=1), j, r * r)
        return k.compress(ok), self.order.take(j.compress(ok))

    def _close(self, a: np.ndarray, j: np.ndarray, r2) -> np.ndarray:
        """Squared distance of points a (3, n) to sorted points j (n,) at most r2."""
        d = a - self.xs.take(j, axis=1)
        d *= d
        return (d[0] + d[1]) + d[2] <= r2
