// The sample test: is one sample (x, y, u, v, t) inside the triangle placed at its (u, v, t)?
//
// Contract (ARCHITECTURE.md §Geometric conventions, docs/conventions.md):
//  * Vertices are pixel-homogeneous (X, Y, W); the sample is the pixel-space point (sx, sy).
//  * Depth of field shears X' = X + u * cx, cx = Kx * (W - F); time lerps p(t) = p0 + t * (p1 - p0).
//  * Edge functions are homogeneous 2D (Olano-Greer) evaluated *relative to the sample*:
//    r_j = (X_j - sx W_j, Y_j - sy W_j), e_i = r_j x r_k. Computing both products and then one
//    subtraction (no fused multiply-add) makes e antisymmetric bit for bit, so two triangles that
//    share an edge never both claim a sample on it (watertight), and the sample-relative form keeps
//    the error proportional to the local geometry, not to the screen position.
//  * det = sum_j W_j e_j is the determinant of the (sheared) vertex matrix: its sign is the
//    triangle's orientation seen from the lens point; a sample is inside when every e_i has the
//    sign of det (then the hit point has W > 0, so vertices behind the camera need no clipping).
//    e_i == 0 is settled by a top-left rule on the edge's gradient, oriented by det.
//  * The 2D, 3D, 4D and 5D kernels are the same formula with the shear and/or lerp skipped; with a
//    zero shear coefficient or a static vertex the skipped steps are exact identities in IEEE
//    arithmetic, so every specialised kernel hits exactly the samples the 5D kernel hits.
#pragma once

#include "rast5d/arith.h"

