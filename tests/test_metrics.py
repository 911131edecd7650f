"""Image error metrics against closed forms and known values (experiments/run/metrics.py) and the
reference images they compare against (experiments/run/references.py)."""
import math

import numpy as np
import pytest

from experiments.run import metrics

pytestmark = pytest.mark.smoke


def test_rmse_and_psnr_of_a_known_perturbation(rng):
    ref = rng.uniform(0.2, 0.8, size=(32, 48, 3))
    d = 0.05
    signs = rng.choice([-1.0, 1.0], size=ref.shape)
    test = ref + d * signs  # every pixel off by exactly d: MSE = d^2
    assert metrics.rmse(test, ref) == pytest.approx(d, rel=1e-12)
    assert metrics.psnr(test, ref) == pytest.approx(10 * math.log10(1 / d**2), rel=1e-12)  # 26.02 dB
    # Half the pixels off by d, the others exact: MSE = d^2 / 2.
    half = ref.copy()
    half[::2] += d
    assert metrics.rmse(half, ref) == pytest.approx(d / math.sqrt(2), rel=1e-12)


def test_psnr_of_gaussian_noise_matches_its_variance(rng):
    ref = np.full((256, 256, 3), 0.5)
    sigma = 0.02
    test = ref + rng.normal(0.0, sigma, size=ref.shape)  # no clipping at 0.5 +- 25 sigma
    assert metrics.psnr(test, ref) == pytest.approx(-20 * math.log10(sigma), abs=0.05)  # 33.98 dB


def test_identical_images(rng):
    x = rng.uniform(0, 1, size=(24, 24, 3))
    assert metrics.rmse(x, x) == 0.0
    assert metrics.psnr(x, x) == math.inf
    assert metrics.ssim(x, x) == pytest.approx(1.0)
    assert metrics.flip(x, x) == pytest.approx(0.0, abs=1e-6)


def test_ssim_and_flip_fall_with_noise(rng):
    ref = np.clip(np.linspace(0, 1, 64)[None, :, None] * np.ones((64, 64, 3)), 0, 1)
    small = ref + rng.normal(0, 0.02, ref.shape)
    large = ref + rng.normal(0, 0.2, ref.shape)
    assert 1.0 > metrics.ssim(small, ref) > metrics.ssim(large, ref)
    assert 0.0 < metrics.flip(small, ref) < metrics.flip(large, ref)
    # A constant offset of c in a flat image: SSIM's luminance term (2 m1 m2 + C1) / (m1^2 + m2^2 + C1).
    flat = np.full((32, 32, 3), 0.4)
    c1 = (0.01 * 1.0) ** 2
    expected = (2 * 0.4 * 0.5 + c1) / (0.4**2 + 0.5**2 + c1)
    assert metrics.ssim(flat + 0.1, flat) == pytest.approx(expected, rel=1e-6)


def test_metrics_clip_to_the_unit_range_and_check_shapes():
    a = np.full((8, 8, 3), 2.0)
    b = np.ones((8, 8, 3))
    assert metrics.rmse(a, b) == 0.0  # both clip to 1
    with pytest.raises(ValueError, match="shapes differ"):
        metrics.rmse(np.zeros((8, 8, 3)), np.zeros((8, 9, 3)))


def test_reference_is_cached_and_points_get_metric_columns(tmp_path, monkeypatch):
    monkeypatch.setenv("RAST5D_RESULTS", str(tmp_path))
    from experiments import config as xc
    from experiments import run as runner

    p = tmp_path / "m.yaml"
    p.write_text("scene: {name: quad}\ncamera: {width: 24, height: 24, coc_px: 6}\nsamples: {spp: 4, seed: 1}\n"
                 "pipeline: {algorithm: tile}\noutputs: {metrics: {reference_spp: 64}}\n"
                 "sweep: {samples.spp: [1, 64]}\n")
    df = runner.run_sweep(xc.load_config(p), workers=0, progress=False)
    assert (df["status"] == "ok").all()
    refs = list((tmp_path / "references").glob("*.npy"))
    assert len(refs) == 1  # one reference for both points
    assert df["metric.rmse"].iloc[0] > df["metric.rmse"].iloc[1] > 0  # different seeds: not identical
    # The reference is the same scene at reference_spp: recompute the 1-spp error independently.
    ref = np.load(refs[0])
    c1 = xc.expand_sweep(xc.load_config(p))[0][1]
    _, result = runner.render_point(c1.model_copy(update={"outputs": xc.OutputsSpec()}))
    img = np.clip(result.image.astype(np.float64), 0, 1)
    assert df["metric.rmse"].iloc[0] == pytest.approx(np.sqrt(np.mean((img - np.clip(ref, 0, 1)) ** 2)))
