// INTERLEAVE and HINTERLEAVE ([Akenine-Möller 2012] §5.3, after Fatahalian et al. 2009 and
// Keller & Heidrich 2001): one pass per discrete lens coordinate of an interleaved sample table.
// Each pass shears the (static) triangle to that lens coordinate, bounds it, and inside-tests with
// the 2D kernel only the samples that use that lens coordinate. HINTERLEAVE adds a standard tile
// vs static-triangle test on 8x8 tiles in each pass. The per-pass shear, bounds and edge setup
// are triangle setup. Moving triangles: bounds over both shutter ends, general sample test, no
// tile test (conservative, counted).
// ACCUMULATION buffering ([Toth 2008] §2.2, §8; Haeberli and Akeley 1990) is the same
// pass structure on an accumulation table (SampleTable.accumulation: every pixel uses the same N
// positions, sample s = pass s): one full pinhole pass per lens position, the triangle re-sent and
// set up as an ordinary pinhole triangle every pass (a static triangle's 2D edge setup charged per
// pass). Its samples tested, images and counts equal INTERLEAVE's on the same table except that setup.
// A moving triangle is a static one within a pass, since the pass has one shutter time too: on a
// table whose every pass has one time in all pixels (SampleTable.accumulation), each pass moves the
// triangle to its time and shears it to its lens position with the 5D kernel's float operations
// (so the 2D test of the placed vertices is bit-identical to the 5D test), sets up its 2D edges and
// bounds its pixels by the projected vertices (the setup box when a vertex is behind the eye).
// On other interleaved tables moving triangles take INTERLEAVE's conservative path.
// What a GPU repeats in every pass after the first is charged too (docs/gpu.md): the triangle is
// re-sent and set up again (accum.resends: the setup unit's triangles), its vertices transformed again
// by the vertex shader (accum.vertex_ops, in ops.setup: cost::gpu::kVertexTransform per vertex and
// shutter end), and each pass's image is added into the accumulation buffer by a full-screen pass
// (accum.buffer_bytes, charged per screen bin at its end: every pixel, whether or not a triangle
// reached it).
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "gpu/costs.h"
#include "setup/footprint.h"
#include "tiletest/box_bounds.h"
#include "tiletest/precision_4d.h"
#include "tiletest/edges_2d.h"
#include "traversal/traversal.h"

namespace rast5d {
namespace {

template <class A, bool kHier, bool kPassSetup = false>
class Interleave final : public Traversal {
  using D = typename A::f64;
  using F = typename A::f32;

 public:
  Interleave(const Frame& f, ThreadState& ts) : f_(f), c_(ts.counters), pipe_(f, ts) {
    if constexpr (kPassSetup) pass_times(f.table);
    // Without per-pixel statistics nothing is done for a pixel without samples of the pass's lens
    // coordinate (at_pixel() is a no-op): the passes visit only the pixels that hold some.
    if (!ts.observers.wants_targets()) lens_rows(f.table);
  }

