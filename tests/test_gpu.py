"""The conventional-GPU pipeline ([Toth 2008] §3-5, §9.6; [McGuire 2010]) and accumulation buffering ([Toth 2008] §2.2, §8):
bounds conservative against an independent numpy model of the sheared, moving triangle (random and
hypothesis-drawn triangles, adversarial classes), closed-form bound areas for a disc-of-confusion
triangle, the paper's orderings, every fallback counted, [Toth 2008] Table 2's float counts, the pixel
shader's work, and accumulation against INTERLEAVE counter for counter.

The same image as bruteforce for every gpu_* algorithm (and accumulation) on the hard cases and the
synthetic scenes comes from the registry-driven tests (test_invariants.py, test_hardcases.py)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import sim
from sim import _core
from tests.reference import make_scene, world_from_pixel

pytestmark = pytest.mark.invariants

METHODS = ("pe_triangle", "vr_triangle", "hexagon2d", "wedge", "reduced_wedge", "hexagon3d", "convex_hull",
           "adaptive")
GPU_ALGORITHMS = tuple(f"gpu_{m}" for m in METHODS)
SIZE = 64


def params(kx=6.0, ky=None, focus=4.0, near=0.1, width=SIZE, height=SIZE, **extra):
    p = _core.RenderParams()
    p.width, p.height = width, height
    p.coc_x_px, p.coc_y_px = kx, kx if ky is None else ky
    p.focus_w, p.near_w = focus, near
    p.table_has_lens = p.table_has_time = True
    for k, v in extra.items():
        setattr(p, k, v)
    return p


def homog(pts):
    """(3, 3) pixel positions and depths (x, y, W) -> pixel-homogeneous (X, Y, W) float32."""
    pts = np.asarray(pts, dtype=np.float64)
    return np.stack([pts[:, 0] * pts[:, 2], pts[:, 1] * pts[:, 2], pts[:, 2]], axis=1).astype(np.float32)


def screen_points(v0, v1, kx, ky, focus, near, rng, n=4000, disk=True):
    """Independent model (float64): screen positions of random points of the triangle at random
    (u, v, t), the lens point in the unit disk (or square); points behind the near plane dropped."""
    v0 = np.asarray(v0, dtype=np.float64)
    v1 = np.asarray(v1, dtype=np.float64)
    bary = rng.dirichlet((1, 1, 1), size=n)
    corners = np.eye(3)[rng.integers(0, 3, size=n // 4)]  # vertices and edges matter most
    bary[: n // 4] = corners
    edge = rng.uniform(size=n // 4)
    bary[n // 4: n // 2] = 0.0
    idx = rng.integers(0, 3, size=n // 4)
    bary[np.arange(n // 4, n // 2), idx] = edge
    bary[np.arange(n // 4, n // 2), (idx + 1) % 3] = 1.0 - edge
    t = rng.uniform(size=n)
    if disk:
        r, a = np.sqrt(rng.uniform(size=n)), rng.uniform(0, 2 * np.pi, size=n)
        r[: n // 2] = 1.0  # the rim
        u, v = r * np.cos(a), r * np.sin(a)
    else:
        u, v = rng.choice([-1.0, 1.0], size=n), rng.uniform(-1, 1, size=n)
    P = (1 - t)[:, None, None] * v0[None] + t[:, None, None] * v1[None]  # (n, 3 vertices, XYW)
    q = np.einsum("nj,njc->nc", bary, P)
    X = q[:, 0] + u * kx * (q[:, 2] - focus)
    Y = q[:, 1] + v * ky * (q[:, 2] - focus)
    keep = q[:, 2] >= near
    return np.stack([X[keep] / q[keep, 2], Y[keep] / q[keep, 2]], axis=1)


def assert_contains(bound, pts, what):
    planes = bound["planes"]
    # A triangle degenerate on screen (a segment) may get a zero-width slab of 2 planes from the 3D
    # methods; anything else is a bounded polygon. "Zero width" is relative to the segment's length:
    # float32 vertices leave a sliver of area about eps32 x length^2 (a 40-px segment: ~1e-6 px^2).
    x0, x1, y0, y1 = bound["box"]
    sliver = 8 * float(np.finfo(np.float32).eps) * ((x1 - x0) ** 2 + (y1 - y0) ** 2)
    assert planes.shape[0] >= 3 or (planes.shape[0] == 2 and bound["area"] <= sliver), what
    # Pixel-square test of the rasterizer = the point itself is enough here (the square contains it).
    excess = pts @ planes[:, :2].T - planes[:, 2][None, :]
    worst = float(excess.max()) if excess.size else -1.0
    assert worst <= 0.0, f"{what}: a hit lies {worst:.3g} outside the bound ({bound['used']}, {bound['fallback']})"


def random_triangle(rng, moving=False, cross_near=False):
    c = rng.uniform(-10, SIZE + 10, size=2)
    size = rng.uniform(0.5, 40)
    pts = np.column_stack([c[0] + size * rng.uniform(-1, 1, 3), c[1] + size * rng.uniform(-1, 1, 3),
                           4.0 * np.exp(rng.uniform(-1.2, 1.5, 3))])
    v0 = homog(pts)
    if cross_near:
        v0[0, 2] = rng.uniform(-2.0, 0.05)
    v1 = v0.copy()
    if moving:
        v1 = (v0 + rng.uniform(-8, 8, size=(3, 3)) * np.array([v0[:, 2], v0[:, 2], np.full(3, 0.1)]).T).astype(np.float32)
        v1[:, 2] = np.maximum(v1[:, 2], 0.2)
    return v0, v1


@pytest.mark.parametrize("method", METHODS)
def test_bounds_conservative_random(method, rng):
    """Every hit of random static, moving and near-crossing triangles at random lens points (disk
    and square lens sets) lies inside the bound."""
    kx = 6.0
    for trial in range(40):
        moving, cross = trial % 4 == 1, trial % 4 == 2
        v0, v1 = random_triangle(rng, moving=moving, cross_near=cross)
        disk = trial % 3 != 0
        p = params(kx=kx, ky=-kx * 0.75)
        b = _core.gpu_bound(method, p, v0, v1, disk)
        if b["culled"]:
            continue
        pts = screen_points(v0, v1, kx, -kx * 0.75, 4.0, 0.1, rng, disk=disk)
        assert_contains(b, pts, f"{method} trial {trial}")


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(xs=st.lists(st.floats(-40, 100), min_size=3, max_size=3), ys=st.lists(st.floats(-40, 100), min_size=3, max_size=3),
       ws=st.lists(st.floats(0.3, 60.0), min_size=3, max_size=3), kx=st.floats(0.0, 80.0),
       method=st.sampled_from(METHODS), seed=st.integers(0, 2**31))
@example(xs=[0.0, 0.0, 39.75], ys=[0.75, 0.75, 0.0], ws=[1.0, 1.500000238418579, 1.0], kx=0.0, method="wedge",
         seed=0)  # a screen segment whose float32 vertices leave a 7.9e-7 px^2 sliver
def test_bounds_conservative_hypothesis(xs, ys, ws, kx, method, seed):
    v0 = homog(np.column_stack([xs, ys, ws]))
    b = _core.gpu_bound(method, params(kx=kx), v0, v0, True)
    if b["culled"]:
        return
    pts = screen_points(v0, v0, kx, kx, 4.0, 0.1, np.random.default_rng(seed), n=800)
    assert_contains(b, pts, f"{method} hypothesis")


ADVERSARIAL = {
    # focus crossing: one vertex in front of, one on, one behind the focus plane
    "focus_crossing": [(5, 6, 2.0), (50, 9, 4.0), (24, 58, 14.0)],
    "vertex_on_focus_plane": [(30, 4, 4.0), (4, 50, 2.5), (60, 46, 11.0)],
    "huge_blur_sliver": [(10, 10, 1.0), (54, 11, 1.0), (32, 10.3, 1.0)],
    "sliver_across_focus": [(2, 30, 1.5), (62, 31, 30.0), (33, 30.2, 4.0)],
    "tiny_far": [(31, 31, 60.0), (31.4, 31, 60.0), (31, 31.3, 60.0)],
}


@pytest.mark.parametrize("case", sorted(ADVERSARIAL))
@pytest.mark.parametrize("method", METHODS)
def test_bounds_conservative_adversarial(method, case, rng):
    v0 = homog(ADVERSARIAL[case])
    for kx in (0.5, 8.0, 120.0):
        for disk in (True, False):
            b = _core.gpu_bound(method, params(kx=kx), v0, v0, disk)
            assert not b["culled"]
            assert_contains(b, screen_points(v0, v0, kx, kx, 4.0, 0.1, rng, disk=disk), f"{method} {case} kx={kx}")


def test_behind_camera_and_moving_fallbacks(rng):
    """[Toth 2008] §4.8: 2D methods fall back to clip-and-box across the near plane, 3D methods clip their
    volume; [Toth 2008]'s methods give moving triangles [McGuire 2010]'s hull; all counted and conservative."""
    v0 = homog([(10, 10, 3.0), (50, 14, 5.0), (30, 50, 8.0)])
    v0[0] = [0.4, -0.3, -1.0]  # behind the camera
    for method in ("pe_triangle", "vr_triangle", "hexagon2d", "convex_hull"):
        b = _core.gpu_bound(method, params(), v0, v0, True)
        assert b["fallback"] == "near" and b["used"] == "box", method
    for method in ("wedge", "hexagon3d", "reduced_wedge"):
        b = _core.gpu_bound(method, params(), v0, v0, True)
        assert b["volume_clipped"] and b["fallback"] in ("none", "reduced"), (method, b["fallback"])
        assert_contains(b, screen_points(v0, v0, 6.0, 6.0, 4.0, 0.1, rng), method)
    assert _core.gpu_bound("adaptive", params(), v0, v0, True)["used"] == "hexagon3d"
    s0 = homog([(10, 10, 3.0), (50, 14, 5.0), (30, 50, 8.0)])
    s1 = homog([(20, 12, 3.5), (58, 20, 5.0), (36, 60, 7.0)])
    for method in ("pe_triangle", "hexagon2d", "wedge", "hexagon3d"):
        b = _core.gpu_bound(method, params(), s0, s1, True)
        assert b["fallback"] == "motion" and b["used"] == "convex_hull", method
        assert_contains(b, screen_points(s0, s1, 6.0, 6.0, 4.0, 0.1, rng), method)
    assert _core.gpu_bound("convex_hull", params(), s0, s1, True)["fallback"] == "none"


def test_variable_radius_fallback_when_a_circle_encloses_another():
    """[Toth 2008] §4.6: no outer tangent when one confusion circle contains the other: the parallel-edge
    triangle, counted."""
    v0 = homog([(30, 30, 0.5), (31, 30, 4.0), (30, 31, 4.0)])  # one very blurry vertex next to two sharp
    b = _core.gpu_bound("vr_triangle", params(kx=10.0), v0, v0, True)
    assert b["fallback"] == "vr" and b["used"] == "pe_triangle"
    ok = homog([(10, 10, 3.0), (50, 14, 3.2), (30, 50, 3.4)])
    assert _core.gpu_bound("vr_triangle", params(kx=4.0), ok, ok, True)["fallback"] == "none"


def exterior_angles(q):
    q = np.asarray(q, dtype=np.float64)
    out = []
    for i in range(3):
        a, b, c = q[i - 1], q[i], q[(i + 1) % 3]
        d1, d2 = b - a, c - b
        cosang = d1 @ d2 / np.linalg.norm(d1) / np.linalg.norm(d2)
        out.append(math.acos(max(-1.0, min(1.0, cosang))))
    return np.array(out)


def test_closed_form_bound_area_disc_of_confusion_triangle():
    """A triangle parallel to the image plane has one disc of confusion of radius r = kx |1 - F / W|
    at every vertex. Closed forms: parallel-edge triangle A + P r + r^2 sum tan(phi_i / 2), hexagon
    A + P r + 2 r^2 sum tan(phi_i / 4) (phi_i the exterior angles); the 3D hexagon and wedge of a
    fronto-parallel triangle are flat and project to the same polygons."""
    q = np.array([(12.0, 9.0), (51.0, 17.0), (25.0, 55.0)])
    W, F, kx = 8.0, 4.0, 6.0
    v0 = homog(np.column_stack([q, np.full(3, W)]))
    r = kx * abs(1 - F / W)
    d1, d2 = q[1] - q[0], q[2] - q[0]
    A = 0.5 * abs(d1[0] * d2[1] - d1[1] * d2[0])
    P = sum(np.linalg.norm(q[(i + 1) % 3] - q[i]) for i in range(3))
    phi = exterior_angles(q)
    pe = A + P * r + r * r * np.tan(phi / 2).sum()
    hexa = A + P * r + 2 * r * r * np.tan(phi / 4).sum()
    got = {m: _core.gpu_bound(m, params(kx=kx, focus=F), v0, v0, True)["area"] for m in METHODS}
    assert got["pe_triangle"] == pytest.approx(pe, rel=1e-5)
    assert got["hexagon2d"] == pytest.approx(hexa, rel=1e-5)
    assert got["wedge"] == pytest.approx(pe, rel=1e-4)
    assert got["reduced_wedge"] == pytest.approx(pe, rel=1e-4)
    assert got["hexagon3d"] == pytest.approx(hexa, rel=1e-4)
    # equal radii: the variable-radius tangents are the parallel edges
    assert got["vr_triangle"] == pytest.approx(pe, rel=1e-5)


def test_paper_orderings(rng):
    """[Toth 2008]'s orderings: the hexagon is the tightest of its class (§4.4: inside the parallel-edge
    triangle in 2D, inside the wedge in 3D); the reduced wedge covers the wedge's screen area with
    fewer triangles (§4.5); the variable-radius triangle is not always tighter than the parallel-edge
    one (§4.6: both orders occur); with zero blur every bound fits the triangle exactly (§4.4, §4.5).
    Focus-crossing triangles around the focus plane ([Toth 2008] Fig. 6's narrow waist)."""
    vr_smaller = vr_larger = 0
    n = 0
    for _ in range(80):
        c = rng.uniform(10, 54, size=2)
        sz = rng.uniform(3, 20)
        pts = np.column_stack([c[0] + rng.uniform(-sz, sz, 3), c[1] + rng.uniform(-sz, sz, 3),
                               [rng.uniform(2.5, 3.8), rng.uniform(3.8, 4.2), rng.uniform(4.2, 6.0)]])
        v0 = homog(pts)
        a = {m: _core.gpu_bound(m, params(kx=10.0), v0, v0, True) for m in METHODS}
        assert a["hexagon2d"]["area"] <= a["pe_triangle"]["area"] * (1 + 1e-9)
        if a["reduced_wedge"]["fallback"] == "none":
            assert a["hexagon3d"]["area"] <= a["wedge"]["area"] * (1 + 1e-9)
            assert a["reduced_wedge"]["area"] == pytest.approx(a["wedge"]["area"], rel=1e-9)
            assert a["reduced_wedge"]["out_triangles"] <= 4 < a["wedge"]["out_triangles"]
        if a["vr_triangle"]["fallback"] == "none":
            vr_smaller += a["vr_triangle"]["area"] < a["pe_triangle"]["area"]
            vr_larger += a["vr_triangle"]["area"] > a["pe_triangle"]["area"]
        n += 1
        sharp = {m: _core.gpu_bound(m, params(kx=0.0), v0, v0, True)["area"] for m in METHODS}
        d1, d2 = pts[1, :2] - pts[0, :2], pts[2, :2] - pts[0, :2]
        area = 0.5 * abs(d1[0] * d2[1] - d1[1] * d2[0])
        for m in ("pe_triangle", "vr_triangle", "hexagon2d", "wedge", "reduced_wedge", "hexagon3d"):
            assert sharp[m] == pytest.approx(area, rel=1e-4), m
    assert n == 80 and vr_smaller > 0 and vr_larger > 0


@pytest.mark.parametrize("method,strip_vertices", [("hexagon2d", 6), ("hexagon3d", 22)])
def test_table2_constants_floats(method, strip_vertices):
    """[Toth 2008] Table 2 exactly: bump-mapped textured surface (35 constant floats per vertex): 2D hexagon
    234 / 164 / 59 output floats, 3D hexagon 858 / 788 / 123; interpolated floats per fragment 39
    without constants, 4 with."""
    want = {"hexagon2d": (234, 164, 59), "hexagon3d": (858, 788, 123)}[method]
    cam = sim.Camera(width=32, height=32, coc_px=4.0, focus_distance=5.0)
    p = world_from_pixel(16, 16, 5.0, 32, 32)
    tri = np.array([world_from_pixel(6, 6, 3.0, 32, 32), world_from_pixel(26, 8, 3.0, 32, 32),
                    world_from_pixel(14, 27, 3.0, 32, 32)])
    del p
    table = sim.SampleTable.stratified(spp=4, seed=1)
    got = []
    for constants in ("none", "triangle", "strip"):
        res = sim.render(make_scene([tri]), cam, table,
                         sim.PipelineConfig(algorithm=f"gpu_{method}", gpu_constants=constants, gpu_payload_floats=35,
                                            threads=1))
        s = res.flat_stats
        assert s["gpu.gs_triangles"] + 2 == strip_vertices
        got.append(s["gpu.gs_floats"])
        per_fragment = s["gpu.interp_floats"] / s["gpu.fragments"]
        assert per_fragment == (39 if constants == "none" else 4)
        # the perturbation-texture coordinate (2) and, without constants, the 4D shear constants (6)
        assert s["ops.ps_setup"] == (8 if constants == "none" else 2) * s["gpu.fragments"]
    assert tuple(got) == want


@pytest.mark.parametrize("constants", ["none", "triangle", "strip"])
def test_output_floats_follow_table2s_rules_from_the_emitted_geometry(constants):
    """Independent of the engine's float formula (checked against the paper's two rows above): [Toth 2008]
    Table 2's rules applied to the geometry each method emits, counted by the engine as strip triangles per
    input triangle. One strip per bound, so its strip vertices are triangles + 2; every strip vertex carries
    the 4 position floats; the payload goes on every strip vertex (no constants), once per emitted triangle
    (triangle constants) or once per strip (strip constants). Fails on any method whose floats do not follow
    the rules (a payload counted per vertex under triangle constants would be off by (V - T) x P per strip)."""
    payload = 35
    scene, cam = scene_and_camera()
    table = sim.SampleTable.stratified(spp=4, seed=2)
    for alg in GPU_ALGORITHMS:
        s = sim.render(scene, cam, table, sim.PipelineConfig(algorithm=alg, gpu_constants=constants,
                                                             gpu_payload_floats=payload, threads=1),
                       timing=False).flat_stats
        strips = s["gpu.gs_triangles_in"] - s["gpu.culled_bound"] if "gpu.culled_bound" in s else s["gpu.gs_triangles_in"]
        triangles = s["gpu.gs_triangles"]
        strip_vertices = triangles + 2 * strips
        per = {"none": strip_vertices * (4 + payload), "triangle": strip_vertices * 4 + triangles * payload,
               "strip": strip_vertices * 4 + strips * payload}[constants]
        assert s["gpu.gs_floats"] == per, (alg, constants, s["gpu.gs_floats"], per)


def test_accumulation_resolves_as_the_ray_caster(request):
    """Independent of INTERLEAVE (the comparison above is engine against engine): every sample of an
    accumulation render, each pass a pinhole render at its lens position and time, resolves to the triangle
    and depth the float64 ray caster finds at that sample, static and moving, away from edges and the near
    plane (tests/reference/compare.py)."""
    from tests import reference as ref

    scene, cam = scene_and_camera()
    table = sim.SampleTable.accumulation(passes=16, seed=5)
    moving = make_scene(scene.positions, scene.positions + np.array([0.3, -0.2, 0.0]))
    for label, moved in (("static", scene), ("moving", moving)):
        res = sim.render(moved, cam, table, sim.PipelineConfig(algorithm="accumulation", threads=1),
                         export_samples=True, timing=False)
        r = ref.check_resolved(request, f"accumulation {label}", cam, moved.positions, moved.positions_t1, table, res)
        assert r["covered"] > 0


def scene_and_camera():
    rng = np.random.default_rng(7)
    tris = []
    for _ in range(8):
        c = rng.uniform(4, 28, size=2)
        tris.append([world_from_pixel(*(c + rng.uniform(-9, 9, 2)), rng.uniform(2.0, 12.0), 32, 32) for _ in range(3)])
    return make_scene(np.array(tris)), sim.Camera(width=32, height=32, coc_px=5.0, focus_distance=5.0)


def test_pixel_shader_counts():
    """Every fragment runs spp sample tests in the pixel shader; fragments never exceed the pixels
    the rasterizer tested; fragments with a hit plus zero-hit fragments are all fragments; the
    fixed-function sample-test unit gets none of that work."""
    scene, cam = scene_and_camera()
    table = sim.SampleTable.stratified(spp=8, seed=2)
    for alg in GPU_ALGORITHMS:
        s = sim.render(scene, cam, table, sim.PipelineConfig(algorithm=alg, threads=1)).flat_stats
        assert s["gpu.ps_samples_tested"] == 8 * s["gpu.fragments"] == s["raster.samples_tested"], alg
        assert s["gpu.fragments"] <= s["gpu.raster_pixels_tested"]
        assert 0 <= s["gpu.fragments_zero_hit"] < s["gpu.fragments"]
        assert s["gpu.ps_ops"] == s["ops.sample_inside"] + s["ops.ps_setup"]
        assert s["timing.sample_test.work"] == 0 and s["timing.pixel_shader.work"] == s["gpu.ps_ops"]
        assert s["timing.geometry_shader.work"] == s["gpu.gs_ops"] > 0
        assert s["gpu.gs_triangles_in"] == s["setup.class_4d"] + s["setup.class_2d"]


def test_fallback_counters_in_renders():
    """A render counts each fallback cause; nothing is silently missed (same image as bruteforce)."""
    cam = sim.Camera(width=32, height=32, coc_px=4.0, focus_distance=5.0, near=0.1)
    front = np.array([world_from_pixel(4, 28, 3.0, 32, 32), world_from_pixel(28, 26, 3.0, 32, 32),
                      world_from_pixel(16, 4, 4.0, 32, 32)])
    crossing = front.copy()
    crossing[0] = [0.3, 0.3, 0.5]  # behind the camera
    moving0 = np.array([world_from_pixel(6, 6, 3.0, 32, 32), world_from_pixel(20, 8, 3.0, 32, 32),
                        world_from_pixel(10, 20, 3.0, 32, 32)])
    scene = make_scene(np.array([crossing, moving0]), np.array([crossing, moving0 + [0.3, 0.1, 0.0]]))
    table = sim.SampleTable.stratified(spp=8, seed=3)
    ref = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce", threads=1))
    for alg, want in [("gpu_hexagon2d", {"gpu.fallback_near": 1, "gpu.fallback_motion": 1}),
                      ("gpu_wedge", {"gpu.volume_clipped": 1, "gpu.fallback_motion": 1}),
                      ("gpu_convex_hull", {"gpu.fallback_near": 1, "gpu.fallback_motion": 0})]:
        res = sim.render(scene, cam, table, sim.PipelineConfig(algorithm=alg, threads=1))
        for k, v in want.items():
            assert res.flat_stats[k] == v, (alg, k, res.flat_stats[k])
        assert np.array_equal(res.image, ref.image), alg


# ---- accumulation buffering ----

def test_accumulation_table_is_the_same_in_every_pixel():
    t = sim.SampleTable.accumulation(passes=16, seed=3)
    assert t.spp == 16 and t.n_lens == 16
    s = t.samples("disk")
    assert np.array_equal(s, np.broadcast_to(s[:1, :1], s.shape))  # no per-pixel randomisation
    assert sorted(np.unique(t.lens_index)) == list(range(16))
    with pytest.raises(ValueError, match="passes"):
        sim.SampleTable.create("accumulation", spp=8, passes=4)
    with pytest.raises(ValueError, match="passes: expected an integer"):
        sim.SampleTable.accumulation(passes=0)
    # the time strata: one pass per 1/16 of the shutter
    assert sorted(np.floor(s[0, 0, :, 4] * 16).astype(int)) == list(range(16))


ACCUM_COUNTERS = {"accum.resends", "accum.vertex_ops", "accum.buffer_bytes"}


def test_accumulation_equals_interleave_counter_for_counter():
    """N = spp passes, one lens position per pass: the accumulation algorithm tests exactly
    INTERLEAVE's samples; every counter agrees except the per-pass pinhole triangle setup it adds
    (ops.setup: passes x the 2D edge setup per static triangle), what it repeats every pass after the
    first (accum.*: the vertex transform in ops.setup, the accumulation buffer's DRAM bytes) and the
    energy that follows from them."""
    scene, cam = scene_and_camera()
    table = sim.SampleTable.accumulation(passes=16, seed=5)
    a = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="accumulation", threads=1))
    i = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="interleave", threads=1))
    assert np.array_equal(a.image, i.image)
    sa, si = a.flat_stats, i.flat_stats
    static = si["setup.class_2d"] + si["setup.class_4d"]
    differ = {k for k in si if isinstance(si[k], (int, float)) and not (isinstance(si[k], float) and math.isnan(si[k]))
              and sa[k] != si[k] and not k.startswith(("time.", "timing.", "energy.")) and "ops" not in k}
    assert differ == {"accum.resends", "accum.buffer_bytes", "dram.bytes", "dram.bytes_color"}, differ  # + ops below
    assert sa["ops.setup"] - si["ops.setup"] == 16 * 28 * static + sa["accum.vertex_ops"]
    assert sa["raster.samples_tested"] == si["raster.samples_tested"] > 0
    assert sa["dram.bytes_color"] - si["dram.bytes_color"] == sa["accum.buffer_bytes"] > 0


