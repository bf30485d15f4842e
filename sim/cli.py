"""The `cablecheck` command line.

Subcommands:
  run SCENE   simulate a scene, check it, write the report and the recording.
  sweep SCENE move one part (or assembly) along a line; list the parts it hits.
  bench       measure what accuracy costs in time (tables, CSV and a plot).
  check SCENE validate a scene file without simulating it.
  study FILE  run the variants of a design study on a Dask cluster (`sim.study`,
              `sim.studyrun`); tabulate, plot and answer it.

Exit status: 0 when nothing reaches the `--fail-on` level, 1 when something
does, 2 for bad input (the message names the file, the key and the
problem; never a traceback), 130 when interrupted with Ctrl-C and 143 when
terminated with SIGTERM (the report, marked incomplete, and the recording are
still written). Output paths are checked before any work starts.

This module parses arguments, shows progress and prints summaries; the work
is done in `sim.run`.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

from sim.stop import StopRequest   # first: signals are taken before the heavy imports

EXIT_OK, EXIT_FAIL, EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_TERMINATED = 0, 1, 2, 130, 143

_DESCRIPTION = """\
Physics-backed interference checking for flexible cables and rigid parts.
A TOML scene describes parts, scripted bodies and cables; MuJoCo simulates the
cables sagging and following their ends, and every checked step is measured.
"""

_RUN_EPILOG = """\
outputs:
  recording  recordings/<scene name>.rrd unless --record/--no-record; open it
             with `rerun FILE`.
  report     JSON beside the recording (same name, .json) unless --report.
  Both are written atomically: an interrupted run (Ctrl-C) still leaves a
  readable recording and a report with "complete": false.

exit status:
  0  nothing reached the --fail-on level    1  something did
  2  bad input (file, key and problem are printed)
  130  interrupted (Ctrl-C)    143  terminated (SIGTERM)
