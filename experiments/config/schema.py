"""The experiment schema (pydantic v2): every section and key of a config file, with its type,
default and description, and the validation of a merged config into a RenderConfig.

Every parameter is declared once: the `pipeline` section comes from sim.PipelineConfig's field
declarations, the `hardware` section from sim.HardwareConfig.field_docs(). Unknown keys are errors
that name the key, the file and the line (docs/design_notes.md, note 9: each parameter declared once).
"""
from __future__ import annotations

import copy
import difflib
import re
import typing
from pathlib import Path
from typing import Any, Literal, Optional, Union

from pydantic import (BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, create_model, field_validator,
                      model_validator)

import sim

REPO = Path(__file__).resolve().parents[2]

# Names read from their registries: the engine's lens shapes and occlusion-query modes, the sample
# table's generators (all of them, and those that may render metric references).
LensShapeName = Literal[tuple(sim.lens.LENS_SHAPES)]
QueryModeName = Literal[tuple(sim.intervals.query_modes())]
SampleKind = Literal[tuple(sim.SampleTable.kinds())]  # generators and lines (SampleTable.lines)
ReferenceKind = Literal[tuple(sim.SampleTable.generators(reference=True))]


class ConfigError(sim.ConfigError):
    """A configuration file, --set override or sweep point is invalid; the message names the file,
    line, key and value (a sim.ConfigError, so ``rast5d.Error`` catches it)."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class SceneSpec(_Strict):
    """Which workload to render (models/)."""

    name: Optional[str] = Field(None, description=(
        "A named scene (models.scene_names()), e.g. 'spot_wall', "
        "'bunny'"))
    path: Optional[str] = Field(None, description=(
        "A scene file: YAML scene, Mitsuba XML, glTF/GLB or a mesh (OBJ/PLY/...); relative to the config file "
        "that names it, else the working directory (docs/scenes.md)"))
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
    lens: Optional[LensShapeName] = Field(None, description="Aperture shape")
    eye: Optional[list[float]] = Field(None, description="Camera position [world]; default origin")
    target: Optional[list[float]] = Field(None, description="Point looked at [world]; default -z")
    up: Optional[list[float]] = Field(None, description="Up direction; default +y")
    near: Optional[float] = Field(None, description="Near plane distance [world units]")
    shutter: Optional[list[float]] = Field(None, description="Shutter interval [open, close] within [0, 1]")
    u_scale: Optional[float] = Field(None, description=(
        "Lens extent in u relative to v (>= 1): V views side by side on a camera line, each a full-size lens "
        "(samples.kind multiview with views V and u_scale V); default 1"))


class SamplesSpec(_Strict):
    """The programmable sample table (sim.SampleTable)."""

    kind: SampleKind = Field(
        "stratified", description="Sample-table kind (sim.SampleTable generator)")
    spp: int = Field(16, description="Samples per pixel (1..4096)")
    seed: int = Field(0, description="Random seed")
    period: int = Field(32, description="Repeat period P of the P x P pixel table [px]")
    lens: bool = Field(True, description="Include the lens (u, v) dimensions")
    time: bool = Field(True, description="Include the time dimension")
    n_lens: Optional[int] = Field(None, description="Interleaved only: number of discrete lens positions (64, 256)")
    views: Optional[int] = Field(None, description=(
        "Multiview only: number of views splitting the lens in u ([Nilsson 2012] §8); spp is the total over all views"))
    n_lines: Optional[int] = Field(None, description=(
        "Lines only (samples.kind lines, algorithm lines): line samples per pixel ([Tzeng 2012] §3); default 16"))
    wheel: Optional[int] = Field(None, description=(
        "Lines only: lines per wagon wheel sharing one screen point; default sim.sample_table.LINE_WHEEL (2, "
        "chosen by the wheel sweep of the methods page)"))


def _spec_type(spec):
    """The pydantic type of one parameter declaration (sim/engine/core/params.def): named choices
    become Literals, so a wrong value fails at load naming the key, file and line."""
    from sim import params

    if spec.kind == "group":
        types = {m.py_type for m in spec.members}
        if spec.keys == "all" and len(types) == 1:
            return dict[Literal[tuple(m.key for m in spec.members)], types.pop()]
        return dict
    names = spec.choices if spec.choices is not None else (
        spec.values if spec.type == "str" and spec.values is not None else None)
    if names is not None:
        return Literal[tuple(names)]
    base = params.PY_TYPES[spec.type]
    if spec.sentinel == ("auto",):
        return Union[base, Literal["auto"]]
    if spec.sentinel == (None,):
        return Optional[base]
    return base


def _pipeline_model() -> type[BaseModel]:
    """The pipeline section, generated from the parameter declaration through sim.PipelineConfig."""
    from sim import params

    specs = {spec.name: spec for spec in params.layer("pipeline")}
    fields = {}
    for name, info in sim.PipelineConfig.field_docs().items():
        unit = f" [{info['unit']}]" if info["unit"] else ""
        fields[name] = (_spec_type(specs[name]), Field(info["default"], description=info["doc"] + unit))
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
                        "out keep their defaults; validated by sim.HardwareConfig.")


class PlotSpec(_Strict):
    """One figure or table of a report page (docs/reports.md)."""

    kind: Literal["line", "bar", "table", "scatter", "heatmap", "image_grid", "image"] = Field(
        "line", description="line | bar | table | scatter | heatmap | image_grid | image")
    map: Optional[str] = Field(None, description=(
        "heatmap only: a per-pixel map (sim.pixel_stats: raster.samples_tested, ops.total, tile.culled_H, ...) "
        "or 'tile.cull_reason' of the one point left by where: (one panel per facet value), kept in the "
        "result store by the render of its sweep point; then x, row and y are not needed"))
    x: Optional[str] = Field(None, description=(
        "Column on the x axis (table: the row key; heatmap and image_grid: the column whose values make the "
        "columns)"))
    y: Union[str, list[str]] = Field("", description=(
        "Column(s) on the y axis (table: the value columns; heatmap: the cell value; image_grid: the value "
        "written under each image)"))
    row: Optional[str] = Field(None, description=(
        "heatmap and image_grid: the column whose values make the rows"))
    hue: Optional[Union[str, list[str]]] = Field(None, description=(
        "Column whose values get one line/bar colour (table: one column each); a list of columns combines "
        "their values with spaces ('tile 1')"))
    style: Optional[str] = Field(None, description="scatter only: column whose values get one marker shape each")
    facet: Optional[str] = Field(None, description="Column whose values get one panel each")
    where: dict[str, Any] = Field(default_factory=dict, description=(
        "Equality filter {column: value or [values]}; null matches a missing value"))
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
    echo: bool = Field(False, description="table only: also print the table on the terminal when the page is written")
    optional: bool = Field(False, description=(
        "Leave the plot out (silently) when a column it names is missing, e.g. timing.cycles where the point "
        "kind does not produce it"))

    @model_validator(mode="after")
    def _check(self):
        if self.kind in ("line", "bar", "scatter") and self.x is None:
            raise ValueError(f"a {self.kind} plot needs x")
        if self.map is not None and self.kind != "heatmap":
            raise ValueError("map: only for heatmap plots")
        if self.kind in ("heatmap", "image_grid") and self.map is None and (self.x is None or self.row is None):
            raise ValueError(f"a {self.kind} plot needs x and row")
        if self.kind not in ("image",) and self.map is None and not self.y:
            raise ValueError(f"a {self.kind} plot needs y")
        if self.row is not None and self.kind not in ("heatmap", "image_grid"):
            raise ValueError("row: only for heatmap and image_grid plots")
        if self.echo and self.kind != "table":
            raise ValueError("echo: only for table plots")
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
    (experiments/run/references.py, experiments/run/metrics.py). Adds columns metric.rmse, metric.psnr,
    metric.ssim, metric.ghosting (and metric.flip)."""

    reference_spp: int = Field(1024, description="Samples per pixel of the reference image (>= 1024 for reports)")
    reference_kind: ReferenceKind = Field(
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
    page: Optional[str] = Field(None, description=(
        "Report page name: reports/<folder>/<page>.md (configs may share a page)"))
    folder: str = Field("paper", description="Folder of the page under reports/")
    title: Optional[str] = Field(None, description="Section title on the page")
    text: Optional[str] = Field(None, description=(
        "Markdown above the figures: what, how, departures, caveats; every figure in it is a placeholder filled "
        "from the page's data ({column[key=value]:.2f}, docs/reports.md §Prose)"))
    summary: Optional[str] = Field(None, description=(
        "The section's result in a few sentences, a template like text: printed at the top of the section and "
        "gathered into the README's Results section with a link to the page"))
    derived: dict[str, str] = Field(default_factory=dict, description=(
        "New columns: pandas expressions over result columns (dotted names allowed), e.g. "
        "'shade.quad_requests / raster.samples_hit'"))
    column_labels: dict[str, str] = Field(default_factory=dict, description=(
        "Human labels with units for columns on axes, legends and panel titles {column: 'label [unit]'}, "
        "e.g. {mcycles: 'estimated frame time [Mcycles]'}; counters and config keys take theirs from their "
        "declarations, a derived 'counter / 1e6' its counter's with the prefix"))
    plots: list[PlotSpec] = Field(default_factory=list, description="Figures and tables (see the plot keys below)")
    order: int = Field(0, description="Position of this config's section on a shared page (ascending)")


class ExecutorSpec(_Strict):
    """Where the points of a sweep run (the command line's --workers / --scheduler take precedence)."""

    kind: Literal["local", "dask"] = Field("local", description="local process pool or a Dask distributed cluster")
    workers: Optional[int] = Field(None, description="local: worker processes (default: the core count)")
    address: Optional[str] = Field(None, description="dask: scheduler address, e.g. tcp://host:8786")
    point_timeout_s: Optional[float] = Field(None, description=(
        "seconds one point may run; a point running longer is stopped and stored as an error row naming this "
        "key (each point then runs in a child process of its worker, killed at the timeout; docs/store.md). "
        "Default: no limit"))
    connect_timeout_s: float = Field(30.0, description=(
        "dask: seconds to wait for the scheduler to answer (at the start, or after the connection is lost) "
        "before the run stops with an error naming it"))

    @model_validator(mode="after")
    def _check(self):
        if self.kind == "dask" and not self.address:
            raise ValueError("executor.kind 'dask' needs executor.address (or --scheduler ADDRESS)")
        if self.workers is not None and self.workers < 1:
            raise ValueError(f"executor.workers: expected >= 1, got {self.workers}")
        for key in ("point_timeout_s", "connect_timeout_s"):
            v = getattr(self, key)
            if v is not None and not v > 0:
                raise ValueError(f"executor.{key}: expected a number of seconds > 0, got {v!r}")
        return self


# point.options of kind 'precision' (experiments/run/precision.py): the study and its row.
PRECISION_OPTIONS = {"study": ("2d", "nd", "4d", "box", "5d", "render"), "viewport": None, "arithmetic": None,
                     "frac_bits": None, "cls": None}


class PointSpec(_Strict):
    """What one point of the sweep computes (docs/reports.md §Point kinds). `render` renders the scene;
    `occlusion_query` asks whether `query` is hidden behind the scene (sim.occlusion_query) and records
    the query's own work; `conservative` rasterizes the scene conservatively (sim.conservative_raster,
    1 x 1 tiles, per-pixel t-z boxes); `retime` re-times the stored work records of the render on the
    hardware `hardware` (sim.timing.estimate, no re-render when the records are in the result store);
    `timing_reference` measures the timing model against its cycle-stepped reference (sim.timing.reference)
    on the render's visit records, with the model on bin records beside it, and what each costs."""

    kind: Literal["render", "occlusion_query", "conservative", "retime", "timing_reference", "transparency", "sampler",
                  "soft_shadows", "caustics", "glossy", "precision"] = Field(
        "render", description=("render | occlusion_query | conservative | retime | timing_reference (the timing "
                               "model against its cycle-stepped reference on the same records) | a use of the rasterizer "
                               "(sim.uses.USES): transparency | sampler | soft_shadows | caustics | glossy | precision "
                               "(a row of the numerical-precision study, point.options: study, viewport, arithmetic, "
                               "frac_bits, cls)"))
    query: Optional[SceneSpec] = Field(None, description="occlusion_query: the query scene (the config's scene "
                                                         "is the occluders)")
    mode: QueryModeName = Field("samples", description=(
        "occlusion_query: 'samples' (test the query's samples) or 'intervals' (ẑ against HiZ, no sample tests)"))
    hardware: dict[str, Any] = Field(default_factory=dict, description=(
        "retime: hardware keys deep-merged over the config's hardware section for the timing estimate "
        "(the render itself uses the config's hardware)"))
    options: dict[str, Any] = Field(default_factory=dict, description=(
        "A use kind's options (keyword arguments of its sim.uses function, e.g. reference_spp); unknown "
        "keys are errors"))

    @model_validator(mode="after")
    def _check(self):
        if (self.kind == "occlusion_query") != (self.query is not None):
            raise ValueError("point.query: needed by kind 'occlusion_query' and only by it")
        if self.hardware and self.kind != "retime":
            raise ValueError("point.hardware: only for kind 'retime'")
        from sim import uses

        if self.kind == "precision":
            unknown = sorted(set(self.options) - set(PRECISION_OPTIONS))
            if unknown:
                raise ValueError(f"point.options: unknown {unknown} for kind 'precision' (known: "
                                 f"{', '.join(PRECISION_OPTIONS)})")
            study = self.options.get("study")
            if study not in PRECISION_OPTIONS["study"]:
                raise ValueError(f"point.options.study: expected one of {', '.join(PRECISION_OPTIONS['study'])}, "
                                 f"got {study!r}")
        elif self.options and self.kind not in uses.USES:
            raise ValueError(f"point.options: only for the use kinds ({', '.join(uses.USES)}) and 'precision'")
        if self.kind in uses.USES:
            known = uses.use_options(self.kind)
            unknown = sorted(set(self.options) - set(known))
            if unknown:
                raise ValueError(f"point.options: unknown option {unknown[0]!r} for kind {self.kind!r} "
                                 f"(known: {', '.join(sorted(known))})")
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
    point: PointSpec = Field(default_factory=PointSpec, description="What each point computes (default: a render)")
    outputs: OutputsSpec = Field(default_factory=OutputsSpec, description="Files, metrics and the report spec")
    executor: ExecutorSpec = Field(default_factory=ExecutorSpec, description="Where the points run")
    _auto_bin_size: bool = PrivateAttr(False)

    @model_validator(mode="after")
    def _resolve_bin_size(self):
        """pipeline.bin_size 'auto' as the render resolves it (sim.pipeline.resolved_bin_size), so a point's hash
        and row hold the bin size it is rendered with."""
        if self.pipeline.bin_size == "auto":
            from sim.pipeline import resolved_bin_size

            self.pipeline.bin_size = resolved_bin_size(self.pipeline.sample_fraction, self.pipeline.hinterleave_tile)
            self._auto_bin_size = True  # a sweep resolves it again per point (sweep.expand_sweep)
        return self

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

    def retime_hardware(self) -> "sim.HardwareConfig":
        """The hardware of a retime point: the hardware section with point.hardware merged over it."""
        return sim.HardwareConfig.from_dict(deep_merge(self.hardware_config().describe(), self.point.hardware))


def deep_merge(base: dict, over: dict) -> dict:
    """Mappings merge key by key; any other value in ``over`` replaces the base's."""
    out = copy.deepcopy(base)
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def _drop_none(d):
    if isinstance(d, dict):
        return {k: _drop_none(v) for k, v in d.items() if v is not None}
    return d


# ---- validation ----------------------------------------------------------------------------------

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
            out.append(f"{where}: unknown key {dotted!r}{_did_you_mean(str(loc[-1]), _known_keys(loc[:-1]))}")
        else:
            msg = e["msg"].removeprefix("Value error, ")
            hint = ""
            if e["type"] == "literal_error" and isinstance(e.get("input"), str):
                hint = _did_you_mean(e["input"], re.findall(r"'([^']*)'", e.get("ctx", {}).get("expected", "")))
            out.append(f"{where}: {dotted}: {msg} (got {e.get('input')!r}){hint}")
    return "\n".join(dict.fromkeys(out))


def _known_keys(loc: tuple) -> list[str]:
    """The keys the schema accepts at a location (a path of keys and list indices), or []."""
    model: Any = RenderConfig
    for part in loc:
        if isinstance(part, int):
            continue
        fields = getattr(model, "model_fields", None)
        if not fields or part not in fields:
            return []
        ann = fields[part].annotation
        candidates = [ann, *typing.get_args(ann)]
        candidates += [a for c in candidates for a in typing.get_args(c)]  # list[PlotSpec], Optional[...]
        model = next((c for c in candidates if isinstance(c, type) and issubclass(c, BaseModel)), None)
        if model is None:
            return []
    return list(getattr(model, "model_fields", {}))


def _did_you_mean(word: str, known: list[str]) -> str:
    """'; did you mean 'x'?' for the closest known word (difflib), or ''."""
    close = difflib.get_close_matches(word, known, n=2, cutoff=0.6)
    return f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""


def validate_model(data: dict, source: str = "config", lines: dict | None = None) -> RenderConfig:
    """The RenderConfig of a merged config dict; ConfigError naming file, line, key and value. The
    columns its outputs name are checked by experiments.config.validate (columns.py), once per config
    (not per sweep point)."""
    try:
        config = RenderConfig.model_validate(data)
    except ValidationError as e:
        raise ConfigError(_format_validation(e, source, lines)) from None
    try:
        config.hardware_config()
    except sim.ConfigError as e:
        where = lines.get(("hardware",), source) if lines else source
        raise ConfigError(f"{where}: hardware: {e}") from None
    if config.point.hardware:
        try:
            config.retime_hardware()
        except sim.ConfigError as e:
            where = lines.get(("point", "hardware"), source) if lines else source
            raise ConfigError(f"{where}: point.hardware: {e}") from None
    return config
