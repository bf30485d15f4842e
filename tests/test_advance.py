"""Conservative advancement (checker.advance) changes no answer.

Every example scene is run with the skip rule and checking every step in
full; events and pairs must be identical, and validation compares exactly
the fully checked steps. Unit tests of the bound itself follow.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from checker.advance import Advancement
from checker.interference.hits import Gaps, PartCandidates
from sim.run import RunOptions, run_scene
from sim.scene import load_scene

SCENES = sorted((Path(__file__).resolve().parents[1] / "scenes").glob("*.toml"))


def _strip(rows):
    return [{k: (np.asarray(v).tolist() if isinstance(v, np.ndarray) else v) for k, v in r.items()} for r in rows]


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_skipping_changes_no_answer(path: Path, tmp_path):
    scene = load_scene(path)
    fast = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    full = run_scene(scene, RunOptions(report=tmp_path / "b.json", record=None, advance=False))
    assert _strip(fast["events"]) == _strip(full["events"])
    assert _strip(fast["pairs"]) == _strip(full["pairs"])
    assert fast["summary"] == full["summary"]
    for a, b in zip(fast["cables"], full["cables"]):
        assert a["max_strain"] == b["max_strain"] and a["min_bend_radius"] == b["min_bend_radius"]
    adv = fast["settings"]["advance"]
    assert full["settings"]["advance"] is None
    if adv is not None:
        assert adv["full_checks"] + adv["proven_clear_steps"] == fast["settings"]["checked_steps"]
        if path.stem in ("arm", "keepout_bolt", "drawer_pinch"):
            # a pair inside the clearance for long stretches: checked on its own, the rest skipped
            assert adv["proven_clear_steps"] > adv["full_checks"]
    if "validation" in fast:                                  # MuJoCo compared at every checked step
        assert fast["validation"]["compared_steps"] == fast["settings"]["checked_steps"]
        assert fast["validation"] == full["validation"]


def test_drawer_skips_steps(tmp_path):
    scene = load_scene(SCENES[[p.stem for p in SCENES].index("drawer")])
    rep = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    assert rep["settings"]["advance"]["proven_clear_steps"] > 0


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


def test_bound_stretch_and_gaps_at_or_below_zero():
    a, pts, poses = _adv()
    stretched = pts.copy()
    stretched[2, 0] += 0.11                  # element lengths change by 0.11 > 0.1
    assert not a.proven_clear(stretched, poses)
    a, pts, poses = _adv(gap_cable=0.0)
    assert not a.proven_clear(pts, poses)
    a, pts, poses = _adv(bound=0.5)          # part pair at the clearance
    assert not a.proven_clear(pts, poses)


def test_attached_part_moves_while_far_part_approaches(tmp_path):
    """The drawer (carrying the cable's end) moves out while a probe on its
    own body comes down onto the cable's middle: per-centre gaps in each
    part's own frame must still catch the probe."""
    text = (SCENES[[p.stem for p in SCENES].index("drawer")]).read_text()
    text = text.replace("duration = 4.0", "duration = 1.5") + '''
[[bodies]]
name = "probe"
pos = [0, 0, 0]

[[parts]]
name = "probe/block"
body = "probe"
shape = "box"
size = [20, 20, 20]
pos = [130, 0, 200]

[[motion]]
body = "probe"
keys = [ { t = 0.0, pos = [0, 0, 0] },
         { t = 1.5, pos = [0, 0, -125] } ]
'''
    path = tmp_path / "probe.toml"
    path.write_text(text)
    scene = load_scene(path)
    fast = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    full = run_scene(scene, RunOptions(report=tmp_path / "b.json", record=None, advance=False))
    assert any(e["b"] == "probe/block" for e in _strip(full["events"]))
    assert _strip(fast["events"]) == _strip(full["events"])
    assert _strip(fast["pairs"]) == _strip(full["pairs"])
    assert fast["settings"]["advance"]["proven_clear_steps"] > 0


# ---------------------------------------------------------------------------
# Cable pairs bounded per pair of body centres and per pair of blocks

from checker.interference import Checker                      # noqa: E402
from checker.records import PairType                           # noqa: E402
from checker.scene_state import CableState, CheckConfig        # noqa: E402

_R, _CLEAR, _H, _STRETCH = 0.01, 0.005, 0.02, 0.0025
_NO_PARTS = np.zeros((0, 4, 4))


def _cable_adv(cables):
    """A checker without parts and an Advancement started from its full check."""
    config = CheckConfig(clearance=_CLEAR)
    checker = Checker([], config, horizon=_H, stretch=_STRETCH)
    states = [CableState(f"c{k}", c, _R) for k, c in enumerate(cables)]
    checked = checker.check_with_gaps(states)
    assert not [r for r in checked.records if r.type in (PairType.SELF, PairType.CABLE_CABLE)]
    offsets = np.concatenate([[0], np.cumsum([len(c) for c in cables])])
    radii = np.full(len(cables), _R)
    adv = Advancement(offsets, config.spacing * radii, np.zeros(0), _CLEAR, _STRETCH, radii)
    z = np.zeros(0, np.int64)
    adv.start(np.concatenate(cables), _NO_PARTS, checked.gaps, (z, z), np.zeros(0))
    old = Advancement(offsets, config.spacing * radii, np.zeros(0), _CLEAR, _STRETCH, radii)
    old.start(np.concatenate(cables), _NO_PARTS, replace(checked.gaps, cable_candidates=None), (z, z), np.zeros(0))
    return checker, adv, old, offsets


def _pairwise(checker, pts, offsets):
    cables = [CableState(f"c{k}", pts[a:b], _R) for k, (a, b) in enumerate(zip(offsets[:-1], offsets[1:]))]
    return [r for r in checker.check(cables, horizon=0.0) if r.type in (PairType.SELF, PairType.CABLE_CABLE)]


def _line(a, b, n):
    return np.linspace(a, b, n)


def _turn(pts, about, angle, axis=2):
    """pts rotated by angle about the point ``about`` (axis z, or y with axis=1)."""
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]) if axis == 2 else \
        np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])
    return (pts - about) @ rot.T + about


