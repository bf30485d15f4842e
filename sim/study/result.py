"""A study's rows and its answer, from the variants' reports.

`row_from_report` reduces one variant's report to the numbers a study
compares (hard / soft event counts, worst distance, strain and bend
extremes, agreement with MuJoCo, run time); `free_of_hard` and
`length_window` answer the study's question: which variants have no hard
interference, and for a single varied cable length, the window of lengths
that are neither pulled taut nor in hard contact or bent too tight.

This module is pure bookkeeping on report dicts: it runs nothing (see
`cablecheck.study.execute`) and writes nothing (see `cablecheck.study.plot`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from enum import Enum
from typing import Any

from cablecheck.study.goal import Goal, Requirement, judge

SHAPE_TYPES = ("bend", "taut")
"""Event types about one cable's shape, not a distance between surfaces."""


class Status(Enum):
    """What became of a variant."""

    DONE = "done"          # ran to the end; its report is there
    FAILED = "failed"      # raised an error (see `Row.error`)
    NOT_RUN = "not run"    # the study was interrupted before it finished


@dataclass(frozen=True)
class CableRow:
    """One cable of a variant (scene units).

    Attributes:
      name: the cable.
      hard, soft: events of this cable with another thing or itself (bend
        and taut are not counted here: see the flags).
      closest: its least distance to anything within the run's reach (None:
        nothing came within it); closest_to: what.
      max_strain, taut, min_bend_radius, bend_violation, max_twist: as the
        report's cable row (twist in degrees; None where undefined).
      wear: the most sliding at one place of the cable (None: no contact).
    """

    name: str
    hard: int
    soft: int
    closest: float | None
    closest_to: str | None
    max_strain: float | None
    taut: bool
    min_bend_radius: float | None
    bend_violation: bool
    max_twist: float | None
    wear: float | None


CABLE_COLUMNS = ("hard", "soft", "closest", "closest_to", "max_strain", "taut", "min_bend_radius",
                 "bend_violation", "max_twist", "wear")
"""`CableRow` fields in results.csv, one set per varied cable ("<cable>: <field>")."""


def cable_rows(report: dict) -> tuple[CableRow, ...]:
    """Each cable of a report, in its order."""
    closest = {c["cable"]: c for c in (report.get("closest") or {}).get("cables", ())}
    out = []
    for c in report.get("cables", ()):
        name = c["name"]
        mine = [e for e in report.get("events", ()) if e["type"] not in SHAPE_TYPES
                and (e["a"] == name or (e["type"] in ("cable-cable", "self") and e["b"] == name))]
        near = closest.get(name) or {}
        worn = (c.get("wear") or {}).get("most_worn")
        out.append(CableRow(
            name=name, hard=sum(e["severity"] == "hard" for e in mine),
            soft=sum(e["severity"] == "soft" for e in mine),
            closest=near.get("min_distance"), closest_to=near.get("other"),
            max_strain=c.get("max_strain"), taut=bool(c.get("taut", False)),
            min_bend_radius=c.get("min_bend_radius"), bend_violation=bool(c.get("bend_violation", False)),
            max_twist=c.get("max_twist"), wear=None if not worn else worn["sliding"]))
    return tuple(out)


