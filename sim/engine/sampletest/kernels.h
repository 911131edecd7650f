// The sample test: is one sample (x, y, u, v, t) inside the triangle placed at its (u, v, t)?
//
// Contract (docs/conventions.md, geometric conventions):
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

#include <cstdint>

#include "core/arith.h"
#include "core/triangle.h"

namespace rast5d {

// Homogeneous edge functions and determinant of a (sheared) triangle at the sample (sx, sy).
// Cost: cost::kEdges (core/costs.h). The scalar-argument form is the single definition of the
// arithmetic (the batched fast path calls it in vectorisable loops); the array form forwards to it.
template <class F>
inline void edge_functions_s(F X0, F X1, F X2, F Y0, F Y1, F Y2, F W0, F W1, F W2, F sx, F sy, F& e0, F& e1,
                             F& e2, F& det) {
  const F rx0 = madd(W0, -sx, X0), ry0 = madd(W0, -sy, Y0);
  const F rx1 = madd(W1, -sx, X1), ry1 = madd(W1, -sy, Y1);
  const F rx2 = madd(W2, -sx, X2), ry2 = madd(W2, -sy, Y2);
  e0 = rx1 * ry2 - ry1 * rx2;
  e1 = rx2 * ry0 - ry2 * rx0;
  e2 = rx0 * ry1 - ry0 * rx1;
  det = madd(W2, e2, madd(W1, e1, W0 * e0));
}

template <class F>
inline void edge_functions(const F X[3], const F Y[3], const F W[3], F sx, F sy, F e[3], F& det) {
  edge_functions_s(X[0], X[1], X[2], Y[0], Y[1], Y[2], W[0], W[1], W[2], sx, sy, e[0], e[1], e[2], det);
}

// ---- batched fast path ---------------------------------------------------------------------------
// The per-class sample kernels over a batch of samples in structure-of-arrays form, written as
// straight-line loops over restrict-qualified parameters so the compiler vectorises them. They
// perform exactly the operations of shear_static / lerp_vertices / shear_moving followed by
// edge_functions, in the same order, so every result is bit-identical to the scalar kernels.
struct BatchTri {
  float X0, X1, X2, Y0, Y1, Y2, W0, W1, W2;
  float cx0, cx1, cx2, cy0, cy1, cy2;        // static shear coefficients (4D)
  float dX0, dX1, dX2, dY0, dY1, dY2, dW0, dW1, dW2;  // motion (3D, 5D)
  float kx, nkx, ky, nky;                    // moving shear constants (5D)
};

[[gnu::noinline]] inline void batch_edges_2d(int n, const BatchTri& T, const float* __restrict bx,
                                              const float* __restrict by, float* __restrict e0,
                                              float* __restrict e1, float* __restrict e2, float* __restrict dt) {
  const float X0 = T.X0, X1 = T.X1, X2 = T.X2, Y0 = T.Y0, Y1 = T.Y1, Y2 = T.Y2, W0 = T.W0, W1 = T.W1, W2 = T.W2;
  for (int i = 0; i < n; ++i)
    edge_functions_s(X0, X1, X2, Y0, Y1, Y2, W0, W1, W2, bx[i], by[i], e0[i], e1[i], e2[i], dt[i]);
}

[[gnu::noinline]] inline void batch_edges_4d(int n, const BatchTri& T, const float* __restrict bx,
                                              const float* __restrict by, const float* __restrict bu,
                                              const float* __restrict bv, float* __restrict e0,
                                              float* __restrict e1, float* __restrict e2, float* __restrict dt) {
  const float X0 = T.X0, X1 = T.X1, X2 = T.X2, Y0 = T.Y0, Y1 = T.Y1, Y2 = T.Y2, W0 = T.W0, W1 = T.W1, W2 = T.W2;
  const float cx0 = T.cx0, cx1 = T.cx1, cx2 = T.cx2, cy0 = T.cy0, cy1 = T.cy1, cy2 = T.cy2;
  for (int i = 0; i < n; ++i) {
    const float u = bu[i], v = bv[i];
    edge_functions_s(madd(u, cx0, X0), madd(u, cx1, X1), madd(u, cx2, X2), madd(v, cy0, Y0), madd(v, cy1, Y1),
                     madd(v, cy2, Y2), W0, W1, W2, bx[i], by[i], e0[i], e1[i], e2[i], dt[i]);
  }
}

[[gnu::noinline]] inline void batch_edges_3d(int n, const BatchTri& T, const float* __restrict bx,
                                              const float* __restrict by, const float* __restrict bt,
                                              float* __restrict e0, float* __restrict e1, float* __restrict e2,
                                              float* __restrict dt) {
  const float X0 = T.X0, X1 = T.X1, X2 = T.X2, Y0 = T.Y0, Y1 = T.Y1, Y2 = T.Y2, W0 = T.W0, W1 = T.W1, W2 = T.W2;
  const float dX0 = T.dX0, dX1 = T.dX1, dX2 = T.dX2, dY0 = T.dY0, dY1 = T.dY1, dY2 = T.dY2;
  const float dW0 = T.dW0, dW1 = T.dW1, dW2 = T.dW2;
  for (int i = 0; i < n; ++i) {
    const float t = bt[i];
    edge_functions_s(madd(t, dX0, X0), madd(t, dX1, X1), madd(t, dX2, X2), madd(t, dY0, Y0), madd(t, dY1, Y1),
                     madd(t, dY2, Y2), madd(t, dW0, W0), madd(t, dW1, W1), madd(t, dW2, W2), bx[i], by[i], e0[i],
                     e1[i], e2[i], dt[i]);
  }
}

[[gnu::noinline]] inline void batch_edges_5d(int n, const BatchTri& T, const float* __restrict bx,
                                              const float* __restrict by, const float* __restrict bu,
                                              const float* __restrict bv, const float* __restrict bt,
                                              float* __restrict e0, float* __restrict e1, float* __restrict e2,
                                              float* __restrict dt) {
  const float X0 = T.X0, X1 = T.X1, X2 = T.X2, Y0 = T.Y0, Y1 = T.Y1, Y2 = T.Y2, W0 = T.W0, W1 = T.W1, W2 = T.W2;
  const float dX0 = T.dX0, dX1 = T.dX1, dX2 = T.dX2, dY0 = T.dY0, dY1 = T.dY1, dY2 = T.dY2;
  const float dW0 = T.dW0, dW1 = T.dW1, dW2 = T.dW2;
  const float kx = T.kx, nkx = T.nkx, ky = T.ky, nky = T.nky;
  for (int i = 0; i < n; ++i) {
    const float t = bt[i], u = bu[i], v = bv[i];
    const float xt0 = madd(t, dX0, X0), yt0 = madd(t, dY0, Y0), wt0 = madd(t, dW0, W0);
    const float xt1 = madd(t, dX1, X1), yt1 = madd(t, dY1, Y1), wt1 = madd(t, dW1, W1);
    const float xt2 = madd(t, dX2, X2), yt2 = madd(t, dY2, Y2), wt2 = madd(t, dW2, W2);
    edge_functions_s(madd(u, madd(wt0, kx, nkx), xt0), madd(u, madd(wt1, kx, nkx), xt1),
                     madd(u, madd(wt2, kx, nkx), xt2), madd(v, madd(wt0, ky, nky), yt0),
                     madd(v, madd(wt1, ky, nky), yt1), madd(v, madd(wt2, ky, nky), yt2), wt0, wt1, wt2, bx[i], by[i],
                     e0[i], e1[i], e2[i], dt[i]);
  }
}

// Batch decision flags: 1 = covered (det != 0 and every e_i strictly has det's sign; back-facing
// det > 0 rejected when culling), 2 = undecided (an e_i is exactly 0: the scalar top-left path
// decides). Same decisions as edge_signs() for every sample it marks 1 or 0.
[[gnu::noinline]] inline void batch_flags(int n, const float* __restrict e0, const float* __restrict e1,
                                           const float* __restrict e2, const float* __restrict det,
                                           bool back_face_cull, std::uint8_t* __restrict flags) {
  const int bfc = back_face_cull ? 1 : 0;
  for (int i = 0; i < n; ++i) {
    const float a = e0[i], b = e1[i], c = e2[i], d = det[i];
    const int dpos = d > 0.0f, dneg = d < 0.0f;
    const int allpos = (a > 0.0f) & (b > 0.0f) & (c > 0.0f);
    const int allneg = (a < 0.0f) & (b < 0.0f) & (c < 0.0f);
    const int anyzero = (a == 0.0f) | (b == 0.0f) | (c == 0.0f);
    const int cov = (dpos & allpos & (1 - bfc)) | (dneg & allneg);
    flags[i] = static_cast<std::uint8_t>(cov | ((anyzero & (dpos | dneg)) << 1));
  }
}

// Sign tests of the edge functions against det. Cost: cost::kSigns.
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
// Cost per zero edge: cost::kTieBreak.
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

// Shear static vertices to lens point (u, v). Cost: cost::kShear.
template <class F>
inline void shear_static(const F X[3], const F Y[3], const F cx[3], const F cy[3], F u, F v, F Xs[3],
                         F Ys[3]) {
  for (int j = 0; j < 3; ++j) {
    Xs[j] = madd(u, cx[j], X[j]);
    Ys[j] = madd(v, cy[j], Y[j]);
  }
}

// Move vertices to time t. Cost: cost::kLerp.
template <class F>
inline void lerp_vertices(const F X[3], const F Y[3], const F W[3], const F dX[3], const F dY[3],
                          const F dW[3], F t, F Xt[3], F Yt[3], F Wt[3]) {
  for (int j = 0; j < 3; ++j) {
    Xt[j] = madd(t, dX[j], X[j]);
    Yt[j] = madd(t, dY[j], Y[j]);
    Wt[j] = madd(t, dW[j], W[j]);
  }
}

// Shear coefficients of moving vertices, then shear. Cost: cost::kShearMoving.
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
// the near plane). Cost: cost::kDepth.
template <class F>
inline bool hit_depth(const F e[3], F det, F neg_near, F& sum, F& z) {
  sum = e[0] + e[1] + e[2];
  const F inv_det = rcp(det);
  const F inv_w = sum * inv_det;
  z = madd(neg_near, inv_w, F(1.0f));
  return z >= F(0.0f);
}

// Perspective-correct barycentrics b_i = e_i / sum(e) and the interpolated vertex colour.
// Cost: cost::kColor.
template <class F>
inline void hit_color(const F e[3], F sum, const F c0[3], const F c1[3], const F c2[3], F out[3]) {
  const F inv = rcp(sum);
  const F b0 = e[0] * inv, b1 = e[1] * inv, b2 = e[2] * inv;
  for (int ch = 0; ch < 3; ++ch) out[ch] = madd(b2, c2[ch], madd(b1, c1[ch], b0 * c0[ch]));
}

}  // namespace rast5d
