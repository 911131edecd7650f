// INSTRUMENTATION ONLY: the exact active region of 001_3248aaf17c219d5e.txt §4 evaluated
// point-wise in double (no grid, no oracle, no margin), for tile.samples_optimal, the denominator
// of 001 Table 1. Never used to cull and never counted in ops.*.
#pragma once

#include <algorithm>

#include "core/sample_table.h"
#include "setup/footprint.h"
#include "setup/setup.h"
#include "tiletest/tile_test.h"

namespace rast5d::tiletest {

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

// Is the sample's (u, v, t) inside the exact active region of the (unexpanded) tile
// [tx, tx + T) x [ty, ty + T)? Instrumentation for tile.samples_optimal (uncounted).
inline bool in_exact_region(const TriSetup& tri, const Footprint& fp, const FrameConst& fc,
                            const PixelSamples& ps, int s, int tx, int ty, int T) {
  const double u = ps.u[s], v = ps.v[s];
  if (!tri.moving) {
    double x[6], y[6];
    for (int j = 0; j < fp.n; ++j) x[j] = fp.lv[j].ax + u * fp.lv[j].bx, y[j] = fp.lv[j].ay + v * fp.lv[j].by;
    return polygon_overlaps_tile(x, y, fp.n, tx, tx + T, ty, ty + T);
  }
  const double t = ps.t[s];
  double P[3][3];
  for (int j = 0; j < 3; ++j) {
    P[j][0] = tri.X[j] + t * static_cast<double>(tri.dX[j]);
    P[j][1] = tri.Y[j] + t * static_cast<double>(tri.dY[j]);
    P[j][2] = tri.W[j] + t * static_cast<double>(tri.dW[j]);
    if (!(P[j][2] > fc.near_d)) return true;  // crosses the near plane at t: not evaluated
  }
  return footprint_overlaps_tile(P, 3, fc.kx_d, fc.ky_d, fc.focus_d, u, v, tx, tx + T, ty, ty + T);
}

}  // namespace rast5d::tiletest
