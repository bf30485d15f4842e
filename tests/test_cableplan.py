"""Cable plans (sim.cableplan): a points route starts exactly on its points,
is checked as given without dynamics, runs through every point with slack;
routes the plan cannot keep are refused."""

from __future__ import annotations

import numpy as np
from buildscenes import run_steps, slider_scene

from sim.build import build
from sim.scene import parse_scene


def test_points_cable_starts_exactly_on_its_points(tmp_path):
    pts = [[0, 0, 0.5], [0.2, 0, 0.45], [0.4, 0, 0.45], [0.6, 0, 0.5]]
    data = slider_scene(tmp_path)
    data["cables"][0] = {"name": "c", "radius": 0.004, "points": pts, "end": {"body": "slider"}, "segments": 30}
    built = build(parse_scene(data, tmp_path / "s.toml"))
    routed = built.cables[0].routed
    assert np.allclose(routed[[0, -1]], [pts[0], pts[-1]])
    seg_len = np.linalg.norm(np.diff(routed, axis=0), axis=1).sum()
    p = np.asarray(pts, float)
    assert np.isclose(seg_len, np.linalg.norm(np.diff(p, axis=0), axis=1).sum(), rtol=1e-3)


def _points_scene(dynamics: bool, length=None, segments=None) -> dict:
    a = np.linspace(0.0, np.pi, 9)
    points = np.stack([0.2 * np.cos(a), 0.05 * np.sin(2 * a), 0.3 + 0.1 * np.sin(a)], axis=1)
    cable = {"name": "c", "radius": 0.004, "points": points.tolist()}
    if length is not None:
        cable["length"] = length
    if segments is not None:
        cable["segments"] = segments
    return {"scene": {"name": "p", "units": "m", "duration": 0.0, "settle": 0.2},
            "effects": {"dynamics": dynamics}, "cables": [cable]}, points


def _distance_to_polyline(points: np.ndarray, route: np.ndarray) -> np.ndarray:
    a, b = route[:-1], route[1:]
    ab = b - a
    t = np.clip(np.einsum("pij,ij->pi", points[:, None, :] - a[None], ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
    return np.linalg.norm(points[:, None, :] - (a[None] + t[:, :, None] * ab[None]), axis=2).min(axis=1)


def test_points_route_with_dynamics_off_is_checked_as_given(tmp_path):
    data, points = _points_scene(dynamics=False, segments=20)
    sim, states = run_steps(data, tmp_path)
    checked = states[0].cables[0]
    assert len(checked) == 23   # 20 elements and the short held edge of each clamped end
    assert _distance_to_polyline(checked, points).max() < 1e-12      # on the given centreline
    assert all(np.abs(checked - p).sum(axis=1).min() < 1e-12 for p in points)   # every point a vertex
    route = float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())
    assert np.isclose(sim.built.cables[0].length, route, rtol=1e-12)


def test_points_route_longer_than_given_with_dynamics_off_is_refused(tmp_path):
    import pytest

    from sim.scene import SceneError
    data, points = _points_scene(dynamics=False, length=0.8)
    with pytest.raises(SceneError, match="checked as given") as e:
        parse_scene(data, tmp_path / "s.toml")
    assert e.value.key == "cables[0].length"


def test_points_route_with_slack_starts_through_every_point(tmp_path):
    data, points = _points_scene(dynamics=True, length=0.8)
    built = build(parse_scene(data, tmp_path / "s.toml"))
    routed = built.cables[0].routed
    assert all(np.abs(routed - p).sum(axis=1).min() < 1e-12 for p in points)
    assert np.isclose(np.linalg.norm(np.diff(routed, axis=0), axis=1).sum(), 0.8, rtol=1e-9)


def test_too_few_segments_for_the_points_is_refused(tmp_path):
    import pytest

    from sim.scene import SceneError
    data, _ = _points_scene(dynamics=True, segments=6)
    with pytest.raises(SceneError, match="at least 8") as e:
        parse_scene(data, tmp_path / "s.toml")
    assert e.value.key == "cables[0].segments"
