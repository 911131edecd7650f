"""Sample tables and lens maps: uniform marginals (chi-square), strata and (0,m,2)-nets, area-preserving lens shapes, interleaved lens positions, period, seeds, lens-grid buckets and input errors."""

import math

import numpy as np
import pytest
from scipy import stats

from sim.lens import LENS_SHAPES, inside_lens, lens_area, map_to_lens
from sim.sample_table import SampleTable

pytestmark = pytest.mark.invariants

P_MIN = 1e-4  # a correct sampler fails a chi-square test at this level once in 10^4 runs
GENERATORS = ["random", "stratified", "stratified_permuted", "sobol", "interleaved", "multiview"]
# Generators whose table is the same in every pixel by design (accumulation buffering: its own tests
# in tests/test_gpu.py); the per-pixel property tests below do not apply to them.
SAME_IN_EVERY_PIXEL = ["accumulation"]
EXTRA = {"interleaved": {"n_lens": 64}, "multiview": {"views": 2}}


def make(name, **params):
    return SampleTable.create(name, **{**EXTRA.get(name, {}), **params})


def f64(a):
    return np.asarray(a, dtype=np.float64)


def chi2_uniform_p(values, bins):
    counts, _ = np.histogram(values, bins=bins, range=(0.0, 1.0))
    assert counts.sum() == np.size(values), "values outside [0, 1)"
    return stats.chisquare(counts).pvalue


def per_pixel_is_permutation(ids, n):
    """ids (..., n): every row holds each of 0..n-1 exactly once."""
    return np.array_equal(np.sort(ids, axis=-1), np.broadcast_to(np.arange(n), ids.shape))


def test_registry_lists_every_generator_and_classmethods_match_create():
    assert SampleTable.generators() == GENERATORS + SAME_IN_EVERY_PIXEL
    for name in GENERATORS + SAME_IN_EVERY_PIXEL:
        via_method = getattr(SampleTable, name)(spp=4, seed=3, period=4, **EXTRA.get(name, {}))
        via_create = make(name, spp=4, seed=3, period=4)
        assert via_method.generator == name
        assert np.array_equal(via_method.samples(), via_create.samples())
    with pytest.raises(ValueError, match="generator: unknown .*'halton'"):
        SampleTable.create("halton", spp=4)


# ------------------------------------------------------------------ marginals


@pytest.mark.parametrize("name", GENERATORS)
def test_marginals_pass_chi_square(name):
    table = make(name, spp=16, period=16, seed=7)
    s = table.samples("square")
    for column, label in ((0, "x"), (1, "y"), (4, "t")):
        p = chi2_uniform_p(f64(s[..., column]), 32)
        assert p > P_MIN, f"{name}: {label} marginal rejected, p = {p:.3g}"
    # The canonical lens coordinates. An interleaved table uses only N = 64 positions, jittered
    # on an 8x8 grid, so its marginal is discrete: bin it by the 8 grid columns.
    lens_bins = 8 if name == "interleaved" else 32
    for column, label in ((2, "a"), (3, "b")):
        p = chi2_uniform_p(table.unit[..., column], lens_bins)
        assert p > P_MIN, f"{name}: canonical {label} marginal rejected, p = {p:.3g}"


def test_chi_square_rejects_a_biased_marginal():
    x = f64(SampleTable.random(spp=16, period=16, seed=7).samples()[..., 0])
    assert chi2_uniform_p(x, 32) > P_MIN
    assert chi2_uniform_p(x**2, 32) < 1e-12


# ------------------------------------------------------------------ stratification


@pytest.mark.parametrize("spp, nx, ny", [(1, 1, 1), (7, 7, 1), (8, 4, 2), (12, 4, 3), (16, 4, 4), (64, 8, 8)])
def test_stratified_hits_every_stratum_once(spp, nx, ny):
    table = SampleTable.stratified(spp=spp, period=8, seed=2)
    s, unit = f64(table.samples()), table.unit
    xy = np.floor(s[..., 0] * nx) + nx * np.floor(s[..., 1] * ny)
    assert per_pixel_is_permutation(xy.astype(int), spp)
    ab = np.floor(unit[..., 2] * nx) + nx * np.floor(unit[..., 3] * ny)
    assert per_pixel_is_permutation(ab.astype(int), spp)
    assert per_pixel_is_permutation(np.floor(s[..., 4] * spp).astype(int), spp)
    if spp > 1:  # (a, b) strata are permuted across samples, not locked to the (x, y) stratum
        assert not np.array_equal(ab, xy)


