// TILE ([Akenine-Möller 2012] §4-§5.1, "OUR"): visit the triangle's screen tiles once each; per
// tile, the h_i lines give uv-boxes (the active u and v sets), the H_j lines give a conservative
// bitmask over the lens-grid cells, and only samples in surviving cells whose (u, v) passes the
// h_i lines are inside-tested. TILE_INTERLEAVED ("OUR (i)") is the same traversal on an
// interleaved sample table, with the 2D inside test on the triangle pre-sheared to each of the N
// lens coordinates in setup.
//
// Triangle classes: 2D (static, in focus) uses the standard tile vs triangle test (edge functions
// at the tile corners and the bounding box, tiletest/edges_2d.h); 4D (static, defocused) the full
// h_i + H_j test; moving triangles (3D/5D, [Nilsson 2012] §2): per time sub-interval a
// conservative t̂ and, for 5D, lens sets from the h_i lines over the sub-interval's end vertices
// (intervals/time_interval.h); samples are selected through the (lens cell, time stratum) index of
// the table. With motion_test 'bounds', moving triangles take the h_i lines over the 6 shutter-end
// vertices, no H_j, no t̂ (counted in trav.motion_fallback). Every accepted pair may be depth-culled
// against HiZ with ẑ, and occlusion queries use the same ẑ (backend/zcull.h).
#include <algorithm>
#include <vector>

#include "backend/zcull.h"
#include "intervals/clip.h"
#include "intervals/time_interval.h"
#include "setup/footprint.h"
#include "tiletest/candidates.h"
#include "tiletest/edges_2d.h"
#include "traversal/exact_region.h"
#include "intervals/halfspace_5d.h"
#include "tiletest/halfspace_edges.h"
#include "tiletest/halfspace_lens.h"
#include "tiletest/lens_shape.h"
#include "tiletest/precision_4d.h"
#include "intervals/precision_5d.h"
#include "traversal/algorithms/tile/active_cells.h"
#include "traversal/algorithms/tile/axis_cache.h"
#include "traversal/algorithms/tile/hj_cells.h"
#include "traversal/traversal.h"

namespace rast5d {
namespace {

template <class A, bool kInterleaved>
class Tile final : public Traversal {
  using D = typename A::f64;
  using F = typename A::f32;

 public:
  static constexpr bool kDepthCull = true;
  Tile(const Frame& f, ThreadState& ts)
      : f_(f), c_(ts.counters), pipe_(f, ts), zcull_(f, ts.counters, ts.buffers, pipe_),
        lens_mask_(tiletest::lens_cells(f.p.lens_shape, f.p.lens_grid)) {
    for (int c = 0; c < 64; ++c) {
      low64_.set(c);
      if (lens_mask_.test(c)) lens_mask64_ |= std::uint64_t(1) << c;
    }
  }

  void rasterize(const TriSetup& tri, const BinRect& bin, bool charge_setup) override {
    zcull_.begin_triangle(tri, charge_setup);
    if (zcull_.query_answered()) return;  // interval-based query already answered: abort
    rasterize_tri(tri, bin, charge_setup);
    zcull_.end_triangle();
  }

 private:
  void rasterize_tri(const TriSetup& tri, const BinRect& bin, bool charge_setup) {
    std::uint64_t setup_ops = 0;
    if (tri.cls == DimClass::k2D) {
      const tiletest::Edges2D e = tiletest::edges_2d_in<D>(f_.p.precision_tile, tri.X, tri.Y, tri.W);
      if (f_.p.cost_model == CostModel::kHardware)
        discard<A>();  // the hardware model sets these edges up once in triangle setup (sample test)
      else
        charge<A>(setup_ops, cost::kEdges2DSetup);
      if (charge_setup) c_[Counter::ops_setup] += setup_ops;
      raster_2d(tri, e, bin);
      return;
    }
    if (tri.moving && f_.p.motion_test == MotionTest::kIntervals && !kInterleaved) {
      iv::motion_setup<A>(tri, f_.fc, f_.p.time_splits, ms_, setup_ops);
      if (f_.p.halfspace_H5) {  // H5 planes per sub-interval (intervals/halfspace_5d.h)
        tiletest::h5_setup<A>(ms_, f_.fc, h5_oracle(tri), h5_, setup_ops);
        if (charge_setup) c_[Counter::tile_H5_sub_unoriented] += static_cast<std::uint64_t>(h5_.n_unoriented);
      }
      if (f_.p.precision_tile.kind != PrecisionKind::kFloat64)  // t̂, lens sets, H5 in the format (precision_5d.h)
        p5_.setup(f_.p.precision_tile, ms_, 0.5 * f_.fc.near_d, f_.p.halfspace_H5 ? &h5_ : nullptr);
      if (charge_setup) c_[Counter::ops_setup] += setup_ops;
      raster_motion(tri, bin);
      return;
    }
    const Footprint fp = build_footprint<A>(tri, f_, f_.p.halfspace_H, setup_ops);
    if (f_.p.precision_tile.kind != PrecisionKind::kFloat64) {  // the 4D test in pipeline.precision.tile
      bool active[6];
      for (int k = 0; k < 6; ++k) active[k] = k < fp.n_edges && fp.edges[k].active;
      p4_.setup(f_.p.precision_tile, fp.lv, fp.n, active, f_.p.halfspace_H && !tri.moving);
    }
    if (kInterleaved && !tri.moving) shear_lens_positions(tri, setup_ops);
    if (charge_setup) {
      c_[Counter::ops_setup] += setup_ops;
      c_[Counter::setup_H_edges_enabled] += fp.edges_enabled;
      c_[Counter::setup_H_edges_disabled] += fp.edges_disabled;
      if (tri.moving) ++c_[Counter::trav_motion_fallback];
      if (!tri.moving && f_.p.halfspace_H && fp.sigma == 0) ++c_[Counter::tile_H_split_orientation];
    }
    raster_lens(tri, fp, bin);
  }

