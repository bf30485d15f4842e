"""The reach test of the detection model's concave surfaces (cablecheck.detection.surfacereach):
a surface left out of a collision pass is one on which MuJoCo finds no
contact, so the pass finds what it finds with every surface in."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cablecheck.build.stages import build
from cablecheck.checker.closest import segment_triangle
from cablecheck.detection import mesh as detection_mesh
from cablecheck.detection.mesh import SURFACE_PREFIX, surface_geoms
from cablecheck.detection.surfacereach import (
    PIECE_LEVELS,
    REACH_SLACK,
    REACH_TOLERANCES,
    SurfaceReach,
    oriented_boxes,
    pieces,
)
from cablecheck.run.loop import Simulation
from cablecheck.scene.load import load_scene
from tests.strategies import coords, rotations
from tests.test_detection_mesh import POCKET_FLOOR, u_mesh

CLEARANCE = 0.005
RADIUS = 0.005


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    """Two concave U meshes on bodies of their own ("near" with the cable's
    end 3 mm above its pocket's floor, "far" 1 m away) and a cable from the
    world to a point 30 mm below a third body, "carrier"; no dynamics."""
    return _cell(tmp_path_factory.mktemp("reach"))


@pytest.fixture(scope="module")
def patched(tmp_path_factory):
    """The same cell with each U cut into patches of at most 3 triangles
    (16 per U) on a tree of boxes 4 levels deep."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(detection_mesh, "PATCH_TRIANGLES", 3)
        return _cell(tmp_path_factory.mktemp("patched"))


def _cell(tmp):
    u_mesh().export(tmp / "u.stl")
    end_z = POCKET_FLOOR + RADIUS + 0.003
    (tmp / "reach.toml").write_text(f"""
[scene]
name = "reach"
units = "m"
duration = 0.004
[effects]
dynamics = false
[check]
clearance = {CLEARANCE!r}
[[bodies]]
name = "near"
[[bodies]]
name = "far"
pos = [1.0, 0.0, 0.0]
[[bodies]]
name = "carrier"
pos = [0.0, 0.0, {end_z + 0.03!r}]
[[parts]]
name = "near/u"
body = "near"
shape = "mesh"
file = "u.stl"
[[parts]]
name = "far/u"
body = "far"
shape = "mesh"
file = "u.stl"
[[cables]]
name = "c"
radius = {RADIUS!r}
start = {{ pos = [0.0, 0.0, 0.3] }}
end = {{ body = "carrier", pos = [0.0, 0.0, -0.03] }}
segments = 10
""")
    built = build(load_scene(tmp / "reach.toml"))
    sim = Simulation(built)
    sim.reset()
    return built, sim


def _key(raw) -> list:
    return sorted(zip(raw.geom[:, 0].tolist(), raw.geom[:, 1].tolist(), raw.flex[:, 0].tolist(),
                      raw.flex[:, 1].tolist(), raw.elem[:, 0].tolist(), raw.dist.tolist()))


def _unfiltered(sim: Simulation, qposes) -> list:
    every = Simulation(sim.built, reach=False)
    assert every.detector.reach is None
    return every.detector.collide_many(qposes)


def _reachable(sim: Simulation, qpos: np.ndarray) -> np.ndarray:
    m, d = sim.built.detect, sim.detector.detect_data
    d.qpos[:] = qpos
    mujoco.mj_kinematics(m, d)
    return sim.detector.reach.reachable(d.xpos[None].copy(), d.xmat[None].copy())[0]


def _placed(built, qpos: np.ndarray, body: str, pos, rot: np.ndarray) -> np.ndarray:
    """`qpos` with `body`'s free joint at `pos` (model coordinates) turned by `rot`."""
    m = built.model
    adr = int(m.jnt_qposadr[m.body_jntadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body)]])
    out = qpos.copy()
    out[adr:adr + 3] = pos
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.asarray(rot, float).ravel())
    out[adr + 3:adr + 7] = quat
    return out


