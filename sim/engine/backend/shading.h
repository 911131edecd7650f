// Shading: which samples cost a shader execution, packed into 2x2 quads, and the texel fetches
// those executions make (docs/shading.md).
//
// Contract:
//  - Shading never changes the image. Every sample that passes the depth test gets its own
//    (textured) colour, a function of the triangle and the sample only, so every exact algorithm
//    still renders bit-identical images. The shading *modes* change only the work counted: how
//    many quads the shader runs, with how many live and helper lanes, and which texels they fetch.
//  - Early-z: a sample costs shading only if it passes the depth test at the moment it is tested
//    (in the algorithm's order); a later, nearer triangle does not refund it.
//  - A *visit* is the unit of shading reuse under MSAA: an algorithm's stay in one screen tile with
//    one triangle (TILE, LAINE), one pass over the triangle's pixels in a bin (a lens-grid cell for
//    INTERVAL, a lens coordinate for INTERLEAVE / HINTERLEAVE), or, for BRUTEFORCE, which walks
//    each triangle's pixels once per bin, the whole triangle in the bin. Algorithms mark visit ends
//    with SamplePipeline::end_visit(); a visit never spans two triangles or two bins.
//  - Modes ([Akenine-Möller 2012] §3, §6.4; [Nilsson 2012] §2):
//      none          shading work is not modelled (no shade.* / tex.* counts; the default, the
//                    fastest; textures still colour the image);
//      per_sample    supersampling: a lane per (pixel, sample index); a quad = one sample index
//                    over a 2x2 pixel block;
//      msaa          a lane per pixel per visit (all of the pixel's covered samples share it);
//      per_lens_cell a lane per (pixel, lens-grid cell) per visit: what INTERVAL can do;
//      cache         a memoising shading cache keyed by (triangle, shading-grid point): the
//                    grid is the screen as seen through the lens centre at shutter open, with
//                    shading_grid x shading_grid points per pixel; each visit looks up its distinct
//                    points, misses are shaded in 2x2 quads of grid points. LRU, N entries, one
//                    cache per screen bin processor, emptied at the start of each bin.
//  - Texture cache: each shaded lane (live or helper: helpers fetch too, as in hardware) fetches
//    its footprint in every texture of the triangle; the line addresses go to a per-bin stream,
//    and the streams are run through the cache model in bin raster order as the bins complete (bin b
//    to cache b mod count). That is the modelled hardware order, and it makes the counts
//    independent of the thread count.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "backend/cache_model.h"
#include "core/counters.h"
#include "core/params.h"
#include "core/sample_table.h"
#include "backend/texture.h"

namespace rast5d {

inline constexpr int kMaxTexSlots = 4;

// Per-render shading constants, read-only while workers run (except the per-bin streams, each
// written by the one thread owning that bin).
struct ShadeFrame {
  ShadingMode mode = ShadingMode::kPerSample;
  int grid = 1;                  // shading-grid points per pixel edge (cache mode)
  int cache_entries = 1024;      // shading cache (cache mode)
  int texture_count = 0;         // texture slots per shader (0: untextured)
  TexFilter filter = TexFilter::kTrilinear;
  int sample_dist_tex = -1;      // [Toth 2008] §5.3 sample-distribution texture (nearest, 1:1 pixels), or -1
  int line_bytes = 64;
  TextureSet textures;
  std::vector<std::int32_t> tex_ids;  // n_tri x kMaxTexSlots, -1 = slot unused
  std::vector<float> uvs;             // n_tri x 3 x 2
  std::vector<double> jac;            // n_tri x 4: d(u, v)/d(x, y) in pixels
  std::vector<float> lod;             // n_tri x kMaxTexSlots
  std::vector<std::vector<std::uint32_t>> streams;  // per bin: texture-cache line indices
  bool textured() const { return texture_count > 0 || sample_dist_tex >= 0; }
};

// Per-thread shading state: the records of the open visit, the shading cache, the bin's stream.
class ShadeState {
 public:
  struct Rec {
    int px, py, s, cell;
    float gx, gy;  // lens-centre screen position of the hit point (cache mode)
    float u, v;    // texture coordinates of the hit point
  };

  void attach(const ShadeFrame* sf, Counters* c) {
    sf_ = sf, c_ = c;
    counting_ = sf_ && sf_->mode != ShadingMode::kNone;
    if (sf_ && sf_->mode == ShadingMode::kCache) cache_ = std::make_unique<LruSet>(sf_->cache_entries);
  }
  const ShadeFrame* frame() const { return sf_; }
  // Shading work is modelled (a mode other than none): records, visits, quads, texel fetches.
  bool counting() const { return counting_; }

  void begin_bin(int bin) {
    close_visit();
    stream_ = counting_ && sf_->textured() ? const_cast<std::vector<std::uint32_t>*>(&sf_->streams[bin]) : nullptr;
    if (cache_) cache_->clear();
  }

