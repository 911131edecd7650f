"""Engine throughput benchmark (`make bench`, i.e. `pytest -m bench`), never part of `make test`.

Runs experiments/bench/bench_core.py and writes reports/bench/bench_core.md. Its figures are rates
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
