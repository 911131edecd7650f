#include "traversal/render.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "sampletest/precision.h"
#include "setup/setup.h"
#include "tiletest/tile_test.h"
#include "traversal/bin_covariates.h"
#include "traversal/bin_sample.h"
#include "traversal/sampled_setup.h"
#include "traversal/traversal.h"

namespace rast5d {

std::vector<AlgorithmEntry> algorithms() {
  std::vector<AlgorithmEntry> out;
  for (const auto& [name, info] : TraversalRegistry::entries())
    out.push_back({name, info.description, info.needs_interleaved_table, info.line_samples() ? "lines" : "points",
                   info.tables == TableKinds::kLines         ? "lines"
                   : info.tables == TableKinds::kInterleaved ? "interleaved"
                                                             : "points",
                   info.depth_cull, info.pipeline == PipelineKind::kGpu ? "gpu" : "sample"});
  return out;
}

void validate_frame_params(const RenderParams& p) {
  auto fail = [](const std::string& m) { throw std::invalid_argument(m); };
  validate_domains(p);  // every numeric parameter against its params.def domain
  if (p.bin_size % 8 != 0) fail("bin_size: expected a multiple of 8, got " + std::to_string(p.bin_size));
  if (p.time_strata % p.time_splits != 0)  // each time stratum lies in one sub-interval
    fail("time_strata: expected a multiple of time_splits, got " + std::to_string(p.time_splits) + " / " +
         std::to_string(p.time_strata));
  // What one params.def row cannot say: the texture cache's line size is a power of two and its
  // lines fill whole sets.
  const int lb = p.tex_cache_line_bytes;
  if (lb & (lb - 1)) fail("tex_cache_line_bytes: expected a power of two, got " + std::to_string(lb));
  if (p.tex_cache_size_bytes % lb)
    fail("tex_cache_size_bytes: expected a multiple of the line size, got " + std::to_string(p.tex_cache_size_bytes));
  if (p.tex_cache_ways && (p.tex_cache_size_bytes / lb) % p.tex_cache_ways)
    fail("tex_cache_ways: expected 0 or a divisor of the number of lines, got " + std::to_string(p.tex_cache_ways));
}

void validate_params(const RenderParams& p, const SampleTable& table) {
  auto fail = [](const std::string& m) { throw std::invalid_argument(m); };
  validate_frame_params(p);
  const auto& reg = TraversalRegistry::entries();
  auto it = reg.find(p.algorithm);
  if (it == reg.end()) {
    std::string names;
    for (const auto& kv : reg) names += (names.empty() ? "" : ", ") + kv.first;
    fail("algorithm: unknown '" + p.algorithm + "' (known: " + names + ")");
  }
  if (it->second.needs_interleaved_table && table.n_lens() == 0)
    fail("algorithm: '" + p.algorithm +
         "' needs an interleaved sample table (SampleTable.interleaved), got a table without "
         "discrete lens coordinates");
  // Occlusion queries are answered by the depth-cull stage (backend/zcull.h); algorithms without it
  // would draw the query triangles as occluders.
  if (p.query_first >= 0 && p.query_mode != QueryMode::kNone && !it->second.depth_cull) {
    std::string names;
    for (const auto& kv : reg)
      if (kv.second.depth_cull) names += (names.empty() ? "'" : ", '") + kv.first + "'";
    fail("algorithm: occlusion queries are answered by the algorithms with a depth-cull stage (" + names + "); got '" +
         p.algorithm + "'");
  }
  const bool lines_algo = it->second.line_samples();
  const std::string quoted = "'" + p.algorithm + "'";
  if (lines_algo != p.table_lines)
    fail(lines_algo ? "algorithm: " + quoted + " tests line samples and needs a line-sample table (SampleTable.lines), "
                      "got a point-sample table"
                    : "algorithm: " + quoted +
                          " tests point samples, got a line-sample table (SampleTable.lines needs a line-sample "
                          "algorithm)");
  if (lines_algo && p.lens_shape != LensShape::kDisk)
    fail("lens_shape: line samples (algorithm " + quoted + ") cross the disk lens through its centre; got a non-disk lens");
  if (lines_algo && p.shading == ShadingMode::kPerLensCell)
    fail("shading: line samples have no lens-grid cells, so 'per_lens_cell' does not apply to algorithm " + quoted +
         "; use 'none', 'per_sample', 'msaa' or 'cache'");
  if (p.lens_grid != table.grid())
    fail("lens_grid: the sample table was bucketed for G=" + std::to_string(table.grid()) +
         ", got " + std::to_string(p.lens_grid));
}

// The cache lines of a triangle's set-up (TriSetup is several lines; a bin's list visits set-ups far
// apart in memory), fetched a few triangles ahead (small triangles take less than a miss's latency).
static inline void prefetch_setup(const TriSetup& t) {
  const char* p = reinterpret_cast<const char*>(&t);
  for (std::size_t o = 0; o < sizeof(TriSetup); o += 64) __builtin_prefetch(p + o);
}

// The per-render shading constants: textures with mip chains and addresses, per-triangle texture
// slots, uvs, analytic uv derivatives and levels of detail (backend/texture.h).
static void build_shade_frame(const RenderParams& p, const SceneArrays& scene, const TriSetup* setups,
                              const std::vector<char>& alive, int n_bins, ShadeFrame& sf) {
  sf.mode = p.shading;
  sf.grid = p.shading_grid;
  sf.cache_entries = p.shading_cache_entries;
  sf.filter = p.texture_filter;
  sf.line_bytes = p.tex_cache_line_bytes;
  const bool have_tex = scene.uvs && scene.tex_slots && !scene.textures.empty();
  sf.texture_count = have_tex ? p.texture_count : 0;
  sf.sample_dist_tex = !scene.textures.empty() ? p.texture_sample_distribution_index : -1;
  if (sf.sample_dist_tex >= static_cast<int>(scene.textures.size()))
    throw std::invalid_argument("texture_sample_distribution_index: no texture " +
                                std::to_string(sf.sample_dist_tex));
  if (!sf.textured()) return;
  for (const auto& t : scene.textures) sf.textures.add(t.data, t.height, t.width, t.channels);
  sf.textures.layout(p.texture_layout);
  if (sf.mode != ShadingMode::kNone) sf.streams.assign(static_cast<std::size_t>(n_bins), {});
  if (sf.texture_count == 0) return;
  const std::size_t n = static_cast<std::size_t>(scene.n);
  sf.uvs.assign(scene.uvs, scene.uvs + n * 6);
  sf.tex_ids.assign(scene.tex_slots, scene.tex_slots + n * kMaxTexSlots);
  for (std::size_t i = 0; i < sf.tex_ids.size(); ++i) {
    std::int32_t& id = sf.tex_ids[i];
    if (static_cast<int>(i % kMaxTexSlots) >= sf.texture_count) {
      id = -1;
    } else if (id < -1 || id >= sf.textures.size()) {
      throw std::invalid_argument("tex_slots: triangle " + std::to_string(i / kMaxTexSlots) + " uses texture " +
                                  std::to_string(id) + ", expected -1.." + std::to_string(sf.textures.size() - 1));
    }
  }
  sf.jac.assign(n * 4, 0.0);
  sf.lod.assign(n * kMaxTexSlots, 0.0f);
  for (std::size_t i = 0; i < n; ++i) {
    if (!alive[i]) continue;
    const TriSetup& t = setups[i];
    uv_jacobian(t.X, t.Y, t.W, &sf.uvs[i * 6], p.near_w, &sf.jac[i * 4]);
    for (int k = 0; k < kMaxTexSlots; ++k) {
      const int id = sf.tex_ids[i * kMaxTexSlots + k];
      if (id >= 0) {
        const MipLevel& l0 = sf.textures[id].levels[0];
        sf.lod[i * kMaxTexSlots + k] = lod_from_jacobian(&sf.jac[i * 4], l0.w, l0.h);
      }
    }
  }
}

RenderResult render(const RenderParams& p, const SceneArrays& scene, const SampleTable& table,
                    const std::function<bool()>& interrupted, bool export_samples,
                    const std::vector<int>* bins, const RenderObservers& observers) {
  validate_params(p, table);
  PixelStats* const pstats = observers.pixel_stats;
  const FrameConst fc = make_frame_const(p);
  const int n_threads = p.threads > 0
                            ? p.threads
                            : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  RenderResult result;
  result.image.assign(static_cast<std::size_t>(p.width) * p.height * 3, 0.0f);
  if (export_samples) {
    const std::size_t n = static_cast<std::size_t>(p.width) * p.height * table.spp();
    result.sample_depth.assign(n, 0.0f);
    result.sample_triangle.assign(n, -1);
  }

  // ---- setup: static partition over triangles, each thread its own counters ----
  std::vector<std::uint64_t> frame_pool;  // per-pixel statistics with no pixel bounds
  // Sampled simulation or a bin list: setup only for the triangles that reach the drawn bins, their
  // setup counters in their home bins' rows (traversal/sampled_setup.h). Their set-ups are constructed
  // in storage left unconstructed elsewhere (only the set-up triangles' pages are touched).
  const bool restricted = (bins || p.sample_fraction < 1.0) && !pstats && !p.record_timing;
  std::vector<TriSetup> setups(restricted ? 0 : static_cast<std::size_t>(scene.n));
  UnconstructedSetups sparse_setups;
  TriSetup* const S = restricted ? sparse_setups.allocate(static_cast<std::size_t>(scene.n)) : setups.data();
  std::vector<char> alive(static_cast<std::size_t>(scene.n), 0);
  std::vector<Counters> setup_counters(n_threads);
  std::vector<int> restricted_bins;
  std::vector<Counters> homed_setup;
  if (restricted) {
    sampled_setup(p, fc, scene, table.spp(), bins, S, alive, setup_counters[0], homed_setup, restricted_bins,
                  result);
    bins = &restricted_bins;
  }
  {
    auto work = [&](int t) {
      const int lo = static_cast<int>(static_cast<long long>(scene.n) * t / n_threads);
      const int hi = static_cast<int>(static_cast<long long>(scene.n) * (t + 1) / n_threads);
      for (int i = lo; i < hi; ++i) {
        const float* v0 = scene.v0 + static_cast<std::size_t>(i) * 9;
        const float* v1 = scene.v1 + static_cast<std::size_t>(i) * 9;
        const float* col = scene.colors + static_cast<std::size_t>(i) * 9;
        alive[i] = p.op_count == OpCount::kExact
                       ? setup_triangle<ExactArith>(v0, v1, col, i, p, fc, S[i], setup_counters[t])
                       : setup_triangle<FastArith>(v0, v1, col, i, p, fc, S[i], setup_counters[t]);
        if (scene.alpha) S[i].alpha = scene.alpha[i];
      }
    };
    if (pstats) {  // per-pixel statistics: one thread, each triangle's setup charged to its bounds
      PixelCursor cur;
      cur.attach(pstats);
      for (int i = 0; i < scene.n; ++i) {
        const float* v0 = scene.v0 + static_cast<std::size_t>(i) * 9;
        const float* v1 = scene.v1 + static_cast<std::size_t>(i) * 9;
        const float* col = scene.colors + static_cast<std::size_t>(i) * 9;
        alive[i] = p.op_count == OpCount::kExact
                       ? setup_triangle<ExactArith>(v0, v1, col, i, p, fc, S[i], setup_counters[0])
                       : setup_triangle<FastArith>(v0, v1, col, i, p, fc, S[i], setup_counters[0]);
        if (scene.alpha) S[i].alpha = scene.alpha[i];
        const TriSetup& t = S[i];
        cur.triangle = i;
        cur.x0 = t.bx0, cur.y0 = t.by0, cur.x1 = t.bx1, cur.y1 = t.by1, cur.kind = 3;
        cur.commit(setup_counters[0], true);
        cur.commit(setup_counters[0], false);
      }
      frame_pool = cur.frame_pool;
      result.trace_events = std::move(cur.events);
    } else if (!restricted) {
      std::vector<std::thread> pool;
      for (int t = 1; t < n_threads; ++t) pool.emplace_back(work, t);
      work(0);
      for (auto& th : pool) th.join();
    }
  }
  std::vector<std::uint32_t> live;
  live.reserve(scene.n);
  for (int i = 0; i < scene.n; ++i)
    if (alive[i]) live.push_back(static_cast<std::uint32_t>(i));

  // ---- binning: each bin lists the triangles overlapping it, in submission order ----
  const int B = p.bin_size;
  const int bins_x = (p.width + B - 1) / B, bins_y = (p.height + B - 1) / B;
  const int n_bins = bins_x * bins_y;
  std::vector<std::vector<std::uint32_t>> bin_lists(n_bins);
  for (std::uint32_t i : live) {
    const TriSetup& t = S[i];
    for (int by = t.by0 / B; by <= (t.by1 - 1) / B; ++by)
      for (int bx = t.bx0 / B; bx <= (t.bx1 - 1) / B; ++bx) bin_lists[by * bins_x + bx].push_back(i);
  }

  ShadeFrame shade_frame;
  build_shade_frame(p, scene, S, alive, n_bins, shade_frame);

  // ---- the bins to render: all, or a subset (a list, or sampled simulation) ----
  std::vector<int> drawn;
  if (!restricted && (bins || p.sample_fraction < 1.0)) {
    result.bin_work.assign(static_cast<std::size_t>(n_bins), 0);
    for (int b = 0; b < n_bins; ++b) {
      const int bx = b % bins_x, by = b / bins_x;
      const int x0 = bx * B, y0 = by * B, x1 = std::min(p.width, x0 + B), y1 = std::min(p.height, y0 + B);
      std::int64_t w = 0;
      for (std::uint32_t i : bin_lists[b]) {
        const TriSetup& t = S[i];
        const std::int64_t dx = std::min(t.bx1, x1) - std::max(t.bx0, x0), dy = std::min(t.by1, y1) - std::max(t.by0, y0);
        if (dx > 0 && dy > 0) w += dx * dy;
      }
      result.bin_work[b] = w * table.spp();
    }
    bin_covariates(setups, bin_lists, bins_x, B, p.width, p.height, table.spp(), result.bin_aux);
    result.bin_aux_total.assign(kBinAux, 0.0);  // every bin's auxiliaries computed: their sums
    for (int b = 0; b < n_bins; ++b)
      for (int j = 0; j < kBinAux; ++j) result.bin_aux_total[j] += result.bin_aux[kBinAux * b + j];
  }
  if (!bins && p.sample_fraction < 1.0) {
    BinSample s = stratify_bins(result.bin_work, p.sample_fraction, static_cast<std::uint64_t>(p.sample_seed));
    drawn = std::move(s.bins);
    result.sampled_stratum = std::move(s.stratum);
    result.strata_sizes = std::move(s.sizes);
    bins = &drawn;
  }
  if (bins) {
    result.sampled_bins = *bins;
    require_bin_list(*bins, n_bins);
    result.bin_counters.assign(bins->size() * static_cast<std::size_t>(kNumCounters), 0);
  }
  const int n_work = bins ? static_cast<int>(bins->size()) : n_bins;

  // ---- traversal: workers take whole bins ----
  // Timing records per bin: each bin is rasterized by exactly one worker, so its stream is
  // written without locks and its content does not depend on the thread count.
  std::vector<std::vector<TileWork>> bin_records(p.record_timing ? n_bins : 0);
  // The texture-cache line stream length after each record, so the cache replay can hand every
  // record its own misses (the cache is simulated after the render, in bin order).
  const bool track_stream_ends = p.record_timing && !shade_frame.streams.empty();
  std::vector<std::vector<std::uint32_t>> bin_stream_ends(track_stream_ends ? n_bins : 0);
  std::vector<ThreadState> states(n_threads);
  for (auto& s : states) s.shade.attach(&shade_frame, &s.counters);
  std::vector<PixelCursor> cursors(pstats ? n_threads : 0);
  for (int t = 0; t < static_cast<int>(cursors.size()); ++t) {
    cursors[t].attach(pstats);
    states[t].cursor = &cursors[t];
  }
  const int trace_bin =
      pstats && pstats->tracing() ? (pstats->trace_y / B) * bins_x + pstats->trace_x / B : -1;
  std::atomic<int> bins_done{0};
  std::atomic<int> next_bin{0};
  std::atomic<bool> cancel{false};
  std::atomic<int> running{n_threads};
  std::mutex mu;
  std::condition_variable cv;
  std::exception_ptr error;
  const Frame frame{p, fc, table};
  auto worker = [&](int t) {
    try {
      tiletest::t_snap_margin_px = snap_margin_px(p.precision_sample, p.precision_tile);  // this thread's tiles
      ThreadState& ts = states[t];
      auto algo = TraversalRegistry::entries().at(p.algorithm).create(frame, ts, p.op_count == OpCount::kExact);
      const bool per_visit = p.record_timing && p.timing_per_visit;
      std::vector<TileWork> visit_recs;
      std::vector<std::uint32_t> visit_ends;
      for (;;) {
        const int k = next_bin.fetch_add(1);
        if (k >= n_work || cancel.load(std::memory_order_relaxed)) break;
        const int b = bins ? (*bins)[k] : k;
        const Counters at_start = bins ? ts.counters : Counters{};
        if (trace_bin >= 0 && b != trace_bin) continue;
        const int bx = b % bins_x, by = b / bins_x;
        BinRect r{bx * B, by * B, std::min(p.width, (bx + 1) * B), std::min(p.height, (by + 1) * B)};
        ts.buffers.begin(r, table.spp());
        ts.shade.begin_bin(b);
        const std::vector<std::uint32_t>& list = bin_lists[b];
        for (std::size_t li = 0; li < list.size(); ++li) {
          const std::uint32_t i = list[li];
          if (cancel.load(std::memory_order_relaxed)) break;  // Ctrl-C: stop within one triangle
          if (li + 4 < list.size()) prefetch_setup(S[list[li + 4]]);  // a later triangle's set-up
          const TriSetup& tri = S[i];
          const bool home = (tri.by0 / B) * bins_x + (tri.bx0 / B) == b;
          const TileWork before = p.record_timing ? work_from_counters(ts.counters) : TileWork{};
          if (per_visit) {  // hardware.timing.granularity 'visit': end_visit() records (sample_pipeline.h)
            visit_recs.clear(), visit_ends.clear();
            ts.visit_mark = before;
            ts.visit_records = &visit_recs;
            ts.visit_stream = track_stream_ends ? &shade_frame.streams[b] : nullptr;
            ts.visit_stream_ends = track_stream_ends ? &visit_ends : nullptr;
          }
          PixelCursor* const cur = ts.cursor;
          const int rx0 = std::max(tri.bx0, r.x0), ry0 = std::max(tri.by0, r.y0);
          const int rx1 = std::min(tri.bx1, r.x1), ry1 = std::min(tri.by1, r.y1);
          if (cur) {  // the triangle's pixels in this bin until the algorithm aims finer
            cur->target(ts.counters, rx0, ry0, rx1, ry1, 0);
            cur->triangle = i;
          }
          algo->rasterize(tri, r, home);
          if (cur) {
            cur->target(ts.counters, rx0, ry0, rx1, ry1, 0);
            cur->commit(ts.counters, true);
          }
          if (!p.record_timing) continue;
          if (per_visit) {
            ts.visit_records = nullptr;
            // The visits' records, then what the triangle did after its last visit (if anything);
            // the triangle's setup goes with its first record.
            const TileWork rest = work_from_counters(ts.counters).since(ts.visit_mark);
            const bool rest_empty = rest.tile_tests == 0 && rest.sample_tests == 0 && rest.depth_tests == 0 &&
                                    rest.quads == 0 && rest.texel_fetches == 0 && rest.memory_bytes == 0;
            if (!rest_empty || visit_recs.empty()) {
              visit_recs.push_back(rest);
              if (track_stream_ends) visit_ends.push_back(static_cast<std::uint32_t>(shade_frame.streams[b].size()));
            }
            for (std::size_t k = 0; k < visit_recs.size(); ++k) {
              TileWork w = visit_recs[k];
              w.bin = b;
              w.triangles = (k == 0 && home) ? 1u : 0u;
              bin_records[b].push_back(w);
              if (track_stream_ends) bin_stream_ends[b].push_back(visit_ends[k]);
            }
            continue;
          }
          TileWork w = work_from_counters(ts.counters).since(before);
          w.bin = b;
          w.triangles = home ? 1u : 0u;  // setup is done once, charged in the triangle's first bin
          bin_records[b].push_back(w);
          if (track_stream_ends)
            bin_stream_ends[b].push_back(static_cast<std::uint32_t>(shade_frame.streams[b].size()));
        }
        {
          // End-of-bin work (the line-sample composite): its own record, after the bin's triangles.
          const TileWork before = p.record_timing ? work_from_counters(ts.counters) : TileWork{};
          algo->end_bin(r);
          if (p.record_timing) {
            TileWork w = work_from_counters(ts.counters).since(before);
            w.bin = b;
            if (w.depth_tests || w.sample_tests || w.tile_tests || w.quads || w.texel_fetches || w.memory_bytes ||
                w.gs_ops || w.gs_floats || w.raster_pixels || w.ps_ops) {
              bin_records[b].push_back(w);
              if (track_stream_ends)
                bin_stream_ends[b].push_back(static_cast<std::uint32_t>(shade_frame.streams[b].size()));
            }
          }
        }
        ts.shade.close_visit();  // algorithms end their visits; this only guards the contract
        if (ts.cursor) {
          ts.cursor->commit(ts.counters);
          ts.cursor->triangle = -1;
        }
        bins_done.fetch_add(1, std::memory_order_relaxed);
        ts.buffers.resolve(result.image.data(), p.width);
        if (export_samples)
          ts.buffers.export_samples(result.sample_depth.data(), result.sample_triangle.data(), p.width);
        if (bins) {  // this bin's counters: each row is written by the one worker that owns the bin
          std::uint64_t* row = &result.bin_counters[static_cast<std::size_t>(k) * kNumCounters];
          for (int i = 0; i < kNumCounters; ++i) row[i] = ts.counters.v[i] - at_start.v[i];
        }
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mu);
      if (!error) error = std::current_exception();
      cancel = true;
    }
    {
      std::lock_guard<std::mutex> lock(mu);
      --running;
    }
    cv.notify_all();
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < n_threads; ++t) pool.emplace_back(worker, t);
  {
    std::unique_lock<std::mutex> lock(mu);
    while (running.load() > 0) {
      cv.wait_for(lock, std::chrono::milliseconds(20));
      if (running.load() == 0) break;
      lock.unlock();
      const bool stop = interrupted && interrupted();
      if (observers.progress && !stop) observers.progress(bins_done.load(), n_work);
      lock.lock();
      if (stop) {
        cancel = true;
        result.interrupted = true;
      }
    }
  }
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);
  for (std::size_t k = 0; k < homed_setup.size(); ++k) {  // the setup of the triangles homed in drawn bin k
    std::uint64_t* row = &result.bin_counters[k * kNumCounters];
    for (int i = 0; i < kNumCounters; ++i) row[i] += homed_setup[k].v[i];
  }

