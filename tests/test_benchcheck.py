"""The checker's bench tables (cablecheck.bench.checker_tables): the comparison against the
exact reference counts misses and false alarms as defined, and the scaling
exponent fit recovers a power law. The tables themselves run in test_bench
on the tiny sizes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, strategies as st

from cablecheck.bench.checker_tables import _compare, _fit_exponent


def test_compare_counts_misses_false_alarms_and_the_worst_error():
    ref = {("self", "a", "a"): -0.002, ("cable-cable", "a", "b"): 0.001, ("keepout", "a", "z"): -0.001,
           ("cable-structure", "b", "p"): 0.003}
    got = {("self", "a", "a"): -0.0015,                     # found, 0.5 mm off
           ("keepout", "a", "z"): 0.0005,                    # found but not as a hit: a missed hard
           ("cable-structure", "b", "p"): -0.001,            # a hit where the reference is clear
           ("cable-cable", "b", "c"): 0.002}                 # a pair the reference lacks
    missed_hard, missed, false, worst = _compare(ref, got)
    assert (missed_hard, missed, false) == (1, 1, 2)
    assert worst == pytest.approx(0.004, abs=1e-15)
    assert _compare(ref, ref) == (0, 0, 0, 0.0) and _compare({}, {}) == (0, 0, 0, 0.0)


@given(st.floats(-3.0, 3.0), st.floats(1e-3, 1e3))
def test_fit_exponent_recovers_a_power_law(p, c):
    x = np.array([10.0, 20.0, 40.0, 80.0, 160.0])
    assert _fit_exponent(x, c * x ** p) == pytest.approx(p, abs=1e-9)