@pytest.mark.parametrize("moving", [False, True])
def test_accumulation_charges_what_every_pass_repeats(moving):
    """docs/gpu.md "What a GPU repeats every pass", counted by hand from the scene and the table: per
    triangle (N - 1) re-sends, (N - 1) x 3 vertices x 16 ops (x 2 shutter ends when moving) of vertex
    shading, and 2 x 8 bytes per pixel and pass after the first for the accumulation buffer; the timing
    model's setup unit sets every triangle up N times, its shader ALUs do the vertex shading, DRAM moves the
    buffer. INTERLEAVE on the same table charges none of it (a method that leaves them out is caught)."""
    scene, cam = scene_and_camera()
    if moving:
        scene = make_scene(scene.positions, scene.positions + np.array([0.3, -0.2, 0.0]))
    n = 8
    table = sim.SampleTable.accumulation(passes=n, seed=5)
    res = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="accumulation", threads=2), keep_timing_records=True)
    s, recs = res.flat_stats, res.timing_records
    live = s["setup.class_2d"] + s["setup.class_3d"] + s["setup.class_4d"] + s["setup.class_5d"]
    assert live > 0 and s["trav.passes"] == n * live
    assert s["accum.resends"] == (n - 1) * live
    assert s["accum.vertex_ops"] == (n - 1) * live * 3 * 16 * (2 if moving else 1)
    assert s["accum.buffer_bytes"] == 32 * 32 * 2 * 8 * (n - 1)
    assert recs["triangles"].sum() == s["setup.triangles"] + s["accum.resends"]
    assert recs["gs_ops"].sum() == s["accum.vertex_ops"] == s["timing.geometry_shader.work"]
    assert recs["dram_color"].sum() == s["dram.bytes_color"] >= s["accum.buffer_bytes"]
    inter = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="interleave", threads=2)).flat_stats
    assert all(inter[k] == 0 for k in ACCUM_COUNTERS)
    assert s["timing.setup.work"] == inter["timing.setup.work"] + s["accum.resends"]


