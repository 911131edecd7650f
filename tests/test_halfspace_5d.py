"""The H5 test (pipeline.halfspace.H5, intervals/halfspace_5d.h): [Akenine-Möller 2012]'s H_j lines extended to time for moving triangles. Conservative against brute force (adversarial moving classes and hypothesis), never removes a sample of the exact 5D region (tile.samples_optimal is unchanged, and equals laine5d's), documented op costs equal the counting scalar's under both cost models, and it culls where it should."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import models
import sim
from tests.test_intervals import ADVERSARIAL, HYPO, camera, make_scene, moving_tri, table

pytestmark = pytest.mark.invariants

H5 = {"h": True, "H": True, "H5": True}


def _render(scene, cam, tab, **cfg):
    return sim.render(scene, cam, tab, sim.PipelineConfig(threads=1, count_optimal=True, **cfg), export_samples=True)


def _same_as_bruteforce(scene, cam, tab, configs):
    """Every config renders brute force's sample ownership and image, and keeps the exact 5D region:
    hits <= optimal <= tested, with the optimum of tile without H5 (the exact region does not depend
    on the tile test, so a conservative test cannot change it). Returns the H5 renders' stats."""
    ref = _render(scene, cam, tab, algorithm="bruteforce")
    out = []
    for cfg in configs:
        base = _render(scene, cam, tab, algorithm="tile", **{k: v for k, v in cfg.items() if k != "halfspace"})
        res = _render(scene, cam, tab, algorithm="tile", **cfg)
        assert np.array_equal(ref.sample_triangle, res.sample_triangle), cfg
        assert np.array_equal(ref.image, res.image), cfg
        st_, b = res.flat_stats, base.flat_stats
        assert st_["raster.samples_hit"] <= st_["tile.samples_optimal"] <= st_["raster.samples_tested"], (cfg, st_)
        assert st_["tile.samples_optimal"] == b["tile.samples_optimal"], cfg
        assert st_["raster.samples_tested"] <= b["raster.samples_tested"], cfg
        out.append(st_)
    return out


@pytest.mark.parametrize("coc", [0.0, 6.0, 25.0])
@pytest.mark.parametrize("name", sorted(ADVERSARIAL))
def test_h5_same_samples_as_bruteforce_adversarial(name, coc):
    """Moving through the near plane, changing facing, through the focus plane, 600 px motion, rotating,
    the plane sweeping through the camera: tile with H5 (oracle off: every edge tested) at tile sizes
    1, 2, 8 and 1 or 4 time sub-intervals hits exactly brute force's samples."""
    tris = ADVERSARIAL[name]
    scene = make_scene(np.array([a for a, _ in tris]), np.array([b for _, b in tris]))
    configs = [dict(tile_size=t, time_splits=s, time_strata=max(8, s), selective_H=False, halfspace=H5)
               for t in (1, 2, 8) for s in (1, 4)]
    _same_as_bruteforce(scene, camera(coc), table(), configs)


@settings(max_examples=40, **HYPO)
@given(c0=st.tuples(st.floats(-10, 40), st.floats(-10, 34)), motion=st.tuples(st.floats(-120, 120), st.floats(-60, 60)),
       d0=st.floats(0.3, 12.0), d1=st.floats(0.3, 12.0), size=st.floats(0.5, 30.0), rot=st.floats(-3.0, 3.0),
       coc=st.sampled_from([0.0, 4.0, 20.0]), tile=st.sampled_from([1, 2, 4, 8]), splits=st.sampled_from([1, 2, 4]),
       grid=st.sampled_from([1, 4, 8]))
def test_h5_conservative_random(c0, motion, d0, d1, size, rot, coc, tile, splits, grid):
    a, b = moving_tri(c0, (c0[0] + motion[0], c0[1] + motion[1]), d0, d1, size=size, rot=rot)
    cfg = dict(tile_size=tile, time_splits=splits, lens_grid=grid, selective_H=False, halfspace=H5)
    _same_as_bruteforce(make_scene(a[None], b[None]), camera(coc), table(8), [cfg])