  // Shear the static triangle to every discrete lens coordinate (OUR (i) setup cost).
  void shear_lens_positions(const TriSetup& tri, std::uint64_t& ops) {
    const int n = f_.table.n_lens();
    sx_.resize(static_cast<std::size_t>(n) * 3);
    sy_.resize(static_cast<std::size_t>(n) * 3);
    F X[3], Y[3], cx[3], cy[3], Xs[3], Ys[3];
    for (int j = 0; j < 3; ++j) X[j] = F(tri.X[j]), Y[j] = F(tri.Y[j]), cx[j] = F(tri.cx[j]), cy[j] = F(tri.cy[j]);
    for (int i = 0; i < n; ++i) {
      shear_static(X, Y, cx, cy, F(f_.table.lens_u(i)), F(f_.table.lens_v(i)), Xs, Ys);
      charge<A>(ops, cost::kShear);
      for (int j = 0; j < 3; ++j) sx_[3 * i + j] = raw(Xs[j]), sy_[3 * i + j] = raw(Ys[j]);
      if (f_.p.cost_model == CostModel::kHardware) {  // the affine 2D sample test's edges per lens position
        tiletest::edges_2d<D>(&sx_[3 * i], &sy_[3 * i], tri.W);
        charge<A>(ops, cost::kEdges2DSetup);
      }
    }
  }

  // Visit the tiles overlapping the triangle's bounds in the bin; fn(tx, ty, px0, py0, px1, py1)
  // gets the tile origin and its pixels inside the bounds (pixels outside the triangle's setup
  // bounds cannot be hit: the hardware masks them with the bounding-box test).
  template <class Fn>
  void for_tiles(const TriSetup& tri, const BinRect& bin, Fn&& fn) {
    const int T = f_.p.tile_size;
    const int x0 = std::max(tri.bx0, bin.x0), x1 = std::min(tri.bx1, bin.x1);
    const int y0 = std::max(tri.by0, bin.y0), y1 = std::min(tri.by1, bin.y1);
    for (int ty = (y0 / T) * T; ty < y1; ty += T)
      for (int tx = (x0 / T) * T; tx < x1; tx += T)
        if (!zcull_.query_answered()) {  // interval-based query: abort at the first visible tile
          pipe_.at_rect(std::max(tx, x0), std::max(ty, y0), std::min(tx + T, x1), std::min(ty + T, y1));
          fn(tx, ty, std::max(tx, x0), std::max(ty, y0), std::min(tx + T, x1), std::min(ty + T, y1));
          pipe_.end_visit();  // a shading visit = one tile
        }
  }

