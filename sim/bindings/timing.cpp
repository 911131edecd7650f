// The timing model (docs/timing.md): the work-record dtype, the units and figures, the estimate.
#include "bindings.h"

#include <cmath>

#include <pybind11/stl.h>

#include <vector>

#include "timing/timing.h"

namespace rast5d::bindings {

void register_timing(py::module_& m) {
  PYBIND11_NUMPY_DTYPE(TileWork, bin, triangles, tile_tests, sample_tests, depth_tests, quads, texel_fetches,
                       tex_misses, memory_bytes);


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
        if (!(std::isfinite(tex_hit_latency) && std::isfinite(tex_miss_latency)))
          throw std::invalid_argument("tex_hit_latency, tex_miss_latency: expected finite numbers");
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
}

}  // namespace rast5d::bindings