def test_a_far_surface_is_left_out_and_the_contacts_are_the_same(cell):
    built, sim = cell
    assert len(sim.detector.reach) == 2
    q0 = built.qpos0
    names = {p.geom_id: p.name for p in built.parts}
    surfaces = [names[g] for g in surface_geoms(built.detect)[1].tolist()]
    assert sorted(surfaces) == ["far/u", "near/u"]
    assert _reachable(sim, q0).tolist() == [n == "near/u" for n in surfaces]
    # the near U moved down past the cable's end and up over it: contact, none, overlap
    start = q0[int(built.model.jnt_qposadr[built.model.body_jntadr[
        mujoco.mj_name2id(built.model, mujoco.mjtObj.mjOBJ_BODY, "near")]]):][:3]
    qposes = [_placed(built, q0, "near", start + [0.0, 0.0, dz], np.eye(3)) for dz in (-0.05, -0.01, 0.0, 0.002, 0.01)]
    # and the far U brought under the cable's end in the middle of the batch: its surface in, then out again
    far = _placed(built, q0, "near", start + [0.0, 0.0, -0.05], np.eye(3))
    far = _placed(built, far, "far", start, np.eye(3))
    qposes = qposes[:2] + [far] + qposes[2:]
    # (10 mm below, the pocket's floor is 13 mm from the cable's end: beyond the
    # contact distance, and the pieces' boxes leave the near U out too)
    assert [_reachable(sim, q).tolist().count(True) for q in qposes[1:4]] == [0, 1, 1]
    found = sim.detector.collide_many(qposes)
    assert [_key(a) for a in found] == [_key(b) for b in _unfiltered(sim, qposes)]
    assert len(found[3].dist) and len(found[2].dist) and not len(found[0].dist)   # contacts, and states without
    m = built.detect
    flexes = sim.detector.reach.flexes
    assert (m.flex_vertnum[flexes] > 0).all() and (m.flex_bvhadr[flexes] >= 0).all()


@settings(max_examples=60)
@given(offset=coords(3, -0.12, 0.12), turn=rotations(), carrier=coords(3, -0.05, 0.05),
       carrier_turn=rotations(), far=st.booleans())
def test_a_surface_left_out_is_beyond_the_contact_distance(cell, offset, turn, carrier, carrier_turn, far):
    """The near U and the body holding the cable's end at drawn poses: a
    surface found out of reach is farther from every cable element than
    MuJoCo's contact distance (exact segment-triangle distances), and the
    pass finds the same contacts as one with every surface in."""
    _left_out_beyond_contact(cell, offset, turn, carrier, carrier_turn, far)


@settings(max_examples=60)
@given(offset=coords(3, -0.12, 0.12), turn=rotations(), carrier=coords(3, -0.05, 0.05),
       carrier_turn=rotations(), far=st.booleans())
def test_a_patch_left_out_is_beyond_the_contact_distance(patched, offset, turn, carrier, carrier_turn, far):
    """The same with each U in small patches, each patch tested down the
    tree of boxes: a patch left out is beyond MuJoCo's contact distance,
    and the contacts are those of every patch in."""
    _, sim = patched
    assert len(sim.detector.reach) == 32 and len(sim.detector.reach._levels) == 5 + PIECE_LEVELS
    _left_out_beyond_contact(patched, offset, turn, carrier, carrier_turn, far)


def _along(a, b, g, axes, lo, hi) -> np.ndarray:
    """Segments (ends a, b, grown by g) that reach a box (along `axes`, lo,
    hi) along its axes and their direction crossed with each axis."""
    pa, pb = a @ axes.T, b @ axes.T
    along = ~((np.minimum(pa, pb) - g > hi) | (np.maximum(pa, pb) + g < lo)).any(1)
    w, mid = 0.5 * (pb - pa), 0.5 * (pa + pb) - 0.5 * (lo + hi)
    for axis in np.eye(3):
        cross = np.cross(w, axis)
        extent = np.abs(cross) @ (0.5 * (hi - lo)) + g[:, 0] * np.linalg.norm(cross, axis=1)
        along &= ~(np.abs((mid * cross).sum(1)) > extent)
    return along


