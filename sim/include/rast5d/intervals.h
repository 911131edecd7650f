// Per-tile intervals of the 5D pipeline (002_95ea0844b256f75b.txt §2, Fig. 2): conservative time
// intervals t̂ for moving triangles, lens boxes per time sub-interval for moving and defocused
// ones, user clip planes, and the depth interval ẑ (002 Appendix A).
//
// Contract (tested in tests/test_intervals.py against the brute-force sample test):
//  * every sample (x, y, u, v, t) that the exact sample test hits, with (x, y) in a tile and t in
//    sub-interval k, has t inside the tile's t̂_k and (u, v) inside the sub-interval's lens sets;
//  * its depth z = 1 - near / W_hit is inside ẑ widened by kDepthMargin (see zhat_widen).
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
//  * 5D lens sets: the 001 h_i lines over the six vertices at the sub-interval's ends (a linearly
//    moving point's projection is monotonic in t, so they bound the sub-interval).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "rast5d/clip.h"
#include "rast5d/footprint.h"

namespace rast5d::iv {

inline constexpr int kMaxSplits = 16;
// Relative margin on W applied to ẑ before it is compared with depths computed by the float
// sample test (docs/conventions.md: float hit depths can be off by several % near the camera).
inline constexpr double kDepthMargin = 0.125;

// ---- documented costs (tests/test_op_costs.py checks them against the counting type) ----------
inline constexpr std::uint64_t kFormCull = 7;  // SUB, RCP, MUL, 2 CMP, MAX, MIN
// Per (tile, sub-interval), excluding the forms: 4 edges x (MAX, MIN) against the W-valid
// interval, 2 x 4 passes x 4 edges x 2 CMP for the hull of the complement, MADD x 2 back to t,
// MAX + MIN against the clip box, CMP for emptiness.
inline constexpr std::uint64_t kTimeHull = 8 + 64 + 2 + 2 + 1;
// 3D: per edge, 3 vertices x 2 ends MADD (distance) + 3 forms.
inline constexpr std::uint64_t kTimeInterval3D = 4 * (6 + 3 * kFormCull) + kTimeHull;  // 185
// 5D: 12 MADD per axis (shear at the two lens corners), per edge 12 MADD + 6 forms.
inline constexpr std::uint64_t kTimeInterval5D = 24 + 4 * (12 + 6 * kFormCull) + kTimeHull;  // 317
// Per sub-interval setup (tile independent): per end and vertex 3 MADD lerp; 5D: 2 MADD shear
// slopes (MADD + MUL per axis); the W-valid interval: 3 x (SUB for each end) + 3 forms.
inline constexpr std::uint64_t kSubSetup3D = 2 * 9 + 3 * (2 + kFormCull);      // 45
inline constexpr std::uint64_t kSubSetup5D = kSubSetup3D + 2 * 3 * 4;          // 69
// Clip box applied to one axis' interval list: MAX + MIN per interval.
inline constexpr std::uint64_t kClipInterval = 2;

// {s : g(s) < 0} for the linear form g(s) = g0 + s (g1 - g0), s in R, as an open interval,
// intersected into (lo, hi). Cost: kFormCull (fixed: both comparisons and the root always run).
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

// Build the sub-intervals of a moving triangle. ops: setup operations (kSubSetup3D/5D per
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
    charge<A>(ops, ms.lens ? kSubSetup5D : kSubSetup3D);
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
// [tlo, thi] is in global time, clipped to the clip box. Cost: kTimeInterval3D / 5D.
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
  charge<A>(ops, lens ? kTimeInterval5D : kTimeInterval3D);
  // Round outwards by more than the float rounding of the sample's t and of s -> t.
  tlo = raw(t0) - 0x1p-20;
  thi = raw(t1) + 0x1p-20;
  return !empty;
}

