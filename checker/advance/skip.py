"""The skip rule's state machine: :class:`Advancement`, restarted at every full check.

A full check starts the bound (:meth:`Advancement.start`) from its gaps; each
later state is tested (:meth:`Advancement.clear_run`, many consecutive states
at once) against the conditions of the package docstring: cable pairs
(:mod:`~checker.advance.cablepairs`), cables against parts
(:mod:`~checker.advance.structure`), part pairs
(:mod:`~checker.advance.partpairs`), and here the elements' pieces and
stretch. The pairs the caller evaluates itself (*active*) come back from
:meth:`Advancement.start` as an :class:`Active` record.

Deliberately not here: the arithmetic of the three conditions, the checks
themselves, any simulator.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from checker.advance.cablepairs import CablePairGaps
from checker.advance.common import FAR_HORIZONS, Layout, Start, leading, row_norm3
from checker.advance.partpairs import PartPairGaps, PartSolids
from checker.advance.structure import CentrePartGaps
from checker.cable import element_pieces, polyline_arc_lengths
from checker.closest import row_norm
from checker.interference.hits import Gaps


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
            the part-pair condition (:class:`~checker.advance.partpairs.PartSolids`),
            or None (their bounding radii alone).

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
                 part_solids: PartSolids | None = None):
        offsets = np.asarray(offsets, np.int64)
        cable_of_pt = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
        self._valid = cable_of_pt[:-1] == cable_of_pt[1:]
        self._offsets = offsets
        self._lim = np.asarray(spacing, float)[cable_of_pt[:-1]]
        # per element: the limit (inf between cables) and 1 for a real element
        self._lim_all = np.where(self._valid, self._lim, np.inf)
        self._validf = self._valid.astype(float)
        rad = None if radius is None else np.asarray(radius, float)[cable_of_pt]
        box = None if part_box is None or radius is None else \
            (np.asarray(part_box[0], float)[:, None, :], np.asarray(part_box[1], float)[:, None, :])
        self.clearance = float(clearance)
        self.stretch = float(stretch)
        self._layout = Layout(offsets, cable_of_pt, self._valid, rad, box, np.asarray(part_radius, float),
                              self.clearance, self.stretch)
        self._pairs = PartPairGaps(part_radius, clearance, part_solids)
        self._ok = False
        self.full = 0
        self.skipped = 0

    def start(self, pts: np.ndarray, poses: np.ndarray, gaps: Gaps, pairs: tuple[np.ndarray, np.ndarray],
              pair_bound: np.ndarray, active: tuple[np.ndarray, np.ndarray] | None = None,
              cable_active: np.ndarray | None = None) -> Active:
        """A full check ran at this state: cable body centres (N, 3) and part
        poses (P, 4, 4); the check's gaps (:class:`~checker.interference.hits.Gaps`,
        parts numbered as in ``poses``, inf for parts it does not check) and
        part pairs with their distance bounds (:func:`~checker.advance.partpairs.part_pair_bounds`).

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
        self._pts = np.array(pts, float)
        rot = np.array(poses[:, :3, :3], float)
        self._pos = pos = np.array(poses[:, :3, 3], float)
        self._seg_raw = row_norm(self._pts[1:] - self._pts[:-1])
        # pieces per element, densify_batch's arithmetic (1 between cables)
        self._pieces_all = np.where(self._valid, element_pieces(self._seg_raw, self._lim), 1.0)
        scale = max(float(np.abs(self._pts).max(initial=0.0)), float(np.abs(pos).max(initial=0.0)))
        mu = 1e-9 * (1.0 + scale)
        self._g_cable = float(gaps.cable) - mu
        gap_part = np.asarray(gaps.part, float)
        n, n_p = len(self._pts), len(gap_part)
        # arc length of each centre, as densify_batch computes it
        s_c = polyline_arc_lengths(np.where(self._valid, self._seg_raw, 0.0), self._offsets)
        horizon = gaps.horizon
        start = Start(self._pts, rot, pos, self._seg_raw, s_c, mu, float(horizon))
        candidates = gaps.part_candidates
        sparse = (candidates is not None and self._layout.box is not None and n > 1 and horizon > 0
                  and n * n_p > self.SPARSE_ENTRIES)
        self._parts = CentrePartGaps(self._layout, start)
        structure = self._parts.start(gap_part, candidates, active, sparse)
        self._cable_pairs = gaps.cable_candidates is not None
        cable = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        if self._cable_pairs:
            self._cable_gaps = CablePairGaps(self._layout, start)
            cable = self._cable_gaps.start(gaps.cable_candidates, float(horizon), mu, cable_active)
            cable_ok = self._cable_gaps.ok_at_start()             # the blocks' gaps on first use
        else:
            cable_ok = self._g_cable > 0
        self._pairs.start(poses, pairs, pair_bound, mu)
        self._stretch = self.stretch - mu
        self._ok = cable_ok and self._parts.ok_at_start() and self._pairs.ok and self.stretch > mu
        return Active(structure, cable)

    def stop(self) -> None:
        """A full check ran without gaps: prove nothing until the next :meth:`start`."""
        self.full += 1
        self._ok = False
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
        ok = self._cable_gaps.clear(x, move, dcc, diag, d, seg) if self._cable_pairs else dcc < self._g_cable
        n = leading(ok)
        if n:
            x, seg = x[:, :, :n], seg[:, :n]
            # every element still splits into as many pieces (elements
            # joining two cables: limit inf, 1 piece at the start and now)
            pieces = element_pieces(seg, self._lim_all[:, None])
            ok = (pieces == self._pieces_all[:, None]).all(axis=0) & \
                (self._validf @ np.abs(seg - self._seg_raw[:, None]) < self._stretch)
            n = leading(ok)
        if n and len(self._pos):
            poses = poses[:n]
            dp = self._pairs.moves(poses).T                                # (P, S)
            ok = self._parts.clear(x[:, :, :n], poses, dq[:, :n], dp) & self._pairs.clear(dp, poses)
            n = leading(ok)
        self.skipped += n
        return n
