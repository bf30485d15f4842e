"""The JSON report: plain-data assembly and an atomic write.

`write_report` writes to a temporary file in the target folder, flushes and
fsyncs it, then renames it over the target, so a reader never sees a
half-written report and an earlier report is replaced only by a complete
one. Numbers are converted to plain floats and rounded to what they mean
(distances to 1e-9 scene units), and non-finite values become null: JSON has
no NaN.

This module does not decide what goes into the report (the run does) and
does not know MuJoCo.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

SCHEMA = "cablecheck.report/1"


def plain(value: Any) -> Any:
    """`value` with numpy scalars/arrays, tuples and paths made JSON-ready."""
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return plain(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        f = float(value)
        return round(f, 12) if math.isfinite(f) else None
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "value") and isinstance(getattr(value, "value"), str):  # str enums
        return value.value
    return value


def write_report(report: dict, path: Path) -> None:
    """Write `report` as JSON to `path` atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(plain(report), indent=1, allow_nan=False)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.write("\n")
            f.flush()
            os.fsync(f.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes it private; a report is not
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
