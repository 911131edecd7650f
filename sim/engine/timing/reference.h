// The timing model's reference (docs/timing.md "The model's own error"): the same units, simulated
// cycle by cycle on finer items with real FIFO occupancy, to measure what the record-level max-plus
// model (timing/timing.h) loses.
//
// Items: each work record is split into n items of equal shares of its work (remainders to the first
// items), n = max(1, quads, ceil(sample tests / 64)): one item per shaded quad, or per 64 sample tests
// (a 2x2 quad's samples at 16 spp) when the record shades none. A record's texture misses and depth
// fills go with its first items (one each), which take the miss and fill latencies.
//
// Each cycle, from the last unit to the first: items whose latency has run out enter the next unit's
// FIFO (they hold a slot since they left); then the unit spends up to its throughput of work on the
// items at the head of its FIFO, in order, several per cycle when they are small; an item whose work
// is done leaves into the unit's latency pipeline only if the next FIFO has a free slot (a FIFO of F
// entries counts the items in its queue and in the upstream latency pipeline), else it blocks the
// unit. The first unit draws items from the record stream. With idle units bypassed (the model's
// default), an item with no work for a unit takes neither its latency nor a slot of its FIFO, and
// passes it in order. A cycle in which a unit does work counts
// as busy; one in which it holds a finished item, blocked; else starved. Cores: bins dealt
// round-robin, DRAM bandwidth split, each core simulated alone; the frame ends with the last.
//
// Contract: deterministic; the same configuration as the max-plus model (TimingConfig), items
// instead of records; cycles are whole clocks.
#pragma once

#include <cstddef>

#include "timing/timing.h"

namespace rast5d {

struct ReferenceResult {
  double cycles = 0;           // whole clocks
  std::uint64_t items = 0;     // items simulated
  std::uint64_t steps = 0;     // unit-cycles stepped (the simulator's own work)
  std::array<UnitStats, kNumUnits> units{};  // busy, blocked, starved clocks; work as in the records
};

// Throws std::invalid_argument for a bad configuration.
ReferenceResult simulate_reference(const TileWork* records, std::size_t n, const TimingConfig& cfg);

}  // namespace rast5d
