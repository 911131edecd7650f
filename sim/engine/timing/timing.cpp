// The timing model (docs/timing.md), streamed: TimingModel::feed() takes one record at a time. A record i visits units k = 0..K-1 in order. With s(i,k) =
// work / throughput, L(i,k) the latency, F(k) the input FIFO depth of unit k:
//   A(i,0)   = 0                                      (the bin lists in memory never run dry)
//   S(i,k)   = max(A(i,k), D(i-1,k))                  start: input present and the unit free
//   C(i,k)   = S(i,k) + s(i,k)                        the unit has accepted all the record's work
//   D(i,k)   = max(C(i,k), S(i-F(k+1), k+1))          leave: a credit (FIFO slot) in unit k+1
//   A(i,k+1) = D(i,k) + L(i,k)                        the record reaches unit k+1's FIFO head
//   cycles   = max_i A(i,K)                            (A(i,K): out of the last unit)
// The unit holds a finished record until it may leave (blocking after service); the FIFO slot
// is reserved when the record leaves unit k, so F(k+1) bounds the records in unit k's latency
// pipeline plus unit k+1's queue (credit-based flow control). Every step is max and +, so every
// time is a nondecreasing function of the others; a larger F only replaces S(i-F, k+1) by an
// earlier start (S is nondecreasing in i), hence deeper FIFOs are never slower. Since S(i,k) >=
// C(i-1,k), C(N-1,k) >= sum_i s(i,k), and cycles >= C(N-1,k) for every k.
#include "timing/timing.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace rast5d {

bool TileWork::empty() const {
  return !(triangles || gs_ops || gs_floats || raster_pixels || ps_ops || tile_tests || sample_tests || depth_tests ||
           depth_fills || quads || texel_fetches || tex_misses || dram_bytes);
}

TileWork work_from_counters(const Counters& c, const MemoryTotalsView& mem) {
  auto d = [&](Counter k) { return c[k]; };
  TileWork w;
  w.tile_tests = d(Counter::tile_visited);
  // Sample tests run in a conventional GPU's pixel shader are pixel_shader work (gpu.ps_ops), not
  // the fixed-function sample-test unit's.
  // A line test and a wheel's lens-space set-up take the lane slots of their operations (timing.h).
  w.sample_tests = d(Counter::raster_samples_tested) - d(Counter::gpu_ps_samples_tested)
                   + kLineTestSlots * d(Counter::lines_tests) + kLinePointSetupSlots * d(Counter::lines_point_setups);
  // The shader ALUs: a GPU geometry shader's bounds, and the vertex shading accumulation buffering
  // repeats every pass; the setup unit: the triangles accumulation re-sends every pass (the recorder
  // adds each triangle's own set-up in its home bin).
  w.gs_ops = d(Counter::gpu_gs_ops) + d(Counter::accum_vertex_ops);
  w.triangles = d(Counter::accum_resends);
  w.gs_floats = d(Counter::gpu_gs_floats);
  w.raster_pixels = d(Counter::gpu_raster_pixels_tested);
  w.ps_ops = d(Counter::gpu_ps_ops);
  // Line samples: a segment offered to its line's buffer and a composite step (the nearest
  // covering segment of one elementary interval) are one depth-unit item each, as a covered
  // point sample's depth test is.
  w.depth_tests = d(Counter::depth_tests) + d(Counter::lines_segments) + d(Counter::lines_composite_steps);
  w.quads = d(Counter::shade_quad_requests);
  w.texel_fetches = d(Counter::tex_fetches) + d(Counter::gpu_perturb_fetches);  // + the GPU's perturbation texture
  // DRAM: with the depth-tile cache, its line fills and write-backs; without it every per-sample depth
  // read and write (depth.bytes_*). Colour lines only with the colour buffer modelled. HiZ traffic goes
  // to DRAM as counted (hiz.bytes_*).
  w.dram_depth = mem.depth ? mem.depth_dram : d(Counter::depth_bytes_read) + d(Counter::depth_bytes_written);
  w.depth_fills = mem.depth ? mem.depth_fills : 0;
  // Colour: the colour cache's lines and the resolve, and accumulation buffering's full-screen passes.
  w.dram_color = mem.color ? mem.color_dram + d(Counter::accum_buffer_bytes) : 0;
  w.dram_hiz = d(Counter::hiz_bytes_read) + d(Counter::hiz_bytes_written);
  w.dram_bytes = w.dram_depth + w.dram_color + w.dram_hiz;
  return w;
}

