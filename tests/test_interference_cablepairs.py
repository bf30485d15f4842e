"""Self and cable-cable pairs (cablecheck.checker.interference.cablepairs): the batched pass is the single-state check's, bit for bit."""

import numpy as np
import pytest
from helpers import element_gaps, examples
from hypothesis import assume, given, settings, strategies as st
from strategies import cable_sets, coils, coords, polylines
from test_interference import as_dict, assert_same, brute_exact, brute_points

from cablecheck.checker.cable import densify_batch
from cablecheck.checker.interference import Checker, check_state
from cablecheck.checker.records import PairType
from cablecheck.checker.arrays import ranges, within
from cablecheck.checker.cable import self_pair_window
from cablecheck.checker.interference.cablepairs import closest_elements, point_pair_rows
from cablecheck.checker.interference.hits import TYPE_ORDER, worst_records
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



@settings(max_examples=60, deadline=None)
@given(st.lists(st.one_of(polylines(min_points=3, max_points=16, step=0.02).map(lambda x: (x, None)),
                          coils(max_points=24).map(lambda c: (c.points, c.radius))), min_size=1, max_size=6),
       st.data())
def test_cable_pairs_many_prunes_nothing_the_product_holds(drawn, data):
    """Drawn cables, some active pairs of centres drawn at random (a centre with
    itself, neighbours, across cables), some states, the points of every centre
    or of the active ones and their neighbours only: the records equal, to the
    bit, those of pairing every point next to each active centre with every
    one next to its partner, nothing pruned. Coils among them come back on
    themselves: a point against a piece's midpoint of its own cable."""
    from cablecheck.checker.interference.discrete import around_centres
    lines = [x for x, _ in drawn]
    radii = np.array([r if r is not None else data.draw(st.floats(0.002, 0.01)) for _, r in drawn])
    cfg = CheckConfig(clearance=data.draw(st.floats(0.0, 0.01)), spacing=data.draw(st.sampled_from([0.5, 1.0, 2.0])))
    checker = Checker([], cfg)
    offsets = np.concatenate([[0], np.cumsum([len(x) for x in lines])])
    n = int(offsets[-1])
    base = np.concatenate(lines)
    states = base[None] + data.draw(coords((data.draw(st.integers(1, 3)), n, 3), -2e-3, 2e-3))
    pieces = [densify_batch(x, offsets, cfg.spacing * radii, source=True)[4] for x in states]
    assume(all(np.array_equal(pieces[0], q) for q in pieces))
    k = data.draw(st.integers(1, 3 * n))
    seed = data.draw(st.integers(0, 2 ** 32 - 1))
    rng = np.random.default_rng(seed)
    ci, cj = rng.integers(0, n, k), rng.integers(0, n, k)
    cj = np.where(rng.random(k) < 0.3, np.clip(ci + rng.integers(-2, 3, k), 0, n - 1), cj)
    keep = around_centres(np.r_[ci, cj], n) if data.draw(st.booleans()) else None
    dense = checker.densify_many(states, offsets, radii, keep=keep)
    names = [f"c{x}" for x in range(len(lines))]
    got = checker.cable_pairs_many(names, radii, dense, (ci, cj))
    want = _next_to_active_every_pair(cfg.clearance, names, radii, dense, (ci, cj))
    for g, w in zip(got, want):
        assert [(r.type, r.a, r.b, r.min_distance, r.s, r.s_b) for r in g] == \
            [(r.type, r.a, r.b, r.min_distance, r.s, r.s_b) for r in w]
        assert all(np.array_equal(a.where, b.where) for a, b in zip(g, w))



