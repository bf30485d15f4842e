"""Signed distances of primitive pairs: closed forms, exact depths, the lower-bound rule, and
the part-part records the issue of curved parts' tessellations used to miss."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cablecheck.checker.convex import CONVEX, convex_pairs
from cablecheck.checker.parts import check_parts
from cablecheck.checker.partset import PartSet
from cablecheck.checker.shapes import Shape, ShapeType, signed_distance_batch

K = {t: k for k, t in enumerate(CONVEX)}
EYE = np.eye(3)


def rot(a, b, c):
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
    return rz @ ry @ rx


def one(ta, sa, ra, pa, tb, sb, rb, pb):
    pad = lambda s: np.pad(np.asarray(s, float), (0, 3 - len(s)))[None]
    sd, where, exact, apart = convex_pairs(np.array([K[ta]]), pad(sa), np.asarray(ra, float)[None],
                                           np.asarray(pa, float)[None], np.array([K[tb]]), pad(sb),
                                           np.asarray(rb, float)[None], np.asarray(pb, float)[None])
    return sd[0], where[0], exact[0], apart[0]


def parts_records(shapes, poses, clearance=0.0, tolerance=5e-4):
    names = [f"p{k}" for k in range(len(shapes))]
    ps = PartSet.build(names, shapes, tolerance=tolerance)
    return {(r.a, r.b): (r.severity.value, r.min_distance) for r in check_parts(ps, ps.place(np.array(poses)), clearance)}


def pose(x=0.0, y=0.0, z=0.0, r=EYE):
    t = np.eye(4)
    t[:3, :3] = r
    t[:3, 3] = [x, y, z]
    return t


def test_spheres_overlapping_by_less_than_the_tessellation_error_are_found_exactly():
    # radius 50 mm, tessellated to 0.5 mm: the inscribed polyhedra never met at 0.2 mm
    s = Shape(ShapeType.SPHERE, [0.05])
    got = parts_records([s, s], [pose(), pose(0.0998)])
    assert got[("p0", "p1")][0] == "hard"
    assert got[("p0", "p1")][1] == pytest.approx(-2e-4, abs=1e-12)


def test_cylinder_in_a_box_by_a_tenth_of_a_millimetre():
    cyl = Shape(ShapeType.CYLINDER, [0.03, 0.05])
    plate = Shape(ShapeType.BOX, [0.2, 0.2, 0.01])
    got = parts_records([plate, cyl], [pose(), pose(0.0, 0.0, 0.01 + 0.05 - 1e-4, rot(0, 0, 0.3))])
    assert got[("p0", "p1")][0] == "hard"
    assert got[("p0", "p1")][1] == pytest.approx(-1e-4, abs=1e-12)
    # standing 0.1 mm clear: soft at the exact gap with a clearance
    got = parts_records([plate, cyl], [pose(), pose(0.0, 0.0, 0.06 + 1e-4)], clearance=1e-3)
    assert got[("p0", "p1")] == ("soft", pytest.approx(1e-4, abs=1e-12))


def test_deep_sphere_overlap_is_not_understated():
    s = Shape(ShapeType.SPHERE, [0.05])
    got = parts_records([s, s], [pose(), pose(0.06)])
    assert got[("p0", "p1")][1] == pytest.approx(-0.04, abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(st.floats(0.1, 2.0), st.floats(0.1, 2.0), st.lists(st.floats(-4, 4), min_size=3, max_size=3))
def test_sphere_sphere_closed_form(r1, r2, c):
    sd, where, exact, _ = one(ShapeType.SPHERE, [r1], EYE, [0, 0, 0], ShapeType.SPHERE, [r2], EYE, c)
    assert exact and sd == pytest.approx(np.linalg.norm(c) - r1 - r2, abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(st.floats(0.05, 1.0), st.floats(0.05, 1.0), st.floats(0.0, 2.0), st.floats(-3, 3), st.floats(-1.5, 1.5))
def test_parallel_capsules(r1, r2, h, dy, dz):
    sd, _, exact, _ = one(ShapeType.CAPSULE, [r1, h], EYE, [0, 0, 0], ShapeType.CAPSULE, [r2, h], EYE, [0, dy, dz])
    # parallel axes of equal length, shifted along them by |dz| <= their length: axes |dy| apart
    axis_gap = np.hypot(dy, max(abs(dz) - 2 * h, 0.0))
    assert exact and sd == pytest.approx(axis_gap - r1 - r2, abs=1e-12)


def test_box_box_depth_is_the_least_axis_overlap():
    sd, _, exact, _ = one(ShapeType.BOX, [1, 1, 1], EYE, [0, 0, 0], ShapeType.BOX, [0.5, 0.5, 0.5], EYE, [1.2, 0.3, 0])
    assert exact and sd == pytest.approx(-0.3)
    # a box rotated 45 degrees about z entering a face with its edge: depth along x
    r = rot(0, 0, np.pi / 4)
    sd, _, _, _ = one(ShapeType.BOX, [1, 1, 1], EYE, [0, 0, 0], ShapeType.BOX, [0.5, 0.5, 0.5], r, [1.6, 0, 0])
    assert sd == pytest.approx(1.6 - 1 - 0.5 * np.sqrt(2))
    # boxes apart are left to the triangles
    assert one(ShapeType.BOX, [1, 1, 1], EYE, [0, 0, 0], ShapeType.BOX, [1, 1, 1], EYE, [2.5, 0, 0])[3]


def _random_pairs(rng, n):
    ka = rng.integers(0, 5, n)
    kb = rng.integers(0, 5, n)
    sa = rng.uniform(0.2, 1.0, (n, 3))
    sb = rng.uniform(0.2, 1.0, (n, 3))
    ra = np.array([rot(*rng.uniform(-np.pi, np.pi, 3)) for _ in range(n)])
    rb = np.array([rot(*rng.uniform(-np.pi, np.pi, 3)) for _ in range(n)])
    pa = rng.uniform(-1, 1, (n, 3))
    pb = pa + rng.uniform(-2.5, 2.5, (n, 3))
    return ka, sa, ra, pa, kb, sb, rb, pb


def _solid_samples(k, s, r, p, rng, m):
    """Points drawn in a cube holding the primitive; world points and their signed distances."""
    local = rng.uniform(-1, 1, (m, 3)) * (s[0] + s[1] + s[2])
    d, _ = signed_distance_batch(CONVEX[k], np.repeat(s[None], m, 0), local)
    return local @ r.T + p, d


@pytest.mark.parametrize("seed", [0, 1])
def test_signed_distance_is_a_lower_bound_and_depth_an_upper_one(seed):
    """Against independent witnesses: a point inside both solids at depths dA, dB proves a depth of
    at least min(dA, dB) (a shorter translation leaves that point in both); two points, one of each
    solid, prove a distance of at most theirs."""
    rng = np.random.default_rng(seed)
    n = 300
    ka, sa, ra, pa, kb, sb, rb, pb = _random_pairs(rng, n)
    sd, where, exact, apart = convex_pairs(ka, sa, ra, pa, kb, sb, rb, pb)
    for k in range(n):
        xa, da = _solid_samples(ka[k], sa[k], ra[k], pa[k], rng, 600)
        xa = xa[da <= 0]
        if not len(xa):
            continue
        lb = np.einsum("nji,nj->ni", np.repeat(rb[k][None], len(xa), 0), xa - pb[k])
        db, _ = signed_distance_batch(CONVEX[kb[k]], np.repeat(sb[k][None], len(xa), 0), lb)
        la = np.einsum("nji,nj->ni", np.repeat(ra[k][None], len(xa), 0), xa - pa[k])
        dself, _ = signed_distance_batch(CONVEX[ka[k]], np.repeat(sa[k][None], len(xa), 0), la)
        both = db < 0
        if both.any():
            assert sd[k] <= -np.max(np.minimum(-dself[both], -db[both])) + 1e-9
        if apart[k]:
            continue
        # distance witnesses: each sample of A to its closest point on B
        assert sd[k] <= db.min() + 1e-9 or db.min() < 0


def test_agrees_with_a_general_collision_library_when_apart():
    fcl = pytest.importorskip("fcl")
    rng = np.random.default_rng(7)
    n = 400
    ka, sa, ra, pa, kb, sb, rb, pb = _random_pairs(rng, n)
    sd, _, exact, apart = convex_pairs(ka, sa, ra, pa, kb, sb, rb, pb)

    def geom(k, s):
        t = CONVEX[k]
        return {ShapeType.BOX: lambda: fcl.Box(*(2 * s)), ShapeType.SPHERE: lambda: fcl.Sphere(s[0]),
                ShapeType.CAPSULE: lambda: fcl.Capsule(s[0], 2 * s[1]),
                ShapeType.CYLINDER: lambda: fcl.Cylinder(s[0], 2 * s[1]),
                ShapeType.ELLIPSOID: lambda: fcl.Ellipsoid(*s)}[t]()

    checked = 0
    for k in range(n):
        if apart[k] or sd[k] <= 0:
            continue
        a = fcl.CollisionObject(geom(ka[k], sa[k]), fcl.Transform(ra[k], pa[k]))
        b = fcl.CollisionObject(geom(kb[k], sb[k]), fcl.Transform(rb[k], pb[k]))
        ref = fcl.distance(a, b, fcl.DistanceRequest(), fcl.DistanceResult())
        # fcl's GJK stops early on curved shapes (its answers are a little high); ours a lower bound
        assert sd[k] <= ref + 1e-9
        assert sd[k] >= ref - 2e-3 * max(1.0, ref)
        if exact[k]:
            assert sd[k] == pytest.approx(ref, abs=1e-3)
        checked += 1
    assert checked > 200


def test_capsule_tip_in_a_box_is_exact():
    # axis along z, lower tip 0.2 into the top face: pushed up by 0.2
    sd, _, exact, _ = one(ShapeType.CAPSULE, [0.2, 0.5], EYE, [0.3, -0.2, 1.5], ShapeType.BOX, [1, 1, 1], EYE, [0, 0, 0])
    assert exact and sd == pytest.approx(-0.2, abs=1e-12)
    # lying across the box's top edge, axis along y through the edge line x = 1, z = 1
    sd, _, exact, _ = one(ShapeType.CAPSULE, [0.2, 0.5], rot(np.pi / 2, 0, 0), [1.0, 0.0, 1.0],
                          ShapeType.BOX, [1, 1, 1], EYE, [0, 0, 0])
    assert exact and sd == pytest.approx(-0.2, abs=1e-12)


def test_pairs_proven_beyond_the_clearance_are_not_refined():
    rng = np.random.default_rng(3)
    args = _random_pairs(rng, 200)
    full, _, _, _ = convex_pairs(*args)
    quick, _, _, _ = convex_pairs(*args, beyond=0.5)
    both = ~np.isnan(full)                                     # (two boxes apart: the caller's)
    assert np.array_equal(np.isnan(quick), ~both)
    assert np.all(quick[both] <= full[both] + 1e-12)           # still lower bounds
    near = both & (full < 0.5)
    np.testing.assert_allclose(quick[near], full[near])        # the ones that matter are refined


def test_overlapping_curved_depth_is_close_to_a_dense_search():
    """Depth of overlapping pairs of the general rule: an upper bound (any direction's h_D is
    one), within 2 % of the least h_D over 50,000 directions spread on the sphere."""
    from cablecheck.checker.convex import _fibonacci, _h_d

    rng = np.random.default_rng(11)
    ka, sa, ra, pa, kb, sb, rb, pb = _random_pairs(rng, 400)
    sd, _, exact, apart = convex_pairs(ka, sa, ra, pa, kb, sb, rb, pb)
    rows = np.flatnonzero(~exact & ~apart & (sd < -0.05))[:25]
    assert len(rows) >= 10
    u = _fibonacci(50000)
    for k in rows:
        args = [np.repeat(np.asarray(x)[k:k + 1], len(u), axis=0) for x in (ka, sa, ra, pa, kb, sb, rb, pb)]
        dense = _h_d(*args, u)[0].min()
        assert -sd[k] <= dense * 1.02 + 1e-9


def test_a_sphere_sinking_into_a_plane_by_less_than_its_tessellation_error():
    s = Shape(ShapeType.SPHERE, [0.05])
    got = parts_records([Shape(ShapeType.PLANE, []), s], [pose(), pose(0.0, 0.0, 0.05 - 1e-4, rot(0.3, 0.2, 0.1))])
    assert got[("p0", "p1")] == ("hard", pytest.approx(-1e-4, abs=1e-12))
    cyl = Shape(ShapeType.CYLINDER, [0.03, 0.05])
    tilt = rot(np.pi / 2, 0, 0)                    # lying on its side: lowest along a generator
    got = parts_records([Shape(ShapeType.PLANE, []), cyl], [pose(), pose(0.0, 0.0, 0.03 + 2e-4, tilt)], clearance=1e-3)
    assert got[("p0", "p1")] == ("soft", pytest.approx(2e-4, abs=1e-12))


def _cylinder_sd(rad, half, x):
    """Reference: a point's signed distance to the cylinder of radius rad, half length half, axis z."""
    radial, axial = np.hypot(x[0], x[1]) - rad, abs(x[2]) - half
    if radial > 0 or axial > 0:
        return float(np.hypot(max(radial, 0.0), max(axial, 0.0)))
    return float(max(radial, axial))


