"""Memory honesty: the estimate that guards a render (sim.memory_estimate, checked against
PipelineConfig.memory_limit_bytes before anything is allocated) against the peak memory the render
really takes, measured in a fresh process (Linux: peak RSS reset through /proc/self/clear_refs just
before the render, read from VmHWM after it).

Margin: the measured peak increase must stay within the estimate plus 25 % plus 48 MiB (the fixed
part covers the allocator's arenas, thread stacks and pages the render touches outside its buffers);
and the estimate must not exceed 4 x the measured peak plus 48 MiB, so a limit it enforces is not
absurdly pessimistic. The memory limit's message names the largest parts, what to lower and how to
raise the limit."""
import json
import os
import subprocess
import sys

import pytest

import sim

pytestmark = [pytest.mark.smoke,
              pytest.mark.skipif(bool(os.environ.get("RAST5D_SANITIZED")) or not os.path.exists("/proc/self/clear_refs"),
                                 reason="needs Linux peak-RSS reset; sanitizer builds allocate differently")]

MIB = 2**20
SLACK = 48 * MIB

CHILD = r"""
import json, sys
import numpy as np
import sim

w, h, spp, n, threads, export = (int(a) for a in sys.argv[1:7])
rng = np.random.default_rng(1)
# n small triangles spread over the frame at depth 3..6, plus moving copies: work in every bin
c = np.stack([rng.uniform(-2, 2, n), rng.uniform(-2, 2, n), -rng.uniform(3, 6, n)], axis=1)
pos = c[:, None, :] + rng.normal(0, 0.15, (n, 3, 3))

class S:
    positions = pos
    positions_t1 = pos + [0.05, 0, 0]
    colors = None

camera = sim.Camera(width=w, height=h, coc_px=4, focus_distance=4)
table = sim.SampleTable.create("stratified", spp=spp, seed=1)
config = sim.PipelineConfig(algorithm="tile", threads=threads)
samples = table.samples(camera.lens)
from sim.render import visit_record_estimate  # the default hardware.timing.granularity is 'visit'
visits = visit_record_estimate(camera, *camera.engine_vertices(S.positions, S.positions_t1), config)
est = sim.memory_estimate(camera, spp, n, config, threads, bool(export), True, period=samples.shape[0],
                          visit_records=visits)

def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key):
            return int(line.split()[1]) * 1024
before = status("VmRSS:")
open("/proc/self/clear_refs", "w").write("5")  # reset the peak RSS to the current RSS
r = sim.render(S(), camera, table, config, export_samples=bool(export))
peak = status("VmHWM:")
print(json.dumps({"estimate": est, "peak_increase": peak - before}))
"""


