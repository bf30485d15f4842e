"""Output paths checked before any work starts.

A run may take minutes; a report path that names a folder, or sits under a
file, must fail at once with the option and the problem, not after the run
with the name of a temporary file. `check_output` answers "can a file be
written at this path?" without writing it: the path must not be a folder,
every existing ancestor must be a folder, and the deepest existing one must
be writable (missing folders are created when the output is written).

This module does not write outputs (see `cablecheck.report.document.write_report` and
`cablecheck.record.Recorder`, which write atomically).
"""

from __future__ import annotations

import os
from pathlib import Path


class OutputPathError(Exception):
    """An output path that cannot be written.

    Attributes:
      option: the command-line option that gave it (``--report``, ``--record``,
        ``--out``) or ``(default)`` wording for a default path.
      path: the path.
      problem: what is wrong, in words.
    """

    def __init__(self, option: str, path: Path, problem: str):
        super().__init__(f"{option} {path}: {problem}")
        self.option = option
        self.path = path
        self.problem = problem


def check_output(path: Path, option: str) -> Path:
    """Raise OutputPathError unless a file can be written at `path`; return it."""
    path = Path(path)
    if path.is_dir():
        raise OutputPathError(option, path, "is a folder; give a file name")
    if path.name in ("", ".", ".."):
        raise OutputPathError(option, path, "names no file")
    return _writable_below(path.absolute().parent, path, option)


def check_folder(path: Path, option: str) -> Path:
    """Raise OutputPathError unless `path` is (or can be made) a writable folder."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputPathError(option, path, "is a file; give a folder")
    return _writable_below(path.absolute(), path, option)


def _writable_below(folder: Path, path: Path, option: str) -> Path:
    """`path` when the deepest existing ancestor of `folder` (itself included)
    is a folder we may write in (the missing ones below it can be made)."""
    while not folder.exists():
        folder = folder.parent
    if not folder.is_dir():
        raise OutputPathError(option, path, f"{folder} is a file, not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputPathError(option, path, f"no permission to write in {folder}")
    return path
