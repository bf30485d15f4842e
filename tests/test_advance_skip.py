"""The skip rule's state machine (cablecheck.checker.advance.skip): starts, runs of states, pieces and stretch."""

from __future__ import annotations

import numpy as np
from test_advance_cablepairs import _CLEAR, _H, _R, _STRETCH, _hairpin

from cablecheck.checker.advance import Advancement
from cablecheck.checker.interference import Checker
from cablecheck.checker.interference.discrete import points_error
from cablecheck.checker.interference.hits import Gaps
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import CableState, CheckConfig, PartState
from cablecheck.checker.shapes import Shape, ShapeType


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


def _hairpin_over_moving_slab():
    """A hairpin 25 mm above a slab's surface, an Advancement factory started
    from its full check, and 40 random batches of 12 states in which the
    cable moves and bends and the slab moves (seeded)."""
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

    def batches():
        rng = np.random.default_rng(3)
        for _ in range(40):
            scale = rng.choice([0.001, 0.003, 0.01])
            pts = hp[None] + np.cumsum(rng.normal(size=(12, 1, 3)) * scale, axis=0)
            pts[:, 5:] += np.cumsum(rng.normal(size=(12, 1, 3)) * scale, axis=0)   # and bends
            poses = np.repeat(poses0, 12, axis=0)[:, None].copy()
            poses[:, 0, :3, 3] += np.cumsum(rng.normal(size=(12, 3)) * scale, axis=0)
            yield pts, poses

    return fresh, batches()


def test_clear_run_counts_the_leading_states_one_at_a_time_would():
    """clear_run over a batch of states equals testing them in order, one at
    a time, up to the first that is not proven clear (with a part moving)."""
    fresh, batches = _hairpin_over_moving_slab()
    counts = set()
    for pts, poses in batches:
        one, batch = fresh(), fresh()
        expect = 0
        while expect < 12 and one.proven_clear(pts[expect], poses[expect]):
            expect += 1
        assert batch.clear_run(pts, poses) == expect == batch.skipped
        counts.add(expect)
    assert 0 in counts and 12 in counts and len(counts) > 2


def _two_slabs():
    """Two slabs and two cables (metres): cable a lies inside the clearance
    of slab 0 (an active pair), cable b starts 12 mm above slab 1 (a
    candidate 7 mm past the clearance); the checker and an Advancement
    started from its full check with (a, slab 0) active."""
    slab = Shape(ShapeType.BOX, [0.3, 0.1, 0.01])
    config = CheckConfig(clearance=_CLEAR)
    parts = [PartState("slab0", slab, np.eye(4)), PartState("slab1", slab, np.eye(4))]
    poses = np.tile(np.eye(4), (2, 1, 1))
    poses[1, :3, 3] = [0.0, 0.5, 0.0]
    checker = Checker(parts, config, horizon=_H, stretch=_STRETCH)
    x = np.linspace(-0.2, 0.2, 21)
    a = np.stack([x, np.zeros(21), np.full(21, 0.01 + _R + 0.002)], axis=1)
    b = np.stack([x, np.full(21, 0.5), np.full(21, 0.01 + _R + 0.012)], axis=1)
    offsets = np.array([0, 21, 42])
    radii = np.array([_R, _R])
    gaps = checker.check_with_gaps([CableState("a", a, _R), CableState("b", b, _R)], poses).gaps
    z = np.zeros(0, np.int64)

    def fresh():
        adv = Advancement(offsets, config.spacing * radii, np.array([0.32, 0.32]), _CLEAR, _STRETCH, radii,
                          checker.part_bounds())
        adv.start(np.concatenate([a, b]), poses, gaps, (z, z), np.zeros(0), active=(np.array([0]), np.array([0])))
        return adv

    return checker, fresh, np.concatenate([a, b]), poses, offsets, radii