def test_cable_end_dragged_far_while_no_pair_is_close():
    """The drawer: one end fixed, the other swung many horizons away; the
    whole cable's spread fails the old bound, the local one holds."""
    pts = _line([0.0, 0, 0], [0.6, 0, 0], 41)               # 15 mm elements
    checker, adv, old, offsets = _cable_adv([pts])
    moved = _turn(pts, pts[0], 0.1, axis=1)                 # the end moves 60 mm = 3 horizons
    assert not old.proven_clear(moved, _NO_PARTS)
    assert adv.proven_clear(moved, _NO_PARTS)
    assert not _pairwise(checker, moved, offsets)
    # a kink: centres 20.. swing further, their neighbours move apart by
    # more than H; near element pairs stay apart by the chord bound, far
    # block pairs by their spheres at this state
    kinked = moved.copy()
    kinked[20:] = _turn(moved[20:], moved[20], 0.4, axis=1)
    assert adv.proven_clear(kinked, _NO_PARTS) and not _pairwise(checker, kinked, offsets)
    # folded back onto itself: found by the full check, never proven clear
    folded = moved.copy()
    folded[20:] = _turn(moved[20:], moved[20], 2.5, axis=1)
    assert _pairwise(checker, folded, offsets) and not adv.proven_clear(folded, _NO_PARTS)


def _hairpin(gap, leg=0.4):
    """A cable folded onto itself: two legs along x ``gap`` apart (centre to
    centre) joined by a half circle, about 10 mm elements; and the index of
    the second leg's first centre."""
    s = np.arange(0.0, leg, 0.01)
    a = np.stack([s[::-1], np.zeros_like(s), np.zeros_like(s)], axis=1)
    n = max(3, int(np.ceil(np.pi * gap / 2 / 0.01)) + 1)
    t = np.linspace(-np.pi / 2, np.pi / 2, n)[1:-1]
    arc = np.stack([-0.5 * gap * np.cos(t), 0.5 * gap + 0.5 * gap * np.sin(t), np.zeros_like(t)], axis=1)
    b = np.stack([s, np.full_like(s, gap), np.zeros_like(s)], axis=1)
    return np.concatenate([a, arc, b]), len(a) + len(arc)


def test_cable_folding_onto_itself():
    """The second leg of a hairpin turns about its first centre onto the
    first leg: proven clear while the tip is far, never once it is close."""
    pts, second = _hairpin(0.06)                             # legs 60 mm apart: 35 mm past the clearance
    checker, adv, old, offsets = _cable_adv([pts])
    proven = 0
    angles = np.linspace(0.0, 0.15, 31)
    for angle in angles:
        moved = pts.copy()
        moved[second:] = _turn(pts[second:], pts[second], -angle)
        clear = adv.proven_clear(moved, _NO_PARTS)
        proven += clear
        if clear:                                            # sound: the full check agrees
            assert not _pairwise(checker, moved, offsets)
    assert 0 < proven < len(angles)
    assert _pairwise(checker, moved, offsets)                # the tip reached the first leg
    assert not adv.proven_clear(moved, _NO_PARTS)


