"""Initial cable shapes: waypoints kept as vertices, requested length, droop away from parts."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cablecheck.build.route import initial_shape, polyline_length, resample_even, run_elements


def _on_polyline(points: np.ndarray, route: np.ndarray) -> np.ndarray:
    """(n,) distance of each point to the polyline `route` (brute force)."""
    a, b = route[:-1], route[1:]
    ab = b - a
    t = np.clip(np.einsum("pij,ij->pi", points[:, None, :] - a[None], ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
    closest = a[None] + t[:, :, None] * ab[None]
    return np.linalg.norm(points[:, None, :] - closest, axis=2).min(axis=1)


def test_straight_route_of_its_own_length_stays_straight():
    route = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    pts = initial_shape(route, 1.0, [10])
    assert np.allclose(pts[:, 0], np.linspace(0, 1, 11)) and np.allclose(pts[:, 1:], 0)


def test_longer_cable_droops_down_with_exact_element_length():
    route = np.array([[0.0, 0, 1], [0.8, 0, 1]])
    pts = initial_shape(route, 1.0, [40])
    assert np.isclose(polyline_length(pts), 1.0, rtol=1e-9)
    assert np.array_equal(pts[0], route[0]) and np.array_equal(pts[-1], route[-1])
    assert pts[:, 2].min() < 1.0 - 0.2 and np.allclose(pts[:, 1], 0)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert seg.max() / seg.min() < 1.05  # evenly spaced elements


def test_vertical_run_droops_sideways():
    route = np.array([[0.0, 0, 0], [0.0, 0, 1]])
    pts = initial_shape(route, 1.2, [20])
    assert np.isclose(polyline_length(pts), 1.2, rtol=1e-9)
    assert np.abs(pts[:, :2]).max() > 0.1


def test_points_route_without_slack_is_its_polyline_with_every_point_a_vertex():
    # a dense curved route with uneven spacing: nothing is resampled across corners
    a = np.linspace(0, 1.5 * np.pi, 23) ** 1.3
    route = np.stack([0.1 * np.cos(a), 0.1 * np.sin(a), 0.01 * a], axis=1)
    runs = np.linalg.norm(np.diff(route, axis=0), axis=1)
    counts = run_elements(runs, 60)
    pts = initial_shape(route, polyline_length(route), counts)
    assert len(pts) == 61
    vertex_of_point = np.concatenate([[0], np.cumsum(counts)])
    assert np.array_equal(pts[vertex_of_point], route)
    assert _on_polyline(pts, route).max() < 1e-15
    assert np.isclose(polyline_length(pts), polyline_length(route), rtol=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(*[st.floats(-5, 5)] * 3), min_size=2, max_size=6),
       st.floats(1.0, 2.0), st.integers(0, 40), st.sampled_from([1.0, 1e-3]))
def test_length_ends_and_waypoints_hold_for_any_route(points, stretch, extra, unit):
    route = np.array(points) * unit
    runs = np.linalg.norm(np.diff(route, axis=0), axis=1)
    if runs.min() < 1e-3 * unit:
        return
    length = polyline_length(route) * stretch
    counts = run_elements(runs, len(runs) + 1 + extra)
    pts = initial_shape(route, length, counts)
    assert np.all(np.isfinite(pts))
    assert np.isclose(polyline_length(pts), length, rtol=1e-6)
    assert np.array_equal(pts[np.concatenate([[0], np.cumsum(counts)])], route)


@given(st.lists(st.floats(1e-3, 10.0), min_size=1, max_size=30), st.integers(0, 100))
def test_run_elements_share_in_proportion(runs, extra):
    runs = np.array(runs)
    elements = len(runs) + extra
    counts = run_elements(runs, elements)
    assert counts.sum() == elements and counts.min() >= 1
    # no run above the floor of one element has a whole element more than its share
    share = runs / runs.sum() * elements
    assert np.all((counts == 1) | (counts - share < 1.0 + 1e-9))


def test_run_elements_refuses_fewer_elements_than_runs():
    with pytest.raises(ValueError, match="waypoints as vertices"):
        run_elements(np.ones(5), 4)


def test_slack_without_a_run_of_two_elements_is_refused():
    route = np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]])
    with pytest.raises(ValueError, match="two elements"):
        initial_shape(route, 2.5, [1, 1])


def _floor_depth(radius: float):
    """Depth into the half-space z < 0 of a cable vertex of `radius`."""
    return lambda p: radius - p[:, 2]


def test_run_on_a_floor_droops_sideways_not_into_it():
    r = 0.005
    route = np.array([[0.0, 0, 0], [0.3, 0, 0], [0.6, 0.1, 0]])   # centreline on the floor surface
    counts = run_elements(np.linalg.norm(np.diff(route, axis=0), axis=1), 30)
    down = initial_shape(route, 0.8, counts)
    assert down[:, 2].min() < -0.05                                 # the old droop: into the floor
    pts = initial_shape(route, 0.8, counts, depth=_floor_depth(r))
    assert np.isclose(polyline_length(pts), 0.8, rtol=1e-9)
    assert np.abs(pts[:, 2]).max() < 1e-12                           # lies on the floor, snaking sideways
    assert np.abs(pts[:, 1]).max() > 0.05


def test_droop_turns_only_as_far_as_it_must():
    # a ledge: a box below z = 0 for y < 0.02; beyond it the cable may hang down
    r = 0.002

    def depth(p):
        inside = np.minimum(-p[:, 2], 0.02 - p[:, 1])      # >0 inside the quarter space
        outside = np.hypot(np.maximum(p[:, 2], 0), np.maximum(p[:, 1] - 0.02, 0))
        return r - np.where(inside > 0, -inside, outside)

    route = np.array([[0.0, 0.0, 0.01], [0.5, 0.0, 0.01]])
    pts = initial_shape(route, 0.6, [40], depth=depth)
    assert depth(pts).max() <= 1e-9                                      # the straight run is clear: so is the droop
    mid = pts[20]
    angle = np.degrees(np.arctan2(mid[1], -(mid[2] - 0.01)))
    assert 0 < angle < 90                                                # turned off straight down, not all the way up


def test_resample_even_keeps_ends_and_spacing():
    route = np.array([[0.0, 0, 0], [1.0, 0, 0], [1.0, 1.0, 0]])
    pts = resample_even(route, 5)
    assert np.allclose(pts, [[0, 0, 0], [0.5, 0, 0], [1, 0, 0], [1, 0.5, 0], [1, 1, 0]])
