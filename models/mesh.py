"""Mesh files (OBJ, PLY, glTF, ... through trimesh) -> Scene, keeping UVs and texture images."""
from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .scene import Scene, SceneError, as_linear_texture, srgb_to_linear
from .textures import image_to_linear, load_texture, sample_bilinear

if TYPE_CHECKING:  # trimesh and PIL are imported where a mesh file is read
    import trimesh
    from PIL import Image

__all__ = ["load_mesh", "ASSETS_DIR", "asset_path"]

ASSETS_DIR = Path(__file__).resolve().parent / "assets"

_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")


def asset_path(relative: str) -> Path:
    """Path of a file under models/assets/ (the bundled meshes; see models/assets/README.md)."""
    return ASSETS_DIR / relative


def _material_image(material: Any) -> Image.Image | None:
    """The colour texture of a trimesh material, or None. trimesh gives a mesh that has UVs but no
    material a 2x2 single-colour placeholder image; that one is treated as no texture."""
    from PIL import Image

    image = getattr(material, "image", None)  # SimpleMaterial (OBJ/MTL)
    if image is None:
        image = getattr(material, "baseColorTexture", None)  # PBRMaterial (glTF)
    if not isinstance(image, Image.Image):
        return None
    if image.size[0] <= 2 and image.size[1] <= 2:
        pixels = np.asarray(image.convert("RGBA")).reshape(-1, 4)
        if (pixels == pixels[0]).all():
            return None
    return image


def _material_color(material: Any) -> np.ndarray | None:
    """Linear RGB diffuse colour of a material without a texture image (MTL Kd / glTF baseColorFactor)."""
    rgba = getattr(material, "diffuse", None)
    if rgba is None:
        rgba = getattr(material, "baseColorFactor", None)
    if rgba is None:
        return None
    rgba = np.asarray(rgba, dtype=np.float32).reshape(-1)
    if rgba.size < 3:
        return None
    encoded = rgba[:3] / 255.0 if rgba.dtype.kind in "iu" or rgba.max() > 1.0 else rgba[:3]
    return srgb_to_linear(np.clip(encoded, 0.0, 1.0))


def _sibling_texture(path: Path) -> Path | None:
    """A texture next to a mesh that names none (e.g. spot_triangulated.obj + spot_texture.png)."""
    stems = [path.stem + "_texture", path.stem, path.stem.split("_")[0] + "_texture"]
    for stem in stems:
        for suffix in _IMAGE_SUFFIXES:
            candidate = path.with_name(stem + suffix)
            if candidate.is_file():
                return candidate
    return None


def _read_geometries(path: Path) -> list[trimesh.Trimesh]:
    import trimesh  # only a mesh file needs it (a built-in scene reads none)

    try:
        # Warnings during parsing mean trimesh read only part of the file: treat them as errors.
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            loaded = trimesh.load_scene(str(path), process=False)
            geometries = loaded.dump(concatenate=False)
    except Exception as exc:  # trimesh raises many kinds on bad input; the user needs path + reason
        raise SceneError(f"mesh: cannot read {path}: {type(exc).__name__}: {exc}") from None
    meshes = [g for g in geometries if isinstance(g, trimesh.Trimesh) and len(g.faces) > 0]
    if not meshes:
        raise SceneError(f"mesh: no triangles in {path} (empty file, point cloud, or not a mesh)")
    return meshes


