// Conservative rasterization mode ([Nilsson 2012] Fig. 2).
#include "bindings.h"

#include <pybind11/stl.h>

#include <cstring>
#include <vector>

#include "conservative/conservative.h"
#include "frame/render.h"

namespace rast5d::bindings {

void register_conservative(py::module_& m) {
  m.def(
      "conservative_raster",
      [](const RenderParams& p, const FArr& v0, const FArr& v1, bool reduce, std::uint64_t max_records) {
        require_shape(v0, {-1, 3, 3}, "v0");
        const py::ssize_t n = v0.shape(0);
        require_shape(v1, {n, 3, 3}, "v1");
        require_finite(v0, "v0");
        require_finite(v1, "v1");
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
      "Conservative rasterization: fragment records or per-pixel tz-boxes.");
}

}  // namespace rast5d::bindings
