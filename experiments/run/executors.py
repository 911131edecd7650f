"""Executors: run the points of a sweep [(key, (config json, image path, threads))] and report each
finished row through ``finished(key, row)``: a local process pool (``local``; 0 workers = in-process)
or a Dask distributed cluster (``dask``)."""
from __future__ import annotations

import signal
import time

from .points import error_row, run_point


def worker_init():
    # The parent handles Ctrl-C (it cancels and terminates the pool); workers ignore SIGINT so an
    # interrupted sweep never leaves half-written rows.
    signal.signal(signal.SIGINT, signal.SIG_IGN)



def local(todo, workers: int, finished):
    """Run todo [(key, args)] on a process pool; call finished(key, row) as points finish.

    A point that kills its worker (a crash in native code) breaks the whole pool, and every point
    still pending in it fails with it; those points are then re-run one per fresh process, so only
    the point that crashes is recorded as an error."""
    if workers <= 0:  # in-process, serial (debugging)
        for key, args in todo:
            finished(key, run_point(*args))
        return
    broken = _pool_run(todo, workers, finished)
    for key, args in broken:  # isolate: one process per point
        if _pool_run([(key, args)], 1, finished):
            finished(key, error_row(args[0], "worker process died (crash in the engine?); the point was "
                                              "re-run alone and died again"))


def _pool_run(todo, workers: int, finished) -> list:
    """One process pool over todo; returns the (key, args) that did not finish because the pool broke."""
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    pool = ProcessPoolExecutor(max_workers=workers, initializer=worker_init)
    broken = []
    try:
        futures = {pool.submit(run_point, *args): (key, args) for key, args in todo}
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
    except KeyboardInterrupt:
        for proc in list(getattr(pool, "_processes", {}).values()):  # our own workers, by object
            proc.terminate()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
    return sorted(broken, key=lambda t: t[0])


def dask(todo, address, finished):
    """Run todo on a Dask distributed cluster at ``address`` (or an existing Client)."""
    from distributed import Client, as_completed

    client = address if isinstance(address, Client) else Client(address, set_as_default=False)
    try:
        futures = {}
        for key, args in todo:
            # pure=False: never reuse another submission's result; the store is the cache.
            futures[client.submit(run_point, *args, pure=False, key=f"rast5d-{key}-{time.time_ns()}")] = (key, args)
        try:
            for fut in as_completed(list(futures), loop=client.loop):
                key, args = futures[fut]
                try:
                    row = fut.result()
                except Exception as e:  # noqa: BLE001 - lost worker, serialisation, ...
                    row = error_row(args[0], f"dask: {type(e).__name__}: {e}", transient=True)
                finished(key, row)
        except KeyboardInterrupt:
            client.cancel(list(futures))
            raise
    finally:
        if client is not address:
            client.close()
