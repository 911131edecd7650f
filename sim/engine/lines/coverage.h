// Line samples in the lens ([Tzeng 2012] §3.1): analytic coverage of a lens-space line
// by a static (possibly defocused) triangle.
//
// Contract:
//  * A line sample is a screen point (sx, sy) and a direction (c, s) = (cos θ, sin θ) through the
//    lens centre; it covers the lens points p (c, s), p in [-1, 1] (the unit disk lens).
//  * At a fixed screen point the homogeneous edge functions of the sheared triangle
//    (sampletest/kernels.h) are linear in (u, v): the u·v terms cancel because every vertex is
//    sheared by the same K (W_j - F) ([Tzeng 2012] Eq. 2 in homogeneous form). So are det = Σ W_j e_j and
//    sum = Σ e_j. line_point_setup() computes, once per (screen point, triangle), each function's
//    value at the lens centre and its u and v gradients ([Tzeng 2012]'s C_i, A_i, B_i); line_interval()
//    restricts them to one direction and intersects the half-lines where every e_i has det's sign
//    (and, for triangles crossing the near plane, where the hit point has W >= near: det - near·sum
//    has det's sign). The result is at most two intervals (one per sign of det) of p in [-1, 1]:
//    the triangle's coverage of the line, exact up to float rounding of the interval ends.
//  * Ties (an e_i exactly zero) have measure zero on a line and are not settled by a top-left rule.
//  * The costs are counted through the scalar type (core/arith.h); the fast path charges the
//    documented figures of core/costs.h (cost::kLinePointSetup, line_interval_cost()).
#pragma once

#include "core/arith.h"
#include "core/costs.h"

namespace rast5d {

// The lens-space functions of one triangle at one screen point: f(u, v) = f0 + u fu + v fv for
// f in e_0, e_1, e_2, det, h = det - near·sum, sum.
template <class F>
struct LinePoint {
  F e0[3], eu[3], ev[3];
  F d0, du, dv;
  F s0, su, sv;
  F h0, hu, hv;
};

// Cost: cost::kLinePointSetup.
template <class F>
inline void line_point_setup(const float X[3], const float Y[3], const float W[3], const float cx[3],
                             const float cy[3], F sx, F sy, F neg_near, LinePoint<F>& o) {
  F rx[3], ry[3];
  for (int j = 0; j < 3; ++j) {
    rx[j] = madd(F(W[j]), -sx, F(X[j]));
    ry[j] = madd(F(W[j]), -sy, F(Y[j]));
  }
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    o.e0[i] = rx[j] * ry[k] - ry[j] * rx[k];
    o.eu[i] = madd(-F(cx[k]), ry[j], F(cx[j]) * ry[k]);  // d/du: cx_j ry_k - ry_j cx_k
    o.ev[i] = madd(-F(cy[j]), rx[k], rx[j] * F(cy[k]));  // d/dv: rx_j cy_k - cy_j rx_k
  }
  o.d0 = madd(F(W[2]), o.e0[2], madd(F(W[1]), o.e0[1], F(W[0]) * o.e0[0]));
  o.du = madd(F(W[2]), o.eu[2], madd(F(W[1]), o.eu[1], F(W[0]) * o.eu[0]));
  o.dv = madd(F(W[2]), o.ev[2], madd(F(W[1]), o.ev[1], F(W[0]) * o.ev[0]));
  o.s0 = o.e0[0] + o.e0[1] + o.e0[2];
  o.su = o.eu[0] + o.eu[1] + o.eu[2];
  o.sv = o.ev[0] + o.ev[1] + o.ev[2];
  o.h0 = madd(neg_near, o.s0, o.d0);
  o.hu = madd(neg_near, o.su, o.du);
  o.hv = madd(neg_near, o.sv, o.dv);
}

// One line's functions of p: f(p) = f0 + p g.
template <class F>
struct LineFns {
  F e0[3], eg[3];
  F d0, dg, s0, sg;
};

// The coverage of one line: up to two intervals [lo, hi] of p (n of them), and the functions for
// shading and depth. ops: the documented operation count of this call (data dependent: a function
// whose slope is zero costs a sign test of its constant instead of a root).
template <class F>
struct LineCoverage {
  int n = 0;
  float lo[2], hi[2];
  LineFns<F> fn;
};

