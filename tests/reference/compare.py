"""Engine against the ray caster: the engine-side probes, the float32 tolerances and their
conditioning, and the comparators of one triangle's samples and of a render's resolved samples.

Tolerances of a float32 engine against the float64 reference are explained in test_raycaster.py.
"""
from __future__ import annotations

import numpy as np

from sim import _core

from experiments.reference.probes import engine_params, engine_probe, lens_homogeneous  # noqa: F401
from experiments.reference.raycaster import (edge_distance_px, near_rel_distance, proj_scales, ray_cast,
                                             resolve_nearest, sample_rays, triangle_at)

def table_points(table, cam):
    """All samples of the image as absolute points (H, W, spp, 5) float32, pixel (px, py) using
    table entry [py mod P, px mod P]."""
    s = table.samples(cam.lens)
    P = s.shape[0]
    ys = np.arange(cam.height) % P
    xs = np.arange(cam.width) % P
    pts = s[ys[:, None], xs[None, :]].astype(np.float64)
    pts[..., 0] += np.arange(cam.width)[None, :, None]
    pts[..., 1] += np.arange(cam.height)[:, None, None]
    return pts.astype(np.float32)


# ----------------------------------------------------------------------------- tolerances

EDGE_TOL_PX = 1e-3
NEAR_TOL_REL = 1e-4
DEPTH_TOL_REL = 1e-5  # relative error of the hit depth w where the computation is well conditioned
EPS32 = 2.0 ** -24  # float32 unit roundoff
KAPPA_FACTOR = 8.0  # depth tolerance in units of eps32 * kappa where that exceeds DEPTH_TOL_REL
Z_ROUND = 2.0 ** -22  # float32 rounding of z = 1 - near / w (two ulps of 1)





