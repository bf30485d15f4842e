"""What a study asks of a variant: requirements that must hold, a goal to make best, judged on its report.

Study file::

    [[require]]
    clearance = 0.005                       # least distance between these, scene units
    between = ["signal", "j2s7s300_link_3"] # two names: cables, parts or assembly paths
    [[require]]
    no_hard = true                          # no hard contact of these cables (default: all)
    cables = ["signal"]
    [[require]]
    min_bend_radius = 0.03                  # also: max_strain = 0.01, taut = false
    [goal]
    maximise = "clearance"                  # between = [...]; or minimise = "length" | "wear"

Every requirement has a margin in scene units, negative where it fails: a
clearance's least distance less the limit; ``no_hard``'s least distance of
the cables to anything (hard below 0); a bend limit's least bend radius less
the limit; a strain limit (and ``taut = false``, the taut strain) the strain
left times the cable's length. Distances come from the report's
``closest`` (every pair within its reach, and every pair below the
clearance): where nothing of the two came within the reach, the distance is
at least the reach and the margin is a lower bound (``at_least``).

This module reads study tables and report dicts; it runs nothing and writes
nothing (see `cablecheck.study.execute`, `cablecheck.study.plot`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from typing import Any

from cablecheck.checker.cable import TAUT_STRAIN
from cablecheck.scene.allow import covers as covers_part

APPROACH_TYPES = ("cable-structure", "keepout", "cable-cable", "self", "part-part")
"""Report pair types that are distances between two things (not bend or taut)."""


class Need(Enum):
    """What a requirement asks."""

    CLEARANCE = "clearance"
    NO_HARD = "no_hard"
    MIN_BEND = "min_bend_radius"
    MAX_STRAIN = "max_strain"
    NOT_TAUT = "taut"


class Aim(Enum):
    """What a goal makes best."""

    CLEARANCE = "clearance"     # maximise the least distance between two names
    LENGTH = "length"           # minimise the cables' length
    WEAR = "wear"               # minimise the most sliding at one place of a cable


@dataclass(frozen=True)
class Requirement:
    """One ``[[require]]`` table.

    Attributes:
      need: what it asks; limit: its number (None for no_hard and taut).
      between: for a clearance, the two names (each a cable, a part or an
        assembly path).
      cables: the cables it concerns (empty: every cable).
      label: short words for tables ("clearance signal~link_3 >= 0.005").
    """

    need: Need
    limit: float | None
    between: tuple[str, str] | None
    cables: tuple[str, ...]
    label: str


@dataclass(frozen=True)
class Goal:
    """The ``[goal]`` table: what to make best (see `Aim`)."""

    aim: Aim
    between: tuple[str, str] | None
    cables: tuple[str, ...]
    label: str


@dataclass(frozen=True)
class Judgement:
    """A variant's report against the study's requirements and goal.

    Attributes:
      margins: per requirement, its margin in scene units (inf where
        nothing limits it, e.g. a straight cable's bend).
      at_least: per requirement, the margin is a lower bound (nothing of
        the two came within the report's reach).
      satisfied: every requirement holds (margin >= 0).
      margin: the least margin (inf without requirements).
      objective: the goal's value, larger is better (a length or wear
        to minimise is negated); None without a goal.
    """

    margins: tuple[float, ...]
    at_least: tuple[bool, ...]
    satisfied: bool
    margin: float
    objective: float | None



class GoalError(ValueError):
    """A requirement or goal table that cannot be used: (where, problem)."""


def parse_requirements(entries: Any) -> tuple[Requirement, ...]:
    """The ``[[require]]`` tables; GoalError("require[i].key", problem) for a bad one."""
    if entries is None:
        return ()
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise GoalError("require", "expected [[require]] tables")
    return tuple(_requirement(e, f"require[{i}]") for i, e in enumerate(entries))


def parse_goal(table: Any) -> Goal | None:
    """The ``[goal]`` table, or None; GoalError for a bad one."""
    if table is None:
        return None
    if not isinstance(table, dict):
        raise GoalError("goal", "expected a table")
    _only(table, "goal", ("maximise", "minimise", "between", "cables"))
    if ("maximise" in table) == ("minimise" in table):
        raise GoalError("goal", "give one of 'maximise' or 'minimise'")
    word = "maximise" if "maximise" in table else "minimise"
    allowed = {"maximise": ("clearance",), "minimise": ("length", "wear")}[word]
    what = table[word]
    if what not in allowed:
        raise GoalError(f"goal.{word}", f"expected one of {', '.join(map(repr, allowed))}, got {what!r}")
    aim = Aim(what)
    between = _between(table, "goal") if aim is Aim.CLEARANCE else None
    if aim is not Aim.CLEARANCE and "between" in table:
        raise GoalError("goal.between", f"only for maximise = 'clearance', not {word} = {what!r}")
    cables = _names(table.get("cables", []), "goal.cables")
    label = (f"most clearance {between[0]}~{between[1]}" if aim is Aim.CLEARANCE
             else f"least {what}" + (f" of {', '.join(cables)}" if cables else ""))
    return Goal(aim, between, cables, label)


def check_names(requirements: tuple[Requirement, ...], goal: Goal | None, cables: set[str],
                parts: set[str], bodies: set[str] = frozenset()) -> tuple[str, str] | None:
    """The first (where, problem) of a name that covers no cable or part of
    the scene (nor begins with one of ``bodies``, an mjcf model's, whose
    geoms' parts are named "body/geom"), or None."""
    items = [(f"require[{i}]", r.between, r.cables) for i, r in enumerate(requirements)]
    if goal is not None:
        items.append(("goal", goal.between, goal.cables))
    for where, between, named in items:
        for name in between or ():
            if not covers(name, cables, parts) and name.split("/")[0] not in bodies:
                return f"{where}.between", f"{name!r} names no cable or part of the scene"
        for name in named:
            if name not in cables:
                return f"{where}.cables", f"{name!r} is not a cable of the scene"
    return None


def covers(name: str, cables: set[str] | tuple, parts: set[str] | tuple) -> bool:
    """The name is a cable, a part or an assembly path of some part."""
    return name in cables or covers_part(name, parts)


def judge(report: dict, requirements: tuple[Requirement, ...], goal: Goal | None) -> Judgement:
    """The report of one variant against the requirements and the goal."""
    margins, bounds = [], []
    for r in requirements:
        m, at_least = _margin(report, r)
        margins.append(m)
        bounds.append(at_least)
    margin = min(margins, default=math.inf)
    return Judgement(tuple(margins), tuple(bounds), all(m >= 0.0 for m in margins), margin,
                     None if goal is None else _objective(report, goal))


# -- judging ------------------------------------------------------------------

def _pairs(report: dict) -> list[dict]:
    closest = report.get("closest") or {}
    return [p for p in closest.get("pairs", ()) if p["type"] in APPROACH_TYPES]


def _reach(report: dict) -> float:
    return float((report.get("closest") or {}).get("reach") or 0.0)


def _is(name: str, side: str, cables: set[str]) -> bool:
    """``side`` of a pair is covered by ``name`` (a cable name, or a part under it)."""
    return side == name if side in cables else covers_part(name, (side,))


def _least_between(report: dict, a: str, b: str) -> tuple[float, bool]:
    cables = {c["name"] for c in report.get("cables", ())}
    found = [p["min_distance"] for p in _pairs(report)
             if (_is(a, p["a"], cables) and _is(b, p["b"], cables))
             or (_is(b, p["a"], cables) and _is(a, p["b"], cables))]
    return (min(found), False) if found else (_reach(report), True)


def _least_of(report: dict, cables: tuple[str, ...]) -> tuple[float, bool]:
    names = set(cables) or {c["name"] for c in report.get("cables", ())}
    found = [p["min_distance"] for p in _pairs(report) if p["a"] in names or
             (p["type"] in ("cable-cable", "self") and p["b"] in names)]
    return (min(found), False) if found else (_reach(report), True)


def _cables(report: dict, names: tuple[str, ...]) -> list[dict]:
    return [c for c in report.get("cables", ()) if not names or c["name"] in names]


def _margin(report: dict, r: Requirement) -> tuple[float, bool]:
    if r.need is Need.CLEARANCE:
        d, at_least = _least_between(report, *r.between)
        return d - r.limit, at_least
    if r.need is Need.NO_HARD:
        return _least_of(report, r.cables)
    cables = _cables(report, r.cables)
    if r.need is Need.MIN_BEND:
        bends = [c["min_bend_radius"] for c in cables if c.get("min_bend_radius") is not None]
        return (min(bends) - r.limit if bends else math.inf), False
    limit = r.limit if r.need is Need.MAX_STRAIN else TAUT_STRAIN
    left = [(limit - abs(c["max_strain"]) if r.need is Need.MAX_STRAIN else limit - c["max_strain"])
            * c["length"] for c in cables if c.get("max_strain") is not None]
    return min(left, default=math.inf), False


def _objective(report: dict, goal: Goal) -> float:
    if goal.aim is Aim.CLEARANCE:
        return _least_between(report, *goal.between)[0]
    cables = _cables(report, goal.cables)
    if goal.aim is Aim.LENGTH:
        return -sum(c["length"] for c in cables)
    worn = [c["wear"]["most_worn"]["sliding"] for c in cables
            if c.get("wear") and c["wear"].get("most_worn")]
    return -max(worn, default=0.0)


# -- reading ------------------------------------------------------------------

_REQUIRE_KEYS = ("clearance", "between", "no_hard", "cables", "min_bend_radius", "max_strain", "taut")


def _requirement(entry: dict, where: str) -> Requirement:
    _only(entry, where, _REQUIRE_KEYS)
    asks = [k for k in ("clearance", "no_hard", "min_bend_radius", "max_strain", "taut") if k in entry]
    if len(asks) != 1:
        raise GoalError(where, "give exactly one of clearance, no_hard, min_bend_radius, max_strain, taut"
                        + (f" (got {', '.join(asks)})" if asks else ""))
    need = Need(asks[0])
    value = entry[asks[0]]
    cables = _names(entry.get("cables", []), f"{where}.cables")
    if need is Need.CLEARANCE:
        limit = _number(value, f"{where}.clearance")
        between = _between(entry, where)
        if "cables" in entry:
            raise GoalError(f"{where}.cables", "a clearance names its two sides in 'between'")
        return Requirement(need, limit, between, (), f"clearance {between[0]}~{between[1]} >= {limit:g}")
    if "between" in entry:
        raise GoalError(f"{where}.between", "only a clearance is between two names")
    scope = f" of {', '.join(cables)}" if cables else ""
    if need is Need.NO_HARD:
        if value is not True:
            raise GoalError(f"{where}.no_hard", f"expected true, got {value!r}")
        return Requirement(need, None, None, cables, f"no hard contact{scope}")
    if need is Need.NOT_TAUT:
        if value is not False:
            raise GoalError(f"{where}.taut", f"expected false (never taut), got {value!r}")
        return Requirement(need, None, None, cables, f"never taut{scope}")
    limit = _number(value, f"{where}.{need.value}")
    if need is Need.MIN_BEND:
        return Requirement(need, limit, None, cables, f"bend radius{scope} >= {limit:g}")
    return Requirement(need, limit, None, cables, f"strain{scope} <= {limit:g}")


def _only(table: dict, where: str, allowed: tuple[str, ...]) -> None:
    for k in table:
        if k not in allowed:
            raise GoalError(f"{where}.{k}", f"unknown key (known: {', '.join(allowed)})")


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
        raise GoalError(where, f"expected a number >= 0, got {value!r}")
    return float(value)


def _names(value: Any, where: str) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
        raise GoalError(where, f"expected an array of names, got {value!r}")
    return tuple(value)


def _between(table: dict, where: str) -> tuple[str, str]:
    value = table.get("between")
    if not isinstance(value, list) or len(value) != 2 or not all(isinstance(v, str) and v for v in value):
        raise GoalError(f"{where}.between", f"expected two names, got {value!r}")
    return value[0], value[1]

