"""A zoo of arms as they come: a dress-pack scene on each, timed side by side in one run.

Issue 29 item 2. Each arm is a public MuJoCo model shipped with its meshes
in a PyPI package (robosuite's ``models/assets/robots/<arm>/robot.xml``,
gymnasium-robotics' Fetch and kitchen Franka: include fragments, wrapped
as they are), used as it comes: its visual meshes drawn and
never checked, its collision meshes or primitives as the parts. On each
the benchmark writes a scene (units m) in a temporary folder:

- a hose (radius 7 mm) clamped on the back of the base, clipped to the
  upper arm and the forearm (a few cm out from each link's collision
  geometry, on the side facing up at the start pose) and clamped to the
  wrist, 12 % longer than its route;
- a table (box) under the base, a post (cylinder) behind and beside the
  arm, a tool (box) on the last link (``[[allow]]``: the base on the
  table, the tool on its flange);
- a pick-and-place from a CSV trajectory (t, then each joint in degrees,
  cubic): base yaw, shoulder, elbow, wrist and wrist roll move (the
  descents' signs chosen from the model's kinematics, every value clipped
  within the joint's range), 4.4 s; one arm (``--hz-arm``) is also driven
  from the same program sampled at 100 Hz.

Each scene runs as a user runs it (``cablecheck run SCENE --report R
--record X --quiet``, a subprocess: a crash of one arm leaves the others
running) and the report gives the columns: elements (cable elements +
checked parts), simulation, check, validation, recording (CPU seconds of
the stages, the report's ``timing``), (c+v+r)/sim, the real-time factor
(simulated seconds over the run's wall ``total_s``, building included;
and over the whole command's wall, as a user waits for it: Python's
start, the imports and reading the scene included),
agreement with MuJoCo's contacts, hard / soft events, and the events that
lie within two attachment zones of an end or clip (arc length along the
cable from the held point, from the built model's attachments): possible
false alarms, listed under the table with their pair, distance and time,
and what MuJoCo's contacts say of each at its worst step (the report's
validation: a contact event whose pair the validation found agreeing
there is no false alarm of the checker's; a bend or taut event is no
contact, and has no second opinion).

Needs robosuite and gymnasium-robotics installed without their
dependencies (``pip install --no-deps robosuite gymnasium-robotics``:
only their model files are read, nothing of them is imported; their
dependencies bring MuJoCo 3, whose ``mujoco`` module replaces the one of
``mujoco-core`` 4 that cablecheck needs). Arms whose package is
missing are named and skipped; with none installed the benchmark says so
and exits 2.

``--doc docs/performance.md`` writes the table with the date, the machine,
``uptime``'s load before and after and the command between the markers
``<!-- bench_robots -->`` and ``<!-- /bench_robots -->``.

Run: python benchmarks/bench_robots.py [--arms panda,ur5e,...] [--hz-arm panda]
       [--duration S] [--timeout S] [--keep DIR] [--doc docs/performance.md]
     python benchmarks/bench_robots.py --from DIR/rows.json [--doc docs/performance.md]
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import importlib.util
import json
import math
import os
import platform
import re
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(Path(__file__).resolve().parent))

BEGIN, END = "<!-- bench_robots -->", "<!-- /bench_robots -->"
HOSE_RADIUS = 0.007
STANDOFF = 0.03
"""Clip and clamp points this far (m) beyond the link's collision geometry (the hose's axis)."""
SLACK = 1.12
"""Hose length over its route's."""
HZ = 100.0


@dataclasses.dataclass(frozen=True)
class Arm:
    """One arm of the zoo: where its model ships and how it is dressed.

    joints: base yaw, shoulder, elbow, wrist flex, wrist roll (the program's five channels).
    home: the start pose, degrees, one per joint of ``joints``.
    base, clips, wrist: the bodies the hose's start, clips and end ride on.
    tool: the last link (the tool box is on it, ``tool_pos`` in its frame).
    """

    package: str
    model: str
    joints: tuple[str, ...]
    home: tuple[float, ...]
    base: str
    clips: tuple[str, ...]
    wrist: str
    tool: str
    tool_pos: tuple[float, float, float] = (0.0, 0.0, 0.06)
    stand: str | None = None
    """The body the table goes under (default ``base``: a mobile robot's hose starts on its torso)."""
    fragment: dict | None = None
    """A model that is an include fragment (gymnasium-robotics' Fetch): the
    wrapper's compiler options and the files to include (relative to the
    package): ``assets`` at the top, ``body`` inside the worldbody."""