def test_cable_pairs_many_hairpin_of_long_elements_against_the_product():
    """A hairpin whose legs are a few long elements each (8 radii), the far leg
    shifted along by part of a spacing so that a point faces the midpoint of a
    piece across: with active pairs drawn among the legs' centres, the pruned
    pass gives the product's records, some of them at a piece's midpoint."""
    r = 0.004
    cfg = CheckConfig(clearance=0.002)
    checker = Checker([], cfg)
    at_mid = 0
    for shift in np.linspace(0.0, 2 * r, 9):
        leg = np.arange(6) * 8 * r
        a = np.stack([leg, np.zeros(6), np.zeros(6)], axis=1)
        b = np.stack([leg[::-1] + shift, np.full(6, 2 * r + 0.001), np.zeros(6)], axis=1)
        turn = np.array([[leg[-1] + 4 * r, r + 0.0005, 0.0]])
        pts = np.concatenate([a, turn, b])
        offsets = np.array([0, len(pts)])
        rng = np.random.default_rng(int(shift * 1e6))
        ci, cj = rng.integers(0, 6, 20), rng.integers(7, 13, 20)
        dense = checker.densify_many(pts[None], offsets, np.array([r]))
        got = checker.cable_pairs_many(["c"], np.array([r]), dense, (ci, cj))
        want = _next_to_active_every_pair(cfg.clearance, ["c"], np.array([r]), dense, (ci, cj))
        assert [(x.type, x.min_distance, x.s, x.s_b) for x in got[0]] == \
            [(x.type, x.min_distance, x.s, x.s_b) for x in want[0]]
        at_mid += sum(not np.any(np.isclose(x.s_b, dense.s, rtol=0, atol=1e-12)) for x in got[0])
    assert at_mid > 0


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


