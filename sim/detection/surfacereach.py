"""Which patches of the concave mesh surfaces the cables can reach at a state.

A concave mesh is seen by the detection model as rigid flexes of its own
triangles, in patches (`cablecheck.detection.mesh`). MuJoCo places every flex at
every mj_flex (vertices, element boxes, tree) and its collision pass
visits every flex that has contact bits (the broadphase box of all its
vertices, then the tree against each cable), near a cable or not: a
state's cost would grow with the meshes' size. `SurfaceReach` leaves the
patches no cable can reach out of the state's pass, so it grows with what
is near.

The bound: a patch's triangles lie in boxes fixed in the frame of the
body that carries them: the patch's, and those of its pieces (`pieces`:
its triangles halved `PIECE_LEVELS` times, each piece's box in the body's
axes and along its own principal axes, `oriented_boxes`). MuJoCo makes a
contact between a cable element (segment, radius r) and a triangle
(radius rho) only when their distance is below r + rho + the pair's
margin and gap (the two flexes' added; mj_collideElems), give or take the
convex solver's tolerance (`opt.ccd_tolerance`: the solver tests the
shapes grown by the margin for intersection to that tolerance). When a
segment lies apart from a box grown by r + rho + margin + gap +
`REACH_SLACK` along some axis, every point of the segment is that far
from every point in the box, so MuJoCo could report no contact with a
triangle in it; a patch is left out when every segment lies so apart
from its box or from each of its pieces' boxes. The test runs in steps
with the same bound:
each segment against the box of all the patches on a body, then down a
tree of boxes over that body's patches and their pieces (each node the
box of its children, a few levels at a time); the segments that reach a
patch's box are tested again along the patch's own principal axes before
its pieces, and those that reach a piece's box along the piece's (a
slanted, thin box is far tighter along them), both also along the
segment's direction crossed with each axis (with the box's axes, the axes
that separate a segment from a box whenever anything does). Before them a
cull in the world frame leaves out, with no rotation, the (segment, body)
pairs whose spheres lie apart (the segment's around its box grown by the
bound, the body's around the box of its patches): what it leaves out the
first step would, so what is kept is the same: on the robot cell a state
keeps a few of its hundreds of patches, fewer than the patches' own boxes
alone would (each kept patch costs mj_flex and mj_collision work even
without contacts). Every
one-dimensional flex counts as a cable; should the mjcf model bring a
flex of another dimension that can meet a surface, no patch is ever left
out. The positions are MuJoCo's body poses at the state (mj_kinematics;
the simulation's, which share the detection model's kinematic tree and so
are its own bit for bit), the cable vertices placed as mj_flex places
them: nothing comes from the checker, so validation still judges the
checker against all that MuJoCo finds on the whole surface
(tests/test_surfacereach.py compares the contacts and the bound against
exact distances).

How a patch is left out: the detection model is never stepped, so for
one pass its flex gets no vertices, no elements, no tree and no contact
bits (`flex_vertnum`, `flex_elemnum`, `flex_bvhadr`, `flex_contype`,
`flex_conaffinity`): mj_flex skips its vertices and elements and the
collision pass never pairs it. Its vertices are also put on the world
body (`flex_vertbodyid` 0): MuJoCo's broadphase takes the centre and
spread of every flex vertex off the world to choose its sweep axis, left
out or not, and the axis only orders the sweep (the box pairs it finds,
and so the contacts, are the same). `restore` puts the model back as
compiled.

This module does not read contacts (`cablecheck.detection.contacts`) or decide what a
contact means; it only narrows MuJoCo's pass.
"""

from __future__ import annotations

from collections.abc import Iterator

import mujoco
import numpy as np

from cablecheck.checker.arrays import ranges, within
from cablecheck.detection.mesh import surface_geoms

REACH_SLACK = 0.1
"""Room beyond MuJoCo's contact distance in the reach bound, as a share of
the pair's margin (module docstring) ..."""