  void rasterize(const TriSetup& tri, const BinRect& bin, bool charge_setup) override {
    std::uint64_t setup_ops = 0;
    const Footprint fp = build_footprint<A>(tri, f_, false, setup_ops);
    const int N = f_.table.n_lens();
    const int HT = f_.p.hinterleave_tile;
    const int bx0 = std::max(tri.bx0, bin.x0), bx1 = std::min(tri.bx1, bin.x1);
    const int by0 = std::max(tri.by0, bin.y0), by1 = std::min(tri.by1, bin.y1);
    F X[3], Y[3], cx[3], cy[3];
    float W[3];
    for (int j = 0; j < 3; ++j) {
      X[j] = F(tri.X[j]), Y[j] = F(tri.Y[j]), cx[j] = F(tri.cx[j]), cy[j] = F(tri.cy[j]);
      W[j] = tri.W[j];
    }
    const bool per_pass_motion = kPassSetup && tri.moving && !pass_t_.empty() &&
                                 (tri.cls == DimClass::k3D || tri.cls == DimClass::k5D);
    for (int i = 0; i < N; ++i) {
      const float ui = f_.table.lens_u(i), vi = f_.table.lens_v(i);
      if (per_pass_motion) {
        moving_pass(tri, i, bx0, bx1, by0, by1, setup_ops);
        continue;
      }
      float xs[3], ys[3];
      if (!tri.moving) {
        F Xs[3], Ys[3];
        shear_static(X, Y, cx, cy, F(ui), F(vi), Xs, Ys);
        charge<A>(setup_ops, cost::kShear);
        for (int j = 0; j < 3; ++j) xs[j] = raw(Xs[j]), ys[j] = raw(Ys[j]);
      }
      int x0 = bx0, x1 = bx1, y0 = by0, y1 = by1;
      if (fp.h_valid) {
        double lx, hx, ly, hy;
        tiletest::box_bounds<D>(fp.lv, fp.n, ui, ui, vi, vi, lx, hx, ly, hy);
        if (f_.p.precision_tile.kind != PrecisionKind::kFloat64)  // the bounds in pipeline.precision.tile
          c_[Counter::precision_tile4d_overflows] +=
              tiletest::box_bounds_in(f_.p.precision_tile, fp.lv, fp.n, ui, ui, vi, vi, lx, hx, ly, hy);
        charge<A>(setup_ops, tiletest::box_bounds_cost(fp.lv, fp.n, true));
        tiletest::pixel_range(lx, hx, bx0, bx1, x0, x1);
        tiletest::pixel_range(ly, hy, by0, by1, y0, y1);
      }
      tiletest::Edges2D e;
      // per-pass setup, charged whether or not this bin sees the pass; the hardware cost model's
      // affine 2D sample test uses these edges too (sampletest/hardware.h), so INTERLEAVE pays them;
      // accumulation sets up its pinhole triangle every pass
      if ((kPassSetup || kHier || f_.p.cost_model == CostModel::kHardware) && !tri.moving) {
        e = tiletest::edges_2d_in<D>(f_.p.precision_tile, xs, ys, W);
        charge<A>(setup_ops, cost::kEdges2DSetup);
      }
      if (x0 >= x1 || y0 >= y1) continue;
      // One batch per lens coordinate: the pre-sheared vertices change with i.
      if (tri.moving)
        pipe_.begin(tri);
      else
        pipe_.begin_sheared(tri, xs, ys, 0);
      if (kHier && !tri.moving) {
        for (int ty = (y0 / HT) * HT; ty < y1; ty += HT)
          for (int tx = (x0 / HT) * HT; tx < x1; tx += HT) {
            pipe_.at_rect(std::max(tx, x0), std::max(ty, y0), std::min(tx + HT, x1), std::min(ty + HT, y1));
            ++c_[Counter::tile_visited];
            bool overflow;
            const bool out = tiletest::tile_outside_2d_in<D>(e, tiletest::expand_lo(tx), tiletest::expand_hi(tx + HT),
                                                             tiletest::expand_lo(ty), tiletest::expand_hi(ty + HT),
                                                             overflow) ||
                             !e.valid;
            if (overflow) ++c_[Counter::precision_tile_overflows];
            charge<A>(c_[Counter::ops_tile], cost::kTile2D);
            if (out) {
              ++c_[Counter::tile_culled_2d];
              continue;
            }
            ++c_[Counter::tile_accepted];
            pass(i, std::max(tx, x0), std::min(tx + HT, x1), std::max(ty, y0), std::min(ty + HT, y1));
          }
      } else {
        pass(i, x0, x1, y0, y1);
      }
      pipe_.end_visit();  // a visit = one lens-coordinate pass
      pipe_.flush();      // xs / ys are this iteration's
    }
    if (charge_setup) {
      c_[Counter::ops_setup] += setup_ops;
      c_[Counter::trav_passes] += static_cast<std::uint64_t>(N);
      if (tri.moving && !per_pass_motion) ++c_[Counter::trav_motion_fallback];
      if constexpr (kPassSetup) {  // the passes after the first re-send, set up and transform the triangle
        const std::uint64_t resends = N > 1 ? static_cast<std::uint64_t>(N - 1) : 0;
        const std::uint64_t vertex_ops = resends * 3 * (tri.moving ? 2 : 1) * cost::gpu::kVertexTransform;
        c_[Counter::accum_resends] += resends;
        c_[Counter::accum_vertex_ops] += vertex_ops;
        c_[Counter::ops_setup] += vertex_ops;
      }
    }
  }

