// The per-sample backend of the sample pipeline (traversal/sample_pipeline.h): a covered sample
// is rejected by the user clip box (intervals/clip.h), gets its depth (near plane), survives the
// alpha mask of a transparent triangle (backend/alpha.h), runs the depth
// test against the bin's depth buffer (backend/bin_buffers.h), and on a pass writes depth, colour
// and triangle index, textures the colour (backend/texture.h) and joins the open shading visit
// (backend/shading.h). Counters: depth.*, raster.samples_covered / _hit / _near_rejected,
// alpha.*, interval.samples_clipped, occlusion.samples_passed, ops.interp.
//
// Contract: the image depends only on the triangle and the sample (never on the algorithm, the
// shading mode or the arithmetic path); depth-read skipping (zmin-culling) changes counters only.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#if defined(__AVX512F__) && defined(__AVX512BW__)
#include <immintrin.h>
#endif

#include "backend/alpha.h"
#include "backend/bin_buffers.h"
#include "backend/shading.h"
#include "core/arith.h"
#include "core/costs.h"
#include "core/counters.h"
#include "core/sample_table.h"
#include "intervals/clip.h"
#include "sampletest/kernels.h"
#include "core/triangle.h"

namespace rast5d {

#if defined(__AVX512F__) && defined(__AVX512BW__)
// Permutations interleaving three 16-lane vectors r, g, b into 48 floats r0 g0 b0 r1 ... (the colour
// buffer's layout): output vector k takes element j (global 16 k + j = 3 lane + ch) from r or g
// (v[k][0]: lane, or 16 + lane), then keeps it or takes b (v[k][1]: j, or 16 + lane).
struct InterleaveRGB {
  alignas(64) std::int32_t v[3][2][16];
  constexpr InterleaveRGB() : v{} {
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 16; ++j) {
        const int g = 16 * k + j, lane = g / 3, ch = g % 3;
        v[k][0][j] = ch == 1 ? 16 + lane : lane;
        v[k][1][j] = ch == 2 ? 16 + lane : j;
      }
  }
};
inline constexpr InterleaveRGB kInterleave{};
#endif

template <class A>
class SampleBackend {
 public:
  SampleBackend(const Frame& f, Counters& c, BinBuffers& buf, ShadeState& sh)
      : f_(f), c_(c), buf_(buf), sh_(sh),
        depth_step_(f.p.precision_depth.kind == PrecisionKind::kFixed ? std::ldexp(1.0, -f.p.precision_depth.frac_bits)
                                                                      : 0.0) {}

  // skip_depth_reads: the pair is entirely in front of HiZ zmin (the depth test's result is the
  // same); query: occlusion-query triangle, depth test only.
  void set_depth_mode(bool skip_depth_reads, bool query) {
    skip_depth_reads_ = skip_depth_reads;
    query_ = query;
  }

