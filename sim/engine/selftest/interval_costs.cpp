// Cost self-tests of the interval kernels (intervals/): each run executes a kernel once
// on the counting type (ExactArith: the tally) and once on the fast path (FastArith: the
// documented cost it charges) with the same random input; tests/test_op_costs.py requires equality.
#include <random>

#include "intervals/clip.h"
#include "intervals/depth_interval.h"
#include "intervals/time_interval.h"
#include "selftest/kernel_costs.h"

namespace rast5d {
namespace {

using Pair = std::pair<std::uint64_t, std::uint64_t>;

double rnd(std::mt19937_64& g, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(g); }

FrameConst frame(std::mt19937_64& g, bool lens) {
  RenderParams p;
  p.width = p.height = 256;
  p.coc_x_px = lens ? rnd(g, 1, 60) : 0.0;
  p.coc_y_px = -p.coc_x_px;
  p.focus_w = 5;
  p.near_w = 0.1;
  return make_frame_const(p);
}

// A moving triangle; some vertices may cross W = 0 during the shutter.
TriSetup moving_tri(std::mt19937_64& g, bool lens) {
  TriSetup t;
  t.moving = true;
  t.defocused = lens;
  t.cls = lens ? DimClass::k5D : DimClass::k3D;
  for (int j = 0; j < 3; ++j) {
    t.W[j] = static_cast<float>(rnd(g, 0.5, 20));
    t.X[j] = static_cast<float>(rnd(g, 0, 256) * t.W[j]);
    t.Y[j] = static_cast<float>(rnd(g, 0, 256) * t.W[j]);
    t.dW[j] = static_cast<float>(rnd(g, (g() % 4 == 0) ? -25.0 : -0.3, 0.3));
    t.dX[j] = static_cast<float>(rnd(g, -600, 600));
    t.dY[j] = static_cast<float>(rnd(g, -600, 600));
    t.cx[j] = t.cy[j] = 0.0f;
  }
  return t;
}

template <class Fn>
Pair both(Fn&& fn) {
  std::uint64_t exact = 0, doc = 0;
  OpTally::take();
  fn.template operator()<ExactArith>(exact);
  fn.template operator()<FastArith>(doc);
  OpTally::take();
  return {exact, doc};
}

const bool kRegistered = [] {
  auto& R = TileKernelCostRegistry::entries();
  R.emplace("interval.form_cull", [](std::mt19937_64& g) -> Pair {
    const double a = rnd(g, -2, 2), b = rnd(g, -2, 2);
    OpTally::take();
    Counted<double> lo(-1e300), hi(1e300);
    iv::form_cull(Counted<double>(a), Counted<double>(b), lo, hi);
    return {OpTally::take(), cost::kFormCull};
  });
  for (const bool lens : {false, true}) {
    const std::string sfx = lens ? "_5d" : "_3d";
    R.emplace("interval.motion_setup" + sfx, [lens](std::mt19937_64& g) -> Pair {
      const FrameConst fc = frame(g, lens);
      const TriSetup t = moving_tri(g, lens);
      const int S = 1 << (g() % 5);
      return both([&]<class A>(std::uint64_t& ops) {
        iv::MotionSetup ms;
        iv::motion_setup<A>(t, fc, S, ms, ops);
      });
    });
    R.emplace("interval.tile_intervals" + sfx, [lens](std::mt19937_64& g) -> Pair {
      const FrameConst fc = frame(g, lens);
      const TriSetup t = moving_tri(g, lens);
      const int S = 1 << (g() % 5);
      iv::MotionSetup ms;
      std::uint64_t ignore = 0;
      iv::motion_setup<FastArith>(t, fc, S, ms, ignore);
      iv::ClipBox clip;
      if (g() % 2) clip.active_u = clip.active_t = true, clip.u_lo = -0.5, clip.u_hi = 0.7, clip.t_lo = 0.2, clip.t_hi = 0.9;
      const double x0 = rnd(g, 0, 256), y0 = rnd(g, 0, 256), T = static_cast<double>(1 << (g() % 4));
      return both([&]<class A>(std::uint64_t& ops) {
        iv::TileIntervals ti;
        Counters c;
        iv::motion_tile_intervals<A>(ms, clip, t.cls, x0, x0 + T, y0, y0 + T, ti, ops, c);
      });
    });
    R.emplace("zhat.planes" + sfx, [lens](std::mt19937_64& g) -> Pair {
      const FrameConst fc = frame(g, lens);
      const TriSetup t = moving_tri(g, lens);
      const double x0 = rnd(g, 0, 256), y0 = rnd(g, 0, 256), u0 = rnd(g, -1, 0.5), v0 = rnd(g, -1, 0.5);
      const double ta = rnd(g, 0, 1), tb = std::min(1.0, ta + rnd(g, 0, 1));
      const bool planes_on = g() % 4 != 0;
      return both([&]<class A>(std::uint64_t& ops) {
        iv::MovingPlanes mp;
        iv::moving_planes<A>(t, mp, ops);
        iv::zhat<A>(t, planes_on ? &mp : nullptr, fc, lens, x0, x0 + 2, y0, y0 + 2, u0, u0 + 0.5, v0, v0 + 0.5, ta,
                    tb, ops);
      });
    });
  }
  R.emplace("interval.clip_axis", [](std::mt19937_64& g) -> Pair {
    tiletest::AxisSet s = tiletest::full_axis();
    s.n_intervals = 1 + static_cast<int>(g() % 3);
    for (int i = 0; i < s.n_intervals; ++i) s.iv_lo[i] = -1 + i * 0.6, s.iv_hi[i] = -0.8 + i * 0.6;
    const double lo = rnd(g, -1, 0), hi = rnd(g, 0, 1);
    return both([&]<class A>(std::uint64_t& ops) {
      tiletest::AxisSet c = s;
      iv::clip_axis<A>(c, lo, hi, ops);
    });
  });
  return true;
}();

}  // namespace
}  // namespace rast5d
