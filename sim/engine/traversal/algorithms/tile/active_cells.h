// TILE's active lens-grid cells of one screen tile: the cells inside the tile's uv-boxes and on the
// lens shape ([Akenine-Möller 2012] §5.1, Fig. 10), then less the cells its H_j lines cull
// (hj_cells.h). A 64-bit mask for grids up to 8 x 8, a bitset above.
#pragma once

#include <algorithm>
#include <cstdint>

#include "core/counters.h"
#include "tiletest/common.h"

namespace rast5d {

struct ActiveCells {
  bool small = true;         // G * G <= 64: bits64 holds the cells; else bits
  std::uint64_t bits64 = 0;
  tiletest::CellMask bits;
  int i0 = 0, i1 = -1, j0 = 0, j1 = -1;  // bounding rows and columns of the cells (before H_j)

  bool none() const { return small ? bits64 == 0 : bits.none(); }

  // Remove the culled cells, counting tile.cells_tested and tile.cells_culled.
  // low64: the first 64 bits set (to read a bitset as a 64-bit mask).
  void remove(const tiletest::CellMask& culled, const tiletest::CellMask& low64, Counters& c) {
    if (small) {
      const std::uint64_t culled64 = (culled & low64).to_ullong();
      c[Counter::tile_cells_tested] += static_cast<std::uint64_t>(__builtin_popcountll(bits64));
      c[Counter::tile_cells_culled] += static_cast<std::uint64_t>(__builtin_popcountll(bits64 & culled64));
      bits64 &= ~culled64;
    } else {
      c[Counter::tile_cells_tested] += bits.count();
      c[Counter::tile_cells_culled] += (bits & culled).count();
      bits &= ~culled;
    }
  }

  // remove() for small grids, the culled cells as a 64-bit mask.
  void remove64(std::uint64_t culled64, Counters& c) {
    c[Counter::tile_cells_tested] += static_cast<std::uint64_t>(__builtin_popcountll(bits64));
    c[Counter::tile_cells_culled] += static_cast<std::uint64_t>(__builtin_popcountll(bits64 & culled64));
    bits64 &= ~culled64;
  }

  // The active cells' indices in increasing order; returns how many.
  int list(int* out, int grid) const {
    int n = 0;
    if (small) {
      for (std::uint64_t m = bits64; m; m &= m - 1) out[n++] = __builtin_ctzll(m);
    } else {
      for (int c = 0; c < grid * grid; ++c)
        if (bits.test(c)) out[n++] = c;
    }
    return n;
  }
};

// The cells of the G x G grid whose column bit is in bx and row bit in by (tiletest::axis_cells)
// and that lie on the lens (lens_mask; lens_mask64 its first 64 bits).
inline ActiveCells active_cells(std::uint32_t bx, std::uint32_t by, int G, const tiletest::CellMask& lens_mask,
                                std::uint64_t lens_mask64) {
  ActiveCells a;
  a.small = G * G <= 64;
  a.i0 = G, a.i1 = -1, a.j0 = G, a.j1 = -1;
  if (a.small) {
    for (int j = 0; j < G; ++j)
      if (by >> j & 1u) a.bits64 |= static_cast<std::uint64_t>(bx) << (j * G);
    a.bits64 &= lens_mask64;
    std::uint64_t cols = 0;
    for (int j = 0; j < G; ++j) {
      const std::uint64_t row = (a.bits64 >> (j * G)) & ((std::uint64_t(1) << G) - 1);
      if (row) a.j0 = std::min(a.j0, j), a.j1 = j, cols |= row;
    }
    if (cols) a.i0 = __builtin_ctzll(cols), a.i1 = 63 - __builtin_clzll(cols);
  } else {
    for (int j = 0; j < G; ++j) {
      if (!(by >> j & 1u)) continue;
      for (int i = 0; i < G; ++i)
        if ((bx >> i & 1u) && lens_mask.test(j * G + i)) {
          a.bits.set(j * G + i);
          a.i0 = std::min(a.i0, i), a.i1 = std::max(a.i1, i), a.j0 = std::min(a.j0, j), a.j1 = std::max(a.j1, j);
        }
    }
  }
  return a;
}

}  // namespace rast5d
