"""Stochastic transparency ([McGuire 2010], "Stochastic Transparency"): screen-door
transparency with a random mask per sample, order independent, in one pass of the engine.

The engine keeps a covered sample of a triangle with opacity alpha with probability alpha
(backend/alpha.h; the scene's ``alpha``), so after the depth test each sample holds the nearest
surviving layer and the resolved pixel is, on average, the sorted "over" blend
c = a1 c1 + (1 - a1)(a2 c2 + (1 - a2)(...)) ([McGuire 2010], "Correct on average"). The reference,
``sorted_blend``, is a float64 ray cast that sorts every layer per sample position and blends;
depth peeling reaches the same image exactly in as many passes as the most layers any sample sees.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from ..render import _scene_arrays, render
from .common import UseResult, figures, ops_all, pinhole_rays, ray_triangle, tiled_samples, to_view, view_dirs, view_ray_triangle


def sorted_blend(scene, camera, table, *, chunk: int = 1 << 16) -> tuple[np.ndarray, np.ndarray]:
    """(image (H, W, 3), layers (H, W, spp)): per sample position of ``table`` (pinhole, the sample's
    time), every layer hit sorted by depth and composited front to back with the scene's alpha;
    layers counts the triangles each sample position hits. Background black."""
    p0, p1, col = _scene_arrays(scene)
    alpha = getattr(scene, "alpha", None)
    alpha = np.ones(p0.shape[0]) if alpha is None else np.asarray(alpha, np.float64)
    S = tiled_samples(table, camera)
    H, W, spp, _ = S.shape
    flat = S.reshape(-1, 5)
    out = np.zeros((flat.shape[0], 3))
    layers = np.zeros(flat.shape[0], np.int32)
    s_open, s_close = camera.shutter
    moving = not np.array_equal(p0, p1)
    view = to_view(camera, p0)
    for lo in range(0, flat.shape[0], chunk):
        f = flat[lo:lo + chunk]
        tau = s_open + f[:, 4] * (s_close - s_open)
        depth = np.full((p0.shape[0], f.shape[0]), np.inf)
        colour = np.zeros((p0.shape[0], f.shape[0], 3))
        if moving:
            o, d = pinhole_rays(camera, f[:, 0], f[:, 1])
        else:
            dx, dy = view_dirs(camera, f[:, 0], f[:, 1])
        for i in range(p0.shape[0]):
            if moving:
                hit, t, bary = ray_triangle(o, d, p0[i] + tau[:, None, None] * (p1[i] - p0[i]))
                colour[i] = bary @ col[i]
            else:
                hit, t, (b0, b1, b2) = view_ray_triangle(dx, dy, view[i])
                colour[i] = b0[:, None] * col[i, 0] + b1[:, None] * col[i, 1] + b2[:, None] * col[i, 2]
            depth[i] = np.where(hit, t, np.inf)
        order = np.argsort(depth, axis=0, kind="stable")
        dep = np.take_along_axis(depth, order, axis=0)
        a = np.where(np.isfinite(dep), alpha[order], 0.0)
        c = np.take_along_axis(colour, order[..., None], axis=0)
        trans = np.cumprod(np.vstack([np.ones((1, f.shape[0])), 1.0 - a[:-1]]), axis=0)
        out[lo:lo + chunk] = np.sum((trans * a)[..., None] * c, axis=0)
        layers[lo:lo + chunk] = np.isfinite(dep).sum(axis=0)
    per_sample = out.reshape(H, W, spp, 3)
    return per_sample.mean(axis=2).astype(np.float32), layers.reshape(H, W, spp)


def stochastic_transparency(scene, camera, table, pipeline=None, *, hardware=None, reference: bool = True
                            ) -> UseResult:
    """One order-independent pass of the engine over a scene with per-triangle ``alpha``; with
    ``reference`` also the sorted-blending reference at the same sample positions, the error, and
    depth peeling's work (max layers passes of the same scene rendered opaque at the same spp).

    Figures: transparency.rmse, transparency.max_layers, transparency.peel_samples_tested,
    transparency.peel_ops, transparency.ops (sim.uses.FIGURES)."""
    if getattr(scene, "alpha", None) is None:
        raise ConfigError("scene.alpha: stochastic transparency needs a scene with per-triangle alpha "
                          "(e.g. models.named('transparent_layers') or Scene.with_alpha)")
    if camera.coc_px != 0:
        raise ConfigError(f"camera.coc_px: the transparency reference is a pinhole ray cast, got {camera.coc_px!r}")
    r = render(scene, camera, table, pipeline, hardware=hardware)
    flat = dict(r.flat_stats)
    flat.update(figures(transparency__ops=ops_all(flat)))
    arrays = {}
    if reference:
        ref, layers = sorted_blend(scene, camera, table)
        opaque = render(scene.with_alpha(None) if hasattr(scene, "with_alpha") else _Opaque(scene), camera, table,
                        pipeline, hardware=hardware, timing=False).flat_stats
        passes = int(layers.max())
        flat.update(figures(
            transparency__rmse=float(np.sqrt(np.mean((r.image.astype(np.float64) - ref) ** 2))),
            transparency__max_layers=passes,
            transparency__peel_samples_tested=passes * int(opaque["raster.samples_tested"]),
            transparency__peel_ops=passes * ops_all(opaque)))
        arrays = {"reference": ref, "layers": layers}
    return UseResult(r.image, dict(sorted(flat.items())), arrays)


class _Opaque:
    """A duck-typed scene without alpha."""

    def __init__(self, scene):
        self.positions = scene.positions
        self.positions_t1 = getattr(scene, "positions_t1", None)
        self.colors = getattr(scene, "colors", None)
