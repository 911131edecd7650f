// INSTRUMENTATION ONLY: the exact active region of [Akenine-Möller 2012] §4 evaluated
// point-wise in double (no grid, no oracle, no margin), for tile.samples_optimal, the denominator
// of [Akenine-Möller 2012] Table 1. Never used to cull and never counted in ops.*.
#pragma once

#include <algorithm>
#include <cstdint>
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "core/sample_table.h"
#include "setup/footprint.h"
#include "setup/setup.h"
#include "tiletest/common.h"

namespace rast5d::tiletest {

// Does the convex polygon with screen vertices (x[j], y[j]) overlap the tile [x0, x1] x [y0, y1]?
// Exact separating-axis test in double: the optimal tile test of [Akenine-Möller 2012] §4 evaluated point-wise,
// used for tile.samples_optimal (uncounted instrumentation).
inline bool polygon_overlaps_tile(const double* x, const double* y, int n, double x0, double x1, double y0,
                                  double y1) {
  double lx = kInf, hx = -kInf, ly = kInf, hy = -kInf;
  for (int j = 0; j < n; ++j)
    lx = std::min(lx, x[j]), hx = std::max(hx, x[j]), ly = std::min(ly, y[j]), hy = std::max(hy, y[j]);
  if (hx < x0 || lx > x1 || hy < y0 || ly > y1) return false;
  double area = 0;
  for (int j = 0; j < n; ++j) area += x[j] * y[(j + 1) % n] - x[(j + 1) % n] * y[j];
  if (area == 0) return false;  // seen edge-on: the sample test's det is 0, nothing can hit
  const double s = area > 0 ? 1.0 : -1.0;
  const double cx[4] = {x0, x1, x0, x1}, cy[4] = {y0, y0, y1, y1};
  for (int j = 0; j < n; ++j) {
    const int k = (j + 1) % n;
    const double ex = x[k] - x[j], ey = y[k] - y[j];
    if (ex == 0 && ey == 0) continue;
    bool all_out = true;
    for (int c = 0; c < 4 && all_out; ++c)
      if (s * (ex * (cy[c] - y[j]) - ey * (cx[c] - x[j])) >= 0) all_out = false;
    if (all_out) return false;
  }
  return true;
}

// The footprint polygon (pixel-homogeneous vertices, all W > 0) seen from lens point (u, v).
inline bool footprint_overlaps_tile(const double (*P)[3], int n, double kx, double ky, double focus,
                                    double u, double v, double x0, double x1, double y0, double y1) {
  double x[6], y[6];
  for (int j = 0; j < n; ++j) {
    x[j] = (P[j][0] + u * kx * (P[j][2] - focus)) / P[j][2];
    y[j] = (P[j][1] + v * ky * (P[j][2] - focus)) / P[j][2];
  }
  return polygon_overlaps_tile(x, y, n, x0, x1, y0, y1);
}

// Is the sample's (u, v, t) inside the exact active region of the (unexpanded) tile
// [tx, tx + T) x [ty, ty + T)? Instrumentation for tile.samples_optimal (uncounted).
inline bool in_exact_region(const TriSetup& tri, const Footprint& fp, const FrameConst& fc,
                            const PixelSamples& ps, int s, int tx, int ty, int T) {
  const double u = ps.u[s], v = ps.v[s];
  if (!tri.moving) {
    double x[6], y[6];
    for (int j = 0; j < fp.n; ++j) x[j] = fp.lv[j].ax + u * fp.lv[j].bx, y[j] = fp.lv[j].ay + v * fp.lv[j].by;
    return polygon_overlaps_tile(x, y, fp.n, tx, tx + T, ty, ty + T);
  }
  const double t = ps.t[s];
  double P[3][3];
  for (int j = 0; j < 3; ++j) {
    P[j][0] = tri.X[j] + t * static_cast<double>(tri.dX[j]);
    P[j][1] = tri.Y[j] + t * static_cast<double>(tri.dY[j]);
    P[j][2] = tri.W[j] + t * static_cast<double>(tri.dW[j]);
    if (!(P[j][2] > fc.near_d)) return true;  // crosses the near plane at t: not evaluated
  }
  return footprint_overlaps_tile(P, 3, fc.kx_d, fc.ky_d, fc.focus_d, u, v, tx, tx + T, ty, ty + T);
}

#if defined(__AVX512F__)
// polygon_overlaps_tile() of 8 polygons at once (vertex j of lane l in x[j], y[j]), each lane
// performing its double operations (min / max in its operand order, ordered compares, the same sums
// in the same order): the lanes where it returns true, within ok.
inline __mmask8 polygons_overlap_tile(const __m512d* x, const __m512d* y, int m, double tx0, double tx1, double ty0,
                                      double ty1, __mmask8 ok) {
  const __m512d zero = _mm512_setzero_pd();
  const __m512d x0 = _mm512_set1_pd(tx0), x1 = _mm512_set1_pd(tx1), y0 = _mm512_set1_pd(ty0), y1 = _mm512_set1_pd(ty1);
  __m512d lx = _mm512_set1_pd(kInf), hx = _mm512_set1_pd(-kInf), ly = lx, hy = hx;
  for (int j = 0; j < m; ++j) {
    lx = _mm512_min_pd(x[j], lx), hx = _mm512_max_pd(x[j], hx);  // std::min(lx, x) = x < lx ? x : lx
    ly = _mm512_min_pd(y[j], ly), hy = _mm512_max_pd(y[j], hy);
  }
  ok &= static_cast<__mmask8>(~(_mm512_cmp_pd_mask(hx, x0, _CMP_LT_OQ) | _mm512_cmp_pd_mask(lx, x1, _CMP_GT_OQ) |
                                _mm512_cmp_pd_mask(hy, y0, _CMP_LT_OQ) | _mm512_cmp_pd_mask(ly, y1, _CMP_GT_OQ)));
  __m512d area = zero;
  for (int j = 0; j < m; ++j) {
    const int k = (j + 1) % m;
    area = _mm512_add_pd(area, _mm512_sub_pd(_mm512_mul_pd(x[j], y[k]), _mm512_mul_pd(x[k], y[j])));
  }
  ok &= static_cast<__mmask8>(~_mm512_cmp_pd_mask(area, zero, _CMP_EQ_OQ));
  const __m512d sg = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(area, zero, _CMP_GT_OQ), _mm512_set1_pd(-1.0),
                                          _mm512_set1_pd(1.0));
  const __m512d cx[4] = {x0, x1, x0, x1}, cy[4] = {y0, y0, y1, y1};
  for (int j = 0; j < m && ok; ++j) {
    const int k = (j + 1) % m;
    const __m512d ex = _mm512_sub_pd(x[k], x[j]), ey = _mm512_sub_pd(y[k], y[j]);
    const __mmask8 point = _mm512_cmp_pd_mask(ex, zero, _CMP_EQ_OQ) & _mm512_cmp_pd_mask(ey, zero, _CMP_EQ_OQ);
    __mmask8 some_in = 0;
    for (int c = 0; c < 4; ++c) {
      const __m512d d = _mm512_mul_pd(
          sg, _mm512_sub_pd(_mm512_mul_pd(ex, _mm512_sub_pd(cy[c], y[j])), _mm512_mul_pd(ey, _mm512_sub_pd(cx[c], x[j]))));
      some_in |= _mm512_cmp_pd_mask(d, zero, _CMP_GE_OQ);
    }
    ok &= point | some_in;
  }
  return ok;
}
#endif

