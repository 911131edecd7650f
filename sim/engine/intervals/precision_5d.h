// The motion tile tests in a chosen arithmetic (pipeline.precision.tile: float32 or fixed point;
// docs/precision.md, docs/tile_tests.md "Precision"): the time intervals t̂ and the 5D lens sets of
// `motion_test: intervals` (intervals/time_interval.h; TILE's moving triangles and LAINE5D) and the H5
// planes (intervals/halfspace_5d.h). The float64 kernels stay the render's counted form (precision changes
// which (lens, time) regions are culled, not what a test costs); each *_in function below returns the
// decision of the datapath in the format, conservative by construction, with the arithmetic of
// precision_4d.h (PVal: a value of the format and a bound of its distance to the exact value; Arith4D):
//
//  * 5D lens sets: the h_i lines over the six end vertices of a sub-interval, precision_4d.h's h_sets_in on
//    their lens vertices (a, b snapped in fixed point: a linearly moving vertex's projection lies on the
//    segment between its projections at the sub-interval's ends, so the snapped segment stays within
//    2^-frac_bits px of the exact one, inside the 2^(1 - frac_bits) px tile widening).
//  * t̂: per vertex j the homogeneous coordinates (X, Y, W) and the shear slopes kx (W - F), ky (W - F) at
//    the sub-interval's ends, scaled by the positive factor 1 / max(|W_j(0)|, |W_j(1)|) (every form
//    g = X' - e W of a vertex is homogeneous in them: its sign and its root in s do not change; the scaled
//    X is in pixels at the farther end), are the datapath's inputs, rounded to the format WITH their
//    rounding carried (a homogeneous coordinate's snapping is not bounded in pixels: X / W moves by
//    2^-frac_bits / W). Per tile edge e (snapped outward), vertex and lens-box corner, g(s) = X'(s) - e W(s)
//    is linear in s; with g0, g1 the format's values at the ends and e0, e1 their bounds, every admissible
//    g is below the upper line (1 - s)(g0 + e0) + s (g1 + e1) on s in [0, 1], so the set where the upper
//    line is negative (its root rounded inward onto the register grid: fixed 2^-2 frac_bits, float32
//    binary32) is culled for every admissible g: the culled intervals only shrink. The same holds for
//    "every W_j > w_eps" (where culling is allowed), so t̂_k (the hull of the rest) only grows; its ends
//    round outward to the format, then (as float64) by 2^-20 and to binary32.
//  * H5: the per-sub-interval quadratics f0, f1 - f0, f2 of the seven H_j constants (halfspace_5d.h) are
//    set up in float64 on the triangle scaled by 1 / max W (degree 2 in the homogeneous coordinates and F:
//    the signs do not change) and rounded to the format with their rounding carried; per (tile, t̂_k) the
//    constants at both ends of t̂_k, the corner lines A u + B v + C and the remainder ρ_c are the format's
//    with running bounds; a lens cell is culled by an edge only where sigma (A u + B v + C) + ρ_c plus the
//    bounds is negative over the cell at both ends of t̂_k and at all four tile corners (the AND over the
//    corners is what the support corner of the float64 form selects). The orientation sigma, the
//    sub-interval's usability (every vertex in front, one orientation) and the selective oracle are the
//    float64 set-up's decisions, as the lens vertices are.
//  * Overflow: a fixed-point value reaching 2^int_bits sets `overflow` (counted per tile in
//    precision.tile5d_overflows); `max_abs` records the largest register (the fewest int_bits n satisfy
//    max_abs < 2^n), for t̂ with the lens sets (ar) and for H5 (ar_h5) apart.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "intervals/clip.h"
#include "intervals/time_interval.h"
#include "intervals/halfspace_5d.h"
#include "tiletest/precision_4d.h"