  // A covered sample: clip box, depth, near plane, depth test, colour, texturing, shading visit.
  // Cost: ops.interp (cost::kDepth, cost::kDepthTest, cost::kColor).
  template <class G>
  inline void covered(const TriSetup& tri, const G e[3], G det, int px, int py, int s) {
    if (clip_active_ && !clip_pass(px, py, s)) {  // user clip box: never a hit
      ++c_[Counter::interval_samples_clipped];
      return;
    }
    ++c_[Counter::raster_samples_covered];
    std::uint64_t& iops = c_[Counter::ops_interp];
    G sum, z;
    const bool in_front = hit_depth(e, det, G(f_.fc.neg_near), sum, z);
    charge<A>(iops, cost::kDepth);
    if (!in_front) {
      ++c_[Counter::raster_samples_near_rejected];
      return;
    }
    ++c_[Counter::raster_samples_hit];
    if (depth_step_ > 0.0) z = G(quantize_depth(raw(z)));  // pipeline.precision.depth: fixed
    if (tri.alpha < 1.0f) {  // stochastic transparency: the sample survives with probability alpha
      ++c_[Counter::alpha_samples_tested];
      if (!alpha_keeps(tri.alpha, px, py, s, f_.table.spp(), f_.p.alpha_stratified, tri.index, alpha_seed_)) {
        ++c_[Counter::alpha_samples_discarded];
        return;
      }
    }
    ++c_[Counter::depth_tests];
    if (skip_depth_reads_) ++c_[Counter::depth_reads_skipped];
    else c_[Counter::depth_bytes_read] += 4;
    memory::LineMarks* const marks = buf_.line_marks();  // the memory model's tile caches, when it runs
    const std::uint32_t line = marks ? marks->mark(px, py, s) : 0;
    const std::size_t slot = buf_.slot(px, py, s);
    float& zbuf = buf_.depth(slot);
    const bool pass = z < G(zbuf);
    charge<A>(iops, cost::kDepthTest);
    if (!pass) return;
    if (query_) {  // occlusion query: count, write nothing
      ++c_[Counter::occlusion_samples_passed];
      return;
    }
    ++c_[Counter::depth_passes];
    c_[Counter::depth_bytes_written] += 4;
    if (marks) marks->add(line, memory::kDepthWrite | memory::kColorWrite);
    G c0[3], c1[3], c2[3], out[3];
    for (int ch = 0; ch < 3; ++ch)
      c0[ch] = G(tri.color[0][ch]), c1[ch] = G(tri.color[1][ch]), c2[ch] = G(tri.color[2][ch]);
    hit_color(e, sum, c0, c1, c2, out);
    charge<A>(iops, cost::kColor);
    zbuf = raw(z);
    buf_.set_triangle(slot, static_cast<std::int32_t>(tri.index));
    float* dst = buf_.color(slot);
    for (int ch = 0; ch < 3; ++ch) dst[ch] = raw(out[ch]);
    if (const ShadeFrame* sf = sh_.frame(); sf && (sh_.counting() || sf->texture_count > 0))
      shade_record(*sf, tri, raw(e[0]), raw(e[1]), raw(e[2]), raw(sum), px, py, s, dst);
  }

#if defined(__AVX512F__) && defined(__AVX512BW__)
  // Whether covered_lanes() may stand for covered() on tri's samples: no clip box, float depth, an
  // opaque triangle, no occlusion query, and no shading record or texturing (whose order the sample
  // walk decides). Slots index the colour buffer in 32-bit lanes.
  bool lanes_ready(const TriSetup& tri) const {
    if constexpr (A::counting) {
      return false;
    } else {
      const ShadeFrame* sf = sh_.frame();
      return !clip_active_ && depth_step_ == 0.0 && !(tri.alpha < 1.0f) && !query_ &&
             !(sf && (sh_.counting() || sf->texture_count > 0)) && buf_.slots() < (std::size_t(1) << 29);
    }
  }