  // ---- 2D: standard tile test, every sample of accepted tiles --------------------------------
  void raster_2d(const TriSetup& tri, const tiletest::Edges2D& e, const BinRect& bin) {
    const int T = f_.p.tile_size;
    const int spp = f_.table.spp();
    pipe_.begin(tri);
    const double snap = tiletest::t_snap_margin_px;  // pipeline.precision.sample: fixed
    const double blx = tri.lo_x - (std::fabs(tri.lo_x) * 0x1p-18 + 0x1p-12 + snap);
    const double bhx = tri.hi_x + (std::fabs(tri.hi_x) * 0x1p-18 + 0x1p-12 + snap);
    const double bly = tri.lo_y - (std::fabs(tri.lo_y) * 0x1p-18 + 0x1p-12 + snap);
    const double bhy = tri.hi_y + (std::fabs(tri.hi_y) * 0x1p-18 + 0x1p-12 + snap);
    for_tiles(tri, bin, [&](int tx, int ty, int px0, int py0, int tx1, int ty1) {
      ++c_[Counter::tile_visited];
      const double x0 = tiletest::expand_lo(tx), x1 = tiletest::expand_hi(tx + T);
      const double y0 = tiletest::expand_lo(ty), y1 = tiletest::expand_hi(ty + T);
      bool overflow;
      const bool out_edges = tiletest::tile_outside_2d_in<D>(e, x0, x1, y0, y1, overflow) || !e.valid;
      if (overflow) ++c_[Counter::precision_tile_overflows];
      const bool b0 = D(x1) < D(blx), b1 = D(x0) > D(bhx), b2 = D(y1) < D(bly), b3 = D(y0) > D(bhy);
      charge<A>(c_[Counter::ops_tile], cost::kTile2D + cost::kBBoxTile);
      if (out_edges || b0 || b1 || b2 || b3) {
        ++c_[Counter::tile_culled_2d];
        return;
      }
      ++c_[Counter::tile_accepted];
      if (!zcull_.check(tri, tx, ty, x0, x1, y0, y1, false, 0, 0, 0, 0, 0, 0, (tx1 - px0) * (ty1 - py0) * spp)) return;
      bool optimal_tile = false;
      if (f_.p.count_optimal)
        optimal_tile = tiletest::footprint_overlaps_tile(tri.poly, tri.poly_n, 0, 0, f_.fc.focus_d, 0, 0, tx,
                                                         tx + T, ty, ty + T);
      for (int py = py0; py < ty1; ++py)
        for (int px = px0; px < tx1; ++px) {
          const PixelSamples ps = f_.table.pixel(px, py);
          pipe_.push_pixel(px, py, ps);
          if (optimal_tile) c_[Counter::tile_samples_optimal] += spp;
        }
    });
    pipe_.flush();
  }

