"""Reading the compiled model back (cablecheck.build.modelread): mesh parts, visual geoms
(drawn, never parts, names stable), the model's own excluded pairs."""

from __future__ import annotations

import copy

import numpy as np
import trimesh
from buildscenes import arm_built, arm_scene, run_steps, slider_scene

from cablecheck.build.stages import build
from cablecheck.run.loop import Simulation
from cablecheck.scene.load import parse_scene


def test_mesh_part_matches_box_part(tmp_path):
    box = trimesh.creation.box(extents=[0.04, 0.04, 0.4])
    box.export(tmp_path / "post.stl")
    a = slider_scene(tmp_path)
    b = copy.deepcopy(a)
    b["parts"][0] = {"name": "frame/post", "shape": "mesh", "file": "post.stl", "pos": [0.36, 0.0, 0.2]}
    built_a = build(parse_scene(a, tmp_path / "s.toml"))
    built_b = build(parse_scene(b, tmp_path / "s.toml"))
    pa, pb = built_a.parts[0], built_b.parts[0]
    assert pb.shape == "mesh" and pb.vertices.shape == (8, 3)
    sa, sb = Simulation(built_a), Simulation(built_b)
    sa.reset(), sb.reset()
    ta, tb = sa.state(0, False).part_poses[0], sb.state(0, False).part_poses[0]
    world_b = pb.vertices @ tb[:3, :3].T + tb[:3, 3]
    assert np.allclose(np.sort(world_b, axis=0),
                       np.sort(np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
                               * pa.size + ta[:3, 3], axis=0), atol=1e-6)  # MuJoCo stores mesh vertices as float32


def test_visual_geoms_are_drawn_never_parts_and_names_do_not_move(tmp_path):
    """A model with and without its visual geoms gives the same parts, names
    and skipped pairs; the visual geoms are listed to be drawn, from the
    file compiled whole, and left out of the simulation and detection
    models, whose bodies keep the mass MuJoCo gives them with them."""
    import mujoco

    from cablecheck.build.drawn import drawn_geoms
    from cablecheck.run.stepcheck import part_pairs_skipped
    bare = arm_built(tmp_path, visuals=False)
    bare_drawn = drawn_geoms(mujoco.MjModel.from_xml_path(str(tmp_path / "arm.xml")))
    dressed = arm_built(tmp_path, visuals=True)
    whole = mujoco.MjModel.from_xml_path(str(tmp_path / "arm.xml"))
    drawn = drawn_geoms(whole)
    names = [p.name for p in bare.parts]
    assert names == [p.name for p in dressed.parts]
    assert set(names) == {"cell/table", "stand/column", "link/capsule0", "link/lug", "link/sphere2", "post/rod"}
    assert [v.name for v in drawn] == ["stand/box0", "link/lug", "link/shell"] and not bare_drawn
    assert [v.shape for v in drawn] == ["box", "mesh", "capsule"] and drawn[1].vertices.shape == (4, 3)
    assert np.array_equal(part_pairs_skipped(bare), part_pairs_skipped(dressed))
    for built in (bare, dressed):
        for m in (built.model, built.detect):
            assert m.ngeom == bare.model.ngeom       # the visual geoms are not there
    for v in drawn:
        assert dressed.model.body(v.body_id).name == whole.body(v.body_id).name == v.body
    # the visual geoms weigh (no <inertial> in the file): their mass stays with their bodies
    for body in ("stand", "link"):
        assert np.isclose(dressed.model.body(body).mass[0], whole.body(body).mass[0], rtol=1e-12)
        assert dressed.model.body(body).mass[0] > bare.model.body(body).mass[0]


def test_model_exclude_pairs_are_honoured(tmp_path):
    from cablecheck.run.stepcheck import part_pairs_skipped
    plain = arm_built(tmp_path, visuals=False)
    excluded = arm_built(tmp_path, visuals=False, contact='<contact><exclude body1="link" body2="post"/></contact>')
    for built, expect in ((plain, False), (excluded, True)):
        idx = {p.name: k for k, p in enumerate(built.parts)}
        skip = part_pairs_skipped(built)
        assert skip[idx["link/sphere2"], idx["post/rod"]] == expect
        assert skip[idx["post/rod"], idx["link/sphere2"]] == expect
        assert not skip[idx["cell/table"], idx["post/rod"]]


