"""The initial shape of a cable: its route made as long as the cable, as vertices.

A cable is routed as a polyline of waypoints (start, via points, clips, end,
or the given `points`) at t = 0. Every waypoint becomes a vertex of the
cable: each straight run between two waypoints is split into a whole number
of equal elements (`run_elements` shares the elements among the runs in
proportion to their lengths), so a route is never resampled across its
corners and a `points` route is checked as given.

When the cable is longer than its route it cannot lie straight along it:
`initial_shape` lets every run of two or more elements droop by the same
ratio of extra length, as a half sine over the run (zero at its waypoints),
whose height is found by root finding so that the run's elements have the
run's share of the length; at a waypoint where a clamp holds the run's
chord (the route's direction, a clamp's default at an end) the bump is
flattened, so the cable leaves the clamp along it, and a run of two or more elements leaving a
clamp given another direction first bends to it (a cubic Hermite curve,
`hermite`; `route_lengths` says how much longer that makes the route). A
run droops downwards (sideways for a vertical run) unless that takes it deeper into a part the cable collides with than
the straight run is: then it turns about its chord to the nearest direction
that does not (a cable laid along a floor snakes sideways on the floor
instead of starting inside it). The caller says what "deep" is through a
`depth` function, so this module knows nothing of parts, MuJoCo or bodies:
it takes world points.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import numpy as np

from cablecheck.checker.cable import arc_length

_DENSE = 4000
"""Samples along a run when measuring and resampling its droop."""

TURN_STEP = 10.0
"""Degrees between the droop directions tried about a run's chord."""

DOWN = np.array([0.0, 0.0, -1.0])

Depth = Callable[[np.ndarray], np.ndarray]
"""depth(points (m, 3)) -> (m,): how far a cable vertex at each point
reaches into the parts it collides with (radius less signed distance;
0 or less when clear)."""


def polyline_length(points: np.ndarray) -> float:
    """Length of an (n, 3) polyline."""
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())


def resample_even(points: np.ndarray, count: int) -> np.ndarray:
    """`count` points evenly spaced in arc length along an (n, 3) polyline."""
    s = arc_length(points)
    targets = np.linspace(0.0, s[-1], count)
    return np.stack([np.interp(targets, s, points[:, k]) for k in range(3)], axis=1)


def run_elements(runs: np.ndarray, elements: int) -> np.ndarray:
    """Elements per run (each >= 1, summing to `elements`), as near as possible
    to proportional to the run lengths `runs` (so elements come out nearly
    equal). `elements` must be at least the number of runs."""
    runs = np.asarray(runs, float)
    if elements < len(runs):
        raise ValueError(f"{elements} elements cannot have all {len(runs) + 1} waypoints as vertices")
    share = runs / runs.sum() * elements
    out = np.maximum(np.floor(share).astype(int), 1)
    while out.sum() < elements:  # give to the runs furthest below their share
        out[np.argmax(share - out)] += 1
    while out.sum() > elements:  # take from the runs furthest above it, never below 1
        over = np.where(out > 1, out - share, -np.inf)
        out[np.argmax(over)] -= 1
    return out


def _bump(x: np.ndarray, held: int) -> np.ndarray:
    """The droop's shape across a unit run, zero at both ends: a half sine,
    or with zero slope at a clamped end (`held`: bit 0 the run's start, bit 1
    its end) so the cable leaves the clamp along the run's chord:
    sin(pi x) x (2 - x) (start; at the other end the half sine's slope),
    its mirror (end), sin^2(pi x) (both)."""
    if held == 3:
        return np.sin(np.pi * x) ** 2
    if held == 1:
        return np.sin(np.pi * x) * x * (2.0 - x)
    if held == 2:
        return np.sin(np.pi * x) * (1.0 - x * x)
    return np.sin(np.pi * x)


