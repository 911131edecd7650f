// Self-measurement of kernel costs for tests: each entry runs one kernel on the counting scalar
// type with random inputs and returns the tally, next to the documented cost that the fast path
// charges. Kernels register themselves next to their definition (KernelCostRegistry::add).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <utility>

namespace rast5d {

struct KernelCostEntry {
  std::uint64_t documented;
  std::function<std::uint64_t(std::mt19937_64&)> run_counted;  // returns the tally of one run
};

class KernelCostRegistry {
 public:
  static std::map<std::string, KernelCostEntry>& entries() {
    static std::map<std::string, KernelCostEntry> m;
    return m;
  }
  static bool add(const std::string& name, KernelCostEntry e) {
    entries().emplace(name, std::move(e));
    return true;
  }
};

// Kernels whose documented cost depends on the configuration (number of vertices, blur, tile):
// each run returns (counted, documented) for one random configuration.
class TileKernelCostRegistry {
 public:
  using Run = std::function<std::pair<std::uint64_t, std::uint64_t>(std::mt19937_64&)>;
  static std::map<std::string, Run>& entries() {
    static std::map<std::string, Run> m;
    return m;
  }
};

}  // namespace rast5d
