"""Tests of cablecheck.checker.hullbound: GJK's lower bound on the distance between convex hulls,
against the hulls' distance by non-negative least squares (scipy), on point sets drawn by
hypothesis, turned, in m or mm and far from the origin."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import nnls

from cablecheck.checker.hullbound import hull_lower_bounds
from helpers import examples
from strategies import coords, rotations


def _hull_distance(a: np.ndarray, b: np.ndarray) -> float:
    """The distance between the convex hulls of a and b by non-negative least squares (scipy's
    Lawson-Hanson active set): weights on both sets' points, each summing to one (held by a heavy
    row), whose weighted points are nearest; the distance of those two points of the hulls."""
    c = a.mean(axis=0)
    size = max(float(np.abs(np.concatenate([a, b]) - c).max()), 1e-300)
    pa, pb = (a - c) / size, (b - c) / size
    heavy = 1e4
    m = np.zeros((5, len(pa) + len(pb)))
    m[:3, :len(pa)], m[:3, len(pa):] = pa.T, -pb.T
    m[3, :len(pa)] = m[4, len(pa):] = heavy
    w, _ = nnls(m, np.array([0.0, 0.0, 0.0, heavy, heavy]), maxiter=10000)
    la, lb = w[:len(pa)] / w[:len(pa)].sum(), w[len(pa):] / w[len(pa):].sum()
    return float(np.linalg.norm(la @ pa - lb @ pb)) * size


@settings(max_examples=examples(60), deadline=None)
@given(coords((8, 3), -1.0, 1.0), coords((11, 3), -1.0, 1.0), coords(3, -3.0, 3.0), rotations(),
       st.sampled_from([0.0, 1e3]), st.sampled_from([1.0, 1e-3]))
def test_bound_never_above_the_hulls_distance_and_near_it_apart(a, b, shift, rot, far, scale):
    """Never above the hulls' distance, about 0 or less where they overlap, and within the tolerance
    of the distance where they are apart; the same in m or mm, at the origin or 1 km off."""
    a = (a @ rot.T) * scale + far
    b = (b @ rot.T + shift) * scale + far
    tol = 1e-4 * scale
    got = float(hull_lower_bounds(a[None], b[None], tol)[0])
    ref = _hull_distance(a, b)                 # two points of the hulls: at least their distance
    rounding = 1e-9 * (scale + far)
    assert got <= ref + rounding
    if ref > 1e-6 * scale:
        assert got >= ref - tol - 1e-6 * scale - rounding
    else:
        assert got <= 1e-6 * scale + rounding


def test_boxes_apart_by_a_known_gap():
    """Two unit cubes' corners (and points inside) 0.25 apart along x, then along a diagonal: the
    bound is the gap, within the tolerance; padding a set with copies of a point changes nothing."""
    rng = np.random.default_rng(3)
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    a = np.concatenate([cube, rng.random((20, 3))])
    b = np.concatenate([cube, rng.random((20, 3)), np.repeat(cube[:1], 5, axis=0)]) + [1.25, 0.0, 0.0]
    got = hull_lower_bounds(a[None], b[None], 1e-9)[0]
    assert abs(got - 0.25) <= 1e-9
    c = cube + [1.3, 1.4, 0.0]                        # nearest corners (1, 1, z) and (1.3, 1.4, z)
    got = hull_lower_bounds(cube[None], c[None], 1e-9)[0]
    assert abs(got - 0.5) <= 1e-9


def test_rows_are_independent_and_overlap_is_not_proven_apart():
    """A batch answers each row as it alone would; overlapping sets give 0 or less."""
    rng = np.random.default_rng(5)
    a = rng.random((6, 15, 3))
    b = rng.random((6, 15, 3)) + np.array([[0.5, 0, 0], [3, 0, 0], [0, 2, 0], [0.1, 0.1, 0.1], [0, 0, 5], [1.5, 1.5, 0]])[:, None]
    batch = hull_lower_bounds(a, b, 1e-6)
    alone = np.array([hull_lower_bounds(a[k:k + 1], b[k:k + 1], 1e-6)[0] for k in range(6)])
    assert np.array_equal(batch, alone)
    assert batch[0] <= 0.0 and batch[3] <= 0.0
    assert np.all(batch[[1, 2, 4, 5]] > 0.0)