namespace rast5d {

enum class DimClass : int { k2D = 0, k3D = 1, k4D = 2, k5D = 3 };

// Homogeneous edge functions and determinant of a (sheared) triangle at the sample (sx, sy).
// Cost: kCostEdges (costs.h).
template <class F>
inline void edge_functions(const F X[3], const F Y[3], const F W[3], F sx, F sy, F e[3], F& det) {
  F rx[3], ry[3];
  for (int j = 0; j < 3; ++j) {
    rx[j] = madd(W[j], -sx, X[j]);
    ry[j] = madd(W[j], -sy, Y[j]);
  }
  e[0] = rx[1] * ry[2] - ry[1] * rx[2];
  e[1] = rx[2] * ry[0] - ry[2] * rx[0];
  e[2] = rx[0] * ry[1] - ry[0] * rx[1];
  det = madd(W[2], e[2], madd(W[1], e[1], W[0] * e[0]));
}

// Sign tests of the edge functions against det. Cost: kCostSigns (4 CMP).
// Returns +1 inside, 0 outside, -1 undecided (some e_i == 0 with the others agreeing: tie rule).
// back_face_cull: reject det > 0 (back-facing; front faces are counter-clockwise in view space,
// which is det < 0 in y-down pixel coordinates).
template <class F>
inline int edge_signs(const F e[3], F det, bool back_face_cull, int& det_sign, int& zero_mask) {
  det_sign = sign_of(det);
  const int s0 = sign_of(e[0]);
  const int s1 = sign_of(e[1]);
  const int s2 = sign_of(e[2]);
  zero_mask = (s0 == 0) | ((s1 == 0) << 1) | ((s2 == 0) << 2);
  if (det_sign == 0) return 0;
  if (back_face_cull && det_sign > 0) return 0;
  if (s0 == -det_sign || s1 == -det_sign || s2 == -det_sign) return 0;
  return zero_mask ? -1 : 1;
}

// Top-left rule for an edge whose function is exactly zero at the sample. Edge i runs from
// vertex j = i+1 to k = i+2. Its gradient (A, B) = (W_k ry_j - W_j ry_k, W_j rx_k - W_k rx_j),
// each computed as two products and one subtraction, is exactly negated for the neighbour that
// lists the edge the other way round, so exactly one of two triangles sharing it owns the sample.
// Cost per zero edge: kCostTieBreak.
template <class F>
inline bool tie_break_edge(const F X[3], const F Y[3], const F W[3], F sx, F sy, int i, int det_sign) {
  const int j = (i + 1) % 3, k = (i + 2) % 3;
  const F rxj = madd(W[j], -sx, X[j]), ryj = madd(W[j], -sy, Y[j]);
  const F rxk = madd(W[k], -sx, X[k]), ryk = madd(W[k], -sy, Y[k]);
  F a = W[k] * ryj - W[j] * ryk;
  F b = W[j] * rxk - W[k] * rxj;
  if (det_sign < 0) {
    a = -a;
    b = -b;
  }
  const int sa = sign_of(a);
  const int sb = sign_of(b);
  return sa != 0 ? sa > 0 : sb > 0;
}

// ---- per-class vertex placement --------------------------------------------------------------

// Shear static vertices to lens point (u, v). Cost: kCostShear (6 MADD).
template <class F>
inline void shear_static(const F X[3], const F Y[3], const F cx[3], const F cy[3], F u, F v, F Xs[3],
                         F Ys[3]) {
  for (int j = 0; j < 3; ++j) {
    Xs[j] = madd(u, cx[j], X[j]);
    Ys[j] = madd(v, cy[j], Y[j]);
  }
}

// Move vertices to time t. Cost: kCostLerp (9 MADD).
template <class F>
inline void lerp_vertices(const F X[3], const F Y[3], const F W[3], const F dX[3], const F dY[3],
                          const F dW[3], F t, F Xt[3], F Yt[3], F Wt[3]) {
  for (int j = 0; j < 3; ++j) {
    Xt[j] = madd(t, dX[j], X[j]);
    Yt[j] = madd(t, dY[j], Y[j]);
    Wt[j] = madd(t, dW[j], W[j]);
  }
}

// Shear coefficients of moving vertices, then shear. Cost: kCostShearMoving (12 MADD).
// cx = Kx * W + (-Kx F) with the same float constants as the static setup, so a static vertex
// gets bit-identical coefficients.
template <class F>
inline void shear_moving(const F Xt[3], const F Yt[3], const F Wt[3], F kx, F neg_kx_f, F ky,
                         F neg_ky_f, F u, F v, F Xs[3], F Ys[3]) {
  for (int j = 0; j < 3; ++j) {
    const F cxj = madd(Wt[j], kx, neg_kx_f);
    const F cyj = madd(Wt[j], ky, neg_ky_f);
    Xs[j] = madd(u, cxj, Xt[j]);
    Ys[j] = madd(v, cyj, Yt[j]);
  }
}

// ---- interpolation of covered samples (the same for every algorithm) -------------------------

// Depth of the hit point: z = 1 - near / W_hit, W_hit = det / sum(e). Returns z (>= 0 in front of
// the near plane). Cost: kCostDepth (2 ADD, RCP, MUL, MADD, CMP).
template <class F>
inline bool hit_depth(const F e[3], F det, F neg_near, F& sum, F& z) {
  sum = e[0] + e[1] + e[2];
  const F inv_det = rcp(det);
  const F inv_w = sum * inv_det;
  z = madd(neg_near, inv_w, F(1.0f));
  return z >= F(0.0f);
}

// Perspective-correct barycentrics b_i = e_i / sum(e) and the interpolated vertex colour.
// Cost: kCostColor (RCP, 3 MUL, 9 for the colour).
template <class F>
inline void hit_color(const F e[3], F sum, const F c0[3], const F c1[3], const F c2[3], F out[3]) {
  const F inv = rcp(sum);
  const F b0 = e[0] * inv, b1 = e[1] * inv, b2 = e[2] * inv;
  for (int ch = 0; ch < 3; ++ch) out[ch] = madd(b2, c2[ch], madd(b1, c1[ch], b0 * c0[ch]));
}

}  // namespace rast5d
