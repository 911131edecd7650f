#include "frame/traverse.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

#include "sampletest/precision.h"
#include "tiletest/common.h"
#include "traversal/traversal.h"

namespace rast5d {

namespace {

// The cache lines of a triangle's set-up (TriSetup is several lines; a bin's list visits set-ups far
// apart in memory), fetched a few triangles ahead (small triangles take less than a miss's latency).
inline void prefetch_setup(const TriSetup& t) {
  const char* p = reinterpret_cast<const char*>(&t);
  for (std::size_t o = 0; o < sizeof(TriSetup); o += 64) __builtin_prefetch(p + o);
}

}  // namespace

std::vector<std::unique_ptr<Worker>> make_workers(const TraversalJob& job, int n_threads) {
  const RenderParams& p = job.p;
  std::vector<std::unique_ptr<Worker>> workers;
  for (int t = 0; t < n_threads; ++t) {
    auto w = std::make_unique<Worker>();
    ThreadState& ts = w->ts;
    ts.shade.attach(&job.shade, &ts.counters);
    // Observers in dispatch order: the memory model, then the recorder that reads its totals.
    if (p.record_timing && (p.depth_buffer_enabled || p.color_buffer_enabled)) {
      w->memory = std::make_unique<memory::SampleBufferModel>(p, job.frame.table, ts.buffers.depth_samples(), job.moving);
      ts.buffers.set_line_marks(w->memory->marks());
      ts.observers.add(w->memory.get());
    }
    if (p.record_timing) {
      w->recorder = std::make_unique<TimingRecorder>(ts.counters, w->memory.get(), p.timing_per_visit);
      ts.observers.add(w->recorder.get());
    }
    if (job.options.pixel_stats) {
      w->pixels = std::make_unique<PixelStatsObserver>(job.options.pixel_stats, ts.counters);
      ts.observers.add(w->pixels.get());
    }
    workers.push_back(std::move(w));
  }
  return workers;
}

void traverse_bins(const TraversalJob& job, std::vector<std::unique_ptr<Worker>>& workers, BinStream& stream,
                   RenderResult& result) {
  const RenderParams& p = job.p;
  const Binning& bn = job.binning;
  const SampleTable& table = job.frame.table;
  const std::vector<int>* bins = job.work;
  const int n_work = bins ? static_cast<int>(bins->size()) : bn.count();
  const int n_threads = static_cast<int>(workers.size());
  PixelStats* const pstats = job.options.pixel_stats;
  const int trace_bin =
      pstats && pstats->tracing() ? (pstats->trace_y / bn.size) * bn.bins_x + pstats->trace_x / bn.size : -1;
  std::atomic<int> bins_done{0};
  std::atomic<int> next_bin{0};
  std::atomic<bool> cancel{false};
  std::atomic<int> running{n_threads};
  std::mutex mu;
  std::condition_variable cv;
  std::exception_ptr error;

  auto worker = [&](int t) {
    try {
      tiletest::t_snap_margin_px = snap_margin_px(p.precision_sample, p.precision_tile);  // this thread's tiles
      Worker& w = *workers[t];
      ThreadState& ts = w.ts;
      Observers& obs = ts.observers;
      auto algo = TraversalRegistry::entries().at(p.algorithm).create(job.frame, ts, p.op_count == OpCount::kExact);
      for (;;) {
        const int k = next_bin.fetch_add(1);
        if (k >= n_work || cancel.load(std::memory_order_relaxed)) break;
        const int b = bins ? (*bins)[k] : k;
        if (trace_bin >= 0 && b != trace_bin) {
          stream.complete(k, BinRecords{});
          continue;
        }
        if (!stream.wait_turn(k, cancel)) break;
        const Counters at_start = bins ? ts.counters : Counters{};
        const BinRect r = bn.rect(b, p.width, p.height);
        BinRecords out;
        if (w.recorder)
          w.recorder->set_output(&out, job.shade.streams.empty() ? nullptr : &job.shade.streams[static_cast<std::size_t>(b)],
                                 [&stream, k](BinRecords& o) { stream.feed_head(k, o); }, BinStream::kChunk);
        ts.buffers.begin(r, table.spp());
        ts.shade.begin_bin(b);
        obs.begin_bin(b, r);
        // A unit of a dense bin (pipeline.sample_split) traverses only its triangles; the bin's image
        // and exported samples are those of its first drawn unit (a sampled frame's image is partial).
        const bool unit = job.split && !job.split->lists[static_cast<std::size_t>(k)].empty();
        const bool resolve = !job.split || k == 0 || std::find(bins->begin(), bins->begin() + k, b) == bins->begin() + k;
        const std::vector<std::uint32_t>& list =
            unit ? job.split->lists[static_cast<std::size_t>(k)] : bn.lists[static_cast<std::size_t>(b)];
        for (std::size_t li = 0; li < list.size(); ++li) {
          if (cancel.load(std::memory_order_relaxed)) break;  // Ctrl-C: stop within one triangle
          if (li + 4 < list.size()) prefetch_setup(job.setups[list[li + 4]]);  // a later triangle's set-up
          const std::uint32_t i = list[li];
          const TriSetup& tri = job.setups[i];
          const bool home = bn.home(tri) == b;
          obs.begin_triangle(i, std::max(tri.bx0, r.x0), std::max(tri.by0, r.y0), std::min(tri.bx1, r.x1),
                             std::min(tri.by1, r.y1), home);
          algo->rasterize(tri, r, home);
          obs.end_triangle();
        }
        obs.begin_tail();
        algo->end_bin(r);  // end-of-bin work (the line samples' composite)
        ts.shade.close_visit();  // algorithms end their visits; this only guards the contract
        obs.end_bin();
        bins_done.fetch_add(1, std::memory_order_relaxed);
        if (resolve) ts.buffers.resolve(result.image.data(), p.width);
        if (resolve && job.options.export_samples)
          ts.buffers.export_samples(result.sample_depth.data(), result.sample_triangle.data(), p.width);
        if (bins) {  // this bin's counters: each row is written by the one worker that owns the bin
          std::uint64_t* row = &result.sampled.bin_counters[static_cast<std::size_t>(k) * kNumCounters];
          for (int c = 0; c < kNumCounters; ++c) row[c] = ts.counters.v[c] - at_start.v[c];
        }
        stream.complete(k, std::move(out));
      }
    } catch (...) {
      {
        std::lock_guard<std::mutex> lock(mu);
        if (!error) error = std::current_exception();
        cancel = true;
      }
      stream.cancel();
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
      const bool stop = job.interrupted && job.interrupted();
      if (job.options.progress && !stop) job.options.progress(bins_done.load(), n_work);
      lock.lock();
      if (stop) {
        cancel = true;
        result.interrupted = true;
        stream.cancel();
      }
    }
  }
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace rast5d
