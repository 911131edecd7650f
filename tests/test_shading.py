"""Shading, texturing and the texture cache (docs/shading.md): quad counting on
hand-made cases against numpy references built from the exported per-sample coverage, the cache
model against a tiny Python reference simulator, the mip level against the closed form for a
textured plane, texel layouts, and the same-image invariant with texturing on."""
from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np
import pytest

import models
import sim
from sim import _core

pytestmark = pytest.mark.invariants


# ---- a tiny reference cache simulator ------------------------------------------------------------

def reference_cache(lines, n_lines, ways):
    """Set-associative LRU with the 3C split, written independently of the engine."""
    ways = n_lines if ways == 0 else ways
    n_sets = n_lines // ways
    sets = [OrderedDict() for _ in range(n_sets)]
    shadow = OrderedDict()  # fully associative LRU of n_lines
    seen = set()
    out = dict(accesses=0, hits=0, misses=0, cold=0, capacity=0, conflict=0)
    hits = []
    for a in lines:
        a = int(a)
        out["accesses"] += 1
        sh_hit = a in shadow
        if sh_hit:
            shadow.move_to_end(a)
        else:
            shadow[a] = True
            if len(shadow) > n_lines:
                shadow.popitem(last=False)
        s = sets[a % n_sets]
        hit = a in s
        if hit:
            s.move_to_end(a)
        else:
            s[a] = True
            if len(s) > ways:
                s.popitem(last=False)
        hits.append(hit)
        if hit:
            out["hits"] += 1
        else:
            out["misses"] += 1
            if a not in seen:
                out["cold"] += 1
            elif not sh_hit:
                out["capacity"] += 1
            else:
                out["conflict"] += 1
        seen.add(a)
    return out, np.array(hits)


@pytest.mark.parametrize("n_lines,ways", [(16, 1), (16, 2), (16, 4), (16, 0), (64, 8), (8, 8)])
@pytest.mark.parametrize("draw", [1, 2])  # two address streams per cache shape, each from its own rng
def test_cache_model_matches_reference(n_lines, ways, draw, rng):
    # A mix of locality: a random walk over a working set larger than the cache, plus jumps.
    walk = np.cumsum(rng.integers(-3, 4, size=3000)) % 200
    jumps = rng.integers(0, 1000, size=3000)
    stream = np.where(rng.random(3000) < 0.8, walk, jumps).astype(np.uint64)
    got = _core.simulate_cache(stream, n_lines, ways)
    want, want_hits = reference_cache(stream, n_lines, ways)
    for k, v in want.items():
        assert got[k] == v, k
    np.testing.assert_array_equal(got["hit"], want_hits)
    assert got["cold"] + got["capacity"] + got["conflict"] == got["misses"]
    if ways == 0 or ways == n_lines:
        assert got["conflict"] == 0  # a fully associative cache has no conflict misses


def test_cache_model_rejects_bad_geometry():
    with pytest.raises(ValueError, match="ways"):
        _core.simulate_cache(np.zeros(3, np.uint64), 16, 3)


# ---- texel layouts ---------------------------------------------------------------------------------

def _morton(x, y):
    r = 0
    for b in range(16):
        r |= ((x >> b) & 1) << (2 * b) | ((y >> b) & 1) << (2 * b + 1)
    return r


