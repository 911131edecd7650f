// The conventional-GPU pipeline as a traversal ([Toth 2008] §3, Fig. 4;
// [McGuire 2010]): per triangle the geometry shader emits bounding geometry
// (gpu/geometry_shader.h), the fixed-function 2D rasterizer turns it into fragments
// (gpu/raster2d.h), and the pixel shader tests every sample of each fragment against the triangle
// at the sample's (u, v, t) with the engine's exact sample test and tie rule (the sample pipeline,
// traversal/sample_pipeline.h; [Toth 2008] §5.1-5.2, [McGuire 2010]'s per-MSAA-sample loop), then hands covered
// samples to the same backend. Every sample the exact test hits lies in a fragment (the bounds are
// conservative), so the image is bruteforce's.
//
// Pixel shader ([Toth 2008] §5.1, §9.6): without triangle constants it re-derives the sample kernel's
// per-triangle constants from the interpolated vertex data for every fragment (ops.ps_setup);
// with triangle or strip constants the geometry shader derives them once. Interpolation moves
// 4 + payload floats per fragment without constants, 4 with (gpu.interp_floats). Its (u, v, t)
// come from the perturbation texture of [Toth 2008] §5.3, a pre-computed, stratified block of per-pixel
// samples repeated over the screen and addressed by the pixel's position: the sample table is that
// texture (docs/gpu.md), so each fragment pays the texture coordinate (ops.ps_setup) and one texel
// per sample (gpu.perturb_fetches, timing unit texture).
//
// Early depth ([Toth 2008] §5.4, §9.7): the pixel shader writes the depth it computes, so a GPU tests depth
// after it; with [Toth 2008] §9.7's depth interval (the triangle's conservative depth range handed to the
// tiled depth buffer, pipeline hiz.enabled) whole HiZ tiles of fragments are rejected before the
// pixel shader with the engine's ẑ and HiZ (backend/zcull.h), exactly as `tile` culls its tiles.
//
// Counters: gpu.* and ops.ps_setup; the geometry shader's operations go to ops.setup (and
// gpu.gs_ops), the rasterizer's to ops.tile; once per triangle in its first bin (charge_setup).
#pragma once

#include <algorithm>
#include <cmath>

#include <utility>
#include <vector>

#include "backend/zcull.h"
#include "gpu/geometry_shader.h"
#include "gpu/raster2d.h"
#include "traversal/traversal.h"

namespace rast5d::gpu {

// Per-render constants of the geometry shader, from the parameters and the sample table.
inline GsFrame make_gs_frame(const Frame& f) {
  GsFrame g;
  g.kx = f.fc.lens_active ? f.fc.kx_d : 0.0;
  g.ky = f.fc.lens_active ? f.fc.ky_d : 0.0;
  g.focus = f.fc.focus_d;
  g.neg_focus = -f.fc.focus_d;
  g.near_clip = f.fc.near_d * (1.0 - 0x1p-12);
  g.s = 1.0 / std::max(1, std::max(f.p.width, f.p.height));
  g.inv_s = std::max(1, std::max(f.p.width, f.p.height));
  g.adaptive_ratio = f.p.gpu_adaptive_ratio;
  // The lens set's support: the unit disk when every (u, v) of the table lies in it, else the
  // square [-1, 1]^2 (always valid).
  bool disk = true;
  const int P = f.table.period(), spp = f.table.spp();
  for (int py = 0; py < P && disk; ++py)
    for (int px = 0; px < P && disk; ++px) {
      const PixelSamples ps = f.table.pixel(px, py);
      for (int s = 0; s < spp; ++s) {
        const double u = ps.u[s], v = ps.v[s];
        if (!(u * u + v * v <= 1.0)) {
          disk = false;
          break;
        }
      }
    }
  g.disk = disk;
  return g;
}

// Floats of contained-triangle data per bounding vertex besides its 4 position floats.
inline int payload_floats(const RenderParams& p, const TriSetup& tri) {
  if (p.gpu_payload_floats >= 0) return p.gpu_payload_floats;
  return 3 * (3 + 1 + 3) + (tri.moving ? 9 : 0);
}

template <class A, Method kMethod>
class GpuBounding final : public Traversal {
  using D = typename A::f64;
  using F = typename A::f32;

