"""The bad-input catalogue: what rast5d refuses, with which exception and message, and where the
message points. tests/test_errors_catalogue.py runs every case; `python -m tests.catalogue.bad_inputs`
writes docs/errors.md from the same table (a test checks the page is fresh).

A case is a function that performs one bad call in a scratch folder ``d`` (a pathlib.Path). Its row
gives the category, the input in words, the expected exception type, a regular expression the message
must match, and where the message points (the field, value, file, line or element it names). Rows
with ``error=None`` document inputs that are accepted on purpose (the function then checks the
outcome itself)."""
from __future__ import annotations

import re
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

CATEGORIES = ("Python API", "bindings", "YAML config", "command line", "scene file")


@dataclass(frozen=True)
class Case:
    id: str
    category: str
    input: str
    error: type | None
    match: str
    points_to: str
    run: Callable[[Path], object]


CASES: list[Case] = []


def case(category: str, input: str, error, match: str, points_to: str):
    assert category in CATEGORIES, category

    def register(fn):
        CASES.append(Case(fn.__name__, category, input, error, match, points_to, fn))
        return fn

    return register


# ---- helpers ------------------------------------------------------------------------------------

def _sim():
    import sim

    return sim


def _errors():
    import models
    import sim
    from experiments.config import ConfigError as XConfigError

    return sim.ConfigError, sim.SceneInputError, models.SceneError, XConfigError


class _Arrays:
    """A duck-typed scene of raw arrays (what sim.render accepts besides models.Scene)."""

    def __init__(self, positions, positions_t1=None, colors=None):
        self.positions, self.positions_t1, self.colors = positions, positions_t1, colors


def _tri(n=1, z=-3.0):
    p = np.array([[[-1, -1, z], [1, -1, z], [0, 1, z]]], dtype=np.float64)
    return np.repeat(p, n, axis=0)


def _render(scene=None, camera=None, table=None, config=None, **kw):
    sim = _sim()
    scene = _Arrays(_tri()) if scene is None else scene
    camera = sim.Camera(width=16, height=16, coc_px=2) if camera is None else camera
    table = sim.SampleTable.create("stratified", spp=4, seed=1) if table is None else table
    return sim.render(scene, camera, table, config, **kw)


def _params(**kw):
    """Valid engine parameters for a 16 x 16 frame (what sim.render hands the binding)."""
    sim = _sim()
    from sim import params as sp

    camera = sim.Camera(width=16, height=16, coc_px=2)
    p = sim._core.RenderParams()
    for k, v in camera.engine_params().items():
        setattr(p, k, v)
    p.lens_shape = camera.lens
    sp.set_layer(p, "pipeline", sim.PipelineConfig())
    p.lens_grid = sim.PipelineConfig().resolved_lens_grid(4)
    for k, v in kw.items():
        setattr(p, k, v)
    return p, camera


def _core_render(v0=None, v1=None, colors=None, samples=None, lens_index=None, lens_uv=None, params=None, **kw):
    sim = _sim()
    p, camera = _params() if params is None else (params, None)
    if v0 is None:
        cam = sim.Camera(width=16, height=16, coc_px=2)
        v0, _ = cam.engine_vertices(_tri(), _tri())
        v0 = v0.astype(np.float32)
    n = v0.shape[0] if v0.ndim else 0
    v1 = v0 if v1 is None else v1
    colors = np.full((n, 3, 3), 0.5, np.float32) if colors is None else colors
    if samples is None:
        samples = sim.SampleTable.create("stratified", spp=4, seed=1).samples("disk")
    lens_index = np.zeros((0,), np.int32) if lens_index is None else lens_index
    lens_uv = np.zeros((0, 2), np.float32) if lens_uv is None else lens_uv
    return sim._core.render(p, v0, v1, colors, samples, lens_index, lens_uv, **kw)


def _config(d: Path, text: str, name: str = "c.yaml", overrides=()):
    from experiments.config import load_config

    p = d / name
    p.write_text(text)
    return load_config(p, list(overrides))


BASE = "scene: {name: quad}\ncamera: {width: 16, height: 16}\n"


# ---- Python API: scene arrays -------------------------------------------------------------------

@case("Python API", "scene positions of shape (N, 3) instead of (N, 3, 3)", "SceneInputError",
      r"scene\.positions: expected shape \(N, 3, 3\), got \(2, 3\)", "the array and its shape")
def positions_wrong_shape(d):
    _render(_Arrays(np.zeros((2, 3))))


@case("Python API", "scene positions of strings (dtype '<U1')", "SceneInputError",
      r"scene\.positions: expected a numeric array, got dtype <U1", "the array and its dtype")
def positions_wrong_dtype(d):
    _render(_Arrays(np.full((1, 3, 3), "a")))


@case("Python API", "a NaN vertex in the scene positions", "SceneInputError",
      r"scene\.positions: triangle 0 vertex 1 is not finite", "the triangle, the vertex and its value")
def positions_nan(d):
    p = _tri()
    p[0, 1, 0] = np.nan
    _render(_Arrays(p))


@case("Python API", "+inf in the shutter-close positions", "SceneInputError",
      r"scene\.positions_t1: triangle 2 vertex 0 is not finite", "the triangle, the vertex and its value")
def positions_t1_inf(d):
    p1 = _tri(3)
    p1[2, 0, 2] = np.inf
    _render(_Arrays(_tri(3), p1))


@case("Python API", "shutter-close positions for a different number of triangles", "SceneInputError",
      r"scene\.positions_t1: expected 3 triangles, got 2", "both counts")
def positions_t1_count(d):
    _render(_Arrays(_tri(3), _tri(2)))


@case("Python API", "vertices of 1e38 (finite, but overflow float32 once projected)", "SceneInputError",
      r"scene\.positions: triangle 0 overflows float32 after projection", "the triangle and its vertices")
def positions_overflow(d):
    p = _tri()
    p[0, :, 0] = [-1e38, 1e38, 3e38]
    _render(_Arrays(p))


@case("Python API", "colors with 2 channels per vertex", "SceneInputError",
      r"scene\.colors: expected shape \(N, 3, 3\), got \(1, 3, 2\)", "the array and its shape")
def colors_wrong_shape(d):
    _render(_Arrays(_tri(), colors=np.zeros((1, 3, 2))))


@case("Python API", "an object without .positions as the scene", "SceneInputError",
      r"scene: expected an object with \.positions.*got dict", "the argument and the type given")
def scene_not_a_scene(d):
    _render({"positions": _tri()})


@case("Python API", "an empty scene (0 triangles)", None, "",
      "accepted: a black frame, 0 samples tested, and an EmptyFrameWarning giving the cull causes")
