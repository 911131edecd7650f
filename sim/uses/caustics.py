"""Caustic volumes as moving triangles ([Nilsson 2012] §4, Fig. 7-8).

Each caustic beam is a generator triangle of the refracting surface at t = 0 and its end triangle on
the receiver at t = 1; the moving triangle is rasterized in the conservative mode (1 x 1 tiles, no
sample test, back-face culling off), which runs the pixel shader once per pixel the beam may cover at
any t, with its t̂ and ẑ (sim.conservative_raster). The shader computes the exact time interval in
which the pixel centre is inside all three moving edges ([GDAM10]: each homogeneous edge function is
a quadratic in t) and uses ẑ = [z_lo, z_hi] as the path length of the eye ray in the beam (volume
caustics). Fill rate is compared with a bounding-volume method (Ernst et al.): the pixels of the
convex hull of the beam's six vertices, which any bounding prism contains (a lower bound for the
prism's fill). Surface light: a floor point inside end triangle i receives the beam's flux over its
area, Phi_i / A_i; the reference is a brute-force photon splat through the same (linear) beams.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from ..intervals import conservative_raster
from ..pipeline import PipelineConfig
from ..render import _scene_arrays
from .common import UseResult, figures, pinhole_rays


def _engine64(camera, points):
    return camera.clip_to_engine(camera.world_to_clip(points))


def _roots01(a, b, c):
    """Real roots in (0, 1) of a t^2 + b t + c (arrays), as (n, 2) with nan where absent."""
    out = np.full(a.shape + (2,), np.nan)
    scale = np.maximum(np.maximum(np.abs(a), np.abs(b)), np.abs(c))
    scale = np.where(scale > 0, scale, 1.0)
    A, B, C = a / scale, b / scale, c / scale
    quad = np.abs(A) > 1e-12
    disc = B * B - 4 * A * C
    ok = quad & (disc >= 0)
    sq = np.sqrt(np.where(ok, disc, 0.0))
    q = -0.5 * (B + np.where(B >= 0, sq, -sq))
    with np.errstate(divide="ignore", invalid="ignore"):
        r1 = np.where(ok, q / np.where(quad, A, 1.0), np.nan)
        r2 = np.where(ok & (q != 0), C / np.where(q != 0, q, 1.0), np.nan)
        lin = ~quad & (np.abs(B) > 1e-12)
        r1 = np.where(lin, -C / np.where(lin, B, 1.0), r1)
    out[..., 0], out[..., 1] = r1, np.where(lin, np.nan, r2)
    out[(out <= 0) | (out >= 1)] = np.nan
    return out


def edge_quadratics(v0, v1, sx, sy):
    """Coefficients (n, 3 edges, 3: t^2, t, 1) of the homogeneous edge functions of moving triangles
    (pixel-homogeneous vertices v0 -> v1, (n, 3, 3) float64) at sample points (sx, sy) (n,):
    r_j(t) = a_j + t b_j with a_j = (X_j - sx W_j, Y_j - sy W_j), e_i = r_j x r_k."""
    def rel(v):
        return np.stack([v[..., 0] - sx[:, None] * v[..., 2], v[..., 1] - sy[:, None] * v[..., 2]], -1)
    a = rel(v0)
    b = rel(v1) - a
    cross = lambda p, q: p[..., 0] * q[..., 1] - p[..., 1] * q[..., 0]  # noqa: E731
    out = np.empty(v0.shape[:1] + (3, 3))
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        out[:, i, 0] = cross(b[:, j], b[:, k])
        out[:, i, 1] = cross(a[:, j], b[:, k]) + cross(b[:, j], a[:, k])
        out[:, i, 2] = cross(a[:, j], a[:, k])
    return out


def exact_time_intervals(v0, v1, sx, sy):
    """(t_lo, t_hi, inside_length) per point: the hull and the total length of the set of t in [0, 1] in
    which (sx, sy) is strictly inside the moving triangle (either orientation: culling off); t_lo =
    nan when empty. Breakpoints are the edge quadratics' roots; each piece is tested at its middle."""
    Q = edge_quadratics(v0, v1, sx, sy)
    roots = _roots01(Q[..., 0], Q[..., 1], Q[..., 2]).reshape(len(sx), 6)
    bp = np.sort(np.concatenate([np.zeros((len(sx), 1)), roots, np.ones((len(sx), 1))], 1), axis=1)  # nan last
    lo_b, hi_b = bp[:, :-1], bp[:, 1:]
    valid = np.isfinite(lo_b) & np.isfinite(hi_b) & (hi_b > lo_b)
    mid = np.where(valid, 0.5 * (lo_b + hi_b), 0.5)
    e = Q[:, :, None, 0] * mid[:, None] ** 2 + Q[:, :, None, 1] * mid[:, None] + Q[:, :, None, 2]
    inside = valid & (np.all(e > 0, axis=1) | np.all(e < 0, axis=1))
    any_in = inside.any(axis=1)
    t_lo = np.where(any_in, np.nanmin(np.where(inside, lo_b, np.inf), axis=1), np.nan)
    t_hi = np.where(any_in, np.nanmax(np.where(inside, hi_b, -np.inf), axis=1), np.nan)
    length = np.sum(np.where(inside, hi_b - lo_b, 0.0), axis=1)
    return t_lo, t_hi, length


