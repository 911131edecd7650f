"""The 5D pipeline's intervals: conservative (û, v̂, t̂) and ẑ per tile against brute force (random and adversarial moving/defocused triangles, hypothesis), same image for every algorithm with time intervals, clip planes and HiZ, per-class costs (static triangles pay nothing for time, in-focus nothing for lens), conservative mode, occlusion queries."""
from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sim
from tests import reference
from tests.reference import Tris

pytestmark = pytest.mark.invariants

ALGORITHMS = sim.algorithm_names("points")
INTERLEAVED = sorted(name for name, _desc, needs in sim._core.algorithms() if needs)
ARBITRARY = [a for a in ALGORITHMS if a not in INTERLEAVED]
WIDTH, HEIGHT, FOCUS, NEAR = 32, 24, 4.0, 0.05
HYPO = dict(deadline=None, derandomize=True, database=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.data_too_large])



def make_scene(p0, p1=None) -> Tris:
    return reference.make_scene(p0, p1, colour_seed=99)


def world(px, py, depth, width=WIDTH, height=HEIGHT, fov_y_deg=45.0):
    """World point at view depth `depth` seen by the lens centre at pixel (px, py)."""
    s_y = 1.0 / math.tan(math.radians(fov_y_deg) / 2.0)
    s_x = s_y * height / width
    return np.array([(2.0 * px / width - 1.0) * depth / s_x, (1.0 - 2.0 * py / height) * depth / s_y, -depth])


def camera(coc, width=WIDTH, height=HEIGHT, lens="disk"):
    return sim.Camera(width=width, height=height, fov_y_deg=45, focus_distance=FOCUS, coc_px=coc, lens=lens, near=NEAR)


@functools.lru_cache(maxsize=None)
def table(spp=16, seed=3):
    return sim.SampleTable.stratified(spp=spp, seed=seed)


# ---------------------------------------------------------------- conservative intervals and ẑ


def check_conservative(scene, cam, spp=16, time_splits=4, depth_rel_tol=2e-3):
    """Every brute-force hit of triangle i at (px, py, s) lies in the conservative-mode record of
    (px, py, i) (1 x 1 tiles: the same interval functions the tile algorithm uses): (u, v, t) in
    (û, v̂, t̂) and depth in ẑ (geometric, up to float rounding; the HiZ-widened ẑ, whose margin is
    each pair's own rounding bound, is tested through images in test_zhat_margin_*).
    Returns the number of hits checked."""
    tab = table(spp)
    samples = tab.samples(cam.lens)  # (P, P, spp, 5)
    P = samples.shape[0]
    cons = sim.conservative_raster(scene, cam, sim.PipelineConfig(time_splits=time_splits, time_strata=max(8, time_splits)))
    rec = {(int(r["x"]), int(r["y"]), int(r["triangle"])): r for r in cons.records}
    checked = 0
    for i in range(scene.positions.shape[0]):
        one = make_scene(scene.positions[i:i + 1], scene.positions_t1[i:i + 1])
        res = sim.render(one, cam, tab, sim.PipelineConfig(algorithm="bruteforce", threads=1), export_samples=True)
        ys, xs, ss = np.nonzero(res.sample_triangle == 0)
        for y, x, s in zip(ys.tolist(), xs.tolist(), ss.tolist()):
            r = rec.get((x, y, i))
            assert r is not None, f"triangle {i}: hit at pixel ({x}, {y}) sample {s} but no conservative record"
            _, _, u, v, t = samples[y % P, x % P, s]
            assert r["u_lo"] <= u <= r["u_hi"] and r["v_lo"] <= v <= r["v_hi"], (i, x, y, s, u, v, r)
            assert r["t_lo"] <= t <= r["t_hi"], (i, x, y, s, t, r)
            z = float(res.sample_depth[y, x, s])
            w = NEAR / (1.0 - z)
            wlo, whi = NEAR / (1.0 - float(r["z_lo"])), NEAR / max(1e-30, 1.0 - float(r["z_hi"]))
            assert wlo * (1 - depth_rel_tol) <= w <= whi * (1 + depth_rel_tol), (i, x, y, s, w, wlo, whi)
            checked += 1
    return checked


