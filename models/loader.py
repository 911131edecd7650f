"""models.load: a named scene, a YAML scene file (configs/scenes/*.yaml) or a mesh file -> Scene.

A YAML scene file lists objects, each either a mesh file or a named scene, with an optional
transform, linear motion and colour. Unknown keys anywhere are errors naming the key and the file.

    name: bunny_on_show                 # optional, default: the file's stem
    objects:
      - mesh: models/assets/stanford-bunny/stanford-bunny.obj   # relative to the YAML file, else the repo root
        transform: {scale: 20, rotate_deg: [0, 30, 0], translate: [0, -2, -4]}   # scale, then rotate, then translate
        motion: {translate: [0.1, 0, 0]}                         # offset at shutter close (t=1)
        color: [0.8, 0.7, 0.6]                                   # linear RGB for every vertex
      - scene: quad                                              # a named scene ...
        params: {size: 8, depth: 10}                             # ... and its parameters
    camera_hint: {width: 512, height: 512, fov_y_deg: 45, focus_distance: 4}
"""
from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Union

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from .geometry import compose, rotation_matrix_deg, scale_matrix, translation_matrix
from .mesh import load_mesh
from .registry import named
from .scene import Scene, SceneError

__all__ = ["load", "load_scene_file", "REPO_ROOT"]

REPO_ROOT = Path(__file__).resolve().parent.parent
MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")
YAML_SUFFIXES = (".yaml", ".yml")