def test_visual_geoms_make_no_contacts_nor_events(tmp_path):
    """A visual shell the cable runs through is never a contact, part or event."""
    data = arm_scene(tmp_path, visuals=True)
    sim, states = run_steps(data, tmp_path)
    for m in (sim.built.model, sim.built.detect):
        assert not ((m.geom_contype == 0) & (m.geom_conaffinity == 0)).any()   # left out
    assert all(not str(n).startswith(("link/shell", "stand/box0")) for s in states for n in s.contacts.b)


_WELDED = """<mujoco><worldbody>
  <body name="a"><joint name="ja" type="hinge"/><geom name="ga" size="1"/>
    <body name="a2"><geom name="ga2" size="1"/>
      <body name="b"><joint name="jb" type="hinge"/><geom name="gb" size="1"/>
        <body name="b2"><geom name="gb2" size="1"/>
          <body name="c"><joint name="jc" type="hinge"/><geom name="gc" size="1"/></body>
        </body>
      </body>
    </body>
  </body>
</worldbody></mujoco>"""


def test_skipped_part_pairs_are_those_mujoco_never_collides(tmp_path):
    """Five overlapping spheres on a chain of hinged bodies, two of them with a welded companion body
    (no joint: robosuite's Sawyer hangs right_l1_2 on right_l1 so): the part pairs the part-part check
    leaves out are exactly those MuJoCo's own collision pass gives no contact, read from mj_collision."""
    import mujoco

    from cablecheck.run.stepcheck import part_pairs_skipped

    (tmp_path / "welded.xml").write_text(_WELDED)
    data = {"scene": {"name": "w", "units": "m", "duration": 0.1, "mjcf": "welded.xml"},
            "effects": {"contact": ["part-part"]}}
    built = build(parse_scene(data, tmp_path / "s.toml"), detect=False)
    names = [p.name for p in built.parts]
    assert names == ["a/ga", "a2/ga2", "b/gb", "b2/gb2", "c/gc"]
    ref = mujoco.MjModel.from_xml_path(str(tmp_path / "welded.xml"))
    d = mujoco.MjData(ref)
    mujoco.mj_forward(ref, d)
    touching = {frozenset((ref.geom(int(c.geom[0])).name, ref.geom(int(c.geom[1])).name)) for c in d.contact[:d.ncon]}
    skip = part_pairs_skipped(built)
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            pair = frozenset((names[i].split("/")[1], names[j].split("/")[1]))
            assert skip[i, j] == (pair not in touching), (names[i], names[j])
    assert frozenset(("ga", "gc")) in touching and frozenset(("ga2", "gb")) not in touching


def test_a_link_turning_in_a_base_welded_to_the_world_is_left_out(tmp_path):
    """An arm's base link welded to the world and its first, jointed link overlap at their joint by
    design: left out, where MuJoCo (which exempts the world's weld group from its parent filter)
    collides them; a part of the world itself against that link is still checked."""
    from cablecheck.run.stepcheck import part_pairs_skipped

    (tmp_path / "base.xml").write_text(
        '<mujoco><worldbody><geom name="floor" type="box" size="1 1 0.1" pos="0 0 -2"/>'
        '<body name="base"><geom name="gbase" size="1"/>'
        '<body name="shoulder"><joint type="hinge"/><geom name="gsh" size="1"/></body></body>'
        '</worldbody></mujoco>')
    data = {"scene": {"name": "b", "units": "m", "duration": 0.1, "mjcf": "base.xml"},
            "effects": {"contact": ["part-part"]}}
    built = build(parse_scene(data, tmp_path / "s.toml"), detect=False)
    idx = {p.name: k for k, p in enumerate(built.parts)}
    skip = part_pairs_skipped(built)
    assert skip[idx["base/gbase"], idx["shoulder/gsh"]] and skip[idx["shoulder/gsh"], idx["base/gbase"]]
    assert not skip[idx["world/floor"], idx["shoulder/gsh"]]
