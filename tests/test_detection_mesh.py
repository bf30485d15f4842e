"""Concave mesh parts in the detection model (cablecheck.detection.mesh): MuJoCo
sees the mesh's own surface, not its convex hull."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings, strategies as st

from cablecheck.build.stages import build
from cablecheck.detection import mesh as detection_mesh
from cablecheck.detection.mesh import SURFACE_RADIUS, hull_parts, is_convex, patches, surface_geoms
from cablecheck.run.loop import Simulation
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import load_scene

# A U in the x-z plane (cm): a base 8 wide, 2 thick, and two prongs 2 wide
# rising 6 above it, with a 4 wide pocket between them; extruded 10 along y.
_U = np.array([(-4, -4), (4, -4), (4, -2), (4, 4), (2, 4), (2, -2), (-2, -2), (-2, 4), (-4, 4), (-4, -2)],
              float) / 100.0
_U_CAP = [(0, 1, 2), (0, 2, 5), (0, 5, 6), (0, 6, 9), (5, 2, 3), (5, 3, 4), (9, 6, 7), (9, 7, 8)]
POCKET_FLOOR = -0.02
"""z of the pocket's floor (the base's top face), metres."""
POCKET_HALF = 0.02
"""Half-width of the pocket along x (the prongs' inner faces), metres."""


def u_mesh(depth: float = 0.1) -> trimesh.Trimesh:
    """The U extruded along y: a closed, non-convex mesh."""
    n = len(_U)
    # the outline and every cap triangle run counter-clockwise in (x, z)
    front = np.column_stack([_U[:, 0], np.full(n, -depth / 2), _U[:, 1]])
    back = front + [0.0, depth, 0.0]
    faces = [(a + n, b + n, c + n) for a, b, c in _U_CAP] + [(a, c, b) for a, b, c in _U_CAP]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, j + n), (i, j + n, i + n)]
    mesh = trimesh.Trimesh(np.vstack([front, back]), np.array(faces), process=True)
    if mesh.volume < 0:
        mesh.invert()
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume == pytest.approx(0.1 * 0.004)
    return mesh


def _scene(tmp_path, z_end: float, keepout: bool = False, units: str = "m", shift=(0.0, 0.0, 0.0)):
    """A straight cable (r 5 mm, held by the world) coming down the middle of
    the U's pocket, its end at height z_end; the U on a body of its own (MuJoCo
    never collides a flex element with a body holding one of its vertices);
    clearance 5 mm. `units` "mm" writes the same scene in millimetres; `shift`
    (metres) moves all of it."""
    k = {"m": 1.0, "mm": 1000.0}[units]
    u_mesh().apply_scale(k).export(tmp_path / "u.stl")
    x, y, z = (k * np.asarray(shift, float)).tolist()
    (tmp_path / "u.toml").write_text(f"""
[scene]
name = "pocket"
units = "{units}"
duration = 0.004
[effects]
dynamics = false
[check]
clearance = {0.005 * k!r}
[[bodies]]
name = "fixture"
pos = [{x!r}, {y!r}, {z!r}]
[[parts]]
name = "u"
body = "fixture"
shape = "mesh"
file = "u.stl"
keepout = {str(keepout).lower()}
[[cables]]
name = "c"
radius = {0.005 * k!r}
start = {{ pos = [{x!r}, {y!r}, {z + 0.3 * k!r}] }}
end = {{ pos = [{x!r}, {y!r}, {z + z_end * k!r}] }}
segments = 10
""")
    return load_scene(tmp_path / "u.toml")


def _mujoco(scene):
    built = build(scene)
    sim = Simulation(built)
    sim.reset()
    return built, sim.detector.detect_qpos(built.qpos0)


def test_the_u_is_concave_and_a_box_is_convex():
    u = u_mesh()
    assert not is_convex(u.vertices, u.faces)
    box = trimesh.creation.box(extents=[0.1, 0.2, 0.3])
    assert is_convex(box.vertices, box.faces)


def test_only_non_convex_mesh_geoms_get_a_surface_and_cable_flexes_keep_their_ids(tmp_path):
    scene = _scene(tmp_path, 0.0)
    built = build(scene)
    flexes, geoms = surface_geoms(built.detect)
    (part,) = built.parts
    assert geoms.tolist() == [part.geom_id] and flexes.tolist() == [1]
    assert built.detect.flex_rigid[flexes].all() and built.detect.nq == built.model.nq
    assert built.cables[0].flex_id == 0 and surface_geoms(built.model)[0].size == 0   # physics untouched
    # the hull geom no longer meets the cable in the detection model, only the surface does
    cable_bit = int(built.detect.flex_contype[0]) & ~int(built.detect.flex_conaffinity[0])
    assert not built.detect.geom_conaffinity[part.geom_id] & cable_bit
    # so the hull can explain no disagreement on it (without a detection model, any mesh part's may)
    assert hull_parts(built.parts, built.detect) == frozenset() and hull_parts(built.parts, None) == {"u"}
    box = trimesh.creation.box(extents=[0.04, 0.04, 0.04])
    box.apply_translation([0.2, 0, 0])
    box.export(tmp_path / "u.stl")                                                   # a convex mesh part
    convex = build(load_scene(tmp_path / "u.toml"))
    assert surface_geoms(convex.detect)[0].size == 0 and hull_parts(convex.parts, convex.detect) == {"u"}


