"""Sampled simulation (sim/sampling.py, sampled/bin_sample.h, PipelineConfig.sample_fraction): the
engine renders exactly the chosen bins and reports their own counters; the draw is stratified by
brute-force work; the stratified estimator's 95% intervals cover the whole-frame value at the stated
rate over many seeds; figures that need the whole frame are NaN; bad fractions are errors naming
the field."""
import math

import numpy as np
import pytest

import models
import sim
from sim import sampling

W = H = 192
BIN = 16  # 144 bins


@pytest.fixture(scope="module")
def setup():
    scene = models.named("bunny")
    hint = scene.camera_hint
    camera = sim.Camera(width=W, height=H, fov_y_deg=hint.get("fov_y_deg", 45.0),
                        focus_distance=hint["focus_distance"], coc_px=10.0)
    table = sim.SampleTable.stratified(spp=16, seed=3)
    return scene, camera, table


def config(**kw):
    return sim.PipelineConfig(algorithm="tile", bin_size=BIN, threads=2, **kw)


@pytest.fixture(scope="module")
def full(setup):
    """The whole frame, and every bin's own counters from the engine (bins = all, in order)."""
    scene, camera, table = setup
    res = sim.render(scene, camera, table, config(), timing=False)
    return res, (W // BIN) * (H // BIN)


def _engine_bins(setup, bins):
    """The engine's output of the frame rendered with an explicit bin list (sim.render's _bins), with
    the image."""
    scene, camera, table = setup
    r = sim.render(scene, camera, table, config(), timing=False, _bins=np.asarray(bins))
    return {**r.config["bins"], "image": r.image}


def test_bin_counters_sum_to_the_frame(setup, full):
    """All bins listed: the rows plus the setup equal the render without a bin list; a subset's rows
    equal the same bins' rows of the full list (a bin's counters do not depend on the others)."""
    res, n_bins = full
    allb = _engine_bins(setup, np.arange(n_bins))
    names = list(allb["counters"])
    rows = allb["bin_counters"]
    assert rows.shape == (n_bins, len(names))
    for i, n in enumerate(names):
        assert allb["counters"][n] == res.flat_stats[n], n
    assert rows[:, names.index("raster.samples_tested")].sum() == res.flat_stats["raster.samples_tested"]
    # Setup is counted in each triangle's home bin (no triangle is culled before binning here); only
    # the submitted triangles are a frame count.
    assert rows[:, names.index("ops.setup")].sum() == res.flat_stats["ops.setup"] > 0
    assert rows[:, names.index("setup.triangles")].sum() == 0
    pick = np.array([140, 3, 77, 78, 20], np.int32)
    sub = _engine_bins(setup, pick)
    assert np.array_equal(sub["bin_counters"], rows[pick])
    img = sub["image"]
    assert img[:BIN, :BIN].sum() == 0  # bin 0 was not rendered


def test_engine_rejects_bad_bin_lists(setup):
    with pytest.raises(ValueError, match="bins"):
        _engine_bins(setup, [1, 1])
    with pytest.raises(ValueError, match="bins"):
        _engine_bins(setup, [10_000])


def test_t_quantile_against_scipy():
    from scipy import stats

    for df in (1, 2, 3, 4, 5, 8, 12, 30, 100, 1000):
        assert sampling.t_quantile_975(df) == pytest.approx(stats.t.ppf(0.975, df), rel=2e-3), df


def test_draw_is_stratified_by_work(setup, full):
    """2 distinct bins per stratum, strata are runs of the bins with work sorted by work, and only
    bins with work are drawn; the same seed gives the same draw."""
    res, n_bins = full
    work = np.asarray(_engine_bins(setup, np.arange(n_bins))["bin_work"])
    K = int((work > 0).sum())
    s = sampling.choose_bins(work, 0.2, 11)
    assert len(s.bins) <= 2 * (round(0.2 * K) // 2) and s.sizes.sum() == K
    assert (work[s.bins] > 0).all() and len(set(s.bins.tolist())) == len(s.bins)
    order = sorted(np.flatnonzero(work > 0).tolist(), key=lambda b: work[b])  # stable, as the engine
    edges = np.concatenate([[0], np.cumsum(s.sizes)])
    drawn = np.bincount(s.stratum, minlength=len(s.sizes))
    for h in range(len(s.sizes)):
        members = set(order[edges[h]:edges[h + 1]])
        assert set(s.bins[s.stratum == h].tolist()) <= members
        # 2 drawn per stratum, or the take-all stratum (the heaviest bins, all traversed) last
        assert drawn[h] == 2 or (h == len(s.sizes) - 1 and drawn[h] == s.sizes[h])
    assert np.array_equal(sampling.choose_bins(work, 0.2, 11).bins, s.bins)
    assert not np.array_equal(sampling.choose_bins(work, 0.2, 12).bins, s.bins)


def test_intervals_cover_the_frame_value_at_the_stated_rate(setup, full):
    """Over 400 seeds at fractions 0.2 and 0.3 (6 and 9 strata here), the 95% interval of
    raster.samples_tested, ops.total and raster.samples_hit covers the whole-frame value in >= 88% of
    the draws (measured 0.92-0.95: 2 bins per stratum and few strata cover a little below nominal;
    a wrong variance, e.g. half of it, covers about 0.83), and the estimator is unbiased (mean error
    within 4 standard errors)."""
    res, n_bins = full
    allb = _engine_bins(setup, np.arange(n_bins))
    names = list(allb["counters"])
    rows = allb["bin_counters"]
    work = allb["bin_work"]
    aux = allb["bin_aux"]
    from sim.stats import DERIVED

    for fraction in (0.2, 0.3):
        hits = {k: 0 for k in ("raster.samples_tested", "raster.samples_hit", "ops.total")}
        errs = {k: [] for k in hits}
        for seed in range(400):
            s = sampling.choose_bins(work, fraction, seed, aux)
            flat, ci = sampling.estimate(s, _counters_with_setup(allb["counters"], rows, s, names), rows[s.bins],
                                         DERIVED, names)
            for figure in hits:
                truth = res.flat_stats[figure]
                hits[figure] += abs(flat[figure] - truth) <= ci[figure]
                errs[figure].append(flat[figure] - truth)
        for figure in hits:
            rate = hits[figure] / 400
            assert rate >= 0.88, (fraction, figure, rate)
            e = np.asarray(errs[figure])
            assert abs(e.mean()) <= 4 * e.std() / math.sqrt(len(e)), (fraction, figure, e.mean())


def _counters_with_setup(total, rows, s, names):
    """The engine's totals for a render of s.bins only: setup (total minus every bin) plus those bins."""
    bins_sum = rows[s.bins].sum(axis=0)
    all_sum = rows.sum(axis=0)
    return {n: int(total[n]) - int(all_sum[i]) + int(bins_sum[i]) for i, n in enumerate(names)}


def test_sampled_render_matches_the_estimator_on_the_same_bins(setup, full):
    """sim.render with sample_fraction: estimates equal the estimator on the engine's rows for the
    chosen bins; whole-frame figures are NaN; the interval contains the frame value here."""
    scene, camera, table = setup
    res, n_bins = full
    r = sim.render(scene, camera, table, config(sample_fraction=0.25, sample_seed=5))
    assert r.ci95 is not None and r.timing_records is None
    K = r.flat_stats["sample.candidates"]
    assert 0 < K <= n_bins and 4 <= r.flat_stats["sample.bins"] <= 2 * (round(0.25 * K) // 2)
    for k in ("tex.cache.hits", "timing.cycles"):
        assert math.isnan(r.flat_stats[k]) and math.isnan(r.ci95[k])
    for k in ("raster.samples_tested", "ops.total", "raster.ste"):
        assert abs(r.flat_stats[k] - res.flat_stats[k]) <= 2 * r.ci95[k], k
    assert r.flat_stats["frame.pixels"] == W * H and r.ci95["frame.pixels"] == 0


@pytest.mark.parametrize("fraction", [0, -0.5, 1.5, float("nan"), "half", True])
def test_bad_fraction(fraction):
    with pytest.raises(sim.ConfigError, match="sample_fraction"):
        sim.PipelineConfig(sample_fraction=fraction)


def test_too_few_bins_is_an_error(setup):
    scene, camera, table = setup
    with pytest.raises(sim.ConfigError, match=r"PipelineConfig.sample_fraction: 0.02.* screen bins that hold triangles"):
        sim.render(scene, camera, table, config(sample_fraction=0.02))


def test_few_strata_warn(setup):
    """Below sampling.FEW_STRATA sampled strata the render warns (naming sample_fraction and what to
    raise); with enough strata it does not."""
    scene, camera, table = setup
    with pytest.warns(sim.errors.FewStrataWarning, match=r"sample_fraction: drawing \d+ of \d+ bins gives \d+ sampled strata"):
        sim.render(scene, camera, table, config(sample_fraction=0.25, sample_seed=5), timing=False)
    import warnings

    small = sim.PipelineConfig(algorithm="tile", bin_size=8, threads=2, sample_fraction=0.5, sample_seed=5)
    with warnings.catch_warnings():
        warnings.simplefilter("error", sim.errors.FewStrataWarning)
        r = sim.render(scene, camera, table, small, timing=False)
    assert r.flat_stats["sample.strata"] >= sampling.FEW_STRATA


def test_whole_frame_fraction_is_exact(setup, full):
    scene, camera, table = setup
    res, _ = full
    r = sim.render(scene, camera, table, config(sample_fraction=1.0), timing=False)
    assert r.ci95 is None and r.flat_stats["raster.samples_tested"] == res.flat_stats["raster.samples_tested"]
    s = sampling.choose_bins([0, 5, 1, 0, 2, 9], 0.99, 1)  # 4 bins with work: all of them, exact
    assert s.exact and s.bins.tolist() == [1, 2, 4, 5]


@pytest.mark.bench
def test_bench_sampling(tmp_path):
    """experiments/bench/bench_sampling.py (make bench): speed against error of sampled simulation,
    the coverage of its intervals over many draws, and the timing granularity's error against its cost
    and units smaller than a bin on the dense scene (reports/bench/bench_sampling.md). Checks what does
    not depend on timing: the sections, that every fraction's estimate has an interval, and the
    granularity rows' record counts."""
    import os

    from experiments.bench import bench_sampling

    quick = os.environ.get("RAST5D_BENCH_QUICK", "") not in ("", "0")
    out = tmp_path if quick else bench_sampling.REPO / "reports" / "bench"
    got = bench_sampling.run(quick=quick, out=out)
    page = got["page"].read_text()
    for section in ("## Sampled simulation", "## Coverage of the 95% intervals", "## Summary",
                    "## Units smaller than a bin", "## Timing-model granularity"):
        assert section in page
    assert all(r["ci ops.total"] > 0 and 0.0 <= r["cov ops.total"] <= 1.0 for r in got["split"])
    assert all(r["ci ops.total"] > 0 for r in got["sampling"] if r["fraction"] < 1)
    assert all(0.0 <= r["cov ops.total"] <= 1.0 for r in got["coverage"])
    assert all(r["records_visit"] >= r["records_bin"] for r in got["granularity"])


def _hard_scene(moving: bool):
    """Random triangles that take every setup path: wholly behind the near plane, crossing it, off
    screen, collinear (degenerate), back-facing, large and small; moving ones with positions_t1."""
    rng = np.random.default_rng(7)
    n = 400
    centre = np.column_stack([rng.uniform(-6, 6, n), rng.uniform(-6, 6, n), rng.uniform(-12, 1.0, n)])
    size = rng.choice([0.05, 0.4, 3.0], n)
    pos = centre[:, None, :] + size[:, None, None] * rng.normal(size=(n, 3, 3))
    pos[::17, 2] = pos[::17, 0] + 0.5 * (pos[::17, 1] - pos[::17, 0])  # collinear
    pos[::23, :, 2] = 0.5  # wholly behind the camera
    t1 = pos + rng.normal(scale=0.3, size=pos.shape) * (rng.uniform(size=n) < 0.4)[:, None, None] if moving else None
    return models.Scene.from_arrays(pos, colors=rng.uniform(size=(n, 3)), positions_t1=t1, name="hard")


@pytest.mark.parametrize("moving, op_count, backface", [(False, "documented", True), (True, "documented", False),
                                                        (True, "exact", True)])
def test_every_bin_listed_equals_the_whole_frame_on_every_setup_path(moving, op_count, backface):
    """Setup restricted to the drawn bins after a bounds pre-pass (sampled/sampled_setup.h): with every
    bin listed, the counters and the image equal the whole frame's, on triangles culled behind the near
    plane, off screen, degenerate and back-facing, near-clipped, moving and crossing the near plane
    while moving; a sampled render's setup rows are its home bins' share (setup.triangles exact)."""
    scene = _hard_scene(moving)
    camera = sim.Camera(width=96, height=80, fov_y_deg=60.0, focus_distance=4.0, coc_px=6.0)
    table = sim.SampleTable.stratified(spp=8, seed=2)
    cfg = sim.PipelineConfig(algorithm="tile", bin_size=16, threads=2, op_count=op_count, backface_cull=backface)
    full = sim.render(scene, camera, table, cfg, timing=False)
    for key in ("setup.culled_near", "setup.culled_offscreen", "setup.culled_degenerate", "setup.near_clipped"):
        assert full.flat_stats[key] > 0, key
    if moving:
        assert full.flat_stats["setup.bbox_fallback"] > 0 and full.flat_stats["setup.class_5d"] > 0
    if backface:
        assert full.flat_stats["setup.culled_backface"] > 0
    listed = sim.render(scene, camera, table, cfg, timing=False, _bins=np.arange(6 * 5))
    for name, value in full.flat_stats.items():
        if not name.startswith(("time.", "timing.", "energy.")):
            assert listed.flat_stats[name] == value or (math.isnan(value) and math.isnan(listed.flat_stats[name])), name
    assert np.array_equal(listed.image, full.image)
    out = listed.config["bins"]
    names = list(out["counters"])
    rows = np.asarray(out["bin_counters"])
    # The frame part (total minus the rows): every submitted triangle and every cull (exact under
    # sampling); the live triangles' classes are in their home bins' rows.
    frame = {n: int(out["counters"][n]) - int(rows[:, i].sum()) for i, n in enumerate(names)}
    assert frame["setup.triangles"] == len(scene.positions)
    for key in ("near", "offscreen", "degenerate", "backface"):
        assert frame[f"setup.culled_{key}"] == full.flat_stats[f"setup.culled_{key}"], key
    assert frame["setup.class_4d"] == frame["setup.class_5d"] == 0


def test_table_index_renders_what_the_samples_array_renders():
    """sim.SampleTable.engine_index (the (lens cell, time stratum) index built once, sim._core.SampleTableIndex):
    the engine renders the same image and counters from it as from the samples array, on a moving scene
    and an interleaved table (its own lens_index); sim.render reuses one index per (lens, grid, strata);
    a mismatched index is refused naming the field."""
    from sim import _core, params as P
    from sim.render import _camera_params

    scene = _hard_scene(True)
    camera = sim.Camera(width=96, height=80, fov_y_deg=60.0, focus_distance=4.0, coc_px=6.0)
    p1 = np.asarray(scene.positions_t1, np.float64)
    v0, v1 = camera.engine_vertices(np.asarray(scene.positions, np.float64), p1)
    col = np.full(v0.shape, 0.5, np.float32)
    for table, algorithm in ((sim.SampleTable.stratified(spp=8, seed=2), "tile"),
                             (sim.SampleTable.create("interleaved", spp=16, seed=1), "interleave")):
        cfg = sim.PipelineConfig(algorithm=algorithm, bin_size=16, threads=2)
        p = _camera_params(camera)
        P.set_layer(p, "pipeline", cfg)
        samples = table.samples(camera.lens)
        p.lens_grid = cfg.resolved_lens_grid(samples.shape[2])
        p.table_has_lens = p.table_has_time = True
        p.record_timing = False
        if table.n_lens:
            li = np.ascontiguousarray(table.lens_index, np.int32)
            luv = np.ascontiguousarray(table.lens_positions(camera.lens), np.float32)
        else:
            li, luv = np.zeros(0, np.int32), np.zeros((0, 2), np.float32)
        a = _core.render(p, v0, v1, col, samples, li, luv)
        index = table.engine_index(camera.lens, p.lens_grid, p.time_strata)
        assert index is table.engine_index(camera.lens, p.lens_grid, p.time_strata)  # built once
        assert (index.grid, index.time_strata, index.spp, index.n_lens) == (p.lens_grid, p.time_strata,
                                                                            samples.shape[2], table.n_lens)
        b = _core.render(p, v0, v1, col, index, np.zeros(0, np.int32), np.zeros((0, 2), np.float32))
        assert a["counters"] == b["counters"] and a["counters"]["raster.samples_tested"] > 0
        assert np.array_equal(a["image"], b["image"])
        import copy
        import pickle

        for twin in (pickle.loads(pickle.dumps(table)), copy.deepcopy(table)):  # the index is rebuilt, not copied
            c = _core.render(p, v0, v1, col, twin.engine_index(camera.lens, p.lens_grid, p.time_strata),
                             np.zeros(0, np.int32), np.zeros((0, 2), np.float32))
            assert c["counters"] == a["counters"] and np.array_equal(c["image"], a["image"])
        with pytest.raises(ValueError, match="samples: the SampleTableIndex has lens_grid"):
            _core.render(p, v0, v1, col, table.engine_index(camera.lens, p.lens_grid, 2 * p.time_strata),
                         np.zeros(0, np.int32), np.zeros((0, 2), np.float32))
        with pytest.raises(ValueError, match="lens_index"):
            _core.render(p, v0, v1, col, index, np.zeros(1, np.int32), np.zeros((0, 2), np.float32))


def test_an_auxiliary_with_zero_total_leaves_the_fit_and_the_degrees_of_freedom():
    """sim.sampling.Estimator: an auxiliary no bin has (frame total 0) is not a coefficient of the fit,
    and the interval's degrees of freedom count only the coefficients used: the half-width is
    t_{0.975, H - (p - 1)} times the square root of the variance, p the coefficients used."""
    rng = np.random.default_rng(5)
    K = 200
    work = rng.integers(50, 500, K)
    cover = work * rng.uniform(0.4, 0.6, K)
    aux = np.column_stack([cover, np.zeros(K)])  # no bin has the second auxiliary
    s = sampling.choose_bins(work, 0.1, 3, aux)
    fit = sampling.Estimator(s)
    assert fit.coefficients == 2 and fit.extra_coefficients == 1
    y = (3 * work + cover + rng.normal(0, 20, K))[s.bins]
    names = ["raster.samples_tested"]
    flat, ci = sampling.estimate(s, {names[0]: int(y.sum())}, y[:, None].astype(np.uint64), [], names)
    _, var = fit.total(y[:, None].astype(np.uint64).astype(np.float64))
    H = sampling.sampled_strata(s)
    assert ci[names[0]] == pytest.approx(sampling.t_quantile_975(H - 1) * math.sqrt(var[0]), rel=1e-12)
    full = sampling.Estimator(sampling.choose_bins(work, 0.1, 3, np.column_stack([cover, cover])))
    assert full.coefficients == 3 and full.extra_coefficients == 2


@pytest.mark.parametrize("moving", [False, True])
def test_auxiliary_totals_are_the_sums_over_every_bin(moving):
    """The pre-pass sums each triangle's auxiliaries over the union of its bins (sampled/sampled_setup.h);
    the drawn bins' values are computed per bin (shares of the bounds, areas clipped to the bin). With
    every bin listed, the per-bin values (coverage, footprint, edge) add up to the pre-pass's totals,
    on triangles larger than a bin, moving, near-clipped and culled."""
    scene = _hard_scene(moving)
    camera = sim.Camera(width=96, height=80, fov_y_deg=60.0, focus_distance=4.0, coc_px=6.0)
    table = sim.SampleTable.stratified(spp=8, seed=2)
    cfg = sim.PipelineConfig(algorithm="tile", bin_size=16, threads=2)
    out = sim.render(scene, camera, table, cfg, timing=False, _bins=np.arange(6 * 5)).config["bins"]
    aux, total = np.asarray(out["bin_aux"]), np.asarray(out["bin_aux_total"])
    assert aux.shape == (30, 3) and total.shape == (3,) and np.all(total > 0)
    assert np.allclose(aux.sum(axis=0), total, rtol=1e-9, atol=0), (aux.sum(axis=0), total)


# ---- units smaller than a bin for the dense bins (PipelineConfig.sample_split, sampled/dense_units.h) ----

SPLIT_FIGURES = ("raster.samples_tested", "ops.total", "raster.samples_hit")


def test_split_estimates_are_unbiased_and_cover(setup, full):
    """Units of the dense bins' triangles: over 200 engine draws (seeds 0..199) at fraction 0.3 with
    sample_split 0.25 (dense bins cut into units), the mean estimate of each figure lies within 4
    standard errors of the whole frame's exact value (a normal bound on the mean of 200 independent
    draws; likewise every other counter estimated under units that the frame counts), and the 95% intervals cover it in 0.88-0.995 of the draws (binomial: 3 standard deviations
    around 0.95 at n = 200 reach 0.90; the draw's few strata cover a little below nominal). With each
    drawn unit's counters cut by a tenth before the estimate (a unit traversal that loses work) the
    mean of samples_tested lies far outside the bound."""
    res, _ = full
    scene, camera, table = setup
    n, frac = 200, 0.3
    counted = [k for k in sim.counter_docs() if k.startswith(sampling.VISIT_SUMS) and res.flat_stats.get(k, 0) > 0]
    est = {k: [] for k in (*SPLIT_FIGURES, *counted)}
    hits = {k: 0 for k in SPLIT_FIGURES}
    cut = 0
    for seed in range(n):
        r = sim.render(scene, camera, table, config(sample_fraction=frac, sample_seed=seed, sample_split=0.25),
                       timing=False)
        cut += r.flat_stats["sample.candidates"] > int((np.asarray(_bin_work(setup)) > 0).sum())
        for k in est:
            est[k].append(r.flat_stats[k])
        for k in SPLIT_FIGURES:
            hits[k] += abs(r.flat_stats[k] - res.flat_stats[k]) <= r.ci95[k]
    assert cut == n  # every draw cut some dense bin into units
    for k in SPLIT_FIGURES:
        assert 0.88 <= hits[k] / n <= 0.995, (k, hits[k] / n)
    # Every counter estimated under units (sampling.VISIT_SUMS) that the frame counts: its mean too.
    for k in est:
        e = np.asarray(est[k]) - res.flat_stats[k]
        assert abs(e.mean()) <= 4 * e.std() / math.sqrt(n) + 1e-9 * res.flat_stats[k], (k, e.mean(), e.std())


def _bin_work(setup):
    scene, camera, table = setup
    r = sim.render(scene, camera, table, config(), timing=False, _bins=np.asarray([0]))
    return r.config["bins"]["bin_work"]


def test_split_marks_depth_order_counters_absent(setup, full):
    """Under units, counters that depend on the triangles drawn before in the bin are NaN (absent), the
    visit sums are estimated; the result is the same for 1 and 2 threads, bit for bit."""
    scene, camera, table = setup
    cfg = config(sample_fraction=0.3, sample_seed=4, sample_split=0.25)
    one = sim.render(scene, camera, table, cfg.replace(threads=1), timing=False)
    two = sim.render(scene, camera, table, cfg, timing=False)
    for k in ("depth.passes", "depth.bytes_written", "ops.interp"):
        assert math.isnan(two.flat_stats[k]) and math.isnan(two.ci95[k]), k
    for k in SPLIT_FIGURES + ("depth.tests", "tile.visited", "ops.per_pixel", "frame.pixels"):
        assert math.isfinite(two.flat_stats[k]), k
    assert {k: v for k, v in one.flat_stats.items() if k != "time.wall_s"}.keys() == \
        {k: v for k, v in two.flat_stats.items() if k != "time.wall_s"}.keys()
    for k, v in one.flat_stats.items():
        if k != "time.wall_s":
            assert v == two.flat_stats[k] or (math.isnan(v) and math.isnan(two.flat_stats[k])), k
    assert np.array_equal(one.image, two.image)


def test_split_at_fraction_one_is_the_whole_frame(setup, full):
    """sample_fraction 1 draws every bin: sample_split cuts nothing and the figures are the whole frame's."""
    res, _ = full
    scene, camera, table = setup
    with pytest.warns(sim.UnreadParameterWarning):
        cfg = config(sample_split=0.5)
    r = sim.render(scene, camera, table, cfg, timing=False)
    for k, v in res.flat_stats.items():
        if k != "time.wall_s" and not (isinstance(v, float) and math.isnan(v)):
            assert r.flat_stats[k] == v, k


@pytest.mark.parametrize("kw, field", [({"hiz": {"enabled": True}}, "hiz.enabled"), ({"shading": "msaa"}, "shading"),
                                       ({"algorithm": "lines"}, "line samples")])
def test_split_refuses_depth_reading_configurations(setup, kw, field):
    """Units would change what a counter counts where the traversal reads depth: a ConfigError naming
    the field and the value (sim.render for the point algorithms, the check itself for line samples)."""
    scene, camera, table = setup
    cfg = sim.PipelineConfig(**{"algorithm": "tile", "bin_size": BIN, "threads": 2, "sample_fraction": 0.3,
                                "sample_split": 0.5, **kw})
    with pytest.raises(sim.ConfigError, match=r"PipelineConfig\.sample_split: 0\.5 .*" + field):
        if kw.get("algorithm") == "lines":
            sampling.check_split(cfg)
        else:
            sim.render(scene, camera, table, cfg, timing=False)
