"""Small helpers shared by test files. Not a test file."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

LONG = os.environ.get("HYPOTHESIS_PROFILE") == "long"
"""A long local run of the property tests (HYPOTHESIS_PROFILE=long, tests/conftest.py)."""


def seeds(n: int) -> range:
    """Seeds of a parametrised test drawing whole scenes (seconds each): ``n``
    in CI, ten times as many under the long profile."""
    return range(10 * n if LONG else n)


def examples(n: int) -> int:
    """``max_examples`` for a property test drawing scenes: ``n`` (what CI runs, derandomised),
    or 30 times as many under the long profile."""
    return 30 * n if LONG else n


def write_text(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def recorded_rows(record: Path, entity: str) -> list[dict]:
    """Every row a rerun recording holds at `entity`, in time order: {column: value} plus "t" (s) or None
    for a static row."""
    return recorded_entities(record, entity, whole=True).get(entity, [])


def recorded_entities(record: Path, prefix: str, whole: bool = False) -> dict[str, list[dict]]:
    """The rows (as `recorded_rows` gives them) of every entity whose path starts with `prefix` (with
    `whole`: is `prefix`), read in one pass."""
    import pyarrow as pa
    from rerun.chunk import RrdReader

    found: dict[str, list[dict]] = {}
    for chunk in RrdReader(record).stream():
        path = chunk.entity_path
        if not (path == prefix if whole else path.startswith(prefix)):
            continue
        batch = chunk.to_record_batch()
        n = chunk.num_rows
        # sim_time in nanoseconds (not every one is a whole number of microseconds)
        times = (batch.column("sim_time").cast(pa.int64()).to_numpy() * 1e-9 if "sim_time" in batch.schema.names
                 else [None] * n)
        data = {k: batch.column(k).to_pylist() for k in batch.schema.names if "RowId" not in k and k != "sim_time"}
        rows = found.setdefault(path, [])
        for i in range(n):
            row = {k: v[i] for k, v in data.items()}
            row["t"] = None if times[i] is None else float(times[i])
            rows.append(row)
    return {path: sorted(rows, key=lambda r: (r["t"] is not None, r["t"] or 0.0)) for path, rows in found.items()}


def element_gaps(pa: np.ndarray, pb: np.ndarray) -> np.ndarray:
    """(m, na, nb) how far apart the bounding spheres (about each element's
    middle, half its length across) of every element pair of polylines pa
    (m, na + 1, 3) and pb (m, nb + 1, 3) are, state by state: the every-pair
    reference of `element_pairs_within` (and of `closest_elements`)."""
    from cablecheck.checker.closest import row_norm
    ma, mb = 0.5 * (pa[:, 1:] + pa[:, :-1]), 0.5 * (pb[:, 1:] + pb[:, :-1])
    ha, hb = 0.5 * row_norm(pa[:, 1:] - pa[:, :-1]), 0.5 * row_norm(pb[:, 1:] - pb[:, :-1])
    return row_norm(ma[:, :, None, :] - mb[:, None, :, :]) - ha[:, :, None] - hb[:, None, :]


def busy_states(n: int, seconds: float):
    """States 0 .. n - 1, each after `seconds` of the making thread's own CPU
    time (a simulation's cost, for the threads and processes that make them)."""
    for k in range(n):
        t = time.thread_time()
        while time.thread_time() - t < seconds:
            pass
        yield k
