"""Start-up: the wall time of short commands, whole processes as a user runs them.

The commands, each timed as a subprocess ``--repeat`` times after one
untimed warm-up (median, least and most, seconds of wall time):

1. ``cablecheck check scenes/drawer.toml``;
2. ``cablecheck run STATIC --no-record --report R``: the static check of
   ``--static C,P`` cables x primitive parts (default 100 x 300), the
   harness scene of :func:`cablecheck.bench.harness.harness_scene` with no motion,
   dynamics and validation off (so no MuJoCo model is built: the routes are
   checked as drooped), written here as TOML;
3. (``--record``) the same run writing its recording as well.

Beside the wall time: the median CPU seconds of the process (user and
system, all its threads, numpy's BLAS threads starting up among them) and
the report's own ``timing.total_s`` of the static run (the rest of the
process is the interpreter, the imports and the report's writing). Children
get a bytecode cache of their own (``PYTHONPYCACHEPREFIX``, a temporary
folder, warmed by the first run), as an installed package has its ``.pyc``
files, whatever ``PYTHONDONTWRITEBYTECODE`` says here (``--no-bytecode``
times the sources compiled on every start instead). ``--before REV`` times
git revision REV's ``sim`` and ``checker`` (exported to a temporary folder,
run through the same entry point from there) in the same session,
alternating with this checkout; ``--rev REV`` times revision REV in place
of this checkout (its committed code alone, without the changes of the
working tree). The figures, the date, the load (``uptime``) before and
after and the commands are printed; ``--doc FILE`` also writes them into
FILE between the markers ``<!-- bench_startup -->`` and ``<!--
/bench_startup -->`` (added at the end if absent).

Run: python benchmarks/bench_startup.py [--repeat N] [--static C,P] [--record]
       [--rev REV] [--before REV] [--no-bytecode] [--doc docs/performance.md]

Timings depend on the machine and its load: the targets (issue 30) are
for a quiet machine; a load above 0.5 is reported beside the figures.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

TARGETS = {"check drawer": 1.0, "static run": 1.5}
"""Wall-time targets in seconds (issue 30, "start-up paid only for what runs")."""

BEGIN, END = "<!-- bench_startup -->", "<!-- /bench_startup -->"


def static_scene(cables: int, parts: int, folder: Path) -> Path:
    """The static harness scene (see the module docstring), written to ``folder``."""
    from cablecheck.bench.harness import harness_scene, write_scene

    data = harness_scene(cables, parts, segments=40, duration=0.0, dynamics=False)
    data["check"]["validate"] = False
    return write_scene(data, folder / f"static_{cables}x{parts}.toml")


ENTRY = "import sys; from cablecheck.cli.main import main; sys.exit(main())"
"""What the installed ``cablecheck`` script runs."""


def command_prefix(tree: Path | None) -> list[str]:
    """How the command is started: the installed ``cablecheck`` beside this
    interpreter (as a user runs it), or for an exported tree the same entry
    point run from that tree's folder."""
    script = Path(sys.executable).parent / "cablecheck"
    if tree is None and script.exists():
        return [str(script)]
    return [sys.executable, "-c", ENTRY]


def child_env(tree: Path | None, cache: Path | None) -> dict:
    """The children's environment: their own bytecode cache, and the tree first on the path."""
    env = dict(os.environ)
    if cache is not None:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = str(cache)
    else:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    if tree is not None:
        env["PYTHONPATH"] = str(tree)
    return env


