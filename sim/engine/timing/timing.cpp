// The timing model (docs/timing.md). A record i visits units k = 0..K-1 in order. With s(i,k) =
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

std::uint64_t TileWork::amount(Unit u) const {
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
    case Unit::memory: return memory_bytes;
    case Unit::kCount: break;
  }
  return 0;
}

TileWork TileWork::since(const TileWork& b) const {
  TileWork w;
  w.gs_ops = gs_ops - b.gs_ops;
  w.gs_floats = gs_floats - b.gs_floats;
  w.raster_pixels = raster_pixels - b.raster_pixels;
  w.ps_ops = ps_ops - b.ps_ops;
  w.tile_tests = tile_tests - b.tile_tests;
  w.sample_tests = sample_tests - b.sample_tests;
  w.depth_tests = depth_tests - b.depth_tests;
  w.quads = quads - b.quads;
  w.texel_fetches = texel_fetches - b.texel_fetches;
  w.tex_misses = tex_misses - b.tex_misses;
  w.memory_bytes = memory_bytes - b.memory_bytes;
  return w;
}

TileWork work_from_counters(const Counters& c) {
  auto d = [&](Counter k) { return c[k]; };
  TileWork w;
  w.tile_tests = d(Counter::tile_visited);
  // Sample tests run in a conventional GPU's pixel shader are pixel_shader work (gpu.ps_ops), not
  // the fixed-function sample-test unit's.
  w.sample_tests = d(Counter::raster_samples_tested) - d(Counter::gpu_ps_samples_tested)
                   + d(Counter::lines_tests);  // a line test is one item
  w.gs_ops = d(Counter::gpu_gs_ops);
  w.gs_floats = d(Counter::gpu_gs_floats);
  w.raster_pixels = d(Counter::gpu_raster_pixels_tested);
  w.ps_ops = d(Counter::gpu_ps_ops);
  // Line samples: a segment offered to its line's buffer and a composite step (the nearest
  // covering segment of one elementary interval) are one depth-unit item each, as a covered
  // point sample's depth test is.
  w.depth_tests = d(Counter::depth_tests) + d(Counter::lines_segments) + d(Counter::lines_composite_steps);
  w.quads = d(Counter::shade_quad_requests);
  w.texel_fetches = d(Counter::tex_fetches) + d(Counter::gpu_perturb_fetches);  // + the GPU's perturbation texture
  // Memory: per-sample depth traffic and HiZ traffic (depth.*, hiz.*). Texture-cache misses and
  // the line bytes they fetch are added per record by the cache replay after the render
  // (traversal/render.cpp), since the cache is simulated in bin order once all bins are done.
  w.memory_bytes = d(Counter::depth_bytes_read) + d(Counter::depth_bytes_written) + d(Counter::hiz_bytes_read) +
                   d(Counter::hiz_bytes_written);
  return w;
}

namespace {

void check(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

// One pipeline consuming its record stream (indices into records) in order.
double run_pipeline(const TileWork* records, const std::vector<std::uint32_t>& stream,
                    const TimingConfig& cfg, double memory_throughput, std::array<UnitStats, kNumUnits>& st) {
  const std::size_t n = stream.size();
  if (n == 0) return 0.0;
  std::array<double, kNumUnits> inv_tp{}, prev_depart{};
  std::array<std::size_t, kNumUnits> fifo{};
  std::array<std::vector<double>, kNumUnits> starts;  // ring: S(i, k) of the last F(k) records
  for (int k = 0; k < kNumUnits; ++k) {
    const double tp = k == static_cast<int>(Unit::memory) ? memory_throughput : cfg.units[k].throughput;
    inv_tp[k] = 1.0 / tp;
    // A FIFO at least as deep as the stream never refuses a record: no ring needed.
    fifo[k] = static_cast<std::uint64_t>(cfg.units[k].fifo) >= n ? 0 : static_cast<std::size_t>(cfg.units[k].fifo);
    if (k > 0 && fifo[k]) starts[k].assign(fifo[k], 0.0);
  }
  constexpr int kTex = static_cast<int>(Unit::texture);
  std::array<double, kNumUnits> busy{}, blocked{};
  double end = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const TileWork& w = records[stream[i]];
    double arrive = 0.0;
    for (int k = 0; k < kNumUnits; ++k) {
      const double start = std::max(arrive, prev_depart[k]);
      const double service = static_cast<double>(w.amount(static_cast<Unit>(k))) * inv_tp[k];
      const double done = start + service;
      double depart = done;
      if (k + 1 < kNumUnits && fifo[k + 1] && i >= fifo[k + 1])
        depart = std::max(done, starts[k + 1][i % fifo[k + 1]]);  // S(i - F(k+1), k+1)
      if (k > 0 && fifo[k]) starts[k][i % fifo[k]] = start;
      busy[k] += service;
      blocked[k] += depart - done;
      prev_depart[k] = depart;
      double latency = cfg.units[k].latency;
      if (k == kTex && w.texel_fetches) latency += w.tex_misses ? cfg.tex_miss_latency : cfg.tex_hit_latency;
      arrive = depart + latency;
    }
    end = std::max(end, arrive);
  }
  for (int k = 0; k < kNumUnits; ++k) {
    st[k].busy += busy[k];
    st[k].blocked += blocked[k];
    st[k].starved += std::max(0.0, end - busy[k] - blocked[k]);
  }
  return end;
}

}  // namespace

