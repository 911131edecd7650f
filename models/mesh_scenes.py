"""Named scenes built from the bundled meshes in models/assets/: bunny, spot, teapot, and the default
scene spot_wall (the textured cow in front of a checkered wall, moving a little: defocus + motion)."""
from __future__ import annotations

import functools
from typing import Any, Sequence

import numpy as np

from .geometry import compose, rotation_matrix_deg, scale_matrix, translation_matrix
from .mesh import asset_path, load_mesh
from .procedural import quad_triangles
from .registry import register_scene
from .scene import Scene, SceneError

__all__ = ["place_in_view"]

SPOT_OBJ = "spot/spot_triangulated.obj"
BUNNY_OBJ = "stanford-bunny/stanford-bunny.obj"
TEAPOT_OBJ = "teapot/teapot.obj"


@functools.lru_cache(maxsize=8)
def _asset_scene(relative: str) -> Scene:
    # Cached: callers only derive new scenes from it (transformed/with_color copy the arrays).
    return load_mesh(asset_path(relative))


def place_in_view(
    scene: Scene,
    *,
    distance: float,
    rotation_deg: Sequence[float] = (0.0, 0.0, 0.0),
    fov_y_deg: float = 45.0,
    aspect: float = 1.0,
    fill: float = 0.8,
) -> Scene:
    """Centre the scene's bounding box on the origin, rotate it (degrees about x, y, z), scale it so
    its bounding sphere spans fill of the smaller half-extent of the view at distance, and move it
    to (0, 0, -distance)."""
    if not np.isfinite(distance) or distance <= 0:
        raise SceneError(f"distance: expected a positive number, got {distance!r}")
    if len(rotation_deg) != 3:
        raise SceneError(f"rotation_deg: expected (rx, ry, rz), got {rotation_deg!r}")
    lo, hi = scene.bounds()
    centre = 0.5 * (lo + hi)
    radius = float(np.linalg.norm(scene.positions.reshape(-1, 3) - centre, axis=1).max())
    half_extent = distance * np.tan(np.radians(fov_y_deg) / 2.0) * min(1.0, aspect)
    scale = fill * half_extent / radius if radius > 0 else 1.0
    matrix = compose(
        translation_matrix((0.0, 0.0, -distance)),
        scale_matrix(scale),
        rotation_matrix_deg(rotation_deg),
        translation_matrix(-centre),
    )
    return scene.transformed(matrix)


def _mesh_scene(
    relative: str, name: str, distance: float, rotation_deg: Sequence[float], color: Any,
    width: int, height: int, fov_y_deg: float, shading: str = "headlight",
) -> Scene:
    from . import shading as _shading

    scene = _asset_scene(relative)
    if color is not None:
        scene = scene.with_color(color)
    scene = place_in_view(
        scene, distance=distance, rotation_deg=rotation_deg, fov_y_deg=fov_y_deg, aspect=width / height
    )
    scene = _shading.apply(scene, shading)  # one colour: Lambert under a headlight at the camera (origin)
    scene.name = name
    return scene.with_camera_hint(width=width, height=height, fov_y_deg=fov_y_deg, focus_distance=distance)


@register_scene("bunny")
def bunny(
    *,
    distance: float = 4.0,
    rotation_deg: Sequence[float] = (0.0, 0.0, 0.0),
    color: Sequence[float] | None = (0.8, 0.75, 0.7),
    width: int = 512,
    height: int = 512,
    fov_y_deg: float = 45.0,
    shading: str = "headlight",
) -> Scene:
    """The Stanford bunny (69,451 triangles; research/non-commercial licence), fitted in view at distance; shading 'headlight' (Lambert under a light at the camera, models/shading.py) or 'flat'."""
    return _mesh_scene(BUNNY_OBJ, "bunny", distance, rotation_deg, color, width, height, fov_y_deg, shading)


@register_scene("spot")
def spot(
    *,
    distance: float = 4.0,
    rotation_deg: Sequence[float] = (0.0, -120.0, 0.0),
    width: int = 512,
    height: int = 512,
    fov_y_deg: float = 45.0,
) -> Scene:
    """Keenan Crane's textured cow (5,856 triangles, UVs, 1024^2 texture), fitted in view at distance."""
    return _mesh_scene(SPOT_OBJ, "spot", distance, rotation_deg, None, width, height, fov_y_deg)


