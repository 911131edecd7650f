"""Float64 thin-lens ray caster, the independent reference for the engine's coverage and depth.

It is built from the camera *model* (camera.py docstring), not from the engine's clip-space shear:
a sample (sx, sy, u, v, t) is the world ray from the lens point L = (u R, v R, 0) (view space,
R = aperture radius) through the point of the focus plane (view depth F) that the pinhole camera
sees at pixel position (sx, sy); it is intersected with the triangle at time t by Moller-Trumbore in
float64 and counts when the hit's view depth w >= near.
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

# ----------------------------------------------------------------------------- camera geometry


def pinhole_scales(width, height, fov_y_deg):
    """(s_x, s_y) of the projection: x_ndc = s_x x / w, y_ndc = s_y y / w at view depth w."""
    s_y = 1.0 / math.tan(math.radians(fov_y_deg) / 2.0)
    return s_y * height / width, s_y


def proj_scales(cam):
    """pinhole_scales of camera cam."""
    return pinhole_scales(cam.width, cam.height, cam.fov_y_deg)


def world_from_pixel(px, py, depth, width, height, fov_y_deg=45.0):
    """The world point at view depth `depth` (> 0) that the lens centre of a camera in the default
    pose (at the origin, looking down -z, so view space is world space) sees at pixel (px, py): the
    inverse of px = ((x / depth) s_x + 1) W / 2, py = (1 - (y / depth) s_y) H / 2."""
    s_x, s_y = pinhole_scales(width, height, fov_y_deg)
    return np.array([(2.0 * px / width - 1.0) * depth / s_x, (1.0 - 2.0 * py / height) * depth / s_y, -depth])


def world_to_view(cam, p):
    """(..., 3) world points -> view space (float64) with cam.view_matrix()."""
    m = cam.view_matrix()
    p = np.asarray(p, dtype=np.float64)
    return p @ m[:3, :3].T + m[:3, 3]


def screen_to_world(cam, sx, sy, w):
    """The world point at view depth w that the pinhole sees at pixel position (sx, sy)."""
    s_x, s_y = proj_scales(cam)
    sx, sy, w = np.broadcast_arrays(np.asarray(sx, float), np.asarray(sy, float), np.asarray(w, float))
    view = np.stack([((2.0 * sx / cam.width) - 1.0) / s_x * w, (1.0 - 2.0 * sy / cam.height) / s_y * w, -w], axis=-1)
    m = cam.view_matrix()
    return (view - m[:3, 3]) @ m[:3, :3]  # inverse of a rigid transform


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
    s_x, s_y = proj_scales(cam)
    F = cam.focus_distance
    R = cam.aperture_radius
    q = np.stack([((2.0 * sx / cam.width) - 1.0) / s_x * F, (1.0 - 2.0 * sy / cam.height) / s_y * F,
                  np.full_like(sx, -F)], axis=-1)
    lens = np.stack([u * R, v * R, np.zeros_like(u)], axis=-1)
    return lens, q - lens


# ----------------------------------------------------------------------------- coverage and depth


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


# ----------------------------------------------------------------------------- distances to the decision boundaries


def edge_distance_px(cam, p0, p1, points):
    """Screen distance in pixels from each sample (..., 5) to the nearest of the three edge lines of
    the triangle at the sample's time, as seen from the sample's lens point: the plane through the
    lens point and an edge meets the focus plane in a line, which maps affinely to a line on the
    screen. inf where the plane is parallel to the focus plane and misses the sample."""
    pts = np.asarray(points, dtype=np.float64)
    tri = triangle_at(cam, p0, p1, pts[..., 4])
    org, d = sample_rays(cam, pts)
    s_x, s_y = proj_scales(cam)
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
