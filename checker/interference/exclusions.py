"""Exclusion windows as arrays, built once per window list and selected per check.

A run hands the same list of :class:`~cablecheck.checker.scene_state.Exclusion` windows
to every check, but the checks ask for different cables (all of them in a
full check, one at a time in a second opinion) and different parts (every
part, or one). :func:`exclusion_arrays` turns a list into arrays once (cable
and part of each window as indices into the list's own names, the windows'
ends, the windows of each cable); :meth:`ExclusionArrays.table` then selects
the windows of given cables and parts without a loop over the windows.

Deliberately not here: what a window excuses (the cable-structure passes
of :mod:`~cablecheck.checker.interference.structure` apply it).
"""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from cablecheck.checker.scene_state import Exclusion

_MEMO = threading.local()
_MEMO_SIZE = 4


@dataclass(frozen=True)
class ExclusionTable:
    """The windows of some cables against some parts.

    Attributes:
        excl: (key, lo, hi, n_parts) sorted by key = cable * n_parts + part
            (what :mod:`~cablecheck.checker.interference.structure` takes),
            lo and hi each a window's ends as its points see them: an end
            inside the cable (not its start, not its end: ``Exclusion.to_end``)
            moved inwards by one ulp, so the point on it, which an element
            outside the window shares, is checked.
        cable, lo, hi: each window's cable (index into the asked cables) and
            ends, in the order of the window list.
    """

    excl: tuple
    cable: np.ndarray
    lo: np.ndarray
    hi: np.ndarray


@dataclass(frozen=True)
class ExclusionArrays:
    """One window list as arrays (:func:`exclusion_arrays`).

    Attributes:
        cable_index: each cable name of the list -> its index in ``groups``.
        part_names: the list's part names, each once.
        part: (E,) each window's part (index into ``part_names``).
        lo, hi: (E,) each window's ends (lo <= hi).
        point_lo, point_hi: (E,) the ends as the points see them
            (:attr:`ExclusionTable.excl`).
        groups: each cable's windows (indices into the list, ascending).
    """

    cable_index: Mapping[str, int]
    part_names: tuple[str, ...]
    part: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    point_lo: np.ndarray
    point_hi: np.ndarray
    groups: tuple[np.ndarray, ...]

    def part_map(self, part_index: Mapping[str, int]) -> np.ndarray:
        """(len(part_names),) each part of the list -> its index among a
        checker's parts (-1: not one of them)."""
        return np.array([part_index.get(n, -1) for n in self.part_names], dtype=np.int64)

    def table(self, cable_names: Sequence[str], part_map: np.ndarray, n_parts: int) -> ExclusionTable:
        """The windows of these cables against the parts of ``part_map``
        (:meth:`part_map`), ``n_parts`` parts in all."""
        asked = {n: i for i, n in enumerate(cable_names)}
        sel = [(j, i) for n, i in asked.items() if (j := self.cable_index.get(n)) is not None]
        if sel:
            rows = np.concatenate([self.groups[j] for j, _ in sel])
            cab = np.concatenate([np.full(len(self.groups[j]), i, np.int64) for j, i in sel])
            o = np.argsort(rows, kind="stable")          # back to the list's order
            rows, cab = rows[o], cab[o]
        else:
            rows, cab = np.zeros(0, np.int64), np.zeros(0, np.int64)
        part = part_map[self.part[rows]] if len(part_map) else np.zeros(0, np.int64)
        mine = part >= 0
        rows, cab, part = rows[mine], cab[mine], part[mine]
        lo, hi = self.lo[rows], self.hi[rows]
        n_parts = max(n_parts, 1)
        key = cab * n_parts + part
        o = np.argsort(key, kind="stable")
        return ExclusionTable((key[o], self.point_lo[rows][o], self.point_hi[rows][o], n_parts), cab, lo, hi)


def _build(exclusions: Sequence[Exclusion]) -> ExclusionArrays:
    cables = [e.cable for e in exclusions]
    parts = [e.part for e in exclusions]
    cable_names, cable = np.unique(np.array(cables, dtype=object), return_inverse=True) if cables \
        else (np.zeros(0, object), np.zeros(0, np.int64))
    part_names, part = np.unique(np.array(parts, dtype=object), return_inverse=True) if parts \
        else (np.zeros(0, object), np.zeros(0, np.int64))
    s = np.array([(e.s_min, e.s_max) for e in exclusions], dtype=float).reshape(-1, 2)
    lo, hi = np.minimum(s[:, 0], s[:, 1]), np.maximum(s[:, 0], s[:, 1])
    to_end = np.array([e.to_end for e in exclusions], bool)
    # the points on an end inside the cable belong to an element outside the window too
    point_lo = np.where(lo > 0.0, np.nextafter(lo, np.inf), lo)
    point_hi = np.where(to_end, hi, np.nextafter(hi, -np.inf))
    order = np.argsort(cable, kind="stable")
    bounds = np.searchsorted(cable[order], np.arange(len(cable_names) + 1))
    groups = tuple(order[bounds[j]:bounds[j + 1]] for j in range(len(cable_names)))
    return ExclusionArrays({str(n): j for j, n in enumerate(cable_names)}, tuple(str(n) for n in part_names),
                           np.asarray(part, np.int64).reshape(-1), lo, hi, point_lo, point_hi, groups)


def exclusion_arrays(exclusions: Sequence[Exclusion]) -> ExclusionArrays:
    """The window list as arrays. A run passes one list to every check: the
    arrays of the last few lists (and lengths) seen by this thread are kept,
    each with its list so its identity stays its own."""
    if not isinstance(exclusions, (list, tuple)):
        return _build(list(exclusions))
    memo = getattr(_MEMO, "entries", None)
    if memo is None:
        memo = _MEMO.entries = []
    for held, n, arrays in memo:
        if held is exclusions and n == len(exclusions):
            return arrays
    arrays = _build(exclusions)
    memo.insert(0, (exclusions, len(exclusions), arrays))
    del memo[_MEMO_SIZE:]
    return arrays
