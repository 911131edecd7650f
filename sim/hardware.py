"""HardwareConfig: the modelled hardware (units of the timing model, caches, the sample buffers and
DRAM), validated on construction. Every parameter is declared once, with a unit and a description:
the texture cache, the depth and colour buffers and DRAM in params.def (sim/engine/core/params.def),
the timing model's pipeline units here; the YAML ``hardware:`` section (experiments/config/schema.py)
and docs/config.md are generated from them.

Throughputs are work items per clock in each unit's own currency (triangles, tile tests, sample
tests, depth tests, quads, texel fetches); latencies are in clocks; FIFO depths in entries.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from . import params
from .errors import ConfigError, check_float, check_int, field_docs


@dataclass(frozen=True)
class UnitConfig:
    """One pipeline unit of the timing model (docs/timing.md)."""

    throughput: float = field(default=1.0, metadata={
        "unit": "items/clock", "doc": "Work items the unit accepts per clock (its own currency)"})
    latency_cycles: int = field(default=4, metadata={
        "unit": "clocks", "doc": "Clocks from accepting an item to handing it to the next unit"})
    fifo_entries: int = field(default=32, metadata={
        "unit": "entries", "doc": "Depth of the unit's input FIFO"})

    def validate(self, owner: str) -> None:
        check_float(owner, "throughput", self.throughput, lo=0.0, lo_open=True, hi=1e6)
        check_int(owner, "latency_cycles", self.latency_cycles, 0, 1_000_000)
        check_int(owner, "fifo_entries", self.fifo_entries, 1, 1_000_000)


def _declared_section(name: str):
    """Give ``cls`` one dataclass field per row of the params.def group ``name`` of the hardware
    layer (names, types, defaults, units and docs), in declaration order; its ``validate`` checks
    each value against its declared domain, then calls ``cls._check_across_fields``."""
    group = next(s for s in params.layer("hardware") if s.name == name)

    def wrap(cls):
        cls.section_doc = group.doc

        def validate(self, owner: str) -> None:
            params.check_declared(self, owner)
            self._check_across_fields(owner)

        cls.validate = validate
        return params.declare(cls, group.members, name=lambda spec: spec.key)

    return wrap


@_declared_section("tex_cache")
class TextureCacheConfig:
    """A set-associative texture cache (one per texture unit). Fields: the ``tex_cache`` rows of
    params.def (sim/engine/core/params.def)."""

    def _check_across_fields(self, owner: str) -> None:
        """What one declaration row cannot say: a power-of-two line and whole sets."""
        if self.line_bytes & (self.line_bytes - 1):
            raise ConfigError(f"{owner}.line_bytes: expected a power of two, got {self.line_bytes}")
        lines = self.size_bytes // self.line_bytes
        if self.size_bytes % self.line_bytes or (self.ways and lines % self.ways):
            raise ConfigError(f"{owner}.size_bytes: {self.size_bytes} is not a whole number of sets of "
                              f"{self.ways} x {self.line_bytes}-byte lines")


@_declared_section("depth_buffer")
class DepthBufferConfig:
    """The per-sample depth buffer in DRAM behind a depth-tile cache (docs/memory.md). Fields: the
    ``depth_buffer`` rows of params.def (sim/engine/core/params.def)."""

    def _check_across_fields(self, owner: str) -> None:
        """A power-of-two line, whole sets, and compression only of the cache's lines."""
        if self.line_bytes & (self.line_bytes - 1):
            raise ConfigError(f"{owner}.line_bytes: expected a power of two, got {self.line_bytes}")
        if self.cache_bytes % (self.line_bytes * (self.cache_ways or 1)):
            raise ConfigError(f"{owner}.cache_bytes: {self.cache_bytes} is not a whole number of sets of "
                              f"{self.cache_ways} x {self.line_bytes}-byte lines")
        if self.compression != "none" and not self.enabled:
            raise ConfigError(f"{owner}.compression: {self.compression!r} compresses the depth-tile cache's lines, "
                              f"and {owner}.enabled is false (every sample goes to DRAM uncompressed): set "
                              "compression 'none' or enable the depth buffer")


