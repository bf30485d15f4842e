"""The skip rule's bound on self and cable-cable pairs (the package docstring's second list).

After a full check, the gaps of cable pairs are kept per near element pair
(one cable, within ``2 BLOCK`` elements: also proven apart by the chord
bound at the state itself), per pair of body centres that candidates are
charged to, and per pair of blocks of ``BLOCK`` elements for everything
else (their boxes at the start, and at the state itself; or at the state
itself a separating axis between every two of their elements: two leads
side by side turning together stay apart along the line between them
while their oblique blocks' boxes overlap). Pairs whose
condition fails can be named (:meth:`CablePairGaps.failing`) and left to
the caller (:meth:`CablePairGaps.promote`). :meth:`CablePairGaps.clear`
tests many states at once.

Deliberately not here: cables against parts, part pairs, the run of states
(:class:`cablecheck.checker.advance.skip.Advancement`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from cablecheck.checker.advance.common import FAR_HORIZONS, Layout, Start, bracket, leading, row_norm3
from cablecheck.checker.cable import self_pair_window
from cablecheck.checker.closest import row_norm, segment_segment
from cablecheck.checker.interference.hits import CableCandidates


@dataclass(frozen=True, slots=True)
class NearPairs:
    """The near element pairs of one start (:meth:`CablePairGaps._near_pairs`)
    and their gaps; promoting a pair sets its gaps to inf in place.

    Attributes:
        e, f: (E,) the pairs' elements, ``e <= f < e + 2 BLOCK`` on one cable.
        index: ((N - 1) 2 BLOCK,) the pair of elements (e, e + k) at
            ``e 2 BLOCK + k``, -1 where there is none.
        turn: (E,) the turning below which the chord bound holds (-1: never).
        a, b: (4 E,) the four centre pairs (e or e + 1, f or f + 1) of each.
        g: (E,) the gaps (the horizon until :meth:`CablePairGaps.start`
            charges the candidates and takes the rounding margin off).
        g2: (E,) the squares of their positive parts (empty until then).
    """

    e: np.ndarray
    f: np.ndarray
    index: np.ndarray
    turn: np.ndarray
    a: np.ndarray
    b: np.ndarray
    g: np.ndarray
    g2: np.ndarray


@dataclass(frozen=True, slots=True)
class CentrePairs:
    """The pairs of body centres the candidates of one start are charged to
    (other than the near pairs'); promoting a pair sets its gaps to inf in place.

    Attributes:
        i, j: (M,) the centres.
        g: (M,) the least value minus the clearance of their candidates,
            capped at the horizon, less the rounding margin.
        g2: (M,) the squares of their positive parts.
    """

    i: np.ndarray
    j: np.ndarray
    g: np.ndarray
    g2: np.ndarray


@dataclass(frozen=True, slots=True)
class Blocks:
    """The blocks of one start, their groups and the group pairs to test
    (:meth:`CablePairGaps._start_blocks`, listed on first use).

    Attributes:
        start, last: (B,) first and last body centre of each block.
        nb: the number of blocks B.
        groups: (G,) the first block of each group.
        gi, gj: (Q,) the group pairs to test.
        g_grp, g_grp2: (Q,) their gaps (a lower bound of their block
            pairs'), less the rounding margin, and the squares of their
            positive parts.
        g_far: the far limit's gap (inf when every block pair is listed).
        horizon, far, mu: the start's horizon, ``FAR_HORIZONS`` horizons
            and rounding margin.
        rad: (B, 1) each block's share of a pair's distance (its largest
            radius, half the clearance and the margin), or None (no radii).
        radius: the k-d tree's search radius, or None (every pair listed).
        centre, lo, hi: (B, 3) the centre and bounds of each block's box
            of centres at the start (None without radii).
        r: (B,) each block's largest cable radius (None without radii).
        ok: every group pair's gap and the far limit's are positive.
    """

    start: np.ndarray
    last: np.ndarray
    nb: int
    groups: np.ndarray
    gi: np.ndarray
    gj: np.ndarray
    g_grp: np.ndarray
    g_grp2: np.ndarray
    g_far: float
    horizon: float
    far: float
    mu: float
    rad: np.ndarray | None
    radius: float | None
    centre: np.ndarray | None
    lo: np.ndarray | None
    hi: np.ndarray | None
    r: np.ndarray | None
    ok: bool


class CablePairGaps:
    """The cable-pair gaps of one start.

    Args:
        layout: the run's layout.
        start: the state of the full check.
    """

    BLOCK = 4
    """Elements per block of the far-pair bound."""

    GROUP = 8
    """Blocks per group: block pairs are first tested a group pair at a time."""

    FAR_HORIZONS = FAR_HORIZONS

    def __init__(self, layout: Layout, start: Start):
        # the names the bound's arithmetic reads
        self._pts, self._s_c = start.pts, start.s_c
        self._rad, self._offsets, self._cable, self._valid = layout.rad, layout.offsets, layout.cable, layout.valid
        self.clearance, self.stretch = layout.clearance, layout.stretch
        # what :meth:`start` computes
        self._near: NearPairs | None = None                 # None: no near pairs (no radii)
        self._cc: CentrePairs | None = None
        self._blk_args: tuple[float, float] | None = None   # (horizon, mu) the blocks are listed with
        self._blocks: Blocks | None = None                  # listed on first use (:meth:`_ensure_blocks`)
        self._blk_done = np.zeros(0, np.int64)              # promoted block pairs, a * blocks + b
        self._g_min_nb = np.inf                             # the least near and centre-pair gap

    # the blocks' arrays by their former names (tests read them)
    @property
    def _blk_start(self) -> np.ndarray:
        """(B,) first body centre of each block."""
        return self._blocks.start

    @property
    def _blk_last(self) -> np.ndarray:
        """(B,) last body centre of each block."""
        return self._blocks.last

    @property
    def _blk_rad(self) -> np.ndarray | None:
        """(B, 1) each block's share of a pair's distance, or None."""
        return self._blocks.rad

    @property
    def _g_far(self) -> float:
        """The far limit's gap."""
        return self._blocks.g_far

    def ok_at_start(self) -> bool:
        """True when every centre-pair gap is positive (the blocks' on first use)."""
        return bool(np.all(self._cc.g > 0))

    def start(self, cand: CableCandidates, horizon: float, mu: float,
                           active: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Gaps of cable pairs per pair of body centres (candidates) and per
        pair of blocks (everything else): the package docstring's second list.
        ``active``: (P, 2) cable pairs (a <= b) the caller evaluates itself
        near their candidates; returns the (centre, centre) pairs left to it."""
        n = len(self._pts)
        ca, sa, cb, sb, value = (np.asarray(x) for x in cand)
        ca, cb = ca.astype(np.int64), cb.astype(np.int64)
        ii = jj = np.zeros(0, np.int64)
        gg = np.zeros(0)
        near = self._near_pairs(horizon, mu) if self._rad is not None and n > 1 else None
        pairs = np.zeros((0, 2), np.int64) if active is None else np.asarray(active, np.int64).reshape(-1, 2)
        cable_active = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        member = np.zeros(0, np.int64)
        if len(value) and n:
            lo_a, hi_a = self._bracket(ca, sa)
            lo_b, hi_b = self._bracket(cb, sb)
            n_c = len(self._offsets) - 1
            if len(pairs):
                # the centres of every candidate of an active pair, on either side
                pid = np.full(n_c * n_c, -1, np.int64)
                pid[pairs[:, 0] * n_c + pairs[:, 1]] = np.arange(len(pairs))
                cand_pid = pid[np.minimum(ca, cb) * n_c + np.maximum(ca, cb)]
                on = cand_pid >= 0
                k = np.arange(3)
                rows = np.concatenate([(lo[:, None] + k[None, :])[on] for lo in (lo_a, lo_b)])
                ok = rows <= np.concatenate([np.broadcast_to(hi[:, None], (len(hi), 3))[on] for hi in (hi_a, hi_b)])
                owner = np.concatenate([np.broadcast_to(cand_pid[:, None], (len(ca), 3))[on]] * 2)
                member = np.unique(owner[ok] * n + rows[ok])
            if near is not None:                 # near pairs carry their own candidates
                far_c = ~self._charge_near(near, ca, lo_a, hi_a, cb, lo_b, hi_b, value)
                lo_a, hi_a, lo_b, hi_b, value = lo_a[far_c], hi_a[far_c], lo_b[far_c], hi_b[far_c], value[far_c]
            # every centre pair of the two brackets (at most 3 x 3 each)
            k = np.arange(3)
            i = lo_a[:, None, None] + k[None, :, None]
            j = lo_b[:, None, None] + k[None, None, :]
            ok = (i <= hi_a[:, None, None]) & (j <= hi_b[:, None, None])
            i, j = np.broadcast_to(i, ok.shape)[ok], np.broadcast_to(j, ok.shape)[ok]
            v = np.broadcast_to(value[:, None, None], ok.shape)[ok]
            key = np.minimum(i, j) * n + np.maximum(i, j)
            o = np.argsort(key)                  # (the least per key: any order of equal keys)
            key, v = key[o], v[o]
            first = np.r_[len(key) > 0, key[1:] != key[:-1]][:len(key)]
            start = np.nonzero(first)[0]
            gg = np.minimum.reduceat(v, start) if len(start) else np.zeros(0)
            key = key[first]
            ii, jj = key // n, key % n
            same = ii != jj                      # a centre against itself: no relative motion
            ii, jj, gg = ii[same], jj[same], gg[same]
            if len(member):
                # centre pairs both of whose centres are evaluated by the caller
                c_i, c_j = self._cable[ii], self._cable[jj]
                p_ij = pid[np.minimum(c_i, c_j) * n_c + np.maximum(c_i, c_j)]
                both = (p_ij >= 0) & np.isin(p_ij * n + ii, member) & np.isin(p_ij * n + jj, member)
                cable_active = (ii[both], jj[both])
                ii, jj, gg = ii[~both], jj[~both], gg[~both]
        if near is not None:
            g_near = np.minimum(near.g, horizon) - mu
            near = replace(near, g=g_near, g2=np.where(g_near > 0, g_near, 0.0) ** 2)
        g_cc = np.minimum(gg, horizon) - mu
        self._near = near
        self._cc = CentrePairs(ii, jj, g_cc, np.where(g_cc > 0, g_cc, 0.0) ** 2)
        # the block pairs are listed on first use (:meth:`_ensure_blocks`):
        # a run whose states fail the cheaper conditions never needs them
        self._blk_args = (horizon, mu)
        self._blocks = None
        self._blk_done = np.zeros(0, np.int64)
        self._g_min_nb = self._least_gap()
        return cable_active

    def _least_gap(self) -> float:
        """The least gap of the near pairs and the centre pairs."""
        return min(float(self._cc.g.min(initial=np.inf)),
                   float(self._near.g.min(initial=np.inf)) if self._near is not None else np.inf)

    def _bracket(self, cab: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:func:`~cablecheck.checker.advance.common.bracket` at the start's arc lengths."""
        return bracket(self._s_c, self._cable, self._offsets, cab, s)

    def _ensure_blocks(self) -> bool:
        """List the block pairs of the last start (once); True when their
        gaps are all positive."""
        if self._blocks is None:
            self._blocks = self._start_blocks(*self._blk_args)
        return self._blocks.ok

    def _start_blocks(self, horizon: float, mu: float) -> Blocks:
        """Blocks, their groups and the group pairs to test (the module
        docstring's block condition).

        Groups of GROUP consecutive blocks: a group pair's box of relative
        displacements holds each of its block pairs' boxes, so a group pair
        whose box is below a lower bound of its block pairs' gaps clears them
        all; the block pairs of the others are formed when tested
        (:meth:`_block_pairs`), with their own gaps. The lower bound: the
        distance between the groups' boxes (holding their blocks' boxes)
        less the groups' largest radii, put through the blocks' rule
        (``max(H, min(d, far))``, which grows with d). Block pairs listed (one by one) are those whose
        centres lie within the search radius of the k-d tree (``2 max reach
        + clearance + far``) when there are more than 64 blocks, else all;
        the group pairs kept are those that may hold one."""
        n = len(self._pts)
        # blocks of BLOCK elements of one cable: centres [s, s + K] (overlapping
        # by one), the last of each cable shorter (a block across two cables
        # would reach from one's end to the other's start)
        kb = self.BLOCK
        first, count = self._offsets[:-1], np.diff(self._offsets)
        per = np.where(count > 0, -(-np.maximum(count - 1, 1) // kb), 0)
        blk_start = np.repeat(first, per) + kb * (np.arange(int(per.sum())) - np.repeat(np.cumsum(per) - per, per))
        blk_last = np.minimum(blk_start + kb, np.repeat(first + count - 1, per))
        nb = len(blk_start)
        far = self.FAR_HORIZONS * horizon
        groups = np.arange(0, nb, self.GROUP)
        ng = len(groups)
        z, e = np.zeros(0, np.int64), np.zeros(0)
        if nb == 0:
            return Blocks(blk_start, blk_last, nb, groups, z, z, e, e, np.inf, horizon, far, mu,
                          None, None, None, None, None, None, True)
        lo = np.minimum.reduceat(self._pts, blk_start)
        hi = np.maximum.reduceat(self._pts, blk_start)
        lo = np.minimum(lo, self._pts[blk_last])
        hi = np.maximum(hi, self._pts[blk_last])
        centre = 0.5 * (lo + hi)
        big = 0.5 * row_norm(hi - lo)               # encloses the block's centres, so its elements
        group = np.arange(nb) // self.GROUP
        blk_radius = None                           # the k-d tree's search radius (None: every pair)
        blk_rad = None
        g_far = np.inf
        if self._rad is not None:
            rad = np.maximum(np.maximum.reduceat(self._rad, blk_start), self._rad[blk_last])
            blk_rad = rad[:, None] + self.clearance / 2 + mu      # each block's share of a pair's
            reach = big + rad
            g_lo = np.minimum.reduceat(lo, groups)
            g_hi = np.maximum.reduceat(hi, groups)
            g_rad = np.maximum.reduceat(rad, groups)
            if nb <= 64:                                # few blocks: every pair
                gi, gj = np.triu_indices(ng)
            else:
                from scipy.spatial import (
                    cKDTree,  # a fifth of a second to import: loaded where a tree is built
                )

                radius = 2.0 * float(reach.max()) + self.clearance + far
                blk_radius = radius
                tree = cKDTree(centre)
                listed = int(tree.count_neighbors(tree, radius)) == nb * nb
                g_far = (np.inf if listed else far) - mu
                g_centre = 0.5 * (g_lo + g_hi)
                off = row_norm(centre - g_centre[group])
                pairs = cKDTree(g_centre).query_pairs(radius + 2.0 * float(off.max()) + 1e-9 * (1.0 + radius),
                                                      output_type="ndarray")
                gi = np.concatenate([np.arange(ng), pairs[:, 0]]).astype(np.int64)
                gj = np.concatenate([np.arange(ng), pairs[:, 1]]).astype(np.int64)
            dist = _box_distance(g_lo[gi], g_hi[gi], g_lo[gj], g_hi[gj]) - g_rad[gi] - g_rad[gj] - self.clearance
            g_grp = np.maximum(horizon, np.minimum(dist, far))
        else:
            gi, gj = np.triu_indices(ng)
            g_grp = np.full(len(gi), horizon)
        g_grp = g_grp - mu
        boxes = (centre, lo, hi, rad) if self._rad is not None else (None, None, None, None)
        return Blocks(blk_start, blk_last, nb, groups, gi.astype(np.int64), gj.astype(np.int64), g_grp,
                      np.where(g_grp > 0, g_grp, 0.0) ** 2, g_far, horizon, far, mu, blk_rad, blk_radius,
                      *boxes, bool(np.all(g_grp > 0)) and g_far > 0)

    def _block_pairs(self, gp: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The block pairs (a <= b) of group pairs gp and their squared gaps
        (the package docstring's ``max(H, L[A, B])``, less the rounding
        margin): those listed, other than a block with itself or the next on
        one cable (their element pairs are near pairs)."""
        blk = self._blocks
        g, nb = self.GROUP, blk.nb
        k = np.arange(g * g)
        bi = (blk.gi[gp] * g)[:, None] + (k // g)[None, :]
        bj = (blk.gj[gp] * g)[:, None] + (k % g)[None, :]
        keep = (bi <= bj) & (bj < nb)
        bi, bj = bi[keep], bj[keep]
        end = blk.last[bj]
        near = (bj - bi <= 1) & (self._cable[blk.start[bi]] == self._cable[end])
        bi, bj = bi[~near], bj[~near]
        if len(self._blk_done):
            keep = ~np.isin(bi * nb + bj, self._blk_done)
            bi, bj = bi[keep], bj[keep]
        if blk.rad is None:
            gap = np.full(len(bi), blk.horizon)
        else:
            if blk.radius is not None:
                c = blk.centre
                on = row_norm(c[bi] - c[bj]) <= blk.radius
                bi, bj = bi[on], bj[on]
            dist = (_box_distance(blk.lo[bi], blk.hi[bi], blk.lo[bj], blk.hi[bj])
                    - blk.r[bi] - blk.r[bj] - self.clearance)
            gap = np.maximum(blk.horizon, np.minimum(dist, blk.far))
        gap = gap - blk.mu
        return bi, bj, np.where(gap > 0, gap, 0.0) ** 2

    def _near_pairs(self, horizon: float, mu: float) -> NearPairs:
        """Near element pairs (e, f), e <= f <= e + 2 BLOCK - 1 on one cable,
        their arc-length window, the distance their places must exceed, and
        their gaps (the horizon until candidates are charged)."""
        n, span = len(self._pts), 2 * self.BLOCK
        e = np.repeat(np.arange(n - 1), span)
        f = e + np.tile(np.arange(span), n - 1)
        keep = f < n - 1
        e, f = e[keep], f[keep]
        keep = self._valid[e] & self._valid[f] & (self._cable[e] == self._cable[f])
        ne, nf = e[keep], f[keep]
        index = np.full((n - 1) * span, -1, np.int64)
        index[ne * span + (nf - ne)] = np.arange(len(ne))
        r = self._rad[ne]
        # the chord bound as a turning limit: places checked are at least
        # max(w, S) apart along the cable, with S the arc length from centre
        # e + 1 to f, which can shrink by at most ``stretch`` while skipping
        arc = self._s_c
        window = self_pair_window(r, self.clearance) - mu
        ds = np.maximum(window, arc[nf] - arc[ne + 1] - self.stretch - mu)
        ratio = (2.0 * r + self.clearance + mu) / ds
        turn = np.where(ratio < 1.0, 2.0 * np.arccos(np.minimum(ratio, 1.0)) - 1e-9, -1.0)
        # the four centre pairs (e or e + 1, f or f + 1) of each near pair
        a = np.concatenate([ne, ne, ne + 1, ne + 1])
        b = np.concatenate([nf, nf + 1, nf, nf + 1])
        return NearPairs(ne, nf, index, turn, a, b, np.full(len(ne), float(horizon)), np.zeros(0))

    def _charge_near(self, pairs: NearPairs, ca, lo_a, hi_a, cb, lo_b, hi_b, value) -> np.ndarray:
        """Charge the candidates whose places lie on near element pairs to
        those pairs' gaps (``pairs.g``, in place); returns which candidates
        were (n,) bool."""
        span = 2 * self.BLOCK
        first, last = self._offsets[ca], self._offsets[ca + 1] - 2          # the cable's elements
        ea0, ea1 = np.clip(lo_a, first, last), np.clip(np.maximum(hi_a - 1, lo_a), first, last)
        first_b, last_b = self._offsets[cb], self._offsets[cb + 1] - 2
        eb0, eb1 = np.clip(lo_b, first_b, last_b), np.clip(np.maximum(hi_b - 1, lo_b), first_b, last_b)
        near = (ca == cb) & (np.maximum(ea1, eb1) - np.minimum(ea0, eb0) < span)
        if near.any():
            # most places lie inside one element on either side: those pairs
            # directly, the few at a centre (two elements) expanded
            one = near & (ea0 == ea1) & (eb0 == eb1)
            many = near & ~one
            k = np.arange(3)
            ea = ea0[many][:, None, None] + k[None, :, None]
            eb = eb0[many][:, None, None] + k[None, None, :]
            ok = (ea <= ea1[many][:, None, None]) & (eb <= eb1[many][:, None, None])
            ea = np.concatenate([ea0[one], np.broadcast_to(ea, ok.shape)[ok]])
            eb = np.concatenate([eb0[one], np.broadcast_to(eb, ok.shape)[ok]])
            v = np.concatenate([value[one], np.broadcast_to(value[many][:, None, None], ok.shape)[ok]])
            e, f = np.minimum(ea, eb), np.maximum(ea, eb)
            np.minimum.at(pairs.g, pairs.index[e * span + (f - e)], v)
        return near

    def _near_clear(self, move: np.ndarray, d: np.ndarray, seg: np.ndarray) -> np.ndarray:
        """Near element pairs per state (S,): each either provably apart by
        the chord bound at this state (module docstring) or within its gap
        of relative motion since the start. d (N - 1, 3, S) the elements,
        seg (N - 1, S) their lengths."""
        return ~self._near_bad(move, d, seg).any(axis=0)

    def _near_bad(self, move: np.ndarray, d: np.ndarray, seg: np.ndarray) -> np.ndarray:
        """(E, S): near element pair e fails at state s (:meth:`_near_clear`)."""
        s = move.shape[2]
        # turning at each centre, rounded up (arccos loses ~1e-8 near 0); a
        # zero-length element turns by pi (proves nothing)
        den = seg[:-1] * seg[1:]
        cos = np.divide(np.einsum("eis,eis->es", d[:-1], d[1:]), den, out=np.full(den.shape, -1.0),
                        where=den > 0)
        turn = np.zeros((len(move), s))
        turn[1:-1] = np.arccos(np.clip(cos, -1.0, 1.0)) + 1e-6
        turn = np.cumsum(turn, axis=0)
        near = self._near
        bad = turn[near.f] - turn[near.e] >= near.turn[:, None]     # (E, S)
        rows = np.nonzero(bad.any(axis=1))[0]
        if len(rows):                            # the relative motion only where the chord fails
            m = len(near.e)
            a = (near.a.reshape(4, m)[:, rows]).ravel()
            b = (near.b.reshape(4, m)[:, rows]).ravel()
            dd = move[a] - move[b]
            rel2 = np.einsum("pis,pis->ps", dd, dd).reshape(4, len(rows), s).max(axis=0)
            bad[rows] &= rel2 >= near.g2[rows, None]
        return bad

    def clear(self, x: np.ndarray, move: np.ndarray, dcc: np.ndarray, diag: np.ndarray,
                           d: np.ndarray, seg: np.ndarray) -> np.ndarray:
        """The cable-pair conditions of the package docstring (second list),
        per state (S,) of ``move`` (N, 3, S): ``dcc`` (S,) bounds every
        |d_a - d_b|, ``diag`` (S,) (the bounding box's diagonal) also every
        block pair's box bound; x (N, 3, S) the centres, d and seg the
        elements and their lengths. Exact for the leading run of states that
        pass (all :meth:`clear_run` uses); after the first state that fails,
        every state is reported failing unevaluated.

        Cheapest first: near pairs and candidate centre pairs (skipped for
        states whose whole spread is below all their gaps), then the far
        limit and the block pairs, listed on first use. Block pairs are
        tested a group pair at a time first (a group's box of displacements
        holds its blocks'; group pairs whose least gap exceeds the spread
        pass unlooked), one by one only in group pairs that do not pass
        whole, the boxes at this state only for block pairs failing the
        box, the axes only for those still failing, and over runs of
        states of doubling length."""
        n_s = len(dcc)
        ok = np.ones(n_s, bool)
        easy = diag < self._g_min_nb               # every relative motion is below every such gap
        if not easy.all():
            pair_ok = self._near_clear(move, d, seg) if self._near is not None else np.ones(n_s, bool)
            pair_ok |= easy
            m = leading(pair_ok)
            cc = self._cc
            if len(cc.i) and m:
                dd = move[cc.i][:, :, :m] - move[cc.j][:, :, :m]
                pair_ok[:m] &= (np.einsum("mis,mis->ms", dd, dd) < cc.g2[:, None]).all(axis=0) | easy[:m]
            ok &= pair_ok
        n = leading(ok)
        ok[n:] = False
        if not n:
            return ok
        if not self._ensure_blocks():
            return np.zeros(n_s, bool)
        ok[:n] &= dcc[:n] < self._blocks.g_far
        n = leading(ok)
        ok[n:] = False
        if len(self._blocks.gi) and n:
            # states in runs of doubling length, each only once the ones
            # before all passed: a failure near the start costs a state or two
            a, b = 0, 1
            while a < n:
                b = min(b, n)
                blk = self._blocks_clear(x[:, :, a:b], move[:, :, a:b], float(diag[a:b].max()))
                if not blk.all():
                    ok[a + leading(blk):] = False
                    break
                a, b = b, 2 * b + 1
        return ok

    def failing(self, x: np.ndarray, move: np.ndarray, dcc: np.ndarray, diag: np.ndarray,
                d: np.ndarray, seg: np.ndarray) -> tuple[tuple, int]:
        """The cable-pair conditions (as :meth:`clear`, same arguments) per
        pair: ((near element pairs, centre pairs, block pairs), stop). Each
        of the three is (index, first failing state) arrays: near pairs
        index :class:`NearPairs`, centre pairs :class:`CentrePairs`, block pairs
        (a, b, first). ``stop``: the first state at which a condition fails
        that names no pair (the far limit, gaps not all positive; S when
        none). A state passes :meth:`clear` exactly when no pair fails at
        it and it is before ``stop``."""
        n_s = len(dcc)
        z = np.zeros(0, np.int64)
        near = cc = (z, z)
        easy = diag < self._g_min_nb
        if not easy.all():
            if self._near is not None:
                bad = self._near_bad(move, d, seg) & ~easy
                rows = np.nonzero(bad.any(axis=1))[0]
                near = (rows, np.argmax(bad[rows], axis=1))
            c_p = self._cc
            if len(c_p.i):
                dd = move[c_p.i] - move[c_p.j]
                bad = (np.einsum("mis,mis->ms", dd, dd) >= c_p.g2[:, None]) & ~easy
                rows = np.nonzero(bad.any(axis=1))[0]
                cc = (rows, np.argmax(bad[rows], axis=1))
        if not self._ensure_blocks():
            return (near, cc, (z, z, z)), 0
        far = dcc >= self._blocks.g_far
        stop = int(np.argmax(far)) if far.any() else n_s
        blocks = (z, z, z)
        if len(self._blocks.gi) and stop:
            bi, bj, bad = self._block_fails(x[:, :, :stop], move[:, :, :stop], float(diag[:stop].max()))
            rows = np.nonzero(bad.any(axis=1))[0]
            blocks = (bi[rows], bj[rows], np.argmax(bad[rows], axis=1))
        return (near, cc, blocks), stop

    def centre_pairs(self, near: np.ndarray, cc: np.ndarray, a: np.ndarray,
                     b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The pairs of body centres (i <= j, unique) whose places make up
        near element pairs ``near``, centre pairs ``cc`` and block pairs (a,
        b): evaluating them evaluates every pair of places the conditions
        of those pairs bound."""
        z = np.zeros(0, np.int64)
        ne, nf = (z, z) if self._near is None else (self._near.e, self._near.f)
        i = [np.repeat(ne[near], 4) + np.tile([0, 0, 1, 1], len(near)),
             self._cc.i[cc]]
        j = [np.repeat(nf[near], 4) + np.tile([0, 1, 0, 1], len(near)),
             self._cc.j[cc]]
        if len(a):
            blk = self._blocks
            k = np.arange(self.BLOCK + 1)
            ia = (blk.start[a][:, None, None] + k[:, None]) + 0 * k[None, None, :]
            jb = (blk.start[b][:, None, None] + k[None, None, :]) + 0 * k[:, None]
            ok = (ia <= blk.last[a][:, None, None]) & (jb <= blk.last[b][:, None, None])
            i.append(ia[ok])
            j.append(jb[ok])
        i, j = np.concatenate(i).astype(np.int64), np.concatenate(j).astype(np.int64)
        n = len(self._pts)
        key = np.unique(np.minimum(i, j) * n + np.maximum(i, j))
        return key // n, key % n

    def promote(self, near: np.ndarray, cc: np.ndarray, a: np.ndarray, b: np.ndarray) -> None:
        """Leave near element pairs, centre pairs and block pairs out of
        the bound until the next start (the caller evaluates their centre
        pairs, :meth:`centre_pairs`, at every state)."""
        if len(near):
            self._near.g[near] = np.inf
            self._near.g2[near] = np.inf
        if len(cc):
            self._cc.g[cc] = np.inf
            self._cc.g2[cc] = np.inf
        if len(a):
            self._blk_done = np.union1d(self._blk_done, a * self._blocks.nb + b)
        if len(near) or len(cc):
            self._g_min_nb = self._least_gap()

    def _blocks_clear(self, x: np.ndarray, move: np.ndarray, diag: float) -> np.ndarray:
        """The block-pair condition per state (S,) of x and move (N, 3, S);
        ``diag`` bounds every block pair's box (the largest diagonal)."""
        return ~self._block_fails(x, move, diag)[2].any(axis=0)

    def _block_fails(self, x: np.ndarray, move: np.ndarray,
                     diag: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The block pairs (a, b) tested one by one and whether each fails
        at each state ((M, S) bool); the others pass (:meth:`_blocks_clear`)."""
        s = x.shape[2]
        z = np.zeros(0, np.int64)
        none = (z, z, np.zeros((0, s), bool))
        blk = self._blocks
        # group pairs whose least gap exceeds every box pass whole
        cand = np.nonzero(blk.g_grp <= diag)[0]
        if not len(cand):
            return none
        box = self._block_boxes(move)
        glo = np.minimum.reduceat(box[0], blk.groups, axis=0)
        ghi = np.maximum.reduceat(box[1], blk.groups, axis=0)
        gi, gj = blk.gi[cand], blk.gj[cand]
        rel = np.maximum(np.abs(ghi[gi] - glo[gj]), np.abs(glo[gi] - ghi[gj]))
        grp_ok = np.einsum("pis,pis->ps", rel, rel) < blk.g_grp2[cand, None]
        fail = cand[~grp_ok.all(axis=1)]
        if not len(fail):
            return none
        bi, bj, g2 = self._block_pairs(fail)                            # their block pairs
        rel = np.maximum(np.abs(box[1][bi] - box[0][bj]), np.abs(box[0][bi] - box[1][bj]))
        blk_ok = np.einsum("pis,pis->ps", rel, rel) < g2[:, None]
        if blk.rad is not None:
            bad = np.nonzero(~blk_ok.all(axis=1))[0]
            if len(bad):
                # or apart now: the blocks' boxes of centres, at this state
                lo, hi = self._block_boxes(x)
                a, b = bi[bad], bj[bad]
                sep = np.maximum(np.maximum(lo[b] - hi[a], lo[a] - hi[b]), 0.0)
                blk_ok[bad] |= row_norm3(sep) > blk.rad[a] + blk.rad[b]
                # or apart now by a separating axis between every two of
                # their elements, at the states the boxes leave failing
                r, at = np.nonzero(~blk_ok[bad])
                if len(r):
                    a, b = bi[bad[r]], bj[bad[r]]
                    need = (blk.rad[a] + blk.rad[b])[:, 0]
                    blk_ok[bad[r], at] = self._axes_gap(x, a, b, at, need) > need
        return bi, bj, ~blk_ok

    def _axes_gap(self, x: np.ndarray, a: np.ndarray, b: np.ndarray, at: np.ndarray,
                  enough: np.ndarray | None = None) -> np.ndarray:
        """(M,): a lower bound on the distance between any place of block
        a and any of block b (M,) at state ``at`` (M,) of x (N, 3, S): for
        every two of their elements, the larger of the gap of their
        midpoints' spheres (half an element's length holds its points) and
        the gap of their projections on the unit vector between their
        closest points (package docstring, *axes*); -inf for a block
        without elements. ``enough`` (M,): element pairs whose spheres are
        farther apart than that skip the axes (the spheres' gap is bound
        enough)."""
        blk = self._blocks
        k = np.arange(self.BLOCK)
        ea = blk.start[a][:, None] + k                                           # (M, K) elements
        eb = blk.start[b][:, None] + k
        ok = (ea < blk.last[a][:, None])[:, :, None] & (eb < blk.last[b][:, None])[:, None, :]
        m, i, j = np.nonzero(ok)                                                 # m ascending
        out = np.full(len(a), -np.inf)
        if not len(m):
            return out
        e, f, s = ea[m, i], eb[m, j], np.asarray(at, np.int64)[m]
        p0, p1, q0, q1 = x[e, :, s], x[e + 1, :, s], x[f, :, s], x[f + 1, :, s]   # (P, 3) each
        gap = row_norm(0.5 * ((q0 + q1) - (p0 + p1))) - 0.5 * (row_norm(p1 - p0) + row_norm(q1 - q0))
        axes = np.flatnonzero(gap <= enough[m]) if enough is not None else np.arange(len(m))
        if len(axes):
            p0, p1, q0, q1 = p0[axes], p1[axes], q0[axes], q1[axes]
            _, _, _, cp, cq = segment_segment(p0, p1, q0, q1)
            v = cq - cp
            length = row_norm(v)
            n = v / np.where(length > 0.0, length, 1.0)[:, None]                # 0 where they touch: gap 0
            proj = (np.minimum(np.einsum("ij,ij->i", n, q0), np.einsum("ij,ij->i", n, q1))
                    - np.maximum(np.einsum("ij,ij->i", n, p0), np.einsum("ij,ij->i", n, p1)))
            gap[axes] = np.maximum(gap[axes], proj)
        first = np.flatnonzero(np.r_[True, m[1:] != m[:-1]])
        out[m[first]] = np.minimum.reduceat(gap, first)
        return out

    def _block_boxes(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Componentwise least and largest of v (N, 3, S) over each block's
        centres: ((B, 3, S), (B, 3, S))."""
        blk = self._blocks
        last = v[blk.last]
        return (np.minimum(np.minimum.reduceat(v, blk.start, axis=0), last),
                np.maximum(np.maximum.reduceat(v, blk.start, axis=0), last))


def _box_distance(lo_a: np.ndarray, hi_a: np.ndarray, lo_b: np.ndarray, hi_b: np.ndarray) -> np.ndarray:
    """Distance between axis-aligned boxes, row by row ((M, 3) corners): 0
    where they overlap."""
    sep = np.maximum(np.maximum(lo_b - hi_a, lo_a - hi_b), 0.0)
    return row_norm(sep)
