"""The "Modern Hall" interior (Mitsuba 0.5 XML in models/assets/modern-hall/scene.xml) as a Scene.

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
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from .geometry import scale_matrix, translation_matrix
from .mesh import asset_path, load_mesh
from .registry import register_scene
from .scene import Scene, SceneError
from .textures import load_texture, sample_bilinear

__all__ = ["load_mitsuba_scene", "mitsuba_sensor"]

HALL_XML = "modern-hall/scene.xml"
GLASS_STAND_IN = (0.75, 0.8, 0.82)
DEFAULT_REFLECTANCE = (0.5, 0.5, 0.5)  # Mitsuba's default diffuse reflectance

# Mitsuba's camera frame: looks down +z, +y up, +x to the image's left. Ours: looks down -z, +y up,
# +x right. Turning 180 degrees about y maps one onto the other (a rotation, so no mirroring).
MITSUBA_TO_OUR_CAMERA = np.diag([-1.0, 1.0, -1.0, 1.0])


def _floats(text: str | None, where: str) -> np.ndarray:
    try:
        return np.array([float(v) for v in (text or "").replace(",", " ").split()], dtype=np.float64)
    except ValueError:
        raise SceneError(f"{where}: not a list of numbers: {text!r}") from None


def _transform(element: ET.Element | None, where: str) -> np.ndarray:
    """A Mitsuba <transform>: its children apply in document order, each after the previous ones."""
    matrix = np.eye(4)
    if element is None:
        return matrix
    for op in element:
        kind = op.tag
        if kind == "matrix":
            values = _floats(op.get("value"), f"{where}: matrix")
            if values.size != 16:
                raise SceneError(f"{where}: matrix needs 16 values, got {values.size}")
            step = values.reshape(4, 4)
        elif kind == "translate":
            step = translation_matrix([float(op.get(a, 0.0)) for a in "xyz"])
        elif kind == "scale":
            if op.get("value") is not None:
                step = scale_matrix(float(op.get("value")))
            else:
                step = scale_matrix([float(op.get(a, 1.0)) for a in "xyz"])
        elif kind == "rotate":
            axis = np.array([float(op.get(a, 0.0)) for a in "xyz"])
            angle = float(op.get("angle", 0.0))
            step = _axis_angle(axis, angle)
        elif kind == "lookat":
            origin = _floats(op.get("origin"), f"{where}: lookat origin")
            target = _floats(op.get("target"), f"{where}: lookat target")
            up = _floats(op.get("up", "0 1 0"), f"{where}: lookat up")
            forward = (target - origin) / np.linalg.norm(target - origin)
            left = np.cross(up, forward)
            left /= np.linalg.norm(left)
            step = np.eye(4)
            step[:3, 0], step[:3, 1], step[:3, 2], step[:3, 3] = left, np.cross(forward, left), forward, origin
        else:
            raise SceneError(f"{where}: unsupported transform element <{kind}>")
        matrix = step @ matrix
    return matrix


def _axis_angle(axis: np.ndarray, angle_deg: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    x, y, z = axis
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    rot = np.array([
        [c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
        [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
        [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)],
    ])
    matrix = np.eye(4)
    matrix[:3, :3] = rot
    return matrix


def _to_world(element: ET.Element, where: str) -> np.ndarray:
    for child in element.findall("transform"):
        if child.get("name") in ("toWorld", "to_world"):
            return _transform(child, where)
    return np.eye(4)


def _named(element: ET.Element, tag: str, name: str) -> ET.Element | None:
    return next((c for c in element.findall(tag) if c.get("name") == name), None)


def _material(bsdf: ET.Element | None, base: Path) -> tuple[tuple[float, float, float], Path | None]:
    """(linear colour, texture path or None) standing in for a Mitsuba bsdf."""
    if bsdf is None:
        return DEFAULT_REFLECTANCE, None
    kind = bsdf.get("type", "")
    if kind in ("twosided", "mask", "bumpmap", "normalmap"):
        return _material(bsdf.find("bsdf"), base)
    for name in ("reflectance", "diffuseReflectance", "diffuse_reflectance", "base_color"):
        texture = _named(bsdf, "texture", name)
        if texture is not None:
            filename = _named(texture, "string", "filename")
            if texture.get("type") == "bitmap" and filename is not None:
                return DEFAULT_REFLECTANCE, base / filename.get("value")
        rgb = _named(bsdf, "rgb", name)
        if rgb is not None:
            value = _floats(rgb.get("value"), f"bsdf {bsdf.get('id')}: {name}")
            return tuple(float(v) for v in np.broadcast_to(value, (3,))), None
    if "conductor" in kind:
        eta = _named(bsdf, "rgb", "eta")
        k = _named(bsdf, "rgb", "k")
        spec = _named(bsdf, "rgb", "specularReflectance")
        if eta is not None and k is not None:
            n_, k_ = _floats(eta.get("value"), "eta"), _floats(k.get("value"), "k")
            fresnel = ((n_ - 1) ** 2 + k_**2) / ((n_ + 1) ** 2 + k_**2)
            if spec is not None:
                fresnel = fresnel * _floats(spec.get("value"), "specularReflectance")
            return tuple(float(v) for v in fresnel), None
        return (0.9, 0.9, 0.9), None
    if "dielectric" in kind:
        return GLASS_STAND_IN, None
    return DEFAULT_REFLECTANCE, None


def mitsuba_sensor(root: ET.Element) -> dict:
    """The sensor as {to_world (4x4), fov_y_deg, width, height}. Mitsuba 0.5's fov is horizontal
    unless fovAxis says otherwise."""
    sensor = root.find("sensor")
    if sensor is None:
        raise SceneError("mitsuba: no <sensor> element")
    film = sensor.find("film")
    width = int(_named(film, "integer", "width").get("value")) if film is not None else 768
    height = int(_named(film, "integer", "height").get("value")) if film is not None else 576
    fov_el = _named(sensor, "float", "fov")
    fov = float(fov_el.get("value")) if fov_el is not None else 45.0
    axis_el = _named(sensor, "string", "fovAxis") or _named(sensor, "string", "fov_axis")
    axis = axis_el.get("value") if axis_el is not None else "x"
    if axis == "smaller":
        axis = "x" if width < height else "y"
    elif axis == "larger":
        axis = "x" if width >= height else "y"
    tan_half = np.tan(np.radians(fov) / 2.0)
    if axis == "x":
        tan_half_y = tan_half * height / width
    elif axis == "y":
        tan_half_y = tan_half
    elif axis == "diagonal":
        tan_half_y = tan_half * height / np.hypot(width, height)
    else:
        raise SceneError(f"mitsuba: unknown fovAxis {axis!r}")
    return {
        "to_world": _to_world(sensor, "sensor"),
        "fov_y_deg": float(np.degrees(2.0 * np.arctan(tan_half_y))),
        "width": width,
        "height": height,
    }


def load_mitsuba_scene(xml_path: Path) -> tuple[Scene, dict]:
    """World-space Scene of the XML's OBJ shapes (in file order), and the sensor (mitsuba_sensor)."""
    try:
        root = ET.parse(xml_path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise SceneError(f"mitsuba: cannot read {xml_path}: {exc}") from None
    base = xml_path.parent
    bsdfs = {b.get("id"): b for b in root.findall("bsdf") if b.get("id")}
    texture_cache: dict[Path, int] = {}
    textures: list[np.ndarray] = []
    parts = []
    for index, shape in enumerate(root.findall("shape")):
        if shape.get("type") != "obj":
            continue  # emitter disks/rectangles
        where = f"{xml_path.name}: shape {index}"
        filename = _named(shape, "string", "filename")
        if filename is None:
            raise SceneError(f"{where}: obj shape without a filename")
        ref = shape.find("ref")
        if ref is not None:
            if ref.get("id") not in bsdfs:
                raise SceneError(f"{where}: unknown bsdf id {ref.get('id')!r}")
            bsdf = bsdfs[ref.get("id")]
        else:
            bsdf = shape.find("bsdf")
        color, texture_path = _material(bsdf, base)
        mesh_path = base / filename.get("value")
        mesh = load_mesh(mesh_path, color=color, name=mesh_path.stem)
        mesh = mesh.transformed(_to_world(shape, where))
        if texture_path is not None and mesh.uvs is not None:
            if texture_path not in texture_cache:
                texture_cache[texture_path] = len(textures)
                textures.append(load_texture(texture_path))
            tex_id = texture_cache[texture_path]
            mesh.colors = sample_bilinear(textures[tex_id], mesh.uvs)[..., :3]
            mesh.texture_ids = np.full(mesh.n_triangles, tex_id, dtype=np.int32)
        else:
            mesh.texture_ids = np.full(mesh.n_triangles, -1, dtype=np.int32)
        parts.append(mesh)
    if not parts:
        raise SceneError(f"mitsuba: no obj shapes in {xml_path}")
    uvs = np.concatenate([p.uvs if p.uvs is not None else np.zeros((p.n_triangles, 3, 2), np.float32) for p in parts])
    scene = Scene(
        positions=np.concatenate([p.positions for p in parts]),
        positions_t1=np.concatenate([p.positions_t1 for p in parts]),
        colors=np.concatenate([p.colors for p in parts]),
        uvs=uvs,
        textures=textures,
        texture_ids=np.concatenate([p.texture_ids for p in parts]),
        name=xml_path.parent.name,
    )
    return scene, mitsuba_sensor(root)


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
    return load_mitsuba_scene(asset_path(HALL_XML))


@register_scene("modern_hall")
def modern_hall(
    *,
    camera_space: bool = True,
    width: int = 640,
    focus_distance: float | None = None,
) -> Scene:
    """Bitterli's "Modern Hall" (19 OBJs, 30,911 triangles incl. 2,432 zero-area) seen from its sensor."""
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
    return scene.with_camera_hint(**hint)
