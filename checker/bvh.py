"""Bounding-volume hierarchy for rigid parts: assembly boxes, part OBBs, triangle trees.

Three levels, as in the papers (translational sweep verification: AABB in
part frames, OBB in the assembly frame, separating-axis tests; interference
of lightweight CAD models: assembly boxes, then part boxes, then
triangles):

- :class:`TriangleForest`: one axis-aligned box tree per part over its
  triangles, in the part's own frame, built once for all parts together,
  one numpy pass per tree level (median split on the longest axis,
  ``LEAF_SIZE`` triangles per leaf), and stored flat, so that one vectorised traversal answers many box queries against
  many parts at once (:meth:`TriangleForest.query`). Poses never change it.
- Oriented boxes: a part's box in its frame placed by its pose is an OBB in
  the assembly (world) frame; :func:`obb_overlap` is the 15-axis separating
  axis test (3 + 3 face normals, 9 edge cross products) for whole arrays of
  box pairs.
- :func:`assembly_boxes`: world AABBs of every assembly path prefix
  ("frame", "frame/left", ...), from the parts' world AABBs, and
  :func:`prefix_hits`, which tells for each part whether every assembly it
  belongs to passed a test.
- Box pairs: :func:`aabb_pairs`, one sort and sweep over all boxes, and
  :func:`assembly_pairs`, the same pairs found by descending the assembly
  tree (assemblies whose boxes do not overlap contribute no pairs), one
  numpy pass per tree level.

Touching boxes count as overlapping (closed boxes), so a contact exactly on a
box face is never pruned. Nothing here knows about triangles' contents, contacts
or distances.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from cablecheck.checker.arrays import all_columns, ranges, within

LEAF_SIZE = 8
"""Triangles per leaf of a part's tree."""


