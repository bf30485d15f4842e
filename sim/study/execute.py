"""Run a study's variants on Dask distributed: an embedded local cluster or a running scheduler.

`run_variants` submits one task per variant and collects the outcomes as
they finish. Each task (`run_variant`) gets the variant's scene dict and the
scene's files as bytes (`cablecheck.study.bundle`), writes them into a temporary folder
on the worker, parses and runs the scene with `cablecheck.run.runner.run_scene`, and
returns the report and the recording as bytes: the workers need no shared
disk, and the same inputs give the same numbers wherever they run. The
client writes each variant's report and recording into
``<out>/variants/<id>/`` as soon as it arrives, and last its
``variant.json``: the hash of the variant's scene dict and files
(`scene_hash`), by which ``--resume`` keeps it.

The scene's files reach the cluster once per batch, as a Dask `Variable`
kept by the scheduler; a worker fetches them at its first variant of the
batch and keeps them (`_files`, by their hash). The variants' tasks depend
on no data held by a worker: the scheduler hands them to whichever worker
is free (data a task depended on would draw every task to the one worker
holding it, which is how two workers came to be slower than one), and a
worker that dies takes nothing with it: its variant runs again elsewhere (on
a running scheduler, once a worker is there). A variant whose worker dies
`distributed.scheduler.allowed-failures` + 1 times is a failed row
(KilledWorker).

Each variant runs on its worker's one task thread, with no simulation
stepped ahead on another (`RunOptions(overlap=False)`), so N workers run N
variants on N cores. Python's imports stay loaded in a worker between its
variants; its first variant pays them.

Temporary folders: a variant's lies under the embedded cluster's study
folder (`cablecheck.study.cluster`, removed when the study ends) or else in the
worker's temporary folder, named ``cablecheck-variant-<host>-<pid>-<id>-*``;
each variant first removes such folders of processes of this host that no
longer exist (a worker killed mid-variant).

A Ctrl-C (the study's stop request) cancels what has not finished: variants
already running see the study's Dask `Event` set and stop within half a
second, on any cluster; what finished is kept. A variant that raises, or
whose worker dies too often, becomes a failed row with its error; the others
go on. The cluster itself: `cablecheck.study.cluster`.

This module does not parse study files (see `cablecheck.study.definition`), reduce reports to
rows (`cablecheck.study.result`) or write the study's tables and plot (`cablecheck.study.plot`).

Dask (`distributed`) is imported inside the functions that use it: a study's
bad input (its file, scenes, address) is refused before Dask, slow to load, is.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import socket
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from cablecheck.report.document import write_report
from cablecheck.scene.errors import SceneError
from cablecheck.study.bundle import Bundle, make_bundle, materialise
from cablecheck.study.cluster import Cluster, cluster, workers_of
from cablecheck.study.definition import check_variant, variant_at
from cablecheck.study.plot import write_atomic
from cablecheck.study.result import Row, Status, row_from_report
from cablecheck.study.search import Search

POLL_S = 0.05
"""How often the client looks for finished variants and a stop request, seconds."""

Progress = Callable[[int, int, int], None]
"""progress(finished, total, failed): called as variants finish."""

STOP_POLL_S = 0.5
"""How often a running variant asks whether its study was stopped, seconds."""

TEMP_PREFIX = "cablecheck-variant-"
"""A variant's temporary folder's name begins so (then host, process id, variant id)."""

VARIANT_FILE = "variant.json"
"""Written last into a finished variant's folder: its id and `scene_hash`."""


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
      temp_root: the folder to make the variant's temporary folder in
        (None: the worker's temporary folder).
      files: (name of the Dask `Variable` holding the scene's files,
        their `bundle_hash`), or None: the files are given to `run_variant`.
    """

    id: str
    data: dict
    record: bool
    stop_event: str | None = None
    temp_root: str | None = None
    files: tuple[str, str] | None = None


class _EventStop:
    """`run_scene`'s stop request on a worker: asked once the study's Dask
    Event is set, looked up at most every STOP_POLL_S seconds."""

    signal_name = None

    def __init__(self, name: str):
        from distributed import Event  # Dask loads here, not at import (module docstring)

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
      task_s: the task's wall time on its worker (files written, scene
        parsed, run, outputs read), seconds.
      pid: the worker process's id.
    """

    report: bytes
    recording: bytes | None
    task_s: float = 0.0
    pid: int = 0


_FILES: dict[str, Bundle] = {}
"""A worker's scene files by `bundle_hash`: the last `_FILES_KEPT` batches'."""

_FILES_KEPT = 2


def _files(name: str, digest: str) -> Bundle:
    """The scene's files of a batch: kept from an earlier variant on this
    worker, else fetched from the scheduler's `Variable` `name`."""
    if digest not in _FILES:
        from distributed import Variable  # Dask loads here, not at import (module docstring)

        doc = Variable(name).get(timeout=60)
        _FILES[digest] = Bundle(scene=doc["scene"], files=tuple((n, bytes(b)) for n, b in doc["files"]))
        while len(_FILES) > _FILES_KEPT:
            del _FILES[next(iter(_FILES))]
    return _FILES[digest]


def bundle_hash(bundle: Bundle) -> str:
    """SHA-256 of a bundle's scene name and files (names and bytes)."""
    h = hashlib.sha256(bundle.scene.encode() + b"\0")
    for name, content in bundle.files:
        h.update(name.encode() + b"\0" + str(len(content)).encode() + b"\0")
        h.update(content)
    return h.hexdigest()


def run_variant(task: VariantTask, bundle: Bundle | None = None) -> VariantOutput:
    """Run one variant in a temporary folder on this machine (a Dask task);
    its scene's files are `bundle`, or else fetched as `task.files` says."""
    from cablecheck.run.runner import RunOptions, run_scene  # loaded once per worker process, kept after
    from cablecheck.scene.load import parse_scene

    t0 = time.perf_counter()
    if bundle is None:
        bundle = _files(*task.files)
    root = task.temp_root if task.temp_root and os.path.isdir(task.temp_root) else tempfile.gettempdir()
    remove_stale_temp(root)
    prefix = f"{TEMP_PREFIX}{_host()}-{os.getpid()}-{task.id}-"
    with tempfile.TemporaryDirectory(prefix=prefix, dir=root) as tmp:
        scene_path = materialise(bundle, Path(tmp) / "scene")
        scene = parse_scene(task.data, scene_path)
        report = Path(tmp) / "out" / "report.json"
        record = Path(tmp) / "out" / "recording.rrd" if task.record else None
        stop = _EventStop(task.stop_event) if task.stop_event else None
        # a worker is one thread, one core's share of the cluster: its run
        # stays on that thread (no simulation stepped ahead, cablecheck.run.ahead)
        run_scene(scene, RunOptions(report=report, record=record, overlap=False), stop=stop)
        return VariantOutput(report=report.read_bytes(), recording=record.read_bytes() if record else None,
                             task_s=time.perf_counter() - t0, pid=os.getpid())


def _host() -> str:
    """This machine's name as it may stand in a folder name."""
    return "".join(c if c.isalnum() else "_" for c in socket.gethostname())[:40] or "host"


def remove_stale_temp(root: str | Path) -> list[Path]:
    """Remove the variants' temporary folders in `root` left by processes of
    this host, owned by this user, that no longer exist (a worker killed
    mid-variant); return them."""
    gone = []
    mine = f"{TEMP_PREFIX}{_host()}-"
    try:
        entries = list(os.scandir(root))
    except OSError:
        return gone
    for entry in entries:
        if not entry.name.startswith(mine):
            continue
        pid = entry.name[len(mine):].split("-", 1)[0]
        try:
            if not pid.isdigit() or entry.stat(follow_symlinks=False).st_uid != os.getuid() \
                    or _alive(int(pid)):
                continue
        except OSError:
            continue
        shutil.rmtree(entry.path, ignore_errors=True)
        gone.append(Path(entry.path))
    return gone


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:   # another user's process
        return True
    return True


def scene_hash(data: dict, bundle: Bundle) -> str:
    """SHA-256 of a variant's scene dict (canonical JSON) and of its scene's
    files (`bundle_hash`): equal hashes, the same run."""
    h = hashlib.sha256()
    h.update(json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=True).encode())
    h.update(bundle_hash(bundle).encode())
    return h.hexdigest()