RS = "models/assets/robots"
ZOO: dict[str, Arm] = {
    "panda": Arm("robosuite", f"{RS}/panda/robot.xml",
                 ("joint1", "joint2", "joint4", "joint6", "joint7"), (0, 11.25, -150, 168.5, 45),
                 "link0", ("link3", "link5"), "link6", "right_hand"),
    "ur5e": Arm("robosuite", f"{RS}/ur5e/robot.xml",
                ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_3_joint"),
                (-26.9, -99.4, 142.1, -130.3, -114.1),
                "fixed_base_link", ("upper_arm_link", "forearm_link"), "wrist_1_link", "right_hand"),
    "iiwa": Arm("robosuite", f"{RS}/iiwa/robot.xml",
                ("joint_1", "joint_2", "joint_4", "joint_6", "joint_7"), (0, 37.2, -108.3, 34.4, 0),
                "fixed_base_link", ("link_3", "link_5"), "link_6", "right_hand"),
    "kinova3": Arm("robosuite", f"{RS}/kinova3/robot.xml",
                   ("Actuator1", "Actuator2", "Actuator4", "Actuator6", "Actuator7"), (0, 37.2, 108.3, 34.4, -90),
                   "fixed_base_link", ("HalfArm2_Link", "forearm_link"), "SphericalWrist2_Link", "right_hand"),
    "sawyer": Arm("robosuite", f"{RS}/sawyer/robot.xml",
                  ("right_j0", "right_j1", "right_j3", "right_j5", "right_j6"), (0, -67.6, 124.9, 32.7, -90),
                  "right_arm_base_link", ("right_l2", "right_l4"), "right_l5", "right_hand"),
    "xarm7": Arm("robosuite", f"{RS}/xarm7/robot.xml",
                 ("joint1", "joint2", "joint4", "joint6", "joint7"), (0, 0, 70.2, 70.2, 0),
                 "base", ("link3", "link5"), "link6", "right_hand"),
    "jaco": Arm("robosuite", f"{RS}/jaco/robot.xml",
                ("j2s7s300_joint_1", "j2s7s300_joint_2", "j2s7s300_joint_4", "j2s7s300_joint_6",
                 "j2s7s300_joint_7"), (182.9, 210.8, 67, 215.4, 180),
                "j2s7s300_link_0", ("j2s7s300_link_2", "j2s7s300_link_4"), "j2s7s300_link_5", "right_hand"),
    "tiago": Arm("robosuite", f"{RS}/tiago/robot.xml",
                 ("arm_right_1_joint", "arm_right_2_joint", "arm_right_4_joint", "arm_right_6_joint",
                  "arm_right_5_joint"), (20, 20, 60, 0, 0),
                 "torso_lift_link", ("arm_right_2_link", "arm_right_4_link"), "arm_right_5_link", "right_hand",
                 stand="base_link"),
    "baxter": Arm("robosuite", f"{RS}/baxter/robot.xml",
                  ("right_s0", "right_s1", "right_e1", "right_w1", "right_w2"), (0, -28.6, 68.75, 45.8, 0),
                  "torso", ("right_upper_elbow", "right_upper_forearm"), "right_lower_forearm", "right_hand"),
    "spot_arm": Arm("robosuite", f"{RS}/spot_arm/robot.xml",
                    ("arm_sh0", "arm_sh1", "arm_el0", "arm_wr0", "arm_wr1"), (0, -68.75, 91.67, -22.9, 0),
                    "arm_link_sh0", ("arm_link_hr0", "arm_link_el1"), "arm_link_wr0", "right_hand", (0.12, 0.0, 0.0)),
    "fetch": Arm("gymnasium_robotics", "envs/assets/fetch/robot.xml",
                 ("robot0:shoulder_pan_joint", "robot0:shoulder_lift_joint", "robot0:elbow_flex_joint",
                  "robot0:wrist_flex_joint", "robot0:wrist_roll_joint"), (0, -40, 80, 50, 0),
                 "robot0:torso_lift_link", ("robot0:upperarm_roll_link", "robot0:forearm_roll_link"),
                 "robot0:wrist_flex_link", "robot0:gripper_link", (0.12, 0.0, 0.0), stand="robot0:base_link",
                 fragment={"compiler": {"angle": "radian", "coordinate": "local", "meshdir": "envs/assets/stls/fetch",
                                        "texturedir": "envs/assets/textures"},
                           "assets": "envs/assets/fetch/shared.xml", "body": "envs/assets/fetch/robot.xml"}),
    "kitchen_franka": Arm("gymnasium_robotics", "envs/assets/kitchen_franka/franka_assets/chain.xml",
                          ("robot:panda0_joint1", "robot:panda0_joint2", "robot:panda0_joint4", "robot:panda0_joint6",
                           "robot:panda0_joint7"), (0, -20, -120, 100, 45),
                          "panda0_link0", ("panda0_link3", "panda0_link5"), "panda0_link6", "panda0_link7",
                          fragment={"compiler": {"angle": "radian",
                                                 "meshdir": "envs/assets/kitchen_franka/franka_assets/meshes"},
                                    "assets": "envs/assets/kitchen_franka/franka_assets/assets.xml",
                                    "body": "envs/assets/kitchen_franka/franka_assets/chain.xml"}),
}
PACKAGES = {"robosuite": "robosuite", "gymnasium_robotics": "gymnasium-robotics"}

PROGRAM = [  # t (s), then the change from home (degrees) of yaw, shoulder, elbow, wrist flex, wrist roll;
    (0.0, (0, 0, 0, 0, 0)),          # the shoulder, elbow and wrist columns lower the tool (signs from the
    (0.7, (-35, -8, -8, -6, 0)),     # model at home), negative: raised; the tool works at home's height
    (1.2, (-35, 0, 0, 0, 60)),       # down on the pick, rolling the wrist
    (1.6, (-35, 0, 0, 0, 60)),       # grip
    (2.1, (-35, -8, -8, -6, 60)),    # lift
    (3.0, (35, -8, -8, -6, -60)),    # across, rolling back
    (3.5, (35, 0, 0, 0, -60)),       # down on the place
    (3.9, (35, 0, 0, 0, -60)),       # release
    (4.4, (0, 0, 0, 0, 0)),          # home
]


# --------------------------------------------------------------------------- pure helpers

def write_trajectory(path: Path, joints: list[str], rows: list[tuple[float, list[float]]]) -> Path:
    """A trajectory CSV the scene's ``[[motion]] file`` reads: header ``t,<joint>,...``,
    one row per sample (seconds, then degrees)."""
    lines = [",".join(["t", *joints])]
    for t, values in rows:
        if len(values) != len(joints):
            raise ValueError(f"row at t = {t} has {len(values)} values for {len(joints)} joints")
        lines.append(",".join([f"{t:.6g}", *(f"{v:.6f}" for v in values)]))
    path.write_text("\n".join(lines) + "\n")
    return path


