"""Reference images of the image-error metrics (experiments/run/metrics.py), cached in the store.

The reference of a point is the same scene, camera, pipeline and hardware rendered with
``outputs.metrics.reference_spp`` samples per pixel (>= 1024 in the reports) of a fixed-seed table
of ``reference_kind``, by ``reference_algorithm`` (every exact algorithm renders the same image from
the same table). It is cached as results/references/<hash>-<engine version>.npy.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..config import RenderConfig, build, config_hash
from . import metrics
from .store import atomic_write, engine_id, results_dir

REFERENCE_SEED = 2012  # fixed, and different from the seeds of the tables under test


def reference_config(config):
    """The config whose image is ``config``'s reference (see the module docstring)."""
    m = config.outputs.metrics
    d = config.model_dump(exclude={"sweep"})
    d["samples"] = {"kind": m.reference_kind, "spp": m.reference_spp, "seed": REFERENCE_SEED,
                    "period": config.samples.period, "lens": config.samples.lens, "time": config.samples.time}
    d["pipeline"].update(algorithm=m.reference_algorithm, count_optimal=False, lens_grid="auto")
    # The reference renders the full scene (no level of detail) with points: the line-sample
    # settings do not apply, so they take their defaults and do not split the reference cache.
    d["pipeline"].pop("lod", None)
    d["pipeline"].pop("lines", None)
    # Nor do the tile test's half-space modes (the reference's algorithm has none; every exact algorithm
    # renders the same image): a sweep over them shares one reference.
    d["pipeline"].pop("halfspace", None)
    d["outputs"] = {}
    return RenderConfig.model_validate(d)


def _reference_path(ref_config) -> Path:
    return results_dir() / "references" / f"{config_hash(ref_config)}-{engine_id()}.npy"


def reference_image(config, threads: int | None = None) -> np.ndarray:
    """The cached reference image of ``config`` (rendered on first use)."""
    import sim

    ref = reference_config(config)
    path = _reference_path(ref)
    if path.exists():
        return np.load(path)
    scene, camera, table, pipeline = build(ref)
    if threads is not None:
        pipeline = pipeline.replace(threads=threads)
    image = sim.render(scene, camera, table, pipeline, timing=False).image  # the image is all it needs
    atomic_write(path, lambda tmp: np.save(tmp, image), suffix=".npy")
    return image


def prepare_references(configs, progress: bool = True) -> None:
    """Render the distinct missing references of ``configs`` up front, with every core, so that the
    sweep's workers only read them."""
    todo = {}
    for c in configs:
        ref = reference_config(c)
        p = _reference_path(ref)
        if not p.exists():
            todo.setdefault(p, c)
    for i, (p, c) in enumerate(todo.items()):
        t0 = time.perf_counter()
        reference_image(c)
        if progress:
            print(f"reference {i + 1}/{len(todo)}: {c.scene.name or c.scene.path}, "
                  f"{c.outputs.metrics.reference_spp} spp -> {p.name} ({time.perf_counter() - t0:.1f} s)")


def point_metrics(config, image: np.ndarray) -> dict:
    """{metric.rmse, metric.psnr, metric.ssim, metric.ghosting[, metric.flip]} of a point's image against its
    reference."""
    ref = reference_image(config, threads=1)
    out = {"metric.rmse": metrics.rmse(image, ref), "metric.psnr": metrics.psnr(image, ref),
           "metric.ssim": metrics.ssim(image, ref), "metric.ghosting": metrics.ghosting(image, ref),
           "metric.reference_spp": config.outputs.metrics.reference_spp}
    if config.outputs.metrics.flip:
        out["metric.flip"] = metrics.flip(image, ref)
    return out