def moving_tri(c0, c1, d0, d1, size=6.0, rot=0.0):
    """A triangle around pixel c0 at depth d0 moving to pixel c1 at depth d1."""
    offs = [(0.0, 0.0), (size, 0.3 * size), (0.2 * size, size)]
    a = [world(c0[0] + ox, c0[1] + oy, d0) for ox, oy in offs]
    b = [world(c1[0] + (ox * math.cos(rot) - oy * math.sin(rot)), c1[1] + (ox * math.sin(rot) + oy * math.cos(rot)), d1)
         for ox, oy in offs]
    return np.array(a), np.array(b)


ADVERSARIAL = {
    # zero motion: a static triangle through the same machinery
    "zero_motion": [moving_tri((10, 8), (10, 8), 3.0, 3.0)],
    "fast_600px": [moving_tri((-250, 8), (350, 14), 4.0, 4.0, size=5)],
    "changes_facing": [(np.array([world(8, 6, 4), world(20, 6, 4), world(12, 18, 4)]),
                        np.array([world(8, 6, 4), world(20, 6, 4), world(12, -6, 4)]))],
    # the triangle's plane sweeps through the camera: edge-on to the eye at mid-shutter
    "plane_through_camera": [(np.array([world(6, 6, 3), world(20, 8, 3), world(10, 18, 2)]),
                              np.array([world(6, 6, 3), world(20, 8, 3), np.array([0.0, 0.0, 1.0])]))],
    # a vertex crosses w = 0 (and the near plane) during the shutter
    "crosses_w0": [(np.array([world(6, 6, 3), world(20, 8, 3), world(10, 18, 1.0)]),
                    np.array([world(6, 6, 3), world(20, 8, 3), np.array([0.2, -0.1, 1.5])]))],
    # moving through the focus plane with defocus (CoC changes sign during the shutter)
    "through_focus": [moving_tri((6, 6), (18, 12), 2.0, 8.0, size=8)],
    "rotating": [moving_tri((8, 8), (14, 10), 4.0, 4.5, size=10, rot=2.5)],
}


@pytest.mark.parametrize("coc", [0.0, 6.0, 25.0])
@pytest.mark.parametrize("name", sorted(ADVERSARIAL))
def test_conservative_adversarial(name, coc):
    tris = ADVERSARIAL[name]
    scene = make_scene(np.array([a for a, _ in tris]), np.array([b for _, b in tris]))
    cam = camera(coc)
    check_conservative(scene, cam)
    # and the tile algorithm at every tile size and split count renders brute force's image
    ref = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="bruteforce", threads=1), export_samples=True)
    for tile in (1, 2, 8):
        for splits in (1, 4, 16):
            res = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="tile", tile_size=tile,
                                                                      time_splits=splits, time_strata=max(8, splits),
                                                                      threads=1),
                             export_samples=True)
            assert np.array_equal(ref.sample_triangle, res.sample_triangle), (name, coc, tile, splits)
            assert ref.flat_stats["raster.samples_hit"] == res.flat_stats["raster.samples_hit"]


@settings(max_examples=40, **HYPO)
@given(c0=st.tuples(st.floats(-10, 40), st.floats(-10, 34)), motion=st.tuples(st.floats(-120, 120), st.floats(-60, 60)),
       d0=st.floats(0.6, 12.0), d1=st.floats(0.6, 12.0), size=st.floats(0.5, 20.0), rot=st.floats(-3.0, 3.0),
       coc=st.sampled_from([0.0, 4.0, 20.0]))
def test_conservative_random(c0, motion, d0, d1, size, rot, coc):
    a, b = moving_tri(c0, (c0[0] + motion[0], c0[1] + motion[1]), d0, d1, size=size, rot=rot)
    check_conservative(make_scene(a[None], b[None]), camera(coc), spp=8)


