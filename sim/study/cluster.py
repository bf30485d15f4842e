"""The Dask cluster a study runs on: an embedded local cluster, or a running scheduler checked first.

`cluster` opens a Dask client and closes it (and an embedded cluster) on
leaving. A scheduler address (``--scheduler``) is checked before anything
connects (`check_address`: ``tcp://`` or ``tls://`` and HOST:PORT, a host
that resolves, for ``tls://`` Dask's TLS configuration with its files), then
probed with Dask's own handshake within `CONNECT_TIMEOUT_S` (a port that
accepts and never answers is an error, not a hang); every wait polls the
study's stop request, so Ctrl-C is honoured while connecting and while
waiting for a worker. Problems raise `StudyRunError` naming ``--scheduler``,
the address and the problem.

The embedded cluster (``--workers``) is a `distributed.LocalCluster` of
worker processes (each under a nanny that restarts it if it dies) with one
thread each, listening on 127.0.0.1 only, without a dashboard (the
scheduler's HTTP server, which Dask starts regardless, takes a free port of
127.0.0.1, not 8787 on every interface); Dask's
nanny starts them with OMP / MKL / OpenBLAS threads set to 1
(`distributed.nanny.pre-spawn-environ`). Its worker processes ignore
SIGINT, so a Ctrl-C in the terminal reaches only the study.

Its workers are forked from a fork server (`start_forkserver`, Python's
`multiprocessing` "forkserver", which Dask supports as
`distributed.worker.multiprocessing-method`) that the command line starts
first thing, before it reads the study: the server loads Dask and the
run's modules (`WORKER_IMPORTS`) on the second core while the study loads
its own, and every worker forked from it starts with them loaded. Spawned
instead, each worker started a Python of its own and loaded them at its
first variant: 8 variants of the drawer took 15.2 s on one worker and
10.7 s on two (1.42 times as fast); forked, 12.3-13.0 and 7.8-8.1 s
(1.53-1.67 in three measurements), on this 2-core machine
(`benchmarks/bench_study.py --scaling`, 2026-11-28 22:50-23:08,
docs/performance.md). The server is single-threaded (no lock held by another
thread is copied into a worker), starts with the environment Dask's nanny
gives a worker it spawns (`SERVER_ENV`: threads at 1) and SIGINT ignored,
and is stopped with the cluster. A worker that dies is
started again by its nanny the default way (spawned). Its workers'
scratch space and the variants' temporary folders lie under one folder of
the study's (`Cluster.temp_root`), removed when the cluster closes: a worker
killed mid-variant leaves nothing behind. Within `closing_later` (the
command line's study) the cluster closes on a thread of its own while the
study writes its tables and plot.

This module runs no variant (see `cablecheck.study.execute`).

Dask (`distributed`) is imported inside the functions that use it: a study's
bad input (its file, scenes, address) is refused before Dask, slow to load, is.
"""

from __future__ import annotations

import asyncio
import logging
import multiprocessing
import multiprocessing.forkserver
import os
import shutil
import signal
import socket
import tempfile
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

POLL_S = 0.05
"""How often a wait looks at the stop request, seconds."""

CONNECT_TIMEOUT_S = 10.0
"""How long connecting to a scheduler (and its handshake) may take, seconds."""

WORKER_WAIT_S = 60.0
"""How long a study on a running scheduler waits for its first worker, seconds."""

SCHEMES = ("tcp", "tls")
"""Address schemes a study connects with."""

TLS_HINT = ("DASK_DISTRIBUTED__COMM__TLS__CA_FILE=ca.pem DASK_DISTRIBUTED__COMM__TLS__CLIENT__CERT=client.pem "
            "DASK_DISTRIBUTED__COMM__TLS__CLIENT__KEY=client.key")


class StudyRunError(Exception):
    """The cluster could not be used (a bad or unreachable scheduler address, no worker)."""


class Interrupted(KeyboardInterrupt):
    """The study was asked to stop while the cluster was being opened."""


@dataclass
class Cluster:
    """An open cluster.

    Attributes:
      client: the Dask client.
      temp_root: the folder the variants' temporary folders go in on the
        workers (the embedded cluster's, removed on closing), or None: each
        worker's own temporary folder.
    """

    client: object
    temp_root: str | None = None