@pytest.mark.parametrize("h,w", [(16, 16), (12, 20)])
def test_texel_addresses(h, w):
    for y in range(h):
        for x in range(w):
            assert _core.texel_address(h, w, "linear", 0, x, y) == (y * w + x) * 4
            bw = -(-w // 4)
            blocked = ((y // 4) * bw + x // 4) * 64 + ((y % 4) * 4 + x % 4) * 4
            assert _core.texel_address(h, w, "blocked", 0, x, y) == blocked
            morton = _morton(x // 4, y // 4) * 64 + ((y % 4) * 4 + x % 4) * 4
            assert _core.texel_address(h, w, "morton", 0, x, y) == morton
    # Level 1 lives after level 0 (4 KiB aligned), without overlap.
    assert _core.texel_address(h, w, "linear", 1, 0, 0) >= h * w * 4


# ---- mip level vs the closed form for a textured plane -------------------------------------------

@pytest.mark.parametrize("depth", [2.0, 5.0, 17.0])
@pytest.mark.parametrize("tex", [256, 1024])
def test_lod_closed_form_fronto_parallel_plane(depth, tex):
    cam = sim.Camera(width=200, height=200, fov_y_deg=50.0, focus_distance=5.0)
    side = 1.5
    s = side / 2
    quad = np.array([[[-s, -s, -depth], [s, -s, -depth], [s, s, -depth]],
                     [[-s, -s, -depth], [s, s, -depth], [-s, s, -depth]]], float)
    uvs = np.array([[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1], [0, 1]]], np.float32)
    v0, _ = cam.engine_vertices(quad, quad)
    lod, jac = _core.triangle_lod(np.asarray(v0, np.float32), uvs, tex, tex, 0.01)
    # Closed form: the plane spans side * s_y * H / (2 depth) pixels and tex texels.
    s_y = 1.0 / math.tan(math.radians(50.0) / 2)
    pixels = side * s_y * 200 / (2 * depth)
    want = math.log2(tex / pixels)
    np.testing.assert_allclose(lod, want, atol=1e-4)
    np.testing.assert_allclose(np.abs(jac[:, 0]), 1 / pixels, rtol=1e-4)  # du/dx
    np.testing.assert_allclose(jac[:, 1], 0, atol=1e-7)  # du/dy


# ---- quad counting on hand-made cases -------------------------------------------------------------

def _triangle_scene(coc=0.0, size=24):
    # One fronto-parallel triangle at the focus depth covering part of a size x size image.
    d = 5.0
    tri = np.array([[[-1.3, -1.1, -d], [1.2, -0.6, -d], [-0.2, 1.25, -d]]], float)
    scene = models.Scene.from_arrays(tri)
    cam = sim.Camera(width=size, height=size, fov_y_deg=45.0, focus_distance=d, coc_px=coc)
    return scene, cam


def _hits(scene, cam, table):
    r = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce"), export_samples=True)
    return r.sample_triangle >= 0  # (H, W, spp); one triangle: every hit passes the depth test


def _reference_quads(hit, key_of_sample=None):
    """quad requests, live lanes for lanes keyed by (pixel, key(sample)) grouped in 2x2 quads."""
    ys, xs, ss = np.nonzero(hit)
    key = np.zeros_like(ss) if key_of_sample is None else key_of_sample(ys, xs, ss)
    lanes = set(zip(ys.tolist(), xs.tolist(), key.tolist()))
    quads = {(y // 2, x // 2, k) for y, x, k in lanes}
    return len(quads), len(lanes)


def _shade(scene, cam, table, algorithm, shading, **kw):
    cfg = sim.PipelineConfig(algorithm=algorithm, shading=shading, **kw)
    return sim.render(scene, cam, table, cfg).flat_stats


@pytest.mark.parametrize("coc", [0.0, 3.0])
def test_quad_counts_hand_made(coc):
    scene, cam = _triangle_scene(coc)
    table = sim.SampleTable.stratified(spp=16, seed=3)
    hit = _hits(scene, cam, table)
    samples = table.samples(cam.lens)
    P = samples.shape[0]
    G = 4
    cell_u = np.clip(np.floor((samples[..., 2] + 1) * G / 2), 0, G - 1).astype(int)
    cell_v = np.clip(np.floor((samples[..., 3] + 1) * G / 2), 0, G - 1).astype(int)
    cell = cell_v * G + cell_u

    msaa_q, msaa_live = _reference_quads(hit)
    ss_q, ss_live = _reference_quads(hit, lambda y, x, s: s)
    lc_q, lc_live = _reference_quads(hit, lambda y, x, s: cell[y % P, x % P, s])

    def check(stats, quads, live):
        assert stats["shade.quad_requests"] == quads
        assert stats["shade.lanes_live"] == live
        assert stats["shade.lanes_helper"] == 4 * quads - live
        assert stats["shade.invocations"] == 4 * quads

    # BRUTEFORCE walks the triangle once per bin: one visit, MSAA shades once per pixel.
    check(_shade(scene, cam, table, "bruteforce", "msaa"), msaa_q, msaa_live)
    check(_shade(scene, cam, table, "bruteforce", "per_sample"), ss_q, ss_live)
    check(_shade(scene, cam, table, "bruteforce", "per_lens_cell"), lc_q, lc_live)
    # TILE with 2x2 or 4x4 tiles: tiles hold whole quads, so the same counts.
    for T in (2, 4):
        check(_shade(scene, cam, table, "tile", "msaa", tile_size=T), msaa_q, msaa_live)
        check(_shade(scene, cam, table, "tile", "per_lens_cell", tile_size=T), lc_q, lc_live)
    # 1x1 tiles: every visit is one pixel, so every quad has one live lane and three helpers.
    check(_shade(scene, cam, table, "tile", "msaa", tile_size=1), msaa_live, msaa_live)
    # INTERVAL visits each lens cell in its own pass: MSAA can shade only per (pixel, cell).
    check(_shade(scene, cam, table, "interval", "msaa"), lc_q, lc_live)


def test_shading_cache_counts_hand_made():
    # In focus, fronto-parallel: a sample's hit point seen through the lens centre is the sample
    # position itself, so the shading-grid point is floor(sample position * grid).
    scene, cam = _triangle_scene(0.0)
    table = sim.SampleTable.stratified(spp=16, seed=5)
    hit = _hits(scene, cam, table)
    samples = table.samples(cam.lens)
    P = samples.shape[0]
    for grid in (1, 2):
        ys, xs, ss = np.nonzero(hit)
        gx = np.floor((xs + samples[ys % P, xs % P, ss, 0]) * grid).astype(int)
        gy = np.floor((ys + samples[ys % P, xs % P, ss, 1]) * grid).astype(int)
        points = set(zip(gx.tolist(), gy.tolist()))
        quads = {(x // 2, y // 2) for x, y in points}
        st = _shade(scene, cam, table, "bruteforce", "cache", shading_grid=grid, shading_cache_entries=1 << 16)
        assert st["shade.cache_misses"] == len(points)
        assert st["shade.cache_hits"] == 0  # one visit: every point is looked up once
        assert st["shade.quad_requests"] == len(quads)
        assert st["shade.lanes_live"] == len(points)
        # Per-tile visits look each point up once per tile that needs it; in focus, the points of a
        # pixel are inside the pixel, so 1x1 tiles never share points either.
        st1 = _shade(scene, cam, table, "tile", "cache", tile_size=1, shading_grid=grid, shading_cache_entries=1 << 16)
        assert st1["shade.cache_misses"] == len(points) and st1["shade.cache_hits"] == 0
    # A one-entry cache with interval: every visit (lens cell) looks up the pixel again.
    st = _shade(scene, cam, table, "interval", "cache", shading_cache_entries=1)
    assert st["shade.cache_misses"] + st["shade.cache_hits"] > len(points)


# ---- textured renders -------------------------------------------------------------------------------

def _textured_scene():
    scene = models.named("spot")
    cam = sim.Camera(**{**scene.camera_hint, "width": 64, "height": 64, "coc_px": 6.0})
    return scene, cam


def test_same_image_with_texturing_all_algorithms():
    scene, cam = _textured_scene()
    table = sim.SampleTable.interleaved(spp=16, n_lens=16, seed=2)
    images = {}
    stats = {}
    for algo in sim.algorithm_names("points"):
        for shading in ("msaa", "cache", "none"):
            cfg = sim.PipelineConfig(algorithm=algo, shading=shading, texture_count=2, texture_filter="trilinear")
            r = sim.render(scene, cam, table, cfg)
            images[(algo, shading)] = r.image
            stats[(algo, shading)] = r.flat_stats
    ref = images[("bruteforce", "none")]
    for key, img in images.items():
        np.testing.assert_array_equal(img, ref, err_msg=str(key))
    untextured = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce")).image
    assert not np.array_equal(untextured, ref)  # the texture does reach the image
    assert stats[("tile", "msaa")]["tex.fetches"] > 0
    assert stats[("tile", "none")]["tex.fetches"] == 0


def test_texture_counters_independent_of_threads():
    scene, cam = _textured_scene()
    table = sim.SampleTable.stratified(spp=16, seed=2)
    out = []
    for threads in (1, 2, 3):
        cfg = sim.PipelineConfig(algorithm="tile", shading="cache", texture_count=1, threads=threads, bin_size=16,
                                 texture_sample_distribution=True)
        r = sim.render(scene, cam, table, cfg, hardware=sim.HardwareConfig(tex_cache={"size_bytes": 4096, "count": 2}))
        out.append({k: v for k, v in r.flat_stats.items() if k.startswith(("shade.", "tex."))})
    assert out[0] == out[1] == out[2]
    s = out[0]
    assert s["tex.cache.accesses"] == s["tex.cache.hits"] + s["tex.cache.misses"] > 0
    assert s["tex.cache.misses"] == s["tex.cache.misses_cold"] + s["tex.cache.misses_capacity"] + s["tex.cache.misses_conflict"]
    assert s["tex.cache.bytes_fetched"] == 64 * s["tex.cache.misses"]


def test_textured_plane_matches_numpy_bilinear(rng):
    # A fronto-parallel textured square, magnified (lambda < 0: level 0, bilinear): every sample's
    # colour is the bilinear texture value at its uv, which the affine map gives in closed form.
    d, side, n = 5.0, 2.0, 40
    s = side / 2
    quad = np.array([[[-s, -s, -d], [s, -s, -d], [s, s, -d]], [[-s, -s, -d], [s, s, -d], [-s, s, -d]]], float)
    uvs = np.array([[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1], [0, 1]]], np.float32)
    tex = rng.uniform(0.2, 1.0, size=(8, 8, 3)).astype(np.float32)
    scene = models.Scene.from_arrays(quad, colors=np.ones((2, 3, 3)), uvs=uvs, texture=tex)
    cam = sim.Camera(width=n, height=n, fov_y_deg=45.0, focus_distance=d)
    table = sim.SampleTable.stratified(spp=4, seed=1)
    r = sim.render(scene, cam, table, sim.PipelineConfig(texture_count=1, texture_filter="bilinear"),
                   export_samples=True)
    samples = table.samples(cam.lens)
    P = samples.shape[0]
    ys, xs = np.mgrid[0:n, 0:n]
    px = xs[..., None] + samples[ys % P, xs % P, :, 0]
    py = ys[..., None] + samples[ys % P, xs % P, :, 1]
    half = side / 2 * (1 / math.tan(math.radians(22.5))) * n / (2 * d)  # half-size in pixels
    u = (px - (n / 2 - half)) / (2 * half)
    v = 1 - (py - (n / 2 - half)) / (2 * half)
    from models.textures import sample_bilinear
    col = sample_bilinear(tex, np.stack([u, v], -1))
    col[r.sample_triangle < 0] = 0
    want = col.mean(axis=2)
    inside = (r.sample_triangle >= 0).all(axis=2)
    np.testing.assert_allclose(r.image[inside], want[inside], atol=2e-4)


def test_bad_shading_config_is_a_config_error():
    with pytest.raises(sim.ConfigError, match="shading"):
        sim.PipelineConfig(shading="deferred")
    with pytest.raises(sim.ConfigError, match="texture_count"):
        sim.PipelineConfig(texture_count=5)
    with pytest.raises(sim.ConfigError, match="texture_layout"):
        sim.PipelineConfig(texture_layout="tiled")
    with pytest.raises(sim.ConfigError, match="tex_cache.size_bytes"):
        sim.HardwareConfig(tex_cache={"size_bytes": 1024, "ways": 3})


def test_interval_msaa_equals_tile_per_lens_cell_on_a_scene():
    # Each sample meets the triangles in submission order in every algorithm, so early-z passes the
    # same samples; with 2x2 tiles a tile visit is one quad, so INTERVAL's MSAA (a visit per lens-cell
    # pass) and TILE's per-lens-cell shading must issue the same quads.
    scene = models.named("spot_wall")
    cam = sim.Camera(**{**scene.camera_hint, "width": 64, "height": 64, "coc_px": 8.0})
    table = sim.SampleTable.stratified(spp=16, seed=9)
    a = _shade(scene, cam, table, "interval", "msaa")
    b = _shade(scene, cam, table, "tile", "per_lens_cell", tile_size=2)
    for k in ("shade.quad_requests", "shade.lanes_live", "shade.lanes_helper", "depth.passes"):
        assert a[k] == b[k], k
    c = _shade(scene, cam, table, "tile", "msaa", tile_size=2)
    assert c["shade.quad_requests"] < b["shade.quad_requests"] < _shade(scene, cam, table, "tile", "per_sample")[
        "shade.quad_requests"]


def test_shading_counts_same_on_counting_path():
    scene, cam = _textured_scene()
    table = sim.SampleTable.stratified(spp=8, seed=3)
    out = []
    for op_count in ("documented", "exact"):
        cfg = sim.PipelineConfig(algorithm="tile", shading="cache", texture_count=1, op_count=op_count)
        r = sim.render(scene, cam, table, cfg)
        out.append(({k: v for k, v in r.flat_stats.items() if k.startswith(("shade.", "tex."))}, r.image))
    assert out[0][0] == out[1][0]
    np.testing.assert_array_equal(out[0][1], out[1][1])


def test_sample_distribution_texture_adds_one_fetch_per_lane():
    # [Toth 2008] §5.3: one extra nearest texel per shaded lane, at a 1:1 pixel mapping (coherent: it should
    # hardly ever miss once its few lines are in).
    scene, cam = _textured_scene()
    table = sim.SampleTable.stratified(spp=8, seed=3)
    base = _shade(scene, cam, table, "tile", "msaa", texture_count=1)
    with_sd = _shade(scene, cam, table, "tile", "msaa", texture_count=1, texture_sample_distribution=True)
    assert with_sd["shade.invocations"] == base["shade.invocations"]
    assert with_sd["tex.fetches"] - base["tex.fetches"] == base["shade.invocations"]
    assert with_sd["tex.cache.accesses"] - base["tex.cache.accesses"] == base["shade.invocations"]
    only_sd = _shade(scene, cam, table, "tile", "msaa", texture_sample_distribution=True)
    assert only_sd["tex.fetches"] == base["shade.invocations"]
    assert only_sd["tex.cache.hit_rate"] > 0.9


@pytest.mark.parametrize("shading", ["per_sample", "msaa", "per_lens_cell", "cache", "none"])
def test_every_option_combination_renders_the_same_image(shading):
    scene = models.named("spot_wall")
    cam = sim.Camera(**{**scene.camera_hint, "width": 32, "height": 32, "coc_px": 5.0})
    table = sim.SampleTable.interleaved(spp=8, n_lens=16, seed=1)
    ref = None
    for algo in ("bruteforce", "tile", "interleave"):
        for count, filt, layout, sd, grid in ((0, "bilinear", "linear", True, 1), (1, "bilinear", "morton", False, 2),
                                              (3, "trilinear", "blocked", True, 3), (4, "trilinear", "linear", False, 1)):
            cache = {"shading_grid": grid, "shading_cache_entries": 16} if shading == "cache" else {}  # read by it only
            cfg = sim.PipelineConfig(algorithm=algo, shading=shading, texture_count=count, texture_filter=filt,
                                     texture_layout=layout, texture_sample_distribution=sd, bin_size=16, **cache)
            hw = sim.HardwareConfig(tex_cache={"size_bytes": 2048, "ways": 0, "line_bytes": 32, "count": 3})
            r = sim.render(scene, cam, table, cfg, hardware=hw)
            if count == 3:
                if ref is None:
                    ref = r.image
                np.testing.assert_array_equal(r.image, ref)
            s = r.flat_stats
            assert s["tex.cache.misses_conflict"] == 0  # fully associative
            if shading != "none":
                assert s["shade.invocations"] == 4 * s["shade.quad_requests"]


def test_bad_texture_inputs_raise_not_crash():
    scene, cam = _triangle_scene(0.0, size=16)
    table = sim.SampleTable.stratified(spp=4, seed=1)
    bad_ids = models.Scene.from_arrays(scene.positions, uvs=np.full((1, 3, 2), np.float32(0.5)),
                                       texture=np.ones((4, 4, 3), np.float32))
    bad_ids.texture_ids = np.array([3], np.int32)  # past the one texture, set behind the validator's back
    with pytest.raises(ValueError, match="tex_slots|texture"):
        sim.render(bad_ids, cam, table, sim.PipelineConfig(shading="msaa", texture_count=1))
    # Non-finite uvs from a duck-typed scene (past models.Scene's validator): refused by the engine,
    # naming the array, the triangle and the vertex.
    class Duck:
        positions = scene.positions
        uvs = np.full((1, 3, 2), np.nan, np.float32)
        textures = [np.ones((4, 4, 3), np.float32)]
        texture_ids = np.zeros(1, np.int32)
    with pytest.raises(ValueError, match=r"uvs: triangle 0 vertex 0 is not finite"):
        sim.render(Duck(), cam, table, sim.PipelineConfig(shading="msaa", texture_count=1))
