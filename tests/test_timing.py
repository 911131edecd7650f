"""The timing model (docs/timing.md): bounds and closed forms on synthetic record streams, a
hand-computed two-unit example, the documented recursion written out independently, and
determinism and counter agreement on real renders (the records a render keeps, the figures it
streams)."""
from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import models
import sim
from sim import HardwareConfig, UnitConfig
from sim.timing import UNITS

pytestmark = pytest.mark.invariants

HYPO = dict(deadline=None, derandomize=True, database=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])

# The record field that carries each unit's work (docs/timing.md, "Units and currencies").
WORK_FIELD = {"geometry_shader": "gs_ops", "gs_output": "gs_floats", "raster2d": "raster_pixels",
              "pixel_shader": "ps_ops",
              "setup": "triangles", "tile_test": "tile_tests", "sample_test": "sample_tests",
              "depth": "depth_tests", "shader": "quads", "texture": "texel_fetches", "dram": "dram_bytes"}
REL = 1e-9  # the model sums in double precision, the tests in numpy: allow rounding only


def unit_params(hw: HardwareConfig, name: str) -> tuple[float, int, int]:
    """(throughput, latency, FIFO) of a unit; the DRAM unit ends the pipe with no latency of its own
    (dram.latency_cycles is the depth-line fill latency, added at the depth unit)."""
    if name == "dram":
        return hw.dram.bytes_per_clock, 0, hw.dram.fifo_entries
    u = getattr(hw, name)
    return u.throughput, u.latency_cycles, u.fifo_entries


def make_hw(units: dict[str, tuple[float, int, int]], fill_latency: int = 0, idle_units: str = "traverse",
            **extra) -> HardwareConfig:
    """HardwareConfig from {unit: (throughput, latency, fifo)}; unnamed units get zero latency (the
    DRAM unit always: its latency argument is ignored); fill_latency is dram.latency_cycles;
    idle_units as hardware.timing.idle_units ('traverse' unless asked: the closed forms below count
    every unit's latency)."""
    kw = {"timing": {"idle_units": idle_units}}
    for name in UNITS:
        tp, lat, fifo = units.get(name, (1.0, 0, 1_000_000))
        if name == "dram":
            kw["dram"] = {"bytes_per_clock": tp, "fifo_entries": fifo, "latency_cycles": fill_latency}
        else:
            kw[name] = UnitConfig(tp, lat, fifo)
    kw.setdefault("tex_cache", sim.TextureCacheConfig(hit_latency_cycles=0, miss_latency_cycles=0))
    kw.update(extra)
    return HardwareConfig(**kw)


# --------------------------------------------------------------------------------- strategies

unit_st = st.tuples(st.sampled_from([0.25, 0.5, 1.0, 1.5, 3.0, 4.0, 64.0]), st.integers(0, 40), st.integers(1, 6))


@st.composite
def streams(draw, max_records=40):
    n = draw(st.integers(1, max_records))
    recs = sim.timing.records(n)
    for f in WORK_FIELD.values():
        recs[f] = draw(st.lists(st.integers(0, 50), min_size=n, max_size=n))
    recs["tex_misses"] = draw(st.lists(st.integers(0, 2), min_size=n, max_size=n))
    recs["depth_fills"] = draw(st.lists(st.integers(0, 2), min_size=n, max_size=n))
    recs["bin"] = draw(st.lists(st.integers(-1, 5), min_size=n, max_size=n))
    return recs


@st.composite
def hardware(draw, cores=(1,)):
    units = {name: draw(unit_st) for name in UNITS}
    tex = sim.TextureCacheConfig(hit_latency_cycles=draw(st.integers(0, 10)), miss_latency_cycles=draw(st.integers(0, 100)))
    return make_hw(units, fill_latency=draw(st.integers(0, 80)), idle_units=draw(st.sampled_from(["bypass", "traverse"])),
                   tex_cache=tex, cores=draw(st.sampled_from(cores)))


# ------------------------------------------------------------------------------------- bounds


