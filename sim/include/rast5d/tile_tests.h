// Tile tests: pure functions from (triangle footprint, screen tile) to conservative lens regions.
//
// Contract: every test is *conservative*: it never removes a (u, v) from which the float sample
// test could hit a sample of the tile. They run in double on the tile expanded by a margin
// (kMarginAbs + kMarginRel * |coordinate| pixels), far larger than the float sample test's error,
// and invariant 1 (tests/test_tile_invariants.py) checks it against brute force.
//
// Geometry (001_3248aaf17c219d5e.txt §4; mapping in docs/conventions.md). Seen from lens point
// (u, v), a footprint vertex (X, Y, W) with W > 0 lands at pixel
//     x(u) = X/W + u * Kx * (1 - F/W) = a_x + u b_x,      y(v) = a_y + v b_y.
// A tile [X0, X1] x [Y0, Y1] can see the triangle from (u, v) only if the projected triangle
// overlaps it. By the separating-axis theorem two convex polygons are disjoint iff an axis of
// one of their edges separates them:
//  * the tile's axes (x and y) give the h_i lines (001 §4.2, Eq. 1-3): on the x axis the triangle
//    is left of the tile iff every a_j + u b_j < X0, an intersection of half-lines in u — one per
//    vertex, u < (X0 - a_j)/b_j for b_j > 0 (behind the focus plane), u > ... for b_j < 0 (in
//    front) — i.e. an open *gap* (L1, R1) of u. Likewise right of the tile: gap (L2, R2). The
//    active u set is [-1, 1] minus the two gaps: one interval when all vertices are on one side of
//    the focus plane (001 Fig. 5), two or three when the triangle crosses it (001 Fig. 6-7: the
//    "inner" region is culled). The (u, v) active region of the h_i lines is the product of the
//    u and v sets: these are our uv-boxes. Vertices with W == F (b = 0) give no line (001: "such
//    vertices are always ignored"), but they still block a gap when they project into the tile.
//  * the triangle's edge axes give the H_j lines (001 §4.3, Eq. 4-5): the tile is outside edge
//    (q, r) iff every tile corner T is on the other side of the projected edge from the triangle:
//    sign det[q - L, r - L, T - L] = -sign det[q - L, r - L, s - L] for lens point L. Both
//    determinants are affine in (u, v): det[q-L, r-L, T-L] is the plane through q, r and T
//    (Eq. 5: n = q x r + (r - q) x T, c = -T . (q x r)) evaluated at L (Eq. 4), and
//    det[q-L, r-L, s-L] is the triangle's orientation seen from L (its sign sigma is constant over
//    the lens unless the lens sees the triangle edge-on; then we skip H_j culling, counted).
//    All projected edge lines pass through v, the edge's intersection with the focus plane, so
//    only the two tile corners subtending the largest angle at v matter (001's nine-region table):
//    the other corners lie in the cone they span. The edge culls lens point L iff BOTH tangent
//    planes have sigma * H < 0. (001 prunes candidates whose plane is not separating and flips the
//    culling direction between uv-box A and B; with the orientation sigma of the whole triangle
//    the two rules coincide, and ANDing both tangent lines is exact in every region case, including
//    the one where both candidates separate.) Region 5 (v inside the tile) gives no line; edges
//    with q_w = r_w = F are ignored (001 §4.3); d_w = 0 edges take the corners from (d_x, d_y).
#pragma once

#include <algorithm>
#include <bitset>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "rast5d/arith.h"
#include "rast5d/costs.h"
#include "rast5d/params.h"

namespace rast5d::tiletest {

inline constexpr double kMarginAbs = 0x1p-10;  // pixels
inline constexpr double kMarginRel = 0x1p-18;  // of the tile coordinate's magnitude
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr float kInfF = std::numeric_limits<float>::infinity();

inline float round_up_to_float(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, kInfF);
  return f;
}
inline float round_down_to_float(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -kInfF);
  return f;
}

// One bit per lens-grid cell (G <= 16), bit j * G + i.
using CellMask = std::bitset<256>;

inline double expand_lo(double x) { return x - (kMarginAbs + kMarginRel * std::fabs(x)); }
inline double expand_hi(double x) { return x + (kMarginAbs + kMarginRel * std::fabs(x)); }

