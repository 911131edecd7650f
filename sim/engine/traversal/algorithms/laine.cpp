// LAINE ([Akenine-Möller 2012] §6.3; Laine et al. 2011, depth of field only): per tile, the
// axis-aligned lens bounds (our h_i lines, the same "dual-space" bounds); every sample of the
// tile's pixels is tested against them and, if inside, inside-tested. No lens grid and no early out
// at tile level (an empty region still costs each sample its comparisons).
#include <algorithm>
#include <vector>

#include "setup/footprint.h"
#include "tiletest/candidates.h"
#include "traversal/exact_region.h"
#include "tiletest/halfspace_lens.h"
#include "tiletest/precision_4d.h"
#include "traversal/traversal.h"

namespace rast5d {
namespace {

template <class A>
class Laine final : public Traversal {
  using D = typename A::f64;
  using F = typename A::f32;

 public:
  Laine(const Frame& f, ThreadState& ts) : f_(f), c_(ts.counters), pipe_(f, ts) {}

  void rasterize(const TriSetup& tri, const BinRect& bin, bool charge_setup) override {
    std::uint64_t setup_ops = 0;
    const Footprint fp = build_footprint<A>(tri, f_, false, setup_ops);
    if (charge_setup) {
      c_[Counter::ops_setup] += setup_ops;
      if (tri.moving) ++c_[Counter::trav_motion_fallback];
    }
    const RenderParams& p = f_.p;
    const int T = p.tile_size, spp = f_.table.spp();
    const bool use_h = p.halfspace_h && fp.h_valid;
    const bool prec4d = p.precision_tile.kind != PrecisionKind::kFloat64;  // tiletest/precision_4d.h
    if (prec4d && use_h) p4_.setup(p.precision_tile, fp.lv, fp.n, nullptr, false);
    pipe_.begin(tri);
    const int x0 = std::max(tri.bx0, bin.x0), x1 = std::min(tri.bx1, bin.x1);
    const int y0 = std::max(tri.by0, bin.y0), y1 = std::min(tri.by1, bin.y1);
    for (int ty = (y0 / T) * T; ty < y1; ty += T)
      for (int tx = (x0 / T) * T; tx < x1; tx += T) {
        pipe_.at_rect(std::max(tx, x0), std::max(ty, y0), std::min(tx + T, x1), std::min(ty + T, y1));
        ++c_[Counter::tile_visited];
        tiletest::AxisSet sx, sy;
        bool empty = false;
        if (use_h)
          empty = !tile_h_sets<A>(fp, tiletest::expand_lo(tx), tiletest::expand_hi(tx + T), tiletest::expand_lo(ty),
                                  tiletest::expand_hi(ty + T), sx, sy, c_[Counter::ops_tile]);
        if (use_h && prec4d) {  // the decision in pipeline.precision.tile (counted as the float64 form)
          bool ovf;
          empty = !p4_.h_sets(tiletest::expand_lo(tx), tiletest::expand_hi(tx + T), tiletest::expand_lo(ty),
                              tiletest::expand_hi(ty + T), sx, sy, ovf);
          if (ovf) ++c_[Counter::precision_tile4d_overflows];
        }
        ++c_[Counter::tile_accepted];
        const std::uint64_t region_cost =
            empty ? cost::kSampleRegionEmpty : static_cast<std::uint64_t>(sx.n_cmp + sy.n_cmp);
        // Pixels of the tile inside the triangle's bounds (the bounding-box mask).
        for (int py = std::max(ty, y0); py < std::min(ty + T, y1); ++py)
          for (int px = std::max(tx, x0); px < std::min(tx + T, x1); ++px) {
            const PixelSamples ps = f_.table.pixel(px, py);
            pipe_.at_pixel(px, py);
            int n = 0;
            if (!A::counting && !empty) {
              tiletest::select_candidates<false>(spp, ps.u, ps.v, ps.cell, ~std::uint64_t(0), sx, sy, sel_.data());
              n = tiletest::compact_flags(sel_.data(), spp, cand_.data());
            } else {
              for (int s = 0; s < spp; ++s) {
                bool pass;
                if (empty) {
                  // Laine's per-sample test u_min <= u <= u_max, v_min <= v <= v_max against an
                  // empty region (u_min > u_max): cost::kSampleRegionEmpty comparisons that always fail.
                  const F u(ps.u[s]), v(ps.v[s]);
                  pass = (u >= F(1.0f)) & (u <= F(-1.0f)) & (v >= F(1.0f)) & (v <= F(-1.0f));
                } else {
                  pass = region_cost == 0 ||
                         (tiletest::axis_pass(sx, F(ps.u[s])) & tiletest::axis_pass(sy, F(ps.v[s])));
                }
                cand_[n] = s;
                n += pass;
              }
            }
            charge<A>(c_[Counter::ops_sample_region], region_cost * static_cast<std::uint64_t>(spp));
            if (p.count_optimal && fp.n > 0)
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
  tiletest::Tile4DPrecision p4_;  // the h_i sets in pipeline.precision.tile (not float64)
  std::vector<int> cand_ = std::vector<int>(f_.table.spp());  // one pixel's candidates
  std::vector<std::uint8_t> sel_ = std::vector<std::uint8_t>(f_.table.spp() + 8, 0);
};

}  // namespace

RAST5D_REGISTER_TRAVERSAL("laine",
                          "[Laine 2011] as in [Akenine-Möller 2012] §6.3: per-tile axis-aligned lens bounds, every sample "
                          "checked against them, no tile-level early out",
                          TableKinds::kPoints, PipelineKind::kSample, Laine);

}  // namespace rast5d