@settings(max_examples=80, deadline=None)
@given(st.floats(0.05, 1.0), st.floats(0.05, 1.0), st.floats(0.05, 1.0), st.floats(0.05, 1.0),
       st.lists(st.floats(-3, 3), min_size=3, max_size=3), st.lists(st.floats(-np.pi, np.pi), min_size=3, max_size=3),
       st.floats(-np.pi, np.pi), st.booleans())
def test_parallel_cylinders_closed_form(r1, h1, r2, h2, off, angles, turn, flip):
    """Parallel axes (either way round, B turned about its axis): A - B is the cylinder of radius
    r1 + r2 and half length h1 + h2, and B's centre's signed distance to it is the pair's."""
    frame = rot(*angles)
    rb = frame @ rot(np.pi if flip else 0.0, 0.0, turn)
    pb = frame @ np.asarray(off)
    sd, where, exact, _ = one(ShapeType.CYLINDER, [r1, h1], frame, [0, 0, 0], ShapeType.CYLINDER, [r2, h2], rb, pb)
    assert exact or not np.isclose(np.linalg.norm(np.cross(frame[:, 2], rb[:, 2])), 0.0, atol=0.0)
    ref = _cylinder_sd(r1 + r2, h1 + h2, np.asarray(off))
    assert sd <= ref + 1e-12 and sd == pytest.approx(ref, abs=1e-12)
    assert np.all(np.isfinite(where))


