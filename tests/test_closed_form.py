"""Converged images of white fronto-parallel squares on black (so the image is coverage) against closed-form coverage: defocus (disk, square, hexagon apertures, in front of and behind the focus plane), motion (full and partial shutter), both at once, and sharp focus, within Monte Carlo error.

Expected pixel value (tests/reference/closed_form.py rect_coverage): the square's indicator convolved with the
aperture scaled to the CoC radius K |1 - F / depth| px and/or with the motion box, averaged over
the pixel's area (each sample has its own (x, y) in the pixel). Tolerance per pixel:
|image - expected| <= 5 sigma + 1/spp with sigma = sqrt(p (1 - p) / spp), the binomial error of spp
independent samples; stratified and Sobol tables have less variance than that, so this is
conservative; the extra 1/spp covers the Poisson tail of pixels with p ~ 0 (one stray sample).
The RMS of the z-scores must be <= 1.25 (E[z^2] = 1 for independent samples and less for
stratified ones, whose variance never exceeds that of independent sampling), so a systematic error
smaller than 5 sigma per pixel still fails. Each test also checks that
the image does *not* fit a wrong profile (the test's power).
"""
from __future__ import annotations

import numpy as np
import pytest

import sim
from tests import reference as ref

pytestmark = pytest.mark.invariants

W = H = 40
RECT = (12.3, 27.6, 10.7, 29.2)  # pixel rectangle seen by the pinhole at the square's depth
K_SIGMA = 5.0
RMS_Z_MAX = 1.25  # E[z^2] <= 1 (= 1 for independent samples); measured 0.42-0.61 stratified/Sobol, 0.93 random


def render_coverage(cam, scene, table):
    res = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce", threads=2))
    img = res.image.astype(np.float64)
    assert np.array_equal(img[..., 0], img[..., 1]) and np.array_equal(img[..., 0], img[..., 2])
    return img[..., 0]


def deviation(img, expected, spp):
    """Per-pixel check facts (Ramulator-style expected / measured / deviation)."""
    sigma = np.sqrt(np.clip(expected * (1.0 - expected), 0.0, None) / spp)
    dev = img - expected
    tol = K_SIGMA * sigma + 1.0 / spp
    z = dev[sigma > 0] / sigma[sigma > 0]
    return {
        "max_abs_dev": float(np.abs(dev).max()),
        "max_z": float(np.abs(z).max()),
        "rms_z": float(np.sqrt(np.mean(z * z))),
        "mean_dev": float(dev.mean()),
        "sum_expected": float(expected.sum()),
        "sum_measured": float(img.sum()),
        "bad_pixels": int((np.abs(dev) > tol).sum()),
        "worst_pixel": tuple(int(i) for i in np.unravel_index(np.argmax(np.abs(dev) - tol), dev.shape)),
    }


def check(request, label, img, expected, spp, wrong=None):
    d = deviation(img, expected, spp)
    for k, v in d.items():
        request.node.user_properties.append((k, v))
    print(f"\n{label}: " + ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in d.items()))
    y, x = d["worst_pixel"]
    assert d["bad_pixels"] == 0, f"{label}: pixel (x={x}, y={y}) measured {img[y, x]:.5f}, expected {expected[y, x]:.5f}; {d}"
    assert d["rms_z"] <= RMS_Z_MAX, f"{label}: RMS z-score {d['rms_z']:.3f} (systematic error?) {d}"
    if wrong is not None:  # power: a wrong profile must be rejected
        dw = deviation(img, wrong, spp)
        assert dw["bad_pixels"] > 0 or dw["rms_z"] > RMS_Z_MAX, f"{label}: the test cannot tell the wrong profile apart"


LENSES = ["disk", "square", "hexagon"]
WRONG_LENS = {"disk": "square", "square": "disk", "hexagon": "square"}


@pytest.mark.parametrize("depth", [2.5, 12.0], ids=["in_front_of_focus", "behind_focus"])
@pytest.mark.parametrize("lens", LENSES)
def test_defocused_square(lens, depth, request):
    cam = sim.Camera(width=W, height=H, fov_y_deg=45, focus_distance=5.0, coc_px=6.0, lens=lens, near=0.05)
    spp = 256
    table = sim.SampleTable.stratified(spp=spp, seed=11)
    img = render_coverage(cam, ref.fronto_square(cam, RECT, depth), table)
    radius = 6.0 * abs(1.0 - 5.0 / depth)  # K |1 - F / depth|: 6 px in front, 3.5 px behind
    expected = ref.rect_coverage(W, H, RECT, radius, lens)
    wrong = ref.rect_coverage(W, H, RECT, radius * 1.25, lens)  # a 25% error in the CoC radius
    check(request, f"defocus {lens} depth={depth}", img, expected, spp, wrong)
    if lens != "hexagon":  # the shape matters: the other aperture's profile is rejected
        other = ref.rect_coverage(W, H, RECT, radius, WRONG_LENS[lens])
        dw = deviation(img, other, spp)
        assert dw["bad_pixels"] > 0 or dw["rms_z"] > RMS_Z_MAX