def test_ghosting_metric_separates_accumulation_from_stochastic():
    """Accumulation's error is coherent (ghosts: neighbouring pixels err alike); stratified
    stochastic error at the same spp is noise."""
    from experiments.run.metrics import ghosting

    scene, cam = scene_and_camera()
    cfg = sim.PipelineConfig(algorithm="tile", threads=1)
    ref = sim.render(scene, cam, sim.SampleTable.stratified(spp=512, seed=9), cfg).image
    acc = sim.render(scene, cam, sim.SampleTable.accumulation(passes=4, seed=9), cfg).image
    sto = sim.render(scene, cam, sim.SampleTable.stratified(spp=4, seed=9), cfg).image
    assert ghosting(acc, ref) > ghosting(sto, ref) + 0.08


def test_hexagon3d_of_a_triangle_in_the_focus_plane_is_conservative():
    """A triangle exactly in the focus plane gives a volume of zero thickness whose projected hull has
    coincident points; an edge between them has no reliable direction and must not cut the bound
    (found by the tile-invariant property test: 45 samples missed before)."""
    import types

    p = np.array([[[-0.8456750568001622, 0.44558117473960523, -1.0], [0.9595947528310035, 0.7076038693424638, -1.0],
                   [-0.4374421879961216, 0.29937100053842325, -1.0]]])
    scene = types.SimpleNamespace(positions=p, positions_t1=p, colors=None)
    cam = sim.Camera(width=32, height=24, fov_y_deg=45.0, focus_distance=1.0, coc_px=10.0, lens="disk", near=0.05)
    table = sim.SampleTable.random(spp=16, seed=5)
    out = {}
    for algo in ("bruteforce", "gpu_hexagon3d"):
        r = sim.render(scene, cam, table, sim.PipelineConfig(algorithm=algo, threads=1, tile_size=1, lens_grid=1),
                       export_samples=True)
        out[algo] = r.sample_triangle
    assert (out["bruteforce"] >= 0).sum() > 0
    assert np.array_equal(out["bruteforce"], out["gpu_hexagon3d"])


