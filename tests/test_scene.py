"""Scene loading: valid scenes, unit conversion, and every class of bad input."""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Mapping
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh
from hypothesis import HealthCheck, given, settings, strategies as st

import cablecheck.scene.format as scene_format
from cablecheck.scene.errors import SceneError
from cablecheck.scene.format import DEFAULT_CLEARANCE, DEFAULT_DAMPING, Hold
from cablecheck.scene.frames import euler_matrix
from cablecheck.scene.load import load_scene, parse_scene
from cablecheck.scene.records import Anchor, BodyKey, JointKey, KeyframeKey, Scene

ARM_XML = """
<mujoco model="arm">
  <worldbody>
    <body name="upper" pos="0 0 0.5" euler="0 90 0">
      <joint name="shoulder" type="ball"/>
      <geom type="capsule" size="0.03 0.1"/>
      <body name="forearm" pos="0 0 0.2">
        <joint name="elbow" type="hinge" axis="0 1 0"/>
        <geom type="capsule" size="0.025 0.1"/>
        <body name="slider" pos="0 0 0.2">
          <joint name="lift" type="slide"/>
          <geom size="0.02"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

# The SPEC's example scene, verbatim apart from the commented-out lines.
SPEC_EXAMPLE = """
[scene]
name = "drawer-harness"
units = "m"            # "m" or "mm"
duration = 3.0         # simulated seconds of scripted motion after t = 0
timestep = 0.002       # optional
settle = 1.0           # optional: seconds simulated with motion frozen before t = 0
mjcf = "arm.xml"       # optional: an existing MuJoCo model (robot, fixture) to build on

[effects]              # simulate only what the scene calls for
dynamics = true        # false: no stepping; check the cables exactly as routed
gravity = true
contact = ["cable-structure"]   # interactions that push back physically, any of

[check]
method = "points"      # "points" (paper: discrete points) or "exact" (segment distances)
spacing = 2.0          # discrete-point spacing as a multiple of the cable radius (paper: 2)
clearance = 0.005      # soft interference: surface distance below this (default 5 mm in scene units)
every = 1              # check every Nth step
validate = true        # compare with MuJoCo's contacts at each checked step
attach_zone = 5.0      # arc length, in cable radii, next to an end or clip where touching

[[bodies]]             # rigid bodies moved by script; parts and cable ends ride on them
name = "drawer"
pos = [0, 0, 0]
euler = [0, 0, 0]

[[parts]]
name = "cabinet/rail_left"     # "/" separates assembly levels
body = "world"                 # "world", a [[bodies]] name or a body of the mjcf model
shape = "box"                  # box | sphere | cylinder | capsule | ellipsoid | plane | mesh
size = [0.3, 0.02, 0.02]
pos = [0.4, 0.1, 0.3]
euler = [0, 0, 0]
# file = "meshes/bracket.stl"  # shape = "mesh": any format trimesh reads
# scale = 0.001
# keepout = true               # a clearance zone (e.g. bolt wrench space): detected, never collides

[[cables]]
name = "power"
radius = 0.004
start = { body = "world", pos = [0, 0, 0.6] }
end = { body = "drawer", pos = [0.5, 0, 0.6] }
via = [[0.25, 0.0, 0.5]]       # optional routing waypoints for the initial shape
length = 0.7                   # optional; default: length of the route; never shorter
# points = [[...], ...]        # alternative to start/via: the routed centreline itself
clips = [ { body = "world", pos = [0.12, 0.0, 0.55] } ]   # optional clamps along the route
segments = 40                  # optional: MuJoCo elements
young = 1.0e8                  # bending modulus, Pa
density = 1500                 # kg/m^3
min_bend_radius = 0.04         # optional: report bends tighter than this

[[motion]]                     # keyframes, interpolated in time; a body's keys are its world
body = "drawer"                # pose (as in [[bodies]]); before the first key and after the
                               # last one it holds that key's pose
keys = [ { t = 0.0, pos = [0, 0, 0] },
         { t = 2.0, pos = [0.3, 0, 0], euler = [0, 0, 0] } ]