@pytest.mark.parametrize("coc", [0.0, 6.0, 25.0])
@pytest.mark.parametrize("name", sorted(ADVERSARIAL))
def test_laine5d_same_samples_as_bruteforce_adversarial(name, coc):
    """laine5d's per-tile time and lens bounds are conservative on the adversarial moving classes: every
    sample brute force hits, laine5d hits (same sample ownership, same image), at tile sizes 1, 2 and 8."""
    tris = ADVERSARIAL[name]
    scene = make_scene(np.array([a for a, _ in tris]), np.array([b for _, b in tris]))
    cam = camera(coc)
    ref = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="bruteforce", threads=1), export_samples=True)
    for tile in (1, 2, 8):
        res = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="laine5d", tile_size=tile, threads=1),
                         export_samples=True)
        assert np.array_equal(ref.sample_triangle, res.sample_triangle), (name, coc, tile)
        assert np.array_equal(ref.image, res.image)


@settings(max_examples=40, **HYPO)
@given(c0=st.tuples(st.floats(-10, 40), st.floats(-10, 34)), motion=st.tuples(st.floats(-120, 120), st.floats(-60, 60)),
       d0=st.floats(0.3, 12.0), d1=st.floats(0.3, 12.0), size=st.floats(0.5, 20.0), rot=st.floats(-3.0, 3.0),
       coc=st.sampled_from([0.0, 4.0, 20.0]))
def test_laine5d_conservative_random(c0, motion, d0, d1, size, rot, coc):
    a, b = moving_tri(c0, (c0[0] + motion[0], c0[1] + motion[1]), d0, d1, size=size, rot=rot)
    scene, cam = make_scene(a[None], b[None]), camera(coc)
    ref = sim.render(scene, cam, table(8), sim.PipelineConfig(algorithm="bruteforce", threads=1), export_samples=True)
    res = sim.render(scene, cam, table(8), sim.PipelineConfig(algorithm="laine5d", threads=1), export_samples=True)
    assert np.array_equal(ref.sample_triangle, res.sample_triangle)
    # and it tests fewer samples than brute force once the triangle moves far
    if abs(motion[0]) + abs(motion[1]) > 60 and coc == 0.0:
        assert res.flat_stats["raster.samples_tested"] <= ref.flat_stats["raster.samples_tested"]


# ---------------------------------------------------------------- same image, every algorithm


def mixed_scene(n=24, seed=5, motion_px=30.0):
    """Static and moving, in-focus and defocused triangles, overlapping in depth."""
    rng = np.random.default_rng(seed)
    p0, p1 = [], []
    for i in range(n):
        c = rng.uniform(-4, [WIDTH + 4, HEIGHT + 4])
        depth = FOCUS if i % 4 in (0, 1) else FOCUS * rng.uniform(0.4, 2.5)
        size = rng.uniform(3, 14)
        moving = i % 2 == 1
        d1 = depth if i % 4 == 1 else depth * (rng.uniform(0.8, 1.25) if moving else 1.0)
        m = rng.uniform(-motion_px, motion_px, 2) if moving else np.zeros(2)
        a, b = moving_tri(c, c + m, depth, d1, size=size, rot=rng.uniform(-1, 1) if moving else 0.0)
        p0.append(a), p1.append(b)
    return make_scene(np.array(p0), np.array(p1))


