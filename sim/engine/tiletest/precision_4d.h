// The 4D tile test in a chosen arithmetic (pipeline.precision.tile: float32 or fixed point; docs/precision.md,
// docs/tile_tests.md "Precision"): the h_i lines ([Akenine-Möller 2012] §4.2 Eq. 1-3), the H_j lines
// (§4.3 Eq. 4-5), the screen bounds over a lens box (INTERVAL, INTERLEAVE) and ẑ. The float64 kernels
// (halfspace_lens.h, halfspace_edges.h, box_bounds.h) stay the render's counted form: precision changes
// which lens regions are culled, not what a test costs. Each *_in function below returns the decision
// of the datapath in the format, made conservative by construction:
//
//  * Inputs. Per footprint vertex the lens projection x(u) = a_x + u b_x, y(v) = a_y + v b_y
//    (lens_vertex.h, set up in float64 as the sample test's vertex placement is). Fixed point: a and b
//    snap to the 2^-frac_bits sub-pixel grid (exact from then on). Seen from any lens point |u|, |v| <= 1
//    the snapped vertex lies within 2^-(frac_bits+1) (1 + 1) = 2^-frac_bits px of the exact one per axis,
//    and so does every point of the snapped footprint (convex combinations); every tile is already widened
//    by 2^(1-frac_bits) px when a stage is fixed (tiletest/common.h t_snap_margin_px), so a tile the exact
//    footprint overlaps is overlapped by the snapped footprint: a test exact on the snapped inputs is
//    conservative. The tile edges themselves snap outward (a larger tile). float32: a, b round to nearest
//    and their rounding |x - fl(x)| is carried as an error bound (no widening is assumed).
//  * Arithmetic. Every value is the format's own (fixed: a multiple of 2^-2 frac_bits, the register
//    resolution of core/fixed.h; float32: a binary32 number) together with a bound e of its distance to
//    the exact value of the same formula on the inputs (running error analysis, Higham §3.3): for c = a op b,
//    e_c = propagated input bounds + |fl(c) - c_double| + 2^-52 |c_double| (the last term covers the double
//    the simulator computes c_double in). A reciprocal whose argument's bound reaches the argument is
//    unbounded (e = inf): the quantity built on it then culls nothing.
//  * Decisions move inward by e: a gap bound of the h_i lines is lowered (upper ends) or raised (lower
//    ends) by its e; a lens cell is culled by an H_j line only if the line's value plus the bound of every
//    coefficient's error is negative over the whole cell; screen bounds move outward by e; ẑ rounds outward
//    to the format.
//  * H_j in lens-vertex form: seen from (u, v) the projected edge q r and a tile corner T have orientation
//        O(u, v) = (P_r - P_q) x (T - P_q) = C + A u + B v + D u v,
//        A = Δb_x (T_y - a_qy) + Δa_y b_qx,  B = -Δa_x b_qy - Δb_y (T_x - a_qx),
//        C = Δa_x (T_y - a_qy) - Δa_y (T_x - a_qx),  D = Δb_y b_qx - Δb_x b_qy        (Δ = r - q),
//    a positive multiple (1 / (W_q W_r F)) of halfspace_edges.h's plane H (Eq. 4-5), and with b_x : b_y =
//    Kx : Ky for every vertex D = 0 exactly; after snapping D is tiny and |D| (|u v| <= 1) is added to the
//    bound. In fixed point every product of two snapped inputs is exact (2 frac_bits fraction bits). The
//    edge culls a cell when sigma O < 0 there for all four tile corners (the AND over the four corners is
//    what [Akenine-Möller 2012]'s two tangent corners select; the precision form does not rely on the nine-region table,
//    whose focus-plane point would itself be rounded). sigma is the orientation of the footprint seen from
//    the lens, sum over edges of (P_k x P_k+1), bilinear in (u, v): its sign is taken at the four lens-square
//    corners and trusted only where value - bound > 0 (or value + bound < 0) at all four; otherwise the
//    precision form uses no H_j line for the triangle.
//  * Overflow: a fixed-point value reaching 2^int_bits sets `overflow` (hardware would wrap); the render
//    keeps the unwrapped value and counts the tile test in precision.tile4d_overflows. `max_abs` records
//    the largest value (precision study: the fewest int_bits n satisfy max_abs < 2^n).
// Time intervals t̂, the 5D lens sets of moving triangles and H5: precision_5d.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/params.h"
#include "tiletest/halfspace_lens.h"
#include "tiletest/lens_vertex.h"
#include "tiletest/common.h"

