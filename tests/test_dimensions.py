"""Dimension specialisation: the 2D/3D/4D kernels chosen in setup hit exactly (bitwise) the samples the general 5D kernel hits, triangles are classified as documented, and tables without a lens or time dimension classify triangles down.

Exactness is what sampletest/kernels.h promises: with a zero shear coefficient or a static vertex the
skipped steps are IEEE identities, so covered/hit/depth/w_hit must be bit-identical between
``probe(force_general=False)`` and ``probe(force_general=True)`` (no tolerance).
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import sim
from tests import reference as ref

pytestmark = pytest.mark.invariants

CLASS_2D, CLASS_3D, CLASS_4D, CLASS_5D = 0, 1, 2, 3
N_PER_CLASS = 150
POINTS = 300


def make_camera(rng, coc):
    return sim.Camera(width=int(rng.integers(32, 97)), height=int(rng.integers(32, 97)),
                      fov_y_deg=float(rng.uniform(30, 80)), focus_distance=float(rng.uniform(1.0, 12.0)),
                      coc_px=coc, lens=("disk", "square", "hexagon")[rng.integers(3)], near=0.05)


def triangle_of_class(rng, cls):
    """(camera, p0, p1) whose engine class is cls. In focus means W == F exactly for every vertex
    at both shutter ends (the default pose maps world z = -F to W = F exactly) or a pinhole."""
    pinhole = rng.random() < 0.3 and cls in (CLASS_2D, CLASS_3D)
    cam = make_camera(rng, 0.0 if pinhole else float(rng.uniform(0.5, 60.0)))
    F = cam.focus_distance
    kinds = ("plain", "crosses_focus", "behind_camera", "behind_near")
    p0, _ = ref.random_triangle(rng, cam, kinds[rng.integers(len(kinds))])
    if cls in (CLASS_2D, CLASS_3D) and not pinhole:
        p0[:, 2] = -F  # in the focus plane
    p1 = p0.copy()
    if cls in (CLASS_3D, CLASS_5D):
        size = np.ptp(p0[:, :2], axis=0).max() + 1e-3
        p1 = p0 + rng.normal(size=(3, 3)) * size * rng.uniform(0.05, 1.0)
        if cls == CLASS_3D and not pinhole:
            p1[:, 2] = -F
        if cls == CLASS_5D and rng.random() < 0.3:
            p1[:, 2] = p0[:, 2]  # moving sideways only, out of focus
    if cls == CLASS_4D and np.all(p0[:, 2] == -F):
        p0[0, 2] -= 1.0
        p1 = p0.copy()
    return cam, p0, p1


def tie_points(rng, cam, p0, p1, m):
    """Samples on the triangle's projected vertices and edge midpoints (float32), where the edge
    functions are zero or tiny and the top-left rule decides, at lens (0, 0) and t in {0, 1/2}."""
    pts = []
    for t in (0.0, 0.5):
        tri = ref.triangle_at(cam, p0, p1, np.array(t))
        w = -tri[:, 2]
        if np.any(w <= 0):
            continue
        s_x, s_y = ref.proj_scales(cam)
        x = (s_x * tri[:, 0] / w + 1.0) * cam.width / 2.0
        y = (1.0 - s_y * tri[:, 1] / w) * cam.height / 2.0
        xy = np.concatenate([np.stack([x, y], 1), (np.stack([x, y], 1) + np.roll(np.stack([x, y], 1), 1, 0)) / 2.0])
        for q in xy:
            pts.append([q[0], q[1], 0.0, 0.0, t])
    pts = np.array(pts, dtype=np.float32).reshape(-1, 5)
    return pts[:m]


def assert_identical(a, b, what):
    for key in ("covered", "hit"):
        assert np.array_equal(a[key], b[key]), f"{what}: {key} differs at {np.flatnonzero(a[key] != b[key])[:5]}"
    for key in ("depth", "w_hit"):
        x = np.asarray(a[key], np.float32).view(np.uint32)
        y = np.asarray(b[key], np.float32).view(np.uint32)
        assert np.array_equal(x, y), f"{what}: {key} not bitwise equal at {np.flatnonzero(x != y)[:5]}"


@pytest.mark.parametrize("cls", [CLASS_2D, CLASS_3D, CLASS_4D, CLASS_5D], ids=["2D", "3D", "4D", "5D"])
def test_specialised_kernel_equals_general_kernel(cls, rng, request):
    hits = samples = 0
    for i in range(N_PER_CLASS):
        cam, p0, p1 = triangle_of_class(rng, cls)
        pts = ref.sample_points(rng, cam, p0, p1, POINTS)
        pts = np.concatenate([pts, tie_points(rng, cam, p0, p1, 12)])
        fast = ref.engine_probe(cam, p0, p1, pts)
        general = ref.engine_probe(cam, p0, p1, pts, force_general=True)
        if fast["dim_class"] == -1:  # culled at the near plane: nothing to compare
            continue
        assert fast["dim_class"] == cls, f"triangle {i}: class {fast['dim_class']}, expected {cls}; {cam!r} p0={p0.tolist()} p1={p1.tolist()}"
        assert general["dim_class"] == cls
        assert_identical(fast, general, f"class {cls} triangle {i} {cam!r} p0={p0.tolist()} p1={p1.tolist()}")
        hits += int(fast["hit"].sum())
        samples += len(pts)
    request.node.user_properties.append(("hits", hits))
    request.node.user_properties.append(("samples", samples))
    assert hits > 0.05 * samples  # the comparison exercised covered samples


def test_grid_aligned_ties_identical():
    """Vertices on exact pixel positions and samples exactly on their edges: every kernel must take
    the same top-left decisions as the 5D kernel, for each class."""
    cam = sim.Camera(width=64, height=64, fov_y_deg=90.0, focus_distance=4.0, coc_px=16.0, near=0.05)
    pin = sim.Camera(width=64, height=64, fov_y_deg=90.0, focus_distance=4.0, coc_px=0.0, near=0.05)
    px = np.array([[10.0, 10.0], [30.0, 10.0], [10.0, 30.0]])
    a = ref.screen_to_world(cam, px[:, 0], px[:, 1], 4.0)  # at the focus plane
    b = ref.screen_to_world(cam, px[:, 0] + 6.0, px[:, 1] - 2.0, 4.0)  # moved by whole pixels
    deep = ref.screen_to_world(cam, px[:, 0], px[:, 1], 8.0)
    g = np.arange(8.0, 33.0, 0.5)
    xs, ys = np.meshgrid(g, g)
    pts = []
    for u, v in ((0.0, 0.0), (0.5, -0.25), (-1.0, 0.0)):
        for t in (0.0, 0.5, 0.75):
            pts.append(np.stack([xs.ravel(), ys.ravel(), np.full(xs.size, u), np.full(xs.size, v),
                                 np.full(xs.size, t)], 1))
    pts = np.concatenate(pts).astype(np.float32)
    for c, (camera, p0, p1, cls) in {
        "2D": (cam, a, a, CLASS_2D), "3D": (cam, a, b, CLASS_3D), "3D pinhole": (pin, deep, deep + 0.25, CLASS_3D),
        "4D": (cam, deep, deep, CLASS_4D), "5D": (cam, deep, b, CLASS_5D),
    }.items():
        fast = ref.engine_probe(camera, p0, p1, pts)
        general = ref.engine_probe(camera, p0, p1, pts, force_general=True)
        assert fast["dim_class"] == cls, c
        assert_identical(fast, general, c)
        assert fast["hit"].any() and not fast["hit"].all()
    # A sample on the shared diagonal of two triangles belongs to exactly one (watertight, 2D).
    quad = ref.screen_to_world(cam, [10.0, 30.0, 30.0, 10.0], [10.0, 10.0, 30.0, 30.0], 4.0)
    diag = np.stack([np.linspace(10, 30, 41), np.linspace(10, 30, 41), np.zeros(41), np.zeros(41), np.zeros(41)], 1)
    diag = diag.astype(np.float32)[1:-1]
    h1 = ref.engine_probe(cam, quad[[0, 1, 2]], quad[[0, 1, 2]], diag)["hit"]
    h2 = ref.engine_probe(cam, quad[[0, 2, 3]], quad[[0, 2, 3]], diag)["hit"]
    assert np.all(h1 ^ h2)


@pytest.mark.parametrize("has_lens,has_time", [(False, True), (True, False), (False, False)],
                         ids=["no_lens", "no_time", "neither"])
def test_table_without_dimension_classifies_down(has_lens, has_time, rng):
    """Without a lens dimension (every u = v = 0) 4D -> 2D and 5D -> 3D; without time (every t = 0)
    3D -> 2D and 5D -> 4D. The reduced kernel must equal both the general kernel and the full
    classification on those samples, bit for bit."""
    for cls in (CLASS_2D, CLASS_3D, CLASS_4D, CLASS_5D):
        want = cls
        if not has_lens:
            want = {CLASS_4D: CLASS_2D, CLASS_5D: CLASS_3D}.get(want, want)
        if not has_time:
            want = {CLASS_3D: CLASS_2D, CLASS_5D: CLASS_4D}.get(want, want)
        for i in range(40):
            cam, p0, p1 = triangle_of_class(rng, cls)
            pts = ref.sample_points(rng, cam, p0, p1, 200)
            if not has_lens:
                pts[:, 2:4] = 0.0
            if not has_time:
                pts[:, 4] = 0.0
            reduced = ref.engine_probe(cam, p0, p1, pts, has_lens=has_lens, has_time=has_time)
            if reduced["dim_class"] == -1:
                continue
            general = ref.engine_probe(cam, p0, p1, pts, has_lens=has_lens, has_time=has_time, force_general=True)
            full = ref.engine_probe(cam, p0, p1, pts)
            assert reduced["dim_class"] == want, f"class {cls} -> {reduced['dim_class']}, expected {want}"
            assert full["dim_class"] == cls
            assert_identical(reduced, general, f"class {cls} reduced vs general")
            assert_identical(reduced, full, f"class {cls} reduced vs full classification")


def _class_scene():
    cam = sim.Camera(width=48, height=48, fov_y_deg=45, focus_distance=5.0, coc_px=8.0, near=0.05)
    a = ref.screen_to_world(cam, [6, 20, 8], [6, 8, 20], 5.0)
    b = ref.screen_to_world(cam, [28, 42, 30], [6, 8, 20], 5.0)
    c = ref.screen_to_world(cam, [6, 20, 8], [28, 30, 42], 3.0)
    d = ref.screen_to_world(cam, [28, 42, 30], [28, 30, 42], 9.0)
    shift = np.array([0.2, -0.1, 0.0])
    p0 = np.array([a, b, c, d])
    p1 = np.array([a, b + shift, c, d + shift + [0, 0, 1.0]])
    return cam, SimpleNamespace(positions=p0, positions_t1=p1, colors=np.ones((4, 3, 3)))


@pytest.mark.parametrize("lens,time,expected", [
    (True, True, (1, 1, 1, 1)), (False, True, (2, 2, 0, 0)), (True, False, (2, 0, 2, 0)), (False, False, (4, 0, 0, 0)),
], ids=["full", "no_lens", "no_time", "neither"])
def test_render_class_counters(lens, time, expected):
    """One triangle of each class (2D, 3D, 4D, 5D); the setup counters follow the table's dimensions."""
    cam, scene = _class_scene()
    table = sim.SampleTable.stratified(spp=16, seed=5, lens=lens, time=time)
    res = sim.render(scene, cam, table, sim.PipelineConfig(threads=2))
    got = tuple(res.flat_stats[f"setup.class_{k}"] for k in ("2d", "3d", "4d", "5d"))
    assert got == expected


