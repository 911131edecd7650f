// The texture unit: mip chains, texel layouts (addresses for the texture cache), mip-level
// selection from analytic per-triangle UV derivatives, and bilinear / trilinear filtering.
//
// Conventions (as models/textures.py sample_bilinear): texel (x, y) of a W x H level covers
// [x, x+1) x [y, y+1) in texel space; uv maps to x = u * W - 0.5, y = (1 - v) * H - 0.5 (v points
// up, row 0 is the top of the image); addressing wraps (repeat). A texel is 4 bytes (RGBA8) in
// memory, whatever its float value in the model.
//
// Level of detail ([Toth 2008] §9.2): the UV derivatives are computed analytically
// per triangle from its vertices projected through the lens centre at shutter open, not from
// differences between neighbouring quad lanes (which stochastic rasterization scatters over the
// triangle). rho = max(|d(uv)/dx|, |d(uv)/dy|) in level-0 texels, lambda = log2(rho) (OpenGL 4.6
// §8.14); the mapping is the triangle's affine screen -> uv map, exact for planes parallel to the
// image plane.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/params.h"

namespace rast5d {

inline constexpr int kTexelBytes = 4;
inline constexpr int kTexBlock = 4;  // blocked layouts: 4 x 4 texels = 64 bytes per block

struct MipLevel {
  int w = 1, h = 1;
  std::vector<float> rgb;  // h x w x 3, linear
  std::uint64_t base = 0;  // byte address of texel (0, 0)
  int blocks_x = 1;  // blocked: blocks per row
};

struct Texture {
  std::vector<MipLevel> levels;
};

inline std::uint64_t morton2(std::uint32_t x, std::uint32_t y) {
  std::uint64_t r = 0;
  for (int b = 0; b < 20; ++b)
    r |= (static_cast<std::uint64_t>((x >> b) & 1u) << (2 * b)) | (static_cast<std::uint64_t>((y >> b) & 1u) << (2 * b + 1));
  return r;
}

// Every texture of a render, laid out one after another in one address space (each level aligned
// to 4 KiB).
class TextureSet {
 public:
  // data: h x w x channels floats (channels 1..4; only the first three are used as colour).
  void add(const float* data, int h, int w, int channels) {
    if (h < 1 || w < 1 || channels < 1) throw std::invalid_argument("textures: empty texture");
    Texture t;
    MipLevel l0;
    l0.w = w, l0.h = h;
    l0.rgb.resize(static_cast<std::size_t>(w) * h * 3);
    for (std::size_t i = 0; i < static_cast<std::size_t>(w) * h; ++i)
      for (int c = 0; c < 3; ++c) l0.rgb[i * 3 + c] = data[i * channels + std::min(c, channels - 1)];
    t.levels.push_back(std::move(l0));
    // Box-filtered chain down to 1 x 1 (odd edges: the last texel is reused).
    while (t.levels.back().w > 1 || t.levels.back().h > 1) {
      const MipLevel& a = t.levels.back();
      MipLevel b;
      b.w = std::max(1, a.w / 2), b.h = std::max(1, a.h / 2);
      b.rgb.resize(static_cast<std::size_t>(b.w) * b.h * 3);
      for (int y = 0; y < b.h; ++y)
        for (int x = 0; x < b.w; ++x)
          for (int c = 0; c < 3; ++c) {
            float s = 0;
            for (int dy = 0; dy < 2; ++dy)
              for (int dx = 0; dx < 2; ++dx) {
                const int sx = std::min(a.w - 1, 2 * x + dx), sy = std::min(a.h - 1, 2 * y + dy);
                s += a.rgb[(static_cast<std::size_t>(sy) * a.w + sx) * 3 + c];
              }
            b.rgb[(static_cast<std::size_t>(y) * b.w + x) * 3 + c] = 0.25f * s;
          }
      t.levels.push_back(std::move(b));
    }
    textures_.push_back(std::move(t));
  }

