"""pipeline.precision in renders (docs/precision.md): validation naming the field and the value; the
fixed-point and float64 sample tests against the independent float64 ray caster (differences only within
the stated distance of an edge); every exact algorithm renders the same image at a fixed-point sample or
tile precision (the tile tests stay conservative) on full-size screens with the hard cases (vertices far
off screen, near the near plane, behind the camera); overflow is detected; a fixed-point depth buffer
resolves close layers by submission order exactly where the closed form says their depths round
together."""
from __future__ import annotations

import numpy as np
import pytest

import sim
from sim.errors import ConfigError
from tests import reference as ref

FIX4 = {"fixed": {"int_bits": 40, "frac_bits": 4}}


def fixed(int_bits, frac_bits):
    return {"fixed": {"int_bits": int_bits, "frac_bits": frac_bits}}


# ----------------------------------------------------------------------------- validation

@pytest.mark.parametrize("value,field,shown", [
    ({"sample": "float16"}, "PipelineConfig.precision.sample", "'float16'"),
    ({"depth": "float64"}, "PipelineConfig.precision.depth", "'float64'"),
    ({"tile": fixed(0, 4)}, "PipelineConfig.precision.tile.fixed.int_bits", "0"),
    ({"tile": fixed(20, 25)}, "PipelineConfig.precision.tile.fixed.frac_bits", "25"),
    ({"sample": fixed(60, 24)}, "PipelineConfig.precision.sample.fixed", "109"),
    ({"tile": {"fixed": {"int_bits": 20}}}, "PipelineConfig.precision.tile", "'int_bits': 20"),
    ({"tile": {"fixed": {"int_bits": 20, "frac_bits": 4}, "float32": 1}}, "PipelineConfig.precision.tile", "float32"),
    ({"sample": fixed(True, 4)}, "PipelineConfig.precision.sample.fixed.int_bits", "True"),
    ({"bogus": "float32"}, "PipelineConfig.precision", "bogus"),
])
def test_bad_precision_names_the_field_and_the_value(value, field, shown):
    with pytest.raises(ConfigError) as err:
        sim.PipelineConfig(precision=value)
    assert field in str(err.value) and shown in str(err.value)


def test_precision_defaults_and_normal_form():
    assert sim.PipelineConfig().precision == {"tile": "float64", "sample": "float32", "depth": "float32"}
    cfg = sim.PipelineConfig(precision={"sample": fixed(np.int64(30), 8)})
    assert cfg.precision == {"tile": "float64", "sample": fixed(30, 8), "depth": "float32"}
    assert type(cfg.precision["sample"]["fixed"]["int_bits"]) is int


def test_engine_refuses_bad_precision_naming_the_field():
    p = sim._core.RenderParams()
    p.precision_sample = fixed(30, 8)
    assert p.precision_sample == fixed(30, 8)
    with pytest.raises(ValueError, match="precision_tile.*'half'"):
        p.precision_tile = "half"
    with pytest.raises(ValueError, match="precision_sample.*int_bits"):
        p.precision_sample = fixed(0, 4)


def test_yaml_precision_is_checked_at_load():
    from experiments.config import validate

    ok = validate({"scene": {"name": "spot"}, "pipeline": {"precision": {"sample": FIX4}}}, "t.yaml")
    assert ok.pipeline.precision["sample"] == FIX4
    from experiments.config import ConfigError

    with pytest.raises(ConfigError, match=r"t\.yaml: pipeline\.precision.*smaple"):
        validate({"scene": {"name": "spot"}, "pipeline": {"precision": {"smaple": "float32"}}}, "t.yaml")


# ----------------------------------------------------------------------------- against the ray caster

def _coverage(cam, p0, p1, table, precision, algorithm="bruteforce"):
    cfg = sim.PipelineConfig(algorithm=algorithm, precision=precision, threads=1)
    res = sim.render(ref.make_scene(p0, p1), cam, table, cfg, export_samples=True, timing=False)
    return res.sample_triangle[..., ] >= 0, res


