"""Invariant 1, conservative culling: every traversal algorithm's per-sample coverage and depth equal brute force's, bitwise, on random and adversarial triangles (hypothesis)."""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sim
from tests import reference
from tests.reference import make_scene

pytestmark = pytest.mark.invariants

ALGORITHMS = sim.algorithm_names("points")
INTERLEAVED = sorted(name for name, _desc, needs in sim._core.algorithms() if needs)
ANY_TABLE = [a for a in ALGORITHMS if a not in INTERLEAVED]
LENSES = ["disk", "square", "hexagon"]
TILE_SIZES = [1, 2, 4, 8]
LENS_GRIDS = [1, 2, 4, 8, 16]
HALFSPACE = {"none": {"h": False, "H": False}, "h": {"h": True, "H": False},
             "H": {"h": False, "H": True}, "both": {"h": True, "H": True}}
OTHER_TABLES = ["stratified", "random", "sobol", "stratified_permuted"]
SPP = 16
WIDTH, HEIGHT = 32, 24  # not square: catches s_x / s_y and X / Y mix-ups
NEAR = 0.05
# Per-render results that must not depend on the traversal algorithm. (raster.samples_covered and
# samples_near_rejected may: a sample behind the near plane is no hit, so an algorithm may skip it.)
SAME_COUNTERS = ("raster.samples_hit", "depth.tests", "depth.passes", "setup.triangles")

HYPO = dict(deadline=None, derandomize=True, database=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.data_too_large])


# ---------------------------------------------------------------------------------- scenes




world_from_pixel = functools.partial(reference.world_from_pixel, width=WIDTH, height=HEIGHT)


# ---------------------------------------------------------------------------------- tables


@functools.lru_cache(maxsize=None)
def table(kind: str, seed: int = 5, n_lens: int = 64):
    if kind == "interleaved":
        return sim.SampleTable.interleaved(spp=SPP, n_lens=n_lens, seed=seed)
    return getattr(sim.SampleTable, kind)(spp=SPP, seed=seed)


# ---------------------------------------------------------------------------------- checks


def engine_vertex_camera(v0, **kw):
    """A camera that hands the engine the given pixel-homogeneous vertices unchanged (static), so that
    a focus-plane intersection or a sample can sit *exactly* on a line, which the world -> clip
    transform cannot express. world_from_engine() gives the world points they stand for."""

    class EngineVertexCamera(sim.Camera):
        def engine_vertices(self, positions, positions_t1):
            a = np.asarray(v0, dtype=np.float32).reshape(-1, 3, 3)
            return a, a.copy()

    return EngineVertexCamera(**kw)


def world_from_engine(v, width=WIDTH, height=HEIGHT, fov_y_deg=45.0):
    v = np.asarray(v, dtype=np.float64)
    return np.stack([reference.world_from_pixel(X / W, Y / W, W, width, height, fov_y_deg) for X, Y, W in v.reshape(-1, 3)]
                    ).reshape(v.shape)


@dataclass
class Case:
    """One conservative-culling example: a scene, camera parameters and pipeline switches."""

    p0: np.ndarray
    p1: np.ndarray | None = None
    focus: float = 5.0
    coc: float = 10.0
    lens: str = "disk"
    fov: float = 45.0
    width: int = WIDTH
    height: int = HEIGHT
    cfg: dict | None = None
    other_table: str = "stratified"
    n_lens: int = 64
    engine: np.ndarray | None = None  # pixel-homogeneous (X_h, Y_h, W) vertices that bypass the camera

    def camera(self):
        kw = dict(width=self.width, height=self.height, fov_y_deg=self.fov, focus_distance=self.focus,
                  coc_px=self.coc, lens=self.lens, near=NEAR)
        return sim.Camera(**kw) if self.engine is None else engine_vertex_camera(self.engine, **kw)

    def describe(self) -> str:
        p1 = "static" if self.p1 is None else f"positions_t1={np.asarray(self.p1).tolist()!r}"
        if self.engine is not None:
            p1 += f"; engine (pixel-homogeneous) vertices {np.asarray(self.engine).tolist()!r}"
        return (f"positions={np.asarray(self.p0).tolist()!r}, {p1}; Camera(width={self.width}, "
                f"height={self.height}, fov_y_deg={self.fov!r}, focus_distance={self.focus!r}, "
                f"coc_px={self.coc!r}, lens={self.lens!r}, near={NEAR}); config={self.cfg!r}")