# ---- early depth ([Toth 2008] §9.7), the perturbation texture ([Toth 2008] §5.3), overdraw on screen ----

def occluded_scene(n=32):
    """A wall at depth 3 in front of defocused triangles at depth 6-9: most of their fragments lie
    behind the wall's stored depths."""
    rng = np.random.default_rng(11)
    d = 3.0
    tris = [[world_from_pixel(-8, -8, d, n, n), world_from_pixel(40, -8, d, n, n), world_from_pixel(-8, 40, d, n, n)],
            [world_from_pixel(40, -8, d, n, n), world_from_pixel(40, 40, d, n, n), world_from_pixel(-8, 40, d, n, n)]]
    for _ in range(10):
        c = rng.uniform(4, 28, size=2)
        tris.append([world_from_pixel(*(c + rng.uniform(-8, 8, 2)), rng.uniform(6.0, 9.0), n, n) for _ in range(3)])
    return make_scene(np.array(tris)), sim.Camera(width=n, height=n, coc_px=2.0, focus_distance=3.0)


@pytest.mark.parametrize("alg", GPU_ALGORITHMS)
def test_early_depth_rejects_hidden_fragments_before_the_pixel_shader(alg):
    """With HiZ ([Toth 2008] §9.7's depth interval) hidden fragments never reach the pixel shader: the image
    stays bruteforce's, the rasterized fragments are the same (shaded + depth-culled), each culled
    fragment saves spp pixel-shader sample tests, and the counting path agrees with the documented
    costs."""
    scene, cam = occluded_scene()
    table = sim.SampleTable.stratified(spp=8, seed=2)
    ref = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce", threads=1))
    off = sim.render(scene, cam, table, sim.PipelineConfig(algorithm=alg, threads=1)).flat_stats
    for tile in (1, 4):
        runs = [sim.render(scene, cam, table, sim.PipelineConfig(algorithm=alg, threads=1, op_count=oc, tile_size=tile,
                                                                 hiz={"enabled": True, "tile_size": tile}))
                for oc in ("documented", "exact")]
        for r in runs:
            assert np.array_equal(r.image, ref.image), (alg, tile)
        on, exact = runs[0].flat_stats, runs[1].flat_stats
        assert {k: on[k] for k in on if k.startswith("ops.")} == {k: exact[k] for k in exact if k.startswith("ops.")}
        culled = on["gpu.fragments_depth_culled"]
        assert culled > 0.3 * off["gpu.fragments"], (alg, tile, culled)
        assert on["gpu.fragments"] + culled == off["gpu.fragments"]
        assert on["zcull.samples_culled"] == 8 * culled
        assert off["gpu.ps_samples_tested"] - on["gpu.ps_samples_tested"] == 8 * culled
        assert on["gpu.raster_pixels_tested"] == off["gpu.raster_pixels_tested"]  # rasterized, then culled
        assert on["gpu.ps_ops"] < off["gpu.ps_ops"]
    # any thread count and bin size: the same counts
    other = sim.render(scene, cam, table, sim.PipelineConfig(algorithm=alg, threads=2, bin_size=16, tile_size=1,
                                                             hiz={"enabled": True, "tile_size": 4})).flat_stats
    four = sim.render(scene, cam, table, sim.PipelineConfig(algorithm=alg, threads=1, tile_size=1,
                                                            hiz={"enabled": True, "tile_size": 4})).flat_stats
    assert {k: v for k, v in other.items() if k.startswith(("gpu.", "ops.", "zcull.", "raster."))} == \
        {k: v for k, v in four.items() if k.startswith(("gpu.", "ops.", "zcull.", "raster."))}


