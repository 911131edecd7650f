"""Blur-based level of detail ([Toth 2008] §7.2; [Tzeng 2012] §4.2).

Per object, a chain of simplified meshes (level 0 = the original; level k keeps about
``reduction**k`` of its triangles), built with fast-simplification (quadric edge collapse, the
library trimesh uses) and cached on disk by content hash. The level of each object is chosen from
its blur, as [Tzeng 2012] §4.2: s_lod = c_min / d_avg, with c_min the smallest CoC radius [px] over the
object's bounding box (0 when the box reaches the focus plane) and d_avg the screen length [px]
of the object's average edge placed at the box centre, parallel to the image plane. Level k's
average edge is about ``reduction**(-k/2)`` times longer, so the chosen level is the coarsest
whose edges stay within the blur: k = floor(2 log2(s_lod / s_min) / log2(1/reduction)), clamped
to [0, levels - 1]; s_lod < s_min keeps the original.

Objects are the connected components of the scene (triangles sharing a vertex position).
Objects smaller than ``min_triangles`` are never simplified. Vertex colours follow the collapses
(the mean colour of the original vertices merged into each new one). Textured and moving scenes
are kept as they are (the simplification does not carry uvs or motion): the report says so.

Use: ``scene2, report = models.lod.apply(scene, camera, PipelineConfig.lod)``; sim.render adds
``report.stats`` (the lod.* figures declared in sim/stats.py) to Result.flat_stats and the
per-object levels to Result.config["lod"]. The rast5d configs apply it when ``pipeline.lod.enabled``.
"""
from __future__ import annotations

import hashlib
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .scene import Scene, SceneError

MAX_LEVELS = 4


def cache_dir() -> Path:
    """Where simplified meshes are cached: $RAST5D_LOD_CACHE, else ~/.cache/rast5d/lod."""
    return Path(os.environ.get("RAST5D_LOD_CACHE", Path.home() / ".cache" / "rast5d" / "lod"))


@dataclass
class LodReport:
    stats: dict = field(default_factory=dict)
    objects: list = field(default_factory=list)  # per object: triangles, level, s_lod, c_min, d_avg


def check_params(lod: dict) -> dict:
    """The lod parameters with defaults; ValueError naming the key for bad values."""
    p = {"enabled": False, "levels": 3, "reduction": 0.5, "s_min": 1.0, "min_triangles": 64}
    for k, v in (lod or {}).items():
        if k not in p:
            raise SceneError(f"pipeline.lod.{k}: unknown key (known: {', '.join(p)})")
        p[k] = v
    if not isinstance(p["levels"], int) or not 1 <= p["levels"] <= MAX_LEVELS:
        raise SceneError(f"pipeline.lod.levels: expected an integer in 1..{MAX_LEVELS}, got {p['levels']!r}")
    if not 0.0 < float(p["reduction"]) < 1.0:
        raise SceneError(f"pipeline.lod.reduction: expected a fraction in (0, 1), got {p['reduction']!r}")
    if not float(p["s_min"]) > 0.0:
        raise SceneError(f"pipeline.lod.s_min: expected > 0, got {p['s_min']!r}")
    return p


def objects(positions: np.ndarray) -> np.ndarray:
    """Connected-component label per triangle (triangles sharing a vertex position), 0..n-1 in
    order of first appearance."""
    n = positions.shape[0]
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    _, vid = np.unique(positions.reshape(-1, 3), axis=0, return_inverse=True)
    vid = vid.reshape(n, 3)
    label = np.arange(vid.max() + 1)
    while True:
        tri = label[vid].min(axis=1)
        new = label.copy()
        np.minimum.at(new, vid.ravel(), np.repeat(tri, 3))
        new = new[new]  # pointer jumping
        if np.array_equal(new, label):
            break
        label = new
    comp = label[vid[:, 0]]
    _, first = np.unique(comp, return_index=True)
    order = np.argsort(np.argsort(first))
    return order[np.searchsorted(np.unique(comp), comp)]


def _indexed(pos: np.ndarray, col: np.ndarray):
    pts, inv = np.unique(pos.reshape(-1, 3), axis=0, return_inverse=True)
    inv = inv.reshape(-1)  # numpy 2.0.0 returns it as (n, 1) with axis=0
    faces = inv.reshape(-1, 3)
    vcol = np.zeros((pts.shape[0], 3))
    cnt = np.zeros(pts.shape[0])
    np.add.at(vcol, inv, col.reshape(-1, 3))
    np.add.at(cnt, inv, 1.0)
    return pts, faces, vcol / cnt[:, None]


