// The per-sample depth and colour buffers as the hardware keeps them (docs/memory.md): in DRAM, in
// lines of one screen tile's samples, reached through a depth-tile cache and a colour-tile cache,
// with depth compression (memory/compression.h) and a cleared (fast-clear) tile state.
//
// A worker thread's SampleBufferModel observes its traversal (core/visit_observer.h). The backend
// marks the lines a visit touches (LineMarks::mark: a depth test reads or writes a depth line, a
// passed test writes the colour line); at the visit's end the touched lines go through the caches in
// ascending line order: a miss fills the line from DRAM (nothing for a cleared line, else its stored
// size: compressed for depth), an evicted dirty line is written back (depth compressed from its
// current samples, colour raw). At the end of a bin the colour buffer is resolved (lines not in the
// cache are read, the bin's pixels are written) and the depth cache is flushed.
//
// Contract: what the model adds depends only on the bin's own visits in their order (never on the
// thread count); its totals grow monotonically, so a record's memory work is a difference of totals.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/bin_rect.h"
#include "core/params.h"
#include "core/sample_table.h"
#include "core/visit_observer.h"
#include "memory/compression.h"
#include "memory/tile_cache.h"

namespace rast5d::memory {

// Where the samples of a bin lie in buffer lines: screen tiles of T x T pixels (T the largest power
// of two up to 8 whose samples fit one line), each in per_tile lines (more than one only when one
// pixel's samples exceed a line).
struct LineGeometry {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int spp = 1, per_line = 256;  // samples per line
  int tile = 1, shift = 0, per_tile = 1, tiles_x = 1, tiles_y = 1;

  void set(const BinRect& r, int samples_per_pixel, int samples_per_line) {
    x0 = r.x0, y0 = r.y0, x1 = r.x1, y1 = r.y1;
    spp = samples_per_pixel, per_line = samples_per_line;
    tile = 8, shift = 3;
    while (tile > 1 && tile * tile * spp > per_line) tile >>= 1, --shift;
    per_tile = (tile * tile * spp + per_line - 1) / per_line;
    tiles_x = (x1 - x0 + tile - 1) / tile;
    tiles_y = (y1 - y0 + tile - 1) / tile;
  }
  std::size_t lines() const { return static_cast<std::size_t>(tiles_x) * tiles_y * per_tile; }
  std::uint32_t line_of(int px, int py, int s) const {
    const int t = ((py - y0) >> shift) * tiles_x + ((px - x0) >> shift);
    return static_cast<std::uint32_t>(per_tile == 1 ? t : t * per_tile + s / per_line);
  }
  // The pixels [px0, px1) x [py0, py1) and samples [s0, s1) of a line.
  void extent(std::uint32_t line, int& px0, int& py0, int& px1, int& py1, int& s0, int& s1) const {
    const int t = static_cast<int>(line) / per_tile, k = static_cast<int>(line) % per_tile;
    px0 = x0 + (t % tiles_x) * tile, py0 = y0 + (t / tiles_x) * tile;
    px1 = std::min(x1, px0 + tile), py1 = std::min(y1, py0 + tile);
    s0 = per_tile == 1 ? 0 : k * per_line;
    s1 = per_tile == 1 ? spp : std::min(spp, s0 + per_line);
  }
};

// What the backend marks per depth-tested sample (backend/sample_backend.h).
enum LineFlag : std::uint8_t { kTouched = 1, kDepthWrite = 2, kColorWrite = 4 };

struct LineMarks {
  LineGeometry geo;
  std::vector<std::uint8_t> flags;      // per line of the bin
  std::vector<std::uint32_t> touched;   // lines marked since the last visit end
  int last_px = -1, last_py = -1;       // the pixel of the last mark (one line per pixel: per_tile 1)
  std::uint32_t last_line = 0;
  // The line of sample s of pixel (px, py), marked touched. The pixel's line is remembered while the
  // visit goes on (last_px is reset at each visit end; a pixel spans lines only when per_tile > 1).
  inline std::uint32_t mark(int px, int py, int s) {
    if (px == last_px && py == last_py) return last_line;
    const std::uint32_t l = geo.line_of(px, py, s);
    if (!flags[l]) touched.push_back(l);
    flags[l] |= kTouched;
    if (geo.per_tile == 1) last_px = px, last_py = py, last_line = l;
    return l;
  }
  inline void add(std::uint32_t l, std::uint8_t f) { flags[l] |= f; }
};

// Monotonic totals of one worker's memory model.
struct MemoryTotals {
  std::uint64_t depth_accesses = 0, depth_hits = 0, depth_misses = 0, depth_fills = 0, depth_fill_bytes = 0;
  std::uint64_t depth_writebacks = 0, depth_writeback_bytes = 0, depth_writeback_raw_bytes = 0;
  std::uint64_t color_accesses = 0, color_hits = 0, color_misses = 0, color_fill_bytes = 0;
  std::uint64_t color_writebacks = 0, color_writeback_bytes = 0, color_resolve_read_bytes = 0;
  std::uint64_t color_resolve_write_bytes = 0;