def timed(cmd: list[str], env: dict, cwd: Path) -> tuple[float, float]:
    """Wall seconds and CPU seconds (user + system, all its threads) of one
    run of ``cmd`` (its output discarded); an exit status above 1 is an error."""
    t0 = time.perf_counter()
    with tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(cmd, env=env, cwd=cwd, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        code = os.waitstatus_to_exitcode(status)
        if code not in (0, 1):
            err.seek(0)
            raise RuntimeError(f"{shlex.join(cmd)} exited {code}: {err.read().strip()[-300:]}")
    return wall, usage.ru_utime + usage.ru_stime


def export(rev: str) -> Path:
    """The ``sim`` and ``checker`` packages of git revision ``rev`` in a temporary folder."""
    folder = Path(tempfile.mkdtemp(prefix="bench_startup_before_"))
    archive = subprocess.run(["git", "-C", str(REPO), "archive", rev, "checker", "sim"],
                             check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder


def revision(rev: str) -> str:
    """The short hash of git revision ``rev``."""
    return subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", rev], check=True,
                          capture_output=True, text=True).stdout.strip()


def load() -> str:
    """``uptime``'s line (the load averages over 1, 5 and 15 minutes)."""
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def one_minute(uptime: str) -> float:
    """The one-minute load average of an ``uptime`` line."""
    return float(uptime.split("load average:")[1].split(",")[0])


def cases(static: Path, report: Path, record: bool) -> list[tuple[str, list[str]]]:
    """(name, arguments) of the timed commands (absolute paths: an exported
    tree runs from its own folder)."""
    out = [("check drawer", ["check", str(REPO / "scenes" / "drawer.toml")]),
           ("static run", ["run", str(static), "--no-record", "--quiet", "--report", str(report)])]
    if record:
        out.append(("static run, recorded", ["run", str(static), "--quiet", "--record",
                                             str(report.with_suffix(".rrd")), "--report", str(report)]))
    return out


def shown(args: list[str], static: Path, report: Path) -> str:
    """The command as a user would type it: the repository's paths relative,
    the scene written here as STATIC, the outputs as REPORT and RECORDING."""
    names = {str(static): "STATIC", str(report): "REPORT", str(report.with_suffix(".rrd")): "RECORDING"}
    words = [names.get(w, w.replace(str(REPO) + os.sep, "")) for w in args]
    return "cablecheck " + " ".join(words)


def measure(trees: dict[str, Path | None], todo: list[tuple[str, list[str]]], repeat: int,
            caches: dict[str, Path | None], static: Path, report: Path) -> list[dict]:
    """Every case in every tree, one warm-up each, then ``repeat`` rounds
    alternating the trees; one row per (tree, case)."""
    rows = []
    for name, args in todo:
        walls: dict[str, list[float]] = {label: [] for label in trees}
        cpus: dict[str, list[float]] = {label: [] for label in trees}
        totals: dict[str, list[float]] = {label: [] for label in trees}
        for label, tree in trees.items():       # warm-up: bytecode, disk cache
            timed(command_prefix(tree) + args, child_env(tree, caches[label]), tree or REPO)
        for _ in range(repeat):
            for label, tree in trees.items():
                wall, cpu = timed(command_prefix(tree) + args, child_env(tree, caches[label]), tree or REPO)
                walls[label].append(wall)
                cpus[label].append(cpu)
                if args[0] == "run":
                    totals[label].append(json.loads(report.read_text())["timing"]["total_s"])
        for label in trees:
            w = walls[label]
            rows.append({"tree": label, "case": name, "command": shown(args, static, report),
                         "median_s": statistics.median(w), "min_s": min(w), "max_s": max(w),
                         "cpu_s": statistics.median(cpus[label]),
                         "run_total_s": statistics.median(totals[label]) if totals[label] else None,
                         "target_s": TARGETS.get(name)})
    return rows


def table(rows: list[dict]) -> str:
    """The rows as a Markdown table."""
    lines = ["| tree | command | median s | least s | most s | CPU s | report total_s | target s |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        total = "-" if r["run_total_s"] is None else f"{r['run_total_s']:.3f}"
        target = "-" if r["target_s"] is None else f"{r['target_s']:.1f}"
        lines.append(f"| {r['tree']} | `{r['command']}` | {r['median_s']:.3f} | {r['min_s']:.3f} | "
                     f"{r['max_s']:.3f} | {r['cpu_s']:.3f} | {total} | {target} |")
    return "\n".join(lines)


def write_doc(path: Path, text: str) -> None:
    """Put ``text`` between the markers in ``path`` (the markers added at the end if absent)."""
    old = path.read_text() if path.exists() else ""
    block = f"{BEGIN}\n{text}\n{END}"
    if BEGIN in old and END in old:
        head, rest = old.split(BEGIN, 1)
        new = head + block + rest.split(END, 1)[1]
    else:
        new = old.rstrip("\n") + ("\n\n" if old else "") + block + "\n"
    path.write_text(new)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=7, help="timed runs per command (after one warm-up)")
    ap.add_argument("--static", default="100,300", help="cables,parts of the static scene")
    ap.add_argument("--record", action="store_true", help="also time the static run writing its recording")
    ap.add_argument("--rev", default=None, help="time this git revision in place of this checkout")
    ap.add_argument("--before", default=None, help="a git revision timed beside this checkout")
    ap.add_argument("--no-bytecode", action="store_true", help="compile the sources on every start")
    ap.add_argument("--doc", type=Path, default=None, help="write the figures into this Markdown file")
    a = ap.parse_args()
    cables, parts = (int(x) for x in a.static.split(","))
    work = Path(tempfile.mkdtemp(prefix="bench_startup_"))
    trees: dict[str, Path | None] = {"this checkout": None}
    try:
        if a.rev:
            trees = {f"{a.rev} ({revision(a.rev)})": export(a.rev)}
        if a.before:
            trees[f"before: {a.before} ({revision(a.before)})"] = export(a.before)
        static, report = static_scene(cables, parts, work), work / "report.json"
        caches = {label: None if a.no_bytecode else Path(tempfile.mkdtemp(prefix="pyc_", dir=work))
                  for label in trees}
        before_load = load()
        started = datetime.datetime.now().astimezone()
        rows = measure(trees, cases(static, report, a.record), a.repeat, caches, static, report)
        after_load = load()
    finally:
        for tree in trees.values():
            if tree is not None:
                shutil.rmtree(tree, ignore_errors=True)
        shutil.rmtree(work, ignore_errors=True)
    busy = max(one_minute(before_load), one_minute(after_load))
    text = "\n".join([
        f"Measured {started:%Y-%m-%d %H:%M %Z} on {os.cpu_count()} cores, {a.repeat} runs per command "
        f"after one warm-up, {'sources compiled on every start' if a.no_bytecode else 'bytecode cached'}"
        f"; static scene: {cables} cables x {parts} primitive parts (`cablecheck.bench.harness`, no motion, "
        "dynamics and validation off).",
        "",
        f"Load before: `{before_load}`; after: `{after_load}`"
        + (" (not quiet: figures above the quiet machine's)" if busy > 0.5 else "") + ".",
        "",
        f"Command: `python benchmarks/bench_startup.py {shlex.join(sys.argv[1:])}`",
        "",
        table(rows),
    ])
    print(text)
    if a.doc is not None:
        write_doc(a.doc, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
