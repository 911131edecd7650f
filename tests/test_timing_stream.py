"""The timing model streamed inside the engine (frame/bin_stream.h) against what it replaced.

1. With the memory model off, every timing.* figure of a set of renders equals, bit for bit, what the
   record-level model computed before it was streamed (tests/golden/timing_flat.csv, recorded with
   that model; tests/golden/timing_flat.py).
2. The streamed figures equal the model re-run over the render's kept records (sim.timing.estimate:
   the whole array at once, after the render), with the memory model on, for several algorithms,
   cores and thread counts.
3. Keeping no records bounds the memory a timed render needs (the records in flight only)."""
from __future__ import annotations

import math

import pytest

import models
import sim
from tests.golden import timing_flat

pytestmark = pytest.mark.golden


def _same(a: str, b: float) -> bool:
    return float(a) == b or (math.isnan(float(a)) and math.isnan(b))


@pytest.mark.parametrize("case", timing_flat.cases(), ids=lambda c: "-".join(str(x) for x in c if x != ""))
def test_memory_model_off_reproduces_the_record_level_model(case):
    golden = timing_flat.read()
    want = {k[-1]: v for k, v in golden.items() if k[:-1] == case}
    got = timing_flat.compute(case)
    assert want and set(got) == set(want)
    bad = {k: (want[k], repr(got[k])) for k in want if not _same(want[k], got[k])}
    assert not bad, bad


def test_golden_check_fails_on_a_different_model():
    """The check above can fail: one more clock of setup latency moves the frame's cycles."""
    case = ("bunny", "tile", "visit", 1, "")
    want = {k[-1]: v for k, v in timing_flat.read().items() if k[:-1] == case}
    scene = models.named("bunny")
    hint = scene.camera_hint
    cam = sim.Camera(width=64, height=64, fov_y_deg=hint.get("fov_y_deg", 45.0), focus_distance=hint["focus_distance"],
                     coc_px=10)
    hw = sim.HardwareConfig.from_dict({**timing_flat.FLAT_MEMORY, "setup": {"latency_cycles": 17},
                                       "timing": {"idle_units": "traverse"}})
    r = sim.render(scene, cam, sim.SampleTable.stratified(spp=16, seed=3), sim.PipelineConfig(algorithm="tile", threads=2),
                   hardware=hw)
    assert float(want["timing.cycles"]) != r.flat_stats["timing.cycles"]


@pytest.mark.parametrize("algorithm,cores,threads", [("tile", 1, 1), ("interval", 2, 2), ("bruteforce", 3, 2),
                                                     ("interleave", 1, 2)])
def test_streamed_figures_equal_the_model_over_the_kept_records(algorithm, cores, threads):
    scene = models.named("spot_wall")
    cam = sim.Camera.for_scene(scene, width=80, height=64, coc_px=12)
    table = (sim.SampleTable.interleaved(spp=16, n_lens=64, seed=2) if algorithm in sim.interleaved_algorithms()
             else sim.SampleTable.stratified(spp=16, seed=2))
    cfg = sim.PipelineConfig(algorithm=algorithm, threads=threads, shading="msaa", texture_count=1)
    hw = sim.HardwareConfig(cores=cores)
    r = sim.render(scene, cam, table, cfg, hardware=hw, keep_timing_records=True)
    batch = sim.timing.estimate(r.timing_records, hw)
    assert batch and all(r.flat_stats[k] == v for k, v in batch.items()), \
        {k: (r.flat_stats[k], v) for k, v in batch.items() if r.flat_stats[k] != v}
    assert r.flat_stats["dram.bytes_texture"] == r.flat_stats["tex.cache.bytes_fetched"] > 0
