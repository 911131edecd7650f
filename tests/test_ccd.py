"""Continuous collision detection example (experiments/examples/ccd.py, [Nilsson 2012] §3): tests that know the answer."""
from __future__ import annotations

import numpy as np
import pytest

from experiments.examples import ccd

pytestmark = pytest.mark.invariants


def test_same_place_different_times_do_not_collide():
    a, b = ccd.example(same_time=False)
    res = ccd.overlap(a, b)
    assert not ccd.may_collide(a, b)
    assert res["xy"].tz_pixels == 0  # the view along z separates them in time
    assert ccd.may_collide_depth_only(a, b)  # depth-only (time ignored) cannot tell


def test_same_time_collides():
    a, b = ccd.example(same_time=True)
    assert ccd.may_collide(a, b)
    # independent check: the cubes really overlap at t = 0.5 (centres coincide)
    pa = a.positions + 0.5 * (a.positions_t1 - a.positions)
    pb = b.positions + 0.5 * (b.positions_t1 - b.positions)
    assert np.allclose(pa.reshape(-1, 3).mean(0), pb.reshape(-1, 3).mean(0))


def test_far_apart_never_collide():
    a = ccd.moving_cube((-1.0, 1.0, 0.0), (1.0, 1.0, 0.0), 0.2)
    b = ccd.moving_cube((-1.0, -1.0, 0.0), (1.0, -1.0, 0.0), 0.2)
    assert not ccd.may_collide(a, b)
