// The standard 2D tile test of static, in-focus triangles (TILE's 2D class, HINTERLEAVE): the
// triangle's edge functions evaluated at each tile's most inside corner.
//
// Contract (tiletest/common.h): tile_outside_2d is true only if no point of the (expanded) tile is inside
// the triangle.
#pragma once

#include <cmath>

#include "core/arith.h"
#include "core/costs.h"
#include "core/fixed.h"
#include "core/params.h"
#include "tiletest/common.h"

namespace rast5d::tiletest {

// Homogeneous edge functions e_i(x, y) = A_i x + B_i y + C_i of a triangle (pixel-homogeneous
// vertices), oriented by sigma = sign det so that the inside is sigma * e_i >= 0 for all i (also
// for vertices behind the camera: Olano-Greer), plus the corner of a tile that maximises each.
struct Edges2D {
  double A[3], B[3], C[3];  // already multiplied by sigma
  bool x_hi[3], y_hi[3];    // which tile corner maximises edge i
  bool valid = false;       // false: det == 0 (no sample can hit)
  Precision precision = Precision::float64();  // the arithmetic of tile_outside_2d_in (pipeline.precision.tile)
  bool overflow = false;                       // fixed point: the set-up reached 2^int_bits
};

// Cost: cost::kEdges2DSetup.
template <class D, class In>
inline Edges2D edges_2d(const In* X, const In* Y, const In* W) {
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

namespace rast5d::tiletest {

// ---- the 2D tile test in a chosen arithmetic (pipeline.precision.tile; docs/precision.md) ----------
// edges_2d_in / tile_outside_2d_in run the D form (counted, as always: precision does not change the
// operation counts) and, for float32 or fixed, decide with that arithmetic instead:
//  * float32: the same set-up and evaluation in binary32;
//  * fixed {int_bits, frac_bits}: each vertex scaled by 1 / |W| to screen pixels (x, y, +-1; a positive
//    factor keeps every sign) and snapped to the 2^-frac_bits grid with the tile corners; the set-up's
//    products and the evaluation are exact in core/fixed.h's registers (C keeps its 2 frac_bits
//    fraction bits), values reaching 2^int_bits set overflow. The snapped triangle lies within
//    sampletest/precision.h's snap_margin_px of the exact one, by which every tile is widened
//    (tiletest/common.h t_snap_margin_px): the fixed-point test stays conservative.
template <class D>
inline Edges2D edges_2d_in(const Precision& p, const float* X, const float* Y, const float* W) {
  Edges2D e = edges_2d<D>(X, Y, W);
  if (p.kind == PrecisionKind::kFloat64) return e;
  if (p.kind == PrecisionKind::kFloat32) {
    e = edges_2d<float>(X, Y, W);
  } else {
    double x[3], y[3], w[3];
    for (int j = 0; j < 3; ++j) {
      const double s = W[j] != 0.0f ? 1.0 / std::fabs(static_cast<double>(W[j])) : 1.0;
      x[j] = X[j] * s, y[j] = Y[j] * s, w[j] = W[j] * s;
    }
    FixedFormat::set(p.int_bits, p.frac_bits);
    const Edges2D ef = edges_2d<Fixed>(x, y, w);
    // A triangle that snaps to zero area has no edge functions; the exact triangle still lies within the
    // snap margin of the snapped segment, and a float sample test may hit it: keep its float64 edges.
    if (!ef.valid && e.valid) return e;
    e = ef;
    e.overflow = FixedFormat::overflow;
  }
  e.precision = p;
  return e;
}

// Is the (expanded) tile outside one of the edges, in e's arithmetic? overflow: fixed point only.
template <class D>
inline bool tile_outside_2d_in(const Edges2D& e, double x0, double x1, double y0, double y1, bool& overflow) {
  const bool out = tile_outside_2d<D>(e, x0, x1, y0, y1);
  overflow = false;
  switch (e.precision.kind) {
    case PrecisionKind::kFloat64: return out;
    case PrecisionKind::kFloat32: return tile_outside_2d<float>(e, x0, x1, y0, y1);
    default: {
      FixedFormat::set(e.precision.int_bits, e.precision.frac_bits);
      bool r = false;
      for (int i = 0; i < 3; ++i) {  // A, B, C are exact multiples of 2^-2 frac_bits (edges_2d<Fixed>)
        const Fixed v = madd(fixed_exact(e.A[i]), Fixed(e.x_hi[i] ? x1 : x0),
                             madd(fixed_exact(e.B[i]), Fixed(e.y_hi[i] ? y1 : y0), fixed_exact(e.C[i])));
        if (v < Fixed(0.0)) r = true;
      }
      overflow = e.overflow || FixedFormat::overflow;
      return r;
    }
  }
}

}  // namespace rast5d::tiletest