@settings(max_examples=300, **HYPO)
@given(recs=streams(), hw=hardware(cores=(1, 2, 3)))
def test_never_below_the_throughput_bound(recs, hw):
    """cycles >= max over units of work / throughput (per core: DRAM bandwidth is split, other
    units are replicated, so the bound is W_k / (tp_k x cores) and W_mem / tp_mem); and every unit's
    clocks add up: busy + blocked + starved = cycles x cores."""
    out = sim.timing.estimate(recs, hw)
    bound = 0.0
    for name in UNITS:
        tp, _, _ = unit_params(hw, name)
        work = float(np.sum(recs[WORK_FIELD[name]], dtype=np.float64))
        assert out[f"timing.{name}.work"] == work
        per_core = work / tp if name == "dram" else work / (tp * hw.cores)
        bound = max(bound, per_core)
        total = out[f"timing.{name}.busy_cycles"] + out[f"timing.{name}.blocked_cycles"] + out[f"timing.{name}.starved_cycles"]
        assert total == pytest.approx(out["timing.cycles"] * hw.cores, rel=REL, abs=1e-9), name
        assert min(out[f"timing.{name}.blocked_cycles"], out[f"timing.{name}.starved_cycles"]) >= -1e-9
    assert out["timing.cycles"] >= bound * (1 - REL)
    if hw.cores == 1:  # one pipeline: the derived bound is exactly this one
        assert out["timing.throughput_bound"] == pytest.approx(bound, rel=REL)


@settings(max_examples=300, **HYPO)
@given(recs=streams(), hw=hardware(cores=(1, 2)), unit=st.sampled_from(UNITS), extra=st.integers(1, 50))
def test_deeper_fifos_are_never_slower(recs, hw, unit, extra):
    """Deepening one unit's FIFO (or every FIFO) never increases the estimate (exactly: the model is
    max and + only, and rounding is monotone)."""
    base = sim.timing.estimate(recs, hw)["timing.cycles"]
    tp, lat, fifo = unit_params(hw, unit)
    units = {name: unit_params(hw, name) for name in UNITS}
    units[unit] = (tp, lat, fifo + extra)
    fill, idle = hw.dram.latency_cycles, hw.timing.idle_units
    deeper = make_hw(units, fill_latency=fill, idle_units=idle, tex_cache=hw.tex_cache, cores=hw.cores)
    assert sim.timing.estimate(recs, deeper)["timing.cycles"] <= base
    all_deeper = make_hw({k: (t, lt, f + extra) for k, (t, lt, f) in units.items()}, fill_latency=fill,
                         idle_units=idle, tex_cache=hw.tex_cache, cores=hw.cores)
    assert sim.timing.estimate(recs, all_deeper)["timing.cycles"] <= base


# -------------------------------------------------------------------------------- closed forms


@settings(max_examples=200, **HYPO)
@given(unit=st.sampled_from(UNITS), tp=st.sampled_from([0.5, 1.0, 3.0, 32.0]),
       latencies=st.lists(st.integers(0, 30), min_size=len(UNITS), max_size=len(UNITS)),
       work=st.lists(st.integers(1, 100), min_size=1, max_size=60), hit_latency=st.integers(0, 9))
def test_one_busy_unit_closed_form(unit, tp, latencies, work, hit_latency):
    """Only one unit has work and every FIFO is deep enough: the unit never starves after the pipeline
    has filled and never blocks, so cycles = (sum of latencies) + (sum of work) / throughput."""
    n = len(work)
    recs = sim.timing.records(n)
    recs[WORK_FIELD[unit]] = work
    latencies = [0 if u == "dram" else lat for u, lat in zip(UNITS, latencies)]  # DRAM: no latency of its own
    units = {name: (1.0, lat, n) for name, lat in zip(UNITS, latencies)}
    units[unit] = (tp, latencies[UNITS.index(unit)], n)
    hw = make_hw(units, tex_cache=sim.TextureCacheConfig(hit_latency_cycles=hit_latency, miss_latency_cycles=0))
    # Records with texel fetches and no misses also wait the cache's hit latency.
    texture_extra = hit_latency if unit == "texture" else 0
    expected = sum(latencies) + texture_extra + sum(work) / tp
    out = sim.timing.estimate(recs, hw)
    assert out["timing.cycles"] == pytest.approx(expected, rel=REL)
    assert out[f"timing.{unit}.busy_cycles"] == pytest.approx(sum(work) / tp, rel=REL)
    assert out[f"timing.{unit}.blocked_cycles"] == 0
    assert out["timing.bottleneck"] == unit


