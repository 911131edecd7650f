// LINES ([Tzeng 2012] §3-4): line samples in the lens instead of point samples.
// The table is a line table (SampleTable.lines): sample s of a pixel is a screen point (x, y) and
// a line direction (u, v) = (cos θ, sin θ) through the lens centre; consecutive lines with the same
// screen point form a wagon wheel and share the lens-space setup ([Tzeng 2012] §3.1.1). For every pixel of
// the triangle's bounds in the bin and every line, the analytic interval of the line inside the
// triangle (lines/coverage.h) becomes a segment, shaded at its midpoint and offered to the line's
// segment buffer (lines/segment_buffer.h). When the bin's triangles are done, end_bin() composites
// each line (κ-weighted, [Tzeng 2012] §3.1.2) into the bin's sample colours, which resolve() averages.
// With pipeline.lines.tile_clip the triangle's h_i lens region of each screen tile ([Akenine-Möller 2012] §4.2)
// first tells which lines can meet the triangle there; the others skip the test: the same image,
// but for float32 slivers of the line test outside the exact coverage on sub-pixel triangles, which
// the clip may drop (each of κ < 1e-4; docs/op_costs.md, test_tile_clip_drops_only_rounding_slivers).
//
// Texturing: the segment's colour is textured at its midpoint, at the uv of the midpoint's hit point
// and the triangle's texture level of detail (backend/texture.h: the analytic screen -> uv map, as
// for a point sample), through the texture unit. With a shading mode, each shaded segment is a
// shader lane of the shading model (backend/shading.h): per_sample, a lane per segment (quads of
// one line index over 2x2 pixels); msaa, a lane per pixel per visit; cache, the shading cache keyed
// by the midpoint's hit point seen through the lens centre. Its texel fetches go to the bin's
// texture-cache stream, like a point sample's; a visit is the triangle's pass over its pixels in
// the bin (as BRUTEFORCE's). The modes count work only; the image is the same in every mode.
// Static triangles only (depth of field, 4D and in-focus 2D): motion blur needs point samples.
// Not modelled for line samples: lens-cell shading (per_lens_cell), per-sample depth export.
// Counters: lines.*, ops.sample_inside (setups and tests), ops.sample_region (tile clip),
// ops.tile and ops.setup (tile clip's h_i lines), ops.interp (segment shading), ops.segments;
// with a shading mode shade.* and tex.* (backend/shading.h).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "lines/coverage.h"
#include "lines/segment_buffer.h"
#include "setup/footprint.h"
#include "tiletest/halfspace_lens.h"
#include "traversal/traversal.h"

namespace rast5d {
namespace {

template <class A>
class Lines final : public Traversal {
  using F = typename A::f32;
  using D = typename A::f64;

 public:
  Lines(const Frame& f, ThreadState& ts) : f_(f), c_(ts.counters), buf_(ts.buffers), sh_(ts.shade), ts_(ts) {
    const RenderParams& p = f.p;
    rules_.capacity = p.lines_buffer_size;
    rules_.min_weight = static_cast<float>(p.lines_min_weight);
    rules_.occlusion = p.lines_occlusion;
    rules_.merge = p.lines_merge;
    rules_.merge_depth = static_cast<float>(p.lines_merge_depth);
    rules_.merge_color2 = static_cast<float>(p.lines_merge_color * p.lines_merge_color);
    rules_.merge_gap = static_cast<float>(p.lines_merge_gap);
  }

