// A scene as the engine receives it: plain arrays, owned by the caller for the length of a render.
#pragma once

#include <cstdint>
#include <vector>

namespace rast5d {

struct SceneArrays {
  int n = 0;
  const float* v0 = nullptr;      // n x 3 x 3: (X_h, Y_h, W) per vertex at t = 0
  const float* v1 = nullptr;      // same at t = 1
  const float* colors = nullptr;  // n x 3 x 3 linear RGB per vertex
  const float* alpha = nullptr;   // n opacities in [0, 1] (optional: stochastic transparency)
  // Texturing (optional): uvs n x 3 x 2; tex_slots n x 4 texture indices (-1 unused); textures.
  const float* uvs = nullptr;
  const std::int32_t* tex_slots = nullptr;
  struct TextureView {
    const float* data;
    int height, width, channels;
  };
  std::vector<TextureView> textures;
};

}  // namespace rast5d
