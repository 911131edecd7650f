// sim._core: the pybind11 face of the engine. The Python layer (sim/*.py) validates user input and
// converts scenes and cameras into these arrays; see sim/_core.pyi for the documented signatures.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>
#include <random>
#include <stdexcept>
#include <string>

#include "rast5d/counters.h"
#include "rast5d/kernel_costs.h"
#include "rast5d/probe.h"
#include "rast5d/render.h"
#include "rast5d/timing.h"
#include "rast5d/shading.h"
#include "rast5d/texture.h"
#include "rast5d/conservative.h"
#include <cstring>

namespace py = pybind11;
using namespace rast5d;

namespace {

using FArr = py::array_t<float, py::array::c_style | py::array::forcecast>;
using IArr = py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>;

void require_shape(const py::array& a, std::initializer_list<py::ssize_t> shape, const char* name) {
  bool ok = a.ndim() == static_cast<py::ssize_t>(shape.size());
  int k = 0;
  for (py::ssize_t d : shape) {
    if (!ok) break;
    if (d >= 0 && a.shape(k) != d) ok = false;
    ++k;
  }
  if (!ok) {
    std::string got = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) {
      if (i) got.append(", ");
      got.append(std::to_string(a.shape(i)));
    }
    got.append(")");
    throw std::invalid_argument(std::string(name).append(": unexpected shape ").append(got));
  }
}

SampleTable make_table(const FArr& samples, int grid, const IArr& lens_index, const FArr& lens_uv) {
  require_shape(samples, {-1, -1, -1, 5}, "samples");
  const int P = static_cast<int>(samples.shape(0));
  if (samples.shape(1) != P) throw std::invalid_argument("samples: the table must be P x P pixels");
  const int spp = static_cast<int>(samples.shape(2));
  const bool inter = lens_index.size() > 0;
  if (inter) require_shape(lens_index, {P, P, spp}, "lens_index");
  if (inter) require_shape(lens_uv, {-1, 2}, "lens_uv");
  return SampleTable(P, spp, samples.data(), grid, inter ? lens_index.data() : nullptr,
                     inter ? static_cast<int>(lens_uv.shape(0)) : 0, inter ? lens_uv.data() : nullptr);
}

