// User clip planes (002_95ea0844b256f75b.txt §2): an axis-aligned box in (u, v, t). Semantics:
// a sample whose (u, v, t) lies outside the closed box is never hit, for every algorithm (the
// sample pipeline rejects it after the inside test, counted in interval.samples_clipped); the
// tile algorithm also intersects its intervals with the box (counted MIN/MAX) so that such
// samples are mostly never tested.
#pragma once

#include <limits>

#include "rast5d/params.h"

namespace rast5d::iv {

inline constexpr double kInfD = std::numeric_limits<double>::infinity();

// The user clip box (002 §2): samples outside it are never hit.
struct ClipBox {
  double u_lo = -kInfD, u_hi = kInfD, v_lo = -kInfD, v_hi = kInfD, t_lo = -kInfD, t_hi = kInfD;
  bool active_u = false, active_v = false, active_t = false;
  bool active() const { return active_u || active_v || active_t; }
};

inline ClipBox clip_box(const RenderParams& p) {
  ClipBox c;
  c.active_u = p.clip_u_lo > -1.0 || p.clip_u_hi < 1.0;
  c.active_v = p.clip_v_lo > -1.0 || p.clip_v_hi < 1.0;
  c.active_t = p.clip_t_lo > 0.0 || p.clip_t_hi < 1.0;
  if (c.active_u) c.u_lo = p.clip_u_lo, c.u_hi = p.clip_u_hi;
  if (c.active_v) c.v_lo = p.clip_v_lo, c.v_hi = p.clip_v_hi;
  if (c.active_t) c.t_lo = p.clip_t_lo, c.t_hi = p.clip_t_hi;
  return c;
}

// Closed-box membership of a float sample, as the sample test's clip rejection uses it.
inline bool in_clip(const ClipBox& c, float u, float v, float t) {
  return !(c.active_u && (u < c.u_lo || u > c.u_hi)) && !(c.active_v && (v < c.v_lo || v > c.v_hi)) &&
         !(c.active_t && (t < c.t_lo || t > c.t_hi));
}

}  // namespace rast5d::iv