def load_mesh(
    path: str | Path,
    *,
    color: Any = None,
    name: str | None = None,
    texture: str | Path | np.ndarray | None = None,
) -> Scene:
    """Load a mesh file as a static Scene in the file's own coordinates.

    UVs are kept when the file has them, and the material's image becomes a texture (sRGB-decoded to
    linear float32). A textured OBJ without a material file picks up a sibling image named
    <stem>_texture.png, <stem>.png or <first word of stem>_texture.png (spot_texture.png for
    spot_triangulated.obj); texture= gives the image explicitly (path or array).
    Per-vertex colours: color if given; else the texture bilinearly sampled at each vertex's UV (so
    pictures show the texture before the engine textures); else the file's vertex/face colours or
    material colour; else 0.8 grey. Errors (missing file, garbage, no triangles) raise SceneError.
    """
    path = Path(path)
    if not path.exists():
        raise SceneError(f"mesh: file not found: {path}")
    if not path.is_file():
        raise SceneError(f"mesh: not a file: {path}")
    explicit_texture = None
    if texture is not None:
        if isinstance(texture, (str, Path)):
            explicit_texture = load_texture(texture)
        else:
            explicit_texture = as_linear_texture("texture", texture)

    textures: list[np.ndarray] = []
    image_ids: dict[int, int] = {}  # id(PIL image) -> index in textures
    parts = []  # (positions, colors, uvs | None, texture_ids)
    for geometry in _read_geometries(path):
        faces = np.asarray(geometry.faces)
        positions = np.asarray(geometry.vertices, dtype=np.float64)[faces]
        n = len(faces)
        visual = geometry.visual
        uv = getattr(visual, "uv", None) if getattr(visual, "kind", None) == "texture" else None
        uvs = None
        if uv is not None and len(uv) == len(geometry.vertices):
            uvs = np.asarray(uv, dtype=np.float64)[faces]
        material = getattr(visual, "material", None)

        image_index = -1
        if uvs is not None:
            image = _material_image(material)
            if explicit_texture is not None:
                image_index = image_ids.setdefault(-1, len(textures))
                if image_index == len(textures):
                    textures.append(explicit_texture)
            elif image is not None:
                image_index = image_ids.setdefault(id(image), len(textures))
                if image_index == len(textures):
                    textures.append(image_to_linear(image))
            else:
                sibling = _sibling_texture(path)
                if sibling is not None:
                    image_index = image_ids.setdefault(-2, len(textures))
                    if image_index == len(textures):
                        textures.append(load_texture(sibling))
        elif explicit_texture is not None:
            raise SceneError(f"mesh: texture given but {path} has no UVs")

        colors = None
        if color is None:
            if image_index >= 0:
                colors = sample_bilinear(textures[image_index], uvs)[..., :3]
            elif getattr(visual, "kind", None) == "vertex":
                colors = srgb_to_linear(np.asarray(visual.vertex_colors)[faces][..., :3] / 255.0)
            elif getattr(visual, "kind", None) == "face":
                per_face = srgb_to_linear(np.asarray(visual.face_colors)[:, :3] / 255.0)
                colors = np.repeat(per_face[:, None, :], 3, axis=1)
            elif material is not None and getattr(material, "image", None) is None:
                # a real material without an image (trimesh's placeholder always has one)
                colors = _material_color(material)
        parts.append((positions, colors, uvs, np.full(n, image_index, dtype=np.int32)))

    any_uvs = any(p[2] is not None for p in parts)
    try:
        scenes = [
            Scene.from_arrays(
                positions,
                colors=color if color is not None else colors,
                uvs=uvs if uvs is not None else (np.zeros((len(positions), 3, 2)) if any_uvs else None),
                textures=textures,
                texture_ids=ids,
                name=name or path.stem,
            )
            for positions, colors, uvs, ids in parts
        ]
    except SceneError as exc:
        raise SceneError(f"mesh: {path}: {exc}") from None
    if len(scenes) == 1:
        return scenes[0]
    # Each part already indexes the shared texture list, so merge without Scene.concat's remapping.
    return Scene(
        positions=np.concatenate([s.positions for s in scenes]),
        positions_t1=np.concatenate([s.positions_t1 for s in scenes]),
        colors=np.concatenate([s.colors for s in scenes]),
        uvs=np.concatenate([s.uvs for s in scenes]) if any_uvs else None,
        textures=textures,
        texture_ids=np.concatenate([s.texture_ids for s in scenes]),
        name=name or path.stem,
    )
