"""Type stub for the rast5d engine (sim/bindings/*.cpp; one section per binding file). Use the
Python face (sim.render, sim.Camera, sim.SampleTable, sim.PipelineConfig) rather than calling these
directly."""
from typing import Any, Callable

import numpy as np
import numpy.typing as npt

# ---- params.cpp: the render parameters (core/params.def) and the registries by name ----
class RenderParams:
    """Engine parameters, declared in sim/engine/core/params.def; set them through sim.render.
    A choice parameter reads and writes its name (ValueError for an unknown one)."""
    # ---- generated from params.def by `python -m sim.gen_stub`: do not edit ----
    # camera: set from sim.Camera
    width: int  # Image width [px]; default 0
    height: int  # Image height [px]; default 0
    coc_x_px: float  # Shear coefficient for u: the circle-of-confusion radius at infinity [px]; default 0.0
    coc_y_px: float  # Shear coefficient for v (negative: image rows grow downwards, lens v points up) [px]; default 0.0
    focus_w: float  # F: view depth of the focus plane; default 1.0
    near_w: float  # Near plane: samples whose hit point has W < near_w are rejected; default 0.01
    lens_shape: str  # Lens aperture shape: the camera's lens (lens_shapes: disk, square, hexagon); default 'disk'
    # pipeline: from sim.PipelineConfig
    algorithm: str  # Traversal algorithm: one of sim.algorithm_names(); default 'bruteforce'
    threads: int  # Worker threads; 0 = all hardware threads (results are identical for any count); default 0
    tile_size: int  # Screen tile edge for tile-based algorithms: 1, 2, 4 or 8 [px]; default 2
    lens_grid: int  # G of the G x G lens-grid cells (1, 2, 4, 8, 16) or 'auto' (4; 8 at >= 256 spp); default 4
    halfspace_h: bool  # Use the h_i half-space lines; default True
    halfspace_H: bool  # Use the H_j half-space lines; default True
    halfspace_H5: bool  # tile, moving triangles (motion_test 'intervals'): the H_j lines extended to time, culling lens cells per tile over each t̂_k (docs/tile_tests.md H5); off by default; default False
    selective_H: bool  # [Akenine-Möller 2012] Appendix A oracle: disable H_j lines on edges where they are not expected to pay; default True
    oracle: str  # Oracle estimate: 'simplified' ([Akenine-Möller 2012] Eq. 15, the paper's) or 'full' (Eq. 11-12) (oracle_modes: simplified, full); default 'simplified'
    c_sample: float  # Oracle C_sample; null = the documented 4D sample-test cost of the cost model [ops]; default -1.0
    c_tile: float  # Oracle C_tile (one edge's H_j lines vs one tile); null = documented [ops]; default -1.0
    backface_cull: bool  # Cull back-facing triangles; default False
    op_count: str  # 'documented' (charge each kernel's documented cost) or 'exact' (counting scalar type) (op_counts: documented, exact); default 'documented'
    cost_model: str  # Operation cost model: 'robust' (float32 sample-relative edge functions, no FMA) or 'hardware' (fixed-point affine edge functions with FMA; 2D edges set up per triangle or lens position); the image is the same in both (cost_models: robust, hardware); default 'robust'
    count_optimal: bool  # Instrument tile.samples_optimal (exact lens region per tile; [Akenine-Möller 2012] Table 1); off by default: it costs more than the traversal it describes; default False
    simd: bool  # Fast path: the 4D/5D sample tests in explicit SIMD (bit-identical results and counts; false = the auto-vectorised kernels, for benchmarks); default True
    precision_tile: str | dict  # Tile tests: the 2D edge test (in-focus triangles of tile and tile_interleaved; hinterleave) and the 4D test (h_i sets, H_j cells, lens-box bounds, ẑ; tiletest/precision_4d.h): float64 (the default), float32 (2D: no extra margin, may lose samples; 4D: error-bounded), or fixed point on vertices and tile corners snapped to frac_bits sub-pixel bits (tiles widened by 2^(1 - frac_bits) px); default 'float64'
    precision_sample: str | dict  # Sample test decision: float32 (the default), float64, or fixed point on the vertices placed at the sample's (u, v, t) and projected, snapped with the sample to frac_bits sub-pixel bits; tile tests widen by 2^(1 - frac_bits) px to stay conservative; default 'float32'
    precision_depth: str | dict  # Stored sample depth z in [0, 1]: float32 (the default) or fixed point (z rounded to frac_bits fraction bits, frac_bits <= 24: a unorm depth buffer); float64 is refused (the buffer holds float32); default 'float32'
    hinterleave_tile: int  # HINTERLEAVE tile edge: 4, 8 or 16 [px]; default 8
    bin_size: int  # Screen bin edge for threading and for sampled simulation's strata (multiple of 8 and of hinterleave_tile); auto = 64, or sim.pipeline.SAMPLED_BIN_SIZE in a sampled render (sample_fraction < 1; chosen by the sampling page) [px]; default 64
    lines_buffer_size: int  # Segment-buffer capacity per line sample; 0 = unlimited ([Tzeng 2012] does not state its size; 8 overflows by 27% on modern_hall at CoC 40 and darkens it, 32 does not) [segments]; default 32
    lines_min_weight: float  # Drop segments that merged nowhere and whose κ weight (share of the line) is below this; 0 = off; default 0.0001
    lines_occlusion: bool  # Drop segments covered by a buffered segment entirely in front (and remove those an incoming segment hides); default True
    lines_merge: bool  # Merge a segment into a buffered one within the three thresholds; default True
    lines_merge_depth: float  # Merge: largest difference of midpoint depth z; default 0.001
    lines_merge_color: float  # Merge: largest Euclidean distance of linear RGB colours; default 0.05
    lines_merge_gap: float  # Merge: largest gap between the two intervals along the line (0: touching or overlapping); default 0.0
    lines_tile_clip: bool  # Skip line-triangle tests of lines that miss the tile's h_i lens region (the same image, but for float32 slivers of the line test outside the exact coverage on sub-pixel triangles: docs/op_costs.md); default False
    sample_fraction: float  # Sampled simulation: traverse this fraction of the screen bins that hold triangles (2 per stratum of bins with similar brute-force work), scale the counters to the frame and give 95% confidence half-widths (Result.ci95); 1 = the whole frame, exact; default 1.0
    sample_seed: int  # Seed of the sampled bins (sample_fraction < 1); default 0
    sample_split: float  # Sampled simulation: 0 = a bin heavier than a stratum's share of the brute-force work is traversed whole (a take-all stratum); s in (0, 1] = it is cut into units of its triangles of about s times a stratum's share each, drawn like bins; counters that depend on depth order are then not estimated (NaN); default 0.0
    shading: str  # What costs a shader lane: 'per_sample' (supersampling), 'msaa' (one per pixel per visit), 'per_lens_cell' (one per pixel and lens-grid cell per visit), 'cache' (memoising shading cache, [Nilsson 2012] §2) or 'none' (not modelled: no shade.*/tex.* counts, fastest); the image is the same in every mode (shading_modes: per_sample, msaa, per_lens_cell, cache, none); default 'none'
    shading_cache_entries: int  # Shading cache (shading: cache): LRU entries, key (triangle, shading-grid point) [entries]; default 1024
    shading_grid: int  # Shading cache: shading-grid points per pixel edge (1 = pixel grid, 2 = 2x2 per pixel, ...) [points/px]; default 1
    texture_count: int  # Textures read per shader lane, 0..4 (0: untextured, the vertex colour) [textures]; default 0
    texture_filter: str  # 'bilinear' (nearest mip level) or 'trilinear'; level of detail from analytic per-triangle derivatives (texture_filters: bilinear, trilinear); default 'trilinear'
    texture_layout: str  # Texel layout in memory: 'linear' (row-major), 'blocked' (4x4 texel blocks) or 'morton' (4x4 blocks in Morton order) (texture_layouts: linear, blocked, morton); default 'blocked'
    alpha_seed: int  # Seed of the per-sample random alpha masks (scenes with alpha: a covered sample of a triangle survives with probability alpha); default 0
    alpha_stratified: bool  # Alpha masks stratified over a pixel's samples (one random offset per pixel and triangle: floor or ceil of alpha x spp samples kept) instead of independent per sample; default False
    motion_test: str  # tile, moving triangles: 'intervals' (t̂ and lens sets per time sub-interval, samples indexed by time stratum) or 'bounds' (h_i lines over the shutter ends, no t̂) (motion_tests: intervals, bounds); default 'intervals'
    time_splits: int  # Time sub-intervals S per shutter (1, 2, 4, 8, 16): tile computes t̂ (and 5D lens sets) per sub-interval; default 1
    time_strata: int  # Time strata per lens cell in the sample-table index (1..64, a multiple of time_splits): tile walks only the strata that overlap t̂; default 8
    clip_u: list[float]  # Lens u range kept; default [-1.0, 1.0]
    clip_v: list[float]  # Lens v range kept; default [-1.0, 1.0]
    clip_t: list[float]  # Shutter time range kept; default [0.0, 1.0]
    zhat: str  # Depth interval per (triangle, tile): 'planes' (moving box + moving planes, [Nilsson 2012] App. A) or 'vertex' (vertex min/max) (zhat_modes: planes, vertex); default 'planes'
    zhat_margin: str  # Widening of ẑ before it is compared with float sample depths (HiZ, occlusion queries): 'derived' (each pair's rounding bound) or 'fixed' (12.5 % of W, for comparison) (zhat_margins: derived, fixed); default 'derived'
    zhat_stats: bool  # tile: compute the depth interval of every accepted pair and count its width (zcull.width_zhat, zcull.width_vertex); default False
    hiz_enabled: bool  # zmax/zmin culling against per-tile HiZ; default False
    hiz_tile_size: int  # HiZ tile edge (>= tile_size) [px]; default 8
    gpu_constants: str  # gpu_* algorithms: 'none' (data on every bounding vertex, setup re-derived per fragment), 'triangle' or 'strip' constants ([Toth 2008] §9.6) (gpu_constants: none, triangle, strip); default 'none'
    gpu_payload_floats: int  # gpu_* algorithms: floats of contained-triangle data per bounding vertex besides its 4 position floats; auto = 3 x (position 3, disc of confusion 1, colour 3) = 21, + 9 end positions when moving ([Toth 2008] Table 2's bump-mapped example: 35) [floats]; default -1
    gpu_adaptive_ratio: float  # gpu_adaptive: parallel-edge triangle when the largest confusion radius <= ratio x sqrt(projected area), else the 2D hexagon ([Toth 2008] §4.7); default 0.5
    # hardware: from sim.HardwareConfig
    tex_cache_size_bytes: int  # Capacity of one cache (a whole number of sets of ways x line_bytes) [bytes]; default 16384
    tex_cache_line_bytes: int  # Cache line size (a power of two) [bytes]; default 64
    tex_cache_ways: int  # Associativity; 0 = fully associative [ways]; default 4
    tex_cache_count: int  # Number of texture caches; screen bin b uses cache b mod count [caches]; default 1
    depth_buffer_enabled: bool  # Model the depth-tile cache and compression; false: every depth read and write goes to DRAM (4 bytes per sample, depth.bytes_read + depth.bytes_written); default True
    depth_buffer_cache_bytes: int  # Depth-tile cache capacity (a whole number of sets of cache_ways x line_bytes) [bytes]; default 1048576
    depth_buffer_cache_ways: int  # Depth-tile cache associativity, LRU; 0 = fully associative [ways]; default 4
    depth_buffer_line_bytes: int  # Depth-buffer line: the samples of a screen tile of the largest power-of-two edge (up to 8 px) whose samples fit (line_bytes / 4 samples); a power of two [bytes]; default 1024
    depth_buffer_compression: str  # Depth compression of lines written to DRAM: 'none', 'plane' (static-plane baseline) or 'time_predictor' (two layers of time-dependent predictors and delta residuals) (depth_compressions: none, plane, time_predictor); default 'time_predictor'
    depth_buffer_fast_clear: bool  # A line not written this frame is read as cleared from its tile-status bit, at no DRAM cost; default True
    color_buffer_enabled: bool  # Model the colour sample buffer (writes, fills, write-backs, the resolve); false: no colour traffic; default True
    color_buffer_cache_bytes: int  # Colour-tile cache capacity (a whole number of sets of cache_ways lines; a line holds the samples of one depth-buffer line) [bytes]; default 1048576
    color_buffer_cache_ways: int  # Colour-tile cache associativity, LRU; 0 = fully associative [ways]; default 4
    color_buffer_bytes_per_sample: int  # Bytes of one colour sample (and of one resolved pixel) [bytes]; default 4
    color_buffer_fast_clear: bool  # A line not written this frame is in the constant-colour (cleared) state: no DRAM read; default True
    dram_burst_bytes: int  # Smallest DRAM transfer: compressed depth lines are rounded up to it [bytes]; default 32
    # frame: set by sim.render for this render
    texture_sample_distribution_index: int  # Texture index of the sample-distribution texture (texture_sample_distribution), or -1; default -1
    table_has_lens: bool  # The sample table has lens coordinates (else u = v = 0 is exact); default True
    table_has_time: bool  # The sample table has time coordinates (else t = 0 is exact); default True
    record_timing: bool  # Run the timing and memory model on the render's work records (docs/timing.md); default True
    table_lines: bool  # The sample table holds line samples (SampleTable.lines): (x, y) a screen point, (u, v) the line direction; default False
    timing_per_visit: bool  # Timing records per shading visit instead of per (triangle, bin) (hardware.timing.granularity 'visit'); default False
    query_first: int  # Occlusion query: triangles from this index are the query (no writes); -1 none; default -1
    query_mode: str  # Occlusion query: 'none', 'samples' (sample-based) or 'intervals' (ẑ vs HiZ, abort) (query_modes: none, samples, intervals); default 'none'
    # ---- end of the generated fields ----
    def __init__(self) -> None: ...