// Cost: line_interval_cost(n_fns, n_flat), n_fns = 4 (+1 with the near function), n_flat the
// functions with a zero slope; returns that figure.
template <class F>
inline std::uint64_t line_interval(const LinePoint<F>& q, F c, F s, bool near_fn, bool back_face_cull,
                                   LineCoverage<F>& out) {
  LineFns<F>& fn = out.fn;
  F g[5], f0[5];
  for (int i = 0; i < 3; ++i) {
    fn.e0[i] = q.e0[i];
    fn.eg[i] = madd(s, q.ev[i], c * q.eu[i]);
    f0[i] = q.e0[i], g[i] = fn.eg[i];
  }
  fn.d0 = q.d0, fn.dg = madd(s, q.dv, c * q.du);
  fn.s0 = q.s0, fn.sg = madd(s, q.sv, c * q.su);
  f0[3] = q.d0, g[3] = fn.dg;
  const int n_fns = near_fn ? 5 : 4;
  if (near_fn) f0[4] = q.h0, g[4] = madd(s, q.hv, c * q.hu);
  // Case +1: every function > 0 (det > 0); case -1: every function < 0.
  F lo_p = F(-1.0f), hi_p = F(1.0f), lo_n = F(-1.0f), hi_n = F(1.0f);
  bool empty_p = back_face_cull, empty_n = false;
  int n_flat = 0;
  for (int k = 0; k < n_fns; ++k) {
    const int sg = sign_of(g[k]);
    if (sg == 0) {
      ++n_flat;
      const int s0 = sign_of(f0[k]);
      if (s0 <= 0) empty_p = true;
      if (s0 >= 0) empty_n = true;
      continue;
    }
    const F r = -f0[k] * rcp(g[k]);  // f(r) = 0
    if (sg > 0) {  // f > 0 for p > r
      lo_p = vmax(lo_p, r);
      hi_n = vmin(hi_n, r);
    } else {
      hi_p = vmin(hi_p, r);
      lo_n = vmax(lo_n, r);
    }
  }
  out.n = 0;
  const bool cov_p = lo_p < hi_p;
  const bool cov_n = lo_n < hi_n;
  if (cov_p && !empty_p) out.lo[out.n] = raw(lo_p), out.hi[out.n] = raw(hi_p), ++out.n;
  if (cov_n && !empty_n) out.lo[out.n] = raw(lo_n), out.hi[out.n] = raw(hi_n), ++out.n;
  return cost::line_interval_cost(n_fns, n_flat);
}

// line_point_setup() and line_interval() for a batch of lines on the fast path (float, no counting):
// the same IEEE operations in the same order, without branches, so that the compiler vectorises the
// loop over lines and every figure keeps its bits (tests/test_lines.py compares the counting path,
// which runs the functions above, on every counter and the image). Lines sharing a screen point
// each repeat its setup (the same arithmetic; cost::kLinePointSetup is charged once per wheel
// by the caller). Per line i: nseg[i] intervals [lo[k][i], hi[k][i]] (the first holds the
// det > 0 interval when both exist, as line_interval's order), nflat[i] for line_interval_cost(),
// and the functions of p in fn[...][i] (LineFns: e0[3], eg[3], d0, dg, s0, sg).
struct LineBatch {
  static constexpr int kLanes = 64;
  float sx[kLanes], sy[kLanes], c[kLanes], s[kLanes];
  float lo[2][kLanes], hi[2][kLanes];
  float fn[10][kLanes];
  int nseg[kLanes], nflat[kLanes];
};

