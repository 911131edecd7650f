"""PipelineConfig: the rasterizer's algorithm and hardware switches, validated on construction.

Its fields are the ``pipeline`` rows of params.def (sim/engine/core/params.def, read through
sim.params): names, types, defaults, units, docs and domains are declared there once. This module
adds only what a single row cannot say: the checks across fields and the lens-grid resolution."""
from __future__ import annotations

import copy
import dataclasses
import functools
import warnings

from . import _core, params
from .errors import ConfigError, UnreadParameterWarning, field_docs

_OWNER = "PipelineConfig"


# Screen bins of a whole-frame render (the threads' work units; the timing model's bin order) and of a
# sampled render (pipeline.sample_fraction < 1), whose strata the bins make: the largest bin size whose 95%
# intervals hold on the default scene at a quarter of its bins (reports/paper/sampling.md,
# configs/paper/sampling.yaml). pipeline.bin_size 'auto' (the default) picks one of them.
WHOLE_FRAME_BIN_SIZE = 64
SAMPLED_BIN_SIZE = 8


def resolved_bin_size(sample_fraction: float, hinterleave_tile: int = 8) -> int:
    """The bin size 'auto' stands for: WHOLE_FRAME_BIN_SIZE, or SAMPLED_BIN_SIZE when sample_fraction < 1 (at
    least HINTERLEAVE's tile, of which a bin is a multiple)."""
    return WHOLE_FRAME_BIN_SIZE if sample_fraction >= 1 else max(SAMPLED_BIN_SIZE, hinterleave_tile)


@dataclasses.dataclass(frozen=True)
class AlgorithmInfo:
    """What the traversal registry declares about an algorithm (sim/engine/traversal/traversal.h,
    one RAST5D_REGISTER_TRAVERSAL line per algorithm); code reads these facts, never the name."""

    name: str
    description: str
    samples: str  # "points" or "lines": the samples it tests
    tables: tuple[str, ...]  # the sample-table kinds (samples.kind) it accepts
    discrete_lens: bool  # it needs a table with discrete lens coordinates (interleaved, accumulation)
    depth_cull: bool  # it runs the depth-cull stage: reads pipeline.hiz, answers occlusion queries
    pipeline: str  # "sample" (the 5D sample pipeline) or "gpu" (a conventional GPU's: docs/gpu.md)

    @property
    def exact(self) -> bool:
        """Point-sample algorithms are exact: all render the same image from the same table."""
        return self.samples == "points"


@functools.lru_cache(maxsize=None)
def _registry() -> dict[str, AlgorithmInfo]:
    from .sample_table import SampleTable

    out = {}
    for name, facts in sorted(_core.algorithm_facts().items()):
        kind = facts["tables"]
        if kind == "lines":
            tables = ("lines",)
        elif kind == "interleaved":
            tables = tuple(SampleTable.generators(discrete_lens=True))
        else:
            tables = tuple(SampleTable.generators())
        out[name] = AlgorithmInfo(name, facts["description"], facts["samples"], tables, kind == "interleaved",
                                  bool(facts["depth_cull"]), facts["pipeline"])
    return out


def algorithm_info(name: str | None = None):
    """The registry's facts (AlgorithmInfo) about algorithm ``name``, or {name: AlgorithmInfo} of every
    registered algorithm. An unknown name is a ConfigError naming the known ones."""
    reg = _registry()
    if name is None:
        return dict(reg)
    if name not in reg:
        raise ConfigError(f"{_OWNER}.algorithm: unknown {name!r} (known: {', '.join(reg)})")
    return reg[name]


def algorithm_names(samples: str | None = None) -> list[str]:
    """Names of the registered traversal algorithms; ``samples="points"``: those that test point samples
    (the exact ones, which render the same image from the same point table), ``"lines"``: those that
    test line samples (they need SampleTable.lines)."""
    if samples not in (None, "points", "lines"):
        raise ConfigError(f"samples: expected 'points', 'lines' or None, got {samples!r}")
    return [n for n, info in _registry().items() if samples is None or info.samples == samples]


def line_algorithms() -> list[str]:
    """Names of the registered line-sample algorithms ([Tzeng 2012] §3-4): they need SampleTable.lines."""
    return algorithm_names("lines")


def algorithm_docs() -> dict[str, str]:
    return {name: info.description for name, info in _registry().items()}


def interleaved_algorithms() -> list[str]:
    """Names of the registered algorithms that need a table with discrete lens coordinates."""
    return [n for n, info in _registry().items() if info.discrete_lens]


# ---- parameters the render does not read -------------------------------------------------------------
# Each rule: (the fields, whether the render reads them, why not). A field that differs from its
# default where the render does not read it has no effect on the result: PipelineConfig warns by name
# (UnreadParameterWarning), and experiments' sweeps hash and store the point as if it were left at its
# default (experiments/config/sweep.py), so an identical result is not computed twice.
_UNREAD_RULES = (
    (("hiz.enabled", "hiz.tile_size"), lambda c, a: a.depth_cull,
     lambda c, a: f"algorithm {c.algorithm!r} has no depth-cull stage (sim.algorithm_info(name).depth_cull)"),
    (tuple(f"lines.{k}" for k in ("buffer_size", "min_weight", "occlusion", "merge", "merge_depth", "merge_color",
                                  "merge_gap", "tile_clip")),
     lambda c, a: a.samples == "lines",
     lambda c, a: f"algorithm {c.algorithm!r} tests point samples; pipeline.lines configures line samples"),
    (("gpu_constants", "gpu_payload_floats"), lambda c, a: a.pipeline == "gpu",
     lambda c, a: f"algorithm {c.algorithm!r} does not run the conventional-GPU pipeline (docs/gpu.md)"),
    (("sample_seed", "sample_split"), lambda c, a: c.sample_fraction < 1,
     lambda c, a: "sample_fraction is 1 (the whole frame: no bins are drawn)"),
    (("shading_cache_entries", "shading_grid"), lambda c, a: c.shading == "cache",
     lambda c, a: f"shading is {c.shading!r}; the shading cache is shading 'cache'"),
)


