// The sample pipeline: the exact sample test and the backend, shared by every traversal algorithm
// (traversal.h). An algorithm hands it candidate samples; it runs the inside test of the triangle's
// class (sampletest/) and hands covered samples to the backend (backend/sample_backend.h: clip
// box, depth, depth test, colour, texturing, shading visit). Counters: raster.*,
// ops.sample_inside.
//
// Contract: for one triangle the pipeline's results and counters depend only on the set of
// samples pushed, not on how they are batched (test(), push(), push_pixel(), push_pixel_masked())
// or on the arithmetic path: the fast path's vectorised kernels perform exactly the float
// operations of the scalar kernels and charge the documented costs (core/costs.h) that the
// counting path tallies.
#pragma once

#include <algorithm>
#include <cstring>
#include <vector>

#include "backend/bin_buffers.h"
#include "backend/sample_backend.h"
#include "backend/shading.h"
#include "core/arith.h"
#include "core/costs.h"
#include "core/counters.h"
#include "core/params.h"
#include "core/pixel_stats.h"
#include "core/sample_table.h"
#include "sampletest/hardware.h"
#include "sampletest/inside.h"
#include "sampletest/precision.h"
#include "sampletest/kernels.h"
#include "sampletest/simd_batch.h"
#include "setup/setup.h"
#include "tiletest/candidates.h"
#include "timing/timing.h"

namespace rast5d {

// Per worker thread: counters, the screen bin's buffers, the shading state, and the observers of its
// traversal (the memory model, the timing recorder, per-pixel statistics: core/visit_observer.h).
struct ThreadState {
  Counters counters;
  BinBuffers buffers;
  ShadeState shade;  // the open shading visit, shading cache, texture stream (backend/shading.h)
  Observers observers;
};

// Two ways in: test() / test_sheared() for one sample, or the batch protocol
//   begin(tri) | begin_sheared(tri, Xs, Ys, stride);  push(px, py, ps, s)... | push_pixel(...);  flush()
// A batch holds candidate samples of one triangle (any pixels; each sample at most once). On the
// fast path the batch is evaluated by vectorised straight-line kernels performing exactly the
// float operations of the scalar kernels (bit-identical results, same counts); on the counting
// path push() tests immediately with the counting scalar type. begin() flushes a pending batch.
template <class A>
class SamplePipeline {
 public:
  using F = typename A::f32;

  SamplePipeline(const Frame& f, ThreadState& ts)
      : f_(f), c_(ts.counters), sh_(ts.shade), ts_(ts), backend_(f, ts.counters, ts.buffers, ts.shade), cap_(std::max(kBatch, f.table.spp())),
        model_(f.p.cost_model),
        precise_(f.p.precision_sample.kind != PrecisionKind::kFloat32),
        obs_(ts.observers), visits_(ts.observers.wants_visits()), targets_(ts.observers.wants_targets()) {
    // Two regions: the batch at 0 and, from pixel_at(), one pixel evaluated while a batch is pending
    // (run_pixel() when the test order is free).
    const std::size_t len = 2 * static_cast<std::size_t>(pixel_at());
    for (auto* v : {&gx_, &gy_, &gu_, &gv_, &gt_, &bdet_}) v->resize(len);
    for (auto* v : {&bpx_, &bpy_, &bs_, &bl_}) v->resize(len);
    sel_index_.resize(cap_);
    be_.resize(3 * len);
    flags_.assign(len + 64, 0);
  }

  // Test canonical sample s of pixel (px, py) against tri with the kernel of tri's class.
  inline void test(const TriSetup& tri, int px, int py, const PixelSamples& ps, int s) {
    cur_ps_ = &ps;
    test_values(tri, F(static_cast<float>(px) + ps.x[s]), F(static_cast<float>(py) + ps.y[s]), F(ps.u[s]),
                F(ps.v[s]), F(ps.t[s]), px, py, s);
  }

  // Test with static vertices already sheared to the sample's (discrete) lens coordinate: the 2D
  // kernel. Xs = madd(u_i, cx, X) computed with the same float operations as the 4D kernel, so the
  // result is bit-identical to test().
  inline void test_sheared(const TriSetup& tri, const float Xs[3], const float Ys[3], int px, int py,
                           const PixelSamples& ps, int s) {
    cur_ps_ = &ps;
    test_sheared_values(tri, Xs, Ys, F(static_cast<float>(px) + ps.x[s]), F(static_cast<float>(py) + ps.y[s]),
                        px, py, s);
  }

  // Per-pixel statistics (core/pixel_stats.h): the work from here on is done for pixel (px, py), or
  // for the pixels [x0, x1) x [y0, y1) (a tile). Without an observer of targets: one flag test.
  inline void at_pixel(int px, int py) {
    if (targets_) [[unlikely]] retarget(px, py, px + 1, py + 1, 2);
  }
  inline void at_rect(int x0, int y0, int x1, int y1) {
    if (targets_) [[unlikely]] retarget(x0, y0, x1, y1, 1);
  }

