"""Translational sweep: analytic first contacts, thin plates, grazing, start overlap, assemblies."""

import numpy as np
import pytest
import trimesh

from cablecheck.checker.partset import PartSet
from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape
from cablecheck.checker.sweep import sweep


def pose(x=0.0, y=0.0, z=0.0, rot=None):
    t = np.eye(4)
    t[:3, 3] = [x, y, z]
    if rot is not None:
        t[:3, :3] = rot
    return t


def box(*h):
    return Shape(ShapeType.BOX, list(h))


def run(parts, poses, direction, distance, mover="m", **kw):
    names = [n for n, _ in parts]
    ps = PartSet.build(names, [s for _, s in parts], tolerance=kw.pop("tolerance", 1e-4))
    moving = ps.select(mover)
    return sweep(ps, ps.place(np.array(poses)), moving, np.asarray(direction, float), distance, **kw)


def hits(result):
    return {h.part: h.distance for h in result.hits}


def test_axis_aligned_boxes_exact_distance_and_order():
    r = run([("m", box(0.5, 0.5, 0.5)), ("a", box(0.5, 0.5, 0.5)), ("b", box(0.2, 0.2, 0.2)),
             ("far", box(0.5, 0.5, 0.5)), ("beside", box(0.5, 0.5, 0.5))],
            [pose(), pose(3), pose(6, 0.3, -0.3), pose(30), pose(3, 2)], [1, 0, 0], 20.0)
    assert hits(r) == {"a": 2.0, "b": pytest.approx(5.3, abs=1e-12)}
    assert [h.part for h in r.hits] == ["a", "b"]
    assert r.hits[0].where[0] == pytest.approx(2.5)
    assert r.overlapping == ()


def test_direction_need_not_be_unit_and_distance_limits():
    parts = [("m", box(0.5, 0.5, 0.5)), ("a", box(0.5, 0.5, 0.5))]
    assert hits(run(parts, [pose(), pose(0, 0, 3)], [0, 0, 7], 2.0)) == {"a": 2.0}
    assert hits(run(parts, [pose(), pose(0, 0, 3)], [0, 0, 7], 1.999)) == {}


def test_diagonal_direction_against_rotated_box():
    c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)
    rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    # a unit cube rotated 45 degrees about z presents an edge at x = 5 - sqrt(2)/2
    r = run([("m", box(0.5, 0.5, 0.5)), ("a", box(0.5, 0.5, 0.5))], [pose(), pose(5, 0, 0, rz)],
            [1, 0, 0], 10.0)
    assert hits(r)["a"] == pytest.approx(5 - np.sqrt(0.5) - 0.5, abs=1e-12)


def test_spheres_within_tessellation_error():
    tol = 1e-3
    r = run([("m", Shape(ShapeType.SPHERE, [1.0])), ("a", Shape(ShapeType.SPHERE, [0.5]))],
            [pose(), pose(10, 0.3)], [1, 0, 0], 20.0, tolerance=tol)
    exact = 10 - np.sqrt(1.5 ** 2 - 0.3 ** 2)
    # inscribed tessellations (within tol of each sphere) meet a little later, never earlier;
    # the contact normal is within 12 degrees of the travel here
    assert exact - 1e-12 <= hits(r)["a"] <= exact + 2 * tol / 0.97


def test_thin_plate_a_coarse_sampler_steps_over():
    # 1e-4 thick plate; a sampler with 1 mm steps would jump it
    r = run([("m", box(0.5, 0.5, 0.5)), ("plate", box(5e-5, 2, 2))], [pose(), pose(3.2)], [1, 0, 0], 10.0)
    assert hits(r) == {"plate": pytest.approx(3.2 - 5e-5 - 0.5, abs=1e-12)}


