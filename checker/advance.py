"""Conservative advancement: steps on which no pair can have come within the clearance.

After a full check at step k0 the checker knows, up to a horizon H, how far
every pair stays from the clearance (:attr:`checker.interference.Checker.gaps`,
its ``part_candidates`` and :func:`part_pair_bounds`). On a later step k, with

- ``d_i``: the displacement of cable body centre i since k0, ``dq_i = |d_i|``,
- ``spread``: the diagonal of the bounding box of all ``d_i`` (at least
  ``|d_a - d_b|`` for any two centres; ``min(spread, 2 max dq)`` is used),
- ``u_i^k``: centre i in part k's own frame, ``R_k^T (x_i - t_k)``, and
  ``rel[i, k] = |u_i^k(k) - u_i^k(k0)|`` its displacement relative to part k,
- ``dp[k]``: a bound on how far any point of part k moved since k0, its
  translation plus ``||R - R0||_F`` times the part's bounding radius about
  its frame's origin (a plane that rotated: unbounded),
- ``g[i, k]``: centre i's gap to part k: the smallest value minus the
  clearance of part k's candidates on the elements next to centre i, H where
  there is none (capped at H),

no pair can have come within the clearance while

- ``spread < gap_cable`` (self and cable-cable),
- ``dq_i < g[i, k]`` for every part k that did not move, and
  ``min(rel[i, k], dq_i + dp[k]) < g[i, k]`` for every part k that moved
  (cable-structure, keep-out),
- ``dp[i] + dp[j] < bound[i, j] - clearance`` for every part pair that can
  move relative to the other (part-part, keep-out between parts),
- every cable element splits into the same number of discrete points as at
  k0, and the cables' element lengths changed by at most ``stretch`` in
  total (summed over elements).

Proof sketch. With the same number of pieces per element, every discrete
point (and every element midpoint, and every point of a piece) is the same
convex combination of the same two body centres as at k0, in the world and
in any part's frame alike (the maps are affine); so its displacement is the
same combination of the two centres' displacements: at most the larger of
their ``dq`` (or ``rel``), and the difference of two such displacements lies
within the bounding box's diagonal. A point of a rigid part moved by at most
``dp``. Every value checked is a distance between two cable points, or a
point's distance to a rigid solid, minus fixed radii: a 1-Lipschitz function
of the places, so it dropped by at most ``|d_a - d_b|`` (cable pairs), and
by at most the point's displacement in the part's own frame, or the point's
plus the part's displacement in the world (cable and part; a point outside a
solid with distance above the clearance stays outside, where the signed
distance is the distance). At k0 every candidate value below ``clearance +
H`` was evaluated, and each part candidate is charged to every centre of the
element holding its arc length (with a rounding margin: more centres only
lower the gaps); a point with no candidate for part k was at least H past
the clearance from it. Exclusions are windows in arc length (self: ``|s_a -
s_b| < pi r + clearance``; attachments: fixed windows), and an arc length
moved by at most the total change of element lengths; the gaps at k0
therefore include candidates up to ``stretch`` inside every window, so none
that left a window since was unaccounted for. Part pairs: the least distance
of their triangles is at least the separation of their oriented boxes on any
box axis (or, for a plane, the box's lowest point above it), which
:func:`part_pair_bounds` takes at k0. Rounding is absorbed by a margin of
1e-9 of the scene's extent.

So on such a step the pairwise checks (and the simulator's detection used to
validate them) can be skipped: their answer is "no pair below the
clearance", exactly what a full check would return. Single-cable checks
(bend, taut) still run every step. Method ``exact`` (closest points whose
exclusion can change discontinuously) and the face-plane distance never
skip.

This module holds only the bound; it takes arrays and knows no simulator.
"""

from __future__ import annotations

import numpy as np

from checker.closest import row_norm
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


