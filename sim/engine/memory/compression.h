// Depth compression of the stochastic depth buffer (docs/memory.md): the bytes one depth-buffer line
// takes in DRAM when the depth-tile cache writes it back.
//
// Schemes (hardware.depth_buffer.compression):
//   none            raw: 4 bytes per sample.
//   plane           the static-plane baseline of depth compressors for static triangles: one plane
//                   z = a + b x + c y over every written sample of the line, per-sample residuals.
//   time_predictor  in the manner of [Andersson 2011]: the written depths are split into up to two
//                   layers (2-means clustering on depth), each layer gets a time-dependent predictor
//                   z = a + b x + c y + t (d + e x + f y) (or the plane, whichever encodes shorter;
//                   in a frame where nothing moves depth does not depend on t, and the plane is
//                   fitted alone), and every sample stores its delta residual.
//
// Encoding (both predictive schemes): a 32-bit header; a clear mask (1 bit per sample) when the line
// mixes cleared and written samples; a layer mask (1 bit per written sample) with two layers; per
// layer its predictor coefficients (32 bits each) and its residual width (5 bits); then every written
// sample's residual at its layer's width (enough bits for the largest |residual| plus a sign).
// Depths are compared as 24-bit unorm values (z in [0, 1] scaled by 2^24 - 1). A line is stored
// compressed only when that, rounded up to the DRAM burst, is smaller than raw.
//
// Contract: deterministic (the same depths give the same size on every machine and thread count);
// the compressed size never exceeds the raw size; a line whose samples are all cleared costs 0 bytes.
#pragma once

#include <algorithm>
#include <array>
#if defined(__AVX512F__)
#include <immintrin.h>
#endif
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <vector>

#include "core/params.h"

