"""What the `cablecheck` command line prints: progress bars on stderr and
the summaries of a run, a sweep and a study on stdout.

Everything here reads a finished report (the dict a run or sweep writes as
JSON, a study's rows) and only prints; nothing decides an exit status
(`cablecheck.cli.main`) or computes a result (`cablecheck.run.runner`, `cablecheck.run.sweep`, `cablecheck.study.result`).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

POSITION_DECIMALS = {"mm": 2, "m": 5}
"""Decimals of printed positions: 10 um in either unit, wherever the scene
lies (``%g`` prints 1.235e+07 for a point 12.3 km out in mm)."""


def _position(values, units: str) -> str:
    """A position as fixed-point numbers at `POSITION_DECIMALS` for its units."""
    return ", ".join(f"{x:.{POSITION_DECIMALS.get(units, 5)}f}" for x in values)


class ProgressBar:
    """A one-line progress display on stderr, redrawn at most 10 times a second.

    With the scene's `timestep` (seconds a step), a run's line also says the
    simulated time, the rate against real time and the time left, once the
    run has gone on for `RATE_AFTER` seconds (before that a rate says little)."""

    RATE_AFTER = 2.0

    def __init__(self, enabled: bool, timestep: float | None = None):
        self.enabled = enabled
        self.tty = sys.stderr.isatty()
        self.timestep = timestep
        self._last = 0.0
        self._shown = False
        self._last_pct = -1
        self._start: tuple[float, float] | None = None     # (wall clock, step) when the run stage began

    def _rate(self, done: float, total: float, now: float) -> str:
        """", t = 1.26 of 3 s, 0.85x real time, 2 s left" for the run stage, or ""."""
        if self.timestep is None or self._start is None:
            return ""
        wall, first = now - self._start[0], self._start[1]
        text = f", t = {done * self.timestep:.3g} of {total * self.timestep:.3g} s"
        if wall < self.RATE_AFTER or done <= first:
            return text
        per_step = wall / (done - first)
        return text + (f", {self.timestep / per_step:.2g}x real time, "
                       f"{per_step * (total - done):.0f} s left")

    def __call__(self, stage: str, done: float, total: float) -> None:
        if not self.enabled or total <= 0:
            return
        frac = min(max(done / total, 0.0), 1.0)
        now = time.monotonic()
        if stage == "run" and self._start is None:
            self._start = (now, done)
        rate = self._rate(done, total, now) if stage == "run" else ""
        if self.tty:
            if now - self._last < 0.1 and frac < 1.0:
                return
            self._last = now
            bar = "#" * int(30 * frac)
            label = "settling " if stage == "settle" else "simulating"
            sys.stderr.write(f"\r{label} [{bar:<30}] {100 * frac:5.1f}%{rate}   ")
            sys.stderr.flush()
            self._shown = True
        else:
            pct = int(frac * 4) * 25  # a line every quarter when not on a terminal
            if stage == "run" and pct != self._last_pct:
                self._last_pct = pct
                sys.stderr.write(f"simulating: {pct}%{rate}\n")

    def done(self) -> None:
        if self._shown:
            sys.stderr.write("\r" + " " * 110 + "\r")
            sys.stderr.flush()


class StudyBar:
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


def print_summary(report: dict, report_path: Path) -> None:
    units = report["units"]
    s = report["settings"]
    status = ("complete" if report["complete"] else
              "DIVERGED (report marked incomplete)" if report.get("physics_error") else
              "FAILED (report marked incomplete)" if report.get("error") else
              "INTERRUPTED (report marked incomplete)")
    if "t_end" not in s:     # failed before its first step: no settings, cables or checks to print
        print(f"{report['scene']}: {status} before its first step, after {report['timing']['total_s']:.2f} s")
        print(f"  report: {report_path}")
        return
    print(f"{report['scene']}: {status}, {s['steps']} steps to t = {s['t_end']:.3f} s, "
          f"{s['checked_steps']} checked, method {s['method']}")
    for c in report["cables"]:
        bend = c["min_bend_radius"]
        flags = [f for f, on in (("TAUT", c["taut"]), ("BEND", c["bend_violation"])) if on]
        strain = c["max_strain"]
        if strain is None:       # no step checked (a run stopped while building or settling)
            print(f"  cable {c['name']}: length {c['length']:.4g} {units}, no step checked")
            continue
        print(f"  cable {c['name']}: length {c['length']:.4g} {units}, max strain "
              f"{round(100 * strain, 2) + 0.0:.2f} %, min bend radius "
              f"{'straight' if bend is None else f'{bend:.4g} {units}'}"
              + (f", max twist {c['max_twist']:.3g} deg{_torsion(c, units)}" if c.get("max_twist") is not None
                 else "")
              + (f"  [{', '.join(flags)}]" if flags else ""))
        _print_closest(report, c["name"], units)
    _print_events(report)
    _print_baseline(report)
    _print_review(report)
    _print_excused(report)
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
    for w in report.get("physics_warnings", ()):
        print(f"  warning: {w}")
    t = report["timing"]
    print(f"  time {t['total_s']:.2f} s (simulation {t['sim_s']:.2f} s, checks {t['check_s']:.2f} s, "
          f"MuJoCo comparison {t['validate_s']:.2f} s, recording {t['record_s']:.2f} s)")
    print(f"  report: {report_path}")
    if report.get("recording"):
        print(f"  recording: {report['recording']}  (view: rerun {report['recording']})")


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
        status = f"[{e['status']}] " if "status" in e else ""
        print(f"    {status}{e['severity'].upper():4} {e['phase']:7} {e['type']:15} {pair}: "
              f"t {e['t_start']:.3f}-{e['t_end']:.3f} s, worst {e['min_distance']:.4g} {units} "
              f"at t {e['t_worst']:.3f} s, ({where}), s = {e['s']:.4g} {units}")
        if e["severity"] == "hard" and e.get("joint_ranges"):
            print(f"         {_joint_cause(e, report.get('joint_units', {}))}")
        if e.get("review"):
            print(f"         {e['review']['status']}: {e['review']['comment']}")
    if len(events) > most:
        print(f"    ... {len(events) - most} more in the report")


def _print_review(report: dict) -> None:
    """The reviewer's notes (--review): how many are on clashes, and those on none."""
    r = report.get("review")
    if not r:
        return
    print(f"  review notes {r['file']}: {r['on_events']} clash(es) noted, {len(r['unmatched'])} note(s) "
          f"on no clash of this run" + (":" if r["unmatched"] else ""))
    for n in r["unmatched"]:
        print(f"    review[{n['index']}] {n['a']} / {n['b']} ({n['status']}): {n['comment']}")


