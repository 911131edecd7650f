// LAINE5D: after Laine, Aila, Karras and Lehtinen 2011 ("Clipless dual-space bounds for faster
// stochastic rasterization"), motion and defocus together, as the 5D comparator [Akenine-Möller 2012] lacked. Per
// screen tile the triangle gets axis-aligned bounds of the sample coordinates that can hit it, and
// every sample of the tile's pixels is checked against them before the inside test: no lens grid,
// no time-strata index and no tile-level early out (an empty bound still costs each sample its
// comparisons), as in `laine`.
//  * Static triangles: the lens bounds of `laine` (the h_i lines, Laine's dual-space lens bounds).
//  * Moving triangles: a time interval t̂ and, with defocus, lens bounds over t̂ from one
//    sub-interval of intervals/time_interval.h: the separating lines of each tile edge in the dual
//    (position, time) space of the vertices' linear motion, evaluated at the lens-box corners, and
//    the h_i lines of the six shutter-end vertices for the lens. Departure: Laine et al. bound time
//    and lens jointly per tile with their own affine bounds; here the two are bounded one after the
//    other with the engine's conservative interval functions (the same t̂ and lens sets TILE uses
//    with time_splits 1), so the comparison isolates the traversal (per-sample checks) from the bounds.
// Per-sample cost (ops.sample_region): t against t̂ 2 CMP (cost::kSampleTime), u and v against the
// lens sets their n_cmp; against an empty bound cost::kSampleTime comparisons that fail.
#include <algorithm>
#include <vector>

#include "intervals/clip.h"
#include "intervals/time_interval.h"
#include "setup/footprint.h"
#include "tiletest/candidates.h"
#include "traversal/exact_region.h"
#include "tiletest/halfspace_lens.h"
#include "tiletest/precision_4d.h"
#include "intervals/precision_5d.h"
#include "traversal/traversal.h"

namespace rast5d {
namespace {

template <class A>
class Laine5D final : public Traversal {
  using D = typename A::f64;
  using F = typename A::f32;

 public:
  Laine5D(const Frame& f, ThreadState& ts) : f_(f), c_(ts.counters), pipe_(f, ts) {}

