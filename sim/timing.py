"""The cycle-approximate timing model (docs/timing.md), on the engine's work records or on synthetic
ones. The model itself is C++ (sim/engine/timing/timing.cpp): ``sim.render`` runs it inside the
engine on the records as the bins complete; this module maps a HardwareConfig onto it
(``config``), re-times kept records (``estimate``), declares the derived timing figures and
documents every figure.

    recs = sim.timing.records(3)                 # zeroed structured array, RECORD_DTYPE
    recs["sample_tests"] = [64, 128, 0]
    sim.timing.estimate(recs, sim.HardwareConfig())["timing.cycles"]

``sim.render(..., keep_timing_records=True)`` keeps the render's records (``Result.timing_records``),
so a hardware sweep can re-run ``estimate`` on one render's records without rendering again (the
unit throughputs, latencies, FIFOs, cores and DRAM bandwidth change; the caches' misses and the DRAM
bytes are those of the render's own caches).
"""
from __future__ import annotations

import numpy as np

from . import _core
from .derived import Derived, evaluate, ratio
from .derived import docs as derived_docs
from .errors import ConfigError
from .hardware import HardwareConfig

#: The units in pipeline order.
UNITS: tuple[str, ...] = tuple(name for name, _currency, _desc in _core.timing_units())
#: One work record (rast5d::TileWork): bin, then one amount per unit (tex_misses selects latency).
RECORD_DTYPE: np.dtype = _core.timing_record_dtype()


def records(n: int = 0) -> np.ndarray:
    """n zeroed work records."""
    return np.zeros(n, dtype=RECORD_DTYPE)


def _as_records(recs) -> np.ndarray:
    recs = np.asarray(recs)
    if recs.dtype == RECORD_DTYPE:
        return np.ascontiguousarray(recs).reshape(-1)
    if recs.dtype.names is None:
        raise ConfigError(f"records: expected a structured array with fields from {RECORD_DTYPE.names}, "
                          f"got dtype {recs.dtype}")
    unknown = [n for n in recs.dtype.names if n not in RECORD_DTYPE.names]
    if unknown:
        raise ConfigError(f"records: unknown field {unknown[0]!r} (known: {', '.join(RECORD_DTYPE.names)})")
    out = records(recs.size)
    for name in recs.dtype.names:  # missing fields stay zero
        col = np.asarray(recs[name]).reshape(-1)
        if name != "bin" and np.any(col < 0):
            raise ConfigError(f"records.{name}: amounts must be >= 0, got {col.min()}")
        out[name] = col
    return out


def config(hw: HardwareConfig):
    """The engine's timing configuration (``_core.TimingConfig``) of a HardwareConfig: per unit its
    throughput, latency and FIFO depth (the DRAM unit's from ``hardware.dram``), the texture hit and
    miss latencies, the depth-line fill latency (``dram.latency_cycles``), the cores and whether a record
    bypasses the units it has no work for (``timing.idle_units``)."""
    tp, lat, fifo = [], [], []
    for name in UNITS:
        if name == "dram":
            tp.append(float(hw.dram.bytes_per_clock))
            lat.append(0.0)  # the DRAM unit ends the pipe; its latency is the clients' fill latency
            fifo.append(int(hw.dram.fifo_entries))
        else:
            u = getattr(hw, name)
            tp.append(float(u.throughput))
            lat.append(float(u.latency_cycles))
            fifo.append(int(u.fifo_entries))
    try:
        return _core.TimingConfig(tp, lat, fifo, float(hw.tex_cache.hit_latency_cycles),
                                  float(hw.tex_cache.miss_latency_cycles), float(hw.dram.latency_cycles),
                                  int(hw.cores), hw.timing.idle_units == "bypass")
    except ValueError as e:
        raise ConfigError(f"hardware: {e}") from None