"""


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive number: {text!r}")
    return value


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="cablecheck", description=_DESCRIPTION,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"%(prog)s {version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    chk = sub.add_parser("check", help="validate a scene file without simulating it",
                         description="Read and validate SCENE (and the files it names) as `run` "
                                     "would, print what it holds and exit: 0 when it is valid, 2 "
                                     "when it is not (the file, the key and the problem are printed).")
    chk.add_argument("scene", metavar="SCENE", type=Path, help="scene file (TOML)")
    chk.add_argument("--quiet", action="store_true", help="print nothing but errors")
    run = sub.add_parser("run", help="simulate and check a scene",
                         description="Simulate SCENE, check every step, write a report and a recording.",
                         epilog=_RUN_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    run.add_argument("scene", metavar="SCENE", type=Path, help="scene file (TOML)")
    run.add_argument("--report", type=Path, metavar="PATH",
                     help="JSON report path (default: beside the recording, .json)")
    rec = run.add_mutually_exclusive_group()
    rec.add_argument("--record", type=Path, metavar="PATH",
                     help="rerun recording path (default: recordings/<scene name>.rrd)")
    rec.add_argument("--no-record", action="store_true", help="do not write a recording")
    run.add_argument("--method", choices=("points", "exact"),
                     help="override [check] method: discrete points (paper) or exact segment distances")
    run.add_argument("--spacing", type=_positive_float, metavar="K",
                     help="override [check] spacing: discrete-point spacing in cable radii (paper: 2)")
    run.add_argument("--fail-on", choices=("hard", "soft", "never"), default="hard",
                     help="exit 1 when interference of this severity or worse is found (default: hard)")
    run.add_argument("--full-every-step", action="store_true",
                     help="run the full pairwise check on every checked step; by default (method "
                          "points) a step on which everything is proven clear since the last full "
                          "check, but the pairs already near the clearance, checks only those: the "
                          "same events, pairs and MuJoCo comparison, several times faster")
    run.add_argument("--quiet", action="store_true", help="print nothing but errors")
    run.add_argument("--only", metavar="PATH",
                     help="check only interference involving this assembly path (a part name or "
                          "prefix): its parts against the rest, and cables against its parts")
    sw = sub.add_parser("sweep", help="translational sweep: which parts a moving part hits",
                        description="Move --part (a part or assembly path) from its t = 0 pose along "
                                    "--direction by --distance (scene units); list every part it hits "
                                    "with the travel at first contact, and the parts it overlaps at the "
                                    "start. Exit status: 0 nothing hit or overlapping, 1 something is, "
                                    "2 bad input.")
    sw.add_argument("scene", metavar="SCENE", type=Path, help="scene file (TOML)")
    sw.add_argument("--part", required=True, metavar="NAME", help="part name or assembly path prefix")
    sw.add_argument("--direction", required=True, metavar="X,Y,Z", type=_direction,
                    help="direction of travel in scene axes (any length, not zero); "
                         "write --direction=-1,0,0 when it starts with a minus sign")
    sw.add_argument("--distance", required=True, metavar="H", type=_nonnegative_float,
                    help="travel in scene units")
    sw.add_argument("--report", type=Path, metavar="PATH",
                    help="JSON report path (default: recordings/<scene name>-sweep.json)")
    sw.add_argument("--precision", type=_positive_float, metavar="P",
                    help="precision in scene units (default 0.5 mm)")
    sw.add_argument("--only", metavar="PATH", help="test only the parts of this assembly path")
    sw.add_argument("--quiet", action="store_true", help="print nothing but errors")
    st = sub.add_parser("study", help="run the variants of a design study, locally or on a Dask cluster",
                        description="Vary a scene as STUDY.toml says ([[vary]] keys, a grid or zip of "
                                    "values), check every variant's scene, run the variants in parallel "
                                    "and write <out>/<name>/results.csv, study.json, study.png and each "
                                    "variant's report and recording under variants/<id>/. Exit status: 0 "
                                    "when no variant reaches --fail-on, 1 when one does (or failed), 2 "
                                    "for bad input, 130 when interrupted (finished variants are kept).")
    st.add_argument("study", metavar="STUDY", type=Path, help="study file (TOML)")
    where = st.add_mutually_exclusive_group()
    where.add_argument("--workers", type=_positive_int, metavar="N",
                       help="worker processes of the embedded local cluster (default: the number "
                            "of cores); it listens on 127.0.0.1 only")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="run on a running Dask scheduler instead, e.g. tcp://host:8786 "
                            "(the scene's files travel with the tasks)")
    st.add_argument("--out", type=Path, default=Path("recordings/studies"), metavar="DIR",
                    help="output folder; the study writes DIR/<name>/ (default: recordings/studies)")
    st.add_argument("--fail-on", choices=("hard", "soft", "never"), default="hard",
                    help="exit 1 when a variant has interference of this severity or worse "
                         "(default: hard)")
    st.add_argument("--no-record", action="store_true", help="write no recordings, reports only")
    st.add_argument("--quiet", action="store_true", help="print nothing but errors")
    bench = sub.add_parser("bench", help="what accuracy costs in time: tables, CSV and a plot",
                           description="Measure discretisation accuracy, physics resolution, scale, "
                                       "the checker beside python-fcl and MuJoCo's collision, and "
                                       "per-step cost of the example scenes; print the tables and "
                                       "write them as CSV plus bench.png into --out.")
    bench.add_argument("--quick", action="store_true", help="fewer scenes and repeats (under a minute)")
    bench.add_argument("--out", type=Path, default=Path("recordings/bench"), metavar="DIR",
                       help="output folder (default: recordings/bench)")
    return parser


def _nonnegative_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value >= 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a non-negative number: {text!r}")
    return value


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1: {text!r}")
    return value


def _direction(text: str) -> tuple[float, float, float]:
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y,Z numbers, got {text!r}") from None
    if len(values) != 3 or not all(abs(v) < float("inf") for v in values):
        raise argparse.ArgumentTypeError(f"expected three finite numbers X,Y,Z, got {text!r}")
    if not any(values):
        raise argparse.ArgumentTypeError(f"must not be the zero vector, got {text!r}")
    return values  # type: ignore[return-value]


class _ProgressBar:
    """A one-line progress display on stderr, redrawn at most 10 times a second."""

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self.tty = sys.stderr.isatty()
        self._last = 0.0
        self._shown = False
        self._last_pct = -1

    def __call__(self, stage: str, done: float, total: float) -> None:
        if not self.enabled or total <= 0:
            return
        frac = min(max(done / total, 0.0), 1.0)
        now = time.monotonic()
        if self.tty:
            if now - self._last < 0.1 and frac < 1.0:
                return
            self._last = now
            bar = "#" * int(30 * frac)
            label = "settling " if stage == "settle" else "simulating"
            sys.stderr.write(f"\r{label} [{bar:<30}] {100 * frac:5.1f}%")
            sys.stderr.flush()
            self._shown = True
        else:
            pct = int(frac * 4) * 25  # a line every quarter when not on a terminal
            if stage == "run" and pct != self._last_pct:
                self._last_pct = pct
                sys.stderr.write(f"simulating: {pct}%\n")

    def done(self) -> None:
        if self._shown:
            sys.stderr.write("\r" + " " * 60 + "\r")
            sys.stderr.flush()


def version() -> str:
    """The installed product version."""
    from importlib.metadata import PackageNotFoundError, version as dist_version

    try:
        return dist_version("cablecheck")
    except PackageNotFoundError:   # run from a source tree that was never installed
        return "unknown"


def _cmd_check(args: argparse.Namespace) -> int:
    from sim.scene import load_scene

    scene = load_scene(args.scene)
    if not args.quiet:
        steps = round(scene.duration / scene.timestep)
        print(f"{args.scene}: valid scene {scene.name!r} ({scene.units}): {len(scene.cables)} cable(s), "
              f"{len(scene.parts)} part(s), {len(scene.bodies)} scripted bod"
              f"{'y' if len(scene.bodies) == 1 else 'ies'}, {len(scene.motions)} motion(s)"
              + (f", on {scene.mjcf.name}" if scene.mjcf else "")
              + f"; {scene.duration:g} s in {steps} steps of {scene.timestep:g} s")
    return EXIT_OK


def _cmd_run(args: argparse.Namespace, stop: StopRequest) -> int:
    from sim.outputs import check_output
    from sim.scene import load_scene

    for option, path in (("--report", args.report), ("--record", args.record)):
        if path is not None:
            check_output(path, option)
    scene = load_scene(args.scene)
    record = None if args.no_record else (args.record or Path("recordings") / f"{scene.name}.rrd")
    report = args.report or (record or Path("recordings") / scene.name).with_suffix(".json")
    if record is not None and args.record is None:
        check_output(record, "recording (default path)")
    if args.report is None:
        check_output(report, "report (default path)")
    from sim.run import RunOptions, run_scene  # MuJoCo and rerun load only when needed

    options = RunOptions(report=report, record=record, method=args.method, spacing=args.spacing,
                         only=args.only, advance=not args.full_every_step)
    bar = _ProgressBar(enabled=not args.quiet)
    try:
        result = run_scene(scene, options, progress=bar, stop=stop,
                           warn=None if args.quiet else (lambda w: print(f"warning: {w}", file=sys.stderr)))
    finally:
        bar.done()
    if not args.quiet:
        _print_summary(result, report)
    if not result["complete"]:
        return EXIT_TERMINATED if result.get("interrupted") == "SIGTERM" else EXIT_INTERRUPTED
    return EXIT_FAIL if _fails(result, args.fail_on) else EXIT_OK


def _cmd_sweep(args: argparse.Namespace) -> int:
    from sim.sweep import SweepOptions, sweep_scene  # MuJoCo loads only when needed

    from sim.outputs import check_output
    from sim.scene import load_scene

    if args.report is not None:
        check_output(args.report, "--report")
    scene = load_scene(args.scene)
    report = args.report or Path("recordings") / f"{scene.name}-sweep.json"
    if args.report is None:
        check_output(report, "report (default path)")
    options = SweepOptions(part=args.part, direction=args.direction, distance=args.distance,
                           precision=args.precision, only=args.only, report=report)
    result = sweep_scene(scene, options)
    if not args.quiet:
        _print_sweep(result, report)
    return EXIT_FAIL if (result["hits"] or result["overlapping"]) else EXIT_OK


class _StudyBar:
    """Progress over a study's variants on stderr: a redrawn bar on a terminal, else a line per tenth."""

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self.tty = sys.stderr.isatty()
        self._tenth = -1

    def __call__(self, done: int, total: int, failed: int) -> None:
        if not self.enabled:
            return
        note = f", {failed} failed" if failed else ""
        if self.tty:
            bar = "#" * int(30 * done / total)
            sys.stderr.write(f"\rvariants [{bar:<30}] {done}/{total}{note}  ")
            sys.stderr.flush()
        elif 10 * done // total != self._tenth:
            self._tenth = 10 * done // total
            sys.stderr.write(f"variants: {done}/{total}{note}\n")

    def done(self) -> None:
        if self.enabled and self.tty:
            sys.stderr.write("\r" + " " * 70 + "\r")
            sys.stderr.flush()


