"""Twist from held end frames: analytic cases, brute-force transport, winding over time."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

from cablecheck.checker.twist import TwistMeter, transport, twist_angle, update_many


def _rot(axis, angle) -> np.ndarray:
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def _brute_transport(points: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Carry v edge by edge with explicit rotation matrices (axis t_k x t_k+1)."""
    t = np.diff(points, axis=0)
    t = t / np.linalg.norm(t, axis=1)[:, None]
    v = v - np.dot(v, t[0]) * t[0]
    v = v / np.linalg.norm(v)
    for a, b in zip(t[:-1], t[1:]):
        c = np.cross(a, b)
        if np.linalg.norm(c) > 1e-15:
            v = _rot(c, np.arctan2(np.linalg.norm(c), np.dot(a, b))) @ v
    return v


def test_straight_cable_with_end_turned_a_quarter_reads_90_degrees():
    pts = np.stack([np.linspace(0, 1, 21), np.zeros(21), np.zeros(21)], axis=1)
    meter = TwistMeter(pts, np.eye(3), np.eye(3))
    turned = _rot([1, 0, 0], np.radians(90))
    twist = meter.update(np.stack([pts, pts]), np.stack([np.eye(3)] * 2), np.stack([np.eye(3), turned]))
    assert np.allclose(np.degrees(twist), [0.0, 90.0], atol=1e-9)
    # turning the start the same way untwists it
    assert np.isclose(np.degrees(meter.update(pts[None], turned[None], turned[None]))[0], 0.0, atol=1e-9)


def test_planar_bent_cable_with_transported_frames_reads_no_twist():
    a = np.linspace(0, 0.75 * np.pi, 30)                 # an arc in the xy plane, turning 135 degrees
    pts = np.stack([np.sin(a), 1 - np.cos(a), np.zeros_like(a)], axis=1)
    heading = np.arctan2(*np.diff(pts, axis=0)[:, [1, 0]].T)
    start, end = _rot([0, 0, 1], heading[0]), _rot([0, 0, 1], heading[-1])   # frames with x along the cable
    local = np.array([0.0, 0.3, 1.0])                    # fixed in each frame, not perpendicular to the cable
    u = start @ local
    assert np.isclose(twist_angle(pts[None], u[None], (end @ local)[None])[0], 0.0, atol=1e-12)
    tangent = end @ [1.0, 0, 0]
    rolled = _rot(tangent, np.radians(-30)) @ end
    assert np.isclose(np.degrees(twist_angle(pts[None], u[None], (rolled @ local)[None])[0]), -30.0, atol=1e-9)


def test_winding_past_half_turns_is_counted():
    pts = np.stack([np.zeros(11), np.zeros(11), np.linspace(0, 0.5, 11)], axis=1)
    meter = TwistMeter(pts, np.eye(3), np.eye(3))
    angle = np.linspace(0, -3 * 2 * np.pi, 91)[1:]       # three turns, 12 degrees a state
    ends = np.stack([_rot([0, 0, 1], x) for x in angle])
    twist = np.concatenate([meter.update(np.repeat(pts[None], 30, 0), np.repeat(np.eye(3)[None], 30, 0), ends[k:k + 30])
                            for k in range(0, 90, 30)])   # in batches, as a run feeds it
    assert np.allclose(twist, angle, atol=1e-9)
    assert np.isclose(np.degrees(meter.max_abs), 1080.0)


def test_zero_length_edges_scale_and_distance_change_nothing():
    rng = np.random.default_rng(3)
    pts = np.cumsum(rng.normal(size=(12, 3)), axis=0)
    u, v = rng.normal(size=3), rng.normal(size=3)
    base = twist_angle(pts[None], u[None], v[None])[0]
    doubled = np.insert(pts, [0, 5, 12], pts[[0, 4, 11]], axis=0)     # repeated points at both ends and inside
    assert np.isclose(twist_angle(doubled[None], u[None], v[None])[0], base, atol=1e-12)
    moved = pts * 1e-3 + 2.2e4
    assert np.isclose(twist_angle(moved[None], u[None], v[None])[0], base, atol=1e-7)


