"""The default shading of a mesh without colours: Lambert under a headlight, per vertex, at load.

A mesh whose vertices all carry one colour and no texture (the bundled bunny and teapot, a user's OBJ
or PLY without colours) would render as a flat silhouette: every pixel the same grey. Such a mesh is
shaded once, when it is loaded and placed, as a diffuse (Lambertian) surface lit by a point light at
the camera (a headlight)::

    colour(vertex) = base * (ambient + (1 - ambient) * |n . l|)

with ``n`` the vertex's smooth normal (the area-weighted mean of the normals of the triangles sharing
its position), ``l`` the unit vector from the vertex to the light (the camera hint's ``eye``, else the
origin, where the default camera sits) and ``ambient`` 0.25. The ``|n . l|`` makes it two-sided, so a
mesh's winding does not matter. Colours are fixed at load: the rasterizer interpolates them like any
vertex colour, and no operation count changes (shading costs are the pipeline's `shading:` model, not
this). Switch it off with the scene parameter ``shading: flat`` (named mesh scenes) or
``models.load(path, shading="flat")``.
"""
from __future__ import annotations

import numpy as np

SHADINGS = ("headlight", "flat")
AMBIENT = 0.25


def is_uncoloured(scene) -> bool:
    """Whether every vertex has the same colour and no triangle is textured."""
    cols = np.asarray(scene.colors).reshape(-1, 3)
    textured = scene.texture_ids is not None and np.any(np.asarray(scene.texture_ids) >= 0)
    return len(cols) > 0 and not textured and bool(np.all(cols == cols[0]))


def vertex_normals(positions: np.ndarray) -> np.ndarray:
    """(N, 3, 3) smooth unit normals: per vertex position, the area-weighted sum of the normals of the
    triangles that share it (a vertex of no area keeps its face normal, or +z)."""
    p = np.asarray(positions, dtype=np.float64)
    face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])  # length = 2 x area
    flat = p.reshape(-1, 3)
    scale = max(float(np.abs(flat).max()), 1e-30) if len(flat) else 1.0
    # Each coordinate rounds to an integer in [-2^20, 2^20]; the three fit one uint64 key (base 2^21 + 1),
    # so positions group by a 1-D unique (a row-wise unique sorts structured rows: ten times as long).
    keys = (np.round(flat / scale * 2**20).astype(np.int64) + 2**20).astype(np.uint64)
    base = np.uint64(2**21 + 1)
    _, inverse = np.unique((keys[:, 0] * base + keys[:, 1]) * base + keys[:, 2], return_inverse=True)
    inverse = inverse.reshape(-1)
    # Per group, the face normals summed in vertex order (as np.add.at adds them), one axis at a time.
    face3 = np.repeat(face, 3, axis=0)
    groups = inverse.max() + 1 if len(inverse) else 0
    acc = np.stack([np.bincount(inverse, weights=face3[:, k], minlength=groups) for k in range(3)], axis=1)
    n = acc[inverse].reshape(-1, 3, 3)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    fallback = np.repeat(face[:, None, :], 3, axis=1)
    fl = np.linalg.norm(fallback, axis=-1, keepdims=True)
    fallback = np.where(fl > 0, fallback / np.where(fl > 0, fl, 1), np.array([0.0, 0.0, 1.0]))
    return np.where(length > 0, n / np.where(length > 0, length, 1), fallback)


def headlight(scene, eye=None, ambient: float = AMBIENT):
    """``scene`` with its vertex colours shaded by a Lambertian headlight at ``eye`` (default: the
    camera hint's eye, else the origin). The colours of both shutter ends use the open-shutter
    geometry (a moving mesh keeps its shading)."""
    if eye is None:
        eye = (scene.camera_hint or {}).get("eye") or (0.0, 0.0, 0.0)
    eye = np.asarray(eye, dtype=np.float64)
    n = vertex_normals(scene.positions)
    to_light = eye - np.asarray(scene.positions, dtype=np.float64)
    dist = np.linalg.norm(to_light, axis=-1, keepdims=True)
    l = to_light / np.where(dist > 0, dist, 1.0)
    lambert = np.abs(np.sum(n * l, axis=-1, keepdims=True))
    colors = np.asarray(scene.colors, dtype=np.float64) * (ambient + (1.0 - ambient) * lambert)
    return scene.with_color(colors.astype(np.float32))


def apply(scene, shading: str = "headlight", eye=None):
    """The default shading of a loaded scene: headlight() when it is uncoloured and ``shading`` is
    'headlight'; the scene itself otherwise ('flat', or a mesh with colours or a texture)."""
    from .scene import SceneError

    if shading not in SHADINGS:
        raise SceneError(f"shading: expected one of {', '.join(SHADINGS)}, got {shading!r}")
    if shading == "flat" or not is_uncoloured(scene):
        return scene
    return headlight(scene, eye)