  // Accumulation: every pass after the first reads and writes the accumulation buffer over the whole
  // screen (a full-screen pass), so every pixel of the bin costs 2 x kAccumPixelBytes per such pass.
  void end_bin(const BinRect& bin) override {
    if constexpr (kPassSetup) {
      const int N = f_.table.n_lens();
      const std::uint64_t pixels = static_cast<std::uint64_t>(std::max(bin.x1 - bin.x0, 0)) *
                                   static_cast<std::uint64_t>(std::max(bin.y1 - bin.y0, 0));
      if (N > 1) c_[Counter::accum_buffer_bytes] += pixels * 2 * cost::gpu::kAccumPixelBytes * static_cast<std::uint64_t>(N - 1);
    }
  }

 private:
  // The shutter time of every pass when it is the same in every pixel of the table (accumulation
  // tables); else pass_t_ stays empty.
  void pass_times(const SampleTable& table) {
    const int N = table.n_lens(), P = table.period(), spp = table.spp();
    if (N <= 0) return;
    std::vector<float> t(static_cast<std::size_t>(N), 0.0f);
    std::vector<char> seen(static_cast<std::size_t>(N), 0);
    for (int py = 0; py < P; ++py)
      for (int px = 0; px < P; ++px) {
        const PixelSamples ps = table.pixel(px, py);
        for (int s = 0; s < spp; ++s) {
          const int i = ps.lens_index[s];
          if (!seen[i]) seen[i] = 1, t[i] = ps.t[s];
          else if (t[i] != ps.t[s]) return;
        }
      }
    pass_t_ = std::move(t);
  }