def render(case: Case, algorithm: str, tbl, **overrides):
    cfg = sim.PipelineConfig(algorithm=algorithm, threads=1, **{"count_optimal": True, **(case.cfg or {}), **overrides})
    return sim.render(make_scene(case.p0, case.p1), case.camera(), tbl, cfg, export_samples=True)


def assert_same_samples(ref, res, case: Case, tbl, algorithm: str):
    """res must equal the brute-force ref per sample, bitwise; else fail with a reproducer."""
    same_tri = ref.sample_triangle == res.sample_triangle
    same_depth = ref.sample_depth.view(np.uint32) == res.sample_depth.view(np.uint32)
    bad = ~(same_tri & same_depth)
    if bad.any():
        y, x, s = (int(i) for i in np.argwhere(bad)[0])
        smp = tbl.pixel_samples(x, y, case.lens)[s].tolist()
        pytest.fail(
            f"{algorithm} differs from bruteforce at pixel (x={x}, y={y}) sample {s} (x, y, u, v, t)={smp}: "
            f"triangle {ref.sample_triangle[y, x, s]} -> {res.sample_triangle[y, x, s]}, depth "
            f"{ref.sample_depth[y, x, s]!r} -> {res.sample_depth[y, x, s]!r}; {int(bad.sum())} samples differ. "
            f"Table {tbl!r}. Reproducer: {case.describe()}"
        )
    assert np.array_equal(ref.image.view(np.uint32), res.image.view(np.uint32)), (algorithm, case.describe())
    for k in SAME_COUNTERS:
        assert ref.flat_stats[k] == res.flat_stats[k], (
            f"{algorithm}: {k} = {res.flat_stats[k]} but bruteforce {ref.flat_stats[k]} (a culled hit hidden "
            f"by depth?). Table {tbl!r}. Reproducer: {case.describe()}")


def assert_tile_bounds(res, case: Case, algorithm: str):
    """[Akenine-Möller 2012] Table 1: tested >= optimal (exact active lens region) >= hit, per tile algorithm."""
    st_ = res.flat_stats
    tested, optimal, hit = st_["raster.samples_tested"], st_["tile.samples_optimal"], st_["raster.samples_hit"]
    assert tested >= optimal >= hit, (
        f"{algorithm}: samples_tested={tested} samples_optimal={optimal} samples_hit={hit}; {case.describe()}")


def check_conservative(case: Case, algorithms=None):
    """Every algorithm (interleaved ones on an interleaved table, the others also on case.other_table)
    gives brute force's per-sample triangle and depth. Returns the tile results for extra checks."""
    want = set(algorithms or ALGORITHMS)
    out = {}
    for tbl, algs in ((table("interleaved", n_lens=case.n_lens), ALGORITHMS), (table(case.other_table), ANY_TABLE)):
        algs = [a for a in algs if a in want and a != "bruteforce"]
        if not algs:
            continue
        ref = render(case, "bruteforce", tbl)
        for a in algs:
            res = render(case, a, tbl)
            assert_same_samples(ref, res, case, tbl, a)
            if a == "tile":
                assert_tile_bounds(res, case, a)
                out.setdefault("tile", res)
    return out


# ---------------------------------------------------------------------------------- strategies

# No subnormal floats (they found a bug once; test_conservative_subnormal_coc_laine pins it).
finite = functools.partial(st.floats, allow_nan=False, allow_infinity=False, allow_subnormal=False)
# Focus distances: float32-exact ones (a vertex at depth F then has W == F exactly) and others
# (W rounds to float32 and misses F by an ulp: 1 - F/W is tiny but not zero).
focus_st = st.one_of(st.sampled_from([1.0, 2.0, 2.5, 4.0, 5.0, 6.25, 8.0]), finite(min_value=1.0, max_value=12.0))
coc_st = st.one_of(st.sampled_from([0.0, 0.01, 0.5, 3.0, 10.0, 40.0, 120.0]), finite(min_value=0.0, max_value=80.0))
lens_st = st.sampled_from(LENSES)
pixel_x = finite(min_value=-0.4 * WIDTH, max_value=1.4 * WIDTH)
pixel_y = finite(min_value=-0.4 * HEIGHT, max_value=1.4 * HEIGHT)


@st.composite
def config_st(draw, tile_size=None):
    """Every tile-test switch of PipelineConfig; c_tile = 0 keeps every H_j edge enabled."""
    return {
        "tile_size": draw(st.sampled_from(TILE_SIZES)) if tile_size is None else tile_size,
        "lens_grid": draw(st.sampled_from(LENS_GRIDS)),
        "halfspace": dict(HALFSPACE[draw(st.sampled_from(["none", "h", "H", "both", "both", "H"]))]),
        "selective_H": draw(st.booleans()),  # (on: small triangles lose their H_j edges)
        "oracle": draw(st.sampled_from(["simplified", "full"])),
        "c_tile": draw(st.sampled_from([None, 0.0, 0.0])),
        "hinterleave_tile": draw(st.sampled_from([4, 8, 16])),
        "backface_cull": draw(st.sampled_from([False, False, True])),
    }


