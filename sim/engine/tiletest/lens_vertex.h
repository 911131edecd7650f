// Per-vertex lens projection (setup of the h_i lines, [Akenine-Möller 2012] §4.2 Eq. 1): a
// footprint vertex seen from lens point (u, v) lands at x(u) = a_x + u b_x, y(v) = a_y + v b_y.
#pragma once

#include <cstdint>

#include "core/arith.h"
#include "core/costs.h"

namespace rast5d::tiletest {

struct LensVertex {
  double ax, ay;   // pixel position seen from the lens centre
  double bx, by;   // d x / d u and d y / d v
  double ibx, iby; // 1 / b (Eq. 1's delta), 0 if b == 0
  double ox, oy;   // -a / b (Eq. 1's offset): the lens coordinate where x(u) = X0 is X0 * ib + o
  int kx, ky;      // sign of b per axis: +1, -1, or 0 (W == F: no line)
};

// Cost: cost::kLensVertexBase + cost::kLensVertexAxis per axis whose slope b is non-zero (b == 0: the vertex is on the focus plane or the camera has
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

}  // namespace rast5d::tiletest