  // One pass of a moving triangle: the pinhole triangle at the pass's time and lens position.
  void moving_pass(const TriSetup& tri, int i, int bx0, int bx1, int by0, int by1, std::uint64_t& setup_ops) {
    F X0[3], Y0[3], W0[3], dX[3], dY[3], dW[3], Xt[3], Yt[3], Wt[3], Xs[3], Ys[3];
    for (int j = 0; j < 3; ++j) {
      X0[j] = F(tri.X[j]), Y0[j] = F(tri.Y[j]), W0[j] = F(tri.W[j]);
      dX[j] = F(tri.dX[j]), dY[j] = F(tri.dY[j]), dW[j] = F(tri.dW[j]);
    }
    lerp_vertices(X0, Y0, W0, dX, dY, dW, F(pass_t_[i]), Xt, Yt, Wt);
    charge<A>(setup_ops, cost::kLerp);
    if (tri.cls == DimClass::k5D) {
      shear_moving(Xt, Yt, Wt, F(f_.fc.kx), F(f_.fc.neg_kx_f), F(f_.fc.ky), F(f_.fc.neg_ky_f),
                   F(f_.table.lens_u(i)), F(f_.table.lens_v(i)), Xs, Ys);
      charge<A>(setup_ops, cost::kShearMoving);
    } else {
      for (int j = 0; j < 3; ++j) Xs[j] = Xt[j], Ys[j] = Yt[j];
    }
    // The pass's pinhole triangle: the placed vertices (the backend reads W through it).
    pass_tri_ = tri;
    for (int j = 0; j < 3; ++j) {
      pass_xs_[j] = raw(Xs[j]), pass_ys_[j] = raw(Ys[j]);
      pass_tri_.W[j] = raw(Wt[j]);
    }
    tiletest::edges_2d<D>(pass_xs_, pass_ys_, pass_tri_.W);
    charge<A>(setup_ops, cost::kEdges2DSetup);
    int x0 = bx0, x1 = bx1, y0 = by0, y1 = by1;
    bool front = true;
    for (int j = 0; j < 3; ++j) front = (D(pass_tri_.W[j]) > D(0.0)) && front;
    charge<A>(setup_ops, cost::kFrontCheck);
    if (front) {  // the projected vertices' box (tiletest::pixel_range widens it for rounding)
      D lx(tiletest::kInf), hx(-tiletest::kInf), ly(tiletest::kInf), hy(-tiletest::kInf);
      for (int j = 0; j < 3; ++j) {
        const D r = rcp(D(pass_tri_.W[j]));
        const D x = D(pass_xs_[j]) * r, y = D(pass_ys_[j]) * r;
        lx = vmin(lx, x), hx = vmax(hx, x), ly = vmin(ly, y), hy = vmax(hy, y);
      }
      charge<A>(setup_ops, 3 * cost::kBoundsPoint);
      tiletest::pixel_range(raw(lx), raw(hx), bx0, bx1, x0, x1);
      tiletest::pixel_range(raw(ly), raw(hy), by0, by1, y0, y1);
    }
    if (x0 >= x1 || y0 >= y1) return;
    pipe_.begin_sheared(pass_tri_, pass_xs_, pass_ys_, 0);
    pass(i, x0, x1, y0, y1);
    pipe_.end_visit();  // a visit = one pass
    pipe_.flush();      // pass_tri_ and the vertices are this pass's
  }

  // The table's samples by lens coordinate (period P <= 64): bit mx of rows_[i * P + my] is set when
  // pixel (mx, my) holds a sample of lens coordinate i; that pixel's samples of i are entries
  // loff_[i * P * P + my * P + mx] .. loff_[... + 1] of ex_ / ey_ / es_ ((x, y) in the pixel and the
  // canonical index), in the pixel's lens_order.
  void lens_rows(const SampleTable& table) {
    const int N = table.n_lens(), P = table.period(), spp = table.spp();
    if (N <= 0 || P > 64) return;
    const std::size_t PP = static_cast<std::size_t>(P) * P;
    rows_.assign(static_cast<std::size_t>(N) * P, 0);
    loff_.assign(static_cast<std::size_t>(N) * PP + 1, 0);
    for (int my = 0; my < P; ++my)
      for (int mx = 0; mx < P; ++mx) {
        const PixelSamples ps = table.pixel(mx, my);
        for (int s = 0; s < spp; ++s) {
          const std::size_t i = static_cast<std::size_t>(ps.lens_index[s]);
          rows_[i * P + my] |= std::uint64_t(1) << mx;
          ++loff_[i * PP + static_cast<std::size_t>(my) * P + mx + 1];
        }
      }
    for (std::size_t k = 1; k < loff_.size(); ++k) loff_[k] += loff_[k - 1];
    ex_.resize(PP * spp), ey_.resize(PP * spp), es_.resize(PP * spp);
    for (int my = 0; my < P; ++my)
      for (int mx = 0; mx < P; ++mx) {
        const PixelSamples ps = table.pixel(mx, my);
        const std::size_t pi = static_cast<std::size_t>(my) * P + mx;
        for (int k = 0; k < spp; ++k) {
          const int s = ps.lens_order[k], i = ps.lens_index[s];
          const std::size_t e = static_cast<std::size_t>(loff_[i * PP + pi] + (k - ps.lens_offsets[i]));
          ex_[e] = ps.x[s], ey_[e] = ps.y[s], es_[e] = s;
        }
      }
    period_ = P;
    pow2_mask_ = (P & (P - 1)) == 0 ? P - 1 : -1;
  }