def empty_scene(d):
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = _render(_Arrays(np.zeros((0, 3, 3))))
    assert r.flat_stats["raster.samples_tested"] == 0 and not r.image.any()
    assert any(w.category.__name__ == "EmptyFrameWarning" for w in caught)


@case("Python API", "zero-area and duplicate triangles", None, "",
      "accepted: zero-area triangles are culled at setup, duplicates rendered (depth test picks one)")
def degenerate_and_duplicate(d):
    p = np.concatenate([_tri(2), np.zeros((1, 3, 3)) + [0, 0, -3]])
    r = _render(_Arrays(p))
    assert r.flat_stats["raster.samples_hit"] > 0


# ---- Python API: camera, pipeline, hardware, sample tables -------------------------------------------

@case("Python API", "Camera(width=100000)", "ConfigError", r"Camera\.width: expected an integer in 1\.\.16384, got 100000",
      "the field, the range and the value")
def camera_enormous(d):
    _sim().Camera(width=100000)


@case("Python API", "Camera(fov_y_deg=180)", "ConfigError", r"Camera\.fov_y_deg: expected < 180.*got 180",
      "the field, the bound and the value")
def camera_fov(d):
    _sim().Camera(fov_y_deg=180)


@case("Python API", "Camera(coc_px=nan)", "ConfigError", r"Camera\.coc_px: expected a finite number, got nan",
      "the field and the value")
def camera_coc_nan(d):
    _sim().Camera(coc_px=float("nan"))


@case("Python API", "Camera(lens='octagon')", "ConfigError", r"Camera\.lens: unknown shape 'octagon' \(known: ",
      "the field, the value and the known shapes")
def camera_lens(d):
    _sim().Camera(lens="octagon")


@case("Python API", "Camera(shutter=(0.8, 0.2)) (closes before it opens)", "ConfigError",
      r"Camera\.shutter: expected open <= close, got \(0\.8, 0\.2\)", "the field and the value")
def camera_shutter(d):
    _sim().Camera(shutter=(0.8, 0.2))


@case("Python API", "Camera(eye=target)", "ConfigError", r"Camera\.target: must differ from eye", "the field and the value")
def camera_eye_target(d):
    _sim().Camera(eye=(0, 0, 0), target=(0, 0, 0))


@case("Python API", "a dict instead of sim.Camera", "ConfigError", r"camera: expected sim\.Camera, got dict",
      "the argument and the type given")
def camera_wrong_type(d):
    _render(camera={"width": 16})


@case("Python API", "PipelineConfig(algorithm='tilez')", "ConfigError", r"algorithm.*'tilez'.*tile",
      "the field, the value and the known algorithms")
def pipeline_algorithm(d):
    _sim().PipelineConfig(algorithm="tilez")


@case("Python API", "PipelineConfig(bin_size=12)", "ConfigError", r"bin_size.*12", "the field and the value")
def pipeline_bin_size(d):
    _render(config=_sim().PipelineConfig(bin_size=12))


@case("Python API", "PipelineConfig(precision={'depth': 'float64'})", "ConfigError",
      r"precision\.depth: expected 'float32' or \{fixed.*'float64'", "the stage, the kinds it accepts and the value")
def pipeline_precision_kind(d):
    _sim().PipelineConfig(precision={"depth": "float64"})


@case("Python API", "PipelineConfig(precision={'sample': {'fixed': {'int_bits': 0, 'frac_bits': 4}}})", "ConfigError",
      r"precision\.sample\.fixed\.int_bits: expected an integer in 1\.\.62, got 0", "the bit field, its range and the value")
def pipeline_precision_bits(d):
    _sim().PipelineConfig(precision={"sample": {"fixed": {"int_bits": 0, "frac_bits": 4}}})


@case("Python API", "an algorithm that needs an interleaved table with a stratified table", "ConfigError",
      r"algorithm: '.*' needs an interleaved sample table", "the algorithm and the table it needs")
def pipeline_needs_interleaved(d):
    sim = _sim()
    _render(config=sim.PipelineConfig(algorithm=sim.interleaved_algorithms()[0]))


@case("Python API", "a sample-based occlusion query with an algorithm that has no depth-cull stage (bruteforce)",
      "ConfigError", r"algorithm: occlusion queries are answered by .*got 'bruteforce'",
      "the algorithms that answer queries and the one given")
def occlusion_query_algorithm(d):
    sim = _sim()
    occluder, query = _Arrays(_tri(z=-3.0)), _Arrays(_tri(z=-2.0))
    sim.occlusion_query(occluder, query, sim.Camera(width=16, height=16), sim.SampleTable.create("stratified", spp=4, seed=1),
                        sim.PipelineConfig(algorithm="bruteforce"))


@case("Python API", "a frame whose buffers exceed the memory limit (16384^2 px, 4096 spp)", "ConfigError",
      r"memory: estimated .* GiB exceeds PipelineConfig\.memory_limit_bytes.*largest: .*Lower .*raise the limit",
      "the estimate, the limit, the sizes behind it, the two largest parts, what to lower and how to raise the limit")
def memory_limit(d):
    sim = _sim()
    _render(camera=sim.Camera(width=16384, height=16384), config=sim.PipelineConfig(threads=2),
            table=sim.SampleTable.create("random", spp=4096, seed=1, period=1))


@case("Python API", "HardwareConfig texture cache line of 48 bytes (not a power of two)", "ConfigError",
      r"line_bytes.*48", "the field and the value")
def hardware_line(d):
    sim = _sim()
    _render(hardware=sim.HardwareConfig(tex_cache=sim.TextureCacheConfig(line_bytes=48)))


@case("Python API", "HardwareConfig depth-tile cache of 100000 bytes (not whole sets of 4 x 1024-byte lines)",
      "ConfigError", r"HardwareConfig\.depth_buffer\.cache_bytes: 100000 is not a whole number of sets of 4 x 1024-byte lines",
      "the field, the value and the set it must divide into")
def hardware_depth_cache(d):
    _sim().HardwareConfig(depth_buffer={"cache_bytes": 100000})


@case("Python API", "HardwareConfig colour-tile cache of 40000 bytes", "ConfigError",
      r"HardwareConfig\.color_buffer\.cache_bytes: 40000 is not a whole number of sets of 4 x 1024-byte lines "
      r"\(256 samples of 4 bytes", "the field, the value, the line and where its size comes from")
def hardware_color_cache(d):
    _sim().HardwareConfig(color_buffer={"cache_bytes": 40000})