  // ---- batch protocol ----
  inline void begin(const TriSetup& tri) {
    flush();
    tri_ = &tri;
    sheared_ = false;
    stride_ = 0;
    free_order_ = order_free();
    need_t_ = tri.cls == DimClass::k3D || tri.cls == DimClass::k5D;
  }
  // Static triangle pre-sheared to discrete lens coordinates: lens_stride 0 = every sample uses
  // Xs/Ys; 3 = sample s uses Xs + 3 * lens_index[s] (interleaved tables).
  inline void begin_sheared(const TriSetup& tri, const float* Xs, const float* Ys, int lens_stride) {
    flush();
    tri_ = &tri;
    sheared_ = true;
    xs_ = Xs, ys_ = Ys, stride_ = lens_stride;
    free_order_ = order_free();
    need_t_ = false;
  }
  inline void push(int px, int py, const PixelSamples& ps, int s) {
    if (one_at_a_time()) {
      if (!sheared_) {
        test(*tri_, px, py, ps, s);
      } else {
        const int off = stride_ ? stride_ * ps.lens_index[s] : 0;
        test_sheared(*tri_, xs_ + off, ys_ + off, px, py, ps, s);
      }
    } else {
      if (n_ == cap_) flush();
      const int i = n_++;
      gx_[i] = static_cast<float>(px) + ps.x[s];
      gy_[i] = static_cast<float>(py) + ps.y[s];
      gu_[i] = ps.u[s], gv_[i] = ps.v[s], gt_[i] = ps.t[s];
      bpx_[i] = px, bpy_[i] = py, bs_[i] = s;
      if (stride_) bl_[i] = ps.lens_index[s];
    }
  }
  // push() of sample s of pixel (px, py) whose in-pixel position (ps.x[s], ps.y[s]) is (x, y): the
  // same float operations. A static triangle sheared to one lens coordinate (begin_sheared() with
  // lens stride 0) reads no other sample field; anything else goes through push().
  inline void push_xy(int px, int py, float x, float y, int s) {
    if (one_at_a_time() || !sheared_ || stride_) {
      push(px, py, f_.table.pixel(px, py), s);
      return;
    }
    if (n_ == cap_) flush();
    const int i = n_++;
    gx_[i] = static_cast<float>(px) + x;
    gy_[i] = static_cast<float>(py) + y;
    bpx_[i] = px, bpy_[i] = py, bs_[i] = s;
  }
  // Samples idx[0..n) of pixel (px, py), in order: push() of each, with the batch bookkeeping
  // once per list on the fast path.
  inline void push_list(int px, int py, const PixelSamples& ps, const std::int32_t* idx, int n) {
    if (one_at_a_time() || sheared_ || n > cap_) {
      push_each(px, py, ps, n, [idx](int i) { return idx[i]; });
      return;
    }
    if (n_ + n > cap_) flush();
    const int i0 = n_;
    float* __restrict gx = gx_.data() + i0;
    float* __restrict gy = gy_.data() + i0;
    float* __restrict gu = gu_.data() + i0;
    float* __restrict gv = gv_.data() + i0;
    float* __restrict gt = gt_.data() + i0;
    int* __restrict bpx = bpx_.data() + i0;
    int* __restrict bpy = bpy_.data() + i0;
    int* __restrict bs = bs_.data() + i0;
    const float fx = static_cast<float>(px), fy = static_cast<float>(py);
    for (int i = 0; i < n; ++i) {
      const int s = idx[i];
      gx[i] = fx + ps.x[s], gy[i] = fy + ps.y[s];
      gu[i] = ps.u[s], gv[i] = ps.v[s], gt[i] = ps.t[s];
      bpx[i] = px, bpy[i] = py, bs[i] = s;
    }
    n_ = i0 + n;
  }
  // Every sample of pixel (px, py).
  [[gnu::always_inline]] inline void push_pixel(int px, int py, const PixelSamples& ps) {
    at_pixel(px, py);
    const int spp = f_.table.spp();
    if (one_at_a_time()) {
      push_each(px, py, ps, spp, [](int s) { return s; });
    } else if constexpr (!A::counting) {
      if (spp >= 32) run_pixel(px, py, ps, nullptr, spp);  // large enough to be its own batch
      else append_pixel(px, py, ps, spp);
    }
  }
  // The samples s of pixel (px, py) with sel[s] != 0 (n_sel of them). With enough samples per
  // pixel the fast path evaluates the kernel for the whole pixel in one vectorised pass and keeps
  // the selected lanes (predication, as SIMD hardware would); only the selected samples are tested,
  // counted and shaded, so the results and counts equal pushing them one by one.
  // idx[0..n_sel) lists the selected samples.
  inline void push_pixel_masked(int px, int py, const PixelSamples& ps, const std::uint8_t* sel, const int* idx,
                                int n_sel) {
    at_pixel(px, py);
    if constexpr (!A::counting) {
      const int spp = f_.table.spp();
      if (!one_at_a_time() && spp >= 32 && 3 * n_sel >= spp) {
        run_pixel(px, py, ps, sel, n_sel);
        return;
      }
    }
    push_each(px, py, ps, n_sel, [idx](int i) { return idx[i]; });
  }