def test_defocused_square_random_table(request):
    """Independent uniform samples: the binomial error model is exact, so the RMS z is ~1."""
    cam = sim.Camera(width=W, height=H, fov_y_deg=45, focus_distance=5.0, coc_px=6.0, lens="disk", near=0.05)
    spp = 1024
    table = sim.SampleTable.random(spp=spp, seed=12)
    img = render_coverage(cam, ref.fronto_square(cam, RECT, 3.0), table)
    expected = ref.rect_coverage(W, H, RECT, 6.0 * abs(1.0 - 5.0 / 3.0), "disk")
    check(request, "defocus disk, random table", img, expected, spp)
    z = deviation(img, expected, spp)["rms_z"]
    assert 0.7 <= z <= 1.3


def test_sobol_table_converges(request):
    cam = sim.Camera(width=W, height=H, fov_y_deg=45, focus_distance=5.0, coc_px=10.0, lens="hexagon", near=0.05)
    spp = 256
    table = sim.SampleTable.sobol(spp=spp, seed=13)
    img = render_coverage(cam, ref.fronto_square(cam, RECT, 20.0), table)
    expected = ref.rect_coverage(W, H, RECT, 10.0 * (1.0 - 5.0 / 20.0), "hexagon")
    check(request, "defocus hexagon, sobol", img, expected, spp, ref.rect_coverage(W, H, RECT, 7.5, "square"))


def test_in_focus_square_is_sharp(request):
    """At the focus plane the blur vanishes whatever the lens: plain box-filtered area coverage."""
    cam = sim.Camera(width=W, height=H, fov_y_deg=45, focus_distance=5.0, coc_px=30.0, lens="disk", near=0.05)
    spp = 256
    table = sim.SampleTable.stratified(spp=spp, seed=14)
    img = render_coverage(cam, ref.fronto_square(cam, RECT, 5.0), table)
    expected = ref.rect_coverage(W, H, RECT)
    check(request, "in focus", img, expected, spp, ref.rect_coverage(W, H, RECT, 1.0, "disk"))
    # Pixels wholly inside (outside) the square have every (no) sample covered, blur or not.
    res = sim.render(ref.fronto_square(cam, RECT, 5.0), cam, table, export_samples=True)
    inside = expected == 1.0
    assert inside.sum() > 100 and np.all(res.sample_triangle[inside] >= 0)
    assert np.all(res.sample_triangle[expected == 0.0] < 0)
    assert res.flat_stats["setup.class_2d"] == 2  # W == F exactly: the 2D kernel


@pytest.mark.parametrize("shutter", [(0.0, 1.0), (0.25, 0.75)], ids=["full_shutter", "half_shutter"])
@pytest.mark.parametrize("motion_px", [11.5, -7.25])
def test_moving_square(motion_px, shutter, request):
    """A square moving sideways by motion_px during [0, 1]: the shutter [open, close] sees it from
    x0 + open m to x0 + close m, a box blur of (close - open) m."""
    cam = sim.Camera(width=W, height=H, fov_y_deg=45, focus_distance=5.0, coc_px=0.0, near=0.05, shutter=shutter)
    spp = 256
    table = sim.SampleTable.stratified(spp=spp, seed=15)
    img = render_coverage(cam, ref.fronto_square(cam, RECT, 7.0, motion_px=motion_px), table)
    s0, s1 = shutter
    rect = (RECT[0] + s0 * motion_px, RECT[1] + s0 * motion_px, RECT[2], RECT[3])
    expected = ref.rect_coverage(W, H, rect, motion_x=(s1 - s0) * motion_px)
    wrong = ref.rect_coverage(W, H, RECT, motion_x=motion_px) if shutter != (0.0, 1.0) else \
        ref.rect_coverage(W, H, RECT, motion_x=0.85 * motion_px)
    check(request, f"motion {motion_px} px shutter {shutter}", img, expected, spp, wrong)


def test_moving_defocused_square(request):
    """5D: defocus (disk, 4 px) and motion (-9 px) at once; the profile is their joint convolution."""
    cam = sim.Camera(width=W, height=H, fov_y_deg=45, focus_distance=5.0, coc_px=8.0, lens="disk", near=0.05)
    spp = 256
    table = sim.SampleTable.stratified(spp=spp, seed=16)
    img = render_coverage(cam, ref.fronto_square(cam, RECT, 10.0, motion_px=-9.0), table)
    expected = ref.rect_coverage(W, H, RECT, 4.0, "disk", motion_x=-9.0, n_lens=1024, n_time=128)
    wrong = ref.rect_coverage(W, H, RECT, 0.0, motion_x=-9.0)
    check(request, "motion + defocus", img, expected, spp, wrong)