 public:
  static constexpr bool kDepthCull = true;
  GpuBounding(const Frame& f, ThreadState& ts)
      : f_(f), c_(ts.counters), pipe_(f, ts), zcull_(f, ts.counters, ts.buffers, pipe_), gs_(make_gs_frame(f)) {}

  void rasterize(const TriSetup& tri, const BinRect& bin, bool charge_setup) override {
    zcull_.begin_triangle(tri, charge_setup);
    if (zcull_.query_answered()) return;  // interval-based occlusion query already answered
    rasterize_tri(tri, bin, charge_setup);
    zcull_.end_triangle();
  }

 private:
  void rasterize_tri(const TriSetup& tri, const BinRect& bin, bool charge_setup) {
    std::uint64_t gs_ops = 0, raster_setup_ops = 0;
    const Bound b = gs_.run(kMethod, tri, gs_ops);
    const GpuConstants constants = f_.p.gpu_constants;
    if (constants != GpuConstants::kNone) rederive(tri, gs_ops);  // once, in the geometry shader
    RasterSetup r;
    raster_setup<A>(b, tri, f_.p.width, f_.p.height, r, raster_setup_ops);
    if (charge_setup) {
      account(tri, b, gs_ops, raster_setup_ops);
      outside_box(tri, r);
    }

    const int x0 = std::max(r.x0, bin.x0), x1 = std::min(r.x1, bin.x1);
    const int y0 = std::max(r.y0, bin.y0), y1 = std::min(r.y1, bin.y1);
    if (x0 >= x1 || y0 >= y1) return;
    pipe_.begin(tri);
    // Early depth ([Toth 2008] §9.7's depth interval, pipeline hiz.enabled): the rasterizer's fragments are
    // grouped by HiZ tile and the triangle's conservative depth interval over the tile, the whole
    // lens and the shutter (ẑ, intervals/depth_interval.h) is compared with the tile's stored depths
    // (backend/zcull.h) before the pixel shader runs: a tile behind HiZ's zmax loses its fragments,
    // one in front of zmin skips the depth reads. Without HiZ one group: the scan box.
    const bool by_tile = f_.p.hiz_enabled || f_.p.zhat_stats || f_.p.query_mode == QueryMode::kIntervals;
    const int T = by_tile ? f_.p.hiz_tile_size : std::max(x1 - x0, y1 - y0);
    const bool lens = tri.cls == DimClass::k4D || tri.cls == DimClass::k5D;
    const int spp = f_.table.spp();
    std::uint64_t raster_ops = 0;
    for (int ty = by_tile ? bin.y0 + ((y0 - bin.y0) / T) * T : y0; ty < y1; ty += T)
      for (int tx = by_tile ? bin.x0 + ((x0 - bin.x0) / T) * T : x0; tx < x1; tx += T) {
        if (zcull_.query_answered()) break;
        const int rx0 = std::max(tx, x0), rx1 = std::min(tx + T, x1);
        const int ry0 = std::max(ty, y0), ry1 = std::min(ty + T, y1);
        pipe_.at_rect(rx0, ry0, rx1, ry1);
        frags_.clear();
        for (int py = ry0; py < ry1; ++py)
          for (int px = rx0; px < rx1; ++px) {
            pipe_.at_pixel(px, py);
            ++c_[Counter::gpu_raster_pixels_tested];
            if (pixel_covered<A>(r, px, py, raster_ops)) frags_.push_back({px, py});
          }
        if (frags_.empty()) continue;
        if (by_tile) {
          pipe_.at_rect(rx0, ry0, rx1, ry1);
          const int n = static_cast<int>(frags_.size());
          const std::uint64_t culled0 = c_[Counter::zcull_pairs_culled];
          if (!zcull_.check(tri, rx0, ry0, rx0, rx1, ry0, ry1, lens, -1.0, 1.0, -1.0, 1.0, 0.0, 1.0, n * spp)) {
            // behind zmax (an interval-based occlusion query's pairs also stop here, uncounted)
            if (c_[Counter::zcull_pairs_culled] != culled0) c_[Counter::gpu_fragments_depth_culled] += static_cast<std::uint64_t>(n);
            continue;
          }
        }
        for (const auto& fr : frags_) pixel_shader(tri, fr.first, fr.second);
      }
    c_[Counter::ops_tile] += raster_ops;
    pipe_.end_visit();  // a visit = the triangle's fragments in this bin
    pipe_.flush();
  }

