"""A request to stop, from SIGINT (Ctrl-C) or SIGTERM, taken at any moment of a run.

`StopRequest` replaces the two signals' handlers while it is entered (in the
main thread; Python takes signal handlers nowhere else): the first signal
only sets `asked`, which the run polls between steps, so the steps already
simulated are checked and the report and recording are written; a second
signal raises KeyboardInterrupt at once. The command line enters one at its
very start, so a signal during start-up (imports, loading, building) is not
lost either. Leaving it puts the previous handlers back.

This module does not decide what stopping means for a run (see `cablecheck.run.runner`).
"""

from __future__ import annotations

import signal
import threading


class StopRequest:
    """SIGINT / SIGTERM turned into a flag (see the module docstring).

    Attributes:
      asked: a stop was asked.
      signal_name: "SIGINT" or "SIGTERM" for the first signal, else None.
    """

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self):
        self.asked = False
        self.signal_name: str | None = None
        self._old: dict = {}

    def _handler(self, signum, frame) -> None:
        if self.asked:
            raise KeyboardInterrupt
        self.asked = True
        self.signal_name = signal.Signals(signum).name

    def __enter__(self) -> "StopRequest":
        if threading.current_thread() is threading.main_thread():
            self._old = {s: signal.signal(s, self._handler) for s in self.SIGNALS}
        return self

    def __exit__(self, *exc) -> None:
        for s, old in self._old.items():
            signal.signal(s, old)
        self._old = {}