  // Fast path: the samples s of pixel (px, py) with sel[s] != 0, where sel holds spp flags followed
  // by zeros up to a multiple of 16 (flags_padding()). Same results and counts as
  // push_pixel_masked(): many selected samples go through run_pixel() with the mask; few are
  // appended to the batch by SIMD compression (no per-sample branch or index list).
  inline void push_flagged(int px, int py, const PixelSamples& ps, const std::uint8_t* sel) {
    static_assert(!A::counting, "push_flagged is the fast path's");
    const int spp = f_.table.spp();
    if (one_at_a_time()) [[unlikely]] {
      at_pixel(px, py);
      push_each(px, py, ps, spp, [sel](int s) { return sel[s] ? s : -1; });
      return;
    }
#if defined(__AVX512F__) && defined(__AVX512BW__)
    int n_sel = 0;
    for (int w = 0; w < spp; w += 16) {
      const __m128i f = _mm_loadu_si128(reinterpret_cast<const __m128i*>(sel + w));
      n_sel += __builtin_popcount(_mm_test_epi8_mask(f, f));
    }
    at_pixel(px, py);
    if (spp >= 32 && 3 * n_sel >= spp) {
      run_pixel(px, py, ps, sel, n_sel);
      return;
    }
    if (n_sel == 0) return;
    if (n_ + spp > cap_) flush();
    const __m512 fx = _mm512_set1_ps(static_cast<float>(px)), fy = _mm512_set1_ps(static_cast<float>(py));
    const __m512i vpx = _mm512_set1_epi32(px), vpy = _mm512_set1_epi32(py);
    const __m512i iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    for (int w = 0; w < spp; w += 16) {
      const __m128i f = _mm_loadu_si128(reinterpret_cast<const __m128i*>(sel + w));
      const __mmask16 m = _mm_test_epi8_mask(f, f);
      if (!m) continue;
      const int i = n_;  // 16 lanes stored from i: the arrays have kSlack lanes beyond cap_
      _mm512_storeu_ps(&gx_[i], _mm512_maskz_compress_ps(m, _mm512_add_ps(fx, _mm512_maskz_loadu_ps(m, ps.x + w))));
      _mm512_storeu_ps(&gy_[i], _mm512_maskz_compress_ps(m, _mm512_add_ps(fy, _mm512_maskz_loadu_ps(m, ps.y + w))));
      _mm512_storeu_ps(&gu_[i], _mm512_maskz_compress_ps(m, _mm512_maskz_loadu_ps(m, ps.u + w)));
      _mm512_storeu_ps(&gv_[i], _mm512_maskz_compress_ps(m, _mm512_maskz_loadu_ps(m, ps.v + w)));
      _mm512_storeu_ps(&gt_[i], _mm512_maskz_compress_ps(m, _mm512_maskz_loadu_ps(m, ps.t + w)));
      _mm512_storeu_si512(&bpx_[i], vpx);
      _mm512_storeu_si512(&bpy_[i], vpy);
      _mm512_storeu_si512(&bs_[i], _mm512_maskz_compress_epi32(m, _mm512_add_epi32(iota, _mm512_set1_epi32(w))));
      if (stride_)
        _mm512_storeu_si512(&bl_[i], _mm512_maskz_compress_epi32(m, _mm512_maskz_loadu_epi32(m, ps.lens_index + w)));
      n_ += __builtin_popcount(m);
    }
#else
    const int n_sel = compact_index(sel, spp);
    push_pixel_masked(px, py, ps, sel, sel_index_.data(), n_sel);
#endif
  }
#if defined(__AVX512F__) && defined(__AVX512BW__) && defined(__AVX512VBMI__)
  static constexpr bool kFusedSelect = true;
#else
  static constexpr bool kFusedSelect = false;
#endif
  // Fast path, fused (kFusedSelect builds, spp <= 64): tiletest::select_candidates<true> and
  // push_flagged() of pixel (px, py) in one pass, without the flag bytes in between. The cell
  // test is a byte permute of the tile's active cells (b.active as 64 bytes), the cut tests the same ordered
  // float compares as select_candidates (lanes outside active cells are not compared: their flag
  // is 0 either way). Same samples pushed, same results and counts. Returns how many samples lie
  // in active cells (select_candidates' return).
  [[gnu::always_inline]] inline int push_selected(int px, int py, const PixelSamples& ps,
                                                  const tiletest::SelectBounds& b) {
    static_assert(!A::counting, "push_selected is the fast path's");
#if defined(__AVX512F__) && defined(__AVX512BW__) && defined(__AVX512VBMI__)
    const int spp = f_.table.spp();
    const std::uint64_t tail = spp >= 64 ? ~std::uint64_t(0) : ((std::uint64_t(1) << spp) - 1);
    const __m512i cells = _mm512_maskz_loadu_epi8(tail, ps.cell);
    const __m512i act_bytes = _mm512_permutexvar_epi8(cells, _mm512_maskz_set1_epi8(b.active, 1));
    const std::uint64_t act = _mm512_test_epi8_mask(act_bytes, act_bytes) & tail;
    const int in_cells = __builtin_popcountll(act);
    // Every group of 16 is compared (no data-dependent branch: at a few selected samples per pixel
    // the branches would mispredict); the per-tile cut switches are predictable.
    const __m512 a0 = _mm512_set1_ps(b.a0), b0 = _mm512_set1_ps(b.b0), a1 = _mm512_set1_ps(b.a1),
                 b1 = _mm512_set1_ps(b.b1), c0 = _mm512_set1_ps(b.c0), d0 = _mm512_set1_ps(b.d0),
                 c1 = _mm512_set1_ps(b.c1), d1 = _mm512_set1_ps(b.d1);
    // Without cuts (interval's cells; tiles whose h_i sets cut nothing) the active cells' samples.
    const bool cuts = b.u0 | b.u1 | b.v0 | b.v1;
    std::uint64_t sel = cuts ? 0 : act;
    for (int w = 0; cuts && w < spp; w += 16) {
      const __mmask16 lanes = static_cast<__mmask16>(tail >> w);
      __mmask16 keep = static_cast<__mmask16>(act >> w);
      const __m512 u = _mm512_maskz_loadu_ps(lanes, ps.u + w);
      const __m512 v = _mm512_maskz_loadu_ps(lanes, ps.v + w);
      if (b.u0) keep &= ~_mm512_mask_cmp_ps_mask(_mm512_cmp_ps_mask(u, a0, _CMP_GT_OQ), u, b0, _CMP_LT_OQ);
      if (b.u1) keep &= ~_mm512_mask_cmp_ps_mask(_mm512_cmp_ps_mask(u, a1, _CMP_GT_OQ), u, b1, _CMP_LT_OQ);
      if (b.v0) keep &= ~_mm512_mask_cmp_ps_mask(_mm512_cmp_ps_mask(v, c0, _CMP_GT_OQ), v, d0, _CMP_LT_OQ);
      if (b.v1) keep &= ~_mm512_mask_cmp_ps_mask(_mm512_cmp_ps_mask(v, c1, _CMP_GT_OQ), v, d1, _CMP_LT_OQ);
      sel |= static_cast<std::uint64_t>(keep) << w;
    }
    const int n_sel = __builtin_popcountll(sel);
    at_pixel(px, py);
    if (n_sel == 0) return in_cells;
    if (one_at_a_time()) [[unlikely]] {
      push_each(px, py, ps, spp, [sel](int s) { return (sel >> s) & 1 ? s : -1; });
      return in_cells;
    }
    // Every sample: the pixel as its own batch (push_pixel). Fewer: compressed into the batch, which
    // measured faster than the whole pixel's kernel with a mask down to a few unselected samples.
    if (spp >= 32 && n_sel == spp) {
      run_pixel(px, py, ps, nullptr, spp);
      return in_cells;
    }
    if (n_ + spp > cap_) flush();
    int n = n_;  // 16 lanes stored from n: the arrays have kSlack lanes beyond cap_
    float* __restrict gx = gx_.data();
    float* __restrict gy = gy_.data();
    float* __restrict gu = gu_.data();
    float* __restrict gv = gv_.data();
    float* __restrict gt = gt_.data();
    int* __restrict bpx = bpx_.data();
    int* __restrict bpy = bpy_.data();
    int* __restrict bs = bs_.data();
    const bool need_t = need_t_;
    const __m512 fx = _mm512_set1_ps(static_cast<float>(px)), fy = _mm512_set1_ps(static_cast<float>(py));
    const __m512i vpx = _mm512_set1_epi32(px), vpy = _mm512_set1_epi32(py);
    const __m512i iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    // The groups of 16 holding selected samples, lowest first (one loop exit to predict, not one
    // branch per group).
    unsigned groups = 0;
    for (int g = 0; g < 4; ++g) groups |= static_cast<unsigned>(((sel >> (16 * g)) & 0xffffu) != 0) << g;
    for (; groups; groups &= groups - 1) {
      const int w = 16 * __builtin_ctz(groups);
      const __mmask16 m = static_cast<__mmask16>(sel >> w);
      _mm512_storeu_ps(gx + n, _mm512_maskz_compress_ps(m, _mm512_add_ps(fx, _mm512_maskz_loadu_ps(m, ps.x + w))));
      _mm512_storeu_ps(gy + n, _mm512_maskz_compress_ps(m, _mm512_add_ps(fy, _mm512_maskz_loadu_ps(m, ps.y + w))));
      _mm512_storeu_ps(gu + n, _mm512_maskz_compress_ps(m, _mm512_maskz_loadu_ps(m, ps.u + w)));
      _mm512_storeu_ps(gv + n, _mm512_maskz_compress_ps(m, _mm512_maskz_loadu_ps(m, ps.v + w)));
      if (need_t) _mm512_storeu_ps(gt + n, _mm512_maskz_compress_ps(m, _mm512_maskz_loadu_ps(m, ps.t + w)));
      _mm512_storeu_si512(bpx + n, vpx);
      _mm512_storeu_si512(bpy + n, vpy);
      _mm512_storeu_si512(bs + n, _mm512_maskz_compress_epi32(m, _mm512_add_epi32(iota, _mm512_set1_epi32(w))));
      if (stride_)
        _mm512_storeu_si512(bl_.data() + n,
                            _mm512_maskz_compress_epi32(m, _mm512_maskz_loadu_epi32(m, ps.lens_index + w)));
      n += __builtin_popcount(m);
    }
    n_ = n;
    return in_cells;
#else
    (void)px, (void)py, (void)ps, (void)b;
    return 0;  // not compiled in (kFusedSelect false): callers take select_candidates + push_flagged
#endif
  }

