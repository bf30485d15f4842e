"""Which patches of the concave mesh surfaces the cables can reach at a state.

A concave mesh is seen by the detection model as rigid flexes of its own
triangles, in patches (`sim.detection_mesh`). MuJoCo places every flex at
every mj_flex (vertices, element boxes, tree) and its collision pass
visits every flex that has contact bits (the broadphase box of all its
vertices, then the tree against each cable), near a cable or not: a
state's cost would grow with the meshes' size. `SurfaceReach` leaves the
patches no cable can reach out of the state's pass, so it grows with what
is near.

The bound: a patch's triangles lie in its box (axis-aligned in the frame
of the body that carries them, fixed). MuJoCo makes a contact between a
cable element (segment, radius r) and a triangle (radius rho) only when
their distance is below r + rho + the pair's margin and gap (the two
flexes' added; mj_collideElems), give or take the convex solver's
tolerance (`opt.ccd_tolerance`: the solver tests the shapes grown by the
margin for intersection to that tolerance). When the segment's box, in
the patch body's frame, lies apart from the patch's box grown by r + rho
+ margin + gap + `REACH_SLACK` along some axis, every point of the segment
is that far from every point of the patch, so MuJoCo could report no
contact there. The test runs in
three steps with the same bound: each segment against the box of all the
patches on a body, then down a tree of boxes over that body's patches
(each node the box of its children, a few levels at a time) to the
patches themselves, and last the segments that reach a patch's box again
along the patch's own principal axes (`oriented_boxes`: a slanted, thin
patch's box along them is far tighter; any direction separates as well as
the body's axes). Before them a cull in the world frame leaves out, with
no rotation, the (segment, body) pairs whose spheres lie apart (the
segment's around its box grown by the bound, the body's around the box
of its patches): what it leaves out the first step would, so the patches
kept are the same. Every
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

This module does not read contacts (`sim.contacts`) or decide what a
contact means; it only narrows MuJoCo's pass.
"""

from __future__ import annotations

from collections.abc import Iterator

import mujoco
import numpy as np

from checker.arrays import ranges
from sim.detection_mesh import surface_geoms


REACH_SLACK = 0.1
"""Room beyond MuJoCo's contact distance in the reach bound, as a share of
the pair's margin (module docstring) ..."""

REACH_TOLERANCES = 100.0
"""... and in convex solver tolerances (`opt.ccd_tolerance`, the precision
of MuJoCo's intersection test of the grown shapes): far more than any
rounding, far less than a patch."""

TREE_STEP = 2
"""Levels of a body's tree of patch boxes tested at once (2**2 boxes per
segment): fewer steps down the tree, each a few numpy calls (1, 2, 3, 4 levels
at once: 64, 55, 59, 73 us a state on the robot cell, side by side)."""

CULL_ROOM = 1e-9
"""Metres added to a segment's sphere in the first cull (`SurfaceReach.reachable`):
far more than the rounding of the distances, it only keeps more to test."""


