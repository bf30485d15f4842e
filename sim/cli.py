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
problem; never a traceback), 3 when the simulation diverged (the report's
`physics_error` names when, the cable or body and the likely cause), 4 when
a run failed with an error (the report's `error` holds its type, message
and traceback; any other command prints one line and exits 4 too), 130
when interrupted with Ctrl-C and 143 when terminated with SIGTERM (for a
run in each of the last four, the report, marked incomplete, and the
recording are still written). Tracebacks are printed only with the environment variable
`CABLECHECK_TRACEBACK` set. Output paths are checked before any work starts.

This module runs the sub-commands and maps their outcomes and errors to
exit statuses. The arguments are parsed by `sim.cliargs`, progress and
summaries printed by `sim.cliprint`; the work is done in `sim.run`,
`sim.sweep`, `sim.study` and `sim.bench`.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from sim.stop import StopRequest   # first: signals are taken before the heavy imports
from sim.cliargs import build_parser
from sim.cliprint import ProgressBar, StudyBar, print_study, print_summary, print_sweep

EXIT_OK, EXIT_FAIL, EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_TERMINATED = 0, 1, 2, 130, 143
EXIT_DIVERGED, EXIT_ERROR = 3, 4

TRACEBACK_ENV = "CABLECHECK_TRACEBACK"
"""Set (to anything but empty or 0): an error's traceback is printed too."""


def _show_traceback() -> bool:
    return os.environ.get(TRACEBACK_ENV, "") not in ("", "0")


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
    warnings = scene.warnings
    if "cable-structure" in scene.effects.contact and scene.cables:
        from sim.build import plan_cables            # MuJoCo loads only for a scene whose cables collide
        from sim.routecheck import route_warnings

        warnings += route_warnings(scene, *plan_cables(scene))
    if not args.quiet:
        steps = round(scene.duration / scene.timestep)
        print(f"{args.scene}: valid scene {scene.name!r} ({scene.units}): {len(scene.cables)} cable(s), "
              f"{len(scene.parts)} part(s), {len(scene.bodies)} scripted bod"
              f"{'y' if len(scene.bodies) == 1 else 'ies'}, {len(scene.motions)} motion(s)"
              + (f", on {scene.mjcf.name}" if scene.mjcf else "")
              + f"; {scene.duration:g} s in {steps} steps of {scene.timestep:g} s")
    for w in warnings:
        print(f"warning: {args.scene}: {w}", file=sys.stderr)
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
                         only=args.only, advance=not args.full_every_step, baseline=args.baseline,
                         review=args.review)
    bar = ProgressBar(enabled=not args.quiet, timestep=scene.timestep)
    try:
        result = run_scene(scene, options, progress=bar, stop=stop,
                           warn=None if args.quiet else (lambda w: print(f"warning: {w}", file=sys.stderr)))
    finally:
        bar.done()
    if not args.quiet:
        print_summary(result, report)
    if result.get("physics_error"):
        print(f"cablecheck: {result['physics_error']['message']} (report: {report})", file=sys.stderr)
        return EXIT_DIVERGED
    if result.get("error"):
        e = result["error"]
        if _show_traceback():
            print(e["traceback"], end="", file=sys.stderr)
        print(f"cablecheck: error: the run failed: {e['type']}: {_one_line(e['message'])} (report, with the "
              f"traceback: {report}; {TRACEBACK_ENV}=1 prints it)", file=sys.stderr)
        return EXIT_ERROR
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
        print_sweep(result, report)
    return EXIT_FAIL if (result["hits"] or result["overlapping"]) else EXIT_OK