namespace rast5d::tiletest {

// A value of the format and a bound of its distance to the exact value.
struct PVal {
  double v = 0.0, e = 0.0;
};
// The ends of the interval a PVal guarantees; an undefined bound (NaN: inf * 0) is no bound at all.
inline double lower(PVal x) {
  const double r = x.v - x.e;
  return r == r ? r : -kInf;
}
inline double upper(PVal x) {
  const double r = x.v + x.e;
  return r == r ? r : kInf;
}

// The format's arithmetic (float32 or fixed; float64 is never routed here).
struct Arith4D {
  PrecisionKind kind;
  int int_bits = 0, frac_bits = 0;
  double grid = 0.0;     // fixed: register resolution 2^-2 frac_bits
  double in_grid = 0.0;  // fixed: input resolution 2^-frac_bits
  double lim = kInf;     // fixed: 2^int_bits
  bool overflow = false;
  double max_abs = 0.0;

  explicit Arith4D(const Precision& p) : kind(p.kind), int_bits(p.int_bits), frac_bits(p.frac_bits) {
    if (kind == PrecisionKind::kFixed) {
      grid = std::ldexp(1.0, -2 * frac_bits);
      in_grid = std::ldexp(1.0, -frac_bits);
      lim = std::ldexp(1.0, int_bits);
    }
  }
  bool fixed() const { return kind == PrecisionKind::kFixed; }

  // The format's value nearest to x (fixed: on the register grid; overflow recorded).
  double reg(double x) {
    if (!fixed()) return static_cast<double>(static_cast<float>(x));
    if (!std::isfinite(x)) {
      overflow = true;
      return x;
    }
    const double r = std::nearbyint(x / grid) * grid;
    note(r);
    return r;
  }
  void note(double r) {
    const double a = std::fabs(r);
    if (a > max_abs) max_abs = a;
    if (a >= lim) overflow = true;
  }
  PVal rounded(double exact_double) {
    const double v = reg(exact_double);
    return {v, std::fabs(v - exact_double) + 0x1p-52 * std::fabs(exact_double)};
  }
  // An input of the datapath: fixed snaps to the sub-pixel grid and is exact from then on (the tile
  // widening covers the snapping); float32 rounds and carries the rounding.
  PVal input(double x) {
    if (fixed()) {
      const double r = std::nearbyint(x / in_grid) * in_grid;
      note(r);
      return {r, 0.0};
    }
    const double r = static_cast<double>(static_cast<float>(x));
    return {r, std::fabs(x - r)};
  }
  // A tile edge, moved outward onto the format (a larger tile): exact.
  PVal edge_lo(double x) {
    const double r = fixed() ? std::floor(x / in_grid) * in_grid : static_cast<double>(round_down_to_float(x));
    note_if_fixed(r);
    return {r, 0.0};
  }
  PVal edge_hi(double x) {
    const double r = fixed() ? std::ceil(x / in_grid) * in_grid : static_cast<double>(round_up_to_float(x));
    note_if_fixed(r);
    return {r, 0.0};
  }
  void note_if_fixed(double r) {
    if (fixed()) note(r);
  }
  // A value outside the datapath (a lens coordinate of the grid, a constant): the format's nearest, its
  // rounding carried.
  PVal constant(double x) { return rounded(x); }

