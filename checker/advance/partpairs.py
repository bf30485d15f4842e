"""The skip rule's bound on part pairs (part-part, keep-out between parts).

Two rigid parts that may move relative to each other stay apart while a
bound on how far one moved relative to the other stays below a lower bound
on their distance at the full check, the separation of their oriented boxes
along a box axis (:func:`part_pair_bounds`): the sum of their moves in the
world, or the move of one in the other's own frame, modulo turns about the
axis of a solid of revolution (:class:`PartPairGaps`); or while the same
separation at the state itself exceeds the clearance (a door panel that
swung far from its start, still far from the frame).

Deliberately not here: cables, the run of states
(:class:`cablecheck.checker.advance.skip.Advancement`), the part-part check itself
(:mod:`cablecheck.checker.parts`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cablecheck.checker.partset import PartSet, Placement


def part_pair_bounds(parts: PartSet, placed: Placement, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Lower bounds (n,) on the distance between parts i and j (n,).

    Two finite parts: the largest separation of their oriented boxes along
    one of the six box axes (0 or less when they may overlap). A plane
    (half-space local z < 0) and a finite part: the height of the part's box
    above the plane (what the part-part check measures, the lowest vertex,
    is at least that). Two planes: inf (no vertices to test).
    """
    rot, c, pos = placed.rot, placed.centre, placed.pos
    return box_bounds(parts.half(), parts.plane, i, j, (rot[i], c[i], pos[i]), (rot[j], c[j], pos[j]))


