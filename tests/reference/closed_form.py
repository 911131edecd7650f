"""Closed-form expected coverage of axis-aligned squares blurred by the lens and moving in x, and the
fronto-parallel squares that realise them in a scene."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from experiments.reference.raycaster import screen_to_world

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
