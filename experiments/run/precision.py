from __future__ import annotations

import functools
import time

import numpy as np

import sim
from sim import _core

from ..reference import hard_cases
from .. import reference as ref
VIEWPORTS = (512, 1024, 2048, 4096, 8192)
FRAC_BITS = (4, 8)
TILE = 8
N_SAMPLES, N_EDGE_SAMPLES, N_TILES = 200, 200, 150


def cross2(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def delta(frac_bits: int) -> float:
    """Stated distance [px] from an edge within which a fixed-point sample test may disagree with
    float64: the vertex and sample snapping (half a grid step each way in x and y) plus the rounding
    of the edge set-up's products."""
    return 2.0 ** (1 - frac_bits)


def clip_polygon(poly: np.ndarray, planes) -> np.ndarray:
    """Sutherland-Hodgman in pixel-homogeneous space; planes are functions p -> signed value (>= 0 kept)."""
    for f in planes:
        if len(poly) == 0:
            break
        out = []
        for i in range(len(poly)):
            a, b = poly[i], poly[(i + 1) % len(poly)]
            fa, fb = f(a), f(b)
            if fa >= 0:
                out.append(a)
            if (fa >= 0) != (fb >= 0):
                out.append(a + (b - a) * (fa / (fa - fb)))
        poly = np.array(out)
    return poly


@functools.lru_cache(maxsize=8)
def screen_triangles(V: int, seed: int = 0):
    """Screen-space triangles [px] of the hard-case suite at a V x V viewport: clipped to the near plane
    and to the guard band [-V, 2V], projected, fan-triangulated."""
    tris = []
    for name, (cam_kw, p0, p1, _) in sorted(hard_cases().items()):
        scale = V / cam_kw["width"]
        cam = sim.Camera(**{**cam_kw, "width": V, "height": V, "coc_px": cam_kw["coc_px"] * scale})
        e = cam.engine_params()
        v0, v1 = cam.engine_vertices(p0, p1)
        for verts in (np.asarray(v0, np.float64), np.asarray(v1, np.float64)):
            for u, v in ((0, 0), (-1, -1), (1, -1), (-1, 1), (1, 1)):
                for t in verts.reshape(-1, 3, 3):
                    P = t.copy()
                    P[:, 0] += u * e["coc_x_px"] * (P[:, 2] - e["focus_w"])
                    P[:, 1] += v * e["coc_y_px"] * (P[:, 2] - e["focus_w"])
                    G = V
                    poly = clip_polygon(P, [lambda p: p[2] - e["near_w"],
                                            lambda p: p[0] + G * p[2], lambda p: (V + G) * p[2] - p[0],
                                            lambda p: p[1] + G * p[2], lambda p: (V + G) * p[2] - p[1]])
                    if len(poly) < 3:
                        continue
                    xy = poly[:, :2] / poly[:, 2:3]
                    for k in range(1, len(xy) - 1):
                        tri = np.array([xy[0], xy[k], xy[k + 1]])
                        area = 0.5 * abs(cross2(tri[1] - tri[0], tri[2] - tri[0]))
                        if area > 1e-3:
                            tris.append((name, tri))
    return tris


def edges64(tri):
    """float64 edge functions e_i(x, y) = A x + B y + C oriented inside >= 0."""
    A = np.array([tri[(i + 1) % 3][1] - tri[(i + 2) % 3][1] for i in range(3)])
    B = np.array([tri[(i + 2) % 3][0] - tri[(i + 1) % 3][0] for i in range(3)])
    C = np.array([tri[(i + 1) % 3][0] * tri[(i + 2) % 3][1] - tri[(i + 1) % 3][1] * tri[(i + 2) % 3][0]
                  for i in range(3)])
    s = np.sign(A[0] * tri[0][0] + B[0] * tri[0][1] + C[0])
    return A * s, B * s, C * s


def queries(tri, V, frac_bits, rng):
    """Sample points (random in the on-screen bounds + near the edges) and 8x8 tiles near the triangle."""
    lo = np.clip(tri.min(0), 0, V)
    hi = np.clip(tri.max(0), 0, V)
    pts = [lo + (hi - lo) * rng.random((N_SAMPLES, 2))]
    d = delta(frac_bits)
    for i in range(3):
        a, b = tri[i], tri[(i + 1) % 3]
        s = rng.random((N_EDGE_SAMPLES // 3, 1))
        n = np.array([-(b - a)[1], (b - a)[0]]) / max(np.hypot(*(b - a)), 1e-30)
        off = (rng.random((N_EDGE_SAMPLES // 3, 1)) * 2 - 1) * 3 * d
        pts.append(a + s * (b - a) + off * n)
    pts = np.concatenate(pts)
    pts = pts[(pts >= 0).all(1) & (pts <= V).all(1)]
    t0, t1 = (lo // TILE).astype(int), (hi // TILE).astype(int)
    nx, ny = t1[0] - t0[0] + 1, t1[1] - t0[1] + 1
    k = np.arange(nx * ny) if nx * ny <= N_TILES else rng.choice(nx * ny, N_TILES, replace=False)
    x, y = (t0[0] + k // ny) * TILE, (t0[1] + k % ny) * TILE
    tiles = np.stack([x, x + TILE, y, y + TILE], axis=1).astype(np.float64)
    return pts, tiles.reshape(-1, 4)


def reference(tri, pts, tiles, inset=0.0):
    """float64: inside (M,), distance to the nearest edge line (M,), and tile outside (K,) of the
    triangle with its edges moved inwards by `inset` px (an inset triangle that is empty culls every tile)."""
    A, B, C = edges64(tri)
    e = pts[:, :1] * A + pts[:, 1:] * B + C  # (M, 3)
    inside = (e >= 0).all(1)
    with np.errstate(divide="ignore", invalid="ignore"):
        dist = np.min(np.where(np.hypot(A, B) > 0, np.abs(e) / np.hypot(A, B), np.inf), axis=1)
    xs = np.where(A >= 0, tiles[:, 1:2], tiles[:, 0:1])
    ys = np.where(B >= 0, tiles[:, 3:4], tiles[:, 2:3])
    outside = ((A * xs + B * ys + C - inset * np.hypot(A, B)) < 0).any(1)
    if inset > 0:  # the inset triangle is empty when the inradius 2 area / perimeter is below inset
        area2 = abs(cross2(tri[1] - tri[0], tri[2] - tri[0]))
        perim = sum(np.hypot(*(tri[(i + 1) % 3] - tri[i])) for i in range(3))
        if area2 <= inset * perim:
            outside = np.ones(len(tiles), dtype=bool)
    return inside, dist, outside


def evaluate(tris, V, int_bits, frac_bits, seed=1, kind="fixed"):
    """One pass of the render's 2D kernels over the triangles: overflows, tile violations (culled tiles
    holding a point of the triangle farther than DELTA from its edges; float: any overlap), tiles, sample
    disagreements beyond DELTA (float: beyond EDGE_TOL_PX), samples, max disagreement distance [px], cull
    rate lost, share of samples differing, and the largest register magnitudes (set-up + tile test, sample)."""
    rng = np.random.default_rng(seed)
    ovf = viol = n_t = bad = n_s = lost = culled_ref = differ = 0
    dmax = max_t = max_s = 0.0
    d = delta(frac_bits) if kind == "fixed" else EDGE_TOL_PX
    for _name, tri in tris:
        pts, tiles = queries(tri, V, frac_bits, rng)
        r = _core.precision_probe_2d(tri, pts, tiles, int_bits, frac_bits, kind)
        inside, dist, outside = reference(tri, pts, tiles)
        _, _, outside_shrunk = reference(tri, pts[:0], tiles, inset=d if kind == "fixed" else 0.0)
        ovf += int(np.asarray(r["overflow_sample"]).sum() + np.asarray(r["overflow_tile"]).sum())
        max_t, max_s = max(max_t, r["max_abs_tile"]), max(max_s, r["max_abs_sample"])
        fo = np.asarray(r["tile_outside"])
        viol += int((fo & ~outside_shrunk).sum())
        lost += int((~fo & outside).sum())
        culled_ref += int(outside.sum())
        n_t += len(tiles)
        dis = np.asarray(r["inside"]) != inside
        if dis.any():
            dmax = max(dmax, float(dist[dis].max()))
        bad += int((dis & (dist > d)).sum())
        differ += int(dis.sum())
        n_s += len(pts)
    return dict(overflows=ovf, tile_violations=viol, tiles=n_t, sample_bad=bad, samples=n_s, dmax=dmax,
                cull_lost=lost / max(culled_ref, 1), differ=differ / max(n_s, 1), max_tile=max_t, max_sample=max_s)


EDGE_TOL_PX = 1e-3  # float32 engine against float64 (tests/test_raycaster.py)
PROBE_BITS = 60  # int_bits of the measuring pass (wide enough for every clipped triangle)


def guard_band_int_bits(V: int) -> int:
    """Closed-form int_bits of the 2D tile test and sample test for any triangle clipped to the guard band
    [-V, 2V] and samples and tiles on the V x V screen: relative coordinates |x_j - s_x| <= 2V, so every
    edge function is below 2 (2V)^2 = 8 V^2 and its partial sums (det, A x + B y + C) below 16 V^2 = 2^(4 + 2
    log2 V): registers must reach 2^(5 + 2 ceil(log2 V))."""
    return 5 + 2 * int(np.ceil(np.log2(V)))


def int_bits_for(max_abs: float) -> int:
    """The fewest integer bits n whose registers hold max_abs: max_abs < 2^n."""
    return max(1, int(np.floor(np.log2(max_abs))) + 1) if max_abs >= 1 else 1


@functools.lru_cache(maxsize=8)
def _hard_camera_list(V):
    return list(_hard_cameras_gen(V))


def _hard_cameras(V):
    return iter(_hard_camera_list(V))


def _hard_cameras_gen(V):
    """The hard cases at a V x V viewport, with their blur (4D, 5D) and in focus (coc 0: 2D, 3D)."""
    for name, (cam_kw, p0, p1, _) in sorted(hard_cases().items()):
        scale = V / cam_kw["width"]
        for coc in (cam_kw["coc_px"] * scale, 0.0):
            yield name, sim.Camera(**{**cam_kw, "width": V, "height": V, "coc_px": coc}), p0, p1


def _probe_4d(ref, cam, v0, tiles, cells=None, prec="float64"):
    """sim._core.precision_probe_4d of a triangle at camera cam on the GRID_4D lens grid, tile test in prec."""
    params = ref.engine_params(cam)
    params.lens_grid = GRID_4D
    params.precision_tile = prec
    return _core.precision_probe_4d(params, v0, tiles) if cells is None else _core.precision_probe_4d(params, v0, tiles, cells)


def _static_4d_cases(V):
    """(camera, triangle p0, engine vertices, lens vertices, in band) of each static defocused (4D) triangle
    of the hard cases at viewport V, as the render's 4D tile test sees it (lens grid GRID_4D); in band: the
    lens vertices lie within a guard band of one viewport (what a clipping datapath sees)."""
    for _name, cam, p0, _p1 in _hard_cameras(V):
        if cam.coc_px == 0.0:
            continue
        for i in range(p0.shape[0]):
            v0, _ = cam.engine_vertices(p0[i][None], p0[i][None])
            probe = _probe_4d(ref, cam, v0[0], np.zeros((0, 4)))
            if probe["dim_class"] != 2:  # static defocused (4D) only
                continue
            lv = np.asarray(probe["lens_vertices"])
            band = bool((np.abs(lv[:, :2] - V / 2) <= 1.5 * V).all() and (np.abs(lv[:, 2:]) <= V).all())
            yield cam, p0[i], v0[0], lv, band


CLASSES = ("2D", "3D", "4D", "5D")
N_PROBE = 600


# ----------------------------------------------------------------------------- the 4D tile test

FRAC_4D = (2, 4, 8)
TILE_4D, N_TILES_4D, GRID_4D = 2, 48, 4
CHECK_PAIRS, CHECK_POINTS = 150, 8


def _tiles_near(lv, V, rng):
    """Up to N_TILES_4D tiles of TILE_4D px on the screen over the footprint's extent seen from the lens."""
    ends = np.concatenate([lv[:, :2] - np.abs(lv[:, 2:]), lv[:, :2] + np.abs(lv[:, 2:])])
    lo = np.clip(ends.min(0) - TILE_4D, 0, V - TILE_4D)
    hi = np.clip(ends.max(0) + TILE_4D, lo + TILE_4D, V)
    x = np.floor(rng.uniform(lo[0], hi[0] - TILE_4D + 1, N_TILES_4D) / TILE_4D) * TILE_4D
    y = np.floor(rng.uniform(lo[1], hi[1] - TILE_4D + 1, N_TILES_4D) / TILE_4D) * TILE_4D
    return np.stack([x, x + TILE_4D, y, y + TILE_4D], axis=1)


def _ray_cast_hits(ref, cam, p0, tiles, culled, rng):
    """Culled (tile, lens cell) pairs checked with the float64 ray caster: random samples of the tile's
    pixels and the cell's lens points; returns (hits in front of the near plane, samples)."""
    pairs = np.argwhere(culled)
    if len(pairs) == 0:
        return 0, 0
    if len(pairs) > CHECK_PAIRS:
        pairs = pairs[rng.choice(len(pairs), CHECK_PAIRS, replace=False)]
    t = np.repeat(pairs[:, 0], CHECK_POINTS)
    c = np.repeat(pairs[:, 1], CHECK_POINTS)
    r = rng.random((len(t), 4))
    T = tiles[t]
    pts = np.stack([T[:, 0] + r[:, 0] * TILE_4D, T[:, 2] + r[:, 1] * TILE_4D,
                    -1.0 + (c % GRID_4D + r[:, 2]) * 2.0 / GRID_4D, -1.0 + (c // GRID_4D + r[:, 3]) * 2.0 / GRID_4D,
                    np.zeros(len(t))], axis=1)
    return int(ref.ray_cast(cam, p0, p0, pts).hit.sum()), len(t)


# ----------------------------------------------------------------------------- INTERVAL's box bounds

N_POINTS_BOX = 600


# ----------------------------------------------------------------------------- the motion tile tests

FRAC_5D = (2, 4, 8)
TILE_5D, SPLITS_5D, GRID_5D, N_POINTS_5D, N_RANDOM_5D = 2, 4, 4, 600, 16
MOTION_5D = np.array([0.6, -0.4, 1.5])  # world units: a sideways, receding move for the suite's static cases


def _motion_cases(V, rng):
    """Moving triangles at viewport V: every hard case moving (its own shutter-close positions, or moved by
    MOTION_5D: through the near plane, behind the camera, gigantic coordinates, huge blur...) with the suite's
    blur scaled with the viewport (5D) and in focus (3D), and N_RANDOM_5D motion_field-style triangles (random
    screen positions 20 % beyond the viewport, depths 0.3-20, motion up to a quarter of the viewport and 3
    depth units, some through the near plane) at CoC V / 32 and 0."""
    for name, cam, p0, p1 in _hard_cameras(V):
        if np.array_equal(p0, p1):
            p1 = p0 + MOTION_5D
        for i in range(p0.shape[0]):
            yield name, cam, p0[i], p1[i]
    for coc in (V / 32.0, 0.0):
        cam = sim.Camera(width=V, height=V, fov_y_deg=45.0, focus_distance=5.0, coc_px=coc, lens="square", near=0.1)
        for i in range(N_RANDOM_5D):
            w0 = rng.uniform(0.3, 20.0, 3)
            xy0 = rng.uniform(-0.2 * V, 1.2 * V, (3, 2))
            xy1 = xy0 + rng.uniform(-0.25, 0.25, 2) * V + rng.normal(0, 0.02 * V, (3, 2))
            w1 = np.maximum(w0 + rng.uniform(-3.0, 3.0, 3), 0.02)
            p0 = np.array([ref.screen_to_world(cam, x, y, d) for (x, y), d in zip(xy0, w0)])
            p1 = np.array([ref.screen_to_world(cam, x, y, d) for (x, y), d in zip(xy1, w1)])
            yield f"random_{i}", cam, p0, p1


def _probe_5d(ref, cam, v0, v1, tiles, pts, prec):
    params = ref.engine_params(cam)
    params.lens_grid, params.time_splits, params.halfspace_H5 = GRID_5D, SPLITS_5D, True
    params.precision_tile = prec
    return _core.precision_probe_5d(params, v0, v1, tiles, pts)




# ----------------------------------------------------------------------------- one point per row

def _prec(arithmetic: str, frac_bits, int_bits: int = PROBE_BITS):
    """pipeline.precision form of an arithmetic ('float32', 'float64', 'fixed' with frac_bits)."""
    return arithmetic if arithmetic != "fixed" else {"fixed": {"int_bits": int_bits, "frac_bits": frac_bits}}


def study_2d(V: int, arithmetic: str, frac_bits=None) -> dict:
    """The 2D tile test and the 2D sample test (sim._core.precision_probe_2d) on the hard-case suite
    projected at viewport V: in fixed point the fewest int_bits (one measuring pass), the check at that width
    and one bit below, and the closed-form guard-band width; in float32 the same check without a width."""
    tris = screen_triangles(V)
    if arithmetic == "float32":
        r = evaluate(tris, V, 0, 8, kind="float32")
        return dict(triangles=len(tris), samples=r["samples"], tiles=r["tiles"], dmax=r["dmax"], differ=r["differ"],
                    cull_lost=r["cull_lost"], tile_violations=r["tile_violations"], sample_bad=r["sample_bad"],
                    total_bits=32, safe=r["tile_violations"] == 0 and r["sample_bad"] == 0)
    F = int(frac_bits)
    wide = evaluate(tris, V, PROBE_BITS, F)
    it, is_ = int_bits_for(wide["max_tile"]), int_bits_for(wide["max_sample"])
    at = evaluate(tris, V, max(it, is_), F)
    below = evaluate(tris, V, max(it, is_) - 1, F)
    gb = guard_band_int_bits(V)
    at_gb = evaluate(tris, V, gb, F)
    return dict(int_bits_tile=it, int_bits_sample=is_, int_bits_bound=gb, bound_total_bits=1 + gb + 2 * F,
                bound_safe=at_gb["overflows"] == 0 and at_gb["tile_violations"] == 0 and at_gb["sample_bad"] == 0,
                total_bits=1 + max(it, is_) + 2 * F, triangles=len(tris),
                safe=at["overflows"] == 0 and at["tile_violations"] == 0 and at["sample_bad"] == 0,
                samples=at["samples"], tiles=at["tiles"], dmax=at["dmax"], differ=at["differ"],
                cull_lost=at["cull_lost"], tile_violations=at["tile_violations"], sample_bad=at["sample_bad"],
                below_overflows=below["overflows"])


def _class_of(cam, p0, p1) -> str:
    return ("2D", "3D", "4D", "5D")[2 * (cam.coc_px > 0) + (not np.array_equal(p0, p1))]


def study_nd(V: int, cls: str, arithmetic: str, frac_bits=None, seed: int = 3) -> dict:
    """The render's sample test (sim._core.precision_probe: vertices placed at each sample's (u, v, t)) on
    the hard cases of class ``cls`` at viewport V, against the float64 ray caster: samples, disagreements
    beyond the stated distance, the largest disagreement distance, and (fixed) the fewest int_bits over all
    samples and over those whose placed triangle lies in front of the near plane and in the guard band."""
    rng = np.random.default_rng(seed)
    F = None if arithmetic != "fixed" else int(frac_bits)
    a = dict(samples=0, bad=0, differ=0, dmax=0.0, max_all=0.0, max_clipped=0.0, clipped=0)
    for _name, cam, p0, p1 in _hard_cameras(V):
        for i in range(p0.shape[0]):
            pts = ref.sample_points(rng, cam, p0[i], p1[i], N_PROBE)  # every case draws: the same points per row
            if _class_of(cam, p0[i], p1[i]) != cls:
                continue
            pts64 = pts.astype(np.float64)
            rc = ref.ray_cast(cam, p0[i], p1[i], pts64)
            edge = ref.edge_distance_px(cam, p0[i], p1[i], pts64)
            near = ref.near_rel_distance(cam, rc.w)
            H, _ = ref.lens_homogeneous(cam, p0[i], p1[i], pts64)
            W = H[..., 2]
            with np.errstate(divide="ignore", invalid="ignore"):
                xy = H[..., :2] / W[..., None]
            clipped_ok = (W >= cam.near).all(-1) & (np.abs(xy - V / 2) <= 1.5 * V).all((-1, -2))
            v0, v1 = cam.engine_vertices(p0[i][None], p1[i][None])
            params = ref.engine_params(cam)
            params.precision_sample = _prec(arithmetic, F)
            r = _core.precision_probe(params, v0[0], v1[0], pts)
            if r["dim_class"] < 0:
                continue
            tol = delta(F) if F is not None else EDGE_TOL_PX
            mism = (np.asarray(r["covered"]) != rc.covered) & (near > 1e-3)
            a["samples"] += len(pts)
            a["differ"] += int((mism & (edge > EDGE_TOL_PX)).sum())
            a["bad"] += int((mism & (edge > tol)).sum())
            if mism.any():
                a["dmax"] = max(a["dmax"], float(edge[mism].max()))
            m = np.asarray(r["max_abs"])
            a["max_all"] = max(a["max_all"], float(m.max()))
            a["clipped"] += int(clipped_ok.sum())
            if clipped_ok.any():
                a["max_clipped"] = max(a["max_clipped"], float(m[clipped_ok].max()))
    out = dict(samples=a["samples"], sample_bad=a["bad"], differ=a["differ"] / max(a["samples"], 1),
               dmax=a["dmax"], in_band=a["clipped"] / max(a["samples"], 1))
    if F is not None:
        out.update(int_bits_all=int_bits_for(a["max_all"]), int_bits_band=int_bits_for(a["max_clipped"]))
    return out


def study_4d(V: int, arithmetic: str, frac_bits=None, seed: int = 5) -> dict:
    """The render's 4D tile test (h_i sets and H_j cells; sim._core.precision_probe_4d) on the static
    defocused triangles of the hard-case suite at viewport V (blur scaled with V), 2x2 tiles near each
    footprint, a 4x4 lens grid: lens cells culled in float64 and lost in the format, culled (tile, cell)
    pairs checked with the float64 ray caster (hits must be none), and (fixed) the fewest int_bits in band
    and over all triangles, and the overflows one bit below."""
    rng = np.random.default_rng(seed)
    F = None if arithmetic != "fixed" else int(frac_bits)
    cases = [(cam, p0, v0, _tiles_near(lv, V, rng), band) for cam, p0, v0, lv, band in _static_4d_cases(V)]
    check = np.random.default_rng((seed, 0 if F is None else F))
    a = dict(tiles=0, culled64=0, culled=0, lost=0, hits=0, checked=0, max_all=0.0, max_band=0.0)
    for cam, p0, v0, tiles, band in cases:
        r = _probe_4d(ref, cam, v0, tiles, prec=_prec(arithmetic, F))
        c, c64 = np.asarray(r["culled"]), np.asarray(r["culled64"])
        a["tiles"] += len(tiles)
        a["culled64"] += int(c64.sum())
        a["culled"] += int(c.sum())
        a["lost"] += int((c64 & ~c).sum())
        h, n = _ray_cast_hits(ref, cam, p0, tiles, c, check)
        a["hits"] += h
        a["checked"] += n
        if F is not None:
            a["max_all"] = max(a["max_all"], float(r["max_abs"]))
            if band:
                a["max_band"] = max(a["max_band"], float(r["max_abs"]))
    out = dict(triangles=len(cases), tiles=a["tiles"], culled64=a["culled64"],
               cull_lost=a["lost"] / max(a["culled64"], 1), checked=a["checked"], hits=a["hits"])
    if F is not None:
        ib = int_bits_for(a["max_all"])
        below = sum(int(np.asarray(_probe_4d(ref, cam, v0, tiles, prec=_prec("fixed", F, max(ib - 1, 1)))
                                   ["overflow"]).sum()) for cam, _p0, v0, tiles, _b in cases)
        band = int_bits_for(a["max_band"])
        out.update(int_bits_all=ib, int_bits_band=band, total_bits=1 + band + 2 * F, below_overflows=below)
    return out


def study_box(V: int, arithmetic: str, frac_bits=None, seed: int = 11) -> dict:
    """INTERVAL's (and INTERLEAVE's) screen bounds of a static defocused triangle over a lens box
    (tiletest/box_bounds.h; precision_4d.h box_bounds_in) on the static defocused hard cases at viewport V,
    the 16 cells of a 4x4 lens grid: how far the format moves the bounds outward (mean and largest, px), the
    float64 ray caster's hits outside their cell's bounds widened as a render widens them (must be none),
    and (fixed) the fewest int_bits in band and over all, and the overflows one bit below."""
    rng = np.random.default_rng(seed)
    F = None if arithmetic != "fixed" else int(frac_bits)
    step = 2.0 / GRID_4D
    cells = np.array([[-1 + i * step, -1 + (i + 1) * step, -1 + j * step, -1 + (j + 1) * step]
                      for j in range(GRID_4D) for i in range(GRID_4D)])
    cases = []
    for cam, p0, v0, _lv, band in _static_4d_cases(V):
        pts = ref.sample_points(rng, cam, p0, p0, N_POINTS_BOX).astype(np.float64)
        pts[:, 4] = 0.0
        rc = ref.ray_cast(cam, p0, p0, pts)
        hit = rc.hit & (ref.near_rel_distance(cam, rc.w) > 1e-3)
        ci = np.clip(np.floor((pts[:, 2] + 1) / step), 0, GRID_4D - 1).astype(int)
        cj = np.clip(np.floor((pts[:, 3] + 1) / step), 0, GRID_4D - 1).astype(int)
        cases.append((cam, v0, pts[hit], (cj * GRID_4D + ci)[hit], band))
    prec = _prec(arithmetic, F)
    a = dict(boxes=0, hits=0, outside=0, outside64=0, grow_sum=0.0, grow_max=0.0, max_all=0.0, max_band=0.0)
    for cam, v0, hp, hc, band in cases:
        r = _probe_4d(ref, cam, v0, np.zeros((0, 4)), cells, prec)
        b, b64 = np.asarray(r["box"]), np.asarray(r["box64"])
        grow = np.concatenate([b64[:, 0] - b[:, 0], b[:, 1] - b64[:, 1], b64[:, 2] - b[:, 2], b[:, 3] - b64[:, 3]])
        grow = grow[np.isfinite(grow)]
        a["boxes"] += len(cells)
        a["grow_sum"] += float(grow.sum())
        a["grow_max"] = max(a["grow_max"], float(grow.max()) if len(grow) else 0.0)
        snap = 2.0 ** (1 - F) if F is not None else 0.0
        for bb, key in ((b, "outside"), (b64, "outside64")):
            lo, hi = bb[hc][:, [0, 2]], bb[hc][:, [1, 3]]
            tol_lo = 2.0 ** -10 + snap + 2.0 ** -18 * np.abs(lo)
            tol_hi = 2.0 ** -10 + snap + 2.0 ** -18 * np.abs(hi)
            xy = hp[:, :2]
            a[key] += int(((xy < lo - tol_lo) | (xy > hi + tol_hi)).any(1).sum())
        a["hits"] += len(hp)
        if F is not None:
            a["max_all"] = max(a["max_all"], float(r["max_abs_box"]))
            if band:
                a["max_band"] = max(a["max_band"], float(r["max_abs_box"]))
    out = dict(triangles=len(cases), boxes=a["boxes"], hits=a["hits"], outside=a["outside"],
               outside64=a["outside64"], grow_mean=a["grow_sum"] / max(4 * a["boxes"], 1), grow_max=a["grow_max"])
    if F is not None:
        ib = int_bits_for(a["max_all"])
        below = sum(int(np.asarray(_probe_4d(ref, cam, v0, np.zeros((0, 4)), cells, _prec("fixed", F, max(ib - 1, 1)))
                                   ["box_overflow"]).sum()) for cam, v0, *_ in cases)
        band = int_bits_for(a["max_band"])
        out.update(int_bits_all=ib, int_bits_band=band, total_bits=1 + band + 2 * F, below_overflows=below)
    return out


def study_5d(V: int, cls: str, arithmetic: str, frac_bits=None, seed: int = 7) -> dict:
    """The render's motion tile tests (t̂ and 5D lens sets per time sub-interval, H5 cells; tile with
    motion_test intervals, time_splits 4, a 4x4 lens grid; sim._core.precision_probe_5d) on moving triangles
    of class ``cls`` (3D: in focus, 5D: blurred) at viewport V: samples the float64 ray caster hits that the
    format's region excludes (must be none; float64's own too), samples float64 excludes and the share the
    format keeps (cull lost), and (fixed) the fewest int_bits of t̂ with the lens sets and of H5, in band and
    over all, and the overflowing tests one bit below."""
    rng = np.random.default_rng(seed)
    F = None if arithmetic != "fixed" else int(frac_bits)
    cases = []
    for _name, cam, p0, p1 in _motion_cases(V, rng):
        pts = ref.sample_points(rng, cam, p0, p1, N_POINTS_5D).astype(np.float64)
        pts = pts[(pts[:, :2] >= 0).all(1) & (pts[:, :2] < V).all(1)]
        if len(pts) == 0 or ("5D" if cam.coc_px > 0 else "3D") != cls:
            continue
        x, y = np.floor(pts[:, 0] / TILE_5D) * TILE_5D, np.floor(pts[:, 1] / TILE_5D) * TILE_5D
        tiles = np.stack([x, x + TILE_5D, y, y + TILE_5D], axis=1)
        v0, v1 = cam.engine_vertices(p0[None], p1[None])
        v0, v1 = np.asarray(v0[0], np.float32), np.asarray(v1[0], np.float32)
        r64 = _probe_5d(ref, cam, v0, v1, tiles, pts, "float64")
        if "kept" not in r64:  # static (no motion left after projection) or culled at the near plane
            continue
        rc = ref.ray_cast(cam, p0, p1, pts)
        hit = rc.hit & (ref.near_rel_distance(cam, rc.w) > 1e-3)
        H = np.concatenate([v0, v1]).astype(np.float64)
        W = H[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            xy = H[:, :2] / W[:, None]
        band = bool((W >= cam.near).all() and (np.abs(xy - V / 2) <= 1.5 * V).all() and cam.coc_px <= V)
        cases.append((cam, v0, v1, tiles, pts, hit, band))
    prec = _prec(arithmetic, F)
    a = dict(samples=0, hits=0, culled64=0, lost=0, viol=0, viol64=0, max_all=0.0, max_band=0.0, max_all_h5=0.0,
             max_band_h5=0.0)
    for cam, v0, v1, tiles, pts, hit, band in cases:
        r = _probe_5d(ref, cam, v0, v1, tiles, pts, prec)
        kept, kept64 = np.asarray(r["kept"]), np.asarray(r["kept64"])
        a["samples"] += len(pts)
        a["hits"] += int(hit.sum())
        a["culled64"] += int((~kept64).sum())
        a["lost"] += int((kept & ~kept64).sum())
        a["viol"] += int((hit & ~kept).sum())
        a["viol64"] += int((hit & ~kept64).sum())
        if F is not None:
            for key, m in (("", float(r["max_abs"])), ("_h5", float(r["max_abs_h5"]))):
                a["max_all" + key] = max(a["max_all" + key], m)
                if band:
                    a["max_band" + key] = max(a["max_band" + key], m)
    out = dict(triangles=len(cases), samples=a["samples"], hits=a["hits"], culled64=a["culled64"],
               cull_lost=a["lost"] / max(a["culled64"], 1), outside=a["viol"], outside64=a["viol64"])
    if F is not None:
        ib = int_bits_for(max(a["max_all"], a["max_all_h5"]))
        below = sum(int(np.asarray(_probe_5d(ref, cam, v0, v1, tiles, pts, _prec("fixed", F, max(ib - 1, 1)))
                                   ["overflow"]).sum()) for cam, v0, v1, tiles, pts, *_ in cases)
        band, band_h5 = int_bits_for(a["max_band"]), int_bits_for(a["max_band_h5"])
        out.update(int_bits_all=int_bits_for(a["max_all"]), int_bits_all_h5=int_bits_for(a["max_all_h5"]),
                   int_bits_band=band, int_bits_band_h5=band_h5, total_bits=1 + max(band, band_h5) + 2 * F,
                   below_overflows=below)
    return out


STUDIES = {"2d": study_2d, "nd": study_nd, "4d": study_4d, "box": study_box, "5d": study_5d}


def study_render(config, threads) -> tuple[dict, object]:
    """The point's render in its pipeline.precision against the same render in the default precision:
    its counters, the image RMSE between the two, the samples whose visible triangle differs, and the
    default render's samples tested, 2D tiles and H5 cells culled."""
    from ..config import build

    scene, camera, table, pipeline = build(config)
    if threads is not None and config.pipeline.threads == 0:
        pipeline = pipeline.replace(threads=threads)
    default = pipeline.replace(precision=sim.PipelineConfig().precision)
    r = sim.render(scene, camera, table, pipeline, export_samples=True, timing=False)
    base = sim.render(scene, camera, table, default, export_samples=True, timing=False)
    b = base.flat_stats
    figures = dict(rmse=float(np.sqrt(np.mean((r.image - base.image) ** 2))),
                   samples_differ=int((r.sample_triangle != base.sample_triangle).sum()),
                   samples=int(r.sample_triangle.size), tested_base=int(b["raster.samples_tested"]),
                   culled_2d_base=int(b["tile.culled_2d"]), culled_H5_base=int(b["tile.H5_cells_culled"]))
    return figures, r


def precision_point(config, row, image_path, threads):
    """Point kind `precision`: one row of the numerical-precision study (docs/precision.md), chosen by
    point.options: study (2d, nd, 4d, box, 5d: the engine's kernels in an arithmetic against float64 and
    the ray caster on the hard-case suite at a viewport; render: the point's own render in its
    pipeline.precision against the default precision), viewport, arithmetic (float32, float64, fixed),
    frac_bits, cls (2D..5D). Its figures are numerics.* (sim/figures.py)."""
    from sim.figures import numerics

    opts = dict(config.point.options)  # keys and study checked by the schema (PRECISION_OPTIONS)
    study = opts.get("study")
    t0 = time.perf_counter()
    if study == "render":
        figures, result = study_render(config, threads)
        row.update(result.flat_stats)
    elif study in STUDIES:
        args = {k: opts[k] for k in ("viewport", "arithmetic", "frac_bits", "cls") if opts.get(k) is not None}
        if "viewport" not in args or "arithmetic" not in args:
            raise sim.ConfigError(f"point.options: study {study!r} needs viewport and arithmetic")
        if args["arithmetic"] not in ("float32", "float64", "fixed") or (args["arithmetic"] == "fixed") != (
                "frac_bits" in args):
            raise sim.ConfigError("point.options.arithmetic: 'float32', 'float64', or 'fixed' with frac_bits; got "
                                  f"{args['arithmetic']!r}, frac_bits {opts.get('frac_bits')!r}")
        figures = STUDIES[study](args.pop("viewport"), **args)
        result = None
    else:
        raise sim.ConfigError(f"point.options.study: expected one of {', '.join([*STUDIES, 'render'])}, got {study!r}")
    row.update(numerics(**figures))
    row["time.wall_s"] = time.perf_counter() - t0
    return result
