// Traversal algorithms: one interface, one file per implementation, registered by name
// (STYLE.md; Ramulator 2's self-registering factory). Adding an algorithm = one .cpp file with a
// RAST5D_REGISTER_TRAVERSAL line.
//
// Calling protocol (one instance per worker thread, created once per render):
//   1. The engine runs triangle setup (setup.h) for every triangle, once.
//   2. For each screen bin, in any order across threads, and for each triangle whose bounds
//      overlap the bin, in submission order, the engine calls rasterize(tri, bin, charge_setup).
//      charge_setup is true in exactly one bin per triangle (its first bin in raster order): an
//      algorithm recomputes its per-triangle setup in every bin it is called for, but charges the
//      operations only then, so counts never depend on binning or thread count.
//   3. rasterize() hands candidate samples of pixels inside the bin to the SamplePipeline, which
//      runs the exact sample test and the backend.
//
// Contract: an implementation must be *exact*: it must pass to the sample pipeline every sample
// of the bin that the exact sample test hits (it may pass more: that is its inefficiency), each
// at most once per call, for every triangle class (moving triangles through a conservative path,
// counted in trav.motion_fallback). Tile tests it uses must be conservative (never cull a hit).
// Then all algorithms render bit-identical images from the same sample table and differ only in
// their work counters.
#pragma once

#include <cstring>
#include <functional>
#include <vector>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "rast5d/arith.h"
#include "rast5d/backend.h"
#include "rast5d/costs.h"
#include "rast5d/counters.h"
#include "rast5d/inside.h"
#include "rast5d/params.h"
#include "rast5d/sample_table.h"
#include "rast5d/sample_test.h"
#include "rast5d/setup.h"

namespace rast5d {

struct Frame {
  const RenderParams& p;
  const FrameConst& fc;
  const SampleTable& table;
};

struct ThreadState {
  Counters counters;
  BinBuffers buffers;
};

// The sample test and backend, shared by every algorithm.
template <class A>
class SamplePipeline {
 public:
  using F = typename A::f32;

  SamplePipeline(const Frame& f, ThreadState& ts) : f_(f), c_(ts.counters), buf_(ts.buffers) {}

  // Test canonical sample s of pixel (px, py) against tri with the kernel of tri's class.
  inline void test(const TriSetup& tri, int px, int py, const PixelSamples& ps, int s) {
    const F sx = F(static_cast<float>(px) + ps.x[s]);
    const F sy = F(static_cast<float>(py) + ps.y[s]);
    F X[3], Y[3], W[3], e[3], det;
    int n_ties;
    const bool covered = inside_test(tri, tri.cls, f_.fc, sx, sy, F(ps.u[s]), F(ps.v[s]), F(ps.t[s]),
                                     f_.p.backface_cull, X, Y, W, e, det, n_ties);
    ++c_[kTestedByClass[static_cast<int>(tri.cls)]];
    finish(tri, covered, e, det, n_ties, px, py, s, kInsideCost[static_cast<int>(tri.cls)]);
  }

  // Test with static vertices already sheared to the sample's (discrete) lens coordinate: the 2D
  // kernel. Xs = madd(u_i, cx, X) computed with the same float operations as the 4D kernel, so the
  // result is bit-identical to test().
  inline void test_sheared(const TriSetup& tri, const float Xs[3], const float Ys[3], int px, int py,
                           const PixelSamples& ps, int s) {
    const F sx = F(static_cast<float>(px) + ps.x[s]);
    const F sy = F(static_cast<float>(py) + ps.y[s]);
    F X[3], Y[3], W[3], e[3], det;
    for (int j = 0; j < 3; ++j) X[j] = F(Xs[j]), Y[j] = F(Ys[j]), W[j] = F(tri.W[j]);
    int n_ties;
    const bool covered = inside_from_vertices(X, Y, W, sx, sy, f_.p.backface_cull, e, det, n_ties);
    ++c_[Counter::raster_samples_tested_2d];
    finish(tri, covered, e, det, n_ties, px, py, s, cost::kInside2D);
  }

