// Depth intervals ẑ ([Nilsson 2012] Appendix A): a conservative interval of the depth a
// (triangle, tile) pair can produce, for HiZ culling and occlusion queries (backend/zcull.h).
//
// Contract (tested in tests/test_intervals.py against the brute-force sample test): the depth
// z = 1 - near / W_hit of every sample of the tile that the exact sample test hits, at a time in
// [ta, tb] and a lens point in the given box, is inside ẑ (up to the double rounding of ẑ itself),
// and the depth the float sample test computes for it is inside ẑ widened by the pair's own
// rounding bound (zhat_margin, zhat_widen).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/arith.h"
#include "core/costs.h"
#include "intervals/clip.h"
#include "core/triangle.h"

namespace rast5d::iv {

// The former fixed relative margin on W (pipeline.zhat_margin: fixed, kept for comparison).
inline constexpr double kFixedDepthMargin = 0.125;

struct ZHat {
  double zlo = 0, zhi = 1;      // depth z = 1 - near / W
  double wlo = 0, whi = kInfD;  // view depth W
  double vwlo = 0, vwhi = kInfD;  // vertex min/max only (for the tightness report)
  double margin = kInfD;        // relative rounding bound rho of the float hit depth W (zhat_margin)
};

// Bound rho on the relative error of the view depth W_hit = det / sum(e) that the float32 sample
// kernels compute (sampletest/kernels.h: vertex placement, edge_functions, hit_depth) for any sample of
// the (x, y, u, v, t) box whose exact hit lies at W_hit <= whi: |W_float - W_hit| <= rho W_hit.
// First-order forward error analysis with unit roundoff u = 2^-24 over interval bounds of every
// intermediate on the box (each operation adds at most u times its result's magnitude):
//   placed vertices X', Y', W (lerp, shear: one rounding per MADD, bounded by |value| u each),
//   relative coordinates r = X' - x W, edge functions e_i = r_j r'_k - r'_j r_k (2 MUL + SUB),
//   sum = sum e_i, det = sum W_j e_j, then sum / det (RCP, MUL).
// A covered sample has all e_i of det's sign, so |sum| = sum |e_i| = |det| / W_hit >= D / whi
// with D a lower bound of |det| over the box (the determinant of the placed vertices: bilinear in
// (u, v), so the lens-box corners bound it, and a cubic in t, bounded at its critical points).
// rho = inf when D = 0 (the triangle is seen edge-on from part of the box): no depth culling.
// Robustness of the float simulator, not hardware work: not charged (a fixed-point datapath
// computes exact depths). Plain double; its own rounding is covered by the slack.
inline double zhat_margin(const TriSetup& tri, const FrameConst& fc, bool lens, double x0, double x1, double y0,
                          double y1, double u0, double u1, double v0, double v1, double ta, double tb, double whi) {
  constexpr double u = 0x1p-24;
  if (!(whi < kInfD)) return kInfD;
  if (!lens) u0 = u1 = v0 = v1 = 0.0;
  const bool moving = tri.moving;
  if (!moving) ta = tb = 0.0;
  struct Iv {
    double lo, hi;
    double mag() const { return std::max(std::fabs(lo), std::fabs(hi)); }
  };
  auto add = [](Iv a, Iv b) { return Iv{a.lo + b.lo, a.hi + b.hi}; };
  auto mul = [](Iv a, Iv b) {
    const double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
    return Iv{std::min({p[0], p[1], p[2], p[3]}), std::max({p[0], p[1], p[2], p[3]})};
  };
  auto neg = [](Iv a) { return Iv{-a.hi, -a.lo}; };
  const Iv T{ta, tb}, U{u0, u1}, V{v0, v1}, SX{x0, x1}, SY{y0, y1};
  Iv Xp[3], Yp[3], Wp[3];
  double ex[3], ey[3], ew[3];  // absolute error bounds of the placed vertices
  for (int j = 0; j < 3; ++j) {
    const Iv X0{tri.X[j], tri.X[j]}, Y0{tri.Y[j], tri.Y[j]}, W0{tri.W[j], tri.W[j]};
    Iv Xt = X0, Yt = Y0, Wt = W0;
    ex[j] = ey[j] = ew[j] = 0.0;
    if (moving) {
      Xt = add(X0, mul(T, Iv{tri.dX[j], tri.dX[j]}));
      Yt = add(Y0, mul(T, Iv{tri.dY[j], tri.dY[j]}));
      Wt = add(W0, mul(T, Iv{tri.dW[j], tri.dW[j]}));
      ex[j] = u * Xt.mag(), ey[j] = u * Yt.mag(), ew[j] = u * Wt.mag();
    }
    Xp[j] = Xt, Yp[j] = Yt, Wp[j] = Wt;
    if (lens) {
      Iv cx{tri.cx[j], tri.cx[j]}, cy{tri.cy[j], tri.cy[j]};
      double ecx = 0.0, ecy = 0.0;
      if (moving) {  // cx = Wt kx + (-kx F) in float
        cx = add(mul(Wt, Iv{fc.kx, fc.kx}), Iv{fc.neg_kx_f, fc.neg_kx_f});
        cy = add(mul(Wt, Iv{fc.ky, fc.ky}), Iv{fc.neg_ky_f, fc.neg_ky_f});
        ecx = u * cx.mag() + std::fabs(fc.kx) * ew[j];
        ecy = u * cy.mag() + std::fabs(fc.ky) * ew[j];
      }
      Xp[j] = add(Xt, mul(U, cx));
      Yp[j] = add(Yt, mul(V, cy));
      ex[j] += u * Xp[j].mag() + U.mag() * ecx;
      ey[j] += u * Yp[j].mag() + V.mag() * ecy;
    }
  }
  Iv rx[3], ry[3];
  double erx[3], ery[3];
  for (int j = 0; j < 3; ++j) {
    rx[j] = add(Xp[j], neg(mul(SX, Wp[j])));
    ry[j] = add(Yp[j], neg(mul(SY, Wp[j])));
    erx[j] = u * rx[j].mag() + ex[j] + SX.mag() * ew[j];
    ery[j] = u * ry[j].mag() + ey[j] + SY.mag() * ew[j];
  }
  double P[3], E[3];  // |e_i| bound and its error bound
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const double a = rx[j].mag() * ry[k].mag(), b = ry[j].mag() * rx[k].mag();
    P[i] = a + b;
    E[i] = erx[j] * ry[k].mag() + rx[j].mag() * ery[k] + ery[j] * rx[k].mag() + ry[j].mag() * erx[k] + 2 * u * P[i];
  }
  const double e_sum = E[0] + E[1] + E[2] + 2 * u * (P[0] + P[1] + P[2]);
  double e_det = 0.0;
  for (int j = 0; j < 3; ++j) e_det += Wp[j].mag() * E[j] + ew[j] * P[j] + 3 * u * Wp[j].mag() * P[j];
  // Lower bound of |det| over the box.
  double dmin;
  auto det3 = [](const double (&m)[3][3]) {
    return m[0][0] * (m[1][1] * m[2][2] - m[2][1] * m[1][2]) - m[1][0] * (m[0][1] * m[2][2] - m[2][1] * m[0][2]) +
           m[2][0] * (m[0][1] * m[1][2] - m[1][1] * m[0][2]);
  };
  if (!moving) {
    double lo = kInfD, hi = -kInfD;
    for (int c = 0; c < 4; ++c) {
      const double uu = (c & 1) ? u1 : u0, vv = (c & 2) ? v1 : v0;
      double m[3][3];
      for (int j = 0; j < 3; ++j) {
        m[j][0] = double(tri.X[j]) + uu * double(tri.cx[j]);
        m[j][1] = double(tri.Y[j]) + vv * double(tri.cy[j]);
        m[j][2] = tri.W[j];
      }
      const double d = det3(m);
      lo = std::min(lo, d), hi = std::max(hi, d);
    }
    double mag = 0.0;
    for (int j = 0; j < 3; ++j) mag = std::max(mag, Xp[j].mag() + Yp[j].mag() + Wp[j].mag());
    const double slack = 1e-9 * mag * mag * mag;  // the double rounding of the evaluations
    dmin = lo > slack ? lo - slack : (hi < -slack ? -hi - slack : 0.0);
  } else {
    // det of the placed vertices at lens corner (uu, vv) and time t; the multiple of the W column in
    // the shear X' = Xt + u (kx Wt + c), c = -kx F, cancels, so det(X', Y', W) = det(Xt + u c, Yt +
    // v c', Wt): bilinear in (u, v) (its extremes over the lens box are at corners) and a cubic in t,
    // whose extremes over [ta, tb] are at the ends or at the roots of its derivative.
    auto det_at = [&](double t, double uu, double vv) {
      double m[3][3];
      for (int j = 0; j < 3; ++j) {
        m[j][0] = double(tri.X[j]) + t * double(tri.dX[j]) + uu * double(fc.neg_kx_f);
        m[j][1] = double(tri.Y[j]) + t * double(tri.dY[j]) + vv * double(fc.neg_ky_f);
        m[j][2] = double(tri.W[j]) + t * double(tri.dW[j]);
      }
      return det3(m);
    };
    double lo = kInfD, hi = -kInfD;
    const int nl = lens ? 2 : 1;
    for (int c = 0; c < nl * nl; ++c) {
      const double uu = lens ? ((c & 1) ? u1 : u0) : 0.0, vv = lens ? ((c & 2) ? v1 : v0) : 0.0;
      const double f0 = det_at(0, uu, vv), f1 = det_at(1, uu, vv), f2 = det_at(2, uu, vv), f3 = det_at(3, uu, vv);
      const double d1 = f1 - f0, d2 = f2 - 2 * f1 + f0, d3 = f3 - 3 * f2 + 3 * f1 - f0;
      const double a3 = d3 / 6, a2 = d2 / 2 - d3 / 2, a1 = d1 - d2 / 2 + d3 / 3;
      double ts[4] = {ta, tb, ta, ta};
      int nt = 2;
      const double qa = 3 * a3, qb = 2 * a2, qc = a1;  // p'(t) = qa t^2 + qb t + qc
      if (qa != 0.0) {
        const double disc = qb * qb - 4 * qa * qc;
        if (disc >= 0) {
          const double r = std::sqrt(disc);
          ts[nt++] = (-qb - r) / (2 * qa), ts[nt++] = (-qb + r) / (2 * qa);
        }
      } else if (qb != 0.0) {
        ts[nt++] = -qc / qb;
      }
      for (int k = 0; k < nt; ++k) {
        const double t = std::min(tb, std::max(ta, ts[k]));
        const double d = det_at(t, uu, vv);
        lo = std::min(lo, d), hi = std::max(hi, d);
      }
    }
    double mag = 0.0;
    for (int j = 0; j < 3; ++j) mag = std::max(mag, Xp[j].mag() + Yp[j].mag() + Wp[j].mag());
    const double slack = 1e-9 * mag * mag * mag;  // the double rounding of the evaluations
    dmin = lo > slack ? lo - slack : (hi < -slack ? -hi - slack : 0.0);
  }
  dmin *= 1.0 - 0x1p-40;
  if (!(dmin > 0.0)) return kInfD;
  // x2: the second-order terms, and samples the float test covers within rounding of an edge
  // (their exact hit is on the plane just outside the triangle).
  const double rho = 2.0 * (e_det / dmin + e_sum * whi / dmin + 2 * u) + 0x1p-40;
  return std::isfinite(rho) ? rho : kInfD;
}

