// INTERVAL ([Akenine-Möller 2012] §5.2, after Fatahalian et al. 2009): one pass per lens-grid
// cell; in each pass the triangle is bounded over the cell's (u, v) range and only that cell's
// samples of the pixels inside the bounds are inside-tested. No tile test. The per-cell bounds are
// triangle setup. Moving triangles are bounded over both shutter ends (conservative, counted).
#include <algorithm>

#include "setup/footprint.h"
#include "tiletest/box_bounds.h"
#include "tiletest/candidates.h"
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
    if constexpr (!A::counting) {
      if (fused_ && pipe_.order_free()) {
        fused_passes(tri, fp, bx0, bx1, by0, by1, setup_ops, passes);
        pipe_.flush();
        if (charge_setup) {
          c_[Counter::ops_setup] += setup_ops;
          c_[Counter::trav_passes] += passes;
          if (tri.moving) ++c_[Counter::trav_motion_fallback];
        }
        return;
      }
    }
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
              const int k0 = ps.cell_offsets[c], k1 = ps.cell_offsets[c + 1];
              pipe_.push_list(px, py, ps, ps.cell_order + k0, k1 - k0);
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
  // Fast path (SamplePipeline::order_free(): nothing observes the test order): the passes' pixel
  // rectangles and charges as above, then one walk over the pixels of their union, pushing per
  // pixel the samples of every cell whose rectangle holds it (SamplePipeline::push_selected with
  // no cuts). The same samples are tested as by the passes, each once.
  void fused_passes(const TriSetup& tri, const Footprint& fp, int bx0, int bx1, int by0, int by1,
                    std::uint64_t& setup_ops, std::uint64_t& passes) {
    const int G = f_.p.lens_grid;
    int ux0 = bx1, ux1 = bx0, uy0 = by1, uy1 = by0;
    int rx0[64], rx1[64], ry0[64], ry1[64];
    // A cell's x bounds depend only on its u range (its column), its y bounds only on its v range
    // (its row): box_bounds' x and y parts are separate computations, so they are evaluated once
    // per column and row (the same float operations); every pass is still charged its bounds.
    int cx0[8], cx1[8], cy0[8], cy1[8];
    std::uint64_t bounds_cost = 0;
    if (fp.h_valid) {
      bounds_cost = tiletest::box_bounds_cost(fp.lv, fp.n, false);
      for (int k = 0; k < G; ++k) {
        double lx, hx, ly, hy;
        tiletest::box_bounds<D>(fp.lv, fp.n, SampleTable::cell_lo(k, G), SampleTable::cell_hi(k, G),
                                SampleTable::cell_lo(k, G), SampleTable::cell_hi(k, G), lx, hx, ly, hy);
        tiletest::pixel_range(lx, hx, bx0, bx1, cx0[k], cx1[k]);
        tiletest::pixel_range(ly, hy, by0, by1, cy0[k], cy1[k]);
      }
    }
    std::uint64_t cells = 0;
    for (int c = 0; c < G * G; ++c) {
      if (!lens_mask_.test(c)) continue;
      const int ci = c % G, cj = c / G;
      int x0 = bx0, x1 = bx1, y0 = by0, y1 = by1;
      if (fp.h_valid) {
        charge<A>(setup_ops, bounds_cost);
        x0 = cx0[ci], x1 = cx1[ci], y0 = cy0[cj], y1 = cy1[cj];
      }
      ++passes;  // a visit = one lens-cell pass: end_visit() records nothing when order_free()
      rx0[c] = x0, rx1[c] = x1, ry0[c] = y0, ry1[c] = y1;
      if (x0 >= x1 || y0 >= y1) continue;
      cells |= std::uint64_t(1) << c;
      ux0 = std::min(ux0, x0), ux1 = std::max(ux1, x1), uy0 = std::min(uy0, y0), uy1 = std::max(uy1, y1);
    }
    if (!cells) return;
    // Per column (row) the cells whose rectangle spans it: cells start at x0 and end at x1.
    const int W = ux1 - ux0, H = uy1 - uy0;
    const std::size_t need = static_cast<std::size_t>(W + 1 + H + 1 + std::max(W, H) + 1);
    if (spans_.size() < need) spans_.resize(std::max(need, 2 * spans_.size()));
    std::uint64_t* const col = spans_.data();
    std::uint64_t* const row = col + (W + 1);
    std::uint64_t* const end = row + (H + 1);
    std::fill(col, col + need, 0);
    auto spans = [&](std::uint64_t* out, const int* lo, const int* hi, int origin, int len) {
      std::fill(end, end + len + 1, 0);
      for (std::uint64_t m = cells; m; m &= m - 1) {
        const int c = __builtin_ctzll(m);
        out[lo[c] - origin] |= std::uint64_t(1) << c;
        end[hi[c] - origin] |= std::uint64_t(1) << c;
      }
      std::uint64_t cur = 0;
      for (int k = 0; k < len; ++k) cur = (cur & ~end[k]) | out[k], out[k] = cur;
    };
    spans(col, rx0, rx1, ux0, W);
    spans(row, ry0, ry1, uy0, H);
    // A pixel in every cell's rectangle (every cell of the grid active) tests all its samples: the
    // whole-pixel push, without the selection.
    const std::uint64_t every = G * G == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << (G * G)) - 1;
    tiletest::SelectBounds sb;
    for (int py = uy0; py < uy1; ++py) {
      const std::uint64_t r = row[py - uy0];
      if (!r) continue;
      for (int px = ux0; px < ux1; ++px) {
        const std::uint64_t act = r & col[px - ux0];
        if (!act) continue;
        if (act == every) {
          pipe_.push_pixel(px, py, f_.table.pixel(px, py));
          continue;
        }
        sb.set_cells(act);
        pipe_.push_selected(px, py, f_.table.pixel(px, py), sb);
      }
    }
  }

  const Frame& f_;
  Counters& c_;
  SamplePipeline<A> pipe_;
  tiletest::CellMask lens_mask_;
  // Fast path: fused_passes() (grids up to 8 x 8, spp up to 64, SIMD on, float32 sample test, float64
  // tile stage: the box bounds in pipeline.precision.tile are the ordered passes').
  const bool fused_ = SamplePipeline<A>::kFusedSelect && f_.p.simd && f_.table.spp() <= 64 &&
                      f_.p.lens_grid * f_.p.lens_grid <= 64 && f_.p.precision_sample.kind == PrecisionKind::kFloat32 &&
                      f_.p.precision_tile.kind == PrecisionKind::kFloat64;
  std::vector<std::uint64_t> spans_;  // fused_passes(): per pixel column and row, the cells spanning it
};

}  // namespace

RAST5D_REGISTER_TRAVERSAL("interval",
                          "[Akenine-Möller 2012] §5.2 INTERVAL: one pass per lens-grid cell, triangle bounded over the cell",
                          TableKinds::kPoints, PipelineKind::kSample, Interval);

}  // namespace rast5d
