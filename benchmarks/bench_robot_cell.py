"""The robot cell (scenes/robot_cell.toml) run with contact on: where the time goes.

A 7-axis arm as published (robosuite's Kinova Jaco: visual meshes with
``contype = conaffinity = 0`` beside collision meshes) on a table inside a
fence, dressed with two hoses clipped to the upper arm and the forearm,
running a 5 s pick-and-place. One run, recording on, gives side by side
(the report's ``timing``):

- check + validation + recording against MuJoCo's simulation time (the
  ratio the robot-cell target is set on), the same with the wear map
  (made from the check's records, a stage of its own in the report), and
  the real-time factor (simulated seconds per wall second);
- parts, pairs and events that come from the model's visual geoms (0 when
  the model is taken as it comes);
- hard events of a cable against a part riding the body one of its ends or
  clips is held by (its clamp's own link);
- agreement with MuJoCo's contacts and the disagreements' reasons;
- MuJoCo's own collision pass on the detection model (its CPU time, inside
  the validation stage): validation's floor, and the ratio check +
  validation + recording would reach were the rest of validation free, or
  were all our own work free (MuJoCo's collision pass alone);
- the real-time factor of the whole run, and how much of the run comes
  before its step loop (the report's ``loop_s``); with ``--serial`` the same run again on one thread
  (``RunOptions.overlap`` False: no simulation stepped ahead, ``cablecheck.run.ahead``)
  and the two runs' wall times side by side.

The stages are CPU seconds of the thread that ran them (the report's
``timing``), so the ratio does not depend on whether they overlapped.

``--profile`` adds the functions where the run spends most of its time
(cProfile, cumulative; it profiles the checking thread only). ``--duration``
shortens the run (the example is 5 s).

Run: python benchmarks/bench_robot_cell.py [--duration S] [--profile] [--serial] [--out DIR]
"""

from __future__ import annotations

import argparse
import cProfile
import dataclasses
import pstats
import tempfile
from collections import Counter
from pathlib import Path

