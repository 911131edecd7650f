"""Run the points of a sweep on a local process pool or a Dask cluster (executors.py), through the
result store (store.py): cached points are read, the others computed and stored as they finish."""
from __future__ import annotations

import os
import time
from pathlib import Path

from ..config import RenderConfig, config_hash, expand_sweep
from .executors import dask, local
from .points import render_config
from .store import cached_row, images_dir as store_images_dir, store_point, table_path, to_frame, write_parquet


def run_sweep(config: RenderConfig, *, name: str | None = None, source: str = "config", workers: int | None = None,
              scheduler=None, force: bool = False, images_dir: str | Path | None = None, progress: bool = True,
              lines: dict | None = None):
    """Run every point of config's sweep; returns the sweep's table (pandas DataFrame, one row per point,
    in sweep order) and writes it to results/<name>.parquet. ``workers`` (default: executor.workers or the
    core count; 0 = in-process) is the local pool; ``scheduler`` (an address or a distributed.Client, or
    executor: {kind: dask}) runs the points on Dask instead. Ctrl-C raises KeyboardInterrupt after the
    finished points are saved."""
    name = name or config.name or "experiment"
    ex = config.executor
    if scheduler is None and ex.kind == "dask":
        scheduler = ex.address
    if workers is None:
        workers = ex.workers or os.cpu_count() or 1
    points = expand_sweep(config, source, lines)
    if config.outputs.images and images_dir is None:
        images_dir = store_images_dir(name)
    rows: dict[int, dict] = {}
    todo = []
    for i, (point, cfg) in enumerate(points):
        h = config_hash(cfg)
        cached = None if force else cached_row(h)
        if cached is not None and (images_dir is None or (Path(images_dir) / f"{h}.png").exists()):
            rows[i] = cached
            continue
        image = str(Path(images_dir) / f"{h}.png") if images_dir is not None else None
        # Several processes on 2 cores: one engine thread per point (results do not depend on it).
        threads = 1 if (scheduler is not None or workers > 1) else None
        todo.append((i, (cfg.model_dump_json(), image, threads)))
    if config.outputs.metrics is not None and todo:
        from .references import prepare_references

        prepare_references([points[i][1] for i, _ in todo], progress=progress)
    # retime points that re-time the same render: the first of each computes and stores the render, the
    # others run after it and read its records.
    phases = [todo]
    if config.point.kind == "retime":
        first: dict = {}
        for key, args in todo:
            first.setdefault(config_hash(render_config(points[key][1])), key)
        lead = set(first.values())
        phases = [[t for t in todo if t[0] in lead], [t for t in todo if t[0] not in lead]]
    bar = None
    if progress and todo:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), desc=name, unit="point", dynamic_ncols=True)
    n_failed = 0

    def finished(i: int, row: dict):
        nonlocal n_failed
        rows[i] = row
        store_point(row)
        if row.get("status") != "ok":
            n_failed += 1
        if bar is not None:
            bar.update(1)
            if row.get("status") != "ok":
                bar.write(f"{name}: point {points[i][0]} failed: {row.get('error')}")

    t0 = time.perf_counter()
    interrupted = False
    try:
        for phase in phases:
            if scheduler is not None:
                dask(phase, scheduler, finished)
            else:
                local(phase, workers, finished)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        if bar is not None:
            bar.close()
    df = to_frame([rows[i] for i in sorted(rows)])
    if len(df):
        write_parquet(df, table_path(name))
    n_cached = len(rows) - (len(todo) if not interrupted else sum(1 for k, _ in todo if k in rows))
    summary = {"points": len(points), "rendered": len(rows) - n_cached, "cached": n_cached, "failed": n_failed,
               "seconds": time.perf_counter() - t0}
    df.attrs["summary"] = summary
    if progress:
        print(f"{name}: {len(rows)}/{len(points)} points ({summary['rendered']} rendered, {n_cached} cached, "
              f"{n_failed} failed) in {summary['seconds']:.1f} s -> {table_path(name)}")
    if interrupted:
        raise KeyboardInterrupt
    return df
