// ACCUMULATION buffering (000_de06ed5e73318ec6.txt §2.2, §8; Haeberli and Akeley 1990): one full
// pinhole pass per lens position of the table (SampleTable.accumulation: every pixel uses the same
// N positions, sample s = pass s). Each pass re-sends the triangle: it is sheared to the pass's
// lens position, bounded, and set up as an ordinary pinhole triangle (2D edge setup, charged per
// pass), and the pass's samples are tested with the 2D kernel. The samples tested are INTERLEAVE's
// (001 §5.3) on the same table, so images and sample counts equal it; the per-pass triangle setup
// is the cost accumulation adds. Moving triangles: bounds over both shutter ends and the general
// sample test, as INTERLEAVE (counted in trav.motion_fallback).
#include <algorithm>

#include "setup/footprint.h"
#include "tiletest/box_bounds.h"
#include "tiletest/edges_2d.h"
#include "traversal/traversal.h"

namespace rast5d {
namespace {

template <class A>
class Accumulation final : public Traversal {
  using D = typename A::f64;
  using F = typename A::f32;

 public:
  Accumulation(const Frame& f, ThreadState& ts) : f_(f), c_(ts.counters), pipe_(f, ts) {}

  void rasterize(const TriSetup& tri, const BinRect& bin, bool charge_setup) override {
    std::uint64_t setup_ops = 0;
    const Footprint fp = build_footprint<A>(tri, f_, false, setup_ops);
    const int N = f_.table.n_lens();
    const int bx0 = std::max(tri.bx0, bin.x0), bx1 = std::min(tri.bx1, bin.x1);
    const int by0 = std::max(tri.by0, bin.y0), by1 = std::min(tri.by1, bin.y1);
    F X[3], Y[3], cx[3], cy[3];
    float W[3];
    for (int j = 0; j < 3; ++j) {
      X[j] = F(tri.X[j]), Y[j] = F(tri.Y[j]), cx[j] = F(tri.cx[j]), cy[j] = F(tri.cy[j]);
      W[j] = tri.W[j];
    }
    for (int i = 0; i < N; ++i) {
      const float ui = f_.table.lens_u(i), vi = f_.table.lens_v(i);
      float xs[3], ys[3];
      if (!tri.moving) {
        F Xs[3], Ys[3];
        shear_static(X, Y, cx, cy, F(ui), F(vi), Xs, Ys);
        charge<A>(setup_ops, cost::kShear);
        for (int j = 0; j < 3; ++j) xs[j] = raw(Xs[j]), ys[j] = raw(Ys[j]);
        // The pass's pinhole triangle setup (its 2D edge equations), every pass.
        const tiletest::Edges2D e = tiletest::edges_2d<D>(xs, ys, W);
        (void)e;
        charge<A>(setup_ops, cost::kEdges2DSetup);
      }
      int x0 = bx0, x1 = bx1, y0 = by0, y1 = by1;
      if (fp.h_valid) {
        double lx, hx, ly, hy;
        tiletest::box_bounds<D>(fp.lv, fp.n, ui, ui, vi, vi, lx, hx, ly, hy);
        charge<A>(setup_ops, tiletest::box_bounds_cost(fp.lv, fp.n, true));
        tiletest::pixel_range(lx, hx, bx0, bx1, x0, x1);
        tiletest::pixel_range(ly, hy, by0, by1, y0, y1);
      }
      if (x0 >= x1 || y0 >= y1) continue;
      if (tri.moving)
        pipe_.begin(tri);
      else
        pipe_.begin_sheared(tri, xs, ys, 0);
      for (int py = y0; py < y1; ++py)
        for (int px = x0; px < x1; ++px) {
          const PixelSamples ps = f_.table.pixel(px, py);
          pipe_.at_pixel(px, py);
          for (int k = ps.lens_offsets[i]; k < ps.lens_offsets[i + 1]; ++k) pipe_.push(px, py, ps, ps.lens_order[k]);
        }
      pipe_.end_visit();  // a visit = one pass
      pipe_.flush();
    }
    if (charge_setup) {
      c_[Counter::ops_setup] += setup_ops;
      c_[Counter::trav_passes] += static_cast<std::uint64_t>(N);
      if (tri.moving) ++c_[Counter::trav_motion_fallback];
    }
  }

 private:
  const Frame& f_;
  Counters& c_;
  SamplePipeline<A> pipe_;
};

}  // namespace

RAST5D_REGISTER_TRAVERSAL("accumulation",
                          "000 §2.2 accumulation buffering: one pinhole pass per lens position of an "
                          "accumulation table (triangle re-sent and set up every pass), 2D test",
                          true, Accumulation);

}  // namespace rast5d