  PVal add(PVal a, PVal b) {
    PVal r = rounded(a.v + b.v);
    r.e += a.e + b.e;
    return r;
  }
  PVal sub(PVal a, PVal b) { return add(a, PVal{-b.v, b.e}); }
  PVal mul(PVal a, PVal b) {
    PVal r = rounded(a.v * b.v);
    r.e += std::fabs(a.v) * b.e + std::fabs(b.v) * a.e + a.e * b.e;
    return r;
  }
  PVal madd(PVal a, PVal b, PVal c) { return add(mul(a, b), c); }
  // 1 / b: |1/b - 1/b'| <= e_b / (|b| (|b| - e_b)) for |b' - b| <= e_b < |b|. Fixed point holds the
  // reciprocal as a reciprocal unit delivers it, normalised: a mantissa of the register's width
  // (1 + int_bits + 2 frac_bits bits) and its exponent (on the register grid a large blur's 1/b of
  // 2^-11 would keep no significant bit at 4 fraction bits).
  PVal rcp(PVal b) {
    const double m = std::fabs(b.v);
    if (!(m > b.e) || !std::isfinite(m)) return {0.0, kInf};  // unbounded (an infinite b: ilogb(1/b) undefined)
    const double q = 1.0 / b.v;
    double v = static_cast<double>(static_cast<float>(q));
    if (fixed()) {
      const int shift = int_bits + 2 * frac_bits - (std::ilogb(q) + 1);
      v = std::ldexp(std::nearbyint(std::ldexp(q, shift)), -shift);
    }
    return {v, std::fabs(v - q) + 0x1p-52 * std::fabs(q) + b.e / (m * (m - b.e))};
  }
};

// One footprint vertex in the format: a, b and Eq. 1's delta = 1/b per axis, set up per triangle; k = sign of
// the format's b (0: no h_i line on that axis).
struct LensVertexIn {
  PVal ax, ay, bx, by, ibx, iby;
  int kx = 0, ky = 0;
};

inline LensVertexIn lens_vertex_in(Arith4D& ar, const LensVertex& v) {
  LensVertexIn p;
  p.ax = ar.input(v.ax), p.ay = ar.input(v.ay), p.bx = ar.input(v.bx), p.by = ar.input(v.by);
  p.kx = (p.bx.v > 0) - (p.bx.v < 0);
  p.ky = (p.by.v > 0) - (p.by.v < 0);
  if (p.kx != 0) p.ibx = ar.rcp(p.bx);
  if (p.ky != 0) p.iby = ar.rcp(p.by);
  return p;
}

// halfspace_lens.h axis_gaps in the format: per vertex and tile edge the lens coordinate c = (e - a) delta
// (Eq. 1 with delta = 1/b set up per triangle; the SUB before the MUL keeps delta's rounding multiplied by
// the vertex-to-edge distance, not by the tile coordinate as e delta + o would: the MADD form loses most
// h_i culls at large viewports), each gap bound moved inward by its bound (an upper end down, a lower end
// up), so a gap only shrinks. A vertex with b = 0 (in focus in the format) blocks a gap unless it lies beyond
// the edge by more than its bound.
inline Gaps axis_gaps_in(Arith4D& ar, const LensVertexIn* vs, int n, bool y_axis, double lo, double hi) {
  const PVal L = ar.edge_lo(lo), H = ar.edge_hi(hi);
  double L0 = -kInf, R0 = kInf, L1 = -kInf, R1 = kInf;
  Gaps g;
  for (int j = 0; j < n; ++j) {
    const LensVertexIn& v = vs[j];
    const int k = y_axis ? v.ky : v.kx;
    if (k == 0) {
      const PVal a = y_axis ? v.ay : v.ax;
      if (!(upper(a) < L.v)) g.blocked[0] = true;
      if (!(lower(a) > H.v)) g.blocked[1] = true;
      continue;
    }
    const PVal ib = y_axis ? v.iby : v.ibx, a = y_axis ? v.ay : v.ax;
    const PVal c_lo = ar.mul(ar.sub(L, a), ib), c_hi = ar.mul(ar.sub(H, a), ib);
    if (k > 0) {  // gap 0 is u < c_lo, gap 1 is u > c_hi
      R0 = std::min(R0, lower(c_lo));
      L1 = std::max(L1, upper(c_hi));
    } else {      // gap 0 is u > c_lo, gap 1 is u < c_hi
      L0 = std::max(L0, upper(c_lo));
      R1 = std::min(R1, lower(c_hi));
    }
  }
  g.L[0] = L0, g.R[0] = R0, g.L[1] = L1, g.R[1] = R1;
  return g;
}

// The h_i sets of one tile in the format (axis_set on the inward gaps). Returns false if either is empty.
inline bool h_sets_in(Arith4D& ar, const LensVertexIn* vs, int n, double x0, double x1, double y0, double y1,
                      AxisSet& sx, AxisSet& sy) {
  sx = axis_set<double>(axis_gaps_in(ar, vs, n, false, x0, x1));
  sy = axis_set<double>(axis_gaps_in(ar, vs, n, true, y0, y1));
  return !sx.empty && !sy.empty;
}

// The footprint's orientation over the lens square in the format: +1 / -1 where the bilinear signed
// area (2 x area, sum of P_k x P_k+1) is surely of that sign at the four lens corners, else 0.
inline int orientation_in(Arith4D& ar, const LensVertexIn* vs, int n) {
  int pos = 0, neg = 0;
  for (int c = 0; c < 4; ++c) {
    const PVal u = ar.constant((c & 1) ? 1.0 : -1.0), v = ar.constant((c & 2) ? 1.0 : -1.0);
    PVal area{0.0, 0.0};
    PVal x[6], yv[6];
    for (int j = 0; j < n; ++j) x[j] = ar.madd(u, vs[j].bx, vs[j].ax), yv[j] = ar.madd(v, vs[j].by, vs[j].ay);
    for (int j = 0; j < n; ++j) {
      const int k = (j + 1) % n;
      area = ar.add(area, ar.sub(ar.mul(x[j], yv[k]), ar.mul(yv[j], x[k])));
    }
    pos += lower(area) > 0.0;
    neg += upper(area) < 0.0;
  }
  return pos == 4 ? 1 : (neg == 4 ? -1 : 0);
}

// H_j in the format over the cells [i0, i1] x [j0, j1] of a G x G lens grid, for the expanded tile
// [x0, x1] x [y0, y1]: bit (j G + i) set where some active edge has sigma O < 0 over the whole cell at
// all four tile corners (O, sigma: header). edge_active[k]: edge (k, k+1) in use (the float64 set-up's
// choice: ignored edges and the selective-H oracle). any_line: some edge was evaluated.
inline CellMask hj_culled_in(Arith4D& ar, const LensVertexIn* vs, int n, const bool* edge_active, int sigma,
                             double x0, double x1, double y0, double y1, int G, int i0, int i1, int j0, int j1,
                             bool& any_line) {
  CellMask culled;
  any_line = false;
  if (sigma == 0) return culled;
  const PVal X[2] = {ar.edge_lo(x0), ar.edge_hi(x1)}, Y[2] = {ar.edge_lo(y0), ar.edge_hi(y1)};
  const double step = 2.0 / G, s = sigma;
  for (int k = 0; k < n; ++k) {
    if (!edge_active[k]) continue;
    const LensVertexIn &q = vs[k], &r = vs[(k + 1) % n];
    const PVal dax = ar.sub(r.ax, q.ax), day = ar.sub(r.ay, q.ay);
    const PVal dbx = ar.sub(r.bx, q.bx), dby = ar.sub(r.by, q.by);
    const PVal D = ar.sub(ar.mul(dby, q.bx), ar.mul(dbx, q.by));
    const PVal B0 = ar.mul(dax, q.by);
    const PVal A0 = ar.mul(day, q.bx);
    CellMask edge;
    edge.set();
    for (int c = 0; c < 4; ++c) {
      const PVal ty = ar.sub(Y[c >> 1], q.ay), tx = ar.sub(X[c & 1], q.ax);
      const PVal A = ar.add(ar.mul(dbx, ty), A0);
      const PVal B = ar.sub(PVal{-B0.v, B0.e}, ar.mul(dby, tx));
      const PVal C = ar.sub(ar.mul(dax, ty), ar.mul(day, tx));
      // sigma O over a cell <= s C + max_cell(s A u) + max_cell(s B v) + (e_A + e_B + e_C + |D| + e_D),
      // |u|, |v| <= 1; evaluated in double with a relative slack for its own rounding.
      const double sA = s * A.v, sB = s * B.v;
      const double bound = A.e + B.e + C.e + std::fabs(D.v) + D.e +
                           0x1p-48 * (std::fabs(A.v) + std::fabs(B.v) + std::fabs(C.v));
      CellMask corner;
      for (int j = j0; j <= j1; ++j) {
        const double v_hi = -1.0 + step * (sB >= 0 ? j + 1 : j);
        const double row = s * C.v + sB * v_hi + bound;
        for (int i = i0; i <= i1; ++i) {
          const double u_hi = -1.0 + step * (sA >= 0 ? i + 1 : i);
          if (row + sA * u_hi < 0.0) corner.set(j * G + i);
        }
      }
      edge &= corner;
    }
    culled |= edge;
    any_line = true;
  }
  return culled;
}

// box_bounds.h in the format: per vertex a + u b at the box's lens corners, moved outward by its bound.
inline void box_bounds_in(Arith4D& ar, const LensVertex* lv, int n, double u0, double u1, double v0, double v1,
                          double& lx, double& hx, double& ly, double& hy) {
  lx = kInf, hx = -kInf, ly = kInf, hy = -kInf;
  const PVal U[2] = {ar.constant(u0), ar.constant(u1)}, V[2] = {ar.constant(v0), ar.constant(v1)};
  for (int j = 0; j < n; ++j) {
    const LensVertexIn p = lens_vertex_in(ar, lv[j]);
    for (int c = 0; c < 2; ++c) {
      const PVal x = ar.madd(U[c], p.bx, p.ax), y = ar.madd(V[c], p.by, p.ay);
      lx = std::min(lx, lower(x)), hx = std::max(hx, upper(x));
      ly = std::min(ly, lower(y)), hy = std::max(hy, upper(y));
    }
  }
}

// The bounds of box_bounds.h in precision p (not float64), replacing lx .. hy; returns true on overflow.
inline bool box_bounds_in(const Precision& p, const LensVertex* lv, int n, double u0, double u1, double v0, double v1,
                          double& lx, double& hx, double& ly, double& hy) {
  Arith4D ar(p);
  box_bounds_in(ar, lv, n, u0, u1, v0, v1, lx, hx, ly, hy);
  return ar.overflow;
}

// ẑ = [zlo, zhi] rounded outward to the format (fixed: the register grid; float32: binary32).
inline void zhat_round_out(const Precision& p, double& zlo, double& zhi) {
  if (p.kind == PrecisionKind::kFloat32) {
    if (std::isfinite(zlo)) zlo = round_down_to_float(zlo);
    if (std::isfinite(zhi)) zhi = round_up_to_float(zhi);
  } else if (p.kind == PrecisionKind::kFixed) {
    const double g = std::ldexp(1.0, -2 * p.frac_bits);
    if (std::isfinite(zlo)) zlo = std::floor(zlo / g) * g;
    if (std::isfinite(zhi)) zhi = std::ceil(zhi / g) * g;
  }
}

// ---- the per-triangle state of a tile algorithm ---------------------------------------------------------
// set up once per triangle from the float64 footprint (lens vertices, edge activity); active() is false for
// float64 (the render then never calls the *_in forms).
struct Tile4DPrecision {
  Precision p = Precision::float64();
  Arith4D ar{Precision::float64()};
  int n = 0, sigma = 0;
  LensVertexIn lv[6];
  bool edge_active[6] = {false, false, false, false, false, false};

