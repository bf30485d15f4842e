"""cablecheck.checker.wear: contact time, sliding and bending cycles per arc-length bin."""

from __future__ import annotations

import numpy as np
import pytest

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