@dataclass(frozen=True, eq=False)
class TriangleForest:
    """Box trees over the triangles of many parts, stored flat.

    Attributes:
        node_lo, node_hi: (N, 3) node boxes in their part's frame.
        left, right: (N,) child node indices, -1 for leaves.
        first, count: (N,) a leaf's range in ``order``.
        order: (T,) triangle indices (global, see ``tri_part``) in leaf order.
        root: (P,) root node of each part, -1 for a part without triangles.
        tri_part: (T,) the part of each triangle.
        tri_lo, tri_hi: (T, 3) each triangle's box in its part's frame.
    """

    node_lo: np.ndarray
    node_hi: np.ndarray
    left: np.ndarray
    right: np.ndarray
    first: np.ndarray
    count: np.ndarray
    order: np.ndarray
    root: np.ndarray
    tri_part: np.ndarray
    tri_lo: np.ndarray
    tri_hi: np.ndarray

    @staticmethod
    def build(tri_lo: np.ndarray, tri_hi: np.ndarray, tri_part: np.ndarray, parts: int) -> "TriangleForest":
        """Build the trees from per-triangle boxes (T, 3) grouped by part.

        ``tri_part`` must be sorted (each part's triangles contiguous). Every
        part's tree is built at once, one numpy pass per tree level: a node is
        a contiguous range of ``order``; a node of more than ``LEAF_SIZE``
        triangles is split at the median of its triangles' box centres along
        the longest axis of their extent (one sort by node, then centre,
        for all nodes of the level), its lower half becoming the left child.
        The nodes are then numbered part by part: a part's tree is one
        contiguous block, its root first, a node's children side by side
        (``right == left + 1``). Memory and time are O(T) per level,
        O(T log T) in all."""
        tri_lo = np.asarray(tri_lo, float).reshape(-1, 3)
        tri_hi = np.asarray(tri_hi, float).reshape(-1, 3)
        tri_part = np.asarray(tri_part, np.int64)
        i64 = np.int64
        centre = 0.5 * (tri_lo + tri_hi)
        starts = np.searchsorted(tri_part, np.arange(parts + 1))
        counts = np.diff(starts)
        has = np.flatnonzero(counts > 0)
        root = np.full(parts, -1, i64)
        root[has] = np.arange(len(has))
        order = np.arange(len(tri_part), dtype=i64)
        # per node, filled level by level: range in ``order``, children
        n_first: list[np.ndarray] = [starts[has]]
        n_count: list[np.ndarray] = [counts[has]]
        n_left: list[np.ndarray] = []
        level_first, level_count = starts[has], counts[has]
        total = len(has)
        while len(level_first):
            split = level_count > LEAF_SIZE
            left = np.full(len(level_first), -1, i64)
            nxt_first = nxt_count = np.zeros(0, i64)
            if split.any():
                f, c = level_first[split], level_count[split]
                seg = np.repeat(np.arange(len(f)), c)
                idx = ranges(f, c)
                cen = centre[order[idx]]
                bounds = np.r_[0, np.cumsum(c)[:-1]]
                c_lo = np.minimum.reduceat(cen, bounds, axis=0)
                ext = np.maximum.reduceat(cen, bounds, axis=0) - c_lo
                axis = np.argmax(ext, axis=1)
                a_seg = axis[seg][:, None]
                # by node, then centre, in one sort: node + centre scaled into [0, 0.5]
                frac = (np.take_along_axis(cen, a_seg, 1)[:, 0] - np.take_along_axis(c_lo, axis[:, None], 1)[seg, 0]) \
                    / np.maximum(np.take_along_axis(ext, axis[:, None], 1)[seg, 0], 1e-300)
                perm = np.argsort(seg + 0.5 * np.clip(frac, 0.0, 1.0), kind="stable")
                order[idx] = order[idx[perm]]
                half = c // 2
                k = np.flatnonzero(split)
                left[k] = total + 2 * np.arange(len(k))  # children of a level's nodes, in pairs
                nxt_first = np.stack([f, f + half], axis=1).ravel()
                nxt_count = np.stack([half, c - half], axis=1).ravel()
                total += len(nxt_first)
                n_first.append(nxt_first)
                n_count.append(nxt_count)
            n_left.append(left)
            level_first, level_count = nxt_first, nxt_count
        first = np.concatenate(n_first) if n_first else np.zeros(0, i64)
        count = np.concatenate(n_count) if n_count else np.zeros(0, i64)
        left = np.concatenate(n_left) if n_left else np.zeros(0, i64)
        # node boxes: reduce each node's range of ``order`` (ranges of one level are disjoint)
        node_lo = np.empty((len(first), 3))
        node_hi = np.empty((len(first), 3))
        s_lo, s_hi = tri_lo[order], tri_hi[order]
        lvl = np.r_[0, np.cumsum([len(x) for x in n_first])]
        for a, b in zip(lvl[:-1], lvl[1:]):     # loop over tree levels (about log2(T / LEAF_SIZE))
            f, c = first[a:b], count[a:b]
            if not len(f):
                continue
            o = np.argsort(f, kind="stable")
            fo, co = f[o], c[o]
            idx = ranges(fo, co)
            bounds = np.r_[0, np.cumsum(co)[:-1]]
            node_lo[a + o] = np.minimum.reduceat(s_lo[idx], bounds, axis=0)
            node_hi[a + o] = np.maximum.reduceat(s_hi[idx], bounds, axis=0)
        # renumber the nodes part by part (stably: each part's nodes keep their
        # level order, a node's two children stay side by side), so that a part's
        # tree is one contiguous block of nodes, root first (what ``tiled`` copies)
        node_part = tri_part[order[first]] if len(first) else np.zeros(0, i64)
        perm = np.argsort(node_part, kind="stable")           # new node -> old node
        new_of = np.empty(len(perm), i64)
        new_of[perm] = np.arange(len(perm), dtype=i64)
        left = left[perm]
        left = np.where(left >= 0, new_of[np.maximum(left, 0)], -1)
        right = np.where(left >= 0, left + 1, -1)
        first, count = first[perm], count[perm]
        node_lo, node_hi = node_lo[perm], node_hi[perm]
        root[has] = new_of[root[has]]
        leaf = left < 0
        return TriangleForest(
            node_lo=node_lo, node_hi=node_hi, left=left, right=right,
            first=np.where(leaf, first, -1), count=np.where(leaf, count, 0),
            order=order, root=root, tri_part=tri_part, tri_lo=tri_lo, tri_hi=tri_hi)

    def tiled(self, idx: np.ndarray) -> "TriangleForest":
        """The trees of parts ``idx`` (n,), in that order (a part may repeat):
        part k of the result has the tree of part ``idx[k]``, node for node,
        with its triangles renumbered in the same order."""
        idx = np.asarray(idx, np.int64)
        n_parts = len(self.root)
        # each part's nodes are one contiguous block starting at its root (see build)
        has = self.root >= 0
        node_end = np.full(n_parts, -1, np.int64)
        roots = self.root[has]
        node_end[has] = np.r_[roots[1:], len(self.left)] if len(roots) else node_end[has]
        t_start = np.searchsorted(self.tri_part, np.arange(n_parts + 1))
        n_first = np.where(has[idx], self.root[idx], 0)
        n_cnt = np.where(has[idx], node_end[idx] - n_first, 0)
        t_first, t_cnt = t_start[idx], t_start[idx + 1] - t_start[idx]
        nodes = ranges(n_first, n_cnt)
        tris = ranges(t_first, t_cnt)
        node_shift = np.repeat(np.cumsum(n_cnt) - n_cnt - n_first, n_cnt)       # old node -> new node
        tri_shift = np.cumsum(t_cnt) - t_cnt - t_first                           # per part: old tri -> new
        left, right = self.left[nodes], self.right[nodes]
        first, count = self.first[nodes], self.count[nodes]
        leaf = left < 0
        # leaves' ranges in ``order``: laid out anew, part by part
        new_first = np.where(leaf, np.cumsum(np.where(leaf, count, 0)) - np.where(leaf, count, 0), -1)
        owner = np.repeat(np.arange(len(idx)), n_cnt)
        order = self.order[ranges(first[leaf], count[leaf])] + np.repeat(tri_shift[owner[leaf]], count[leaf])
        return TriangleForest(
            node_lo=self.node_lo[nodes], node_hi=self.node_hi[nodes],
            left=np.where(leaf, -1, left + node_shift), right=np.where(leaf, -1, right + node_shift),
            first=new_first, count=count, order=order,
            root=np.where(has[idx], np.cumsum(n_cnt) - n_cnt, -1),
            tri_part=np.repeat(np.arange(len(idx)), t_cnt),
            tri_lo=self.tri_lo[tris], tri_hi=self.tri_hi[tris])

    def query(self, part: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Triangles whose boxes meet query boxes, one query per row.

        Breadth-first, one numpy pass per tree level over every live
        (query, node) pair; the triangles of the leaves reached are then
        tested box against box.

        Args:
            part: (Q,) part of each query.
            lo, hi: (Q, 3) query boxes in that part's frame.

        Returns:
            query, triangle: (K,) matching query rows and global triangle indices.
        """
        q = np.arange(len(part))
        n = self.root[part]
        keep = n >= 0
        q, n = q[keep], n[keep]
        out_q: list[np.ndarray] = []
        out_t: list[np.ndarray] = []
        while len(q):
            hit = all_columns((self.node_lo[n] <= hi[q]) & (lo[q] <= self.node_hi[n]))
            q, n = q[hit], n[hit]
            leaf = self.left[n] < 0
            if leaf.any():
                lq, ln = q[leaf], n[leaf]
                cnt = self.count[ln]
                rows = np.repeat(lq, cnt)
                out_q.append(rows)
                out_t.append(self.order[ranges(self.first[ln], cnt)])
            inner = ~leaf
            q = np.concatenate([q[inner], q[inner]])
            n = np.concatenate([self.left[n[inner]], self.right[n[inner]]])
        if not out_q:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        rq, rt = np.concatenate(out_q), np.concatenate(out_t)
        ok = all_columns((self.tri_lo[rt] <= hi[rq]) & (lo[rq] <= self.tri_hi[rt]))
        return rq[ok], rt[ok]


def box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n, 8, 3) corners of boxes (n, 3)."""
    bits = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float)
    return lo[:, None, :] + bits[None] * (hi - lo)[:, None, :]