def param_specs() -> list[dict[str, Any]]:
    """The parameter declaration (params.def), one dict per row in order: kind ('engine',
    'python' or 'group'), stage (the pipeline stage of its section), layer, name (user path),
    engine (RenderParams field or None), group, type, default, unit, domain, doc, choices; group
    rows: kind, stage, layer, name, keys, doc."""
def choices() -> dict[str, list[tuple[str, str]]]:
    """Registries by name (one per choice parameter, in declaration order): {'lens_shapes':
    [(name, description)], 'shading_modes': ..., 'query_modes': ..., ...}."""

# ---- render.cpp: the render, the sample-table buckets and the registries of the engine ----
class SampleTableIndex:
    """The engine's sample table with its (lens cell, time stratum) index, built once (immutable; it holds
    its own copy of the samples): pass it to render() as samples, with empty lens_index and lens_uv.
    sim.SampleTable.engine_index builds and caches one per (lens, grid, time_strata)."""
    def __init__(self, samples: npt.NDArray[np.float32], grid: int, time_strata: int,
                 lens_index: npt.NDArray[np.int32], lens_uv: npt.NDArray[np.float32]) -> None: ...
    @property
    def period(self) -> int: ...
    @property
    def spp(self) -> int: ...
    @property
    def grid(self) -> int: ...
    @property
    def time_strata(self) -> int: ...
    @property
    def n_lens(self) -> int: ...