  std::uint64_t depth_dram() const { return depth_fill_bytes + depth_writeback_bytes; }
  std::uint64_t color_dram() const {
    return color_fill_bytes + color_writeback_bytes + color_resolve_read_bytes + color_resolve_write_bytes;
  }
  void merge(const MemoryTotals& o) {
    const std::uint64_t* src = &o.depth_accesses;
    std::uint64_t* dst = &depth_accesses;
    for (std::size_t i = 0; i < sizeof(MemoryTotals) / sizeof(std::uint64_t); ++i) dst[i] += src[i];
  }
};

// The figures the model exports (name, unit, description), declared once (docs/counters.md).
struct MemoryFigure {
  const char* name;
  const char* unit;
  const char* description;
};
inline constexpr MemoryFigure kMemoryFigures[] = {
    {"depth.cache.accesses", "lines", "Depth-tile cache accesses: lines a visit depth-tests (once per line and visit)"},
    {"depth.cache.hits", "lines", "Depth-tile cache hits"},
    {"depth.cache.misses", "lines", "Depth-tile cache misses (each allocates the line; cleared lines are filled at no cost)"},
    {"depth.cache.fills", "lines", "Depth-tile cache misses that read the line from DRAM (lines written back before)"},
    {"depth.cache.writebacks", "lines", "Dirty depth lines written to DRAM (evicted, or flushed at the end of their bin)"},
    {"depth.bytes_raw", "bytes", "Uncompressed size of the depth lines written back (4 bytes per sample)"},
    {"depth.bytes_stored", "bytes", "DRAM bytes of the depth lines written back (compressed, burst-rounded)"},
    {"depth.compression_ratio", "ratio",
     "depth.bytes_stored / depth.bytes_raw: compressed over raw depth bytes written (1 with compression off)"},
    {"color.cache.accesses", "lines", "Colour-tile cache accesses: lines a visit writes colour samples to"},
    {"color.cache.hits", "lines", "Colour-tile cache hits"},
    {"color.cache.misses", "lines", "Colour-tile cache misses (a line that is not cleared is filled from DRAM)"},
    {"color.bytes_written", "bytes", "Colour samples written into the colour-tile cache: depth.passes x bytes per sample"},
    {"color.bytes_resolve", "bytes", "DRAM bytes of the per-bin resolve: sample lines read back and pixels written"},
};

class SampleBufferModel final : public VisitObserver {
 public:
  // moving: some triangle of the frame moves (the compressor then fits time-dependent predictors).
  SampleBufferModel(const RenderParams& p, const SampleTable& table, const std::vector<float>& depth, bool moving)
      : p_(p), table_(table), depth_(depth), depth_on_(p.depth_buffer_enabled), color_on_(p.color_buffer_enabled),
        moving_(moving) {
    per_line_ = p.depth_buffer_line_bytes / 4;
    depth_capacity_ = static_cast<std::uint64_t>(p.depth_buffer_cache_bytes / p.depth_buffer_line_bytes);
    color_line_bytes_ = static_cast<std::uint64_t>(per_line_) * p.color_buffer_bytes_per_sample;
    color_capacity_ = static_cast<std::uint64_t>(p.color_buffer_cache_bytes) / color_line_bytes_;
    if (depth_on_ && p.depth_buffer_compression != DepthCompression::kNone) {
      // The table's sample positions and times in the compressor's fixed point, once.
      const int P = table.period(), spp = table.spp();
      fixed_pos_.resize(static_cast<std::size_t>(P) * P * spp * 3);
      for (int py = 0; py < P; ++py)
        for (int px = 0; px < P; ++px) {
          const PixelSamples ps = table.pixel(px, py);
          std::int16_t* out = &fixed_pos_[(static_cast<std::size_t>(py) * P + px) * spp * 3];
          for (int s = 0; s < spp; ++s) {
            out[3 * s] = static_cast<std::int16_t>(std::floor(static_cast<double>(ps.x[s]) * 256.0 + 0.5));
            out[3 * s + 1] = static_cast<std::int16_t>(std::floor(static_cast<double>(ps.y[s]) * 256.0 + 0.5));
            out[3 * s + 2] = static_cast<std::int16_t>(std::floor(static_cast<double>(ps.t[s]) * 4096.0 + 0.5));
          }
        }
    }
  }
  bool depth_on() const { return depth_on_; }
  bool color_on() const { return color_on_; }
  LineMarks* marks() { return &marks_; }
  const MemoryTotals& totals() const { return tot_; }
  bool wants_visits() const override { return true; }