  if (pstats) {  // what had no pixel bounds, over the whole frame; the trace in bin order
    for (const auto& cur : cursors) {
      for (std::size_t k = 0; k < frame_pool.size(); ++k) frame_pool[k] += cur.frame_pool[k];
      result.trace_events.insert(result.trace_events.end(), cur.events.begin(), cur.events.end());
      result.trace_samples.insert(result.trace_samples.end(), cur.samples.begin(), cur.samples.end());
    }
    for (std::size_t k = 0; k < frame_pool.size(); ++k)
      if (frame_pool[k]) pstats->spread(k, frame_pool[k], 0, 0, p.width, p.height);
  }
  for (const auto& c : setup_counters) result.counters.merge(c);
  for (const auto& s : states) result.counters.merge(s.counters);
  result.counters[Counter::frame_pixels] = static_cast<std::uint64_t>(p.width) * p.height;
  result.counters[Counter::frame_samples] =
      static_cast<std::uint64_t>(p.width) * p.height * table.spp();
  result.counters[Counter::frame_bins] = static_cast<std::uint64_t>(n_bins);
  if (shade_frame.textured() && shade_frame.mode != ShadingMode::kNone && !result.interrupted) {
    const std::uint64_t lines = static_cast<std::uint64_t>(p.tex_cache_size_bytes / p.tex_cache_line_bytes);
    std::vector<std::vector<std::uint32_t>> seg_misses;
    const CacheStats cs = simulate_texture_caches(shade_frame.streams, p.tex_cache_count, lines,
                                                  static_cast<std::uint64_t>(p.tex_cache_ways),
                                                  track_stream_ends ? &bin_stream_ends : nullptr,
                                                  track_stream_ends ? &seg_misses : nullptr);
    if (track_stream_ends)  // each record's texture misses and the line bytes they fetch (docs/timing.md)
      for (std::size_t b = 0; b < bin_records.size(); ++b)
        for (std::size_t k = 0; k < bin_records[b].size(); ++k) {
          bin_records[b][k].tex_misses += seg_misses[b][k];
          bin_records[b][k].memory_bytes += static_cast<std::uint64_t>(seg_misses[b][k]) * p.tex_cache_line_bytes;
        }
    Counters& c = result.counters;
    c[Counter::tex_cache_accesses] = cs.accesses;
    c[Counter::tex_cache_hits] = cs.hits;
    c[Counter::tex_cache_misses] = cs.misses;
    c[Counter::tex_cache_misses_cold] = cs.cold;
    c[Counter::tex_cache_misses_capacity] = cs.capacity;
    c[Counter::tex_cache_misses_conflict] = cs.conflict;
    c[Counter::tex_cache_bytes_fetched] = cs.misses * static_cast<std::uint64_t>(p.tex_cache_line_bytes);
  }
  if (p.record_timing && !result.interrupted) {
    std::size_t total = static_cast<std::size_t>(scene.n) - live.size();
    for (const auto& v : bin_records) total += v.size();
    result.timing_records.reserve(total);
    // Culled triangles still pass through setup: setup-only records, before the bins.
    TileWork culled;
    culled.bin = -1;
    culled.triangles = 1;
    result.timing_records.insert(result.timing_records.end(), static_cast<std::size_t>(scene.n) - live.size(), culled);
    for (const auto& v : bin_records) result.timing_records.insert(result.timing_records.end(), v.begin(), v.end());
  }
  return result;
}

}  // namespace rast5d
