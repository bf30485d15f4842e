"""Self and cable-cable pairs (cablecheck.checker.interference.cablepairs): the batched pass is the single-state check's, bit for bit."""

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st
from strategies import cable_sets, coils, coords, polylines
from test_interference import as_dict, assert_same, brute_exact, brute_points

from cablecheck.checker.cable import densify_batch
from cablecheck.checker.interference import Checker, check_state
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import CableState, CheckConfig

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
        # the batched pass's precondition: every element split alike in every state
        pieces = [densify_batch(x, offsets, cfg.spacing * radii, source=True)[4] for x in states]
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
    # the batched pass's precondition: every element split alike in every state (the
    # points per cable alone can match while two elements trade a piece)
    pieces = [densify_batch(x, offsets, cfg.spacing * radii, source=True)[4] for x in states]
    assume(all(np.array_equal(pieces[0], q) for q in pieces))
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


def _self_distance(records):
    """The self record's distance (None: no self record)."""
    found = [r.min_distance for r in records if r.type == PairType.SELF]
    return found[0] if found else None


@settings(max_examples=60, deadline=None)
@given(coils(), st.floats(0.0, 2.0), st.sampled_from([1.0, 2.0, 4.0]), st.sampled_from([0.0, 1e4]))
def test_self_rule_exact_never_misses_what_points_finds(cable, clearance_r, spacing, far):
    """On drawn coils (which come back to themselves at the window's edge):
    method exact's self record equals an every-element-pair reference of
    the documented rule taken literally (the least distance over places at
    least pi r + clearance apart along the cable, by clipping each pair's
    parameter square: test_closest.seg_seg_apart_ref), method points' equals
    the literal every-point-pair reference, and exact is never clear where
    points is not, nor farther (points' places are places of exact's
    elements); also with the coil 10,000 radii from the origin."""
    r = cable.radius
    cable = CableState("c", cable.points + far * r * np.array([0.6, -0.8, 0.3]), r)
    cfg_p = CheckConfig(method="points", spacing=spacing, clearance=clearance_r * r)
    cfg_e = CheckConfig(method="exact", spacing=spacing, clearance=clearance_r * r)
    pts = check_state([cable], [], cfg_p)
    exact = check_state([cable], [], cfg_e)
    scale = 1e-12 * (1.0 + float(np.abs(cable.points).max()))
    ref_p = brute_points([cable], [], cfg_p).get((PairType.SELF, "c", "c"))
    ref_e = brute_exact([cable], [], cfg_e).get((PairType.SELF, "c", "c"))
    d_p, d_e = _self_distance(pts), _self_distance(exact)
    assert (d_p is None) == (ref_p is None) and (d_p is None or abs(d_p - ref_p) <= scale)
    assert (d_e is None) == (ref_e is None) and (d_e is None or abs(d_e - ref_e) <= 1e3 * scale)
    if d_p is not None:
        assert d_e is not None and d_e <= d_p + scale


def test_self_rule_at_the_windows_edge_a_hairpin():
    """A hairpin of radius 4 mm, clearance 5 mm (window 4 pi + 5 along the
    cable): a bend of 8 chords of a circle of radius 4 between two legs
    that open from 8 mm apart at the bend to 10 mm 20 mm below. The legs'
    elements are nearest at the bend, inside the window; past it, by
    symmetry at a = (window - bend) / 2 down each leg, they are 8 + 2 a / L
    apart (L the leg's length): exact finds that surface distance, points
    (its points farther down) a larger one."""
    bend = np.linspace(np.pi, 0.0, 9)
    arc = np.stack([4.0 * np.cos(bend), 4.0 * np.sin(bend), np.zeros(9)], axis=1)
    cable = CableState("c", np.concatenate([[[-5.0, -20.0, 0.0]], arc, [[5.0, -20.0, 0.0]]]), 4.0)
    leg, bent = np.hypot(1.0, 20.0), 16 * 4.0 * np.sin(np.pi / 16)
    a = (4.0 * np.pi + 5.0 - bent) / 2
    d_e = _self_distance(check_state([cable], [], CheckConfig(method="exact", clearance=5.0)))
    d_p = _self_distance(check_state([cable], [], CheckConfig(method="points", clearance=5.0)))
    assert d_e == pytest.approx(2 * a / leg, abs=1e-12) and d_e < d_p - 0.4
