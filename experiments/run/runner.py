"""Run the points of a sweep on a local process pool or a Dask cluster (executors.py), through the
result store (store.py): cached points are read, the others computed and stored as they finish.
Each computed point is locked in the store while it runs, so two runs sharing a store never compute
the same point twice: the second waits for the first's row."""
from __future__ import annotations

import os
import time
from contextlib import contextmanager
from pathlib import Path

from ..config import RenderConfig, config_hash, expand_sweep
from .executors import close as close_client, connect, dask, local
from .points import render_config
from .store import (RunStopped, StoreError, cached_row, check_locks, claim, images_dir as store_images_dir, lock_is_stale,
                    lock_path, release, store_point, table_path, to_frame, write_table, SweepRows)


_SWEEPS: dict | None = None  # inside sweeps_once(): id(config) -> (config, [(point, config, hash)])


@contextmanager
def sweeps_once():
    """Within this context each config object's sweep is expanded and hashed once (hashed_sweep):
    ``rast5d report`` reads a sweep for the pool, the sweep itself and its pictures. Outside it every
    call hashes again, so a file edited between two runs in one process gives its points new hashes."""
    global _SWEEPS
    outer = _SWEEPS
    _SWEEPS = {} if outer is None else outer
    try:
        yield
    finally:
        _SWEEPS = outer


def hashed_sweep(config: RenderConfig, source: str = "config", lines: dict | None = None) -> list:
    """[(point, point config, config_hash)] of config's sweep (expand_sweep); once per config object
    inside sweeps_once(). ``source`` and ``lines`` only name the place of an invalid point in its error."""
    hit = _SWEEPS.get(id(config)) if _SWEEPS is not None else None
    if hit is not None and hit[0] is config:
        return hit[1]
    out = [(point, cfg, config_hash(cfg)) for point, cfg in expand_sweep(config, source, lines)]
    if _SWEEPS is not None:
        _SWEEPS[id(config)] = (config, out)
    return out


def render_hash(config: RenderConfig) -> str:
    """The hash of the render whose work records a retime point re-times."""
    return config_hash(render_config(config))


def stored_row(h: str, images_dir=None, retry_failed: bool = False) -> dict | None:
    """The stored row of point ``h`` if it can be served: a row of a sweep with images needs its image
    too (a failed point has none)."""
    cached = cached_row(h, retry_failed=retry_failed)
    if cached is not None and (images_dir is None or cached.get("status") != "ok"
                               or (Path(images_dir) / f"{h}.png").exists()):
        return cached
    return None


def point_args(h: str, cfg: RenderConfig, images_dir, threads: int | None, keep_records=frozenset(),
               pictures: dict | None = None) -> tuple:
    """The run_point arguments of point ``h``: its image path (a sweep with images), the records it keeps
    for retime points (``keep_records``), the pictures a page draws of it (``pictures``: {hash: names})."""
    image = str(Path(images_dir) / f"{h}.png") if images_dir is not None else None
    return (cfg.model_dump_json(), image, threads, h if h in keep_records else None,
            tuple(sorted((pictures or {}).get(h, ()))))


