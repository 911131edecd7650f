"""Mitsuba 0.5 / 2 / 3 XML scenes -> Scene (``models.load("scene.xml")``).

What is imported:
- shapes ``obj``, ``ply`` (mesh files, through trimesh) and ``rectangle``, ``disk``, ``cube``, ``sphere``
  (tessellated here), each with its ``toWorld``/``to_world`` transform (``matrix``, ``translate``,
  ``rotate``, ``scale``, ``lookat``, applied in document order);
- materials become per-vertex colours and textures: a ``bitmap`` reflectance / base colour texture ->
  the texture (sRGB-decoded) and colours sampled from it at the UVs; an ``rgb``/``float`` reflectance
  -> that colour; a conductor -> its normal-incidence Fresnel reflectance ((n-1)^2 + k^2) /
  ((n+1)^2 + k^2); a dielectric (glass) -> a pale grey stand-in (the rasterizer has no transparency);
  ``twosided``/``mask``/``bumpmap``/``normalmap`` wrappers -> their inner material;
- the ``perspective``/``thinlens`` sensor -> the scene's camera hint (eye, target, up, vertical field of
  view, film size, focus distance, near plane), so ``sim.Camera(**scene.camera_hint)`` sees what the
  sensor saw;
- Mitsuba 3 ``<default name=.. value=..>`` parameters and ``$name`` references.

Everything else (emitters and emitter shapes unless ``include_emitters``, instances, ``serialized``
and other shape types, media, includes, non-bitmap textures, approximated materials) is listed in one
:class:`SceneImportWarning` per file: never dropped silently.
"""
from __future__ import annotations

import re
import warnings
import xml.etree.ElementTree as ET
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .geometry import scale_matrix, translation_matrix
from .mesh import load_mesh
from .scene import Scene, SceneError
from .textures import load_texture, sample_bilinear

__all__ = ["load_mitsuba", "read_mitsuba", "mitsuba_sensor", "sensor_camera_hint", "SceneImportWarning",
           "ImportReport"]

GLASS_STAND_IN = (0.75, 0.8, 0.82)
DEFAULT_REFLECTANCE = (0.5, 0.5, 0.5)  # Mitsuba's default diffuse reflectance
MESH_SHAPES = ("obj", "ply")
PRIMITIVE_SHAPES = ("rectangle", "disk", "cube", "sphere")
# Top-level elements that describe rendering, not the scene's content: read nothing, report nothing.
RENDER_ONLY = ("integrator", "default")


class SceneImportWarning(UserWarning):
    """A scene file held elements the importer leaves out or approximates (listed in the message)."""


@dataclass
class ImportReport:
    """What an importer left out ("skipped") or approximated, counted by description."""

    skipped: Counter = field(default_factory=Counter)
    approximated: Counter = field(default_factory=Counter)

    def text(self) -> str:
        def fmt(c: Counter) -> str:
            return "; ".join(f"{what}" + (f" (x{n})" if n > 1 else "") for what, n in sorted(c.items()))

        parts = []
        if self.skipped:
            parts.append("not imported: " + fmt(self.skipped))
        if self.approximated:
            parts.append("approximated: " + fmt(self.approximated))
        return ". ".join(parts)

    def warn(self, path: Path, stacklevel: int = 3) -> None:
        if self.skipped or self.approximated:
            warnings.warn(f"{path}: {self.text()}", SceneImportWarning, stacklevel=stacklevel)


# ---- XML helpers ---------------------------------------------------------------------------------

def _floats(text: str | None, where: str) -> np.ndarray:
    try:
        return np.array([float(v) for v in (text or "").replace(",", " ").split()], dtype=np.float64)
    except ValueError:
        raise SceneError(f"{where}: not a list of numbers: {text!r}") from None


def _named(element: ET.Element, tag: str, name: str) -> ET.Element | None:
    return next((c for c in element.findall(tag) if c.get("name") == name), None)


def _named_any(element: ET.Element, tag: str, *names: str) -> ET.Element | None:
    for name in names:
        found = _named(element, tag, name)
        if found is not None:
            return found
    return None


def _expand_includes(root: ET.Element, base: Path, where: Path, depth: int = 0) -> None:
    """Replace every <include filename=".."/> by the children of the file it names (relative to the
    including file), recursively."""
    if depth > 16:
        raise SceneError(f"mitsuba: {where}: <include> nested more than 16 deep (a cycle?)")
    for index, element in reversed(list(enumerate(root))):
        if element.tag != "include":
            continue
        path = base / element.get("filename", "")
        try:
            included = ET.parse(path).getroot()
        except (OSError, ET.ParseError) as exc:
            raise SceneError(f"mitsuba: {where}: <include filename={element.get('filename')!r}>: {exc}") from None
        _expand_includes(included, path.parent, path, depth + 1)
        root.remove(element)
        for offset, child in enumerate(list(included)):
            root.insert(index + offset, child)