def sample(keys: list[tuple[float, list[float]]], rate: float) -> list[tuple[float, list[float]]]:
    """The keyframes sampled at ``rate`` Hz, each span eased with a smoothstep
    (zero velocity at every key, as a controller's point-to-point moves), the
    last key included."""
    times = np.array([k[0] for k in keys], float)
    values = np.array([k[1] for k in keys], float)
    if len(times) < 2 or np.any(np.diff(times) <= 0):
        raise ValueError("keys need at least two strictly increasing times")
    n = int(round((times[-1] - times[0]) * rate))
    out = []
    for i in range(n + 1):
        t = min(times[0] + i / rate, times[-1])
        k = min(int(np.searchsorted(times, t, side="right")) - 1, len(times) - 2)
        u = (t - times[k]) / (times[k + 1] - times[k])
        w = u * u * (3 - 2 * u)
        out.append((round(float(t), 9), list(values[k] + w * (values[k + 1] - values[k]))))
    return out


def near_held(s: float, held: list[tuple[str, float]], zone: float) -> tuple[str, float] | None:
    """The end or clip (window name, arc length) nearest arc length ``s`` when
    it is within ``zone`` of it, else None."""
    best = min(held, key=lambda w: abs(w[1] - s), default=None)
    return best if best is not None and abs(best[1] - s) <= zone else None


def ratio(t: dict) -> float:
    """(check + validation + recording) / simulation of a report's ``timing``."""
    return (t["check_s"] + t["validate_s"] + t["record_s"]) / max(t["sim_s"], 1e-12)


# --------------------------------------------------------------------------- models

def package_root(package: str) -> Path | None:
    """The installed package's folder (found, not imported), or None."""
    spec = importlib.util.find_spec(package)
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(list(spec.submodule_search_locations)[0])


def standalone(arm: Arm, root: Path, folder: Path) -> Path:
    """The arm's model file as MuJoCo loads it on its own: the package's own
    file, or for a fragment a wrapper in ``folder`` that includes it (absolute
    paths: the meshes stay where the package put them)."""
    if arm.fragment is None:
        return root / arm.model
    f = arm.fragment
    comp = " ".join(f'{k}="{(root / v) if k.endswith("dir") else v}"' for k, v in f["compiler"].items())
    # the compiler after the assets: an included file's own relative meshdir (the kitchen Franka's) is overridden
    xml = (f'<mujoco model="{Path(arm.model).parent.name}">\n'
           f'  <include file="{root / f["assets"]}"/>\n  <compiler {comp}/>\n'
           f'  <worldbody>\n    <include file="{root / f["body"]}"/>\n  </worldbody>\n</mujoco>\n')
    path = folder / f"{Path(arm.model).parent.name}_standalone.xml"
    path.write_text(xml)
    return path


def _points(m, body: int, only: int | None = None) -> np.ndarray:
    """The body's collision geometry (or geom ``only``'s) as points in the
    body's frame (mesh vertices, a primitive's bounding box corners)."""
    import mujoco
    pts = []
    for g in range(m.ngeom):
        if m.geom_bodyid[g] != body or not (m.geom_contype[g] or m.geom_conaffinity[g]):
            continue
        if only is not None and g != only:
            continue
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, m.geom_quat[g])
        rot = rot.reshape(3, 3)
        if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            k = m.geom_dataid[g]
            local = m.mesh_vert[m.mesh_vertadr[k]:m.mesh_vertadr[k] + m.mesh_vertnum[k]]
        else:
            c, h = m.geom_aabb[g, :3], m.geom_aabb[g, 3:]
            local = c + h * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        pts.append(local @ rot.T + m.geom_pos[g])
    if not pts:
        raise ValueError(f"body {m.body(body).name} has no collision geometry")
    return np.concatenate(pts)


def outside(m, d, body_name: str, world_dir, across: bool = True) -> tuple[list[float], np.ndarray]:
    """A point on ``body_name`` (its frame) STANDOFF beyond its collision
    geometry, across from the middle of its bounding box, in world direction
    ``world_dir`` (at the pose in ``d``) made square to the link's length (the
    box's longest side; world -x, behind, where ``world_dir`` runs along
    it; as given with ``across`` False); and that point in the world."""
    b = m.body(body_name).id
    pts = _points(m, b)
    rot = d.xmat[b].reshape(3, 3)
    size = pts.max(0) - pts.min(0)
    long = int(np.argmax(size)) if across and np.max(size) > 1.3 * np.median(size) else None
    u = np.zeros(3)
    for want in (world_dir, (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0)):
        u = rot.T @ (np.asarray(want, float) / np.linalg.norm(want))
        if long is not None:
            u[long] = 0.0
        if np.linalg.norm(u) > 0.4:
            break
    u /= np.linalg.norm(u)
    c = (pts.min(0) + pts.max(0)) / 2
    local = c + u * (float(np.max((pts - c) @ u)) + STANDOFF)
    return [round(float(x), 4) for x in local], d.xpos[b] + rot @ local


UP = (0.0, 0.0, 1.0)
STYLES = {"up": (UP, False), "up, across": (UP, True), "behind": ((-1.0, 0.0, 0.0), True),
          "left": ((0.0, 1.0, 0.0), True), "right": ((0.0, -1.0, 0.0), True)}