def test_folded_back_edge_stays_finite():
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 0, 0], [0.5, 1, 0]])
    t_end, moved = transport(pts[None], np.array([[0.0, 0, 1]]))
    assert np.all(np.isfinite(moved)) and np.isclose(np.dot(t_end[0], moved[0]), 0.0, atol=1e-12)


_coord = st.floats(-1.0, 1.0)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(_coord, _coord, _coord), min_size=2, max_size=12),
       st.tuples(_coord, _coord, _coord))
def test_vectorised_transport_matches_edge_by_edge(points, vector):
    pts = np.array(points)
    e = np.diff(pts, axis=0)
    lengths = np.linalg.norm(e, axis=1)
    assume(lengths.min() > 1e-3)
    t = e / lengths[:, None]
    assume(np.all(np.einsum("ij,ij->i", t[:-1], t[1:]) > -0.99))     # no near cusps
    v = np.array(vector)
    assume(np.linalg.norm(np.cross(v, t[0])) > 1e-3)
    _, moved = transport(pts[None], v[None])
    assert np.allclose(moved[0], _brute_transport(pts, v), atol=1e-9)


def _wrist_scene(dynamics: bool, turns_deg: float) -> dict:
    """A straight cable along x from the world to a body that turns about x."""
    return {"scene": {"name": "w", "units": "m", "duration": 0.5, "settle": 0.0},
            "effects": {"dynamics": dynamics, "gravity": False},
            "bodies": [{"name": "wrist", "pos": [0.5, 0, 0.3]}],
            "cables": [{"name": "c", "radius": 0.004, "start": {"pos": [0, 0, 0.3]},
                        "end": {"body": "wrist", "pos": [0, 0, 0]}, "twist_stiffness": 2e7}],
            "motion": [{"body": "wrist", "keys": [{"t": 0.0, "euler": [0, 0, 0]},
                                                  {"t": 0.4, "euler": [turns_deg, 0, 0]}]}]}


def test_run_reports_the_twist_a_turning_end_winds_in(tmp_path):
    from cablecheck.run.runner import RunOptions, run_scene
    from cablecheck.scene.load import parse_scene
    for dynamics in (False, True):
        report = run_scene(parse_scene(_wrist_scene(dynamics, 90.0), tmp_path / "w.toml"),
                           RunOptions(report=tmp_path / "r.json", record=None))
        (cable,) = report["cables"]
        assert abs(cable["max_twist"] - 90.0) < (1e-6 if not dynamics else 0.5), dynamics
        moment = 2e7 * np.pi * 0.004 ** 4 / 2 * np.radians(cable["max_twist"]) / cable["length"]
        assert cable["twist_from"] == ("rod" if dynamics else "ends")
        if not dynamics:
            assert cable["max_twist_moment"] == pytest.approx(moment, rel=1e-12)
        else:
            # the rod's own largest moment: spread over a little less than the cable's
            # length (between the clamped edges' middles, tests/test_rodtwist.py), and
            # while the end turns, the vertex next to it leads by about one simulation
            # step of the turn (docs/twist.md): 2.6 % here
            assert moment < cable["max_twist_moment"] < 1.04 * moment


def test_update_many_is_each_meter_updated_alone():
    """Meters updated together (two cables of one point count, one of
    another) give the bits of each updated alone, step after step."""
    rng = np.random.default_rng(3)
    shapes = [np.cumsum(rng.normal(size=(n, 3)), axis=0) for n in (9, 9, 14)]
    rots = [np.linalg.qr(rng.normal(size=(2, 3, 3)))[0] for _ in shapes]
    alone = [TwistMeter(p, r[0], r[1]) for p, r in zip(shapes, rots)]
    together = [TwistMeter(p, r[0], r[1]) for p, r in zip(shapes, rots)]
    for _ in range(3):
        pts = [p[None] + 0.1 * rng.normal(size=(5,) + p.shape) for p in shapes]
        start = [np.linalg.qr(rng.normal(size=(5, 3, 3)))[0] for _ in shapes]
        end = [np.linalg.qr(rng.normal(size=(5, 3, 3)))[0] for _ in shapes]
        got = update_many(together, pts, start, end)
        for m, g, p, s, e in zip(alone, got, pts, start, end):
            assert np.array_equal(m.update(p, s, e), g)
    assert [m.max_abs for m in alone] == [m.max_abs for m in together]
