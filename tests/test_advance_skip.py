"""The skip rule's state machine (checker.advance.skip): starts, runs of states, pieces and stretch."""

from __future__ import annotations

import numpy as np
from test_advance_cablepairs import _CLEAR, _H, _R, _STRETCH, _hairpin

from checker.advance import Advancement
from checker.interference import Checker
from checker.interference.hits import Gaps
from checker.scene_state import CableState, CheckConfig, PartState
from checker.shapes import Shape, ShapeType


def _adv(gap_cable=1.0, gap_part=1.0, bound=10.0):
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])
    poses = np.tile(np.eye(4), (2, 1, 1))
    a = Advancement(np.array([0, 3]), np.array([5.0]), np.array([1.0, 1.0]), 0.5, 0.1)
    a.start(pts, poses, Gaps(0.0, gap_cable, np.array([gap_part, gap_part])), (np.array([0]), np.array([1])),
            np.array([bound]))
    return a, pts, poses


def test_bound_cable_and_parts():
    a, pts, poses = _adv()
    assert a.proven_clear(pts, poses)
    moved = pts + [0.0, 0.49, 0.0]
    assert a.proven_clear(moved, poses)
    assert not a.proven_clear(pts + [0.0, 1.01, 0.0], poses)   # past the part gap 1
    # the cable's own pairs: the spread of the displacements (0 here), not
    # twice the largest (1.2 > gap_cable 1)
    assert a.proven_clear(pts + [0.0, 0.6, 0.0], poses)
    p2 = poses.copy()
    p2[0, :3, 3] = [0.3, 0, 0]
    assert a.proven_clear(moved, p2)          # |(-0.3, 0.49)| < 1 in part 0's frame
    assert not a.proven_clear(moved + [0, 0.5, 0], p2)   # |(-0.3, 0.99)| > 1
    # a part and the cable moving together: nothing moved in the part's frame
    p4 = poses.copy()
    p4[:, :3, 3] = [0.0, 5.0, 0.0]
    a2, _, _ = _adv(bound=100.0)
    assert a2.proven_clear(pts + [0.0, 5.0, 0.0], p4)
    assert not a2.proven_clear(pts, p4)
    c, s = np.cos(0.2), np.sin(0.2)
    p3 = poses.copy()
    p3[1, :3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]   # ||dR||_F ~ 0.28 per unit radius
    assert a.proven_clear(pts, p3)
    p3[1, :3, 3] = [0.8, 0.4, 0]
    assert not a.proven_clear(pts, p3)


def test_bound_stretch_and_gaps_at_or_below_zero():
    a, pts, poses = _adv()
    stretched = pts.copy()
    stretched[2, 0] += 0.11                  # element lengths change by 0.11 > 0.1
    assert not a.proven_clear(stretched, poses)
    a, pts, poses = _adv(gap_cable=0.0)
    assert not a.proven_clear(pts, poses)
    a, pts, poses = _adv(bound=0.5)          # part pair at the clearance
    assert not a.proven_clear(pts, poses)


def test_clear_run_counts_the_leading_states_one_at_a_time_would():
    """clear_run over a batch of states equals testing them in order, one at
    a time, up to the first that is not proven clear (with a part moving)."""
    hp, _ = _hairpin(0.04)
    config = CheckConfig(clearance=_CLEAR)
    poses0 = np.eye(4)[None].copy()
    poses0[0, :3, 3] = [0.0, 0.0, -0.05]                  # a slab 25 mm under the cable's surface
    checker = Checker([PartState("slab", Shape(ShapeType.BOX, [1.0, 1.0, 0.015]), np.eye(4))],
                      config, horizon=_H, stretch=_STRETCH)
    gaps = checker.check_with_gaps([CableState("c0", hp, _R)], poses0).gaps
    offsets = np.array([0, len(hp)])
    z = np.zeros(0, np.int64)

    def fresh():
        a = Advancement(offsets, config.spacing * np.array([_R]), np.array([1.5]), _CLEAR, _STRETCH,
                        np.array([_R]), checker.part_bounds())
        a.start(hp, poses0, gaps, (z, z), np.zeros(0))
        return a

    rng = np.random.default_rng(3)
    counts = set()
    for trial in range(40):
        scale = rng.choice([0.001, 0.003, 0.01])
        pts = hp[None] + np.cumsum(rng.normal(size=(12, 1, 3)) * scale, axis=0)
        pts[:, 5:] += np.cumsum(rng.normal(size=(12, 1, 3)) * scale, axis=0)   # and bends
        poses = np.repeat(poses0, 12, axis=0)[:, None].copy()
        poses[:, 0, :3, 3] += np.cumsum(rng.normal(size=(12, 3)) * scale, axis=0)
        one, batch = fresh(), fresh()
        expect = 0
        while expect < 12 and one.proven_clear(pts[expect], poses[expect]):
            expect += 1
        assert batch.clear_run(pts, poses) == expect == batch.skipped
        counts.add(expect)
    assert 0 in counts and 12 in counts and len(counts) > 2
