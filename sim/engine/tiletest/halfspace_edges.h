// H_j lines ([Akenine-Möller 2012] §4.3, Eq. 4-5): per triangle edge, lens lines that cull the
// lens points from which the tile lies outside the projected edge, evaluated over lens-grid cells.
//
// The tile is outside edge (q, r) iff every tile corner T is on the other side of the projected
// edge from the triangle: sign det[q - L, r - L, T - L] = -sign det[q - L, r - L, s - L] for lens
// point L. Both determinants are affine in (u, v): det[q-L, r-L, T-L] is the plane through q, r and
// T (Eq. 5: n = q x r + (r - q) x T, c = -T . (q x r)) evaluated at L (Eq. 4), and
// det[q-L, r-L, s-L] is the triangle's orientation seen from L (its sign sigma is constant over
// the lens unless the lens sees the triangle edge-on; then H_j culls per lens cell of one sign,
// setup/footprint.h). All projected edge lines pass through v, the edge's intersection with the
// focus plane, so only the two tile corners subtending the largest angle at v matter ([Akenine-Möller 2012]'s
// nine-region table): the other corners lie in the cone they span. The edge culls lens point L iff
// BOTH tangent planes have sigma * H < 0. ([Akenine-Möller 2012] prunes candidates whose plane is not separating and
// flips the culling direction between uv-box A and B; with the orientation sigma of the whole
// triangle the two rules coincide, and ANDing both tangent lines is exact in every region case,
// including the one where both candidates separate.) Region 5 (v inside the tile) gives no line;
// edges with q_w = r_w = F are ignored ([Akenine-Möller 2012] §4.3); d_w = 0 edges take the corners from (d_x, d_y).
//
// Contract (tiletest/common.h): line_cells marks a lens cell only where the line is negative over the
// whole cell, so an edge culls only cells from which the expanded tile is outside the edge.
#pragma once

#include <cstdint>

#include "core/arith.h"
#include "core/costs.h"
#include "tiletest/common.h"

