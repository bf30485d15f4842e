"""Clash status against an earlier run: which clashes are new, still present or resolved.

`cablecheck run --baseline EARLIER.json` reads an earlier run's report
(:func:`load_baseline`) and :func:`compare` matches this run's events to
its events: the same pair (type, a, b) at the same place along cable a,
within :data:`PLACE_RADII` of that cable's radius of arc length (parts
have no arc length: a part-part or keep-out pair of parts matches by the
pair alone). Not by time: a changed scene moves clashes in time. Each pair
of events is matched at most once, nearest places first. This run's events
are `new` or `present`; the earlier ones left unmatched are `resolved`.

Lengths are compared in metres whatever either report's units. A file that
is no cablecheck report is bad input (:class:`BaselineError`, exit status 2).

This module reads and compares; the report (`cablecheck.report.document`), the summary
(`cablecheck.cli.printing`) and the recording say the statuses.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

PLACE_RADII = 10.0
"""Two events of one pair are one clash when their worst places along cable
a lie within this many of its radii of arc length of each other."""

SCHEMA = "cablecheck.report/1"
UNITS = {"m": 1.0, "mm": 0.001}


class ClashStatus(str, Enum):
    """A clash against the baseline."""

    NEW = "new"
    PRESENT = "present"
    RESOLVED = "resolved"


class BaselineError(Exception):
    """An earlier report that cannot be used as a baseline (the file and why)."""

    def __init__(self, path: Path, problem: str):
        super().__init__(f"{path}: {problem}")
        self.path = path
        self.problem = problem


@dataclass(frozen=True)
class BaselineEvent:
    """An event of the earlier run, lengths in metres.

    Attributes:
        type, a, b: the pair; severity, phase: as reported.
        min_distance: worst signed distance, metres; t_worst: when, seconds.
        s: arc length along cable a at the worst place, metres.
    """

    type: str
    a: str
    b: str
    severity: str
    phase: str
    min_distance: float
    t_worst: float
    s: float


@dataclass(frozen=True)
class Baseline:
    """An earlier run's events (`path`: the report read)."""

    path: Path
    events: tuple[BaselineEvent, ...]


@dataclass(frozen=True)
class Comparison:
    """This run against the baseline.

    Attributes:
        path: the baseline report.
        status: per event of this run, in its order: new or present.
        resolved: the baseline's events no event of this run matched.
    """

    path: Path
    status: tuple[ClashStatus, ...]
    resolved: tuple[BaselineEvent, ...]

    def counts(self) -> dict[str, int]:
        """{"new": n, "present": n, "resolved": n}."""
        return {"new": sum(s is ClashStatus.NEW for s in self.status),
                "present": sum(s is ClashStatus.PRESENT for s in self.status),
                "resolved": len(self.resolved)}


def load_baseline(path: Path) -> Baseline:
    """The events of the report at `path`; BaselineError when it is unreadable
    or no cablecheck report."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except OSError as e:
        raise BaselineError(path, f"cannot be read ({e.strerror or e})") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise BaselineError(path, f"is not a JSON report ({e})") from None
    if not isinstance(data, dict) or data.get("schema") != SCHEMA:
        raise BaselineError(path, f"is not a cablecheck report (no \"schema\": \"{SCHEMA}\")")
    scale = UNITS.get(data.get("units"))
    if scale is None:
        raise BaselineError(path, f"has units {data.get('units')!r}, not one of {', '.join(UNITS)}")
    out = []
    try:
        for e in data["events"]:
            out.append(BaselineEvent(str(e["type"]), str(e["a"]), str(e["b"]), str(e["severity"]), str(e["phase"]),
                                     float(e["min_distance"]) * scale, float(e["t_worst"]), float(e["s"]) * scale))
    except (KeyError, TypeError, ValueError) as e:
        raise BaselineError(path, f"has an event without its type, pair, severity, distance, time or place ({e})") \
            from None
    return Baseline(path, tuple(out))


def compare(events: Sequence, radii: Mapping[str, float], baseline: Baseline) -> Comparison:
    """Match this run's `events` (records with type, a, b, s in metres) to the
    baseline's (module docstring); `radii`: each cable's radius, metres."""
    now = [(str(getattr(e.type, "value", e.type)), e.a, e.b, float(e.s)) for e in events]
    before = [(e.type, e.a, e.b, e.s) for e in baseline.events]
    candidates = []         # (place apart, this run's event, the baseline's)
    for i, (kind, a, b, s) in enumerate(now):
        reach = PLACE_RADII * radii.get(a, 0.0)
        for j, (kind_b, a_b, b_b, s_b) in enumerate(before):
            if (kind, a, b) == (kind_b, a_b, b_b) and abs(s - s_b) <= reach:
                candidates.append((abs(s - s_b), i, j))
    matched_now, matched_before = set(), set()
    for _, i, j in sorted(candidates):         # nearest places first, each event once
        if i not in matched_now and j not in matched_before:
            matched_now.add(i)
            matched_before.add(j)
    status = tuple(ClashStatus.PRESENT if i in matched_now else ClashStatus.NEW for i in range(len(now)))
    resolved = tuple(e for j, e in enumerate(baseline.events) if j not in matched_before)
    return Comparison(baseline.path, status, resolved)


def resolved_rows(comparison: Comparison, unit: float) -> list[dict]:
    """The resolved clashes as report rows, in scene units (`unit`: metres per unit)."""
    return [{"type": e.type, "a": e.a, "b": e.b, "severity": e.severity, "phase": e.phase,
             "t_worst": e.t_worst, "min_distance": e.min_distance / unit, "s": e.s / unit,
             "status": ClashStatus.RESOLVED.value}
            for e in sorted(comparison.resolved, key=lambda e: (e.min_distance, e.type, e.a, e.b))]

