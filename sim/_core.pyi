"""Type stub for the rast5d engine (sim/bindings/module.cpp). Use the Python face (sim.render,
sim.Camera, sim.SampleTable, sim.PipelineConfig) rather than calling these directly."""
from typing import Any

import numpy as np
import numpy.typing as npt

class LensShape:
    square: LensShape
    disk: LensShape
    hexagon: LensShape

class RenderParams:
    """Engine parameters; see sim/include/rast5d/params.h. Vertices are pixel-homogeneous:
    X_h = (x_clip + w) * width / 2, Y_h = (w - y_clip) * height / 2, W = w."""
    width: int
    height: int
    coc_x_px: float  # shear coefficient for u in pixels (the CoC radius at infinity)
    coc_y_px: float  # shear coefficient for v (negative: rows grow downwards)
    focus_w: float
    near_w: float
    lens_shape: LensShape
    algorithm: str
    tile_size: int
    lens_grid: int
    hinterleave_tile: int
    threads: int
    bin_size: int
    halfspace_h: bool
    halfspace_H: bool
    selective_H: bool
    oracle_full: bool
    c_sample: float  # < 0: the documented 4D sample-test cost
    c_tile: float  # < 0: the documented cost of one edge's H_j lines against one tile
    backface_cull: bool
    exact_ops: bool
    count_optimal: bool
    table_has_lens: bool
    table_has_time: bool
    record_timing: bool  # record timing work records (Result.timing_records); docs/timing.md
    # shading, texturing, texture cache (issue 6; docs/shading.md)
    shading_mode: int  # 0 per_sample, 1 msaa, 2 per_lens_cell, 3 cache, 4 none
    shading_cache_entries: int
    shading_grid: int
    tex_count: int
    tex_filter: int  # 0 bilinear, 1 trilinear
    tex_layout: int  # 0 linear, 1 blocked 4x4, 2 Morton 4x4 blocks
    tex_sample_dist: int  # texture index of the sample-distribution texture, or -1
    tex_cache_bytes: int
    tex_cache_line_bytes: int
    tex_cache_ways: int  # 0 = fully associative
    tex_cache_count: int
    # issue 5 (docs/intervals.md)
    time_splits: int
    time_strata: int
    motion_intervals: bool
    clip_u_lo: float
    clip_u_hi: float
    clip_v_lo: float
    clip_v_hi: float
    clip_t_lo: float
    clip_t_hi: float
    zhat_planes: bool
    zhat_stats: bool
    hiz_enabled: bool
    hiz_tile: int
    query_first: int
    query_mode: int  # 0 none, 1 sample-based, 2 interval-based occlusion query
    def __init__(self) -> None: ...

def render(
    params: RenderParams,
    v0: npt.NDArray[np.float32],  # (N, 3, 3) pixel-homogeneous vertices at t = 0
    v1: npt.NDArray[np.float32],  # (N, 3, 3) at t = 1
    colors: npt.NDArray[np.float32],  # (N, 3, 3) linear RGB
    samples: npt.NDArray[np.float32],  # (P, P, spp, 5): x, y, u, v, t
    lens_index: npt.NDArray[np.int32],  # (P, P, spp) or empty
    lens_uv: npt.NDArray[np.float32],  # (N_lens, 2) or empty
    export_samples: bool = False,
    uvs: npt.NDArray[np.float32] | None = None,  # (N, 3, 2) texture coordinates (issue 6)
    tex_slots: npt.NDArray[np.int32] | None = None,  # (N, 4) texture index per slot, -1 unused
    textures: list[npt.NDArray[np.float32]] = ...,  # (H, W, 1..4) linear images
) -> dict[str, Any]:
    """Returns {'image': (H, W, 3) float32, 'counters': {name: int}}, with params.record_timing
    'timing_records' (timing_record_dtype(), culled triangles then bins in raster order) and, with export_samples,
    'sample_depth' (H, W, spp) float32 and 'sample_triangle' (H, W, spp) int32. Releases the GIL;
    Ctrl-C raises KeyboardInterrupt. Raises ValueError for invalid parameters."""

def lens_grid_buckets(
    samples: npt.NDArray[np.float32], grid: int
) -> tuple[npt.NDArray[np.int32], npt.NDArray[np.int32], npt.NDArray[np.int32]]:
    """(order (P,P,spp), counts (P,P,G*G), offsets (P,P,G*G)) of 001 Fig. 10."""

