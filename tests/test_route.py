"""Initial cable shapes: requested length, fixed ends, droop direction."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings, strategies as st

from sim.route import initial_shape, polyline_length, resample_even


def test_straight_route_of_its_own_length_stays_straight():
    route = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    pts = initial_shape(route, 1.0, 11)
    assert np.allclose(pts[:, 0], np.linspace(0, 1, 11)) and np.allclose(pts[:, 1:], 0)


def test_longer_cable_droops_down_with_exact_element_length():
    route = np.array([[0.0, 0, 1], [0.8, 0, 1]])
    pts = initial_shape(route, 1.0, 41)
    assert np.isclose(polyline_length(pts), 1.0, rtol=1e-9)
    assert np.allclose(pts[0], route[0]) and np.allclose(pts[-1], route[-1])
    assert pts[:, 2].min() < 1.0 - 0.2 and np.allclose(pts[:, 1], 0)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert seg.max() / seg.min() < 1.05  # evenly spaced elements


def test_vertical_run_droops_sideways():
    route = np.array([[0.0, 0, 0], [0.0, 0, 1]])
    pts = initial_shape(route, 1.2, 21)
    assert np.isclose(polyline_length(pts), 1.2, rtol=1e-9)
    assert np.abs(pts[:, :2]).max() > 0.1


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(*[st.floats(-5, 5)] * 3), min_size=2, max_size=5),
       st.floats(1.0, 2.0), st.integers(3, 60), st.sampled_from([1.0, 1e-3]))
def test_length_and_ends_hold_for_any_route(points, stretch, count, unit):
    route = np.array(points) * unit
    if np.linalg.norm(np.diff(route, axis=0), axis=1).min() < 1e-3 * unit:
        return
    length = polyline_length(route) * stretch
    pts = initial_shape(route, length, count)
    assert np.all(np.isfinite(pts))
    assert np.isclose(polyline_length(pts), length, rtol=1e-6)
    assert np.allclose(pts[[0, -1]], route[[0, -1]], atol=1e-12 * unit + 1e-12)


def test_resample_even_keeps_ends_and_spacing():
    route = np.array([[0.0, 0, 0], [1.0, 0, 0], [1.0, 1.0, 0]])
    pts = resample_even(route, 5)
    assert np.allclose(pts, [[0, 0, 0], [0.5, 0, 0], [1, 0, 0], [1, 0.5, 0], [1, 1, 0]])


def test_uneven_dense_route_gets_nearly_equal_elements():
    # a long lead-in, then many short runs (a `points` route), with slack
    lead = [[-0.11, 0, 0]]
    coil = [[0.02 * np.cos(a), 0.0, 0.02 * np.sin(a)] for a in np.linspace(0, 2 * np.pi, 18)]
    route = np.array(lead + coil)
    length = polyline_length(route) * 1.02
    pts = initial_shape(route, length, 37)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert np.isclose(seg.sum(), length, rtol=1e-6)
    assert seg.max() / seg.min() < 2.5


def test_route_without_slack_is_resampled_evenly():
    route = np.array([[0.0, 0, 0], [0.3, 0, 0], [0.6, 0.03, 0]])
    pts = initial_shape(route, polyline_length(route), 61)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert np.allclose(seg, seg.mean(), rtol=1e-3)  # an element across the corner is a chord
