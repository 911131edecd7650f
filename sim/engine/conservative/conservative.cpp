#include "conservative/conservative.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include "intervals/clip.h"
#include "intervals/depth_interval.h"
#include "intervals/time_interval.h"
#include "setup/footprint.h"
#include "core/validate.h"
#include "tiletest/edges_2d.h"
#include "sampletest/precision.h"
#include "tiletest/halfspace_lens.h"
#include "tiletest/precision_4d.h"
#include "intervals/precision_5d.h"

namespace rast5d {

ConservativeResult conservative_raster(const RenderParams& p, const SceneArrays& scene, bool reduce,
                                       std::uint64_t max_records) {
  using A = FastArith;
  using D = double;
  validate_frame_params(p);
  const FrameConst fc = make_frame_const(p);
  // build_footprint needs a Frame; without H_j lines it never reads the table.
  const float one_sample[5] = {0.5f, 0.5f, 0.0f, 0.0f, 0.0f};
  const SampleTable table(1, 1, one_sample, p.lens_grid, nullptr, 0, nullptr);
  const Frame frame{p, fc, table};
  const iv::ClipBox clip = iv::clip_box(p);
  ConservativeResult out;
  Counters& c = out.counters;
  const std::size_t npix = static_cast<std::size_t>(p.width) * p.height;
  if (reduce) {
    out.tz_box.resize(npix * 4);
    for (std::size_t i = 0; i < npix; ++i) {
      out.tz_box[4 * i + 0] = out.tz_box[4 * i + 1] = std::numeric_limits<float>::infinity();
      out.tz_box[4 * i + 2] = out.tz_box[4 * i + 3] = -std::numeric_limits<float>::infinity();
    }
    out.count.assign(npix, 0);
  }
  iv::MotionSetup ms;
  iv::TileIntervals ti;
  iv::MovingPlanes planes;
  // pipeline.precision.tile (not float64): the tile tests decided in the format (tiletest/precision_4d.h,
  // precision_5d.h), tiles widened by the fixed-point snapping as in a render (restored on return)
  const bool prec = p.precision_tile.kind != PrecisionKind::kFloat64;
  const tiletest::ScopedSnapMargin snap_margin(snap_margin_px(p.precision_sample, p.precision_tile));
  tiletest::Tile4DPrecision p4;
  tiletest::Motion5DPrecision p5;
  const double lens_lo = -1.0, lens_hi = 1.0;  // in focus / no blur: every lens point
  for (int i = 0; i < scene.n; ++i) {
    TriSetup tri;
    const float* v0 = scene.v0 + static_cast<std::size_t>(i) * 9;
    const float* v1 = scene.v1 + static_cast<std::size_t>(i) * 9;
    const float* col = scene.colors + static_cast<std::size_t>(i) * 9;
    if (!setup_triangle<A>(v0, v1, col, static_cast<std::uint32_t>(i), p, fc, tri, c)) continue;
    std::uint64_t sops = 0;
    iv::moving_planes<A>(tri, planes, sops);
    c[Counter::ops_zhat] += sops;
    Footprint fp;
    tiletest::Edges2D e2{};
    if (tri.cls == DimClass::k2D) {
      e2 = tiletest::edges_2d<D>(tri.X, tri.Y, tri.W);
      if (prec) e2 = tiletest::edges_2d_in<D>(p.precision_tile, tri.X, tri.Y, tri.W);
    } else if (tri.moving) {
      iv::motion_setup<A>(tri, fc, p.time_splits, ms, sops);
      if (prec) p5.setup(p.precision_tile, ms, 0.5 * fc.near_d, nullptr);
    } else {
      fp = build_footprint<A>(tri, frame, false, sops);
      if (prec && fp.h_valid) p4.setup(p.precision_tile, fp.lv, fp.n, nullptr, false);
    }
    c[Counter::ops_setup] += sops;
    for (int py = tri.by0; py < tri.by1; ++py)
      for (int px = tri.bx0; px < tri.bx1; ++px) {
        ++c[Counter::conservative_pixels_tested];
        const double x0 = tiletest::expand_lo(px), x1 = tiletest::expand_hi(px + 1);
        const double y0 = tiletest::expand_lo(py), y1 = tiletest::expand_hi(py + 1);
        double u0 = lens_lo, u1 = lens_hi, w0 = lens_lo, w1 = lens_hi, t0 = 0.0, t1 = 1.0;
        bool lens = tri.defocused;
        if (tri.cls == DimClass::k2D) {
          bool out2 = tiletest::tile_outside_2d<D>(e2, x0, x1, y0, y1);
          if (prec) {  // the decision in pipeline.precision.tile (counted as the float64 form)
            bool ovf;
            out2 = tiletest::tile_outside_2d_in<D>(e2, x0, x1, y0, y1, ovf);
            if (ovf) ++c[Counter::precision_tile_overflows];
          }
          if (out2 || !e2.valid) continue;
        } else if (tri.moving) {
          bool keep = iv::motion_tile_intervals<A>(ms, clip, tri.cls, x0, x1, y0, y1, ti, c[Counter::ops_tile], c);
          if (prec) {  // the decision in pipeline.precision.tile (counted as the float64 form)
            bool ovf;
            keep = p5.tile_intervals(clip, x0, x1, y0, y1, ti, true, ovf);
            if (ovf) ++c[Counter::precision_tile5d_overflows];
          }
          if (!keep) continue;
          if (lens) u0 = ti.u0, u1 = ti.u1, w0 = ti.v0, w1 = ti.v1;
          t0 = ti.t0, t1 = ti.t1;
        } else {
          tiletest::AxisSet sx = tiletest::full_axis(), sy = tiletest::full_axis();
          bool keep = !fp.h_valid || tile_h_sets<A>(fp, x0, x1, y0, y1, sx, sy, c[Counter::ops_tile]);
          if (prec && fp.h_valid) {  // the decision in pipeline.precision.tile (counted as the float64 form)
            bool ovf;
            keep = p4.h_sets(x0, x1, y0, y1, sx, sy, ovf);
            if (ovf) ++c[Counter::precision_tile4d_overflows];
          }
          if (!keep) continue;
          if (!iv::clip_lens<A>(clip, sx, sy, c[Counter::ops_tile])) continue;
          u0 = sx.iv_lo[0], u1 = sx.iv_hi[sx.n_intervals - 1];
          w0 = sy.iv_lo[0], w1 = sy.iv_hi[sy.n_intervals - 1];
        }
        if (!tri.moving) {  // static: every time of the (clipped) shutter
          t0 = std::max(0.0, clip.t_lo), t1 = std::min(1.0, clip.t_hi);
          if (t1 < t0) continue;
        }
        if (!lens) {  // in focus: every lens point of the clip box
          u0 = std::max(-1.0, clip.u_lo), u1 = std::min(1.0, clip.u_hi);
          w0 = std::max(-1.0, clip.v_lo), w1 = std::min(1.0, clip.v_hi);
        }
        const iv::ZHat z = iv::zhat<A>(tri, p.zhat == ZhatMode::kPlanes ? &planes : nullptr, fc, lens, x0, x1, y0,
                                       y1, u0, u1, w0, w1, std::max(0.0, t0), std::min(1.0, t1),
                                       c[Counter::ops_zhat]);
        ++c[Counter::conservative_records];
        double zlo = z.zlo, zhi = z.zhi;
        if (prec) tiletest::zhat_round_out(p.precision_tile, zlo, zhi);  // outward to the format
        // Round outwards to float.
        const float zl = tiletest::round_down_to_float(zlo), zh = tiletest::round_up_to_float(zhi);
        const float tl = tiletest::round_down_to_float(t0), th = tiletest::round_up_to_float(t1);
        if (reduce) {
          const std::size_t k = static_cast<std::size_t>(py) * p.width + px;
          float* b = &out.tz_box[4 * k];
          b[0] = std::min(b[0], tl), b[1] = std::min(b[1], zl), b[2] = std::max(b[2], th), b[3] = std::max(b[3], zh);
          ++out.count[k];
        } else {
          if (out.records.size() >= max_records)
            throw std::length_error("conservative_raster: more than max_records=" + std::to_string(max_records) +
                                    " fragment records; use reduce='tz_box' or raise max_records");
          out.records.push_back(ConservativeRecord{px, py, static_cast<std::int32_t>(i),
                                                   tiletest::round_down_to_float(u0), tiletest::round_up_to_float(u1),
                                                   tiletest::round_down_to_float(w0), tiletest::round_up_to_float(w1),
                                                   tl, th, zl, zh});
        }
      }
  }
  return out;
}

}  // namespace rast5d
