"""Engine throughput benchmark (`make bench`, i.e. `pytest -m bench`), never part of `make test`.

Runs experiments/bench/bench_core.py, bench_speed.py and bench_report_points.py and writes
reports/bench/bench_core.md, bench_speed.md and bench_report_points.md (RAST5D_BENCH_BASE_CORE: a
built sim._core module the last compares against). Its figures are rates
and ratios measured in one run; nothing here compares a time against a threshold. With
RAST5D_BENCH_QUICK=1 it runs the quick variant (smaller mixed_sizes) and writes the page to a
temporary directory instead, so the reviewed page only ever holds the full benchmark.
"""
from __future__ import annotations

import os

import pytest

from experiments.bench import bench_core

pytestmark = pytest.mark.bench


def test_bench_core(tmp_path):
    quick = os.environ.get("RAST5D_BENCH_QUICK", "") not in ("", "0")
    out = tmp_path if quick else bench_core.REPO / "reports" / "bench"
    got = bench_core.run(quick=quick, out=out)
    page = got["page"].read_text()
    for section in ("# bench_core: brute-force throughput", "## ns per sample test by dimension class",
                    "## Exact operation counting"):
        assert section in page
    # exact counting is a second way to count the same work: it must agree with the documented costs
    assert got["counts_equal"] == {"bruteforce": True, "tile": True}


def test_bench_speed(tmp_path):
    """experiments/bench/bench_speed.py: wall time against operations and the SIMD sample tests, as
    ratios measured in one run (reports/bench/bench_speed.md). Checks only what does not depend on
    timing: the sections and the operation ratios."""
    from experiments.bench import bench_speed

    quick = os.environ.get("RAST5D_BENCH_QUICK", "") not in ("", "0")
    out = tmp_path if quick else bench_speed.REPO / "reports" / "bench"
    got = bench_speed.run(quick=quick, out=out)
    page = got["page"].read_text()
    for section in ("## Wall time against operations", "## Explicit-SIMD sample tests"):
        assert section in page
    for r in got["rows"]:
        if r["algorithm"] == "bruteforce":
            assert r["ops_ratio"] == 1.0


def test_bench_report_points(tmp_path):
    """experiments/bench/bench_report_points.py: CPU time of the report's most expensive points
    (reports/bench/bench_report_points.md); against the engine module named by
    RAST5D_BENCH_BASE_CORE when set (alternating processes), where the images and counters must be
    the same. Checks no time."""
    from experiments.bench import bench_report_points

    quick = os.environ.get("RAST5D_BENCH_QUICK", "") not in ("", "0")
    out = tmp_path if quick else bench_report_points.REPO / "reports" / "bench"
    base = os.environ.get("RAST5D_BENCH_BASE_CORE") or None
    got = bench_report_points.run(base_core=base, rounds=1 if quick else 2, out=out)
    assert len(got["rows"]) == len(bench_report_points.POINTS)
    if base:
        assert all(r["same"] for r in got["rows"]), [r["point"] for r in got["rows"] if not r["same"]]


def test_bench_timing(tmp_path):
    """experiments/bench/bench_timing.py: the timing and memory model's CPU time over the untimed
    render, the peak memory of a timed 1080p frame, and the renders the memory guard used to refuse
    (reports/bench/bench_timing.md). Checks no time: the sections, and that none is refused."""
    from experiments.bench import bench_timing

    quick = os.environ.get("RAST5D_BENCH_QUICK", "") not in ("", "0")
    out = tmp_path if quick else bench_core.REPO / "reports" / "bench"
    got = bench_timing.run(quick=quick, out=out)
    page = got["page"].read_text()
    for section in ("## CPU time, timed over untimed", "## Peak memory of a frame", "## Renders the memory guard"):
        assert section in page
    assert all(r["estimate"] <= r["limit"] for r in got["refusals"])


def test_bench_mitsuba(tmp_path):
    """experiments/bench/bench_mitsuba.py: rast5d against Mitsuba 3 on the same scenes, frames, spp and
    sampler class, wall time and error against a converged reference, and the 1080p frame with timing
    on (reports/bench/bench_mitsuba.md). Without Mitsuba (the bench extra) or LLVM the page says why.
    Checks no time: the sections, and that both renderers' images are near the reference (a wrong
    camera, mirror or colour convention would put one far from it)."""
    from experiments.bench import bench_mitsuba

    quick = os.environ.get("RAST5D_BENCH_QUICK", "") not in ("", "0")
    out = tmp_path if quick else bench_core.REPO / "reports" / "bench"
    got = bench_mitsuba.run(quick=quick, out=out)
    page = got["page"].read_text()
    assert "# bench_mitsuba" in page
    if not got["variants"]:
        assert "Mitsuba was not run" in page
        return
    assert "## Wall time and error" in page and "## Ratios" in page
    for r in got["rows"]:
        assert r["rmse"] < 0.15, r


def test_bench_rate(tmp_path):
    """experiments/bench/bench_rate.py: the whole render's brute-force sample-test rate on medium
    triangles against the kernels alone (reports/bench/bench_rate.md). Checks no time: the page, and
    that the workload is the 4D class it names."""
    from experiments.bench import bench_rate

    quick = os.environ.get("RAST5D_BENCH_QUICK", "") not in ("", "0")
    out = tmp_path if quick else bench_core.REPO / "reports" / "bench"
    got = bench_rate.run(out=out, repeats=2 if quick else 5)
    page = got["page"].read_text()
    assert "# bench_rate" in page and "Where the render's CPU time goes" in page
    assert got["classes"]["4d"] == got["tested"]
    assert 0 <= got["fixed_python"] <= got["fixed"] and got["kernel_s"] > 0


def test_bench_overhead(tmp_path):
    """experiments/bench/bench_overhead.py: a render's cost outside the engine on a fresh and a reused
    table, and the start-up of a cached run (reports/bench/bench_overhead.md). Checks no time: the
    sections, and that the cached run imported no heavy library."""
    from experiments.bench import bench_overhead

    quick = os.environ.get("RAST5D_BENCH_QUICK", "") not in ("", "0")
    out = tmp_path if quick else bench_core.REPO / "reports" / "bench"
    got = bench_overhead.run(out=out, repeats=3 if quick else 15)
    page = got["page"].read_text()
    for section in ("## Fixed cost of a render", "## Start-up of a cached run"):
        assert section in page
    assert got["startup"]["loaded"] == []