"""Where the clips and the via points sit on their links: a world direction
at the start pose, and whether it is made square to the link's length
(:func:`outside`). The scene takes the style whose route enters the arm's
collision geometry least (:func:`route_depth`) among those whose hose
settles slack (:func:`settles`; :func:`best_scene`)."""

TRIAL = 0.5
"""Program seconds of each style's trial run (:func:`settles`), after the
scene's 0.5 s settle: the start of the first move (0.7 s long)."""
STRAIN_LIMIT = 0.01
"""Most stretch a style's hose may take in its trial run: the product's taut
strain (``cablecheck.checker.cable.TAUT_STRAIN``, 1 %); a hose with its 12 %
slack that settles stretched is held across something. (Half of it, 0.5 %,
passed over every style of the Fetch with no depth at t = 0, for one that
enters its links by 29 mm and diverges at 3.3 s of the program.)"""
TRIAL_TIMEOUT = 180.0
"""Wall seconds a trial run may take (then it counts as not settling)."""


def has_geometry(m, body: int) -> bool:
    return any(m.geom_bodyid[g] == body and (m.geom_contype[g] or m.geom_conaffinity[g]) for g in range(m.ngeom))


def chain(m, first: str, last: str) -> list[int]:
    """The bodies from ``first`` down the kinematic tree to ``last`` (both included)."""
    out, b, top = [], m.body(last).id, m.body(first).id
    while b != top:
        if b <= 0:
            raise ValueError(f"{last} does not hang from {first}")
        out.append(b)
        b = int(m.body_parentid[b])
    return [top] + out[::-1]


def held_clearance(m, d, held: list[tuple[str, np.ndarray]]) -> float:
    """The least clearance (m) of each held point (body, world point) from the
    collision geometry of every other body, as MuJoCo collides it (the convex
    hull of its vertices, of a primitive's box corners): the largest of the
    point's distances to the hull's face planes, the distance itself where
    the nearest point of the hull is on a face and less elsewhere, negative
    inside (the depth). An end or clip in or against a neighbouring link is
    a design error no route check sees (it excuses the attachment zones).
    (Until 2026-11-28 this took the distance to the nearest hull vertex, so
    a point 12 mm from every vertex of a wrist's hull passed while the hose
    there lay 4.6 mm inside its face.)"""
    from scipy.spatial import ConvexHull

    least = math.inf
    for g in range(m.ngeom):
        if not (m.geom_contype[g] or m.geom_conaffinity[g]) or m.geom_bodyid[g] == 0:
            continue
        pts = _points(m, int(m.geom_bodyid[g]), only=g)
        b = int(m.geom_bodyid[g])
        world = d.xpos[b] + pts @ d.xmat[b].reshape(3, 3).T
        planes = ConvexHull(world).equations        # MuJoCo collides a mesh as its convex hull
        for name, p in held:
            if m.body(name).id == b:
                continue
            least = min(least, float(np.max(planes[:, :3] @ p + planes[:, 3])))
    return least


def flange(m, body_name: str) -> str:
    """The body carrying the tool's mount: ``body_name`` or its nearest
    ancestor with collision geometry (robosuite's ``right_hand`` has none)."""
    b = m.body(body_name).id
    while b > 0:
        if has_geometry(m, b):
            return m.body(b).name
        b = int(m.body_parentid[b])
    raise ValueError(f"no body with collision geometry carries {body_name}")


def program(m, arm: Arm) -> tuple[list[tuple[float, list[float]]], list[str]]:
    """The pick-and-place keys (t, degrees per joint of ``arm.joints``), the
    descents' signs those that lower the tool at home, every value clipped
    to its joint's range less 5 degrees; and notes on what was clipped."""
    import mujoco
    d = mujoco.MjData(m)
    ids = [m.joint(j).id for j in arm.joints]

    def pose(deg):
        for j, v in zip(ids, deg):
            d.qpos[m.jnt_qposadr[j]] = math.radians(v)
        mujoco.mj_kinematics(m, d)
        return d.xpos[m.body(arm.tool).id][2]

    z0 = pose(arm.home)
    signs = [1.0, 1.0, 1.0, 1.0, 1.0]
    for i in (1, 2, 3):
        trial = list(arm.home)
        trial[i] += 5.0
        signs[i] = -1.0 if pose(trial) > z0 else 1.0
    notes, keys = [], []
    for t, delta in PROGRAM:
        row = []
        for i, j in enumerate(ids):
            v = arm.home[i] + signs[i] * delta[i]
            if m.jnt_limited[j]:
                lo, hi = (math.degrees(x) for x in m.jnt_range[j])
                c = min(max(v, lo + 5), hi - 5)
                if c != v:
                    notes.append(f"{arm.joints[i]} {v:.1f} -> {c:.1f} deg (range)")
                v = c
            row.append(round(v, 3))
        keys.append((t, row))
    return keys, notes


