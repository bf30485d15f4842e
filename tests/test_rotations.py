"""Rotations as written: a body's euler keys are interpolated as the numbers
are written (keys 0, 270, -270, 0 turn +270 degrees, 540 back, then 270 to
0), never the short way, through `Motion` (keys and CSV files, linear and
cubic), the step loop's poses and a whole `cablecheck run`.

Expected values are computed here on their own: the written numbers
interpolated by `np.interp` or by a Fritsch-Carlson cubic written out below
(zero slopes at the first and last sample, as `cablecheck.run.curves` documents), and
turned into rotations by scipy's `Rotation.from_euler('XYZ')` (MuJoCo's
intrinsic x, y, z).
"""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.spatial.transform import Rotation

from cablecheck.build.stages import build
from cablecheck.cli.main import main
from cablecheck.run.loop import Simulation
from cablecheck.run.motion import Motion
from cablecheck.scene.load import load_scene, parse_scene

TURNS = ([0.0, 1.0, 2.0, 3.0], [0.0, 270.0, -270.0, 0.0])
"""The turntable's key times (s) and z angles (degrees)."""


def written_linear(times, t_keys, values) -> np.ndarray:
    """(m, C) straight lines between the written `values` (n, C), held outside."""
    values = np.asarray(values, float).reshape(len(t_keys), -1)
    return np.column_stack([np.interp(times, t_keys, v) for v in values.T])


def written_cubic(times, t_keys, values) -> np.ndarray:
    """(m, C) piecewise cubic Hermite through the written `values` (n, C):
    Fritsch-Carlson slopes (weighted harmonic mean of the neighbouring
    secants where they have one sign, else 0), 0 at both ends; held outside."""
    t = np.asarray(t_keys, float)
    y = np.asarray(values, float).reshape(len(t), -1)
    if len(t) == 1:
        return np.repeat(y, len(np.atleast_1d(times)), axis=0)
    h = np.diff(t)[:, None]
    secant = np.diff(y, axis=0) / h
    slope = np.zeros_like(y)
    if len(t) > 2:
        m0, m1, h0, h1 = secant[:-1], secant[1:], h[:-1], h[1:]
        w1, w2 = 2.0 * h1 + h0, h1 + 2.0 * h0
        same = np.sign(m0) * np.sign(m1) > 0
        with np.errstate(divide="ignore", invalid="ignore"):
            slope[1:-1] = np.where(same, (w1 + w2) / (w1 / m0 + w2 / m1), 0.0)
    x = np.clip(np.asarray(times, float), t[0], t[-1])
    i = np.clip(np.searchsorted(t, x, side="right") - 1, 0, len(t) - 2)
    hi = h[i]
    s = (x - t[i])[:, None] / hi
    return ((2 * s**3 - 3 * s**2 + 1) * y[i] + (s**3 - 2 * s**2 + s) * hi * slope[i]
            + (3 * s**2 - 2 * s**3) * y[i + 1] + (s**3 - s**2) * hi * slope[i + 1])


WRITTEN = {"linear": written_linear, "cubic": written_cubic}


def turntable_scene(interpolation: str, euler_keys=None, timestep: float = 0.01) -> dict:
    """A table turning about z by `euler_keys` ((t, [x, y, z]) pairs; default
    `TURNS`) with a sphere 'bob' on it at radius 0.2 m and a world sphere
    'post' at angle 180 degrees, both of radius 0.02 m."""
    if euler_keys is None:
        euler_keys = [(t, [0.0, 0.0, z]) for t, z in zip(*TURNS)]
    keys = [{"t": float(t), "euler": [float(a) for a in e]} for t, e in euler_keys]
    duration = max(float(euler_keys[-1][0]), 0.1)
    return {"scene": {"name": "turntable", "units": "m", "duration": duration, "timestep": timestep},
            "check": {"clearance": 0.005},
            "bodies": [{"name": "table", "pos": [0.0, 0.0, 0.1]}],
            "parts": [{"name": "bob", "body": "table", "shape": "sphere", "size": [0.02],
                       "pos": [0.2, 0.0, 0.0]},
                      {"name": "post", "shape": "sphere", "size": [0.02], "pos": [-0.2, 0.0, 0.1]}],
            "motion": [{"body": "table", "keys": keys, "interpolation": interpolation}]}


