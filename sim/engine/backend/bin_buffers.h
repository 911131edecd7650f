// The bin buffers: per-sample depth buffer (LESS), colour and triangle index for one screen bin,
// the box resolve, and the bin's HiZ (backend/hiz.h).
// A bin is owned by one thread at a time, so the buffers need no locks; triangles reach a bin in
// submission order, so the result does not depend on the thread count.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "backend/hiz.h"
#include "core/bin_rect.h"
#include "memory/sample_buffers.h"

namespace rast5d {

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
    if (hiz_.enabled()) hiz_.begin(r);
  }

  // The memory model's line marks (memory/sample_buffers.h), or nullptr when it does not run: the
  // backend marks the lines each depth test and colour write touches.
  void set_line_marks(memory::LineMarks* m) { marks_ = m; }
  memory::LineMarks* line_marks() const { return marks_; }
  // The bin's depth samples, row-major pixels of spp samples (read by the memory model's compressor).
  const std::vector<float>& depth_samples() const { return depth_; }

  // The bin's HiZ (backend/hiz.h; enabled by set_tile before begin()).
  HiZBuffer& hiz() { return hiz_; }
  // Recompute the HiZ tiles marked since the last update; returns how many changed.
  int hiz_update() { return hiz_.update(depth_.data(), spp_); }

  std::size_t slot(int px, int py, int s) const {
    return (static_cast<std::size_t>(py - rect_.y0) * w_ + (px - rect_.x0)) * spp_ + s;
  }
  float& depth(std::size_t slot) { return depth_[slot]; }
  // Whole-buffer views for the backend's vectorised path (backend/sample_backend.h): depth and triangle
  // index per slot, colour 3 floats per slot; the bin's rectangle, row width and samples per pixel.
  float* depth_data() { return depth_.data(); }
  float* color_data() { return color_.data(); }
  std::int32_t* triangle_data() { return tri_.data(); }
  std::size_t slots() const { return depth_.size(); }
  const BinRect& rect() const { return rect_; }
  int row_pixels() const { return w_; }
  int spp() const { return spp_; }
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
  HiZBuffer hiz_;
  memory::LineMarks* marks_ = nullptr;
};

}  // namespace rast5d
