// Per-triangle tile-test setup shared by the tile-based algorithms (tile, tile_interleaved, laine):
// the lens projection of the footprint vertices (h_i lines), the triangle's orientation over the
// lens, the per-edge H_j constants and the selective-H oracle ([Akenine-Möller 2012] Appendix A).
//
// Contract: the footprint's lens vertices bound the triangle's projection from every lens point
// (and, for a moving triangle, every time), so the h_i and H_j lines built on them are
// conservative (tiletest/common.h).
#pragma once

#include <algorithm>
#include <cmath>

#include "core/costs.h"
#include "sampletest/hardware.h"
#include "setup/setup.h"
#include "tiletest/halfspace_edges.h"
#include "tiletest/halfspace_lens.h"
#include "tiletest/lens_vertex.h"

namespace rast5d {

struct Footprint {
  // Vertices whose lens projections bound the triangle: the static footprint polygon (3 or 4), or
  // the 6 shutter-end vertices of a moving triangle (h_i lines only), all with W > 0.
  int n = 0;
  tiletest::LensVertex lv[6];
  double P[6][3];
  bool h_valid = false;  // false: moving and may cross the near plane (no tile test possible)
  // H_j lines (static triangles only).
  int sigma = 0;         // orientation over the lens, 0 if it changes sign over the lens square
  // When sigma == 0: the lens cells where the orientation det(u, v) is surely positive / negative.
  tiletest::CellMask orient_pos, orient_neg;
  int n_edges = 0;
  tiletest::EdgeH edges[4];
  int edges_enabled = 0, edges_disabled = 0;
};

// Determinant of three columns (9 ops: cross product 6, dot 3).
template <class D>
inline D det3_columns(const D a[3], const D b[3], const D c[3]) {
  // rows are vertices; columns a, b, c: det = a . (b x c) over the vertex index
  const D x0 = madd(b[1], c[2], -(b[2] * c[1]));
  const D x1 = madd(b[2], c[0], -(b[0] * c[2]));
  const D x2 = madd(b[0], c[1], -(b[1] * c[0]));
  return madd(a[0], x0, madd(a[1], x1, a[2] * x2));
}

// Orientation of the (static) triangle seen from lens point (u, v): det(u, v) = D0 + u Du + v Dv
// (the u v term vanishes), the sign of the sample test's determinant. Returns +1/-1 if the sign is
// clearly the same at all four lens-square corners, else 0; `line` receives det as a lens line and
// `thr` the threshold below which its sign is not trusted. Cost: cost::kOrientation.
template <class D>
inline int lens_orientation(const TriSetup& tri, const FrameConst& fc, tiletest::Line* line = nullptr,
                            double* thr_out = nullptr) {
  D X[3], Y[3], W[3], one[3];
  for (int j = 0; j < 3; ++j) X[j] = D(tri.X[j]), Y[j] = D(tri.Y[j]), W[j] = D(tri.W[j]), one[j] = D(1.0);
  const D d0 = det3_columns(X, Y, W);
  const D du = det3_columns(one, Y, W) * D(-(fc.kx_d * fc.focus_d));
  const D dv = det3_columns(X, one, W) * D(-(fc.ky_d * fc.focus_d));
  const double scale = std::fabs(raw(d0)) + std::fabs(raw(du)) + std::fabs(raw(dv));
  const double thr = 1e-9 * scale;
  if (line) *line = tiletest::Line{raw(du), raw(dv), raw(d0)};
  if (thr_out) *thr_out = thr;
  int pos = 0, neg = 0;
  for (int k = 0; k < 4; ++k) {
    const D su = (k & 1) ? du : -du, sv = (k & 2) ? dv : -dv;
    const D val = d0 + su + sv;
    const bool p = val > D(thr);
    const bool q = val < D(-thr);
    pos += p, neg += q;
  }
  return pos == 4 ? 1 : (neg == 4 ? -1 : 0);
}

// Build the footprint. Operations go to `ops` (the caller charges them to ops.setup only in the
// triangle's first bin). with_H: also set up H_j lines and the oracle.
template <class A>
inline Footprint build_footprint(const TriSetup& tri, const Frame& f, bool with_H, std::uint64_t& ops) {
  using D = typename A::f64;
  const FrameConst& fc = f.fc;
  const RenderParams& p = f.p;
  Footprint fp;
  const D neg_f(-fc.focus_d), kx(fc.kx_d), ky(fc.ky_d);
  auto add_vertex = [&](double X, double Y, double W) {
    fp.P[fp.n][0] = X, fp.P[fp.n][1] = Y, fp.P[fp.n][2] = W;
    fp.lv[fp.n] = tiletest::lens_vertex(D(X), D(Y), D(W), neg_f, kx, ky);
    charge<A>(ops, tiletest::lens_vertex_cost(fp.lv[fp.n]));
    ++fp.n;
  };
  if (!tri.moving) {
    for (int j = 0; j < tri.poly_n; ++j) add_vertex(tri.poly[j][0], tri.poly[j][1], tri.poly[j][2]);
    fp.h_valid = true;
  } else if (!tri.full_bounds) {
    for (int e = 0; e < 2; ++e)
      for (int j = 0; j < 3; ++j)
        add_vertex(static_cast<double>(tri.X[j]) + (e ? static_cast<double>(tri.dX[j]) : 0.0),
                   static_cast<double>(tri.Y[j]) + (e ? static_cast<double>(tri.dY[j]) : 0.0),
                   static_cast<double>(tri.W[j]) + (e ? static_cast<double>(tri.dW[j]) : 0.0));
    fp.h_valid = true;
  }
  if (!with_H || tri.moving) return fp;

  tiletest::Line orient;
  double thr;
  fp.sigma = lens_orientation<D>(tri, fc, &orient, &thr);
  charge<A>(ops, cost::kOrientation);
  if (fp.sigma == 0) {
    // The lens sees the triangle edge-on somewhere: cull with H_j only in lens cells where the
    // orientation has one sign (cells where it is ~0 see a sliver and are left to the sample test).
    const int Gc = p.lens_grid;
    fp.orient_pos = tiletest::line_cells<D>(tiletest::Line{-orient.A, -orient.B, thr - orient.C}, Gc, 0, Gc - 1, 0, Gc - 1);
    fp.orient_neg = tiletest::line_cells<D>(tiletest::Line{orient.A, orient.B, orient.C + thr}, Gc, 0, Gc - 1, 0, Gc - 1);
    charge<A>(ops, 2 * tiletest::line_cells_cost(Gc, Gc));
  }
  // Selective H_j oracle ([Akenine-Möller 2012] Appendix A): N_samples * C_sample < N_tiles * C_tile disables.
  const int T = p.tile_size, G = p.lens_grid;
  const double n_tiles = static_cast<double>((tri.bx1 - 1) / T - tri.bx0 / T + 1) *
                         static_cast<double>((tri.by1 - 1) / T - tri.by0 / T + 1);
  const double c_sample = p.c_sample >= 0 ? p.c_sample : static_cast<double>(sample_test_cost(p.cost_model, DimClass::k4D));
  const double c_tile = p.c_tile >= 0 ? p.c_tile
                                      : static_cast<double>(cost::kTangentCorners +
                                                            2 * (cost::kLineAtCorner + tiletest::line_cells_cost(G, G)));
  D tile_budget(0.0);
  if (p.selective_H) {
    tile_budget = D(n_tiles) * D(c_tile);
    charge<A>(ops, cost::kOracleBudget);
  }
  const double spp = f.table.spp();
  fp.n_edges = fp.n;
  for (int i = 0; i < fp.n; ++i) {
    const int k = (i + 1) % fp.n;
    fp.edges[i] = tiletest::edge_setup(fp.P[i], fp.P[k], D(fc.focus_d), kx, ky);
    charge<A>(ops, fp.edges[i].parallel ? cost::kEdgeSetupParallel : cost::kEdgeSetup);
    if (!fp.edges[i].active) continue;
    if (p.selective_H) {
      const tiletest::LensVertex &a = fp.lv[i], &b = fp.lv[k];
      D n_samples;
      if (p.oracle != OracleMode::kFull) {  // Eq. 15: N = R_S / 2 |X_q - X_p| |Y_q - Y_p|
        const D dx = D(b.ax) - D(a.ax), dy = D(b.ay) - D(a.ay);
        n_samples = (vabs(dx) * vabs(dy)) * D(0.5 * spp);
      } else {  // Eq. 9-12: N = R_S / 8 F(a, b) F(c, d)
        const D da = D(b.ax) - D(a.ax), db = D(b.bx) - D(a.bx);
        const D dc = D(b.ay) - D(a.ay), dd = D(b.by) - D(a.by);
        auto Ffun = [](D x, D y) {
          const bool big = vabs(x) >= vabs(y);
          const D f1 = vabs(x) * D(2.0);
          const D f2 = madd(x * x, rcp(vabs(y)), vabs(y));
          return big ? f1 : f2;
        };
        n_samples = (Ffun(da, db) * Ffun(dc, dd)) * D(spp / 8.0);
      }
      const bool keep = !(n_samples * D(c_sample) < tile_budget);
      charge<A>(ops, p.oracle == OracleMode::kFull ? cost::kOracleFull : cost::kOracleSimplified);
      if (!keep) {
        fp.edges[i].active = false;
        ++fp.edges_disabled;
        continue;
      }
    }
    ++fp.edges_enabled;
  }
  return fp;
}

// The h_i sets of one tile from the footprint's lens vertices (tiletest/halfspace_lens.h).
template <class A>
inline bool tile_h_sets(const Footprint& fp, double x0, double x1, double y0, double y1,
                        tiletest::AxisSet& sx, tiletest::AxisSet& sy, std::uint64_t& ops) {
  return tiletest::tile_h_sets<A>(fp.lv, fp.n, x0, x1, y0, y1, sx, sy, ops);
}

}  // namespace rast5d
