"""The step loop: scripted bodies follow their script exactly; settling finds rest."""

from __future__ import annotations

import time
from pathlib import Path

import mujoco
import numpy as np

from sim.build import build
from sim.loop import Simulation
from sim.motion import Motion
from sim.scene import euler_matrix, parse_scene


def _door(contact: bool) -> dict:
    """A door panel sliding flush on a floor, with a stiff cable pressing on it."""
    keys = [{"t": 0.0, "pos": [0.0, 0.0, 0.0], "euler": [0, 0, 0]},
            {"t": 0.5, "pos": [0.2, 0.0, 0.0], "euler": [0, 0, 30]}]
    return {"scene": {"name": "door", "units": "m", "duration": 0.5, "settle": 0.5},
            "effects": {"contact": ["cable-structure"] if contact else []},
            "bodies": [{"name": "door"}],
            "parts": [{"name": "floor", "shape": "box", "size": [1, 1, 0.01], "pos": [0, 0, -0.01]},
                      {"name": "panel", "body": "door", "shape": "box", "size": [0.2, 0.01, 0.2],
                       "pos": [0, 0, 0.2]}],
            "motion": [{"body": "door", "keys": keys}],
            "cables": [{"name": "c", "radius": 0.005, "start": {"pos": [-0.3, 0.05, 0.3]},
                        "end": {"body": "door", "pos": [0.1, 0.015, 0.35]}, "length": 0.6,
                        "young": 5e8, "density": 3000}]}


def test_scripted_bodies_follow_their_script_exactly():
    """Whatever the cable does to it, the panel's pose is the script's at every
    step (it read 1e-6 m into the floor when cables pressed on it), and the
    held cable end rides it exactly."""
    data = _door(contact=True)
    scene = parse_scene(data, Path("/virtual/door.toml"))
    built = build(scene, detect=False)
    sim = Simulation(built)
    sim.reset()
    sim.settle()
    motion = Motion(built)
    script = mujoco.MjData(built.model)   # the script's own pose, by forward kinematics
    door = built.body_ids["door"]
    panel = [p.name for p in built.parts].index("panel")
    for state in sim.steps(contacts=False):
        motion.apply(script, state.t)
        mujoco.mj_kinematics(built.model, script)
        pos, rot = script.xpos[door], script.xmat[door].reshape(3, 3)
        expected = pos + built.origin + rot @ np.array([0, 0, 0.2])
        np.testing.assert_allclose(state.part_poses[panel][:3, 3], expected, atol=1e-12)
        end = pos + built.origin + rot @ np.array([0.1, 0.015, 0.35])
        np.testing.assert_allclose(state.cables[0][-1], end, atol=1e-12)
    # the panel's bottom stays flush on the floor
    assert abs(state.part_poses[panel][2, 3] - 0.2) < 1e-12
    assert np.allclose(euler_matrix([0, 0, 30]), state.part_poses[panel][:3, :3], atol=1e-9)


def test_settling_finds_rest_without_drag():
    """Kinetic damping: a cable settles to rest although only its own material damps it."""
    data = _door(contact=False)
    data["scene"]["duration"] = 0.0
    data["scene"]["settle"] = 2.0
    sim = Simulation(build(parse_scene(data, Path("/virtual/door.toml")), detect=False))
    sim.reset()
    sim.settle()
    state = next(sim.steps(contacts=False))
    assert sim.data.energy[1] < 1e-9 and np.isfinite(state.cables[0]).all()


def test_the_detection_models_collision_time_is_mujocos_timer_of_its_passes():
    """`collision_seconds` counts MuJoCo's collision passes on the detection
    model, one per state collided, and no more than the wall time they took."""
    built = build(parse_scene(_door(contact=True), Path("/virtual/door.toml")))
    sim = Simulation(built)
    sim.reset()
    assert sim.collision_seconds() == 0.0
    qposes = [sim.data.qpos.copy()] * 5
    start = time.perf_counter()
    sim.collide_many(qposes)
    wall = time.perf_counter() - start
    timer = sim.detect_data.timer[mujoco.mjtTimer.mjTIMER_POS_COLLISION]
    assert timer.number == 5
    assert 0.0 < sim.collision_seconds() <= wall
    assert Simulation(build(parse_scene(_door(contact=True), Path("/virtual/door.toml")), detect=False)
                      ).collision_seconds() == 0.0
