"""The pieces every `cablecheck bench` table is made of: `Table` (printed as
a text block, written as CSV) and `median_time`, the one way a cell is timed.

Nothing here measures a particular thing (the table modules do:
`cablecheck.bench.checker_tables`, `cablecheck.bench.sim_tables`) or draws (`cablecheck.bench.plot`).
"""

from __future__ import annotations

import csv
import io
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


@dataclass
class Table:
    """One result table: a CSV file ``<name>.csv`` and a printed block."""

    name: str
    title: str
    columns: list[str]
    rows: list[list] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def add(self, *row) -> None:
        if len(row) != len(self.columns):
            raise ValueError(f"{self.name}: row of {len(row)} values for {len(self.columns)} columns")
        self.rows.append(list(row))

    def column(self, name: str) -> list:
        i = self.columns.index(name)
        return [r[i] for r in self.rows]

    def text(self) -> str:
        cells = [[_fmt(v) for v in r] for r in self.rows]
        widths = [max([len(c)] + [len(r[i]) for r in cells]) for i, c in enumerate(self.columns)]
        out = io.StringIO()
        out.write(f"\n{self.title}\n")
        out.write("  " + "  ".join(c.rjust(w) for c, w in zip(self.columns, widths)) + "\n")
        for r in cells:
            out.write("  " + "  ".join(v.rjust(w) for v, w in zip(r, widths)) + "\n")
        for n in self.notes:
            out.write(f"  - {n}\n")
        return out.getvalue()

    def write_csv(self, folder: Path) -> Path:
        path = folder / f"{self.name}.csv"
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(self.columns)
            for r in self.rows:
                w.writerow(["" if v is None else (f"{v:.6g}" if isinstance(v, float) else v) for v in r])
        return path


def median_time(fn: Callable[[], object], repeat: int) -> float:
    """Median wall seconds of `fn()` over `repeat` calls after one warm-up call."""
    fn()
    ts = []
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if v == 0.0 or not math.isfinite(v):
            return f"{v:g}"
        return f"{v:.3g}" if abs(v) < 1e4 else f"{v:.0f}"
    return str(v)


def text_table(cols: list[str], rows: list[list]) -> str:
    """Rows under right-aligned column names, floats to 3 decimals (the
    recording benchmarks' tables, printed only)."""
    fmt = lambda v: "-" if v is None else (f"{v:.3f}" if isinstance(v, float) else str(v))
    cells = [[fmt(v) for v in r] for r in rows]
    width = [max(len(c), *(len(r[k]) for r in cells)) for k, c in enumerate(cols)]
    return "\n".join(["  ".join(c.rjust(w) for c, w in zip(cols, width))]
                     + ["  ".join(v.rjust(w) for v, w in zip(r, width)) for r in cells])
