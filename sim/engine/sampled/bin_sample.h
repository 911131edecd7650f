// Sampled simulation (pipeline.sample_fraction, sim/sampling.py): which screen bins to traverse.
//
// The bins that hold triangles are sorted by their brute-force work (sum over their triangles of
// the pixels of the triangle's screen bounds inside the bin: what brute force would test, times
// spp) and cut into H strata of neighbouring work; 2 bins are drawn per stratum without
// replacement. Bins without triangles do no traversal work: their counters are exactly zero and
// they are never drawn. Sorting by work makes the strata homogeneous (stratification by size), so
// the estimator's variance is that of the work not explained by brute-force work. Bins heavier than
// a stratum's share of the work are taken with certainty (a take-all stratum).
#pragma once

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace rast5d {

struct BinSample {
  std::vector<int> bins;     // the bins to traverse (sorted by stratum, then bin index)
  std::vector<int> stratum;  // stratum of each
  std::vector<int> sizes;    // bins per stratum
  int candidates = 0;        // bins with triangles
};

// splitmix64: a small, platform-independent generator (the draw must not depend on the standard
// library's distributions).
inline std::uint64_t splitmix64(std::uint64_t& s) {
  std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Throws std::invalid_argument naming sample_fraction when fewer than 2 strata remain. Returns
// every bin with triangles (sizes empty) when the fraction covers them all.
inline BinSample stratify_bins(const std::vector<std::int64_t>& work, double fraction, std::uint64_t seed) {
  BinSample s;
  std::vector<int> cand;
  for (int b = 0; b < static_cast<int>(work.size()); ++b)
    if (work[b] > 0) cand.push_back(b);
  s.candidates = static_cast<int>(cand.size());
  const int H = static_cast<int>(fraction * s.candidates + 0.5) / 2;
  if (2 * H >= s.candidates) {
    s.bins = cand;
    return s;
  }
  if (H < 2)
    throw std::invalid_argument(
        "sample_fraction: " + std::to_string(fraction) + " of the " + std::to_string(s.candidates) +
        " screen bins that hold triangles gives " + std::to_string(H) +
        " strata of 2 bins; a confidence interval needs at least 2 (4 bins): raise sample_fraction or use a "
        "smaller bin_size");
  std::stable_sort(cand.begin(), cand.end(), [&](int a, int b) { return work[a] < work[b]; });
  // Take-all stratum: a bin whose work exceeds a stratum's average share (total / H) is traversed
  // with certainty (it would dominate any stratum it fell in); each such bin uses one draw of the
  // budget. The take-all bins form the last stratum, whose size equals its draws (no variance).
  double total = 0;
  for (int b : cand) total += static_cast<double>(work[b]);
  std::size_t K = cand.size();
  int budget = 2 * H;
  std::vector<int> take_all;
  while (K > 0 && budget - 1 >= 4 && static_cast<double>(work[cand[K - 1]]) * H > total) {
    take_all.push_back(cand[K - 1]);
    total -= static_cast<double>(work[cand[K - 1]]);
    --K, --budget;
  }
  const int H2 = budget / 2;
  std::uint64_t st = seed * 0x2545F4914F6CDD1Dull + 1;
  for (int h = 0; h < H2; ++h) {
    const std::size_t lo = K * h / H2, hi = K * (h + 1) / H2, n = hi - lo;
    const std::size_t i = splitmix64(st) % n;
    std::size_t j = splitmix64(st) % (n - 1);
    if (j >= i) ++j;
    const int a = cand[lo + std::min(i, j)], b = cand[lo + std::max(i, j)];
    s.bins.push_back(a), s.bins.push_back(b);
    s.stratum.push_back(h), s.stratum.push_back(h);
    s.sizes.push_back(static_cast<int>(n));
  }
  if (!take_all.empty()) {
    std::sort(take_all.begin(), take_all.end());
    for (int b : take_all) s.bins.push_back(b), s.stratum.push_back(H2);
    s.sizes.push_back(static_cast<int>(take_all.size()));
  }
  return s;
}

}  // namespace rast5d