def _triangles(verts: np.ndarray, faces: np.ndarray) -> set:
    """Each triangle as the set of its three vertices' coordinates (exact bits)."""
    return {frozenset(map(tuple, verts[f].tolist())) for f in faces}


def test_a_surface_is_its_geoms_mesh_in_the_detection_model_itself(tmp_path):
    """The surfaces are read from the simulation model, which compiles the same
    meshes (the detection model compiles once): every concave mesh geom's
    patches together hold exactly its mesh's non-degenerate triangles, where
    the detection model itself puts them (its own mesh vertices and geom
    frame), to the bit. The robot cell's links (mjcf meshes, some bodies
    without a name) and a part's U on a scripted body."""
    import mujoco

    from pathlib import Path
    cell = load_scene(Path(__file__).resolve().parents[1] / "scenes" / "robot_cell.toml")
    for built in (build(cell), build(_scene(tmp_path, 0.0))):
        m = built.detect
        flexes, geoms = surface_geoms(m)
        assert len(set(geoms.tolist())) >= 1
        for g in sorted(set(geoms.tolist())):
            mid = int(m.geom_dataid[g])
            va, vn = int(m.mesh_vertadr[mid]), int(m.mesh_vertnum[mid])
            fa, fn = int(m.mesh_faceadr[mid]), int(m.mesh_facenum[mid])
            rot = np.zeros(9)
            mujoco.mju_quat2Mat(rot, m.geom_quat[g])
            verts = m.mesh_vert[va:va + vn].astype(float) @ rot.reshape(3, 3).T + m.geom_pos[g]
            faces = m.mesh_face[fa:fa + fn].astype(int)
            faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])]
            held = set()
            for f in flexes[geoms == g].tolist():
                assert (m.flex_vertbodyid[m.flex_vertadr[f]:m.flex_vertadr[f] + m.flex_vertnum[f]]
                        == m.geom_bodyid[g]).all()
                fv = m.flex_vert[m.flex_vertadr[f]:m.flex_vertadr[f] + m.flex_vertnum[f]]
                fe = m.flex_elem[m.flex_elemdataadr[f]:m.flex_elemdataadr[f] + 3 * m.flex_elemnum[f]].reshape(-1, 3)
                held |= _triangles(fv, fe)
            assert held == _triangles(verts, faces), g


def test_a_surface_read_under_another_geoms_id_is_refused():
    """`check_surfaces`: a geom whose compiled id is not the one its mesh was
    read under would give its surface to another geom."""
    class Geom:
        id = 4
    detection_mesh.check_surfaces([(Geom(), 4)])
    with pytest.raises(RuntimeError, match="numbers geom 3 as 4"):
        detection_mesh.check_surfaces([(Geom(), 3)])


@pytest.mark.parametrize("gap", [0.003, 0.0005, -0.002])
@pytest.mark.parametrize("units, shift", [("m", (0.0, 0.0, 0.0)), ("mm", (400.0, -250.0, 120.0))])
def test_mujoco_distance_is_the_mesh_surface_distance(tmp_path, gap, units, shift):
    """The cable's end `gap` above the pocket's floor (negative: into it):
    MuJoCo's distance is the mesh's, to 1e-7 m apart (the surface's radius
    added back) and 1e-6 m in overlap (a depth from MuJoCo's EPA), not the
    hull's (about -0.02 - gap: the end is inside the hull); the same in
    millimetres, 500 m from the origin."""
    built, found = _mujoco(_scene(tmp_path, POCKET_FLOOR + 0.005 + gap, units=units, shift=shift))
    mine = found.b == "u"
    assert mine.any() and set(found.kind[mine]) == {"cable-structure"} and (found.elem_b[mine] == -1).all()
    assert abs(found.dist[mine].min() - gap) < (1e-7 if gap > 0 else 1e-6), (found.dist[mine].min(), gap)
    assert SURFACE_RADIUS < 1e-5


def test_a_keepout_mesh_is_read_as_keepout(tmp_path):
    _, found = _mujoco(_scene(tmp_path, POCKET_FLOOR + 0.008, keepout=True))
    mine = found.b == "u"
    assert set(found.kind[mine]) == {"keepout"} and abs(found.dist[mine].min() - 0.003) < 1e-7


