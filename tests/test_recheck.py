"""Second opinions on one pair (cablecheck.checker.recheck), against closed forms: a
sparse straight cable past a sphere and across another cable measured
exactly; a cable through the pocket of an L bracket clear of the mesh but
inside its convex hull; a batch's answers those of each state alone."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from helpers import examples
from hypothesis import given, settings, strategies as st

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


@settings(max_examples=examples(20), deadline=None)
@given(seed=st.integers(0, 2**32 - 1), copies=st.integers(1, 30), windows=st.booleans(), limited=st.booleans())
def test_exact_records_of_many_pairs_at_once_are_each_pairs_alone(seed, copies, windows, limited):
    """Drawn cables against drawn parts (a mesh, primitives, a keep-out, a
    plane; some with attachment windows), each copy its own pair, pose and state, some
    limited below a value or to a span: exact_records_pairs gives, to the
    bit, each copy's record as exact_records_many of its pair alone, which
    is the one-part exact checker's own check."""
    from cablecheck.checker.recheck import exact_records_many, exact_records_pairs
    from cablecheck.checker.scene_state import Exclusion
    rng = np.random.default_rng(seed)
    parts = [PartState("bracket", mesh_shape(BRACKET.vertices, BRACKET.faces), np.eye(4)),
             PartState("ball", Shape(ShapeType.SPHERE, [10.0]), np.eye(4)),
             PartState("box", Shape(ShapeType.BOX, [8.0, 5.0, 12.0]), np.eye(4)),
             PartState("zone", Shape(ShapeType.CAPSULE, [6.0, 10.0]), np.eye(4), keepout=True),
             PartState("floor", Shape(ShapeType.PLANE, [0.0, 0.0, 0.0]), np.eye(4))]
    names = ["c0", "c1", "c2"]
    excl = [Exclusion("c1", "box", 0.0, 30.0), Exclusion("c2", "ball", 40.0, 60.0)] if windows else []
    recheck = Recheck(parts, CheckConfig("points", clearance=3.0), excl)
    drawn = []                          # a few cable objects, each shared by several copies
    for _ in range(5):
        a = names[int(rng.integers(0, 3))]
        centre = rng.uniform(-15.0, 45.0, 3)
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        pts = centre + np.linspace(-60.0, 60.0, int(rng.integers(3, 12)))[:, None] * d + rng.normal(size=(1, 3)) * 2.0
        drawn.append(CableState(a, pts, float(rng.uniform(1.0, 4.0))))
    keys, cables, poses, below, spans, checkers = [], [], [], [], [], []
    for _ in range(copies):
        k = int(rng.integers(0, len(parts)))
        cable = drawn[int(rng.integers(0, len(drawn)))]
        a = cable.name
        cables.append(cable)
        keys.append((PairType.KEEPOUT if parts[k].keepout else CS, a, parts[k].name))
        pose = np.eye(4)
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        pose[:3, :3] = q * np.sign(np.linalg.det(q))
        pose[:3, 3] = rng.uniform(0.0, 30.0, 3)
        poses.append(pose)
        below.append(float(rng.uniform(-5.0, 3.0)))
        lo = float(rng.uniform(0.0, 80.0))
        spans.append((lo, lo + float(rng.uniform(5.0, 60.0))))
        checkers.append(recheck.exact_checker(k))
    poses = np.array(poses)
    b, sp = (below, np.array(spans)) if limited else (None, None)
    got = exact_records_pairs(checkers, keys, cables, poses, excl, b, sp)
    for i in range(copies):
        alone = exact_records_many(checkers[i], [cables[i]], poses[i][None], excl, keys[i],
                                   None if b is None else [b[i]], None if sp is None else sp[i][None])[0]
        assert (got[i] is None) == (alone is None)
        if alone is not None:
            assert (got[i].type, got[i].a, got[i].b, got[i].min_distance, got[i].s, got[i].severity) == \
                (alone.type, alone.a, alone.b, alone.min_distance, alone.s, alone.severity)
            assert np.array_equal(got[i].where, alone.where)
        own = [r for r in checkers[i].check([cables[i]], poses[i][None], excl) if r.type in (CS, PairType.KEEPOUT)]
        if not limited:
            assert [(r.min_distance, r.s) for r in own] == ([] if alone is None else [(alone.min_distance, alone.s)])
        elif own and own[0].min_distance < b[i] and sp[i][0] <= own[0].s <= sp[i][1]:
            assert alone is not None and alone.min_distance == own[0].min_distance


