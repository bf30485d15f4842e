"""cablecheck.checker.interference.margins: closest approaches against references computed another way.

- Random cables (polylines) in random states among boxes and spheres at
  random poses, with random attachment windows: every state sampled, each
  pair's least distance against dense samples of every element measured in
  closed form (a sphere's centre distance less its radius; a box's clamped
  point outside, least face depth inside) and, for two cables, the least
  distance between dense samples of both. Signed distance is 1-Lipschitz,
  so the sampled reference is within half a sample spacing of the truth.
- A sphere passing a straight cable on a slant, sampled sparsely: the
  refinement finds the least over every state, in closed form.
- Windows, events and the per-cable summary.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from helpers import examples
from hypothesis import given, settings, strategies as st

from cablecheck.checker.interference.margins import Closest, MarginLog, per_cable, with_events
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import CheckConfig, Exclusion, PartState
from cablecheck.checker.shapes import Shape, ShapeType

SAMPLES = 801
EXACT = CheckConfig(method="exact", clearance=0.0)


def _box_sd(x: np.ndarray, half: np.ndarray) -> np.ndarray:
    q = np.abs(x) - half
    return np.linalg.norm(np.maximum(q, 0.0), axis=-1) + np.minimum(q.max(axis=-1), 0.0)


def _dense(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    u = np.linspace(0.0, 1.0, SAMPLES)
    return a[:, None, :] + u[None, :, None] * (b - a)[:, None, :]       # (n, SAMPLES, 3)


def _part_reference(shape: Shape, pose: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    loc = (_dense(a, b) - pose[:3, 3]) @ pose[:3, :3]
    d = np.linalg.norm(loc, axis=-1) - shape.size[0] if shape.type is ShapeType.SPHERE else _box_sd(loc, shape.size)
    return float(d.min()) if d.size else np.inf


def _cable_reference(a0, b0, a1, b1) -> float:
    x, y = _dense(a0, b0).reshape(-1, 3), _dense(a1, b1).reshape(-1, 3)
    d2 = (x * x).sum(1)[:, None] + (y * y).sum(1)[None, :] - 2.0 * x @ y.T
    return float(np.sqrt(max(d2.min(), 0.0)))


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


@settings(max_examples=examples(25), deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 3), st.integers(1, 3))
def test_every_pair_within_reach_matches_a_dense_reference(seed: int, n_cables: int, n_states: int):
    rng = np.random.default_rng(seed)
    counts = rng.integers(2, 7, n_cables)
    offsets = np.r_[0, np.cumsum(counts)]
    radii = rng.uniform(0.002, 0.01, n_cables)
    rest = np.concatenate([np.r_[0, np.cumsum(rng.uniform(0.02, 0.08, c - 1))] for c in counts])
    pts = rng.uniform(-0.1, 0.1, (n_states, offsets[-1], 3))
    shapes = [Shape(ShapeType.SPHERE, np.array([rng.uniform(0.01, 0.05)])),
              Shape(ShapeType.BOX, rng.uniform(0.005, 0.05, 3))]
    parts = [PartState(f"p{k}", s, np.eye(4), bool(k)) for k, s in enumerate(shapes)]
    poses = np.tile(np.eye(4), (n_states, len(parts), 1, 1))
    for s in range(n_states):
        for k in range(len(parts)):
            poses[s, k, :3, :3] = _rotation(rng)
            poses[s, k, :3, 3] = rng.uniform(-0.08, 0.08, 3)
    names = [f"c{j}" for j in range(n_cables)]
    windows = [Exclusion("c0", "p1", 0.0, float(rng.uniform(0.0, 0.1)), "start")]
    reach = float(rng.uniform(0.005, 0.05))
    log = MarginLog(parts, names, offsets, rest, radii, windows, reach, EXACT)
    log.add(np.arange(n_states) * 0.01, pts, poses, np.arange(n_states))
    got = {(c.a, c.b): c for c in log.closest()}
    expect: dict[tuple[str, str], float] = {}
    for j in range(n_cables):
        e = np.arange(offsets[j], offsets[j + 1] - 1)
        mid = 0.5 * (rest[e] + rest[e + 1])
        for k, part in enumerate(parts):
            keep = e[~((j == 0) & (k == 1) & (mid >= 0.0) & (mid <= windows[0].s_max))]
            ref = min(_part_reference(part.shape, poses[s, k], pts[s, keep], pts[s, keep + 1])
                      for s in range(n_states)) - radii[j]
            expect[(names[j], part.name)] = ref
        for i in range(j + 1, n_cables):
            f = np.arange(offsets[i], offsets[i + 1] - 1)
            ref = min(_cable_reference(pts[s, ea][None], pts[s, ea + 1][None], pts[s, fb][None], pts[s, fb + 1][None])
                      for s in range(n_states) for ea in e for fb in f) - radii[j] - radii[i]
            expect[(names[j], names[i])] = ref
    tol = 0.2 / (SAMPLES - 1)          # half a sample of the longest element (0.2 * sqrt 3 / 2 < 0.2)
    for key, ref in expect.items():
        if ref < reach - tol:
            assert key in got, key
            assert got[key].min_distance == pytest.approx(ref, abs=tol)
        elif ref > reach + tol:
            assert key not in got, key
    for c in got.values():        # each row's place is where it says
        assert c.min_distance < reach
        assert np.all(np.isfinite(c.where)) and np.isfinite(c.s)
        assert c.type in (PairType.CABLE_STRUCTURE, PairType.KEEPOUT, PairType.CABLE_CABLE)
        if c.b == "p1":
            assert c.type is PairType.KEEPOUT


@pytest.mark.parametrize("method", ["exact", "points"])
@pytest.mark.parametrize("every", [1, 7, 25])
def test_a_passing_sphere_is_found_at_its_nearest_state_between_sparse_samples(method: str, every: int):
    # a cable along x at the origin; a sphere of radius R crossing it on a
    # slant at height H: centre (x0 + u t, y0 + w t, H), distance to the
    # centreline sqrt(y^2 + H^2) while its x stays inside the cable
    R, H, r = 0.02, 0.05, 0.004
    x = np.linspace(-0.5, 0.5, 41)
    cable = np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=1)
    times = np.arange(300) * 0.002
    centre = np.stack([-0.1 + 0.3 * times, -0.2 + 0.9 * times, np.full_like(times, H)], axis=1)
    pts = np.repeat(cable[None], len(times), axis=0)
    poses = np.tile(np.eye(4), (len(times), 1, 1, 1))
    poses[:, 0, :3, 3] = centre
    parts = [PartState("ball", Shape(ShapeType.SPHERE, np.array([R])), np.eye(4), False)]
    log = MarginLog(parts, ["lead"], np.array([0, len(x)]), x + 0.5, np.array([r]), [], 0.1,
                    CheckConfig(method=method, spacing=2.0, clearance=0.0))
    for lo in range(0, len(times), 64):                                       # batches of 64 states
        sl = slice(lo, min(lo + 64, len(times)))
        n = len(times[sl])
        samples = np.union1d(np.arange(0, n, every), [0, n - 1])
        log.add(times[sl], pts[sl], poses[sl], samples)
    (c,) = log.closest()
    d = np.sqrt(centre[:, 1] ** 2 + H ** 2) - R - r
    k = int(np.argmin(d))
    # both methods meet the centreline's nearest point: it lies at a body
    # centre or a discrete point when the sphere is right above one; else
    # the points method may read up to (spacing / 2)^2 / (2 H) more
    assert c.t == pytest.approx(times[k])
    assert c.min_distance == pytest.approx(d[k], abs=1e-12 if method == "exact" else (2 * r) ** 2 / (8 * H))
    assert c.where[0] == pytest.approx(centre[k, 0], abs=1e-12 if method == "exact" else 2 * r)
    assert c.s == pytest.approx(centre[k, 0] + 0.5, abs=1e-12 if method == "exact" else 2 * r)


def test_an_element_inside_a_window_is_not_measured_against_its_part():
    x = np.linspace(0.0, 0.2, 5)
    pts = np.stack([x, np.zeros(5), np.zeros(5)], axis=1)[None]
    part = PartState("clamp", Shape(ShapeType.BOX, np.array([0.01, 0.01, 0.01])), np.eye(4), False)
    poses = np.eye(4)[None, None].copy()
    poses[0, 0, :3, 3] = [0.0, 0.0, 0.02]                     # over the first element
    win = [Exclusion("lead", "clamp", 0.0, 0.05, "start")]
    excused = MarginLog([part], ["lead"], np.array([0, 5]), x, np.array([0.002]), win, 0.1, EXACT)
    plain = MarginLog([part], ["lead"], np.array([0, 5]), x, np.array([0.002]), [], 0.1, EXACT)
    for log in (excused, plain):
        log.add(np.zeros(1), pts, poses, np.array([0]))
    assert plain.closest()[0].min_distance == pytest.approx(0.01 - 0.002)
    # the second element (0.05 - 0.1) is still measured: the box's corner region
    (c,) = excused.closest()
    assert c.s >= 0.05 and c.min_distance == pytest.approx(np.hypot(0.05 - 0.01, 0.01) - 0.002)


def test_events_nearer_than_the_samples_take_their_place_and_cables_read_their_nearest():
    near = Closest(PairType.CABLE_STRUCTURE, "a", "box", 0.004, 1.0, np.zeros(3), 0.1)
    pair = Closest(PairType.CABLE_CABLE, "a", "b", 0.006, 2.0, np.ones(3), 0.2, 0.7)
    event = SimpleNamespace(type="cable-structure", a="a", b="box", min_distance=-0.001, t_worst=1.5,
                            where=np.full(3, 2.0), s=0.3)
    bend = SimpleNamespace(type="bend", a="a", b="a", min_distance=-5.0, t_worst=0.0, where=np.zeros(3), s=0.0)
    rows = with_events([near, pair], [event, bend])
    assert [(c.a, c.b, c.min_distance, c.t) for c in rows] == [("a", "box", -0.001, 1.5), ("a", "b", 0.006, 2.0)]
    a, b, c = per_cable(rows, ["a", "b", "c"])
    assert (a.other, a.min_distance, a.s) == ("box", -0.001, 0.3)
    assert (b.other, b.min_distance, b.s) == ("a", 0.006, 0.7)        # b's own place along it
    assert c is None


def test_a_cable_pair_event_that_takes_the_place_keeps_both_cables_nearest():
    """Two cables whose event reads as near as the samples or nearer: the pair's row is the event's, and
    each cable still reads its nearest, the second at its own place along it (the event's `s_b`)."""
    pair = Closest(PairType.CABLE_CABLE, "a", "b", -0.0015, 0.058, np.ones(3), 0.15, 0.12)
    event = SimpleNamespace(type="cable-cable", a="a", b="b", min_distance=-0.0015, t_worst=0.122,
                            where=np.full(3, 2.0), s=0.151, s_b=0.121)
    (row,) = with_events([pair], [event])
    assert (row.t, row.s, row.s_b) == (0.122, 0.151, 0.121)
    a, b = per_cable([row], ["a", "b"])
    assert (a.other, a.s, b.other, b.s) == ("b", 0.151, "a", 0.121)