@settings(max_examples=200, **HYPO)
@given(unit=st.sampled_from(UNITS[1:]), s_work=st.integers(1, 8),
       up_latency=st.integers(0, 60), fifo=st.integers(1, 6), n=st.integers(1, 40),
       other_latencies=st.lists(st.integers(0, 20), min_size=len(UNITS), max_size=len(UNITS)))
def test_credit_loop_closed_form(unit, s_work, up_latency, fifo, n, other_latencies):
    """One busy unit b with a shallow input FIFO F behind an upstream latency L (unit b-1): each record
    needs the credit of the record F before it, which returns L clocks late. Then
    S(i) = L0 + max over c in {0, floor(i/F)} of (c L + (i - c F) s)   (L0 = sum of latencies before b)
    and cycles = S(n-1) + s + (sum of latencies from b on): the latency-bound regime
    (rate min(1/s, F/L) records per clock), written here independently of the model's recursion."""
    b = UNITS.index(unit)
    lat = list(other_latencies)
    lat[b - 1] = up_latency
    lat[UNITS.index("dram")] = 0  # the DRAM unit has no latency of its own
    units = {name: (1.0, lat[k], 1_000_000) for k, name in enumerate(UNITS)}
    units[unit] = (1.0, lat[b], fifo)
    hw = make_hw(units)
    recs = sim.timing.records(n)
    recs[WORK_FIELD[unit]] = s_work
    L0 = sum(lat[:b])
    s = float(s_work)

    def start(i):
        q = i // fifo
        return L0 + max(i * s, q * up_latency + (i - q * fifo) * s)

    expected = start(n - 1) + s + sum(lat[b:])
    assert sim.timing.estimate(recs, hw)["timing.cycles"] == pytest.approx(expected, rel=REL)


def test_two_unit_example_by_hand():
    """setup (1 triangle/clock, latency 2) feeding tile_test (1 test/clock, latency 1, FIFO 1).
    Records (triangles, tile tests): (1, 4), (1, 1), (1, 1). By hand (S start, C done, D leave):
      r0: setup S0 C1 D1 -> tile arrives 3: S3 C7 D7, out at 8
      r1: setup S1 C2, waits for r0 to leave the tile FIFO (starts at 3): D3 (blocked 1), arrives 5;
          tile S7 C8 D8, out at 9
      r2: setup S3 C4, credit of r1 (tile start 7): D7 (blocked 3), arrives 9; tile S9 C10, out at 11
    cycles 11; setup busy 3, blocked 4, starved 4; tile busy 6, blocked 0, starved 3 + 1 + 1 = 5.
    With a 2-entry FIFO: r1 leaves setup at 2 (arrives 4, starts 7), r2 needs r0's credit (3):
    D3, arrives 5, tile S8 C9, out at 10."""
    recs = sim.timing.records(3)
    recs["triangles"] = 1
    recs["tile_tests"] = [4, 1, 1]
    hw = make_hw({"setup": (1.0, 2, 16), "tile_test": (1.0, 1, 1)})
    out = sim.timing.estimate(recs, hw)
    assert out["timing.cycles"] == 11
    got = {(u, k): out[f"timing.{u}.{k}_cycles"] for u in ("setup", "tile_test") for k in ("busy", "blocked", "starved")}
    assert got == {("setup", "busy"): 3, ("setup", "blocked"): 4, ("setup", "starved"): 4,
                   ("tile_test", "busy"): 6, ("tile_test", "blocked"): 0, ("tile_test", "starved"): 5}
    assert out["timing.bottleneck"] == "tile_test"
    assert out["timing.tile_test.stall_cycles"] == 5
    assert out["timing.throughput_bound"] == 6 and out["timing.bound_ratio"] == pytest.approx(11 / 6)
    hw2 = make_hw({"setup": (1.0, 2, 16), "tile_test": (1.0, 1, 2)})
    assert sim.timing.estimate(recs, hw2)["timing.cycles"] == 10