@dataclass(frozen=True)
class Row:
    """One variant of a study.

    Attributes:
      id: the variant's id (its folder name).
      values: the varied values, one per ``[[vary]]`` key.
      status: done, failed or not run.
      exit_status: what `cablecheck run` of this variant exits with under
        ``--fail-on hard`` (0 or 1; 3 for a diverged simulation, 4 for a
        run that failed with an error); None for a variant not run or
        interrupted.
      hard, soft: event counts.
      worst_distance: the smallest signed surface distance of any pair that
        came within the clearance (scene units), excluding bend and taut;
        None when none did.
      max_strain: the largest absolute strain over the cables (signed).
      min_bend_radius: the tightest bend over the cables (scene units);
        None when every cable stayed straight.
      taut, bend_violation: any cable pulled taut / bent below its limit.
      agreement: fraction of (step, pair) classifications on which the
        checker and MuJoCo agree; None without validation.
      run_time_s: the run's own wall time (its report's timing.total_s).
      error: the failure, in words, for a failed or unrun variant.
      report, recording: the variant's output files (paths as text), or None.
      satisfied: every requirement of the study holds (None: not run, or
        no requirement).
      margin: the least margin over the requirements, scene units
        (negative where one fails; None: not run or no requirement).
      objective: the goal's value, larger is better (a length or wear to
        make least is negated); None without a goal or a run.
      margins: per requirement, its margin (None where unbounded).
      at_least: per requirement, its margin is a lower bound (nothing of
        the two came within the run's reach).
      cables: per cable, its own answers (`CableRow`), in the scene's order.
    """

    id: str
    values: tuple[Any, ...]
    status: Status
    exit_status: int | None = None
    hard: int | None = None
    soft: int | None = None
    worst_distance: float | None = None
    max_strain: float | None = None
    min_bend_radius: float | None = None
    taut: bool | None = None
    bend_violation: bool | None = None
    agreement: float | None = None
    run_time_s: float | None = None
    error: str | None = None
    report: str | None = None
    recording: str | None = None
    satisfied: bool | None = None
    margin: float | None = None
    objective: float | None = None
    margins: tuple[float | None, ...] = ()
    at_least: tuple[bool, ...] = ()
    cables: tuple[CableRow, ...] = ()

    def cable(self, name: str) -> CableRow | None:
        return next((c for c in self.cables if c.name == name), None)

    def score(self) -> tuple:
        """Larger is better: finished first, then requirements met, then the
        goal (else the margin), then the margin (see `cablecheck.study.goal.Judgement`)."""
        if self.status is not Status.DONE:
            return (False, False, -math.inf, -math.inf)
        m = -math.inf if self.margin is None else self.margin
        second = self.objective if self.objective is not None else m
        return (True, bool(self.satisfied) if self.satisfied is not None else True, second, m)


COLUMNS = ("status", "exit_status", "hard", "soft", "worst_distance", "max_strain",
           "min_bend_radius", "taut", "bend_violation", "agreement", "run_time_s", "satisfied", "margin",
           "objective", "error")
"""Row fields after the id and the varied values, in the order results.csv gives them."""


def _stopped(report: dict) -> str:
    """Why an incomplete run stopped: its divergence, its error, or the signal."""
    if report.get("physics_error"):
        return report["physics_error"]["message"]
    if report.get("error"):
        return f"the run failed: {report['error']['type']}: {report['error']['message']}"
    return f"the run stopped early ({report.get('interrupted') or 'incomplete'})"


def row_from_report(id: str, values: tuple, report: dict, report_path: str | None = None,
                    recording: str | None = None, requirements: tuple[Requirement, ...] = (),
                    goal: Goal | None = None) -> Row:
    """The study row of a variant's report (see `Row` for each field),
    judged against the study's requirements and goal; a report marked
    incomplete is a failed row (with what it measured)."""
    judged = judge(report, requirements, goal) if (requirements or goal) and report.get("complete", True) else None
    summary = report["summary"]
    distances = [p["min_distance"] for p in report.get("pairs", ()) if p["type"] not in SHAPE_TYPES]
    cables = report.get("cables", ())
    strains = [c["max_strain"] for c in cables if c.get("max_strain") is not None]
    bends = [c["min_bend_radius"] for c in cables if c.get("min_bend_radius") is not None]
    validation = report.get("validation")
    complete = report.get("complete", True)
    return Row(
        id=id, values=tuple(values), status=Status.DONE if complete else Status.FAILED,
        error=None if complete else _stopped(report),
        exit_status=(1 if summary["hard"] > 0 else 0) if complete else
        3 if report.get("physics_error") else 4 if report.get("error") else None,
        hard=summary["hard"], soft=summary["soft"],
        worst_distance=min(distances) if distances else None,
        max_strain=max(strains, key=abs) if strains else None,
        min_bend_radius=min(bends) if bends else None,
        taut=any(c.get("taut", False) for c in cables),
        bend_violation=any(c.get("bend_violation", False) for c in cables),
        agreement=None if validation is None else validation.get("agreement"),
        run_time_s=report.get("timing", {}).get("total_s"),
        report=report_path, recording=recording,
        satisfied=None if judged is None or not requirements else judged.satisfied,
        margin=None if judged is None or not requirements else _finite(judged.margin),
        objective=None if judged is None else judged.objective,
        margins=() if judged is None else tuple(_finite(m) for m in judged.margins),
        at_least=() if judged is None else judged.at_least,
        cables=cable_rows(report))


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def _as_cable(row: Row, name: str) -> Row:
    """The row with one cable's events and flags in place of every cable's."""
    c = row.cable(name)
    if c is None:
        return row
    return replace(row, hard=c.hard, soft=c.soft, taut=c.taut, bend_violation=c.bend_violation)


