// The programmable sample table as the engine sees it (docs/conventions.md, the sample table).
//
// A P x P block of pixels repeats over the screen; pixel (px mod P, py mod P) holds spp samples
// (x, y, u, v, t): x, y in [0, 1) inside the pixel, (u, v) in the lens shape inside [-1, 1]^2,
// t in [0, 1). A sample's *canonical index* s (its position in the table) names its slot in the
// depth buffer, so every algorithm, whatever order it visits samples in, writes the same slots.
//
// Lens-grid buckets ([Akenine-Möller 2012] §5.1, Fig. 10): the lens square [-1, 1]^2 is cut
// into G x G cells; cell (i, j) = (clamp(floor((u + 1) G / 2)), clamp(floor((v + 1) G / 2))),
// index j * G + i. Per pixel, `cell_order` lists canonical indices sorted by cell (stable) and
// `cell_offsets[c] .. cell_offsets[c + 1]` is cell c's range.
//
// Interleaved tables also carry N discrete lens coordinates and, per sample, the index of the
// one it uses; `lens_order` / `lens_offsets` bucket each pixel's samples by that index.
#pragma once

#include <cstdint>
#include <vector>

namespace rast5d {

struct PixelSamples {
  const float* x;
  const float* y;
  const float* u;
  const float* v;
  const float* t;
  const std::uint8_t* cell;          // spp entries: lens-grid cell of each sample (G <= 16)
  const std::int32_t* cell_order;    // spp entries
  const std::int32_t* cell_offsets;  // G*G + 1 entries
  const std::int32_t* lens_index;    // spp entries (interleaved tables only)
  const std::int32_t* lens_order;    // spp entries (interleaved tables only)
  const std::int32_t* lens_offsets;  // n_lens + 1 entries (interleaved tables only)
  // Time strata within lens-grid cells (set_time_strata(S)): `ct_order` lists canonical indices
  // sorted by (cell, stratum), stratum k = clamp(floor(t S), 0, S - 1); bucket (c, k) is
  // ct_order[ct_offsets[c * S + k] .. ct_offsets[c * S + k + 1]).
  const std::int32_t* ct_order;      // spp entries
  const std::int32_t* ct_offsets;    // G*G*S + 1 entries
  const std::uint8_t* ct_cell;       // spp entries, in ct_order's order: each entry's lens-grid cell
  const std::uint8_t* ct_stratum;    // spp entries, in ct_order's order: each entry's time stratum
  const float* ct_t;                 // spp entries, in ct_order's order: t, u, v of each entry's sample
  const float* ct_u;                 //   (the same floats as t[ct_order[i]], ...: read without a gather)
  const float* ct_v;
};

class SampleTable {
 public:
  // samples: P*P*spp*5 floats, [py][px][s][x, y, u, v, t]. lens_index: P*P*spp (or empty).
  // lens_uv: n_lens*2 (or empty).
  SampleTable(int period, int spp, const float* samples, int grid, const std::int32_t* lens_index,
              int n_lens, const float* lens_uv);

  int period() const { return period_; }
  int spp() const { return spp_; }
  int grid() const { return grid_; }
  int n_lens() const { return n_lens_; }
  float lens_u(int i) const { return lens_u_[i]; }
  float lens_v(int i) const { return lens_v_[i]; }

  // Inlined so that a caller's unused fields cost nothing (it runs once per pixel visit).
  [[gnu::always_inline]] inline PixelSamples pixel(int px, int py) const {
    const int P = period_;
    // A power-of-two period (the usual tables): a mask, exact for negative coordinates too.
    const int mx = pow2_mask_ >= 0 ? (px & pow2_mask_) : ((px % P) + P) % P;
    const int my = pow2_mask_ >= 0 ? (py & pow2_mask_) : ((py % P) + P) % P;
    const std::size_t pi = static_cast<std::size_t>(my) * P + mx;
    const std::size_t base = pi * spp_;
    PixelSamples ps{};
    ps.x = &x_[base];
    ps.y = &y_[base];
    ps.u = &u_[base];
    ps.v = &v_[base];
    ps.t = &t_[base];
    ps.cell = &cell_idx_[base];
    ps.cell_order = &cell_order_[base];
    ps.cell_offsets = &cell_offsets_[pi * (grid_ * grid_ + 1)];
    ps.ct_order = ct_order_.empty() ? nullptr : &ct_order_[base];
    ps.ct_offsets = ct_offsets_.empty() ? nullptr : &ct_offsets_[pi * (grid_ * grid_ * strata_ + 1)];
    ps.ct_cell = ct_cell_.empty() ? nullptr : &ct_cell_[base];
    ps.ct_stratum = ct_stratum_.empty() ? nullptr : &ct_stratum_[base];
    ps.ct_t = ct_tuv_.empty() ? nullptr : &ct_tuv_[3 * base];
    ps.ct_u = ct_tuv_.empty() ? nullptr : &ct_tuv_[3 * base + spp_];
    ps.ct_v = ct_tuv_.empty() ? nullptr : &ct_tuv_[3 * base + 2 * spp_];
    if (n_lens_ > 0) {
      ps.lens_index = &lens_index_[base];
      ps.lens_order = &lens_order_[base];
      ps.lens_offsets = &lens_offsets_[pi * (n_lens_ + 1)];
    }
    return ps;
  }

  // Index every pixel's samples by (lens-grid cell, time stratum) with S strata of equal length in
  // t (1 <= S <= 64), so that a traversal can skip the samples outside a time interval without
  // touching them (samples culled by the time intervals before the sample test).
  void set_time_strata(int S);
  int time_strata() const { return strata_; }
  // Sub-interval k of S on [0, 1]: [k / S, (k + 1) / S].
  static int stratum_of(float t, int S) {
    const int k = static_cast<int>(static_cast<double>(t) * S);
    return !(t > 0.0f) ? 0 : (k >= S ? S - 1 : k);
  }

  static int cell_of(float u, float v, int grid) {
    auto axis = [grid](float a) {
      int i = static_cast<int>(static_cast<double>(a + 1.0f) * 0.5 * grid);
      if (!(a + 1.0f > 0.0f)) i = 0;
      return i < 0 ? 0 : (i >= grid ? grid - 1 : i);
    };
    return axis(v) * grid + axis(u);
  }

  // The (u, v) extent of lens-grid cell index i (0..G-1) on one axis.
  static double cell_lo(int i, int grid) { return -1.0 + 2.0 * i / grid; }
  static double cell_hi(int i, int grid) { return -1.0 + 2.0 * (i + 1) / grid; }

 private:
  int period_, spp_, grid_, n_lens_;
  int pow2_mask_ = -1;  // period - 1 when the period is a power of two, else -1
  int strata_ = 0;
  std::vector<std::int32_t> ct_order_, ct_offsets_;
  std::vector<std::uint8_t> ct_cell_, ct_stratum_;
  std::vector<float> ct_tuv_;  // per pixel: spp t, then spp u, then spp v, in ct_order's order
  std::vector<float> x_, y_, u_, v_, t_;
  std::vector<std::int32_t> cell_order_, cell_offsets_;
  std::vector<std::uint8_t> cell_idx_;
  std::vector<float> lens_u_, lens_v_;
  std::vector<std::int32_t> lens_index_, lens_order_, lens_offsets_;
};

}  // namespace rast5d