// Clip an axis set's active intervals to [lo, hi] (counted MAX + MIN per interval); drops empty
// intervals. The per-sample cuts are left unchanged: samples outside the clip range in surviving
// cells are rejected by the per-sample clip comparison.
template <class A>
inline void clip_axis(tiletest::AxisSet& s, double lo, double hi, std::uint64_t& ops) {
  using D = typename A::f64;
  int n = 0;
  for (int i = 0; i < s.n_intervals; ++i) {
    const D a = vmax(D(s.iv_lo[i]), D(lo));
    const D b = vmin(D(s.iv_hi[i]), D(hi));
    charge<A>(ops, kClipInterval);
    if (raw(a) <= raw(b)) s.iv_lo[n] = raw(a), s.iv_hi[n] = raw(b), ++n;
  }
  s.n_intervals = n;
  s.empty = n == 0;
}

// The user clip box on a tile's lens sets (u and v axes, where active). False when either set is
// left without an interval.
template <class A>
inline bool clip_lens(const ClipBox& clip, tiletest::AxisSet& sx, tiletest::AxisSet& sy, std::uint64_t& ops) {
  if (clip.active_u) clip_axis<A>(sx, clip.u_lo, clip.u_hi, ops);
  if (clip.active_v) clip_axis<A>(sy, clip.v_lo, clip.v_hi, ops);
  return sx.n_intervals != 0 && sy.n_intervals != 0;
}

// ---- ẑ: conservative depth interval of a (triangle, tile) pair (002 Appendix A) ----------------

// Documented costs of ẑ. Vertex test (the moving box in W over t̂; W is linear in t): per vertex
// 2 MADD (ends) + 2 MIN + 2 MAX, near clamp MAX, z = 1 - near / W twice (RCP + MADD).
inline constexpr std::uint64_t kZhatVertex = 3 * 6 + 1 + 2 + 2;  // 23
// Moving planes, per triangle: t = 1 vertices 9 ADD; per base time 6 SUB (edges), 3 x (MUL +
// MADD) normal, MUL + 2 MADD offset, 3 x 3 MADD distances, 2 MAX + 2 MIN.
inline constexpr std::uint64_t kZhatPlaneSetup = 9 + 2 * (6 + 6 + 3 + 9 + 4);  // 65
// Per plane (4 planes) and tile: per lens corner (u, v) [1 or 4]: per screen corner 2 MADD + 2 CMP
// (+2 MADD ray offset with lens), the lens term (4 MUL + 2 MADD with lens), 2 MADD time terms;
// per (lens, screen) corner RCP + 2 x (MUL + MIN/MAX); MIN + MAX into the bound.
inline constexpr std::uint64_t kZhatPlaneTile3D = 4 * (1 * (4 * 4 + 0 + 2) + 4 * 5 + 2);  // 160
inline constexpr std::uint64_t kZhatPlaneTile5D = 4 * (4 * (4 * 6 + 6 + 2) + 16 * 5 + 2);  // 840
inline constexpr std::uint64_t zhat_plane_cost(bool lens) { return lens ? kZhatPlaneTile5D : kZhatPlaneTile3D; }

struct ZHat {
  double zlo = 0, zhi = 1;      // depth z = 1 - near / W
  double wlo = 0, whi = kInfD;  // view depth W
  double vwlo = 0, vwhi = kInfD;  // vertex min/max only (for the tightness report)
};

// Per-triangle moving planes (002 App. A Eq. 1): for base time tau in {0, 1} the triangle's plane
// n . P + d = 0 at tau, pushed along its normal by v so that the whole moving triangle stays on
// the side n . P + d + v |t - tau| <= 0.
struct MovingPlanes {
  int n = 0;
  double nx[4], ny[4], nw[4], d[4], v[4], tau[4];
};

