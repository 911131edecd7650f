// Cost self-tests of the sample, interpolation and setup kernels (see kernel_costs.h).
#include "selftest/kernel_costs.h"

#include "core/arith.h"
#include "core/costs.h"
#include "setup/footprint.h"
#include "sampletest/hardware.h"
#include "sampletest/inside.h"
#include "tiletest/box_bounds.h"
#include "tiletest/edges_2d.h"
#include "tiletest/halfspace_edges.h"
#include "tiletest/halfspace_lens.h"
#include "tiletest/lens_shape.h"
#include "tiletest/lens_vertex.h"

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

// The hardware cost model's sample test (sampletest/hardware.h), ties counted separately.
std::uint64_t hw_inside_cost_run(std::mt19937_64& g, DimClass cls) {
  const FrameConst fc = frame();
  const TriSetup t = random_setup(g, fc, cls == DimClass::k3D || cls == DimClass::k5D);
  OpTally::take();
  hw_inside_test(t, cls, fc, CF(rnd(g, 0, 512)), CF(rnd(g, 0, 512)), CF(rnd(g, -1, 1)), CF(rnd(g, -1, 1)),
                 CF(rnd(g, 0, 1)), 0);
  return OpTally::take();
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
  R.emplace("sample.hw_inside_2d", KernelCostEntry{cost::kHwInside2D, [](std::mt19937_64& g) {
              return hw_inside_cost_run(g, DimClass::k2D);
            }});
  R.emplace("sample.hw_inside_3d", KernelCostEntry{cost::kHwInside3D, [](std::mt19937_64& g) {
              return hw_inside_cost_run(g, DimClass::k3D);
            }});
  R.emplace("sample.hw_inside_4d", KernelCostEntry{cost::kHwInside4D, [](std::mt19937_64& g) {
              return hw_inside_cost_run(g, DimClass::k4D);
            }});
  R.emplace("sample.hw_inside_5d", KernelCostEntry{cost::kHwInside5D, [](std::mt19937_64& g) {
              return hw_inside_cost_run(g, DimClass::k5D);
            }});
  R.emplace("sample.hw_inside_sheared", KernelCostEntry{cost::kHwInside2D, [](std::mt19937_64& g) {
              float X[3], Y[3], W[3];
              for (int j = 0; j < 3; ++j) W[j] = rnd(g, 0.5f, 20), X[j] = rnd(g, 0, 500) * W[j], Y[j] = rnd(g, 0, 500) * W[j];
              OpTally::take();
              hw_inside_sheared(X, Y, W, CF(rnd(g, 0, 512)), CF(rnd(g, 0, 512)));
              return OpTally::take();
            }});
  R.emplace("sample.hw_tie_break", KernelCostEntry{cost::kHwTieBreak, [](std::mt19937_64& g) {
              CF X[3], Y[3], W[3], rx[3], ry[3];
              random_tri(g, X, Y, W);
              for (int j = 0; j < 3; ++j) rx[j] = X[j], ry[j] = Y[j];
              OpTally::take();
              hw_tie_break(W, rx, ry, static_cast<int>(g() % 3), (g() & 1) ? 1 : -1);
              return OpTally::take();
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

// ---- tile-test kernels: costs that depend on the configuration ------------------------------
namespace rast5d {
namespace {

using CD = Counted<double>;
using Pair = std::pair<std::uint64_t, std::uint64_t>;

double rndd(std::mt19937_64& g, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(g); }

// A random lens vertex; sometimes on the focus plane (W == F) or with no blur (k == 0).
tiletest::LensVertex random_lens_vertex(std::mt19937_64& g, double k) {
  const double W = (g() % 5 == 0) ? 5.0 : rndd(g, 0.5, 20.0);
  return tiletest::lens_vertex(CD(rndd(g, -100, 600) * W), CD(rndd(g, -100, 600) * W), CD(W), CD(-5.0), CD(k),
                               CD(-k));
}

tiletest::AxisSet random_axis_set(std::mt19937_64& g, tiletest::Gaps* out = nullptr) {
  tiletest::LensVertex vs[6];
  const int n = 3 + static_cast<int>(g() % 4);
  const double k = (g() % 6 == 0) ? 0.0 : rndd(g, 0.5, 80);
  for (int j = 0; j < n; ++j) vs[j] = random_lens_vertex(g, k);
  const double x0 = rndd(g, 0, 500);
  const tiletest::Gaps gx = tiletest::axis_gaps(vs, n, false, 1.0 * x0, x0 + 2.0);
  if (out) *out = gx;
  return tiletest::axis_set<double>(gx);
}

tiletest::EdgeH random_edge(std::mt19937_64& g, bool& parallel) {
  double q[3] = {rndd(g, -100, 600), rndd(g, -100, 600), rndd(g, 0.5, 20)};
  double r[3] = {rndd(g, -100, 600), rndd(g, -100, 600), (g() % 4 == 0) ? q[2] : rndd(g, 0.5, 20)};
  for (int k = 0; k < 2; ++k) q[k] *= q[2], r[k] *= r[2];
  parallel = r[2] == q[2];
  return tiletest::edge_setup(q, r, CD(5.0), CD(rndd(g, 1, 60)), CD(-rndd(g, 1, 60)));
}

const bool kRegisteredTile = [] {
  auto& R = TileKernelCostRegistry::entries();
  R.emplace("tile.lens_vertex", [](std::mt19937_64& g) -> Pair {
    const double k = (g() % 4 == 0) ? 0.0 : rndd(g, 0.5, 60);
    OpTally::take();
    const tiletest::LensVertex v = random_lens_vertex(g, k);
    return {OpTally::take(), tiletest::lens_vertex_cost(v)};
  });
  R.emplace("tile.axis_gaps", [](std::mt19937_64& g) -> Pair {
    tiletest::LensVertex vs[6];
    const int n = 3 + static_cast<int>(g() % 4);
    const double k = (g() % 6 == 0) ? 0.0 : rndd(g, 0.5, 80);
    for (int j = 0; j < n; ++j) vs[j] = random_lens_vertex(g, k);
    const bool y = (g() & 1) != 0;
    const double x0 = rndd(g, 0, 500);
    OpTally::take();
    tiletest::axis_gaps(vs, n, y, CD(x0), CD(x0 + 2.0));
    return {OpTally::take(), tiletest::axis_gaps_cost(vs, n, y)};
  });
  R.emplace("tile.axis_set", [](std::mt19937_64& g) -> Pair {
    tiletest::Gaps gx;
    random_axis_set(g, &gx);
    OpTally::take();
    tiletest::axis_set<CD>(gx);
    return {OpTally::take(), (gx.blocked[0] ? 0 : cost::kAxisSetGap) + (gx.blocked[1] ? 0 : cost::kAxisSetGap)};
  });
  R.emplace("tile.axis_pass", [](std::mt19937_64& g) -> Pair {
    const tiletest::AxisSet s = random_axis_set(g);
    OpTally::take();
    tiletest::axis_pass(s, Counted<float>(static_cast<float>(rndd(g, -1, 1))));
    return {OpTally::take(), static_cast<std::uint64_t>(s.n_cmp)};
  });
  R.emplace("tile.axis_cells", [](std::mt19937_64& g) -> Pair {
    const tiletest::AxisSet s = random_axis_set(g);
    OpTally::take();
    tiletest::axis_cells<CD>(s, 4 << (g() % 3));
    return {OpTally::take(), static_cast<std::uint64_t>(s.n_cmp)};
  });
  R.emplace("tile.box_overlaps_lens", [](std::mt19937_64& g) -> Pair {
    const LensShape shape = static_cast<LensShape>(g() % 3);
    const double u0 = rndd(g, -1, 1), v0 = rndd(g, -1, 1);
    OpTally::take();
    tiletest::box_overlaps_lens<CD>(shape, u0, std::min(1.0, u0 + rndd(g, 0, 1)), v0, std::min(1.0, v0 + rndd(g, 0, 1)));
    return {OpTally::take(),
            shape == LensShape::kSquare ? 0 : (shape == LensShape::kDisk ? cost::kBoxDisk : cost::kBoxHexagon)};
  });
  R.emplace("tile.edge_setup", [](std::mt19937_64& g) -> Pair {
    bool parallel;
    OpTally::take();
    random_edge(g, parallel);
    return {OpTally::take(), parallel ? cost::kEdgeSetupParallel : cost::kEdgeSetup};
  });
  R.emplace("tile.tangent_corners", [](std::mt19937_64& g) -> Pair {
    bool parallel;
    const tiletest::EdgeH e = random_edge(g, parallel);
    const double x0 = rndd(g, 0, 500), y0 = rndd(g, 0, 500);
    int m, n;
    OpTally::take();
    tiletest::tangent_corners<CD>(e, x0, x0 + 2, y0, y0 + 2, m, n);
    return {OpTally::take(), e.parallel ? 0 : cost::kTangentCorners};
  });
  R.emplace("tile.line_at_corner", [](std::mt19937_64& g) -> Pair {
    bool parallel;
    const tiletest::EdgeH e = random_edge(g, parallel);
    OpTally::take();
    tiletest::line_at_corner<CD>(e, rndd(g, 0, 500), rndd(g, 0, 500), (g() & 1) ? 1 : -1);
    return {OpTally::take(), cost::kLineAtCorner};
  });
  R.emplace("tile.line_cells", [](std::mt19937_64& g) -> Pair {
    const int G = 1 << (g() % 4);
    const int i0 = static_cast<int>(g() % G), j0 = static_cast<int>(g() % G);
    const int i1 = i0 + static_cast<int>(g() % (G - i0)), j1 = j0 + static_cast<int>(g() % (G - j0));
    const tiletest::Line l{rndd(g, -3, 3), rndd(g, -3, 3), rndd(g, -3, 3)};
    OpTally::take();
    tiletest::line_cells<CD>(l, G, i0, i1, j0, j1);
    const std::uint64_t rows = j1 - j0 + 1, cols = i1 - i0 + 1;
    return {OpTally::take(), tiletest::line_cells_cost(rows, cols)};
  });
  R.emplace("tile.edges_2d", [](std::mt19937_64& g) -> Pair {
    float X[3], Y[3], W[3];
    for (int j = 0; j < 3; ++j) W[j] = rnd(g, 0.5f, 20), X[j] = rnd(g, 0, 500) * W[j], Y[j] = rnd(g, 0, 500) * W[j];
    OpTally::take();
    tiletest::edges_2d<CD>(X, Y, W);
    return {OpTally::take(), cost::kEdges2DSetup};
  });
  R.emplace("tile.tile_outside_2d", [](std::mt19937_64& g) -> Pair {
    float X[3], Y[3], W[3];
    for (int j = 0; j < 3; ++j) W[j] = rnd(g, 0.5f, 20), X[j] = rnd(g, 0, 500) * W[j], Y[j] = rnd(g, 0, 500) * W[j];
    const tiletest::Edges2D e = tiletest::edges_2d<double>(X, Y, W);
    const double x0 = rndd(g, 0, 500), y0 = rndd(g, 0, 500);
    OpTally::take();
    tiletest::tile_outside_2d<CD>(e, x0, x0 + 2, y0, y0 + 2);
    return {OpTally::take(), cost::kTile2D};
  });
  R.emplace("tile.box_bounds", [](std::mt19937_64& g) -> Pair {
    tiletest::LensVertex vs[6];
    const int n = 3 + static_cast<int>(g() % 4);
    const double k = (g() % 6 == 0) ? 0.0 : rndd(g, 0.5, 80);
    for (int j = 0; j < n; ++j) vs[j] = random_lens_vertex(g, k);
    const bool point = (g() & 1) != 0;
    const double u0 = rndd(g, -1, 1), v0 = rndd(g, -1, 1);
    double a, b, c, d;
    OpTally::take();
    tiletest::box_bounds<CD>(vs, n, u0, point ? u0 : u0 + 0.25, v0, point ? v0 : v0 + 0.25, a, b, c, d);
    return {OpTally::take(), tiletest::box_bounds_cost(vs, n, point)};
  });
  R.emplace("tile.lens_orientation", [](std::mt19937_64& g) -> Pair {
    RenderParams p;
    p.width = p.height = 512;
    p.coc_x_px = rndd(g, 0, 60);
    p.coc_y_px = -p.coc_x_px;
    p.focus_w = 5;
    const FrameConst fc = make_frame_const(p);
    const TriSetup t = random_setup(g, fc, false);
    OpTally::take();
    lens_orientation<CD>(t, fc);
    return {OpTally::take(), cost::kOrientation};
  });
  return true;
}();

}  // namespace
}  // namespace rast5d
