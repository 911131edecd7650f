"""The figures of the rasterizer's uses (sim/uses/) and of the numerical-precision study
(experiments/run/precision.py), declared once: name -> (unit, description). A leaf module, so sim.stats
merges them into sim.counter_docs() without importing the uses."""
from __future__ import annotations

# Every figure a use adds to its flat_stats, declared once: name -> (unit, description).
FIGURES: dict[str, tuple[str, str]] = {
    # stochastic transparency ([McGuire 2010])
    "transparency.rmse": ("linear RGB", "RMS error of the stochastic-transparency image against sorted alpha blending "
                                        "at the same sample positions"),
    "transparency.max_layers": ("layers", "Most layers any sample position sees: the passes depth peeling needs"),
    "transparency.peel_samples_tested": ("samples", "Depth peeling's sample tests: max_layers passes of the opaque "
                                                    "render at the same spp"),
    "transparency.peel_ops": ("ops", "Depth peeling's operations: max_layers x (ops.total + ops.interp) of the opaque "
                                     "render at the same spp"),
    "transparency.ops": ("ops", "Stochastic transparency's operations: ops.total + ops.interp of its one pass"),
    # the rasterizer as a sampler ([Nilsson 2012] §5)
    "sampler.points": ("samples", "Sample points the rasterizer placed inside the simploids (sample tests that hit)"),
    "sampler.expected_points": ("samples", "E[N] = density x volume of the simploids (closed form)"),
    "sampler.chi2_p": ("probability", "p-value of the chi-square test of uniformity of the points inside the "
                                      "simploids (large = consistent with uniform)"),
    "sampler.chi2_dof": ("cells", "Degrees of freedom of that chi-square test"),
    "sampler.void_points": ("samples", "Points inside the voids (must be 0)"),
    "sampler.candidates_per_test": ("ratio", "sampler.points / raster.samples_tested: candidates per sample test"),
    # motion-blurred soft shadows ([Nilsson 2012] §7)
    "shadow.light_samples": ("samples", "Fixed (u, v, t) samples of the 5D shadow map (2D shadow maps in the array)"),
    "shadow.map_texels": ("texels", "Shadow-map texels over all light samples (map pixels x light samples)"),
    "shadow.onepass_ops": ("ops", "ops.total + ops.interp of the one-pass 5D shadow map"),
    "shadow.accum_ops": ("ops", "ops.total + ops.interp of the accumulation-buffer shadow maps (one pass per light "
                                "sample)"),
    "shadow.onepass_setups": ("triangles", "Triangle setups of the one-pass 5D shadow map"),
    "shadow.accum_setups": ("triangles", "Triangle setups of the accumulation passes"),
    "shadow.maps_equal": ("bool", "The one-pass 5D map equals the accumulation passes' maps sample for sample"),
    "shadow.lookups": ("lookups", "Shadow-map look-ups of the camera pass (one per camera sample that hits)"),
    "shadow.penumbra_measured": ("world units", "Penumbra width measured on the receiver (plane over plane)"),
    "shadow.penumbra_formula": ("world units", "Penumbra width by similar triangles: light width x "
                                               "(receiver - occluder) / occluder distance"),
    "shadow.rmse": ("linear RGB", "RMS error of the soft-shadow image against a many-light-sample reference"),
    "shadow.bands": ("levels", "Distinct visibility levels in the penumbra (banding: at most light_samples + 1)"),
    # caustic volumes ([Nilsson 2012] §4)
    "caustics.volumes": ("volumes", "Caustic volumes (generator triangles)"),
    "caustics.fill_tiles": ("pairs", "(volume, pixel) pairs the conservative 1 x 1 tile test passes with a non-empty "
                                     "t̂ (the rasterizer's candidates)"),
    "caustics.fill_moving": ("invocations", "Pixel-shader invocations of the volumes as moving triangles: (volume, "
                                            "pixel) pairs whose pixel centre has a non-empty exact time interval"),
    "caustics.fill_prism": ("invocations", "Pixel-shader invocations of the bounding-volume approach: pixel centres "
                                           "inside the convex hull of the beam's six vertices (a lower bound for any "
                                           "bounding prism)"),
    "caustics.fill_prism_tiles": ("pairs", "(volume, pixel) pairs of that hull under the conservative 1 x 1 tile "
                                           "test"),
    "caustics.fill_ratio": ("ratio", "caustics.fill_moving / caustics.fill_prism"),
    "caustics.zhat_misses": ("pixels", "Sampled pixel centres whose ray-marched beam hits fall outside ẑ (must be 0)"),
    "caustics.light_error": ("ratio", "Relative L1 difference of the accumulated surface light and a brute-force "
                                      "photon splat of the same beams (both blurred by 2 px)"),
    "caustics.folded": ("volumes", "Volumes whose end triangle is flipped against the generator (fold over)"),
    "caustics.zhat_over_path": ("ratio", "Mean over covered pixel centres of the ẑ width over the ray-marched path "
                                         "length inside the beam (>= 1: ẑ is conservative)"),
    # planar glossy reflections ([Nilsson 2012] §6)
    "glossy.texels": ("texels", "Texels of the reflection map"),
    "glossy.samples_per_texel": ("samples", "Samples per reflection-map texel (the lens samples of the glossy lobe)"),
    "glossy.ops_per_texel": ("ops/texel", "(ops.total + ops.interp) of the reflection-map pass per texel"),
    "glossy.tests_per_texel": ("samples/texel", "raster.samples_tested of the reflection-map pass per texel"),
    "glossy.map_rmse": ("linear RGB", "RMS error of the reflection map against a converged map (1024 samples per "
                                      "texel)"),
    "glossy.image_rmse": ("linear RGB", "RMS error of the final image against the one with the converged map"),
}



