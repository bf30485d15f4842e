"""Cable discretisation, arc length, bend radius and the self-pair rule."""

import numpy as np
import pytest
from helpers import element_gaps, examples
from hypothesis import given, settings, strategies as st
from hypothesis.extra.numpy import arrays

from cablecheck.checker.cable import (
    arc_length,
    bend_radius,
    densify,
    densify_batch,
    resample,
    self_pair_excluded,
)

pytestmark = pytest.mark.filterwarnings("error")

polyline = arrays(np.float64, st.tuples(st.integers(2, 12), st.just(3)), elements=st.floats(-5, 5, allow_subnormal=False))


@settings(max_examples=150, deadline=None)
@given(polyline, st.floats(0.05, 3.0))
def test_resample_spacing_ends_and_on_polyline(p, l):
    pts, s = resample(p, l)
    total = arc_length(p)[-1]
    assert np.allclose(pts[0], p[0]) and np.allclose(pts[-1], p[-1])
    assert s[0] == 0 and s[-1] == pytest.approx(total)
    gaps = np.diff(s)
    assert np.all(gaps <= l * (1 + 1e-9)) and np.allclose(gaps, gaps[0])
    # Chords are never longer than the arc between the points.
    assert np.all(np.linalg.norm(np.diff(pts, axis=0), axis=1) <= gaps + 1e-9)


@settings(max_examples=150, deadline=None)
@given(polyline, st.floats(0.05, 3.0))
def test_densify_keeps_vertices_and_length(p, l):
    pts, s = densify(p, l)
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert np.all(steps <= l * (1 + 1e-9))
    assert s[-1] == pytest.approx(arc_length(p)[-1], rel=1e-12, abs=1e-12)
    assert np.allclose(np.diff(s), steps, atol=1e-9)
    # Every original point is still there, in order.
    hit = [np.nonzero(np.all(pts == q, axis=1))[0] for q in p]
    assert all(len(h) for h in hit)


def test_densify_batch_restarts_arc_length_per_cable():
    a = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    b = np.array([[5.0, 0, 0], [5.0, 2.0, 0]])
    pts, s, cab, off = densify_batch(np.concatenate([a, b]), np.array([0, 2, 4]), np.array([0.5, 1.0]))
    assert np.array_equal(cab, [0, 0, 0, 1, 1, 1]) and np.array_equal(off, [0, 3, 6])
    assert np.allclose(s, [0, 0.5, 1.0, 0, 1.0, 2.0])


def test_zero_length_cable():
    pts, s = resample(np.zeros((3, 3)), 0.1)
    assert len(pts) == 2 and np.all(s == 0)
    pts, s = densify(np.zeros((3, 3)), 0.1)
    assert len(pts) == 3 and np.all(s == 0)


def test_bend_radius_of_a_circle_and_of_straight_and_folded_runs():
    R = 0.3
    th = np.linspace(0, np.pi, 40)
    circle = np.stack([R * np.cos(th), R * np.sin(th), 0 * th], axis=1)
    r = bend_radius(circle)
    assert np.isinf(r[0]) and np.isinf(r[-1])
    assert np.allclose(r[1:-1], R, rtol=1e-9)
    straight = np.stack([np.linspace(0, 1, 5), np.zeros(5), np.zeros(5)], axis=1)
    assert np.all(np.isinf(bend_radius(straight)))
    folded = np.array([[0.0, 0, 0], [1.0, 0, 0], [0.0, 0, 0]])
    assert bend_radius(folded)[1] == 0.0
    repeated = np.array([[0.0, 0, 0], [0.0, 0, 0], [1.0, 0, 0]])
    assert np.isinf(bend_radius(repeated)[1])
    # Scale: mm gives 1000x.
    assert np.allclose(bend_radius(circle * 1000)[1:-1], 1000 * R, rtol=1e-9)


def test_self_pair_rule_at_pi_r():
    r = 0.004
    s = np.array([0.0, 2 * r, 3 * r, np.pi * r * (1 - 1e-9), np.pi * r, 4 * r])
    assert list(self_pair_excluded(0.0, s, r)) == [True, True, True, True, False, False]
    # The paper's spacing 2r: adjacent points excluded, two apart checked.
    k = np.arange(5)
    assert list(self_pair_excluded(0.0, 2 * r * k, r)) == [True, True, False, False, False]