// ---- per-vertex lens projection (setup) ---------------------------------------------------------

struct LensVertex {
  double ax, ay;   // pixel position seen from the lens centre
  double bx, by;   // d x / d u and d y / d v
  double ibx, iby; // 1 / b (Eq. 1's delta), 0 if b == 0
  double ox, oy;   // -a / b (Eq. 1's offset): the lens coordinate where x(u) = X0 is X0 * ib + o
  int kx, ky;      // sign of b per axis: +1, -1, or 0 (W == F: no line)
};

// Cost: cost::kLensVertexBase (6: RCP, 2 MUL, MADD, 2 MUL) + cost::kLensVertexAxis (2: RCP, MUL)
// per axis whose slope b is non-zero (b == 0: the vertex is on the focus plane or the camera has
// no blur, and gives no h_i line on that axis).
template <class D>
inline LensVertex lens_vertex(D X, D Y, D W, D neg_focus, D coc_x, D coc_y) {
  LensVertex v{};
  const D r = rcp(W);
  const D ax = X * r, ay = Y * r;
  const D g = madd(neg_focus, r, D(1.0));
  const D bx = g * coc_x, by = g * coc_y;
  v.ax = raw(ax), v.ay = raw(ay), v.bx = raw(bx), v.by = raw(by);
  v.kx = (v.bx > 0) - (v.bx < 0);
  v.ky = (v.by > 0) - (v.by < 0);
  v.ibx = v.iby = v.ox = v.oy = 0.0;
  if (v.kx != 0) {
    const D ibx = rcp(bx);
    v.ibx = raw(ibx);
    v.ox = raw(-(ax * ibx));
  }
  if (v.ky != 0) {
    const D iby = rcp(by);
    v.iby = raw(iby);
    v.oy = raw(-(ay * iby));
  }
  return v;
}

inline std::uint64_t lens_vertex_cost(const LensVertex& v) {
  return cost::kLensVertexBase + (v.kx != 0 ? cost::kLensVertexAxis : 0) + (v.ky != 0 ? cost::kLensVertexAxis : 0);
}

// Documented cost of the gap bounds of one axis (y: the v axis) over n lens vertices (axis_gaps).
inline std::uint64_t axis_gaps_cost(const LensVertex* lv, int n, bool y) {
  std::uint64_t c = 0;
  for (int j = 0; j < n; ++j) c += ((y ? lv[j].ky : lv[j].kx) != 0) ? cost::kGapVertex : cost::kGapVertexInFocus;
  return c;
}

// Documented cost of line_cells over rows x cols lens cells.
inline std::uint64_t line_cells_cost(std::uint64_t rows, std::uint64_t cols) {
  return cost::kLineCellsBase + rows + 2 * rows * cols;
}

// ---- h_i lines: the active lens interval set of one axis -------------------------------------

struct Gaps {
  double L[2] = {-kInf, -kInf};  // gap k is the open interval (L[k], R[k]); k = 0: all vertices
  double R[2] = {kInf, kInf};    // before the tile's low edge, k = 1: all after its high edge
  bool blocked[2] = {false, false};  // a W == F vertex inside the tile range: no gap
};

// Cost per vertex: 4 (2 MADD, MIN, MAX) with a line, 2 CMP for a W == F vertex.
template <class D>
inline Gaps axis_gaps(const LensVertex* vs, int n, bool y_axis, D lo, D hi) {
  D L0(-kInf), R0(kInf), L1(-kInf), R1(kInf);
  Gaps g;
  for (int j = 0; j < n; ++j) {
    const LensVertex& v = vs[j];
    const int k = y_axis ? v.ky : v.kx;
    if (k == 0) {
      const D a(y_axis ? v.ay : v.ax);
      if (!(a < lo)) g.blocked[0] = true;
      if (!(a > hi)) g.blocked[1] = true;
      continue;
    }
    const D ib(y_axis ? v.iby : v.ibx), o(y_axis ? v.oy : v.ox);
    const D c_lo = madd(lo, ib, o);  // lens coordinate where the vertex sits on the low edge
    const D c_hi = madd(hi, ib, o);
    if (k > 0) {  // moves with u: before the low edge for u < c_lo, after the high edge for u > c_hi
      R0 = vmin(R0, c_lo);
      L1 = vmax(L1, c_hi);
    } else {
      L0 = vmax(L0, c_lo);
      R1 = vmin(R1, c_hi);
    }
  }
  g.L[0] = raw(L0), g.R[0] = raw(R0), g.L[1] = raw(L1), g.R[1] = raw(R1);
  return g;
}

