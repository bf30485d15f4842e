"""Hypothesis strategies that draw geometry for the checker's property tests.

Cables are random walks (so they fold back on themselves and cross each
other), parts are primitives of drawn sizes at drawn poses; every number is
drawn by hypothesis, so a failure shrinks to a small case. Not a test file.
"""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from cablecheck.checker.scene_state import CableState, PartState
from cablecheck.checker.shapes import Shape, ShapeType


def coords(shape, lo: float, hi: float):
    """Float arrays of ``shape`` with finite elements in [lo, hi]."""
    return arrays(float, shape, elements=st.floats(lo, hi, allow_nan=False, allow_infinity=False, width=64))


@st.composite
def rotations(draw) -> np.ndarray:
    """A proper rotation (3, 3) from a drawn unit quaternion."""
    q = draw(coords(4, -1.0, 1.0))
    n = float(np.linalg.norm(q))
    if n < 1e-3:
        return np.eye(3)
    w, x, y, z = q / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


@st.composite
def poses(draw, reach: float = 0.1) -> np.ndarray:
    """A rigid transform (4, 4) within ``reach`` of the origin."""
    out = np.eye(4)
    out[:3, :3] = draw(rotations())
    out[:3, 3] = draw(coords(3, -reach, reach))
    return out


@st.composite
def polylines(draw, min_points: int = 3, max_points: int = 12, step: float = 0.03) -> np.ndarray:
    """A random walk (n, 3) of steps up to ``step`` per axis from near the origin."""
    n = draw(st.integers(min_points, max_points))
    start = draw(coords(3, -0.08, 0.08))
    steps = draw(coords((n - 1, 3), -step, step))
    return start + np.concatenate([np.zeros((1, 3)), np.cumsum(steps, axis=0)])


@st.composite
def cable_sets(draw, max_cables: int = 3, **kw) -> list[CableState]:
    """1..max_cables cables c0, c1, ... of drawn radii (2-12 mm)."""
    n = draw(st.integers(1, max_cables))
    return [CableState(f"c{k}", draw(polylines(**kw)), draw(st.floats(0.002, 0.012))) for k in range(n)]


PRIMITIVES = (ShapeType.BOX, ShapeType.SPHERE, ShapeType.CYLINDER, ShapeType.CAPSULE, ShapeType.ELLIPSOID)


@st.composite
def part_sets(draw, max_parts: int = 4) -> list[PartState]:
    """1..max_parts primitive parts p0, p1, ... (some keep-out) at drawn poses."""
    n = draw(st.integers(1, max_parts))
    return [PartState(f"p{k}", Shape(draw(st.sampled_from(PRIMITIVES)), draw(coords(3, 0.005, 0.05))),
                      draw(poses()), keepout=draw(st.booleans())) for k in range(n)]


@st.composite
def coils(draw, min_points: int = 8, max_points: int = 40) -> CableState:
    """A cable "c" (radius 2-12 mm) wound as a drawn helix, tight enough
    (coil radius 0.5-3 radii, pitch up to 4 radii a turn) that it comes back
    within the clearance of itself near the self rule's window edge (pi r
    + clearance along it), with drawn jitter on every point (up to 0.4 r)."""
    r = draw(st.floats(0.002, 0.012))
    n = draw(st.integers(min_points, max_points))
    coil = draw(st.floats(0.5, 3.0)) * r
    pitch = draw(st.floats(0.0, 4.0)) * r
    turn = np.cumsum(draw(coords(n, 0.15, 1.2)))
    pts = np.stack([coil * np.cos(turn), coil * np.sin(turn), pitch * turn / (2 * np.pi)], axis=1)
    return CableState("c", pts + draw(coords((n, 3), -0.4 * r, 0.4 * r)), r)
