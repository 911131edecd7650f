// The lens shape against uv-boxes and lens-grid cells: a box of the lens square that misses the
// lens (disk or hexagon) holds no sample.
//
// Contract (tiletest/common.h): box_overlaps_lens is false only if the box misses the lens shape.
#pragma once

#include "core/arith.h"
#include "core/params.h"
#include "core/sample_table.h"
#include "tiletest/common.h"

namespace rast5d::tiletest {

// Does the box [u0, u1] x [v0, v1] (inside [-1, 1]^2) overlap the lens shape?
// Cost: 0 (square), cost::kBoxDisk (disk), cost::kBoxHexagon (hexagon).
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

// Lens-grid cells that intersect the lens shape (a sample can only live in those).
inline CellMask lens_cells(LensShape shape, int grid) {
  CellMask m;
  for (int j = 0; j < grid; ++j)
    for (int i = 0; i < grid; ++i)
      if (box_overlaps_lens<double>(shape, SampleTable::cell_lo(i, grid), SampleTable::cell_hi(i, grid),
                                              SampleTable::cell_lo(j, grid), SampleTable::cell_hi(j, grid)))
        m.set(j * grid + i);
  return m;
}

}  // namespace rast5d::tiletest
