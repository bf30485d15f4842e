"""Interpolation of scripted motion (cablecheck.run.curves): linear exact and held
outside, cubic with a continuous velocity equal to the derivative, no
overshoot between samples, merged motions each on their own times."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings, strategies as st

from cablecheck.run.curves import interpolant, merge


def test_linear_is_exact_and_holds_outside():
    curve = merge([interpolant(np.array([1.0, 3.0]), np.array([[0.0], [-2.0]]), "linear")])
    assert np.allclose(curve.at(2.0), ([-1.0], [-1.0]))
    assert np.allclose(curve.at(0.0), ([0.0], [0.0])) and np.allclose(curve.at(5.0), ([-2.0], [0.0]))


def test_cubic_has_continuous_velocity_equal_to_the_derivative():
    times = np.array([0.0, 0.4, 1.0, 1.7, 2.0])
    values = np.array([[0.0, 1.0], [0.3, -1.0], [1.0, 0.5], [0.2, 0.5], [-0.5, 2.0]])
    curve = merge([interpolant(times, values, "cubic")])
    h = 1e-7
    for knot in times:
        left, right = curve.at(knot - h)[1], curve.at(knot + h)[1]
        assert np.allclose(left, right, atol=1e-5)                      # no jump at a sample
    for t in np.linspace(0.01, 1.99, 37):
        fd = (curve.at(t + h)[0] - curve.at(t - h)[0]) / (2 * h)
        assert np.allclose(curve.at(t)[1], fd, atol=1e-5)               # rate = d value / dt
    assert np.allclose(curve.at(0.0)[1], 0.0) and np.allclose(curve.at(2.0)[1], 0.0)
    assert np.allclose(curve.sample(times), values)


@settings(max_examples=60)
@given(st.lists(st.floats(-100, 100), min_size=2, max_size=8), st.sampled_from(["cubic", "linear"]))
def test_interpolants_stay_between_neighbouring_samples(ys, kind):
    """No overshoot: the joint-range check of the samples bounds the whole motion."""
    times = np.arange(len(ys), dtype=float)
    values = np.array(ys)[:, None]
    poly = interpolant(times, values, kind)
    fine = np.linspace(0.0, len(ys) - 1.0, 40 * len(ys))
    got = poly(fine)[:, 0]
    i = np.minimum(fine.astype(int), len(ys) - 2)
    lo = np.minimum(values[i, 0], values[i + 1, 0])
    hi = np.maximum(values[i, 0], values[i + 1, 0])
    assert np.all(got >= lo - 1e-9) and np.all(got <= hi + 1e-9)


def test_merge_keeps_each_motion_on_its_own_times():
    a = interpolant(np.array([0.0, 1.0, 3.0]), np.array([[0.0, 0.0], [1.0, 2.0], [1.0, 5.0]]), "cubic")
    b = interpolant(np.array([0.5, 2.0]), np.array([[3.0], [4.0]]), "linear")
    c = interpolant(np.array([4.0]), np.array([[7.0]]), "cubic")
    curve = merge([a, b, c])
    ts = np.linspace(-1.0, 5.0, 601)
    got = curve.sample(ts)
    assert np.allclose(got[:, :2], a(np.clip(ts, 0.0, 3.0)), atol=1e-12)
    assert np.allclose(got[:, 2], b(np.clip(ts, 0.5, 2.0))[:, 0], atol=1e-12)
    assert np.allclose(got[:, 3], 7.0)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-3.0, 3.0), min_size=2, max_size=6), st.sampled_from(["cubic", "linear"]),
       st.lists(st.floats(-1.0, 7.0), min_size=1, max_size=30))
def test_at_many_is_at_time_by_time_to_the_bit(ys, kind, ts):
    """The loop evaluates a block of steps' times at once: the same bits as
    one `at` after the other, breakpoints, ends and times outside included."""
    times = np.arange(len(ys), dtype=float) * 1.3
    ts = np.array(ts + [0.0, times[-1], times[1]])
    curve = merge([interpolant(times, np.column_stack([ys, np.square(ys)]), kind)])
    value, rate = curve.at_many(ts)
    for t, v, r in zip(ts, value, rate):
        one_v, one_r = curve.at(float(t))
        assert np.array_equal(v, one_v) and np.array_equal(r, one_r)


@settings(max_examples=80, deadline=None)
@given(st.lists(st.sampled_from([0.0, 60.0, -45.0, 1e-3, 179.99]), min_size=2, max_size=7),
       st.lists(st.floats(0.01, 3.0), min_size=6, max_size=6), st.sampled_from(["cubic", "linear"]),
       st.lists(st.floats(-1.0, 8.0), min_size=1, max_size=30))
def test_a_motion_never_leaves_its_samples_range_even_by_rounding(ys, steps, kind, ts):
    """Keys repeated at their extremes (a joint keyed at its range's end, back
    to 0 at the last key), on uneven times, evaluated anywhere (the keys'
    times and the last included): every value lies within the samples' least
    and greatest exactly, as `at`, `at_many` and `sample` give it; the
    polynomial alone leaves them by rounding (keys 0, 60, 0 over 1 s each:
    -4.4e-16 at the end)."""
    times = np.concatenate([[0.0], np.cumsum(steps[:len(ys) - 1])])
    values = np.radians(np.array(ys))[:, None]
    curve = merge([interpolant(times, values, kind)], [values])
    t = np.concatenate([times, np.array(ts)])
    got = np.concatenate([curve.sample(t)[:, 0], curve.at_many(t)[0][:, 0], [curve.at(float(x))[0][0] for x in t]])
    assert got.min() >= values.min() and got.max() <= values.max()


def test_keys_back_to_zero_read_zero_at_the_last():
    times, values = np.array([0.0, 1.0, 2.0]), np.radians(np.array([[0.0], [60.0], [0.0]]))
    poly = interpolant(times, values, "cubic")
    assert poly(2.0)[0] != 0.0                      # the sum of the last interval's rounded terms
    assert merge([poly], [values]).at(2.0)[0][0] == 0.0
