"""Bounding-volume hierarchy: tree queries, OBB separating axes and box pairs against brute force."""

import numpy as np
from hypothesis import given, settings, strategies as st

from cablecheck.checker.bvh import (
    Assemblies,
    TriangleForest,
    aabb_pairs,
    box_corners,
    obb_overlap,
    prefix_hits,
)


def _rot(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def _obb_brute(c1, r1, h1, c2, r2, h2) -> bool:
    """Separated iff some of the 15 axes separates the projected corners (with rounding slack)."""
    k1 = box_corners(-h1[None], h1[None])[0] @ r1.T + c1
    k2 = box_corners(-h2[None], h2[None])[0] @ r2.T + c2
    axes = list(r1.T) + list(r2.T) + [np.cross(a, b) for a in r1.T for b in r2.T]
    for ax in axes:
        n = np.linalg.norm(ax)
        if n < 1e-9:
            continue
        p1, p2 = k1 @ (ax / n), k2 @ (ax / n)
        if p1.max() < p2.min() - 1e-9 or p2.max() < p1.min() - 1e-9:
            return False
    return True


@settings(max_examples=150)
@given(st.integers(0, 10**6))
def test_obb_overlap_matches_corner_projection(seed):
    rng = np.random.default_rng(seed)
    c1, c2 = rng.uniform(-2, 2, 3), rng.uniform(-2, 2, 3)
    r1, r2 = _rot(rng), _rot(rng)
    h1, h2 = rng.uniform(0.1, 1.5, 3), rng.uniform(0.1, 1.5, 3)
    got = obb_overlap(c1[None], r1[None], h1[None], c2[None], r2[None], h2[None])[0]
    assert got == _obb_brute(c1, r1, h1, c2, r2, h2)


def test_obb_overlap_of_a_batch_is_each_pair_alone():
    """Many pairs in one call answer as each pair alone (and as the corner projection)."""
    rng = np.random.default_rng(11)
    n = 200
    c1, c2 = rng.uniform(-2, 2, (n, 3)), rng.uniform(-2, 2, (n, 3))
    r1, r2 = np.stack([_rot(rng) for _ in range(n)]), np.stack([_rot(rng) for _ in range(n)])
    h1, h2 = rng.uniform(0.1, 1.5, (n, 3)), rng.uniform(0.1, 1.5, (n, 3))
    got = obb_overlap(c1, r1, h1, c2, r2, h2)
    alone = [obb_overlap(c1[k:k + 1], r1[k:k + 1], h1[k:k + 1], c2[k:k + 1], r2[k:k + 1], h2[k:k + 1])[0]
             for k in range(n)]
    assert got.tolist() == alone
    assert got.tolist() == [_obb_brute(c1[k], r1[k], h1[k], c2[k], r2[k], h2[k]) for k in range(n)]
    assert 0 < got.sum() < n


def test_touching_boxes_overlap():
    eye = np.eye(3)[None]
    h = np.ones((1, 3))
    assert obb_overlap(np.zeros((1, 3)), eye, h, np.array([[2.0, 0, 0]]), eye, h)[0]
    assert not obb_overlap(np.zeros((1, 3)), eye, h, np.array([[2.001, 0, 0]]), eye, h)[0]


def test_forest_query_matches_brute_force():
    rng = np.random.default_rng(3)
    lo = rng.uniform(-10, 10, (500, 3))
    hi = lo + rng.uniform(0, 1, (500, 3))
    part = np.repeat(np.arange(5), 100)
    forest = TriangleForest.build(lo, hi, part, 5)
    q_lo = rng.uniform(-10, 10, (40, 3))
    q_hi = q_lo + rng.uniform(0, 4, (40, 3))
    q_part = rng.integers(0, 5, 40)
    qi, ti = forest.query(q_part, q_lo, q_hi)
    got = set(zip(qi.tolist(), ti.tolist()))
    want = {(q, t) for q in range(40) for t in range(500)
            if part[t] == q_part[q] and np.all(lo[t] <= q_hi[q]) and np.all(q_lo[q] <= hi[t])}
    assert got == want


@settings(max_examples=60)
@given(st.lists(st.integers(0, 300), min_size=1, max_size=7), st.lists(st.integers(0, 6), min_size=1, max_size=12),
       st.integers(0, 2**32 - 1))
def test_tiled_forest_answers_as_brute_force_on_each_copy(counts, pick, seed):
    """Trees of parts with different triangle counts (so of different depths,
    laid out level by level across parts when built), tiled in any order with
    repeats: each copy's query answers what brute force gives that part's
    triangles, renumbered; every part's nodes form one block from its root."""
    rng = np.random.default_rng(seed)
    n = len(counts)
    idx = np.array([p % n for p in pick])
    part = np.repeat(np.arange(n), counts)
    lo = rng.uniform(-10, 10, (len(part), 3))
    hi = lo + rng.uniform(0, 1.5, (len(part), 3))
    forest = TriangleForest.build(lo, hi, part, n)
    for f in (forest, forest.tiled(idx)):
        live = np.flatnonzero(f.root >= 0)
        blocks = np.r_[f.root[live], len(f.left)]
        inner = f.left >= 0
        owner = np.repeat(live, np.diff(blocks))
        assert np.array_equal(blocks[:-1], np.sort(f.root[live]))
        assert np.all(owner[f.left[inner]] == owner[inner]) and np.all(f.right[inner] == f.left[inner] + 1)
    tiled = forest.tiled(idx)
    t_start = np.r_[0, np.cumsum(counts)]
    new_start = np.r_[0, np.cumsum(np.array(counts)[idx])]
    q = 50
    q_part = rng.integers(0, len(idx), q)
    q_lo = rng.uniform(-10, 10, (q, 3))
    q_hi = q_lo + rng.uniform(0, 6, (q, 3))
    qi, ti = tiled.query(q_part, q_lo, q_hi)
    got = set(zip(qi.tolist(), (ti - new_start[q_part[qi]]).tolist()))
    want = set()
    for k in range(q):
        p = idx[q_part[k]]
        rows = np.arange(t_start[p], t_start[p + 1])
        hit = np.all((lo[rows] <= q_hi[k]) & (q_lo[k] <= hi[rows]), axis=1)
        want |= {(k, int(t - t_start[p])) for t in rows[hit]}
    assert got == want
    assert np.array_equal(tiled.tri_lo, lo[np.concatenate([np.arange(t_start[p], t_start[p + 1]) for p in idx])])


def test_aabb_pairs_matches_brute_force():
    rng = np.random.default_rng(5)
    lo = rng.uniform(0, 20, (200, 3))
    hi = lo + rng.uniform(0, 2, (200, 3))
    i, j = aabb_pairs(lo, hi, 0.25)
    got = set(zip(i.tolist(), j.tolist()))
    want = {(a, b) for a in range(200) for b in range(a + 1, 200)
            if np.all(lo[a] - 0.25 <= hi[b] + 0.25) and np.all(lo[b] - 0.25 <= hi[a] + 0.25)}
    assert got == want


def test_assemblies_and_prefix_hits():
    asm = Assemblies.of(["frame/left/rail", "frame/right/rail", "bolt"])
    assert asm.names == ("frame", "frame/left", "frame/right")
    hit = np.array([True, False, True])
    assert prefix_hits(asm, hit).tolist() == [False, True, True]


@settings(max_examples=200)
@given(st.integers(0, 2**32 - 1))
def test_assembly_pairs_equal_sort_and_sweep(seed):
    from cablecheck.checker.bvh import assembly_boxes, assembly_pairs
    rng = np.random.default_rng(seed)
    n = int(rng.integers(0, 60))
    names = ["/".join([f"a{rng.integers(0, 3)}" for _ in range(rng.integers(0, 4))] + [f"p{k}"])
             for k in range(n)]
    lo = rng.uniform(0, 10, (n, 3))
    lo[::4, 0] = np.round(lo[::4, 0])          # ties and touching boxes
    hi = lo + rng.uniform(0, 2, (n, 3))
    hi[::3, 0] = np.round(hi[::3, 0] + 0.5)
    hi[::5, 1] = lo[::5, 1]
    live = rng.random(n) < 0.9
    asm = Assemblies.of(names)
    a_lo, a_hi = assembly_boxes(asm, lo, hi)
    margin = float(rng.choice([0.0, 0.3]))
    i, j = assembly_pairs(asm, lo, hi, a_lo, a_hi, live, margin)
    idx = np.flatnonzero(live)
    a, b = aabb_pairs(lo[idx], hi[idx], margin)
    got = list(zip(i.tolist(), j.tolist()))
    assert len(got) == len(set(got))
    assert set(got) == set(zip(idx[a].tolist(), idx[b].tolist()))
