// The geometry shader of the conventional-GPU pipeline ([Toth 2008] §3.3, §4;
// [McGuire 2010] "(2+1)D rasterization"): per triangle, a bounding polygon in screen
// space that contains every pixel position a sample can hit the triangle at, for every lens point
// (u, v) of the sample table and every time t of the shutter.
//
// Camera model (docs/conventions.md): vertex j at lens point (u, v) projects to
//   x = X_j / W_j + u kx b_j,  y = Y_j / W_j + v ky b_j,  b_j = 1 - F / W_j,
// so its circle of confusion is the lens set scaled by (kx b_j, ky b_j): the confusion shape of the
// vertex. A sheared triangle is the hull of its three sheared vertices, and for a moving triangle
// each sheared vertex moves on a segment between its shutter-end positions (projective images of
// segments are segments while W > 0). Hence every hit lies in the convex hull of the confusion
// shapes of the 3 (static) or 6 (moving: both shutter ends) vertex positions, and a half-plane
// n.x <= h is conservative whenever h is at least the support of every shape in direction n:
//   h(n) = max_j (n . p_j + S_L(n_x kx b_j, n_y ky b_j)),
// with S_L the support function of the table's lens set: r |(a, b)| with r = 1 when every (u, v)
// of the table lies in the unit disk ("disk"), |a| + |b| otherwise ("square", always valid since
// u, v are in [-1, 1]). Every method below chooses directions as its paper says and takes h as
// that support, so every method is conservative by construction; the methods differ in how
// many half-planes (output vertices, triangles) they spend and how tight they are.
//
// Methods ([Toth 2008] Table 1, [McGuire 2010]):
//   pe_triangle   3 half-planes parallel to the edges ([Toth 2008] §4.5, 2D)
//   vr_triangle   3 half-planes tangent to the two confusion circles of each edge ([Toth 2008] §4.6); falls
//                 back to pe_triangle when a circle encloses the other or the bound inverts
//   hexagon2d     the 3 edge half-planes plus 3 at each vertex with the averaged normal ([Toth 2008] §4.4)
//   wedge         3D: the pe construction in the triangle's plane with the discs of confusion
//                 projected to it, extruded along the normal to enclose the largest disc ([Toth 2008] §4.5)
//   reduced_wedge the wedge's silhouette as one strip ([Toth 2008] §4.5); needs the volume in front of the
//                 near plane (the silhouette from the pinhole exists), else the full wedge
//   hexagon3d     3D: the hexagon construction in the triangle's plane, extruded ([Toth 2008] §4.4)
//   convex_hull   [McGuire 2010]'s (2+1)D hull: the convex hull of the confusion boxes of the vertex positions
//                 at both shutter ends; clip-and-box (the triangle's setup box) across z = 0
//   adaptive      [Toth 2008] §4.7 per triangle: pe_triangle when the blur is small against the triangle,
//                 else hexagon2d; hexagon3d across the near plane; convex_hull when moving
// Special cases ([Toth 2008] §4.8), each counted: 2D methods with a vertex behind the near plane (inverted
// planes) use clip-and-box; [Toth 2008]'s methods (defocus only) on moving triangles use convex_hull;
// triangles degenerate in image space use the box; 3D volumes reaching behind the near plane are
// clipped there (the clipped volume's projection is still conservative: accepted hits have W >= near).
//
// Costs: gpu/costs.h, charged per executed kernel (charge<A>), counted by the counting scalar.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/arith.h"
#include "gpu/costs.h"
#include "core/triangle.h"

