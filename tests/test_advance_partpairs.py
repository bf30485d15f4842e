"""The skip rule's part-pair bound (checker.advance.partpairs): box separations are lower bounds on distances."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from strategies import coords, poses

from checker.advance.partpairs import PartPairGaps, part_pair_bounds
from checker.partset import PartSet
from checker.shapes import Shape, ShapeType

pytestmark = pytest.mark.filterwarnings("error")


def _corners(half: np.ndarray) -> np.ndarray:
    return np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half


def test_boxes_apart_along_an_axis_and_a_box_above_a_plane():
    """Analytic: two unit cubes 0.5 apart along x; a cube 2 above a floor plane."""
    cube = Shape(ShapeType.BOX, [0.5, 0.5, 0.5])
    ps = PartSet.build(["a", "b", "floor"], [cube, cube, Shape(ShapeType.PLANE, [])])
    pose = np.tile(np.eye(4), (3, 1, 1))
    pose[1, :3, 3] = [1.5, 0.0, 0.0]
    pose[0, :3, 3] = [0.0, 0.0, 2.5]
    pose[1, 2, 3] = 2.5
    bound = part_pair_bounds(ps, ps.place(pose), np.array([0, 0, 1]), np.array([1, 2, 2]))
    assert bound == pytest.approx([0.5, 2.0, 2.0])


@settings(max_examples=60, deadline=None)
@given(coords(3, 0.01, 0.1), coords(3, 0.01, 0.1), poses(reach=0.2), poses(reach=0.2))
def test_bound_never_exceeds_the_distance_of_the_boxes(half_a, half_b, pose_a, pose_b):
    """The bound is at most the distance between any point of one box and
    any point of the other (checked on their corners and centres)."""
    ps = PartSet.build(["a", "b"], [Shape(ShapeType.BOX, half_a), Shape(ShapeType.BOX, half_b)])
    bound = part_pair_bounds(ps, ps.place(np.stack([pose_a, pose_b])), np.array([0]), np.array([1]))[0]
    pa = np.vstack([_corners(half_a), np.zeros(3)]) @ pose_a[:3, :3].T + pose_a[:3, 3]
    pb = np.vstack([_corners(half_b), np.zeros(3)]) @ pose_b[:3, :3].T + pose_b[:3, 3]
    assert bound <= np.linalg.norm(pa[:, None] - pb[None], axis=2).min() + 1e-12


@given(st.floats(0.0, 0.5), st.floats(0.0, 0.5))
def test_pairs_clear_while_the_moves_stay_below_the_bound(move_a, move_b):
    """Two parts 1 apart (bound 1, clearance 0.1): clear exactly while the
    sum of their moves stays below 0.9 (less the rounding margin)."""
    gaps = PartPairGaps(np.array([0.5, 0.5]), 0.1)
    start = np.tile(np.eye(4), (2, 1, 1))
    gaps.start(start, (np.array([0]), np.array([1])), np.array([1.0]), mu=0.0)
    now = start.copy()
    now[0, 0, 3] += move_a
    now[1, 1, 3] -= move_b
    assert gaps.clear_at(now) == (move_a + move_b < 0.9)
    gaps.stop()
    assert not gaps.clear_at(start)


@given(st.floats(0.0, 1.5), st.floats(0.0, 1.5))
def test_failing_pairs_are_the_pairs_whose_bound_fails(move_a, move_c):
    """Three parts, pairs (0, 1) and (1, 2) bound 1 apart (clearance 0.1):
    a pair is failing exactly when its moves reach 0.9; no pairs after a stop."""
    gaps = PartPairGaps(np.array([0.5, 0.5, 0.5]), 0.1)
    start = np.tile(np.eye(4), (3, 1, 1))
    gaps.start(start, (np.array([0, 1]), np.array([1, 2])), np.array([1.0, 1.0]), mu=0.0)
    now = start.copy()
    now[0, 0, 3] += move_a
    now[2, 1, 3] -= move_c
    fi, fj = gaps.failing_at(now)
    want = [(0, 1)] * (move_a >= 0.9) + [(1, 2)] * (move_c >= 0.9)
    assert list(zip(fi.tolist(), fj.tolist())) == want
    assert gaps.clear_at(now) == (not want)
    gaps.stop()
    assert gaps.failing_at(start) is None
