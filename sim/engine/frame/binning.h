// The frame's binning stage (frame/render.h): the screen in bins of bin_size pixels, each listing the
// live triangles whose bounds overlap it, in submission order.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/bin_rect.h"
#include "core/params.h"
#include "core/triangle.h"

namespace rast5d {

struct Binning {
  int size = 64, bins_x = 1, bins_y = 1;
  std::vector<std::vector<std::uint32_t>> lists;
  int count() const { return bins_x * bins_y; }
  BinRect rect(int b, int width, int height) const {
    const int bx = b % bins_x, by = b / bins_x;
    return BinRect{bx * size, by * size, std::min(width, (bx + 1) * size), std::min(height, (by + 1) * size)};
  }
  // The bin that charges triangle t's setup: the one holding the top-left corner of its bounds.
  int home(const TriSetup& t) const { return (t.by0 / size) * bins_x + (t.bx0 / size); }
};

inline Binning bin_triangles(const RenderParams& p, const TriSetup* S, const std::vector<std::uint32_t>& live) {
  Binning bn;
  bn.size = p.bin_size;
  bn.bins_x = (p.width + bn.size - 1) / bn.size;
  bn.bins_y = (p.height + bn.size - 1) / bn.size;
  bn.lists.resize(static_cast<std::size_t>(bn.count()));
  for (std::uint32_t i : live) {
    const TriSetup& t = S[i];
    for (int by = t.by0 / bn.size; by <= (t.by1 - 1) / bn.size; ++by)
      for (int bx = t.bx0 / bn.size; bx <= (t.bx1 - 1) / bn.size; ++bx) bn.lists[by * bn.bins_x + bx].push_back(i);
  }
  return bn;
}

}  // namespace rast5d