def test_texture_miss_latency_and_cores():
    """A record with a texture-cache miss waits the miss latency instead of the hit latency; two cores
    take alternate bins and split the memory bandwidth (hand-computed)."""
    recs = sim.timing.records(2)
    recs["texel_fetches"] = [4, 4]
    recs["tex_misses"] = [0, 1]
    tex = sim.TextureCacheConfig(hit_latency_cycles=5, miss_latency_cycles=100)
    hw = make_hw({"texture": (4.0, 2, 64)}, tex_cache=tex)
    # r0: S0 C1, out at 1 + 2 + 5 = 8; r1: S1 C2, out at 2 + 2 + 100 = 104.
    assert sim.timing.estimate(recs, hw)["timing.cycles"] == 104
    recs = sim.timing.records(4)
    recs["bin"] = [0, 1, 2, 3]
    recs["dram_bytes"] = [64, 64, 64, 0]
    hw = make_hw({"dram": (32.0, 0, 64)}, cores=2)
    # Core 0: bins 0 and 2, 128 bytes at 16 bytes/clock = 8; core 1: 64 bytes = 4 (then starves 4).
    out = sim.timing.estimate(recs, hw)
    assert out["timing.cycles"] == 8
    assert out["timing.dram.busy_cycles"] == 12 and out["timing.dram.starved_cycles"] == 4


def test_depth_fill_latency():
    """A record whose depth unit fills a line from DRAM waits dram.latency_cycles there (hand-computed):
    depth 4 tests/clock, latency 3; r0 (4 tests, no fill) out at 1 + 3 = 4; r1 (4 tests, a fill) starts
    at 1, done at 2, out at 2 + 3 + 50 = 55."""
    recs = sim.timing.records(2)
    recs["depth_tests"] = [4, 4]
    recs["depth_fills"] = [0, 1]
    hw = make_hw({"depth": (4.0, 3, 64)}, fill_latency=50)
    assert sim.timing.estimate(recs, hw)["timing.cycles"] == 55


def test_empty_stream_and_bad_input():
    out = sim.timing.estimate(sim.timing.records(0))
    assert out["timing.cycles"] == 0 and out["timing.bottleneck"] == "none"
    with pytest.raises(sim.ConfigError, match="unknown field 'bogus'"):
        sim.timing.estimate(np.zeros(2, dtype=[("bogus", "u8")]))
    with pytest.raises(sim.ConfigError, match="sample_tests"):
        sim.timing.estimate(np.array([(-1,)], dtype=[("sample_tests", "i8")]))
    with pytest.raises(sim.ConfigError, match="HardwareConfig.cores"):
        HardwareConfig(cores=0)
    with pytest.raises(sim.ConfigError, match="dram.fifo_entries"):
        HardwareConfig(dram={"fifo_entries": 0})
    with pytest.raises(sim.ConfigError, match="dram.bytes_per_clock"):
        HardwareConfig(dram={"bytes_per_clock": 0})
    with pytest.raises(sim.ConfigError, match="hardware"):
        sim.timing.estimate(sim.timing.records(1), hardware={"cores": 2})


# ------------------------------------------------------------------------------- real renders


@functools.lru_cache(maxsize=None)
def _scene():
    import models

    return models.named("spot_wall")


