// The cycle-stepped reference of the timing model (timing/reference.h).
#include "timing/reference.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <vector>

namespace rast5d {

namespace {

constexpr int kTex = static_cast<int>(Unit::texture);
constexpr int kDepth = static_cast<int>(Unit::depth);
constexpr int kDram = static_cast<int>(Unit::dram);
constexpr double kEps = 1e-9;

struct Item {
  std::array<std::uint64_t, kNumUnits> work{};
  bool tex_miss = false, fill = false;
};

// The items of one core's records, in stream order.
std::vector<Item> split(const TileWork* records, const std::vector<std::uint32_t>& stream) {
  std::vector<Item> items;
  for (const std::uint32_t r : stream) {
    const TileWork& w = records[r];
    const std::uint64_t n = std::max<std::uint64_t>({1, w.quads, (w.sample_tests + 63) / 64});
    const std::size_t first = items.size();
    items.resize(first + n);
    for (int k = 0; k < kNumUnits; ++k) {
      const std::uint64_t a = w.amount(static_cast<Unit>(k)), base = a / n, extra = a % n;
      for (std::uint64_t j = 0; j < n; ++j) items[first + j].work[k] = base + (j < extra ? 1 : 0);
    }
    for (std::uint64_t j = 0; j < n; ++j) {
      items[first + j].tex_miss = j < w.tex_misses;
      items[first + j].fill = j < w.depth_fills;
    }
  }
  return items;
}

struct Core {
  double end = 0;
  std::uint64_t steps = 0;
  std::array<UnitStats, kNumUnits> units{};
};

Core run_core(const std::vector<Item>& items, const TimingConfig& cfg, double dram_tp) {
  Core out;
  const std::size_t n = items.size();
  if (n == 0) return out;
  std::array<double, kNumUnits> tp{};
  std::array<std::uint64_t, kNumUnits> fifo{};
  for (int k = 0; k < kNumUnits; ++k) {
    tp[k] = k == kDram ? dram_tp : cfg.units[k].throughput;
    fifo[k] = static_cast<std::uint64_t>(cfg.units[k].fifo);
  }
  struct InFlight {
    std::uint64_t ready;
    std::uint32_t id;
  };
  std::array<std::deque<std::uint32_t>, kNumUnits> queue;  // arrived, waiting for service
  std::array<std::deque<InFlight>, kNumUnits> pipe;        // left the unit, in its latency pipeline
  std::array<std::uint64_t, kNumUnits> occ{};              // FIFO slots held: queue + upstream pipe
  std::array<std::int64_t, kNumUnits> cur, held;
  cur.fill(-1), held.fill(-1);
  std::array<double, kNumUnits> rem{};
  std::size_t next_source = 0, finished = 0;
  // bypass_idle: an item occupies (latency, FIFO slot) only the units it has work for.
  auto occupies = [&](int k, const Item& it) { return !cfg.bypass_idle || it.work[k] > 0; };
  auto latency = [&](int k, const Item& it) {
    double l = occupies(k, it) ? cfg.units[k].latency : 0.0;
    if (k == kTex && it.work[kTex]) l += it.tex_miss ? cfg.tex_miss_latency : cfg.tex_hit_latency;
    if (k == kDepth && it.fill) l += cfg.fill_latency;
    return static_cast<std::uint64_t>(std::ceil(l));
  };
  for (std::uint64_t c = 0; finished < n; ++c) {
    for (int k = 0; k < kNumUnits; ++k) {  // latency over: into the next FIFO, in order
      auto& pl = pipe[k];
      while (!pl.empty() && pl.front().ready <= c) {
        if (k + 1 < kNumUnits) queue[k + 1].push_back(pl.front().id);
        else ++finished;
        pl.pop_front();
      }
    }
    if (finished == n) {
      out.end = static_cast<double>(c);
      break;
    }
    for (int k = kNumUnits - 1; k >= 0; --k) {
      ++out.steps;
      auto& pl = pipe[k];
      double budget = tp[k];
      bool blocked = false;
      for (;;) {
        if (held[k] >= 0) {  // a finished item leaves when the next FIFO has a slot
          const Item& it = items[static_cast<std::size_t>(held[k])];
          const bool slot = k + 1 < kNumUnits && occupies(k + 1, it);
          if (slot && occ[k + 1] >= fifo[k + 1]) {
            blocked = true;
            break;
          }
          if (slot) ++occ[k + 1];
          pl.push_back({c + latency(k, it), static_cast<std::uint32_t>(held[k])});
          held[k] = -1;
        }
        if (cur[k] < 0) {
          if (k == 0) {
            if (next_source == n) break;
            cur[k] = static_cast<std::int64_t>(next_source++);
          } else {
            if (queue[k].empty()) break;
            cur[k] = queue[k].front();
            queue[k].pop_front();
            if (occupies(k, items[static_cast<std::size_t>(cur[k])])) --occ[k];  // the slot frees when service starts
          }
          rem[k] = static_cast<double>(items[static_cast<std::size_t>(cur[k])].work[k]);
        }
        const double use = std::min(budget, rem[k]);
        rem[k] -= use;
        budget -= use;
        if (rem[k] > kEps) break;  // the cycle's budget is spent
        held[k] = cur[k];
        cur[k] = -1;
      }
      const double used = (tp[k] - budget) / tp[k];
      UnitStats& st = out.units[k];
      st.busy += used;
      if (blocked) st.blocked += 1.0 - used;
      else st.starved += 1.0 - used;
    }
  }
  return out;
}

}  // namespace

ReferenceResult simulate_reference(const TileWork* records, std::size_t n, const TimingConfig& cfg) {
  cfg.validate();
  ReferenceResult r;
  std::vector<std::vector<std::uint32_t>> streams(static_cast<std::size_t>(cfg.cores));
  std::uint64_t unbinned = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t b = records[i].bin;
    const std::uint64_t core = b >= 0 ? static_cast<std::uint64_t>(b) % cfg.cores : unbinned++ % cfg.cores;
    streams[core].push_back(static_cast<std::uint32_t>(i));
    for (int k = 0; k < kNumUnits; ++k) r.units[k].work += static_cast<double>(records[i].amount(static_cast<Unit>(k)));
  }
  std::vector<Core> cores;
  for (const auto& s : streams) {
    const std::vector<Item> items = split(records, s);
    r.items += items.size();
    cores.push_back(run_core(items, cfg, cfg.units[kDram].throughput / cfg.cores));
  }
  for (const Core& c : cores) {
    r.cycles = std::max(r.cycles, c.end);
    r.steps += c.steps;
  }
  for (const Core& c : cores)
    for (int k = 0; k < kNumUnits; ++k) {
      r.units[k].busy += c.units[k].busy;
      r.units[k].blocked += c.units[k].blocked;
      r.units[k].starved += c.units[k].starved + (r.cycles - c.end);
    }
  return r;
}

}  // namespace rast5d
