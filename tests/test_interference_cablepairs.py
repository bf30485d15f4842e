"""Self and cable-cable pairs (checker.interference.cablepairs): the batched pass is the single-state check's, bit for bit."""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from strategies import cable_sets, coords, polylines
from test_interference import as_dict, assert_same, brute_points

from checker.cable import densify_batch
from checker.interference import Checker, check_state
from checker.records import PairType
from checker.scene_state import CableState, CheckConfig

pytestmark = pytest.mark.filterwarnings("error")


def test_cable_pairs_many_is_each_states_self_and_cable_cable():
    """cable_pairs_many with every pair of centres of some cable pairs active
    (so every place pair is evaluated): per state, exactly the full check's
    self and cable-cable records of those pairs (values, places, bits)."""
    seen = set()
    for seed in range(30):
        rng = np.random.default_rng(300 + seed)
        cables = []
        for c in range(3):
            n = int(rng.integers(4, 14))
            # loose coils about a shared centre: self and cable-cable hits
            t = np.linspace(0, rng.uniform(4, 12), n)
            pts = np.stack([0.03 * np.cos(t), 0.03 * np.sin(t), 0.004 * t + 0.01 * c], axis=1)
            cables.append(CableState(f"c{c}", pts + rng.normal(size=pts.shape) * 0.002, 0.004))
        cfg = CheckConfig(clearance=0.004)
        checker = Checker([], cfg)
        offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
        radii = np.array([c.radius for c in cables])
        states = np.stack([np.concatenate([c.points for c in cables]) + rng.normal(size=(offsets[-1], 3)) * 1e-5
                           for _ in range(int(rng.integers(1, 5)))])
        pieces = [np.diff(densify_batch(x, offsets, cfg.spacing * radii)[3]) for x in states]
        if any(not np.array_equal(pieces[0], q) for q in pieces):
            continue
        chosen = [(0, 0), (0, 1), (2, 2)][: int(rng.integers(1, 4))]
        ci, cj = [], []
        for a, b in chosen:
            i, j = np.meshgrid(np.arange(offsets[a], offsets[a + 1]), np.arange(offsets[b], offsets[b + 1]))
            ci.append(i.ravel())
            cj.append(j.ravel())
        got = checker.cable_pairs_many([c.name for c in cables], radii, checker.densify_many(states, offsets, radii),
                                       (np.concatenate(ci), np.concatenate(cj)))
        wanted = {(f"c{a}", f"c{b}") for a, b in chosen}
        for x, recs in zip(states, got):
            now = [CableState(c.name, x[a:b], c.radius) for c, a, b in zip(cables, offsets[:-1], offsets[1:])]
            want = [r for r in checker.check(now) if r.type in (PairType.SELF, PairType.CABLE_CABLE)
                    and (r.a, r.b) in wanted]
            assert [(r.type, r.a, r.b, r.min_distance, r.s, r.s_b) for r in recs] == \
                [(r.type, r.a, r.b, r.min_distance, r.s, r.s_b) for r in want]
            assert all(np.array_equal(a.where, b.where) for a, b in zip(recs, want))
            seen |= {r.type for r in want}
    assert seen == {PairType.SELF, PairType.CABLE_CABLE}


@settings(max_examples=40, deadline=None)
@given(cable_sets(max_cables=3, max_points=12), st.data())
def test_cable_pairs_kernel_batched_equals_single_state(cables, data):
    """point_pair_rows through cable_pairs_many (every pair of centres of
    every cable pair active, many states at once) and through Checker.check
    (one state): the same self and cable-cable records, bits and places
    included, on drawn random walks (which fold and cross) and small moves."""
    cfg = CheckConfig(clearance=data.draw(st.floats(0.0, 0.01)))
    checker = Checker([], cfg)
    offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
    radii = np.array([c.radius for c in cables])
    base = np.concatenate([c.points for c in cables])
    states = base[None] + data.draw(coords((data.draw(st.integers(1, 3)), len(base), 3), -1e-4, 1e-4))
    pieces = [np.diff(densify_batch(x, offsets, cfg.spacing * radii)[3]) for x in states]
    assume(all(np.array_equal(pieces[0], q) for q in pieces))     # the batched pass's precondition
    i, j = np.meshgrid(np.arange(offsets[-1]), np.arange(offsets[-1]))
    keep = i <= j
    got = checker.cable_pairs_many([c.name for c in cables], radii, checker.densify_many(states, offsets, radii),
                                   (i[keep], j[keep]))
    for x, recs in zip(states, got):
        now = [CableState(c.name, x[a:b], c.radius) for c, a, b in zip(cables, offsets[:-1], offsets[1:])]
        want = [r for r in checker.check(now) if r.type in (PairType.SELF, PairType.CABLE_CABLE)]
        assert [(r.type, r.a, r.b, r.min_distance, r.s, r.s_b) for r in recs] == \
            [(r.type, r.a, r.b, r.min_distance, r.s, r.s_b) for r in want]
        assert all(np.array_equal(a.where, b.where) for a, b in zip(recs, want))


@settings(max_examples=40, deadline=None)
@given(st.lists(polylines(min_points=6, max_points=20, step=0.006), min_size=1, max_size=2),
       st.floats(0.002, 0.006), st.floats(0.0, 0.01))
def test_points_near_field_equals_brute_force(lines, radius, clearance):
    """Random walks of steps about the radius fold back within a few places
    along the cable (the near field's windows) and cross each other: the
    self and cable-cable records equal an every-pair reference."""
    cables = [CableState(f"c{k}", p, radius) for k, p in enumerate(lines)]
    cfg = CheckConfig(clearance=clearance)
    assert_same(as_dict(check_state(cables, [], cfg)), brute_points(cables, [], cfg), 1e-12)