  // Test candidate samples idx[0..n) of pixel (px, py). Same results and counts as calling
  // test() for each; the fast path evaluates the kernels for the whole batch in branch-free
  // loops (the decisions of near-edge samples are data-dependent and mispredict otherwise),
  // with the identical float operations, so the results are bit-identical.
  inline void test_many(const TriSetup& tri, int px, int py, const PixelSamples& ps, const int* idx, int n) {
    if constexpr (A::counting) {
      for (int i = 0; i < n; ++i) test(tri, px, py, ps, idx ? idx[i] : i);
    } else {
      if (n <= 0) return;
      const float fx = static_cast<float>(px), fy = static_cast<float>(py);
      const int cls = static_cast<int>(tri.cls);
      const FrameConst& fc = f_.fc;
      const BatchTri T{tri.X[0],  tri.X[1],  tri.X[2],  tri.Y[0],  tri.Y[1],  tri.Y[2],  tri.W[0],
                       tri.W[1],  tri.W[2],  tri.cx[0], tri.cx[1], tri.cx[2], tri.cy[0], tri.cy[1],
                       tri.cy[2], tri.dX[0], tri.dX[1], tri.dX[2], tri.dY[0], tri.dY[1], tri.dY[2],
                       tri.dW[0], tri.dW[1], tri.dW[2], fc.kx,     fc.neg_kx_f, fc.ky, fc.neg_ky_f};
      // Gather the batch into contiguous arrays (only the components the class needs; a null idx
      // means samples 0..n-1, already contiguous), then run the class's vectorised kernel.
      const float *bu = ps.u, *bv = ps.v, *bt = ps.t;
      if (idx == nullptr) {
        gather_xy(ps.x, ps.y, fx, fy, n);
      } else {
        for (int i = 0; i < n; ++i) {
          const int s = idx[i];
          gx_[i] = fx + ps.x[s], gy_[i] = fy + ps.y[s];
        }
        if (cls >= 2) {
          for (int i = 0; i < n; ++i) gu_[i] = ps.u[idx[i]], gv_[i] = ps.v[idx[i]];
          bu = gu_.data(), bv = gv_.data();
        }
        if (cls & 1) {
          for (int i = 0; i < n; ++i) gt_[i] = ps.t[idx[i]];
          bt = gt_.data();
        }
      }
      float* e = be_.data();
      switch (cls) {
        case 0: batch_edges_2d(n, T, gx_.data(), gy_.data(), e, e + n, e + 2 * n, bdet_.data()); break;
        case 2: batch_edges_4d(n, T, gx_.data(), gy_.data(), bu, bv, e, e + n, e + 2 * n, bdet_.data()); break;
        case 1: batch_edges_3d(n, T, gx_.data(), gy_.data(), bt, e, e + n, e + 2 * n, bdet_.data()); break;
        default:
          batch_edges_5d(n, T, gx_.data(), gy_.data(), bu, bv, bt, e, e + n, e + 2 * n, bdet_.data());
          break;
      }
      c_[kTestedByClass[cls]] += static_cast<std::uint64_t>(n);
      classify_batch(tri, px, py, ps, idx, n, kInsideCost[cls], false, nullptr, nullptr, 0);
    }
  }

  // Batched test_sheared(). With lens_stride == 0 every sample uses Xs/Ys; with lens_stride == 3
  // sample s uses Xs[3 * lens_index[s]] (the triangle pre-sheared to each lens coordinate).
  inline void test_many_sheared(const TriSetup& tri, const float* Xs, const float* Ys, int lens_stride, int px,
                                int py, const PixelSamples& ps, const int* idx, int n) {
    if constexpr (A::counting) {
      for (int i = 0; i < n; ++i) {
        const int s = idx ? idx[i] : i;
        const int off = lens_stride ? lens_stride * ps.lens_index[s] : 0;
        test_sheared(tri, Xs + off, Ys + off, px, py, ps, s);
      }
    } else {
      if (n <= 0) return;
      const float fx = static_cast<float>(px), fy = static_cast<float>(py);
      const float W[3] = {tri.W[0], tri.W[1], tri.W[2]};
      if (lens_stride == 0) {
        if (idx == nullptr) {
          gather_xy(ps.x, ps.y, fx, fy, n);
        } else {
          for (int i = 0; i < n; ++i) {
            const int s = idx[i];
            gx_[i] = fx + ps.x[s], gy_[i] = fy + ps.y[s];
          }
        }
        BatchTri T{};
        T.X0 = Xs[0], T.X1 = Xs[1], T.X2 = Xs[2], T.Y0 = Ys[0], T.Y1 = Ys[1], T.Y2 = Ys[2];
        T.W0 = W[0], T.W1 = W[1], T.W2 = W[2];
        float* e = be_.data();
        batch_edges_2d(n, T, gx_.data(), gy_.data(), e, e + n, e + 2 * n, bdet_.data());
      } else {
        for (int i = 0; i < n; ++i) {
          const int s = idx ? idx[i] : i;
          const int off = lens_stride * ps.lens_index[s];
          float ev[3];
          edge_functions(Xs + off, Ys + off, W, fx + ps.x[s], fy + ps.y[s], ev, bdet_[i]);
          be_[i] = ev[0], be_[n + i] = ev[1], be_[2 * n + i] = ev[2];
        }
      }
      c_[Counter::raster_samples_tested_2d] += static_cast<std::uint64_t>(n);
      classify_batch(tri, px, py, ps, idx, n, cost::kInside2D, true, Xs, Ys, lens_stride);
    }
  }

