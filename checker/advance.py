"""Conservative advancement: steps on which no pair can have come within the clearance.

After a full check at step k0 the checker knows, up to a horizon H, how far
every pair stays from the clearance (:attr:`checker.interference.Checker.gaps`,
its ``part_candidates`` and ``cable_candidates``, and :func:`part_pair_bounds`). On a later step k, with

- ``d_i``: the displacement of cable body centre i since k0, ``dq_i = |d_i|``,
- ``spread``: the diagonal of the bounding box of all ``d_i`` (at least
  ``|d_a - d_b|`` for any two centres; ``min(spread, 2 max dq)`` is used),
- ``u_i^k``: centre i in part k's own frame, ``R_k^T (x_i - t_k)``, and
  ``rel[i, k] = |u_i^k(k) - u_i^k(k0)|`` its displacement relative to part k,
- ``dp[k]``: a bound on how far any point of part k moved since k0, its
  translation plus ``||R - R0||_F`` times the part's bounding radius about
  its frame's origin (a plane that rotated: unbounded),
- ``g[i, k]``: centre i's gap to part k (inf when (i, k) is *active*: the
  caller evaluates every discrete point of the elements next to i against
  part k directly at every step, as the run does for places inside or
  near the clearance at k0): the smallest, over the elements
  next to centre i, of the value minus the clearance of part k's candidates
  on the element, or where there is none the larger of H and the element's
  floor ``F[e, k]``: at k0, the distance in part k's frame between the
  element's bounding box and the part's box, minus the cable radius and the
  clearance (a lower bound on every value of the element against part k),

no pair can have come within the clearance while

- self and cable-cable, either ``spread < gap_cable`` (the least gap over
  all cable pairs), or, with the checker's cable candidates, all of

  - for every near element pair (e, f) (one cable, ``e <= f < e + 2
    BLOCK``), either the chord bound holds at step k: ``T < pi`` and
    ``max(w, S) cos(T / 2) > 2 r + clearance``, with ``T`` the cable's
    total turning at the centres e + 1 .. f (the sum of the angles between
    consecutive elements) at step k, ``S`` the arc length from centre e + 1
    to centre f at k0 minus ``stretch`` (the arc length at k is no less
    under the last condition), ``w = pi r + clearance`` the self-exclusion window
    (:func:`checker.cable.self_pair_excluded`) and r the cable's radius; or
    the largest ``|d_a - d_b|`` over a in {e, e + 1} and b in {f, f + 1} is
    below the pair's gap: the least value minus the clearance of the
    candidates with both places on the pair (H when there is none, capped
    at H),
  - ``|d_i - d_j| < g[i, j]`` for every pair of centres (i, j) such that a
    candidate pair that is no near pair's has one place on an element next
    to i and the other on an element next to j; ``g[i, j]`` the least such
    candidate's value minus the clearance,
  - for every pair of blocks A, B of ``BLOCK`` consecutive elements
    (centres ``b K .. b K + K``) other than a block with itself or the
    next on one cable (their element pairs are all near pairs), either
    ``box(A, B) < max(H, L[A, B])``, where ``box(A, B)`` is the norm of
    the componentwise largest ``|d_a - d_b|`` over the two blocks'
    bounding boxes of displacements, and ``L[A, B]`` the distance at k0
    between spheres enclosing the blocks' centres, minus the largest radii
    of the two blocks and the clearance (capped at ``FAR_HORIZONS * H``);
    or the same distance at step k itself is above 0,
  - ``min(spread, 2 max dq) < FAR_HORIZONS * H`` when some block pairs are
    farther apart than that and left unlisted,
- ``dq_i < g[i, k]`` for every part k that did not move, and
  ``min(rel[i, k], dq_i + dp[k]) < g[i, k]`` for every part k that moved
  (cable-structure, keep-out),
- ``dp[i] + dp[j] < bound[i, j] - clearance`` for every part pair that can
  move relative to the other (part-part, keep-out between parts), except
  the pairs the caller leaves out of the bound and checks itself at every
  step (*active* part pairs, within the clearance at k0),
- every cable element splits into the same number of discrete points as at
  k0, and the cables' element lengths changed by at most ``stretch`` in
  total (summed over elements).

Proof sketch. With the same number of pieces per element, every discrete
point (and every element midpoint, and every point of a piece) is the same
convex combination of the same two body centres as at k0, in the world and
in any part's frame alike (the maps are affine); so its displacement is the
same combination of the two centres' displacements: at most the larger of
their ``dq`` (or ``rel``), and the difference of two such displacements lies
within the bounding box's diagonal. Cable pairs, per place: two places on
elements (i, i + 1) and (j, j + 1) moved relative to each other by a convex combination of ``d_i - d_j``,
``d_i - d_(j+1)``, ``d_(i+1) - d_j`` and ``d_(i+1) - d_(j+1)`` (the
product of the two combinations' weights), so by at most the largest of
their norms (a common translation cancels); each such centre pair carries
the gap of every candidate charged to it (each side charged as the part
candidates are, below). A checked pair of places that was no candidate was
at least H past the clearance at k0 (or deeper than ``stretch`` inside its
exclusion window, where it stays), and at least ``L[A, B]`` past it for
blocks holding its elements (each place is in the convex hull of its
block's centres, inside the enclosing sphere); its relative displacement
lies in the difference of the two blocks' boxes of displacements, whose
largest point is ``box(A, B)`` away from the origin, and below
``min(spread, 2 max dq)`` for any two places. A block joining two cables
only holds more centres: its box and sphere only grow. A point of a rigid
part moved by at most
``dp``. Every value checked is a distance between two cable points, or a
point's distance to a rigid solid, minus fixed radii: a 1-Lipschitz function
of the places, so it dropped by at most ``|d_a - d_b|`` (cable pairs), and
by at most the point's displacement in the part's own frame, or the point's
plus the part's displacement in the world (cable and part; a point outside a
solid with distance above the clearance stays outside, where the signed
distance is the distance). Two conditions look at step k alone (the chord's ``S`` aside). Spheres:
every place of a block lies in the convex hull of its centres, inside the
sphere about their bounding box. Chord: let two places on elements e and f
be checked at step k, so their arc lengths differ by at least ``w`` (and by
at least ``S``). Along the polyline between them the unit tangent turns by
at most ``T`` in total, so every tangent lies within the angle ``T / 2`` of
the tangent halfway along that turning, m; the chord is the integral of
the tangent over the arc, so its length is at least its component along
m, at least the arc length times ``cos(T / 2)``, and the pair's distance
minus ``2 r`` exceeds the clearance. (The turning angles are rounded up by
1e-6 rad; ``arccos`` near 0 loses about 1e-8.) At k0 every candidate value below ``clearance +
H`` was evaluated, and each part candidate is charged to every centre of the
element holding its arc length (with a rounding margin: more centres only
lower the gaps); a point with no candidate for part k was at least H past
the clearance from it, and at least ``F[e, k]`` past it, since the element
lies in its box and the part in its own (a point outside the part's box is
outside the part, at a distance no less than the boxes' separation). Exclusions are windows in arc length (self: ``|s_a -
s_b| < pi r + clearance``), and an arc length moved by at most the total
change of element lengths; attachments are fixed windows of the cable's
material, where a discrete point, the same combination of the same two
centres, keeps its material coordinate (and so its window) while skipping;
the gaps at k0 include candidates up to ``stretch`` inside every window
all the same, so none that left a window since was unaccounted for. Part pairs: the least distance
of their triangles is at least the separation of their oriented boxes on any
box axis (or, for a plane, the box's lowest point above it), which
:func:`part_pair_bounds` takes at k0. Rounding is absorbed by a margin of
1e-9 of the scene's extent.

So on such a step the pairwise checks can be skipped: their answer is "no
pair below the clearance" apart from the active pairs, exactly what a full
check would return. Single-cable checks (bend, taut) and the active pairs are still
evaluated every step, by the caller. Method ``exact`` (closest points whose
exclusion can change discontinuously) and the face-plane distance never
skip.

This module holds only the bound; it takes arrays and knows no simulator.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from checker.arrays import ranges
from checker.cable import polyline_arc_lengths, self_pair_window
from checker.closest import row_norm
from checker.interference.hits import Gaps
from checker.partset import PartSet, Placement


@dataclass(frozen=True)
class Active:
    """The pairs a start of :class:`Advancement` leaves to the caller.

    The caller evaluates them itself at every state proven clear, until the
    next start: they were inside or near the clearance at the full check.

    Attributes:
        structure: (centre, part) arrays: body centres and the parts
            (numbered as in the poses) they are evaluated against.
        cable: (centre, centre) arrays: pairs of body centres whose discrete
            places are evaluated against each other.
    """

    structure: tuple[np.ndarray, np.ndarray]
    cable: tuple[np.ndarray, np.ndarray]


def part_pair_bounds(parts: PartSet, placed: Placement, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Lower bounds (n,) on the distance between parts i and j (n,).

    Two finite parts: the largest separation of their oriented boxes along
    one of the six box axes (0 or less when they may overlap). A plane
    (half-space local z < 0) and a finite part: the height of the part's box
    above the plane (what the part-part check measures, the lowest vertex,
    is at least that). Two planes: inf (no vertices to test).
    """
    half = parts.half()
    c, rot = placed.centre, placed.rot
    out = np.full(len(i), np.inf)
    pi, pj = parts.plane[i], parts.plane[j]
    both = ~pi & ~pj
    if both.any():
        a, b = i[both], j[both]
        ra, rb = rot[a], rot[b]
        t = c[b] - c[a]
        rel = np.abs(np.einsum("nji,njk->nik", ra, rb))   # |A_i . B_k|
        ta = np.abs(np.einsum("nji,nj->ni", ra, t))        # along a's axes
        tb = np.abs(np.einsum("nji,nj->ni", rb, t))        # along b's axes
        sa = ta - half[a] - np.einsum("nik,nk->ni", rel, half[b])
        sb = tb - half[b] - np.einsum("nik,ni->nk", rel, half[a])
        out[both] = np.maximum(sa.max(axis=1), sb.max(axis=1))
    one = pi ^ pj
    if one.any():
        p = np.where(pi, i, j)[one]
        q = np.where(pi, j, i)[one]
        nrm = rot[p][:, :, 2]
        height = np.einsum("ni,ni->n", c[q] - placed.pos[p], nrm)
        extent = np.einsum("nk,nk->n", np.abs(np.einsum("nji,nj->ni", rot[q], nrm)), half[q])
        out[one] = height - extent
    return out