def test_perturbation_texture_fetches_and_coordinates():
    """[Toth 2008] §5.3: every fragment computes its perturbation-texture coordinate (2 ops) and fetches one
    texel per sample; the texture unit of the timing model receives the fetches."""
    scene, cam = scene_and_camera()
    table = sim.SampleTable.stratified(spp=8, seed=2)
    for constants, rederive in (("none", 6), ("triangle", 0)):
        s = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="gpu_hexagon2d", threads=1,
                                                             gpu_constants=constants)).flat_stats
        assert s["setup.class_4d"] == s["gpu.gs_triangles_in"]  # every triangle defocused: 6-op re-derivation
        assert s["gpu.perturb_fetches"] == 8 * s["gpu.fragments"] > 0
        assert s["ops.ps_setup"] == (2 + rederive) * s["gpu.fragments"]
        assert s["timing.texture.work"] == s["tex.fetches"] + s["gpu.perturb_fetches"]


def pixels_meeting(planes, width, height, eps):
    """Pixels (px, py) on screen whose square [px, px + 1] x [py, py + 1] meets every half-plane
    n . p <= h (each widened by eps): independent of the engine's rasterizer."""
    ys, xs = np.mgrid[0:height, 0:width]
    ok = np.ones((height, width), dtype=bool)
    for nx, ny, h in planes:
        cx = xs + (1.0 if nx < 0 else 0.0)
        cy = ys + (1.0 if ny < 0 else 0.0)
        ok &= nx * cx + ny * cy <= h + eps
    return int(ok.sum())