@pytest.mark.parametrize("coc", [0.0, 8.0])
def test_same_image_all_algorithms_clip_and_hiz(coc):
    scene, cam = mixed_scene(), camera(coc)
    configs = [dict()] + [dict(clip={"u": [-0.5, 0.8], "t": [0.1, 0.7]})]
    for cfg in configs:
        ref = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="bruteforce", **cfg), export_samples=True)
        assert ref.flat_stats["raster.samples_hit"] > 0
        for a in ARBITRARY:
            res = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm=a, **cfg), export_samples=True)
            assert np.array_equal(ref.image, res.image), (a, cfg)
            assert np.array_equal(ref.sample_triangle, res.sample_triangle), (a, cfg)
            assert ref.flat_stats["raster.samples_hit"] == res.flat_stats["raster.samples_hit"], (a, cfg)
        for hiz_tile in (2, 8):
            for zhat in ("planes", "vertex"):
                res = sim.render(scene, cam, table(), sim.PipelineConfig(
                    algorithm="tile", hiz={"enabled": True, "tile_size": hiz_tile}, zhat=zhat, **cfg),
                    export_samples=True)
                assert np.array_equal(ref.image, res.image), ("hiz", hiz_tile, zhat, cfg)
                assert np.array_equal(ref.sample_depth.view(np.uint32), res.sample_depth.view(np.uint32))
                assert np.array_equal(ref.sample_triangle, res.sample_triangle)
                # visible hits are identical; raster.samples_hit drops by the hits of culled pairs
                assert ref.flat_stats["depth.passes"] == res.flat_stats["depth.passes"]
                assert res.flat_stats["raster.samples_hit"] <= ref.flat_stats["raster.samples_hit"]


def test_clip_semantics():
    """No hit outside the closed clip box, for every algorithm; the tile algorithm's intervals keep
    almost all clipped samples from being tested."""
    scene, cam = mixed_scene(), camera(8.0)
    clip = {"u": [-0.5, 0.8], "v": [-1.0, 0.3], "t": [0.1, 0.7]}
    samples = table().samples(cam.lens)
    P = samples.shape[0]
    for a in ("bruteforce", "tile"):
        res = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm=a, clip=clip), export_samples=True)
        ys, xs, ss = np.nonzero(res.sample_triangle >= 0)
        s = samples[ys % P, xs % P, ss]
        assert len(ys) > 0
        for k, axis in ((2, "u"), (3, "v"), (4, "t")):
            assert np.all((s[:, k] >= clip[axis][0]) & (s[:, k] <= clip[axis][1])), (a, axis)
        if a == "bruteforce":
            brute_clipped = res.flat_stats["interval.samples_clipped"]
        else:
            # (static triangles keep all times: they pay nothing for time, clip included)
            assert res.flat_stats["interval.samples_clipped"] < 0.75 * brute_clipped


def depth_layers(n_layers=6, width=WIDTH, height=HEIGHT, margin=2):
    """Full-screen quads, front to back (submission order), each a little smaller than the last."""
    tris = []
    for k in range(n_layers):
        d = 2.0 + 0.5 * k
        m = margin
        a, b, c, e = (world(x, y, d, width, height) for x, y in ((-m, -m), (width + m, -m), (width + m, height + m),
                                                                   (-m, height + m)))
        tris += [[a, b, c], [a, c, e]]
    return make_scene(np.array(tris))


def test_hiz_culls_hidden_layers_without_changing_the_image():
    scene, cam = depth_layers(), camera(0.0)
    off = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="tile"), export_samples=True)
    on = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="tile", hiz={"enabled": True, "tile_size": 8}),
                    export_samples=True)
    assert np.array_equal(off.image, on.image)
    f = on.flat_stats
    # layers 2..6 are entirely behind layer 1: every one of their pairs is zmax-culled
    assert f["zcull.pairs_culled"] >= 0.8 * 5 / 6 * f["zcull.pairs"]
    assert f["depth.bytes_read"] < 0.3 * off.flat_stats["depth.bytes_read"]
    assert off.flat_stats["depth.bytes_read"] == 4 * off.flat_stats["depth.tests"]
    assert f["depth.bytes_written"] == 4 * f["depth.passes"] == 4 * off.flat_stats["depth.passes"]
    # back to front: nothing is culled, every pair after the first is in front of zmin (no reads)
    back = make_scene(scene.positions[::-1].copy())
    r = sim.render(back, cam, table(), sim.PipelineConfig(algorithm="tile", hiz={"enabled": True, "tile_size": 8}))
    assert r.flat_stats["zcull.pairs_culled"] == 0
    assert r.flat_stats["zcull.pairs_zmin"] > 0.5 * r.flat_stats["zcull.pairs"]
    assert r.flat_stats["depth.reads_skipped"] > 0


