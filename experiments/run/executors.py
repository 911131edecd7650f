"""Executors: run the points of a sweep [(key, (config json, image path, threads, ...))] and report each
finished row through ``finished(key, row)``: a local process pool (``local``; 0 workers = in-process)
or a Dask distributed cluster (``dask``).

Faults (docs/store.md):
- a local worker process that dies breaks the pool; its points are re-run one per fresh process, so
  only a point that kills its process is recorded as failed;
- a Dask worker that dies has its points re-run by Dask; a point that kills every worker it runs on
  (Dask's ``distributed.scheduler.allowed-failures``) is a stored error row, which names the memory
  when the worker's nanny restarted it for exceeding its ``memory_limit``;
- a lost Dask scheduler stops the run at once with a ClusterError naming it (the finished points are
  stored); a scheduler that does not answer is a ClusterError after ``executor.connect_timeout_s``;
- ``executor.point_timeout_s``: each point runs in a child process of its worker (one per worker
  thread, reused from point to point), which is killed when the point runs longer: an error row.
  On a Dask worker with a ``memory_limit`` the child is also stopped when it outgrows that limit.

``serve()`` is that child: it reads points from its stdin and writes their rows to its stdout
(length-prefixed pickles)."""
from __future__ import annotations

import functools
import os
import pickle
import signal
import struct
import sys
import threading
import time

from .points import error_row, run_point
from .store import RunStopped


class ClusterError(RunStopped):
    """The Dask scheduler did not answer, or was lost during the run (the finished points are stored)."""


def worker_init():
    # The parent handles Ctrl-C (it cancels and terminates the pool); workers ignore SIGINT so an
    # interrupted sweep never leaves half-written rows.
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _gib(n: float) -> str:
    return f"{n / 2 ** 30:.2f} GiB"


# ---- a point in a child process, stopped at a timeout -----------------------------------------------

_HEADER = struct.Struct(">Q")
_START_TIMEOUT_S = 300.0  # a child imports the engine before its first point (slow on a loaded machine)


def _send(fd: int, obj) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    view = memoryview(_HEADER.pack(len(data)) + data)
    while view:
        n = os.write(fd, view)
        view = view[n:]


class _Closed(Exception):
    """The other end of a child's pipe closed (the process died)."""


class _Child:
    """A child process running points for this thread (``serve``)."""

    def __init__(self):
        import subprocess

        self.setting = _setting()
        self.proc = subprocess.Popen([sys.executable, "-c", "from experiments.run.executors import serve; serve()"],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, start_new_session=True)
        self.buffer = b""
        try:
            ready = self.receive(time.monotonic() + _START_TIMEOUT_S)  # ("ready", pid) once it has imported
        except _Closed:
            self.kill()
            raise _Closed(f"it ended at start-up ({_describe_exit(self.proc.returncode)})") from None
        if not (isinstance(ready, tuple) and ready[0] == "ready"):
            self.kill()
            raise _Closed(f"no answer within {_START_TIMEOUT_S:g} s")

    def usable(self) -> bool:
        """Alive, and started in this process's current environment and folder (RAST5D_RESULTS, ...)."""
        return self.proc.poll() is None and self.setting == _setting()

    def kill(self) -> None:
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)  # its own session: the point's process and anything it started
        except (ProcessLookupError, PermissionError):
            pass
        self.proc.wait()
        for f in (self.proc.stdin, self.proc.stdout):
            try:
                f.close()
            except OSError:
                pass

    def receive(self, deadline: float, watch=None):
        """The next message, or None at ``deadline``; ``watch()`` is called about every 0.2 s while waiting
        (it may return a result that ends the wait). Raises _Closed if the child died."""
        import select

        fd = self.proc.stdout.fileno()
        while True:
            if len(self.buffer) >= _HEADER.size:
                (n,) = _HEADER.unpack_from(self.buffer)
                if len(self.buffer) >= _HEADER.size + n:
                    data = self.buffer[_HEADER.size:_HEADER.size + n]
                    self.buffer = self.buffer[_HEADER.size + n:]
                    return pickle.loads(data)
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            ready, _, _ = select.select([fd], [], [], min(left, 0.2))
            if ready:
                chunk = os.read(fd, 1 << 20)
                if not chunk:
                    raise _Closed("end of output")
                self.buffer += chunk
            elif watch is not None:
                seen = watch()
                if seen is not None:
                    return seen


