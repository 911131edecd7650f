"""Experiment configuration: the YAML schema (pydantic v2), `extends:`, `--set` overrides, sweep
expansion (cartesian product and `zip:` groups), and the construction of the scene, camera, sample
table and pipeline of one point.

Every parameter is declared once, with its type, default and description: the `pipeline` section
comes from sim.PipelineConfig's field declarations, the `hardware` section from
sim.HardwareConfig.field_docs(). Unknown keys are errors that name the key, the file and the line
(STYLE.md §Configuration). ``python -m experiments.config`` prints docs/config.md.
"""
from __future__ import annotations

import copy
import hashlib
import itertools
import json
import typing
from pathlib import Path
from typing import Any, Literal, Optional, Union

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, create_model, field_validator, model_validator

import sim
from models.loader import UniqueKeyLoader

REPO = Path(__file__).resolve().parent.parent


class ConfigError(ValueError):
    """A configuration file or override is invalid; the message names the file, line, key and value."""


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


class SamplesSpec(_Strict):
    """The programmable sample table (sim.SampleTable)."""

    kind: Literal["random", "stratified", "stratified_permuted", "sobol", "interleaved", "multiview"] = Field(
        "stratified", description="Sample-table kind (sim.SampleTable generator)")
    spp: int = Field(16, description="Samples per pixel (1..4096)")
    seed: int = Field(0, description="Random seed")
    period: int = Field(32, description="Repeat period P of the P x P pixel table [px]")
    lens: bool = Field(True, description="Include the lens (u, v) dimensions")
    time: bool = Field(True, description="Include the time dimension")
    n_lens: Optional[int] = Field(None, description="Interleaved only: number of discrete lens positions (64, 256)")
    views: Optional[int] = Field(None, description=(
        "Multiview only: number of views splitting the lens in u (002 §8); spp is the total over all views"))