namespace rast5d::memory {

inline constexpr double kUnorm24 = 16777215.0;
inline constexpr int kHeaderBits = 32;
inline constexpr int kCoefBits = 32;
inline constexpr int kWidthBits = 5;

// Bits for a signed residual of magnitude at most m (0: every residual is exactly zero).
inline int residual_bits(std::int64_t m) {
  if (m == 0) return 0;
  int b = 0;
  while ((std::int64_t(1) << b) <= m) ++b;
  return b + 1;  // magnitude bits and a sign
}

// The written samples of a line (or of one layer), contiguous, in fixed point: x, y in 1/256 px from
// the line's tile corner, t in 1/4096 of the shutter, z the 24-bit depth.
struct FitSamples {
  std::vector<std::int32_t> xq, yq, tq, z;
  int n = 0;
  void resize(std::size_t m) {
    for (auto* v : {&xq, &yq, &tq, &z}) v->resize(m);
  }
};

// The 24-bit unorm depth of a stored depth z in [0, 1].
inline std::int32_t unorm24(float z) {
  return static_cast<std::int32_t>(std::floor(std::clamp(static_cast<double>(z), 0.0, 1.0) * kUnorm24 + 0.5));
}

// Least-squares fits of the depths of a set of samples over the first k basis functions of
// (1, x, y, t, t x, t y), k = 1 (a constant), 3 (a plane) and 6 (a time-dependent plane), and the
// bits each needs: coefficients, residual width, and every sample's residual (the depth minus the
// prediction rounded half up). The normal equations are summed in 64-bit integers over the fixed-point
// positions (exact, so the result does not depend on the order of the sums), then solved in double.
class PredictorFit {
 public:
  // Bits of the samples under the first k basis functions for each k of `ks` (ascending, of 1, 3, 6),
  // into bits_out (-1 where the system is singular: too few distinct samples).
  void fit(const FitSamples& s, std::initializer_list<int> ks, long* bits_out) {
    const int n = s.n;
    const std::int32_t* __restrict xq = s.xq.data();
    const std::int32_t* __restrict yq = s.yq.data();
    const std::int32_t* __restrict tq = s.tq.data();
    const std::int32_t* __restrict zq = s.z.data();
    // The sums of the normal equations, straight-line (integer sums vectorise in any order): the 10
    // of the plane, and the 17 more of the time terms only when a 6-term fit is asked for.
    int maxk = 0;
    for (const int k : ks) maxk = std::max(maxk, k);
    std::int64_t sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0, sz = 0, szx = 0, szy = 0;
    std::int64_t st = 0, stx = 0, sty = 0, sxt = 0, sxtx = 0, sxty = 0, syt = 0, sytx = 0, syty = 0, stt = 0, sttx = 0,
                 stty = 0, stxtx = 0, stxty = 0, styty = 0, szt = 0, sztx = 0, szty = 0;
    if (maxk <= 3) {
      for (int i = 0; i < n; ++i) {
        const std::int64_t x = xq[i], y = yq[i], z = zq[i];
        sx += x, sy += y, sxx += x * x, sxy += x * y, syy += y * y, sz += z, szx += z * x, szy += z * y;
      }
    } else {
      for (int i = 0; i < n; ++i) {
        const std::int64_t x = xq[i], y = yq[i], t = tq[i], z = zq[i];
        const std::int64_t tx = t * x, ty = t * y;
        sx += x, sy += y, st += t, stx += tx, sty += ty;
        sxx += x * x, sxy += x * y, sxt += x * t, sxtx += x * tx, sxty += x * ty;
        syy += y * y, syt += y * t, sytx += y * tx, syty += y * ty;
        stt += t * t, sttx += t * tx, stty += t * ty;
        stxtx += tx * tx, stxty += tx * ty, styty += ty * ty;
        sz += z, szx += z * x, szy += z * y, szt += z * t, sztx += z * tx, szty += z * ty;
      }
    }
    // Upper triangle of A^T A row by row over the basis (1, x, y, t, tx, ty), and A^T z.
    const std::int64_t ata[21] = {n,   sx,  sy,   st,   stx,   sty,   sxx,  sxy,   sxt,   sxtx, sxty,
                                  syy, syt, sytx, syty, stt,   sttx,  stty, stxtx, stxty, styty};
    const std::int64_t atb[6] = {sz, szx, szy, szt, sztx, szty};
    // Back to real units: basis r carries the scale 2^shift[r].
    static constexpr int shift[6] = {0, 8, 8, 12, 20, 20};
    double A[6][6], B[6];
    int m = 0;
    for (int r = 0; r < 6; ++r) {
      B[r] = std::ldexp(static_cast<double>(atb[r]), -shift[r]);
      for (int c = r; c < 6; ++c, ++m) A[r][c] = A[c][r] = std::ldexp(static_cast<double>(ata[m]), -shift[r] - shift[c]);
    }
    double coef[3][6] = {};
    bool ok[3] = {false, false, false};
    int f = 0;
    for (const int k : ks) {
      double a[36], b[6];
      for (int r = 0; r < k; ++r) {
        b[r] = B[r];
        for (int c = 0; c < k; ++c) a[r * k + c] = A[r][c];
      }
      ok[f] = n >= k && solve(a, b, k, coef[f]);
      ++f;
    }
    const int nf = f;
    std::int64_t worst[3] = {0, 0, 0};
    for (int g = 0; g < nf; ++g) {  // each predictor's largest |residual| (a max: exact in any order)
      const double c[6] = {coef[g][0], coef[g][1] / 256.0, coef[g][2] / 256.0, coef[g][3], coef[g][4] / 256.0,
                           coef[g][5] / 256.0};
      worst[g] = static_cast<std::int64_t>(max_residual(c, xq, yq, tq, zq, n));
    }
    f = 0;
    for (const int k : ks) {
      bits_out[f] = ok[f] ? static_cast<long>(k) * kCoefBits + kWidthBits + static_cast<long>(n) * residual_bits(worst[f])
                          : -1;
      ++f;
    }
  }

 private:
  // max over i of |z_i - floor(p_i + 0.5)|, p_i = c0 + (c1 x + c2 y) + t (c3 + c4 x + c5 y) with x, y in
  // 1/256 px and t = tq / 4096: the same operations per sample in both paths, and a max is exact.
  static double max_residual(const double* c, const std::int32_t* xq, const std::int32_t* yq, const std::int32_t* tq,
                             const std::int32_t* zq, int n) {
    double w = 0.0;
    int i = 0;
#if defined(__AVX512F__)
    const __m512d c0 = _mm512_set1_pd(c[0]), c1 = _mm512_set1_pd(c[1]), c2 = _mm512_set1_pd(c[2]),
                  c3 = _mm512_set1_pd(c[3]), c4 = _mm512_set1_pd(c[4]), c5 = _mm512_set1_pd(c[5]);
    const __m512d inv_t = _mm512_set1_pd(1.0 / 4096.0), half = _mm512_set1_pd(0.5);
    __m512d vw = _mm512_setzero_pd();
    for (; i + 8 <= n; i += 8) {
      const __m512d x = _mm512_cvtepi32_pd(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(xq + i)));
      const __m512d y = _mm512_cvtepi32_pd(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(yq + i)));
      const __m512d t = _mm512_mul_pd(_mm512_cvtepi32_pd(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(tq + i))), inv_t);
      const __m512d z = _mm512_cvtepi32_pd(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(zq + i)));
      const __m512d lin = _mm512_add_pd(_mm512_mul_pd(c1, x), _mm512_mul_pd(c2, y));
      const __m512d tc = _mm512_add_pd(_mm512_add_pd(c3, _mm512_mul_pd(c4, x)), _mm512_mul_pd(c5, y));
      const __m512d pr = _mm512_add_pd(_mm512_add_pd(c0, lin), _mm512_mul_pd(t, tc));
      const __m512d rounded = _mm512_roundscale_pd(_mm512_add_pd(pr, half), _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
      const __m512d r = _mm512_abs_pd(_mm512_sub_pd(z, rounded));
      vw = _mm512_max_pd(vw, r);
    }
    w = _mm512_reduce_max_pd(vw);
