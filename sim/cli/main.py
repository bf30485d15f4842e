"""The `cablecheck` command line.

Subcommands:
  run SCENE   simulate a scene, check it, write the report and the recording.
  sweep SCENE move one part (or assembly) along a line; list the parts it hits.
  bench       measure what accuracy costs in time (tables, CSV and a plot).
  check SCENE validate a scene file without simulating it.
  study FILE  run the variants of a design study on a Dask cluster (`cablecheck.study.definition`,
              `cablecheck.study.execute`); tabulate, plot and answer it.

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
exit statuses. Each command imports its own modules inside its function, so
a command loads only what it uses (`check` no MuJoCo unless a cable
collides, no rerun without a recording, no Dask outside a study); those are
this module's deferred imports. The arguments are parsed by `cablecheck.cli.args`, progress and
summaries printed by `cablecheck.cli.printing`; the work is done in `cablecheck.run.runner`,
`cablecheck.run.sweep`, `cablecheck.study.definition` and `cablecheck.bench.command`.
"""

from __future__ import annotations

import argparse
import atexit
import os
import sys
import threading
from pathlib import Path

from cablecheck.about import version
from cablecheck.cli.args import build_parser
from cablecheck.cli.printing import ProgressBar, StudyBar, print_study, print_summary, print_sweep
from cablecheck.run.stop import StopRequest

EXIT_OK, EXIT_FAIL, EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_TERMINATED = 0, 1, 2, 130, 143
EXIT_DIVERGED, EXIT_ERROR = 3, 4

TRACEBACK_ENV = "CABLECHECK_TRACEBACK"
"""Set (to anything but empty or 0): an error's traceback is printed too."""


def _show_traceback() -> bool:
    return os.environ.get(TRACEBACK_ENV, "") not in ("", "0")



