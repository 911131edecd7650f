// Fixed-point scalar for precision studies: the tile-test and sample-test templates instantiated on
// Fixed (sim._core.precision_probe_2d, reports/paper/precision.md) behave as an integer datapath:
// inputs (vertex and sample coordinates) snap to the nearest multiple of 2^-frac_bits; every
// register holds a sign, int_bits integer bits and 2 frac_bits fraction bits, so the products of two
// snapped inputs and their sums (the 2D edge set-up and the affine edge functions) are exact, and a
// product of products rounds to nearest; any value whose magnitude reaches 2^int_bits sets the
// overflow flag (hardware would wrap: that result is invalid). The format is per thread
// (FixedFormat::set), so one build serves every precision.
#pragma once

#include <cmath>
#include <cstdint>

namespace rast5d {

struct FixedFormat {
  int int_bits = 31, frac_bits = 8;
  static inline thread_local int s_int = 31, s_frac = 8;
  static inline thread_local bool overflow = false;
  // The largest |register| since set() (precision studies: the fewest int_bits is the smallest n with
  // max_abs < 2^n).
  static inline thread_local double max_abs = 0.0;
  static void set(int int_bits, int frac_bits) {
    s_int = int_bits, s_frac = frac_bits;
    overflow = false;
    max_abs = 0.0;
  }
};

struct Fixed {
  __int128 r = 0;  // value = r * 2^-(2 frac_bits)
  Fixed() = default;
  Fixed(double x) {  // NOLINT: snap to the 2^-frac_bits grid
    const double s = std::ldexp(x, FixedFormat::s_frac);
    if (!(std::fabs(s) < 0x1p100)) {
      FixedFormat::overflow = true;
      r = 0;
      return;
    }
    r = static_cast<__int128>(std::nearbyint(s)) << FixedFormat::s_frac;
    check();
  }
  Fixed(float x) : Fixed(static_cast<double>(x)) {}  // NOLINT
  Fixed(int x) : Fixed(static_cast<double>(x)) {}    // NOLINT
  static Fixed raw_value(__int128 v) {
    Fixed f;
    f.r = v;
    f.check();
    return f;
  }
  void check() const {
    const __int128 lim = static_cast<__int128>(1) << (FixedFormat::s_int + 2 * FixedFormat::s_frac);
    if (r >= lim || r <= -lim) FixedFormat::overflow = true;
    const double a = std::fabs(static_cast<double>(r));
    if (a > FixedFormat::max_abs) FixedFormat::max_abs = a;
  }
  double to_double() const { return std::ldexp(static_cast<double>(r), -2 * FixedFormat::s_frac); }
};

// A value already on the register grid (a multiple of 2^-2 frac_bits, e.g. a stored set-up
// coefficient), without snapping it to frac_bits.
inline Fixed fixed_exact(double x) {
  const double s = std::ldexp(x, 2 * FixedFormat::s_frac);
  if (!(std::fabs(s) < 0x1p100)) {
    FixedFormat::overflow = true;
    return Fixed();
  }
  return Fixed::raw_value(static_cast<__int128>(std::nearbyint(s)));
}

inline Fixed operator+(Fixed a, Fixed b) { return Fixed::raw_value(a.r + b.r); }
inline Fixed operator-(Fixed a, Fixed b) { return Fixed::raw_value(a.r - b.r); }
inline Fixed operator-(Fixed a) { return Fixed::raw_value(-a.r); }
inline Fixed operator*(Fixed a, Fixed b) {
  const int F = 2 * FixedFormat::s_frac;
  const __int128 p = a.r * b.r;
  const __int128 half = F > 0 ? (static_cast<__int128>(1) << (F - 1)) : 0;
  // round to nearest (ties away from zero) at 2 frac_bits: exact for products of snapped inputs
  const __int128 q = p >= 0 ? (p + half) >> F : -((-p + half) >> F);
  return Fixed::raw_value(q);
}
inline bool operator<(Fixed a, Fixed b) { return a.r < b.r; }
inline bool operator<=(Fixed a, Fixed b) { return a.r <= b.r; }
inline bool operator>(Fixed a, Fixed b) { return a.r > b.r; }
inline bool operator>=(Fixed a, Fixed b) { return a.r >= b.r; }
inline Fixed madd(Fixed a, Fixed b, Fixed c) { return a * b + c; }
inline Fixed vmin(Fixed a, Fixed b) { return b < a ? b : a; }
inline Fixed vmax(Fixed a, Fixed b) { return a < b ? b : a; }
inline int sign_of(Fixed a) { return (a.r > 0) - (a.r < 0); }
inline double raw(Fixed a) { return a.to_double(); }

}  // namespace rast5d
