#include "setup/setup.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/costs.h"
#include "tiletest/edges_2d.h"

namespace rast5d {

FrameConst make_frame_const(const RenderParams& p) {
  FrameConst fc;
  fc.width = p.width;
  fc.height = p.height;
  fc.kx = static_cast<float>(p.coc_x_px);
  fc.ky = static_cast<float>(p.coc_y_px);
  fc.focus = static_cast<float>(p.focus_w);
  fc.lens_active = p.table_has_lens && (fc.kx != 0.0f || fc.ky != 0.0f);
  fc.time_active = p.table_has_time;
  // The same float products as the kernels, so W == F gives a shear coefficient of exactly 0.
  fc.neg_kx_f = -(fc.kx * fc.focus);
  fc.neg_ky_f = -(fc.ky * fc.focus);
  fc.neg_near = -static_cast<float>(p.near_w);
  fc.kx_d = fc.kx;
  fc.ky_d = fc.ky;
  fc.focus_d = fc.focus;
  fc.near_d = static_cast<float>(p.near_w);
  return fc;
}

namespace {

// Conservative widening of float bounds before they are rounded to whole pixels. The float
// sample test can place a hit a few ulps of the coordinates outside the exact triangle; this is
// orders of magnitude more than that.
inline double widen_lo(double v) { return v - (std::fabs(v) * 0x1p-12 + 0x1p-8); }
inline double widen_hi(double v) { return v + (std::fabs(v) * 0x1p-12 + 0x1p-8); }

// Near-plane clip of a static triangle (Sutherland-Hodgman on W >= w_clip), in double.
int clip_near(const double in[3][3], double w_clip, double out[4][3]) {
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const double* a = in[i];
    const double* b = in[(i + 1) % 3];
    const bool ain = a[2] >= w_clip, bin = b[2] >= w_clip;
    if (ain) {
      for (int k = 0; k < 3; ++k) out[n][k] = a[k];
      ++n;
    }
    if (ain != bin) {
      const double s = (w_clip - a[2]) / (b[2] - a[2]);
      for (int k = 0; k < 3; ++k) out[n][k] = a[k] + s * (b[k] - a[k]);
      out[n][2] = w_clip;
      ++n;
    }
  }
  return n;
}

// det of the sheared vertex matrix at lens point (u, v): the orientation seen from there.
double sheared_det(const double P[3][3], double kx, double ky, double focus, double u, double v) {
  double M[3][3];
  for (int j = 0; j < 3; ++j) {
    M[j][0] = P[j][0] + u * kx * (P[j][2] - focus);
    M[j][1] = P[j][1] + v * ky * (P[j][2] - focus);
    M[j][2] = P[j][2];
  }
  return M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) -
         M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
         M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]);
}

// Whether every vertex (at both ends of the shutter if moving) lies behind the near plane; any_near
// says whether one does.
bool behind_near(const float* v0, const float* v1, bool moving, float near_f, bool& any_near) {
  bool all_near = true;
  any_near = false;
  for (int j = 0; j < 3; ++j) {
    for (int e = 0; e < (moving ? 2 : 1); ++e) {
      const float w = (e == 0 ? v0 : v1)[3 * j + 2];
      if (w < near_f) {
        any_near = true;
      } else {
        all_near = false;
      }
    }
  }
  return all_near;
}

// Static triangle crossing the near plane: o.poly = the part in front of it and its screen bounds
// (swept over the lens when defocused). Samples whose hit point is behind the near plane are
// rejected, so this is conservative; the clip plane sits a little nearer than the near plane to
// cover the float depth test's rounding.
void clipped_bounds(TriSetup& o, const FrameConst& fc, bool defocused, double& lo_x, double& hi_x, double& lo_y,
                    double& hi_y) {
  o.near_clipped = true;
  double tri[3][3];
  for (int j = 0; j < 3; ++j) tri[j][0] = o.X[j], tri[j][1] = o.Y[j], tri[j][2] = o.W[j];
  o.poly_n = clip_near(tri, fc.near_d * (1.0 - 0x1p-12), o.poly);
  lo_x = lo_y = std::numeric_limits<double>::infinity();
  hi_x = hi_y = -std::numeric_limits<double>::infinity();
  for (int j = 0; j < o.poly_n; ++j) {
    const double px = o.poly[j][0] / o.poly[j][2], py = o.poly[j][1] / o.poly[j][2];
    const double b = defocused ? 1.0 - fc.focus_d / o.poly[j][2] : 0.0;
    const double ex = std::fabs(b * fc.kx_d), ey = std::fabs(b * fc.ky_d);
    lo_x = std::min(lo_x, px - ex), hi_x = std::max(hi_x, px + ex);
    lo_y = std::min(lo_y, py - ey), hi_y = std::max(hi_y, py + ey);
  }
}