def _hull_fans(P2, P3):
    """Fan triangles (world) of the convex hull of each volume's six projected vertices."""
    out, owner = [], []
    for i in range(len(P2)):
        pts = P2[i]
        order = np.lexsort((pts[:, 1], pts[:, 0]))
        hull = []
        for pass_pts in (order, order[::-1]):  # Andrew's monotone chain
            start = len(hull)
            for k in pass_pts:
                while len(hull) >= start + 2:
                    o, a = pts[hull[-2]], pts[hull[-1]]
                    if (a[0] - o[0]) * (pts[k][1] - o[1]) - (a[1] - o[1]) * (pts[k][0] - o[0]) <= 0:
                        hull.pop()
                    else:
                        break
                hull.append(k)
            hull.pop()
        for k in range(1, len(hull) - 1):
            out.append(P3[i][[hull[0], hull[k], hull[k + 1]]])
            owner.append(i)
    return np.array(out), np.array(owner)


class _Tris:
    def __init__(self, p0, p1=None):
        self.positions = p0
        self.positions_t1 = p0 if p1 is None else p1
        self.colors = None


def caustic_volumes(scene, camera, table=None, pipeline=None, *, hardware=None, time_splits: int = 4,
                    photons: int = 400_000, path_samples: int = 1500, image: str = "light", seed: int = 0
                    ) -> UseResult:
    """The caustic volumes of ``scene`` (generators at t = 0, ends on the receiver y = 0 at t = 1, e.g.
    models 'water_caustics') through ``camera``. `table` is not used (the conservative mode tests no
    samples). Figures: caustics.volumes, fill_moving, fill_exact, fill_prism, fill_ratio, light_error,
    folded, zhat_over_path."""
    if image not in ("light", "fill"):
        raise ConfigError(f"point.options.image: expected 'light' or 'fill', got {image!r}")
    if isinstance(photons, bool) or not isinstance(photons, int) or not 1000 <= photons <= 50_000_000:
        raise ConfigError(f"point.options.photons: expected an integer in 1000..50000000, got {photons!r}")
    p0, p1, _ = _scene_arrays(scene)
    if not np.allclose(p1[..., 1], 0.0):
        raise ConfigError("scene: caustic volumes end on the receiver y = 0 at t = 1 (models 'water_caustics')")
    pipe = (pipeline or PipelineConfig()).replace(time_splits=time_splits, backface_cull=False)
    cr = conservative_raster(_Tris(p0, p1), camera, pipe)
    rec = cr.records
    flat = dict(cr.flat_stats)
    n_vol = len(p0)
    H, W = camera.height, camera.width
    # exact per-pixel time intervals at the pixel centres
    e0, e1 = _engine64(camera, p0), _engine64(camera, p1)
    tri = rec["triangle"].astype(np.int64)
    sx, sy = rec["x"] + 0.5, rec["y"] + 0.5
    t_lo, t_hi, _ = exact_time_intervals(e0[tri], e1[tri], sx.astype(np.float64), sy.astype(np.float64))
    exact = np.isfinite(t_lo)
    # bounding volume: the convex hull of the six vertices, rasterized conservatively (static)
    P3 = np.concatenate([p0, p1], axis=1)
    E6 = np.concatenate([e0, e1], axis=1)
    hull, owner = _hull_fans(E6[..., :2] / E6[..., 2:3], P3)
    hr = conservative_raster(_Tris(hull), camera, pipe).records
    # standard rasterization of the hull at pixel centres (the conservative records are a superset)
    fan = _engine64(camera, hull)[hr["triangle"]]
    cx, cy = hr["x"] + 0.5, hr["y"] + 0.5
    fx, fy = fan[..., 0] / fan[..., 2], fan[..., 1] / fan[..., 2]
    def side(i, j):
        return (fx[:, j] - fx[:, i]) * (cy - fy[:, i]) - (fy[:, j] - fy[:, i]) * (cx - fx[:, i])
    s0, s1, s2 = side(0, 1), side(1, 2), side(2, 0)
    centre_in = ((s0 >= 0) & (s1 >= 0) & (s2 >= 0)) | ((s0 <= 0) & (s1 <= 0) & (s2 <= 0))
    key = owner[hr["triangle"]].astype(np.int64) * (W * H) + hr["y"].astype(np.int64) * W + hr["x"]
    prism_keys = np.unique(key[centre_in])
    fill_prism = int(len(prism_keys))
    prism_px = np.bincount(prism_keys % (W * H), minlength=W * H).reshape(H, W)
    fill_prism_tiles = int(len(np.unique(key)))
    # surface light on the floor: Phi_i / A_i where the pixel centre's floor point is inside end i
    area = lambda P: 0.5 * ((P[:, 1, 0] - P[:, 0, 0]) * (P[:, 2, 2] - P[:, 0, 2])  # noqa: E731
                            - (P[:, 1, 2] - P[:, 0, 2]) * (P[:, 2, 0] - P[:, 0, 0]))
    a_gen, a_end = area(p0), area(p1)
    flux = np.abs(a_gen)  # unit irradiance from straight above
    folded = int(np.sum(np.sign(a_gen) != np.sign(a_end)))
    o, d = pinhole_rays(camera, sx.astype(np.float64), sy.astype(np.float64))
    with np.errstate(divide="ignore", invalid="ignore"):
        s_floor = -o[:, 1] / d[:, 1]
        s_floor = np.where(np.isfinite(s_floor), s_floor, -1.0)
        X = o + s_floor[:, None] * d
    inside_end = _inside_xz(p1[tri], X) & (s_floor > 0)
    light = np.zeros(H * W)
    np.add.at(light, (rec["y"].astype(np.int64) * W + rec["x"])[inside_end],
              (flux / np.maximum(np.abs(a_end), 1e-300))[tri[inside_end]])
    light = light.reshape(H, W)
    splat = photon_splat(p0, p1, camera, photons, seed)
    light_error = _blurred_l1(light, splat, 2)
    # ẑ as the path length in the beam, against a brute-force march over t at pixel centres
    rng = np.random.default_rng(seed)
    pick = rng.choice(np.nonzero(exact)[0], size=min(path_samples, int(exact.sum())), replace=False)
    near = camera.near
    zlo, zhi = rec["z_lo"][pick].astype(np.float64), rec["z_hi"][pick].astype(np.float64)
    w_lo, w_hi = near / (1 - zlo), near / (1 - zhi)
    m_lo, m_hi = march_beam(p0[tri[pick]], p1[tri[pick]], o[pick], d[pick])
    path = m_hi - m_lo
    ok = np.isfinite(path) & (path > 1e-6)
    ratio = float(np.mean((w_hi - w_lo)[ok] / path[ok])) if ok.any() else float("nan")
    zhat_misses = int(np.sum(ok & ((m_lo < w_lo * (1 - 1e-5)) | (m_hi > w_hi * (1 + 1e-5)))))
    # volume light: the ẑ width of every (beam, pixel) with a non-empty exact interval, times the beam's
    # mean intensity
    vol = np.zeros(H * W)
    w_all_lo = near / (1 - rec["z_lo"].astype(np.float64))
    w_all_hi = near / (1 - rec["z_hi"].astype(np.float64))
    mean_int = flux / np.maximum(0.5 * (np.abs(a_gen) + np.abs(a_end)), 1e-300)
    np.add.at(vol, (rec["y"].astype(np.int64) * W + rec["x"])[exact],
              ((w_all_hi - w_all_lo) * mean_int[tri])[exact])
    vol = vol.reshape(H, W)
    moving_px = np.bincount((rec["y"].astype(np.int64) * W + rec["x"])[exact], minlength=W * H).reshape(H, W)
    if image == "light":
        picture = np.zeros((H, W, 3), np.float32)
        picture[..., 0] = picture[..., 1] = picture[..., 2] = 0.18 * light
        picture += (0.03 * vol)[..., None] * np.array([0.5, 0.8, 1.0], np.float32)
    else:  # [Nilsson 2012] Fig. 8 in kind: shader invocations per pixel, moving triangles | hull, one heat scale
        picture = _heat(np.concatenate([moving_px, prism_px], axis=1) / max(1, prism_px.max()))
    fill_moving = int(exact.sum())
    flat.update(figures(caustics__volumes=n_vol, caustics__fill_tiles=int(len(rec)),
                        caustics__fill_moving=fill_moving, caustics__fill_prism=fill_prism,
                        caustics__fill_prism_tiles=fill_prism_tiles,
                        caustics__fill_ratio=fill_moving / max(fill_prism, 1), caustics__light_error=light_error,
                        caustics__folded=folded, caustics__zhat_over_path=ratio,
                        caustics__zhat_misses=zhat_misses))
    return UseResult(np.clip(picture, 0, None), dict(sorted(flat.items())),
                     {"records": rec, "t_lo": t_lo, "t_hi": t_hi, "light": light, "splat": splat, "volume": vol,
                      "fill_moving": moving_px, "fill_prism": prism_px})


