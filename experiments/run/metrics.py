"""Image error metrics.

All metrics compare linear RGB images clipped to [0, 1] (the engine's output range for our scenes):
- rmse: sqrt(mean((test - ref)^2)) over every pixel and channel;
- psnr: 10 log10(peak^2 / mse) [dB], peak 1 (inf for identical images);
- ssim: scikit-image's structural_similarity (Wang et al. 2004; Gaussian-free 7x7 window,
  data_range 1, mean over the channels);
- flip: mean LDR-FLIP (flip-evaluator; Andersson et al. 2020) on the sRGB-encoded images;
- ghosting: the lag-one spatial autocorrelation of the error ([Toth 2008] §2.2: accumulation buffering's
  ghosts are coherent copies, so neighbouring pixels err alike; per-pixel stochastic noise does not).

The reference images they compare against: experiments/run/references.py.
"""
from __future__ import annotations

import numpy as np


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


def ghosting(test: np.ndarray, ref: np.ndarray) -> float:
    """Spatial coherence of the error e = test - ref (channel mean, image mean removed): the mean
    over horizontal and vertical neighbour pairs of e(p) e(q), divided by the mean of e^2. About 0
    for independent per-pixel noise, towards 1 for ghosting ([Toth 2008] §2.2, §8); 0 for identical images."""
    test, ref = _pair(test, ref)
    e = test - ref
    if e.ndim == 3:
        e = e.mean(axis=2)
    e = e - e.mean()
    var = float(np.mean(e * e))
    if var == 0.0 or e.shape[0] < 2 or e.shape[1] < 2:
        return 0.0
    cx = float(np.mean(e[:, 1:] * e[:, :-1]))
    cy = float(np.mean(e[1:, :] * e[:-1, :]))
    return 0.5 * (cx + cy) / var


def _srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055).astype(np.float32)


def _pair(test, ref) -> tuple[np.ndarray, np.ndarray]:
    test = np.asarray(test, dtype=np.float64)
    ref = np.asarray(ref, dtype=np.float64)
    if test.shape != ref.shape:
        raise ValueError(f"metrics: image shapes differ: test {test.shape}, reference {ref.shape}")
    return np.clip(test, 0.0, 1.0), np.clip(ref, 0.0, 1.0)