def _spectrum_rgb(text: str, where: str) -> tuple[np.ndarray, bool]:
    """(linear RGB, exact) of a Mitsuba <spectrum> value: one number (grey, exact) or
    wavelength:value pairs averaged over 400-500 / 500-600 / 600-700 nm (an approximation)."""
    text = (text or "").strip()
    if ":" not in text:
        value = _floats(text, where)
        return np.broadcast_to(value[:1], (3,)).copy(), True
    try:
        pairs = np.array([[float(a) for a in item.split(":")] for item in text.split(",") if item.strip()])
    except ValueError:
        raise SceneError(f"{where}: not a spectrum: {text!r}") from None
    lam, val = pairs[:, 0], pairs[:, 1]
    rgb = []
    for lo, hi in ((600, 700), (500, 600), (400, 500)):
        grid = np.linspace(lo, hi, 21)
        rgb.append(float(np.interp(grid, lam, val).mean()))
    return np.array(rgb), False


def _substitute_defaults(root: ET.Element, overrides: dict | None = None) -> None:
    """Mitsuba 3 parameters: <default name="n" value="v"/> and "$n" in any attribute."""
    values = {d.get("name"): d.get("value") for d in root.iter("default") if d.get("name")}
    values.update({k: str(v) for k, v in (overrides or {}).items()})
    if not values:
        return
    pattern = re.compile(r"\$(\w+)")
    for element in root.iter():
        for key, text in element.attrib.items():
            if "$" in text:
                element.set(key, pattern.sub(lambda m: values.get(m.group(1), m.group(0)), text))


def _vector(op: ET.Element, default: float, where: str) -> np.ndarray:
    """x/y/z attributes, or a value="x y z" (Mitsuba 3) or a single value for all three."""
    if op.get("value") is not None:
        values = _floats(op.get("value"), where)
        if values.size == 1:
            return np.repeat(values, 3)
        if values.size != 3:
            raise SceneError(f"{where}: expected 1 or 3 values, got {op.get('value')!r}")
        return values
    return np.array([float(op.get(a, default)) for a in "xyz"])


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


def _transform(element: ET.Element | None, where: str) -> np.ndarray:
    """A Mitsuba <transform>: its children apply in document order, each after the previous ones."""
    matrix = np.eye(4)
    if element is None:
        return matrix
    for op in element:
        kind = op.tag
        if kind == "matrix":
            values = _floats(op.get("value"), f"{where}: matrix")
            if values.size == 9:
                step = np.eye(4)
                step[:3, :3] = values.reshape(3, 3)
            elif values.size == 16:
                step = values.reshape(4, 4)
            else:
                raise SceneError(f"{where}: matrix needs 9 or 16 values, got {values.size}")
        elif kind == "translate":
            if op.get("value") is None:
                step = translation_matrix([float(op.get(a, 0.0)) for a in "xyz"])
            else:
                step = translation_matrix(_vector(op, 0.0, f"{where}: translate"))
        elif kind == "scale":
            if op.get("value") is not None:
                values = _floats(op.get("value"), f"{where}: scale")
                step = scale_matrix(float(values[0]) if values.size == 1 else values)
            else:
                step = scale_matrix([float(op.get(a, 1.0)) for a in "xyz"])
        elif kind == "rotate":
            axis = _vector(op, 0.0, f"{where}: rotate axis")
            if not np.any(axis):
                raise SceneError(f"{where}: rotate needs a non-zero axis")
            step = _axis_angle(axis, float(op.get("angle", 0.0)))
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


def _to_world(element: ET.Element, where: str) -> np.ndarray:
    for child in element.findall("transform"):
        if child.get("name") in ("toWorld", "to_world"):
            return _transform(child, where)
    return np.eye(4)


# ---- materials -----------------------------------------------------------------------------------

_COLOR_NAMES = ("reflectance", "diffuseReflectance", "diffuse_reflectance", "base_color", "baseColor")