[[motion]]                     # a joint of the mjcf model, driven kinematically
joint = "elbow"
keys = [ { t = 0.0, value = 0.0 }, { t = 2.0, value = -90.0 } ]   # degrees, or scene units for slides
"""

# A scene in metres using every feature; tests mutate copies of it.
BASE = {
    "scene": {"name": "t", "units": "m", "duration": 1.0, "timestep": 0.001, "settle": 0.5,
              "mjcf": "arm.xml"},
    "effects": {"dynamics": True, "gravity": False, "contact": ["cable-structure", "self"]},
    "check": {"method": "exact", "spacing": 1.0, "clearance": 0.002, "every": 2,
              "validate": False, "attach_zone": 3.0},
    "bodies": [{"name": "drawer", "pos": [1.0, 0.0, 0.0], "euler": [0.0, 0.0, 90.0]}],
    "parts": [
        {"name": "cab/rail", "shape": "box", "size": [0.3, 0.02, 0.02], "pos": [0.4, 0.1, 0.3],
         "euler": [10.0, 0.0, 0.0]},
        {"name": "ball", "body": "forearm", "shape": "sphere", "size": [0.05]},
        {"name": "floor", "shape": "plane"},
        {"name": "bracket", "body": "drawer", "shape": "mesh", "file": "box.stl",
         "scale": 0.5, "keepout": True},
    ],
    "cables": [
        {"name": "power", "radius": 0.004, "start": {"pos": [0.0, 0.0, 0.6]},
         "end": {"body": "drawer", "pos": [0.5, 0.0, 0.6]}, "via": [[0.25, 0.0, 0.5]],
         "length": 2.0, "clips": [{"body": "upper", "pos": [0.0, 0.0, 0.1]}],
         "segments": 40, "young": 1e8, "density": 1200.0, "min_bend_radius": 0.04},
        {"name": "signal", "radius": 0.002,
         "points": [[0.0, 0.1, 0.0], [0.1, 0.1, 0.0], [0.2, 0.1, 0.05]],
         "start": {"body": "drawer"}},
    ],
    "motion": [
        {"body": "drawer", "keys": [{"t": 0.0, "pos": [1.0, 0.0, 0.0]},
                                    {"t": 2.0, "pos": [1.3, 0.0, 0.0], "euler": [0.0, 0.0, 45.0]}]},
        {"joint": "elbow", "keys": [{"t": 0.0, "value": 0.0}, {"t": 2.0, "value": -90.0}]},
        {"joint": "lift", "keys": [{"t": 0.0, "value": 0.02}, {"t": 1.0, "value": 0.1}]},
    ],
}


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    """A folder with the files BASE refers to, plus broken ones."""
    d = tmp_path_factory.mktemp("scene")
    (d / "arm.xml").write_text(ARM_XML)
    trimesh.creation.box(extents=[0.1, 0.1, 0.1]).export(d / "box.stl")
    open_box = trimesh.creation.box(extents=[0.1, 0.1, 0.1])
    open_box.update_faces(np.arange(len(open_box.faces)) > 0)
    open_box.export(d / "open.stl")
    (d / "garbage.stl").write_bytes(b"solid nothing\nthis is not an stl\n")
    (d / "broken.xml").write_text("<mujoco><worldbody><geom type='box'/></worldbody></mujoco>")
    return d


def parse(data: dict, folder: Path) -> Scene:
    return parse_scene(data, folder / "scene.toml")


def put(data: dict, path: str, value) -> dict:
    """Set data[a][b][0]... for path 'a.b.0...'; returns data."""
    *head, last = [int(k) if k.isdigit() else k for k in path.split(".")]
    target = data
    for key in head:
        target = target[key]
    target[last] = value
    return data


def drop(data: dict, path: str) -> dict:
    *head, last = [int(k) if k.isdigit() else k for k in path.split(".")]
    target = data
    for key in head:
        target = target[key]
    del target[last]
    return data


# -- valid scenes ------------------------------------------------------------


def test_minimal_scene_has_spec_defaults(tmp_path):
    f = tmp_path / "min.toml"
    f.write_text('[scene]\nname = "min"\nunits = "mm"\nduration = 0\n')
    s = load_scene(f)
    assert (s.name, s.units, s.scale, s.duration) == ("min", "mm", 0.001, 0.0)
    assert (s.timestep, s.settle, s.mjcf) == (0.002, 0.0, None)
    assert s.effects.dynamics and s.effects.gravity and s.effects.contact == frozenset()
    assert s.check.method == "points" and s.check.spacing == 2.0 and s.check.every == 1
    assert s.check.clearance == DEFAULT_CLEARANCE == 0.005   # 5 mm whatever the units
    assert s.check.validate and s.check.attach_zone == 5.0
    assert s.bodies == s.parts == s.cables == s.motions == ()


def test_spec_example_loads(folder):
    f = folder / "spec.toml"
    f.write_text(SPEC_EXAMPLE)
    s = load_scene(f)
    assert s.name == "drawer-harness" and s.settle == 1.0 and s.mjcf == folder / "arm.xml"
    assert s.effects.contact == {"cable-structure"}
    (part,) = s.parts
    assert part.name == "cabinet/rail_left" and part.size == (0.3, 0.02, 0.02)
    (cable,) = s.cables
    assert cable.start == Anchor("world", (0.0, 0.0, 0.6))
    assert cable.start.hold == Hold.CLAMP and cable.damping == DEFAULT_DAMPING
    assert cable.end == Anchor("drawer", (0.5, 0.0, 0.6))
    assert cable.via.shape == (1, 3) and cable.points is None and cable.length == 0.7
    assert cable.clips == (Anchor("world", (0.12, 0.0, 0.55)),)
    assert (cable.segments, cable.young, cable.density, cable.min_bend_radius) == (40, 1e8, 1500, 0.04)
    np.testing.assert_allclose(cable.route, [[0, 0, 0.6], [0.25, 0, 0.5], [0.5, 0, 0.6]])
    body, joint = s.motions
    assert body.body == "drawer" and body.joint is None
    assert body.keys == (BodyKey(0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
                         BodyKey(2.0, (0.3, 0.0, 0.0), (0.0, 0.0, 0.0)))
    assert joint.joint == "elbow" and joint.keys == (JointKey(0.0, 0.0), JointKey(2.0, -90.0))


def test_base_scene_records(folder):
    s = parse(copy.deepcopy(BASE), folder)
    assert s.effects == s.effects.__class__(True, False, frozenset({"cable-structure", "self"}))
    assert [p.shape for p in s.parts] == ["box", "sphere", "plane", "mesh"]
    assert s.parts[2].size == () and s.parts[3].size == ()
    assert s.parts[3].file == folder / "box.stl" and s.parts[3].file.is_absolute()
    assert s.parts[3].mesh_scale == 0.5 and s.parts[3].keepout
    power, signal = s.cables
    assert signal.via.shape == (0, 3) and signal.length is None and signal.segments is None
    assert signal.end == Anchor("world", (0.2, 0.1, 0.05))
    # the drawer turns 90 degrees about z at (1, 0, 0): world (0, 0.1, 0) is (0.1, 1, 0) in it
    np.testing.assert_allclose(signal.start.pos, [0.1, 1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(power.route[-1], [1.0, 0.5, 0.6], atol=1e-12)
    # a key without euler keeps the body's [[bodies]] orientation
    assert s.motions[0].keys[0].euler == (0.0, 0.0, 90.0)
    with pytest.raises(ValueError):
        power.via[0, 0] = 1.0   # records are frozen, arrays too


def test_euler_matches_mujoco():
    xml = '<mujoco><worldbody><body euler="10 -25 130"><geom size=".1"/></body></worldbody></mujoco>'
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    np.testing.assert_allclose(euler_matrix([10, -25, 130]), d.xmat[1].reshape(3, 3), atol=1e-12)


def test_anchor_on_mjcf_body_uses_its_compiled_pose(folder):
    data = copy.deepcopy(BASE)
    put(data, "cables.1.start", {"body": "upper"})
    s = parse(data, folder)
    m = mujoco.MjModel.from_xml_path(str(folder / "arm.xml"))
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    b = m.body("upper").id
    world = d.xpos[b] + d.xmat[b].reshape(3, 3) @ np.asarray(s.cables[1].start.pos)
    np.testing.assert_allclose(world, [0.0, 0.1, 0.0], atol=1e-12)


def test_t0_frames_follow_the_first_keys(folder):
    """At t = 0 a keyframed body is at its first key (it holds it until then), and
    keyframed mjcf joints are at their first key's value."""
    data = copy.deepcopy(BASE)
    put(data, "bodies.0.pos", [0.0, 0.0, 0.0])
    put(data, "motion.0.keys.0", {"t": 0.5, "pos": [2.0, 0.0, 0.0]})   # euler from [[bodies]]
    put(data, "motion.1.keys.0.value", -30.0)
    put(data, "motion.2.keys.0.value", 0.05)
    put(data, "cables.0.end", {"body": "slider", "pos": [0.0, 0.01, 0.0]})
    put(data, "cables.0.length", 5.0)
    put(data, "cables.1.end", {"body": "drawer"})
    s = parse(data, folder)
    origin, rotation = s.start_frames["drawer"]
    np.testing.assert_allclose(origin, [2.0, 0.0, 0.0])
    np.testing.assert_allclose(rotation, euler_matrix([0, 0, 90]), atol=1e-15)
    # the cable with points ends at (0.2, 0.1, 0.05): in the drawer frame at t = 0
    np.testing.assert_allclose(rotation @ s.cables[1].end.pos + origin, [0.2, 0.1, 0.05])
    m = mujoco.MjModel.from_xml_path(str(folder / "arm.xml"))
    d = mujoco.MjData(m)
    d.qpos[m.jnt_qposadr[m.joint("elbow").id]] = np.radians(-30.0)
    d.qpos[m.jnt_qposadr[m.joint("lift").id]] = 0.05
    mujoco.mj_kinematics(m, d)
    b = m.body("slider").id
    np.testing.assert_allclose(s.start_frames["slider"][0], d.xpos[b], atol=1e-12)
    np.testing.assert_allclose(s.cables[0].route[-1],
                               d.xpos[b] + d.xmat[b].reshape(3, 3) @ [0.0, 0.01, 0.0], atol=1e-12)
    assert {"world", "drawer", "upper", "forearm", "slider"} <= set(s.start_frames)


