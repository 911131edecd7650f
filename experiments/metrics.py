"""Image error metrics and the cached reference images they compare against.

All metrics compare linear RGB images clipped to [0, 1] (the engine's output range for our scenes):
- rmse: sqrt(mean((test - ref)^2)) over every pixel and channel;
- psnr: 10 log10(peak^2 / mse) [dB], peak 1 (inf for identical images);
- ssim: scikit-image's structural_similarity (Wang et al. 2004; Gaussian-free 7x7 window,
  data_range 1, mean over the channels);
- flip: mean LDR-FLIP (flip-evaluator; Andersson et al. 2020) on the sRGB-encoded images.

The reference of a point is the same scene, camera, pipeline and hardware rendered with
``outputs.metrics.reference_spp`` samples per pixel (>= 1024 in the reports) of a fixed-seed table
of ``reference_kind``, by ``reference_algorithm`` (every exact algorithm renders the same image from
the same table). It is cached as results/references/<hash>-<engine version>.npy.
"""
from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

REFERENCE_SEED = 2012  # fixed, and different from the seeds of the tables under test


def rmse(test: np.ndarray, ref: np.ndarray) -> float:
    test, ref = _pair(test, ref)
    return float(np.sqrt(np.mean((test - ref) ** 2)))


def psnr(test: np.ndarray, ref: np.ndarray, peak: float = 1.0) -> float:
    test, ref = _pair(test, ref)
    mse = float(np.mean((test - ref) ** 2))
    return float("inf") if mse == 0.0 else float(10.0 * np.log10(peak * peak / mse))


def ssim(test: np.ndarray, ref: np.ndarray) -> float:
    from skimage.metrics import structural_similarity

    test, ref = _pair(test, ref)
    if test.ndim == 3:
        return float(structural_similarity(test, ref, channel_axis=2, data_range=1.0))
    return float(structural_similarity(test, ref, data_range=1.0))


def flip(test: np.ndarray, ref: np.ndarray) -> float:
    """Mean LDR-FLIP of sRGB-encoded images (0 = identical)."""
    import flip_evaluator

    test, ref = _pair(test, ref)
    _, mean, _ = flip_evaluator.evaluate(_srgb(ref), _srgb(test), "LDR", inputsRGB=True, applyMagma=False)
    return float(mean)


def _srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055).astype(np.float32)


def _pair(test, ref) -> tuple[np.ndarray, np.ndarray]:
    test = np.asarray(test, dtype=np.float64)
    ref = np.asarray(ref, dtype=np.float64)
    if test.shape != ref.shape:
        raise ValueError(f"metrics: image shapes differ: test {test.shape}, reference {ref.shape}")
    return np.clip(test, 0.0, 1.0), np.clip(ref, 0.0, 1.0)


# ---- references ----------------------------------------------------------------------------------

def reference_config(config):
    """The config whose image is ``config``'s reference (see the module docstring)."""
    m = config.outputs.metrics
    d = config.model_dump(exclude={"sweep"})
    d["samples"] = {"kind": m.reference_kind, "spp": m.reference_spp, "seed": REFERENCE_SEED,
                    "period": config.samples.period, "lens": config.samples.lens, "time": config.samples.time}
    d["pipeline"].update(algorithm=m.reference_algorithm, count_optimal=False, lens_grid="auto")
    d["outputs"] = {}
    from .config import RenderConfig

    return RenderConfig.model_validate(d)


def _reference_path(ref_config) -> Path:
    from .config import config_hash
    from .runner import engine_id, results_dir

    return results_dir() / "references" / f"{config_hash(ref_config)}-{engine_id()}.npy"


def reference_image(config, threads: int | None = None) -> np.ndarray:
    """The cached reference image of ``config`` (rendered on first use)."""
    import sim

    from .config import build

    ref = reference_config(config)
    path = _reference_path(ref)
    if path.exists():
        return np.load(path)
    scene, camera, table, pipeline = build(ref)
    if threads is not None:
        pipeline = pipeline.replace(threads=threads)
    image = sim.render(scene, camera, table, pipeline).image
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + f".tmp{os.getpid()}.npy")
    np.save(tmp, image)
    os.replace(tmp, path)
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
    """{metric.rmse, metric.psnr, metric.ssim[, metric.flip]} of a point's image against its reference."""
    ref = reference_image(config, threads=1)
    out = {"metric.rmse": rmse(image, ref), "metric.psnr": psnr(image, ref), "metric.ssim": ssim(image, ref),
           "metric.reference_spp": config.outputs.metrics.reference_spp}
    if config.outputs.metrics.flip:
        out["metric.flip"] = flip(image, ref)
    return out