  // Nothing observes the order in which one triangle's samples are tested: no shading visits or
  // texture stream are recorded (shading none), no observer of visits (timing records, the memory
  // model) or of pixel targets (per-pixel statistics). Then depth slots, colours and every counter
  // depend only on the set of samples pushed (each sample is tested once per triangle and owns its
  // depth slot).
  bool order_free() const { return !sh_.counting() && !visits_ && !targets_; }

  // sel arrays for push_flagged(): spp flags and this many more, zero.
  static constexpr int flags_padding() { return 16; }

  // Depth-test switches set by z-culling (backend/zcull.h, backend/sample_backend.h). Flush before
  // changing them: they apply to the samples evaluated by the next flush.
  void set_depth_mode(bool skip_depth_reads, bool query) {
    flush();
    backend_.set_depth_mode(skip_depth_reads, query);
  }

  inline void flush() {
    if constexpr (!A::counting) {
      if (n_ > 0) run_batch(false, 0, n_);
      n_ = 0;
    }
  }

  // The end of a shading visit (backend/shading.h): every sample pushed since the previous end_visit()
  // belongs to one visit, whose shading work is counted now. Algorithms call it when they leave a
  // screen tile (or finish a pass) for the current triangle, and always before rasterize() returns.
  // Without a shading model (mode none) it does nothing, not even flush(): callers still flush.
  inline void end_visit() {
    if (visits_) {  // observers of visits: close the visit, then tell them
      flush();
      if (sh_.counting()) sh_.close_visit();
      obs_.end_visit();
      return;
    }
    if (!sh_.counting()) return;
    flush();
    sh_.close_visit();
  }