def _material(bsdf: ET.Element | None, base: Path, ids: dict, report: ImportReport | None = None
              ) -> tuple[tuple[float, float, float], Path | None]:
    """(linear colour, texture path or None) standing in for a Mitsuba bsdf."""
    report = report if report is not None else ImportReport()
    if bsdf is None:
        return DEFAULT_REFLECTANCE, None
    if bsdf.tag == "ref":
        target = ids.get(bsdf.get("id"))
        if target is None:
            raise SceneError(f"unknown bsdf id {bsdf.get('id')!r}")
        bsdf = target
    kind = bsdf.get("type", "")
    if kind in ("twosided", "mask", "bumpmap", "normalmap"):
        inner = bsdf.find("bsdf")
        if inner is None:
            inner = next((r for r in bsdf.findall("ref") if r.get("id") in ids), None)
        return _material(inner, base, ids, report)
    for name in _COLOR_NAMES:
        texture = _named(bsdf, "texture", name)
        if texture is None:
            ref = _named(bsdf, "ref", name)
            if ref is not None and ids.get(ref.get("id")) is not None and ids[ref.get("id")].tag == "texture":
                texture = ids[ref.get("id")]
        if texture is not None:
            filename = _named(texture, "string", "filename")
            if texture.get("type") == "bitmap" and filename is not None:
                return DEFAULT_REFLECTANCE, base / filename.get("value")
            report.approximated[f"<texture type={texture.get('type')!r}> as Mitsuba's default grey"] += 1
            return DEFAULT_REFLECTANCE, None
        rgb = _named(bsdf, "rgb", name)
        if rgb is None:
            rgb = _named(bsdf, "float", name)
        if rgb is not None:
            value = _floats(rgb.get("value"), f"bsdf {bsdf.get('id')}: {name}")
            return tuple(float(v) for v in np.broadcast_to(value, (3,))), None
        spectrum = _named(bsdf, "spectrum", name)
        if spectrum is not None:
            rgb, exact = _spectrum_rgb(spectrum.get("value"), f"bsdf {bsdf.get('id')}: {name}")
            if not exact:
                report.approximated["spectral reflectance as its 400-500/500-600/600-700 nm band means"] += 1
            return tuple(float(v) for v in rgb), None
    if "conductor" in kind:
        eta = _named(bsdf, "rgb", "eta")
        k = _named(bsdf, "rgb", "k")
        spec = _named_any(bsdf, "rgb", "specularReflectance", "specular_reflectance")
        if eta is not None and k is not None:
            n_, k_ = _floats(eta.get("value"), "eta"), _floats(k.get("value"), "k")
            fresnel = ((n_ - 1) ** 2 + k_**2) / ((n_ + 1) ** 2 + k_**2)
            if spec is not None:
                fresnel = fresnel * _floats(spec.get("value"), "specularReflectance")
            return tuple(float(v) for v in fresnel), None
        return (0.9, 0.9, 0.9), None
    if "dielectric" in kind:
        report.approximated["dielectric bsdf (glass) as an opaque pale grey"] += 1
        return GLASS_STAND_IN, None
    return DEFAULT_REFLECTANCE, None


# ---- sensor --------------------------------------------------------------------------------------

def mitsuba_sensor(root: ET.Element) -> dict:
    """The sensor as {to_world (4x4), fov_y_deg, width, height[, focus_distance, near,
    aperture_radius]}. Mitsuba's fov is horizontal unless fovAxis/fov_axis says otherwise."""
    sensor = root.find("sensor")
    if sensor is None:
        raise SceneError("mitsuba: no <sensor> element")
    film = sensor.find("film")
    width_el = _named(film, "integer", "width") if film is not None else None
    height_el = _named(film, "integer", "height") if film is not None else None
    width = int(width_el.get("value")) if width_el is not None else 768
    height = int(height_el.get("value")) if height_el is not None else 576
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
    out = {
        "type": sensor.get("type", "perspective"),
        "to_world": _to_world(sensor, "sensor"),
        "fov_y_deg": float(np.degrees(2.0 * np.arctan(tan_half_y))),
        "width": width,
        "height": height,
    }
    for key, names in (("focus_distance", ("focusDistance", "focus_distance")),
                       ("near", ("nearClip", "near_clip")),
                       ("aperture_radius", ("apertureRadius", "aperture_radius"))):
        el = _named_any(sensor, "float", *names)
        if el is not None:
            out[key] = float(el.get("value"))
    return out


