"""Index arithmetic shared by the vectorised passes.

Many passes expand "group i has count[i] items starting at start[i]" into
flat index arrays without a Python loop; `within` and `ranges` are that
expansion, and `products` every pair of two such groups, written once. `first_least` picks each group's least value
without sorting. `all_columns`, `max_columns` and `min_columns` are numpy's ``all``, ``max`` and ``min``
over ``axis=1`` for a few columns. This module holds no geometry.
"""

from __future__ import annotations

import numpy as np


def within(count: np.ndarray) -> np.ndarray:
    """0 .. count[i] - 1 for every group i, concatenated: (sum(count),)."""
    count = np.asarray(count, np.int64)
    return np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)


def all_columns(mask: np.ndarray) -> np.ndarray:
    """(n,) each row of a boolean (n, k) ``mask`` all true, for a few columns
    (a box test's three axes): the columns ANDed, the same answer as
    ``np.all(mask, axis=1)``, which costs ten times as much there
    (numpy's reduction, row by row)."""
    out = mask[:, 0]
    for k in range(1, mask.shape[1]):
        out = out & mask[:, k]
    return out


def max_columns(x: np.ndarray) -> np.ndarray:
    """(n,) each row's largest of an (n, k) array's few columns: ``np.max(x,
    axis=1)``'s values (NaN where a row holds one), at a fifth of its cost
    there (:func:`all_columns`)."""
    out = x[:, 0]
    for k in range(1, x.shape[1]):
        out = np.maximum(out, x[:, k])
    return out


def min_columns(x: np.ndarray) -> np.ndarray:
    """(n,) each row's least of an (n, k) array's few columns (:func:`max_columns`)."""
    out = x[:, 0]
    for k in range(1, x.shape[1]):
        out = np.minimum(out, x[:, k])
    return out


def ranges(start: np.ndarray, count: np.ndarray) -> np.ndarray:
    """start[i] .. start[i] + count[i] - 1 for every group i, concatenated."""
    return np.repeat(np.asarray(start, np.int64), count) + within(count)


def products(count_a: np.ndarray, count_b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every pair of group i's count_a[i] items on one side and count_b[i] on
    the other, group by group, the first side's outer: (group, x, y), each
    (sum(count_a * count_b),), with 0 <= x < count_a[group] and 0 <= y <
    count_b[group]."""
    count_b = np.asarray(count_b, np.int64)
    per = np.asarray(count_a, np.int64) * count_b
    group = np.repeat(np.arange(len(per)), per)
    r = within(per)
    nb = np.maximum(count_b[group], 1)
    return group, r // nb, r % nb


TABLE_KEYS = 1 << 16
"""`first_least` numbers the keys present through a table of this many
entries at most ..."""

TABLE_GROUPS = 1 << 18
"""... and finds the least per (state, key) in tables of this many; beyond
either it sorts."""


def first_least(state: np.ndarray, key: np.ndarray, value: np.ndarray, keys: int) -> np.ndarray:
    """The index of the least `value` of each distinct (state, key), the
    first of equal ones, in (state, key) order: what sorting the rows by
    (state, key, value, index) and taking each group's first gives.

    `state`, `key` (n,) non-negative ints, `key` below `keys`; `value` (n,).
    Without a sort (a sort of a few thousand rows by several keys costs
    milliseconds): the keys present are numbered in order through a table,
    then each group's least and its first row are found by unbuffered
    minima into tables of (states x keys present); a sort when those
    tables would be large, or a value is not finite."""
    state, key = np.asarray(state, np.int64), np.asarray(key, np.int64)
    value = np.asarray(value, float)
    n = len(value)
    if not n:
        return np.zeros(0, np.int64)
    if keys <= TABLE_KEYS and np.isfinite(value).all():
        present = np.zeros(keys, bool)
        present[key] = True
        number = np.cumsum(present) - 1
        groups = (int(state.max()) + 1) * (int(number[-1]) + 1)
        if groups <= TABLE_GROUPS:
            group = state * (int(number[-1]) + 1) + number.take(key)
            least = np.full(groups, np.inf)
            np.minimum.at(least, group, value)
            hit = np.flatnonzero(value == least.take(group))
            first = np.full(groups, n)
            np.minimum.at(first, group.take(hit), hit)
            return first[first < n]
    order = np.lexsort((np.arange(n), value, key, state))
    s, k = state[order], key[order]
    return order[np.r_[True, (s[1:] != s[:-1]) | (k[1:] != k[:-1])]]