def vertex_at(draw, depth):
    return world_from_pixel(draw(pixel_x), draw(pixel_y), depth)


@st.composite
def moving(draw, p0, prob=0.3):
    """Optionally a linear motion of the triangles (the motion fallback path): None = static."""
    if draw(st.integers(0, 99)) >= round(100 * prob):
        return None
    v = draw(st.lists(finite(min_value=-1.5, max_value=1.5), min_size=p0.size, max_size=p0.size))
    return p0 + np.reshape(v, p0.shape)


def coc_seen_one_side(tri, focus, frac, width=WIDTH, fov_y_deg=45.0, height=HEIGHT):
    """The CoC (px) whose square lens [-R, R]^2 reaches frac of the way to the triangle's plane:
    below frac = 1 every lens point sees the same side, so the H_j lines stay on (sigma != 0)."""
    p, q, r = np.asarray(tri, dtype=np.float64)
    n = np.cross(q - p, r - p)
    reach = abs(n[0]) + abs(n[1])
    if reach == 0 or not np.isfinite(reach):
        return 10.0
    radius = frac * abs(n @ p) / reach
    s_x, _ = reference.pinhole_scales(width, height, fov_y_deg)
    return float(min(radius * s_x * width / (2.0 * focus), 300.0))


@st.composite
def case_st(draw, tris, focus=focus_st, coc=coc_st, tile_size=None, motion_prob=0.25, one_side_prob=0.0):
    """A Case around world triangles; with one_side_prob, the CoC is chosen so that the first
    triangle's orientation is the same from every lens point (H_j lines active)."""
    p0 = np.asarray(tris, dtype=np.float64).reshape(-1, 3, 3)
    focus = focus if isinstance(focus, float) else draw(focus)
    if draw(st.integers(0, 99)) < round(100 * one_side_prob):
        coc = coc_seen_one_side(p0[0], focus, draw(st.sampled_from([0.3, 0.9, 0.99, 1.01])))
        motion_prob = min(motion_prob, 0.1)
    else:
        coc = coc if isinstance(coc, float) else draw(coc)
    return Case(p0=p0, p1=draw(moving(p0, motion_prob)), focus=focus, coc=coc, lens=draw(lens_st),
                cfg=draw(config_st(tile_size)), other_table=draw(st.sampled_from(OTHER_TABLES)),
                n_lens=draw(st.sampled_from([16, 64])))


@st.composite
def random_triangles(draw):
    """1-3 triangles anywhere around the screen at depths 0.3..25: the common case."""
    n = draw(st.integers(1, 3))
    tris = [[vertex_at(draw, draw(finite(min_value=0.3, max_value=25.0))) for _ in range(3)] for _ in range(n)]
    return draw(case_st(tris, one_side_prob=0.4))


@st.composite
def focus_crossing(draw):
    """Vertices on both sides of the focus plane ([Akenine-Möller 2012] Fig. 6-7: two or three uv-boxes)."""
    F = draw(focus_st)
    ratios = [draw(finite(min_value=0.15, max_value=0.97)), draw(finite(min_value=1.03, max_value=6.0)),
              draw(finite(min_value=0.15, max_value=6.0))]
    tri = [vertex_at(draw, F * r) for r in draw(st.permutations(ratios))]
    return draw(case_st([tri], focus=F, one_side_prob=0.5))


@st.composite
def vertex_on_focus(draw):
    """One or two vertices exactly at view depth F (world z = -F): b = 0, no h_i line; with two,
    an edge lies in the focus plane (ignored by [Akenine-Möller 2012] §4.3); also one vertex at float32(F)."""
    F = draw(focus_st)
    k = draw(st.integers(1, 3))
    depths = [F] * k + [F * draw(finite(min_value=0.2, max_value=5.0)) for _ in range(3 - k)]
    tri = [vertex_at(draw, d) for d in draw(st.permutations(depths))]
    if draw(st.booleans()):  # the vertex lands at the float32 neighbour of F instead
        j = draw(st.integers(0, 2))
        tri[j][2] = -float(np.nextafter(np.float32(F), np.float32(np.inf if draw(st.booleans()) else 0)))
    return draw(case_st([tri], focus=F, one_side_prob=0.5))