// The bounds widened and rounded to the pixel rectangle [bx0, bx1) x [by0, by1) on screen; false
// when it is empty (off screen).
bool pixel_rect(TriSetup& o, const RenderParams& p, double lo_x, double hi_x, double lo_y, double hi_y) {
  auto to_lo = [](double v, int limit) {
    v = std::floor(widen_lo(v));
    if (!(v > 0.0)) return 0;
    return v > limit ? limit : static_cast<int>(v);
  };
  auto to_hi = [](double v, int limit) {
    v = std::floor(widen_hi(v)) + 1.0;
    if (!(v < limit)) return limit;
    return v < 0.0 ? 0 : static_cast<int>(v);
  };
  o.lo_x = lo_x, o.hi_x = hi_x, o.lo_y = lo_y, o.hi_y = hi_y;
  o.bx0 = to_lo(lo_x, p.width);
  o.bx1 = to_hi(hi_x, p.width);
  o.by0 = to_lo(lo_y, p.height);
  o.by1 = to_hi(hi_y, p.height);
  return o.bx0 < o.bx1 && o.by0 < o.by1;
}

// Degenerate static triangles: if the footprint projects to (nearly) a single point from every
// lens corner, its area is below what the float sample test resolves, whose rounding would then
// decide coverage (spurious hits around the point). Such a triangle covers no sample in exact
// arithmetic (up to a negligible probability), so it is culled. A triangle seen edge-on through
// the pinhole still projects to a segment and is kept.
bool degenerate(const TriSetup& o, const FrameConst& fc, bool defocused) {
  // Zero area in 3D (collinear vertices, up to the float rounding of the vertices): thinner than
  // a few ulps of its coordinates, so exact coverage is empty and the float sample test would only
  // see rounding noise along the projected segment.
  const double V[3][3] = {{o.X[0], o.X[1], o.X[2]}, {o.Y[0], o.Y[1], o.Y[2]}, {o.W[0], o.W[1], o.W[2]}};
  double e1[3], e2[3], pmax = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double a = V[k][0], b1 = V[k][1], b2 = V[k][2];
    e1[k] = b1 - a, e2[k] = b2 - a;
    pmax = std::max({pmax, std::fabs(a), std::fabs(b1), std::fabs(b2)});
  }
  const double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2],
               cz = e1[0] * e2[1] - e1[1] * e2[0];
  const double cross = std::sqrt(cx * cx + cy * cy + cz * cz);
  const double l1 = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  const double l2 = std::sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
  if (!(cross > 0x1p-20 * pmax * (l1 + l2))) return true;
  if (o.poly_n < 3) return false;
  double extent = 0.0, mag = 0.0;
  const int corners = defocused ? 4 : 1;
  for (int k = 0; k < corners; ++k) {
    const double u = defocused ? ((k & 1) ? 1.0 : -1.0) : 0.0, v = defocused ? ((k & 2) ? 1.0 : -1.0) : 0.0;
    double lx = std::numeric_limits<double>::infinity(), hx = -lx, ly = lx, hy = -lx;
    for (int j = 0; j < o.poly_n; ++j) {
      const double w = o.poly[j][2];
      const double b = 1.0 - fc.focus_d / w;
      const double x = o.poly[j][0] / w + u * fc.kx_d * b, y = o.poly[j][1] / w + v * fc.ky_d * b;
      lx = std::min(lx, x), hx = std::max(hx, x), ly = std::min(ly, y), hy = std::max(hy, y);
      mag = std::max(mag, std::max(std::fabs(x), std::fabs(y)));
    }
    extent = std::max(extent, (hx - lx) + (hy - ly));
  }
  return !(extent > 0x1p-20 * (mag + 1.0));
}

// A static triangle back-facing from every lens point (det > 0; det is affine in (u, v), so the
// lens-square corners decide).
bool back_facing(const TriSetup& o, const FrameConst& fc, bool defocused) {
  double P[3][3];
  for (int j = 0; j < 3; ++j) P[j][0] = o.X[j], P[j][1] = o.Y[j], P[j][2] = o.W[j];
  bool all_back = true;
  const double us[4] = {-1, 1, -1, 1}, vs[4] = {-1, -1, 1, 1};
  for (int k = 0; k < (defocused ? 4 : 1); ++k) {
    const double d = defocused ? sheared_det(P, fc.kx_d, fc.ky_d, fc.focus_d, us[k], vs[k])
                               : sheared_det(P, 0, 0, fc.focus_d, 0, 0);
    all_back &= d > 0.0;
  }
  return all_back;
}

}  // namespace

