"""cablecheck.study.search: rounds of points that close in on the best of analytic functions within a budget."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import examples
from hypothesis import given, settings, strategies as st

from cablecheck.study.search import Search


def _run(search: Search, f) -> list[np.ndarray]:
    seen = []
    points = search.first()
    while points:
        seen += points
        search.tell(points, [(f(p),) for p in points])
        points = search.next()
    return seen


@settings(max_examples=examples(40), deadline=None)
@given(st.floats(-5, 5), st.floats(0.1, 10), st.floats(0, 1), st.integers(1, 4), st.integers(6, 20))
def test_one_key_closes_in_on_the_peak_and_keeps_to_its_budget(lo, width, where, batch, budget):
    hi = lo + width
    peak = lo + where * width
    search = Search([lo], [hi], budget, batch)
    seen = _run(search, lambda p: -abs(p[0] - peak))
    assert len(seen) == budget
    assert all(lo <= p[0] <= hi for p in seen)
    assert len({float(p[0]) for p in seen}) == len(seen)                 # never the same point twice
    best, _ = search.best()
    # the first round's spacing is at most width / 2 and each later round halves the box around the best
    assert abs(best[0] - peak) <= width / 4 + 1e-9


def test_two_keys_find_a_small_feasible_corner_within_forty_runs():
    # feasible only within 0.06 of (0.9, 0.2) in the unit square; the score is (feasible, -distance)
    target = np.array([0.9, 0.2])

    def f(p):
        d = float(np.linalg.norm(p - target))
        return d < 0.06, -d

    search = Search([0, 0], [1, 1], 40, 2)
    points = search.first()
    while points:
        search.tell(points, [f(p) for p in points])
        points = search.next()
    best, score = search.best()
    assert score[0] and len(search.points) == 40


def test_a_box_of_one_point_per_round_still_spends_the_budget_on_new_points():
    search = Search([0.0], [1.0], 5, 1)
    seen = _run(search, lambda p: -(p[0] - 0.3) ** 2)
    assert len(seen) == 5 and len({float(p[0]) for p in seen}) == 5
    assert search.best()[0][0] == pytest.approx(0.3, abs=0.25)
