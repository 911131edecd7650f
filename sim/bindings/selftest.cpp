// Test-only entry points: the exact sample test at given points, the operation-cost self-checks
// (sim/engine/selftest/), and the texture cache and texture unit against Python references.
#include "bindings.h"

#include <pybind11/stl.h>

#include <algorithm>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "backend/cache_model.h"
#include "backend/texture.h"
#include "core/fixed.h"
#include "sampletest/hardware.h"
#include "sampletest/precision.h"
#include "setup/footprint.h"
#include "tiletest/box_bounds.h"
#include "tiletest/edges_2d.h"
#include "tiletest/precision_4d.h"
#include "intervals/precision_5d.h"
#include "traversal/algorithms/tile/hj_cells.h"
#include "selftest/kernel_costs.h"
#include "selftest/probe.h"

namespace rast5d::bindings {

namespace {

using DArr = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Every value of a within +-bound (NaN and, for a finite bound, infinities never are);
// std::invalid_argument "name: expected <expected>, got <value>" otherwise.
void require_within(const DArr& a, double bound, const char* name, const char* expected) {
  for (py::ssize_t i = 0; i < a.size(); ++i)
    if (!(std::fabs(a.data()[i]) <= bound))
      throw std::invalid_argument(std::string(name) + ": expected " + expected + ", got " +
                                  std::to_string(a.data()[i]));
}

}  // namespace

void register_selftest(py::module_& m) {
  m.def(
      "probe",
      [](const RenderParams& p, const FArr& v0, const FArr& v1, const FArr& points, bool force_general) {
        require_shape(v0, {3, 3}, "v0");
        require_shape(v1, {3, 3}, "v1");
        require_shape(points, {-1, 5}, "points");
        const int m_pts = static_cast<int>(points.shape(0));
        ProbeResult r = probe_samples(p, v0.data(), v1.data(), points.data(), m_pts, force_general);
        py::dict out;
        py::array_t<bool> covered(m_pts), hit(m_pts);
        py::array_t<float> depth(m_pts), w_hit(m_pts);
        for (int i = 0; i < m_pts; ++i) {
          covered.mutable_data()[i] = r.covered[i];
          hit.mutable_data()[i] = r.hit[i];
          depth.mutable_data()[i] = r.depth[i];
          w_hit.mutable_data()[i] = r.w_hit[i];
        }
        out["dim_class"] = r.dim_class;
        out["covered"] = covered;
        out["hit"] = hit;
        out["depth"] = depth;
        out["w_hit"] = w_hit;
        return out;
      },
      py::arg("params"), py::arg("v0"), py::arg("v1"), py::arg("points"), py::arg("force_general") = false,
      "Evaluate the exact sample test of one triangle at points (M, 5) = (sx, sy, u, v, t).");

  m.def(
      "measure_kernel_costs",
      [](int trials, std::uint64_t seed) {
        py::dict d;
        std::mt19937_64 g(seed);
        for (auto& [name, e] : KernelCostRegistry::entries()) {
          std::uint64_t lo = ~0ull, hi = 0;
          for (int i = 0; i < trials; ++i) {
            const std::uint64_t n = e.run_counted(g);
            lo = std::min(lo, n);
            hi = std::max(hi, n);
          }
          d[py::str(name)] = py::make_tuple(e.documented, lo, hi);
        }
        return d;
      },
      py::arg("trials") = 100, py::arg("seed") = 1,
      "Run every registered kernel on the counting scalar type: {name: (documented, min, max)}.");

  m.def(
      "measure_tile_kernel_costs",
      [](int trials, std::uint64_t seed) {
        py::dict d;
        std::mt19937_64 g(seed);
        for (auto& [name, run] : TileKernelCostRegistry::entries()) {
          int mismatches = 0;
          std::uint64_t lo = ~0ull, hi = 0;
          for (int i = 0; i < trials; ++i) {
            const auto [counted, documented] = run(g);
            mismatches += counted != documented;
            lo = std::min(lo, documented);
            hi = std::max(hi, documented);
          }
          d[py::str(name)] = py::make_tuple(trials, mismatches, lo, hi);
        }
        return d;
      },
      py::arg("trials") = 200, py::arg("seed") = 1,
      "Tile-test kernels with configuration-dependent costs: {name: (runs, mismatches, min documented, "
      "max documented)}; counted == documented on every run means mismatches == 0.");

  m.def(
      "simulate_cache",
      [](const py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>& lines, std::uint64_t n_lines,
         std::uint64_t ways) {
        // One tag and one stamp per line, plus the LRU shadow: 2^26 lines is 1.5 GiB already.
        if (n_lines < 1 || n_lines > (std::uint64_t{1} << 26))
          throw std::invalid_argument("n_lines: expected 1..67108864, got " + std::to_string(n_lines));
        if (ways && n_lines % ways) throw std::invalid_argument("ways: expected 0 or a divisor of n_lines");
        SetAssocCache cache(n_lines, ways);
        py::array_t<bool> hit(lines.size());
        for (py::ssize_t i = 0; i < lines.size(); ++i) hit.mutable_data()[i] = cache.access(lines.data()[i]);
        const CacheStats& st = cache.stats();
        py::dict d;
        d["accesses"] = st.accesses, d["hits"] = st.hits, d["misses"] = st.misses;
        d["cold"] = st.cold, d["capacity"] = st.capacity, d["conflict"] = st.conflict;
        d["hit"] = hit;
        return d;
      },
      py::arg("lines"), py::arg("n_lines"), py::arg("ways"),
      "Run a stream of line indices through one set-associative LRU cache (ways 0 = fully "
      "associative) with the 3C miss classification; {'accesses', 'hits', 'misses', 'cold', "
      "'capacity', 'conflict', 'hit' (per access)}.");

  m.def(
      "triangle_lod",
      [](const FArr& v0, const FArr& uvs, int tex_width, int tex_height, double near_w) {
        require_shape(v0, {-1, 3, 3}, "v0");
        const py::ssize_t n = v0.shape(0);
        require_shape(uvs, {n, 3, 2}, "uvs");
        if (tex_width < 1 || tex_height < 1) throw std::invalid_argument("tex_width/tex_height: expected >= 1");
        py::array_t<float> lod(n);
        py::array_t<double> jac({n, static_cast<py::ssize_t>(4)});
        for (py::ssize_t i = 0; i < n; ++i) {
          float X[3], Y[3], W[3];
          for (int j = 0; j < 3; ++j) {
            X[j] = v0.data()[i * 9 + j * 3], Y[j] = v0.data()[i * 9 + j * 3 + 1], W[j] = v0.data()[i * 9 + j * 3 + 2];
          }
          double J[4];
          uv_jacobian(X, Y, W, uvs.data() + i * 6, near_w, J);
          for (int k = 0; k < 4; ++k) jac.mutable_data()[i * 4 + k] = J[k];
          lod.mutable_data()[i] = lod_from_jacobian(J, tex_width, tex_height);
        }
        return py::make_tuple(lod, jac);
      },
      py::arg("v0"), py::arg("uvs"), py::arg("tex_width"), py::arg("tex_height"), py::arg("near_w") = 0.0,
      "Per-triangle analytic uv derivatives (lens centre, shutter open) and level of detail for a "
      "tex_width x tex_height texture: (lod (n,), jacobian (n, 4) = du/dx, du/dy, dv/dx, dv/dy).");

  m.def(
      "texel_address",
      [](int height, int width, const std::string& layout, int level, int x, int y) {
        const TexLayout lay = choice_value<TexLayout>(layout, "layout");
        if (height < 1 || height > 16384 || width < 1 || width > 16384)
          throw std::invalid_argument("height, width: expected 1..16384, got " + std::to_string(height) + " x " +
                                      std::to_string(width));
        std::vector<float> img(static_cast<std::size_t>(height) * width, 0.0f);
        TextureSet ts;
        ts.add(img.data(), height, width, 1);
        ts.layout(lay);
        if (level < 0 || level >= ts.levels(0)) throw std::invalid_argument("level: out of range");
        const int lw = std::max(1, width >> level), lh = std::max(1, height >> level);
        if (x < 0 || x >= lw || y < 0 || y >= lh)
          throw std::invalid_argument("x, y: expected a texel of the " + std::to_string(lw) + " x " + std::to_string(lh) +
                                      " level, got (" + std::to_string(x) + ", " + std::to_string(y) + ")");
        return ts.address(0, level, x, y);
      },
      py::arg("height"), py::arg("width"), py::arg("layout"), py::arg("level"), py::arg("x"), py::arg("y"),
      "Byte address of texel (x, y) of a level of a lone height x width texture; layout: a name in "
      "choices()['texture_layouts'].");

  m.def(
      "precision_probe",
      [](const RenderParams& p, const FArr& v0, const FArr& v1, const FArr& points) {
        require_shape(v0, {3, 3}, "v0");
        require_shape(v1, {3, 3}, "v1");
        require_shape(points, {-1, 5}, "points");
        const Precision prec = p.precision_sample;
        const int m_pts = static_cast<int>(points.shape(0));
        const FrameConst fc = make_frame_const(p);
        const float col[9] = {1, 1, 1, 1, 1, 1, 1, 1, 1};
        TriSetup tri;
        Counters c;
        setup_triangle<FastArith>(v0.data(), v1.data(), col, 0, p, fc, tri, c);
        py::array_t<bool> covered(m_pts), overflow(m_pts);
        py::array_t<double> max_abs(m_pts);
        for (int i = 0; i < m_pts; ++i) {
          const float* q = points.data() + 5 * static_cast<std::size_t>(i);
          bool cov, ovf = false;
          double mag = 0.0;
          if (prec.kind == PrecisionKind::kFloat32) {
            float X[3], Y[3], W[3], e[3], det;
            int n_ties;
            cov = inside_test<float>(tri, tri.cls, fc, q[0], q[1], q[2], q[3], q[4], p.backface_cull, X, Y, W, e, det,
                                     n_ties);
          } else {
            double e[3], det;
            cov = precise_inside(tri, fc, prec, q[0], q[1], q[2], q[3], q[4], p.backface_cull, e, det, ovf);
            if (prec.kind == PrecisionKind::kFixed) mag = std::ldexp(FixedFormat::max_abs, -2 * prec.frac_bits);
          }
          covered.mutable_data()[i] = cov;
          overflow.mutable_data()[i] = ovf;
          max_abs.mutable_data()[i] = mag;
        }
        py::dict out;
        out["dim_class"] = c[Counter::setup_culled_near] ? -1 : static_cast<int>(tri.cls);
        out["covered"] = covered;
        out["overflow"] = overflow;
        out["max_abs"] = max_abs;
        return out;
      },
      py::arg("params"), py::arg("v0"), py::arg("v1"), py::arg("points"),
      "The sample test of one triangle (v0, v1: pixel-homogeneous vertices at shutter open/close) at points "
      "(M, 5) = (sx, sy, u, v, t) in params.precision_sample (sampletest/precision.h): covered (M,), and for "
      "fixed point overflow (M,) and max_abs (M,), the largest register magnitude (the fewest int_bits n "
      "satisfy max_abs < 2^n).");

  m.def(
      "precision_probe_2d",
      [](const DArr& tri, const DArr& points, const DArr& tiles, int int_bits, int frac_bits, const std::string& kind) {
        require_shape(tri, {3, 2}, "tri");
        require_shape(points, {-1, 2}, "points");
        require_shape(tiles, {-1, 4}, "tiles");
        Precision prec = Precision::fixed(int_bits, frac_bits);
        if (kind == "float32") prec = Precision::float32();
        else if (kind == "float64") prec = Precision::float64();
        else if (kind != "fixed") throw std::invalid_argument("kind: expected 'fixed', 'float32' or 'float64', got '" + kind + "'");
        check_precision("int_bits, frac_bits", prec);
        float X[3], Y[3];
        const float W[3] = {1.0f, 1.0f, 1.0f};
        double Xd[3], Yd[3];
        const double Wd[3] = {1.0, 1.0, 1.0};
        for (int j = 0; j < 3; ++j) {
          Xd[j] = tri.data()[2 * j], Yd[j] = tri.data()[2 * j + 1];
          X[j] = static_cast<float>(Xd[j]), Y[j] = static_cast<float>(Yd[j]);
        }
        // the render's kernels: the 2D tile test (tiletest/edges_2d.h edges_2d_in / tile_outside_2d_in)
        // and the sample test (sampletest/precision.h) in the chosen arithmetic
        const tiletest::Edges2D e = tiletest::edges_2d_in<double>(prec, X, Y, W);
        const double setup_abs = prec.kind == PrecisionKind::kFixed ? FixedFormat::max_abs : 0.0;
        const int m_pts = static_cast<int>(points.shape(0)), k = static_cast<int>(tiles.shape(0));
        py::array_t<bool> inside(m_pts), outside(k), ovf_s(m_pts), ovf_t(k);
        double max_s = 0.0, max_t = setup_abs;
        for (int i = 0; i < m_pts; ++i) {
          const double sx = points.data()[2 * i], sy = points.data()[2 * i + 1];
          bool in, ovf = false;
          if (prec.kind == PrecisionKind::kFixed) {
            in = fixed_inside_placed(Xd, Yd, Wd, sx, sy, prec, false, ovf);
            max_s = std::max(max_s, FixedFormat::max_abs);
          } else if (prec.kind == PrecisionKind::kFloat32) {
            float e3[3], det;
            int n_ties;
            const float Wf[3] = {1.0f, 1.0f, 1.0f};
            in = inside_from_vertices<float>(X, Y, Wf, static_cast<float>(sx), static_cast<float>(sy), false, e3, det, n_ties);
          } else {
            double e3[3], det;
            int n_ties;
            in = inside_from_vertices<double>(Xd, Yd, Wd, sx, sy, false, e3, det, n_ties);
          }
          inside.mutable_data()[i] = in;
          ovf_s.mutable_data()[i] = ovf;
        }
        for (int i = 0; i < k; ++i) {
          const double* t = tiles.data() + 4 * i;
          bool ovf;
          outside.mutable_data()[i] = tiletest::tile_outside_2d_in<double>(e, t[0], t[1], t[2], t[3], ovf) || !e.valid;
          if (prec.kind == PrecisionKind::kFixed) max_t = std::max(max_t, FixedFormat::max_abs);
          ovf_t.mutable_data()[i] = ovf;
        }
        const double unit = prec.kind == PrecisionKind::kFixed ? std::ldexp(1.0, -2 * frac_bits) : 0.0;
        py::dict out;
        out["inside"] = inside;
        out["tile_outside"] = outside;
        out["overflow_sample"] = ovf_s;
        out["overflow_tile"] = ovf_t;
        out["max_abs_sample"] = max_s * unit;
        out["max_abs_tile"] = max_t * unit;
        out["valid"] = e.valid;
        return out;
      },
      py::arg("tri"), py::arg("points"), py::arg("tiles"), py::arg("int_bits"), py::arg("frac_bits"),
      py::arg("kind") = "fixed",
      "The render's 2D tile test (tiletest/edges_2d.h, pipeline.precision.tile) and sample test "
      "(sampletest/precision.h, pipeline.precision.sample) of one screen-space triangle tri (3, 2) [px] in "
      "fixed point (int_bits, frac_bits; core/fixed.h), 'float32' or 'float64' (kind): inside (M,) at points "
      "(M, 2), tile_outside (K,) for tiles (K, 4) = (x0, x1, y0, y1), per-query overflow flags, and the "
      "largest register magnitudes max_abs_sample / max_abs_tile (fixed: the fewest int_bits n satisfy "
      "max_abs < 2^n).");

  m.def(
      "precision_probe_4d",
      [](const RenderParams& p, const FArr& v0, const DArr& tiles, const DArr& boxes) {
        require_shape(v0, {3, 3}, "v0");
        require_shape(tiles, {-1, 4}, "tiles");
        require_shape(boxes, {-1, 4}, "boxes");
        require_within(boxes, std::numeric_limits<double>::max(), "boxes", "finite lens coordinates");
        validate_domains(p);  // lens_grid sizes the (tiles, G * G) outputs
        require_finite(v0, "v0");
        // lens-cell indices are ints: finite, screen-sized tiles
        require_within(tiles, 0x1p24, "tiles", "finite pixel coordinates within +-2^24");
        const FrameConst fc = make_frame_const(p);
        const float col[9] = {1, 1, 1, 1, 1, 1, 1, 1, 1};
        TriSetup tri;
        Counters c;
        setup_triangle<FastArith>(v0.data(), v0.data(), col, 0, p, fc, tri, c);
        py::dict out;
        out["dim_class"] = c[Counter::setup_culled_near] ? -1 : static_cast<int>(tri.cls);
        if (c[Counter::setup_culled_near] || tri.poly_n < 3) return out;
        // the render's footprint of a static triangle (setup/footprint.h): lens vertices of the clipped
        // polygon, H_j edges (all active: no oracle), the orientation over the lens
        const int n = tri.poly_n, G = p.lens_grid, k_tiles = static_cast<int>(tiles.shape(0));
        tiletest::LensVertex lv[6];
        Footprint fp;  // H_j edges only: hj_culled_cells with one orientation over the lens (sigma != 0)
        bool active[6] = {false, false, false, false, false, false};
        for (int j = 0; j < n; ++j)
          lv[j] = tiletest::lens_vertex(tri.poly[j][0], tri.poly[j][1], tri.poly[j][2], -fc.focus_d, fc.kx_d, fc.ky_d);
        fp.n_edges = n;
        for (int j = 0; j < n; ++j) {
          fp.edges[j] = tiletest::edge_setup(tri.poly[j], tri.poly[(j + 1) % n], fc.focus_d, fc.kx_d, fc.ky_d);
          active[j] = fp.edges[j].active;
        }
        const int sigma = lens_orientation<double>(tri, fc);
        fp.sigma = sigma;
        const Precision prec = p.precision_tile;
        const tiletest::ScopedSnapMargin snap_margin(snap_margin_px(p.precision_sample, prec));
        tiletest::Tile4DPrecision p4;
        if (prec.kind != PrecisionKind::kFloat64) p4.setup(prec, lv, n, active, true);
        py::array_t<bool> culled64({k_tiles, G * G}), culled({k_tiles, G * G}), overflow(k_tiles);
        auto cells = [G](const tiletest::AxisSet& sx, const tiletest::AxisSet& sy, bool keep, const tiletest::CellMask& H,
                         bool* dst) {
          const std::uint32_t bx = keep ? tiletest::axis_cells<double>(sx, G) : 0u;
          const std::uint32_t by = keep ? tiletest::axis_cells<double>(sy, G) : 0u;
          for (int j = 0; j < G; ++j)
            for (int i = 0; i < G; ++i) dst[j * G + i] = !(((bx >> i) & 1u) && ((by >> j) & 1u)) || H.test(j * G + i);
        };
        for (int t = 0; t < k_tiles; ++t) {
          const double* q = tiles.data() + 4 * static_cast<std::size_t>(t);
          const double x0 = tiletest::expand_lo(q[0]), x1 = tiletest::expand_hi(q[1]);
          const double y0 = tiletest::expand_lo(q[2]), y1 = tiletest::expand_hi(q[3]);
          tiletest::AxisSet sx, sy;
          std::uint64_t ops = 0;
          const bool keep64 = tiletest::tile_h_sets<FastArith>(lv, n, x0, x1, y0, y1, sx, sy, ops);
          tiletest::CellMask H64;
          if (sigma != 0) {
            Counters hc;
            bool any_line;
            H64 = hj_culled_cells<FastArith>(fp, x0, x1, y0, y1, G, 0, G - 1, 0, G - 1, hc, any_line);
          }
          cells(sx, sy, keep64, H64, culled64.mutable_data() + static_cast<std::size_t>(t) * G * G);
          if (prec.kind == PrecisionKind::kFloat64) {
            cells(sx, sy, keep64, H64, culled.mutable_data() + static_cast<std::size_t>(t) * G * G);
            overflow.mutable_data()[t] = false;
            continue;
          }
          bool o1, o2, any;
          const bool keep = p4.h_sets(x0, x1, y0, y1, sx, sy, o1);
          const tiletest::CellMask H = p4.hj_cells(x0, x1, y0, y1, G, 0, G - 1, 0, G - 1, any, o2);
          cells(sx, sy, keep, H, culled.mutable_data() + static_cast<std::size_t>(t) * G * G);
          overflow.mutable_data()[t] = o1 || o2;
        }
        // INTERVAL's and INTERLEAVE's screen bounds over the lens boxes (box_bounds.h; precision_4d.h box_bounds_in)
        const int k_boxes = static_cast<int>(boxes.shape(0));
        py::array_t<double> box64({k_boxes, 4}), boxf({k_boxes, 4});
        py::array_t<bool> box_overflow(k_boxes);
        tiletest::Arith4D arb(prec);
        for (int b = 0; b < k_boxes; ++b) {
          const double* q = boxes.data() + 4 * static_cast<std::size_t>(b);
          double* d64 = box64.mutable_data() + 4 * static_cast<std::size_t>(b);
          double* df = boxf.mutable_data() + 4 * static_cast<std::size_t>(b);
          tiletest::box_bounds<double>(lv, n, q[0], q[1], q[2], q[3], d64[0], d64[1], d64[2], d64[3]);
          for (int k = 0; k < 4; ++k) df[k] = d64[k];
          box_overflow.mutable_data()[b] = false;
          if (prec.kind == PrecisionKind::kFloat64) continue;
          arb.overflow = false;
          tiletest::box_bounds_in(arb, lv, n, q[0], q[1], q[2], q[3], df[0], df[1], df[2], df[3]);
          box_overflow.mutable_data()[b] = arb.overflow;
        }
        out["box64"] = box64;
        out["box"] = boxf;
        out["box_overflow"] = box_overflow;
        out["max_abs_box"] = prec.kind == PrecisionKind::kFixed ? arb.max_abs : 0.0;
        py::array_t<double> lens_vertices({n, 4});
        for (int j = 0; j < n; ++j) {
          double* d = lens_vertices.mutable_data() + 4 * j;
          d[0] = lv[j].ax, d[1] = lv[j].ay, d[2] = lv[j].bx, d[3] = lv[j].by;
        }
        out["culled64"] = culled64;
        out["culled"] = culled;
        out["overflow"] = overflow;
        out["max_abs"] = prec.kind == PrecisionKind::kFixed ? p4.ar.max_abs : 0.0;
        out["sigma64"] = sigma;
        out["sigma"] = prec.kind == PrecisionKind::kFloat64 ? sigma : p4.sigma;
        out["lens_vertices"] = lens_vertices;
        return out;
      },
      py::arg("params"), py::arg("v0"), py::arg("tiles"), py::arg("boxes") = DArr(std::vector<py::ssize_t>{0, 4}),
      "The render's 4D tile test (h_i sets and H_j cells of tile's static path; tiletest/precision_4d.h in "
      "params.precision_tile, tiles widened as a render widens them) of one static triangle v0 (3, 3) "
      "(pixel-homogeneous) against tiles (K, 4) = (x0, x1, y0, y1): culled64 / culled (K, G*G), the lens cells "
      "culled in float64 and in the precision; overflow (K,); max_abs (fixed: the largest register, the "
      "fewest int_bits n satisfy max_abs < 2^n); sigma64 / sigma (orientation over the lens; 0: no H_j); "
      "lens_vertices (n, 4) = (a_x, a_y, b_x, b_y) of the footprint polygon; per lens box boxes[b] = (u0, u1, v0, "
      "v1) INTERVAL's screen bounds (lx, hx, ly, hy) in float64 (box64) and in the precision (box, moved outward "
      "by their error bounds), box_overflow, max_abs_box (fixed: the largest register of the bounds).");

  m.def(
      "precision_probe_5d",
      [](const RenderParams& p, const FArr& v0, const FArr& v1, const DArr& tiles, const DArr& points) {
        require_shape(v0, {3, 3}, "v0");
        require_shape(v1, {3, 3}, "v1");
        require_shape(tiles, {-1, 4}, "tiles");
        require_shape(points, {tiles.shape(0), 5}, "points");
        validate_domains(p);  // time_splits sizes the sub-intervals, lens_grid the cells
        require_finite(v0, "v0");
        require_finite(v1, "v1");
        require_within(tiles, 0x1p24, "tiles", "finite pixel coordinates within +-2^24");
        require_within(points, 0x1p24, "points", "finite coordinates within +-2^24");
        const FrameConst fc = make_frame_const(p);
        const float col[9] = {1, 1, 1, 1, 1, 1, 1, 1, 1};
        TriSetup tri;
        Counters c;
        setup_triangle<FastArith>(v0.data(), v1.data(), col, 0, p, fc, tri, c);
        py::dict out;
        out["dim_class"] = c[Counter::setup_culled_near] ? -1 : static_cast<int>(tri.cls);
        out["moving"] = tri.moving;
        if (c[Counter::setup_culled_near] || !tri.moving) return out;
        // the render's set-up of a moving triangle (tile, motion_test intervals): sub-intervals, H5 (no oracle)
        const int S = p.time_splits, G = p.lens_grid, n = static_cast<int>(tiles.shape(0));
        std::uint64_t ops = 0;
        iv::MotionSetup ms;
        iv::motion_setup<FastArith>(tri, fc, S, ms, ops);
        tiletest::MotionH5 h5;
        tiletest::h5_setup<FastArith>(ms, fc, tiletest::H5Oracle{}, h5, ops);
        const bool with_h5 = p.halfspace_H5;
        const Precision prec = p.precision_tile;
        const iv::ClipBox clip = iv::clip_box(p);
        const tiletest::ScopedSnapMargin snap_margin(snap_margin_px(p.precision_sample, prec));
        tiletest::Motion5DPrecision p5;
        if (prec.kind != PrecisionKind::kFloat64) p5.setup(prec, ms, 0.5 * fc.near_d, with_h5 ? &h5 : nullptr);
        py::array_t<bool> kept64(n), kept(n), overflow(n);
        iv::TileIntervals ti;
        tiletest::CellMask h5m[iv::kMaxSplits];
        // a sample of the tile passes the (lens, time) region: t in t̂_k, (u, v) in the lens sets and not in
        // an H5-culled cell of its sub-interval k (the render's selection, tile.cpp raster_motion)
        auto pass = [&](bool any, const double* q) {
          if (!any) return false;
          const float u = static_cast<float>(q[2]), v = static_cast<float>(q[3]), t = static_cast<float>(q[4]);
          const int k = std::clamp(static_cast<int>(std::floor(static_cast<double>(t) * S)), 0, S - 1);
          if (!ti.active[k] || !(t >= ti.tlo[k] && t <= ti.thi[k])) return false;
          if (ms.lens && !(tiletest::axis_pass(ti.sx[k], u) && tiletest::axis_pass(ti.sy[k], v))) return false;
          const int i = std::clamp(static_cast<int>(std::floor((u + 1.0) * 0.5 * G)), 0, G - 1);
          const int j = std::clamp(static_cast<int>(std::floor((v + 1.0) * 0.5 * G)), 0, G - 1);
          return !h5m[k].test(j * G + i);
        };
        for (int r = 0; r < n; ++r) {
          const double* q = tiles.data() + 4 * static_cast<std::size_t>(r);
          const double* pt = points.data() + 5 * static_cast<std::size_t>(r);
          const double x0 = tiletest::expand_lo(q[0]), x1 = tiletest::expand_hi(q[1]);
          const double y0 = tiletest::expand_lo(q[2]), y1 = tiletest::expand_hi(q[3]);
          Counters cc;
          bool any = iv::motion_tile_intervals<FastArith>(ms, clip, tri.cls, x0, x1, y0, y1, ti, ops, cc, p.halfspace_h);
          for (int k = 0; k < S; ++k) {
            h5m[k].reset();
            std::uint64_t lines = 0;
            if (with_h5 && any && ti.active[k] && h5.sub[k].usable)
              h5m[k] = tiletest::h5_culled_cells<FastArith>(h5, k, x0, x1, y0, y1, ti.tlo[k], ti.thi[k], G, 0, G - 1, 0,
                                                            G - 1, ops, lines);
          }
          kept64.mutable_data()[r] = pass(any, pt);
          if (prec.kind == PrecisionKind::kFloat64) {
            kept.mutable_data()[r] = kept64.mutable_data()[r];
            overflow.mutable_data()[r] = false;
            continue;
          }
          bool o1, o2 = false;
          any = p5.tile_intervals(clip, x0, x1, y0, y1, ti, p.halfspace_h, o1);
          for (int k = 0; k < S; ++k) {
            h5m[k].reset();
            bool ok;
            if (with_h5 && any && ti.active[k]) {
              h5m[k] = p5.h5_cells(h5, k, x0, x1, y0, y1, ti.tlo[k], ti.thi[k], G, 0, G - 1, 0, G - 1, ok);
              o2 |= ok;
            }
          }
          kept.mutable_data()[r] = pass(any, pt);
          overflow.mutable_data()[r] = o1 || o2;
        }
        int usable = 0;
        for (int k = 0; k < S; ++k) usable += h5.sub[k].usable;
        out["kept64"] = kept64;
        out["kept"] = kept;
        out["overflow"] = overflow;
        out["max_abs"] = prec.kind == PrecisionKind::kFixed ? p5.ar.max_abs : 0.0;
        out["max_abs_h5"] = prec.kind == PrecisionKind::kFixed ? p5.ar_h5.max_abs : 0.0;
        out["h5_usable"] = usable;
        out["bounds"] = py::make_tuple(tri.bx0, tri.bx1, tri.by0, tri.by1);
        return out;
      },
      py::arg("params"), py::arg("v0"), py::arg("v1"), py::arg("tiles"), py::arg("points"),
      "The render's motion tile tests (tile with motion_test intervals: t̂ and 5D lens sets per time sub-interval, "
      "and with params.halfspace_H5 the H5 cells over the whole lens grid; intervals/precision_5d.h in "
      "params.precision_tile, tiles widened as a render widens them) of one triangle moving from v0 to v1 (3, 3) "
      "(pixel-homogeneous): per row r the tile tiles[r] = (x0, x1, y0, y1) and the sample points[r] = (x, y, u, v, "
      "t); kept64 / kept (N,): the sample passes the tile's (lens, time) region in float64 / in the precision; "
      "overflow (N,); max_abs / max_abs_h5 (fixed: the largest register of t̂ with the lens sets / of H5, the "
      "fewest int_bits n satisfy max_abs < 2^n); "
      "h5_usable (sub-intervals with an H5 test); bounds (the set-up's pixel bounds x0, x1, y0, y1). A static "
      "triangle returns dim_class and moving only.");
}

}  // namespace rast5d::bindings
