// The conventional-GPU pipeline's geometry shader, probed directly (tests, reports): the bound of
// one triangle by one method (gpu/geometry_shader.h).
#include "bindings.h"

#include <pybind11/stl.h>

#include <stdexcept>
#include <string>

#include "gpu/geometry_shader.h"
#include "setup/setup.h"

namespace rast5d::bindings {

namespace {

gpu::Method method_by_name(const std::string& name) {
  static const std::pair<const char*, gpu::Method> kNames[] = {
      {"pe_triangle", gpu::Method::kPETriangle}, {"vr_triangle", gpu::Method::kVRTriangle},
      {"hexagon2d", gpu::Method::kHexagon2D},    {"wedge", gpu::Method::kWedge},
      {"reduced_wedge", gpu::Method::kReducedWedge}, {"hexagon3d", gpu::Method::kHexagon3D},
      {"convex_hull", gpu::Method::kConvexHull}, {"adaptive", gpu::Method::kAdaptive},
      {"box", gpu::Method::kBox}};
  for (const auto& [n, m] : kNames)
    if (name == n) return m;
  throw std::invalid_argument("method: unknown '" + name +
                              "' (known: pe_triangle, vr_triangle, hexagon2d, wedge, reduced_wedge, hexagon3d, "
                              "convex_hull, adaptive, box)");
}

const char* method_name(gpu::Method m) {
  switch (m) {
    case gpu::Method::kPETriangle: return "pe_triangle";
    case gpu::Method::kVRTriangle: return "vr_triangle";
    case gpu::Method::kHexagon2D: return "hexagon2d";
    case gpu::Method::kWedge: return "wedge";
    case gpu::Method::kReducedWedge: return "reduced_wedge";
    case gpu::Method::kHexagon3D: return "hexagon3d";
    case gpu::Method::kConvexHull: return "convex_hull";
    case gpu::Method::kAdaptive: return "adaptive";
    case gpu::Method::kBox: return "box";
  }
  return "?";
}

const char* fallback_name(gpu::Fallback f) {
  switch (f) {
    case gpu::Fallback::kNone: return "none";
    case gpu::Fallback::kNear: return "near";
    case gpu::Fallback::kMotion: return "motion";
    case gpu::Fallback::kDegenerate: return "degenerate";
    case gpu::Fallback::kVR: return "vr";
    case gpu::Fallback::kReduced: return "reduced";
  }
  return "?";
}

}  // namespace

void register_gpu(py::module_& m) {
  m.def(
      "gpu_bound",
      [](const std::string& method, const RenderParams& p, const FArr& v0, const FArr& v1, bool disk) {
        require_shape(v0, {3, 3}, "v0");
        require_shape(v1, {3, 3}, "v1");
        const gpu::Method meth = method_by_name(method);
        const FrameConst fc = make_frame_const(p);
        const float col[9] = {1, 1, 1, 1, 1, 1, 1, 1, 1};
        TriSetup tri;
        Counters c;
        py::dict out;
        if (!setup_triangle<FastArith>(v0.data(), v1.data(), col, 0, p, fc, tri, c)) {
          out["culled"] = true;
          return out;
        }
        gpu::GsFrame g;
        g.kx = fc.lens_active ? fc.kx_d : 0.0;
        g.ky = fc.lens_active ? fc.ky_d : 0.0;
        g.focus = fc.focus_d, g.neg_focus = -fc.focus_d;
        g.near_clip = fc.near_d * (1.0 - 0x1p-12);
        g.s = 1.0 / std::max(1, std::max(p.width, p.height));
        g.inv_s = std::max(1, std::max(p.width, p.height));
        g.disk = disk;
        g.adaptive_ratio = p.gpu_adaptive_ratio;
        std::uint64_t ops = 0;
        const gpu::Bound b = gpu::GeometryShader<FastArith>(g).run(meth, tri, ops);
        py::array_t<double> planes({b.n_planes, 3}), verts({b.n_verts, 2});
        for (int i = 0; i < b.n_planes; ++i) {
          planes.mutable_at(i, 0) = b.nx[i], planes.mutable_at(i, 1) = b.ny[i], planes.mutable_at(i, 2) = b.h[i];
        }
        for (int i = 0; i < b.n_verts; ++i) verts.mutable_at(i, 0) = b.vx[i], verts.mutable_at(i, 1) = b.vy[i];
        out["culled"] = false;
        out["planes"] = planes;
        out["vertices"] = verts;
        out["area"] = b.area;
        out["used"] = method_name(b.used);
        out["fallback"] = fallback_name(b.fallback);
        out["volume_clipped"] = b.volume_clipped;
        out["out_vertices"] = b.out_vertices;
        out["out_triangles"] = b.out_triangles;
        out["ops"] = ops;
        out["box"] = py::make_tuple(tri.lo_x, tri.hi_x, tri.lo_y, tri.hi_y);
        return out;
      },
      py::arg("method"), py::arg("params"), py::arg("v0"), py::arg("v1"), py::arg("disk") = true,
      "The conventional-GPU geometry shader's bound of one triangle (pixel-homogeneous vertices v0 at t = 0, v1 "
      "at t = 1): {'planes' (n, 3) rows nx, ny, h of n.x <= h (margins included), 'vertices', 'area' (px^2), "
      "'used', 'fallback', 'volume_clipped', 'out_vertices', 'out_triangles', 'ops', 'box', 'culled'}. "
      "disk: the lens set is the unit disk (else the square).");
}

}  // namespace rast5d::bindings