namespace rast5d::gpu {

// SQRT: one operation (gpu/costs.h).
inline float vsqrt(float a) { return std::sqrt(a); }
inline double vsqrt(double a) { return std::sqrt(a); }
template <class T>
inline Counted<T> vsqrt(Counted<T> a) {
  ++OpTally::count;
  return Counted<T>(std::sqrt(a.v));
}

enum class Method : int {
  kPETriangle = 0,
  kVRTriangle,
  kHexagon2D,
  kWedge,
  kReducedWedge,
  kHexagon3D,
  kConvexHull,
  kAdaptive,
  kBox,  // fallback only: the triangle's setup box
};

// Why a triangle did not get its method's own bound ([Toth 2008] §4.8), counted per triangle.
enum class Fallback : int { kNone = 0, kNear, kMotion, kDegenerate, kVR, kReduced };

inline constexpr int kMaxPlanes = 64;

// Per-render constants of the geometry shader.
struct GsFrame {
  double kx = 0, ky = 0, focus = 1, neg_focus = -1;  // kx = ky = 0 without a lens dimension
  double near_clip = 0;  // the near plane, a little nearer (as setup's clip) for float rounding
  double s = 1, inv_s = 1;  // (X, Y) scale of the view-like space of the 3D methods
  bool disk = true;         // every (u, v) of the table is in the unit disk
  double adaptive_ratio = 0.5;
};

// A bounding polygon: half-planes n.x <= h (outward normals, margins included) for the rasterizer;
// the polygon's vertices (for its area and the rasterizer's scan box); the emitted geometry.
struct Bound {
  int n_planes = 0;
  double nx[kMaxPlanes], ny[kMaxPlanes], h[kMaxPlanes];
  int n_verts = 0;
  double vx[kMaxPlanes], vy[kMaxPlanes];
  bool verts_valid = false;
  Method used = Method::kBox;
  Fallback fallback = Fallback::kNone;
  bool volume_clipped = false;
  int out_vertices = 0;   // distinct vertices of the emitted geometry
  int out_triangles = 0;  // triangles of the emitted strip (strip vertices = triangles + 2)
  double area = 0;        // area of the bounding polygon, px^2 (the box for the fallback)
};

namespace detail {

template <class D>
struct Shape {
  D x, y, ex, ey;  // projected position and confusion extents |kx b|, |ky b|
};

// Cost: cost::gpu::kShape.
template <class D>
inline Shape<D> shape(double X, double Y, double W, const GsFrame& g) {
  Shape<D> s;
  const D r = rcp(D(W));
  s.x = D(X) * r;
  s.y = D(Y) * r;
  const D b = madd(D(g.neg_focus), r, D(1.0));
  s.ex = vabs(b * D(g.kx));
  s.ey = vabs(b * D(g.ky));
  return s;
}

// Support of one shape in direction (nx, ny). Cost: cost::gpu::support_cost(disk).
template <class D>
inline D support(D nx, D ny, const Shape<D>& s, bool disk) {
  const D d = madd(nx, s.x, ny * s.y);
  const D a = nx * s.ex, c = ny * s.ey;
  const D r = disk ? vsqrt(madd(a, a, c * c)) : vabs(a) + vabs(c);
  return d + r;
}

// Outward unit normal of edge a -> b of a counter-clockwise (positive-area) polygon.
// Cost: cost::gpu::kEdgeNormal.
template <class D>
inline void edge_normal(D ax, D ay, D bx, D by, D& nx, D& ny) {
  const D dx = bx - ax, dy = by - ay;
  const D inv = rcp(vsqrt(madd(dx, dx, dy * dy)));
  nx = dy * inv;
  ny = -(dx * inv);
}

// Intersection of lines n1.x = h1 and n2.x = h2; false when n2 does not turn counter-clockwise
// from n1 (parallel or inverted). Cost: cost::gpu::kIntersect.
template <class D>
inline bool intersect(D n1x, D n1y, D h1, D n2x, D n2y, D h2, D& x, D& y) {
  const D det = n1x * n2y - n1y * n2x;
  const bool ok = det > D(1e-12);
  const D inv = rcp(det);
  x = (h1 * n2y - h2 * n1y) * inv;
  y = (n1x * h2 - n2x * h1) * inv;
  return ok;
}

// Conservative margin of a half-plane for the float sample test's rounding (as setup's widening;
// robustness, not charged).
inline double margin_for(double mag) { return 0x1p-8 + 0x1p-12 * mag; }

template <class D>
inline void add_plane(Bound& b, D nx, D ny, D h, double m) {
  const double rx = raw(nx), ry = raw(ny);
  b.nx[b.n_planes] = rx;
  b.ny[b.n_planes] = ry;
  b.h[b.n_planes] = raw(h) + m * (std::fabs(rx) + std::fabs(ry));
  ++b.n_planes;
}

inline double polygon_area(const double* x, const double* y, int n) {
  double a = 0.0;
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    a += x[i] * y[j] - x[j] * y[i];
  }
  return 0.5 * std::fabs(a);
}

// The fallback box: the triangle's setup bounds (for a triangle across the near plane, those of
// its near-clipped polygon: [McGuire 2010]'s clip-and-box). No geometry-shader work (setup's).
inline void box_bound(const TriSetup& tri, Bound& b) {
  b.n_planes = 0;
  const double m = margin_for(std::max({std::fabs(tri.lo_x), std::fabs(tri.hi_x), std::fabs(tri.lo_y),
                                        std::fabs(tri.hi_y)}));
  add_plane<double>(b, 1.0, 0.0, tri.hi_x, m);
  add_plane<double>(b, 0.0, 1.0, tri.hi_y, m);
  add_plane<double>(b, -1.0, 0.0, -tri.lo_x, m);
  add_plane<double>(b, 0.0, -1.0, -tri.lo_y, m);
  b.n_verts = 4;
  b.vx[0] = tri.lo_x, b.vy[0] = tri.lo_y, b.vx[1] = tri.hi_x, b.vy[1] = tri.lo_y;
  b.vx[2] = tri.hi_x, b.vy[2] = tri.hi_y, b.vx[3] = tri.lo_x, b.vy[3] = tri.hi_y;
  b.verts_valid = true;
  b.used = Method::kBox;
  b.out_vertices = 4;
  b.out_triangles = 2;
  b.area = (tri.hi_x - tri.lo_x) * (tri.hi_y - tri.lo_y);
}

// Convex hull (Andrew's monotone chain) of n points, counter-clockwise; returns its size.
// Costs: per comparison kHullCompare, per orientation test kHullCross.
template <class A, class D>
inline int convex_hull(D* px, D* py, int n, int* hull, std::uint64_t& ops) {
  int idx[kMaxPlanes * 2];
  for (int i = 0; i < n; ++i) idx[i] = i;
  std::uint64_t n_cmp = 0;
  std::stable_sort(idx, idx + n, [&](int a, int b) {
    ++n_cmp;
    const bool lt_x = px[a] < px[b];
    const bool gt_x = px[b] < px[a];
    const bool lt_y = py[a] < py[b];
    return lt_x || (!gt_x && lt_y);
  });
  if constexpr (A::counting) {
    ops += OpTally::take();
  } else {
    ops += n_cmp * cost::gpu::kHullCompare;
  }
  auto cross_le0 = [&](int o, int a, int b) {
    const D ax = px[a] - px[o], ay = py[a] - py[o], bx = px[b] - px[o], by = py[b] - py[o];
    const bool le = !(ax * by - ay * bx > D(0.0));
    charge<A>(ops, cost::gpu::kHullCross);
    return le;
  };
  int k = 0;
  for (int i = 0; i < n; ++i) {
    while (k >= 2 && cross_le0(hull[k - 2], hull[k - 1], idx[i])) --k;
    hull[k++] = idx[i];
  }
  for (int i = n - 2, t = k + 1; i >= 0; --i) {
    while (k >= t && cross_le0(hull[k - 2], hull[k - 1], idx[i])) --k;
    hull[k++] = idx[i];
  }
  return n > 1 ? k - 1 : n;
}

// Half-planes and vertices of the hull of (px, py); false if the hull has no area.
template <class A, class D>
inline bool hull_bound(D* px, D* py, int n, double mag, Bound& b, std::uint64_t& ops) {
  int hull[kMaxPlanes * 2 + 2];
  const int k = convex_hull<A>(px, py, n, hull, ops);
  if (k < 3 || k > kMaxPlanes) return false;
  double vx[kMaxPlanes], vy[kMaxPlanes];
  for (int i = 0; i < k; ++i) vx[i] = raw(px[hull[i]]), vy[i] = raw(py[hull[i]]);
  const double area = polygon_area(vx, vy, k);
  if (!(area > 0.0)) return false;
  const double m = margin_for(mag);
  b.n_planes = 0;
  for (int i = 0; i < k; ++i) {
    const int a = hull[i], c = hull[(i + 1) % k];
    const D dx = px[c] - px[a], dy = py[c] - py[a];
    const D h = madd(dy, px[a], (-dx) * py[a]);
    charge<A>(ops, cost::gpu::kHullEdge);
    // An edge between two hull points that coincide up to rounding (a volume of zero thickness: a
    // triangle in the focus plane) has no reliable direction; leaving its plane out only widens the
    // bound.
    if (std::fabs(raw(dx)) + std::fabs(raw(dy)) <= 1e-9 * mag) continue;
    add_plane(b, dy, -dx, h, m);
  }
  b.n_verts = k;
  for (int i = 0; i < k; ++i) b.vx[i] = vx[i], b.vy[i] = vy[i];
  b.verts_valid = true;
  b.area = area;
  b.out_vertices = k;
  b.out_triangles = k - 2;
  return true;
}

}  // namespace detail

