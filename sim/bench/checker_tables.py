"""The checker's own bench tables, on randomised scenes (`cablecheck.bench.scenes`):
accuracy against exact geometry (``discretisation``), growth with cables
and parts (``scale``) and the discrete-point paper's cases (``paper``).

The sizes come from a `BenchSizes` (`cablecheck.bench.command`). Nothing here simulates
(`cablecheck.bench.sim_tables` holds the tables that run MuJoCo) or asserts a time.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from cablecheck.bench.scenes import RADIUS, make_scene
from cablecheck.bench.table import Table, median_time
from cablecheck.checker.interference import Checker
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import CheckConfig

if TYPE_CHECKING:   # the sizes live with the bench that orders the tables
    from cablecheck.bench.command import BenchSizes

PAPER_CABLE_CABLE_S = (0.008, 6.3)
PAPER_CABLE_STRUCTURE_S = (0.24, 12.4)
"""The discrete-point paper's reported range of check times (2016 desktop), seconds."""

SCALE_POINTS = 200
"""Body centres per cable in the scale and paper scenes."""

_DISTANCE_TYPES = (PairType.SELF, PairType.CABLE_CABLE, PairType.CABLE_STRUCTURE, PairType.KEEPOUT)

_CONFIGS = (
    ("points 4r", CheckConfig("points", 4.0)),
    ("points 2r", CheckConfig("points", 2.0)),
    ("points r", CheckConfig("points", 1.0)),
    ("points r/2", CheckConfig("points", 0.5)),
    ("face-plane 2r", CheckConfig("points", 2.0, face_plane=True)),
    ("exact", CheckConfig("exact")),
)
"""The configurations the discretisation table compares with the exact method."""


def _pairs(records) -> dict:
    return {(r.type, r.a, r.b): r.min_distance for r in records if r.type in _DISTANCE_TYPES}


def _compare(ref: dict, got: dict) -> tuple[int, int, int, float]:
    """(missed hard, missed any, false alarms, worst |distance error| on shared pairs)."""
    missed_hard = sum(1 for k, d in ref.items() if d < 0 and not (k in got and got[k] < 0))
    missed = sum(1 for k in ref if k not in got)
    false = sum(1 for k, d in got.items() if k not in ref or (d < 0 <= ref[k]))
    shared = [abs(got[k] - ref[k]) for k in got if k in ref]
    return missed_hard, missed, false, (max(shared) if shared else 0.0)


def discretisation_table(sizes: BenchSizes) -> Table:
    """Spacing and method against the exact method on randomised scenes."""
    n_seeds = sizes.disc_scenes
    repeat = sizes.repeat
    r = RADIUS
    # Elements 6r long, so that spacing 4r, 2r, r and r/2 all insert points.
    scenes = [make_scene(seed=1000 + s, n_cables=12, n_points=40, n_prims=40, n_meshes=2,
                         room=(0.4, 0.4, 0.25), step=6 * r) for s in range(n_seeds)]
    # elements 4r; the full size is 100 cables (10,000 body centres)
    large = make_scene(seed=0, n_cables=sizes.large_cables, n_points=100, step=4 * r)
    n_large = sum(len(c.points) for c in large[0])
    refs = [_pairs(Checker(parts, CheckConfig("exact")).check(cables)) for cables, parts in scenes]
    table = Table("discretisation", "Discretisation: accuracy against exact geometry, time per check",
                  ["config", "spacing_r", "ms_per_check", "ms_large", "pairs", "ref_pairs",
                   "ref_hard", "missed_hard", "missed", "false_alarms", "worst_error_mm"])
    for label, cfg in _CONFIGS:
        tot = [0, 0, 0, 0]
        worst = 0.0
        n_pairs = 0
        secs = 0.0
        for (cables, parts), ref in zip(scenes, refs):
            checker = Checker(parts, cfg)
            got = _pairs(checker.check(cables))
            mh, m, fa, err = _compare(ref, got)
            tot[0] += mh
            tot[1] += m
            tot[2] += fa
            worst = max(worst, err)
            n_pairs += len(got)
            secs += median_time(lambda: checker.check(cables), repeat)
        big = Checker(large[1], cfg)
        t_large = median_time(lambda: big.check(large[0]), max(2, repeat // 2))
        table.add(label, cfg.spacing if cfg.method == "points" else None, 1e3 * secs / len(scenes),
                  1e3 * t_large, n_pairs, sum(len(x) for x in refs),
                  sum(1 for x in refs for d in x.values() if d < 0), tot[0], tot[1], tot[2], 1e3 * worst)
    # The reference itself against dense points: points only over-estimate a
    # distance (they sample the centreline), so dense points bound it from above.
    dense = CheckConfig("points", 0.125)
    dmax = 0.0
    below = 0.0
    for (cables, parts), ref in zip(scenes, refs):
        got = _pairs(Checker(parts, dense).check(cables))
        for k in set(got) & set(ref):
            dmax = max(dmax, abs(got[k] - ref[k]))
            below = max(below, ref[k] - got[k])
    n_body = sum(len(c.points) for cables, _ in scenes for c in cables)
    table.notes += [
        f"{n_seeds} randomised scenes of 12 cables x 40 body centres (elements 6r, r = {r * 1e3:g} mm) and "
        f"40 primitives + 2 meshes in a 0.4 x 0.4 x 0.25 m box ({n_body} body centres in all); "
        "clearance 5 mm; pairs = self, cable-cable, cable-structure and keep-out pairs below the clearance.",
        "reference: method exact (segment distances to capsules and part surfaces); "
        f"dense points at r/8 agree with it within {dmax * 1e3:.3g} mm "
        f"(never below it by more than {max(below, 0.0) * 1e3:.2g} mm).",
        f"ms_large: the same configuration on a {len(large[0])}-cable scene of {n_large} body centres "
        f"(elements 4r) against {len(large[1])} parts.",
        "missed: reference pairs a configuration does not report; false alarms: pairs it reports that "
        "the reference does not, or hard where the reference is not.",
    ]
    return table


def _fit_exponent(x: Sequence[float], y: Sequence[float]) -> float:
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])


