"""The checker's close-pair queries done by python-fcl, a general collision
library, timed: the independent yardstick of `cablecheck bench` and
``benchmarks/``.

python-fcl is optional (the ``bench`` and ``test`` extras): it is imported
only when a comparison runs, and its absence raises `FclMissing` saying how
to install it. This module times fcl only; the checker's side and the
ratios are the callers'.
"""

from __future__ import annotations

import time

import numpy as np

from cablecheck.checker.cable import densify_batch
from cablecheck.checker.shapes import ShapeType

INSTALL = "pip install 'cablecheck[bench]'"
"""How to get python-fcl."""


class FclMissing(ImportError):
    """python-fcl is not installed; the message says how to install it."""


def load_fcl():
    """The `fcl` module, or `FclMissing` when python-fcl is not installed."""
    try:
        import fcl  # python-fcl: an optional dependency (the bench and test extras), loaded for this table only
    except ImportError as e:
        raise FclMissing(f"python-fcl is not installed ({INSTALL}): {e}") from None
    return fcl


def fcl_queries(cables, parts, config, repeat):
    """The same close-pair queries with python-fcl's dynamic AABB tree.

    Cable pieces (spheres at the points for ``points``, capsules per element
    for ``exact``) are inflated by the clearance; one collide call finds
    cable-part pairs and one finds cable-cable and self pairs. The time
    includes updating every cable piece's transform, as every simulated step
    would. Only the pairs are found (no distances): fcl's distance queries
    per pair would be slower still.

    Returns (update seconds, pair query seconds, pieces found), medians over
    max(1, repeat // 3) runs. Raises `FclMissing` without python-fcl.
    """
    fcl = load_fcl()

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
