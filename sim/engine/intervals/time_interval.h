// Time intervals t̂ of the 5D pipeline ([Nilsson 2012] §2, Fig. 2): per screen tile and
// time sub-interval, a conservative interval of shutter time for moving triangles, and for
// defocused ones the lens sets of each sub-interval.
//
// Contract (tested in tests/test_intervals.py against the brute-force sample test): every sample
// (x, y, u, v, t) that the exact sample test hits, with (x, y) in a tile and t in sub-interval k,
// has t inside the tile's t̂_k and (u, v) inside the sub-interval's lens sets.
//
// Method (docs/intervals.md):
//  * The shutter [0, 1] is split into S sub-intervals [k/S, (k+1)/S] (S = time_splits). On
//    sub-interval k, with s in [0, 1] the local time, every vertex moves linearly, so the signed
//    distance of a (sheared) vertex to a tile edge line, X'_j(s) - x0 W_j(s), is linear in s
//    (pixel-homogeneous coordinates). "Every vertex outside the edge for every lens point of the
//    lens box" holds on an intersection of half-lines in s: an open interval. While every W_j > 0
//    the triangle's projection is the hull of its projected vertices, so on that interval the
//    triangle misses the tile. t̂_k is the hull of the complement of the union of the four edges'
//    intervals. With defocus the sheared X'_j = X_j + u kx (W_j - F) is linear in u, so the lens
//    box enters through its two corners per axis (the forms at u0 and u1 both must be outside).
//  * W crossing zero: culling is allowed only on the sub-interval's part where every W_j(s) >
//    w_eps (itself an open interval of s); elsewhere the tile keeps the time.
//  * 5D lens sets: the [Akenine-Möller 2012] h_i lines over the six vertices at the sub-interval's ends (a linearly
//    moving point's projection is monotonic in t, so they bound the sub-interval).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/arith.h"
#include "core/costs.h"
#include "core/counters.h"
#include "intervals/clip.h"
#include "core/triangle.h"
#include "tiletest/halfspace_lens.h"
#include "tiletest/lens_vertex.h"

