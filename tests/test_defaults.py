"""Defaults chosen by measurement: the line-sample wheel and the bin size of sampled renders are the sizes
their sweeps on the committed report pages choose (reports/paper/methods.md, reports/paper/sampling.md);
changing either default without its sweep, or the sweep's verdict without the default, fails here."""
from __future__ import annotations

import re
from pathlib import Path

import sim
from sim.pipeline import SAMPLED_BIN_SIZE, WHOLE_FRAME_BIN_SIZE, resolved_bin_size
from sim.sample_table import LINE_WHEEL

ROOT = Path(__file__).resolve().parents[1]


def test_the_line_wheel_is_the_methods_pages_choice():
    page = (ROOT / "reports" / "paper" / "methods.md").read_text()
    chosen = re.search(r"\*\*chosen: (\d+)\*\*", page)
    assert chosen, "the wheel sweep's table (configs/paper/methods_wheel.yaml) is missing from the methods page"
    assert int(chosen.group(1)) == LINE_WHEEL
    assert sim.SampleTable.lines(n_lines=16).params["wheel"] == LINE_WHEEL


def test_the_sampled_bin_size_is_the_sampling_pages_choice():
    page = (ROOT / "reports" / "paper" / "sampling.md").read_text()
    chosen = re.search(r"^\| (\d+) \|.*\| \*\*chosen\*\* \|$", page, flags=re.M)
    assert chosen, "the bin-size sweep's table (configs/paper/sampling.yaml) is missing from the sampling page"
    assert int(chosen.group(1)) == SAMPLED_BIN_SIZE


def test_bin_size_auto_resolves_by_sample_fraction():
    assert sim.PipelineConfig().bin_size == WHOLE_FRAME_BIN_SIZE == resolved_bin_size(1.0)
    sampled = sim.PipelineConfig(sample_fraction=0.25)
    assert sampled.bin_size == SAMPLED_BIN_SIZE
    assert sampled.replace(sample_fraction=1.0).bin_size == WHOLE_FRAME_BIN_SIZE  # 'auto' is resolved again
    assert sim.PipelineConfig().replace(sample_fraction=0.5).bin_size == SAMPLED_BIN_SIZE
    assert sim.PipelineConfig(bin_size=32, sample_fraction=0.5).bin_size == 32  # an explicit size stays
    assert sim.PipelineConfig(sample_fraction=0.5, hinterleave_tile=16).bin_size == 16  # a multiple of its tile


def test_a_yaml_sweep_resolves_auto_per_point(tmp_path):
    import warnings

    from experiments import config as xc
    from experiments.config import expand_sweep

    p = tmp_path / "s.yaml"
    p.write_text("name: s\nscene: {name: spot_wall, params: {width: 16, height: 16}}\ncamera: {width: 16, height: 16}\n"
                 "sweep:\n  pipeline.sample_fraction: [1.0, 0.5]\n")
    data, lines = xc.load_dict(p)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        points = expand_sweep(xc.validate(data, str(p), lines), str(p), lines)
    assert [c.pipeline.bin_size for _, c in points] == [WHOLE_FRAME_BIN_SIZE, SAMPLED_BIN_SIZE]
