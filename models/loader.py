"""models.load: a named scene, a YAML scene file (configs/scenes/*.yaml) or a mesh file -> Scene.

A YAML scene file lists objects, each either a mesh file or a named scene, with an optional
transform, linear motion and colour. Unknown keys anywhere are errors naming the key and the file.

    name: bunny_on_show                 # optional, default: the file's stem
    objects:
      - mesh: models/assets/stanford-bunny/stanford-bunny.obj   # relative to the YAML file, else the working
                                                                 # directory, else the repository root
        transform: {scale: 20, rotate_deg: [0, 30, 0], translate: [0, -2, -4]}   # scale, then rotate, then translate
        motion: {translate: [0.1, 0, 0]}                         # offset at shutter close (t=1)
        color: [0.8, 0.7, 0.6]                                   # linear RGB for every vertex
      - scene: quad                                              # a named scene ...
        params: {size: 8, depth: 10}                             # ... and its parameters
    camera_hint: {width: 512, height: 512, fov_y_deg: 45, focus_distance: 4}

Without a camera pose (camera_hint eye/target) and without named scenes, the hint frames the meshes'
bounding box (models/framing.py).
"""
from __future__ import annotations

import difflib
from pathlib import Path
from typing import Annotated, Any, Union

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from .geometry import compose, rotation_matrix_deg, scale_matrix, translation_matrix
from .framing import frame_hint, has_pose
from .gltf import load_gltf
from .mesh import load_mesh
from .mitsuba import load_mitsuba
from .registry import named
from .scene import Scene, SceneError

__all__ = ["load", "load_scene_file", "resolve_path", "candidate_paths", "REPO_ROOT"]

REPO_ROOT = Path(__file__).resolve().parent.parent
MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")
GLTF_SUFFIXES = (".glb", ".gltf")
XML_SUFFIXES = (".xml",)
YAML_SUFFIXES = (".yaml", ".yml")

