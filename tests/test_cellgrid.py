"""Cell grid (cablecheck.checker.cellgrid): pairs and near queries equal a brute-force search, exactly."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st
from strategies import coords

from cablecheck.checker.cellgrid import CellGrid

pytestmark = pytest.mark.filterwarnings("error")


def _d2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Squared distances (len(a), len(b)), summed in the grid's order."""
    d = a[:, None] - b[None]
    d = d * d
    return (d[..., 0] + d[..., 1]) + d[..., 2]


def brute_pairs(x: np.ndarray, r: float) -> set:
    i, j = np.nonzero(np.triu(_d2(x, x) <= r * r, 1))
    return set(zip(i.tolist(), j.tolist()))


def brute_near(x: np.ndarray, c: np.ndarray, r: np.ndarray) -> set:
    k, i = np.nonzero(_d2(c, x) <= (r * r)[:, None])
    return set(zip(k.tolist(), i.tolist()))


@st.composite
def clouds(draw):
    """Points (n, 3): a box of drawn size at a drawn offset (up to 1e6 from
    the origin), some points repeated, some on a line (one long strip)."""
    n = draw(st.integers(0, 40))
    scale = 10.0 ** draw(st.floats(-3, 3))
    offset = draw(coords(3, -1e6, 1e6)) if draw(st.booleans()) else np.zeros(3)
    x = offset + draw(coords((n, 3), 0.0, 1.0)) * scale
    if n > 2 and draw(st.booleans()):
        x[: n // 3] = x[-1]
    if n > 2 and draw(st.booleans()):
        x[:, 1:] = x[:1, 1:]                       # all on a line along x
    return x, scale


def _as_set(a, b) -> set:
    got = list(zip(a.tolist(), b.tolist()))
    assert len(got) == len(set(got)), "a pair returned twice"
    return set(got)


@settings(max_examples=150, deadline=None)
@given(clouds(), st.floats(0.0, 1.0), st.sampled_from([0.0, 0.3, 1.0, 2.5]), st.booleans())
@example((np.zeros((5, 3)), 1.0), 0.0, 0.0, False)
@example((np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]]), 1.0), 1.0, 1.0, True)
def test_pairs_are_the_brute_force_pairs(cloud, cell, ratio, dense):
    """Every pair i < j within the reach, once, and nothing else; the same
    with the tables or binary search, or no grid at all (few points);
    reaches beyond the cell too."""
    x, scale = cloud
    reach = cell * scale * ratio
    for grid in (CellGrid(x, cell * scale, None if dense else 0, brute=0), CellGrid(x, cell * scale)):
        assert _as_set(*grid.pairs(reach)) == brute_pairs(x, reach)


@settings(max_examples=150, deadline=None)
@given(clouds(), st.floats(0.0, 1.0), st.integers(0, 6), st.data())
def test_near_is_the_brute_force_near(cloud, cell, k, data):
    """Centres inside and outside the points' box, radii below and above the cell."""
    x, scale = cloud
    lo = x.min(axis=0) if len(x) else np.zeros(3)
    c = lo + data.draw(coords((k, 3), -0.5, 1.5)) * scale
    r = data.draw(coords(k, 0.0, 2.0)) * scale
    for table, brute in ((None, 0), (0, 0), (None, 64)):
        grid = CellGrid(x, cell * scale, table, brute)
        assert _as_set(*grid.near(c, r)) == brute_near(x, c, r)


def test_exactly_at_the_reach_is_a_pair_far_from_the_origin():
    """Points exactly the reach apart (in floating point) pair up at 1e6 m;
    a hair farther, not."""
    x = np.array([[1e6, 1e6, 1e6], [1e6 + 0.125, 1e6, 1e6], [1e6 + 0.25 + 2 ** -20, 1e6, 1e6]])
    grid = CellGrid(x, 0.125, brute=0)
    assert _as_set(*grid.pairs(0.125)) == {(0, 1)}
    assert _as_set(*grid.near(x[:1], np.array([0.125]))) == {(0, 0), (0, 1)}


def test_empty_and_single():
    for brute in (0, 64):
        assert CellGrid(np.zeros((0, 3)), 1.0, brute=brute).pairs(1.0)[0].size == 0
        assert CellGrid(np.ones((1, 3)), 1.0, brute=brute).pairs(1.0)[0].size == 0
        assert CellGrid(np.zeros((0, 3)), 1.0, brute=brute).near(np.zeros((2, 3)), 1.0)[0].size == 0


def test_non_finite_points_are_refused():
    with pytest.raises(ValueError, match="finite"):
        CellGrid(np.array([[0.0, 0.0, np.nan]]), 1.0)


def test_far_apart_points_keep_the_tables_small():
    """Strips crossed far apart along x (the x-table would be mostly empty)
    are searched instead: the same pairs, no table larger than the points."""
    y = np.arange(50.0)
    x = np.concatenate([np.c_[np.zeros(50), y, np.zeros(50)], np.c_[np.full(50, 1e4), y, np.zeros(50)]])
    grid = CellGrid(x, 1.0, brute=0)
    assert grid.table is None
    assert _as_set(*grid.pairs(1.0)) == brute_pairs(x, 1.0)
    c = np.array([[0.0, 10.0, 0.0], [1e4, 20.0, 0.5]])
    r = np.array([2.0, 1.0])
    assert _as_set(*grid.near(c, r)) == brute_near(x, c, r)
