"""Python APIs over the 5D pipeline's intervals (docs/intervals.md):

* ``conservative_raster``: the conservative rasterization mode ([Nilsson 2012] §2, Fig. 2): 1 x 1 tiles, no
  sample test, one fragment record (pixel, triangle, û, v̂, t̂, ẑ) per (triangle, pixel) pair, or a
  per-pixel tz-box reduction computed in C++ ([Nilsson 2012] §3) for large scenes.
* ``occlusion_query``: 5D occlusion queries ([Nilsson 2012] §3), sample-based or interval-based.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _core, params
from . import params as _params
from .camera import Camera
from .errors import ConfigError
from .pipeline import PipelineConfig
from .render import _camera_params, _interval_params, _scene_arrays, render
from .stats import flat_stats

RECORD_DTYPE = np.dtype([
    ("x", "<i4"), ("y", "<i4"), ("triangle", "<i4"),
    ("u_lo", "<f4"), ("u_hi", "<f4"), ("v_lo", "<f4"), ("v_hi", "<f4"),
    ("t_lo", "<f4"), ("t_hi", "<f4"), ("z_lo", "<f4"), ("z_hi", "<f4"),
])


@dataclass
class ConservativeResult:
    """records: structured array (RECORD_DTYPE) when reduce is None; tz_box (H, W, 4) = (t_lo, z_lo,
    t_hi, z_hi) per pixel (+inf/-inf where empty) and count (H, W) with reduce="tz_box".
    z is the engine's depth z = 1 - near / w."""

    flat_stats: dict
    records: np.ndarray | None = None
    tz_box: np.ndarray | None = None
    count: np.ndarray | None = None


def conservative_raster(scene, camera: Camera, pipeline: PipelineConfig | None = None, *,
                        reduce: str | None = None, max_records: int = 20_000_000) -> ConservativeResult:
    """Conservative 5D rasterization of ``scene``: for every (triangle, pixel) pair whose 1 x 1 tile
    test passes, the tile's (û, v̂, t̂) and ẑ. pipeline supplies time_splits, clip, zhat and precision (the
    tile tests in pipeline.precision.tile: docs/precision.md).
    Raises ConfigError when more than ``max_records`` records would be produced (the message
    suggests reduce="tz_box", whose memory is 20 bytes per pixel)."""
    pipeline = pipeline or PipelineConfig()
    params = _camera_params(camera)
    if reduce not in (None, "tz_box"):
        raise ConfigError(f"reduce: expected None or 'tz_box', got {reduce!r}")
    if isinstance(max_records, bool) or not isinstance(max_records, int) or max_records < 0:
        raise ConfigError(f"max_records: expected a non-negative integer, got {max_records!r}")
    if max_records * RECORD_DTYPE.itemsize > pipeline.memory_limit_bytes:
        raise ConfigError(f"max_records: {max_records} records need {max_records * RECORD_DTYPE.itemsize} bytes, "
                          f"more than PipelineConfig.memory_limit_bytes={pipeline.memory_limit_bytes}")
    p0, p1, _ = _scene_arrays(scene)
    v0, v1 = camera.engine_vertices(p0, p1)
    params.lens_grid = 4
    params.table_has_lens = True
    params.table_has_time = True
    _interval_params(params, pipeline)
    _params.set_layer(params, "pipeline", pipeline, only=_params.stage("pipeline", "precision"))  # pipeline.precision
    try:
        out = _core.conservative_raster(params, np.ascontiguousarray(v0, np.float32),
                                        np.ascontiguousarray(v1, np.float32), reduce == "tz_box", int(max_records))
    except ValueError as e:
        raise ConfigError(f"{e}") from None
    stats = flat_stats(out["counters"])
    if reduce == "tz_box":
        return ConservativeResult(stats, tz_box=out["tz_box"], count=out["count"])
    assert out["record_bytes"] == RECORD_DTYPE.itemsize
    return ConservativeResult(stats, records=out["records"].view(RECORD_DTYPE))  # no copy


def query_modes() -> list[str]:
    """The occlusion-query modes (the engine's query_modes registry without 'none', which means no
    query), in engine order."""
    return [m for m in params.choices("query_modes") if m != "none"]


@dataclass
class OcclusionResult:
    """visible: the query may be visible (interval-based: conservative, no false "occluded");
    samples_passed: query samples passing the depth test (sample-based only);
    work: the query's own counters (the render with the query minus the occluders alone)."""

    visible: bool
    samples_passed: int
    work: dict
    flat_stats: dict


class _Concat:
    def __init__(self, a, b):
        self.positions = np.concatenate([a[0], b[0]])
        self.positions_t1 = np.concatenate([a[1], b[1]])
        self.colors = np.concatenate([a[2], b[2]])


def occlusion_query(occluders, query, camera: Camera, table, pipeline: PipelineConfig | None = None, *,
                    mode: str = "samples") -> OcclusionResult:
    """5D occlusion query ([Nilsson 2012] §3): is ``query`` (a scene) hidden behind ``occluders`` for every
    sample (lens point and time)?

    mode="samples": the query triangles are rasterized with the samples of the 5D rasterizer and
    the samples passing the depth test are counted (nothing written); visible iff any passes. It needs
    an algorithm with a depth-cull stage: "tile", "tile_interleaved" or a gpu_* method.
    mode="intervals": the tile algorithm compares each (query triangle, tile) ẑ with the HiZ
    zmax of the occluders and aborts at the first pair that may be visible; no sample is touched.
    It needs algorithm "tile" and runs single-threaded (the abort order must be deterministic);
    HiZ uses pipeline.hiz.tile_size. Conservative: a hidden query may be reported visible, never
    the reverse."""
    pipeline = pipeline or PipelineConfig(algorithm="tile")
    modes = query_modes()
    if mode not in modes:
        raise ConfigError(f"mode: expected {' or '.join(repr(m) for m in modes)}, got {mode!r}")
    if mode == "intervals":
        if pipeline.algorithm != "tile":
            raise ConfigError(f"pipeline.algorithm: the interval-based query needs 'tile', got {pipeline.algorithm!r}")
        pipeline = pipeline.replace(threads=1, hiz={**pipeline.hiz, "enabled": True})
    occ = _scene_arrays(occluders)
    q = _scene_arrays(query)
    scene = _Concat(occ, q)
    n_occ = occ[0].shape[0]
    full = render(scene, camera, table, pipeline, query=(n_occ, mode))
    alone = render(_Concat(occ, tuple(a[:0] for a in q)), camera, table, pipeline)
    work = {k: v - alone.flat_stats.get(k, 0) for k, v in full.flat_stats.items()
            if isinstance(v, int) and not isinstance(v, bool)}
    f = full.flat_stats
    visible = f["occlusion.samples_passed"] > 0 if mode == "samples" else f["occlusion.visible_pairs"] > 0
    return OcclusionResult(visible=bool(visible), samples_passed=int(f["occlusion.samples_passed"]), work=work,
                           flat_stats=f)