def check_address(address: str) -> str:
    """`address` as Dask takes it (``scheme://host:port``), or StudyRunError
    naming ``--scheduler`` and what is wrong with it. Nothing connects."""
    where = f"--scheduler {address!r}"
    text = address.strip()
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    scheme = scheme.lower()
    if scheme not in SCHEMES:
        raise StudyRunError(f"{where}: the scheme {scheme + '://'!r} is not a Dask scheduler's; give "
                            "tcp://HOST:PORT (or tls://HOST:PORT with Dask's TLS configuration)")
    if not rest or "/" in rest or "?" in rest or "@" in rest:
        raise StudyRunError(f"{where}: expected HOST:PORT after {scheme}://, e.g. {scheme}://10.0.0.5:8786")
    if rest.startswith("["):   # [IPv6]:port
        host, bracket, port = rest[1:].partition("]")
        port = port[1:] if bracket and port.startswith(":") else ""
    else:
        host, _, port = rest.rpartition(":")
        if not _:
            host, port = rest, ""
    if not host:
        raise StudyRunError(f"{where}: no host; give {scheme}://HOST:PORT")
    if not port:
        raise StudyRunError(f"{where}: no port; give {scheme}://{host}:PORT (a scheduler's default is 8786)")
    if not port.isdigit() or not 0 < int(port) < 65536:
        raise StudyRunError(f"{where}: the port {port!r} is not a number from 1 to 65535")
    try:
        socket.getaddrinfo(host, int(port), type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as e:
        raise StudyRunError(f"{where}: the host {host!r} cannot be resolved ({e.strerror or e})") from None
    if scheme == "tls":
        _check_tls(where)
    shown = f"[{host}]" if ":" in host else host
    return f"{scheme}://{shown}:{int(port)}"


def _check_tls(where: str) -> None:
    """StudyRunError unless Dask's configuration gives the client a CA file and a certificate that exist."""
    from distributed.security import Security  # Dask loads here, not at import (module docstring)

    sec = Security()
    missing = [name for name, value in (("distributed.comm.tls.ca-file", sec.tls_ca_file),
                                        ("distributed.comm.tls.client.cert", sec.tls_client_cert))
               if not value]
    if missing:
        raise StudyRunError(f"{where}: a tls:// scheduler needs Dask's TLS configuration; "
                            f"{' and '.join(missing)} not set (e.g. {TLS_HINT})")
    for name, value in (("distributed.comm.tls.ca-file", sec.tls_ca_file),
                        ("distributed.comm.tls.client.cert", sec.tls_client_cert),
                        ("distributed.comm.tls.client.key", sec.tls_client_key)):
        if value and not Path(value).is_file():
            raise StudyRunError(f"{where}: {name} names {value!r}, which is no file")


def _wait(coro, timeout: float, stop):
    """Run `coro` in a fresh event loop in this thread; TimeoutError after
    `timeout` s, Interrupted once `stop.asked` (both cancel it)."""
    async def main():
        task = asyncio.ensure_future(coro)
        deadline = time.monotonic() + timeout
        try:
            while not task.done():
                if stop is not None and stop.asked:
                    raise Interrupted
                if time.monotonic() > deadline:
                    raise TimeoutError
                await asyncio.wait({task}, timeout=POLL_S)
            return task.result()
        finally:
            if not task.done():
                task.cancel()
                try:
                    await task
                except BaseException:   # its cancellation, or what it raised on the way out
                    pass

    return asyncio.run(main())


async def _identity(address: str, timeout: float) -> dict:
    """The scheduler's answer to Dask's identity request."""
    from distributed.comm import connect  # Dask loads here, not at import (module docstring)
    from distributed.security import Security  # Dask loads here, not at import (module docstring)

    comm = await connect(address, timeout=timeout, **Security().get_connection_args("client"))
    try:
        await comm.write({"op": "identity", "reply": True})
        return await comm.read()
    finally:
        comm.abort()


def probe(address: str, stop=None, timeout: float | None = None) -> None:
    """StudyRunError unless a Dask scheduler answers at `address` within
    `timeout` s (default CONNECT_TIMEOUT_S); Interrupted when a stop is asked meanwhile."""
    where = f"--scheduler {address!r}"
    timeout = CONNECT_TIMEOUT_S if timeout is None else timeout
    try:
        reply = _wait(_identity(address, timeout), timeout, stop)
    except TimeoutError:
        raise StudyRunError(f"{where}: no answer within {timeout:g} s (is it a Dask scheduler, "
                            "and reachable from here?)") from None
    except (OSError, ValueError, TypeError) as e:   # refused, reset, TLS handshake, comm errors
        raise StudyRunError(f"{where}: cannot connect: {' '.join(str(e).split()) or type(e).__name__}") from None
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        raise StudyRunError(f"{where}: something answered, but not a Dask scheduler ({str(reply)[:80]})")


@contextmanager
def cluster(workers: int | None, scheduler: str | None, stop=None):
    """A `Cluster` on the embedded local cluster or on `scheduler`; closed on leaving."""
    from distributed import Client  # Dask loads here, not at import (module docstring)

    if scheduler is not None:
        address = check_address(scheduler)
        probe(address, stop)
        try:
            client = Client(address, timeout=f"{CONNECT_TIMEOUT_S:g}s")
        except (OSError, TimeoutError, ValueError, TypeError) as e:
            raise StudyRunError(f"--scheduler {scheduler!r}: cannot connect: {e}") from None
        try:
            _wait_for_worker(client, scheduler, stop)
            yield Cluster(client)
        finally:
            client.close()
        return
    n = workers or os.cpu_count() or 1
    root = tempfile.mkdtemp(prefix="cablecheck-study-")
    local = client = None
    try:
        local = _local(n, root)
        client = Client(local)
        yield Cluster(client, temp_root=root)
    finally:
        if _LATER is not None:
            thread = threading.Thread(target=_close, args=(client, local, root), name="cablecheck-cluster-close")
            thread.start()
            _LATER.append(thread)
        else:
            _close(client, local, root)


def _local(n: int, root: str):
    """The embedded `LocalCluster` (see the module docstring)."""
    import dask  # Dask loads here, not at import (module docstring)
    from distributed import LocalCluster  # Dask loads here, not at import (module docstring)

    # each worker holds one variant at a time, the rest wait at the scheduler
    # for whichever worker is free first (Dask's default hands a worker a
    # second one to queue, which a worker still busy may then hold while
    # another is idle)
    method = "forkserver" if start_forkserver() else dask.config.get("distributed.worker.multiprocessing-method")
    import distributed.utils

    # the server's imports are ours (WORKER_IMPORTS): Dask's own list would import
    # its optional packages (pandas, lz4) into the study's process the first time
    distributed.utils._forkserver_preload_set = True
    with _sigint_ignored(), dask.config.set({"distributed.scheduler.worker-saturation": 1.0,
                                             "distributed.worker.multiprocessing-method": method}):
        # no dashboard; the scheduler's HTTP server (health and metrics
        # routes, started whatever dashboard_address says) on a free port of 127.0.0.1
        return LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                            dashboard_address="127.0.0.1:0",
                            scheduler_kwargs={"dashboard": False, "local_directory": root},
                            silence_logs=logging.ERROR, local_directory=root)


