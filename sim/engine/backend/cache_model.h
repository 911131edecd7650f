// Texture-cache model: a set-associative LRU cache of fixed-size lines with the "3C" miss
// classification (Hill & Smith): a miss is *cold* when the line was never accessed before,
// *capacity* when a fully associative LRU cache of the same number of lines (the shadow cache)
// misses too, and *conflict* otherwise (the shadow cache would have hit).
//
// Contract: access() is deterministic (no hashing of pointers, no randomness); feeding the same
// line stream gives the same counts. Addresses are line indices (byte address / line bytes).
// The tests check this model against a small Python reference simulator (tests/test_shading.py).
#pragma once

#include <cstdint>
#include <list>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace rast5d {

// A fully associative LRU set of `capacity` lines: O(1) lookup through a hash map into a recency
// list (front = most recent).
class LruSet {
 public:
  explicit LruSet(std::size_t capacity = 0) : cap_(capacity) { map_.reserve(capacity * 2 + 1); }
  // Returns true on a hit; on a miss inserts the line, evicting the least recently used one.
  bool access(std::uint64_t key) {
    auto it = map_.find(key);
    if (it != map_.end()) {
      order_.splice(order_.begin(), order_, it->second);
      return true;
    }
    if (cap_ == 0) return false;
    if (map_.size() == cap_) {
      map_.erase(order_.back());
      order_.pop_back();
    }
    order_.push_front(key);
    map_[key] = order_.begin();
    return false;
  }
  void clear() {
    map_.clear();
    order_.clear();
  }

 private:
  std::size_t cap_;
  std::list<std::uint64_t> order_;
  std::unordered_map<std::uint64_t, std::list<std::uint64_t>::iterator> map_;
};

struct CacheStats {
  std::uint64_t accesses = 0, hits = 0, misses = 0, cold = 0, capacity = 0, conflict = 0;
};

// One cache: `lines` lines in sets of `ways` (0 = fully associative). Set index = line mod sets.
class SetAssocCache {
 public:
  SetAssocCache(std::uint64_t lines, std::uint64_t ways) {
    ways_ = (ways == 0 || ways > lines) ? lines : ways;
    sets_ = lines / ways_;
    tags_.assign(sets_ * ways_, kEmpty);
    stamp_.assign(sets_ * ways_, 0);
    shadow_ = LruSet(static_cast<std::size_t>(lines));
    fully_ = sets_ == 1;
  }

  bool access(std::uint64_t line) {
    ++st_.accesses;
    const bool shadow_hit = shadow_.access(line);
    bool hit;
    if (fully_) {
      hit = shadow_hit;  // the cache *is* a fully associative LRU cache of this size
    } else {
      const std::uint64_t set = line % sets_;
      std::uint64_t* tag = &tags_[set * ways_];
      std::uint64_t* st = &stamp_[set * ways_];
      ++clock_;
      hit = false;
      std::uint64_t victim = 0;
      for (std::uint64_t w = 0; w < ways_; ++w) {
        if (tag[w] == line) {
          hit = true;
          st[w] = clock_;
          break;
        }
        if (st[w] < st[victim]) victim = w;  // empty ways have stamp 0: filled first
      }
      if (!hit) tag[victim] = line, st[victim] = clock_;
    }
    if (hit) {
      ++st_.hits;
    } else {
      ++st_.misses;
      if (seen_.insert(line).second)
        ++st_.cold;
      else if (!shadow_hit)
        ++st_.capacity;
      else
        ++st_.conflict;
    }
    return hit;
  }
  const CacheStats& stats() const { return st_; }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);
  std::uint64_t ways_ = 1, sets_ = 1, clock_ = 0;
  bool fully_ = false;
  std::vector<std::uint64_t> tags_, stamp_;
  LruSet shadow_;
  std::unordered_set<std::uint64_t> seen_;
  CacheStats st_;
};

}  // namespace rast5d
