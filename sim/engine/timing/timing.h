// The cycle-approximate timing model (docs/timing.md): work records flow, in order, through a
// linear pipeline of units, each with a throughput, a latency and a bounded input FIFO.
//
// Contract:
//   * Records are consumed in the order given; every unit processes records in that order.
//   * Deterministic: the result depends only on the record sequence and the configuration.
//   * cycles >= max over units of (total work / throughput) (a unit is never faster than its
//     throughput), and a deeper FIFO never makes the estimate larger (the model is a max-plus
//     system, monotone in every start time, and a deeper FIFO only relaxes one of its terms).
//   * For every unit and core, busy + blocked + starved = cycles (summed over cores).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/counters.h"

namespace rast5d {

// The units in pipeline order: (identifier, exported name, currency, description). Declared once;
// the timing figures' docs (sim.counter_docs, docs/counters.md) are generated from this list.
#define RAST5D_TIMING_UNITS(X)                                                                            \
  X(geometry_shader, "geometry_shader", "ops", "Conventional GPU: geometry-shader ALU (gpu.gs_ops)")      \
  X(gs_output, "gs_output", "floats", "Conventional GPU: geometry shader to rasterizer bandwidth (gpu.gs_floats)") \
  X(raster2d, "raster2d", "pixels", "Conventional GPU: 2D rasterizer pixel tests (gpu.raster_pixels_tested)") \
  X(pixel_shader, "pixel_shader", "ops", "Conventional GPU: pixel-shader lanes (gpu.ps_ops: sample tests, re-derived setup)") \
  X(setup, "setup", "triangles", "Triangle setup (one triangle per live or culled triangle)")           \
  X(tile_test, "tile_test", "tile tests", "Tile vs triangle tests (tile.visited)")                      \
  X(sample_test, "sample_test", "sample tests", "Sample-in-triangle tests, throughput = lanes")         \
  X(depth, "depth", "depth tests", "Per-sample depth tests")                                            \
  X(shader, "shader", "quads", "Quad shading (2x2 lanes per quad)")                                     \
  X(texture, "texture", "texel fetches", "Texture unit: texel fetches through the texture cache")       \
  X(memory, "memory", "bytes", "Memory interface: depth traffic and texture-cache miss traffic")

enum class Unit : int {
#define RAST5D_X(id, name, currency, desc) id,
  RAST5D_TIMING_UNITS(RAST5D_X)
#undef RAST5D_X
      kCount
};
inline constexpr int kNumUnits = static_cast<int>(Unit::kCount);

struct UnitInfo {
  std::string_view name, currency, description;
};
inline constexpr std::array<UnitInfo, kNumUnits> kUnitInfo = {{
#define RAST5D_X(id, name, currency, desc) {name, currency, desc},
    RAST5D_TIMING_UNITS(RAST5D_X)
#undef RAST5D_X
}};

// One unit of work: the amounts one (triangle, screen bin) visit asks of each unit. Plain data
// (it is also a numpy structured dtype: sim.timing.RECORD_DTYPE).
struct TileWork {
  std::int32_t bin = 0;              // screen bin in raster order (< 0: not binned, e.g. culled)
  std::uint64_t gs_ops = 0;          // geometry_shader
  std::uint64_t gs_floats = 0;       // gs_output
  std::uint64_t raster_pixels = 0;   // raster2d
  std::uint64_t ps_ops = 0;          // pixel_shader
  std::uint32_t triangles = 0;       // setup: triangles set up
  std::uint64_t tile_tests = 0;      // tile_test
  std::uint64_t sample_tests = 0;    // sample_test
  std::uint64_t depth_tests = 0;     // depth
  std::uint64_t quads = 0;           // shader
  std::uint64_t texel_fetches = 0;   // texture
  std::uint64_t tex_misses = 0;      // texture: selects the miss latency
  std::uint64_t memory_bytes = 0;    // memory

  std::uint64_t amount(Unit u) const;
  // Field-wise this - before (bin and triangles are not counter-derived and stay 0).
  TileWork since(const TileWork& before) const;
};

// THE mapping from the engine's counters to work: the work a worker thread's counters add up to.
// A record is work_from_counters(after).since(work_from_counters(before)) around one call of
// Traversal::rasterize. A counter that is work for a unit is mapped here.
TileWork work_from_counters(const Counters& c);

struct UnitTiming {
  double throughput = 1.0;  // items per clock, > 0
  double latency = 0.0;     // clocks, >= 0
  std::int64_t fifo = 1;    // input FIFO entries, >= 1
};

struct TimingConfig {
  std::array<UnitTiming, kNumUnits> units{};  // memory: throughput = bytes/clock of the whole chip
  double tex_hit_latency = 0.0;   // added to the texture latency of a record with fetches, no misses
  double tex_miss_latency = 0.0;  // ... of a record with at least one texture-cache miss
  int cores = 1;                  // parallel pipelines; bins round-robin; memory bandwidth split
};

struct UnitStats {
  double work = 0;     // items in the unit's currency
  double busy = 0;     // clocks spent processing (work / throughput)
  double blocked = 0;  // clocks holding a finished record because the next FIFO is full
  double starved = 0;  // clocks idle: input FIFO empty (fill, bubbles, drain, cores done early)
};

// The per-unit figures, declared once: timing.<unit>.<suffix> (unit nullptr: the unit's currency).
struct UnitFigure {
  const char* suffix;
  const char* unit;
  const char* what;
  double UnitStats::*field;
};
inline constexpr UnitFigure kUnitFigures[] = {
    {"work", nullptr, "work given to the unit", &UnitStats::work},
    {"busy_cycles", "clocks", "clocks processing (work / throughput)", &UnitStats::busy},
    {"blocked_cycles", "clocks", "clocks holding a finished record because the next unit's FIFO is full",
     &UnitStats::blocked},
    {"starved_cycles", "clocks", "clocks idle with an empty input FIFO (pipeline fill, bubbles, drain)",
     &UnitStats::starved},
};

struct TimingResult {
  double cycles = 0;  // estimated clocks per frame: the last record leaves the last unit
  std::uint64_t records = 0;
  int cores = 1;
  std::array<UnitStats, kNumUnits> units{};
};

// Throws std::invalid_argument for a bad configuration.
TimingResult simulate_timing(const TileWork* records, std::size_t n, const TimingConfig& cfg);

// (name, unit, description) of every figure simulate_timing exports (timing.cycles,
// timing.<unit>.busy_cycles, ...). Derived figures (stall, utilisation, bottleneck) are in
// sim/timing.py.
struct TimingFigure {
  std::string name, unit, description;
};
std::vector<TimingFigure> timing_figures();

}  // namespace rast5d