def best_row(rows: list[Row]) -> Row | None:
    """The finished row scoring highest (`Row.score`: requirements met,
    then the goal, then the margin); the first of equals; None if none finished."""
    done = [r for r in rows if r.status is Status.DONE]
    return max(done, key=Row.score) if done else None


def fails(row: Row, level: str) -> bool:
    """The row fails `--fail-on level` ("hard", "soft" or "never"); a
    variant that did not finish fails unless the level is "never"."""
    if level == "never":
        return False
    if row.status is not Status.DONE:
        return True
    return row.hard > 0 or (level == "soft" and row.soft > 0)


def free_of_hard(rows: list[Row]) -> list[Row]:
    """The finished variants with no hard interference event."""
    return [r for r in rows if r.status is Status.DONE and r.hard == 0]


@dataclass(frozen=True)
class Window:
    """The interference-free window of a single varied cable length.

    Lengths are the tried values, in scene units. The true bounds lie
    between a bound and its neighbour outside the window (`below`, `above`).

    Attributes:
      shortest: the shortest length that is not taut; None if all were.
      below: the longest taut length shorter than `shortest`, or None.
      longest: the longest length without hard contact or bend violation;
        None if every length had one.
      above: the shortest length longer than `longest` that had one, or None.
      clean: the tried lengths in [shortest, longest] that are neither taut
        nor in hard contact nor bent too tight.
      quiet: the clean lengths with no soft event either (nothing came
        within the clearance).
      recommended: of the quiet lengths (or, when none is quiet, the clean
        ones), the one nearest the middle of the window, the shorter of two
        as near; None when no tried length is clean.
    """

    shortest: float | None
    below: float | None
    longest: float | None
    above: float | None
    clean: tuple[float, ...]
    quiet: tuple[float, ...]
    recommended: float | None

    @property
    def exists(self) -> bool:
        return self.recommended is not None


def length_window(rows: list[Row], index: int = 0, cable: str | None = None) -> Window:
    """The interference-free window over the finished rows, the length
    being `values[index]`: shortest length not taut, longest length with
    no hard contact and no bend violation. With `cable`, of that cable
    alone (the one whose length varies: another cable's contact is not
    this one's answer); else of every cable."""
    done = sorted((r for r in rows if r.status is Status.DONE), key=lambda r: r.values[index])
    if cable is not None:
        done = [_as_cable(r, cable) for r in done]
    lengths = [float(r.values[index]) for r in done]
    untaut = [L for L, r in zip(lengths, done) if not r.taut]
    shortest = min(untaut) if untaut else None
    below = max((L for L, r in zip(lengths, done) if r.taut and shortest is not None
                 and L < shortest), default=None)
    ok = [L for L, r in zip(lengths, done) if r.hard == 0 and not r.bend_violation]
    longest = max(ok) if ok else None
    above = min((L for L, r in zip(lengths, done) if (r.hard > 0 or r.bend_violation)
                 and longest is not None and L > longest), default=None)
    clean = tuple(L for L, r in zip(lengths, done)
                  if not r.taut and r.hard == 0 and not r.bend_violation
                  and shortest is not None and longest is not None and shortest <= L <= longest)
    soft = {L for L, r in zip(lengths, done) if r.soft > 0}
    quiet = tuple(L for L in clean if L not in soft)
    pool = quiet or clean
    recommended = None
    if pool:
        middle = 0.5 * (shortest + longest)
        recommended = min(pool, key=lambda L: (abs(L - middle), L))
    return Window(shortest=shortest, below=below, longest=longest, above=above, clean=clean,
                  quiet=quiet, recommended=recommended)