Finite = Annotated[float, Field(allow_inf_nan=False)]
Vec3 = tuple[Finite, Finite, Finite]
NonNegative = Annotated[float, Field(ge=0.0, allow_inf_nan=False)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class TransformSpec(_Strict):
    """Object-to-world transform: scale, then rotate (degrees about x, then y, then z), then translate."""

    translate: Vec3 = (0.0, 0.0, 0.0)
    rotate_deg: Vec3 = (0.0, 0.0, 0.0)
    scale: Union[Annotated[float, Field(gt=0.0, allow_inf_nan=False)], Vec3] = 1.0

    def matrix(self) -> np.ndarray:
        return compose(
            translation_matrix(self.translate), rotation_matrix_deg(self.rotate_deg), scale_matrix(self.scale)
        )


class MotionSpec(_Strict):
    """Linear motion over the shutter: the object is offset by translate at t=1."""

    translate: Vec3 = (0.0, 0.0, 0.0)


class CameraHintSpec(_Strict):
    """Suggested camera; the keys mirror sim.Camera's arguments."""

    width: Annotated[int, Field(gt=0)] | None = None
    height: Annotated[int, Field(gt=0)] | None = None
    fov_y_deg: Annotated[float, Field(gt=0.0, lt=180.0)] | None = None
    focus_distance: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = None
    eye: Vec3 | None = None
    target: Vec3 | None = None
    up: Vec3 | None = None
    near: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = None


class ObjectSpec(_Strict):
    """One object: exactly one of mesh (a file) or scene (a named scene, with params)."""

    mesh: str | None = None
    scene: str | None = None
    params: dict[str, Any] = Field(default_factory=dict)
    transform: TransformSpec | None = None
    motion: MotionSpec | None = None
    color: tuple[NonNegative, NonNegative, NonNegative] | None = None

    @model_validator(mode="after")
    def _one_source(self) -> "ObjectSpec":
        if (self.mesh is None) == (self.scene is None):
            raise ValueError("give exactly one of 'mesh' or 'scene'")
        if self.mesh is not None and self.params:
            raise ValueError("'params' only applies to 'scene' objects")
        return self


class SceneFileSpec(_Strict):
    name: str | None = None
    objects: list[ObjectSpec]
    camera_hint: CameraHintSpec | None = None


class UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that refuses duplicate keys (PyYAML silently keeps the last one)."""


def _construct_mapping(loader: UniqueKeyLoader, node: yaml.MappingNode, deep: bool = False) -> dict:
    seen = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if not isinstance(key, (str, int, float, bool, type(None))):
            continue  # construct_mapping reports unhashable keys itself
        if key in seen:
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key {key!r}", key_node.start_mark
            )
        seen.add(key)
    return loader.construct_mapping(node, deep=deep)


UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def _format_location(loc: tuple) -> str:
    text = ""
    for part in loc:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text or "(top level)"


def _validation_error(path: Path, exc: ValidationError) -> SceneError:
    lines = []
    for error in exc.errors():
        loc = tuple(p for p in error["loc"] if not (isinstance(p, str) and p.startswith("function-")))
        if error["type"] == "extra_forbidden":
            where = _format_location(loc[:-1])
            lines.append(f"unknown key {loc[-1]!r} in {where}")
        else:
            lines.append(f"{_format_location(loc)}: {error['msg']}")
    return SceneError(f"{path}: " + "; ".join(lines))


def _resolve(path_text: str, yaml_path: Path, what: str) -> Path:
    candidate = Path(path_text)
    if candidate.is_absolute():
        tried = [candidate]
    else:
        tried = [yaml_path.parent / candidate, REPO_ROOT / candidate]
    for option in tried:
        if option.exists():
            return option
    raise SceneError(f"{yaml_path}: {what}: file not found: {path_text} (tried {', '.join(map(str, tried))})")


def load_scene_file(path: str | Path) -> Scene:
    """Build the Scene a YAML scene file describes (see the module docstring for the format)."""
    path = Path(path)
    if not path.is_file():
        raise SceneError(f"scene file: not found: {path}")
    try:
        with open(path, encoding="utf-8") as stream:
            data = yaml.load(stream, Loader=UniqueKeyLoader)  # noqa: S506 (a SafeLoader subclass)
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        raise SceneError(f"{path}: not valid YAML: {exc}") from None
    if not isinstance(data, dict):
        raise SceneError(f"{path}: expected a mapping with 'objects' at the top level, got {type(data).__name__}")
    try:
        spec = SceneFileSpec.model_validate(data)
    except ValidationError as exc:
        raise _validation_error(path, exc) from None

    parts = []
    for index, obj in enumerate(spec.objects):
        where = f"objects[{index}]"
        try:
            if obj.mesh is not None:
                part = load_mesh(_resolve(obj.mesh, path, f"{where}.mesh"))
            else:
                part = named(obj.scene, **obj.params)
            if obj.transform is not None:
                part = part.transformed(obj.transform.matrix())
            if obj.motion is not None:
                part = part.with_motion(obj.motion.translate)
            if obj.color is not None:
                part = part.with_color(obj.color)
        except SceneError as exc:
            message = str(exc)
            raise SceneError(message if message.startswith(str(path)) else f"{path}: {where}: {message}") from None
        parts.append(part)

    scene = Scene.concat(*parts, name=spec.name or path.stem)
    if spec.camera_hint is not None:
        scene = scene.with_camera_hint(**spec.camera_hint.model_dump(exclude_none=True))
    return scene


def load(name_or_path: str | Path, **overrides: Any) -> Scene:
    """A Scene from a registered name (overrides are its parameters), a YAML scene file (.yaml/.yml,
    no overrides) or a mesh file (.obj/.ply/...; overrides are load_mesh's color/name/texture).
    Relative file paths are tried against the working directory, then the repository root."""
    text = str(name_or_path)
    suffix = Path(text).suffix.lower()
    if isinstance(name_or_path, Path) or suffix in YAML_SUFFIXES + MESH_SUFFIXES:
        path = Path(text)
        if not path.is_absolute() and not path.exists() and (REPO_ROOT / path).exists():
            path = REPO_ROOT / path
        if suffix in YAML_SUFFIXES:
            if overrides:
                raise SceneError(
                    f"{path}: overrides {sorted(overrides)} are not accepted for a scene file; "
                    "put parameters in the file's objects[].params"
                )
            return load_scene_file(path)
        if suffix in MESH_SUFFIXES:
            unknown = sorted(set(overrides) - {"color", "name", "texture"})
            if unknown:
                raise SceneError(f"{path}: unknown mesh option(s) {unknown}; accepted: color, name, texture")
            return load_mesh(path, **overrides)
        raise SceneError(f"{path}: unknown scene file type {suffix!r}; expected {YAML_SUFFIXES + MESH_SUFFIXES}")
    return named(text, **overrides)
