// Direct evaluation of the exact sample test for one triangle at arbitrary sample points, for the
// reference tests (numpy ray caster, dimension specialisation). Not part of the timed pipeline.
#pragma once

#include <cstdint>
#include <vector>

#include "core/params.h"

namespace rast5d {

struct ProbeResult {
  int dim_class = 0;  // 0..3 = 2D, 3D, 4D, 5D; -1 if culled by the near plane in setup
  std::vector<std::uint8_t> covered, hit;
  std::vector<float> depth, w_hit;
};

// points: m x 5 (sx, sy absolute pixel coordinates, u, v, t). force_general: use the 5D kernel
// whatever the class.
ProbeResult probe_samples(const RenderParams& p, const float v0[9], const float v1[9],
                          const float* points, int m, bool force_general);

}  // namespace rast5d