namespace rast5d::tiletest {

// Per-edge constants (setup). For tile corner (Xc, Yc) in pixels, with Q = q x r and d = r - q in
// pixel-homogeneous (X, Y, W), the plane through q, r and T = F (Xc, Yc, 1) evaluated at lens
// point L = (u Kx F, v Ky F, 0), divided by F > 0, is H(u, v) = A u + B v + C with
//   A = -Kx (Q_x + F d_y) + Kx F d_w Yc,  B = -Ky (Q_y - F d_x) - Ky F d_w Xc,
//   C = Q_x Xc + Q_y Yc + Q_w                        ([Akenine-Möller 2012] Eq. 4-5 in our coordinates).
struct EdgeH {
  bool active = false;  // false: ignored (q_w = r_w = F), disabled by the oracle, or degenerate
  double a0, a1, b0, b1, cx, cy, c0;
  bool parallel = false;  // d_w == 0: no focus-plane intersection; corners from (d_x, d_y)
  double vx = 0, vy = 0;  // focus-plane intersection v, in pixels
  int par_m = 0, par_n = 0;  // tangent corners for parallel edges (corner = bit0: x high, bit1: y high)
};

// Cost: cost::kEdgeSetup for a crossing edge, cost::kEdgeSetupParallel when d_w == 0.
template <class D>
inline EdgeH edge_setup(const double q[3], const double r[3], D focus, D coc_x, D coc_y) {
  EdgeH e;
  const D qx(q[0]), qy(q[1]), qw(q[2]), rx(r[0]), ry(r[1]), rw(r[2]);
  const D Qx = madd(qy, rw, -(qw * ry));
  const D Qy = madd(qw, rx, -(qx * rw));
  const D Qw = madd(qx, ry, -(qy * rx));
  const D dx = rx - qx, dy = ry - qy, dw = rw - qw;
  const D kxf = coc_x * focus, kyf = coc_y * focus;
  e.a0 = raw(-(coc_x * madd(focus, dy, Qx)));
  e.a1 = raw(kxf * dw);
  e.b0 = raw(-(coc_y * madd(-focus, dx, Qy)));
  e.b1 = raw(-(kyf * dw));
  e.cx = raw(Qx), e.cy = raw(Qy), e.c0 = raw(Qw);
  e.active = true;
  if (raw(dw) == 0.0) {
    e.parallel = true;
    // max / min over corners of n_xy . t with n_xy proportional to (-d_y, d_x) (q_w > 0).
    const double nx = -raw(dy), ny = raw(dx);
    e.par_m = (nx >= 0 ? 1 : 0) | (ny >= 0 ? 2 : 0);
    e.par_n = 3 - e.par_m;
    if (q[2] == raw(focus)) e.active = false;  // q_w = r_w = F: ignored ([Akenine-Möller 2012] §4.3)
  } else {
    const D t = (focus - qw) * rcp(dw);
    const D inv_f = rcp(focus);
    e.vx = raw(madd(t, dx, qx) * inv_f);
    e.vy = raw(madd(t, dy, qy) * inv_f);
  }
  return e;
}

// The nine-region table ([Akenine-Möller 2012] §4.3): the two tile corners subtending the largest angle at v.
// Corners are numbered bit0 = x high, bit1 = y high. Returns false in region 5 (no line).
// Cost: cost::kTangentCorners (0 for parallel edges).
template <class D>
inline bool tangent_corners(const EdgeH& e, double x0, double x1, double y0, double y1, int& m, int& n) {
  if (e.parallel) {
    m = e.par_m, n = e.par_n;
    return true;
  }
  const bool left = D(e.vx) < D(x0), right = D(e.vx) > D(x1);
  const bool below = D(e.vy) < D(y0), above = D(e.vy) > D(y1);
  const int cx = left ? -1 : (right ? 1 : 0), cy = below ? -1 : (above ? 1 : 0);
  // Corner index: bit0 = x high, bit1 = y high. Row: cy + 1 (v below / within / above the
  // tile in y), column: cx + 1 (left / within / right). Derivation: docs/tile_tests.md.
  static constexpr int kM[3][3] = {{1, 0, 0}, {0, -1, 1}, {0, 2, 1}};
  static constexpr int kN[3][3] = {{2, 1, 3}, {2, -1, 3}, {3, 3, 2}};
  if (cx == 0 && cy == 0) return false;
  m = kM[cy + 1][cx + 1];
  n = kN[cy + 1][cx + 1];
  return true;
}

struct Line {
  double A, B, C;  // sigma * H(u, v) = A u + B v + C; the edge culls where this is < 0
};

// Cost: cost::kLineAtCorner.
template <class D>
inline Line line_at_corner(const EdgeH& e, double xc, double yc, int sigma) {
  const D A = madd(D(e.a1), D(yc), D(e.a0));
  const D B = madd(D(e.b1), D(xc), D(e.b0));
  const D C = madd(D(e.cx), D(xc), madd(D(e.cy), D(yc), D(e.c0)));
  const double s = sigma;
  return Line{s * raw(A), s * raw(B), s * raw(C)};
}

// Cell masks: a CellMask, or a 64-bit integer for grids up to 8 x 8 (the fast path's).
inline void set_cell(CellMask& m, int c) { m.set(c); }
inline void set_cell(std::uint64_t& m, int c) { m |= std::uint64_t(1) << c; }

// Evaluate a line at the most positive corner of each lens cell in the rectangle
// [i0, i1] x [j0, j1] of a G x G grid; bit (j * G + i) of `negative` is set where the line is
// negative over the whole cell. Cost: line_cells_cost(rows, cols). M = std::uint64_t needs G <= 8.
template <class D, class M = CellMask>
inline M line_cells(const Line& l, int grid, int i0, int i1, int j0, int j1) {
  const double step = 2.0 / grid;
  const bool a_pos = D(l.A) >= D(0.0);
  const bool b_pos = D(l.B) >= D(0.0);
  const double u_first = -1.0 + step * (a_pos ? i0 + 1 : i0);
  const double v_first = -1.0 + step * (b_pos ? j0 + 1 : j0);
  const D su = D(l.A) * D(step), sv = D(l.B) * D(step);
  D row = madd(D(l.A), D(u_first), madd(D(l.B), D(v_first), D(l.C))) - su;
  M negative{};
  for (int j = j0; j <= j1; ++j) {
    D val = row;
    for (int i = i0; i <= i1; ++i) {
      val = val + su;
      if (val < D(0.0)) set_cell(negative, j * grid + i);
    }
    row = row + sv;
  }
  return negative;
}

// Documented cost of line_cells over rows x cols lens cells: cost::kLineCellsBase, 1 per row, 2 per
// cell.
inline std::uint64_t line_cells_cost(std::uint64_t rows, std::uint64_t cols) {
  return cost::kLineCellsBase + rows + 2 * rows * cols;
}

}  // namespace rast5d::tiletest
