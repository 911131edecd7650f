"""Scenes for the 5D-pipeline reports (docs/intervals.md): triangles moving a given number of
pixels over the shutter, and stacks of screen-filling layers for depth complexity."""
from __future__ import annotations

import numpy as np

from .geometry import pixels_to_view
from .procedural import _hint, mixed_sizes
from .registry import register_scene
from .scene import Scene, SceneError


@register_scene("motion_field")
def motion_field(
    *,
    n: int = 400,
    motion_px: float = 50.0,
    min_area_px: float = 4.0,
    max_area_px: float = 400.0,
    depth_min: float = 3.0,
    depth_max: float = 8.0,
    focus_distance: float = 5.0,
    seed: int = 0,
    resolution: int = 128,
    fov_y_deg: float = 45.0,
) -> Scene:
    """mixed_sizes triangles, each translated motion_px pixels (random direction) in its depth plane over the shutter."""
    if not np.isfinite(motion_px) or motion_px < 0:
        raise SceneError(f"motion_px: expected a non-negative number, got {motion_px!r}")
    base = mixed_sizes(n=n, min_area_px=min_area_px, max_area_px=max_area_px, depth_min=depth_min,
                       depth_max=depth_max, seed=seed, resolution=resolution, fov_y_deg=fov_y_deg,
                       focus_distance=focus_distance)
    p0 = np.asarray(base.positions, dtype=np.float64)
    rng = np.random.default_rng(seed + 1)
    ang = rng.uniform(0.0, 2.0 * np.pi, len(p0))
    # a screen displacement of motion_px at the triangle's mean depth, as a world offset in its plane
    depth = -p0[:, :, 2].mean(axis=1)
    px_per_unit = resolution / (2.0 * depth * np.tan(np.radians(fov_y_deg) / 2.0))
    offset = np.zeros((len(p0), 3))
    offset[:, 0] = motion_px * np.cos(ang) / px_per_unit
    offset[:, 1] = motion_px * np.sin(ang) / px_per_unit
    return Scene.from_arrays(p0, colors=np.asarray(base.colors)[:, 0], positions_t1=p0 + offset[:, None, :],
                             name="motion_field", camera_hint=base.camera_hint)


@register_scene("depth_layers")
def depth_layers(
    *,
    layers: int = 4,
    front_depth: float = 2.0,
    spacing: float = 0.75,
    order: str = "front_to_back",
    motion_px: float = 0.0,
    resolution: int = 128,
    fov_y_deg: float = 45.0,
    focus_distance: float = 4.0,
) -> Scene:
    """`layers` screen-covering, slightly tilted quads (depth complexity = layers), submitted front to back or back to front."""
    if isinstance(layers, bool) or not isinstance(layers, (int, np.integer)) or layers < 1:
        raise SceneError(f"layers: expected a positive integer, got {layers!r}")
    if order not in ("front_to_back", "back_to_front"):
        raise SceneError(f"order: expected 'front_to_back' or 'back_to_front', got {order!r}")
    rng = np.random.default_rng(layers)
    tris, tris1, colors = [], [], []
    m = 0.15 * resolution + motion_px
    corners = np.array([[-m, -m], [resolution + m, -m], [resolution + m, resolution + m], [-m, resolution + m]])
    ks = range(layers) if order == "front_to_back" else range(layers - 1, -1, -1)
    for k in ks:
        d = front_depth + spacing * k
        tilt = 1.0 + 0.05 * np.array([-1.0, -1.0, 1.0, 1.0]) * (1 if k % 2 else -1)
        quad = pixels_to_view(corners[None], (d * tilt)[None], resolution, resolution, fov_y_deg)[0]
        shift = np.zeros(3)
        shift[0] = motion_px * 2.0 * d * np.tan(np.radians(fov_y_deg) / 2.0) / resolution * (1 if k % 2 else -1)
        for a, b, c in ((0, 1, 2), (0, 2, 3)):
            tris.append(quad[[a, b, c]])
            tris1.append(quad[[a, b, c]] + shift)
        col = rng.uniform(0.2, 0.9, 3)
        colors += [col, col]
    return Scene.from_arrays(np.array(tris), colors=np.array(colors), positions_t1=np.array(tris1),
                             name="depth_layers",
                             camera_hint=_hint(resolution, resolution, fov_y_deg, float(focus_distance)))