  // Assign byte addresses for `layout`.
  void layout(TexLayout lay) {
    layout_ = lay;
    std::uint64_t addr = 0;
    for (Texture& t : textures_)
      for (MipLevel& l : t.levels) {
        l.blocks_x = (l.w + kTexBlock - 1) / kTexBlock;
        const int blocks_y = (l.h + kTexBlock - 1) / kTexBlock;
        int p = 1;
        while (p < std::max(l.blocks_x, blocks_y)) p *= 2;
        const std::uint64_t block_bytes = kTexBlock * kTexBlock * kTexelBytes;
        std::uint64_t bytes;
        if (lay == TexLayout::kLinear)
          bytes = static_cast<std::uint64_t>(l.w) * l.h * kTexelBytes;
        else if (lay == TexLayout::kBlocked)
          bytes = static_cast<std::uint64_t>(l.blocks_x) * blocks_y * block_bytes;
        else  // Morton: padded to p x p blocks, p the power of two covering both sides
          bytes = (morton2(p - 1, p - 1) + 1) * block_bytes;
        l.base = addr;
        addr += (bytes + 4095) / 4096 * 4096;
      }
  }

  int size() const { return static_cast<int>(textures_.size()); }
  const Texture& operator[](int i) const { return textures_[i]; }
  int levels(int i) const { return static_cast<int>(textures_[i].levels.size()); }

  // Byte address of texel (x, y) (already wrapped) of level l of texture i.
  std::uint64_t address(int i, int l, int x, int y) const {
    const MipLevel& m = textures_[i].levels[l];
    if (layout_ == TexLayout::kLinear)
      return m.base + (static_cast<std::uint64_t>(y) * m.w + x) * kTexelBytes;
    const std::uint64_t bx = x / kTexBlock, by = y / kTexBlock;
    const std::uint64_t in_block = static_cast<std::uint64_t>(y % kTexBlock) * kTexBlock + x % kTexBlock;
    const std::uint64_t block = layout_ == TexLayout::kBlocked ? by * m.blocks_x + bx
                                                               : morton2(static_cast<std::uint32_t>(bx),
                                                                         static_cast<std::uint32_t>(by));
    return m.base + (block * kTexBlock * kTexBlock + in_block) * kTexelBytes;
  }

  // The 2 x 2 bilinear footprint of uv at level l: wrapped texel coordinates and weights.
  struct Footprint {
    int x[2], y[2];
    float fx, fy;
  };
  Footprint footprint(int i, int l, float u, float v) const {
    const MipLevel& m = textures_[i].levels[l];
    float x = u * static_cast<float>(m.w) - 0.5f;
    float y = (1.0f - v) * static_cast<float>(m.h) - 0.5f;
    if (!(std::fabs(x) < 1e9f)) x = 0.0f;  // far outside any wrap period: keep the integer cast defined
    if (!(std::fabs(y) < 1e9f)) y = 0.0f;
    const float x0 = std::floor(x), y0 = std::floor(y);
    Footprint f;
    f.fx = x - x0, f.fy = y - y0;
    const long long ix = static_cast<long long>(x0), iy = static_cast<long long>(y0);
    f.x[0] = wrap(ix, m.w), f.x[1] = wrap(ix + 1, m.w);
    f.y[0] = wrap(iy, m.h), f.y[1] = wrap(iy + 1, m.h);
    return f;
  }

  // The mip levels a lookup with level of detail lambda reads and their weights:
  // bilinear = the nearest level (GL_LINEAR_MIPMAP_NEAREST), trilinear = the two around lambda.
  int select_levels(int i, float lambda, TexFilter filter, int lv[2], float w[2]) const {
    const int top = levels(i) - 1;
    const float lam = std::isfinite(lambda) ? std::clamp(lambda, 0.0f, static_cast<float>(top)) : 0.0f;
    if (filter == TexFilter::kBilinear || lam <= 0.0f || lam >= static_cast<float>(top)) {
      lv[0] = filter == TexFilter::kBilinear ? std::min(top, static_cast<int>(std::floor(lam + 0.5f)))
                                             : static_cast<int>(lam);
      w[0] = 1.0f;
      return 1;
    }
    lv[0] = static_cast<int>(std::floor(lam));
    lv[1] = lv[0] + 1;
    w[1] = lam - static_cast<float>(lv[0]);
    w[0] = 1.0f - w[1];
    return 2;
  }