@settings(max_examples=60, deadline=None)
@given(st.floats(0.05, 1.0), st.floats(0.0, 1.0), st.floats(0.05, 1.0), st.floats(0.05, 1.0),
       st.lists(st.floats(-3, 3), min_size=3, max_size=3), st.floats(-np.pi, np.pi))
def test_capsule_on_a_parallel_cylinder_closed_form(r1, h1, r2, h2, off, turn):
    """A capsule is its axis grown by a ball: against a parallel cylinder, the signed distance of the
    capsule's centre to the cylinder of radius r2 and half length h1 + h2, less r1."""
    frame = rot(0.3, -0.7, 1.1)
    pb = frame @ np.asarray(off)
    sd, _, _, _ = one(ShapeType.CAPSULE, [r1, h1], frame, [0, 0, 0], ShapeType.CYLINDER, [r2, h2],
                      frame @ rot(0, 0, turn), pb)
    assert sd == pytest.approx(_cylinder_sd(r2, h1 + h2, np.asarray(off)) - r1, abs=1e-12)


def test_parallel_cylinders_against_the_general_rule_and_a_dense_search():
    """Brute force: minus the signed distance is the least support function h_D of A - B over all
    directions, so never above the least over 50,000 spread directions; and the general rule
    (descent on the directions, exact apart, an upper bound on the depth overlapping) on the same
    pair turned 1e-6 rad off parallel agrees with it to that tilt."""
    from cablecheck.checker.convex import _fibonacci, _h_d

    rng = np.random.default_rng(5)
    u = _fibonacci(50000)
    pad = lambda s: np.pad(s, (0, 1))
    cyl = K[ShapeType.CYLINDER]
    for _ in range(40):
        frame = rot(*rng.uniform(-np.pi, np.pi, 3))
        sa, sb = rng.uniform(0.1, 1.0, 2), rng.uniform(0.1, 1.0, 2)
        rb = frame @ rot(np.pi * rng.integers(0, 2), 0.0, rng.uniform(-np.pi, np.pi))
        pb = frame @ rng.uniform(-1.5, 1.5, 3)
        sd, _, exact, _ = one(ShapeType.CYLINDER, sa, frame, [0, 0, 0], ShapeType.CYLINDER, sb, rb, pb)
        args = [np.repeat(np.asarray(x)[None], len(u), axis=0)
                for x in (cyl, pad(sa), frame, np.zeros(3), cyl, pad(sb), rb, pb)]
        assert -sd <= _h_d(*args, u)[0].min() + 1e-12
        general, _, g_exact, _ = one(ShapeType.CYLINDER, sa, frame, [0, 0, 0], ShapeType.CYLINDER, sb,
                                     rb @ rot(1e-6, 0, 0), pb)
        assert not g_exact
        assert general <= sd + 4e-6
        if sd > 0:
            assert general == pytest.approx(sd, abs=4e-6)


