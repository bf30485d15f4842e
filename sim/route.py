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

_DENSE = 4000
"""Samples along the route when measuring and resampling it."""


def polyline_length(points: np.ndarray) -> float:
    """Length of an (n, 3) polyline."""
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())


def arc_lengths(points: np.ndarray) -> np.ndarray:
    """(n,) cumulative arc length of an (n, 3) polyline, starting at 0."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(seg)])


def resample_even(points: np.ndarray, count: int) -> np.ndarray:
    """`count` points evenly spaced in arc length along an (n, 3) polyline."""
    s = arc_lengths(points)
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


def initial_shape(route: np.ndarray, length: float, count: int,
                  down: np.ndarray = np.array([0.0, 0.0, -1.0])) -> np.ndarray:
    """(count, 3) points, evenly spaced, of a shape of arc length `length` along `route`.

    Method: densify the route; if it is shorter than `length`, add a droop
    h * sin(pi s / S) along the droop direction (a half sine over the route's
    arc length s in [0, S]) and find h by Brent's method so that the
    resampled polyline (the cable's elements) has the requested length to
    1e-9 relative; then resample evenly. Both ends stay where they
    are. `length` shorter than the route is the caller's error (the scene
    loader rejects it); it is treated as the route's length.
    """
    route = np.asarray(route, dtype=float)
    dense = resample_even(route, _DENSE)
    s = arc_lengths(dense)
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