def scene_for(name: str, arm: Arm, root: Path, folder: Path, rate: float | None,
              duration: float | None, style: str = "up, across") -> tuple[Path, list[str], float]:
    """Write arm ``name``'s scene (and its trajectory, keys or sampled at
    ``rate`` Hz) into ``folder``, its clips and via points placed in ``style``
    (:data:`STYLES`); its path, notes, and the held points' clearance
    (:func:`held_clearance`)."""
    import mujoco

    from cablecheck.bench.harness import write_scene

    model_path = standalone(arm, root, folder)
    m = mujoco.MjModel.from_xml_path(str(model_path))
    keys, notes = program(m, arm)
    label = name if rate is None else f"{name}_{int(rate)}hz"
    csv = write_trajectory(folder / f"{label}.csv", list(arm.joints), keys if rate is None else sample(keys, rate))

    d = mujoco.MjData(m)
    for j, v in zip(arm.joints, keys[0][1]):
        d.qpos[m.jnt_qposadr[m.joint(j).id]] = math.radians(v)
    mujoco.mj_kinematics(m, d)
    start, p_start = outside(m, d, arm.base, (-1, 0, 0.3))
    way, across = STYLES[style]
    clips = [outside(m, d, b, way, across) for b in arm.clips]
    end, p_end = outside(m, d, arm.wrist, way, across)
    vias = [p_start + np.array([-0.02, 0, 0.6 * (clips[0][1][2] - p_start[2])])]
    route = [p_start, vias[0]]           # in order along the arm (the product inserts each clip where the route passes)
    for b in chain(m, arm.clips[0], arm.wrist)[:-1]:   # every link from the first clip to the wrist: a clip or a via
        name = m.body(b).name
        if name in arm.clips:
            route.append(clips[arm.clips.index(name)][1])
        elif has_geometry(m, b):
            vias.append(outside(m, d, name, way, across)[1])
            route.append(vias[-1])
    route.append(p_end)
    length = SLACK * float(sum(np.linalg.norm(b - a) for a, b in zip(route, route[1:])))

    base = m.body(arm.stand or arm.base).id
    base_xy = d.xpos[base][:2]
    floor = float(min((d.xpos[base] + d.xmat[base].reshape(3, 3) @ p)[2] for p in _points(m, base)))
    data = {
        "scene": {"name": f"zoo-{label}", "units": "m", "duration": duration or PROGRAM[-1][0], "settle": 0.5,
                  "mjcf": str(model_path)},
        "effects": {"contact": ["cable-structure"]},
        "check": {"clearance": 0.005},
        "parts": [
            {"name": "cell/table", "shape": "box", "size": [0.7, 0.7, 0.02],
             "pos": [round(float(base_xy[0]) + 0.2, 4), round(float(base_xy[1]), 4), round(floor - 0.02, 4)]},
            {"name": "cell/post", "shape": "cylinder", "size": [0.04, 0.5],
             "pos": [round(float(base_xy[0]) - 0.3, 4), round(float(base_xy[1]) + 0.45, 4), round(floor + 0.5, 4)]},
            {"name": "tool/body", "body": arm.tool, "shape": "box", "size": [0.025, 0.025, 0.025],
             "pos": list(arm.tool_pos)},
        ],
        "cables": [{
            "name": "hose", "radius": HOSE_RADIUS,
            "start": {"body": arm.base, "pos": start},
            "via": [[round(float(x), 4) for x in v] for v in vias],
            "clips": [{"body": b, "pos": c[0]} for b, c in zip(arm.clips, clips)],
            "end": {"body": arm.wrist, "pos": end},
            "length": round(length, 4), "young": 5.0e6, "density": 1200, "min_bend_radius": 0.035,
        }],
        "motion": [{"file": csv.name, "angles": "deg", "interpolation": "cubic"}],
        "allow": [{"a": "cell/table", "b": arm.stand or arm.base, "reason": "the arm's base is bolted to the table"},
                  {"a": "tool", "b": flange(m, arm.tool), "reason": "the tool is mounted on the flange"}],
    }
    held = [(arm.base, p_start), *zip(arm.clips, (c[1] for c in clips)), (arm.wrist, p_end)]
    return write_scene(data, folder / f"{label}.toml"), notes, held_clearance(m, d, held)


DEPTH = re.compile(r"up to ([0-9.eE+-]+) m inside")


def route_depth(scene_path: Path) -> float:
    """How deep the routed hose enters the parts it collides with at t = 0, summed
    over the parts (metres), as ``cablecheck check`` warns; inf when the check fails."""
    out = subprocess.run(cli() + ["check", str(scene_path)], capture_output=True, text=True, cwd=REPO)
    if out.returncode != 0:
        return math.inf
    return sum(float(x) for x in DEPTH.findall(out.stdout + out.stderr))


def settles(scene_path: Path) -> dict:
    """Run the scene (cut to :data:`TRIAL` seconds of its program) as a user
    does, without a recording, and read its report: ``complete``, ``taut``
    (a taut event or the cable's taut flag), ``strain`` (the cables' largest
    ``max_strain``), ``ok`` (complete, not taut, strain within
    :data:`STRAIN_LIMIT`) and ``why`` (what is wrong, for a note)."""
    report = scene_path.with_suffix(".json")
    report.unlink(missing_ok=True)
    args = ["run", str(scene_path), "--no-record", "--report", str(report), "--fail-on", "never", "--quiet"]
    try:
        subprocess.run(cli() + args, capture_output=True, text=True, cwd=REPO, timeout=TRIAL_TIMEOUT,
                       check=False)
    except subprocess.TimeoutExpired:
        return {"complete": False, "taut": True, "strain": math.inf, "ok": False,
                "why": f"trial run not done in {TRIAL_TIMEOUT:g} s"}
    if not report.exists():
        return {"complete": False, "taut": True, "strain": math.inf, "ok": False, "why": "trial run failed"}
    r = json.loads(report.read_text())
    complete = bool(r.get("complete", True))
    taut = any(e["type"] == "taut" for e in r["events"]) or any(c.get("taut") for c in r["cables"])
    strain = max((math.inf if c.get("max_strain") is None else float(c["max_strain"]) for c in r["cables"]),
                 default=0.0)                       # None: diverged before a step was checked
    why = [w for w, on in ((f"diverged at t {r['settings']['t_end']:g} s", not complete), ("taut", taut),
                           (f"strain {100 * strain:.1f} %", math.isfinite(strain) and strain > STRAIN_LIMIT))
           if on]
    return {"complete": complete, "taut": taut, "strain": strain, "ok": not why,
            "why": ", ".join(why) if why else f"strain {100 * strain:.2f} %"}