@register_scene("teapot")
def teapot(
    *,
    distance: float = 4.0,
    rotation_deg: Sequence[float] = (15.0, 0.0, 0.0),
    color: Sequence[float] | None = (0.75, 0.75, 0.8),
    width: int = 512,
    height: int = 512,
    fov_y_deg: float = 45.0,
    shading: str = "headlight",
) -> Scene:
    """The Utah teapot (6,320 triangles), fitted in view at distance; shading 'headlight' (Lambert under a light at the camera, models/shading.py) or 'flat'."""
    return _mesh_scene(TEAPOT_OBJ, "teapot", distance, rotation_deg, color, width, height, fov_y_deg, shading)


def _checker_wall(
    x_range: tuple[float, float], y_range: tuple[float, float], depth: float, cells_x: int,
    colors: tuple[Sequence[float], Sequence[float]],
) -> Scene:
    """A wall at z = -depth made of square-ish cells in two alternating colours (geometry, not a
    texture, so the pattern shows before the engine has texturing)."""
    width = x_range[1] - x_range[0]
    height = y_range[1] - y_range[0]
    cell = width / cells_x
    cells_y = max(1, int(round(height / cell)))
    cell_h = height / cells_y
    tris, cols = [], []
    for j in range(cells_y):
        for i in range(cells_x):
            centre = (x_range[0] + (i + 0.5) * cell, y_range[0] + (j + 0.5) * cell_h, -depth)
            tris.append(quad_triangles(centre, cell, cell_h))
            cols += [colors[(i + j) % 2]] * 2
    return Scene.from_arrays(np.concatenate(tris), colors=np.asarray(cols, dtype=np.float64))


@register_scene("spot_wall")
def spot_wall(
    *,
    cow_distance: float = 3.5,
    wall_distance: float = 8.0,
    cow_motion: Sequence[float] = (0.12, 0.0, 0.0),
    rotation_deg: Sequence[float] = (0.0, -120.0, 0.0),
    cow_fill: float = 0.5,
    checker_cells: int = 10,
    width: int = 512,
    height: int = 512,
    fov_y_deg: float = 45.0,
) -> Scene:
    """Default scene: the textured spot cow, moving sideways, in focus before a defocused checkered wall and floor."""
    if not 0 < cow_distance < wall_distance:
        raise SceneError(f"cow_distance, wall_distance: need 0 < cow < wall, got {cow_distance}, {wall_distance}")
    aspect = width / height
    tan_half = np.tan(np.radians(fov_y_deg) / 2.0)
    # Rotate the cow, then scale it so its larger screen extent is cow_fill of the frame.
    cow = _asset_scene(SPOT_OBJ)
    lo, hi = cow.bounds()
    rotated = cow.transformed(compose(rotation_matrix_deg(rotation_deg), translation_matrix(-0.5 * (lo + hi))))
    rlo, rhi = rotated.bounds()
    frame_w, frame_h = 2 * cow_distance * tan_half * aspect, 2 * cow_distance * tan_half
    scale = cow_fill / max((rhi[0] - rlo[0]) / frame_w, (rhi[1] - rlo[1]) / frame_h)
    # Centre its box on the view axis, a little low so the floor line sits under its feet.
    rcentre = 0.5 * (rlo + rhi)
    cow = rotated.transformed(
        compose(translation_matrix((0.0, -0.1 * frame_h, -cow_distance)), scale_matrix(scale), translation_matrix(-rcentre))
    ).with_motion(cow_motion)
    floor_y = float(cow.positions[..., 1].min())

    half_w = 1.3 * wall_distance * tan_half * aspect
    top = 1.3 * wall_distance * tan_half
    wall = _checker_wall((-half_w, half_w), (floor_y, top), wall_distance, checker_cells,
                         ((0.8, 0.8, 0.78), (0.15, 0.2, 0.35)))
    near_z, far_z = -0.5, -wall_distance
    floor = Scene.from_arrays(
        [
            [[-half_w, floor_y, near_z], [half_w, floor_y, near_z], [half_w, floor_y, far_z]],
            [[-half_w, floor_y, near_z], [half_w, floor_y, far_z], [-half_w, floor_y, far_z]],
        ],
        colors=(0.45, 0.35, 0.25),
    )
    return Scene.concat(wall, floor, cow, name="spot_wall").with_camera_hint(
        width=width, height=height, fov_y_deg=fov_y_deg, focus_distance=cow_distance
    )
