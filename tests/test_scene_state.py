"""The checker's input records (cablecheck.checker.scene_state): values that would
break the geometry are refused at construction, naming the record; good
ones are stored as float arrays."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from strategies import rotations

from cablecheck.checker.scene_state import CableState, CheckConfig, PartState
from cablecheck.checker.shapes import Shape, ShapeType

BOX = Shape(ShapeType.BOX, [0.1, 0.1, 0.1])


@given(rotations())
def test_any_rotation_is_a_pose_and_is_kept_as_floats(rot):
    pose = np.eye(4)
    pose[:3, :3] = rot
    part = PartState("frame/post", BOX, pose.tolist())
    assert part.pose.dtype == float and np.array_equal(part.pose, pose)


@pytest.mark.parametrize("pose, words", [
    (np.eye(3), "finite 4x4"),
    (np.where(np.eye(4) == 1, np.nan, 0.0), "finite 4x4"),
    (np.diag([1.0, 1.0, 1.001, 1.0]), "not orthonormal"),
    (np.diag([2.0, 1.0, 1.0, 1.0]), "not orthonormal"),
])
def test_bad_poses_are_refused_naming_the_part(pose, words):
    with pytest.raises(ValueError, match=f"part 'frame/post': pose .*{words}"):
        PartState("frame/post", BOX, pose)


def test_cable_points_radius_and_rest_coordinate_are_checked():
    pts = np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]])
    good = CableState("c", pts.astype(int), 0.01, rest_s=[0, 1, 2])
    assert good.points.dtype == float and good.rest_s.dtype == float
    for points in (pts[:1], pts[:, :2], np.where(pts == 2.0, np.inf, pts)):
        with pytest.raises(ValueError, match="cable 'c': points"):
            CableState("c", points, 0.01)
    for radius in (0.0, -1.0, np.nan, np.inf):
        with pytest.raises(ValueError, match="cable 'c': radius must be positive"):
            CableState("c", pts, radius)
    for rest in ([0.0, 1.0], [0.0, 1.0, 1.0], [0.0, np.nan, 2.0], [2.0, 1.0, 0.0]):
        with pytest.raises(ValueError, match=r"cable 'c': rest_s must be \(3,\) finite and strictly increasing"):
            CableState("c", pts, 0.01, rest_s=rest)


def test_check_config_refuses_unknown_methods_and_bad_numbers():
    assert CheckConfig("exact", spacing=1.5, clearance=0.0).clearance == 0.0
    with pytest.raises(ValueError, match="method must be 'points' or 'exact'"):
        CheckConfig("sampled")
    for spacing in (0.0, -2.0, np.nan):
        with pytest.raises(ValueError, match="spacing must be positive"):
            CheckConfig(spacing=spacing)
    for clearance in (-1e-9, np.inf):
        with pytest.raises(ValueError, match="clearance must be >= 0"):
            CheckConfig(clearance=clearance)


def test_with_points_is_replace_with_its_checks():
    """A cable at other centres is what dataclasses.replace makes (every
    field, the points as floats), and the points are checked as the
    constructor checks them: as many, finite."""
    import dataclasses

    import numpy as np
    import pytest

    from cablecheck.checker.scene_state import CableState

    cable = CableState("a", np.zeros((4, 3)) + np.arange(4)[:, None], 0.01, 0.05, 3.0, np.arange(4.0))
    moved = np.arange(12, dtype=np.int64).reshape(4, 3)
    got, want = cable.with_points(moved), dataclasses.replace(cable, points=moved)
    for field in dataclasses.fields(CableState):
        np.testing.assert_array_equal(getattr(got, field.name), getattr(want, field.name))
    assert got.points.dtype == want.points.dtype == float
    assert got.rest_s is cable.rest_s and cable.points[1, 0] == 1.0          # the original untouched
    with pytest.raises(ValueError, match="points must be"):
        cable.with_points(np.zeros((3, 3)))
    bad = np.zeros((4, 3))
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        cable.with_points(bad)
