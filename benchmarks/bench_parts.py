"""Part-part checks step after step: assembly-box pruning on and off, side by side.

The scene is the sweep benchmark's generated assembly of ``benchmarks/bench_sweep.py``
(:func:`bench_sweep.generate`, 2,101 parts in mm: 21 lines x 10 cells x 10
boxes and hexagonal prisms, ``plant/lineNN/cellK/partK``) with a few parts
moving, each on its own rigid body: the mover travels 5,000 mm along +x
through the middle line (touching, grazing and overlapping parts on its
way) and four plant parts in other lines wobble across y and z. Everything
else is one static body, so its pairs are checked once, at the first step.

Two :class:`cablecheck.checker.parts.PartChecker` run the same steps: one pairs part
boxes through the assembly boxes (``assemblies=True``, the default: lines
whose boxes, grown by the clearance, do not overlap contribute no pairs),
one with a single sort and sweep over all part boxes (``assemblies=False``).
Both are timed at every step (interleaved, so both see the same machine),
their records are compared (must be identical) and the candidate-pair stage
(:func:`cablecheck.checker.parts.candidate_pairs`, where the two differ) is timed on its
own.

Run: python benchmarks/bench_parts.py [--steps N] [--clearance MM] [--seed S]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from bench_sweep import TRAVEL, generate

from cablecheck.checker.parts import PartChecker, candidate_pairs
from cablecheck.checker.partset import PartSet

WOBBLERS = ("plant/line03/cell2/part4", "plant/line08/cell5/part0",
            "plant/line13/cell7/part6", "plant/line17/cell9/part9")


def scene(seed: int):
    """(parts, rest poses (P, 4, 4), moving indices)."""
    names, shapes, poses, _ = generate(seed)
    moving = [0] + [names.index(n) for n in WOBBLERS]
    groups = ["plant"] * len(names)
    for k, i in enumerate(moving):
        groups[i] = f"moving{k}"
    return PartSet.build(names, shapes, groups=groups, tolerance=0.125), poses, np.array(moving)


def step_poses(rest: np.ndarray, moving: np.ndarray, t: float) -> np.ndarray:
    """Poses at time t in [0, 1]."""
    p = rest.copy()
    p[moving[0], 0, 3] += TRAVEL * t
    for k, i in enumerate(moving[1:]):
        p[i, 1, 3] += 60.0 * np.sin(2 * np.pi * (t + 0.25 * k))
        p[i, 2, 3] += 60.0 * np.cos(2 * np.pi * (t + 0.25 * k))
    return p


def _key(records) -> list:
    return [(r.type.value, r.a, r.b, r.severity.value, r.min_distance, tuple(np.round(r.where, 9)))
            for r in records]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--clearance", type=float, default=1.0, help="mm")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    t0 = time.perf_counter()
    parts, rest, moving = scene(args.seed)
    build = time.perf_counter() - t0
    checkers = {False: PartChecker(parts, args.clearance, assemblies=False),
                True: PartChecker(parts, args.clearance, assemblies=True)}
    times: dict[bool, list[float]] = {False: [], True: []}
    stage: dict[bool, list[float]] = {False: [], True: []}
    first: dict[bool, float] = {}
    counts = []
    same = True
    for s in range(args.steps + 1):
        poses = step_poses(rest, moving, s / args.steps)
        got = {}
        for flag in ((False, True) if s % 2 else (True, False)):
            c = time.perf_counter()
            got[flag] = checkers[flag].check(poses)
            dt = time.perf_counter() - c
            if s == 0:
                first[flag] = dt
            else:
                times[flag].append(dt)
        same &= _key(got[False]) == _key(got[True])
        counts.append(len(got[True]))
        if s:
            placed = parts.place(poses)
            grp = checkers[True]._group
            for flag in (False, True):
                c = time.perf_counter()
                candidate_pairs(parts, placed, args.clearance, None,
                                lambda i, j: grp[i] != grp[j], flag)
                stage[flag].append(time.perf_counter() - c)
    print(f"scene: {len(parts.names)} parts ({len(parts.tris)} triangles, {len(parts.assemblies.names)} "
          f"assemblies), {len(moving)} moving, clearance {args.clearance:g} mm, {args.steps} steps "
          f"(+ the first, which also checks the static pairs); built in {build:.2f} s")
    print(f"records per step: {min(counts)} to {max(counts)}; identical with and without assembly "
          f"pruning at every step: {'yes' if same else 'NO'}")
    print(f"{'ms':<44}{'part boxes only':>16}{'assembly boxes':>16}{'ratio':>8}")
    rows = [("first check (all pairs)", [first[False]], [first[True]]),
            ("PartChecker.check per step, median", times[False], times[True]),
            ("PartChecker.check per step, best", [min(times[False])], [min(times[True])]),
            ("  candidate pairs stage per step, median", stage[False], stage[True])]
    for label, off, on in rows:
        a, b = 1e3 * statistics.median(off), 1e3 * statistics.median(on)
        print(f"{label:<44}{a:>16.2f}{b:>16.2f}{a / b:>7.1f}x")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
