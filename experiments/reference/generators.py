"""Random inputs for the reference comparisons: cameras, triangles of every hard kind, samples
aimed at a triangle's edges and near-plane cut, and the duck-typed scene sim.render accepts."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import sim
from sim.lens import map_to_lens

from .raycaster import proj_scales, screen_to_world, triangle_at, world_to_view

# ----------------------------------------------------------------------------- cameras and triangles

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


# ----------------------------------------------------------------------------- samples


def lens_uv(rng, shape, n):
    """n uniform lens points (float32-exact values as float64) in the aperture `shape`."""
    u, v = map_to_lens(rng.random(n), rng.random(n), shape)
    return np.stack([u, v], axis=1).astype(np.float32).astype(np.float64)


def sample_points(rng, cam, p0, p1, m):
    """m samples (m, 5) float32, lens points uniform in the camera's aperture, t uniform: half with
    (x, y) uniform in the triangle's blurred, moving screen bounds (the whole screen when a vertex
    is behind the near plane), half aimed at the triangle from the sample's lens point and time
    (near its edges and, where it crosses the near plane, near that cut)."""
    view = np.concatenate([world_to_view(cam, p0), world_to_view(cam, p1)])
    w = -view[:, 2]
    s_x, s_y = proj_scales(cam)
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


# ----------------------------------------------------------------------------- scenes


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
