// TILE's h_i sets per tile column and per tile row (fast path). The u set of a tile depends only on
// its x range and the v set only on its y range ([Akenine-Möller 2012] Eq. 1-3,
// tiletest/halfspace_lens.h), so the sets, their lens-grid columns/rows (axis_cells) and their
// documented costs are computed once per column and per row of the triangle's tiles in a bin and
// read by every tile. Each tile is still charged what tile_h_sets charges it (the hardware tests
// every tile); only the simulator's arithmetic is shared. The counting path does not use this: it
// evaluates every tile with the counting scalar type.
#pragma once

#include <cstdint>
#include <vector>

#include "core/arith.h"
#include "core/costs.h"
#include "tiletest/halfspace_lens.h"
#include "tiletest/lens_vertex.h"
#include "tiletest/common.h"

namespace rast5d {

struct AxisCache {
  struct Axis {
    tiletest::AxisSet set;
    std::uint32_t cells = 0;  // tiletest::axis_cells of set
    std::uint64_t cost = 0;   // tile_h_sets' documented cost for this axis
  };
  int tx0 = 0, ty0 = 0;       // first tile column / row origin
  std::vector<Axis> cols, rows;

  // The tiles of size T whose origins run from t0 (a multiple of T) below end; h: h_i lines in use.
  // F64: the fast path's double type (plain double).
  template <class F64>
  static void build_axis(std::vector<Axis>& out, const tiletest::LensVertex* lv, int n, bool y, bool h, int t0,
                         int end, int T, int G) {
    out.clear();
    const std::uint64_t gaps_cost = h ? tiletest::axis_gaps_cost(lv, n, y) : 0;
    for (int t = t0; t < end; t += T) {
      Axis a;
      if (h) {
        const tiletest::Gaps g =
            tiletest::axis_gaps(lv, n, y, F64(tiletest::expand_lo(t)), F64(tiletest::expand_hi(t + T)));
        a.set = tiletest::axis_set<F64>(g);
        a.cost = gaps_cost;
        for (int k = 0; k < 2; ++k) a.cost += g.blocked[k] ? 0 : cost::kAxisSetGap;
      } else {
        a.set = tiletest::full_axis();
      }
      a.cells = tiletest::axis_cells<F64>(a.set, G);
      out.push_back(a);
    }
  }

  template <class F64>
  void build(const tiletest::LensVertex* lv, int n, bool h, int x0, int x1, int y0, int y1, int T, int G) {
    tx0 = (x0 / T) * T, ty0 = (y0 / T) * T;
    build_axis<F64>(cols, lv, n, false, h, tx0, x1, T, G);
    build_axis<F64>(rows, lv, n, true, h, ty0, y1, T, G);
  }
};

}  // namespace rast5d