def test_overdraw_is_the_bounds_area_on_screen_beyond_the_setup_box():
    """A GPU rasterizes the whole bounding polygon inside the viewport: a sliver's parallel-edge
    triangle spikes far beyond the triangle's screen bounds, and those pixels are fragments too
    (counted apart, no hit); pixels off screen are never generated. Fragments equal the on-screen
    pixels meeting the bound's half-planes (numpy, within a rounding band)."""
    n = 48
    from sim.render import _camera_params

    cam = sim.Camera(width=n, height=n, coc_px=3.0, focus_distance=5.0)
    pix = [(3.0, 30.0, 7.0), (45.0, 31.0, 7.0), (24.0, 30.6, 7.0)]  # an obtuse sliver: PE spikes off screen
    scene = make_scene(np.array([[world_from_pixel(x, y, w, n, n) for x, y, w in pix]]))
    table = sim.SampleTable.stratified(spp=4, seed=1)
    ref = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce", threads=1))
    for alg, method in (("gpu_pe_triangle", "pe_triangle"), ("gpu_hexagon2d", "hexagon2d")):
        r = sim.render(scene, cam, table, sim.PipelineConfig(algorithm=alg, threads=1))
        s = r.flat_stats
        assert np.array_equal(r.image, ref.image)
        b = _core.gpu_bound(method, _camera_params(cam), homog(pix), homog(pix), True)
        lo, hi = (pixels_meeting(b["planes"], n, n, e) for e in (-1e-3, 1e-3))
        assert lo <= s["gpu.fragments"] <= hi, (alg, lo, s["gpu.fragments"], hi)
        if method == "pe_triangle":
            assert b["vertices"][:, 0].min() < -100 and b["vertices"][:, 0].max() > n + 100  # spikes off screen
            assert s["gpu.fragments_outside_box"] > 5
        assert s["gpu.fragments_zero_hit"] >= s["gpu.fragments_outside_box"]
        assert s["gpu.ps_samples_tested"] == 4 * s["gpu.fragments"]


