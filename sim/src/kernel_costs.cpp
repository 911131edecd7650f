// Cost self-tests of the sample, interpolation and setup kernels (see kernel_costs.h).
#include "rast5d/kernel_costs.h"

#include "rast5d/arith.h"
#include "rast5d/costs.h"
#include "rast5d/inside.h"

namespace rast5d {
namespace {

using CF = Counted<float>;

float rnd(std::mt19937_64& g, float lo, float hi) {
  return std::uniform_real_distribution<float>(lo, hi)(g);
}

void random_tri(std::mt19937_64& g, CF X[3], CF Y[3], CF W[3]) {
  for (int j = 0; j < 3; ++j) {
    W[j] = CF(rnd(g, 0.5f, 20.0f));
    X[j] = CF(rnd(g, -100.0f, 600.0f) * W[j].v);
    Y[j] = CF(rnd(g, -100.0f, 600.0f) * W[j].v);
  }
}

TriSetup random_setup(std::mt19937_64& g, const FrameConst& fc, bool moving) {
  TriSetup t;
  for (int j = 0; j < 3; ++j) {
    t.W[j] = rnd(g, 0.5f, 20.0f);
    t.X[j] = rnd(g, 0.0f, 512.0f) * t.W[j];
    t.Y[j] = rnd(g, 0.0f, 512.0f) * t.W[j];
    t.dX[j] = moving ? rnd(g, -50.0f, 50.0f) : 0.0f;
    t.dY[j] = moving ? rnd(g, -50.0f, 50.0f) : 0.0f;
    t.dW[j] = moving ? rnd(g, -0.2f, 0.2f) : 0.0f;
    t.cx[j] = fc.kx * t.W[j] + fc.neg_kx_f;
    t.cy[j] = fc.ky * t.W[j] + fc.neg_ky_f;
    for (int ch = 0; ch < 3; ++ch) t.color[j][ch] = rnd(g, 0, 1);
  }
  return t;
}

FrameConst frame() {
  RenderParams p;
  p.width = p.height = 512;
  p.coc_x_px = 10;
  p.coc_y_px = -10;
  p.focus_w = 5;
  return make_frame_const(p);
}

std::uint64_t inside_cost_run(std::mt19937_64& g, DimClass cls) {
  const FrameConst fc = frame();
  const TriSetup t = random_setup(g, fc, cls == DimClass::k3D || cls == DimClass::k5D);
  CF X[3], Y[3], W[3], e[3], det;
  int n_ties;
  OpTally::take();
  inside_test(t, cls, fc, CF(rnd(g, 0, 512)), CF(rnd(g, 0, 512)), CF(rnd(g, -1, 1)), CF(rnd(g, -1, 1)),
              CF(rnd(g, 0, 1)), false, X, Y, W, e, det, n_ties);
  // Ties are charged separately (kTieBreak per zero edge); remove them from the tally.
  const std::uint64_t n = OpTally::take();
  return n - static_cast<std::uint64_t>(n_ties) * cost::kTieBreak;
}

const bool kRegistered = [] {
  auto& R = KernelCostRegistry::entries();
  R.emplace("sample.edges", KernelCostEntry{cost::kEdges, [](std::mt19937_64& g) {
              CF X[3], Y[3], W[3], e[3], det;
              random_tri(g, X, Y, W);
              OpTally::take();
              edge_functions(X, Y, W, CF(rnd(g, 0, 512)), CF(rnd(g, 0, 512)), e, det);
              return OpTally::take();
            }});
  R.emplace("sample.signs", KernelCostEntry{cost::kSigns, [](std::mt19937_64& g) {
              CF e[3] = {CF(rnd(g, -1, 1)), CF(rnd(g, -1, 1)), CF(rnd(g, -1, 1))};
              int ds, zm;
              OpTally::take();
              edge_signs(e, CF(rnd(g, -1, 1)), false, ds, zm);
              return OpTally::take();
            }});
  R.emplace("sample.tie_break", KernelCostEntry{cost::kTieBreak, [](std::mt19937_64& g) {
              CF X[3], Y[3], W[3];
              random_tri(g, X, Y, W);
              OpTally::take();
              tie_break_edge(X, Y, W, CF(rnd(g, 0, 512)), CF(rnd(g, 0, 512)),
                             static_cast<int>(g() % 3), (g() & 1) ? 1 : -1);
              return OpTally::take();
            }});
  R.emplace("sample.shear", KernelCostEntry{cost::kShear, [](std::mt19937_64& g) {
              CF X[3], Y[3], W[3], Xs[3], Ys[3];
              random_tri(g, X, Y, W);
              OpTally::take();
              shear_static(X, Y, W, W, CF(rnd(g, -1, 1)), CF(rnd(g, -1, 1)), Xs, Ys);
              return OpTally::take();
            }});
  R.emplace("sample.lerp", KernelCostEntry{cost::kLerp, [](std::mt19937_64& g) {
              CF X[3], Y[3], W[3], Xt[3], Yt[3], Wt[3];
              random_tri(g, X, Y, W);
              OpTally::take();
              lerp_vertices(X, Y, W, X, Y, W, CF(rnd(g, 0, 1)), Xt, Yt, Wt);
              return OpTally::take();
            }});
  R.emplace("sample.shear_moving", KernelCostEntry{cost::kShearMoving, [](std::mt19937_64& g) {
              CF X[3], Y[3], W[3], Xs[3], Ys[3];
              random_tri(g, X, Y, W);
              OpTally::take();
              shear_moving(X, Y, W, CF(3.0f), CF(-15.0f), CF(-3.0f), CF(15.0f), CF(rnd(g, -1, 1)),
                           CF(rnd(g, -1, 1)), Xs, Ys);
              return OpTally::take();
            }});
  R.emplace("sample.inside_2d", KernelCostEntry{cost::kInside2D, [](std::mt19937_64& g) {
              return inside_cost_run(g, DimClass::k2D);
            }});
  R.emplace("sample.inside_3d", KernelCostEntry{cost::kInside3D, [](std::mt19937_64& g) {
              return inside_cost_run(g, DimClass::k3D);
            }});
  R.emplace("sample.inside_4d", KernelCostEntry{cost::kInside4D, [](std::mt19937_64& g) {
              return inside_cost_run(g, DimClass::k4D);
            }});
  R.emplace("sample.inside_5d", KernelCostEntry{cost::kInside5D, [](std::mt19937_64& g) {
              return inside_cost_run(g, DimClass::k5D);
            }});
  R.emplace("interp.depth", KernelCostEntry{cost::kDepth, [](std::mt19937_64& g) {
              CF e[3] = {CF(rnd(g, 0.1f, 1)), CF(rnd(g, 0.1f, 1)), CF(rnd(g, 0.1f, 1))};
              CF sum, z;
              OpTally::take();
              hit_depth(e, CF(rnd(g, 1, 2)), CF(-0.1f), sum, z);
              return OpTally::take();
            }});
  R.emplace("interp.depth_test", KernelCostEntry{cost::kDepthTest, [](std::mt19937_64& g) {
              CF z(rnd(g, 0, 1));
              const float zbuf = rnd(g, 0, 1);
              OpTally::take();
              volatile bool pass = z < CF(zbuf);
              (void)pass;
              return OpTally::take();
            }});
  R.emplace("interp.color", KernelCostEntry{cost::kColor, [](std::mt19937_64& g) {
              CF e[3] = {CF(rnd(g, 0.1f, 1)), CF(rnd(g, 0.1f, 1)), CF(rnd(g, 0.1f, 1))};
              CF c0[3] = {CF(0.1f), CF(0.2f), CF(0.3f)}, out[3];
              OpTally::take();
              hit_color(e, CF(rnd(g, 0.5f, 3)), c0, c0, c0, out);
              return OpTally::take();
            }});
  R.emplace("setup.bounds_point", KernelCostEntry{cost::kBoundsPoint, [](std::mt19937_64& g) {
              CF a(1e30f), b(-1e30f), c(1e30f), d(-1e30f);
              OpTally::take();
              bounds_point(CF(rnd(g, 0, 900)), CF(rnd(g, 0, 900)), CF(rnd(g, 1, 9)), CF(-5.0f),
                           CF(10.0f), CF(-10.0f), false, a, b, c, d);
              return OpTally::take();
            }});
  R.emplace("setup.bounds_point_lens", KernelCostEntry{cost::kBoundsPointLens, [](std::mt19937_64& g) {
              CF a(1e30f), b(-1e30f), c(1e30f), d(-1e30f);
              OpTally::take();
              bounds_point(CF(rnd(g, 0, 900)), CF(rnd(g, 0, 900)), CF(rnd(g, 1, 9)), CF(-5.0f),
                           CF(10.0f), CF(-10.0f), true, a, b, c, d);
              return OpTally::take();
            }});
  return true;
}();

}  // namespace
}  // namespace rast5d
