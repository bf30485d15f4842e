"""check_state against brute-force references, analytic cases and the paper's cases."""

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings, strategies as st
from test_closest import seg_seg_apart_ref

from cablecheck.checker.cable import densify, self_pair_excluded
from cablecheck.checker.closest import segment_segment
from cablecheck.checker.interference import check_state
from cablecheck.checker.records import PairType, Severity
from cablecheck.checker.scene_state import CableState, CheckConfig, Exclusion, PartState
from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape, segment_signed_distance, signed_distance

pytestmark = pytest.mark.filterwarnings("error")


def pose(R=None, t=(0, 0, 0)):
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    T[:3, 3] = t
    return T


def rot(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def random_scene(seed, n_cables=3, n_parts=4, with_mesh=True):
    rng = np.random.default_rng(seed)
    cables = []
    for c in range(n_cables):
        n = rng.integers(2, 9)
        start = rng.uniform(-0.1, 0.1, 3)
        pts = start + np.cumsum(rng.normal(size=(n, 3)) * 0.03, axis=0)
        if rng.random() < 0.3:
            pts[1] = pts[0]  # a zero-length element
        cables.append(CableState(f"c{c}", pts, float(rng.uniform(0.004, 0.012))))
    kinds = [ShapeType.BOX, ShapeType.SPHERE, ShapeType.CYLINDER, ShapeType.CAPSULE, ShapeType.ELLIPSOID]
    parts = []
    for k in range(n_parts):
        kind = kinds[rng.integers(len(kinds))]
        parts.append(PartState(f"p{k}", Shape(kind, rng.uniform(0.01, 0.05, 3)), pose(rot(rng), rng.uniform(-0.1, 0.1, 3)),
                               keepout=bool(rng.random() < 0.25)))
    if with_mesh:
        m = trimesh.creation.torus(0.04, 0.012, major_sections=16, minor_sections=8)
        parts.append(PartState("mesh", mesh_shape(m.vertices, m.faces), pose(rot(rng), rng.uniform(-0.1, 0.1, 3))))
    return cables, parts


def _local(part, x):
    return (x - part.pose[:3, 3]) @ part.pose[:3, :3]


def brute_points(cables, parts, cfg, exclusions=()):
    """O(n^2) reference for method points: every pair, every part."""
    best = {}

    def put(key, v):
        best[key] = min(best.get(key, np.inf), v)

    dense = [densify(c.points, cfg.spacing * c.radius) for c in cables]
    for a, (ca, (pa, sa)) in enumerate(zip(cables, dense)):
        r = ca.radius
        for i in range(len(pa)):
            for j in range(i + 1, len(pa)):
                if not self_pair_excluded(sa[i], sa[j], r, cfg.clearance):
                    put((PairType.SELF, ca.name, ca.name), np.linalg.norm(pa[i] - pa[j]) - 2 * r)
            for e in range(len(pa) - 1):
                if i in (e, e + 1):
                    continue
                sm = 0.5 * (sa[e] + sa[e + 1])
                if not self_pair_excluded(sa[i], sm, r, cfg.clearance):
                    put((PairType.SELF, ca.name, ca.name), np.linalg.norm(pa[i] - 0.5 * (pa[e] + pa[e + 1])) - 2 * r)
        for b in range(a + 1, len(cables)):
            cb = cables[b]
            pb = dense[b][0]
            d = np.linalg.norm(pa[:, None] - pb[None], axis=2).min()
            put((PairType.CABLE_CABLE, ca.name, cb.name), d - r - cb.radius)
        for part in parts:
            keep = np.ones(len(pa), bool)
            for ex in exclusions:
                if ex.cable == ca.name and ex.part == part.name:
                    keep &= ~((sa >= ex.s_min) & (sa <= ex.s_max))
            if not keep.any():
                continue
            d = signed_distance(part.shape, _local(part, pa[keep]))[0] - r
            put((PairType.KEEPOUT if part.keepout else PairType.CABLE_STRUCTURE, ca.name, part.name), d.min())
    return {k: v for k, v in best.items() if v < cfg.clearance}


def brute_exact(cables, parts, cfg):
    """O(n^2) reference for method exact: every element pair, every element-part pair
    (self: the least distance over each element pair's places outside the window)."""
    best = {}

    def put(key, v):
        best[key] = min(best.get(key, np.inf), v)

    dense = [densify(c.points, cfg.spacing * c.radius) for c in cables]
    for a, (ca, (pa, sa)) in enumerate(zip(cables, dense)):
        r = ca.radius
        na = len(pa) - 1
        # self: the documented rule literally, every element pair's places at
        # least pi r + clearance apart along the cable (polygon reference)
        window = np.pi * r + cfg.clearance
        for i in range(na):
            for j in range(i + 1, na):
                d = seg_seg_apart_ref(pa[i], pa[i + 1], pa[j], pa[j + 1], sa[i], sa[i + 1], sa[j], sa[j + 1],
                                      window)
                put((PairType.SELF, ca.name, ca.name), d - 2 * r)
        for b in range(a + 1, len(cables)):
            cb = cables[b]
            pb = dense[b][0]
            for i in range(na):
                for j in range(len(pb) - 1):
                    d = segment_segment(pa[i][None], pa[i + 1][None], pb[j][None], pb[j + 1][None])[0][0]
                    put((PairType.CABLE_CABLE, ca.name, cb.name), d - r - cb.radius)
        for part in parts:
            d, _ = segment_signed_distance(part.shape, _local(part, pa[:-1]), _local(part, pa[1:]))
            put((PairType.KEEPOUT if part.keepout else PairType.CABLE_STRUCTURE, ca.name, part.name), d.min() - r)
    return {k: v for k, v in best.items() if v < cfg.clearance}


def as_dict(records):
    return {(r.type, r.a, r.b): r.min_distance for r in records}


def assert_same(got, ref, tol):
    assert set(got) == set(ref), (set(got) ^ set(ref))
    for k in ref:
        assert got[k] == pytest.approx(ref[k], abs=tol), k


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_points_method_equals_brute_force(seed):
    cables, parts = random_scene(seed)
    cfg = CheckConfig(method="points", clearance=0.01)
    ex = [Exclusion(cables[0].name, parts[0].name, 0.01, 0.05)]
    got = check_state(cables, parts, cfg, ex)
    assert_same(as_dict(got), brute_points(cables, parts, cfg, ex), 1e-12)
    for r in got:
        assert r.severity is (Severity.HARD if r.min_distance < 0 else Severity.SOFT)
        assert np.all(np.isfinite(r.where)) and np.isfinite(r.s)


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_exact_method_equals_brute_force(seed):
    cables, parts = random_scene(seed)
    cfg = CheckConfig(method="exact", clearance=0.01)
    assert_same(as_dict(check_state(cables, parts, cfg)), brute_exact(cables, parts, cfg), 1e-12)


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_exact_is_never_less_severe_than_points(seed):
    cables, parts = random_scene(seed, with_mesh=False)
    pts = as_dict(check_state(cables, parts, CheckConfig(method="points", clearance=0.01)))
    ex = as_dict(check_state(cables, parts, CheckConfig(method="exact", clearance=0.01)))
    for k, v in pts.items():
        if k[0] is not PairType.SELF:  # self pairs use different exclusion points
            assert k in ex and ex[k] <= v + 1e-12


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 2**31 - 1), st.sampled_from(["points", "exact"]))
def test_translation_and_mm_scaling_give_the_same_answers(seed, method):
    cables, parts = random_scene(seed)
    cfg = CheckConfig(method=method, clearance=0.01)
    base = check_state(cables, parts, cfg)
    shift = np.array([1e4, -1e4, 1e4])
    moved_c = [CableState(c.name, c.points + shift, c.radius) for c in cables]
    moved_p = [PartState(p.name, p.shape, pose(p.pose[:3, :3], p.pose[:3, 3] + shift), p.keepout) for p in parts]
    moved = check_state(moved_c, moved_p, cfg)
    assert [(r.type, r.a, r.b, r.severity) for r in moved] == [(r.type, r.a, r.b, r.severity) for r in base]
    by_name = {c.name: c for c in cables}
    for r0, r1 in zip(base, moved):
        assert r1.min_distance == pytest.approx(r0.min_distance, abs=1e-9)
        # The worst place may be any of several tied ones, but it is on cable a.
        pts = by_name[r1.a].points
        from cablecheck.checker.closest import point_segment

        n = len(pts) - 1
        d = point_segment(np.tile(r1.where - shift, (n, 1)), pts[:-1], pts[1:])[0]
        assert d.min() < 1e-9
    mm_c = [CableState(c.name, c.points * 1000, c.radius * 1000) for c in cables]
    mm_p = []
    for p in parts:
        sh = p.shape
        sh = mesh_shape(sh.vertices * 1000, sh.faces) if sh.type is ShapeType.MESH else Shape(sh.type, sh.size * 1000)
        mm_p.append(PartState(p.name, sh, pose(p.pose[:3, :3], p.pose[:3, 3] * 1000), p.keepout))
    mm = check_state(mm_c, mm_p, CheckConfig(method=method, clearance=10.0))
    assert [(r.type, r.a, r.b, r.severity) for r in mm] == [(r.type, r.a, r.b, r.severity) for r in base]
    for r0, r1 in zip(base, mm):
        assert r1.min_distance == pytest.approx(1000 * r0.min_distance, rel=1e-9, abs=1e-9)