def test_a_knuckle_turning_on_its_pin_keeps_the_same_depth_to_the_bit():
    """A door's knuckle turning round its hinge pin: the pair's depth (the pin's radius plus the
    knuckle's) is the same number at every angle, exactly."""
    values = {one(ShapeType.CYLINDER, [0.004, 0.2], EYE, [0, 0, 0], ShapeType.CYLINDER, [0.012, 0.04],
                  rot(0, 0, a), [0, 0, 0])[0] for a in np.linspace(0, np.pi / 3, 50)}
    assert values == {-0.016}


def test_nearly_parallel_cylinders_stay_a_lower_bound():
    """Axes 1e-10 rad apart take B's enclosing cylinder along A's axis: never above the general
    rule's answer for the same pair (exact when apart), and within rounding of it."""
    tilt = rot(1e-10, 0, 0)
    for pb in ([0.5, 0.0, 0.1], [0.0, 0.0, 1.3], [0.05, 0.02, 0.0]):
        sd, _, exact, _ = one(ShapeType.CYLINDER, [0.2, 0.5], EYE, [0, 0, 0], ShapeType.CYLINDER, [0.1, 0.3], tilt, pb)
        ref = _cylinder_sd(0.3, 0.8, np.asarray(pb))
        assert not exact and sd <= ref + 1e-12 and sd == pytest.approx(ref, abs=1e-9)
