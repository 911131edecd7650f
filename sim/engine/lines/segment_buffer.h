// The per-line segment buffer and its composite ([Tzeng 2012] §4, §4.1, Fig. 3, Fig. 6).
//
// Contract:
//  * One buffer per line sample holds the segments (lens intervals covered by a triangle, each
//    shaded once at its midpoint) that reached it. With every heuristic off and no capacity limit
//    it holds every segment, and composite() is the exact visibility integral of the line up to
//    the depth order inside each elementary interval (decided at its midpoint; intersecting
//    segments are ordered there, as [Tzeng 2012] §4.1 accepts).
//  * Heuristics (pipeline.lines.*), in [Tzeng 2012] §4.1's order for an incoming segment: occluded (an
//    existing segment covers it and lies entirely in front: dropped; it covers an existing one and
//    lies entirely in front: that one is removed), merge (depth, colour and gap within thresholds:
//    the two become one segment over their union with the κ-weighted colour), length (a segment
//    that merged nowhere and whose κ weight is below min_weight is dropped: tessellated surfaces
//    first merge their short pieces), capacity (a full buffer evicts its smallest-κ segment, or
//    drops the incoming one when that is the smallest). The occlusion test never changes the image (it
//    removes only segments hidden over their whole extent, depth being monotone along a segment);
//    the others trade bias for storage and work.
//  * Every operation is counted in [Akenine-Möller 2012] §6.2 units through the scalar type F: the functions return
//    the documented count of what they executed (core/costs.h, §line samples), and the counting
//    path's tally equals it (tests/test_lines.py).
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "core/arith.h"
#include "core/costs.h"
#include "core/counters.h"
#include "lines/coverage.h"

