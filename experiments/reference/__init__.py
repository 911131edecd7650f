"""Independent numpy references, in the package because the precision page measures the engine's
kernels against them (and the tests compare the engine with them):

    raycaster  float64 thin-lens ray caster: coverage, depth, nearest-hit visibility
    hardcases  named hard inputs (behind the camera, at the near plane, focus crossings, degenerate and
               edge-on triangles, huge blur, gigantic coordinates) with their expected setup counters
    generators random cameras, triangles, samples and scenes
    probes     the engine side: parameters of a camera, the per-sample probe, lens-homogeneous vertices
"""
from .generators import KINDS, Tris, lens_uv, make_scene, random_camera, random_triangle, sample_points
from .hardcases import hard_cases
from .probes import engine_params, engine_probe, lens_homogeneous
from .raycaster import (edge_distance_px, near_rel_distance, pinhole_scales, proj_scales, ray_cast,
                        resolve_nearest, sample_rays, screen_to_world, triangle_at, world_from_pixel, world_to_view)

__all__ = ["KINDS", "Tris", "edge_distance_px", "engine_params", "engine_probe", "hard_cases", "lens_homogeneous",
           "lens_uv", "make_scene", "near_rel_distance", "pinhole_scales", "proj_scales", "random_camera",
           "random_triangle", "ray_cast", "resolve_nearest", "sample_points", "sample_rays", "screen_to_world",
           "triangle_at", "world_from_pixel", "world_to_view"]