template <class A>
inline void moving_planes(const TriSetup& tri, MovingPlanes& mp, std::uint64_t& ops) {
  using D = typename A::f64;
  D Q[2][3][3];
  for (int j = 0; j < 3; ++j) {
    Q[0][j][0] = D(static_cast<double>(tri.X[j]));
    Q[0][j][1] = D(static_cast<double>(tri.Y[j]));
    Q[0][j][2] = D(static_cast<double>(tri.W[j]));
    Q[1][j][0] = Q[0][j][0] + D(static_cast<double>(tri.dX[j]));
    Q[1][j][1] = Q[0][j][1] + D(static_cast<double>(tri.dY[j]));
    Q[1][j][2] = Q[0][j][2] + D(static_cast<double>(tri.dW[j]));
  }
  mp.n = 0;
  for (int base = 0; base < 2; ++base) {
    const auto& q = Q[base];
    const auto& r = Q[1 - base];
    D e1[3], e2[3];
    for (int a = 0; a < 3; ++a) e1[a] = q[1][a] - q[0][a], e2[a] = q[2][a] - q[0][a];
    const D nx = madd(e1[1], e2[2], -(e1[2] * e2[1]));
    const D ny = madd(e1[2], e2[0], -(e1[0] * e2[2]));
    const D nw = madd(e1[0], e2[1], -(e1[1] * e2[0]));
    const D d = -madd(nx, q[0][0], madd(ny, q[0][1], nw * q[0][2]));
    // distances of the other end's vertices from the plane
    D dist[3];
    for (int j = 0; j < 3; ++j) dist[j] = madd(nx, r[j][0], madd(ny, r[j][1], madd(nw, r[j][2], d)));
    const D mx = vmax(dist[0], vmax(dist[1], dist[2]));
    const D mn = vmin(dist[0], vmin(dist[1], dist[2]));
    // orientation +n: v = -max (Eq. 1); orientation -n: the plane -n . P - d, v = -max(-dist) = min
    for (int o = 0; o < 2; ++o) {
      const double s = o ? -1.0 : 1.0;
      mp.nx[mp.n] = s * raw(nx), mp.ny[mp.n] = s * raw(ny), mp.nw[mp.n] = s * raw(nw), mp.d[mp.n] = s * raw(d);
      mp.v[mp.n] = o ? raw(mn) : -raw(mx);
      mp.tau[mp.n] = base;
      ++mp.n;
    }
  }
  charge<A>(ops, kZhatPlaneSetup);
}

// ẑ of the pair: the vertex (moving box) bound over t̂ = [ta, tb], tightened by the moving planes
// evaluated at the corners of the (x, y, u, v, t) box when the plane does not sweep over it
// (its ray-direction term keeps one sign at every corner). planes = nullptr: vertex bound only.
// Cost: kZhatVertex + zhat_plane_cost(lens) when planes are used (fixed per call).
template <class A>
inline ZHat zhat(const TriSetup& tri, const MovingPlanes* planes, const FrameConst& fc, bool lens, double x0,
                 double x1, double y0, double y1, double u0, double u1, double v0, double v1, double ta, double tb,
                 std::uint64_t& ops) {
  using D = typename A::f64;
  ZHat z;
  D wlo(kInfD), whi(-kInfD);
  for (int j = 0; j < 3; ++j) {
    const D W0(static_cast<double>(tri.W[j])), dW(static_cast<double>(tri.dW[j]));
    const D a = madd(D(ta), dW, W0), b = madd(D(tb), dW, W0);
    wlo = vmin(wlo, vmin(a, b));
    whi = vmax(whi, vmax(a, b));
  }
  z.vwlo = raw(wlo), z.vwhi = raw(whi);
  if (planes) {
    const D kx(fc.kx_d), ky(fc.ky_d), F(fc.focus_d);
    const int nl = lens ? 2 : 1;
    for (int i = 0; i < planes->n; ++i) {
      const D nx(planes->nx[i]), ny(planes->ny[i]), nw(planes->nw[i]), d(planes->d[i]), vv(planes->v[i]);
      // Along the ray through pixel (x, y) from lens point (u, v): P(W) = (W (x - u kx) + u kx F,
      // W (y - v ky) + v ky F, W); n . P + d + v |t - tau| = W Den + Num.
      D dens[2][2][2][2], nums[2][2][2];
      int pos = 0, neg = 0;
      for (int a = 0; a < nl; ++a)
        for (int b = 0; b < nl; ++b) {
          const D u = lens ? D(a ? u1 : u0) : D(0.0), v = lens ? D(b ? v1 : v0) : D(0.0);
          for (int cx = 0; cx < 2; ++cx)
            for (int cy = 0; cy < 2; ++cy) {
              const D xr = lens ? madd(-u, kx, D(cx ? x1 : x0)) : D(cx ? x1 : x0);
              const D yr = lens ? madd(-v, ky, D(cy ? y1 : y0)) : D(cy ? y1 : y0);
              const D den = madd(nx, xr, madd(ny, yr, nw));
              dens[a][b][cx][cy] = den;
              pos += den > D(0.0);
              neg += den < D(0.0);
            }
          const D lensterm = lens ? madd(nx * u, kx * F, madd(ny * v, ky * F, d)) : d;
          for (int ct = 0; ct < 2; ++ct) {
            const double tt = ct ? tb : ta;
            const D dt(std::fabs(tt - planes->tau[i]));
            nums[a][b][ct] = madd(vv, dt, lensterm);
          }
        }
      const int corners = nl * nl * 4;
      // Den > 0 everywhere: W <= -Num / Den (upper bound); Den < 0 everywhere: lower bound. The
      // bound is linear-fractional over the box, so its extreme is at a corner.
      D ext = pos == corners ? D(-kInfD) : D(kInfD);
      for (int a = 0; a < nl; ++a)
        for (int b = 0; b < nl; ++b)
          for (int cx = 0; cx < 2; ++cx)
            for (int cy = 0; cy < 2; ++cy) {
              const D r = rcp(dens[a][b][cx][cy]);
              for (int ct = 0; ct < 2; ++ct) {
                const D w = -(nums[a][b][ct] * r);
                ext = pos == corners ? vmax(ext, w) : vmin(ext, w);
              }
            }
      // (the plane sweeps over the box when Den changes sign: no bound from it)
      whi = vmin(whi, pos == corners ? ext : D(kInfD));
      wlo = vmax(wlo, neg == corners ? ext : D(-kInfD));
    }
  }
  wlo = vmax(wlo, D(fc.near_d));
  z.wlo = raw(wlo), z.whi = raw(whi);
  const D nn(-fc.near_d), one(1.0);
  z.zlo = raw(madd(nn, rcp(wlo), one));
  z.zhi = raw(whi) >= kInfD ? 1.0 : raw(madd(nn, rcp(whi), one));
  charge<A>(ops, kZhatVertex + (planes ? zhat_plane_cost(lens) : 0));
  return z;
}

