// Explicit-SIMD batch sample tests: the 4D and 5D batch kernels of sampletest/kernels.h (batch_edges_4d /
// batch_edges_5d followed by batch_flags) fused into one pass over the batch, with AVX-512 or AVX2
// intrinsics where the compiler targets them and the scalar kernels otherwise. A batch's last n % 16
// (AVX-512 with VL) or n % 8 (AVX2) samples are one masked vector; without either, the scalar kernels.
//
// Why: the auto-vectorised path runs two loops (edge functions to memory, then the flags reading
// them back); the fused kernel keeps e_0..e_2 and det in registers for the flags and stores each
// value once. Contract: bit-identical to the scalar kernels. Every float operation is the same,
// in the same order (madd(a, b, c) is a multiply then an add, two roundings: no FMA, as
// -ffp-contract=off keeps the scalar path), and the comparisons are the same ordered, quiet
// compares (NaN compares false in both). tests/test_simd.py checks the equality on random and
// adversarial batches against the scalar kernels (sim._core.simd_selftest).
#pragma once

#include <cstdint>
#include <cstring>

#include "core/byte_spread.h"

#if defined(__AVX512F__) && defined(__AVX512BW__) || defined(__AVX2__)
#include <immintrin.h>
#endif

#include "sampletest/kernels.h"

namespace rast5d::simd {

// The instruction set this build's fused kernels use ("avx512", "avx2" or "scalar").
inline const char* isa() {
#if defined(__AVX512F__) && defined(__AVX512BW__)
  return "avx512";
#elif defined(__AVX2__)
  return "avx2";
#else
  return "scalar";
#endif
}

#if defined(__AVX512F__) && defined(__AVX512BW__)
using V = __m512;
constexpr int kW = 16;
inline V load(const float* p) { return _mm512_loadu_ps(p); }
inline void store(float* p, V v) { _mm512_storeu_ps(p, v); }
inline V set1(float a) { return _mm512_set1_ps(a); }
inline V mul(V a, V b) { return _mm512_mul_ps(a, b); }
inline V add(V a, V b) { return _mm512_add_ps(a, b); }
inline V sub(V a, V b) { return _mm512_sub_ps(a, b); }
inline V neg(V a) { return _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(a), _mm512_set1_epi32(INT32_MIN))); }
using M = __mmask16;
inline M gt0(V a) { return _mm512_cmp_ps_mask(a, _mm512_setzero_ps(), _CMP_GT_OQ); }
inline M lt0(V a) { return _mm512_cmp_ps_mask(a, _mm512_setzero_ps(), _CMP_LT_OQ); }
inline M eq0(V a) { return _mm512_cmp_ps_mask(a, _mm512_setzero_ps(), _CMP_EQ_OQ); }
// flags[i] = bit i of cov | (bit i of undecided) << 1, 16 bytes.
inline void store_flags(std::uint8_t* out, M cov, M und) {
  const __m128i one = _mm_set1_epi8(1), two = _mm_set1_epi8(2);
  const __m128i f = _mm_or_si128(_mm_maskz_mov_epi8(cov, one), _mm_maskz_mov_epi8(und, two));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(out), f);
}
#elif defined(__AVX2__)
using V = __m256;
constexpr int kW = 8;
inline V load(const float* p) { return _mm256_loadu_ps(p); }
inline void store(float* p, V v) { _mm256_storeu_ps(p, v); }
inline V set1(float a) { return _mm256_set1_ps(a); }
inline V mul(V a, V b) { return _mm256_mul_ps(a, b); }
inline V add(V a, V b) { return _mm256_add_ps(a, b); }
inline V sub(V a, V b) { return _mm256_sub_ps(a, b); }
inline V neg(V a) { return _mm256_xor_ps(a, _mm256_set1_ps(-0.0f)); }
using M = unsigned;
inline M gt0(V a) { return static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a, _mm256_setzero_ps(), _CMP_GT_OQ))); }
inline M lt0(V a) { return static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a, _mm256_setzero_ps(), _CMP_LT_OQ))); }
inline M eq0(V a) { return static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a, _mm256_setzero_ps(), _CMP_EQ_OQ))); }
// flags[i] = bit i of cov | (bit i of undecided) << 1, the first n (<= 8) bytes.
inline void store_flags(std::uint8_t* out, M cov, M und, std::size_t n = 8) {
  const std::uint64_t f = spread_bits(cov) | (spread_bits(und) << 1);
  std::memcpy(out, &f, n);
}
#endif

#if defined(__AVX512F__) && defined(__AVX512BW__) || defined(__AVX2__)
inline V vmadd(V a, V b, V c) { return add(mul(a, b), c); }

