// User clip planes ([Nilsson 2012] §2): an axis-aligned box in (u, v, t).
//
// Contract: a sample whose (u, v, t) lies outside the closed box is never hit, for every
// algorithm (backend/sample_backend.h rejects it after the inside test, counted in
// interval.samples_clipped); the tile algorithm also intersects its lens intervals with the box
// (clip_lens, cost::kClipInterval) so that such samples are mostly never tested.
#pragma once

#include <cstdint>
#include <limits>

#include "core/arith.h"
#include "core/costs.h"
#include "core/params.h"
#include "tiletest/halfspace_lens.h"

namespace rast5d::iv {

inline constexpr double kInfD = std::numeric_limits<double>::infinity();

// The user clip box ([Nilsson 2012] §2): samples outside it are never hit.
struct ClipBox {
  double u_lo = -kInfD, u_hi = kInfD, v_lo = -kInfD, v_hi = kInfD, t_lo = -kInfD, t_hi = kInfD;
  bool active_u = false, active_v = false, active_t = false;
  bool active() const { return active_u || active_v || active_t; }
};

inline ClipBox clip_box(const RenderParams& p) {
  ClipBox c;
  c.active_u = p.clip_u[0] > -1.0 || p.clip_u[1] < 1.0;
  c.active_v = p.clip_v[0] > -1.0 || p.clip_v[1] < 1.0;
  c.active_t = p.clip_t[0] > 0.0 || p.clip_t[1] < 1.0;
  if (c.active_u) c.u_lo = p.clip_u[0], c.u_hi = p.clip_u[1];
  if (c.active_v) c.v_lo = p.clip_v[0], c.v_hi = p.clip_v[1];
  if (c.active_t) c.t_lo = p.clip_t[0], c.t_hi = p.clip_t[1];
  return c;
}

// Closed-box membership of a float sample, as the sample test's clip rejection uses it.
inline bool in_clip(const ClipBox& c, float u, float v, float t) {
  return !(c.active_u && (u < c.u_lo || u > c.u_hi)) && !(c.active_v && (v < c.v_lo || v > c.v_hi)) &&
         !(c.active_t && (t < c.t_lo || t > c.t_hi));
}

// Clip an axis set's active intervals to [lo, hi] (cost::kClipInterval per interval); drops empty
// intervals. The per-sample cuts are left unchanged: samples outside the clip range in surviving
// cells are rejected by the per-sample clip comparison.
template <class A>
inline void clip_axis(tiletest::AxisSet& s, double lo, double hi, std::uint64_t& ops) {
  using D = typename A::f64;
  int n = 0;
  for (int i = 0; i < s.n_intervals; ++i) {
    const D a = vmax(D(s.iv_lo[i]), D(lo));
    const D b = vmin(D(s.iv_hi[i]), D(hi));
    charge<A>(ops, cost::kClipInterval);
    if (raw(a) <= raw(b)) s.iv_lo[n] = raw(a), s.iv_hi[n] = raw(b), ++n;
  }
  s.n_intervals = n;
  s.empty = n == 0;
}

// The user clip box on a tile's lens sets (u and v axes, where active). False when either set is
// left without an interval.
template <class A>
inline bool clip_lens(const ClipBox& clip, tiletest::AxisSet& sx, tiletest::AxisSet& sy, std::uint64_t& ops) {
  if (clip.active_u) clip_axis<A>(sx, clip.u_lo, clip.u_hi, ops);
  if (clip.active_v) clip_axis<A>(sy, clip.v_lo, clip.v_hi, ops);
  return sx.n_intervals != 0 && sy.n_intervals != 0;
}

}  // namespace rast5d::iv
