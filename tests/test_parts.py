"""Part-part and keep-out interference: the steel-structure paper's boundary cases, containment, clearance, reuse."""

import numpy as np
import pytest
import trimesh

from cablecheck.checker.parts import PartChecker, check_parts
from cablecheck.checker.partset import PartSet
from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape
from cablecheck.checker.tessellate import part_surface


def pose(x=0.0, y=0.0, z=0.0):
    t = np.eye(4)
    t[:3, 3] = [x, y, z]
    return t


def box(*h):
    return Shape(ShapeType.BOX, list(h))


def check(parts, poses, clearance=0.01, keepout=None, **kw):
    ps = PartSet.build([n for n, _ in parts], [s for _, s in parts], keepout=keepout)
    recs = check_parts(ps, ps.place(np.array(poses)), clearance, **kw)
    return {(r.a, r.b): (r.type.value, r.severity.value, r.min_distance) for r in recs}


CUBE = box(0.5, 0.5, 0.5)


@pytest.mark.parametrize("other, why", [
    (pose(1.0), "touching faces"),
    (pose(1.0, 1.0), "shared edge"),
    (pose(1.0, 1.0, 1.0), "shared corner"),
    (pose(1.0, 0.3, 0.2), "faces partly on each other"),
])
def test_touching_is_contact_not_interference(other, why):
    assert check([("a", CUBE), ("b", CUBE)], [pose(), other]) == {}, why


def test_vertex_on_face_touches():
    # a pyramid standing on its apex exactly on the cube's top face
    tm = trimesh.Trimesh(vertices=[[0, 0, 0], [-0.3, -0.3, 1], [0.3, -0.3, 1], [0.3, 0.3, 1], [-0.3, 0.3, 1]],
                         faces=[[0, 2, 1], [0, 3, 2], [0, 4, 3], [0, 1, 4], [1, 2, 3], [1, 3, 4]])
    tm.fix_normals()
    apex = mesh_shape(np.asarray(tm.vertices), np.asarray(tm.faces))
    assert check([("a", CUBE), ("p", apex)], [pose(), pose(0.1, 0.1, 0.5)]) == {}
    assert check([("a", CUBE), ("p", apex)], [pose(), pose(0.1, 0.1, 0.49)])[("a", "p")][1] == "hard"


def test_overlap_depth_soft_gap_and_clear():
    got = check([("a", CUBE), ("b", CUBE), ("c", CUBE), ("d", CUBE)],
                [pose(), pose(0.9), pose(0, 1.004), pose(0, -1.5)], clearance=0.01)
    assert got[("a", "b")][:2] == ("part-part", "hard")
    # depth: the deepest probe (corners and centroids set in by 1e-5 of the size): -0.1 to 1e-4
    assert got[("a", "b")][2] == pytest.approx(-0.1, abs=1e-4) and got[("a", "b")][2] < 0
    assert got[("a", "c")][:2] == ("part-part", "soft")
    assert got[("a", "c")][2] == pytest.approx(0.004)
    assert ("a", "d") not in got and ("b", "c") in got


def test_containment_counts_as_overlap():
    got = check([("big", box(2, 2, 2)), ("small", box(0.1, 0.1, 0.1)), ("twin", box(2, 2, 2))],
                [pose(), pose(0.5, 0.5, 0.5), pose()])
    assert got[("big", "small")][:2] == ("part-part", "hard")
    # minus the deepest probe's depth: small's corner (0.4, 0.4, 0.4) is 1.6 inside
    assert got[("big", "small")][2] == pytest.approx(-1.6)
    assert got[("big", "twin")][1] == "hard"          # coincident parts overlap


def test_keepout_entered_by_a_part():
    got = check([("bolt", box(0.1, 0.1, 0.5)), ("zone", box(0.3, 0.3, 0.3)), ("arm", CUBE)],
                [pose(), pose(0, 0, 0.8), pose(0.5, 0, 1.3)], keepout=[False, True, False])
    assert got[("arm", "zone")][:2] == ("keepout", "hard")
    assert ("bolt", "zone") not in got     # the zone sits on the bolt head: touching only


def test_open_mesh_warns_and_still_checks_its_surface():
    tm = trimesh.creation.box(extents=[1, 1, 1])
    tm.update_faces(np.arange(len(tm.faces)) != 0)      # one triangle missing
    sheet = mesh_shape(np.asarray(tm.vertices), np.asarray(tm.faces))
    ps = PartSet.build(["open", "b"], [sheet, CUBE])
    assert ps.warnings and "inside and outside cannot be decided" in ps.warnings[0]
    recs = check_parts(ps, ps.place(np.array([pose(), pose(0.7)])), 0.01)
    assert [r.severity.value for r in recs] == ["hard"]       # surfaces cross
    # inside an open mesh, no containment can be decided: no record
    recs = check_parts(ps, ps.place(np.array([pose(), pose()])), 0.01)
    assert recs == [] or all(r.severity.value == "hard" for r in recs)


def test_planes_and_focus():
    got = check([("floor", Shape(ShapeType.PLANE, [])), ("a", CUBE), ("sunk/b", CUBE), ("sunk/c", CUBE)],
                [pose(), pose(0, 0, 0.5), pose(3, 0, 0.2), pose(3.5, 0, 0.2)])
    assert ("floor", "a") not in got                  # resting on the floor: touching
    assert got[("floor", "sunk/b")][2] == pytest.approx(-0.3)
    ps = PartSet.build(["floor", "a", "sunk/b", "sunk/c"], [Shape(ShapeType.PLANE, []), CUBE, CUBE, CUBE])
    recs = check_parts(ps, ps.place(np.array([pose(), pose(0, 0, 0.5), pose(3, 0, 0.2), pose(3.5, 0, 0.2)])),
                       0.01, focus=ps.select("sunk/c"))
    assert {(r.a, r.b) for r in recs} == {("floor", "sunk/c"), ("sunk/b", "sunk/c")}


