// The conventional 2D rasterizer of the GPU pipeline ([Toth 2008] §3.1): the
// geometry shader's bounding polygon (gpu/geometry_shader.h) is rasterized conservatively: a
// pixel is a fragment when its square [px, px + 1] x [py, py + 1] meets every half-plane of the
// polygon (one fragment per pixel and triangle, as a convex strip dilated by the pixel gives).
// Every sample of the pixel can then be tested by the pixel shader, whatever its offset in the
// pixel. A GPU rasterizes the whole polygon clipped to the viewport (the screen: pixels off screen
// are never generated) with no per-triangle scissor, so its fragments beyond the triangle's setup
// box are overdraw too: the scan box of the bin's fragments is the polygon's box inside the setup
// box and the bin, and the pipeline counts the polygon's on-screen pixels outside the setup box
// once per triangle (ex0..ey1; gpu.fragments_outside_box), where no sample can be inside.
//
// Costs (gpu/costs.h): per edge kRasterEdgeSetup, per vertex kRasterScanVertex (once per triangle),
// per (pixel, edge) evaluated kRasterEdge (the test stops at the first edge that rejects).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/arith.h"
#include "core/bin_rect.h"
#include "gpu/costs.h"
#include "gpu/geometry_shader.h"

namespace rast5d::gpu {

struct RasterSetup {
  int n = 0;
  double nx[kMaxPlanes], ny[kMaxPlanes], h[kMaxPlanes];
  double ox[kMaxPlanes], oy[kMaxPlanes];  // the pixel corner that tests each edge (0 or 1)
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;     // scan box [x0, x1) x [y0, y1) before the bin
  // The polygon's box on screen, which a GPU rasterizes whole (no per-triangle scissor); pixels
  // of it outside the setup box [bx0, bx1) x [by0, by1) cannot hold a hit.
  int ex0 = 0, ex1 = 0, ey0 = 0, ey1 = 0;
};

// Edge setup and scan box. Operations go to ops (charged once per triangle by the caller).
template <class A>
inline void raster_setup(const Bound& b, const TriSetup& tri, int width, int height, RasterSetup& r,
                         std::uint64_t& ops) {
  using D = typename A::f64;
  r.n = b.n_planes;
  for (int i = 0; i < r.n; ++i) {
    r.nx[i] = b.nx[i], r.ny[i] = b.ny[i], r.h[i] = b.h[i];
    r.ox[i] = D(b.nx[i]) < D(0.0) ? 1.0 : 0.0;
    r.oy[i] = D(b.ny[i]) < D(0.0) ? 1.0 : 0.0;
    charge<A>(ops, cost::gpu::kRasterEdgeSetup);
  }
  r.x0 = r.ex0 = tri.bx0, r.x1 = r.ex1 = tri.bx1, r.y0 = r.ey0 = tri.by0, r.y1 = r.ey1 = tri.by1;
  if (!b.verts_valid || b.n_verts < 3) return;
  D lx = D(b.vx[0]), hx = lx, ly = D(b.vy[0]), hy = ly;
  for (int i = 0; i < b.n_verts; ++i) {
    lx = vmin(lx, D(b.vx[i])), hx = vmax(hx, D(b.vx[i]));
    ly = vmin(ly, D(b.vy[i])), hy = vmax(hy, D(b.vy[i]));
    charge<A>(ops, cost::gpu::kRasterScanVertex);
  }
  // The vertices are those of the polygon before its margins: widen the scan box by the margins'
  // effect on the vertices, computed from the margined half-planes (robustness, not charged).
  double mlx = raw(lx), mhx = raw(hx), mly = raw(ly), mhy = raw(hy);
  if (b.n_planes == b.n_verts) {
    for (int i = 0; i < b.n_planes; ++i) {
      const int j = (i + 1) % b.n_planes;
      const double det = b.nx[i] * b.ny[j] - b.ny[i] * b.nx[j];
      if (!(det > 0.0)) return;  // keep the setup box
      const double x = (b.h[i] * b.ny[j] - b.h[j] * b.ny[i]) / det;
      const double y = (b.nx[i] * b.h[j] - b.nx[j] * b.h[i]) / det;
      if (!std::isfinite(x) || !std::isfinite(y)) return;
      mlx = std::min(mlx, x), mhx = std::max(mhx, x), mly = std::min(mly, y), mhy = std::max(mhy, y);
    }
  } else {
    return;
  }
  const double pad = 0x1p-6 + 1e-9 * std::max({std::fabs(mlx), std::fabs(mhx), std::fabs(mly), std::fabs(mhy)});
  auto clampi = [](double v, int lo, int hi) {
    if (!(v > lo)) return lo;
    if (!(v < hi)) return hi;
    return static_cast<int>(v);
  };
  r.x0 = std::max(r.x0, clampi(std::floor(mlx - pad), tri.bx0, tri.bx1));
  r.x1 = std::min(r.x1, clampi(std::floor(mhx + pad) + 1.0, tri.bx0, tri.bx1));
  r.y0 = std::max(r.y0, clampi(std::floor(mly - pad), tri.by0, tri.by1));
  r.y1 = std::min(r.y1, clampi(std::floor(mhy + pad) + 1.0, tri.by0, tri.by1));
  r.ex0 = clampi(std::floor(mlx - pad), 0, width), r.ex1 = clampi(std::floor(mhx + pad) + 1.0, 0, width);
  r.ey0 = clampi(std::floor(mly - pad), 0, height), r.ey1 = clampi(std::floor(mhy + pad) + 1.0, 0, height);
}

// Does pixel (px, py)'s square meet every half-plane? Operations go to ops.
template <class A>
inline bool pixel_covered(const RasterSetup& r, int px, int py, std::uint64_t& ops) {
  using D = typename A::f64;
  for (int i = 0; i < r.n; ++i) {
    const D cx(px + r.ox[i]), cy(py + r.oy[i]);
    const bool out = madd(D(r.nx[i]), cx, D(r.ny[i]) * cy) > D(r.h[i]);
    charge<A>(ops, cost::gpu::kRasterEdge);
    if (out) return false;
  }
  return true;
}

}  // namespace rast5d::gpu
