"""Scenes of the rasterizer's other uses ([Nilsson 2012] §4-§7) and of stochastic transparency ([McGuire 2010]):
overlapping transparent layers, moving simploids for the sampler, a plane over a plane under an
area light, a water surface over a pool floor, and a glossy floor under objects. The uses
themselves are in sim/uses/ (point kinds in experiments/run/uses.py)."""
from __future__ import annotations

from typing import Any

import numpy as np

from .registry import register_scene
from .scene import Scene, SceneError


def _positive(name: str, value: float) -> float:
    if not np.isfinite(value) or value <= 0:
        raise SceneError(f"{name}: expected a positive number, got {value!r}")
    return float(value)


def _rect(center, half_x, half_y, z) -> np.ndarray:
    """(2, 3, 3): an axis-aligned rectangle in the plane z, counter-clockwise seen from +z."""
    cx, cy = center
    a, b = (cx - half_x, cy - half_y, z), (cx + half_x, cy - half_y, z)
    c, d = (cx + half_x, cy + half_y, z), (cx - half_x, cy + half_y, z)
    return np.array([[a, b, c], [a, c, d]], dtype=np.float64)


# Default layers of transparent_layers: (centre x, centre y, depth, alpha, colour). Front to back in
# depth but submitted in a scrambled order (stochastic transparency is order independent). They hold
# the hard inputs: alpha exactly 0 (invisible), exactly 1 (opaque, hides what is behind it), and an
# opaque back wall.
_LAYERS = (
    (-0.35, 0.25, 2.4, 0.5, (0.95, 0.2, 0.15)),
    (0.30, 0.30, 2.8, 0.25, (0.15, 0.8, 0.2)),
    (0.05, -0.30, 2.6, 0.75, (0.2, 0.35, 0.95)),
    (0.45, -0.35, 2.2, 1.0, (0.95, 0.85, 0.2)),
    (-0.40, -0.40, 2.1, 0.0, (0.9, 0.9, 0.9)),
    (0.00, 0.05, 3.0, 0.4, (0.85, 0.3, 0.85)),
)


@register_scene("transparent_layers")
def transparent_layers(
    *,
    layers: Any = None,
    size: float = 0.9,
    tilted: bool = True,
    back_wall: bool = True,
    width: int = 128,
    height: int = 128,
    fov_y_deg: float = 45.0,
) -> Scene:
    """Overlapping transparent squares with per-triangle alpha (alpha 0, 1 and between), one tilted square cutting through another, an opaque back wall."""
    size = _positive("size", size)
    spec = _LAYERS if layers is None else layers
    tris, cols, alphas = [], [], []
    for i, layer in enumerate(spec):
        try:
            cx, cy, depth, alpha, colour = layer
        except (TypeError, ValueError):
            raise SceneError(f"layers[{i}]: expected (x, y, depth, alpha, (r, g, b)), got {layer!r}") from None
        r = _rect((float(cx), float(cy)), size / 2, size / 2, -_positive(f"layers[{i}].depth", depth))
        tris.append(r)
        cols += [colour, colour]
        alphas += [alpha, alpha]
    if tilted:  # cuts through the layer at depth 2.6: no order of whole primitives is right
        a = np.array([[-0.5, -0.1, -2.2], [0.6, -0.1, -3.0], [0.6, 0.45, -3.0]])
        tris.append(np.array([a, [a[0], a[2], [-0.5, 0.45, -2.2]]]))
        cols += [(0.1, 0.9, 0.9)] * 2
        alphas += [0.6, 0.6]
    if back_wall:
        tris.append(_rect((0.0, 0.0), 2.0, 2.0, -4.0))
        cols += [(0.25, 0.25, 0.25)] * 2
        alphas += [1.0, 1.0]
    scene = Scene.from_arrays(np.concatenate(tris), colors=np.asarray(cols, np.float64), name="transparent_layers")
    scene = scene.with_alpha(np.asarray(alphas, np.float64))
    return scene.with_camera_hint(width=width, height=height, fov_y_deg=fov_y_deg, focus_distance=3.0)