@lru_cache(maxsize=256)
def _profile(ratio: float, count: int, held: int = 0) -> np.ndarray:
    """(count + 1, 2) points of a unit run drooped to length `ratio`: (along
    the chord, across it), evenly spaced along the bump (`_bump`), whose height is
    found by Brent's method so that the `count` elements have length `ratio`
    to 1e-12 relative. Read-only, and found once per (ratio, count, held): the
    cables of a harness share a few (the static harness of 100 cables x 300
    parts asks for 1,200, 27 of them distinct)."""
    out = _find_profile(ratio, count, held)
    out.setflags(write=False)
    return out


def _find_profile(ratio: float, count: int, held: int) -> np.ndarray:
    """`_profile`, found afresh."""
    x = np.linspace(0.0, 1.0, _DENSE)
    bump = _bump(x, held)

    def shape(h: float) -> np.ndarray:
        return resample_even(np.stack([x, h * bump, np.zeros_like(x)], axis=1), count + 1)[:, :2]

    if ratio <= 1.0 + 1e-12 or count < 2:
        return np.stack([np.linspace(0.0, 1.0, count + 1), np.zeros(count + 1)], axis=1)

    def excess(h: float) -> float:
        # measured on the resampled points: their chords are the cable's elements
        return float(np.linalg.norm(np.diff(shape(h), axis=0), axis=1).sum()) - ratio

    from scipy.optimize import brentq  # scipy, a third of a second to import: only a run with slack pays it

    hi = ratio
    while excess(hi) < 0.0:
        hi *= 2.0
    return shape(brentq(excess, 0.0, hi, xtol=1e-13, rtol=1e-12))


def _directions(axis: np.ndarray, down: np.ndarray) -> np.ndarray:
    """(R, C, 3) unit droop directions per run, perpendicular to its chord
    `axis` (R, 3), in order of preference: `down` without its component along
    the chord (sideways for a vertical run), then turning about the chord by
    +-TURN_STEP, +-2 TURN_STEP, ... up to 180 degrees."""
    d0 = down[None, :] - (axis @ down)[:, None] * axis
    n0 = np.linalg.norm(d0, axis=1)
    side = np.cross(axis, [1.0, 0.0, 0.0])
    side_y = np.cross(axis, [0.0, 1.0, 0.0])
    side = np.where((np.linalg.norm(side, axis=1) < 1e-6)[:, None], side_y, side)
    d0 = np.where((n0 < 1e-6)[:, None], side, d0)
    d0 /= np.linalg.norm(d0, axis=1)[:, None]
    e = np.cross(axis, d0)
    steps = np.arange(1, int(round(180.0 / TURN_STEP)) + 1) * np.radians(TURN_STEP)
    theta = np.concatenate([[0.0], np.stack([steps, -steps], axis=1).ravel()[:-1]])
    return np.cos(theta)[None, :, None] * d0[:, None, :] + np.sin(theta)[None, :, None] * e[:, None, :]


