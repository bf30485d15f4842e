"""cablecheck.checker.interference.excused: each window's worst moment against a brute-force reference.

Random cables (polylines) in random states, boxes and spheres at random
poses, random windows: the reference samples every element of a window
densely and measures each sample to the part in closed form (a sphere's
centre distance less its radius; a box's clamped-point distance outside and
least face depth inside), so its least value is within half a sample
spacing of the true one (signed distance is 1-Lipschitz).
"""

from __future__ import annotations

import numpy as np
from helpers import examples
from hypothesis import given, settings, strategies as st

from cablecheck.checker.interference.excused import ExcusedLog
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import Exclusion, PartState
from cablecheck.checker.shapes import Shape, ShapeType

SAMPLES = 4001


def _box_sd(x: np.ndarray, half: np.ndarray) -> np.ndarray:
    q = np.abs(x) - half
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=-1)
    return outside + np.minimum(q.max(axis=-1), 0.0)


def _reference(shape: Shape, pose: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,) least signed distance of world segments a b (n, 3) to the placed shape, sampled."""
    u = np.linspace(0.0, 1.0, SAMPLES)
    x = a[:, None, :] + u[None, :, None] * (b - a)[:, None, :]
    loc = (x - pose[:3, 3]) @ pose[:3, :3]
    if shape.type is ShapeType.SPHERE:
        d = np.linalg.norm(loc, axis=-1) - shape.size[0]
    else:
        d = _box_sd(loc, shape.size)
    return d.min(axis=1)


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


@settings(max_examples=examples(40), deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_states=st.integers(1, 6), scale=st.sampled_from([1.0, 1e3]),
       far=st.sampled_from([0.0, 1e3]))
def test_each_windows_worst_is_the_sampled_least(seed, n_states, scale, far):
    rng = np.random.default_rng(seed)
    radius, clearance = 0.01 * scale, 0.05 * scale
    counts = rng.integers(3, 9, size=2)
    offsets = np.r_[0, np.cumsum(counts)]
    pts = far * scale + scale * np.cumsum(rng.normal(scale=0.05, size=(n_states, offsets[-1], 3)), axis=1)
    rest = np.concatenate([np.r_[0.0, np.cumsum(np.full(c - 1, 0.05 * scale))] for c in counts])
    shapes = [Shape(ShapeType.BOX, rng.uniform(0.01, 0.08, 3) * scale),
              Shape(ShapeType.SPHERE, np.array([rng.uniform(0.01, 0.08) * scale]))]
    parts = [PartState(f"p{k}", sh, np.eye(4), keepout=bool(k)) for k, sh in enumerate(shapes)]
    poses = np.tile(np.eye(4), (n_states, len(parts), 1, 1))
    for s in range(n_states):
        for k in range(len(parts)):
            near = pts[s, rng.integers(offsets[-1])]          # put the part near the cable
            poses[s, k, :3, :3] = _rotation(rng)
            poses[s, k, :3, 3] = near + rng.normal(scale=0.04 * scale, size=3)
    windows = []
    for j, name in enumerate(("a", "b")):
        for k in range(len(parts)):
            lo = float(rng.choice(rest[offsets[j]:offsets[j + 1]]))
            windows.append(Exclusion(name, f"p{k}", lo, lo + float(rng.integers(1, 4)) * 0.05 * scale,
                                     "start" if k == 0 else "clip 1"))
    times = 0.01 * np.arange(n_states)
    log = ExcusedLog(windows, parts, ["a", "b"], offsets, rest, np.array([radius, radius]), clearance)
    log.add(times, pts, poses)
    found = {(x.a, x.b, x.window): x for x in log.worst()}
    for e in windows:
        j, k = "ab".index(e.cable), int(e.part[1])
        first = np.arange(offsets[j], offsets[j + 1] - 1)
        mid = 0.5 * (rest[first] + rest[first + 1])
        first = first[(mid >= e.s_min) & (mid <= e.s_max)]
        per_state = np.array([_reference(shapes[k], poses[s, k], pts[s, first], pts[s, first + 1]).min()
                              if len(first) else np.inf for s in range(n_states)]) - radius
        tol = 1e-9 * scale + 0.5 * 0.2 * scale / (SAMPLES - 1)      # elements are < 0.2 * scale long
        x = found.get((e.cable, e.part, e.window))
        if per_state.min() < clearance - tol:
            assert x is not None
            assert per_state.min() - tol <= x.min_distance <= per_state.min() + 1e-9 * scale
            # the worst state is one at that distance, the first such
            s = int(round(x.t / 0.01))
            assert per_state[s] <= x.min_distance + tol and (per_state[:s] > x.min_distance - tol).all()
            assert x.type is (PairType.KEEPOUT if k else PairType.CABLE_STRUCTURE)
        elif per_state.min() > clearance + tol:
            assert x is None


def test_states_added_in_batches_give_the_same_worst():
    rng = np.random.default_rng(3)
    pts = np.cumsum(rng.normal(scale=0.05, size=(10, 8, 3)), axis=1)
    rest = np.r_[0.0, np.cumsum(np.full(7, 0.05))]
    parts = [PartState("p", Shape(ShapeType.SPHERE, np.array([0.05])), np.eye(4))]
    poses = np.tile(np.eye(4), (10, 1, 1, 1))
    poses[:, 0, :3, 3] = pts[:, 3] + rng.normal(scale=0.03, size=(10, 3))
    window = [Exclusion("c", "p", 0.0, 0.4, "end")]
    whole = ExcusedLog(window, parts, ["c"], np.array([0, 8]), rest, np.array([0.01]), 1.0)
    whole.add(np.arange(10) * 0.1, pts, poses)
    parts_ = ExcusedLog(window, parts, ["c"], np.array([0, 8]), rest, np.array([0.01]), 1.0)
    for lo, hi in ((0, 3), (3, 4), (4, 10)):
        parts_.add(np.arange(lo, hi) * 0.1, pts[lo:hi], poses[lo:hi])
    (a,), (b,) = whole.worst(), parts_.worst()
    assert (a.min_distance, a.t, a.s) == (b.min_distance, b.t, b.s) and np.array_equal(a.where, b.where)


def test_no_windows_no_work():
    log = ExcusedLog([], [], ["c"], np.array([0, 4]), np.zeros(4), np.array([0.01]), 0.005)
    assert not log
    log.add(np.zeros(1), np.zeros((1, 4, 3)), np.zeros((1, 0, 4, 4)))
    assert log.worst() == ()