# --- the paper's cases and analytic answers ----------------------------------


def test_two_crossing_cables():
    r = 0.004
    a = CableState("a", np.array([[-0.1, 0, 0], [0.1, 0, 0]]), r)
    b = CableState("b", np.array([[0.0, -0.1, 0.006], [0.0, 0.1, 0.006]]), r)
    exact = check_state([a, b], [], CheckConfig(method="exact"))
    assert len(exact) == 1 and exact[0].type is PairType.CABLE_CABLE
    assert exact[0].min_distance == pytest.approx(0.006 - 2 * r, abs=1e-15)
    assert exact[0].severity is Severity.HARD and np.allclose(exact[0].where, 0)
    assert exact[0].s == pytest.approx(0.1) and exact[0].s_b == pytest.approx(0.1)
    pts = check_state([a, b], [], CheckConfig(method="points"))
    assert len(pts) == 1 and pts[0].min_distance >= exact[0].min_distance


def test_cable_through_a_box_and_along_its_edge():
    r = 0.004
    box = PartState("box", Shape(ShapeType.BOX, [0.05, 0.02, 0.02]), pose(t=[1.0, 2.0, 3.0]))
    through = CableState("through", np.array([[1.0, 1.9, 3.005], [1.0, 2.1, 3.005]]), r)
    edge = CableState("edge", np.array([[0.9, 2.02, 3.02], [1.1, 2.02, 3.02]]), r)
    for method in ("points", "exact"):
        out = {rec.a: rec for rec in check_state([through, edge], [box], CheckConfig(method=method))}
        assert out["through"].min_distance == pytest.approx(-0.015 - r, abs=1e-12)
        assert out["through"].type is PairType.CABLE_STRUCTURE and out["through"].severity is Severity.HARD
        assert out["edge"].min_distance == pytest.approx(-r, abs=1e-12)  # centreline exactly on the edge


