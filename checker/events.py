"""Interference over time: events (intervals below the clearance) and worst pairs.

`EventTracker.update` takes each checked step's interference records and
keeps, per (type, a, b) pair, the interval it has stayed below the
clearance. An event is a maximal such interval; its severity is the worst it
reached (a record's severity is decided by `cablecheck.checker.records.severity_of`;
an event is hard once any of its records is), its `phase` (:class:`Phase`)
is static when it contains t = 0 (the settled rest state before motion) and
dynamic otherwise.

Flicker: a pair grazing the clearance can drop out for a step or two as the
cable vibrates. An open event is closed only after the pair has been clear
for `hold` seconds (by default three checked steps); a return within that
time continues the same event, and the event's `t_end` is the last time the
pair was below the clearance, so no clear time is counted as interference.

`pairs` keeps every pair that came below the clearance with its worst
distance and when.

Allowed pairs (:class:`AllowList`, the scene's ``[[allow]]``): contacts that
belong to the design (a robot base bolted to its table, a hinge pin through
its knuckles). Their records never open an event and are not in `pairs`;
`allowed` keeps each one's worst distance and when, with the rule's reason.
Bend and taut records (a single cable's measures) are never allowed.

This module does not check geometry or know MuJoCo: it takes records and
times.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np

from cablecheck.checker.records import Interference, PairType, Severity

PairKey = tuple[PairType, str, str]
"""(type, a, b) of a pair (a string enum: a key of plain strings finds it too)."""

_NEVER_ALLOWED = (PairType.BEND, PairType.TAUT)


class Phase(StrEnum):
    """When an event happened; the values are the report's ``phase``."""

    STATIC = "static"      # the event contains t = 0: the settled rest state, before any motion
    DYNAMIC = "dynamic"    # it started once the motion was under way


def phase_of(t_start: float) -> Phase:
    """The phase of an event that started at `t_start` (s)."""
    return Phase.STATIC if t_start <= 0.0 else Phase.DYNAMIC


@dataclass(frozen=True)
class AllowRule:
    """A pair of names whose contact is expected.

    Attributes:
      a, b: each a part name, an assembly path prefix ("cell/table" covers
        "cell/table/top") or a cable name.
      reason: why the contact is expected.
    """

    a: str
    b: str
    reason: str


def covered(pattern: str, name: str) -> bool:
    """`name` is `pattern` or lies under the assembly path `pattern`."""
    return name == pattern or name.startswith(pattern + "/")


class AllowList:
    """Which pairs the rules allow; each (type, a, b) is decided once."""

    def __init__(self, rules=()):
        self.rules = tuple(rules)
        self._seen: dict[PairKey, AllowRule | None] = {}

    def match(self, key: PairKey) -> AllowRule | None:
        """The first rule allowing the pair (type, a, b), or None."""
        try:
            return self._seen[key]
        except KeyError:
            pass
        kind, a, b = key
        rule = None
        if kind not in _NEVER_ALLOWED:
            rule = next((r for r in self.rules if (covered(r.a, a) and covered(r.b, b))
                         or (covered(r.a, b) and covered(r.b, a))), None)
        self._seen[key] = rule
        return rule

    def __bool__(self) -> bool:
        return bool(self.rules)


@dataclass(frozen=True)
class Event:
    """A maximal interval in which a pair stayed below the clearance.

    Attributes:
      type, a, b: the pair.
      severity: worst severity reached.
      phase: static when the interval contains t = 0, else dynamic.
      t_start, t_end: first and last checked time below the clearance, s.
      t_worst: time of the smallest distance, s.
      min_distance: smallest signed distance (units of the records).
      where: (3,) worst point on cable a.
      s: arc length along cable a at the worst point.
      s_b: for two cables (or a cable and itself), the arc length along b
        there; else None.
    """

    type: PairType
    a: str
    b: str
    severity: Severity
    phase: Phase
    t_start: float
    t_end: float
    t_worst: float
    min_distance: float
    where: np.ndarray
    s: float
    s_b: float | None = None