def _cmd_study(args: argparse.Namespace, stop: StopRequest) -> int:
    from sim.bundle import make_bundle
    from sim.outputs import check_folder
    from sim.study import Method, check_study_names, check_variants, load_study, variants, varied_cables
    from sim.studyresult import fails, length_window

    from sim.studycluster import StudyRunError, check_address

    check_folder(args.out, "--out")
    if args.scheduler is not None:
        try:   # the address's form, its host and TLS settings, before any work
            check_address(args.scheduler)
        except StudyRunError as e:
            print(f"cablecheck: error: {e}", file=sys.stderr)
            return EXIT_BAD_INPUT
    study = load_study(args.study)
    folder = args.out / study.name
    check_folder(folder, "study folder (--out/<name>)")
    found = variants(study)   # a search's: the corners of its box
    scenes = check_variants(study, found)   # every variant's scene, before anything runs
    check_study_names(study, scenes[0])
    searching = study.search.method is Method.OPTIMISE
    from sim.studyplot import write_outputs
    from sim.studyrun import VariantTask, run_search, run_variants

    where = (f"the Dask scheduler at {args.scheduler}" if args.scheduler else
             f"{args.workers or os.cpu_count() or 1} local worker process(es)")
    if not args.quiet:
        what = (f"a search of at most {study.search.budget} run(s)" if searching else f"{len(found)} variant(s)")
        print(f"study {study.name}: {what} of {study.scene_path} on {where}", flush=True)
    bar = StudyBar(enabled=not args.quiet)
    try:
        try:
            if searching:
                rows, complete = run_search(study, not args.no_record, folder, workers=args.workers,
                                            scheduler=args.scheduler, stop=stop, progress=bar,
                                            resume=args.resume)
            else:
                bundle, datas = make_bundle(study.scene_path, [v.data for v in found])
                tasks = [VariantTask(id=v.id, data=d, record=not args.no_record) for v, d in zip(found, datas)]
                rows, complete = run_variants(tasks, {v.id: v.values for v in found}, bundle, folder,
                                              workers=args.workers, scheduler=args.scheduler, stop=stop,
                                              progress=bar, judged=(study.requirements, study.goal),
                                              resume=args.resume)
        finally:
            bar.done()
    except StudyRunError as e:   # a cluster that cannot be used
        print(f"cablecheck: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    units = scenes[0].units
    window = None   # no window, and no recommendation, from an interrupted study
    if complete and not searching and len(study.vary) == 1 and study.vary[0].path.endswith(".length") and \
            study.vary[0].path.startswith("cables[") and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) for x in study.vary[0].values):
        window = length_window(rows, cable=varied_cables(study)[0])   # the varied cable's own answer
    settings = {"fail_on": args.fail_on, "record": not args.no_record,
                "cluster": args.scheduler or f"local, {args.workers or os.cpu_count() or 1} workers",
                "version": version()}
    paths = write_outputs(folder, study, rows, complete=complete, units=units, window=window,
                          settings=settings)
    if not args.quiet:
        print_study(study, rows, units, window, complete, paths)
    if not complete:
        return EXIT_TERMINATED if stop.signal_name == "SIGTERM" else EXIT_INTERRUPTED
    return EXIT_FAIL if any(fails(r, args.fail_on) for r in rows) else EXIT_OK


def _fails(report: dict, level: str) -> bool:
    summary = report.get("summary", {})
    if level == "never":
        return False
    if level == "soft":
        return summary.get("hard", 0) + summary.get("soft", 0) > 0
    return summary.get("hard", 0) > 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `cablecheck` command; returns the exit status.

    SIGINT and SIGTERM are taken from the start (`sim.stop`): a run asked to
    stop while it starts up still writes its incomplete report."""
    with StopRequest() as stop:
        return _main(build_parser(version()).parse_args(argv), stop)


def _main(args: argparse.Namespace, stop: StopRequest) -> int:
    try:   # numpy and MuJoCo load here, with the signals already taken
        from sim.baseline import BaselineError
        from sim.review import ReviewError
        from sim.outputs import OutputPathError
        from sim.scene import SceneError
    except KeyboardInterrupt:
        print("cablecheck: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED

    try:
        if args.command == "check":
            return _cmd_check(args)
        if args.command == "run":
            return _cmd_run(args, stop)
        if args.command == "sweep":
            from sim.mjlog import log_file_off   # a run takes MuJoCo's messages itself (sim.run)

            with log_file_off():
                return _cmd_sweep(args)
        if args.command == "study":
            from sim.studycluster import closing_later   # its cluster closes while it writes its outputs

            with closing_later():
                return _cmd_study(args, stop)
        if args.command == "bench":
            from sim.bench import FULL, QUICK, run_bench
            from sim.outputs import check_folder

            check_folder(args.out, "--out")  # MuJoCo and matplotlib load only when needed

            from sim.mjlog import log_file_off

            with log_file_off():
                run_bench(QUICK if args.quick else FULL, out=args.out)
            return EXIT_OK
    except SceneError as e:
        print(f"cablecheck: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (OutputPathError, BaselineError, ReviewError) as e:
        print(f"cablecheck: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ValueError as e:
        from sim.checkview import OptionError   # --only of a run, the sweep's options
        if not isinstance(e, OptionError):
            return _failed(args, e)
        print(f"cablecheck: error: {args.scene}: {e.option}: {e.problem}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as e:
        print(f"cablecheck: error: {e.filename or ''}: {e.strerror or e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("cablecheck: interrupted", file=sys.stderr)
        return EXIT_TERMINATED if stop.signal_name == "SIGTERM" else EXIT_INTERRUPTED
    except Exception as e:   # never a bare traceback (a run writes its own report, sim.run)
        return _failed(args, e)
    return EXIT_BAD_INPUT


def _failed(args: argparse.Namespace, e: Exception) -> int:
    """An unexpected error of a command: one line on stderr (the traceback
    only with `TRACEBACK_ENV` set), exit status 4."""
    if _show_traceback():
        import traceback

        traceback.print_exception(type(e), e, e.__traceback__)
    print(f"cablecheck: error: {args.command} failed: {type(e).__name__}: {_one_line(str(e))} "
          f"({TRACEBACK_ENV}=1 prints the traceback)", file=sys.stderr)
    return EXIT_ERROR


def _one_line(text: str) -> str:
    """`text` with its line breaks and runs of spaces made single spaces."""
    return " ".join(text.split())


if __name__ == "__main__":
    sys.exit(main())
