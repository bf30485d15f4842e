"""Scripted motion: what Motion hands to MuJoCo, joint values in events.
Interpolation (cablecheck.run.curves) is tested in test_curves."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import mujoco
import numpy as np
import pytest

from cablecheck.build.stages import build
from cablecheck.cli.main import main
from cablecheck.run.motion import Motion, body_rate
from cablecheck.scene.frames import euler_matrix
from cablecheck.scene.load import load_scene

ROOT = Path(__file__).resolve().parents[1]
ARM_XML = ROOT / "scenes" / "arm.xml"



def test_body_rates_integrate_the_euler_path():
    """The body-frame rate handed to a free joint carries its orientation along the angles."""
    rng = np.random.default_rng(1)
    e0, rate = rng.uniform(-2, 2, 3), rng.uniform(-1, 1, 3)
    dt = 1e-6
    omega = body_rate(e0, rate)
    r0, r1 = euler_matrix(np.degrees(e0)), euler_matrix(np.degrees(e0 + rate * dt))
    skew = r0.T @ (r1 - r0) / dt
    assert np.allclose([skew[2, 1], skew[0, 2], skew[1, 0]], omega, atol=1e-5)


# -- Motion on a built scene ---------------------------------------------------------

SCENE = """
[scene]
name = "arm-motion"
units = "m"
duration = {duration}
mjcf = "{xml}"
{extra}
"""


def _scene(tmp_path: Path, motion: str, duration: float = 2.0, xml: Path = ARM_XML,
           files: dict | None = None, extra: str = ""):
    for name, text in (files or {}).items():
        (tmp_path / name).write_text(textwrap.dedent(text).lstrip())
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(duration=duration, xml=xml, extra=extra) + textwrap.dedent(motion))
    return load_scene(path)


def _driven(scene, t: float, joint: str) -> tuple[float, float]:
    """(qpos, qvel) Motion puts on `joint` at time t."""
    built = build(scene, detect=False)
    data = mujoco.MjData(built.model)
    Motion(built).apply(data, t)
    drive = built.joints[joint]
    return float(data.qpos[drive.qpos_adr]), float(data.qvel[drive.dof_adr])


CSV = """\
t,elbow,shoulder_pitch
0.0,0,0
0.5,-20,10
1.0,-60,15
1.5,-30,0
"""


def test_csv_degrees_and_radians_agree_and_velocity_is_the_derivative(tmp_path):
    rad = "t,elbow,shoulder_pitch\n" + "\n".join(
        ",".join([r.split(",")[0]] + [str(float(np.radians(float(v)))) for v in r.split(",")[1:]])
        for r in CSV.splitlines()[1:])
    deg_scene = _scene(tmp_path, '[[motion]]\nfile = "deg.csv"\n', files={"deg.csv": CSV})
    rad_scene = _scene(tmp_path, '[[motion]]\nfile = "rad.csv"\nangles = "rad"\n',
                       files={"rad.csv": rad})
    for t in (0.25, 0.5, 0.8, 1.2):
        assert np.allclose(_driven(deg_scene, t, "elbow"), _driven(rad_scene, t, "elbow"))
    assert _driven(deg_scene, 1.0, "elbow")[0] == pytest.approx(np.radians(-60.0))
    # the velocity MuJoCo gets is the derivative of the position, also across a sample
    built = build(deg_scene, detect=False)
    motion, data = Motion(built), mujoco.MjData(built.model)
    adr = built.joints["elbow"].qpos_adr
    h = 1e-6
    for t in (0.5 - 1e-4, 0.5, 0.5 + 1e-4, 1.0):
        q = []
        for s in (t - h, t + h):
            motion.apply(data, s)
            q.append(data.qpos[adr])
        motion.apply(data, t)
        assert data.qvel[built.joints["elbow"].dof_adr] == pytest.approx(
            (q[1] - q[0]) / (2 * h), rel=1e-5, abs=1e-6)


def test_linear_csv_and_time_scale(tmp_path):
    lin = _scene(tmp_path, '[[motion]]\nfile = "a.csv"\ninterpolation = "linear"\n',
                 files={"a.csv": CSV})
    q, v = _driven(lin, 0.75, "elbow")
    assert q == pytest.approx(np.radians(-40.0)) and v == pytest.approx(np.radians(-80.0))
    fast = _scene(tmp_path, '[[motion]]\nfile = "a.csv"\ninterpolation = "linear"\ntime_scale = 2.0\n',
                  files={"a.csv": CSV})
    q2, v2 = _driven(fast, 0.375, "elbow")
    assert q2 == pytest.approx(q) and v2 == pytest.approx(2 * v)
    keys = _scene(tmp_path, """
        [[motion]]
        joint = "elbow"
        time_scale = 0.5
        interpolation = "linear"
        keys = [ { t = 0.0, value = 0.0 }, { t = 1.0, value = -60.0 } ]
        """)
    assert _driven(keys, 1.0, "elbow")[0] == pytest.approx(np.radians(-30.0))


def test_body_columns_follow_the_file(tmp_path):
    csv = "t,slider.x,slider.rz\n0,0,0\n1,0.2,90\n"
    scene = _scene(tmp_path, """
        [[bodies]]
        name = "slider"
        pos = [1.0, 0.0, 0.5]

        [[motion]]
        file = "b.csv"
        interpolation = "linear"
        """, files={"b.csv": csv})
    built = build(scene, detect=False)
    data = mujoco.MjData(built.model)
    Motion(built).apply(data, 0.5)
    qa, da = built.free["slider"]
    assert np.allclose(data.qpos[qa:qa + 3] + built.origin, [0.1, 0.0, 0.5])  # y, z from [[bodies]]
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, euler_matrix([0, 0, 45]).ravel())
    assert np.allclose(data.qpos[qa + 3:qa + 7], quat) or np.allclose(data.qpos[qa + 3:qa + 7], -quat)
    assert np.allclose(data.qvel[da:da + 6], [0.2, 0, 0, 0, 0, np.radians(90.0)])


LIMITED = ARM_XML.read_text().replace(
    '<joint name="elbow" type="hinge" axis="0 1 0"/>',
    '<joint name="elbow" type="hinge" axis="0 1 0" range="-180 180"/>').replace(
    '<joint name="base_yaw" type="hinge" axis="0 0 1"/>',
    '<joint name="base_yaw" type="hinge" axis="0 0 1" ref="30"/>').replace(
    "</worldbody>",
    '</worldbody>\n  <keyframe><key name="home" qpos="0.5 -0.3 1.2"/></keyframe>')


def test_model_keyframe_as_a_pose_and_unkeyed_joints_hold_qpos0(tmp_path):
    xml = tmp_path / "limited.xml"
    xml.write_text(LIMITED)
    scene = _scene(tmp_path, """
        [[motion]]
        keys = [ { t = 0.0, key = "home" } ]
        """, xml=xml)
    for joint, value in (("base_yaw", 0.5), ("shoulder_pitch", -0.3), ("elbow", 1.2)):
        assert _driven(scene, 0.3, joint) == pytest.approx((value, 0.0))
    # a joint's own keys may start from the keyframe; base_yaw keeps its ref (qpos0)
    scene = _scene(tmp_path, """
        [[motion]]
        joint = "elbow"
        keys = [ { t = 0.0, key = "home" }, { t = 1.0, value = 10.0 } ]
        """, xml=xml)
    assert _driven(scene, 0.0, "elbow")[0] == pytest.approx(1.2)
    assert _driven(scene, 1.0, "elbow")[0] == pytest.approx(np.radians(10.0))
    assert _driven(scene, 0.5, "base_yaw") == pytest.approx((np.radians(30.0), 0.0))
    assert scene.start_frames["forearm"][0] == pytest.approx(
        _forearm_at(xml, {"elbow": 1.2}), abs=1e-12)


def _forearm_at(xml: Path, qpos: dict) -> np.ndarray:
    m = mujoco.MjModel.from_xml_path(str(xml))
    d = mujoco.MjData(m)
    for name, value in qpos.items():
        d.qpos[m.jnt_qposadr[m.joint(name).id]] = value
    mujoco.mj_kinematics(m, d)
    return d.xpos[m.body("forearm").id]


def test_out_of_range_key_and_sample_are_refused(tmp_path):
    xml = tmp_path / "limited.xml"
    xml.write_text(LIMITED)
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(duration=1.0, xml=xml, extra="") + textwrap.dedent("""
        [[motion]]
        joint = "elbow"
        keys = [ { t = 0.0, value = 0.0 }, { t = 1.5, value = 250.0 } ]
        """))
    assert main(["run", str(path), "--no-record", "--quiet"]) == 2
    (tmp_path / "pick.csv").write_text("t,elbow\n0,0\n0.5,90\n1.25,-181\n")
    path.write_text(SCENE.format(duration=1.0, xml=xml, extra="") + '[[motion]]\nfile = "pick.csv"\n')
    with pytest.raises(Exception) as exc:
        load_scene(path)
    message = str(exc.value)
    for fragment in ("motion[0].file", "pick.csv line 4", "t = 1.25 s", "'elbow'", "-181 deg",
                     "-180..180 deg"):
        assert fragment in message, message


# -- joint values in events ------------------------------------------------------------

def test_events_carry_joint_values_link_and_ranges(tmp_path, capsys):
    """A sphere on the upper arm through the hose: one hard event against that link."""
    text = (ROOT / "scenes" / "arm.toml").read_text()
    text = text.replace('mjcf = "arm.xml"', f'mjcf = "{ARM_XML}"').replace(
        "duration = 3.0", "duration = 0.6").replace("settle = 0.5", "settle = 0.05")
    text = text.replace("[[cables]]", """[[parts]]
