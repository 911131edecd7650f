// Shared helpers of the binding files: numpy array types, shape checks, the sample-table
// conversion, counters as a dict, and one register function per binding file (module.cpp calls
// them in order).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <string>

#include "core/counters.h"
#include "core/sample_table.h"

namespace rast5d::bindings {

namespace py = pybind11;

using FArr = py::array_t<float, py::array::c_style | py::array::forcecast>;
using IArr = py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>;

inline void require_shape(const py::array& a, std::initializer_list<py::ssize_t> shape, const char* name) {
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

inline SampleTable make_table(const FArr& samples, int grid, const IArr& lens_index, const FArr& lens_uv) {
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

inline py::dict counters_to_dict(const Counters& c) {
  py::dict d;
  for (int i = 0; i < kNumCounters; ++i)
    d[py::str(std::string(kCounterInfo[i].name))] = py::int_(c.v[i]);
  return d;
}


void register_params(py::module_& m);        // params.cpp: RenderParams, param_specs, choices
void register_render(py::module_& m);        // render.cpp: render, sample-table buckets, registries
void register_timing(py::module_& m);        // timing.cpp: timing records and the timing model
void register_conservative(py::module_& m);  // conservative.cpp: conservative rasterization mode
void register_selftest(py::module_& m);      // selftest.cpp: probes and unit checks for the tests
void register_simd(py::module_& m);          // simd.cpp: the SIMD sample tests beside the scalar ones

}  // namespace rast5d::bindings
