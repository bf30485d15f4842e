"""Broad phase: chunks of consecutive discrete items and their bounding spheres.

The points (or elements) of every cable are cut into chunks of a few
consecutive ones, each with a bounding sphere (around the chord's midpoint,
of half the arc length), and pairs of consecutive chunks ("super chunks")
are binned into a uniform grid (:class:`checker.cellgrid.CellGrid`).
:meth:`Chunks.pairs` gives chunk pairs that may come within a reach (cable
against cable, other than neighbours along one cable: the near field of
:mod:`checker.interference.cablepairs`); :func:`chunk_part_pairs` meets
every part's bounding sphere with the grid, then the chunks' spheres. Cost
therefore grows with the number of close pairs, not with points x parts.

Deliberately not here: exact distances (the narrow phases of
:mod:`~checker.interference.cablepairs` and
:mod:`~checker.interference.structure`) and the near field along one cable.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from checker.cellgrid import CellGrid
if TYPE_CHECKING:
    from checker.interference.structure import PartTable

CHUNK = 4
NEAR = 2 * CHUNK - 1  # offsets along a cable covered by the near field
SLACK = 1e-9  # relative margin of the pruning bounds against rounding


class Chunks:
    """Runs of up to ``CHUNK`` consecutive items of one cable with bounding spheres.

    Item ``i`` (an index into the points) stands for the piece from ``p[i]``
    to ``p[i + 1]`` when the next point is on the same cable (a point and the
    element after it, or an element), else for ``p[i]`` alone.

    Attributes:
        idx: (C, CHUNK) item indices, -1 padded.
        cable: (C,) cable of each chunk; chunk ids are consecutive along a cable.
        centre, radius: bounding spheres.
        sub: (S, 2) the chunks of each super chunk (two consecutive chunks of
            one cable), -1 padded; sup_centre, sup_radius: their spheres.
        grid: the super chunks' centres in a cell grid, its cells sized for
            :meth:`pairs` at ``reach``.
        has_next: (M,) point i + 1 is on point i's cable.
    """

    def __init__(self, p, s, cable, has_next, items, reach: float = 0.0):
        ic = cable[items]
        n = len(items)
        # Position of each item along its cable's run of items.
        new_cable = np.r_[True, ic[1:] != ic[:-1]]
        run_start = np.nonzero(new_cable)[0]
        local = np.arange(n) - np.repeat(run_start, np.diff(np.r_[run_start, n]))
        slot = local % CHUNK
        first = slot == 0
        cid = np.cumsum(first) - 1
        starts = np.nonzero(first)[0]
        self.idx = np.full((len(starts), CHUNK), -1, dtype=np.int64)
        self.idx[cid, slot] = items
        self.cable = ic[starts]
        # A chunk's pieces form a polyline from a to b of arc length L; every
        # point x of it lies within L / 2 of the chord's midpoint, since
        # |x - a| + |x - b| <= L.
        a = items[starts]
        last = items[np.r_[starts[1:], n] - 1]
        b = np.where(has_next[last], last + 1, last)
        self.centre = 0.5 * (p[a] + p[b])
        self.radius = 0.5 * (s[b] - s[a])
        self.has_next = has_next
        # Pairs of consecutive chunks of one cable ("super chunks") hold the
        # grid for chunk pairs: half as many spheres to pair up.
        nc = len(starts)
        new_sup = np.r_[True, self.cable[1:] != self.cable[:-1]]
        run = np.nonzero(new_sup)[0]
        local = np.arange(nc) - np.repeat(run, np.diff(np.r_[run, nc]))
        first = local % 2 == 0
        sid = np.cumsum(first) - 1
        sup_start = np.nonzero(first)[0]
        self.sub = np.full((len(sup_start), 2), -1, dtype=np.int64)
        self.sub[sid, local % 2] = np.arange(nc)
        sa = a[sup_start]
        sb = b[np.r_[sup_start[1:], nc] - 1]
        self.sup_centre = 0.5 * (p[sa] + p[sb])
        self.sup_radius = 0.5 * (s[sb] - s[sa])
        rmax = float(self.sup_radius.max()) if nc else 0.0
        self.grid = CellGrid(self.sup_centre, (reach + 2.0 * rmax) * (1 + SLACK))

    def pairs(self, reach: float) -> tuple[np.ndarray, np.ndarray]:
        """Chunk pairs (A < B) whose spheres come within ``reach``, except
        chunks of one cable that are the same or adjacent (the near field)."""
        none = np.zeros(0, np.int64), np.zeros(0, np.int64)
        if len(self.sup_radius) < 2:
            return none  # one super chunk: its two chunks are adjacent
        # Super chunk pairs first (the two chunks of one are adjacent), then
        # their chunks' 2 x 2 combinations against the chunks' own spheres.
        rmax = float(self.sup_radius.max())
        sa, sb = self.grid.pairs((reach + 2.0 * rmax) * (1 + SLACK))
        if len(sa) == 0:
            return none
        a = np.repeat(self.sub.take(sa, axis=0), 2, axis=1).ravel()
        b = np.tile(self.sub.take(sb, axis=0), (1, 2)).ravel()
        ok = (a >= 0) & (b >= 0)
        a, b = a[ok], b[ok]
        a, b = np.minimum(a, b), np.maximum(a, b)
        lim = reach + self.radius[a] + self.radius[b]
        keep = within_reach(self.centre[a], self.centre[b], lim) & ~((self.cable[a] == self.cable[b]) & (b - a <= 1))
        return a[keep], b[keep]

    def expand(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """All item pairs (i in chunk a, j in chunk b), flattened, padding dropped."""
        i = np.repeat(self.idx[a], CHUNK, axis=1).ravel()
        j = np.tile(self.idx[b], (1, CHUNK)).ravel()
        ok = (i >= 0) & (j >= 0)
        return i[ok], j[ok]


def within_reach(x: np.ndarray, y: np.ndarray, lim: np.ndarray) -> np.ndarray:
    """|x - y| < lim for rows of (n, 3) arrays, with a margin (pruning only)."""
    t = x - y
    lim = lim * (1 + SLACK)
    return np.einsum("ij,ij->i", t, t) < _square(lim)


def within_reach_t(x: np.ndarray, y: np.ndarray, lim: np.ndarray) -> np.ndarray:
    """:func:`within_reach` for coordinate-major (3, n) arrays (contiguous slices)."""
    t = x - y
    t *= t
    lim = lim * (1 + SLACK)
    return t[0] + t[1] + t[2] < _square(lim)


def _square(lim: np.ndarray) -> np.ndarray:
    """lim squared, never below the least subnormal: a reach under 1e-162
    squares to 0 and would drop coincident points (pruning stays conservative)."""
    return np.maximum(lim * lim, np.finfo(np.float64).smallest_subnormal)


def chunk_part_pairs(tab: PartTable, ch: Chunks, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """(item, part) pairs where the item may lie within ``margin`` of the part.

    Each finite part's bounding sphere, grown by ``margin``, is met with the
    super chunks' spheres through their grid, then with their chunks'
    spheres; the items of every chunk met are candidates. Planes take every item.
    Returns item indices (into the points) and part indices, both (n,).
    """
    items, parts = [], []
    fin = tab.finite
    if len(fin) and len(ch.radius):
        c_world = np.einsum("nij,nj->ni", tab.rot[fin], tab.c_loc) + tab.trans[fin]
        rad = tab.half_diag + margin
        k, sup = ch.grid.near(c_world, (rad + float(ch.sup_radius.max())) * (1 + SLACK))
        c = ch.sub.take(sup, axis=0).ravel()
        k = np.repeat(k, 2)
        ok = c >= 0
        c, k = c[ok], k[ok]
        ok = within_reach(ch.centre[c], c_world[k], rad[k] + ch.radius[c])
        c, k = c[ok], k[ok]
        it = ch.idx[c].ravel()
        pk = np.repeat(fin[k], CHUNK)
        ok = it >= 0
        items.append(it[ok])
        parts.append(pk[ok])
    if len(tab.planes):
        every = ch.idx[ch.idx >= 0]
        items.append(np.tile(every, len(tab.planes)))
        parts.append(np.repeat(tab.planes, len(every)))
    if not items:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(items), np.concatenate(parts)