def test_h5_culls_large_moving_defocused_triangles():
    """Large triangles translating diagonally with defocus: the H5 planes cull lens cells and whole tiles,
    so fewer samples are tested than with t̂ and the lens sets alone (and the same ones are hit)."""
    tris = [moving_tri((2, 2), (14, 10), 3.0, 3.2, size=18), moving_tri((28, 4), (16, 16), 6.0, 5.5, size=14, rot=0.2)]
    scene = make_scene(np.array([a for a, _ in tris]), np.array([b for _, b in tris]))
    for coc in (0.0, 8.0):
        (st_,) = _same_as_bruteforce(scene, camera(coc), table(), [dict(selective_H=False, halfspace=H5)])
        base = _render(scene, camera(coc), table(), algorithm="tile").flat_stats
        assert st_["tile.H5_lines"] > 0 and st_["tile.culled_H5"] > 0, coc
        assert st_["raster.samples_tested"] < 0.95 * base["raster.samples_tested"], (coc, st_["raster.samples_tested"],
                                                                                     base["raster.samples_tested"])
        if coc > 0:
            assert st_["tile.H5_cells_culled"] > 0


def test_h5_off_by_default_changes_nothing():
    """halfspace.H5 is off by default; turning it on changes no counter of a static scene."""
    assert sim.PipelineConfig().halfspace["H5"] is False
    scene = models.named("focus_crossing")
    cam = sim.Camera(width=48, height=48, fov_y_deg=45, focus_distance=4.0, coc_px=10)
    a = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="tile", threads=1)).flat_stats
    b = sim.render(scene, cam, table(), sim.PipelineConfig(algorithm="tile", threads=1, halfspace=H5)).flat_stats
    raw = set(sim._core.counter_docs())
    assert {k: a[k] for k in raw} == {k: b[k] for k in raw}


@pytest.mark.parametrize("model", ["robust", "hardware"])
@pytest.mark.parametrize("selective", [True, False])
def test_h5_documented_op_counts_equal_exact_counts(model, selective):
    """Every H5 kernel (setup per sub-interval, oracle, per-tile constants, corner lines, box pre-tests,
    cell lines) charges its documented cost: whole renders count the same operations with op_count
    documented and exact, on 3D and 5D moving triangles, under both cost models."""
    tris = [moving_tri((2, 2), (14, 10), 3.0, 3.2, size=18), moving_tri((20, 4), (10, 14), 6.0, 2.5, size=10, rot=1.0),
            moving_tri((8, 8), (9, 9), 4.0, 4.0, size=6)]
    scene = make_scene(np.array([a for a, _ in tris]), np.array([b for _, b in tris]))
    for coc in (0.0, 8.0):
        for splits in (1, 4):
            cfg = dict(algorithm="tile", threads=1, cost_model=model, selective_H=selective, time_splits=splits,
                       halfspace=H5)
            doc = sim.render(scene, camera(coc), table(), sim.PipelineConfig(op_count="documented", **cfg)).flat_stats
            exact = sim.render(scene, camera(coc), table(), sim.PipelineConfig(op_count="exact", **cfg)).flat_stats
            ops = {k: v for k, v in doc.items() if k.startswith("ops.")}
            assert ops == {k: exact[k] for k in ops}, (coc, splits)
            assert doc["tile.H5_lines"] == exact["tile.H5_lines"] > 0


@pytest.mark.parametrize("name", ["through_focus", "rotating", "fast_600px"])
def test_laine5d_counts_the_same_exact_5d_optimum_as_tile(name):
    """count_optimal in laine5d: the samples it tests inside the exact (u, v, t) region of their tile are
    those tile tests there (both keep the whole region), so both report the same optimum."""
    tris = ADVERSARIAL[name]
    scene = make_scene(np.array([a for a, _ in tris]), np.array([b for _, b in tris]))
    for coc in (0.0, 10.0):
        opt = [_render(scene, camera(coc), table(), algorithm=a, tile_size=2).flat_stats["tile.samples_optimal"]
               for a in ("tile", "laine5d")]
        assert opt[0] == opt[1] > 0, (coc, opt)