// The active set of one axis within the lens square [-1, 1]: [-1, 1] minus the gaps that reach
// into it. A cut with lo == -inf covers everything below hi (one comparison per sample), with
// hi == +inf everything above lo; an interior cut needs two.
struct AxisSet {
  bool empty = false;
  int n_cuts = 0;
  double cut_lo[2] = {0, 0}, cut_hi[2] = {0, 0};
  // The cuts as float open intervals, rounded inwards (so a float sample compared against them is
  // culled only if it is inside the double cut: conservative). Unused cuts are (+inf, -inf).
  float fl_lo[2] = {kInfF, kInfF}, fl_hi[2] = {-kInfF, -kInfF};
  int n_cmp = 0;        // per-sample comparisons (ops.sample_region)
  int n_intervals = 0;  // disjoint active intervals (uv-box factor)
  double iv_lo[3] = {0, 0, 0}, iv_hi[3] = {0, 0, 0};
};

// Cost: 5 CMP per gap that is not blocked.
template <class D>
inline AxisSet axis_set(const Gaps& g) {
  AxisSet s;
  for (int k = 0; k < 2; ++k) {
    if (g.blocked[k]) continue;
    const D L(g.L[k]), R(g.R[k]);
    const bool nonempty = L < R;
    const bool reaches_lo = R > D(-1.0);
    const bool reaches_hi = L < D(1.0);
    const bool open_lo = L < D(-1.0);
    const bool open_hi = R > D(1.0);
    if (!(nonempty && reaches_lo && reaches_hi)) continue;
    if (open_lo && open_hi) {  // the gap covers the whole lens: nothing is active
      s.empty = true;
      continue;  // (the other gap is still evaluated: fixed cost per gap)
    }
    s.cut_lo[s.n_cuts] = open_lo ? -kInf : g.L[k];
    s.cut_hi[s.n_cuts] = open_hi ? kInf : g.R[k];
    s.fl_lo[s.n_cuts] = open_lo ? -kInfF : round_up_to_float(g.L[k]);
    s.fl_hi[s.n_cuts] = open_hi ? kInfF : round_down_to_float(g.R[k]);
    s.n_cmp += (open_lo || open_hi) ? 1 : 2;
    ++s.n_cuts;
  }
  if (s.empty) {
    s.n_cuts = 0, s.n_cmp = 0, s.n_intervals = 0;
    return s;
  }
  // Active intervals, for counting uv-boxes and the lens-shape overlap test (control logic only).
  double lo[2] = {s.cut_lo[0], s.cut_lo[1]}, hi[2] = {s.cut_hi[0], s.cut_hi[1]};
  if (s.n_cuts == 2 && lo[1] < lo[0]) std::swap(lo[0], lo[1]), std::swap(hi[0], hi[1]);
  double start = -1.0;
  for (int k = 0; k < s.n_cuts; ++k) {
    if (lo[k] > start) {
      s.iv_lo[s.n_intervals] = start;
      s.iv_hi[s.n_intervals] = std::min(lo[k], 1.0);
      ++s.n_intervals;
    }
    start = std::max(start, hi[k]);
  }
  if (start <= 1.0) {
    s.iv_lo[s.n_intervals] = start;
    s.iv_hi[s.n_intervals] = 1.0;
    ++s.n_intervals;
  }
  s.empty = s.n_intervals == 0;
  return s;
}