@pytest.mark.parametrize("m", [2, 4, 6, 8])
def test_sobol_xy_and_lens_are_0m2_nets(m):
    spp = 2**m
    table = SampleTable.sobol(spp=spp, period=4 if m == 8 else 8, seed=11)
    s = f64(table.samples())
    for first, second in ((s[..., 0], s[..., 1]), (table.unit[..., 2], table.unit[..., 3])):
        for k in range(m + 1):  # elementary intervals 2^-k x 2^-(m-k), all of area 1/spp
            cell = np.floor(first * 2**k) * 2 ** (m - k) + np.floor(second * 2 ** (m - k))
            assert per_pixel_is_permutation(cell.astype(int), spp), f"interval shape 2^-{k} x 2^-{m - k}"
    assert per_pixel_is_permutation(np.floor(s[..., 4] * spp).astype(int), spp)
    # Independent scrambles: pixels differ, and (x, y) differ from (a, b).
    assert not np.array_equal(s[0, 0, :, :2], s[0, 1, :, :2])
    assert not np.array_equal(np.sort(s[0, 0, :, 0]), np.sort(table.unit[0, 0, :, 2]))


def test_sobol_net_check_fails_for_random_points():
    s = f64(SampleTable.random(spp=16, period=4, seed=11).samples())
    cell = np.floor(s[..., 0] * 4) * 4 + np.floor(s[..., 1] * 4)
    assert not per_pixel_is_permutation(cell.astype(int), 16)


