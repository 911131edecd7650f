"""Bad input raises a clear exception naming the field and the value, and never crashes."""
import types

import numpy as np
import pytest

import models
import sim

pytestmark = pytest.mark.smoke


def tri_scene(p=None):
    p = np.array([[[-1.0, -1.0, -5.0], [1.0, -1.0, -5.0], [0.0, 1.0, -5.0]]]) if p is None else p
    return types.SimpleNamespace(positions=p, positions_t1=p, colors=None)


CAM = dict(width=32, height=32, focus_distance=5.0, coc_px=4.0)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_vertices(bad):
    p = np.array([[[-1.0, -1.0, -5.0], [1.0, bad, -5.0], [0.0, 1.0, -5.0]]])
    with pytest.raises(sim.SceneInputError, match=r"scene\.positions: triangle 0 vertex 1 is not finite"):
        sim.render(tri_scene(p), sim.Camera(**CAM), sim.SampleTable.random(spp=4))
    with pytest.raises(models.SceneError, match="positions"):
        models.Scene.from_arrays(p)


@pytest.mark.parametrize("spp", [0, 4097, -3, 2.5, True])
def test_spp_out_of_range(spp):
    with pytest.raises(ValueError, match=r"spp.*" + (str(spp) if not isinstance(spp, bool) else "True")):
        sim.SampleTable.stratified(spp=spp)


@pytest.mark.parametrize("field,value", [("width", 0), ("height", 0), ("width", 16385), ("height", 100000),
                                         ("width", 3.5), ("fov_y_deg", 0), ("fov_y_deg", 180), ("focus_distance", -1),
                                         ("coc_px", -2), ("near", 0), ("lens", "octagon")])
def test_camera_fields(field, value):
    args = dict(CAM, **{field: value})
    with pytest.raises(sim.ConfigError, match=rf"Camera\.{field}.*{value}"):
        sim.Camera(**args)


def test_camera_both_blur_parameters():
    with pytest.raises(sim.ConfigError, match="coc_px or aperture_radius"):
        sim.Camera(width=8, height=8, coc_px=3, aperture_radius=0.1)


def test_coc_and_aperture_round_trip():
    cam = sim.Camera(width=640, height=480, fov_y_deg=50, focus_distance=3.0, coc_px=12.5)
    back = sim.Camera(width=640, height=480, fov_y_deg=50, focus_distance=3.0, aperture_radius=cam.aperture_radius)
    assert back.coc_px == pytest.approx(12.5, rel=1e-12)
    assert cam.coc_radius_px(1e12) == pytest.approx(12.5)
    assert cam.coc_radius_px(3.0) == 0


def test_memory_estimate_refused_before_allocating():
    cam = sim.Camera(width=16384, height=16384, focus_distance=5.0)
    with pytest.raises(sim.ConfigError, match=r"memory: estimated .* GiB exceeds .*memory_limit_bytes.*width=16384"):
        sim.render(tri_scene(), cam, sim.SampleTable.random(spp=64),
                   sim.PipelineConfig(memory_limit_bytes=1 << 30))


@pytest.mark.parametrize("positions,match", [
    (np.zeros((2, 3)), r"scene\.positions: expected shape \(N, 3, 3\), got \(2, 3\)"),
    (np.zeros((1, 4, 3)), r"expected shape \(N, 3, 3\), got \(1, 4, 3\)"),
    (np.array([[["a", "b", "c"]] * 3]), r"scene\.positions: expected a numeric array, got dtype"),
])
def test_wrong_shapes_and_dtypes(positions, match):
    with pytest.raises(sim.SceneInputError, match=match):
        sim.render(types.SimpleNamespace(positions=positions), sim.Camera(**CAM), sim.SampleTable.random(spp=4))


def test_not_a_scene():
    with pytest.raises(sim.SceneInputError, match="scene: expected an object with .positions"):
        sim.render(42, sim.Camera(**CAM), sim.SampleTable.random(spp=4))


def test_mismatched_t1():
    s = types.SimpleNamespace(positions=np.zeros((2, 3, 3)), positions_t1=np.zeros((1, 3, 3)))
    with pytest.raises(sim.SceneInputError, match=r"positions_t1: expected 2 triangles, got 1"):
        sim.render(s, sim.Camera(**CAM), sim.SampleTable.random(spp=4))