# The memory model off: every depth read and write goes to DRAM (the records then carry exactly the
# counters' traffic).
FLAT_MEMORY = {"depth_buffer": {"enabled": False, "compression": "none"}, "color_buffer": {"enabled": False}}


def _render(threads, algorithm="tile", coc=12.0, **kw):
    cam = sim.Camera(width=96, height=96, fov_y_deg=40, focus_distance=4.0, coc_px=coc, eye=(0, 0.3, 0), target=(0, 0.3, -4))
    table = sim.SampleTable.stratified(spp=16, seed=3)
    kw.setdefault("keep_timing_records", kw.get("timing", True))
    return sim.render(_scene(), cam, table, sim.PipelineConfig(algorithm=algorithm, threads=threads), **kw)


@pytest.mark.parametrize("algorithm", ["tile", "interval", "bruteforce"])
def test_render_timing_identical_for_any_thread_count(algorithm):
    one, two = _render(1, algorithm), _render(2, algorithm)
    assert one.timing_records.tobytes() == two.timing_records.tobytes()
    model = set(sim.timing.docs())
    t1 = {k: v for k, v in one.flat_stats.items() if k in model}
    t2 = {k: v for k, v in two.flat_stats.items() if k in model}
    assert t1 == t2 and t1["timing.cycles"] > 0 and t1["depth.cache.misses"] > 0


def test_render_records_add_up_to_the_counters():
    """The records are deltas of the engine's counters: their sums are the frame's counters (with the
    memory model off, the DRAM bytes are the per-sample depth traffic)."""
    res = _render(2, "tile", hardware=HardwareConfig(cores=2, **FLAT_MEMORY))
    recs, st_ = res.timing_records, res.flat_stats
    assert recs["triangles"].sum() == st_["setup.triangles"]
    assert (recs["bin"] < 0).sum() == st_["setup.triangles"] - np.sum(recs["triangles"][recs["bin"] >= 0])
    assert recs["tile_tests"].sum() == st_["tile.visited"] > 0
    assert recs["sample_tests"].sum() == st_["raster.samples_tested"] > 0
    assert recs["depth_tests"].sum() == st_["depth.tests"]
    assert recs["dram_bytes"].sum() == st_["depth.bytes_read"] + st_["depth.bytes_written"] > 0  # no HiZ, untextured
    assert recs["dram_bytes"].sum() == recs["dram_depth"].sum() == st_["dram.bytes"] == st_["dram.bytes_depth"]
    assert recs["quads"].sum() == 0 and recs["texel_fetches"].sum() == 0 and recs["tex_misses"].sum() == 0
    assert recs["bin"].max() < st_["frame.bins"]
    assert st_["timing.cores"] == 2 and st_["timing.records"] == len(recs)
    # Re-timing the stored records gives the render's figures.
    again = sim.timing.estimate(recs, HardwareConfig(cores=2, **FLAT_MEMORY))
    assert all(st_[k] == v for k, v in again.items())


def test_render_records_carry_the_memory_model():
    """With the memory model on, the records carry its DRAM bytes by client and its depth fills; their
    sums are the streamed figures, and re-timing the kept records gives the streamed timing."""
    res = _render(2, "tile", hardware=HardwareConfig(cores=2))
    recs, st_ = res.timing_records, res.flat_stats
    for client in ("depth", "color", "texture", "hiz"):
        assert recs[f"dram_{client}"].sum() == st_[f"dram.bytes_{client}"], client
    assert recs["dram_bytes"].sum() == st_["dram.bytes"] == sum(st_[f"dram.bytes_{c}"] for c in ("depth", "color", "texture", "hiz"))
    assert recs["depth_fills"].sum() == st_["depth.cache.fills"]
    assert st_["depth.cache.hits"] + st_["depth.cache.misses"] == st_["depth.cache.accesses"] > 0
    assert st_["dram.bytes_depth"] < st_["depth.bytes_read"] + st_["depth.bytes_written"]  # the cache and compression
    again = sim.timing.estimate(recs, HardwareConfig(cores=2))
    assert all(st_[k] == v for k, v in again.items())