class Advancement:
    """The bound of the module docstring, restarted at every full check.

    Args:
        offsets: (C + 1,) start of each cable in the concatenated body centres.
        spacing: (C,) largest discrete element length per cable (as the checker).
        part_radius: (P,) bounding radius of each part about its frame's
            origin (inf for planes).
        clearance: the clearance (part pairs' bounds are distances).
        stretch: total change of element lengths allowed (the checker's).
    """

    def __init__(self, offsets: np.ndarray, spacing: np.ndarray, part_radius: np.ndarray,
                 clearance: float, stretch: float):
        offsets = np.asarray(offsets, np.int64)
        cable_of_pt = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
        self._valid = cable_of_pt[:-1] == cable_of_pt[1:]
        self._offsets = offsets
        self._cable = cable_of_pt
        self._first = offsets[:-1]
        self._lim = np.asarray(spacing, float)[cable_of_pt[:-1]]
        self._rho = np.asarray(part_radius, float)
        self.clearance = float(clearance)
        self.stretch = float(stretch)
        self._ok = False
        self.full = 0
        self.skipped = 0

    def _elements(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        seg = row_norm(pts[1:] - pts[:-1])
        self._seg_raw = seg
        # the same arithmetic as checker.cable.densify_batch
        pieces = np.where(self._valid, np.maximum(1, np.ceil(seg / self._lim * (1.0 - 1e-12))), 0)
        return np.where(self._valid, seg, 0.0), pieces

    def start(self, pts: np.ndarray, poses: np.ndarray, gap_cable: float, gap_part: np.ndarray,
              pairs: tuple[np.ndarray, np.ndarray], pair_bound: np.ndarray,
              candidates: tuple[np.ndarray, ...] | None = None, horizon: float = 0.0) -> None:
        """A full check ran at this state: cable body centres (N, 3) and part
        poses (P, 4, 4); the checker's gaps (cable, per part (P,), inf for
        parts it does not check) and part pairs with their distance bounds.

        ``candidates``: the checker's cable-structure and keep-out candidates
        (cable, arc length, part index in ``poses``, value - clearance) found
        up to ``horizon`` past the clearance; with them the part gaps are
        kept per body centre (the smallest over the elements next to it,
        ``horizon`` where there is none), else every centre gets the part's gap."""
        self.full += 1
        self._pts = np.array(pts, float)
        self._rot = np.array(poses[:, :3, :3], float)
        self._pos = np.array(poses[:, :3, 3], float)
        self._seg, self._pieces = self._elements(self._pts)
        scale = max(float(np.abs(self._pts).max(initial=0.0)), float(np.abs(self._pos).max(initial=0.0)))
        mu = 1e-9 * (1.0 + scale)
        self._g_cable = float(gap_cable) - mu
        gap_part = np.asarray(gap_part, float)
        self._g_part = gap_part - mu
        n, n_p = len(self._pts), len(gap_part)
        if candidates is None:
            g = np.broadcast_to(gap_part, (n, n_p)).copy()
        else:
            g = np.where(np.isfinite(gap_part), float(horizon), np.inf)[None, :].repeat(n, 0)
            cab, s, part, value = candidates
            if len(value):
                # a candidate at arc length s lies on an element whose centres
                # bracket s (at k0's arc lengths, as densify_batch computes them);
                # widened by a rounding margin, more centres only lower the gaps
                cum = np.concatenate([[0.0], np.cumsum(np.where(self._valid, self._seg_raw, 0.0))])
                s_c = cum - cum[self._first][self._cable]
                width = 2.0 * (float(s_c.max(initial=0.0)) + float(np.abs(s).max())) + 1.0
                key_c = self._cable * width + s_c
                key = cab * width + s
                eps = 1e-9 * width * (1 + len(self._offsets))
                lo = np.maximum(np.searchsorted(key_c, key - eps, "left") - 1, self._offsets[cab])
                hi = np.minimum(np.searchsorted(key_c, key + eps, "right"), self._offsets[cab + 1] - 1)
                count = hi - lo + 1
                rows = np.repeat(lo, count) + (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count))
                np.minimum.at(g, (rows, np.repeat(part, count)), np.repeat(value, count))
                g = np.minimum(g, horizon)
        self._g_pt = g - mu
        self._g_static = {}
        self._u0 = {}
        self._pi, self._pj = pairs
        self._g_pair = np.asarray(pair_bound, float) - self.clearance - mu
        self._stretch = self.stretch - mu
        self._ok = (self._g_cable > 0 and bool(np.all(self._g_pt > 0))
                    and bool(np.all(self._g_pair > 0)) and self.stretch > mu)

    def stop(self) -> None:
        """A full check ran without gaps: prove nothing until the next :meth:`start`."""
        self.full += 1
        self._ok = False

    def proven_clear(self, pts: np.ndarray, poses: np.ndarray) -> bool:
        """True when no pair can be within the clearance (module docstring);
        counts the step as skipped then."""
        if not self._ok or len(pts) != len(self._pts):
            return False
        move = pts - self._pts
        dq = row_norm(move)
        dc = float(dq.max(initial=0.0))
        if len(move):
            spread = move.max(axis=0) - move.min(axis=0)
            dcc = min(2.0 * dc, float(np.sqrt(spread @ spread)))
        else:
            dcc = 0.0
        if not dcc < self._g_cable:
            return False
        seg, pieces = self._elements(pts)
        if np.any(pieces != self._pieces) or not np.abs(seg - self._seg).sum() < self._stretch:
            return False
        if len(self._pos):
            rot, pos = poses[:, :3, :3], poses[:, :3, 3]
            moved = np.any(rot != self._rot, axis=(1, 2)) | np.any(pos != self._pos, axis=1)
            key = moved.tobytes()
            g_static = self._g_static.get(key)
            if g_static is None:
                g_static = self._g_static[key] = self._g_pt[:, ~moved].min(axis=1, initial=np.inf)
            if not np.all(dq < g_static):
                return False
            if moved.any():
                m = np.nonzero(moved)[0]
                d_rot = rot[m] - self._rot[m]
                fro = np.sqrt(np.einsum("kij,kij->k", d_rot, d_rot))
                dp_m = row_norm(pos[m] - self._pos[m]) + np.where(fro > 0, fro * self._rho[m], 0.0)
                # each centre in each moving part's own frame
                key_m = m.tobytes()
                u0 = self._u0.get(key_m)
                if u0 is None:
                    u0 = self._u0[key_m] = (self._pts[None] - self._pos[m][:, None]) @ self._rot[m]
                du = (pts[None] - pos[m][:, None]) @ rot[m] - u0   # rows R^T (x - t)
                rel = np.sqrt((du[..., 0] * du[..., 0] + du[..., 1] * du[..., 1]) + du[..., 2] * du[..., 2])
                bound = np.minimum(rel, dq[None, :] + dp_m[:, None])
                if not np.all(bound < self._g_pt[:, m].T):
                    return False
                if len(self._pi):
                    d_rot = rot - self._rot
                    fro = np.sqrt(np.einsum("kij,kij->k", d_rot, d_rot))
                    dp = row_norm(pos - self._pos) + np.where(fro > 0, fro * self._rho, 0.0)
                    if not np.all(dp[self._pi] + dp[self._pj] < self._g_pair):
                        return False
        self.skipped += 1
        return True
