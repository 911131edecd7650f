// Backend: per-sample depth buffer (LESS) and colour for one screen bin, and the box resolve.
// A bin is owned by one thread at a time, so the buffers need no locks; triangles reach a bin in
// submission order, so the result does not depend on the thread count.
#pragma once

#include <algorithm>
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
    if (hiz_tile_ > 0) {
      hx_ = (w_ + hiz_tile_ - 1) / hiz_tile_;
      const int hy = (r.y1 - r.y0 + hiz_tile_ - 1) / hiz_tile_;
      const std::size_t nh = static_cast<std::size_t>(hx_) * hy;
      hiz_min_.assign(nh, std::numeric_limits<float>::infinity());
      hiz_max_.assign(nh, std::numeric_limits<float>::infinity());
      hiz_dirty_.assign(nh, 0);
      dirty_list_.clear();
    }
  }

  // ---- HiZ (002 §3, 000 §5.4): per HiZ tile (hiz_tile x hiz_tile pixels of the bin) the
  // min and max of the per-sample depths, +inf while any sample is empty. Conservative at all
  // times: a traversal marks the HiZ tiles it may have written (hiz_mark) and calls hiz_update()
  // after each triangle, which recomputes the marked tiles from the depth buffer (as hardware does
  // on tile write-back). Contract: hiz_max(px, py) >= every depth of the tile, hiz_min <= every.
  void set_hiz_tile(int h) { hiz_tile_ = h; }
  std::size_t hiz_index(int px, int py) const {
    return static_cast<std::size_t>((py - rect_.y0) / hiz_tile_) * hx_ + (px - rect_.x0) / hiz_tile_;
  }
  float hiz_min(int px, int py) const { return hiz_min_[hiz_index(px, py)]; }
  float hiz_max(int px, int py) const { return hiz_max_[hiz_index(px, py)]; }
  void hiz_mark(int px, int py) {
    const std::size_t i = hiz_index(px, py);
    if (!hiz_dirty_[i]) hiz_dirty_[i] = 1, dirty_list_.push_back(i);
  }
  // Recompute the marked HiZ tiles; returns how many changed (each is one 8-byte HiZ write).
  int hiz_update() {
    int changed = 0;
    for (const std::size_t i : dirty_list_) {
      hiz_dirty_[i] = 0;
      const int hx = static_cast<int>(i % hx_), hy = static_cast<int>(i / hx_);
      const int x0 = rect_.x0 + hx * hiz_tile_, y0 = rect_.y0 + hy * hiz_tile_;
      const int x1 = std::min(rect_.x1, x0 + hiz_tile_), y1 = std::min(rect_.y1, y0 + hiz_tile_);
      float mn = std::numeric_limits<float>::infinity(), mx = -std::numeric_limits<float>::infinity();
      for (int py = y0; py < y1; ++py)
        for (int px = x0; px < x1; ++px) {
          const std::size_t b = slot(px, py, 0);
          for (int s = 0; s < spp_; ++s) mn = std::min(mn, depth_[b + s]), mx = std::max(mx, depth_[b + s]);
        }
      if (mn != hiz_min_[i] || mx != hiz_max_[i]) ++changed;
      hiz_min_[i] = mn, hiz_max_[i] = mx;
    }
    dirty_list_.clear();
    return changed;
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
  int hiz_tile_ = 0, hx_ = 0;
  std::vector<float> hiz_min_, hiz_max_;
  std::vector<std::uint8_t> hiz_dirty_;
  std::vector<std::size_t> dirty_list_;
};

}  // namespace rast5d
