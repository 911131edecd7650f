"""PipelineConfig: the rasterizer's algorithm and hardware switches, validated on construction."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from . import _core
from .errors import ConfigError, check_float, check_int, field_docs

_OWNER = "PipelineConfig"
# Choices whose order is the engine's enum order (params.h): render.py passes their indices.
SHADING_MODES = ("per_sample", "msaa", "per_lens_cell", "cache", "none")
TEXTURE_FILTERS = ("bilinear", "trilinear")
TEXTURE_LAYOUTS = ("linear", "blocked", "morton")


def algorithm_names() -> list[str]:
    """Names of the registered traversal algorithms."""
    return [name for name, _desc, _inter in _core.algorithms()]


def algorithm_docs() -> dict[str, str]:
    return {name: desc for name, desc, _inter in _core.algorithms()}


@dataclass(frozen=True)
class PipelineConfig:
    """What the rasterizer does. Every field is validated; bad values raise ConfigError.
    Field documentation: ``PipelineConfig.field_docs()`` and docs/config.md."""

    algorithm: str = field(default="bruteforce", metadata={
        "doc": "Traversal algorithm: one of sim.algorithm_names()"})
    threads: int = field(default=0, metadata={
        "doc": "Worker threads; 0 = all hardware threads (results are identical for any count)"})
    tile_size: int = field(default=2, metadata={
        "unit": "px", "doc": "Screen tile edge for tile-based algorithms: 1, 2, 4 or 8"})
    lens_grid: int | str = field(default="auto", metadata={
        "doc": "G of the G x G lens-grid cells (1, 2, 4, 8, 16) or 'auto' (4; 8 at >= 256 spp)"})
    halfspace: dict = field(default_factory=lambda: {"h": True, "H": True}, metadata={
        "doc": "{h: bool, H: bool}: use the h_i / H_j half-space lines (001 Table 2 modes)"})
    selective_H: bool = field(default=True, metadata={
        "doc": "001 Appendix A oracle: disable H_j lines on edges where they are not expected to pay"})
    oracle: str = field(default="simplified", metadata={
        "doc": "Oracle estimate: 'simplified' (001 Eq. 15, the paper's) or 'full' (Eq. 11-12)"})
    c_sample: float | None = field(default=None, metadata={
        "unit": "ops", "doc": "Oracle C_sample; null = the documented 4D sample-test cost"})
    c_tile: float | None = field(default=None, metadata={
        "unit": "ops", "doc": "Oracle C_tile (one edge's H_j lines vs one tile); null = documented"})
    backface_cull: bool = field(default=False, metadata={"doc": "Cull back-facing triangles"})
    op_count: str = field(default="documented", metadata={
        "doc": "'documented' (charge each kernel's documented cost) or 'exact' (counting scalar type)"})
    count_optimal: bool = field(default=True, metadata={
        "doc": "Instrument tile.samples_optimal (exact lens region per tile; 001 Table 1)"})
    hinterleave_tile: int = field(default=8, metadata={
        "unit": "px", "doc": "HINTERLEAVE tile edge: 4, 8 or 16"})
    bin_size: int = field(default=64, metadata={
        "unit": "px", "doc": "Screen bin edge for threading (multiple of 8 and of hinterleave_tile)"})
    memory_limit_bytes: int = field(default=4 << 30, metadata={
        "unit": "bytes", "doc": "Refuse renders whose memory estimate exceeds this"})
    # ---- shading and texturing (issue 6 part A; docs/shading.md) ----
    shading: str = field(default="none", metadata={
        "doc": "What costs a shader lane: 'per_sample' (supersampling), 'msaa' (one per pixel per visit), "
               "'per_lens_cell' (one per pixel and lens-grid cell per visit), 'cache' (memoising "
               "shading cache, 002 §2) or 'none' (not modelled: no shade.*/tex.* counts, fastest); "
               "the image is the same in every mode"})
    shading_cache_entries: int = field(default=1024, metadata={
        "unit": "entries", "doc": "Shading cache (shading: cache): LRU entries, key (triangle, shading-grid point)"})
    shading_grid: int = field(default=1, metadata={
        "unit": "points/px", "doc": "Shading cache: shading-grid points per pixel edge (1 = pixel grid, 2 = 2x2 per pixel, ...)"})
    texture_count: int = field(default=0, metadata={
        "unit": "textures", "doc": "Textures read per shader lane, 0..4 (0: untextured, the vertex colour)"})
    texture_filter: str = field(default="trilinear", metadata={
        "doc": "'bilinear' (nearest mip level) or 'trilinear'; level of detail from analytic per-triangle derivatives"})
    texture_layout: str = field(default="blocked", metadata={
        "doc": "Texel layout in memory: 'linear' (row-major), 'blocked' (4x4 texel blocks) or 'morton' (4x4 blocks in Morton order)"})
    texture_source: str = field(default="auto", metadata={
        "doc": "Slot 0: 'auto' (the scene's texture, else procedural), 'scene' (untextured triangles stay so) or 'procedural'"})
    texture_procedural_size: int = field(default=512, metadata={
        "unit": "texels", "doc": "Edge of the procedural textures (square)"})
    texture_uv_scale: float = field(default=1.0, metadata={
        "unit": "1/world unit", "doc": "Planar uvs for triangles without a scene texture: texture repeats per world unit"})
    texture_sample_distribution: bool = field(default=False, metadata={
        "doc": "Also fetch the sample-distribution texture of 000 §5.3 (one texel per lane, 1:1 with pixels)"})
    # ---- issue 5: the 5D pipeline (docs/intervals.md) ----
    motion_test: str = field(default="intervals", metadata={
        "doc": "tile, moving triangles: 'intervals' (t̂ and lens sets per time sub-interval, samples "
               "indexed by time stratum) or 'bounds' (h_i lines over the shutter ends, no t̂)"})
    time_splits: int = field(default=1, metadata={
        "doc": "Time sub-intervals S per shutter (1, 2, 4, 8, 16): tile computes t̂ (and 5D lens sets) "
               "per sub-interval"})
    time_strata: int = field(default=8, metadata={
        "doc": "Time strata per lens cell in the sample-table index (1..64, a multiple of time_splits): "
               "tile walks only the strata that overlap t̂"})
    clip: dict = field(default_factory=dict, metadata={
        "doc": "User clip box {u: [lo, hi], v: [lo, hi], t: [lo, hi]} (002 §2; any subset): samples "
               "outside it are never hit, for every algorithm"})
    zhat: str = field(default="planes", metadata={
        "doc": "Depth interval per (triangle, tile): 'planes' (moving box + moving planes, 002 App. A) "
               "or 'vertex' (vertex min/max)"})
    zhat_stats: bool = field(default=False, metadata={
        "doc": "tile: compute the depth interval of every accepted pair and count its width "
               "(zcull.width_zhat, zcull.width_vertex)"})
    hiz: dict = field(default_factory=lambda: {"enabled": False, "tile_size": 8}, metadata={
        "doc": "{enabled: bool, tile_size: px}: per-tile zmin/zmax (HiZ) with zmax- and zmin-culling "
               "of (triangle, tile) pairs (tile algorithm); tile_size in 1, 2, 4, 8 and >= tile_size"})

    def __post_init__(self):
        names = algorithm_names()
        if not isinstance(self.algorithm, str) or self.algorithm not in names:
            raise ConfigError(f"{_OWNER}.algorithm: unknown {self.algorithm!r} (known: {', '.join(names)})")
        check_int(_OWNER, "threads", self.threads, 0, 1024)
        if self.tile_size not in (1, 2, 4, 8) or isinstance(self.tile_size, bool):
            raise ConfigError(f"{_OWNER}.tile_size: expected 1, 2, 4 or 8, got {self.tile_size!r}")
        if self.lens_grid != "auto" and (isinstance(self.lens_grid, bool) or self.lens_grid not in (1, 2, 4, 8, 16)):
            raise ConfigError(f"{_OWNER}.lens_grid: expected 1, 2, 4, 8, 16 or 'auto', got {self.lens_grid!r}")
        if not isinstance(self.halfspace, dict) or set(self.halfspace) - {"h", "H"}:
            raise ConfigError(f"{_OWNER}.halfspace: expected {{'h': bool, 'H': bool}}, got {self.halfspace!r}")
        hs = {"h": True, "H": True, **self.halfspace}
        for k, v in hs.items():
            if not isinstance(v, bool):
                raise ConfigError(f"{_OWNER}.halfspace.{k}: expected a bool, got {v!r}")
        object.__setattr__(self, "halfspace", hs)
        for name in ("selective_H", "backface_cull", "count_optimal", "texture_sample_distribution", "zhat_stats"):
            if not isinstance(getattr(self, name), bool):
                raise ConfigError(f"{_OWNER}.{name}: expected a bool, got {getattr(self, name)!r}")
        if self.oracle not in ("simplified", "full"):
            raise ConfigError(f"{_OWNER}.oracle: expected 'simplified' or 'full', got {self.oracle!r}")
        for name in ("c_sample", "c_tile"):
            if getattr(self, name) is not None:
                check_float(_OWNER, name, getattr(self, name), lo=0.0)
        if self.op_count not in ("documented", "exact"):
            raise ConfigError(f"{_OWNER}.op_count: expected 'documented' or 'exact', got {self.op_count!r}")
        if self.hinterleave_tile not in (4, 8, 16) or isinstance(self.hinterleave_tile, bool):
            raise ConfigError(f"{_OWNER}.hinterleave_tile: expected 4, 8 or 16, got {self.hinterleave_tile!r}")
        check_int(_OWNER, "bin_size", self.bin_size, 8, 4096)
        if self.bin_size % 8 or self.bin_size % self.hinterleave_tile:
            raise ConfigError(f"{_OWNER}.bin_size: expected a multiple of 8 and of hinterleave_tile, got {self.bin_size}")
        check_int(_OWNER, "memory_limit_bytes", self.memory_limit_bytes, 1 << 20, 1 << 50)
        for name, allowed in (("shading", SHADING_MODES), ("texture_filter", TEXTURE_FILTERS),
                              ("texture_layout", TEXTURE_LAYOUTS),
                              ("texture_source", ("auto", "scene", "procedural"))):
            if getattr(self, name) not in allowed:
                raise ConfigError(f"{_OWNER}.{name}: expected one of {', '.join(allowed)}, got {getattr(self, name)!r}")
        check_int(_OWNER, "shading_cache_entries", self.shading_cache_entries, 1, 1 << 24)
        check_int(_OWNER, "shading_grid", self.shading_grid, 1, 16)
        check_int(_OWNER, "texture_count", self.texture_count, 0, 4)
        check_int(_OWNER, "texture_procedural_size", self.texture_procedural_size, 1, 8192)
        check_float(_OWNER, "texture_uv_scale", self.texture_uv_scale, lo=0.0, lo_open=True, hi=1e6)
        self._validate_intervals()

    def _validate_intervals(self):
        """Time/lens intervals, clip box, depth intervals and HiZ (docs/intervals.md)."""
        if self.motion_test not in ("intervals", "bounds"):
            raise ConfigError(f"{_OWNER}.motion_test: expected 'intervals' or 'bounds', got {self.motion_test!r}")
        if isinstance(self.time_splits, bool) or self.time_splits not in (1, 2, 4, 8, 16):
            raise ConfigError(f"{_OWNER}.time_splits: expected 1, 2, 4, 8 or 16, got {self.time_splits!r}")
        if (isinstance(self.time_strata, bool) or self.time_strata not in (1, 2, 4, 8, 16, 32, 64)
                or self.time_strata % self.time_splits):
            raise ConfigError(f"{_OWNER}.time_strata: expected 1, 2, 4, ..., 64 and a multiple of time_splits "
                              f"({self.time_splits}), got {self.time_strata!r}")
        if not isinstance(self.clip, dict) or set(self.clip) - {"u", "v", "t"}:
            raise ConfigError(f"{_OWNER}.clip: expected {{u: [lo, hi], v: [lo, hi], t: [lo, hi]}}, got {self.clip!r}")
        clip = {}
        for axis, value in self.clip.items():
            if not isinstance(value, (list, tuple)) or len(value) != 2:
                raise ConfigError(f"{_OWNER}.clip.{axis}: expected [lo, hi], got {value!r}")
            lo = check_float(_OWNER, f"clip.{axis}[0]", value[0])
            hi = check_float(_OWNER, f"clip.{axis}[1]", value[1])
            if not lo <= hi:
                raise ConfigError(f"{_OWNER}.clip.{axis}: expected lo <= hi, got {list(value)!r}")
            clip[axis] = [lo, hi]
        object.__setattr__(self, "clip", clip)
        if self.zhat not in ("planes", "vertex"):
            raise ConfigError(f"{_OWNER}.zhat: expected 'planes' or 'vertex', got {self.zhat!r}")
        if not isinstance(self.hiz, dict) or set(self.hiz) - {"enabled", "tile_size"}:
            raise ConfigError(f"{_OWNER}.hiz: expected {{enabled: bool, tile_size: int}}, got {self.hiz!r}")
        hiz = {"enabled": False, "tile_size": 8, **self.hiz}
        if not isinstance(hiz["enabled"], bool):
            raise ConfigError(f"{_OWNER}.hiz.enabled: expected a bool, got {hiz['enabled']!r}")
        ts = hiz["tile_size"]
        if isinstance(ts, bool) or ts not in (1, 2, 4, 8) or ts < self.tile_size:
            raise ConfigError(f"{_OWNER}.hiz.tile_size: expected 1, 2, 4 or 8 and >= tile_size "
                              f"({self.tile_size}), got {ts!r}")
        object.__setattr__(self, "hiz", hiz)

    @classmethod
    def field_docs(cls) -> dict[str, dict]:
        """{field: {"default", "unit", "doc"}} for every field (the single declaration)."""
        return field_docs(cls)

    def resolved_lens_grid(self, spp: int) -> int:
        if self.lens_grid == "auto":
            return 8 if spp >= 256 else 4
        return int(self.lens_grid)

    def replace(self, **changes) -> "PipelineConfig":
        return dataclasses.replace(self, **changes)

    def describe(self) -> dict:
        return dataclasses.asdict(self)  # deep-copies the dict and list fields
