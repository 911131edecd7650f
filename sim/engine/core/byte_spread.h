// The 8 bits of a lane mask spread to 8 bytes, 0 or 1 each (bit i to byte i): how the AVX2 paths,
// whose compares give a bit mask (movemask), store flag bytes with one 8-byte write.
#pragma once

#include <cstdint>
#include <cstring>

namespace rast5d {

struct ByteSpread {
  std::uint64_t v[256];
  constexpr ByteSpread() : v() {
    for (int m = 0; m < 256; ++m)
      for (int i = 0; i < 8; ++i) v[m] |= static_cast<std::uint64_t>((m >> i) & 1) << (8 * i);
  }
};
inline constexpr ByteSpread kByteSpread{};

// The spread of mask's low 8 bits as one word (little-endian x86: byte i = bit i).
inline std::uint64_t spread_bits(unsigned mask) { return kByteSpread.v[mask & 0xffu]; }

// The first n (<= 8) bytes of the spread of mask, written at out.
inline void store_spread(std::uint8_t* out, unsigned mask, std::size_t n = 8) {
  const std::uint64_t f = spread_bits(mask);
  std::memcpy(out, &f, n);
}

}  // namespace rast5d