// Is the (float) lens coordinate x outside every cut? Cost: s.n_cmp CMP. The counting path performs
// exactly the n_cmp comparisons the hardware needs; the fast path evaluates them branch-free
// (unused and infinite bounds compare trivially). Both compare against the same float bounds.
template <class F>
inline bool axis_pass(const AxisSet& s, F x) {
  if constexpr (is_counted_v<F>) {
    bool pass = true;
    for (int k = 0; k < s.n_cuts; ++k) {
      bool above = true, below = true;
      if (s.cut_lo[k] != -kInf) above = x > F(s.fl_lo[k]);
      if (s.cut_hi[k] != kInf) below = x < F(s.fl_hi[k]);
      if (above && below) pass = false;
    }
    return pass;
  } else {
    const float v = x;
    const bool in0 = (v > s.fl_lo[0]) & (v < s.fl_hi[0]);
    const bool in1 = (v > s.fl_lo[1]) & (v < s.fl_hi[1]);
    return !(in0 | in1);
  }
}

// Fast-path candidate selection for one pixel: flag[s] = sample s is in an active lens cell
// (bit cell[s] of active, G * G <= 64; kCells = false: every cell) and passes both axis sets.
template <bool kCells>
[[gnu::noinline]] inline void select_candidates(int spp, const float* __restrict u, const float* __restrict v,
                                                 const std::uint8_t* __restrict cell, std::uint64_t active,
                                                 const AxisSet& su, const AxisSet& sv,
                                                 std::uint8_t* __restrict flags) {
  const float a0 = su.fl_lo[0], b0 = su.fl_hi[0], a1 = su.fl_lo[1], b1 = su.fl_hi[1];
  const float c0 = sv.fl_lo[0], d0 = sv.fl_hi[0], c1 = sv.fl_lo[1], d1 = sv.fl_hi[1];
  for (int s = 0; s < spp; ++s) {
    const float x = u[s], y = v[s];
    const int in_u = ((x > a0) & (x < b0)) | ((x > a1) & (x < b1));
    const int in_v = ((y > c0) & (y < d0)) | ((y > c1) & (y < d1));
    int act = 1;
    if constexpr (kCells) act = static_cast<int>((active >> cell[s]) & 1u);
    flags[s] = static_cast<std::uint8_t>(act & (1 - in_u) & (1 - in_v));
  }
}

// Indices of the set flags, in order (skipping 8 zero flags at a time).
inline int compact_flags(const std::uint8_t* flags, int n, int* out) {
  int m = 0;
  for (int w = 0; w < n; w += 8) {
    std::uint64_t word = 0;
    std::memcpy(&word, flags + w, 8);
    if (!word) continue;
    const int end = std::min(n, w + 8);
    for (int i = w; i < end; ++i) {
      out[m] = i;
      m += flags[i];
    }
  }
  return m;
}

// Lens-grid cells of one axis that intersect the active set, as a bit mask (bit i = cell i).
// Cell i covers [-1 + 2i/G, -1 + 2(i+1)/G). A cell is dropped only if it lies inside a cut
// (001 §5.1: "clamp them down and up to the nearest grid cell").
// Cost: 1 MADD per finite cut end.
template <class D>
inline std::uint32_t axis_cells(const AxisSet& s, int grid) {
  std::uint32_t bits = grid >= 32 ? 0xffffffffu : ((1u << grid) - 1u);
  const D half_g(0.5 * grid);
  for (int k = 0; k < s.n_cuts; ++k) {
    // Cells fully inside (lo, hi): lo < -1 + 2i/G and -1 + 2(i+1)/G <= hi, i.e. gl < i <= gh - 1.
    int first = 0, last = grid - 1;
    if (s.cut_lo[k] != -kInf) {
      const double gl = raw(madd(D(s.cut_lo[k]), half_g, half_g));
      first = static_cast<int>(std::floor(gl)) + 1;
    }
    if (s.cut_hi[k] != kInf) {
      const double gh = raw(madd(D(s.cut_hi[k]), half_g, half_g));
      last = static_cast<int>(std::floor(gh)) - 1;
    }
    first = std::max(first, 0), last = std::min(last, grid - 1);
    for (int i = first; i <= last; ++i) bits &= ~(1u << i);
  }
  return bits;
}

// ---- lens shape -----------------------------------------------------------------------------

