"""Independent numpy references for the engine tests: a float64 thin-lens ray caster, closed-form coverage of defocused and moving squares, and generators of random and hard-case triangles.

The ray caster is built from the camera *model* (camera.py docstring), not from the engine's
clip-space shear: a sample (sx, sy, u, v, t) is the world ray from the lens point
L = (u R, v R, 0) (view space, R = aperture radius) through the point of the focus plane
(view depth F) that the pinhole camera sees at pixel position (sx, sy); it is intersected with the
triangle at time t by Moller-Trumbore in float64 and counts when the hit's view depth w >= near.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

import sim
from sim import _core
from sim.lens import map_to_lens

# ----------------------------------------------------------------------------- the ray caster


def _proj_scales(cam):
    s_y = 1.0 / math.tan(math.radians(cam.fov_y_deg) / 2.0)
    s_x = s_y * cam.height / cam.width
    return s_x, s_y


def world_to_view(cam, p):
    """(..., 3) world points -> view space (float64) with cam.view_matrix()."""
    m = cam.view_matrix()
    p = np.asarray(p, dtype=np.float64)
    return p @ m[:3, :3].T + m[:3, 3]


def triangle_at(cam, p0, p1, t):
    """View-space vertices (..., 3, 3) of world triangles p0 -> p1 (..., 3, 3) at table time t (...):
    the scene time is shutter_open + t (shutter_close - shutter_open)."""
    s_open, s_close = cam.shutter
    tau = s_open + np.asarray(t, dtype=np.float64) * (s_close - s_open)
    p0 = np.asarray(p0, dtype=np.float64)
    p1 = np.asarray(p1, dtype=np.float64)
    world = p0 + tau[..., None, None] * (p1 - p0)
    return world_to_view(cam, world)


def sample_rays(cam, points):
    """(..., 5) samples (sx, sy, u, v, t) -> view-space origins L and directions D (..., 3).
    D = Q - L with Q the focus-plane point, so the ray point L + s D has view depth w = s F."""
    pts = np.asarray(points, dtype=np.float64)
    sx, sy, u, v = pts[..., 0], pts[..., 1], pts[..., 2], pts[..., 3]
    s_x, s_y = _proj_scales(cam)
    F = cam.focus_distance
    R = cam.aperture_radius
    q = np.stack([((2.0 * sx / cam.width) - 1.0) / s_x * F, (1.0 - 2.0 * sy / cam.height) / s_y * F,
                  np.full_like(sx, -F)], axis=-1)
    lens = np.stack([u * R, v * R, np.zeros_like(u)], axis=-1)
    return lens, q - lens


def ray_cast(cam, p0, p1, points):
    """Ray-cast world triangles (..., 3, 3) at shutter open/close against samples (..., 5).

    Returns a namespace of arrays (...): covered (the ray's forward half hits the triangle),
    hit (covered and w >= near), w (view depth of the ray/plane intersection, nan if parallel),
    depth (z = 1 - near / w where hit, +inf elsewhere)."""
    pts = np.asarray(points, dtype=np.float64)
    tri = triangle_at(cam, p0, p1, pts[..., 4])
    org, d = sample_rays(cam, pts)
    a, b, c = tri[..., 0, :], tri[..., 1, :], tri[..., 2, :]
    e1, e2 = b - a, c - a
    pvec = np.cross(d, e2)
    det = np.einsum("...i,...i->...", e1, pvec)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        tvec = org - a
        b1 = np.einsum("...i,...i->...", tvec, pvec) * inv
        qvec = np.cross(tvec, e1)
        b2 = np.einsum("...i,...i->...", d, qvec) * inv
        s = np.einsum("...i,...i->...", e2, qvec) * inv
    w = s * cam.focus_distance
    ok = (det != 0) & np.isfinite(s)
    with np.errstate(divide="ignore", invalid="ignore"):
        covered = ok & (b1 >= 0) & (b2 >= 0) & (b1 + b2 <= 1) & (s > 0)
        hit = covered & (w >= cam.near)
        depth = np.where(hit, 1.0 - cam.near / w, np.inf)
    return SimpleNamespace(covered=covered, hit=hit, w=np.where(ok, w, np.nan), depth=depth)


def edge_distance_px(cam, p0, p1, points):
    """Screen distance in pixels from each sample (..., 5) to the nearest of the three edge lines of
    the triangle at the sample's time, as seen from the sample's lens point: the plane through the
    lens point and an edge meets the focus plane in a line, which maps affinely to a line on the
    screen. inf where the plane is parallel to the focus plane and misses the sample."""
    pts = np.asarray(points, dtype=np.float64)
    tri = triangle_at(cam, p0, p1, pts[..., 4])
    org, d = sample_rays(cam, pts)
    s_x, s_y = _proj_scales(cam)
    F = cam.focus_distance
    # dQ/dsx = (2F / (W s_x), 0, 0), dQ/dsy = (0, -2F / (H s_y), 0)
    ax, ay = 2.0 * F / (cam.width * s_x), -2.0 * F / (cam.height * s_y)
    best = np.full(pts.shape[:-1], np.inf)
    for i in range(3):
        a = tri[..., i, :] - org
        b = tri[..., (i + 1) % 3, :] - org
        n = np.cross(a, b)
        f = np.einsum("...i,...i->...", n, d)  # n . (Q - L)
        g = np.hypot(n[..., 0] * ax, n[..., 1] * ay)
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = np.where(g > 0, np.abs(f) / g, np.where(f == 0, 0.0, np.inf))
        best = np.minimum(best, dist)
    return best


def near_rel_distance(cam, w):
    """|w - near| / near of the ray/plane intersection depth (inf where w is nan)."""
    w = np.asarray(w, dtype=np.float64)
    return np.where(np.isnan(w), np.inf, np.abs(w - cam.near) / cam.near)


# ----------------------------------------------------------------------------- the engine side


def engine_params(cam, *, has_lens=True, has_time=True):
    p = _core.RenderParams()
    for k, v in cam.engine_params().items():
        setattr(p, k, v)
    p.lens_shape = getattr(_core.LensShape, cam.lens)
    p.table_has_lens = has_lens
    p.table_has_time = has_time
    return p


def engine_probe(cam, p0, p1, points, *, force_general=False, has_lens=True, has_time=True):
    """_core.probe of one world triangle (3, 3) at shutter open/close on samples (M, 5)."""
    v0, v1 = cam.engine_vertices(np.asarray(p0)[None], np.asarray(p1)[None])
    pts = np.ascontiguousarray(points, dtype=np.float32)
    return _core.probe(engine_params(cam, has_lens=has_lens, has_time=has_time), v0[0], v1[0], pts,
                       force_general)


def table_points(table, cam):
    """All samples of the image as absolute points (H, W, spp, 5) float32, pixel (px, py) using
    table entry [py mod P, px mod P]."""
    s = table.samples(cam.lens)
    P = s.shape[0]
    ys = np.arange(cam.height) % P
    xs = np.arange(cam.width) % P
    pts = s[ys[:, None], xs[None, :]].astype(np.float64)
    pts[..., 0] += np.arange(cam.width)[None, :, None]
    pts[..., 1] += np.arange(cam.height)[:, None, None]
    return pts.astype(np.float32)


def resolve_nearest(cam, positions, positions_t1, points):
    """Visibility by nearest w over triangles (N, 3, 3) for samples (..., 5): (depth, triangle,
    per-triangle ray-cast namespace with a leading N axis)."""
    n = positions.shape[0]
    pts = np.asarray(points, dtype=np.float64)
    shape = pts.shape[:-1]
    p0 = positions.reshape((n,) + (1,) * len(shape) + (3, 3))
    p1 = positions_t1.reshape((n,) + (1,) * len(shape) + (3, 3))
    rc = ray_cast(cam, p0, p1, np.broadcast_to(pts, (n,) + pts.shape))
    w = np.where(rc.hit, rc.w, np.inf)
    tri = np.argmin(w, axis=0)
    best = np.take_along_axis(w, tri[None], axis=0)[0]
    tri = np.where(np.isfinite(best), tri, -1)
    with np.errstate(divide="ignore"):
        depth = np.where(np.isfinite(best), 1.0 - cam.near / best, np.inf)
    return depth, tri, rc


# ----------------------------------------------------------------------------- random inputs


def lens_uv(rng, shape, n):
    """n uniform lens points (float32-exact values as float64) in the aperture `shape`."""
    u, v = map_to_lens(rng.random(n), rng.random(n), shape)
    return np.stack([u, v], axis=1).astype(np.float32).astype(np.float64)


def screen_to_world(cam, sx, sy, w):
    """The world point at view depth w that the pinhole sees at pixel position (sx, sy)."""
    s_x, s_y = _proj_scales(cam)
    sx, sy, w = np.broadcast_arrays(np.asarray(sx, float), np.asarray(sy, float), np.asarray(w, float))
    view = np.stack([((2.0 * sx / cam.width) - 1.0) / s_x * w, (1.0 - 2.0 * sy / cam.height) / s_y * w, -w], axis=-1)
    m = cam.view_matrix()
    return (view - m[:3, 3]) @ m[:3, :3]  # inverse of a rigid transform


KINDS = ("plain", "behind_camera", "crosses_focus", "behind_near", "moving", "moving_through_near")


def random_camera(rng):
    shape = ("disk", "square", "hexagon")[rng.integers(3)]
    width = int(rng.integers(24, 97))
    height = int(rng.integers(24, 97))
    coc = float(rng.choice([0.0, rng.uniform(0.0, 2.0), rng.uniform(0.0, 60.0), 60.0 * rng.random() ** 0.5]))
    kw = {}
    if rng.random() < 0.3:  # a posed camera exercises view_matrix
        eye = rng.normal(size=3) * 3.0
        kw = {"eye": eye, "target": eye + rng.normal(size=3), "up": rng.normal(size=3)}
    shutter = (0.0, 1.0) if rng.random() < 0.8 else tuple(sorted(rng.uniform(0, 1, 2)))
    return sim.Camera(width=width, height=height, fov_y_deg=float(rng.uniform(20, 90)),
                      focus_distance=float(np.exp(rng.uniform(np.log(0.5), np.log(20.0)))), coc_px=coc,
                      lens=shape, near=float(np.exp(rng.uniform(np.log(0.01), np.log(0.5)))),
                      shutter=shutter, **kw)


def random_triangle(rng, cam, kind):
    """A world triangle (p0, p1) of the given kind (see KINDS) for camera cam."""
    F = cam.focus_distance
    w_c = float(np.exp(rng.uniform(np.log(max(2.0 * cam.near, 0.1 * F)), np.log(8.0 * F))))
    cx = rng.uniform(-0.2, 1.2) * cam.width
    cy = rng.uniform(-0.2, 1.2) * cam.height
    centre = screen_to_world(cam, cx, cy, w_c)
    size_px = float(np.exp(rng.uniform(np.log(0.5), np.log(2.0 * max(cam.width, cam.height)))))
    world_per_px = 2.0 * w_c * math.tan(math.radians(cam.fov_y_deg) / 2.0) / cam.height
    r = size_px * world_per_px
    m = cam.view_matrix()
    right, up, back = m[0, :3], m[1, :3], m[2, :3]
    offs = rng.normal(size=(3, 3)) * [r, r, r * rng.uniform(0.0, 1.0)]
    p0 = centre + offs[:, :1] * right + offs[:, 1:2] * up + offs[:, 2:3] * back
    p1 = p0.copy()
    eye = cam.eye
    if kind == "behind_camera":  # one vertex behind the camera (view depth < 0)
        j = rng.integers(3)
        p0[j] = eye + back * rng.uniform(0.1, 2.0) * w_c + (p0[j] - centre) + right * rng.normal() * r
        p1 = p0.copy()
    elif kind == "crosses_focus":
        depths = F * np.array([rng.uniform(0.3, 0.95), rng.uniform(1.05, 4.0), rng.uniform(0.3, 4.0)])
        rng.shuffle(depths)
        pix = np.stack([cx + rng.normal(size=3) * size_px, cy + rng.normal(size=3) * size_px], axis=1)
        p0 = screen_to_world(cam, pix[:, 0], pix[:, 1], depths)
        p1 = p0.copy()
    elif kind == "behind_near":  # one or two vertices between the camera and the near plane
        k = int(rng.integers(1, 3))
        idx = rng.choice(3, size=k, replace=False)
        pix = np.stack([cx + rng.normal(size=3) * size_px, cy + rng.normal(size=3) * size_px], axis=1)
        depths = np.full(3, w_c)
        depths[idx] = cam.near * rng.uniform(-0.5, 0.99, size=k)
        depths[depths == 0] = 0.5 * cam.near
        p0 = screen_to_world(cam, pix[:, 0], pix[:, 1], depths)
        p1 = p0.copy()
    if kind == "moving":
        shift = rng.normal(size=3) * r * rng.uniform(0.1, 3.0)
        p1 = p0 + shift + rng.normal(size=(3, 3)) * r * 0.2
    elif kind == "moving_through_near":  # approaches the camera through the near plane
        p1 = p0 - back * (w_c - cam.near * rng.uniform(-2.0, 0.8)) + rng.normal(size=(3, 3)) * r * 0.2
    return p0, p1


def sample_points(rng, cam, p0, p1, m):
    """m samples (m, 5) float32, lens points uniform in the camera's aperture, t uniform: half with
    (x, y) uniform in the triangle's blurred, moving screen bounds (the whole screen when a vertex
    is behind the near plane), half aimed at the triangle from the sample's lens point and time
    (near its edges and, where it crosses the near plane, near that cut)."""
    view = np.concatenate([world_to_view(cam, p0), world_to_view(cam, p1)])
    w = -view[:, 2]
    s_x, s_y = _proj_scales(cam)
    if np.all(w > cam.near):
        px = (s_x * view[:, 0] / w + 1.0) * cam.width / 2.0
        py = (1.0 - s_y * view[:, 1] / w) * cam.height / 2.0
        blur = cam.coc_px * np.abs(1.0 - cam.focus_distance / w)
        lo = np.array([np.min(px - blur), np.min(py - blur)]) - 1.0
        hi = np.array([np.max(px + blur), np.max(py + blur)]) + 1.0
        lo = np.maximum(lo, 0.0)
        hi = np.minimum(hi, [cam.width, cam.height])
        if np.any(hi <= lo):
            lo, hi = np.zeros(2), np.array([cam.width, cam.height], float)
    else:
        lo, hi = np.zeros(2), np.array([cam.width, cam.height], float)
    k = m // 2
    xy = np.concatenate([lo + rng.random((m - k, 2)) * (hi - lo), np.zeros((k, 2))])
    uv = lens_uv(rng, cam.lens, m)
    t = rng.random(m).astype(np.float32).astype(np.float64)
    # Targeted half: a random point of the triangle at the sample's (u, v, t), barycentrics a little
    # beyond [0, 1] so that many land just inside or just outside an edge, seen from the lens point.
    bary = rng.dirichlet(np.ones(3), size=k)
    bary += rng.normal(size=(k, 3)) * 10.0 ** rng.uniform(-6, -1, size=(k, 1))
    tri = triangle_at(cam, p0, p1, t[m - k:])
    pv = np.einsum("kj,kjc->kc", bary, tri)
    # A quarter of those sit on the triangle's cut by the plane w = near (1 + delta), |delta| tiny,
    # where the triangle crosses the near plane: the near-plane rejection is tested at its edge.
    wv = -tri[..., 2]
    level = cam.near * (1.0 + rng.choice([-1.0, 1.0], size=k) * 10.0 ** rng.uniform(-7, -2, size=k))
    above = wv >= level[:, None]
    crosses = above.any(axis=1) & ~above.all(axis=1) & (rng.random(k) < 0.25)
    for i in np.flatnonzero(crosses):
        ends = []
        for a, b in ((0, 1), (1, 2), (2, 0)):
            if above[i, a] != above[i, b]:
                f = (level[i] - wv[i, a]) / (wv[i, b] - wv[i, a])
                ends.append(tri[i, a] + f * (tri[i, b] - tri[i, a]))
        g = rng.random()
        pv[i] = ends[0] + g * (ends[1] - ends[0])
    lens_pt = np.stack([uv[m - k:, 0], uv[m - k:, 1], np.zeros(k)], axis=1) * cam.aperture_radius
    wp = -pv[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        q = lens_pt + (pv - lens_pt) * (cam.focus_distance / wp)[:, None]
        tx = (s_x * q[:, 0] / cam.focus_distance + 1.0) * cam.width / 2.0
        ty = (1.0 - s_y * q[:, 1] / cam.focus_distance) * cam.height / 2.0
    good = (wp > 0) & (tx >= 0) & (tx < cam.width) & (ty >= 0) & (ty < cam.height)
    xy[m - k:, 0] = np.where(good, tx, rng.random(k) * cam.width)
    xy[m - k:, 1] = np.where(good, ty, rng.random(k) * cam.height)
    pts = np.concatenate([xy, uv, t[:, None]], axis=1).astype(np.float32)
    # keep x, y inside the image after rounding to float32
    pts[:, 0] = np.minimum(pts[:, 0], np.nextafter(np.float32(cam.width), np.float32(0)))
    pts[:, 1] = np.minimum(pts[:, 1], np.nextafter(np.float32(cam.height), np.float32(0)))
    return pts


# ----------------------------------------------------------------------------- the comparison

# Tolerances of a float32 engine against the float64 reference (see test_raycaster.py).
EDGE_TOL_PX = 1e-3
NEAR_TOL_REL = 1e-4
DEPTH_TOL_REL = 1e-5  # relative error of the hit depth w where the computation is well conditioned
EPS32 = 2.0 ** -24  # float32 unit roundoff
KAPPA_FACTOR = 8.0  # depth tolerance in units of eps32 * kappa where that exceeds DEPTH_TOL_REL
Z_ROUND = 2.0 ** -22  # float32 rounding of z = 1 - near / w (two ulps of 1)


def lens_homogeneous(cam, p0, p1, points):
    """Pixel-homogeneous vertices (..., 3, 3) = (px W, py W, W) of the triangle at each sample's time,
    as seen from the sample's lens point: (px, py) is where the line from the lens point through the
    vertex meets the focus plane, in pixels; W the vertex's view depth. Also the pinhole ones."""
    pts = np.asarray(points, dtype=np.float64)
    tri = triangle_at(cam, p0, p1, pts[..., 4])
    org, _ = sample_rays(cam, pts)
    s_x, s_y = _proj_scales(cam)
    F = cam.focus_distance
    W = -tri[..., 2]
    rel = tri - org[..., None, :]
    # focus-plane point of the line L + s (P - L) at depth F: L + (P - L) F / W; in homogeneous
    # form, multiplied through by W: L W + (P - L) F
    qx = org[..., None, 0] * W + rel[..., 0] * F
    qy = org[..., None, 1] * W + rel[..., 1] * F
    X = (s_x * qx / F + W) * cam.width / 2.0
    Y = (W - s_y * qy / F) * cam.height / 2.0
    X0 = (s_x * tri[..., 0] + W) * cam.width / 2.0
    Y0 = (W - s_y * tri[..., 1]) * cam.height / 2.0
    return np.stack([X, Y, W], axis=-1), np.stack([X0, Y0, W], axis=-1)