namespace rast5d::tiletest {

// A set-up value rounded into the format with its rounding carried (plus rel relative error of the
// float64 value itself); overflow recorded.
inline PVal carried_in(Arith4D& ar, double x, double rel = 0x1p-52) {
  if (!ar.fixed() && !(std::fabs(x) < 0x1p127)) return {x, kInf};  // beyond binary32: no bound (culls nothing)
  PVal r = ar.rounded(x);
  r.e += rel * std::fabs(x);
  return r;
}

// x rounded down / up onto the format (fixed: the register grid; float32: binary32), after a relative
// slack for the double it was computed in; infinities stay.
inline double round_dn_in(const Arith4D& ar, double x) {
  if (!std::isfinite(x)) return x;
  x -= 0x1p-50 * std::fabs(x);
  if (ar.fixed()) return std::floor(x / ar.grid) * ar.grid;
  return static_cast<double>(round_down_to_float(x));
}
inline double round_up_in(const Arith4D& ar, double x) {
  if (!std::isfinite(x)) return x;
  x += 0x1p-50 * std::fabs(x);
  if (ar.fixed()) return std::ceil(x / ar.grid) * ar.grid;
  return static_cast<double>(round_up_to_float(x));
}

// time_interval.h form_cull in the format: the open set of s in [0, 1] where every admissible linear g
// with g(0) in g0, g(1) in g1 is negative (the upper line's negative part), intersected into (lo, hi).
inline void form_cull_in(const Arith4D& ar, PVal g0, PVal g1, double& lo, double& hi) {
  const double h0 = upper(g0), h1 = upper(g1);
  double a = kInf, b = -kInf;  // none
  if (h0 < 0.0 && h1 < 0.0) {
    a = -kInf, b = kInf;
  } else if (h0 < 0.0 || h1 < 0.0) {
    const double root = h0 / (h0 - h1);  // in (0, 1]
    if (root == root) {
      if (h0 < 0.0)
        a = -kInf, b = round_dn_in(ar, root);  // s < root
      else
        a = round_up_in(ar, root), b = kInf;   // s > root
    }
  }
  lo = std::max(lo, a);
  hi = std::min(hi, b);
}

// One sub-interval of a moving triangle in the format.
struct SubIntervalIn {
  PVal P[2][3][3];              // scaled (X, Y, W) per end and vertex
  PVal cwx[2][3], cwy[2][3];    // scaled shear slopes
  double wlo = kInf, whi = -kInf;  // local s where every W_j > w_eps surely (culling allowed)
  int n_lv = 0;
  LensVertexIn lv[6];           // 5D: the lens vertices of the six end vertices (lens_ok)
  // H5 (usable sub-intervals): f0, f1 - f0, f2 per edge and field, scaled by 1 / max W^2
  PVal f0[3][kH5Fields], g[3][kH5Fields], f2[3][kH5Fields];
};

// time_interval.h time_interval in the format. Returns false if empty.
inline bool time_interval_in(Arith4D& ar, const SubIntervalIn& si, double ta, double tb, bool lens, double x0,
                             double x1, double y0, double y1, double u0, double u1, double v0, double v1,
                             const iv::ClipBox& clip, double& tlo, double& thi) {
  const PVal E[4] = {ar.edge_lo(x0), ar.edge_hi(x1), ar.edge_lo(y0), ar.edge_hi(y1)};
  const PVal U[2] = {ar.constant(u0), ar.constant(u1)}, V[2] = {ar.constant(v0), ar.constant(v1)};
  const int nc = lens ? 2 : 1;
  double lo[4], hi[4];
  for (int ed = 0; ed < 4; ++ed) {
    lo[ed] = -kInf, hi[ed] = kInf;
    const bool yaxis = ed >= 2, high = ed & 1;
    for (int j = 0; j < 3; ++j)
      for (int c = 0; c < nc; ++c) {
        PVal g[2];
        for (int end = 0; end < 2; ++end) {
          PVal a = si.P[end][j][yaxis ? 1 : 0];
          if (lens) a = yaxis ? ar.madd(V[c], si.cwy[end][j], a) : ar.madd(U[c], si.cwx[end][j], a);
          const PVal eW = ar.mul(E[ed], si.P[end][j][2]);
          g[end] = high ? ar.sub(eW, a) : ar.sub(a, eW);
        }
        form_cull_in(ar, g[0], g[1], lo[ed], hi[ed]);
      }
    lo[ed] = std::max(lo[ed], si.wlo);
    hi[ed] = std::min(hi[ed], si.whi);
  }
  double slo = 0.0, shi = 1.0;  // hull of [0, 1] minus the union of the open intervals
  for (int pass = 0; pass < 4; ++pass)
    for (int ed = 0; ed < 4; ++ed)
      if (lo[ed] < slo && slo < hi[ed]) slo = hi[ed];
  for (int pass = 0; pass < 4; ++pass)
    for (int ed = 0; ed < 4; ++ed)
      if (lo[ed] < shi && shi < hi[ed]) shi = lo[ed];
  double t0 = round_dn_in(ar, ta + slo * (tb - ta)), t1 = round_up_in(ar, ta + shi * (tb - ta));
  if (!(t0 == t0)) t0 = ta;  // undefined (never expected): keep the sub-interval's start
  if (!(t1 == t1)) t1 = tb;
  t0 = std::max(t0, clip.t_lo);
  t1 = std::min(t1, clip.t_hi);
  tlo = t0 - 0x1p-20;
  thi = t1 + 0x1p-20;
  return !(t1 < t0);
}

// The H5 cells of sub-interval k in the format (halfspace_5d.h h5_culled_cells; header).
inline CellMask h5_cells_in(Arith4D& ar, const SubIntervalIn& si, const SubH5& s, bool lens, int S, int k,
                            double x0, double x1, double y0, double y1, double t_lo, double t_hi, int G, int i0,
                            int i1, int j0, int j1) {
  CellMask culled;
  const double sl = t_lo * S - k, sh = t_hi * S - k;
  const double ds = sh - sl;
  const double rq = ds * ds * (0.25 * (1.0 + 0x1p-20));
  const PVal sv[2] = {ar.constant(sl), ar.constant(sh)};
  const PVal sm[2] = {ar.constant(sl - 1.0), ar.constant(sh - 1.0)};
  const PVal X[2] = {ar.edge_lo(x0), ar.edge_hi(x1)}, Y[2] = {ar.edge_lo(y0), ar.edge_hi(y1)};
  const double sigma = s.sigma, step = 2.0 / G;
  const int m0 = lens ? 0 : 4;
  for (int e = 0; e < 3; ++e) {
    if (!s.edges[e].active) continue;
    PVal f[2][kH5Fields];
    for (int end = 0; end < 2; ++end)
      for (int m = m0; m < kH5Fields; ++m)
        f[end][m] = ar.add(ar.mul(sv[end], ar.add(ar.mul(sm[end], si.f2[e][m]), si.g[e][m])), si.f0[e][m]);
    CellMask edge;
    edge.set();
    bool edge_culls = true;
    for (int c = 0; c < 4 && edge_culls; ++c) {
      const PVal xc = X[c & 1], yc = Y[c >> 1];
      const PVal C2 = ar.add(ar.add(ar.mul(si.f2[e][4], xc), ar.mul(si.f2[e][5], yc)), si.f2[e][6]);
      double rho = upper(PVal{std::fabs(C2.v), C2.e});
      if (lens) rho += upper(PVal{std::fabs(si.f2[e][0].v), si.f2[e][0].e}) + upper(PVal{std::fabs(si.f2[e][2].v), si.f2[e][2].e});
      rho = rho * rq * (1.0 + 0x1p-48);
      for (int end = 0; end < 2 && edge_culls; ++end) {
        const PVal C = ar.add(ar.add(ar.mul(f[end][4], xc), ar.mul(f[end][5], yc)), f[end][6]);
        if (!lens) {
          edge_culls = sigma * C.v + C.e + rho + 0x1p-48 * std::fabs(C.v) < 0.0;
          continue;
        }
        const PVal A = ar.add(ar.mul(f[end][1], yc), f[end][0]);
        const PVal B = ar.add(ar.mul(f[end][3], xc), f[end][2]);
        const double sA = sigma * A.v, sB = sigma * B.v;
        const double bound = A.e + B.e + C.e + rho + 0x1p-48 * (std::fabs(A.v) + std::fabs(B.v) + std::fabs(C.v));
        CellMask line;
        for (int j = j0; j <= j1; ++j) {
          const double v_hi = -1.0 + step * (sB >= 0 ? j + 1 : j);
          const double row = sigma * C.v + sB * v_hi + bound;
          for (int i = i0; i <= i1; ++i) {
            const double u_hi = -1.0 + step * (sA >= 0 ? i + 1 : i);
            if (row + sA * u_hi < 0.0) line.set(j * G + i);
          }
        }
        edge &= line;
        edge_culls = edge.any();
      }
    }
    if (!edge_culls) continue;
    if (!lens) {
      culled.set();
      return culled;
    }
    culled |= edge;
  }
  return culled;
}

// ---- the per-triangle state of a motion tile algorithm --------------------------------------------------
// Set up once per moving triangle from the float64 set-up (iv::MotionSetup, and the MotionH5 when H5 is on);
// active() is false for float64 (the render then never calls it).
struct Motion5DPrecision {
  Precision p = Precision::float64();
  Arith4D ar{Precision::float64()};     // t̂ and the 5D lens sets
  Arith4D ar_h5{Precision::float64()};  // H5 (its own registers: max_abs per test)
  int S = 1;
  bool lens = false, with_h5 = false, setup_overflow = false;
  SubIntervalIn sub[iv::kMaxSplits];

