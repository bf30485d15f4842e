"""Keyframe interpolation: positions, slerp, velocities, holding before and after."""

from __future__ import annotations

import mujoco
import numpy as np

from sim.motion import BodyTrack, JointTrack, slerp


def _quat_z(deg: float) -> np.ndarray:
    h = np.radians(deg) / 2
    return np.array([np.cos(h), 0, 0, np.sin(h)])


def test_body_track_interpolates_and_holds():
    track = BodyTrack(0, 0, np.array([1.0, 3.0]), np.array([[0, 0, 0], [2.0, 0, 0]]),
                      np.array([_quat_z(0), _quat_z(90)]))
    pos, quat, vel, omega = track.at(2.0)
    assert np.allclose(pos, [1, 0, 0]) and np.allclose(quat, _quat_z(45))
    assert np.allclose(vel, [1, 0, 0]) and np.allclose(omega, [0, 0, np.radians(45)])
    for t, expect in ((0.0, 0), (5.0, 1)):
        pos, quat, vel, omega = track.at(t)
        assert np.allclose(pos, track.pos[expect]) and not vel.any() and not omega.any()


def test_slerp_takes_short_arc_and_stays_unit():
    q = slerp(_quat_z(10), -_quat_z(30), 0.5)  # -q is the same rotation
    assert np.isclose(np.linalg.norm(q), 1)
    assert np.isclose(abs(np.dot(q, _quat_z(20))), 1)


def test_angular_velocity_integrates_to_next_key():
    q0, q1 = _quat_z(0), np.array([0.9, 0.1, 0.3, 0.3]) / np.linalg.norm([0.9, 0.1, 0.3, 0.3])
    track = BodyTrack(0, 0, np.array([0.0, 0.5]), np.zeros((2, 3)), np.array([q0, q1]))
    *_, omega = track.at(0.1)
    q = q0.copy()
    mujoco.mju_quatIntegrate(q, omega, 0.5)
    assert np.allclose(q, q1, atol=1e-12) or np.allclose(q, -q1, atol=1e-12)


def test_joint_track_value_and_velocity():
    track = JointTrack(0, 0, np.array([0.0, 2.0]), np.array([0.0, -1.0]))
    assert track.at(1.0) == (-0.5, -0.5)
    assert track.at(-1.0) == (0.0, 0.0) and track.at(3.0) == (-1.0, 0.0)