  bool active() const { return p.kind != PrecisionKind::kFloat64; }
  // The lens vertices (and, with H, the edges' activity) of one triangle.
  void setup(const Precision& prec, const LensVertex* vs, int count, const bool* active_edges, bool with_H) {
    p = prec;
    ar = Arith4D(prec);
    n = count;
    for (int j = 0; j < n; ++j) lv[j] = lens_vertex_in(ar, vs[j]);
    for (int j = 0; j < 6; ++j) edge_active[j] = with_H && active_edges && j < n && active_edges[j];
    sigma = with_H ? orientation_in(ar, lv, n) : 0;
    setup_overflow = ar.overflow;
  }
  // The h_i sets of one tile in the format; overflow: a register of the set-up or of this test reached
  // 2^int_bits.
  bool h_sets(double x0, double x1, double y0, double y1, AxisSet& sx, AxisSet& sy, bool& overflow) {
    ar.overflow = false;
    const bool keep = h_sets_in(ar, lv, n, x0, x1, y0, y1, sx, sy);
    overflow = ar.overflow || setup_overflow;
    return keep;
  }
  // The H_j cells of one tile in the format (hj_culled_in).
  CellMask hj_cells(double x0, double x1, double y0, double y1, int G, int i0, int i1, int j0, int j1,
                    bool& any_line, bool& overflow) {
    ar.overflow = false;
    const CellMask m = hj_culled_in(ar, lv, n, edge_active, sigma, x0, x1, y0, y1, G, i0, i1, j0, j1, any_line);
    overflow = ar.overflow || setup_overflow;
    return m;
  }
  bool setup_overflow = false;
};

}  // namespace rast5d::tiletest