  // covered() of the covered samples in lanes m, 16 at a time: edge functions e0, e1, e2 and det,
  // pixel (px, py) and sample s per lane. The same float operations per lane as covered() (hit_depth,
  // the depth test, hit_color) and the same counters. The lanes' slots are distinct (a batch holds
  // each sample of its triangle once), so the lanes' depth tests do not depend on each other; the
  // memory model's line marks are made in lane order.
  void covered_lanes(const TriSetup& tri, __mmask16 m, __m512 e0, __m512 e1, __m512 e2, __m512 det, __m512i px,
                     __m512i py, __m512i s) {
    const int n_cov = __builtin_popcount(m);
    c_[Counter::raster_samples_covered] += static_cast<std::uint64_t>(n_cov);
    std::uint64_t& iops = c_[Counter::ops_interp];
    const __m512 sum = _mm512_add_ps(_mm512_add_ps(e0, e1), e2);
    const __m512 one = _mm512_set1_ps(1.0f);
    const __m512 inv_w = _mm512_mul_ps(sum, _mm512_div_ps(one, det));
    const __m512 z = _mm512_add_ps(_mm512_mul_ps(_mm512_set1_ps(f_.fc.neg_near), inv_w), one);
    iops += cost::kDepth * static_cast<std::uint64_t>(n_cov);
    const __mmask16 front = _mm512_mask_cmp_ps_mask(m, z, _mm512_setzero_ps(), _CMP_GE_OQ);
    const int n_hit = __builtin_popcount(front);
    c_[Counter::raster_samples_near_rejected] += static_cast<std::uint64_t>(n_cov - n_hit);
    if (!front) return;
    c_[Counter::raster_samples_hit] += static_cast<std::uint64_t>(n_hit);
    c_[Counter::depth_tests] += static_cast<std::uint64_t>(n_hit);
    if (skip_depth_reads_) c_[Counter::depth_reads_skipped] += static_cast<std::uint64_t>(n_hit);
    else c_[Counter::depth_bytes_read] += 4 * static_cast<std::uint64_t>(n_hit);
    const BinRect& r = buf_.rect();
    const __m512i pixel = _mm512_add_epi32(
        _mm512_mullo_epi32(_mm512_sub_epi32(py, _mm512_set1_epi32(r.y0)), _mm512_set1_epi32(buf_.row_pixels())),
        _mm512_sub_epi32(px, _mm512_set1_epi32(r.x0)));
    const __m512i slot = _mm512_add_epi32(_mm512_mullo_epi32(pixel, _mm512_set1_epi32(buf_.spp())), s);
    float* depth = buf_.depth_data();
    // The lanes' slots are consecutive (a pixel's samples in order, the common case): plain masked
    // loads and stores instead of gathers and scatters.
    const int i0 = __builtin_ctz(m);
    const int base = _mm_cvtsi128_si32(_mm512_castsi512_si128(_mm512_permutexvar_epi32(_mm512_set1_epi32(i0), slot))) - i0;
    const __m512i iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    const bool runs = base >= 0 && _mm512_mask_cmpneq_epi32_mask(m, slot, _mm512_add_epi32(_mm512_set1_epi32(base), iota)) == 0;
    const __m512 zbuf = runs ? _mm512_maskz_loadu_ps(front, depth + base)
                             : _mm512_mask_i32gather_ps(_mm512_setzero_ps(), front, slot, depth, 4);
    const __mmask16 pass = _mm512_mask_cmp_ps_mask(front, z, zbuf, _CMP_LT_OQ);
    iops += cost::kDepthTest * static_cast<std::uint64_t>(n_hit);
    if (memory::LineMarks* const marks = buf_.line_marks()) {
      alignas(64) int lx[16], ly[16], ls[16];
      _mm512_store_si512(lx, px), _mm512_store_si512(ly, py), _mm512_store_si512(ls, s);
      for (unsigned k = front; k; k &= k - 1) {
        const int i = __builtin_ctz(k);
        const std::uint32_t line = marks->mark(lx[i], ly[i], ls[i]);
        if ((pass >> i) & 1) marks->add(line, memory::kDepthWrite | memory::kColorWrite);
      }
    }
    if (!pass) return;
    const std::uint64_t n_pass = static_cast<std::uint64_t>(__builtin_popcount(pass));
    c_[Counter::depth_passes] += n_pass;
    c_[Counter::depth_bytes_written] += 4 * n_pass;
    const __m512 inv = _mm512_div_ps(one, sum);
    const __m512 b0 = _mm512_mul_ps(e0, inv), b1 = _mm512_mul_ps(e1, inv), b2 = _mm512_mul_ps(e2, inv);
    iops += cost::kColor * n_pass;
    __m512 rgb[3];
    for (int ch = 0; ch < 3; ++ch) {
      const __m512 lo = _mm512_add_ps(_mm512_mul_ps(b1, _mm512_set1_ps(tri.color[1][ch])),
                                      _mm512_mul_ps(b0, _mm512_set1_ps(tri.color[0][ch])));
      rgb[ch] = _mm512_add_ps(_mm512_mul_ps(b2, _mm512_set1_ps(tri.color[2][ch])), lo);
    }
    const __m512i index = _mm512_set1_epi32(static_cast<std::int32_t>(tri.index));
    float* color = buf_.color_data();
    if (runs) {
      _mm512_mask_storeu_ps(depth + base, pass, z);
      _mm512_mask_storeu_epi32(buf_.triangle_data() + base, pass, index);
      // The 16 lanes' (r, g, b) interleaved into 48 floats, each lane's mask bit repeated 3 times.
#if defined(__BMI2__)
      const std::uint64_t m3 = _pdep_u64(pass, 0x249249249249ull) * 7;
#else
      std::uint64_t m3 = 0;
      for (int i = 0; i < 16; ++i) m3 |= static_cast<std::uint64_t>((pass >> i) & 1) * 7 << (3 * i);
#endif
      float* dst = color + 3 * static_cast<std::size_t>(base);
      for (int k = 0; k < 3; ++k) {
        const __m512i rg = _mm512_load_si512(kInterleave.v[k][0]), b = _mm512_load_si512(kInterleave.v[k][1]);
        const __m512 v = _mm512_permutex2var_ps(_mm512_permutex2var_ps(rgb[0], rg, rgb[1]), b, rgb[2]);
        _mm512_mask_storeu_ps(dst + 16 * k, static_cast<__mmask16>(m3 >> (16 * k)), v);
      }
      return;
    }
    _mm512_mask_i32scatter_ps(depth, pass, slot, z, 4);
    _mm512_mask_i32scatter_epi32(buf_.triangle_data(), pass, slot, index, 4);
    const __m512i slot3 = _mm512_mullo_epi32(slot, _mm512_set1_epi32(3));
    for (int ch = 0; ch < 3; ++ch) _mm512_mask_i32scatter_ps(color + ch, pass, slot3, rgb[ch], 4);
  }

#endif

