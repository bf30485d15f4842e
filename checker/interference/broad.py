"""Broad phase: chunks of consecutive discrete items and their bounding spheres.

The points (or elements) of every cable are cut into chunks of a few
consecutive ones, each with a bounding sphere (around the chord's midpoint,
of half the arc length), and pairs of consecutive chunks ("super chunks")
are binned into a uniform grid (:class:`cablecheck.checker.cellgrid.CellGrid`).
:meth:`Chunks.pairs` gives chunk pairs that may come within a reach (cable
against cable, other than neighbours along one cable: the near field of
:mod:`cablecheck.checker.interference.cablepairs`); :func:`chunk_part_pairs` meets
every part's bounding sphere with the grid, then the chunks' spheres and
(optionally) the part's own box. Cost therefore grows with the number of
close pairs, not with points x parts.

Deliberately not here: exact distances (the narrow phases of
:mod:`~cablecheck.checker.interference.cablepairs` and
:mod:`~cablecheck.checker.interference.structure`) and the near field along one cable.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cablecheck.checker.arrays import within
from cablecheck.checker.cellgrid import CellGrid

if TYPE_CHECKING:
    from cablecheck.checker.interference.structure import PartTable

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
        n = len(items)
        ic = cable.take(items)
        # Runs of one cable's items (start, length), cut into chunks.
        run_start = np.r_[0, np.flatnonzero(ic[1:] != ic[:-1]) + 1] if n else np.zeros(0, np.int64)
        run_end = np.r_[run_start[1:], n]
        per = -(-(run_end - run_start) // CHUNK)
        starts = np.repeat(run_start, per) + CHUNK * within(per)
        end = np.repeat(run_end, per)
        at = starts[:, None] + np.arange(CHUNK)
        self.idx = np.where(at < end[:, None], items.take(np.minimum(at, max(n - 1, 0))), -1)
        self.cable = ic.take(starts)
        # A chunk's pieces form a polyline from a to b of arc length L; every
        # point x of it lies within L / 2 of the chord's midpoint, since
        # |x - a| + |x - b| <= L.
        a = items.take(starts)
        last = items.take(np.minimum(starts + CHUNK, end) - 1)
        b = np.where(has_next.take(last), last + 1, last)
        self.centre = 0.5 * (p.take(a, axis=0) + p.take(b, axis=0))
        self.radius = 0.5 * (s.take(b) - s.take(a))
        self.has_next = has_next
        # Pairs of consecutive chunks of one cable ("super chunks") hold the
        # grid for chunk pairs: half as many spheres to pair up.
        first = np.cumsum(per) - per                    # each run's first chunk
        half = -(-per // 2)
        sup_start = np.repeat(first, half) + 2 * within(half)
        sup_end = np.repeat(first + per, half)
        second = sup_start + 1
        self.sub = np.stack([sup_start, np.where(second < sup_end, second, -1)], axis=1)
        sa = a.take(sup_start)
        sb = b.take(np.minimum(second, sup_end - 1))
        self.sup_centre = 0.5 * (p.take(sa, axis=0) + p.take(sb, axis=0))
        self.sup_radius = 0.5 * (s.take(sb) - s.take(sa))
        rmax = float(self.sup_radius.max()) if len(sup_start) else 0.0
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
        a, b = a.compress(ok), b.compress(ok)
        a, b = np.minimum(a, b), np.maximum(a, b)
        lim = reach + self.radius.take(a) + self.radius.take(b)
        keep = rows_within(self.centre, a, b, lim) & ~((self.cable.take(a) == self.cable.take(b)) & (b - a <= 1))
        return a.compress(keep), b.compress(keep)

    def expand(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """All item pairs (i in chunk a, j in chunk b), flattened, padding dropped."""
        i = np.repeat(self.idx.take(a, axis=0), CHUNK, axis=1).ravel()
        j = np.tile(self.idx.take(b, axis=0), (1, CHUNK)).ravel()
        ok = (i >= 0) & (j >= 0)
        return i.compress(ok), j.compress(ok)


def within_reach(x: np.ndarray, y: np.ndarray, lim: np.ndarray) -> np.ndarray:
    """|x - y| < lim for rows of (n, 3) arrays, with a margin (pruning only)."""
    t = x - y
    t *= t
    lim = lim * (1 + SLACK)
    return (t[:, 0] + t[:, 1]) + t[:, 2] < reach_squared(lim)


def rows_within(p: np.ndarray, i: np.ndarray, j: np.ndarray, lim: np.ndarray) -> np.ndarray:
    """:func:`within_reach` of rows i and j of p (n, 3), the same bits. Where
    the pairs outnumber the points, a coordinate at a time: p's columns are
    copied once and each gathered alone (a harness's 6 million candidate
    point pairs: gathering rows of three cost half as much again)."""
    if len(i) < len(p):
        return within_reach(p.take(i, axis=0), p.take(j, axis=0), lim)
    t = None
    for k in range(3):
        x = np.ascontiguousarray(p[:, k])
        d = x.take(i) - x.take(j)
        d *= d
        t = d if t is None else t + d
    lim = lim * (1 + SLACK)
    return t < reach_squared(lim)


def within_reach_t(x: np.ndarray, y: np.ndarray, lim: np.ndarray) -> np.ndarray:
    """:func:`within_reach` for coordinate-major (3, n) arrays (contiguous slices)."""
    t = x - y
    t *= t
    lim = lim * (1 + SLACK)
    return t[0] + t[1] + t[2] < reach_squared(lim)


def reach_squared(lim: np.ndarray) -> np.ndarray:
    """lim squared, never below the least subnormal: a reach under 1e-162
    squares to 0 and would drop coincident points (pruning stays conservative)."""
    return np.maximum(lim * lim, np.finfo(np.float64).smallest_subnormal)


def chunk_part_pairs(tab: PartTable, ch: Chunks, margin: float, box: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(item, part) pairs where the item may lie within ``margin`` of the part.

    Each finite part's bounding sphere, grown by ``margin``, is met with the
    super chunks' spheres through their grid, then with their chunks'
    spheres (with ``box``, then each chunk's sphere with the part's own box
    in its frame, grown by ``margin``); the items of every chunk met are
    candidates. Planes take every item.
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
        c, k = c.compress(ok), k.compress(ok)
        centre, rc = ch.centre.take(c, axis=0), ch.radius.take(c)
        ok = within_reach(centre, c_world.take(k, axis=0), rad.take(k) + rc)
        c, k = c.compress(ok), k.compress(ok)
        if box:
            # the chunk's sphere against the part's own box grown by the
            # margin (and by a margin for the rounding of the frame change)
            part = fin.take(k)
            d = centre.compress(ok, axis=0) - tab.trans.take(part, axis=0)
            loc = np.einsum("ni,nij->nj", d, tab.rot.take(part, axis=0))
            a = np.abs(d)
            grow = ((margin + rc.compress(ok)) * (1 + SLACK) + SLACK * np.maximum(np.maximum(a[:, 0], a[:, 1]), a[:, 2]))
            inb = (loc >= tab.lo.take(part, axis=0) - grow[:, None]) & (loc <= tab.hi.take(part, axis=0) + grow[:, None])
            ok = inb[:, 0] & inb[:, 1] & inb[:, 2]
            c, k = c.compress(ok), k.compress(ok)
        it = ch.idx.take(c, axis=0).ravel()
        pk = np.repeat(fin.take(k), CHUNK)
        ok = it >= 0
        items.append(it.compress(ok))
        parts.append(pk.compress(ok))
    if len(tab.planes):
        every = ch.idx[ch.idx >= 0]
        items.append(np.tile(every, len(tab.planes)))
        parts.append(np.repeat(tab.planes, len(every)))
    if not items:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(items), np.concatenate(parts)
