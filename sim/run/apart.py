"""The simulation stepped ahead in a process of its own while the run checks.

`StepsApart` does what `cablecheck.run.ahead.StepsAhead` does (the run's
states made ahead of the checks, handed on in order, at most `depth` of them
in flight, a set-up run first, errors handed on after the states made before
them), in a child process forked from the run instead of a thread.

Why a process: a thread shares Python's interpreter lock with the checks.
MuJoCo releases it inside its functions, but the simulation's thread takes
it back after every mj_step, mj_kinematics and mj_flex (about seven times a
scene step) and waits for it while the checks hold it, and both sides ran
10-20 % more CPU time side by side than alone (docs/performance.md). Forked,
the simulation keeps its model, data, script and the states' generator as
they were (nothing of them is pickled) and steps on the other core without
waiting for anything. Measured side by side with the thread, 2026-11-29, three
runs each (`cablecheck run --no-record`): robosuite's Tiago zoo scene 4.91-5.00
-> 4.29-4.36 s, the checks and validation 2.20-2.32 -> 1.91-1.93 CPU s;
gymnasium's kitchen Franka with a hose resting on its links 3.38-3.40 ->
2.91-3.07 s; the Fetch 4.66-4.93 -> 4.33-4.61 s; the 64 x 1,000 crossing
harness, whose own simulation is its wall time, (c+v+r)/sim 1.30 -> 1.26
(`benchmarks/bench_scale.py`).

What crosses: each state, pickled (its arrays: a few kB to a few hundred kB),
in chunks of up to `CHUNK` through a pipe; a thread of the run's
(`cablecheck-states`) reads them into a queue, so the child never waits for
the checks to take a chunk. The child takes one of `depth` slots (a
semaphore) per state and the run gives it back as it takes the state, so
at most `depth` states are in flight, as in the thread's bounded queue.
Settling's progress comes back the same way and is reported from that
thread (as the thread's settling reports from its own).

Stops: the run's stop request lives in the run's process, so the child
polls a shared flag instead, before each state (and settling, between its
steps); the run raises it when `halted()` says so (looked at as it takes
each state, and every `HALT_EVERY` seconds while the child is quiet, so a
Ctrl-C while the run still builds ends the settling at once), and on
`close()`. The child ignores SIGINT and SIGTERM: Ctrl-C reaches the
whole process group, and the run, not the child, decides what a stop
means (every state made before it is handed on and checked).

Errors: an exception in the child is pickled (or, when it cannot be, a
RuntimeError naming it) and raised in the run after the states made before
it, its traceback in the child added as a note. A child that dies without a
word (a crash in MuJoCo, a kill) ends the iteration with a RuntimeError
naming its exit status: the run ends incomplete with that error instead of
the whole command dying with it.

At the end the child runs `finish()` and sends its value (`finished`): a
run takes the simulation's own warning counters and MuJoCo's messages from
there, since they were raised in the child.

What it counts: `cpu`, the child's CPU seconds making and pickling the states
(waits for a slot or the pipe left out) plus the reading thread's
unpickling, the simulation stage's cost; `before_cpu`, the child's set-up.

Only where `fork` is (`available`: Linux). Written here rather than with
`concurrent.futures.ProcessPoolExecutor` or a `multiprocessing.Pool`: those
pickle the function and its arguments (here a live MuJoCo model and a
generator) and return one result per call, not a stream with a bound.

This module does not decide what a state is or when a run stops (see
`cablecheck.run.loop`, `cablecheck.run.runner`); it only moves states from one
process to another.
"""

from __future__ import annotations

import multiprocessing
import pickle
import queue
import signal
import sys
import threading
import traceback
from collections.abc import Callable, Iterable, Iterator

from cablecheck.run.ahead import thread_cpu

CHUNK = 16
"""Most states the child sends in one message (fewer when it would otherwise
wait for a slot with states in hand, and at the end)."""

HALT_EVERY = 0.05
"""Seconds between two looks at `halted` while no message comes from the child."""

CLOSE_WAIT = 2.0
"""Seconds `close()` waits for the child to end after the state it is
making before it kills it."""

_END = object()


class _Failed:
    """An exception of the child's, to raise in the run."""

    def __init__(self, exc: BaseException):
        self.exc = exc


def available() -> bool:
    """Can a run step ahead in a forked process here: Linux, where `fork`
    keeps a MuJoCo model usable in the child (macOS's system libraries are
    not safe to use after a fork in a process with threads; Windows has no
    fork)."""
    return sys.platform.startswith("linux") and "fork" in multiprocessing.get_all_start_methods()


