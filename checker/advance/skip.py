"""The skip rule's state machine: :class:`Advancement`, restarted at every full check.

A full check starts the bound (:meth:`Advancement.start`) from its gaps; each
later state is tested (:meth:`Advancement.clear_run`, many consecutive states
at once) against the conditions of the package docstring: cable pairs
(:mod:`~cablecheck.checker.advance.cablepairs`), cables against parts
(:mod:`~cablecheck.checker.advance.structure`), part pairs
(:mod:`~cablecheck.checker.advance.partpairs`), and here the elements' pieces and
stretch. The pairs the caller evaluates itself (*active*) come back from
:meth:`Advancement.start` as an :class:`Active` record; with
:meth:`Advancement.clear_run_local` the pairs whose bound fails later join
them (*promoted*) instead of ending the run, up to a budget
(:class:`Cleared`).

Deliberately not here: the arithmetic of the three conditions, the checks
themselves, any simulator.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cablecheck.checker.advance.cablepairs import CablePairGaps
from cablecheck.checker.advance.common import FAR_HORIZONS, Layout, Start, leading, row_norm3
from cablecheck.checker.advance.partpairs import PartPairGaps, PartSolids
from cablecheck.checker.advance.structure import CentrePartGaps
from cablecheck.checker.cable import element_pieces, polyline_arc_lengths
from cablecheck.checker.closest import row_norm
from cablecheck.checker.interference.hits import Gaps


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


@dataclass(frozen=True)
class Cleared:
    """A run of states :meth:`Advancement.clear_run_local` proved clear.

    Attributes:
        states: how many leading states are proven clear but for ``active``.
        active: the pairs the caller evaluates itself at those states: the
            start's, and those whose bound failed since (promoted).
    """

    states: int
    active: Active


@dataclass(frozen=True, slots=True)
class Started:
    """What :meth:`Advancement.start` keeps of one full check: the bound's
    state until the next start (the gaps' objects drop promoted pairs).

    Attributes:
        start: the full check's state (body centres, part poses, element
            lengths, arc lengths, margin, horizon).
        pieces: (N - 1,) pieces per element (1 between cables).
        run_last: (N - 1,) the last element of each element's stretch run
            (:meth:`Advancement._stretch_runs`), or None (whole cables).
        stretch: the stretch allowed, less the rounding margin.
        g_cable: the check's cable gap less the margin (bounds every cable
            pair when ``cable`` is None).
        parts: the centre-part gaps.
        cable: the cable-pair gaps, or None (the check gave no cable candidates).
        ok: every condition held at the start (else nothing is proven).
    """

    start: Start
    pieces: np.ndarray
    run_last: np.ndarray | None
    stretch: float
    g_cable: float
    parts: CentrePartGaps
    cable: CablePairGaps | None
    ok: bool


class Advancement:
    """The bound of the package docstring, restarted at every full check.

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
        part_solids: the parts' boxes, symmetry and tessellation errors for
            the part-pair condition (:class:`~cablecheck.checker.advance.partpairs.PartSolids`),
            or None (their bounding radii alone).
        least: (N - 1,) the least pieces the checker splits each element
            into (`cablecheck.checker.cable.rest_pieces`), or None (those
            its length needs).

    Attributes:
        full, skipped: full checks started (or stopped) and states proven clear so far.
    """

    SPARSE_ENTRIES = 200_000
    """Above this many centre-part pairs the gaps are kept sparse (only the
    pairs within ``FAR_HORIZONS`` horizons); below, a dense table."""

    FAR_HORIZONS = FAR_HORIZONS

    def __init__(self, offsets: np.ndarray, spacing: np.ndarray, part_radius: np.ndarray,
                 clearance: float, stretch: float, radius: np.ndarray | None = None,
                 part_box: tuple[np.ndarray, np.ndarray] | None = None,
                 part_solids: PartSolids | None = None, least: np.ndarray | None = None):
        offsets = np.asarray(offsets, np.int64)
        cable_of_pt = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
        self._valid = cable_of_pt[:-1] == cable_of_pt[1:]
        self._offsets = offsets
        self._lim = np.asarray(spacing, float)[cable_of_pt[:-1]]
        # per element: the limit (inf between cables) and 1 for a real element
        self._lim_all = np.where(self._valid, self._lim, np.inf)
        # and the least pieces the checker splits it into (densify_batch's `least`; 1 between cables)
        self._least = np.ones(len(self._valid)) if least is None else np.where(self._valid, least, 1.0)
        self._validf = self._valid.astype(float)
        # the first element of every cable that has one: without radii the
        # stretch is summed per cable (an arc length moves with its own
        # cable's elements alone); with them over windows (see _stretch_runs)
        self._cable_first = offsets[:-1][np.diff(offsets) >= 2]
        rad = None if radius is None else np.asarray(radius, float)[cable_of_pt]
        box = None if part_box is None or radius is None else \
            (np.asarray(part_box[0], float)[:, None, :], np.asarray(part_box[1], float)[:, None, :])
        self.clearance = float(clearance)
        self.stretch = float(stretch)
        self._layout = Layout(offsets, cable_of_pt, self._valid, rad, box, np.asarray(part_radius, float),
                              self.clearance, self.stretch)
        self._pairs = PartPairGaps(part_radius, clearance, part_solids)
        self._since: Started | None = None          # the last start (None: before one, or stopped)
        z = np.zeros(0, np.int64)
        self._active = Active((z, z), (z, z))       # the pairs the caller evaluates, since the start
        self._promoted = 0                          # pairs promoted since the start
        self._step = 1                              # states per evaluation (doubling since the start)
        self.full = 0
        self.skipped = 0

    # the last start's state by its former names (tests read them)
    @property
    def _pts(self) -> np.ndarray:
        """(N, 3) the body centres at the last start."""
        return self._since.start.pts

    @property
    def _parts(self) -> CentrePartGaps:
        """The centre-part gaps of the last start."""
        return self._since.parts

    @property
    def _cable_gaps(self) -> CablePairGaps | None:
        """The cable-pair gaps of the last start (None: no cable candidates)."""
        return self._since.cable

    @property
    def _run_last(self) -> np.ndarray | None:
        """The stretch runs of the last start (:meth:`_stretch_runs`)."""
        return self._since.run_last

    def _proving(self, pts: np.ndarray) -> Started | None:
        """The last start, when it can prove states pts (S, N, 3) clear (some
        states, as many body centres as at the start); else None."""
        since = self._since
        if since is None or not since.ok or len(pts) == 0 or pts.shape[1] != len(since.start.pts):
            return None
        return since

    def start(self, pts: np.ndarray, poses: np.ndarray, gaps: Gaps, pairs: tuple[np.ndarray, np.ndarray],
              pair_bound: np.ndarray, active: tuple[np.ndarray, np.ndarray] | None = None,
              cable_active: np.ndarray | None = None) -> Active:
        """A full check ran at this state: cable body centres (N, 3) and part
        poses (P, 4, 4); the check's gaps (:class:`~cablecheck.checker.interference.hits.Gaps`,
        parts numbered as in ``poses``, inf for parts it does not check) and
        part pairs with their distance bounds (:func:`~cablecheck.checker.advance.partpairs.part_pair_bounds`).

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
        self.full += 1
        pts = np.array(pts, float)
        rot = np.array(poses[:, :3, :3], float)
        pos = np.array(poses[:, :3, 3], float)
        seg_raw = row_norm(pts[1:] - pts[:-1])
        # pieces per element, densify_batch's arithmetic (1 between cables)
        pieces = np.where(self._valid, element_pieces(seg_raw, self._lim, self._least), 1.0)
        scale = max(float(np.abs(pts).max(initial=0.0)), float(np.abs(pos).max(initial=0.0)))
        mu = 1e-9 * (1.0 + scale)
        g_cable = float(gaps.cable) - mu
        gap_part = np.asarray(gaps.part, float)
        n, n_p = len(pts), len(gap_part)
        # arc length of each centre, as densify_batch computes it
        s_c = polyline_arc_lengths(np.where(self._valid, seg_raw, 0.0), self._offsets)
        horizon = gaps.horizon
        start = Start(pts, rot, pos, seg_raw, s_c, mu, float(horizon))
        candidates = gaps.part_candidates
        sparse = (candidates is not None and self._layout.box is not None and n > 1 and horizon > 0
                  and n * n_p > self.SPARSE_ENTRIES)
        parts = CentrePartGaps(self._layout, start)
        structure = parts.start(gap_part, candidates, active, sparse)
        self._promoted = 0
        self._step = 1
        cable_gaps = None
        cable = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        if gaps.cable_candidates is not None:
            cable_gaps = CablePairGaps(self._layout, start)
            cable = cable_gaps.start(gaps.cable_candidates, float(horizon), mu, cable_active)
            cable_ok = cable_gaps.ok_at_start()             # the blocks' gaps on first use
        else:
            cable_ok = g_cable > 0
        self._pairs.start(poses, pairs, pair_bound, mu)
        ok = cable_ok and parts.ok_at_start() and self._pairs.ok and self.stretch > mu
        self._since = Started(start, pieces, self._stretch_runs(s_c), self.stretch - mu, g_cable, parts,
                              cable_gaps, ok)
        self._active = Active(structure, cable)
        return self._active

    def clear_run_local(self, pts: np.ndarray, poses: np.ndarray, budget: int) -> Cleared:
        """Like :meth:`clear_run`, but a pair whose own bound fails does not
        end the run: it is *promoted*, left out of the bound until the next
        start and handed to the caller with the active pairs, to evaluate
        at every state of the run (as it evaluates the active pairs). A run
        ends where a condition fails that names no pair (pieces, stretch,
        part pairs, the cable pairs' far limit, a centre past the sparse
        gaps' cap) or where the pairs promoted since the start would exceed
        ``budget`` (centre-part pairs plus pairs of body centres, a block
        pair counted as its (BLOCK + 1)^2 centre pairs): past that a full check
        costs less than evaluating them. With ``budget`` 0 it counts what
        :meth:`clear_run` counts.

        Why it is sound: a state passes when every pair either passes its
        bound (the package docstring) or is evaluated by the caller; a pair
        promoted at a later state of the run is evaluated at the earlier
        ones too (evaluating a pair that is clear adds no record).

        Each condition is evaluated on runs of states of doubling length,
        counted from the start across calls: a run that ends early after a
        start costs a state or two, and one that goes on is soon evaluated
        a whole call's states at a time (numpy's per-call overhead once)."""
        since = self._proving(pts)
        if since is None:
            return Cleared(0, self._active)
        z = np.zeros(0, np.int64)
        a, done, total = 0, 0, len(pts)
        structure, cable = [self._active.structure], [self._active.cable]
        n_parts, cable_gaps, parts = len(since.start.pos), since.cable, since.parts
        while a < total:
            b = min(a + self._step, total)
            x, move, dq, diag, dcc, d, seg = _states(pts[a:b], since.start.pts)
            # the conditions that name no pair first: pieces, stretch, part pairs
            pieces = element_pieces(seg, self._lim_all[:, None], self._least[:, None])
            n = leading((pieces == since.pieces[:, None]).all(axis=0) & self._stretch_ok(seg, since))
            dp = np.zeros((n_parts, n))
            if n and n_parts:
                dp = self._pairs.moves(poses[a:a + n]).T                   # (P, S)
                n = leading(self._pairs.clear(dp, poses[a:a + n]))
            if not n:
                break
            run = slice(0, n)
            if cable_gaps is not None:
                (near, cc, blocks), stop = cable_gaps.failing(
                    x[:, :, run], move[:, :, run], dcc[run], diag[run], d[:, :, run], seg[:, run])
            else:
                near = cc = (z, z)
                blocks = (z, z, z)
                stop = leading(dcc[run] < since.g_cable)
            if n_parts:
                centre, part, first, stop_p = parts.failing(x[:, :, run], poses[a:a + n], dq[:, run],
                                                             dp[:, run])
                stop = min(stop, stop_p)
            else:
                centre = part = first = z
            # pairs promoted per state, and the first state past the budget
            per = (np.bincount(first, minlength=n) + 4 * np.bincount(near[1], minlength=n)
                   + np.bincount(cc[1], minlength=n)
                   + (CablePairGaps.BLOCK + 1) ** 2 * np.bincount(blocks[2], minlength=n))
            over = self._promoted + np.cumsum(per) > budget
            m = min(stop, int(np.argmax(over)) if over.any() else n)
            take = first < m
            parts.promote(centre[take], part[take])
            structure.append((centre[take], part[take]))
            if cable_gaps is not None:
                ne, cc_k, on = near[0][near[1] < m], cc[0][cc[1] < m], blocks[2] < m
                cable_gaps.promote(ne, cc_k, blocks[0][on], blocks[1][on])
                cable.append(cable_gaps.centre_pairs(ne, cc_k, blocks[0][on], blocks[1][on]))
            self._promoted += int(per[:m].sum())
            done = a + m
            if m < b - a:
                break
            a = b
            self._step *= 2
        self.skipped += done
        if len(structure) > 1 or len(cable) > 1:
            n_c = len(since.start.pts)
            self._active = Active(_union(structure, n_c), _union(cable, n_c))
        return Cleared(done, self._active)

    def _stretch_runs(self, s_c: np.ndarray) -> np.ndarray | None:
        """(N - 1,): for each element e the last element of the run [e, L]
        whose total change of length the stretch condition bounds, or None
        (no radii: whole cables).

        Which runs matter. Self pairs: two places on elements e <= f of one
        cable that were inside the exclusion window deeper than ``stretch``
        at the start (so no candidate) had the elements between them shorter
        in all than the window ``w = pi r + clearance``; their arc-length
        separation changed by at most the change of elements e .. f. The
        chord bound: the arc from centre e + 1 to centre f of a near pair (f
        < e + 2 BLOCK) changed by at most that of elements e + 1 .. f - 1. So
        L is the last element f of e's cable with ``s_c[f] - s_c[e + 1] < w
        + stretch`` (widened: a longer run only bounds more), and at least e
        + 2 BLOCK."""
        rad = self._layout.rad
        if rad is None or len(s_c) < 2:
            return None
        n = len(s_c)
        e = np.arange(n - 1)
        cable = self._layout.cable
        last = self._offsets[cable[e] + 1] - 2                      # the cable's last element
        w = np.pi * rad[e] + self.clearance + self.stretch
        width = 2.0 * (float(s_c.max(initial=0.0)) + float(w.max(initial=0.0))) + 1.0
        key = cable * width + s_c
        reach = np.searchsorted(key, key[np.minimum(e + 1, n - 1)] + w + 1e-9 * width, "left") - 1
        run = np.maximum(reach, e + 2 * CablePairGaps.BLOCK)
        return np.where(self._valid, np.minimum(run, last), e)

    def _stretch_ok(self, seg: np.ndarray, since: Started) -> np.ndarray:
        """Per state (S,): the stretch condition: the element lengths of
        every run of :meth:`_stretch_runs` (without radii: of every cable)
        changed by at most ``stretch`` in total since the start ``since``;
        seg (N - 1, S) the element lengths (between cables too, left out).
        The runs' sums are differences of one cumulative sum (its rounding,
        ~1e-16 of all the changes, far below the margin)."""
        change = self._validf[:, None] * np.abs(seg - since.start.seg[:, None])
        if since.run_last is not None:
            total = np.concatenate([np.zeros((1, seg.shape[1])), np.cumsum(change, axis=0)])
            runs = total[since.run_last + 1] - total[:-1]
            return (runs < since.stretch).all(axis=0)
        if not len(self._cable_first):
            return np.ones(seg.shape[1], bool)
        return (np.add.reduceat(change, self._cable_first, axis=0) < since.stretch).all(axis=0)

    def stop(self) -> None:
        """A full check ran without gaps: prove nothing until the next :meth:`start`."""
        self.full += 1
        self._since = None
        self._pairs.stop()

    def start_pairs(self, poses: np.ndarray, pairs: tuple[np.ndarray, np.ndarray],
                    pair_bound: np.ndarray) -> None:
        """Restart the part-pair condition alone (:meth:`part_pairs_clear`)
        at this state: after a full check whose cable checks left no gaps
        (a pair inside the clearance), the part-part check can still be
        proven clear on later full checks. (:meth:`start` restarts it too,
        with its own rounding margin.)"""
        self._pairs.start(poses, pairs, pair_bound)

    def part_pairs_clear(self, poses: np.ndarray) -> bool:
        """True when no moving part pair can be within the clearance (the
        part-pair condition of the package docstring alone): the part-part
        check's answer is then its same-body records only, even on a step
        whose cable checks run in full."""
        return self._pairs.clear_at(poses)

    def part_pairs_failing(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The moving part pairs whose bound fails at poses (the others
        provably outside the clearance), or None when no bound holds."""
        return self._pairs.failing_at(poses)

    def proven_clear(self, pts: np.ndarray, poses: np.ndarray) -> bool:
        """True when no pair can be within the clearance at one state (body
        centres (N, 3), part poses (P, 4, 4)); counts it as skipped then."""
        return self.clear_run(np.asarray(pts)[None], np.asarray(poses)[None]) == 1

    def clear_run(self, pts: np.ndarray, poses: np.ndarray) -> int:
        """How many leading states of a run of consecutive states (body
        centres (S, N, 3), part poses (S, P, 4, 4)) are proven clear (package
        docstring); counts them as skipped.

        Vectorised over the states: numpy's cost per call, not the arrays'
        size, dominates for a cable's few dozen centres, so a batch of
        states costs about what one does. The states are laid out last
        ((N, 3, S)): numpy reduces and gathers along a leading axis far
        faster than along a short middle one. Every part is handled alike
        (a part that did not move has ``rel`` equal to ``dq`` up to
        rounding, far below the margin). After each condition only the
        states up to the first failure are carried on."""
        since = self._proving(pts)
        if since is None:
            return 0
        x = np.ascontiguousarray(np.transpose(pts, (1, 2, 0)))           # (N, 3, S)
        move = x - since.start.pts[:, :, None]
        dq = row_norm3(move)                                              # (N, S)
        if len(move):
            spread = move.max(axis=0) - move.min(axis=0)                 # (3, S)
            diag = np.sqrt(np.einsum("is,is->s", spread, spread))
            dcc = np.minimum(2.0 * dq.max(axis=0), diag)
        else:
            diag = dcc = np.zeros(x.shape[2])
        d = x[1:] - x[:-1]                                                # (N - 1, 3, S)
        seg = row_norm3(d)
        ok = since.cable.clear(x, move, dcc, diag, d, seg) if since.cable is not None else dcc < since.g_cable
        n = leading(ok)
        if n:
            x, seg = x[:, :, :n], seg[:, :n]
            # every element still splits into as many pieces (elements
            # joining two cables: limit inf, 1 piece at the start and now)
            pieces = element_pieces(seg, self._lim_all[:, None], self._least[:, None])
            ok = (pieces == since.pieces[:, None]).all(axis=0) & \
                self._stretch_ok(seg, since)
            n = leading(ok)
        if n and len(since.start.pos):
            poses = poses[:n]
            dp = self._pairs.moves(poses).T                                # (P, S)
            ok = since.parts.clear(x[:, :, :n], poses, dq[:, :n], dp) & self._pairs.clear(dp, poses)
            n = leading(ok)
        self.skipped += n
        return n


def _union(pairs: list[tuple[np.ndarray, np.ndarray]], n: int) -> tuple[np.ndarray, np.ndarray]:
    """The distinct pairs of a list of (first, second) arrays, sorted by
    (second, first); ``n`` bounds the first."""
    first = np.concatenate([np.asarray(p[0], np.int64) for p in pairs])
    second = np.concatenate([np.asarray(p[1], np.int64) for p in pairs])
    key = np.unique(second * n + first)
    return key % n, key // n


def _states(pts: np.ndarray, start: np.ndarray) -> tuple:
    """What the conditions read of states pts (S, N, 3), the start's centres
    ``start`` (N, 3): the centres laid out last x (N, 3, S), their moves
    and the moves' lengths dq (N, S), the bounds on any two centres'
    relative move (the bounding box's diagonal, and the least of it and
    twice the largest dq) (S,), the elements d (N - 1, 3, S) and their
    lengths (N - 1, S)."""
    x = np.ascontiguousarray(np.transpose(pts, (1, 2, 0)))
    move = x - start[:, :, None]
    dq = row_norm3(move)
    if len(move):
        spread = move.max(axis=0) - move.min(axis=0)
        diag = np.sqrt(np.einsum("is,is->s", spread, spread))
        dcc = np.minimum(2.0 * dq.max(axis=0), diag)
    else:
        diag = dcc = np.zeros(x.shape[2])
    d = x[1:] - x[:-1]
    return x, move, dq, diag, dcc, d, row_norm3(d)
