"""A motion's CSV file of samples: the header (``t`` first), the numbers and
each row's line number, every problem named by line and column.

Which joint or body a column drives, and the conversion to MuJoCo units,
are `cablecheck.scene.motion`'s; this module only reads the table.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from cablecheck.scene.errors import SceneError, fmt
from cablecheck.scene.format import LARGEST


def read_samples(scene: Path, path: Path, written: str, where: str
                 ) -> tuple[list[str], np.ndarray, list[int]]:
    """The CSV motion file `path` (named `written` at key `where` of the
    scene file `scene`): its header (``t`` first), its (n, columns) numbers
    and each row's line number. Blank lines are skipped; every cell must be
    a finite number, t not negative and strictly increasing."""
    def fail(problem: str) -> SceneError:
        return SceneError(scene, where, f"{written}: {problem}")

    try:
        text = path.read_bytes().decode("utf-8-sig")
    except OSError as e:
        raise fail(f"cannot read: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise fail(f"not UTF-8 text (byte {e.start}: {e.reason})") from None
    reader = csv.reader(io.StringIO(text))
    rows, lines = [], []
    try:
        for row in reader:
            if any(cell.strip() for cell in row):
                rows.append([cell.strip() for cell in row])
                lines.append(reader.line_num)
    except csv.Error as e:
        raise fail(f"line {reader.line_num}: not CSV: {e}") from None
    if not rows:
        raise fail("empty: expected a header 't,<joint or body.axis>,...' and rows")
    header = rows[0]
    if header[0] != "t":
        raise fail(f"line {lines[0]}: the header's first column must be 't' (time, s), "
                   f"got {header[0]!r}")
    if len(header) < 2:
        raise fail(f"line {lines[0]}: the header names no joint or body column")
    for c, name in enumerate(header):
        if not name:
            raise fail(f"line {lines[0]}: column {c + 1} of the header is empty")
        if name in header[:c]:
            raise fail(f"line {lines[0]}: column {name!r} appears twice")
    body = rows[1:]
    if not body:
        raise fail("no samples: the header is the only row")
    for row, line in zip(body, lines[1:]):
        if len(row) != len(header):
            raise fail(f"line {line}: {len(row)} cell{'s' * (len(row) != 1)}, the header "
                       f"has {len(header)}")
    try:
        table = np.array(body, dtype=float)
    except ValueError:   # find the cell numpy could not read
        for r, row in enumerate(body):
            for c, cell in enumerate(row):
                try:
                    float(cell)
                except ValueError:
                    raise fail(f"line {lines[r + 1]}, column {header[c]!r}: not a number: "
                               f"{cell!r}") from None
        raise
    finite = np.isfinite(table) & (np.abs(table) <= LARGEST)
    if not finite.all():
        r, c = np.argwhere(~finite)[0]
        raise fail(f"line {lines[r + 1]}, column {header[c]!r}: not a finite number of "
                   f"magnitude at most {LARGEST:g}: {body[r][c]!r}")
    t = table[:, 0]
    if t[0] < 0:
        raise fail(f"line {lines[1]}, column 't': must not be negative, got {fmt(t[0])}")
    steps = np.flatnonzero(np.diff(t) <= 0)
    if len(steps):
        r = steps[0] + 1
        raise fail(f"line {lines[r + 1]}, column 't': times must increase strictly: "
                   f"{fmt(t[r])} after {fmt(t[r - 1])} (line {lines[r]})")
    return header, table, lines[1:]
