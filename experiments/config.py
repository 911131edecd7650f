"""Experiment configuration: the YAML schema (pydantic v2), overrides, sweep expansion, and the
construction of the scene, camera, sample table and pipeline for one point.

Every parameter is declared once, with its type, default and description; unknown keys are errors
that name the key and the file (STYLE.md §Configuration). ``python -m experiments.config`` prints
the reference that lives in docs/config.md.
"""
from __future__ import annotations

import copy
import hashlib
import itertools
import json
import typing
from pathlib import Path
from typing import Any, Literal, Optional

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, create_model, model_validator

import sim

REPO = Path(__file__).resolve().parent.parent


class ConfigError(ValueError):
    """A configuration file or override is invalid; the message names the file, key and value."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class SceneSpec(_Strict):
    """Which workload to render (models/)."""

    name: Optional[str] = Field(None, description="A named scene (models.scene_names()), e.g. 'spot_wall', 'bunny'")
    path: Optional[str] = Field(None, description="A scene YAML file or a mesh (OBJ/PLY), relative to the repository")
    params: dict[str, Any] = Field(default_factory=dict, description="Keyword parameters of the named scene")

    @model_validator(mode="after")
    def _one_source(self):
        if (self.name is None) == (self.path is None):
            raise ValueError("give exactly one of scene.name or scene.path")
        if self.path is not None and self.params:
            raise ValueError("scene.params only apply to named scenes (put parameters in the scene file)")
        return self


class CameraSpec(_Strict):
    """The thin-lens camera (sim.Camera). Unset fields come from the scene's camera hint, then from
    sim.Camera's defaults. Give coc_px or aperture_radius, not both."""

    width: Optional[int] = Field(None, description="Image width [px] (1..16384)")
    height: Optional[int] = Field(None, description="Image height [px] (1..16384)")
    fov_y_deg: Optional[float] = Field(None, description="Vertical field of view [deg]")
    focus_distance: Optional[float] = Field(None, description="Distance of the focus plane [world units]")
    coc_px: Optional[float] = Field(None, description="CoC radius at infinity [px] (the paper's 'CoC')")
    aperture_radius: Optional[float] = Field(None, description="Aperture radius [world units] (instead of coc_px)")
    lens: Optional[Literal["disk", "square", "hexagon"]] = Field(None, description="Aperture shape")
    eye: Optional[list[float]] = Field(None, description="Camera position [world]; default origin")
    target: Optional[list[float]] = Field(None, description="Point looked at [world]; default -z")
    up: Optional[list[float]] = Field(None, description="Up direction; default +y")
    near: Optional[float] = Field(None, description="Near plane distance [world units]")
    shutter: Optional[list[float]] = Field(None, description="Shutter interval [open, close] within [0, 1]")


class TableSpec(_Strict):
    """The programmable sample table (sim.SampleTable)."""

    generator: Literal["random", "stratified", "stratified_permuted", "sobol", "interleaved"] = Field(
        "stratified", description="Sample generator")
    spp: int = Field(16, description="Samples per pixel (1..4096)")
    seed: int = Field(0, description="Random seed")
    period: int = Field(32, description="Repeat period P of the P x P pixel table")
    lens: bool = Field(True, description="Include the lens (u, v) dimensions")
    time: bool = Field(True, description="Include the time dimension")
    n_lens: Optional[int] = Field(None, description="Interleaved only: number of discrete lens positions (64, 256)")


def _pipeline_model() -> type[BaseModel]:
    """The pipeline section, generated from sim.PipelineConfig's field declarations."""
    fields = {}
    types = {"algorithm": str, "threads": int, "tile_size": int, "lens_grid": int | Literal["auto"],
             "halfspace": dict[Literal["h", "H"], bool], "selective_H": bool, "oracle": Literal["simplified", "full"],
             "c_sample": Optional[float], "c_tile": Optional[float], "backface_cull": bool,
             "op_count": Literal["documented", "exact"], "count_optimal": bool, "hinterleave_tile": int,
             "bin_size": int, "memory_limit_bytes": int}
    hints = typing.get_type_hints(sim.PipelineConfig)
    for name, info in sim.PipelineConfig.field_docs().items():
        unit = f" [{info['unit']}]" if info["unit"] else ""
        # Fields added to sim.PipelineConfig appear here by themselves (with their declared type);
        # the table above only narrows types for better error messages.
        fields[name] = (types.get(name, hints[name]), Field(info["default"], description=info["doc"] + unit))
    return create_model("PipelineSpec", __config__=ConfigDict(extra="forbid"),
                        __doc__="The rasterizer pipeline (sim.PipelineConfig).", **fields)