@case("Python API", "HardwareConfig depth line of 1000 bytes (not a power of two)", "ConfigError",
      r"depth_buffer\.line_bytes: expected a power of two, got 1000", "the field and the value")
def hardware_depth_line(d):
    _sim().HardwareConfig(depth_buffer={"line_bytes": 1000})


@case("Python API", "HardwareConfig with depth compression and the depth-tile cache off", "ConfigError",
      r"HardwareConfig\.depth_buffer\.compression: 'plane' compresses the depth-tile cache's lines, and "
      r"HardwareConfig\.depth_buffer\.enabled is false", "the two fields and what to change")
def hardware_compression_without_cache(d):
    _sim().HardwareConfig(depth_buffer={"enabled": False, "compression": "plane"})


@case("Python API", "HardwareConfig with a DRAM bandwidth of 0 bytes per clock", "ConfigError",
      r"HardwareConfig\.dram\.bytes_per_clock: expected .*got 0", "the field, its range and the value")
def hardware_dram_zero(d):
    _sim().HardwareConfig(dram={"bytes_per_clock": 0})


@case("Python API", "sim.render(keep_timing_records=True) with timing off", "ConfigError",
      r"keep_timing_records: the work records are the timing model's; timing is off", "the keyword and why")
def keep_records_untimed(d):
    _render(timing=False, keep_timing_records=True)


@case("Python API", "SampleTable.create('blue')", "ValueError", r"blue.*(known|expected)", "the kind and the known kinds")
def table_unknown_kind(d):
    _sim().SampleTable.create("blue", spp=4)


@case("Python API", "SampleTable.create(spp=0)", "ValueError", r"spp.*0", "the field, the range and the value")
def table_spp_zero(d):
    _sim().SampleTable.create("stratified", spp=0)


@case("Python API", "SampleTable.create(period=0)", "ValueError", r"period.*0", "the field, the range and the value")
def table_period(d):
    _sim().SampleTable.create("stratified", spp=4, period=0)


@case("Python API", "SampleTable.from_array with x = 1.0 (outside [0, 1))", "ValueError", r"x.*1",
      "the column, the sample and the value")
def table_x_range(d):
    s = np.zeros((4, 5), np.float32)
    s[2, 0] = 1.0
    _sim().SampleTable.from_array(s)


@case("Python API", "SampleTable.from_array with u = 1.5 (outside [-1, 1])", "ValueError", r"u.*1\.5",
      "the column, the sample and the value")
def table_u_range(d):
    s = np.zeros((4, 5), np.float32)
    s[1, 2] = 1.5
    _sim().SampleTable.from_array(s)


@case("Python API", "SampleTable.from_array with a NaN time", "ValueError", r"t.*nan", "the column, the sample and the value")
def table_nan(d):
    s = np.zeros((4, 5), np.float32)
    s[3, 4] = np.nan
    _sim().SampleTable.from_array(s)


@case("Python API", "SampleTable.from_array of shape (4, 2, 8, 5): inconsistent periods", "ValueError",
      r"samples: expected shape \(spp, 5\) or \(P, P, spp, 5\), got \(4, 2, 8, 5\)", "the expected and given shapes")
def table_periods(d):
    _sim().SampleTable.from_array(np.zeros((4, 2, 8, 5), np.float32))


@case("Python API", "SampleTable.from_array with a lens_index past lens_positions", "ValueError",
      r"lens_index", "the field and the offending index")
def table_lens_index(d):
    s = np.zeros((4, 5), np.float32)
    _sim().SampleTable.from_array(s, lens_index=np.array([0, 1, 2, 7]), lens_positions=np.zeros((3, 2)))


@case("Python API", "conservative_raster(reduce='sum')", "ConfigError", r"reduce: expected None or 'tz_box', got 'sum'",
      "the argument and the value")
def conservative_reduce(d):
    sim = _sim()
    sim.conservative_raster(_Arrays(_tri()), sim.Camera(width=16, height=16), reduce="sum")


@case("Python API", "occlusion_query(mode='pixels')", "ConfigError", r"mode: expected .*'samples'.*got 'pixels'",
      "the argument, the value and the modes")
def occlusion_mode(d):
    sim = _sim()
    sim.occlusion_query(_Arrays(_tri()), _Arrays(_tri(z=-5)), sim.Camera(width=16, height=16),
                        sim.SampleTable.create("stratified", spp=4), mode="pixels")


@case("Python API", "models.Scene texture_ids naming texture 3 of 1", "SceneError",
      r"texture_ids: triangle 0 has id 3, expected -1 \(untextured\) or 0\.\.0", "the triangle, the id and the range")
def scene_texture_ids(d):
    import models

    models.Scene.from_arrays(_tri(), uvs=np.zeros((1, 3, 2)), textures=[np.zeros((4, 4, 3), np.float32)], texture_ids=[3])


@case("Python API", "a texture with 2 channels", "SceneError", r"texture: expected shape \(H, W, 3\|4\), got \(4, 4, 2\)",
      "the texture and its shape")
def texture_channels(d):
    import models

    models.Scene.from_arrays(_tri(), uvs=np.zeros((1, 3, 2)), texture=np.zeros((4, 4, 2), np.float32))


@case("Python API", "a float texture with a texel of 1.5", "SceneError",
      r"texture: texel \(row 1, column 2, channel 0\) = 1\.5 is not in \[0, 1\]", "the texel and its value")
def texture_range(d):
    import models

    t = np.zeros((4, 4, 3), np.float32)
    t[1, 2, 0] = 1.5
    models.Scene.from_arrays(_tri(), uvs=np.zeros((1, 3, 2)), texture=t)


@case("Python API", "an empty (0 x 0) texture", "SceneError", r"texture: expected shape \(H, W, 3\|4\), got \(0, 0, 3\)",
      "the texture and its shape")
def texture_empty(d):
    import models

    models.Scene.from_arrays(_tri(), uvs=np.zeros((1, 3, 2)), texture=np.zeros((0, 0, 3), np.float32))


@case("Python API", "a 3 x 5 texture (odd, not a power of two)", None, "",
      "accepted: mip levels halve with rounding down to 1 x 1")
def texture_odd_size(d):
    import models

    sim = _sim()
    uv = np.array([[[0, 0], [1, 0], [0.5, 1]]], np.float64)
    scene = models.Scene.from_arrays(_tri(), uvs=uv, texture=np.full((3, 5, 3), 0.5, np.float32))
    r = _render(scene, config=sim.PipelineConfig(shading="msaa"))
    assert r.flat_stats["raster.samples_hit"] > 0



def _lines_table():
    return _sim().SampleTable.lines(n_lines=4, seed=1)