 private:
  // The stored depth in a fixed-point depth buffer (pipeline.precision.depth; docs/precision.md): z in
  // [0, 1] rounded to the nearest multiple of 2^-frac_bits (frac_bits <= 24: exact in float32).
  float quantize_depth(float z) const {
    return static_cast<float>(std::nearbyint(static_cast<double>(z) / depth_step_) * depth_step_);
  }

  // Texture the sample's colour (a function of triangle and sample only: the image stays the same
  // for every algorithm and shading mode) and hand the sample to the open shading visit.
  void shade_record(const ShadeFrame& sf, const TriSetup& tri, float e0, float e1, float e2, float sum, int px, int py,
                    int s, float* dst) {
    ShadeState::Rec r{px, py, s, 0, 0.0f, 0.0f, 0.0f, 0.0f};
    const float inv = 1.0f / sum;
    const float b0 = e0 * inv, b1 = e1 * inv, b2 = e2 * inv;
    if (sf.mode == ShadingMode::kPerLensCell) r.cell = f_.table.pixel(px, py).cell[s];
    if (sf.mode == ShadingMode::kCache) {  // the hit point seen through the lens centre at shutter open
      const float X = b0 * tri.X[0] + b1 * tri.X[1] + b2 * tri.X[2];
      const float Y = b0 * tri.Y[0] + b1 * tri.Y[1] + b2 * tri.Y[2];
      const float W = b0 * tri.W[0] + b1 * tri.W[1] + b2 * tri.W[2];
      r.gx = X / W, r.gy = Y / W;
    }
    if (sf.texture_count > 0) {
      const float* uv = &sf.uvs[static_cast<std::size_t>(tri.index) * 6];
      r.u = b0 * uv[0] + b1 * uv[2] + b2 * uv[4];
      r.v = b0 * uv[1] + b1 * uv[3] + b2 * uv[5];
      for (int k = 0; k < sf.texture_count; ++k) {
        const int id = sf.tex_ids[static_cast<std::size_t>(tri.index) * kMaxTexSlots + k];
        if (id < 0) continue;
        float t[3];
        sf.textures.sample(id, sf.lod[static_cast<std::size_t>(tri.index) * kMaxTexSlots + k], sf.filter, r.u, r.v, t);
        for (int ch = 0; ch < 3; ++ch) dst[ch] *= t[ch];
      }
    }
    if (sh_.counting()) sh_.record(tri.index, r);
  }

  bool clip_pass(int px, int py, int s) const {
    const PixelSamples ps = f_.table.pixel(px, py);
    return iv::in_clip(clip_, ps.u[s], ps.v[s], ps.t[s]);
  }

  const Frame& f_;
  Counters& c_;
  BinBuffers& buf_;
  ShadeState& sh_;
  const double depth_step_;  // pipeline.precision.depth: fixed: 2^-frac_bits, else 0
  const iv::ClipBox clip_ = iv::clip_box(f_.p);
  const bool clip_active_ = clip_.active();
  const std::uint32_t alpha_seed_ = static_cast<std::uint32_t>(f_.p.alpha_seed);
  bool skip_depth_reads_ = false, query_ = false;
};

}  // namespace rast5d
