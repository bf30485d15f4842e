"""The skip rule's centre-part bound (cablecheck.checker.advance.structure): per-centre gaps, box floors, active pairs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, event, given, settings, strategies as st
from strategies import coords, rotations
from test_advance_cablepairs import _CLEAR, _H, _R, _STRETCH

from cablecheck.checker.advance import Advancement
from cablecheck.checker.interference import Checker
from cablecheck.checker.interference.hits import Gaps, PartCandidates
from cablecheck.checker.scene_state import CableState, CheckConfig, PartState
from cablecheck.checker.shapes import Shape, ShapeType


def test_gaps_per_centre():
    """Candidates give each body centre its own gap: a centre far from the
    part may move further than the part's (smallest) gap."""
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]])
    poses = np.tile(np.eye(4), (1, 1, 1))
    a = Advancement(np.array([0, 4]), np.array([5.0]), np.array([1.0]), 0.5, 1.0)
    # one candidate at s = 0.25 (element 0: centres 0 and 1), 0.2 past the clearance
    cand = PartCandidates(np.array([0]), np.array([0.25]), np.array([0]), np.array([0.2]))
    a.start(pts, poses, Gaps(3.0, 1.0, np.array([0.2]), cand), (np.zeros(0, int), np.zeros(0, int)), np.zeros(0))
    far = pts.copy()
    far[3] += [0.0, 0.0, 0.9]                 # centre 3: horizon 3; spread 0.9 < 1
    assert a.proven_clear(far, poses)
    near = pts.copy()
    near[1] += [0.0, 0.0, 0.21]               # centre 1 borders the candidate's element
    assert not a.proven_clear(near, poses)
    far[3] += [0.0, 0.0, 0.2]                 # spread 1.1 > gap_cable 1
    assert not a.proven_clear(far, poses)
    far[3] -= [0.0, 0.0, 0.2]
    far[0] -= [0.0, 0.0, 0.2]                 # spread 1.1 again, and centre 0 past 0.2
    assert not a.proven_clear(far, poses)


def test_part_gap_floor_from_boxes():
    """A centre with no candidate for a part gets the larger of the horizon
    and its elements' distance from the part's box (minus radius and
    clearance) as its gap: far centres may move further than the horizon,
    and never past the box."""
    pts = np.array([[0.0, 10, 0], [1, 10, 0], [2, 10, 0], [3, 10, 0]])   # 10 above the unit box's centre
    poses = np.tile(np.eye(4), (1, 1, 1))
    box = (np.array([[-0.5, -0.5, -0.5]]), np.array([[0.5, 0.5, 0.5]]))
    none = (np.zeros(0, int), np.zeros(0, int))
    gaps = Gaps(1.0, 100.0, np.array([1.0]), PartCandidates(np.zeros(0, int), np.zeros(0), np.zeros(0, int), np.zeros(0)))
    a = Advancement(np.array([0, 4]), np.array([5.0]), np.array([1.0]), 0.5, 1.0,
                    np.array([0.1]), box)
    a.start(pts, poses, gaps, none, np.zeros(0))
    # centres 0 and 1: elements' boxes 9.5 from the part's box; gap 9.5 - 0.1 - 0.5 = 8.9
    assert a.proven_clear(pts - [0.0, 8.8, 0.0], poses)
    assert not a.proven_clear(pts - [0.0, 9.0, 0.0], poses)
    # without the boxes every centre has the horizon (1)
    b = Advancement(np.array([0, 4]), np.array([5.0]), np.array([1.0]), 0.5, 1.0, np.array([0.1]))
    b.start(pts, poses, gaps, none, np.zeros(0))
    assert b.proven_clear(pts - [0.0, 0.9, 0.0], poses)
    assert not b.proven_clear(pts - [0.0, 1.1, 0.0], poses)
    # a plane (half-space z < 0 in its frame) 10 below: gap 10 - 0.6
    plane = (np.full((1, 3), -np.inf), np.array([[np.inf, np.inf, 0.0]]))
    flat = pts[:, [0, 2, 1]]                                     # z = 10
    c = Advancement(np.array([0, 4]), np.array([5.0]), np.array([np.inf]), 0.5, 1.0,
                    np.array([0.1]), plane)
    c.start(flat, poses, gaps, none, np.zeros(0))
    assert c.proven_clear(flat - [0.0, 0.0, 9.3], poses)
    assert not c.proven_clear(flat - [0.0, 0.0, 9.5], poses)


