"""Time one full :func:`checker.interference.check_state` on a large scene.

The checker benchmark's scene: 100 cables of 200 points (20,000 points), 300 primitive
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

The scene lives in :mod:`sim.benchscene` and the fcl queries in
:mod:`sim.benchfcl` (shared with ``cablecheck bench``, which prints the full
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

from checker.interference import Checker, check_state  # noqa: E402
from checker.records import PairType  # noqa: E402
from checker.scene_state import CheckConfig  # noqa: E402
from checker.shapes import ShapeType  # noqa: E402
from sim.benchfcl import FclMissing, fcl_queries, load_fcl  # noqa: E402
from sim.benchscene import make_scene  # noqa: E402


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
