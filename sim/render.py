"""sim.render: hand a scene, a camera and a sample table to the engine, get a Result."""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field

import numpy as np

from . import _core
from .camera import Camera
from .errors import ConfigError, EmptyFrameWarning, MemoryLimitError, SceneInputError
from .hardware import HardwareConfig, TimingRecordsConfig
from . import params as _params
from . import pixel_stats as _pixel_stats
from .pipeline import PipelineConfig
from .texturing import texture_inputs
from .energy import MEMORY_FIGURES as ENERGY_MEMORY_FIGURES
from .energy import estimate as energy_estimate
from .timing import config as timing_config
from .timing import derive as timing_derive
from .timing import docs as timing_docs
from . import sampling as _sampling
from .stats import flat_stats, nest


@dataclass
class Result:
    """What a render returns.

    Fields::

        image       (H, W, 3) float32 linear RGB; row 0 is the top; background is black
        stats       nested dict of counters and derived figures: stats["raster"]["ste"]
        flat_stats  flat dict: {"raster.samples_tested": ..., "ops.total": ..., "time.wall_s": ...}
        sample_depth, sample_triangle  (H, W, spp) per-sample depth z = 1 - near/w (+inf empty) and
                    winning triangle index (-1 empty), only with render(..., export_samples=True)
        timing_records  the timing model's work records (sim.timing.RECORD_DTYPE), only with
                    render(..., keep_timing_records=True), else None; sim.timing.estimate(
                    result.timing_records, hw) re-times the same render on other hardware
        ci95        sampled simulation (PipelineConfig.sample_fraction < 1): {figure: 95% confidence
                    half-width} of every counter and derived figure in flat_stats, which then hold
                    frame estimates; NaN for figures not estimable under sampling (sim.sampling).
                    None for a whole-frame render (exact figures)
        pixel_stats counter name -> (H, W) uint64 map of where that work was done, only with
                    render(..., pixel_stats=True or [names]); each map sums exactly to its frame
                    counter (sim.pixel_stats)
    """

    image: np.ndarray
    flat_stats: dict
    config: dict = field(default_factory=dict)
    sample_depth: np.ndarray | None = None
    sample_triangle: np.ndarray | None = None
    timing_records: np.ndarray | None = None
    ci95: dict | None = None
    pixel_stats: dict | None = None

    @property
    def stats(self) -> dict:
        return nest(self.flat_stats)

    def save_png(self, path):
        from .png import write_png

        return write_png(path, self.image)


