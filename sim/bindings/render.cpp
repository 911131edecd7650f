// The render entry point, the sample table's lens-grid buckets, and the counter and algorithm
// registries.
#include "bindings.h"

#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <variant>
#include <vector>

#include "backend/shading.h"
#include "timing/timing.h"
#include "frame/render.h"
#include "sampled/bin_covariates.h"
#include "sampled/bin_sample.h"

namespace rast5d::bindings {

void register_render(py::module_& m) {
  // A sample table with its (lens cell, time stratum) index, built once and shared by every render
  // that passes it instead of the samples array. It holds its own copy of the samples and has no
  // mutator, so it cannot go stale; render() checks its lens grid and strata against the params.
  py::class_<SampleTable, std::shared_ptr<SampleTable>>(
      m, "SampleTableIndex",
      "The engine's sample table with its (lens cell, time stratum) index, built once: pass it to render() "
      "as samples (with empty lens_index and lens_uv) to skip rebuilding the index per render. Immutable.")
      .def(py::init([](const FArr& samples, int grid, int time_strata, const IArr& lens_index, const FArr& lens_uv) {
             auto t = std::make_shared<SampleTable>(make_table(samples, grid, lens_index, lens_uv));
             t->set_time_strata(time_strata);
             return t;
           }),
           py::arg("samples"), py::arg("grid"), py::arg("time_strata"), py::arg("lens_index"), py::arg("lens_uv"))
      .def_property_readonly("period", &SampleTable::period)
      .def_property_readonly("spp", &SampleTable::spp)
      .def_property_readonly("grid", &SampleTable::grid)
      .def_property_readonly("time_strata", &SampleTable::time_strata)
      .def_property_readonly("n_lens", &SampleTable::n_lens);

  m.def(
      "render",
      [](const RenderParams& p, const FArr& v0, const FArr& v1, const FArr& colors,
         const std::variant<std::shared_ptr<SampleTable>, FArr>& samples,
         const IArr& lens_index, const FArr& lens_uv, bool export_samples, std::optional<FArr> uvs,
         std::optional<IArr> tex_slots, std::vector<FArr> textures, std::optional<IArr> bins,
         std::optional<FArr> alpha, std::vector<std::string> pixel_stats,
         std::optional<std::pair<int, int>> trace_pixel, std::optional<py::function> progress,
         std::optional<TimingConfig> timing, bool keep_timing_records) {
        require_shape(v0, {-1, 3, 3}, "v0");
        const py::ssize_t n = v0.shape(0);
        require_shape(v1, {n, 3, 3}, "v1");
        require_shape(colors, {n, 3, 3}, "colors");
        require_finite(v0, "v0");
        require_finite(v1, "v1");
        require_finite(colors, "colors");
        std::optional<SampleTable> built;  // from a samples array: the (lens cell, time stratum) index per render
        const SampleTable* tp = nullptr;
        if (const auto* idx = std::get_if<std::shared_ptr<SampleTable>>(&samples)) {
          if (!*idx) throw std::invalid_argument("samples: expected a float array or a SampleTableIndex, got None");
          tp = idx->get();
          if (tp->grid() != p.lens_grid || tp->time_strata() != p.time_strata)
            throw std::invalid_argument("samples: the SampleTableIndex has lens_grid " + std::to_string(tp->grid()) +
                                        " and time_strata " + std::to_string(tp->time_strata()) +
                                        ", the params ask for " + std::to_string(p.lens_grid) + " and " +
                                        std::to_string(p.time_strata));
          if (lens_index.size() > 0 || lens_uv.size() > 0)
            throw std::invalid_argument("lens_index: a SampleTableIndex holds its own lens_index and lens_uv; "
                                        "pass empty arrays with it");
        } else {
          built.emplace(make_table(std::get<FArr>(samples), p.lens_grid, lens_index, lens_uv));
          built->set_time_strata(p.time_strata);
          tp = &*built;
        }
        const SampleTable& table = *tp;
        SceneArrays scene{static_cast<int>(n), v0.data(), v1.data(), colors.data()};
        if (uvs && tex_slots) {  // texturing: uvs (n, 3, 2), tex_slots (n, 4), textures (H, W, C)
          require_shape(*uvs, {n, 3, 2}, "uvs");
          require_shape(*tex_slots, {n, kMaxTexSlots}, "tex_slots");
          require_finite(*uvs, "uvs");
          scene.uvs = uvs->data(), scene.tex_slots = tex_slots->data();
        }
        if (alpha) {  // per-triangle opacity (stochastic transparency)
          require_shape(*alpha, {n}, "alpha");
          require_finite(*alpha, "alpha");
          scene.alpha = alpha->data();
        }
        for (std::size_t i = 0; i < textures.size(); ++i) {
          const FArr& t = textures[i];
          const std::string name = "textures[" + std::to_string(i) + "]";
          require_shape(t, {-1, -1, -1}, name.c_str());
          if (t.shape(0) < 1 || t.shape(1) < 1 || t.shape(2) < 1 || t.shape(2) > 4)
            throw std::invalid_argument(name + ": expected (H, W, 1..4) with H, W >= 1");
          require_finite(t, name.c_str());
          scene.textures.push_back({t.data(), static_cast<int>(t.shape(0)), static_cast<int>(t.shape(1)),
                                    static_cast<int>(t.shape(2))});
        }
        std::optional<std::vector<int>> bin_list;
        if (bins) {
          require_shape(*bins, {-1}, "bins");
          bin_list.emplace(bins->data(), bins->data() + bins->shape(0));
        }
        // Per-pixel statistics: the named counters' maps (core/pixel_stats.h).
        PixelStats pstats;
        RenderOptions obs;
        obs.export_samples = export_samples;
        obs.bins = bin_list ? &*bin_list : nullptr;
        obs.timing = timing ? &*timing : nullptr;
        obs.keep_timing_records = keep_timing_records;
        if (!pixel_stats.empty() || trace_pixel) {
          std::vector<int> ids;
          for (const auto& name : pixel_stats) {
            int id = -1;
            for (int i = 0; i < kNumCounters; ++i)
              if (kCounterInfo[static_cast<std::size_t>(i)].name == name) id = i;
            if (id < 0) throw std::invalid_argument("pixel_stats: unknown counter '" + name + "'");
            ids.push_back(id);
          }
          pstats.init(p.width, p.height, ids);
          if (trace_pixel) {
            if (trace_pixel->first < 0 || trace_pixel->first >= p.width || trace_pixel->second < 0 ||
                trace_pixel->second >= p.height)
              throw std::invalid_argument("pixel: (" + std::to_string(trace_pixel->first) + ", " +
                                          std::to_string(trace_pixel->second) + ") is outside the " +
                                          std::to_string(p.width) + "x" + std::to_string(p.height) + " image");
            pstats.trace_x = trace_pixel->first, pstats.trace_y = trace_pixel->second;
          }
          obs.pixel_stats = &pstats;
        }
        std::optional<py::error_already_set> pending;
        if (progress)
          obs.progress = [&progress, &pending](int done, int total) {
            if (pending) return;
            py::gil_scoped_acquire acquire;
            try {
              (*progress)(done, total);
            } catch (py::error_already_set& e) {
              pending.emplace(std::move(e));
            }
          };
        RenderResult res;
        {
          py::gil_scoped_release release;
          res = render(
              p, scene, table,
              [&pending]() {
                if (pending) return true;  // progress() raised
                py::gil_scoped_acquire acquire;
                if (PyErr_CheckSignals() != 0) {
                  pending.emplace();
                  return true;
                }
                return false;
              },
              obs);
        }
        if (pending) throw *pending;
        py::array_t<float> image({p.height, p.width, 3});
        std::copy(res.image.begin(), res.image.end(), image.mutable_data());
        py::dict out;
        out["image"] = image;
        out["counters"] = counters_to_dict(res.counters);
        if (!res.sampled.empty()) {  // a bin list or sampled simulation
          const SampledBins& sb = res.sampled;
          const auto n_rows = static_cast<py::ssize_t>(sb.bins.size());
          py::array_t<std::uint64_t> bc({n_rows, static_cast<py::ssize_t>(kNumCounters)});
          std::copy(sb.bin_counters.begin(), sb.bin_counters.end(), bc.mutable_data());
          out["bin_counters"] = bc;  // (len(bins), counters) in counter_docs() order
          out["bins"] = py::array_t<int>(n_rows, sb.bins.data());
          out["bin_stratum"] = py::array_t<int>(static_cast<py::ssize_t>(sb.stratum.size()), sb.stratum.data());
          out["strata_sizes"] = py::array_t<int>(static_cast<py::ssize_t>(sb.strata_sizes.size()), sb.strata_sizes.data());
          out["bin_work"] = py::array_t<std::int64_t>(static_cast<py::ssize_t>(sb.bin_work.size()), sb.bin_work.data());
          out["bin_aux"] = py::array_t<double>({static_cast<py::ssize_t>(sb.bin_work.size()), py::ssize_t{kBinAux}},
                                               sb.bin_aux.data());  // (bins, [coverage, footprint, edge])
          out["bin_aux_total"] = py::array_t<double>(kBinAux, sb.bin_aux_total.data());
        }
        if (res.timed) {
          out["timing"] = timing_to_dict(res.timing);
          out["memory"] = memory_to_dict(res.memory, res.memory_depth, res.memory_color,
                                         res.counters[Counter::depth_passes] *
                                             static_cast<std::uint64_t>(p.color_buffer_bytes_per_sample));
        }
        if (keep_timing_records && res.timed) {
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
        if (obs.pixel_stats) {
          const py::ssize_t k = static_cast<py::ssize_t>(pstats.channels.size());
          py::array_t<std::uint64_t> maps({k, static_cast<py::ssize_t>(p.height), static_cast<py::ssize_t>(p.width)});
          std::copy(pstats.maps.begin(), pstats.maps.end(), maps.mutable_data());
          out["pixel_stats"] = maps;
        }
        if (trace_pixel) {
          py::list events, samples;
          for (const auto& ev : res.trace_events) {
            py::dict d;
            for (const auto& [id, v] : ev.deltas) d[py::str(std::string(kCounterInfo[static_cast<std::size_t>(id)].name))] = v;
            events.append(py::make_tuple(ev.triangle, ev.kind, py::make_tuple(ev.x0, ev.y0, ev.x1, ev.y1), d));
          }
          for (const auto& sm : res.trace_samples) samples.append(py::make_tuple(sm.triangle, sm.sample, sm.covered, sm.hit));
          out["trace_events"] = events;
          out["trace_samples"] = samples;
        }
        return out;
      },
      py::arg("params"), py::arg("v0"), py::arg("v1"), py::arg("colors"), py::arg("samples"),
      py::arg("lens_index"), py::arg("lens_uv"), py::arg("export_samples") = false, py::arg("uvs") = py::none(),
      py::arg("tex_slots") = py::none(), py::arg("textures") = std::vector<FArr>(), py::arg("bins") = py::none(),
      py::arg("alpha") = py::none(),
      py::arg("pixel_stats") = std::vector<std::string>(), py::arg("trace_pixel") = py::none(),
      py::arg("progress") = py::none(), py::arg("timing") = py::none(), py::arg("keep_timing_records") = false,
      "Render pixel-homogeneous triangles; returns {'image', 'counters'[, 'timing', 'memory'][, 'timing_records'][, "
      "'sample_depth', 'sample_triangle'][, 'bin_counters', 'bins', 'bin_stratum', 'strata_sizes', "
      "'bin_work', 'bin_aux', 'bin_aux_total'][, 'pixel_stats' (k, H, W)][, 'trace_events', 'trace_samples']}. samples: "
      "the (P, P, spp, 5) table, or a SampleTableIndex built once for it (then lens_index and lens_uv empty). With params.record_timing the timing and memory model runs on the render (timing: the units, a TimingConfig) and its raw figures are in 'timing' and 'memory'; keep_timing_records keeps the work records. bins (or params.sample_fraction < 1: a stratified draw): render only these screen bins "
      "(row-major) and return their counters, one row per bin in counter_docs() order. The GIL is "
      "released; Ctrl-C interrupts; progress(done_bins, total_bins) is called while it runs.");

  m.def(
      "stratify_bins",
      [](const std::vector<std::int64_t>& work, double fraction, std::uint64_t seed) {
        const BinSample s = stratify_bins(work, fraction, seed);
        return py::make_tuple(s.bins, s.stratum, s.sizes);
      },
      py::arg("work"), py::arg("fraction"), py::arg("seed"),
      "The sampled bins of pipeline.sample_fraction (sampled/bin_sample.h) for per-bin brute-force work: "
      "(bins, stratum of each, strata sizes); sizes empty when every bin with work is drawn.");

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
      "Lens-grid buckets ([Akenine-Möller 2012] Fig. 10): (order (P,P,spp), counts (P,P,G*G), offsets (P,P,G*G)).");

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

  m.def("algorithm_facts", []() {
    py::dict d;
    for (const auto& a : algorithms()) {
      py::dict f;
      f["description"] = a.description;
      f["samples"] = a.samples;
      f["tables"] = a.tables;
      f["depth_cull"] = a.depth_cull;
      f["pipeline"] = a.pipeline;
      d[py::str(a.name)] = f;
    }
    return d;
  }, "{name: {description, samples ('points' | 'lines'), tables ('points' | 'interleaved' | 'lines'), "
     "depth_cull, pipeline ('sample' | 'gpu')}}: the traversal registry's facts about every algorithm.");
}

}  // namespace rast5d::bindings