Finite = Annotated[float, Field(allow_inf_nan=False)]
Vec3 = tuple[Finite, Finite, Finite]
NonNegative = Annotated[float, Field(ge=0.0, allow_inf_nan=False)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class TransformSpec(_Strict):
    """Object-to-world transform: scale, then rotate (degrees about x, then y, then z), then translate."""

    translate: Vec3 = Field((0.0, 0.0, 0.0), description="Offset [world units], applied last")
    rotate_deg: Vec3 = Field((0.0, 0.0, 0.0), description="Rotation [deg] about x, then y, then z")
    scale: Union[Annotated[float, Field(gt=0.0, allow_inf_nan=False)], Vec3] = Field(
        1.0, description="Uniform factor (> 0) or per-axis factors, applied first")

    def matrix(self) -> np.ndarray:
        return compose(
            translation_matrix(self.translate), rotation_matrix_deg(self.rotate_deg), scale_matrix(self.scale)
        )


class MotionSpec(_Strict):
    """Linear motion over the shutter: the object is offset by translate at t=1."""

    translate: Vec3 = Field((0.0, 0.0, 0.0), description="Offset at shutter close (t = 1) [world units]")


class CameraHintSpec(_Strict):
    """Suggested camera; the keys mirror sim.Camera's arguments."""

    width: Annotated[int, Field(gt=0)] | None = Field(None, description="Image width [px]")
    height: Annotated[int, Field(gt=0)] | None = Field(None, description="Image height [px]")
    fov_y_deg: Annotated[float, Field(gt=0.0, lt=180.0)] | None = Field(
        None, description="Vertical field of view [deg]")
    focus_distance: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = Field(
        None, description="Distance of the focus plane [world units]")
    eye: Vec3 | None = Field(None, description="Camera position [world]; with target, the camera pose")
    target: Vec3 | None = Field(None, description="Point looked at [world]")
    up: Vec3 | None = Field(None, description="Up direction")
    near: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = Field(
        None, description="Near plane distance [world units]")


class ObjectSpec(_Strict):
    """One object: exactly one of mesh (a file) or scene (a named scene, with params)."""

    mesh: str | None = Field(None, description=(
        "A mesh file (OBJ, PLY, STL, OFF, glTF/GLB): relative to the scene file, else the working directory, "
        "else the repository root"))
    scene: str | None = Field(None, description="A named scene (the table below)")
    params: dict[str, Any] = Field(default_factory=dict, description="The named scene's parameters")
    transform: TransformSpec | None = Field(None, description="Object-to-world transform (section below)")
    motion: MotionSpec | None = Field(None, description="Linear motion over the shutter (section below)")
    color: tuple[NonNegative, NonNegative, NonNegative] | None = Field(
        None, description="Linear RGB for every vertex (replaces the file's colours)")

    @model_validator(mode="after")
    def _one_source(self) -> "ObjectSpec":
        if (self.mesh is None) == (self.scene is None):
            raise ValueError("give exactly one of 'mesh' or 'scene'")
        if self.mesh is not None and self.params:
            raise ValueError("'params' only applies to 'scene' objects")
        return self


class SceneFileSpec(_Strict):
    """A YAML scene file: objects placed in one world, and a suggested camera."""

    name: str | None = Field(None, description="Scene name (default: the file's stem)")
    objects: list[ObjectSpec] = Field(..., description="The objects (section below), concatenated in order")
    camera_hint: CameraHintSpec | None = Field(None, description=(
        "Suggested camera (section below); the config's camera section overrides it. Without eye/target and "
        "without named scenes, the view frames the bounding box"))


class UniqueKeyLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """SafeLoader that refuses duplicate keys (PyYAML silently keeps the last one). It parses with
    libyaml where PyYAML was built with it (CSafeLoader: the same tags and values as SafeLoader, parsed
    about ten times faster), else in Python."""


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


def python_parser_error(text: str) -> yaml.YAMLError | None:
    """The pure-Python parser's error on text (it quotes the offending line under a caret, libyaml's
    does not): for the message of a file UniqueKeyLoader refused; None if it parses."""
    try:
        yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError as e:
        return e
    return None


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
            known = {f for m in (SceneFileSpec, ObjectSpec, TransformSpec, MotionSpec, CameraHintSpec)
                     for f in m.model_fields}
            close = difflib.get_close_matches(str(loc[-1]), sorted(known), n=1, cutoff=0.6)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            lines.append(f"unknown key {loc[-1]!r} in {where}{hint}")
        else:
            lines.append(f"{_format_location(loc)}: {error['msg']}")
    return SceneError(f"{path}: " + "; ".join(lines))


def candidate_paths(path_text: str | Path, *bases: Path) -> list[Path]:
    """The places a relative path is looked for, in order: each base folder, then the working directory,
    then the repository (or installed package) root, without repeats; an absolute path is itself."""
    candidate = Path(path_text)
    if candidate.is_absolute():
        return [candidate]
    out: list[Path] = []
    for base in (*bases, Path.cwd(), REPO_ROOT):
        option = base / candidate
        if option not in out and option.resolve() not in {o.resolve() for o in out}:
            out.append(option)
    return out


def resolve_path(path_text: str | Path, *bases: Path, what: str = "file") -> Path:
    """The first existing candidate_paths(path_text, *bases); SceneError naming every place tried."""
    tried = candidate_paths(path_text, *bases)
    for option in tried:
        if option.exists():
            return option
    raise SceneError(f"{what}: file not found: {path_text} (tried {', '.join(map(str, tried))})")


def _resolve(path_text: str, yaml_path: Path, what: str) -> Path:
    try:
        return resolve_path(path_text, yaml_path.parent, what=what)
    except SceneError as exc:
        raise SceneError(f"{yaml_path}: {exc}") from None


def load_scene_file(path: str | Path) -> Scene:
    """Build the Scene a YAML scene file describes (see the module docstring for the format)."""
    path = Path(path)
    if not path.is_file():
        raise SceneError(f"scene file: not found: {path}")
    try:
        with open(path, encoding="utf-8") as stream:
            text = stream.read()
        data = yaml.load(text, Loader=UniqueKeyLoader)  # noqa: S506 (a SafeLoader subclass)
    except UnicodeDecodeError as exc:
        raise SceneError(f"{path}: not valid YAML: {exc}") from None
    except yaml.YAMLError as exc:
        if not isinstance(exc, yaml.constructor.ConstructorError):
            exc = python_parser_error(text) or exc
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
    if not has_pose(scene.camera_hint) and not any(obj.scene for obj in spec.objects):
        # meshes only and no camera pose: look at them (the default camera may sit inside them)
        framing = frame_hint(scene, fov_y_deg=scene.camera_hint.get("fov_y_deg", 45.0))
        scene = scene.with_camera_hint(**{**framing, **scene.camera_hint})
    return scene


def load(name_or_path: str | Path, **overrides: Any) -> Scene:
    """A Scene from a registered name (overrides are its parameters) or a file:

    - a YAML scene file (.yaml/.yml, no overrides; the format above);
    - a Mitsuba 0.5/2/3 XML scene (.xml; overrides: include_emitters, parameters), its sensor as the
      camera hint (models/mitsuba.py);
    - a glTF 2.0 scene (.gltf/.glb; overrides: color, name, texture) with node transforms, base-colour
      textures and its camera node as the hint (models/gltf.py);
    - a mesh (.obj/.ply/.stl/.off; overrides: load_mesh's color, name, texture, and shading), with a
      camera hint that frames its bounding box (models/framing.py); a mesh without colours is shaded
      by a headlight at that camera (models/shading.py; ``shading="flat"`` keeps one colour).

    Elements an importer leaves out or approximates are listed in one SceneImportWarning. Relative
    paths are tried against the working directory, then the repository (or installed package) root;
    the error names every place tried."""
    text = str(name_or_path)
    suffix = Path(text).suffix.lower()
    if isinstance(name_or_path, Path) or suffix in YAML_SUFFIXES + MESH_SUFFIXES + XML_SUFFIXES:
        tried = candidate_paths(text)
        path = next((p for p in tried if p.exists()), None)
        if path is None:
            raise SceneError(f"scene file: not found: {text} (tried {', '.join(map(str, tried))})")
        if suffix in YAML_SUFFIXES:
            if overrides:
                raise SceneError(
                    f"{path}: overrides {sorted(overrides)} are not accepted for a scene file; "
                    "put parameters in the file's objects[].params"
                )
            return load_scene_file(path)
        if suffix in XML_SUFFIXES:
            unknown = sorted(set(overrides) - {"include_emitters", "parameters"})
            if unknown:
                raise SceneError(f"{path}: unknown Mitsuba option(s) {unknown}; accepted: include_emitters, parameters")
            return load_mitsuba(path, **overrides)
        if suffix in MESH_SUFFIXES:
            unknown = sorted(set(overrides) - {"color", "name", "texture", "shading"})
            if unknown:
                raise SceneError(f"{path}: unknown mesh option(s) {unknown}; accepted: color, name, texture, shading")
            from . import shading as _shading

            mode = overrides.pop("shading", "headlight")
            if suffix in GLTF_SUFFIXES:
                return _shading.apply(load_gltf(path, **overrides), mode)
            mesh = load_mesh(path, **overrides)
            mesh = mesh.with_camera_hint(**frame_hint(mesh))
            return _shading.apply(mesh, mode)  # an uncoloured mesh: Lambert under a headlight
        raise SceneError(f"{path}: unknown scene file type {suffix!r}; expected one of "
                         f"{', '.join(YAML_SUFFIXES + XML_SUFFIXES + MESH_SUFFIXES)} or a scene name")
    return named(text, **overrides)
