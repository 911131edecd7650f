"""Procedural scenes: single triangles, quads, hard cases (focus crossing, behind the camera,
degenerate) and the mixed-size scene of [Akenine-Möller 2012] Fig. 17.

All scenes are in the view space of the engine's default camera (origin, looking down -z, +y up).
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from .geometry import pixels_to_view
from .registry import register_scene
from .scene import Scene, SceneError

__all__ = ["quad_triangles"]


def _hint(width: int, height: int, fov_y_deg: float, focus_distance: float) -> dict:
    return {"width": width, "height": height, "fov_y_deg": fov_y_deg, "focus_distance": focus_distance}


def _ndc_point(ndc_x: float, ndc_y: float, depth: float, fov_y_deg: float, aspect: float = 1.0) -> list[float]:
    """The view-space point at depth (> 0) that projects to normalised device coordinates (x, y)."""
    tan_half = np.tan(np.radians(fov_y_deg) / 2.0)
    return [ndc_x * tan_half * aspect * depth, ndc_y * tan_half * depth, -depth]


def quad_triangles(center: Sequence[float], size_x: float, size_y: float) -> np.ndarray:
    """(2, 3, 3): a rectangle in the plane z = center[2], facing +z (counter-clockwise seen from the
    camera), split along its rising diagonal."""
    cx, cy, cz = (float(c) for c in center)
    hx, hy = size_x / 2.0, size_y / 2.0
    a, b, c, d = (cx - hx, cy - hy, cz), (cx + hx, cy - hy, cz), (cx + hx, cy + hy, cz), (cx - hx, cy + hy, cz)
    return np.array([[a, b, c], [a, c, d]], dtype=np.float64)


def _positive(name: str, value: float) -> float:
    if not np.isfinite(value) or value <= 0:
        raise SceneError(f"{name}: expected a positive number, got {value!r}")
    return float(value)


@register_scene("single_triangle")
def single_triangle(
    *,
    vertices: Any = None,
    depth: float = 3.0,
    color: Sequence[float] = (0.9, 0.35, 0.2),
    width: int = 256,
    height: int = 256,
    fov_y_deg: float = 45.0,
) -> Scene:
    """One triangle: vertices (3, 3) in view space, or a default one facing the camera at depth."""
    depth = _positive("depth", depth)
    if vertices is None:
        vertices = [[-0.8, -0.6, -depth], [0.8, -0.5, -depth], [0.1, 0.7, -depth]]
    vertices = np.asarray(vertices, dtype=np.float64)
    if vertices.shape != (3, 3):
        raise SceneError(f"vertices: expected shape (3, 3), got {vertices.shape}")
    scene = Scene.from_arrays(vertices[None], colors=color, name="single_triangle")
    mean_depth = float(-scene.positions[0, :, 2].mean())
    focus = mean_depth if mean_depth > 0 else depth
    return scene.with_camera_hint(**_hint(width, height, fov_y_deg, focus))


@register_scene("quad")
def quad(
    *,
    size: float = 1.0,
    depth: float = 3.0,
    center: Sequence[float] = (0.0, 0.0),
    translation_t1: Sequence[float] | None = None,
    color: Sequence[float] = (0.2, 0.6, 0.9),
    width: int = 256,
    height: int = 256,
    fov_y_deg: float = 45.0,
) -> Scene:
    """A fronto-parallel square (2 triangles) of side size at depth, centred at (x, y), optionally moving."""
    size, depth = _positive("size", size), _positive("depth", depth)
    if len(center) != 2:
        raise SceneError(f"center: expected (x, y), got {center!r}")
    scene = Scene.from_arrays(
        quad_triangles((center[0], center[1], -depth), size, size),
        colors=color,
        name="quad",
        camera_hint=_hint(width, height, fov_y_deg, depth),
    )
    return scene if translation_t1 is None else scene.with_motion(translation_t1)


@register_scene("focus_crossing")
def focus_crossing(
    *,
    focus_distance: float = 4.0,
    near_depth: float = 2.0,
    far_depth: float = 8.0,
    width: int = 256,
    height: int = 256,
    fov_y_deg: float = 45.0,
) -> Scene:
    """Two triangles spanning the focus plane: one vertex near and two far (left), and the reverse (right)."""
    if not 0 < near_depth < focus_distance < far_depth:
        raise SceneError(
            f"focus_crossing: need 0 < near_depth < focus_distance < far_depth, "
            f"got {near_depth}, {focus_distance}, {far_depth}"
        )

    def p(x: float, y: float, d: float) -> list[float]:
        return _ndc_point(x, y, d, fov_y_deg, width / height)

    positions = [
        [p(-0.9, -0.6, far_depth), p(-0.1, -0.6, far_depth), p(-0.5, 0.7, near_depth)],
        [p(0.15, -0.6, near_depth), p(0.85, -0.6, near_depth), p(0.5, 0.7, far_depth)],
    ]
    colors = [[0.9, 0.5, 0.1], [0.1, 0.7, 0.4]]
    return Scene.from_arrays(
        positions, colors=colors, name="focus_crossing", camera_hint=_hint(width, height, fov_y_deg, focus_distance)
    )


@register_scene("behind_camera")
def behind_camera(
    *,
    behind_z: float = 1.0,
    depth: float = 3.0,
    width: int = 256,
    height: int = 256,
    fov_y_deg: float = 45.0,
) -> Scene:
    """Triangles with a vertex behind the camera (view z = behind_z > 0) that are still partly visible."""
    behind_z = _positive("behind_z", behind_z)
    depth = _positive("depth", depth)
    positions = [
        # a wedge whose third vertex is behind the camera: its visible part runs off the top right
        [[-1.0, -0.8, -depth], [1.0, -0.8, -depth], [1.2, 0.9, behind_z]],
        # a floor that runs under the camera and on behind it
        [[-4.0, -1.2, -4.0 * depth], [4.0, -1.2, -4.0 * depth], [0.0, -1.2, behind_z + 3.0]],
    ]
    colors = [[0.85, 0.25, 0.25], [0.3, 0.3, 0.8]]
    return Scene.from_arrays(
        positions, colors=colors, name="behind_camera", camera_hint=_hint(width, height, fov_y_deg, depth)
    )


@register_scene("degenerate")
def degenerate(
    *,
    width: int = 256,
    height: int = 256,
    fov_y_deg: float = 45.0,
    focus_distance: float = 3.0,
) -> Scene:
    """Zero-area triangles, edge-on triangles whose plane holds the camera centre, and one normal triangle."""
    positions = [
        # 0: a normal triangle behind everything, so the image is not empty
        [[-2.0, -1.5, -6.0], [2.0, -1.5, -6.0], [0.0, 2.0, -6.0]],
        # 1: a repeated vertex
        [[-0.5, 0.2, -3.0], [0.5, 0.6, -3.0], [-0.5, 0.2, -3.0]],
        # 2: collinear vertices in a plane of constant depth
        [[-1.0, -1.0, -3.0], [0.0, 0.0, -3.0], [1.0, 1.0, -3.0]],
        # 3: collinear vertices on a line that recedes in depth
        [[-1.0, 0.5, -2.0], [0.0, 0.5, -3.0], [1.0, 0.5, -4.0]],
        # 4: all three vertices the same point
        [[0.3, -0.3, -3.0], [0.3, -0.3, -3.0], [0.3, -0.3, -3.0]],
        # 5: edge-on in the plane x = 0: a line through the pinhole, an area through an off-centre
        #    lens point because its vertices sit at different depths from the focus plane
        [[0.0, -0.5, -2.0], [0.0, 0.5, -3.0], [0.0, -0.3, -5.0]],
        # 6: edge-on in the tilted plane x + y = 0 (also through the camera centre)
        [[0.3, -0.3, -2.0], [-0.4, 0.4, -3.0], [0.5, -0.5, -6.0]],
    ]
    colors = [
        [0.5, 0.5, 0.5],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 0.0],
        [1.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
    ]
    return Scene.from_arrays(
        positions, colors=colors, name="degenerate", camera_hint=_hint(width, height, fov_y_deg, focus_distance)
    )


@register_scene("mixed_sizes")
def mixed_sizes(
    *,
    n: int = 20000,
    min_area_px: float = 1.0,
    max_area_px: float = 1e5,
    depth_min: float = 2.0,
    depth_max: float = 10.0,
    seed: int = 0,
    resolution: int = 512,
    fov_y_deg: float = 45.0,
    focus_distance: float | None = None,
) -> Scene:
    """Triangles with log-uniform screen areas ([Akenine-Möller 2012] Fig. 17): random depths, positions, colours."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
        raise SceneError(f"n: expected a non-negative integer, got {n!r}")
    if not 0 < min_area_px <= max_area_px:
        raise SceneError(f"min_area_px, max_area_px: need 0 < min <= max, got {min_area_px}, {max_area_px}")
    if not 0 < depth_min <= depth_max:
        raise SceneError(f"depth_min, depth_max: need 0 < min <= max, got {depth_min}, {depth_max}")
    if focus_distance is None:
        focus_distance = 0.5 * (depth_min + depth_max)
    rng = np.random.default_rng(seed)
    # Screen areas at the reference resolution/fov, log-uniform in [min, max].
    area_px = np.exp(rng.uniform(np.log(min_area_px), np.log(max_area_px), n))
    depth = rng.uniform(depth_min, depth_max, n)
    centroid_px = rng.uniform(0.0, resolution, (n, 2))
    # Reasonably fat shapes: three vertices near 0, 120 and 240 degrees (jittered) at radii 0.7..1.3,
    # in counter-clockwise order (angles stay increasing) in a y-up frame, randomly rotated.
    angles = (
        np.array([0.0, 2.0, 4.0]) * np.pi / 3.0
        + rng.uniform(-0.35, 0.35, (n, 3))
        + rng.uniform(0.0, 2.0 * np.pi, (n, 1))
    )
    radii = rng.uniform(0.7, 1.3, (n, 3))
    shape = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=-1)  # (n, 3, 2)
    shape -= shape.mean(axis=1, keepdims=True)
    edge1, edge2 = shape[:, 1] - shape[:, 0], shape[:, 2] - shape[:, 0]
    unit_area = 0.5 * (edge1[:, 0] * edge2[:, 1] - edge1[:, 1] * edge2[:, 0])
    shape *= np.sqrt(area_px / unit_area)[:, None, None]
    # y-up offsets -> pixel coordinates (rows grow downwards)
    pixel = centroid_px[:, None, :] + shape * np.array([1.0, -1.0])
    # Tilt each triangle a little (vertex depths within +-5 %), so it only roughly faces the camera;
    # unprojecting each vertex at its own depth keeps the designed screen area exact.
    vertex_depth = np.clip(depth[:, None] * rng.uniform(0.95, 1.05, (n, 3)), depth_min, depth_max)
    positions = pixels_to_view(pixel, vertex_depth, resolution, resolution, fov_y_deg)
    colors = rng.uniform(0.15, 0.95, (n, 3))
    return Scene.from_arrays(
        positions,
        colors=colors,
        name="mixed_sizes",
        camera_hint=_hint(resolution, resolution, fov_y_deg, float(focus_distance)),
    )