#endif
    for (; i < n; ++i) {
      const double x = xq[i], y = yq[i], t = tq[i] * (1.0 / 4096.0), z = zq[i];
      const double lin = c[1] * x + c[2] * y;
      const double tc = (c[3] + c[4] * x) + c[5] * y;
      const double pr = (c[0] + lin) + t * tc;
      w = std::max(w, std::fabs(z - std::floor(pr + 0.5)));
    }
    return w;
  }

  // Gaussian elimination with partial pivoting on the k x k system; false when a pivot vanishes.
  static bool solve(double* a, double* b, int k, double* x) {
    for (int c = 0; c < k; ++c) {
      int p = c;
      for (int r = c + 1; r < k; ++r)
        if (std::fabs(a[r * k + c]) > std::fabs(a[p * k + c])) p = r;
      const double scale = std::fabs(a[c * k + c]) + std::fabs(a[p * k + c]);
      if (!(std::fabs(a[p * k + c]) > 1e-9 * std::max(1.0, scale))) return false;
      if (p != c) {
        for (int j = 0; j < k; ++j) std::swap(a[c * k + j], a[p * k + j]);
        std::swap(b[c], b[p]);
      }
      for (int r = c + 1; r < k; ++r) {
        const double f = a[r * k + c] / a[c * k + c];
        for (int j = c; j < k; ++j) a[r * k + j] -= f * a[c * k + j];
        b[r] -= f * b[c];
      }
    }
    for (int r = k - 1; r >= 0; --r) {
      double v = b[r];
      for (int j = r + 1; j < k; ++j) v -= a[r * k + j] * x[j];
      x[r] = v / a[r * k + r];
    }
    for (int j = k; j < 6; ++j) x[j] = 0.0;
    return true;
  }
};

// Scratch space of one compressor (one per worker thread).
class DepthCompressor {
 public:
  // The written samples of the next line: the caller fills [0, written) and sets n.
  FitSamples& samples() { return all_; }

  // Stored bytes of a line of `n` samples whose written ones are in samples(), under `scheme`: raw
  // (4 x samples), or the encoding rounded up to the burst when that is smaller.
  // moving: some triangle of the frame moves (else the time-dependent terms are not fitted).
  std::uint64_t stored_bytes(DepthCompression scheme, int n, std::uint64_t burst, bool moving = true) {
    moving_ = moving;
    const std::uint64_t raw = 4ull * static_cast<std::uint64_t>(n);
    const int written = all_.n;
    if (written == 0) return 0;  // every sample cleared: the tile-status state alone
    if (scheme == DepthCompression::kNone) return raw;
    long bits = kHeaderBits + (written < n ? n : 0);
    if (scheme == DepthCompression::kPlane) {
      long b;
      fit_.fit(all_, {3}, &b);
      if (b < 0) return raw;
      bits += b;
    } else {
      const long one = best_layer(all_);
      long two = -1;
      if (written >= 4 && one > kCoefBits + kWidthBits + 2l * written) two = two_layers();
      bits += (two >= 0 && two < one) ? two : one;
    }
    const std::uint64_t bytes = round_up(static_cast<std::uint64_t>((bits + 7) / 8), burst);
    return std::min(bytes, raw);
  }

 private:
  static std::uint64_t round_up(std::uint64_t v, std::uint64_t g) { return g ? (v + g - 1) / g * g : v; }

  // Bits of one layer with its best predictor (a plane, or a time-dependent plane).
  long best_layer(const FitSamples& s) {
    long b[2] = {-1, -1};
    if (moving_) fit_.fit(s, {3, 6}, b);
    else fit_.fit(s, {3}, b);
    long best = -1;
    for (const long v : b)
      if (v >= 0 && (best < 0 || v < best)) best = v;
    if (best < 0) fit_.fit(s, {1}, &best);  // too few distinct samples for a plane: a constant
    return best < 0 ? kCoefBits + kWidthBits + 32l * s.n : best;
  }