def depth_condition(cam, p0, p1, points):
    """kappa >= 1 per sample: a first-order bound, in units of the float32 epsilon, of the relative
    error of the hit depth w computed in float32 from pixel-homogeneous vertices (X, Y, W) seen from
    the lens point (the shear of a vertex is (X - X_pinhole)). w = sum W_i e_i / sum e_i with the
    edge functions e_i = r_j x r_k of r_j = (X_j - sx W_j, Y_j - sy W_j); dw / de_i =
    (W_i - w) / sum e, and |de_i| <~ eps * (|r_j| magnitudes incl. the terms that cancel in r_j).
    Large where a vertex lies near the lens plane and the blur is large, or the view is grazing."""
    pts = np.asarray(points, dtype=np.float64)
    h, h0 = lens_homogeneous(cam, p0, p1, pts)
    sx, sy = pts[..., 0, None], pts[..., 1, None]
    X, Y, W = h[..., 0], h[..., 1], h[..., 2]
    rx, ry = X - sx * W, Y - sy * W
    # magnitudes of the terms that are added to form rx, ry (pinhole coordinate, shear, sx W)
    mx = np.abs(h0[..., 0]) + np.abs(X - h0[..., 0]) + np.abs(sx * W) + np.abs(rx)
    my = np.abs(h0[..., 1]) + np.abs(Y - h0[..., 1]) + np.abs(sy * W) + np.abs(ry)
    e = np.empty_like(W)
    b = np.empty_like(W)
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        e[..., i] = rx[..., j] * ry[..., k] - ry[..., j] * rx[..., k]
        b[..., i] = mx[..., j] * my[..., k] + my[..., j] * mx[..., k]
    s = e.sum(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        w = (W * e).sum(axis=-1) / s
        kappa = (np.abs(W - w[..., None]) * b).sum(axis=-1) / np.abs(s * w)
    return np.where(np.isfinite(kappa), np.maximum(kappa, 1.0), np.inf)


def compare_probe(cam, p0, p1, points):
    """Engine probe vs ray caster on one triangle: a dict of mismatch and depth-error facts.
    A hit mismatch is explained when the sample is within EDGE_TOL_PX of an edge line or within
    max(NEAR_TOL_REL, the depth tolerance of w) of the near plane (the engine decides "in front"
    from its own w, so the near-plane decision is as accurate as w); depth must agree within
    depth_tolerances where both hit."""
    eng = engine_probe(cam, p0, p1, points)
    ref = ray_cast(cam, p0, p1, points)
    mism = eng["hit"] != ref.hit
    edge = edge_distance_px(cam, p0, p1, points)
    near = near_rel_distance(cam, ref.w)
    tol_w, tol_z = depth_tolerances(cam, p0, p1, points, ref.w)
    near_tol = np.maximum(NEAR_TOL_REL, tol_w)
    explained = (edge < EDGE_TOL_PX) | (near < near_tol)
    both = eng["hit"] & ref.hit
    with np.errstate(divide="ignore", invalid="ignore"):
        w_err = np.abs(eng["w_hit"].astype(np.float64) - ref.w) / ref.w
    z_err = np.abs(eng["depth"].astype(np.float64) - ref.depth)
    depth_bad = both & ~((w_err <= tol_w) & (z_err <= tol_z))
    kappa = depth_condition(cam, p0, p1, points)
    return {
        "samples": len(points),
        "hits": int(ref.hit.sum()),
        "both": int(both.sum()),
        "mismatches": int(mism.sum()),
        "unexplained": int((mism & ~explained).sum()),
        "unexplained_idx": np.flatnonzero(mism & ~explained),
        "max_mismatch_edge_px": float(np.max(np.where(mism & (near >= near_tol), edge, 0.0), initial=0.0)),
        "max_mismatch_near_rel": float(np.max(np.where(mism & (edge >= EDGE_TOL_PX), near, 0.0), initial=0.0)),
        "near_mismatches_beyond_1e-4": int((mism & (edge >= EDGE_TOL_PX) & (near >= NEAR_TOL_REL)).sum()),
        "depth_bad": int(depth_bad.sum()),
        "depth_bad_idx": np.flatnonzero(depth_bad),
        "max_w_rel_err": float(np.max(w_err[both], initial=0.0)),
        "hits_w_err_above_tol_rel": int((w_err[both] > DEPTH_TOL_REL).sum()),
        "max_w_err_per_eps_kappa": float(np.max(w_err[both] / (EPS32 * kappa[both]), initial=0.0)),
        "max_z_abs_err": float(np.max(z_err[both], initial=0.0)),
        "eng": eng,
        "ref": ref,
        "edge": edge,
        "near": near,
    }


def depth_tolerances(cam, p0, p1, points, w_ref):
    """(relative tolerance of w, absolute tolerance of z) per sample: DEPTH_TOL_REL, widened to
    KAPPA_FACTOR eps32 kappa where the float32 computation is ill-conditioned (kappa from
    depth_condition; over 1,200 random triangles the worst error is 3.8 eps32 kappa, the median
    0.04 eps32 kappa)."""
    kappa = depth_condition(cam, p0, p1, points)
    tol_w = np.maximum(DEPTH_TOL_REL, KAPPA_FACTOR * EPS32 * kappa)
    with np.errstate(divide="ignore", invalid="ignore"):
        tol_z = (cam.near / np.abs(w_ref)) * tol_w + Z_ROUND
    return tol_w, tol_z


def compare_resolved(cam, positions, positions_t1, points, eng_triangle, eng_depth):
    """Resolved visibility of a render (eng_triangle, eng_depth (...)) vs the ray caster on the
    samples points (..., 5). A sample whose winning triangle differs is explained when it lies within
    EDGE_TOL_PX of an edge (or max(NEAR_TOL_REL, depth tolerance) of the near plane) of either
    triangle involved, or when
    the two triangles' reference depths are within the depth tolerance (a float32 depth tie).
    Where both pick the same triangle, z must agree within its tolerance."""
    ref_depth, ref_tri, rc = resolve_nearest(cam, positions, positions_t1, points)
    n = positions.shape[0]
    pts = np.asarray(points, dtype=np.float64)
    edge = np.stack([edge_distance_px(cam, positions[i], positions_t1[i], pts) for i in range(n)])
    near = near_rel_distance(cam, rc.w)
    tols = [depth_tolerances(cam, positions[i], positions_t1[i], pts, rc.w[i]) for i in range(n)]
    tol_w = np.stack([t[0] for t in tols])
    tol_z = np.stack([t[1] for t in tols])
    close = (edge < EDGE_TOL_PX) | (near < np.maximum(NEAR_TOL_REL, tol_w))  # (n, ...)

    def pick(a, idx):
        return np.take_along_axis(a, np.maximum(idx, 0)[None], axis=0)[0]

    e_tri = np.asarray(eng_triangle)
    mism = e_tri != ref_tri
    explained = np.zeros_like(mism)
    for idx in (e_tri, ref_tri):
        explained |= (idx >= 0) & pick(close, idx)
    both = (e_tri >= 0) & (ref_tri >= 0)
    z_e_ref = pick(np.where(rc.hit, rc.depth, np.inf), e_tri)
    with np.errstate(invalid="ignore"):
        gap = np.abs(z_e_ref - ref_depth)
    tie = both & np.isfinite(gap) & (gap <= pick(tol_z, e_tri) + pick(tol_z, ref_tri))
    explained |= tie
    same = (e_tri == ref_tri) & (ref_tri >= 0)
    with np.errstate(invalid="ignore"):
        z_err = np.where(same, np.abs(np.asarray(eng_depth, dtype=np.float64) - ref_depth), 0.0)
    depth_bad = same & ~(z_err <= pick(tol_z, ref_tri))
    return {
        "samples": int(mism.size),
        "covered": int((ref_tri >= 0).sum()),
        "mismatches": int(mism.sum()),
        "unexplained": int((mism & ~explained).sum()),
        "unexplained_idx": np.argwhere(mism & ~explained),
        "depth_ties": int((mism & tie).sum()),
        "depth_bad": int(depth_bad.sum()),
        "max_z_err": float(np.max(np.where(same, z_err, 0.0), initial=0.0)),
        "ref_triangle": ref_tri,
        "ref_depth": ref_depth,
    }


# ----------------------------------------------------------------------------- closed forms


def _clip_antiderivative(s, lo, hi):
    """C(s) with C' = clip(s, lo, hi)."""
    s = np.asarray(s, dtype=np.float64)
    return lo * np.minimum(s, lo) + (np.clip(s, lo, hi) ** 2 - lo * lo) / 2.0 + hi * np.maximum(s - hi, 0.0)


def overlap_integral(a, lo, hi, d0, d1):
    """integral over d in [d0, d1] of len([a - d, a + 1 - d] & [lo, hi]) (pixel [a, a+1] shifted by -d)."""
    C = _clip_antiderivative
    # len = clip(a + 1 - d) - clip(a - d); integral of clip(c - d) dd over [d0, d1] = C(c - d0) - C(c - d1)
    return (C(a + 1 - d0, lo, hi) - C(a + 1 - d1, lo, hi)) - (C(a - d0, lo, hi) - C(a - d1, lo, hi))


def overlap(a, lo, hi, d):
    """len([a - d, a + 1 - d] & [lo, hi])."""
    return np.clip(a + 1.0 - d, lo, hi) - np.clip(a - d, lo, hi)


def _lens_profile(shape, n):
    """Midpoint nodes s in (-1, 1) over the lens's u extent, their weights ds, the half-height of the
    shape at s, and the shape's area (uniform density 1 / area). The disk uses s = sin(theta) so
    that the square-root end points are integrated smoothly."""
    if shape == "disk":
        theta = (np.arange(n) + 0.5) / n * math.pi - math.pi / 2.0
        return np.sin(theta), np.cos(theta) * (math.pi / n), np.cos(theta), math.pi
    s = (np.arange(n) + 0.5) / n * 2.0 - 1.0
    ds = np.full(n, 2.0 / n)
    if shape == "square":
        return s, ds, np.ones(n), 4.0
    if shape == "hexagon":  # vertices (+-1, 0), (+-1/2, +-sqrt(3)/2)
        half = np.where(np.abs(s) <= 0.5, math.sqrt(3.0) / 2.0, math.sqrt(3.0) * (1.0 - np.abs(s)))
        return s, ds, half, 1.5 * math.sqrt(3.0)
    raise ValueError(shape)


def rect_coverage(width, height, rect, radius=0.0, shape="disk", motion_x=0.0, n_lens=4096, n_time=256):
    """Expected pixel coverage (H, W) of the axis-aligned pixel rectangle rect = (x0, x1, y0, y1)
    blurred by the lens `shape` scaled to `radius` px (uniform over the aperture: a point moves by
    radius * (u, -v)) and moving by motion_x px in x over t in [0, 1), averaged over each pixel
    [X, X+1) x [Y, Y+1):

        E = (1 / area) int_lens int_t  ox(r u + t m) oy(-r v)  du dv dt,

    with ox(d) = |[X - d, X + 1 - d] & [x0, x1]| (pixel shifted against the image shift). The inner
    v integral is exact (piecewise quadratic antiderivative), u by a midpoint rule with n_lens nodes
    (sin substitution for the disk), t exact without blur and by n_time midpoints with it."""
    x0, x1, y0, y1 = rect
    px = np.arange(width, dtype=np.float64)
    py = np.arange(height, dtype=np.float64)
    if radius == 0.0:
        oy = overlap(py, y0, y1, 0.0)
        if motion_x == 0.0:
            ox = overlap(px, x0, x1, 0.0)
        else:
            ox = overlap_integral(px, x0, x1, 0.0, motion_x) / motion_x  # d = t m over [0, m]
        return oy[:, None] * ox[None, :]
    s, ds, half, area = _lens_profile(shape, n_lens)
    h = radius * half
    oy = overlap_integral(py[None, :], y0, y1, -h[:, None], h[:, None])  # (n, H), symmetric in v
    times = (np.arange(n_time) + 0.5) / n_time if motion_x else np.zeros(1)
    ox = np.zeros((len(s), width))
    for t in times:
        ox += overlap(px[None, :], x0, x1, radius * s[:, None] + t * motion_x)
    ox /= len(times)
    # du = ds (radius cancels against the radius^2 of the area)
    return np.einsum("n,nh,nw->hw", ds, oy, ox) / (area * radius)


def fronto_square(cam, rect, depth, motion_px=0.0):
    """Two triangles forming the axis-aligned pixel rectangle rect = (x0, x1, y0, y1) as seen by the
    pinhole at view depth `depth`, moving by motion_px pixels in x (at that depth) over the shutter."""
    x0, x1, y0, y1 = rect
    corners = screen_to_world(cam, [x0, x1, x1, x0], [y0, y0, y1, y1], depth)
    shifted = screen_to_world(cam, np.array([x0, x1, x1, x0]) + motion_px, [y0, y0, y1, y1], depth)
    tris = np.array([[0, 1, 2], [0, 2, 3]])
    p0, p1 = corners[tris], shifted[tris]
    return SimpleNamespace(positions=p0, positions_t1=p1, colors=np.ones((2, 3, 3)))


# ----------------------------------------------------------------------------- hard cases


def hard_cases():
    """Named hard inputs: {name: (camera kwargs, positions (N,3,3), positions_t1 (N,3,3),
    expected setup counters)}. Positions are built in the default camera's view space (the world)."""
    base = dict(width=32, height=32, fov_y_deg=45.0, focus_distance=5.0, coc_px=8.0, lens="disk", near=0.1)
    cam = sim.Camera(**base)

    def px(sx, sy, w):
        return screen_to_world(cam, sx, sy, w)

    def tri(*verts):
        return np.array(verts, dtype=np.float64)

    F = cam.focus_distance
    cases = {}

    def add(name, p0, p1=None, counters=None, **cam_kw):
        p0 = np.asarray(p0, dtype=np.float64)
        p1 = p0.copy() if p1 is None else np.asarray(p1, dtype=np.float64)
        cases[name] = ({**base, **cam_kw}, p0, p1, counters or {})

    add("vertex_behind_camera",
        [tri(px(6, 7, 3.0), px(25, 12, 4.0), [0.4, -0.3, 2.0]),
         tri(px(20, 25, 6.0), [-0.5, 0.6, 1.0], [0.7, 0.2, 3.0])],
        counters={"setup.near_clipped": 2})
    add("crosses_focus_plane", [tri(px(5, 6, 2.0), px(27, 9, F), px(14, 28, 14.0))])
    add("edge_parallel_to_focus_plane",
        [tri(px(4, 5, 3.0), px(26, 5, 3.0), px(15, 27, 9.0)),
         tri(px(6, 20, F), px(28, 22, F), px(17, 3, 2.0))])
    add("vertex_exactly_at_focus", [tri(px(16, 4, F), px(4, 28, 2.5), px(29, 26, 11.0))])
    add("degenerate_collinear_3d",
        [tri([-0.5, -0.25, -3.0], [0.0, 0.0, -4.0], [0.5, 0.25, -5.0]),
         tri([-0.5, 0.5, -6.0], [-0.5, 0.5, -6.0], [0.5, -0.5, -4.0]),
         tri([0.25, 0.25, -4.0], [0.25, 0.25, -4.0], [0.25, 0.25, -4.0])])
    add("edge_on_to_pinhole", [tri([0.0, -1.0, -3.0], [0.0, 1.0, -3.0], [0.0, 0.25, -9.0])], coc_px=12.0)
    add("huge_blur_tiny_triangles",
        [tri(px(12, 12, 4.5), px(20, 13, 4.5), px(15, 20, 4.5)),
         tri(px(8, 10, 2.5), px(16, 9, 2.5), px(11, 17, 2.5)),
         tri(px(20, 20, 40.0), px(23, 21, 40.0), px(21, 24, 40.0))],
        coc_px=500.0)
    add("tiny_coc", [tri(px(3.3, 4.1, 2.0), px(28.7, 9.2, 7.0), px(12.5, 29.9, 20.0))], coc_px=0.001)
    add("entirely_behind_near_plane",
        [tri(px(4, 4, 0.05), px(28, 4, 0.09), px(16, 28, 0.02)),
         tri([0.0, 0.0, 1.0], [1.0, 0.0, 2.0], [0.0, 1.0, 0.5]),
         tri(px(8, 8, 3.0), px(24, 8, 3.0), px(16, 24, 3.0))],
        counters={"setup.culled_near": 2})
    add("moving_through_near_plane",
        [tri(px(6, 6, 3.0), px(26, 8, 3.5), px(15, 27, 4.0)),
         tri(px(8, 20, 0.05), px(25, 22, 0.05), px(16, 5, 0.08))],
        [tri(px(6, 6, 3.0) + [0, 0, 4.0], px(26, 8, 3.5) + [0, 0, 4.0], px(15, 27, 4.0) + [0, 0, 4.0]),
         tri(px(8, 20, 3.0), px(25, 22, 3.0), px(16, 5, 4.0))],
        counters={"setup.bbox_fallback": 2})
    add("vertex_on_lens_plane_and_at_near",  # w = 0 exactly (a point at infinity), w = near exactly
        [tri(px(6, 8, 3.0), px(26, 10, 6.0), [0.3, -0.2, 0.0]),
         tri(px(4, 24, cam.near), px(28, 28, 2.0), px(16, 12, 4.0))],
        counters={"setup.near_clipped": 1})
    add("gigantic_coordinates",  # edges of the 1e6-sized triangles cross the screen
        [tri([-2e5, -1e5, -1e6], [3e5, -1.5e5, -1e6], [0.0, 2e5, -1.1e6]),
         tri([-1e6, 0.3, -10.0], [1e6, -0.5, -10.0], [0.0, -1e6, -9.0]),
         tri([0.2, -1e6, -1e6], [0.9, 1e6, -1e6], [1e6, 0.0, -1e6])])
    add("moving_and_defocused_crossing_focus",
        [tri(px(4, 4, 2.0), px(20, 6, 8.0), px(10, 20, 5.0))],
        [tri(px(12, 10, 9.0), px(28, 12, 2.5), px(18, 28, 5.0))])
    return cases


def check_resolved(request, label, cam, positions, positions_t1, table, result) -> dict:
    """Compare a render's resolved samples (export_samples=True) with the ray caster, record the
    figures on the test report, and fail on any mismatch away from an edge or the near plane or any
    depth outside tolerance. Returns compare_resolved's dict for further checks."""
    pts = table_points(table, cam)
    r = compare_resolved(cam, positions, positions_t1, pts, result.sample_triangle, result.sample_depth)
    for k in ("samples", "covered", "mismatches", "unexplained", "depth_ties", "depth_bad", "max_z_err"):
        request.node.user_properties.append((k, r[k]))
    bad = [tuple(int(v) for v in i) for i in r["unexplained_idx"][:5]]
    assert r["unexplained"] == 0, (
        f"{label}: {r['unexplained']} samples (py, px, s) differ from the ray caster away from edges: {bad}, "
        f"engine {[int(result.sample_triangle[i]) for i in bad]}, reference {[int(r['ref_triangle'][i]) for i in bad]}")
    assert r["depth_bad"] == 0, f"{label}: depth differs on {r['depth_bad']} samples (max |dz| {r['max_z_err']:.3g})"
    return r


@dataclass
class Tris:
    """The duck-typed scene sim.render accepts: world-space (N, 3, 3) arrays."""

    positions: np.ndarray
    positions_t1: np.ndarray
    colors: np.ndarray


def make_scene(p0, p1=None, colour_seed: int = 1234) -> Tris:
    """Triangles p0 (static, or moving to p1) with distinct, deterministic vertex colours."""
    p0 = np.asarray(p0, dtype=np.float64).reshape(-1, 3, 3)
    p1 = p0.copy() if p1 is None else np.asarray(p1, dtype=np.float64).reshape(-1, 3, 3)
    n = p0.shape[0]
    rng = np.random.default_rng(colour_seed + n)
    return Tris(p0, p1, rng.uniform(0.1, 1.0, size=(n, 3, 3)))