@case("Python API", "a line-sample table (SampleTable.lines) with a point-sample algorithm", "ConfigError",
      r"algorithm: a line-sample table \(SampleTable\.lines\) needs algorithm 'lines', got 'bruteforce'",
      "the table, the algorithm it needs and the one given")
def lines_table_point_algorithm(d):
    _render(table=_lines_table())


@case("Python API", "algorithm 'lines' with a point-sample table", "ConfigError",
      r"algorithm: 'lines' needs a line-sample table .* got a stratified point-sample table",
      "the algorithm, the table it needs and the one given")
def lines_algorithm_point_table(d):
    _render(config=_sim().PipelineConfig(algorithm="lines"))


@case("Python API", "algorithm 'lines' on a moving scene (positions_t1 differs)", "ConfigError",
      r"algorithm: 'lines' renders static scenes only .* motion blur needs point samples",
      "the algorithm, the moving positions and what to use instead")
def lines_motion_blur(d):
    _render(_Arrays(_tri(), _tri() + [0.1, 0.0, 0.0]), table=_lines_table(),
            config=_sim().PipelineConfig(algorithm="lines"))


@case("Python API", "algorithm 'lines' with lens-cell shading (shading: per_lens_cell)", "ConfigError",
      r"shading: line samples have no lens-grid cells.*use 'none', 'per_sample', 'msaa' or 'cache'",
      "the parameter, why and the values to use")
def lines_shading(d):
    _render(table=_lines_table(), config=_sim().PipelineConfig(algorithm="lines", shading="per_lens_cell"))


@case("Python API", "line samples whose segment buffers exceed the memory limit (64 lines, 4096-segment buffers)",
      "ConfigError", r"memory: estimated .* largest: segment buffers \(threads x bin_size\^2 x n_lines x buffer_size\)"
      r".*n_lines and pipeline\.lines\.buffer_size",
      "the estimate, the segment buffers as the largest part and the two settings to lower")
def lines_memory(d):
    sim = _sim()
    config = sim.PipelineConfig(algorithm="lines", threads=2, bin_size=512, lines={"buffer_size": 4096})
    _render(camera=sim.Camera(width=512, height=512, coc_px=2), table=sim.SampleTable.lines(n_lines=64, seed=1),
            config=config)

# ---- bindings (sim._core, raw arrays) ------------------------------------------------------------------

@case("bindings", "_core.render with v0 of shape (1, 3, 4)", "ValueError", r"v0: unexpected shape \(1, 3, 4\)",
      "the argument and its shape")
def core_v0_shape(d):
    _core_render(v0=np.zeros((1, 3, 4), np.float32))


@case("bindings", "_core.render with v1 for another triangle count", "ValueError", r"v1: unexpected shape \(2, 3, 3\)",
      "the argument and its shape")
def core_v1_count(d):
    _core_render(v1=np.zeros((2, 3, 3), np.float32))


@case("bindings", "_core.render with a 4 x 2 pixel sample table", "ValueError",
      r"samples: the table must be P x P pixels", "the argument")
def core_samples_period(d):
    _core_render(samples=np.zeros((4, 2, 4, 5), np.float32))


@case("bindings", "_core.render with a NaN sample coordinate", "ValueError", r"samples: .*not finite|samples.*nan",
      "the argument, the sample and the value")
def core_samples_nan(d):
    s = _sim().SampleTable.create("stratified", spp=4, seed=1).samples("disk").copy()
    s[0, 0, 1, 2] = np.nan
    _core_render(samples=s)


@case("bindings", "_core.render with a NaN engine vertex", "ValueError", r"v0: triangle 0 vertex 2 is not finite",
      "the argument, the triangle and the vertex")
def core_vertex_nan(d):
    sim = _sim()
    v0, _ = sim.Camera(width=16, height=16).engine_vertices(_tri(), _tri())
    v0 = v0.astype(np.float32)
    v0[0, 2, 1] = np.nan
    _core_render(v0=v0)


@case("bindings", "_core.render with lens_index 9 of 4 lens positions", "ValueError", r"lens_index.*9.*0\.\.3",
      "the argument, the pixel and sample, the value and the range")
def core_lens_index(d):
    s = _sim().SampleTable.create("stratified", spp=4, seed=1, period=2).samples("disk")
    li = np.zeros((2, 2, 4), np.int32)
    li[1, 0, 3] = 9
    _core_render(samples=s, lens_index=li, lens_uv=np.zeros((4, 2), np.float32))


@case("bindings", "_core.render with a SampleTableIndex built for 16 time strata, the params asking for 8", "ValueError",
      r"samples: the SampleTableIndex has lens_grid \d+ and time_strata 16, the params ask for \d+ and \d+",
      "the argument, the index's lens grid and strata and the params'")
def core_table_index_strata(d):
    sim = _sim()
    p, _ = _params()
    index = sim.SampleTable.create("stratified", spp=4, seed=1).engine_index("disk", p.lens_grid, 2 * p.time_strata)
    _core_render(samples=index, params=p)


@case("bindings", "_core.render with tex_slots naming texture 5 of 1", "ValueError",
      r"tex_slots: triangle 0 uses texture 5, expected -1\.\.0", "the triangle, the id and the range")
def core_tex_slots(d):
    p, _ = _params(texture_count=1, shading="msaa")
    _core_render(params=p, uvs=np.zeros((1, 3, 2), np.float32), tex_slots=np.array([[5, -1, -1, -1]], np.int32),
                 textures=[np.zeros((4, 4, 3), np.float32)])


@case("bindings", "_core.render with a 5-channel texture", "ValueError", r"textures\[0\]: expected \(H, W, 1\.\.4\)",
      "the texture and the expected shape")
def core_texture_channels(d):
    _core_render(textures=[np.zeros((4, 4, 5), np.float32)])


@case("bindings", "_core.render with a NaN texel", "ValueError", r"textures\[0\]: .*not finite",
      "the texture and the texel")
def core_texture_nan(d):
    t = np.zeros((4, 4, 3), np.float32)
    t[2, 1, 0] = np.nan
    _core_render(textures=[t])


@case("bindings", "_core.render with NaN texture coordinates", "ValueError", r"uvs: triangle 0 .*not finite",
      "the argument, the triangle and the value")
def core_uvs_nan(d):
    p, _ = _params(texture_count=1, shading="msaa")
    uv = np.zeros((1, 3, 2), np.float32)
    uv[0, 1, 0] = np.nan
    _core_render(params=p, uvs=uv, tex_slots=np.zeros((1, 4), np.int32), textures=[np.zeros((4, 4, 3), np.float32)])


