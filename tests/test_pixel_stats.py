"""Per-pixel statistics and the pixel trace (sim.pixel_stats): the maps sum exactly to the frame
counters for every algorithm and thread count, leave the image and the counters alone, and put the
hits where the independent ray caster finds them; a traced pixel's samples match brute force."""
from __future__ import annotations

import functools

import numpy as np
import pytest

import sim
from tests.reference import ray_cast
from tests.reference.compare import table_points
from experiments.reference.raycaster import edge_distance_px, near_rel_distance
from tests.test_invariants import interleaved_table, synthetic_scene

W, H = 40, 32


@functools.lru_cache(maxsize=None)
def setup(moving=True):
    cam = sim.Camera(width=W, height=H, fov_y_deg=45, focus_distance=5.0, coc_px=6)
    return synthetic_scene(W, H, 5.0, moving=moving), cam, interleaved_table()


@functools.lru_cache(maxsize=None)
def reference_hits():
    """Per pixel, the (triangle, sample) pairs the float64 ray caster hits, and a mask of pixels
    with no sample near an edge or the near plane (where float32 and float64 may disagree)."""
    scene, cam, table = setup()
    pts = table_points(table, cam).astype(np.float64)  # (H, W, spp, 5)
    n = scene.positions.shape[0]
    p0 = scene.positions.reshape(n, 1, 1, 1, 3, 3)
    p1 = scene.positions_t1.reshape(n, 1, 1, 1, 3, 3)
    big = np.broadcast_to(pts, (n,) + pts.shape)
    rc = ray_cast(cam, p0, p1, big)
    close = (edge_distance_px(cam, p0, p1, big) < 1e-3) | (near_rel_distance(cam, rc.w) < 1e-4)
    return rc.hit, ~close.any(axis=(0, 3))


@pytest.mark.parametrize("algorithm", sim.algorithm_names("points"))
def test_maps_sum_to_frame_counters_for_every_thread_count(algorithm):
    scene, cam, table = setup()
    plain = sim.render(scene, cam, table, sim.PipelineConfig(algorithm=algorithm, threads=2), timing=False)
    maps = {}
    for threads in (1, 3):
        res = sim.render(scene, cam, table, sim.PipelineConfig(algorithm=algorithm, threads=threads),
                         timing=False, pixel_stats=True)
        assert set(sim.pixel_stats.DEFAULT) | {"ops.total"} <= set(res.pixel_stats)
        for name, m in res.pixel_stats.items():
            assert m.shape == (H, W), name
            assert int(m.sum()) == res.flat_stats[name], f"{algorithm}, {threads} threads: {name}"
        # opt-in observation: same image and counters as without it
        assert np.array_equal(plain.image.view(np.uint32), res.image.view(np.uint32))
        assert {k: v for k, v in res.flat_stats.items() if k != "time.wall_s"} == \
               {k: v for k, v in plain.flat_stats.items() if k != "time.wall_s"}
        for name, m in res.pixel_stats.items():
            if name in maps:
                assert np.array_equal(maps[name], m), f"{algorithm}: {name} depends on the thread count"
            maps[name] = m
    # hits where the ray caster finds them (every algorithm is exact)
    hit, clean = reference_hits()
    ref = hit.sum(axis=(0, 3))
    got = maps["raster.samples_hit"]
    assert clean.mean() > 0.5
    bad = np.argwhere(clean & (ref != got))
    assert not len(bad), f"{algorithm}: hits differ at (y, x) {bad[:5].tolist()}: {got[tuple(bad[0])]} vs {ref[tuple(bad[0])]}"
    assert (maps["raster.samples_tested"] >= got).all()


def test_every_counter_maps_exactly():
    scene, cam, table = setup()
    names = [n for n in sim._core.counter_docs() if not n.startswith(("frame.", "tex.cache."))]
    res = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="tile"), timing=False, pixel_stats=names)
    for n in names:
        assert int(res.pixel_stats[n].sum()) == res.flat_stats[n], n


def test_tile_cull_reason_map():
    scene, cam, table = setup(moving=False)
    cfg = sim.PipelineConfig(algorithm="tile", tile_size=4)
    res = sim.render(scene, cam, table, cfg, timing=False, pixel_stats=True)
    reason, names = sim.pixel_stats.cull_reason(res.pixel_stats, 4)
    assert reason.shape == (H // 4, W // 4)
    assert res.flat_stats["tile.culled_H"] > 0 and names.index("tile.culled_H") in reason
    blocks = sim.pixel_stats.tile_blocks(res.pixel_stats["tile.culled_H"], 4)
    assert blocks.sum() == res.flat_stats["tile.culled_H"]


def test_bad_names_are_config_errors():
    scene, cam, table = setup()
    with pytest.raises(sim.ConfigError, match="raster.samples_tsted"):
        sim.render(scene, cam, table, pixel_stats=["raster.samples_tsted"])
    with pytest.raises(sim.ConfigError, match="tex.cache.hits"):
        sim.render(scene, cam, table, pixel_stats=["tex.cache.hits"])
    with pytest.raises(sim.ConfigError, match="outside"):
        sim.trace_pixel(scene, cam, table, W, 0)


@pytest.mark.parametrize("algorithm", ["bruteforce", "tile", "interleave"])
def test_trace_matches_brute_force(algorithm):
    scene, cam, table = setup()
    hit, clean = reference_hits()
    cfg = sim.PipelineConfig(algorithm=algorithm)
    maps = sim.render(scene, cam, table, cfg, timing=False, pixel_stats=True).pixel_stats
    ys, xs = np.nonzero(clean & (hit.sum(axis=(0, 3)) > 1))
    for y, x in list(zip(ys, xs))[:: max(1, len(ys) // 4)][:4]:
        tr = sim.trace_pixel(scene, cam, table, int(x), int(y), cfg)
        assert len(tr.samples) == maps["raster.samples_tested"][y, x]
        for t in range(scene.positions.shape[0]):
            expect = set(np.nonzero(hit[t, y, x])[0].tolist())
            assert set(tr.hit(t)) == expect, f"{algorithm} ({x}, {y}) triangle {t}"
            assert expect <= set(tr.tested(t))
            if algorithm == "bruteforce" and tr.tested(t):
                assert sorted(tr.tested(t)) == list(range(table.spp))
        assert "samples hit" in str(tr)
    if algorithm == "tile":
        verdicts = [v for _, v, _ in tr.tile_verdicts()]
        assert "tile.accepted" in verdicts
