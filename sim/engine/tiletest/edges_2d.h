// The standard 2D tile test of static, in-focus triangles (TILE's 2D class, HINTERLEAVE): the
// triangle's edge functions evaluated at each tile's most inside corner.
//
// Contract (tile_test.h): tile_outside_2d is true only if no point of the (expanded) tile is inside
// the triangle.
#pragma once

#include "core/arith.h"
#include "core/costs.h"
#include "sampletest/sample_test.h"
#include "tiletest/tile_test.h"

namespace rast5d::tiletest {

// Homogeneous edge functions e_i(x, y) = A_i x + B_i y + C_i of a triangle (pixel-homogeneous
// vertices), oriented by sigma = sign det so that the inside is sigma * e_i >= 0 for all i (also
// for vertices behind the camera: Olano-Greer), plus the corner of a tile that maximises each.
struct Edges2D {
  double A[3], B[3], C[3];  // already multiplied by sigma
  bool x_hi[3], y_hi[3];    // which tile corner maximises edge i
  bool valid = false;       // false: det == 0 (no sample can hit)
};

// Cost: cost::kEdges2DSetup.
template <class D>
inline Edges2D edges_2d(const float* X, const float* Y, const float* W) {
  Edges2D e;
  D A[3], B[3], C[3];
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    A[i] = madd(D(Y[j]), D(W[k]), -(D(W[j]) * D(Y[k])));
    B[i] = madd(D(W[j]), D(X[k]), -(D(X[j]) * D(W[k])));
    C[i] = madd(D(X[j]), D(Y[k]), -(D(Y[j]) * D(X[k])));
  }
  const D det = madd(A[0], D(X[0]), madd(B[0], D(Y[0]), C[0] * D(W[0])));
  const int sigma = sign_of(det);
  e.valid = sigma != 0;
  for (int i = 0; i < 3; ++i) {
    e.A[i] = sigma * raw(A[i]), e.B[i] = sigma * raw(B[i]), e.C[i] = sigma * raw(C[i]);
    e.x_hi[i] = D(e.A[i]) >= D(0.0);
    e.y_hi[i] = D(e.B[i]) >= D(0.0);
  }
  return e;
}

// Is the (expanded) tile outside one of the edges? Cost: cost::kTile2D.
template <class D>
inline bool tile_outside_2d(const Edges2D& e, double x0, double x1, double y0, double y1) {
  bool outside = false;
  for (int i = 0; i < 3; ++i) {
    const D v = madd(D(e.A[i]), D(e.x_hi[i] ? x1 : x0), madd(D(e.B[i]), D(e.y_hi[i] ? y1 : y0), D(e.C[i])));
    if (v < D(0.0)) outside = true;
  }
  return outside;
}

}  // namespace rast5d::tiletest
