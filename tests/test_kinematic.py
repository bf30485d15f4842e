"""The step loop without MuJoCo: parts and end frames exactly where MuJoCo's kinematics puts them."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
from hypothesis import given, settings, strategies as st

from cablecheck.build.stages import build
from cablecheck.build.static import build_static
from cablecheck.run.kinematic import KinematicSimulation, place
from cablecheck.run.loop import Simulation
from cablecheck.scene.load import parse_scene

coord = st.floats(-1.0, 1.0, allow_nan=False)
angle = st.floats(-180.0, 180.0, allow_nan=False)
vec3 = st.tuples(coord, coord, coord)
euler = st.tuples(angle, angle, angle)
# near the body's own frame, where MuJoCo's compiler takes the body's frame (FRAME_EPS)
tiny = st.floats(-2e-6, 2e-6, allow_nan=False)
near3 = st.tuples(tiny, tiny, tiny)
part = st.fixed_dictionaries({"body": st.sampled_from(["world", "arm"]), "pos": st.one_of(vec3, near3),
                              "euler": st.one_of(euler, st.tuples(tiny, tiny, tiny)),
                              "shape": st.sampled_from(["box", "ellipsoid"])})
key = st.fixed_dictionaries({"pos": vec3, "euler": euler})


def _scene(parts: list[dict], keys: list[dict], far: float) -> dict:
    """World parts `far` from the origin (a world part near the origin tests the world's own frame)."""
    off = np.array([far, 0.5 * far, -far])
    rows = [{"name": f"p{k}", "shape": p["shape"], "body": p["body"], "size": [0.01, 0.02, 0.03],
             "pos": (np.array(p["pos"]) + (off if p["body"] == "world" else 0.0)).tolist(), "euler": list(p["euler"])}
            for k, p in enumerate(parts)]
    times = np.linspace(0.0, 0.05, len(keys))
    return {
        "scene": {"name": "kin", "units": "m", "duration": 0.05, "timestep": 0.01, "settle": 0.0},
        "effects": {"dynamics": False, "contact": []},
        "check": {"validate": False},
        "bodies": [{"name": "arm", "pos": (off + keys[0]["pos"]).tolist(), "euler": list(keys[0]["euler"])}],
        "parts": rows,
        "cables": [{"name": "c", "radius": 0.004, "segments": 8, "start": {"pos": off.tolist()},
                    "end": {"body": "arm", "pos": [0.3, 0.0, 0.0]}}],
        "motion": [{"body": "arm", "keys": [{"t": float(t), "pos": (off + k["pos"]).tolist(), "euler": list(k["euler"])}
                                            for t, k in zip(times, keys)]}],
    }


@settings(max_examples=15)
@given(parts=st.lists(part, min_size=1, max_size=6), keys=st.lists(key, min_size=1, max_size=3),
       far=st.sampled_from([0.0, 10.0, 2.2e4]))
def test_states_are_mujocos_to_the_bit(parts, keys, far):
    """Part poses, end frames, cables and step times equal a MuJoCo build's loop exactly."""
    scene = parse_scene(_scene(parts, keys, far), Path("/nonexistent/kin.toml"))
    mj = Simulation(build(scene, detect=False))
    kin = KinematicSimulation(build_static(scene))
    mj.reset()
    kin.reset()
    assert kin.settle_steps == mj.settle_steps == 0 and kin.total_steps == mj.total_steps
    for a, b in zip(mj.steps(contacts=False, every=2), kin.steps(contacts=False, every=2), strict=True):
        assert (a.step, a.t) == (b.step, b.t)
        assert np.array_equal(a.part_poses, b.part_poses)
        assert np.array_equal(a.end_rot, b.end_rot)
        assert all(np.array_equal(x, y) for x, y in zip(a.cables, b.cables, strict=True))
        assert b.contacts is None
    assert kin.warnings() == {}


@settings(max_examples=30)
@given(body_pos=vec3, body_quat=st.tuples(coord, coord, coord, coord).filter(lambda q: np.linalg.norm(q) > 0.1),
       pos=vec3, quat=st.tuples(coord, coord, coord, coord).filter(lambda q: np.linalg.norm(q) > 0.1))
def test_place_is_a_frame_in_a_frame(body_pos, body_quat, pos, quat):
    """A point p of the frame lands at R_body (R p + t) + t_body (brute force with numpy)."""
    bq = np.array(body_quat) / np.linalg.norm(body_quat)
    q = np.array(quat) / np.linalg.norm(quat)
    bmat = np.zeros(9)
    mujoco.mju_quat2Mat(bmat, bq)
    out = np.zeros((4, 4))
    place(np.array(body_pos), bq, bmat, np.array(pos), q, mujoco.mjtSameFrame.mjSAMEFRAME_NONE, out)
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, q)
    p = np.array([0.3, -0.2, 0.5])
    expect = bmat.reshape(3, 3) @ (rot.reshape(3, 3) @ p + pos) + body_pos
    assert np.allclose(out[:3, :3] @ p + out[:3, 3], expect, atol=1e-12)
    assert np.allclose(out[3], [0, 0, 0, 1])
