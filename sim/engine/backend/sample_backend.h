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