def _heat(x):
    """Black -> red -> yellow -> white for x in [0, 1] (linear RGB)."""
    x = np.clip(np.asarray(x, np.float64), 0, 1)
    return np.stack([np.clip(3 * x, 0, 1), np.clip(3 * x - 1, 0, 1), np.clip(3 * x - 2, 0, 1)], -1).astype(np.float32)


def _inside_xz(T, X):
    """Points X (n, 3) inside triangles T (n, 3, 3) projected on the xz plane (either orientation)."""
    def cr(a, b, p):
        return (b[:, 0] - a[:, 0]) * (p[:, 2] - a[:, 2]) - (b[:, 2] - a[:, 2]) * (p[:, 0] - a[:, 0])
    c0, c1, c2 = cr(T[:, 0], T[:, 1], X), cr(T[:, 1], T[:, 2], X), cr(T[:, 2], T[:, 0], X)
    return ((c0 >= 0) & (c1 >= 0) & (c2 >= 0)) | ((c0 <= 0) & (c1 <= 0) & (c2 <= 0))


def photon_splat(p0, p1, camera, photons: int, seed: int = 0) -> np.ndarray:
    """Brute force: photons uniform over the generators' xz projection (unit irradiance), each carried
    through its beam linearly (generator barycentrics -> the same barycentrics of the end triangle),
    binned by the camera pixel that sees its floor point and divided by the pixel's floor area:
    irradiance per pixel (H, W)."""
    rng = np.random.default_rng(seed + 1)
    a = np.abs(0.5 * ((p0[:, 1, 0] - p0[:, 0, 0]) * (p0[:, 2, 2] - p0[:, 0, 2])
                      - (p0[:, 1, 2] - p0[:, 0, 2]) * (p0[:, 2, 0] - p0[:, 0, 0])))
    total = a.sum()
    which = rng.choice(len(p0), size=photons, p=a / total)
    r1, r2 = rng.random(photons), rng.random(photons)
    s = np.sqrt(r1)
    b = np.stack([1 - s, s * (1 - r2), s * r2], 1)
    X = np.einsum("nk,nkc->nc", b, p1[which])
    e = camera.clip_to_engine(camera.world_to_clip(X))
    px, py = np.floor(e[:, 0] / e[:, 2]).astype(np.int64), np.floor(e[:, 1] / e[:, 2]).astype(np.int64)
    H, W = camera.height, camera.width
    ok = (e[:, 2] > 0) & (px >= 0) & (px < W) & (py >= 0) & (py < H)
    flux = np.bincount(py[ok] * W + px[ok], minlength=H * W).reshape(H, W) * (total / photons)
    return flux / _pixel_floor_area(camera)