namespace {

void check(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

constexpr int kTex = static_cast<int>(Unit::texture);
constexpr int kDepth = static_cast<int>(Unit::depth);
constexpr int kDram = static_cast<int>(Unit::dram);

}  // namespace

void TimingConfig::validate() const {
  for (int k = 0; k < kNumUnits; ++k) {
    const std::string name(kUnitInfo[k].name);
    const UnitTiming& u = units[k];
    const std::string tp = k == kDram ? "dram.bytes_per_clock" : name + ".throughput";
    check(u.throughput > 0 && u.throughput < std::numeric_limits<double>::infinity(),
          tp + ": expected > 0 and finite, got " + std::to_string(u.throughput));
    check(u.latency >= 0 && u.latency < std::numeric_limits<double>::infinity(),
          name + ".latency_cycles: expected >= 0, got " + std::to_string(u.latency));
    check(u.fifo >= 1, name + ".fifo_entries: expected >= 1, got " + std::to_string(u.fifo));
  }
  check(tex_hit_latency >= 0 && tex_miss_latency >= 0, "tex_cache latencies: expected >= 0");
  check(fill_latency >= 0 && fill_latency < std::numeric_limits<double>::infinity(),
        "dram.latency_cycles: expected >= 0, got " + std::to_string(fill_latency));
  check(cores >= 1 && cores <= 4096, "cores: expected 1..4096, got " + std::to_string(cores));
}

TimingModel::TimingModel(const TimingConfig& cfg) : cfg_(cfg), cores_(static_cast<std::size_t>(cfg.cores)) {
  cfg_.validate();
  r_.cores = cfg.cores;
  for (int k = 0; k < kNumUnits; ++k) {
    // The DRAM bandwidth is split evenly between the cores (a static partition).
    const double tp = k == kDram ? cfg.units[k].throughput / cfg.cores : cfg.units[k].throughput;
    inv_tp_[k] = 1.0 / tp;
  }
}

// One record through one core's units (the recursion of docs/timing.md). With bypass_idle a record
// occupies only the units it has work for: elsewhere it waits for its predecessor (in order) and
// passes at once, without latency and without a FIFO slot; a FIFO of F entries then holds the last F
// records that have work for its unit.
void TimingModel::feed(const TileWork& w) {
  ++r_.records;
  std::array<double, kNumUnits> amount;
  for (int k = 0; k < kNumUnits; ++k) {
    amount[k] = static_cast<double>(w.amount(static_cast<Unit>(k)));
    r_.units[k].work += amount[k];
  }
  r_.dram_depth += w.dram_depth, r_.dram_color += w.dram_color;
  r_.dram_texture += w.dram_texture, r_.dram_hiz += w.dram_hiz;
  // Bins are dealt round-robin to the cores by bin index; unbinned records (bin < 0) in turn.
  const std::uint64_t core = w.bin >= 0 ? static_cast<std::uint64_t>(w.bin) % cfg_.cores : unbinned_++ % cfg_.cores;
  Pipeline& pl = cores_[core];
  std::array<bool, kNumUnits> occupies;
  for (int k = 0; k < kNumUnits; ++k) occupies[k] = !cfg_.bypass_idle || amount[k] > 0;
  double arrive = 0.0;
  for (int k = 0; k < kNumUnits; ++k) {
    const double start = std::max(arrive, pl.prev_depart[k]);
    const double service = amount[k] * inv_tp_[k];
    const double done = start + service;
    double depart = done;
    if (k + 1 < kNumUnits && occupies[k + 1]) {  // a credit in unit k+1's FIFO: S(i - F(k+1), k+1)
      const std::uint64_t f = static_cast<std::uint64_t>(cfg_.units[k + 1].fifo);
      const std::uint64_t i = pl.n[k + 1];
      if (i >= f) depart = std::max(done, pl.starts[k + 1][i % f]);
    }
    if (k > 0 && occupies[k]) {  // remember S(i, k) for the records F(k) behind
      const std::uint64_t f = static_cast<std::uint64_t>(cfg_.units[k].fifo);
      const std::uint64_t i = pl.n[k];
      auto& ring = pl.starts[k];
      if (ring.size() < f && ring.size() == i) ring.push_back(start);  // grows to F entries
      else ring[i % f] = start;
    }
    if (occupies[k]) ++pl.n[k];
    pl.busy[k] += service;
    pl.blocked[k] += depart - done;
    pl.prev_depart[k] = depart;
    double latency = occupies[k] ? cfg_.units[k].latency : 0.0;
    if (k == kTex && w.texel_fetches) latency += w.tex_misses ? cfg_.tex_miss_latency : cfg_.tex_hit_latency;
    if (k == kDepth && w.depth_fills) latency += cfg_.fill_latency;
    arrive = depart + latency;
  }
  pl.end = std::max(pl.end, arrive);
}

TimingResult TimingModel::finish() {
  TimingResult r = r_;
  for (const Pipeline& pl : cores_) {
    for (int k = 0; k < kNumUnits; ++k) {
      r.units[k].busy += pl.busy[k];
      r.units[k].blocked += pl.blocked[k];
      r.units[k].starved += std::max(0.0, pl.end - pl.busy[k] - pl.blocked[k]);
    }
    r.cycles = std::max(r.cycles, pl.end);
  }
  // A core that finishes early idles until the frame ends: starved.
  for (const Pipeline& pl : cores_)
    for (auto& u : r.units) u.starved += r.cycles - pl.end;
  return r;
}

TimingResult simulate_timing(const TileWork* records, std::size_t n, const TimingConfig& cfg) {
  TimingModel m(cfg);
  for (std::size_t i = 0; i < n; ++i) m.feed(records[i]);
  return m.finish();
}

std::vector<TimingFigure> timing_figures() {
  std::vector<TimingFigure> out = {
      {"timing.cycles", "clocks", "Estimated clocks per frame: the last work record leaves the last unit (docs/timing.md)"},
      {"timing.records", "records", "Work records fed to the timing model (one per visit, or per triangle and screen bin with hardware.timing.granularity 'bin'; one per culled triangle; one per bin with end-of-bin work)"},
      {"timing.cores", "pipelines", "Parallel pipelines modelled (hardware.cores); per-unit clocks are summed over them"},
      {"dram.bytes", "bytes", "DRAM traffic of every client: dram.bytes_depth + dram.bytes_color + dram.bytes_texture + dram.bytes_hiz"},
      {"dram.bytes_depth", "bytes", "DRAM traffic of the depth buffer: line fills and write-backs of the depth-tile cache (with hardware.depth_buffer.enabled false: 4 bytes per depth read and write)"},
      {"dram.bytes_color", "bytes", "DRAM traffic of the colour sample buffer: line fills and write-backs, and the per-bin resolve (0 with hardware.color_buffer.enabled false)"},
      {"dram.bytes_texture", "bytes", "DRAM traffic of the texture caches: line fills (tex.cache.bytes_fetched)"},
      {"dram.bytes_hiz", "bytes", "DRAM traffic of HiZ: hiz.bytes_read + hiz.bytes_written"},
  };
  for (const auto& u : kUnitInfo)
    for (const auto& f : kUnitFigures)
      out.push_back({"timing." + std::string(u.name) + "." + f.suffix, f.unit ? f.unit : std::string(u.currency),
                     std::string(u.description) + ": " + f.what});
  return out;
}

}  // namespace rast5d
