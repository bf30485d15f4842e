"""The simulated rod's twist (cablecheck.build.rodtwist, cablecheck.build.untwist,
checker.twist.RodTwistMeter): a turned clamp winds the rod as the closed form
says and MuJoCo's own reaction shows; every cable starts untwisted as routed;
the rod's twist end to end is the twist the ends' frames give by parallel
transport (computed another way), on routes and turns drawn at random."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import mujoco
import numpy as np
import pytest

from cablecheck.build.rodtwist import TwistReader
from cablecheck.build.stages import build
from cablecheck.build.untwist import start_state
from cablecheck.checker.twist import RodTwistMeter, TwistMeter
from cablecheck.run.loop import Simulation
from cablecheck.scene.load import parse_scene
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

SHEAR = 2e7
RADIUS = 0.004
POLAR = np.pi * RADIUS ** 4 / 2


def _turning(turn_deg: float, euler=None, hold: str = "clamp", via=None, length=None,
             duration: float = 0.5, gravity: bool = False) -> dict:
    """A cable from the world to a body at x = 0.5 that turns `turn_deg` about
    x (the cable) over 0.4 s, then holds (or to `euler`, degrees), straight
    along x unless routed `via`."""
    end = {"body": "wrist", "pos": [0, 0, 0]}
    if hold != "clamp":
        end["hold"] = hold
    cable = {"name": "c", "radius": RADIUS, "start": {"pos": [0, 0, 0.3]}, "end": end,
             "twist_stiffness": SHEAR}
    if via is not None:
        cable["via"] = via
    if length is not None:
        cable["length"] = length
    euler = [turn_deg, 0.0, 0.0] if euler is None else list(euler)
    return {"scene": {"name": "w", "units": "m", "duration": duration, "settle": 0.0},
            "effects": {"dynamics": True, "gravity": gravity},
            "bodies": [{"name": "wrist", "pos": [0.5, 0, 0.3]}],
            "cables": [cable],
            "motion": [{"body": "wrist", "keys": [{"t": 0.0, "euler": [0, 0, 0]}, {"t": 0.4, "euler": euler}]}]}


def _simulate(scene: dict, tmp_path: Path, every: int = 1):
    """The built scene, its simulation and its states, each state with its
    first cable's twist read (`twist`, radians per interior vertex)."""
    built = build(parse_scene(scene, tmp_path / "w.toml"), detect=False)
    sim = Simulation(built, validate=False)
    sim.reset()
    sim.settle()
    states = list(sim.steps(contacts=False, every=every))
    reader = TwistReader.of(built)
    twist = reader.read_many([s.rod for s in states], np.stack([np.concatenate(s.cables) for s in states]),
                             np.stack([s.qpos for s in states]))[0]
    return built, sim, [SimpleNamespace(**vars(s), twist=t) for s, t in zip(states, twist)]


@pytest.mark.parametrize("turn", [90.0, 360.0, -720.0])
def test_a_turned_clamp_winds_the_rod_evenly_with_the_closed_form_moment(turn, tmp_path):
    built, sim, states = _simulate(_turning(turn, duration=0.8), tmp_path, every=50)
    rod, twist = built.rods[0], states[-1].twist
    assert np.degrees(twist.sum()) == pytest.approx(turn, abs=0.05)
    # evenly spread between the clamped edges (the short held edges stand for a
    # little less length than the regular elements)
    moment = rod.stiffness * twist
    assert np.allclose(moment, moment.mean(), rtol=1e-3)
    # G J theta / L over the length between the two clamped edges' middles
    s = built.cables[0].rest_s
    span = 0.5 * (s[-2] + s[-1]) - 0.5 * (s[0] + s[1])
    assert moment.mean() == pytest.approx(SHEAR * POLAR * np.radians(turn) / span, rel=2e-3)
    # MuJoCo's own reaction on the turning body, about the cable (x)
    m, d = sim.model, sim.data
    mujoco.mj_forward(m, d)
    dof = built.free["wrist"][1]
    assert -d.qfrc_passive[dof + 3] == pytest.approx(moment.mean(), rel=2e-3)


def test_a_pinned_end_turns_freely(tmp_path):
    _, _, states = _simulate(_turning(360.0, hold="pin", duration=0.6), tmp_path, every=60)
    assert max(abs(np.degrees(s.twist.sum())) for s in states) < 1.0


_via = st.tuples(st.floats(0.1, 0.4), st.floats(-0.25, 0.25), st.floats(0.05, 0.55))


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(via=st.lists(_via, min_size=0, max_size=2),
       euler=st.tuples(st.floats(-400, 400), st.floats(-60, 60), st.floats(-60, 60)),
       slack=st.floats(1.01, 1.2), gravity=st.booleans())