PipelineSpec = _pipeline_model()


class OutputSpec(_Strict):
    """Where `rast5d render` writes (command-line -o/--stats take precedence)."""

    image: Optional[str] = Field(None, description="PNG path for the image")
    stats: Optional[str] = Field(None, description="JSON path for the statistics")


class RenderConfig(_Strict):
    """One experiment: a scene, camera, sample table and pipeline, optionally swept."""

    name: Optional[str] = Field(None, description="Experiment name (reports, result files)")
    description: Optional[str] = Field(None, description="Free text")
    scene: SceneSpec = Field(..., description="The workload")
    camera: CameraSpec = Field(default_factory=CameraSpec, description="Camera (overrides the scene's hint)")
    sample_table: TableSpec = Field(default_factory=TableSpec, description="Sample table")
    pipeline: PipelineSpec = Field(default_factory=PipelineSpec, description="Pipeline")
    output: OutputSpec = Field(default_factory=OutputSpec, description="Outputs of `rast5d render`")
    sweep: dict[str, list[Any]] = Field(default_factory=dict, description=(
        "Dotted keys to lists of values, e.g. {camera.coc_px: [0, 10, 50]}: `rast5d run` renders the "
        "cartesian product"))


# ---- loading -------------------------------------------------------------------------------------

class _UniqueKeyLoader(yaml.SafeLoader):
    pass


def _construct_mapping(loader, node, deep=False):
    seen = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in seen:
            raise ConfigError(f"duplicate key {key!r} at line {key_node.start_mark.line + 1}")
        seen.add(key)
    return yaml.SafeLoader.construct_mapping(loader, node, deep)


_UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def _set_dotted(d: dict, dotted: str, value, source: str):
    parts = dotted.split(".")
    node = d
    for p in parts[:-1]:
        child = node.setdefault(p, {})
        if not isinstance(child, dict):
            raise ConfigError(f"{source}: cannot set {dotted!r}: {p!r} is not a section")
        node = child
    node[parts[-1]] = value


def parse_override(text: str) -> tuple[str, Any]:
    """'camera.coc_px=10' -> ('camera.coc_px', 10); the value is parsed as YAML."""
    if "=" not in text:
        raise ConfigError(f"--set: expected key=value, got {text!r}")
    key, raw = text.split("=", 1)
    key = key.strip()
    if not key:
        raise ConfigError(f"--set: empty key in {text!r}")
    try:
        value = yaml.safe_load(raw) if raw.strip() else None
    except yaml.YAMLError as e:
        raise ConfigError(f"--set {key}: cannot parse value {raw!r}: {e}") from None
    return key, value


def _format_validation(err: ValidationError, source: str) -> str:
    lines = []
    for e in err.errors():
        loc = ".".join(str(p) for p in e["loc"]) or "(top level)"
        if e["type"] == "extra_forbidden":
            lines.append(f"{source}: unknown key {loc!r}")
        else:
            lines.append(f"{source}: {loc}: {e['msg']} (got {e.get('input')!r})")
    return "\n".join(lines)


def load_dict(path: str | Path) -> dict:
    path = Path(path)
    if not path.exists():
        raise ConfigError(f"config: file not found: {path}")
    try:
        data = yaml.load(path.read_text(), Loader=_UniqueKeyLoader)
    except ConfigError as e:
        raise ConfigError(f"{path}: {e}") from None
    except yaml.YAMLError as e:
        raise ConfigError(f"{path}: not valid YAML: {e}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping at the top level, got {type(data).__name__}")
    return data


def validate(data: dict, source: str = "config") -> RenderConfig:
    try:
        return RenderConfig.model_validate(data)
    except ValidationError as e:
        raise ConfigError(_format_validation(e, source)) from None


