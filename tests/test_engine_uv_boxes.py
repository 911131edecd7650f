"""The h_i lines leave at most 2 active intervals per lens axis, so at most 4 uv-boxes per tile
(tiletest/halfspace_lens.h, docs/tile_tests.md): a brute-force scan of the lens axis over random
focus-crossing triangles, and the engine's tile.uv_boxes on one-tile images."""
from __future__ import annotations

import numpy as np
import pytest

from sim import _core

pytestmark = pytest.mark.invariants

FOCUS = 1.0
U = np.linspace(-1.0, 1.0, 4001)  # dense lens axis


def active_runs(a: np.ndarray, b: np.ndarray, x0: float, x1: float) -> int:
    """Maximal runs of u in [-1, 1] from which the projected vertices a_j + u b_j are neither all
    left of [x0, x1] nor all right of it (the h_i active set of one axis), by brute force."""
    x = a[:, None] + U[None, :] * b[:, None]
    active = ~(np.all(x < x0, axis=0) | np.all(x > x1, axis=0))
    return int(active[0]) + int(np.count_nonzero(active[1:] & ~active[:-1]))


def random_crossing_axis(rng: np.random.Generator, n: int):
    """n footprint vertices, some in front of the focus plane and some behind: screen positions
    a = X / W and slopes b = K (1 - F / W) for a random CoC K (either sign)."""
    w = np.concatenate([rng.uniform(0.2, 0.95, 1), rng.uniform(1.05, 6.0, 1), rng.uniform(0.2, 6.0, n - 2)])
    a = rng.uniform(-40.0, 40.0, n)
    k = rng.choice([-1.0, 1.0]) * rng.uniform(1.0, 60.0)
    return a, k * (1.0 - FOCUS / w)


@pytest.mark.parametrize("n", [3, 4, 6])  # triangle, near-clipped quad, moving sub-interval ends
def test_brute_force_at_most_two_intervals_per_axis(n):
    rng = np.random.default_rng(20 + n)
    most = 0
    for _ in range(3000):
        a, b = random_crossing_axis(rng, n)
        x0 = rng.uniform(-20.0, 20.0)
        runs = active_runs(a, b, x0, x0 + rng.choice([1.0, 2.0, 4.0, 8.0]))
        assert runs <= 2, (a, b, x0)
        most = max(most, runs)
    assert most == 2  # the bound is reached: a crossing triangle can leave two intervals


def one_tile_uv_boxes(v0: np.ndarray, coc: float, lens: str) -> tuple[int, int]:
    """(tile.uv_boxes, tiles that reached the uv-box stage) of one static triangle on an 8 x 8
    image covered by a single 8 x 8 tile (h_i lines only)."""
    p = _core.RenderParams()
    p.width = p.height = 8
    p.coc_x_px, p.coc_y_px = coc, -coc
    p.focus_w, p.near_w = FOCUS, 0.05
    p.lens_shape = lens
    p.algorithm, p.tile_size, p.lens_grid = "tile", 8, 4
    p.halfspace_h, p.halfspace_H = True, False
    p.table_has_lens, p.table_has_time = True, False
    p.threads = 1
    rng = np.random.default_rng(0)
    samples = np.zeros((1, 1, 16, 5), np.float32)
    samples[..., :2] = rng.random((1, 1, 16, 2))
    samples[..., 2:4] = rng.uniform(-1.0, 1.0, (1, 1, 16, 2))
    colors = np.ones((1, 3, 3), np.float32)
    out = _core.render(p, v0, v0, colors, samples, np.zeros((0,), np.int32), np.zeros((0, 2), np.float32))
    c = out["counters"]
    reached = c["tile.visited"] - c["tile.culled_h"] - c["interval.culled_clip"]
    return c["tile.uv_boxes"], reached


@pytest.mark.parametrize("lens", ["square", "disk"])
def test_engine_tile_has_at_most_four_uv_boxes(lens):
    rng = np.random.default_rng(7)
    most = 0
    for _ in range(400):
        w = np.concatenate([rng.uniform(0.3, 0.95, 1), rng.uniform(1.05, 5.0, 1), rng.uniform(0.3, 5.0, 1)])
        rng.shuffle(w)
        xy = rng.uniform(-12.0, 20.0, (3, 2))
        v0 = np.stack([xy[:, 0] * w, xy[:, 1] * w, w], axis=1)[None].astype(np.float32)
        boxes, reached = one_tile_uv_boxes(v0, float(rng.uniform(2.0, 30.0)), lens)
        assert reached <= 1
        assert boxes <= 4 * reached, (v0, boxes)
        most = max(most, boxes)
    assert most == 4  # two intervals on both axes occur
