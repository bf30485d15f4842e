"""The skip rule's cable-pair bound (cablecheck.checker.advance.cablepairs): sound on moves that fold, kink and cross.

Each test starts the bound from a real full check (Checker.check_with_gaps)
and compares what it proves clear with the pairwise check at the new state.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from hypothesis import given, settings, strategies as st
from strategies import coords, polylines

from cablecheck.checker.advance import Advancement
from cablecheck.checker.closest import segment_segment
from cablecheck.checker.interference import Checker
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import CableState, CheckConfig

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
    margin = 0.05 - 2 * _R - _CLEAR                          # how far b may come before the clearance
    for gap in np.linspace(0.0, 0.035, 36):
        moved = pts - gap * shift
        if adv.proven_clear(moved, _NO_PARTS):
            proven += 1
            assert gap < margin and not _pairwise(checker, moved, offsets)
    # the blocks' boxes (parallel leads: their distance is the leads') prove
    # every step short of the clearance, past the horizon
    assert proven == np.count_nonzero(np.linspace(0.0, 0.035, 36) < margin - 1e-9) > _H / 0.001 + 1
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


def _clear_args(adv, pts):
    """What Advancement.clear_run hands the cable-pair conditions for states pts (S, N, 3)."""
    from cablecheck.checker.advance.common import row_norm3
    x = np.ascontiguousarray(np.transpose(pts, (1, 2, 0)))
    move = x - adv._pts[:, :, None]
    dq = row_norm3(move)
    spread = move.max(axis=0) - move.min(axis=0)
    diag = np.sqrt(np.einsum("is,is->s", spread, spread))
    d = x[1:] - x[:-1]
    return x, move, np.minimum(2.0 * dq.max(axis=0), diag), diag, d, row_norm3(d)


def test_failing_names_every_pair_clear_rejects():
    """CablePairGaps.failing: the first state at which a near pair, a
    centre pair or a block pair fails (or a condition naming no pair) is
    the first state clear rejects; promoting the pairs named lets the
    states pass up to the next such condition."""
    from cablecheck.checker.advance.common import leading
    rng = np.random.default_rng(8)
    grid = np.array([(x, y) for x in range(5) for y in range(4)], float) * 0.06
    cables = [np.stack([np.linspace(0.0, 1.0, 41), np.full(41, x), np.full(41, y)], axis=1) for x, y in grid]
    hp, second = _hairpin(0.04)
    seen = set()
    for trial in range(24):
        base = cables if trial % 2 else [hp]
        flat = np.concatenate(base)
        scale = rng.choice([0.001, 0.004, 0.01, 0.03])
        moves = np.cumsum(rng.normal(size=(8, 1, 3)) * scale, axis=0)
        pts = flat[None] + moves * rng.random(len(flat))[None, :, None]
        _, adv, _, _ = _cable_adv(base)
        gaps = adv._cable_gaps
        args = _clear_args(adv, pts)
        expect = leading(gaps.clear(*args))
        (near, cc, blocks), stop = gaps.failing(*args)
        first = min([stop] + [int(f.min()) for f in (near[1], cc[1], blocks[2]) if len(f)])
        assert first == expect
        seen.add((expect, bool(len(near[0])), bool(len(cc[0])), bool(len(blocks[0]))))
        gaps.promote(near[0], cc[0], blocks[0], blocks[1])
        (near2, cc2, blocks2), stop2 = gaps.failing(*args)
        assert stop2 == stop and not len(near2[0]) + len(cc2[0]) + len(blocks2[0])
        assert leading(gaps.clear(*args)) == stop
        i, j = gaps.centre_pairs(near[0], cc[0], blocks[0], blocks[1])
        assert np.all(i <= j) and len(np.unique(i * len(flat) + j)) == len(i)
    assert any(s[1] for s in seen) and any(s[3] for s in seen) and {s[0] for s in seen} >= {0, 8}


def test_blocks_stay_on_one_cable():
    """Blocks of BLOCK elements restart at every cable (a block across two
    cables would span from one's end to the other's start)."""
    cables = [_line([0.0, 0, 0], [0.4, 0, 0], 41), _line([0.0, 0.1, 0], [0.1, 0.1, 0], 3),
              _line([0.0, 0.2, 0], [0.4, 0.2, 0], 10)]
    _, adv, _, offsets = _cable_adv(cables)
    gaps = adv._cable_gaps
    gaps._ensure_blocks()
    start, last = gaps._blk_start, gaps._blk_last
    cable = np.searchsorted(offsets, start, "right") - 1
    assert np.all(last < offsets[cable + 1]) and np.all(last - start <= gaps.BLOCK) and np.all(last > start)
    assert start.tolist() == [0, 4, 8, 12, 16, 20, 24, 28, 32, 36, 41, 44, 48, 52]


def test_parallel_leads_turning_together_apart_by_the_axes():
    """Two leads side by side turning together far about a distant axis:
    their blocks' relative displacements pass every gap and their oblique
    blocks' boxes overlap, yet every two of their elements are apart along
    the line between their closest points (the axes), so the states are
    proven clear; pushed within the clearance of each other, never."""
    a = _line([0.0, 0, 0], [0.4, 0, 0], 41)                  # 10 mm elements
    b = _line([0.0, 0.05, 0], [0.4, 0.05, 0], 41)            # 25 mm past the clearance: no candidate
    checker, adv, _, offsets = _cable_adv([a, b])
    pts = np.concatenate([a, b])
    gaps = adv._cable_gaps
    for angle in (0.6, 0.8, -0.7):
        turned = _turn(pts, np.array([1.0, -1.0, 0.0]), angle)
        assert not _pairwise(checker, turned, offsets)
        assert adv.proven_clear(turned, _NO_PARTS)
        x = turned[:, :, None]
        bi, bj, bad = gaps._block_fails(x, x - pts[:, :, None], 1.0)
        assert len(bi) and not bad.any()                      # block pairs tested, all apart
        # the boxes alone (at the state) leave some of them failing
        lo, hi = gaps._block_boxes(x)
        sep = np.maximum(np.maximum(lo[bj] - hi[bi], lo[bi] - hi[bj]), 0.0)
        assert (np.sqrt((sep ** 2).sum(axis=1))[:, 0] <= (gaps._blk_rad[bi] + gaps._blk_rad[bj])[:, 0]).any()
    close = pts.copy()
    close[41:] -= [0.0, 0.05 - 2 * _R - _CLEAR + 0.001, 0.0]      # 1 mm inside the clearance
    turned = _turn(close, np.array([1.0, -1.0, 0.0]), 0.7)
    assert _pairwise(checker, turned, offsets) and not adv.proven_clear(turned, _NO_PARTS)


@settings(max_examples=300, deadline=None)
@given(cables=st.lists(polylines(min_points=2, max_points=14, step=0.02), min_size=1, max_size=2),
       t=coords(9, 0.0, 1.0))
def test_axes_gap_bounds_every_two_places(cables, t):
    """The axes' gap of two blocks never exceeds the distance of any two
    places on them (brute force: places at drawn and fixed parameters on
    every two of their elements, and the closest points of every two
    elements); on elements meeting at an angle it is their distance."""
    config = CheckConfig(clearance=_CLEAR)
    checker = Checker([], config, horizon=_H, stretch=_STRETCH)
    offsets = np.concatenate([[0], np.cumsum([len(c) for c in cables])])
    radii = np.full(len(cables), _R)
    adv = Advancement(offsets, config.spacing * radii, np.zeros(0), _CLEAR, _STRETCH, radii)
    pts = np.concatenate(cables)
    z = np.zeros(0, np.int64)
    adv.start(pts, _NO_PARTS, checker.check_with_gaps([CableState(f"c{k}", c, _R) for k, c in enumerate(cables)]).gaps,
              (z, z), np.zeros(0))
    gaps = adv._cable_gaps
    gaps._ensure_blocks()
    nb = len(gaps._blk_start)
    a, b = (x.ravel() for x in np.meshgrid(np.arange(nb), np.arange(nb), indexing="ij"))
    got = gaps._axes_gap(pts[:, :, None], a, b, np.zeros(len(a), np.int64))
    # with ``enough``, the spheres alone where they suffice: still a lower bound, the same verdict
    enough = np.abs(t[0]) * 0.05 * np.ones(len(a))
    cheap = gaps._axes_gap(pts[:, :, None], a, b, np.zeros(len(a), np.int64), enough)
    assert np.array_equal(cheap > enough, got > enough) and np.all(cheap <= got)
    u = np.concatenate([[0.0, 0.5, 1.0], t])
    for m in range(len(a)):
        ea = np.arange(gaps._blk_start[a[m]], gaps._blk_last[a[m]])
        eb = np.arange(gaps._blk_start[b[m]], gaps._blk_last[b[m]])
        if not len(ea) or not len(eb):
            assert got[m] == -np.inf
            continue
        pa = (pts[ea][:, None] * (1 - u)[:, None] + pts[ea + 1][:, None] * u[:, None]).reshape(-1, 3)
        pb = (pts[eb][:, None] * (1 - u)[:, None] + pts[eb + 1][:, None] * u[:, None]).reshape(-1, 3)
        places = np.sqrt(((pa[:, None] - pb[None]) ** 2).sum(axis=2)).min()
        e, f = np.repeat(ea, len(eb)), np.tile(eb, len(ea))
        seg = segment_segment(pts[e], pts[e + 1], pts[f], pts[f + 1])[0].min()
        assert got[m] <= min(places, seg) + 1e-12 and cheap[m] <= min(places, seg) + 1e-12
    # two elements meeting at right angles 30 mm apart: the gap is their distance
    cross = [_line([0.0, 0, 0], [0.04, 0, 0], 5), _line([0.02, -0.02, 0.03], [0.02, 0.02, 0.03], 5)]
    adv = Advancement(np.array([0, 5, 10]), config.spacing * np.full(2, _R), np.zeros(0), _CLEAR, _STRETCH,
                      np.full(2, _R))
    adv.start(np.concatenate(cross), _NO_PARTS, checker.check_with_gaps(
        [CableState(f"c{k}", c, _R) for k, c in enumerate(cross)]).gaps, (z, z), np.zeros(0))
    adv._cable_gaps._ensure_blocks()
    gap = adv._cable_gaps._axes_gap(np.concatenate(cross)[:, :, None], np.array([0]), np.array([1]), np.array([0]))
    assert abs(gap[0] - 0.03) < 1e-12
