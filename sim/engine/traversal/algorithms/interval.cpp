// INTERVAL (001_3248aaf17c219d5e.txt §5.2, after Fatahalian et al. 2009): one pass per lens-grid
// cell; in each pass the triangle is bounded over the cell's (u, v) range and only that cell's
// samples of the pixels inside the bounds are inside-tested. No tile test. The per-cell bounds are
// triangle setup. Moving triangles are bounded over both shutter ends (conservative, counted).
#include <algorithm>

#include "setup/footprint.h"
#include "tiletest/box_bounds.h"
#include "tiletest/precision_4d.h"
#include "tiletest/lens_shape.h"
#include "traversal/traversal.h"

namespace rast5d {
namespace {

template <class A>
class Interval final : public Traversal {
  using D = typename A::f64;

 public:
  Interval(const Frame& f, ThreadState& ts)
      : f_(f), c_(ts.counters), pipe_(f, ts), lens_mask_(tiletest::lens_cells(f.p.lens_shape, f.p.lens_grid)) {}

  void rasterize(const TriSetup& tri, const BinRect& bin, bool charge_setup) override {
    std::uint64_t setup_ops = 0;
    const Footprint fp = build_footprint<A>(tri, f_, false, setup_ops);
    const int G = f_.p.lens_grid, T = f_.p.tile_size;
    const int bx0 = std::max(tri.bx0, bin.x0), bx1 = std::min(tri.bx1, bin.x1);
    const int by0 = std::max(tri.by0, bin.y0), by1 = std::min(tri.by1, bin.y1);
    std::uint64_t passes = 0;
    pipe_.begin(tri);
    for (int c = 0; c < G * G; ++c) {
      if (!lens_mask_.test(c)) continue;
      const int ci = c % G, cj = c / G;
      int x0 = bx0, x1 = bx1, y0 = by0, y1 = by1;
      if (fp.h_valid) {
        double lx, hx, ly, hy;
        tiletest::box_bounds<D>(fp.lv, fp.n, SampleTable::cell_lo(ci, G), SampleTable::cell_hi(ci, G),
                                SampleTable::cell_lo(cj, G), SampleTable::cell_hi(cj, G), lx, hx, ly, hy);
        if (f_.p.precision_tile.kind != PrecisionKind::kFloat64)  // the bounds in pipeline.precision.tile
          c_[Counter::precision_tile4d_overflows] += tiletest::box_bounds_in(
              f_.p.precision_tile, fp.lv, fp.n, SampleTable::cell_lo(ci, G), SampleTable::cell_hi(ci, G),
              SampleTable::cell_lo(cj, G), SampleTable::cell_hi(cj, G), lx, hx, ly, hy);
        charge<A>(setup_ops, tiletest::box_bounds_cost(fp.lv, fp.n, false));
        tiletest::pixel_range(lx, hx, bx0, bx1, x0, x1);
        tiletest::pixel_range(ly, hy, by0, by1, y0, y1);
      }
      ++passes;
      // Pixels of the pass in tile order (the traversal order a cache model would see).
      for (int ty = (y0 / T) * T; ty < y1; ty += T)
        for (int tx = (x0 / T) * T; tx < x1; tx += T)
          for (int py = std::max(ty, y0); py < std::min(ty + T, y1); ++py)
            for (int px = std::max(tx, x0); px < std::min(tx + T, x1); ++px) {
              const PixelSamples ps = f_.table.pixel(px, py);
              pipe_.at_pixel(px, py);
              for (int k = ps.cell_offsets[c]; k < ps.cell_offsets[c + 1]; ++k)
                pipe_.push(px, py, ps, ps.cell_order[k]);
            }
      pipe_.end_visit();  // a visit = one lens-cell pass
    }
    pipe_.flush();
    if (charge_setup) {
      c_[Counter::ops_setup] += setup_ops;
      c_[Counter::trav_passes] += passes;
      if (tri.moving) ++c_[Counter::trav_motion_fallback];
    }
  }

 private:
  const Frame& f_;
  Counters& c_;
  SamplePipeline<A> pipe_;
  tiletest::CellMask lens_mask_;
};

}  // namespace

RAST5D_REGISTER_TRAVERSAL("interval",
                          "001 §5.2 INTERVAL: one pass per lens-grid cell, triangle bounded over the cell",
                          false, Interval);

}  // namespace rast5d
