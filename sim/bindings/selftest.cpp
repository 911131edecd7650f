// Test-only entry points: the exact sample test at given points, the operation-cost self-checks
// (sim/engine/selftest/), and the texture cache and texture unit against Python references.
#include "bindings.h"

#include <pybind11/stl.h>

#include <random>
#include <string>
#include <vector>

#include "backend/cache_model.h"
#include "backend/texture.h"
#include "selftest/kernel_costs.h"
#include "selftest/probe.h"

namespace rast5d::bindings {

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
        std::vector<float> img(static_cast<std::size_t>(height) * width, 0.0f);
        TextureSet ts;
        ts.add(img.data(), height, width, 1);
        ts.layout(lay);
        if (level < 0 || level >= ts.levels(0)) throw std::invalid_argument("level: out of range");
        return ts.address(0, level, x, y);
      },
      py::arg("height"), py::arg("width"), py::arg("layout"), py::arg("level"), py::arg("x"), py::arg("y"),
      "Byte address of texel (x, y) of a level of a lone height x width texture; layout: a name in "
      "choices()['texture_layouts'].");
}

}  // namespace rast5d::bindings
