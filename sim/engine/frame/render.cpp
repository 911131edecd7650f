#include "frame/render.h"

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <thread>

#include "frame/bin_stream.h"
#include "frame/binning.h"
#include "frame/setup_stage.h"
#include "frame/traverse.h"

namespace rast5d {

namespace {

// Counters that are whole-frame facts, and the texture caches' counters from the replay.
void assemble_counters(const RenderParams& p, const SampleTable& table, const Binning& bn, const FrameSetup& fs,
                       const std::vector<std::unique_ptr<Worker>>& workers, const TextureCacheReplay* replay,
                       RenderResult& result) {
  for (const auto& c : fs.counters) result.counters.merge(c);
  for (const auto& w : workers) result.counters.merge(w->ts.counters);
  Counters& c = result.counters;
  c[Counter::frame_pixels] = static_cast<std::uint64_t>(p.width) * p.height;
  c[Counter::frame_samples] = static_cast<std::uint64_t>(p.width) * p.height * table.spp();
  c[Counter::frame_bins] = static_cast<std::uint64_t>(bn.count());
  if (replay && !result.interrupted) {
    const CacheStats cs = replay->stats();
    c[Counter::tex_cache_accesses] = cs.accesses;
    c[Counter::tex_cache_hits] = cs.hits;
    c[Counter::tex_cache_misses] = cs.misses;
    c[Counter::tex_cache_misses_cold] = cs.cold;
    c[Counter::tex_cache_misses_capacity] = cs.capacity;
    c[Counter::tex_cache_misses_conflict] = cs.conflict;
    c[Counter::tex_cache_bytes_fetched] = cs.misses * static_cast<std::uint64_t>(p.tex_cache_line_bytes);
  }
}

// Per-pixel statistics: what had no pixel bounds, over the whole frame; the trace in bin order.
void assemble_pixel_stats(const RenderParams& p, const FrameSetup& fs, const std::vector<std::unique_ptr<Worker>>& workers,
                          PixelStats& pstats, RenderResult& result) {
  std::vector<std::uint64_t> pool = fs.frame_pool;
  result.trace_events = fs.trace_events;
  for (const auto& w : workers) {
    const PixelCursor& cur = w->pixels->cur;
    for (std::size_t k = 0; k < pool.size(); ++k) pool[k] += cur.frame_pool[k];
    result.trace_events.insert(result.trace_events.end(), cur.events.begin(), cur.events.end());
    result.trace_samples.insert(result.trace_samples.end(), cur.samples.begin(), cur.samples.end());
  }
  for (std::size_t k = 0; k < pool.size(); ++k)
    if (pool[k]) pstats.spread(k, pool[k], 0, 0, p.width, p.height);
}

}  // namespace

RenderResult render(const RenderParams& p, const SceneArrays& scene, const SampleTable& table,
                    const std::function<bool()>& interrupted, const RenderOptions& opt) {
  validate_params(p, table);
  const FrameConst fc = make_frame_const(p);
  const Frame frame{p, fc, table};
  const int n_threads =
      p.threads > 0 ? p.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  RenderResult result;
  result.image.assign(static_cast<std::size_t>(p.width) * p.height * 3, 0.0f);
  if (opt.export_samples) {
    const std::size_t n = static_cast<std::size_t>(p.width) * p.height * table.spp();
    result.sample_depth.assign(n, 0.0f);
    result.sample_triangle.assign(n, -1);
  }

  // ---- set-up ----
  FrameSetup fs = setup_stage(p, fc, scene, table.spp(), n_threads, opt.bins, opt.pixel_stats, result.sampled);
  // The work items' screen bins: with units of the dense bins (pipeline.sample_split), a bin may recur.
  const std::vector<int>* bins = fs.restricted ? (fs.split.empty() ? &fs.drawn : &fs.split.bins) : opt.bins;

  // ---- binning ----
  const Binning bn = bin_triangles(p, fs.S, fs.live);
  ShadeFrame shade;
  build_shade_frame(p, scene, fs.S, fs.alive, bn.count(), shade);

  // ---- the bins to traverse: all, a list, or sampled simulation's draw ----
  std::vector<int> drawn;
  if (!fs.restricted && (bins || p.sample_fraction < 1.0)) {
    whole_frame_bins(fs.setups, bn.lists, bn.bins_x, bn.size, p.width, p.height, table.spp(), result.sampled);
    if (!bins) {
      BinSample s = stratify_bins(result.sampled.bin_work, p.sample_fraction, static_cast<std::uint64_t>(p.sample_seed));
      drawn = std::move(s.bins);
      result.sampled.stratum = std::move(s.stratum);
      result.sampled.strata_sizes = std::move(s.sizes);
      bins = &drawn;
    }
  }
  if (!fs.split.empty() && !shade.streams.empty())
    throw std::invalid_argument("sample_split: units of a bin's triangles share its texture-line stream; "
                                "use shading 'none' or sample_split 0");
  if (bins) {
    result.sampled.bins = fs.split.empty() ? *bins : fs.drawn;
    if (fs.split.empty()) require_bin_list(*bins, bn.count());
    result.sampled.bin_counters.assign(bins->size() * static_cast<std::size_t>(kNumCounters), 0);
  }

  // ---- the bin stream's consumers: the texture-cache replay and the timing model ----
  std::unique_ptr<TextureCacheReplay> replay;
  if (!shade.streams.empty())
    replay = std::make_unique<TextureCacheReplay>(p.tex_cache_count,
                                                  static_cast<std::uint64_t>(p.tex_cache_size_bytes / p.tex_cache_line_bytes),
                                                  static_cast<std::uint64_t>(p.tex_cache_ways));
  std::unique_ptr<TimingModel> model;
  if (p.record_timing) {
    model = std::make_unique<TimingModel>(opt.timing ? *opt.timing : TimingConfig{});
    // Culled triangles still pass through setup: setup-only records, before the bins.
    TileWork culled;
    culled.bin = -1;
    culled.triangles = 1;
    const std::size_t n_culled = static_cast<std::size_t>(scene.n) - fs.live.size();
    for (std::size_t i = 0; i < n_culled; ++i) model->feed(culled);
    if (opt.keep_timing_records) result.timing_records.assign(n_culled, culled);
  }
  BinStream stream(bins ? static_cast<int>(bins->size()) : bn.count(), bins, BinStream::kBudget, replay.get(),
                   &shade.streams, model.get(), opt.keep_timing_records && model ? &result.timing_records : nullptr,
                   p.tex_cache_line_bytes);

  // ---- traversal, resolve per bin ----
  bool moving = false;
  for (const std::uint32_t i : fs.live) moving = moving || fs.S[i].moving;
  const TraversalJob job{p, frame, fs.S, bn, shade, bins, fs.split.empty() ? nullptr : &fs.split, moving, opt, interrupted};
  auto workers = make_workers(job, n_threads);
  traverse_bins(job, workers, stream, result);
  stream.finish();

  // ---- assembly ----
  for (std::size_t k = 0; k < fs.homed.size(); ++k) {  // the setup of the triangles homed in drawn bin k
    std::uint64_t* row = &result.sampled.bin_counters[k * kNumCounters];
    for (int i = 0; i < kNumCounters; ++i) row[i] += fs.homed[k].v[i];
  }
  if (opt.pixel_stats) assemble_pixel_stats(p, fs, workers, *opt.pixel_stats, result);
  assemble_counters(p, table, bn, fs, workers, replay.get(), result);
  if (model && !result.interrupted) {
    result.timed = true;
    result.timing = model->finish();
    result.memory_depth = p.depth_buffer_enabled;
    result.memory_color = p.color_buffer_enabled;
    for (const auto& w : workers)
      if (w->memory) result.memory.merge(w->memory->totals());
  } else {
    result.timing_records.clear();
  }
  return result;
}

}  // namespace rast5d