namespace rast5d::iv {

inline constexpr int kMaxSplits = 16;  // time sub-intervals per shutter (time_splits)

// {s : g(s) < 0} for the linear form g(s) = g0 + s (g1 - g0), s in R, as an open interval,
// intersected into (lo, hi). Cost: cost::kFormCull (fixed: both comparisons and the root always run).
template <class D>
inline void form_cull(D g0, D g1, D& lo, D& hi) {
  const D root = g0 * rcp(g0 - g1);
  const bool n0 = g0 < D(0.0);
  const bool n1 = g1 < D(0.0);
  // both negative: all s; neither: none; only at s=0: s < root; only at s=1: s > root.
  const D a = n0 ? D(-kInfD) : (n1 ? root : D(kInfD));
  const D b = n0 ? (n1 ? D(kInfD) : root) : (n1 ? D(kInfD) : D(-kInfD));
  lo = vmax(lo, a);
  hi = vmin(hi, b);
}

// One time sub-interval of a moving triangle (tile independent).
struct SubInterval {
  double ta = 0, tb = 1;
  double P[2][3][3];        // vertices (X, Y, W) at ta (P[0]) and tb (P[1])
  double cwx[2][3], cwy[2][3];  // shear slopes kx (W - F), ky (W - F) per end and vertex (5D)
  double wlo = -kInfD, whi = kInfD;  // local s where every W_j > w_eps (culling allowed)
  bool lens_ok = false;     // 5D: every end vertex has W > w_eps: h_i lines valid
  int n_lv = 0;
  tiletest::LensVertex lv[6];
};

struct MotionSetup {
  int S = 1;
  bool lens = false;  // 5D: lens sets and lens-box time intervals
  SubInterval sub[kMaxSplits];
};

// Build the sub-intervals of a moving triangle. ops: setup operations (cost::kSubSetup3D/5D per
// sub-interval, plus the lens vertices of 5D).
template <class A>
inline void motion_setup(const TriSetup& tri, const FrameConst& fc, int S, MotionSetup& ms, std::uint64_t& ops) {
  using D = typename A::f64;
  ms.S = S;
  ms.lens = tri.defocused;
  const double w_eps = 0.5 * fc.near_d;
  const D kx(fc.kx_d), ky(fc.ky_d), negF(-fc.focus_d), eps(w_eps);
  for (int k = 0; k < S; ++k) {
    SubInterval& si = ms.sub[k];
    si.ta = static_cast<double>(k) / S;
    si.tb = static_cast<double>(k + 1) / S;
    D lo(-kInfD), hi(kInfD);
    for (int e = 0; e < 2; ++e) {
      const D t(e ? si.tb : si.ta);
      for (int j = 0; j < 3; ++j) {
        const D X = madd(t, D(static_cast<double>(tri.dX[j])), D(static_cast<double>(tri.X[j])));
        const D Y = madd(t, D(static_cast<double>(tri.dY[j])), D(static_cast<double>(tri.Y[j])));
        const D W = madd(t, D(static_cast<double>(tri.dW[j])), D(static_cast<double>(tri.W[j])));
        si.P[e][j][0] = raw(X), si.P[e][j][1] = raw(Y), si.P[e][j][2] = raw(W);
        if (ms.lens) {
          si.cwx[e][j] = raw(madd(kx, W, kx * negF));
          si.cwy[e][j] = raw(madd(ky, W, ky * negF));
        } else {
          si.cwx[e][j] = si.cwy[e][j] = 0.0;
        }
      }
    }
    // Where is every W_j > eps? {s : eps - W_j(s) < 0} per vertex, intersected.
    for (int j = 0; j < 3; ++j) form_cull(eps - D(si.P[0][j][2]), eps - D(si.P[1][j][2]), lo, hi);
    si.wlo = raw(lo), si.whi = raw(hi);
    charge<A>(ops, ms.lens ? cost::kSubSetup5D : cost::kSubSetup3D);
    si.lens_ok = false;
    si.n_lv = 0;
    if (ms.lens) {
      bool ok = true;
      for (int e = 0; e < 2; ++e)
        for (int j = 0; j < 3; ++j) ok &= si.P[e][j][2] > w_eps;
      si.lens_ok = ok;
      if (ok)
        for (int e = 0; e < 2; ++e)
          for (int j = 0; j < 3; ++j) {
            si.lv[si.n_lv] = tiletest::lens_vertex(D(si.P[e][j][0]), D(si.P[e][j][1]), D(si.P[e][j][2]), negF, kx, ky);
            charge<A>(ops, tiletest::lens_vertex_cost(si.lv[si.n_lv]));
            ++si.n_lv;
          }
    }
  }
}

// The time interval of sub-interval si against the (expanded) tile [x0, x1] x [y0, y1] for lens
// points in [u0, u1] x [v0, v1] (3D: lens = false, the box is ignored). Returns false if empty;
// [tlo, thi] is in global time, clipped to the clip box. Cost: cost::kTimeInterval3D / 5D.
template <class A>
inline bool time_interval(const SubInterval& si, bool lens, double x0, double x1, double y0, double y1,
                          double u0, double u1, double v0, double v1, const ClipBox& clip, double& tlo,
                          double& thi, std::uint64_t& ops) {
  using D = typename A::f64;
  // Sheared coordinates per end e, vertex j and lens corner c (3D: c = 0 only, no shear).
  D Xs[2][3][2], Ys[2][3][2], W[2][3];
  const int nc = lens ? 2 : 1;
  for (int e = 0; e < 2; ++e)
    for (int j = 0; j < 3; ++j) {
      W[e][j] = D(si.P[e][j][2]);
      for (int c = 0; c < nc; ++c) {
        if (lens) {
          Xs[e][j][c] = madd(D(c ? u1 : u0), D(si.cwx[e][j]), D(si.P[e][j][0]));
          Ys[e][j][c] = madd(D(c ? v1 : v0), D(si.cwy[e][j]), D(si.P[e][j][1]));
        } else {
          Xs[e][j][c] = D(si.P[e][j][0]);
          Ys[e][j][c] = D(si.P[e][j][1]);
        }
      }
    }
  // Culled open interval of s per edge: 0 = left of x0, 1 = right of x1, 2 = above y0, 3 = below y1.
  D lo[4], hi[4];
  const double edge_pos[4] = {x0, x1, y0, y1};
  for (int ed = 0; ed < 4; ++ed) {
    lo[ed] = D(-kInfD), hi[ed] = D(kInfD);
    const bool yaxis = ed >= 2;
    const bool high = ed & 1;
    const D e(edge_pos[ed]);
    for (int j = 0; j < 3; ++j)
      for (int c = 0; c < nc; ++c) {
        D g[2];
        for (int end = 0; end < 2; ++end) {
          const D a = yaxis ? Ys[end][j][c] : Xs[end][j][c];
          // outside low edge: a - e W < 0; outside high edge: e W - a < 0
          g[end] = high ? madd(e, W[end][j], -a) : madd(-e, W[end][j], a);
        }
        form_cull(g[0], g[1], lo[ed], hi[ed]);
      }
    // Only where every W_j > eps.
    lo[ed] = vmax(lo[ed], D(si.wlo));
    hi[ed] = vmin(hi[ed], D(si.whi));
  }
  // Hull of [0, 1] minus the union of the open intervals (lo, hi): advance each end past every
  // interval that contains it (4 passes suffice for 4 intervals). Fixed cost.
  D slo(0.0), shi(1.0);
  for (int pass = 0; pass < 4; ++pass)
    for (int ed = 0; ed < 4; ++ed) {
      const bool a = lo[ed] < slo;
      const bool b = slo < hi[ed];
      slo = (a && b) ? hi[ed] : slo;
    }
  for (int pass = 0; pass < 4; ++pass)
    for (int ed = 0; ed < 4; ++ed) {
      const bool a = lo[ed] < shi;
      const bool b = shi < hi[ed];
      shi = (a && b) ? lo[ed] : shi;
    }
  const D len(si.tb - si.ta), ta(si.ta);
  D t0 = madd(slo, len, ta), t1 = madd(shi, len, ta);
  t0 = vmax(t0, D(clip.t_lo));
  t1 = vmin(t1, D(clip.t_hi));
  const bool empty = t1 < t0;
  charge<A>(ops, lens ? cost::kTimeInterval5D : cost::kTimeInterval3D);
  // Round outwards by more than the float rounding of the sample's t and of s -> t.
  tlo = raw(t0) - 0x1p-20;
  thi = raw(t1) + 0x1p-20;
  return !empty;
}

// ---- all intervals of one tile for a moving triangle ------------------------------------------

struct TileIntervals {
  int n_active = 0;
  bool active[kMaxSplits];
  float tlo[kMaxSplits], thi[kMaxSplits];  // t̂_k, rounded outwards to float
  tiletest::AxisSet sx[kMaxSplits], sy[kMaxSplits];  // 5D: lens sets of sub-interval k
  // Hulls over the active sub-intervals: (û, v̂, t̂) of the tile.
  double u0 = 1, u1 = -1, v0 = 1, v1 = -1, t0 = 1, t1 = 0;
};

// Per sub-interval: 5D lens sets from the h_i lines of its six end vertices (clipped), then the
// time interval for the hull of those sets. Tile-stage operations go to ops; the per-class
// evaluation counters to c. Returns false when every sub-interval is empty. lens_sets = false
// (tile with halfspace.h off): no h_i lines, t̂ for the whole lens (the clip box still applies).
template <class A>
inline bool motion_tile_intervals(const MotionSetup& ms, const ClipBox& clip, DimClass cls, double x0, double x1,
                                  double y0, double y1, TileIntervals& ti, std::uint64_t& ops, Counters& c,
                                  bool lens_sets = true) {
  ti.n_active = 0;
  ti.u0 = ti.v0 = ti.t0 = kInfD;
  ti.u1 = ti.v1 = ti.t1 = -kInfD;
  const bool is5 = cls == DimClass::k5D;
  for (int k = 0; k < ms.S; ++k) {
    const SubInterval& si = ms.sub[k];
    ti.active[k] = false;
    tiletest::AxisSet& sx = ti.sx[k];
    tiletest::AxisSet& sy = ti.sy[k];
    sx = tiletest::full_axis(), sy = tiletest::full_axis();
    if (ms.lens) {
      ++c[is5 ? Counter::interval_lens_tests_5d : Counter::interval_lens_tests_3d];
      if (si.lens_ok && lens_sets) tiletest::tile_h_sets<A>(si.lv, si.n_lv, x0, x1, y0, y1, sx, sy, ops);  // empty sets: caught below
      if (!clip_lens<A>(clip, sx, sy, ops) || sx.empty || sy.empty) continue;
    }
    const double u0 = ms.lens ? sx.iv_lo[0] : 0.0, u1 = ms.lens ? sx.iv_hi[sx.n_intervals - 1] : 0.0;
    const double v0 = ms.lens ? sy.iv_lo[0] : 0.0, v1 = ms.lens ? sy.iv_hi[sy.n_intervals - 1] : 0.0;
    ++c[is5 ? Counter::interval_time_tests_5d : Counter::interval_time_tests_3d];
    double tlo, thi;
    if (!time_interval<A>(si, ms.lens, x0, x1, y0, y1, u0, u1, v0, v1, clip, tlo, thi, ops)) continue;
    ti.active[k] = true;
    ++ti.n_active;
    ti.tlo[k] = tiletest::round_down_to_float(tlo);
    ti.thi[k] = tiletest::round_up_to_float(thi);
    ti.u0 = std::min(ti.u0, u0), ti.u1 = std::max(ti.u1, u1);
    ti.v0 = std::min(ti.v0, v0), ti.v1 = std::max(ti.v1, v1);
    ti.t0 = std::min(ti.t0, tlo), ti.t1 = std::max(ti.t1, thi);
  }
  c[Counter::interval_sub_active] += static_cast<std::uint64_t>(ti.n_active);
  c[Counter::interval_sub_culled] += static_cast<std::uint64_t>(ms.S - ti.n_active);
  return ti.n_active > 0;
}

}  // namespace rast5d::iv