_CHILDREN = threading.local()


def _setting() -> tuple:
    return os.getcwd(), dict(os.environ)


def _memory_limit() -> tuple[float, float] | None:
    """(memory_limit in bytes, the nanny's terminate fraction) of the Dask worker this runs on, or None."""
    if "distributed" not in sys.modules:  # not a Dask worker (a local pool's process)
        return None
    try:
        from distributed import get_worker

        worker = get_worker()
    except (ImportError, ValueError):
        return None
    manager = getattr(worker, "memory_manager", None)
    limit = getattr(manager, "memory_limit", None) or getattr(worker, "memory_limit", None)
    if not limit:
        return None
    import dask

    fraction = dask.config.get("distributed.worker.memory.terminate", 0.95)
    return (float(limit), float(fraction)) if fraction else None


def _rss(pid: int) -> int:
    try:
        import psutil

        return psutil.Process(pid).memory_info().rss
    except Exception:  # noqa: BLE001 - gone, or no psutil
        return 0


def _describe_exit(code: int | None) -> str:
    if code is not None and code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"


def timed_point(timeout_s: float, config_json: str, *args) -> dict:
    """run_point in a child process of this worker thread, stopped after ``timeout_s`` seconds (an error
    row naming executor.point_timeout_s) or when it outgrows the Dask worker's memory_limit (an error row
    naming the memory). A child that dies is replaced; the point is run once more, in a fresh child, and
    is an error row if that dies too."""
    job = (config_json, *args)
    died = None
    for _attempt in range(2):
        child = getattr(_CHILDREN, "child", None)
        if child is None or not child.usable():
            if child is not None:
                child.kill()
            try:
                child = _CHILDREN.child = _Child()
            except (_Closed, OSError) as e:
                _CHILDREN.child = None
                return error_row(config_json, f"executor.point_timeout_s: the point's child process could not "
                                              f"start ({e}); see the worker's log", transient=True)
        limit = _memory_limit()
        over: list = []

        def watch():
            if limit is not None:
                rss = _rss(child.proc.pid)
                if rss > limit[0] * limit[1]:
                    over.append(rss)
                    return ("memory", rss)
            return None

        t0 = time.monotonic()
        try:
            _send(child.proc.stdin.fileno(), job)
            message = child.receive(t0 + timeout_s, watch)
        except (_Closed, BrokenPipeError, OSError):
            child.kill()
            _CHILDREN.child = None
            died = child.proc.returncode
            continue
        if message is None:  # the timeout
            child.kill()
            _CHILDREN.child = None
            return error_row(config_json, (
                f"executor.point_timeout_s = {timeout_s:g}: the point ran longer than {timeout_s:g} s and was "
                "stopped (its process killed); it is stored as failed: `rast5d run --retry-failed` runs it again "
                "(raise executor.point_timeout_s if it needs longer)"))
        kind, value = message
        if kind == "memory":
            child.kill()
            _CHILDREN.child = None
            return error_row(config_json, (
                f"out of memory: the point's process grew to {_gib(value)} resident, over {limit[1]:.0%} of the "
                f"Dask worker's memory_limit ({_gib(limit[0])}), and was stopped; give the workers more memory "
                "(dask worker --memory-limit) or make the point smaller; `rast5d run --retry-failed` runs it again"))
        if kind == "raise":
            raise value
        return value
    return error_row(config_json, f"the point's process died ({_describe_exit(died)}) twice, in two fresh processes "
                                  "(a crash in the engine, or the system's out-of-memory killer?)")