def test_active_places_leave_the_bound():
    """A place inside a part's clearance (a candidate below 0) proves
    nothing, unless its (cable, part) pair is active (the run checks the
    points near the part itself at every step): then the centres within
    FAR_HORIZONS horizons of the part are free against it, and everything
    else still bounds the step."""
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])
    poses = np.tile(np.eye(4), (2, 1, 1))
    cand = PartCandidates(np.array([0]), np.array([0.5]), np.array([0]), np.array([-0.2]))    # element 0 in part 0
    gaps = Gaps(2.0, 1.0, np.array([-0.2, 2.0]), cand)
    z = np.zeros(0, np.int64)
    for active, expect in ((None, False), ((np.array([0]), np.array([0])), True)):
        a = Advancement(np.array([0, 3]), np.array([5.0]), np.array([1.0, 1.0]), 0.5, 0.1)
        left = a.start(pts, poses, gaps, (z, z), np.zeros(0), active=active)
        assert a.proven_clear(pts + [0.0, 0.1, 0.0], poses) is expect
    assert left.structure[0].tolist() == [0, 1, 2] and left.structure[1].tolist() == [0, 0, 0]
    moved = pts.copy()
    moved[0] += [0.0, 2.1, 0.0]
    assert not a.proven_clear(moved, poses)          # part 1 still bounds it (gap: the horizon, 2)
    # a far centre (no box: gap the horizon; 8 horizons = 16 away) stays bounded
    far = np.array([[0.0, 0, 0], [1, 0, 0], [20, 0, 0], [21, 0, 0]])
    box = (np.array([[-0.5, -0.5, -0.5], [-0.5, -0.5, -0.5]]), np.array([[0.5, 0.5, 0.5], [0.5, 0.5, 0.5]]))
    b = Advancement(np.array([0, 4]), np.array([50.0]), np.array([1.0, 1.0]), 0.5, 0.1, np.array([0.1]), box)
    left = b.start(far, poses, Gaps(2.0, 100.0, np.array([-0.2, 2.0]), cand), (z, z), np.zeros(0),
                   active=(np.array([0]), np.array([0])))
    assert left.structure[0].tolist() == [0, 1, 2]         # centre 3's element is 19.5 from the box
    moved = far.copy()
    moved[3] -= [17.0, 0.0, 0.0]
    assert not b.proven_clear(moved, poses)
    assert b.proven_clear(far + [0.0, 0.0, 1.9], poses)


def _slabs_run(sparse: bool, seed: int):
    """An Advancement over two slabs and two cables (tests/test_advance_skip.py),
    its centre-part gaps dense or sparse, and random moves of the cables and
    of slab 1: (gaps, states as Advancement.clear_run hands them)."""
    import pytest
    from test_advance_skip import _two_slabs

    from cablecheck.checker.advance.common import row_norm3

    checker, fresh, pts0, poses, offsets, radii = _two_slabs()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Advancement, "SPARSE_ENTRIES", 0 if sparse else 10 ** 9)
        adv = fresh()
    rng = np.random.default_rng(seed)
    scale = rng.choice([0.001, 0.003, 0.01])
    pts = pts0[None] + np.cumsum(rng.normal(size=(10, 1, 3)) * scale, axis=0) * rng.random(len(pts0))[None, :, None]
    poses_s = np.repeat(poses[None], 10, axis=0)
    if seed % 2:
        poses_s[:, 1, :3, 3] += np.cumsum(rng.normal(size=(10, 3)) * scale, axis=0)
    x = np.ascontiguousarray(np.transpose(pts, (1, 2, 0)))
    dq = row_norm3(x - adv._pts[:, :, None])
    dp = adv._pairs.moves(poses_s).T
    return adv._parts, (x, poses_s, dq, dp)


def test_failing_names_every_pair_clear_rejects():
    """CentrePartGaps.failing (dense and sparse): the first state at which a
    (centre, part) pair fails (or a condition naming no pair) is the first
    state clear rejects; once the pairs named are promoted, clear passes
    every state up to such a condition."""
    from cablecheck.checker.advance.common import leading
    seen = set()
    for sparse in (False, True):
        for seed in range(16):
            parts, args = _slabs_run(sparse, seed)
            assert parts._sparse is sparse
            expect = leading(parts.clear(*args))
            centre, part, first, stop = parts.failing(*args)
            assert min([stop] + first.tolist()) == expect
            seen.add((sparse, expect, len(centre) > 0))
            parts.promote(centre, part)
            assert not len(parts.failing(*args)[0])
            assert leading(parts.clear(*args)) == stop
    assert {(s, e > 0) for s, e, _ in seen} >= {(False, True), (True, True)}
    assert any(named and e < 10 for _, e, named in seen)


