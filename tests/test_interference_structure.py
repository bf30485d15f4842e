"""Cables against parts (cablecheck.checker.interference.structure): the batched pass is the single-state check's, bit for bit."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from strategies import cable_sets, coords, part_sets, poses
from test_interference import pose, random_scene, rot

from cablecheck.checker.interference import Checker
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import CableState, CheckConfig, Exclusion, PartState
from cablecheck.checker.shapes import Shape, ShapeType

pytestmark = pytest.mark.filterwarnings("error")


def test_structure_many_is_each_states_check():
    """structure_many over a run of states, every centre of some cables
    active for some parts: per state, exactly the full check's records of
    those pairs (values, places, bits)."""
    seen = 0
    for seed in range(25):
        rng = np.random.default_rng(100 + seed)
        cables, parts = random_scene(seed, n_cables=3, n_parts=5)
        cfg = CheckConfig(clearance=0.01)
        checker = Checker(parts, cfg)
        ex = [Exclusion(cables[1].name, parts[2].name, 0.01, 0.05)]
        n_s = int(rng.integers(1, 6))
        moves = [[c.points + rng.normal(size=c.points.shape) * 0.01 for c in cables] for _ in range(n_s)]
        poses = np.stack([[p.pose @ pose(rot(rng) if rng.random() < 0.5 else None, rng.normal(size=3) * 0.01)
                           for p in parts] for _ in range(n_s)])
        pc = rng.integers(0, 3, 4)
        pk = rng.integers(0, len(parts), 4)
        offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
        centres = np.concatenate([np.arange(offsets[c], offsets[c + 1]) for c in pc])
        owners = np.concatenate([np.full(offsets[c + 1] - offsets[c], k) for c, k in zip(pc, pk)])
        radii = np.array([c.radius for c in cables])
        dense = checker.densify_many(np.stack([np.concatenate(m) for m in moves]), offsets, radii)
        got = checker.structure_many([c.name for c in cables], radii, dense, poses, ex, (centres, owners))
        wanted = {(cables[c].name, parts[k].name) for c, k in zip(pc, pk)}
        for state, recs in zip(range(n_s), got):
            states = [CableState(c.name, m, c.radius) for c, m in zip(cables, moves[state])]
            full = checker.check(states, poses[state], ex)
            want = [r for r in full if (r.a, r.b) in wanted
                    and r.type in (PairType.CABLE_STRUCTURE, PairType.KEEPOUT)]
            assert [(r.type, r.a, r.b, r.min_distance, r.s, r.severity) for r in recs] == \
                [(r.type, r.a, r.b, r.min_distance, r.s, r.severity) for r in want]
            assert all(np.array_equal(a.where, b.where) for a, b in zip(recs, want))
            seen += len(want)
    assert seen > 10


def test_structure_many_evaluates_only_next_to_active_centres():
    """One active centre: the record is the worst over the points of its two
    elements (the caller knows the rest to be clear); elsewhere nothing is
    looked at."""
    box = PartState("box", Shape(ShapeType.BOX, [0.05, 0.05, 0.05]), pose())
    # along x, 0.1 above the box top except centre 4, 2 mm above it (r 1 mm: value 1 mm)
    pts = np.stack([np.linspace(-0.2, 0.2, 9), np.zeros(9), np.full(9, 0.15)], axis=1)
    pts[4, 2] = 0.052
    checker = Checker([box], CheckConfig(clearance=0.005))
    names, radii, off = ["c"], np.array([0.001]), np.array([0, 9])
    full = [r for r in checker.check([CableState("c", pts, 0.001)]) if r.type is PairType.CABLE_STRUCTURE]
    assert len(full) == 1 and abs(full[0].min_distance - 0.001) < 1e-12
    dense = checker.densify_many(pts[None], off, radii)
    got = checker.structure_many(names, radii, dense, np.eye(4)[None, None], (),
                                 (np.array([4]), np.array([0])))[0]
    assert [(r.min_distance, r.s) for r in got] == [(full[0].min_distance, full[0].s)]
    far = checker.structure_many(names, radii, dense, np.eye(4)[None, None], (),
                                 (np.array([0]), np.array([0])))[0]
    assert far == []                    # centre 0's elements stay 0.1 m above


@settings(max_examples=40, deadline=None)
@given(cable_sets(max_cables=3, max_points=10), part_sets(max_parts=4), st.data())
def test_structure_kernel_batched_equals_single_state(cables, parts, data):
    """point_values through structure_many (every centre active for every
    part, many states and poses at once) and through Checker.check (one
    state): the same cable-structure and keep-out records, bits and places
    included, on drawn cables, parts, moves and an exclusion window."""
    cfg = CheckConfig(clearance=data.draw(st.floats(0.0, 0.02)))
    checker = Checker(parts, cfg)
    lo = data.draw(st.floats(0.0, 0.05))
    ex = [Exclusion(cables[-1].name, parts[0].name, lo, lo + data.draw(st.floats(0.0, 0.05)))]
    n_s = data.draw(st.integers(1, 3))
    moves = [[c.points + data.draw(coords(c.points.shape, -0.01, 0.01)) for c in cables] for _ in range(n_s)]
    pose_sets = np.stack([[data.draw(poses()) @ p.pose if data.draw(st.booleans()) else p.pose for p in parts]
                          for _ in range(n_s)])
    offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
    centres = np.repeat(np.arange(offsets[-1]), len(parts))
    owners = np.tile(np.arange(len(parts)), offsets[-1])
    radii = np.array([c.radius for c in cables])
    dense = checker.densify_many(np.stack([np.concatenate(m) for m in moves]), offsets, radii)
    got = checker.structure_many([c.name for c in cables], radii, dense, pose_sets, ex, (centres, owners))
    for state, recs in enumerate(got):
        now = [CableState(c.name, m, c.radius) for c, m in zip(cables, moves[state])]
        want = [r for r in checker.check(now, pose_sets[state], ex)
                if r.type in (PairType.CABLE_STRUCTURE, PairType.KEEPOUT)]
        assert [(r.type, r.a, r.b, r.min_distance, r.s, r.severity) for r in recs] == \
            [(r.type, r.a, r.b, r.min_distance, r.s, r.severity) for r in want]
        assert all(np.array_equal(a.where, b.where) for a, b in zip(recs, want))


@settings(max_examples=100, deadline=None)
@given(st.data())
def test_active_points_is_the_dense_mask(data):
    """active_points' runs equal marking every (centre, part) entry in a
    dense parts x centres table and reading each point's own centre (and,
    inside an element, the next one): the same pairs, in the same order."""
    from cablecheck.checker.interference.structure import active_points

    cuts = data.draw(st.lists(st.integers(2, 5), min_size=1, max_size=3))      # centres per cable
    n = sum(cuts)
    n_s = data.draw(st.integers(1, 3))
    per = np.array(data.draw(st.lists(st.integers(0, 3), min_size=n, max_size=n)))  # inner points per centre
    per[np.cumsum(cuts) - 1] = 0                  # a cable's last centre starts no element
    src = np.repeat(np.arange(n_s * n), np.tile(per + 1, n_s))
    own = np.r_[True, src[1:] != src[:-1]]
    m = data.draw(st.integers(0, 20))
    ci = np.array(data.draw(st.lists(st.integers(0, n - 1), min_size=m, max_size=m)), np.int64)
    pi = np.array(data.draw(st.lists(st.integers(0, 6), min_size=m, max_size=m)), np.int64)
    it, k = active_points(src, own, ci, pi, n, n_s)
    centre = src % n
    parts = np.unique(pi)
    mark = np.zeros((len(parts), n + 1), bool)
    mark[np.searchsorted(parts, pi), ci] = True
    kk, want_it = np.nonzero(mark[:, centre] | (~own & mark[:, centre + 1]))
    assert np.array_equal(it, want_it) and np.array_equal(k, parts[kk])


def test_active_points_on_densified_states():
    """The same on real discrete points (densify_many of random cables, several states)."""
    from cablecheck.checker.interference.structure import active_points

    rng = np.random.default_rng(3)
    cables, parts = random_scene(4, n_cables=3, n_parts=5)
    checker = Checker(parts, CheckConfig(clearance=0.01))
    offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
    radii = np.array([c.radius for c in cables])
    pts = np.stack([np.concatenate([c.points for c in cables]) + rng.normal(size=(offsets[-1], 3)) * 0.01
                    for _ in range(4)])
    dense = checker.densify_many(pts, offsets, radii)
    n = offsets[-1]
    ci, pi = rng.integers(0, n, 30), rng.integers(0, len(parts), 30)
    it, k = active_points(dense.src, dense.own, ci, pi, n, 4)
    parts_u = np.unique(pi)
    mark = np.zeros((len(parts_u), n + 1), bool)
    mark[np.searchsorted(parts_u, pi), ci] = True
    centre = dense.src % n
    kk, want_it = np.nonzero(mark[:, centre] | (~dense.own & mark[:, centre + 1]))
    assert len(want_it) and np.array_equal(it, want_it) and np.array_equal(k, parts_u[kk])


@settings(max_examples=60, deadline=None)
@given(cable_sets(max_cables=3, max_points=10), part_sets(max_parts=4), st.data())
def test_near_entries_drop_only_entries_no_point_of_which_passes_the_box(cables, parts, data):
    """near_entries against brute force: every (state, centre, part) entry
    it drops has no discrete point (of every state's full densification)
    inside the part's local box grown by the cable radius and the
    clearance; and structure_many on the entries it keeps, with the
    points of their elements alone, gives every state's records of all
    the entries, bits and places included."""
    from cablecheck.checker.interference.discrete import around_centres
    from cablecheck.checker.interference.structure import active_points

    cfg = CheckConfig(clearance=data.draw(st.floats(0.0, 0.02)))
    checker = Checker(parts, cfg)
    n_s = data.draw(st.integers(1, 3))
    moves = np.stack([np.concatenate([c.points + data.draw(coords(c.points.shape, -0.02, 0.02)) for c in cables])
                      for _ in range(n_s)])
    pose_sets = np.stack([[data.draw(poses()) @ p.pose if data.draw(st.booleans()) else p.pose for p in parts]
                          for _ in range(n_s)])
    offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
    radii = np.array([c.radius for c in cables])
    n = offsets[-1]
    centres = np.repeat(np.arange(n), len(parts))
    owners = np.tile(np.arange(len(parts)), n)
    si, ci, pi = checker.near_entries(moves, pose_sets, offsets, radii, (centres, owners))
    kept = set(zip(si.tolist(), ci.tolist(), pi.tolist()))
    # brute force: every point of every entry in the part's frame against its grown box
    dense = checker.densify_many(moves, offsets, radii)
    it, k = active_points(dense.src, dense.own, centres, owners, n, n_s)
    state, cab = dense.poly[it] // len(cables), dense.poly[it] % len(cables)
    pose = pose_sets[state, k]
    loc = np.einsum("ni,nij->nj", dense.p[it] - pose[:, :3, 3], pose[:, :3, :3])
    lo, hi = checker.part_bounds()
    thr = (radii[cab] + cfg.clearance)[:, None]
    inside = ((loc >= lo[k] - thr) & (loc <= hi[k] + thr)).all(axis=1)
    # an inside point belongs to its own centre's entry, or inside an element to the far centre's
    centre = dense.src[it] % n
    for j in np.flatnonzero(inside):
        s_, c_, k_ = int(state[j]), int(centre[j]), int(k[j])
        assert (s_, c_, k_) in kept or (not dense.own[it[j]] and (s_, c_ + 1, k_) in kept)
    # the records of the kept entries, with the points of their elements alone
    keep = around_centres(ci, n, si, n_s)
    names = [c.name for c in cables]
    if len(si):
        got = checker.structure_many(names, radii, checker.densify_many(moves, offsets, radii, None, keep),
                                     pose_sets, [], (si, ci, pi))
    else:
        got = [[] for _ in range(n_s)]
    want = checker.structure_many(names, radii, dense, pose_sets, [], (centres, owners))
    for g, w in zip(got, want):
        assert [(r.type, r.a, r.b, r.min_distance, r.s) for r in g] == [(r.type, r.a, r.b, r.min_distance, r.s)
                                                                        for r in w]
        assert all(np.array_equal(a.where, b.where) for a, b in zip(g, w))
    assert around_centres(ci, n).sum() >= len(np.unique(ci))
    # per state, each state's rows are the mask of its own centres alone
    for st_ in range(n_s):
        assert np.array_equal(keep[st_], around_centres(ci[si == st_], n))


def test_near_entries_keep_a_centre_whose_element_alone_comes_near():
    """A cable passing a box: the centres away from it are kept only while
    one of their two elements reaches the grown box (its points might
    pass), the far ones dropped; turning the box away drops them all."""
    box = PartState("box", Shape(ShapeType.BOX, [0.05, 0.05, 0.05]), pose())
    xs = np.linspace(-0.3, 0.3, 7)                           # 100 mm elements
    pts = np.stack([xs, np.zeros(7), np.full(7, 0.058)], axis=1)
    checker = Checker([box], CheckConfig(clearance=0.005))
    r = 0.002                                                # grown box: 7 mm past the part's
    entries = (np.arange(7), np.zeros(7, np.int64))
    off, radii = np.array([0, 7]), np.array([r])
    si, ci, _ = checker.near_entries(pts[None], np.eye(4)[None, None], off, radii, entries)
    assert len(si) == 0                                      # 8 mm above: farther than r + clearance (7 mm)
    pts[:, 2] = 0.056                                        # 6 mm above: within 7 mm
    si, ci, _ = checker.near_entries(pts[None], np.eye(4)[None, None], off, radii, entries)
    # centre 3 lies over the box (|x| <= 57 mm), 2 and 4 (x -+100 mm) only
    # through their element towards it, 1 and 5 not at all
    assert ci.tolist() == [2, 3, 4]
    away = pose(t=(0.0, 0.0, -0.5))
    si, ci, _ = checker.near_entries(pts[None], away[None, None], off, radii, entries)
    assert len(si) == 0


def test_a_tables_rows_are_the_table_of_those_parts():
    """PartTable.rows(idx): the same arrays, to the bit, as the table built
    from the parts in that order (a part repeated, a plane and a mesh among
    them), without building it again."""
    import trimesh

    from cablecheck.checker.interference.structure import PartTable
    from cablecheck.checker.shapes import mesh_shape
    box = trimesh.creation.box(extents=[4.0, 6.0, 8.0])
    rng = np.random.default_rng(3)
    parts = [PartState("ball", Shape(ShapeType.SPHERE, [3.0]), pose(rot(rng), (1.0, 2.0, 3.0))),
             PartState("floor", Shape(ShapeType.PLANE, [0.0, 0.0, 0.0]), pose(None, (0.0, 0.0, -5.0))),
             PartState("mesh", mesh_shape(box.vertices, box.faces), pose(rot(rng), (7.0, -1.0, 2.0))),
             PartState("zone", Shape(ShapeType.CAPSULE, [1.5, 4.0]), pose(rot(rng), (0.0, 3.0, 0.0)), keepout=True)]
    idx = np.array([2, 0, 0, 3, 1, 2, 3])
    got, want = PartTable(parts).rows(idx), PartTable([parts[k] for k in idx])
    for name in ("size", "type", "lo", "hi", "keepout", "is_plane", "finite", "planes", "c_loc", "half_diag",
                 "rot", "trans"):
        assert np.array_equal(getattr(got, name), getattr(want, name)), name
    assert got.names == want.names and [p.name for p in got.parts] == [p.name for p in want.parts]
    assert (got.mesh_group >= 0).tolist() == (want.mesh_group >= 0).tolist()
    assert all(got.mesh_shapes[g] is want.mesh_shapes[h] for g, h in zip(got.mesh_group, want.mesh_group) if g >= 0)