class StepsApart:
    """`states` iterated in a forked child process, at most `depth` ahead of
    the consumer (module docstring).

    Iterating yields the states in order; an exception raised in the child
    is raised here, after the states made before it. `close()` stops the
    child after the state it is making, waits for it and reads what it
    sent; a closed iteration yields nothing more.

    Args:
      states: iterated in the child (forked: a generator over a live
        simulation is fine; it is never pickled).
      depth: most states in flight.
      before: called in the child before the first state, as
        ``before(progress, halted)``: a progress callable whose calls are
        made in the run's process (`progress`), and the child's stop flag.
      progress: called in the run's process, on the reading thread, with
        the arguments `before` gave its progress callable.
      finish: called in the child after the last state (or an error or a
        stop); its value (picklable) becomes `finished`.
      halted: polled in the run's process as each state is taken, and every
        `HALT_EVERY` seconds meanwhile (on the reading thread); once it
        returns True the child makes no further state (and ends its set-up
        when that polls its flag).

    Attributes:
      cpu: the child's CPU seconds making and sending the states so far,
        plus this process's reading them.
      before_cpu: the child's CPU seconds in `before`.
      finished: the value of `finish()` once the child has ended (None before).
    """

    def __init__(self, states: Iterable, depth: int, before: Callable | None = None,
                 progress: Callable | None = None, finish: Callable[[], object] | None = None,
                 halted: Callable[[], bool] | None = None):
        ctx = multiprocessing.get_context("fork")
        self._halt = ctx.Event()
        self._slots = ctx.Semaphore(max(int(depth), 1))
        recv, send = ctx.Pipe(duplex=False)
        self._recv = recv
        self._queue: queue.Queue = queue.Queue()
        self._progress = progress
        self._halted = halted
        self._closed = False
        self._child_cpu = 0.0
        self._read_cpu = 0.0
        self._take_cpu = 0.0
        self.before_cpu = 0.0
        self.finished: object = None
        # the child must not write again what this process has buffered for its outputs
        sys.stdout.flush()
        sys.stderr.flush()
        self._process = ctx.Process(target=_child, args=(states, before, finish, send, self._halt, self._slots),
                                    name="cablecheck-simulation", daemon=True)
        self._process.start()
        send.close()
        self._reader = threading.Thread(target=self._read, name="cablecheck-states", daemon=True)
        self._reader.start()

    @property
    def cpu(self) -> float:
        return self._child_cpu + self._read_cpu + self._take_cpu

    def _read(self) -> None:
        start = thread_cpu()
        try:
            while True:
                try:
                    while not self._recv.poll(HALT_EVERY):   # a stop asked here reaches a child still settling
                        self._check_halt()
                    raw = self._recv.recv_bytes()
                except (EOFError, OSError):
                    self._process.join()
                    self._queue.put(_Failed(RuntimeError(
                        "the simulation process ended without a word "
                        f"(exit status {self._process.exitcode}): MuJoCo crashed, or it was killed")))
                    return
                if raw[:1] == b"S":                     # states: unpickled as they are taken (`__iter__`)
                    self._queue.put(raw)
                    continue
                kind, payload = pickle.loads(raw)
                if kind == "progress":
                    if self._progress is not None:
                        self._progress(*payload)
                elif kind == "error":
                    self._queue.put(_Failed(payload))
                else:                                   # "end"
                    cpu, self.before_cpu, self.finished = payload
                    self._child_cpu = max(self._child_cpu, cpu)
                    self._queue.put(_END)
                    return
        except BaseException as exc:    # reading failed (a progress callback's error): the states end with it
            self._queue.put(_Failed(exc))
        finally:
            self._read_cpu = thread_cpu() - start

    def __iter__(self) -> Iterator:
        while not self._closed:
            item = self._queue.get()
            if item is _END:
                return
            if isinstance(item, _Failed):
                raise item.exc
            start = thread_cpu()
            states, cpu = pickle.loads(memoryview(item)[1:])
            self._take_cpu += thread_cpu() - start
            self._child_cpu = max(self._child_cpu, cpu)     # the child's "end" may have been read first
            for state in states:
                if self._closed:
                    return
                self._slots.release()
                self._check_halt()
                yield state

    def _check_halt(self) -> None:
        if self._halted is not None and not self._halt.is_set() and self._halted():
            self._halt.set()

    def close(self) -> None:
        """Stop the child (after the state it is making), wait for it and for what it sent."""
        self._closed = True
        self._halt.set()
        self._process.join(timeout=CLOSE_WAIT)
        if self._process.is_alive():
            self._process.kill()
            self._process.join()
        self._reader.join()
        self._recv.close()

    def __enter__(self) -> "StepsApart":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _child(states: Iterable, before: Callable | None, finish: Callable[[], object] | None, send,
           halt, slots) -> None:
    """The child's work: `before`, the states in chunks, `finish`; then it ends."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)      # the run decides what a stop means
    signal.signal(signal.SIGTERM, signal.SIG_IGN)

    def out(kind: str, payload) -> None:
        send.send_bytes(pickle.dumps((kind, payload), protocol=pickle.HIGHEST_PROTOCOL))

    before_cpu = 0.0
    start = thread_cpu()
    chunk: list = []

    def flush() -> None:
        if chunk:
            send.send_bytes(b"S" + pickle.dumps((chunk, thread_cpu() - start - before_cpu),
                                                 protocol=pickle.HIGHEST_PROTOCOL))
            chunk.clear()

    try:
        try:
            if before is not None:
                try:
                    before(lambda *args: out("progress", args), halt.is_set)
                finally:
                    before_cpu = thread_cpu() - start
            it = iter(states)
            while not halt.is_set():
                if not slots.acquire(block=False):
                    flush()                              # the run takes these while this waits
                    while not slots.acquire(timeout=0.1):
                        if halt.is_set():
                            break
                    if halt.is_set():
                        break
                try:
                    state = next(it)
                except StopIteration:
                    break
                chunk.append(state)
                if len(chunk) >= CHUNK:
                    flush()
            flush()
        except BaseException as exc:    # handed to the run, raised there
            flush()
            out("error", _sendable(exc))
        finished = None
        try:
            finished = finish() if finish is not None else None
        except Exception as exc:
            out("error", _sendable(exc))
        out("end", (thread_cpu() - start - before_cpu, before_cpu, finished))
    except (BrokenPipeError, OSError):      # the run is gone: nothing to tell
        pass
    finally:
        send.close()


def _sendable(exc: BaseException) -> BaseException:
    """`exc` with its traceback in the child as a note, or a RuntimeError
    naming it when it cannot be pickled."""
    exc.add_note("in the simulation process:\n" + "".join(traceback.format_exception(exc)).rstrip())
    try:
        pickle.dumps(exc)
    except Exception:
        return RuntimeError(f"{type(exc).__name__}: {exc}")
    return exc