TimingResult simulate_timing(const TileWork* records, std::size_t n, const TimingConfig& cfg) {
  for (int k = 0; k < kNumUnits; ++k) {
    const std::string name(kUnitInfo[k].name);
    const UnitTiming& u = cfg.units[k];
    check(u.throughput > 0 && u.throughput < std::numeric_limits<double>::infinity(),
          name + ".throughput: expected > 0 and finite, got " + std::to_string(u.throughput));
    check(u.latency >= 0 && u.latency < std::numeric_limits<double>::infinity(),
          name + ".latency_cycles: expected >= 0, got " + std::to_string(u.latency));
    check(u.fifo >= 1, name + ".fifo_entries: expected >= 1, got " + std::to_string(u.fifo));
  }
  check(cfg.tex_hit_latency >= 0 && cfg.tex_miss_latency >= 0, "tex_cache latencies: expected >= 0");
  check(cfg.cores >= 1 && cfg.cores <= 4096, "cores: expected 1..4096, got " + std::to_string(cfg.cores));

  TimingResult r;
  r.records = n;
  r.cores = cfg.cores;
  // Bins are dealt round-robin to the cores by bin index; unbinned records (bin < 0) in turn.
  std::vector<std::vector<std::uint32_t>> streams(cfg.cores);
  std::uint64_t unbinned = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t b = records[i].bin;
    const std::uint64_t core = b >= 0 ? static_cast<std::uint64_t>(b) % cfg.cores : unbinned++ % cfg.cores;
    streams[core].push_back(static_cast<std::uint32_t>(i));
    for (int k = 0; k < kNumUnits; ++k) r.units[k].work += static_cast<double>(records[i].amount(static_cast<Unit>(k)));
  }
  const double memory_throughput = cfg.units[static_cast<int>(Unit::memory)].throughput / cfg.cores;
  std::vector<double> ends(cfg.cores);
  for (int c = 0; c < cfg.cores; ++c) {
    ends[c] = run_pipeline(records, streams[c], cfg, memory_throughput, r.units);
    r.cycles = std::max(r.cycles, ends[c]);
  }
  // A core that finishes early idles until the frame ends: starved.
  for (int c = 0; c < cfg.cores; ++c)
    for (auto& u : r.units) u.starved += r.cycles - ends[c];
  return r;
}

std::vector<TimingFigure> timing_figures() {
  std::vector<TimingFigure> out = {
      {"timing.cycles", "clocks", "Estimated clocks per frame: the last work record leaves the last unit (docs/timing.md)"},
      {"timing.records", "records", "Work records fed to the timing model (one per triangle and screen bin visited, one per culled triangle, one per bin with end-of-bin work)"},
      {"timing.cores", "pipelines", "Parallel pipelines modelled (hardware.cores); per-unit clocks are summed over them"},
  };
  for (const auto& u : kUnitInfo)
    for (const auto& f : kUnitFigures)
      out.push_back({"timing." + std::string(u.name) + "." + f.suffix, f.unit ? f.unit : std::string(u.currency),
                     std::string(u.description) + ": " + f.what});
  return out;
}

}  // namespace rast5d
