"""One local process pool over the points of many sweeps (``rast5d report``): every missing point of
every config, each distinct point once (points shared between configs hash alike), and the reference
images their image metrics need. Rows go to the result store as they finish; the sweeps then read them
from it (run_sweep), so pages and tables are built exactly as without this pass.

Order: reference images first (their points wait for them); then config after config, the costliest
first, and each config's largest points first, by an estimate of their work (pixels x samples per pixel
x the blur and the algorithm's weight; estimate_cost). Configs complete one after the other while their
sections are written (PoolRun.wait_ready), and the small points of the lightest configs fill the end,
so no core idles there. Only the order depends on the estimate, never a result. Retime points run after
the render whose records they re-time (kept for them: ``keep_records``). A pool broken by a crashing
point stops this pass; the sweeps then compute what is left, isolating the crash as they do.
"""
from __future__ import annotations

import functools
import heapq
import itertools
import threading

import sim

from ..config import RenderConfig
from .executors import timed_point, worker_init

from .points import run_point
from .runner import hashed_sweep, point_args, render_hash, stored_row
from .store import claim, images_dir as store_images_dir, records_path, release, store_point

# Relative work per sample of an algorithm (estimate_cost); only the order of the pool uses it.
_ALGORITHM_WEIGHT = {"bruteforce": 2.0, "interleave": 3.0, "hinterleave": 3.0, "tile_interleaved": 3.0,
                     "accumulation": 3.0, "lines": 2.0}


def estimate_cost(config: RenderConfig, spp: int | None = None) -> float:
    """A rough, relative estimate of a point's CPU time, for ordering the pool."""
    cam, params = config.camera, (config.scene.params or {})
    w = cam.width or params.get("width") or 640
    h = cam.height or params.get("height") or round(w * 9 / 16)
    spp = spp or config.samples.spp or 1
    if config.samples.kind == "lines":
        spp = 4 * (config.samples.n_lines or 4)
    coc = cam.coc_px or 0.0
    alg = config.pipeline.algorithm or "tile"
    try:
        gpu = sim.algorithm_info(alg).pipeline == "gpu"
    except sim.ConfigError:
        gpu = False
    weight = 1.0 if gpu else _ALGORITHM_WEIGHT.get(alg, 1.0)
    return float(w) * float(h) * spp * (1.0 + coc / 10.0) * weight


def reference_job(config_json: str) -> None:
    """Render (and cache) the reference image of a point's metrics in a pool worker."""
    from . import references

    references.reference_image(RenderConfig.model_validate_json(config_json), threads=1)


def pool_label(configs, width: int = 40) -> str:
    """The progress bar's label: the names of the configs being run ('report: fig14, fig15 +12 more')."""
    names = [c.name for c in configs]
    text = ""
    for i, n in enumerate(names):
        more = len(names) - i - 1
        cand = (text + ", " if text else "") + n
        if len(cand) > width and text:
            return f"report: {text} +{len(names) - i} more"
        text = cand
    return f"report: {text}" if text else "report"


