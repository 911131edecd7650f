// Per-pixel statistics (opt-in, sim.render(..., pixel_stats=...)): chosen counters charged to the
// pixels the work was done for, one (height x width) map per counter.
//
// Mechanism: each worker thread holds a PixelCursor with a snapshot of its counters and a target
// rectangle (a triangle's pixel bounds in a bin, a screen tile, or one pixel). When the target
// changes, the counter deltas since the snapshot are spread over the old target's pixels: every
// pixel gets delta / area and the first delta % area pixels in raster order one more, so each map
// sums exactly to its frame counter. A worker's PixelStatsObserver (core/visit_observer.h) aims its
// cursor at each triangle's pixels in the bin and at the targets the traversal announces through
// SamplePipeline::at_pixel / at_rect (which flush the pending batch first); without it those are one
// flag test.
// Per-triangle counters (ops.setup, setup.*, trav.*) are charged to the triangle's pixel bounds in
// its bin whenever they are counted. Work with no pixel bounds (triangles culled at the near plane
// or off screen) is spread over the whole frame. Targets never leave the current bin, and bins
// belong to one thread at a time, so the maps need no locks and do not depend on the thread count.
//
// Trace mode (sim.trace_pixel): the cursor also records, for one pixel, every target containing it
// with its non-zero counter deltas (tile verdicts, samples, operations) and each sample tested.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "core/counters.h"
#include "core/visit_observer.h"

namespace rast5d {

// The shared maps: channel-major, channels x height x width.
struct PixelStats {
  int width = 0, height = 0;
  std::vector<int> channels;      // counter indices
  std::vector<char> per_tri;      // channel is a per-triangle counter
  std::vector<std::uint64_t> maps;
  // Trace mode: the pixel (trace_x, trace_y) >= 0.
  int trace_x = -1, trace_y = -1;

  void init(int w, int h, const std::vector<int>& counter_ids) {
    width = w, height = h;
    channels = counter_ids;
    per_tri.assign(channels.size(), 0);
    for (std::size_t k = 0; k < channels.size(); ++k) {
      const std::string_view n = kCounterInfo[static_cast<std::size_t>(channels[k])].name;
      per_tri[k] = n == "ops.setup" || n.substr(0, 6) == "setup." || n.substr(0, 5) == "trav.";
    }
    maps.assign(channels.size() * static_cast<std::size_t>(w) * h, 0);
  }
  bool tracing() const { return trace_x >= 0; }

  // Spread d over [x0, x1) x [y0, y1) (non-empty, inside the image).
  void spread(std::size_t k, std::uint64_t d, int x0, int y0, int x1, int y1) {
    std::uint64_t* m = maps.data() + k * static_cast<std::size_t>(width) * height;
    const std::uint64_t area = static_cast<std::uint64_t>(x1 - x0) * static_cast<std::uint64_t>(y1 - y0);
    const std::uint64_t q = d / area;
    std::uint64_t r = d % area;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        std::uint64_t add = q;
        if (r) --r, ++add;
        m[static_cast<std::size_t>(y) * width + x] += add;
      }
  }
};

// One traced event: a target containing the traced pixel and what was counted there.
struct TraceEvent {
  std::int64_t triangle;  // -1: not inside a triangle's rasterization
  int kind;               // 0 = triangle bounds, 1 = tile, 2 = pixel, 3 = setup
  int x0, y0, x1, y1;
  std::vector<std::pair<int, std::uint64_t>> deltas;  // (counter index, delta), non-zero only
};
struct TraceSample {
  std::int64_t triangle;
  int sample;
  bool covered, hit;
};

// Per worker thread.
struct PixelCursor {
  PixelStats* stats = nullptr;
  std::vector<std::uint64_t> snap, frame_pool;  // per channel
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0, kind = 0;
  std::int64_t triangle = -1;
  // Trace mode: every counter is a channel; events for the traced pixel.
  std::vector<TraceEvent> events;
  std::vector<TraceSample> samples;
  std::vector<std::uint64_t> trace_snap;

