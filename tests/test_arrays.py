"""Index expansion (checker.arrays) against the Python loop it replaces."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from checker.arrays import ranges, within

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