def best_scene(name: str, arm: Arm, root: Path, folder: Path, rate: float | None,
               duration: float | None) -> tuple[Path, list[str]]:
    """The scene of the style (:data:`STYLES`) whose route enters the arm least
    at t = 0 (:func:`route_depth`, and ends and clips closer than the hose's
    radius and 5 mm to another link) of those whose hose settles slack: a
    trial run of each candidate (:func:`settles`), in that order until one
    does. The t = 0 criteria alone took 'up, across' on the Kinova Gen3 (no
    depth, its clips 42 mm clear): its hose wedged between two links' hulls
    while it settled, came taut (6 % strain) for the whole run, and checking
    it took 13 s for 2.9 s of simulation. When no style settles slack the
    least bad is taken (complete, not taut, least strain, least depth) and
    the note says so. A note names the style, what depth is left and the
    styles passed over."""
    tried, trials = {}, {}
    need = HOSE_RADIUS + 0.005
    short = min(duration or PROGRAM[-1][0], TRIAL)
    paths = {}
    for style in STYLES:                            # in order; a clean one with no depth ends the search
        sub = folder / "styles" / style.replace(", ", "_")
        sub.mkdir(parents=True, exist_ok=True)
        paths[style], _, clear = scene_for(name, arm, root, sub, rate, short, style)
        tried[style] = route_depth(paths[style]) + max(0.0, need - clear)
        if tried[style] == 0.0:
            trials[style] = settles(paths[style])
            if trials[style]["ok"]:
                break
    for style in sorted(tried, key=tried.get):      # else the least depth that settles slack
        if style not in trials:
            trials[style] = settles(paths[style])
        if trials[style]["ok"]:
            break
    good = [s for s in trials if trials[s]["ok"]]
    style = (min(good, key=tried.get) if good else
             min(trials, key=lambda s: (not trials[s]["complete"], trials[s]["taut"], trials[s]["strain"], tried[s])))
    path, notes, clear = scene_for(name, arm, root, folder, rate, duration, style)
    left = (f"; the route still enters the arm by {1000 * tried[style]:.1f} mm in all (ends and clips "
            f"{1000 * clear:.0f} mm from the nearest other link)") if tried[style] else ""
    bad = "" if good else (f"; no style settles slack in its {short:g} s trial (this one: "
                           f"{trials[style]['why']}), the least bad taken")
    over = [f"{s} ({trials[s]['why']})" for s in trials if s != style and not trials[s]["ok"]]
    passed = f"; passed over as not settling slack: {'; '.join(over)}" if over else ""
    return path, [*notes, f"clips and via points: {style}{left}{bad}{passed}"]


# --------------------------------------------------------------------------- runs

def held_points(scene_path: Path) -> tuple[list[tuple[str, float]], float, dict]:
    """The hose's ends and clips (window, arc length at rest) in the built
    model, its attachment zone (arc length), and the counts of the built
    scene (checked parts, of them mesh parts, visual geoms drawn only)."""
    from cablecheck.build.drawn import DrawnLoad
    from cablecheck.build.stages import build
    from cablecheck.scene.load import load_scene

    scene = load_scene(scene_path)
    built = build(scene, detect=False)
    c = built.cables[0]
    held: dict[str, list[float]] = {}
    for a in c.attachments:
        held.setdefault(a.window, []).append(float(a.s))
    counts = {"parts": len(built.parts), "meshes": sum(p.shape == "mesh" for p in built.parts),
              "triangles": sum(len(p.faces) for p in built.parts if p.faces is not None),
              "visuals": len(DrawnLoad(scene).result())}
    return [(w, float(np.mean(s))) for w, s in held.items()], built.scene.check.attach_zone * c.radius, counts


def cli() -> list[str]:
    script = Path(sys.executable).parent / "cablecheck"
    return [str(script)] if script.exists() else [sys.executable, "-c",
                                                  "import sys; from cablecheck.cli.main import main; sys.exit(main())"]