def depth_condition(cam, p0, p1, points):
    """kappa >= 1 per sample: a first-order bound, in units of the float32 epsilon, of the relative
    error of the hit depth w computed in float32 from pixel-homogeneous vertices (X, Y, W) seen from
    the lens point (the shear of a vertex is (X - X_pinhole)). w = sum W_i e_i / sum e_i with the
    edge functions e_i = r_j x r_k of r_j = (X_j - sx W_j, Y_j - sy W_j); dw / de_i =
    (W_i - w) / sum e, and |de_i| <~ eps * (|r_j| magnitudes incl. the terms that cancel in r_j).
    Large where a vertex lies near the lens plane and the blur is large, or the view is grazing."""
    pts = np.asarray(points, dtype=np.float64)
    h, h0 = lens_homogeneous(cam, p0, p1, pts)
    sx, sy = pts[..., 0, None], pts[..., 1, None]
    X, Y, W = h[..., 0], h[..., 1], h[..., 2]
    rx, ry = X - sx * W, Y - sy * W
    # magnitudes of the terms that are added to form rx, ry (pinhole coordinate, shear, sx W)
    mx = np.abs(h0[..., 0]) + np.abs(X - h0[..., 0]) + np.abs(sx * W) + np.abs(rx)
    my = np.abs(h0[..., 1]) + np.abs(Y - h0[..., 1]) + np.abs(sy * W) + np.abs(ry)
    e = np.empty_like(W)
    b = np.empty_like(W)
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        e[..., i] = rx[..., j] * ry[..., k] - ry[..., j] * rx[..., k]
        b[..., i] = mx[..., j] * my[..., k] + my[..., j] * mx[..., k]
    s = e.sum(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        w = (W * e).sum(axis=-1) / s
        kappa = (np.abs(W - w[..., None]) * b).sum(axis=-1) / np.abs(s * w)
    return np.where(np.isfinite(kappa), np.maximum(kappa, 1.0), np.inf)


def depth_tolerances(cam, p0, p1, points, w_ref):
    """(relative tolerance of w, absolute tolerance of z) per sample: DEPTH_TOL_REL, widened to
    KAPPA_FACTOR eps32 kappa where the float32 computation is ill-conditioned (kappa from
    depth_condition; over 1,200 random triangles the worst error is 3.8 eps32 kappa, the median
    0.04 eps32 kappa)."""
    kappa = depth_condition(cam, p0, p1, points)
    tol_w = np.maximum(DEPTH_TOL_REL, KAPPA_FACTOR * EPS32 * kappa)
    with np.errstate(divide="ignore", invalid="ignore"):
        tol_z = (cam.near / np.abs(w_ref)) * tol_w + Z_ROUND
    return tol_w, tol_z


# ----------------------------------------------------------------------------- comparators


def compare_probe(cam, p0, p1, points):
    """Engine probe vs ray caster on one triangle: a dict of mismatch and depth-error facts.
    A hit mismatch is explained when the sample is within EDGE_TOL_PX of an edge line or within
    max(NEAR_TOL_REL, the depth tolerance of w) of the near plane (the engine decides "in front"
    from its own w, so the near-plane decision is as accurate as w); depth must agree within
    depth_tolerances where both hit."""
    eng = engine_probe(cam, p0, p1, points)
    ref = ray_cast(cam, p0, p1, points)
    mism = eng["hit"] != ref.hit
    edge = edge_distance_px(cam, p0, p1, points)
    near = near_rel_distance(cam, ref.w)
    tol_w, tol_z = depth_tolerances(cam, p0, p1, points, ref.w)
    near_tol = np.maximum(NEAR_TOL_REL, tol_w)
    explained = (edge < EDGE_TOL_PX) | (near < near_tol)
    both = eng["hit"] & ref.hit
    with np.errstate(divide="ignore", invalid="ignore"):
        w_err = np.abs(eng["w_hit"].astype(np.float64) - ref.w) / ref.w
    z_err = np.abs(eng["depth"].astype(np.float64) - ref.depth)
    depth_bad = both & ~((w_err <= tol_w) & (z_err <= tol_z))
    kappa = depth_condition(cam, p0, p1, points)
    return {
        "samples": len(points),
        "hits": int(ref.hit.sum()),
        "both": int(both.sum()),
        "mismatches": int(mism.sum()),
        "unexplained": int((mism & ~explained).sum()),
        "unexplained_idx": np.flatnonzero(mism & ~explained),
        "max_mismatch_edge_px": float(np.max(np.where(mism & (near >= near_tol), edge, 0.0), initial=0.0)),
        "max_mismatch_near_rel": float(np.max(np.where(mism & (edge >= EDGE_TOL_PX), near, 0.0), initial=0.0)),
        "near_mismatches_beyond_1e-4": int((mism & (edge >= EDGE_TOL_PX) & (near >= NEAR_TOL_REL)).sum()),
        "depth_bad": int(depth_bad.sum()),
        "depth_bad_idx": np.flatnonzero(depth_bad),
        "max_w_rel_err": float(np.max(w_err[both], initial=0.0)),
        "hits_w_err_above_tol_rel": int((w_err[both] > DEPTH_TOL_REL).sum()),
        "max_w_err_per_eps_kappa": float(np.max(w_err[both] / (EPS32 * kappa[both]), initial=0.0)),
        "max_z_abs_err": float(np.max(z_err[both], initial=0.0)),
        "eng": eng,
        "ref": ref,
        "edge": edge,
        "near": near,
    }


def compare_resolved(cam, positions, positions_t1, points, eng_triangle, eng_depth):
    """Resolved visibility of a render (eng_triangle, eng_depth (...)) vs the ray caster on the
    samples points (..., 5). A sample whose winning triangle differs is explained when it lies within
    EDGE_TOL_PX of an edge (or max(NEAR_TOL_REL, depth tolerance) of the near plane) of either
    triangle involved, or when
    the two triangles' reference depths are within the depth tolerance (a float32 depth tie).
    Where both pick the same triangle, z must agree within its tolerance."""
    ref_depth, ref_tri, rc = resolve_nearest(cam, positions, positions_t1, points)
    n = positions.shape[0]
    pts = np.asarray(points, dtype=np.float64)
    edge = np.stack([edge_distance_px(cam, positions[i], positions_t1[i], pts) for i in range(n)])
    near = near_rel_distance(cam, rc.w)
    tols = [depth_tolerances(cam, positions[i], positions_t1[i], pts, rc.w[i]) for i in range(n)]
    tol_w = np.stack([t[0] for t in tols])
    tol_z = np.stack([t[1] for t in tols])
    close = (edge < EDGE_TOL_PX) | (near < np.maximum(NEAR_TOL_REL, tol_w))  # (n, ...)

    def pick(a, idx):
        return np.take_along_axis(a, np.maximum(idx, 0)[None], axis=0)[0]

    e_tri = np.asarray(eng_triangle)
    mism = e_tri != ref_tri
    explained = np.zeros_like(mism)
    for idx in (e_tri, ref_tri):
        explained |= (idx >= 0) & pick(close, idx)
    both = (e_tri >= 0) & (ref_tri >= 0)
    z_e_ref = pick(np.where(rc.hit, rc.depth, np.inf), e_tri)
    with np.errstate(invalid="ignore"):
        gap = np.abs(z_e_ref - ref_depth)
    tie = both & np.isfinite(gap) & (gap <= pick(tol_z, e_tri) + pick(tol_z, ref_tri))
    explained |= tie
    same = (e_tri == ref_tri) & (ref_tri >= 0)
    with np.errstate(invalid="ignore"):
        z_err = np.where(same, np.abs(np.asarray(eng_depth, dtype=np.float64) - ref_depth), 0.0)
    depth_bad = same & ~(z_err <= pick(tol_z, ref_tri))
    return {
        "samples": int(mism.size),
        "covered": int((ref_tri >= 0).sum()),
        "mismatches": int(mism.sum()),
        "unexplained": int((mism & ~explained).sum()),
        "unexplained_idx": np.argwhere(mism & ~explained),
        "depth_ties": int((mism & tie).sum()),
        "depth_bad": int(depth_bad.sum()),
        "max_z_err": float(np.max(np.where(same, z_err, 0.0), initial=0.0)),
        "ref_triangle": ref_tri,
        "ref_depth": ref_depth,
    }


def check_resolved(request, label, cam, positions, positions_t1, table, result) -> dict:
    """Compare a render's resolved samples (export_samples=True) with the ray caster, record the
    figures on the test report, and fail on any mismatch away from an edge or the near plane or any
    depth outside tolerance. Returns compare_resolved's dict for further checks."""
    pts = table_points(table, cam)
    r = compare_resolved(cam, positions, positions_t1, pts, result.sample_triangle, result.sample_depth)
    for k in ("samples", "covered", "mismatches", "unexplained", "depth_ties", "depth_bad", "max_z_err"):
        request.node.user_properties.append((k, r[k]))
    bad = [tuple(int(v) for v in i) for i in r["unexplained_idx"][:5]]
    assert r["unexplained"] == 0, (
        f"{label}: {r['unexplained']} samples (py, px, s) differ from the ray caster away from edges: {bad}, "
        f"engine {[int(result.sample_triangle[i]) for i in bad]}, reference {[int(r['ref_triangle'][i]) for i in bad]}")
    assert r["depth_bad"] == 0, f"{label}: depth differs on {r['depth_bad']} samples (max |dz| {r['max_z_err']:.3g})"
    return r