  Counters& counters() { return c_; }

 private:
  static constexpr Counter kTestedByClass[4] = {
      Counter::raster_samples_tested_2d, Counter::raster_samples_tested_3d,
      Counter::raster_samples_tested_4d, Counter::raster_samples_tested_5d};
  static constexpr int kBatch = 4096;

  void gather_xy(const float* __restrict x, const float* __restrict y, float fx, float fy, int n) {
    float* __restrict gx = gx_.data();
    float* __restrict gy = gy_.data();
    for (int i = 0; i < n; ++i) gx[i] = fx + x[i], gy[i] = fy + y[i];
  }

  // Decide the batch from be_/bdet_: covered where det != 0 and every e_i has det's sign; samples
  // with an e_i == 0 go through the scalar path (top-left rule). Then interpolate and shade.
  inline void classify_batch(const TriSetup& tri, int px, int py, const PixelSamples& ps, const int* idx, int n,
                             std::uint64_t inside_cost, bool sheared, const float* Xs, const float* Ys,
                             int lens_stride = 0) {
    const bool bfc = f_.p.backface_cull;
    // Flags: 1 = covered (every e_i has det's non-zero sign), 2 = an e_i is exactly zero (scalar
    // top-left path). Vectorised; then skip 8 flags at a time (most batches are mostly misses).
    batch_flags(n, be_.data(), be_.data() + n, be_.data() + 2 * n, bdet_.data(), bfc, flags_.data());
    c_[Counter::raster_samples_tested] += static_cast<std::uint64_t>(n);
    c_[Counter::ops_sample_inside] += inside_cost * static_cast<std::uint64_t>(n);
    int n_tie = 0;
    for (int w = 0; w < n; w += 8) {
      std::uint64_t word;
      std::memcpy(&word, &flags_[w], 8);
      if (!word) continue;
      for (int i = w; i < std::min(n, w + 8); ++i) {
        const std::uint8_t fl = flags_[i];
        if (fl & 1) {
          const F ev[3] = {be_[i], be_[n + i], be_[2 * n + i]};
          shade(tri, ev, bdet_[i], px, py, idx ? idx[i] : i);
        } else if (fl & 2) {
          tie_[n_tie++] = i;
        }
      }
    }
    for (int k = 0; k < n_tie; ++k) {  // rare: an edge function is exactly zero
      const int i = tie_[k];
      const int s = idx ? idx[i] : i;
      float X[3], Y[3], W[3], e[3], det;
      int n_ties;
      const float sx = static_cast<float>(px) + ps.x[s], sy = static_cast<float>(py) + ps.y[s];
      bool covered;
      if (sheared) {
        const int off = lens_stride ? lens_stride * ps.lens_index[s] : 0;
        for (int j = 0; j < 3; ++j) X[j] = Xs[off + j], Y[j] = Ys[off + j], W[j] = tri.W[j];
        covered = inside_from_vertices(X, Y, W, sx, sy, bfc, e, det, n_ties);
      } else {
        covered = inside_test(tri, tri.cls, f_.fc, sx, sy, ps.u[s], ps.v[s], ps.t[s], bfc, X, Y, W, e, det, n_ties);
      }
      c_[Counter::ops_sample_inside] += static_cast<std::uint64_t>(n_ties) * cost::kTieBreak;
      if (n_ties) ++c_[Counter::raster_tie_breaks];
      if (covered) shade(tri, e, det, px, py, s);
    }
  }