 private:
  static constexpr Counter kTestedByClass[4] = {
      Counter::raster_samples_tested_2d, Counter::raster_samples_tested_3d,
      Counter::raster_samples_tested_4d, Counter::raster_samples_tested_5d};
  static constexpr int kBatch = 1024;  // small enough for the batch to stay in L1/L2
  static constexpr int kSlack = 16;    // push_flagged / push_selected / append_pixel store whole vectors past the end

  // Where run_pixel() evaluates a pixel while a batch is pending: past the batch region.
  int pixel_at() const { return cap_ + kSlack; }

  // Samples are tested one at a time as they are pushed (push() -> test()), not batched: the
  // counting path, and a sample-test decision other than float32 (pipeline.precision.sample,
  // sampletest/precision.h). Every entry point then hands its samples to push_each().
  bool one_at_a_time() const {
    if constexpr (A::counting) return true;
    else return precise_;
  }
  // push() of the samples pick(0), ..., pick(n - 1) of pixel (px, py) that are >= 0, in that order.
  template <class Pick>
  [[gnu::noinline]] void push_each(int px, int py, const PixelSamples& ps, int n, Pick pick) {
    for (int i = 0; i < n; ++i)
      if (const int s = pick(i); s >= 0) push(px, py, ps, s);
  }

  // Indices of the set flags of sel[0..n) into sel_index_ (tiletest/candidates.h compact_flags).
  int compact_index(const std::uint8_t* sel, int n) {
    int m = 0;
    for (int w = 0; w < n; w += 8) {
      std::uint64_t word = 0;
      std::memcpy(&word, sel + w, 8);
      if (!word) continue;
      for (int i = w; i < std::min(n, w + 8); ++i) {
        sel_index_[m] = i;
        m += sel[i];
      }
    }
    return m;
  }

  void retarget(int x0, int y0, int x1, int y1, int kind) {
    if (obs_.aims_at(x0, y0, x1, y1)) return;
    flush();  // the pending samples' work belongs to the current target
    obs_.target(x0, y0, x1, y1, kind);
  }

  inline void test_values(const TriSetup& tri, F sx, F sy, F u, F v, F t, int px, int py, int s) {
    F X[3], Y[3], W[3], e[3], det;
    int n_ties;
    const bool covered = inside_test(tri, tri.cls, f_.fc, sx, sy, u, v, t, f_.p.backface_cull, X, Y, W, e, det, n_ties);
    ++c_[kTestedByClass[static_cast<int>(tri.cls)]];
    if constexpr (A::counting) {
      if (model_ == CostModel::kHardware) {  // count the hardware form instead (sampletest/hardware.h)
        OpTally::take();
        hw_inside_test(tri, tri.cls, f_.fc, sx, sy, u, v, t, n_ties ? tie_mask(e) : 0);
      }
    }
    finish(tri, covered, e, det, n_ties, px, py, s,
           sample_test_cost(model_, tri.cls) + n_ties * tie_break_cost(model_, tri.cls));
  }

  inline void test_sheared_values(const TriSetup& tri, const float Xs[3], const float Ys[3], F sx, F sy, int px,
                                  int py, int s) {
    F X[3], Y[3], W[3], e[3], det;
    for (int j = 0; j < 3; ++j) X[j] = F(Xs[j]), Y[j] = F(Ys[j]), W[j] = F(tri.W[j]);
    int n_ties;
    const bool covered = inside_from_vertices(X, Y, W, sx, sy, f_.p.backface_cull, e, det, n_ties);
    ++c_[Counter::raster_samples_tested_2d];
    if constexpr (A::counting) {
      if (model_ == CostModel::kHardware) {
        OpTally::take();
        hw_inside_sheared(Xs, Ys, tri.W, sx, sy);
      }
    }
    finish(tri, covered, e, det, n_ties, px, py, s,
           sample_test_cost(model_, DimClass::k2D) + n_ties * tie_break_cost(model_, DimClass::k2D));
  }

  // One pixel's samples as a batch of their own (no per-sample pixel/index bookkeeping); with sel,
  // only the selected samples count (fast path only). When the test order is free (order_free()) a
  // pending batch stays pending and the pixel is evaluated in the second region; else the batch is
  // flushed first.
  void run_pixel(int px, int py, const PixelSamples& ps, const std::uint8_t* sel, int n_sel) {
    const int spp = f_.table.spp();
    int at = 0;
    if (n_ > 0 && free_order_) at = pixel_at();
    else flush();
    gather_xy(static_cast<float>(px), static_cast<float>(py), ps, spp, at);
    uniform_ps_ = &ps;
    if (stride_)
      for (int s = 0; s < spp; ++s) bl_[at + s] = ps.lens_index[s];
    uniform_px_ = px, uniform_py_ = py;
    run_batch(true, at, spp, sel, n_sel);
  }