@pytest.mark.parametrize("sample,tol_px", [("float64", ref.EDGE_TOL_PX), (fixed(40, 4), 2.0 ** -3),
                                           (fixed(40, 8), 2.0 ** -7)], ids=["float64", "fixed4", "fixed8"])
def test_sample_precision_agrees_with_the_ray_caster_away_from_edges(sample, tol_px):
    """Coverage of one triangle at a time (2D/3D/4D/5D kinds, vertices behind the camera and near the
    plane) differs from the float64 ray caster only within tol_px of an edge (seen from the sample's
    lens point) or of the near plane; with 4 fraction bits the snapping does change coverage."""
    rng = np.random.default_rng(7)
    table = sim.SampleTable.stratified(spp=4, seed=3)
    differ = 0
    for i in range(24):
        cam = ref.random_camera(rng)
        p0, p1 = ref.random_triangle(rng, cam, ref.KINDS[i % len(ref.KINDS)])
        cov, _ = _coverage(cam, p0[None], p1[None], table, {"sample": sample})
        pts = ref.table_points(table, cam)
        rc = ref.ray_cast(cam, p0, p1, pts.astype(np.float64))
        edge = ref.edge_distance_px(cam, p0, p1, pts.astype(np.float64))
        near = ref.near_rel_distance(cam, rc.w)
        mism = cov != rc.hit
        differ += int((mism & (edge > ref.EDGE_TOL_PX)).sum())
        bad = mism & (edge > tol_px) & (near > 1e-3)
        assert not bad.any(), f"#{i}: {int(bad.sum())} samples differ {edge[bad].max():.3g} px from an edge"
    if sample != "float64" and sample["fixed"]["frac_bits"] == 4:
        assert differ > 0, "4 sub-pixel bits must move some decisions beyond the float32 tolerance"


# ----------------------------------------------------------------------------- conservative tile tests

HARD = ref.hard_cases()


def _hard_scene(name, size):
    cam_kw, p0, p1, _ = HARD[name]
    cam = sim.Camera(**{**cam_kw, "width": size, "height": size})
    return cam, ref.make_scene(p0, p1)


def _same_image_everywhere(precision, size, names, algorithms):
    strat = sim.SampleTable.stratified(spp=2, seed=5)
    inter = sim.SampleTable.interleaved(spp=2, n_lens=16, seed=5)
    for name in names:
        cam, scene = _hard_scene(name, size)
        for table, algos in ((strat, [a for a in algorithms if a not in sim.interleaved_algorithms()]),
                             (inter, [a for a in algorithms if a in sim.interleaved_algorithms()])):
            base = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce", precision=precision),
                              timing=False)
            for algo in algos:
                if algo == "bruteforce":
                    continue
                r = sim.render(scene, cam, table, sim.PipelineConfig(algorithm=algo, precision=precision),
                               timing=False)
                assert np.array_equal(r.image, base.image), f"{name}: {algo} differs from bruteforce at {precision}"


@pytest.mark.slow
@pytest.mark.parametrize("precision", [{"sample": fixed(40, 4)}, {"tile": fixed(40, 4)}, {"tile": fixed(40, 8)},
                                       {"sample": "float64", "tile": fixed(40, 6)}],
                         ids=["sample_fixed4", "tile_fixed4", "tile_fixed8", "sample64_tile_fixed6"])
def test_every_algorithm_renders_the_same_image_at_fixed_precision(precision):
    """The tile tests stay conservative against a fixed-point sample test (tiles widened by the snap
    margin) and as fixed-point 2D tests themselves: every point-sample algorithm renders brute force's
    image, on a 512 px screen with the hard cases (far off screen, behind the camera, at the near plane,
    huge blur, moving through the near plane)."""
    _same_image_everywhere(precision, 512, sorted(HARD), sim.algorithm_names("points"))