def transformed_aabb(lo: np.ndarray, hi: np.ndarray, rot: np.ndarray, shift: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """AABB of boxes (n, 3) after ``x -> rot x + shift`` (rot (n, 3, 3), shift (n, 3)).

    Uses centre and the absolute rotation (Arvo), exact for the rotated box."""
    c = 0.5 * (lo + hi)
    h = 0.5 * (hi - lo)
    cw = np.einsum("nij,nj->ni", rot, c) + shift
    hw = np.einsum("nij,nj->ni", np.abs(rot), h)
    return cw - hw, cw + hw


_CROSS = tuple(np.array(v, np.int64) for v in zip(*[
    (i, (i + 1) % 3, (i + 2) % 3, j, (j + 1) % 3, (j + 2) % 3) for i in range(3) for j in range(3)]))
"""(i, i+1, i+2, j, j+1, j+2) mod 3 for the nine edge-cross axes A_i x B_j."""


def obb_overlap(c1: np.ndarray, r1: np.ndarray, h1: np.ndarray,
                c2: np.ndarray, r2: np.ndarray, h2: np.ndarray) -> np.ndarray:
    """15-axis separating-axis test for pairs of oriented boxes.

    Box k has centre ``c`` (n, 3), axes as the columns of ``r`` (n, 3, 3) and
    half extents ``h`` (n, 3). The boxes are disjoint when their projections
    on one of the 15 axes (each box's 3 axes, 9 cross products) are separated
    by more than a rounding allowance; touching boxes overlap. Cross products
    of nearly parallel edges are kept small by adding ``1e-12`` to the
    absolute rotation (Gottschalk's guard), which can only widen projections.

    Returns:
        (n,) bool, True when the boxes may overlap.
    """
    rot = np.einsum("nji,njk->nik", r1, r2)          # r2's axes in r1's frame
    t = np.einsum("nji,nj->ni", r1, c2 - c1)          # centre offset in r1's frame
    scale = np.abs(c1).max(axis=1) + np.abs(c2).max(axis=1) + h1.max(axis=1) + h2.max(axis=1)
    slack = 1e-12 * scale
    ar = np.abs(rot) + 1e-12
    sep = np.zeros(len(c1), bool)
    # axes of box 1
    ra = h1
    rb = np.einsum("nij,nj->ni", ar, h2)
    sep |= np.any(np.abs(t) > ra + rb + slack[:, None], axis=1)
    # axes of box 2
    ra = np.einsum("nji,nj->ni", ar, h1)
    tb = np.einsum("nji,nj->ni", rot, t)
    sep |= np.any(np.abs(tb) > ra + h2 + slack[:, None], axis=1)
    # cross products A_i x B_j, the nine at once (each term the loop's own
    # products and sums: the same bits, a tenth of the numpy calls)
    i, i1, i2, j, j1, j2 = _CROSS
    ra = h1[:, i1] * ar[:, i2, j] + h1[:, i2] * ar[:, i1, j]
    rb = h2[:, j1] * ar[:, i, j2] + h2[:, j2] * ar[:, i, j1]
    tt = np.abs(t[:, i2] * rot[:, i1, j] - t[:, i1] * rot[:, i2, j])
    sep |= (tt > ra + rb + slack[:, None]).any(axis=1)
    return ~sep


def aabb_pairs(lo: np.ndarray, hi: np.ndarray, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """All pairs i < j of boxes (n, 3) that overlap after growing each by ``margin``.

    Sort and sweep on x (vectorised: each box's candidates are the boxes
    starting within its x range), then y and z are tested.
    """
    n = len(lo)
    if n < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    lo = lo - margin
    hi = hi + margin
    order = np.argsort(lo[:, 0], kind="stable")
    slo = lo[order, 0]
    end = np.searchsorted(slo, hi[order, 0], side="right")
    cnt = np.maximum(end - np.arange(n) - 1, 0)
    a = np.repeat(np.arange(n), cnt)
    b = a + 1 + within(cnt)
    i, j = order[a], order[b]
    ok = all_columns((lo[i, 1:] <= hi[j, 1:]) & (lo[j, 1:] <= hi[i, 1:]))
    i, j = i[ok], j[ok]
    return np.minimum(i, j), np.maximum(i, j)


@dataclass(frozen=True)
class Assemblies:
    """Assembly path prefixes of a set of parts.

    Attributes:
        names: (A,) every proper prefix of a part name ("a", "a/b" for "a/b/c").
        member: (P, D) assembly index of each part at each depth, -1 past its depth.
    """

    names: tuple[str, ...]
    member: np.ndarray

    @staticmethod
    def of(part_names: list[str]) -> "Assemblies":
        """The assemblies of parts named by "/"-separated paths."""
        index: dict[str, int] = {}
        rows = []
        for name in part_names:
            levels = name.split("/")[:-1]
            row = []
            for d in range(len(levels)):
                key = "/".join(levels[:d + 1])
                row.append(index.setdefault(key, len(index)))
            rows.append(row)
        depth = max((len(r) for r in rows), default=0)
        member = np.full((len(part_names), depth), -1, np.int64)
        for i, r in enumerate(rows):
            member[i, :len(r)] = r
        return Assemblies(tuple(index), member)

    @cached_property
    def tree(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The assembly tree of :func:`assembly_pairs`, built once: parent (A,)
        of each assembly (-1: top level), parent (P,) of each part, and every
        node (assemblies, then parts as A + p) ordered by parent (stably)."""
        na, npart = len(self.names), len(self.member)
        depth = (self.member >= 0).sum(axis=1)
        parent = np.full(na, -2, np.int64)
        for d in range(self.member.shape[1]):                 # loop over assembly levels
            m = self.member[:, d]
            ok = m >= 0
            parent[m[ok]] = self.member[ok, d - 1] if d else -1
        pp = np.full(npart, -1, np.int64)
        if self.member.shape[1]:
            pp = np.where(depth > 0, self.member[np.arange(npart), np.maximum(depth - 1, 0)], -1)
        key = np.concatenate([parent, pp]) + 1
        order = np.flatnonzero(key >= 0)
        order = order[np.argsort(key[order], kind="stable")]
        return parent, pp, order


def assembly_boxes(asm: Assemblies, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World AABBs (A, 3) of each assembly from its parts' AABBs (P, 3)."""
    a_lo = np.full((len(asm.names), 3), np.inf)
    a_hi = np.full((len(asm.names), 3), -np.inf)
    for d in range(asm.member.shape[1]):     # loop over assembly levels
        m = asm.member[:, d]
        rows = np.flatnonzero(m >= 0)
        rows = rows[np.argsort(m[rows], kind="stable")]
        if not len(rows):
            continue
        ms = m[rows]
        first = np.flatnonzero(np.r_[True, ms[1:] != ms[:-1]])
        a_lo[ms[first]] = np.minimum.reduceat(lo[rows], first, axis=0)
        a_hi[ms[first]] = np.maximum.reduceat(hi[rows], first, axis=0)
    return a_lo, a_hi


def prefix_hits(asm: Assemblies, hit: np.ndarray) -> np.ndarray:
    """(P,) True for parts all of whose assemblies have ``hit`` (A,) True."""
    ok = np.ones(len(asm.member), bool)
    for d in range(asm.member.shape[1]):
        m = asm.member[:, d]
        ok &= (m < 0) | hit[np.maximum(m, 0)]
    return ok


def _grouped_range(g_pts: np.ndarray, x_pts: np.ndarray, g_q: np.ndarray, lo_q: np.ndarray,
                   hi_q: np.ndarray, open_lo: bool) -> tuple[np.ndarray, np.ndarray]:
    """(query, point) index pairs: points of the query's group with x in [lo, hi] ((lo, hi] if ``open_lo``).

    One sort for all groups: values are replaced by their dense ranks (ties
    equal), so ``group * M + rank`` orders by group, then x, exactly."""
    if not len(g_pts) or not len(g_q):
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    vals, rank = np.unique(np.concatenate([x_pts, lo_q, hi_q]), return_inverse=True)
    m = len(vals) + 1
    n, k = len(x_pts), len(lo_q)
    rp, rlo, rhi = rank[:n], rank[n:n + k], rank[n + k:]
    key = g_pts.astype(np.int64) * m + rp
    order = np.argsort(key, kind="stable")
    ks = key[order]
    base = g_q.astype(np.int64) * m
    start = np.searchsorted(ks, base + rlo, side="right" if open_lo else "left")
    end = np.searchsorted(ks, base + rhi, side="right")
    cnt = np.maximum(end - start, 0)
    q = np.repeat(np.arange(k), cnt)
    return q, order[ranges(start, cnt)]


def assembly_pairs(asm: Assemblies, lo: np.ndarray, hi: np.ndarray, a_lo: np.ndarray, a_hi: np.ndarray,
                   live: np.ndarray, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The pairs of :func:`aabb_pairs` among ``live`` parts, found through the assembly boxes.

    A simultaneous descent of the assembly tree (nodes: assemblies and parts),
    one numpy pass per level: the children of one node are paired by a sort
    and sweep grouped by parent; two distinct nodes whose boxes (grown by
    ``margin``) overlap pass their children on, paired side against side.
    Two assemblies whose boxes do not overlap contribute no pairs, and nothing
    below them is looked at. An assembly's box holds its parts' boxes, so
    the pairs are exactly those of :func:`aabb_pairs` on the live parts (as
    ``i < j``, in no particular order).

    Args:
        asm: the parts' assemblies.
        lo, hi: (P, 3) parts' world boxes; a_lo, a_hi: (A, 3) the assemblies'.
        live: (P,) bool, parts to pair (others, e.g. planes, are left out).
        margin: growth of every box.
    """
    na = len(asm.names)
    a_parent, pp, order = asm.tree
    parent = np.concatenate([a_parent, np.where(live, pp, -2)])   # -2: not in the tree; -1: top level
    node_lo = np.concatenate([a_lo, lo]) - margin
    node_hi = np.concatenate([a_hi, hi]) + margin
    # children of node key k (0: top level, 1 + a: assembly a) in ch[start[k]:start[k + 1]]
    key = parent + 1
    ch = order[key[order] >= 0]          # order: by parent, stably; dropping dead parts keeps it so
    start = np.searchsorted(key[ch], np.arange(na + 2))

    def expand(nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(row, child): the children of each node, a part standing for itself."""
        is_asm = nodes < na
        k = np.where(is_asm, nodes + 1, 0)
        cnt = np.where(is_asm, start[np.minimum(k + 1, na + 1)] - start[k], 1)
        row = np.repeat(np.arange(len(nodes)), cnt)
        pos = ranges(start[k], cnt)
        child = np.where(np.repeat(is_asm, cnt), ch[np.minimum(pos, len(ch) - 1)] if len(ch) else 0,
                         np.repeat(nodes, cnt))
        return row, child

    def overlap(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return all_columns((node_lo[x] <= node_hi[y]) & (node_lo[y] <= node_hi[x]))

    out_i: list[np.ndarray] = []
    out_j: list[np.ndarray] = []
    selves = np.array([-1], np.int64)                      # nodes whose own children are still to pair
    cross_a = cross_b = np.zeros(0, np.int64)              # distinct nodes with overlapping boxes
    while len(selves) or len(cross_a):
        # children of one node among themselves (grouped sort and sweep)
        k = selves + 1
        cnt = start[k + 1] - start[k]
        grp = np.repeat(np.arange(len(selves)), cnt)
        kids = ch[ranges(start[k], cnt)]
        q, p = _grouped_range(grp, node_lo[kids, 0], grp, node_lo[kids, 0], node_hi[kids, 0], False)
        a, b = kids[q], kids[p]
        la, lb = node_lo[a, 0], node_lo[b, 0]
        first = (lb > la) | ((lb == la) & (b > a))
        a, b = a[first], b[first]
        keep = overlap(a, b)
        na_a, na_b = a[keep], b[keep]
        # two overlapping nodes: children side against side
        ra, ca = expand(cross_a)
        rb, cb = expand(cross_b)
        q1, p1 = _grouped_range(rb, node_lo[cb, 0], ra, node_lo[ca, 0], node_hi[ca, 0], False)
        q2, p2 = _grouped_range(ra, node_lo[ca, 0], rb, node_lo[cb, 0], node_hi[cb, 0], True)
        a = np.concatenate([ca[q1], ca[p2]])
        b = np.concatenate([cb[p1], cb[q2]])
        keep = overlap(a, b)
        a = np.concatenate([na_a, a[keep]])
        b = np.concatenate([na_b, b[keep]])
        both = (a >= na) & (b >= na)
        out_i.append(a[both] - na)
        out_j.append(b[both] - na)
        cross_a, cross_b = a[~both], b[~both]
        selves = kids[kids < na]
    i = np.concatenate(out_i) if out_i else np.zeros(0, np.int64)
    j = np.concatenate(out_j) if out_j else np.zeros(0, np.int64)
    return np.minimum(i, j), np.maximum(i, j)