def _cmd_study(args: argparse.Namespace, stop: StopRequest) -> int:
    from sim.bundle import make_bundle
    from sim.outputs import check_folder
    from sim.study import check_variants, load_study, variants
    from sim.studyresult import fails, length_window

    check_folder(args.out, "--out")
    study = load_study(args.study)
    folder = args.out / study.name
    check_folder(folder, "study folder (--out/<name>)")
    found = variants(study)
    scenes = check_variants(study, found)   # every variant's scene, before anything runs
    bundle, datas = make_bundle(study.scene_path, [v.data for v in found])
    from sim.studyplot import write_outputs
    from sim.studyrun import VariantTask, run_variants

    tasks = [VariantTask(id=v.id, data=d, record=not args.no_record) for v, d in zip(found, datas)]
    where = (f"the Dask scheduler at {args.scheduler}" if args.scheduler else
             f"{args.workers or os.cpu_count() or 1} local worker process(es)")
    if not args.quiet:
        print(f"study {study.name}: {len(tasks)} variant(s) of {study.scene_path} on {where}",
              flush=True)
    bar = _StudyBar(enabled=not args.quiet)
    try:
        rows, complete = run_variants(tasks, {v.id: v.values for v in found}, bundle, folder,
                                      workers=args.workers, scheduler=args.scheduler, stop=stop,
                                      progress=bar)
    finally:
        bar.done()
    units = scenes[0].units
    window = None
    if len(study.vary) == 1 and study.vary[0].path.endswith(".length") and \
            study.vary[0].path.startswith("cables[") and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) for x in study.vary[0].values):
        window = length_window(rows)
    settings = {"fail_on": args.fail_on, "record": not args.no_record,
                "cluster": args.scheduler or f"local, {args.workers or os.cpu_count() or 1} workers",
                "version": version()}
    paths = write_outputs(folder, study, rows, complete=complete, units=units, window=window,
                          settings=settings)
    if not args.quiet:
        _print_study(study, rows, units, window, complete, paths)
    if not complete:
        return EXIT_TERMINATED if stop.signal_name == "SIGTERM" else EXIT_INTERRUPTED
    return EXIT_FAIL if any(fails(r, args.fail_on) for r in rows) else EXIT_OK