name = "bump"
body = "upper_arm"
shape = "sphere"
size = [0.025]
pos = [0.027, 0.12, 0.051]
keepout = true

[[cables]]""")
    text = text.replace("{ t = 1.5, value = -40.0 }, { t = 3.0, value = 0.0 }",
                        "{ t = 0.6, value = -40.0 }")
    path = tmp_path / "bump.toml"
    path.write_text(text)
    report_path = tmp_path / "r.json"
    assert main(["run", str(path), "--no-record", "--report", str(report_path)]) == 1
    report = json.loads(report_path.read_text())
    bump = [e for e in report["events"] if e["b"] == "bump"]
    # The hose starts in the bump; swinging with only its material damping
    # (docs/physics.md) it may leave and come back, each stay an event of its own.
    assert bump and all(e["severity"] == "hard" for e in bump)
    motion = Motion(build(load_scene(path), detect=False))
    printed = capsys.readouterr().out
    for e in bump:
        assert set(e["joints"]) == {"base_yaw", "shoulder_pitch", "elbow"}
        for name, value in e["joints"].items():
            assert value == pytest.approx(np.degrees(motion.joint_values([e["t_worst"]], [name])[0, 0]))
        assert e["link"] == "upper_arm"
        assert list(e["joint_ranges"]) == ["shoulder_pitch", "base_yaw"]   # nearest joint first
        fine = np.degrees(motion.joint_values(np.linspace(e["t_start"], e["t_end"], 2001),
                                              ["shoulder_pitch", "base_yaw"]))
        assert np.allclose(list(e["joint_ranges"].values()),
                           np.stack([fine.min(axis=0), fine.max(axis=0)], axis=1), atol=1e-9)
        lo, hi = e["joint_ranges"]["shoulder_pitch"]
        assert f"link upper_arm; joints over the event: shoulder_pitch {lo:.4g}..{hi:.4g} deg, base_yaw" \
            in printed
    assert report["joint_units"] == {"base_yaw": "deg", "shoulder_pitch": "deg", "elbow": "deg"}


def test_no_joint_fields_without_moving_joints(tmp_path):
    report_path = tmp_path / "r.json"
    main(["run", str(ROOT / "scenes" / "bracket_static.toml"), "--no-record", "--quiet",
          "--report", str(report_path)])
    report = json.loads(report_path.read_text())
    assert report["events"] and "joints" not in report["events"][0]
    assert "joint_units" not in report