def test_two_cables_approaching():
    a = _line([0.0, 0, 0], [0.5, 0, 0], 51)
    b = _line([0.0, 0.05, 0], [0.5, 0.05, 0], 51)           # 30 mm past the clearance: no candidate
    checker, adv, old, offsets = _cable_adv([a, b])
    pts = np.concatenate([a, b])
    assert adv.proven_clear(pts + [0.0, 0.3, 0.0], _NO_PARTS)   # both translate together
    shift = np.zeros_like(pts)
    shift[51:] = [0.0, 1.0, 0.0]
    proven = 0
    for gap in np.linspace(0.0, 0.035, 36):
        moved = pts - gap * shift
        if adv.proven_clear(moved, _NO_PARTS):
            proven += 1
            assert gap < _H and not _pairwise(checker, moved, offsets)
    assert proven > 0
    assert _pairwise(checker, pts - 0.035 * shift, offsets)
    assert not adv.proven_clear(pts - 0.035 * shift, _NO_PARTS)


def test_random_motions_are_sound():
    """Random rigid motions of a hairpin (its second leg also turning about
    its first centre) and a cable crossing above it: whenever the bound
    proves a step clear, the full check finds no pair."""
    hp, second = _hairpin(0.04)
    cross = _line([0.2, -0.1, 0.03], [0.2, 0.2, 0.03], 31)   # 30 mm above: 10 mm past the clearance
    checker, adv, old, offsets = _cable_adv([hp, cross])
    rng = np.random.default_rng(6)
    moves = []
    for _ in range(400):
        scale = rng.choice([0.005, 0.01, 0.02, 0.04])
        h = hp.copy()
        h[second:] = _turn(h[second:], h[second], rng.normal() * scale * 2)
        h = _turn(h, rng.normal(size=3) * 0.2, rng.normal() * scale) + rng.normal(size=3) * scale
        c = _turn(cross, rng.normal(size=3) * 0.2, rng.normal() * scale, axis=1) + rng.normal(size=3) * scale
        moves.append(np.concatenate([h, c]))
    _assert_sound(checker, adv, offsets, moves)


def _assert_sound(checker, adv, offsets, moves):
    """Whenever the bound proves a state clear the full check finds no cable
    pair; and both happen among the states."""
    proven = found = 0
    for moved in moves:
        hit = bool(_pairwise(checker, moved, offsets))
        found += hit
        if adv.proven_clear(moved, _NO_PARTS):
            proven += 1
            assert not hit
    assert proven > 0 and found > 0


def test_clear_run_counts_the_leading_states_one_at_a_time_would():
    """clear_run over a batch of states equals testing them in order, one at
    a time, up to the first that is not proven clear (with a part moving)."""
    from checker.scene_state import PartState
    from checker.shapes import Shape, ShapeType
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


def _arc(length, curvature, n):
    """n centres along a planar arc of the given length and curvature from the origin along x."""
    s = np.linspace(0.0, length, n)
    if curvature == 0:
        return np.stack([s, np.zeros_like(s), np.zeros_like(s)], axis=1)
    return np.stack([np.sin(curvature * s) / curvature, (1 - np.cos(curvature * s)) / curvature,
                     np.zeros_like(s)], axis=1)


def test_near_pairs_by_the_chord_bound():
    """A cable curling up ever tighter until it closes on itself: neighbouring
    blocks turn far more than the horizon relative to each other, yet their
    element pairs are proven apart by the chord bound at each state, while
    the curl is open; once the ends meet nothing is proven."""
    length = 0.6
    pts = _arc(length, 0.5, 41)                                # 15 mm elements, gently bent
    checker, adv, old, offsets = _cable_adv([pts])
    proven = old_proven = 0
    for k in np.linspace(0.5, 1.15 * 2 * np.pi / length, 40):
        moved = _arc(length, k, 41)
        clear = adv.proven_clear(moved, _NO_PARTS)
        hit = bool(_pairwise(checker, moved, offsets))
        assert not (clear and hit)
        proven += clear
        if k < 2.5:                                             # half a turn over the cable, no contact
            assert clear
            old_proven += old.proven_clear(moved, _NO_PARTS)
    assert old_proven < proven / 2                              # the whole-cable spread gives up early
    assert hit and not clear