@case("bindings", "RenderParams.width = 0", "ValueError", r"width.*0", "the parameter, its domain and the value")
def core_params_width(d):
    p, _ = _params(width=0)
    _core_render(params=p)


@case("bindings", "RenderParams.algorithm = 'nope'", "ValueError", r"algorithm: unknown 'nope' \(known: ",
      "the parameter, the value and the known names")
def core_params_algorithm(d):
    p, _ = _params(algorithm="nope")
    _core_render(params=p)


@case("bindings", "_core.lens_grid_buckets with grid 0", "ValueError", r"grid: expected 1\.\.64", "the argument and its range")
def core_lens_grid(d):
    _sim()._core.lens_grid_buckets(np.zeros((1, 1, 4, 5), np.float32), 0)


@case("bindings", "_core.render with a list of strings as vertices", "TypeError", r"incompatible function arguments",
      "the function and the accepted signature")
def core_wrong_type(d):
    p, _ = _params()
    z = np.zeros((1, 3, 3), np.float32)
    _sim()._core.render(p, [["a"]], z, z, np.zeros((1, 1, 4, 5), np.float32), np.zeros(0, np.int32),
                        np.zeros((0, 2), np.float32))


@case("bindings", "_core.TimingConfig with 2 throughputs for 11 units", "ValueError",
      r"throughput, latency, fifo: expected one value per unit", "the arguments and the unit count")
def core_timing_units(d):
    _sim()._core.TimingConfig([1.0, 1.0], [1.0, 1.0], [1, 1], 1.0, 1.0)


@case("bindings", "_core.simulate_cache with 3 ways over 8 lines", "ValueError", r"ways: expected 0 or a divisor of n_lines",
      "the argument")
def core_cache_ways(d):
    _sim()._core.simulate_cache(np.zeros(4, np.uint64), 8, 3)


@case("bindings", "_core.simulate_cache with 2^31 - 1 lines (found by fuzzing: allocated 48 GiB)", "ValueError",
      r"n_lines: expected 1\.\.67108864, got 2147483647", "the argument, its range and the value")
def core_cache_lines(d):
    _sim()._core.simulate_cache(np.zeros(4, np.uint64), 2**31 - 1, 0)


@case("bindings", "_core.TimingConfig with an infinite texture-miss latency (found by fuzzing)", "ValueError",
      r"tex_hit_latency, tex_miss_latency: expected finite numbers", "the arguments")
def core_timing_latency(d):
    sim = _sim()
    k = len(sim._core.timing_units())
    sim._core.TimingConfig([1.0] * k, [1.0] * k, [4] * k, 4.0, float("inf"))


@case("bindings", "_core.TimingConfig with a zero DRAM bandwidth", "ValueError",
      r"dram\.bytes_per_clock: expected > 0 and finite, got 0", "the field and the value")
def core_timing_dram(d):
    sim = _sim()
    k = len(sim._core.timing_units())
    sim._core.TimingConfig([1.0] * (k - 1) + [0.0], [0.0] * k, [4] * k)


@case("bindings", "RenderParams with a 100000-byte depth-tile cache of 1024-byte lines in 4 ways", "ValueError",
      r"depth_buffer_cache_bytes: 100000 is not a whole number of sets of 4 x 1024-byte lines",
      "the parameter, the value and the set it must divide into")
def core_depth_cache_geometry(d):
    p, _ = _params(depth_buffer_cache_bytes=100000)
    _core_render(params=p)


@case("bindings", "RenderParams compressing depth with the depth-tile cache off", "ValueError",
      r"depth_buffer_compression: 'time_predictor' compresses the depth-tile cache's lines, and "
      r"depth_buffer_enabled is false", "the two parameters and what to change")
def core_depth_compression_without_cache(d):
    p, _ = _params(depth_buffer_enabled=False)
    _core_render(params=p)


@case("bindings", "_core.texel_address of a 2^31 - 1 x 8 texture (found by fuzzing: allocated 64 GiB)", "ValueError",
      r"height, width: expected 1\.\.16384, got 2147483647 x 8", "the arguments, their range and the values")
def core_texel_size(d):
    _sim()._core.texel_address(2**31 - 1, 8, "linear", 0, 0, 0)


@case("bindings", "_core.texel_address at mip level 9 of a 4 x 4 texture", "ValueError", r"level: out of range",
      "the argument")
def core_texel_level(d):
    _sim()._core.texel_address(4, 4, "linear", 9, 0, 0)


@case("Python API", "a scene opacity (alpha) of 1.5 for stochastic transparency", "SceneInputError",
      r"scene\.alpha: triangle 1 has opacity 1\.5, expected \[0, 1\]", "the triangle and its opacity")
def alpha_out_of_range(d):
    scene = _Arrays(_tri(2))
    scene.alpha = np.array([0.5, 1.5])
    _render(scene)


# ---- YAML configs ------------------------------------------------------------------------------------

@case("YAML config", "an option a use kind does not have (point.options.spp for kind glossy)", "ConfigError",
      r"point\.options: unknown option 'spp' for kind 'glossy'", "the option, the kind and the known options")
def yaml_use_unknown_option(d):
    _config(d, "scene: {name: glossy_floor}\npoint: {kind: glossy, options: {spp: 4}}\n")


@case("Python API", "a misspelled keyword to PipelineConfig (tile_sise=2)", "KeywordError",
      r"PipelineConfig: unknown keyword 'tile_sise'; did you mean 'tile_size'", "the keyword and the nearest name")
def pipeline_keyword(d):
    _sim().PipelineConfig(tile_sise=2)


@case("Python API", "a misspelled keyword to Camera (widht=64)", "KeywordError",
      r"Camera: unknown keyword 'widht'; did you mean 'width'", "the keyword and the nearest name")
def camera_keyword(d):
    _sim().Camera(widht=64)


@case("YAML config", "a misspelled plot column (y: raster.stee)", "ConfigError",
      r"c\.yaml:7: outputs\.plots\[0\]\.y: unknown column 'raster\.stee'; did you mean 'raster\.ste'",
      "the file, the line, the plot, the column and the nearest known ones")
def yaml_plot_column(d):
    _config(d, BASE + "outputs:\n  plots:\n    - kind: line\n      x: camera.coc_px\n      y: raster.stee\n")


@case("YAML config", "an unknown column in a derived expression (ops.totl / 1e9)", "ConfigError",
      r"c\.yaml:5: outputs\.derived\.gops: unknown column 'ops\.totl'.*did you mean 'ops\.total'",
      "the file, the line, the derived column and the nearest known ones")