def _simplify(pos: np.ndarray, col: np.ndarray, keep: float) -> tuple[np.ndarray, np.ndarray]:
    """(positions, colours) of the object simplified to about `keep` of its triangles, cached."""
    key = hashlib.sha256()
    key.update(np.ascontiguousarray(pos, dtype=np.float64).tobytes())
    key.update(np.ascontiguousarray(col, dtype=np.float64).tobytes())
    key.update(f"fast-simplification quadric keep={keep:.6f}".encode())
    path = cache_dir() / f"{key.hexdigest()}.npz"
    if path.exists():
        with np.load(path) as z:
            return z["positions"], z["colors"]
    import fast_simplification

    pts, faces, vcol = _indexed(pos, col)
    new_pts, new_faces, collapses = fast_simplification.simplify(
        pts, faces, target_reduction=1.0 - keep, return_collapses=True)
    _, _, mapping = fast_simplification.replay_simplification(pts, faces, collapses)
    ncol = np.zeros((new_pts.shape[0], 3))
    cnt = np.zeros(new_pts.shape[0])
    np.add.at(ncol, mapping, vcol)
    np.add.at(cnt, mapping, 1.0)
    ncol /= np.maximum(cnt, 1.0)[:, None]
    out_pos, out_col = new_pts[new_faces], ncol[new_faces]
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
    np.savez(tmp, positions=out_pos, colors=out_col)
    os.replace(tmp, path)
    return out_pos, out_col


def _view(camera, pts: np.ndarray) -> np.ndarray:
    """View depth w of world points (the camera's view transform)."""
    return camera.world_to_clip(pts)[..., 3]


def choose_level(s_lod: float, levels: int, reduction: float, s_min: float) -> int:
    if not s_lod >= s_min or levels <= 1:
        return 0
    k = math.floor(2.0 * math.log2(s_lod / s_min) / math.log2(1.0 / reduction))
    return int(min(max(k, 0), levels - 1))


def apply(scene: Scene, camera, lod: dict, textured: bool = False) -> tuple[Scene, LodReport]:
    """The scene with each object replaced by its chosen level, and the report. textured: the
    render reads the scene's textures (pipeline.texture_count > 0); the simplified meshes carry no
    uvs, so a textured render keeps the scene as it is."""
    p = check_params(lod)
    pos = np.asarray(scene.positions, dtype=np.float64)
    col = np.asarray(scene.colors, dtype=np.float64)
    report = LodReport()
    n = pos.shape[0]
    counts = [0] * MAX_LEVELS
    if not p["enabled"] or n == 0:
        report.stats = _stats(n, n, 0, counts)
        return scene, report  # nothing applied: sim.render adds no lod.* figures
    if not scene.is_static or (textured and scene.uvs is not None):
        counts[0] = n
        report.stats = _stats(n, n, 0, counts)
        report.objects.append({"object": "all", "triangles": n, "level": 0, "reason": "moving or textured: kept"})
        kept = scene._replace()
        kept.lod_report = report
        return kept, report
    labels = objects(pos)
    K = float(getattr(camera, "coc_px", 0.0) or 0.0)
    F = float(camera.focus_distance)
    focal_px = camera.height / (2.0 * math.tan(math.radians(camera.fov_y_deg) / 2.0))
    out_pos, out_col = [], []
    for obj in range(int(labels.max()) + 1):
        sel = labels == obj
        opos, ocol = pos[sel], col[sel]
        m = opos.shape[0]
        lo, hi = opos.reshape(-1, 3).min(axis=0), opos.reshape(-1, 3).max(axis=0)
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        w = _view(camera, corners)
        wc = float(_view(camera, (0.5 * (lo + hi))[None])[0])
        w_lo, w_hi = max(float(w.min()), 1e-9), max(float(w.max()), 1e-9)
        if w_lo <= F <= w_hi:
            c_min = 0.0
        else:
            c_min = min(K * abs(1.0 - F / w_lo), K * abs(1.0 - F / w_hi))
        edges = np.linalg.norm(opos - np.roll(opos, 1, axis=1), axis=2)
        d_avg = float(edges.mean()) * focal_px / max(wc, 1e-9)
        s_lod = c_min / d_avg if d_avg > 0 else 0.0
        level = choose_level(s_lod, p["levels"], float(p["reduction"]), float(p["s_min"]))
        if m < p["min_triangles"]:
            level = 0
        if level > 0:
            npos, ncol = _simplify(opos, ocol, float(p["reduction"]) ** level)
        else:
            npos, ncol = opos, ocol
        counts[level] += npos.shape[0]
        out_pos.append(npos)
        out_col.append(ncol)
        report.objects.append({"object": obj, "triangles": m, "submitted": int(npos.shape[0]), "level": level,
                               "s_lod": s_lod, "c_min_px": c_min, "d_avg_px": d_avg})
    new_pos = np.concatenate(out_pos)
    new_col = np.concatenate(out_col)
    report.stats = _stats(n, new_pos.shape[0], sum(1 for o in report.objects if o["level"] > 0), counts)
    new = Scene.from_arrays(new_pos, colors=new_col, name=scene.name, camera_hint=scene.camera_hint)
    new.lod_report = report
    return new, report


def _stats(n_in: int, n_out: int, simplified: int, counts: list) -> dict:
    s = {"lod.triangles_in": n_in, "lod.triangles": n_out, "lod.triangles_saved": n_in - n_out,
         "lod.objects_simplified": simplified}
    for k in range(MAX_LEVELS):
        s[f"lod.triangles_level{k}"] = counts[k]
    return s
