// Sampled simulation (pipeline.sample_fraction, sim/sampling.py) and renders of a bin list: triangle
// setup and binning only for the triangles that reach the traversed bins.
//
// 1. Bounds pre-pass over every triangle (setup_bounds(): setup's own bounds and culls, without the
//    kernel constants, nothing charged). From it, for every bin: the brute-force work (the
//    stratification's sort key, sampled/bin_sample.h) and the frame totals of the regression
//    estimator's auxiliaries (sampled/bin_covariates.h), summed per triangle.
// 2. The draw (or the given list). With pipeline.sample_split > 0 the dense bins are first cut into
//    units of their triangles (sampled/dense_units.h), which are drawn like bins.
// 3. setup_triangle() for the live triangles whose bounds overlap a drawn bin, and for the culled ones
//    (their counts are exact). The drawn bins' auxiliaries come from the same setup fields.
//
// Setup counts: setup.triangles and the whole setup of the culled triangles are the frame's exactly.
// Every live triangle's setup counters belong to its home bin (the bin holding the top-left corner of
// its bounds, the bin where traversals charge their per-triangle setup too): they are added to that
// bin's row of SampledBins::bin_counters when it is drawn, and estimated with the rest of the bin's
// counters; a triangle set up only because it reaches a drawn bin it is not homed in adds nothing to
// the counters. With every bin listed, the counters equal the whole frame's. Under units, a triangle
// homed in a cut bin belongs to its unit there, and its setup counts when that unit is drawn.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "setup/setup.h"
#include "sampled/bin_covariates.h"
#include "sampled/bin_sample.h"
#include "sampled/dense_units.h"
#include "core/scene.h"