def _scene_for(n_cables: int, n_parts: int, seed: int = 0):
    n_meshes = max(1, round(n_parts / 31))
    return make_scene(seed=seed, n_cables=n_cables, n_points=SCALE_POINTS, n_prims=n_parts - n_meshes,
                      n_meshes=n_meshes)


def scale_table(sizes: BenchSizes) -> Table:
    """Time per check as cables and parts grow (each axis with the other held)."""
    repeat = sizes.repeat
    table = Table("scale", f"Scale: time per check against cables and parts ({SCALE_POINTS} body "
                           "centres per cable)",
                  ["axis", "cables", "points", "parts", "ms_points", "ms_exact", "us_per_point_points",
                   "us_per_point_exact"])
    fits = {}
    for axis, values in (("cables", sizes.scale_cables), ("parts", sizes.scale_parts)):
        xs, tp, te = [], [], []
        for v in values:
            cables, parts = (_scene_for(v, sizes.scale_held_parts) if axis == "cables"
                             else _scene_for(sizes.scale_held_cables, v))
            n_pts = sum(len(c.points) for c in cables)
            cp, ce = Checker(parts, CheckConfig("points")), Checker(parts, CheckConfig("exact"))
            t_p = median_time(lambda: cp.check(cables), repeat)
            t_e = median_time(lambda: ce.check(cables), repeat)
            table.add(axis, len(cables), n_pts, len(parts), 1e3 * t_p, 1e3 * t_e, 1e6 * t_p / n_pts,
                      1e6 * t_e / n_pts)
            xs.append(n_pts if axis == "cables" else len(parts))
            tp.append(t_p)
            te.append(t_e)
        # Growth fitted from the second value up (one cable or ten parts is mostly fixed cost).
        fits[axis] = (_fit_exponent(xs[1:], tp[1:]), _fit_exponent(xs[1:], te[1:]))
    cables, parts = sizes.scale_cables, sizes.scale_parts
    table.notes += [
        f"fitted exponent of time against points ({cables[1]} to {cables[-1]} cables, "
        f"{sizes.scale_held_parts} parts): points {fits['cables'][0]:.2f}, exact {fits['cables'][1]:.2f} "
        "(1 = linear).",
        f"fitted exponent of time against parts ({parts[1]:,} to {parts[-1]:,} parts, "
        f"{sizes.scale_held_cables} cables): points {fits['parts'][0]:.2f}, exact {fits['parts'][1]:.2f}; "
        "the cable-cable work is a fixed share.",
        "parts: one torus mesh (2,000 triangles) per 31 parts, the rest primitives, in a 2 x 2 x 1 m room.",
    ]
    return table


def paper_table(sizes: BenchSizes) -> Table:
    """The discrete-point paper's simple and complex cases in kind."""
    repeat = sizes.repeat
    table = Table("paper", "The discrete-point paper (Ju et al., 2016) in kind: our time per check beside the paper's",
                  ["case", "cables", "points", "parts", "cable_cable_s", "cable_structure_s",
                   "full_check_s", "paper_cable_cable_s", "paper_cable_structure_s"])
    for case, n_c, n_p in sizes.paper_cases:
        cables, parts = _scene_for(n_c, n_p, seed=3)
        cfg = CheckConfig("points")
        alone = Checker([], cfg)
        full = Checker(parts, cfg)
        t_cc = median_time(lambda: alone.check(cables), repeat)
        t_full = median_time(lambda: full.check(cables), repeat)
        table.add(case, len(cables), sum(len(c.points) for c in cables), len(parts), t_cc,
                  max(t_full - t_cc, 0.0), t_full, f"{PAPER_CABLE_CABLE_S[0]}-{PAPER_CABLE_CABLE_S[1]}",
                  f"{PAPER_CABLE_STRUCTURE_S[0]}-{PAPER_CABLE_STRUCTURE_S[1]}")
    table.notes += [
        f"method points at 2r, {SCALE_POINTS} body centres per cable; cable_cable_s: the check without "
        "parts (self and cable-cable); cable_structure_s: the full check minus that; this machine, one core.",
        "paper: 8 cases up to over 100 cables and over 200 parts on a 2016 desktop; its per-case "
        "sizes are not given, so the comparison is by range.",
    ]
    return table
