// Conservative rasterization mode ([Nilsson 2012] §2, Fig. 2 bottom right): 1 x 1 pixel
// tiles, no sample test; every (triangle, pixel) pair whose tile test passes emits a fragment
// record with the tile's intervals (û, v̂, t̂) and depth interval ẑ, or is reduced per pixel into a
// tz-box (min t_lo, min z_lo, max t_hi, max z_hi; [Nilsson 2012] §3, continuous collision detection).
//
// Contract: for every sample (x, y, u, v, t) the exact sample test hits in pixel (px, py), the
// triangle's record of that pixel exists and contains (u, v, t) in its intervals and the hit's
// depth in [z_lo, z_hi] (geometric ẑ, no float margin: see intervals/depth_interval.h).
#pragma once

#include <cstdint>
#include <vector>

#include "core/counters.h"
#include "core/params.h"
#include "core/scene.h"

namespace rast5d {

struct ConservativeRecord {
  std::int32_t x, y, triangle;
  float u_lo, u_hi, v_lo, v_hi, t_lo, t_hi, z_lo, z_hi;
};

struct ConservativeResult {
  std::vector<ConservativeRecord> records;  // reduce == false
  std::vector<float> tz_box;                // reduce == true: height x width x 4 (t_lo, z_lo, t_hi, z_hi)
  std::vector<std::int32_t> count;          // reduce == true: fragments per pixel
  Counters counters;
};

// Single-threaded. Throws std::length_error when more than max_records records would be made.
ConservativeResult conservative_raster(const RenderParams& p, const SceneArrays& scene, bool reduce,
                                       std::uint64_t max_records);

}  // namespace rast5d
