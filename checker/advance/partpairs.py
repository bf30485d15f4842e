"""The skip rule's bound on part pairs (part-part, keep-out between parts).

Two rigid parts that may move relative to each other stay apart while the
sum of how far any point of each moved is below a lower bound on their
distance at the full check: the separation of their oriented boxes along a
box axis (:func:`part_pair_bounds`).

Deliberately not here: cables, the run of states
(:class:`checker.advance.skip.Advancement`), the part-part check itself
(:mod:`checker.parts`).
"""

from __future__ import annotations

import numpy as np

from checker.partset import PartSet, Placement


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


class PartPairGaps:
    """The part-pair condition, restarted at every full check.

    Args:
        part_radius: (P,) bounding radius of each part about its frame's
            origin (inf for planes).
        clearance: the clearance.
    """

    def __init__(self, part_radius: np.ndarray, clearance: float):
        self._rho = np.asarray(part_radius, float)
        self.clearance = float(clearance)
        self.ok = False
        """True while the last start proved every pair apart (else nothing is proven)."""

    def start(self, poses: np.ndarray, pairs: tuple[np.ndarray, np.ndarray],
              pair_bound: np.ndarray, mu: float | None = None) -> None:
        """Restart at this state: part poses (P, 4, 4), the moving part pairs
        (i, j) and lower bounds on their distances (:func:`part_pair_bounds`);
        ``mu`` the rounding margin (None: from the poses)."""
        self._poses = np.array(poses, float)
        self._pi, self._pj = pairs
        if mu is None:
            mu = 1e-9 * (1.0 + float(np.abs(self._poses[:, :3, 3]).max(initial=0.0)))
        self._g_pair = np.asarray(pair_bound, float) - self.clearance - mu
        self.ok = bool(np.all(self._g_pair > 0))

    def stop(self) -> None:
        """Prove nothing until the next :meth:`start`."""
        self.ok = False

    def moves(self, poses: np.ndarray) -> np.ndarray:
        """dp (..., P): how far any point of each part moved since the start
        (poses (..., P, 4, 4))."""
        dpose = poses - self._poses
        d_rot, d_pos = dpose[..., :3, :3], dpose[..., :3, 3]
        fro = np.sqrt(np.einsum("...ij,...ij->...", d_rot, d_rot))
        dp = np.sqrt(np.einsum("...i,...i->...", d_pos, d_pos))
        dp += np.multiply(fro, self._rho, out=np.zeros_like(fro), where=fro > 0)   # plane turned: inf
        return dp

    def clear(self, dp: np.ndarray) -> np.ndarray:
        """The condition per state (S,) from the parts' moves dp (P, S) (:meth:`moves`)."""
        if not len(self._pi):
            return np.ones(dp.shape[1], bool)
        return (dp[self._pi] + dp[self._pj] < self._g_pair[:, None]).all(axis=0)

    def clear_at(self, poses: np.ndarray) -> bool:
        """True when no moving part pair can be within the clearance (the
        part-pair condition of the package docstring alone): the part-part
        check's answer is then its same-body records only, even on a step
        whose cable checks run in full."""
        if not self.ok or len(poses) != len(self._poses):
            return False
        dp = self.moves(poses)
        return not len(self._pi) or bool(np.all(dp[self._pi] + dp[self._pj] < self._g_pair))

    def failing_at(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The moving part pairs (i, j) whose bound fails at poses (every
        other pair is provably outside the clearance), or None when no pair
        is bounded (before a start, or the part count changed)."""
        if not self.ok or len(poses) != len(self._poses):
            return None
        if not len(self._pi):
            return self._pi[:0], self._pj[:0]
        dp = self.moves(poses)
        fail = ~(dp[self._pi] + dp[self._pj] < self._g_pair)
        return self._pi[fail], self._pj[fail]
