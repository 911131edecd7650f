"""One local process pool over the points of many sweeps (``rast5d report``): every missing point of
every config, each distinct point once (points shared between configs hash alike), and the reference
images their image metrics need, run largest first, so that no core idles at the tail of each sweep
while the next waits. Rows go to the result store as they finish; the sweeps then read them from it
(run_sweep), so pages and tables are built exactly as without this pass.

Order: reference images first (their points wait for them), then points by an estimate of their work
(pixels x samples per pixel x the blur and the algorithm's weight; estimate_cost). Only the order
depends on the estimate, never a result. Retime points are left to their sweeps (their renders are
kept for them: ``keep_records``). A pool broken by a crashing point stops this pass; the sweeps then
compute what is left, isolating the crash as they do.
"""
from __future__ import annotations

import heapq
import itertools

from ..config import RenderConfig, config_hash, expand_sweep
from .executors import worker_init
from .points import run_point
from .store import cached_row, claim, images_dir as store_images_dir, release, store_point

# Relative work per sample of an algorithm (estimate_cost); only the order of the pool uses it.
_ALGORITHM_WEIGHT = {"bruteforce": 2.0, "interleave": 3.0, "hinterleave": 3.0, "tile_interleaved": 3.0,
                     "accumulation": 3.0, "lines": 2.0}


def estimate_cost(config: RenderConfig, spp: int | None = None) -> float:
    """A rough, relative estimate of a point's CPU time, for ordering the pool (largest first)."""
    cam, params = config.camera, (config.scene.params or {})
    w = cam.width or params.get("width") or 640
    h = cam.height or params.get("height") or round(w * 9 / 16)
    spp = spp or config.samples.spp or 1
    if config.samples.kind == "lines":
        spp = 4 * (config.samples.n_lines or 4)
    coc = cam.coc_px or 0.0
    alg = config.pipeline.algorithm or "tile"
    weight = 1.0 if alg.startswith("gpu_") else _ALGORITHM_WEIGHT.get(alg, 1.0)
    return float(w) * float(h) * spp * (1.0 + coc / 10.0) * weight


def reference_job(config_json: str) -> None:
    """Render (and cache) the reference image of a point's metrics in a pool worker."""
    from . import references

    references.reference_image(RenderConfig.model_validate_json(config_json), threads=1)


def run_all(sweeps, *, workers: int, keep_records=frozenset(), force=frozenset(), retry_failed: bool = False,
            progress: bool = True) -> dict:
    """Compute every missing point of ``sweeps`` [(config, source, lines)] on one pool of ``workers``
    processes, largest first; configs named in ``force`` are recomputed. Returns {"computed": n,
    "complete": whether every job ran (False after a broken pool or Ctrl-C: the sweeps finish the rest)}."""
    from .references import _reference_path, reference_config

    jobs, seen, waits = [], set(), {}
    refs: dict = {}
    claimed: set[str] = set()
    for config, source, lines in sweeps:
        if config.point.kind == "retime":
            continue
        img_dir = store_images_dir(config.name) if config.outputs.images else None
        for _, cfg in expand_sweep(config, source, lines):
            h = config_hash(cfg)
            if h in seen:
                continue
            seen.add(h)
            if config.name not in force:
                cached = cached_row(h, retry_failed=retry_failed)
                if cached is not None and (img_dir is None or cached.get("status") != "ok"
                                           or (img_dir / f"{h}.png").exists()):
                    continue
            if not claim(h):  # another run is computing it; the sweep waits for its row
                continue
            claimed.add(h)
            image = str(img_dir / f"{h}.png") if img_dir is not None else None
            args = (cfg.model_dump_json(), image, 1) + ((h,) if h in keep_records else ())
            job = ("point", h, args, estimate_cost(cfg))
            if cfg.outputs.metrics is not None:
                ref = reference_config(cfg)
                path = _reference_path(ref)
                if not path.exists():
                    if path not in refs:
                        refs[path] = ("reference", path, (cfg.model_dump_json(),),
                                      estimate_cost(ref, cfg.outputs.metrics.reference_spp))
                    waits.setdefault(path, []).append(job)
                    continue
            jobs.append(job)
    total = len(jobs) + len(refs) + sum(len(v) for v in waits.values())
    if total == 0:
        return {"computed": 0, "complete": True}
    order = itertools.count()
    ready: list = []

    def push(job, first: bool = False):
        heapq.heappush(ready, (0 if first else 1, -job[3], next(order), job))

    for job in refs.values():
        push(job, first=True)
    for job in jobs:
        push(job)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=total, desc="report (all configs)", unit="job", dynamic_ncols=True)
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    computed, complete = 0, True
    pool = ProcessPoolExecutor(max_workers=max(1, workers), initializer=worker_init)
    running: dict = {}
    try:
        while ready or running:
            while ready and len(running) < max(1, workers):
                job = heapq.heappop(ready)[3]
                fn = reference_job if job[0] == "reference" else run_point
                running[pool.submit(fn, *job[2])] = job
            done, _ = wait(list(running), return_when=FIRST_COMPLETED)
            for fut in done:
                job = running.pop(fut)
                try:
                    result = fut.result()
                except BrokenProcessPool:
                    complete = False
                    raise
                except Exception:  # noqa: BLE001 - a reference that fails: its points render it themselves
                    result = None
                if job[0] == "reference":
                    for waiting in waits.pop(job[1], []):
                        push(waiting)
                else:
                    store_point(result)
                    release(job[1])
                    claimed.discard(job[1])
                    computed += 1
                if bar is not None:
                    bar.update(1)
    except BrokenProcessPool:
        complete = False
    except KeyboardInterrupt:
        for proc in list(getattr(pool, "_processes", {}).values()):  # our own workers, by object
            proc.terminate()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    finally:
        for h in claimed:
            release(h)
        if bar is not None:
            bar.close()
    pool.shutdown(wait=True)
    return {"computed": computed, "complete": complete}
