"""The step loop: scripted bodies follow their script exactly; settling finds rest."""

from __future__ import annotations

import time
from pathlib import Path

import mujoco
import numpy as np
import pytest

from cablecheck.build.stages import build
from cablecheck.run.loop import Simulation, script_times
from cablecheck.run.motion import Motion
from cablecheck.scene.frames import euler_matrix
from cablecheck.scene.load import parse_scene


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


def test_the_detection_models_collision_time_is_the_cpu_time_of_its_passes():
    """`collision_seconds` counts the CPU time of MuJoCo's collision passes on
    the detection model (one per state collided, by MuJoCo's own count):
    part of the calling thread's CPU time for the whole pass, and more
    with each pass."""
    built = build(parse_scene(_door(contact=True), Path("/virtual/door.toml")))
    sim = Simulation(built)
    sim.reset()
    assert sim.detector.collision_seconds() == 0.0
    qposes = [sim.data.qpos.copy()] * 5
    start = time.thread_time()
    sim.detector.collide_many(qposes)
    cpu = time.thread_time() - start
    assert sim.detector.detect_data.timer[mujoco.mjtTimer.mjTIMER_POS_COLLISION].number == 5
    first = sim.detector.collision_seconds()
    assert 0.0 < first <= cpu
    sim.detector.collide_many(qposes)
    assert sim.detector.collision_seconds() > first
    assert Simulation(build(parse_scene(_door(contact=True), Path("/virtual/door.toml")), detect=False)
                      ).detector is None


def _robot_cell(duration: float):
    """The robot cell example (concave meshes seen as patches), shortened."""
    import dataclasses

    from cablecheck.scene.load import load_scene
    scene = load_scene(Path(__file__).resolve().parents[1] / "scenes" / "robot_cell.toml")
    return dataclasses.replace(scene, duration=duration, settle=0.02)


def test_the_simulations_body_poses_are_the_detection_models_bit_for_bit():
    """The states carry the simulation's body poses; the detection model,
    with the same kinematic tree, puts its bodies at the same poses bit for
    bit at the same qpos, so the reach test may take them, and the pass
    finds the same contacts with them, without them, and with every patch in."""
    built = build(_robot_cell(0.04))
    assert built.model.nbody == built.detect.nbody
    sim = Simulation(built)
    sim.reset()
    sim.settle()
    states = list(sim.steps(contacts=False))
    m2, d2 = built.detect, sim.detector.detect_data
    for s in states:
        d2.qpos[:] = s.qpos
        mujoco.mj_kinematics(m2, d2)
        assert np.array_equal(s.xpos, d2.xpos) and np.array_equal(s.xmat, d2.xmat)
    qposes = [s.qpos for s in states]
    poses = (np.stack([s.xpos for s in states]), np.stack([s.xmat for s in states]))
    assert all(np.array_equal(a, b) for a, b in zip(poses, sim.detector.detect_poses(qposes)))

    def fields(raws):
        return [[r.geom, r.flex, r.elem, r.dist, r.pos] for r in raws]

    given, own = sim.detector.collide_many(qposes, poses), sim.detector.collide_many(qposes)
    every = Simulation(built, reach=False).detector.collide_many(qposes)
    assert sum(len(r.dist) for r in given) > 0
    for a, b, c in zip(fields(given), fields(own), fields(every)):
        assert all(np.array_equal(x, y) and np.array_equal(x, z) for x, y, z in zip(a, b, c))
    # a simulation without a mesh part (no reach test) keeps no poses
    assert next(Simulation(build(parse_scene(_door(contact=True), Path("/virtual/door.toml")))).steps(
        contacts=False)).xpos is None


@pytest.mark.parametrize("substeps, step_size, timestep", [(1, 0.002, 0.002), (2, 0.0005, 0.001),
                                                           (3, 0.002 / 3, 0.002), (7, 1e-3 / 7, 1e-3)])
def test_script_times_are_the_loops_products_in_order(substeps, step_size, timestep):
    """The block of script times is, bit for bit and in order, what the loop
    computed one substep after the other."""
    ks = np.arange(40, 300)
    one = [t for k in ks.tolist() for t in
           [((k - 1) * substeps + j) * step_size for j in range(1, substeps)] + [k * timestep]]
    assert np.array_equal(script_times(ks, substeps, step_size, timestep), np.array(one))
