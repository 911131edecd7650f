"""PipelineConfig: the rasterizer's algorithm and hardware switches, validated on construction.

Its fields are the ``pipeline`` rows of params.def (sim/engine/core/params.def, read through
sim.params): names, types, defaults, units, docs and domains are declared there once. This module
adds only what a single row cannot say: the checks across fields and the lens-grid resolution."""
from __future__ import annotations

import dataclasses
import functools

from . import _core, params
from .errors import ConfigError, field_docs

_OWNER = "PipelineConfig"


def algorithm_names() -> list[str]:
    """Names of the registered point-sample traversal algorithms: the exact ones, which render the
    same image from the same point table (line-sample algorithms: line_algorithms())."""
    lines = set(line_algorithms())
    return [name for name, _desc, _inter in _core.algorithms() if name not in lines]


def line_algorithms() -> list[str]:
    """Names of the registered line-sample algorithms (004 §3-4): they need SampleTable.lines."""
    return [name for name, _desc, _inter in _core.algorithms() if name == "lines" or name.startswith("lines_")]


def algorithm_docs() -> dict[str, str]:
    return {name: desc for name, desc, _inter in _core.algorithms()}


def interleaved_algorithms() -> list[str]:
    """Names of the registered algorithms that need an interleaved sample table."""
    return [name for name, _desc, inter in _core.algorithms() if inter]


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
        self._check_across_fields()

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
        return dataclasses.replace(self, **changes)

    def describe(self) -> dict:
        return dataclasses.asdict(self)  # deep-copies the dict and list fields
