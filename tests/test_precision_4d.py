"""The 4D tile test in pipeline.precision.tile (tiletest/precision_4d.h; docs/precision.md): the h_i sets and
H_j cells of a static defocused triangle computed in float32 or fixed point stay conservative against the
independent float64 ray caster (no culled (tile, lens cell) pair holds a sample the triangle covers) on the
hard-case suite and on random triangles at several bit widths; they still cull (the test can fail: fewer
bits cull less, never wrongly); every exact algorithm renders brute force's image with a float32 or fixed
tile stage; overflow of a narrow format is counted in precision.tile4d_overflows."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sim
from sim import _core
from tests import reference as ref

HARD = ref.hard_cases()


def fixed(int_bits, frac_bits):
    return {"fixed": {"int_bits": int_bits, "frac_bits": frac_bits}}


TILE_PRECISIONS = ["float32", fixed(40, 2), fixed(40, 4), fixed(40, 8)]
IDS = ["float32", "fixed2", "fixed4", "fixed8"]


def probe(cam, v0, tiles, precision, grid=4):
    params = ref.engine_params(cam)
    params.lens_grid = grid
    params.precision_tile = precision
    return _core.precision_probe_4d(params, np.asarray(v0, np.float32), np.asarray(tiles, np.float64))


def tiles_near(r, cam, rng, size=4, n=40):
    """Tiles of `size` px on the screen near the footprint (its lens vertices' extent over the lens)."""
    lv = np.asarray(r["lens_vertices"])
    lo = np.minimum(lv[:, :2] - np.abs(lv[:, 2:]), lv[:, :2] + np.abs(lv[:, 2:])).min(0) - size
    hi = np.maximum(lv[:, :2] - np.abs(lv[:, 2:]), lv[:, :2] + np.abs(lv[:, 2:])).max(0) + size
    lo = np.clip(lo, 0, [cam.width - size, cam.height - size])
    hi = np.clip(hi, lo + size, [cam.width, cam.height])
    x = np.floor(rng.uniform(lo[0], hi[0] - size + 1, n) / size) * size
    y = np.floor(rng.uniform(lo[1], hi[1] - size + 1, n) / size) * size
    return np.stack([x, x + size, y, y + size], axis=1)


def violations(cam, p0, tiles, culled, grid, rng, per_pair=12, max_pairs=300):
    """Culled (tile, cell) pairs with a ray-cast hit in front of the near plane at random sample points."""
    pairs = np.argwhere(culled)
    if len(pairs) == 0:
        return 0, 0
    if len(pairs) > max_pairs:
        pairs = pairs[rng.choice(len(pairs), max_pairs, replace=False)]
    t, c = pairs[:, 0], pairs[:, 1]
    i, j = c % grid, c // grid
    m = len(pairs) * per_pair
    r = rng.random((m, 4))
    rep = lambda a: np.repeat(a, per_pair)  # noqa: E731
    T = tiles[rep(t)]
    sx = T[:, 0] + r[:, 0] * (T[:, 1] - T[:, 0])
    sy = T[:, 2] + r[:, 1] * (T[:, 3] - T[:, 2])
    u = -1.0 + (rep(i) + r[:, 2]) * 2.0 / grid
    v = -1.0 + (rep(j) + r[:, 3]) * 2.0 / grid
    pts = np.stack([sx, sy, u, v, np.zeros(m)], axis=1)
    rc = ref.ray_cast(cam, p0, p0, pts)
    return int(rc.hit.sum()), m


def check_triangle(cam, p0, precision, rng, grid=4):
    v0, _ = cam.engine_vertices(p0[None], p0[None])
    r64 = probe(cam, v0[0], np.zeros((0, 4)), "float64", grid)
    if r64["dim_class"] != 2:  # static defocused triangles only (4D)
        return None
    tiles = tiles_near(r64, cam, rng)
    r = probe(cam, v0[0], tiles, precision, grid)
    bad, n = violations(cam, p0, tiles, np.asarray(r["culled"]), grid, rng)
    bad64, _ = violations(cam, p0, tiles, np.asarray(r["culled64"]), grid, rng)
    assert bad64 == 0
    return bad, n, int(np.asarray(r["culled"]).sum()), int(np.asarray(r["culled64"]).sum()), r


@pytest.mark.parametrize("precision", TILE_PRECISIONS, ids=IDS)
def test_hard_cases_stay_conservative(precision, rng):
    """Every static triangle of the hard-case suite (far off screen, behind the camera, at the near plane,
    crossing the focus plane, huge blur), at 256 px: no lens cell culled in the precision holds a covered
    sample of its tile."""
    culled = culled64 = 0
    for name, (cam_kw, p0, _p1, _) in sorted(HARD.items()):
        cam = sim.Camera(**{**cam_kw, "width": 256, "height": 256, "coc_px": cam_kw["coc_px"] * 8})
        for k in range(p0.shape[0]):
            out = check_triangle(cam, p0[k], precision, rng)
            if out is None:
                continue
            bad, n, c, c64, _ = out
            assert bad == 0, f"{name}[{k}]: {bad} of {n} samples in culled cells are hit at {precision}"
            culled += c
            culled64 += c64
    assert culled64 > 0 and culled > 0.5 * culled64  # the precision form still culls


@settings(max_examples=25, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31 - 1), which=st.integers(0, 3), coc=st.floats(0.5, 60.0),
       size=st.sampled_from([512, 2048, 8192]))
