"""Planar glossy reflections and refractions ([Nilsson 2012] §6, Fig. 13-14).

The reflection map is rendered by a camera at the primary camera's mirror image under the glossy
plane, its lens parallel to the plane and its focus plane on the plane (which is also where its near
side ends: the plane's own triangles are left out of the pass); an off-centre viewport (Camera.shift)
encloses the glossy rectangle exactly, so texel (i, j) is a fixed point of the surface for every lens
position. The lens is the glossy lobe: a disk of radius roughness x (camera-plane distance), sampled
uniformly and stratified (4D rasterization, no time), so each texel averages the scene over a cone of
directions in one pass; the resolved map is then looked up (bilinear) where the primary camera sees the
plane. Error is against a converged map (1024 samples per texel), work per texel is the map pass's.
Refraction moves the primary camera along the plane normal onto the refracted central ray (exact for
that ray, progressively approximate towards the edges, as [Nilsson 2012] says) and looks down through the plane.
"""
from __future__ import annotations

import numpy as np

from ..camera import Camera
from ..errors import ConfigError
from ..render import _scene_arrays, render
from ..sample_table import SampleTable
from .common import UseResult, figures, ops_all, pinhole_rays, tiled_samples


class _Sub:
    def __init__(self, p0, p1, col):
        self.positions, self.positions_t1, self.colors = p0, p1, col


def reflection_camera(camera: Camera, rect, roughness: float, texels: int, mode: str = "reflection",
                      ior: float = 1.33) -> Camera:
    """The map camera for the plane y = 0 and the glossy rectangle rect = (x0, x1, z0, z1) ([Nilsson 2012] Fig. 13):
    reflection: at the primary camera's mirror image, looking up (+y); refraction: the primary camera
    translated along the plane normal onto the refracted central ray (the ray through the centre of the
    image, refracted with index ior), looking down (-y). Either way the lens is parallel to the plane, the
    plane is the focus plane and an off-centre viewport (shift) encloses rect."""
    x0, x1, z0, z1 = rect
    e = np.asarray(camera.eye, np.float64)
    if e[1] <= 0:
        raise ConfigError(f"camera.eye: the primary camera must be above the glossy plane y = 0, got {e.tolist()}")
    if mode == "reflection":
        eye, look, sign_x = np.array([e[0], -e[1], e[2]]), np.array([0.0, 1.0, 0.0]), -1.0
    elif mode == "refraction":
        d = np.asarray(camera.target, np.float64) - e
        d /= np.linalg.norm(d)
        if d[1] >= 0:
            raise ConfigError("camera.target: the central ray must reach the plane y = 0 for a refraction map")
        c = e + (-e[1] / d[1]) * d  # where the central ray meets the plane
        n = np.array([0.0, 1.0, 0.0])
        eta = 1.0 / ior
        cos_i = -float(n @ d)
        k = 1.0 - eta ** 2 * (1.0 - cos_i ** 2)
        r = eta * d + (eta * cos_i - np.sqrt(k)) * n  # the refracted central ray
        h = np.hypot(d[0], d[2])
        s_back = np.hypot(c[0] - e[0], c[2] - e[2]) / max(np.hypot(r[0], r[2]), 1e-12) if h > 1e-12 else e[1] / -r[1]
        eye = np.array([e[0], c[1] - s_back * r[1], e[2]])  # e moved along the normal onto the refracted ray
        look, sign_x = np.array([0.0, -1.0, 0.0]), 1.0
    else:
        raise ConfigError(f"point.options.mode: expected 'reflection' or 'refraction', got {mode!r}")
    D = abs(eye[1])
    aspect = (x1 - x0) / (z1 - z0)
    width = texels
    height = max(1, int(round(texels / aspect)))
    # view space (up -z): x_v = sign_x (x - eye_x), y_v = -(z - eye_z), w = |y - eye_y|
    xa, xb = sorted((sign_x * (x1 - eye[0]), sign_x * (x0 - eye[0])))
    ya, yb = sorted((-(z1 - eye[2]), -(z0 - eye[2])))
    s_y = 2 * D / (yb - ya)
    fov = float(np.degrees(2 * np.arctan(1 / s_y)))
    s_x = s_y * height / width
    shift = (-s_x * (xa + xb) / (2 * D), -s_y * (ya + yb) / (2 * D))
    return Camera(width=width, height=height, fov_y_deg=fov, focus_distance=D, aperture_radius=roughness * D,
                  eye=eye, target=eye + look, up=(0.0, 0.0, -1.0), near=0.05 * D, shift=shift)


