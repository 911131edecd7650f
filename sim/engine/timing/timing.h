// The cycle-approximate timing model (docs/timing.md): work records flow, in order, through a
// linear pipeline of units, each with a throughput, a latency and a bounded input FIFO. TimingModel
// consumes the records as a stream (the frame hands it each bin's records as the bins complete, in
// bin order: frame/bin_stream.h), so a frame's timing needs memory for the records in flight only;
// simulate_timing() runs the same model over a whole record array (re-timing kept records).
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

#include "core/costs.h"
#include "core/counters.h"

namespace rast5d {

// The units in pipeline order: (identifier, exported name, currency, description). Declared once;
// the timing figures' docs (sim.counter_docs, docs/counters.md) are generated from this list.
#define RAST5D_TIMING_UNITS(X)                                                                            \
  X(geometry_shader, "geometry_shader", "ops", "Conventional GPU: shader ALU ops of the geometry shader (gpu.gs_ops) and of accumulation buffering's repeated vertex shading (accum.vertex_ops)") \
  X(gs_output, "gs_output", "floats", "Conventional GPU: geometry shader to rasterizer bandwidth (gpu.gs_floats)") \
  X(raster2d, "raster2d", "pixels", "Conventional GPU: 2D rasterizer pixel tests (gpu.raster_pixels_tested)") \
  X(pixel_shader, "pixel_shader", "ops", "Conventional GPU: pixel-shader lanes (gpu.ps_ops: sample tests, re-derived setup)") \
  X(setup, "setup", "triangles", "Triangle setup (one triangle per live or culled triangle)")           \
  X(tile_test, "tile_test", "tile tests", "Tile vs triangle tests (tile.visited)")                      \
  X(sample_test, "sample_test", "sample tests", "Sample-in-triangle tests, throughput = lanes")         \
  X(depth, "depth", "depth tests", "Per-sample depth tests")                                            \
  X(shader, "shader", "quads", "Quad shading (2x2 lanes per quad)")                                     \
  X(texture, "texture", "texel fetches", "Texture unit: texel fetches through the texture cache")       \
  X(dram, "dram", "bytes", "DRAM interface: the traffic of every client (depth, colour, texture, HiZ)")

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

// One unit of work: the amounts one visit (or one (triangle, screen bin) visit) asks of each unit.
// Plain data (it is also a numpy structured dtype: sim.timing.RECORD_DTYPE).
struct TileWork {
  std::int64_t bin = 0;              // screen bin in raster order (< 0: not binned, e.g. culled)
  std::uint64_t gs_ops = 0;          // geometry_shader
  std::uint64_t gs_floats = 0;       // gs_output
  std::uint64_t raster_pixels = 0;   // raster2d
  std::uint64_t ps_ops = 0;          // pixel_shader
  std::uint64_t triangles = 0;       // setup: triangles set up
  std::uint64_t tile_tests = 0;      // tile_test
  std::uint64_t sample_tests = 0;    // sample_test
  std::uint64_t depth_tests = 0;     // depth
  std::uint64_t depth_fills = 0;     // depth: lines filled from DRAM (selects the fill latency)
  std::uint64_t quads = 0;           // shader
  std::uint64_t texel_fetches = 0;   // texture
  std::uint64_t tex_misses = 0;      // texture: selects the miss latency
  std::uint64_t dram_depth = 0;      // dram, by client: depth lines (or per-sample depth traffic)
  std::uint64_t dram_color = 0;      //   colour lines and the resolve
  std::uint64_t dram_texture = 0;    //   texture-cache line fills
  std::uint64_t dram_hiz = 0;        //   HiZ reads and writes
  std::uint64_t dram_bytes = 0;      // dram: the sum of the four clients