@st.composite
def parallel_edge(draw):
    """An edge parallel to the focus plane (two vertices at the same depth, d_w = 0)."""
    F = draw(focus_st)
    d = draw(st.one_of(st.just(F), finite(min_value=0.3, max_value=20.0)))
    other = draw(finite(min_value=0.3, max_value=20.0))
    tri = [vertex_at(draw, d), vertex_at(draw, d), vertex_at(draw, other)]
    return draw(case_st([draw(st.permutations(tri))], focus=F, one_side_prob=0.5))


@st.composite
def behind_camera(draw):
    """One or two vertices behind the camera or the near plane (Olano-Greer; near-clipped footprint)."""
    F = draw(focus_st)
    k = draw(st.integers(1, 2))
    behind = [draw(st.one_of(st.sampled_from([0.0, NEAR, -NEAR, -1.0]), finite(min_value=-6.0, max_value=NEAR)))
              for _ in range(k)]
    front = [draw(finite(min_value=0.2, max_value=15.0)) for _ in range(3 - k)]
    tri = []
    for d in draw(st.permutations(behind + front)):
        x, y = draw(finite(min_value=-4, max_value=4)), draw(finite(min_value=-4, max_value=4))
        tri.append([x, y, -d])
    return draw(case_st([tri], focus=F))


@st.composite
def extreme_coc(draw):
    """A tiny triangle (0.05-1 px) under CoC >= 200 px, or any triangle under CoC <= 0.01 px."""
    F = draw(focus_st)
    if draw(st.booleans()):
        coc = draw(st.one_of(st.sampled_from([200.0, 1000.0, 5000.0]), finite(min_value=200.0, max_value=3000.0)))
        cx, cy = draw(pixel_x), draw(pixel_y)
        size = draw(finite(min_value=0.05, max_value=1.0))
        d = F * draw(finite(min_value=0.3, max_value=4.0))
        tri = [world_from_pixel(cx + size * draw(finite(min_value=-1, max_value=1)),
                                cy + size * draw(finite(min_value=-1, max_value=1)),
                                d * draw(finite(min_value=0.97, max_value=1.03))) for _ in range(3)]
    else:
        coc = draw(st.one_of(st.sampled_from([1e-6, 1e-3, 0.01]), finite(min_value=1e-7, max_value=0.01)))
        tri = [vertex_at(draw, F * draw(finite(min_value=0.2, max_value=5.0))) for _ in range(3)]
    return draw(case_st([tri], focus=F, coc=coc))


@st.composite
def degenerate(draw):
    """Zero area (repeated vertex, collinear), or a plane through the lens centre or another lens
    point: edge-on from part of the lens, so the orientation changes sign over the lens."""
    F = draw(focus_st)
    coc = draw(coc_st)
    p = vertex_at(draw, draw(finite(min_value=0.3, max_value=15.0)))
    q = vertex_at(draw, draw(finite(min_value=0.3, max_value=15.0)))
    a, b = draw(finite(min_value=0.1, max_value=2.0)), draw(finite(min_value=0.1, max_value=2.0))
    kind = draw(st.sampled_from(["repeat", "collinear", "centre", "lens_point", "point"]))
    if kind == "repeat":
        r = p.copy()
    elif kind == "collinear":
        r = p + a * (q - p)
    elif kind == "point":
        q = p.copy()
        r = p.copy()
    else:
        cam = sim.Camera(width=WIDTH, height=HEIGHT, fov_y_deg=45.0, focus_distance=F, coc_px=coc)
        lu, lv = draw(finite(min_value=-0.7, max_value=0.7)), draw(finite(min_value=-0.7, max_value=0.7))
        L = np.zeros(3) if kind == "centre" else np.array([lu * cam.aperture_radius, lv * cam.aperture_radius, 0.0])
        r = L + a * (p - L) + b * (q - L)  # the plane of p, q, r contains lens point L
    tri = draw(st.permutations([p, q, r]))
    return draw(case_st([tri], focus=F, coc=coc))


@st.composite
def axis_aligned(draw):
    """Edges nearly (slope ~1e-6) or exactly parallel to the screen axes."""
    F = draw(focus_st)
    d = F * draw(finite(min_value=0.3, max_value=4.0))
    x0, x1, y0 = draw(pixel_x), draw(pixel_x), draw(pixel_y)
    eps = draw(st.sampled_from([0.0, 1e-6, -1e-6, 3e-7, 1e-5]))
    y1 = y0 + eps * (x1 - x0)
    d1 = d if draw(st.booleans()) else d * (1 + draw(st.sampled_from([0.0, 1e-6, -1e-6])))
    pts = [(x0, y0, d), (x1, y1, d1), (draw(pixel_x), draw(pixel_y), F * draw(finite(min_value=0.3, max_value=4.0)))]
    if draw(st.booleans()):  # vertical instead of horizontal
        pts = [(y * WIDTH / HEIGHT, x * HEIGHT / WIDTH, w) for x, y, w in pts]
    tri = [world_from_pixel(*pt) for pt in pts]
    return draw(case_st([draw(st.permutations(tri))], focus=F, one_side_prob=0.5))