# The numerical-precision study (experiments/run/precision.py, point kind `precision`; docs/precision.md):
# the engine's kernels in an arithmetic against float64 and the ray caster, per viewport.
NUMERICS: dict[str, tuple[str, str]] = {
    "numerics.int_bits_tile": ("bits", "Fewest integer bits of the 2D tile test's registers (set-up included) on the "
                                       "suite: every magnitude below 2^int_bits"),
    "numerics.int_bits_sample": ("bits", "Fewest integer bits of the 2D sample test's registers on the suite"),
    "numerics.int_bits_bound": ("bits", "Closed-form integer bits of the 2D tests for any triangle clipped to the guard "
                                        "band: 5 + 2 ceil(log2 V)"),
    "numerics.bound_total_bits": ("bits", "Total bits of the closed-form format: 1 + int_bits_bound + 2 frac_bits"),
    "numerics.bound_safe": ("bool", "The closed-form format overflows nowhere and misses nothing on the suite"),
    "numerics.total_bits": ("bits", "Register width: 1 + fewest int_bits (in band) + 2 frac_bits (float32: 32)"),
    "numerics.safe": ("bool", "At the fewest int_bits: no overflow, no tile culled that holds a point of the triangle "
                              "beyond DELTA from its edges, no sample decision different beyond DELTA"),
    "numerics.triangles": ("triangles", "Triangles of the study's workload at this viewport"),
    "numerics.samples": ("samples", "Sample decisions checked"),
    "numerics.tiles": ("tiles", "Tiles checked"),
    "numerics.boxes": ("boxes", "Lens-cell bounds checked (triangles x lens cells)"),
    "numerics.dmax": ("px", "Largest distance from an edge of a sample whose decision differs from float64"),
    "numerics.differ": ("ratio", "Share of the checked samples whose decision differs from the reference beyond "
                                 "10^-3 px of an edge"),
    "numerics.sample_bad": ("samples", "Sample decisions differing from the reference beyond the stated distance (DELTA "
                                       "= 2^(1 - frac_bits) px in fixed point, 10^-3 px in floats): must be 0"),
    "numerics.tile_violations": ("tiles", "Tiles culled that hold a point of the triangle beyond DELTA from its edges"),
    "numerics.cull_lost": ("ratio", "Share of float64's culls (tiles, lens cells or samples) that the format does not "
                                    "make"),
    "numerics.below_overflows": ("tests", "Overflowing register values with one integer bit fewer than the fewest"),
    "numerics.in_band": ("ratio", "Share of the samples whose placed triangle lies in front of the near plane and in a "
                                  "guard band of one viewport (what a clipping datapath sees)"),
    "numerics.int_bits_all": ("bits", "Fewest integer bits over every case (t̂ and the lens sets for the motion tests)"),
    "numerics.int_bits_band": ("bits", "Fewest integer bits over the cases in the guard band (t̂ and the lens sets for "
                                       "the motion tests)"),
    "numerics.int_bits_all_h5": ("bits", "Motion tests: fewest integer bits of H5 over every case"),
    "numerics.int_bits_band_h5": ("bits", "Motion tests: fewest integer bits of H5 over the cases in the guard band"),
    "numerics.culled64": ("pairs", "(tile, lens cell) pairs (4D test) or samples (motion tests) that float64 culls"),
    "numerics.checked": ("samples", "Samples of culled (tile, lens cell) pairs checked with the float64 ray caster"),
    "numerics.hits": ("samples", "Checked samples the float64 ray caster hits (4D: inside culled pairs, must be 0)"),
    "numerics.outside": ("samples", "Ray-cast hits outside the format's bounds or region (must be 0)"),
    "numerics.outside64": ("samples", "Ray-cast hits outside float64's own bounds or region (must be 0)"),
    "numerics.grow_mean": ("px", "Mean outward move of a lens cell's screen bound by the format against float64"),
    "numerics.grow_max": ("px", "Largest outward move of a lens cell's screen bound against float64"),
    "numerics.rmse": ("linear RGB", "RMS difference of the render's image and the default precision's"),
    "numerics.samples_differ": ("samples", "Samples whose visible triangle differs from the default precision's render"),
    "numerics.tested_base": ("samples", "raster.samples_tested of the default precision's render"),
    "numerics.culled_2d_base": ("tiles", "tile.culled_2d of the default precision's render"),
    "numerics.culled_H5_base": ("cells", "tile.H5_cells_culled of the default precision's render"),
}


def numerics(**values) -> dict:
    """{numerics.name: value} with each name checked against NUMERICS."""
    out = {}
    for k, v in values.items():
        name = f"numerics.{k}"
        if name not in NUMERICS:
            raise KeyError(f"undeclared numerics figure {name!r}")
        out[name] = v.item() if hasattr(v, "item") else v
    return out


def figure_docs() -> dict[str, tuple[str, str]]:
    return {**FIGURES, **NUMERICS}