def _print_study(study, rows, units: str, window, complete: bool, paths: dict) -> None:
    from sim.study import format_value
    from sim.studyresult import Status, free_of_hard

    def num(x, fmt=".4g"):
        return "-" if x is None else format(x, fmt)

    keys = [v.key for v in study.vary]
    values = [", ".join(format_value(x) for x in r.values) for r in rows]
    vw = max(len(" ; ".join(keys)), *(len(v) for v in values))
    print(f"  {'id':<4} {' ; '.join(keys):<{vw}}  {'hard':>4} {'soft':>4} {'worst':>9} "
          f"{'strain %':>8} {'bend':>8}  time s  status")
    for r, v in zip(rows, values):
        if r.status is Status.DONE:
            flags = "".join(f" {f}" for f, on in (("TAUT", r.taut), ("BEND", r.bend_violation)) if on)
            strain = None if r.max_strain is None else 100 * r.max_strain
            print(f"  {r.id:<4} {v:<{vw}}  {r.hard:>4} {r.soft:>4} {num(r.worst_distance):>9} "
                  f"{num(strain, '.2f'):>8} {num(r.min_bend_radius):>8}  {num(r.run_time_s, '6.1f'):>6}  "
                  f"done{flags}")
        else:
            print(f"  {r.id:<4} {v:<{vw}}  {r.status.value.upper()}: {r.error}")
    free = free_of_hard(rows)
    print(f"  free of hard events: {len(free)} of {len(rows)}"
          + (": " + "; ".join(f"{r.id} ({', '.join(format_value(x) for x in r.values)})"
                              for r in free) if free else ""))
    if window is not None and complete:
        key = study.vary[0].key
        if window.shortest is None:
            print(f"  {key}: every length tried was pulled taut; try longer")
        elif window.longest is None:
            print(f"  {key}: every length tried had hard contact or a bend violation")
        elif not window.exists:
            print(f"  {key}: no interference-free length: shortest not taut {window.shortest:g} {units}, "
                  f"longest without hard contact or bend violation {window.longest:g} {units}")
        else:
            lo = f" (taut at {window.below:g})" if window.below is not None else " (shortest tried)"
            hi = (f" (hard contact or bend violation at {window.above:g})" if window.above is not None
                  else " (longest tried)")
            print(f"  interference-free window of {key}: {window.shortest:g}{lo} to "
                  f"{window.longest:g} {units}{hi}")
            pool, kind = (window.quiet, "with no event at all") if window.quiet else \
                (window.clean, "neither taut nor in hard contact nor bent too tight")
            print(f"  recommended: {window.recommended:g} {units}: of the lengths tried {kind} "
                  f"({', '.join(f'{x:g}' for x in pool)}), the nearest to the window's middle")
    if not complete:
        print("  INTERRUPTED: the tables hold the variants that finished (the others: not run)")
    print(f"  results: {paths['csv']}  (also {paths['json'].name}, {paths['png'].name})")


