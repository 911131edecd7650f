// Per-sample alpha coverage: stochastic transparency ([McGuire 2010], "Stochastic
// Transparency": screen-door + multi-sampling + random masks). A covered sample of a triangle with
// alpha < 1 survives with probability alpha, decided by an integer hash of (pixel, sample, triangle,
// seed); a discarded sample neither tests nor writes depth. The hashes of different triangles are
// independent, so the masks of overlapping layers are uncorrelated and the resolved colour equals
// sorted alpha blending in expectation, for any submission order ("correct on average").
//
// Contract: alpha >= 1 keeps every sample, alpha <= 0 keeps none (exact: the hash is a 24-bit
// fraction in [0, 1)); the decision depends on the sample and the triangle only (never on the
// algorithm or the thread count). The hash is fixed-function integer work: it is counted in
// alpha.samples_tested, not in the float op model (ops.*).
#pragma once

#include <cstdint>

namespace rast5d {

// A 32-bit integer finaliser (lowbias32, Wellons): full avalanche, cheap in hardware.
inline std::uint32_t alpha_mix32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

// The sample's mask value in [0, 1): a 24-bit fraction (exact in float).
inline float alpha_mask_value(int px, int py, int s, std::uint32_t triangle, std::uint32_t seed) {
  std::uint32_t h = alpha_mix32(triangle ^ alpha_mix32(seed + 0x9e3779b9U));
  h = alpha_mix32(h ^ static_cast<std::uint32_t>(s));
  h = alpha_mix32(h ^ static_cast<std::uint32_t>(px));
  h = alpha_mix32(h ^ (static_cast<std::uint32_t>(py) * 0x85ebca6bU));
  return static_cast<float>(h >> 8) * (1.0f / 16777216.0f);
}

// A pseudo-random permutation of 0..n-1 keyed by h: two rounds of ((x ^ a) * odd + b) mod 2^k
// (bijections of 0..2^k-1), cycle-walked into 0..n-1.
inline std::uint32_t alpha_permute(std::uint32_t x, std::uint32_t n, std::uint32_t h) {
  std::uint32_t mask = 1;
  while (mask < n) mask <<= 1;
  --mask;
  const std::uint32_t h2 = alpha_mix32(h ^ 0x68e31da4U);
  do {
    x = (((x ^ h) * (h2 | 1U)) + (h >> 16)) & mask;
    x = (((x ^ (h2 >> 8)) * ((h >> 3) | 1U)) + h2) & mask;
  } while (x >= n);
  return x;
}

// Stratified masks ([McGuire 2010], "pixel shader sets the mask as a pseudo-random function of alpha, x, y,
// prim ID"): sample s of a pixel gets the value (perm(s) / spp + r) mod 1 with a random permutation
// and offset per (pixel, triangle), so a triangle keeps floor or ceil of alpha x spp of the pixel's
// samples, each still with probability alpha (correct on average); the permutation keeps the masks of
// two layers uncorrelated. 24-bit fractions as above.
inline float alpha_mask_value_stratified(int px, int py, int s, int spp, std::uint32_t triangle, std::uint32_t seed) {
  std::uint32_t h = alpha_mix32(triangle ^ alpha_mix32(seed + 0x7f4a7c15U));
  h = alpha_mix32(h ^ static_cast<std::uint32_t>(px));
  h = alpha_mix32(h ^ (static_cast<std::uint32_t>(py) * 0x85ebca6bU));
  const std::uint32_t k = alpha_permute(static_cast<std::uint32_t>(s), static_cast<std::uint32_t>(spp), h);
  const std::uint64_t r = alpha_mix32(h + 0x165667b1U) >> 8;
  const std::uint64_t v = ((static_cast<std::uint64_t>(k) << 24) / static_cast<std::uint64_t>(spp) + r) & 0xffffffU;
  return static_cast<float>(v) * (1.0f / 16777216.0f);
}

// True when the sample is kept (covered) for a triangle of opacity alpha.
inline bool alpha_keeps(float alpha, int px, int py, int s, int spp, bool stratified, std::uint32_t triangle,
                        std::uint32_t seed) {
  return (stratified ? alpha_mask_value_stratified(px, py, s, spp, triangle, seed)
                     : alpha_mask_value(px, py, s, triangle, seed)) < alpha;
}

}  // namespace rast5d