def run_one(label: str, scene_path: Path, timeout: float | None = None) -> dict:
    """Run the scene as a user does; the row of the table (or its error)."""
    report_path, rec = scene_path.with_suffix(".json"), scene_path.with_suffix(".rrd")
    row: dict = {"arm": label, "scene": str(scene_path)}
    try:
        held, zone, counts = held_points(scene_path)
    except Exception as exc:                       # the product failed on the model: report it, go on
        row["error"] = f"building: {type(exc).__name__}: {exc}"
        return row
    t0 = time.perf_counter()
    args = ["run", str(scene_path), "--report", str(report_path), "--quiet", "--fail-on", "never"]
    try:
        proc = subprocess.run(cli() + args + ["--record", str(rec)], capture_output=True, text=True, cwd=REPO,
                              timeout=timeout)
    except subprocess.TimeoutExpired:               # killed: run it again without its recording
        row["error"] = (f"cablecheck run did not finish within {timeout:g} s (killed); the figures are of the "
                        "same run with --no-record")
        report_path.unlink(missing_ok=True)
        try:
            proc = subprocess.run(cli() + args + ["--no-record"], capture_output=True, text=True, cwd=REPO,
                                  timeout=timeout)
        except subprocess.TimeoutExpired:
            row["error"] = f"cablecheck run did not finish within {timeout:g} s, with or without a recording"
            return row
    row["wall_s"] = time.perf_counter() - t0
    if proc.returncode not in (0, 3) or not report_path.exists():
        row["error"] = f"cablecheck run exited {proc.returncode}: {(proc.stderr or proc.stdout).strip()[-1500:]}"
        return row
    r = json.loads(report_path.read_text())
    if not r.get("complete", True):
        row["error"] = (f"incomplete run (exit {proc.returncode}) at t = {r['settings']['t_end']:g} s: "
                        f"{r.get('physics_error') or r.get('error') or r.get('interrupted')}")
    t = r["timing"]
    duration = r["settings"]["t_end"]
    events = r["events"]
    near = []
    for e in events:
        hit = near_held(float(e["s"]), held, 2 * zone) if e.get("s") is not None else None
        if hit is not None:
            near.append({**{k: e[k] for k in ("severity", "type", "a", "b", "min_distance", "t_worst")},
                         "window": hit[0], "ds": float(e["s"]) - hit[1],
                         "mujoco": second_opinion(e, r.get("validation") or {}, r.get("physics_warnings", ()))})
    row.update({
        "elements": r["cables"][0]["segments"], **counts, "duration": duration, "complete": r.get("complete", True), "timing": t, "ratio": ratio(t),
        "rtf": duration / max(t["total_s"], 1e-12), "agreement": r["validation"]["agreement"],
        "hard": sum(e["severity"] == "hard" for e in events), "soft": sum(e["severity"] == "soft" for e in events),
        "near_held": near, "excused": len(r.get("excused", [])), "report": str(report_path),
    })
    return row


