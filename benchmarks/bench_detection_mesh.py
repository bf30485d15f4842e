"""MuJoCo's collision pass on the robot cell's detection model: concave meshes
as their own surface (cablecheck.detection.mesh) against MuJoCo's convex hulls.

The same simulated states (every `--every`-th step of the robot cell after
settling) go through the detection model's collision pass (mj_kinematics,
mj_flex, mj_collision, the contacts copied out: `Detector.collide_many`,
a batch of 32 states at a time) four times, side by side in one run: with
the meshes left to MuJoCo's convex hulls; as built, each non-convex
collision mesh rigid flexes of its triangles, every surface in every pass;
each mesh one flex, those no cable can reach at a state left out of its
pass; and as a run does it, each mesh in patches, the patches no cable can
reach left out (`cablecheck.detection.surfacereach`; the contacts of the last three must be
the same, and are checked by name). Printed: ms per state for each (CPU
time of this process, best of `--repeat`), the ratios, contacts per
state, and the (cable, part) pairs each sees within the clearance.

Run: python benchmarks/bench_detection_mesh.py [--states N] [--every K]
"""

from __future__ import annotations

import argparse
import time
from collections import Counter
from pathlib import Path
from unittest import mock

import numpy as np

import cablecheck.build.mjspec
import cablecheck.detection.mesh
from cablecheck.build.stages import build
from cablecheck.detection.detector import Detector
from cablecheck.run.loop import Simulation
from cablecheck.scene.load import load_scene

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "robot_cell.toml"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--states", type=int, default=200, help="states timed (default 200)")
    ap.add_argument("--every", type=int, default=10, help="take every K-th step (default 10)")
    ap.add_argument("--repeat", type=int, default=3, help="best of R passes (default 3)")
    args = ap.parse_args(argv)

    scene = load_scene(SCENE)
    surfaces = build(scene)
    with mock.patch.object(cablecheck.build.mjspec, "add_surfaces", lambda spec, like, cable_bit: []):
        hulls = build(scene)
    with mock.patch.object(cablecheck.detection.mesh, "PATCH_TRIANGLES", 10 ** 9):
        whole = build(scene)
    run = Simulation(surfaces)
    run.reset()
    run.settle()
    states = []
    for i, state in enumerate(run.steps(contacts=False)):
        if i % args.every == 0:
            states.append(state.qpos.copy())
        if len(states) >= args.states:
            break
    meshes = whole.detect.nflex - hulls.detect.nflex
    patches = surfaces.detect.nflex - hulls.detect.nflex
    triangles = int(surfaces.detect.flex_elemnum[hulls.detect.nflex:].sum())
    print(f"robot cell: {len(states)} states, {meshes} concave meshes as surfaces ({triangles} triangles, "
          f"{patches} patches of at most {cablecheck.detection.mesh.PATCH_TRIANGLES})")
    rows, found = {}, {}
    for label, built, reach in (("hulls", hulls, True), ("surfaces, every one", surfaces, False),
                                ("whole meshes in reach", whole, True), ("patches in reach", surfaces, True)):
        detector = Detector(built, reach=reach)
        best = np.inf
        for _ in range(args.repeat):
            t0 = time.process_time()
            raws = [r for k in range(0, len(states), 32) for r in detector.collide_many(states[k:k + 32])]
            best = min(best, time.process_time() - t0)
        named = detector.read_many(raws)
        near = Counter(pair for c in named for pair in set(zip(c.a, c.b)))
        rows[label] = best / len(states)
        found[label] = [sorted(zip(c.kind.tolist(), c.a.tolist(), c.b.tolist(), c.elem_a.tolist(),
                                   c.dist.tolist(), map(tuple, c.pos.tolist()))) for c in named]
        print(f"  {label:21s} {1e3 * rows[label]:7.3f} ms/state, {np.mean([len(r.dist) for r in raws]):6.1f} "
              f"contacts/state; pairs within the clearance (states): {dict(near)}")
    every = rows["surfaces, every one"]
    same = found["surfaces, every one"] == found["whole meshes in reach"] == found["patches in reach"]
    print(f"  surfaces / hulls = {every / rows['hulls']:.1f}x every one, "
          f"{rows['whole meshes in reach'] / rows['hulls']:.1f}x whole meshes in reach, "
          f"{rows['patches in reach'] / rows['hulls']:.1f}x patches in reach; / every one = "
          f"{rows['whole meshes in reach'] / every:.2f} whole meshes, {rows['patches in reach'] / every:.2f} "
          f"patches; same contacts: {same}")


if __name__ == "__main__":
    main()
