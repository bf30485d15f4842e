"""Twisted rods in the cable model (cablecheck.bench.physics_cases.twisted_buckling and
twisted_hose) against what physics says without a peer: a buckled rod whose clamped end is
turned about the chord leaves its buckling plane, the more the more it is turned, mirrored when
turned the other way, and keeps its length; the twist it carries and the writhe of its shape add
up to the turns; a slack hose turned four turns whirls about its chord, symmetric end for end,
and hangs in its plane when not turned. PyElastica's answers to the same problems are in
benchmarks/elastica_peer.py (docs/physics.md, the peer table).

At commit 6074e19 a cable clamped at both ends and routed with more than a few % of slack
along its chord carried no twist at all: MuJoCo (4.0.1) kept no twist state for its rod
(`mjData.plastic` stayed 0 from the first step) however its end was turned, because the model's
shape at qpos0 folded exactly back at its end (cablecheck.build.cableplan.STRAIGHT_KINK, which
fixed it). Both the hose routed with 20 % slack and the same hose routed with 1 % and its end
moved in are tested.
"""

from __future__ import annotations

import pytest
from cablecheck.bench import physics_cases as cases

SHEAR_ROD = cases.ROD["young"] / 3.0


@pytest.fixture(scope="module")
def rod_turned():
    """The buckled rod (20 elements) turned 1, 3 and -3 turns, and not turned."""
    return {t: cases.twisted_buckling(t, twist_stiffness=SHEAR_ROD) for t in (0.0, 1.0, 3.0, -3.0)}


def test_a_buckled_rod_turned_leaves_its_plane_the_more_the_more_it_is_turned(rod_turned):
    assert abs(rod_turned[0.0].measured) < 0.5                    # not turned: in its plane
    assert 20.0 < rod_turned[1.0].measured < rod_turned[3.0].measured
    assert rod_turned[3.0].measured > 90.0


def test_a_buckled_rod_turned_the_other_way_leaves_its_plane_the_other_way(rod_turned):
    assert rod_turned[-3.0].measured == pytest.approx(-rod_turned[3.0].measured, abs=1.0)


def test_a_twisted_buckled_rod_keeps_its_length_and_its_link(rod_turned):
    for turns, r in rod_turned.items():
        assert abs(r.extra["least"]) < 1e-3 and abs(r.extra["final"]) < 1e-3
        # twist (read from the simulated rod) and writhe (of the shape) share the turns: the
        # writhe of a bow this flat is small, so most of the turns stay twist
        assert r.extra["twist"] == pytest.approx(360.0 * turns, abs=0.05 * 360.0 * abs(turns) + 0.5)
    # its bow gets shallower as it winds out of its plane (the length goes into the third dimension)
    assert rod_turned[3.0].extra["deflection"] < 0.8 * rod_turned[3.0].extra["deflection_before"]


def test_a_twisted_buckled_rods_shape_does_not_depend_on_how_fast_it_was_turned(rod_turned):
    slow = cases.twisted_buckling(3.0, twist_stiffness=SHEAR_ROD, turn=2.0 * cases.TWIST_TURN)
    assert slow.measured == pytest.approx(rod_turned[3.0].measured, abs=1.0)


@pytest.fixture(scope="module")
def hose_moved():
    """The slack hose, its end moved in from 1 % slack (its twist state started), turned 4 turns and not."""
    shear = 5e7 / 3.0
    return {t: cases.twisted_hose(t, twist_stiffness=shear, approach=0.01) for t in (0.0, 4.0)}


def test_a_slack_hose_turned_four_turns_whirls_about_its_chord_symmetric_end_for_end(hose_moved):
    turned, still = hose_moved[4.0], hose_moved[0.0]
    assert abs(still.measured) < 0.5 and abs(still.extra["whirl"]) < 0.5      # not turned: hangs in its plane
    assert still.extra["sag"] == pytest.approx(still.extra["sag_before"], rel=1e-3)
    assert turned.measured > 90.0                                  # its halves whirl opposite ways
    assert abs(turned.extra["whirl"]) < 1.0                        # its middle stays below the chord
    assert turned.extra["sag"] < 0.8 * turned.extra["sag_before"]
    assert turned.extra["twist"] > 0.9 * 1440.0 and abs(turned.extra["least"]) < 1e-3


def test_a_slack_hose_routed_slack_and_turned_four_turns_whirls_about_its_chord():
    r = cases.twisted_hose(4.0, twist_stiffness=5e7 / 3.0)
    assert r.extra["twist"] > 0.9 * 1440.0
    assert r.measured > 90.0


def test_a_slack_hose_turned_past_its_critical_twist_throws_a_loop():
    """A hose (r 5 mm, 0.5 m) clamped level over 0.4 m, its end turned 10 turns about the chord
    in 5 s: the twist the simulated rod carries climbs to a critical value and then drops by more
    than a turn within 0.1 s, the hose snapping into a loop (its writhe takes the turns), and the
    loop brings the hose onto itself (a self record of the checker at the snap); the rod never
    carries the ten turns as twist."""
    import numpy as np

    from cablecheck.bench.physics_cases import _scene, _twisted_run
    from cablecheck.checker.interference import Checker
    from cablecheck.checker.scene_state import CableState, CheckConfig

    scene = _scene({"scene": {"name": "loop", "units": "m", "duration": 6.0, "settle": 2.0},
                    "bodies": [{"name": "b", "pos": [0.4, 0, 1]}],
                    "motion": [{"body": "b", "interpolation": "linear",
                                "keys": [{"t": 0.0, "pos": [0.4, 0, 1], "euler": [0, 0, 0]},
                                         {"t": 5.0, "pos": [0.4, 0, 1], "euler": [3600, 0, 0]}]}],
                    "cables": [{"name": "hose", "radius": 0.005, "length": 0.5,
                                "start": {"pos": [0, 0, 1], "tangent": [1, 0, 0]},
                                "end": {"body": "b", "pos": [0, 0, 0], "tangent": [1, 0, 0]}}]})
    built, _, states, _, twist = _twisted_run(scene, 1, settle=True)
    twist = np.degrees(twist)
    t = np.array([s.t for s in states])
    peak = int(np.argmax(twist))
    assert 720.0 < twist[peak] < 0.9 * 3600.0                        # a critical twist, short of the turns
    after = (t > t[peak]) & (t < t[peak] + 0.1)
    assert twist[peak] - twist[after].min() > 360.0                    # released within 0.1 s
    checker = Checker([], CheckConfig(clearance=0.001))
    near = np.flatnonzero((t > t[peak] - 0.02) & (t < t[peak] + 0.1))
    c = built.cables[0]
    selfs = [r for k in near for r in checker.check([CableState(c.name, states[k].cables[0], c.radius,
                                                                c.min_bend_radius, c.length, c.rest_s)])
             if r.type.value == "self"]
    assert selfs, "the loop did not bring the hose onto itself"
