// Fast-path candidate selection of one pixel's samples against a tile's lens region (active lens
// cells and the h_i cuts): a vectorisable scan, then compaction. The counting path walks the
// cells' buckets instead and charges the same per-sample comparisons.
//
// Contract: select_candidates flags exactly the samples that the bucket walk over the active cells
// with axis_pass (halfspace_lens.h) selects, so both paths test the same samples.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#if defined(__AVX512F__) && defined(__AVX512BW__) && defined(__AVX512VL__) || defined(__AVX2__)
#include <immintrin.h>
#endif

#include "core/byte_spread.h"
#include "tiletest/halfspace_lens.h"

namespace rast5d::tiletest {

// Fast-path candidate selection for one pixel: flag[s] = sample s is in an active lens cell
// (bit cell[s] of active, G * G <= 64; kCells = false: every cell) and passes both axis sets.
// Returns how many samples lie in active cells (the samples whose (u, v) was compared).
template <bool kCells>
[[gnu::noinline]] inline int select_candidates(int spp, const float* __restrict u, const float* __restrict v,
                                                 const std::uint8_t* __restrict cell, std::uint64_t active,
                                                 const AxisSet& su, const AxisSet& sv,
                                                 std::uint8_t* __restrict flags) {
  const float a0 = su.fl_lo[0], b0 = su.fl_hi[0], a1 = su.fl_lo[1], b1 = su.fl_hi[1];
  const float c0 = sv.fl_lo[0], d0 = sv.fl_hi[0], c1 = sv.fl_lo[1], d1 = sv.fl_hi[1];
  int in_cells = 0;
  int s = 0;
#if defined(__AVX2__)
  // 8 samples at a time: the same ordered compares (NaN false), the cell bit as a variable shift of
  // the active mask's low or high half (a count past 31 shifts in zeros), the flags from the bit mask.
  {
    const __m256 A0 = _mm256_set1_ps(a0), B0 = _mm256_set1_ps(b0), A1 = _mm256_set1_ps(a1), B1 = _mm256_set1_ps(b1);
    const __m256 C0 = _mm256_set1_ps(c0), D0 = _mm256_set1_ps(d0), C1 = _mm256_set1_ps(c1), D1 = _mm256_set1_ps(d1);
    const __m256i lo = _mm256_set1_epi32(static_cast<int>(static_cast<std::uint32_t>(active)));
    const __m256i hi = _mm256_set1_epi32(static_cast<int>(static_cast<std::uint32_t>(active >> 32)));
    const __m256i k32 = _mm256_set1_epi32(32);
    auto inside = [](__m256 x, __m256 lo0, __m256 hi0, __m256 lo1, __m256 hi1) {
      return static_cast<unsigned>(_mm256_movemask_ps(_mm256_or_ps(
          _mm256_and_ps(_mm256_cmp_ps(x, lo0, _CMP_GT_OQ), _mm256_cmp_ps(x, hi0, _CMP_LT_OQ)),
          _mm256_and_ps(_mm256_cmp_ps(x, lo1, _CMP_GT_OQ), _mm256_cmp_ps(x, hi1, _CMP_LT_OQ)))));
    };
    for (; s + 8 <= spp; s += 8) {
      const unsigned in_u = inside(_mm256_loadu_ps(u + s), A0, B0, A1, B1);
      const unsigned in_v = inside(_mm256_loadu_ps(v + s), C0, D0, C1, D1);
      unsigned act = 0xffu;
      if constexpr (kCells) {
        std::uint64_t bytes;
        std::memcpy(&bytes, cell + s, 8);
        const __m256i c = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(static_cast<long long>(bytes)));
        const __m256i bit = _mm256_or_si256(_mm256_srlv_epi32(lo, c), _mm256_srlv_epi32(hi, _mm256_sub_epi32(c, k32)));
        act = static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_slli_epi32(bit, 31))));
      }
      in_cells += __builtin_popcount(act);
      store_spread(flags + s, act & ~in_u & ~in_v);
    }
  }
#endif
  for (; s < spp; ++s) {
    const float x = u[s], y = v[s];
    const int in_u = ((x > a0) & (x < b0)) | ((x > a1) & (x < b1));
    const int in_v = ((y > c0) & (y < d0)) | ((y > c1) & (y < d1));
    int act = 1;
    if constexpr (kCells) act = static_cast<int>((active >> cell[s]) & 1u);
    in_cells += act;
    flags[s] = static_cast<std::uint8_t>(act & (1 - in_u) & (1 - in_v));
  }
  return in_cells;
}