class SurfaceReach:
    """The surface patches of a detection model, their reach test and the
    switch that leaves some out of a collision pass.

    Args:
      model: the detection model (`sim.detection_mesh.add_surfaces`).

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
        # per body carrying patches, a binary tree of boxes over its patches (in
        # flex order: a surface's patches come in k-d order, neighbours next to
        # each other), padded to 2**depth leaves with empty boxes; level 0 is
        # the box of all the body's patches
        self._carriers, row_body = np.unique(self.bodies, return_inverse=True)
        n_c = len(self._carriers)
        rank = np.zeros(len(flexes), np.int64)
        order = np.argsort(row_body, kind="stable")
        starts = np.searchsorted(row_body[order], np.arange(n_c))
        rank[order] = np.arange(len(flexes)) - starts[row_body[order]]
        depth = int(np.ceil(np.log2(rank.max() + 1))) if len(flexes) else 0
        self._leaf_row = np.full((n_c, 2 ** depth), -1, np.int64)
        self._leaf_row[row_body, rank] = np.arange(len(flexes))
        lo = np.full((n_c, 2 ** depth, 3), np.inf)
        hi = np.full((n_c, 2 ** depth, 3), -np.inf)
        lo[row_body, rank], hi[row_body, rank] = self.lo, self.hi
        self._levels = [(lo, hi)]
        while lo.shape[1] > 1:
            lo, hi = lo.reshape(n_c, -1, 2, 3).min(axis=2), hi.reshape(n_c, -1, 2, 3).max(axis=2)
            self._levels.insert(0, (lo, hi))
        # the boxes as the test compares them (`_met`): the root's (B, 8) and,
        # below it, a few levels at a time (`TREE_STEP`), each step's level by
        # ancestor in the level above the step, all its 2**step descendants at
        # once (B * nodes, 8 * 2**step): a box its descendants meet it meets too
        self._root = _faces(self._levels[0][0][:, 0], self._levels[0][1][:, 0])
        self._steps = []
        level = 0
        while level + 1 < len(self._levels):
            step = min(TREE_STEP, len(self._levels) - 1 - level)
            level += step
            self._steps.append((step, _faces(*self._levels[level]).reshape(-1, 8 << step)))
        self._axis_faces = _faces(self.axis_lo, self.axis_hi)
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
        states given by the detection model's body poses after mj_kinematics,
        `xpos` (S, nbody, 3) and `xmat` (S, nbody, 9) (module docstring).

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
            pts[:, self._held] += np.einsum("svij,vj->svi", rot, self._offset)
        a, b = pts.take(self._segs[:, 0], axis=1), pts.take(self._segs[:, 1], axis=1)   # (S, E, 3)
        mid, d = 0.5 * (a + b), b - a
        # the spheres: a segment's radius with room for rounding (it only widens the cull)
        half = 0.5 * np.sqrt(_row_dots(d)) + self._grow + CULL_ROOM
        rot = xmat.take(self._carriers, axis=1).reshape(n_s, n_c, 3, 3)       # (S, B, 3, 3)
        origin = xpos.take(self._carriers, axis=1)                            # (S, B, 3)
        centre = origin + np.einsum("sbij,bj->sbi", rot, self._centre)
        gap = (_row_dots(centre)[:, :, None] + _row_dots(mid)[:, None, :]
               - 2.0 * (centre @ mid.transpose(0, 2, 1)))                     # (S, B, E) squared distances
        reach = self._radius[None, :, None] + half[:, None, :]
        sc, e = np.divmod(np.flatnonzero(gap <= reach * reach), n_e)          # flat: np.nonzero's 3-d indices cost more
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
        for step, faces in self._steps:                     # down the tree: the descendants of nodes met
            nodes = len(faces) // n_c
            i, j = np.divmod(np.flatnonzero(_met(np.tile(apart, 1 << step),
                                                 faces.take(body * nodes + node, axis=0))), 1 << step)
            k, body, apart, node = k.take(i), body.take(i), apart.take(i, axis=0), (node.take(i) << step) + j
        # the pairs met at the leaves, each segment again in its patch's own
        # axes (a padding leaf's empty box met nothing)
        row = self._leaf_row.take(body * self._leaf_row.shape[1] + node)
        axes, grow = self.axes.take(row, axis=0), grow.take(k, axis=0)
        pa, pb = np.einsum("tij,tj->ti", axes, la.take(k, axis=0)), np.einsum("tij,tj->ti", axes, lb.take(k, axis=0))
        meet = _met(_segment_faces(np.minimum(pa, pb) - grow, np.maximum(pa, pb) + grow),
                    self._axis_faces.take(row, axis=0))
        out = np.zeros((n_s, len(self.flexes)), bool)
        out[s.take(k)[meet], row[meet]] = True
        return out

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