def _print_sweep(r: dict, path: Path) -> None:
    u = r["units"]
    d = ", ".join(f"{x:.4g}" for x in r["direction"])
    print(f"{r['scene']}: sweep {r['part']!r} along ({d}) by {r['distance']:g} {u} "
          f"(precision {r['precision']:.3g} {u})")
    if r["hits"]:
        width = max(len(h["part"]) for h in r["hits"])
        print(f"  {'part':<{width}}  {'distance':>12}  where")
        for h in r["hits"]:
            w = _position(h["where"], u)
            print(f"  {h['part']:<{width}}  {h['distance']:>12.6g}  ({w})")
    else:
        print("  no part hit")
    if r["overlapping"]:
        print(f"  overlapping at the start: {', '.join(r['overlapping'])}")
    for w in r["warnings"]:
        print(f"  warning: {w}")
    print(f"  report: {path}")


POSITION_DECIMALS = {"mm": 2, "m": 5}
"""Decimals of printed positions: 10 um in either unit, wherever the scene
lies (``%g`` prints 1.235e+07 for a point 12.3 km out in mm)."""


def _position(values, units: str) -> str:
    """A position as fixed-point numbers at `POSITION_DECIMALS` for its units."""
    return ", ".join(f"{x:.{POSITION_DECIMALS.get(units, 5)}f}" for x in values)


def _fails(report: dict, level: str) -> bool:
    summary = report.get("summary", {})
    if level == "never":
        return False
    if level == "soft":
        return summary.get("hard", 0) + summary.get("soft", 0) > 0
    return summary.get("hard", 0) > 0


def _print_summary(report: dict, report_path: Path) -> None:
    units = report["units"]
    s = report["settings"]
    status = "complete" if report["complete"] else "INTERRUPTED (report marked incomplete)"
    print(f"{report['scene']}: {status}, {s['steps']} steps to t = {s['t_end']:.3f} s, "
          f"{s['checked_steps']} checked, method {s['method']}")
    for c in report["cables"]:
        bend = c["min_bend_radius"]
        flags = [f for f, on in (("TAUT", c["taut"]), ("BEND", c["bend_violation"])) if on]
        strain = c["max_strain"]
        print(f"  cable {c['name']}: length {c['length']:.4g} {units}, max strain "
              f"{round(100 * strain, 2) + 0.0:.2f} %, min bend radius "
              f"{'straight' if bend is None else f'{bend:.4g} {units}'}"
              + (f", max twist {c['max_twist']:.3g} deg" if c.get("max_twist") is not None else "")
              + (f"  [{', '.join(flags)}]" if flags else ""))
    _print_events(report)
    for c in report["cables"]:
        _print_wear(c["name"], c.get("wear"), units)
    v = report.get("validation")
    if v and not v["pair_steps"]:
        print(f"  MuJoCo cross-check: no cable pair came within the clearance on either side "
              f"({v['compared_steps']} steps compared)")
    elif v:
        print(f"  MuJoCo cross-check: {100 * v['agreement']:.2f} % of {v['pair_steps']} (step, pair) "
              f"classifications agree ({v['checker_only']} checker only, {v['mujoco_only']} MuJoCo only"
              + (f", {v['severity_differs']} differ in severity" if v.get("severity_differs") else "") + ")")
    adv = s.get("advance")
    if adv and adv["proven_clear_steps"]:
        full = adv["full_checks"]
        print(f"  full check on {full} of {s['checked_steps']} checked steps; on the others everything was "
              f"proven clear since the last one but the pairs already near the clearance, checked on "
              f"their own (--full-every-step checks every step in full)")
    if report.get("warnings"):
        print(f"  MuJoCo warnings: {report['warnings']}")
    for w in report.get("part_warnings", ()):
        print(f"  warning: {w}")
    t = report["timing"]
    print(f"  time {t['total_s']:.2f} s (simulation {t['sim_s']:.2f} s, checks {t['check_s']:.2f} s, "
          f"MuJoCo comparison {t['validate_s']:.2f} s, recording {t['record_s']:.2f} s)")
    print(f"  report: {report_path}")
    if report.get("recording"):
        print(f"  recording: {report['recording']}  (view: rerun {report['recording']})")