def render(
    params: RenderParams,
    v0: npt.NDArray[np.float32],  # (N, 3, 3) pixel-homogeneous vertices at t = 0
    v1: npt.NDArray[np.float32],  # (N, 3, 3) at t = 1
    colors: npt.NDArray[np.float32],  # (N, 3, 3) linear RGB
    samples: npt.NDArray[np.float32] | SampleTableIndex,  # (P, P, spp, 5): x, y, u, v, t; or its index
    lens_index: npt.NDArray[np.int32],  # (P, P, spp) or empty (always empty with a SampleTableIndex)
    lens_uv: npt.NDArray[np.float32],  # (N_lens, 2) or empty
    export_samples: bool = False,
    uvs: npt.NDArray[np.float32] | None = None,  # (N, 3, 2) texture coordinates
    tex_slots: npt.NDArray[np.int32] | None = None,  # (N, 4) texture index per slot, -1 unused
    textures: list[npt.NDArray[np.float32]] = ...,  # (H, W, 1..4) linear images
    pixel_stats: list[str] = ...,  # counter names to map per pixel (sim.pixel_stats)
    trace_pixel: tuple[int, int] | None = None,  # (x, y): trace this pixel (counting path, its bin only)
    progress: Callable[[int, int], None] | None = None,  # (bins done, bins) every few ms
) -> dict[str, Any]:
    """Returns {'image': (H, W, 3) float32, 'counters': {name: int}}, with params.record_timing
    'timing_records' (timing_record_dtype(), culled triangles then bins in raster order) and, with export_samples,
    'sample_depth' (H, W, spp) float32 and 'sample_triangle' (H, W, spp) int32, with pixel_stats 'pixel_stats'
    (k, H, W) uint64, with trace_pixel 'trace_events' [(triangle, kind, (x0, y0, x1, y1), {counter: n})] and
    'trace_samples' [(triangle, sample, covered, hit)]. Releases the GIL;
    Ctrl-C raises KeyboardInterrupt. Raises ValueError for invalid parameters."""