def run_variants(tasks: list[VariantTask], values: dict[str, tuple], bundle: Bundle, out: Path, *,
                 workers: int | None = None, scheduler: str | None = None,
                 stop=None, progress: Progress | None = None, judged: tuple = ((), None),
                 resume: bool = False, spare: Callable[[], None] | None = None) -> tuple[list[Row], bool]:
    """Run every task on the cluster; write each variant's outputs under
    `out`/variants/<id>/ as it arrives. Returns the rows in task order and
    whether every task was run (False after a stop request: unfinished
    variants are cancelled and become rows marked not run).

    `workers`: size of the embedded cluster (default: the number of cores);
    `scheduler`: address of a running one instead. `stop` has an `asked`
    attribute polled while waiting (`cablecheck.run.stop.StopRequest`). `judged`: the
    study's (requirements, goal) each row is judged by. `resume`: keep the
    variants already in `out` whose scene hash is the task's (see
    `run_batch`); without it, `out`/variants is emptied first. `spare`:
    work for a core the variants leave idle (`run_batch`)."""
    with cluster(workers, scheduler, stop) as cl:
        if not resume:
            clear_variants(out)
        rows, complete = run_batch(cl, tasks, values, bundle, out, stop=stop, progress=progress,
                                   judged=judged, resume=resume, spare=spare)
    if complete:
        prune_variants(out, [r.id for r in rows])
    return rows, complete


