// Render parameters handed from Python (sim/pipeline.py validates them first).
#pragma once

#include <string>

namespace rast5d {

enum class LensShape : int { kSquare = 0, kDisk = 1, kHexagon = 2 };

struct RenderParams {
  // Image.
  int width = 0;
  int height = 0;
  // Camera, in the engine's pixel-homogeneous clip space (see docs/conventions.md):
  // X_h = (x_clip + w) * width / 2, Y_h = (w - y_clip) * height / 2, W = w.
  // Depth of field is the shear X'_h = X_h + u * coc_x_px * (W - F), Y'_h = Y_h + v * coc_y_px * (W - F).
  double coc_x_px = 0.0;  // CoC radius at infinity in pixels (signed shear coefficient for u)
  double coc_y_px = 0.0;  // same for v (negative: image rows grow downwards, lens v points up)
  double focus_w = 1.0;   // F: view depth of the focus plane
  double near_w = 0.01;   // near plane: samples whose hit point has W < near_w are rejected
  LensShape lens_shape = LensShape::kDisk;
  // Pipeline.
  std::string algorithm = "bruteforce";
  int tile_size = 2;       // tile edge in pixels: 1, 2, 4 or 8
  int lens_grid = 4;       // G: G x G lens-grid cells over [-1, 1]^2
  int hinterleave_tile = 8;
  int threads = 0;         // 0: all hardware threads
  int bin_size = 64;       // screen bin edge in pixels (multiple of 8)
  bool halfspace_h = true;  // 001 Table 2 switches
  bool halfspace_H = true;
  bool selective_H = true;  // 001 Appendix A oracle
  bool oracle_full = false; // Eq. 11-12 instead of the simplified Eq. 15
  double c_sample = -1.0;   // oracle sample-test cost (ops); < 0: the documented 4D sample-test cost
  double c_tile = -1.0;     // oracle cost of one H_j line against one tile; < 0: documented
  bool backface_cull = false;
  bool exact_ops = false;   // run kernels on the counting scalar type
  bool count_optimal = true;  // instrument tile.samples_optimal
  // Sample table facts (filled by sim.render from the table).
  bool table_has_lens = true;
  bool table_has_time = true;
  // Timing model (issue 6 part B, docs/timing.md): record one work record per (triangle, bin)
  // visit for the cycle-approximate timing model.
  bool record_timing = true;
  // Shading, texturing and the texture cache (issue 6 part A; docs/shading.md).
  int shading_mode = 4;             // ShadingMode: 0 per_sample, 1 msaa, 2 per_lens_cell, 3 cache, 4 none
  int shading_cache_entries = 1024; // cache mode: LRU entries
  int shading_grid = 1;             // cache mode: shading-grid points per pixel edge
  int tex_count = 0;                // texture slots per shader, 0..4 (0: untextured)
  int tex_filter = 1;               // TexFilter: 0 bilinear, 1 trilinear
  int tex_layout = 1;               // TexLayout: 0 linear, 1 blocked 4x4, 2 blocked 4x4 Morton
  int tex_sample_dist = -1;         // texture index of the 000 §5.3 sample-distribution texture, or -1
  int tex_cache_bytes = 16384;      // hardware.tex_cache
  int tex_cache_line_bytes = 64;
  int tex_cache_ways = 4;           // 0 = fully associative
  int tex_cache_count = 1;
  // Issue 5, the 5D pipeline (sim/pipeline.py: time_splits, motion_test, clip, zhat, hiz):
  int time_splits = 1;            // S time sub-intervals per shutter for moving triangles (tile)
  int time_strata = 8;            // time strata per lens cell in the sample table index (multiple of S)
  bool motion_intervals = true;   // tile: t̂ / per-sub-interval lens sets (false: whole-shutter h_i)
  double clip_u_lo = -1.0, clip_u_hi = 1.0;  // user clip box (002 §2); samples outside are rejected
  double clip_v_lo = -1.0, clip_v_hi = 1.0;
  double clip_t_lo = 0.0, clip_t_hi = 1.0;
  bool zhat_planes = true;        // ẑ: moving box + moving planes (002 App. A); false: vertex min/max
  bool zhat_stats = false;        // tile: compute ẑ for every accepted pair (tightness counters)
  bool hiz_enabled = false;       // tile: zmax/zmin culling against per-tile HiZ
  int hiz_tile = 8;               // HiZ tile edge in pixels (>= tile_size, <= 8)
  int query_first = -1;           // occlusion query: triangles from this index are the query (no writes)
  int query_mode = 0;             // 0 none, 1 sample-based, 2 interval-based (ẑ vs HiZ, abort)
};

}  // namespace rast5d
