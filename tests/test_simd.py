"""The explicit-SIMD batch sample tests (sampletest/simd_batch.h) are bit-identical to the scalar
batch kernels (sampletest/kernels.h): edge functions, determinant and decision flags, on
random triangles and samples, on exact ties (e_i == 0 on purpose), signed zeros, NaN and huge or
tiny magnitudes, for every batch length around the vector width (a batch's last n mod 16 samples with AVX-512,
n mod 8 with AVX2, are one masked vector; builds without either use the scalar kernels)."""
import numpy as np
import pytest

import sim

_core = sim._core


def _tri(rng, scale=1.0):
    t = rng.normal(size=28).astype(np.float32) * np.float32(scale)
    t[6:9] = np.abs(t[6:9]) + np.float32(0.1)  # W > 0 at t = 0 (any sign is legal; mostly positive)
    return t


def _samples(rng, n, scale=1.0):
    s = rng.normal(size=(n, 5)).astype(np.float32) * np.float32(scale)
    s[:, 4] = rng.random(n, dtype=np.float32)
    return s


def _same(cls, tri, smp, bfc=False):
    e, f = _core.simd_batch_compare(cls, tri, smp, bfc)
    assert np.array_equal(e[0].view(np.uint32), e[1].view(np.uint32)), (cls, tri.tolist())
    assert np.array_equal(f[0], f[1]), (cls, tri.tolist())
    return f[0]


@pytest.mark.parametrize("cls", [2, 3])
def test_random_batches_bit_identical(cls, rng):
    seen = set()
    for k in range(200):
        n = int(rng.integers(1, 70))
        tri, smp = _tri(rng, 10.0 ** rng.integers(-3, 4)), _samples(rng, n, 10.0 ** rng.integers(-2, 3))
        seen.update(np.unique(_same(cls, tri, smp, bfc=bool(k % 2))).tolist())
    assert {0, 1} <= seen  # both outcomes exercised


@pytest.mark.parametrize("cls", [2, 3])
def test_ties_zeros_and_specials(cls, rng):
    """Samples on a vertex and on the edges' lines (e_i exactly 0), signed zeros, NaN, inf, denormals."""
    tri = np.zeros(28, np.float32)
    tri[0:9] = [0, 4, 0, 0, 0, 4, 1, 1, 1]  # X, Y, W: a right triangle at the origin
    n = 64
    smp = np.zeros((n, 5), np.float32)
    smp[:, 0] = np.repeat(np.arange(8, dtype=np.float32) * 0.5, 8)
    smp[:, 1] = np.tile(np.arange(8, dtype=np.float32) * 0.5, 8)
    flags = _same(cls, tri, smp)
    assert (flags == 2).any()  # exact ties reach the top-left path in both
    special = np.array([0.0, -0.0, np.nan, np.inf, -np.inf, 1e-42, -1e-42, 3e38], np.float32)
    for col in range(5):
        s2 = _samples(rng, 40)
        s2[:, col] = rng.choice(special, size=40)
        _same(cls, _tri(rng), s2)
        t2 = _tri(rng)
        t2[rng.integers(0, 28, size=3)] = rng.choice(special, size=3)
        _same(cls, t2, _samples(rng, 40))


def test_isa_is_named():
    assert _core.simd_isa() in ("avx512", "avx2", "scalar")


