// Operation accounting (docs/op_costs.md; [Akenine-Möller 2012] §6.2).
//
// Contract: every kernel that does arithmetic the hardware would do is a template over its
// scalar type and uses only the operators and helpers below. Each of ADD/SUB, MUL, MADD (FMA),
// CMP (an ordered comparison or a sign test), MIN, MAX and RCP counts as one operation;
// negation, absolute value, moves, integer/bit work and control flow are free.
//
// The fast path instantiates kernels on float/double and adds the documented cost of each
// executed kernel (core/costs.h). The counting path instantiates the same kernels on Counted<T>,
// which performs the identical IEEE operation in the identical order (the build uses
// -ffp-contract=off) and tallies one operation per call, so the two paths produce bit-identical
// results and tests/test_op_costs.py proves the documented costs.
#pragma once

#include <cmath>
#include <cstdint>
#include <type_traits>

namespace rast5d {

// Thread-local tally of operations executed on Counted<T>. Read with take().
struct OpTally {
  static inline thread_local std::uint64_t count = 0;
  static std::uint64_t take() {
    std::uint64_t n = count;
    count = 0;
    return n;
  }
};

template <class T>
struct Counted {
  T v{};
  Counted() = default;
  constexpr Counted(T x) : v(x) {}  // NOLINT: implicit from raw scalars (constants are free)
  template <class U, class = std::enable_if_t<std::is_arithmetic_v<U> && !std::is_same_v<U, T>>>
  constexpr Counted(U x) : v(static_cast<T>(x)) {}
  explicit operator T() const { return v; }
};

template <class T>
struct is_counted : std::false_type {};
template <class T>
struct is_counted<Counted<T>> : std::true_type {};

template <class T>
inline constexpr bool is_counted_v = is_counted<T>::value;

// raw(): the underlying IEEE value of a scalar, free.
inline float raw(float x) { return x; }
inline double raw(double x) { return x; }
template <class T>
inline T raw(Counted<T> x) { return x.v; }

#define RAST5D_COUNTED_BINOP(op)                                        \
  template <class T>                                                    \
  inline Counted<T> operator op(Counted<T> a, Counted<T> b) {          \
    ++OpTally::count;                                                   \
    return Counted<T>(a.v op b.v);                                      \
  }                                                                     \
  template <class T, class U, class = std::enable_if_t<std::is_arithmetic_v<U>>> \
  inline Counted<T> operator op(Counted<T> a, U b) {                    \
    ++OpTally::count;                                                   \
    return Counted<T>(a.v op static_cast<T>(b));                        \
  }                                                                     \
  template <class T, class U, class = std::enable_if_t<std::is_arithmetic_v<U>>> \
  inline Counted<T> operator op(U a, Counted<T> b) {                    \
    ++OpTally::count;                                                   \
    return Counted<T>(static_cast<T>(a) op b.v);                        \
  }
RAST5D_COUNTED_BINOP(+)
RAST5D_COUNTED_BINOP(-)
RAST5D_COUNTED_BINOP(*)
#undef RAST5D_COUNTED_BINOP

#define RAST5D_COUNTED_CMP(op)                                          \
  template <class T>                                                    \
  inline bool operator op(Counted<T> a, Counted<T> b) {                \
    ++OpTally::count;                                                   \
    return a.v op b.v;                                                  \
  }                                                                     \
  template <class T, class U, class = std::enable_if_t<std::is_arithmetic_v<U>>> \
  inline bool operator op(Counted<T> a, U b) {                          \
    ++OpTally::count;                                                   \
    return a.v op static_cast<T>(b);                                    \
  }                                                                     \
  template <class T, class U, class = std::enable_if_t<std::is_arithmetic_v<U>>> \
  inline bool operator op(U a, Counted<T> b) {                          \
    ++OpTally::count;                                                   \
    return static_cast<T>(a) op b.v;                                    \
  }
RAST5D_COUNTED_CMP(<)
RAST5D_COUNTED_CMP(<=)
RAST5D_COUNTED_CMP(>)
RAST5D_COUNTED_CMP(>=)
#undef RAST5D_COUNTED_CMP

// Negation is a sign-bit flip: free.
template <class T>
inline Counted<T> operator-(Counted<T> a) { return Counted<T>(-a.v); }

// ---- helpers: one operation each ----------------------------------------------------------

// a*b + c. Evaluated as two IEEE operations (multiply, then add) on every path and every
// platform; counted as one MADD, as in the paper's hardware model.
inline float madd(float a, float b, float c) { return a * b + c; }
inline double madd(double a, double b, double c) { return a * b + c; }
template <class T>
inline Counted<T> madd(Counted<T> a, Counted<T> b, Counted<T> c) {
  ++OpTally::count;
  return Counted<T>(a.v * b.v + c.v);
}

inline float vmin(float a, float b) { return b < a ? b : a; }
inline double vmin(double a, double b) { return b < a ? b : a; }
inline float vmax(float a, float b) { return a < b ? b : a; }
inline double vmax(double a, double b) { return a < b ? b : a; }
template <class T>
inline Counted<T> vmin(Counted<T> a, Counted<T> b) {
  ++OpTally::count;
  return Counted<T>(b.v < a.v ? b.v : a.v);
}
template <class T>
inline Counted<T> vmax(Counted<T> a, Counted<T> b) {
  ++OpTally::count;
  return Counted<T>(a.v < b.v ? b.v : a.v);
}

inline float rcp(float a) { return 1.0f / a; }
inline double rcp(double a) { return 1.0 / a; }
template <class T>
inline Counted<T> rcp(Counted<T> a) {
  ++OpTally::count;
  return Counted<T>(T(1) / a.v);
}

// Sign test: -1, 0 or +1. One CMP.
inline int sign_of(float a) { return (a > 0.0f) - (a < 0.0f); }
inline int sign_of(double a) { return (a > 0.0) - (a < 0.0); }
template <class T>
inline int sign_of(Counted<T> a) {
  ++OpTally::count;
  return (a.v > T(0)) - (a.v < T(0));
}

// |a| is a sign-bit clear: free.
inline float vabs(float a) { return std::fabs(a); }
inline double vabs(double a) { return std::fabs(a); }
template <class T>
inline Counted<T> vabs(Counted<T> a) { return Counted<T>(std::fabs(a.v)); }

// Scalar families used by the kernels: Fast = the hardware-speed path, Exact = counting path.
struct FastArith {
  static constexpr bool counting = false;
  using f32 = float;
  using f64 = double;
};
struct ExactArith {
  static constexpr bool counting = true;
  using f32 = Counted<float>;
  using f64 = Counted<double>;
};

// Charge the operations of one executed kernel to a stage counter. On the fast path this adds
// the documented cost; on the counting path it adds what Counted<T> tallied since the last take.
template <class A>
inline void charge(std::uint64_t& stage_ops, std::uint64_t documented_cost) {
  if constexpr (A::counting) {
    stage_ops += OpTally::take();
  } else {
    stage_ops += documented_cost;
  }
}
// Discard work that is not charged (e.g. per-triangle setup recomputed in a second bin).
template <class A>
inline void discard() {
  if constexpr (A::counting) OpTally::take();
}

}  // namespace rast5d