REACH_TOLERANCES = 100.0
"""... and in convex solver tolerances (`opt.ccd_tolerance`, the precision
of MuJoCo's intersection test of the grown shapes): far more than any
rounding, far less than a patch."""

PIECE_LEVELS = 4
"""Halvings of a patch's triangles below it in the reach test's tree: its
boxes test pieces of a sixteenth of a patch (a curved patch's box holds
much that none of its pieces' boxes does), and a patch is kept when a
segment reaches one of its pieces."""

TREE_STEP = 2
"""Levels of a body's tree of patch boxes tested at once (2**2 boxes per
segment): fewer steps down the tree, each a few numpy calls (1 to 4 levels at
once were timed side by side on the robot cell; 2 was the fastest)."""

CULL_ROOM = 1e-9
"""Metres added to a segment's sphere in the first cull (`SurfaceReach.reachable`),
and ..."""

CULL_ROUNDING = 1e-12
"""... this share of |c|^2 + |m|^2 added to the squared reach, c and m the
two spheres' centres (their squared distance is taken as |c|^2 + |m|^2 -
2 c.m, which rounds in proportion to that sum): far more than any
rounding, they only keep more pairs to test."""


class SurfaceReach:
    """The surface patches of a detection model, their reach test and the
    switch that leaves some out of a collision pass.

    Args:
      model: the detection model (`cablecheck.detection.mesh.add_surfaces`).

    Attributes:
      flexes: (F,) the patches' flex ids.
      bodies: (F,) the body carrying each patch.
      lo, hi: (F, 3) each patch's box in its body's frame.
    """

    def __init__(self, model: mujoco.MjModel):
        self.model = m = model
        self.flexes = flexes = surface_geoms(m)[0]
        surface = np.zeros(m.nflex, bool)
        surface[flexes] = True
        adr = m.flex_vertadr[flexes]
        self.bodies = m.flex_vertbodyid[adr].astype(np.int64)
        # each patch's box: one reduction over the model's vertices, cut at every
        # flex's first (a flex's vertices are contiguous; none has no vertex)
        self.lo, self.hi = np.zeros((0, 3)), np.zeros((0, 3))
        self.axes, self.axis_lo, self.axis_hi = np.zeros((0, 3, 3)), np.zeros((0, 3)), np.zeros((0, 3))
        if len(flexes):
            self.lo = np.minimum.reduceat(m.flex_vert, m.flex_vertadr, axis=0)[flexes]
            self.hi = np.maximum.reduceat(m.flex_vert, m.flex_vertadr, axis=0)[flexes]
            self.axes, self.axis_lo, self.axis_hi = oriented_boxes(m.flex_vert, m.flex_vertadr, m.flex_vertnum)
            self.axes, self.axis_lo, self.axis_hi = self.axes[flexes], self.axis_lo[flexes], self.axis_hi[flexes]
        # each patch's triangles in PIECE_LEVELS halvings: 2**PIECE_LEVELS pieces
        # (some empty when it has fewer triangles), each with its box in its
        # body's frame and along its own principal axes
        self.piece_patch, self.piece_node, self.piece_lo, self.piece_hi, self.piece_axes, \
            self.piece_axis_lo, self.piece_axis_hi = pieces(m, flexes, PIECE_LEVELS)
        # per body carrying patches, a binary tree of boxes over its patches' pieces
        # (in flex order: a surface's patches come in k-d order, neighbours next to
        # each other, a patch's pieces under it), padded to 2**depth leaves with
        # empty boxes; level 0 is the box of all the body's patches
        self._carriers, row_body = np.unique(self.bodies, return_inverse=True)
        n_c = len(self._carriers)
        rank = np.zeros(len(flexes), np.int64)
        order = np.argsort(row_body, kind="stable")
        starts = np.searchsorted(row_body[order], np.arange(n_c))
        rank[order] = np.arange(len(flexes)) - starts[row_body[order]]
        leaf = (rank.take(self.piece_patch) << PIECE_LEVELS) + self.piece_node     # each piece's leaf
        piece_body = row_body.take(self.piece_patch)
        patch_depth = int(np.ceil(np.log2(rank.max() + 1))) if len(flexes) else 0
        depth = patch_depth + PIECE_LEVELS if len(flexes) else 0
        self._patch_row = np.full((n_c, 2 ** patch_depth), -1, np.int64)    # the patch at each node of its level
        self._patch_row[row_body, rank] = np.arange(len(flexes))
        self._leaf_row = np.full((n_c, 2 ** depth), -1, np.int64)
        self._leaf_row[piece_body, leaf] = np.arange(len(self.piece_patch))
        lo = np.full((n_c, 2 ** depth, 3), np.inf)
        hi = np.full((n_c, 2 ** depth, 3), -np.inf)
        lo[piece_body, leaf], hi[piece_body, leaf] = self.piece_lo, self.piece_hi
        self._levels = [(lo, hi)]
        while lo.shape[1] > 1:
            lo, hi = lo.reshape(n_c, -1, 2, 3).min(axis=2), hi.reshape(n_c, -1, 2, 3).max(axis=2)
            self._levels.insert(0, (lo, hi))
        # the boxes as the test compares them (`_met`): the root's (B, 8) and,
        # below it, a few levels at a time (`TREE_STEP`), each step's level by
        # ancestor in the level above the step, all its 2**step descendants at
        # once (B * nodes, 8 * 2**step): a box its descendants meet it meets too
        self._root = _faces(self._levels[0][0][:, 0], self._levels[0][1][:, 0])
        # (a step ends at the patches' level: there each pair is tested along
        # the patch's own axes too, before its pieces)
        self._steps = []
        level = 0
        while level + 1 < len(self._levels):
            end = patch_depth if level < patch_depth else len(self._levels) - 1
            step = min(TREE_STEP, end - level)
            level += step
            self._steps.append((step, _faces(*self._levels[level]).reshape(-1, 8 << step), level == patch_depth))
        self._patch_faces = _faces(self.axis_lo, self.axis_hi)
        self._patch_centre, self._patch_half = 0.5 * (self.axis_lo + self.axis_hi), 0.5 * (self.axis_hi - self.axis_lo)
        self._axis_faces = _faces(self.piece_axis_lo, self.piece_axis_hi)
        self._axis_centre = 0.5 * (self.piece_axis_lo + self.piece_axis_hi)
        self._axis_half = 0.5 * (self.piece_axis_hi - self.piece_axis_lo)
        # each body's patches in a sphere (world frame, the first cull): around its root box
        root_lo, root_hi = self._levels[0][0][:, 0], self._levels[0][1][:, 0]
        self._centre = 0.5 * (root_lo + root_hi)
        self._radius = 0.5 * np.sqrt(((root_hi - root_lo) ** 2).sum(axis=1)) if n_c else np.zeros(0)
        radius = float(m.flex_radius[flexes].max()) if len(flexes) else 0.0
        s_margin = float(m.flex_margin[flexes].max()) if len(flexes) else 0.0
        s_gap = float(m.flex_gap[flexes].max()) if len(flexes) else 0.0
        override = bool(m.opt.enableflags & int(mujoco.mjtEnableBit.mjENBL_OVERRIDE))
        # a flex of the mjcf model itself (not a cable) that can meet a surface: no
        # bound is kept for it, every patch stays in every pass
        meets = ((m.flex_contype & int(np.bitwise_or.reduce(m.flex_conaffinity[flexes], initial=0)))
                 | (m.flex_conaffinity & int(np.bitwise_or.reduce(m.flex_contype[flexes], initial=0)))) != 0
        self._always = bool((meets & ~surface & (m.flex_dim != 1)).any())
        # the cables: their vertices (flex vertex ids, in order) and elements (pairs of rows)
        vids, segs, grow = [], [], []
        for c in np.flatnonzero(~surface & (m.flex_dim == 1)).tolist():
            v0, n = int(m.flex_vertadr[c]), int(m.flex_vertnum[c])
            da = int(m.flex_elemdataadr[c])
            elem = m.flex_elem[da:da + 2 * int(m.flex_elemnum[c])].reshape(-1, 2).astype(np.int64)
            segs.append(elem + sum(len(v) for v in vids))
            vids.append(np.arange(v0, v0 + n))
            # a contact needs a distance below r + rho + margin + gap (mj_assignMargin:
            # the option's margin replaces the pair's under override)
            margin = float(m.opt.o_margin) if override else float(m.flex_margin[c]) + s_margin
            room = margin + float(m.flex_gap[c]) + s_gap
            slack = REACH_SLACK * margin + REACH_TOLERANCES * float(m.opt.ccd_tolerance)
            grow.append(np.full(len(elem), float(m.flex_radius[c]) + radius + room + slack))
        verts = np.concatenate(vids) if vids else np.zeros(0, np.int64)
        self._vbody = m.flex_vertbodyid[verts].astype(np.int64)
        offset = m.flex_vert[verts]
        self._held = np.flatnonzero(offset.any(axis=1))      # vertices off their body's origin
        self._offset = offset[self._held]
        self._segs = np.concatenate(segs) if segs else np.zeros((0, 2), np.int64)
        self._grow = np.concatenate(grow) if grow else np.zeros(0)
        self._compiled = tuple(a[flexes].copy() for a in self._fields())
        self._vertbody = m.flex_vertbodyid.copy()
        self._kept = np.ones(len(flexes), bool)             # as compiled: every patch in

    def __len__(self) -> int:
        return len(self.flexes)

    def _fields(self) -> tuple[np.ndarray, ...]:
        m = self.model
        return m.flex_vertnum, m.flex_elemnum, m.flex_bvhadr, m.flex_contype, m.flex_conaffinity

    def reachable(self, xpos: np.ndarray, xmat: np.ndarray) -> np.ndarray:
        """(S, F) bool: the patches some cable element can reach, for S
        states given by the body poses after mj_kinematics (the detection
        model's, or the simulation's: the same), `xpos` (S, nbody, 3) and
        `xmat` (S, nbody, 9) (module docstring).

        Before the boxes, a cull in the world frame: a segment's sphere
        (around its midpoint, half its length plus its growth) apart from the
        sphere around a body's root box is apart from the box (a few
        rotations per state are left to do, not one per segment and body)."""
        xpos, xmat = np.asarray(xpos, float), np.asarray(xmat, float)
        n_s = len(xpos)
        if self._always:
            return np.ones((n_s, len(self.flexes)), bool)
        if not len(self.flexes) or not len(self._segs):
            return np.zeros((n_s, len(self.flexes)), bool)
        n_c, n_e = len(self._carriers), len(self._segs)
        pts = xpos.take(self._vbody, axis=1)                                  # (S, V, 3), as mj_flex places them
        if len(self._held):
            rot = xmat.take(self._vbody[self._held], axis=1).reshape(n_s, -1, 3, 3)
            pts[:, self._held] += (rot @ self._offset[None, :, :, None])[..., 0]
        a, b = pts.take(self._segs[:, 0], axis=1), pts.take(self._segs[:, 1], axis=1)   # (S, E, 3)
        mid, d = 0.5 * (a + b), b - a
        # the spheres: a segment's radius with room for rounding (it only widens the cull)
        half = 0.5 * np.sqrt(_row_dots(d)) + self._grow + CULL_ROOM
        rot = xmat.take(self._carriers, axis=1).reshape(n_s, n_c, 3, 3)       # (S, B, 3, 3)
        origin = xpos.take(self._carriers, axis=1)                            # (S, B, 3)
        centre = origin + np.einsum("sbij,bj->sbi", rot, self._centre)
        # (S, B, E) squared distances of the centres, |c|^2 + |m|^2 - 2 c.m (one
        # product of matrices), and room for that sum's rounding, in proportion to it
        norms = _row_dots(centre)[:, :, None] + _row_dots(mid)[:, None, :]
        gap = norms - 2.0 * (centre @ mid.transpose(0, 2, 1))
        reach = self._radius[None, :, None] + half[:, None, :]
        near = gap <= reach * reach + CULL_ROUNDING * norms
        sc, e = np.divmod(np.flatnonzero(near), n_e)                          # flat: np.nonzero's 3-d indices cost more
        s = sc // n_c
        # the pairs left, into their body's frame: R^T (p - x)
        c, se = sc - s * n_c, s * n_e + e
        rot, origin = rot.reshape(-1, 3, 3).take(sc, axis=0), origin.reshape(-1, 3).take(sc, axis=0)
        la = np.einsum("ti,tij->tj", a.reshape(-1, 3).take(se, axis=0) - origin, rot)
        lb = np.einsum("ti,tij->tj", b.reshape(-1, 3).take(se, axis=0) - origin, rot)
        grow = self._grow.take(e)[:, None]
        apart = _segment_faces(np.minimum(la, lb) - grow, np.maximum(la, lb) + grow)      # (T, 8)
        k = np.flatnonzero(_met(apart, self._root.take(c, axis=0)))   # near all of a body's patches
        apart, body, node = apart.take(k, axis=0), c.take(k), np.zeros(len(k), np.int64)
        for step, faces, patches in self._steps:            # down the tree: the descendants of nodes met
            nodes = len(faces) // n_c
            i, j = np.divmod(np.flatnonzero(_met(np.tile(apart, 1 << step),
                                                 faces.take(body * nodes + node, axis=0))), 1 << step)
            k, body, apart, node = k.take(i), body.take(i), apart.take(i, axis=0), (node.take(i) << step) + j
            if patches:                                     # the pairs that reach a patch's box: along its axes
                row = self._patch_row.take(body * self._patch_row.shape[1] + node)
                i = np.flatnonzero(self._along(la.take(k, axis=0), lb.take(k, axis=0), grow.take(k, axis=0), row,
                                               self.axes, self._patch_faces, self._patch_centre, self._patch_half))
                k, body, apart, node = k.take(i), body.take(i), apart.take(i, axis=0), node.take(i)
        # the pairs met at the leaves, each segment again along its piece's own
        # axes (a padding leaf's empty box met nothing)
        row = self._leaf_row.take(body * self._leaf_row.shape[1] + node)
        near = self._along(la.take(k, axis=0), lb.take(k, axis=0), grow.take(k, axis=0), row, self.piece_axes,
                           self._axis_faces, self._axis_centre, self._axis_half)
        out = np.zeros((n_s, len(self.flexes)), bool)
        out[s.take(k)[near], self.piece_patch.take(row[near])] = True
        return out

    @staticmethod
    def _along(la: np.ndarray, lb: np.ndarray, grow: np.ndarray, row: np.ndarray, axes: np.ndarray,
               faces: np.ndarray, centre: np.ndarray, half: np.ndarray) -> np.ndarray:
        """(T,) True where segments (ends `la`, `lb` (T, 3) in the body's
        frame, grown by `grow` (T, 1)) reach boxes `row` (T,) along the
        boxes' own axes (`axes`, and the boxes as `_faces`, centres and
        halves along them) and along the segment's direction crossed with
        each axis (with the box's own, every axis on which a segment and a
        box can lie apart)."""
        axes = axes.take(row, axis=0)
        pa, pb = np.einsum("tij,tj->ti", axes, la), np.einsum("tij,tj->ti", axes, lb)
        meet = _met(_segment_faces(np.minimum(pa, pb) - grow, np.maximum(pa, pb) + grow), faces.take(row, axis=0))
        # along L = w x axis, w the segment's half (w . L = 0: the segment
        # projects to a point): |m . L| beyond the box's reach along L and
        # the growth times |L|, m the segment's midpoint from the box's centre
        w, half = 0.5 * (pb - pa), half.take(row, axis=0)
        m = 0.5 * (pa + pb) - centre.take(row, axis=0)
        j, i = [1, 2, 0], [2, 0, 1]
        wj, wi, aw = w[:, j], w[:, i], np.abs(w)
        across = np.abs(m[:, j] * wi - m[:, i] * wj)
        reach = half[:, j] * aw[:, i] + half[:, i] * aw[:, j] + grow * np.sqrt(wj * wj + wi * wi)
        return meet & ~(across > reach).any(axis=1)

    def leave_out(self, keep: np.ndarray) -> None:
        """Take the patches in `keep` (F,) bool into the next mj_flex and
        mj_collision of the model and leave the others out (`restore` puts
        them all back). Only the patches whose state changes are written."""
        for _ in self.leave_out_each(np.asarray(keep, bool)[None]):
            pass

    def leave_out_each(self, keep: np.ndarray) -> Iterator[int]:
        """`leave_out` for S states in turn, `keep` (S, F) bool: yields each
        state's index once the model is set for it. What changes from state
        to state is found for all of them at once; a state writes only the
        patches that change (none, mostly: then nothing)."""
        keep = np.asarray(keep, bool)
        n_s, n_f = keep.shape
        if not n_f:
            yield from range(n_s)
            return
        before = np.concatenate([self._kept[None], keep[:-1]])
        state, row = np.divmod(np.flatnonzero(keep != before), n_f)          # the changes, state by state
        now = keep[state, row]
        flexes = self.flexes.take(row)
        values = [np.where(now, compiled.take(row), off)
                  for compiled, off in zip(self._compiled, (0, 0, -1, 0, 0))]
        count = self._compiled[0].take(row)                                    # their vertices as compiled
        verts = ranges(self.model.flex_vertadr[flexes], count)
        bodies = np.where(np.repeat(now, count), self._vertbody[verts], 0)
        at = np.searchsorted(state, np.arange(n_s + 1)).tolist()
        vert_at = np.concatenate([[0], np.cumsum(count)])[at].tolist()
        fields, vertbody = self._fields(), self.model.flex_vertbodyid
        for i in range(n_s):
            lo, hi = at[i], at[i + 1]
            if hi > lo:
                f = flexes[lo:hi]
                for field, value in zip(fields, values):
                    field[f] = value[lo:hi]
                vertbody[verts[vert_at[i]:vert_at[i + 1]]] = bodies[vert_at[i]:vert_at[i + 1]]
                self._kept = keep[i].copy()
            yield i

    def restore(self) -> None:
        """Every patch as compiled."""
        for field, value in zip(self._fields(), self._compiled):
            field[self.flexes] = value
        self.model.flex_vertbodyid[:] = self._vertbody
        self._kept = np.ones(len(self.flexes), bool)