def _straddling(h, rot0, axis, angle, c, direction, a, b, n_ride, n_still, spacing=0.05):
    """A cable straddling a part that turns about its frame's origin (a door
    about its hinge): ``n_ride`` centres ride with the part (fixed in its
    frame), ``n_still`` are held in the world; the element joining the two
    runs lies at the later state on the line through ``c`` (the part's frame)
    along ``direction``, its riding end ``a`` before c, its still end ``b``
    past it, and the still run slides along that line to keep the element's
    length. Returns the checker, the Advancement (started at the earlier
    state), and the cable and poses at the later state."""
    checker = Checker([PartState("door", Shape(ShapeType.BOX, list(h)), np.eye(4))], CheckConfig(clearance=_CLEAR),
                      horizon=_H, stretch=_STRETCH)
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    turn = np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)        # Rodrigues
    poses0 = np.eye(4)[None].copy()
    poses0[0, :3, :3] = rot0
    poses1 = poses0.copy()
    poses1[0, :3, :3] = turn @ rot0
    ride = c - (a + spacing * np.arange(n_ride)[::-1, None]) * direction         # in the part's frame
    still = poses1[0, :3, :3] @ (c + (b + spacing * np.arange(n_still)[:, None]) * direction).T
    still = still.T                                                              # in the world
    ride0, ride1 = ride @ poses0[0, :3, :3].T, ride @ poses1[0, :3, :3].T
    length = np.linalg.norm(still[0] - ride0[-1])
    toward = still[0] - ride1[-1]
    slide = ride1[-1] + length * toward / np.linalg.norm(toward) - still[0]
    pts0 = np.concatenate([ride0, still])
    pts1 = np.concatenate([ride1, still + slide])
    offsets, radii = np.array([0, len(pts0)]), np.array([_R])
    gaps = checker.check_with_gaps([CableState("c", pts0, _R)], poses0).gaps
    adv = Advancement(offsets, checker.config.spacing * radii, checker.part_radius(), _CLEAR, _STRETCH, radii,
                      checker.part_bounds())
    z = np.zeros(0, np.int64)
    adv.start(pts0, poses0, gaps, (z, z), np.zeros(0))
    return checker, adv, CableState("c", pts1, _R), poses1


def test_riding_and_still_centres_bound_the_element_between_them():
    """A door (a 6 cm cube about its hinge) turns 40 degrees; a cable's
    centre rides with it 1 m out, its neighbour is held in the world: the
    first did not move in the door's frame, the second moved less in the
    world than the door's gap minus its corners' move, yet the element
    between them sweeps through the door. Each centre alone passes one of
    its two bounds; the element's points pass neither, so the state is not
    proven clear (the full check finds the cable inside the door). The same
    cable 0.3 m off the hinge, turning 10 degrees, is proven clear."""
    along = np.array([2.0, -0.6, 0.0]) / np.linalg.norm([2.0, -0.6, 0.0])
    z = np.array([0.0, 0.0, 1.0])
    for angle, c, direction, expect in ((40.0, np.zeros(3), along, False),
                                        (10.0, np.array([0.0, 0.3, 0.0]), np.array([1.0, 0.0, 0.0]), True)):
        checker, adv, cable, poses = _straddling((0.03, 0.03, 0.03), np.eye(3), z, np.radians(angle), c,
                                                 direction, 1.044, 1.044, 1, 1)
        g = adv._parts._g_pt[:, 0]
        world = np.linalg.norm(cable.points[1] - adv._pts[1]) + adv._pairs.moves(poses[None])[0, 0]
        assert world < g[1] and 0.0 < g[0]          # the still centre by the world, the rider by rel
        assert adv.proven_clear(cable.points, poses) is expect
        assert (checker.check([cable], poses, horizon=0.0) == []) is expect


def _straddling_matches_the_full_check(sparse: bool):
    """Hypothesis: an element straddling a turning part (a run riding with
    it, a run held still; the element passing through the part or up to
    0.3 m off it): a state proven clear has no record in the full check
    (there are no active pairs)."""
    @settings(max_examples=200)
    @given(h=coords(3, 0.01, 0.05), rot0=rotations(), axis=coords(3, -1.0, 1.0), angle=st.floats(-1.2, 1.2),
           c=coords(3, -1.5, 1.5), off=st.one_of(st.just(np.zeros(3)), coords(3, -0.3, 0.3)),
           direction=coords(3, -1.0, 1.0),
           a=st.floats(0.2, 0.8), b=st.floats(0.2, 0.8), n_ride=st.integers(1, 3), n_still=st.integers(1, 3))
    def check(h, rot0, axis, angle, c, off, direction, a, b, n_ride, n_still):
        assume(np.linalg.norm(axis) > 0.1 and np.linalg.norm(direction) > 0.1)
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(Advancement, "SPARSE_ENTRIES", 0 if sparse else 10 ** 9)
            checker, adv, cable, poses = _straddling(h, rot0, axis / np.linalg.norm(axis), angle, c * h + off,
                                                     direction / np.linalg.norm(direction), a, b, n_ride, n_still)
        assert adv._parts._sparse is sparse
        clear = adv.proven_clear(cable.points, poses)
        event(f"proven clear: {clear}")
        if clear:
            assert checker.check([cable], poses, horizon=0.0) == []

    check()


def test_straddling_element_dense():
    _straddling_matches_the_full_check(False)


def test_straddling_element_sparse():
    _straddling_matches_the_full_check(True)
