"""Small geometry helpers: 4x4 affine matrices and the pinhole mapping of the engine's default camera.

The default camera sits at the origin looking down -z, +y up, with a vertical field of view fov_y_deg.
Pixel (X, Y) covers [X, X+1) x [Y, Y+1) and row 0 is the top of the picture (docs/conventions.md).
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

__all__ = [
    "translation_matrix",
    "scale_matrix",
    "rotation_matrix_deg",
    "compose",
    "pixels_to_view",
    "view_to_pixels",
]


def translation_matrix(offset: Sequence[float]) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, 3] = np.asarray(offset, dtype=np.float64)
    return matrix


def scale_matrix(scale: float | Sequence[float]) -> np.ndarray:
    factors = np.broadcast_to(np.asarray(scale, dtype=np.float64), (3,))
    return np.diag([*factors, 1.0])


def rotation_matrix_deg(angles_deg: Sequence[float]) -> np.ndarray:
    """Rotation by (rx, ry, rz) degrees about the x, then y, then z axis (right-handed, counter-
    clockwise looking down each axis towards the origin): R = Rz @ Ry @ Rx."""
    rx, ry, rz = np.radians(np.asarray(angles_deg, dtype=np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
    rot_x = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    rot_y = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rot_z = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    matrix = np.eye(4)
    matrix[:3, :3] = rot_z @ rot_y @ rot_x
    return matrix


def compose(*matrices: Any) -> np.ndarray:
    """compose(A, B, C) = A @ B @ C: C acts first."""
    result = np.eye(4)
    for matrix in matrices:
        result = result @ np.asarray(matrix, dtype=np.float64)
    return result


def pixels_to_view(pixel_xy: np.ndarray, depth: np.ndarray, width: int, height: int, fov_y_deg: float) -> np.ndarray:
    """Points at view depth depth (> 0, i.e. z = -depth) that the pinhole maps to pixel_xy (..., 2)."""
    pixel_xy = np.asarray(pixel_xy, dtype=np.float64)
    depth = np.asarray(depth, dtype=np.float64)
    tan_half = np.tan(np.radians(fov_y_deg) / 2.0)
    ndc_x = 2.0 * pixel_xy[..., 0] / width - 1.0
    ndc_y = 1.0 - 2.0 * pixel_xy[..., 1] / height
    x = ndc_x * tan_half * (width / height) * depth
    y = ndc_y * tan_half * depth
    return np.stack([x, y, -depth * np.ones_like(x)], axis=-1)


def view_to_pixels(points: np.ndarray, width: int, height: int, fov_y_deg: float) -> np.ndarray:
    """Pinhole projection of view-space points (..., 3) with z < 0 to pixel coordinates (..., 2)."""
    points = np.asarray(points, dtype=np.float64)
    tan_half = np.tan(np.radians(fov_y_deg) / 2.0)
    depth = -points[..., 2]
    ndc_x = points[..., 0] / (depth * tan_half * (width / height))
    ndc_y = points[..., 1] / (depth * tan_half)
    return np.stack([(ndc_x + 1.0) * 0.5 * width, (1.0 - ndc_y) * 0.5 * height], axis=-1)