@pytest.mark.parametrize("kwargs,match", [
    (dict(algorithm="fastest"), r"PipelineConfig\.algorithm: unknown 'fastest' \(known: .*bruteforce"),
    (dict(tile_size=3), r"PipelineConfig\.tile_size: expected 1, 2, 4 or 8, got 3"),
    (dict(lens_grid=5), r"PipelineConfig\.lens_grid: .* got 5"),
    (dict(halfspace={"x": True}), r"PipelineConfig\.halfspace"),
    (dict(op_count="approx"), r"PipelineConfig\.op_count: .* got 'approx'"),
    (dict(threads=-1), r"PipelineConfig\.threads: .* got -1"),
    (dict(bin_size=12), r"PipelineConfig\.bin_size"),
])
def test_pipeline_fields(kwargs, match):
    with pytest.raises(sim.ConfigError, match=match):
        sim.PipelineConfig(**kwargs)


def test_interleaved_algorithm_needs_interleaved_table():
    with pytest.raises(sim.ConfigError, match="'interleave' needs an interleaved sample table"):
        sim.render(tri_scene(), sim.Camera(**CAM), sim.SampleTable.random(spp=4),
                   sim.PipelineConfig(algorithm="interleave"))


def test_missing_and_unreadable_mesh(tmp_path):
    with pytest.raises(models.SceneError, match="not found"):
        models.load_mesh(tmp_path / "nope.obj")
    garbage = tmp_path / "garbage.obj"
    garbage.write_bytes(b"\x00\xff not an obj \x01")
    with pytest.raises(models.SceneError, match="garbage.obj"):
        models.load_mesh(garbage)


def test_empty_scene_renders_black():
    empty = types.SimpleNamespace(positions=np.zeros((0, 3, 3)), positions_t1=np.zeros((0, 3, 3)), colors=None)
    for algo in ("bruteforce", "tile", "interval", "laine"):
        r = sim.render(empty, sim.Camera(**CAM), sim.SampleTable.random(spp=4), sim.PipelineConfig(algorithm=algo))
        assert r.image.shape == (32, 32, 3) and not r.image.any()
        assert r.flat_stats["raster.samples_tested"] == 0


def test_unknown_yaml_key(tmp_path):
    from experiments.config import ConfigError, load_config

    cfg = tmp_path / "c.yaml"
    cfg.write_text("scene: {name: quad}\ncamera: {widht: 32}\n")
    with pytest.raises(ConfigError, match=r"c\.yaml:2: unknown key 'camera\.widht'"):
        load_config(cfg)
    cfg.write_text("scene: {name: quad}\nscene: {name: bunny}\n")
    with pytest.raises(ConfigError, match="duplicate key 'scene'"):
        load_config(cfg)
    with pytest.raises(ConfigError, match="file not found"):
        load_config(tmp_path / "missing.yaml")


def test_config_files_read_as_the_python_yaml_parser_reads_them(tmp_path):
    """Config files are parsed once (by libyaml where PyYAML has it): every bundled config gives the
    data and the line of every key that PyYAML's pure-Python SafeLoader gives, parsed on its own; a
    syntax error quotes the offending line under a caret, as the Python parser words it."""
    import yaml

    from experiments.config import ConfigError, load, load_config
    from experiments.paths import bundled_configs

    files = sorted(bundled_configs().rglob("*.yaml"))
    assert len(files) > 50
    for f in files:
        text = f.read_text()
        want = (yaml.load(text, Loader=yaml.SafeLoader),  # noqa: S506 - the reference parser
                load._node_lines(yaml.compose(text, Loader=yaml.SafeLoader), str(f)))
        assert load._read_yaml(f) == want, f
    bad = tmp_path / "bad.yaml"
    bad.write_text("scene: {name: quad}\ncamera: [1, 2\nsamples: {spp: 4}\n")
    with pytest.raises(ConfigError, match=r"(?s)not valid YAML: while parsing a flow sequence.*line 3.*samples: \{spp: 4\}\n +\^"):
        load_config(bad)
