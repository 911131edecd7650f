// The bin stream (frame/render.h): completed bins, consumed in bin order while the workers go on.
// Its consumers are the texture-cache replay (each bin's line stream, then freed) and the timing
// model (each bin's work records, with their texture misses: the records are complete once the
// replay has run, and nothing is patched afterwards).
//
// A worker hands each bin it finishes to complete(); whichever call completes the next bin in order
// consumes it and every later bin already waiting, under the stream's lock. The worker holding the
// next bin also hands its records over while it rasterizes, in chunks (feed_head()), so a slow bin's
// records do not pile up. A worker waits before starting a bin while the finished bins waiting hold
// more than `budget` records, and in the middle of a bin that is not next once it holds `budget`
// records itself, so the records in flight stay bounded by (threads + 1) x budget (the worker holding
// the next bin never waits, so this cannot deadlock). A render of a bin list keeps every bin and consumes them in
// bin index order at the end (finish()).
//
// Contract: bins are consumed in increasing bin index, whatever the thread count and timing.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <numeric>
#include <optional>
#include <vector>

#include "backend/shading.h"
#include "timing/recorder.h"
#include "timing/timing.h"

namespace rast5d {

class BinStream {
 public:
  // bins: the work items' bin indices (nullptr: item k is bin k, consumed as it comes); replay and
  // model: the consumers (either may be null); streams: the bins' texture-line streams.
  BinStream(int n_work, const std::vector<int>* bins, std::size_t budget, TextureCacheReplay* replay,
            std::vector<std::vector<std::uint32_t>>* streams, TimingModel* model,
            std::vector<TileWork>* kept, int tex_line_bytes)
      : bins_(bins), budget_(budget), replay_(replay), streams_(streams), model_(model), kept_(kept),
        line_bytes_(static_cast<std::uint64_t>(tex_line_bytes)), pending_(static_cast<std::size_t>(n_work)) {}

  // Records a worker gathers before it hands them over (feed_head()).
  static constexpr std::size_t kChunk = 4096;
  // The stream's budget: the records the finished bins waiting for their turn may hold, and each
  // worker's bin that is not next (sim/render.py's memory estimate counts (threads + 1) of them,
  // sim._core.STREAM_BUDGET). On a 2-thread 1080p frame of the dense interior, 2^15 records held some
  // 30 MiB in flight and 2^13 made the workers wait (30 % more wall time); 2^14 holds about 10 MiB at
  // the wall time of 2^15 within 5 %.
  static constexpr std::size_t kBudget = std::size_t(1) << 14;

  bool active() const { return replay_ || model_; }

  // Before a worker starts item k: wait while it is too far ahead. False when cancelled meanwhile.
  bool wait_turn(int k, const std::atomic<bool>& cancel) {
    if (!active() || bins_) return !cancel.load();
    std::unique_lock<std::mutex> lock(mu_);
    while (k > next_ && buffered_ >= budget_) {
      if (cancel.load() || cancelled_) return false;
      cv_.wait_for(lock, std::chrono::milliseconds(5));
    }
    return !cancel.load();
  }

  // While item k is rasterized: if it is the next to consume, consume its records so far (the texture
  // lines up to the last record's end with them) and empty them. A bin that is not next and already
  // holds `budget` records waits here (between two triangles) until it is next.
  void feed_head(int k, BinRecords& out) {
    if (!active() || bins_ || out.records.empty()) return;
    std::unique_lock<std::mutex> lock(mu_);
    while (k != next_ && out.records.size() >= budget_ && !cancelled_) cv_.wait_for(lock, std::chrono::milliseconds(5));
    if (k != next_) return;
    consume(k, out);
    out.records.clear(), out.stream_ends.clear();
  }

  // Wake and release every waiting worker (the render stops).
  void cancel() {
    std::lock_guard<std::mutex> lock(mu_);
    cancelled_ = true;
    cv_.notify_all();
  }

  // Item k is rasterized; its records (moved) are consumed now or by a later call.
  void complete(int k, BinRecords&& out) {
    if (!active()) return;
    std::lock_guard<std::mutex> lock(mu_);
    if (bins_) {  // a bin list: consumed in bin order by finish()
      pending_[static_cast<std::size_t>(k)].emplace(std::move(out));
      return;
    }
    if (k != next_) buffered_ += out.records.size();
    pending_[static_cast<std::size_t>(k)].emplace(std::move(out));
    while (next_ < static_cast<int>(pending_.size()) && pending_[next_]) {
      if (next_ != k) buffered_ -= pending_[next_]->records.size();
      consume(next_, *pending_[next_], true);
      pending_[next_].reset();
      ++next_;
      head_offset_ = 0;
    }
    cv_.notify_all();
  }

  // A bin list: consume every completed item in increasing bin index.
  void finish() {
    if (!active() || !bins_) return;
    std::vector<int> order(pending_.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return (*bins_)[a] < (*bins_)[b]; });
    for (int k : order)
      if (pending_[k]) consume(k, *pending_[k], true), pending_[k].reset();
  }

 private:
  // Item k's records, with the texture lines from head_offset_ up to the last record's end (up to the
  // stream's end when `last`: the bin is done, and its stream is freed).
  void consume(int k, BinRecords& out, bool last = false) {
    const int b = bins_ ? (*bins_)[k] : k;
    if (replay_) {
      std::vector<std::uint32_t>& stream = (*streams_)[static_cast<std::size_t>(b)];
      const bool per_record = model_ != nullptr;
      const std::size_t end = last ? stream.size() : (out.stream_ends.empty() ? head_offset_ : out.stream_ends.back());
      replay_->consume(b, stream, head_offset_, end, per_record ? &out.stream_ends : nullptr, &misses_);
      head_offset_ = end;
      if (per_record)  // each record's texture misses and the line bytes they fetch
        for (std::size_t i = 0; i < out.records.size(); ++i) {
          TileWork& w = out.records[i];
          w.tex_misses += misses_[i];
          w.dram_texture += static_cast<std::uint64_t>(misses_[i]) * line_bytes_;
          w.dram_bytes += static_cast<std::uint64_t>(misses_[i]) * line_bytes_;
        }
      if (last) std::vector<std::uint32_t>().swap(stream);  // the bin's stream is done with
    }
    if (model_)
      for (const TileWork& w : out.records) model_->feed(w);
    if (kept_) kept_->insert(kept_->end(), out.records.begin(), out.records.end());
  }

  const std::vector<int>* bins_;
  const std::size_t budget_;
  TextureCacheReplay* replay_;
  std::vector<std::vector<std::uint32_t>>* streams_;
  TimingModel* model_;
  std::vector<TileWork>* kept_;
  const std::uint64_t line_bytes_;
  std::mutex mu_;
  std::condition_variable cv_;
  int next_ = 0;
  std::size_t head_offset_ = 0;  // the next bin's texture lines already replayed
  std::size_t buffered_ = 0;     // records of finished bins waiting for their turn
  bool cancelled_ = false;
  std::vector<std::optional<BinRecords>> pending_;
  std::vector<std::uint32_t> misses_;
};

}  // namespace rast5d