  // One fragment: the pixel shader's perturbation-texture coordinate ([Toth 2008] §5.3) and fetches, its
  // re-derived setup without triangle constants ([Toth 2008] §9.6), the interpolated floats, and every
  // sample of the pixel through the exact sample test ([Toth 2008] §5.1).
  void pixel_shader(const TriSetup& tri, int px, int py) {
    const int spp = f_.table.spp();
    ++c_[Counter::gpu_fragments];
    c_[Counter::gpu_interp_floats] += interp_floats(tri);
    std::uint64_t ps_setup = 0;
    perturb_coord(px, py, ps_setup);
    if (f_.p.gpu_constants == GpuConstants::kNone) rederive(tri, ps_setup);
    c_[Counter::gpu_perturb_fetches] += static_cast<std::uint64_t>(spp);
    const std::uint64_t covered0 = c_[Counter::raster_samples_covered];
    const std::uint64_t ops0 = c_[Counter::ops_sample_inside];
    pipe_.push_pixel(px, py, f_.table.pixel(px, py));
    pipe_.flush();
    if (c_[Counter::raster_samples_covered] == covered0) ++c_[Counter::gpu_fragments_zero_hit];
    c_[Counter::gpu_ps_samples_tested] += static_cast<std::uint64_t>(spp);
    c_[Counter::ops_ps_setup] += ps_setup;
    c_[Counter::gpu_ps_ops] += ps_setup + (c_[Counter::ops_sample_inside] - ops0);
  }

  // The polygon's on-screen pixels outside the setup box (raster2d.h), once per triangle: the
  // rasterizer tests and emits them and the pixel shader runs on each, finding no sample inside
  // (the setup box bounds every hit). Its sample tests are charged at the documented cost of the
  // triangle's class (sampletest/hardware.h, proven by the counting path on every other test);
  // they are not run, since they cannot hit and lie outside the bin being rendered.
  void outside_box(const TriSetup& tri, const RasterSetup& r) {
    const int spp = f_.table.spp();
    const std::uint64_t test_cost = sample_test_cost(f_.p.cost_model, tri.cls);
    std::uint64_t raster_ops = 0, n = 0, ps_setup = 0;
    for (int py = r.ey0; py < r.ey1; ++py)
      for (int px = r.ex0; px < r.ex1; ++px) {
        if (py >= tri.by0 && py < tri.by1 && px >= tri.bx0 && px < tri.bx1) {
          px = std::max(px, tri.bx1 - 1);  // skip the setup box's span of this row
          continue;
        }
        ++c_[Counter::gpu_raster_pixels_tested];
        if (!pixel_covered<A>(r, px, py, raster_ops)) continue;
        ++n;
        perturb_coord(px, py, ps_setup);
        if (f_.p.gpu_constants == GpuConstants::kNone) rederive(tri, ps_setup);
      }
    c_[Counter::ops_tile] += raster_ops;
    if (n == 0) return;
    const std::uint64_t tests = n * static_cast<std::uint64_t>(spp);
    c_[Counter::gpu_fragments] += n;
    c_[Counter::gpu_fragments_outside_box] += n;
    c_[Counter::gpu_fragments_zero_hit] += n;
    c_[Counter::gpu_interp_floats] += n * interp_floats(tri);
    c_[Counter::gpu_perturb_fetches] += tests;
    c_[Counter::gpu_ps_samples_tested] += tests;
    c_[Counter::raster_samples_tested] += tests;
    c_[kTestedByClass[static_cast<int>(tri.cls)]] += tests;
    c_[Counter::ops_sample_inside] += tests * test_cost;
    c_[Counter::ops_ps_setup] += ps_setup;
    c_[Counter::gpu_ps_ops] += ps_setup + tests * test_cost;
  }

  std::uint64_t interp_floats(const TriSetup& tri) const {
    return f_.p.gpu_constants == GpuConstants::kNone ? 4 + static_cast<std::uint64_t>(payload_floats(f_.p, tri)) : 4;
  }

  // The perturbation texture's coordinate ([Toth 2008] §5.3): the pixel's position scaled to one texel per
  // pixel of the sample table's repeating block. Cost kPerturbCoord.
  void perturb_coord(int px, int py, std::uint64_t& ops) const {
    const D inv(1.0 / f_.table.period());
    const D s = D(static_cast<double>(px)) * inv, t = D(static_cast<double>(py)) * inv;
    sink_ = static_cast<float>(raw(s) + raw(t));
    charge<A>(ops, cost::gpu::kPerturbCoord);
  }

