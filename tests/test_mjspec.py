"""The scene written as MuJoCo models (cablecheck.build.mjspec): euler angles as
quaternions, parts placed and sized as the scene says (relative to the
model's origin), planes drawn with a positive grid, the two models' margins,
and the step's time constants set together."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from buildscenes import slider_scene
from hypothesis import given
from strategies import coords

from cablecheck.build.built import CABLE_PREFIX, end_roll_body
from cablecheck.build.cablephysics import contact_time_constant, edge_time_constant
from cablecheck.build.mjspec import PLANE_GRID, SIM_MARGIN_FRACTION, euler_quat, part_size, set_step
from cablecheck.build.stages import build
from cablecheck.scene.frames import euler_matrix
from cablecheck.scene.load import parse_scene


@given(coords(3, -720.0, 720.0))
def test_euler_quaternion_is_a_unit_quaternion_of_the_scene_rotation(euler):
    q = euler_quat(euler)
    assert abs(np.linalg.norm(q) - 1.0) < 1e-12
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, q)
    assert np.allclose(mat.reshape(3, 3), euler_matrix(euler), rtol=0, atol=1e-12)


def test_parts_are_placed_and_sized_as_the_scene_says(tmp_path):
    data = slider_scene(tmp_path)
    data["parts"] += [
        {"name": "tilted", "shape": "cylinder", "size": [0.03, 0.1], "pos": [1e4, -2e4, 5.0], "euler": [30, -45, 60]},
        {"name": "floor", "shape": "plane", "pos": [0, 0, -0.1]}]
    built = build(parse_scene(data, tmp_path / "s.toml"))
    d = mujoco.MjData(built.model)
    mujoco.mj_kinematics(built.model, d)
    by = {p.name: p for p in built.parts}
    g = by["tilted"].geom_id
    assert np.allclose(d.geom_xpos[g] + built.origin, [1e4, -2e4, 5.0], rtol=0, atol=1e-9)
    assert np.allclose(d.geom_xmat[g].reshape(3, 3), euler_matrix([30, -45, 60]), atol=1e-12)
    assert np.allclose(built.model.geom_size[g][:2], [0.03, 0.1])
    assert np.allclose(built.model.geom_size[by["floor"].geom_id], [0.0, 0.0, PLANE_GRID])
    data["parts"][-1] = {"name": "mat", "shape": "plane", "size": [0.4, 0.2], "pos": [0, 0, -0.05]}
    mat = build(parse_scene(data, tmp_path / "s.toml"))
    assert np.allclose(mat.model.geom_size[mat.parts[-1].geom_id], [0.4, 0.2, 0.04])   # a tenth of the larger
    margin = built.model.geom_margin[g]
    assert margin == pytest.approx(SIM_MARGIN_FRACTION * 0.004)
    assert built.detect.geom_margin[g] == pytest.approx(built.scene.check.clearance)


def test_part_size_pads_to_three_numbers(tmp_path):
    scene = parse_scene(slider_scene(tmp_path) | {"parts": [
        {"name": "ball", "shape": "sphere", "size": [0.05], "pos": [0, 0, 0]}]}, tmp_path / "s.toml")
    assert part_size(scene.parts[0]) == [0.05, 0.0, 0.0]


def test_set_step_moves_the_time_constants_with_the_step(tmp_path):
    built = build(parse_scene(slider_scene(tmp_path), tmp_path / "s.toml"))
    m = built.model
    set_step(m, 2.5e-4)
    assert m.opt.timestep == 2.5e-4
    assert np.all(m.flex_solref[:, 0] == contact_time_constant(2.5e-4))
    edges = m.eq_type == int(mujoco.mjtEq.mjEQ_FLEX)
    assert edges.any() and np.all(m.eq_solref[edges, 0] == edge_time_constant(2.5e-4))


def test_the_detection_model_computes_no_edge_jacobians_and_finds_the_same_contacts():
    """The detection model's flexes carry no edge equality, stiffness or
    damping (`never_stepped`): mj_flex computes no edge Jacobian there, and
    its pass without mj_comPos finds the contacts, bit for bit and in order,
    of a pass with them and mj_comPos."""
    import copy
    import dataclasses
    from pathlib import Path as P

    from cablecheck.run.loop import Simulation
    from cablecheck.scene.load import load_scene
    scene = load_scene(P(__file__).resolve().parents[1] / "scenes" / "robot_cell.toml")
    built = build(dataclasses.replace(scene, duration=0.04, settle=0.02))   # hoses on an arm, always in contact
    m = built.detect
    assert not m.flex_edgeequality.any() and not m.flex_damping.any()
    assert not m.flex_edgestiffness.any() and not m.flex_edgedamping.any()
    cables = [c.flex_id for c in built.cables]
    assert built.model.flex_edgeequality[cables].all() and built.model.flex_damping[cables].any()
    ref = copy.deepcopy(m)                     # as compiled before: the simulation model's edge settings
    for f in ("flex_edgeequality", "flex_edgestiffness", "flex_edgedamping", "flex_damping"):
        getattr(ref, f)[cables] = getattr(built.model, f)[cables]
    sim = Simulation(built)
    sim.reset()
    sim.settle()
    qposes = [s.qpos for k, s in enumerate(sim.steps(contacts=False)) if k % 4 == 0]
    d, dr = mujoco.MjData(m), mujoco.MjData(ref)
    found = 0
    for qpos in qposes:
        d.qpos[:], dr.qpos[:] = qpos, qpos
        mujoco.mj_kinematics(m, d)
        mujoco.mj_flex(m, d)
        mujoco.mj_collision(m, d)
        mujoco.mj_kinematics(ref, dr)
        mujoco.mj_comPos(ref, dr)
        mujoco.mj_flex(ref, dr)
        mujoco.mj_collision(ref, dr)
        assert not d.flexedge_J.any() and dr.flexedge_J.any()
        assert np.array_equal(d.flexedge_length, dr.flexedge_length)
        assert d.ncon == dr.ncon
        n = d.ncon
        for f in ("geom", "flex", "elem", "vert", "dist", "pos", "frame", "includemargin"):
            assert np.array_equal(getattr(d.contact, f)[:n], getattr(dr.contact, f)[:n]), f
        found += n
    assert found


@pytest.mark.parametrize("name", ['pow"er <1>', "a & b", "it's > x"])
def test_names_with_xml_characters_build_as_written(tmp_path, name):
    # the cables are written into the model as MJCF text: names are quoted, not pasted
    data = slider_scene(tmp_path)
    data["cables"][0]["name"] = name
    built = build(parse_scene(data, tmp_path / "s.toml"))
    assert [c.name for c in built.cables] == [name]
    assert mujoco.mj_name2id(built.model, mujoco.mjtObj.mjOBJ_FLEX, CABLE_PREFIX + name) >= 0


def test_a_scene_whose_names_hold_xml_characters_runs_and_records(tmp_path):
    """Cable, body and part names with quotes, <, > and & run end to end: the
    models build, the run checks, the report and the recording name them as written."""
    from cablecheck.run.runner import RunOptions, run_scene

    cable, body, part = 'pow"er <1>', "sl&der <a>", "frame/po'st > 2"
    data = slider_scene(tmp_path)
    data["cables"][0]["name"] = cable
    data["bodies"][0]["name"] = body
    data["cables"][0]["end"]["body"] = body
    data["motion"][0]["body"] = body
    data["parts"][0]["name"] = part
    data["parts"][0]["pos"] = [0.3, 0.0, 0.45]   # in the cable's way: the run reports it by name
    report = run_scene(parse_scene(data, tmp_path / "odd.toml"),
                       RunOptions(report=tmp_path / "r.json", record=tmp_path / "r.rrd"))
    assert report["complete"], report.get("error")
    pairs = {(e["a"], e["b"]) for e in report["events"]}
    assert (cable, part) in pairs and {n for pair in pairs for n in pair} == {cable, part}
    assert (tmp_path / "r.rrd").stat().st_size > 0


_ROBOT_DEFAULTS = """<joint limited="true" damping="50" frictionloss="0.1" armature="0.01"/>
      <geom condim="4" solref="0.01 1" solimp="0.99 0.99 0.01" friction="2 0.1 0.01" group="3"/>"""

_CLASSED = """<mujoco>
  {option}
  <default>
    {main}
    <default class="robot">
      {robot}
    </default>
  </default>
  <worldbody>
    <body name="stand" pos="0 0 0.2" {cls}>
      <geom name="column" type="box" size="0.03 0.03 0.1"/>
      <body name="link" pos="0 0 0.15">
        <joint name="j" type="hinge" axis="0 0 1" range="-90 90"/>
        <geom name="arm" type="capsule" fromto="0 0 0 0.25 0 0" size="0.02"/>
      </body>
    </body>
  </worldbody>