def test_render_records_carry_shading_texture_and_hiz_work():
    """With shading, texturing and HiZ on, the records carry the quads, texel fetches, the texture
    misses of the cache replay (each record its own) and all memory traffic."""
    cam = sim.Camera(width=64, height=64, coc_px=4)
    table = sim.SampleTable.stratified(spp=4, seed=1)
    cfg = sim.PipelineConfig(algorithm="tile", threads=2, shading="msaa", texture_count=1,
                             hiz={"enabled": True, "tile_size": 8})
    hw = HardwareConfig(**FLAT_MEMORY)
    res = sim.render(models.named("spot_wall"), cam, table, cfg, hardware=hw, keep_timing_records=True)
    recs, st_ = res.timing_records, res.flat_stats
    assert recs["quads"].sum() == st_["shade.quad_requests"] > 0
    assert recs["texel_fetches"].sum() == st_["tex.fetches"] > 0
    assert recs["tex_misses"].sum() == st_["tex.cache.misses"] > 0
    assert (recs["tex_misses"] > 0).sum() > 1  # spread over the records, not lumped
    assert recs["dram_bytes"].sum() == (st_["depth.bytes_read"] + st_["depth.bytes_written"] + st_["hiz.bytes_read"]
                                        + st_["hiz.bytes_written"] + st_["tex.cache.bytes_fetched"])
    one = sim.render(models.named("spot_wall"), cam, table, cfg.replace(threads=1), hardware=hw, keep_timing_records=True)
    assert one.timing_records.tobytes() == recs.tobytes()


def test_render_without_timing():
    """Switched off (timing=False, or hardware.timing.enabled false): the model's figures are absent,
    never 0; the counters are the same; records are kept only when asked for."""
    model = set(sim.timing.docs())
    res = _render(1, timing=False)
    assert res.timing_records is None and not model & set(res.flat_stats)
    off = _render(1, hardware=HardwareConfig(timing={"enabled": False}), keep_timing_records=False)
    assert off.timing_records is None and not model & set(off.flat_stats)
    on = _render(1, keep_timing_records=False)
    assert on.timing_records is None and on.flat_stats["timing.cycles"] > 0
    assert res.flat_stats["raster.samples_tested"] == on.flat_stats["raster.samples_tested"]
    with pytest.raises(sim.ConfigError, match="keep_timing_records"):
        _render(1, timing=False, keep_timing_records=True)


def reference_cycles(recs: np.ndarray, hw: HardwareConfig) -> float:
    """docs/timing.md's recursion written out directly (lists of all start times, no ring buffers),
    for streams with several cores, texture and fill latencies, and idle units bypassed or traversed
    (bypassed: a record occupies only the units it has work for; a FIFO of F holds the last F records
    that occupy its unit)."""
    cores = hw.cores
    bypass = hw.timing.idle_units == "bypass"
    params = [unit_params(hw, u) for u in UNITS]
    ends = []
    for c in range(cores):
        idx = [i for i in range(len(recs)) if recs["bin"][i] >= 0 and recs["bin"][i] % cores == c]
        unbinned = [i for i in range(len(recs)) if recs["bin"][i] < 0]
        idx += [i for j, i in enumerate(unbinned) if j % cores == c]
        idx.sort()
        K = len(UNITS)
        S = [[0.0] * K for _ in idx]
        D = [[0.0] * K for _ in idx]
        end = 0.0
        occupants = [[] for _ in UNITS]  # per unit: the positions n of the records that occupy it
        for n, i in enumerate(idx):
            arrive = 0.0
            occ = [not bypass or recs[WORK_FIELD[u]][i] > 0 for u in UNITS]
            for k, u in enumerate(UNITS):
                tp, lat, _ = params[k]
                if u == "dram":
                    tp = tp / cores
                if not occ[k]:
                    lat = 0
                S[n][k] = max(arrive, D[n - 1][k] if n else 0.0)
                C = S[n][k] + float(recs[WORK_FIELD[u]][i]) / tp
                D[n][k] = C
                if k + 1 < K and occ[k + 1]:
                    F = params[k + 1][2]
                    before = occupants[k + 1]
                    if len(before) >= F:
                        D[n][k] = max(C, S[before[len(before) - F]][k + 1])
                if occ[k]:
                    occupants[k].append(n)
                if u == "texture" and recs["texel_fetches"][i]:
                    lat += hw.tex_cache.miss_latency_cycles if recs["tex_misses"][i] else hw.tex_cache.hit_latency_cycles
                if u == "depth" and recs["depth_fills"][i]:
                    lat += hw.dram.latency_cycles
                arrive = D[n][k] + lat
            end = max(end, arrive)
        ends.append(end)
    return max(ends)


