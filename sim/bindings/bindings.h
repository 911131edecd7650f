// Shared helpers of the binding files: numpy array types, shape checks, the sample-table
// conversion, counters as a dict, and one register function per binding file (module.cpp calls
// them in order).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <string>

#include "core/counters.h"
#include "memory/sample_buffers.h"
#include "timing/timing.h"
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

// Every value of a float array is finite; std::invalid_argument naming the array, the item (the
// index along axis 0, and the triangle's vertex for (N, 3, k) arrays) and the value otherwise.
inline void require_finite(const FArr& a, const char* name) {
  const float* d = a.data();
  const py::ssize_t n = a.size();
  for (py::ssize_t i = 0; i < n; ++i) {
    if (std::isfinite(d[i])) continue;
    std::string where;
    if (a.ndim() == 3 && a.shape(1) == 3) {
      const py::ssize_t per = 3 * a.shape(2);
      where = "triangle " + std::to_string(i / per) + " vertex " + std::to_string((i % per) / a.shape(2));
    } else {
      where = "element " + std::to_string(i);
    }
    throw std::invalid_argument(std::string(name) + ": " + where + " is not finite (" + std::to_string(d[i]) + ")");
  }
}

inline SampleTable make_table(const FArr& samples, int grid, const IArr& lens_index, const FArr& lens_uv) {
  require_shape(samples, {-1, -1, -1, 5}, "samples");
  const int P = static_cast<int>(samples.shape(0));
  if (samples.shape(1) != P) throw std::invalid_argument("samples: the table must be P x P pixels");
  const int spp = static_cast<int>(samples.shape(2));
  if (P < 1 || spp < 1) throw std::invalid_argument("samples: expected at least one pixel and one sample");
  // The coordinates' domains (sim.SampleTable checks the same): x, y in [0, 1], u, v in [-1, 1],
  // t in [0, 1]; NaN fails every comparison and is refused too.
  static constexpr const char* kCol[5] = {"x", "y", "u", "v", "t"};
  static constexpr float kLo[5] = {0.0f, 0.0f, -1.0f, -1.0f, 0.0f};
  const float* sd = samples.data();
  for (py::ssize_t i = 0; i < samples.size(); ++i) {
    const int c = static_cast<int>(i % 5);
    if (sd[i] >= kLo[c] && sd[i] <= 1.0f) continue;
    const py::ssize_t s = i / 5;
    throw std::invalid_argument("samples: pixel (" + std::to_string(s / spp % P) + ", " +
                                std::to_string(s / spp / P) + ") sample " + std::to_string(s % spp) + " " + kCol[c] +
                                " = " + std::to_string(sd[i]) + " is outside [" + std::to_string(kLo[c]) + ", 1]");
  }
  const bool inter = lens_index.size() > 0;
  if (inter) require_shape(lens_index, {P, P, spp}, "lens_index");
  if (inter) require_shape(lens_uv, {-1, 2}, "lens_uv");
  if (inter) {
    require_finite(lens_uv, "lens_uv");
    const std::int32_t* li = lens_index.data();
    const py::ssize_t n_lens = lens_uv.shape(0);
    for (py::ssize_t i = 0; i < lens_index.size(); ++i)
      if (li[i] < 0 || li[i] >= n_lens)
        throw std::invalid_argument("lens_index: pixel (" + std::to_string(i / spp % P) + ", " +
                                    std::to_string(i / spp / P) + ") sample " + std::to_string(i % spp) + " = " +
                                    std::to_string(li[i]) + ", expected 0.." + std::to_string(n_lens - 1) +
                                    " (one per lens_uv row)");
  }
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
// The raw figures of the timing model and of the memory model (timing.cpp).
py::dict timing_to_dict(const TimingResult& r);
py::dict memory_to_dict(const memory::MemoryTotals& m, bool depth, bool color, std::uint64_t color_bytes_written);
void register_conservative(py::module_& m);  // conservative.cpp: conservative rasterization mode
void register_selftest(py::module_& m);      // selftest.cpp: probes and unit checks for the tests
void register_gpu(py::module_& m);           // gpu.cpp: the conventional-GPU geometry shader probe
void register_simd(py::module_& m);          // simd.cpp: the SIMD sample tests beside the scalar ones

}  // namespace rast5d::bindings