def run_sweep(config: RenderConfig, *, name: str | None = None, source: str = "config", workers: int | None = None,
              scheduler=None, force: bool = False, images_dir: str | Path | None = None, progress: bool = True,
              lines: dict | None = None, retry_failed: bool = False, wait_poll_s: float = 0.5,
              keep_records: set[str] | frozenset[str] = frozenset(), pictures: dict | None = None,
              pooled: frozenset[str] = frozenset(), locks: bool = True, frame: bool = True):
    """Run every point of config's sweep; returns the sweep's table (pandas DataFrame, one row per point,
    in sweep order) and writes it to results/<name>.parquet. ``workers`` (default: executor.workers or the
    core count; 0 = in-process) is the local pool; ``scheduler`` (an address or a distributed.Client, or
    executor: {kind: dask}) runs the points on Dask instead. Stored failed points are served as failed
    unless ``retry_failed``. Points another run is computing (locked in the store) are waited for;
    ``locks=False`` (``rast5d run --no-lock``) takes and honours no lock (a point another run computes
    too keeps the row stored first). Ctrl-C raises KeyboardInterrupt after the finished points are
    saved; a fault of the store's disk or of the cluster raises StoreError or ClusterError (RunStopped)
    after the same. ``keep_records``: hashes of
    render points whose timing records a retime point will re-time (``rast5d report`` collects them):
    those points store their records, so the retime does not render them again. ``pictures``
    ({hash: names}, experiments/report/heatmaps.py pictured_points): what a page pictures of a point,
    kept in the store by its render. ``pooled``: hashes this process's report pool computes (their rows
    count as rendered by this run, not by another one). The result store must be writable
    (experiments.paths.check_results_dir), checked before the first render. ``frame=False`` returns
    the rows (store.SweepRows: a list of dicts with ``.summary``) instead of a DataFrame."""
    from ..paths import check_results_dir

    name = name or config.name or "experiment"
    ex = config.executor
    if scheduler is None and ex.kind == "dask":
        scheduler = ex.address
    if workers is None:
        workers = ex.workers or os.cpu_count() or 1
    swept = hashed_sweep(config, source, lines)  # every point validated: ConfigError listing the bad ones
    check_results_dir()  # before the first render
    if locks:
        locks = check_locks()  # a file system that cannot lock: a StoreWarning, and no locks
    points = [(point, cfg) for point, cfg, _ in swept]
    hashes = [h for _, _, h in swept]
    if config.outputs.images and images_dir is None:
        images_dir = store_images_dir(name)
    rows: dict[int, dict] = {}
    # Several processes on 2 cores: one engine thread per point (results do not depend on it).
    threads = 1 if (scheduler is not None or workers > 1) else None

    def from_store(i: int) -> dict | None:
        return stored_row(hashes[i], images_dir, retry_failed)

    def job(i: int) -> tuple:
        return i, point_args(hashes[i], points[i][1], images_dir, threads, keep_records, pictures)

    client = None
    if isinstance(scheduler, str):  # an address that does not answer stops the run before any lock
        client = connect(scheduler, ex.connect_timeout_s)
    todo, waiting = [], []
    n_pooled_early = 0
    claimed: set[str] = set()
    bar = None
    n_failed = 0
    n_done = 0
    n_kept = 0  # computed here, but another run stored the point first: its row is kept

    def finished(i: int, row: dict):
        nonlocal n_failed, n_done, n_kept
        n_done += 1
        rows[i] = row  # in the table even if Ctrl-C comes while it is stored
        try:
            stored = store_point(row, replace=force, replace_failed=retry_failed)
        except StoreError:
            del rows[i]  # not stored: not in the table either
            raise
        n_kept += stored is not row
        rows[i] = stored
        release(hashes[i])
        if stored.get("status") != "ok":
            n_failed += 1
        if bar is not None:
            bar.update(1)
            if stored.get("status") != "ok":
                bar.write(f"{name}: point {points[i][0]} failed: {stored.get('error')}")

    def execute(jobs):
        if scheduler is not None:
            dask(jobs, client if client is not None else scheduler, finished, point_timeout_s=ex.point_timeout_s,
                 connect_timeout_s=ex.connect_timeout_s)
        else:
            local(jobs, workers, finished, point_timeout_s=ex.point_timeout_s)

    t0 = time.perf_counter()
    interrupted = False
    stopped: RunStopped | None = None
    n_waited, n_pooled = 0, n_pooled_early
    try:
        for i, (point, cfg) in enumerate(points):
            h = hashes[i]
            cached = None if force else from_store(i)
            if cached is not None:
                rows[i] = cached
                n_pooled_early += h in pooled  # finished by this run's report pool before the sweep looked
                continue
            if h not in claimed and not claim(h, locks):  # another run is computing it
                waiting.append(i)
                continue
            claimed.add(h)
            todo.append(job(i))
        n_pooled = n_pooled_early
        if config.outputs.metrics is not None and todo:
            from .references import prepare_references

            prepare_references([points[i][1] for i, _ in todo], progress=progress)
        # retime points that re-time the same render: the first of each computes and stores the render, the
        # others run after it and read its records.
        phases = [todo]
        if config.point.kind == "retime":
            first: dict = {}
            for key, args in todo:
                first.setdefault(render_hash(points[key][1]), key)
            lead = set(first.values())
            phases = [[t for t in todo if t[0] in lead], [t for t in todo if t[0] not in lead]]
        if progress and todo:
            from tqdm import tqdm

            bar = tqdm(total=len(todo), desc=name, unit="point", dynamic_ncols=True)
        for phase in phases:
            if phase:  # nothing to compute: no pool is started
                execute(phase)
        # Points another run was computing: take its rows, or compute them if it gave up on them.
        while waiting:
            still = []
            for i in waiting:
                h = hashes[i]
                if lock_path(h).exists() and not lock_is_stale(lock_path(h)):
                    still.append(i)
                    continue
                row = from_store(i)
                if row is not None:
                    rows[i] = row
                    if h in pooled:
                        n_pooled += 1
                    else:
                        n_waited += 1
                elif claim(h, locks):
                    claimed.add(h)
                    execute([job(i)])
                else:
                    still.append(i)
            waiting = still
            if waiting:
                time.sleep(wait_poll_s)
    except KeyboardInterrupt:
        interrupted = True
    except RunStopped as e:  # a full or read-only store, a lost scheduler: keep what finished, then raise
        stopped = e
    finally:
        for h in claimed:
            release(h)
        if bar is not None:
            bar.close()
        if client is not None:
            close_client(client)
    ordered = [rows[i] for i in sorted(rows)]
    table = table_path(name)
    if ordered:
        try:
            write_table(ordered, table)
        except StoreError:
            if stopped is None:
                raise  # the disk filled or turned read-only at the table: the points are stored
            table = "no table written (the store cannot be written)"
    n_rendered = n_done + n_pooled
    n_cached = len(rows) - n_rendered - n_waited
    n_failed_stored = sum(1 for r in rows.values() if r.get("status") != "ok") - n_failed
    summary = {"points": len(points), "rendered": n_rendered, "cached": n_cached, "failed": n_failed,
               "failed_cached": n_failed_stored, "from_other_run": n_waited, "pooled": n_pooled,
               "stored_by_other_run": n_kept, "seconds": time.perf_counter() - t0}
    if frame:
        df = to_frame(ordered)
        df.attrs["summary"] = summary
    else:
        df = SweepRows(ordered)
        df.summary = summary
    if progress:
        extra = f", {n_waited} computed by another run" if n_waited else ""
        if n_kept:
            extra += f", {n_kept} also computed by another run, which stored them first (its rows kept)"
        stored = (f"; {n_failed_stored} failed point(s) served from the store (their error is kept: "
                  "`rast5d run --retry-failed` re-renders them)") if n_failed_stored else ""
        print(f"{name}: {len(rows)}/{len(points)} points ({n_rendered} rendered, {n_cached} cached{extra}, "
              f"{n_failed} failed{stored}) in {summary['seconds']:.1f} s -> {table}")
    if interrupted:
        raise KeyboardInterrupt
    if stopped is not None:
        raise stopped
    return df
