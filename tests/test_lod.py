"""Blur-based level of detail (models/lod.py; [Toth 2008] §7.2, [Tzeng 2012] §4.2): object split, level choice from
s_lod = c_min / d_avg, simplification with its disk cache, and the render path."""
from __future__ import annotations

import math

import numpy as np
import pytest

import sim
from models import Scene, lod


def _grid(n, z, x0=-1.0, x1=1.0, color=(0.8, 0.5, 0.2)):
    """An n x n grid of quads (2 n^2 triangles) in the plane z, sharing vertices."""
    xs = np.linspace(x0, x1, n + 1)
    tris = []
    for i in range(n):
        for j in range(n):
            a, b = (xs[i], xs[j], z), (xs[i + 1], xs[j], z)
            c, d = (xs[i + 1], xs[j + 1], z), (xs[i], xs[j + 1], z)
            tris += [[a, b, c], [a, c, d]]
    return Scene.from_arrays(np.array(tris), colors=color)


def test_objects_are_connected_components():
    a, b = _grid(3, -5.0), _grid(2, -6.0, 2.0, 3.0)
    labels = lod.objects(Scene.concat(a, b).positions)
    assert labels.tolist() == [0] * a.n_triangles + [1] * b.n_triangles


def test_choose_level():
    # reduction 0.5: each level's edges are sqrt(2) longer; s_lod = 2 allows 2 levels of sqrt(2).
    assert lod.choose_level(0.5, 3, 0.5, 1.0) == 0
    assert lod.choose_level(math.sqrt(2) * 1.0001, 3, 0.5, 1.0) == 1
    assert lod.choose_level(2.0001, 3, 0.5, 1.0) == 2
    assert lod.choose_level(100.0, 3, 0.5, 1.0) == 2
    assert lod.choose_level(100.0, 1, 0.5, 1.0) == 0


def test_blurred_object_is_simplified_and_cached(tmp_path, monkeypatch):
    monkeypatch.setenv("RAST5D_LOD_CACHE", str(tmp_path))
    cam = sim.Camera(width=64, height=64, focus_distance=20.0, coc_px=30.0)
    near = _grid(16, -4.0)  # w = 4, F = 20: CoC 30 |1 - 5| = 120 px, edges ~ 10 px
    params = dict(sim.PipelineConfig().lod, enabled=True)
    out, rep = lod.apply(near, cam, params)
    o = rep.objects[0]
    expect_c = 30.0 * abs(1.0 - 20.0 / 4.0)
    assert o["c_min_px"] == pytest.approx(expect_c)
    focal = 64 / (2 * math.tan(math.radians(45.0) / 2))
    edges = np.linalg.norm(near.positions - np.roll(near.positions, 1, axis=1), axis=2).mean()
    assert o["d_avg_px"] == pytest.approx(edges * focal / 4.0)
    assert o["level"] == 2 and out.n_triangles < 0.35 * near.n_triangles
    assert rep.stats["lod.triangles_saved"] == near.n_triangles - out.n_triangles
    assert rep.stats["lod.triangles_level2"] == out.n_triangles
    assert len(list(tmp_path.glob("*.npz"))) == 1
    again, _ = lod.apply(near, cam, params)  # from the cache
    assert np.array_equal(again.positions, out.positions)
    # In focus: the box reaches the focus plane, c_min = 0, level 0.
    focused, rep2 = lod.apply(_grid(16, -20.0), cam, params)
    assert rep2.objects[0]["level"] == 0 and focused.n_triangles == 2 * 16 * 16


def test_render_reports_lod_figures(tmp_path, monkeypatch):
    monkeypatch.setenv("RAST5D_LOD_CACHE", str(tmp_path))
    cam = sim.Camera(width=32, height=32, focus_distance=20.0, coc_px=8.0)
    scene = _grid(12, -4.0)
    cfg = sim.PipelineConfig(algorithm="tile", threads=1, lod=dict(sim.PipelineConfig().lod, enabled=True))
    table = sim.SampleTable.stratified(spp=4, time=False)
    with pytest.raises(sim.ConfigError, match="pipeline.lod"):
        sim.render(scene, cam, table, cfg)
    reduced, _ = lod.apply(scene, cam, cfg.lod)
    r = sim.render(reduced, cam, table, cfg)
    assert r.flat_stats["lod.triangles"] == reduced.n_triangles < scene.n_triangles
    assert r.config["lod"][0]["level"] > 0
    full = sim.render(scene, cam, table, cfg.replace(lod=dict(cfg.lod, enabled=False)))
    assert r.flat_stats["setup.triangles"] < full.flat_stats["setup.triangles"]


def test_bad_lod_parameters():
    with pytest.raises(sim.ConfigError, match="levels"):
        sim.PipelineConfig(lod=dict(sim.PipelineConfig().lod, levels=9))
    with pytest.raises(sim.ConfigError, match="reduction"):
        sim.PipelineConfig(lod=dict(sim.PipelineConfig().lod, reduction=1.5))
    with pytest.raises(ValueError, match="pipeline.lod.bogus"):
        lod.check_params({"bogus": 1})