// How many of the samples cand[0..n) of pixel ps lie in the exact active region of the tile: the sum
// of in_exact_region() over them, 8 samples at a time in AVX-512 lanes, each lane performing
// in_exact_region's double operations, so the count is the scalar one. Uncounted instrumentation.
inline std::uint64_t count_exact_region(const TriSetup& tri, const Footprint& fp, const FrameConst& fc,
                                        const PixelSamples& ps, const int* cand, int n, int tx, int ty, int T) {
  std::uint64_t count = 0;
  int i = 0;
#if defined(__AVX512F__)
  if (tri.moving || fp.n > 0) {
    for (; i < n; i += 8) {
      const int lanes = std::min(8, n - i);
      alignas(64) double ub[8], vb[8], tb[8];
      for (int l = 0; l < 8; ++l) {
        const int s = cand[i + (l < lanes ? l : 0)];
        ub[l] = ps.u[s], vb[l] = ps.v[s], tb[l] = ps.t[s];
      }
      const __m512d u = _mm512_load_pd(ub), v = _mm512_load_pd(vb);
      const __mmask8 live = static_cast<__mmask8>((1u << lanes) - 1);
      __m512d x[6], y[6];
      if (!tri.moving) {
        for (int j = 0; j < fp.n; ++j) {
          x[j] = _mm512_add_pd(_mm512_set1_pd(fp.lv[j].ax), _mm512_mul_pd(u, _mm512_set1_pd(fp.lv[j].bx)));
          y[j] = _mm512_add_pd(_mm512_set1_pd(fp.lv[j].ay), _mm512_mul_pd(v, _mm512_set1_pd(fp.lv[j].by)));
        }
        count += static_cast<std::uint64_t>(__builtin_popcount(polygons_overlap_tile(x, y, fp.n, tx, tx + T, ty, ty + T, live)));
        continue;
      }
      // Moving: the vertices at each sample's t; a vertex not beyond the near plane counts the sample.
      const __m512d t = _mm512_load_pd(tb);
      const __m512d near = _mm512_set1_pd(fc.near_d), focus = _mm512_set1_pd(fc.focus_d);
      const __m512d ukx = _mm512_mul_pd(u, _mm512_set1_pd(fc.kx_d)), vky = _mm512_mul_pd(v, _mm512_set1_pd(fc.ky_d));
      __mmask8 behind = 0;
      for (int j = 0; j < 3; ++j) {
        const __m512d P0 = _mm512_add_pd(_mm512_set1_pd(tri.X[j]), _mm512_mul_pd(t, _mm512_set1_pd(tri.dX[j])));
        const __m512d P1 = _mm512_add_pd(_mm512_set1_pd(tri.Y[j]), _mm512_mul_pd(t, _mm512_set1_pd(tri.dY[j])));
        const __m512d P2 = _mm512_add_pd(_mm512_set1_pd(tri.W[j]), _mm512_mul_pd(t, _mm512_set1_pd(tri.dW[j])));
        behind |= static_cast<__mmask8>(~_mm512_cmp_pd_mask(P2, near, _CMP_GT_OQ));
        const __m512d d = _mm512_sub_pd(P2, focus);
        x[j] = _mm512_div_pd(_mm512_add_pd(P0, _mm512_mul_pd(ukx, d)), P2);
        y[j] = _mm512_div_pd(_mm512_add_pd(P1, _mm512_mul_pd(vky, d)), P2);
      }
      behind &= live;
      count += static_cast<std::uint64_t>(__builtin_popcount(behind));
      count += static_cast<std::uint64_t>(
          __builtin_popcount(polygons_overlap_tile(x, y, 3, tx, tx + T, ty, ty + T, static_cast<__mmask8>(live & ~behind))));
    }
  }
#endif
  for (; i < n; ++i) count += in_exact_region(tri, fp, fc, ps, cand[i], tx, ty, T);
  return count;
}

}  // namespace rast5d::tiletest