// One tile's selection bounds for SamplePipeline::push_selected (the fused fast path): the same
// active cells (bit c of active) and the same float cut bounds as select_candidates, set up once
// per tile.
struct SelectBounds {
  std::uint64_t active;
  float a0, b0, a1, b1;  // u cuts (AxisSet::fl_lo / fl_hi)
  float c0, d0, c1, d1;  // v cuts
  // Cut k of an axis can flag a sample only if lo < hi (else (x > lo) & (x < hi) is false for
  // every x, NaN included), so the others are skipped without changing a flag.
  bool u0, u1, v0, v1;

  void set(std::uint64_t active_cells, const AxisSet& su, const AxisSet& sv) {
    active = active_cells;
    a0 = su.fl_lo[0], b0 = su.fl_hi[0], a1 = su.fl_lo[1], b1 = su.fl_hi[1];
    c0 = sv.fl_lo[0], d0 = sv.fl_hi[0], c1 = sv.fl_lo[1], d1 = sv.fl_hi[1];
    u0 = a0 < b0, u1 = a1 < b1, v0 = c0 < d0, v1 = c1 < d1;
  }
  // Every sample of the cells in active_cells, no cuts.
  void set_cells(std::uint64_t active_cells) {
    active = active_cells;
    a0 = b0 = a1 = b1 = c0 = d0 = c1 = d1 = 0.0f;
    u0 = u1 = v0 = v1 = false;
  }
};

// Indices of the set flags, in order (skipping 8 zero flags at a time).
inline int compact_flags(const std::uint8_t* flags, int n, int* out) {
  int m = 0;
  for (int w = 0; w < n; w += 8) {
    std::uint64_t word = 0;
    std::memcpy(&word, flags + w, 8);
    if (!word) continue;
    const int end = std::min(n, w + 8);
    for (int i = w; i < end; ++i) {
      out[m] = i;
      m += flags[i];
    }
  }
  return m;
}

// A moving triangle's region of one pixel and one time sub-interval, in the bounds its fast path
// compares against (floats: the scalar loop's F(...) conversions).
struct MotionRegion {
  const std::uint8_t* cell_sel = nullptr;  // 1 for a listed lens cell (G * G entries, readable 3 past)
  bool cell_bits_on = false;               // G * G <= 64: the listed cells are also the bits of cell_bits
  std::uint64_t cell_bits = 0;
  int j0 = 0, j1 = -1;                     // the time strata of the sub-interval that its t̂ overlaps
  float t_lo = 0, t_hi = 0;                // t̂
  bool lens = false;                       // compare u, v against the axis sets
  const AxisSet* su = nullptr;
  const AxisSet* sv = nullptr;
  bool cu = false, cv = false;             // the clipped lens axes
  float u_lo = 0, u_hi = 0, v_lo = 0, v_hi = 0;
};

#if defined(__AVX512F__) && defined(__AVX512BW__) && defined(__AVX512VL__)
inline constexpr bool kMotionSelectVector = true;

// The lanes of m whose lens coordinate x passes one axis: outside both cuts of `cuts` (axis_pass's
// fast form) when `lens`, and inside [lo, hi] when the axis is clipped.
inline __mmask16 motion_axis_pass(__mmask16 m, __m512 x, bool lens, const AxisSet* cuts, bool clipped, float lo,
                                  float hi) {
  __mmask16 pass = m;
  if (lens) {
    const __mmask16 in0 = _mm512_cmp_ps_mask(x, _mm512_set1_ps(cuts->fl_lo[0]), _CMP_GT_OQ) &
                          _mm512_cmp_ps_mask(x, _mm512_set1_ps(cuts->fl_hi[0]), _CMP_LT_OQ);
    const __mmask16 in1 = _mm512_cmp_ps_mask(x, _mm512_set1_ps(cuts->fl_lo[1]), _CMP_GT_OQ) &
                          _mm512_cmp_ps_mask(x, _mm512_set1_ps(cuts->fl_hi[1]), _CMP_LT_OQ);
    pass &= static_cast<__mmask16>(~(in0 | in1));
  }
  if (clipped)
    pass &= _mm512_cmp_ps_mask(x, _mm512_set1_ps(lo), _CMP_GE_OQ) & _mm512_cmp_ps_mask(x, _mm512_set1_ps(hi), _CMP_LE_OQ);
  return pass;
}