def close_layers(gap, n_layers=4, moving=False, tilt=0.0, ext=2):
    """Full-screen quads front to back, `gap` apart in view depth (relative), optionally tilted and
    moving (each layer slides 3 px and recedes 1 % over the shutter)."""
    tris, tris1 = [], []
    for k in range(n_layers):
        d = 2.0 * (1.0 + gap) ** k
        quad = [(-ext, -ext), (WIDTH + ext, -ext), (WIDTH + ext, HEIGHT + ext), (-ext, HEIGHT + ext)]
        a, b, c, e = (world(x, y, d * (1.0 + tilt * x / WIDTH)) for x, y in quad)
        a1, b1, c1, e1 = (world(x + 3, y, 1.01 * d * (1.0 + tilt * x / WIDTH)) for x, y in quad)
        tris += [[a, b, c], [a, c, e]]
        tris1 += [[a1, b1, c1], [a1, c1, e1]] if moving else [[a, b, c], [a, c, e]]
    return make_scene(np.array(tris), np.array(tris1))


@pytest.mark.parametrize("coc,moving,tilt", [(0.0, False, 0.0), (0.0, False, 0.3), (6.0, False, 0.0),
                                             (0.0, True, 0.0), (6.0, True, 0.2)])
def test_zhat_margin_culls_close_layers_without_changing_the_image(coc, moving, tilt):
    """Layers 3 % apart in depth: the per-pair rounding margin (far below the former fixed 12.5 %, which
    culled none of them) lets HiZ cull the hidden layers; the image and every visible sample's depth equal
    the render without HiZ (a margin too small would cull visible samples)."""
    scene, cam = close_layers(0.03, moving=moving, tilt=tilt, ext=2 + 3 * int(coc)), camera(coc)
    off = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="bruteforce"), export_samples=True)
    for zhat in ("planes", "vertex"):
        on = sim.render(scene, cam, table(), sim.PipelineConfig(
            algorithm="tile", hiz={"enabled": True, "tile_size": 8}, zhat=zhat, zhat_stats=True), export_samples=True)
        assert np.array_equal(off.image, on.image), zhat
        assert np.array_equal(off.sample_depth.view(np.uint32), on.sample_depth.view(np.uint32)), zhat
        f = on.flat_stats
        if not moving and tilt == 0.0:  # flat static layers: every pair of layers 2..4 is culled
            assert f["zcull.pairs_culled"] >= 0.7 * 3 / 4 * f["zcull.pairs"], (zhat, f["zcull.pairs_culled"])
        elif zhat == "planes" or tilt == 0.0:  # (tilted: the vertex box spans 20 % of depth)
            assert f["zcull.pairs_culled"] > 0, zhat
        # the compared interval is at least the geometric one: width of W over near is positive
        assert f["zcull.width_zhat"] > 0


def test_zhat_width_measures_the_compared_interval():
    """zcull.width_zhat sums the widths of the intervals compared with HiZ (ẑ widened by each pair's
    margin): for flat static layers at W = d the geometric width is 0, so the sum is the margins alone,
    2 rho d per pair in units of 1e-6 near, far below the former fixed 2 x 12.5 %."""
    scene, cam = close_layers(0.03), camera(0.0)
    f = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="tile", zhat_stats=True)).flat_stats
    mean_rel_width = f["zcull.width_zhat"] / f["zcull.pairs"] * 1e-6 * NEAR / 2.0
    assert 0 < mean_rel_width < 1e-3, mean_rel_width