def to_mm(data: dict) -> dict:
    """The same scene written in millimetres."""
    d = copy.deepcopy(data)
    k = 1000.0
    scale = lambda v: [scale(x) for x in v] if isinstance(v, list) else v * k  # noqa: E731
    d["scene"]["units"] = "mm"
    d["check"]["clearance"] *= k
    for b in d["bodies"]:
        b["pos"] = scale(b["pos"])
    for p in d["parts"]:
        for key in ("size", "pos", "scale"):   # mesh scale: file units -> scene units
            if key in p:
                p[key] = scale(p[key])
    for c in d["cables"]:
        for key in ("radius", "via", "length", "points", "min_bend_radius"):
            if key in c:
                c[key] = scale(c[key])
        for a in [c.get("start", {}), c.get("end", {}), *c.get("clips", [])]:
            if "pos" in a:
                a["pos"] = scale(a["pos"])
    for m in d["motion"]:
        for key in m["keys"]:
            if "pos" in key:
                key["pos"] = scale(key["pos"])
            if m.get("joint") == "lift":   # slide joint: scene units
                key["value"] *= k
    return d


def assert_same(a, b, where="scene"):
    """Records equal up to float rounding, recursively."""
    if dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for field in dataclasses.fields(a):
            assert_same(getattr(a, field.name), getattr(b, field.name), f"{where}.{field.name}")
    elif isinstance(a, Mapping):
        assert sorted(a) == sorted(b), where
        for key in a:
            assert_same(a[key], b[key], f"{where}[{key!r}]")
    elif isinstance(a, (tuple, list, np.ndarray)) and not isinstance(a, str):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, float):
        assert math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-15), f"{where}: {a} != {b}"
    else:
        assert a == b, where


def test_mm_scene_equals_m_scene(folder):
    m = parse(copy.deepcopy(BASE), folder)
    mm = parse(to_mm(BASE), folder)
    assert (m.units, m.scale, mm.units, mm.scale) == ("m", 1.0, "mm", 0.001)
    lift_m, lift_mm = m.motions[2], mm.motions[2]
    assert [k.value for k in lift_mm.keys] == [20.0, 100.0]   # raw, in scene units
    assert_same(lift_m.keys[1].value * m.scale, lift_mm.keys[1].value * mm.scale)
    same = lambda s: dataclasses.replace(s, units="", scale=0.0, motions=s.motions[:2])  # noqa: E731
    assert_same(same(m), same(mm))


def test_length_check_uses_bodies_pose_and_tolerance(folder):
    data = copy.deepcopy(BASE)
    route = parse(data, folder).cables[0].route
    exact = float(np.linalg.norm(np.diff(route, axis=0), axis=1).sum())
    put(data, "cables.0.length", exact * (1 - 1e-12))
    assert parse(data, folder).cables[0].length == pytest.approx(exact)
    put(data, "cables.0.length", exact * (1 - 1e-6))
    with pytest.raises(SceneError, match="shorter than the route"):
        parse(data, folder)


# -- bad input ---------------------------------------------------------------


def check_error(exc: pytest.ExceptionInfo, file: Path, key: str, fragment: str):
    e = exc.value
    assert (e.key, e.file) == (key, file), str(e)
    assert fragment in e.problem, str(e)
    assert str(e) == f"{file}: {key}: {e.problem}"