  inline void finish(const TriSetup& tri, bool covered, const F e[3], F det, int n_ties, int px, int py,
                     int s, std::uint64_t inside_cost) {
    ++c_[Counter::raster_samples_tested];
    charge<A>(c_[Counter::ops_sample_inside], inside_cost + n_ties * cost::kTieBreak);
    if (n_ties) ++c_[Counter::raster_tie_breaks];
    if (covered) shade(tri, e, det, px, py, s);
  }

  // A covered sample: depth, near plane, depth test, colour. Cost: ops.interp.
  inline void shade(const TriSetup& tri, const F e[3], F det, int px, int py, int s) {
    ++c_[Counter::raster_samples_covered];
    std::uint64_t& iops = c_[Counter::ops_interp];
    F sum, z;
    const bool in_front = hit_depth(e, det, F(f_.fc.neg_near), sum, z);
    charge<A>(iops, cost::kDepth);
    if (!in_front) {
      ++c_[Counter::raster_samples_near_rejected];
      return;
    }
    ++c_[Counter::raster_samples_hit];
    ++c_[Counter::depth_tests];
    const std::size_t slot = buf_.slot(px, py, s);
    float& zbuf = buf_.depth(slot);
    const bool pass = z < F(zbuf);
    charge<A>(iops, cost::kDepthTest);
    if (!pass) return;
    ++c_[Counter::depth_passes];
    F c0[3], c1[3], c2[3], out[3];
    for (int ch = 0; ch < 3; ++ch)
      c0[ch] = F(tri.color[0][ch]), c1[ch] = F(tri.color[1][ch]), c2[ch] = F(tri.color[2][ch]);
    hit_color(e, sum, c0, c1, c2, out);
    charge<A>(iops, cost::kColor);
    zbuf = raw(z);
    buf_.set_triangle(slot, static_cast<std::int32_t>(tri.index));
    float* dst = buf_.color(slot);
    for (int ch = 0; ch < 3; ++ch) dst[ch] = raw(out[ch]);
  }

  const Frame& f_;
  Counters& c_;
  BinBuffers& buf_;
  // Batch scratch (fast path): edge functions, determinants, covered and tie lists.
  std::vector<float> be_ = std::vector<float>(3 * kBatch), bdet_ = std::vector<float>(kBatch);
  std::vector<int> cov_ = std::vector<int>(kBatch), tie_ = std::vector<int>(kBatch);
  std::vector<std::uint8_t> flags_ = std::vector<std::uint8_t>(kBatch + 8, 0);
  std::vector<float> gx_ = std::vector<float>(kBatch), gy_ = std::vector<float>(kBatch),
                     gu_ = std::vector<float>(kBatch), gv_ = std::vector<float>(kBatch),
                     gt_ = std::vector<float>(kBatch);
};

class Traversal {
 public:
  virtual ~Traversal() = default;
  virtual void rasterize(const TriSetup& tri, const BinRect& bin, bool charge_setup) = 0;
};

struct TraversalInfo {
  std::string description;
  bool needs_interleaved_table = false;
  std::function<std::unique_ptr<Traversal>(const Frame&, ThreadState&, bool exact)> create;
};

class TraversalRegistry {
 public:
  static std::map<std::string, TraversalInfo>& entries() {
    static std::map<std::string, TraversalInfo> m;
    return m;
  }
  static bool add(const std::string& name, TraversalInfo info) {
    entries().emplace(name, std::move(info));
    return true;
  }
};

#define RAST5D_REGISTER_TRAVERSAL(NAME, DESCRIPTION, NEEDS_INTERLEAVED, CLASS)                   \
  static const bool kRegistered_##CLASS = ::rast5d::TraversalRegistry::add(                       \
      NAME, ::rast5d::TraversalInfo{                                                              \
                DESCRIPTION, NEEDS_INTERLEAVED,                                                   \
                [](const ::rast5d::Frame& f, ::rast5d::ThreadState& ts,                           \
                   bool exact) -> std::unique_ptr<::rast5d::Traversal> {                          \
                  if (exact) return std::make_unique<CLASS<::rast5d::ExactArith>>(f, ts);         \
                  return std::make_unique<CLASS<::rast5d::FastArith>>(f, ts);                     \
                }})

}  // namespace rast5d
