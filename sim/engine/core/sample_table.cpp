#include "core/sample_table.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

namespace rast5d {

namespace {

// One pixel's samples bucketed by key[s] in [0, buckets): order = sample indices sorted by key
// (stable), off[b] .. off[b + 1] = the range of bucket b in order. off has buckets + 1 zeroed slots.
template <class Key>
void bucket_samples(const Key* key, int spp, int buckets, std::int32_t* order, std::int32_t* off) {
  for (int s = 0; s < spp; ++s) ++off[key[s] + 1];
  for (int b = 0; b < buckets; ++b) off[b + 1] += off[b];
  std::iota(order, order + spp, 0);
  std::stable_sort(order, order + spp, [&](int a, int b) { return key[a] < key[b]; });
}

}  // namespace

SampleTable::SampleTable(int period, int spp, const float* samples, int grid,
                         const std::int32_t* lens_index, int n_lens, const float* lens_uv)
    : period_(period), spp_(spp), grid_(grid), n_lens_(lens_index ? n_lens : 0) {
  if (period < 1 || spp < 1 || grid < 1) throw std::invalid_argument("SampleTable: bad dimensions");
  if ((period & (period - 1)) == 0) pow2_mask_ = period - 1;
  const std::size_t npix = static_cast<std::size_t>(period) * period;
  const std::size_t n = npix * spp;
  x_.resize(n), y_.resize(n), u_.resize(n), v_.resize(n), t_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    x_[i] = samples[i * 5 + 0];
    y_[i] = samples[i * 5 + 1];
    u_[i] = samples[i * 5 + 2];
    v_[i] = samples[i * 5 + 3];
    t_[i] = samples[i * 5 + 4];
  }
  const int cells = grid * grid;
  cell_order_.resize(n);
  cell_idx_.assign(n, 0);
  cell_offsets_.assign(npix * (cells + 1), 0);
  std::vector<int> cell(spp);
  for (std::size_t p = 0; p < npix; ++p) {
    const std::size_t base = p * spp;
    std::int32_t* order = &cell_order_[base];
    std::int32_t* off = &cell_offsets_[p * (cells + 1)];
    for (int s = 0; s < spp; ++s) {
      cell[s] = cell_of(u_[base + s], v_[base + s], grid);
      cell_idx_[base + s] = static_cast<std::uint8_t>(cell[s] < 256 ? cell[s] : 255);
    }
    bucket_samples(cell.data(), spp, cells, order, off);
  }
  if (n_lens_ > 0) {
    lens_u_.resize(n_lens_), lens_v_.resize(n_lens_);
    for (int i = 0; i < n_lens_; ++i) lens_u_[i] = lens_uv[2 * i], lens_v_[i] = lens_uv[2 * i + 1];
    lens_index_.assign(lens_index, lens_index + n);
    lens_order_.resize(n);
    lens_offsets_.assign(npix * (n_lens_ + 1), 0);
    for (std::size_t p = 0; p < npix; ++p) {
      const std::size_t base = p * spp;
      const std::int32_t* li = &lens_index_[base];
      std::int32_t* order = &lens_order_[base];
      std::int32_t* off = &lens_offsets_[p * (n_lens_ + 1)];
      for (int s = 0; s < spp; ++s)
        if (li[s] < 0 || li[s] >= n_lens_) throw std::invalid_argument("SampleTable: lens_index out of range");
      bucket_samples(li, spp, n_lens_, order, off);
    }
  }
}

void SampleTable::set_time_strata(int S) {
  if (S < 1 || S > 64) throw std::invalid_argument("time_splits: expected 1..64, got " + std::to_string(S));
  if (S == strata_) return;
  strata_ = S;
  const std::size_t npix = static_cast<std::size_t>(period_) * period_;
  const int buckets = grid_ * grid_ * S;
  ct_order_.resize(npix * spp_);
  ct_offsets_.assign(npix * (buckets + 1), 0);
  ct_cell_.resize(npix * spp_);
  ct_stratum_.resize(npix * spp_);
  ct_tuv_.resize(npix * spp_ * 3);
  std::vector<int> key(spp_);
  for (std::size_t p = 0; p < npix; ++p) {
    const std::size_t base = p * spp_;
    std::int32_t* order = &ct_order_[base];
    std::int32_t* off = &ct_offsets_[p * (buckets + 1)];
    for (int s = 0; s < spp_; ++s)
      key[s] = cell_of(u_[base + s], v_[base + s], grid_) * S + stratum_of(t_[base + s], S);
    bucket_samples(key.data(), spp_, buckets, order, off);
    float* tuv = &ct_tuv_[3 * base];
    for (int i = 0; i < spp_; ++i) {
      const int k = key[order[i]];
      ct_cell_[base + i] = static_cast<std::uint8_t>(k / S);
      ct_stratum_[base + i] = static_cast<std::uint8_t>(k % S);
      tuv[i] = t_[base + order[i]], tuv[spp_ + i] = u_[base + order[i]], tuv[2 * spp_ + i] = v_[base + order[i]];
    }
  }
}

}  // namespace rast5d