def clear_variants(out: Path) -> None:
    """A study rewrites its own folder: no stale variants."""
    folder = Path(out) / "variants"
    if folder.exists():
        shutil.rmtree(folder)


def prune_variants(out: Path, ids: list[str]) -> None:
    """Remove the folders under `out`/variants that are not of `ids` (a
    resumed study's leftovers of another expansion)."""
    folder = Path(out) / "variants"
    keep = set(ids)
    if folder.is_dir():
        for sub in folder.iterdir():
            if sub.name not in keep:
                shutil.rmtree(sub) if sub.is_dir() else sub.unlink()


def kept_row(task: VariantTask, values: tuple, digest: str, folder: Path, judged: tuple) -> Row | None:
    """The row of a variant already finished in `folder` with this scene
    hash (and a recording if the task wants one), from its report; else None."""
    try:
        kept = json.loads((folder / VARIANT_FILE).read_text())
        report = json.loads((folder / "report.json").read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(kept, dict) or kept.get("scene_sha256") != digest or kept.get("id") != task.id:
        return None
    recording = folder / "recording.rrd"
    if task.record and not recording.is_file():
        return None
    return row_from_report(task.id, values, report, str(folder / "report.json"),
                           str(recording) if task.record else None, *judged)


def run_batch(cl: Cluster, tasks: list[VariantTask], values: dict[str, tuple], bundle: Bundle, out: Path, *,
              stop=None, progress: Progress | None = None, judged: tuple = ((), None),
              done: int = 0, total: int | None = None, resume: bool = False,
              spare: Callable[[], None] | None = None) -> tuple[list[Row], bool]:
    """`run_variants` on an open `cluster`: one batch of a study (a search
    runs several); `done` and `total` count the study's variants for
    `progress`. With `resume`, a variant whose folder holds a finished run
    of the same scene hash (`kept_row`) is not run again: its row is read
    from its report. `spare` is called once, on a daemon thread of its own,
    as soon as fewer variants run than this machine has cores (one worker
    on two cores: from the start; as many workers as cores: when the last
    variants leave a core idle): the outputs' imports (matplotlib, 0.3-0.4
    s) then cost no variant anything."""
    folder = Path(out) / "variants"
    rows: dict[str, Row] = {}
    complete = True
    total = len(tasks) if total is None else total
    client = cl.client
    digests = {t.id: scene_hash(t.data, bundle) for t in tasks}
    failed = 0
    todo = []
    for t in tasks:
        row = kept_row(t, values[t.id], digests[t.id], folder / t.id, judged) if resume else None
        if row is None:
            todo.append(t)
            continue
        rows[t.id] = row
        failed += row.status is Status.FAILED
        if progress:
            progress(done + len(rows), total, failed)
    futures = {}
    stopped = shared = None
    if todo:
        from distributed import Event, Variable  # Dask loads here, not at import (module docstring)

        tag = os.urandom(4).hex()
        shared = Variable(f"cablecheck-files-{tag}", client=client)   # kept by the scheduler
        shared.set({"scene": bundle.scene, "files": [[n, b] for n, b in bundle.files]})
        files = (shared.name, bundle_hash(bundle))
        stopped = Event(f"cablecheck-stop-{tag}", client=client)
        futures = {client.submit(run_variant, replace(t, stop_event=stopped.name, temp_root=cl.temp_root,
                                                      files=files),
                                 key=f"cablecheck-{tag}-{t.id}", pure=False,
                                 priority=len(todo) - k): t   # in study order
                   for k, t in enumerate(todo)}
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    threads = sum(client.nthreads().values()) if futures and spare is not None else 0
    try:
        while futures:
            if stop is not None and stop.asked:
                complete = False
                break
            if spare is not None and min(len(futures), threads) < cores:
                threading.Thread(target=spare, name="cablecheck-spare", daemon=True).start()
                spare = None
            finished = [f for f in futures if f.done()]
            if not finished:
                time.sleep(POLL_S)
                continue
            for f in finished:
                t = futures.pop(f)
                rows[t.id] = _collect(f, t, values[t.id], folder / t.id, judged, digests[t.id])
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
        if shared is not None:
            shared.delete()
    for t in tasks:
        if t.id not in rows:
            rows[t.id] = Row(id=t.id, values=values[t.id], status=Status.NOT_RUN,
                             error="the study was interrupted before it finished")
    return [rows[t.id] for t in tasks], complete


def _collect(future, task: VariantTask, values: tuple, folder: Path, judged: tuple, digest: str) -> Row:
    """The row of a finished future; its report and recording written under
    `folder` (emptied first), then its `VARIANT_FILE`."""
    try:
        output: VariantOutput = future.result()
    except Exception as e:   # its own error, its worker's death (KilledWorker), or cancelled
        return Row(id=task.id, values=values, status=Status.FAILED,
                   error=f"{type(e).__name__}: {e}".strip())

    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    report = json.loads(output.report)
    recording = None
    if output.recording is not None:
        recording = folder / "recording.rrd"
        write_atomic(recording, output.recording)
    report["recording"] = None if recording is None else str(recording)
    path = folder / "report.json"
    write_report(report, path)
    write_atomic(folder / VARIANT_FILE, (json.dumps({"id": task.id, "scene_sha256": digest,
                                                     "task_s": output.task_s, "worker_pid": output.pid},
                                                    indent=1) + "\n").encode())
    return row_from_report(task.id, values, report, str(path),
                           None if recording is None else str(recording), *judged)


def run_search(study, record: bool, out: Path, *, workers: int | None = None, scheduler: str | None = None,
               stop=None, progress: Progress | None = None, resume: bool = False,
               spare: Callable[[], None] | None = None) -> tuple[list[Row], bool]:
    """A study's search (``[search] method = "optimise"``): rounds of
    variants in the varied keys' ranges on one cluster, each round's points
    proposed by `cablecheck.study.search.Search` from the rows so far
    (`cablecheck.study.result.Row.score`), until the budget is spent. Returns every
    row in the order run and whether the search ran to its end.

    Each round's scenes are checked (`cablecheck.study.definition.check_variant`) before the
    round runs; a point the scene refuses is a failed row with the scene's
    complaint, not run. `resume` keeps finished variants as `run_batch`
    does: the search proposes the same points from the same rows. `spare`
    as `run_batch` takes it, offered to every round (it must bear being
    called again)."""

    lo = [v.bounds[0] for v in study.vary]
    hi = [v.bounds[1] for v in study.vary]
    budget = study.search.budget
    rows: list[Row] = []
    complete = True
    with cluster(workers, scheduler, stop) as cl:
        if not resume:
            clear_variants(out)
        batch = max(1, workers_of(cl.client))
        search = Search(lo, hi, budget, batch)
        points = search.first()
        width = max(3, len(str(budget - 1)))
        while points and complete:
            found = [variant_at(study, f"{len(rows) + k:0{width}d}", tuple(float(x) for x in p))
                     for k, p in enumerate(points)]
            refused: dict[str, Row] = {}
            for v in found:
                try:
                    check_variant(study, v)
                except SceneError as e:
                    refused[v.id] = Row(id=v.id, values=v.values, status=Status.FAILED, error=str(e))
            runnable = [v for v in found if v.id not in refused]
            got: dict[str, Row] = dict(refused)
            if runnable:
                bundle, datas = make_bundle(study.scene_path, [v.data for v in runnable])
                tasks = [VariantTask(id=v.id, data=d, record=record) for v, d in zip(runnable, datas)]
                ran, complete = run_batch(cl, tasks, {v.id: v.values for v in runnable}, bundle, out, stop=stop,
                                          progress=progress, judged=(study.requirements, study.goal),
                                          done=len(rows) + len(refused), total=budget, resume=resume,
                                          spare=spare)
                got.update((r.id, r) for r in ran)
            batch_rows = [got[v.id] for v in found]
            rows += batch_rows
            search.tell(points, [r.score() for r in batch_rows])
            points = search.next()
    if complete:
        prune_variants(out, [r.id for r in rows])
    return rows, complete
