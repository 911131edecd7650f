// The types every stage of a frame shares: the per-render constants, the frame a stage reads, the
// triangle's dimension class and its set-up (filled by setup/, read by every later stage).
#pragma once

#include <cstdint>

#include "core/params.h"
#include "core/sample_table.h"

namespace rast5d {

// The cheapest exact sample kernel of a triangle (sampletest/kernels.h): static and in focus (2D),
// moving (3D), defocused (4D), or both (5D).
enum class DimClass : int { k2D = 0, k3D = 1, k4D = 2, k5D = 3 };

// Per-render constants shared by every stage.
struct FrameConst {
  int width = 0, height = 0;
  bool lens_active = false;  // camera has a blur and the table has a lens dimension
  bool time_active = false;  // the table has a time dimension
  // float constants of the sample kernels (see sampletest/kernels.h): cx = kx * W + neg_kx_f
  float kx = 0, ky = 0, neg_kx_f = 0, neg_ky_f = 0, focus = 1, neg_near = 0;
  // double versions for tile tests
  double kx_d = 0, ky_d = 0, focus_d = 1, near_d = 0;
};

FrameConst make_frame_const(const RenderParams& p);

// What every stage of one frame reads: the parameters, their derived constants, the sample table.
struct Frame {
  const RenderParams& p;
  const FrameConst& fc;
  const SampleTable& table;
};

struct TriSetup {
  std::uint32_t index = 0;  // submission order
  DimClass cls = DimClass::k2D;
  bool moving = false;
  bool defocused = false;
  bool near_clipped = false;  // static, crosses the near plane: footprint is the clipped polygon
  bool full_bounds = false;   // moving and may cross the near plane: full-screen bounds
  // Sample-kernel data: pixel-homogeneous vertices at t = 0, deltas to t = 1, static shear.
  float X[3], Y[3], W[3];
  float dX[3], dY[3], dW[3];
  float cx[3], cy[3];
  float color[3][3];
  float alpha = 1.0f;  // opacity (scene alpha; < 1: per-sample alpha coverage, backend/alpha.h)
  // Conservative pixel bounds, clipped to the image: [bx0, bx1) x [by0, by1), and the unrounded
  // bounds they came from (before widening and clipping).
  int bx0 = 0, by0 = 0, bx1 = 0, by1 = 0;
  double lo_x = 0, hi_x = 0, lo_y = 0, hi_y = 0;
  // Footprint for tile tests, in double: a convex polygon with W >= near (static triangles: the
  // triangle or its near-clipped polygon, 3 or 4 vertices; moving triangles: poly_n = 0).
  int poly_n = 0;
  double poly[4][3];
};

}  // namespace rast5d
