"""Index arithmetic shared by the vectorised passes.

Many passes expand "group i has count[i] items starting at start[i]" into
flat index arrays without a Python loop; the two functions here are that
expansion, written once. This module holds no geometry.
"""

from __future__ import annotations

import numpy as np


def within(count: np.ndarray) -> np.ndarray:
    """0 .. count[i] - 1 for every group i, concatenated: (sum(count),)."""
    count = np.asarray(count, np.int64)
    return np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)


def ranges(start: np.ndarray, count: np.ndarray) -> np.ndarray:
    """start[i] .. start[i] + count[i] - 1 for every group i, concatenated."""
    return np.repeat(np.asarray(start, np.int64), count) + within(count)