py::dict counters_to_dict(const Counters& c) {
  py::dict d;
  for (int i = 0; i < kNumCounters; ++i)
    d[py::str(std::string(kCounterInfo[i].name))] = py::int_(c.v[i]);
  return d;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "rast5d engine: a functional, operation-counting 5D stochastic rasterizer";

  py::enum_<LensShape>(m, "LensShape")
      .value("square", LensShape::kSquare)
      .value("disk", LensShape::kDisk)
      .value("hexagon", LensShape::kHexagon);

  py::class_<RenderParams>(m, "RenderParams")
      .def(py::init<>())
      .def_readwrite("width", &RenderParams::width)
      .def_readwrite("height", &RenderParams::height)
      .def_readwrite("coc_x_px", &RenderParams::coc_x_px)
      .def_readwrite("coc_y_px", &RenderParams::coc_y_px)
      .def_readwrite("focus_w", &RenderParams::focus_w)
      .def_readwrite("near_w", &RenderParams::near_w)
      .def_readwrite("lens_shape", &RenderParams::lens_shape)
      .def_readwrite("algorithm", &RenderParams::algorithm)
      .def_readwrite("tile_size", &RenderParams::tile_size)
      .def_readwrite("lens_grid", &RenderParams::lens_grid)
      .def_readwrite("hinterleave_tile", &RenderParams::hinterleave_tile)
      .def_readwrite("threads", &RenderParams::threads)
      .def_readwrite("bin_size", &RenderParams::bin_size)
      .def_readwrite("halfspace_h", &RenderParams::halfspace_h)
      .def_readwrite("halfspace_H", &RenderParams::halfspace_H)
      .def_readwrite("selective_H", &RenderParams::selective_H)
      .def_readwrite("oracle_full", &RenderParams::oracle_full)
      .def_readwrite("c_sample", &RenderParams::c_sample)
      .def_readwrite("c_tile", &RenderParams::c_tile)
      .def_readwrite("backface_cull", &RenderParams::backface_cull)
      .def_readwrite("exact_ops", &RenderParams::exact_ops)
      .def_readwrite("count_optimal", &RenderParams::count_optimal)
      .def_readwrite("table_has_lens", &RenderParams::table_has_lens)
      .def_readwrite("table_has_time", &RenderParams::table_has_time)
      .def_readwrite("record_timing", &RenderParams::record_timing)
      .def_readwrite("shading_mode", &RenderParams::shading_mode)
      .def_readwrite("shading_cache_entries", &RenderParams::shading_cache_entries)
      .def_readwrite("shading_grid", &RenderParams::shading_grid)
      .def_readwrite("tex_count", &RenderParams::tex_count)
      .def_readwrite("tex_filter", &RenderParams::tex_filter)
      .def_readwrite("tex_layout", &RenderParams::tex_layout)
      .def_readwrite("tex_sample_dist", &RenderParams::tex_sample_dist)
      .def_readwrite("tex_cache_bytes", &RenderParams::tex_cache_bytes)
      .def_readwrite("tex_cache_line_bytes", &RenderParams::tex_cache_line_bytes)
      .def_readwrite("tex_cache_ways", &RenderParams::tex_cache_ways)
      .def_readwrite("tex_cache_count", &RenderParams::tex_cache_count)
      // issue 5
      .def_readwrite("time_splits", &RenderParams::time_splits)
      .def_readwrite("time_strata", &RenderParams::time_strata)
      .def_readwrite("motion_intervals", &RenderParams::motion_intervals)
      .def_readwrite("clip_u_lo", &RenderParams::clip_u_lo)
      .def_readwrite("clip_u_hi", &RenderParams::clip_u_hi)
      .def_readwrite("clip_v_lo", &RenderParams::clip_v_lo)
      .def_readwrite("clip_v_hi", &RenderParams::clip_v_hi)
      .def_readwrite("clip_t_lo", &RenderParams::clip_t_lo)
      .def_readwrite("clip_t_hi", &RenderParams::clip_t_hi)
      .def_readwrite("zhat_planes", &RenderParams::zhat_planes)
      .def_readwrite("zhat_stats", &RenderParams::zhat_stats)
      .def_readwrite("hiz_enabled", &RenderParams::hiz_enabled)
      .def_readwrite("hiz_tile", &RenderParams::hiz_tile)
      .def_readwrite("query_first", &RenderParams::query_first)
      .def_readwrite("query_mode", &RenderParams::query_mode);

  PYBIND11_NUMPY_DTYPE(TileWork, bin, triangles, tile_tests, sample_tests, depth_tests, quads, texel_fetches,
                       tex_misses, memory_bytes);

  m.def(
      "render",
      [](const RenderParams& p, const FArr& v0, const FArr& v1, const FArr& colors, const FArr& samples,
         const IArr& lens_index, const FArr& lens_uv, bool export_samples, std::optional<FArr> uvs,
         std::optional<IArr> tex_slots, std::vector<FArr> textures) {
        require_shape(v0, {-1, 3, 3}, "v0");
        const py::ssize_t n = v0.shape(0);
        require_shape(v1, {n, 3, 3}, "v1");
        require_shape(colors, {n, 3, 3}, "colors");
        SampleTable table = make_table(samples, p.lens_grid, lens_index, lens_uv);
        table.set_time_strata(p.time_strata);  // (lens cell, time stratum) index, issue 5
        SceneArrays scene{static_cast<int>(n), v0.data(), v1.data(), colors.data()};
        if (uvs && tex_slots) {  // texturing (issue 6): uvs (n, 3, 2), tex_slots (n, 4), textures (H, W, C)
          require_shape(*uvs, {n, 3, 2}, "uvs");
          require_shape(*tex_slots, {n, kMaxTexSlots}, "tex_slots");
          scene.uvs = uvs->data(), scene.tex_slots = tex_slots->data();
        }
        for (const FArr& t : textures) {
          require_shape(t, {-1, -1, -1}, "textures[i]");
          if (t.shape(0) < 1 || t.shape(1) < 1 || t.shape(2) < 1 || t.shape(2) > 4)
            throw std::invalid_argument("textures[i]: expected (H, W, 1..4) with H, W >= 1");
          scene.textures.push_back({t.data(), static_cast<int>(t.shape(0)), static_cast<int>(t.shape(1)),
                                    static_cast<int>(t.shape(2))});
        }
        std::optional<py::error_already_set> pending;
        RenderResult res;
        {
          py::gil_scoped_release release;
          res = render(
              p, scene, table,
              [&pending]() {
                py::gil_scoped_acquire acquire;
                if (PyErr_CheckSignals() != 0) {
                  pending.emplace();
                  return true;
                }
                return false;
              },
              export_samples);
        }
        if (pending) throw *pending;
        py::array_t<float> image({p.height, p.width, 3});
        std::copy(res.image.begin(), res.image.end(), image.mutable_data());
        py::dict out;
        out["image"] = image;
        out["counters"] = counters_to_dict(res.counters);
        if (p.record_timing) {
          py::array_t<TileWork> recs(static_cast<py::ssize_t>(res.timing_records.size()));
          std::copy(res.timing_records.begin(), res.timing_records.end(), recs.mutable_data());
          out["timing_records"] = recs;
        }
        if (export_samples) {
          const py::ssize_t spp = table.spp();
          py::array_t<float> depth({static_cast<py::ssize_t>(p.height), static_cast<py::ssize_t>(p.width), spp});
          py::array_t<std::int32_t> tri({static_cast<py::ssize_t>(p.height), static_cast<py::ssize_t>(p.width), spp});
          std::copy(res.sample_depth.begin(), res.sample_depth.end(), depth.mutable_data());
          std::copy(res.sample_triangle.begin(), res.sample_triangle.end(), tri.mutable_data());
          out["sample_depth"] = depth;
          out["sample_triangle"] = tri;
        }
        return out;
      },
      py::arg("params"), py::arg("v0"), py::arg("v1"), py::arg("colors"), py::arg("samples"),
      py::arg("lens_index"), py::arg("lens_uv"), py::arg("export_samples") = false, py::arg("uvs") = py::none(),
      py::arg("tex_slots") = py::none(), py::arg("textures") = std::vector<FArr>(),
      "Render pixel-homogeneous triangles; returns {'image', 'counters'[, 'timing_records'][, "
      "'sample_depth', 'sample_triangle']}. The GIL is released; Ctrl-C interrupts.");

  m.def(
      "lens_grid_buckets",
      [](const FArr& samples, int grid) {
        if (grid < 1 || grid > 64) throw std::invalid_argument("grid: expected 1..64");
        SampleTable t = make_table(samples, grid, IArr(), FArr());
        const py::ssize_t P = t.period(), S = t.spp(), C = static_cast<py::ssize_t>(grid) * grid;
        py::array_t<std::int32_t> order({P, P, S}), counts({P, P, C}), offsets({P, P, C});
        auto o = order.mutable_unchecked<3>();
        auto cn = counts.mutable_unchecked<3>();
        auto of = offsets.mutable_unchecked<3>();
        for (int y = 0; y < P; ++y)
          for (int x = 0; x < P; ++x) {
            const PixelSamples ps = t.pixel(x, y);
            for (int s = 0; s < S; ++s) o(y, x, s) = ps.cell_order[s];
            for (int c = 0; c < C; ++c) {
              of(y, x, c) = ps.cell_offsets[c];
              cn(y, x, c) = ps.cell_offsets[c + 1] - ps.cell_offsets[c];
            }
          }
        return py::make_tuple(order, counts, offsets);
      },
      py::arg("samples"), py::arg("grid"),
      "Lens-grid buckets (001 Fig. 10): (order (P,P,spp), counts (P,P,G*G), offsets (P,P,G*G)).");

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

  m.def("counter_docs", []() {
    py::dict d;
    for (const auto& info : kCounterInfo)
      d[py::str(std::string(info.name))] =
          py::make_tuple(std::string(info.unit), std::string(info.description));
    return d;
  });

  m.def("algorithms", []() {
    py::list l;
    for (const auto& a : algorithms())
      l.append(py::make_tuple(a.name, a.description, a.needs_interleaved_table));
    return l;
  });

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

  // ---- timing model (issue 6 part B; docs/timing.md) ----
  m.def("timing_record_dtype", []() { return py::dtype::of<TileWork>(); },
        "The numpy structured dtype of one timing work record (rast5d::TileWork).");

  m.def("timing_units", []() {
    py::list l;
    for (const auto& u : kUnitInfo)
      l.append(py::make_tuple(std::string(u.name), std::string(u.currency), std::string(u.description)));
    return l;
  }, "[(name, currency, description)] of the timing model's units in pipeline order.");

  m.def("timing_docs", []() {
    py::dict d;
    for (const auto& f : timing_figures()) d[py::str(f.name)] = py::make_tuple(f.unit, f.description);
    return d;
  }, "{name: (unit, description)} of the figures timing_estimate returns.");

  m.def(
      "timing_estimate",
      [](const py::array_t<TileWork, py::array::c_style>& records, const std::vector<double>& throughput,
         const std::vector<double>& latency, const std::vector<std::int64_t>& fifo, double tex_hit_latency,
         double tex_miss_latency, int cores) {
        if (records.ndim() != 1) throw std::invalid_argument("records: expected a 1-D array");
        if (throughput.size() != kNumUnits || latency.size() != kNumUnits || fifo.size() != kNumUnits)
          throw std::invalid_argument("throughput, latency, fifo: expected one value per unit (" +
                                      std::to_string(kNumUnits) + ")");
        TimingConfig cfg;
        for (int k = 0; k < kNumUnits; ++k) cfg.units[k] = {throughput[k], latency[k], fifo[k]};
        cfg.tex_hit_latency = tex_hit_latency;
        cfg.tex_miss_latency = tex_miss_latency;
        cfg.cores = cores;
        TimingResult r;
        {
          py::gil_scoped_release release;
          r = simulate_timing(records.data(), static_cast<std::size_t>(records.size()), cfg);
        }
        py::dict d;
        d["timing.cycles"] = r.cycles;
        d["timing.records"] = r.records;
        d["timing.cores"] = r.cores;
        for (int k = 0; k < kNumUnits; ++k)
          for (const auto& f : kUnitFigures)
            d[py::str("timing." + std::string(kUnitInfo[k].name) + "." + f.suffix)] = r.units[k].*f.field;
        return d;
      },
      py::arg("records"), py::arg("throughput"), py::arg("latency"), py::arg("fifo"),
      py::arg("tex_hit_latency"), py::arg("tex_miss_latency"), py::arg("cores") = 1,
      "Run the timing model on work records (units in timing_units() order); returns flat "
      "{'timing.cycles', 'timing.<unit>.busy_cycles', ...}. Raises ValueError for a bad configuration.");

  // ---- issue 6: texture cache and texture unit, exposed for tests against Python references ----
  m.def(
      "simulate_cache",
      [](const py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>& lines, std::uint64_t n_lines,
         std::uint64_t ways) {
        if (n_lines < 1) throw std::invalid_argument("n_lines: expected >= 1");
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
      [](int height, int width, int layout, int level, int x, int y) {
        if (layout < 0 || layout > 2) throw std::invalid_argument("layout: expected 0..2");
        std::vector<float> img(static_cast<std::size_t>(height) * width, 0.0f);
        TextureSet ts;
        ts.add(img.data(), height, width, 1);
        ts.layout(static_cast<TexLayout>(layout));
        if (level < 0 || level >= ts.levels(0)) throw std::invalid_argument("level: out of range");
        return ts.address(0, level, x, y);
      },
      py::arg("height"), py::arg("width"), py::arg("layout"), py::arg("level"), py::arg("x"), py::arg("y"),
      "Byte address of texel (x, y) of a level of a lone height x width texture (layout 0 linear, 1 "
      "blocked 4x4, 2 Morton-ordered 4x4 blocks).");

  // ---- issue 5: conservative rasterization mode (002 Fig. 2) ----
  m.def(
      "conservative_raster",
      [](const RenderParams& p, const FArr& v0, const FArr& v1, bool reduce, std::uint64_t max_records) {
        require_shape(v0, {-1, 3, 3}, "v0");
        const py::ssize_t n = v0.shape(0);
        require_shape(v1, {n, 3, 3}, "v1");
        std::vector<float> colors(static_cast<std::size_t>(n) * 9, 0.0f);
        SceneArrays scene{static_cast<int>(n), v0.data(), v1.data(), colors.data()};
        ConservativeResult res;
        {
          py::gil_scoped_release release;
          res = conservative_raster(p, scene, reduce, max_records);
        }
        py::dict out;
        out["counters"] = counters_to_dict(res.counters);
        if (reduce) {
          py::array_t<float> tz({p.height, p.width, 4});
          std::copy(res.tz_box.begin(), res.tz_box.end(), tz.mutable_data());
          py::array_t<std::int32_t> cnt({p.height, p.width});
          std::copy(res.count.begin(), res.count.end(), cnt.mutable_data());
          out["tz_box"] = tz;
          out["count"] = cnt;
        } else {
          const std::size_t bytes = res.records.size() * sizeof(ConservativeRecord);
          py::array_t<std::uint8_t> raw(static_cast<py::ssize_t>(bytes));
          if (bytes) std::memcpy(raw.mutable_data(), res.records.data(), bytes);
          out["records"] = raw;
          out["record_bytes"] = sizeof(ConservativeRecord);
        }
        return out;
      },
      py::arg("params"), py::arg("v0"), py::arg("v1"), py::arg("reduce"), py::arg("max_records"),
      "Conservative rasterization (issue 5): fragment records or per-pixel tz-boxes.");
}
