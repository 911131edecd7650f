"""The engine side of a comparison with the ray caster: the engine parameters of a camera, the engine's
per-sample probe of one triangle, and the pixel-homogeneous vertices a sample's lens point sees (the
float64 inputs of the fixed-point and float32 probes of the precision study)."""
from __future__ import annotations

import numpy as np

from sim import _core

from .raycaster import proj_scales, sample_rays, triangle_at


def engine_params(cam, *, has_lens=True, has_time=True):
    p = _core.RenderParams()
    for k, v in cam.engine_params().items():
        setattr(p, k, v)
    p.lens_shape = cam.lens
    p.table_has_lens = has_lens
    p.table_has_time = has_time
    return p


def engine_probe(cam, p0, p1, points, *, force_general=False, has_lens=True, has_time=True):
    """_core.probe of one world triangle (3, 3) at shutter open/close on samples (M, 5)."""
    v0, v1 = cam.engine_vertices(np.asarray(p0)[None], np.asarray(p1)[None])
    pts = np.ascontiguousarray(points, dtype=np.float32)
    return _core.probe(engine_params(cam, has_lens=has_lens, has_time=has_time), v0[0], v1[0], pts,
                       force_general)


def lens_homogeneous(cam, p0, p1, points):
    """Pixel-homogeneous vertices (..., 3, 3) = (px W, py W, W) of the triangle at each sample's time,
    as seen from the sample's lens point: (px, py) is where the line from the lens point through the
    vertex meets the focus plane, in pixels; W the vertex's view depth. Also the pinhole ones."""
    pts = np.asarray(points, dtype=np.float64)
    tri = triangle_at(cam, p0, p1, pts[..., 4])
    org, _ = sample_rays(cam, pts)
    s_x, s_y = proj_scales(cam)
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
