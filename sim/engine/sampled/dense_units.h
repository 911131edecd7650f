// Sampled simulation with pipeline.sample_split = s > 0 (sim/sampling.py): a sampling unit smaller
// than a bin for the dense bins.
//
// With H = round(f K) / 2 strata over the K bins that hold triangles and W their brute-force work, a
// bin whose work exceeds s W / H (s times a stratum's share) is cut into g = ceil(work / (s W / H))
// units of its triangles (at most one per triangle): its (triangle, bin) pairs sorted by their work in
// the bin (the pixels of the triangle's bounds in the bin, times spp; ties by submission order) are
// dealt to the units in serpentine order (0 .. g-1, g-1 .. 0, ...), so the units of a bin hold
// similar work and similar mixes of large and small triangles. A unit's work is the sum of its
// pairs', so the units of a bin add up to the bin's work exactly.
//
// The units join the population the stratified draw (sampled/bin_sample.h) takes from: the per-unit
// work vector is every screen bin's (a dense bin's entry set to 0: it is never drawn whole), followed
// by the units' (index n_bins + u). A drawn unit is traversed as its screen bin holding only the
// unit's triangles, in submission order. Counters summed over (triangle, bin) visits that do not read
// the depth buffer are sums over the units of a bin; counters that depend on the triangles drawn
// before (depth passes, HiZ, z-culling, shading, the sample buffers' caches) are not, and
// sim/sampling.py does not estimate them under units (NaN).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace rast5d {

// The units of a render's dense bins.
struct DenseUnits {
  std::vector<int> bin;              // screen bin of dense bin d
  std::vector<int> of_bin;           // per screen bin: its d, or -1 (empty when no bin is dense)
  std::vector<std::size_t> first;    // dense bin d's pairs: tri / unit [first[d], first[d + 1])
  std::vector<std::uint32_t> tri;    // the dense bins' triangles, in submission order per bin
  std::vector<int> unit;             // the unit (0 .. units() - 1) each pair is dealt to
  std::vector<int> unit_dense;       // the dense bin d of each unit
  bool empty() const { return bin.empty(); }
  std::size_t units() const { return unit_dense.size(); }
  // The unit of triangle i in screen bin b (b dense, i one of its triangles).
  int unit_of(int b, std::uint32_t i) const {
    const int d = of_bin[static_cast<std::size_t>(b)];
    const auto lo = tri.begin() + static_cast<std::ptrdiff_t>(first[d]);
    const auto hi = tri.begin() + static_cast<std::ptrdiff_t>(first[d + 1]);
    return unit[static_cast<std::size_t>(std::lower_bound(lo, hi, i) - tri.begin())];
  }
};

// A sampled draw's screen bin and triangle list per drawn entry (sampled_setup): lists[k] empty =
// the whole bin.
struct SplitDraw {
  std::vector<int> bins;
  std::vector<std::vector<std::uint32_t>> lists;
  bool empty() const { return bins.empty(); }
};

// Cuts the dense bins of `work` (per screen bin, brute-force work times spp; extended in place by the
// units' work, the dense bins' own entries set to 0). bounds(i, x0, y0, x1, y1) gives triangle i's
// screen bounds (false: culled). Nothing is cut when the draw takes every bin (2 H >= K) or has fewer
// than 2 strata (the draw refuses it).
template <class Bounds>
DenseUnits split_dense_bins(std::vector<std::int64_t>& work, double fraction, double share, int spp, int B, int bins_x,
                            int bins_y, std::size_t n, Bounds bounds) {
  DenseUnits u;
  const std::size_t n_bins = work.size();
  long long K = 0;
  double total = 0;
  for (std::int64_t w : work) K += w > 0, total += static_cast<double>(w);
  const long long H = static_cast<long long>(fraction * static_cast<double>(K) + 0.5) / 2;
  if (2 * H >= K || H < 2) return u;
  const double cap = share * total / static_cast<double>(H);
  u.of_bin.assign(n_bins, -1);
  for (std::size_t b = 0; b < n_bins; ++b)
    if (static_cast<double>(work[b]) > cap) u.of_bin[b] = static_cast<int>(u.bin.size()), u.bin.push_back(static_cast<int>(b));
  if (u.bin.empty()) return DenseUnits{};
  // The (triangle, work in the bin) pairs of each dense bin.
  std::vector<std::vector<std::pair<std::uint32_t, std::int64_t>>> pairs(u.bin.size());
  for (std::size_t i = 0; i < n; ++i) {
    int x0, y0, x1, y1;
    if (!bounds(i, x0, y0, x1, y1)) continue;
    for (int by = y0 / B; by <= (y1 - 1) / B && by < bins_y; ++by)
      for (int bx = x0 / B; bx <= (x1 - 1) / B && bx < bins_x; ++bx) {
        const int d = u.of_bin[static_cast<std::size_t>(by) * bins_x + bx];
        if (d < 0) continue;
        const std::int64_t dx = std::min(x1, (bx + 1) * B) - std::max(x0, bx * B);
        const std::int64_t dy = std::min(y1, (by + 1) * B) - std::max(y0, by * B);
        pairs[d].emplace_back(static_cast<std::uint32_t>(i), dx * dy * spp);
      }
  }
  u.first.push_back(0);
  std::vector<std::int64_t> unit_work;
  for (std::size_t d = 0; d < u.bin.size(); ++d) {
    const auto& pr = pairs[d];
    const std::size_t m = pr.size();
    const double w = static_cast<double>(work[static_cast<std::size_t>(u.bin[d])]);
    const std::size_t g = std::max<std::size_t>(1, std::min<std::size_t>(m, static_cast<std::size_t>(std::ceil(w / cap))));
    std::vector<std::size_t> order(m);
    for (std::size_t j = 0; j < m; ++j) order[j] = j;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return pr[a].second > pr[b].second; });
    const int base = static_cast<int>(u.unit_dense.size());
    std::vector<int> dealt(m);
    for (std::size_t r = 0; r < m; ++r) {
      const std::size_t round = r / g, pos = r % g;
      dealt[order[r]] = base + static_cast<int>(round % 2 == 0 ? pos : g - 1 - pos);
    }
    u.unit_dense.insert(u.unit_dense.end(), g, static_cast<int>(d));
    unit_work.insert(unit_work.end(), g, 0);
    for (std::size_t j = 0; j < m; ++j) {
      u.tri.push_back(pr[j].first);
      u.unit.push_back(dealt[j]);
      unit_work[static_cast<std::size_t>(dealt[j])] += pr[j].second;
    }
    u.first.push_back(u.tri.size());
    work[static_cast<std::size_t>(u.bin[d])] = 0;
  }
  work.insert(work.end(), unit_work.begin(), unit_work.end());
  return u;
}

}  // namespace rast5d
