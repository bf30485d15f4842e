"""Benchmark scenes and the general-collision-library comparison, shared.

Used by `cablecheck bench` (:mod:`sim.bench`) and by
``benchmarks/bench_checker.py``, so both time the same scenes:

- :func:`make_scene`: randomised cables (smooth random walks) and parts
  (boxes, cylinders, capsules, spheres, ellipsoids, torus meshes) placed in a
  room; the defaults are the checker benchmark's scene of 100 cables x 200 points against
  300 primitives and 10 meshes.
- :func:`fcl_queries`: the same close-pair queries done by python-fcl (an
  optional dependency, the ``bench`` extra), timed.

Deliberately not here: timing of the checker itself, tables, printing
(:mod:`sim.bench`); nothing here is used by a run.
"""

from __future__ import annotations

import time

import numpy as np
import trimesh

from checker.scene_state import CableState, PartState
from checker.shapes import Shape, ShapeType, mesh_shape


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    return q


def make_scene(seed: int = 0, n_cables: int = 100, n_points: int = 200, n_prims: int = 300,
               n_meshes: int = 10, room=(2.0, 2.0, 1.0), step: float | None = None,
               radius: float = 0.004):
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


def fcl_queries(cables, parts, config, repeat):
    """The same close-pair queries with python-fcl's dynamic AABB tree.

    Cable pieces (spheres at the points for ``points``, capsules per element
    for ``exact``) are inflated by the clearance; one collide call finds
    cable-part pairs and one finds cable-cable and self pairs. The time
    includes updating every cable piece's transform, as every simulated step
    would. Only the pairs are found (no distances): fcl's distance queries
    per pair would be slower still.

    Returns (update seconds, pair query seconds, pieces found), medians over
    max(1, repeat // 3) runs. Raises ImportError without python-fcl.
    """
    import fcl

    from checker.cable import densify_batch

    radii = np.array([c.radius for c in cables])
    pts = np.concatenate([c.points for c in cables])
    offsets = np.concatenate([[0], np.cumsum([len(c.points) for c in cables])])
    p, s, cab, _ = densify_batch(pts, offsets, config.spacing * radii)
    objs = []
    if config.method == "points":
        for i in range(len(p)):
            objs.append(fcl.CollisionObject(fcl.Sphere(radii[cab[i]] + config.clearance / 2), fcl.Transform(p[i])))
    else:
        seg = np.nonzero(cab[:-1] == cab[1:])[0]
        for i in seg:
            a, b = p[i], p[i + 1]
            length = float(np.linalg.norm(b - a))
            objs.append(fcl.CollisionObject(fcl.Capsule(radii[cab[i]] + config.clearance / 2, length), fcl.Transform()))
    part_objs = []
    for pt in parts:
        sh = pt.shape
        if sh.type is ShapeType.BOX:
            g = fcl.Box(*(2 * sh.size[:3]))
        elif sh.type is ShapeType.SPHERE:
            g = fcl.Sphere(sh.size[0])
        elif sh.type is ShapeType.CYLINDER:
            g = fcl.Cylinder(sh.size[0], 2 * sh.size[1])
        elif sh.type is ShapeType.CAPSULE:
            g = fcl.Capsule(sh.size[0], 2 * sh.size[1])
        elif sh.type is ShapeType.ELLIPSOID:
            g = fcl.Ellipsoid(*sh.size[:3])
        else:
            m = fcl.BVHModel()
            m.beginModel(len(sh.vertices), len(sh.faces))
            m.addSubModel(sh.vertices, sh.faces)
            m.endModel()
            g = m
        part_objs.append(fcl.CollisionObject(g, fcl.Transform(pt.pose[:3, :3], pt.pose[:3, 3])))
    parts_mgr = fcl.DynamicAABBTreeCollisionManager()
    parts_mgr.registerObjects(part_objs)
    parts_mgr.setup()

    def capsule_tf(a, b):
        d = b - a
        n = np.linalg.norm(d)
        z = d / n if n > 0 else np.array([0.0, 0.0, 1.0])
        x = np.cross(z, [1.0, 0, 0]) if abs(z[0]) < 0.9 else np.cross(z, [0, 1.0, 0])
        x /= np.linalg.norm(x)
        return fcl.Transform(np.stack([x, np.cross(z, x), z], axis=1), 0.5 * (a + b))

    req = fcl.CollisionRequest(num_max_contacts=1, enable_contact=False)

    def collect(o1, o2, found):
        # Every broad-phase pair gets a narrow test; never stop early (fcl's
        # default callback stops at the first contact).
        if fcl.collide(o1, o2, req, fcl.CollisionResult()):
            found.append((id(o1), id(o2)))
        return False

    def run():
        t0 = time.perf_counter()
        if config.method == "points":
            for i, o in enumerate(objs):
                o.setTranslation(p[i])
        else:
            for o, i in zip(objs, seg):
                o.setTransform(capsule_tf(p[i], p[i + 1]))
        mgr = fcl.DynamicAABBTreeCollisionManager()
        mgr.registerObjects(objs)
        mgr.setup()
        t1 = time.perf_counter()
        found = []
        mgr.collide(parts_mgr, found, collect)
        mgr.collide(found, collect)
        t2 = time.perf_counter()
        return t1 - t0, t2 - t1, len(found)

    run()
    res = [run() for _ in range(max(1, repeat // 3))]
    upd = float(np.median([r[0] for r in res]))
    qry = float(np.median([r[1] for r in res]))
    return upd, qry, res[0][2]