  void rasterize(const TriSetup& tri, const BinRect& bin, bool charge_setup) override {
    if (tri.moving)
      throw std::invalid_argument("algorithm: 'lines' renders static triangles only (depth of field); triangle " +
                                  std::to_string(tri.index) +
                                  " moves during the shutter: motion blur needs point samples");
    open_bin(bin);
    const RenderParams& p = f_.p;
    const int x0 = std::max(tri.bx0, bin.x0), x1 = std::min(tri.bx1, bin.x1);
    const int y0 = std::max(tri.by0, bin.y0), y1 = std::min(tri.by1, bin.y1);
    if (!p.lines_tile_clip) {
      for (int py = y0; py < y1; ++py)
        for (int px = x0; px < x1; ++px) pixel(tri, px, py, nullptr);
      end_visit();
      return;
    }
    std::uint64_t setup_ops = 0;
    const Footprint fp = build_footprint<A>(tri, f_, false, setup_ops);
    if (charge_setup) c_[Counter::ops_setup] += setup_ops;
    const int T = p.tile_size;
    for (int ty = (y0 / T) * T; ty < y1; ty += T)
      for (int tx = (x0 / T) * T; tx < x1; tx += T) {
        Boxes boxes;
        bool clip = fp.h_valid && tri.defocused;
        if (clip) {
          ++c_[Counter::tile_visited];
          tiletest::AxisSet sx, sy;
          const bool any = tile_h_sets<A>(fp, tiletest::expand_lo(tx), tiletest::expand_hi(tx + T),
                                          tiletest::expand_lo(ty), tiletest::expand_hi(ty + T), sx, sy,
                                          c_[Counter::ops_tile]);
          if (!any) {
            ++c_[Counter::tile_culled_h];
            for (int py = std::max(ty, y0); py < std::min(ty + T, y1); ++py)
              for (int px = std::max(tx, x0); px < std::min(tx + T, x1); ++px)
                c_[Counter::lines_culled_tile] += static_cast<std::uint64_t>(f_.table.spp());
            continue;
          }
          ++c_[Counter::tile_accepted];
          widen_boxes(sx, sy, boxes);
        }
        for (int py = std::max(ty, y0); py < std::min(ty + T, y1); ++py)
          for (int px = std::max(tx, x0); px < std::min(tx + T, x1); ++px)
            pixel(tri, px, py, clip && !boxes.all_lines ? &boxes : nullptr);
      }
    end_visit();
  }

  void end_bin(const BinRect& bin) override {
    if (!open_ || bin.x0 != bin_.x0 || bin.y0 != bin_.y0) return;
    const int spp = f_.table.spp();
    std::uint64_t ops = 0, steps = 0;
    const F neg_near = F(f_.fc.neg_near);
    for (int py = bin_.y0; py < bin_.y1; ++py)
      for (int px = bin_.x0; px < bin_.x1; ++px)
        for (int s = 0; s < spp; ++s) {
          const std::size_t slot = buf_.slot(px, py, s);
          std::vector<Segment>& segs = segs_[slot];
          if (segs.empty()) continue;
          float col[3];
          ops += composite_line<F>(segs, neg_near, scratch_, col, steps);
          float* dst = buf_.color(slot);
          for (int ch = 0; ch < 3; ++ch) dst[ch] = col[ch];
          segs.clear();
        }
    charge<A>(c_[Counter::ops_segments], ops);
    c_[Counter::lines_composite_steps] += steps;
    open_ = false;
  }

 private:
  struct Boxes {
    int n = 0;
    bool all_lines = false;  // a box holds the lens centre
    float lo[4]{}, hi[4]{};  // pseudo-angle interval of the lines meeting each box
    bool shifted[4]{};
  };

  void open_bin(const BinRect& bin) {
    if (open_ && bin.x0 == bin_.x0 && bin.y0 == bin_.y0) return;
    bin_ = bin;
    open_ = true;
    const std::size_t n = static_cast<std::size_t>(bin.x1 - bin.x0) * (bin.y1 - bin.y0) * f_.table.spp();
    if (segs_.size() < n) segs_.resize(n);
  }

  // The uv-boxes of the tile (products of the u and v intervals), widened outwards so that float
  // rounding never skips a line that meets the exact region, as intervals of line directions.
  void widen_boxes(const tiletest::AxisSet& sx, const tiletest::AxisSet& sy, Boxes& b) {
    b.n = 0;
    b.all_lines = false;
    for (int i = 0; i < sx.n_intervals; ++i)
      for (int j = 0; j < sy.n_intervals; ++j) {
        const F e = F(kWiden);
        const F u0 = F(static_cast<float>(sx.iv_lo[i])) - e, u1 = F(static_cast<float>(sx.iv_hi[i])) + e;
        const F v0 = F(static_cast<float>(sy.iv_lo[j])) - e, v1 = F(static_cast<float>(sy.iv_hi[j])) + e;
        // Every line passes through the lens centre: a box holding it meets every line.
        const F z(0.0f);
        const bool l = u0 <= z, r = u1 >= z, d = v0 <= z, u = v1 >= z;
        std::uint64_t ops = cost::kLineBoxWiden + cost::kLineBoxCentre;
        if (l && r && d && u) {
          b.all_lines = true;
        } else {
          F lo, hi;
          bool shifted;
          ops += box_angles(u0, u1, v0, v1, lo, hi, shifted);
          b.lo[b.n] = raw(lo), b.hi[b.n] = raw(hi), b.shifted[b.n] = shifted;
          ++b.n;
        }
        charge<A>(c_[Counter::ops_tile], ops);
      }
  }

