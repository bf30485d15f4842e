"""Bend radius along a cable's centreline.

The local bend radius at an interior point is the radius of the circle
through it and its two neighbours (the circumradius of the triangle they
form): R = |a| |b| |a + b| / (2 |a x b|) with a, b the two edges. Collinear
points bend with infinite radius; so do coincident points, which have no
direction to bend in.

This module does not smooth or resample: the caller chooses the points.
"""

from __future__ import annotations

import numpy as np


def bend_radius(points: np.ndarray) -> np.ndarray:
    """(n - 2,) local bend radius at the interior points of an (n, 3) polyline."""
    p = np.asarray(points, dtype=float)
    if len(p) < 3:
        return np.zeros(0)
    a = p[1:-1] - p[:-2]
    b = p[2:] - p[1:-1]
    cross = np.linalg.norm(np.cross(a, b), axis=1)
    num = np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1) * np.linalg.norm(a + b, axis=1)
    # Relative threshold: collinear to rounding, whatever the scale of the scene.
    straight = cross <= 1e-12 * np.maximum(num, np.finfo(float).tiny) ** (2.0 / 3.0)
    out = np.full(len(a), np.inf)
    out[~straight] = num[~straight] / (2.0 * cross[~straight])
    return out