def lens_grid_buckets(
    samples: npt.NDArray[np.float32], grid: int
) -> tuple[npt.NDArray[np.int32], npt.NDArray[np.int32], npt.NDArray[np.int32]]:
    """(order (P,P,spp), counts (P,P,G*G), offsets (P,P,G*G)) of [Akenine-Möller 2012] Fig. 10."""

def counter_docs() -> dict[str, tuple[str, str]]: ...
def algorithms() -> list[tuple[str, str, bool]]: ...
def algorithm_facts() -> dict[str, dict[str, object]]:
    """{name: {description, samples ('points' | 'lines'), tables ('points' | 'interleaved' | 'lines'),
    depth_cull, pipeline ('sample' | 'gpu')}}: the traversal registry's facts about every algorithm."""

# ---- timing.cpp: the timing model (docs/timing.md) ----
STREAM_BUDGET: int  # work records the bin stream lets finished bins, and each worker's bin, hold [records]
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

# ---- conservative.cpp: conservative rasterization ----
def conservative_raster(
    params: RenderParams,
    v0: npt.NDArray[np.float32],  # (N, 3, 3) engine vertices at t = 0
    v1: npt.NDArray[np.float32],  # (N, 3, 3) at t = 1
    reduce: bool,
    max_records: int,
) -> dict[str, Any]:
    """Conservative rasterization ([Nilsson 2012] Fig. 2): {'counters', 'records': uint8 bytes of (x, y, triangle,
    u_lo, u_hi, v_lo, v_hi, t_lo, t_hi, z_lo, z_hi) records, 'record_bytes'} or, with reduce,
    {'counters', 'tz_box': float32 (H, W, 4), 'count': int32 (H, W)}. ValueError past max_records."""