def _get(config, dotted: str):
    head, _, rest = dotted.partition(".")
    value = getattr(config, head)
    return value[rest] if rest else value


def unread_parameters(config: "PipelineConfig") -> dict[str, str]:
    """{dotted field: why} of the fields set away from their defaults that this configuration's render
    does not read (for example ``hiz.enabled`` under ``bruteforce``, which has no depth-cull stage)."""
    info = _registry().get(config.algorithm)
    if info is None:
        return {}
    defaults = _defaults()
    out = {}
    for fields, reads, why in _UNREAD_RULES:
        if reads(config, info):
            continue
        for f in fields:
            if _get(config, f) != _get(defaults, f):
                out[f] = why(config, info)
    return out


def without_unread(config: "PipelineConfig") -> "PipelineConfig":
    """config with every unread field (unread_parameters) back at its default: the configuration the
    render actually sees."""
    unread = unread_parameters(config)
    if not unread:
        return config
    defaults = _defaults()
    changes: dict = {}
    for f in unread:
        head, _, rest = f.partition(".")
        if rest:
            changes.setdefault(head, dict(getattr(config, head)))[rest] = copy.deepcopy(getattr(defaults, head)[rest])
        else:
            changes[head] = copy.deepcopy(getattr(defaults, head))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnreadParameterWarning)
        return dataclasses.replace(config, **changes)


class _Defaults:
    """The declared default of every PipelineConfig field, as attributes (no instance is built), made
    once per process: read them, do not change them (copy one before handing it to a config)."""

    def __init__(self):
        self._values = {f.name: f.default_factory() if f.default is dataclasses.MISSING else f.default
                        for f in dataclasses.fields(PipelineConfig)}

    def __getattr__(self, name):
        try:
            return self.__dict__["_values"][name]
        except KeyError:
            raise AttributeError(name) from None


@functools.lru_cache(maxsize=1)
def _defaults() -> _Defaults:
    return _Defaults()


def shading_modes() -> list[str]:
    """Names of the shading modes (the ``shading`` parameter), in engine order."""
    return params.choices("shading_modes")


def texture_filters() -> list[str]:
    """Names of the texture filters (``texture_filter``)."""
    return params.choices("texture_filters")


def texture_layouts() -> list[str]:
    """Names of the texel layouts (``texture_layout``)."""
    return params.choices("texture_layouts")


@functools.partial(params.declare, specs=params.layer("pipeline"))
class PipelineConfig:
    """What the rasterizer does. Every field is validated; bad values raise ConfigError.
    Field documentation: ``PipelineConfig.field_docs()`` and docs/config.md; the declaration is
    sim/engine/core/params.def."""

    def __post_init__(self):
        params.check_declared(self, _OWNER)
        if self.bin_size == "auto":  # resolved here, so every reader sees the bin size the render uses
            object.__setattr__(self, "bin_size", resolved_bin_size(self.sample_fraction, self.hinterleave_tile))
            object.__setattr__(self, "_auto_bin_size", True)
        self._check_across_fields()
        for field, why in unread_parameters(self).items():
            warnings.warn(f"{_OWNER}.{field} = {_get(self, field)!r} is not read: {why}; it has no effect",
                          UnreadParameterWarning, stacklevel=4)

    def _check_across_fields(self):
        """What one declaration row cannot say: constraints between fields."""
        if self.bin_size % 8 or self.bin_size % self.hinterleave_tile:
            raise ConfigError(f"{_OWNER}.bin_size: expected a multiple of 8 and of hinterleave_tile, got {self.bin_size}")
        if self.time_strata % self.time_splits:
            raise ConfigError(f"{_OWNER}.time_strata: expected a multiple of time_splits ({self.time_splits}), "
                              f"got {self.time_strata!r}")
        if self.hiz["tile_size"] < self.tile_size:
            raise ConfigError(f"{_OWNER}.hiz.tile_size: expected >= tile_size ({self.tile_size}), "
                              f"got {self.hiz['tile_size']!r}")

    @classmethod
    def field_docs(cls) -> dict[str, dict]:
        """{field: {"default", "unit", "doc"}} for every field (from the declaration)."""
        return field_docs(cls)

    def resolved_lens_grid(self, spp: int) -> int:
        if self.lens_grid == "auto":
            return 8 if spp >= 256 else 4
        return int(self.lens_grid)

    def replace(self, **changes) -> "PipelineConfig":
        """A copy with ``changes``; a bin size left at 'auto' is resolved again (a sampled copy of a whole-frame
        config gets the sampled bin size)."""
        if getattr(self, "_auto_bin_size", False) and "bin_size" not in changes:
            changes["bin_size"] = "auto"
        return dataclasses.replace(self, **changes)

    def describe(self) -> dict:
        return dataclasses.asdict(self)  # deep-copies the dict and list fields