// The geometry shader: the bound of tri by method (after the special cases). Operations go to ops.
template <class A>
class GeometryShader {
  using D = typename A::f64;
  using Shape = detail::Shape<D>;

 public:
  explicit GeometryShader(const GsFrame& g) : g_(g) {}

  Bound run(Method method, const TriSetup& tri, std::uint64_t& ops) const {
    Bound b;
    const bool three_d = method == Method::kWedge || method == Method::kReducedWedge || method == Method::kHexagon3D;
    if (method == Method::kBox) {
      detail::box_bound(tri, b);
      return b;
    }
    if (tri.moving) {
      if (method != Method::kConvexHull && method != Method::kAdaptive) b.fallback = Fallback::kMotion;
      if (tri.full_bounds) {  // may cross the near plane during the shutter: [McGuire 2010]'s box
        if (b.fallback == Fallback::kNone) b.fallback = Fallback::kNear;
        detail::box_bound(tri, b);
        return b;
      }
      hull(tri, b, ops);
      return b;
    }
    if (tri.near_clipped) {
      if (method == Method::kAdaptive) return volume(Method::kHexagon3D, tri, b, ops);
      if (three_d) return volume(method, tri, b, ops);
      b.fallback = Fallback::kNear;  // inverted planes ([Toth 2008] §4.8.1) / z = 0 crossing ([McGuire 2010])
      detail::box_bound(tri, b);
      return b;
    }
    if (three_d) return volume(method, tri, b, ops);
    if (method == Method::kConvexHull) {
      hull(tri, b, ops);
      return b;
    }
    return planar(method, tri, b, ops);
  }