@st.composite
def region_boundary(draw):
    """An edge whose focus-plane intersection v lies on a tile line x = i*T and/or y = j*T (or a
    tile-test margin away): the boundaries of [Akenine-Möller 2012] §4.3's nine regions."""
    T = draw(st.sampled_from(TILE_SIZES))
    F = draw(focus_st)
    offsets = st.sampled_from([0.0, 0.0, 1e-6, -1e-6, 2.0**-10, -(2.0**-10), 2.0**-10 + 1e-9])
    vx = T * draw(st.integers(0, WIDTH // T)) + draw(offsets)
    vy = T * draw(st.integers(0, HEIGHT // T)) + draw(offsets)
    mode = draw(st.sampled_from(["corner", "x_line", "y_line"]))
    if mode == "x_line":
        vy = draw(finite(min_value=0, max_value=HEIGHT))
    elif mode == "y_line":
        vx = draw(finite(min_value=0, max_value=WIDTH))
    v = world_from_pixel(vx, vy, F)  # the point at depth F that projects to pixel (vx, vy)
    d1 = F * draw(st.one_of(finite(min_value=0.2, max_value=0.95), finite(min_value=1.05, max_value=5.0)))
    p = vertex_at(draw, d1)
    lam = draw(finite(min_value=0.1, max_value=3.0))
    q = v + lam * (v - p)  # the edge pq passes through v (q may be behind the camera)
    r = vertex_at(draw, F * draw(finite(min_value=0.2, max_value=5.0)))
    tri = [p, q, r] if draw(st.booleans()) else [q, p, r]
    case = draw(case_st([tri], focus=F, tile_size=T, motion_prob=0.1, one_side_prob=0.6))
    if draw(st.integers(0, 3)):  # mostly keep every H_j edge on, so the region table is used
        case.cfg["halfspace"] = {"h": draw(st.booleans()), "H": True}
        case.cfg["selective_H"] = False
    return case


@st.composite
def moving_triangles(draw):
    """Moving triangles (3D/5D: the conservative motion path), crossing the focus or near plane in time."""
    F = draw(focus_st)
    tri = [vertex_at(draw, F * draw(finite(min_value=0.2, max_value=4.0))) for _ in range(3)]
    p0 = np.array(tri)
    dz = draw(st.sampled_from([0.0, 0.0, -2.0 * F, 0.8 * F, F]))
    vel = np.array([[draw(finite(min_value=-2, max_value=2)), draw(finite(min_value=-2, max_value=2)),
                     dz * draw(finite(min_value=0, max_value=1))] for _ in range(3)])
    case = draw(case_st([p0], focus=F, motion_prob=0.0))
    case.p1 = (p0 + vel).reshape(1, 3, 3)
    return case


STRATEGIES = {
    "random": (random_triangles(), 150),
    "focus_crossing": (focus_crossing(), 120),
    "vertex_on_focus": (vertex_on_focus(), 100),
    "parallel_edge": (parallel_edge(), 100),
    "behind_camera": (behind_camera(), 100),
    "extreme_coc": (extreme_coc(), 100),
    "degenerate": (degenerate(), 100),
    "axis_aligned": (axis_aligned(), 100),
    "region_boundary": (region_boundary(), 200),
    "moving": (moving_triangles(), 100),
}


def on_one_view_ray(p0, max_angle=1e-5) -> bool:
    """A triangle whose three vertices lie within max_angle (radians) of one line through the eye: a
    needle pointing at the camera, or a sub-1e-3-px speck. A float sample test can give such triangles
    spurious hits, so setup culls footprints below float resolution (counted in
    setup.culled_degenerate) and every traversal masks pixels outside the setup bounds; the tests
    below pin the cases hypothesis found."""
    p = np.asarray(p0, dtype=np.float64).reshape(-1, 3, 3)
    norm = np.linalg.norm(p, axis=2, keepdims=True)
    d = np.divide(p, norm, out=np.zeros_like(p), where=norm > 0)
    sines = [np.linalg.norm(np.cross(d[:, i], d[:, j]), axis=1) for i, j in ((0, 1), (0, 2), (1, 2))]
    return bool(np.any(np.max(sines, axis=0) <= max_angle))


def _make_test(strategy, n):
    @settings(max_examples=n, **HYPO)
    @given(case=strategy)
    def test(case):
        check_conservative(case)

    return test


test_conservative_random = _make_test(*STRATEGIES["random"])
test_conservative_focus_crossing = _make_test(*STRATEGIES["focus_crossing"])
test_conservative_vertex_on_focus = _make_test(*STRATEGIES["vertex_on_focus"])
test_conservative_parallel_edge = _make_test(*STRATEGIES["parallel_edge"])
test_conservative_behind_camera = _make_test(*STRATEGIES["behind_camera"])
test_conservative_extreme_coc = _make_test(*STRATEGIES["extreme_coc"])
test_conservative_degenerate = _make_test(*STRATEGIES["degenerate"])
test_conservative_axis_aligned = _make_test(*STRATEGIES["axis_aligned"])
test_conservative_region_boundary = _make_test(*STRATEGIES["region_boundary"])
test_conservative_moving = _make_test(*STRATEGIES["moving"])


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(STRATEGIES))
def test_conservative_long(name):
    """Ten times the examples of the default run, per strategy."""
    strategy, n = STRATEGIES[name]
    _make_test(strategy, 10 * n)()


# ---------------------------------------------------------------------------------- explicit sweeps

# Fixed adversarial triangles (world space) for the full product of tile-test switches.
F_SWEEP = 4.0
SWEEP_TRIANGLES = {
    # one vertex in front of the focus plane, two far behind ([Akenine-Möller 2012] Fig. 7: uv-boxes A and B); its
    # plane cuts the lens, so the orientation changes sign and H_j is skipped (conservatively)
    "crossing": [world_from_pixel(5.3, 4.1, 2.1), world_from_pixel(27.2, 9.6, 9.0), world_from_pixel(12.5, 21.7, 6.5)],
    # crossing the focus plane at a shallow angle: two uv-boxes and H_j lines
    "shallow_crossing": [world_from_pixel(3.0, 4.0, 3.3), world_from_pixel(29.0, 8.0, 4.6), world_from_pixel(12.0, 22.0, 4.1)],
    # all behind / all in front of the focus plane, large on screen
    "behind_focus": [world_from_pixel(-3.0, 2.0, 7.0), world_from_pixel(30.0, 6.0, 9.5), world_from_pixel(9.0, 26.0, 8.0)],
    "front_focus": [world_from_pixel(4.0, 3.0, 2.5), world_from_pixel(28.0, 7.0, 3.0), world_from_pixel(14.0, 22.0, 3.4)],
    # a vertex exactly at F, and an edge whose focus-plane intersection is the tile corner (16, 8)
    "corner_v": [2.0 * world_from_pixel(16.0, 8.0, F_SWEEP) - world_from_pixel(3.0, 20.0, 3.4),
                 world_from_pixel(3.0, 20.0, 3.4), world_from_pixel(25.0, 3.0, F_SWEEP)],
}


@pytest.mark.parametrize("name", sorted(SWEEP_TRIANGLES))
@pytest.mark.parametrize("lens", LENSES)
def test_conservative_full_switch_product(name, lens):
    """tile over tile sizes x lens grids x halfspace modes x selective_H x oracle (and laine,
    interval over the switches they read), on both an interleaved and a stratified table."""
    case = Case(p0=np.array([SWEEP_TRIANGLES[name]]), focus=F_SWEEP, coc=12.0, lens=lens)
    for tbl in (table("interleaved"), table("stratified")):
        ref = render(case, "bruteforce", tbl)
        seen = set()
        for T in TILE_SIZES:
            for G in LENS_GRIDS:
                for hs in HALFSPACE:
                    for selective, oracle in ((False, "simplified"), (True, "simplified"), (True, "full")):
                        case.cfg = dict(tile_size=T, lens_grid=G, halfspace=dict(HALFSPACE[hs]),
                                        selective_H=selective, oracle=oracle)
                        for a, key in (("tile", (T, G, hs, selective, oracle)), ("laine", (T, HALFSPACE[hs]["h"])),
                                       ("interval", (G,))):
                            if (a, key) in seen:
                                continue
                            seen.add((a, key))
                            res = render(case, a, tbl)
                            assert_same_samples(ref, res, case, tbl, a)
                            if a == "tile":
                                assert_tile_bounds(res, case, a)


def test_sweep_triangles_exercise_the_tile_tests():
    """The fixed cases are not vacuous: the h_i lines alone and the H_j lines each cull samples,
    cells and tiles that brute force tests."""
    totals = {k: 0 for k in ("tile.culled_H", "tile.cells_culled", "tile.H_lines", "ops.sample_region")}
    for name in SWEEP_TRIANGLES:
        for hs in ("h", "H"):
            case = Case(p0=np.array([SWEEP_TRIANGLES[name]]), focus=F_SWEEP, coc=12.0,
                        cfg=dict(tile_size=2, lens_grid=8, selective_H=False, halfspace=dict(HALFSPACE[hs])))
            res = check_conservative(case, ["tile"])["tile"]
            for k in totals:
                totals[k] += res.flat_stats[k]
            if name != "crossing" or hs == "h":  # "crossing" is edge-on from part of the lens: no H_j
                brute = render(case, "bruteforce", table("interleaved")).flat_stats["raster.samples_tested"]
                assert res.flat_stats["raster.samples_tested"] < 0.9 * brute, (name, hs)
    assert all(v > 0 for v in totals.values()), totals


@pytest.mark.parametrize("T", TILE_SIZES)
@pytest.mark.parametrize("where", ["corner", "x_line", "y_line", "x_margin", "y_margin"])
@pytest.mark.parametrize("third", ["front", "behind", "at_focus"])
def test_conservative_exact_region_boundaries(T, where, third):
    """Edge qr meets the focus plane *exactly* (dyadic arithmetic) on a tile corner, a tile line, or
    the boundary of the margin-expanded tile: [Akenine-Möller 2012] §4.3's nine-region table at its seams."""
    F = 4.0  # q at W = 3.5, r at W = 4.5: the edge's focus point is their exact midpoint
    lo = lambda x: x - (2.0**-10 + 2.0**-18 * abs(x))  # tiletest::expand_lo / expand_hi
    hi = lambda x: x + (2.0**-10 + 2.0**-18 * abs(x))
    vx, vy = {"corner": (2 * T, T), "x_line": (3 * T, 5.375), "y_line": (7.625, 2 * T),
              "x_margin": (lo(2 * T), 9.5), "y_margin": (11.25, hi(T))}[where]
    dq = np.array([-6.5, 4.25]) if third != "behind" else np.array([5.0, 3.5])  # pixel offset of q from v
    q = np.array([(vx + dq[0]) * 3.5, (vy + dq[1]) * 3.5, 3.5])
    r = np.array([2.0 * vx * F - q[0], 2.0 * vy * F - q[1], 4.5])  # (q + r) / 2 = F * (vx, vy, 1)
    assert np.array_equal(np.float32([q, r]), [q, r])  # exactly representable: v is exact in the engine
    sw = {"front": 3.75, "behind": 4.5, "at_focus": F}[third]
    s = np.float32([(vx + 9.25) * sw, (vy - 7.5) * sw, sw])
    v0 = np.array([[q, r, s]])
    # CoC 2.5 px keeps every lens point on one side of the triangle's plane (H_j stays on); the
    # bound is coc_seen_one_side(world_from_engine(v0)[0], F, 1.0) >= 3.0 for all these cases.
    h_lines = 0
    for lens, hs, G in (("disk", "both", 4), ("square", "H", 1), ("hexagon", "both", 16), ("disk", "H", 16)):
        case = Case(p0=world_from_engine(v0), engine=v0, focus=F, coc=2.5, lens=lens,
                    cfg=dict(tile_size=T, lens_grid=G, halfspace=dict(HALFSPACE[hs]), selective_H=False))
        res = check_conservative(case, ["tile", "laine", "tile_interleaved"])["tile"]
        assert res.flat_stats["raster.samples_hit"] > 0
        h_lines += res.flat_stats["tile.H_lines"]
    assert h_lines > 0  # the H_j lines (and so the region table) were used


def test_ties_on_shared_edges_and_vertices_agree(rng):
    """Samples exactly on a shared edge or at a vertex (top-left rule): every algorithm, including the
    pre-sheared 2D kernel of the interleaved ones, resolves the tie like brute force."""
    F = 1.0
    tbl = table("interleaved")
    smp = tbl.samples("disk")
    tris = []
    for _ in range(12):
        px, py, k = int(rng.integers(3, WIDTH - 3)), int(rng.integers(3, HEIGHT - 3)), int(rng.integers(SPP))
        sx = float(np.float32(px) + smp[py, px, k, 0])  # the engine's float32 sample position
        sy = float(np.float32(py) + smp[py, px, k, 1])
        dx, dy = rng.choice([-1.0, 1.0]) * rng.uniform(1.0, 3.0), rng.uniform(1.0, 3.0)
        w3 = float(rng.choice([1.0, 2.0, 0.75]))
        a, b = [sx, sy, 1.0], [float(np.float32(sx + dx)), sy, 1.0]  # horizontal edge through the sample (W = F)
        for sign in (1.0, -1.0):  # the two triangles sharing edge ab
            tris.append([a, b, [float(np.float32((sx + 0.3 * dx) * w3)), float(np.float32((sy + sign * dy) * w3)), w3]])
    v0 = np.array(tris)
    ties = 0
    for coc in (0.0, 7.0):
        case = Case(p0=world_from_engine(v0), engine=v0, focus=F, coc=coc, cfg=dict(tile_size=2, selective_H=False))
        ties += check_conservative(case)["tile"].flat_stats["raster.tie_breaks"]
    assert ties > 0


def test_checker_detects_a_missing_sample():
    """The comparison is not vacuous: one hit turned into a miss is caught."""
    tri = SWEEP_TRIANGLES["crossing"]
    other = [world_from_pixel(2.0, 2.0, 3.0), world_from_pixel(30.0, 3.0, 3.0), world_from_pixel(16.0, 22.0, 3.0)]
    case = Case(p0=np.array([tri, other]), focus=F_SWEEP, coc=12.0)
    tbl = table("stratified")
    ref = render(case, "bruteforce", tbl)
    res = render(case, "tile", tbl)
    assert_same_samples(ref, res, case, tbl, "tile")
    res.sample_triangle = res.sample_triangle.copy()
    hit = np.argwhere(res.sample_triangle >= 0)[0]
    res.sample_triangle[tuple(hit)] = -1  # what a culled hit would look like
    with pytest.raises(pytest.fail.Exception, match="differs from bruteforce"):
        assert_same_samples(ref, res, case, tbl, "tile")


def test_conservative_subnormal_coc_laine():
    """Regression: a subnormal coc_px (float32 CoC 0: the 2D class) once made laine's h_i lines cull
    hits (found by hypothesis before subnormal floats were left out of the strategies)."""
    p0 = np.array([[[-1.104569499661587, 0.6903559372884918, -2.0], [-1.0355339059327378, 0.6903559372884918, -2.0],
                    [-0.5522847498307935, 0.4142135623730951, -1.0]]])
    for coc in (5e-324, 1e-310, 2e-308, 1e-300, 1e-45, 1e-40):
        case = Case(p0=p0, focus=1.0, coc=coc, lens="disk",
                    cfg=dict(tile_size=1, lens_grid=1, halfspace={"h": True, "H": False}, selective_H=False))
        check_conservative(case, ["laine", "tile", "interval"])


# A triangle collapsed onto a view ray (zero or ~1e-8 px projected area): a float sample test can hit
# its samples, also outside the setup bounds, and brute force and tile/laine must still agree.


@pytest.mark.parametrize("algorithm", ["tile", "laine"])
def test_segment_on_a_view_ray(algorithm):
    """A zero-area triangle: three points on the optical axis (one behind the camera). Brute force hits
    pixel (15, 11) sample 5 of stratified(spp=16, seed=5) at depth 0.1333 (tile's 2D test, in double,
    sees det == 0 and culls it); laine with 8-px tiles hits 118 samples brute force never tests."""
    case = Case(p0=np.array([[[0.0, 0.0, 1.0], [0.0, 0.0, -3.0], [0.0, 0.0, -0.21875]]]), focus=1.0, coc=0.0,
                cfg=dict(tile_size=8, lens_grid=1, halfspace={"h": False, "H": False}, selective_H=False))
    check_conservative(case, [algorithm])


def test_needle_towards_the_eye():
    """Found by hypothesis (degenerate strategy, slow run): a needle from depth 0.25 to 1.75 that
    projects to about pixel (0, 0); laine (8-px tiles) hits pixel (0, 5) sample 0 at depth 0.9667,
    five pixels away, where brute force (by its bounds) tests nothing."""
    p0 = np.array([[[-0.9664983122038886, 0.7248736651173227, -1.75], [-0.13807118745769836, 0.10355339059327377, -0.25],
                    [-0.8284271247461902, 0.6213202917829472, -1.5]]])
    assert on_one_view_ray(p0)
    case = Case(p0=p0, focus=1.0, coc=1.7591595078233144e-08,
                cfg=dict(tile_size=8, lens_grid=1, halfspace={"h": False, "H": False}, selective_H=False))
    check_conservative(case, ["laine"])
