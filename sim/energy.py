"""Energy estimate from counted events (docs/energy.md): a per-event energy table (pJ per operation,
per byte at each memory level, per cache access; each entry names its source, as Accelergy's tables do)
turns a render's counters into `energy.*` figures per stage and per frame.

The table is pluggable: `render` adds the figures of the default table (`DEFAULT`); `estimate(stats,
table)` re-estimates any result's counters with another one (`EnergyTable.from_dict` /
`EnergyTable.load` read a table from a dict or a YAML/JSON file), like `sim.timing.estimate` re-times.
Every figure is a sum of (events x pJ per event), so energy is linear in the counted events.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from .errors import ConfigError


@dataclass(frozen=True)
class EnergyEntry:
    """pJ per event; `per` names the event unit, `source` where the figure comes from."""

    pj: float
    per: str
    source: str


HOROWITZ = "[Horowitz 2014] Fig. 1.1.9 (45 nm, 0.9 V)"  # docs/references.md

# The entries every table must have.
KEYS = ("op.robust", "op.hardware", "sram.depth_byte", "sram.hiz_byte", "sram.color_byte", "cache.tex_access",
        "cache.tile_access", "dram.byte")


@dataclass(frozen=True)
class EnergyTable:
    name: str
    entries: dict[str, EnergyEntry] = field(default_factory=dict)

    def __post_init__(self):
        missing = [k for k in KEYS if k not in self.entries]
        if missing:
            raise ConfigError(f"energy table {self.name!r}: missing entries {missing} (needs {list(KEYS)})")
        for k, e in self.entries.items():
            if not (isinstance(e.pj, (int, float)) and e.pj >= 0 and e.pj == e.pj):
                raise ConfigError(f"energy table {self.name!r}: {k}.pj = {e.pj!r} must be a number >= 0")
            if not str(e.source).strip():
                raise ConfigError(f"energy table {self.name!r}: {k} names no source")

    @classmethod
    def from_dict(cls, data: dict, name: str = "custom") -> "EnergyTable":
        """{name?, entries: {key: {pj, per, source}}}; unknown keys in an entry are errors."""
        if not isinstance(data, dict) or "entries" not in data:
            raise ConfigError(f"energy table {name!r}: expected a mapping with 'entries'")
        entries = {}
        for k, v in data["entries"].items():
            if not isinstance(v, dict) or set(v) - {"pj", "per", "source"} or "pj" not in v or "source" not in v:
                raise ConfigError(f"energy table {name!r}: entry {k!r} = {v!r} needs exactly pj, per, source")
            entries[k] = EnergyEntry(float(v["pj"]), str(v.get("per", "event")), str(v["source"]))
        return cls(str(data.get("name", name)), entries)

    @classmethod
    def load(cls, path: str | Path) -> "EnergyTable":
        path = Path(path)
        text = path.read_text()
        if path.suffix in (".yaml", ".yml"):
            import yaml

            data = yaml.safe_load(text)
        else:
            data = json.loads(text)
        return cls.from_dict(data, name=path.stem)

    def to_dict(self) -> dict:
        return {"name": self.name,
                "entries": {k: {"pj": e.pj, "per": e.per, "source": e.source} for k, e in self.entries.items()}}


DEFAULT = EnergyTable("horowitz45", {
    # One counted operation ([Akenine-Möller 2012] §6.2: ADD, MUL, MADD, CMP, MIN, MAX, RCP count one each). The counters do
    # not split the mix, so each is charged as a fused multiply-add (an add plus a multiply), an upper
    # bound for the adds and compares.
    "op.robust": EnergyEntry(0.9 + 3.7, "op", f"32-bit float add 0.9 pJ + multiply 3.7 pJ; {HOROWITZ}"),
    "op.hardware": EnergyEntry(0.1 + 3.1, "op", f"32-bit integer add 0.1 pJ + multiply 3.1 pJ; {HOROWITZ}"),
    # On-chip buffers: the depth-tile cache's samples (32 KB class SRAM), the HiZ tiles (8 KB class) and
    # the colour-tile cache's samples (32 KB class).
    "sram.depth_byte": EnergyEntry(20.0 / 8, "byte", f"32 KB SRAM, 20 pJ per 64-bit access; {HOROWITZ}"),
    "sram.hiz_byte": EnergyEntry(10.0 / 8, "byte", f"8 KB SRAM, 10 pJ per 64-bit access; {HOROWITZ}"),
    "sram.color_byte": EnergyEntry(20.0 / 8, "byte", f"32 KB SRAM, 20 pJ per 64-bit access; {HOROWITZ}"),
    # A tag lookup of the depth- or colour-tile cache (64 KB default): one 64-bit access of a 32 KB SRAM
    # (the smallest array of the figure at or below the tag store's size is an upper bound).
    "cache.tile_access": EnergyEntry(20.0, "access", f"32 KB SRAM, 20 pJ per 64-bit access; {HOROWITZ}"),
    # Texture cache (16 KB default): one access between the 8 KB (10 pJ) and 32 KB (20 pJ) figures.
    "cache.tex_access": EnergyEntry(15.0, "access", f"16 KB cache, interpolated from 8 KB 10 pJ / 32 KB 20 pJ "
                                                    f"per 64-bit access; {HOROWITZ}"),
    # Off-chip: every DRAM client (depth and colour lines, texture lines, HiZ).
    "dram.byte": EnergyEntry(1950.0 / 8, "byte", f"DRAM 1.3-2.6 nJ per 64-bit access (midpoint); {HOROWITZ}"),
})

# (figure, unit, description, [(counter, entry key or None for the op entry of the cost model)])
FIGURES = (
    ("energy.setup", "setup operations", [("ops.setup", None)]),
    ("energy.tile", "tile-test operations", [("ops.tile", None)]),
    ("energy.sample", "sample-stage operations (region checks and inside tests)",
     [("ops.sample_region", None), ("ops.sample_inside", None)]),
    ("energy.interp", "depth, depth-test and colour operations of covered samples", [("ops.interp", None)]),
    ("energy.zhat", "depth-interval operations", [("ops.zhat", None)]),
    ("energy.depth", "depth samples read and written in the depth-tile cache (on-chip SRAM) and its tag lookups",
     [("depth.bytes_read", "sram.depth_byte"), ("depth.bytes_written", "sram.depth_byte"),
      ("depth.cache.accesses", "cache.tile_access")]),
    ("energy.color", "colour samples written in the colour-tile cache (on-chip SRAM) and its tag lookups",
     [("color.bytes_written", "sram.color_byte"), ("color.cache.accesses", "cache.tile_access")]),
    ("energy.hiz", "HiZ traffic (on-chip SRAM)",
     [("hiz.bytes_read", "sram.hiz_byte"), ("hiz.bytes_written", "sram.hiz_byte")]),
    ("energy.tex", "texture-cache accesses", [("tex.cache.accesses", "cache.tex_access")]),
    ("energy.dram", "DRAM traffic of every client (dram.bytes: depth, colour, texture, HiZ)",
     [("dram.bytes", "dram.byte")]),
)


#: Figures that read the memory model's events (tile-cache accesses, DRAM bytes): a render without the
#: timing and memory model (sim.render(timing=False)) leaves them out rather than report part of them.
MEMORY_FIGURES = ("energy.depth", "energy.color", "energy.dram", "energy.frame")


def docs() -> dict[str, tuple[str, str]]:
    """{figure: (unit, description)} of the energy figures."""
    out = {name: ("pJ", f"Energy of {what} (sim.energy; default table {DEFAULT.name})") for name, what, _ in FIGURES}
    out["energy.raster"] = ("pJ", "energy.setup + energy.tile + energy.sample: the rasterizer's arithmetic")
    out["energy.frame"] = ("pJ", "Sum of every energy.* stage figure (shader programs are not modelled)")
    for name in MEMORY_FIGURES:
        unit, text = out[name]
        out[name] = (unit, text + "; needs the timing and memory model (absent from a render without timing)")
    return out


def _with_memory_events(stats: dict) -> dict:
    """The DRAM bytes without the timing and memory model: the texture-cache line fills, the only DRAM
    traffic counted then."""
    out = dict(stats)
    if "dram.bytes" not in stats:
        out["dram.bytes"] = float(stats.get("tex.cache.bytes_fetched", 0))
    return out


def estimate(stats: dict, table: EnergyTable = DEFAULT, cost_model: str = "robust") -> dict[str, float]:
    """energy.* figures (pJ) from a flat counter dict (Result.flat_stats), with the table's operation
    entry for the cost model the counts were made under ('robust' or 'hardware')."""
    if cost_model not in ("robust", "hardware"):
        raise ConfigError(f"energy: cost_model = {cost_model!r}: expected 'robust' or 'hardware'")
    op = table.entries[f"op.{cost_model}"].pj
    stats = _with_memory_events(stats)
    out: dict[str, float] = {}
    for name, _what, terms in FIGURES:
        out[name] = float(sum(float(stats.get(c, 0)) * (op if key is None else table.entries[key].pj)
                              for c, key in terms))
    out["energy.raster"] = out["energy.setup"] + out["energy.tile"] + out["energy.sample"]
    out["energy.frame"] = sum(out[name] for name, _, _ in FIGURES)
    return out
