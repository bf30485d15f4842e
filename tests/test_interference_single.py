"""Bend and taut (cablecheck.checker.interference.single): the batched records are the single-state check's, bit for bit."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from strategies import coords, polylines

from cablecheck.checker.cable import CableMeasures
from cablecheck.checker.interference import Checker, single_records_many
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import CableState, CheckConfig

pytestmark = pytest.mark.filterwarnings("error")


def _assert_batched_is_single_state(pts, offsets, rest, limit) -> set:
    """single_records_many on states (S, N, 3) gives, state by state, the
    bend and taut records of Checker.check (bits and places included);
    returns the record types seen."""
    names = [f"c{k}" for k in range(len(offsets) - 1)]
    _, _, radius_at = CableMeasures(offsets).many(pts, at_points=True)
    got = single_records_many(names, pts, offsets, radius_at, rest, limit, 0.005)
    checker = Checker([], CheckConfig(clearance=0.005))
    seen = set()
    for state in range(len(pts)):
        cables = [CableState(n, pts[state, a:b], 0.004, None if np.isnan(lim) else float(lim), float(rl))
                  for n, a, b, lim, rl in zip(names, offsets[:-1], offsets[1:], limit, rest)]
        want = [r for r in checker.check(cables) if r.type in (PairType.BEND, PairType.TAUT)]
        assert [(r.type, r.a, r.min_distance, r.s, r.severity) for r in got[state]] == \
            [(r.type, r.a, r.min_distance, r.s, r.severity) for r in want]
        assert all(np.array_equal(a.where, b.where) for a, b in zip(got[state], want))
        seen |= {r.type for r in want}
    return seen


def test_single_records_many_is_each_states_bend_and_taut():
    rng = np.random.default_rng(8)
    seen = set()
    for trial in range(40):
        counts = rng.integers(3, 12, rng.integers(1, 4))
        offsets = np.concatenate([[0], np.cumsum(counts)])
        n_s = int(rng.integers(1, 5))
        pts = np.cumsum(rng.normal(size=(n_s, offsets[-1], 3)) * 0.01, axis=1)
        if trial % 4 == 0:
            pts[:, 2] = pts[:, 1]                        # a zero-length element
        rest = np.array([float(np.sum(np.linalg.norm(np.diff(pts[0, a:b], axis=0), axis=1)))
                         for a, b in zip(offsets[:-1], offsets[1:])]) * rng.uniform(0.97, 1.01, len(counts))
        limit = np.where(rng.random(len(counts)) < 0.7, rng.uniform(0.001, 0.02, len(counts)), np.nan)
        seen |= _assert_batched_is_single_state(pts, offsets, rest, limit)
    assert seen == {PairType.BEND, PairType.TAUT}


@settings(max_examples=40, deadline=None)
@given(st.lists(polylines(min_points=3, max_points=10, step=0.01), min_size=1, max_size=3), st.data())
def test_single_kernel_batched_equals_single_state(lines, data):
    """single_rows through single_records_many (many states at once) and
    through Checker.check (one state): the same bend and taut records, bits
    and places included, on drawn polylines, limits and rest lengths."""
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in lines])])
    n_s = data.draw(st.integers(1, 3))
    base = np.concatenate(lines)
    pts = base[None] + data.draw(coords((n_s, len(base), 3), -0.004, 0.004))
    length = np.array([float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1))) for p in lines])
    rest = length * np.array(data.draw(st.lists(st.floats(0.95, 1.03), min_size=len(lines), max_size=len(lines))))
    limit = np.array(data.draw(st.lists(st.one_of(st.just(np.nan), st.floats(0.0005, 0.05)),
                                        min_size=len(lines), max_size=len(lines))))
    _assert_batched_is_single_state(pts, offsets, rest, limit)