WORKER_IMPORTS = ("distributed", "numpy", "mujoco", "scipy.interpolate", "trimesh", "rerun", "cablecheck.scene.load",
                  "cablecheck.run.runner", "cablecheck.study.execute")
"""What the fork server loads for the workers forked from it: Dask, and what
a variant's run loads (`cablecheck.study.execute.run_variant`; trimesh for
a scene with mesh parts). A worker's first variant of the drawer then took
0.95 s against 0.93 for its next (spawned, 1.76 against 1.04)."""

SERVER_ENV = {"MALLOC_TRIM_THRESHOLD_": "65536", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "OPENBLAS_NUM_THREADS": "1"}
"""The fork server's (and so its workers') environment beyond this
process's: Dask's own `distributed.nanny.pre-spawn-environ` (one thread a
worker; freed memory given back to the system), which a nanny sets only
for a worker it spawns, not for one forked from the server."""

_SERVER: list = []
"""The fork server this process started and has not stopped (one at most)."""


def start_forkserver() -> bool:
    """Start the fork server the embedded cluster's workers are forked from
    (module docstring), unless it runs already; False where Python has no
    fork server (Windows): the workers are then spawned."""
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return False
    if _SERVER:
        return True
    multiprocessing.get_context("forkserver").set_forkserver_preload(list(WORKER_IMPORTS))
    old = {k: os.environ.get(k) for k in SERVER_ENV}
    os.environ.update(SERVER_ENV)
    try:
        with _sigint_ignored():       # the server, and every worker forked from it, ignore SIGINT
            multiprocessing.forkserver.ensure_running()
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    _SERVER.append(multiprocessing.forkserver)
    return True


def _stop_forkserver() -> None:
    """Stop the fork server (its workers have ended), waiting for it: no
    process outlives the study, and its CPU time is counted as its parent's.
    `ForkServer._stop` is Python's own (its test suite's); where it is
    missing the server ends with this process."""
    if _SERVER:
        module = _SERVER.pop()
        stop = getattr(getattr(module, "_forkserver", None), "_stop", None)
        if stop is not None:
            stop()


def _close(client, local, root: str) -> None:
    """Close the client and the embedded cluster (running tasks get a few
    seconds, then their processes end) and its fork server, then remove its
    temporary folder."""
    try:
        try:
            if client is not None:
                client.close()
        finally:
            if local is not None:
                local.close()
                _stop_forkserver()
    except KeyboardInterrupt:   # a second Ctrl-C: the worker processes, daemonic, end with us
        pass
    finally:
        shutil.rmtree(root, ignore_errors=True)


_LATER: list[threading.Thread] | None = None
"""Within `closing_later`: the threads closing embedded clusters."""


@contextmanager
def closing_later():
    """Within it, an embedded cluster that is left closes on a thread of its
    own (its processes end while the study writes its outputs); leaving it
    waits for them to be closed."""
    global _LATER
    outer, _LATER = _LATER, []
    try:
        yield
    finally:
        threads, _LATER = _LATER, outer
        for t in threads:
            t.join()


def _wait_for_worker(client, scheduler: str, stop) -> None:
    """Return once the scheduler has a worker; StudyRunError after
    WORKER_WAIT_S, Interrupted on a stop request."""
    deadline = time.monotonic() + WORKER_WAIT_S
    while not client.nthreads():
        if stop is not None and stop.asked:
            raise Interrupted
        if time.monotonic() > deadline:
            raise StudyRunError(f"no Dask worker joined the scheduler at {scheduler} within "
                                f"{WORKER_WAIT_S:g} s (start one: dask worker {scheduler} --host 127.0.0.1 "
                                "--nthreads 1 --no-dashboard)")
        time.sleep(0.2)


def workers_of(client) -> int:
    """How many workers the cluster has now."""
    return len(client.nthreads())


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