 private:
  void degenerate(const TriSetup& tri, Bound& b) const {
    b.fallback = Fallback::kDegenerate;
    detail::box_bound(tri, b);
  }

  // [McGuire 2010]: the hull of the confusion boxes of the vertex positions (both shutter ends if moving).
  void hull(const TriSetup& tri, Bound& b, std::uint64_t& ops) const {
    D px[kMaxPlanes], py[kMaxPlanes];
    int n = 0;
    double mag = 0.0;
    const int ends = tri.moving ? 2 : 1;
    for (int e = 0; e < ends; ++e)
      for (int j = 0; j < 3; ++j) {
        const double X = tri.X[j] + (e ? static_cast<double>(tri.dX[j]) : 0.0);
        const double Y = tri.Y[j] + (e ? static_cast<double>(tri.dY[j]) : 0.0);
        const double W = tri.W[j] + (e ? static_cast<double>(tri.dW[j]) : 0.0);
        const Shape s = detail::shape<D>(X, Y, W, g_);
        charge<A>(ops, cost::gpu::kShape);
        const D lx = s.x - s.ex, hx = s.x + s.ex, ly = s.y - s.ey, hy = s.y + s.ey;
        px[n] = lx, py[n] = ly, ++n;
        px[n] = hx, py[n] = ly, ++n;
        px[n] = hx, py[n] = hy, ++n;
        px[n] = lx, py[n] = hy, ++n;
        charge<A>(ops, cost::gpu::kHullCorners);
        mag = std::max({mag, std::fabs(raw(s.x)) + raw(s.ex), std::fabs(raw(s.y)) + raw(s.ey)});
      }
    b.used = Method::kConvexHull;
    if (!detail::hull_bound<A>(px, py, n, mag, b, ops)) degenerate(tri, b);
  }

