"""The methods page's helpers (experiments/report/tables.py): the α fit with its confidence interval
against a known power law, and the equal-error interpolation."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from experiments.report import tables


def test_alpha_fit_recovers_a_power_law(rng):
    x = np.array([1e6, 4e6, 1.6e7, 6.4e7, 2.56e8])
    y = 3.0 * x ** -0.5 * np.exp(rng.normal(0, 0.02, x.size))
    a, hw, n = tables._fit_alpha(x, y)
    assert n == 5 and abs(a - 0.5) < 0.05 and 0 < hw < 0.1 and a - hw < 0.5 < a + hw
    exact, hw0, _ = tables._fit_alpha(x, 3.0 * x ** -0.75)
    assert abs(exact - 0.75) < 1e-9 and hw0 < 1e-6


def test_equal_error_interpolation():
    g = pd.DataFrame({"ops.total": [1e6, 1e7, 1e8], "ops.interp": [0, 0, 0], "ops.segments": [0, 0, 0],
                      "metric.rmse": [0.1, 0.01, 0.001]})
    assert math.isclose(tables._interp_work(g, 0.01), 1e7, rel_tol=1e-9)
    assert math.isclose(tables._interp_work(g, 10 ** -1.5), 10 ** 6.5, rel_tol=1e-9)


def test_pareto_front():
    pts = [(1.0, 0.5, "a"), (2.0, 0.6, "b"), (2.0, 0.3, "c"), (4.0, 0.3, "d"), (8.0, 0.1, "e")]
    assert [lab for _c, _e, lab in tables._pareto(pts)] == ["a", "c", "e"]


def test_equal_error_cost_follows_the_work_order():
    """Wall time (or cycles) at equal error: interpolated between the same bracketing points."""
    g = pd.DataFrame({"ops.total": [1e6, 1e7, 1e8], "ops.interp": [0, 0, 0], "ops.segments": [0, 0, 0],
                      "metric.rmse": [0.1, 0.01, 0.001], "time.wall_s": [0.1, 1.0, 10.0]})
    assert math.isclose(tables._interp_work(g, 10 ** -1.5, tables._wall), 10 ** -0.5, rel_tol=1e-9)


def test_alpha_before_the_interleaved_floor():
    """An interleaved family gets a second fit over spp <= its lens positions (before the discrete-lens
    floor); the full fit is flattened by the floor, the restricted one recovers the power law."""
    spp = np.array([4, 16, 32, 64, 128, 256, 512, 1024], float)
    ops = 1e6 * spp
    rmse = np.maximum(0.2 * spp ** -0.5, 0.02)  # floor from 100 spp on
    g = pd.DataFrame({"samples.spp": spp, "samples.n_lens": 64.0, "ops.total": ops, "ops.interp": 0.0,
                      "ops.segments": 0.0, "metric.rmse": rmse})
    pre, n = tables._before_lens_floor(g)
    assert n == 64 and list(pre["samples.spp"]) == [4, 16, 32, 64]
    a_pre, _hw, _n = tables._fit_alpha(pre["ops.total"], pre["metric.rmse"])
    a_all, _hw, _n = tables._fit_alpha(g["ops.total"], g["metric.rmse"])
    assert abs(a_pre - 0.5) < 1e-9 and a_all < 0.4
    assert tables._before_lens_floor(g.assign(**{"samples.n_lens": np.nan})) is None