def sensor_camera_hint(sensor: dict, report: ImportReport | None = None) -> dict:
    """A camera hint (sim.Camera keywords) for a sensor in world space: eye, target, up, the vertical
    field of view, the film size, and the focus distance and near plane when the sensor gives them."""
    to_world = sensor["to_world"]
    eye = to_world[:3, 3]
    forward = to_world[:3, 2] / np.linalg.norm(to_world[:3, 2])
    up = to_world[:3, 1] / np.linalg.norm(to_world[:3, 1])
    if np.linalg.det(to_world[:3, :3]) < 0 and report is not None:
        report.approximated["a mirrored sensor transform (negative determinant) as unmirrored"] += 1
    hint = {"width": sensor["width"], "height": sensor["height"], "fov_y_deg": sensor["fov_y_deg"],
            "eye": tuple(float(v) for v in eye), "target": tuple(float(v) for v in eye + forward),
            "up": tuple(float(v) for v in up)}
    for key in ("focus_distance", "near"):
        if sensor.get(key, 0) > 0:
            hint[key] = sensor[key]
    if sensor.get("aperture_radius") and report is not None:
        report.approximated[f"thin-lens aperture radius {sensor['aperture_radius']:g} left to the config "
                            "(camera.aperture_radius)"] += 1
    if sensor["type"] not in ("perspective", "thinlens") and report is not None:
        report.approximated[f"<sensor type={sensor['type']!r}> as a perspective camera"] += 1
    return hint


# ---- shapes --------------------------------------------------------------------------------------

def _primitive(kind: str, shape: ET.Element, where: str) -> Scene:
    """A built-in Mitsuba shape in its object space, as triangles with UVs."""
    if kind == "rectangle":
        quad = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float64)
        uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64)
        faces = np.array([[0, 1, 2], [0, 2, 3]])
        return Scene.from_arrays(quad[faces], uvs=uv[faces], name=kind)
    if kind == "disk":
        n = 64
        angle = np.linspace(0.0, 2 * np.pi, n + 1)
        ring = np.stack([np.cos(angle), np.sin(angle), np.zeros_like(angle)], axis=1)
        centre = np.zeros((n, 3))
        positions = np.stack([centre, ring[:-1], ring[1:]], axis=1)
        uvs = (positions[..., :2] + 1.0) / 2.0
        return Scene.from_arrays(positions, uvs=uvs, name=kind)
    if kind == "cube":
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
        faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
        return Scene.from_arrays(corners[faces], name=kind)
    if kind == "sphere":
        centre_el = _named(shape, "point", "center")
        centre = _vector(centre_el, 0.0, f"{where}: center") if centre_el is not None else np.zeros(3)
        radius_el = _named(shape, "float", "radius")
        radius = float(radius_el.get("value")) if radius_el is not None else 1.0
        n_theta, n_phi = 24, 48
        theta = np.linspace(0.0, np.pi, n_theta + 1)
        phi = np.linspace(0.0, 2 * np.pi, n_phi + 1)
        grid = np.stack([np.sin(theta)[:, None] * np.cos(phi)[None, :],
                         np.sin(theta)[:, None] * np.sin(phi)[None, :],
                         np.cos(theta)[:, None] * np.ones_like(phi)[None, :]], axis=-1) * radius + centre
        uv = np.stack(np.meshgrid(phi / (2 * np.pi), 1.0 - theta / np.pi), axis=-1)
        tris, tuv = [], []
        for i in range(n_theta):
            for j in range(n_phi):
                a, b, c, d = (i, j), (i, j + 1), (i + 1, j), (i + 1, j + 1)
                for tri in ((a, c, d), (a, d, b)):
                    tris.append([grid[p] for p in tri])
                    tuv.append([uv[p] for p in tri])
        positions = np.array(tris)
        keep = np.linalg.norm(np.cross(positions[:, 1] - positions[:, 0], positions[:, 2] - positions[:, 0]),
                              axis=1) > 0  # the pole rows' collapsed triangles
        return Scene.from_arrays(positions[keep], uvs=np.array(tuv)[keep], name=kind)
    raise AssertionError(kind)


def _shape_bsdf(shape: ET.Element, ids: dict) -> ET.Element | None:
    inline = shape.find("bsdf")
    if inline is not None:
        return inline
    refs = [r for r in shape.findall("ref") if r.get("name") in (None, "bsdf")]
    return next((r for r in refs if r.get("id") in ids), refs[0] if refs and refs[0].get("name") == "bsdf" else None)


