// Triangle setup (docs/architecture.md: setup builds per-triangle work, traversal consumes it).
//
// Contract: setup_triangle() fills a TriSetup whose pixel bounds contain every pixel with a sample
// the exact sample test can hit, for every (u, v) in [-1, 1]^2 and t in [0, 1]. It classifies the
// triangle as 2D/3D/4D/5D (the cheapest exact sample kernel) and prepares the constants of that
// kernel. When a vertex can be behind the near plane, static triangles are bounded through their
// near-clipped polygon and moving ones fall back to full-screen bounds (counted).
#pragma once

#include <cstdint>

#include "core/arith.h"
#include "core/counters.h"
#include "core/params.h"
#include "core/sample_table.h"
#include "core/triangle.h"

namespace rast5d {

// Returns false when the triangle is culled (the reason is counted).
// Operations are charged to c[ops_setup] (exact mode: tallied by the counting type).
template <class A>
bool setup_triangle(const float* v0, const float* v1, const float* col, std::uint32_t index,
                    const RenderParams& p, const FrameConst& fc, TriSetup& out, Counters& c);

// The x-extent of the conservative bounds of point (X, Y, W) over the lens square: the bounds
// kernel, exposed for the op-cost tests. Cost: cost::kBoundsPointLens (or kBoundsPoint).
template <class F>
inline void bounds_point(F X, F Y, F W, F neg_focus, F kx, F ky, bool lens, F& minx, F& maxx,
                         F& miny, F& maxy) {
  const F r = rcp(W);
  const F px = X * r;
  const F py = Y * r;
  if (lens) {
    const F b = madd(neg_focus, r, F(1.0f));
    const F ex = vabs(b * kx);
    const F ey = vabs(b * ky);
    minx = vmin(minx, px - ex);
    maxx = vmax(maxx, px + ex);
    miny = vmin(miny, py - ey);
    maxy = vmax(maxy, py + ey);
  } else {
    minx = vmin(minx, px);
    maxx = vmax(maxx, px);
    miny = vmin(miny, py);
    maxy = vmax(maxy, py);
  }
}

}  // namespace rast5d

namespace rast5d {

// The bounds pre-pass of sampled simulation (sampled/sampled_setup.h): setup_triangle()'s bounds and
// culls without its kernel constants, with the same float operations, charging nothing:
// o.X, o.Y, o.W, o.cx, o.cy, o.moving, o.defocused, o.near_clipped, o.full_bounds, o.poly and the pixel
// bounds (bx0, by0, bx1, by1 and lo_x..hi_y), equal to setup_triangle()'s for the same triangle.
// Returns 0, or the cull setup_triangle() counts: 1 every vertex behind the near plane (then only the
// vertex fields are set), 2 bounds off screen, 3 degenerate, 4 back-facing (back-face culling on).
int setup_bounds(const float* v0, const float* v1, const RenderParams& p, const FrameConst& fc, TriSetup& o);

}  // namespace rast5d
