// The sample test in the form a fixed-point hardware datapath evaluates it (pipeline.cost_model:
// hardware; costs in core/costs.h, "sample test, hardware cost model").
//
// Contract: these kernels count the hardware model's operations on the counting path; the
// render's decisions stay those of the robust kernels (sampletest/kernels.h). In a fixed-point datapath
// with vertices snapped to the sub-pixel grid every edge function is an exact integer, so its
// decisions are the exact ones, which the robust float kernels reproduce (watertight, top-left
// rule); the two forms differ in what they cost, not in which samples they cover, and the image
// is the same under both cost models.
//  * 2D (static in focus, or a static triangle pre-sheared to one discrete lens position):
//    affine edge functions e_i = A_i x + B_i y + C_i from tiletest::edges_2d (set up per triangle
//    or lens position, charged to ops.setup), oriented by det's sign and biased for the top-left
//    rule at setup: 3 x 2 MADD + 3 CMP per sample, ties free.
//  * 3D/4D/5D: the vertices move with the sample; they are placed as in the robust kernels, then
//    relative coordinates, fused multiply-add edge functions and det, 4 sign tests.
#pragma once

#include <cstdint>

#include "core/costs.h"
#include "core/params.h"
#include "sampletest/kernels.h"
#include "core/triangle.h"
#include "tiletest/edges_2d.h"

namespace rast5d {

// Documented cost of one sample test (without ties) under a cost model. affine: the 2D kernel
// (class 2D, or a pre-sheared static triangle).
inline std::uint64_t sample_test_cost(CostModel m, DimClass cls) {
  static constexpr std::uint64_t robust[4] = {cost::kInside2D, cost::kInside3D, cost::kInside4D, cost::kInside5D};
  static constexpr std::uint64_t hw[4] = {cost::kHwInside2D, cost::kHwInside3D, cost::kHwInside4D,
                                          cost::kHwInside5D};
  return (m == CostModel::kHardware ? hw : robust)[static_cast<int>(cls)];
}
// Documented cost of one edge settled by the top-left rule.
inline std::uint64_t tie_break_cost(CostModel m, DimClass cls) {
  if (m != CostModel::kHardware) return cost::kTieBreak;
  return cls == DimClass::k2D ? cost::kHwTieBreak2D : cost::kHwTieBreak;
}

// Affine 2D test against set-up edges (oriented: inside is e_i >= 0 after the top-left bias).
// Cost: cost::kHwInside2D.
template <class F>
inline bool hw_inside_affine(const tiletest::Edges2D& e, F sx, F sy) {
  bool in = e.valid;
  for (int i = 0; i < 3; ++i) {
    const F v = madd(F(e.A[i]), sx, madd(F(e.B[i]), sy, F(e.C[i])));
    if (v < F(0.0f)) in = false;
  }
  return in;
}

// Relative coordinates, fused multiply-add edge functions and det of placed vertices.
// Cost: cost::kHwEdges. rx, ry are kept for the tie rule.
template <class F>
inline void hw_edges(const F X[3], const F Y[3], const F W[3], F sx, F sy, F rx[3], F ry[3], F e[3], F& det) {
  for (int j = 0; j < 3; ++j) {
    rx[j] = madd(W[j], -sx, X[j]);
    ry[j] = madd(W[j], -sy, Y[j]);
  }
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    e[i] = madd(rx[j], ry[k], -(ry[j] * rx[k]));
  }
  det = madd(W[2], e[2], madd(W[1], e[1], W[0] * e[0]));
}

// Top-left rule for edge i from the held relative coordinates: the gradient's signs.
// Cost: cost::kHwTieBreak.
template <class F>
inline bool hw_tie_break(const F W[3], const F rx[3], const F ry[3], int i, int det_sign) {
  const int j = (i + 1) % 3, k = (i + 2) % 3;
  const F a = madd(W[k], ry[j], -(W[j] * ry[k]));
  const F b = madd(W[j], rx[k], -(W[k] * rx[j]));
  const int sa = sign_of(a) * (det_sign < 0 ? -1 : 1), sb = sign_of(b) * (det_sign < 0 ? -1 : 1);
  return sa != 0 ? sa > 0 : sb > 0;
}

// The hardware-form test of one sample against a set-up triangle, for counting: runs the kernel
// of the triangle's class and, for each edge in tie_mask (the edges the robust test settled by
// the top-left rule), the tie kernel. Returns the hardware form's own decision (instrumentation).
template <class F>
inline bool hw_inside_test(const TriSetup& tri, DimClass cls, const FrameConst& fc, F sx, F sy, F u, F v, F t,
                           int tie_mask) {
  if (cls == DimClass::k2D) {
    const tiletest::Edges2D e = tiletest::edges_2d<double>(tri.X, tri.Y, tri.W);  // set-up (ops.setup)
    return hw_inside_affine(e, sx, sy);
  }
  F X[3], Y[3], W[3];
  if (cls == DimClass::k4D) {
    F X0[3], Y0[3], cx[3], cy[3];
    for (int j = 0; j < 3; ++j) {
      X0[j] = F(tri.X[j]), Y0[j] = F(tri.Y[j]), W[j] = F(tri.W[j]);
      cx[j] = F(tri.cx[j]), cy[j] = F(tri.cy[j]);
    }
    shear_static(X0, Y0, cx, cy, u, v, X, Y);
  } else {
    F X0[3], Y0[3], W0[3], dX[3], dY[3], dW[3];
    for (int j = 0; j < 3; ++j) {
      X0[j] = F(tri.X[j]), Y0[j] = F(tri.Y[j]), W0[j] = F(tri.W[j]);
      dX[j] = F(tri.dX[j]), dY[j] = F(tri.dY[j]), dW[j] = F(tri.dW[j]);
    }
    if (cls == DimClass::k3D) {
      lerp_vertices(X0, Y0, W0, dX, dY, dW, t, X, Y, W);
    } else {
      F Xt[3], Yt[3];
      lerp_vertices(X0, Y0, W0, dX, dY, dW, t, Xt, Yt, W);
      shear_moving(Xt, Yt, W, F(fc.kx), F(fc.neg_kx_f), F(fc.ky), F(fc.neg_ky_f), u, v, X, Y);
    }
  }
  F rx[3], ry[3], e[3], det;
  hw_edges(X, Y, W, sx, sy, rx, ry, e, det);
  int det_sign, zero_mask;
  int in = edge_signs(e, det, false, det_sign, zero_mask);
  for (int i = 0; i < 3; ++i)
    if (tie_mask & (1 << i))
      if (!hw_tie_break(W, rx, ry, i, det_sign)) in = 0;
  return in != 0;
}

// Pre-sheared static triangle at one lens position (INTERLEAVE, HINTERLEAVE, OUR (i)): the affine
// 2D kernel on the lens position's edges (set up per pass, charged to ops.setup by the caller).
template <class F>
inline bool hw_inside_sheared(const float Xs[3], const float Ys[3], const float W[3], F sx, F sy) {
  const tiletest::Edges2D e = tiletest::edges_2d<double>(Xs, Ys, W);
  return hw_inside_affine(e, sx, sy);
}

}  // namespace rast5d
