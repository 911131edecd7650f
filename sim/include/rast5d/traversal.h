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

#include <functional>
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

  Counters& counters() { return c_; }

 private:
  static constexpr Counter kTestedByClass[4] = {
      Counter::raster_samples_tested_2d, Counter::raster_samples_tested_3d,
      Counter::raster_samples_tested_4d, Counter::raster_samples_tested_5d};

  inline void finish(const TriSetup& tri, bool covered, const F e[3], F det, int n_ties, int px, int py,
                     int s, std::uint64_t inside_cost) {
    ++c_[Counter::raster_samples_tested];
    charge<A>(c_[Counter::ops_sample_inside], inside_cost + n_ties * cost::kTieBreak);
    if (n_ties) ++c_[Counter::raster_tie_breaks];
    if (!covered) return;
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
