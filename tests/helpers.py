"""Small helpers shared by test files. Not a test file."""

from __future__ import annotations

import os
from pathlib import Path

LONG = os.environ.get("HYPOTHESIS_PROFILE") == "long"
"""A long local run of the property tests (HYPOTHESIS_PROFILE=long, tests/conftest.py)."""


def examples(n: int) -> int:
    """``max_examples`` for a property test drawing scenes: ``n`` (what CI runs, derandomised),
    or 30 times as many under the long profile."""
    return 30 * n if LONG else n


def write_text(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path