def yaml_derived_column(d):
    _config(d, BASE + "outputs:\n  derived:\n    gops: 'ops.totl / 1e9'\n")


@case("YAML config", "a sweep whose algorithms need other sample tables (interleave, lines with stratified samples)",
      "ConfigError", r"2 of 3 sweep points are invalid \(nothing was rendered\).*'interleave' needs an interleaved "
      r"sample table.*'lines' needs a line-sample table", "every bad point, its sweep line and what it needs")
def yaml_sweep_combinations(d):
    _config(d, BASE + "sweep:\n  pipeline.algorithm: [tile, interleave, lines]\n")


@case("YAML config", "a --set value out of range (--set samples.spp=0)", "ConfigError",
      r"--set samples\.spp=0: samples\.spp: expected an integer in 1\.\.4096, got 0", "the flag, the key and the value")
def yaml_set_out_of_range(d):
    _config(d, BASE, overrides=["samples.spp=0"])


@case("YAML config", "a --set that makes the sweep's algorithms clash with the sample table (--set samples.kind=lines)",
      "ConfigError", r"c\.yaml:4 .*: pipeline\.algorithm: .*needs algorithm 'lines', got 'tile'.*"
      r"\(samples\.kind set by --set samples\.kind=lines\)", "the sweep line, the clash and the flag that set the partner")
def yaml_set_combination(d):
    _config(d, BASE + "sweep:\n  pipeline.algorithm: [tile, interval]\n", overrides=["samples.kind=lines"])


@case("YAML config", "an unknown key (camera.heigth)", "ConfigError", r"c\.yaml:4: unknown key 'camera\.heigth'",
      "the file, the line and the key")
def yaml_unknown_key(d):
    _config(d, "scene: {name: quad}\ncamera:\n  width: 24\n  heigth: 24\n")


@case("YAML config", "a string where an integer goes (camera.width: big)", "ConfigError", r"c\.yaml:2: camera\.width",
      "the file, the line, the key and the value")
def yaml_wrong_type(d):
    _config(d, "scene: {name: quad}\ncamera: {width: big}\n")


@case("YAML config", "samples.spp: -1 (refused when the point is built)", "ConfigError",
      r"samples\.spp: expected an integer in 1\.\.4096, got -1", "the key, the range and the value")
def yaml_bad_value(d):
    from experiments.config import build

    build(_config(d, BASE + "samples: {spp: -1}\n"))


@case("YAML config", "pipeline.algorithm: tilez", "ConfigError", r"c\.yaml:3: pipeline\.algorithm.*'tile'",
      "the file, the line, the key and the allowed values")
def yaml_bad_choice(d):
    _config(d, BASE + "pipeline: {algorithm: tilez}\n")


@case("YAML config", "extends: a cycle a.yaml -> b.yaml -> a.yaml", "ConfigError", r"extends: cycle .*a\.yaml.*b\.yaml.*a\.yaml",
      "the files of the cycle in order")
def yaml_extends_cycle(d):
    (d / "b.yaml").write_text("extends: a.yaml\n")
    _config(d, "extends: b.yaml\n" + BASE, name="a.yaml")


@case("YAML config", "extends: a missing file", "ConfigError", r"c\.yaml:1: extends: base config 'nope\.yaml' not found",
      "the file, the line and the missing name")
def yaml_extends_missing(d):
    _config(d, "extends: nope.yaml\n" + BASE)


@case("YAML config", "a sweep with an invalid value (pipeline.algorithm: [tile, tilez])", "ConfigError",
      r"c\.yaml:4 \(sweep point \{'pipeline\.algorithm': 'tilez'\}\): pipeline\.algorithm: .*'tilez'.*did you mean 'tile'", "the file, the line of the value, the key, the allowed values and the nearest one")
def yaml_sweep_value(d):
    from experiments.config import expand_sweep

    expand_sweep(_config(d, BASE + "sweep:\n  pipeline.algorithm: [tile, tilez]\n"), "c.yaml")


@case("YAML config", "a sweep over an unknown key (camera.cocpx)", "ConfigError", r"cocpx",
      "the sweep point and the key")
def yaml_sweep_key(d):
    from experiments.config import expand_sweep

    expand_sweep(_config(d, BASE + "sweep:\n  camera.cocpx: [1, 2]\n"), "c.yaml")


@case("YAML config", "text that is not YAML (an unclosed bracket)", "ConfigError", r"c\.yaml: .*line \d",
      "the file and the line")
def yaml_syntax(d):
    _config(d, "scene: {name: quad\ncamera: {width: 16}\n")


@case("YAML config", "a duplicate key", "ConfigError", r"c\.yaml.*duplicate key 'camera'", "the file, the line and the key")
def yaml_duplicate(d):
    _config(d, BASE + "camera: {width: 8}\n")


@case("YAML config", "a scene section with neither name nor path", "ConfigError",
      r"c\.yaml:1: scene: give exactly one of scene\.name or scene\.path", "the file, the line and the section")
def yaml_scene_both(d):
    _config(d, "scene: {}\n")


@case("YAML config", "--set without '=' (camera.coc_px)", "ConfigError", r"--set: expected key=value, got 'camera\.coc_px'",
      "the override")
def yaml_override(d):
    _config(d, BASE, overrides=["camera.coc_px"])


@case("YAML config", "a list where a mapping goes (camera: [1, 2])", "ConfigError", r"c\.yaml:2: camera", "the file, the line and the key")
def yaml_section_type(d):
    _config(d, "scene: {name: quad}\ncamera: [1, 2]\n")


# ---- command line --------------------------------------------------------------------------------

@case("command line", "a results directory that cannot be written (--results /proc/x)", "OutputDirError",
      r"results directory: cannot write to /proc/x.*--results DIR", "the directory, why, and the option that moves it")
def cli_results_unwritable(d):
    import os

    from experiments.paths import check_results_dir

    old = os.environ.get("RAST5D_RESULTS")
    os.environ["RAST5D_RESULTS"] = "/proc/x"
    try:
        check_results_dir()
    finally:
        if old is None:
            os.environ.pop("RAST5D_RESULTS")
        else:
            os.environ["RAST5D_RESULTS"] = old


@case("command line", "rast5d init into a directory that is not empty", "ConfigError",
      r"init: .* is not empty; give an empty or new directory, or --force", "the directory and --force")
def cli_init_not_empty(d):
    from experiments.cli import init_dir

    (d / "mine.txt").write_text("x")
    init_dir(d)


@case("command line", "rast5d render --point naming a key the sweep does not sweep (camera.cox)", "ConfigError",
      r"--point camera\.cox: not a swept key .*did you mean 'camera\.coc_px'", "the flag, the key and the swept keys")
