"""The hardware page's pipeline (experiments/report/hardware.py) shrunk: the equal-error interpolation against
closed forms, and one tiny scene rendered by every family (points by three methods, accumulation buffering)
whose equal-error figures are checked against an independent interpolation of its rows, and whose verdict is
rewritten when its numbers change."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

from experiments.report import hardware as hw


def test_n_at_error_is_exact_on_a_power_law():
    # e = c n^-b: log-log interpolation between any two grid points is exact, so the n of e(16) is 16.
    c, b = 0.3, 0.5
    ns = [4, 8, 32, 64]
    errs = [c * n ** -b for n in ns]
    for target_n in (5.0, 16.0, 50.0):
        assert hw.n_at_error(ns, errs, c * target_n ** -b) == pytest.approx(target_n, rel=1e-12)
    assert math.isnan(hw.n_at_error(ns, errs, c * 128 ** -b))  # beneath the curve's floor: not reached
    assert hw.fit_halfwidth(ns, errs, 16.0) == pytest.approx(0.0, abs=1e-9)  # no residual, no interval


def test_fit_halfwidth_matches_the_inverse_prediction_formula():
    ns = np.array([4.0, 8.0, 16.0, 32.0, 64.0])
    errs = 0.3 * ns ** -0.5 * np.array([1.05, 0.97, 1.02, 0.96, 1.03])
    x, y = np.log(ns), np.log(errs)
    # Closed form of the least-squares slope, intercept and residual scale (no polyfit).
    xm, ym = x.mean(), y.mean()
    slope = np.sum((x - xm) * (y - ym)) / np.sum((x - xm) ** 2)
    s = math.sqrt(np.sum((y - (ym + slope * (x - xm))) ** 2) / 3)
    n_star = 20.0
    expected = 3.182 * s / abs(slope) * math.sqrt(1 / 5 + (math.log(n_star) - xm) ** 2 / np.sum((x - xm) ** 2))
    assert hw.fit_halfwidth(ns, errs, n_star) == pytest.approx(expected, rel=1e-9)


@pytest.fixture(scope="module")
def tiny_rows(tmp_path_factory):
    """One scene (the teapot, 24 x 24, CoC 6): bruteforce, tile and a GPU method at 4-32 spp, accumulation
    buffering at 4-64 passes, every point against one 256-spp reference."""
    import os

    from experiments import config as xc
    from experiments import run as runner

    tmp = tmp_path_factory.mktemp("hardware")
    old = os.environ.get("RAST5D_RESULTS")
    os.environ["RAST5D_RESULTS"] = str(tmp)
    try:
        algs = ["bruteforce"] * 4 + ["tile"] * 4 + ["gpu_hexagon2d"] * 4 + ["accumulation"] * 5
        kinds = ["stratified"] * 12 + ["accumulation"] * 5
        spp = [4, 8, 16, 32] * 3 + [4, 8, 16, 32, 64]
        p = tmp / "hardware_tiny.yaml"
        p.write_text(
            "scene: {name: teapot, params: {width: 24, height: 24}}\n"
            "camera: {width: 24, height: 24, coc_px: 6, focus_distance: 6.0}\n"
            "samples: {kind: stratified, spp: 16, seed: 1}\n"
            "pipeline: {algorithm: tile, threads: 1, count_optimal: false, shading: msaa}\n"
            "outputs: {metrics: {reference_spp: 256, reference_kind: stratified, reference_algorithm: bruteforce}}\n"
            f"sweep: {{samples.kind: {kinds}, samples.spp: {spp}, pipeline.algorithm: {algs},\n"
            "        zip: [[samples.kind, samples.spp, pipeline.algorithm]]}\n")
        df = runner.run_sweep(xc.load_config(p), workers=0, progress=False)
    finally:
        if old is None:
            os.environ.pop("RAST5D_RESULTS", None)
        else:
            os.environ["RAST5D_RESULTS"] = old
    return [r for _, r in df.iterrows()]


def _loglog(xs, ys, x):
    """Independent log-log interpolation (numpy.interp in log space)."""
    order = np.argsort(xs)
    return float(np.exp(np.interp(np.log(x), np.log(np.asarray(xs, float)[order]), np.log(np.asarray(ys, float)[order]))))


def test_equal_error_rows_of_a_tiny_scene(tiny_rows):
    rows = tiny_rows
    scene = hw.scene_label(rows[0])
    eq = {(r["metric"], r["method"]): r for r in hw.equal_error_rows(rows, hw.FullCosts(rows), [scene])}
    assert {m for _, m in eq} == {"bruteforce", "tile", "gpu_hexagon2d", "accumulation"}
    points = [r for r in rows if hw.kind(r) == "points"]
    # Every exact point method renders the same image: one error per spp.
    for n in (4, 8, 16, 32):
        assert len({round(float(r["metric.rmse"]), 12) for r in points if hw.n_of(r) == n}) == 1
    target = next(float(r["metric.rmse"]) for r in points if hw.n_of(r) == hw.TARGET_SPP)
    for m in ("bruteforce", "tile", "gpu_hexagon2d"):
        own = next(r for r in points if r["pipeline.algorithm"] == m and hw.n_of(r) == hw.TARGET_SPP)
        assert eq["rmse", m]["n"] == hw.TARGET_SPP
        assert eq["rmse", m]["cycles"] == pytest.approx(float(own["timing.cycles"]), rel=1e-12)
    # Accumulation: the n at which its RMSE curve crosses the target, found independently (the bracketing pair
    # by scanning, then the log-log line through it), and its cycles there.
    acc = sorted((hw.n_of(r), float(r["metric.rmse"]), float(r["timing.cycles"])) for r in rows if hw.kind(r) == "accumulation")
    row = eq["rmse", "accumulation"]
    crossing = [(a, b) for a, b in zip(acc, acc[1:]) if min(a[1], b[1]) <= target <= max(a[1], b[1])]
    assert crossing, "accumulation's curve must cross the target within its passes on this scene"
    (n0, e0, c0), (n1, e1, c1) = crossing[0]
    n_star = _loglog([e0, e1], [n0, n1], target)
    assert row["n"] == pytest.approx(n_star, rel=1e-9)
    assert row["cycles"] == pytest.approx(_loglog([n0, n1], [c0, c1], n_star), rel=1e-9)
    assert row["n_lo"] <= row["n"] <= row["n_hi"]


def test_verdict_rewrites_with_the_numbers(tiny_rows, monkeypatch):
    rows = tiny_rows
    scene = hw.scene_label(rows[0])
    base = hw.equal_error_rows(rows, hw.FullCosts(rows), [scene])
    monkeypatch.setattr(hw, "all_equal_error", lambda: [dict(r) for r in base])
    first = "\n".join(hw.hardware_verdict(None, None))
    ratio = float(re.search(r"`gpu_hexagon2d`\) needs ([\d.]+)× more cycles", first).group(1))
    cheapest = re.search(r"Fewest cycles overall: `([^`]+)`", first).group(1)
    assert cheapest in ("bruteforce", "tile")
    # The GPU method made a hundred times faster: the verdict names it, in other words.
    faster = [dict(r, cycles=r["cycles"] / (100 * ratio)) if r["method"] == "gpu_hexagon2d" else dict(r) for r in base]
    monkeypatch.setattr(hw, "all_equal_error", lambda: faster)
    second = "\n".join(hw.hardware_verdict(None, None))
    assert second != first
    assert re.search(r"Fewest cycles overall: `gpu_hexagon2d` \(GPU\)", second)
    assert "× fewer cycles" in second