  void attach(PixelStats* s) {
    stats = s;
    snap.assign(s->channels.size(), 0);
    frame_pool.assign(s->channels.size(), 0);
    trace_snap.assign(s->tracing() ? kNumCounters : 0, 0);
  }
  bool traced_here() const {
    return stats->trace_x >= x0 && stats->trace_x < x1 && stats->trace_y >= y0 && stats->trace_y < y1;
  }
  bool traces_pixel(int px, int py) const { return px == stats->trace_x && py == stats->trace_y; }

  // Charge the deltas since the snapshot to the current target (per-triangle channels only when
  // `per_tri`), then aim at the new one.
  void commit(const Counters& c, bool per_tri = false) {
    for (std::size_t k = 0; k < snap.size(); ++k) {
      if (stats->per_tri[k] != static_cast<char>(per_tri)) continue;
      const std::uint64_t now = c.v[static_cast<std::size_t>(stats->channels[k])];
      const std::uint64_t d = now - snap[k];
      if (!d) continue;
      snap[k] = now;
      if (x0 < x1 && y0 < y1) stats->spread(k, d, x0, y0, x1, y1);
      else frame_pool[k] += d;
    }
    if (!trace_snap.empty()) {
      TraceEvent ev{triangle, kind, x0, y0, x1, y1, {}};
      for (int i = 0; i < kNumCounters; ++i) {
        const bool tri_counter = is_per_tri(i);
        if (tri_counter != per_tri) continue;
        const std::uint64_t d = c.v[static_cast<std::size_t>(i)] - trace_snap[static_cast<std::size_t>(i)];
        if (!d) continue;
        trace_snap[static_cast<std::size_t>(i)] = c.v[static_cast<std::size_t>(i)];
        ev.deltas.emplace_back(i, d);
      }
      if (!ev.deltas.empty() && traced_here()) events.push_back(std::move(ev));
    }
  }
  void target(const Counters& c, int nx0, int ny0, int nx1, int ny1, int nkind) {
    commit(c);
    x0 = nx0, y0 = ny0, x1 = nx1, y1 = ny1, kind = nkind;
  }
  static bool is_per_tri(int i) {
    const std::string_view n = kCounterInfo[static_cast<std::size_t>(i)].name;
    return n == "ops.setup" || n.substr(0, 6) == "setup." || n.substr(0, 5) == "trav.";
  }
};

// A worker's per-pixel statistics as an observer of its traversal.
class PixelStatsObserver final : public VisitObserver {
 public:
  PixelStatsObserver(PixelStats* s, const Counters& c) : c_(c) { cur.attach(s); }
  bool wants_targets() const override { return true; }

  void begin_triangle(std::uint32_t tri, int x0, int y0, int x1, int y1, bool) override {
    rx0_ = x0, ry0_ = y0, rx1_ = x1, ry1_ = y1;  // the triangle's pixels in this bin, until aimed finer
    cur.target(c_, x0, y0, x1, y1, 0);
    cur.triangle = tri;
  }
  void target(int x0, int y0, int x1, int y1, int kind) override { cur.target(c_, x0, y0, x1, y1, kind); }
  bool aims_at(int x0, int y0, int x1, int y1) const override {
    return cur.x0 == x0 && cur.y0 == y0 && cur.x1 == x1 && cur.y1 == y1;
  }
  void end_triangle() override {
    cur.target(c_, rx0_, ry0_, rx1_, ry1_, 0);
    cur.commit(c_, true);  // the per-triangle counters, to the triangle's pixels in the bin
  }
  void end_bin() override {
    cur.commit(c_);
    cur.triangle = -1;
  }
  bool traces(int px, int py) const override { return cur.stats->tracing() && cur.traces_pixel(px, py); }
  void traced_sample(std::int64_t tri, int s, bool covered, bool hit) override {
    cur.samples.push_back({tri, s, covered, hit});
  }

  PixelCursor cur;

 private:
  const Counters& c_;
  int rx0_ = 0, ry0_ = 0, rx1_ = 0, ry1_ = 0;
};

}  // namespace rast5d
