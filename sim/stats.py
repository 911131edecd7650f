"""Counter export: raw counters come from the engine's registry (counters.def); derived figures
are declared here once, with unit and description, and evaluated at export, never stored."""
from __future__ import annotations

from . import _core
from .derived import Derived, evaluate, nest, ratio  # noqa: F401 - nest: sim.stats.nest
from .derived import docs as derived_docs
from .timing import docs as timing_docs
from .sampling import docs as sampling_docs
from .energy import docs as energy_docs
from .figures import figure_docs as use_figure_docs
from .references import cite

# By pipeline stage; a formula may use the figures declared before it (sim.derived.evaluate).
DERIVED: tuple[Derived, ...] = (
    # operations ([Akenine-Möller 2012] §6.2), summed over setup, tile and sample stages
    Derived("ops.sample", "ops", "Sample-stage operations: ops.sample_region + ops.sample_inside",
            lambda s: s["ops.sample_region"] + s["ops.sample_inside"]),
    Derived("ops.total", "ops", "Rasterization operations as in [Akenine-Möller 2012] §6.2: ops.setup + ops.tile + ops.sample "
            "(+ ops.ps_setup: a conventional GPU's pixel shader re-deriving setup per fragment)",
            lambda s: s["ops.setup"] + s["ops.tile"] + s["ops.sample"] + s["ops.ps_setup"]),
    Derived("ops.per_pixel", "ops/pixel", "ops.total / frame.pixels",
            lambda s: ratio(s["ops.total"], s["frame.pixels"])),
    Derived("ops.per_sample_test", "ops/test", "ops.sample_inside / raster.samples_tested",
            lambda s: ratio(s["ops.sample_inside"], s["raster.samples_tested"])),
    # tile tests
    Derived("tile.tested_over_optimal", "ratio",
            "raster.samples_tested / tile.samples_optimal ([Akenine-Möller 2012] Table 1; tile algorithms only)",
            lambda s: ratio(s["raster.samples_tested"], s["tile.samples_optimal"])),
    Derived("tile.culled", "tiles", "Tiles culled by any tile test",
            lambda s: s["tile.culled_2d"] + s["tile.culled_h"] + s["tile.culled_lens"] + s["tile.culled_H"]
            + s["tile.culled_H5"]),
    Derived("tile.cull_rate", "ratio", "tile.culled / tile.visited",
            lambda s: ratio(s["tile.culled"], s["tile.visited"])),
    Derived("tile.cells_cull_rate", "ratio", "tile.cells_culled / tile.cells_tested",
            lambda s: ratio(s["tile.cells_culled"], s["tile.cells_tested"])),
    # sample tests
    Derived("raster.ste", "ratio", "Sample-test efficiency: raster.samples_hit / raster.samples_tested",
            lambda s: ratio(s["raster.samples_hit"], s["raster.samples_tested"])),
    # depth test, HiZ and z-culling
    Derived("depth.pass_rate", "ratio", "depth.passes / depth.tests",
            lambda s: ratio(s["depth.passes"], s["depth.tests"])),
    Derived("depth.bytes", "bytes", "Per-sample depth traffic: depth.bytes_read + depth.bytes_written",
            lambda s: s["depth.bytes_read"] + s["depth.bytes_written"]),
    Derived("hiz.bytes", "bytes", "HiZ traffic: hiz.bytes_read + hiz.bytes_written",
            lambda s: s["hiz.bytes_read"] + s["hiz.bytes_written"]),
    Derived("zcull.cull_rate", "ratio", "zcull.pairs_culled / zcull.pairs",
            lambda s: ratio(s["zcull.pairs_culled"], s["zcull.pairs"])),
    Derived("zcull.tightness", "ratio", "zcull.width_zhat / zcull.width_vertex (1 = no gain over vertex min/max)",
            lambda s: ratio(s["zcull.width_zhat"], s["zcull.width_vertex"])),
    # shading and texturing (docs/shading.md)
    Derived("shade.quads_per_sample", "quads/sample",
            "shade.quad_requests / depth.passes: quad shading requests relative to supersampling ([Akenine-Möller 2012] Table 3)",
            lambda s: ratio(s["shade.quad_requests"], s["depth.passes"])),
    Derived("shade.helper_share", "ratio", "shade.lanes_helper / shade.invocations ([Toth 2008] §9.5 quad waste)",
            lambda s: ratio(s["shade.lanes_helper"], s["shade.invocations"])),
    Derived("shade.cache_hit_rate", "ratio", "shade.cache_hits / (shade.cache_hits + shade.cache_misses)",
            lambda s: ratio(s["shade.cache_hits"], s["shade.cache_hits"] + s["shade.cache_misses"])),
    Derived("tex.cache.hit_rate", "ratio", "tex.cache.hits / tex.cache.accesses",
            lambda s: ratio(s["tex.cache.hits"], s["tex.cache.accesses"])),
    Derived("tex.cache.bytes_per_pixel", "bytes/pixel", "tex.cache.bytes_fetched / frame.pixels",
            lambda s: ratio(s["tex.cache.bytes_fetched"], s["frame.pixels"])),
)

MEASURED = {
    "time.wall_s": ("s", "Wall-clock time of the engine call (setup, traversal, resolve)"),
}

# Blur-based level of detail (models/lod.py, pipeline.lod): figures of the scene handed to the engine.
LOD = {
    "lod.triangles_in": ("triangles", "Triangles of the scene before level of detail"),
    "lod.triangles": ("triangles", "Triangles submitted after level of detail"),
    "lod.triangles_saved": ("triangles", "lod.triangles_in - lod.triangles"),
    "lod.objects_simplified": ("objects", "Objects (connected components) rendered at a level > 0"),
    **{f"lod.triangles_level{k}": ("triangles", f"Triangles submitted from objects at level {k}") for k in range(4)},
}


def counter_docs() -> dict[str, tuple[str, str]]:
    """{name: (unit, description)} for every raw counter, derived figure and measured figure."""
    docs = dict(_core.counter_docs())
    docs.update(derived_docs(DERIVED))
    docs.update(MEASURED)
    docs.update(LOD)
    docs.update(timing_docs())  # the timing model's figures (docs/timing.md)
    docs.update(sampling_docs())  # sampled simulation (sim/sampling.py)
    docs.update(energy_docs())  # the energy estimate (sim.energy, docs/energy.md)
    docs.update(use_figure_docs())  # the figures of the rasterizer's uses (sim/figures.py)
    return {name: (unit, cite(doc)) for name, (unit, doc) in docs.items()}


def flat_stats(raw: dict, measured: dict | None = None) -> dict:
    """Raw counters + derived figures (+ measured figures), flat and sorted by name."""
    flat = evaluate(DERIVED, {k: int(v) for k, v in raw.items()})
    if measured:
        flat.update(measured)
    return dict(sorted(flat.items()))