def _next_to_active_every_pair(clearance, names, radii, dense, active):
    """cable_pairs_many as first written: every point next to centre i paired with
    every one next to j (and with the pieces' midpoints), made distinct by sorting,
    nothing pruned: the reference the pruned pass must equal."""
    n_s, n, n_c = dense.states, dense.centres, dense.cables
    out = [[] for _ in range(n_s)]
    ci, cj = (np.asarray(x, np.int64) for x in active)
    if n_s == 0 or len(ci) == 0:
        return out
    radii = np.asarray(radii, float)
    p, s, poly, src, own = dense.p, dense.s, dense.poly, dense.src, dense.own
    cab, rad = poly % n_c, radii[poly % n_c]
    m = len(p) // n_s                                  # points per state (the same in each)
    if m * n_s != len(p) or not np.all(src.reshape(n_s, m) - n * np.arange(n_s)[:, None] == src[:m]):
        raise ValueError("every state must split its elements into as many pieces as the first")
    # one state's layout: the points next to each centre (its own point,
    # the points inside its two elements) and the pieces inside them
    c0, own0 = src[:m], own[:m]
    # a piece: two consecutive points of one element (or an element's last
    # and its far end), never across centres left out (densify_many's keep)
    piece0 = np.r_[(poly[1:m] == poly[:m - 1]) & (c0[1:] - c0[:-1] <= 1), False]
    pt_c = np.concatenate([c0[own0], c0[~own0], c0[~own0] + 1])           # centre each point is next to
    pt_i = np.concatenate([np.flatnonzero(own0), np.flatnonzero(~own0), np.flatnonzero(~own0)])
    pc_c = np.concatenate([c0[piece0], c0[piece0] + 1])                  # centre each piece is next to
    pc_i = np.concatenate([np.flatnonzero(piece0)] * 2)

    def around(centres, of_c, of_i):
        """(which entry, item index) for the items next to each centre."""
        o = np.argsort(of_c, kind="stable")
        of_c, of_i = of_c[o], of_i[o]
        lo = np.searchsorted(of_c, centres, "left")
        cnt = np.searchsorted(of_c, centres, "right") - lo
        entry = np.repeat(np.arange(len(centres)), cnt)
        return entry, of_i[ranges(lo, cnt)]

    def product(ea, xa, eb, xb):
        """Every (x, y) with x from side a and y from side b of one entry."""
        oa, ob = np.argsort(ea, kind="stable"), np.argsort(eb, kind="stable")
        ea, xa, eb, xb = ea[oa], xa[oa], eb[ob], xb[ob]
        na = np.bincount(ea, minlength=len(ci))
        nb = np.bincount(eb, minlength=len(ci))
        fa, fb = np.cumsum(na) - na, np.cumsum(nb) - nb
        per = na * nb
        e = np.repeat(np.arange(len(ci)), per)
        r = within(per)
        return xa[fa[e] + r // np.maximum(nb[e], 1)], xb[fb[e] + r % np.maximum(nb[e], 1)]

    def tiled(x, y):
        """Unique (x, y) of one state, for every state."""
        key = np.unique(x * m + y)
        off = (m * np.arange(n_s))[:, None]
        return ((key // m)[None] + off).ravel(), ((key % m)[None] + off).ravel()

    ia, xa = around(ci, pt_c, pt_i)
    ib, xb = around(cj, pt_c, pt_i)
    x, y = product(ia, xa, ib, xb)
    lo, hi = tiled(np.minimum(x, y), np.maximum(x, y))
    keep = lo != hi
    lo, hi = lo[keep], hi[keep]
    same = cab[lo] == cab[hi]
    # a point against the midpoint of a piece not touching it
    pa, qa = around(ci, pc_c, pc_i)
    pb, qb = around(cj, pc_c, pc_i)
    q1, e1 = product(ia, xa, pb, qb)
    q2, e2 = product(ib, xb, pa, qa)
    q, e = tiled(np.r_[q1, q2], np.r_[e1, e2])
    keep = (cab[q] == cab[e]) & (q != e) & (q != e + 1)
    rows = point_pair_rows(p, s, cab, rad, self_pair_window(rad, clearance), clearance, clearance,
                           (lo[~same], hi[~same]), (lo[same], hi[same]), (q[keep], e[keep]))
    t, a, b, v, w, sb = ([] for _ in range(6))
    for kind, a_k, b_k, v_k, w_k, sb_k, rec in rows:
        o = slice(None) if rec is None else rec
        t.append(np.full(len(v_k[o]), TYPE_ORDER.index(kind)))
        for acc, x in zip((a, b, v, w, sb), (a_k, b_k, v_k, w_k, sb_k)):
            acc.append(x[o])
    t, a, b, v, w, sb = (np.concatenate(x) for x in (t, a, b, v, w, sb))
    return worst_records(n_s, w // m, t, a, b, v, p[w], s[w], sb, clearance, names, lambda _: names)



@settings(max_examples=40, deadline=None)
@given(cable_sets(max_cables=3, max_points=14), st.floats(0.0, 0.01), st.sampled_from([0.5, 2.0]))
def test_cable_cable_exact_alone_is_the_checks_own(cables, clearance, spacing):
    """cable_cable_exact (the second opinion on a pair of cables, no search
    along each cable) gives, bits and places included, the cable-cable
    records of Checker.check with method exact, on drawn random walks that
    fold and cross."""
    from cablecheck.checker.interference.pipeline import cable_cable_exact
    cfg = CheckConfig(method="exact", clearance=clearance, spacing=spacing)
    got = cable_cable_exact(cables, cfg)
    want = [r for r in Checker([], cfg).check(cables) if r.type == PairType.CABLE_CABLE]
    assert [(r.type, r.a, r.b, r.min_distance, r.s, r.s_b) for r in got] == \
        [(r.type, r.a, r.b, r.min_distance, r.s, r.s_b) for r in want]
    assert all(np.array_equal(a.where, b.where) for a, b in zip(got, want))


def _closest_elements_of_all_pairs(pa, pb, upper):
    """closest_elements as first written: every element pair's gap (element_gaps),
    the reference the pruned search must equal."""
    from cablecheck.checker.closest import segment_segment
    n_s = len(pa)
    gap = element_gaps(pa, pb)
    slack = 1e-9 * (1.0 + np.abs(pa).max(axis=(1, 2)) + np.abs(pb).max(axis=(1, 2)))
    k, ia, ib = np.nonzero(gap <= (upper + slack)[:, None, None])
    d, u, v, _, _ = segment_segment(pa[k, ia], pa[k, ia + 1], pb[k, ib], pb[k, ib + 1])
    best = np.full(n_s, np.inf)
    out = [np.zeros(n_s, np.int64), np.zeros(n_s, np.int64), np.zeros(n_s), np.zeros(n_s)]
    if len(k):
        o = np.lexsort((ib, ia, d, k))
        head = o[np.r_[True, k[o][1:] != k[o][:-1]]]
        best[k[head]] = d[head]
        for x, y in zip(out, (ia, ib, u, v)):
            x[k[head]] = y[head]
    return (best, *out)


@settings(max_examples=examples(80), deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(2, 40), st.integers(2, 40), st.integers(1, 6),
       st.sampled_from([1e-3, 1.0, 1e3]), st.sampled_from([0.0, 1e4]))
def test_closest_elements_pruned_are_those_of_every_pair(seed, na, nb, states, unit, far):
    """Drawn polylines (random walks crossing each other, many states, mm or m,
    far from the origin) and drawn limits, some at an element pair's exact
    gap, some none (inf): the swept search returns, to the bit, what comparing every
    element pair's bounding spheres returns."""
    rng = np.random.default_rng(seed)
    pa = far + unit * np.cumsum(rng.normal(size=(states, na, 3)), axis=1)
    pb = far + unit * np.cumsum(rng.normal(size=(states, nb, 3)), axis=1)
    pb[:, 0] = pa[:, na // 2]                                           # they meet somewhere
    if nb <= na and rng.random() < 0.5:                                 # or lie side by side
        pb = pa[:, :nb] + unit * rng.normal(scale=0.5, size=3)
    upper = unit * rng.uniform(0.0, 3.0, states)
    gaps = element_gaps(pa, pb)
    upper[0] = gaps[0].ravel()[rng.integers(0, gaps[0].size)]          # a limit right at a gap
    if states > 1:
        upper[-1] = np.inf                                              # no limit: every pair
    got = closest_elements(pa, pb, upper)
    want = _closest_elements_of_all_pairs(pa, pb, upper)
    for g, w in zip(got, want):
        assert np.array_equal(g, w)


@settings(max_examples=examples(40), deadline=None)
@given(seed=st.integers(0, 2**32 - 1), scale=st.sampled_from([1.0, 1e-3, 1e3]), far=st.sampled_from([0.0, 1e3]),
       limit=st.sampled_from([0.0, 0.3, -0.2]))
def test_pruning_keeps_every_point_pair_below_the_limit(seed, scale, far, limit):
    """The pruning test (rows_within) that spares computing a value for
    most candidate point pairs keeps every pair whose value (distance less
    both radii) is below the limit: drawn points in m and mm, a kilometre
    out, some pairs exactly at the limit, a negative limit; and it drops
    the pairs far beyond it."""
    from cablecheck.checker.closest import row_norm
    from cablecheck.checker.interference.broad import rows_within
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 80))
    p = far + rng.uniform(-1.0, 1.0, (n, 3)) * scale
    rad = rng.uniform(0.01, 0.2, n) * scale
    i, j = rng.integers(0, n, 300), rng.integers(0, n, 300)
    # some pairs at the limit exactly: j moved to distance limit + r_i + r_j from i
    d = rng.normal(size=(20, 3))
    d /= row_norm(d)[:, None]
    p[j[:20]] = p[i[:20]] + d * np.maximum(limit * scale + rad[i[:20]] + rad[j[:20]], 0.0)[:, None]
    lim = limit * scale
    keep = rows_within(p, i, j, lim + rad[i] + rad[j])
    ki, kj = i[keep], j[keep]
    kept = set(zip(ki.tolist(), kj.tolist()))
    below = row_norm(p[i] - p[j]) - rad[i] - rad[j] < lim
    assert {(a, b) for a, b, x in zip(i.tolist(), j.tolist(), below) if x} <= kept
    # (a reach below 0 is taken as its size: pruning only)
    reach = lim + rad[i] + rad[j]
    far_off = row_norm(p[i] - p[j]) > np.abs(reach) + 1e-6 * scale
    assert not ({(a, b) for a, b, x in zip(i.tolist(), j.tolist(), far_off) if x} & kept)