def _die_with_parent() -> None:
    """Linux: this child is killed when the thread that started it ends (its worker died)."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def serve() -> None:
    """The child of timed_point: points from stdin, rows to stdout, until stdin closes."""
    out = os.dup(1)
    os.dup2(2, 1)  # whatever a point prints goes to stderr, not into the rows
    _die_with_parent()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _send(out, ("ready", os.getpid()))
    inp = sys.stdin.buffer
    while True:
        header = inp.read(_HEADER.size)
        if len(header) < _HEADER.size:
            return
        job = pickle.loads(inp.read(_HEADER.unpack(header)[0]))
        try:
            message = ("row", run_point(*job))
        except Exception as e:  # noqa: BLE001 - a store fault (StoreError): raised in the worker
            try:
                pickle.dumps(e)
                message = ("raise", e)
            except Exception:  # noqa: BLE001 - an exception that does not pickle
                message = ("raise", RuntimeError(f"{type(e).__name__}: {e}"))
        _send(out, message)


def _point_function(point_timeout_s: float | None):
    return run_point if point_timeout_s is None else functools.partial(timed_point, float(point_timeout_s))


# ---- the local pool ----------------------------------------------------------------------------------

def local(todo, workers: int, finished, point_timeout_s: float | None = None):
    """Run todo [(key, args)] on a process pool; call finished(key, row) as points finish.

    A point that kills its worker (a crash in native code) breaks the whole pool, and every point
    still pending in it fails with it; those points are then re-run one per fresh process, so only
    the point that crashes is recorded as an error. ``point_timeout_s``: see timed_point."""
    fn = _point_function(point_timeout_s)
    if workers <= 0:  # in-process, serial (debugging)
        for key, args in todo:
            finished(key, fn(*args))
        return
    broken = _pool_run(todo, workers, finished, fn)
    for key, args in broken:  # isolate: one process per point
        if _pool_run([(key, args)], 1, finished, fn):
            finished(key, error_row(args[0], "worker process died (crash in the engine?); the point was "
                                              "re-run alone and died again"))


def _pool_run(todo, workers: int, finished, fn=run_point) -> list:
    """One process pool over todo; returns the (key, args) that did not finish because the pool broke.
    Anything raised meanwhile (Ctrl-C, a store that cannot be written) terminates the pool's workers."""
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    pool = ProcessPoolExecutor(max_workers=workers, initializer=worker_init)
    broken = []
    try:
        futures = {pool.submit(fn, *args): (key, args) for key, args in todo}
        pending = set(futures)
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                try:
                    row = fut.result()
                except BrokenProcessPool:
                    broken.append(futures[fut])
                    continue
                finished(futures[fut][0], row)
    except BaseException:
        for proc in list((getattr(pool, "_processes", None) or {}).values()):  # our own workers, by object
            proc.terminate()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
    return sorted(broken, key=lambda t: t[0])


# ---- Dask ----------------------------------------------------------------------------------------------

def connect(address: str, timeout_s: float = 30.0):
    """A distributed.Client of the scheduler at ``address``; a ClusterError naming it if it does not
    answer within ``timeout_s`` seconds (executor.connect_timeout_s)."""
    from distributed import Client

    try:
        return Client(address, timeout=f"{float(timeout_s)}s", set_as_default=False)
    except (OSError, TimeoutError) as e:
        raise ClusterError(f"executor: the Dask scheduler at {address} did not answer within {timeout_s:g} s "
                           f"({type(e).__name__}: {e}); is it running, and is the address right? (--scheduler "
                           "ADDRESS or executor.address; executor.connect_timeout_s sets the wait)") from None
    except Exception as e:  # noqa: BLE001 - a malformed address, an unknown protocol
        raise ClusterError(f"executor: cannot connect to a Dask scheduler at {address!r} ({type(e).__name__}: {e}); "
                           "give an address such as tcp://host:8786 (--scheduler ADDRESS or executor.address)") from None


def _address(client) -> str:
    try:
        return client.scheduler.address
    except AttributeError:
        return str(client)