from cablecheck.build.stages import build
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import load_scene

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "robot_cell.toml"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=None, help="simulated seconds (default: the scene's)")
    ap.add_argument("--profile", action="store_true", help="print the top functions by cumulative time")
    ap.add_argument("--out", type=Path, default=None, help="folder for report.json and cell.rrd")
    ap.add_argument("--serial", action="store_true",
                    help="run it again on one thread and compare the two runs' wall times")
    args = ap.parse_args(argv)

    scene = load_scene(SCENE)
    if args.duration is not None:
        scene = dataclasses.replace(scene, duration=args.duration)
    out = args.out or Path(tempfile.mkdtemp(prefix="bench_robot_cell_"))
    out.mkdir(parents=True, exist_ok=True)

    built = build(scene, detect=False)
    from cablecheck.build.drawn import DrawnLoad
    visual_names = {v.name for v in DrawnLoad(scene).result()}
    part_names = [p.name for p in built.parts]
    held = {(c.name, a.body) for c in built.cables for a in c.attachments}
    body_of = {p.name: p.body for p in built.parts}

    profiler = cProfile.Profile() if args.profile else None
    if profiler:
        profiler.enable()
    report = run_scene(scene, RunOptions(report=out / "report.json", record=out / "cell.rrd"))
    if profiler:
        profiler.disable()

    t = report["timing"]
    # all our work at the steps: the check, the wear map made from its records, validation, recording
    overhead = t["check_s"] + t["wear_s"] + t["validate_s"] + t["record_s"]
    duration = report["settings"]["t_end"]
    events = report["events"]
    from_visual = [e for e in events if e["a"] in visual_names or e["b"] in visual_names]
    pairs_visual = [p for p in report.get("pairs", []) if p.get("a") in visual_names or p.get("b") in visual_names]
    clamp_hard = [e for e in events if e["severity"] == "hard" and (e["a"], body_of.get(e["b"])) in held]
    v = report["validation"]
    adv = report["settings"]["advance"]

    print(f"robot cell: {len(part_names)} parts ({len(visual_names)} visual geoms drawn, not checked), "
          f"{len(built.cables)} cables, {duration:g} s simulated, {report['settings']['checked_steps']} steps checked "
          f"({adv['full_checks']} in full)")
    print(f"  MuJoCo simulation       {t['sim_s']:8.2f} s  ({t['sim_ms_per_step']:.2f} ms/step)")
    print(f"  check                   {t['check_s']:8.2f} s  ({t['check_ms_per_step']:.2f} ms/step)")
    print(f"  validation (MuJoCo)     {t['validate_s']:8.2f} s  ({t['validate_ms_per_step']:.2f} ms/step)")
    print(f"  wear map                {t['wear_s']:8.2f} s  ({t['wear_ms_per_step']:.2f} ms/step)")
    print(f"  recording               {t['record_s']:8.2f} s  ({t['record_ms_per_step']:.2f} ms/step)")
    col, sim_s = t["validate_collision_s"], max(t["sim_s"], 1e-12)
    print(f"  of validation, MuJoCo's collision pass (detection model): {col:.2f} s "
          f"({t['validate_collision_ms_per_step']:.2f} ms/step) = {col / sim_s:.2f} of the "
          f"simulation (validation's floor); the rest, ours: {t['validate_s'] - col:.2f} s")
    print(f"  check + validation + recording / simulation = {(overhead - t['wear_s']) / sim_s:.2f} (target <= 1); "
          f"with the wear map, check + wear map + validation + recording / simulation = {overhead / sim_s:.2f}")
    print(f"  with validation at its floor: (check + wear map + MuJoCo's collision pass + recording) / simulation = "
          f"{(t['check_s'] + t['wear_s'] + col + t['record_s']) / sim_s:.2f}; "
          f"MuJoCo's collision pass alone / simulation = {col / sim_s:.2f}")
    print(f"  real-time factor = {duration / t['total_s']:.3f} (simulated s per wall s, building and settling "
          f"included; target >= 1): {t['total_s']:.2f} s, of which {t['total_s'] - t['loop_s']:.2f} s before the "
          f"step loop (building; the simulation settles and steps on its thread meanwhile)")
    if args.serial:
        one = run_scene(scene, RunOptions(report=out / "serial.json", record=out / "serial.rrd", overlap=False))
        t1 = one["timing"]
        print(f"  on one thread (nothing simulated ahead): whole run {t1['total_s']:.2f} s against "
              f"{t['total_s']:.2f} s, {t1['total_s'] / t['total_s']:.2f}x as long; "
              f"its (check + validation + recording) / simulation = "
              f"{(t1['check_s'] + t1['validate_s'] + t1['record_s']) / max(t1['sim_s'], 1e-12):.2f}, "
              f"with the wear map "
              f"{(t1['check_s'] + t1['wear_s'] + t1['validate_s'] + t1['record_s']) / max(t1['sim_s'], 1e-12):.2f}")
    print(f"  parts from visual geoms: {len(set(part_names) & visual_names)}, pairs: {len(pairs_visual)}, "
          f"events: {len(from_visual)} (target 0)")
    print(f"  hard events against a clamp's own link: {len(clamp_hard)} (target 0)"
          + "".join(f"\n    {e['a']} / {e['b']} worst {e['min_distance']:.4g} at t {e['t_worst']:.3f} s"
                    for e in clamp_hard))
    print(f"  agreement with MuJoCo: {100 * v['agreement']:.2f} % of {v['pair_steps']} (step, pair) "
          f"classifications (target >= 98 %); disagreements by reason: {dict(v.get('reasons', {}))}")
    kinds = Counter((e["severity"], e["type"]) for e in events)
    print(f"  events: {dict(kinds)}")
    for e in events:
        print(f"    {e['severity']:4s} {e['phase']:7s} {e['type']:15s} {e['a']} / {e['b']}: "
              f"t {e['t_start']:.3f}-{e['t_end']:.3f} s, worst {e['min_distance']:.4g}")
    print(f"  report: {out / 'report.json'}  recording: {out / 'cell.rrd'}")
    if profiler:
        print("\nwhere the time goes (cProfile, cumulative):")
        pstats.Stats(profiler).sort_stats("cumulative").print_stats(25)


if __name__ == "__main__":
    main()