// The entries [lo, hi) of a pixel's (cell, stratum) order (PixelSamples::ct_order, ct_cell,
// ct_stratum, and the samples' t, u, v in that order: ct_t, ct_u, ct_v) whose cell is listed and
// stratum in [j0, j1], 16 at a time: returns how many (the samples compared); appends the ones inside
// t̂, outside the lens cuts and inside the clipped axes to out[n..], in order, writing up to 16
// entries past the last (out needs that slack). The same float comparisons as the scalar loop of
// Tile::raster_motion, on the same floats.
inline int select_motion(const std::int32_t* __restrict order, const std::uint8_t* __restrict cell,
                         const std::uint8_t* __restrict stratum, const float* __restrict t,
                         const float* __restrict u, const float* __restrict v, int lo, int hi,
                         const MotionRegion& r, int* __restrict out, int& n) {
  int checked = 0;
  const __m512i vj0 = _mm512_set1_epi32(r.j0), vj1 = _mm512_set1_epi32(r.j1), byte = _mm512_set1_epi32(0xFF);
  const __m512 tlo = _mm512_set1_ps(r.t_lo), thi = _mm512_set1_ps(r.t_hi);
  // Up to 64 cells: cell c is listed when bit c of cell_bits is set (its 32-bit half shifted by c mod 32).
  const __m512i bits_lo = _mm512_set1_epi32(static_cast<int>(static_cast<std::uint32_t>(r.cell_bits)));
  const __m512i bits_hi = _mm512_set1_epi32(static_cast<int>(static_cast<std::uint32_t>(r.cell_bits >> 32)));
  const __m512i one = _mm512_set1_epi32(1), c31 = _mm512_set1_epi32(31);
  for (int idx = lo; idx < hi; idx += 16) {
    const int left = hi - idx;
    const __mmask16 m0 = left >= 16 ? __mmask16(0xFFFF) : static_cast<__mmask16>((1u << left) - 1u);
    const __m512i ce = _mm512_cvtepu8_epi32(_mm_maskz_loadu_epi8(m0, cell + idx));
    const __m512i st = _mm512_cvtepu8_epi32(_mm_maskz_loadu_epi8(m0, stratum + idx));
    __mmask16 m;
    if (r.cell_bits_on) {
      const __m512i half = _mm512_mask_blend_epi32(_mm512_cmpgt_epi32_mask(ce, c31), bits_lo, bits_hi);
      m = _mm512_mask_test_epi32_mask(m0, _mm512_srlv_epi32(half, _mm512_and_si512(ce, c31)), one);
    } else {
      const __m512i listed = _mm512_mask_i32gather_epi32(_mm512_setzero_si512(), m0, ce, r.cell_sel, 1);
      m = _mm512_mask_test_epi32_mask(m0, listed, byte);
    }
    m &= _mm512_cmpge_epi32_mask(st, vj0) & _mm512_cmple_epi32_mask(st, vj1);
    if (!m) continue;
    checked += __builtin_popcount(m);
    const __m512i smp = _mm512_maskz_loadu_epi32(m, order + idx);
    const __m512 tv = _mm512_maskz_loadu_ps(m, t + idx);
    __mmask16 pass = _mm512_mask_cmp_ps_mask(m, tv, tlo, _CMP_GE_OQ) & _mm512_cmp_ps_mask(tv, thi, _CMP_LE_OQ);
    if (r.lens || r.cu) pass &= motion_axis_pass(m, _mm512_maskz_loadu_ps(m, u + idx), r.lens, r.su, r.cu, r.u_lo, r.u_hi);
    if (r.lens || r.cv) pass &= motion_axis_pass(m, _mm512_maskz_loadu_ps(m, v + idx), r.lens, r.sv, r.cv, r.v_lo, r.v_hi);
    // Compressed in a register and stored whole (out has 16 entries of slack): a masked compressing
    // store to memory is microcoded on some processors, many times slower.
    _mm512_storeu_si512(out + n, _mm512_maskz_compress_epi32(pass, smp));
    n += __builtin_popcount(pass);
  }
  return checked;
}
#else
inline constexpr bool kMotionSelectVector = false;
// Defined where AVX-512 is compiled in; a caller tests kMotionSelectVector first (if constexpr), so
// without it the call is discarded and never made.
int select_motion(const std::int32_t* order, const std::uint8_t* cell, const std::uint8_t* stratum, const float* t,
                  const float* u, const float* v, int lo, int hi, const MotionRegion& r, int* out, int& n);
#endif

}  // namespace rast5d::tiletest
