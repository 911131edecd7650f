"""The rasterizer's uses (sim.uses; [Nilsson 2012] §4-§7, [McGuire 2010]): each checked against a closed form, a
brute-force computation or a statistical test that does not run the code under test."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import models
import sim
from sim import uses

pytestmark = pytest.mark.invariants


def _layers_scene(alphas, colors=None, depth0=2.0):
    """Full-screen squares, front to back, with the given alphas."""
    tris, cols = [], []
    for i, a in enumerate(alphas):
        z = -(depth0 + 0.5 * i)
        h = 5.0
        tris += [[(-h, -h, z), (h, -h, z), (h, h, z)], [(-h, -h, z), (h, h, z), (-h, h, z)]]
        c = (0.2 + 0.15 * i, 0.9 - 0.2 * i, 0.5) if colors is None else colors[i]
        cols += [c, c]
    return models.Scene.from_arrays(np.array(tris, float), colors=np.array(cols, float)).with_alpha(
        np.repeat(np.asarray(alphas, float), 2))


CAM = dict(width=32, height=32, fov_y_deg=45.0, focus_distance=3.0)


# ---- stochastic transparency ([McGuire 2010]) ---------------------------------------------------------------

def test_transparency_alpha_one_is_opaque_bit_for_bit():
    sc = models.named("transparent_layers", width=32, height=32)
    cam = sim.Camera(**sc.camera_hint)
    table = sim.SampleTable.stratified(spp=8, seed=3)
    ones = sim.render(sc.with_alpha(np.ones(sc.n_triangles)), cam, table)
    none = sim.render(sc.with_alpha(None), cam, table)
    assert np.array_equal(ones.image, none.image)
    assert ones.flat_stats["alpha.samples_tested"] == 0


def test_transparency_alpha_zero_is_invisible_bit_for_bit():
    """A layer of alpha exactly 0 in front of opaque layers changes nothing (every sample is discarded)."""
    sc = _layers_scene([0.0, 1.0, 1.0])
    cam = sim.Camera(**CAM)
    table = sim.SampleTable.stratified(spp=4, seed=1)
    with_zero = sim.render(sc, cam, table)
    without = sim.render(models.Scene.from_arrays(sc.positions[2:], colors=sc.colors[2:]), cam, table)
    assert np.array_equal(with_zero.image, without.image)
    assert with_zero.flat_stats["alpha.samples_discarded"] == with_zero.flat_stats["alpha.samples_tested"] == 32 * 32 * 4


@pytest.mark.parametrize("stratified", [False, True])
def test_transparency_winners_follow_the_over_operator_chi2(stratified):
    """Per sample the surviving front layer is layer i with probability a_i prod_{j<i} (1 - a_j): chi-square
    over 16k samples of a constant stack (masks uncorrelated across layers, independent or stratified)."""
    alphas = [0.5, 0.25, 0.75]
    sc = _layers_scene(alphas)
    cam = sim.Camera(**CAM)
    r = sim.render(sc, cam, sim.SampleTable.stratified(spp=16, seed=2), sim.PipelineConfig(alpha_stratified=stratified),
                   export_samples=True)
    layer = np.where(r.sample_triangle >= 0, r.sample_triangle // 2, len(alphas)).ravel()
    counts = np.bincount(layer, minlength=len(alphas) + 1)
    p, through = [], 1.0
    for a in alphas:
        p.append(through * a)
        through *= 1 - a
    p.append(through)
    _, pval = stats.chisquare(counts, np.asarray(p) * counts.sum())
    assert pval > 1e-3, (counts, p)


def test_stratified_masks_keep_floor_or_ceil_of_alpha_spp_per_pixel():
    big = [[(-20.0, -20.0, -2.0), (20.0, -20.0, -2.0), (0.0, 20.0, -2.0)]]  # one triangle over the screen
    sc = models.Scene.from_arrays(np.array(big)).with_alpha([0.3])
    for spp in (8, 12):
        r = sim.render(sc, sim.Camera(**CAM), sim.SampleTable.stratified(spp=spp, seed=1),
                       sim.PipelineConfig(alpha_stratified=True), export_samples=True)
        kept = (r.sample_triangle >= 0).sum(axis=2)
        assert set(np.unique(kept)) <= {int(np.floor(0.3 * spp)), int(np.ceil(0.3 * spp))}
        assert kept.mean() == pytest.approx(0.3 * spp, rel=0.05)


def test_transparency_converges_to_sorted_blending():
    """The error against sorted alpha blending (float64 ray cast, same sample positions) falls as spp^-1/2,
    and the mean error over the image is zero within its noise (correct on average)."""
    sc = models.named("transparent_layers", width=48, height=48)
    cam = sim.Camera(**sc.camera_hint)
    rmse, bias = {}, {}
    for spp in (4, 64):
        r = uses.stochastic_transparency(sc, cam, sim.SampleTable.stratified(spp=spp, seed=7))
        rmse[spp] = r.flat_stats["transparency.rmse"]
        bias[spp] = float(np.mean(r.image - r.arrays["reference"]))
        assert r.flat_stats["transparency.max_layers"] == 8  # back wall + 6 squares + the tilted one
    assert 0.15 < rmse[64] / rmse[4] < 0.4, rmse  # 1/4 expected
    assert abs(bias[64]) < 3 * rmse[64] / 48, bias


def test_transparency_reference_is_order_independent_and_engine_mean_too(rng):
    sc = models.named("transparent_layers", width=32, height=32, tilted=False)
    cam = sim.Camera(**sc.camera_hint)
    table = sim.SampleTable.stratified(spp=32, seed=5)
    perm = rng.permutation(sc.n_triangles)
    shuffled = models.Scene.from_arrays(sc.positions[perm], colors=sc.colors[perm]).with_alpha(sc.alpha[perm])
    a = uses.stochastic_transparency(sc, cam, table)
    b = uses.stochastic_transparency(shuffled, cam, table)
    assert np.allclose(a.arrays["reference"], b.arrays["reference"], atol=1e-6)
    assert b.flat_stats["transparency.rmse"] < 1.5 * a.flat_stats["transparency.rmse"] + 0.005


def test_transparency_bad_alpha_is_a_clear_error():
    sc = _layers_scene([0.5])
    with pytest.raises(models.SceneError, match="alpha"):
        sc.with_alpha([0.5, 1.5])
    with pytest.raises(sim.ConfigError, match="scene.alpha"):
        uses.stochastic_transparency(sc.with_alpha(None), sim.Camera(**CAM), sim.SampleTable.stratified(spp=1))


# ---- the rasterizer as a sampler ([Nilsson 2012] §5) ----------------------------------------------------------

def test_chi2_sf_matches_scipy():
    from sim.uses.common import chi2_sf

    for x, k in [(0.5, 1), (3.0, 2), (26.0, 26), (40.0, 26), (300.0, 242), (1.0, 80), (120.0, 80)]:
        assert chi2_sf(x, k) == pytest.approx(stats.chi2.sf(x, k), rel=1e-9, abs=1e-14)


@pytest.mark.parametrize("coc, depth, spp", [(0.0, 3.0, 16), (6.0, 2.0, 32)])
def test_sampler_simploid_points_are_uniform(coc, depth, spp):
    """Chi-square over 3^d cells of the warped unit cube; calibrated for a random table (its p-values spread
    over (0, 1): uniform seeds measured 0.28-1.0 at 128 px), so the bound p > 1e-3 fails one correct run in a
    thousand. Power: test_sampler_chi2_rejects_a_mildly_non_uniform_table."""
    sc = models.named("sampler_simploids", depth=depth, width=128, height=128)
    cam = sim.Camera(coc_px=coc, **{**sc.camera_hint, "focus_distance": 3.0})
    r = uses.sample_simploids(sc, cam, sim.SampleTable.random(spp=spp, seed=11))
    f = r.flat_stats
    n, e = f["sampler.points"], f["sampler.expected_points"]
    assert abs(n - e) < 5 * np.sqrt(e), (n, e)
    assert f["sampler.chi2_p"] > 1e-3
    assert f["sampler.chi2_dof"] == (3 ** 5 - 1 if coc else 3 ** 3 - 1)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_sampler_chi2_rejects_a_mildly_non_uniform_table(seed):
    """The test can fail, on a small bias: shutter times warped t -> t^1.2 (the time density then runs from
    infinite at t = 0 down to 0.83 at t = 1: about a fifth fewer samples late in the shutter). At 128 px and
    16 spp (about 4,500 points) it is rejected at p < 1e-3 for 8 of 8 seeds measured (t^1.1: 1 of 8); at
    64 px (about 1,100 points) t^1.2 is rejected for 3 of 8 and t^1.1 never."""
    sc = models.named("sampler_simploids", width=128, height=128)
    cam = sim.Camera(**sc.camera_hint)
    s = np.array(sim.SampleTable.random(spp=16, seed=seed).samples())
    s[..., 4] = s[..., 4] ** 1.2
    r = uses.sample_simploids(sc, cam, sim.SampleTable.from_array(s))
    assert r.flat_stats["sampler.chi2_p"] < 1e-3


def test_sampler_voids_get_no_points_and_cells_are_uniform():
    """Counts per kept cell against the null of pixel-stratified samples (every pixel holds spp samples:
    mean spp x area, variance spp x sum f (1 - f) over the pixels a cell covers a share f of); calibrated
    for a random table (seeds measured 0.01-0.99); a multinomial chi-square gives p = 1 here for every
    table, random or not, and so tests nothing. Power: test_sampler_voids_reject_a_biased_table."""
    sc = models.named("sampler_voids", width=64, height=64)
    cam = sim.Camera(**sc.camera_hint)
    r = uses.sample_simploids(sc, cam, sim.SampleTable.random(spp=8, seed=2), domain="voids")
    f = r.flat_stats
    assert f["sampler.void_points"] == 0
    assert f["sampler.chi2_p"] > 1e-3
    assert abs(f["sampler.points"] - f["sampler.expected_points"]) < 5 * np.sqrt(f["sampler.expected_points"])
    with pytest.raises(sim.ConfigError, match="domain"):
        uses.sample_simploids(sc, cam, sim.SampleTable.random(spp=1), domain="cube")


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_sampler_voids_reject_a_biased_table(seed):
    """The void domain's test can fail: samples that avoid the last quarter of every pixel in x (a table
    denser by a third on the rest) are rejected at p < 1e-3 (measured: a fifth avoided, 6 of 8 seeds at 8 spp;
    a tenth, 0 of 8)."""
    sc = models.named("sampler_voids", width=64, height=64)
    cam = sim.Camera(**sc.camera_hint)
    s = np.array(sim.SampleTable.random(spp=16, seed=seed).samples())
    s[..., 0] *= 0.75
    r = uses.sample_simploids(sc, cam, sim.SampleTable.from_array(s), domain="voids")
    assert r.flat_stats["sampler.chi2_p"] < 1e-3


# ---- motion-blurred soft shadows ([Nilsson 2012] §7) ------------------------------------------------------------

def _shadow_run(motion=0.0, **options):
    sc = models.named("shadow_planes", motion=motion, width=48, height=48)
    cam = sim.Camera(**sc.camera_hint)
    opts = dict(light_resolution=128, light_grid=4, reference_grid=4)
    opts.update(options)
    return sc, uses.soft_shadows(sc, cam, sim.SampleTable.stratified(spp=16, seed=1), **opts)


@pytest.mark.parametrize("motion", [0.0, 0.6])
def test_shadow_one_pass_equals_accumulation_passes(motion):
    _, r = _shadow_run(motion)
    f = r.flat_stats
    assert f["shadow.maps_equal"] is True
    assert f["shadow.accum_setups"] == f["shadow.light_samples"] * f["shadow.onepass_setups"]


def test_shadow_lookup_matches_brute_force_rays():
    """Shadow-map visibility of receiver points against the segment to each light point intersected with the
    plate analytically (away from one map texel of the plate's shadow edges)."""
    from sim.uses import shadows

    h, lc, R = 0.5, np.array([-0.8, 2.0, 0.0]), 0.3
    sc = models.named("shadow_planes", occluder_height=h)
    light = shadows.light_camera(lc, R, 90.0, 256)
    uvt = shadows.light_samples(3)
    maps, _ = shadows.shadow_maps(sc, light, uvt)
    rng = np.random.default_rng(5)
    pts = np.stack([rng.uniform(-1.5, 1.5, 4000), np.zeros(4000), rng.uniform(-1.2, 1.2, 4000)], 1)
    texel = 2 * lc[1] * np.tan(np.radians(45)) / 256
    for s in range(len(uvt)):
        lp = lc + np.array([uvt[s, 0] * R, 0.0, -uvt[s, 1] * R])
        f = h / lp[1]
        xp, zp = pts[:, 0] + f * (lp[0] - pts[:, 0]), pts[:, 2] + f * (lp[2] - pts[:, 2])
        blocked = (xp >= -1.0) & (xp <= 0.0) & (np.abs(zp) <= 0.6)
        margin = 2 * texel  # a texel at the receiver, seen through the plate's edge
        clear = (np.minimum(np.abs(xp + 1.0), np.abs(xp)) > margin) & (np.abs(np.abs(zp) - 0.6) > margin)
        lit = shadows.lookup(light, maps, pts, np.full(len(pts), s), uvt)
        assert np.array_equal(lit[clear], ~blocked[clear]), s


def test_shadow_penumbra_width_is_similar_triangles_and_banded():
    """Plane over plane: the penumbra on the receiver is 2R h_o / (h_l - h_o) wide (within two map texels), and
    an n x n light grid gives at most n + 1 visibility levels across a straight edge (banding)."""
    _, r = _shadow_run(light_resolution=512, light_grid=8)
    f = r.flat_stats
    texel = 2 * 2.0 * np.tan(np.radians(45)) / 512
    assert abs(f["shadow.penumbra_measured"] - f["shadow.penumbra_formula"]) < 2 * texel * 8 / 7 + 1e-3
    assert f["shadow.bands"] == 9


# ---- caustic volumes as moving triangles ([Nilsson 2012] §4) ------------------------------------------------------

def test_caustic_time_intervals_match_a_root_finder(rng):
    """Exact per-point time intervals (edge quadratics) against dense sampling of the inside test in t, with
    brentq refining each sign change of the inside indicator's edge functions."""
    from scipy.optimize import brentq

    from sim.uses.caustics import edge_quadratics, exact_time_intervals

    n = 400
    v0 = np.concatenate([rng.uniform(0, 32, (n, 3, 2)), rng.uniform(1, 4, (n, 3, 1))], -1)
    v1 = np.concatenate([rng.uniform(0, 32, (n, 3, 2)), rng.uniform(1, 4, (n, 3, 1))], -1)
    v0[..., :2] *= v0[..., 2:]  # pixel-homogeneous: X = x W
    v1[..., :2] *= v1[..., 2:]
    sx, sy = rng.uniform(4, 28, n), rng.uniform(4, 28, n)
    t_lo, t_hi, length = exact_time_intervals(v0, v1, sx, sy)
    ts = np.linspace(0, 1, 4001)
    Q = edge_quadratics(v0, v1, sx, sy)
    for i in range(n):
        e = Q[i, :, 0:1] * ts ** 2 + Q[i, :, 1:2] * ts + Q[i, :, 2:3]
        inside = np.all(e > 0, 0) | np.all(e < 0, 0)
        if not inside.any():
            assert np.isnan(t_lo[i]) or t_hi[i] - t_lo[i] < 2e-3
            continue
        first, last = ts[np.argmax(inside)], ts[len(ts) - 1 - np.argmax(inside[::-1])]
        # refine the dense estimate with a root finder on the edge that changes sign there
        def refine(t_guess, step):
            a, b = max(0.0, t_guess - step), min(1.0, t_guess + step)
            for k in range(3):
                f = lambda t: (Q[i, k, 0] * t * t + Q[i, k, 1] * t + Q[i, k, 2])  # noqa: E731
                if f(a) * f(b) < 0:
                    return brentq(f, a, b, xtol=1e-12)
            return t_guess
        lo_ref = 0.0 if first == 0 else refine(first, 2.5e-4)
        hi_ref = 1.0 if last == 1 else refine(last, 2.5e-4)
        assert t_lo[i] == pytest.approx(lo_ref, abs=1e-6), i
        assert t_hi[i] == pytest.approx(hi_ref, abs=1e-6), i
        assert length[i] == pytest.approx(inside.mean(), abs=2e-3)


def test_caustic_intervals_inside_the_conservative_bounds_and_zhat_holds_the_beam():
    sc = models.named("water_caustics", grid=10, width=48, height=48)
    cam = sim.Camera(**sc.camera_hint)
    r = uses.caustic_volumes(sc, cam, photons=20_000, path_samples=400)
    rec, lo, hi = r.arrays["records"], r.arrays["t_lo"], r.arrays["t_hi"]
    ok = np.isfinite(lo)
    assert ok.any()
    assert np.all(rec["t_lo"][ok] <= lo[ok] + 1e-6) and np.all(rec["t_hi"][ok] >= hi[ok] - 1e-6)
    assert r.flat_stats["caustics.zhat_misses"] == 0
    assert r.flat_stats["caustics.zhat_over_path"] >= 1.0
    assert r.flat_stats["caustics.volumes"] == 200
    assert r.arrays["fill_moving"].sum() == r.flat_stats["caustics.fill_moving"]
    assert r.arrays["fill_prism"].sum() == r.flat_stats["caustics.fill_prism"]
    fill = uses.caustic_volumes(sc, cam, photons=2000, path_samples=10, image="fill")
    assert fill.image.shape == (48, 96, 3)


def test_caustic_light_matches_a_photon_splat():
    sc = models.named("water_caustics", grid=24, amplitude=0.008, width=64, height=64)
    cam = sim.Camera(**sc.camera_hint)
    r = uses.caustic_volumes(sc, cam, photons=1_000_000, path_samples=10)
    assert r.flat_stats["caustics.folded"] == 0
    assert r.flat_stats["caustics.light_error"] < 0.06


def _one_beam(end_rotation_deg, shift=(0.0, 0.0)):
    a = np.radians(np.array([90.0, 210.0, 330.0]))
    top = np.stack([0.3 * np.cos(a), np.full(3, 1.0), 0.3 * np.sin(a)], 1)
    b = a + np.radians(end_rotation_deg)
    bottom = np.stack([0.3 * np.cos(b) + shift[0], np.zeros(3), 0.3 * np.sin(b) + shift[1]], 1)
    return models.Scene.from_arrays(top[None], positions_t1=bottom[None])


def test_caustic_twisted_beam_fills_less_than_its_hull_and_parallel_beam_equals_it():
    """Hard inputs: a generator that twists by 120 degrees on its way down (its sides are twisted bilinear
    patches) covers fewer pixels than the hull of its six vertices; a straight beam seen along its axis
    (parallel to the view) covers exactly the pixel centres of its nearer end."""
    top_cam = sim.Camera(width=64, height=64, fov_y_deg=40, eye=(0, 3, 0), target=(0, 0, 0), up=(0, 0, -1))
    side_cam = sim.Camera(width=64, height=64, fov_y_deg=40, eye=(0, 0.5, 3), target=(0, 0.5, 0))
    twisted = uses.caustic_volumes(_one_beam(60.0), side_cam, photons=1000, path_samples=10).flat_stats
    assert twisted["caustics.fill_moving"] < 0.97 * twisted["caustics.fill_prism"]
    straight = uses.caustic_volumes(_one_beam(0.0), top_cam, photons=1000, path_samples=10).flat_stats
    # brute force: pixel centres inside the projection of the top (nearer, larger) triangle
    e = top_cam.clip_to_engine(top_cam.world_to_clip(_one_beam(0.0).positions[0]))
    px, py = np.meshgrid(np.arange(64) + 0.5, np.arange(64) + 0.5)
    x, y = e[:, 0] / e[:, 2], e[:, 1] / e[:, 2]
    side = [(x[j] - x[i]) * (py - y[i]) - (y[j] - y[i]) * (px - x[i]) for i, j in ((0, 1), (1, 2), (2, 0))]
    inside = (np.all(np.array(side) > 0, 0) | np.all(np.array(side) < 0, 0)).sum()
    assert straight["caustics.fill_moving"] == straight["caustics.fill_prism"] == inside


# ---- planar glossy reflections ([Nilsson 2012] §6) -----------------------------------------------------------------

def test_glossy_map_with_a_pinhole_lens_is_a_mirror():
    """Roughness -> 0: the map look-up at each floor point equals the colour of the first triangle hit by the
    mirror-reflected eye ray (float64 brute force), except near the objects' silhouettes."""
    from sim.uses.common import pinhole_rays, ray_triangle
    from sim.uses.glossy import _bilinear, reflection_camera

    sc = models.named("glossy_floor", width=64, height=48)
    cam = sim.Camera(**sc.camera_hint)
    objs = ~np.all(np.abs(sc.positions[:, :, 1]) < 1e-9, axis=1)
    rcam = reflection_camera(cam, (-1.5, 1.5, -3.0, 0.0), 1e-6, 256)
    rmap = sim.render(models.Scene.from_arrays(sc.positions[objs], colors=sc.colors[objs]), rcam,
                      sim.SampleTable.stratified(spp=4, seed=1)).image.astype(np.float64)
    px, py = np.meshgrid(np.arange(64) + 0.5, np.arange(48) + 0.5)
    o, d = pinhole_rays(cam, px.ravel(), py.ravel())
    s = -o[:, 1] / d[:, 1]
    on = (s > 0)
    P = o[on] + s[on, None] * d[on]
    on_floor = (np.abs(P[:, 0]) < 1.4) & (P[:, 2] > -2.9) & (P[:, 2] < -0.1)
    P = P[on_floor]
    rd = d[on][on_floor] * np.array([1.0, -1.0, 1.0])
    best = np.full(len(P), np.inf)
    want = np.zeros((len(P), 3))
    for tri, c in zip(sc.positions[objs], sc.colors[objs]):
        hit, t, _ = ray_triangle(P, rd, tri)
        closer = hit & (t < best)
        best[closer] = t[closer]
        want[closer] = c.mean(axis=0)
    e = rcam.clip_to_engine(rcam.world_to_clip(P))
    got = _bilinear(rmap, e[:, 0] / e[:, 2], e[:, 1] / e[:, 2])
    bad = np.any(np.abs(got - want) > 0.05, axis=1)
    assert len(P) > 500 and bad.mean() < 0.05, bad.mean()


def test_glossy_error_falls_with_samples_per_texel():
    sc = models.named("glossy_floor", width=48, height=32)
    cam = sim.Camera(**sc.camera_hint)
    f = {spp: uses.glossy_reflection(sc, cam, sim.SampleTable.stratified(spp=spp, seed=1), map_texels=48,
                                     roughness=0.15, reference_spp=256).flat_stats for spp in (4, 64)}
    assert f[64]["glossy.map_rmse"] < 0.5 * f[4]["glossy.map_rmse"]
    assert f[64]["glossy.tests_per_texel"] > 8 * f[4]["glossy.tests_per_texel"]
    assert f[4]["glossy.texels"] == 48 * 48


def test_camera_shift_moves_the_principal_point():
    """Off-centre viewport (Camera.shift): the axis point lands shift * (W/2, -H/2) px from the centre; a
    shifted render covers the same area as an unshifted one (closed form: a fronto-parallel square)."""
    base = dict(width=64, height=32, fov_y_deg=40.0, focus_distance=3.0)
    cam = sim.Camera(shift=(0.25, -0.5), **base)
    e = cam.clip_to_engine(cam.world_to_clip(np.array([[0.0, 0.0, -2.0]])))[0]
    assert e[0] / e[2] == pytest.approx(32 + 0.25 * 32) and e[1] / e[2] == pytest.approx(16 + 0.5 * 16)
    quad = models.named("quad", size=0.5, depth=3.0)
    table = sim.SampleTable.stratified(spp=16, seed=1)
    a = sim.render(quad, cam, table).flat_stats["raster.samples_hit"]
    b = sim.render(quad, sim.Camera(**base), table).flat_stats["raster.samples_hit"]
    side_px = 0.5 / 3.0 / np.tan(np.radians(20.0)) * 16
    assert a == pytest.approx(b, rel=0.02) and a == pytest.approx(16 * side_px ** 2, rel=0.03)
    with pytest.raises(sim.ConfigError, match="shift"):
        sim.Camera(shift=(1.0,), **base)


# ---- the uses as point kinds (YAML) ----------------------------------------------------------------------

def test_use_point_kind_from_yaml(tmp_path):
    from experiments.config import validate
    from experiments.run import render_point

    cfg = validate({"scene": {"name": "transparent_layers", "params": {"width": 24, "height": 24}},
                    "samples": {"kind": "stratified", "spp": 4, "seed": 1},
                    "point": {"kind": "transparency", "options": {"reference": True}}})
    row, result = render_point(cfg, tmp_path / "t.png")
    assert (tmp_path / "t.png").exists()
    assert row["transparency.max_layers"] == 8 and row["point.options.reference"] is True
    assert result.stats["alpha"]["samples_tested"] > 0
    from experiments.config import ConfigError

    with pytest.raises(ConfigError, match="point.options: unknown option 'spp' for kind 'glossy'"):
        validate({"scene": {"name": "glossy_floor"}, "point": {"kind": "glossy", "options": {"spp": 4}}})
    with pytest.raises(ConfigError, match=r"point\.options: only for the use kinds .* and 'precision'"):
        validate({"scene": {"name": "glossy_floor"}, "point": {"kind": "render", "options": {"roughness": 0.1}}})
    docs = sim.counter_docs()
    for name, (unit, desc) in uses.FIGURES.items():
        assert docs[name] == (unit, desc)


def test_alpha_masks_same_image_for_every_algorithm_and_thread_count():
    """The alpha mask depends on the sample and the triangle only: every exact algorithm and any thread count
    give the same image (the engine's invariants, with transparency on)."""
    sc = models.named("transparent_layers", width=32, height=32)
    cam = sim.Camera(**sc.camera_hint)
    table = sim.SampleTable.stratified(spp=8, seed=9)
    ref = sim.render(sc, cam, table, sim.PipelineConfig(algorithm="bruteforce", threads=1))
    for algo in ("tile", "interval"):
        for threads in (1, 2):
            r = sim.render(sc, cam, table, sim.PipelineConfig(algorithm=algo, threads=threads, bin_size=16))
            assert np.array_equal(r.image, ref.image), (algo, threads)
            assert r.flat_stats["alpha.samples_discarded"] == ref.flat_stats["alpha.samples_discarded"]


def test_refraction_camera_sits_on_the_refracted_central_ray():
    """[Nilsson 2012] §6: the refraction map's camera is the primary camera moved along the plane normal onto the
    refracted central ray, so the points of that ray under the plane project onto the central ray's surface
    point (closed form: Snell's law at the plane y = 0)."""
    from sim.uses.glossy import reflection_camera

    cam = sim.Camera(width=64, height=48, fov_y_deg=45, eye=(0.3, 1.0, 1.8), target=(0.0, 0.25, -1.5))
    rc = reflection_camera(cam, (-1.5, 1.5, -3.0, 0.0), 0.1, 64, mode="refraction", ior=1.33)
    assert rc.eye[0] == cam.eye[0] and rc.eye[2] == cam.eye[2] and rc.eye[1] > cam.eye[1]
    d = (cam.target - cam.eye) / np.linalg.norm(cam.target - cam.eye)
    c = cam.eye + (-cam.eye[1] / d[1]) * d
    sin_t = np.hypot(d[0], d[2]) / 1.33  # Snell
    horiz = np.array([d[0], 0.0, d[2]]) / np.hypot(d[0], d[2])
    r = sin_t * horiz + np.array([0.0, -np.sqrt(1 - sin_t ** 2), 0.0])
    e = rc.clip_to_engine(rc.world_to_clip(np.array([c, c + 0.7 * r, c + 1.5 * r])))
    xy = e[:, :2] / e[:, 2:]
    assert np.allclose(xy, xy[0], atol=1e-6)
    with pytest.raises(sim.ConfigError, match="mode"):
        reflection_camera(cam, (-1.5, 1.5, -3.0, 0.0), 0.1, 64, mode="diffuse")