  void pixel(const TriSetup& tri, int px, int py, const Boxes* boxes) {
    if constexpr (!A::counting) {
      pixel_batched(tri, px, py, boxes);
      return;
    }
    const PixelSamples ps = f_.table.pixel(px, py);
    const int spp = f_.table.spp();
    const F neg_near = F(f_.fc.neg_near);
    const bool near_fn = tri.near_clipped;
    const bool bfc = f_.p.backface_cull;
    LinePoint<F> q;
    bool have_q = false;
    float qx = 0.0f, qy = 0.0f;
    for (int s = 0; s < spp; ++s) {
      const float c = ps.u[s], sn = ps.v[s];
      if (boxes) {  // tile clip: does the line's direction fall in a box's interval?
        float a;
        pseudo_angle(c, sn, a);  // a table constant of the line (free)
        bool meets = false;
        std::uint64_t box_ops = 0;
        for (int k = 0; k < boxes->n && !meets; ++k) {
          const F la = F(boxes->shifted[k] && a < 1.0f ? a + 2.0f : a);
          const bool in_lo = F(boxes->lo[k]) <= la;
          const bool in_hi = la <= F(boxes->hi[k]);
          meets = in_lo && in_hi;
          box_ops += cost::kLineAngleTest;
        }
        charge<A>(c_[Counter::ops_sample_region], box_ops);
        if (!meets) {
          ++c_[Counter::lines_culled_tile];
          continue;
        }
      }
      const float sx = static_cast<float>(px) + ps.x[s], sy = static_cast<float>(py) + ps.y[s];
      if (!have_q || sx != qx || sy != qy) {  // a new wheel: its screen point's lens-space setup
        line_point_setup(tri.X, tri.Y, tri.W, tri.cx, tri.cy, F(sx), F(sy), neg_near, q);
        charge<A>(c_[Counter::ops_sample_inside], cost::kLinePointSetup);
        ++c_[Counter::lines_point_setups];
        have_q = true, qx = sx, qy = sy;
      }
      LineCoverage<F> cov;
      const std::uint64_t test_ops = line_interval(q, F(c), F(sn), near_fn, bfc, cov);
      charge<A>(c_[Counter::ops_sample_inside], test_ops);
      ++c_[Counter::lines_tests];
      for (int k = 0; k < cov.n; ++k) offer(tri, cov, cov.lo[k], cov.hi[k], px, py, s, k);
    }
  }

  // pixel() on the fast path: the tile clip's angle test per line as there, then the lines that pass,
  // up to LineBatch::kLanes at a time, through line_intervals_batch (vectorised over lines; the same
  // figures), then their segments offered in line order.
  void pixel_batched(const TriSetup& tri, int px, int py, const Boxes* boxes) {
    const PixelSamples ps = f_.table.pixel(px, py);
    const int spp = f_.table.spp();
    const float neg_near = f_.fc.neg_near;
    bool have_q = false;
    float qx = 0.0f, qy = 0.0f;
    int line[LineBatch::kLanes], meets[LineBatch::kLanes], tested[LineBatch::kLanes];
    std::uint64_t setups = 0, test_ops = 0, box_ops = 0, culled = 0;
    for (int base = 0; base < spp; base += LineBatch::kLanes) {
      const int m = std::min(LineBatch::kLanes, spp - base);
      if (boxes) {  // tile clip: does the line's direction fall in a box's interval?
        lines_meet_boxes(ps.u + base, ps.v + base, m, boxes->n, boxes->lo, boxes->hi, boxes->shifted, meets, tested);
        for (int j = 0; j < m; ++j) box_ops += cost::kLineAngleTest * static_cast<std::uint64_t>(tested[j]);
      }
      int n = 0;
      for (int j = 0; j < m; ++j) {
        if (boxes && !meets[j]) {
          ++culled;
          continue;
        }
        const int s = base + j;
        const float sx = static_cast<float>(px) + ps.x[s], sy = static_cast<float>(py) + ps.y[s];
        if (!have_q || sx != qx || sy != qy) ++setups, have_q = true, qx = sx, qy = sy;  // a new wheel
        batch_.sx[n] = sx, batch_.sy[n] = sy, batch_.c[n] = ps.u[s], batch_.s[n] = ps.v[s], line[n] = s;
        ++n;
      }
      if (n) test_batch(tri, px, py, n, line, neg_near, test_ops);
    }
    charge<A>(c_[Counter::ops_sample_region], box_ops);
    c_[Counter::lines_culled_tile] += culled;
    charge<A>(c_[Counter::ops_sample_inside], setups * cost::kLinePointSetup + test_ops);
    c_[Counter::lines_point_setups] += setups;
  }