def _direct(reach: SurfaceReach, m: mujoco.MjModel, xpos: np.ndarray, xmat: np.ndarray) -> np.ndarray:
    """The reach test with neither the cull nor the tree: every segment
    against every piece of every patch, its box in its body's frame, then
    along the patch's and the piece's own axes and the segment's direction
    crossed with them (a leaf's ancestors hold its box, so the tree prunes
    nothing it would keep)."""
    d = mujoco.MjData(m)
    out = np.zeros((len(xpos), len(reach)), bool)
    g = reach._grow[:, None]
    for i, (x, r) in enumerate(zip(xpos, xmat)):
        d.xpos[:], d.xmat[:] = x, r
        mujoco.mj_flex(m, d)
        verts = np.concatenate([np.arange(m.flex_vertadr[c], m.flex_vertadr[c] + m.flex_vertnum[c])
                                for c in np.flatnonzero(m.flex_dim == 1)])
        pts = d.flexvert_xpos[verts]
        for p, patch in enumerate(reach.piece_patch):
            body = reach.bodies[patch]
            local = (pts - x[body]) @ r[body].reshape(3, 3)
            a, b = local[reach._segs[:, 0]], local[reach._segs[:, 1]]
            box = ~((np.minimum(a, b) - g > reach.piece_hi[p]) | (np.maximum(a, b) + g < reach.piece_lo[p])).any(1)
            whole = _along(a, b, g, reach.axes[patch], reach.axis_lo[patch], reach.axis_hi[patch])
            piece = _along(a, b, g, reach.piece_axes[p], reach.piece_axis_lo[p], reach.piece_axis_hi[p])
            out[i, patch] |= (box & whole & piece).any()
    return out


def test_the_cull_and_the_tree_keep_the_patches_a_direct_test_keeps(patched):
    """The carrier and the two Us at poses drawn around the cable's end, many
    states at once: the world-frame cull of sphere pairs and the steps down
    the tree keep exactly the patches that testing every segment against
    every piece keeps (some states keep none, some many)."""
    built, sim = patched
    m, d = built.detect, sim.detector.detect_data
    q0 = built.qpos0
    jnt = built.model.body_jntadr[mujoco.mj_name2id(built.model, mujoco.mjtObj.mjOBJ_BODY, "carrier")]
    end = q0[int(built.model.jnt_qposadr[jnt]):][:3]
    rng = np.random.default_rng(7)
    xpos, xmat = [], []
    for _ in range(150):
        turns = [np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(3)]
        turns = [t * np.sign(np.linalg.det(t)) for t in turns]
        qpos = _placed(built, q0, "near", end + rng.uniform(-0.1, 0.1, 3), turns[0])
        qpos = _placed(built, qpos, "far", end + rng.uniform(-0.1, 0.1, 3), turns[1])
        qpos = _placed(built, qpos, "carrier", end + rng.uniform(-0.05, 0.05, 3), turns[2])
        d.qpos[:] = qpos
        mujoco.mj_kinematics(m, d)
        xpos.append(d.xpos.copy())
        xmat.append(d.xmat.copy())
    xpos, xmat = np.array(xpos), np.array(xmat)
    got = sim.detector.reach.reachable(xpos, xmat)
    kept = got.sum(axis=1)
    assert (kept == 0).any() and kept.max() >= 4
    assert np.array_equal(got, _direct(sim.detector.reach, m, xpos, xmat))


def test_patches_are_left_out_one_by_one(patched):
    """With the cable's end in the near U's pocket some of its patches are
    in the pass and others out, and the contacts are those of every patch in."""
    built, sim = patched
    keep = _reachable(sim, built.qpos0)
    names = {p.geom_id: p.name for p in built.parts}
    near = np.array([names[g] == "near/u" for g in surface_geoms(built.detect)[1].tolist()])
    assert keep[near].any() and not keep[near].all() and not keep[~near].any()
    found = sim.detector.collide_many([built.qpos0])
    assert len(found[0].dist) and _key(found[0]) == _key(_unfiltered(sim, [built.qpos0])[0])


