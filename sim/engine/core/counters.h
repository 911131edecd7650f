// Counter registry (docs/architecture.md, "a counter"): declared once in counters.def; per thread; merged by
// summation at the end of a render (integer sums, so the merge order never matters).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace rast5d {

enum class Counter : int {
#define RAST5D_COUNTER(id, name, unit, desc) id,
#include "core/counters.def"
#undef RAST5D_COUNTER
  kCount
};

inline constexpr int kNumCounters = static_cast<int>(Counter::kCount);

struct CounterInfo {
  std::string_view name;
  std::string_view unit;
  std::string_view description;
};

inline constexpr std::array<CounterInfo, kNumCounters> kCounterInfo = {{
#define RAST5D_COUNTER(id, name, unit, desc) {name, unit, desc},
#include "core/counters.def"
#undef RAST5D_COUNTER
}};

struct Counters {
  std::array<std::uint64_t, kNumCounters> v{};
  std::uint64_t& operator[](Counter c) { return v[static_cast<int>(c)]; }
  std::uint64_t operator[](Counter c) const { return v[static_cast<int>(c)]; }
  void merge(const Counters& o) {
    for (int i = 0; i < kNumCounters; ++i) v[i] += o.v[i];
  }
};

}  // namespace rast5d
