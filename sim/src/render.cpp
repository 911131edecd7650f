#include "rast5d/render.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "rast5d/setup.h"
#include "rast5d/traversal.h"

namespace rast5d {

std::vector<AlgorithmEntry> algorithms() {
  std::vector<AlgorithmEntry> out;
  for (const auto& [name, info] : TraversalRegistry::entries())
    out.push_back({name, info.description, info.needs_interleaved_table});
  return out;
}

void validate_params(const RenderParams& p, const SampleTable& table) {
  auto fail = [](const std::string& m) { throw std::invalid_argument(m); };
  if (p.width < 1 || p.width > 16384) fail("width: expected 1..16384, got " + std::to_string(p.width));
  if (p.height < 1 || p.height > 16384)
    fail("height: expected 1..16384, got " + std::to_string(p.height));
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
  if (p.tile_size != 1 && p.tile_size != 2 && p.tile_size != 4 && p.tile_size != 8)
    fail("tile_size: expected 1, 2, 4 or 8, got " + std::to_string(p.tile_size));
  if (p.bin_size < 8 || p.bin_size % 8 != 0 || p.bin_size > 4096)
    fail("bin_size: expected a multiple of 8 in 8..4096, got " + std::to_string(p.bin_size));
  if (p.lens_grid != table.grid())
    fail("lens_grid: the sample table was bucketed for G=" + std::to_string(table.grid()) +
         ", got " + std::to_string(p.lens_grid));
  if (p.threads < 0 || p.threads > 1024)
    fail("threads: expected 0 (all) .. 1024, got " + std::to_string(p.threads));
  if (!(p.focus_w > 0)) fail("focus_w: expected > 0, got " + std::to_string(p.focus_w));
  if (!(p.near_w > 0)) fail("near_w: expected > 0, got " + std::to_string(p.near_w));
  if (p.time_splits < 1 || p.time_splits > 16 || p.time_strata < 1 || p.time_strata > 64 ||
      p.time_strata % p.time_splits != 0)  // issue 5: each time stratum lies in one sub-interval
    fail("time_splits/time_strata: expected 1..16 / 1..64 with time_strata a multiple of time_splits, got " +
         std::to_string(p.time_splits) + " / " + std::to_string(p.time_strata));
}

RenderResult render(const RenderParams& p, const SceneArrays& scene, const SampleTable& table,
                    const std::function<bool()>& interrupted, bool export_samples) {
  validate_params(p, table);
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
  std::vector<TriSetup> setups(static_cast<std::size_t>(scene.n));
  std::vector<char> alive(static_cast<std::size_t>(scene.n), 0);
  std::vector<Counters> setup_counters(n_threads);
  {
    auto work = [&](int t) {
      const int lo = static_cast<int>(static_cast<long long>(scene.n) * t / n_threads);
      const int hi = static_cast<int>(static_cast<long long>(scene.n) * (t + 1) / n_threads);
      for (int i = lo; i < hi; ++i) {
        const float* v0 = scene.v0 + static_cast<std::size_t>(i) * 9;
        const float* v1 = scene.v1 + static_cast<std::size_t>(i) * 9;
        const float* col = scene.colors + static_cast<std::size_t>(i) * 9;
        alive[i] = p.exact_ops ? setup_triangle<ExactArith>(v0, v1, col, i, p, fc, setups[i],
                                                            setup_counters[t])
                               : setup_triangle<FastArith>(v0, v1, col, i, p, fc, setups[i],
                                                           setup_counters[t]);
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < n_threads; ++t) pool.emplace_back(work, t);
    work(0);
    for (auto& th : pool) th.join();
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
    const TriSetup& t = setups[i];
    for (int by = t.by0 / B; by <= (t.by1 - 1) / B; ++by)
      for (int bx = t.bx0 / B; bx <= (t.bx1 - 1) / B; ++bx) bin_lists[by * bins_x + bx].push_back(i);
  }

  // ---- traversal: workers take whole bins ----
  std::vector<ThreadState> states(n_threads);
  std::atomic<int> next_bin{0};
  std::atomic<bool> cancel{false};
  std::atomic<int> running{n_threads};
  std::mutex mu;
  std::condition_variable cv;
  std::exception_ptr error;
  const Frame frame{p, fc, table};
  auto worker = [&](int t) {
    try {
      ThreadState& ts = states[t];
      auto algo = TraversalRegistry::entries().at(p.algorithm).create(frame, ts, p.exact_ops);
      for (;;) {
        const int b = next_bin.fetch_add(1);
        if (b >= n_bins || cancel.load(std::memory_order_relaxed)) break;
        const int bx = b % bins_x, by = b / bins_x;
        BinRect r{bx * B, by * B, std::min(p.width, (bx + 1) * B), std::min(p.height, (by + 1) * B)};
        ts.buffers.begin(r, table.spp());
        for (std::uint32_t i : bin_lists[b]) {
          if (cancel.load(std::memory_order_relaxed)) break;  // Ctrl-C: stop within one triangle
          const TriSetup& tri = setups[i];
          const bool home = (tri.by0 / B) * bins_x + (tri.bx0 / B) == b;
          algo->rasterize(tri, r, home);
        }
        ts.buffers.resolve(result.image.data(), p.width);
        if (export_samples)
          ts.buffers.export_samples(result.sample_depth.data(), result.sample_triangle.data(), p.width);
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
      lock.lock();
      if (stop) {
        cancel = true;
        result.interrupted = true;
      }
    }
  }
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);

  for (const auto& c : setup_counters) result.counters.merge(c);
  for (const auto& s : states) result.counters.merge(s.counters);
  result.counters[Counter::frame_pixels] = static_cast<std::uint64_t>(p.width) * p.height;
  result.counters[Counter::frame_samples] =
      static_cast<std::uint64_t>(p.width) * p.height * table.spp();
  result.counters[Counter::frame_bins] = static_cast<std::uint64_t>(n_bins);
  return result;
}

}  // namespace rast5d
