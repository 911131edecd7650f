// H5: the H_j lines of [Akenine-Möller 2012] §4.3 (Eq. 4-5) extended to time, for moving
// triangles: per (screen tile, time sub-interval, lens-grid cell) a conservative test of whether the
// tile lies outside a triangle edge for every (u, v, t) of the cell and the tile's time interval
// t̂_k. It refines the (lens cell x t̂_k) boxes that the time intervals and 5D lens sets
// (intervals/time_interval.h) leave; docs/tile_tests.md "H5".
//
// Geometry. With the vertices linear in t, at local time s of sub-interval [ta, tb] the edge (q, r)
// has q(s) = q_a + s Δq, r(s) = r_a + s Δr, so Q = q x r is quadratic in s and d = r - q linear:
// every H_j constant of halfspace_edges.h (a0, a1, b0, b1, cx, cy, c0) is a quadratic
//     f(s) = f0 + s (f1 - f0) + s (s - 1) f2,      f2 = its s^2 coefficient (from Δq x Δr),
// and for tile corner c the line of [Akenine-Möller 2012] Eq. 4 is H_c(u, v, s) = A(s) u + B(s) v + C(s). On the
// tile's time interval [s_lo, s_hi] (from t̂_k), with σ in [0, 1] its local time,
//     H_c = (1 - σ) H_c(u, v, s_lo) + σ H_c(u, v, s_hi) + R_c(u, v) (s_hi - s_lo)^2 σ (σ - 1),
// where R_c = A2 u + B2 v + C2 (the s^2 coefficients at corner c). As σ (σ - 1) is in [-1/4, 0],
//     H_c <= (1 - σ) H_c(s_lo) + σ H_c(s_hi) + ρ_c,   ρ_c = (|A2| + |B2| + |C2|) (s_hi - s_lo)^2 / 4
// over the lens square. For fixed (u, v) the right side is linear in σ, so its maximum over a lens
// cell x [s_lo, s_hi] is its maximum over the cell at σ = 0 or σ = 1: the cell is outside corner c's
// line for the whole interval iff both end lines (each raised by ρ_c) are negative over the cell
// (line_cells, the [Akenine-Möller 2012] §5.1 evaluation at the cell's most positive corner). These are the
// separating planes in (u, v, t) of the title: per corner, two lines in the lens plane at the ends
// of t̂_k and their conservative hull in t.
//
// The tile is outside edge (q, r) seen from (u, v) at t iff every tile corner is on the other side
// of the projected edge from the third vertex: sigma * H_c < 0 for all four corners, with sigma the
// triangle's orientation seen from (u, v, t) (the sign of the sample test's determinant). H_c is
// affine in the corner, so where its corner gradient keeps its sign one support corner decides (else
// 2 or 4 corners; [Akenine-Möller 2012]'s two tangent corners are not used: the focus-plane point v of the edge moves
// with t, and its nine-region class may change within t̂_k). sigma must be one sign over the lens
// square and the sub-interval: the orientation det[X', Y', W] is affine in (u, v) and cubic in s,
// and its tensor Bernstein coefficients over the lens square's corners and [0, 1] bound it (convex
// hull property); a sub-interval whose 16 coefficients do not share a sign (with a relative margin)
// gets no H5 test (setup.H5_sub_unoriented). Every vertex must be in front (W > w_eps at both ends,
// so for the whole sub-interval) for the projected triangle to be the hull of its projected
// vertices. 3D triangles (no lens) use u = v = 0: H_c = C(s), a test per sub-interval.
//
// Contract (tiletest/common.h): conservative. The tile is the expanded tile, the constants are in double,
// and a cell is culled only where the bound above is negative over the whole cell: it never
// removes a (u, v, t) of t̂_k from which the float sample test could hit a sample of the tile.
// tests/test_halfspace_5d.py checks it against brute force.
#pragma once

#include <cmath>
#include <cstdint>

