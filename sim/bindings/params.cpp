// RenderParams: the frame parameters every engine entry point takes.
#include "bindings.h"

#include "core/params.h"

namespace rast5d::bindings {

void register_params(py::module_& m) {
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
}

}  // namespace rast5d::bindings
