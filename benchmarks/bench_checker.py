"""Time one full :func:`cablecheck.checker.interference.check_state` on a large scene.

The checker benchmark's scene: 100 cables of 200 points (20,000 points), 300 primitive
parts (boxes, cylinders, capsules, spheres, ellipsoids) and 10 torus meshes of
2,000 triangles, in metres. It prints the median time of a full check with
method ``points`` and ``exact`` (with :func:`check_state`, and with a
:class:`~cablecheck.checker.interference.Checker` reused across calls as a simulation
loop would, the parts prepared once), where the time goes, and the same close-pair
queries done by python-fcl (a general collision library) in the same run when
it is installed, with the ratio. It also counts the false alarms of the
paper's face-plane distance (``face_plane=True``) against true surface
distance on the same scene.

It also times MuJoCo's ``mj_collision`` on the same capsules (one per
cable element, radius r, margin the clearance) and parts, interleaved call
by call with the checker's ``points`` check so both see the same load
(``--no-mujoco`` skips it).

Run: ``python benchmarks/bench_checker.py [--repeat N] [--no-fcl] [--no-mujoco]``. Timings
are single-threaded (set OMP/BLAS threads to 1 for a fair number).

The scene lives in :mod:`cablecheck.bench.scenes` and the fcl queries in
:mod:`cablecheck.bench.fcl` (shared with ``cablecheck bench``, which prints the full
accuracy-and-cost tables).

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

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from cablecheck.bench.fcl import FclMissing, fcl_queries, load_fcl  # noqa: E402
from cablecheck.bench.scenes import make_scene  # noqa: E402
from cablecheck.checker.interference import Checker, check_state  # noqa: E402
from cablecheck.checker.records import PairType  # noqa: E402
from cablecheck.checker.scene_state import CheckConfig  # noqa: E402
from cablecheck.checker.shapes import ShapeType  # noqa: E402


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


def mujoco_model(cables, parts, margin: float):
    """The same scene for MuJoCo: every cable a free body of capsules (one
    per element, so MuJoCo tests cable-part and cable-cable pairs, not a
    cable against itself), every part a world geom (a mesh as MuJoCo collides
    it: its convex hull), every geom with `margin` (contacts within the
    clearance, as the checker reports pairs within it)."""
    import mujoco

    def num(x):
        return " ".join(f"{v:.17g}" for v in np.ravel(x))

    sizes = {ShapeType.BOX: 3, ShapeType.SPHERE: 1, ShapeType.CYLINDER: 2, ShapeType.CAPSULE: 2,
             ShapeType.ELLIPSOID: 3}
    assets, geoms, meshes = [], [], {}
    for part in parts:
        sh, pose = part.shape, part.pose
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(pose[:3, :3]).ravel())
        where = f'pos="{num(pose[:3, 3])}" quat="{num(quat)}" margin="{margin}"'
        if sh.type is ShapeType.MESH:
            if id(sh) not in meshes:
                meshes[id(sh)] = f"mesh{len(meshes)}"
                assets.append(f'<mesh name="{meshes[id(sh)]}" vertex="{num(sh.vertices)}"/>')
            geoms.append(f'<geom type="mesh" mesh="{meshes[id(sh)]}" {where}/>')
        else:
            geoms.append(f'<geom type="{sh.type.value}" size="{num(sh.size[:sizes[sh.type]])}" {where}/>')
    bodies = []
    for c in cables:
        caps = "".join(f'<geom type="capsule" size="{c.radius}" fromto="{num(np.r_[a, b])}" margin="{margin}"/>'
                       for a, b in zip(c.points[:-1], c.points[1:]))
        bodies.append(f'<body name="{c.name}"><freejoint/>{caps}</body>')
    return mujoco.MjModel.from_xml_string(
        f'<mujoco><asset>{"".join(assets)}</asset><worldbody>{"".join(geoms)}{"".join(bodies)}</worldbody></mujoco>')


def side_by_side_mujoco(cables, parts, config, repeat):
    """Seconds (min, median) of a reused Checker's check and of MuJoCo's
    mj_collision on the same capsules and parts, interleaved call by call
    (so both see the same machine load), and MuJoCo's contact count."""
    import mujoco

    model = mujoco_model(cables, parts, config.clearance)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    checker = Checker(parts, config)
    poses = np.array([p.pose for p in parts])
    checker.check(cables, poses)
    mujoco.mj_collision(model, data)
    tc, tm = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        checker.check(cables, poses)
        t1 = time.perf_counter()
        mujoco.mj_collision(model, data)
        t2 = time.perf_counter()
        tc.append(t1 - t0)
        tm.append(t2 - t1)
    return (min(tc), float(np.median(tc))), (min(tm), float(np.median(tm))), int(data.ncon)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--no-fcl", action="store_true")
    ap.add_argument("--profile", action="store_true", help="print where the time goes")
    ap.add_argument("--no-mujoco", action="store_true", help="skip the mj_collision comparison")
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
    if not args.no_mujoco:
        (c_min, c_med), (m_min, m_med), ncon = side_by_side_mujoco(cables, parts, CheckConfig("points"),
                                                                   max(args.repeat, 15))
        print(f"side by side (interleaved): points {c_min * 1e3:.2f} ms (median {c_med * 1e3:.2f}), MuJoCo "
              f"mj_collision on the same {n_pts - len(cables)} capsules and {len(parts)} parts "
              f"{m_min * 1e3:.2f} ms (median {m_med * 1e3:.2f}, {ncon} contacts); points / mj_collision = "
              f"{c_min / m_min:.2f} (min), {c_med / m_med:.2f} (median)")
    # The paper's face-plane distance against true distance on the same scene.
    t_fp, _, out_fp = time_check(cables, parts, CheckConfig(method="points", face_plane=True), 3)
    true_pairs = {(r.type, r.a, r.b) for r in results["points"][1] if r.type is PairType.CABLE_STRUCTURE}
    fp_pairs = {(r.type, r.a, r.b) for r in out_fp if r.type is PairType.CABLE_STRUCTURE}
    print(f"face-plane |BP.N|: {len(fp_pairs)} cable-structure pairs vs {len(true_pairs)} true; "
          f"false alarms {len(fp_pairs - true_pairs)}, misses {len(true_pairs - fp_pairs)}")
    if not args.no_fcl:
        try:
            load_fcl()
        except FclMissing as e:
            print(f"{e}; no comparison")
            return
        for method in ("points", "exact"):
            upd, qry, n_found = fcl_queries(cables, parts, CheckConfig(method=method), args.repeat)
            ours = results[method][0]
            print(f"fcl {method:>6}: update {upd * 1e3:8.2f} ms + pair query {qry * 1e3:8.2f} ms "
                  f"= {(upd + qry) * 1e3:8.2f} ms ({n_found} touching pieces); checker is "
                  f"{(upd + qry) / ours:5.1f}x faster ({qry / ours:5.1f}x on the query alone)")


if __name__ == "__main__":
    main()
