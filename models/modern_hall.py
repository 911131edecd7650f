"""The "Modern Hall" interior (Mitsuba 0.5 XML in models/assets/modern-hall/scene.xml) as a Scene,
read by the Mitsuba importer (models/mitsuba.py, as ``models.load`` reads any Mitsuba scene).

Only the <shape type="obj"> entries are geometry here (19 OBJs, 30,911 triangles, 2,432 of them
zero-area, all kept: they are a hard case; in view space rounding gives 3 of them ~1e-16 area). The emitter-only disks and rectangles (area lights,
partly outside the windows) are left out. Materials become per-vertex colours and textures:
- a bitmap reflectance texture -> the texture (sRGB-decoded) and colours sampled from it at the UVs;
- an rgb reflectance -> that colour;
- a conductor -> its normal-incidence Fresnel reflectance ((n-1)^2 + k^2) / ((n+1)^2 + k^2);
- a dielectric (glass) -> a pale grey stand-in, as the rasterizer has no transparency.
"""
from __future__ import annotations

import functools
import warnings

import numpy as np

from .mesh import asset_path
from .mitsuba import SceneImportWarning, read_mitsuba
from .registry import register_scene
from .scene import Scene

HALL_XML = "modern-hall/scene.xml"

# Mitsuba's camera frame: looks down +z, +y up, +x to the image's left. Ours: looks down -z, +y up,
# +x right. Turning 180 degrees about y maps one onto the other (a rotation, so no mirroring).
MITSUBA_TO_OUR_CAMERA = np.diag([-1.0, 1.0, -1.0, 1.0])


def _centre_depth(view: Scene) -> float:
    """Autofocus: depth of the nearest surface on the view axis (the ray through the image centre),
    or the median centroid depth if the axis hits nothing."""
    v0, v1, v2 = view.positions[:, 0], view.positions[:, 1], view.positions[:, 2]
    direction = np.array([0.0, 0.0, -1.0])
    edge1, edge2 = v1 - v0, v2 - v0
    p = np.cross(direction, edge2)
    det = np.einsum("ij,ij->i", p, edge1)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = -v0
    u = np.einsum("ij,ij->i", p, s) * inv
    q = np.cross(s, edge1)
    w = (q @ direction) * inv
    t = np.einsum("ij,ij->i", q, edge2) * inv
    hit = ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (t > 0)
    if hit.any():
        return float(t[hit].min())
    return float(np.median(-view.positions[..., 2].mean(axis=1)))


@functools.lru_cache(maxsize=2)
def _hall_world() -> tuple[Scene, dict]:
    # The public importer (models.load on a .xml); what it leaves out here is documented above.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SceneImportWarning)
        world, sensor, _ = read_mitsuba(asset_path(HALL_XML))
    return world, sensor


@register_scene("modern_hall")
def modern_hall(
    *,
    camera_space: bool = True,
    width: int = 640,
    focus_distance: float | None = None,
    subdivide: int = 0,
) -> Scene:
    """Bitterli's "Modern Hall" (19 OBJs, 30,911 triangles incl. 2,432 zero-area) seen from its sensor;
    subdivide=1 splits every triangle into four (123,644 triangles: the dense interior of the
    benchmarks)."""
    world, sensor = _hall_world()
    # camera_space=True (default): the geometry is moved into the sensor's view space, so the
    # engine's default camera (origin, looking down -z, +y up) sees what the Mitsuba sensor saw, and
    # camera_hint holds no pose. camera_space=False: world coordinates, camera_hint has eye/target/up.
    world_to_view = MITSUBA_TO_OUR_CAMERA @ np.linalg.inv(sensor["to_world"])
    height = int(round(width * sensor["height"] / sensor["width"]))
    view = world.transformed(world_to_view)
    if focus_distance is None:
        focus_distance = _centre_depth(view)
    hint = {"width": width, "height": height, "fov_y_deg": sensor["fov_y_deg"], "focus_distance": focus_distance}
    if camera_space:
        scene = view
    else:
        to_world = sensor["to_world"]
        eye = to_world[:3, 3]
        forward = to_world[:3, 2] / np.linalg.norm(to_world[:3, 2])
        up = to_world[:3, 1] / np.linalg.norm(to_world[:3, 1])
        hint.update(eye=tuple(eye), target=tuple(eye + forward), up=tuple(up))
        scene = world.transformed(None)  # a copy: world is cached
    scene.name = "modern_hall"
    if subdivide:
        scene = scene.subdivided(subdivide)
    return scene.with_camera_hint(**hint)