  // Every sample of pixel (px, py) appended to the batch (fast path, spp < 32).
  inline void append_pixel(int px, int py, const PixelSamples& ps, int spp) {
    if (n_ + spp > cap_) flush();
    const int i0 = n_;
#if defined(__AVX512F__)
    // 16 lanes at a time (the arrays have kSlack lanes beyond cap_); lanes past spp are overwritten
    // by the next push or never read.
    const __m512 fx = _mm512_set1_ps(static_cast<float>(px)), fy = _mm512_set1_ps(static_cast<float>(py));
    const __m512i vpx = _mm512_set1_epi32(px), vpy = _mm512_set1_epi32(py);
    const __m512i iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    for (int w = 0; w < spp; w += 16) {
      const __mmask16 m = spp - w >= 16 ? __mmask16(0xffff) : static_cast<__mmask16>((1u << (spp - w)) - 1);
      const int i = i0 + w;
      _mm512_storeu_ps(&gx_[i], _mm512_add_ps(fx, _mm512_maskz_loadu_ps(m, ps.x + w)));
      _mm512_storeu_ps(&gy_[i], _mm512_add_ps(fy, _mm512_maskz_loadu_ps(m, ps.y + w)));
      _mm512_storeu_ps(&gu_[i], _mm512_maskz_loadu_ps(m, ps.u + w));
      _mm512_storeu_ps(&gv_[i], _mm512_maskz_loadu_ps(m, ps.v + w));
      if (need_t_) _mm512_storeu_ps(&gt_[i], _mm512_maskz_loadu_ps(m, ps.t + w));
      _mm512_storeu_si512(&bpx_[i], vpx);
      _mm512_storeu_si512(&bpy_[i], vpy);
      _mm512_storeu_si512(&bs_[i], _mm512_add_epi32(iota, _mm512_set1_epi32(w)));
    }
#else
    gather_pixel(static_cast<float>(px), static_cast<float>(py), ps, spp, i0);
    for (int s = 0; s < spp; ++s) bpx_[i0 + s] = px, bpy_[i0 + s] = py, bs_[i0 + s] = s;
#endif
    if (stride_)
      for (int s = 0; s < spp; ++s) bl_[i0 + s] = ps.lens_index[s];
    n_ += spp;
  }

  static void mask_flags(int n, const std::uint8_t* __restrict sel, std::uint8_t* __restrict flags) {
    for (int i = 0; i < n; ++i) flags[i] = static_cast<std::uint8_t>(flags[i] * (sel[i] != 0));
  }

  void gather_xy(float fx, float fy, const PixelSamples& ps, int spp, int at) {
    float* __restrict gx = gx_.data() + at;
    float* __restrict gy = gy_.data() + at;
    const float* __restrict x = ps.x;
    const float* __restrict y = ps.y;
    for (int s = 0; s < spp; ++s) gx[s] = fx + x[s], gy[s] = fy + y[s];
  }

  void gather_pixel(float fx, float fy, const PixelSamples& ps, int spp, int i0) {
    float* __restrict gx = gx_.data() + i0;
    float* __restrict gy = gy_.data() + i0;
    float* __restrict gu = gu_.data() + i0;
    float* __restrict gv = gv_.data() + i0;
    float* __restrict gt = gt_.data() + i0;
    const float* __restrict x = ps.x;
    const float* __restrict y = ps.y;
    const float* __restrict u = ps.u;
    const float* __restrict v = ps.v;
    const float* __restrict t = ps.t;
    for (int s = 0; s < spp; ++s) {
      gx[s] = fx + x[s], gy[s] = fy + y[s];
      gu[s] = u[s], gv[s] = v[s], gt[s] = t[s];
    }
  }