def _pixel_floor_area(camera) -> np.ndarray:
    """Area on the floor y = 0 of every pixel's footprint (the quadrilateral of its corner rays)."""
    H, W = camera.height, camera.width
    gx, gy = np.meshgrid(np.arange(W + 1, dtype=np.float64), np.arange(H + 1, dtype=np.float64))
    o, d = pinhole_rays(camera, gx, gy)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = -o[..., 1] / d[..., 1]
        s = np.where(np.isfinite(s) & (s > 0), s, np.nan)
        P = o + s[..., None] * d
    a, b, c, dd = P[:-1, :-1], P[:-1, 1:], P[1:, 1:], P[1:, :-1]
    with np.errstate(invalid="ignore"):
        area = 0.5 * np.abs((c[..., 0] - a[..., 0]) * (dd[..., 2] - b[..., 2]) - (c[..., 2] - a[..., 2]) * (dd[..., 0] - b[..., 0]))
        return np.where(np.isfinite(area) & (area > 0), area, np.inf)


def _blurred_l1(a, b, k: int = 2) -> float:
    """Relative L1 difference of two images after a (2k+1)^2 box blur, over pixels where both are finite."""
    def blur(x):
        x = np.where(np.isfinite(x), x, 0.0)
        p = np.pad(x, k, mode="edge")
        c = np.cumsum(np.cumsum(p, 0), 1)
        c = np.pad(c, ((1, 0), (1, 0)))
        n = 2 * k + 1
        return (c[n:, n:] - c[:-n, n:] - c[n:, :-n] + c[:-n, :-n]) / n ** 2
    A, B = blur(a), blur(b)
    return float(np.sum(np.abs(A - B)) / max(np.sum(np.abs(B)), 1e-300))


def march_beam(p0, p1, o, d, steps: int = 257):
    """Brute force over t: the ray (o, d) against the beam's triangle at `steps` times in [0, 1]; (w_min,
    w_max) of the hits (the ray parameter is the camera's view depth), nan where none."""
    from .common import ray_triangle

    lo = np.full(len(o), np.inf)
    hi = np.full(len(o), -np.inf)
    for t in np.linspace(0.0, 1.0, steps):
        hit, w, _ = ray_triangle(o, d, p0 + t * (p1 - p0))
        lo = np.where(hit, np.minimum(lo, w), lo)
        hi = np.where(hit, np.maximum(hi, w), hi)
    return np.where(np.isfinite(lo), lo, np.nan), np.where(np.isfinite(hi), hi, np.nan)
