"""MuJoCo's own messages during a run: taken, counted by kind, never printed or written to a file.

MuJoCo reports warnings through a process-wide handler whose default
prints each message and appends it to `MUJOCO_LOG.TXT` in the working
directory. A run (`cablecheck.run.runner`) enters a `MujocoMessages` for its whole
length: MuJoCo's warnings then come to it instead (`mujoco.set_mju_user_warning`;
the Python bindings call it from whichever thread steps, so the simulation
stepping ahead on its own thread, `cablecheck.run.ahead`, is covered; one
stepping in a process of its own, `cablecheck.run.apart`, takes them there
and hands them back at its end: `MujocoMessages.add`), and the
default handler's log file is switched off (`mujoco.MjLogConfig`), so
nothing is written to the working directory and the terminal is not
flooded. What the messages said is kept for the report instead:
`warning_counts` counts MuJoCo's warnings by kind, from each data's own
counters (`mjData.warning`: MuJoCo only prints a kind's first occurrence,
its counter counts them all) and from the messages that belong to no
counted kind (for example the solver's "Linesearch objective is not
convex"), keyed by their text with numbers replaced by '#'.

Outside a run (the other commands, the tests) `log_file_off` keeps only
the file away: MuJoCo still prints its messages.

This module does not decide what a warning means for the run (see
`cablecheck.run.divergence`) and does not stop anything.
"""

from __future__ import annotations

import re
import threading
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager

import mujoco

_NUMBER = re.compile(r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")
_TIME = re.compile(r"\s*Time = [^ ]*$")


def _prefix(kind: int) -> str:
    """The text of MuJoCo's warning `kind` up to its first number (or its end)."""
    text = mujoco.mju_warningText(kind, 0)
    m = _NUMBER.search(text)
    return text[:m.start()] if m else text


_KINDS = tuple((_prefix(k), mujoco.mjtWarning(k).name) for k in range(int(mujoco.mjtWarning.mjNWARNING)))
"""(text prefix, name) of each of MuJoCo's counted warning kinds."""


def message_kind(message: str) -> str:
    """The kind of a MuJoCo message: the `mjtWarning` name it was raised
    as (e.g. "mjWARN_BADQACC"), else its text with the trailing time
    dropped and numbers replaced by '#'."""
    for prefix, name in _KINDS:
        if message.startswith(prefix):
            return name
    return _NUMBER.sub("#", _TIME.sub("", message.strip())).strip()


class MujocoMessages:
    """MuJoCo's warnings taken while entered (module docstring).

    Entering replaces MuJoCo's process-wide warning handler and turns its
    log file off; leaving puts both back as they were. Runs nest (the
    innermost takes the messages) but should not overlap on two threads.

    Attributes:
      counts: messages taken so far, by `message_kind`.
      first: the first message of each kind, as MuJoCo wrote it.
    """

    def __init__(self):
        self.counts: Counter[str] = Counter()
        self.first: dict[str, str] = {}
        self._lock = threading.Lock()
        self._old_handler = None
        self._old_file: bool | None = None

    def _take(self, message: str) -> None:
        kind = message_kind(message)
        with self._lock:
            self.counts[kind] += 1
            self.first.setdefault(kind, message.strip())

    def __enter__(self) -> "MujocoMessages":
        self._old_handler = mujoco.get_mju_user_warning()
        mujoco.set_mju_user_warning(self._take)
        self._old_file = _set_log_file(False)
        return self

    def __exit__(self, *exc) -> None:
        mujoco.set_mju_user_warning(self._old_handler)
        _set_log_file(self._old_file)

    def add(self, counts: dict[str, int], first: dict[str, str]) -> None:
        """Take messages counted elsewhere (a simulation stepped in another
        process, `cablecheck.run.apart`): `counts` by kind, `first` their first texts."""
        with self._lock:
            self.counts.update(counts)
            for kind, text in first.items():
                self.first.setdefault(kind, text)

    def others(self) -> dict[str, int]:
        """Counts of the messages that are not one of MuJoCo's counted kinds."""
        names = {name for _, name in _KINDS}
        with self._lock:
            return {k: n for k, n in self.counts.items() if k not in names}


def _set_log_file(on: bool) -> bool:
    """Turn the default handler's `MUJOCO_LOG.TXT` on or off; return what it was."""
    config = mujoco.MjLogConfig.get()
    old = bool(config.logto_file)
    config.logto_file = on
    config.set()
    return old


@contextmanager
def log_file_off() -> Iterator[None]:
    """MuJoCo's default handler writes no `MUJOCO_LOG.TXT` while entered (it still prints)."""
    old = _set_log_file(False)
    try:
        yield
    finally:
        _set_log_file(old)


def data_warnings(data: mujoco.MjData | None) -> dict[str, int]:
    """`data`'s warning counters by `mjtWarning` name, nonzero only."""
    if data is None:
        return {}
    return {mujoco.mjtWarning(i).name: int(w.number) for i, w in enumerate(data.warning) if w.number}


def warning_counts(datas, messages: MujocoMessages | None) -> dict[str, int]:
    """MuJoCo's warnings of a run by kind: the counters of every data it
    stepped or collided (`datas`, None entries skipped; a dict: the counters
    of a data stepped in another process, as `data_warnings` gives them),
    summed, and the `messages` of no counted kind; sorted by kind."""
    total: Counter[str] = Counter()
    for d in datas:
        total.update(d if isinstance(d, dict) else data_warnings(d))
    if messages is not None:
        total.update(messages.others())
    return dict(sorted(total.items()))