def test_grazing_flush_faces_slide_past_but_pushing_in_hits():
    parts = [("m", box(0.5, 0.5, 0.5)), ("rail", box(5, 0.5, 0.5))]
    poses = [pose(), pose(3, 1.0)]          # rail's face flush with m's +y face
    assert hits(run(parts, poses, [1, 0, 0], 10.0)) == {}           # sliding along: touching only
    assert hits(run(parts, poses, [0, 1, 0], 10.0)) == {"rail": 0.0}   # pushed into it at once
    assert hits(run(parts, poses, [0, -1, 0], 10.0)) == {}          # pulled away


def test_edge_grazing_box_corner_line_is_not_a_hit():
    # a box whose edge runs exactly along the swept volume's edge
    parts = [("m", box(0.5, 0.5, 0.5)), ("e", box(0.5, 0.5, 0.5))]
    assert hits(run(parts, [pose(), pose(4, 1.0, 1.0)], [1, 0, 0], 10.0)) == {}
    assert hits(run(parts, [pose(), pose(4, 0.999, 0.999)], [1, 0, 0], 10.0)) == {"e": 3.0}


def test_start_overlap_and_containment_are_listed_not_hit():
    r = run([("m", box(0.5, 0.5, 0.5)), ("over", box(0.5, 0.5, 0.5)), ("shell", box(3, 3, 3)),
             ("same", box(0.5, 0.5, 0.5)), ("touch", box(0.5, 0.5, 0.5))],
            [pose(), pose(0.5, 0.5), pose(), pose(), pose(-1.0)], [1, 0, 0], 1.0)
    assert r.overlapping == ("over", "same", "shell")
    assert hits(r) == {}


def test_assembly_moves_as_one_and_only_restricts_targets():
    parts = [("tool/a", box(0.5, 0.5, 0.5)), ("tool/b", box(0.5, 0.5, 0.5)),
             ("frame/x", box(0.5, 0.5, 0.5)), ("rack/y", box(0.5, 0.5, 0.5))]
    poses = [pose(), pose(0, 3), pose(5, 3), pose(7, 0)]
    r = run(parts, poses, [1, 0, 0], 10.0, mover="tool")
    assert hits(r) == {"frame/x": 4.0, "rack/y": 6.0}
    assert {h.part: h.by for h in r.hits} == {"frame/x": "tool/b", "rack/y": "tool/a"}
    ps = PartSet.build([n for n, _ in parts], [s for _, s in parts])
    r2 = sweep(ps, ps.place(np.array(poses)), ps.select("tool"), np.array([1.0, 0, 0]), 10.0,
               against=ps.select("rack"))
    assert hits(r2) == {"rack/y": 6.0}


def test_mesh_matches_box_and_plane_is_exact():
    tm = trimesh.creation.box(extents=[1, 1, 1])
    mesh = mesh_shape(np.asarray(tm.vertices), np.asarray(tm.faces))
    # along +x the mesh cube behaves as the box
    assert hits(run([("m", mesh), ("a", box(0.5, 0.5, 0.5))], [pose(), pose(4)], [1, 0, 0], 10.0)) \
        == {"a": 3.0}
    # along x and down at 45 degrees: the floor (solid below z = -2) is 1.5 below m's
    # bottom, met after 1.5 sqrt(2); the box at x = 4 passes above by then
    r = run([("m", mesh), ("a", box(0.5, 0.5, 0.5)), ("floor", Shape(ShapeType.PLANE, []))],
            [pose(), pose(4), pose(0, 0, -2.0)], [1, 0, -1], 10.0)
    assert hits(r) == {"floor": pytest.approx(1.5 * np.sqrt(2), abs=1e-12)}


