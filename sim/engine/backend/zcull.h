// Depth culling of (triangle, tile) pairs against HiZ, and occlusion queries ([Nilsson 2012]
// §3, Appendix A; docs/intervals.md). A traversal that has accepted a pair by its tile test asks
// check() with the pair's (x, y, u, v, t) box: ẑ (intervals/depth_interval.h) against the HiZ tile's
// zmax culls the pair (zmax-culling), against zmin lets its samples skip depth reads (zmin-culling).
// Occlusion-query triangles (query_first and later) either run the depth test only (query_mode samples)
// or are answered from ẑ alone (query_mode intervals: a pair not behind HiZ makes the query visible and
// the traversal stops).
//
// Contract: never culls a pair with a sample that would pass the depth test (ẑ is conservative and
// HiZ is conservative at all times, backend/hiz.h); the image is the same with and without
// HiZ. Counters: zcull.*, hiz.*, occlusion.* and ops.zhat.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "backend/bin_buffers.h"
#include "backend/hiz.h"
#include "core/arith.h"
#include "core/costs.h"
#include "core/counters.h"
#include "intervals/depth_interval.h"
#include "tiletest/precision_4d.h"
#include "core/triangle.h"

namespace rast5d {

// Pipeline: the traversal's SamplePipeline (set_depth_mode, flush).
template <class A, class Pipeline>
class DepthCull {
  using D = typename A::f64;

 public:
  DepthCull(const Frame& f, Counters& c, BinBuffers& buf, Pipeline& pipe) : f_(f), c_(c), buf_(buf), pipe_(pipe) {
    if (f.p.hiz_enabled || f.p.query_mode == QueryMode::kIntervals) buf_.hiz().set_tile(f.p.hiz_tile_size);
  }

  // Per triangle, in every bin: query state and the moving planes of ẑ (charged in the first bin).
  void begin_triangle(const TriSetup& tri, bool charge_setup) {
    const RenderParams& p = f_.p;
    query_ = p.query_first >= 0 && tri.index >= static_cast<std::uint32_t>(p.query_first) &&
             p.query_mode != QueryMode::kNone;
    set_mode(false);
    need_z_ = p.hiz_enabled || p.zhat_stats || (query_ && p.query_mode == QueryMode::kIntervals);
    if (need_z_ && p.zhat == ZhatMode::kPlanes) {
      std::uint64_t ops = 0;
      iv::moving_planes<A>(tri, planes_, ops);
      if (charge_setup) c_[Counter::ops_zhat] += ops;
    }
  }
  // After the triangle's samples: flush them and write back the HiZ tiles it may have changed.
  void end_triangle() {
    pipe_.flush();
    if (f_.p.hiz_enabled && !query_) c_[Counter::hiz_bytes_written] += 8 * static_cast<std::uint64_t>(buf_.hiz_update());
  }
  // An interval-based query has been answered: the traversal may stop.
  bool query_answered() const { return query_ && query_visible_; }

  // One (triangle, tile) pair that passed its tile test: ẑ against HiZ. Returns false when the pair
  // is culled (zmax-culling, or an interval-based query pair: no samples either way); sets the
  // depth-read mode of the pair's samples (zmin-culling).
  bool check(const TriSetup& tri, int tx, int ty, double x0, double x1, double y0, double y1, bool lens, double u0,
             double u1, double v0, double v1, double ta, double tb, int n_samples) {
    const RenderParams& p = f_.p;
    if (!need_z_) return true;
    const bool query_iv = query_ && p.query_mode == QueryMode::kIntervals;
    iv::ZHat z = iv::zhat<A>(tri, p.zhat == ZhatMode::kPlanes ? &planes_ : nullptr, f_.fc, lens, x0, x1, y0, y1, u0,
                             u1, v0, v1, ta, tb, c_[Counter::ops_zhat]);
    if (p.zhat_margin == ZhatMargin::kFixed) z.margin = iv::kFixedDepthMargin;
    ++c_[Counter::zcull_pairs];
    const double nr = f_.fc.near_d;
    auto width = [nr](double lo, double hi) {
      const double w = (hi - std::max(lo, nr)) / nr * 1e6;
      return w > 0 ? static_cast<std::uint64_t>(std::llround(std::min(w, 1e15))) : std::uint64_t(0);
    };
    // the intervals actually compared: widened by the pair's rounding bound (iv::zhat_widen); a pair
    // with an unbounded margin compares [near, inf) and is counted apart
    if (z.margin < iv::kInfD) {
      double wl, wh;
      iv::zhat_widen_w(z, nr, z.wlo, z.whi, wl, wh);
      c_[Counter::zcull_width_zhat] += width(wl, wh);
      iv::zhat_widen_w(z, nr, z.vwlo, z.vwhi, wl, wh);
      c_[Counter::zcull_width_vertex] += width(wl, wh);
    } else {
      ++c_[Counter::zcull_pairs_unbounded];
    }
    if (!(p.hiz_enabled || query_iv)) return true;
    double zlo, zhi;
    iv::zhat_widen(z, nr, zlo, zhi);
    tiletest::zhat_round_out(p.precision_tile, zlo, zhi);  // pipeline.precision.tile: outward to the format
    const double zmax = buf_.hiz().max(tx, ty), zmin = buf_.hiz().min(tx, ty);
    c_[Counter::hiz_bytes_read] += 8;
    const bool behind = D(zlo) >= D(zmax);
    const bool front = D(zhi) < D(zmin);
    charge<A>(c_[Counter::ops_zhat], cost::kHiZCompare);
    if (query_iv) {
      ++c_[Counter::occlusion_pairs_tested];
      if (!behind) ++c_[Counter::occlusion_visible_pairs], query_visible_ = true;
      return false;
    }
    if (behind) {
      ++c_[Counter::zcull_pairs_culled];
      c_[Counter::zcull_samples_culled] += static_cast<std::uint64_t>(n_samples);
      return false;
    }
    if (front) ++c_[Counter::zcull_pairs_zmin];
    set_mode(front);
    if (p.hiz_enabled) buf_.hiz().mark(tx, ty);
    return true;
  }

 private:
  void set_mode(bool skip_reads) {
    const bool q = query_ && f_.p.query_mode == QueryMode::kSamples;
    if (skip_reads != skip_reads_ || q != mode_query_) pipe_.set_depth_mode(skip_reads, q);
    skip_reads_ = skip_reads, mode_query_ = q;
  }

  const Frame& f_;
  Counters& c_;
  BinBuffers& buf_;
  Pipeline& pipe_;
  iv::MovingPlanes planes_;
  bool query_ = false, query_visible_ = false, need_z_ = false, skip_reads_ = false, mode_query_ = false;
};

}  // namespace rast5d
