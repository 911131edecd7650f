// The sample test decided in a stage precision other than the robust float32 kernels'
// (pipeline.precision.sample; docs/precision.md). The render's operation counts stay those of the
// cost model's kernels: precision changes which samples are covered, not what a test costs.
//
// Contract:
//  * float64: the robust kernel (sampletest/inside.h) instantiated on double.
//  * fixed {int_bits, frac_bits}: the vertices are placed at the sample's (u, v, t) in float64, each
//    scaled by 1 / |W_j| (a positive factor: every edge function and det keep their signs, so the
//    exact decision is unchanged and vertices behind the camera need no clipping) to screen pixels
//    (x_j, y_j, +-1), then snapped with the sample position to the 2^-frac_bits sub-pixel grid; the
//    sample-relative edge functions, det, sign tests and top-left rule run on core/fixed.h's Fixed,
//    whose registers keep 2 frac_bits fraction bits, so they are exact on the snapped inputs. A value
//    reaching 2^int_bits sets overflow (hardware would wrap; the render keeps the unwrapped decision
//    and counts the sample in precision.sample_overflows).
//  * e and det returned are the float64 ones (depth and colour interpolation).
#pragma once

#include <algorithm>
#include <cmath>

#include "core/fixed.h"
#include "core/params.h"
#include "sampletest/inside.h"

namespace rast5d {

// Widening of every tile test's tile (tiletest/common.h) that keeps it conservative against the
// snapped triangle of a fixed-point sample test: each snapped vertex and the snapped sample move at
// most 2^-(frac_bits+1) px per axis, so the snapped triangle lies within 2^-frac_bits px of the exact
// one relative to the sample; twice that is used.
inline double snap_margin_px(const Precision& p) {
  return p.kind == PrecisionKind::kFixed ? std::ldexp(1.0, 1 - p.frac_bits) : 0.0;
}
// The widening a render's tile tests need: the larger of the fixed-point sample test's and the
// fixed-point 2D tile test's (tiletest/edges_2d.h) snapping; float stages need none beyond kMarginAbs.
inline double snap_margin_px(const Precision& sample, const Precision& tile) {
  return std::max(snap_margin_px(sample), snap_margin_px(tile));
}

// A pixel-homogeneous vertex scaled to (x, y, +-1) by 1 / |W| (W == 0: unchanged).
inline void to_screen(double X, double Y, double W, double& x, double& y, double& w) {
  const double s = W != 0.0 ? 1.0 / std::fabs(W) : 1.0;
  x = X * s, y = Y * s, w = W * s;
}

// The fixed-point decision for a triangle already placed at the sample's (u, v, t).
inline bool fixed_inside_placed(const double X[3], const double Y[3], const double W[3], double sx, double sy,
                                const Precision& p, bool back_face_cull, bool& overflow) {
  FixedFormat::set(p.int_bits, p.frac_bits);
  Fixed Xf[3], Yf[3], Wf[3], ef[3], detf;
  for (int j = 0; j < 3; ++j) {
    double x, y, w;
    to_screen(X[j], Y[j], W[j], x, y, w);
    Xf[j] = Fixed(x), Yf[j] = Fixed(y), Wf[j] = Fixed(w);
  }
  int n_ties;
  const bool covered = inside_from_vertices(Xf, Yf, Wf, Fixed(sx), Fixed(sy), back_face_cull, ef, detf, n_ties);
  overflow = FixedFormat::overflow;
  return covered;
}

// The decision of sample (sx, sy, u, v, t) in precision p (not float32), with float64 e and det.
inline bool precise_inside(const TriSetup& tri, const FrameConst& fc, const Precision& p, double sx, double sy,
                           double u, double v, double t, bool back_face_cull, double e[3], double& det,
                           bool& overflow) {
  double X[3], Y[3], W[3];
  int n_ties;
  const bool covered64 = inside_test<double>(tri, tri.cls, fc, sx, sy, u, v, t, back_face_cull, X, Y, W, e, det, n_ties);
  overflow = false;
  if (p.kind != PrecisionKind::kFixed) return covered64;
  return fixed_inside_placed(X, Y, W, sx, sy, p, back_face_cull, overflow);
}

}  // namespace rast5d