def test_translation_and_units_invariance():
    parts = [("m", box(0.5, 0.5, 0.5)), ("a", box(0.2, 0.3, 0.4))]
    base = hits(run(parts, [pose(), pose(3, 0.4, 0.1)], [1, 0, 0], 10.0))["a"]
    far = hits(run(parts, [pose(2e4, 2e4, 2e4), pose(2e4 + 3, 2e4 + 0.4, 2e4 + 0.1)], [1, 0, 0], 10.0))["a"]
    mm = [("m", box(500, 500, 500)), ("a", box(200, 300, 400))]
    in_mm = hits(run(mm, [pose(), pose(3000, 400, 100)], [1, 0, 0], 1e4, tolerance=0.1))["a"]
    assert far == pytest.approx(base, abs=1e-9) and in_mm / 1000 == pytest.approx(base, abs=1e-12)


def test_bad_arguments():
    ps = PartSet.build(["m", "f"], [box(1, 1, 1), Shape(ShapeType.PLANE, [])])
    placed = ps.place(np.array([pose(), pose()]))
    with pytest.raises(ValueError, match="direction"):
        sweep(ps, placed, ps.select("m"), np.zeros(3), 1.0)
    with pytest.raises(ValueError, match="distance"):
        sweep(ps, placed, ps.select("m"), np.array([1.0, 0, 0]), -1.0)
    with pytest.raises(ValueError, match="plane"):
        sweep(ps, placed, ps.select("f"), np.array([1.0, 0, 0]), 1.0)


def _rot(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


@pytest.mark.parametrize("seed", range(25))
def test_first_contact_separates_clear_from_overlap(seed):
    """Random rotated boxes: just before the reported travel the parts are clear,
    just after it they overlap (checked by the independent part-part test)."""
    from cablecheck.checker.parts import check_parts

    rng = np.random.default_rng(seed)
    shapes = [box(*rng.uniform(0.2, 1.0, 3)), box(*rng.uniform(0.05, 1.0, 3))]
    poses = np.array([pose(rot=_rot(rng)), pose(*rng.uniform(-0.6, 0.6, 3) + [4, 0, 0], rot=_rot(rng))])
    ps = PartSet.build(["m", "a"], shapes)
    d = np.array([1.0, 0, 0])
    r = sweep(ps, ps.place(poses), ps.select("m"), d, 10.0)
    if not r.hits:
        assert r.overlapping == ()
        return
    t = r.hits[0].distance

    def hard_at(travel):
        moved = poses.copy()
        moved[0, :3, 3] += travel * d
        return any(x.severity.value == "hard" for x in check_parts(ps, ps.place(moved), 0.0))

    assert not hard_at(t - 1e-6) and hard_at(t + 1e-3)


@pytest.mark.parametrize("seed", range(10))
def test_contained_batch_equals_pair_by_pair(seed):
    """_contained (all moving/candidate pairs in one batch, boxes pruned first)
    marks exactly the parts the pair-by-pair probe test marks."""
    from cablecheck.checker.sweep import _contained, probes_inside

    rng = np.random.default_rng(seed)
    ico = trimesh.creation.icosphere(1, 0.3)
    kinds = [ShapeType.BOX, ShapeType.SPHERE, ShapeType.CAPSULE, ShapeType.CYLINDER, ShapeType.ELLIPSOID]
    n = int(rng.integers(4, 14))
    shapes = [Shape(kinds[c], list(rng.uniform(0.05, 0.5, 3))) if c < 5 else mesh_shape(ico.vertices, ico.faces)
              for c in rng.integers(0, 6, n)]
    poses = [pose(*rng.uniform(0, 1.0, 3), rot=_rot(rng)) for _ in range(n)]
    names = [f"m/p{k}" if k < 3 else f"p{k}" for k in range(n)]
    ps = PartSet.build(names, shapes, tolerance=0.05)
    placed = ps.place(np.array(poses))
    mv, cand = np.arange(3), np.arange(3, n)
    want = np.zeros(n, bool)
    for c in cand:
        want[c] = any(probes_inside(ps, placed, m, c) is not None or probes_inside(ps, placed, c, m) is not None
                      for m in mv)
    assert np.array_equal(_contained(ps, placed, mv, cand), want)