def test_random_triangles_stay_conservative(seed, which, coc, size):
    """Random triangles in front of and across the focus plane at 512 to 8192 px, float32 and fixed 2 / 4 / 8
    sub-pixel bits."""
    rng = np.random.default_rng(seed)
    cam = sim.Camera(width=size, height=size, fov_y_deg=45.0, focus_distance=5.0, coc_px=coc, lens="square")
    w = rng.uniform(0.5, 20.0, 3)
    xy = rng.uniform(-0.2 * size, 1.2 * size, (3, 2))
    p0 = np.array([ref.screen_to_world(cam, x, y, d) for (x, y), d in zip(xy, w)])
    out = check_triangle(cam, p0, TILE_PRECISIONS[which], rng)
    if out is not None:
        bad, n, *_ = out
        assert bad == 0


def test_fewer_bits_cull_less_and_float32_nearly_as_float64():
    """The precision form loses culls as the sub-pixel bits shrink (rounding moves every decision inward),
    and float32 culls within 1 % of float64 on a blurred triangle."""
    cam = sim.Camera(width=1024, height=1024, fov_y_deg=45.0, focus_distance=5.0, coc_px=12.0, lens="square")
    p0 = np.array([ref.screen_to_world(cam, 300, 200, 3.0), ref.screen_to_world(cam, 700, 260, 4.0),
                   ref.screen_to_world(cam, 420, 640, 9.0)])
    v0, _ = cam.engine_vertices(p0[None], p0[None])
    xs = np.arange(240, 760, 8.0)
    tiles = np.array([[x, x + 2, y, y + 2] for x in xs for y in np.arange(160, 700, 8.0)])
    counts = {}
    for name, prec in (("float64", "float64"), ("float32", "float32"), ("f8", fixed(40, 8)), ("f2", fixed(40, 2)),
                       ("f0", fixed(40, 0))):
        counts[name] = int(np.asarray(probe(cam, v0[0], tiles, prec, grid=8)["culled"]).sum())
    assert counts["float32"] >= 0.99 * counts["float64"]
    assert counts["float64"] >= counts["f8"] > counts["f2"] > counts["f0"] > 0


def test_narrow_formats_overflow_and_are_counted():
    """With 8 integer bits the lens vertices of a 512 px screen overflow (counted per test; laine5d's static
    triangles too); 30 suffice."""
    cam = sim.Camera(width=512, height=512, fov_y_deg=45.0, focus_distance=5.0, coc_px=6.0, lens="square")
    p0 = np.array([[ref.screen_to_world(cam, 10, 20, 3.0), ref.screen_to_world(cam, 500, 40, 4.0),
                    ref.screen_to_world(cam, 200, 490, 8.0)]])
    table = sim.SampleTable.stratified(spp=2, seed=1)
    for algo in ("tile", "interval", "laine", "laine5d"):
        few = sim.render(ref.make_scene(p0), cam, table,
                         sim.PipelineConfig(algorithm=algo, precision={"tile": fixed(8, 4)}), timing=False)
        ok = sim.render(ref.make_scene(p0), cam, table,
                        sim.PipelineConfig(algorithm=algo, precision={"tile": fixed(30, 4)}), timing=False)
        assert few.flat_stats["precision.tile4d_overflows"] > 0, algo
        assert ok.flat_stats["precision.tile4d_overflows"] == 0, algo
        assert np.array_equal(ok.image, few.image)  # the render keeps the unwrapped values


@pytest.mark.parametrize("precision", [{"tile": "float32"}, {"tile": fixed(40, 2)}, {"tile": fixed(40, 6)}],
                         ids=["float32", "fixed2", "fixed6"])