# ---- accumulation buffering of moving triangles ----

def moving_scene(n=32):
    rng = np.random.default_rng(5)
    t0, t1 = [], []
    for _ in range(10):
        c = rng.uniform(4, 28, size=2)
        tri = np.array([world_from_pixel(*(c + rng.uniform(-8, 8, 2)), rng.uniform(2.0, 10.0), n, n) for _ in range(3)])
        t0.append(tri), t1.append(tri + rng.uniform(-0.6, 0.6, 3))
    tri = np.array([world_from_pixel(10, 10, 3.0, n, n), world_from_pixel(20, 12, 3.0, n, n),
                    world_from_pixel(14, 22, 3.0, n, n)])
    t0.append(tri), t1.append(tri + [0.0, 0.0, 3.2])  # passes behind the eye late in the shutter
    return make_scene(np.array(t0), np.array(t1)), sim.Camera(width=n, height=n, coc_px=4.0, focus_distance=5.0,
                                                              near=0.1)


def test_accumulation_moves_each_triangle_to_its_pass():
    """Each accumulation pass is a pinhole render at one (u, v, t): moving triangles are placed at the
    pass's time and lens position and tested in 2D, with no conservative motion path; the image is
    bruteforce's with the same table and the counting path agrees with the documented costs. On an
    interleaved table (times differ per pixel) moving triangles take INTERLEAVE's conservative path."""
    scene, cam = moving_scene()
    table = sim.SampleTable.accumulation(passes=16, seed=5)
    ref = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce", threads=1))
    runs = [sim.render(scene, cam, table, sim.PipelineConfig(algorithm="accumulation", threads=1, op_count=oc))
            for oc in ("documented", "exact")]
    inter = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="interleave", threads=1)).flat_stats
    for r in runs:
        assert np.array_equal(r.image, ref.image)
    a, e = runs[0].flat_stats, runs[1].flat_stats
    assert {k: a[k] for k in a if k.startswith("ops.")} == {k: e[k] for k in e if k.startswith("ops.")}
    assert a["trav.motion_fallback"] == 0 and inter["trav.motion_fallback"] == 11
    assert a["raster.samples_tested"] == a["raster.samples_tested_2d"] > 0
    assert a["raster.samples_hit"] == ref.flat_stats["raster.samples_hit"]
    assert a["raster.samples_tested"] < inter["raster.samples_tested"]
    other = sim.SampleTable.create("interleaved", spp=16, n_lens=16, seed=4)
    ref2 = sim.render(scene, cam, other, sim.PipelineConfig(algorithm="bruteforce", threads=1))
    r2 = sim.render(scene, cam, other, sim.PipelineConfig(algorithm="accumulation", threads=1))
    assert np.array_equal(r2.image, ref2.image) and r2.flat_stats["trav.motion_fallback"] == 11


def test_accumulation_per_pass_motion_on_the_hard_cases():
    """The per-pass motion path on every moving hard case (behind the camera, crossing the near
    plane, focus crossing, degenerate...): per-sample winners and image equal bruteforce's with the
    accumulation table."""
    from types import SimpleNamespace

    from tests import reference as ref

    table = sim.SampleTable.accumulation(passes=16, seed=23)
    moving = {k: v for k, v in ref.hard_cases().items() if not np.array_equal(v[1], v[2])}
    assert len(moving) >= 2
    rng = np.random.default_rng(3)
    for name, (cam_kw, p0, p1, _counters) in sorted(moving.items()):
        scene = SimpleNamespace(positions=p0, positions_t1=p1, colors=rng.uniform(0.2, 1.0, p0.shape))
        cam = sim.Camera(**cam_kw)
        base = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="bruteforce", threads=1), export_samples=True)
        acc = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="accumulation", threads=2), export_samples=True)
        assert np.array_equal(acc.sample_triangle, base.sample_triangle), name
        assert np.array_equal(acc.image, base.image), name
