"""What every part of the skip rule shares: the run's layout, one start's state, small helpers.

:class:`Layout` is fixed for a run (which body centre is on which cable,
radii, the parts' boxes); :class:`Start` is the state of one full check the
bound restarts from. :func:`bracket` finds the body centres around an arc
length, as the candidates of a check give them.

Deliberately not here: any condition of the bound (see the package docstring).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

FAR_HORIZONS = 8.0
"""Pairs nearer than this many horizons are kept one by one; the others
share a coarser bound (block pairs: the whole displacement spread; centre and
part: the cap of the sparse gaps)."""


@dataclass(frozen=True)
class Layout:
    """The run's cables and parts as the bound sees them (fixed for a run).

    Attributes:
        offsets: (C + 1,) start of each cable in the concatenated body centres.
        cable: (N,) cable of each centre.
        valid: (N - 1,) element i joins centres i and i + 1 of one cable.
        rad: (N,) cable radius at each centre, or None (not known).
        box: ((P, 1, 3), (P, 1, 3)) each part's bounds in its own frame, or None.
        rho: (P,) bounding radius of each part about its frame's origin (inf for planes).
        clearance: the clearance.
        stretch: total change of element lengths allowed.
    """

    offsets: np.ndarray
    cable: np.ndarray
    valid: np.ndarray
    rad: np.ndarray | None
    box: tuple[np.ndarray, np.ndarray] | None
    rho: np.ndarray
    clearance: float
    stretch: float


@dataclass(frozen=True)
class Start:
    """The state a start of the bound takes.

    Attributes:
        pts: (N, 3) body centres.
        rot, pos: (P, 3, 3) and (P, 3) the parts' rotations and positions.
        seg: (N - 1,) element lengths (also between cables).
        s_c: (N,) arc length of each centre along its cable (as
            :func:`cablecheck.checker.cable.densify_batch` computes it).
        mu: the rounding margin (1e-9 of the scene's extent).
        horizon: the check's horizon.
    """

    pts: np.ndarray
    rot: np.ndarray
    pos: np.ndarray
    seg: np.ndarray
    s_c: np.ndarray
    mu: float
    horizon: float


def bracket(s_c: np.ndarray, cable: np.ndarray, offsets: np.ndarray, cab: np.ndarray,
            s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First and last body centre (n,) of the element(s) holding arc length
    s on cable cab, at the start's arc lengths ``s_c`` of the centres of
    cables ``cable`` (C + 1 ``offsets``); widened by a rounding margin (more
    centres only lower the gaps)."""
    width = 2.0 * (float(s_c.max(initial=0.0)) + float(np.abs(s).max(initial=0.0))) + 1.0
    key_c = cable * width + s_c
    key = cab * width + s
    eps = 1e-9 * width * (1 + len(offsets))
    lo = np.maximum(np.searchsorted(key_c, key - eps, "left") - 1, offsets[cab])
    hi = np.minimum(np.searchsorted(key_c, key + eps, "right"), offsets[cab + 1] - 1)
    return lo, hi


def row_norm3(v: np.ndarray) -> np.ndarray:
    """Euclidean length over axis 1 of (M, 3, S) ``v``: (M, S), the
    arithmetic of :func:`cablecheck.checker.closest.row_norm` (so the same bits)."""
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    return np.sqrt((x * x + y * y) + z * z)


def leading(ok: np.ndarray) -> int:
    """Number of leading True values of a bool vector."""
    return len(ok) if ok.all() else int(np.argmin(ok))