  // ---- 4D (h_i + H_j), moving (h_i over the shutter ends), or no test --------------------------
  void raster_lens(const TriSetup& tri, const Footprint& fp, const BinRect& bin) {
    const RenderParams& p = f_.p;
    const int T = p.tile_size, G = p.lens_grid;
    const bool use_h = p.halfspace_h && fp.h_valid;
    const bool use_H_in = p.halfspace_H && !tri.moving && p.precision_tile.kind != PrecisionKind::kFloat64;
    const bool use_H = p.halfspace_H && !tri.moving && !use_H_in;  // build_footprint set up H_j (sigma, or per-cell signs)
    if (kInterleaved && !tri.moving)
      pipe_.begin_sheared(tri, sx_.data(), sy_.data(), 3);
    else
      pipe_.begin(tri);
    // Fast path: the h_i sets of every tile column and row, once (axis_cache.h).
    const bool clip_uv = clip_.active_u || clip_.active_v;
    const bool prec4d = f_.p.precision_tile.kind != PrecisionKind::kFloat64;  // tiletest/precision_4d.h
    if constexpr (!A::counting)
      if (!prec4d) axes_.build<D>(fp.lv, fp.n, use_h, std::max(tri.bx0, bin.x0), std::min(tri.bx1, bin.x1),
                     std::max(tri.by0, bin.y0), std::min(tri.by1, bin.y1), T, G);
    for_tiles(tri, bin, [&](int tx, int ty, int px0, int py0, int tx1, int ty1) {
      ++c_[Counter::tile_visited];
      const double x0 = tiletest::expand_lo(tx), x1 = tiletest::expand_hi(tx + T);
      const double y0 = tiletest::expand_lo(ty), y1 = tiletest::expand_hi(ty + T);
      tiletest::AxisSet csx, csy;  // this tile's sets (counting path, or clipped)
      const tiletest::AxisSet* psx = &csx;
      const tiletest::AxisSet* psy = &csy;
      const AxisCache::Axis* col = nullptr;
      const AxisCache::Axis* row = nullptr;
      bool cached_axes = !prec4d;
      if constexpr (A::counting) cached_axes = false;
      if (cached_axes) {
        col = &axes_.cols[static_cast<std::size_t>((tx - axes_.tx0) / T)];
        row = &axes_.rows[static_cast<std::size_t>((ty - axes_.ty0) / T)];
        psx = &col->set, psy = &row->set;
        if (use_h) {
          if (!tri.moving) ++c_[Counter::interval_lens_tests_4d];
          c_[Counter::ops_tile] += col->cost + row->cost;  // what tile_h_sets charges
          if (psx->empty || psy->empty) {
            ++c_[Counter::tile_culled_h];
            return;
          }
        }
      } else {
        csx = tiletest::full_axis(), csy = tiletest::full_axis();
        if (use_h) {
          if (!tri.moving) ++c_[Counter::interval_lens_tests_4d];
          bool keep = tile_h_sets<A>(fp, x0, x1, y0, y1, csx, csy, c_[Counter::ops_tile]);
          if (prec4d) {  // the decision in pipeline.precision.tile (counted as the float64 form)
            bool ovf;
            keep = p4_.h_sets(x0, x1, y0, y1, csx, csy, ovf);
            if (ovf) ++c_[Counter::precision_tile4d_overflows];
          }
          if (!keep) {
            ++c_[Counter::tile_culled_h];
            return;
          }
        }
      }
      if (clip_uv) {  // user clip planes on the lens intervals
        if (psx != &csx) csx = *psx, csy = *psy, psx = &csx, psy = &csy;
        if (!iv::clip_lens<A>(clip_, csx, csy, c_[Counter::ops_tile])) {
          ++c_[Counter::interval_culled_clip];
          return;
        }
      }
      const tiletest::AxisSet& sx = *psx;
      const tiletest::AxisSet& sy = *psy;
      // uv-boxes and the lens shape.
      c_[Counter::tile_uv_boxes] += static_cast<std::uint64_t>(sx.n_intervals) * sy.n_intervals;
      if (p.lens_shape != LensShape::kSquare) {
        bool any = false;
        for (int a = 0; a < sx.n_intervals; ++a)
          for (int b = 0; b < sy.n_intervals; ++b) {
            any |= tiletest::box_overlaps_lens<D>(p.lens_shape, sx.iv_lo[a], sx.iv_hi[a], sy.iv_lo[b], sy.iv_hi[b]);
            charge<A>(c_[Counter::ops_tile], p.lens_shape == LensShape::kDisk ? cost::kBoxDisk : cost::kBoxHexagon);
          }
        if (!any) {
          ++c_[Counter::tile_culled_lens];
          return;
        }
      }
      // Lens cells inside the uv-boxes (clamped to the grid, [Akenine-Möller 2012] §5.1).
      const bool cached_cells = col && !clip_uv;
      const std::uint32_t bx = cached_cells ? col->cells : tiletest::axis_cells<D>(sx, G);
      const std::uint32_t by = cached_cells ? row->cells : tiletest::axis_cells<D>(sy, G);
      charge<A>(c_[Counter::ops_tile], sx.n_cmp + sy.n_cmp);
      ActiveCells active = active_cells(bx, by, G, lens_mask_, lens_mask64_);
      if (active.none()) {
        ++c_[Counter::tile_culled_lens];
        return;
      }
      if (use_H_in) {  // H_j in pipeline.precision.tile: counted as the float64 form, decided in the format
        bool any_line, ovf;
        hj_culled_cells<A>(fp, x0, x1, y0, y1, G, active.i0, active.i1, active.j0, active.j1, c_, any_line);
        const tiletest::CellMask culled =
            p4_.hj_cells(x0, x1, y0, y1, G, active.i0, active.i1, active.j0, active.j1, any_line, ovf);
        if (ovf) ++c_[Counter::precision_tile4d_overflows];
        if (any_line) {
          active.remove(culled, low64_, c_);
          if (active.none()) {
            ++c_[Counter::tile_culled_H];
            return;
          }
        }
      }

      // H_j lines: conservative overlap bitmask over the cells ([Akenine-Möller 2012] §5.1).
      if (use_H) {
        bool any_line;
        if (!A::counting && active.small) {  // the same bits as a 64-bit mask
          const std::uint64_t culled = hj_culled_cells<A, std::uint64_t>(fp, x0, x1, y0, y1, G, active.i0, active.i1,
                                                                         active.j0, active.j1, c_, any_line);
          if (any_line) active.remove64(culled, c_);
        } else {
          const tiletest::CellMask culled =
              hj_culled_cells<A>(fp, x0, x1, y0, y1, G, active.i0, active.i1, active.j0, active.j1, c_, any_line);
          if (any_line) active.remove(culled, low64_, c_);
        }
        if (any_line) {
          if (active.none()) {
            ++c_[Counter::tile_culled_H];
            return;
          }
        }
      }
      ++c_[Counter::tile_accepted];
      if (!zcull_.check(tri, tx, ty, x0, x1, y0, y1, true, sx.iv_lo[0], sx.iv_hi[sx.n_intervals - 1], sy.iv_lo[0],
                        sy.iv_hi[sy.n_intervals - 1], 0.0, tri.moving ? 1.0 : 0.0,
                        (tx1 - px0) * (ty1 - py0) * f_.table.spp()))
        return;
      // Samples of surviving cells, each checked against the h_i lines, then inside-tested.
      const bool fast_select = !A::counting && active.small;  // vectorised scan: no cell list
      const int n_cells = fast_select ? 0 : active.list(cell_list_.data(), G);
      const int* const cl = cell_list_.data();
      const std::uint64_t region_cost = static_cast<std::uint64_t>(sx.n_cmp + sy.n_cmp);
      const bool count_opt = p.count_optimal;
      const int spp = f_.table.spp();
      const std::uint64_t active_bits = active.bits64;
      std::uint64_t region_checked = 0;  // fast path: ops.sample_region charged once per tile
      // Fast path: a vectorised scan of each pixel's samples, even when the active cells hold few
      // of them (measured faster than walking the cells' buckets at 64 spp: no per-cell branches).
      const bool vectorised = fast_select;
      if constexpr (!A::counting) {
        // Select and push in one SIMD pass per pixel (SamplePipeline::push_selected), the tile's
        // bounds set up once.
        if (vectorised && !count_opt && fused_select_) {
          tiletest::SelectBounds sb;
          sb.set(active_bits, sx, sy);
          for (int py = py0; py < ty1; ++py)
            for (int px = px0; px < tx1; ++px)
              region_checked += static_cast<std::uint64_t>(pipe_.push_selected(px, py, f_.table.pixel(px, py), sb));
          c_[Counter::ops_sample_region] += region_cost * region_checked;
          return;
        }
      }
      for (int py = py0; py < ty1; ++py)
        for (int px = px0; px < tx1; ++px) {
          const PixelSamples ps = f_.table.pixel(px, py);
          pipe_.at_pixel(px, py);
          // Candidates: samples of the surviving cells whose (u, v) passes the h_i lines.
          int n = 0, checked = 0;
          if (vectorised) {  // vectorised scan of the pixel's samples
            checked = tiletest::select_candidates<true>(spp, ps.u, ps.v, ps.cell, active_bits, sx, sy, sel_.data());
            if (!count_opt) {  // straight to the batch (SamplePipeline::push_flagged)
              if constexpr (!A::counting) {
                region_checked += static_cast<std::uint64_t>(checked);
                pipe_.push_flagged(px, py, ps, sel_.data());
              }
              continue;
            }
            n = tiletest::compact_flags(sel_.data(), spp, cand_.data());
          } else {  // the counting path, or grids above 8 x 8: walk the active cells' buckets
            for (int q = 0; q < n_cells; ++q) {
              const int k0 = ps.cell_offsets[cl[q]], k1 = ps.cell_offsets[cl[q] + 1];
              checked += k1 - k0;
              for (int k = k0; k < k1; ++k) {
                const int s = ps.cell_order[k];
                cand_[n] = s;
                n += region_cost == 0 || (tiletest::axis_pass(sx, F(ps.u[s])) & tiletest::axis_pass(sy, F(ps.v[s])));
              }
            }
          }
          if constexpr (A::counting) {  // the tally of this pixel's comparisons is taken here
            if (region_cost) charge<A>(c_[Counter::ops_sample_region], region_cost * checked);
          } else {
            region_checked += static_cast<std::uint64_t>(checked);
          }
          if (count_opt)
            c_[Counter::tile_samples_optimal] += tiletest::count_exact_region(tri, fp, f_.fc, ps, cand_.data(), n, tx, ty, T);
          if (vectorised)
            pipe_.push_pixel_masked(px, py, ps, sel_.data(), cand_.data(), n);
          else
            for (int i = 0; i < n; ++i) pipe_.push(px, py, ps, cand_[i]);
        }
      if constexpr (!A::counting) c_[Counter::ops_sample_region] += region_cost * region_checked;
    });
    pipe_.flush();
  }

