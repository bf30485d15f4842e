"""Second opinions on one pair (cablecheck.checker.recheck), against closed forms: a
sparse straight cable past a sphere and across another cable measured
exactly; a cable through the pocket of an L bracket clear of the mesh but
inside its convex hull; a batch's answers those of each state alone."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from cablecheck.checker.recheck import Recheck, convex_hull_shape
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import CableState, CheckConfig, PartState
from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape, signed_distance

BRACKET = trimesh.load(Path(__file__).resolve().parents[1] / "scenes" / "meshes" / "l_bracket.stl")  # mm
CS, CC = PairType.CABLE_STRUCTURE, PairType.CABLE_CABLE


def _pose(x=0.0, y=0.0, z=0.0):
    pose = np.eye(4)
    pose[:3, 3] = [x, y, z]
    return pose


@pytest.fixture(scope="module")
def recheck():
    parts = [PartState("bracket", mesh_shape(BRACKET.vertices, BRACKET.faces), np.eye(4)),
             PartState("ball", Shape(ShapeType.SPHERE, [10.0]), _pose(100.0))]
    return Recheck(parts, CheckConfig("points", clearance=5.0), [])


def _cable(name, a, b, radius=1.0):
    return CableState(name, np.array([a, b], float), radius)


def test_convex_hull_is_closed_and_fills_the_pocket():
    mesh = mesh_shape(BRACKET.vertices, BRACKET.faces)
    hull = convex_hull_shape(mesh)
    assert hull.closed and len(hull.vertices) <= len(BRACKET.vertices)
    pocket = np.array([[20.0, 0.0, 25.0]])
    assert signed_distance(mesh, pocket)[0][0] > 0 > signed_distance(hull, pocket)[0][0]
    on = BRACKET.vertices
    assert np.all(signed_distance(hull, on)[0] <= 1e-9)                 # the mesh lies within its hull


def test_exact_distances_of_sparse_straight_cables(recheck):
    """Two points per cable: no discrete point comes near, the segments do."""
    past_ball = _cable("d", [100.0, -50.0, 13.0], [100.0, 50.0, 13.0])
    e, f = _cable("e", [-50.0, 0, 200.0], [50.0, 0, 200.0]), _cable("f", [0, -50.0, 203.0], [0, 50.0, 203.0])
    state = recheck.at([past_ball, e, f], np.array([np.eye(4), _pose(100.0)]))
    assert state.exact((CS, "d", "ball")) == pytest.approx(13.0 - 10.0 - 1.0, abs=1e-9)
    assert state.exact((CC, "e", "f")) == pytest.approx(3.0 - 2.0, abs=1e-9)
    far = recheck.at([_cable("d", [100.0, -50.0, 30.0], [100.0, 50.0, 30.0])], np.array([np.eye(4), _pose(100.0)]))
    assert far.exact((CS, "d", "ball")) is None                          # 19 beyond the clearance of 5
    assert state.exact((CS, "d", "nothing")) is None and state.exact((CS, "gone", "ball")) is None
    assert state.hull((CC, "e", "f")) is None


def test_a_cable_through_the_pocket_is_clear_of_the_mesh_but_not_its_hull(recheck):
    through = _cable("c", [20.0, -40.0, 25.0], [20.0, 40.0, 25.0])
    state = recheck.at([through], np.array([np.eye(4), _pose(100.0)]))
    assert recheck.is_mesh("bracket") and not recheck.is_mesh("ball") and not recheck.is_mesh("nothing")
    assert state.exact((CS, "c", "bracket")) is None
    depth = signed_distance(convex_hull_shape(recheck.parts[0].shape), np.array([[20.0, 0.0, 25.0]]))[0][0]
    assert state.hull((CS, "c", "bracket")) == pytest.approx(depth - 1.0, abs=1e-9)
    assert state.hull((CS, "c", "bracket"), exact=False) < 0


def test_a_batchs_answers_are_each_states_alone(recheck):
    states = [[_cable("c", [20.0 + dx, -40.0, 25.0], [20.0 + dx, 40.0, 25.0])] for dx in (0.0, 7.0, 30.0)]
    poses = np.array([[np.eye(4), _pose(100.0)]] * 3)
    batch = recheck.many(states, poses)
    key = (CS, "c", "bracket")
    alone = [recheck.at(s, p).hull(key, exact=False) for s, p in zip(states, poses)]
    assert [batch.at(i).hull(key, exact=False) for i in range(3)] == alone
    assert alone[0] < 0 and alone[2] is None


def test_near_finds_a_clear_sides_distance_up_to_the_limit(recheck):
    """A cable 0.05 beyond the clearance of a sphere, two cables 0.05 beyond
    it from each other: clear for exact, found by ``near`` up to 5.1 at the
    closed-form distance; beyond the limit, still None."""
    past_ball = _cable("d", [100.0, -50.0, 16.05], [100.0, 50.0, 16.05])
    e, f = _cable("e", [-50.0, 0, 200.0], [50.0, 0, 200.0]), _cable("f", [0, -50.0, 207.05], [0, 50.0, 207.05])
    state = recheck.at([past_ball, e, f], np.array([np.eye(4), _pose(100.0)]))
    assert state.exact((CS, "d", "ball")) is None and state.exact((CC, "e", "f")) is None
    assert state.near((CS, "d", "ball"), 5.1) == pytest.approx(5.05, abs=1e-9)
    assert state.near((CC, "e", "f"), 5.1) == pytest.approx(5.05, abs=1e-9)
    assert state.near((CS, "d", "ball"), 5.02) is None and state.near((CC, "e", "f"), 5.0) is None
    assert state.near((CS, "d", "nothing"), 5.1) is None and state.near((CS, "gone", "ball"), 5.1) is None


def test_near_on_a_self_pair_measures_with_the_wider_window(recheck):
    """A hairpin of radius 1 bent round a circle of radius 7 (33 points, 32
    chords): places on the bend a window w apart along it are 14 sin(w / 14)
    apart (to the chords' sagitta). At the clearance 5 (w = pi + 5) that is
    5.7 between surfaces, clear; ``near`` up to a limit L measures with w =
    pi + L: the bend's own places that far apart, the wider window's
    answer (and nothing nearer, the legs being 12 apart)."""
    bend = np.linspace(np.pi, 0.0, 33)
    arc = np.stack([7.0 * np.cos(bend), 7.0 * np.sin(bend), np.zeros(33)], axis=1)
    legs = np.linspace(-40.0, 0.0, 9)[:-1]
    pts = np.concatenate([np.stack([np.full(8, -7.0), legs, np.zeros(8)], 1), arc,
                          np.stack([np.full(8, 7.0), legs[::-1], np.zeros(8)], 1)])
    state = recheck.at([CableState("h", pts, 1.0)], np.array([np.eye(4), _pose(100.0)]))
    key = (PairType.SELF, "h", "h")
    assert state.exact(key) is None
    chord_arc = 32 * 14.0 * np.sin(np.pi / 64) / (7.0 * np.pi)    # polyline length per unit of the circle's arc
    for limit in (11.0, 11.9):
        w = (np.pi + limit) / chord_arc                        # the window, as arc of the circle
        assert state.near(key, limit) == pytest.approx(14.0 * np.sin(w / 14.0) - 2.0, abs=0.03)
