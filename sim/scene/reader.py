"""`Reader`: what reading one scene file needs at hand, and the readers of
single values (tables, numbers, names, vectors, lengths, file names).

Each value reader checks one TOML value and returns it converted (lengths
in metres) or raises `SceneError` naming the key path. The tables are read
by the modules named after them (`cablecheck.scene.settings`, `parts`, `cables`,
`motion`, `allow`), which take a `Reader` first; `cablecheck.scene.load` calls them
in order. A `Reader` also keeps what later tables need from earlier ones:
the scale, the mjcf model, the body frames at t = 0 and the meshes read.
"""

from __future__ import annotations

import difflib
import math
from pathlib import Path
from typing import Any

import numpy as np

from cablecheck.scene.errors import SceneError, describe, fmt, join_key
from cablecheck.scene.format import LARGEST
from cablecheck.scene.mjcf import MjcfInfo
from cablecheck.scene.records import Effects


def is_number(value: Any) -> bool:
    """An int or float that is not a bool (TOML's booleans are ints to Python)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


class Reader:
    """Reads the values of one scene file; holds the file for error messages.

    Attributes:
      file: the scene file as given; folder: its folder (relative file names
        are resolved against it).
      scale: metres per scene unit (1.0 until `[scene] units` is read).
      mjcf: the compiled base model, or None.
      frames: body name -> (origin, rotation) at t = 0; the mjcf bodies are
        None until the motions are read.
      body_index: `[[bodies]]` name -> its key path.
      effects_read: the `[effects]` table once read.
      meshes: mesh file -> its mesh nodes, read once per file.
    """

    def __init__(self, file: Path):
        self.file = file
        self.meshes: dict[Path, list] = {}
        self.folder = file.parent
        self.scale = 1.0
        self.mjcf: MjcfInfo | None = None
        self.frames: dict[str, tuple[np.ndarray, np.ndarray] | None] = {}
        self.body_index: dict[str, str] = {}
        self.effects_read = Effects()

    def error(self, key: str, problem: str) -> SceneError:
        return SceneError(self.file, key, problem)

    def table(self, value: Any, where: str, allowed: tuple[str, ...],
              required: tuple[str, ...] = ()) -> dict:
        """Check that `value` is a table with only `allowed` keys and all `required` ones."""
        if not isinstance(value, dict):
            raise self.error(where, f"expected a table, got {describe(value)}")
        for key in value:
            if key not in allowed:
                close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.6)
                hint = (f"did you mean '{close[0]}'?" if close
                        else "valid keys: " + ", ".join(allowed))
                raise self.error(join_key(where, key), f"unknown key ({hint})")
        for key in required:
            if key not in value:
                raise self.error(join_key(where, key), "missing (required)")
        return value

    def tables(self, value: Any, where: str) -> list:
        """An array of tables (`[[where]]`)."""
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.error(where, f"expected an array of tables ([[{where}]]), "
                                    f"got {describe(value)}")
        return value

    def number(self, value: Any, where: str, *, positive: bool = False,
               nonnegative: bool = False) -> float:
        if not is_number(value):
            raise self.error(where, f"expected a number, got {describe(value)}")
        if isinstance(value, float) and not math.isfinite(value):
            raise self.error(where, f"must be a finite number, got {value}")
        if abs(value) > LARGEST:
            raise self.error(where, f"out of range: magnitude above {LARGEST:g}")
        value = float(value)
        if positive and value <= 0:
            raise self.error(where, f"must be positive, got {fmt(value)}")
        if nonnegative and value < 0:
            raise self.error(where, f"must not be negative, got {fmt(value)}")
        return value

    def integer(self, value: Any, where: str, minimum: int) -> int:
        if not isinstance(value, int) or isinstance(value, bool):
            raise self.error(where, f"expected an integer, got {describe(value)}")
        if value < minimum:
            raise self.error(where, f"must be at least {minimum}, got {value}")
        return value

    def boolean(self, value: Any, where: str) -> bool:
        if not isinstance(value, bool):
            raise self.error(where, f"expected true or false, got {describe(value)}")
        return value

    def string(self, value: Any, where: str, choices: tuple[str, ...] | None = None) -> str:
        if not isinstance(value, str):
            raise self.error(where, f"expected a string, got {describe(value)}")
        if choices is not None and value not in choices:
            raise self.error(where, f"must be one of {', '.join(map(repr, choices))}, "
                                    f"got {value!r}")
        return value

    def name(self, value: Any, where: str) -> str:
        value = self.string(value, where)
        if not value.strip():
            raise self.error(where, "must not be empty")
        return value

    def vector(self, value: Any, where: str, length: int = 3) -> tuple[float, ...]:
        if not isinstance(value, list):
            raise self.error(where, f"expected an array of {length} numbers, "
                                    f"got {describe(value)}")
        if len(value) != length:
            raise self.error(where, f"expected {length} numbers, got {len(value)}")
        return tuple(self.number(v, f"{where}[{i}]") for i, v in enumerate(value))

    def length(self, value: Any, where: str, **kw) -> float:
        """A length in scene units, returned in metres."""
        return self.number(value, where, **kw) * self.scale

    def position(self, value: Any, where: str) -> tuple[float, float, float]:
        """A (3,) position in scene units, returned in metres."""
        return tuple(v * self.scale for v in self.vector(value, where))

    def point_list(self, value: Any, where: str) -> np.ndarray:
        """An array of 3-vectors in scene units, returned as a read-only (k, 3) in metres."""
        if not isinstance(value, list):
            raise self.error(where, f"expected an array of [x, y, z] points, "
                                    f"got {describe(value)}")
        out = np.array([self.vector(v, f"{where}[{i}]") for i, v in enumerate(value)],
                       float).reshape(-1, 3) * self.scale
        out.setflags(write=False)
        return out

    def file_path(self, value: Any, where: str) -> Path:
        """A path relative to the scene file, which must exist as a file."""
        text = self.name(value, where)
        try:
            path = (self.folder / text).resolve()
            found = path.is_file()
        except (OSError, ValueError):      # a NUL byte, a name too long for the file system
            raise self.error(where, f"not a usable file name: {text!r}") from None
        if not found:
            raise self.error(where, f"file not found: {path}")
        return path

    def unique(self, records: tuple, where: str, kind: str) -> None:
        seen: dict[str, int] = {}
        for i, record in enumerate(records):
            if record.name in seen:
                raise self.error(f"{where}[{i}].name", f"duplicate {kind} name "
                                 f"{record.name!r} (also {where}[{seen[record.name]}])")
            seen[record.name] = i

    def unit_name(self) -> str:
        """The scene's units, for messages."""
        return "m" if self.scale == 1.0 else "mm"