def measure(w, h, spp, n=2000, threads=1, export=False) -> dict:
    out = subprocess.run([sys.executable, "-c", CHILD, str(w), str(h), str(spp), str(n), str(threads), str(int(export))],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _check(m):
    assert m["peak_increase"] <= 1.25 * m["estimate"] + SLACK, m
    assert m["estimate"] <= 4 * m["peak_increase"] + SLACK, m


@pytest.mark.parametrize("size", [(512, 512, 64, 2000, 1, False), (256, 256, 16, 20000, 2, True)])
def test_memory_estimate_bounds_the_measured_peak(size):
    _check(measure(*size))


@pytest.mark.slow
@pytest.mark.parametrize("size", [(256, 256, 16, 2000, 1, False), (1024, 1024, 16, 2000, 1, False),
                                  (1024, 1024, 64, 2000, 2, False), (2048, 2048, 16, 2000, 1, False),
                                  (1024, 1024, 16, 100000, 1, False), (512, 512, 64, 2000, 1, True),
                                  (1024, 1024, 256, 500, 2, False)])
def test_memory_estimate_bounds_the_measured_peak_over_sizes(size):
    _check(measure(*size))


def test_the_limit_message_says_what_to_lower_and_how_to_raise_it():
    class S:
        positions = [[[-1, -1, -3], [1, -1, -3], [0, 1, -3]]]

    with pytest.raises(sim.ConfigError) as info:
        sim.render(S(), sim.Camera(width=8192, height=8192), sim.SampleTable.create("stratified", spp=256),
                   sim.PipelineConfig(threads=1, memory_limit_bytes=2**30))
    text = str(info.value)
    assert "largest: image (width x height)" in text and "spp, the frame size, pipeline.bin_size" in text
    assert "PipelineConfig(memory_limit_bytes=" in text and "pipeline.memory_limit_bytes" in text
    # the limit it suggests lets the same render past the check (the check is the estimate, not a guess)
    need = sim.memory_estimate(sim.Camera(width=8192, height=8192), 256, 1, sim.PipelineConfig(threads=1), 1,
                               period=32)
    suggested = int(text.split("PipelineConfig(memory_limit_bytes=")[1].split(")")[0])
    assert suggested >= need


LINES_CHILD = r"""
import json, sys
import numpy as np
import sim

w, h, n_lines, n, threads, cap, bin_size = (int(a) for a in sys.argv[1:8])
rng = np.random.default_rng(1)
# n large triangles over the frame at depth 3..6: about 8 layers along every line, so that with
# occlusion and merging off the segment buffers fill up to their capacity
c = np.stack([rng.uniform(-1.5, 1.5, n), rng.uniform(-1.5, 1.5, n), -rng.uniform(3, 6, n)], axis=1)

class S:
    positions = c[:, None, :] + rng.normal(0, 0.5, (n, 3, 3))
    colors = np.repeat(rng.uniform(0, 1, (n, 1, 3)), 3, axis=1)

camera = sim.Camera(width=w, height=h, coc_px=6, focus_distance=4)
table = sim.SampleTable.lines(n_lines=n_lines, seed=1)
config = sim.PipelineConfig(algorithm="lines", threads=threads, bin_size=bin_size,
                            lines={"buffer_size": cap, "occlusion": False, "merge": False, "min_weight": 0.0})
est = sim.memory_estimate(camera, n_lines, n, config, threads, period=table.samples(camera.lens).shape[0])

def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key):
            return int(line.split()[1]) * 1024
before = status("VmRSS:")
open("/proc/self/clear_refs", "w").write("5")  # reset the peak RSS to the current RSS
r = sim.render(S(), camera, table, config)
peak = status("VmHWM:")
print(json.dumps({"estimate": est, "peak_increase": peak - before, "overflows": r.flat_stats["lines.overflows"]}))
"""


@pytest.mark.parametrize("size", [(128, 128, 16, 400, 1, 8, 128), (128, 128, 16, 400, 1, 32, 128)])
def test_memory_estimate_bounds_a_line_render(size):
    """Line samples: the segment buffers (one per line of a worker's bin, each up to
    pipeline.lines.buffer_size segments) are a named part of the estimate; with buffers that fill
    (8 segments: they overflow) and with buffers that stay part-empty (32), the same margins hold."""
    from sim.render import memory_parts

    out = subprocess.run([sys.executable, "-c", LINES_CHILD, *map(str, size)], capture_output=True, text=True,
                         check=True)
    m = json.loads(out.stdout.strip().splitlines()[-1])
    _check(m)
    w, h, n_lines, n, threads, cap, bin_size = size
    config = sim.PipelineConfig(algorithm="lines", threads=threads, bin_size=bin_size, lines={"buffer_size": cap})
    part = memory_parts(sim.Camera(width=w, height=h), n_lines, n, config, threads)[
        "segment buffers (threads x bin_size^2 x n_lines x buffer_size)"]
    assert part == threads * min(bin_size, w) * min(bin_size, h) * n_lines * (24 + cap * 52)
    if cap == 8:
        assert m["overflows"] > 0  # the buffers were full
    # point-sample algorithms have no segment buffers
    assert memory_parts(sim.Camera(width=w, height=h), 16, n, sim.PipelineConfig(), threads)[
        "segment buffers (threads x bin_size^2 x n_lines x buffer_size)"] == 0