  // Inside-test the samples of lens coordinate i in the pixel rectangle, row by row (pixels in
  // increasing x, each pixel's samples in lens_order).
  void pass(int i, int x0, int x1, int y0, int y1) {
    if (period_ > 0) {  // the same pixels and samples in the same order, skipping the pixels without any
      const int P = period_;
      const std::uint64_t* rows = rows_.data() + static_cast<std::size_t>(i) * P;
      const std::int32_t* loff = loff_.data() + static_cast<std::size_t>(i) * P * P;
      // coordinate mod P: a mask for a power-of-two period (no division per pass and row)
      auto wrap = [P, m = pow2_mask_](int a) { return m >= 0 ? (a & m) : ((a % P) + P) % P; };
      const int bx_first = x0 - wrap(x0);
      for (int py = y0; py < y1; ++py) {
        const int my = wrap(py);
        const std::uint64_t r = rows[my];
        if (!r) continue;
        for (int bx = bx_first; bx < x1; bx += P) {
          const int lo = std::max(x0 - bx, 0), hi = std::min(x1 - bx, P);
          std::uint64_t m = r & (hi >= 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << hi) - 1) & ~((std::uint64_t(1) << lo) - 1);
          for (; m; m &= m - 1) {
            const int mx = __builtin_ctzll(m);
            const int pi = my * P + mx;
            for (int e = loff[pi]; e < loff[pi + 1]; ++e) pipe_.push_xy(bx + mx, py, ex_[e], ey_[e], es_[e]);
          }
        }
      }
      return;
    }
    for (int py = y0; py < y1; ++py)
      for (int px = x0; px < x1; ++px) {
        const PixelSamples ps = f_.table.pixel(px, py);
        pipe_.at_pixel(px, py);
        for (int k = ps.lens_offsets[i]; k < ps.lens_offsets[i + 1]; ++k) pipe_.push(px, py, ps, ps.lens_order[k]);
      }
  }

  const Frame& f_;
  Counters& c_;
  SamplePipeline<A> pipe_;
  // lens_rows(); empty with per-pixel statistics or a period above 64
  std::vector<std::uint64_t> rows_;
  std::vector<std::int32_t> loff_, es_;
  std::vector<float> ex_, ey_;
  int period_ = 0;      // the table's period when rows_ is set, else 0
  int pow2_mask_ = -1;  // period_ - 1 when it is a power of two, else -1
  std::vector<float> pass_t_;  // accumulation: each pass's shutter time (empty: not one per pass)
  TriSetup pass_tri_;
  float pass_xs_[3], pass_ys_[3];
};

template <class A>
using InterleaveFlat = Interleave<A, false>;
template <class A>
using InterleaveHier = Interleave<A, true>;
template <class A>
using Accumulation = Interleave<A, false, true>;

}  // namespace

RAST5D_REGISTER_TRAVERSAL("interleave",
                          "[Akenine-Möller 2012] §5.3 INTERLEAVE: one pass per discrete lens coordinate, 2D test of that "
                          "coordinate's samples",
                          TableKinds::kInterleaved, PipelineKind::kSample, InterleaveFlat);
RAST5D_REGISTER_TRAVERSAL("hinterleave",
                          "[Akenine-Möller 2012] §5.3 HINTERLEAVE: INTERLEAVE plus an 8x8 tile vs static-triangle test per pass",
                          TableKinds::kInterleaved, PipelineKind::kSample, InterleaveHier);
RAST5D_REGISTER_TRAVERSAL("accumulation",
                          "[Toth 2008] §2.2 accumulation buffering: one pinhole pass per lens position of an "
                          "accumulation table (triangle re-sent and set up every pass), 2D test",
                          TableKinds::kInterleaved, PipelineKind::kSample, Accumulation);

}  // namespace rast5d
