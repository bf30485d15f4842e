"""cablecheck.checker.wear: contact time, sliding and bending cycles per arc-length bin."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from helpers import examples

from cablecheck.checker.records import Interference, PairType, Severity
from cablecheck.checker.scene_state import Exclusion
from cablecheck.checker.shapes import Shape, ShapeType
from cablecheck.checker.wear import REVERSAL_STRAIN, WearMap, curvature_vectors

R = 0.01          # cable radius, m
CLEAR = 0.005     # clearance, m
N = 21            # body centres along 1 m


def _lying_cable(shift: float) -> np.ndarray:
    """Flat on the plate (top at z = 0) for x in [0, 0.5], rising at 45 degrees after."""
    x = np.linspace(0.0, 1.0, N)
    z = R + np.maximum(x - 0.5, 0.0)
    return np.stack([x + shift, np.zeros(N), z], axis=1)


def _pose(offset) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, 3] = offset
    return pose


def _record(a: str, b: str, kind=PairType.CABLE_STRUCTURE) -> Interference:
    return Interference(kind, a, b, 0.0, Severity.SOFT, np.zeros(3), 0.0)


def _plate_run(plate_moves: bool, steps: int = 50, duration: float = 1.0, travel: float = 0.2,
               exclusions=()) -> WearMap:
    plate = Shape(ShapeType.BOX, np.array([2.0, 0.5, 0.01]))
    rest_s = np.linspace(0.0, 1.0, N)
    wear = WearMap(["c"], [rest_s], [R], [("plate", plate)], CLEAR, exclusions)
    for k in range(steps + 1):
        t = duration * k / steps
        shift = travel * t / duration
        poses = _pose([shift if plate_moves else 0.0, 0.0, -0.01])[None]
        wear.update(t, [_lying_cable(shift)], poses, [_record("c", "plate")])
    return wear


def test_cable_lying_on_a_plate_and_sliding_wears_only_where_it_touches():
    """The flat half touches (the element leaving the plate touches at its
    lower end); it slides the whole travel for the whole time; the raised
    half does not touch and does not slide."""
    w = _plate_run(plate_moves=False).result()[0]
    touching = np.arange(N - 1) <= 10
    np.testing.assert_allclose(w.contact_time[touching], 1.0, atol=1e-12)
    np.testing.assert_allclose(w.sliding[touching], 0.2, rtol=1e-9)
    assert not w.contact_time[~touching].any() and not w.sliding[~touching].any()
    assert set(w.touches[i] for i in np.flatnonzero(touching)) == {"plate"}
    assert all(w.touches[i] is None for i in np.flatnonzero(~touching))
    np.testing.assert_allclose(w.s, np.linspace(0.0, 1.0, N)[:-1])
    assert w.most_worn() in range(11)   # all slid alike (to rounding)


def test_a_plate_carrying_the_cable_along_is_contact_without_sliding():
    w = _plate_run(plate_moves=True).result()[0]
    assert (w.contact_time[:11] == pytest.approx(1.0))
    assert np.abs(w.sliding).max() < 1e-12


def test_an_attachment_window_is_no_contact():
    w = _plate_run(False, exclusions=[Exclusion("c", "plate", 0.0, 0.26)]).result()[0]
    mid = 0.5 * (np.linspace(0, 1, N)[1:] + np.linspace(0, 1, N)[:-1])
    held = mid <= 0.26
    assert not w.contact_time[held].any()
    assert (w.contact_time[~held][: 11 - held.sum()] == pytest.approx(1.0))


def test_no_records_no_wear():
    plate = Shape(ShapeType.BOX, np.array([2.0, 0.5, 0.01]))
    wear = WearMap(["c"], [np.linspace(0, 1, N)], [R], [("plate", plate)], CLEAR)
    for k in range(5):
        wear.update(0.1 * k, [_lying_cable(0.01 * k)], _pose([0, 0, -0.01])[None], [])
    w = wear.result()[0]
    assert not w.contact_time.any() and not w.sliding.any() and w.most_worn() is None


def test_sliding_is_tangential_only():
    """A cable pressed down into the plate and lifted again (normal motion) does not slide."""
    plate = Shape(ShapeType.BOX, np.array([2.0, 0.5, 0.01]))
    wear = WearMap(["c"], [np.linspace(0, 1, N)], [R], [("plate", plate)], CLEAR)
    for k in range(20):
        pts = _lying_cable(0.0)
        pts[:, 2] += 0.002 * np.sin(k)
        wear.update(0.05 * k, [pts], _pose([0, 0, -0.01])[None], [_record("c", "plate")])
    w = wear.result()[0]
    assert w.contact_time[0] > 0.9 and w.sliding.max() < 1e-12


def test_two_crossing_cables_slide_against_each_other_at_the_crossing():
    """Cable b slides along x over cable a at the crossing: only the elements
    at the crossing touch, both slide the travel."""
    x = np.linspace(-0.5, 0.5, N)
    a = np.stack([x, np.zeros(N), np.zeros(N)], axis=1)
    wear = WearMap(["a", "b"], [x + 0.5, x + 0.5], [R, R], [], CLEAR)
    steps, travel = 20, 0.01
    for k in range(steps + 1):
        b = np.stack([np.full(N, travel * k / steps + 1e-3), x, np.full(N, 2 * R)], axis=1)
        wear.update(k / steps, [a, b], np.zeros((0, 4, 4)),
                    [_record("a", "b", PairType.CABLE_CABLE)])
    wa, wb = wear.result()
    # the crossing sits at x = 0 on a and y = 0 on b: the elements around s = 0.5
    for w in (wa, wb):
        hit = np.flatnonzero(w.contact_time > 0)
        assert set(hit) <= {9, 10} and len(hit) >= 1
        assert w.touches[hit[0]] in ("a", "b")
    assert wa.sliding.max() == pytest.approx(travel, rel=1e-6)
    assert wb.sliding[wb.contact_time > 0].max() <= travel + 1e-12


def test_curvature_of_a_circle_is_one_over_its_radius():
    rho = 0.3
    th = np.linspace(0, 1.0, 40)
    pts = np.stack([rho * np.cos(th), rho * np.sin(th), np.zeros_like(th)], axis=1)
    k = curvature_vectors(pts)
    # 2 tan(phi/2) / edge length against 1 / rho: equal to second order in the angle
    np.testing.assert_allclose(np.linalg.norm(k[1:-1], axis=1), 1 / rho, rtol=1e-3)
    np.testing.assert_allclose(k[1:-1, 2], 1 / rho, rtol=1e-3)   # counter-clockwise: +z
    assert not k[0].any() and not k[-1].any()
    assert not curvature_vectors(np.zeros((5, 3))).any()          # degenerate: zero, no NaN


def _bent(kappa: float) -> np.ndarray:
    """A 1 m polyline bent to a constant curvature kappa in the xz plane."""
    s = np.linspace(0.0, 1.0, N)
    if abs(kappa) < 1e-12:
        return np.stack([s, np.zeros(N), np.zeros(N)], axis=1)
    return np.stack([np.sin(kappa * s) / kappa, np.zeros(N), (1 - np.cos(kappa * s)) / kappa], axis=1)


@pytest.mark.parametrize("periods", [1, 3])
def test_bending_back_and_forth_counts_cycles(periods: int):
    wear = WearMap(["c"], [np.linspace(0, 1, N)], [R], [], CLEAR)
    steps = 40 * periods
    amplitude = 20 * REVERSAL_STRAIN / R
    for k in range(steps + 1):
        wear.update(k / 40, [_bent(amplitude * np.sin(2 * np.pi * k / 40))], np.zeros((0, 4, 4)), [])
    w = wear.result()[0]
    np.testing.assert_allclose(w.bend_cycles, periods)


def test_wiggles_below_the_reversal_strain_are_no_cycles():
    wear = WearMap(["c"], [np.linspace(0, 1, N)], [R], [], CLEAR)
    base = 50 * REVERSAL_STRAIN / R
    for k in range(200):
        wear.update(k / 40, [_bent(base + 0.4 * REVERSAL_STRAIN / R * np.sin(k))], np.zeros((0, 4, 4)), [])
    assert not wear.result()[0].bend_cycles.any()


def test_a_cable_on_a_floor_plane_far_from_the_origin_in_mm():
    """A plane (infinite bounds), a scene 10 km out: the same answers, no warnings."""
    import warnings

    plane = Shape(ShapeType.PLANE, np.zeros(3))
    far = np.array([1e4, -2e4, 0.0])
    wear = WearMap(["c"], [np.linspace(0, 1, N)], [R], [("floor", plane)], CLEAR)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for k in range(11):
            wear.update(0.1 * k, [_lying_cable(0.02 * k) + far], _pose(far)[None], [_record("c", "floor")])
    w = wear.result()[0]
    np.testing.assert_allclose(w.contact_time[:11], 1.0, atol=1e-9)
    np.testing.assert_allclose(w.sliding[:11], 0.2, rtol=1e-6)
    assert not w.contact_time[11:].any()


def test_self_contact_follows_the_checkers_self_rule():
    """A hairpin (radius 4 mm, clearance 5 mm) whose legs open at 30 degrees
    past a bend of 5 mm: its only self contact lies just past the self
    window's edge (pi r + clearance along the cable). The elements in
    contact for one second are exactly those that, by an every-pair
    reference of the rule (the least distance over two elements' places at
    least the window apart, test_closest.seg_seg_apart_ref), come within the
    clearance of another; none else."""
    from test_closest import seg_seg_apart_ref
    r, clear = 0.004, 0.005
    th = np.radians(30.0)
    bend = np.linspace(np.pi, 0.0, 9)
    arc = np.stack([0.005 * np.cos(bend), 0.06 + 0.005 * np.sin(bend), np.zeros(9)], 1)
    down = np.array([-np.sin(th), -np.cos(th), 0.0])
    pts = np.concatenate([[arc[0] + down * k * 0.01 for k in range(6, 0, -1)], arc,
                          [arc[-1] + down * [-1, 1, 1] * k * 0.01 for k in range(1, 7)]])
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))]
    w = np.pi * r + clear
    n = len(pts) - 1
    want = np.zeros(n, bool)
    for i in range(n):
        for j in range(i + 1, n):
            if seg_seg_apart_ref(pts[i], pts[i + 1], pts[j], pts[j + 1], s[i], s[i + 1], s[j], s[j + 1], w) \
                    < 2 * r + clear:
                want[i] = want[j] = True
    assert 0 < want.sum() < n
    wear = WearMap(["c"], [s], [r], [], clear)
    for k in range(11):
        wear.update(0.1 * k, [pts], np.zeros((0, 4, 4)), [_record("c", "c", PairType.SELF)])
    got = wear.result()[0].contact_time
    np.testing.assert_allclose(got[want], 1.0, atol=1e-12)
    assert not got[~want].any()


def _reference_wear(names, rest_s, radii, parts, clearance, exclusions, steps):
    """Contact time, sliding and time against each partner per element, by a
    plain loop over steps, named pairs and elements, each element measured
    against its part alone (the module's rules: exact for a primitive, the
    least of a mesh element's ends and middle; slip tangential to the part
    at the element's nearest place)."""
    from cablecheck.checker.shapes import segment_signed_distance, signed_distance

    shapes = dict(parts)
    offsets = np.r_[0, np.cumsum([len(s) for s in rest_s])]
    contact = [np.zeros(len(s) - 1) for s in rest_s]
    sliding = [np.zeros(len(s) - 1) for s in rest_s]
    partner = [{} for _ in rest_s]
    before = [np.zeros(len(s) - 1, bool) for s in rest_s]
    prev = None
    for t, pts, poses, recs in steps:
        if prev is None:
            prev = (t, pts, poses)
        t0, p0, q0 = prev
        dt = t - t0
        touch = [np.zeros(len(s) - 1, bool) for s in rest_s]
        slide = [np.zeros(len(s) - 1) for s in rest_s]
        for ci, name in {(names.index(r.a), r.b) for r in recs}:
            k = [n for n, _ in parts].index(name)
            shape = shapes[name]
            for j in range(len(rest_s[ci]) - 1):
                mid = 0.5 * (rest_s[ci][j] + rest_s[ci][j + 1])
                if any(e.cable == names[ci] and e.part == name and e.s_min <= mid <= e.s_max for e in exclusions):
                    continue
                # R^T (x - o) written as the module writes it: a deepest place inside a solid lies on
                # its medial surface, where the nearest surface point (the slip's normal) flips with
                # the last bit of the place
                to_local = lambda x, q: np.einsum("ni,nij->nj", (x - q[:3, 3])[None], q[None, :3, :3])[0]
                a, b = (to_local(pts[offsets[ci] + j + d], poses[k]) for d in (0, 1))
                if shape.type is ShapeType.MESH:
                    ds = signed_distance(shape, np.array([a, 0.5 * (a + b), b]))[0]
                    d, u = ds.min(), 0.5 * np.argmin(ds)
                else:
                    d, u = (v[0] for v in segment_signed_distance(shape, a[None], b[None]))
                if d - radii[ci] >= clearance:
                    continue
                touch[ci][j] = True
                partner[ci][name] = partner[ci].get(name, np.zeros(len(rest_s[ci]) - 1))
                partner[ci][name][j] += dt
                pa, pb = (to_local(p0[offsets[ci] + j + d], q0[k]) for d in (0, 1))
                now, then = a + u * (b - a), pa + u * (pb - pa)
                normal = now - signed_distance(shape, now[None])[1][0]
                move = now - then
                if np.linalg.norm(normal) > 0:
                    unit = normal / np.linalg.norm(normal)
                    move = move - (move @ unit) * unit
                slide[ci][j] = max(slide[ci][j], np.linalg.norm(move))
        for ci in range(len(rest_s)):
            contact[ci] += dt * touch[ci]
            sliding[ci] += np.where(touch[ci] & before[ci], slide[ci], 0.0)
            before[ci] = touch[ci]
        prev = (t, pts, poses)
    return contact, sliding, partner


@settings(max_examples=examples(6), deadline=None)           # about 0.3 s a draw: the reference is a plain loop
@given(seed=st.integers(0, 2 ** 32 - 1), batched=st.booleans())
def test_many_pairs_at_once_are_each_pair_measured_alone(seed, batched):
    """Cables among parts of every kind (a mesh too) that turn and slide,
    records naming changing sets of pairs, an attachment window: contact
    time, sliding and each partner's time, element by element, as a plain
    loop over the pairs and elements finds them, whether the steps come one
    at a time or in one batch."""
    import trimesh

    from cablecheck.checker.shapes import mesh_shape

    rng = np.random.default_rng(seed)
    box_mesh = trimesh.creation.box((0.04, 0.03, 0.02))
    shapes = [Shape(ShapeType.BOX, rng.uniform(0.01, 0.03, 3)), Shape(ShapeType.SPHERE, rng.uniform(0.01, 0.03, 3)),
              Shape(ShapeType.CAPSULE, rng.uniform(0.01, 0.03, 3)), Shape(ShapeType.CYLINDER, rng.uniform(0.01, 0.03, 3)),
              Shape(ShapeType.ELLIPSOID, rng.uniform(0.01, 0.03, 3)), Shape(ShapeType.PLANE, np.zeros(3)),
              mesh_shape(np.asarray(box_mesh.vertices), np.asarray(box_mesh.faces))]
    parts = [(f"p{k}", sh) for k, sh in enumerate(shapes)]
    names = ["a", "b", "c"]
    counts = rng.integers(4, 9, len(names))
    rest_s = [np.linspace(0.0, 0.2, n) for n in counts]
    radii = rng.uniform(0.003, 0.01, len(names))
    clearance = 0.004
    exclusions = [Exclusion("b", "p0", 0.0, 0.08)]

    def pose(k, t):
        q = np.eye(4)
        ang = 0.3 * k + 2.0 * t
        c, s = np.cos(ang), np.sin(ang)
        q[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
        q[:3, 3] = [0.03 * np.sin(k + 3 * t), 0.02 * k - 0.06, -0.01 if k == 5 else 0.0]
        return q

    start = [rng.uniform(-0.05, 0.05, (n, 3)) for n in counts]
    drift = [rng.uniform(-0.02, 0.02, (n, 3)) for n in counts]
    steps = []
    for i in range(5):
        t = 0.01 * i
        pts = np.concatenate([p + d * i for p, d in zip(start, drift)])
        poses = np.stack([pose(k, t) for k in range(len(parts))])
        recs = [_record(names[c], parts[k][0]) for c in range(len(names)) for k in range(len(parts))
                if rng.random() < 0.6]
        steps.append((t, pts, poses, recs))
    wear = WearMap(names, rest_s, radii, parts, clearance, exclusions)
    if batched:
        wear.update_many([s[0] for s in steps], np.stack([s[1] for s in steps]), np.stack([s[2] for s in steps]),
                         [s[3] for s in steps])
    else:
        for t, pts, poses, recs in steps:
            wear.update_many([t], pts[None], poses[None], [recs])
    contact, sliding, partner = _reference_wear(names, rest_s, radii, parts, clearance, exclusions, steps)
    got = wear.result()
    for c in range(len(names)):
        np.testing.assert_allclose(got[c].contact_time, contact[c], rtol=1e-12, atol=1e-15)
        # an ellipsoid's nearest place comes from a line search whose iterations depend on the
        # rows solved together (one element alone, or many): its parameter agrees to ~1e-9
        np.testing.assert_allclose(got[c].sliding, sliding[c], rtol=1e-7, atol=1e-12)
        assert set(wear._partner_time[c]) >= set(partner[c])
        for name, times in partner[c].items():
            np.testing.assert_allclose(wear._partner_time[c][name], times, rtol=1e-12, atol=1e-15)
