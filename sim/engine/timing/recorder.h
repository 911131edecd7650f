// The timing recorder (docs/timing.md): a worker's observer that cuts its traversal into work
// records, one per visit (hardware.timing.granularity 'visit') or one per (triangle, bin) ('bin'),
// as differences of the thread's counters and memory-model totals (work_from_counters). Each bin's
// records go to that bin's output, with the length of its texture-line stream after each record
// (the texture-cache replay hands each record the misses of its own stretch: frame/bin_stream.h).
//
// Record stream of a bin: per triangle in submission order its visits' records (the triangle's
// setup with the first; whatever it did after its last visit as one more), then one record of the
// end-of-bin work (the line samples' composite, the memory model's resolve and flush) if any.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "core/counters.h"
#include "core/visit_observer.h"
#include "memory/sample_buffers.h"
#include "timing/timing.h"

namespace rast5d {

// What one bin hands to the in-order stream.
struct BinRecords {
  std::vector<TileWork> records;
  std::vector<std::uint32_t> stream_ends;  // per record: the bin's texture-line stream length after it
};

class TimingRecorder final : public VisitObserver {
 public:
  // mem: the thread's memory model (nullptr when neither buffer is modelled); stream: where the
  // texture lines of the bin being rasterized go (nullptr: not textured).
  TimingRecorder(const Counters& c, const memory::SampleBufferModel* mem, bool per_visit)
      : c_(c), mem_(mem), per_visit_(per_visit) {}
  bool wants_visits() const override { return per_visit_; }

  // The output of the next bin (set before begin_bin), its texture stream, and where a chunk of
  // kChunk records goes while the bin is rasterized (it may take them: it empties the output).
  void set_output(BinRecords* out, const std::vector<std::uint32_t>* stream,
                  std::function<void(BinRecords&)> hand_over = {}, std::size_t chunk = 0) {
    out_ = out;
    stream_ = stream;
    hand_over_ = std::move(hand_over);
    chunk_ = chunk;
  }

  void begin_bin(int bin, const BinRect&) override { bin_ = bin; }
  void begin_triangle(std::uint32_t, int, int, int, int, bool home) override {
    home_ = home;
    mark_ = now();
    first_ = out_->records.size();
  }
  void end_visit() override {
    if (!per_visit_) return;  // 'bin' granularity: one record per (triangle, bin)
    const TileWork w = now();
    emit(w.since(mark_));
    mark_ = w;
  }
  void end_triangle() override {
    // The visits' records, then what the triangle did after its last visit (if anything); the
    // triangle's setup goes with its first record.
    const TileWork rest = now().since(mark_);
    if (!rest.empty() || out_->records.size() == first_) emit(rest);
    if (home_) out_->records[first_].triangles += 1;  // its own set-up (+ accumulation's re-sends, counted)
    if (hand_over_ && out_->records.size() >= chunk_) hand_over_(*out_);  // between triangles only
  }
  void begin_tail() override { mark_ = now(); }
  void end_bin() override {
    const TileWork w = now().since(mark_);
    if (!w.empty()) emit(w);
  }

 private:
  TileWork now() const {
    MemoryTotalsView v;
    if (mem_) {
      const memory::MemoryTotals& t = mem_->totals();
      v.depth = mem_->depth_on(), v.color = mem_->color_on();
      v.depth_dram = t.depth_dram(), v.depth_fills = t.depth_fills, v.color_dram = t.color_dram();
    }
    return work_from_counters(c_, v);
  }
  std::uint32_t stream_len() const { return stream_ ? static_cast<std::uint32_t>(stream_->size()) : 0; }
  void emit(const TileWork& w) {
    out_->records.push_back(w);
    out_->records.back().bin = bin_;
    out_->stream_ends.push_back(stream_len());
  }

  const Counters& c_;
  const memory::SampleBufferModel* mem_;
  const bool per_visit_;
  BinRecords* out_ = nullptr;
  const std::vector<std::uint32_t>* stream_ = nullptr;
  std::function<void(BinRecords&)> hand_over_;
  std::size_t chunk_ = 0;
  int bin_ = 0;
  bool home_ = false;
  std::size_t first_ = 0;  // the triangle's first record in the bin's output
  TileWork mark_;
};

}  // namespace rast5d