def test_self_crossing_only_the_midpoint_pass_catches():
    r = 0.01
    # Leg 1 along x at spacing 2r with points at x = -r and +r; the loop comes
    # back along y above it with a point right over leg 1's element midpoint.
    leg1 = np.stack([np.arange(-7, 8, 2) * r, np.zeros(8), np.zeros(8)], axis=1)
    h = 1.9 * r
    up = np.array([[7 * r, 0, 2 * r], [7 * r, -6 * r, 2 * r], [0, -6 * r, h]])
    leg2 = np.stack([np.zeros(7), np.arange(-6, 8, 2) * r, np.full(7, h)], axis=1)
    pts = densify(np.concatenate([leg1, up, leg2[1:]]), 2 * r)[0]
    cable = CableState("loop", pts, r)
    # No two points are within 2r of each other away from neighbours...
    from cablecheck.checker.cable import arc_length

    s = arc_length(pts)
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    far = ~self_pair_excluded(s[:, None], s[None], r)
    assert d[far].min() > 2 * r
    # ...but the point over the midpoint is 1.9 r from it.
    out = check_state([cable], [], CheckConfig(method="points", clearance=0.0))
    assert len(out) == 1 and out[0].type is PairType.SELF
    assert out[0].min_distance == pytest.approx(h - 2 * r, abs=1e-12)
    exact = check_state([cable], [], CheckConfig(method="exact", clearance=0.0))
    assert exact[0].min_distance == pytest.approx(h - 2 * r, abs=1e-12)