@register_scene("moving_quads")
def moving_quads(
    *,
    speed: float = 1.0,
    width: int = 256,
    height: int = 256,
    fov_y_deg: float = 45.0,
    focus_distance: float = 4.0,
) -> Scene:
    """Quads at several depths moving in different directions and speeds, over a static backdrop."""
    # (centre x, y, depth, size, motion over the shutter at speed 1, colour)
    layout = [
        ((0.0, 0.0), 9.0, 8.0, (0.0, 0.0, 0.0), (0.35, 0.35, 0.35)),
        ((-0.7, 0.5), 3.0, 0.5, (0.6, 0.0, 0.0), (0.9, 0.2, 0.2)),
        ((0.6, 0.4), 4.0, 0.6, (0.0, -0.8, 0.0), (0.2, 0.8, 0.3)),
        ((0.0, -0.8), 6.0, 1.0, (-1.0, 0.5, 0.0), (0.2, 0.3, 0.9)),
        ((0.5, -0.6), 3.5, 0.4, (0.0, 0.0, 1.0), (0.9, 0.8, 0.2)),
        ((-0.4, -0.3), 2.5, 0.3, (0.15, 0.1, 0.0), (0.8, 0.3, 0.8)),
    ]
    parts = []
    for (cx, cy), depth, size, motion, color in layout:
        part = Scene.from_arrays(quad_triangles((cx, cy, -depth), size, size), colors=color)
        parts.append(part.with_motion(np.asarray(motion) * speed))
    return Scene.concat(*parts, name="moving_quads").with_camera_hint(
        **_hint(width, height, fov_y_deg, focus_distance)
    )