def _rotations(built, times) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The table's world rotation (m, 3, 3), position (m, 3) and body-frame
    angular velocity (m, 3) that `Motion` puts into MuJoCo at `times`, through
    the loop's vectorised path (`Curve.at_many`, `apply_values`); each time's
    qpos and qvel also checked equal to the bit to the one-time path (`apply`)."""
    m, motion = built.model, Motion(built)
    many, one = mujoco.MjData(m), mujoco.MjData(m)
    body = built.body_ids["table"]
    dof = built.free["table"][1]
    value, rate = motion.curve.at_many(times)
    rot, pos, omega = [], [], []
    for t, v, r in zip(times, value, rate):
        motion.apply_values(many, v, r)
        motion.apply(one, float(t))
        assert np.array_equal(many.qpos, one.qpos) and np.array_equal(many.qvel, one.qvel)
        mujoco.mj_kinematics(m, many)
        rot.append(many.xmat[body].reshape(3, 3).copy())
        pos.append(many.xpos[body] + built.origin)
        omega.append(many.qvel[dof + 3:dof + 6].copy())
    return np.array(rot), np.array(pos), np.array(omega)


def _z_angle(rot: np.ndarray) -> np.ndarray:
    """Unwrapped rotation angle (degrees) about z of rotations (m, 3, 3) about z,
    sampled finely enough that consecutive ones differ by less than 180."""
    return np.unwrap(np.degrees(np.arctan2(rot[:, 1, 0], rot[:, 0, 0])), period=360.0)


# -- the turntable, closed form ------------------------------------------------------

@pytest.mark.parametrize("interpolation", ["linear", "cubic"])
def test_turntable_turns_as_written(interpolation):
    """0, 270, -270, 0: +270, then 540 back, then 270 to 0, at every sampled
    time the written numbers' interpolation, and the angular velocity its
    derivative; 1080 degrees turned in all."""
    built = build(parse_scene(turntable_scene(interpolation), Path("/virtual/turntable.toml")),
                  detect=False)
    times = np.linspace(-0.5, 3.5, 801)       # 0.005 s apart: at most 2.7 degrees between samples
    rot, pos, omega = _rotations(built, times)
    assert np.allclose(rot[:, 2], [0.0, 0.0, 1.0], atol=1e-15) and np.allclose(pos, [0, 0, 0.1])
    angle = _z_angle(rot)
    expected = WRITTEN[interpolation](times, *TURNS)[:, 0]
    np.testing.assert_allclose(angle, expected, rtol=0.0, atol=1e-9)
    at_keys = np.isin(times, TURNS[0])
    np.testing.assert_allclose(angle[at_keys], TURNS[1], atol=1e-9)
    assert np.isclose(np.abs(np.diff(angle)).sum(), 1080.0)
    if interpolation == "linear":   # 270 deg/s, -540, 270 inside the three intervals
        speed = np.select([times < 0, times < 1, times < 2, times < 3], [0.0, 270.0, -540.0, 270.0], 0.0)
        inside = ~np.isin(times, TURNS[0])
    else:   # 0, 270, -270, 0: every inner slope 0, so each interval is a smoothstep
        i = np.clip(np.floor(times), 0, 2).astype(int)
        s = np.clip(times - i, 0.0, 1.0)
        step = np.diff(TURNS[1])[i]
        np.testing.assert_allclose(expected, np.array(TURNS[1])[i] + step * (3 * s**2 - 2 * s**3),
                                   atol=1e-9)
        speed = step * 6 * s * (1 - s)
        inside = np.ones_like(times, bool)
    np.testing.assert_allclose(np.degrees(omega[inside]), np.column_stack(
        [np.zeros((inside.sum(), 2)), speed[inside]]), atol=1e-9)


@pytest.mark.parametrize("interpolation", ["linear", "cubic"])
def test_motion_files_turn_as_written(tmp_path, interpolation):
    """The same turn from a CSV file's `table.rz` column."""
    rows = "\n".join(f"{t},{z}" for t, z in zip(*TURNS))
    (tmp_path / "turn.csv").write_text(f"t,table.rz\n{rows}\n")
    data = turntable_scene(interpolation)
    data["motion"] = [{"file": "turn.csv", "interpolation": interpolation}]
    scene = parse_scene(data, tmp_path / "turntable.toml")
    np.testing.assert_array_equal(scene.motions[0].trajectory.body_euler[:, 0, 2], TURNS[1])
    times = np.linspace(0.0, 3.0, 601)
    rot, _, _ = _rotations(build(scene, detect=False), times)
    np.testing.assert_allclose(_z_angle(rot), WRITTEN[interpolation](times, *TURNS)[:, 0], atol=1e-9)


def test_a_full_turn_between_two_keys_is_a_turn_not_a_hold():
    """0 then 360: the table turns once (180 halfway), and is back at 0."""
    scene = parse_scene(turntable_scene("linear", [(0.0, [0, 0, 0]), (1.0, [0, 0, 360])]),
                        Path("/virtual/turn.toml"))
    rot, _, _ = _rotations(build(scene, detect=False), np.array([0.0, 0.25, 0.5, 0.75, 1.0]))
    np.testing.assert_allclose(_z_angle(rot), [0, 90, 180, 270, 360], atol=1e-9)


# -- any keys, any axes --------------------------------------------------------------

angles = st.floats(-720.0, 720.0, allow_nan=False)


@settings(max_examples=60)
@given(st.lists(st.tuples(st.floats(0.05, 2.0), st.tuples(angles, angles, angles)), min_size=1, max_size=6),
       st.sampled_from(["linear", "cubic"]), st.floats(0.0, 1.0))