def test_cable_measures_match_arc_length_and_bend_radius():
    """The run loop's fused pass gives the same bits as the per-cable functions."""
    from cablecheck.checker.cable import CableMeasures, arc_length, bend_radius
    rng = np.random.default_rng(0)
    for trial in range(100):
        counts = rng.integers(2, 30, rng.integers(1, 5))
        off = np.concatenate([[0], np.cumsum(counts)])
        pts = np.cumsum(rng.normal(size=(off[-1], 3)), 0)
        if trial % 3 == 0:   # a zero-length element
            k = int(rng.integers(1, len(pts)))
            pts[k] = pts[k - 1]
        if trial % 5 == 0:   # straight runs
            pts[:, 1:] = 0.0
        lengths, bend = CableMeasures(off)(pts)
        for c in range(len(counts)):
            p = pts[off[c]:off[c + 1]]
            assert lengths[c] == arc_length(p)[-1]
            assert bend[c] == np.min(bend_radius(p))


def test_cable_measures_many_states_same_bits():
    """Measuring S states at once equals measuring each state on its own."""
    from cablecheck.checker.cable import CableMeasures
    rng = np.random.default_rng(1)
    for trial in range(30):
        counts = rng.integers(2, 20, rng.integers(1, 4))
        off = np.concatenate([[0], np.cumsum(counts)])
        states = np.cumsum(rng.normal(size=(int(rng.integers(1, 9)), off[-1], 3)), 1)
        m = CableMeasures(off)
        lengths, bend = m.many(states)
        assert lengths.shape == bend.shape == (len(states), len(counts))
        for k, pts in enumerate(states):
            one_l, one_b = m(pts)
            assert np.array_equal(lengths[k], one_l) and np.array_equal(bend[k], one_b)


def test_arc_lengths_do_not_depend_on_the_polylines_batched_before():
    """densify_batch's arc lengths are each polyline's own (arc_length's bits),
    so checking many states at once gives the answers of checking each."""
    rng = np.random.default_rng(5)
    polys = [np.cumsum(rng.normal(size=(int(rng.integers(2, 12)), 3)) * 10 ** rng.uniform(-3, 3), 0)
             for _ in range(8)]
    off = np.concatenate([[0], np.cumsum([len(p) for p in polys])])
    _, s, cab, new_off = densify_batch(np.concatenate(polys), off, np.full(len(polys), np.inf))
    for c, p in enumerate(polys):
        assert np.array_equal(s[new_off[c]:new_off[c + 1]], arc_length(p))


@settings(max_examples=50, deadline=None)
@given(arrays(float, 6, elements=st.floats(0.0, 5.0)), st.floats(0.1, 2.0))
def test_element_pieces_is_densify_batchs_split(lengths, spacing):
    """element_pieces gives the number of pieces densify_batch cuts each
    element into (at least one, none longer than the spacing)."""
    from cablecheck.checker.cable import element_pieces
    pts = np.stack([np.concatenate([[0.0], np.cumsum(lengths)]), np.zeros(7), np.zeros(7)], axis=1)
    _, _, _, offsets, src, _, _ = densify_batch(pts, np.array([0, 7]), np.array([spacing]), source=True)
    made = np.bincount(src, minlength=7)[:-1]
    want = element_pieces(np.linalg.norm(np.diff(pts, axis=0), axis=1), spacing)
    assert np.array_equal(made, want) and np.all(want >= 1)
    assert np.all(np.linalg.norm(np.diff(pts, axis=0), axis=1) / want <= spacing * (1 + 1e-9))
    assert element_pieces(np.array([3.0]), np.inf)[0] == 1.0


def test_arc_lengths_of_many_polylines_and_element_gaps_against_brute_force():
    """arc_length of m polylines at once is each one's own, summed by hand;
    the reference element_gaps never exceeds two elements' distance, sampled densely."""
    from cablecheck.checker.cable import arc_length

    rng = np.random.default_rng(3)
    pa, pb = rng.normal(size=(4, 6, 3)), rng.normal(size=(4, 5, 3)) + 0.5
    s = arc_length(pa)
    for k in range(4):
        by_hand = [0.0]
        for i in range(5):
            by_hand.append(by_hand[-1] + float(np.sqrt(((pa[k, i + 1] - pa[k, i]) ** 2).sum())))
        assert np.allclose(s[k], by_hand, rtol=0, atol=1e-12)
        assert np.array_equal(s[k], arc_length(pa[k]))
    gaps = element_gaps(pa, pb)
    t = np.linspace(0.0, 1.0, 201)[:, None]
    for k in range(4):
        for i in range(5):
            for j in range(4):
                x = pa[k, i] + t * (pa[k, i + 1] - pa[k, i])
                y = pb[k, j] + t * (pb[k, j + 1] - pb[k, j])
                sampled = np.sqrt(((x[:, None] - y[None]) ** 2).sum(axis=2)).min()
                assert gaps[k, i, j] <= sampled + 1e-12