@register_scene("textured_square")
def textured_square(
    *,
    edge_px: float = 64.0,
    width: int = 320,
    height: int = 320,
    fov_y_deg: float = 45.0,
    depth: float = 10.0,
    focus_distance: float = 5.0,
    texture_size: int = 512,
    texture_seed: int = 7,
) -> Scene:
    """A fronto-parallel square (two triangles) covering edge_px x edge_px pixels at ``depth``, with uvs
    0..edge_px/texture_size so that the procedural texture maps about one texel per pixel (level of
    detail about 0): the texture-cache workload of Hakura & Gupta's pinhole comparison."""
    from sim.texturing import procedural_texture

    _positive("edge_px", edge_px)
    _positive("depth", depth)
    s_y = 1.0 / np.tan(np.radians(fov_y_deg) / 2.0)
    half = edge_px / (s_y * height / depth)
    k = edge_px / texture_size
    uvs = np.array([[[0, 0], [k, 0], [k, k]], [[0, 0], [k, k], [0, k]]], np.float32)
    scene = Scene.from_arrays(quad_triangles((0.0, 0.0, -depth), 2 * half, 2 * half), uvs=uvs,
                              texture=procedural_texture(texture_size, texture_seed))
    return scene.with_camera_hint(**_hint(width, height, fov_y_deg, focus_distance))
