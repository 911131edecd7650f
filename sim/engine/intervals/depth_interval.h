// Depth intervals ẑ (002_95ea0844b256f75b.txt Appendix A): a conservative interval of the depth a
// (triangle, tile) pair can produce, for HiZ culling and occlusion queries (backend/zcull.h).
//
// Contract (tested in tests/test_intervals.py against the brute-force sample test): the depth
// z = 1 - near / W_hit of every sample of the tile that the exact sample test hits, at a time in
// [ta, tb] and a lens point in the given box, is inside ẑ widened by kDepthMargin (zhat_widen).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/arith.h"
#include "core/costs.h"
#include "intervals/clip.h"
#include "setup/setup.h"

namespace rast5d::iv {

// Relative margin on W applied to ẑ before it is compared with depths computed by the float
// sample test (docs/conventions.md: float hit depths can be off by several % near the camera).
inline constexpr double kDepthMargin = 0.125;

struct ZHat {
  double zlo = 0, zhi = 1;      // depth z = 1 - near / W
  double wlo = 0, whi = kInfD;  // view depth W
  double vwlo = 0, vwhi = kInfD;  // vertex min/max only (for the tightness report)
};

// Per-triangle moving planes (002 App. A Eq. 1): for base time tau in {0, 1} the triangle's plane
// n . P + d = 0 at tau, pushed along its normal by v so that the whole moving triangle stays on
// the side n . P + d + v |t - tau| <= 0.
struct MovingPlanes {
  int n = 0;
  double nx[4], ny[4], nw[4], d[4], v[4], tau[4];
};

// Cost: cost::kZhatPlaneSetup.
template <class A>
inline void moving_planes(const TriSetup& tri, MovingPlanes& mp, std::uint64_t& ops) {
  using D = typename A::f64;
  D Q[2][3][3];
  for (int j = 0; j < 3; ++j) {
    Q[0][j][0] = D(static_cast<double>(tri.X[j]));
    Q[0][j][1] = D(static_cast<double>(tri.Y[j]));
    Q[0][j][2] = D(static_cast<double>(tri.W[j]));
    Q[1][j][0] = Q[0][j][0] + D(static_cast<double>(tri.dX[j]));
    Q[1][j][1] = Q[0][j][1] + D(static_cast<double>(tri.dY[j]));
    Q[1][j][2] = Q[0][j][2] + D(static_cast<double>(tri.dW[j]));
  }
  mp.n = 0;
  for (int base = 0; base < 2; ++base) {
    const auto& q = Q[base];
    const auto& r = Q[1 - base];
    D e1[3], e2[3];
    for (int a = 0; a < 3; ++a) e1[a] = q[1][a] - q[0][a], e2[a] = q[2][a] - q[0][a];
    const D nx = madd(e1[1], e2[2], -(e1[2] * e2[1]));
    const D ny = madd(e1[2], e2[0], -(e1[0] * e2[2]));
    const D nw = madd(e1[0], e2[1], -(e1[1] * e2[0]));
    const D d = -madd(nx, q[0][0], madd(ny, q[0][1], nw * q[0][2]));
    // distances of the other end's vertices from the plane
    D dist[3];
    for (int j = 0; j < 3; ++j) dist[j] = madd(nx, r[j][0], madd(ny, r[j][1], madd(nw, r[j][2], d)));
    const D mx = vmax(dist[0], vmax(dist[1], dist[2]));
    const D mn = vmin(dist[0], vmin(dist[1], dist[2]));
    // orientation +n: v = -max (Eq. 1); orientation -n: the plane -n . P - d, v = -max(-dist) = min
    for (int o = 0; o < 2; ++o) {
      const double s = o ? -1.0 : 1.0;
      mp.nx[mp.n] = s * raw(nx), mp.ny[mp.n] = s * raw(ny), mp.nw[mp.n] = s * raw(nw), mp.d[mp.n] = s * raw(d);
      mp.v[mp.n] = o ? raw(mn) : -raw(mx);
      mp.tau[mp.n] = base;
      ++mp.n;
    }
  }
  charge<A>(ops, cost::kZhatPlaneSetup);
}

// ẑ of the pair: the vertex (moving box) bound over t̂ = [ta, tb], tightened by the moving planes
// evaluated at the corners of the (x, y, u, v, t) box when the plane does not sweep over it
// (its ray-direction term keeps one sign at every corner). planes = nullptr: vertex bound only.
// Cost: cost::kZhatVertex + cost::zhat_plane_cost(lens) when planes are used (fixed per call).
template <class A>
inline ZHat zhat(const TriSetup& tri, const MovingPlanes* planes, const FrameConst& fc, bool lens, double x0,
                 double x1, double y0, double y1, double u0, double u1, double v0, double v1, double ta, double tb,
                 std::uint64_t& ops) {
  using D = typename A::f64;
  ZHat z;
  D wlo(kInfD), whi(-kInfD);
  for (int j = 0; j < 3; ++j) {
    const D W0(static_cast<double>(tri.W[j])), dW(static_cast<double>(tri.dW[j]));
    const D a = madd(D(ta), dW, W0), b = madd(D(tb), dW, W0);
    wlo = vmin(wlo, vmin(a, b));
    whi = vmax(whi, vmax(a, b));
  }
  z.vwlo = raw(wlo), z.vwhi = raw(whi);
  if (planes) {
    const D kx(fc.kx_d), ky(fc.ky_d), F(fc.focus_d);
    const int nl = lens ? 2 : 1;
    for (int i = 0; i < planes->n; ++i) {
      const D nx(planes->nx[i]), ny(planes->ny[i]), nw(planes->nw[i]), d(planes->d[i]), vv(planes->v[i]);
      // Along the ray through pixel (x, y) from lens point (u, v): P(W) = (W (x - u kx) + u kx F,
      // W (y - v ky) + v ky F, W); n . P + d + v |t - tau| = W Den + Num.
      D dens[2][2][2][2], nums[2][2][2];
      int pos = 0, neg = 0;
      for (int a = 0; a < nl; ++a)
        for (int b = 0; b < nl; ++b) {
          const D u = lens ? D(a ? u1 : u0) : D(0.0), v = lens ? D(b ? v1 : v0) : D(0.0);
          for (int cx = 0; cx < 2; ++cx)
            for (int cy = 0; cy < 2; ++cy) {
              const D xr = lens ? madd(-u, kx, D(cx ? x1 : x0)) : D(cx ? x1 : x0);
              const D yr = lens ? madd(-v, ky, D(cy ? y1 : y0)) : D(cy ? y1 : y0);
              const D den = madd(nx, xr, madd(ny, yr, nw));
              dens[a][b][cx][cy] = den;
              pos += den > D(0.0);
              neg += den < D(0.0);
            }
          const D lensterm = lens ? madd(nx * u, kx * F, madd(ny * v, ky * F, d)) : d;
          for (int ct = 0; ct < 2; ++ct) {
            const double tt = ct ? tb : ta;
            const D dt(std::fabs(tt - planes->tau[i]));
            nums[a][b][ct] = madd(vv, dt, lensterm);
          }
        }
      const int corners = nl * nl * 4;
      // Den > 0 everywhere: W <= -Num / Den (upper bound); Den < 0 everywhere: lower bound. The
      // bound is linear-fractional over the box, so its extreme is at a corner.
      D ext = pos == corners ? D(-kInfD) : D(kInfD);
      for (int a = 0; a < nl; ++a)
        for (int b = 0; b < nl; ++b)
          for (int cx = 0; cx < 2; ++cx)
            for (int cy = 0; cy < 2; ++cy) {
              const D r = rcp(dens[a][b][cx][cy]);
              for (int ct = 0; ct < 2; ++ct) {
                const D w = -(nums[a][b][ct] * r);
                ext = pos == corners ? vmax(ext, w) : vmin(ext, w);
              }
            }
      // (the plane sweeps over the box when Den changes sign: no bound from it)
      whi = vmin(whi, pos == corners ? ext : D(kInfD));
      wlo = vmax(wlo, neg == corners ? ext : D(-kInfD));
    }
  }
  wlo = vmax(wlo, D(fc.near_d));
  z.wlo = raw(wlo), z.whi = raw(whi);
  const D nn(-fc.near_d), one(1.0);
  z.zlo = raw(madd(nn, rcp(wlo), one));
  z.zhi = raw(whi) >= kInfD ? 1.0 : raw(madd(nn, rcp(whi), one));
  charge<A>(ops, cost::kZhatVertex + (planes ? cost::zhat_plane_cost(lens) : 0));
  return z;
}

// ẑ widened for comparisons with float sample depths (kDepthMargin on W).
inline void zhat_widen(const ZHat& z, double near, double& zlo, double& zhi) {
  const double wl = std::max(near, z.wlo) * (1.0 - kDepthMargin);
  const double wh = z.whi * (1.0 + kDepthMargin);
  zlo = 1.0 - near / wl;
  zhi = std::isinf(wh) ? 1.0 : 1.0 - near / wh;
}

}  // namespace rast5d::iv