def test_toml_syntax_error_names_line(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text('[scene]\nname = "x"\nunits = \n')
    with pytest.raises(SceneError) as exc:
        load_scene(f)
    check_error(exc, f, "line 3, column 9", "invalid TOML")


def test_missing_file(tmp_path):
    with pytest.raises(SceneError) as exc:
        load_scene(tmp_path / "nope.toml")
    check_error(exc, tmp_path / "nope.toml", "(file)", "cannot read")


def test_directory_is_not_a_scene(tmp_path):
    with pytest.raises(SceneError) as exc:
        load_scene(tmp_path)
    check_error(exc, tmp_path, "(file)", "cannot read")


def test_not_utf8(tmp_path):
    f = tmp_path / "latin.toml"
    f.write_bytes('[scene]\nname = "caf\u00e9"\n'.encode("latin-1"))
    with pytest.raises(SceneError) as exc:
        load_scene(f)
    check_error(exc, f, "(file)", "not UTF-8")


def nested_scene_dict_wrong(d):
    d["bodies"] = {"name": "drawer"}
    return d


BAD = [
    # missing required keys
    ("no scene", lambda d: drop(d, "scene"), "scene", "missing"),
    ("no name", lambda d: drop(d, "scene.name"), "scene.name", "missing"),
    ("no units", lambda d: drop(d, "scene.units"), "scene.units", "missing"),
    ("no duration", lambda d: drop(d, "scene.duration"), "scene.duration", "missing"),
    ("no radius", lambda d: drop(d, "cables.1.radius"), "cables[1].radius", "missing"),
    ("no shape", lambda d: drop(d, "parts.0.shape"), "parts[0].shape", "missing"),
    ("no size", lambda d: drop(d, "parts.0.size"), "parts[0].size", "required for shape 'box'"),
    ("no mesh file", lambda d: drop(d, "parts.3.file"), "parts[3].file", "required for shape 'mesh'"),
    ("no start", lambda d: drop(d, "cables.0.start"), "cables[0].start", "missing"),
    ("no end", lambda d: drop(d, "cables.0.end"), "cables[0].end", "missing"),
    ("no keys", lambda d: drop(d, "motion.0.keys"), "motion[0].keys", "missing"),
    ("no key t", lambda d: drop(d, "motion.1.keys.1.t"), "motion[1].keys[1].t", "missing"),
    ("no key value", lambda d: drop(d, "motion.1.keys.0.value"), "motion[1].keys[0].value",
     "missing"),
    ("no body name", lambda d: drop(d, "bodies.0.name"), "bodies[0].name", "missing"),
    # unknown keys, with a suggestion
    ("unknown top", lambda d: put(d, "cable", []), "cable", "did you mean 'cables'?"),
    ("unknown scene", lambda d: put(d, "scene.unit", "m"), "scene.unit", "did you mean 'units'?"),
    ("unknown cable", lambda d: put(d, "cables.0.raduis", 1), "cables[0].raduis",
     "did you mean 'radius'?"),
    ("unknown anchor", lambda d: put(d, "cables.0.start.bdy", "x"), "cables[0].start.bdy",
     "did you mean 'body'?"),
    ("unknown check", lambda d: put(d, "check.spacng", 1), "check.spacng",
     "did you mean 'spacing'?"),
    ("unknown effects", lambda d: put(d, "effects.colour", 1), "effects.colour", "valid keys:"),
    ("unknown part", lambda d: put(d, "parts.0.sise", [1]), "parts[0].sise", "'size'"),
    ("unknown key key", lambda d: put(d, "motion.1.keys.0.vlaue", 1), "motion[1].keys[0].vlaue",
     "'value'"),
    ("value on body key", lambda d: put(d, "motion.0.keys.0.value", 1),
     "motion[0].keys[0].value", "unknown key"),
    ("unknown body", lambda d: put(d, "bodies.0.mass", 1), "bodies[0].mass", "unknown key"),
    ("unknown motion", lambda d: put(d, "motion.0.speed", 1), "motion[0].speed", "unknown key"),
    ("unknown clip", lambda d: put(d, "cables.0.clips.0.euler", [0, 0, 0]),
     "cables[0].clips[0].euler", "unknown key"),
    # wrong types
    ("radius string", lambda d: put(d, "cables.0.radius", "4"), "cables[0].radius",
     "expected a number, got a string"),
    ("radius bool", lambda d: put(d, "cables.0.radius", True), "cables[0].radius",
     "expected a number, got a boolean"),
    ("pos arity", lambda d: put(d, "bodies.0.pos", [1, 2]), "bodies[0].pos", "expected 3 numbers"),
    ("pos not array", lambda d: put(d, "parts.0.pos", 1.0), "parts[0].pos", "expected an array"),
    ("pos entry", lambda d: put(d, "cables.0.start.pos", [0, "a", 0]), "cables[0].start.pos[1]",
     "expected a number"),
    ("euler bool", lambda d: put(d, "parts.0.euler", [0, False, 0]), "parts[0].euler[1]",
     "boolean"),
    ("dynamics int", lambda d: put(d, "effects.dynamics", 1), "effects.dynamics",
     "expected true or false"),
    ("validate str", lambda d: put(d, "check.validate", "yes"), "check.validate",
     "expected true or false"),
    ("keepout str", lambda d: put(d, "parts.3.keepout", "true"), "parts[3].keepout",
     "expected true or false"),
    ("every float", lambda d: put(d, "check.every", 2.0), "check.every", "expected an integer"),
    ("segments float", lambda d: put(d, "cables.0.segments", 40.0), "cables[0].segments",
     "expected an integer"),
    ("name int", lambda d: put(d, "scene.name", 3), "scene.name", "expected a string"),
    ("contact string", lambda d: put(d, "effects.contact", "self"), "effects.contact",
     "expected an array of strings"),
    ("bodies table", nested_scene_dict_wrong, "bodies", "[[bodies]]"),
    ("scene array", lambda d: put(d, "scene", [1]), "scene", "expected a table"),
    ("start not table", lambda d: put(d, "cables.0.start", [0, 0, 0]), "cables[0].start",
     "expected a table"),
    ("via flat", lambda d: put(d, "cables.0.via", [0.1, 0.2, 0.3]), "cables[0].via[0]",
     "expected an array of 3 numbers"),
    ("clips table", lambda d: put(d, "cables.0.clips", {"body": "world"}), "cables[0].clips",
     "expected an array"),
    ("keys table", lambda d: put(d, "motion.0.keys", {"t": 0}), "motion[0].keys",
     "expected an array of tables"),
    ("mesh path int", lambda d: put(d, "parts.3.file", 1), "parts[3].file", "expected a string"),
    # NaN and infinity
    ("radius nan", lambda d: put(d, "cables.0.radius", math.nan), "cables[0].radius", "finite"),
    ("pos inf", lambda d: put(d, "bodies.0.pos", [0, math.inf, 0]), "bodies[0].pos[1]", "finite"),
    ("duration inf", lambda d: put(d, "scene.duration", math.inf), "scene.duration", "finite"),
    ("key t nan", lambda d: put(d, "motion.0.keys.1.t", math.nan), "motion[0].keys[1].t",
     "finite"),
    ("value -inf", lambda d: put(d, "motion.1.keys.1.value", -math.inf),
     "motion[1].keys[1].value", "finite"),
    ("points nan", lambda d: put(d, "cables.1.points.1", [0, math.nan, 0]),
     "cables[1].points[1][1]", "finite"),
    ("huge integer", lambda d: put(d, "bodies.0.pos", [0, 10**400, 0]), "bodies[0].pos[1]",
     "out of range"),
    ("huge float", lambda d: put(d, "cables.0.via.0", [1e300, 0, 0]), "cables[0].via[0][0]",
     "out of range"),
    # ranges
    ("radius zero", lambda d: put(d, "cables.0.radius", 0), "cables[0].radius", "positive"),
    ("radius negative", lambda d: put(d, "cables.1.radius", -0.001), "cables[1].radius",
     "positive"),
    ("length zero", lambda d: put(d, "cables.0.length", 0.0), "cables[0].length", "positive"),
    ("duration negative", lambda d: put(d, "scene.duration", -1), "scene.duration",
     "not be negative"),
    ("settle negative", lambda d: put(d, "scene.settle", -0.1), "scene.settle", "not be negative"),
    ("timestep zero", lambda d: put(d, "scene.timestep", 0), "scene.timestep", "positive"),
    ("size zero", lambda d: put(d, "parts.0.size.1", 0), "parts[0].size[1]", "positive"),
    ("size negative", lambda d: put(d, "parts.1.size.0", -0.05), "parts[1].size[0]", "positive"),
    ("mesh scale zero", lambda d: put(d, "parts.3.scale", 0), "parts[3].scale", "positive"),
    ("young zero", lambda d: put(d, "cables.0.young", 0), "cables[0].young", "positive"),
    ("density negative", lambda d: put(d, "cables.0.density", -1), "cables[0].density",
     "positive"),
    ("bend radius zero", lambda d: put(d, "cables.0.min_bend_radius", 0),
     "cables[0].min_bend_radius", "positive"),
    ("spacing zero", lambda d: put(d, "check.spacing", 0), "check.spacing", "positive"),
    ("clearance negative", lambda d: put(d, "check.clearance", -0.001), "check.clearance",
     "not be negative"),
    ("attach zone negative", lambda d: put(d, "check.attach_zone", -1), "check.attach_zone",
     "not be negative"),
    ("every zero", lambda d: put(d, "check.every", 0), "check.every", "at least 1"),
    ("segments one", lambda d: put(d, "cables.0.segments", 1), "cables[0].segments",
     "at least 2"),
    ("hold unknown", lambda d: put(d, "cables.0.start.hold", "weld"), "cables[0].start.hold",
     "'clamp', 'pin', 'free'"),
    ("hold not a string", lambda d: put(d, "cables.0.end.hold", 1), "cables[0].end.hold",
     "expected a string"),
    ("clip hold unknown", lambda d: put(d, "cables.0.clips.0.hold", "tight"), "cables[0].clips[0].hold",
     "must be one of"),
    ("damping negative", lambda d: put(d, "cables.0.damping", -0.1), "cables[0].damping",
     "not be negative"),
    ("damping not a number", lambda d: put(d, "cables.0.damping", "low"), "cables[0].damping",
     "expected a number"),
    ("segments too many", lambda d: put(d, "cables.0.segments", 1000), "cables[0].segments",
     "would touch"),
    ("key t negative", lambda d: put(d, "motion.0.keys.0.t", -1.0), "motion[0].keys[0].t",
     "not be negative"),
    # shapes and sizes
    ("box two sizes", lambda d: put(d, "parts.0.size", [1, 2]), "parts[0].size",
     "shape 'box' takes 3 numbers"),
    ("sphere three sizes", lambda d: put(d, "parts.1.size", [1, 2, 3]), "parts[1].size",
     "takes 1 number (radius)"),
    ("plane size of one number", lambda d: put(d, "parts.2.size", [1]), "parts[2].size",
     "takes 2 or 3 numbers"),
    ("plane size negative", lambda d: put(d, "parts.2.size", [1, -1]), "parts[2].size[1]",
     "must not be negative"),
    ("plane grid spacing zero", lambda d: put(d, "parts.2.size", [1, 1, 0]), "parts[2].size[2]",
     "grid spacing must be positive"),
    ("mesh with size", lambda d: put(d, "parts.3.size", [1]), "parts[3].size",
     "not used by shape 'mesh'"),
    ("file on box", lambda d: put(d, "parts.0.file", "box.stl"), "parts[0].file",
     "only for shape 'mesh'"),
    ("scale on sphere", lambda d: put(d, "parts.1.scale", 2.0), "parts[1].scale",
     "only for shape 'mesh'"),
    ("unknown shape", lambda d: put(d, "parts.0.shape", "cone"), "parts[0].shape",
     "must be one of"),
    # enumerations
    ("units cm", lambda d: put(d, "scene.units", "cm"), "scene.units", "must be one of 'm', 'mm'"),
    ("method fast", lambda d: put(d, "check.method", "fast"), "check.method",
     "'points', 'exact'"),
    ("contact name", lambda d: put(d, "effects.contact", ["self", "cable-part"]),
     "effects.contact[1]", "got 'cable-part'"),
    # routes
    ("too short", lambda d: put(d, "cables.0.length", 1.0), "cables[0].length",
     "shorter than the route"),
    ("points too short", lambda d: put(d, "cables.1.length", 0.2), "cables[1].length",
     "0.2 m is shorter than the route (0.211803 m along points"),
    ("one point", lambda d: put(d, "cables.1.points", [[0, 0, 0]]), "cables[1].points",
     "at least 2 points"),
    ("via with points", lambda d: put(d, "cables.1.via", [[0, 0, 0]]), "cables[1].via",
     "not allowed with 'points'"),
    ("start pos with points", lambda d: put(d, "cables.1.start.pos", [0, 0, 0]),
     "cables[1].start.pos", "not allowed with 'points'"),
    ("repeated point", lambda d: put(d, "cables.1.points.2", [0.1, 0.1, 0.0]),
     "cables[1].points[2]", "zero-length route segment"),
    ("via on start", lambda d: put(d, "cables.0.via", [[0, 0, 0.6]]), "cables[0].via[0]",
     "zero-length route segment"),
    ("end on via", lambda d: put(d, "cables.0.via", [[1.0, 0.5, 0.6]]), "cables[0].end",
     "zero-length route segment"),
    # names
    ("part body", lambda d: put(d, "parts.0.body", "drawr"), "parts[0].body",
     "did you mean 'drawer'?"),
    ("start body", lambda d: put(d, "cables.0.start.body", "nowhere"), "cables[0].start.body",
     "no body named 'nowhere'"),
    ("end body", lambda d: put(d, "cables.0.end.body", "nowhere"), "cables[0].end.body",
     "no body named"),
    ("clip body", lambda d: put(d, "cables.0.clips.0.body", "uper"), "cables[0].clips[0].body",
     "did you mean 'upper'?"),
    ("motion body unknown", lambda d: put(d, "motion.0.body", "door"), "motion[0].body",
     "no [[bodies]] entry named 'door'"),
    ("motion body mjcf", lambda d: put(d, "motion.0.body", "forearm"), "motion[0].body",
     "cannot be keyframed by pose"),
    ("motion body world", lambda d: put(d, "motion.0.body", "world"), "motion[0].body",
     "cannot move"),
    ("motion joint unknown", lambda d: put(d, "motion.1.joint", "elbw"), "motion[1].joint",
     "did you mean 'elbow'?"),
    ("motion joint ball", lambda d: put(d, "motion.1.joint", "shoulder"), "motion[1].joint",
     "ball joint"),
    ("motion joint no mjcf", lambda d: drop(d, "scene.mjcf") and drop(d, "parts.1")
     and put(d, "cables.0.clips", []), "motion[1].joint", "no mjcf model"),
    ("motion both", lambda d: put(d, "motion.0.joint", "elbow"), "motion[0]", "exactly one"),
    ("motion neither", lambda d: drop(d, "motion.1.joint"), "motion[1]", "exactly one"),
    ("motion twice", lambda d: put(d, "motion.2.joint", "elbow"), "motion[2]",
     "already driven by motion[1]"),
    ("empty name", lambda d: put(d, "cables.0.name", " "), "cables[0].name", "empty"),
    ("empty level", lambda d: put(d, "parts.0.name", "cab//rail"), "parts[0].name",
     "empty assembly level"),
    ("leading slash", lambda d: put(d, "parts.0.name", "/rail"), "parts[0].name",
     "empty assembly level"),
    ("scene name path", lambda d: put(d, "scene.name", "a/b"), "scene.name", "file name"),
    ("body named world", lambda d: put(d, "bodies.0.name", "world"), "bodies[0].name",
     "fixed world frame"),
    ("body named as mjcf", lambda d: put(d, "bodies.0.name", "upper"), "bodies[0].name",
     "body of the mjcf model"),
    ("duplicate body", lambda d: d["bodies"].append({"name": "drawer"}) or d, "bodies[1].name",
     "duplicate body name 'drawer' (also bodies[0])"),
    ("duplicate part", lambda d: put(d, "parts.2.name", "ball"), "parts[2].name",
     "duplicate part name 'ball' (also parts[1])"),
    ("duplicate cable", lambda d: put(d, "cables.1.name", "power"), "cables[1].name",
     "duplicate cable name"),
    ("cable named as part", lambda d: put(d, "cables.1.name", "floor"), "cables[1].name",
     "also the name of parts[2]"),
    # keyframes
    ("keys empty", lambda d: put(d, "motion.0.keys", []), "motion[0].keys", "empty"),
    ("keys equal t", lambda d: put(d, "motion.1.keys.1.t", 0.0), "motion[1].keys[1].t",
     "increase strictly"),
    ("keys decreasing", lambda d: put(d, "motion.0.keys.0.t", 3.0), "motion[0].keys[1].t",
     "increase strictly"),
    # files
    ("mesh missing", lambda d: put(d, "parts.3.file", "nope.stl"), "parts[3].file",
     "file not found"),
    ("mesh garbage", lambda d: put(d, "parts.3.file", "garbage.stl"), "parts[3].file",
     "garbage.stl"),
    ("mesh unknown format", lambda d: put(d, "parts.3.file", "arm.xml"), "parts[3].file",
     "trimesh cannot load arm.xml"),
    ("keepout open mesh", lambda d: put(d, "parts.3.file", "open.stl"), "parts[3].file",
     "not a closed surface"),
    ("mjcf missing", lambda d: put(d, "scene.mjcf", "robot.xml"), "scene.mjcf", "file not found"),
    ("mjcf broken", lambda d: put(d, "scene.mjcf", "broken.xml"), "scene.mjcf",
     "size 0 must be positive"),
]


@pytest.mark.parametrize("mutate, key, fragment", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_input(folder, mutate, key, fragment):
    data = mutate(copy.deepcopy(BASE))
    with pytest.raises(SceneError) as exc:
        parse(data, folder)
    check_error(exc, folder / "scene.toml", key, fragment)


def test_open_mesh_allowed_when_not_keepout(folder):
    data = put(copy.deepcopy(BASE), "parts.3.file", "open.stl")
    put(data, "parts.3.keepout", False)
    assert parse(data, folder).parts[3].file.name == "open.stl"


def test_bad_input_from_file_names_file_and_key(folder):
    f = folder / "radius.toml"
    f.write_text(SPEC_EXAMPLE.replace("radius = 0.004", "radius = -4"))
    with pytest.raises(SceneError) as exc:
        load_scene(f)
    assert str(exc.value) == f"{f}: cables[0].radius: must be positive, got -4"


# -- never a traceback ---------------------------------------------------------

def _paths(value, prefix=""):
    """Every key path inside BASE, as 'a.b.0' strings."""
    items = (value.items() if isinstance(value, dict)
             else enumerate(value) if isinstance(value, list) else ())
    for k, v in items:
        path = f"{prefix}{k}"
        yield path
        yield from _paths(v, path + ".")


PATHS = sorted(_paths(BASE))
JUNK = st.recursive(
    st.none() | st.booleans() | st.integers(-10**30, 10**30)
    | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner,
                                                                max_size=3),
    max_leaves=8)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(edits=st.lists(st.tuples(st.sampled_from(PATHS), JUNK | st.just(KeyError)), max_size=3))
def test_any_edit_gives_a_scene_or_a_scene_error(folder, edits):
    data = copy.deepcopy(BASE)
    for path, value in edits:
        try:
            if value is KeyError:
                drop(data, path)
            else:
                put(data, path, value)
        except (KeyError, IndexError, TypeError):
            pass   # an earlier edit removed or replaced the container
    try:
        parse(data, folder)
    except SceneError as e:
        assert e.key and e.problem


# -- limits -------------------------------------------------------------------


@pytest.mark.parametrize("path, value, key, fragment", [
    ("scene.duration", 1e9, "scene.duration", "steps, above the limit of 10,000,000"),
    # a radius no unit makes sense of is refused before it could need a billion points (cablecheck.scene.units)
    ("cables.0.radius", 1e-9, "cables[0].radius", "is no cable radius"),
])
def test_absurd_sizes_are_refused_with_the_limit(folder, path, value, key, fragment):
    data = put(copy.deepcopy(BASE), "check.method", "points")
    with pytest.raises(SceneError) as exc:
        parse(put(data, path, value), folder)
    check_error(exc, folder / "scene.toml", key, fragment)
    assert ("[limits]" in exc.value.problem) == (key == "scene.duration")


def test_limits_can_be_raised(folder):
    data = put(copy.deepcopy(BASE), "scene.duration", 20_000.0)   # 2e7 steps at 1 ms
    with pytest.raises(SceneError, match="limit of 10,000,000"):
        parse(data, folder)
    assert parse(put(data, "limits", {"steps": 30_000_000}), folder).limits.steps == 30_000_000
    data = put(copy.deepcopy(BASE), "cables.0.segments", 30)
    with pytest.raises(SceneError) as exc:
        parse(put(data, "limits", {"elements": 20}), folder)
    check_error(exc, folder / "scene.toml", "cables[0].segments", "30 elements, above the limit of 20")
    with pytest.raises(SceneError) as exc:
        parse(put(copy.deepcopy(BASE), "limits", {"points": 0}), folder)
    check_error(exc, folder / "scene.toml", "limits.points", "at least 1")


# -- the format reference -------------------------------------------------------

REFERENCE = Path(__file__).resolve().parents[1] / "docs" / "scene-format.md"

# Heading of each table in docs/scene-format.md -> the keys the loader accepts there.
REFERENCE_TABLES = {
    "`[scene]`": scene_format.SCENE_KEYS,
    "`[effects]`": scene_format.EFFECTS_KEYS,
    "`[check]`": scene_format.CHECK_KEYS,
    "`[[bodies]]`": scene_format.BODY_KEYS,
    "`[[parts]]`": scene_format.PART_KEYS,
    "`[[cables]]`": scene_format.CABLE_KEYS,
    "`[[cables]]` `start`, `end` and `clips`": scene_format.ANCHOR_KEYS,
    "`[[motion]]`": scene_format.MOTION_KEYS,
    "`[[motion]]` keys of a body": scene_format.BODY_KEY_KEYS,
    "`[[motion]]` keys of a joint": scene_format.JOINT_KEY_KEYS,
    "`[limits]`": scene_format.LIMIT_KEYS,
    "`[[allow]]`": scene_format.ALLOW_KEYS,
}


def _documented_keys() -> dict[str, list[str]]:
    """Heading -> keys of the rows of its table (rows start with | `key` |)."""
    out: dict[str, list[str]] = {}
    heading = None
    for line in REFERENCE.read_text().splitlines():
        if line.startswith("### "):
            heading = line[4:].strip()
            out[heading] = []
        elif heading and line.startswith("| `"):
            out[heading].append(line.split("`")[1])
    return out


def test_scene_format_reference_lists_every_accepted_key():
    """docs/scene-format.md documents exactly the keys the loader accepts, table by table."""
    documented = _documented_keys()
    assert set(documented) == set(REFERENCE_TABLES)
    for heading, accepted in REFERENCE_TABLES.items():
        assert sorted(documented[heading]) == sorted(accepted), heading
    tops = {h.strip("`[]").split("`")[0].strip("[]") for h in documented}
    assert set(scene_format.TOP_KEYS) <= tops


# -- motion files, keyframes, interpolation ------------------------------------------

LIMITED_XML = ARM_XML.replace('<joint name="elbow" type="hinge" axis="0 1 0"/>',
                              '<joint name="elbow" type="hinge" axis="0 1 0" range="-180 180"/>'
                              ).replace('<joint name="lift" type="slide"/>',
                                        '<joint name="lift" type="slide" range="0 0.2"/>'
                                        ).replace("</worldbody>", """</worldbody>
  <keyframe>
    <key name="home" qpos="1 0 0 0 0.4 0.05"/>
    <key name="tilted" qpos="0.9 0.1 0 0 0.4 0.05"/>
  </keyframe>""")


def _with_file(folder: Path, text: str | None, **motion) -> dict:
    """BASE with motion[1] (elbow) replaced by a file motion; `text` written as f.csv."""
    (folder / "limited.xml").write_text(LIMITED_XML)
    if text is not None:
        (folder / "f.csv").write_text(text)
    data = put(copy.deepcopy(BASE), "scene.mjcf", "limited.xml")
    data["motion"][1] = {"file": "f.csv", **motion}
    return data


def test_motion_file_in_scene_units(folder):
    text = "t,elbow,lift,drawer.x,drawer.rz\n0,10,20,1000,90\n0.5,20,30,1200,-170\n"
    m = _with_file(folder, text, time_scale=2.0)
    drop(m, "motion.2")
    data = put(copy.deepcopy(m), "scene.units", "mm")
    put(data, "check.clearance", 2.0)
    drop(data, "motion.0")
    data["bodies"][0]["pos"] = [1000.0, 0.0, 0.0]
    data["parts"] = data["parts"][:3]
    data["cables"] = []
    s = parse(data, folder)
    (motion,) = s.motions
    tr = motion.trajectory
    assert motion.file == folder / "f.csv" and motion.time_scale == 2.0 and motion.keys == ()
    assert motion.interpolation == "cubic" and motion.angles == "deg"
    np.testing.assert_allclose(tr.times, [0.0, 0.25])
    assert tr.joints == ("elbow", "lift") and tr.bodies == ("drawer",)
    np.testing.assert_allclose(tr.joint_values, [[np.radians(10), 0.02], [np.radians(20), 0.03]])
    np.testing.assert_allclose(tr.body_pos[:, 0], [[1.0, 0.0, 0.0], [1.2, 0.0, 0.0]])
    # rz as written (90 -> -170: 260 degrees back, not 100 on); rx, ry from [[bodies]]
    np.testing.assert_array_equal(tr.body_euler[:, 0], [[0, 0, 90], [0, 0, -170]])
    np.testing.assert_allclose(s.start_frames["drawer"][1], euler_matrix([0, 0, 90]), atol=1e-15)


def test_keyframe_keys(folder):
    data = _with_file(folder, None)
    data["motion"][1] = {"joint": "elbow", "keys": [{"t": 0.0, "key": "home"},
                                                    {"t": 1.0, "value": 30.0}]}
    s = parse(data, folder)
    np.testing.assert_allclose(s.motions[1].trajectory.joint_values[:, 0], [0.4, np.radians(30)])
    assert s.motions[1].keys[0] == KeyframeKey(0.0, "home")
    data["motion"][1:] = [{"keys": [{"t": 0.0, "key": "home"}], "interpolation": "linear"}]
    tr = parse(data, folder).motions[1].trajectory
    assert tr.joints == ("elbow", "lift") and tr.interpolation == "linear"
    np.testing.assert_allclose(tr.joint_values, [[0.4, 0.05]])


MOTION_BAD = [
    # (id, csv text or None, motion keys, key, fragment)
    ("file missing", None, {"file": "nope.csv"}, "motion[1].file", "file not found"),
    ("empty file", "", {}, "motion[1].file", "f.csv: empty"),
    ("header without t", "time,elbow\n0,1\n", {}, "motion[1].file",
     "f.csv: line 1: the header's first column must be 't'"),
    ("header only t", "t\n0\n", {}, "motion[1].file", "names no joint or body column"),
    ("header only", "t,elbow\n", {}, "motion[1].file", "no samples"),
    ("duplicate column", "t,elbow,elbow\n0,1,1\n", {}, "motion[1].file", "'elbow' appears twice"),
    ("unknown column", "t,elbw\n0,1\n", {}, "motion[1].file",
     "f.csv column 'elbw': neither a joint of the mjcf model nor <body>.x/.y/.z/.rx/.ry/.rz of a "
     "[[bodies]] body (did you mean 'elbow'?)"),
    ("ball joint column", "t,shoulder\n0,1\n", {}, "motion[1].file",
     "f.csv column 'shoulder': 'shoulder' is a ball joint"),
    ("mjcf body column", "t,forearm.x\n0,1\n", {}, "motion[1].file",
     "f.csv column 'forearm.x': 'forearm' is a body of the mjcf model"),
    ("short row", "t,elbow\n0,1\n\n1\n", {}, "motion[1].file", "f.csv: line 4: 1 cell, the header has 2"),
    ("not a number", "t,elbow\n0,1\n1,abc\n", {}, "motion[1].file",
     "f.csv: line 3, column 'elbow': not a number: 'abc'"),
    ("nan", "t,elbow\n0,1\n1,nan\n", {}, "motion[1].file",
     "f.csv: line 3, column 'elbow': not a finite number"),
    ("t repeats", "t,elbow\n0,1\n0.5,2\n0.5,3\n", {}, "motion[1].file",
     "f.csv: line 4, column 't': times must increase strictly: 0.5 after 0.5 (line 3)"),
    ("t negative", "t,elbow\n-1,1\n0.5,2\n", {}, "motion[1].file", "must not be negative"),
    ("sample out of range", "t,elbow\n0,0\n1.5,181\n", {}, "motion[1].file",
     "f.csv line 3, t = 1.5 s: joint 'elbow' at 181 deg is outside its range -180..180 deg"),
    ("rad out of range", "t,elbow\n0,0\n2,3.2\n", {"angles": "rad"}, "motion[1].file",
     "f.csv line 3, t = 2 s: joint 'elbow' at 3.2 rad is outside its range -3.14159..3.14159 rad"),
    ("slide out of range", "t,lift\n0,0\n2,0.3\n", {}, "motion[1].file",
     "joint 'lift' at 0.3 m is outside its range 0..0.2 m"),
    ("file and keys", "t,elbow\n0,1\n", {"keys": [{"t": 0, "value": 1}]}, "motion[1].keys",
     "not allowed with 'file'"),
    ("file and joint", "t,elbow\n0,1\n", {"joint": "elbow"}, "motion[1]", "exactly one"),
    ("bad interpolation", "t,elbow\n0,1\n", {"interpolation": "spline"},
     "motion[1].interpolation", "must be one of 'cubic', 'linear'"),
    ("bad angles", "t,elbow\n0,1\n", {"angles": "grad"}, "motion[1].angles", "must be one of"),
    ("time_scale zero", "t,elbow\n0,1\n", {"time_scale": 0}, "motion[1].time_scale",
     "must be positive"),
    ("driven twice", "t,lift\n0,0.1\n", {}, "motion[2]", "joint 'lift' is already driven by motion[1]"),
]


@pytest.mark.parametrize("text, motion, key, fragment", [b[1:] for b in MOTION_BAD],
                         ids=[b[0] for b in MOTION_BAD])
def test_bad_motion_file(folder, text, motion, key, fragment):
    data = _with_file(folder, text, **motion)
    if "file" in motion:
        data["motion"][1]["file"] = motion["file"]
    with pytest.raises(SceneError) as exc:
        parse(data, folder)
    check_error(exc, folder / "scene.toml", key, fragment)


KEY_BAD = [
    ("key out of range", {"joint": "elbow", "keys": [{"t": 0, "value": 0}, {"t": 1.5, "value": 250}]},
     "motion[1].keys[1].value",
     "t = 1.5 s: joint 'elbow' at 250 deg is outside its range -180..180 deg"),
    ("unknown keyframe", {"joint": "elbow", "keys": [{"t": 0, "key": "hme"}]}, "motion[1].keys[0].key",
     "no keyframe named 'hme' in the mjcf model (known: home, tilted)"),
    ("value and key", {"joint": "elbow", "keys": [{"t": 0, "key": "home", "value": 1}]},
     "motion[1].keys[0]", "not both"),
    ("keyframe moves a ball joint", {"keys": [{"t": 0, "key": "tilted"}]}, "motion[1].keys[0].key",
     "keyframe 'tilted' moves joint shoulder; only named hinge and slide joints are driven"),
    ("keyframes and values", {"keys": [{"t": 0, "key": "home"}, {"t": 1, "value": 2}]}, "motion[1]",
     "exactly one"),
    ("keyframes drive lift twice", {"keys": [{"t": 0, "key": "home"}]}, "motion[2]",
     "joint 'lift' is already driven by motion[1]"),
    ("angles on a body", {"body": "drawer", "angles": "rad", "keys": [{"t": 0}]}, "motion[1].angles",
     "not used by a body's motion"),
]


@pytest.mark.parametrize("motion, key, fragment", [b[1:] for b in KEY_BAD], ids=[b[0] for b in KEY_BAD])
def test_bad_motion_keys(folder, motion, key, fragment):
    data = _with_file(folder, None)
    data["motion"][1] = motion
    if motion.get("body") == "drawer":
        drop(data, "motion.0")
        data["motion"].insert(0, {"joint": "elbow", "keys": [{"t": 0, "value": 0}]})
    with pytest.raises(SceneError) as exc:
        parse(data, folder)
    check_error(exc, folder / "scene.toml", key, fragment)


def test_keyframes_need_an_mjcf_model(folder):
    data = drop(drop(copy.deepcopy(BASE), "scene.mjcf"), "parts.1")
    put(data, "cables.0.clips", [])
    data["motion"][1:] = [{"keys": [{"t": 0.0, "key": "home"}]}]
    with pytest.raises(SceneError) as exc:
        parse(data, folder)
    check_error(exc, folder / "scene.toml", "motion[1].keys[0].key", "no mjcf model")


def test_plane_takes_an_optional_drawing_size_in_scene_units(folder):
    data = to_mm(BASE)
    put(data, "parts.2.size", [500, 200])
    assert parse(data, folder).parts[2].size == (0.5, 0.2)
    put(data, "parts.2.size", [500, 0, 20])
    assert parse(data, folder).parts[2].size == (0.5, 0.0, 0.02)
    drop(data, "parts.2.size")
    assert parse(data, folder).parts[2].size == ()


def test_twist_stiffness_is_a_positive_modulus(folder):
    data = copy.deepcopy(BASE)
    put(data, "cables.0.twist_stiffness", 2.5e7)
    assert parse(data, folder).cables[0].twist_stiffness == 2.5e7
    assert parse(copy.deepcopy(BASE), folder).cables[0].twist_stiffness is None
    put(data, "cables.0.twist_stiffness", 0)
    with pytest.raises(SceneError) as e:
        parse(data, folder)
    check_error(e, folder / "scene.toml", "cables[0].twist_stiffness", "must be positive")


# -- [[allow]] and attach_links --------------------------------------------


def _with_allow(*rules) -> dict:
    data = copy.deepcopy(BASE)
    data["allow"] = [dict(r) for r in rules]
    return data


def test_allow_pairs_parts_assemblies_cables_and_mjcf_bodies(folder):
    scene = parse(_with_allow({"a": "cab", "b": "power", "reason": "the harness rests on the cabinet"},
                              {"a": "forearm", "b": "ball", "reason": "the ball rides the forearm"},
                              {"a": "signal", "b": "signal", "reason": "coiled on purpose"}), folder)
    assert [(r.a, r.b, r.reason) for r in scene.allow] == [
        ("cab", "power", "the harness rests on the cabinet"), ("forearm", "ball", "the ball rides the forearm"),
        ("signal", "signal", "coiled on purpose")]
    assert parse(copy.deepcopy(BASE), folder).allow == ()


@pytest.mark.parametrize("rule, key, fragment", [
    ({"a": "cab/rial", "b": "power", "reason": "x"}, "allow[0].a", "did you mean 'cab/rail'?"),
    ({"a": "cab", "b": "powr", "reason": "x"}, "allow[0].b", "did you mean 'power'?"),
    ({"a": "cab/rail", "b": "power"}, "allow[0].reason", "missing (required)"),
    ({"a": "cab/rail", "b": "power", "reason": " "}, "allow[0].reason", "must not be empty"),
    ({"a": "cab/rail", "b": "power", "reason": "x", "why": "y"}, "allow[0].why", "unknown key"),
    ({"a": "ca", "b": "power", "reason": "x"}, "allow[0].a", "no part, assembly path or cable named 'ca'"),
], ids=["part", "cable", "no reason", "empty reason", "unknown key", "partial level"])
def test_allow_errors_name_the_key(folder, rule, key, fragment):
    with pytest.raises(SceneError) as exc:
        parse(_with_allow(rule), folder)
    check_error(exc, folder / "scene.toml", key, fragment)


def test_allow_names_checked_against_built_parts(folder):
    """A name the loader took for the mjcf model's geoms must still cover a built part; one the builder
    would not give is refused at load already (the loader names the geoms as the builder does)."""
    from cablecheck.scene.allow import check_allow_names
    scene = parse(_with_allow({"a": "upper/capsule0", "b": "power", "reason": "x"}), folder)
    with pytest.raises(SceneError) as exc:
        check_allow_names(scene, ["upper/capsule1", "forearm", "cab/rail", "power"])
    check_error(exc, folder / "scene.toml", "allow[0].a", "did you mean 'upper/capsule1'?")
    check_allow_names(scene, ["upper/capsule0", "power"])
    with pytest.raises(SceneError) as exc:
        parse(_with_allow({"a": "upper/wrist", "b": "power", "reason": "x"}), folder)
    check_error(exc, folder / "scene.toml", "allow[0].a", "did you mean 'upper'?")


def test_attach_links(folder):
    assert parse(copy.deepcopy(BASE), folder).check.attach_links == 0
    assert parse(put(copy.deepcopy(BASE), "check.attach_links", 2), folder).check.attach_links == 2
    for bad, fragment in ((-1, "at least 0"), (1.5, "expected an integer")):
        with pytest.raises(SceneError) as exc:
            parse(put(copy.deepcopy(BASE), "check.attach_links", bad), folder)
        check_error(exc, folder / "scene.toml", "check.attach_links", fragment)


def test_holds_and_damping_are_read(tmp_path):
    """`hold` on ends and clips, `damping` per cable (SPEC, additions)."""
    data = {"scene": {"name": "h", "units": "mm", "duration": 0},
            "cables": [{"name": "c", "radius": 4, "start": {"pos": [0, 0, 0], "hold": "pin"},
                        "end": {"pos": [500, 0, 0], "hold": "free"},
                        "clips": [{"pos": [250, 0, 0], "hold": "clamp"}], "damping": 0.1}]}
    cable = parse_scene(data, tmp_path / "h.toml").cables[0]
    assert (cable.start.hold, cable.end.hold, cable.clips[0].hold) == (Hold.PIN, Hold.FREE, Hold.CLAMP)
    assert cable.damping == 0.1


def test_many_short_elements_allowed_without_self_contact(tmp_path):
    """Elements shorter than the radius: MuJoCo's flex takes them; only with
    self-contact pushing back must elements exceed 2.25 radii."""
    data = {"scene": {"name": "s", "units": "m", "duration": 0},
            "cables": [{"name": "c", "radius": 0.004, "start": {"pos": [0, 0, 0]}, "end": {"pos": [0.2, 0, 0]},
                        "segments": 100}]}
    assert parse_scene(data, tmp_path / "s.toml").cables[0].segments == 100
    data["effects"] = {"contact": ["self"]}
    with pytest.raises(SceneError) as e:
        parse_scene(data, tmp_path / "s.toml")
    assert e.value.key == "cables[0].segments" and "use at most 22" in e.value.problem  # 0.2 m / 22 = 9.09 mm > 9 mm
