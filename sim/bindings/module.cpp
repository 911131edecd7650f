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
#include "rast5d/conservative.h"
#include "rast5d/intervals.h"
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

  m.def(
      "render",
      [](const RenderParams& p, const FArr& v0, const FArr& v1, const FArr& colors, const FArr& samples,
         const IArr& lens_index, const FArr& lens_uv, bool export_samples) {
        require_shape(v0, {-1, 3, 3}, "v0");
        const py::ssize_t n = v0.shape(0);
        require_shape(v1, {n, 3, 3}, "v1");
        require_shape(colors, {n, 3, 3}, "colors");
        SampleTable table = make_table(samples, p.lens_grid, lens_index, lens_uv);
        table.set_time_strata(p.time_strata);  // (lens cell, time stratum) index, issue 5
        SceneArrays scene{static_cast<int>(n), v0.data(), v1.data(), colors.data()};
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
      py::arg("lens_index"), py::arg("lens_uv"), py::arg("export_samples") = false,
      "Render pixel-homogeneous triangles; returns {'image', 'counters'[, 'sample_depth', "
      "'sample_triangle']}. The GIL is released; Ctrl-C interrupts.");

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

  // ---- issue 5: conservative rasterization mode (002 Fig. 2) ----
  m.def(
      "conservative_raster",
      [](const RenderParams& p, const FArr& v0, const FArr& v1, bool reduce, std::uint64_t max_records) {
        require_shape(v0, {-1, 3, 3}, "v0");
        const py::ssize_t n = v0.shape(0);
        require_shape(v1, {n, 3, 3}, "v1");
        if (p.width < 1 || p.height < 1 || p.width > 16384 || p.height > 16384)
          throw std::invalid_argument("width/height: expected 1..16384");
        if (p.time_splits < 1 || p.time_splits > iv::kMaxSplits)
          throw std::invalid_argument("time_splits: expected 1..16, got " + std::to_string(p.time_splits));
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