  void begin_bin(int /*bin*/, const BinRect& r) override {
    marks_.geo.set(r, table_.spp(), per_line_);
    const std::size_t n = marks_.geo.lines();
    marks_.flags.assign(n, 0);
    marks_.touched.clear();
    marks_.last_px = -1;
    if (depth_on_) {
      depth_cache_.reset(depth_capacity_, static_cast<std::uint64_t>(p_.depth_buffer_cache_ways), n);
      // A line not written this frame is cleared: free with fast clear, else read whole.
      depth_stored_.assign(n, kUnset);
    }
    if (color_on_) {
      color_cache_.reset(color_capacity_, static_cast<std::uint64_t>(p_.color_buffer_cache_ways), n);
      color_stored_.assign(n, 0);
    }
  }

  void end_visit() override { settle(); }
  void end_triangle() override { settle(); }

  void end_bin() override {
    settle();
    const LineGeometry& g = marks_.geo;
    const std::size_t n = g.lines();
    if (color_on_) {  // resolve: every line of the bin is read (cache or DRAM), every pixel written
      for (std::size_t l = 0; l < n; ++l)
        if (!color_cache_.contains(static_cast<std::uint32_t>(l)))
          tot_.color_resolve_read_bytes += color_fill(static_cast<std::uint32_t>(l));
      tot_.color_resolve_write_bytes += static_cast<std::uint64_t>(g.x1 - g.x0) * (g.y1 - g.y0) *
                                        static_cast<std::uint64_t>(p_.color_buffer_bytes_per_sample);
    }
    if (depth_on_) depth_cache_.for_each_dirty([&](std::uint32_t l) { write_back_depth(l); });
  }

 private:
  static constexpr std::uint64_t kUnset = ~std::uint64_t(0);

  // The lines the visit touched, through the caches in ascending order.
  void settle() {
    auto& touched = marks_.touched;
    marks_.last_px = -1;
    if (touched.empty()) return;
    std::sort(touched.begin(), touched.end());
    for (const std::uint32_t l : touched) {
      const std::uint8_t f = marks_.flags[l];
      marks_.flags[l] = 0;
      if (depth_on_) {
        ++tot_.depth_accesses;
        const TileCache::Access a = depth_cache_.access(l, (f & kDepthWrite) != 0);
        if (a.hit) {
          ++tot_.depth_hits;
        } else {
          ++tot_.depth_misses;
          const std::uint64_t b = depth_fill(l);
          if (b) ++tot_.depth_fills, tot_.depth_fill_bytes += b;
        }
        if (a.evicted >= 0) write_back_depth(static_cast<std::uint32_t>(a.evicted));
      }
      if (color_on_ && (f & kColorWrite)) {
        ++tot_.color_accesses;
        const TileCache::Access a = color_cache_.access(l, true);
        if (a.hit) {
          ++tot_.color_hits;
        } else {
          ++tot_.color_misses;
          tot_.color_fill_bytes += color_fill(l);
        }
        if (a.evicted >= 0) {
          const std::uint64_t b = color_raw(static_cast<std::uint32_t>(a.evicted));
          ++tot_.color_writebacks, tot_.color_writeback_bytes += b;
          color_stored_[a.evicted] = 1;
        }
      }
    }
    touched.clear();
  }

