"""The rasterizer's uses (sim.uses; 002 §4-§7, 003): each checked against a closed form, a
brute-force computation or a statistical test that does not run the code under test."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import models
import sim
from sim import uses


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


# ---- stochastic transparency (003) ---------------------------------------------------------------

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


def test_transparency_winners_follow_the_over_operator_chi2():
    """Per sample the surviving front layer is layer i with probability a_i prod_{j<i} (1 - a_j): chi-square
    over 16k samples of a constant stack (independent masks across layers and samples)."""
    alphas = [0.5, 0.25, 0.75]
    sc = _layers_scene(alphas)
    cam = sim.Camera(**CAM)
    r = sim.render(sc, cam, sim.SampleTable.stratified(spp=16, seed=2), export_samples=True)
    layer = np.where(r.sample_triangle >= 0, r.sample_triangle // 2, len(alphas)).ravel()
    counts = np.bincount(layer, minlength=len(alphas) + 1)
    p, through = [], 1.0
    for a in alphas:
        p.append(through * a)
        through *= 1 - a
    p.append(through)
    _, pval = stats.chisquare(counts, np.asarray(p) * counts.sum())
    assert pval > 1e-3, (counts, p)


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