def _memory_kill(client, worker: str | None, since: float, wait_s: float = 15.0) -> tuple[float | None] | None:
    """(resident bytes or None,) if the nanny of ``worker`` restarted it for exceeding its memory budget
    since ``since``, else None: from the scheduler's event log (distributed >= 2024.2), else from the
    nannies' logs. A nanny answers for its logs only once its restarted worker has joined again: asked
    for up to ``wait_s`` seconds."""
    if not worker:
        return None
    deadline = time.monotonic() + wait_s
    while True:
        try:
            for t, event in client.get_events("worker-restart-memory"):
                if isinstance(event, dict) and event.get("worker") == worker and t >= since - 1:
                    return (float(event.get("rss") or 0) or None,)
        except Exception:  # noqa: BLE001 - a scheduler without the event
            pass
        try:
            logs = client.get_worker_logs(nanny=True)
        except Exception:  # noqa: BLE001 - a nanny restarting its worker
            logs = {}
        for lines in logs.values():
            for line in lines:
                text = line[1] if isinstance(line, (tuple, list)) and len(line) > 1 else str(line)
                if f"Worker {worker} (pid=" in text and "memory budget" in text:
                    return (None,)
        if time.monotonic() > deadline or client.status != "running":
            return None
        time.sleep(0.5)


def _failed_row(client, error: BaseException, config_json: str, since: float) -> dict:
    """The row of a point whose Dask task raised ``error`` (run_point itself never raises)."""
    if type(error).__name__ == "KilledWorker":
        last = getattr(error, "last_worker", None)
        address = getattr(last, "address", None)
        allowed = getattr(error, "allowed_failures", None)
        attempts = f"each of its {allowed + 1} attempts" if isinstance(allowed, int) else "each attempt"
        limit_note = (f" (allowed-failures = {allowed} in the scheduler's distributed.scheduler config)"
                      if isinstance(allowed, int) else "")
        memory = _memory_kill(client, address, since)
        if memory is not None:
            (rss,) = memory
            limit = getattr(last, "memory_limit", None)
            over = f"its memory_limit of {_gib(limit)}" if limit else "its memory_limit"
            size = f" ({_gib(rss)} resident)" if rss else ""
            return error_row(config_json, (
                f"out of memory: the point's Dask worker was restarted by its nanny for going over {over}{size}, "
                f"on {attempts}{limit_note}: the point needs more memory than a worker has; give the workers more "
                "(dask worker --memory-limit) or make the point smaller; `rast5d run --retry-failed` runs it again"))
        return error_row(config_json, (
            f"the point's Dask worker died on {attempts}{limit_note}: a crash in the engine, or workers killed "
            "from outside; `rast5d run --retry-failed` runs it again"))
    return error_row(config_json, f"dask: {type(error).__name__}: {error}", transient=True)


def _cancelled(fut) -> str | None:
    """Why the scheduler dropped ``fut`` (cancelled: the scheduler was lost or restarted), or None."""
    if fut.status != "cancelled":
        return None
    # the reason Dask gives ('scheduler-connection-lost'); reading it through result() would wait on a
    # client that is reconnecting
    text = str(getattr(getattr(fut, "_state", None), "exception", None) or "")
    return text.split("reason:", 1)[1].strip().split()[0].rstrip(".") if "reason:" in text else "its points were dropped"