  void rasterize(const TriSetup& tri, const BinRect& bin, bool charge_setup) override {
    std::uint64_t setup_ops = 0;
    Footprint fp;
    if (tri.moving)
      iv::motion_setup<A>(tri, f_.fc, 1, ms_, setup_ops);
    else
      fp = build_footprint<A>(tri, f_, false, setup_ops);
    if (charge_setup) c_[Counter::ops_setup] += setup_ops;
    const RenderParams& p = f_.p;
    const int T = p.tile_size, spp = f_.table.spp();
    const bool use_h = !tri.moving && p.halfspace_h && fp.h_valid;
    const bool prec = p.precision_tile.kind != PrecisionKind::kFloat64;  // tiletest/precision_{4d,5d}.h
    if (prec && tri.moving) p5_.setup(p.precision_tile, ms_, 0.5 * f_.fc.near_d, nullptr);
    if (prec && use_h) p4_.setup(p.precision_tile, fp.lv, fp.n, nullptr, false);
    pipe_.begin(tri);
    const int x0 = std::max(tri.bx0, bin.x0), x1 = std::min(tri.bx1, bin.x1);
    const int y0 = std::max(tri.by0, bin.y0), y1 = std::min(tri.by1, bin.y1);
    for (int ty = (y0 / T) * T; ty < y1; ty += T)
      for (int tx = (x0 / T) * T; tx < x1; tx += T) {
        pipe_.at_rect(std::max(tx, x0), std::max(ty, y0), std::min(tx + T, x1), std::min(ty + T, y1));
        ++c_[Counter::tile_visited];
        const double ex0 = tiletest::expand_lo(tx), ex1 = tiletest::expand_hi(tx + T);
        const double ey0 = tiletest::expand_lo(ty), ey1 = tiletest::expand_hi(ty + T);
        tiletest::AxisSet sx = tiletest::full_axis(), sy = tiletest::full_axis();
        bool empty = false, timed = false;
        float tlo = 0.0f, thi = 1.0f;
        if (tri.moving) {
          timed = true;
          empty = !iv::motion_tile_intervals<A>(ms_, clip_, tri.cls, ex0, ex1, ey0, ey1, ti_, c_[Counter::ops_tile], c_);
          if (prec) {  // the decision in pipeline.precision.tile (counted as the float64 form)
            bool ovf;
            empty = !p5_.tile_intervals(clip_, ex0, ex1, ey0, ey1, ti_, true, ovf);
            if (ovf) ++c_[Counter::precision_tile5d_overflows];
          }
          if (!empty) sx = ti_.sx[0], sy = ti_.sy[0], tlo = ti_.tlo[0], thi = ti_.thi[0];
        } else if (use_h) {
          empty = !tile_h_sets<A>(fp, ex0, ex1, ey0, ey1, sx, sy, c_[Counter::ops_tile]);
          if (prec) {  // the decision in pipeline.precision.tile (counted as the float64 form)
            bool ovf;
            empty = !p4_.h_sets(ex0, ex1, ey0, ey1, sx, sy, ovf);
            if (ovf) ++c_[Counter::precision_tile4d_overflows];
          }
        }
        ++c_[Counter::tile_accepted];
        const std::uint64_t region_cost =
            empty ? (timed ? cost::kSampleTime : cost::kSampleRegionEmpty)
                  : static_cast<std::uint64_t>(sx.n_cmp + sy.n_cmp) + (timed ? cost::kSampleTime : 0);
        for (int py = std::max(ty, y0); py < std::min(ty + T, y1); ++py)
          for (int px = std::max(tx, x0); px < std::min(tx + T, x1); ++px) {
            const PixelSamples ps = f_.table.pixel(px, py);
            pipe_.at_pixel(px, py);
            int n = 0;
            for (int s = 0; s < spp; ++s) {
              bool pass;
              if (empty) {
                if (timed) {  // t against an empty t̂ (t_lo > t_hi): 2 CMP that fail
                  const F t(ps.t[s]);
                  pass = (t >= F(1.0f)) & (t <= F(0.0f));
                } else {  // as `laine`: u, v against an empty lens region
                  const F u(ps.u[s]), v(ps.v[s]);
                  pass = (u >= F(1.0f)) & (u <= F(-1.0f)) & (v >= F(1.0f)) & (v <= F(-1.0f));
                }
              } else {
                pass = true;
                if (timed) {
                  const F t(ps.t[s]);
                  pass = (t >= F(tlo)) & (t <= F(thi));
                }
                if (sx.n_cmp) pass &= tiletest::axis_pass(sx, F(ps.u[s]));
                if (sy.n_cmp) pass &= tiletest::axis_pass(sy, F(ps.v[s]));
              }
              cand_[n] = s;
              n += pass;
            }
            charge<A>(c_[Counter::ops_sample_region], region_cost * static_cast<std::uint64_t>(spp));
            if (p.count_optimal)  // instrumentation: the exact (u, v) or (u, v, t) region of the tile
              c_[Counter::tile_samples_optimal] += tiletest::count_exact_region(tri, fp, f_.fc, ps, cand_.data(), n, tx, ty, T);
            for (int i = 0; i < n; ++i) pipe_.push(px, py, ps, cand_[i]);
          }
        pipe_.end_visit();  // a visit = one tile
      }
    pipe_.flush();
  }

 private:
  const Frame& f_;
  Counters& c_;
  SamplePipeline<A> pipe_;
  const iv::ClipBox clip_ = iv::clip_box(f_.p);
  iv::MotionSetup ms_;
  iv::TileIntervals ti_;
  tiletest::Tile4DPrecision p4_;    // static: the h_i sets in pipeline.precision.tile (not float64)
  tiletest::Motion5DPrecision p5_;  // moving: t̂ and lens sets in pipeline.precision.tile (not float64)
  std::vector<int> cand_ = std::vector<int>(f_.table.spp());
};

}  // namespace

RAST5D_REGISTER_TRAVERSAL("laine5d",
                          "after [Laine 2011], motion and defocus: per-tile time interval and lens bounds, "
                          "every sample checked against them, no tile-level early out",
                          TableKinds::kPoints, PipelineKind::kSample, Laine5D);

}  // namespace rast5d