template <class A>
bool setup_triangle(const float* v0, const float* v1, const float* col, std::uint32_t index,
                    const RenderParams& p, const FrameConst& fc, TriSetup& o, Counters& c) {
  using F = typename A::f32;
  ++c[Counter::setup_triangles];
  o.index = index;
  for (int j = 0; j < 3; ++j) {
    o.X[j] = v0[3 * j + 0];
    o.Y[j] = v0[3 * j + 1];
    o.W[j] = v0[3 * j + 2];
    for (int ch = 0; ch < 3; ++ch) o.color[j][ch] = col[3 * j + ch];
  }
  bool moving = false;
  if (fc.time_active)
    for (int i = 0; i < 9; ++i) moving |= (v1[i] != v0[i]);
  o.moving = moving;

  // Near plane: common to all algorithms, not counted ([Akenine-Möller 2012] §6.2).
  bool any_near;
  if (behind_near(v0, v1, moving, -fc.neg_near, any_near)) {
    ++c[Counter::setup_culled_near];
    return false;
  }

  std::uint64_t& ops = c[Counter::ops_setup];
  if (moving) {
    F d[9];
    for (int i = 0; i < 9; ++i) d[i] = F(v1[i]) - F(v0[i]);
    charge<A>(ops, cost::kSetupMotion);
    for (int j = 0; j < 3; ++j) {
      o.dX[j] = raw(d[3 * j]);
      o.dY[j] = raw(d[3 * j + 1]);
      o.dW[j] = raw(d[3 * j + 2]);
    }
  } else {
    for (int j = 0; j < 3; ++j) o.dX[j] = o.dY[j] = o.dW[j] = 0.0f;
  }

  bool defocused = false;
  for (int j = 0; j < 3; ++j) o.cx[j] = o.cy[j] = 0.0f;
  if (fc.lens_active) {
    if (!moving) {
      for (int j = 0; j < 3; ++j) {
        o.cx[j] = raw(madd(F(o.W[j]), F(fc.kx), F(fc.neg_kx_f)));
        o.cy[j] = raw(madd(F(o.W[j]), F(fc.ky), F(fc.neg_ky_f)));
        defocused |= (o.cx[j] != 0.0f) || (o.cy[j] != 0.0f);
      }
      charge<A>(ops, cost::kSetupShear);
    } else {
      for (int j = 0; j < 3; ++j) defocused |= (o.W[j] != fc.focus) || (o.dW[j] != 0.0f);
    }
  }
  o.defocused = defocused;
  o.cls = moving ? (defocused ? DimClass::k5D : DimClass::k3D)
                 : (defocused ? DimClass::k4D : DimClass::k2D);

  // Bounds.
  double lo_x, hi_x, lo_y, hi_y;
  o.near_clipped = o.full_bounds = false;
  o.poly_n = 0;
  if (!any_near) {
    const F inf(std::numeric_limits<float>::infinity());
    F minx = inf, miny = inf, maxx = -inf, maxy = -inf;
    const int ends = moving ? 2 : 1;
    for (int e = 0; e < ends; ++e) {
      const float* v = e == 0 ? v0 : v1;
      for (int j = 0; j < 3; ++j) {
        bounds_point(F(v[3 * j]), F(v[3 * j + 1]), F(v[3 * j + 2]), F(-fc.focus), F(fc.kx), F(fc.ky),
                     defocused, minx, maxx, miny, maxy);
        charge<A>(ops, defocused ? cost::kBoundsPointLens : cost::kBoundsPoint);
      }
    }
    lo_x = raw(minx), hi_x = raw(maxx), lo_y = raw(miny), hi_y = raw(maxy);
    if (!moving) {
      o.poly_n = 3;
      for (int j = 0; j < 3; ++j) o.poly[j][0] = o.X[j], o.poly[j][1] = o.Y[j], o.poly[j][2] = o.W[j];
    }
  } else if (!moving) {
    ++c[Counter::setup_near_clipped];
    clipped_bounds(o, fc, defocused, lo_x, hi_x, lo_y, hi_y);
  } else {
    // Moving and possibly crossing the near plane during the shutter: the projection is unbounded.
    ++c[Counter::setup_bbox_fallback];
    o.full_bounds = true;
    lo_x = lo_y = -1.0;
    hi_x = p.width + 1.0;
    hi_y = p.height + 1.0;
  }

  if (!pixel_rect(o, p, lo_x, hi_x, lo_y, hi_y)) {
    ++c[Counter::setup_culled_offscreen];
    return false;
  }

  // Degenerate static triangles (degenerate()): culled, their operations not charged (robustness,
  // like the near plane); the culls are counted in setup.culled_degenerate.
  if (!moving && degenerate(o, fc, defocused)) {
    ++c[Counter::setup_culled_degenerate];
    return false;
  }
  // Optional back-face culling of static triangles back-facing from every lens point. Not counted
  // ([Akenine-Möller 2012] §6.2).
  if (p.backface_cull && !moving && back_facing(o, fc, defocused)) {
    ++c[Counter::setup_culled_backface];
    return false;
  }

  switch (o.cls) {
    case DimClass::k2D:
      ++c[Counter::setup_class_2d];
      if (p.cost_model == CostModel::kHardware) {  // the affine sample test's edges (sampletest/hardware.h)
        tiletest::edges_2d<typename A::f64>(o.X, o.Y, o.W);
        charge<A>(ops, cost::kEdges2DSetup);
      }
      break;
    case DimClass::k3D: ++c[Counter::setup_class_3d]; break;
    case DimClass::k4D: ++c[Counter::setup_class_4d]; break;
    case DimClass::k5D: ++c[Counter::setup_class_5d]; break;
  }
  return true;
}

