// Tile tests: pure functions from (triangle footprint, screen tile) to conservative lens regions.
// One header per test ([Akenine-Möller 2012] §4-§5.1; docs/tile_tests.md):
//   lens_vertex.h      per-vertex lens projection (setup of the h_i lines)
//   halfspace_lens.h   h_i lines: the active u and v sets of a tile (uv-boxes), lens-grid cells
//   halfspace_edges.h  H_j lines: the per-edge lens lines, evaluated over lens-grid cells
//   lens_shape.h       uv-box against the lens shape (square, disk, hexagon)
//   edges_2d.h         the standard 2D tile test of static, in-focus triangles
//   box_bounds.h       screen bounds of the footprint over a lens box (INTERVAL, INTERLEAVE)
//   candidates.h       fast-path selection of a pixel's candidate samples
//   exact_region.h     the exact region, evaluated point-wise (instrumentation only)
//   precision_4d.h     h_i, H_j, box bounds and ẑ in float32 / fixed point (pipeline.precision.tile)
//   precision_5d.h     t̂, 5D lens sets and H5 of moving triangles in float32 / fixed point (the same)
//
// Contract: every test is *conservative*: it never removes a (u, v) from which the float sample
// test could hit a sample of the tile. They run in double on the tile expanded by a margin
// (kMarginAbs + kMarginRel * |coordinate| pixels), far larger than the float sample test's error,
// and invariant 1 (tests/test_tile_invariants.py) checks it against brute force.
//
// Geometry ([Akenine-Möller 2012] §4; mapping in docs/conventions.md). Seen from lens point (u, v), a footprint
// vertex (X, Y, W) with W > 0 lands at pixel
//     x(u) = X/W + u * Kx * (1 - F/W) = a_x + u b_x,      y(v) = a_y + v b_y.
// A tile [X0, X1] x [Y0, Y1] can see the triangle from (u, v) only if the projected triangle
// overlaps it. By the separating-axis theorem two convex polygons are disjoint iff an axis of
// one of their edges separates them: the tile's axes give the h_i lines (halfspace_lens.h), the
// triangle's edge axes the H_j lines (halfspace_edges.h).
#pragma once

#include <bitset>
#include <cmath>
#include <limits>

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

// Extra widening [px] while the render's sample test decides in fixed point (pipeline.precision.sample:
// the snapped triangle reaches up to sampletest/precision.h's snap_margin_px beyond the exact one); set
// by each render worker thread, 0 otherwise.
inline thread_local double t_snap_margin_px = 0.0;

// Sets t_snap_margin_px for a scope and restores the previous value on leaving it (also on a throw).
class ScopedSnapMargin {
 public:
  explicit ScopedSnapMargin(double px) : saved_(t_snap_margin_px) { t_snap_margin_px = px; }
  ~ScopedSnapMargin() { t_snap_margin_px = saved_; }
  ScopedSnapMargin(const ScopedSnapMargin&) = delete;
  ScopedSnapMargin& operator=(const ScopedSnapMargin&) = delete;

 private:
  double saved_;
};

inline double expand_lo(double x) { return x - (kMarginAbs + t_snap_margin_px + kMarginRel * std::fabs(x)); }
inline double expand_hi(double x) { return x + (kMarginAbs + t_snap_margin_px + kMarginRel * std::fabs(x)); }

}  // namespace rast5d::tiletest
