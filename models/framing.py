"""A camera hint that frames a scene from its bounding box: for meshes and scene files that carry no
camera, so that the first render of a bare mesh shows the mesh (the default camera at the origin
may sit inside it or look away from it)."""
from __future__ import annotations

import numpy as np

from .scene import Scene

__all__ = ["frame_hint", "has_pose"]

POSE_KEYS = ("eye", "target")


def has_pose(hint: dict) -> bool:
    """True when a camera hint places the camera (eye or target given)."""
    return any(k in hint for k in POSE_KEYS)


def frame_hint(scene: Scene, *, fov_y_deg: float = 45.0, aspect: float = 1.0, margin: float = 1.1) -> dict:
    """Camera hint (sim.Camera keywords) looking down -z at the centre of the scene's bounding box
    from the distance at which its bounding sphere (radius times margin) fills the narrower field of
    view; focused on the centre, near plane well in front of the sphere."""
    lo, hi = scene.bounds()
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    centre = (lo + hi) / 2.0
    radius = float(np.linalg.norm(hi - lo)) / 2.0 * margin
    if not np.isfinite(radius) or radius <= 0.0:
        radius = 1.0
    half_y = np.radians(fov_y_deg) / 2.0
    half = min(half_y, np.arctan(np.tan(half_y) * aspect))
    distance = radius / np.sin(half)
    eye = centre + np.array([0.0, 0.0, distance])
    return {
        "fov_y_deg": float(fov_y_deg),
        "eye": tuple(float(v) for v in eye),
        "target": tuple(float(v) for v in centre),
        "up": (0.0, 1.0, 0.0),
        "focus_distance": float(distance),
        "near": float(max(distance - radius, distance * 1e-3) * 0.5),
    }
