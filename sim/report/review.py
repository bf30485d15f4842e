"""A reviewer's notes on clashes, carried into a run's report: `cablecheck run --review NOTES.toml`.

Notes file::

    [[review]]
    a = "signal"                       # a cable, a part or an assembly path
    b = "j2s7s300_link_3"              # the other side (either order)
    status = "approved"                # "reviewed" or "approved"
    comment = "rests on the sleeve; accepted at the design review"
    type = "cable-structure"           # optional: only this kind of pair

An entry covers an event when its two names cover the event's two sides,
in either order (a cable by its name, a part by its name or an assembly
path above it) and, when given, its type is the event's. Each event takes
the first entry that covers it; an entry that covers no event of the run
is listed as unmatched (a fixed clash, a renamed part: never dropped
silently). A file that cannot be used is bad input (:class:`ReviewError`,
exit status 2) naming the file, the key and the problem.

This module reads and matches; the report (`cablecheck.report.document`) and the summary
(`cablecheck.cli.printing`) say the notes. Status against an earlier run (new,
present, resolved) is `cablecheck.report.baseline`'s.
"""

from __future__ import annotations

import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

from cablecheck.scene.allow import covers

_KEYS = ("a", "b", "status", "comment", "type")
PAIR_TYPES = ("self", "cable-cable", "cable-structure", "keepout", "part-part", "bend", "taut")


class ReviewStatus(str, Enum):
    """What a reviewer said of a clash."""

    REVIEWED = "reviewed"   # looked at; still to decide
    APPROVED = "approved"   # accepted as it is


class ReviewError(Exception):
    """A notes file that cannot be used: the file, the key and the problem."""

    def __init__(self, path: Path, key: str, problem: str):
        super().__init__(f"{path}: {key}: {problem}")
        self.path, self.key, self.problem = path, key, problem


@dataclass(frozen=True)
class ReviewNote:
    """One ``[[review]]`` entry (``index``: its place in the file)."""

    index: int
    a: str
    b: str
    status: ReviewStatus
    comment: str
    type: str | None = None

    def covers(self, event) -> bool:
        """The note is about this event's pair (either order)."""
        if self.type is not None and str(getattr(event.type, "value", event.type)) != self.type:
            return False
        return ((covers(self.a, (event.a,)) and covers(self.b, (event.b,)))
                or (covers(self.a, (event.b,)) and covers(self.b, (event.a,))))


@dataclass(frozen=True)
class ReviewMatch:
    """The notes against one run's events.

    Attributes:
      path: the notes file.
      notes: every entry, in file order.
      per_event: for each event (in the run's order), its note or None.
      unmatched: the notes that cover no event of the run.
    """

    path: Path
    notes: tuple[ReviewNote, ...]
    per_event: tuple[ReviewNote | None, ...]
    unmatched: tuple[ReviewNote, ...]


def load_review(path: Path) -> tuple[ReviewNote, ...]:
    """The notes of a file; ReviewError for a file that cannot be used."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ReviewError(path, "(file)", "not found") from None
    except (OSError, UnicodeDecodeError) as e:
        raise ReviewError(path, "(file)", f"cannot be read: {e}") from None
    except tomllib.TOMLDecodeError as e:
        raise ReviewError(path, "(file)", f"is not TOML: {e}") from None
    extra = [k for k in data if k != "review"]
    if extra:
        raise ReviewError(path, extra[0], "unknown table (a notes file holds [[review]] entries)")
    entries = data.get("review", [])
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise ReviewError(path, "review", "expected [[review]] tables")
    return tuple(_note(path, i, e) for i, e in enumerate(entries))


def match(path: Path, notes: Sequence[ReviewNote], events: Sequence) -> ReviewMatch:
    """Each event's first covering note, and the notes that cover none."""
    per_event = tuple(next((n for n in notes if n.covers(e)), None) for e in events)
    used = {id(n) for n in per_event if n is not None}
    unmatched = tuple(n for n in notes if id(n) not in used and not any(n.covers(e) for e in events))
    return ReviewMatch(Path(path), tuple(notes), per_event, unmatched)


def _note(path: Path, i: int, entry: dict) -> ReviewNote:
    where = f"review[{i}]"
    for k in entry:
        if k not in _KEYS:
            raise ReviewError(path, f"{where}.{k}", f"unknown key (known: {', '.join(_KEYS)})")
    for k in ("a", "b", "status"):
        if k not in entry:
            raise ReviewError(path, f"{where}.{k}", "missing")
    for k in ("a", "b", "comment", "status", "type"):
        if k in entry and (not isinstance(entry[k], str) or (k != "comment" and not entry[k].strip())):
            raise ReviewError(path, f"{where}.{k}", f"expected a non-empty string, got {entry[k]!r}")
    try:
        status = ReviewStatus(entry["status"])
    except ValueError:
        raise ReviewError(path, f"{where}.status", "expected 'reviewed' or 'approved', "
                                                   f"got {entry['status']!r}") from None
    kind = entry.get("type")
    if kind is not None and kind not in PAIR_TYPES:
        raise ReviewError(path, f"{where}.type", f"expected one of {', '.join(PAIR_TYPES)}, got {kind!r}")
    return ReviewNote(i, entry["a"], entry["b"], status, entry.get("comment", ""), kind)