  // Evaluate n samples from region offset at (fast path): the pending batch (at 0, n_), or with
  // uniform, samples 0..n-1 of pixel (uniform_px_, uniform_py_), of which only those flagged in sel
  // (n_sel of them) count when sel is given.
  void run_batch(bool uniform, int at, int n, const std::uint8_t* sel = nullptr, int n_sel = 0) {
    uniform_ = uniform;
    at_ = at;
    const bool masked = sel != nullptr;
    const TriSetup& tri = *tri_;
    float* e = be_.data() + 3 * static_cast<std::size_t>(at);
    float* d = bdet_.data() + at;
    std::uint8_t* flags = flags_.data() + at;
    float* gx = gx_.data() + at;
    float* gy = gy_.data() + at;
    std::uint64_t inside_cost;
    bool have_flags = false;  // the kernel computed the flags too
    const float* bu = uniform ? uniform_ps_->u : gu_.data();
    const float* bv = uniform ? uniform_ps_->v : gv_.data();
    const float* bt = uniform ? uniform_ps_->t : gt_.data();
    if (!sheared_) {
      const int cls = static_cast<int>(tri.cls);
      const FrameConst& fc = f_.fc;
      const BatchTri T{tri.X[0],  tri.X[1],  tri.X[2],  tri.Y[0],  tri.Y[1],  tri.Y[2],  tri.W[0],
                       tri.W[1],  tri.W[2],  tri.cx[0], tri.cx[1], tri.cx[2], tri.cy[0], tri.cy[1],
                       tri.cy[2], tri.dX[0], tri.dX[1], tri.dX[2], tri.dY[0], tri.dY[1], tri.dY[2],
                       tri.dW[0], tri.dW[1], tri.dW[2], fc.kx,     fc.neg_kx_f, fc.ky, fc.neg_ky_f};
      const bool bfc = f_.p.backface_cull;
      switch (cls) {  // 4D and 5D: edges and flags in one explicit-SIMD pass (sampletest/simd_batch.h)
        case 0: batch_edges_2d(n, T, gx, gy, e, e + n, e + 2 * n, d); break;
        case 2:
          if (f_.p.simd) {
            simd::batch_test_4d(n, T, gx, gy, bu, bv, e, e + n, e + 2 * n, d, bfc, flags);
            have_flags = true;
          } else {
            batch_edges_4d(n, T, gx, gy, bu, bv, e, e + n, e + 2 * n, d);
          }
          break;
        case 1: batch_edges_3d(n, T, gx, gy, bt, e, e + n, e + 2 * n, d); break;
        default:
          if (f_.p.simd) {
            simd::batch_test_5d(n, T, gx, gy, bu, bv, bt, e, e + n, e + 2 * n, d, bfc, flags);
            have_flags = true;
          } else {
            batch_edges_5d(n, T, gx, gy, bu, bv, bt, e, e + n, e + 2 * n, d);
          }
          break;
      }
      c_[kTestedByClass[cls]] += static_cast<std::uint64_t>(masked ? n_sel : n);
      inside_cost = sample_test_cost(model_, tri.cls);
    } else {
      const float W[3] = {tri.W[0], tri.W[1], tri.W[2]};
      if (stride_ == 0) {
        BatchTri T{};
        T.X0 = xs_[0], T.X1 = xs_[1], T.X2 = xs_[2], T.Y0 = ys_[0], T.Y1 = ys_[1], T.Y2 = ys_[2];
        T.W0 = W[0], T.W1 = W[1], T.W2 = W[2];
        batch_edges_2d(n, T, gx, gy, e, e + n, e + 2 * n, d);
      } else {
        for (int i = 0; i < n; ++i) {
          const int off = stride_ * bl_[at + i];
          edge_functions_s(xs_[off], xs_[off + 1], xs_[off + 2], ys_[off], ys_[off + 1], ys_[off + 2], W[0], W[1],
                           W[2], gx[i], gy[i], e[i], e[n + i], e[2 * n + i], d[i]);
        }
      }
      c_[Counter::raster_samples_tested_2d] += static_cast<std::uint64_t>(masked ? n_sel : n);
      inside_cost = sample_test_cost(model_, DimClass::k2D);
    }
    // Flags: 1 = covered, 2 = an e_i is exactly zero (scalar top-left path). Then skip 8 flags at a
    // time (most batches are mostly misses).
    if (!have_flags) batch_flags(n, e, e + n, e + 2 * n, d, f_.p.backface_cull, flags);
    if (sel) mask_flags(n, sel, flags);
    const int tested = masked ? n_sel : n;
    c_[Counter::raster_samples_tested] += static_cast<std::uint64_t>(tested);
    c_[Counter::ops_sample_inside] += inside_cost * static_cast<std::uint64_t>(tested);
    auto settle = [&](int i) {
      const std::uint8_t fl = flags[i];
      const int px = uniform ? uniform_px_ : bpx_[i], py = uniform ? uniform_py_ : bpy_[i];
      const int smp = uniform ? i : bs_[i];
      if (fl & 1) {
        const F ev[3] = {e[i], e[n + i], e[2 * n + i]};
        shade(tri, ev, d[i], px, py, smp);
      } else if (fl & 2) {
        tie_break_sample(tri, i, px, py, smp);
      }
    };
#if defined(__AVX512F__) && defined(__AVX512BW__)
    if (backend_.lanes_ready(tri)) {
      // The covered samples 16 lanes at a time through the backend's vectorised path, then the ties
      // (settled one by one). Their depth slots are distinct, so the order of the two does not show.
      const __m128i one = _mm_set1_epi8(1), two = _mm_set1_epi8(2);
      const __m512i iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
      std::uint64_t ties = 0;
      for (int w = 0; w < n; w += 16) {
        const __mmask16 live = n - w >= 16 ? __mmask16(0xffff) : static_cast<__mmask16>((1u << (n - w)) - 1);
        const __m128i f = _mm_maskz_loadu_epi8(live, flags + w);
        const __mmask16 cov = _mm_test_epi8_mask(f, one);
        ties |= static_cast<std::uint64_t>(_mm_test_epi8_mask(f, two)) << (w & 63);
        if (cov) {
          __m512i vpx, vpy, vs;
          if (uniform) {
            vpx = _mm512_set1_epi32(uniform_px_), vpy = _mm512_set1_epi32(uniform_py_);
            vs = _mm512_add_epi32(iota, _mm512_set1_epi32(w));
          } else {
            vpx = _mm512_maskz_loadu_epi32(cov, bpx_.data() + w), vpy = _mm512_maskz_loadu_epi32(cov, bpy_.data() + w);
            vs = _mm512_maskz_loadu_epi32(cov, bs_.data() + w);
          }
          backend_.covered_lanes(tri, cov, _mm512_maskz_loadu_ps(cov, e + w), _mm512_maskz_loadu_ps(cov, e + n + w),
                                 _mm512_maskz_loadu_ps(cov, e + 2 * n + w), _mm512_maskz_loadu_ps(cov, d + w), vpx,
                                 vpy, vs);
        }
        if ((w & 63) == 48 || w + 16 >= n) {  // the ties of these 64 lanes, lowest first
          const int base = w & ~63;
          for (; ties; ties &= ties - 1) {
            const int i = base + __builtin_ctzll(ties);
            tie_break_sample(tri, i, uniform ? uniform_px_ : bpx_[i], uniform ? uniform_py_ : bpy_[i],
                             uniform ? i : bs_[i]);
          }
        }
      }
      return;
    }
    // The nonzero flags, 64 at a time, as a bit mask walked lowest first: the same samples in the
    // same order as the byte walk below, without a branch per flag.
    for (int w = 0; w < n; w += 64) {
      const std::uint64_t live = n - w >= 64 ? ~std::uint64_t(0) : ((std::uint64_t(1) << (n - w)) - 1);
      const __m512i f = _mm512_maskz_loadu_epi8(live, flags + w);
      for (std::uint64_t m = _mm512_test_epi8_mask(f, f); m; m &= m - 1) settle(w + __builtin_ctzll(m));
    }
#else
    for (int w = 0; w < n; w += 8) {
      std::uint64_t word;
      std::memcpy(&word, flags + w, 8);
      if (!word) continue;
      for (int i = w; i < std::min(n, w + 8); ++i)
        if (flags[i]) settle(i);
    }
#endif
  }

