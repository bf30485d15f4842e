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
(each node the box of its children) to the patches themselves, and last
the segments that reach a patch's box again along the patch's own
principal axes (`oriented_boxes`: a slanted, thin patch's box along them
is far tighter; any direction separates as well as the body's axes). Every
one-dimensional flex counts as a cable; should the mjcf model bring a
flex of another dimension that can meet a surface, no patch is ever left
out. The positions are the detection model's own
(mj_kinematics at the state, the cable vertices placed as mj_flex places
them): nothing comes from the checker, so validation still judges the
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
        # below the root, each level's boxes by parent, both children at once, as
        # (hi, -lo): a segment's (lo, -hi) greater along any axis is apart from it
        self._children = [np.concatenate([hi, -lo], axis=2).reshape(n_c, -1, 2, 6) for lo, hi in self._levels[1:]]
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
        `xpos` (S, nbody, 3) and `xmat` (S, nbody, 9) (module docstring)."""
        xpos, xmat = np.asarray(xpos, float), np.asarray(xmat, float)
        n_s = len(xpos)
        if self._always:
            return np.ones((n_s, len(self.flexes)), bool)
        if not len(self.flexes) or not len(self._segs):
            return np.zeros((n_s, len(self.flexes)), bool)
        pts = xpos[:, self._vbody]                                            # (S, V, 3), as mj_flex places them
        if len(self._held):
            rot = xmat[:, self._vbody[self._held]].reshape(n_s, -1, 3, 3)
            pts[:, self._held] += (rot @ self._offset[None, :, :, None])[..., 0]
        rot = xmat[:, self._carriers].reshape(n_s, -1, 3, 3)                  # (S, B, 3, 3)
        diff = pts[:, None, :, :] - xpos[:, self._carriers, None, :]          # (S, B, V, 3)
        local = diff @ rot                                                    # into each carrier's frame: R^T (p - x)
        a, b = local[:, :, self._segs[:, 0]], local[:, :, self._segs[:, 1]]   # (S, B, E, 3)
        grow = self._grow[:, None]
        seg_lo, seg_hi = np.minimum(a, b) - grow, np.maximum(a, b) + grow
        root_lo, root_hi = self._levels[0]
        near = ~((seg_lo > root_hi[:, 0][:, None, :]) | (seg_hi < root_lo[:, 0][:, None, :])).any(axis=3)
        s, c, e = np.nonzero(near)                          # segments near all of a body's patches
        apart = np.concatenate([seg_lo[s, c, e], -seg_hi[s, c, e]], axis=1)   # (T, 6)
        seg, body, node = np.arange(len(s)), c, np.zeros(len(s), np.int64)
        for children in self._children:                     # down the tree: the children of nodes met
            meet = ~(apart[:, None, :] > children[body, node]).any(axis=2)   # (T, 2)
            i, j = np.nonzero(meet)
            seg, body, apart, node = seg[i], body[i], apart[i], 2 * node[i] + j
        # the pairs met at the leaves, each segment again in its patch's own
        # axes (a padding leaf's empty box met nothing)
        s, c, e, row = s[seg], body, e[seg], self._leaf_row[body, node]
        axes = self.axes[row]                                                 # (T, 3, 3), rows the axes
        a = (axes @ local[s, c, self._segs[e, 0]][:, :, None])[..., 0]
        b = (axes @ local[s, c, self._segs[e, 1]][:, :, None])[..., 0]
        grow = self._grow[e][:, None]
        meet = ~((np.minimum(a, b) - grow > self.axis_hi[row]) | (np.maximum(a, b) + grow < self.axis_lo[row])).any(1)
        out = np.zeros((n_s, len(self.flexes)), bool)
        out[s[meet], row[meet]] = True
        return out

    def leave_out(self, keep: np.ndarray) -> None:
        """Take the patches in `keep` (F,) bool into the next mj_flex and
        mj_collision of the model and leave the others out (`restore` puts
        them all back). Only the patches whose state changes are written."""
        keep = np.asarray(keep, bool)
        change = np.flatnonzero(keep != self._kept)
        if not len(change):
            return
        flexes, now = self.flexes[change], keep[change]
        for field, compiled, off in zip(self._fields(), self._compiled, (0, 0, -1, 0, 0)):
            field[flexes] = np.where(now, compiled[change], off)
        count = self._compiled[0][change]                   # the patches' vertices as compiled
        verts = ranges(self.model.flex_vertadr[flexes], count)
        self.model.flex_vertbodyid[verts] = np.where(np.repeat(now, count), self._vertbody[verts], 0)
        self._kept = keep.copy()

    def restore(self) -> None:
        """Every patch as compiled."""
        for field, value in zip(self._fields(), self._compiled):
            field[self.flexes] = value
        self.model.flex_vertbodyid[:] = self._vertbody
        self._kept = np.ones(len(self.flexes), bool)


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