def _cmd_check(args: argparse.Namespace) -> int:
    from cablecheck.scene.load import load_scene  # each command loads its own modules (module docstring)

    scene = load_scene(args.scene)
    warnings = scene.warnings
    if "cable-structure" in scene.effects.contact and scene.cables:
        # MuJoCo loads only for a scene whose cables collide
        from cablecheck.build.routecheck import route_warnings
        from cablecheck.build.stages import build_simulation, plan_cables

        planned = plan_cables(scene)
        warnings += route_warnings(scene, *planned)
        if scene.effects.dynamics:   # what the run's model warns of: the step, fast parts, held points pinched
            warnings += build_simulation(scene, planned).warnings
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
    # each command loads its own modules (module docstring)
    from cablecheck.report.outputs import check_output
    from cablecheck.scene.load import load_scene

    for option, path in (("--report", args.report), ("--record", args.record), ("--html", args.html)):
        if path is not None:
            check_output(path, option)
    scene = load_scene(args.scene)
    record = None if args.no_record else (args.record or Path("recordings") / f"{scene.name}.rrd")
    report = args.report or (record or Path("recordings") / scene.name).with_suffix(".json")
    if record is not None and args.record is None:
        check_output(record, "recording (default path)")
    if args.report is None:
        check_output(report, "report (default path)")
    from cablecheck.run.runner import RunOptions, run_scene  # MuJoCo and rerun load only when needed

    options = RunOptions(report=report, record=record, method=args.method, spacing=args.spacing,
                         only=args.only, advance=not args.full_every_step, baseline=args.baseline,
                         review=args.review, html=args.html)
    bar = ProgressBar(enabled=not args.quiet, timestep=scene.timestep)
    try:
        result = run_scene(scene, options, progress=bar, stop=stop,
                           warn=None if args.quiet else (lambda w: print(f"warning: {w}", file=sys.stderr)))
    finally:
        bar.done()
    if not args.quiet:
        print_summary(result, report)
        for w in (result.get("html") or {}).get("warnings", []):
            print(f"warning: {w}", file=sys.stderr)
        if args.html is not None:
            print(f"HTML report: {args.html}")
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
    # each command loads its own modules (module docstring)
    from cablecheck.report.outputs import check_output
    from cablecheck.run.sweep import SweepOptions, sweep_scene
    from cablecheck.scene.load import load_scene

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
    if args.scheduler is None:
        # the embedded cluster's fork server loads the workers' modules on the
        # second core while the study loads its own (cablecheck.study.cluster)
        from cablecheck.study.cluster import start_forkserver
        start_forkserver()
    # each command loads its own modules (module docstring)
    from cablecheck.study.cluster import StudyRunError
    from cablecheck.study.definition import Method
    from cablecheck.study.result import fails
    from cablecheck.study.run import run_study

    def announce(study, runs: int, where: str) -> None:
        if not args.quiet:
            searching = study.search.method is Method.OPTIMISE
            what = f"a search of at most {runs} run(s)" if searching else f"{runs} variant(s)"
            print(f"study {study.name}: {what} of {study.scene_path} on {where}", flush=True)

    bar = StudyBar(enabled=not args.quiet)
    try:
        try:
            outcome = run_study(args.study, args.out, workers=args.workers, scheduler=args.scheduler,
                                record=not args.no_record, resume=args.resume, fail_on=args.fail_on, stop=stop,
                                progress=bar, announce=announce)
        finally:
            bar.done()
    except StudyRunError as e:   # a cluster that cannot be used
        print(f"cablecheck: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if not args.quiet:
        print_study(outcome.study, outcome.rows, outcome.units, outcome.window, outcome.complete, outcome.paths)
    if not outcome.complete:
        return EXIT_TERMINATED if stop.signal_name == "SIGTERM" else EXIT_INTERRUPTED
    return EXIT_FAIL if any(fails(r, args.fail_on) for r in outcome.rows) else EXIT_OK


def _fails(report: dict, level: str) -> bool:
    summary = report.get("summary", {})
    if level == "never":
        return False
    if level == "soft":
        return summary.get("hard", 0) + summary.get("soft", 0) > 0
    return summary.get("hard", 0) > 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `cablecheck` command; returns the exit status.

    SIGINT and SIGTERM are taken from the start (`cablecheck.run.stop`): a run asked to
    stop while it starts up still writes its incomplete report."""
    with StopRequest() as stop:
        return _main(build_parser(version()).parse_args(argv), stop)


def _main(args: argparse.Namespace, stop: StopRequest) -> int:
    try:   # numpy and MuJoCo load here, with the signals already taken
        from cablecheck.report.baseline import BaselineError
        from cablecheck.report.outputs import OutputPathError
        from cablecheck.report.review import ReviewError
        from cablecheck.scene.errors import SceneError
    except KeyboardInterrupt:
        print("cablecheck: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED

    try:
        if args.command == "check":
            return _cmd_check(args)
        if args.command == "run":
            return _cmd_run(args, stop)
        if args.command == "sweep":
            from cablecheck.run.mjlog import log_file_off  # each command loads its own modules

            with log_file_off():   # (a run takes MuJoCo's messages itself, cablecheck.run.runner)
                return _cmd_sweep(args)
        if args.command == "study":
            from cablecheck.study.cluster import closing_later  # each command loads its own modules

            with closing_later():   # its cluster closes while it writes its outputs
                return _cmd_study(args, stop)
        if args.command == "bench":
            # each command loads its own modules: MuJoCo and matplotlib only here
            from cablecheck.bench.command import FULL, QUICK, run_bench
            from cablecheck.report.outputs import check_folder
            from cablecheck.run.mjlog import log_file_off

            check_folder(args.out, "--out")

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
        from cablecheck.build.checkview import OptionError  # --only of a run, the sweep's options
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
    except Exception as e:   # never a bare traceback (a run writes its own report, cablecheck.run.runner)
        return _failed(args, e)
    return EXIT_BAD_INPUT


def _failed(args: argparse.Namespace, e: Exception) -> int:
    """An unexpected error of a command: one line on stderr (the traceback
    only with `TRACEBACK_ENV` set), exit status 4."""
    if _show_traceback():
        import traceback  # only to print one

        traceback.print_exception(type(e), e, e.__traceback__)
    print(f"cablecheck: error: {args.command} failed: {type(e).__name__}: {_one_line(str(e))} "
          f"({TRACEBACK_ENV}=1 prints the traceback)", file=sys.stderr)
    return EXIT_ERROR


def _one_line(text: str) -> str:
    """`text` with its line breaks and runs of spaces made single spaces."""
    return " ".join(text.split())


def console() -> None:
    """The `cablecheck` console script: :func:`main`, then :func:`exit_at_once`
    with its status (an error `main` lets out, and argparse's own exits for
    `--help` and bad arguments, leave as Python leaves)."""
    exit_at_once(main())


def exit_at_once(status: int) -> None:
    """End the process with `status` without the interpreter's teardown.

    By the time a command returns, everything it writes is closed (reports,
    recordings, a study's tables). What Python's exit does then is free every
    object of the thousand or so modules a run or a study loads (numpy,
    MuJoCo, scipy, Dask, matplotlib, rerun): 0.3-0.4 s on this machine, which
    the operating system does at once (`python -c "import distributed,
    matplotlib.pyplot, mujoco, scipy.optimize, cablecheck.run.runner"`: 1.38-
    1.50 s, and 1.06-1.10 s ending with `os._exit`). What the exit must still
    do is done first: the threads that are not daemons are waited for, the
    exit handlers run (logging's, multiprocessing's, Dask's, rerun's: Python
    keeps no public call for that, so `atexit._run_exitfuncs`), and the
    standard streams are flushed (a closed pipe is no error then)."""
    for thread in threading.enumerate():
        if thread is not threading.main_thread() and not thread.daemon:
            thread.join()
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(status)


if __name__ == "__main__":
    console()
