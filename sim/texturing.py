"""Texture inputs of the engine's texture unit (docs/shading.md): which textures each triangle's
shader reads, their uvs, procedural textures for scenes without any, and the sample-distribution
texture of [Toth 2008] §5.3. numpy only (the engine never imports models)."""
from __future__ import annotations

import functools

import numpy as np

from .errors import SceneInputError

MAX_SLOTS = 4


@functools.lru_cache(maxsize=16)
def procedural_texture(size: int, seed: int) -> np.ndarray:
    """A (size, size, 3) float32 texture in [0.5, 1]: 8x8-texel tiles of random tints with a
    texel-level random detail, so that every mip level has content. Deterministic in seed; made
    once per (size, seed) and shared, read-only."""
    return _readonly(_procedural_texture(size, seed))


def _readonly(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


def _procedural_texture(size: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(1000 + seed)
    tiles = -(-size // 8)
    tint = rng.uniform(0.6, 1.0, size=(tiles, tiles, 3))
    image = np.kron(tint, np.ones((8, 8, 1)))[:size, :size]
    detail = rng.uniform(0.85, 1.0, size=(size, size, 1))
    return np.ascontiguousarray(np.clip(image * detail, 0.5, 1.0), dtype=np.float32)


def planar_uvs(positions: np.ndarray, uv_per_unit: float) -> np.ndarray:
    """(N, 3, 2) uvs: each triangle projected on the coordinate plane most facing its normal,
    scaled by uv_per_unit (texture repeats per world unit)."""
    p = np.asarray(positions, dtype=np.float64)
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    axis = np.argmax(np.abs(normal), axis=1)  # dropped axis
    keep = np.array([[1, 2], [0, 2], [0, 1]])[axis]  # (N, 2)
    uv = np.take_along_axis(p, keep[:, None, :].repeat(3, axis=1), axis=2)
    return (uv * uv_per_unit).astype(np.float32)


def sample_distribution_texture(samples: np.ndarray) -> np.ndarray:
    """[Toth 2008] §5.3: the sample table's per-pixel random numbers as a texture, one texel per pixel of
    the table's P x P period (the lens position of sample 0, mapped to [0, 1])."""
    uv = samples[:, :, 0, 2:4]
    tex = np.zeros(uv.shape[:2] + (3,), np.float32)
    tex[..., :2] = 0.5 * (uv + 1.0)
    return tex


def texture_inputs(scene, positions: np.ndarray, colors: np.ndarray, config, samples: np.ndarray):
    """(uvs (N,3,2) | None, tex_slots (N,4) | None, textures [..], sample_dist_index, colors).

    Slot 0 reads the triangle's scene texture (pipeline.texture_source 'auto' or 'scene') and the
    vertex colour becomes white so that the texture replaces the colour baked from it; triangles
    without one read procedural texture 0 ('auto', 'procedural') or are untextured ('scene').
    Slots 1..texture_count-1 read procedural textures 1..3 (detail maps, multiplied in)."""
    n = positions.shape[0]
    count = config.texture_count
    textures: list[np.ndarray] = []
    if count == 0 and not config.texture_sample_distribution:
        return None, None, textures, -1, colors
    slots = np.full((n, MAX_SLOTS), -1, np.int32)
    uvs = None
    if count > 0:
        scene_tex = list(getattr(scene, "textures", None) or [])
        ids = getattr(scene, "texture_ids", None)
        ids = np.full(n, -1, np.int32) if ids is None or not scene_tex else np.asarray(ids, np.int32)
        if ids.shape != (n,):
            raise SceneInputError(f"scene.texture_ids: expected shape ({n},), got {ids.shape}")
        scene_uvs = getattr(scene, "uvs", None)
        if config.texture_source == "procedural" or scene_uvs is None:
            ids = np.full(n, -1, np.int32)
        planar = planar_uvs(positions, config.texture_uv_scale)
        if scene_uvs is not None:
            scene_uvs = np.asarray(scene_uvs, np.float32)
            if scene_uvs.shape != (n, 3, 2):
                raise SceneInputError(f"scene.uvs: expected shape ({n}, 3, 2), got {scene_uvs.shape}")
            uvs = np.where((ids >= 0)[:, None, None], scene_uvs, planar)
        else:
            uvs = planar
        for t in scene_tex:
            t = np.asarray(t, np.float32)
            if t.ndim == 2:
                t = t[..., None]
            textures.append(np.ascontiguousarray(t))
        n_proc = count if config.texture_source != "scene" else count - 1
        proc = []
        for k in range(max(n_proc, 0)):
            proc.append(len(textures))
            textures.append(procedural_texture(config.texture_procedural_size, k))
        has_scene = ids >= 0
        if config.texture_source == "scene":
            slots[:, 0] = ids
            for k in range(1, count):
                slots[:, k] = np.where(has_scene, proc[k - 1], -1)
        else:
            slots[:, 0] = np.where(has_scene, ids, proc[0])
            for k in range(1, count):
                slots[:, k] = proc[k]
        colors = np.where(has_scene[:, None, None], np.float32(1.0), colors).astype(np.float32)
    sample_dist = -1
    if config.texture_sample_distribution:
        sample_dist = len(textures)
        textures.append(sample_distribution_texture(samples))
        if uvs is None:
            uvs = np.zeros((n, 3, 2), np.float32)
    return uvs, slots, textures, sample_dist, colors