@register_scene("sampler_simploids")
def sampler_simploids(
    *,
    n: int = 6,
    depth: float = 3.0,
    motion: float = 0.35,
    seed: int = 1,
    width: int = 96,
    height: int = 96,
    fov_y_deg: float = 45.0,
) -> Scene:
    """Triangles at one depth whose vertices move independently in their plane: (2,1)-simploids in xyt ([Nilsson 2012] §5, Fig. 10), disjoint over the shutter."""
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 64:
        raise SceneError(f"n: expected an integer in 1..64, got {n!r}")
    depth = _positive("depth", depth)
    rng = np.random.default_rng(seed)
    half = depth * np.tan(np.radians(fov_y_deg) / 2.0)  # half the view's height at that depth
    side = int(np.ceil(np.sqrt(n)))
    cell = 1.8 * half / side
    p0, p1 = [], []
    for i in range(n):
        cx = -0.9 * half + (i % side + 0.5) * cell
        cy = 0.9 * half - (i // side + 0.5) * cell
        r = 0.22 * cell
        while True:  # every vertex its own motion (the area changes over the shutter), never flipping
            ang = np.sort(rng.uniform(0, 2 * np.pi, 3))
            base = np.stack([cx + r * np.cos(ang), cy + r * np.sin(ang), np.full(3, -depth)], axis=1)
            end = base.copy()
            end[:, :2] += rng.uniform(-1, 1, (3, 2)) * motion * r
            ts = np.linspace(0.0, 1.0, 65)[:, None, None]
            v = base[None, :, :2] + ts * (end - base)[None, :, :2]
            e1, e2 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
            area = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
            if np.all(area > 0.15 * r * r):
                break
        p0.append(base)
        p1.append(end)
    cols = rng.uniform(0.3, 1.0, (n, 3))
    scene = Scene.from_arrays(np.array(p0), colors=cols, positions_t1=np.array(p1), name="sampler_simploids")
    return scene.with_camera_hint(width=width, height=height, fov_y_deg=fov_y_deg, focus_distance=depth)


@register_scene("sampler_voids")
def sampler_voids(
    *,
    cells: int = 8,
    voids: int = 12,
    depth: float = 3.0,
    seed: int = 2,
    width: int = 96,
    height: int = 96,
    fov_y_deg: float = 45.0,
) -> Scene:
    """A square domain tessellated into cells x cells squares (two triangles each) with `voids` cells left out: a sample domain with voids ([Nilsson 2012] §5)."""
    if isinstance(cells, bool) or not isinstance(cells, int) or not 1 <= cells <= 64:
        raise SceneError(f"cells: expected an integer in 1..64, got {cells!r}")
    if isinstance(voids, bool) or not isinstance(voids, int) or not 0 <= voids < cells * cells:
        raise SceneError(f"voids: expected an integer in 0..{cells * cells - 1}, got {voids!r}")
    depth = _positive("depth", depth)
    half = 0.8 * depth * np.tan(np.radians(fov_y_deg) / 2.0)
    rng = np.random.default_rng(seed)
    holes = set(rng.choice(cells * cells, size=voids, replace=False).tolist())
    step = 2 * half / cells
    tris, cols = [], []
    for j in range(cells):
        for i in range(cells):
            if j * cells + i in holes:
                continue
            x0, y0 = -half + i * step, -half + j * step
            a, b, c, d = (x0, y0, -depth), (x0 + step, y0, -depth), (x0 + step, y0 + step, -depth), (x0, y0 + step, -depth)
            tris += [[a, b, c], [a, c, d]]
            cols += [(0.2 + 0.6 * i / cells, 0.3 + 0.6 * j / cells, 0.6)] * 2
    scene = Scene.from_arrays(np.array(tris), colors=np.array(cols), name="sampler_voids")
    return scene.with_camera_hint(width=width, height=height, fov_y_deg=fov_y_deg, focus_distance=depth)


@register_scene("shadow_planes")
def shadow_planes(
    *,
    occluder_height: float = 0.5,
    motion: float = 0.0,
    floor_size: float = 4.0,
    width: int = 96,
    height: int = 96,
) -> Scene:
    """A floor (y = 0) under a 1 x 1.2 plate at occluder_height whose right edge lies on x = 0, the plate moving by `motion` along +x over the shutter: plane over plane for soft shadows ([Nilsson 2012] §7)."""
    h = _positive("occluder_height", occluder_height)
    f = _positive("floor_size", floor_size) / 2
    floor = np.array([[(-f, 0, -f), (-f, 0, f), (f, 0, f)], [(-f, 0, -f), (f, 0, f), (f, 0, -f)]], np.float64)
    plate = np.array([[(-1.0, h, -0.6), (-1.0, h, 0.6), (0.0, h, 0.6)],
                      [(-1.0, h, -0.6), (0.0, h, 0.6), (0.0, h, -0.6)]], np.float64)
    p0 = np.concatenate([floor, plate])
    p1 = p0.copy()
    p1[2:, :, 0] += float(motion)
    cols = np.array([(0.8, 0.8, 0.75)] * 2 + [(0.85, 0.3, 0.2)] * 2)
    scene = Scene.from_arrays(p0, colors=cols, positions_t1=p1, name="shadow_planes")
    return scene.with_camera_hint(width=width, height=height, fov_y_deg=50.0, focus_distance=4.0,
                                  eye=(0.3, 3.0, 3.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), near=0.05)


def water_height(x, z, amplitude: float, seed: int = 0):
    """A procedural water surface: the sum of a few sine waves (height and its x, z derivatives)."""
    rng = np.random.default_rng(seed)
    h = np.zeros_like(x, dtype=np.float64)
    hx = np.zeros_like(h)
    hz = np.zeros_like(h)
    for k in range(5):
        ang = rng.uniform(0, 2 * np.pi)
        freq = rng.uniform(8.0, 16.0)
        phase = rng.uniform(0, 2 * np.pi)
        a = amplitude / (k + 1)
        kx, kz = freq * np.cos(ang), freq * np.sin(ang)
        arg = kx * x + kz * z + phase
        h += a * np.sin(arg)
        hx += a * kx * np.cos(arg)
        hz += a * kz * np.cos(arg)
    return h, hx, hz


@register_scene("water_caustics")
def water_caustics(
    *,
    grid: int = 72,
    size: float = 2.0,
    water_level: float = 1.0,
    amplitude: float = 0.025,
    ior: float = 1.33,
    seed: int = 0,
    view: str = "oblique",
    width: int = 128,
    height: int = 128,
) -> Scene:
    """Caustic volumes ([Nilsson 2012] §4): generator triangles of a procedural water surface (t = 0) and their ends on the pool floor y = 0 (t = 1), light straight down, refracted per vertex; grid x grid x 2 volumes."""
    if isinstance(grid, bool) or not isinstance(grid, int) or not 1 <= grid <= 512:
        raise SceneError(f"grid: expected an integer in 1..512, got {grid!r}")
    if view not in ("oblique", "top"):
        raise SceneError(f"view: expected 'oblique' or 'top', got {view!r}")
    size, water_level, ior = _positive("size", size), _positive("water_level", water_level), _positive("ior", ior)
    g = np.linspace(-size / 2, size / 2, grid + 1)
    X, Z = np.meshgrid(g, g, indexing="xy")
    h, hx, hz = water_height(X, Z, float(amplitude), seed)
    top = np.stack([X, water_level + h, Z], -1)
    n = np.stack([-hx, np.ones_like(h), -hz], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    d = np.array([0.0, -1.0, 0.0])  # light direction
    eta = 1.0 / ior  # Snell: air into water
    cos_i = -(n @ d)
    k = 1.0 - eta ** 2 * (1.0 - cos_i ** 2)
    r = eta * d + (eta * cos_i - np.sqrt(k))[..., None] * n
    bottom = top + (top[..., 1] / -r[..., 1])[..., None] * r  # to the floor y = 0
    bottom[..., 1] = 0.0

    def tris(P):
        a, b, c, dd = P[:-1, :-1], P[:-1, 1:], P[1:, 1:], P[1:, :-1]
        return np.concatenate([np.stack([a, b, c], 2).reshape(-1, 3, 3), np.stack([a, c, dd], 2).reshape(-1, 3, 3)])

    p0, p1 = tris(top), tris(bottom)
    cols = np.full((len(p0), 3), (0.6, 0.8, 1.0))
    scene = Scene.from_arrays(p0, colors=cols, positions_t1=p1, name="water_caustics")
    if view == "top":  # looking straight down: the beams run along the view direction
        hint = dict(eye=(0.0, 4.0, 0.0), target=(0.0, 0.0, 0.0), up=(0.0, 0.0, -1.0), fov_y_deg=35.0)
    else:
        hint = dict(eye=(0.0, 2.4, 3.2), target=(0.0, 0.45, 0.0), up=(0.0, 1.0, 0.0), fov_y_deg=45.0)
    return scene.with_camera_hint(width=width, height=height, focus_distance=3.0, near=0.05, **hint)


@register_scene("glossy_floor")
def glossy_floor(
    *,
    below: bool = False,
    width: int = 128,
    height: int = 96,
) -> Scene:
    """A glossy floor (y = 0, x in [-1.5, 1.5], z in [-3, 0]) under standing triangles at several heights and a striped back wall (below: all of it 1.6 under the surface, for refraction): planar glossy reflections and refractions ([Nilsson 2012] §6)."""
    floor = np.array([[(-1.5, 0, -3.0), (-1.5, 0, 0.0), (1.5, 0, 0.0)],
                      [(-1.5, 0, -3.0), (1.5, 0, 0.0), (1.5, 0, -3.0)]], np.float64)
    tris = [floor]
    cols = [(0.15, 0.15, 0.18)] * 2
    objects = [  # standing triangles: (x0, x1, z, bottom, top, colour)
        (-1.1, -0.5, -1.2, 0.0, 0.7, (0.9, 0.2, 0.15)),
        (-0.2, 0.4, -1.8, 0.25, 0.9, (0.2, 0.8, 0.3)),
        (0.6, 1.2, -1.0, 0.5, 1.0, (0.2, 0.35, 0.95)),
    ]
    for x0, x1, z, b, t, c in objects:
        tris.append(np.array([[(x0, b, z), (x1, b, z), (0.5 * (x0 + x1), t, z)]], np.float64))
        cols.append(c)
    for k in range(6):  # back wall stripes
        x0 = -1.5 + k * 0.5
        c = (0.95, 0.85, 0.3) if k % 2 == 0 else (0.3, 0.3, 0.35)
        tris.append(np.array([[(x0, 0, -3.0), (x0 + 0.5, 0, -3.0), (x0 + 0.5, 1.5, -3.0)],
                              [(x0, 0, -3.0), (x0 + 0.5, 1.5, -3.0), (x0, 1.5, -3.0)]], np.float64))
        cols += [c, c]
    p = np.concatenate(tris)
    if below:  # everything but the surface moved under it (a pool seen through a glossy water surface)
        p[2:, :, 1] = p[2:, :, 1] - 1.6
    scene = Scene.from_arrays(p, colors=np.array(cols), name="glossy_floor")
    return scene.with_camera_hint(width=width, height=height, fov_y_deg=45.0, focus_distance=3.0,
                                  eye=(0.0, 1.0, 1.8), target=(0.0, 0.25, -1.5), up=(0.0, 1.0, 0.0), near=0.05)
