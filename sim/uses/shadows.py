"""Motion-blurred soft shadows from a 5D shadow map ([Nilsson 2012] §7, Fig. 15).

The area light is the light camera's lens: a square light of half-size R is a "square" lens of
aperture radius R with the focus plane at infinity (a large focus distance), so lens position (u, v)
is the light point (u R, v R) and every lens position sees the same directions. A fixed set of N
(u, v, t) samples, the same in every shadow-map pixel (a programmable sample table, [Nilsson 2012] §2), makes
the one-pass render an array of N 2D shadow maps indexed by sample (the 5D shadow map). The camera
pass is a motion-blurred render whose sample s has the same t_s; each of its hits is shadow-tested
against map s (a traditional look-up with that sample's light position). Accumulation buffering
renders the same N maps in N passes of one sample each. With N fixed samples the penumbra shows N+1
visibility levels at most: the banding [Nilsson 2012] mentions.
"""
from __future__ import annotations

import numpy as np

from ..camera import Camera
from ..errors import ConfigError
from ..render import _scene_arrays, render
from ..sample_table import SampleTable
from .common import UseResult, figures, ops_all, pinhole_rays, tiled_samples

_FOCUS_AT_INFINITY = 1.0e4  # light focus distance: far beyond the scene ([Nilsson 2012] Fig. 15)