template <bool kNear>
inline void line_intervals_batch(const float X[3], const float Y[3], const float W[3], const float cx[3],
                                 const float cy[3], float neg_near, bool back_face_cull, int n, LineBatch& b) {
#pragma GCC ivdep
  for (int i = 0; i < n; ++i) {
    LinePoint<float> q;
    line_point_setup(X, Y, W, cx, cy, b.sx[i], b.sy[i], neg_near, q);
    const float c = b.c[i], s = b.s[i];
    float g[5], f0[5];
    for (int k = 0; k < 3; ++k) {
      f0[k] = q.e0[k], g[k] = madd(s, q.ev[k], c * q.eu[k]);
      b.fn[k][i] = q.e0[k], b.fn[3 + k][i] = g[k];
    }
    const float dg = madd(s, q.dv, c * q.du), sg = madd(s, q.sv, c * q.su);
    b.fn[6][i] = q.d0, b.fn[7][i] = dg, b.fn[8][i] = q.s0, b.fn[9][i] = sg;
    f0[3] = q.d0, g[3] = dg;
    if constexpr (kNear) f0[4] = q.h0, g[4] = madd(s, q.hv, c * q.hu);
    constexpr int n_fns = kNear ? 5 : 4;
    float lo_p = -1.0f, hi_p = 1.0f, lo_n = -1.0f, hi_n = 1.0f;
    // Bitwise logic and selects only (no && or ||): a loop without branches.
    int empty_p = back_face_cull, empty_n = 0, n_flat = 0;
    for (int k = 0; k < n_fns; ++k) {
      const int up = g[k] > 0.0f, down = g[k] < 0.0f, flat = 1 ^ (up | down);  // sign_of(g) == 0: NaN too
      n_flat += flat;
      empty_p |= flat & (1 ^ int(f0[k] > 0.0f));  // sign_of(f0) <= 0
      empty_n |= flat & (1 ^ int(f0[k] < 0.0f));  // sign_of(f0) >= 0
      const float r = -f0[k] * rcp(g[k]);  // only used where g has a sign
      lo_p = up ? vmax(lo_p, r) : lo_p;
      hi_n = up ? vmin(hi_n, r) : hi_n;
      hi_p = down ? vmin(hi_p, r) : hi_p;
      lo_n = down ? vmax(lo_n, r) : lo_n;
    }
    const int seg_p = int(lo_p < hi_p) & (1 ^ empty_p), seg_n = int(lo_n < hi_n) & (1 ^ empty_n);
    b.lo[0][i] = seg_p ? lo_p : lo_n, b.hi[0][i] = seg_p ? hi_p : hi_n;
    b.lo[1][i] = lo_n, b.hi[1][i] = hi_n;
    b.nseg[i] = seg_p + seg_n;
    b.nflat[i] = n_flat;
  }
}

// The tile clip's test of lines against the pseudo-angle intervals of up to four uv-boxes, for a batch
// of lines on the fast path: pseudo_angle() of each direction and the box tests, both sides of every
// choice computed and one selected (the same figures as pseudo_angle() and the caller's scalar loop,
// without branches, so that the loop vectorises). meets[i]: a box's interval holds line i's angle;
// tested[i]: the boxes tested until the first that holds it (all of them when none does), as the
// scalar loop stops there (cost::kLineAngleTest each).
inline void lines_meet_boxes(const float* c, const float* s, int n, int n_boxes, const float lo[4], const float hi[4],
                             const bool shifted[4], int* meets, int* tested) {
#pragma GCC ivdep
  for (int i = 0; i < n; ++i) {
    const int fold = s[i] < 0.0f;
    const float x = fold ? -c[i] : c[i], y = fold ? -s[i] : s[i];
    const float a_right = y * rcp(x + y), a_left = 1.0f - x * rcp(y - x);
    float a = x >= 0.0f ? a_right : a_left;
    a = a >= 2.0f ? a - 2.0f : a;
    int met = 0, count = 0;
    for (int k = 0; k < 4; ++k) {
      const int live = int(k < n_boxes) & (1 ^ met);  // the scalar loop tests box k
      const float la = (int(shifted[k]) & int(a < 1.0f)) ? a + 2.0f : a;
      count += live;
      met |= live & int(lo[k] <= la) & int(la <= hi[k]);
    }
    meets[i] = met, tested[i] = count;
  }
}