def test_a_patch_left_out_has_no_vertices_elements_tree_bits_or_body_and_restore_undoes_it(patched):
    built, sim = patched
    m, reach = built.detect, sim.detector.reach
    compiled = [a.copy() for a in (m.flex_vertnum, m.flex_elemnum, m.flex_bvhadr, m.flex_contype,
                                   m.flex_conaffinity, m.flex_vertbodyid)]
    keep = np.arange(len(reach)) % 3 == 0
    for step in (keep, ~keep, keep):     # patches going out, coming back in, out again
        reach.leave_out(step)
        for f, kept in zip(reach.flexes.tolist(), step.tolist()):
            verts = slice(m.flex_vertadr[f], m.flex_vertadr[f] + compiled[0][f])
            if kept:
                assert [int(a[f]) for a in (m.flex_vertnum, m.flex_elemnum, m.flex_bvhadr, m.flex_contype,
                                            m.flex_conaffinity)] == [int(a[f]) for a in compiled[:5]]
                assert np.array_equal(m.flex_vertbodyid[verts], compiled[5][verts])
            else:
                assert m.flex_vertnum[f] == m.flex_elemnum[f] == m.flex_contype[f] == m.flex_conaffinity[f] == 0
                assert m.flex_bvhadr[f] == -1 and not m.flex_vertbodyid[verts].any()
    reach.restore()
    assert all(np.array_equal(a, b) for a, b in zip(compiled, (m.flex_vertnum, m.flex_elemnum, m.flex_bvhadr,
                                                              m.flex_contype, m.flex_conaffinity,
                                                              m.flex_vertbodyid)))


def _left_out_beyond_contact(cell, offset, turn, carrier, carrier_turn, far):
    built, sim = cell
    m, d = built.detect, sim.detector.detect_data
    q0 = built.qpos0
    jnt = built.model.body_jntadr[mujoco.mj_name2id(built.model, mujoco.mjtObj.mjOBJ_BODY, "carrier")]
    end = q0[int(built.model.jnt_qposadr[jnt]):][:3]
    qpos = _placed(built, q0, "near", end + offset, turn)
    qpos = _placed(built, qpos, "carrier", end + carrier, carrier_turn)
    if far:
        qpos = _placed(built, qpos, "far", end - offset, turn.T)
    keep = _reachable(sim, qpos)
    mujoco.mj_flex(m, d)
    cable = built.cables[0]
    pts = d.flexvert_xpos[m.flex_vertadr[cable.flex_id]:][:cable.count]
    margin = float(m.flex_margin[cable.flex_id])
    for f, kept in zip(sim.detector.reach.flexes.tolist(), keep.tolist()):
        verts = d.flexvert_xpos[m.flex_vertadr[f]:][:m.flex_vertnum[f]]
        tri = verts[m.flex_elem[m.flex_elemdataadr[f]:][:3 * m.flex_elemnum[f]].reshape(-1, 3)]
        seg = np.repeat(np.arange(cable.count - 1), len(tri))
        t = np.tile(np.arange(len(tri)), cable.count - 1)
        dist = segment_triangle(pts[seg], pts[seg + 1], tri[t, 0], tri[t, 1], tri[t, 2])[0].min()
        gap = dist - cable.radius - float(m.flex_radius[f])
        assert kept or gap > margin, (f, gap)
    assert _key(sim.detector.collide_many([qpos])[0]) == _key(_unfiltered(sim, [qpos])[0])


@pytest.mark.parametrize("meets", [True, False])
def test_a_model_flex_of_other_dimension_that_can_meet_a_surface_keeps_every_surface(meets):
    """Only cables (one-dimensional flexes) have a bound: a two-dimensional
    flex of the mjcf model whose bits meet a surface's keeps every surface in
    every pass; one whose bits do not changes nothing."""
    spec = mujoco.MjSpec()
    spec.worldbody.add_body(name="b", pos=[0.0, 0.0, 1.0])
    for name, contype, conaffinity in ((f"{SURFACE_PREFIX}0", 0, 8), ("cloth", 8 if meets else 2, 0)):
        f = spec.add_flex()
        f.name, f.dim, f.radius = name, 2, 1e-3
        f.vertbody = ["b"]
        f.vert = [0.0, 0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.1, 0.0]
        f.elem = [0, 1, 2]
        f.contype, f.conaffinity = contype, conaffinity
    m = spec.compile()
    reach = SurfaceReach(m)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    assert reach.reachable(d.xpos[None], d.xmat[None]).tolist() == [[meets]]