def test_chord_bound_sound_on_random_kinks():
    """Random local kinks (one centre pushed sideways, a stretch turned
    about one of its centres): proven clear only when no self pair is found."""
    pts = _arc(0.6, 2.0, 41)
    checker, adv, _, offsets = _cable_adv([pts])
    rng = np.random.default_rng(11)
    moves = []
    for _ in range(300):
        moved = pts.copy()
        i = int(rng.integers(1, 40))
        if rng.random() < 0.5:
            moved[i] += rng.normal(size=3) * rng.choice([0.005, 0.02, 0.05])
        else:
            j = min(40, i + int(rng.integers(2, 12)))
            moved[i:j + 1] = _turn(moved[i:j + 1], moved[i], rng.normal() * 2.0)
        moves.append(moved)
    _assert_sound(checker, adv, offsets, moves)


def test_active_cable_pairs_leave_the_bound():
    """Two cables crossing within the clearance: nothing is proven, unless
    the pair is active; then the centre pairs its candidates are charged to
    are listed for the caller and the rest still bounds the step."""
    a = _line([0.0, 0, 0], [0.4, 0, 0], 41)
    b = _line([0.2, -0.2, 0.022], [0.2, 0.2, 0.022], 41)     # 2 mm past the surfaces: soft
    config = CheckConfig(clearance=_CLEAR)
    checker = Checker([], config, horizon=_H, stretch=_STRETCH)
    states = [CableState("c0", a, _R), CableState("c1", b, _R)]
    checked = checker.check_with_gaps(states)
    assert [r.type for r in checked.records] == [PairType.CABLE_CABLE]
    offsets = np.array([0, 41, 82])
    radii = np.full(2, _R)
    pts = np.concatenate([a, b])
    z = np.zeros(0, np.int64)
    for active, expect in ((None, False), (np.array([[0, 1]]), True)):
        adv = Advancement(offsets, config.spacing * radii, np.zeros(0), _CLEAR, _STRETCH, radii)
        left = adv.start(pts, _NO_PARTS, checked.gaps, (z, z), np.zeros(0), cable_active=active)
        assert adv.proven_clear(pts + [0.0, 0.0, 0.001], _NO_PARTS) is expect
    i, j = left.cable
    near = set(range(14, 27))                                # within the horizon (20 mm) of x = 0.2
    assert len(i) and set(i.tolist()) <= near and set((j - 41).tolist()) <= near
    moved = pts.copy()
    moved[:5] += [0.0, 0.0, 0.03]                            # far from the crossing: still bounded
    assert not adv.proven_clear(moved, _NO_PARTS)


def test_sliding_cable_cable_contact(tmp_path):
    """The crossing's second lead carried along the first: the contact slides
    along "power" while the skipped steps evaluate the active pair on their
    own; the answers are those of checking every step in full."""
    text = (SCENES[[p.stem for p in SCENES].index("crossing")]).read_text()
    text = text.replace("duration = 0.4", "duration = 0.8")
    text = text.replace('start = { pos = [0, -120, 100] }', 'start = { body = "carriage", pos = [0, -120, 100] }')
    text = text.replace('end = { pos = [0, 120, 100] }', 'end = { body = "carriage", pos = [0, 120, 100] }')
    text += '''
[[bodies]]
name = "carriage"

[[motion]]
body = "carriage"
keys = [ { t = 0.0, pos = [0, 0, 0] }, { t = 0.8, pos = [60, 0, 0] } ]
'''
    path = tmp_path / "sliding.toml"
    path.write_text(text)
    scene = load_scene(path)
    fast = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    full = run_scene(scene, RunOptions(report=tmp_path / "b.json", record=None, advance=False))
    assert [e["type"] for e in full["events"]] == ["cable-cable"]
    assert _strip(fast["events"]) == _strip(full["events"])
    assert _strip(fast["pairs"]) == _strip(full["pairs"])
    adv = fast["settings"]["advance"]
    assert adv["proven_clear_steps"] > adv["full_checks"]