  std::uint64_t amount(Unit u) const {
    switch (u) {
      case Unit::geometry_shader: return gs_ops;
      case Unit::gs_output: return gs_floats;
      case Unit::raster2d: return raster_pixels;
      case Unit::pixel_shader: return ps_ops;
      case Unit::setup: return triangles;
      case Unit::tile_test: return tile_tests;
      case Unit::sample_test: return sample_tests;
      case Unit::depth: return depth_tests;
      case Unit::shader: return quads;
      case Unit::texture: return texel_fetches;
      case Unit::dram: return dram_bytes;
      case Unit::kCount: break;
    }
    return 0;
  }
  // Field-wise this - before (bin is not counter-derived and stays 0; triangles holds the counter-derived
  // re-sends, the recorder adds the triangle's own set-up).
  TileWork since(const TileWork& before) const {
    // Every field is 64 bits: the difference as one loop over them (vectorised).
    static_assert(sizeof(TileWork) == kFields * sizeof(std::uint64_t));
    TileWork w;
    const auto* a = reinterpret_cast<const std::uint64_t*>(this);
    const auto* b = reinterpret_cast<const std::uint64_t*>(&before);
    auto* o = reinterpret_cast<std::uint64_t*>(&w);
    for (int i = 0; i < kFields; ++i) o[i] = a[i] - b[i];
    w.bin = 0;
    return w;
  }
  static constexpr int kFields = 18;
  bool empty() const;  // no work for any unit
};

// THE mapping from the engine's counters (and the memory model's totals, when it runs) to work: the
// work a worker thread's counters add up to. A record is the difference of two of these around a
// visit. A counter that is work for a unit is mapped here. Texture misses and their DRAM bytes are
// added by the texture-cache replay, in bin order (frame/bin_stream.h).
struct MemoryTotalsView {
  bool depth = false, color = false;  // which buffers the memory model covers
  std::uint64_t depth_dram = 0, depth_fills = 0, color_dram = 0;
};
TileWork work_from_counters(const Counters& c, const MemoryTotalsView& mem = {});

// A line-triangle test on the sample-test unit ([Tzeng 2012] §3; docs/timing.md, "Line samples"). The
// unit's lanes are sized for the 4D point test (cost::kInside4D operations a lane slot); a line sample's
// work takes the lane slots its operations need, rounded up: the interval of one line inside a
// defocused triangle in front of the near plane (cost::line_interval_cost(4, 0) = 32 operations: 2
// slots), and the lens-space set-up of its wagon wheel's screen point (cost::kLinePointSetup = 45
// operations: 2 slots, once per wheel and triangle, lines.point_setups). Declared here once; the
// sample_test unit's work of a record is raster.samples_tested + kLineTestSlots x lines.tests +
// kLinePointSetupSlots x lines.point_setups.
inline constexpr std::uint64_t lane_slots(std::uint64_t ops) { return (ops + cost::kInside4D - 1) / cost::kInside4D; }
inline constexpr std::uint64_t kLineTestSlots = lane_slots(cost::line_interval_cost(4, 0));
inline constexpr std::uint64_t kLinePointSetupSlots = lane_slots(cost::kLinePointSetup);
static_assert(kLineTestSlots == 2 && kLinePointSetupSlots == 2, "docs/timing.md states both");

struct UnitTiming {
  double throughput = 1.0;  // items per clock, > 0
  double latency = 0.0;     // clocks, >= 0
  std::int64_t fifo = 1;    // input FIFO entries, >= 1
};

struct TimingConfig {
  std::array<UnitTiming, kNumUnits> units{};  // dram: throughput = bytes/clock of the whole chip
  double tex_hit_latency = 0.0;   // added to the texture latency of a record with fetches, no misses
  double tex_miss_latency = 0.0;  // ... of a record with at least one texture-cache miss
  double fill_latency = 0.0;      // added to the depth latency of a record with depth-line fills
  int cores = 1;                  // parallel pipelines; bins round-robin; DRAM bandwidth split
  // A record with no work for a unit passes it at once (no latency, no FIFO slot), in order
  // (hardware.timing.idle_units 'bypass'); false: it traverses every unit ('traverse').
  bool bypass_idle = true;
  void validate() const;          // std::invalid_argument naming the field and the value
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
  // DRAM bytes by client, summed over the records.
  std::uint64_t dram_depth = 0, dram_color = 0, dram_texture = 0, dram_hiz = 0;
};

// The model over a stream of records: feed() them in stream order, then finish() once.
class TimingModel {
 public:
  explicit TimingModel(const TimingConfig& cfg);  // throws std::invalid_argument for a bad configuration
  void feed(const TileWork& w);
  TimingResult finish();

 private:
  struct Pipeline {  // one core's units
    std::array<std::uint64_t, kNumUnits> n{};           // records that occupy each unit, so far
    std::array<double, kNumUnits> prev_depart{}, busy{}, blocked{};
    std::array<std::vector<double>, kNumUnits> starts;  // ring: S(i, k) of the last F(k) records
    double end = 0.0;
  };
  TimingConfig cfg_;
  std::array<double, kNumUnits> inv_tp_{};
  std::vector<Pipeline> cores_;
  std::uint64_t unbinned_ = 0;
  TimingResult r_;
};

// The model over a whole record array (the same arithmetic as feeding them one by one).
TimingResult simulate_timing(const TileWork* records, std::size_t n, const TimingConfig& cfg);

// (name, unit, description) of every figure simulate_timing exports (timing.cycles,
// timing.<unit>.busy_cycles, ...). Derived figures (stall, utilisation, bottleneck) are in
// sim/timing.py.
struct TimingFigure {
  std::string name, unit, description;
};
std::vector<TimingFigure> timing_figures();

}  // namespace rast5d