def probe(
    params: RenderParams,
    v0: npt.NDArray[np.float32],  # (3, 3) one triangle at t = 0
    v1: npt.NDArray[np.float32],  # (3, 3) at t = 1
    points: npt.NDArray[np.float32],  # (M, 5): absolute pixel x, y, then u, v, t
    force_general: bool = False,
) -> dict[str, Any]:
    """Exact sample test at arbitrary points: {'dim_class': int (0..3 = 2D, 3D, 4D, 5D; -1 culled
    near), 'covered', 'hit': bool (M,), 'depth': float32 (M,) z = 1 - near / w, 'w_hit': float32}."""

def counter_docs() -> dict[str, tuple[str, str]]: ...
def algorithms() -> list[tuple[str, str, bool]]: ...
def measure_kernel_costs(trials: int = 100, seed: int = 1) -> dict[str, tuple[int, int, int]]:
    """{kernel: (documented cost, min counted, max counted)} over random inputs."""
def measure_tile_kernel_costs(trials: int = 200, seed: int = 1) -> dict[str, tuple[int, int, int, int]]:
    """Tile-test kernels whose cost depends on the configuration: {name: (runs, mismatches between
    counted and documented, min documented, max documented)}."""

# ---- timing model (docs/timing.md) ----
def timing_record_dtype() -> np.dtype:
    """numpy structured dtype of one work record: bin (int32), triangles (uint32), tile_tests,
    sample_tests, depth_tests, quads, texel_fetches, tex_misses, memory_bytes (uint64)."""
def timing_units() -> list[tuple[str, str, str]]:
    """[(name, currency, description)] of the units in pipeline order."""
def timing_docs() -> dict[str, tuple[str, str]]:
    """{name: (unit, description)} of the figures timing_estimate returns."""
def timing_estimate(
    records: npt.NDArray[Any],  # timing_record_dtype()
    throughput: list[float],  # per unit, items/clock (> 0)
    latency: list[float],  # per unit, clocks (>= 0)
    fifo: list[int],  # per unit, input FIFO entries (>= 1)
    tex_hit_latency: float,
    tex_miss_latency: float,
    cores: int = 1,
) -> dict[str, float]:
    """Flat {'timing.cycles', 'timing.records', 'timing.cores', 'timing.<unit>.work',
    'timing.<unit>.busy_cycles', '...blocked_cycles', '...starved_cycles'}. ValueError for a bad config."""
# ---- issue 6: texture cache and texture unit (docs/shading.md) ----
def simulate_cache(lines: npt.NDArray[np.uint64], n_lines: int, ways: int) -> dict[str, Any]:
    """One set-associative LRU cache (ways 0 = fully associative) over a stream of line indices:
    {'accesses', 'hits', 'misses', 'cold', 'capacity', 'conflict': int, 'hit': bool (M,)}."""
def triangle_lod(v0: npt.NDArray[np.float32], uvs: npt.NDArray[np.float32], tex_width: int, tex_height: int,
                 near_w: float = 0.0) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float64]]:
    """Per-triangle level of detail and uv Jacobian (du/dx, du/dy, dv/dx, dv/dy) from the vertices
    projected through the lens centre at shutter open."""
def texel_address(height: int, width: int, layout: int, level: int, x: int, y: int) -> int:
    """Byte address of a texel of a lone texture (layout 0 linear, 1 blocked 4x4, 2 Morton blocks)."""
def conservative_raster(
    params: RenderParams,
    v0: npt.NDArray[np.float32],  # (N, 3, 3) engine vertices at t = 0
    v1: npt.NDArray[np.float32],  # (N, 3, 3) at t = 1
    reduce: bool,
    max_records: int,
) -> dict[str, Any]:
    """Conservative rasterization (issue 5): {'counters', 'records': uint8 bytes of (x, y, triangle,
    u_lo, u_hi, v_lo, v_hi, t_lo, t_hi, z_lo, z_hi) records, 'record_bytes'} or, with reduce,
    {'counters', 'tz_box': float32 (H, W, 4), 'count': int32 (H, W)}. ValueError past max_records."""