@_declared_section("color_buffer")
class ColorBufferConfig:
    """The per-sample colour (MSAA) buffer in DRAM behind a colour-tile cache, resolved per screen bin
    (docs/memory.md). Fields: the ``color_buffer`` rows of params.def. Its lines hold the samples of
    one depth-buffer line (HardwareConfig checks the cache's sets against depth_buffer.line_bytes)."""

    def _check_across_fields(self, owner: str) -> None:
        pass


@_declared_section("dram")
class DramConfig:
    """DRAM, shared by every client: depth, colour, texture and HiZ traffic (docs/memory.md,
    docs/timing.md). Fields: the ``dram`` rows of params.def."""

    def _check_across_fields(self, owner: str) -> None:
        pass


TIMING_GRANULARITIES = ("bin", "visit")
IDLE_UNITS = ("bypass", "traverse")


@dataclass(frozen=True)
class TimingRecordsConfig:
    """Whether the timing and memory model runs, and what one of its work records covers
    (docs/timing.md)."""

    enabled: bool = field(default=True, metadata={
        "doc": "Run the timing and memory model on every render (sim.render(timing=...) and the command "
               "line's --no-timing override it); off, the timing.*, dram.*, depth.cache.* and color.* "
               "figures are absent"})
    granularity: str = field(default="visit", metadata={
        "doc": "Timing records: 'bin' (one per triangle and 64-px screen bin) or 'visit' (one per shading "
               "visit: per triangle and tile for tile and laine, per pass for interval and interleave, per "
               "triangle and bin for bruteforce); finer records cost simulator time"})

    idle_units: str = field(default="bypass", metadata={
        "doc": "A record with no work for a unit: 'bypass' (passes it at once, in order: no latency, no FIFO "
               "slot, as a visit with no quads sends nothing to the shader) or 'traverse' (passes through "
               "every unit's latency and FIFO, carrying the triangle's state down the pipe)"})

    def validate(self, owner: str) -> None:
        if self.idle_units not in IDLE_UNITS:
            raise ConfigError(f"{owner}.idle_units: expected 'bypass' or 'traverse', got {self.idle_units!r}")
        if not isinstance(self.enabled, bool):
            raise ConfigError(f"{owner}.enabled: expected a bool, got {self.enabled!r}")
        if self.granularity not in TIMING_GRANULARITIES:
            raise ConfigError(f"{owner}.granularity: expected 'bin' or 'visit', got {self.granularity!r}")


_UNIT_DEFAULTS = {
    # unit: (throughput, latency, fifo, currency)
    # The conventional-GPU units (gpu_* algorithms; docs/gpu.md): a GeForce 8800-class part, 128
    # scalar lanes shared by the geometry and pixel shaders' ALU work, 16 pixels per clock of 2D
    # rasterization, 32 floats per clock from the geometry shader. Zero latency: records of the
    # other algorithms (no work in these units) pass through them unchanged.
    "geometry_shader": (128.0, 0, 64, "ops"),
    "gs_output": (32.0, 0, 64, "floats"),
    "raster2d": (16.0, 0, 64, "pixels"),
    "pixel_shader": (128.0, 0, 64, "ops (lanes)"),
    "setup": (1.0, 16, 16, "triangles"),
    "tile_test": (4.0, 4, 32, "tile tests"),
    "sample_test": (64.0, 4, 64, "sample tests (lanes)"),
    "depth": (32.0, 8, 64, "depth tests"),
    "shader": (1.0, 64, 32, "quads"),
    "texture": (4.0, 8, 64, "texel fetches"),
}


def _unit(name: str):
    tp, lat, fifo, currency = _UNIT_DEFAULTS[name]
    return field(default_factory=lambda: UnitConfig(tp, lat, fifo),
                 metadata={"doc": f"{name} unit; throughput in {currency} per clock", "section": True})


