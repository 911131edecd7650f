"""Run the points of a sweep on a local process pool or a Dask cluster, into the result store.

Result store (results/, git-ignored):
- ``results/points/<config hash>-<engine version>.parquet``: one finished point (one row), written
  as soon as the point finishes (so Ctrl-C or a crash keeps every finished point). This is the
  cache: a rerun renders only the points whose file is missing; ``force=True`` re-renders.
- ``results/<name>.parquet``: the sweep's table (one row per point of the current sweep, failed
  points included with ``status = "error"`` and their message), written when the sweep ends or is
  interrupted; ``experiments.load(name)`` reads it.

A row is the flattened resolved config (``camera.coc_px``, ``samples.kind``, ``pipeline.algorithm``,
``hardware.setup.throughput``, ...; camera fields the scene's hint filled in are resolved), every
counter and derived figure of ``Result.flat_stats``, ``time.wall_s``, ``engine.version``,
``engine.git_rev``, ``config_hash``, ``status``, ``error`` (and ``metric.*`` with outputs.metrics).
"""
from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import time
import traceback
from pathlib import Path

from .config import REPO, RESULT_EXCLUDE, ConfigError, RenderConfig, build, config_hash, expand_sweep, flatten

RESULTS = Path(os.environ.get("RAST5D_RESULTS", REPO / "results"))
_ENGINE_ID = None
_GIT_REV = None


def results_dir() -> Path:
    return Path(os.environ.get("RAST5D_RESULTS", RESULTS))


def engine_id() -> str:
    """The engine version: a fingerprint of the compiled engine and of the Python that drives it
    (sim/, models/). Cached points are only reused by the same engine."""
    global _ENGINE_ID
    if _ENGINE_ID is None:
        import hashlib

        import sim

        h = hashlib.sha256(Path(sim._core.__file__).read_bytes())
        for folder in ("sim", "models"):
            for f in sorted((REPO / folder).glob("*.py")):
                h.update(f.read_bytes())
        _ENGINE_ID = h.hexdigest()[:12]
    return _ENGINE_ID


def git_rev() -> str:
    global _GIT_REV
    if _GIT_REV is None:
        try:
            rev = subprocess.check_output(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, text=True,
                                          stderr=subprocess.DEVNULL).strip()
            dirty = subprocess.run(["git", "diff", "--quiet", "HEAD", "--", "sim", "models", "experiments"],
                                   cwd=REPO, stderr=subprocess.DEVNULL).returncode
            _GIT_REV = rev + ("-dirty" if dirty else "")
        except Exception:  # noqa: BLE001 - not a git checkout
            _GIT_REV = "unknown"
    return _GIT_REV


def config_columns(config: RenderConfig, camera=None) -> dict:
    """The flattened resolved config of a point (hardware fully resolved; camera from the built camera)."""
    row = flatten(config.model_dump(exclude=RESULT_EXCLUDE | {"hardware"}))
    try:
        row.update(flatten({"hardware": config.hardware_config().describe()}))
    except Exception:  # noqa: BLE001 - validated on load; keep the row even if not
        pass
    if camera is not None:
        for k in ("width", "height", "fov_y_deg", "focus_distance", "coc_px", "aperture_radius", "lens", "near"):
            if hasattr(camera, k):
                v = getattr(camera, k)
                row[f"camera.{k}"] = v if isinstance(v, (int, float, str)) else json.dumps(v)
    row["config_hash"] = config_hash(config)
    return row


def render_point(config: RenderConfig, image_path: str | Path | None = None, threads: int | None = None
                 ) -> tuple[dict, object]:
    """Render one (non-swept) config: (row, sim.Result)."""
    import sim

    scene, camera, table, pipeline = build(config)
    if threads is not None and config.pipeline.threads == 0:
        pipeline = pipeline.replace(threads=threads)
    result = sim.render(scene, camera, table, pipeline, hardware=config.hardware_config())
    row = config_columns(config, camera)
    row["resolved.lens_grid"] = result.config.get("lens_grid")
    row["scene.triangles"] = scene.n_triangles
    row.update(result.flat_stats)
    if config.outputs.metrics is not None:
        from .metrics import point_metrics

        row.update(point_metrics(config, result.image))
    row.update(status="ok", error="", **{"engine.version": engine_id(), "engine.git_rev": git_rev()})
    if image_path is not None:
        Path(image_path).parent.mkdir(parents=True, exist_ok=True)
        result.save_png(image_path)
    return row, result


def run_point(config_json: str, image_path: str | None = None, threads: int | None = None) -> dict:
    """One point, isolated: any exception becomes a row with status 'error' (never raised)."""
    config = RenderConfig.model_validate_json(config_json)
    t0 = time.perf_counter()
    try:
        row, _ = render_point(config, image_path, threads)
    except Exception as e:  # noqa: BLE001 - a failing point must not stop the sweep
        row = config_columns(config)
        row.update(status="error", error=f"{type(e).__name__}: {e}", traceback=traceback.format_exc(limit=4),
                   **{"engine.version": engine_id(), "engine.git_rev": git_rev(),
                      "time.wall_s": time.perf_counter() - t0})
    return row