  // The shapes of the static triangle and its orientation (counter-clockwise order in ord).
  bool static_shapes(const TriSetup& tri, Shape s[3], int ord[3], D& area2, double& mag, std::uint64_t& ops) const {
    for (int j = 0; j < 3; ++j) {
      s[j] = detail::shape<D>(tri.X[j], tri.Y[j], tri.W[j], g_);
      charge<A>(ops, cost::gpu::kShape);
    }
    mag = 0.0;
    for (int j = 0; j < 3; ++j)
      mag = std::max({mag, std::fabs(raw(s[j].x)) + raw(s[j].ex), std::fabs(raw(s[j].y)) + raw(s[j].ey)});
    const D ax = s[1].x - s[0].x, ay = s[1].y - s[0].y, bx = s[2].x - s[0].x, by = s[2].y - s[0].y;
    area2 = ax * by - ay * bx;
    const bool ccw = area2 > D(0.0);
    const bool nondegenerate = vabs(area2) > D(1e-9 * (mag * mag + 1.0));
    charge<A>(ops, cost::gpu::kOrient);
    ord[0] = 0, ord[1] = ccw ? 1 : 2, ord[2] = ccw ? 2 : 1;
    if (!ccw) area2 = -area2;
    return nondegenerate;
  }

  // h(n) over the triangle's three shapes. Cost: 3 supports + 2 MAX.
  D support3(D nx, D ny, const Shape s[3]) const {
    D h = detail::support(nx, ny, s[0], g_.disk);
    h = vmax(h, detail::support(nx, ny, s[1], g_.disk));
    h = vmax(h, detail::support(nx, ny, s[2], g_.disk));
    return h;
  }
  std::uint64_t support3_cost() const { return 3 * cost::gpu::support_cost(g_.disk) + 2; }

  // Half-planes in counter-clockwise order -> vertices; false if two consecutive ones do not turn.
  bool close_polygon(const D* nx, const D* ny, const D* h, int k, Bound& b, double mag, std::uint64_t& ops) const {
    bool ok = true;
    b.n_planes = 0;
    const double m = detail::margin_for(mag);
    for (int i = 0; i < k; ++i) {
      const int j = (i + 1) % k;
      D x, y;
      ok &= detail::intersect(nx[i], ny[i], h[i], nx[j], ny[j], h[j], x, y);
      charge<A>(ops, cost::gpu::kIntersect);
      b.vx[i] = raw(x), b.vy[i] = raw(y);
      detail::add_plane(b, nx[i], ny[i], h[i], m);
    }
    b.n_verts = k;
    b.verts_valid = ok;
    b.area = ok ? detail::polygon_area(b.vx, b.vy, k) : std::numeric_limits<double>::infinity();
    return ok;
  }

