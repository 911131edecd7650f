// Fast-path candidate selection of one pixel's samples against a tile's lens region (active lens
// cells and the h_i cuts): a vectorisable scan, then compaction. The counting path walks the
// cells' buckets instead and charges the same per-sample comparisons.
//
// Contract: select_candidates flags exactly the samples that the bucket walk over the active cells
// with axis_pass (halfspace_lens.h) selects, so both paths test the same samples.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "tiletest/halfspace_lens.h"

namespace rast5d::tiletest {

// Fast-path candidate selection for one pixel: flag[s] = sample s is in an active lens cell
// (bit cell[s] of active, G * G <= 64; kCells = false: every cell) and passes both axis sets.
// Returns how many samples lie in active cells (the samples whose (u, v) was compared).
template <bool kCells>
[[gnu::noinline]] inline int select_candidates(int spp, const float* __restrict u, const float* __restrict v,
                                                 const std::uint8_t* __restrict cell, std::uint64_t active,
                                                 const AxisSet& su, const AxisSet& sv,
                                                 std::uint8_t* __restrict flags) {
  const float a0 = su.fl_lo[0], b0 = su.fl_hi[0], a1 = su.fl_lo[1], b1 = su.fl_hi[1];
  const float c0 = sv.fl_lo[0], d0 = sv.fl_hi[0], c1 = sv.fl_lo[1], d1 = sv.fl_hi[1];
  int in_cells = 0;
  for (int s = 0; s < spp; ++s) {
    const float x = u[s], y = v[s];
    const int in_u = ((x > a0) & (x < b0)) | ((x > a1) & (x < b1));
    const int in_v = ((y > c0) & (y < d0)) | ((y > c1) & (y < d1));
    int act = 1;
    if constexpr (kCells) act = static_cast<int>((active >> cell[s]) & 1u);
    in_cells += act;
    flags[s] = static_cast<std::uint8_t>(act & (1 - in_u) & (1 - in_v));
  }
  return in_cells;
}

// One tile's selection bounds for SamplePipeline::push_selected (the fused fast path): the same
// active cells (bit c of active) and the same float cut bounds as select_candidates, set up once
// per tile.
struct SelectBounds {
  std::uint64_t active;
  float a0, b0, a1, b1;  // u cuts (AxisSet::fl_lo / fl_hi)
  float c0, d0, c1, d1;  // v cuts
  // Cut k of an axis can flag a sample only if lo < hi (else (x > lo) & (x < hi) is false for
  // every x, NaN included), so the others are skipped without changing a flag.
  bool u0, u1, v0, v1;

  void set(std::uint64_t active_cells, const AxisSet& su, const AxisSet& sv) {
    active = active_cells;
    a0 = su.fl_lo[0], b0 = su.fl_hi[0], a1 = su.fl_lo[1], b1 = su.fl_hi[1];
    c0 = sv.fl_lo[0], d0 = sv.fl_hi[0], c1 = sv.fl_lo[1], d1 = sv.fl_hi[1];
    u0 = a0 < b0, u1 = a1 < b1, v0 = c0 < d0, v1 = c1 < d1;
  }
  // Every sample of the cells in active_cells, no cuts.
  void set_cells(std::uint64_t active_cells) {
    active = active_cells;
    a0 = b0 = a1 = b1 = c0 = d0 = c1 = d1 = 0.0f;
    u0 = u1 = v0 = v1 = false;
  }
};

// Indices of the set flags, in order (skipping 8 zero flags at a time).
inline int compact_flags(const std::uint8_t* flags, int n, int* out) {
  int m = 0;
  for (int w = 0; w < n; w += 8) {
    std::uint64_t word = 0;
    std::memcpy(&word, flags + w, 8);
    if (!word) continue;
    const int end = std::min(n, w + 8);
    for (int i = w; i < end; ++i) {
      out[m] = i;
      m += flags[i];
    }
  }
  return m;
}

}  // namespace rast5d::tiletest
