"""`SceneError` and the helpers every table reader words its messages with.

A problem is reported as the file, the key path (``cables[1].radius``,
0-based indices) and the problem in words. This module formats; it checks
no value itself (`cablecheck.scene.reader` does).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any


class SceneError(Exception):
    """A scene file that cannot be used.

    Attributes:
      file: the scene file (as given to `load_scene` / `parse_scene`).
      key: where in the file: a key path such as ``cables[1].radius`` (0-based
        indices), ``line 3, column 5`` for TOML syntax, ``(file)`` for I/O.
      problem: what is wrong, in words.
    """

    def __init__(self, file: Path, key: str, problem: str):
        super().__init__(f"{file}: {key}: {problem}")
        self.file = file
        self.key = key
        self.problem = problem


def describe(value: Any) -> str:
    """A value's TOML type and (short) text, for error messages."""
    kinds = {bool: "a boolean", int: "an integer", float: "a float", str: "a string",
             list: "an array", dict: "a table"}
    kind = next((k for t, k in kinds.items() if type(value) is t), type(value).__name__)
    text = repr(value)
    return f"{kind} ({text if len(text) <= 40 else text[:37] + '...'})"


def join_key(where: str, key: str) -> str:
    """The key path of `key` inside the table at `where`."""
    return key if where == "(top level)" else f"{where}.{key}"


def fmt(value: float) -> str:
    """A number in a message: 6 significant digits."""
    return f"{value:.6g}"


def written(scene, metres: float) -> str:
    """A length in metres as a warning writes it, in `scene`'s units: 4 significant digits and the unit."""
    return f"{metres / scene.scale:.4g} {scene.units}"
