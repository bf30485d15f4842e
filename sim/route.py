"""The initial shape of a cable: its route made as long as the cable, resampled.

A cable is routed as a polyline (start, via points, end, or the given
`points`) at t = 0. When the cable is longer than that polyline it cannot lie
straight along it: `initial_shape` lets it droop (downwards, or sideways for a
vertical run) so that the shape already has the cable's length and starts
close to rest instead of as a compressed straight line. The droop is a smooth
bump over the whole route, zero at both ends, whose height is found by root
finding so that the arc length equals the requested length.

This module does not know about MuJoCo or bodies: it takes world points.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from checker.cable import arc_length

_DENSE = 4000
"""Samples along the route when measuring and resampling it."""


def polyline_length(points: np.ndarray) -> float:
    """Length of an (n, 3) polyline."""
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())


def resample_even(points: np.ndarray, count: int) -> np.ndarray:
    """`count` points evenly spaced in arc length along an (n, 3) polyline."""
    s = arc_length(points)
    targets = np.linspace(0.0, s[-1], count)
    return np.stack([np.interp(targets, s, points[:, k]) for k in range(3)], axis=1)


def _droop_direction(route: np.ndarray, down: np.ndarray) -> np.ndarray:
    """Unit direction the cable droops in: `down` without its component along the chord."""
    chord = route[-1] - route[0]
    norm = np.linalg.norm(chord)
    if norm == 0.0:
        return down
    axis = chord / norm
    d = down - np.dot(down, axis) * axis
    if np.linalg.norm(d) < 1e-6:  # vertical run: droop sideways
        d = np.cross(axis, [1.0, 0.0, 0.0])
        if np.linalg.norm(d) < 1e-6:
            d = np.cross(axis, [0.0, 1.0, 0.0])
    return d / np.linalg.norm(d)


def _droop(route: np.ndarray, length: float, count: int, down: np.ndarray) -> np.ndarray:
    """`count` evenly spaced points of `route` drooped to arc length `length`."""
    dense = resample_even(route, _DENSE)
    s = arc_length(dense)
    total = s[-1]
    if length > total * (1.0 + 1e-9):
        bump = np.sin(np.pi * s / total)[:, None] * _droop_direction(route, down)[None, :]

        def excess(h: float) -> float:
            # measured on the resampled points: their chords are the cable's elements
            return polyline_length(resample_even(dense + h * bump, count)) - length

        hi = length
        while excess(hi) < 0.0:
            hi *= 2.0
        h = brentq(excess, 0.0, hi, xtol=1e-12 * length, rtol=1e-12)
        dense = dense + h * bump
    return resample_even(dense, count)


def _allocate(weights: np.ndarray, total: int, least: int) -> np.ndarray:
    """Integers >= least summing to `total`, as near as possible to proportional to weights."""
    share = weights / weights.sum() * total
    out = np.maximum(np.floor(share).astype(int), least)
    while out.sum() < total:  # give to the runs furthest below their share
        out[np.argmax(share - out)] += 1
    while out.sum() > total:  # take from the runs furthest above it, never below `least`
        over = np.where(out > least, out - share, -np.inf)
        out[np.argmax(over)] -= 1
    return out


def initial_shape(route: np.ndarray, length: float, count: int,
                  down: np.ndarray = np.array([0.0, 0.0, -1.0])) -> np.ndarray:
    """(count, 3) points along `route` whose polyline has arc length `length`.

    Method: with no slack the points are spaced evenly along the route. With
    slack, every waypoint of the route stays where it is: the elements are
    shared among the straight runs between waypoints in proportion to their
    lengths (so elements come out nearly equal), and every run given two or
    more elements droops by the same ratio of extra length, as a half sine
    h * sin(pi s / S) towards `down` (sideways for a vertical run), h found by
    Brent's method so that its resampled points (the cable's elements) have
    the run's length to 1e-9 relative. Runs given a single element stay
    straight and the others take their share of slack. Drooping run by run
    keeps every waypoint on the cable; a droop over a route with corners
    could shorten a run instead of lengthening it. If no run can droop (a
    dense `points` route), the route droops as a whole. Both ends stay where
    they are. `length` shorter than the route is the caller's error (the
    scene loader rejects it) and is treated as the route's length.
    """
    route = np.asarray(route, dtype=float)
    runs = np.linalg.norm(np.diff(route, axis=0), axis=1)
    total = runs.sum()
    elements = count - 1
    if length <= total * (1.0 + 1e-9) or len(runs) == 1:
        return _droop(route, length, count, down)
    if elements < len(runs):
        return _droop(route, length, count, down)
    counts = _allocate(runs, elements, 1)
    bends = counts >= 2
    if not bends.any():
        return _droop(route, length, count, down)
    ratio = (length - runs[~bends].sum()) / runs[bends].sum()
    pieces = [_droop(route[i:i + 2], runs[i] * (ratio if bends[i] else 1.0), int(counts[i]) + 1, down)
              for i in range(len(runs))]
    return np.concatenate([pieces[0]] + [p[1:] for p in pieces[1:]])