def estimate(recs, hardware: HardwareConfig | None = None) -> dict:
    """Run the timing model on work records; flat {'timing.cycles': ..., 'timing.<unit>.busy_cycles':
    ..., 'timing.bottleneck': name, 'dram.bytes': ..., ...} with the derived figures (docs: ``docs()``)."""
    hw = HardwareConfig() if hardware is None else hardware
    if not isinstance(hw, HardwareConfig):
        raise ConfigError(f"hardware: expected sim.HardwareConfig, got {type(hw).__name__}")
    raw = _core.timing_estimate(_as_records(recs), config(hw))
    return derive(raw)


def reference(recs, hardware: HardwareConfig | None = None) -> dict:
    """The timing model's cycle-stepped reference on the same records (docs/timing.md, "The model's own
    error"): the same units simulated clock by clock on per-quad items with real FIFO occupancy. Flat
    {'timing.cycles', 'timing.items', 'timing.steps', 'timing.<unit>.busy_cycles', ...,
    'timing.bottleneck'}; it costs simulator time in proportion to the frame's clocks, so it is meant
    for small frames."""
    hw = HardwareConfig() if hardware is None else hardware
    if not isinstance(hw, HardwareConfig):
        raise ConfigError(f"hardware: expected sim.HardwareConfig, got {type(hw).__name__}")
    raw = _core.timing_reference(_as_records(recs), config(hw))
    raw["timing.bottleneck"] = _bottleneck(raw)
    return raw


def _bottleneck(s: dict) -> str:
    """The unit with the most busy clocks (first in pipeline order on ties); 'none' without work."""
    best, best_busy = "none", 0.0
    for u in UNITS:
        if s[f"timing.{u}.busy_cycles"] > best_busy:
            best, best_busy = u, s[f"timing.{u}.busy_cycles"]
    return best


def _bound(s: dict) -> float:
    return max(s[f"timing.{u}.busy_cycles"] for u in UNITS) / s["timing.cores"]


# Derived timing figures (sim.derived), formulas over the flat timing dict.
DERIVED: tuple[Derived, ...] = (
    Derived("timing.bottleneck", "unit name",
     "The unit with the most busy clocks (first in pipeline order on ties; 'none' without work)", _bottleneck),
    Derived("timing.throughput_bound", "clocks",
     "max over units of timing.<unit>.busy_cycles / timing.cores: no pipeline can be faster", _bound),
    Derived("timing.bound_ratio", "ratio",
     "timing.cycles / timing.throughput_bound (1 = throughput-bound; more = latency, FIFO and imbalance losses)",
     lambda s: ratio(s["timing.cycles"], s["timing.throughput_bound"])),
) + tuple(
    item for u in UNITS for item in (
        Derived(f"timing.{u}.stall_cycles", "clocks",
         f"timing.{u}.blocked_cycles + timing.{u}.starved_cycles: clocks the {u} unit does no work",
         lambda s, u=u: s[f"timing.{u}.blocked_cycles"] + s[f"timing.{u}.starved_cycles"]),
        Derived(f"timing.{u}.utilization", "ratio",
         f"timing.{u}.busy_cycles / (timing.cycles x timing.cores)",
         lambda s, u=u: ratio(s[f"timing.{u}.busy_cycles"], s["timing.cycles"] * s["timing.cores"])),
    )
)


def derive(raw: dict) -> dict:
    """Raw timing figures + derived ones."""
    return evaluate(DERIVED, dict(raw))


def docs() -> dict[str, tuple[str, str]]:
    """{name: (unit, description)} of every figure of the timing and memory model, raw and derived."""
    d = dict(_core.timing_docs())
    d.update(derived_docs(DERIVED))
    return d


def model_figures() -> frozenset[str]:
    """Every result column a render has only when the timing and memory model runs: the model's figures
    (docs) and the energy figures that read its events (sim.energy.MEMORY_FIGURES)."""
    from .energy import MEMORY_FIGURES

    return frozenset(docs()) | frozenset(MEMORY_FIGURES)