@settings(max_examples=40)
@given(groups=st.lists(st.integers(1, 12), min_size=1, max_size=5), turn=rotations(),
       points=coords((60, 3), -0.05, 0.05), flat=st.booleans())
def test_oriented_boxes_hold_their_points_on_orthonormal_axes(groups, turn, points, flat):
    """Every point lies in its group's box along that group's axes (against
    a brute-force projection), the axes are orthonormal, and a flat group
    turned anywhere gets a box of no thickness."""
    count = np.array(groups)
    adr = np.concatenate([[0], np.cumsum(count)[:-1]])
    verts = points[:count.sum()].copy()
    if flat:
        verts[:, 2] = 0.01
        verts = verts @ turn.T + 0.3
    axes, lo, hi = oriented_boxes(verts, adr, count)
    np.testing.assert_allclose(axes @ axes.transpose(0, 2, 1), np.broadcast_to(np.eye(3), axes.shape), atol=1e-12)
    for k, (a, n) in enumerate(zip(adr, count)):
        along = verts[a:a + n] @ axes[k].T
        np.testing.assert_array_equal(along.min(axis=0) <= along.max(axis=0), True)
        assert (along >= lo[k] - 1e-12).all() and (along <= hi[k] + 1e-12).all()
        np.testing.assert_allclose([along.min(axis=0), along.max(axis=0)], [lo[k], hi[k]], atol=1e-12)
        if flat and n >= 3:
            assert (hi[k] - lo[k]).min() < 1e-9


def test_a_slanted_patch_is_left_out_where_only_its_own_axes_separate_it():
    """A thin square turned 45 degrees about x in its body's frame, the
    cable's segment parallel to it 30 mm off its face: inside the square's
    axis-aligned box grown by the contact distance, apart along the square's
    normal by more than it: left out."""
    spec = mujoco.MjSpec()
    spec.worldbody.add_body(name="b", pos=[0.0, 0.0, 1.0])
    half = 0.05
    c, s45 = np.cos(np.pi / 4), np.sin(np.pi / 4)
    square = [[x, y * c, y * s45] for x, y in ((-half, -half), (half, -half), (half, half), (-half, half))]
    f = spec.add_flex()
    f.name, f.dim, f.radius = f"{SURFACE_PREFIX}0", 2, 1e-6
    f.vertbody = ["b"]
    f.vert = np.ravel(square).tolist()
    f.elem = [0, 1, 2, 0, 2, 3]
    f.contype, f.conaffinity, f.margin = 1, 1, 0.005
    cable = spec.add_flex()
    cable.name, cable.dim, cable.radius, cable.margin = "cable", 1, 0.002, 0.005
    off = 0.03 * np.array([0.0, -s45, c])        # off the face, along its normal
    ends = np.array([[-0.03, 0.0, 0.0], [0.03, 0.0, 0.0]]) + off + [0.0, 0.0, 1.0]
    spec.worldbody.add_body(name="v")
    cable.vertbody = ["v", "v"]
    cable.vert = np.ravel(ends).tolist()
    cable.elem = [0, 1]
    m = spec.compile()
    reach = SurfaceReach(m)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    grow = 0.002 + 1e-6 + 2 * 0.01
    seg = ends - [0.0, 0.0, 1.0]
    assert ((seg.min(axis=0) - grow <= reach.hi[0]) & (seg.max(axis=0) + grow >= reach.lo[0])).all()
    assert reach.reachable(d.xpos[None], d.xmat[None]).tolist() == [[False]]


def _square_and_segment(margin: float, radius: float) -> mujoco.MjModel:
    """A surface patch, a 100 mm square in the plane z = 0 of a fixed body,
    and a cable of one 60 mm element (margin `margin`) on a free body."""
    spec = mujoco.MjSpec()
    spec.worldbody.add_body(name="b")
    half = 0.05
    f = spec.add_flex()
    f.name, f.dim, f.radius = f"{SURFACE_PREFIX}0", 2, 1e-6
    f.vertbody = ["b"]
    f.vert = [-half, -half, 0.0, half, -half, 0.0, half, half, 0.0, -half, half, 0.0]
    f.elem = [0, 1, 2, 0, 2, 3]
    body = spec.worldbody.add_body(name="v")
    body.add_freejoint()
    g = body.add_geom()
    g.type, g.size, g.contype, g.conaffinity = mujoco.mjtGeom.mjGEOM_SPHERE, [0.001, 0.0, 0.0], 0, 0
    c = spec.add_flex()
    c.name, c.dim, c.radius, c.margin = "cable", 1, radius, margin
    c.vertbody = ["v", "v"]
    c.vert = [-0.03, 0.0, 0.0, 0.03, 0.0, 0.0]
    c.elem = [0, 1]
    return spec.compile()


