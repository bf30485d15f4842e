"""What the HTML report shows of each clash beyond the JSON report, kept while a run runs.

A run asked for an HTML report (`--html`) hands an :class:`EvidenceKeeper`
each batch of checked states. It keeps, cheaply, what the pictures and the
plots need and nothing more: per event, the simulation's qpos at the state
where the event last deepened (its worst instant: one vector per event,
overwritten as the event deepens, never a list of states), and per pair
that came below the clearance its distance at each checked step where the
checker recorded it, with the pair's nearest candidate distance at full
checks (the approach before and after), sampled at most every
:data:`NEAR_INTERVAL` simulated seconds. :meth:`EvidenceKeeper.result`
gives, per event of the run, a frozen :class:`ClashEvidence`.

This module decides nothing (events are `cablecheck.checker.events`'),
renders nothing (`cablecheck.report.render`) and lays nothing out
(`cablecheck.report.html`). It does not import MuJoCo.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

NEAR_INTERVAL = 0.01
"""Simulated seconds between two samples of the near pairs' distances (the
recording's rate); distances below the clearance are kept at every checked step."""

PairKey = tuple[str, str, str]
"""(type, a, b) as the report writes them."""


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a, float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class ClashEvidence:
    """One event's picture state and its pair's distance history (metres, seconds).

    Attributes:
      t_spot: the time of the state kept for the picture (the event's worst), or None.
      qpos: the simulation's qpos at that state (read-only), or None when no
        state was kept (a static check, or an event that deepened in no kept state).
      t, distance: the pair's distance history over the run, by time (read-only):
        the recorded distance at every checked step it was below the clearance,
        and the nearest candidate's at sampled full checks around that.
    """

    t_spot: float | None
    qpos: np.ndarray | None
    t: np.ndarray
    distance: np.ndarray


@dataclass(frozen=True)
class Pictures:
    """The clash pictures of a run (`cablecheck.report.render`).

    Attributes:
      png: per event (the report's order), a PNG image, or None where none was made.
      renderer: the OpenGL platform used ("egl" or "osmesa"), or None when nothing rendered.
      warnings: why pictures are missing, in words (empty when every event has one).
    """

    png: tuple[bytes | None, ...]
    renderer: str | None
    warnings: tuple[str, ...]


@dataclass(frozen=True)
class HtmlEvidence:
    """What the HTML report takes from a run besides its report dict.

    Attributes:
      clashes: per event (the report's order), its evidence.
      pictures: the events' pictures.
    """

    clashes: tuple[ClashEvidence, ...]
    pictures: Pictures


def _key(kind, a: str, b: str) -> PairKey:
    return (str(getattr(kind, "value", kind)), a, b)


class EvidenceKeeper:
    """Per event its worst state's qpos, per pair its distance history (module docstring).

    `near_distances(near)`: the pairs' least distances among a full check's
    candidates (`StepResult.near`), as {(type, a, b): metres}.
    """

    def __init__(self, near_distances: Callable[[tuple], dict] | None = None):
        self._near_distances = near_distances
        self._spots: dict[tuple, tuple[float, np.ndarray]] = {}
        self._below: dict[PairKey, dict[float, float]] = {}
        self._near: dict[PairKey, dict[float, float]] = {}
        self._next_near = -np.inf

    def take(self, states: Sequence, results: Sequence, deepest: dict[tuple, int]) -> None:
        """A batch: its states and their results, and `deepest`: (pair key,
        t_start) of each event -> the index of the batch's state where it last
        deepened (`cablecheck.checker.events.EventTracker.worst_at`)."""
        for (key, t_start), k in deepest.items():
            self._spots[(_key(*key), float(t_start))] = (float(states[k].t), states[k].qpos)
        for state, res in zip(states, results):
            t = float(state.t)
            for r in res.records:
                row = self._below.setdefault(_key(r.type, r.a, r.b), {})
                d = float(r.min_distance)
                if d < row.get(t, np.inf):
                    row[t] = d
            if res.near is not None and self._near_distances is not None and t >= self._next_near:
                self._next_near = t + NEAR_INTERVAL
                for key, d in self._near_distances(res.near).items():
                    self._near.setdefault(_key(*key), {})[t] = float(d)

    def result(self, events: Sequence) -> tuple[ClashEvidence, ...]:
        """Per event (in the order given), its evidence."""
        out = []
        for e in events:
            key = _key(e.type, e.a, e.b)
            spot = self._spots.get((key, float(e.t_start)))
            merged = dict(self._near.get(key, {}))
            merged.update(self._below.get(key, {}))      # the recorded distance where both are known
            times = np.array(sorted(merged), float)
            out.append(ClashEvidence(
                t_spot=None if spot is None else spot[0],
                qpos=None if spot is None else _frozen(np.array(spot[1], float)),
                t=_frozen(times), distance=_frozen(np.array([merged[t] for t in times.tolist()], float))))
        return tuple(out)