  Bound& planar(Method method, const TriSetup& tri, Bound& b, std::uint64_t& ops) const {
    Shape s[3];
    int o[3];
    D area2;
    double mag;
    if (!static_shapes(tri, s, o, area2, mag, ops)) {
      degenerate(tri, b);
      return b;
    }
    if (method == Method::kAdaptive) {
      D r2 = madd(s[0].ex, s[0].ex, s[0].ey * s[0].ey);
      r2 = vmax(r2, madd(s[1].ex, s[1].ex, s[1].ey * s[1].ey));
      r2 = vmax(r2, madd(s[2].ex, s[2].ex, s[2].ey * s[2].ey));
      // small blur: r_max^2 <= ratio^2 * area (area = area2 / 2)
      const bool small = !(r2 > D(0.5 * g_.adaptive_ratio * g_.adaptive_ratio) * area2);
      charge<A>(ops, cost::gpu::kAdaptiveChoice);
      method = small ? Method::kPETriangle : Method::kHexagon2D;
    }
    // Outward unit edge normals of the counter-clockwise triangle.
    D enx[3], eny[3];
    for (int i = 0; i < 3; ++i) {
      const Shape& a = s[o[i]];
      const Shape& c = s[o[(i + 1) % 3]];
      detail::edge_normal(a.x, a.y, c.x, c.y, enx[i], eny[i]);
      charge<A>(ops, cost::gpu::kEdgeNormal);
    }
    D nx[6], ny[6], h[6];
    int k = 0;
    if (method == Method::kVRTriangle) {
      if (vr_planes(s, o, nx, ny, ops)) {
        for (int i = 0; i < 3; ++i) {
          h[i] = support3(nx[i], ny[i], s);
          charge<A>(ops, support3_cost());
        }
        b.used = Method::kVRTriangle;
        b.out_vertices = 3, b.out_triangles = 1;
        if (close_polygon(nx, ny, h, 3, b, mag, ops)) return b;
      }
      b.fallback = Fallback::kVR;  // no outer tangent, or the tangents invert ([Toth 2008] §4.6)
      method = Method::kPETriangle;
    }
    if (method == Method::kPETriangle) {
      for (int i = 0; i < 3; ++i) nx[k] = enx[i], ny[k] = eny[i], ++k;
      b.out_vertices = 3, b.out_triangles = 1;
    } else {  // hexagon2d: edge i, then the vertex between edges i and i + 1 (averaged normal)
      for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3;
        nx[k] = enx[i], ny[k] = eny[i], ++k;
        nx[k] = enx[i] + enx[j], ny[k] = eny[i] + eny[j], ++k;
        charge<A>(ops, cost::gpu::kBisector);
      }
      b.out_vertices = 6, b.out_triangles = 4;
    }
    for (int i = 0; i < k; ++i) {
      h[i] = support3(nx[i], ny[i], s);
      charge<A>(ops, support3_cost());
    }
    b.used = method;
    if (!close_polygon(nx, ny, h, k, b, mag, ops)) degenerate(tri, b);
    return b;
  }

  // [Toth 2008] §4.6: per edge the outer tangent of the confusion circles at its ends.
  bool vr_planes(const Shape s[3], const int o[3], D* nx, D* ny, std::uint64_t& ops) const {
    D r[3];
    for (int j = 0; j < 3; ++j) {
      r[j] = g_.disk ? vmax(s[j].ex, s[j].ey) : vsqrt(madd(s[j].ex, s[j].ex, s[j].ey * s[j].ey));
      charge<A>(ops, g_.disk ? cost::gpu::kVRRadiusDisk : cost::gpu::kVRRadiusSquare);
    }
    bool ok = true;
    for (int i = 0; i < 3; ++i) {
      const int a = o[i], c = o[(i + 1) % 3];
      const D dx = s[c].x - s[a].x, dy = s[c].y - s[a].y;
      const D len = vsqrt(madd(dx, dx, dy * dy));
      const D inv = rcp(len);
      const D tx = dx * inv, ty = dy * inv;
      const D beta = (r[a] - r[c]) * inv;
      const D q = madd(-beta, beta, D(1.0));
      ok &= q > D(0.0);
      const D alpha = vsqrt(vmax(q, D(0.0)));
      nx[i] = madd(alpha, ty, beta * tx);
      ny[i] = madd(alpha, -tx, beta * ty);
      charge<A>(ops, cost::gpu::kVRTangent);
    }
    return ok;
  }

  // [Toth 2008] §4.4-4.5, 3D: the hexagon / wedge in the triangle's plane, extruded along its normal, in
  // the view-like space Q = (X s, Y s, W) where the disc of confusion of a point is the lens set
  // scaled by (kx s (W - F), ky s (W - F)) at constant W; projected (and clipped at the near plane).
  Bound& volume(Method method, const TriSetup& tri, Bound& b, std::uint64_t& ops) const {
    D P[3][3];
    for (int j = 0; j < 3; ++j) P[j][0] = D(tri.X[j]) * D(g_.s), P[j][1] = D(tri.Y[j]) * D(g_.s), P[j][2] = D(tri.W[j]);
    D e1[3], f[3], N[3], e2[3];
    for (int c = 0; c < 3; ++c) e1[c] = P[1][c] - P[0][c], f[c] = P[2][c] - P[0][c];
    cross(e1, f, N);
    const D nl = vsqrt(madd(N[0], N[0], madd(N[1], N[1], N[2] * N[2])));
    const D ninv = rcp(nl);
    for (int c = 0; c < 3; ++c) N[c] = N[c] * ninv;
    const D el = vsqrt(madd(e1[0], e1[0], madd(e1[1], e1[1], e1[2] * e1[2])));
    const D einv = rcp(el);
    D u1[3];
    for (int c = 0; c < 3; ++c) u1[c] = e1[c] * einv;
    cross(N, u1, e2);
    D q[3][2];
    q[0][0] = D(0.0), q[0][1] = D(0.0);
    q[1][0] = dot(e1, u1), q[1][1] = dot(e1, e2);
    q[2][0] = dot(f, u1), q[2][1] = dot(f, e2);
    double mag = 0.0;
    for (int j = 0; j < 3; ++j) mag = std::max(mag, std::fabs(raw(P[j][0])) + std::fabs(raw(P[j][1])) + std::fabs(raw(P[j][2])));
    const bool ok_plane = nl > D(1e-15 * (mag * mag + 1e-300));
    D gj[3];
    for (int j = 0; j < 3; ++j) gj[j] = vabs(P[j][2] - D(g_.focus));
    charge<A>(ops, cost::gpu::kPlane);
    if (!ok_plane) {
      degenerate(tri, b);
      return b;
    }
    const D kxs(g_.kx * g_.s), kys(g_.ky * g_.s);
    auto lens_term = [&](D a, D c) { return g_.disk ? vsqrt(madd(a, a, c * c)) : vabs(a) + vabs(c); };
    // In-plane directions: edge normals (and averaged vertex normals for the hexagon).
    D enx[3], eny[3];
    for (int i = 0; i < 3; ++i) {
      detail::edge_normal(q[i][0], q[i][1], q[(i + 1) % 3][0], q[(i + 1) % 3][1], enx[i], eny[i]);
      charge<A>(ops, cost::gpu::kEdgeNormal);
    }
    D mx[6], my[6], h[6];
    int k = 0;
    const bool hex = method == Method::kHexagon3D;
    for (int i = 0; i < 3; ++i) {
      mx[k] = enx[i], my[k] = eny[i], ++k;
      if (hex) {
        const int j = (i + 1) % 3;
        mx[k] = enx[i] + enx[j], my[k] = eny[i] + eny[j], ++k;
        charge<A>(ops, cost::gpu::kBisector);
      }
    }
    for (int i = 0; i < k; ++i) {
      const D Mx = madd(mx[i], u1[0], my[i] * e2[0]);
      const D My = madd(mx[i], u1[1], my[i] * e2[1]);
      const D S0 = lens_term(Mx * kxs, My * kys);
      D hi = madd(mx[i], q[0][0], my[i] * q[0][1]) + gj[0] * S0;
      hi = vmax(hi, madd(mx[i], q[1][0], my[i] * q[1][1]) + gj[1] * S0);
      hi = vmax(hi, madd(mx[i], q[2][0], my[i] * q[2][1]) + gj[2] * S0);
      h[i] = hi;
      charge<A>(ops, cost::gpu::support3d_cost(g_.disk));
    }
    const D d = vmax(vmax(gj[0], gj[1]), gj[2]) * lens_term(N[0] * kxs, N[1] * kys);
    charge<A>(ops, cost::gpu::normal_extent_cost(g_.disk));
    // In-plane polygon.
    D ax[6], ay[6];
    bool ok = true;
    for (int i = 0; i < k; ++i) {
      const int j = (i + 1) % k;
      ok &= detail::intersect(mx[i], my[i], h[i], mx[j], my[j], h[j], ax[i], ay[i]);
      charge<A>(ops, cost::gpu::kIntersect);
    }
    if (!ok) {
      degenerate(tri, b);
      return b;
    }
    // Prism vertices, their near-plane test, projection or pairwise clipping.
    D V[12][3];
    bool front[12];
    int nv = 0;
    bool all_front = true;
    for (int i = 0; i < k; ++i) {
      D base[3];
      for (int c = 0; c < 3; ++c) base[c] = madd(ax[i], u1[c], madd(ay[i], e2[c], P[0][c]));
      for (int c = 0; c < 3; ++c) V[nv][c] = madd(d, N[c], base[c]), V[nv + 1][c] = madd(-d, N[c], base[c]);
      charge<A>(ops, cost::gpu::kPrismVertex);
      nv += 2;
    }
    const D nearp(g_.near_clip);
    for (int i = 0; i < nv; ++i) {
      front[i] = V[i][2] >= nearp;
      charge<A>(ops, cost::gpu::kNearCheck);
      all_front &= front[i];
    }
    D px[kMaxPlanes * 2], py[kMaxPlanes * 2];
    int n = 0;
    double smag = 0.0;
    for (int i = 0; i < nv; ++i) {
      if (!front[i]) continue;
      const D rs = rcp(V[i][2]) * D(g_.inv_s);
      px[n] = V[i][0] * rs, py[n] = V[i][1] * rs;
      charge<A>(ops, cost::gpu::kProject);
      smag = std::max({smag, std::fabs(raw(px[n])), std::fabs(raw(py[n]))});
      ++n;
    }
    if (!all_front) {
      b.volume_clipped = true;
      const D cnear(g_.inv_s / g_.near_clip);
      for (int i = 0; i < nv; ++i)
        for (int j = i + 1; j < nv; ++j) {
          if (front[i] == front[j]) continue;
          const D t = (nearp - V[i][2]) * rcp(V[j][2] - V[i][2]);
          const D Qx = madd(t, V[j][0] - V[i][0], V[i][0]);
          const D Qy = madd(t, V[j][1] - V[i][1], V[i][1]);
          px[n] = Qx * cnear, py[n] = Qy * cnear;
          charge<A>(ops, cost::gpu::kClipPair);
          smag = std::max({smag, std::fabs(raw(px[n])), std::fabs(raw(py[n]))});
          ++n;
        }
    }
    b.used = method;
    if (!detail::hull_bound<A>(px, py, n, smag, b, ops)) {
      degenerate(tri, b);
      return b;
    }
    // Emitted geometry: the hexagon volume 12 vertices / 20 triangles, the wedge 6 / 8 ([Toth 2008]
    // Table 1); the reduced wedge its silhouette as one strip, when it exists (all in front).
    if (method == Method::kHexagon3D) {
      b.out_vertices = 12, b.out_triangles = 20;
    } else if (method == Method::kWedge || !all_front) {
      if (method == Method::kReducedWedge) b.fallback = Fallback::kReduced;
      b.out_vertices = 6, b.out_triangles = 8;
    }  // reduced wedge: hull_bound set the silhouette's n vertices, n - 2 triangles
    return b;
  }

  static void cross(const D a[3], const D b[3], D out[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
  }
  static D dot(const D a[3], const D b[3]) { return madd(a[0], b[0], madd(a[1], b[1], a[2] * b[2])); }

  GsFrame g_;
};

}  // namespace rast5d::gpu