def test_tile_algorithms_render_the_same_image_at_fixed_precision():
    """The fast tier's share of the test above: the algorithms with tile tests, both stages fixed at 4
    sub-pixel bits, 256 px."""
    _same_image_everywhere({"sample": fixed(40, 4), "tile": fixed(40, 4)}, 256,
                           ["crosses_focus_plane", "huge_blur_tiny_triangles", "moving_through_near_plane",
                            "vertex_behind_camera"],
                           ["tile", "interval", "laine", "laine5d", "hinterleave", "tile_interleaved"])


def test_float32_tile_test_runs_and_counts_like_float64():
    """Precision changes decisions, never the operation counts."""
    cam, scene = _hard_scene("crosses_focus_plane", 256)
    cam = sim.Camera(**{**HARD["crosses_focus_plane"][0], "width": 256, "height": 256, "coc_px": 0.0})
    table = sim.SampleTable.stratified(spp=4, seed=1)
    a = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="tile"), timing=False)
    b = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="tile", precision={"tile": "float32"}),
                   timing=False)
    assert a.flat_stats["ops.total"] == b.flat_stats["ops.total"]
    assert b.flat_stats["setup.class_2d"] >= 1


def test_overflow_is_counted():
    """A 512 px screen needs about 20 integer bits (reports/paper/precision.md); 8 overflow."""
    cam = sim.Camera(width=512, height=512, fov_y_deg=45.0, focus_distance=5.0, coc_px=0.0)
    p0 = np.array([[ref.screen_to_world(cam, 10, 20, 5.0), ref.screen_to_world(cam, 500, 40, 5.0),
                    ref.screen_to_world(cam, 200, 490, 5.0)]])
    table = sim.SampleTable.stratified(spp=1, seed=1)
    for algo, prec, counter in (("bruteforce", {"sample": fixed(8, 4)}, "precision.sample_overflows"),
                                ("tile", {"tile": fixed(8, 4)}, "precision.tile_overflows")):
        few = sim.render(ref.make_scene(p0), cam, table, sim.PipelineConfig(algorithm=algo, precision=prec),
                         timing=False)
        assert few.flat_stats[counter] > 0
        enough = {k: fixed(30, 4) for k in prec}
        ok = sim.render(ref.make_scene(p0), cam, table, sim.PipelineConfig(algorithm=algo, precision=enough),
                        timing=False)
        assert ok.flat_stats[counter] == 0 and ok.flat_stats["raster.samples_hit"] > 0


# ----------------------------------------------------------------------------- depth

def test_fixed_depth_rounds_close_layers_together():
    """Two full-screen layers at view depths w1 < w2: with a float32 depth buffer the nearer wins
    everywhere; with frac_bits bits the stored z = round(z 2^F) 2^-F, and where the two round to the
    same value the first submitted (the farther one here) keeps the sample (the depth test is z < zbuf).
    The closed form decides which case each F is."""
    cam = sim.Camera(width=8, height=8, fov_y_deg=45.0, focus_distance=5.0, coc_px=0.0, near=0.1)

    def layer(w):
        return np.array([[ref.screen_to_world(cam, -4, -4, w), ref.screen_to_world(cam, 40, -4, w),
                          ref.screen_to_world(cam, -4, 40, w)]])

    w_far, w_near = 5.0, 4.9
    scene = ref.make_scene(np.concatenate([layer(w_far), layer(w_near)]))
    table = sim.SampleTable.stratified(spp=4, seed=2)
    z = lambda w: 1.0 - cam.near / w  # noqa: E731
    for depth in ("float32", fixed(1, 4), fixed(1, 8), fixed(1, 16)):
        r = sim.render(scene, cam, table, sim.PipelineConfig(precision={"depth": depth}), export_samples=True,
                       timing=False)
        if depth == "float32":
            expected = 1
        else:
            F = depth["fixed"]["frac_bits"]
            same = round(z(w_far) * 2 ** F) == round(z(w_near) * 2 ** F)
            expected = 0 if same else 1
            assert np.all(np.isin(r.sample_depth * 2 ** F, np.round(r.sample_depth * 2 ** F)))
        assert np.all(r.sample_triangle == expected), depth