  bool active() const { return p.kind != PrecisionKind::kFloat64; }

  void setup(const Precision& prec, const iv::MotionSetup& ms, double w_eps, const MotionH5* h5) {
    p = prec;
    ar = Arith4D(prec);
    ar_h5 = Arith4D(prec);
    S = ms.S;
    lens = ms.lens;
    with_h5 = h5 != nullptr;
    for (int k = 0; k < S; ++k) {
      const iv::SubInterval& si = ms.sub[k];
      SubIntervalIn& s = sub[k];
      s.wlo = -kInf, s.whi = kInf;
      double wmax = 0.0;
      for (int j = 0; j < 3; ++j) {
        const double m = std::max(std::fabs(si.P[0][j][2]), std::fabs(si.P[1][j][2]));
        wmax = std::max(wmax, m);
        const double sc = m > 0.0 && std::isfinite(1.0 / m) ? 1.0 / m : 1.0;  // positive: signs and roots kept
        for (int e = 0; e < 2; ++e) {
          for (int c = 0; c < 3; ++c) s.P[e][j][c] = carried_in(ar, si.P[e][j][c] * sc, 0x1p-51);
          s.cwx[e][j] = carried_in(ar, si.cwx[e][j] * sc, 0x1p-51);
          s.cwy[e][j] = carried_in(ar, si.cwy[e][j] * sc, 0x1p-51);
        }
        const PVal eps = carried_in(ar, w_eps * sc, 0x1p-51);
        form_cull_in(ar, ar.sub(eps, s.P[0][j][2]), ar.sub(eps, s.P[1][j][2]), s.wlo, s.whi);
      }
      s.n_lv = si.lens_ok ? si.n_lv : 0;
      for (int j = 0; j < s.n_lv; ++j) s.lv[j] = lens_vertex_in(ar, si.lv[j]);
      if (h5 && h5->sub[k].usable) {
        const double sc = 1.0 / wmax, sc2 = sc * sc;  // usable: every W > w_eps > 0
        for (int e = 0; e < 3; ++e)
          for (int m = 0; m < kH5Fields; ++m) {
            const EdgeH5& eh = h5->sub[k].edges[e];
            sub[k].f0[e][m] = carried_in(ar_h5, eh.f0[m] * sc2, 0x1p-50);
            sub[k].g[e][m] = carried_in(ar_h5, eh.g[m] * sc2, 0x1p-50);
            sub[k].f2[e][m] = carried_in(ar_h5, eh.f2[m] * sc2, 0x1p-50);
          }
      }
    }
    setup_overflow = ar.overflow || ar_h5.overflow;
  }