@dataclass(frozen=True)
class HardwareConfig:
    """The modelled hardware. Nested sections accept dicts (``HardwareConfig.from_dict``)."""

    clock_ghz: float = field(default=1.0, metadata={"unit": "GHz", "doc": "Clock frequency (for times in seconds)"})
    geometry_shader: UnitConfig = _unit("geometry_shader")
    gs_output: UnitConfig = _unit("gs_output")
    raster2d: UnitConfig = _unit("raster2d")
    pixel_shader: UnitConfig = _unit("pixel_shader")
    setup: UnitConfig = _unit("setup")
    tile_test: UnitConfig = _unit("tile_test")
    sample_test: UnitConfig = _unit("sample_test")
    depth: UnitConfig = _unit("depth")
    shader: UnitConfig = _unit("shader")
    texture: UnitConfig = _unit("texture")
    tex_cache: TextureCacheConfig = field(default_factory=TextureCacheConfig, metadata={
        "doc": TextureCacheConfig.section_doc, "section": True})
    depth_buffer: DepthBufferConfig = field(default_factory=DepthBufferConfig, metadata={
        "doc": DepthBufferConfig.section_doc, "section": True})
    color_buffer: ColorBufferConfig = field(default_factory=ColorBufferConfig, metadata={
        "doc": ColorBufferConfig.section_doc, "section": True})
    dram: DramConfig = field(default_factory=DramConfig, metadata={
        "doc": DramConfig.section_doc, "section": True})
    cores: int = field(default=1, metadata={
        "unit": "pipelines", "doc": "Timing model: parallel pipelines; screen bins are dealt round-robin, "
                                    "DRAM bandwidth is split evenly (docs/timing.md)"})
    timing: TimingRecordsConfig = field(default_factory=TimingRecordsConfig, metadata={
        "doc": TimingRecordsConfig.__doc__, "section": True})

    def __post_init__(self):
        # Nested sections: a dict completes the section's own defaults; each section validates itself.
        for f in dataclasses.fields(self):
            if not f.metadata.get("section"):
                continue
            default, value, owner = f.default_factory(), getattr(self, f.name), f"HardwareConfig.{f.name}"
            if isinstance(value, dict):
                _check_keys(type(default), owner, value)
                value = dataclasses.replace(default, **value)
                object.__setattr__(self, f.name, value)
            if not isinstance(value, type(default)):
                raise ConfigError(f"{owner}: expected a {f.name} section, got {value!r}")
            value.validate(owner)
        check_float("HardwareConfig", "clock_ghz", self.clock_ghz, lo=0.0, lo_open=True, hi=1e3)
        check_int("HardwareConfig", "cores", self.cores, 1, 4096)
        # A colour line holds the samples of a depth-buffer line: whole sets of those.
        c, samples = self.color_buffer, self.depth_buffer.line_bytes // 4
        line = samples * c.bytes_per_sample
        if c.cache_bytes % (line * (c.cache_ways or 1)):
            raise ConfigError(f"HardwareConfig.color_buffer.cache_bytes: {c.cache_bytes} is not a whole number of "
                              f"sets of {c.cache_ways} x {line}-byte lines ({samples} samples of "
                              f"{c.bytes_per_sample} bytes: depth_buffer.line_bytes / 4)")

    @classmethod
    def from_dict(cls, d: dict | None) -> "HardwareConfig":
        d = d or {}
        _check_keys(cls, "HardwareConfig", d)
        return cls(**d)

    @classmethod
    def field_docs(cls) -> dict[str, dict]:
        """{field: {"default", "unit", "doc", "fields"?}}; nested sections carry their own fields."""
        return field_docs(cls)

    def describe(self) -> dict:
        return dataclasses.asdict(self)


def _check_keys(cls, owner: str, d) -> None:
    """ConfigError unless d is a mapping of cls's field names (naming the first unknown key)."""
    if not isinstance(d, dict):
        raise ConfigError(f"{owner}: expected a mapping, got {d!r}")
    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(d) - known)
    if unknown:
        raise ConfigError(f"{owner}: unknown key {unknown[0]!r} (known: {', '.join(sorted(known))})")