def table(rows: list[dict]) -> str:
    lines = ["| arm | hose elements / parts | sim s | check s | validate s | record s | (c+v+r)/sim | real time | wall s "
             "| command s | real time, command | agreement | hard / soft | next to a clamp or clip |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if "timing" not in r:
            lines.append(f"| {r['arm']} | error: {r['error'].splitlines()[-1][:120]} |" + " |" * 12)
            continue
        t = r["timing"]
        arm = r["arm"] if r.get("complete", True) else f"{r['arm']} (stopped at {r['duration']:.2f} s)"
        lines.append(f"| {arm} | {r['elements']} / {r['parts']} ({r['meshes']} meshes, "
                     f"{r['triangles']} triangles) | {t['sim_s']:.2f} | {t['check_s']:.2f} | {t['validate_s']:.2f} | "
                     f"{t['record_s']:.2f} | **{r['ratio']:.2f}** | {r['rtf']:.2f}x | {t['total_s']:.1f} | "
                     f"{r['wall_s']:.1f} | {r['duration'] / max(r['wall_s'], 1e-12):.2f}x | "
                     f"{100 * r['agreement']:.2f} % | {r['hard']} / {r['soft']} | {len(r['near_held'])} |")
    return "\n".join(lines)


def code_state() -> str:
    """The revision measured: HEAD, and the product's files changed in the working tree."""
    git = ["git", "-C", str(REPO)]
    head = subprocess.run(git + ["rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(git + ["status", "--porcelain", "--", "sim", "checker"], capture_output=True,
                           text=True).stdout.split("\n")
    dirty = [line[3:] for line in dirty if line.strip()]
    return f"`{head}`" + (f" with uncommitted changes to {len(dirty)} product file(s) ({', '.join(dirty[:8])}"
                          f"{', ...' if len(dirty) > 8 else ''})" if dirty else "")


def load() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def one_minute(uptime: str) -> float:
    try:
        return float(uptime.split("load average:")[1].split(",")[0])
    except (IndexError, ValueError):
        return float("nan")


def write_doc(path: Path, text: str) -> None:
    """bench_startup's marker writer, with this benchmark's markers."""
    import bench_startup
    saved = bench_startup.BEGIN, bench_startup.END
    bench_startup.BEGIN, bench_startup.END = BEGIN, END
    try:
        bench_startup.write_doc(path, text)
    finally:
        bench_startup.BEGIN, bench_startup.END = saved


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--arms", default=",".join(ZOO), help=f"comma-separated, of: {', '.join(ZOO)}")
    ap.add_argument("--hz-arm", default="panda", help="the arm also driven from a 100 Hz CSV ('' for none)")
    ap.add_argument("--duration", type=float, default=None, help="simulated seconds (default: the program's 4.4)")
    ap.add_argument("--keep", type=Path, default=None, help="write the scenes, reports and recordings here")
    ap.add_argument("--doc", type=Path, default=None, help="write the table into this Markdown file")
    ap.add_argument("--timeout", type=float, default=600.0, help="wall seconds one arm's run may take")
    ap.add_argument("--from", dest="rows", type=Path, default=None,
                    help="print (and with --doc write) the table of a kept run's rows.json again, nothing run")
    ap.add_argument("--scenes-only", action="store_true", help="write the scenes and stop")
    a = ap.parse_args(argv)
    if a.rows is not None:
        finish(json.loads(a.rows.read_text()), a.doc)
        return 0
    names = [n for n in a.arms.split(",") if n]
    unknown = [n for n in names if n not in ZOO]
    if unknown:
        print(f"bench_robots: unknown arm(s) {', '.join(unknown)}; the zoo: {', '.join(ZOO)}", file=sys.stderr)
        return 2
    roots = {p: package_root(p) for p in {ZOO[n].package for n in names}}
    missing = sorted(PACKAGES[p] for p, r in roots.items() if r is None)
    if missing:
        print(f"bench_robots: package(s) not installed: {', '.join(missing)}; skipping "
              f"{', '.join(n for n in names if roots[ZOO[n].package] is None)}. Install the optional extra: "
              "pip install --no-deps robosuite gymnasium-robotics (only their model files are read; their "
              "dependencies would replace mujoco-core's mujoco module with MuJoCo 3)", file=sys.stderr)
    names = [n for n in names if roots[ZOO[n].package] is not None]
    if not names:
        print("bench_robots: no arm of the zoo is installed; nothing to run", file=sys.stderr)
        return 2
    folder = a.keep or Path(tempfile.mkdtemp(prefix="bench_robots_"))
    folder.mkdir(parents=True, exist_ok=True)
    todo = []
    for n in names:
        arm, root = ZOO[n], roots[ZOO[n].package]
        for rate in ([None, HZ] if n == a.hz_arm else [None]):
            label = n if rate is None else f"{n} @ {int(rate)} Hz CSV"
            try:
                path, notes = best_scene(n, arm, root, folder, rate, a.duration)
                todo.append((label, path, notes))
            except Exception as exc:
                todo.append((label, None, [f"scene not written: {type(exc).__name__}: {exc}"]))
    if a.scenes_only:
        for label, path, notes in todo:
            print(label, path, "; ".join(notes))
        return 0
    before = load()
    started = datetime.datetime.now().astimezone()
    rows = []
    for label, path, notes in todo:
        row = run_one(label, path, a.timeout) if path is not None else {"arm": label, "error": notes[-1]}
        row["notes"] = notes
        rows.append(row)
        state = row.get("error") or f"(c+v+r)/sim {row['ratio']:.2f}, real time {row['rtf']:.2f}x"
        print(f"  {label}: {state}", file=sys.stderr, flush=True)
    after = load()
    run = {"started": f"{started:%Y-%m-%d %H:%M %Z}", "before": before, "after": after, "code": code_state(),
           "command": f"python benchmarks/bench_robots.py {shlex.join(sys.argv[1:] if argv is None else argv)}",
           "duration": PROGRAM[-1][0] if a.duration is None else a.duration, "rows": rows}
    (folder / "rows.json").write_text(json.dumps(run, indent=1, default=str))
    finish(run, a.doc)
    if a.keep is None:
        print(f"scenes, reports and recordings: {folder}")
    return 0


CONTACTS = ("cable-structure", "keepout", "cable-cable", "self")
"""Event types MuJoCo's contacts have an opinion on (the validation compares them)."""


def second_opinion(e: dict, validation: dict, warnings=()) -> str:
    """What MuJoCo's contacts say of event ``e`` at its worst step: a contact type whose pair
    the validation found disagreeing there names the reason; one it did not, agrees; a taut
    event is no contact (no second opinion); a bend is none either, but where the run warned
    (``warnings``, the report's physics warnings) that the hose's elements cannot resolve its
    bend, it is tighter still on a finer rod (docs/physics.md, Bends the elements cannot resolve)."""
    if e["type"] == "bend":
        if any(f"cable {e['a']!r}" in w and "cannot resolve" in w for w in warnings):
            return "no contact; its elements cannot resolve the bend, which a finer rod reads tighter still"
        return "no contact: no second opinion"
    if e["type"] not in CONTACTS:
        return "no contact: no second opinion"
    if not validation:
        return "not validated"
    for d in validation.get("disagreements", []):
        if (d["type"], d["a"], d["b"]) == (e["type"], e["a"], e["b"]) and \
                d["t_start"] - 1e-9 <= e["t_worst"] <= d["t_end"] + 1e-9:
            return f"MuJoCo differs there ({d['reason']})"
    return "MuJoCo agrees at its worst step"


def hose_event(e: dict) -> bool:
    """An event of the hose (against a part or itself), not of two parts."""
    return e["type"] != "part-part"


def finish(run: dict, doc: Path | None) -> None:
    """Print the run's table and lists (and write them into ``doc``)."""
    rows, before, after = run["rows"], run["before"], run["after"]
    for r in rows:                                  # part-part events have no place along the hose
        r["near_held"] = [e for e in r.get("near_held", []) if hose_event(e)]
    lines = [f"Measured {run['started']} on {platform.node() or 'this machine'} "
             f"({os.cpu_count()} cores, {platform.processor() or platform.machine()}, Python "
             f"{platform.python_version()}), one run each, one after the other; "
             f"{run['duration']:g} s pick-and-place after 0.5 s settling.",
             "", f"Load before: `{before}`; after: `{after}`"
             + (" (not quiet: wall times and the real-time factor are above a quiet machine's)"
                if max(one_minute(before), one_minute(after)) > 0.5 else "") + ".", "",
             f"Code: {run['code']}.", "",
             f"Command: `{run['command']}`", "", table(rows), ""]
    for r in rows:
        if "error" in r:
            lines.append(f"- {r['arm']}: **{r['error']}**")
        for e in r.get("near_held", []):
            lines.append(f"- {r['arm']}: {e['severity']} {e['type']} {e['a']} / {e['b']} at {e['ds'] * 1000:+.0f} mm "
                         f"from {e['window']}, worst {e['min_distance'] * 1000:.1f} mm at t {e['t_worst']:.2f} s "
                         f"({e.get('mujoco', 'possible false alarm')})")
        for n in r.get("notes", []):
            lines.append(f"- {r['arm']}: {n}")
    text = "\n".join(lines).rstrip() + "\n"
    print(text)
    if doc is not None:
        write_doc(doc, text.rstrip("\n"))


if __name__ == "__main__":
    sys.exit(main())