def load_config(path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> RenderConfig:
    """Load a YAML config, apply --set overrides, validate. Raises ConfigError."""
    data = load_dict(path)
    for text in overrides:
        key, value = parse_override(text)
        _set_dotted(data, key, value, f"{path} --set")
    return validate(data, str(path))


def expand_sweep(config: RenderConfig, source: str = "config") -> list[tuple[dict, RenderConfig]]:
    """[(point, config)] for the cartesian product of config.sweep (one point without a sweep)."""
    if not config.sweep:
        return [({}, config)]
    base = config.model_dump(exclude={"sweep"})
    keys = list(config.sweep)
    points = []
    for values in itertools.product(*(config.sweep[k] for k in keys)):
        d = copy.deepcopy(base)
        point = dict(zip(keys, values))
        for k, v in point.items():
            _set_dotted(d, k, v, f"{source} sweep")
        points.append((point, validate(d, f"{source} (sweep point {point})")))
    return points


def config_hash(config: RenderConfig) -> str:
    """Stable hash of everything that determines a render's result."""
    d = config.model_dump(exclude={"name", "description", "output", "sweep"})
    d["pipeline"].pop("threads", None)  # results are identical for any thread count
    blob = json.dumps(d, sort_keys=True, default=str).encode()
    return hashlib.sha256(blob).hexdigest()[:16]


# ---- building the objects of one point ----------------------------------------------------------

def build(config: RenderConfig):
    """(scene, camera, table, pipeline) for one (non-swept) config."""
    import models

    spec = config.scene
    if spec.name is not None:
        scene = models.named(spec.name, **spec.params)
    else:
        p = Path(spec.path)
        scene = models.load(str(p if p.is_absolute() else REPO / p))
    cam_args = dict(scene.camera_hint or {})
    given = {k: v for k, v in config.camera.model_dump().items() if v is not None}
    if "coc_px" in given:  # the config's blur replaces any blur in the hint
        cam_args.pop("aperture_radius", None)
    if "aperture_radius" in given:
        cam_args.pop("coc_px", None)
    cam_args.update(given)
    if cam_args.get("shutter") is not None:
        cam_args["shutter"] = tuple(cam_args["shutter"])
    camera = sim.Camera(**cam_args)
    t = config.sample_table
    params = dict(spp=t.spp, seed=t.seed, period=t.period, lens=t.lens, time=t.time)
    if t.generator == "interleaved":
        if t.n_lens is not None:
            params["n_lens"] = t.n_lens
    elif t.n_lens is not None:
        raise ConfigError(f"sample_table.n_lens: only for the interleaved generator, got generator={t.generator!r}")
    table = sim.SampleTable.create(t.generator, **params)
    pipeline = sim.PipelineConfig(**config.pipeline.model_dump())
    return scene, camera, table, pipeline


# ---- reference documentation --------------------------------------------------------------------

def markdown_reference() -> str:
    """docs/config.md: every section and key with type, default and description."""
    out = ["# Configuration reference", "",
           "Generated by `python -m experiments.config > docs/config.md` from the schema in "
           "`experiments/config.py` (the pipeline section from `sim.PipelineConfig`). Unknown keys are errors.",
           ""]
    sections = [("(top level)", RenderConfig), ("scene", SceneSpec), ("camera", CameraSpec),
                ("sample_table", TableSpec), ("pipeline", PipelineSpec), ("output", OutputSpec)]
    for title, model in sections:
        out += [f"## `{title}`", "", " ".join((model.__doc__ or "").split()), "",
                "| key | type | default | description |", "|---|---|---|---|"]
        for name, f in model.model_fields.items():
            ann = f.annotation
            if isinstance(ann, type) and issubclass(ann, BaseModel):
                out.append(f"| `{name}` | section | see below | {f.description or ''} |")
                continue
            text = ann.__name__ if isinstance(ann, type) else str(ann).replace("typing.", "")
            if text.startswith("Optional[") and text.endswith("]"):
                text = text[len("Optional["):-1] + " or null"
            text = " ".join(text.replace("|", "or").split())
            default = "required" if f.is_required() else repr(f.get_default(call_default_factory=True))
            out.append(f"| `{name}` | `{text}` | `{default}` | {f.description or ''} |")
        out.append("")
    return "\n".join(out)


if __name__ == "__main__":
    print(markdown_reference())
