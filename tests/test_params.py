"""The parameter declaration (params.def): one name per parameter in every layer, and what is
generated from it (RenderParams, sim.PipelineConfig, the stub) agrees with it."""
import dataclasses

import pytest

import sim
from sim import _core, params

pytestmark = pytest.mark.smoke


def test_generated_stub_is_current():
    text = params.STUB_PATH.read_text()
    assert params.stub_text(text) == text, "sim/_core.pyi is stale: run `python -m sim.gen_stub`"


def test_engine_name_is_the_user_name():
    for s in params.specs():
        if s.kind == "engine":
            assert s.engine == s.name.replace(".", "_"), s
            assert hasattr(_core.RenderParams(), s.engine), s.engine


def test_engine_defaults_are_the_declared_defaults():
    p = _core.RenderParams()
    for s in params.specs():
        if s.kind == "engine":
            assert getattr(p, s.engine) == s.default, s.name


def test_pipeline_config_is_the_pipeline_layer():
    fields = {f.name: f for f in dataclasses.fields(sim.PipelineConfig)}
    assert list(fields) == [s.name for s in params.layer("pipeline")]
    docs = sim.PipelineConfig.field_docs()
    for s in params.layer("pipeline"):
        assert docs[s.name]["doc"] == sim.references.cite(s.doc) and docs[s.name]["unit"] == s.unit
        assert docs[s.name]["default"] == s.user_default


def test_every_pipeline_value_reaches_the_engine():
    """Each engine row of the pipeline layer is copied by name: set a non-default value, read it back."""
    cfg = sim.PipelineConfig(algorithm="tile", tile_size=4, halfspace={"h": False}, oracle="full", c_sample=2.5,
                             op_count="exact", shading="msaa", texture_filter="bilinear", texture_layout="morton",
                             motion_test="bounds", zhat="vertex", clip={"t": [0.25, 0.75]},
                             hiz={"enabled": True, "tile_size": 4})
    p = _core.RenderParams()
    params.set_layer(p, "pipeline", cfg)
    assert (p.algorithm, p.tile_size, p.halfspace_h, p.halfspace_H) == ("tile", 4, False, True)
    assert (p.oracle, p.c_sample, p.c_tile, p.op_count) == ("full", 2.5, -1.0, "exact")
    assert (p.shading, p.texture_filter, p.texture_layout) == ("msaa", "bilinear", "morton")
    assert (p.motion_test, p.zhat, p.clip_t, p.clip_u) == ("bounds", "vertex", [0.25, 0.75], [-1.0, 1.0])
    assert (p.hiz_enabled, p.hiz_tile_size, p.lens_grid) == (True, 4, 4)


def test_choice_registries():
    assert sim.shading_modes() == ["per_sample", "msaa", "per_lens_cell", "cache", "none"]
    assert sim.texture_filters() == ["bilinear", "trilinear"]
    assert sim.texture_layouts() == ["linear", "blocked", "morton"]
    p = _core.RenderParams()
    with pytest.raises(ValueError, match=r"oracle: unknown 'x' \(known: simplified, full\)"):
        p.oracle = "x"
    for s in params.specs():
        if s.registry and s.registry != "algorithms":
            assert list(s.choices) == params.choices(s.registry)


SECTIONS = {"tex_cache": sim.TextureCacheConfig, "depth_buffer": sim.DepthBufferConfig,
            "color_buffer": sim.ColorBufferConfig, "dram": sim.DramConfig}


def test_hardware_rows_match_hardware_config():
    """The hardware rows of params.def (texture cache, depth and colour buffers, DRAM) are the fields
    of their sim.HardwareConfig sections (names, defaults, units, docs) and are set from
    sim.HardwareConfig by their nested names, so their engine defaults are its."""
    hw = sim.HardwareConfig().describe()
    groups = {s.name: s for s in params.layer("hardware") if s.kind == "group"}
    assert set(groups) == set(SECTIONS)
    for name, group in groups.items():
        assert [f.name for f in dataclasses.fields(SECTIONS[name])] == [m.key for m in group.members]
        docs = sim.HardwareConfig.field_docs()[name]
        assert docs["doc"] == group.doc
        for m in group.members:
            default = m.default
            assert hw[name][m.key] == default, m.name
            assert docs["fields"][m.key] == {"default": default, "unit": m.unit, "doc": m.doc}, m.name
    with pytest.raises(sim.ConfigError, match=r"HardwareConfig.tex_cache.count: expected an integer in 1..1024"):
        sim.HardwareConfig(tex_cache={"count": 0})
    with pytest.raises(sim.ConfigError, match=r"tex_cache.line_bytes: expected a power of two"):
        sim.HardwareConfig(tex_cache={"line_bytes": 48})
    p = _core.RenderParams()
    p.tex_cache_count = 0  # the engine checks the same declared domain
    with pytest.raises(ValueError, match="tex_cache_count"):
        _render_one(p)


def _render_one(p):
    import numpy as np

    p.width = p.height = 8
    _core.render(p, np.zeros((0, 3, 3), np.float32), np.zeros((0, 3, 3), np.float32),
                 np.zeros((0, 3, 3), np.float32), np.zeros((1, 1, 1, 5), np.float32), np.zeros((0,), np.int32),
                 np.zeros((0, 2), np.float32))


def test_registries_by_name():
    """Every choice parameter is one registry of the engine, read and written by name; the lens
    shapes and occlusion-query modes of Python and of the schema are those registries."""
    import experiments.config.schema as schema
    import typing

    registries = {s.registry for s in params.specs() if s.registry and s.registry != "algorithms"}
    assert registries == set(_core.choices())
    assert sim.lens.LENS_SHAPES == tuple(params.choices("lens_shapes")) == ("disk", "square", "hexagon")
    assert typing.get_args(schema.CameraSpec.model_fields["lens"].annotation)[0] == \
        typing.Literal[sim.lens.LENS_SHAPES]
    assert sim.intervals.query_modes() == ["samples", "intervals"]
    p = _core.RenderParams()
    p.lens_shape, p.query_mode = "hexagon", "intervals"
    assert (p.lens_shape, p.query_mode) == ("hexagon", "intervals")
    with pytest.raises(ValueError, match=r"lens_shape: unknown 'oval' \(known: disk, square, hexagon\)"):
        p.lens_shape = "oval"


def test_interval_parameters_are_the_intervals_stage():
    assert params.stage("pipeline", "intervals") == (
        "motion_test", "time_splits", "time_strata", "clip", "zhat", "zhat_margin", "zhat_stats", "hiz")


def test_sample_kinds_come_from_the_generator_registry():
    import experiments.config.schema as schema
    import typing

    assert typing.get_args(schema.SamplesSpec.model_fields["kind"].annotation) == tuple(sim.SampleTable.kinds())
    assert typing.get_args(schema.MetricsSpec.model_fields["reference_kind"].annotation) == (
        "random", "stratified", "sobol")