  // iv::motion_tile_intervals in the format: replaces ti's sub-intervals, lens sets, t̂ and hulls; returns
  // whether some sub-interval is active. overflow: a register of the set-up or of this test reached 2^int_bits.
  bool tile_intervals(const iv::ClipBox& clip, double x0, double x1, double y0, double y1, iv::TileIntervals& ti,
                      bool lens_sets, bool& overflow) {
    ar.overflow = false;
    ti.n_active = 0;
    ti.u0 = ti.v0 = ti.t0 = kInf;
    ti.u1 = ti.v1 = ti.t1 = -kInf;
    for (int k = 0; k < S; ++k) {
      const SubIntervalIn& si = sub[k];
      ti.active[k] = false;
      AxisSet& sx = ti.sx[k];
      AxisSet& sy = ti.sy[k];
      sx = full_axis(), sy = full_axis();
      if (lens) {
        if (si.n_lv && lens_sets) h_sets_in(ar, si.lv, si.n_lv, x0, x1, y0, y1, sx, sy);
        std::uint64_t ops = 0;  // not charged: the float64 form is the counted one
        if (!iv::clip_lens<FastArith>(clip, sx, sy, ops) || sx.empty || sy.empty) continue;
      }
      const double u0 = lens ? sx.iv_lo[0] : 0.0, u1 = lens ? sx.iv_hi[sx.n_intervals - 1] : 0.0;
      const double v0 = lens ? sy.iv_lo[0] : 0.0, v1 = lens ? sy.iv_hi[sy.n_intervals - 1] : 0.0;
      double tlo, thi;
      const double ta = static_cast<double>(k) / S, tb = static_cast<double>(k + 1) / S;
      if (!time_interval_in(ar, si, ta, tb, lens, x0, x1, y0, y1, u0, u1, v0, v1, clip, tlo, thi)) continue;
      ti.active[k] = true;
      ++ti.n_active;
      ti.tlo[k] = round_down_to_float(tlo);
      ti.thi[k] = round_up_to_float(thi);
      ti.u0 = std::min(ti.u0, u0), ti.u1 = std::max(ti.u1, u1);
      ti.v0 = std::min(ti.v0, v0), ti.v1 = std::max(ti.v1, v1);
      ti.t0 = std::min(ti.t0, tlo), ti.t1 = std::max(ti.t1, thi);
    }
    overflow = ar.overflow || setup_overflow;
    return ti.n_active > 0;
  }

  // The H5 cells of sub-interval k in the format (h5: the float64 set-up's sigma, usability and oracle).
  CellMask h5_cells(const MotionH5& h5, int k, double x0, double x1, double y0, double y1, double t_lo, double t_hi,
                    int G, int i0, int i1, int j0, int j1, bool& overflow) {
    ar_h5.overflow = false;
    CellMask m;
    if (with_h5 && h5.sub[k].usable)
      m = h5_cells_in(ar_h5, sub[k], h5.sub[k], h5.lens, S, k, x0, x1, y0, y1, t_lo, t_hi, G, i0, i1, j0, j1);
    overflow = ar_h5.overflow || setup_overflow;
    return m;
  }
};

}  // namespace rast5d::tiletest