  // An edge function was exactly zero: settle the sample with the scalar test (top-left rule).
  void tie_break_sample(const TriSetup& tri, int i, int px, int py, int smp) {
    float X[3], Y[3], W[3], e[3], det;
    int n_ties;
    bool covered;
    const int k = at_ + i;  // in the region being evaluated
    if (sheared_) {
      const int off = stride_ ? stride_ * bl_[k] : 0;
      for (int j = 0; j < 3; ++j) X[j] = xs_[off + j], Y[j] = ys_[off + j], W[j] = tri.W[j];
      covered = inside_from_vertices(X, Y, W, gx_[k], gy_[k], f_.p.backface_cull, e, det, n_ties);
    } else {
      const bool u = uniform_;
      covered = inside_test(tri, tri.cls, f_.fc, gx_[k], gy_[k], u ? uniform_ps_->u[i] : gu_[k],
                            u ? uniform_ps_->v[i] : gv_[k], u ? uniform_ps_->t[i] : gt_[k], f_.p.backface_cull, X,
                            Y, W, e, det, n_ties);
    }
    c_[Counter::ops_sample_inside] +=
        static_cast<std::uint64_t>(n_ties) * tie_break_cost(model_, sheared_ ? DimClass::k2D : tri.cls);
    if (n_ties) ++c_[Counter::raster_tie_breaks];
    if (covered) shade(tri, e, det, px, py, smp);
  }

  // The edges the robust test settled by the top-left rule (exactly zero edge functions).
  static int tie_mask(const F e[3]) {
    int m = 0;
    for (int i = 0; i < 3; ++i) m |= (raw(e[i]) == 0.0f) << i;
    return m;
  }

  inline void finish(const TriSetup& tri, bool covered, const F e[3], F det, int n_ties, int px, int py,
                     int s, std::uint64_t test_cost) {
    F e_precise[3];
    if (precise_) [[unlikely]] {  // the decision in pipeline.precision.sample (sampletest/precision.h)
      const PixelSamples& ps = *cur_ps_;
      double ed[3], detd;
      bool overflow;
      covered = precise_inside(tri, f_.fc, f_.p.precision_sample, static_cast<double>(px) + ps.x[s],
                               static_cast<double>(py) + ps.y[s], ps.u[s], ps.v[s], ps.t[s], f_.p.backface_cull, ed,
                               detd, overflow);
      if (overflow) ++c_[Counter::precision_sample_overflows];
      for (int i = 0; i < 3; ++i) e_precise[i] = F(static_cast<float>(ed[i]));
      e = e_precise, det = F(static_cast<float>(detd));
    }
    ++c_[Counter::raster_samples_tested];
    charge<A>(c_[Counter::ops_sample_inside], test_cost);
    if (n_ties) ++c_[Counter::raster_tie_breaks];
    if constexpr (A::counting) {  // pixel trace (sim.trace_pixel renders on the counting path)
      if (targets_ && obs_.traces(px, py)) [[unlikely]] {
        const std::uint64_t hits = c_[Counter::raster_samples_hit];
        if (covered) shade(tri, e, det, px, py, s);
        obs_.traced_sample(tri.index, s, covered, c_[Counter::raster_samples_hit] != hits);
        return;
      }
    }
    if (covered) shade(tri, e, det, px, py, s);
  }

  // A covered sample goes to the backend (clip box, depth, depth test, colour, shading).
  template <class G>
  inline void shade(const TriSetup& tri, const G e[3], G det, int px, int py, int s) {
    backend_.covered(tri, e, det, px, py, s);
  }

  const Frame& f_;
  Counters& c_;
  ShadeState& sh_;
  ThreadState& ts_;
  SampleBackend<A> backend_;
  // Pending batch (fast path).
  const TriSetup* tri_ = nullptr;
  bool sheared_ = false;
  const float *xs_ = nullptr, *ys_ = nullptr;
  int stride_ = 0;
  int n_ = 0;
  int cap_;
  CostModel model_;
  bool precise_;                            // pipeline.precision.sample is not float32
  const PixelSamples* cur_ps_ = nullptr;    // the samples of the pixel under test (precise_ only)
  int uniform_px_ = 0, uniform_py_ = 0;
  bool uniform_ = false;
  int at_ = 0;                // region offset of the batch being evaluated (run_batch())
  bool need_t_ = true;        // the triangle's sample test reads t (3D, 5D): else the batch's t lanes are not stored
  bool free_order_ = false;   // order_free() for the current triangle (set by begin())
  const PixelSamples* uniform_ps_ = nullptr;
  std::vector<float> gx_, gy_, gu_, gv_, gt_, be_, bdet_;
  std::vector<int> bpx_, bpy_, bs_, bl_;
  std::vector<int> sel_index_;  // push_flagged() without SIMD compression
  std::vector<std::uint8_t> flags_;
  Observers& obs_;
  const bool visits_, targets_;  // an observer wants visit ends / pixel targets
};

}  // namespace rast5d