  std::uint64_t samples_of(std::uint32_t l) const {
    int px0, py0, px1, py1, s0, s1;
    marks_.geo.extent(l, px0, py0, px1, py1, s0, s1);
    return static_cast<std::uint64_t>(px1 - px0) * (py1 - py0) * (s1 - s0);
  }
  std::uint64_t depth_fill(std::uint32_t l) const {
    if (depth_stored_[l] != kUnset) return depth_stored_[l];
    return p_.depth_buffer_fast_clear ? 0 : 4 * samples_of(l);
  }
  std::uint64_t color_raw(std::uint32_t l) const {
    return samples_of(l) * static_cast<std::uint64_t>(p_.color_buffer_bytes_per_sample);
  }
  std::uint64_t color_fill(std::uint32_t l) const {
    return (color_stored_[l] || !p_.color_buffer_fast_clear) ? color_raw(l) : 0;
  }

  void write_back_depth(std::uint32_t l) {
    int px0, py0, px1, py1, s0, s1;
    const LineGeometry& g = marks_.geo;
    g.extent(l, px0, py0, px1, py1, s0, s1);
    const int n = (px1 - px0) * (py1 - py0) * (s1 - s0);
    memory::FitSamples& fs = compressor_.samples();
    fs.resize(static_cast<std::size_t>(n));
    const int width = g.x1 - g.x0;
    int w = 0;
    for (int py = py0; py < py1; ++py)
      for (int px = px0; px < px1; ++px) {
        const std::size_t pixel = static_cast<std::size_t>(table_.period()) * (py % table_.period()) + px % table_.period();
        const std::int16_t* pos = &fixed_pos_[pixel * 3 * g.spp];
        const float* z = &depth_[(static_cast<std::size_t>(py - g.y0) * width + (px - g.x0)) * g.spp];
        const std::int32_t ox = (px - px0) * 256, oy = (py - py0) * 256;
        for (int s = s0; s < s1; ++s) {
          if (z[s] == std::numeric_limits<float>::infinity()) continue;  // cleared
          fs.xq[w] = ox + pos[3 * s], fs.yq[w] = oy + pos[3 * s + 1], fs.tq[w] = pos[3 * s + 2];
          fs.z[w] = unorm24(z[s]);
          ++w;
        }
      }
    fs.n = w;
    const std::uint64_t bytes =
        compressor_.stored_bytes(p_.depth_buffer_compression, n, static_cast<std::uint64_t>(p_.dram_burst_bytes), moving_);
    depth_stored_[l] = bytes;
    ++tot_.depth_writebacks;
    tot_.depth_writeback_bytes += bytes;
    tot_.depth_writeback_raw_bytes += 4 * static_cast<std::uint64_t>(n);
  }

  const RenderParams& p_;
  const SampleTable& table_;
  const std::vector<float>& depth_;  // the bin's depth samples (backend/bin_buffers.h), row-major pixels
  const bool depth_on_, color_on_, moving_;
  int per_line_ = 256;
  std::uint64_t depth_capacity_ = 1, color_capacity_ = 1, color_line_bytes_ = 1024;
  LineMarks marks_;
  TileCache depth_cache_, color_cache_;
  std::vector<std::uint64_t> depth_stored_;  // per line: DRAM bytes of its last write-back, kUnset if none
  std::vector<std::uint8_t> color_stored_;   // per line: written back this frame
  std::vector<std::int16_t> fixed_pos_;  // per table pixel and sample: x, y (1/256 px), t (1/4096)
  DepthCompressor compressor_;
  MemoryTotals tot_;
};

}  // namespace rast5d::memory
