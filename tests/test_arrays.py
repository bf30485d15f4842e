"""Index expansion (cablecheck.checker.arrays) against the Python loop it replaces, and
each group's first least value against a sort."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import examples
from hypothesis import given, settings, strategies as st

from cablecheck.checker import arrays
from cablecheck.checker.arrays import ranges, within

groups = st.lists(st.tuples(st.integers(-1000, 1000), st.integers(0, 6)), max_size=12)


@given(groups)
def test_within_and_ranges_are_the_concatenated_aranges(drawn):
    start = np.array([s for s, _ in drawn], np.int64)
    count = np.array([c for _, c in drawn], np.int64)
    want_within = [k for c in count for k in range(c)]
    want_ranges = [s + k for s, c in zip(start, count) for k in range(c)]
    got_within, got_ranges = within(count), ranges(start, count)
    assert got_within.dtype == np.int64 and got_ranges.dtype == np.int64
    assert got_within.tolist() == want_within
    assert got_ranges.tolist() == want_ranges


@given(st.lists(st.tuples(st.integers(0, 5), st.integers(0, 5)), max_size=12))
def test_products_are_every_pair_of_each_group_by_the_loop(drawn):
    """products against the nested loop over each group's two sides (empty sides too)."""
    from cablecheck.checker.arrays import products
    count_a = np.array([a for a, _ in drawn], np.int64)
    count_b = np.array([b for _, b in drawn], np.int64)
    want = [(g, x, y) for g, (a, b) in enumerate(drawn) for x in range(a) for y in range(b)]
    group, x, y = products(count_a, count_b)
    assert list(zip(group.tolist(), x.tolist(), y.tolist())) == want


def _sorted_first_least(state, key, value):
    order = np.lexsort((np.arange(len(value)), value, key, state))
    s, k = state[order], key[order]
    return order[np.r_[True, (s[1:] != s[:-1]) | (k[1:] != k[:-1])]] if len(order) else order


@pytest.mark.parametrize("keys", [5, 300, arrays.TABLE_KEYS + 1])
@pytest.mark.parametrize("states", [1, 40, arrays.TABLE_GROUPS])
def test_first_least_is_each_groups_first_least_value_in_group_order(keys, states):
    """Without a sort (small tables) or with one (large ones, or a value not
    finite): the rows a sort by (state, key, value, index) puts first in each
    group, ties in value (drawn from few values) to the first row."""
    rng = np.random.default_rng(keys + states)
    n = 2000
    state = np.sort(rng.integers(0, states, n))
    key = rng.integers(0, keys, n)
    value = rng.integers(0, 4, n).astype(float)
    assert np.array_equal(arrays.first_least(state, key, value, keys), _sorted_first_least(state, key, value))
    value[7] = np.nan
    assert np.array_equal(arrays.first_least(state, key, value, keys), _sorted_first_least(state, key, value))
    assert len(arrays.first_least(state[:0], key[:0], value[:0], keys)) == 0


@settings(max_examples=examples(30), deadline=None)
@given(rows=st.integers(0, 40), cols=st.integers(1, 4), seed=st.integers(0, 2**32 - 1))
def test_all_columns_is_numpys_all_over_rows(rows, cols, seed):
    from cablecheck.checker.arrays import all_columns
    mask = np.random.default_rng(seed).random((rows, cols)) < 0.8
    got = all_columns(mask)
    assert got.dtype == bool and got.shape == (rows,)
    assert np.array_equal(got, np.all(mask, axis=1))


@settings(max_examples=examples(30), deadline=None)
@given(rows=st.integers(0, 40), cols=st.integers(1, 4), seed=st.integers(0, 2**32 - 1), nan=st.booleans())
def test_max_and_min_columns_are_numpys_over_rows(rows, cols, seed, nan):
    from cablecheck.checker.arrays import max_columns, min_columns
    x = np.random.default_rng(seed).normal(size=(rows, cols))
    if nan and rows:
        x[rows // 2, cols - 1] = np.nan         # propagated, as numpy's max and min do
    assert np.array_equal(max_columns(x), np.max(x, axis=1), equal_nan=True)
    assert np.array_equal(min_columns(x), np.min(x, axis=1), equal_nan=True)