// Does the box [u0, u1] x [v0, v1] (inside [-1, 1]^2) overlap the lens shape?
// Cost: 0 (square), kCostBoxDisk = 7 (disk), kCostBoxHexagon = 14 (hexagon).
template <class D>
inline bool box_overlaps_lens(LensShape shape, double u0, double u1, double v0, double v1) {
  if (shape == LensShape::kSquare) return true;
  if (shape == LensShape::kDisk) {
    const D cu = vmax(D(u0), vmin(D(0.0), D(u1)));  // closest point to the centre
    const D cv = vmax(D(v0), vmin(D(0.0), D(v1)));
    const D d2 = madd(cu, cu, cv * cv);
    return !(d2 > D(1.0));
  }
  // Hexagon with vertices (+-1, 0), (+-1/2, +-sqrt(3)/2): separating axes v and the two slanted
  // edge normals (sqrt(3)/2, +-1/2) (the u axis is inside [-1, 1] already).
  constexpr double h = 0.86602540378443864676;  // sqrt(3)/2
  const bool v_sep_lo = D(v1) < D(-h);
  const bool v_sep_hi = D(v0) > D(h);
  // n = (h, 1/2): box max along n below -h, or box min above h; same for n = (h, -1/2).
  const D p1_max = madd(D(h), D(u1), D(0.5) * D(v1));
  const D p1_min = madd(D(h), D(u0), D(0.5) * D(v0));
  const D p2_max = madd(D(h), D(u1), D(-0.5) * D(v0));
  const D p2_min = madd(D(h), D(u0), D(-0.5) * D(v1));
  const bool s1 = p1_max < D(-h);
  const bool s2 = p1_min > D(h);
  const bool s3 = p2_max < D(-h);
  const bool s4 = p2_min > D(h);
  return !(v_sep_lo || v_sep_hi || s1 || s2 || s3 || s4);
}

// ---- H_j lines --------------------------------------------------------------------------------

// Per-edge constants (setup). For tile corner (Xc, Yc) in pixels, with Q = q x r and d = r - q in
// pixel-homogeneous (X, Y, W), the plane through q, r and T = F (Xc, Yc, 1) evaluated at lens
// point L = (u Kx F, v Ky F, 0), divided by F > 0, is H(u, v) = A u + B v + C with
//   A = -Kx (Q_x + F d_y) + Kx F d_w Yc,  B = -Ky (Q_y - F d_x) - Ky F d_w Xc,
//   C = Q_x Xc + Q_y Yc + Q_w                        (001 Eq. 4-5 in our coordinates).
struct EdgeH {
  bool active = false;  // false: ignored (q_w = r_w = F), disabled by the oracle, or degenerate
  double a0, a1, b0, b1, cx, cy, c0;
  bool parallel = false;  // d_w == 0: no focus-plane intersection; corners from (d_x, d_y)
  double vx = 0, vy = 0;  // focus-plane intersection v, in pixels
  int par_m = 0, par_n = 0;  // tangent corners for parallel edges (corner = bit0: x high, bit1: y high)
};

// Cost: kCostEdgeSetup (22) for a crossing edge, kCostEdgeSetupParallel (15) when d_w == 0.
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
    if (q[2] == raw(focus)) e.active = false;  // q_w = r_w = F: ignored (001 §4.3)
  } else {
    const D t = (focus - qw) * rcp(dw);
    const D inv_f = rcp(focus);
    e.vx = raw(madd(t, dx, qx) * inv_f);
    e.vy = raw(madd(t, dy, qy) * inv_f);
  }
  return e;
}

// The nine-region table (001 §4.3): the two tile corners subtending the largest angle at v.
// Corners are numbered bit0 = x high, bit1 = y high. Returns false in region 5 (no line).
// Cost: 4 CMP.
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

// Cost: kCostLineAtCorner (4 MADD).
template <class D>
inline Line line_at_corner(const EdgeH& e, double xc, double yc, int sigma) {
  const D A = madd(D(e.a1), D(yc), D(e.a0));
  const D B = madd(D(e.b1), D(xc), D(e.b0));
  const D C = madd(D(e.cx), D(xc), madd(D(e.cy), D(yc), D(e.c0)));
  const double s = sigma;
  return Line{s * raw(A), s * raw(B), s * raw(C)};
}

