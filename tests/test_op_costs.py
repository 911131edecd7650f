"""Invariant 4, honest counts per kernel: the documented op cost of every kernel equals what the counting scalar type tallies, and renders charge exactly the documented per-class sample-test costs."""
from __future__ import annotations

import functools

import numpy as np
import pytest

import sim
from tests import reference
from tests.reference import Tris

pytestmark = pytest.mark.invariants

TRIALS = 300
CLASSES = ("2d", "3d", "4d", "5d")


@functools.lru_cache(maxsize=None)
def kernel_costs(seed=1):
    return sim._core.measure_kernel_costs(TRIALS, seed)


KERNELS = sorted(kernel_costs())


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("kernel", KERNELS)
def test_documented_cost_equals_counted(kernel, seed):
    """Over 300 random inputs the counting type tallies exactly the documented cost, every time."""
    documented, lo, hi = kernel_costs(seed)[kernel]
    assert documented == lo == hi, f"{kernel}: documented {documented}, counted min {lo} max {hi}"
    assert documented > 0


def test_every_sample_class_kernel_is_measured():
    names = set(KERNELS)
    assert {f"sample.inside_{c}" for c in CLASSES} <= names
    assert {"sample.edges", "sample.signs", "sample.shear", "sample.lerp", "sample.shear_moving",
            "interp.depth", "interp.depth_test", "interp.color"} <= names


@functools.lru_cache(maxsize=None)
def tile_kernel_costs(seed=1):
    """{kernel: (runs, mismatches, min documented, max documented)}: tile-test kernels whose cost
    depends on the configuration, each run compared with its own documented cost."""
    return sim._core.measure_tile_kernel_costs(TRIALS, seed)


TILE_KERNELS = sorted(tile_kernel_costs())


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("kernel", TILE_KERNELS)
def test_tile_kernel_documented_cost_equals_counted(kernel, seed):
    runs, mismatches, lo, hi = tile_kernel_costs(seed)[kernel]
    assert runs == TRIALS and mismatches == 0, f"{kernel}: {mismatches} of {runs} runs counted != documented"
    assert 0 <= lo <= hi


def test_every_tile_test_kernel_is_measured():
    assert {"tile.lens_vertex", "tile.axis_gaps", "tile.axis_set", "tile.axis_pass", "tile.axis_cells",
            "tile.box_overlaps_lens", "tile.edge_setup", "tile.tangent_corners", "tile.line_at_corner",
            "tile.line_cells", "tile.edges_2d", "tile.tile_outside_2d", "tile.box_bounds",
            "tile.lens_orientation"} <= set(TILE_KERNELS)
    # the two cases of the per-vertex and per-edge setup are both drawn (in focus / parallel)
    assert tile_kernel_costs()["tile.lens_vertex"][2:] == (6, 10)
    assert tile_kernel_costs()["tile.edge_setup"][2:] == (17, 25)


def doc(name):
    return kernel_costs()[name][0]


def test_inside_costs_are_strictly_ordered_2d_4d_3d_5d():
    """Cheapest exact kernel per class: 2D < 4D (lens shear) < 3D (time lerp) < 5D (both)."""
    cost = {c: doc(f"sample.inside_{c}") for c in CLASSES}
    print("per-class inside-test costs (ops):", cost)
    assert cost["2d"] < cost["4d"] < cost["3d"] < cost["5d"], cost


def test_inside_costs_compose_from_their_parts():
    edges_signs = doc("sample.edges") + doc("sample.signs")
    assert doc("sample.inside_2d") == edges_signs
    assert doc("sample.inside_3d") == doc("sample.lerp") + edges_signs
    assert doc("sample.inside_4d") == doc("sample.shear") + edges_signs
    assert doc("sample.inside_5d") == doc("sample.lerp") + doc("sample.shear_moving") + edges_signs


# ---------------------------------------------------------------------------------- renders


W, H, F = 40, 32, 4.0


world_from_pixel = functools.partial(reference.world_from_pixel, width=W, height=H)


def single_class_scene(cls):
    """Three overlapping triangles; moving for 3D/5D (the camera's CoC decides 2D/3D vs 4D/5D)."""
    p0 = np.array([
        [world_from_pixel(2.3, 3.1, 3.1), world_from_pixel(36.7, 5.2, 4.7), world_from_pixel(14.9, 29.4, 6.3)],
        [world_from_pixel(30.1, 2.2, 2.6), world_from_pixel(38.4, 27.7, 3.3), world_from_pixel(5.7, 20.8, 2.9)],
        [world_from_pixel(10.2, 12.6, 7.5), world_from_pixel(26.9, 14.1, 5.5), world_from_pixel(18.3, 25.5, 4.4)],
    ])
    p1 = p0 + np.array([0.21, -0.13, 0.37]) if cls in ("3d", "5d") else p0.copy()
    return Tris(p0, p1, np.full(p0.shape, 0.5))


@functools.lru_cache(maxsize=None)
def tables():
    return {"stratified": sim.SampleTable.stratified(spp=16, seed=3),
            "interleaved": sim.SampleTable.interleaved(spp=16, n_lens=64, seed=3)}


INTERLEAVED = {name for name, _desc, needs in sim._core.algorithms() if needs}


@pytest.mark.parametrize("op_count", ["documented", "exact"])
@pytest.mark.parametrize("cls", CLASSES)
@pytest.mark.parametrize("algorithm", sim.algorithm_names("points"))
def test_render_charges_the_documented_class_cost(algorithm, cls, op_count):
    """A single-class scene: every sample test uses that class's kernel (interleaved algorithms: the 2D
    kernel on pre-sheared static triangles), and ops.sample_inside / tests == its documented cost."""
    coc = 10.0 if cls in ("4d", "5d") else 0.0
    cam = sim.Camera(width=W, height=H, fov_y_deg=45, focus_distance=F, coc_px=coc)
    table = tables()["interleaved" if algorithm in INTERLEAVED else "stratified"]
    res = sim.render(single_class_scene(cls), cam, table,
                     sim.PipelineConfig(algorithm=algorithm, threads=2, op_count=op_count))
    st = res.flat_stats
    assert st[f"setup.class_{cls}"] == 3 and st["setup.triangles"] == 3
    assert st["raster.tie_breaks"] == 0  # otherwise ties add cost::kTieBreak per zero edge
    kernel = "2d" if (algorithm in ("interleave", "hinterleave", "tile_interleaved", "accumulation")
                      and cls == "4d") else cls
    tested = st[f"raster.samples_tested_{kernel}"]
    assert tested == st["raster.samples_tested"] > 0
    assert st["ops.sample_inside"] / tested == doc(f"sample.inside_{kernel}")
    assert st["ops.sample_inside"] == tested * doc(f"sample.inside_{kernel}")
    # covered samples: depth (+ near check), then the depth test per hit, then colour per pass
    assert st["ops.interp"] == (st["raster.samples_covered"] * doc("interp.depth")
                                + st["raster.samples_hit"] * doc("interp.depth_test")
                                + st["depth.passes"] * doc("interp.color"))