def read_mitsuba(xml_path: str | Path, *, include_emitters: bool = False, parameters: dict | None = None
                 ) -> tuple[Scene, dict, ImportReport]:
    """(world-space Scene of the XML's shapes in file order, the sensor (mitsuba_sensor) or None,
    the ImportReport of what was left out or approximated). The Scene has no camera hint."""
    xml_path = Path(xml_path)
    try:
        root = ET.parse(xml_path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise SceneError(f"mitsuba: cannot read {xml_path}: {exc}") from None
    if root.tag != "scene":
        raise SceneError(f"mitsuba: {xml_path}: the root element is <{root.tag}>, expected <scene>")
    base = xml_path.parent
    _expand_includes(root, base, xml_path)
    _substitute_defaults(root, parameters)
    report = ImportReport()
    ids = {e.get("id"): e for e in root if e.get("id") and e.tag in ("bsdf", "texture")}
    emitter_ids = {e.get("id") for e in root if e.get("id") and e.tag == "emitter"}
    texture_cache: dict[Path, int] = {}
    textures: list[np.ndarray] = []
    parts = []
    for element in root:
        if element.tag in RENDER_ONLY or element.tag in ("bsdf", "texture", "sensor"):
            continue
        if element.tag == "emitter":
            if element.get("id") in emitter_ids and any(
                    r.get("id") == element.get("id") for sh in root.findall("shape") for r in sh.findall("ref")):
                continue  # a shape's area light: reported with its shape
            report.skipped[f"<emitter type={element.get('type')!r}> (lighting is not modelled)"] += 1
            continue
        if element.tag != "shape":
            report.skipped[f"<{element.tag}" + (f" type={element.get('type')!r}" if element.get("type") else "")
                           + ">"] += 1
            continue
        shape = element
        kind = shape.get("type", "")
        index = len(parts)
        where = f"{xml_path.name}: shape {kind!r} #{index}"
        is_emitter = shape.find("emitter") is not None or any(r.get("id") in emitter_ids for r in shape.findall("ref"))
        if is_emitter and not include_emitters:
            report.skipped[f"emitter <shape type={kind!r}> (area light; include_emitters=True keeps it)"] += 1
            continue
        if kind not in MESH_SHAPES + PRIMITIVE_SHAPES:
            report.skipped[f"<shape type={kind!r}>"] += 1
            continue
        try:
            color, texture_path = _material(_shape_bsdf(shape, ids), base, ids, report)
        except SceneError as exc:
            raise SceneError(f"{where}: {exc}") from None
        if kind in MESH_SHAPES:
            filename = _named(shape, "string", "filename")
            if filename is None:
                raise SceneError(f"{where}: {kind} shape without a filename")
            mesh_path = base / filename.get("value")
            mesh = load_mesh(mesh_path, color=color, name=mesh_path.stem)
        else:
            mesh = _primitive(kind, shape, where).with_color(color)
        mesh = mesh.transformed(_to_world(shape, where))
        if texture_path is not None and mesh.uvs is not None:
            if texture_path not in texture_cache:
                texture_cache[texture_path] = len(textures)
                textures.append(load_texture(texture_path))
            tex_id = texture_cache[texture_path]
            mesh.colors = sample_bilinear(textures[tex_id], mesh.uvs)[..., :3]
            mesh.texture_ids = np.full(mesh.n_triangles, tex_id, dtype=np.int32)
        else:
            if texture_path is not None:
                report.approximated[f"texture {texture_path.name} on a shape without UVs as grey"] += 1
            mesh.texture_ids = np.full(mesh.n_triangles, -1, dtype=np.int32)
        parts.append(mesh)
    if not parts:
        raise SceneError(f"mitsuba: no shapes to import in {xml_path}"
                         + (f" ({report.text()})" if report.skipped else ""))
    uvs = np.concatenate([p.uvs if p.uvs is not None else np.zeros((p.n_triangles, 3, 2), np.float32) for p in parts])
    scene = Scene(
        positions=np.concatenate([p.positions for p in parts]),
        positions_t1=np.concatenate([p.positions_t1 for p in parts]),
        colors=np.concatenate([p.colors for p in parts]),
        uvs=uvs,
        textures=textures,
        texture_ids=np.concatenate([p.texture_ids for p in parts]),
        name=xml_path.parent.name if xml_path.stem == "scene" else xml_path.stem,
    )
    sensor = mitsuba_sensor(root) if root.find("sensor") is not None else None
    return scene, sensor, report


def load_mitsuba(xml_path: str | Path, *, include_emitters: bool = False, parameters: dict | None = None,
                 warn: bool = True) -> Scene:
    """A Mitsuba XML scene in world space, its sensor as the camera hint (or, without a sensor, a view
    framing its bounding box). What was left out or approximated is one SceneImportWarning."""
    from .framing import frame_hint

    scene, sensor, report = read_mitsuba(xml_path, include_emitters=include_emitters, parameters=parameters)
    if sensor is not None:
        hint = sensor_camera_hint(sensor, report)
    else:
        report.approximated["no <sensor>: the camera frames the bounding box"] += 1
        hint = frame_hint(scene)
    if warn:
        report.warn(Path(xml_path))
    return scene.with_camera_hint(**hint)
