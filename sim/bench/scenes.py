"""Benchmark scenes, shared by `cablecheck bench` (`cablecheck.bench.command`) and the
scripts in ``benchmarks/``, so both time the same scenes:

- :func:`make_scene`: randomised cables (smooth random walks) and parts
  (boxes, cylinders, capsules, spheres, ellipsoids, torus meshes) placed in
  a room, as the checker's states; the defaults are the checker benchmark's
  scene of 100 cables x 200 points against 300 primitives and 10 meshes.
- :func:`synthetic_scene`: routed cables among primitive parts as a scene
  file's dict, through the real parser (for MuJoCo's side of a comparison).
- :func:`resting_hose_text`: a hose resting on primitives on a moving rig,
  with others beside it, as a scene file's text.

Deliberately not here: timing, tables and printing (`cablecheck.bench.command` and its
table modules), the python-fcl comparison (`cablecheck.bench.fcl`); nothing here is
used by a run.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from cablecheck.checker.scene_state import CableState, PartState
from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape
from cablecheck.scene.load import parse_scene
from cablecheck.scene.records import Scene

RADIUS = 0.004
"""Cable radius of the randomised scenes, m."""


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    return q


def make_scene(seed: int = 0, n_cables: int = 100, n_points: int = 200, n_prims: int = 300,
               n_meshes: int = 10, room=(2.0, 2.0, 1.0), step: float | None = None,
               radius: float = RADIUS):
    """Cables as smooth random walks through a room of parts, in metres.

    Defaults: the checker benchmark's scene (100 cables of 200 points at spacing 2r,
    20,000 points; 300 primitives; 10 torus meshes of 2,000 triangles in a
    2 x 2 x 1 m room). `step` is the distance between consecutive cable
    points (default 2r); `room` the box the cables start in and the parts
    are placed in. Returns (cables, parts): lists of CableState, PartState.
    """
    rng = np.random.default_rng(seed)
    step = 2 * radius if step is None else step
    room = np.asarray(room, dtype=float)
    cables = []
    for c in range(n_cables):
        d = rng.normal(size=3)
        p = rng.uniform(0.0, room)
        pts = [p]
        for _ in range(n_points - 1):
            d = d / np.linalg.norm(d) + 0.15 * rng.normal(size=3)
            d /= np.linalg.norm(d)
            p = p + step * d
            pts.append(p)
        cables.append(CableState(f"cable{c}", np.array(pts), radius))
    parts = []
    kinds = [ShapeType.BOX, ShapeType.CYLINDER, ShapeType.CAPSULE, ShapeType.SPHERE, ShapeType.ELLIPSOID]
    weights = [0.4, 0.25, 0.15, 0.1, 0.1]
    for k in range(n_prims):
        kind = kinds[rng.choice(len(kinds), p=weights)]
        size = rng.uniform(0.01, 0.06, size=3)
        pose = np.eye(4)
        pose[:3, :3] = random_rotation(rng)
        pose[:3, 3] = rng.uniform(0.0, room)
        parts.append(PartState(f"prim{k}", Shape(kind, size), pose, keepout=bool(k % 10 == 0)))
    torus = trimesh.creation.torus(0.08, 0.02, major_sections=50, minor_sections=20)
    shape = mesh_shape(torus.vertices, torus.faces)
    for k in range(n_meshes):
        pose = np.eye(4)
        pose[:3, :3] = random_rotation(rng)
        pose[:3, 3] = rng.uniform(0.0, room)
        parts.append(PartState(f"mesh{k}", shape, pose))
    return cables, parts


def synthetic_scene(n_cables: int, segments: int, n_parts: int, seed: int = 7) -> Scene:
    """A scene (through the real parser and builder) of routed cables among primitive parts.

    Cables run through random-walk `via` points in a 1 x 1 x 0.5 m room, as
    routed (dynamics off); parts are boxes, cylinders, capsules, spheres and
    ellipsoids at random poses."""
    rng = np.random.default_rng(seed)
    room = np.array([1.0, 1.0, 0.5])
    r = RADIUS
    cables = []
    for c in range(n_cables):
        p = rng.uniform(0.1 * room, 0.9 * room)
        d = rng.normal(size=3)
        pts = [p]
        for _ in range(5):
            d = d / np.linalg.norm(d) + 0.5 * rng.normal(size=3)
            d /= np.linalg.norm(d)
            p = np.clip(p + 0.08 * d, 0.0, room)
            pts.append(p)
        pts = np.array(pts)
        cables.append({"name": f"c{c}", "radius": r,
                       "start": {"body": "world", "pos": pts[0].tolist()},
                       "end": {"body": "world", "pos": pts[-1].tolist()},
                       "via": pts[1:-1].tolist(),
                       # elements at least 2r long, as MuJoCo's flex needs them longer than r
                       "segments": int(min(segments, np.linalg.norm(np.diff(pts, axis=0), axis=1).sum()
                                           // (2 * r)))})
    kinds = ["box", "cylinder", "capsule", "sphere", "ellipsoid"]
    parts = []
    for k in range(n_parts):
        kind = kinds[k % len(kinds)]
        s = rng.uniform(0.01, 0.04, size=3)
        size = {"box": s, "ellipsoid": s, "sphere": s[:1], "cylinder": s[:2], "capsule": s[:2]}[kind]
        parts.append({"name": f"part{k}", "shape": kind, "size": [float(x) for x in size],
                      "pos": rng.uniform(0.0, room).tolist(),
                      "euler": rng.uniform(-180, 180, size=3).tolist()})
    data = {"scene": {"name": f"synthetic{n_cables}x{segments}", "units": "m", "duration": 0.0},
            "effects": {"dynamics": False},
            "parts": parts, "cables": cables}
    return parse_scene(data, Path(f"/virtual/synthetic{n_cables}.toml"))


SHAPES = (("box", "[12, 25, 8]", 8.0, "[0, 0, 0]"), ("capsule", "[8, 25]", 8.0, "[90, 0, 0]"),
          ("cylinder", "[10, 20]", 10.0, "[90, 0, 0]"), ("sphere", "[12]", 12.0, "[0, 0, 0]"),
          ("ellipsoid", "[14, 20, 9]", 9.0, "[0, 0, 0]"))
"""(shape, size, half height below the top, euler): the parts in turn, each
with its top at z = -1 mm in the rig's frame (the hose's underside at 1 mm)."""

PITCH = 38.0
"""mm between the near parts along the hose."""


def resting_hose_text(near: int, far: int, duration: float) -> str:
    """A scene file's text (mm): a 5 mm hose clamped at both ends on a rig that
    turns and rocks, lying across ``near`` primitive parts on it (`SHAPES` in
    turn, their tops 1 mm below the hose's underside), with ``far`` more parts
    200 mm beside it; ``duration`` simulated seconds
    (benchmarks/bench_near.py, tests/test_validation.py)."""
    parts = []
    for k in range(near + far):
        shape, size, below, euler = SHAPES[k % len(SHAPES)]
        x = 40.0 + PITCH * (k if k < near else k - near)
        y = 0.0 if k < near else 200.0 + 40.0 * ((k - near) // max(near, 1))
        parts.append(f'[[parts]]\nname = "rig/p{k}"\nbody = "rig"\nshape = "{shape}"\nsize = {size}\n'
                     f'pos = [{x}, {y}, {-1.0 - below}]\neuler = {euler}\n')
    length = 40.0 + PITCH * max(near, 1)
    return f'''[scene]
name = "near-{near}-far-{far}"
units = "mm"
duration = {duration}
settle = 0.5

[effects]
contact = ["cable-structure"]

[check]
clearance = 3.0

[[bodies]]
name = "rig"
pos = [0, 0, 300]

{"".join(parts)}
[[cables]]
name = "hose"
radius = 5.0
start = {{ body = "rig", pos = [0, 0, 5] }}
end = {{ body = "rig", pos = [{length}, 0, 5] }}
length = {length + 2.0}
young = 5e6
density = 1200

[[motion]]
body = "rig"
keys = [{{t = 0, euler = [0, 0, 0]}}, {{t = {duration / 2}, euler = [0, 8, 60]}}, {{t = {duration}, euler = [0, 0, 120]}}]
'''
