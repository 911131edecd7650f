// HiZ ([Nilsson 2012] §3, [Toth 2008] §5.4): per HiZ tile (tile x tile
// pixels of a screen bin) the min and max of the per-sample depths, +inf while any sample is empty.
// A traversal marks the HiZ tiles it may have written (mark) and the bin's buffers call update()
// after each triangle, which recomputes the marked tiles from the depth buffer (as hardware does on
// tile write-back). Read by z-culling and occlusion queries (backend/zcull.h).
//
// Contract: conservative at all times between triangles: max(px, py) >= every depth of the HiZ
// tile, min(px, py) <= every depth.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/bin_rect.h"

namespace rast5d {

class HiZBuffer {
 public:
  void set_tile(int h) { tile_ = h; }
  bool enabled() const { return tile_ > 0; }

  void begin(const BinRect& r) {
    rect_ = r;
    hx_ = (r.x1 - r.x0 + tile_ - 1) / tile_;
    const int hy = (r.y1 - r.y0 + tile_ - 1) / tile_;
    const std::size_t nh = static_cast<std::size_t>(hx_) * hy;
    min_.assign(nh, std::numeric_limits<float>::infinity());
    max_.assign(nh, std::numeric_limits<float>::infinity());
    dirty_.assign(nh, 0);
    dirty_list_.clear();
  }

  float min(int px, int py) const { return min_[index(px, py)]; }
  float max(int px, int py) const { return max_[index(px, py)]; }
  void mark(int px, int py) {
    const std::size_t i = index(px, py);
    if (!dirty_[i]) dirty_[i] = 1, dirty_list_.push_back(i);
  }

  // Recompute the marked tiles from the bin's depth buffer (depth of sample s of pixel (px, py) at
  // ((py - y0) * width + px - x0) * spp + s); returns how many changed (each is one 8-byte write).
  int update(const float* depth, int spp) {
    const int width = rect_.x1 - rect_.x0;
    int changed = 0;
    for (const std::size_t i : dirty_list_) {
      dirty_[i] = 0;
      const int hx = static_cast<int>(i % hx_), hy = static_cast<int>(i / hx_);
      const int x0 = rect_.x0 + hx * tile_, y0 = rect_.y0 + hy * tile_;
      const int x1 = std::min(rect_.x1, x0 + tile_), y1 = std::min(rect_.y1, y0 + tile_);
      float mn = std::numeric_limits<float>::infinity(), mx = -std::numeric_limits<float>::infinity();
      for (int py = y0; py < y1; ++py)
        for (int px = x0; px < x1; ++px) {
          const std::size_t b = (static_cast<std::size_t>(py - rect_.y0) * width + (px - rect_.x0)) * spp;
          for (int s = 0; s < spp; ++s) mn = std::min(mn, depth[b + s]), mx = std::max(mx, depth[b + s]);
        }
      if (mn != min_[i] || mx != max_[i]) ++changed;
      min_[i] = mn, max_[i] = mx;
    }
    dirty_list_.clear();
    return changed;
  }

 private:
  std::size_t index(int px, int py) const {
    return static_cast<std::size_t>((py - rect_.y0) / tile_) * hx_ + (px - rect_.x0) / tile_;
  }

  BinRect rect_;
  int tile_ = 0, hx_ = 0;
  std::vector<float> min_, max_;
  std::vector<std::uint8_t> dirty_;
  std::vector<std::size_t> dirty_list_;
};

}  // namespace rast5d