#include "core/arith.h"
#include "core/costs.h"
#include "intervals/time_interval.h"
#include "setup/footprint.h"
#include "tiletest/halfspace_edges.h"
#include "tiletest/common.h"

namespace rast5d::tiletest {

inline constexpr int kH5Fields = 7;  // a0, a1, b0, b1, cx, cy, c0 (halfspace_edges.h EdgeH)

// One edge of one sub-interval: f(s) = f0 + s (g + (s - 1) f2) per field (g = f1 - f0).
struct EdgeH5 {
  bool active = false;  // false: disabled by the selective oracle ([Akenine-Möller 2012] Appendix A, per sub-interval)
  double f0[kH5Fields], g[kH5Fields], f2[kH5Fields];
};

struct SubH5 {
  bool usable = false;  // every vertex in front and one orientation over the lens square and sub-interval
  int sigma = 0;
  EdgeH5 edges[3];
};

struct MotionH5 {
  bool lens = false;
  int S = 1;
  int n_unoriented = 0;  // sub-intervals whose orientation may change sign (no H5 test)
  int edges_enabled = 0, edges_disabled = 0;  // by the selective oracle, over the sub-intervals
  SubH5 sub[iv::kMaxSplits];
};

// The seven H_j constants of edge (q, r) at one time (halfspace_edges.h edge_setup without v).
// Cost: cost::kH5EdgeFields (Q 6, d 3, a0 2, a1 1, b0 2, b1 1).
template <class D>
inline void h5_edge_fields(const D q[3], const D r[3], D focus, D coc_x, D coc_y, D kxf, D kyf, D out[kH5Fields]) {
  const D Qx = madd(q[1], r[2], -(q[2] * r[1]));
  const D Qy = madd(q[2], r[0], -(q[0] * r[2]));
  const D Qw = madd(q[0], r[1], -(q[1] * r[0]));
  const D dx = r[0] - q[0], dy = r[1] - q[1], dw = r[2] - q[2];
  out[0] = -(coc_x * madd(focus, dy, Qx));
  out[1] = kxf * dw;
  out[2] = -(coc_y * madd(-focus, dx, Qy));
  out[3] = -(kyf * dw);
  out[4] = Qx, out[5] = Qy, out[6] = Qw;
}

// Sign of the orientation over the lens square (lens) or at the lens centre, and sub-interval si:
// +1 / -1 when every Bernstein coefficient has that sign beyond a relative margin, else 0.
// Cost: cost::kH5Orientation5D / 3D.
template <class D>
inline int h5_orientation(const iv::SubInterval& si, bool lens) {
  int pos = 0, neg = 0;
  const int n_corners = lens ? 4 : 1;
  for (int c = 0; c < n_corners; ++c) {
    const double cu = (c & 1) ? 1.0 : -1.0, cv = (c & 2) ? 1.0 : -1.0;
    D X[2][3], Y[2][3], W[2][3];
    for (int e = 0; e < 2; ++e)
      for (int j = 0; j < 3; ++j) {
        X[e][j] = lens ? madd(D(cu), D(si.cwx[e][j]), D(si.P[e][j][0])) : D(si.P[e][j][0]);
        Y[e][j] = lens ? madd(D(cv), D(si.cwy[e][j]), D(si.P[e][j][1])) : D(si.P[e][j][1]);
        W[e][j] = D(si.P[e][j][2]);
      }
    // det[X(s), Y(s), W(s)] is multilinear in the columns: its degree-3 Bernstein coefficients are
    // the mean determinants with k columns taken at the end ([Akenine-Möller 2012] Appendix A's shear per column).
    const D b0 = det3_columns(X[0], Y[0], W[0]);
    const D b1 = det3_columns(X[1], Y[0], W[0]) + det3_columns(X[0], Y[1], W[0]) + det3_columns(X[0], Y[0], W[1]);
    const D b2 = det3_columns(X[0], Y[1], W[1]) + det3_columns(X[1], Y[0], W[1]) + det3_columns(X[1], Y[1], W[0]);
    const D b3 = det3_columns(X[1], Y[1], W[1]);
    // b1, b2 are 3x the coefficients; the margin is relative to the coefficients' magnitude.
    const D scale = vabs(b0) + vabs(b1) + vabs(b2) + vabs(b3);
    const D thr = scale * D(1e-7);
    const D thr3 = thr * D(3.0);
    pos += (b0 > thr) + (b1 > thr3) + (b2 > thr3) + (b3 > thr);
    neg += (b0 < -thr) + (b1 < -thr3) + (b2 < -thr3) + (b3 < -thr);
  }
  return pos == 4 * n_corners ? 1 : (neg == 4 * n_corners ? -1 : 0);
}

// Per sub-interval of a moving triangle: the edges' quadratics and the orientation (setup).
// Cost per sub-interval: cost::kH5SubSetup5D / 3D (when every vertex is in front; else nothing).
// Selective oracle ([Akenine-Möller 2012] Appendix A, Eq. 13 and 15, per sub-interval): edge (p, q) of the triangle
// at mid-sub-interval seen from the lens centre culls about N = R_S / 2 |X_q - X_p| |Y_q - Y_p|
// samples of the shutter, N / S of the sub-interval's; the edge is disabled when N / S * c_sample <
// n_tiles * c_tile (c_tile: cost::h5_edge_tile_cost). oracle = false keeps every edge.
struct H5Oracle {
  bool on = false;
  double spp = 0, n_tiles = 0, c_sample = 0, c_tile = 0;
};

template <class A>
inline void h5_setup(const iv::MotionSetup& ms, const FrameConst& fc, const H5Oracle& oracle, MotionH5& h5,
                     std::uint64_t& ops) {
  using D = typename A::f64;
  h5.lens = ms.lens;
  h5.S = ms.S;
  h5.n_unoriented = 0;
  h5.edges_enabled = h5.edges_disabled = 0;
  const double w_eps = 0.5 * fc.near_d;
  const D F(fc.focus_d), kx(fc.kx_d), ky(fc.ky_d);
  for (int k = 0; k < ms.S; ++k) {
    const iv::SubInterval& si = ms.sub[k];
    SubH5& s = h5.sub[k];
    s.usable = false;
    bool front = true;
    for (int e = 0; e < 2; ++e)
      for (int j = 0; j < 3; ++j) front &= si.P[e][j][2] > w_eps;
    if (!front) continue;  // no hull argument: t̂ and the lens sets keep this sub-interval
    const D kxf = kx * F, kyf = ky * F;
    for (int i = 0; i < 3; ++i) {
      const int k2 = (i + 1) % 3;
      D q[2][3], r[2][3], f[2][kH5Fields];
      for (int e = 0; e < 2; ++e)
        for (int c = 0; c < 3; ++c) q[e][c] = D(si.P[e][i][c]), r[e][c] = D(si.P[e][k2][c]);
      h5_edge_fields(q[0], r[0], F, kx, ky, kxf, kyf, f[0]);
      h5_edge_fields(q[1], r[1], F, kx, ky, kxf, kyf, f[1]);
      // s^2 coefficients: Q2 = Δq x Δr; d has none.
      D dq[3], dr[3];
      for (int c = 0; c < 3; ++c) dq[c] = q[1][c] - q[0][c], dr[c] = r[1][c] - r[0][c];
      const D Q2x = madd(dq[1], dr[2], -(dq[2] * dr[1]));
      const D Q2y = madd(dq[2], dr[0], -(dq[0] * dr[2]));
      const D Q2w = madd(dq[0], dr[1], -(dq[1] * dr[0]));
      EdgeH5& eh = s.edges[i];
      const D f2[kH5Fields] = {-(kx * Q2x), D(0.0), -(ky * Q2y), D(0.0), Q2x, Q2y, Q2w};
      for (int m = 0; m < kH5Fields; ++m) {
        eh.f0[m] = raw(f[0][m]);
        eh.g[m] = raw(f[1][m] - f[0][m]);
        eh.f2[m] = raw(f2[m]);
      }
    }
    s.sigma = h5_orientation<D>(si, ms.lens);
    charge<A>(ops, ms.lens ? cost::kH5SubSetup5D : cost::kH5SubSetup3D);
    if (s.sigma == 0) {
      ++h5.n_unoriented;
      continue;
    }
    s.usable = true;
    for (int i = 0; i < 3; ++i) s.edges[i].active = true;
    if (!oracle.on) {
      h5.edges_enabled += 3;
      continue;
    }
    // Eq. 15 at mid-sub-interval, lens centre: pixel positions X / W of the mid vertices.
    D px[3], py[3];
    for (int j = 0; j < 3; ++j) {
      const D X = (D(si.P[0][j][0]) + D(si.P[1][j][0])) * D(0.5);
      const D Y = (D(si.P[0][j][1]) + D(si.P[1][j][1])) * D(0.5);
      const D Wm = (D(si.P[0][j][2]) + D(si.P[1][j][2])) * D(0.5);
      const D r = rcp(Wm);
      px[j] = X * r, py[j] = Y * r;
    }
    const D budget = D(oracle.n_tiles) * D(oracle.c_tile);
    for (int i = 0; i < 3; ++i) {
      const int k2 = (i + 1) % 3;
      const D n_samples = (vabs(px[k2] - px[i]) * vabs(py[k2] - py[i])) * D(0.5 * oracle.spp / ms.S);
      const bool keep = !(n_samples * D(oracle.c_sample) < budget);
      s.edges[i].active = keep;
      ++(keep ? h5.edges_enabled : h5.edges_disabled);
    }
    charge<A>(ops, cost::kH5Oracle);
  }
}

// The oracle's C_tile: the expected H5 cost of one edge against one (tile, sub-interval): its
// constants at both ends, the support corner, and that corner's lines (5D: with their box pre-tests
// and the cells at both ends over the full G x G grid, as [Akenine-Möller 2012]'s C_tile counts the lines over the grid).
inline std::uint64_t h5_edge_tile_cost(bool lens, int G) {
  const std::uint64_t g = static_cast<std::uint64_t>(G);
  return lens ? cost::kH5EdgeEnds5D + cost::kH5Support5D + cost::kH5CornerOrder + cost::kH5Corner5D +
                    2 * cost::kH5LineBox + 2 * line_cells_cost(g, g)
              : cost::kH5EdgeEnds3D + cost::kH5Support3D + cost::kH5CornerOrder + cost::kH5Corner3D;
}

// Does the line l (culls where negative) lie entirely below / above zero over the lens box
// [u0, u1] x [v0, v1]? Cost: cost::kH5LineBox (2 CMP signs, 2 x 2 MADD, 2 CMP).
template <class D>
inline void h5_line_box(const Line& l, double u0, double u1, double v0, double v1, bool& all_neg, bool& all_pos) {
  const bool ap = D(l.A) >= D(0.0), bp = D(l.B) >= D(0.0);
  const D hi = madd(D(l.A), D(ap ? u1 : u0), madd(D(l.B), D(bp ? v1 : v0), D(l.C)));
  const D lo = madd(D(l.A), D(ap ? u0 : u1), madd(D(l.B), D(bp ? v0 : v1), D(l.C)));
  all_neg = hi < D(0.0);
  all_pos = lo >= D(0.0);
}

// The lens cells of columns i0..i1, rows j0..j1 of the G x G grid that sub-interval k's H5 planes
// cull for the (expanded) tile [x0, x1] x [y0, y1] over its time interval [t_lo, t_hi] (global
// time, t̂_k). Without a lens (3D) the answer is all cells or none. Charges ops; lines counts the
// corner lines evaluated (tile.H5_lines).
template <class A>
inline CellMask h5_culled_cells(const MotionH5& h5, int k, double x0, double x1, double y0, double y1, double t_lo,
                                double t_hi, int G, int i0, int i1, int j0, int j1, std::uint64_t& ops,
                                std::uint64_t& lines) {
  using D = typename A::f64;
  const SubH5& s = h5.sub[k];
  CellMask culled;
  // Local times of t̂_k in the sub-interval and the remainder factor (s_hi - s_lo)^2 / 4, raised by
  // a relative 2^-20 against its own rounding.
  const D S(static_cast<double>(h5.S)), kk(static_cast<double>(-k));
  const D s_lo = madd(D(t_lo), S, kk), s_hi = madd(D(t_hi), S, kk);
  const D ds = s_hi - s_lo;
  const D rq = (ds * ds) * D(0.25 * (1.0 + 0x1p-20));
  const double sigma = s.sigma;
  const double step = 2.0 / G;
  const double u0 = -1.0 + step * i0, u1 = -1.0 + step * (i1 + 1);
  const double v0 = -1.0 + step * j0, v1 = -1.0 + step * (j1 + 1);
  const D sm[2] = {s_lo - D(1.0), s_hi - D(1.0)};
  const D sv[2] = {s_lo, s_hi};
  charge<A>(ops, cost::kH5TileBase);
  for (int e = 0; e < 3; ++e) {
    const EdgeH5& eh = s.edges[e];
    if (!eh.active) continue;
    // Fields at both ends of t̂_k (3D: cx, cy, c0 only).
    D f[2][kH5Fields];
    const int m0 = h5.lens ? 0 : 4;
    for (int end = 0; end < 2; ++end)
      for (int m = m0; m < kH5Fields; ++m) f[end][m] = madd(sv[end], madd(sm[end], D(eh.f2[m]), D(eh.g[m])), D(eh.f0[m]));
    charge<A>(ops, h5.lens ? cost::kH5EdgeEnds5D : cost::kH5EdgeEnds3D);
    CellMask edge;
    edge.set();
    bool edge_culls = true;
    // The support corner. H_c is affine in the corner: H_c = H_0 + Xc (b1 v + cx) + Yc (a1 u + cy), so
    // where sigma (b1 v + cx) and sigma (a1 u + cy) keep their signs over the lens rectangle and t̂_k,
    // one corner has the largest sigma H_c at every (u, v, t) and the edge culls exactly where that
    // corner is outside. Each gradient component is bounded by its values at both ends (and both
    // rectangle edges) and its s^2 term (b1, a1 are linear in s: only cx2, cy2 enter). A component of
    // uncertain sign keeps both corners on that axis (2 or 4 corners: their AND is exact).
    D gx_lo, gx_hi, gy_lo, gy_hi;
    if (h5.lens) {
      gx_lo = gx_hi = madd(f[0][3], D(v0), f[0][4]);
      gy_lo = gy_hi = madd(f[0][1], D(u0), f[0][5]);
      const D gx[3] = {madd(f[0][3], D(v1), f[0][4]), madd(f[1][3], D(v0), f[1][4]), madd(f[1][3], D(v1), f[1][4])};
      const D gy[3] = {madd(f[0][1], D(u1), f[0][5]), madd(f[1][1], D(u0), f[1][5]), madd(f[1][1], D(u1), f[1][5])};
      for (int q = 0; q < 3; ++q) {
        gx_lo = vmin(gx_lo, gx[q]), gx_hi = vmax(gx_hi, gx[q]);
        gy_lo = vmin(gy_lo, gy[q]), gy_hi = vmax(gy_hi, gy[q]);
      }
    } else {
      gx_lo = vmin(f[0][4], f[1][4]), gx_hi = vmax(f[0][4], f[1][4]);
      gy_lo = vmin(f[0][5], f[1][5]), gy_hi = vmax(f[0][5], f[1][5]);
    }
    const D rx = vabs(D(eh.f2[4])) * rq, ry = vabs(D(eh.f2[5])) * rq;
    const bool x_pos = gx_lo > rx, x_neg = gx_hi < -rx, y_pos = gy_lo > ry, y_neg = gy_hi < -ry;
    charge<A>(ops, h5.lens ? cost::kH5Support5D : cost::kH5Support3D);
    // Corner bits: bit0 = x1, bit1 = y1. First the support corner (or, on an uncertain axis, the
    // larger one at the lens centre and t̂_k's start: 2 CMP).
    const bool up = sigma > 0;
    const bool gx0 = f[0][4] >= D(0.0), gy0 = f[0][5] >= D(0.0);
    charge<A>(ops, cost::kH5CornerOrder);
    const int bx = (x_pos || x_neg) ? ((x_pos == up) ? 1 : 0) : ((gx0 == up) ? 1 : 0);
    const int by = (y_pos || y_neg) ? ((y_pos == up) ? 1 : 0) : ((gy0 == up) ? 1 : 0);
    const int first = bx | (by << 1);
    const int flips = ((x_pos || x_neg) ? 0 : 1) | ((y_pos || y_neg) ? 0 : 2);  // axes with two corners
    for (int n = 0; n < 4 && edge_culls; ++n) {
      if (n & ~flips) continue;  // a certain axis keeps one corner
      const int c = first ^ n;
      const double xc = (c & 1) ? x1 : x0, yc = (c & 2) ? y1 : y0;
      ++lines;
      if (!h5.lens) {  // C(s) at both ends + ρ: the corner is outside for all of t̂_k or not
        const D C2 = madd(D(eh.f2[4]), D(xc), madd(D(eh.f2[5]), D(yc), D(eh.f2[6])));
        const D rho = vabs(C2) * rq;
        bool out = true;
        for (int end = 0; end < 2; ++end) {
          const D C = madd(f[end][4], D(xc), madd(f[end][5], D(yc), f[end][6]));
          out &= madd(D(sigma), C, rho) < D(0.0);
        }
        charge<A>(ops, cost::kH5Corner3D);
        edge_culls = out;
        continue;
      }
      const D A2(eh.f2[0]), B2(eh.f2[2]);
      const D C2 = madd(D(eh.f2[4]), D(xc), madd(D(eh.f2[5]), D(yc), D(eh.f2[6])));
      const D rho = (vabs(A2) + vabs(B2) + vabs(C2)) * rq;
      Line l[2];
      for (int end = 0; end < 2; ++end) {
        const D Al = madd(f[end][1], D(yc), f[end][0]);
        const D Bl = madd(f[end][3], D(xc), f[end][2]);
        const D Cl = madd(f[end][4], D(xc), madd(f[end][5], D(yc), f[end][6]));
        l[end] = Line{sigma * raw(Al), sigma * raw(Bl), raw(madd(D(sigma), Cl, rho))};
      }
      charge<A>(ops, cost::kH5Corner5D);
      // Box pre-test over the cells' rectangle: negative everywhere at both ends: the corner culls
      // every cell; non-negative everywhere at one end: it culls none (nor does the edge).
      bool neg[2], pos[2];
      for (int end = 0; end < 2; ++end) h5_line_box<D>(l[end], u0, u1, v0, v1, neg[end], pos[end]);
      charge<A>(ops, 2 * cost::kH5LineBox);
      if (pos[0] || pos[1]) {
        edge_culls = false;
        continue;
      }
      if (neg[0] && neg[1]) continue;
      for (int end = 0; end < 2; ++end) edge &= line_cells<D>(l[end], G, i0, i1, j0, j1);
      charge<A>(ops, 2 * line_cells_cost(static_cast<std::uint64_t>(j1 - j0 + 1), static_cast<std::uint64_t>(i1 - i0 + 1)));
    }
    if (!edge_culls) continue;
    if (!h5.lens) {  // every cell
      culled.set();
      return culled;
    }
    culled |= edge;
  }
  return culled;
}

}  // namespace rast5d::tiletest