def light_samples(n: int, seed: int = 0) -> np.ndarray:
    """(n*n, 3) fixed (u, v, t): the centres of an n x n grid on the square light, each with its own
    time t_s = (k + 0.5) / n^2 in a seeded random order."""
    k = np.arange(n * n)
    u = ((k % n) + 0.5) / n * 2 - 1
    v = ((k // n) + 0.5) / n * 2 - 1
    t = (np.random.default_rng(seed).permutation(n * n) + 0.5) / (n * n)
    return np.stack([u, v, t], 1)


def light_camera(center, half_size: float, fov_deg: float, resolution: int) -> Camera:
    c = np.asarray(center, np.float64)
    return Camera(width=resolution, height=resolution, fov_y_deg=fov_deg, focus_distance=_FOCUS_AT_INFINITY,
                  aperture_radius=half_size, lens="square", eye=c, target=c - np.array([0.0, 1.0, 0.0]),
                  up=(0.0, 0.0, -1.0), near=0.05)


def _map_table(uvt: np.ndarray) -> SampleTable:
    s = np.zeros((len(uvt), 5))
    s[:, 0:2] = 0.5
    s[:, 2:5] = uvt
    return SampleTable.from_array(s, lens="square")


def shadow_maps(scene, light: Camera, uvt: np.ndarray, pipeline=None, *, hardware=None):
    """(maps (H, W, N) view depth w of the nearest occluder, +inf empty; flat stats) of the one-pass
    5D shadow map."""
    r = render(scene, light, _map_table(uvt), pipeline, export_samples=True, hardware=hardware, timing=False)
    return _as_w(r.sample_depth, light.near), r.flat_stats


def _as_w(z, near):
    with np.errstate(divide="ignore"):
        return np.where(np.isfinite(z), near / (1.0 - z.astype(np.float64)), np.inf)


def lookup(light: Camera, maps: np.ndarray, points: np.ndarray, sample: np.ndarray, uvt: np.ndarray,
           bias: float = 2e-3) -> np.ndarray:
    """Lit (bool) of world points (M, 3) seen from light sample `sample` (M,): project into the light
    view at lens (u_s, v_s) (the thin-lens shear x' = x + u K (1 - F / w)), take the map texel, compare
    view depths with a relative bias."""
    H, W, _ = maps.shape
    e = light.clip_to_engine(light.world_to_clip(points))
    w = e[:, 2]
    K = light.coc_px
    shear = 1.0 - light.focus_distance / w
    x = e[:, 0] / w + uvt[sample, 0] * K * shear
    y = e[:, 1] / w - uvt[sample, 1] * K * shear
    ix, iy = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    inside = (w > 0) & (ix >= 0) & (ix < W) & (iy >= 0) & (iy < H)
    occ = np.full(len(points), np.inf)
    occ[inside] = maps[iy[inside], ix[inside], sample[inside]]
    return ~inside | (w <= occ * (1.0 + bias))


def soft_shadows(scene, camera, table, pipeline=None, *, hardware=None, light_center=(-0.8, 2.0, 0.0),
                 light_half_size: float = 0.3, light_fov_deg: float = 90.0, light_resolution: int = 128,
                 light_grid: int = 4, reference_grid: int = 16, ambient: float = 0.25, accumulation: bool = True,
                 seed: int = 0) -> UseResult:
    """One-pass 5D shadow map over light_grid^2 fixed (u, v, t) samples, then the motion-blurred camera
    pass (spp = light_grid^2, sample s at t_s; the table's (x, y) are kept, its t replaced) with one
    shadow look-up per hit. With `accumulation`, the same maps rendered one pass per light sample
    (compared sample for sample, and their work). The reference renders reference_grid^2 light samples
    the same way; the penumbra is measured on the receiver (y = 0) along x through z = 0 against the
    similar-triangles width for the scene 'shadow_planes' (occluder edge at x = 0)."""
    for name, v, lo, hi in (("light_grid", light_grid, 1, 16), ("reference_grid", reference_grid, 1, 32),
                            ("light_resolution", light_resolution, 8, 2048)):
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            raise ConfigError(f"point.options.{name}: expected an integer in {lo}..{hi}, got {v!r}")
    light = light_camera(light_center, light_half_size, light_fov_deg, light_resolution)
    uvt = light_samples(light_grid, seed)
    maps, one = shadow_maps(scene, light, uvt, pipeline, hardware=hardware)
    image, lookups, V = _camera_pass(scene, camera, table, pipeline, hardware, light, maps, uvt, ambient)
    flat = dict(one)
    flat.update(figures(shadow__light_samples=len(uvt), shadow__map_texels=int(maps.size),
                        shadow__onepass_ops=ops_all(one), shadow__onepass_setups=int(one["setup.triangles"]),
                        shadow__lookups=lookups))
    if accumulation:
        acc_ops = acc_setups = 0
        equal = True
        for s in range(len(uvt)):
            m, st = shadow_maps(scene, light, uvt[s:s + 1], pipeline, hardware=hardware)
            equal &= bool(np.array_equal(m[..., 0], maps[..., s]))
            acc_ops += ops_all(st)
            acc_setups += int(st["setup.triangles"])
        flat.update(figures(shadow__accum_ops=acc_ops, shadow__accum_setups=acc_setups, shadow__maps_equal=equal))
    ref_uvt = light_samples(reference_grid, seed)
    ref_maps, _ = shadow_maps(scene, light, ref_uvt, pipeline, hardware=hardware)
    ref_image, _, _ = _camera_pass(scene, camera, table, pipeline, hardware, light, ref_maps, ref_uvt, ambient)
    # plane over plane: visibility along x on the receiver, z = 0, at t = 0.5 (static scenes: any t)
    p0, p1, _ = _scene_arrays(scene)
    xs = np.linspace(-0.4, 1.6, 2001)  # the right edge's shadow only
    pts = np.stack([xs, np.zeros_like(xs), np.zeros_like(xs)], 1)
    vis = np.mean([lookup(light, maps, pts, np.full(len(xs), s), uvt) for s in range(len(uvt))], axis=0)
    width, bands = _penumbra(xs, vis, light_grid)
    occluder_h = float(np.max(p0[:, :, 1]))
    d_o = float(light_center[1]) - occluder_h
    formula = 2 * light_half_size * occluder_h / d_o
    flat.update(figures(shadow__penumbra_measured=width, shadow__penumbra_formula=formula, shadow__bands=bands,
                        shadow__rmse=float(np.sqrt(np.mean((image - ref_image) ** 2)))))
    return UseResult(image.astype(np.float32), dict(sorted(flat.items())),
                     {"reference": ref_image.astype(np.float32), "maps": maps, "visibility_x": xs,
                      "visibility": vis, "camera_visibility": V})


def _penumbra(xs, vis, n):
    """(width, levels): width from the first x with visibility > 0 to the first with visibility 1,
    scaled by n / (n - 1) (a grid of n light columns puts its extreme samples (n - 1) / n of the light
    width apart); levels: distinct visibility values strictly between 0 and 1, plus the two ends."""
    some = np.nonzero(vis > 1e-9)[0]
    full = np.nonzero(vis >= 1 - 1e-9)[0]
    if len(some) == 0 or len(full) == 0:
        return float("nan"), 0
    a, b = xs[some[0]], xs[full[0]]
    width = (b - a) * (n / (n - 1) if n > 1 else 1.0)
    levels = len(np.unique(np.round(vis[(vis > 1e-9) & (vis < 1 - 1e-9)], 9))) + 2
    return float(width), int(levels)


def _camera_pass(scene, camera, table, pipeline, hardware, light, maps, uvt, ambient):
    """Motion-blurred pinhole render with sample s at time t_s, then per hit the shadow test against
    map s: (image, look-ups, per-sample visibility (H, W, N) with -1 where empty)."""
    N = len(uvt)
    base = np.array(table.samples(camera.lens), dtype=np.float64)
    P = base.shape[0]
    if base.shape[2] != N:  # keep the table's positions, one per light sample
        base = np.array(SampleTable.stratified(spp=N, seed=1).samples(), dtype=np.float64)
        P = base.shape[0]
    s = base.copy()
    s[..., 2:4] = 0.0
    s[..., 4] = uvt[:, 2][None, None, :]
    cam_table = SampleTable.from_array(s)
    r = render(scene, camera, cam_table, pipeline, export_samples=True, hardware=hardware, timing=False)
    S = tiled_samples(cam_table, camera)
    hit = r.sample_triangle >= 0
    o, d = pinhole_rays(camera, S[..., 0][hit], S[..., 1][hit])
    with np.errstate(divide="ignore"):
        w = camera.near / (1.0 - r.sample_depth[hit].astype(np.float64))
    pts = o + w[:, None] * d
    sample_index = np.broadcast_to(np.arange(N), hit.shape)[hit]
    lit = lookup(light, maps, pts, sample_index, uvt)
    _, _, col = _scene_arrays(scene)
    albedo = col.mean(axis=1)[r.sample_triangle[hit]]
    shade = np.zeros(hit.shape + (3,))
    shade[hit] = albedo * (ambient + (1 - ambient) * lit[:, None])
    V = np.full(hit.shape, -1.0)
    V[hit] = lit
    return shade.mean(axis=2), int(hit.sum()), V