def test_checker_checks_same_body_pairs_once_and_replays_them():
    ps = PartSet.build(["a", "b", "c"], [CUBE, CUBE, CUBE], groups=["body", "body", "other"])
    pc = PartChecker(ps, 0.01)
    first = pc.check(np.array([pose(), pose(0.9), pose(5)]))
    assert {(r.a, r.b) for r in first} == {("a", "b")}
    # b moved away in the poses, but a and b share a rigid body: the answer is replayed
    later = pc.check(np.array([pose(), pose(0.9), pose(0.5)]))
    assert {(r.a, r.b) for r in later} == {("a", "b"), ("a", "c"), ("b", "c")}
    # the body moved as a whole: the replayed place moves with it
    moved = pc.check(np.array([pose(0, 0, 10), pose(0.9, 0, 10), pose(5)]))
    ab = [r for r in moved if (r.a, r.b) == ("a", "b")][0]
    first_ab = [r for r in first if (r.a, r.b) == ("a", "b")][0]
    assert np.allclose(ab.where, first_ab.where + [0, 0, 10])


def test_replaying_many_states_gives_each_state_its_own_answer_to_the_bit():
    """replay_many over a batch of turned and moved poses: the records the
    full check replays at each state, places and all, bit for bit."""
    ps = PartSet.build(["a", "b", "c", "d"], [CUBE, CUBE, CUBE, CUBE], groups=["body", "body", "other", "other"])
    pc = PartChecker(ps, 0.01)
    pc.check(np.array([pose(), pose(0.9), pose(9), pose(9.95)]))
    rng = np.random.default_rng(2)
    batch = []
    for _ in range(7):
        q, r = np.linalg.qr(rng.normal(size=(3, 3)))
        q = q * np.sign(np.diag(r)) * np.sign(np.linalg.det(q * np.sign(np.diag(r))))
        carry = np.eye(4)
        carry[:3, :3], carry[:3, 3] = q, rng.uniform(-3, 3, 3)
        turn = np.eye(4)
        turn[:3, :3] = q.T
        batch.append(np.stack([carry @ pose(), carry @ pose(0.9), turn @ pose(9), turn @ pose(9.95)]))
    many = pc.replay_many(np.stack(batch))
    for poses, got in zip(batch, many):
        want = pc.check(poses)[:2]                      # the replayed records come first
        assert [(r.a, r.b) for r in got] == [("a", "b"), ("c", "d")]
        assert [(r.a, r.b, r.min_distance) for r in got] == [(r.a, r.b, r.min_distance) for r in want]
        assert all(np.array_equal(g.where, w.where) for g, w in zip(got, want))
        assert all(np.array_equal(g.where, w.where) for g, w in zip(got, pc.replay(poses)))


def test_tessellation_error_bound_holds():
    for shape in (Shape(ShapeType.SPHERE, [0.7]), Shape(ShapeType.CAPSULE, [0.3, 0.5]),
                  Shape(ShapeType.CYLINDER, [0.4, 0.2]), Shape(ShapeType.ELLIPSOID, [0.5, 0.3, 0.2])):
        surf = part_surface(shape, 2e-3)
        assert surf.closed and 0 < surf.error <= 2e-3
        tm = trimesh.Trimesh(surf.vertices, surf.faces)
        pts, _ = trimesh.sample.sample_surface(tm, 4000, seed=1)
        from cablecheck.checker.shapes import signed_distance
        sd, _ = signed_distance(shape, pts)
        assert np.all(sd <= 1e-12) and -sd.min() <= surf.error + 1e-12
    assert part_surface(CUBE, 1e-3).error == 0.0