// Evaluate a line at the most positive corner of each lens cell in the rectangle
// [i0, i1] x [j0, j1] of a G x G grid; bit (j * G + i) of `negative` is set where the line is
// negative over the whole cell. Cost: cost::kLineCellsBase (7) + rows + 2 per cell.
template <class D>
inline CellMask line_cells(const Line& l, int grid, int i0, int i1, int j0, int j1) {
  const double step = 2.0 / grid;
  const bool a_pos = D(l.A) >= D(0.0);
  const bool b_pos = D(l.B) >= D(0.0);
  const double u_first = -1.0 + step * (a_pos ? i0 + 1 : i0);
  const double v_first = -1.0 + step * (b_pos ? j0 + 1 : j0);
  const D su = D(l.A) * D(step), sv = D(l.B) * D(step);
  D row = madd(D(l.A), D(u_first), madd(D(l.B), D(v_first), D(l.C))) - su;
  CellMask negative;
  for (int j = j0; j <= j1; ++j) {
    D val = row;
    for (int i = i0; i <= i1; ++i) {
      val = val + su;
      if (val < D(0.0)) negative.set(j * grid + i);
    }
    row = row + sv;
  }
  return negative;
}

// ---- screen bounds over a lens box (INTERVAL, INTERLEAVE) -----------------------------------

// Bounds of the footprint seen from every lens point of [u0, u1] x [v0, v1]. Per vertex and axis:
// 2 MADD + MIN + MAX (a vertex on the focus plane: MIN + MAX). With u0 == u1 and v0 == v1 (one
// lens coordinate) one MADD per axis suffices. Cost: see box_bounds_cost().
template <class D>
inline void box_bounds(const LensVertex* lv, int n, double u0, double u1, double v0, double v1, double& lx,
                       double& hx, double& ly, double& hy) {
  const bool point = (u0 == u1) && (v0 == v1);
  D LX(kInf), HX(-kInf), LY(kInf), HY(-kInf);
  for (int j = 0; j < n; ++j) {
    const LensVertex& v = lv[j];
    D xlo(v.ax), xhi(v.ax), ylo(v.ay), yhi(v.ay);
    if (v.kx != 0) {
      if (point) {
        xlo = xhi = madd(D(u0), D(v.bx), D(v.ax));
      } else {
        xlo = madd(D(v.kx > 0 ? u0 : u1), D(v.bx), D(v.ax));
        xhi = madd(D(v.kx > 0 ? u1 : u0), D(v.bx), D(v.ax));
      }
    }
    if (v.ky != 0) {
      if (point) {
        ylo = yhi = madd(D(v0), D(v.by), D(v.ay));
      } else {
        ylo = madd(D(v.ky > 0 ? v0 : v1), D(v.by), D(v.ay));
        yhi = madd(D(v.ky > 0 ? v1 : v0), D(v.by), D(v.ay));
      }
    }
    LX = vmin(LX, xlo), HX = vmax(HX, xhi), LY = vmin(LY, ylo), HY = vmax(HY, yhi);
  }
  lx = raw(LX), hx = raw(HX), ly = raw(LY), hy = raw(HY);
}

inline std::uint64_t box_bounds_cost(const LensVertex* lv, int n, bool point) {
  std::uint64_t c = 0;
  for (int j = 0; j < n; ++j) c += 4 + (lv[j].kx ? (point ? 1 : 2) : 0) + (lv[j].ky ? (point ? 1 : 2) : 0);
  return c;
}

// Pixel range [p0, p1) of conservative bounds [lo, hi], clipped to [clip0, clip1).
inline void pixel_range(double lo, double hi, int clip0, int clip1, int& p0, int& p1) {
  const double a = std::floor(expand_lo(lo)), b = std::floor(expand_hi(hi)) + 1.0;
  p0 = a < clip0 ? clip0 : (a > clip1 ? clip1 : static_cast<int>(a));
  p1 = b > clip1 ? clip1 : (b < clip0 ? clip0 : static_cast<int>(b));
}

// ---- 2D tile test (static, in-focus triangles; HINTERLEAVE) ---------------------------------

// Homogeneous edge functions e_i(x, y) = A_i x + B_i y + C_i of a triangle (pixel-homogeneous
// vertices), oriented by sigma = sign det so that the inside is sigma * e_i >= 0 for all i (also
// for vertices behind the camera: Olano-Greer), plus the corner of a tile that maximises each.
struct Edges2D {
  double A[3], B[3], C[3];  // already multiplied by sigma
  bool x_hi[3], y_hi[3];    // which tile corner maximises edge i
  bool valid = false;       // false: det == 0 (no sample can hit)
};

