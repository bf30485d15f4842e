"""Exclusion windows as arrays: every selection equals the windows picked one by one."""

import numpy as np
from hypothesis import given, settings, strategies as st

from cablecheck.checker.interference.exclusions import exclusion_arrays
from cablecheck.checker.scene_state import Exclusion

CABLES = ["a", "b", "c", "d"]
PARTS = ["p0", "p1", "p2", "q"]


def _reference(exclusions, cable_names, part_names):
    """The windows picked in a loop, in list order, then stably sorted by
    key; the points' ends (``excl``) one ulp inside the window where it ends
    inside the cable: past 0 (its start), and short of its end unless it
    reaches it (``to_end``)."""
    cidx = {n: i for i, n in enumerate(cable_names)}
    pidx = {n: i for i, n in enumerate(part_names)}
    rows = [(cidx[e.cable], pidx[e.part], min(e.s_min, e.s_max), max(e.s_min, e.s_max), e.to_end)
            for e in exclusions if e.cable in cidx and e.part in pidx]
    c = np.array([r[0] for r in rows], np.int64)
    p = np.array([r[1] for r in rows], np.int64)
    lo = np.array([r[2] for r in rows], float)
    hi = np.array([r[3] for r in rows], float)
    point_lo = np.array([r[2] if r[2] <= 0.0 else np.nextafter(r[2], 2.0) for r in rows], float)
    point_hi = np.array([r[3] if r[4] else np.nextafter(r[3], -2.0) for r in rows], float)
    n = max(len(part_names), 1)
    key = c * n + p
    o = np.argsort(key, kind="stable")
    return (key[o], point_lo[o], point_hi[o], n), c, lo, hi


windows = st.lists(st.builds(Exclusion, st.sampled_from(CABLES + ["x"]), st.sampled_from(PARTS + ["y"]),
                             st.floats(-1, 1), st.floats(-1, 1), st.just(""), st.booleans()), max_size=30)


@settings(max_examples=60, deadline=None)
@given(windows, st.lists(st.sampled_from(CABLES), unique=True), st.lists(st.sampled_from(PARTS), unique=True))
def test_table_matches_the_windows_picked_one_by_one(exclusions, cable_names, part_names):
    arrays = exclusion_arrays(exclusions)
    got = arrays.table(cable_names, arrays.part_map({n: i for i, n in enumerate(part_names)}), len(part_names))
    want = _reference(exclusions, cable_names, part_names)
    for g, w in zip(got.excl[:3], want[0][:3]):
        np.testing.assert_array_equal(g, w)
    assert got.excl[3] == want[0][3]
    for g, w in zip((got.cable, got.lo, got.hi), want[1:]):
        np.testing.assert_array_equal(g, w)


def test_one_list_is_built_once_and_a_changed_length_rebuilds():
    exclusions = [Exclusion("a", "p0", 0.0, 0.1)]
    first = exclusion_arrays(exclusions)
    assert exclusion_arrays(exclusions) is first
    exclusions.append(Exclusion("b", "p1", 0.2, 0.1))
    again = exclusion_arrays(exclusions)
    assert again is not first and len(again.part) == 2