// ẑ widened for comparisons with float sample depths (kDepthMargin on W).
inline void zhat_widen(const ZHat& z, double near, double& zlo, double& zhi) {
  const double wl = std::max(near, z.wlo) * (1.0 - kDepthMargin);
  const double wh = z.whi * (1.0 + kDepthMargin);
  zlo = 1.0 - near / wl;
  zhi = std::isinf(wh) ? 1.0 : 1.0 - near / wh;
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

inline tiletest::AxisSet full_axis() {
  tiletest::AxisSet s;
  s.n_intervals = 1;
  s.iv_lo[0] = -1.0, s.iv_hi[0] = 1.0;
  return s;
}

// Per sub-interval: 5D lens sets from the h_i lines of its six end vertices (clipped), then the
// time interval for the hull of those sets. Tile-stage operations go to ops; the per-class
// evaluation counters to c. Returns false when every sub-interval is empty.
template <class A>
inline bool motion_tile_intervals(const MotionSetup& ms, const ClipBox& clip, DimClass cls, double x0, double x1,
                                  double y0, double y1, TileIntervals& ti, std::uint64_t& ops, Counters& c) {
  using D = typename A::f64;
  ti.n_active = 0;
  ti.u0 = ti.v0 = ti.t0 = kInfD;
  ti.u1 = ti.v1 = ti.t1 = -kInfD;
  const bool is5 = cls == DimClass::k5D;
  for (int k = 0; k < ms.S; ++k) {
    const SubInterval& si = ms.sub[k];
    ti.active[k] = false;
    tiletest::AxisSet& sx = ti.sx[k];
    tiletest::AxisSet& sy = ti.sy[k];
    sx = full_axis(), sy = full_axis();
    if (ms.lens) {
      ++c[is5 ? Counter::interval_lens_tests_5d : Counter::interval_lens_tests_3d];
      if (si.lens_ok) tile_h_sets<A>(si.lv, si.n_lv, x0, x1, y0, y1, sx, sy, ops);  // empty sets: caught below
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