  static constexpr Counter kTestedByClass[4] = {
      Counter::raster_samples_tested_2d, Counter::raster_samples_tested_3d,
      Counter::raster_samples_tested_4d, Counter::raster_samples_tested_5d};

  // The sample kernel's per-triangle constants, derived from the vertex data ([Toth 2008] §9.6): the
  // static shear coefficients (4D) or the motion deltas (3D, 5D). Costs kRederiveShear / Motion.
  void rederive(const TriSetup& tri, std::uint64_t& ops) const {
    if (tri.cls == DimClass::k4D) {
      for (int j = 0; j < 3; ++j) {
        const F cx = madd(F(tri.W[j]), F(f_.fc.kx), F(f_.fc.neg_kx_f));
        const F cy = madd(F(tri.W[j]), F(f_.fc.ky), F(f_.fc.neg_ky_f));
        sink_ = raw(cx) + raw(cy);
      }
      charge<A>(ops, cost::gpu::kRederiveShear);
    } else if (tri.moving) {
      for (int j = 0; j < 3; ++j) {
        const F X1 = F(tri.X[j] + tri.dX[j]), Y1 = F(tri.Y[j] + tri.dY[j]), W1 = F(tri.W[j] + tri.dW[j]);
        sink_ = raw(X1 - F(tri.X[j])) + raw(Y1 - F(tri.Y[j])) + raw(W1 - F(tri.W[j]));
      }
      charge<A>(ops, cost::gpu::kRederiveMotion);
    }
  }

  void account(const TriSetup& tri, const Bound& b, std::uint64_t gs_ops, std::uint64_t raster_setup_ops) {
    ++c_[Counter::gpu_gs_triangles_in];
    c_[Counter::gpu_gs_vertices] += static_cast<std::uint64_t>(b.out_vertices);
    c_[Counter::gpu_gs_triangles] += static_cast<std::uint64_t>(b.out_triangles);
    const std::uint64_t strip = static_cast<std::uint64_t>(b.out_triangles) + 2;
    const std::uint64_t P = static_cast<std::uint64_t>(payload_floats(f_.p, tri));
    std::uint64_t floats = 0;
    switch (f_.p.gpu_constants) {
      case GpuConstants::kNone: floats = strip * (4 + P); break;
      case GpuConstants::kTriangle: floats = strip * 4 + static_cast<std::uint64_t>(b.out_triangles) * P; break;
      case GpuConstants::kStrip: floats = strip * 4 + P; break;
    }
    c_[Counter::gpu_gs_floats] += floats;
    c_[Counter::gpu_gs_ops] += gs_ops;
    c_[Counter::ops_setup] += gs_ops;
    c_[Counter::ops_tile] += raster_setup_ops;
    const double area = std::min(b.area, 1e15);
    c_[Counter::gpu_bound_area] += static_cast<std::uint64_t>(std::llround(std::max(0.0, area) * 1000.0));
    switch (b.fallback) {
      case Fallback::kNone: break;
      case Fallback::kNear: ++c_[Counter::gpu_fallback_near]; break;
      case Fallback::kMotion: ++c_[Counter::gpu_fallback_motion]; break;
      case Fallback::kDegenerate: ++c_[Counter::gpu_fallback_degenerate]; break;
      case Fallback::kVR: ++c_[Counter::gpu_fallback_vr]; break;
      case Fallback::kReduced: ++c_[Counter::gpu_fallback_reduced]; break;
    }
    if (b.volume_clipped) ++c_[Counter::gpu_volume_clipped];
    if (kMethod == Method::kAdaptive && !tri.moving && !tri.near_clipped) {
      if (b.used == Method::kPETriangle) ++c_[Counter::gpu_adaptive_pe];
      if (b.used == Method::kHexagon2D) ++c_[Counter::gpu_adaptive_hexagon];
    }
  }

  const Frame& f_;
  Counters& c_;
  SamplePipeline<A> pipe_;
  DepthCull<A, SamplePipeline<A>> zcull_;
  GeometryShader<A> gs_;
  std::vector<std::pair<int, int>> frags_;  // the fragments of one HiZ tile
  mutable float sink_ = 0.0f;
};

}  // namespace rast5d::gpu