def test_straight_and_gently_bent_cables_do_not_self_interfere():
    r = 0.004
    th = np.linspace(0, 1.5 * np.pi, 300)
    R = 5 * r
    coil = np.stack([R * np.cos(th), R * np.sin(th), 0 * th], axis=1)
    straight = np.stack([np.linspace(0, 1, 7), np.zeros(7), np.zeros(7)], axis=1)
    straight = np.insert(straight, 3, straight[3], axis=0)  # coincident points
    for method in ("points", "exact"):
        out = check_state([CableState("coil", coil, r), CableState("line", straight + [0, 1, 0], r)], [],
                          CheckConfig(method=method, clearance=0.0))
        assert out == []


def test_keepout_exclusion_bend_and_taut():
    r = 0.004
    sphere = PartState("bolt-space", Shape(ShapeType.SPHERE, [0.02]), pose(), keepout=True)
    clip = PartState("clip", Shape(ShapeType.BOX, [0.01, 0.01, 0.01]), pose(t=[0.1, 0, 0]))
    pts = np.array([[-0.1, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0]])
    cab = CableState("c", pts, r, min_bend_radius=0.2, rest_length=0.29)
    for method in ("points", "exact"):
        out = check_state([cab], [sphere, clip], CheckConfig(method=method),
                          [Exclusion("c", "clip", 0.15, 0.25)])
        kinds = {rec.type: rec for rec in out}
        assert PairType.CABLE_STRUCTURE not in kinds
        # Points fall at x = +-0.004 (spacing 2r from x = -0.1); exact sees x = 0.
        deepest = -0.02 + (0.004 if method == "points" else 0.0)
        assert kinds[PairType.KEEPOUT].min_distance == pytest.approx(deepest - r, abs=1e-12)
        # Circumradius of the corner: half the 0.2 x 0.1 hypotenuse.
        assert kinds[PairType.BEND].min_distance == pytest.approx(np.hypot(0.2, 0.1) / 2 - 0.2, abs=1e-12)
        assert kinds[PairType.TAUT].min_distance == pytest.approx(0.0029 - 0.01, abs=1e-12)
    # Without the window the clip is hit.
    out = [rec for rec in check_state([cab], [clip], CheckConfig()) if rec.type is PairType.CABLE_STRUCTURE]
    assert len(out) == 1 and out[0].b == "clip" and out[0].severity is Severity.HARD


