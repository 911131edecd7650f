// The timing and memory model (docs/timing.md, docs/memory.md): the work-record dtype, the units and
// figures, the model's configuration, the estimate over kept records.
#include "bindings.h"

#include <cmath>

#include <pybind11/stl.h>

#include <vector>

#include "frame/bin_stream.h"
#include "memory/sample_buffers.h"
#include "timing/reference.h"
#include "timing/timing.h"

namespace rast5d::bindings {

py::dict timing_to_dict(const TimingResult& r) {
  py::dict d;
  d["timing.cycles"] = r.cycles;
  d["timing.records"] = r.records;
  d["timing.cores"] = r.cores;
  for (int k = 0; k < kNumUnits; ++k)
    for (const auto& f : kUnitFigures)
      d[py::str("timing." + std::string(kUnitInfo[k].name) + "." + f.suffix)] = r.units[k].*f.field;
  d["dram.bytes_depth"] = r.dram_depth;
  d["dram.bytes_color"] = r.dram_color;
  d["dram.bytes_texture"] = r.dram_texture;
  d["dram.bytes_hiz"] = r.dram_hiz;
  d["dram.bytes"] = r.dram_depth + r.dram_color + r.dram_texture + r.dram_hiz;
  return d;
}

py::dict memory_to_dict(const memory::MemoryTotals& m, bool depth, bool color, std::uint64_t color_bytes_written) {
  py::dict d;
  if (depth) {
    d["depth.cache.accesses"] = m.depth_accesses;
    d["depth.cache.hits"] = m.depth_hits;
    d["depth.cache.misses"] = m.depth_misses;
    d["depth.cache.fills"] = m.depth_fills;
    d["depth.cache.writebacks"] = m.depth_writebacks;
    d["depth.bytes_raw"] = m.depth_writeback_raw_bytes;
    d["depth.bytes_stored"] = m.depth_writeback_bytes;
  }
  // Compressed over raw depth bytes written: 1 with compression off (or nothing written back).
  d["depth.compression_ratio"] = depth && m.depth_writeback_raw_bytes
                                     ? static_cast<double>(m.depth_writeback_bytes) / static_cast<double>(m.depth_writeback_raw_bytes)
                                     : 1.0;
  if (color) {
    d["color.cache.accesses"] = m.color_accesses;
    d["color.cache.hits"] = m.color_hits;
    d["color.cache.misses"] = m.color_misses;
    d["color.bytes_written"] = color_bytes_written;
    d["color.bytes_resolve"] = m.color_resolve_read_bytes + m.color_resolve_write_bytes;
  }
  return d;
}

void register_timing(py::module_& m) {
  m.attr("STREAM_BUDGET") = py::int_(rast5d::BinStream::kBudget);  // records (frame/bin_stream.h)
  PYBIND11_NUMPY_DTYPE(TileWork, bin, gs_ops, gs_floats, raster_pixels, ps_ops, triangles, tile_tests, sample_tests,
                       depth_tests, depth_fills, quads, texel_fetches, tex_misses, dram_depth, dram_color, dram_texture,
                       dram_hiz, dram_bytes);

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
    for (const auto& f : memory::kMemoryFigures) d[py::str(f.name)] = py::make_tuple(f.unit, f.description);
    return d;
  }, "{name: (unit, description)} of the figures of the timing and memory model.");

  py::class_<TimingConfig>(m, "TimingConfig",
                           "The timing model's units (docs/timing.md): per unit in timing_units() order its "
                           "throughput, latency and FIFO depth; the texture hit and miss latencies, the depth-line "
                           "fill latency, the cores, whether records bypass the units they have no work for. Validated on construction (ValueError naming the field).")
      .def(py::init([](const std::vector<double>& throughput, const std::vector<double>& latency,
                       const std::vector<std::int64_t>& fifo, double tex_hit_latency, double tex_miss_latency,
                       double fill_latency, int cores, bool bypass_idle) {
             if (throughput.size() != kNumUnits || latency.size() != kNumUnits || fifo.size() != kNumUnits)
               throw std::invalid_argument("throughput, latency, fifo: expected one value per unit (" +
                                           std::to_string(kNumUnits) + ")");
             if (!(std::isfinite(tex_hit_latency) && std::isfinite(tex_miss_latency)))
               throw std::invalid_argument("tex_hit_latency, tex_miss_latency: expected finite numbers");
             TimingConfig cfg;
             for (int k = 0; k < kNumUnits; ++k) cfg.units[k] = {throughput[k], latency[k], fifo[k]};
             cfg.tex_hit_latency = tex_hit_latency;
             cfg.tex_miss_latency = tex_miss_latency;
             cfg.fill_latency = fill_latency;
             cfg.cores = cores;
             cfg.bypass_idle = bypass_idle;
             cfg.validate();
             return cfg;
           }),
           py::arg("throughput"), py::arg("latency"), py::arg("fifo"), py::arg("tex_hit_latency") = 0.0,
           py::arg("tex_miss_latency") = 0.0, py::arg("fill_latency") = 0.0, py::arg("cores") = 1,
           py::arg("bypass_idle") = true)
      .def_readonly("cores", &TimingConfig::cores);

  m.def(
      "timing_estimate",
      [](const py::array_t<TileWork, py::array::c_style>& records, const TimingConfig& cfg) {
        if (records.ndim() != 1) throw std::invalid_argument("records: expected a 1-D array");
        TimingResult r;
        {
          py::gil_scoped_release release;
          r = simulate_timing(records.data(), static_cast<std::size_t>(records.size()), cfg);
        }
        return timing_to_dict(r);
      },
      py::arg("records"), py::arg("config"),
      "Run the timing model on work records; returns flat {'timing.cycles', 'timing.<unit>.busy_cycles', "
      "'dram.bytes', ...}. Raises ValueError for a bad configuration.");

  m.def(
      "timing_reference",
      [](const py::array_t<TileWork, py::array::c_style>& records, const TimingConfig& cfg) {
        if (records.ndim() != 1) throw std::invalid_argument("records: expected a 1-D array");
        ReferenceResult r;
        {
          py::gil_scoped_release release;
          r = simulate_reference(records.data(), static_cast<std::size_t>(records.size()), cfg);
        }
        py::dict d;
        d["timing.cycles"] = r.cycles;
        d["timing.items"] = r.items;
        d["timing.steps"] = r.steps;
        d["timing.cores"] = cfg.cores;
        for (int k = 0; k < kNumUnits; ++k)
          for (const auto& f : kUnitFigures)
            d[py::str("timing." + std::string(kUnitInfo[k].name) + "." + f.suffix)] = r.units[k].*f.field;
        return d;
      },
      py::arg("records"), py::arg("config"),
      "The cycle-stepped reference of the timing model (timing/reference.h): the same units on per-quad "
      "items with real FIFO occupancy; returns {'timing.cycles', 'timing.items', 'timing.steps', "
      "'timing.<unit>.busy_cycles', ...}.");
}

}  // namespace rast5d::bindings