def _print_baseline(report: dict, most: int = 5) -> None:
    """Against an earlier run (--baseline): how many clashes are new, still present, resolved."""
    b = report.get("baseline")
    if not b:
        return
    units = report["units"]
    print(f"  against {b['report']}: {b['new']} new, {b['present']} still present, {b['resolved']} resolved")
    for e in b["resolved_events"][:most]:
        pair = e["a"] if e["a"] == e["b"] else f"{e['a']} / {e['b']}"
        print(f"    [resolved] {e['severity'].upper():4} {e['type']:15} {pair}: was {e['min_distance']:.4g} {units} "
              f"at t {e['t_worst']:.3f} s, s = {e['s']:.4g} {units}")
    if len(b["resolved_events"]) > most:
        print(f"    ... {len(b['resolved_events']) - most} more in the report")


def _torsion(c: dict, units: str) -> str:
    """Where the simulated rod's torsional moment was largest, when it carried any."""
    twist = c.get("twist")
    if not twist or not len(twist["max_moment"]) or not c.get("max_twist_moment"):
        return ""
    k = max(range(len(twist["max_moment"])), key=lambda i: twist["max_moment"][i])
    return f" (torsion up to {c['max_twist_moment']:.3g} N m, at {twist['s'][k]:.4g} {units} along)"