def _scene_arrays(scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Duck-typed scene (models.Scene or any object with these attributes) -> validated arrays."""
    try:
        positions = scene.positions
    except AttributeError:
        raise SceneInputError(f"scene: expected an object with .positions (e.g. models.Scene), got {type(scene).__name__}") from None
    positions_t1 = getattr(scene, "positions_t1", None)
    colors = getattr(scene, "colors", None)

    def arr(name, a, last):
        try:
            a = np.asarray(a)
        except Exception:  # noqa: BLE001 - anything not array-like is a bad input
            raise SceneInputError(f"scene.{name}: not array-like ({type(a).__name__})") from None
        if a.dtype.kind not in "fiu":
            raise SceneInputError(f"scene.{name}: expected a numeric array, got dtype {a.dtype}")
        if a.ndim != 3 or a.shape[1:] != (3, last):
            raise SceneInputError(f"scene.{name}: expected shape (N, 3, {last}), got {a.shape}")
        return a.astype(np.float64, copy=False)

    p0 = arr("positions", positions, 3)
    n = p0.shape[0]
    p1 = p0 if positions_t1 is None else arr("positions_t1", positions_t1, 3)
    if p1.shape[0] != n:
        raise SceneInputError(f"scene.positions_t1: expected {n} triangles, got {p1.shape[0]}")
    col = np.full((n, 3, 3), 0.8) if colors is None else arr("colors", colors, 3)
    if col.shape[0] != n:
        raise SceneInputError(f"scene.colors: expected {n} triangles, got {col.shape[0]}")
    for name, a in (("positions", p0), ("positions_t1", p1), ("colors", col)):
        bad = ~np.isfinite(a)
        if bad.any():
            t, v, _ = np.argwhere(bad)[0]
            raise SceneInputError(f"scene.{name}: triangle {t} vertex {v} is not finite: {a[t, v].tolist()}")
    return p0, p1, col


def _scene_alpha(scene, n: int) -> np.ndarray | None:
    """The scene's per-triangle opacity (optional attribute ``alpha``, (N,) in [0, 1]) as float32, or
    None when absent or all 1 (opaque: the engine then skips the alpha masks)."""
    alpha = getattr(scene, "alpha", None)
    if alpha is None:
        return None
    try:
        a = np.asarray(alpha, dtype=np.float64)
    except (TypeError, ValueError):
        raise SceneInputError(f"scene.alpha: not a numeric array ({type(alpha).__name__})") from None
    if a.shape != (n,):
        raise SceneInputError(f"scene.alpha: expected shape ({n},), got {a.shape}")
    bad = ~np.isfinite(a) | (a < 0) | (a > 1)
    if bad.any():
        i = int(np.argmax(bad))
        raise SceneInputError(f"scene.alpha: triangle {i} has opacity {float(a[i])!r}, expected [0, 1]")
    if np.all(a >= 1.0):
        return None
    return np.ascontiguousarray(a, dtype=np.float32)


# One work record (sim.timing.RECORD_DTYPE), and the records the bin stream lets wait per worker.
_RECORD_BYTES = 144
_STREAM_BUDGET = _core.STREAM_BUDGET  # frame/bin_stream.h BinStream::kBudget


def memory_parts(camera: Camera, spp: int, n_triangles: int, config: PipelineConfig, threads: int,
                 export_samples: bool = False, timing: bool = True, period: int = 0,
                 timing_per_visit: bool | None = None, pixel_maps: int = 0,
                 visit_records: int | None = None, keep_timing_records: bool = False,
                 hardware: HardwareConfig | None = None) -> dict[str, int]:
    """Bytes the engine will allocate, by part: {part: bytes}; ``memory_estimate`` is their sum.
    Each part's name says what it grows with (docs/errors.md, tests/test_memory.py).
    ``timing_per_visit`` None: the default ``hardware.timing.granularity``; ``visit_records``: the
    records that granularity makes over the frame (``visit_record_estimate``; None: 16 per (triangle,
    bin)); they are held only for the bins in flight unless ``keep_timing_records``."""
    if timing_per_visit is None:
        timing_per_visit = TimingRecordsConfig().granularity == "visit"
    hw = HardwareConfig() if hardware is None else hardware
    b = config.bin_size
    bins_x = -(-camera.width // b)
    bins_y = -(-camera.height // b)
    grid = config.resolved_lens_grid(spp)
    frame_records = (visit_records if visit_records is not None else n_triangles * 4 * 16) if timing_per_visit \
        else n_triangles * 4
    # The bin stream holds at most its budget of records in finished bins waiting for their turn, and
    # as many in each worker's bin (frame/bin_stream.h BinStream::kBudget).
    in_flight = min(frame_records, (threads + 1) * _STREAM_BUDGET)
    lines_per_bin = -(-min(b, camera.width) * min(b, camera.height) * spp * 4 // hw.depth_buffer.line_bytes)
    return {
        "image (width x height)": camera.width * camera.height * 3 * 4 * 2,  # engine buffer + numpy copy
        "bin buffers (threads x bin_size^2 x spp)": threads * b * b * spp * (4 + 12 + 4),
        "triangle setup (triangles)": n_triangles * (224 + 1 + 4),
        "bin lists (triangles, bins)": n_triangles * 4 * 4 + bins_x * bins_y * 32,
        "sample export (width x height x spp)": camera.width * camera.height * spp * 8 * 2 if export_samples else 0,
        # The records in flight in the bin stream (and each worker's open bin); vectors grow by doubling.
        "timing records in flight (threads)": in_flight * _RECORD_BYTES * 2 if timing else 0,
        # keep_timing_records: every record of the frame, held and copied to numpy (two copies).
        "kept timing records (triangles x tiles of their bounds)":
            frame_records * _RECORD_BYTES * 2 if timing and keep_timing_records else 0,
        # The memory model's per-bin line state per thread: marks, stored sizes, cache slots.
        "memory model (threads x lines per bin)": threads * lines_per_bin * 24 if timing else 0,
        "sample index (period^2 x lens cells x time strata)":
            period * period * (grid * grid * config.time_strata + 1 + spp) * 4,
        "per-pixel statistics (width x height x maps)": camera.width * camera.height * pixel_maps * 8 * 2,
        "segment buffers (threads x bin_size^2 x n_lines x buffer_size)": _segment_buffer_bytes(camera, spp, config,
                                                                                                threads),
    }


# A buffered segment (lines/segment_buffer.h: 13 floats) and a std::vector header per line.
_SEGMENT_BYTES = 52
_SEGMENT_VECTOR_BYTES = 24
# An unlimited buffer (pipeline.lines.buffer_size 0) grows with the depth complexity along each
# line; the estimate assumes this many segments (it is then no bound).
_SEGMENTS_UNLIMITED = 64


def _segment_buffer_bytes(camera: Camera, n_lines: int, config: PipelineConfig, threads: int) -> int:
    """Line samples: every worker keeps one segment buffer per line of its bin (the bin clipped to
    the frame), each a vector that grows by doubling up to pipeline.lines.buffer_size segments and
    keeps its storage from bin to bin: the bound is every buffer full."""
    from .pipeline import algorithm_info

    if algorithm_info(config.algorithm).samples != "lines":
        return 0
    b = config.bin_size
    cap = int(config.lines["buffer_size"]) or _SEGMENTS_UNLIMITED
    cap = 1 << (cap - 1).bit_length()  # vector capacity after doubling
    lines = min(b, camera.width) * min(b, camera.height) * n_lines
    return threads * lines * (_SEGMENT_VECTOR_BYTES + cap * _SEGMENT_BYTES)


def memory_estimate(camera: Camera, spp: int, n_triangles: int, config: PipelineConfig, threads: int,
                    export_samples: bool = False, timing: bool = True, period: int = 0,
                    timing_per_visit: bool | None = None, pixel_maps: int = 0, visit_records: int | None = None,
                    keep_timing_records: bool = False, hardware: HardwareConfig | None = None) -> int:
    """Bytes the engine will allocate (image, per-thread bin buffers, setup, bin lists, exports,
    timing records in flight or kept, the memory model, and with the table's period the (lens cell,
    time stratum) sample index)."""
    return int(sum(memory_parts(camera, spp, n_triangles, config, threads, export_samples, timing,
                                period, timing_per_visit, pixel_maps, visit_records, keep_timing_records,
                                hardware).values()))


def visit_record_estimate(camera: Camera, v0: np.ndarray, v1: np.ndarray, config: PipelineConfig) -> int:
    """Timing records of hardware.timing.granularity 'visit' for engine vertices v0, v1 (N, 3, 3): per
    triangle, the tiles its lens-swept footprint touches (area A and perimeter P of the triangle dilated
    by its largest circle of confusion r: A / s^2 + P / s + 1 tiles of s px, Steiner's formula; a moving
    triangle: the tiles of its bounds over the lens and the shutter), at most the tiles of those bounds (a triangle crossing the near plane: of the
    part in front of it), at least 4 (its bins); bruteforce has one visit per (triangle, bin)."""
    n = len(v0)
    if config.algorithm == "bruteforce" or n == 0:
        return 4 * n
    ts = float(config.tile_size)
    p = camera.engine_params()
    coc, focus, near = abs(p["coc_x_px"]), p["focus_w"], p["near_w"]
    v = np.concatenate([np.asarray(v0, np.float64), np.asarray(v1, np.float64)], axis=1)  # (N, 6, 3)
    w = v[..., 2]
    ok = np.all(w > near, axis=1)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = np.abs(coc * (1 - focus / w))
        x, y = v[..., 0] / w, v[..., 1] / w
        x0 = np.clip(np.nanmin(x - r, axis=1), 0, camera.width)
        x1 = np.clip(np.nanmax(x + r, axis=1), 0, camera.width)
        y0 = np.clip(np.nanmin(y - r, axis=1), 0, camera.height)
        y1 = np.clip(np.nanmax(y + r, axis=1), 0, camera.height)
        bounds = (np.ceil(x1 / ts) - np.floor(x0 / ts)) * (np.ceil(y1 / ts) - np.floor(y0 / ts))
        # the footprint at shutter open and close
        foot = np.zeros(n)
        for k in (0, 3):
            px, py, rr = x[:, k:k + 3], y[:, k:k + 3], r[:, k:k + 3].max(axis=1)
            area = 0.5 * np.abs((px[:, 1] - px[:, 0]) * (py[:, 2] - py[:, 0]) - (px[:, 2] - px[:, 0]) * (py[:, 1] - py[:, 0]))
            per = sum(np.hypot(px[:, (j + 1) % 3] - px[:, j], py[:, (j + 1) % 3] - py[:, j]) for j in range(3))
            a = area + per * rr + np.pi * rr * rr
            pp = per + 2 * np.pi * rr
            foot = np.maximum(foot, a / ts ** 2 + pp / ts + 1)
        moving = np.any(v[:, :3] != v[:, 3:], axis=(1, 2))  # swept over the shutter: its bounds' tiles
        tiles = np.where(moving, bounds, np.minimum(foot, bounds))
    # Crossing the near plane: the tiles of the bounds of the part in front (its vertices in front and
    # the points where its edges cross the plane); wholly behind it: culled, no record.
    tiles = np.where(ok & np.isfinite(tiles), tiles, 0.0)
    for i in np.flatnonzero(~ok & np.any(w > near, axis=1)):
        pts = []
        for k in (0, 3):
            tri = v[i, k:k + 3]
            for j in range(3):
                a, b = tri[j], tri[(j + 1) % 3]
                if a[2] > near:
                    pts.append(a)
                if (a[2] > near) != (b[2] > near):
                    pts.append(a + (a[2] - near) / (a[2] - b[2]) * (b - a))
        q = np.array(pts)
        qw = np.maximum(q[:, 2], near)
        rr = np.abs(coc * (1 - focus / qw))
        qx0, qx1 = np.clip([np.min(q[:, 0] / qw - rr), np.max(q[:, 0] / qw + rr)], 0, camera.width)
        qy0, qy1 = np.clip([np.min(q[:, 1] / qw - rr), np.max(q[:, 1] / qw + rr)], 0, camera.height)
        tiles[i] = (np.ceil(qx1 / ts) - np.floor(qx0 / ts)) * (np.ceil(qy1 / ts) - np.floor(qy0 / ts))
    return int(np.maximum(tiles, 4).sum())


def _memory_message(need: int, parts: dict, camera: Camera, spp: int, n: int, config: PipelineConfig,
                    threads: int) -> str:
    """The memory limit's error: the estimate, the limit, the largest parts and what to change."""
    gib = 2**30
    top = sorted(parts.items(), key=lambda kv: -kv[1])[:2]
    largest = ", ".join(f"{name} {size / gib:.2f} GiB" for name, size in top)
    spp_is_lines = parts.get("segment buffers (threads x bin_size^2 x n_lines x buffer_size)", 0) > 0
    return (f"memory: estimated {need / gib:.2f} GiB exceeds PipelineConfig.memory_limit_bytes="
            f"{config.memory_limit_bytes / gib:.2f} GiB (width={camera.width}, height={camera.height}, "
            f"spp={spp}, triangles={n}, threads={threads}); largest: {largest}. Lower what the largest "
            f"parts grow with (spp, the frame size, pipeline.bin_size or pipeline.threads; export_samples, "
            f"keep_timing_records and timing=False where they apply{'; n_lines and pipeline.lines.buffer_size' if spp_is_lines else ''}"
            f"), or raise the limit if the machine has the memory: "
            f"PipelineConfig(memory_limit_bytes={_round_up_gib(need)}) or pipeline.memory_limit_bytes in a config")


