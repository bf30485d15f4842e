"""Time one full :func:`checker.interference.check_state` on a large scene.

The scene of issue 3: 100 cables of 200 points (20,000 points), 300 primitive
parts (boxes, cylinders, capsules, spheres, ellipsoids) and 10 torus meshes of
2,000 triangles, in metres. It prints the median time of a full check with
method ``points`` and ``exact`` (with :func:`check_state`, and with a
:class:`~checker.interference.Checker` reused across calls as a simulation
loop would, the parts prepared once), where the time goes, and the same close-pair
queries done by python-fcl (a general collision library) in the same run when
it is installed, with the ratio. It also counts the false alarms of the
paper's face-plane distance (``face_plane=True``) against true surface
distance on the same scene.

Run: ``python benchmarks/bench_checker.py [--repeat N] [--no-fcl]``. Timings
are single-threaded (set OMP/BLAS threads to 1 for a fair number).

Deliberately not a test: nothing here asserts a time.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from checker.interference import Checker, check_state  # noqa: E402
from checker.records import PairType  # noqa: E402
from checker.scene_state import CableState, CheckConfig, PartState  # noqa: E402
from checker.shapes import Shape, ShapeType, mesh_shape  # noqa: E402


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    return q


def make_scene(seed: int = 0, n_cables: int = 100, n_points: int = 200, n_prims: int = 300, n_meshes: int = 10):
    """Cables as smooth random walks at spacing 2r through a 2 x 2 x 1 m room of parts."""
    rng = np.random.default_rng(seed)
    radius = 0.004
    step = 2 * radius
    cables = []
    for c in range(n_cables):
        d = rng.normal(size=3)
        p = rng.uniform([0, 0, 0], [2, 2, 1])
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
        pose[:3, 3] = rng.uniform([0, 0, 0], [2, 2, 1])
        parts.append(PartState(f"prim{k}", Shape(kind, size), pose, keepout=bool(k % 10 == 0)))
    torus = trimesh.creation.torus(0.08, 0.02, major_sections=50, minor_sections=20)
    shape = mesh_shape(torus.vertices, torus.faces)
    for k in range(n_meshes):
        pose = np.eye(4)
        pose[:3, :3] = random_rotation(rng)
        pose[:3, 3] = rng.uniform([0, 0, 0], [2, 2, 1])
        parts.append(PartState(f"mesh{k}", shape, pose))
    return cables, parts


def time_check(cables, parts, config, repeat):
    """Median seconds of check_state and of a reused Checker's check, and the records."""
    check_state(cables, parts, config)
    checker = Checker(parts, config)
    poses = np.array([p.pose for p in parts])
    checker.check(cables, poses)
    ts, tc = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = check_state(cables, parts, config)
        t1 = time.perf_counter()
        checker.check(cables, poses)
        tc.append(time.perf_counter() - t1)
        ts.append(t1 - t0)
    return float(np.median(ts)), float(np.median(tc)), out


def fcl_queries(cables, parts, config, repeat):
    """The same close-pair queries with python-fcl's dynamic AABB tree.

    Cable pieces (spheres at the points for ``points``, capsules per element
    for ``exact``) are inflated by the clearance; one collide call finds
    cable-part pairs and one finds cable-cable and self pairs. The time
    includes updating every cable piece's transform, as every simulated step
    would. Only the pairs are found (no distances): fcl's distance queries
    per pair would be slower still.
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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--no-fcl", action="store_true")
    ap.add_argument("--profile", action="store_true", help="print where the time goes")
    args = ap.parse_args(argv)
    cables, parts = make_scene()
    n_pts = sum(len(c.points) for c in cables)
    n_tri = sum(len(p.shape.faces) for p in parts if p.shape.type is ShapeType.MESH)
    print(f"scene: {len(cables)} cables, {n_pts} points, {len(parts)} parts ({n_tri} mesh triangles)")
    results = {}
    for method in ("points", "exact"):
        cfg = CheckConfig(method=method)
        t, t_reuse, out = time_check(cables, parts, cfg, args.repeat)
        results[method] = (t, out)
        counts = {pt.value: sum(r.type is pt for r in out) for pt in PairType}
        counts = {k: v for k, v in counts.items() if v}
        print(f"{method:>6}: {t * 1e3:8.2f} ms per check_state, {t_reuse * 1e3:8.2f} ms per reused "
              f"Checker.check   records {counts}")
        if args.profile:
            pr = cProfile.Profile()
            pr.enable()
            for _ in range(5):
                check_state(cables, parts, cfg)
            pr.disable()
            pstats.Stats(pr).sort_stats("tottime").print_stats(12)
    # The paper's face-plane distance against true distance on the same scene.
    t_fp, _, out_fp = time_check(cables, parts, CheckConfig(method="points", face_plane=True), 3)
    true_pairs = {(r.type, r.a, r.b) for r in results["points"][1] if r.type is PairType.CABLE_STRUCTURE}
    fp_pairs = {(r.type, r.a, r.b) for r in out_fp if r.type is PairType.CABLE_STRUCTURE}
    print(f"face-plane |BP.N|: {len(fp_pairs)} cable-structure pairs vs {len(true_pairs)} true; "
          f"false alarms {len(fp_pairs - true_pairs)}, misses {len(true_pairs - fp_pairs)}")
    if not args.no_fcl:
        try:
            import fcl  # noqa: F401
        except ImportError:
            print("python-fcl not installed: pip install python-fcl for the comparison")
            return
        for method in ("points", "exact"):
            upd, qry, n_found = fcl_queries(cables, parts, CheckConfig(method=method), args.repeat)
            ours = results[method][0]
            print(f"fcl {method:>6}: update {upd * 1e3:8.2f} ms + pair query {qry * 1e3:8.2f} ms "
                  f"= {(upd + qry) * 1e3:8.2f} ms ({n_found} touching pieces); checker is "
                  f"{(upd + qry) / ours:5.1f}x faster ({qry / ours:5.1f}x on the query alone)")


if __name__ == "__main__":
    main()