@settings(max_examples=150, **HYPO)
@given(recs=streams(max_records=25), hw=hardware(cores=(1, 2, 3)))
def test_model_matches_the_documented_recursion(recs, hw):
    assert sim.timing.estimate(recs, hw)["timing.cycles"] == pytest.approx(reference_cycles(recs, hw), rel=REL, abs=1e-9)


def test_every_estimated_figure_is_documented_and_vice_versa():
    """The raw figures the model returns (over records, and streamed from a render with the memory
    model on) are exactly those timing_docs declares."""
    recs = np.zeros(3, dtype=sim._core.timing_record_dtype())
    recs["triangles"] = 1
    tp, lat, fifo = ([1.0] * len(UNITS), [0.0] * len(UNITS), [4] * len(UNITS))
    raw = sim._core.timing_estimate(recs, sim._core.TimingConfig(tp, lat, fifo, 1.0, 10.0, 0.0, 1))
    memory = {name for name in sim._core.timing_docs() if not name.startswith(("timing.", "dram."))}
    assert set(raw) == set(sim._core.timing_docs()) - memory
    streamed = _render(1, keep_timing_records=False, pixel_stats=False).flat_stats
    assert set(sim._core.timing_docs()) <= set(streamed)


def test_a_line_test_costs_its_lane_slots():
    """docs/timing.md, "Line samples on the sample-test unit": a line test takes 2 sample-test lane slots
    (32 operations of the interval over the 28 of the 4D point test the lanes are sized for, rounded up)
    and a wheel's lens-space set-up 2 (45 over 28). The sample-test unit's work of a line-sample frame is
    2 x lines.tests + 2 x lines.point_setups, from the counters; charging a line test as one item (the
    broken mapping below) fails."""
    import math

    cam = sim.Camera(width=48, height=48, fov_y_deg=40, focus_distance=4.0, coc_px=8, eye=(0, 0.3, 0), target=(0, 0.3, -4))
    import models

    scene = models.named("spot_wall", cow_motion=(0.0, 0.0, 0.0))  # line samples: static scenes
    res = sim.render(scene, cam, sim.SampleTable.lines(n_lines=8, seed=2), sim.PipelineConfig(algorithm="lines", threads=1),
                     keep_timing_records=True)
    s = res.flat_stats
    test_slots, setup_slots = math.ceil(32 / 28), math.ceil(45 / 28)  # the documented operations over kInside4D
    assert (test_slots, setup_slots) == (2, 2)
    assert s["raster.samples_tested"] == 0 and s["lines.tests"] > 0 and s["lines.point_setups"] > 0
    expected = test_slots * s["lines.tests"] + setup_slots * s["lines.point_setups"]
    assert s["timing.sample_test.work"] == expected == res.timing_records["sample_tests"].sum()
    assert s["timing.sample_test.work"] != s["lines.tests"]  # one item per line test would be caught
    # Re-timed with 4x the lanes, the sample-test unit's busy clocks are its work over 256.
    again = sim.timing.estimate(res.timing_records, HardwareConfig(sample_test={"throughput": 256}))
    assert again["timing.sample_test.busy_cycles"] == pytest.approx(expected / 256)