@settings(max_examples=examples(30), deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), mm=st.booleans(), far=st.booleans())
def test_a_batchs_cable_cable_opinions_are_each_states_alone(seed, mm, far):
    """Two drawn cables (a zero-length element, crossings, touching and
    overlapping, clear) over 20 states, in m or mm, at the origin or a
    kilometre out: a batch's exact opinion of the pair at each state (found
    a window of states at a time, the centrelines' elements as capsules) is
    the one state's own check (its elements split into pieces, the same
    segments: the same value to the rounding of the pieces' ends)."""
    rng = np.random.default_rng(seed)
    unit = 1000.0 if mm else 1.0
    origin = (np.array([1000.0, -700.0, 300.0]) if far else np.zeros(3)) * unit
    clearance = 0.005 * unit
    recheck = Recheck([], CheckConfig("points", clearance=clearance), [])
    n_a, n_b = rng.integers(2, 9, 2)
    base_a = rng.uniform(-0.05, 0.05, (n_a, 3))
    base_b = rng.uniform(-0.05, 0.05, (n_b, 3))
    if n_a > 2:
        base_a[1] = base_a[0]                                         # a zero-length element
    ra, rb = rng.uniform(0.002, 0.01, 2) * unit
    states = []
    for i in range(20):
        shift = np.array([0.0, 0.0, 0.004 * (i - 10)])
        a = CableState("a", origin + (base_a + 0.002 * i * rng.standard_normal(3)) * unit, float(ra))
        b = CableState("b", origin + (base_b + shift) * unit, float(rb))
        states.append([a, b])
    batch = recheck.many(states, np.zeros((20, 0, 4, 4)))
    key = (CC, "a", "b")
    got = [batch.at(i).exact(key) for i in range(20)]
    alone = [recheck.at(s, np.zeros((0, 4, 4))).exact(key) for s in states]
    tol = 1e-12 * (unit + float(np.abs(origin).max()))
    for g, want in zip(got, alone):
        if g is None and want is None:
            continue
        if g is None or want is None:      # clear on one side: at the clearance on the other
            assert (g if want is None else want) >= clearance - tol, (g, want)
        else:
            assert g == pytest.approx(want, abs=tol)
    assert any(g is not None for g in got) or all(w is None for w in alone)


@pytest.mark.parametrize("x", [18.0, 25.0, 45.0])
def test_held_clear_leaves_out_the_held_elements_alone(x):
    """A cable along x (elements 0-1.5-30-60-... mm, its first two vertices
    held) beside a sphere (radius 3 mm, its centre 6.5 mm off the axis, the
    cable's radius 2.5 mm: 1 mm from the axis's nearest element, clearance
    2 mm). Left out, the held elements (0 to 30 mm) leave the pair at the
    sphere's distance to the next element by the closed form (beside them:
    from (30, 0, 0), 2.7 mm or more, clear; beside a free element: 1 mm,
    not clear); one state alone and a batch of states answer alike; a pair
    with no held window is never cleared so."""
    from cablecheck.checker.shapes import Shape, ShapeType
    from cablecheck.checker.scene_state import Exclusion

    pts = np.array([[0.0, 0, 0], [1.5, 0, 0], [30.0, 0, 0], [60.0, 0, 0], [90.0, 0, 0]])
    s = pts[:, 0].copy()
    cable = CableState("c", pts, 2.5, None, 90.0, s)
    pose = np.eye(4)
    pose[:3, 3] = [x, 6.5, 0.0]
    part = PartState("ball", Shape(ShapeType.SPHERE, [3.0]), pose)
    held = [Exclusion("c", "ball", 0.0, 30.0, "held element", False)]
    key = ("cable-structure", "c", "ball")
    nearest = min(np.linalg.norm(pose[:3, 3] - np.array([min(max(x, lo), hi), 0.0, 0.0]))
                  for lo, hi in ((30.0, 60.0), (60.0, 90.0))) - 5.5
    want = nearest >= 2.0
    rc = Recheck([part], CheckConfig(spacing=2.0, clearance=2.0), [], held)
    one = rc.at([cable], pose[None]).held_clear(key)
    many = rc.many([[cable]] * 3, np.stack([pose[None]] * 3)).at(1).held_clear(key)
    assert one == many == want
    assert Recheck([part], CheckConfig(spacing=2.0, clearance=2.0), []).at([cable], pose[None]).held_clear(key) is False
