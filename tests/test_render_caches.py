"""What sim.render keeps between renders of a sweep instead of making it again: the table's dimensions
per lens shape and the procedural textures; and the memory guard, which estimates the frame's visit
records only when the stream's bound on them does not already decide. Each is compared with the work
done afresh."""
import sys

import numpy as np
import pytest

import models
import sim
from sim.render import memory_estimate, visit_record_estimate
from sim.texturing import _procedural_texture, procedural_texture

pytestmark = pytest.mark.smoke


@pytest.mark.parametrize("lens", ["disk", "square", "hexagon"])
@pytest.mark.parametrize("make", [lambda: sim.SampleTable.stratified(spp=8, seed=2),
                                  lambda: sim.SampleTable.interleaved(spp=8, seed=2, n_lens=4),
                                  lambda: sim.SampleTable.from_array(np.zeros((2, 2, 4, 5), np.float32))])
def test_table_dimensions_are_the_samples(make, lens):
    table = make()
    s = table.samples(lens)
    want = (bool(np.any(s[..., 2:4] != 0)), bool(np.any(s[..., 4] != 0)))
    assert table.dimensions(lens) == want
    assert table.dimensions(lens) is table.dimensions(lens)  # made once per shape


def test_a_table_without_lens_or_time_says_so():
    samples = np.zeros((2, 2, 4, 5), np.float32)
    samples[..., 0:2] = 0.5
    assert sim.SampleTable.from_array(samples.copy()).dimensions() == (False, False)
    samples[0, 0, 3, 4] = 0.25  # one sample at another time
    assert sim.SampleTable.from_array(samples).dimensions() == (False, True)


def test_procedural_textures_are_shared_and_read_only():
    a = procedural_texture(32, 1)
    assert a is procedural_texture(32, 1) and not a.flags.writeable
    np.testing.assert_array_equal(a, _procedural_texture(32, 1))
    with pytest.raises(ValueError):
        a[0, 0, 0] = 0.0


@pytest.fixture(scope="module")
def frame():
    scene = models.named("bunny")
    cam = sim.Camera.for_scene(scene, width=64, height=64, coc_px=10)
    table = sim.SampleTable.stratified(spp=16, seed=1)
    cfg = sim.PipelineConfig(algorithm="tile", threads=1)
    v0, v1 = cam.engine_vertices(scene.positions, scene.positions_t1)
    exact = memory_estimate(cam, 16, scene.n_triangles, cfg, 1, timing=True, period=table.samples().shape[0],
                            visit_records=visit_record_estimate(cam, v0, v1, cfg), keep_timing_records=True)
    return scene, cam, table, exact


def test_the_memory_guard_decides_on_the_frames_records(frame):
    """keep_timing_records: the frame's every record counts, so the guard needs the frame's estimate:
    one byte under it is refused (naming that estimate), the estimate itself renders."""
    scene, cam, table, exact = frame
    cfg = sim.PipelineConfig(algorithm="tile", threads=1, memory_limit_bytes=exact - 1)
    with pytest.raises(sim.MemoryLimitError, match=f"estimated {exact / 2**30:.2f} GiB"):
        sim.render(scene, cam, table, cfg, keep_timing_records=True)
    cfg = sim.PipelineConfig(algorithm="tile", threads=1, memory_limit_bytes=exact)
    assert sim.render(scene, cam, table, cfg, keep_timing_records=True).timing_records is not None


def test_the_stream_bound_decides_without_the_frames_estimate(frame, monkeypatch):
    """Records not kept: the stream holds at most (threads + 1) budgets of them, and under the limit
    that bound decides with no pass over the triangles."""
    scene, cam, table, _ = frame
    monkeypatch.setattr(sys.modules["sim.render"], "visit_record_estimate",
                        lambda *a: (_ for _ in ()).throw(AssertionError("estimated")))
    r = sim.render(scene, cam, table, sim.PipelineConfig(algorithm="tile", threads=1))
    assert r.flat_stats["timing.records"] > 0