def test_the_rod_carries_the_twist_its_ends_frames_give(via, euler, slack, gravity, tmp_path):
    """Routed through points drawn at random (or none: a slack cable along its
    chord, cablecheck.build.cableplan.STRAIGHT_KINK), its end body turned to
    euler angles drawn at random: the cable starts untwisted, and its twist
    end to end is at every step the angle between its start frame carried
    along its centreline and its end frame (`TwistMeter`), accumulated."""
    pts = np.array([[0.0, 0, 0.3], *via, [0.5, 0, 0.3]])
    assume(np.linalg.norm(np.diff(pts, axis=0), axis=1).min() > 0.02)
    length = slack * float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
    scene = _turning(0.0, euler, via=[list(v) for v in via], length=length, duration=0.3, gravity=gravity)
    built, _, states = _simulate(scene, tmp_path, every=5)
    assert abs(states[0].twist.sum()) < 1e-9 * max(1.0, abs(built.end_rolls[0].angle))
    ends = TwistMeter(states[0].cables[0], states[0].end_rot[0, 0], states[0].end_rot[0, 1])
    for s in states[1:]:
        by_ends = ends.update(s.cables[0][None], s.end_rot[None, 0, 0], s.end_rot[None, 0, 1])[0]
        assert np.degrees(s.twist.sum()) == pytest.approx(np.degrees(by_ends), abs=1e-6)


def test_a_slack_cable_along_its_chord_keeps_its_twist_state(tmp_path):
    """Slack between two clamps with no via point, the cable leaves along its
    chord and its rest line runs through its end: without the rest shape's
    kink MuJoCo kept no twist state at all (plastic all 0, a turned end wound
    nothing). Its end turned a quarter turn, it now carries the twist its
    ends' frames give (sagging, some of the turn goes into writhe)."""
    _, _, states = _simulate(_turning(90.0, length=0.6, gravity=True, duration=0.8), tmp_path, every=80)
    ends = TwistMeter(states[0].cables[0], states[0].end_rot[0, 0], states[0].end_rot[0, 1])
    last = states[-1]
    by_ends = ends.update(np.stack([s.cables[0] for s in states[1:]]), np.stack([s.end_rot[0, 0] for s in states[1:]]),
                          np.stack([s.end_rot[0, 1] for s in states[1:]]))[-1]
    assert np.degrees(last.twist.sum()) == pytest.approx(np.degrees(by_ends), abs=1e-6)
    assert np.degrees(last.twist.sum()) > 45.0


def test_a_cable_routed_out_of_plane_starts_untwisted(tmp_path):
    scene = _turning(0.0, via=[[0.2, 0.2, 0.5]], length=1.0)
    built = build(parse_scene(scene, tmp_path / "w.toml"), detect=False)
    (roll,) = built.end_rolls
    assert abs(np.degrees(roll.angle)) > 10.0          # the straight compile left a twist to take out
    d = start_state(built)
    assert abs(built.rods[0].twist(d.qpos, d.plastic).sum()) < 1e-9


def test_rod_meter_keeps_the_extremes_a_loop_would():
    rng = np.random.default_rng(4)
    stiffness, length = rng.uniform(0.1, 1.0, 7), rng.uniform(0.01, 0.05, 7)
    meter = RodTwistMeter(stiffness, length)
    batches = [rng.normal(size=(k, 7)) for k in (3, 1, 5)]
    totals = [meter.take(b) for b in batches]
    allx = np.concatenate(batches)
    assert np.allclose(np.concatenate(totals), [row.sum() for row in allx])
    assert meter.max_abs == pytest.approx(max(abs(row.sum()) for row in allx))
    for v in range(7):
        assert meter.max_moment[v] == pytest.approx(max(abs(row[v]) * stiffness[v] for row in allx))
        assert meter.max_rate[v] == pytest.approx(max(abs(row[v]) / length[v] for row in allx))