@pytest.mark.parametrize("spp, mx, my", [(4, 4, 4), (8, 8, 4), (16, 8, 8)])
def test_stratified_permuted_strata_per_2x2_block(spp, mx, my):
    table = SampleTable.stratified_permuted(spp=spp, period=8, seed=5)
    s, unit = f64(table.samples()), table.unit
    nx, ny = {4: (2, 2), 8: (4, 2), 16: (4, 4)}[spp]
    xy = np.floor(s[..., 0] * nx) + nx * np.floor(s[..., 1] * ny)
    assert per_pixel_is_permutation(xy.astype(int), spp)

    def blocks(a):  # (8, 8, spp) -> (4, 4, 4*spp): the samples of each 2x2 block
        return a.reshape(4, 2, 4, 2, spp).transpose(0, 2, 1, 3, 4).reshape(4, 4, 4 * spp)

    ab = np.floor(unit[..., 2] * mx) + mx * np.floor(unit[..., 3] * my)
    assert per_pixel_is_permutation(blocks(ab).astype(int), 4 * spp)
    assert per_pixel_is_permutation(blocks(np.floor(s[..., 4] * 4 * spp)).astype(int), 4 * spp)
    # The check is not vacuous: single pixels do not hold whole lens strata sets.
    assert not per_pixel_is_permutation((ab // 4).astype(int), spp)


# ------------------------------------------------------------------ lens shapes


@pytest.mark.parametrize("name", GENERATORS)
@pytest.mark.parametrize("shape", LENS_SHAPES)
def test_every_sample_lies_inside_its_lens(name, shape):
    s = make(name, spp=16, period=8, seed=1).samples(shape)
    assert inside_lens(s[..., 2], s[..., 3], shape).all()
    assert (s[..., :2] >= 0).all() and (s[..., :2] < 1).all()
    assert (s[..., 4] >= 0).all() and (s[..., 4] < 1).all()


def test_inside_lens_boundaries():
    r3 = math.sqrt(3.0)
    hex_in = np.array([[1, 0], [-1, 0], [0.5, r3 / 2], [-0.5, -r3 / 2], [0, r3 / 2], [0, 0]])
    hex_out = np.array([[1.01, 0], [0, 0.88], [0.76, 0.44], [-0.9, 0.3]])
    assert inside_lens(hex_in[:, 0], hex_in[:, 1], "hexagon").all()
    assert not inside_lens(hex_out[:, 0], hex_out[:, 1], "hexagon").any()
    assert inside_lens([0.7], [0.7], "disk")[0] and not inside_lens([0.72], [0.72], "disk")[0]
    assert inside_lens([1], [-1], "square")[0] and not inside_lens([1.01], [0], "square")[0]
    assert lens_area("square") == 4.0 and lens_area("disk") == math.pi
    assert lens_area("hexagon") == pytest.approx(1.5 * r3)


@pytest.mark.parametrize("shape", LENS_SHAPES)
def test_maps_land_inside_and_fill_the_shape(shape, rng):
    a, b = rng.random((2, 200_000))
    u, v = map_to_lens(a, b, shape)
    assert u.dtype == np.float64 and inside_lens(u, v, shape, eps=1e-12).all()
    # The images reach the boundary everywhere: the extreme point in 16 directions is near the edge.
    for angle in np.linspace(0, 2 * np.pi, 16, endpoint=False):
        d = np.array([np.cos(angle), np.sin(angle)])
        reach = (u * d[0] + v * d[1]).max()
        support = {"disk": 1.0, "square": abs(d[0]) + abs(d[1])}.get(shape)
        if support is None:  # hexagon: support function over its six vertices
            verts = np.array([[np.cos(k * np.pi / 3), np.sin(k * np.pi / 3)] for k in range(6)])
            support = (verts @ d).max()
        assert reach == pytest.approx(support, abs=0.02)


def disk_cell_p(u, v, rings=10, sectors=16):
    """Chi-square p of the (u, v) histogram over equal-area cells of the unit disk: rings of equal
    area (equal steps in r^2) times equal angular sectors."""
    ring = np.minimum(np.floor((u * u + v * v) * rings), rings - 1)
    sector = np.floor((np.arctan2(v, u) + np.pi) / (2 * np.pi) * sectors) % sectors
    counts = np.bincount((ring * sectors + sector).astype(int), minlength=rings * sectors)
    return stats.chisquare(counts).pvalue


def test_disk_map_is_area_preserving_and_polar_map_is_not(rng):
    a, b = rng.random((2, 400_000))
    u, v = map_to_lens(a, b, "disk")
    assert disk_cell_p(u, v) > P_MIN
    r, theta = a, 2 * np.pi * b  # the biased map: uniform in r crowds the centre
    assert disk_cell_p(r * np.cos(theta), r * np.sin(theta)) < 1e-12


def hexagon_cell_p(u, v, n=16):
    """Chi-square p over the n x n grid cells of [-1, 1]^2 that lie wholly inside the hexagon (all
    of equal area), plus one bin for everything else, with the expectation from the areas."""
    edges = np.linspace(-1, 1, n + 1)
    cu, cv = np.meshgrid(edges, edges, indexing="ij")
    corner_in = inside_lens(cu, cv, "hexagon", eps=0)
    whole = corner_in[:-1, :-1] & corner_in[1:, :-1] & corner_in[:-1, 1:] & corner_in[1:, 1:]
    i = np.clip(np.floor((u + 1) * n / 2).astype(int), 0, n - 1)
    j = np.clip(np.floor((v + 1) * n / 2).astype(int), 0, n - 1)
    in_whole = whole[i, j]
    counts = np.bincount((i * n + j)[in_whole], minlength=n * n)[whole.ravel()]
    cell_fraction = (2 / n) ** 2 / lens_area("hexagon")
    observed = np.append(counts, (~in_whole).sum())
    expected = np.append(np.full(counts.size, cell_fraction * u.size), (1 - cell_fraction * counts.size) * u.size)
    return stats.chisquare(observed, expected).pvalue


def test_hexagon_map_is_area_preserving_and_a_warped_map_is_not(rng):
    a, b = rng.random((2, 400_000))
    u, v = map_to_lens(a, b, "hexagon")
    assert hexagon_cell_p(u, v) > P_MIN
    u_bad, v_bad = map_to_lens(a, b**1.5, "hexagon")  # still inside, but not uniform
    assert inside_lens(u_bad, v_bad, "hexagon").all()
    assert hexagon_cell_p(u_bad, v_bad) < 1e-12


def test_lens_maps_fixed_points():
    u, v = map_to_lens([0.5, 0.0, 0.75], [0.5, 0.0, 0.5], "square")
    assert np.allclose(u, [0, -1, 0.5]) and np.allclose(v, [0, -1, 0])
    u, v = map_to_lens([0.5, 1.0, 0.5], [0.5, 0.5, 1.0], "disk")
    assert np.allclose(u, [0, 1, 0], atol=1e-15) and np.allclose(v, [0, 0, 1], atol=1e-15)


# ------------------------------------------------------------------ interleaved


@pytest.mark.parametrize("n_lens, spp, block", [(64, 64, 1), (256, 64, 2), (256, 16, 4), (64, 32, 2), (16, 64, 1)])
def test_interleaved_positions_are_shared_exact_and_balanced(n_lens, spp, block):
    table = SampleTable.interleaved(spp=spp, n_lens=n_lens, period=8, seed=4)
    assert table.n_lens == n_lens and table.lens_index.dtype == np.int32
    assert table.params["block_px"] == block
    for shape in LENS_SHAPES:
        s = table.samples(shape)
        pos = table.lens_positions(shape)
        assert pos.shape == (n_lens, 2) and pos.dtype == np.float32
        assert len(np.unique(pos, axis=0)) == n_lens
        assert len(np.unique(s[..., 2:4].reshape(-1, 2), axis=0)) == n_lens
        assert np.array_equal(s[..., 2:4].view(np.uint32), pos[table.lens_index].view(np.uint32))
    q = 8 // block
    per_block = table.lens_index.reshape(q, block, q, block, spp).transpose(0, 2, 1, 3, 4).reshape(q * q, -1)
    counts = np.stack([np.bincount(row, minlength=n_lens) for row in per_block])
    assert (counts == block * block * spp // n_lens).all()
    # The canonical positions are jittered strata of a sqrt(N) x sqrt(N) grid.
    n = math.isqrt(n_lens)
    cell = np.floor(table.lens_unit[:, 0] * n) + n * np.floor(table.lens_unit[:, 1] * n)
    assert per_pixel_is_permutation(cell.astype(int), n_lens)


def test_interleaved_uneven_blocks_and_errors():
    table = SampleTable.interleaved(spp=4, n_lens=9, period=4, seed=1)  # 2x2 blocks of 16 samples
    per_block = table.lens_index.reshape(2, 2, 2, 2, 4).transpose(0, 2, 1, 3, 4).reshape(4, -1)
    counts = np.stack([np.bincount(row, minlength=9) for row in per_block])
    assert set(np.unique(counts)) == {1, 2}
    with pytest.raises(ValueError, match="n_lens.*10"):
        SampleTable.interleaved(spp=16, n_lens=10)
    with pytest.raises(ValueError, match="spp.*n_lens"):
        SampleTable.interleaved(spp=96, n_lens=64)
    with pytest.raises(ValueError, match="period.*multiple of 4.*6"):
        SampleTable.interleaved(spp=16, n_lens=256, period=6)
    with pytest.raises(ValueError, match="lens"):
        SampleTable.interleaved(spp=16, lens=False)
    with pytest.raises(ValueError, match="lens_positions"):
        SampleTable.stratified(spp=16).lens_positions()


# ------------------------------------------------------------------ period, seeds, dimensions


@pytest.mark.parametrize("name", GENERATORS)
def test_pixel_samples_repeat_with_the_period(name):
    table = make(name, spp=8, period=8, seed=3)
    s = table.samples("hexagon")
    assert s.shape == (8, 8, 8, 5) and s.dtype == np.float32
    for px, py in [(0, 0), (3, 5), (7, 1), (-1, 2)]:
        base = table.pixel_samples(px, py, "hexagon")
        assert np.array_equal(base, s[py % 8, px % 8])
        assert np.array_equal(base, table.pixel_samples(px + 8, py, "hexagon"))
        assert np.array_equal(base, table.pixel_samples(px, py - 16, "hexagon"))
    assert not np.array_equal(table.pixel_samples(1, 0), table.pixel_samples(0, 1))
    assert np.array_equal(table.pixel_samples(1, 0), table.samples()[0, 1])


@pytest.mark.parametrize("name", GENERATORS)
def test_seeds_are_deterministic_and_distinct(name):
    a = make(name, spp=8, period=4, seed=9)
    b = make(name, spp=8, period=4, seed=9)
    c = make(name, spp=8, period=4, seed=10)
    assert np.array_equal(a.unit, b.unit) and np.array_equal(a.samples(), b.samples())
    assert not np.array_equal(a.samples()[..., :2], c.samples()[..., :2])
    assert not np.array_equal(a.samples()[..., 2:], c.samples()[..., 2:])


@pytest.mark.parametrize("name", [g for g in GENERATORS if g != "interleaved"])
def test_switched_off_dimensions_are_exactly_zero(name):
    full = make(name, spp=8, period=4, seed=2)
    flat = make(name, spp=8, period=4, seed=2, lens=False, time=False)
    assert not flat.has_lens and not flat.has_time
    for shape in LENS_SHAPES:
        s = flat.samples(shape)
        assert (s[..., 2:5] == 0).all() and not np.signbit(s[..., 2:5]).any()
    assert np.array_equal(flat.samples()[..., :2], full.samples()[..., :2])  # x, y unchanged
    assert (full.samples()[..., 4] != 0).any() and (full.samples()[..., 2:4] != 0).any()
    no_time = make(name, spp=8, period=4, seed=2, time=False)
    assert no_time.has_lens and (no_time.samples()[..., 4] == 0).all()
    assert np.array_equal(no_time.samples()[..., :4], full.samples()[..., :4])


def test_interleaved_time_off_is_exactly_zero():
    s = SampleTable.interleaved(spp=16, n_lens=64, period=4, time=False).samples()
    assert (s[..., 4] == 0).all()


# ------------------------------------------------------------------ lens-grid buckets


def numpy_cell(s, grid):
    """The engine's cell rule (sample_table.h cell_of): a + 1 in float32, then * G / 2 in double."""
    def axis(a):
        shifted = (a + np.float32(1)).astype(np.float32).astype(np.float64)
        return np.clip(np.floor(shifted * 0.5 * grid), 0, grid - 1).astype(np.int64)

    return axis(s[..., 3]) * grid + axis(s[..., 2])


@pytest.mark.parametrize("grid", [1, 2, 4, 8, 16])
@pytest.mark.parametrize("name, shape", [("stratified", "disk"), ("sobol", "square"), ("interleaved", "hexagon")])
def test_lens_grid_buckets(grid, name, shape):
    table = make(name, spp=32, period=4, seed=6)
    order, counts, offsets = table.lens_grid(grid, shape)
    P, S, C = 4, 32, grid * grid
    assert order.shape == (P, P, S) and counts.shape == (P, P, C) and offsets.shape == (P, P, C)
    assert order.dtype == counts.dtype == offsets.dtype == np.int32
    assert per_pixel_is_permutation(order, S)
    assert (counts.sum(axis=-1) == S).all()
    assert np.array_equal(offsets, np.cumsum(counts, axis=-1) - counts)
    cell = numpy_cell(table.samples(shape), grid)
    assert np.array_equal(counts, np.stack([np.bincount(c, minlength=C) for c in cell.reshape(-1, S)]).reshape(P, P, C))
    listed = np.take_along_axis(cell, order.astype(np.int64), axis=-1)
    for py in range(P):
        for px in range(P):
            expected = np.repeat(np.arange(C), counts[py, px])
            assert np.array_equal(listed[py, px], expected)
            # stable: within a bucket, canonical indices ascend
            for c in np.nonzero(counts[py, px])[0]:
                run = order[py, px, offsets[py, px, c] : offsets[py, px, c] + counts[py, px, c]]
                assert (np.diff(run) > 0).all()
    if grid > 1 and name != "interleaved":
        assert (counts > 0).sum() > P * P  # buckets really split the samples


@pytest.mark.parametrize("grid", [0, 3, 32, 2.0, True])
def test_lens_grid_rejects_other_sizes(grid):
    with pytest.raises(ValueError, match="lens_grid.*" + str(grid)):
        SampleTable.random(spp=4, period=2).lens_grid(grid)


# ------------------------------------------------------------------ user arrays


def test_from_array_round_trip_and_inference(rng):
    raw = rng.random((2, 2, 8, 5))
    raw[..., 2:4] = raw[..., 2:4] - 0.5
    table = SampleTable.from_array(raw)
    assert table.period == 2 and table.spp == 8 and table.has_lens and table.has_time
    assert table.unit is None and table.n_lens == 0 and table.generator == "from_array"
    assert np.array_equal(table.samples("disk"), raw.astype(np.float32))
    one = SampleTable.from_array(raw[0, 0])  # (spp, 5): every pixel the same
    assert one.period == 1 and np.array_equal(one.pixel_samples(5, 9), raw[0, 0].astype(np.float32))
    flat = raw.copy()
    flat[..., 2:4] = 0
    flat[..., 4] = 0.25
    t = SampleTable.from_array(flat)
    assert not t.has_lens and not t.has_time


def test_from_array_lens_declaration():
    pts = np.zeros((4, 5))
    pts[:, 0] = pts[:, 1] = 0.5
    pts[0, 2:4] = (0.9, 0.9)  # in the square, outside the disk and hexagon
    anything = SampleTable.from_array(pts)  # "any": returned as given for every shape
    assert np.array_equal(anything.samples("disk")[0, 0], pts.astype(np.float32))
    square = SampleTable.from_array(pts, lens="square")
    assert square.samples("square").shape == (1, 1, 4, 5)
    with pytest.raises(ValueError, match=r"\(0, 0, 0\) = \(0.89.*outside the requested 'disk'"):
        square.samples("disk")
    with pytest.raises(ValueError, match="outside the declared 'disk'"):
        SampleTable.from_array(pts, lens="disk")
    with pytest.raises(ValueError, match="lens: unknown shape 'oval'"):
        SampleTable.from_array(pts, lens="oval")


def test_from_array_interleaved():
    gen = SampleTable.interleaved(spp=16, n_lens=64, period=4, seed=1)
    user = SampleTable.from_array(
        gen.samples("disk"), lens_index=gen.lens_index, lens_positions=gen.lens_positions("disk"), lens="disk"
    )
    assert user.n_lens == 64
    assert np.array_equal(user.lens_positions("disk"), gen.lens_positions("disk"))
    broken = gen.samples("disk").copy()
    broken[1, 2, 3, 2] = np.nextafter(broken[1, 2, 3, 2], np.float32(0))
    with pytest.raises(ValueError, match=r"\(1, 2, 3\).*bitwise"):
        SampleTable.from_array(broken, lens_index=gen.lens_index, lens_positions=gen.lens_positions("disk"))
    bad_index = gen.lens_index.copy()
    bad_index[0, 0, 0] = 64
    with pytest.raises(ValueError, match="lens_index.*64"):
        SampleTable.from_array(gen.samples("disk"), lens_index=bad_index, lens_positions=gen.lens_positions("disk"))
    with pytest.raises(ValueError, match="lens_index"):
        SampleTable.from_array(gen.samples("disk"), lens_index=gen.lens_index)


# ------------------------------------------------------------------ errors


@pytest.mark.parametrize(
    "params, field",
    [
        ({"spp": 0}, "spp.*got 0"),
        ({"spp": 4097}, "spp.*got 4097"),
        ({"spp": 2.5}, "spp.*got 2.5"),
        ({"spp": True}, "spp.*got True"),
        ({}, "spp: required"),
        ({"spp": 4, "period": 0}, "period.*got 0"),
        ({"spp": 4, "period": 257}, "period.*got 257"),
        ({"spp": 4, "seed": -1}, "seed.*got -1"),
        ({"spp": 4, "lens": "yes"}, "lens.*'yes'"),
        ({"spp": 4, "shape": "disk"}, "unknown parameter 'shape'"),
    ],
)
@pytest.mark.parametrize("name", ["random", "sobol"])
def test_invalid_parameters_raise(name, params, field):
    with pytest.raises(ValueError, match=field):
        SampleTable.create(name, **params)


def test_odd_period_rejected_for_2x2_blocks():
    with pytest.raises(ValueError, match="period.*even.*got 5"):
        SampleTable.stratified_permuted(spp=4, period=5)


def test_unknown_lens_shape_raises():
    table = SampleTable.random(spp=4, period=2)
    with pytest.raises(ValueError, match=r"lens: unknown shape 'oval' \(known: disk, square, hexagon\)"):
        table.samples("oval")
    with pytest.raises(ValueError, match="lens: unknown shape 'circle'"):
        map_to_lens(0.5, 0.5, "circle")


@pytest.mark.parametrize(
    "edit, match",
    [
        (lambda a: a.__setitem__((3, 0), np.nan), r"samples: non-finite.*\(3, 0\)"),
        (lambda a: a.__setitem__((2, 0), 1.0), r"samples: x must be in \[0, 1\).*\(2,\).*1.0"),
        (lambda a: a.__setitem__((1, 1), -0.1), r"samples: y .*\(1,\)"),
        (lambda a: a.__setitem__((5, 3), 1.5), r"samples: v must be in \[-1, 1\].*\(5,\).*1.5"),
        (lambda a: a.__setitem__((0, 4), 2.0), r"samples: t .*\(0,\).*2.0"),
    ],
)
def test_from_array_rejects_bad_values(edit, match):
    pts = np.full((8, 5), 0.5)
    edit(pts)
    with pytest.raises(ValueError, match=match):
        SampleTable.from_array(pts)


@pytest.mark.parametrize("shape", [(8,), (8, 4), (2, 3, 8, 5), (2, 2, 8, 6), (0, 5), (4097, 5)])
def test_from_array_rejects_bad_shapes(shape):
    with pytest.raises(ValueError, match="samples"):
        SampleTable.from_array(np.full(shape, 0.5))


def test_from_array_rejects_non_numeric():
    with pytest.raises(ValueError, match="samples.*dtype"):
        SampleTable.from_array(np.full((4, 5), "a"))


def test_describe_and_repr():
    table = SampleTable.interleaved(spp=16, n_lens=64, period=4, seed=3, time=False)
    assert table.describe() == {
        "generator": "interleaved",
        "spp": 16,
        "period": 4,
        "seed": 3,
        "n_lens": 64,
        "has_lens": True,
        "has_time": False,
    }
    text = repr(table)
    assert "interleaved" in text and "spp=16" in text and "n_lens=64" in text and len(text) < 120


def test_stratum_values_stay_in_their_stratum_after_float32_rounding():
    """Jitter at the very ends of a stratum must not round into a neighbour (the float32 samples
    are what the stratum tests above and the engine see)."""
    from sim.sample_table import _stratum_values

    for n in (3, 7, 64, 4096, 12288):
        index = np.arange(n)
        for jitter in (0.0, np.nextafter(1.0, 0.0), 1e-9, 1 - 1e-9):
            value = _stratum_values(index, n, np.full(n, jitter))
            assert np.array_equal(value, value.astype(np.float32).astype(np.float64))
            assert np.array_equal(np.floor(value * n), index)
            assert (value < 1).all()


@pytest.mark.parametrize("views, spp", [(2, 16), (7, 56), (4, 4)])
def test_multiview_splits_the_lens_into_views(views, spp):
    """[Nilsson 2012] §8 Fig. 16: view k owns samples k*m..(k+1)*m-1 and the k-th u-interval; within it the
    lens positions are uniform (chi-square on the rescaled u) and v and t stratified per view."""
    table = make("multiview", spp=spp, views=views, period=8, seed=5)
    m = spp // views
    a, b = table.unit[..., 2], table.unit[..., 3]
    for k in range(views):
        ak = f64(a[..., k * m:(k + 1) * m])
        assert ak.min() >= k / views and ak.max() < (k + 1) / views
        local = ak * views - k
        p = chi2_uniform_p(local, 8)
        assert p > P_MIN, f"view {k}: u within the view rejected, p = {p:.3g}"
        p = chi2_uniform_p(f64(b[..., k * m:(k + 1) * m]), 8)
        assert p > P_MIN, f"view {k}: v rejected, p = {p:.3g}"
    with pytest.raises(ValueError, match="divisible by views"):
        make("multiview", spp=10, views=3)
    with pytest.raises(ValueError, match="views: expected"):
        make("multiview", spp=8, views=0)