  // ---- moving triangles (3D, 5D): time sub-intervals with t̂ and lens sets (intervals/) ---------
  void raster_motion(const TriSetup& tri, const BinRect& bin) {
    const RenderParams& p = f_.p;
    const int T = p.tile_size, G = p.lens_grid, S = ms_.S;
    const bool lens = ms_.lens;
    const int spp = f_.table.spp();
    const int NT = f_.table.time_strata(), per_sub = NT / S;  // NT is a multiple of S (validated)
    pipe_.begin(tri);
    iv::TileIntervals& ti = ti_;
    for_tiles(tri, bin, [&](int tx, int ty, int px0, int py0, int tx1, int ty1) {
      ++c_[Counter::tile_visited];
      const double x0 = tiletest::expand_lo(tx), x1 = tiletest::expand_hi(tx + T);
      const double y0 = tiletest::expand_lo(ty), y1 = tiletest::expand_hi(ty + T);
      bool keep_t = iv::motion_tile_intervals<A>(ms_, clip_, tri.cls, x0, x1, y0, y1, ti, c_[Counter::ops_tile], c_, p.halfspace_h);
      if (p5_.active()) {  // the decision in pipeline.precision.tile (counted as the float64 form)
        bool ovf;
        keep_t = p5_.tile_intervals(clip_, x0, x1, y0, y1, ti, p.halfspace_h, ovf);
        if (ovf) ++c_[Counter::precision_tile5d_overflows];
      }
      if (!keep_t) {
        ++c_[Counter::interval_culled_t];
        return;
      }
      // Lens cells per active sub-interval (5D: inside its lens sets; 3D: every cell on the lens).
      int n_cells[iv::kMaxSplits];
      int total_cells = 0;
      bool h5_culled = false;  // H5 removed the last cells of some sub-interval
      // Grids up to 8 x 8 on the vectorised path: the listed cells are the bits of cell_bits_[k].
      constexpr bool kVectorSelect = !A::counting && tiletest::kMotionSelectVector;
      const bool bits_only = kVectorSelect && G * G <= 64;
      for (int k = 0; k < S; ++k) {
        n_cells[k] = 0;
        if (!ti.active[k]) continue;
        int* list = &cell_lists_[static_cast<std::size_t>(k) * 256];
        std::uint32_t bx = (1u << G) - 1, by = (1u << G) - 1;  // no lens: every column and row
        if (lens) {
          bx = tiletest::axis_cells<D>(ti.sx[k], G);
          by = tiletest::axis_cells<D>(ti.sy[k], G);
          charge<A>(c_[Counter::ops_tile], ti.sx[k].n_cmp + ti.sy[k].n_cmp);
        }
        ActiveCells cells = active_cells(bx, by, G, lens_mask_, lens_mask64_);
        if (p.halfspace_H5 && h5_.sub[k].usable && !cells.none()) h5_cull(k, x0, x1, y0, y1, ti, cells, h5_culled);
        if (bits_only) {  // the vectorised selection reads the cells as bits: no list, no flags
          cell_bits_[k] = cells.bits64;
          n_cells[k] = __builtin_popcountll(cells.bits64);
          if (n_cells[k]) first_cell_[k] = __builtin_ctzll(cells.bits64), last_cell_[k] = 63 - __builtin_clzll(cells.bits64);
        } else {
          n_cells[k] = cells.list(list, G);
          if (n_cells[k]) first_cell_[k] = list[0], last_cell_[k] = list[n_cells[k] - 1];
          std::uint8_t* sel = &cell_sel_[static_cast<std::size_t>(k) * 256];  // the listed cells, for the pixels
          std::fill_n(sel, G * G, std::uint8_t{0});
          for (int q = 0; q < n_cells[k]; ++q) sel[list[q]] = 1;
        }
        total_cells += n_cells[k];
        // Time strata of the table index that overlap t̂_k: samples outside are never touched.
        const D slo = D(ti.tlo[k]) * D(NT), shi = D(ti.thi[k]) * D(NT);
        charge<A>(c_[Counter::ops_tile], cost::kTimeStrata);
        strata_lo_[k] = std::max(k * per_sub, static_cast<int>(std::floor(raw(slo))));
        strata_hi_[k] = std::min((k + 1) * per_sub - 1, static_cast<int>(std::floor(raw(shi))));
      }
      if (total_cells == 0) {
        ++c_[h5_culled ? Counter::tile_culled_H5 : Counter::tile_culled_lens];
        return;
      }
      ++c_[Counter::tile_accepted];
      if (!zcull_.check(tri, tx, ty, x0, x1, y0, y1, lens, ti.u0, ti.u1, ti.v0, ti.v1, ti.t0, ti.t1,
                  (tx1 - px0) * (ty1 - py0) * spp))
        return;
      const bool cu = clip_.active_u, cv = clip_.active_v;
      const F cul(cu ? clip_.u_lo : 0.0), cuh(cu ? clip_.u_hi : 0.0), cvl(cv ? clip_.v_lo : 0.0),
          cvh(cv ? clip_.v_hi : 0.0);
      for (int py = py0; py < ty1; ++py)
        for (int px = px0; px < tx1; ++px) {
          const PixelSamples ps = f_.table.pixel(px, py);
          pipe_.at_pixel(px, py);
          std::uint64_t region_ops = 0;
          int n = 0;
          for (int k = 0; k < S; ++k) {
            if (!ti.active[k]) continue;
            const F tk_lo(ti.tlo[k]), tk_hi(ti.thi[k]);
            const tiletest::AxisSet& sx = ti.sx[k];
            const tiletest::AxisSet& sy = ti.sy[k];
            // per sample: t̂, the lens cuts (5D), each clipped lens axis
            const std::uint64_t per = cost::kSampleTime + (lens ? sx.n_cmp + sy.n_cmp : 0) +
                                      (cu ? cost::kSampleClipAxis : 0) + (cv ? cost::kSampleClipAxis : 0);
            const std::uint8_t* sel = &cell_sel_[static_cast<std::size_t>(k) * 256];
            int checked = 0;
            const int j0 = strata_lo_[k], j1 = strata_hi_[k];
            // The samples of the buckets (listed cell, stratum j0..j1), in bucket order: the table
            // lists them by (cell, stratum), so they are the entries of the span from the first such
            // bucket to the last whose cell is listed and whose stratum is in range.
            if (n_cells[k] > 0 && j0 <= j1) {
              const int lo = ps.ct_offsets[first_cell_[k] * NT + j0], hi = ps.ct_offsets[last_cell_[k] * NT + j1 + 1];
              if constexpr (!A::counting && tiletest::kMotionSelectVector) {
                tiletest::MotionRegion r;
                r.cell_sel = sel, r.j0 = j0, r.j1 = j1, r.t_lo = tk_lo, r.t_hi = tk_hi, r.lens = lens, r.su = &sx, r.sv = &sy;
                r.cu = cu, r.cv = cv, r.u_lo = cul, r.u_hi = cuh, r.v_lo = cvl, r.v_hi = cvh;
                r.cell_bits_on = bits_only, r.cell_bits = cell_bits_[k];
                checked = tiletest::select_motion(ps.ct_order, ps.ct_cell, ps.ct_stratum, ps.ct_t, ps.ct_u, ps.ct_v, lo,
                                                  hi, r, cand_.data(), n);
              } else
              for (int idx = lo; idx < hi; ++idx) {
                const int j = ps.ct_stratum[idx];
                if (!sel[ps.ct_cell[idx]] || j < j0 || j > j1) continue;
                const int smp = ps.ct_order[idx];
                ++checked;
                const F t(ps.t[smp]);
                bool pass = (t >= tk_lo) & (t <= tk_hi);
                if (lens) pass &= tiletest::axis_pass(sx, F(ps.u[smp])) & tiletest::axis_pass(sy, F(ps.v[smp]));
                if (cu) {
                  const F u(ps.u[smp]);
                  pass &= (u >= cul) & (u <= cuh);
                }
                if (cv) {
                  const F v(ps.v[smp]);
                  pass &= (v >= cvl) & (v <= cvh);
                }
                cand_[n] = smp;
                n += pass;
              }
            }
            region_ops += per * static_cast<std::uint64_t>(checked);
          }
          // Charge the selection before the sample tests (the counting path tallies in order).
          charge<A>(c_[Counter::ops_sample_region], region_ops);
          if (p.count_optimal)
            c_[Counter::tile_samples_optimal] += tiletest::count_exact_region(tri, fp_dummy_, f_.fc, ps, cand_.data(), n, tx, ty, T);
          pipe_.push_list(px, py, ps, cand_.data(), n);  // push() of each, the batch checked once
        }
    });
    pipe_.flush();
  }