def test_exact_algorithms_render_the_same_image_with_a_reduced_tile_stage(precision):
    """The tile algorithms (4D h_i / H_j, box bounds, ẑ with HiZ) render brute force's image with the tile
    stage alone in float32 or fixed point (sample test float32), on hard cases at 256 px."""
    strat = sim.SampleTable.stratified(spp=2, seed=5)
    inter = sim.SampleTable.interleaved(spp=2, n_lens=16, seed=5)
    for name in ("crosses_focus_plane", "huge_blur_tiny_triangles", "vertex_behind_camera", "gigantic_coordinates"):
        cam_kw, p0, p1, _ = HARD[name]
        cam = sim.Camera(**{**cam_kw, "width": 256, "height": 256})
        scene = ref.make_scene(p0, p1)
        for table, algos in ((strat, ["tile", "interval", "laine", "laine5d"]),
                             (inter, ["interleave", "hinterleave", "tile_interleaved"])):
            base = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce"), timing=False)
            for algo in algos:
                for hiz in (False, True) if sim.algorithm_info(algo).depth_cull else (False,):  # HiZ: depth cull only
                    r = sim.render(scene, cam, table,
                                   sim.PipelineConfig(algorithm=algo, precision=precision, hiz={"enabled": hiz}), timing=False)
                    assert np.array_equal(r.image, base.image), f"{name}: {algo} (hiz {hiz}) differs at {precision}"


CELLS4 = np.array([[-1 + i * 0.5, -0.5 + i * 0.5, -1 + j * 0.5, -0.5 + j * 0.5] for j in range(4) for i in range(4)])


def box_outside(cam, p0, precision, rng, shrink=0.0):
    """Ray-cast hits (of 400 samples, half aimed at the triangle) outside the INTERVAL screen bounds of their lens
    cell in the precision, the bounds widened as pixel_range widens them (and each moved inward by `shrink` of
    their extent)."""
    v0, _ = cam.engine_vertices(p0[None], p0[None])
    params = ref.engine_params(cam)
    params.lens_grid = 4
    params.precision_tile = precision
    r = _core.precision_probe_4d(params, np.asarray(v0[0], np.float32), np.zeros((0, 4)), CELLS4)
    if r["dim_class"] != 2:
        return None
    pts = ref.sample_points(rng, cam, p0, p0, 400).astype(np.float64)
    pts[:, 4] = 0.0
    rc = ref.ray_cast(cam, p0, p0, pts)
    hit = rc.hit & (ref.near_rel_distance(cam, rc.w) > 1e-3)
    c = (np.clip(np.floor((pts[:, 3] + 1) / 0.5), 0, 3) * 4 + np.clip(np.floor((pts[:, 2] + 1) / 0.5), 0, 3)).astype(int)
    b = np.asarray(r["box"])[c[hit]]
    F = precision["fixed"]["frac_bits"] if isinstance(precision, dict) else None
    tol = 2.0 ** -10 + (2.0 ** (1 - F) if F is not None else 0.0)
    lo, hi = b[:, [0, 2]], b[:, [1, 3]]
    lo, hi = lo + shrink * (hi - lo), hi - shrink * (hi - lo)
    xy = pts[hit][:, :2]
    out = (xy < lo - tol - 2.0 ** -18 * np.abs(lo)) | (xy > hi + tol + 2.0 ** -18 * np.abs(hi))
    return int(out.any(1).sum()), int(hit.sum()), bool(np.asarray(r["box_overflow"]).any())


@pytest.mark.parametrize("precision", TILE_PRECISIONS, ids=IDS)
def test_box_bounds_hold_every_hit(precision, rng):
    """INTERVAL's screen bounds over a lens cell in the precision (box_bounds_in) hold every ray-cast hit of the
    cell on the hard cases at 1024 px (blur x32), and the check fails on bounds moved inward by 10 % of their
    extent."""
    hits = moved = 0
    for name, (cam_kw, p0, _p1, _) in sorted(HARD.items()):
        cam = sim.Camera(**{**cam_kw, "width": 1024, "height": 1024, "coc_px": cam_kw["coc_px"] * 32})
        for k in range(p0.shape[0]):
            out = box_outside(cam, p0[k], precision, rng)
            if out is None:
                continue
            bad, n, _ovf = out
            assert bad == 0, f"{name}[{k}]: {bad} of {n} hits outside the bounds at {precision}"
            hits += n
            moved += box_outside(cam, p0[k], precision, rng, shrink=0.1)[0]
    assert hits > 1000 and moved > 0
