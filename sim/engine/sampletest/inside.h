// The complete exact inside test of one sample against a set-up triangle: place the vertices at
// the sample's (u, v, t) with the kernel of the triangle's class, evaluate the edge functions,
// apply the sign tests and the top-left rule. Shared by the render pipeline and sim._core.probe.
#pragma once

#include "core/costs.h"
#include "sampletest/kernels.h"
#include "core/triangle.h"

namespace rast5d {

inline constexpr std::uint64_t kInsideCost[4] = {cost::kInside2D, cost::kInside3D, cost::kInside4D,
                                                 cost::kInside5D};

// The class-independent part: edge functions, signs, top-left rule.
template <class F>
inline bool inside_from_vertices(const F X[3], const F Y[3], const F W[3], F sx, F sy,
                                 bool back_face_cull, F e[3], F& det, int& n_ties) {
  edge_functions(X, Y, W, sx, sy, e, det);
  int det_sign, zero_mask;
  const int in = edge_signs(e, det, back_face_cull, det_sign, zero_mask);
  n_ties = 0;
  if (in >= 0) return in == 1;
  bool covered = true;
  for (int i = 0; i < 3; ++i)
    if (zero_mask & (1 << i)) {
      ++n_ties;
      if (!tie_break_edge(X, Y, W, sx, sy, i, det_sign)) covered = false;
    }
  return covered;
}

// Returns whether the sample is covered; e and det are set for interpolation. n_ties counts the
// edges settled by the top-left rule (each costs cost::kTieBreak more).
template <class F>
inline bool inside_test(const TriSetup& tri, DimClass cls, const FrameConst& fc, F sx, F sy, F u, F v,
                        F t, bool back_face_cull, F X[3], F Y[3], F W[3], F e[3], F& det,
                        int& n_ties) {
  switch (cls) {
    case DimClass::k2D:
      for (int j = 0; j < 3; ++j) X[j] = F(tri.X[j]), Y[j] = F(tri.Y[j]), W[j] = F(tri.W[j]);
      break;
    case DimClass::k4D: {
      F X0[3], Y0[3], cx[3], cy[3];
      for (int j = 0; j < 3; ++j) {
        X0[j] = F(tri.X[j]), Y0[j] = F(tri.Y[j]), W[j] = F(tri.W[j]);
        cx[j] = F(tri.cx[j]), cy[j] = F(tri.cy[j]);
      }
      shear_static(X0, Y0, cx, cy, u, v, X, Y);
      break;
    }
    case DimClass::k3D:
    case DimClass::k5D: {
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
      break;
    }
  }
  return inside_from_vertices(X, Y, W, sx, sy, back_face_cull, e, det, n_ties);
}

}  // namespace rast5d
