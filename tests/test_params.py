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
        assert docs[s.name]["doc"] == s.doc and docs[s.name]["unit"] == s.unit
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


def test_hardware_rows_match_hardware_config():
    """The texture-cache rows are set from sim.HardwareConfig by their nested names, so their engine
    defaults are HardwareConfig's."""
    hw = sim.HardwareConfig().describe()
    for s in params.layer("hardware"):
        group, key = s.name.split(".")
        assert hw[group][key] == s.default, s.name
