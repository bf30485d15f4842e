"""The `cablecheck` command line's arguments: the parser of every
sub-command, its help texts, and the types that check option values.

A bad option value is argparse's usage error (exit status 2). This module
only parses; the sub-commands are run by `cablecheck.cli.main`, and what they print is
`cablecheck.cli.printing`'s.
"""

from __future__ import annotations

import argparse
from pathlib import Path

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
  html       with --html PATH: the same report as one self-contained HTML file
             (clash table, pictures of the spots, distance histories, wear).
  Each is written atomically: an interrupted, diverged or failed run still
  leaves a readable recording and a report with "complete": false.

exit status:
  0  nothing reached the --fail-on level    1  something did
  2  bad input (file, key and problem are printed)
  3  the simulation diverged (NaN, infinite or runaway state, or MuJoCo found
     it unstable): the report holds "physics_error" (time, cable or body,
     likely cause: units, stiffness against the timestep, a body teleported)
  4  the run failed with an error: the report holds "error" (type, message,
     traceback; CABLECHECK_TRACEBACK=1 also prints the traceback)
  130  interrupted (Ctrl-C)    143  terminated (SIGTERM)
"""


def build_parser(version: str) -> argparse.ArgumentParser:
    """The parser of `cablecheck` and its sub-commands; `version` is printed by --version."""
    parser = argparse.ArgumentParser(prog="cablecheck", description=_DESCRIPTION,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"%(prog)s {version}")
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
    run.add_argument("--spacing", type=positive_float, metavar="K",
                     help="override [check] spacing: discrete-point spacing in cable radii (paper: 2)")
    run.add_argument("--fail-on", choices=("hard", "soft", "never"), default="hard",
                     help="exit 1 when interference of this severity or worse is found (default: hard)")
    run.add_argument("--full-every-step", action="store_true",
                     help="run the full pairwise check on every checked step; by default (method "
                          "points) a step on which everything is proven clear since the last full "
                          "check, but the pairs already near the clearance, checks only those: the "
                          "same events, pairs and MuJoCo comparison, faster (docs/accuracy.md)")
    run.add_argument("--quiet", action="store_true", help="print nothing but errors")
    run.add_argument("--baseline", type=Path, metavar="EARLIER.json",
                     help="an earlier run's report: mark each clash new or still present, and list "
                          "the earlier ones now resolved (matched by pair and place along the cable)")
    run.add_argument("--review", type=Path, metavar="NOTES.toml",
                     help="a reviewer's notes ([[review]] a, b, status reviewed|approved, comment): "
                          "carried into the report beside each clash they cover; notes that cover "
                          "no clash are listed")
    run.add_argument("--html", type=Path, metavar="REPORT.html",
                     help="also write an HTML report there: one self-contained file (no network) with "
                          "the summary, the clash table, a picture of each clash's spot at its worst "
                          "time (rendered offscreen), its distance history and each cable's wear")
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
    sw.add_argument("--direction", required=True, metavar="X,Y,Z", type=xyz_direction,
                    help="direction of travel in scene axes (any length, not zero); "
                         "write --direction=-1,0,0 when it starts with a minus sign")
    sw.add_argument("--distance", required=True, metavar="H", type=nonnegative_float,
                    help="travel in scene units")
    sw.add_argument("--report", type=Path, metavar="PATH",
                    help="JSON report path (default: recordings/<scene name>-sweep.json)")
    sw.add_argument("--precision", type=positive_float, metavar="P",
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
    where.add_argument("--workers", type=positive_int, metavar="N",
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
    st.add_argument("--resume", action="store_true",
                    help="keep the variants a previous run of this study finished with the same scene "
                         "(scene data and files hashed) and run only the rest (default: start afresh)")
    st.add_argument("--quiet", action="store_true", help="print nothing but errors")
    bench = sub.add_parser("bench", help="what accuracy costs in time: tables, CSV and a plot",
                           description="Measure discretisation accuracy, physics resolution, scale, "
                                       "the checker beside python-fcl and MuJoCo's collision, and "
                                       "per-step cost of the example scenes; print the tables and "
                                       "write them as CSV plus bench.png into --out.")
    bench.add_argument("--quick", action="store_true", help="fewer scenes and repeats")
    bench.add_argument("--out", type=Path, default=Path("recordings/bench"), metavar="DIR",
                       help="output folder (default: recordings/bench)")
    return parser


def positive_float(text: str) -> float:
    """An option value that is a finite number above zero."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive number: {text!r}")
    return value


def nonnegative_float(text: str) -> float:
    """An option value that is a finite number, zero or above."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value >= 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a non-negative number: {text!r}")
    return value


def positive_int(text: str) -> int:
    """An option value that is a whole number, 1 or above."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1: {text!r}")
    return value


def xyz_direction(text: str) -> tuple[float, float, float]:
    """``X,Y,Z``: three finite numbers, not all zero."""
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