namespace rast5d {

// What a render of a bin list, or a sampled simulation, returns besides the frame's counters: the
// traversed bins (the list, or the stratified draw of sampled/bin_sample.h) with each one's counters
// (one row of kNumCounters per entry, in its order: its traversal work and the setup of the live
// triangles homed in it), every bin's brute-force work (sum over its triangles of their bounds' pixels
// in the bin, times spp), the stratum of each drawn bin and the strata sizes (empty: every bin with
// triangles was drawn), and the regression estimator's auxiliaries (sampled/bin_covariates.h): kBinAux
// per bin (NaN in bins not drawn when only the drawn bins' were computed) and their frame totals.
// Under units of the dense bins (sampled/dense_units.h) bins, bin_work and bin_aux index units: the
// screen bins (a cut bin's entry with work 0) followed by the units.
struct SampledBins {
  std::vector<int> bins, stratum, strata_sizes;
  std::vector<std::uint64_t> bin_counters;
  std::vector<std::int64_t> bin_work;
  std::vector<double> bin_aux, bin_aux_total;
  bool empty() const { return bin_work.empty(); }
};

// A bin list's entries are distinct bin indices in 0 .. n_bins - 1; std::invalid_argument otherwise.
inline void require_bin_list(const std::vector<int>& bins, int n_bins) {
  std::vector<char> seen(static_cast<std::size_t>(n_bins), 0);
  for (int b : bins) {
    if (b < 0 || b >= n_bins || seen[b])
      throw std::invalid_argument("bins: expected distinct bin indices in 0.." + std::to_string(n_bins - 1) +
                                  ", got " + std::to_string(b));
    seen[b] = 1;
  }
}

// Storage for n set-ups, unconstructed: a restricted render constructs only those of the triangles
// it sets up (sampled_setup), so the rest of the array costs neither writes nor page faults. TriSetup
// is trivially destructible.
struct UnconstructedSetups {
  struct Free {
    void operator()(TriSetup* q) const { std::free(q); }
  };
  std::unique_ptr<TriSetup, Free> data;
  TriSetup* allocate(std::size_t n) {
    data.reset(static_cast<TriSetup*>(std::malloc(std::max<std::size_t>(n, 1) * sizeof(TriSetup))));
    if (!data) throw std::bad_alloc();
    return data.get();
  }
};

// Constructs and fills setups[i] and alive[i] for the set-up triangles (setups: n unconstructed slots,
// UnconstructedSetups; only the set-up triangles' slots are read afterwards), frame_setup with the
// frame's setup counters (those of the home bins included), homed[k] with the setup counters of the
// triangles homed in drawn bin k, drawn with the bins to traverse (the list, or the stratified draw),
// and out's bin_work, bin_aux (NaN for the bins not drawn), bin_aux_total, stratum and strata_sizes.
inline void sampled_setup(const RenderParams& p, const FrameConst& fc, const SceneArrays& scene, int spp,
                          const std::vector<int>* list, TriSetup* setups, std::vector<char>& alive,
                          Counters& frame_setup, std::vector<Counters>& homed, std::vector<int>& drawn,
                          SampledBins& out, SplitDraw* split = nullptr) {
  const int B = p.bin_size;
  const int bins_x = (p.width + B - 1) / B, bins_y = (p.height + B - 1) / B;
  const int n_bins = bins_x * bins_y;
  const std::size_t n = static_cast<std::size_t>(scene.n);
  if (list) require_bin_list(*list, n_bins);

  // ---- 1. bounds pre-pass: per-bin work, auxiliary totals ----
  struct Pre {
    int bx0, by0, bx1, by1;
    int culled;  // 0, or setup_bounds()'s cull
  };
  std::vector<Pre> pre(n);
  out.bin_work.assign(static_cast<std::size_t>(n_bins), 0);
  BinAux total;  // the frame's auxiliaries
  TriSetup t;
  for (std::size_t i = 0; i < n; ++i) {
    Pre& q = pre[i];
    q.culled = setup_bounds(scene.v0 + i * 9, scene.v1 + i * 9, p, fc, t);
    if (q.culled) continue;
    q.bx0 = t.bx0, q.by0 = t.by0, q.bx1 = t.bx1, q.by1 = t.by1;
    for (int by = t.by0 / B; by <= (t.by1 - 1) / B; ++by) {
      const std::int64_t dy = std::min(t.by1, (by + 1) * B) - std::max(t.by0, by * B);
      for (int bx = t.bx0 / B; bx <= (t.bx1 - 1) / B; ++bx)
        out.bin_work[by * bins_x + bx] += dy * (std::min(t.bx1, (bx + 1) * B) - std::max(t.bx0, bx * B));
    }
    // The triangle's auxiliaries summed over its bins: bin_covariate_terms over the union of its bins
    // (its bounds lie inside, so the share is 1; clipped areas add up over the bins).
    const double x0 = (t.bx0 / B) * B, y0 = (t.by0 / B) * B;
    const double x1 = std::min(p.width, ((t.bx1 - 1) / B + 1) * B), y1 = std::min(p.height, ((t.by1 - 1) / B + 1) * B);
    bin_covariate_terms(t, triangle_covariates(t, B), x0, y0, x1, y1, total);
  }
  for (auto& w : out.bin_work) w *= spp;
  out.bin_aux_total.assign(kBinAux, 0.0);
  total.store(out.bin_aux_total, 0, spp);

  // ---- 2. the drawn bins (or units of the dense bins' triangles) ----
  DenseUnits dense;
  if (!list && split && p.sample_split > 0)
    dense = split_dense_bins(out.bin_work, p.sample_fraction, p.sample_split, spp, B, bins_x, bins_y,
                             n, [&](std::size_t i, int& x0, int& y0, int& x1, int& y1) {
                               const Pre& q = pre[i];
                               if (q.culled) return false;
                               x0 = q.bx0, y0 = q.by0, x1 = q.bx1, y1 = q.by1;
                               return true;
                             });
  if (list) {
    drawn = *list;
  } else {
    BinSample s = stratify_bins(out.bin_work, p.sample_fraction, static_cast<std::uint64_t>(p.sample_seed));
    drawn = std::move(s.bins);
    out.stratum = std::move(s.stratum);
    out.strata_sizes = std::move(s.sizes);
  }
  // Units of the dense bins: drawn entry k traverses screen bin split->bins[k], with the unit's
  // triangles (split->lists[k]) or the whole bin (an empty list).
  std::vector<int> unit_k(dense.units(), -1);  // drawn entry of each unit of the dense bins
  if (!dense.empty()) {
    split->bins.resize(drawn.size());
    split->lists.assign(drawn.size(), {});
    for (std::size_t k = 0; k < drawn.size(); ++k) {
      const int u = drawn[k] - n_bins;
      split->bins[k] = u < 0 ? drawn[k] : dense.bin[dense.unit_dense[u]];
      if (u >= 0) unit_k[u] = static_cast<int>(k);
    }
  }
  std::vector<int> k_of(static_cast<std::size_t>(n_bins), -1);
  for (std::size_t k = 0; k < drawn.size(); ++k)
    if (drawn[k] < n_bins) k_of[drawn[k]] = static_cast<int>(k);  // distinct: checked
  std::vector<char> in_unit;  // triangles of a drawn unit of a dense bin
  if (!dense.empty()) {
    in_unit.assign(n, 0);
    for (std::size_t d = 0; d < dense.bin.size(); ++d)
      for (std::size_t j = dense.first[d]; j < dense.first[d + 1]; ++j)
        if (unit_k[dense.unit[j]] >= 0) in_unit[dense.tri[j]] = 1;
  }
  // Summed-area table of the drawn bins: does a triangle's bin rectangle hold one?
  const int sx = bins_x + 1;
  std::vector<int> sat(static_cast<std::size_t>(sx) * (bins_y + 1), 0);
  for (int by = 0; by < bins_y; ++by)
    for (int bx = 0; bx < bins_x; ++bx)
      sat[(by + 1) * sx + bx + 1] = (k_of[by * bins_x + bx] >= 0) + sat[by * sx + bx + 1] + sat[(by + 1) * sx + bx] -
                                    sat[by * sx + bx];

  // ---- 3. setup of the triangles that reach the drawn bins ----
  homed.assign(drawn.size(), Counters{});
  std::vector<std::vector<std::uint32_t>> reach(drawn.size());  // live triangles per drawn bin
  Counters c;
  for (std::size_t i = 0; i < n; ++i) {
    const float* v0 = scene.v0 + i * 9;
    const float* v1 = scene.v1 + i * 9;
    const float* col = scene.colors + i * 9;
    const Pre& q = pre[i];
    auto run = [&](Counters& into) {
      new (&setups[i]) TriSetup{};
      return p.op_count == OpCount::kExact
                 ? setup_triangle<ExactArith>(v0, v1, col, static_cast<std::uint32_t>(i), p, fc, setups[i], into)
                 : setup_triangle<FastArith>(v0, v1, col, static_cast<std::uint32_t>(i), p, fc, setups[i], into);
    };
    if (q.culled) {  // culled in setup: counted exactly in the frame
      if (run(frame_setup)) throw std::logic_error("sampled setup: the bounds pre-pass culled a live triangle");
      continue;
    }
    ++frame_setup[Counter::setup_triangles];
    const int cx0 = q.bx0 / B, cy0 = q.by0 / B, cx1 = (q.bx1 - 1) / B + 1, cy1 = (q.by1 - 1) / B + 1;
    if (sat[cy1 * sx + cx1] - sat[cy0 * sx + cx1] - sat[cy1 * sx + cx0] + sat[cy0 * sx + cx0] == 0 &&
        (in_unit.empty() || !in_unit[i]))
      continue;
    c = Counters{};
    if (!(alive[i] = run(c))) throw std::logic_error("sampled setup: setup culled a triangle the pre-pass kept");
    if (scene.alpha) setups[i].alpha = scene.alpha[i];
    const TriSetup& s = setups[i];
    if (s.bx0 != q.bx0 || s.by0 != q.by0 || s.bx1 != q.bx1 || s.by1 != q.by1)
      throw std::logic_error("sampled setup: the bounds pre-pass differs from setup for triangle " + std::to_string(i));
    --c[Counter::setup_triangles];  // counted above for every triangle
    int home = k_of[cy0 * bins_x + cx0];
    if (!dense.empty() && dense.of_bin[cy0 * bins_x + cx0] >= 0) home = unit_k[dense.unit_of(cy0 * bins_x + cx0, i)];
    if (home >= 0) {
      homed[home].merge(c);
      frame_setup.merge(c);
    }
    for (int by = cy0; by < cy1; ++by)
      for (int bx = cx0; bx < cx1; ++bx)
        if (const int k = k_of[by * bins_x + bx]; k >= 0) reach[k].push_back(static_cast<std::uint32_t>(i));
  }
  for (std::size_t d = 0; d < dense.bin.size(); ++d)  // the drawn units' triangles, in submission order
    for (std::size_t j = dense.first[d]; j < dense.first[d + 1]; ++j)
      if (const int k = unit_k[dense.unit[j]]; k >= 0) reach[k].push_back(dense.tri[j]);
  if (!dense.empty())
    for (std::size_t k = 0; k < drawn.size(); ++k)
      if (drawn[k] >= n_bins) split->lists[k] = reach[k];

  // ---- the drawn bins' auxiliaries ----
  out.bin_aux.assign(out.bin_work.size() * kBinAux, std::numeric_limits<double>::quiet_NaN());
  std::vector<TriangleCovariates> cov;
  std::vector<int> cov_of(reach.empty() ? 0 : n, -1);
  for (std::size_t k = 0; k < drawn.size(); ++k) {
    const int b = dense.empty() ? drawn[k] : split->bins[k];
    const int bx = b % bins_x, by = b / bins_x;
    const double x0 = bx * B, y0 = by * B;
    const double x1 = std::min<double>(p.width, x0 + B), y1 = std::min<double>(p.height, y0 + B);
    BinAux a;
    for (std::uint32_t i : reach[k]) {
      if (cov_of[i] < 0) cov_of[i] = static_cast<int>(cov.size()), cov.push_back(triangle_covariates(setups[i], B));
      bin_covariate_terms(setups[i], cov[cov_of[i]], x0, y0, x1, y1, a);
    }
    a.store(out.bin_aux, static_cast<std::size_t>(drawn[k]), spp);
  }
}

// Every bin's brute-force work and auxiliaries when the whole frame was set up (the bin list or the
// sampled draw under per-pixel statistics or timing, which set up every triangle).
inline void whole_frame_bins(const std::vector<TriSetup>& setups, const std::vector<std::vector<std::uint32_t>>& bin_lists,
                             int bins_x, int B, int width, int height, int spp, SampledBins& out) {
  const int n_bins = static_cast<int>(bin_lists.size());
  out.bin_work.assign(static_cast<std::size_t>(n_bins), 0);
  for (int b = 0; b < n_bins; ++b) {
    const int bx = b % bins_x, by = b / bins_x;
    const int x0 = bx * B, y0 = by * B, x1 = std::min(width, x0 + B), y1 = std::min(height, y0 + B);
    std::int64_t w = 0;
    for (std::uint32_t i : bin_lists[b]) {
      const TriSetup& t = setups[i];
      const std::int64_t dx = std::min(t.bx1, x1) - std::max(t.bx0, x0), dy = std::min(t.by1, y1) - std::max(t.by0, y0);
      if (dx > 0 && dy > 0) w += dx * dy;
    }
    out.bin_work[b] = w * spp;
  }
  bin_covariates(setups, bin_lists, bins_x, B, width, height, spp, out.bin_aux);
  out.bin_aux_total.assign(kBinAux, 0.0);  // every bin's auxiliaries computed: their sums
  for (int b = 0; b < n_bins; ++b)
    for (int j = 0; j < kBinAux; ++j) out.bin_aux_total[j] += out.bin_aux[kBinAux * b + j];
}

}  // namespace rast5d