@pytest.mark.parametrize("moving", [False, True])
def test_render_with_and_without_simd_is_identical(moving):
    """Whole renders (4D static and 5D moving, bruteforce and tile): image, per-sample results and
    every counter equal with the explicit-SIMD sample tests on and off."""
    import models

    scene = models.named("moving_quads" if moving else "bunny")
    hint = scene.camera_hint
    cam = sim.Camera(width=64, height=64, fov_y_deg=hint.get("fov_y_deg", 45.0),
                     focus_distance=hint["focus_distance"], coc_px=12.0)
    table = sim.SampleTable.stratified(spp=32, seed=5)
    for algo in ("bruteforce", "tile"):
        a, b = (sim.render(scene, cam, table, sim.PipelineConfig(algorithm=algo, threads=1, simd=flag),
                           export_samples=True, timing=False) for flag in (True, False))
        assert np.array_equal(a.image.view(np.uint32), b.image.view(np.uint32)), algo
        assert np.array_equal(a.sample_depth.view(np.uint32), b.sample_depth.view(np.uint32)), algo
        assert np.array_equal(a.sample_triangle, b.sample_triangle), algo
        cls = "5d" if moving else "4d"
        assert a.flat_stats[f"raster.samples_tested_{cls}"] > 0
        for k, v in a.flat_stats.items():
            if k != "time.wall_s":
                assert v == b.flat_stats[k] or (v != v and b.flat_stats[k] != b.flat_stats[k]), (algo, k)


@pytest.mark.parametrize("algo", ["tile", "interval", "tile_interleaved"])
@pytest.mark.parametrize("case", ["static", "moving", "square_lens", "hexagon_lens", "grid4"])
def test_fused_selection_paths_match_the_portable_paths(algo, case):
    """The fast paths that select and push a pixel's samples in one SIMD pass (tile's per-tile lens
    region, interval's cells walked once over the passes' pixel rectangles) test exactly the
    samples of the portable paths (pipeline.simd false): image, per-sample results and every
    counter equal, at 64 spp (four groups of 16 lanes) and at 48 spp (a partial 64-sample word)."""
    import models

    scene = models.named("moving_quads" if case == "moving" else "bunny")
    hint = scene.camera_hint
    lens = case.split("_")[0] if case.endswith("_lens") else "disk"
    cam = sim.Camera(width=48, height=48, fov_y_deg=hint.get("fov_y_deg", 45.0),
                     focus_distance=hint["focus_distance"], coc_px=20.0, lens=lens)
    if algo == "tile_interleaved":
        if case == "moving":
            pytest.skip("interleaved tables are static-lens tables")
        table = sim.SampleTable.interleaved(spp=64, n_lens=64, seed=3)
    else:
        table = sim.SampleTable.stratified(spp=48 if case == "grid4" else 64, seed=3)
    extra = {"lens_grid": 4} if case == "grid4" else {}
    a, b = (sim.render(scene, cam, table, sim.PipelineConfig(algorithm=algo, threads=1, simd=flag, **extra),
                       export_samples=True, timing=False) for flag in (True, False))
    assert np.array_equal(a.image.view(np.uint32), b.image.view(np.uint32))
    assert np.array_equal(a.sample_depth.view(np.uint32), b.sample_depth.view(np.uint32))
    assert np.array_equal(a.sample_triangle, b.sample_triangle)
    assert a.flat_stats["raster.samples_hit"] > 0
    for k, v in a.flat_stats.items():
        if k != "time.wall_s":
            assert v == b.flat_stats[k] or (v != v and b.flat_stats[k] != b.flat_stats[k]), k


def test_interval_fast_walk_matches_ordered_passes():
    """interval with shading none (the one-walk fast path) and with MSAA shading (the ordered passes,
    since shading visits observe the order) render the same image and count the same samples."""
    import models

    scene = models.named("bunny")
    hint = scene.camera_hint
    cam = sim.Camera(width=48, height=48, fov_y_deg=hint.get("fov_y_deg", 45.0),
                     focus_distance=hint["focus_distance"], coc_px=25.0)
    table = sim.SampleTable.stratified(spp=64, seed=4)
    a, b = (sim.render(scene, cam, table, sim.PipelineConfig(algorithm="interval", threads=1, shading=mode),
                       export_samples=True, timing=False) for mode in ("none", "msaa"))
    assert np.array_equal(a.image.view(np.uint32), b.image.view(np.uint32))
    assert np.array_equal(a.sample_triangle, b.sample_triangle)
    for k in ("raster.samples_tested", "raster.samples_hit", "ops.sample_inside", "ops.setup", "trav.passes"):
        assert a.flat_stats[k] == b.flat_stats[k], k