def _nested_scene(seed):
    """Random boxes, spheres and capsules in random nested assemblies (some flat, some deep)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 30))
    names, shapes, poses, groups = [], [], [], []
    kinds = [ShapeType.BOX, ShapeType.SPHERE, ShapeType.CAPSULE]
    for k in range(n):
        depth = int(rng.integers(0, 4))
        path = [f"a{rng.integers(0, 3)}" for _ in range(depth)]
        names.append("/".join(path + [f"p{k}"]))
        kind = kinds[rng.integers(0, 3)]
        shapes.append(Shape(kind, list(rng.uniform(0.1, 0.4, 3))))
        t = pose(*(rng.uniform(0, 4, 3) + 2.0 * (path[0] == "a1" if path else 0)))
        q, r = np.linalg.qr(rng.normal(size=(3, 3)))
        q = q * np.sign(np.diag(r))
        t[:3, :3] = q * np.sign(np.linalg.det(q))          # a proper rotation
        if rng.random() < 0.3:
            t[:3, :3] = np.eye(3)
            t[:3, 3] = np.round(t[:3, 3] * 2) / 2       # flush faces: touching boxes
        poses.append(t)
        groups.append(f"g{rng.integers(0, 3)}")
    if rng.random() < 0.3:
        names.append("floor")
        shapes.append(Shape(ShapeType.PLANE, []))
        poses.append(pose(z=0.2))
        groups.append("g0")
    return names, shapes, np.array(poses), groups, rng


def _records(recs):
    return [(r.type.value, r.a, r.b, r.severity.value, r.min_distance, tuple(r.where)) for r in recs]


@pytest.mark.parametrize("seed", range(40))
def test_assembly_pruning_gives_identical_records(seed):
    names, shapes, poses, groups, rng = _nested_scene(seed)
    keepout = list(rng.random(len(names)) < 0.1)
    ps = PartSet.build(names, shapes, groups=groups, keepout=keepout, tolerance=0.1)
    clearance = float(rng.choice([0.0, 0.02, 0.1]))
    placed = ps.place(poses)
    focus = ps.select(names[0].split("/")[0]) if seed % 4 == 0 else None
    with_asm = check_parts(ps, placed, clearance, focus)
    assert _records(with_asm) == _records(check_parts(ps, placed, clearance, focus, assemblies=False))
    # step after step, with the groups moving apart from each other
    on = PartChecker(ps, clearance, focus, assemblies=True)
    off = PartChecker(ps, clearance, focus, assemblies=False)
    for step in range(3):
        moved = poses.copy()
        for g in range(3):
            moved[np.array(groups) == f"g{g}", :3, 3] += step * rng.uniform(-0.5, 0.5, 3)
        assert _records(on.check(moved)) == _records(off.check(moved))


@pytest.mark.parametrize("seed", range(12))
def test_batched_probes_equal_pair_by_pair(seed):
    """probes_inside_batch (all pairs in one array, one call per shape type or
    mesh) gives exactly probes_inside pair by pair; check_parts uses it."""
    from cablecheck.checker.sweep import probes_inside, probes_inside_batch

    rng = np.random.default_rng(seed)
    ico = trimesh.creation.icosphere(1, 0.3)
    cube = trimesh.creation.box((0.4, 0.3, 0.5))
    meshes = [mesh_shape(ico.vertices, ico.faces), mesh_shape(cube.vertices, cube.faces),
              mesh_shape(cube.vertices, cube.faces[:-2])]          # the last one open
    kinds = [ShapeType.BOX, ShapeType.SPHERE, ShapeType.CAPSULE, ShapeType.CYLINDER, ShapeType.ELLIPSOID]
    shapes, poses = [], []
    for k in range(int(rng.integers(4, 12))):
        c = int(rng.integers(0, 8))
        shapes.append(Shape(kinds[c], list(rng.uniform(0.05, 0.5, 3))) if c < 5 else meshes[c - 5])
        t = pose(*rng.uniform(0, 0.8, 3))
        q, r = np.linalg.qr(rng.normal(size=(3, 3)))
        q = q * np.sign(np.diag(r))
        t[:3, :3] = q * np.sign(np.linalg.det(q))          # a proper rotation
        poses.append(poses[int(rng.integers(0, k))] if k and rng.random() < 0.2 else t)
    shapes.append(Shape(ShapeType.PLANE, []))
    poses.append(pose(z=0.3))
    ps = PartSet.build([f"p{k}" for k in range(len(shapes))], shapes, tolerance=0.05)
    placed = ps.place(np.array(poses))
    a, b = (x.ravel() for x in np.meshgrid(np.arange(len(shapes)), np.arange(len(shapes))))
    shift = rng.normal(scale=0.2, size=(len(a), 3)) * (rng.random(len(a)) < 0.5)[:, None]
    for sh in (None, shift):
        got = probes_inside_batch(ps, placed, a, b, sh)
        want = [probes_inside(ps, placed, int(x), int(y), None if sh is None else sh[k])
                for k, (x, y) in enumerate(zip(a, b))]
        assert [None if np.isinf(g) else g for g in got.tolist()] == want
        assert any(w is not None for w in want)


@pytest.mark.parametrize("seed", range(5))
def test_moving_pairs_equal_all_pairs_filtered(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 40))
    groups = [f"g{rng.integers(0, 4)}" for _ in range(n)]
    skip = rng.random((n, n)) < 0.2
    skip |= skip.T
    ps = PartSet.build([f"p{k}" for k in range(n)], [box(0.1, 0.1, 0.1)] * n, groups=groups)
    i, j = PartChecker(ps, 0.01, skip=skip).moving_pairs()
    want = [(a, b) for a in range(n) for b in range(a + 1, n) if groups[a] != groups[b] and not skip[a, b]]
    assert list(zip(i.tolist(), j.tolist())) == want


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4])
def test_pairs_at_many_states_are_each_states_own_check(seed):
    """check_pairs_many on primitive pairs (one call for every state), on
    pairs with a mesh or a plane and two boxes apart (laid out once per
    state, the primitive pairs beside them still in one call), and
    check_pairs: each state's records, in their order, are what the
    part-part check of those pairs gives it alone, places bit for bit;
    keep-out zones and a focus included."""
    rng = np.random.default_rng(seed)
    kinds = [ShapeType.BOX, ShapeType.SPHERE, ShapeType.CYLINDER, ShapeType.CAPSULE, ShapeType.ELLIPSOID]
    with_mesh = seed in (2, 4)
    shapes = [Shape(kinds[k], rng.uniform(0.05, 0.3, 3)) for k in rng.integers(0, 5, 5)]
    if with_mesh:
        tm = trimesh.creation.icosphere(subdivisions=1, radius=0.2)
        shapes[0] = mesh_shape(np.asarray(tm.vertices), np.asarray(tm.faces))
    if seed >= 3:           # two boxes (apart at some states), and a plane
        shapes[1] = shapes[3] = Shape(ShapeType.BOX, rng.uniform(0.05, 0.2, 3))
        shapes[4] = Shape(ShapeType.PLANE, [0.0, 0.0, 0.0])
    names = ["p0", "p1", "zone/p2", "p3", "p4"]
    ps = PartSet.build(names, shapes, keepout=[False, False, True, False, False], tolerance=5e-3)
    i, j = np.array([0, 0, 1, 2, 3, 1]), np.array([1, 2, 3, 4, 4, 4])
    batch = np.tile(np.eye(4), (24, 5, 1, 1))
    for s in range(24):
        for k in range(5):
            q, r = np.linalg.qr(rng.normal(size=(3, 3)))
            batch[s, k, :3, :3] = q * np.sign(np.diag(r)) * np.sign(np.linalg.det(q * np.sign(np.diag(r))))
            batch[s, k, :3, 3] = rng.uniform(-0.35, 0.35, 3)
    for focus in (None, ps.select("zone")):
        pc = PartChecker(ps, 0.05, focus)
        many = pc.check_pairs_many(batch, i, j)
        found = 0
        for poses, got in zip(batch, many):
            want = check_parts(ps, ps.place(poses), 0.05, focus, pairs=(i, j))
            for recs in (got, pc.check_pairs(poses, i, j)):
                assert [(r.type, r.a, r.b, r.min_distance, r.severity) for r in recs] == \
                    [(r.type, r.a, r.b, r.min_distance, r.severity) for r in want]
                assert all(np.array_equal(g.where, w.where) for g, w in zip(recs, want))
            found += len(got)
        assert found > 5


# ---- assemblies against an independent reference (python-fcl, closed forms) ----

import fcl  # noqa: E402
from hypothesis import (  # noqa: E402
    example,
    given,
    settings,
    strategies as st,  # noqa: E402
)
from helpers import examples  # noqa: E402
from strategies import rotations  # noqa: E402

_PLATE = trimesh.creation.box((60.0, 40.0, 5.0))
_FOOT = trimesh.creation.box((50.0, 30.0, 5.0))
_PIN = trimesh.creation.cylinder(3.0, 30.0, sections=32)
_BAR = trimesh.creation.box((6.0, 80.0, 6.0))
_TORUS = trimesh.creation.torus(30.0, 6.0, major_sections=48, minor_sections=16)
_SLAB = trimesh.creation.box((80.0, 80.0, 10.0))


def _fcl(tm, shape, t, scale):
    """A python-fcl object of a trimesh mesh (or a primitive ``shape``) scaled and posed by t."""
    if shape is None:
        geom = fcl.BVHModel()
        geom.beginModel(len(tm.vertices), len(tm.faces))
        geom.addSubModel(np.asarray(tm.vertices, float) * scale, np.asarray(tm.faces, np.int32))
        geom.endModel()
    else:
        s = np.asarray(shape.size, float)
        geom = {ShapeType.BOX: lambda: fcl.Box(*(2 * s)), ShapeType.SPHERE: lambda: fcl.Sphere(s[0]),
                ShapeType.CYLINDER: lambda: fcl.Cylinder(s[0], 2 * s[1]),
                ShapeType.CAPSULE: lambda: fcl.Capsule(s[0], 2 * s[1]),
                ShapeType.ELLIPSOID: lambda: fcl.Ellipsoid(*s)}[shape.type]()
    return fcl.CollisionObject(geom, fcl.Transform(t[:3, :3], t[:3, 3]))


def _scaled_mesh(tm, scale):
    return mesh_shape(np.asarray(tm.vertices) * scale, np.asarray(tm.faces))


def _carry(rot, far, scale):
    t = np.eye(4)
    t[:3, :3] = rot
    t[:3, 3] = np.array([1.0, -0.7, 0.4]) * far * scale
    return t


def _turned(axis, angle, pos):
    from scipy.spatial.transform import Rotation
    t = np.eye(4)
    t[:3, :3] = Rotation.from_rotvec(np.asarray(axis, float) * angle).as_matrix()
    t[:3, 3] = pos
    return t


@settings(max_examples=25)
@given(rotations(), st.sampled_from([0.0, 1e4]), st.sampled_from([1.0, 1e-3]), st.sampled_from([0.1, 2.0]),
       st.booleans(), st.floats(-14.0, 14.0), st.floats(0.0, 2 * np.pi), st.floats(-0.3, 0.3))
def test_pins_through_plates_and_bars_through_feet_are_hard(rot, far, scale, depth, primitive, y, spin, tilt):
    """A pin cutting into a plate's side and a bar through a bracket's foot
    (mesh or primitive; no vertex of either inside the other), in mm or m,
    far from the origin: python-fcl finds them colliding and the check
    reports them hard, its depth a lower bound (the pin moved out by
    ``depth`` along x, the bar by ``depth`` along z, clears them); moved
    out a further ``depth``, neither is hard and fcl finds no collision."""
    carry = _carry(rot, far, scale)
    pin = Shape(ShapeType.CYLINDER, [3.0 * scale, 15.0 * scale]) if primitive else _scaled_mesh(_PIN, scale)
    bar = Shape(ShapeType.BOX, [3.0 * scale, 40.0 * scale, 3.0 * scale]) if primitive else _scaled_mesh(_BAR, scale)
    cases = [("plate", _PLATE, "pin", _PIN, pin, lambda out: _turned([0, 0, 1], spin, np.array([33.0 - depth + out, y, 0.0]) * scale)),
             ("foot", _FOOT, "bar", _BAR, bar, lambda out: _turned([0, 0, 1], tilt, np.array([y, 0.0, 5.5 - depth + out]) * scale))]
    for name_a, tm_a, name_b, tm_b, shape_b, place in cases:
        ps = PartSet.build([name_a, name_b], [_scaled_mesh(tm_a, scale), shape_b], tolerance=0.25 * scale)
        for out, overlapping in ((0.0, True), (2 * depth, False)):
            poses = np.array([carry, carry @ place(out)])
            ref = fcl.collide(_fcl(tm_a, None, poses[0], scale), _fcl(tm_b, shape_b if primitive else None, poses[1], scale),
                              fcl.CollisionRequest(), fcl.CollisionResult())
            assert bool(ref) == overlapping
            recs = check_parts(ps, ps.place(poses), 0.05 * scale)
            hard = [r for r in recs if r.severity.value == "hard"]
            if overlapping:
                assert len(hard) == 1 and 0 < -hard[0].min_distance <= depth * scale * (1 + 1e-9) + 1e-12 * far * scale
            else:
                assert not hard


_CURVED = [(Shape(ShapeType.SPHERE, [4.0]), 4.0, None), (Shape(ShapeType.CYLINDER, [4.0, 8.0]), 4.0, [1, 0, 0]),
           (Shape(ShapeType.CYLINDER, [4.0, 8.0]), 8.0, None), (Shape(ShapeType.CAPSULE, [3.0, 6.0]), 3.0, [1, 0, 0]),
           (Shape(ShapeType.ELLIPSOID, [6.0, 4.0, 3.0]), 3.0, None)]


def _scaled(shape, scale):
    return Shape(shape.type, list(np.asarray(shape.size) * scale))


@settings(max_examples=30)
@given(rotations(), st.sampled_from([0.0, 1e4]), st.sampled_from([1.0, 1e-3]), st.integers(0, len(_CURVED) - 1),
       st.floats(0.1, 0.5), st.floats(-20, 20), st.floats(-20, 20), st.floats(0, 2 * np.pi))
def test_curved_primitives_near_a_mesh_face_are_soft_at_their_gap(rot, far, scale, k, gap, x, y, spin):
    """A sphere, a cylinder (side or end), a capsule or an ellipsoid 0.1 to
    0.5 mm above a mesh slab's face (its distance is the gap, by
    construction; fcl agrees to 1e-5 mm), with a coarse tessellation (0.25
    mm, more than the gap): soft, never hard, at the gap to rounding (1e-11
    mm near the origin, 1e-9 mm 1e4 away), never above it."""
    shape, lift, axis = _CURVED[k]
    local = _turned([0, 0, 1], spin, np.array([x, y, 5.0 + lift + gap]) * scale)
    if axis is not None:
        local = local @ _turned(axis, np.pi / 2, np.zeros(3))
    carry = _carry(rot, far, scale)
    poses = np.array([carry, carry @ local])
    sh = _scaled(shape, scale)
    if scale == 1.0:                     # (fcl's curved shapes in m are off by up to 1e-3 of the gap)
        ref = fcl.distance(_fcl(_SLAB, None, poses[0], scale), _fcl(None, sh, poses[1], scale),
                           fcl.DistanceRequest(), fcl.DistanceResult())
        assert ref == pytest.approx(gap, abs=1e-5)
    ps = PartSet.build(["slab", "c"], [_scaled_mesh(_SLAB, scale), sh], tolerance=0.25 * scale)
    recs = check_parts(ps, ps.place(poses), 1.0 * scale)
    assert [(r.a, r.b, r.severity.value) for r in recs] == [("slab", "c", "soft")]
    rounding = 1e-13 * (100.0 + far) * scale                 # of coordinates up to 100 + far
    assert recs[0].min_distance == pytest.approx(gap * scale, abs=rounding)
    assert recs[0].min_distance <= gap * scale + rounding


@settings(max_examples=30)
@given(rotations(), st.integers(0, len(_CURVED) - 1), st.floats(0.0, 2 * np.pi), st.floats(-1.0, 1.0),
       st.floats(-0.5, 1.0))
@example(np.eye(3), 0, 0.0, 0.0, -0.000362896999539534)    # a 0.36 um overlap, read hard at its depth
def test_curved_primitives_near_a_torus_against_fcl(rot, k, around, tilt, gap):
    """A curved primitive at a drawn pose near a torus mesh (from
    trimesh.creation.torus), overlapping it by up to 0.5 mm or up to 1 mm
    clear (placed by bisection on fcl's distance): hard where it overlaps by
    more than 1e-3 mm (fcl collides too; the depth never above the overlap),
    under that hard or not but never deeper than the overlap, never hard
    where fcl finds it clear, and there at fcl's distance to 2e-5
    mm, never above it (fcl's capsules measure up to 6e-6 mm high: a capsule
    0.8125 mm from the torus by fcl is 0.81249379 by fcl's own spheres along
    its axis, 0.81249379 here)."""
    shape, lift, _ = _CURVED[k]
    t = np.eye(4)
    t[:3, :3] = rot
    # the primitive's centre along a direction from the tube's circle, from the tube's
    # surface (fcl sees the mesh as a surface: a part wholly inside it does not collide)
    # out to where fcl says `gap`
    d = np.array([np.cos(around) * np.cos(tilt), np.sin(around) * np.cos(tilt), np.sin(tilt)])
    ring = np.array([np.cos(around), np.sin(around), 0.0]) * 30.0
    slab = _fcl(_TORUS, None, np.eye(4), 1.0)

    def dist_at(c):
        t[:3, 3] = ring + d * c
        return fcl.distance(slab, _fcl(None, shape, t, 1.0), fcl.DistanceRequest(), fcl.DistanceResult())

    lo, hi = 6.0, 30.0                    # bisect the centre's offset to the drawn gap (fcl's distance)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if dist_at(mid) <= max(gap, 0.0) + 1e-9 else (lo, mid)   # (fcl: ~0 overlapping)
    c = hi if gap >= 0 else hi + gap
    ref = dist_at(c)
    poses = np.array([np.eye(4), t.copy()])
    ref_hit = fcl.collide(slab, _fcl(None, shape, poses[1], 1.0), fcl.CollisionRequest(), fcl.CollisionResult())
    ps = PartSet.build(["torus", "c"], [_scaled_mesh(_TORUS, 1.0), shape], tolerance=0.25)
    recs = check_parts(ps, ps.place(poses), 2.0)
    got = {r.severity.value: r.min_distance for r in recs}
    touch = float(ps.touch(np.array([0]), np.array([1]))[0])
    if gap < -1e-3:
        assert ref_hit and "hard" in got and -got["hard"] <= -gap + 1e-6
    elif gap < 0.0:     # overlapping by under 1e-3 mm, where fcl reads about 0: hard or not, never deeper
        assert "hard" not in got or -got["hard"] <= -gap + 1e-6
    else:
        assert "hard" not in got
        if ref > touch + 2e-5:
            assert not ref_hit and got["soft"] == pytest.approx(ref, abs=2e-5) and got["soft"] <= ref + 1e-9


_MESHES = [trimesh.creation.torus(30.0, 6.0, major_sections=24, minor_sections=10), trimesh.creation.box((60, 40, 4)),
           trimesh.creation.cylinder(3.0, 80.0, sections=24), trimesh.creation.annulus(10.0, 20.0, 8.0, sections=24),
           trimesh.creation.box((50, 30, 5))]


@settings(max_examples=12)
@given(st.lists(st.tuples(st.integers(0, 6), st.integers(0, 6)), min_size=1, max_size=6), st.integers(1, 24),
       st.integers(0, 2**32 - 1))
def test_pairs_of_meshes_at_many_states_are_each_states_own_check(pairs, n_states, seed):
    """check_pairs_many on any subset of pairs among meshes with trees of
    different depths (a torus, plates, a rod, an annulus) and curved
    primitives, at many states drawn near each other: each state's records
    are those of check_parts of those pairs at that state alone (the trees
    laid out per state must be those parts' trees: a subset used to crash
    with an IndexError or answer another part's nodes)."""
    rng = np.random.default_rng(seed)
    shapes = [mesh_shape(np.asarray(m.vertices), np.asarray(m.faces)) for m in _MESHES]
    shapes += [Shape(ShapeType.CYLINDER, [2.0, 10.0]), Shape(ShapeType.SPHERE, [5.0])]
    names = [f"p{k}" for k in range(len(shapes))]
    ps = PartSet.build(names, shapes, keepout=[k == 5 for k in range(len(shapes))], tolerance=0.1)
    ij = sorted({(min(a, b), max(a, b)) for a, b in pairs if a != b})
    if not ij:
        return
    i, j = (np.array(x, np.int64) for x in zip(*ij))
    from scipy.spatial.transform import Rotation
    batch = np.tile(np.eye(4), (n_states, len(shapes), 1, 1))
    batch[:, :, :3, :3] = Rotation.random(n_states * len(shapes), random_state=seed % 2**31).as_matrix().reshape(
        n_states, len(shapes), 3, 3)
    batch[:, :, :3, 3] = rng.uniform(-25, 25, (n_states, len(shapes), 3))
    pc = PartChecker(ps, 2.0)
    many = pc.check_pairs_many(batch, i, j)
    for poses, got in zip(batch, many):
        want = check_parts(ps, ps.place(poses), 2.0, pairs=(i, j))
        assert _records(got) == _records(want)


@pytest.mark.parametrize("primitive", [False, True])
def test_rods_and_bars_through_a_foot_are_hard_at_every_step_they_overlap(primitive):
    """A rod crossing a bracket's foot from side to side (its axis through
    the foot's thickness, no vertex of either inside the other) and a bar
    lowered through it, step by step, checked state by state and in one
    batch of states: hard at every step the overlap (closed form, from the
    rod's or bar's offset) is at least 0.1 mm, never hard where it is clear
    by 0.1 mm, the depth never above the overlap."""
    foot = _scaled_mesh(_FOOT, 1.0)
    rod = Shape(ShapeType.CYLINDER, [3.0, 15.0]) if primitive else _scaled_mesh(_PIN, 1.0)
    bar = Shape(ShapeType.BOX, [3.0, 40.0, 3.0]) if primitive else _scaled_mesh(_BAR, 1.0)
    ps = PartSet.build(["foot", "rod", "bar"], [foot, rod, bar], groups=["f", "r", "b"], tolerance=0.25)
    n = 300
    x = np.linspace(-40.0, 40.0, n)                    # the rod's axis crosses the foot's 50 mm along x
    z = np.linspace(12.0, -12.0, n)                    # the bar's centre, lowered through its 5 mm
    poses = np.tile(np.eye(4), (n, 3, 1, 1))
    poses[:, 1, :3, 3] = np.stack([x, np.full(n, 4.0), np.zeros(n)], axis=1)
    poses[:, 2, :3, 3] = np.stack([np.full(n, 7.0), np.zeros(n), z], axis=1)
    # the penetration depth (the shortest move apart) along the motion: the rod's 3 mm radius
    # into the foot's |x| <= 25, else 14 along y (the 32-gon inscribed within 0.015 mm of the
    # circle); the bar's 3 mm half height into the foot's |z| <= 2.5 (moved up or down)
    slack = 0.0 if primitive else 0.015
    rod_depth = np.minimum(28.0 - np.abs(x), 14.0) - slack
    bar_depth = 5.5 - np.abs(z)
    pc = PartChecker(ps, 0.5)
    i, j = np.array([0, 0]), np.array([1, 2])
    many = pc.check_pairs_many(poses, i, j)
    hits = 0
    for k in range(n):
        for recs in (many[k], check_parts(ps, ps.place(poses[k]), 0.5, pairs=(i, j))):
            hard = {r.b: -r.min_distance for r in recs if r.severity.value == "hard" and r.a == "foot"}
            for name, depth in (("rod", rod_depth[k]), ("bar", bar_depth[k])):
                if depth >= 0.1:
                    assert name in hard and hard[name] <= depth + slack + 1e-9, (k, name)
                    hits += 1
                elif depth <= -0.1:
                    assert name not in hard, (k, name)
    assert hits > 300


def test_degenerate_triangles_near_curved_primitives_and_crossings_raise_nothing():
    """A mesh with zero-area triangles (a repeated corner, three corners on a
    line) beside and through curved primitives and a box: no warning, no
    NaN; the sphere above the slab is soft at its gap, the one through it
    hard, the box through it hard."""
    import warnings

    v = np.asarray(_SLAB.vertices, float)
    f = np.asarray(_SLAB.faces)
    extra_v = np.array([[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [2.0, 0.0, 5.0]])
    faces = np.vstack([f, [[0, 0, 1]], len(v) + np.array([[0, 1, 2]])])
    slab = mesh_shape(np.vstack([v, extra_v]), faces)
    shapes = [slab, Shape(ShapeType.SPHERE, [4.0]), Shape(ShapeType.CYLINDER, [2.0, 20.0]), box(3.0, 3.0, 20.0),
              Shape(ShapeType.ELLIPSOID, [5.0, 3.0, 2.0])]
    poses = [pose(), pose(0.5, 0.0, 9.3), pose(20.0, 5.0, 0.0), pose(-20.0, 0.0, 0.0), pose(0.0, 20.0, -7.2)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="raise"):
            ps = PartSet.build([f"p{k}" for k in range(len(shapes))], shapes, tolerance=0.25)
            got = {(r.a, r.b): (r.type.value, r.severity.value, r.min_distance)
                   for r in check_parts(ps, ps.place(np.array(poses)), 1.0)}
    assert all(np.isfinite(d) for _, _, d in got.values())
    assert got[("p0", "p1")][1] == "soft" and got[("p0", "p1")][2] == pytest.approx(0.3, abs=1e-12)
    assert got[("p0", "p2")][1] == "hard" and got[("p0", "p3")][1] == "hard"
    assert got[("p0", "p4")][1] == "soft" and got[("p0", "p4")][2] == pytest.approx(0.2, abs=1e-12)


_ASSEMBLY_MESHES = {"torus": _TORUS, "box": trimesh.creation.box((30.0, 20.0, 8.0)),
                    "cylinder": trimesh.creation.cylinder(6.0, 24.0, sections=20),
                    "annulus": trimesh.creation.annulus(5.0, 12.0, 6.0, sections=20),
                    "icosphere": trimesh.creation.icosphere(2, 9.0)}
_ASSEMBLY_PRIMITIVES = {"sphere": Shape(ShapeType.SPHERE, [5.0]), "cylinder_p": Shape(ShapeType.CYLINDER, [4.0, 9.0]),
                        "capsule": Shape(ShapeType.CAPSULE, [3.0, 7.0]),
                        "ellipsoid": Shape(ShapeType.ELLIPSOID, [8.0, 5.0, 3.0]),
                        "box_p": Shape(ShapeType.BOX, [6.0, 4.0, 3.0])}


@settings(max_examples=30)
@given(st.sampled_from(sorted(_ASSEMBLY_MESHES)), st.sampled_from(sorted(_ASSEMBLY_MESHES) + sorted(_ASSEMBLY_PRIMITIVES)),
       rotations(), rotations(), rotations(), st.floats(-1.0, 1.0), st.sampled_from([0.0, 3e3]))
def test_meshes_against_meshes_and_primitives_by_fcl(name_a, name_b, rot_a, rot_b, rot_d, gap, far):
    """A mesh (torus, box, cylinder, annulus, icosphere from
    trimesh.creation) and a mesh or primitive at drawn orientations, the
    second brought along a drawn direction to a drawn gap by python-fcl's
    distance (the first place, coming in, where fcl says that gap), or
    pushed that far further in: clear by 0.01 mm or more, never hard and at
    fcl's distance (2e-5 mm; fcl's curved primitives run up to 6e-6 mm
    high) when below the clearance, never above it; in by 0.01 mm or more,
    fcl collides and the check is hard, its depth at most the push (moving
    back by it separates the parts)."""
    mesh_a = _ASSEMBLY_MESHES[name_a]
    mesh_b = _ASSEMBLY_MESHES.get(name_b)
    shape_b = _ASSEMBLY_PRIMITIVES.get(name_b)
    base = _carry(rot_a, far, 1.0)
    obj_a = _fcl(mesh_a, None, base, 1.0)
    direction = rot_d[:, 0]
    t = np.eye(4)
    t[:3, :3] = rot_b

    def at(c):
        t[:3, 3] = base[:3, 3] + direction * c
        return t.copy()

    def fcl_distance(c):
        return fcl.distance(obj_a, _fcl(mesh_b, shape_b, at(c), 1.0), fcl.DistanceRequest(), fcl.DistanceResult())

    target = max(gap, 0.0)
    cs = np.linspace(80.0, 0.0, 161)                # coming in from far: the first offset within the gap
    k = next((k for k, c in enumerate(cs) if fcl_distance(c) <= target + 1e-9), None)
    if k is None or k == 0:
        return
    lo, hi = cs[k], cs[k - 1]
    for _ in range(45):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fcl_distance(mid) <= target + 1e-9 else (lo, mid)
    c = hi if gap >= 0 else hi + gap
    poses = np.array([base, at(c)])
    ref = fcl_distance(c)
    hit = fcl.collide(obj_a, _fcl(mesh_b, shape_b, poses[1], 1.0), fcl.CollisionRequest(), fcl.CollisionResult())
    shape_b_here = _scaled_mesh(mesh_b, 1.0) if shape_b is None else shape_b
    ps = PartSet.build(["a", "b"], [_scaled_mesh(mesh_a, 1.0), shape_b_here], tolerance=0.25)
    recs = check_parts(ps, ps.place(poses), 2.0)
    got = {r.severity.value: r.min_distance for r in recs}
    rounding = 1e-12 * (100.0 + far)
    if gap >= 0.01:
        assert not hit and "hard" not in got
        if ref < 2.0 - 2e-5:
            assert got["soft"] == pytest.approx(ref, abs=2e-5 + rounding) and got["soft"] <= ref + rounding
    elif gap <= -0.01:
        assert hit and "hard" in got and -got["hard"] <= -gap + 1e-6 + rounding


_EL = trimesh.util.concatenate([trimesh.creation.box((30.0, 8.0, 8.0)),
                                trimesh.creation.box((8.0, 30.0, 8.0)).apply_translation([11.0, 11.0, 0.0])])


@settings(max_examples=examples(25), deadline=None)
@given(rotations(), rotations(), st.floats(-40.0, 40.0), st.floats(-40.0, 40.0), st.floats(-40.0, 40.0),
       st.sampled_from(["el", "pin", "sphere", "box"]))
def test_pair_values_are_lower_bounds_exact_within_reach(ra, rb, x, y, z, other):
    """`pair_values` against python-fcl's distance of the same two solids: never above it (a lower bound,
    what the active part pairs' condition needs), and within 1e-6 mm of it where fcl finds the solids
    within the reach and apart (an L-shaped mesh against a mesh, a curved primitive, a box); with
    `exact_below`, the convex hulls' bound (the L's hull spans its notch) where it is past that, else
    the same measure."""
    from cablecheck.checker.parts import pair_values

    shapes = {"el": (mesh_shape(_EL.vertices, _EL.faces), None, _EL),
              "pin": (Shape(ShapeType.CYLINDER, [3.0, 15.0]), ShapeType.CYLINDER, None),
              "sphere": (Shape(ShapeType.SPHERE, [9.0]), ShapeType.SPHERE, None),
              "box": (Shape(ShapeType.BOX, [10.0, 4.0, 6.0]), ShapeType.BOX, None)}
    sb, kind_b, tm_b = shapes[other]
    ps = PartSet.build(["a", "b"], [mesh_shape(_EL.vertices, _EL.faces), sb], tolerance=0.05)
    ta, tb = np.eye(4), np.eye(4)
    ta[:3, :3], tb[:3, :3], tb[:3, 3] = ra, rb, [x, y, z]
    reach = 12.0
    value = pair_values(ps, ps.place(np.stack([ta, tb])), np.array([0]), np.array([1]), reach)[0]
    ref_b = _fcl(tm_b, sb if tm_b is None else None, tb, 1.0)
    res = fcl.DistanceResult()
    d = fcl.distance(_fcl(_EL, None, ta, 1.0), ref_b, fcl.DistanceRequest(), res)
    collide = fcl.collide(_fcl(_EL, None, ta, 1.0), ref_b, fcl.CollisionRequest(), fcl.CollisionResult())
    if collide:
        assert value <= 1e-6
    else:
        assert value <= d + 1e-6
        if d < reach - 0.01:
            assert value >= d - 1e-3 - ps.error[1]
    # with exact_below: the hulls' bound where it proves more than 2 apart, never above the measure
    hulled = pair_values(ps, ps.place(np.stack([ta, tb])), np.array([0]), np.array([1]), reach, 2.0)[0]
    assert hulled == value or hulled > 2.0 - ps.error[0] - ps.error[1]
    if not collide:
        assert hulled <= d + 1e-6
    if ps.error[1] == 0.0:                     # the measure of a curved part has its error off twice
        assert hulled <= value + 1e-9


@settings(max_examples=examples(25), deadline=None)
@given(rotations(), rotations(), st.floats(-40.0, 40.0), st.floats(-40.0, 40.0), st.floats(-40.0, 40.0),
       rotations(), st.floats(-6.0, 6.0), st.floats(-6.0, 6.0), st.sampled_from(["el", "pin", "box"]))
def test_hull_separation_along_a_carried_axis_is_a_lower_bound(ra, rb, x, y, z, turn, dx, dy, other):
    """The axis the hulls were found apart along, carried with either part to a drawn later pose
    (the second part turned and moved), never proves the parts farther apart than python-fcl's
    distance there; and at the start it is the hull bound itself."""
    from cablecheck.checker.parts import hull_separations_along, pair_values_axes

    shapes = {"el": (mesh_shape(_EL.vertices, _EL.faces), None, _EL),
              "pin": (Shape(ShapeType.CYLINDER, [3.0, 15.0]), None, None),
              "box": (Shape(ShapeType.BOX, [10.0, 4.0, 6.0]), None, None)}
    sb, _, tm_b = shapes[other]
    ps = PartSet.build(["a", "b"], [mesh_shape(_EL.vertices, _EL.faces), sb], tolerance=0.05)
    ta, tb = np.eye(4), np.eye(4)
    ta[:3, :3], tb[:3, :3], tb[:3, 3] = ra, rb, [x, y, z]
    start = np.stack([ta, tb])
    value, axis = pair_values_axes(ps, ps.place(start), np.array([0]), np.array([1]), 12.0, 0.5)
    if not np.any(axis[0]):
        return                                                      # measured by its triangles
    at_start = hull_separations_along(ps, start[None], 0, 1, axis[0], start)[0]
    assert abs(at_start - value[0]) <= 1e-9 or (value[0] >= 12.0 - ps.error[1] and at_start >= value[0] - 1e-9)
    later = start.copy()
    later[1, :3, :3] = turn @ rb
    later[1, :3, 3] += [dx, dy, 0.0]
    sep = hull_separations_along(ps, later[None], 0, 1, axis[0], start)[0]
    ref_b = _fcl(tm_b, sb if tm_b is None else None, later[1], 1.0)
    a_obj = _fcl(_EL, None, later[0], 1.0)
    if fcl.collide(a_obj, ref_b, fcl.CollisionRequest(), fcl.CollisionResult()):
        assert sep <= 1e-6
    else:
        assert sep <= fcl.distance(a_obj, ref_b, fcl.DistanceRequest(), fcl.DistanceResult()) + 1e-6


@settings(max_examples=12)
@given(st.lists(st.tuples(st.integers(0, 6), st.integers(0, 6)), min_size=1, max_size=6), st.integers(1, 12),
       st.integers(0, 2**32 - 1), st.sampled_from([0.0, 2.0, 8.0]))
def test_triangle_pairs_left_out_by_their_bounds_change_no_record(pairs, n_states, seed, clearance):
    """The triangle pairs whose boxes, or the side of one's plane the other
    lies on, put them farther than the least distance found first (plus a
    curved primitive's tessellation error) are not measured: the records of
    meshes and curved primitives at drawn poses are those of measuring every
    pair (FIRST_PASS past any pair's count), to the bit."""
    import cablecheck.checker.parts as parts_module

    rng = np.random.default_rng(seed)
    shapes = [mesh_shape(np.asarray(m.vertices), np.asarray(m.faces)) for m in _MESHES]
    shapes += [Shape(ShapeType.CYLINDER, [2.0, 10.0]), Shape(ShapeType.SPHERE, [5.0])]
    ps = PartSet.build([f"p{k}" for k in range(len(shapes))], shapes, tolerance=0.1)
    ij = sorted({(min(a, b), max(a, b)) for a, b in pairs if a != b})
    if not ij:
        return
    i, j = (np.array(x, np.int64) for x in zip(*ij))
    from scipy.spatial.transform import Rotation
    for k in range(n_states):
        poses = np.tile(np.eye(4), (len(shapes), 1, 1))
        poses[:, :3, :3] = Rotation.random(len(shapes), random_state=(seed + k) % 2**31).as_matrix()
        poses[:, :3, 3] = rng.uniform(-30, 30, (len(shapes), 3))
        placed = ps.place(poses)
        got = check_parts(ps, placed, clearance, pairs=(i, j))
        first = parts_module.FIRST_PASS
        try:
            parts_module.FIRST_PASS = 10**9
            want = check_parts(ps, placed, clearance, pairs=(i, j))
        finally:
            parts_module.FIRST_PASS = first
        assert _records(got) == _records(want)


@pytest.mark.parametrize("seed", range(4))
def test_pairs_at_many_states_checked_a_few_states_a_call_are_each_states_own_check(seed):
    """With a small TILE_TRIANGLES the states of check_pairs_many are laid out
    and checked a few at a time (a large mesh at a long batch): each
    state's records are still those of check_parts at that state alone."""
    import cablecheck.checker.parts as parts_module
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    shapes = [mesh_shape(np.asarray(m.vertices), np.asarray(m.faces)) for m in _MESHES]
    shapes += [Shape(ShapeType.CYLINDER, [2.0, 10.0]), Shape(ShapeType.SPHERE, [5.0])]
    ps = PartSet.build([f"p{k}" for k in range(len(shapes))], shapes, tolerance=0.1)
    i, j = np.array([0, 0, 3, 5]), np.array([1, 6, 4, 6])
    n_states = 23
    batch = np.tile(np.eye(4), (n_states, len(shapes), 1, 1))
    batch[:, :, :3, :3] = Rotation.random(n_states * len(shapes), random_state=seed).as_matrix().reshape(
        n_states, len(shapes), 3, 3)
    batch[:, :, :3, 3] = rng.uniform(-25, 25, (n_states, len(shapes), 3))
    most = parts_module.TILE_TRIANGLES
    try:
        parts_module.TILE_TRIANGLES = 2000          # 1-2 states a call for these parts
        many = PartChecker(ps, 2.0).check_pairs_many(batch, i, j)
    finally:
        parts_module.TILE_TRIANGLES = most
    assert sum(len(r) for r in many) > 0
    for poses, got in zip(batch, many):
        assert _records(got) == _records(check_parts(ps, ps.place(poses), 2.0, pairs=(i, j)))