def cli_point_unknown_key(d):
    from experiments.cli import parse_point, select_point
    from experiments.config import load_dict, validate

    p = d / "c.yaml"
    p.write_text(BASE + "sweep: {camera.coc_px: [0, 4]}\n")
    data, lines = load_dict(p)
    select_point(validate(data, str(p), lines), str(p), lines, parse_point("camera.cox=4"))


@case("command line", "rast5d render --point that leaves a swept key open", "ConfigError",
      r"--point: 2 points of .* match \{'camera\.coc_px': 4\}; also give pipeline\.algorithm",
      "the points matched and the keys still to give, with their values")
def cli_point_ambiguous(d):
    from experiments.cli import parse_point, select_point
    from experiments.config import load_dict, validate

    p = d / "c.yaml"
    p.write_text(BASE + "sweep: {camera.coc_px: [0, 4], pipeline.algorithm: [tile, bruteforce]}\n")
    data, lines = load_dict(p)
    select_point(validate(data, str(p), lines), str(p), lines, parse_point("camera.coc_px=4"))


@case("command line", "a results or pages directory inside the installed package (site-packages)", "OutputDirError",
      r"results directory: .* is inside the installed package; run from a working directory of your own or give "
      r"--results DIR", "the directory and the option that moves it")
def cli_results_in_package(d):
    import sysconfig

    from experiments.paths import check_output_dir

    check_output_dir(Path(sysconfig.get_paths()["purelib"]) / "results", "results directory",
                     "--results DIR or RAST5D_RESULTS")


@case("command line", "rast5d report --configs naming a folder that does not exist", "ConfigError",
      r"--configs: not a directory: .*nowhere", "the flag and the path")
def cli_configs_missing(d):
    from experiments.paths import configs_dir

    configs_dir(d / "nowhere")


@case("command line", "rast5d render --point with a value the sweep does not have (camera.coc_px=5)", "ConfigError",
      r"--point camera\.coc_px=5: not one of the sweep's values \[0, 4\]", "the flag, the value and the swept values")
def cli_point_unknown_value(d):
    from experiments.cli import parse_point, select_point
    from experiments.config import load_dict, validate

    p = d / "c.yaml"
    p.write_text(BASE + "sweep: {camera.coc_px: [0, 4]}\n")
    data, lines = load_dict(p)
    select_point(validate(data, str(p), lines), str(p), lines, parse_point("camera.coc_px=5"))


@case("command line", "rast5d render --point without '=' (camera.coc_px)", "ConfigError",
      r"--point camera\.coc_px: expected key=value\[,key=value\.\.\.\], got 'camera\.coc_px'", "the flag and the text")
def cli_point_malformed(d):
    from experiments.cli import parse_point

    parse_point("camera.coc_px")


@case("command line", "--set without '=' (--set camera.coc_px)", "ConfigError",
      r"--set: expected key=value, got 'camera\.coc_px'", "the flag and the text")
def cli_set_malformed(d):
    _config(d, BASE, overrides=["camera.coc_px"])


@case("command line", "a Dask scheduler address where nothing answers (--scheduler tcp://127.0.0.1:1, "
      "executor.connect_timeout_s: 2)", "ClusterError",
      r"executor: the Dask scheduler at tcp://127\.0\.0\.1:1 did not answer within 2 s .*is it running, and is the "
      r"address right\? \(--scheduler ADDRESS or executor\.address; executor\.connect_timeout_s",
      "the address, the wait, and the options that set them (within the wait: no hang)")
def cli_scheduler_silent(d):
    from experiments.run.executors import connect

    connect("tcp://127.0.0.1:1", 2)


@case("command line", "a result store on a file system whose exclusive file creation (the point locks) fails "
      "(a warning, shown here raised; the run goes on without locks)", "StoreWarning",
      r"result store .*: point locks do not work on this file system \(an exclusive create \(O_EXCL\) fails.*"
      r"may compute the same point again \(the first row stored is kept",
      "the store, what failed, and what it means for runs sharing the store")
def cli_store_without_locks(d):
    import errno
    import os
    import warnings

    from experiments.run import store

    class NoExclusiveCreate:  # the os module as the store sees it, on such a file system
        def open(self, path, flags, *args):
            if flags & os.O_EXCL:
                raise OSError(errno.ENOTSUP, os.strerror(errno.ENOTSUP), str(path))
            return os.open(path, flags, *args)

        def __getattr__(self, name):
            return getattr(os, name)

    real = store.os
    store.os = NoExclusiveCreate()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", store.StoreWarning)
            store.check_locks(d)
    finally:
        store.os = real
        store._LOCKS_CHECKED.pop(str(d / "points"), None)


# ---- scene files -------------------------------------------------------------------------------------

def _scene(d: Path, text: str, name: str = "s.yaml"):
    import models

    p = d / name
    p.write_text(text)
    return models.load(p)


@case("scene file", "a scene file that does not exist", "SceneError", r"scene file: not found: .*missing\.yaml \(tried ", "the path and every place tried")
def scene_missing(d):
    import models

    models.load(d / "missing.yaml")


@case("scene file", "a mesh that does not exist", "SceneError", r"s\.yaml: objects\[0\]\.mesh: file not found: gone\.obj \(tried ",
      "the scene file, the object, the name and every place tried")
def scene_mesh_missing(d):
    _scene(d, "objects:\n  - mesh: gone.obj\n")


@case("scene file", "a broken mesh (garbage bytes in an .obj)", "SceneError", r"bad\.obj", "the mesh file and what is wrong")
def scene_mesh_garbage(d):
    (d / "bad.obj").write_bytes(b"\x00\xff garbage \x01\x02 f 1 2\n")
    _scene(d, "objects:\n  - mesh: bad.obj\n")


@case("scene file", "a mesh with vertices but no faces", "SceneError", r"empty\.obj.*(no triangles|no faces|empty)",
      "the mesh file")
