// A write-back tile cache (docs/memory.md): set-associative, LRU, over the lines of one screen bin.
// The depth-tile and colour-tile caches of memory/sample_buffers.h are two of them.
//
// Lines are the dense indices 0..n-1 of the bin's buffer lines; set = line mod sets. access() returns
// whether the line was present and which dirty line (if any) it evicted.
//
// Contract: deterministic LRU (stamps, no hashing); a dirty line is reported exactly once, at its
// eviction or by for_each_dirty(); one cache serves one bin at a time (reset() between bins). Because
// every bin's lines are its own and each is reached only while its bin is being rasterized, the hits
// and misses of a bin are those of a cache shared by every bin of a pipeline (the lines left by the
// previous bin are older than any of this bin's and are always evicted first); only the moment their
// write-backs are charged differs (at the end of their own bin: docs/memory.md).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace rast5d::memory {

class TileCache {
 public:
  struct Access {
    bool hit = false;
    std::int64_t evicted = -1;  // a dirty line written back to make room, or -1
  };

  // capacity in lines; ways 0 (or more than the lines) = fully associative; n_lines of the bin.
  void reset(std::uint64_t capacity, std::uint64_t ways, std::size_t n_lines) {
    ways_ = (ways == 0 || ways > capacity) ? capacity : ways;
    sets_ = capacity / ways_;
    tag_.assign(static_cast<std::size_t>(sets_ * ways_), kEmpty);
    stamp_.assign(tag_.size(), 0);
    dirty_.assign(tag_.size(), 0);
    where_.assign(n_lines, -1);
    clock_ = 0;
  }

  Access access(std::uint32_t line, bool write) {
    Access a;
    const std::int64_t at = where_[line];
    ++clock_;
    if (at >= 0) {
      a.hit = true;
      stamp_[at] = clock_;
      dirty_[at] |= static_cast<std::uint8_t>(write);
      return a;
    }
    const std::uint64_t set = line % sets_;
    const std::size_t base = static_cast<std::size_t>(set * ways_);
    std::size_t victim = base;
    for (std::size_t w = base; w < base + ways_; ++w) {
      if (tag_[w] == kEmpty) {
        victim = w;
        break;
      }
      if (stamp_[w] < stamp_[victim]) victim = w;
    }
    if (tag_[victim] != kEmpty) {
      where_[tag_[victim]] = -1;
      if (dirty_[victim]) a.evicted = tag_[victim];
    }
    tag_[victim] = line;
    stamp_[victim] = clock_;
    dirty_[victim] = static_cast<std::uint8_t>(write);
    where_[line] = static_cast<std::int64_t>(victim);
    return a;
  }

  bool contains(std::uint32_t line) const { return where_[line] >= 0; }

  // f(line) for every dirty line still held, ascending line index; they are then clean.
  template <class F>
  void for_each_dirty(F f) {
    for (std::size_t l = 0; l < where_.size(); ++l) {
      const std::int64_t at = where_[l];
      if (at >= 0 && dirty_[at]) {
        dirty_[at] = 0;
        f(static_cast<std::uint32_t>(l));
      }
    }
  }

 private:
  static constexpr std::uint32_t kEmpty = ~std::uint32_t(0);
  std::uint64_t ways_ = 1, sets_ = 1, clock_ = 0;
  std::vector<std::uint32_t> tag_;
  std::vector<std::uint64_t> stamp_;
  std::vector<std::uint8_t> dirty_;
  std::vector<std::int64_t> where_;  // per line of the bin: its slot, or -1
};

}  // namespace rast5d::memory