// Evaluate the segment's shading point p: the hit depth z = 1 - near·sum/det and the perspective
// barycentrics' colour (as backend/sample_backend.h does for a point sample); with `bary`, the
// barycentrics themselves (texture coordinates, the shading cache's grid point).
// Cost: cost::kLineShade.
template <class F>
inline void line_shade(const LineFns<F>& fn, F p, F neg_near, const float col[3][3], F& z, F out[3],
                       float* bary = nullptr) {
  F e[3];
  for (int i = 0; i < 3; ++i) e[i] = madd(p, fn.eg[i], fn.e0[i]);
  const F sum = e[0] + e[1] + e[2];
  const F det = madd(p, fn.dg, fn.d0);
  z = madd(neg_near, sum * rcp(det), F(1.0f));
  const F inv = rcp(sum);
  const F b0 = e[0] * inv, b1 = e[1] * inv, b2 = e[2] * inv;
  for (int ch = 0; ch < 3; ++ch)
    out[ch] = madd(b2, F(col[2][ch]), madd(b1, F(col[1][ch]), b0 * F(col[0][ch])));
  if (bary) bary[0] = raw(b0), bary[1] = raw(b1), bary[2] = raw(b2);
}

// Hit depth at p only. Cost: cost::kLineDepth.
template <class F>
inline F line_depth(F s0, F sg, F d0, F dg, F p, F neg_near) {
  const F sum = madd(p, sg, s0);
  const F det = madd(p, dg, d0);
  return madd(neg_near, sum * rcp(det), F(1.0f));
}

// κ weight of an interval of a wagon-wheel line ([Tzeng 2012] §3.1.2) on the unit disk. Lines through the
// centre at uniform angles sample the disk with density ∝ 1/|p|; weighting dp by |p| undoes it, and
// the normalisation makes the whole line [-1, 1] weigh 1: κ(p1, p2) = (p2|p2| - p1|p1|) / 2
// ([Tzeng 2012] writes 2(p2|p2| - p1|p1|) for its lens p in [-1/2, 1/2]). Cost: cost::kKappa.
template <class F>
inline F kappa(F p1, F p2) {
  return (p2 * vabs(p2) - p1 * vabs(p1)) * F(0.5f);
}

// The undirected direction of (x, y) as a pseudo-angle in [0, 2) ("diamond angle": monotone in
// the angle θ mod π, 0 along +u, 1 along +v), and its shifted form in [1, 3) (values below 1 + 2),
// which is contiguous across θ = 0 instead of θ = π/2. Line directions are table constants
// (computed free, like 1/c); for box corners the cost is counted: pseudo_angle() returns its ops.
template <class F>
inline std::uint64_t pseudo_angle(F x, F y, F& a) {
  std::uint64_t ops = 1;
  if (y < F(0.0f)) x = -x, y = -y;  // fold: (x, y) and (-x, -y) are one line direction
  const bool right = x >= F(0.0f);
  ++ops;
  if (right) {
    a = y * rcp(x + y);  // [0, 1]: ADD, RCP, MUL
    ops += 3;
  } else {
    a = F(1.0f) - x * rcp(y - x);  // (1, 2]: SUB, RCP, MUL, SUB
    ops += 4;
  }
  const bool wrap = a >= F(2.0f);  // (-1, 0) folds to direction 0
  ++ops;
  if (wrap) a = a - F(2.0f), ++ops;
  return ops;
}

inline constexpr float kAngleMargin = 1e-5f;

// The pseudo-angle interval of the lines through the lens centre that meet the (widened) uv-box
// [u0, u1] x [v0, v1], which must not hold the centre: the span of its corners' directions, in the
// shifted form when the box touches the u axis. Cost: returned.
template <class F>
inline std::uint64_t box_angles(F u0, F u1, F v0, F v1, F& lo, F& hi, bool& shifted) {
  std::uint64_t ops = 2;
  const bool below = v0 <= F(0.0f), above = v1 >= F(0.0f);
  shifted = below && above;
  const F us[2] = {u0, u1}, vs[2] = {v0, v1};
  lo = F(4.0f), hi = F(-1.0f);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      F a;
      ops += pseudo_angle(us[i], vs[j], a);
      if (shifted) {
        ++ops;
        if (a < F(1.0f)) a = a + F(2.0f), ++ops;
      }
      lo = vmin(lo, a), hi = vmax(hi, a);
      ops += 2;
    }
  lo = lo - F(kAngleMargin), hi = hi + F(kAngleMargin);
  return ops + 2;
}
}  // namespace rast5d