def _print_closest(report: dict, cable: str, units: str) -> None:
    """A cable's closest approach to anything, clash or not (the report's `closest`)."""
    closest = report.get("closest")
    if not closest:
        return
    row = next((x for x in closest["cables"] if x["cable"] == cable), None)
    if row is None or row["min_distance"] is None:
        print(f"    closest approach: nothing within {closest['reach']:.4g} {units}")
        return
    print(f"    closest approach: {row['min_distance']:.4g} {units} to {row['other']} at t {row['t']:.3f} s, "
          f"{row['s']:.4g} {units} along")


def _print_excused(report: dict, most: int = 5) -> None:
    """What was allowed (`[[allow]]`) and what attachment windows excused: never clashes, never silent."""
    units = report["units"]
    allowed, excused = report.get("allowed", []), report.get("excused", [])
    if allowed:
        print(f"  {len(allowed)} allowed pair(s), not clashes: "
              + "; ".join(f"{p['a']} / {p['b']} worst {p['min_distance']:.4g} {units} ({p['reason']})"
                          for p in allowed[:most]) + (" ..." if len(allowed) > most else ""))
    if excused:
        print(f"  {len(excused)} contact(s) excused by attachment windows, not clashes: "
              + "; ".join(f"{x['a']} {x['window']} / {x['b']} worst {x['min_distance']:.4g} {units} "
                          f"at t {x['t_worst']:.3f} s" for x in excused[:most])
              + (" ..." if len(excused) > most else ""))


def _joint_cause(event: dict, joint_units: dict) -> str:
    """The link an event rubs and the ranges of the joints moving it over the event."""
    ranges = ", ".join(f"{name} {lo:.4g}..{hi:.4g} {joint_units.get(name, '')}".rstrip()
                       for name, (lo, hi) in event["joint_ranges"].items())
    link = f"link {event['link']}" if event["link"] else "no moving link"
    return f"{link}; joints over the event: {ranges}"


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


def print_sweep(r: dict, path: Path) -> None:
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


def print_study(study, rows, units: str, window, complete: bool, paths: dict) -> None:
    # the study's modules load only for the study command, not for every command that prints
    from cablecheck.study.definition import format_value
    from cablecheck.study.result import Status, free_of_hard

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
    if complete and (study.requirements or study.goal):
        _print_answer(study, rows, units)
    if not complete:
        print("  INTERRUPTED: the tables hold the variants that finished (the others: not run); no answer")
    also = ", ".join(paths[k].name for k in ("json", "png", "map") if k in paths)
    print(f"  results: {paths['csv']}  (also {also})")


def _print_answer(study, rows, units: str) -> None:
    """The study's answer in one line: the best variant, whether it keeps
    every requirement and by what margin (each requirement's beside)."""
    # the study's modules load only for the study command (as in print_study)
    from cablecheck.study.definition import format_value
    from cablecheck.study.result import Status, best_row

    best = best_row(rows)
    runs = sum(r.status is not Status.NOT_RUN for r in rows)
    if best is None:
        print(f"  answer: none of the {runs} run(s) finished")
        return
    where = ", ".join(f"{v.key} = {format_value(x)}" for v, x in zip(study.vary, best.values))
    each = "; ".join(f"{q.label}: {'>= ' if low else ''}{'-' if m is None else format(m, '.4g')}"
                     for q, m, low in zip(study.requirements, best.margins, best.at_least))
    goal = "" if study.goal is None or best.objective is None else \
        f", {study.goal.label}: {abs(best.objective):.4g}"
    if not study.requirements:
        print(f"  answer: {where}{goal} (best of {runs} run(s))")
    elif best.satisfied:
        print(f"  answer: {where} keeps every requirement, least margin {best.margin:.4g} {units}"
              f"{goal} (best of {runs} run(s); {each})")
    else:
        print(f"  answer: none of the {runs} run(s) keeps every requirement; the best, {where}, "
              f"misses by {-best.margin:.4g} {units} ({each})")
