"""MuJoCo's collision pass on the robot cell's detection model: concave meshes
as their own surface (sim.detection_mesh) against MuJoCo's convex hulls.

The same simulated states (every `--every`-th step of the robot cell after
settling) go through the detection model's collision pass (mj_kinematics,
mj_flex, mj_collision, the contacts copied out: `Simulation.collide_many`,
a batch of 32 states at a time) three times, side by side in one run: with
the meshes left to MuJoCo's convex hulls; as built, each non-convex
collision mesh a rigid flex of its triangles, every surface in every pass;
and as a run does it, the surfaces no cable can reach at a state left out
(`sim.surfacereach`; the contacts must be the same, and are checked).
Printed: ms per state for each (CPU time of this process, best of
`--repeat`), the ratios, contacts per state, and the (cable, part) pairs
each sees within the clearance.

Run: python benchmarks/bench_detection_mesh.py [--states N] [--every K]
"""

from __future__ import annotations

import argparse
import time
from collections import Counter
from pathlib import Path
from unittest import mock

import numpy as np

import sim.mjspec
from sim.build import build
from sim.loop import Simulation
from sim.scene import load_scene

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "robot_cell.toml"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--states", type=int, default=200, help="states timed (default 200)")
    ap.add_argument("--every", type=int, default=10, help="take every K-th step (default 10)")
    ap.add_argument("--repeat", type=int, default=3, help="best of R passes (default 3)")
    args = ap.parse_args(argv)

    scene = load_scene(SCENE)
    surfaces = build(scene)
    with mock.patch.object(sim.mjspec, "add_surfaces", lambda spec, model, cable_bit: model):
        hulls = build(scene)
    run = Simulation(surfaces)
    run.reset()
    run.settle()
    states = []
    for i, state in enumerate(run.steps(contacts=False)):
        if i % args.every == 0:
            states.append(state.qpos.copy())
        if len(states) >= args.states:
            break
    flexes = surfaces.detect.nflex - hulls.detect.nflex
    triangles = int(surfaces.detect.flex_elemnum[hulls.detect.nflex:].sum())
    print(f"robot cell: {len(states)} states, {flexes} concave meshes as surfaces ({triangles} triangles)")
    rows, found = {}, {}
    for label, built, reach in (("hulls", hulls, True), ("surfaces, every one", surfaces, False),
                                ("surfaces, in reach", surfaces, True)):
        detector = Simulation(built, reach=reach)
        best = np.inf
        for _ in range(args.repeat):
            t0 = time.process_time()
            raws = [r for k in range(0, len(states), 32) for r in detector.collide_many(states[k:k + 32])]
            best = min(best, time.process_time() - t0)
        named = detector.read_many(raws)
        near = Counter(pair for c in named for pair in set(zip(c.a, c.b)))
        rows[label] = best / len(states)
        found[label] = [sorted(zip(r.flex.tolist(), r.geom.tolist(), r.elem.tolist(), r.dist.tolist())) for r in raws]
        print(f"  {label:19s} {1e3 * rows[label]:7.3f} ms/state, {np.mean([len(r.dist) for r in raws]):6.1f} "
              f"contacts/state; pairs within the clearance (states): {dict(near)}")
    same = found["surfaces, every one"] == found["surfaces, in reach"]
    print(f"  surfaces / hulls = {rows['surfaces, every one'] / rows['hulls']:.1f}x every one, "
          f"{rows['surfaces, in reach'] / rows['hulls']:.1f}x in reach; in reach / every one = "
          f"{rows['surfaces, in reach'] / rows['surfaces, every one']:.2f}; same contacts: {same}")


if __name__ == "__main__":
    main()
