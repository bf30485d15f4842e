"""What the skip rule's modules share (cablecheck.checker.advance.common): brackets of arc length, norms with row_norm's bits."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from strategies import coords, polylines

from cablecheck.checker.advance.common import bracket, leading, row_norm3
from cablecheck.checker.cable import polyline_arc_lengths
from cablecheck.checker.closest import row_norm

pytestmark = pytest.mark.filterwarnings("error")


@given(coords((5, 3, 4), -10.0, 10.0))
def test_row_norm3_has_row_norms_bits(v):
    assert np.array_equal(row_norm3(v), row_norm(np.transpose(v, (0, 2, 1)).reshape(-1, 3)).reshape(5, 4))


@settings(max_examples=50, deadline=None)
@given(st.lists(polylines(min_points=2, max_points=8), min_size=1, max_size=3), st.data())
def test_bracket_holds_the_element_of_every_arc_length(lines, data):
    """The centres [lo, hi] bracketing an arc length s on a cable include
    both ends of an element holding s, and stay on that cable."""
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in lines])])
    pts = np.concatenate(lines)
    cable = np.repeat(np.arange(len(lines)), np.diff(offsets))
    seg = np.where(cable[:-1] == cable[1:], row_norm(pts[1:] - pts[:-1]), 0.0)
    s_c = polyline_arc_lengths(seg, offsets)
    c = data.draw(st.integers(0, len(lines) - 1))
    length = s_c[offsets[c + 1] - 1]
    s = data.draw(st.floats(0.0, 1.0)) * length
    lo, hi = bracket(s_c, cable, offsets, np.array([c]), np.array([s]))
    assert offsets[c] <= lo[0] <= hi[0] <= offsets[c + 1] - 1
    on = np.flatnonzero((s_c[offsets[c]:offsets[c + 1] - 1] <= s) & (s <= s_c[offsets[c] + 1:offsets[c + 1]]))
    e = offsets[c] + on
    assert len(e) == 0 or np.any((lo[0] <= e) & (e + 1 <= hi[0]))


def test_leading():
    assert leading(np.array([True, True, False, True])) == 2
    assert leading(np.array([True, True])) == 2 and leading(np.array([False])) == 0
