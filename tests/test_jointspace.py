"""Joint space of a run (cablecheck.run.jointspace) on the example arm: joint values in
degrees at the worst moment, the link a pair rides on with the joints that
move it (nearest first), and ranges over an event that equal a dense
brute-force scan of the script."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cablecheck.build.stages import build
from cablecheck.run.jointspace import JointLog
from cablecheck.run.motion import Motion
from cablecheck.scene.load import load_scene

ARM = Path(__file__).resolve().parents[1] / "scenes" / "arm.toml"


@pytest.fixture(scope="module")
def arm():
    built = build(load_scene(ARM), detect=False)
    motion = Motion(built)
    return JointLog(built, motion), motion


def _scan(motion, names, t0, t1):
    fine = np.degrees(motion.joint_values(np.linspace(t0, t1, 4001), names))
    return np.stack([fine.min(axis=0), fine.max(axis=0)], axis=1)


def _bounds_the_scan(ranges, scan):
    """The exact range holds every scanned value and is no wider than the
    scan's resolution (a sample's extreme falls between scan points)."""
    got = np.array(list(ranges.values()))
    assert np.all(got[:, 0] <= scan[:, 0] + 1e-12) and np.all(got[:, 1] >= scan[:, 1] - 1e-12)
    assert np.allclose(got, scan, rtol=0, atol=1e-5)


def test_values_are_the_scripts_in_degrees(arm):
    log, motion = arm
    assert log and log.names == ["base_yaw", "shoulder_pitch", "elbow"] and log.units == ["deg"] * 3
    times = np.linspace(0.0, 3.0, 13)
    assert np.allclose(log.values(times), np.degrees(motion.joint_values(times, log.names)), rtol=0, atol=1e-12)


@pytest.mark.parametrize("t0, t1", [(0.5, 1.7), (0.0, 3.0), (1.2, 1.3)])
def test_an_event_on_a_link_names_it_and_the_joints_that_move_it(arm, t0, t1):
    log, motion = arm
    fields = log.event_fields(t0, t1, 0.5 * (t0 + t1), "hose", "upper_arm/upper_link")
    assert fields["link"] == "upper_arm"
    assert list(fields["joint_ranges"]) == ["shoulder_pitch", "base_yaw"]     # nearest joint first
    scan = _scan(motion, ["shoulder_pitch", "base_yaw"], t0, t1)
    _bounds_the_scan(fields["joint_ranges"], scan)
    worst = np.degrees(motion.joint_values([0.5 * (t0 + t1)], log.names))[0]
    assert np.allclose(list(fields["joints"].values()), worst, rtol=0, atol=1e-12)
    tool = log.event_fields(t0, t1, t0, "tool/flange", "hose")
    assert tool["link"] == "tool" and list(tool["joint_ranges"]) == ["elbow", "shoulder_pitch", "base_yaw"]


def test_an_event_on_no_moving_link_ranges_every_joint(arm):
    log, motion = arm
    fields = log.event_fields(0.5, 1.7, 1.0, "hose", "cell/floor")
    assert fields["link"] is None
    assert list(fields["joint_ranges"]) == log.names
    _bounds_the_scan(fields["joint_ranges"], _scan(motion, log.names, 0.5, 1.7))