def test_the_twist_read_is_the_states_own_as_mujocos_next_step_would_have_it(tmp_path):
    """MuJoCo's reference frames are those of the start of the step just
    taken; carried to the state's positions they give the twist MuJoCo itself
    finds there (a step of 1e-12 s from a copy of the state), to 1e-8 rad,
    where reading them as they are would be up to a step late (degrees here)."""
    scene = _turning(0.0, [200.0, 30.0, -40.0], via=[[0.25, 0.0, 0.5], [0.3, 0.1, 0.45]], length=1.0,
                     duration=0.12, gravity=True)
    built, sim, _ = _simulate(scene, tmp_path, every=10)
    m, d = sim.model, sim.data
    rod = built.rods[0]
    assert all(rod.held_body[[0, -1]] >= 0) and all(rod.held_body[1:-1] < 0)   # both ends clamped
    late = []
    for k in range(40):            # a few more steps, read as the loop reads a state
        mujoco.mj_step(m, d)
        sim.motion.apply(d, 0.12 + k * m.opt.timestep)
        reader = TwistReader([rod], [built.cables[0].count])
        before = d.xmat[reader.bodies]
        mujoco.mj_kinematics(m, d)
        mujoco.mj_flex(m, d)
        raw = reader.raw(d.plastic, before, d.xmat[reader.bodies])
        c = built.cables[0]
        (mine,) = reader.read_many([raw], d.flexvert_xpos[c.vert_adr:c.vert_adr + c.count][None], d.qpos[None])
        mine = mine[0]
        probe = mujoco.MjData(m)
        mujoco.mj_copyData(probe, m, d)
        step, m.opt.timestep = m.opt.timestep, 1e-12
        mujoco.mj_step(m, probe)
        m.opt.timestep = step
        theirs = rod.twist(probe.qpos, probe.plastic)
        assert np.abs(mine - theirs).max() < 1e-8
        late.append(np.abs(rod.twist(d.qpos, d.plastic) - theirs).max())
    assert max(late) > 1e-3


@pytest.mark.parametrize("turn", [90.0, -720.0])
def test_a_clip_turned_about_the_cable_twists_it_both_ways(turn, tmp_path):
    """A clamped clip in the middle of a cable clamped to the world at both
    ends, its body turned about the cable: each half carries G J theta over
    its own span (between the clamped edges' and the clip edge's middles),
    in opposite senses; the cable's twist end to end stays 0. (MuJoCo's rod
    alone would let the clip's edge turn freely: no moment at all.)"""
    scene = {"scene": {"name": "w", "units": "m", "duration": 0.8, "settle": 0.0},
             "effects": {"dynamics": True, "gravity": False},
             "bodies": [{"name": "mid", "pos": [0.25, 0, 0.3]}],
             "cables": [{"name": "c", "radius": RADIUS, "start": {"pos": [0, 0, 0.3]}, "end": {"pos": [0.5, 0, 0.3]},
                         "clips": [{"body": "mid", "pos": [0, 0, 0]}], "twist_stiffness": SHEAR}],
             "motion": [{"body": "mid", "keys": [{"t": 0.0, "euler": [0, 0, 0]}, {"t": 0.4, "euler": [turn, 0, 0]}]}]}
    built, _, states = _simulate(scene, tmp_path, every=80)
    assert len(built.clip_rolls) == 1
    s = built.cables[0].rest_s
    edge = next(a.vertex for a in built.cables[0].attachments if a.kind == "clip")
    middles = 0.5 * (s[[0, edge, len(s) - 2]] + s[[1, edge + 1, len(s) - 1]])
    moment = built.rods[0].stiffness * states[-1].twist
    before, after = moment[:edge - 1], moment[edge + 1:]
    assert abs(np.degrees(states[-1].twist.sum())) < 1e-4     # the clip's equality gives 1e-7 rad
    assert np.allclose(before, SHEAR * POLAR * np.radians(turn) / (middles[1] - middles[0]), rtol=3e-3)
    assert np.allclose(after, -SHEAR * POLAR * np.radians(turn) / (middles[2] - middles[1]), rtol=3e-3)


def test_a_reader_of_no_rod_reads_nothing():
    """Cables without twist state (a rod MuJoCo keeps none for): no bodies, no state kept, None read."""
    reader = TwistReader([None, None], [5, 7])
    assert len(reader.bodies) == 0
    assert reader.raw(np.zeros(4), np.zeros((0, 9)), np.zeros((0, 9))) is None
    assert reader.read_many([], np.zeros((0, 12, 3)), np.zeros((0, 3))) == [None, None]


def test_a_rod_without_twist_state_is_warned_about(tmp_path, monkeypatch):
    """Nothing silent: with the rest shape's kink taken away, the slack cable along its chord
    gets no twist state from MuJoCo again, and the build says so (the kinked one does not)."""
    import cablecheck.build.cableplan as cableplan

    scene = parse_scene(_turning(90.0, length=0.6, gravity=True), tmp_path / "w.toml")
    assert not [w for w in build(scene, detect=False).warnings if "twist state" in w]
    monkeypatch.setattr(cableplan, "STRAIGHT_KINK", 0.0)
    (warning,) = [w for w in build(scene, detect=False).warnings if "twist state" in w]
    assert "cable 'c'" in warning and "winds nothing" in warning