@settings(max_examples=80, deadline=None)
@given(margin=st.sampled_from([0.0, 0.005]), above=st.floats(-0.001, 0.0015), tilt=st.floats(-0.2, 0.2),
       shift=coords(2, -0.015, 0.015))
def test_the_bound_keeps_every_surface_mujoco_touches_and_leaves_out_what_lies_beyond_its_slack(
        margin, above, tilt, shift):
    """A segment over a flat patch, its lower end `above` MuJoCo's contact
    distance (radius + patch radius + margin): wherever MuJoCo makes a
    contact the patch is kept, and beyond the contact distance + the
    bound's slack it is left out (the bound is that tight on a flat patch)."""
    r = 0.002
    m = _square_and_segment(margin, r)
    reach, d = SurfaceReach(m), mujoco.MjData(m)
    reach_at = r + 1e-6 + margin
    ends = np.array([[-0.03 * np.cos(tilt), 0.0, -0.03 * np.sin(tilt)], [0.03 * np.cos(tilt), 0.0, 0.03 * np.sin(tilt)]])
    low = reach_at + above
    d.qpos[:3] = [shift[0], shift[1], low - ends[:, 2].min()]
    d.qpos[3:7] = [np.cos(tilt / 2), 0.0, -np.sin(tilt / 2), 0.0]    # turned about y: the ends as `ends`
    mujoco.mj_kinematics(m, d)
    kept = bool(reach.reachable(d.xpos[None].copy(), d.xmat[None].copy())[0, 0])
    mujoco.mj_forward(m, d)
    if d.ncon:
        assert kept and d.contact.dist[:d.ncon].min() < margin + 1e-9
    slack = REACH_SLACK * margin + REACH_TOLERANCES * m.opt.ccd_tolerance
    if above > slack + 1e-9:
        assert not kept
    if above < -1e-6:
        assert d.ncon                        # MuJoCo touches it: the case above is met


@pytest.mark.parametrize("levels", [0, 1, 3])
def test_every_triangle_lies_in_a_piece_of_its_patch(cell, levels):
    """`pieces`: each triangle of a patch lies wholly in one of its patch's
    pieces, in its box in the body's frame and along its axes; a patch has
    2**levels pieces (halves of equal counts of triangles), fewer only when
    it has fewer triangles."""
    built, sim = cell
    m, flexes = built.detect, sim.detector.reach.flexes
    patch, node, lo, hi, axes, axis_lo, axis_hi = pieces(m, flexes, levels)
    assert np.bincount(patch, minlength=len(flexes)).max() <= 2 ** levels and (node < 2 ** levels).all()
    eps = 1e-12
    for f, flex in enumerate(flexes.tolist()):
        verts = m.flex_vert[m.flex_vertadr[flex]:][:m.flex_vertnum[flex]]
        tri = verts[m.flex_elem[m.flex_elemdataadr[flex]:][:3 * m.flex_elemnum[flex]].reshape(-1, 3)]
        mine = np.flatnonzero(patch == f)
        inside = np.zeros((len(tri), len(mine)), bool)
        for k, p in enumerate(mine.tolist()):
            along = tri @ axes[p].T
            inside[:, k] = (((tri >= lo[p] - eps) & (tri <= hi[p] + eps)).all(axis=(1, 2))
                            & ((along >= axis_lo[p] - eps) & (along <= axis_hi[p] + eps)).all(axis=(1, 2)))
        assert inside.any(axis=1).all()
        assert len(mine) == min(2 ** levels, len(tri))          # halves of equal counts: none empty