# ---- selftest.cpp: probes and unit checks for the tests ----
def probe(
    params: RenderParams,
    v0: npt.NDArray[np.float32],  # (3, 3) one triangle at t = 0
    v1: npt.NDArray[np.float32],  # (3, 3) at t = 1
    points: npt.NDArray[np.float32],  # (M, 5): absolute pixel x, y, then u, v, t
    force_general: bool = False,
) -> dict[str, Any]:
    """Exact sample test at arbitrary points: {'dim_class': int (0..3 = 2D, 3D, 4D, 5D; -1 culled
    near), 'covered', 'hit': bool (M,), 'depth': float32 (M,) z = 1 - near / w, 'w_hit': float32}."""
def measure_kernel_costs(trials: int = 100, seed: int = 1) -> dict[str, tuple[int, int, int]]:
    """{kernel: (documented cost, min counted, max counted)} over random inputs."""
def measure_tile_kernel_costs(trials: int = 200, seed: int = 1) -> dict[str, tuple[int, int, int, int]]:
    """Tile-test kernels whose cost depends on the configuration: {name: (runs, mismatches between
    counted and documented, min documented, max documented)}."""
def simulate_cache(lines: npt.NDArray[np.uint64], n_lines: int, ways: int) -> dict[str, Any]:
    """One set-associative LRU cache (ways 0 = fully associative) over a stream of line indices:
    {'accesses', 'hits', 'misses', 'cold', 'capacity', 'conflict': int, 'hit': bool (M,)}."""
def triangle_lod(v0: npt.NDArray[np.float32], uvs: npt.NDArray[np.float32], tex_width: int, tex_height: int,
                 near_w: float = 0.0) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float64]]:
    """Per-triangle level of detail and uv Jacobian (du/dx, du/dy, dv/dx, dv/dy) from the vertices
    projected through the lens centre at shutter open."""
def texel_address(height: int, width: int, layout: str, level: int, x: int, y: int) -> int:
    """Byte address of a texel of a lone texture; layout: a name in choices()['texture_layouts']."""
