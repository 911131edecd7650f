"""The timing model's cycle-stepped reference (sim.timing.reference, timing/reference.h): closed forms on
synthetic records (one busy unit; a FIFO and latency credit loop counted in items), determinism, bad
input, and agreement with the max-plus model where both must agree (one item per record, deep FIFOs).
The model-against-reference error on real renders is a measurement (reports/paper/cycles.md), not a test."""
from __future__ import annotations

import pytest

import sim
from sim import HardwareConfig, UnitConfig
from sim.timing import UNITS


def hw_of(units: dict, **extra) -> HardwareConfig:
    """Every unit 1 item/clock, no latency, FIFOs of 10^6 entries, unless named; idle units bypassed."""
    kw = {}
    for name in UNITS:
        tp, lat, fifo = units.get(name, (1.0, 0, 1_000_000))
        if name == "dram":
            kw["dram"] = {"bytes_per_clock": tp, "fifo_entries": fifo, "latency_cycles": 0}
        else:
            kw[name] = UnitConfig(tp, lat, fifo)
    kw.setdefault("tex_cache", sim.TextureCacheConfig(hit_latency_cycles=0, miss_latency_cycles=0))
    return HardwareConfig(**kw, **extra)


@pytest.mark.parametrize("unit,tp,lat", [("sample_test", 64.0, 4), ("depth", 32.0, 8), ("tile_test", 4.0, 0),
                                         ("dram", 32.0, 0)])
def test_one_busy_unit_closed_form(unit, tp, lat):
    """n records of work for one unit: it is never starved once filled, so the frame takes
    ceil(total / throughput) clocks plus its latency, plus at most one clock per unit boundary the items
    cross (a cycle-stepped pipeline hands an item with no latency on at the next clock)."""
    field = {"sample_test": "sample_tests", "depth": "depth_tests", "tile_test": "tile_tests", "dram": "dram_bytes"}[unit]
    recs = sim.timing.records(50)
    recs[field] = 160
    out = sim.timing.reference(recs, hw_of({unit: (tp, lat, 1_000_000)}))
    total = 50 * 160
    busy = -(-total // int(tp))
    hops = len(UNITS)  # each unit hands an item on one clock after finishing it
    assert busy + lat <= out["timing.cycles"] <= busy + lat + hops
    assert out[f"timing.{unit}.busy_cycles"] == pytest.approx(total / tp)
    assert out["timing.bottleneck"] == unit


def test_fifo_occupancy_is_counted_in_items():
    """One record of 8 quads, each fetching one texel (8 items of one quad each), through a shader of
    latency 40 into a texture FIFO of 2 entries: two items can be in flight, each holding its slot for
    its 40 clocks of latency, so 8 items need 4 round trips of about 40 clocks. The record-level model
    sees one record taking one slot: the shader's clock, its latency and the 8 texel clocks, about 49."""
    recs = sim.timing.records(1)
    recs["quads"] = 8
    recs["texel_fetches"] = 8
    hw = hw_of({"shader": (8.0, 40, 64), "texture": (1.0, 0, 2)})
    ref = sim.timing.reference(recs, hw)
    model = sim.timing.estimate(recs, hw)
    assert ref["timing.items"] == 8
    assert 4 * 40 <= ref["timing.cycles"] <= 4 * 42 + len(UNITS)
    assert model["timing.cycles"] == pytest.approx(1 + 40 + 8)


def test_agrees_with_the_model_on_single_item_records():
    """Records of one item each (no quads, at most 64 sample tests), deep FIFOs: the reference and the
    model see the same stream; they differ only by the reference's whole clocks and its one clock per
    unit boundary."""
    recs = sim.timing.records(300)
    recs["triangles"] = [1 if i % 3 == 0 else 0 for i in range(300)]
    recs["tile_tests"] = [2 + i % 5 for i in range(300)]
    recs["sample_tests"] = [(7 * i) % 64 for i in range(300)]
    recs["depth_tests"] = [(3 * i) % 20 for i in range(300)]
    hw = hw_of({"setup": (1.0, 16, 1_000_000), "tile_test": (4.0, 4, 1_000_000), "sample_test": (64.0, 4, 1_000_000),
                "depth": (32.0, 8, 1_000_000)})
    ref = sim.timing.reference(recs, hw)["timing.cycles"]
    model = sim.timing.estimate(recs, hw)["timing.cycles"]
    assert ref == pytest.approx(model, rel=0.02, abs=2 * len(UNITS))


def test_deterministic_and_bad_input():
    recs = sim.timing.records(20)
    recs["sample_tests"] = 100
    recs["quads"] = 3
    a = sim.timing.reference(recs)
    assert a == sim.timing.reference(recs)
    with pytest.raises(sim.ConfigError, match="hardware"):
        sim.timing.reference(recs, hardware={"cores": 2})
    with pytest.raises(sim.ConfigError, match="dram.fifo_entries"):
        HardwareConfig(dram={"fifo_entries": 0})