  // The H5 oracle's inputs (selective_H; c_sample as the H_j oracle's, at the triangle's class).
  tiletest::H5Oracle h5_oracle(const TriSetup& tri) const {
    const RenderParams& p = f_.p;
    tiletest::H5Oracle o;
    o.on = p.selective_H;
    const int T = p.tile_size;
    o.n_tiles = static_cast<double>((tri.bx1 - 1) / T - tri.bx0 / T + 1) * static_cast<double>((tri.by1 - 1) / T - tri.by0 / T + 1);
    o.spp = f_.table.spp();
    o.c_sample = p.c_sample >= 0 ? p.c_sample : static_cast<double>(sample_test_cost(p.cost_model, tri.cls));
    o.c_tile = static_cast<double>(tiletest::h5_edge_tile_cost(tri.defocused, p.lens_grid));
    return o;
  }

  // H5 hook: remove the lens cells of sub-interval k that its planes cull over t̂_k.
  void h5_cull(int k, double x0, double x1, double y0, double y1, const iv::TileIntervals& ti, ActiveCells& cells,
               bool& emptied) {
    std::uint64_t lines = 0;
    tiletest::CellMask culled =
        tiletest::h5_culled_cells<A>(h5_, k, x0, x1, y0, y1, ti.tlo[k], ti.thi[k], f_.p.lens_grid, cells.i0, cells.i1,
                                     cells.j0, cells.j1, c_[Counter::ops_tile], lines);
    c_[Counter::tile_H5_lines] += lines;
    if (p5_.active()) {  // H5 in pipeline.precision.tile: counted as the float64 form, decided in the format
      bool ovf;
      culled = p5_.h5_cells(h5_, k, x0, x1, y0, y1, ti.tlo[k], ti.thi[k], f_.p.lens_grid, cells.i0, cells.i1, cells.j0,
                            cells.j1, ovf);
      if (ovf) ++c_[Counter::precision_tile5d_overflows];
    }
    const std::uint64_t before = cells.small ? static_cast<std::uint64_t>(__builtin_popcountll(cells.bits64)) : cells.bits.count();
    if (cells.small)
      cells.bits64 &= ~(culled & low64_).to_ullong();
    else
      cells.bits &= ~culled;
    const std::uint64_t after = cells.small ? static_cast<std::uint64_t>(__builtin_popcountll(cells.bits64)) : cells.bits.count();
    c_[Counter::tile_H5_cells_tested] += before;
    c_[Counter::tile_H5_cells_culled] += before - after;
    emptied |= after == 0;
  }