@dataclass(frozen=True)
class PairWorst:
    """A pair's worst moment over the whole run."""

    type: PairType
    a: str
    b: str
    min_distance: float
    t: float
    where: np.ndarray


@dataclass(frozen=True)
class AllowedWorst(PairWorst):
    """An allowed pair's worst moment over the whole run, and why it is allowed."""

    reason: str


@dataclass
class _Open:
    t_start: float
    t_last: float
    worst: Interference
    t_worst: float
    severity: Severity


@dataclass
class EventTracker:
    """Builds events from per-step records (see the module docstring).

    Attributes:
      hold: seconds a pair must stay clear before its event closes.
      allow: pairs that never make events (their worst goes to `allowed`).
    """

    hold: float
    allow: AllowList = field(default_factory=AllowList)
    events: list[Event] = field(default_factory=list)
    pairs: dict[PairKey, PairWorst] = field(default_factory=dict)
    allowed: dict[PairKey, AllowedWorst] = field(default_factory=dict)
    _open: dict[PairKey, _Open] = field(default_factory=dict)

    @staticmethod
    def key(record: Interference) -> PairKey:
        kind = record.type
        return (kind if type(kind) is PairType else PairType(kind), record.a, record.b)

    def update(self, t: float, records: Iterable[Interference]) -> tuple[list[PairKey], list[Event]]:
        """Take the records of the step at time t; return (pairs that started
        an event, events that closed)."""
        started: list[PairKey] = []
        seen = set()
        if not records and not self._open:      # most steps of a run: nothing to take or close
            return started, []
        allow = self.allow if self.allow else None
        for r in records:
            k = self.key(r)
            if allow is not None:
                rule = allow.match(k)
                if rule is not None:
                    best = self.allowed.get(k)
                    if best is None or r.min_distance < best.min_distance:
                        self.allowed[k] = AllowedWorst(k[0], r.a, r.b, float(r.min_distance), t,
                                                       np.asarray(r.where), rule.reason)
                    continue
            seen.add(k)
            severity = r.severity if type(r.severity) is Severity else Severity(r.severity)
            ev = self._open.get(k)
            if ev is None:
                ev = self._open[k] = _Open(t, t, r, t, severity)
                started.append(k)
            else:
                ev.t_last = t
                if severity is Severity.HARD:
                    ev.severity = severity
                if r.min_distance < ev.worst.min_distance:
                    ev.worst, ev.t_worst = r, t
            best = self.pairs.get(k)
            if best is None or r.min_distance < best.min_distance:
                self.pairs[k] = PairWorst(k[0], r.a, r.b, float(r.min_distance), t, np.asarray(r.where))
        closed = [self._close(k) for k, ev in list(self._open.items())
                  if k not in seen and t - ev.t_last >= self.hold - 1e-12]
        return started, closed

    @staticmethod
    def _event(k: PairKey, ev: _Open) -> Event:
        w = ev.worst
        return Event(k[0], w.a, w.b, ev.severity, phase_of(ev.t_start), ev.t_start, ev.t_last,
                     ev.t_worst, float(w.min_distance), np.asarray(w.where), float(w.s),
                     None if w.s_b is None else float(w.s_b))

    def _close(self, k: PairKey) -> Event:
        event = self._event(k, self._open.pop(k))
        self.events.append(event)
        return event

    def standing(self, k: PairKey) -> Event:
        """The open event of pair `k` as it stands (its worst and severity so far)."""
        return self._event(k, self._open[k])

    def finish(self) -> list[Event]:
        """Close every open event (end of run); return all events by start time."""
        for k in list(self._open):
            self._close(k)
        self.events.sort(key=lambda e: (e.t_start, e.type, e.a, e.b))
        return self.events

    def open_pairs(self) -> list[PairKey]:
        """Pairs with an event still open."""
        return list(self._open)

    def worst_at(self, t: float) -> list[tuple[PairKey, float]]:
        """(pair, t_start) of each open event whose worst so far is the step at time t
        (it deepened there, or started there)."""
        return [(k, ev.t_start) for k, ev in self._open.items() if ev.t_worst == t]
