"""hardware.timing.granularity: records per shading visit carry exactly the work of the records per
(triangle, bin) (field sums equal, texture misses included), leave counters and image unchanged, and
split the frame into at least as many records; bad values are errors naming the field."""
import numpy as np
import pytest

import models
import sim

# Every work field: the memory model works per visit whatever the records' granularity, so its DRAM
# bytes and depth fills are conserved too.
FIELDS = ("triangles", "tile_tests", "sample_tests", "depth_tests", "depth_fills", "quads", "texel_fetches",
          "tex_misses", "dram_depth", "dram_color", "dram_texture", "dram_hiz", "dram_bytes")


@pytest.fixture(scope="module")
def spot():
    scene = models.named("spot")
    hint = scene.camera_hint
    cam = sim.Camera(width=96, height=96, fov_y_deg=hint.get("fov_y_deg", 45.0),
                     focus_distance=hint["focus_distance"], coc_px=8.0)
    return scene, cam, sim.SampleTable.stratified(spp=16, seed=2)


@pytest.mark.parametrize("algorithm", ["tile", "bruteforce", "interval"])
def test_visit_records_conserve_the_work(spot, algorithm):
    scene, cam, table = spot
    cfg = sim.PipelineConfig(algorithm=algorithm, shading="msaa", texture_count=1, threads=2, bin_size=32)
    a = sim.render(scene, cam, table, cfg, hardware=sim.HardwareConfig(timing={"granularity": "bin"}), keep_timing_records=True)
    b = sim.render(scene, cam, table, cfg, hardware=sim.HardwareConfig(timing={"granularity": "visit"}), keep_timing_records=True)
    assert np.array_equal(a.image.view(np.uint32), b.image.view(np.uint32))
    for k, v in a.flat_stats.items():
        if not k.startswith(("timing.", "time.")) or k.endswith(".work"):
            assert v == b.flat_stats[k] or (v != v and b.flat_stats[k] != b.flat_stats[k]), k
    for f in FIELDS:
        assert int(a.timing_records[f].sum()) == int(b.timing_records[f].sum()), f
    assert int(b.timing_records["tex_misses"].sum()) == a.flat_stats["tex.cache.misses"]
    assert len(b.timing_records) >= len(a.timing_records)
    if algorithm == "tile":
        assert len(b.timing_records) > 2 * len(a.timing_records)  # one per (triangle, tile)
    # The bins appear in the same order; the coarse estimate differs only through the model.
    assert np.array_equal(np.unique(a.timing_records["bin"]), np.unique(b.timing_records["bin"]))
    assert b.flat_stats["timing.cycles"] > 0


@pytest.mark.parametrize("value", ["quad", 1, None])
def test_bad_granularity(value):
    with pytest.raises(sim.ConfigError, match="timing.granularity"):
        sim.HardwareConfig(timing={"granularity": value})