def _worker_init():
    # The parent handles Ctrl-C (it cancels and terminates the pool); workers ignore SIGINT so an
    # interrupted sweep never leaves half-written rows.
    signal.signal(signal.SIGINT, signal.SIG_IGN)


# ---- store -------------------------------------------------------------------------------------

def _point_path(h: str) -> Path:
    return results_dir() / "points" / f"{h}-{engine_id()}.parquet"


def _to_frame(rows: list[dict]):
    import pandas as pd

    df = pd.DataFrame([{k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in r.items()}
                       for r in rows])
    for col in df.columns:  # Parquet needs one type per column: mixed columns become text
        if df[col].dtype == object:
            types = {type(v) for v in df[col] if v is not None}
            if len(types) > 1 and not types <= {int, float}:
                df[col] = [None if v is None else str(v) for v in df[col]]
            elif types <= {int, float} and types:
                df[col] = df[col].astype(float)
    return df


def _write_parquet(df, path: Path):
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + f".tmp{os.getpid()}")
    df.to_parquet(tmp, index=False, engine="pyarrow")
    os.replace(tmp, path)  # atomic: a reader never sees half a file


def _store_point(row: dict):
    if row.get("status") == "ok":
        _write_parquet(_to_frame([row]), _point_path(row["config_hash"]))


def _cached_row(h: str) -> dict | None:
    import pandas as pd

    p = _point_path(h)
    if not p.exists():
        return None
    try:
        return pd.read_parquet(p).iloc[0].to_dict()
    except Exception:  # noqa: BLE001 - a corrupt cache file is recomputed
        return None


def table_path(name: str) -> Path:
    return results_dir() / f"{name}.parquet"


def load(name: str):
    """The result table of experiment ``name`` (results/<name>.parquet) as a pandas DataFrame."""
    import pandas as pd

    p = table_path(name)
    if not p.exists():
        known = sorted(q.stem for q in results_dir().glob("*.parquet"))
        raise FileNotFoundError(f"no results for {name!r} ({p}); run `rast5d run` first (known: {known})")
    return pd.read_parquet(p)


# ---- executors ---------------------------------------------------------------------------------

def _local(todo, workers: int, finished):
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
            finished(key, _error_row(args[0], "worker process died (crash in the engine?); the point was "
                                              "re-run alone and died again"))


def _pool_run(todo, workers: int, finished) -> list:
    """One process pool over todo; returns the (key, args) that did not finish because the pool broke."""
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    pool = ProcessPoolExecutor(max_workers=workers, initializer=_worker_init)
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


def _dask(todo, address, finished):
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
                    row = _error_row(args[0], f"dask: {type(e).__name__}: {e}")
                finished(key, row)
        except KeyboardInterrupt:
            client.cancel(list(futures))
            raise
    finally:
        if client is not address:
            client.close()


def _error_row(config_json: str, message: str) -> dict:
    config = RenderConfig.model_validate_json(config_json)
    row = config_columns(config)
    row.update(status="error", error=message, **{"engine.version": engine_id(), "engine.git_rev": git_rev()})
    return row


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
        images_dir = results_dir() / "images" / name
    rows: dict[int, dict] = {}
    todo = []
    for i, (point, cfg) in enumerate(points):
        h = config_hash(cfg)
        cached = None if force else _cached_row(h)
        if cached is not None and (images_dir is None or (Path(images_dir) / f"{h}.png").exists()):
            rows[i] = cached
            continue
        image = str(Path(images_dir) / f"{h}.png") if images_dir is not None else None
        # Several processes on 2 cores: one engine thread per point (results do not depend on it).
        threads = 1 if (scheduler is not None or workers > 1) else None
        todo.append((i, (cfg.model_dump_json(), image, threads)))
    if config.outputs.metrics is not None and todo:
        from .metrics import prepare_references

        prepare_references([points[i][1] for i, _ in todo], progress=progress)
    bar = None
    if progress and todo:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), desc=name, unit="point", dynamic_ncols=True)
    n_failed = 0

    def finished(i: int, row: dict):
        nonlocal n_failed
        rows[i] = row
        _store_point(row)
        if row.get("status") != "ok":
            n_failed += 1
        if bar is not None:
            bar.update(1)
            if row.get("status") != "ok":
                bar.write(f"{name}: point {points[i][0]} failed: {row.get('error')}")

    t0 = time.perf_counter()
    interrupted = False
    try:
        if scheduler is not None:
            _dask(todo, scheduler, finished)
        else:
            _local(todo, workers, finished)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        if bar is not None:
            bar.close()
    df = _to_frame([rows[i] for i in sorted(rows)])
    if len(df):
        _write_parquet(df, table_path(name))
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


__all__ = ["run_sweep", "load", "render_point", "run_point", "engine_id", "git_rev", "ConfigError"]