def test_clear_run_local_promotes_the_pairs_whose_bound_fails():
    """Cable a shifts along slab 0 inside its clearance (active) while cable
    b comes down onto slab 1, past its gap and into the clearance: without
    a budget the run stops where b's bound fails (as clear_run does); with
    one, b's centres against slab 1 are promoted and every state is proven,
    and evaluating the active and promoted pairs alone gives each state's
    full-check records, to the bit."""
    checker, fresh, pts0, poses, offsets, radii = _two_slabs()
    steps = np.arange(1, 9)
    pts = np.repeat(pts0[None], len(steps), axis=0)
    pts[:, :21, 0] += 0.001 * steps[:, None]                 # a slides along slab 0
    pts[:, 21:, 2] -= 0.002 * steps[:, None]                 # b comes down 2 mm a step, to 4 mm
    poses_s = np.repeat(poses[None], len(steps), axis=0)
    strict = fresh().clear_run(pts, poses_s)
    # b's gap is 7 mm past the clearance less what the points may over-state (points_error, 4.14 mm
    # for r = 10 mm: a pair kept clear by the points is clear by method exact too): 2.86 mm, which b's
    # 2 mm a step passes at the 2nd state
    assert strict == int((0.007 - points_error(_R, 2.0)) // 0.002) == 1
    assert fresh().clear_run_local(pts, poses_s, 0).states == strict
    cleared = fresh().clear_run_local(pts, poses_s, 100)
    assert cleared.states == len(steps)
    centre, part = cleared.active.structure
    assert set(part[centre >= 21].tolist()) == {1} and set(part[centre < 21].tolist()) == {0}
    assert len(cleared.active.cable[0]) == 0
    dense = checker.densify_many(pts, offsets, radii)
    local = checker.structure_many(["a", "b"], radii, dense, poses_s, (), cleared.active.structure)
    for k in range(len(steps)):
        cables = [CableState("a", pts[k, :21], _R), CableState("b", pts[k, 21:], _R)]
        full = [r for r in checker.check(cables, poses_s[k], horizon=0.0)
                if r.type in (PairType.CABLE_STRUCTURE, PairType.KEEPOUT)]
        assert [repr(r) for r in local[k]] == [repr(r) for r in full]
    assert {r.b for r in local[-1]} == {"slab0", "slab1"}      # b ends inside the clearance
    # a tight budget ends the run where the promoted pairs would exceed it
    tight = fresh().clear_run_local(pts, poses_s, 4)
    assert strict <= tight.states < len(steps)


def test_clear_run_local_without_budget_counts_what_clear_run_counts():
    """Budget 0 promotes nothing: the same leading states as clear_run, on
    random moves of a hairpin over a slab (a part moving too)."""
    fresh, batches = _hairpin_over_moving_slab()
    counts = set()
    for pts, poses in batches:
        a, b = fresh(), fresh()
        n = a.clear_run(pts, poses)
        assert b.clear_run_local(pts, poses, 0).states == n == b.skipped
        counts.add(n)
    assert 0 in counts and 12 in counts and len(counts) > 2


def test_stretch_runs_hold_every_pair_the_stretch_protects():
    """Each element's run (Advancement._stretch_runs) reaches every element f
    of its cable that a self pair inside the exclusion window could span
    (the elements between them shorter than the window) and the near
    pairs' chord spans (f < e + 2 BLOCK); a stretch spread over a long cable
    passes where the cable's sum would not, one concentrated in a run does
    not."""
    from cablecheck.checker.advance.cablepairs import CablePairGaps
    rng = np.random.default_rng(4)
    for trial in range(20):
        counts = rng.integers(2, 30, size=3)
        offsets = np.concatenate([[0], np.cumsum(counts)])
        radii = rng.uniform(0.002, 0.01, size=3)
        pts = np.concatenate([np.cumsum(rng.uniform(0.001, 0.02, size=(c, 3)), axis=0) for c in counts])
        a = Advancement(offsets, 0.5 * radii, np.zeros(0), _CLEAR, _STRETCH, radii)
        z = np.zeros(0, np.int64)
        a.start(pts, np.zeros((0, 4, 4)), Gaps(_H, 1.0, np.zeros(0)), (z, z), np.zeros(0))
        run = a._run_last
        cable = np.repeat(np.arange(3), counts)
        s_c = np.concatenate([np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(pts[o:o + c], axis=0), axis=1))]
                              for o, c in zip(offsets[:-1], counts)])
        for e in range(len(pts) - 1):
            if cable[e] != cable[e + 1]:
                continue
            for f in range(e, offsets[cable[e] + 1] - 1):
                window = np.pi * radii[cable[e]] + _CLEAR
                if s_c[f] - s_c[e + 1] < window or f < e + 2 * CablePairGaps.BLOCK:
                    assert run[e] >= f, (trial, e, f)
    # 60 elements of 10 mm, window pi r + clearance = 36 mm: each lengthened by 0.1 mm
    line = np.linspace([0.0, 0, 0], [0.6, 0, 0], 61)
    a = Advancement(np.array([0, 61]), np.array([5.0]), np.zeros(0), _CLEAR, _STRETCH, np.array([_R]))
    z = np.zeros(0, np.int64)
    a.start(line, np.zeros((0, 4, 4)), Gaps(_H, 1.0, np.zeros(0)), (z, z), np.zeros(0))
    spread = line * 1.01                                      # 6 mm in all, 0.1 mm per element
    assert a.proven_clear(spread, np.zeros((0, 4, 4)))
    bunched = line.copy()
    bunched[30:] += [0.003, 0.0, 0.0]                         # 3 mm > stretch (2.5 mm) in one element
    assert not a.proven_clear(bunched, np.zeros((0, 4, 4)))


def test_clear_run_local_in_calls_of_any_length_proves_what_one_call_proves():
    """The states of a batch handed to clear_run_local in consecutive calls
    of drawn lengths (each call's run of states continuing the last's) are
    proven exactly as in one call: the same count, the same pairs left to
    the caller (budgets 0, 3 and 100, on the hairpin's random batches)."""
    fresh, batches = _hairpin_over_moving_slab()
    rng = np.random.default_rng(7)
    counts = set()
    for pts, poses in batches:
        for budget in (0, 3, 100):
            one = fresh().clear_run_local(pts, poses, budget)
            split, done = fresh(), 0
            cuts = np.sort(rng.choice(np.arange(1, 12), size=rng.integers(1, 5), replace=False))
            for lo, hi in zip(np.r_[0, cuts], np.r_[cuts, 12]):
                part = split.clear_run_local(pts[lo:hi], poses[lo:hi], budget)
                done += part.states
                if part.states < hi - lo:
                    break
            assert done == one.states == split.skipped
            assert all(np.array_equal(x, y) for x, y in zip(part.active.structure + part.active.cable,
                                                            one.active.structure + one.active.cable))
            counts.add(one.states)
    assert 0 in counts and 12 in counts and len(counts) > 2