def dask(todo, address, finished, point_timeout_s: float | None = None, connect_timeout_s: float = 30.0,
         poll_s: float = 0.1):
    """Run todo on a Dask distributed cluster at ``address`` (or an existing Client). Each result is
    fetched as soon as its point finishes (in the client's event loop, all at once) and then released,
    so a worker that dies later holds none of them. A lost scheduler stops the run with a ClusterError
    naming it, at once (the scheduler dropped the points) or after ``connect_timeout_s`` seconds without
    a connection; the points finished before are reported."""
    from concurrent.futures import CancelledError

    from distributed import Client, as_completed

    client = address if isinstance(address, Client) else connect(address, connect_timeout_s)
    where = _address(client)
    fn = _point_function(point_timeout_s)
    since = time.time()
    futures: dict = {}
    n_done = 0

    def lost(reason: str) -> ClusterError:
        return ClusterError(
            f"lost the Dask scheduler at {where} ({reason.strip().rstrip('.')}): {n_done} of this run's {len(todo)} "
            f"points finished and are stored, {len(todo) - n_done} were not computed. Start the scheduler (and its "
            "workers) again and rerun: the stored points are not computed again.")

    try:
        for key, args in todo:
            # pure=False: never reuse another submission's result; the store is the cache.
            fut = client.submit(fn, *args, pure=False, key=f"rast5d-{key}-{time.time_ns()}")
            futures[fut] = (key, args)
        arriving = as_completed(list(futures), loop=client.loop, with_results=True, raise_errors=False)
        disconnected = None
        no_workers = _NoWorkers(where)
        while futures:
            batch = arriving.next_batch(block=False) if arriving.has_ready() else []
            dropped = []
            for fut, result in batch:
                key, args = futures.pop(fut)
                status, why = fut.status, _cancelled(fut)
                fut.release()
                if status == "cancelled" or isinstance(result, CancelledError):
                    dropped.append(why or "cancelled")
                    continue
                if status == "error":
                    error = result[1] if isinstance(result, tuple) and len(result) == 3 else result
                    if isinstance(error, RunStopped):
                        raise error
                    if client.status != "running":  # its result went with the scheduler
                        dropped.append(f"connection {client.status}")
                        continue
                    row = _failed_row(client, error, args[0], since)
                else:
                    row = result
                n_done += 1
                finished(key, row)
            if dropped:
                raise lost(dropped[0])
            if client.status != "running":
                disconnected = disconnected or time.monotonic()
                if time.monotonic() - disconnected > connect_timeout_s:
                    raise lost(f"no connection for {connect_timeout_s:g} s; client status {client.status!r}")
            else:
                disconnected = None
                no_workers.check(client)
            if not batch:
                time.sleep(poll_s)
    except BaseException:
        if client.status == "running" and futures:
            try:
                client.cancel(list(futures))
            except Exception:  # noqa: BLE001 - the connection is going
                pass
        raise
    finally:
        if client is not address:
            close(client)


def close(client) -> None:
    """Close a Client; one whose scheduler is gone closes quietly (its reconnection attempts would log
    tracebacks after the run's own error has named the lost scheduler)."""
    import logging

    quiet = client.status != "running"
    loggers = [logging.getLogger(n) for n in ("distributed.client", "distributed.comm", "distributed.core")]
    levels = [lg.level for lg in loggers]
    if quiet:
        for lg in loggers:
            lg.setLevel(logging.CRITICAL)
    try:
        client.close(timeout=5)
    except Exception:  # noqa: BLE001 - a lost scheduler
        pass
    finally:
        for lg, level in zip(loggers, levels):
            lg.setLevel(level)


_NO_WORKERS_NOTE_S = 60.0


class _NoWorkers:
    """Says once (stderr) that the scheduler has had no worker for a minute: the sweep waits for one."""

    def __init__(self, where: str, every_s: float = 5.0):
        self.where, self.since, self.said = where, None, False
        self.every_s, self.last = every_s, time.monotonic()

    def check(self, client) -> None:
        if self.said or time.monotonic() - self.last < self.every_s:  # asking the scheduler is a round trip
            return
        self.last = time.monotonic()
        try:
            n = len(client.scheduler_info().get("workers", {}))
        except Exception:  # noqa: BLE001 - the connection is going; the caller sees it
            return
        now = time.monotonic()
        if n:
            self.since = None
        elif self.since is None:
            self.since = now
        elif now - self.since > _NO_WORKERS_NOTE_S:
            self.said = True
            print(f"rast5d: the Dask scheduler at {self.where} has had no worker for {_NO_WORKERS_NOTE_S:g} s; the "
                  f"sweep waits for one (start one with `dask worker {self.where}`)", file=sys.stderr)