def run_all(sweeps, *, workers: int, keep_records=frozenset(), force=frozenset(), retry_failed: bool = False,
            progress: bool = True, background: bool = False, pictures: dict | None = None) -> "PoolRun":
    """Compute every missing point of ``sweeps`` [(config, source, lines)] on one pool of ``workers``
    processes, config after config (the costliest first, its largest points first; see PoolRun._push);
    configs named in ``force`` are recomputed. Every job's point is claimed
    (locked in the store) before this returns, so a sweep run meanwhile waits for its rows instead of
    computing them. ``background``: the pool runs in a thread (PoolRun.join waits for it).
    ``keep_records`` and ``pictures`` as for run_sweep."""
    from .references import _reference_path, reference_config

    jobs, seen, waits = [], set(), {}
    refs: dict = {}
    claimed: set[str] = set()
    timeouts: dict[str, float] = {}  # executor.point_timeout_s of the points whose config sets it
    rendering: set[str] = set()  # render points of this pool (their hashes)
    retimes = []
    by_config: dict[str, set[str]] = {}  # every point of each config (a point shared by two: in both)
    group: dict = {}  # a job's key (point hash, reference path) -> the config that listed it first
    group_cost: dict[str, float] = {}  # the estimated cost of each config's jobs

    def listed(key, name: str, cost: float) -> None:
        group[key] = name
        group_cost[name] = group_cost.get(name, 0.0) + cost
    for config, source, lines in sweeps:
        img_dir = store_images_dir(config.name) if config.outputs.images else None
        for _, cfg, h in hashed_sweep(config, source, lines):
            by_config.setdefault(config.name, set()).add(h)
            if h in seen:
                continue
            seen.add(h)
            if config.name not in force and stored_row(h, img_dir, retry_failed) is not None:
                continue
            if not claim(h):  # another run is computing it; the sweep waits for its row
                continue
            claimed.add(h)
            if config.executor.point_timeout_s is not None:
                timeouts[h] = config.executor.point_timeout_s
            if config.point.kind == "retime":
                retimes.append((h, cfg, config.name))
                continue
            job = ("point", h, point_args(h, cfg, img_dir, 1, keep_records, pictures), estimate_cost(cfg), h)
            listed(h, config.name, job[3])
            rendering.add(h)
            if cfg.outputs.metrics is not None:
                ref = reference_config(cfg)
                path = _reference_path(ref)
                if not path.exists():
                    if path not in refs:
                        refs[path] = ("reference", path, (cfg.model_dump_json(),),
                                      estimate_cost(ref, cfg.outputs.metrics.reference_spp), path)
                        listed(path, config.name, refs[path][3])
                    waits.setdefault(path, []).append(job)
                    continue
            jobs.append(job)
    # Retime points re-time their render's stored records: after that render (a point of this pool, or
    # the first retime point of the render, which renders and stores it).
    leads: set[str] = set()
    for h, cfg, name in retimes:
        rh = render_hash(cfg)
        if rh in rendering or rh in leads:
            job = ("point", h, point_args(h, cfg, None, 1), 1.0, None)
            waits.setdefault(rh, []).append(job)
        elif records_path(rh).exists():
            job = ("point", h, point_args(h, cfg, None, 1), 1.0, None)
            jobs.append(job)
        else:
            leads.add(rh)
            job = ("point", h, point_args(h, cfg, None, 1), estimate_cost(cfg), rh)
            jobs.append(job)
        listed(h, name, job[3])
    total = len(jobs) + len(refs) + sum(len(v) for v in waits.values())
    run = PoolRun(refs, jobs, waits, claimed, workers, progress, total, label=pool_label([c for c, _, _ in sweeps]),
                  timeouts=timeouts, groups=(group, group_cost), by_config=by_config)
    if background:
        run.start()
    else:
        run.loop()
    return run