// Cost: cost::kEdges2DSetup (27).
template <class D>
inline Edges2D edges_2d(const float* X, const float* Y, const float* W) {
  Edges2D e;
  D A[3], B[3], C[3];
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    A[i] = madd(D(Y[j]), D(W[k]), -(D(W[j]) * D(Y[k])));
    B[i] = madd(D(W[j]), D(X[k]), -(D(X[j]) * D(W[k])));
    C[i] = madd(D(X[j]), D(Y[k]), -(D(Y[j]) * D(X[k])));
  }
  const D det = madd(A[0], D(X[0]), madd(B[0], D(Y[0]), C[0] * D(W[0])));
  const int sigma = sign_of(det);
  e.valid = sigma != 0;
  for (int i = 0; i < 3; ++i) {
    e.A[i] = sigma * raw(A[i]), e.B[i] = sigma * raw(B[i]), e.C[i] = sigma * raw(C[i]);
    e.x_hi[i] = D(e.A[i]) >= D(0.0);
    e.y_hi[i] = D(e.B[i]) >= D(0.0);
  }
  return e;
}

// Is the (expanded) tile outside one of the edges? Cost: cost::kTile2D (9).
template <class D>
inline bool tile_outside_2d(const Edges2D& e, double x0, double x1, double y0, double y1) {
  bool outside = false;
  for (int i = 0; i < 3; ++i) {
    const D v = madd(D(e.A[i]), D(e.x_hi[i] ? x1 : x0), madd(D(e.B[i]), D(e.y_hi[i] ? y1 : y0), D(e.C[i])));
    if (v < D(0.0)) outside = true;
  }
  return outside;
}

// ---- exact reference region (instrumentation, uncounted) -------------------------------------

// Does the convex polygon with screen vertices (x[j], y[j]) overlap the tile [x0, x1] x [y0, y1]?
// Exact separating-axis test in double: the optimal tile test of 001 §4 evaluated point-wise,
// used for tile.samples_optimal (uncounted instrumentation).
inline bool polygon_overlaps_tile(const double* x, const double* y, int n, double x0, double x1, double y0,
                                  double y1) {
  double lx = kInf, hx = -kInf, ly = kInf, hy = -kInf;
  for (int j = 0; j < n; ++j)
    lx = std::min(lx, x[j]), hx = std::max(hx, x[j]), ly = std::min(ly, y[j]), hy = std::max(hy, y[j]);
  if (hx < x0 || lx > x1 || hy < y0 || ly > y1) return false;
  double area = 0;
  for (int j = 0; j < n; ++j) area += x[j] * y[(j + 1) % n] - x[(j + 1) % n] * y[j];
  if (area == 0) return false;  // seen edge-on: the sample test's det is 0, nothing can hit
  const double s = area > 0 ? 1.0 : -1.0;
  const double cx[4] = {x0, x1, x0, x1}, cy[4] = {y0, y0, y1, y1};
  for (int j = 0; j < n; ++j) {
    const int k = (j + 1) % n;
    const double ex = x[k] - x[j], ey = y[k] - y[j];
    if (ex == 0 && ey == 0) continue;
    bool all_out = true;
    for (int c = 0; c < 4 && all_out; ++c)
      if (s * (ex * (cy[c] - y[j]) - ey * (cx[c] - x[j])) >= 0) all_out = false;
    if (all_out) return false;
  }
  return true;
}

// The footprint polygon (pixel-homogeneous vertices, all W > 0) seen from lens point (u, v).
inline bool footprint_overlaps_tile(const double (*P)[3], int n, double kx, double ky, double focus,
                                    double u, double v, double x0, double x1, double y0, double y1) {
  double x[6], y[6];
  for (int j = 0; j < n; ++j) {
    x[j] = (P[j][0] + u * kx * (P[j][2] - focus)) / P[j][2];
    y[j] = (P[j][1] + v * ky * (P[j][2] - focus)) / P[j][2];
  }
  return polygon_overlaps_tile(x, y, n, x0, x1, y0, y1);
}

}  // namespace rast5d::tiletest
