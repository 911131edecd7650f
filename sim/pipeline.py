"""PipelineConfig: the rasterizer's algorithm and hardware switches, validated on construction."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from . import _core
from .errors import ConfigError, check_float, check_int

_OWNER = "PipelineConfig"


def algorithm_names() -> list[str]:
    """Names of the registered traversal algorithms."""
    return [name for name, _desc, _inter in _core.algorithms()]


def algorithm_docs() -> dict[str, str]:
    return {name: desc for name, desc, _inter in _core.algorithms()}


@dataclass(frozen=True)
class PipelineConfig:
    """What the rasterizer does. Every field is validated; bad values raise ConfigError.

    algorithm        traversal algorithm, one of sim.algorithm_names() (default "bruteforce")
    threads          worker threads, 0 = all hardware threads; results are identical for any count
    tile_size        screen tile edge in pixels for tile-based algorithms: 1, 2, 4 or 8
    lens_grid        G of the G x G lens-grid cells, 1/2/4/8/16, or "auto" (4; 8 at >= 256 spp)
    halfspace        {"h": bool, "H": bool}: 001 Table 2 switches for the h_i and H_j lines
    selective_H      001 Appendix A oracle: disable H_j lines on edges where they do not pay
    oracle           "simplified" (Eq. 15, the paper's measurements) or "full" (Eq. 11-12)
    c_sample, c_tile oracle costs in ops (None: the documented 4D sample test / one H_j line)
    backface_cull    cull back-facing triangles (off by default)
    op_count         "documented" (fast: charge each kernel's documented cost) or "exact"
                     (run the kernels on the counting scalar type; slower; same numbers)
    count_optimal    instrument tile.samples_optimal (001 Table 1 denominator)
    bin_size         screen bin edge in pixels for threading (multiple of 8)
    memory_limit_bytes  refuse renders whose memory estimate exceeds this
    """

    algorithm: str = "bruteforce"
    threads: int = 0
    tile_size: int = 2
    lens_grid: int | str = "auto"
    halfspace: dict = field(default_factory=lambda: {"h": True, "H": True})
    selective_H: bool = True
    oracle: str = "simplified"
    c_sample: float | None = None
    c_tile: float | None = None
    backface_cull: bool = False
    op_count: str = "documented"
    count_optimal: bool = True
    hinterleave_tile: int = 8
    bin_size: int = 64
    memory_limit_bytes: int = 4 << 30

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
        for name in ("selective_H", "backface_cull", "count_optimal"):
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

    def resolved_lens_grid(self, spp: int) -> int:
        if self.lens_grid == "auto":
            return 8 if spp >= 256 else 4
        return int(self.lens_grid)

    def replace(self, **changes) -> "PipelineConfig":
        return dataclasses.replace(self, **changes)

    def describe(self) -> dict:
        d = dataclasses.asdict(self)
        d["halfspace"] = dict(self.halfspace)
        return d