// edge_functions_s on vectors: the same operations in the same order.
inline void edges(V X0, V X1, V X2, V Y0, V Y1, V Y2, V W0, V W1, V W2, V sx, V sy, V& e0, V& e1, V& e2, V& det) {
  const V nsx = neg(sx), nsy = neg(sy);
  const V rx0 = vmadd(W0, nsx, X0), ry0 = vmadd(W0, nsy, Y0);
  const V rx1 = vmadd(W1, nsx, X1), ry1 = vmadd(W1, nsy, Y1);
  const V rx2 = vmadd(W2, nsx, X2), ry2 = vmadd(W2, nsy, Y2);
  e0 = sub(mul(rx1, ry2), mul(ry1, rx2));
  e1 = sub(mul(rx2, ry0), mul(ry2, rx0));
  e2 = sub(mul(rx0, ry1), mul(ry0, rx1));
  det = vmadd(W2, e2, vmadd(W1, e1, mul(W0, e0)));
}

// batch_flags on vectors: the covered and undecided lanes.
inline void flag_masks(V a, V b, V c, V d, bool bfc, M& cov, M& und) {
  const M dpos = gt0(d), dneg = lt0(d);
  const M allpos = gt0(a) & gt0(b) & gt0(c);
  const M allneg = lt0(a) & lt0(b) & lt0(c);
  const M anyzero = eq0(a) | eq0(b) | eq0(c);
  cov = static_cast<M>((bfc ? M(0) : static_cast<M>(dpos & allpos)) | (dneg & allneg));
  und = static_cast<M>(anyzero & (dpos | dneg));
}
inline void flags_of(V a, V b, V c, V d, bool bfc, std::uint8_t* out) {
  M cov, und;
  flag_masks(a, b, c, d, bfc, cov, und);
  store_flags(out, cov, und);
}
#endif

// The last n % kW samples of a batch as one masked vector (lanes k < n only are loaded and stored; the
// others load as 0 and are never stored): per lane the same operations as the full vectors, so the
// same bits as the scalar kernels. AVX-512 with VL; AVX2 (vmaskmovps). Small batches (a timing or
// memory model closes the batch at every shading visit) are mostly tail.
#if defined(__AVX512F__) && defined(__AVX512BW__) && defined(__AVX512VL__)
#define RAST5D_SIMD_TAIL 1
using K = __mmask16;
inline K tail_mask(int n) { return static_cast<__mmask16>((1u << n) - 1); }
inline V load_tail(K k, const float* p) { return _mm512_maskz_loadu_ps(k, p); }
inline void store_tail(K k, float* p, V v) { _mm512_mask_storeu_ps(p, k, v); }
inline void flags_tail(K k, int, V a, V b, V c, V d, bool bfc, std::uint8_t* out) {
  M cov, und;
  flag_masks(a, b, c, d, bfc, cov, und);
  const __m128i f = _mm_or_si128(_mm_maskz_mov_epi8(cov, _mm_set1_epi8(1)), _mm_maskz_mov_epi8(und, _mm_set1_epi8(2)));
  _mm_mask_storeu_epi8(out, k, f);
}
#elif defined(__AVX2__) && !(defined(__AVX512F__) && defined(__AVX512BW__))
#define RAST5D_SIMD_TAIL 1
using K = __m256i;
inline K tail_mask(int n) { return _mm256_cmpgt_epi32(_mm256_set1_epi32(n), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7)); }
inline V load_tail(K k, const float* p) { return _mm256_maskload_ps(p, k); }
inline void store_tail(K k, float* p, V v) { _mm256_maskstore_ps(p, k, v); }
inline void flags_tail(K, int n, V a, V b, V c, V d, bool bfc, std::uint8_t* out) {
  M cov, und;
  flag_masks(a, b, c, d, bfc, cov, und);
  store_flags(out, cov, und, static_cast<std::size_t>(n));  // lanes k < n only
}
#endif

// 4D (static, defocused): e, det and flags of n samples; the tail (n mod the vector width) is one
// masked vector (RAST5D_SIMD_TAIL), and builds without AVX2 use the scalar kernels.
inline void batch_test_4d(int n, const BatchTri& T, const float* __restrict bx, const float* __restrict by,
                          const float* __restrict bu, const float* __restrict bv, float* __restrict e0,
                          float* __restrict e1, float* __restrict e2, float* __restrict dt, bool bfc,
                          std::uint8_t* __restrict flags) {
  int i = 0;
#if defined(__AVX512F__) && defined(__AVX512BW__) || defined(__AVX2__)
  const V X0 = set1(T.X0), X1 = set1(T.X1), X2 = set1(T.X2), Y0 = set1(T.Y0), Y1 = set1(T.Y1), Y2 = set1(T.Y2);
  const V W0 = set1(T.W0), W1 = set1(T.W1), W2 = set1(T.W2);
  const V cx0 = set1(T.cx0), cx1 = set1(T.cx1), cx2 = set1(T.cx2), cy0 = set1(T.cy0), cy1 = set1(T.cy1),
          cy2 = set1(T.cy2);
  // one vector of samples at lens (u, v) and pixel (x, y): e0..e2 and det (full vectors and the masked tail)
  auto lanes = [&](V u, V v, V x, V y, V& a, V& b, V& c, V& d) {
    edges(vmadd(u, cx0, X0), vmadd(u, cx1, X1), vmadd(u, cx2, X2), vmadd(v, cy0, Y0), vmadd(v, cy1, Y1),
          vmadd(v, cy2, Y2), W0, W1, W2, x, y, a, b, c, d);
  };
  for (; i + kW <= n; i += kW) {
    V a, b, c, d;
    lanes(load(bu + i), load(bv + i), load(bx + i), load(by + i), a, b, c, d);
    store(e0 + i, a), store(e1 + i, b), store(e2 + i, c), store(dt + i, d);
    flags_of(a, b, c, d, bfc, flags + i);
  }
#endif
#ifdef RAST5D_SIMD_TAIL
  if (i < n) {
    const K k = tail_mask(n - i);
    V a, b, c, d;
    lanes(load_tail(k, bu + i), load_tail(k, bv + i), load_tail(k, bx + i), load_tail(k, by + i), a, b, c, d);
    store_tail(k, e0 + i, a), store_tail(k, e1 + i, b), store_tail(k, e2 + i, c), store_tail(k, dt + i, d);
    flags_tail(k, n - i, a, b, c, d, bfc, flags + i);
    return;
  }
#endif
  if (i < n) {
    batch_edges_4d(n - i, T, bx + i, by + i, bu + i, bv + i, e0 + i, e1 + i, e2 + i, dt + i);
    batch_flags(n - i, e0 + i, e1 + i, e2 + i, dt + i, bfc, flags + i);
  }
}

