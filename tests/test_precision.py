"""Fixed-point instantiations of the render's 2D tile test and sample test (core/fixed.h,
sim._core.precision_probe_2d; pipeline.precision) at the precisions reports/paper/precision.md calls safe: every tile test
conservative and every sample decision equal to float64 except within DELTA of an edge, on full-size
screens with vertices far off screen, near the near plane and behind the camera (clipped to the near plane
and the guard band first, as the study does). The float64 reference is independent numpy code."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sim
from experiments.run import precision as P

HYPO = dict(deadline=None, derandomize=True, database=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])

# (viewport, frac_bits) the test runs; int_bits: the closed-form format reports/paper/precision.md calls safe
# for triangles clipped to the guard band (the precision page: configs/paper/precision_2d.yaml)
SAFE = {(512, 4), (2048, 8), (8192, 4)}


def _safe_bits(V, F):
    return P.guard_band_int_bits(V)


def _clipped_screen_tris(P0, V, near=0.1):
    """Homogeneous (X, Y, W) triangle -> screen triangles after near-plane and guard-band clipping."""
    G = V
    poly = P.clip_polygon(np.asarray(P0, np.float64), [
        lambda p: p[2] - near, lambda p: p[0] + G * p[2], lambda p: (V + G) * p[2] - p[0],
        lambda p: p[1] + G * p[2], lambda p: (V + G) * p[2] - p[1]])
    if len(poly) < 3:
        return []
    xy = poly[:, :2] / poly[:, 2:3]
    return [np.array([xy[0], xy[k], xy[k + 1]]) for k in range(1, len(xy) - 1)]


coord = st.floats(-4.0, 5.0)  # in viewports: far off screen on both sides
depth = st.one_of(st.floats(-2.0, -0.01), st.floats(0.05, 0.2), st.floats(0.2, 50.0))  # behind, near, in front


@pytest.mark.parametrize("V,F", sorted(SAFE))
@settings(max_examples=40, **HYPO)
@given(pts=st.lists(st.tuples(coord, coord, depth), min_size=3, max_size=3), seed=st.integers(0, 2**16))
def test_fixed_point_tests_are_conservative_at_the_safe_precision(V, F, pts, seed):
    I = _safe_bits(V, F)
    Ph = np.array([[x * V * w, y * V * w, w] for x, y, w in pts])  # pixel-homogeneous: X = x_px W
    rng = np.random.default_rng(seed)
    for tri in _clipped_screen_tris(Ph, V):
        if 0.5 * abs(P.cross2(tri[1] - tri[0], tri[2] - tri[0])) < 1e-3:
            continue
        pts_q, tiles = P.queries(tri, V, F, rng)
        r = sim._core.precision_probe_2d(tri, pts_q, tiles, I, F)
        assert not np.asarray(r["overflow_sample"]).any() and not np.asarray(r["overflow_tile"]).any()
        inside, dist, _ = P.reference(tri, pts_q, tiles)
        d = P.delta(F)
        _, _, outside_shrunk = P.reference(tri, pts_q[:0], tiles, inset=d)
        culled = np.asarray(r["tile_outside"])
        assert not (culled & ~outside_shrunk).any(), "fixed-point tile test culled a tile the triangle overlaps"
        off = (np.asarray(r["inside"]) != inside) & (dist > d)
        assert not off.any(), f"sample decisions differ {dist[off].max()} px from an edge"


def test_too_few_bits_is_detected():
    """The probe can fail: 8 integer bits cannot hold an 8192 px viewport's edge set-up."""
    tri = np.array([[10.0, 20.0], [8000.0, 300.0], [4000.0, 8100.0]])
    r = sim._core.precision_probe_2d(tri, np.array([[4000.0, 3000.0]]), np.array([[4000.0, 4008.0, 3000.0, 3008.0]]),
                                     8, 4)
    assert np.asarray(r["overflow_sample"]).all()
    r = sim._core.precision_probe_2d(tri, np.array([[4000.0, 3000.0]]), np.array([[4000.0, 4008.0, 3000.0, 3008.0]]),
                                     40, 4)
    assert not np.asarray(r["overflow_sample"]).any() and r["inside"][0] and not r["tile_outside"][0]