  inline void record(std::uint32_t tri, const Rec& r) {
    if (!recs_.empty() && tri != tri_) close_visit();
    tri_ = tri;
    recs_.push_back(r);
  }

  // Shade the open visit's records: count quads and lanes, run the shading cache, fetch texels.
  void close_visit() {
    if (recs_.empty()) return;
    const ShadingMode mode = sf_->mode;
    const int n = static_cast<int>(recs_.size());
    keys_.resize(n);
    for (int i = 0; i < n; ++i) {
      const Rec& r = recs_[i];
      int x = r.px, y = r.py;
      std::uint64_t sub = 0;
      if (mode == ShadingMode::kCache) {
        x = grid_coord(r.gx), y = grid_coord(r.gy);
      } else if (mode == ShadingMode::kPerSample) {
        sub = static_cast<std::uint64_t>(r.s);
      } else if (mode == ShadingMode::kPerLensCell) {
        sub = static_cast<std::uint64_t>(r.cell);
      }
      const std::uint64_t quad = (static_cast<std::uint64_t>(y >> 1) << 42) | (static_cast<std::uint64_t>(x >> 1) << 21) |
                                 (sub & 0x1FFFFF);
      const std::uint64_t lane = static_cast<std::uint64_t>((x & 1) | ((y & 1) << 1));
      // Within a lane, the record of the first (py, px, s) stands for it (its uv is the lane's), so
      // the counts do not depend on the order the algorithm pushed the samples in.
      const std::uint64_t order = (lane << 62) | (static_cast<std::uint64_t>(r.py & 0xFFFF) << 44) |
                                  (static_cast<std::uint64_t>(r.px & 0xFFFF) << 28) |
                                  static_cast<std::uint64_t>(r.s & 0xFFFFFFF);
      keys_[i] = {quad, order, i};
    }
    std::sort(keys_.begin(), keys_.end(), [](const Key& a, const Key& b) {
      return a.quad != b.quad ? a.quad < b.quad : a.order < b.order;
    });
    for (int i = 0; i < n;) {
      int j = i;
      int first[4] = {-1, -1, -1, -1};
      while (j < n && keys_[j].quad == keys_[i].quad) {
        const int lane = static_cast<int>(keys_[j].order >> 62);
        if (first[lane] < 0) first[lane] = keys_[j].index;
        ++j;
      }
      if (mode == ShadingMode::kCache) {
        // One lookup per distinct grid point of the visit; only misses are shaded.
        for (int lane = 0; lane < 4; ++lane) {
          if (first[lane] < 0) continue;
          const Rec& r = recs_[first[lane]];
          const std::uint64_t key = (static_cast<std::uint64_t>(tri_) << 40) |
                                    (static_cast<std::uint64_t>(grid_coord(r.gy) & 0xFFFFF) << 20) |
                                    static_cast<std::uint64_t>(grid_coord(r.gx) & 0xFFFFF);
          if (cache_->access(key)) {
            ++(*c_)[Counter::shade_cache_hits];
            first[lane] = -1;
          } else {
            ++(*c_)[Counter::shade_cache_misses];
          }
        }
      }
      shade_quad(first, keys_[i].quad);
      i = j;
    }
    recs_.clear();
  }

 private:
  int grid_coord(float g) const {
    const double v = std::floor(static_cast<double>(g) * sf_->grid) + (1 << 19);
    return static_cast<int>(std::clamp(v, 0.0, static_cast<double>((1 << 20) - 1)));
  }

  // One quad with live lanes first[lane] >= 0 (record index): count it and fetch its texels.
  void shade_quad(const int first[4], std::uint64_t quad) {
    int live = 0, any = -1;
    for (int l = 0; l < 4; ++l)
      if (first[l] >= 0) ++live, any = l;
    if (!live) return;
    Counters& c = *c_;
    ++c[Counter::shade_quad_requests];
    c[Counter::shade_lanes_live] += static_cast<std::uint64_t>(live);
    c[Counter::shade_lanes_helper] += static_cast<std::uint64_t>(4 - live);
    c[Counter::shade_invocations] += 4;
    if (!stream_) return;
    // Helper lanes take a live lane's uv moved by the triangle's analytic derivatives.
    const Rec& ref = recs_[first[any]];
    const bool cache = sf_->mode == ShadingMode::kCache;
    const double step = cache ? 1.0 / sf_->grid : 1.0;  // lane spacing in pixels
    const int qx = static_cast<int>((quad >> 21) & 0x1FFFFF), qy = static_cast<int>(quad >> 42);
    // No texture slots (only the sample-distribution texture): no uvs and no derivatives.
    static constexpr double kNoJacobian[4] = {0, 0, 0, 0};
    const double* J = sf_->texture_count > 0 ? &sf_->jac[static_cast<std::size_t>(tri_) * 4] : kNoJacobian;
    for (int l = 0; l < 4; ++l) {
      float u, v;
      if (first[l] >= 0) {
        u = recs_[first[l]].u, v = recs_[first[l]].v;
      } else {
        const double dx = ((l & 1) - (any & 1)) * step, dy = ((l >> 1) - (any >> 1)) * step;
        u = static_cast<float>(ref.u + J[0] * dx + J[1] * dy);
        v = static_cast<float>(ref.v + J[2] * dx + J[3] * dy);
      }
      int px = 2 * qx + (l & 1), py = 2 * qy + (l >> 1);
      if (cache) {
        px = static_cast<int>(std::floor((px - (1 << 19)) / static_cast<double>(sf_->grid)));
        py = static_cast<int>(std::floor((py - (1 << 19)) / static_cast<double>(sf_->grid)));
      }
      fetch_lane(u, v, px, py);
    }
  }

