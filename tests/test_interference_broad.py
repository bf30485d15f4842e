"""Broad phase (cablecheck.checker.interference.broad): chunk pairs and part candidates miss nothing a brute-force search finds."""

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st
from strategies import cable_sets, part_sets

from cablecheck.checker.interference.broad import CHUNK, Chunks, chunk_part_pairs
from cablecheck.checker.interference.discrete import discretise
from cablecheck.checker.interference.structure import PartTable
from cablecheck.checker.scene_state import CableState, CheckConfig

pytestmark = pytest.mark.filterwarnings("error")


def _chunks(cables):
    dp = discretise(cables, CheckConfig(), (np.zeros(0, np.int64), np.zeros(0)))
    has_next = np.r_[dp.cable[:-1] == dp.cable[1:], False]
    return dp, Chunks(dp.p, dp.s, dp.cable, has_next, np.arange(len(dp.p)))


@settings(max_examples=40, deadline=None)
@given(cable_sets(max_cables=3, max_points=12), st.floats(0.0, 0.05))
@example([CableState("c0", np.zeros((12, 3)), 0.002), CableState("c1", np.zeros((12, 3)), 0.002)], 5e-324)
def test_chunk_pairs_hold_every_close_point_pair(cables, reach):
    """Every pair of points nearer than ``reach`` whose chunks are neither the
    same nor neighbours on one cable lies in a chunk pair the tree returns."""
    dp, ch = _chunks(cables)
    chunk_of = np.full(len(dp.p), -1)
    rows, cols = np.nonzero(ch.idx >= 0)
    chunk_of[ch.idx[rows, cols]] = rows
    a, b = ch.pairs(reach)
    found = set(zip(a.tolist(), b.tolist()))
    d = np.linalg.norm(dp.p[:, None] - dp.p[None], axis=2)
    i, j = np.nonzero(d < reach)
    for x, y in zip(chunk_of[i], chunk_of[j]):
        x, y = min(x, y), max(x, y)
        if ch.cable[x] == ch.cable[y] and y - x <= 1:
            continue                                     # the near field's, not the tree's
        assert (x, y) in found


@settings(max_examples=40, deadline=None)
@given(cable_sets(max_cables=3, max_points=12), part_sets(max_parts=4), st.floats(0.0, 0.05))
def test_part_candidates_hold_every_point_near_a_part(cables, parts, margin):
    """Every point nearer than ``margin`` to a part's bounding sphere is a candidate for that part."""
    dp, ch = _chunks(cables)
    tab = PartTable(parts)
    items, pk = chunk_part_pairs(tab, ch, margin)
    found = set(zip(items.tolist(), pk.tolist()))
    centre = np.einsum("nij,nj->ni", tab.rot[tab.finite], tab.c_loc) + tab.trans[tab.finite]
    d = np.linalg.norm(dp.p[:, None] - centre[None], axis=2) - tab.half_diag[None] - margin
    for i, k in zip(*np.nonzero(d < 0)):
        assert (i, tab.finite[k]) in found
    assert ch.idx.shape[1] == CHUNK


@settings(max_examples=40, deadline=None)
@given(cable_sets(max_cables=3, max_points=12), part_sets(max_parts=4), st.floats(0.0, 0.05))
def test_box_cut_keeps_every_point_near_a_part_box(cables, parts, margin):
    """With ``box``, every point within ``margin`` of a part's own box (in the
    part's frame) is still a candidate for it, and no candidate is new."""
    dp, ch = _chunks(cables)
    tab = PartTable(parts)
    items, pk = chunk_part_pairs(tab, ch, margin, box=True)
    found = set(zip(items.tolist(), pk.tolist()))
    assert found <= set(zip(*(x.tolist() for x in chunk_part_pairs(tab, ch, margin))))
    for k in tab.finite:
        loc = (dp.p - tab.trans[k]) @ tab.rot[k]
        gap = np.maximum(np.maximum(tab.lo[k] - loc, loc - tab.hi[k]), 0.0)
        for i in np.flatnonzero(np.linalg.norm(gap, axis=1) < margin):
            assert (i, k) in found