def _round_up_gib(need: int) -> int:
    return -(-need // 2**30) * 2**30


def _camera_params(camera: Camera):
    """RenderParams with the camera's engine parameters and lens shape set."""
    if not isinstance(camera, Camera):
        raise ConfigError(f"camera: expected sim.Camera, got {type(camera).__name__}")
    params = _core.RenderParams()
    for k, v in camera.engine_params().items():
        setattr(params, k, v)
    params.lens_shape = camera.lens
    return params


def _interval_params(params, config: PipelineConfig) -> None:
    """The pipeline parameters the conservative mode reads: those of the intervals stage of
    params.def (time/lens intervals, clip box, depth intervals and HiZ; docs/intervals.md)."""
    _params.set_layer(params, "pipeline", config, only=_params.stage("pipeline", "intervals"))


def check_combination(config: PipelineConfig, table, lens: str = "disk", *, moving: bool = False) -> None:
    """ConfigError when the pipeline's algorithm cannot render with this sample table, lens shape or
    scene motion: what sim.render refuses before the engine runs, in one function, so a sweep checks
    every point (experiments/config/build.py check) before its first render. ``table`` is a
    sim.SampleTable (its kind, generator and discrete lens positions are read); ``moving``: whether the
    scene moves during the shutter (unknown before the scene is built: False)."""
    from .pipeline import algorithm_info, interleaved_algorithms

    algorithm = config.algorithm
    is_lines = getattr(table, "kind", "points") == "lines"
    table_name = getattr(table, "generator", None) or type(table).__name__
    if is_lines != (algorithm_info(algorithm).samples == "lines"):
        if is_lines:
            raise ConfigError(f"algorithm: a line-sample table (SampleTable.lines) needs "
                              f"algorithm 'lines', got {algorithm!r}")
        raise ConfigError("algorithm: 'lines' needs a line-sample table (SampleTable.lines / samples.kind lines), "
                          f"got a {table_name} point-sample table")
    if algorithm in interleaved_algorithms() and not getattr(table, "n_lens", 0):
        raise ConfigError(f"algorithm: {algorithm!r} needs an interleaved sample table (SampleTable.interleaved / "
                          f"samples.kind interleaved, or accumulation), got a {table_name} table without discrete "
                          "lens positions")
    if is_lines and lens != "disk":
        raise ConfigError(f"camera.lens: line samples (algorithm 'lines') cross the disk lens through its centre, "
                          f"got {lens!r}")
    if is_lines and config.shading == "per_lens_cell":
        raise ConfigError("shading: line samples have no lens-grid cells, so 'per_lens_cell' does not apply to "
                          "algorithm 'lines'; use 'none', 'per_sample', 'msaa' or 'cache'")
    if is_lines and moving:
        raise ConfigError("algorithm: 'lines' renders static scenes only (depth of field); the scene moves "
                          "during the shutter (positions_t1): motion blur needs point samples")


def render(scene, camera: Camera, table, config: PipelineConfig | None = None, *,
           export_samples: bool = False, hardware: HardwareConfig | None = None, timing: bool | None = None,
           keep_timing_records: bool = False, query: tuple[int, str] | None = None, pixel_stats=False,
           progress=None, _trace: tuple[int, int] | None = None, _bins: np.ndarray | None = None) -> Result:
    """Render ``scene`` through ``camera`` with sample ``table``. Raises ConfigError/SceneInputError
    (ValueErrors naming the field and value) for bad input; KeyboardInterrupt on Ctrl-C.
    ``hardware`` (default HardwareConfig()) supplies the caches' geometry and the units of the timing
    and memory model (docs/timing.md, docs/memory.md), which runs inside the engine as the bins
    complete: its figures are ``timing.*``, ``dram.*``, ``depth.cache.*``, ``color.*``.
    ``timing`` (None: ``hardware.timing.enabled``) switches it; off, those figures are absent.
    ``keep_timing_records=True`` keeps the work records in ``Result.timing_records`` (for
    ``sim.timing.estimate`` on other hardware; they grow with the frame's visits).
    ``pixel_stats=True`` (or a list of counter names) fills ``Result.pixel_stats`` (sim.pixel_stats).
    ``progress(done_bins, total_bins)`` is called every few milliseconds while the engine runs."""
    if config is None:
        config = PipelineConfig()
    if hardware is None:
        hardware = HardwareConfig()
    if not isinstance(hardware, HardwareConfig):
        raise ConfigError(f"hardware: expected sim.HardwareConfig, got {type(hardware).__name__}")
    if not isinstance(camera, Camera):
        raise ConfigError(f"camera: expected sim.Camera, got {type(camera).__name__}")
    if not isinstance(config, PipelineConfig):
        raise ConfigError(f"config: expected sim.PipelineConfig, got {type(config).__name__}")
    if timing is None:
        timing = hardware.timing.enabled
    if not isinstance(timing, bool) or not isinstance(keep_timing_records, bool):
        raise ConfigError(f"timing, keep_timing_records: expected bools, got {timing!r}, {keep_timing_records!r}")
    if keep_timing_records and not timing:
        raise ConfigError("keep_timing_records: the work records are the timing model's; timing is off "
                          "(timing=False or hardware.timing.enabled false)")
    if pixel_stats is False or pixel_stats is None:
        map_names, derived_maps = [], []
    else:
        try:
            map_names, derived_maps = _pixel_stats.channels(pixel_stats)
        except ValueError as e:
            raise ConfigError(str(e)) from None
    p0, p1, col = _scene_arrays(scene)
    is_lines = getattr(table, "kind", "points") == "lines"
    check_combination(config, table, camera.lens, moving=p1 is not p0 and not np.array_equal(p0, p1))
    lod_report = getattr(scene, "lod_report", None)
    if config.lod["enabled"] and lod_report is None:
        raise ConfigError("pipeline.lod: level of detail is applied to the scene before the render: "
                          "scene, report = models.lod.apply(scene, camera, config.lod) (the rast5d configs do it)")
    samples = table.samples(camera.lens)
    spp = int(samples.shape[2])
    grid = config.resolved_lens_grid(spp)
    threads = config.threads or (os.cpu_count() or 1)
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is reported just below, by triangle
        v0, v1 = camera.engine_vertices(p0, p1)
    per_visit = hardware.timing.granularity == "visit" and timing and config.sample_fraction == 1
    sampled = config.sample_fraction < 1
    timed = timing and not sampled  # the timing model needs the whole frame (sim.sampling)
    def parts_with(visit_records):
        return memory_parts(camera, spp, p0.shape[0], config, threads, export_samples, timed,
                            period=samples.shape[0], timing_per_visit=per_visit,
                            pixel_maps=len(map_names) + len(derived_maps), visit_records=visit_records,
                            keep_timing_records=keep_timing_records, hardware=hardware)

    # Unless the records are kept, the stream holds at most (threads + 1) budgets of them whatever the
    # frame's count: that bound decides first, and the frame's estimate (a pass over every triangle)
    # is made only when the bound is over the limit, for the decision and its message.
    parts = parts_with((threads + 1) * _STREAM_BUDGET if per_visit and not keep_timing_records else None)
    need = int(sum(parts.values()))
    if per_visit and (keep_timing_records or need > config.memory_limit_bytes):
        parts = parts_with(visit_record_estimate(camera, v0, v1, config))
        need = int(sum(parts.values()))
    if need > config.memory_limit_bytes:
        raise MemoryLimitError(_memory_message(need, parts, camera, spp, p0.shape[0], config, threads))
    if not (np.all(np.isfinite(v0)) and np.all(np.isfinite(v1))):
        t = int(np.argwhere(~np.isfinite(v0) | ~np.isfinite(v1))[0][0])
        raise SceneInputError(f"scene.positions: triangle {t} overflows float32 after projection: {p0[t].tolist()}")
    params = _camera_params(camera)
    _params.set_layer(params, "pipeline", config)  # lens_grid 'auto' keeps the engine default:
    params.lens_grid = grid                          # resolved here
    if _trace is not None:  # sim.trace_pixel: the counting path records each sample
        params.op_count = "exact"
    if query is not None:  # (first query triangle, mode name): set by sim.occlusion_query only
        params.query_first, params.query_mode = int(query[0]), query[1]
    # The engine skips a dimension only where skipping is exact: every sample has u = v = 0 (no
    # lens) or t = 0 (no time). A constant non-zero t still places moving triangles at that t.
    dims = getattr(table, "dimensions", None)  # cached on a sim.SampleTable
    params.table_has_lens, params.table_has_time = dims(camera.lens) if dims is not None else (
        bool(np.any(samples[..., 2:4] != 0)), bool(np.any(samples[..., 4] != 0)))
    params.record_timing = timed
    params.table_lines = is_lines
    params.timing_per_visit = hardware.timing.granularity == "visit"
    if sampled and query is not None:
        raise ConfigError(f"PipelineConfig.sample_fraction: {config.sample_fraction!r}: an occlusion query "
                          "stops at the frame's first visible sample and is not estimable from sampled bins; "
                          "use sample_fraction=1")
    if sampled and config.sample_split > 0:
        _sampling.check_split(config)
    if sampled and keep_timing_records:
        raise ConfigError(f"keep_timing_records: PipelineConfig.sample_fraction={config.sample_fraction!r} renders "
                          "sampled bins only; the timing model needs the whole frame")
    if getattr(table, "n_lens", 0):
        lens_index = np.ascontiguousarray(table.lens_index, dtype=np.int32)
        lens_uv = np.ascontiguousarray(table.lens_positions(camera.lens), dtype=np.float32)
    else:
        lens_index = np.zeros((0,), np.int32)
        lens_uv = np.zeros((0, 2), np.float32)
    hardware_desc = hardware.describe()
    _params.set_layer(params, "hardware", hardware_desc)
    uvs, slots, textures, sample_dist, col = texture_inputs(scene, p0, col, config, samples)
    params.texture_sample_distribution_index = sample_dist
    col32 = col.astype(np.float32)
    alpha = _scene_alpha(scene, p0.shape[0])
    t0 = time.perf_counter()
    try:
        engine_index = getattr(table, "engine_index", None)
        if engine_index is not None:  # the table's samples and (lens cell, time stratum) index, built once
            samples_in = engine_index(camera.lens, grid, params.time_strata)
            lens_index, lens_uv = np.zeros((0,), np.int32), np.zeros((0, 2), np.float32)
        else:
            samples_in = samples
        out = _core.render(params, v0, v1, col32, samples_in, lens_index, lens_uv, export_samples,
                           uvs=uvs, tex_slots=slots, textures=textures, alpha=alpha, pixel_stats=map_names,
                           trace_pixel=_trace, progress=progress,
                           bins=None if _bins is None else np.ascontiguousarray(_bins, dtype=np.int32),
                           timing=timing_config(hardware) if timed else None,
                           keep_timing_records=keep_timing_records and timed)
    except ValueError as e:  # invalid_argument from the engine: name it as a config error
        msg = str(e)
        raise ConfigError(f"PipelineConfig.{msg}" if msg.startswith("sample_fraction:") else msg) from None
    wall = time.perf_counter() - t0
    ci95 = None
    if not sampled:
        flat = flat_stats(out["counters"], {"time.wall_s": wall, **(lod_report.stats if lod_report else {})})
    else:
        from .stats import DERIVED

        flat, ci95 = _sampling.estimate(_sampling.from_engine(out), out["counters"], out["bin_counters"], DERIVED,
                                        list(out["counters"]))
        if timing:
            for name in timing_docs():
                flat[name], ci95[name] = float("nan"), float("nan")
        flat["time.wall_s"] = wall
        flat.update(lod_report.stats if lod_report else {})
        flat = dict(sorted(flat.items()))
    records = out.get("timing_records")
    if "timing" in out:  # the timing and memory model's raw figures, and the derived ones
        flat = dict(sorted({**flat, **timing_derive(out["timing"]), **out["memory"]}.items()))
    energy = energy_estimate(flat, cost_model=config.cost_model)  # sim.energy
    if "timing" not in out:  # without the memory model's events these would be part of the figure
        energy = {k: v for k, v in energy.items() if k not in ENERGY_MEMORY_FIGURES}
    flat = dict(sorted({**flat, **energy}.items()))
    desc = {"camera": camera.describe(), "pipeline": config.describe(),
            "table": table.describe() if hasattr(table, "describe") else {}, "lens_grid": grid,
            "hardware": hardware_desc}
    if lod_report is not None:
        desc["lod"] = lod_report.objects
    if query is None and _trace is None and not flat.get("raster.samples_tested") and not flat.get("lines.tests"):
        _warn_empty_frame(flat, camera)
    maps = None
    if "pixel_stats" in out and (map_names or derived_maps):
        maps = _pixel_stats.assemble(map_names, derived_maps, out["pixel_stats"])
    result = Result(image=out["image"], flat_stats=flat, config=desc,
                    sample_depth=out.get("sample_depth"), sample_triangle=out.get("sample_triangle"),
                    timing_records=records, ci95=ci95, pixel_stats=maps)
    if _trace is not None:
        result.config["trace"] = (out["trace_events"], out["trace_samples"])
    if _bins is not None:  # the listed bins' own counters and every bin's auxiliaries (sim.sampling)
        result.config["bins"] = {k: out[k] for k in ("counters", "bin_counters", "bins", "bin_work", "bin_aux",
                                                     "bin_aux_total")}
    return result


def trace_pixel(scene, camera: Camera, table, x: int, y: int, config: PipelineConfig | None = None, *,
                hardware: HardwareConfig | None = None) -> "_pixel_stats.PixelTrace":
    """Trace pixel (x, y) (column, row from the top): render its screen bin on the counting path and
    return a sim.pixel_stats.PixelTrace (the triangles that reached it, each tile test's verdict, each
    sample tested and hit, the operations charged); print it for a readable account."""
    if config is None:
        config = PipelineConfig()
    for name, v in (("x", x), ("y", y)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
            raise ConfigError(f"pixel.{name}: expected an integer, got {v!r}")
    res = render(scene, camera, table, config, hardware=hardware, timing=False, _trace=(int(x), int(y)))
    events, samples = res.config.pop("trace")
    spp = int(table.samples(camera.lens).shape[2])
    return _pixel_stats.PixelTrace(x=int(x), y=int(y), spp=spp, algorithm=config.algorithm,
                                   events=[(int(t), int(k), tuple(r), dict(d)) for t, k, r, d in events],
                                   samples=[(int(t), int(s), bool(c), bool(h)) for t, s, c, h in samples])


def _warn_empty_frame(flat: dict, camera: Camera) -> None:
    """EmptyFrameWarning with the setup cull causes when a frame tested no sample."""
    import warnings

    n = int(flat.get("setup.triangles", 0))
    causes = {"behind the near plane": "setup.culled_near", "off screen": "setup.culled_offscreen",
              "degenerate": "setup.culled_degenerate", "back-facing": "setup.culled_backface"}
    counts = {what: int(flat.get(key, 0)) for what, key in causes.items()}
    rest = n - sum(counts.values())
    text = ", ".join(f"{c} {what}" for what, c in counts.items() if c)
    if rest:
        text += (", " if text else "") + f"{rest} covering no sample position"
    d = camera.describe()
    warnings.warn(f"sim.render: the frame tested no samples: of {n} triangles {text or 'none'} "
                  f"(camera eye {d.get('eye')}, target {d.get('target')}, near {d.get('near')}); frame the "
                  "scene (models.frame_hint) or move the camera", EmptyFrameWarning, stacklevel=3)