  void fetch_lane(float u, float v, int px, int py) {
    const ShadeFrame& sf = *sf_;
    const TextureSet& ts = sf.textures;
    const std::uint64_t lb = static_cast<std::uint64_t>(sf.line_bytes);
    for (int k = 0; k < sf.texture_count; ++k) {
      const int id = sf.tex_ids[static_cast<std::size_t>(tri_) * kMaxTexSlots + k];
      if (id < 0) continue;
      int lv[2];
      float w[2];
      const int nl = ts.select_levels(id, sf.lod[static_cast<std::size_t>(tri_) * kMaxTexSlots + k], sf.filter, lv, w);
      for (int q = 0; q < nl; ++q) {
        const auto f = ts.footprint(id, lv[q], u, v);
        std::uint64_t lines[4];
        int nlines = 0;
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b) {
            const std::uint64_t line = ts.address(id, lv[q], f.x[b], f.y[a]) / lb;
            bool dup = false;
            for (int m = 0; m < nlines; ++m) dup |= lines[m] == line;
            if (!dup) lines[nlines++] = line;
          }
        (*c_)[Counter::tex_fetches] += 4;
        for (int m = 0; m < nlines; ++m) stream_->push_back(static_cast<std::uint32_t>(lines[m]));
      }
    }
    if (sf.sample_dist_tex >= 0) {  // [Toth 2008] §5.3: one texel per pixel, 1:1 screen mapping, nearest
      const MipLevel& m = ts[sf.sample_dist_tex].levels[0];
      const int x = ((px % m.w) + m.w) % m.w, y = ((py % m.h) + m.h) % m.h;
      ++(*c_)[Counter::tex_fetches];
      stream_->push_back(static_cast<std::uint32_t>(ts.address(sf.sample_dist_tex, 0, x, y) / lb));
    }
  }

  const ShadeFrame* sf_ = nullptr;
  Counters* c_ = nullptr;
  bool counting_ = false;
  std::unique_ptr<LruSet> cache_;
  std::vector<std::uint32_t>* stream_ = nullptr;
  std::uint32_t tri_ = 0;
  std::vector<Rec> recs_;
  struct Key {
    std::uint64_t quad, order;
    int index;
  };
  std::vector<Key> keys_;
};

// The texture caches, replayed over the bins' line streams in bin raster order (bin b to cache b mod
// count): the modelled hardware order, independent of the thread count. The frame hands it each bin's
// stream as the bins complete in order (frame/bin_stream.h), and frees the stream after.
class TextureCacheReplay {
 public:
  TextureCacheReplay(int count, std::uint64_t lines, std::uint64_t ways) {
    for (int i = 0; i < count; ++i) caches_.emplace_back(lines, ways);
  }
  // Run bin b's stream from `begin` up to `end`; with ends (stream lengths after each record, within
  // [begin, end]), each record's own misses into misses (one per end).
  void consume(int bin, const std::vector<std::uint32_t>& stream, std::size_t begin, std::size_t end,
               const std::vector<std::uint32_t>* ends, std::vector<std::uint32_t>* misses) {
    SetAssocCache& cache = caches_[static_cast<std::size_t>(bin) % caches_.size()];
    std::size_t i = begin;
    auto run_to = [&](std::size_t stop) {  // accesses [i, stop): their misses
      std::uint32_t m = 0;
      for (; i < stop; ++i) m += !cache.access(stream[i]);
      return m;
    };
    if (ends) {
      misses->clear();
      for (std::uint32_t e : *ends) misses->push_back(run_to(e));
    }
    run_to(end);
  }
  CacheStats stats() const {
    CacheStats s;
    for (const auto& cache : caches_) {
      const CacheStats& t = cache.stats();
      s.accesses += t.accesses, s.hits += t.hits, s.misses += t.misses;
      s.cold += t.cold, s.capacity += t.capacity, s.conflict += t.conflict;
    }
    return s;
  }

 private:
  std::vector<SetAssocCache> caches_;
};

}  // namespace rast5d