def test_no_lens_table_renders_like_a_pinhole():
    """A table without a lens dimension must give the pinhole image, bit for bit, whatever the CoC."""
    cam, scene = _class_scene()
    pin = sim.Camera(width=48, height=48, fov_y_deg=45, focus_distance=5.0, coc_px=0.0, near=0.05)
    table = sim.SampleTable.stratified(spp=16, seed=5, lens=False)
    a = sim.render(scene, cam, table, export_samples=True)
    b = sim.render(scene, pin, table, export_samples=True)
    assert np.array_equal(a.image, b.image)
    assert np.array_equal(a.sample_triangle, b.sample_triangle)
    # and the pinhole image is the ray caster's (independent check of the reduced path)
    pts = ref.table_points(table, cam)
    r = ref.compare_resolved(cam, scene.positions, scene.positions_t1, pts, a.sample_triangle, a.sample_depth)
    assert r["unexplained"] == 0 and r["depth_bad"] == 0 and r["covered"] > 0


def test_probe_reports_culled_near():
    cam = sim.Camera(width=32, height=32, coc_px=5.0, near=0.1)
    p = ref.screen_to_world(cam, [4, 20, 10], [4, 6, 20], 0.05)
    out = ref.engine_probe(cam, p, p, np.array([[10, 10, 0, 0, 0]], np.float32))
    assert out["dim_class"] == -1 and not out["covered"].any()