def test_zhat_planes_tighter_than_vertex_minmax():
    scene, cam = depth_layers(2), camera(0.0)
    tilted = scene.positions.copy()
    tilted[:, :, 2] -= 0.3 * tilted[:, :, 0]  # slanted walls: the planes bound each tile's depth
    r = sim.render(make_scene(tilted), cam, table(), sim.PipelineConfig(algorithm="tile", zhat_stats=True))
    f = r.flat_stats
    assert f["zcull.width_zhat"] < 0.5 * f["zcull.width_vertex"]
    rv = sim.render(make_scene(tilted), cam, table(), sim.PipelineConfig(algorithm="tile", zhat_stats=True, zhat="vertex"))
    assert rv.flat_stats["zcull.width_zhat"] == rv.flat_stats["zcull.width_vertex"] == f["zcull.width_vertex"]


# ---------------------------------------------------------------- model only what the scene needs


def test_static_pays_nothing_for_time_and_in_focus_nothing_for_lens():
    scene, cam = mixed_scene(), camera(8.0)
    r = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="tile", time_splits=4))
    f = r.flat_stats
    assert f["interval.time_tests_3d"] % 4 == 0
    for cls in ("2d", "3d", "4d", "5d"):
        assert f[f"setup.class_{cls}"] > 0, cls
    assert f["interval.time_tests_2d"] == f["interval.time_tests_4d"] == 0
    assert f["interval.lens_tests_2d"] == f["interval.lens_tests_3d"] == 0
    assert f["interval.time_tests_3d"] > 0 and f["interval.time_tests_5d"] > 0
    assert f["interval.lens_tests_4d"] > 0 and f["interval.lens_tests_5d"] > 0
    # the static triangles' work does not depend on the time machinery at all
    static = make_scene(scene.positions[0::2], scene.positions_t1[0::2])
    assert np.array_equal(static.positions, static.positions_t1)
    runs = [sim.render(static, cam, table(), sim.PipelineConfig(algorithm="tile", time_splits=s, time_strata=ns,
                                                                motion_test=m)).flat_stats
            for s, ns, m in ((1, 1, "bounds"), (16, 64, "intervals"))]
    keep = [k for k in runs[0] if k != "time.wall_s"]
    assert {k: runs[0][k] for k in keep} == {k: runs[1][k] for k in keep}


def test_time_intervals_raise_ste_on_fast_motion():
    scene, cam = mixed_scene(motion_px=100.0), camera(0.0)
    ste = {m: sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="tile", motion_test=m)).flat_stats
           for m in ("bounds", "intervals")}
    assert ste["intervals"]["raster.samples_tested_3d"] < 0.6 * ste["bounds"]["raster.samples_tested_3d"]


@pytest.mark.parametrize("coc", [0.0, 10.0])
def test_documented_ops_equal_exact_ops(coc):
    scene, cam = mixed_scene(n=10), camera(coc)
    for cfg in (dict(), dict(clip={"u": [-0.4, 1.0], "t": [0.2, 0.9]}, hiz={"enabled": True, "tile_size": 4},
                             zhat_stats=True)):
        a = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="tile", **cfg)).flat_stats
        b = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="tile", op_count="exact", **cfg)).flat_stats
        for k in a:
            if k.startswith("ops."):
                assert a[k] == b[k] or (isinstance(a[k], float) and math.isnan(a[k])), (k, a[k], b[k], cfg)


# ---------------------------------------------------------------- conservative mode, queries


def test_conservative_records_and_tz_reduction_agree():
    scene, cam = mixed_scene(n=8), camera(5.0)
    recs = sim.conservative_raster(scene, cam).records
    red = sim.conservative_raster(scene, cam, reduce="tz_box")
    assert len(recs) == red.count.sum() == red.flat_stats["conservative.records"]
    tz = np.full((HEIGHT, WIDTH, 4), [np.inf, np.inf, -np.inf, -np.inf], np.float32)
    np.minimum.at(tz[..., 0], (recs["y"], recs["x"]), recs["t_lo"])
    np.minimum.at(tz[..., 1], (recs["y"], recs["x"]), recs["z_lo"])
    np.maximum.at(tz[..., 2], (recs["y"], recs["x"]), recs["t_hi"])
    np.maximum.at(tz[..., 3], (recs["y"], recs["x"]), recs["z_hi"])
    assert np.array_equal(tz, red.tz_box)
    with pytest.raises(sim.ConfigError, match="max_records"):
        sim.conservative_raster(scene, cam, max_records=10)
    with pytest.raises(sim.ConfigError, match="reduce"):
        sim.conservative_raster(scene, cam, reduce="boxes")