// 5D (moving, defocused): as batch_test_4d with the time lerp and the moving shear.
inline void batch_test_5d(int n, const BatchTri& T, const float* __restrict bx, const float* __restrict by,
                          const float* __restrict bu, const float* __restrict bv, const float* __restrict bt,
                          float* __restrict e0, float* __restrict e1, float* __restrict e2, float* __restrict dt,
                          bool bfc, std::uint8_t* __restrict flags) {
  int i = 0;
#if defined(__AVX512F__) && defined(__AVX512BW__) || defined(__AVX2__)
  const V X0 = set1(T.X0), X1 = set1(T.X1), X2 = set1(T.X2), Y0 = set1(T.Y0), Y1 = set1(T.Y1), Y2 = set1(T.Y2);
  const V W0 = set1(T.W0), W1 = set1(T.W1), W2 = set1(T.W2);
  const V dX0 = set1(T.dX0), dX1 = set1(T.dX1), dX2 = set1(T.dX2), dY0 = set1(T.dY0), dY1 = set1(T.dY1),
          dY2 = set1(T.dY2);
  const V dW0 = set1(T.dW0), dW1 = set1(T.dW1), dW2 = set1(T.dW2);
  const V kx = set1(T.kx), nkx = set1(T.nkx), ky = set1(T.ky), nky = set1(T.nky);
  // one vector of samples at time t, lens (u, v) and pixel (x, y): e0..e2 and det (full vectors and the
  // masked tail)
  auto lanes = [&](V t, V u, V v, V x, V y, V& a, V& b, V& c, V& d) {
    const V xt0 = vmadd(t, dX0, X0), yt0 = vmadd(t, dY0, Y0), wt0 = vmadd(t, dW0, W0);
    const V xt1 = vmadd(t, dX1, X1), yt1 = vmadd(t, dY1, Y1), wt1 = vmadd(t, dW1, W1);
    const V xt2 = vmadd(t, dX2, X2), yt2 = vmadd(t, dY2, Y2), wt2 = vmadd(t, dW2, W2);
    edges(vmadd(u, vmadd(wt0, kx, nkx), xt0), vmadd(u, vmadd(wt1, kx, nkx), xt1), vmadd(u, vmadd(wt2, kx, nkx), xt2),
          vmadd(v, vmadd(wt0, ky, nky), yt0), vmadd(v, vmadd(wt1, ky, nky), yt1), vmadd(v, vmadd(wt2, ky, nky), yt2),
          wt0, wt1, wt2, x, y, a, b, c, d);
  };
  for (; i + kW <= n; i += kW) {
    V a, b, c, d;
    lanes(load(bt + i), load(bu + i), load(bv + i), load(bx + i), load(by + i), a, b, c, d);
    store(e0 + i, a), store(e1 + i, b), store(e2 + i, c), store(dt + i, d);
    flags_of(a, b, c, d, bfc, flags + i);
  }
#endif
#ifdef RAST5D_SIMD_TAIL
  if (i < n) {
    const K k = tail_mask(n - i);
    V a, b, c, d;
    lanes(load_tail(k, bt + i), load_tail(k, bu + i), load_tail(k, bv + i), load_tail(k, bx + i),
          load_tail(k, by + i), a, b, c, d);
    store_tail(k, e0 + i, a), store_tail(k, e1 + i, b), store_tail(k, e2 + i, c), store_tail(k, dt + i, d);
    flags_tail(k, n - i, a, b, c, d, bfc, flags + i);
    return;
  }
#endif
  if (i < n) {
    batch_edges_5d(n - i, T, bx + i, by + i, bu + i, bv + i, bt + i, e0 + i, e1 + i, e2 + i, dt + i);
    batch_flags(n - i, e0 + i, e1 + i, e2 + i, dt + i, bfc, flags + i);
  }
}

}  // namespace rast5d::simd