def scene_mesh_no_faces(d):
    (d / "empty.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    _scene(d, "objects:\n  - mesh: empty.obj\n")


@case("scene file", "an unknown key in an object (colour)", "SceneError", r"s\.yaml: unknown key 'colour' in objects\[0\]",
      "the file, the object and the key")
def scene_unknown_key(d):
    _scene(d, "objects:\n  - scene: quad\n    colour: [1, 0, 0]\n")


@case("scene file", "a scene file that is a list, not a mapping", "SceneError",
      r"s\.yaml: expected a mapping with 'objects' at the top level, got list", "the file")
def scene_not_mapping(d):
    _scene(d, "- scene: quad\n")


@case("scene file", "a negative scale in a transform", "SceneError", r"s\.yaml: objects\[0\]\.transform\.scale",
      "the file, the object and the field")
def scene_bad_scale(d):
    _scene(d, "objects:\n  - scene: quad\n    transform: {scale: -2}\n")


@case("scene file", "an unknown named scene", "SceneError", r"(unknown scene|not a registered).*'nosuch'",
      "the name and the known scenes")
def scene_unknown_name(d):
    _scene(d, "objects:\n  - scene: nosuch\n")


@case("scene file", "a named scene with an unknown parameter", "SceneError",
      r"scene 'quad': unknown parameter\(s\) sise; accepted: ", "the scene, the parameter and the accepted ones")
def scene_bad_param(d):
    _scene(d, "objects:\n  - scene: quad\n    params: {sise: 3}\n")


@case("scene file", "a mesh file of an unknown type (.xyz)", "SceneError", r"unknown scene file type '\.xyz'",
      "the path, the suffix and the known types")
def scene_suffix(d):
    import models

    (d / "m.xyz").write_text("")
    models.load(d / "m.xyz")


@case("scene file", "a texture PNG with 2 channels (grey + alpha) beside an OBJ", None, "",
      "accepted: grey is expanded to RGB, alpha kept")
def scene_texture_la(d):
    from PIL import Image

    (d / "q.obj").write_text("v -1 -1 -3\nv 1 -1 -3\nv 0 1 -3\nvt 0 0\nvt 1 0\nvt 0.5 1\nf 1/1 2/2 3/3\n")
    Image.fromarray(np.full((5, 3, 2), 128, np.uint8), mode="LA").save(d / "q_texture.png")
    scene = _scene(d, "objects:\n  - mesh: q.obj\n")
    assert scene.textures and scene.textures[0].shape[2] in (3, 4)


@case("scene file", "zero-area and duplicate triangles in a mesh", None, "",
      "accepted: loaded as given (the engine culls zero-area triangles at setup)")
def scene_degenerate_mesh(d):
    (d / "z.obj").write_text("v 0 0 -3\nv 1 0 -3\nv 2 0 -3\nv 0 1 -3\nf 1 2 3\nf 1 2 4\nf 1 2 4\n")
    scene = _scene(d, "objects:\n  - mesh: z.obj\n")
    assert scene.n_triangles >= 1


# ---- running and the page ------------------------------------------------------------------------------

def _type_name(error) -> str:
    return error if isinstance(error, str) else error.__name__


def outcome(c: Case, d: Path) -> tuple[str, str]:
    """(exception type name, message with the scratch folder written <dir>) of running a case; ("-", "")
    when it raised nothing."""
    try:
        c.run(d)
    except Exception as e:  # noqa: BLE001 - the table records whatever is raised
        message = str(e).replace(str(d.resolve()), "<dir>").replace(str(d), "<dir>")
        repo = str(Path(__file__).resolve().parents[2])
        message = message.replace(repo, "<repo>")
        return type(e).__name__, message
    return "-", ""


def expected_types(c: Case) -> tuple[type, ...]:
    """The exception classes a row's error name stands for."""
    import models
    import sim
    from experiments.config import ConfigError as XConfigError

    from experiments.paths import OutputDirError
    from experiments.run.executors import ClusterError
    from experiments.run.store import StoreWarning

    names = {"SceneInputError": (sim.SceneInputError,), "ConfigError": (sim.ConfigError, XConfigError),
             "SceneError": (models.SceneError,), "ValueError": (ValueError,), "TypeError": (TypeError,),
             "KeywordError": (sim.errors.KeywordError,), "MemoryLimitError": (sim.MemoryLimitError,),
             "OutputDirError": (OutputDirError,), "ClusterError": (ClusterError,), "StoreWarning": (StoreWarning,)}
    return names[_type_name(c.error)]


def _cell(text: str) -> str:
    text = re.sub(r"\s+", " ", text).replace("|", "\\|")
    return text if len(text) <= 700 else text[:697] + "..."


def page() -> str:
    """docs/errors.md: every case with the exception and message it gives today."""
    counts = {k: sum(1 for c in CASES if c.category == k) for k in CATEGORIES}
    lines = [
        "# Bad input: what rast5d refuses and how",
        "",
        "Generated by `python -m tests.catalogue.bad_inputs` from the table in `tests/catalogue/bad_inputs.py`,",
        "which `tests/test_errors_catalogue.py` runs (each case must raise the type shown with a message",
        "naming what the last column says; none may crash the interpreter or hang). A test fails while this",
        "page is stale. Rows whose exception is `-` are inputs accepted on purpose. `<dir>` stands for the",
        "folder the case ran in.",
        "",
        "Every refused input raises a subclass of `rast5d.Error` (`sim.Error`, a `ValueError`): `ConfigError`",
        "(camera, sample table, pipeline, hardware) with `MemoryLimitError` (a render over",
        "`PipelineConfig.memory_limit_bytes`), `KeywordError` (an unknown keyword, also a `TypeError`),",
        "`experiments.config.ConfigError` (YAML configs, `--set` and sweep points, file:line first) with",
        "`PlotError`, and `OutputDirError` (a results or pages directory that cannot be written); and",
        "`SceneError` (scene files and `models.Scene`: `models.SceneError` is this class) with",
        "`SceneInputError` (scene arrays). The bindings (`sim._core`) raise `ValueError` or `TypeError`.",
        "A run stopped by a fault of what it runs on, not of its input, raises `RunStopped` (`ClusterError`:",
        "a Dask scheduler silent or lost; `StoreError`: a full or read-only store; docs/store.md).",
        "The exception column gives each case's own type.",
        "",
        f"{len(CASES)} cases: " + ", ".join(f"{k} {v}" for k, v in counts.items()) + ".",
        "",
    ]
    for cat in CATEGORIES:
        lines += [f"## {cat}", "", "| input | exception | message | points to |", "|---|---|---|---|"]
        for c in CASES:
            if c.category != cat:
                continue
            with tempfile.TemporaryDirectory() as tmp:
                kind, message = outcome(c, Path(tmp))
            lines.append(f"| {_cell(c.input)} | `{kind}` | {_cell(message) or '(accepted)'} | {_cell(c.points_to)} |")
        lines.append("")
    return "\n".join(lines)


def main() -> None:
    out = Path(__file__).resolve().parents[2] / "docs" / "errors.md"
    out.write_text(page())
    print(f"{len(CASES)} cases -> {out}")


if __name__ == "__main__":
    sys.exit(main())