def _row_dots(x: np.ndarray) -> np.ndarray:
    """(..., 3) -> (...): each row's dot product with itself (a product
    with a vector of ones: numpy's sum or einsum over a short last axis
    cost several times more)."""
    return (x * x) @ np.ones(3)


def _faces(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Boxes (..., 3) as `_met` compares them: (hi, -lo) and two columns of
    +inf (nothing is greater), (..., 8)."""
    pad = np.full(lo.shape[:-1] + (2,), np.inf)
    return np.concatenate([hi, -lo, pad], axis=-1)


def _segment_faces(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Segments' boxes (T, 3) as `_met` compares them: (lo, -hi) and two
    zeros, (T, 8)."""
    return np.concatenate([lo, -hi, np.zeros((len(lo), 2))], axis=1)


def _met(apart: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(T, 8k) segments' boxes (`_segment_faces`) against (T, 8k) boxes
    (`_faces`), k of each per row side by side: (T * k,) True where a
    segment's box meets its box (no axis holds them apart: lo > hi or
    -hi > -lo). The eight comparisons of a pair are eight bytes of one
    64-bit word, zero when none holds (numpy's any over a short axis costs
    ten times more)."""
    return np.greater(apart, faces).view(np.uint64).ravel() == 0


def pieces(m: mujoco.MjModel, flexes: np.ndarray, levels: int) -> tuple[np.ndarray, ...]:
    """The triangles of each surface patch `flexes` (F,) of `m` cut in
    `levels` halvings (each piece's triangles split at the median of their
    centres along the piece's longest side), 2**levels pieces a patch at
    most, empty ones left out. Returns, per piece: its patch (row of
    `flexes`) and number within the patch (P,), the box of its triangles in
    the body's frame, lo and hi (P, 3), and along its principal axes
    (`oriented_boxes`: axes (P, 3, 3), lo and hi (P, 3))."""
    flexes = np.asarray(flexes, np.int64)
    if not len(flexes):
        return (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 3)),
                np.zeros((0, 3, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
    if (m.flex_dim[flexes] != 2).any():
        raise ValueError("surface patches are flexes of triangles")
    count = m.flex_elemnum[flexes].astype(np.int64)
    patch = np.repeat(np.arange(len(flexes)), count)                     # (N,) each triangle's
    first = np.repeat(m.flex_elemdataadr[flexes].astype(np.int64), count) + 3 * within(count)
    corner = m.flex_elem[first[:, None] + np.arange(3)] + np.repeat(m.flex_vertadr[flexes], count)[:, None]
    tri = m.flex_vert.reshape(-1, 3)[corner]                                # (N, 3, 3) in the body's frame
    centre = tri.mean(axis=1)
    node = np.zeros(len(tri), np.int64)
    rows = np.arange(len(tri))
    for level in range(levels):
        group, n_g = (patch << level) + node, len(flexes) << level
        lo, hi = np.full((n_g, 3), np.inf), np.full((n_g, 3), -np.inf)
        np.minimum.at(lo, group, centre)
        np.maximum.at(hi, group, centre)
        side = np.argmax(np.where(np.isfinite(hi - lo), hi - lo, 0.0), axis=1)
        order = np.lexsort((centre[rows, side.take(group)], group))       # by piece, then along its side
        size = np.bincount(group, minlength=n_g)
        rank = within(size)                                               # in that order
        node[order] = 2 * node[order] + (2 * rank >= size.take(group[order]))
    piece = (patch << levels) + node
    order = np.argsort(piece, kind="stable")
    size = np.bincount(piece, minlength=len(flexes) << levels)
    used = np.flatnonzero(size)
    verts = tri[order].reshape(-1, 3)
    adr = 3 * (np.cumsum(size) - size)[used]
    axes, axis_lo, axis_hi = oriented_boxes(verts, adr, 3 * size[used])
    return (used >> levels, used & ((1 << levels) - 1), np.minimum.reduceat(verts, adr, axis=0),
            np.maximum.reduceat(verts, adr, axis=0), axes, axis_lo, axis_hi)


def oriented_boxes(verts: np.ndarray, adr: np.ndarray, count: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Boxes along the principal axes of groups of points: group k is
    `verts[adr[k]:adr[k] + count[k]]`, the groups back to back from the
    first point to the last, none empty (a model's flexes).
    Returns (K, 3, 3) orthonormal axes as rows and (K, 3) the points' least
    and largest coordinates along them. A surface patch is a thin piece of
    a mesh, often slanted in its body's frame: along its own axes its box is
    far tighter than the axis-aligned one."""
    verts = np.asarray(verts, float).reshape(-1, 3)
    adr, n = np.asarray(adr, np.int64), np.asarray(count, np.int64)
    centre = np.add.reduceat(verts, adr, axis=0) / n[:, None]
    d = verts - np.repeat(centre, n, axis=0)
    scatter = np.add.reduceat(d[:, :, None] * d[:, None, :], adr, axis=0)
    axes = np.linalg.eigh(scatter)[1].transpose(0, 2, 1)                      # eigenvectors as rows
    along = np.einsum("vij,vj->vi", np.repeat(axes, n, axis=0), verts)
    return axes, np.minimum.reduceat(along, adr, axis=0), np.maximum.reduceat(along, adr, axis=0)
