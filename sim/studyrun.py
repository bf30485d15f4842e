"""Run a study's variants on Dask distributed: an embedded local cluster or a running scheduler.

`run_variants` submits one task per variant and collects the outcomes as
they finish. Each task (`run_variant`) gets the variant's scene dict and the
scene's files as bytes (`sim.bundle`, scattered to the cluster once), writes
them into a temporary folder on the worker, parses and runs the scene with
`sim.run.run_scene`, and returns the report and the recording as bytes: the
workers need no shared disk, and the same inputs give the same numbers
wherever they run. The client writes each variant's report and recording
into ``<out>/variants/<id>/`` as soon as it arrives.

The embedded cluster (`--workers`) is a `distributed.LocalCluster` of worker
processes with one thread each, listening on 127.0.0.1 only, without a
dashboard; its worker processes ignore SIGINT, so a Ctrl-C in the terminal
reaches only the study, which cancels what has not finished (variants
already running see the study's Dask `Event` set and stop within half a
second, on any cluster), closes the cluster and keeps what has finished. Dask's nanny starts worker processes with
OMP / MKL / OpenBLAS threads set to 1 (`distributed.nanny.pre-spawn-environ`).
A variant that raises, or whose worker dies, becomes a failed row with its
error; the others go on.

This module does not parse study files (see `sim.study`), reduce reports to
rows (`sim.studyresult`) or write the study's tables and plot (`sim.studyplot`).
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import signal
import tempfile
import threading
import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

from sim.bundle import Bundle, materialise
from sim.studyplot import write_atomic
from sim.studyresult import Row, Status, row_from_report

POLL_S = 0.05
"""How often the client looks for finished variants and a stop request, seconds."""

WORKER_WAIT_S = 60.0
"""How long a study on a running scheduler waits for its first worker, seconds."""

Progress = Callable[[int, int, int], None]
"""progress(finished, total, failed): called as variants finish."""


class StudyRunError(Exception):
    """The cluster could not be used (a scheduler that cannot be reached, no worker)."""


STOP_POLL_S = 0.5
"""How often a running variant asks whether its study was stopped, seconds."""


@dataclass(frozen=True)
class VariantTask:
    """What one task needs besides the scene's files.

    Attributes:
      id: the variant's id.
      data: its scene dict (file names relative to the scene's folder).
      record: write a recording.
      stop_event: name of the study's Dask `Event`, set when the study is
        stopped: a running variant then ends within `STOP_POLL_S` seconds
        (a cancelled Dask task that has started would run on to its end).
    """

    id: str
    data: dict
    record: bool
    stop_event: str | None = None


class _EventStop:
    """`run_scene`'s stop request on a worker: asked once the study's Dask
    Event is set, looked up at most every STOP_POLL_S seconds."""

    signal_name = None

    def __init__(self, name: str):
        from distributed import Event

        self._event = Event(name)
        self._next = 0.0
        self._asked = False

    @property
    def asked(self) -> bool:
        now = time.monotonic()
        if not self._asked and now >= self._next:
            self._next = now + STOP_POLL_S
            self._asked = self._event.is_set()
        return self._asked


@dataclass(frozen=True)
class VariantOutput:
    """What a task returns.

    Attributes:
      report: the report file's bytes (JSON).
      recording: the recording's bytes, or None without one.
    """

    report: bytes
    recording: bytes | None


def run_variant(task: VariantTask, bundle: Bundle) -> VariantOutput:
    """Run one variant in a temporary folder on this machine (a Dask task)."""
    from sim.run import RunOptions, run_scene   # loads MuJoCo on the worker
    from sim.scene import parse_scene

    with tempfile.TemporaryDirectory(prefix=f"cablecheck-variant-{task.id}-") as tmp:
        scene_path = materialise(bundle, Path(tmp) / "scene")
        scene = parse_scene(task.data, scene_path)
        report = Path(tmp) / "out" / "report.json"
        record = Path(tmp) / "out" / "recording.rrd" if task.record else None
        stop = _EventStop(task.stop_event) if task.stop_event else None
        # a worker is one thread, one core's share of the cluster: its run
        # stays on that thread (no simulation stepped ahead, sim.ahead)
        run_scene(scene, RunOptions(report=report, record=record, overlap=False), stop=stop)
        return VariantOutput(report=report.read_bytes(),
                             recording=record.read_bytes() if record else None)


def run_variants(tasks: list[VariantTask], values: dict[str, tuple], bundle: Bundle, out: Path, *,
                 workers: int | None = None, scheduler: str | None = None,
                 stop=None, progress: Progress | None = None, judged: tuple = ((), None)) -> tuple[list[Row], bool]:
    """Run every task on the cluster; write each variant's outputs under
    `out`/variants/<id>/ as it arrives. Returns the rows in task order and
    whether every task was run (False after a stop request: unfinished
    variants are cancelled and become rows marked not run).

    `workers`: size of the embedded cluster (default: the number of cores);
    `scheduler`: address of a running one instead. `stop` has an `asked`
    attribute polled while waiting (`sim.stop.StopRequest`). `judged`: the
    study's (requirements, goal) each row is judged by."""
    clear_variants(out)
    with cluster(workers, scheduler) as client:
        return run_batch(client, tasks, values, bundle, out, stop=stop, progress=progress, judged=judged)


def clear_variants(out: Path) -> None:
    """A study rewrites its own folder: no stale variants."""
    folder = Path(out) / "variants"
    if folder.exists():
        shutil.rmtree(folder)


def run_batch(client, tasks: list[VariantTask], values: dict[str, tuple], bundle: Bundle, out: Path, *,
              stop=None, progress: Progress | None = None, judged: tuple = ((), None),
              done: int = 0, total: int | None = None) -> tuple[list[Row], bool]:
    """`run_variants` on an open `cluster`: one batch of a study (a search
    runs several); `done` and `total` count the study's variants for
    `progress`."""
    folder = Path(out) / "variants"
    rows: dict[str, Row] = {}
    complete = True
    total = len(tasks) if total is None else total
    from distributed import Event

    shared = client.scatter(bundle, broadcast=False, hash=False)
    tag = os.urandom(4).hex()
    stopped = Event(f"cablecheck-stop-{tag}", client=client)
    futures = {client.submit(run_variant, replace(t, stop_event=stopped.name), shared,
                             key=f"cablecheck-{tag}-{t.id}", pure=False,
                             priority=len(tasks) - k): t   # in study order
               for k, t in enumerate(tasks)}
    failed = 0
    try:
        while futures:
            if stop is not None and stop.asked:
                complete = False
                break
            finished = [f for f in futures if f.done()]
            if not finished:
                time.sleep(POLL_S)
                continue
            for f in finished:
                t = futures.pop(f)
                rows[t.id] = _collect(f, t, values[t.id], folder / t.id, judged)
                failed += rows[t.id].status is Status.FAILED
                f.release()
                if progress:
                    progress(done + len(rows), total, failed)
    except KeyboardInterrupt:   # a second Ctrl-C: stop waiting at once
        complete = False
    finally:
        if futures:
            stopped.set()   # running variants end at their next look (their reports are dropped)
            client.cancel(list(futures))
    for t in tasks:
        if t.id not in rows:
            rows[t.id] = Row(id=t.id, values=values[t.id], status=Status.NOT_RUN,
                             error="the study was interrupted before it finished")
    return [rows[t.id] for t in tasks], complete


def _collect(future, task: VariantTask, values: tuple, folder: Path, judged: tuple) -> Row:
    """The row of a finished future; its report and recording written under `folder`."""
    try:
        output: VariantOutput = future.result()
    except Exception as e:   # its own error, its worker's death (KilledWorker), or cancelled
        return Row(id=task.id, values=values, status=Status.FAILED,
                   error=f"{type(e).__name__}: {e}".strip())
    from sim.report import write_report

    folder.mkdir(parents=True, exist_ok=True)
    report = json.loads(output.report)
    recording = None
    if output.recording is not None:
        recording = folder / "recording.rrd"
        write_atomic(recording, output.recording)
    report["recording"] = None if recording is None else str(recording)
    path = folder / "report.json"
    write_report(report, path)
    return row_from_report(task.id, values, report, str(path),
                           None if recording is None else str(recording), *judged)


@contextmanager
def cluster(workers: int | None, scheduler: str | None):
    """A Dask client on the embedded cluster or on `scheduler`; closed on leaving."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError) as e:
            raise StudyRunError(f"cannot reach the Dask scheduler at {scheduler}: {e}") from None
        try:
            try:
                client.wait_for_workers(1, timeout=WORKER_WAIT_S)
            except TimeoutError:
                raise StudyRunError(f"no Dask worker joined the scheduler at {scheduler} within "
                                    f"{WORKER_WAIT_S:g} s (start one: dask worker {scheduler})") from None
            yield client
        finally:
            client.close()
        return
    n = workers or os.cpu_count() or 1
    with _sigint_ignored():   # worker processes inherit the ignored SIGINT (see module docstring)
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                               dashboard_address=None, silence_logs=logging.ERROR)
    try:
        client = Client(cluster)
        try:
            yield client
        finally:
            client.close()
    finally:
        try:   # waits for running tasks a few seconds, then ends their processes
            cluster.close()
        except KeyboardInterrupt:   # a second Ctrl-C: the worker processes, daemonic, end with us
            pass


@contextmanager
def _sigint_ignored():
    """SIGINT ignored while child processes are started (Python keeps an
    ignored SIGINT ignored at its start-up); the caller's handler is back on
    leaving. A Ctrl-C in those seconds is not seen. A no-op off the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def run_search(study, record: bool, out: Path, *, workers: int | None = None, scheduler: str | None = None,
               stop=None, progress: Progress | None = None) -> tuple[list[Row], bool]:
    """A study's search (``[search] method = "optimise"``): rounds of
    variants in the varied keys' ranges on one cluster, each round's points
    proposed by `sim.studysearch.Search` from the rows so far
    (`sim.studyresult.Row.score`), until the budget is spent. Returns every
    row in the order run and whether the search ran to its end."""
    from sim.bundle import make_bundle
    from sim.study import variant_at
    from sim.studysearch import Search

    lo = [v.bounds[0] for v in study.vary]
    hi = [v.bounds[1] for v in study.vary]
    budget = study.search.budget
    clear_variants(out)
    rows: list[Row] = []
    complete = True
    with cluster(workers, scheduler) as client:
        batch = max(1, len(client.scheduler_info().get("workers", {})))
        search = Search(lo, hi, budget, batch)
        points = search.first()
        width = max(3, len(str(budget - 1)))
        while points and complete:
            found = [variant_at(study, f"{len(rows) + k:0{width}d}", tuple(float(x) for x in p))
                     for k, p in enumerate(points)]
            bundle, datas = make_bundle(study.scene_path, [v.data for v in found])
            tasks = [VariantTask(id=v.id, data=d, record=record) for v, d in zip(found, datas)]
            got, complete = run_batch(client, tasks, {v.id: v.values for v in found}, bundle, out, stop=stop,
                                      progress=progress, judged=(study.requirements, study.goal),
                                      done=len(rows), total=budget)
            rows += got
            search.tell(points, [r.score() for r in got])
            points = search.next()
    return rows, complete