  void test_batch(const TriSetup& tri, int px, int py, int n, const int* line, float neg_near, std::uint64_t& ops) {
    if (tri.near_clipped)
      line_intervals_batch<true>(tri.X, tri.Y, tri.W, tri.cx, tri.cy, neg_near, f_.p.backface_cull, n, batch_);
    else
      line_intervals_batch<false>(tri.X, tri.Y, tri.W, tri.cx, tri.cy, neg_near, f_.p.backface_cull, n, batch_);
    const int n_fns = tri.near_clipped ? 5 : 4;
    c_[Counter::lines_tests] += static_cast<std::uint64_t>(n);
    for (int i = 0; i < n; ++i) {
      ops += cost::line_interval_cost(n_fns, batch_.nflat[i]);
      if (!batch_.nseg[i]) continue;
      LineCoverage<F> cov;
      cov.n = batch_.nseg[i];
      for (int k = 0; k < 3; ++k) cov.fn.e0[k] = F(batch_.fn[k][i]), cov.fn.eg[k] = F(batch_.fn[3 + k][i]);
      cov.fn.d0 = F(batch_.fn[6][i]), cov.fn.dg = F(batch_.fn[7][i]);
      cov.fn.s0 = F(batch_.fn[8][i]), cov.fn.sg = F(batch_.fn[9][i]);
      for (int k = 0; k < cov.n; ++k) cov.lo[k] = batch_.lo[k][i], cov.hi[k] = batch_.hi[k][i];
      for (int k = 0; k < cov.n; ++k) offer(tri, cov, cov.lo[k], cov.hi[k], px, py, line[i], k);
    }
  }

  // A segment [a, b] of the line: the heuristics in [Tzeng 2012] §4.1's order (occlusion, merge, length),
  // shading at the midpoint, the buffer.
  void offer(const TriSetup& tri, const LineCoverage<F>& cov, float a, float b, int px, int py, int s, int k_seg) {
    const std::size_t slot = buf_.slot(px, py, s);
    ++c_[Counter::lines_segments];
    const LineFns<F>& fn = cov.fn;
    const F neg_near = F(f_.fc.neg_near);
    std::uint64_t ops = cost::kSegNew;
    Segment sg{};
    sg.a = a, sg.b = b;
    const F k = kappa(F(a), F(b));
    sg.k = raw(k);
    const F za = line_depth(fn.s0, fn.sg, fn.d0, fn.dg, F(a), neg_near);
    const F zb = line_depth(fn.s0, fn.sg, fn.d0, fn.dg, F(b), neg_near);
    sg.zmin = raw(vmin(za, zb)), sg.zmax = raw(vmax(za, zb));
    sg.s0 = raw(fn.s0), sg.sg = raw(fn.sg), sg.d0 = raw(fn.d0), sg.dg = raw(fn.dg);
    std::vector<Segment>& buf = segs_[slot];
    if (rules_.occlusion && !segment_visible<F>(buf, sg, ops, c_)) {
      charge<A>(c_[Counter::ops_segments], ops);
      ++c_[Counter::lines_rejected_occluded];
      return;
    }
    charge<A>(c_[Counter::ops_segments], ops);
    ops = 0;
    // Shade at the midpoint (ops.interp, as a covered point sample's depth and colour).
    {
      const F m = (F(a) + F(b)) * F(0.5f);
      F z, col[3];
      float bary[3];
      line_shade(fn, m, neg_near, tri.color, z, col, bary);
      sg.zmid = raw(z);
      for (int ch = 0; ch < 3; ++ch) sg.col[ch] = raw(col[ch]);
      charge<A>(c_[Counter::ops_interp], cost::kLineShade);
      if (const ShadeFrame* sf = sh_.frame(); sf && (sh_.counting() || sf->texture_count > 0))
        shade_segment(*sf, tri, bary, px, py, s, k_seg, sg.col);
    }
    if (rules_.merge && segment_merge<F>(buf, sg, rules_, ops)) {
      ++c_[Counter::lines_segments_merged];
    } else {
      // Length: a segment that merged nowhere and is too small to matter is dropped.
      const bool small = k < F(rules_.min_weight);
      ++ops;
      if (small) {
        ++c_[Counter::lines_rejected_small];
      } else {
        segment_insert<F>(buf, sg, rules_.capacity, ops, c_);
      }
    }
    charge<A>(c_[Counter::ops_segments], ops);
  }