def test_end_in_the_pocket_clear_of_the_mesh_inside_the_hull(tmp_path):
    """The cable's end 15 mm from the floor and from each prong: clear of the
    mesh (clearance 5 mm), deep inside its hull. MuJoCo now reports nothing
    and agrees with the checker at every step."""
    scene = _scene(tmp_path, 0.0)
    _, found = _mujoco(scene)
    assert not (found.b == "u").any()
    rep = run_scene(scene, RunOptions(report=tmp_path / "r.json", record=None))
    val = rep["validation"]
    assert rep["events"] == [] and val["compared_steps"] > 0
    assert val["agreement"] == 1.0 and val["disagreements"] == [] and val["reasons"] == {}


def test_end_within_the_clearance_of_the_floor_agrees(tmp_path):
    """3 mm above the floor: both sides class it soft, at the same distance."""
    rep = run_scene(_scene(tmp_path, POCKET_FLOOR + 0.008), RunOptions(report=tmp_path / "r.json", record=None))
    val = rep["validation"]
    assert [(e["b"], e["severity"]) for e in rep["events"]] == [("u", "soft")]
    assert val["agreement"] == 1.0 and val["agree"] == val["pair_steps"] > 0
    assert val["max_distance_error"] < 1e-6


def test_a_face_naming_one_vertex_twice_is_left_out_of_the_surface(tmp_path):
    """An STL with a degenerate triangle (two corners the same point): MuJoCo
    keeps it in the mesh with a repeated index, which a flex refuses; the
    surface leaves it out and MuJoCo's distance is still the mesh's."""
    scene = _scene(tmp_path, POCKET_FLOOR + 0.008)
    u = u_mesh()
    a, b = u.faces[0, :2]
    trimesh.Trimesh(u.vertices, np.vstack([u.faces, [[a, b, a]]]), process=False).export(tmp_path / "u.stl")
    built, found = _mujoco(scene)
    m, g = built.detect, built.parts[0].geom_id
    faces = m.mesh_face[m.mesh_faceadr[m.geom_dataid[g]]:][:m.mesh_facenum[m.geom_dataid[g]]]
    assert (faces[:, 0] == faces[:, 2]).any()                              # MuJoCo kept it
    (flex,) = surface_geoms(m)[0]
    assert m.flex_elemnum[flex] == len(faces) - 1
    assert abs(found.dist[found.b == "u"].min() - 0.003) < 1e-7


@settings(max_examples=50)
@given(n=st.integers(1, 400), most=st.integers(1, 64), seed=st.integers(0, 2**31 - 1))
def test_patches_hold_every_triangle_once_and_none_too_many(n, most, seed):
    """A k-d split of drawn centroids: every triangle in exactly one patch,
    none over `most`, no more patches than halving needs, and two patches
    split at a level lie on the two sides of a plane."""
    centroids = np.random.default_rng(seed).normal(size=(n, 3))
    out = patches(centroids, most)
    assert np.array_equal(np.sort(np.concatenate(out)), np.arange(n))
    assert all(len(p) <= most and np.all(np.diff(p) > 0) for p in out)
    assert len(out) <= 2 ** int(np.ceil(np.log2(max(n / most, 1))))
    if len(out) >= 2:    # the first split: the patches before and after it apart along one axis
        half = len(out) // 2 if len(out) & (len(out) - 1) == 0 else None
        if half:
            a, b = centroids[np.concatenate(out[:half])], centroids[np.concatenate(out[half:])]
            assert any(a[:, k].max() <= b[:, k].min() or b[:, k].max() <= a[:, k].min() for k in range(3))


@pytest.mark.parametrize("z_end", [POCKET_FLOOR + 0.008, POCKET_FLOOR + 0.006, POCKET_FLOOR + 0.004])
def test_a_surface_in_patches_has_the_contacts_of_the_whole_surface(tmp_path, monkeypatch, z_end):
    """The U as one flex and cut into 20 patches of 1 or 2 triangles: the same
    contacts, to the bit (MuJoCo pairs a cable element with each triangle on
    its own), every patch in the pass or only those in reach."""
    scene = _scene(tmp_path, z_end)
    whole = build(scene)
    monkeypatch.setattr(detection_mesh, "PATCH_TRIANGLES", 2)
    cut = build(scene)
    assert len(surface_geoms(whole.detect)[0]) == 1 and len(surface_geoms(cut.detect)[0]) == 20
    assert set(surface_geoms(cut.detect)[1].tolist()) == {whole.parts[0].geom_id}

    def key(built, reach):
        c = Simulation(built, reach=reach).detector.detect_qpos(built.qpos0)
        return sorted(zip(c.kind.tolist(), c.a.tolist(), c.b.tolist(), c.elem_a.tolist(), c.dist.tolist(),
                          map(tuple, c.pos.tolist())))

    expected = key(whole, False)
    assert expected and key(cut, False) == expected and key(cut, True) == expected
