// h_i lines ([Akenine-Möller 2012] §4.2, Eq. 1-3): the active lens interval set of one axis of
// a tile, and the uv-boxes (the product of the u and v sets).
//
// On the x axis the triangle is left of the tile iff every a_j + u b_j < X0 (lens_vertex.h), an
// intersection of half-lines in u, one per vertex: u < (X0 - a_j)/b_j for b_j > 0 (behind the
// focus plane), u > (X0 - a_j)/b_j for b_j < 0 (in front), i.e. an open *gap* of u. Likewise right
// of the tile: a second gap. The active u set is [-1, 1] minus the two gaps. Vertices with W == F
// (b = 0) give no line ([Akenine-Möller 2012]: "such vertices are always ignored"), but they still block a gap when
// they project into the tile.
//
// At most 2 intervals per axis, so at most 4 uv-boxes. With every vertex on one side of the focus
// plane both gaps are half-lines ([Akenine-Möller 2012] Fig. 5): one interval. When the triangle crosses the focus
// plane ([Akenine-Möller 2012] Fig. 6-7, the "inner" region is culled), take a vertex p behind it (b_p > 0) and one
// q in front (b_q < 0), and write c_e(j) = (e - a_j)/b_j. The left gap lies inside
// (c_X0(q), c_X0(p)), the right gap inside (c_X1(p), c_X1(q)); since X1 > X0, c_X1(p) > c_X0(p) and
// c_X1(q) < c_X0(q), so both being non-empty would need c_X1(q) < c_X0(q) < c_X0(p) < c_X1(p) <
// c_X1(q): the lines x_p(u) and x_q(u) cross once, and only one of the two gaps can be open. One
// interior gap leaves two intervals. ([Akenine-Möller 2012] describes two boxes, A and B; the product of the
// per-axis sets also keeps A's u-range with B's v-range, from which the triangle can be visible.)
//
// Contract (tiletest/common.h): a lens coordinate is cut only if every footprint vertex seen from it lies
// beyond the same edge of the expanded tile; axis_pass and axis_cells keep every float sample and
// every lens cell that is not inside a cut.
#pragma once

#include <algorithm>
#include <cstdint>

#include "core/arith.h"
#include "core/costs.h"
#include "tiletest/lens_vertex.h"
#include "tiletest/common.h"

namespace rast5d::tiletest {

// Documented cost of the gap bounds of one axis (y: the v axis) over n lens vertices (axis_gaps).
inline std::uint64_t axis_gaps_cost(const LensVertex* lv, int n, bool y) {
  std::uint64_t c = 0;
  for (int j = 0; j < n; ++j) c += ((y ? lv[j].ky : lv[j].kx) != 0) ? cost::kGapVertex : cost::kGapVertexInFocus;
  return c;
}

struct Gaps {
  double L[2] = {-kInf, -kInf};  // gap k is the open interval (L[k], R[k]); k = 0: all vertices
  double R[2] = {kInf, kInf};    // before the tile's low edge, k = 1: all after its high edge
  bool blocked[2] = {false, false};  // a W == F vertex inside the tile range: no gap
};

// Cost: axis_gaps_cost() (cost::kGapVertex per vertex with a line, cost::kGapVertexInFocus per
// W == F vertex).
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
  int n_intervals = 0;  // disjoint active intervals (uv-box factor): at most 2, see above
  // Room for the 3 intervals that two disjoint interior cuts could leave; the geometry above
  // allows at most 2 (tests/test_engine_uv_boxes.py checks it).
  double iv_lo[3] = {0, 0, 0}, iv_hi[3] = {0, 0, 0};
};

// Cost: cost::kAxisSetGap per gap that is not blocked.
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

// Is the (float) lens coordinate x outside every cut? Cost: s.n_cmp CMP (ops.sample_region). The counting path performs
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

// Lens-grid cells of one axis that intersect the active set, as a bit mask (bit i = cell i).
// Cell i covers [-1 + 2i/G, -1 + 2(i+1)/G). A cell is dropped only if it lies inside a cut
// ([Akenine-Möller 2012] §5.1: "clamp them down and up to the nearest grid cell").
// Cost: 1 MADD per finite cut end, i.e. s.n_cmp.
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

// The whole lens on one axis: no cut, one interval [-1, 1].
inline AxisSet full_axis() {
  AxisSet s;
  s.n_intervals = 1;
  s.iv_lo[0] = -1.0, s.iv_hi[0] = 1.0;
  return s;
}

// h_i lines of one tile from n lens vertices: the active u and v sets. Returns false if either is
// empty. Charges the tile-stage operations to `ops`: axis_gaps_cost() per axis and
// cost::kAxisSetGap per gap that is not blocked.
template <class A>
inline bool tile_h_sets(const tiletest::LensVertex* lv, int n, double x0, double x1, double y0, double y1,
                        tiletest::AxisSet& sx, tiletest::AxisSet& sy, std::uint64_t& ops) {
  using D = typename A::f64;
  std::uint64_t doc = tiletest::axis_gaps_cost(lv, n, false) + tiletest::axis_gaps_cost(lv, n, true);
  const tiletest::Gaps gx = tiletest::axis_gaps(lv, n, false, D(x0), D(x1));
  const tiletest::Gaps gy = tiletest::axis_gaps(lv, n, true, D(y0), D(y1));
  sx = tiletest::axis_set<D>(gx);
  sy = tiletest::axis_set<D>(gy);
  for (int k = 0; k < 2; ++k) doc += (gx.blocked[k] ? 0 : cost::kAxisSetGap) + (gy.blocked[k] ? 0 : cost::kAxisSetGap);
  charge<A>(ops, doc);
  return !sx.empty && !sy.empty;
}

}  // namespace rast5d::tiletest