// Per-triangle moving planes ([Nilsson 2012] App. A Eq. 1): for base time tau in {0, 1} the triangle's plane
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
  z.margin = zhat_margin(tri, fc, lens, x0, x1, y0, y1, u0, u1, v0, v1, ta, tb, z.vwhi);
  charge<A>(ops, cost::kZhatVertex + (planes ? cost::zhat_plane_cost(lens) : 0));
  return z;
}

// The W interval actually compared: ẑ widened by the pair's rounding bound (margin on W).
inline void zhat_widen_w(const ZHat& z, double near, double lo, double hi, double& wl, double& wh) {
  const double rho = z.margin;
  wl = rho < 1.0 ? std::max(near, lo) * (1.0 - rho) : 0.0;
  wh = rho < kInfD ? hi * (1.0 + rho) : kInfD;
}
// ẑ widened for comparisons with float sample depths: W widened by the pair's margin, then the
// float rounding of z = 1 - near / W itself (MADD: at most 2 u absolute for W >= near).
inline void zhat_widen(const ZHat& z, double near, double& zlo, double& zhi) {
  constexpr double kZUlp = 2 * 0x1p-24;
  double wl, wh;
  zhat_widen_w(z, near, z.wlo, z.whi, wl, wh);
  zlo = wl > 0.0 ? 1.0 - near / wl - kZUlp : -kInfD;
  zhi = std::isinf(wh) ? kInfD : 1.0 - near / wh + kZUlp;
}

}  // namespace rast5d::iv