def _random_scene_text(seed: int) -> str:
    """A small random scene in mm: two cables between a fixed point and a
    moving body, random primitives on the world and on two moving bodies
    (one a keep-out), random keyframes; contact off so the cables pass
    through parts and each other (every kind of pair comes and goes)."""
    rng = np.random.default_rng(seed)
    shapes = [("box", 3), ("sphere", 1), ("capsule", 2), ("cylinder", 2)]
    text = f'''[scene]
name = "random-{seed}"
units = "mm"
duration = 0.6
settle = 0.3

[effects]
contact = []

[check]
clearance = {rng.uniform(1.0, 4.0):.3f}
'''
    for b in range(2):
        text += f'\n[[bodies]]\nname = "b{b}"\n'
        moves = np.vstack([np.zeros(3), rng.uniform(-60, 60, (2, 3))])       # bodies start at the origin
        keys = ", ".join(f"{{ t = {t:.2f}, pos = [{x:.1f}, {y:.1f}, {z:.1f}] }}"
                         for t, (x, y, z) in zip((0.0, 0.3, 0.6), moves))
        text += f'\n[[motion]]\nbody = "b{b}"\nkeys = [ {keys} ]\n'
    for k in range(5):
        kind, n = shapes[int(rng.integers(len(shapes)))]
        size = ", ".join(f"{v:.1f}" for v in rng.uniform(5, 25, n))
        pos = ", ".join(f"{v:.1f}" for v in rng.uniform(-80, 80, 3) + [0, 0, 60])
        body = ["world", "b0", "b1"][k % 3]
        text += (f'\n[[parts]]\nname = "p{k}"\nbody = "{body}"\nshape = "{kind}"\nsize = [{size}]\n'
                 f'pos = [{pos}]\nkeepout = {"true" if k == 4 else "false"}\n')
    for c in range(2):
        a = rng.uniform(-120, 120, 3) + [0, 0, 80]
        e = rng.uniform(-120, 120, 3) + [0, 0, 80]
        length = float(np.linalg.norm(e - a)) * rng.uniform(1.05, 1.4)
        text += (f'\n[[cables]]\nname = "c{c}"\nradius = {rng.uniform(2, 5):.2f}\n'
                 f'start = {{ pos = [{a[0]:.1f}, {a[1]:.1f}, {a[2]:.1f}] }}\n'
                 f'end = {{ body = "b{c}", pos = [{e[0]:.1f}, {e[1]:.1f}, {e[2]:.1f}] }}\n'
                 f'length = {length:.1f}\nsegments = {int(rng.integers(12, 30))}\nyoung = 1.0e7\n'
                 f'density = 1500\n')
    return text


@pytest.mark.parametrize("seed", range(6))
def test_random_scenes_skip_without_changing_answers(seed: int, tmp_path):
    path = tmp_path / "random.toml"
    path.write_text(_random_scene_text(seed))
    scene = load_scene(path)
    fast = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    full = run_scene(scene, RunOptions(report=tmp_path / "b.json", record=None, advance=False))
    assert _strip(fast["events"]) == _strip(full["events"])
    assert _strip(fast["pairs"]) == _strip(full["pairs"])
    for a, b in zip(fast["cables"], full["cables"]):
        assert a["max_strain"] == b["max_strain"] and a["min_bend_radius"] == b["min_bend_radius"]


DOOR = Path(__file__).resolve().parent / "scenes" / "door.toml"


def _door_variants(tmp_path) -> dict[str, Path]:
    """The door scene as written (pin allowed), without its [[allow]] pairs
    (the pin overlaps: hard part-part events) and without the pin."""
    text = DOOR.read_text()
    plain = text[:text.index("\n[[allow]]")] + "\n"
    start = plain.index('[[parts]]\nname = "hinge/pin"')
    no_pin = plain[:start] + plain[plain.index("[[parts]]", start + 1):]
    out = {"door": DOOR}
    for name, body in (("no_allow", plain), ("no_pin", no_pin)):
        (tmp_path / f"{name}.toml").write_text(body)
        out[name] = tmp_path / f"{name}.toml"
    return out