@pytest.mark.parametrize("coc", [0.0, 8.0])
def test_occlusion_queries(coc):
    cam = camera(coc)
    wall = depth_layers(1, margin=30)  # covers the screen from every lens point
    hidden = make_scene(np.array([moving_tri((8, 8), (20, 12), 8.0, 9.0, size=6)[0]]),
                        np.array([moving_tri((8, 8), (20, 12), 8.0, 9.0, size=6)[1]]))
    front = make_scene(hidden.positions * 0.2, hidden.positions_t1 * 0.2)  # same pixels, depth 1.6-1.8: in front
    for mode in ("samples", "intervals"):
        h = sim.occlusion_query(wall, hidden, cam, table(), mode=mode)
        v = sim.occlusion_query(wall, front, cam, table(), mode=mode)
        assert not h.visible and v.visible, mode
        if mode == "samples":
            assert h.samples_passed == 0 and v.samples_passed > 0
            assert h.work["raster.samples_tested"] > 0
        else:
            assert h.work["raster.samples_tested"] == 0 and h.work["occlusion.pairs_tested"] > 0
            assert v.work["occlusion.pairs_tested"] == 1  # aborted at the first visible tile
    with pytest.raises(sim.ConfigError, match="tile"):
        sim.occlusion_query(wall, hidden, cam, table(), sim.PipelineConfig(algorithm="bruteforce"), mode="intervals")
    # Sample-based queries through the gpu_* depth-cull stage give the same answers; the algorithms without
    # that stage are refused (they would draw the query as an occluder and report it hidden).
    gpu = sim.PipelineConfig(algorithm="gpu_hexagon2d")
    assert not sim.occlusion_query(wall, hidden, cam, table(), gpu).visible
    assert sim.occlusion_query(wall, front, cam, table(), gpu).visible
    for algorithm in ("bruteforce", "interval", "laine"):
        with pytest.raises((sim.ConfigError, ValueError), match=f"occlusion queries.*got '{algorithm}'"):
            sim.occlusion_query(wall, front, cam, table(), sim.PipelineConfig(algorithm=algorithm))


def test_config_errors():
    for bad in (dict(time_splits=3), dict(time_splits=16), dict(time_strata=12), dict(clip={"w": [0, 1]}), dict(clip={"t": [0.5, 0.2]}), dict(clip={"u": 1}),
                dict(hiz={"enabled": True, "tile_size": 1}, tile_size=2), dict(hiz={"enabled": "yes"}),
                dict(zhat="boxes"), dict(motion_test="x")):
        with pytest.raises(sim.ConfigError):
            sim.PipelineConfig(**bad)


@pytest.mark.slow
@settings(max_examples=300, **HYPO)
@given(c0=st.tuples(st.floats(-40, 70), st.floats(-40, 60)), motion=st.tuples(st.floats(-600, 600), st.floats(-300, 300)),
       d0=st.floats(0.2, 20.0), d1=st.floats(-1.0, 20.0), size=st.floats(0.3, 40.0), rot=st.floats(-3.2, 3.2),
       coc=st.sampled_from([0.0, 2.0, 10.0, 40.0]), splits=st.sampled_from([1, 2, 8]))
def test_conservative_random_large(c0, motion, d0, d1, size, rot, coc, splits):
    """More and wilder triangles (depths through the lens plane, motion up to 600 px)."""
    a, b = moving_tri(c0, (c0[0] + motion[0], c0[1] + motion[1]), d0, d1 if abs(d1) > 1e-3 else 1e-3,
                      size=size, rot=rot)
    check_conservative(make_scene(a[None], b[None]), camera(coc), spp=8, time_splits=splits)
