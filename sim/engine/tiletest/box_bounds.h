// Screen bounds of the footprint over a lens box (INTERVAL, INTERLEAVE): the pixels a triangle can
// cover from any lens point of the box.
//
// Contract (tiletest/common.h): the bounds contain the footprint's projection from every lens point of
// the box, and pixel_range the pixels they touch.
#pragma once

#include <cmath>
#include <cstdint>

#include "core/arith.h"
#include "core/costs.h"
#include "tiletest/lens_vertex.h"
#include "tiletest/common.h"

namespace rast5d::tiletest {

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
  const std::uint64_t axis = point ? cost::kBoxBoundsAxisPoint : cost::kBoxBoundsAxisBox;
  std::uint64_t c = 0;
  for (int j = 0; j < n; ++j) c += cost::kBoxBoundsVertex + (lv[j].kx ? axis : 0) + (lv[j].ky ? axis : 0);
  return c;
}

// Pixel range [p0, p1) of conservative bounds [lo, hi], clipped to [clip0, clip1).
inline void pixel_range(double lo, double hi, int clip0, int clip1, int& p0, int& p1) {
  const double a = std::floor(expand_lo(lo)), b = std::floor(expand_hi(hi)) + 1.0;
  p0 = a < clip0 ? clip0 : (a > clip1 ? clip1 : static_cast<int>(a));
  p1 = b > clip1 ? clip1 : (b < clip0 ? clip0 : static_cast<int>(b));
}

}  // namespace rast5d::tiletest