</mujoco>"""


@pytest.mark.parametrize("detect", [False, True])
@pytest.mark.parametrize("where", ["childclass", "main"])
def test_what_the_scene_adds_to_an_mjcf_body_ignores_its_classes(tmp_path, detect, where):
    """A clamped end's roll hinge, a part on a link and a scripted body of the
    scene are built as in the same model without classes (MuJoCo's own
    defaults): a class limiting its joints without a range (MuJoCo refuses
    the hinge: range 0 0), damping them or adding friction loss, or giving
    its geoms their own contact parameters, reaches none of what the scene
    adds, whether it is the link's childclass or the model's main class; and
    the model's noslip iterations (none with flexes) stop nothing.
    (gymnasium-robotics' kitchen Franka failed to compile on its childclass,
    its Adroit hand on its main class; Fetch's gripper class gave a tool part
    condim 4.)"""
    def built(classes: bool):
        main = _ROBOT_DEFAULTS if classes and where == "main" else ""
        cls = 'childclass="robot"' if classes and where == "childclass" else ""
        option = '<option noslip_iterations="20"/>' if classes else ""
        (tmp_path / "arm.xml").write_text(_CLASSED.format(option=option, main=main, robot=_ROBOT_DEFAULTS, cls=cls))
        data = {"scene": {"name": "t", "units": "m", "duration": 0.05, "settle": 0.05, "mjcf": "arm.xml"},
                "effects": {"contact": ["cable-structure"]},
                "bodies": [{"name": "slider", "pos": [0.0, 0.4, 0.1]}],
                "parts": [{"name": "tool", "body": "link", "shape": "box", "size": [0.02, 0.02, 0.02],
                           "pos": [0.3, 0, 0]},
                          {"name": "block", "body": "slider", "shape": "box", "size": [0.02, 0.02, 0.02]}],
                "cables": [{"name": "hose", "radius": 0.005, "start": {"pos": [-0.2, 0, 0.3]},
                            "end": {"body": "link", "pos": [0.2, 0, 0.04]}, "length": 0.6, "segments": 16}]}
        b = build(parse_scene(data, tmp_path / "s.toml"))
        return b.detect if detect else b.model

    classed, plain = built(True), built(False)
    assert classed.jnt_limited[classed.joint("j").id] == 1           # the model's own joint keeps its class
    assert classed.geom_condim[classed.geom("arm").id] == 4
    roll = classed.joint(end_roll_body("hose")).id
    assert roll == plain.joint(end_roll_body("hose")).id
    assert classed.jnt_limited[roll] == plain.jnt_limited[roll] == 0
    assert classed.dof_damping[classed.jnt_dofadr[roll]] == plain.dof_damping[plain.jnt_dofadr[roll]] == 0.0
    for field in ("dof_frictionloss", "dof_armature"):
        assert getattr(classed, field)[classed.jnt_dofadr[roll]] == getattr(plain, field)[plain.jnt_dofadr[roll]]
    free, free_plain = classed.joint("slider/free").id, plain.joint("slider/free").id
    dofs = slice(classed.jnt_dofadr[free], classed.jnt_dofadr[free] + 6)
    dofs_plain = slice(plain.jnt_dofadr[free_plain], plain.jnt_dofadr[free_plain] + 6)
    for field in ("dof_damping", "dof_frictionloss", "dof_armature"):
        assert np.array_equal(getattr(classed, field)[dofs], getattr(plain, field)[dofs_plain]), field
    assert classed.opt.noslip_iterations == 0
    for part in ("tool", "block"):
        g, h = classed.geom(part).id, plain.geom(part).id
        for field in ("geom_condim", "geom_solref", "geom_solimp", "geom_friction", "geom_group", "geom_margin",
                      "geom_contype", "geom_conaffinity", "geom_priority", "geom_solmix", "geom_gap"):
            assert np.array_equal(getattr(classed, field)[g], getattr(plain, field)[h]), (part, field)