namespace rast5d {

struct Segment {
  float a, b;             // lens interval on the line, a < b
  float k;                // κ weight
  float zmin, zmax, zmid; // hit depth over the segment (monotone: min and max at the ends)
  float s0, sg, d0, dg;   // sum(e) and det along the line: z(p) = 1 - near sum(p) / det(p)
  float col[3];           // shaded at the midpoint
};

struct SegmentRules {
  int capacity = 0;  // 0 = unlimited
  float min_weight = 0.0f;
  bool occlusion = false;
  bool merge = false;
  float merge_depth = 0.0f, merge_color2 = 0.0f, merge_gap = 0.0f;  // merge_color2: squared threshold
};

// Test an incoming segment against the buffer before it is shaded: returns false when it is
// occluded (and removes the existing segments it occludes). n_replaced counts those removals.
// ops: cost::kSegCover per existing segment compared (2 CMP + 1 CMP when it covers).
template <class F>
inline bool segment_visible(std::vector<Segment>& buf, const Segment& n, std::uint64_t& ops, Counters& c) {
  const F na = F(n.a), nb = F(n.b), nzmin = F(n.zmin), nzmax = F(n.zmax);
  for (const Segment& e : buf) {
    const bool l = F(e.a) <= na;
    const bool r = nb <= F(e.b);
    ops += 2;
    if (l && r) {
      ++ops;
      if (F(e.zmax) < nzmin) return false;
    }
  }
  std::size_t w = 0;
  for (std::size_t i = 0; i < buf.size(); ++i) {
    const Segment& e = buf[i];
    const bool l = na <= F(e.a);
    const bool r = F(e.b) <= nb;
    ops += 2;
    bool hidden = false;
    if (l && r) {
      ++ops;
      hidden = nzmax < F(e.zmin);
    }
    if (hidden) {
      ++c[Counter::lines_segments_replaced];
      continue;
    }
    buf[w++] = e;
  }
  buf.resize(w);
  return true;
}

// Merge the incoming segment into the first close enough existing one; true when merged.
template <class F>
inline bool segment_merge(std::vector<Segment>& buf, const Segment& n, const SegmentRules& r, std::uint64_t& ops) {
  for (Segment& e : buf) {
    const F dz = F(n.zmid) - F(e.zmid);
    ops += 2;
    if (!(vabs(dz) <= F(r.merge_depth))) continue;
    const F gap = vmax(F(n.a), F(e.a)) - vmin(F(n.b), F(e.b));
    ops += 4;
    if (!(gap <= F(r.merge_gap))) continue;
    const F d0 = F(n.col[0]) - F(e.col[0]), d1 = F(n.col[1]) - F(e.col[1]), d2 = F(n.col[2]) - F(e.col[2]);
    const F d2sum = madd(d2, d2, madd(d1, d1, d0 * d0));
    ops += 7;
    if (!(d2sum <= F(r.merge_color2))) continue;
    // Merge: union extent, κ-weighted colour, depth range union, the nearer midpoint depth.
    const F a = vmin(F(n.a), F(e.a)), b = vmax(F(n.b), F(e.b));
    const F kn = F(n.k), ke = F(e.k);
    const F inv = rcp(kn + ke);
    F col[3];
    for (int ch = 0; ch < 3; ++ch) col[ch] = madd(kn, F(n.col[ch]), ke * F(e.col[ch])) * inv;
    const F k = kappa(a, b);
    e.zmin = raw(vmin(F(n.zmin), F(e.zmin)));
    e.zmax = raw(vmax(F(n.zmax), F(e.zmax)));
    e.zmid = raw(vmin(F(n.zmid), F(e.zmid)));
    e.a = raw(a), e.b = raw(b), e.k = raw(k);
    for (int ch = 0; ch < 3; ++ch) e.col[ch] = raw(col[ch]);
    ops += cost::kSegMerge;
    return true;
  }
  return false;
}

// Insert into a buffer of the given capacity (0 = unlimited): evict the smallest-κ segment of a
// full buffer, or drop the incoming one when it is the smallest.
template <class F>
inline void segment_insert(std::vector<Segment>& buf, const Segment& n, int capacity, std::uint64_t& ops,
                           Counters& c) {
  if (capacity == 0 || static_cast<int>(buf.size()) < capacity) {
    buf.push_back(n);
    return;
  }
  ++c[Counter::lines_overflows];
  std::size_t m = 0;
  F km = F(buf[0].k);
  for (std::size_t i = 1; i < buf.size(); ++i) {
    ++ops;
    if (F(buf[i].k) < km) m = i, km = F(buf[i].k);
  }
  ++ops;
  if (F(n.k) <= km) {
    ++c[Counter::lines_segments_dropped];
    return;
  }
  ++c[Counter::lines_segments_evicted];
  buf[m] = n;
}

// Composite one line ([Tzeng 2012] Fig. 3): walk the sorted segment ends; in each elementary interval the
// nearest covering segment (depth at the interval's midpoint) contributes κ(interval) x colour.
// scratch: reusable storage. Returns the documented operation count; steps counts the intervals
// that had a covering segment.
template <class F>
inline std::uint64_t composite_line(const std::vector<Segment>& buf, F neg_near, std::vector<float>& scratch,
                                    float out[3], std::uint64_t& steps) {
  out[0] = out[1] = out[2] = 0.0f;
  if (buf.empty()) return 0;
  std::uint64_t ops = 0;
  scratch.clear();
  for (const Segment& s : buf) scratch.push_back(s.a), scratch.push_back(s.b);
  // Insertion sort: one CMP per comparison.
  for (std::size_t i = 1; i < scratch.size(); ++i) {
    const float x = scratch[i];
    std::size_t j = i;
    while (j > 0) {
      ++ops;
      if (!(F(x) < F(scratch[j - 1]))) break;
      scratch[j] = scratch[j - 1];
      --j;
    }
    scratch[j] = x;
  }
  F acc[3] = {F(0.0f), F(0.0f), F(0.0f)};
  for (std::size_t i = 0; i + 1 < scratch.size(); ++i) {
    const F t0 = F(scratch[i]), t1 = F(scratch[i + 1]);
    ++ops;
    if (!(t0 < t1)) continue;
    const F m = (t0 + t1) * F(0.5f);
    ops += 2;
    const Segment* best = nullptr;
    F bz = F(std::numeric_limits<float>::infinity());
    for (const Segment& s : buf) {
      const bool l = F(s.a) <= m;
      const bool r = m <= F(s.b);
      ops += 2;
      if (!(l && r)) continue;
      const F z = line_depth(F(s.s0), F(s.sg), F(s.d0), F(s.dg), m, neg_near);
      ops += cost::kLineDepth + 1;
      if (z < bz) bz = z, best = &s;
    }
    if (!best) continue;
    ++steps;
    const F k = kappa(t0, t1);
    for (int ch = 0; ch < 3; ++ch) acc[ch] = madd(k, F(best->col[ch]), acc[ch]);
    ops += cost::kKappa + 3;
  }
  for (int ch = 0; ch < 3; ++ch) out[ch] = raw(acc[ch]);
  return ops;
}

}  // namespace rast5d