template bool setup_triangle<FastArith>(const float*, const float*, const float*, std::uint32_t,
                                        const RenderParams&, const FrameConst&, TriSetup&, Counters&);
template bool setup_triangle<ExactArith>(const float*, const float*, const float*, std::uint32_t,
                                         const RenderParams&, const FrameConst&, TriSetup&, Counters&);

}  // namespace rast5d

namespace rast5d {

int setup_bounds(const float* v0, const float* v1, const RenderParams& p, const FrameConst& fc, TriSetup& o) {
  // The same steps and float operations as setup_triangle<FastArith> up to its culls.
  for (int j = 0; j < 3; ++j) o.X[j] = v0[3 * j + 0], o.Y[j] = v0[3 * j + 1], o.W[j] = v0[3 * j + 2];
  bool moving = false;
  if (fc.time_active)
    for (int i = 0; i < 9; ++i) moving |= (v1[i] != v0[i]);
  o.moving = moving;
  bool any_near;
  if (behind_near(v0, v1, moving, -fc.neg_near, any_near)) return 1;
  bool defocused = false;
  for (int j = 0; j < 3; ++j) o.cx[j] = o.cy[j] = 0.0f;
  if (fc.lens_active) {
    if (!moving) {
      for (int j = 0; j < 3; ++j) {
        o.cx[j] = madd(o.W[j], fc.kx, fc.neg_kx_f);
        o.cy[j] = madd(o.W[j], fc.ky, fc.neg_ky_f);
        defocused |= (o.cx[j] != 0.0f) || (o.cy[j] != 0.0f);
      }
    } else {
      for (int j = 0; j < 3; ++j) defocused |= (o.W[j] != fc.focus) || (v1[3 * j + 2] - v0[3 * j + 2] != 0.0f);
    }
  }
  o.defocused = defocused;
  double lo_x, hi_x, lo_y, hi_y;
  o.near_clipped = o.full_bounds = false;
  o.poly_n = 0;
  if (!any_near) {
    const float inf = std::numeric_limits<float>::infinity();
    float minx = inf, miny = inf, maxx = -inf, maxy = -inf;
    for (int e = 0; e < (moving ? 2 : 1); ++e) {
      const float* v = e == 0 ? v0 : v1;
      for (int j = 0; j < 3; ++j)
        bounds_point(v[3 * j], v[3 * j + 1], v[3 * j + 2], -fc.focus, fc.kx, fc.ky, defocused, minx, maxx, miny, maxy);
    }
    lo_x = minx, hi_x = maxx, lo_y = miny, hi_y = maxy;
    if (!moving) {
      o.poly_n = 3;
      for (int j = 0; j < 3; ++j) o.poly[j][0] = o.X[j], o.poly[j][1] = o.Y[j], o.poly[j][2] = o.W[j];
    }
  } else if (!moving) {
    clipped_bounds(o, fc, defocused, lo_x, hi_x, lo_y, hi_y);
  } else {
    o.full_bounds = true;
    lo_x = lo_y = -1.0;
    hi_x = p.width + 1.0;
    hi_y = p.height + 1.0;
  }
  if (!pixel_rect(o, p, lo_x, hi_x, lo_y, hi_y)) return 2;
  if (!moving && degenerate(o, fc, defocused)) return 3;
  if (p.backface_cull && !moving && back_facing(o, fc, defocused)) return 4;
  return 0;
}

}  // namespace rast5d