  const Frame& f_;
  Counters& c_;
  SamplePipeline<A> pipe_;
  DepthCull<A, SamplePipeline<A>> zcull_;
  tiletest::CellMask lens_mask_;
  std::vector<int> cell_list_ = std::vector<int>(256);
  std::vector<int> cand_ = std::vector<int>(f_.table.spp() + 16);  // one pixel's candidates (+ select_motion's slack)
  tiletest::CellMask low64_;
  std::uint64_t lens_mask64_ = 0;
  std::vector<std::uint8_t> sel_ =
      std::vector<std::uint8_t>(f_.table.spp() + SamplePipeline<A>::flags_padding(), 0);
  std::vector<float> sx_, sy_;
  // Fast path: SamplePipeline::push_selected in place of select_candidates + push_flagged.
  const bool fused_select_ = SamplePipeline<A>::kFusedSelect && f_.p.simd && f_.table.spp() <= 64;
  AxisCache axes_;  // fast path: h_i sets per tile column and row of the current triangle and bin
  tiletest::Tile4DPrecision p4_;  // the 4D tile test in pipeline.precision.tile (not float64)
  tiletest::Motion5DPrecision p5_;  // t̂, 5D lens sets and H5 in pipeline.precision.tile (not float64)
  const iv::ClipBox clip_ = iv::clip_box(f_.p);
  iv::MotionSetup ms_;
  tiletest::MotionH5 h5_;
  iv::TileIntervals ti_;
  int strata_lo_[iv::kMaxSplits], strata_hi_[iv::kMaxSplits];
  std::vector<int> cell_lists_ = std::vector<int>(256 * iv::kMaxSplits);
  std::vector<std::uint8_t> cell_sel_ = std::vector<std::uint8_t>(256 * iv::kMaxSplits + 4);  // 1: a listed cell
  std::uint64_t cell_bits_[iv::kMaxSplits] = {};  // the listed cells as bits (grids up to 8 x 8, vectorised path)
  int first_cell_[iv::kMaxSplits] = {}, last_cell_[iv::kMaxSplits] = {};  // the lowest and highest listed cell
  const Footprint fp_dummy_{};  // in_exact_region reads no footprint for moving triangles
};

template <class A>
using TileArbitrary = Tile<A, false>;
template <class A>
using TileInterleaved = Tile<A, true>;

}  // namespace

RAST5D_REGISTER_TRAVERSAL("tile",
                          "[Akenine-Möller 2012] §5.1 (OUR): per tile, h_i uv-boxes, H_j lens-cell bitmask, per-sample h_i test",
                          TableKinds::kPoints, PipelineKind::kSample, TileArbitrary);
RAST5D_REGISTER_TRAVERSAL("tile_interleaved",
                          "[Akenine-Möller 2012] OUR (i): the tile algorithm on an interleaved table, 2D test per lens coordinate",
                          TableKinds::kInterleaved, PipelineKind::kSample, TileInterleaved);

}  // namespace rast5d