class PoolRun:
    """The pool of run_all; ``start()`` runs it in a thread (the caller writes pages meanwhile and waits
    for the rows through the store's point locks), ``loop()`` in the caller. ``computed``: points
    stored; ``complete``: every job ran (after a broken pool the sweeps compute what is left)."""

    def __init__(self, refs, jobs, waits, claimed, workers, progress, total, label: str = "report",
                 timeouts: dict | None = None, groups: tuple = ({}, {}), by_config: dict | None = None):
        self.waits, self.claimed, self.workers = waits, claimed, max(1, workers)
        self._group, self._group_cost = groups
        self.timeouts = timeouts or {}
        self.hashes = frozenset(claimed)  # the points this pool computes (the sweeps wait for their rows)
        # of each config's points, those this pool computes (wait_ready)
        self.by_config = {name: hashes & self.hashes for name, hashes in (by_config or {}).items()}
        self._stored = threading.Condition()  # notified as the pool stores a row, and when it ends
        self.computed, self.complete, self.total = 0, True, total
        self._order = itertools.count()
        self._ready: list = []
        for job in refs.values():
            self._push(job, first=True)
        for job in jobs:
            self._push(job)
        self._thread = None
        self._stop = False
        self._bar = None
        if progress and total:
            from tqdm import tqdm

            self._bar = tqdm(total=total, desc=label, unit="job", dynamic_ncols=True)
        self._pool = None
        self._running: dict = {}
        if total:
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(max_workers=self.workers, initializer=worker_init)
            self._fill()  # forks the workers now, before the caller's thread does anything else

    def _push(self, job, first: bool = False):
        # The references first; then config after config, the costliest config first, and within one
        # its largest points first: configs complete one after the other (their sections are written
        # while the pool works on), and the smallest points of the lightest configs fill the end.
        name = self._group.get(job[1], "")
        heapq.heappush(self._ready, (0 if first else 1, -self._group_cost.get(name, 0.0), name, -job[3],
                                     next(self._order), job))

    def _fill(self):
        while self._ready and len(self._running) < self.workers and not self._stop:
            job = heapq.heappop(self._ready)[-1]
            fn = reference_job if job[0] == "reference" else run_point
            if job[0] == "point" and job[1] in self.timeouts:
                fn = functools.partial(timed_point, self.timeouts[job[1]])
            self._running[self._pool.submit(fn, *job[2])] = job

    def ready(self, name: str) -> bool:
        """Every point of config ``name`` that this pool computes is stored (or the pool has ended)."""
        return not (self.by_config.get(name, set()) & self.claimed) or not self.running()

    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def wait_ready(self, names: list[str]) -> int:
        """The index in ``names`` of the first config that is ready, waiting for the pool's rows until
        one is (0 once the pool has ended: its sweep then computes what is left itself)."""
        with self._stored:
            while True:
                for i, name in enumerate(names):
                    if self.ready(name):
                        return i
                self._stored.wait(1.0)

    def start(self):
        self._thread = threading.Thread(target=self.loop, name="rast5d-report-pool", daemon=True)
        self._thread.start()

    def join(self):
        if self._thread is not None:
            self._thread.join()

    def stop(self):
        """Ctrl-C: terminate our own workers (by object) and give up the claims."""
        self._stop = True
        if self._pool is not None:
            for proc in list((getattr(self._pool, "_processes", None) or {}).values()):
                proc.terminate()
            self._pool.shutdown(wait=False, cancel_futures=True)
        self._release_all()

    def _release_all(self):
        for h in list(self.claimed):
            release(h)
        self.claimed.clear()

    def loop(self):
        from concurrent.futures import FIRST_COMPLETED, wait
        from concurrent.futures.process import BrokenProcessPool

        try:
            while (self._ready or self._running) and not self._stop:
                self._fill()
                done, _ = wait(list(self._running), return_when=FIRST_COMPLETED)
                for fut in done:
                    job = self._running.pop(fut)
                    try:
                        result = fut.result()
                    except BrokenProcessPool:
                        raise
                    except Exception:  # noqa: BLE001 - a failed reference: its points render it themselves
                        result = None
                    for waiting in self.waits.pop(job[4], []) if job[4] is not None else ():
                        self._push(waiting)
                    if job[0] == "point" and result is not None:
                        store_point(result)
                        release(job[1])
                        with self._stored:
                            self.claimed.discard(job[1])
                            self._stored.notify_all()
                        self.computed += 1
                    if self._bar is not None:
                        self._bar.update(1)
        except BrokenProcessPool:
            self.complete = False
        except Exception:  # noqa: BLE001 - the sweeps compute whatever is left
            self.complete = False
        finally:
            if self._stop:
                self.complete = False
            with self._stored:
                self._release_all()
                self._stored.notify_all()
            if self._bar is not None:
                self._bar.close()
            if self._pool is not None:
                self._pool.shutdown(wait=not self._stop)
