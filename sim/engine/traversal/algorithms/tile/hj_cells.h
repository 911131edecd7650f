// TILE's H_j test of one screen tile over the lens-grid cells ([Akenine-Möller 2012] §4.3,
// §5.1): per active edge of the footprint, the two tangent lines (tiletest/halfspace_edges.h)
// evaluated conservatively over the cells; a cell is culled when both lines cull it.
#pragma once

#include <cstdint>

#include "core/arith.h"
#include "core/costs.h"
#include "core/counters.h"
#include "setup/footprint.h"
#include "tiletest/halfspace_edges.h"

namespace rast5d {

// Cells of columns i0..i1 and rows j0..j1 of the G x G grid culled by the H_j lines of the
// expanded tile [x0, x1] x [y0, y1]. any_line: some edge gave a line (else nothing is culled).
// Charges ops.tile and counts tile.H_lines. M: tiletest::CellMask, or std::uint64_t for G <= 8
// (the same bits).
inline const tiletest::CellMask& low_cells(const tiletest::CellMask& m, tiletest::CellMask*) { return m; }
inline std::uint64_t low_cells(const tiletest::CellMask& m, std::uint64_t*) {
  return (m & tiletest::CellMask(~0ull)).to_ullong();
}

template <class A, class M = tiletest::CellMask>
M hj_culled_cells(const Footprint& fp, double x0, double x1, double y0, double y1, int G, int i0, int i1, int j0,
                  int j1, Counters& c, bool& any_line) {
  using D = typename A::f64;
  M culled{};
  any_line = false;
  for (int k = 0; k < fp.n_edges; ++k) {
    const tiletest::EdgeH& e = fp.edges[k];
    if (!e.active) continue;
    int m, n;
    const bool has = tiletest::tangent_corners<D>(e, x0, x1, y0, y1, m, n);
    charge<A>(c[Counter::ops_tile], e.parallel ? 0 : cost::kTangentCorners);
    if (!has) continue;  // region 5: the edge points at the tile
    const int rows = j1 - j0 + 1, cols = i1 - i0 + 1;
    const std::uint64_t cells_cost = tiletest::line_cells_cost(rows, cols);
    M edge_culled{};
    if (fp.sigma != 0) {  // one orientation over the lens: cull where sigma * H < 0 for both
      edge_culled = ~M{};
      for (const int corner : {m, n}) {
        const double xc = (corner & 1) ? x1 : x0, yc = (corner & 2) ? y1 : y0;
        const tiletest::Line l = tiletest::line_at_corner<D>(e, xc, yc, fp.sigma);
        edge_culled &= tiletest::line_cells<D, M>(l, G, i0, i1, j0, j1);
        charge<A>(c[Counter::ops_tile], cost::kLineAtCorner + cells_cost);
        ++c[Counter::tile_H_lines];
      }
    } else {  // orientation changes over the lens: per cell of one sign (H < 0 or H > 0)
      M neg_both = ~M{}, pos_both = ~M{};
      for (const int corner : {m, n}) {
        const double xc = (corner & 1) ? x1 : x0, yc = (corner & 2) ? y1 : y0;
        const tiletest::Line l = tiletest::line_at_corner<D>(e, xc, yc, 1);
        neg_both &= tiletest::line_cells<D, M>(l, G, i0, i1, j0, j1);
        pos_both &= tiletest::line_cells<D, M>(tiletest::Line{-l.A, -l.B, -l.C}, G, i0, i1, j0, j1);
        charge<A>(c[Counter::ops_tile], cost::kLineAtCorner + 2 * cells_cost);
        ++c[Counter::tile_H_lines];
      }
      edge_culled = (low_cells(fp.orient_pos, static_cast<M*>(nullptr)) & neg_both) |
                    (low_cells(fp.orient_neg, static_cast<M*>(nullptr)) & pos_both);
    }
    culled |= edge_culled;
    any_line = true;
  }
  return culled;
}

}  // namespace rast5d
