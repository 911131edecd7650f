"""The rasterizer as a sampler ([Nilsson 2012] §5): a moving triangle carves a
(2,1)-simploid out of xyt space (with a lens, a (2,1,1,1)-simploid of xyuvt); the sample table fills
that space with uniform samples and the sample tests pick those inside, so the hits are uniform
samples of the simploid with E[N] = density x volume. A domain tessellated into non-overlapping
primitives gets each sample at most once (the tie rule), and its voids none.

Checks (all from closed forms, none from the engine): the number of points against E[N] (the volume
is the integral of the triangle's screen area over the shutter, a quadratic in t), and a chi-square
test of uniformity: each point (x, y, u, v, t) maps to the unit cube by the inverse of the standard
warps (t by the CDF of the area; (x, y) by its barycentrics in the triangle at its own t, r1 =
(1 - b0)^2, r2 = b2 / (1 - b0); (u, v) on the disk by r^2 and the angle); for the void domain, the
counts per kept cell against equal expectations and zero in every void.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from ..render import _scene_arrays, render
from .common import UseResult, chi2_stratified, chi2_uniform, figures, tiled_samples


def _screen(camera, points):
    """World points -> pixel positions (x, y) and view depth W of the lens centre."""
    e = camera.clip_to_engine(camera.world_to_clip(points))
    return e[..., 0] / e[..., 2], e[..., 1] / e[..., 2], e[..., 2]


def _area(xy):
    """Signed area of screen triangles (..., 3, 2)."""
    a, b, c = xy[..., 0, :], xy[..., 1, :], xy[..., 2, :]
    return 0.5 * ((b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0]))


def _coverage_variance(lo, hi) -> float:
    """sum f (1 - f) over the pixels an axis-aligned square [lo, hi] covers a share f of."""
    def shares(a, b):
        cells = np.arange(int(np.floor(a)), int(np.ceil(b)))
        return np.clip(np.minimum(cells + 1, b) - np.maximum(cells, a), 0.0, 1.0)

    f = np.outer(shares(lo[1], hi[1]), shares(lo[0], hi[0]))
    return float(np.sum(f * (1 - f)))


def sample_simploids(scene, camera, table, pipeline=None, *, hardware=None, domain: str = "simploids",
                     bins: int = 3) -> UseResult:
    """Points inside the scene's simploids from one render (export_samples) and their tests.

    domain="simploids": triangles whose vertices keep their view depth (each moves in its own plane,
    so screen motion is linear and the simploid's volume is exact); a lens is allowed when every
    vertex of a triangle has the same depth (the shear is then a translation). Chi-square over
    bins^d cells of the unit cube (d = 3 for xyt, 5 with a lens).
    domain="voids": static fronto-parallel squares (two triangles each, models 'sampler_voids'):
    chi-square over the kept squares, and no point in a void.

    Figures: sampler.points, sampler.expected_points, sampler.chi2_p, sampler.chi2_dof,
    sampler.void_points, sampler.candidates_per_test."""
    if domain not in ("simploids", "voids"):
        raise ConfigError(f"point.options.domain: expected 'simploids' or 'voids', got {domain!r}")
    if isinstance(bins, bool) or not isinstance(bins, int) or not 2 <= bins <= 16:
        raise ConfigError(f"point.options.bins: expected an integer in 2..16, got {bins!r}")
    p0, p1, _ = _scene_arrays(scene)
    x0, y0, w0 = _screen(camera, p0)
    x1, y1, w1 = _screen(camera, p1)
    if not np.allclose(w0, w1, rtol=1e-9, atol=0):
        raise ConfigError("scene: the sampler's volumes are exact for vertices that keep their view depth; "
                          "a vertex changes depth over the shutter")
    r = render(scene, camera, table, pipeline, hardware=hardware, export_samples=True)
    S = tiled_samples(table, camera)
    tri = r.sample_triangle
    hit = tri >= 0
    pts = S[hit]  # (N, 5)
    ids = tri[hit]
    spp = S.shape[2]
    flat = dict(r.flat_stats)
    lens = camera.coc_px > 0 and table.has_lens
    if domain == "simploids":
        if lens and not np.allclose(w0, w0[:, :1], rtol=1e-9, atol=0):
            raise ConfigError("scene: with a lens the sampler needs each triangle's vertices at one depth")
        xy0 = np.stack([x0, y0], -1)
        xy1 = np.stack([x1, y1], -1)
        # |A(t)| is quadratic in t (no triangle may flip; checked below): exact from three values
        A = np.abs(np.stack([_area(xy0), _area(0.5 * (xy0 + xy1)), _area(xy1)], axis=1))
        c0, c2 = A[:, 0], 2 * A[:, 2] - 4 * A[:, 1] + 2 * A[:, 0]
        c1 = A[:, 2] - A[:, 0] - c2
        if np.any(np.sign(_area(xy0)) != np.sign(_area(xy1))):
            raise ConfigError("scene: a sampler simploid flips orientation over the shutter (no planar simploid)")
        volume = c0 + c1 / 2 + c2 / 3  # px^2 x shutter
        expected_n = float(spp * volume.sum())
        t = pts[:, 4]
        i = ids
        F = (c0[i] * t + c1[i] * t ** 2 / 2 + c2[i] * t ** 3 / 3) / volume[i]
        # the triangle at the point's time and lens position (the shear translates each vertex by
        # u K (W - F) / W in x and -v K (W - F) / W in y at the vertex depth)
        V = xy0[i] + t[:, None, None] * (xy1[i] - xy0[i])
        if lens:
            k = camera.coc_px * (w0[i] - camera.focus_distance) / w0[i]
            V = V + np.stack([pts[:, 2:3] * k, -pts[:, 3:4] * k], -1)
        a, b, c = V[:, 0], V[:, 1], V[:, 2]
        den = _area(V)
        b1 = _area(np.stack([a, pts[:, :2], c], 1)) / den
        b2 = _area(np.stack([a, b, pts[:, :2]], 1)) / den
        b0 = 1.0 - b1 - b2
        cube = [F, (1 - b0) ** 2, np.where(b0 < 1, b2 / np.maximum(1 - b0, 1e-300), 0.5)]
        if lens:
            cube += [pts[:, 2] ** 2 + pts[:, 3] ** 2, (np.arctan2(pts[:, 3], pts[:, 2]) / (2 * np.pi)) % 1.0]
        cube = np.clip(np.stack(cube, 1), 0.0, 1.0 - 1e-12)
        cells = np.floor(cube * bins).astype(np.int64)
        index = np.ravel_multi_index(cells.T, (bins,) * cube.shape[1])
        counts = np.bincount(index, minlength=bins ** cube.shape[1])
        p, dof = chi2_uniform(counts, np.full(counts.shape, len(pts) / counts.size))
        void_points = 0
    else:
        if not np.array_equal(p0, p1) or lens:
            raise ConfigError("scene: the void domain is static and in focus (models 'sampler_voids')")
        xs, ys = x0.reshape(-1, 2, 3), y0.reshape(-1, 2, 3)
        lo = np.stack([xs.min(axis=(1, 2)), ys.min(axis=(1, 2))], 1)
        hi = np.stack([xs.max(axis=(1, 2)), ys.max(axis=(1, 2))], 1)
        area = np.prod(hi - lo, axis=1)
        expected_n = float(spp * area.sum())
        square = ids // 2
        counts = np.bincount(square, minlength=len(area))
        # Every pixel holds exactly spp samples, so a square's count is not multinomial: it is spp per whole
        # pixel inside it plus, for a pixel it covers a share f of, Binomial(spp, f) when the table's samples
        # are independent in the pixel (a random table). chi-square of the counts against that null: mean
        # spp * area, variance spp * sum f (1 - f) over its pixels (a stratified table is more even: p near 1).
        var = spp * np.array([_coverage_variance(lo[q], hi[q]) for q in range(len(area))])
        p, dof = chi2_stratified(counts, spp * area, var)
        # brute force: every sample position inside some kept square, counted once
        flat_s = S.reshape(-1, 5)
        inside = np.zeros(len(flat_s), np.int64)
        for q in range(len(area)):
            inside += ((flat_s[:, 0] >= lo[q, 0]) & (flat_s[:, 0] < hi[q, 0]) & (flat_s[:, 1] >= lo[q, 1])
                       & (flat_s[:, 1] < hi[q, 1]))
        span_lo, span_hi = lo.min(axis=0), hi.max(axis=0)
        in_span = ((flat_s[:, 0] >= span_lo[0]) & (flat_s[:, 0] < span_hi[0]) & (flat_s[:, 1] >= span_lo[1])
                   & (flat_s[:, 1] < span_hi[1]))
        hit_flat = hit.reshape(-1)
        void_points = int(np.sum(hit_flat & in_span & (inside == 0)))
        flat["sampler.double_count"] = int(np.sum(inside > 1))
    flat.update(figures(sampler__points=int(len(pts)), sampler__expected_points=expected_n, sampler__chi2_p=p,
                        sampler__chi2_dof=dof, sampler__void_points=void_points,
                        sampler__candidates_per_test=len(pts) / max(1, flat["raster.samples_tested"])))
    flat.pop("sampler.double_count", None)
    return UseResult(r.image, dict(sorted(flat.items())), {"points": pts, "triangle": ids})
