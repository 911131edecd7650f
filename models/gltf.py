"""glTF 2.0 scenes (.gltf, .glb) -> Scene (``models.load("scene.glb")``).

The geometry comes through trimesh (the node hierarchy's transforms applied, base-colour textures
kept with their UVs, base-colour factors as colours); this module reads the glTF's JSON itself for
what trimesh does not carry: the first perspective camera node becomes the camera hint (eye, target,
up, vertical field of view, near plane; glTF cameras look down -z with +y up, as ours), and the
elements left out or approximated are listed in one SceneImportWarning (animations, skins, morph
targets, lights, non-triangle primitives, material textures other than the base colour, blending
and alpha masks, extensions). Without a camera the view frames the bounding box.
"""
from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np

from .framing import frame_hint
from .mesh import load_mesh
from .mitsuba import ImportReport
from .scene import Scene, SceneError

__all__ = ["load_gltf", "read_gltf_json", "gltf_camera_hint", "node_world_matrices"]

TRIANGLES = 4
PRIMITIVE_MODES = {0: "POINTS", 1: "LINES", 2: "LINE_LOOP", 3: "LINE_STRIP", 4: "TRIANGLES",
                   5: "TRIANGLE_STRIP", 6: "TRIANGLE_FAN"}
IGNORED_TEXTURES = ("normalTexture", "occlusionTexture", "emissiveTexture")
# Extensions whose content the import keeps (the texture transform is read by trimesh).
KEPT_EXTENSIONS = ("KHR_texture_transform", "KHR_mesh_quantization", "KHR_materials_unlit")


def read_gltf_json(path: str | Path) -> dict:
    """The JSON document of a .gltf file or of a .glb file's first chunk."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise SceneError(f"gltf: cannot read {path}: {exc}") from None
    try:
        if data[:4] == b"glTF":
            if len(data) < 20:
                raise ValueError("truncated GLB header")
            length, kind = struct.unpack_from("<II", data, 12)
            if kind != 0x4E4F534A:  # "JSON"
                raise ValueError("the first GLB chunk is not JSON")
            return json.loads(data[20:20 + length].decode("utf-8"))
        return json.loads(data.decode("utf-8"))
    except (ValueError, UnicodeDecodeError, struct.error) as exc:
        raise SceneError(f"gltf: {path}: not a glTF document: {exc}") from None


def _node_matrix(node: dict) -> np.ndarray:
    """A node's local matrix: "matrix" (column-major) or translation * rotation * scale."""
    if "matrix" in node:
        return np.asarray(node["matrix"], dtype=np.float64).reshape(4, 4).T
    t = np.asarray(node.get("translation", (0.0, 0.0, 0.0)), dtype=np.float64)
    x, y, z, w = np.asarray(node.get("rotation", (0.0, 0.0, 0.0, 1.0)), dtype=np.float64)
    s = np.asarray(node.get("scale", (1.0, 1.0, 1.0)), dtype=np.float64)
    rot = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    matrix = np.eye(4)
    matrix[:3, :3] = rot * s[None, :]
    matrix[:3, 3] = t
    return matrix


def node_world_matrices(doc: dict) -> dict[int, np.ndarray]:
    """{node index: world matrix} for the nodes of the default scene (or the first)."""
    nodes = doc.get("nodes", [])
    scenes = doc.get("scenes", [])
    if scenes:
        roots = scenes[doc.get("scene", 0)].get("nodes", [])
    else:
        children = {c for n in nodes for c in n.get("children", [])}
        roots = [i for i in range(len(nodes)) if i not in children]
    out: dict[int, np.ndarray] = {}
    stack = [(i, np.eye(4)) for i in roots]
    while stack:
        index, parent = stack.pop()
        if index in out:
            continue
        world = parent @ _node_matrix(nodes[index])
        out[index] = world
        stack.extend((c, world) for c in nodes[index].get("children", []))
    return out


def gltf_camera_hint(doc: dict, report: ImportReport | None = None) -> dict | None:
    """The camera hint of the first perspective camera node of the default scene, or None."""
    cameras = doc.get("cameras", [])
    nodes = doc.get("nodes", [])
    for index, world in sorted(node_world_matrices(doc).items()):
        cam_index = nodes[index].get("camera")
        if cam_index is None:
            continue
        camera = cameras[cam_index]
        if camera.get("type") != "perspective":
            if report is not None:
                report.skipped[f"{camera.get('type')} camera"] += 1
            continue
        persp = camera["perspective"]
        basis = world[:3, :3]
        eye = world[:3, 3]
        forward = basis @ np.array([0.0, 0.0, -1.0])
        up = basis @ np.array([0.0, 1.0, 0.0])
        hint = {"fov_y_deg": float(np.degrees(persp["yfov"])),
                "eye": tuple(float(v) for v in eye),
                "target": tuple(float(v) for v in eye + forward / np.linalg.norm(forward)),
                "up": tuple(float(v) for v in up / np.linalg.norm(up))}
        if persp.get("znear", 0) > 0:
            hint["near"] = float(persp["znear"])
        aspect = persp.get("aspectRatio")
        if aspect:
            hint["width"], hint["height"] = 640, max(1, int(round(640 / float(aspect))))
        return hint
    return None


def _report_unsupported(doc: dict, report: ImportReport) -> None:
    for key, what in (("animations", "animation"), ("skins", "skin")):
        if doc.get(key):
            report.skipped[f"{what}s ({len(doc[key])}; the rest pose is imported)"] += 1
    for mesh in doc.get("meshes", []):
        for prim in mesh.get("primitives", []):
            mode = prim.get("mode", TRIANGLES)
            if mode not in (TRIANGLES, 5, 6):
                report.skipped[f"{PRIMITIVE_MODES.get(mode, mode)} primitives"] += 1
            if prim.get("targets"):
                report.skipped["morph targets (the base shape is imported)"] += 1
    for material in doc.get("materials", []):
        for key in IGNORED_TEXTURES:
            if key in material:
                report.skipped[key] += 1
        pbr = material.get("pbrMetallicRoughness", {})
        if "metallicRoughnessTexture" in pbr:
            report.skipped["metallicRoughnessTexture"] += 1
        if material.get("alphaMode", "OPAQUE") != "OPAQUE":
            report.approximated[f"alphaMode {material['alphaMode']} as opaque"] += 1
    used = set(doc.get("extensionsUsed", []))
    if "KHR_lights_punctual" in used:
        report.skipped["KHR_lights_punctual lights (lighting is not modelled)"] += 1
        used.discard("KHR_lights_punctual")
    for ext in sorted(used - set(KEPT_EXTENSIONS)):
        report.skipped[f"extension {ext}"] += 1


def load_gltf(path: str | Path, *, warn: bool = True, **mesh_options) -> Scene:
    """A glTF/GLB scene in world space with its camera node as the camera hint (else a view framing the
    bounding box). mesh_options go to load_mesh (color, name, texture)."""
    path = Path(path)
    doc = read_gltf_json(path)
    report = ImportReport()
    _report_unsupported(doc, report)
    scene = load_mesh(path, **mesh_options)
    hint = gltf_camera_hint(doc, report)
    if hint is None:
        hint = frame_hint(scene)
    if warn:
        report.warn(path)
    return scene.with_camera_hint(**hint)
