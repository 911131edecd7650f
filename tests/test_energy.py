"""The energy estimate (sim.energy): every figure is (events x pJ per event) from the table, so energy is
linear in the counted events; tables are pluggable and every entry names its source."""
from __future__ import annotations

import numpy as np
import pytest

import sim
from sim.energy import DEFAULT, EnergyTable, estimate
from tests.test_op_costs import W, H, F, single_class_scene, tables


@pytest.fixture(scope="module")
def result():
    cam = sim.Camera(width=W, height=H, fov_y_deg=45, focus_distance=F, coc_px=10.0)
    return sim.render(single_class_scene("4d"), cam, tables()["stratified"],
                      sim.PipelineConfig(algorithm="tile", threads=1, shading="msaa", texture_count=1,
                                         hiz={"enabled": True, "tile_size": 8}))


def test_every_entry_names_a_source_and_figures_are_documented():
    for key, e in DEFAULT.entries.items():
        assert e.source.strip() and e.pj > 0, key
    docs = sim.counter_docs()
    for k in estimate({}):
        assert k in docs and docs[k][0] == "pJ", k


def test_energy_is_linear_in_the_counted_events(result):
    """E(a c) = a E(c), E(c1 + c2) = E(c1) + E(c2), and each figure equals the hand sum of counter x pJ."""
    st = {k: v for k, v in result.flat_stats.items() if isinstance(v, (int, np.integer))}
    e1 = estimate(st)
    e3 = estimate({k: 3 * v for k, v in st.items()})
    for k in e1:
        assert e3[k] == pytest.approx(3 * e1[k], rel=1e-12), k
    rng = np.random.default_rng(4)
    other = {k: int(rng.integers(0, 10**6)) for k in st}
    both = estimate({k: st[k] + other[k] for k in st})
    eo = estimate(other)
    for k in e1:
        assert both[k] == pytest.approx(e1[k] + eo[k], rel=1e-12), k
    # independent hand sum from the table entries
    op = DEFAULT.entries["op.robust"].pj
    ops = sum(st[c] for c in ("ops.setup", "ops.tile", "ops.sample_region", "ops.sample_inside", "ops.interp",
                              "ops.zhat"))
    mem = ((st["depth.bytes_read"] + st["depth.bytes_written"]) * 2.5 + st["depth.cache.accesses"] * 20.0
           + st["color.bytes_written"] * 2.5 + st["color.cache.accesses"] * 20.0
           + (st["hiz.bytes_read"] + st["hiz.bytes_written"]) * 1.25 + st["tex.cache.accesses"] * 15.0
           + st["dram.bytes"] * 243.75)
    assert e1["energy.frame"] == pytest.approx(ops * op + mem, rel=1e-12)
    assert st["tex.cache.accesses"] > 0 and st["hiz.bytes_read"] > 0 and st["depth.bytes_read"] > 0
    assert st["dram.bytes"] > st["tex.cache.bytes_fetched"] > 0 and st["color.bytes_written"] > 0
    # render adds the default table's figures
    for k in e1:
        assert result.flat_stats[k] == pytest.approx(e1[k], rel=1e-12), k


def test_tables_are_pluggable_and_validated(tmp_path):
    d = DEFAULT.to_dict()
    d["entries"]["dram.byte"]["pj"] = 0.0
    path = tmp_path / "t.json"
    import json

    path.write_text(json.dumps(d))
    t = EnergyTable.load(path)
    st = {"tex.cache.bytes_fetched": 1000, "tex.cache.accesses": 10}
    assert estimate(st, t)["energy.tex"] == 150.0 and estimate(st, t)["energy.dram"] == 0.0
    # without the memory model's dram.bytes, the texture-cache line fills are the DRAM traffic
    assert estimate(st)["energy.tex"] == 150.0 and estimate(st)["energy.dram"] == 243750.0
    assert estimate({**st, "dram.bytes": 2000})["energy.dram"] == 487500.0
    bad = DEFAULT.to_dict()
    del bad["entries"]["op.robust"]
    with pytest.raises(sim.ConfigError, match="op.robust"):
        EnergyTable.from_dict(bad)
    bad = DEFAULT.to_dict()
    bad["entries"]["op.robust"]["source"] = " "
    with pytest.raises(sim.ConfigError, match="source"):
        EnergyTable.from_dict(bad)
    with pytest.raises(sim.ConfigError, match="cost_model"):
        estimate(st, cost_model="fixed")


def test_hardware_cost_model_uses_the_fixed_point_op_entry():
    st = {"ops.sample_inside": 100}
    assert estimate(st, cost_model="hardware")["energy.sample"] == 100 * DEFAULT.entries["op.hardware"].pj


def test_a_render_without_the_memory_model_leaves_out_the_energy_that_reads_it():
    """energy.depth, .color, .dram and .frame read the tile caches' and DRAM's events: a render without the
    timing and memory model leaves them out (fails if they are reported from part of their events), and
    a page that names one runs the model (experiments.config.sweep.reads_timing)."""
    from experiments.config.schema import OutputsSpec as Outputs
    from experiments.config.sweep import reads_timing

    cam = sim.Camera(width=W, height=H, fov_y_deg=45, focus_distance=F, coc_px=10.0)
    args = (single_class_scene("4d"), cam, tables()["stratified"], sim.PipelineConfig(algorithm="tile", threads=1))
    off, on = sim.render(*args, timing=False).flat_stats, sim.render(*args, timing=True).flat_stats
    for name in sim.energy.MEMORY_FIGURES:
        assert name not in off and on[name] > 0, name
    assert off["energy.tile"] == on["energy.tile"] > 0
    assert sim.energy.MEMORY_FIGURES and set(sim.energy.MEMORY_FIGURES) <= sim.timing.model_figures()
    assert reads_timing(Outputs(derived={"x": "dram.bytes / frame.pixels"}))
    assert reads_timing(Outputs(derived={"x": "energy.frame / 1e6"}))
    assert not reads_timing(Outputs(derived={"x": "energy.tile / 1e6"}))