def test_any_euler_keys_are_interpolated_angle_by_angle(keys, interpolation, first):
    """At every time the table's rotation is the rotation of the written
    angles interpolated each on its own ('XYZ', intrinsic), whatever the
    steps between keys, on all three axes at once; the one-time and the
    vectorised paths give the same bits (checked in `_rotations`)."""
    t_keys = first + np.cumsum([0.0] + [dt for dt, _ in keys[1:]])
    euler = np.array([e for _, e in keys], float)
    scene = parse_scene(turntable_scene(interpolation, list(zip(t_keys, euler))),
                        Path("/virtual/any.toml"))
    times = np.concatenate([np.linspace(t_keys[0] - 0.2, t_keys[-1] + 0.2, 97), t_keys])
    rot, _, _ = _rotations(build(scene, detect=False), times)
    expected = Rotation.from_euler("XYZ", WRITTEN[interpolation](times, t_keys, euler),
                                   degrees=True).as_matrix()
    np.testing.assert_allclose(rot, expected, rtol=0.0, atol=1e-9)


# -- through the step loop and a whole run -------------------------------------------

def test_the_loops_part_poses_turn_as_written():
    """The bob's world pose as the simulation reads it from MuJoCo after each
    step (between the keys and at them): at the angle of the written numbers'
    interpolation, at radius 0.2 m about the table's axis."""
    built = build(parse_scene(turntable_scene("cubic", timestep=0.005), Path("/virtual/tt.toml")),
                  detect=False)
    sim = Simulation(built)
    sim.reset()
    sim.settle()
    bob = [p.name for p in built.parts].index("bob")
    states = list(sim.steps(contacts=False))
    times = np.array([s.t for s in states])
    assert len(times) == 601 and times[-1] == pytest.approx(3.0)
    poses = np.array([s.part_poses[bob] for s in states])
    centre = poses[:, :3, 3] - [0.0, 0.0, 0.1]
    np.testing.assert_allclose(np.linalg.norm(centre, axis=1), 0.2, atol=1e-12)
    np.testing.assert_allclose(centre[:, 2], 0.0, atol=1e-12)
    angle = np.unwrap(np.degrees(np.arctan2(centre[:, 1], centre[:, 0])), period=360.0)
    expected = written_cubic(times, *TURNS)[:, 0]
    np.testing.assert_allclose(angle, expected, atol=1e-8)
    np.testing.assert_allclose(_z_angle(poses[:, :3, :3]), expected, atol=1e-8)
    assert angle.max() == pytest.approx(270.0) and angle.min() == pytest.approx(-270.0)


def test_a_run_meets_the_post_where_the_written_turn_passes_it(tmp_path, capsys):
    """`cablecheck check` accepts keys 270 and 540 degrees apart; `cablecheck
    run` finds the bob on the post (at 180 degrees) four times, at 2/3, 7/6,
    11/6 and 7/3 s, as the written turn passes it (the short way, one -360
    degree turn, would pass it once, at 1.5 s), each event's steps, worst
    step and distance those of the closed form: centres 2 R |sin((a - 180) / 2)|
    apart, less both radii."""
    path = tmp_path / "turntable.toml"
    keys = ", ".join(f"{{ t = {t}, euler = [0, 0, {z}] }}" for t, z in zip(*TURNS))
    path.write_text(f"""
[scene]
name = "turntable"
units = "m"
duration = 3.0
timestep = 0.01

[check]
clearance = 0.005

[[bodies]]
name = "table"

[[parts]]
name = "bob"
body = "table"
shape = "sphere"
size = [0.02]
pos = [0.2, 0, 0]

[[parts]]
name = "post"
shape = "sphere"
size = [0.02]
pos = [-0.2, 0, 0]

[[motion]]
body = "table"
interpolation = "linear"
keys = [{keys}]
""")
    assert main(["check", str(path)]) == 0
    report = tmp_path / "turntable.json"
    assert main(["run", str(path), "--no-record", "--quiet", "--report", str(report)]) == 1
    capsys.readouterr()
    events = sorted(json.loads(report.read_text())["events"], key=lambda e: e["t_start"])
    steps = np.arange(301) * 0.01
    angle = written_linear(steps, *TURNS)[:, 0]
    gap = 2 * 0.2 * np.abs(np.sin(np.radians(angle - 180.0) / 2)) - 0.04
    near = np.flatnonzero(gap < 0.005)
    runs = np.split(near, np.flatnonzero(np.diff(near) > 1) + 1)
    assert [round(steps[r].mean(), 2) for r in runs] == pytest.approx([2 / 3, 7 / 6, 11 / 6, 7 / 3], abs=0.01)
    assert len(events) == len(runs) == 4
    for e, r in zip(events, runs):
        worst = r[np.argmin(gap[r])]
        assert (e["type"], {e["a"], e["b"]}, e["severity"]) == ("part-part", {"bob", "post"}, "hard")
        assert (e["t_start"], e["t_end"], e["t_worst"]) == pytest.approx(
            (steps[r[0]], steps[r[-1]], steps[worst]), abs=1e-9)
        assert e["min_distance"] == pytest.approx(gap[worst], abs=1e-9)