class Advancement:
    """The bound of the module docstring, restarted at every full check.

    Args:
        offsets: (C + 1,) start of each cable in the concatenated body centres.
        spacing: (C,) largest discrete element length per cable (as the checker).
        part_radius: (P,) bounding radius of each part about its frame's
            origin (inf for planes).
        clearance: the clearance (part pairs' bounds are distances).
        stretch: total change of element lengths allowed (the checker's).
        radius: (C,) cable radii; with them cable pairs far apart at a full
            check get the blocks' distance as their gap (else the horizon).
        part_box: ((P, 3), (P, 3)) each part's bounds in its own frame
            (infinite for a plane: lo -inf, hi (inf, inf, 0)); with them and
            ``radius``, centres far from a part get the boxes' distance as
            their gap to it (else the horizon).
    """

    BLOCK = 4
    """Elements per block of the far-pair bound."""

    GROUP = 8
    """Blocks per group: block pairs are first tested a group pair at a time."""

    SPARSE_ENTRIES = 200_000
    """Above this many centre-part pairs the gaps are kept sparse (only the
    pairs within ``FAR_HORIZONS`` horizons); below, a dense table."""

    FAR_HORIZONS = 8.0
    """Block pairs nearer than this many horizons are kept one by one; the
    others share the whole displacement spread as their bound."""

    def __init__(self, offsets: np.ndarray, spacing: np.ndarray, part_radius: np.ndarray,
                 clearance: float, stretch: float, radius: np.ndarray | None = None,
                 part_box: tuple[np.ndarray, np.ndarray] | None = None):
        offsets = np.asarray(offsets, np.int64)
        cable_of_pt = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
        self._valid = cable_of_pt[:-1] == cable_of_pt[1:]
        self._offsets = offsets
        self._cable = cable_of_pt
        self._lim = np.asarray(spacing, float)[cable_of_pt[:-1]]
        # per element: the limit (inf between cables) and 1 for a real element
        self._lim_all = np.where(self._valid, self._lim, np.inf)
        self._validf = self._valid.astype(float)
        self._rho = np.asarray(part_radius, float)
        self._rad = None if radius is None else np.asarray(radius, float)[cable_of_pt]
        self._box = None if part_box is None or radius is None else \
            (np.asarray(part_box[0], float)[:, None, :], np.asarray(part_box[1], float)[:, None, :])
        self.clearance = float(clearance)
        self.stretch = float(stretch)
        self._ok = self._pairs_ok = False
        self.full = 0
        self.skipped = 0

    def _elements(self, pts: np.ndarray) -> np.ndarray:
        """Pieces per element of centres pts (0 between cables); leaves the
        element lengths in ``_seg_raw``."""
        seg = row_norm(pts[1:] - pts[:-1])
        self._seg_raw = seg
        # the same arithmetic as checker.cable.densify_batch
        return np.where(self._valid, np.maximum(1, np.ceil(seg / self._lim * (1.0 - 1e-12))), 0)

    def start(self, pts: np.ndarray, poses: np.ndarray, gaps: Gaps, pairs: tuple[np.ndarray, np.ndarray],
              pair_bound: np.ndarray, active: tuple[np.ndarray, np.ndarray] | None = None,
              cable_active: np.ndarray | None = None) -> Active:
        """A full check ran at this state: cable body centres (N, 3) and part
        poses (P, 4, 4); the check's gaps (:class:`~checker.interference.hits.Gaps`,
        parts numbered as in ``poses``, inf for parts it does not check) and
        part pairs with their distance bounds.

        With ``gaps.part_candidates`` (found up to ``gaps.horizon`` past the
        clearance) the part gaps are kept per body centre (the smallest over
        the elements next to it, the horizon where there is none), else every
        centre gets the part's gap. With ``gaps.cable_candidates`` cable pairs
        are bounded per pair of body centres and per pair of blocks, else all
        by ``gaps.cable``.

        Args:
            active: (cable, part index in ``poses``) pairs the caller
                evaluates itself at every step (those inside or near the
                clearance at this state) where they may come close: the
                cable's body centres whose gap to the part is below
                ``FAR_HORIZONS * horizon`` are left out of the bound against
                it; its farther centres still bound the step.
            cable_active: (P, 2) self and cable-cable pairs (a <= b) the
                caller evaluates itself at every step where they came near:
                the pairs of body centres their candidates are charged to
                bound nothing.

        Returns:
            the (centre, part) and (centre, centre) pairs the caller must
            evaluate itself at every step proven clear until the next start.
        """
        gap_cable, gap_part, horizon = gaps.cable, gaps.part, gaps.horizon
        candidates, cable_candidates = gaps.part_candidates, gaps.cable_candidates
        self.full += 1
        self._pts = np.array(pts, float)
        self._rot = np.array(poses[:, :3, :3], float)
        self._pos = np.array(poses[:, :3, 3], float)
        self._pieces = self._elements(self._pts)
        scale = max(float(np.abs(self._pts).max(initial=0.0)), float(np.abs(self._pos).max(initial=0.0)))
        mu = 1e-9 * (1.0 + scale)
        self._g_cable = float(gap_cable) - mu
        gap_part = np.asarray(gap_part, float)
        n, n_p = len(self._pts), len(gap_part)
        # arc length of each centre, as densify_batch computes it
        self._s_c = polyline_arc_lengths(np.where(self._valid, self._seg_raw, 0.0), self._offsets)
        self._sparse = (candidates is not None and self._box is not None and n > 1 and horizon > 0
                        and n * n_p > self.SPARSE_ENTRIES)
        if self._sparse:
            structure = self._start_sparse(gap_part, float(horizon), candidates, active, mu)
            return Active(structure, self._finish_start(poses, pairs, pair_bound, mu, horizon, cable_candidates,
                                                        cable_active))
        u0 = (self._pts[None] - self._pos[:, None]) @ self._rot                  # R^T (x - t)
        if candidates is None:
            g = np.broadcast_to(gap_part, (n, n_p)).copy()
        else:
            base = np.full((n, n_p), float(horizon))
            if self._box is not None and n > 1:
                base = np.maximum(base, self._floor(u0).T)
            g = np.where(np.isfinite(gap_part)[None, :], base, np.inf)
            cab, s, part, value = candidates
            if len(value):
                lo, hi = self._bracket(cab, s)
                count = hi - lo + 1
                rows = ranges(lo, count)
                np.minimum.at(g, (rows, np.repeat(part, count)), np.repeat(value, count))
        structure = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        if active is not None and len(active[0]):
            a_cab, a_part = (np.asarray(x, np.int64) for x in active)
            near = (self._cable[:, None] == a_cab[None, :]) & (g[:, a_part] < self.FAR_HORIZONS * horizon)
            rows, j = np.nonzero(near)
            structure = (rows, a_part[j])
            g[structure] = np.inf
        self._g_pt = g - mu
        # fused-pass data: each centre in each part's frame (homogeneous)
        self._u0h = np.concatenate([u0, np.ones(u0.shape[:2] + (1,))], axis=2)
        self._g_kn = np.ascontiguousarray(self._g_pt.T)
        self._g2 = np.where(self._g_kn > 0, self._g_kn, 0.0) ** 2
        return Active(structure, self._finish_start(poses, pairs, pair_bound, mu, horizon, cable_candidates,
                                                    cable_active))

    def _finish_start(self, poses, pairs, pair_bound, mu, horizon, cable_candidates,
                      cable_active) -> tuple[np.ndarray, np.ndarray]:
        """The rest of :meth:`start` after the cable-part gaps; returns the
        active (centre, centre) pairs."""
        self._cable_pairs = cable_candidates is not None
        active = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        if self._cable_pairs:
            active = self._start_cable_pairs(cable_candidates, float(horizon), mu, cable_active)
            cable_ok = bool(np.all(self._g_cc > 0))             # the blocks' gaps on first use
        else:
            cable_ok = self._g_cable > 0
        self.start_pairs(poses, pairs, pair_bound, mu)
        self._stretch = self.stretch - mu
        # pieces per element (1 between cables)
        self._pieces_all = np.where(self._valid, self._pieces, 1.0)
        # sparse: the entries' gaps are checked on first use
        part_ok = self._sp_cap > 0 if self._sparse else bool(np.all(self._g_pt > 0))
        self._ok = cable_ok and part_ok and self._pairs_ok and self.stretch > mu
        return active

    def _start_sparse(self, gap_part: np.ndarray, horizon: float, candidates: tuple[np.ndarray, ...],
                      active: tuple[np.ndarray, np.ndarray] | None,
                      mu: float) -> tuple[np.ndarray, np.ndarray]:
        """The centre-part gaps ``g[i, k]`` of the module docstring kept only
        where they are below ``cap = FAR_HORIZONS * horizon`` (every other
        checked pair counts as ``cap``: a smaller gap only proves less), as
        (centre, part, gap) entries sorted by part.

        Pairs are listed by a k-d tree of the element midpoints queried about
        each part's frame origin. Why that finds every floor below ``cap``:
        an element of half-length h lies in its bounding box in the part's
        frame, and that box lies within ``sqrt(3) h`` of the midpoint; the
        part's box lies within its bounding radius ``rho`` of the origin; so
        the boxes' distance is at least ``|mid - origin| - sqrt(3) h - rho``,
        and ``F[e, k]`` (that minus the cable radius and the clearance) is at
        least ``cap`` beyond the query radius. Candidates (values at most the
        horizon, below every floor's ``max(H, F)``) are entries of their own.
        Planes and other unbounded parts get every centre. Returns the
        active (centre, part) pairs."""
        n_p = len(gap_part)
        cap = self.FAR_HORIZONS * horizon
        self._sp_cap = cap - mu
        self._sp_default = np.where(np.isfinite(gap_part), self._sp_cap, np.inf)    # an unlisted pair's gap
        self._sp_cache: dict[bytes, tuple] = {}
        first = np.zeros(n_p, bool)
        if active is not None and len(active[0]):
            first[np.asarray(active[1], np.int64)] = True
        # the active parts' entries now (the caller needs the active pairs), the
        # others on first use (:meth:`_ensure_sparse`)
        part, rows, val = self._sparse_entries(gap_part, horizon, candidates, first)
        n = len(self._pts)
        structure = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        if active is not None and len(active[0]):
            a_cab, a_part = (np.asarray(x, np.int64) for x in active)
            # (centre, active pair) for every entry of an active part on the pair's cable
            pair_of = {}
            for j, (c, q) in enumerate(zip(a_cab.tolist(), a_part.tolist())):
                pair_of.setdefault(q, []).append((j, c))
            hit_r, hit_j = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
            for q, lst in pair_of.items():                         # the few active parts
                on = part == q
                for j, c in lst:
                    r = rows[on & (self._cable[rows] == c)]
                    hit_r.append(r)
                    hit_j.append(np.full(len(r), j, np.int64))
            hr, hj = np.concatenate(hit_r), np.concatenate(hit_j)
            o = np.lexsort((hj, hr))
            hr, hj = hr[o], hj[o]
            structure = (hr, a_part[hj])
            drop = np.isin(part * n + rows, a_part[hj] * n + hr)
            part, rows, val = part[~drop], rows[~drop], val[~drop]
        self._sp_first = (part, rows, val - mu)
        self._sp_rest = (gap_part, horizon, candidates, ~first, mu)
        self._sp_ready = False
        return structure

    def _ensure_sparse(self) -> bool:
        """Every sparse entry of the last start (once); True when all gaps are positive."""
        if not self._sp_ready:
            gap_part, horizon, candidates, rest, mu = self._sp_rest
            part, rows, val = self._sparse_entries(gap_part, horizon, candidates, rest)
            p0, r0, g0 = self._sp_first
            self._sp_part = np.concatenate([p0, part])
            self._sp_row = np.concatenate([r0, rows])
            self._sp_g = np.concatenate([g0, val - mu])
            self._sp_ready = True
            self._sp_ok = bool(np.all(self._sp_g > 0)) and self._sp_cap > 0
        return self._sp_ok

    def _sparse_entries(self, gap_part: np.ndarray, horizon: float, candidates: tuple[np.ndarray, ...],
                        only: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(part, centre, gap) entries below the cap of the parts ``only`` (P,) bool
        (see :meth:`_start_sparse`), the least per pair, sorted by part."""
        pts, n = self._pts, len(self._pts)
        cap = self.FAR_HORIZONS * horizon
        checked = np.isfinite(gap_part)
        box_lo, box_hi = self._box[0][:, 0], self._box[1][:, 0]
        seg = np.where(self._valid, self._seg_raw, 0.0)
        elem = np.nonzero(self._valid)[0]
        mid = 0.5 * (pts[elem] + pts[elem + 1])
        bounded = checked & only & np.isfinite(self._rho)
        e_list, k_list = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
        if bounded.any() and len(elem):
            reach = (cap + np.sqrt(3.0) * 0.5 * float(seg.max()) + float(self._rad.max()) + self.clearance
                     + 1e-9 * (1.0 + float(np.abs(pts).max())))
            kb = np.nonzero(bounded)[0]
            found = cKDTree(mid).query_ball_point(self._pos[kb], reach + self._rho[kb])
            count = np.array([len(f) for f in found], np.int64)
            if count.sum():
                e_list.append(elem[np.concatenate([np.asarray(f, np.int64) for f in found if len(f)])])
                k_list.append(np.repeat(kb, count))
        unbounded = np.nonzero(checked & only & ~np.isfinite(self._rho))[0]
        if len(unbounded) and len(elem):
            e_list.append(np.tile(elem, len(unbounded)))
            k_list.append(np.repeat(unbounded, len(elem)))
        e, k = np.concatenate(e_list), np.concatenate(k_list)
        # F[e, k] as _floor computes it (the element's ends in the part's frame)
        rot, pos = self._rot[k], self._pos[k]
        a = np.einsum("ni,nij->nj", pts[e] - pos, rot)
        b = np.einsum("ni,nij->nj", pts[e + 1] - pos, rot)
        sep = np.maximum(np.maximum(np.minimum(a, b) - box_hi[k], box_lo[k] - np.maximum(a, b)), 0.0)
        f = np.sqrt(np.einsum("ni,ni->n", sep, sep)) - self._rad[e] - self.clearance
        rows = np.concatenate([e, e + 1])
        part = np.concatenate([k, k])
        val = np.maximum(horizon, np.concatenate([f, f]))
        cab, s, c_part, value = candidates
        if len(value):
            lo, hi = self._bracket(cab, s)
            count = hi - lo + 1
            rows = np.concatenate([rows, ranges(lo, count)])
            part = np.concatenate([part, np.repeat(np.asarray(c_part, np.int64), count)])
            val = np.concatenate([val, np.repeat(np.asarray(value, float), count)])
        keep = checked[part] & only[part] & (val < cap)
        rows, part, val = rows[keep], part[keep], val[keep]
        key = part * n + rows
        o = np.lexsort((val, key))
        key, val = key[o], val[o]
        first = np.r_[len(key) > 0, key[1:] != key[:-1]][:len(key)]
        key, val = key[first], val[first]                       # the least per (part, centre)
        part, rows = key // n, key % n
        return part, rows, val


    def _floor(self, u0: np.ndarray) -> np.ndarray:
        """(P, N): per centre and part, the least over the elements next to
        the centre of ``F[e, k]`` (module docstring); u0 (P, N, 3) the
        centres in the parts' frames."""
        a, b = u0[:, :-1], u0[:, 1:]
        box_lo, box_hi = self._box
        sep = np.maximum(np.maximum(np.minimum(a, b) - box_hi, box_lo - np.maximum(a, b)), 0.0)
        f = np.sqrt(np.einsum("kei,kei->ke", sep, sep)) - self._rad[:-1] - self.clearance
        f = np.where(self._valid, f, np.inf)
        out = np.full(u0.shape[:2], np.inf)
        out[:, :-1] = f
        out[:, 1:] = np.minimum(out[:, 1:], f)
        return out

    def _bracket(self, cab: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """First and last body centre (n,) of the element(s) holding arc length
        s on cable cab, at the start's arc lengths (as densify_batch computes
        them); widened by a rounding margin (more centres only lower the gaps)."""
        s_c = self._s_c
        width = 2.0 * (float(s_c.max(initial=0.0)) + float(np.abs(s).max(initial=0.0))) + 1.0
        key_c = self._cable * width + s_c
        key = cab * width + s
        eps = 1e-9 * width * (1 + len(self._offsets))
        lo = np.maximum(np.searchsorted(key_c, key - eps, "left") - 1, self._offsets[cab])
        hi = np.minimum(np.searchsorted(key_c, key + eps, "right"), self._offsets[cab + 1] - 1)
        return lo, hi

    def _start_cable_pairs(self, cand: tuple[np.ndarray, ...], horizon: float, mu: float,
                           active: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Gaps of cable pairs per pair of body centres (candidates) and per
        pair of blocks (everything else): the module docstring's second list.
        ``active``: (P, 2) cable pairs (a <= b) the caller evaluates itself
        near their candidates; returns the (centre, centre) pairs left to it."""
        n = len(self._pts)
        ca, sa, cb, sb, value = (np.asarray(x) for x in cand)
        ca, cb = ca.astype(np.int64), cb.astype(np.int64)
        ii = jj = np.zeros(0, np.int64)
        gg = np.zeros(0)
        self._near = self._rad is not None and n > 1
        if self._near:
            self._start_near(horizon, mu)
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
            if self._near:                       # near pairs carry their own candidates
                far_c = ~self._charge_near(ca, lo_a, hi_a, cb, lo_b, hi_b, value)
                lo_a, hi_a, lo_b, hi_b, value = lo_a[far_c], hi_a[far_c], lo_b[far_c], hi_b[far_c], value[far_c]
            # every centre pair of the two brackets (at most 3 x 3 each)
            k = np.arange(3)
            i = lo_a[:, None, None] + k[None, :, None]
            j = lo_b[:, None, None] + k[None, None, :]
            ok = (i <= hi_a[:, None, None]) & (j <= hi_b[:, None, None])
            i, j = np.broadcast_to(i, ok.shape)[ok], np.broadcast_to(j, ok.shape)[ok]
            v = np.broadcast_to(value[:, None, None], ok.shape)[ok]
            key = np.minimum(i, j) * n + np.maximum(i, j)
            o = np.argsort(key, kind="stable")
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
        if self._near:
            self._g_near = np.minimum(self._g_near, horizon) - mu
            self._g_near2 = np.where(self._g_near > 0, self._g_near, 0.0) ** 2
        self._cc_i, self._cc_j = ii, jj
        self._g_cc = np.minimum(gg, horizon) - mu
        self._g_cc2 = np.where(self._g_cc > 0, self._g_cc, 0.0) ** 2
        # the block pairs are listed on first use (:meth:`_ensure_blocks`):
        # a run whose states fail the cheaper conditions never needs them
        self._blk_args = (horizon, mu)
        self._blocks_ready = False
        self._g_min_nb = min(float(self._g_cc.min(initial=np.inf)),
                             float(self._g_near.min(initial=np.inf)) if self._near else np.inf)
        return cable_active

    def _ensure_blocks(self) -> bool:
        """List the block pairs of the last start (once); True when their
        gaps are all positive."""
        if not self._blocks_ready:
            self._start_blocks(*self._blk_args)
            self._blocks_ready = True
            self._blk_ok = bool(np.all(self._g_grp > 0)) and self._g_far > 0
        return self._blk_ok

    def _start_blocks(self, horizon: float, mu: float) -> None:
        """Blocks, their groups and the group pairs to test (the module
        docstring's block condition).

        Groups of GROUP consecutive blocks: a group pair's box of relative
        displacements holds each of its block pairs' boxes, so a group pair
        whose box is below a lower bound of its block pairs' gaps clears them
        all; the block pairs of the others are formed when tested
        (:meth:`_block_pairs`), with their own gaps. The lower bound: the
        distance between spheres about the groups enclosing their blocks'
        spheres, put through the blocks' rule (``max(H, min(d, far))``, which
        grows with d). Block pairs listed (one by one) are those whose
        centres lie within the search radius of the k-d tree (``2 max reach
        + clearance + far``) when there are more than 64 blocks, else all;
        the group pairs kept are those that may hold one."""
        n = len(self._pts)
        # blocks of BLOCK elements: centres [b K, b K + K] (overlapping by one)
        kb = self.BLOCK
        nb = max(1, -(-(n - 1) // kb)) if n else 0
        self._blk_start = np.arange(nb) * kb
        self._blk_last = np.minimum(self._blk_start + kb, max(n - 1, 0))
        far = self.FAR_HORIZONS * horizon
        self._blk_h, self._blk_far, self._blk_mu = horizon, far, mu
        self._grp_blocks = np.arange(0, nb, self.GROUP)
        ng = len(self._grp_blocks)
        self._gi = self._gj = np.zeros(0, np.int64)
        self._g_grp = self._g_grp2 = np.zeros(0)
        self._g_far = np.inf
        self._blk_rad = None
        if nb == 0:
            return
        lo = np.minimum.reduceat(self._pts, self._blk_start)
        hi = np.maximum.reduceat(self._pts, self._blk_start)
        lo = np.minimum(lo, self._pts[self._blk_last])
        hi = np.maximum(hi, self._pts[self._blk_last])
        centre = 0.5 * (lo + hi)
        big = 0.5 * row_norm(hi - lo)               # encloses the block's centres, so its elements
        group = np.arange(nb) // self.GROUP
        self._blk_radius = None                     # the k-d tree's search radius (None: every pair)
        if self._rad is not None:
            rad = np.maximum(np.maximum.reduceat(self._rad, self._blk_start), self._rad[self._blk_last])
            self._blk_rad = rad[:, None] + self.clearance / 2 + mu      # each block's share of a pair's
            reach = big + rad
            self._blk_centre, self._blk_reach = centre, reach
            g_lo = np.minimum.reduceat(centre, self._grp_blocks)
            g_hi = np.maximum.reduceat(centre, self._grp_blocks)
            g_centre = 0.5 * (g_lo + g_hi)
            off = row_norm(centre - g_centre[group])
            g_reach = np.maximum.reduceat(off + reach, self._grp_blocks)
            if nb <= 64:                                # few blocks: every pair
                gi, gj = np.triu_indices(ng)
            else:
                radius = 2.0 * float(reach.max()) + self.clearance + far
                self._blk_radius = radius
                tree = cKDTree(centre)
                listed = int(tree.count_neighbors(tree, radius)) == nb * nb
                self._g_far = (np.inf if listed else far) - mu
                pairs = cKDTree(g_centre).query_pairs(radius + 2.0 * float(off.max()) + 1e-9 * (1.0 + radius),
                                                      output_type="ndarray")
                gi = np.concatenate([np.arange(ng), pairs[:, 0]]).astype(np.int64)
                gj = np.concatenate([np.arange(ng), pairs[:, 1]]).astype(np.int64)
            dist = row_norm(g_centre[gi] - g_centre[gj]) - g_reach[gi] - g_reach[gj] - self.clearance
            g_grp = np.maximum(horizon, np.minimum(dist, far))
        else:
            gi, gj = np.triu_indices(ng)
            g_grp = np.full(len(gi), horizon)
        self._gi, self._gj = gi.astype(np.int64), gj.astype(np.int64)
        self._g_grp = g_grp - mu
        self._g_grp2 = np.where(self._g_grp > 0, self._g_grp, 0.0) ** 2
        self._nb = nb

    def _block_pairs(self, gp: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The block pairs (a <= b) of group pairs gp and their squared gaps
        (the module docstring's ``max(H, L[A, B])``, less the rounding
        margin): those listed, other than a block with itself or the next on
        one cable (their element pairs are near pairs)."""
        g, nb = self.GROUP, self._nb
        k = np.arange(g * g)
        bi = (self._gi[gp] * g)[:, None] + (k // g)[None, :]
        bj = (self._gj[gp] * g)[:, None] + (k % g)[None, :]
        keep = (bi <= bj) & (bj < nb)
        bi, bj = bi[keep], bj[keep]
        end = self._blk_last[bj]
        near = (bj - bi <= 1) & (self._cable[self._blk_start[bi]] == self._cable[end])
        bi, bj = bi[~near], bj[~near]
        if self._blk_rad is None:
            gap = np.full(len(bi), self._blk_h)
        else:
            c = self._blk_centre
            sep = row_norm(c[bi] - c[bj])
            if self._blk_radius is not None:
                on = sep <= self._blk_radius
                bi, bj, sep = bi[on], bj[on], sep[on]
            dist = sep - self._blk_reach[bi] - self._blk_reach[bj] - self.clearance
            gap = np.maximum(self._blk_h, np.minimum(dist, self._blk_far))
        gap = gap - self._blk_mu
        return bi, bj, np.where(gap > 0, gap, 0.0) ** 2

    def _start_near(self, horizon: float, mu: float) -> None:
        """Near element pairs (e, f), e <= f <= e + 2 BLOCK - 1 on one cable,
        their arc-length window, the distance their places must exceed, and
        their gaps (the horizon until candidates are charged)."""
        n, span = len(self._pts), 2 * self.BLOCK
        e = np.repeat(np.arange(n - 1), span)
        f = e + np.tile(np.arange(span), n - 1)
        keep = f < n - 1
        e, f = e[keep], f[keep]
        keep = self._valid[e] & self._valid[f] & (self._cable[e] == self._cable[f])
        self._ne, self._nf = e[keep], f[keep]
        self._near_index = np.full((n - 1) * span, -1, np.int64)
        self._near_index[self._ne * span + (self._nf - self._ne)] = np.arange(len(self._ne))
        r = self._rad[self._ne]
        # the chord bound as a turning limit: places checked are at least
        # max(w, S) apart along the cable, with S the arc length from centre
        # e + 1 to f, which can shrink by at most ``stretch`` while skipping
        arc = self._s_c
        window = self_pair_window(r, self.clearance) - mu
        ds = np.maximum(window, arc[self._nf] - arc[self._ne + 1] - self.stretch - mu)
        ratio = (2.0 * r + self.clearance + mu) / ds
        self._near_turn = np.where(ratio < 1.0, 2.0 * np.arccos(np.minimum(ratio, 1.0)) - 1e-9, -1.0)
        self._g_near = np.full(len(self._ne), float(horizon))
        # the four centre pairs (e or e + 1, f or f + 1) of each near pair
        self._near_a = np.concatenate([self._ne, self._ne, self._ne + 1, self._ne + 1])
        self._near_b = np.concatenate([self._nf, self._nf + 1, self._nf, self._nf + 1])

    def _charge_near(self, ca, lo_a, hi_a, cb, lo_b, hi_b, value) -> np.ndarray:
        """Charge the candidates whose places lie on near element pairs to
        those pairs' gaps; returns which candidates were (n,) bool."""
        span = 2 * self.BLOCK
        first, last = self._offsets[ca], self._offsets[ca + 1] - 2          # the cable's elements
        ea0, ea1 = np.clip(lo_a, first, last), np.clip(np.maximum(hi_a - 1, lo_a), first, last)
        first_b, last_b = self._offsets[cb], self._offsets[cb + 1] - 2
        eb0, eb1 = np.clip(lo_b, first_b, last_b), np.clip(np.maximum(hi_b - 1, lo_b), first_b, last_b)
        near = (ca == cb) & (np.maximum(ea1, eb1) - np.minimum(ea0, eb0) < span)
        if near.any():
            k = np.arange(3)
            ea = ea0[near][:, None, None] + k[None, :, None]
            eb = eb0[near][:, None, None] + k[None, None, :]
            ok = (ea <= ea1[near][:, None, None]) & (eb <= eb1[near][:, None, None])
            ea, eb = np.broadcast_to(ea, ok.shape)[ok], np.broadcast_to(eb, ok.shape)[ok]
            v = np.broadcast_to(value[near][:, None, None], ok.shape)[ok]
            e, f = np.minimum(ea, eb), np.maximum(ea, eb)
            np.minimum.at(self._g_near, self._near_index[e * span + (f - e)], v)
        return near

    def _near_clear(self, move: np.ndarray, d: np.ndarray, seg: np.ndarray) -> np.ndarray:
        """Near element pairs per state (S,): each either provably apart by
        the chord bound at this state (module docstring) or within its gap
        of relative motion since the start. d (N - 1, 3, S) the elements,
        seg (N - 1, S) their lengths."""
        s = move.shape[2]
        # turning at each centre, rounded up (arccos loses ~1e-8 near 0); a
        # zero-length element turns by pi (proves nothing)
        den = seg[:-1] * seg[1:]
        cos = np.divide(np.einsum("eis,eis->es", d[:-1], d[1:]), den, out=np.full(den.shape, -1.0),
                        where=den > 0)
        turn = np.zeros((len(move), s))
        turn[1:-1] = np.arccos(np.clip(cos, -1.0, 1.0)) + 1e-6
        turn = np.cumsum(turn, axis=0)
        bad = turn[self._nf] - turn[self._ne] >= self._near_turn[:, None]     # (E, S)
        rows = np.nonzero(bad.any(axis=1))[0]
        if len(rows):                            # the relative motion only where the chord fails
            m = len(self._ne)
            a = (self._near_a.reshape(4, m)[:, rows]).ravel()
            b = (self._near_b.reshape(4, m)[:, rows]).ravel()
            dd = move[a] - move[b]
            rel2 = np.einsum("pis,pis->ps", dd, dd).reshape(4, len(rows), s).max(axis=0)
            bad[rows] &= rel2 >= self._g_near2[rows, None]
        return ~bad.any(axis=0)

    def _cable_pairs_clear(self, x: np.ndarray, move: np.ndarray, dcc: np.ndarray, diag: np.ndarray,
                           d: np.ndarray, seg: np.ndarray) -> np.ndarray:
        """The cable-pair conditions of the module docstring (second list),
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
        whole, the spheres at this state only for block pairs failing the
        box, and over runs of states of doubling length."""
        n_s = len(dcc)
        ok = np.ones(n_s, bool)
        easy = diag < self._g_min_nb               # every relative motion is below every such gap
        if not easy.all():
            pair_ok = self._near_clear(move, d, seg) if self._near else np.ones(n_s, bool)
            pair_ok |= easy
            m = _leading(pair_ok)
            if len(self._cc_i) and m:
                dd = move[self._cc_i][:, :, :m] - move[self._cc_j][:, :, :m]
                pair_ok[:m] &= (np.einsum("mis,mis->ms", dd, dd) < self._g_cc2[:, None]).all(axis=0) | easy[:m]
            ok &= pair_ok
        n = _leading(ok)
        ok[n:] = False
        if not n:
            return ok
        if not self._ensure_blocks():
            return np.zeros(n_s, bool)
        ok[:n] &= dcc[:n] < self._g_far
        n = _leading(ok)
        ok[n:] = False
        if len(self._gi) and n:
            # states in runs of doubling length, each only once the ones
            # before all passed: a failure near the start costs a state or two
            a, b = 0, 1
            while a < n:
                b = min(b, n)
                blk = self._blocks_clear(x[:, :, a:b], move[:, :, a:b], float(diag[a:b].max()))
                if not blk.all():
                    ok[a + _leading(blk):] = False
                    break
                a, b = b, 2 * b + 1
        return ok

    def _blocks_clear(self, x: np.ndarray, move: np.ndarray, diag: float) -> np.ndarray:
        """The block-pair condition per state (S,) of x and move (N, 3, S);
        ``diag`` bounds every block pair's box (the largest diagonal)."""
        s = x.shape[2]
        # group pairs whose least gap exceeds every box pass whole
        cand = np.nonzero(self._g_grp <= diag)[0]
        if not len(cand):
            return np.ones(s, bool)
        box = self._block_boxes(move)
        glo = np.minimum.reduceat(box[0], self._grp_blocks, axis=0)
        ghi = np.maximum.reduceat(box[1], self._grp_blocks, axis=0)
        gi, gj = self._gi[cand], self._gj[cand]
        rel = np.maximum(np.abs(ghi[gi] - glo[gj]), np.abs(glo[gi] - ghi[gj]))
        grp_ok = np.einsum("pis,pis->ps", rel, rel) < self._g_grp2[cand, None]
        fail = cand[~grp_ok.all(axis=1)]
        if not len(fail):
            return np.ones(s, bool)
        bi, bj, g2 = self._block_pairs(fail)                            # their block pairs
        rel = np.maximum(np.abs(box[1][bi] - box[0][bj]), np.abs(box[0][bi] - box[1][bj]))
        blk_ok = np.einsum("pis,pis->ps", rel, rel) < g2[:, None]
        if self._blk_rad is not None:
            bad = np.nonzero(~blk_ok.all(axis=1))[0]
            if len(bad):
                # or apart now: spheres about the blocks' boxes of centres, at this state
                lo, hi = self._block_boxes(x)
                sphere = 0.5 * row_norm3(hi - lo) + self._blk_rad
                centre = 0.5 * (lo + hi)
                a, b = bi[bad], bj[bad]
                blk_ok[bad] |= row_norm3(centre[a] - centre[b]) > sphere[a] + sphere[b]
        return blk_ok.all(axis=0)

    def _block_boxes(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Componentwise least and largest of v (N, 3, S) over each block's
        centres: ((B, 3, S), (B, 3, S))."""
        last = v[self._blk_last]
        return (np.minimum(np.minimum.reduceat(v, self._blk_start, axis=0), last),
                np.maximum(np.maximum.reduceat(v, self._blk_start, axis=0), last))

    def stop(self) -> None:
        """A full check ran without gaps: prove nothing until the next :meth:`start`."""
        self.full += 1
        self._ok = self._pairs_ok = False

    def start_pairs(self, poses: np.ndarray, pairs: tuple[np.ndarray, np.ndarray],
                    pair_bound: np.ndarray, mu: float | None = None) -> None:
        """Restart the part-pair condition alone (:meth:`part_pairs_clear`)
        at this state: after a full check whose cable checks left no gaps
        (a pair inside the clearance), the part-part check can still be
        proven clear on later full checks. (:meth:`start` restarts it too,
        with its own rounding margin ``mu``.)"""
        self._poses = np.array(poses, float)
        self._pi, self._pj = pairs
        if mu is None:
            mu = 1e-9 * (1.0 + float(np.abs(self._poses[:, :3, 3]).max(initial=0.0)))
        self._g_pair = np.asarray(pair_bound, float) - self.clearance - mu
        self._pairs_ok = bool(np.all(self._g_pair > 0))

    def proven_clear(self, pts: np.ndarray, poses: np.ndarray) -> bool:
        """True when no pair can be within the clearance at one state (body
        centres (N, 3), part poses (P, 4, 4)); counts it as skipped then."""
        return self.clear_run(np.asarray(pts)[None], np.asarray(poses)[None]) == 1

    def clear_run(self, pts: np.ndarray, poses: np.ndarray) -> int:
        """How many leading states of a run of consecutive states (body
        centres (S, N, 3), part poses (S, P, 4, 4)) are proven clear (module
        docstring); counts them as skipped.

        Vectorised over the states: numpy's cost per call, not the arrays'
        size, dominates for a cable's few dozen centres, so a batch of
        states costs about what one does. The states are laid out last
        ((N, 3, S)): numpy reduces and gathers along a leading axis far
        faster than along a short middle one. Every part is handled alike
        (a part that did not move has ``rel`` equal to ``dq`` up to
        rounding, far below the margin). After each condition only the
        states up to the first failure are carried on."""
        if not self._ok or len(pts) == 0 or pts.shape[1] != len(self._pts):
            return 0
        x = np.ascontiguousarray(np.transpose(pts, (1, 2, 0)))           # (N, 3, S)
        move = x - self._pts[:, :, None]
        dq = row_norm3(move)                                              # (N, S)
        if len(move):
            spread = move.max(axis=0) - move.min(axis=0)                 # (3, S)
            diag = np.sqrt(np.einsum("is,is->s", spread, spread))
            dcc = np.minimum(2.0 * dq.max(axis=0), diag)
        else:
            diag = dcc = np.zeros(x.shape[2])
        d = x[1:] - x[:-1]                                                # (N - 1, 3, S)
        seg = row_norm3(d)
        ok = self._cable_pairs_clear(x, move, dcc, diag, d, seg) if self._cable_pairs else dcc < self._g_cable
        n = _leading(ok)
        if n:
            x, seg = x[:, :, :n], seg[:, :n]
            # pieces per element, the arithmetic of checker.cable.densify_batch
            # (elements joining two cables: limit inf, 1 piece at k0 and now)
            pieces = np.maximum(np.ceil(seg / self._lim_all[:, None] * (1.0 - 1e-12)), 1.0)
            ok = (pieces == self._pieces_all[:, None]).all(axis=0) & \
                (self._validf @ np.abs(seg - self._seg_raw[:, None]) < self._stretch)
            n = _leading(ok)
        if n and len(self._pos):
            n = _leading(self._parts_clear(x[:, :, :n], poses[:n], dq[:, :n]))
        self.skipped += n
        return n

    def _parts_clear(self, x: np.ndarray, poses: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """Cable-structure, keep-out and part-pair conditions per state (S,);
        x (N, 3, S) the centres, dq (N, S) their displacements."""
        s = x.shape[2]
        dp = self._part_moves(poses).T                                    # (P, S)
        if self._sparse:
            return self._parts_clear_sparse(x, poses, dq, dp)
        # every centre as it would be had it moved rigidly with part k:
        # u0h[k] (N, 4) times the poses' top rows (4, 3 S), one product per part
        top = np.transpose(poses[:, :, :3, :], (1, 3, 2, 0)).reshape(len(dp), 4, 3 * s)
        w = np.matmul(self._u0h, top).reshape(len(dp), len(x), 3, s)
        w -= x
        bad = np.einsum("knis,knis->kns", w, w) >= self._g2[:, :, None]
        if bad.any():                            # or within the gap by the world displacements
            bad &= (dq + dp[:, None, :]) >= self._g_kn[:, :, None]
        ok = ~bad.reshape(-1, s).any(axis=0)
        if len(self._pi):
            ok &= (dp[self._pi] + dp[self._pj] < self._g_pair[:, None]).all(axis=0)
        return ok

    def _parts_clear_sparse(self, x: np.ndarray, poses: np.ndarray, dq: np.ndarray, dp: np.ndarray) -> np.ndarray:
        """:meth:`_parts_clear` on the sparse gaps: parts that did not move in
        these states (dp 0, so ``rel`` is ``dq``) reduce to one least gap per
        centre; the parts that moved are tested as the dense table does, on
        their own columns (both kept per set of moving parts)."""
        s = x.shape[2]
        if not self._ensure_sparse():
            return np.zeros(s, bool)
        moved = (dp > 0).any(axis=1)
        tag = moved.tobytes()
        if tag not in self._sp_cache:
            n = len(self._pts)
            still = ~moved[self._sp_part]
            g_still = np.full(n, float(self._sp_default[~moved].min(initial=np.inf)))
            np.minimum.at(g_still, self._sp_row[still], self._sp_g[still])
            mk = np.nonzero(moved)[0]
            col = np.full(len(moved), -1, np.int64)
            col[mk] = np.arange(len(mk))
            g_kn = np.repeat(self._sp_default[mk][:, None], n, axis=1)
            on = ~still
            np.minimum.at(g_kn, (col[self._sp_part[on]], self._sp_row[on]), self._sp_g[on])
            u0 = (self._pts[None] - self._pos[mk, None]) @ self._rot[mk]
            u0h = np.concatenate([u0, np.ones(u0.shape[:2] + (1,))], axis=2)
            g2 = np.where(g_kn > 0, g_kn, 0.0) ** 2
            self._sp_cache = {tag: (g_still, mk, u0h, g_kn, g2)}
        g_still, mk, u0h, g_kn, g2 = self._sp_cache[tag]
        ok = (dq < g_still[:, None]).all(axis=0)
        if len(mk):
            top = np.transpose(poses[:, mk, :3, :], (1, 3, 2, 0)).reshape(len(mk), 4, 3 * s)
            w = np.matmul(u0h, top).reshape(len(mk), len(x), 3, s)
            w -= x
            bad = np.einsum("knis,knis->kns", w, w) >= g2[:, :, None]
            if bad.any():
                bad &= (dq + dp[mk][:, None, :]) >= g_kn[:, :, None]
            ok &= ~bad.reshape(-1, s).any(axis=0)
        if len(self._pi):
            ok &= (dp[self._pi] + dp[self._pj] < self._g_pair[:, None]).all(axis=0)
        return ok

    def _part_moves(self, poses: np.ndarray) -> np.ndarray:
        """dp (..., P): how far any point of each part moved since the start
        (poses (..., P, 4, 4))."""
        dpose = poses - self._poses
        d_rot, d_pos = dpose[..., :3, :3], dpose[..., :3, 3]
        fro = np.sqrt(np.einsum("...ij,...ij->...", d_rot, d_rot))
        dp = np.sqrt(np.einsum("...i,...i->...", d_pos, d_pos))
        dp += np.multiply(fro, self._rho, out=np.zeros_like(fro), where=fro > 0)   # plane turned: inf
        return dp

    def part_pairs_clear(self, poses: np.ndarray) -> bool:
        """True when no moving part pair can be within the clearance (the
        part-pair condition of the module docstring alone): the part-part
        check's answer is then its same-body records only, even on a step
        whose cable checks run in full."""
        if not self._pairs_ok or len(poses) != len(self._poses):
            return False
        dp = self._part_moves(poses)
        return not len(self._pi) or bool(np.all(dp[self._pi] + dp[self._pj] < self._g_pair))


def row_norm3(v: np.ndarray) -> np.ndarray:
    """Euclidean length over axis 1 of (M, 3, S) ``v``: (M, S), the
    arithmetic of :func:`checker.closest.row_norm` (so the same bits)."""
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    return np.sqrt((x * x + y * y) + z * z)


def _leading(ok: np.ndarray) -> int:
    """Number of leading True values of a bool vector."""
    return len(ok) if ok.all() else int(np.argmin(ok))
