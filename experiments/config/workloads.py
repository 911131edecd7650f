"""Workloads that only the experiments use, looked up by `scene.name` after the named scenes of
models/ (models.scene_names()). Each takes keyword parameters (`scene.params`) and returns a
models.Scene with a camera hint."""
from __future__ import annotations

import math


def textured_square(*, edge_px: float = 64.0, width: int = 320, height: int = 320, fov_y_deg: float = 45.0,
                    depth: float = 10.0, focus_distance: float = 5.0, texture_size: int = 512, texture_seed: int = 7):
    """A fronto-parallel square (two triangles) covering edge_px x edge_px pixels at ``depth``, with uvs
    0..edge_px/texture_size so that the procedural texture maps about one texel per pixel (lambda ~ 0)."""
    import numpy as np

    import models
    import sim
    from models.procedural import quad_triangles

    s_y = 1.0 / math.tan(math.radians(fov_y_deg) / 2)
    half = edge_px / (s_y * height / depth)
    k = edge_px / texture_size
    uvs = np.array([[[0, 0], [k, 0], [k, k]], [[0, 0], [k, k], [0, k]]], np.float32)
    scene = models.Scene.from_arrays(quad_triangles((0.0, 0.0, -depth), 2 * half, 2 * half), uvs=uvs,
                                     texture=sim.texturing.procedural_texture(texture_size, texture_seed))
    return scene.with_camera_hint(width=width, height=height, fov_y_deg=fov_y_deg, focus_distance=focus_distance)


WORKLOADS = {"textured_square": textured_square}