  // Two layers by 2-means on depth (two iterations from the extremes), each with its best
  // predictor, plus the layer mask; -1 when one layer stays empty. Integer arithmetic: the same
  // split on every path.
  long two_layers() {
    const int n = all_.n;
    const std::int32_t* z = all_.z.data();
    std::int32_t lo = z[0], hi = z[0];
    std::int64_t all = 0;
    for (int i = 0; i < n; ++i) lo = std::min(lo, z[i]), hi = std::max(hi, z[i]), all += z[i];
    if (lo == hi) return -1;
    std::int64_t c0x2 = 2ll * lo, c1x2 = 2ll * hi;  // twice the layer means, rounded down
    int n1 = 0;
    std::int32_t split2 = 0;
    for (int it = 0; it < 2; ++it) {
      split2 = static_cast<std::int32_t>(c0x2 + c1x2);  // a sample joins layer 1 when 4 z > 2 (c0 + c1)
      std::int64_t s1 = 0;
      n1 = 0;
      upper_sum(z, n, split2, n1, s1);
      if (n1 == 0 || n1 == n) return -1;
      c0x2 = (2 * (all - s1)) / (n - n1), c1x2 = (2 * s1) / n1;
    }
    split_layers(split2, n1);
    return best_layer(layers_[0]) + best_layer(layers_[1]) + n;
  }

  // The count and sum of the depths with 4 z > split2 (z < 2^24, so 4 z fits 32 bits).
  static void upper_sum(const std::int32_t* z, int n, std::int32_t split2, int& count, std::int64_t& sum) {
    int i = 0;
#if defined(__AVX512F__)
    const __m512i sp = _mm512_set1_epi32(split2);
    for (; i + 16 <= n; i += 16) {
      const __m512i v = _mm512_loadu_si512(z + i);
      const __mmask16 up = _mm512_cmpgt_epi32_mask(_mm512_slli_epi32(v, 2), sp);
      count += __builtin_popcount(up);
      sum += _mm512_mask_reduce_add_epi32(up, v);  // 16 values below 2^24: no overflow
    }
#endif
    for (; i < n; ++i)
      if (4 * z[i] > split2) ++count, sum += z[i];
  }

  // The two layers' samples, in order (layer 1: 4 z > split2).
  void split_layers(std::int32_t split2, int n1) {
    const int n = all_.n;
    FitSamples& a = layers_[0];
    FitSamples& b = layers_[1];
    a.resize(static_cast<std::size_t>(n - n1) + 16), b.resize(static_cast<std::size_t>(n1) + 16);
    a.n = n - n1, b.n = n1;
    const std::int32_t* src[4] = {all_.xq.data(), all_.yq.data(), all_.tq.data(), all_.z.data()};
    std::int32_t* da[4] = {a.xq.data(), a.yq.data(), a.tq.data(), a.z.data()};
    std::int32_t* db[4] = {b.xq.data(), b.yq.data(), b.tq.data(), b.z.data()};
    int ia = 0, ib = 0, i = 0;
#if defined(__AVX512F__)
    const __m512i sp = _mm512_set1_epi32(split2);
    for (; i + 16 <= n; i += 16) {
      const __mmask16 up = _mm512_cmpgt_epi32_mask(_mm512_slli_epi32(_mm512_loadu_si512(src[3] + i), 2), sp);
      // Each layer's lanes compressed in a register and stored whole (the layers have 16 entries of
      // slack): a masked compressing store to memory is microcoded on some processors.
      for (int f = 0; f < 4; ++f) {
        const __m512i v = _mm512_loadu_si512(src[f] + i);
        _mm512_storeu_si512(db[f] + ib, _mm512_maskz_compress_epi32(up, v));
        _mm512_storeu_si512(da[f] + ia, _mm512_maskz_compress_epi32(static_cast<__mmask16>(~up), v));
      }
      ib += __builtin_popcount(up), ia += 16 - __builtin_popcount(up);
    }
#endif
    for (; i < n; ++i) {
      const bool up = 4 * src[3][i] > split2;
      std::int32_t** d = up ? db : da;
      int& k = up ? ib : ia;
      for (int f = 0; f < 4; ++f) d[f][k] = src[f][i];
      ++k;
    }
  }

  FitSamples all_, layers_[2];
  bool moving_ = true;
  PredictorFit fit_;
};

}  // namespace rast5d::memory
