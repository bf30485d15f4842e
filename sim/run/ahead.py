"""The simulation stepped ahead in a thread of its own while the run checks.

A run's stages alternate on one core: simulate a batch of steps, check it,
validate it, record it. MuJoCo releases Python's global interpreter lock
inside its functions (mj_step, mj_collision), so on a machine with two
cores the next steps can be simulated while the last ones are checked:
`StepsAhead` iterates a run's states from a worker thread into a bounded
queue and hands them on in order, and the run's wall time tends to the
larger of the two sides instead of their sum. The worker starts with the
run's settling (`before`), while the run still builds its detection model
and prepares its checks, so the second core works through the set-up too.
The states are the same objects, computed by the same code in the same
order: the checks, events and report are those of the run in one thread
(tests/test_ahead.py).

Where fork is (Linux) a run steps ahead in a process of its own instead
(`cablecheck.run.apart`): the two sides took the interpreter lock in turn
for the Python part of a step (the script, reading the state) and ran
10-20 % more CPU time side by side than alone, which a process does not
share. This thread serves where there is no fork (macOS, Windows):
the states stay where they are made (no copy, no pickling), and a stop, an
error or a second Ctrl-C reach both sides at once; `SWITCH_INTERVAL` keeps
each turn at the lock short.

What it counts: the worker's own CPU time (`cpu`), the simulation stage's
cost; the caller times its own stages on its own thread (`thread_cpu`), so
neither side's stage includes waiting for the other.

This module does not decide what a state is or when a run stops (see
`cablecheck.run.loop`, `cablecheck.run.runner`); it only moves states from one thread to another.
"""

from __future__ import annotations

import queue
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator

DEPTH = 256
"""Most states simulated ahead of the checks by default (two of the run's
longest batches): enough that the simulation never waits for a batch being
checked, bounded so a slow check does not hold a whole run's states."""

AHEAD_BYTES = 64 * 2 ** 20
"""About the most memory the states simulated ahead may hold (`depth_for`)."""

MAX_DEPTH = 4096
"""Most states simulated ahead, however small they are."""


def depth_for(state_bytes: int) -> int:
    """How many states of about `state_bytes` each may be simulated ahead:
    `AHEAD_BYTES` of them, at least `DEPTH` and at most `MAX_DEPTH`. A run
    starts simulating before its checks are ready (`cablecheck.run.runner`), and a deeper
    queue lets the simulation go on meanwhile instead of waiting."""
    return int(min(max(AHEAD_BYTES // max(int(state_bytes), 1), DEPTH), MAX_DEPTH))

SWITCH_INTERVAL = 0.0005
"""Seconds a thread holding the interpreter lock keeps it before handing it
to one waiting for it (Python's default 0.005 s): the simulation's thread
waits for it after every mj_step, so a long turn would idle it."""

_END = object()


def thread_cpu() -> float:
    """CPU seconds of the calling thread."""
    return time.thread_time()


class StepsAhead:
    """`states` iterated on a worker thread, at most `depth` ahead of the
    consumer (module docstring).

    Iterating yields the states in order; an exception raised by the worker
    is raised here, after the states made before it. `close()` stops the
    worker after the state it is making and waits for it (call it when the
    consumer leaves early); a closed iteration yields nothing more. (To end
    a run early, end `states` itself: the states made until then are all
    handed on.)

    `before`: called on the worker before the first state is made (a run
    settles its simulation there while it prepares its checks); its CPU
    time is kept apart, and an exception it raises is handed on as the
    states' would be.

    Attributes:
      cpu: the worker's CPU seconds spent making the states so far (its
        thread's time, waits for the queue left out).
      before_cpu: the worker's CPU seconds in `before`.
    """

    def __init__(self, states: Iterable, depth: int = DEPTH, before: Callable[[], object] | None = None):
        self._states = states
        self._before = before
        self._queue: queue.Queue = queue.Queue(maxsize=max(int(depth), 1))
        self._closed = threading.Event()
        self.cpu = 0.0
        self.before_cpu = 0.0
        self._switch = sys.getswitchinterval()
        sys.setswitchinterval(min(self._switch, SWITCH_INTERVAL))
        self._thread = threading.Thread(target=self._work, name="cablecheck-simulation", daemon=True)
        self._thread.start()

    def _put(self, item) -> bool:
        """Queue `item` unless closed; False once closed."""
        while not self._closed.is_set():
            try:
                self._queue.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def _work(self) -> None:
        end: object = _END
        try:
            if self._before is not None:
                t = thread_cpu()
                try:
                    self._before()
                finally:
                    self.before_cpu += thread_cpu() - t
            it = iter(self._states)
            while not self._closed.is_set():
                t = thread_cpu()
                try:
                    state = next(it)
                except StopIteration:
                    break
                finally:
                    self.cpu += thread_cpu() - t
                if not self._put(state):
                    return
        except BaseException as exc:   # handed to the consumer, raised there
            end = exc
        self._put(end)

    def __iter__(self) -> Iterator:
        while not self._closed.is_set():
            item = self._queue.get()
            if item is _END:
                return
            if isinstance(item, BaseException):
                raise item
            yield item

    def close(self) -> None:
        """Stop the worker (after the state it is making) and wait for it."""
        self._closed.set()
        while self._thread.is_alive():
            try:                        # a worker blocked on a full queue sees the close
                self._queue.get_nowait()
            except queue.Empty:
                pass
            self._thread.join(timeout=0.05)
        sys.setswitchinterval(self._switch)

    def __enter__(self) -> "StepsAhead":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