  // Texture the segment's midpoint colour and hand the segment to the open shading visit, as
  // backend/sample_backend.h does for a covered point sample: uv from the midpoint's barycentrics,
  // the triangle's level of detail per texture slot, the texture unit's filter (not counted in ops:
  // the texture unit's work is tex.fetches, as for points). The record's sample index is 2 s + k,
  // k the segment's index on its line (a triangle cuts a line in at most two segments), so in
  // per_sample mode every shaded segment is its own lane.
  void shade_segment(const ShadeFrame& sf, const TriSetup& tri, const float b[3], int px, int py, int s, int k,
                     float col[3]) {
    ShadeState::Rec r{px, py, 2 * s + k, 0, 0.0f, 0.0f, 0.0f, 0.0f};
    if (sf.mode == ShadingMode::kCache) {  // the hit point seen through the lens centre
      const float X = b[0] * tri.X[0] + b[1] * tri.X[1] + b[2] * tri.X[2];
      const float Y = b[0] * tri.Y[0] + b[1] * tri.Y[1] + b[2] * tri.Y[2];
      const float W = b[0] * tri.W[0] + b[1] * tri.W[1] + b[2] * tri.W[2];
      r.gx = X / W, r.gy = Y / W;
    }
    if (sf.texture_count > 0) {
      const float* uv = &sf.uvs[static_cast<std::size_t>(tri.index) * 6];
      r.u = b[0] * uv[0] + b[1] * uv[2] + b[2] * uv[4];
      r.v = b[0] * uv[1] + b[1] * uv[3] + b[2] * uv[5];
      for (int t = 0; t < sf.texture_count; ++t) {
        const int id = sf.tex_ids[static_cast<std::size_t>(tri.index) * kMaxTexSlots + t];
        if (id < 0) continue;
        float tc[3];
        sf.textures.sample(id, sf.lod[static_cast<std::size_t>(tri.index) * kMaxTexSlots + t], sf.filter, r.u, r.v,
                           tc);
        for (int ch = 0; ch < 3; ++ch) col[ch] *= tc[ch];
      }
    }
    if (sh_.counting()) sh_.record(tri.index, r);
  }

  // The end of the triangle's shading visit in this bin (SamplePipeline::end_visit's protocol):
  // its segments' shading work is counted now, and the observers of visits hear of it. Without a
  // shading model a triangle's line tests in a bin are one visit (its end is the triangle's end).
  void end_visit() {
    if (!sh_.counting()) return;
    sh_.close_visit();
    if (ts_.observers.wants_visits()) ts_.observers.end_visit();
  }

  static constexpr float kWiden = 1e-4f;

  const Frame& f_;
  Counters& c_;
  BinBuffers& buf_;
  ShadeState& sh_;
  ThreadState& ts_;
  SegmentRules rules_;
  BinRect bin_{};
  bool open_ = false;
  std::vector<std::vector<Segment>> segs_;
  LineBatch batch_;  // pixel_batched: the lines of a pixel under test
  std::vector<float> scratch_;
};

}  // namespace

RAST5D_REGISTER_TRAVERSAL("lines",
                          "Line samples in the lens ([Tzeng 2012] §3-4): analytic line-triangle intervals, segment "
                          "buffers with heuristics, κ-weighted composite; needs a line table "
                          "(SampleTable.lines), static triangles only",
                          TableKinds::kLines, PipelineKind::kSample, Lines);

}  // namespace rast5d
