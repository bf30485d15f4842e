"""Discrete points (cablecheck.checker.interference.discrete): the batched discretisation is each state's, bit for bit."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from strategies import cable_sets, coords

from cablecheck.checker.interference.discrete import densify_many, discretise, insert_at_material
from cablecheck.checker.scene_state import CableState, CheckConfig

pytestmark = pytest.mark.filterwarnings("error")


@settings(max_examples=40, deadline=None)
@given(cable_sets(max_cables=3), st.data())
def test_densify_many_is_each_states_discretisation(cables, data):
    """Every state's points, arc lengths and material coordinates, as the
    single-state discretisation gives them (rest coordinates: the first
    state's arc lengths, stretched by a drawn factor)."""
    cfg = CheckConfig(spacing=data.draw(st.floats(0.5, 3.0)))
    offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
    radii = np.array([c.radius for c in cables])
    base = np.concatenate([c.points for c in cables])
    states = base[None] + data.draw(coords((data.draw(st.integers(1, 3)), len(base), 3), -0.01, 0.01))
    rest = [np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(c.points, axis=0), axis=1))])
            * data.draw(st.floats(0.9, 1.1)) for c in cables]
    ok = [bool(np.all(np.diff(r) > 0)) for r in rest]
    rest_all = np.concatenate(rest) if all(ok) else None
    dense = densify_many(states, offsets, radii, cfg.spacing, rest_all)
    start = 0
    for x in states:
        now = [CableState(c.name, x[a:b], c.radius, rest_s=r if rest_all is not None else None)
               for c, a, b, r in zip(cables, offsets[:-1], offsets[1:], rest)]
        one = discretise(now, cfg, (np.zeros(0, np.int64), np.zeros(0)))
        stop = start + len(one.p)
        assert np.array_equal(dense.p[start:stop], one.p) and np.array_equal(dense.s[start:stop], one.s)
        assert np.array_equal(dense.m[start:stop], one.m)
        assert np.array_equal(dense.poly[start:stop] % len(cables), one.cable)
        start = stop
    assert start == len(dense.p)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0.001, 0.1), min_size=2, max_size=8), st.lists(st.floats(-0.05, 0.5), max_size=5))
def test_insert_at_material_puts_points_on_the_polyline(steps, cuts):
    """Points inserted at material coordinates lie on the polyline there; cuts
    outside the cable or on an existing point add nothing; order is kept. (A
    cut drawn twice is inserted twice: a zero-length element, as two
    exclusion windows sharing an end give.)"""
    s = np.concatenate([[0.0], np.cumsum(steps)])
    p = np.stack([s, np.sin(s * 20.0), np.zeros_like(s)], axis=1)       # bends: points off a straight line
    m = 2.0 * s                                                          # material runs twice as fast
    cable = np.zeros(len(s), np.int64)
    cut_m = np.asarray(cuts, float)
    p2, s2, m2, c2 = insert_at_material(p, s, m, cable, np.zeros(len(cut_m), np.int64), cut_m)
    fresh = cut_m[(cut_m > m[0]) & (cut_m < m[-1]) & ~np.isin(cut_m, m)]
    assert len(p2) == len(p) + len(fresh)
    assert np.all(np.diff(m2) >= 0) and np.all(c2 == 0) and np.all(np.isin(m, m2))
    for mm in fresh:
        k = int(np.flatnonzero(m2 == mm)[0])
        e = int(np.searchsorted(m, mm) - 1)
        u = (mm - m[e]) / (m[e + 1] - m[e])
        assert np.allclose(p2[k], p[e] + u * (p[e + 1] - p[e]), atol=1e-12)
        assert s2[k] == pytest.approx(s[e] + u * (s[e + 1] - s[e]), abs=1e-12)


def _records(found):
    return [[(r.type, r.a, r.b, r.min_distance, r.s, r.s_b, tuple(np.asarray(r.where))) for r in recs]
            for recs in found]


@pytest.mark.parametrize("seed", range(12))
def test_kept_centres_give_every_record_of_the_whole_discretisation(seed):
    """densify_many keeping only the active centres and their neighbours
    (around_centres): structure_many and cable_pairs_many return the same
    records, bit for bit, as on every centre's points (random cables, parts
    with a mesh, states moved a little, sparse random entries)."""
    from test_interference import random_scene

    from cablecheck.checker.interference import Checker
    from cablecheck.checker.interference.discrete import around_centres

    rng = np.random.default_rng(700 + seed)
    cables, parts = random_scene(seed, n_cables=4, n_parts=5)
    checker = Checker(parts, CheckConfig(clearance=0.02))
    offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
    n = int(offsets[-1])
    radii = np.array([c.radius for c in cables])
    base = np.concatenate([c.points for c in cables])
    states = base[None] + rng.normal(size=(int(rng.integers(1, 4)), n, 3)) * 1e-6
    poses = np.stack([[p.pose for p in parts]] * len(states))
    names = [c.name for c in cables]
    rest = np.concatenate([np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(c.points, axis=0), axis=1))] * 1.01
                           for c in cables])
    m = int(rng.integers(1, 6))
    part_entries = (rng.integers(0, n, m), rng.integers(0, len(parts), m))
    cable_entries = (rng.integers(0, n, m), rng.integers(0, n, m))
    whole = checker.densify_many(states, offsets, radii, rest)
    keep = around_centres(np.concatenate([part_entries[0], *cable_entries]), n)
    kept = checker.densify_many(states, offsets, radii, rest, keep)
    assert len(kept.p) <= len(whole.p)
    assert _records(checker.structure_many(names, radii, kept, poses, (), part_entries)) == \
        _records(checker.structure_many(names, radii, whole, poses, (), part_entries))
    assert _records(checker.cable_pairs_many(names, radii, kept, cable_entries)) == \
        _records(checker.cable_pairs_many(names, radii, whole, cable_entries))