def test_plane_and_grazing_at_the_clearance():
    r = 0.004
    floor = PartState("floor", Shape(ShapeType.PLANE, [0.0]), pose())
    cab = CableState("c", np.array([[0, 0, 0.01], [1, 0, r + 0.005]]), r)
    out = check_state([cab], [floor], CheckConfig(clearance=0.005))
    assert out == []  # exactly at the clearance is clear
    cab = CableState("c", np.array([[0, 0, 0.01], [1, 0, r + 0.0049]]), r)
    out = check_state([cab], [floor], CheckConfig(clearance=0.005, method="exact"))
    assert out[0].severity is Severity.SOFT and out[0].min_distance == pytest.approx(0.0049, abs=1e-15)
    assert out[0].s == pytest.approx(np.hypot(1, 0.01 - r - 0.0049))


def test_face_plane_option_raises_false_alarm_near_an_edge():
    r = 0.004
    box = PartState("box", Shape(ShapeType.BOX, [0.05, 0.05, 0.05]), pose())
    # Runs along an edge 3.5 mm from both face planes (less than r) but
    # 4.95 mm from the edge itself (more than r): clear, except face-plane.
    off = 0.05 + 0.0035
    cab = CableState("c", np.array([[off, off, -0.2], [off, off, 0.2]]), r)
    assert check_state([cab], [box], CheckConfig(clearance=0.0)) == []
    fp = check_state([cab], [box], CheckConfig(clearance=0.0, face_plane=True))
    # (the top and bottom face planes, crossed by the run, alarm even more)
    assert len(fp) == 1 and fp[0].min_distance <= 0.0035 - r + 1e-12


@pytest.mark.parametrize("method", ["points", "exact"])
def test_exclusion_window_follows_the_material_of_a_stretched_cable(method):
    """A cable of rest length 1 stretched by 10 %: its end clamp's window
    covers the last 0.2 of material, now the last 0.22 of arc length. The
    clamp block, touching the last 0.05 of the cable, is excused when the
    window is measured along the material (rest_s), not when measured along
    the current arc length (past 1.0, outside [0.8, 1.0])."""
    from cablecheck.checker.interference import Checker
    r = 0.004
    rest = np.linspace(0.0, 1.0, 11)
    pts = np.stack([1.1 * rest, np.zeros(11), np.zeros(11)], axis=1)
    clamp = PartState("clamp", Shape(ShapeType.BOX, [0.025, 0.02, 0.02]), pose(t=(1.09, 0.0, 0.0)))
    window = [Exclusion("c", "clamp", 0.8, 1.0, "end", to_end=True)]     # the window reaches the cable's end
    config = CheckConfig(method=method, clearance=0.005)
    by_arc = check_state([CableState("c", pts, r)], [clamp], config, window)
    assert [(x.b, x.severity) for x in by_arc] == [("clamp", Severity.HARD)] and by_arc[0].s > 1.0
    assert check_state([CableState("c", pts, r, rest_s=rest)], [clamp], config, window) == []
    # unstretched, both measures agree
    assert check_state([CableState("c", pts / 1.1, r, rest_s=rest)], [clamp.__class__(
        "clamp", clamp.shape, pose(t=(0.99, 0.0, 0.0)))], config, window) == []
    if method == "points":     # many states at once: the same windows
        checker = Checker([clamp], config)
        dense = checker.densify_many(pts[None], np.array([0, 11]), np.array([r]), rest)
        assert checker.structure_many(["c"], np.array([r]), dense, clamp.pose[None, None], window,
                                      (np.arange(11), np.zeros(11, np.int64)))[0] == []
        dense = checker.densify_many(pts[None], np.array([0, 11]), np.array([r]))
        assert len(checker.structure_many(["c"], np.array([r]), dense, clamp.pose[None, None], window,
                                          (np.arange(11), np.zeros(11, np.int64)))[0]) == 1


def test_rest_coordinates_must_increase():
    with pytest.raises(ValueError, match="rest_s"):
        CableState("c", np.zeros((3, 3)) + [[0, 0, 0], [1, 0, 0], [2, 0, 0]], 0.01, rest_s=[0.0, 1.0, 1.0])
