"""Independent numpy references for the engine tests: the package's (experiments/reference: the ray
caster, the hard cases, the generators, the engine probes) and the tests' own.

    closed_form  closed-form coverage of defocused and moving squares
    compare      float32 tolerances and the engine-vs-reference comparators
"""
from .closed_form import fronto_square, overlap, overlap_integral, rect_coverage
from .compare import (DEPTH_TOL_REL, EDGE_TOL_PX, EPS32, KAPPA_FACTOR, NEAR_TOL_REL, Z_ROUND, check_resolved,
                      compare_probe, compare_resolved, depth_condition, depth_tolerances, engine_params,
                      engine_probe, lens_homogeneous, table_points)
from experiments.reference.generators import (KINDS, Tris, lens_uv, make_scene, random_camera, random_triangle,
                                              sample_points)
from experiments.reference.hardcases import hard_cases
from experiments.reference.raycaster import (edge_distance_px, near_rel_distance, pinhole_scales, proj_scales,
                                             ray_cast, resolve_nearest, sample_rays, screen_to_world, triangle_at,
                                             world_from_pixel, world_to_view)

__all__ = [
    "DEPTH_TOL_REL", "EDGE_TOL_PX", "EPS32", "KAPPA_FACTOR", "KINDS", "NEAR_TOL_REL", "Z_ROUND",
    "check_resolved", "compare_probe", "compare_resolved", "depth_condition", "depth_tolerances",
    "edge_distance_px", "engine_params", "engine_probe", "fronto_square", "hard_cases", "lens_homogeneous",
    "lens_uv", "make_scene", "near_rel_distance", "overlap", "overlap_integral", "pinhole_scales",
    "proj_scales", "random_camera", "random_triangle", "ray_cast", "rect_coverage", "resolve_nearest",
    "sample_points", "sample_rays", "screen_to_world", "table_points", "triangle_at", "Tris",
    "world_from_pixel", "world_to_view",
]