  // Filtered colour (adds to out with weight `weight`).
  void sample(int i, float lambda, TexFilter filter, float u, float v, float out[3]) const {
    int lv[2];
    float wl[2];
    const int n = select_levels(i, lambda, filter, lv, wl);
    out[0] = out[1] = out[2] = 0.0f;
    for (int k = 0; k < n; ++k) {
      const MipLevel& m = textures_[i].levels[lv[k]];
      const Footprint f = footprint(i, lv[k], u, v);
      const float wx[2] = {1.0f - f.fx, f.fx}, wy[2] = {1.0f - f.fy, f.fy};
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) {
          const float wgt = wl[k] * wy[a] * wx[b];
          const float* t = &m.rgb[(static_cast<std::size_t>(f.y[a]) * m.w + f.x[b]) * 3];
          for (int c = 0; c < 3; ++c) out[c] += wgt * t[c];
        }
    }
  }

 private:
  static int wrap(long long i, int n) {
    long long r = i % n;
    return static_cast<int>(r < 0 ? r + n : r);
  }
  std::vector<Texture> textures_;
  TexLayout layout_ = TexLayout::kBlocked;
};

// Per-triangle affine map from screen pixels (lens centre, shutter open) to uv: the Jacobian
// (du/dx, du/dy, dv/dx, dv/dy). Vertices (X, Y, W) are pixel-homogeneous; uv is 3 x 2. Returns
// false (Jacobian zero) when a vertex is behind the near plane or the projection is degenerate.
inline bool uv_jacobian(const float X[3], const float Y[3], const float W[3], const float* uv, double near_w,
                        double J[4]) {
  J[0] = J[1] = J[2] = J[3] = 0.0;
  double x[3], y[3];
  for (int j = 0; j < 3; ++j) {
    if (!(W[j] > near_w)) return false;
    x[j] = static_cast<double>(X[j]) / W[j];
    y[j] = static_cast<double>(Y[j]) / W[j];
  }
  const double dx1 = x[1] - x[0], dx2 = x[2] - x[0], dy1 = y[1] - y[0], dy2 = y[2] - y[0];
  const double det = dx1 * dy2 - dx2 * dy1;
  if (!(std::fabs(det) > 1e-12)) return false;
  const double du1 = uv[2] - uv[0], du2 = uv[4] - uv[0], dv1 = uv[3] - uv[1], dv2 = uv[5] - uv[1];
  J[0] = (du1 * dy2 - du2 * dy1) / det;  // du/dx
  J[1] = (du2 * dx1 - du1 * dx2) / det;  // du/dy
  J[2] = (dv1 * dy2 - dv2 * dy1) / det;  // dv/dx
  J[3] = (dv2 * dx1 - dv1 * dx2) / det;  // dv/dy
  return true;
}

// lambda = log2(max(|(du/dx W, dv/dx H)|, |(du/dy W, dv/dy H)|)) for a W x H level 0.
// A zero Jacobian (degenerate or near-clipped triangle) gives level 0.
inline float lod_from_jacobian(const double J[4], int w, int h) {
  const double ax = J[0] * w, ay = J[1] * w, bx = J[2] * h, by = J[3] * h;
  const double rho = std::max(std::sqrt(ax * ax + bx * bx), std::sqrt(ay * ay + by * by));
  if (!(rho > 0)) return 0.0f;
  return static_cast<float>(std::log2(rho));
}

}  // namespace rast5d