def _pipeline_model() -> type[BaseModel]:
    """The pipeline section, generated from sim.PipelineConfig's field declarations."""
    fields = {}
    types = {"algorithm": str, "threads": int, "tile_size": int, "lens_grid": Union[int, Literal["auto"]],
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


def _hardware_model(name: str, docs: dict, owner) -> type[BaseModel]:
    """A section generated from sim.HardwareConfig.field_docs() (nested sections recursively). Every
    key is optional: unset keys keep sim.HardwareConfig's defaults, so the section stays a diff."""
    fields = {}
    hints = typing.get_type_hints(owner)
    for key, info in docs.items():
        unit = f" [{info['unit']}]" if info["unit"] else ""
        if "fields" in info:
            sub_owner = hints[key]
            sub = _hardware_model(f"{name}_{key}", info["fields"], sub_owner)
            fields[key] = (Optional[sub], Field(None, description=info["doc"] + unit))
        else:
            fields[key] = (Optional[hints[key]], Field(None, description=f"{info['doc']}{unit}; default "
                                                       f"{info['default']!r}"))
    return create_model(name, __config__=ConfigDict(extra="forbid"),
                        __doc__=f"sim.HardwareConfig {'section ' + name if name != 'HardwareSpec' else ''}".strip(),
                        **fields)


HardwareSpec = _hardware_model("HardwareSpec", sim.HardwareConfig.field_docs(), sim.HardwareConfig)
HardwareSpec.__doc__ = ("The modelled hardware (sim.HardwareConfig: timing units, texture cache, memory). Keys left "
                        "out keep their defaults; validated by sim.HardwareConfig even where no stage uses it yet.")


class PlotSpec(_Strict):
    """One figure or table of a report page (docs/reports.md)."""

    kind: Literal["line", "bar", "table", "scatter"] = Field("line", description="line | bar | table | scatter")
    x: Optional[str] = Field(None, description="Column on the x axis (table: the row key)")
    y: Union[str, list[str]] = Field(..., description="Column(s) on the y axis (table: the value columns)")
    hue: Optional[Union[str, list[str]]] = Field(None, description=(
        "Column whose values get one line/bar colour (table: one column each); a list of columns combines "
        "their values with spaces ('tile 1')"))
    style: Optional[str] = Field(None, description="scatter only: column whose values get one marker shape each")
    facet: Optional[str] = Field(None, description="Column whose values get one panel each")
    where: dict[str, Any] = Field(default_factory=dict, description="Equality filter {column: value or [values]}")
    logx: bool = Field(False, description="Logarithmic x axis")
    logy: bool = Field(False, description="Logarithmic y axis")
    title: Optional[str] = Field(None, description="Figure title")
    xlabel: Optional[str] = Field(None, description="x axis label (default: the column)")
    ylabel: Optional[str] = Field(None, description="y axis label (default: the column)")
    stacked: bool = Field(False, description="bar only: stack the y columns")
    pareto: bool = Field(False, description="scatter only: highlight the lower-left Pareto front (minimise x and y) "
                                            "per facet")
    fit: Optional[Literal["powerlaw"]] = Field(None, description=(
        "table only: 'powerlaw' fits y = c * x^-alpha per hue (and facet) by least squares in log-log and "
        "tabulates alpha"))
    paper: dict[Any, dict[Any, Any]] = Field(default_factory=dict, description=(
        "Published numbers {hue value (or y column without hue): {x value: number or text}}, drawn/tabulated "
        "beside ours"))
    format: Optional[str] = Field(None, description="Python format of the numbers in tables, e.g. '{:.2f}'")
    labels: dict[str, dict[Any, str]] = Field(default_factory=dict, description=(
        "Display names for values of a column {column: {value: name}}, e.g. {mode: {0: none, 1: h_i}}; also "
        "the keys of paper: and where: for that column"))
    columns: list[str] = Field(default_factory=list, description=(
        "scatter and x-less tables: extra columns shown in the data table (e.g. samples.spp)"))
    optional: bool = Field(False, description=(
        "Leave the plot out (silently) when a column it names is missing, e.g. timing.cycles before the timing "
        "model exists"))

    @model_validator(mode="after")
    def _check(self):
        if self.kind in ("line", "bar", "scatter") and self.x is None:
            raise ValueError(f"a {self.kind} plot needs x")
        if self.fit and self.kind != "table":
            raise ValueError("fit: only for table plots")
        if self.fit and (self.x is None or not isinstance(self.y, str)):
            raise ValueError("fit: needs x and a single y column")
        return self

    @property
    def ys(self) -> list[str]:
        return [self.y] if isinstance(self.y, str) else list(self.y)


class MetricsSpec(_Strict):
    """Image error against a reference image of the same point at many samples per pixel
    (experiments/metrics.py). Adds columns metric.rmse, metric.psnr, metric.ssim (and metric.flip)."""

    reference_spp: int = Field(1024, description="Samples per pixel of the reference image (>= 1024 for reports)")
    reference_kind: Literal["random", "stratified", "sobol"] = Field(
        "stratified", description="Sample-table kind of the reference")
    reference_algorithm: str = Field("tile", description="Algorithm rendering the reference (any exact one: same image)")
    flip: bool = Field(False, description="Also compute FLIP (flip-evaluator; slower)")


class OutputsSpec(_Strict):
    """What a config produces: the files of `rast5d render`, image-error metrics, and the report page
    (docs/reports.md)."""

    image: Optional[str] = Field(None, description="`rast5d render`: PNG path for the image (-o takes precedence)")
    stats: Optional[str] = Field(None, description="`rast5d render`: JSON path for the statistics (--stats takes precedence)")
    images: bool = Field(False, description="`rast5d run`: also write each point's PNG next to the results")
    metrics: Optional[MetricsSpec] = Field(None, description="Image error of every point against a reference")
    page: Optional[str] = Field(None, description="Report page name: reports/paper/<page>.md (configs may share a page)")
    title: Optional[str] = Field(None, description="Section title on the page")
    text: Optional[str] = Field(None, description="Markdown above the figures: what, how, departures, caveats")
    derived: dict[str, str] = Field(default_factory=dict, description=(
        "New columns: pandas expressions over result columns (dotted names allowed), e.g. "
        "'shade.quad_requests / raster.samples_hit'"))
    plots: list[PlotSpec] = Field(default_factory=list, description="Figures and tables (see the plot keys below)")
    order: int = Field(0, description="Position of this config's section on a shared page (ascending)")


class ExecutorSpec(_Strict):
    """Where the points of a sweep run (the command line's --workers / --scheduler take precedence)."""

    kind: Literal["local", "dask"] = Field("local", description="local process pool or a Dask distributed cluster")
    workers: Optional[int] = Field(None, description="local: worker processes (default: the core count)")
    address: Optional[str] = Field(None, description="dask: scheduler address, e.g. tcp://host:8786")

    @model_validator(mode="after")
    def _check(self):
        if self.kind == "dask" and not self.address:
            raise ValueError("executor.kind 'dask' needs executor.address (or --scheduler ADDRESS)")
        if self.workers is not None and self.workers < 1:
            raise ValueError(f"executor.workers: expected >= 1, got {self.workers}")
        return self


class RenderConfig(_Strict):
    """One experiment: a scene, camera, sample table, pipeline and hardware, optionally swept."""

    name: Optional[str] = Field(None, description="Experiment name: the result table results/<name>.parquet "
                                                  "(default: the file name; not inherited through extends)")
    description: Optional[str] = Field(None, description="Free text")
    extends: Optional[Union[str, list[str]]] = Field(None, description=(
        "Base config file(s), relative to this file: deep-merged under this one (mappings merge, other values "
        "replace); recursive; cycles are errors"))
    scene: SceneSpec = Field(..., description="The workload")
    camera: CameraSpec = Field(default_factory=CameraSpec, description="Camera (overrides the scene's hint)")
    samples: SamplesSpec = Field(default_factory=SamplesSpec, description="Sample table")
    pipeline: PipelineSpec = Field(default_factory=PipelineSpec, description="Pipeline")
    hardware: HardwareSpec = Field(default_factory=HardwareSpec, description="Modelled hardware")
    sweep: dict[str, Any] = Field(default_factory=dict, description=(
        "Dotted keys to lists of values, e.g. {camera.coc_px: [0, 10, 50]}: `rast5d run` renders the "
        "cartesian product. `zip: [[key1, key2], ...]` makes each group of swept keys vary together (equal "
        "lengths); a key can be a whole section (scene: [{name: a}, {name: b}])"))
    outputs: OutputsSpec = Field(default_factory=OutputsSpec, description="Files, metrics and the report spec")
    executor: ExecutorSpec = Field(default_factory=ExecutorSpec, description="Where the points run")

    @field_validator("sweep")
    @classmethod
    def _check_sweep(cls, sweep: dict) -> dict:
        zipped = sweep.get("zip", [])
        if not isinstance(zipped, list) or not all(isinstance(g, list) and all(isinstance(k, str) for k in g)
                                                   for g in zipped):
            raise ValueError(f"sweep.zip: expected a list of lists of swept keys, got {zipped!r}")
        seen = set()
        for group in zipped:
            if len(group) < 2:
                raise ValueError(f"sweep.zip: a group needs at least two keys, got {group!r}")
            for k in group:
                if k not in sweep or k == "zip":
                    raise ValueError(f"sweep.zip: {k!r} is not a swept key (give its values under sweep:)")
                if k in seen:
                    raise ValueError(f"sweep.zip: {k!r} is in two groups")
                seen.add(k)
            lengths = {k: len(sweep[k]) for k in group}
            if len(set(lengths.values())) != 1:
                raise ValueError(f"sweep.zip: the keys of a group need equal lengths, got {lengths}")
        for k, v in sweep.items():
            if k != "zip" and (not isinstance(v, list) or not v):
                raise ValueError(f"sweep.{k}: expected a non-empty list of values, got {v!r}")
        return sweep

    def hardware_config(self) -> "sim.HardwareConfig":
        return sim.HardwareConfig.from_dict(_drop_none(self.hardware.model_dump()))


def _drop_none(d):
    if isinstance(d, dict):
        return {k: _drop_none(v) for k, v in d.items() if v is not None}
    return d


# ---- loading: YAML with line numbers, extends, overrides ----------------------------------------

def _node_lines(node, source: str, path: tuple = (), out: dict | None = None) -> dict:
    """{key path: 'file:line'} for every mapping key and sequence item of a composed YAML tree."""
    out = {} if out is None else out
    if isinstance(node, yaml.MappingNode):
        for k, v in node.value:
            key = path + (str(k.value),)
            out[key] = f"{source}:{k.start_mark.line + 1}"
            _node_lines(v, source, key, out)
    elif isinstance(node, yaml.SequenceNode):
        for i, v in enumerate(node.value):
            key = path + (i,)
            out[key] = f"{source}:{v.start_mark.line + 1}"
            _node_lines(v, source, key, out)
    return out


def _read_yaml(path: Path) -> tuple[dict, dict]:
    if not path.exists():
        raise ConfigError(f"config: file not found: {path}")
    text = path.read_text()
    try:
        data = yaml.load(text, Loader=UniqueKeyLoader)  # noqa: S506 (a SafeLoader subclass)
        lines = _node_lines(yaml.compose(text, Loader=yaml.SafeLoader), str(path))
    except yaml.constructor.ConstructorError as e:
        if not (e.problem or "").startswith("duplicate key"):
            raise ConfigError(f"{path}: not valid YAML: {e}") from None
        raise ConfigError(f"{path}: {e.problem} at line {e.problem_mark.line + 1}") from None
    except yaml.YAMLError as e:
        raise ConfigError(f"{path}: not valid YAML: {e}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping at the top level, got {type(data).__name__}")
    return data, lines


def deep_merge(base: dict, over: dict) -> dict:
    """Mappings merge key by key; any other value in ``over`` replaces the base's."""
    out = copy.deepcopy(base)
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def _load_with_extends(path: Path, chain: tuple[Path, ...] = ()) -> tuple[dict, dict]:
    path = path.resolve()
    if path in chain:
        cycle = " -> ".join(str(p) for p in chain + (path,))
        raise ConfigError(f"{chain[-1]}: extends: cycle {cycle}")
    data, lines = _read_yaml(path)
    bases = data.pop("extends", None)
    if bases is None:
        return data, lines
    if isinstance(bases, str):
        bases = [bases]
    if not isinstance(bases, list) or not all(isinstance(b, str) for b in bases):
        raise ConfigError(f"{lines.get(('extends',), path)}: extends: expected a file name or a list of them, "
                          f"got {bases!r}")
    merged, merged_lines = {}, {}
    for b in bases:
        base_path = path.parent / b
        if not base_path.exists():
            raise ConfigError(f"{lines.get(('extends',), path)}: extends: base config {b!r} not found "
                              f"(looked for {base_path})")
        bdata, blines = _load_with_extends(base_path, chain + (path,))
        bdata.pop("name", None)  # the name identifies a file's result table: never inherited
        merged = deep_merge(merged, bdata)
        merged_lines.update(blines)
    merged = deep_merge(merged, data)
    merged_lines.update(lines)
    return merged, merged_lines


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


def _format_validation(err: ValidationError, source: str, lines: dict | None = None) -> str:
    out = []
    lines = lines or {}
    for e in err.errors():
        loc = tuple(p for p in e["loc"] if not (isinstance(p, str) and ("[" in p or p.startswith("function-"))))
        dotted = ".".join(str(p) for p in loc) or "(top level)"
        where = source
        for n in range(len(loc), 0, -1):  # the deepest known location
            if loc[:n] in lines:
                where = lines[loc[:n]]
                break
        if e["type"] == "extra_forbidden":
            out.append(f"{where}: unknown key {dotted!r}")
        else:
            msg = e["msg"].removeprefix("Value error, ")
            out.append(f"{where}: {dotted}: {msg} (got {e.get('input')!r})")
    return "\n".join(dict.fromkeys(out))


def load_dict(path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> tuple[dict, dict]:
    """(merged data, {key path: 'file:line'}) after extends and --set overrides, not validated."""
    path = Path(path)
    data, lines = _load_with_extends(path)
    data.setdefault("name", path.stem)
    for text in overrides:
        key, value = parse_override(text)
        _set_dotted(data, key, value, f"{path} --set")
        lines[tuple(key.split("."))] = f"--set {text}"
    return data, lines


def validate(data: dict, source: str = "config", lines: dict | None = None) -> RenderConfig:
    try:
        config = RenderConfig.model_validate(data)
    except ValidationError as e:
        raise ConfigError(_format_validation(e, source, lines)) from None
    try:
        config.hardware_config()
    except sim.ConfigError as e:
        where = lines.get(("hardware",), source) if lines else source
        raise ConfigError(f"{where}: hardware: {e}") from None
    return config


def load_config(path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> RenderConfig:
    """Load a YAML config (following extends), apply --set overrides, validate. Raises ConfigError."""
    data, lines = load_dict(path, overrides)
    config = validate(data, str(path), lines)
    expand_sweep(config, str(path), lines)  # every point is checked up front, not mid-sweep
    return config


def sweep_points(sweep: dict) -> list[dict]:
    """[{dotted key: value}] for a sweep: the cartesian product over the axes, where each `zip` group
    is one axis whose values are taken together (item i of every key in the group)."""
    if not sweep:
        return [{}]
    groups = [list(g) for g in sweep.get("zip", [])]
    in_group = {k for g in groups for k in g}
    axes: list[list[dict]] = []
    for k, values in sweep.items():
        if k == "zip" or k in in_group:
            continue
        axes.append([{k: v} for v in values])
    for g in groups:
        axes.append([{k: sweep[k][i] for k in g} for i in range(len(sweep[g[0]]))])
    # Keep the axis order of the file (first axis varies slowest).
    order = [k for k in sweep if k != "zip"]
    axes.sort(key=lambda ax: min(order.index(k) for k in ax[0]))
    points = []
    for combo in itertools.product(*axes):
        p = {}
        for part in combo:
            p.update(part)
        points.append(p)
    return points


def expand_sweep(config: RenderConfig, source: str = "config", lines: dict | None = None
                 ) -> list[tuple[dict, RenderConfig]]:
    """[(point, config)] for every point of config.sweep (one point without a sweep). Each point is
    validated on its own; ConfigError names the point."""
    if not config.sweep:
        return [({}, config)]
    base = config.model_dump(exclude={"sweep"})
    points = []
    for point in sweep_points(config.sweep):
        d = copy.deepcopy(base)
        for k, v in point.items():
            _set_dotted(d, k, v, f"{source} sweep")
        points.append((point, validate(d, f"{source} (sweep point {point})")))
    return points


RESULT_EXCLUDE = {"name", "description", "extends", "sweep", "outputs", "executor"}


def config_hash(config: RenderConfig) -> str:
    """Stable hash of everything that determines a point's result row: scene, camera, samples,
    pipeline (not the thread count: results are identical for any), hardware, and the metrics spec."""
    d = config.model_dump(exclude=RESULT_EXCLUDE)
    d["pipeline"].pop("threads", None)
    d["metrics"] = config.outputs.metrics.model_dump() if config.outputs.metrics else None
    blob = json.dumps(d, sort_keys=True, default=str).encode()
    return hashlib.sha256(blob).hexdigest()[:16]


def flatten(d: dict, prefix: str = "") -> dict:
    """{'camera': {'coc_px': 10}} -> {'camera.coc_px': 10}; lists become JSON text (one cell)."""
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict) and v:
            out.update(flatten(v, key + "."))
        elif isinstance(v, dict):
            continue
        elif isinstance(v, (list, tuple)):
            out[key] = json.dumps(v)
        else:
            out[key] = v
    return out


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
    t = config.samples
    params = dict(spp=t.spp, seed=t.seed, period=t.period, lens=t.lens, time=t.time)
    if t.kind == "interleaved":
        if t.n_lens is not None:
            params["n_lens"] = t.n_lens
    elif t.n_lens is not None:
        raise ConfigError(f"samples.n_lens: only for the interleaved kind, got kind={t.kind!r}")
    if t.views is not None:
        if t.kind != "multiview":
            raise ConfigError(f"samples.views: only for the multiview kind, got kind={t.kind!r}")
        params["views"] = t.views
    table = sim.SampleTable.create(t.kind, **params)
    pipeline = sim.PipelineConfig(**config.pipeline.model_dump())
    return scene, camera, table, pipeline


# ---- reference documentation --------------------------------------------------------------------

def _type_text(ann) -> str:
    text = ann.__name__ if isinstance(ann, type) else str(ann).replace("typing.", "")
    if text.startswith("Optional[") and text.endswith("]"):
        text = text[len("Optional["):-1] + " or null"
    text = text.replace("experiments.config.", "")
    return " ".join(text.replace("|", "or").split())


def _section_models() -> list[tuple[str, type[BaseModel]]]:
    out = [("(top level)", RenderConfig), ("scene", SceneSpec), ("camera", CameraSpec), ("samples", SamplesSpec),
           ("pipeline", PipelineSpec), ("hardware", HardwareSpec)]

    def nested(prefix, model):
        for name, f in model.model_fields.items():
            for cand in typing.get_args(f.annotation) or (f.annotation,):
                if isinstance(cand, type) and issubclass(cand, BaseModel):
                    out.append((f"{prefix}.{name}", cand))
                    nested(f"{prefix}.{name}", cand)

    nested("hardware", HardwareSpec)
    out += [("outputs", OutputsSpec), ("outputs.metrics", MetricsSpec), ("outputs.plots[]", PlotSpec),
            ("executor", ExecutorSpec)]
    return out


def markdown_reference() -> str:
    """docs/config.md: every section and key with type, default and description."""
    out = ["# Configuration reference", "",
           "Generated by `python -m experiments.docs` from the schema in `experiments/config.py` (the pipeline "
           "section from `sim.PipelineConfig`, the hardware section from `sim.HardwareConfig.field_docs()`). "
           "Unknown keys are errors naming the key, file and line. Report specs (`outputs`): docs/reports.md.",
           ""]
    for title, model in _section_models():
        out += [f"## `{title}`", "", " ".join((model.__doc__ or "").split()), "",
                "| key | type | default | description |", "|---|---|---|---|"]
        for name, f in model.model_fields.items():
            ann = f.annotation
            cands = typing.get_args(ann) or (ann,)
            if any(isinstance(c, type) and issubclass(c, BaseModel) for c in cands) and name != "plots":
                out.append(f"| `{name}` | section | see below | {f.description or ''} |")
                continue
            default = "required" if f.is_required() else repr(f.get_default(call_default_factory=True))
            text = "list of plot specs" if name == "plots" else _type_text(ann)
            out.append(f"| `{name}` | `{text}` | `{default}` | {f.description or ''} |")
        out.append("")
    return "\n".join(out)


if __name__ == "__main__":
    print(markdown_reference())