def _bilinear(img, x, y):
    H, W, _ = img.shape
    x = np.clip(x - 0.5, 0, W - 1)
    y = np.clip(y - 0.5, 0, H - 1)
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    x1, y1 = np.minimum(x0 + 1, W - 1), np.minimum(y0 + 1, H - 1)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    return ((img[y0, x0] * (1 - fx) + img[y0, x1] * fx) * (1 - fy) + (img[y1, x0] * (1 - fx) + img[y1, x1] * fx) * fy)


def glossy_reflection(scene, camera, table, pipeline=None, *, hardware=None, roughness: float = 0.08,
                      map_texels: int = 96, reflectance: float = 0.6, reference_spp: int = 1024,
                      mode: str = "reflection", ior: float = 1.33, seed: int = 1) -> UseResult:
    """Glossy reflections (mode "reflection") or refractions ("refraction", index ior) in the plane y = 0
    of the scene's triangles lying in it (the glossy surface; its bounding rectangle is the map's
    viewport); the map holds the triangles on the far side of the plane. `table` is the primary pass's; the map's samples per
    texel are table.spp (stratified over the lens disk, seeded). Figures: glossy.texels,
    glossy.samples_per_texel, glossy.ops_per_texel, glossy.tests_per_texel, glossy.map_rmse,
    glossy.image_rmse."""
    if not 0 < roughness <= 1:
        raise ConfigError(f"point.options.roughness: expected (0, 1], got {roughness!r}")
    p0, p1, col = _scene_arrays(scene)
    in_plane = np.all(np.abs(p0[:, :, 1]) < 1e-9, axis=1) & np.all(np.abs(p1[:, :, 1]) < 1e-9, axis=1)
    if not in_plane.any():
        raise ConfigError("scene: no triangle lies in the glossy plane y = 0 (models 'glossy_floor')")
    pts = p0[in_plane].reshape(-1, 3)
    rect = (pts[:, 0].min(), pts[:, 0].max(), pts[:, 2].min(), pts[:, 2].max())
    rcam = reflection_camera(camera, rect, roughness, map_texels, mode, ior)
    # the map sees the far side of the plane only: above it for reflection, below it for refraction
    side = p0[:, :, 1].mean(axis=1) > 0 if mode == "reflection" else p0[:, :, 1].mean(axis=1) < 0
    keep = ~in_plane & side
    others = _Sub(p0[keep], p1[keep], col[keep])
    spp = table.spp
    mtable = SampleTable.stratified(spp=spp, seed=seed)
    rmap = render(others, rcam, mtable, pipeline, hardware=hardware, timing=False)
    ref_map = render(others, rcam, SampleTable.stratified(spp=reference_spp, seed=seed + 1), pipeline,
                     hardware=hardware, timing=False).image
    image = _compose(scene, camera, table, pipeline, hardware, in_plane, rcam, rmap.image, reflectance)
    ref_image = _compose(scene, camera, table, pipeline, hardware, in_plane, rcam, ref_map, reflectance)
    f = dict(rmap.flat_stats)
    texels = rcam.width * rcam.height
    f.update(figures(glossy__texels=texels, glossy__samples_per_texel=spp,
                     glossy__ops_per_texel=ops_all(f) / texels,
                     glossy__tests_per_texel=f["raster.samples_tested"] / texels,
                     glossy__map_rmse=float(np.sqrt(np.mean((rmap.image.astype(np.float64) - ref_map) ** 2))),
                     glossy__image_rmse=float(np.sqrt(np.mean((image - ref_image) ** 2)))))
    return UseResult(image.astype(np.float32), dict(sorted(f.items())),
                     {"map": rmap.image, "reference_map": ref_map, "reference": ref_image.astype(np.float32)})


def _compose(scene, camera, table, pipeline, hardware, in_plane, rcam, rmap, reflectance):
    """The primary pass: samples whose nearest triangle lies in the plane take their colour plus
    reflectance x the bilinear map look-up at the hit point (projected by the map camera's lens
    centre: the plane is its focus plane, so every lens position agrees)."""
    r = render(scene, camera, table, pipeline, export_samples=True, hardware=hardware, timing=False)
    S = tiled_samples(table, camera)
    hit = r.sample_triangle >= 0
    _, _, col = _scene_arrays(scene)
    colour = np.zeros(hit.shape + (3,))
    colour[hit] = col.mean(axis=1)[r.sample_triangle[hit]]
    glossy = hit & in_plane[np.maximum(r.sample_triangle, 0)]
    o, d = pinhole_rays(camera, S[..., 0][glossy], S[..., 1][glossy])
    w = camera.near / (1.0 - r.sample_depth[glossy].astype(np.float64))
    P = o + w[:, None] * d
    e = rcam.clip_to_engine(rcam.world_to_clip(P))
    colour[glossy] = colour[glossy] + reflectance * _bilinear(rmap.astype(np.float64), e[:, 0] / e[:, 2],
                                                              e[:, 1] / e[:, 2])
    return colour.mean(axis=2)