@settings(max_examples=examples(60), deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), na=st.integers(1, 30), nb=st.integers(1, 30), states=st.integers(1, 5),
       unit=st.sampled_from([1e-3, 1.0, 1e3]), far=st.sampled_from([0.0, 1e4]), self_pair=st.booleans())
def test_element_pairs_within_are_every_pairs_gaps_within_reach(seed, na, nb, states, unit, far, self_pair):
    """Drawn polylines (random walks, side by side, one against itself; mm
    or m, far out) and reaches (at a pair's gap exactly, negative, none):
    the swept pairs are those whose `element_gaps` gap (to the bit) lies
    within the reach (and its rounding margin), each once."""
    from cablecheck.checker.cable import element_pairs_within
    rng = np.random.default_rng(seed)
    pa = far + unit * np.cumsum(rng.normal(size=(states, na + 1, 3)), axis=1)
    pb = far + unit * np.cumsum(rng.normal(size=(states, nb + 1, 3)), axis=1)
    if self_pair:
        pb = pa
    elif nb <= na and rng.random() < 0.5:
        pb = pa[:, :nb + 1] + unit * rng.normal(scale=0.5, size=3)
    gaps = element_gaps(pa, pb)
    reach = unit * rng.uniform(-0.5, 3.0, states)
    reach[0] = gaps[0].ravel()[rng.integers(0, gaps[0].size)]
    if states > 1:
        reach[-1] = np.inf
    k, ia, ib, gap = element_pairs_within(pa, pb, reach)
    slack = 1e-9 * (1.0 + np.abs(pa).max(axis=(1, 2)) + np.abs(pb).max(axis=(1, 2)))
    want = set(zip(*np.nonzero(gaps <= (reach + slack)[:, None, None])))
    got = list(zip(k.tolist(), ia.tolist(), ib.tolist()))
    assert len(got) == len(set(got)) and set(got) == {tuple(int(x) for x in w) for w in want}
    np.testing.assert_array_equal(gap, gaps[k, ia, ib])


@settings(max_examples=examples(60), deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), unit=st.sampled_from([1e-3, 1.0]))
def test_an_element_keeps_its_rest_pieces_while_it_stretches_a_little(seed, unit):
    """Elements of drawn rest lengths (some at a multiple of the spacing,
    some just below one) stretched and relaxed by up to PIECES_STRETCH:
    each splits into the same number of pieces at every state, and no piece
    is ever longer than the spacing (the points' error bound); stretched
    further, an element gets the pieces its length needs."""
    from cablecheck.checker.cable import PIECES_STRETCH, densify_batch, rest_pieces
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 12))
    lim = 2.0 * unit
    rest_len = rng.uniform(0.3, 5.0, n - 1) * lim
    rest_len[0] = lim * int(rng.integers(1, 4))                        # a multiple of the spacing
    rest_len[-1] = lim * int(rng.integers(1, 4)) * (1 - 1e-9)          # just below one
    rest = np.r_[0.0, np.cumsum(rest_len)]
    least = rest_pieces(rest, np.array([0, n]), np.array([lim]))
    counts = []
    for factor in np.r_[rng.uniform(1.0 - 3 * PIECES_STRETCH, 1.0 + PIECES_STRETCH, 6), 1.0 + PIECES_STRETCH]:
        direction = rng.normal(size=(n - 1, 3))
        direction /= np.linalg.norm(direction, axis=1)[:, None]
        pts = np.r_[np.zeros((1, 3)), np.cumsum(direction * (rest_len * factor)[:, None], axis=0)]
        p, s, _, _, src, own, _ = densify_batch(pts, np.array([0, n]), np.array([lim]), source=True, least=least)
        counts.append(np.bincount(src[~own], minlength=n)[:-1] + 1)     # pieces per element
        assert np.diff(s).max() <= lim * (1 + 1e-9)
    assert all(np.array_equal(c, counts[0]) for c in counts)
    stretched = np.r_[np.zeros((1, 3)), np.cumsum(np.tile([[1.0, 0.0, 0.0]], (n - 1, 1)) * (rest_len * 1.5)[:, None],
                                                  axis=0)]
    p, s, _, _ = densify_batch(stretched, np.array([0, n]), np.array([lim]), least=least)
    assert np.diff(s).max() <= lim * (1 + 1e-9)
