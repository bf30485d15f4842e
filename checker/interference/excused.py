"""What the attachment windows excuse: the piece of cable in each window measured against its part.

The checks leave the points (and, with method ``exact``, the elements) of a
cable that lie inside an attachment window
(:class:`~cablecheck.checker.scene_state.Exclusion`) out of that window's part: a cable
touching the clamp or connector it is fastened in is no clash. So that
nothing is excused silently, :class:`ExcusedLog` measures exactly that piece
of cable against exactly that part at every checked state, and keeps each
window's worst moment below the clearance: what a report lists as
``excused``.

The measure is exact whatever the check's method: the least signed distance
along each element of the window
(:func:`~cablecheck.checker.interference.structure.segment_distances`) less the cable
radius, as method ``exact`` measures a cable against a part. An element is in
a window exactly when its midpoint's material coordinate is (the windows are
widened to whole elements). Elements that provably stay beyond the clearance
(their box, then their midpoint's distance less half their length) are not
searched.

Deliberately not here: which parts a window excuses (the scene's fastening,
``cablecheck.run.stepcheck.attachment_exclusions``), and events: an excused contact
never makes one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cablecheck.checker.interference.structure import PartTable, segment_distances, segments_within
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import Exclusion, PartState


@dataclass(frozen=True)
class ExcusedWorst:
    """An excused contact's worst moment over a run.

    Attributes:
        type: cable-structure, or keepout for a keep-out zone.
        a: the cable; b: the part its window excuses.
        window: the window ("start", "end", "clip N").
        min_distance: the least signed surface distance of the window's
            piece of cable to the part (centreline distance less the
            radius; negative inside), metres.
        t: when (the first checked state at that distance), seconds.
        where: (3,) the worst point on the cable's centreline, world.
        s: its material coordinate (rest arc length) along the cable.
    """

    type: PairType
    a: str
    b: str
    window: str
    min_distance: float
    t: float
    where: np.ndarray
    s: float


class ExcusedLog:
    """The worst moment of every attachment window against its part, over
    the states it is given (oldest first).

    Args:
        exclusions: the run's windows.
        parts: the checked parts (their shapes; poses come with each batch).
        cables: the cables' names, in the order of ``offsets``.
        offsets: (C + 1,) each cable's first body centre.
        rest: (N,) every body centre's material coordinate.
        radii: (C,) cable radii.
        clearance: contacts at or beyond it are not listed.
    """

    def __init__(self, exclusions: Sequence[Exclusion], parts: Sequence[PartState], cables: Sequence[str],
                 offsets: np.ndarray, rest: np.ndarray, radii: np.ndarray, clearance: float):
        part_index = {p.name: k for k, p in enumerate(parts)}
        cable_index = {n: j for j, n in enumerate(cables)}
        self.windows = [e for e in exclusions if e.part in part_index and e.cable in cable_index]
        self.clearance = clearance
        self._tab = PartTable(parts) if self.windows else None
        rows, wins = [], []
        for w, e in enumerate(self.windows):     # prepared once per run, a few windows
            j = cable_index[e.cable]
            first = np.arange(offsets[j], offsets[j + 1] - 1)
            mid = 0.5 * (rest[first] + rest[first + 1])
            inside = first[(mid >= min(e.s_min, e.s_max)) & (mid <= max(e.s_min, e.s_max))]
            rows.append(inside)
            wins.append(np.full(len(inside), w))
        self._first = np.concatenate(rows).astype(np.int64) if rows else np.zeros(0, np.int64)
        self._window = np.concatenate(wins).astype(np.int64) if wins else np.zeros(0, np.int64)
        cable_of = np.array([cable_index[e.cable] for e in self.windows], np.int64)
        win_part = np.array([part_index[e.part] for e in self.windows], np.int64)
        self._keepout = [bool(parts[k].keepout) for k in win_part.tolist()]
        self._part = win_part[self._window]
        self._radius = np.asarray(radii, float)[cable_of][self._window] if len(self.windows) else np.zeros(0)
        self._rest = np.asarray(rest, float)
        self._best = np.full(len(self.windows), np.inf)
        self._t = np.zeros(len(self.windows))
        self._where = np.zeros((len(self.windows), 3))
        self._s = np.zeros(len(self.windows))

    def __bool__(self) -> bool:
        return bool(self.windows)

    def add(self, times: np.ndarray, pts: np.ndarray, poses: np.ndarray) -> None:
        """States at ``times`` (S,): body centres ``pts`` (S, N, 3) and the
        checked parts' poses (S, K, 4, 4)."""
        n_s, n_r = len(times), len(self._first)
        if n_s == 0 or n_r == 0:
            return
        tab = self._tab
        i0 = self._first
        state = np.repeat(np.arange(n_s), n_r)
        pk = np.tile(self._part, n_s)
        rad = np.tile(self._radius, n_s)
        placed = poses[:, self._part]                                    # (S, R, 4, 4)
        rot = placed[:, :, :3, :3].reshape(-1, 3, 3)
        trans = placed[:, :, :3, 3].reshape(-1, 3)
        wa, wb = pts[:, i0].reshape(-1, 3), pts[:, i0 + 1].reshape(-1, 3)
        a = np.einsum("ni,nij->nj", wa - trans, rot)
        b = np.einsum("ni,nij->nj", wb - trans, rot)
        idx, mid = segments_within(tab, pk, a, b, rad, self.clearance, midpoints=True)   # the others provably beyond it
        if len(idx) == 0:
            return
        d, t = segment_distances(tab, pk[idx], a[idx], b[idx], mid)
        value = d - rad[idx]
        below = value < self.clearance
        idx, value, t = idx[below], value[below], t[below]
        if len(idx) == 0:
            return
        win = np.tile(self._window, n_s)[idx]
        # each window's least value, the earliest state on a tie
        o = np.lexsort((state[idx], value, win))
        lead = o[np.r_[True, win[o][1:] != win[o][:-1]]]
        w = win[lead]
        better = value[lead] < self._best[w]
        lead, w = lead[better], w[better]
        k = idx[lead]
        r = k % n_r
        self._best[w] = value[lead]
        self._t[w] = np.asarray(times, float)[state[k]]
        self._where[w] = wa[k] + t[lead, None] * (wb[k] - wa[k])
        rest = self._rest
        self._s[w] = rest[i0[r]] + t[lead] * (rest[i0[r] + 1] - rest[i0[r]])

    def worst(self) -> tuple[ExcusedWorst, ...]:
        """Every window that came below the clearance, with its worst moment."""
        return tuple(ExcusedWorst(PairType.KEEPOUT if self._keepout[w] else PairType.CABLE_STRUCTURE,
                                  e.cable, e.part, e.window, float(self._best[w]), float(self._t[w]),
                                  self._where[w].copy(), float(self._s[w]))
                     for w, e in enumerate(self.windows) if np.isfinite(self._best[w]))
