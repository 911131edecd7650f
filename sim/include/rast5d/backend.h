// Backend: per-sample depth buffer (LESS) and colour for one screen bin, and the box resolve.
// A bin is owned by one thread at a time, so the buffers need no locks; triangles reach a bin in
// submission order, so the result does not depend on the thread count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace rast5d {

struct BinRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // pixels [x0, x1) x [y0, y1)
};

class BinBuffers {
 public:
  void begin(const BinRect& r, int spp) {
    rect_ = r;
    spp_ = spp;
    w_ = r.x1 - r.x0;
    const std::size_t n = static_cast<std::size_t>(w_) * (r.y1 - r.y0) * spp;
    depth_.assign(n, std::numeric_limits<float>::infinity());
    color_.assign(n * 3, 0.0f);
    tri_.assign(n, -1);
  }
  std::size_t slot(int px, int py, int s) const {
    return (static_cast<std::size_t>(py - rect_.y0) * w_ + (px - rect_.x0)) * spp_ + s;
  }
  float& depth(std::size_t slot) { return depth_[slot]; }
  float* color(std::size_t slot) { return &color_[slot * 3]; }
  void set_triangle(std::size_t slot, std::int32_t index) { tri_[slot] = index; }

  // Copy the per-sample depth and triangle index of the bin into full-frame (H, W, spp) arrays.
  void export_samples(float* depth, std::int32_t* tri, int width) const {
    for (int py = rect_.y0; py < rect_.y1; ++py)
      for (int px = rect_.x0; px < rect_.x1; ++px) {
        const std::size_t src = slot(px, py, 0);
        const std::size_t dst = (static_cast<std::size_t>(py) * width + px) * spp_;
        for (int s = 0; s < spp_; ++s) {
          depth[dst + s] = depth_[src + s];
          tri[dst + s] = tri_[src + s];
        }
      }
  }

  // Box filter: the mean of the pixel's samples (background black). image is height x width x 3.
  void resolve(float* image, int width) const {
    const float inv = 1.0f / static_cast<float>(spp_);
    for (int py = rect_.y0; py < rect_.y1; ++py) {
      for (int px = rect_.x0; px < rect_.x1; ++px) {
        float acc[3] = {0, 0, 0};
        const std::size_t base = slot(px, py, 0);
        for (int s = 0; s < spp_; ++s)
          for (int ch = 0; ch < 3; ++ch) acc[ch] += color_[(base + s) * 3 + ch];
        float* out = &image[(static_cast<std::size_t>(py) * width + px) * 3];
        for (int ch = 0; ch < 3; ++ch) out[ch] = acc[ch] * inv;
      }
    }
  }

 private:
  BinRect rect_;
  int spp_ = 1, w_ = 0;
  std::vector<float> depth_, color_;
  std::vector<std::int32_t> tri_;
};

}  // namespace rast5d