def box_bounds(half: np.ndarray, plane: np.ndarray, i: np.ndarray, j: np.ndarray,
               a: tuple[np.ndarray, np.ndarray, np.ndarray],
               b: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """:func:`part_pair_bounds` from the parts' half extents (P, 3) and
    plane flags (P,), for pairs of parts i, j (n,) placed as ``a`` and ``b``:
    each (rotations (n, 3, 3), box centres (n, 3), origins (n, 3)) in the
    world (a pair may list the same parts at another pose)."""
    out = np.full(len(i), np.inf)
    pi, pj = plane[i], plane[j]
    both = ~pi & ~pj
    if both.any():
        ra, rb = a[0][both], b[0][both]
        ha, hb = half[i[both]], half[j[both]]
        t = b[1][both] - a[1][both]
        rel = np.abs(np.einsum("nji,njk->nik", ra, rb))   # |A_i . B_k|
        ta = np.abs(np.einsum("nji,nj->ni", ra, t))        # along a's axes
        tb = np.abs(np.einsum("nji,nj->ni", rb, t))        # along b's axes
        sa = ta - ha - np.einsum("nik,nk->ni", rel, hb)
        sb = tb - hb - np.einsum("nik,ni->nk", rel, ha)
        out[both] = np.maximum(sa.max(axis=1), sb.max(axis=1))
    one = pi ^ pj
    if one.any():
        flip = pi[one][:, None]                            # the plane first
        p_rot = np.where(flip[:, :, None], a[0][one], b[0][one])
        p_pos = np.where(flip, a[2][one], b[2][one])
        q_rot = np.where(flip[:, :, None], b[0][one], a[0][one])
        q_c = np.where(flip, b[1][one], a[1][one])
        q = np.where(pi, j, i)[one]
        nrm = p_rot[:, :, 2]
        height = np.einsum("ni,ni->n", q_c - p_pos, nrm)
        extent = np.einsum("nk,nk->n", np.abs(np.einsum("nji,nj->ni", q_rot, nrm)), half[q])
        out[one] = height - extent
    return out


@dataclass(frozen=True)
class PartSolids:
    """What the part-pair condition knows of each part beyond its bounding radius.

    Attributes:
        lo, hi: (P, 3) bounds in the part's own frame of everything the
            checks measure of it (cables against its solid, parts against
            its triangles or, curved, its true shape: both within the box
            ``PartSet`` grows by the tessellation error); infinite for a plane.
        axial: (P,) bool, the part is unchanged by any turn about its
            frame's z axis (:attr:`cablecheck.checker.partset.PartSet.axial`).
        error: (P,) the part's tessellation error, held off the turned
            bound as a margin (the part-part check measures curved parts
            on their true shapes, never above the true distance).
        group: (P,) int, the rigid body each part rides on (parts of one
            group never move relative to each other), or None: the
            condition then tests no group's box (:class:`PartPairGaps`).
    """

    lo: np.ndarray
    hi: np.ndarray
    axial: np.ndarray
    error: np.ndarray
    group: np.ndarray | None = None


def _boxes_apart(half: np.ndarray, mid: np.ndarray, frame: np.ndarray, i: np.ndarray, j: np.ndarray,
                 poses: np.ndarray, mu: float, clearance: float, plane: np.ndarray | None = None) -> np.ndarray:
    """(n, S): boxes i and j (n,) (half extents and centres (B, 3) in the
    frames of parts ``frame`` (B,); ``plane`` (B,) marks half-spaces) more
    than ``clearance`` apart on a box axis (:func:`box_bounds`) at each of
    poses (S, P, 4, 4), past a rounding margin: ``mu`` plus 1e-9 of the
    boxes' extent from the origin (what the part-part check's own rounding
    allowance grows with)."""
    n_s, n = len(poses), len(i)
    both = np.concatenate([i, j])
    placed = poses[:, frame[both]]                                     # (S, 2n, 4, 4)
    rot = placed[..., :3, :3].reshape(-1, 3, 3)                        # (S * 2n, 3, 3), state-major
    pos = placed[..., :3, 3].reshape(-1, 3)
    c = np.einsum("nij,nj->ni", rot, np.tile(mid[both], (n_s, 1))) + pos
    first = (np.arange(n_s)[:, None] * 2 * n + np.arange(n)[None]).ravel()     # state-major rows
    second = first + n
    ti, tj = np.tile(i, n_s), np.tile(j, n_s)
    flat = np.zeros(len(half), bool) if plane is None else plane
    sep = box_bounds(half, flat, ti, tj, (rot[first], c[first], pos[first]), (rot[second], c[second], pos[second]))
    extent = np.abs(c).max(axis=1) + half[np.tile(both, n_s)].max(axis=1)
    margin = mu + 1e-9 * (extent[first] + extent[second])
    return (sep - clearance > margin).reshape(n_s, n).T


def _turned_z(v: np.ndarray, cos: np.ndarray, sin: np.ndarray) -> np.ndarray:
    """Points v (..., 3) turned about z by the angle of (cos, sin) (broadcast to v[..., 0])."""
    out = np.empty(np.broadcast_shapes(v.shape, cos.shape[:-1] + (3,)))
    x, y = v[..., 0], v[..., 1]
    out[..., 0] = cos[..., 0] * x - sin[..., 0] * y
    out[..., 1] = sin[..., 0] * x + cos[..., 0] * y
    out[..., 2] = v[..., 2]
    return out


def _corner_moves(d_rot: np.ndarray, d_pos: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(n,): the largest ``|d_rot c + d_pos|`` over the corners c (n, 8, 3)
    for d_rot (n, 3, 3), d_pos (n, 3)."""
    v = corners @ np.swapaxes(d_rot, -1, -2) + d_pos[:, None, :]
    return np.sqrt(np.einsum("nki,nki->nk", v, v).max(axis=1))


@dataclass(frozen=True, slots=True)
class PairStart:
    """What :meth:`PartPairGaps.start` keeps of one start: the part-pair
    condition's state until the next.

    Attributes:
        poses: (P, 4, 4) the parts' poses at the start.
        pi, pj: (M,) the moving part pairs.
        g_pair: (M,) their gaps, ``bound - clearance - mu``.
        g_rel: (M,) the gaps the ``rel`` bound is held to (less both
            tessellation errors where it is turned).
        mu: the rounding margin.
        ok: every gap is positive (else nothing is proven).
        f, m: (M,) each pair's frame part and other part.
        turn: (M,) the frame part is axial (and no plane): ``rel`` is turned.
        q0, s0, c0: (M, 3, 3), (M, 3), (M, 8, 3) the other part's pose and
            box corners in the frame part's frame at the start.
        q0_sin: (M, 2, 3) the rows of ``q0`` whose product with Q's top
            rows gives the sine of the undoing turn.
    """

    poses: np.ndarray
    pi: np.ndarray
    pj: np.ndarray
    g_pair: np.ndarray
    g_rel: np.ndarray
    mu: float
    ok: bool
    f: np.ndarray
    m: np.ndarray
    turn: np.ndarray
    q0: np.ndarray
    s0: np.ndarray
    c0: np.ndarray
    q0_sin: np.ndarray


@dataclass(frozen=True, slots=True)
class GroupBoxes:
    """Each rigid group's box at a start: the box of its boxed parts' boxes
    (not a plane's, not a part without a box: those pairs are left to the
    other tests), in the frame of one of them (``ref``), which carries it
    (the parts of a group keep their relative poses).

    Attributes:
        of: (P,) each part's group index (into the arrays below).
        inside: (P,) the part's box is in its group's.
        ref: (G,) the part whose frame holds the group's box.
        half, mid: (G, 3) the box's half extents and centre in that frame.
    """

    of: np.ndarray
    inside: np.ndarray
    ref: np.ndarray
    half: np.ndarray
    mid: np.ndarray


def group_boxes(group: np.ndarray, poses: np.ndarray, corners: np.ndarray, boxed: np.ndarray) -> GroupBoxes:
    """:class:`GroupBoxes` of parts in groups ``group`` (P,) at poses (P, 4, 4),
    from each part's box corners (P, 8, 3) in its frame (``boxed`` (P,):
    the part has a box)."""
    _, of = np.unique(group, return_inverse=True)
    n_g = int(of.max()) + 1 if len(of) else 0
    idx = np.flatnonzero(boxed)
    ref = np.zeros(n_g, np.int64)
    ref[of[idx[::-1]]] = idx[::-1]                       # each group's first boxed part (0: none)
    # the boxed parts' corners in their group's reference frame: R_ref^T (R_p c + t_p - t_ref)
    p = poses[idx]
    r_ref, t_ref = poses[ref[of[idx]], :3, :3], poses[ref[of[idx]], :3, 3]
    world = np.einsum("pij,pkj->pki", p[:, :3, :3], corners[idx]) + p[:, None, :3, 3]
    local = np.einsum("pji,pkj->pki", r_ref, world - t_ref[:, None, :])
    lo = np.zeros((n_g, 3))
    hi = np.zeros((n_g, 3))
    if len(idx):
        lo[of[idx]] = np.inf
        hi[of[idx]] = -np.inf
        np.minimum.at(lo, of[idx], local.min(axis=1))
        np.maximum.at(hi, of[idx], local.max(axis=1))
    return GroupBoxes(of, np.asarray(boxed, bool), ref, 0.5 * (hi - lo), 0.5 * (hi + lo))


class PartPairGaps:
    """The part-pair condition, restarted at every full check.

    A pair (i, j) is clear at a state while the bound on how far any point of
    one part moved relative to the other since the start stays below its
    gap ``g = bound - clearance - mu``: the least of

    - ``dp[i] + dp[j]``, how far any point of each moved in the world
      (:meth:`moves`): ``||R - R0||_F rho + |t - t0|``, or with the parts'
      boxes (:class:`PartSolids`) the largest move of a corner of the box,
      ``max |(R - R0) c + t - t0|`` (a point's move is convex in the point,
      so a box's largest is at a corner);
    - ``rel``: the motion of the pair's *other* part in its *frame* part's
      own frame (a part on a plane's side is measured in the plane's frame):
      with ``Q = R_f^T R_m`` and ``s = R_f^T (t_m - t_f)``, every point
      ``Q u + s`` of the other part moved by at most
      ``||Q - Q0||_F rho_m + |s - s0|``, or the largest ``|(Q - Q0) c + s - s0|``
      over the corners c of its box, relative to the frame part (two parts
      turning and moving together move nothing relative to each other);
    - where the frame part is unchanged by turning about its own z axis
      (``axial``: a cylinder, capsule, sphere or round ellipsoid, as the
      part-part check measures it), the same after turning the other part's
      relative pose about that axis by the angle ``phi`` that best undoes
      its turn since the start, ``Rz(phi) ~ Q0 Q^T`` (a door knuckle turning
      on a hinge pin, a panel swinging round the knuckle's axis: nothing
      moves); the corners of the other part's box are turned (a part
      without a box keeps the radius bound, not turned). The distance of
      the true shapes is the same at both poses, and the part-part check
      measures a curved part on its true shape (against a primitive,
      :mod:`cablecheck.checker.convex`; against a mesh, the mesh's triangles against
      the true shape, :mod:`cablecheck.checker.parts`), never above the true distance;
      this bound is still held to ``g - error[i] - error[j]`` (the
      tessellation errors), a margin on the safe side.

    Each is a bound on the drop of the distance (1-Lipschitz in the points),
    so the pair stays outside the clearance while any one holds. Any
    ``phi`` is sound (its choice only tightens): ``Rz(phi)`` is an isometry
    of the frame part's solid. Failing all three, a pair is still clear at
    a state where its boxes (:class:`PartSolids`, holding the part-part
    check's own boxes) are more than the clearance apart on a box axis
    (:func:`box_bounds`): the check's oriented-box test rejects it there.
    Before those, with the parts' rigid groups known (``solids.group``),
    every pair of two groups whose boxes (:class:`GroupBoxes`, holding
    their parts' boxes) are that far apart at the state is clear at once:
    a gripper's two dozen finger capsules against an arm's links and a
    table are a few group pairs a state, not hundreds of part pairs.

    Args:
        part_radius: (P,) bounding radius of each part about its frame's
            origin (inf for planes).
        clearance: the clearance.
        solids: the parts' boxes, symmetry and tessellation errors, or
            None (the bounding radii alone, no symmetry).
    """

    def __init__(self, part_radius: np.ndarray, clearance: float, solids: PartSolids | None = None):
        self._rho = np.asarray(part_radius, float)
        n = len(self._rho)
        self._plane = ~np.isfinite(self._rho)
        self._axial = np.zeros(n, bool) if solids is None else np.asarray(solids.axial, bool)
        self._error = np.zeros(n) if solids is None else np.asarray(solids.error, float)
        self._group = None if solids is None or solids.group is None else np.asarray(solids.group, np.int64)
        self._boxes: GroupBoxes | None = None      # the group boxes of the start `_boxes_of`
        self._boxes_of: PairStart | None = None
        self._boxed = np.zeros(n, bool)
        self._corners = np.zeros((n, 8, 3))                            # (P, 8, 3), 0 where unboxed
        if solids is not None:
            lo, hi = np.asarray(solids.lo, float), np.asarray(solids.hi, float)
            self._boxed = np.isfinite(lo).all(axis=1) & np.isfinite(hi).all(axis=1)
            pick = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], bool)
            box = np.where(self._boxed[:, None, None], np.stack([lo, hi], axis=1), 0.0)
            self._corners = np.where(pick[None], box[:, 1][:, None], box[:, 0][:, None])
        # the boxes the state's own separation measures (box_bounds): half extents and centres
        self._half = np.where(self._boxed[:, None], 0.5 * (self._corners[:, 7] - self._corners[:, 0]), 0.0)
        self._mid = np.where(self._boxed[:, None], 0.5 * (self._corners[:, 7] + self._corners[:, 0]), 0.0)
        self._known = self._boxed | self._plane
        # the frame part of a pair: a plane first, then an axial part
        self._rank = np.where(self._plane, 2, np.where(self._axial, 1, 0))
        self.clearance = float(clearance)
        self._at: PairStart | None = None
        """The last start (None: before one, or stopped since)."""

    @property
    def ok(self) -> bool:
        """True while the last start proved every pair apart (else nothing is proven)."""
        return self._at is not None and self._at.ok

    def start(self, poses: np.ndarray, pairs: tuple[np.ndarray, np.ndarray],
              pair_bound: np.ndarray, mu: float | None = None) -> None:
        """Restart at this state: part poses (P, 4, 4), the moving part pairs
        (i, j) and lower bounds on their distances (:func:`part_pair_bounds`);
        ``mu`` the rounding margin (None: from the poses)."""
        self._at = self._started(poses, pairs, pair_bound, mu)

    def _started(self, poses: np.ndarray, pairs: tuple[np.ndarray, np.ndarray],
                 pair_bound: np.ndarray, mu: float | None) -> PairStart:
        """The :class:`PairStart` of a start (arguments as :meth:`start`)."""
        poses = np.array(poses, float)
        pi, pj = (np.asarray(x, np.int64) for x in pairs)
        if mu is None:
            mu = 1e-9 * (1.0 + float(np.abs(poses[:, :3, 3]).max(initial=0.0)))
        g_pair = np.asarray(pair_bound, float) - self.clearance - mu
        swap = self._rank[pj] > self._rank[pi]
        f, m = np.where(swap, pj, pi), np.where(swap, pi, pj)
        turn = self._axial[f] & ~self._plane[f]
        g_rel = g_pair - np.where(turn, self._error[pi] + self._error[pj], 0.0)
        q0, s0, c0 = self._relative(poses[None], f, m)
        q0, s0, c0 = q0[0], s0[0], c0[0]
        q0_sin = np.stack([q0[:, 1], -q0[:, 0]], axis=1)   # M10 - M01 against Q's top rows
        return PairStart(poses, pi, pj, g_pair, g_rel, mu, bool(np.all(g_pair > 0)), f, m, turn,
                         q0, s0, c0, q0_sin)

    def stop(self) -> None:
        """Prove nothing until the next :meth:`start`."""
        self._at = None

    def clear_pairs(self, poses: np.ndarray) -> np.ndarray:
        """(M, S) bool: each moving pair of the last start provably outside
        the clearance at each of the poses (S, P, 4, 4) (the condition of
        :meth:`clear`, pair by pair)."""
        poses = np.asarray(poses, float)
        if not len(self._at.pi):
            return np.ones((0, len(poses)), bool)
        return self._pair_ok(self.moves(poses).T, poses)

    def moves(self, poses: np.ndarray) -> np.ndarray:
        """dp (..., P): how far any point of each part moved since the start
        (poses (..., P, 4, 4))."""
        dpose = poses - self._at.poses
        d_rot, d_pos = dpose[..., :3, :3], dpose[..., :3, 3]
        fro = np.sqrt(np.einsum("...ij,...ij->...", d_rot, d_rot))
        dp = np.sqrt(np.einsum("...i,...i->...", d_pos, d_pos))
        dp += np.multiply(fro, self._rho, out=np.zeros_like(fro), where=fro > 0)   # plane turned: inf
        if self._boxed.any():
            turned = (fro > 0) & self._boxed
            if turned.any():
                at = np.nonzero(turned)
                dp[at] = np.minimum(dp[at], _corner_moves(d_rot[at], d_pos[at], self._corners[at[-1]]))
        return dp

    def _relative(self, poses: np.ndarray, f: np.ndarray,
                  m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Q (S, n, 3, 3), s (S, n, 3), corners (S, n, 8, 3)): the other
        part's pose and its box's corners in the frame part's frame, for
        pairs of frame parts ``f`` and other parts ``m`` (n,) at poses (S, P, 4, 4)."""
        pf, pm = poses[:, f], poses[:, m]
        rft = np.swapaxes(pf[..., :3, :3], -1, -2)
        q = rft @ pm[..., :3, :3]
        s = (rft @ (pm[..., :3, 3] - pf[..., :3, 3])[..., None])[..., 0]
        return q, s, self._corners[m][None] @ np.swapaxes(q, -1, -2) + s[..., None, :]

    def _relative_moves(self, poses: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """(n, S): the ``rel`` bound (class docstring) of pairs ``rows`` at poses (S, P, 4, 4)."""
        at = self._at
        m = at.m[rows]
        q, s, c = self._relative(poses, at.f[rows], m)
        q0 = at.q0[rows]
        turn = at.turn[rows]
        loose = np.flatnonzero(~self._boxed[m])
        if turn.any():
            # Rz(phi) nearest M = Q0 Q^T: cos and sin along (M00 + M11, M10 - M01)
            top = q[..., :2, :]
            cos = np.einsum("nak,snak->sn", q0[:, :2], top)
            sin = np.einsum("nak,snak->sn", at.q0_sin[rows], top)
            ln = np.hypot(cos, sin)
            use = turn[None] & (ln > 0)
            ln = np.where(use, ln, 1.0)
            cos = np.where(use, cos / ln, 1.0)[..., None, None]
            sin = np.where(use, sin / ln, 0.0)[..., None, None]
            c = _turned_z(c, cos, sin)
        d = c - at.c0[rows]
        out = np.sqrt(np.einsum("snki,snki->snk", d, d).max(axis=2))              # boxed: the corners'
        if len(loose):                                  # no box: the radius bound, not turned (sound too)
            dq = q[:, loose] - q0[loose]
            fro = np.sqrt(np.einsum("snij,snij->sn", dq, dq))
            ds = s[:, loose] - at.s0[rows[loose]]
            far = np.sqrt(np.einsum("sni,sni->sn", ds, ds))
            far += np.multiply(fro, self._rho[m[loose]], out=np.zeros_like(fro), where=fro > 0)
            out[:, loose] = far
        return out.T

    def _pair_ok(self, dp: np.ndarray, poses: np.ndarray) -> np.ndarray:
        """(n_pairs, S) the condition per pair and state, from the world
        moves dp (P, S) and the poses (S, P, 4, 4): the pairs the world
        moves do not prove apart are tested relative to each other, and
        those still failing by their boxes' separation at the state itself."""
        at = self._at
        ok = dp[at.pi] + dp[at.pj] < at.g_pair[:, None]
        rows = np.flatnonzero(~ok.all(axis=1))
        if len(rows) and self._group is not None:
            ok[rows] |= self._groups_apart(poses, rows)
            rows = rows[~ok[rows].all(axis=1)]
        if len(rows):
            ok[rows] |= self._relative_moves(poses, rows) < at.g_rel[rows, None]
            rows = rows[~ok[rows].all(axis=1) & self._known[at.pi[rows]] & self._known[at.pj[rows]]]
            if len(rows):
                ok[rows] |= self._separated(poses, rows)
        return ok

    def _groups_apart(self, poses: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """(n, S): pairs ``rows`` whose two groups' boxes (:class:`GroupBoxes`)
        are more than the clearance apart at poses (S, P, 4, 4) itself, by
        :meth:`_separated`'s margin: every part's box lies in its group's,
        so no two of their parts come within the clearance there. Each pair
        of groups is measured once."""
        if self._boxes_of is not self._at:      # the start's group boxes, made when first asked for
            self._boxes = group_boxes(self._group, self._at.poses, self._corners, self._boxed & ~self._plane)
            self._boxes_of = self._at
        gb = self._boxes
        i, j = self._at.pi[rows], self._at.pj[rows]
        ga, gc = gb.of[i], gb.of[j]
        out = np.zeros((len(rows), len(poses)), bool)
        use = np.flatnonzero(gb.inside[i] & gb.inside[j])
        if not len(use):
            return out
        n_g = len(gb.ref)
        key, inv = np.unique(ga[use] * n_g + gc[use], return_inverse=True)
        sep = _boxes_apart(gb.half, gb.mid, gb.ref, key // n_g, key % n_g, poses, self._at.mu, self.clearance)
        out[use] = sep[inv]
        return out

    def _separated(self, poses: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """(n, S): pairs ``rows`` (both parts boxed or planes) whose boxes'
        separation at poses (S, P, 4, 4) itself (:func:`box_bounds`) exceeds
        the clearance by the rounding margin: the part-part check's
        oriented-box test (the boxes grown by half the clearance each, no
        larger than these) rejects the pair there, so it has no record.
        The margin: the start's, plus 1e-9 of the boxes' extent from the
        origin (what the test's own rounding allowance grows with)."""
        i, j = self._at.pi[rows], self._at.pj[rows]
        return _boxes_apart(self._half, self._mid, np.arange(len(self._half)), i, j, poses, self._at.mu,
                            self.clearance, self._plane)

    def clear(self, dp: np.ndarray, poses: np.ndarray) -> np.ndarray:
        """The condition per state (S,) from the parts' moves dp (P, S)
        (:meth:`moves`) at poses (S, P, 4, 4)."""
        if not len(self._at.pi):
            return np.ones(dp.shape[1], bool)
        return self._pair_ok(dp, poses).all(axis=0)

    def clear_at(self, poses: np.ndarray) -> bool:
        """True when no moving part pair can be within the clearance (the
        part-pair condition of the package docstring alone): the part-part
        check's answer is then its same-body records only, even on a step
        whose cable checks run in full."""
        if not self.ok or len(poses) != len(self._at.poses):
            return False
        return not len(self._at.pi) or bool(self.clear(self.moves(poses)[:, None], np.asarray(poses)[None])[0])

    def failing_at(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The moving part pairs (i, j) whose bound fails at poses (every
        other pair is provably outside the clearance), or None when no pair
        is bounded (before a start, or the part count changed)."""
        at = self._at
        if not self.ok or len(poses) != len(at.poses):
            return None
        if not len(at.pi):
            return at.pi[:0], at.pj[:0]
        fail = ~self._pair_ok(self.moves(poses)[:, None], np.asarray(poses)[None])[:, 0]
        return at.pi[fail], at.pj[fail]
