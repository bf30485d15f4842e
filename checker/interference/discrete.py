"""The discrete points of the discrete-point distance method (Ju et al., 2016).

Each cable's body centres are densified so that no element is longer than
``spacing * r`` (:func:`cablecheck.checker.cable.densify_batch`); every point carries its
arc length, its material coordinate (where exclusion windows are measured)
and its cable. :func:`discretise` does it for one state (with extra points at
exclusion-window ends for method ``exact``), :func:`densify_many` for many
states at once with the same bits per state.

Deliberately not here: any distance, pairing or broad phase; the pieces-per-
element arithmetic itself lives in :func:`cablecheck.checker.cable.element_pieces`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cablecheck.checker.cable import densify_batch, material_coordinates, rest_pieces, tile_offsets
from cablecheck.checker.scene_state import CableState, CheckConfig


class Discrete:
    """All cables' discrete points, concatenated (a plain bundle of arrays).

    Attributes:
        p: (M, 3) points.
        s: (M,) arc length along the point's cable.
        m: (M,) material coordinate (:attr:`CableState.rest_s`; ``s`` itself
            when no cable has one): exclusion windows are measured in it.
        cable: (M,) cable index.
        radius: (M,) the point's cable radius.
        seg: (E,) index i of each element (p[i], p[i + 1]) within one cable.
    """

    def __init__(self, p, s, m, cable, radius):
        self.p = p
        self.s = s
        self.m = m
        self.cable = cable
        self.radius = radius
        self.seg = np.nonzero(cable[:-1] == cable[1:])[0]


def points_error(radius: float, spacing: float) -> float:
    """The most method ``points`` over-states a cable-part distance, for a
    cable of ``radius`` densified at ``spacing`` radii: a part's corner
    touching the cable's surface half way between two points is
    ``sqrt(r^2 + (h / 2)^2) - r`` from their spheres, ``h = spacing * r``
    (a flat face between them is found exactly). Never under-stated: the
    points lie on the centreline."""
    return float(radius) * (float(np.sqrt(1.0 + (0.5 * spacing) ** 2)) - 1.0)


def rest_table(cables: Sequence[CableState]) -> tuple[np.ndarray, np.ndarray]:
    """(C,) bool, the cable has rest coordinates; (N,) all cables' rest
    coordinates concatenated (0 where a cable has none)."""
    has = np.array([c.rest_s is not None for c in cables], bool)
    if not has.any():
        return has, np.zeros(sum(len(c.points) for c in cables))
    rest = np.concatenate([c.rest_s if c.rest_s is not None else np.zeros(len(c.points)) for c in cables])
    return has, rest


def discretise(
    cables: Sequence[CableState], config: CheckConfig, cuts: tuple[np.ndarray, np.ndarray],
    keep: np.ndarray | None = None, points: np.ndarray | None = None
) -> Discrete:
    """Densify every cable; add points at the material coordinates ``cuts`` = (cable, m).

    ``keep`` (N,) over the cables' body centres, concatenated: only those
    emit (each itself and the points inside its element after it), the same
    points as densifying all (`densify_batch`); each cable must keep one
    contiguous run of its centres, at least one, and the whole of a cable
    with cuts. ``points``: the centres concatenated, where the caller has
    them."""
    radii = np.array([c.radius for c in cables], dtype=float)
    pts = np.concatenate([c.points for c in cables]) if points is None else points
    offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
    has, rest = rest_table(cables)
    # a cable with rest coordinates keeps its elements' pieces as it stretches a little (rest_pieces)
    least = np.where(np.repeat(has, np.diff(offsets))[:-1], rest_pieces(rest, offsets, config.spacing * radii), 1.0)
    p, s, cable, _, src, _, frac = densify_batch(pts, offsets, config.spacing * radii, source=True, keep=keep,
                                                 least=least)
    m = material_coordinates(s, src, frac, has[cable], rest)
    cut_c, cut_m = cuts
    if len(cut_c):
        p, s, m, cable = insert_at_material(p, s, m, cable, cut_c, cut_m)
    return Discrete(p, s, m, cable, radii[cable])


def insert_at_material(p, s, m, cable, cut_c, cut_m):
    """Insert points on the polylines at material coordinates ``cut_m`` of
    cables ``cut_c`` (``m`` may be ``s`` itself: then at arc lengths).

    Cuts outside a cable's length or on an existing point are dropped.
    """
    n_c = int(cable.max()) + 1
    stop = np.searchsorted(cable, np.arange(n_c), side="right")
    length = m[stop - 1]
    first = m[np.r_[0, stop[:-1]]]
    keep = (cut_c >= 0) & (cut_m > first[np.maximum(cut_c, 0)]) & (cut_m < length[np.maximum(cut_c, 0)])
    cut_c, cut_m = cut_c[keep], cut_m[keep]
    # Find the element of each cut: order all points and cuts by (cable, m).
    order = np.lexsort((np.r_[m, cut_m], np.r_[cable, cut_c]))
    is_cut = order >= len(m)
    # For each cut, the last original point before it in that order.
    last_pt = np.maximum.accumulate(np.where(is_cut, -1, order))
    k = last_pt[is_cut]
    ci = order[is_cut] - len(m)
    cm = cut_m[ci]
    dm = m[k + 1] - m[k]
    u = np.where(dm > 0, cm - m[k], 0.0) / np.where(dm > 0, dm, 1.0)
    new_p = p[k] + u[:, None] * (p[k + 1] - p[k])
    new_s = cm if m is s else s[k] + u * (s[k + 1] - s[k])
    fresh = (cm > m[k]) & (cm < m[k + 1])
    new_p, new_s, cm, new_c = new_p[fresh], new_s[fresh], cm[fresh], cut_c[ci][fresh]
    allp = np.concatenate([p, new_p])
    alls = np.concatenate([s, new_s])
    allm = alls if m is s else np.concatenate([m, cm])
    allc = np.concatenate([cable, new_c])
    o = np.lexsort((allm, allc))
    return allp[o], alls[o], allm[o], allc[o]


@dataclass(frozen=True)
class DenseStates:
    """The discrete points of S states at once (:meth:`Checker.densify_many`).

    Attributes:
        p, s: (M, 3) points and (M,) their arc lengths.
        poly: (M,) polyline: state * cables + cable.
        src, own: (M,) the body centre (counted over all states) each point
            starts from, and whether it is that centre itself.
        m: (M,) material coordinate of each point (exclusion windows).
        states, centres, cables: S, body centres per state, cables.
    """

    p: np.ndarray
    s: np.ndarray
    m: np.ndarray
    poly: np.ndarray
    src: np.ndarray
    own: np.ndarray
    states: int
    centres: int
    cables: int


def densify_many(pts: np.ndarray, offsets: np.ndarray, radii: np.ndarray, spacing: float,
                 rest: np.ndarray | None = None, keep: np.ndarray | None = None) -> DenseStates:
    """The discrete points of S states (S, N, 3) at once, each cable of
    each state a polyline of its own (the bits of :meth:`check`'s own
    discretisation of each state), for :meth:`structure_many` and
    :meth:`cable_pairs_many`. ``rest``: (N,) the centres' material
    coordinates (:attr:`CableState.rest_s` of every cable, concatenated),
    or None (the current arc lengths). ``keep``: (N,) bool, the centres
    whose points (their own, those inside the element after them) are
    wanted in every state, or (S, N) bool, in each state (each as without
    ``keep``), or None (all): the callers need the elements next to their
    entries' centres whole, so they keep each such centre and both its
    neighbours (:func:`around_centres`)."""
    n_s, n = pts.shape[:2]
    radii = np.asarray(radii, float)
    if keep is not None:
        keep = np.asarray(keep, bool)
        keep = keep.ravel() if keep.ndim == 2 else np.tile(keep, n_s)
    least = None
    if rest is not None:       # each element's least pieces (rest_pieces), state after state
        per = np.r_[rest_pieces(rest, offsets, spacing * radii), 1.0]
        least = np.tile(per, n_s)[:-1]
    p, s, poly, _, src, own, frac = densify_batch(pts.reshape(-1, 3), tile_offsets(offsets, n_s),
                                                  np.tile(spacing * radii, n_s), source=True, keep=keep, least=least)
    if rest is None:
        m = s
    else:
        m = material_coordinates(s, src, frac, np.ones(len(s), bool), np.tile(np.asarray(rest, float), n_s))
    return DenseStates(p, s, m, poly, src, own, n_s, n, len(radii))


def around_centres(centres: np.ndarray, n: int, states: np.ndarray | None = None,
                   n_states: int = 0) -> np.ndarray:
    """(n,) bool: the given body centres and both neighbours of each (the
    centres ``densify_many`` must keep for the elements next to them to be
    whole: every point on them and both their ends). With ``states`` (the
    state of each centre, below ``n_states``): (n_states, n), each state's
    centres and their neighbours in that state alone."""
    c = np.asarray(centres, np.int64)
    keep = np.zeros(n, bool) if states is None else np.zeros((n_states, n), bool)
    rows = () if states is None else (np.asarray(states, np.int64),)
    for shift in (-1, 0, 1):
        keep[(*rows, np.clip(c + shift, 0, max(n - 1, 0)))] = True
    return keep