def hermite(a: np.ndarray, b: np.ndarray, t0: np.ndarray, t1: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(len(x), 3) points of the cubic Hermite curve from `a` to `b` leaving
    along unit `t0` and arriving along unit `t1`, tangent magnitudes the
    chord's length; x in [0, 1]. The straight run when both are its chord."""
    x = np.asarray(x, float)[:, None]
    h00, h10 = 2 * x ** 3 - 3 * x ** 2 + 1, x ** 3 - 2 * x ** 2 + x
    h01, h11 = -2 * x ** 3 + 3 * x ** 2, x ** 3 - x ** 2
    chord = float(np.linalg.norm(b - a))
    return h00 * a + h10 * chord * t0 + h01 * b + h11 * chord * t1


def _given_ends(route: np.ndarray, counts: np.ndarray, tangents: dict) -> tuple[np.ndarray, list]:
    """(R,) bool: the runs that bend to meet a given tangent at an end (two
    or more elements, a tangent off their chord), and each run's (t0, t1)."""
    axis = np.diff(route, axis=0)
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    ends = [(np.asarray(tangents.get(i, axis[i]), float), np.asarray(tangents.get(i + 1, axis[i]), float))
            for i in range(len(axis))]
    bent = np.array([counts[i] >= 2 and max(np.linalg.norm(t0 - axis[i]), np.linalg.norm(t1 - axis[i])) > 1e-9
                     for i, (t0, t1) in enumerate(ends)], bool)
    return bent, ends


def route_lengths(route: np.ndarray, counts: np.ndarray, tangents: dict | None = None) -> np.ndarray:
    """(W - 1,) length of each run before it droops: its chord, or where it
    bends to meet a given tangent (`initial_shape`), its Hermite curve's."""
    route = np.asarray(route, float)
    runs = np.linalg.norm(np.diff(route, axis=0), axis=1)
    if not tangents:
        return runs
    bent, ends = _given_ends(route, np.asarray(counts, int), tangents)
    x = np.linspace(0.0, 1.0, _DENSE)
    for i in np.flatnonzero(bent):
        runs[i] = polyline_length(hermite(route[i], route[i + 1], *ends[i], x))
    return runs


def _bent_run(a, b, t0, t1, count: int, target: float, across: np.ndarray, held: int) -> np.ndarray:
    """(count + 1, 3) points of a run bent to leave and arrive along `t0`,
    `t1` (`hermite`) and drooped along unit `across` by the bump `held`
    (`_bump`) so that its `count` equal elements have length `target`
    (Brent's method; no droop when the bent run alone is as long)."""
    x = np.linspace(0.0, 1.0, _DENSE)
    base = hermite(a, b, t0, t1, x)
    bump = _bump(x, held)[:, None] * float(np.linalg.norm(b - a)) * across[None, :]

    def shape(h: float) -> np.ndarray:
        return resample_even(base + h * bump, count + 1)

    def excess(h: float) -> float:
        return polyline_length(shape(h)) - target

    if excess(0.0) >= 0.0:
        return shape(0.0)
    from scipy.optimize import brentq  # scipy, a third of a second to import: only a run with slack pays it

    hi = 1.0
    while excess(hi) < 0.0:
        hi *= 2.0
    return shape(brentq(excess, 0.0, hi, xtol=1e-13, rtol=1e-12))


def initial_shape(route: np.ndarray, length: float, counts: np.ndarray,
                  down: np.ndarray = DOWN, depth: Depth | None = None,
                  clamped: np.ndarray | None = None, tangents: dict | None = None) -> np.ndarray:
    """(sum(counts) + 1, 3) vertices through every waypoint of `route`, with
    arc length `length`.

    Args:
      route: (W, 3) waypoints; consecutive ones distinct.
      length: the cable's length, not shorter than the route (shorter is
        treated as the route's length, `route_lengths`: the scene loader
        and `cablecheck.build.cableplan` reject it).
      counts: (W - 1,) elements per run (`run_elements`).
      down: the direction a run droops in by preference.
      depth: how deep a vertex would be in the parts the cable collides
        with; None: droop towards `down` whatever is there.
      clamped: (W,) bool, the waypoints where a clamp holds the cable along
        the runs' chords (or a given tangent): a run droops with zero slope
        there, leaving along its chord. None: none.
      tangents: waypoint index -> unit direction (of travel, start to end)
        a clamp given a `tangent` holds the cable in there.

    Method: run i is split into counts[i] equal elements. A run of two or
    more elements with a given tangent off its chord at an end bends to
    it: the cubic Hermite curve from waypoint to waypoint along the
    tangents (`hermite`; the chord at an end without one). With slack (the
    length longer than the runs so made by more than 1e-9 relative), every
    run of two or more elements droops by the same ratio of its length, as a
    half sine, or with zero slope at its clamped ends (`_bump`), so every
    waypoint stays a vertex and the elements of a run are equal; runs of one
    element stay straight (a kink where a tangent is given). Of the directions about
    a run's chord (`_directions`) the first whose vertices go no deeper into
    the parts than the straight run's (`depth`; so a run that starts clear
    stays clear) is taken, else the one that goes least deep (judged on the
    run not bent to its tangents). Raises
    ValueError when there is slack but no run has two elements to droop in.
    """
    route = np.asarray(route, dtype=float)
    counts = np.asarray(counts, dtype=int)
    chord = np.diff(route, axis=0)
    runs = np.linalg.norm(chord, axis=1)
    axis = chord / runs[:, None]
    tangents = dict(tangents or {})
    clamped = np.zeros(len(route), bool) if clamped is None else np.array(clamped, bool)
    clamped[list(tangents)] = True
    held = clamped[:-1].astype(int) + 2 * clamped[1:].astype(int)
    base = route_lengths(route, counts, tangents)
    bent, ends = _given_ends(route, counts, tangents) if tangents else (np.zeros(len(runs), bool), [])
    total = base.sum()
    bends = counts >= 2
    ratio = 1.0
    if length > total * (1.0 + 1e-9):
        if not bends.any():
            raise ValueError("the cable is longer than its route but no run between two "
                             "waypoints has two elements to droop in")
        ratio = (length - base[~bends].sum()) / base[bends].sum()
    # one profile per distinct element count and clamped ends, looked up per vertex
    run_ratio = np.where(bends, ratio, 1.0)
    kinds, kind_of_run = np.unique(np.stack([counts, run_ratio > 1.0, np.where(run_ratio > 1.0, held, 0)], axis=1),
                                   axis=0, return_inverse=True)
    kind_of_run = kind_of_run.ravel()
    profiles = [_profile(ratio if droops else 1.0, int(n), int(h)) for n, droops, h in kinds]
    start = np.concatenate([[0], np.cumsum([len(p) for p in profiles])])
    table = np.concatenate(profiles)
    # vertices 1..counts[i] of each run (vertex 0 is the previous run's last)
    run = np.repeat(np.arange(len(runs)), counts)
    k = np.arange(len(run)) - np.repeat(np.cumsum(counts) - counts, counts) + 1
    prof = table[start[kind_of_run[run]] + k]
    along = route[run] + (prof[:, 0] * runs[run])[:, None] * axis[run]
    across = prof[:, 1] * runs[run]
    dirs = _directions(axis, np.asarray(down, float))           # (R, C, 3)
    choice = np.zeros(len(runs), int)
    if depth is not None and ratio > 1.0:
        choice = _choose(along, across, dirs, run, runs, depth)
    vertices = along + across[:, None] * dirs[run, choice[run]]
    first = np.cumsum(counts) - counts
    for i in np.flatnonzero(bent):
        vertices[first[i]:first[i] + counts[i]] = _bent_run(
            route[i], route[i + 1], *ends[i], int(counts[i]), ratio * base[i], dirs[i, choice[i]], int(held[i]))[1:]
    vertices[np.cumsum(counts) - 1] = route[1:]  # waypoints exactly as given
    return np.concatenate([route[:1], vertices])


def _choose(along: np.ndarray, across: np.ndarray, dirs: np.ndarray, run: np.ndarray,
            runs: np.ndarray, depth: Depth) -> np.ndarray:
    """(R,) index of the droop direction per run (see `initial_shape`)."""
    n_dir = dirs.shape[1]
    candidates = along[:, None, :] + across[:, None, None] * dirs[run]   # (V, C, 3)
    deep = depth(candidates.reshape(-1, 3)).reshape(len(run), n_dir)
    straight = depth(along)
    first = np.flatnonzero(np.r_[True, run[1:] != run[:-1]])  # vertices are grouped by run
    runs_present = run[first]
    worst = np.maximum.reduceat(deep, first, axis=0)              # (R', C)
    allowed = np.maximum(np.maximum.reduceat(straight, first), 0.0) + 1e-9 * runs[runs_present]
    ok = worst <= allowed[:, None]
    pick = np.where(ok.any(axis=1), np.argmax(ok, axis=1), np.argmin(worst, axis=1))
    choice = np.zeros(len(runs), int)
    choice[runs_present] = pick
    return choice