def _print_wear(cable: str, wear: dict | None, units: str) -> None:
    """The cable's most worn place (what it touches) and its most bent-back one."""
    if not wear:
        return
    worn = wear.get("most_worn")
    cycles = [float(x) for x in wear.get("bend_cycles", ())]
    parts = []
    if worn:
        parts.append(f"most worn at s = {worn['s']:.4g} {units} touching {worn['touches']}: "
                     f"in contact {worn['contact_time']:.3g} s, slid {worn['sliding']:.3g} {units}")
    if cycles and max(cycles) > 0:
        k = max(range(len(cycles)), key=cycles.__getitem__)
        parts.append(f"most bending cycles {cycles[k]:g} at s = {wear['s'][k]:.4g} {units}")
    if parts:
        print(f"  wear of {cable}: " + "; ".join(parts))


def _print_events(report: dict, most: int = 10) -> None:
    """Events worst first, at most `most` of them."""
    units = report["units"]
    summary, events = report["summary"], report["events"]
    if not events:
        print("  no interference")
        return
    print(f"  {len(events)} interference event(s): {summary['hard']} hard, {summary['soft']} soft; "
          f"{summary['static']} static, {summary['dynamic']} dynamic")
    for e in sorted(events, key=lambda e: (e["severity"] != "hard", e["min_distance"]))[:most]:
        pair = e["a"] if e["a"] == e["b"] else f"{e['a']} / {e['b']}"
        where = _position(e["where"], units)
        print(f"    {e['severity'].upper():4} {e['phase']:7} {e['type']:15} {pair}: "
              f"t {e['t_start']:.3f}-{e['t_end']:.3f} s, worst {e['min_distance']:.4g} {units} "
              f"at t {e['t_worst']:.3f} s, ({where}), s = {e['s']:.4g} {units}")
        if e["severity"] == "hard" and e.get("joint_ranges"):
            print(f"         {_joint_cause(e, report.get('joint_units', {}))}")
    if len(events) > most:
        print(f"    ... {len(events) - most} more in the report")


def _joint_cause(event: dict, joint_units: dict) -> str:
    """The link an event rubs and the ranges of the joints moving it over the event."""
    ranges = ", ".join(f"{name} {lo:.4g}..{hi:.4g} {joint_units.get(name, '')}".rstrip()
                       for name, (lo, hi) in event["joint_ranges"].items())
    link = f"link {event['link']}" if event["link"] else "no moving link"
    return f"{link}; joints over the event: {ranges}"


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `cablecheck` command; returns the exit status.

    SIGINT and SIGTERM are taken from the start (`sim.stop`): a run asked to
    stop while it starts up still writes its incomplete report."""
    with StopRequest() as stop:
        return _main(_parser().parse_args(argv), stop)


def _main(args: argparse.Namespace, stop: StopRequest) -> int:
    try:   # numpy, MuJoCo and trimesh load here, with the signals already taken
        from sim.outputs import OutputPathError
        from sim.scene import SceneError
        from sim.studyrun import StudyRunError
    except KeyboardInterrupt:
        print("cablecheck: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED

    try:
        if args.command == "check":
            return _cmd_check(args)
        if args.command == "run":
            return _cmd_run(args, stop)
        if args.command == "sweep":
            return _cmd_sweep(args)
        if args.command == "study":
            return _cmd_study(args, stop)
        if args.command == "bench":
            from sim.bench import run_bench
            from sim.outputs import check_folder

            check_folder(args.out, "--out")  # MuJoCo and matplotlib load only when needed

            run_bench(quick=args.quick, out=args.out)
            return EXIT_OK
    except SceneError as e:
        print(f"cablecheck: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OutputPathError as e:
        print(f"cablecheck: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ValueError as e:
        from sim.sweep import SweepInputError
        if not isinstance(e, SweepInputError):
            raise
        print(f"cablecheck: error: {args.scene}: {e.option}: {e.problem}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as e:
        print(f"cablecheck: error: {e.filename or ''}: {e.strerror or e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except StudyRunError as e:   # a cluster that cannot be used
        print(f"cablecheck: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("cablecheck: interrupted", file=sys.stderr)
        return EXIT_TERMINATED if stop.signal_name == "SIGTERM" else EXIT_INTERRUPTED
    return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