def test_door_hinge_pin_never_forces_full_checks(tmp_path):
    """A hinge pin through its knuckles, one of them on the moving door:
    a part pair inside the clearance for the whole run, checked on its own.
    The door skips exactly the steps the same door without the pin skips,
    and its answers are those of checking every step in full."""
    runs = {}
    for name, path in _door_variants(tmp_path).items():
        scene = load_scene(path)
        fast = run_scene(scene, RunOptions(report=tmp_path / f"{name}.json", record=None))
        if name != "no_pin":
            full = run_scene(scene, RunOptions(report=tmp_path / f"{name}-full.json", record=None, advance=False))
            for key in ("events", "pairs", "allowed", "summary", "validation"):
                assert _strip(fast[key]) == _strip(full[key]) if isinstance(fast[key], list) \
                    else fast[key] == full[key], key
        runs[name] = fast
    skip = {name: rep["settings"]["advance"] for name, rep in runs.items()}
    assert skip["door"] == skip["no_allow"] == skip["no_pin"]
    assert skip["door"]["proven_clear_steps"] > 4 * skip["door"]["full_checks"]
    # the pin: allowed in the scene as written, hard part-part events without the allow pairs
    pin = {(p["a"], p["b"]) for p in runs["door"]["allowed"]}
    assert pin == {("hinge/knuckle_lower", "hinge/pin"), ("hinge/knuckle_upper", "hinge/pin"),
                   ("hinge/pin", "door/knuckle")}
    assert all(p["min_distance"] < 0 and p["reason"] for p in runs["door"]["allowed"])
    hard = {(e["a"], e["b"]) for e in runs["no_allow"]["events"] if e["type"] == "part-part"}
    assert hard == pin and not any(e["type"] == "part-part" for e in runs["door"]["events"])
    cable = lambda rep: [e for e in rep["events"] if e["type"] != "part-part"]    # noqa: E731
    assert _strip(cable(runs["door"])) == _strip(cable(runs["no_allow"]))


@pytest.mark.parametrize("seed", range(3))
def test_sparse_part_gaps_change_no_answer(seed: int, tmp_path, monkeypatch):
    """The sparse centre-part gaps (forced on these small scenes) give the
    answers of checking every step in full, and skip steps as the dense table
    does where no centre moved farther than FAR_HORIZONS horizons."""
    path = tmp_path / "random.toml"
    path.write_text(_random_scene_text(seed))
    scene = load_scene(path)
    dense = run_scene(scene, RunOptions(report=tmp_path / "d.json", record=None))
    monkeypatch.setattr(Advancement, "SPARSE_ENTRIES", 0)
    fast = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    full = run_scene(scene, RunOptions(report=tmp_path / "b.json", record=None, advance=False))
    assert _strip(fast["events"]) == _strip(full["events"])
    assert _strip(fast["pairs"]) == _strip(full["pairs"])
    a, d = fast["settings"]["advance"], dense["settings"]["advance"]
    assert a["proven_clear_steps"] <= d["proven_clear_steps"]
    assert a["proven_clear_steps"] >= 0.9 * d["proven_clear_steps"]


def test_sparse_part_gaps_on_the_drawer(tmp_path, monkeypatch):
    scene = load_scene(SCENES[[p.stem for p in SCENES].index("drawer")])
    dense = run_scene(scene, RunOptions(report=tmp_path / "d.json", record=None))
    monkeypatch.setattr(Advancement, "SPARSE_ENTRIES", 0)
    sparse = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    assert _strip(sparse["events"]) == _strip(dense["events"])
    assert _strip(sparse["pairs"]) == _strip(dense["pairs"])
    assert sparse["settings"]["advance"] == dense["settings"]["advance"]


def test_clear_run_with_many_blocks_counts_what_one_at_a_time_would():
    """Many cables (block pairs found by the k-d tree, some beyond the far
    limit, tested a group at a time): clear_run over a batch equals testing
    the states in order, one at a time, up to the first not proven clear."""
    rng = np.random.default_rng(5)
    grid = np.array([(x, y) for x in range(5) for y in range(4)], float) * 0.06
    grid[:, 1] += np.where(np.arange(len(grid)) >= 12, 1.0, 0.0)        # two bundles far apart
    cables = [np.stack([np.linspace(0.0, 1.0, 41), np.full(41, x), np.full(41, y)], axis=1) for x, y in grid]
    counts = set()
    for trial in range(12):
        scale = rng.choice([0.0005, 0.002, 0.01, 0.04])
        moves = np.cumsum(rng.normal(size=(10, 1, 3)) * scale, axis=0)
        pts = np.concatenate(cables)[None] + moves * np.linspace(0.0, 1.0, len(np.concatenate(cables)))[None, :, None]
        checker, one, _, offsets = _cable_adv(cables)
        _, batch, _, _ = _cable_adv(cables)
        batch._cable_gaps._ensure_blocks()
        assert len(batch._cable_gaps._blk_start) > 64 and np.isfinite(batch._cable_gaps._g_far)
        expect = 0
        while expect < len(pts) and one.proven_clear(pts[expect], _NO_PARTS[None][0]):
            expect += 1
        assert batch.clear_run(pts, np.repeat(_NO_PARTS[None], len(pts), axis=0)) == expect
        counts.add(expect)
    assert len(counts) > 1
