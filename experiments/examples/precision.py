"""Fixed-point precision of the 2D tile test and sample test (001 §7: "an efficient fixed-point
implementation"). For each viewport size (512 to 8192 px) and sub-pixel precision, the fewest integer bits
of a fixed-point datapath (core/fixed.h: vertices and samples snapped to frac_bits; registers of a sign,
int_bits integer and 2 frac_bits fraction bits, so the 2D set-up and edge functions are exact) that keep, on the hard-case suite
(tests/reference/hardcases.py, projected at each viewport, at the lens centre and the four lens-square
corners, both shutter ends):
  * every 2D tile test conservative against the float64 test of the unsnapped triangle, and
  * every affine sample test in agreement with the float64 test except within DELTA(frac_bits) of an edge,
with triangles clipped to the near plane and a guard band of one viewport on each side (as hardware
rasterizers clip before snapping). Writes reports/paper/precision.md (or prints with --print).

    python -m experiments.examples.precision
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import sim
from sim import _core

REPO = Path(__file__).resolve().parents[2]
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


def screen_triangles(V: int, seed: int = 0):
    """Screen-space triangles [px] of the hard-case suite at a V x V viewport: clipped to the near plane
    and to the guard band [-V, 2V], projected, fan-triangulated."""
    sys.path.insert(0, str(REPO))
    from tests.reference.hardcases import hard_cases

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
    tx0, ty0 = (lo // TILE).astype(int), (hi // TILE).astype(int)
    tiles = np.array([(x * TILE, x * TILE + TILE, y * TILE, y * TILE + TILE)
                      for x in range(tx0[0], ty0[0] + 1) for y in range(tx0[1], ty0[1] + 1)], dtype=np.float64)
    if len(tiles) > N_TILES:
        tiles = tiles[rng.choice(len(tiles), N_TILES, replace=False)]
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


def evaluate(tris, V, int_bits, frac_bits, seed=1):
    """(overflows, tile violations, tiles, sample disagreements beyond DELTA, samples, max disagreement
    distance [px], cull rate lost) over the triangles."""
    rng = np.random.default_rng(seed)
    ovf = viol = n_t = bad = n_s = lost = culled_ref = differ = 0
    dmax = 0.0
    for _name, tri in tris:
        pts, tiles = queries(tri, V, frac_bits, rng)
        r = _core.precision_probe_2d(tri, pts, tiles, int_bits, frac_bits)
        inside, dist, outside = reference(tri, pts, tiles)
        # a tile may be culled when it holds no point of the triangle farther than DELTA from its edges
        # (the snapped triangle misses it too: the sample criterion's DELTA)
        _, _, outside_shrunk = reference(tri, pts[:0], tiles, inset=delta(frac_bits))
        o_s, o_t = np.asarray(r["overflow_sample"]), np.asarray(r["overflow_tile"])
        ovf += int(o_s.sum() + o_t.sum())
        fo = np.asarray(r["tile_outside"])
        viol += int((fo & ~outside_shrunk).sum())
        lost += int((~fo & outside).sum())
        culled_ref += int(outside.sum())
        n_t += len(tiles)
        dis = np.asarray(r["inside"]) != inside
        if dis.any():
            dmax = max(dmax, float(dist[dis].max()))
        bad += int((dis & (dist > delta(frac_bits))).sum())
        differ += int(dis.sum())
        n_s += len(pts)
    return dict(overflows=ovf, tile_violations=viol, tiles=n_t, sample_bad=bad, samples=n_s, dmax=dmax,
                cull_lost=lost / max(culled_ref, 1), differ=differ / max(n_s, 1))


def safe(res) -> bool:
    return res["overflows"] == 0 and res["tile_violations"] == 0 and res["sample_bad"] == 0


def fewest_int_bits(tris, V, frac_bits, lo=4, hi=None):
    hi = 60 - 2 * frac_bits if hi is None else hi
    while lo < hi:
        mid = (lo + hi) // 2
        if safe(evaluate(tris, V, mid, frac_bits)):
            hi = mid
        else:
            lo = mid + 1
    return lo


ROWS = REPO / "results" / "precision_rows.json"  # finished (viewport, frac_bits) rows: a rerun resumes


def study():
    import json

    rows = json.loads(ROWS.read_text()) if ROWS.exists() else []
    done = {(r["viewport"], r["frac_bits"]) for r in rows}
    for V in VIEWPORTS:
        if all((V, F) in done for F in FRAC_BITS):
            continue
        tris = screen_triangles(V)
        for F in FRAC_BITS:
            if (V, F) in done:
                continue
            I = fewest_int_bits(tris, V, F)
            at = evaluate(tris, V, I, F)
            below = evaluate(tris, V, I - 2, F)
            rows.append(dict(viewport=V, frac_bits=F, int_bits=I, total_bits=1 + I + 2 * F, safe=safe(at), triangles=len(tris),
                             samples=at["samples"], tiles=at["tiles"], dmax=at["dmax"], differ=at["differ"],
                             cull_lost=at["cull_lost"],
                             below_overflows=below["overflows"], below_tile_violations=below["tile_violations"],
                             below_sample_bad=below["sample_bad"], below_samples=below["samples"],
                             below_tiles=below["tiles"]))
            print(rows[-1], flush=True)
            ROWS.parent.mkdir(exist_ok=True)
            ROWS.write_text(json.dumps(rows))
    rows.sort(key=lambda r: (r["viewport"], r["frac_bits"]))
    return rows


def markdown(rows, elapsed):
    out = ["# precision", "",
           "Made by `python -m experiments.examples.precision` (" + f"{elapsed:.0f} s" + "). Fixed-point "
           "instantiations (`core/fixed.h`) of the 2D edge set-up and 2D tile test (`tiletest/edges_2d.h`) "
           "and the affine sample test (`sampletest/hardware.h`), through `sim._core.precision_probe_2d`.",
           "",
           "## Fewest bits of the 2D tile test and sample test per viewport",
           "",
           "Format: vertices and samples snapped to `frac_bits` sub-pixel bits; every register a sign, `int_bits` "
           "integer and 2 `frac_bits` fraction bits (total bits = 1 + int_bits + 2 frac_bits), so the edge "
           "set-up's products and the affine edge functions are exact; no value may reach 2^int_bits. Workload: the hard-case suite "
           "(`tests/reference/hardcases.py`: vertices behind the camera, at the near plane, on the lens plane, "
           "gigantic coordinates, huge blur, degenerate and edge-on triangles) projected at each viewport, at the "
           "lens centre and the four lens-square corners and at both shutter ends, clipped to the near plane and "
           "to a guard band of one viewport on each side, fan-triangulated. Per triangle: 200 random samples in "
           "its on-screen bounds and 200 within 3 DELTA of its edges; up to 150 of the 8x8 tiles over its bounds. "
           "Safe = no overflow, every tile test conservative against float64 on the unsnapped triangle (a tile "
           "holding no point of the triangle farther than DELTA from its edges may be culled: the snapped "
           "triangle misses it too), every "
           "sample decision equal to float64 except within DELTA = 2^(1 - frac_bits) px of an edge. "
           "cudaraster (Laine & Karras 2011) snaps to 4 sub-pixel bits, the first anchor.",
           "",
           "| viewport [px] | frac_bits | fewest int_bits | total bits | triangles | samples | tiles | "
           "samples differing from float64 | max distance of a differing sample [px] | tile culls lost | "
           "int_bits - 2: values overflowing |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['viewport']} | {r['frac_bits']} | {r['int_bits']} | {r['total_bits']} | {r['triangles']} | "
                   f"{r['samples']} | {r['tiles']} | {100 * r['differ']:.3f} % | {r['dmax']:.4g} | "
                   f"{100 * r['cull_lost']:.3f} % | {r['below_overflows']} |")
    out += ["",
            "The integer bits grow by two per doubling of the viewport: the edge set-up's constant C = x_j y_k - "
            "y_j x_k is a product of two coordinates of the guard band [-V, 2V]. With fewer bits the set-up "
            "overflows (last column: the number of values that reach 2^int_bits; the probe flags them rather than "
            "wrapping, and a wrapped edge constant would make that triangle's tile and sample tests arbitrary). "
            "Samples differing from float64 lie within DELTA of an edge: they are the snapping of vertices and "
            "samples to the sub-pixel grid, do not depend on int_bits, and their distance shrinks 16x from 4 to 8 "
            "fraction bits (the share listed is of samples drawn within 3 DELTA of an edge, so it stays near 1 %); "
            "the image error "
            "of a fixed-point sample test is these samples. Tile culls lost: tiles float64 culls that the snapped "
            "triangle's test keeps (the cull rate lost to snapping).",
            "",
            "Not measured here: the depth stage (z in fixed point), the 4D/5D sample tests (vertices placed per "
            "sample) and the h_i / H_j tile tests, which run in float64 on widened tiles; renders do not yet take "
            "a per-stage precision parameter.", ""]
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--print", action="store_true", help="print instead of writing reports/paper/precision.md")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    rows = study()
    md = markdown(rows, time.perf_counter() - t0)
    if args.print:
        print(md)
    else:
        (REPO / "reports" / "paper" / "precision.md").write_text(md)
        print("wrote reports/paper/precision.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
