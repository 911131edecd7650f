// Sampled simulation (pipeline.sample_fraction, sim/sampling.py): per-bin auxiliary variables,
// known for every bin of the frame before any bin is traversed, that the regression estimator
// uses to predict the traversed work of the bins it did not draw.
//
// For each (triangle, bin) pair of the bin lists:
//   coverage: the area of the triangle at the lens centre inside the bin, times spp (what the
//             sample test hits, before depth);
//   footprint: the area of the triangle swept over the lens inside the bin, times spp (what a
//             conservative traversal has to consider): the Steiner area of the triangle
//             dilated by its vertices' mean circle-of-confusion radius (area + perimeter r + pi r^2);
//   edge:     the perimeter of the triangle at the lens centre, times spp, spread over its bins in
//             proportion to the share of its bounds each holds (the tiles and lens cells a traversal
//             tests but the triangle does not cover lie along its edges).
// A triangle whose lens-centre extent is larger than a bin is clipped to each bin exactly (its
// footprint as the triangle with every edge pushed out by the largest CoC radius); a smaller one
// is spread over its bins in proportion to the share of its bounds each bin holds. Moving,
// near-clipped and full-bounds triangles use their bounds' area for both and their bounds' perimeter
// for the edge. The values only steer
// the estimator's efficiency: any function of the frame known for every bin keeps it consistent,
// and the confidence interval comes from the residuals, so an approximation here widens the
// interval, it never biases it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "setup/setup.h"

namespace rast5d {

namespace bin_covariates_detail {

struct Pt {
  double x, y;
};

// Area of convex polygon p (n <= 3 vertices) inside [x0, x1) x [y0, y1): Sutherland-Hodgman.
inline double clipped_area(const Pt* p, int n, double x0, double y0, double x1, double y1) {
  Pt a[12], b[12];
  int na = n;
  for (int k = 0; k < n; ++k) a[k] = p[k];
  for (int side = 0; side < 4 && na > 0; ++side) {
    int nb = 0;
    for (int k = 0; k < na; ++k) {
      const Pt& s = a[k];
      const Pt& e = a[(k + 1) % na];
      auto dist = [&](const Pt& q) {
        switch (side) {
          case 0: return q.x - x0;
          case 1: return x1 - q.x;
          case 2: return q.y - y0;
          default: return y1 - q.y;
        }
      };
      const double ds = dist(s), de = dist(e);
      if (ds >= 0) b[nb++] = s;
      if ((ds >= 0) != (de >= 0)) {
        const double t = ds / (ds - de);
        b[nb++] = Pt{s.x + t * (e.x - s.x), s.y + t * (e.y - s.y)};
      }
    }
    na = nb;
    for (int k = 0; k < na; ++k) a[k] = b[k];
  }
  double s = 0;
  for (int k = 0; k < na; ++k) s += a[k].x * a[(k + 1) % na].y - a[(k + 1) % na].x * a[k].y;
  return std::abs(s) * 0.5;
}

}  // namespace bin_covariates_detail

// Per triangle: what the bins need of it (computed once, not per bin).
struct TriangleCovariates {
  double bounds = 0;          // pixels of its bounds
  double area = 0, foot = 0;  // lens-centre area and Steiner footprint (small triangles)
  double perim = 0;           // lens-centre perimeter
  bool clip = false;          // larger than a bin: clipped to each bin exactly
  bin_covariates_detail::Pt p[3], o[3];  // lens-centre and pushed-out triangles (clip only)
  bool o_ok = false;
};

inline TriangleCovariates triangle_covariates(const TriSetup& t, double B) {
  using bin_covariates_detail::Pt;
  TriangleCovariates c;
  c.bounds = static_cast<double>(t.bx1 - t.bx0) * (t.by1 - t.by0);
  if (t.moving || t.near_clipped || t.full_bounds || c.bounds <= 0) {
    c.area = c.foot = c.bounds;
    c.perim = 2.0 * ((t.bx1 - t.bx0) + (t.by1 - t.by0));
    return c;
  }
  double r[3];
  for (int j = 0; j < 3; ++j) {
    const double w = t.W[j];
    c.p[j] = Pt{t.X[j] / w, t.Y[j] / w};
    r[j] = std::max(std::abs(static_cast<double>(t.cx[j])), std::abs(static_cast<double>(t.cy[j]))) / std::abs(w);
  }
  const Pt* p = c.p;
  const double cross = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (p[1].y - p[0].y);
  c.area = std::abs(cross) * 0.5;
  const double ext_x = std::max({p[0].x, p[1].x, p[2].x}) - std::min({p[0].x, p[1].x, p[2].x});
  const double ext_y = std::max({p[0].y, p[1].y, p[2].y}) - std::min({p[0].y, p[1].y, p[2].y});
  double len[3];
  for (int j = 0; j < 3; ++j) {
    const double dx = p[(j + 1) % 3].x - p[j].x, dy = p[(j + 1) % 3].y - p[j].y;
    len[j] = std::sqrt(dx * dx + dy * dy);
  }
  c.perim = len[0] + len[1] + len[2];
  const double rm = (r[0] + r[1] + r[2]) / 3.0;
  c.foot = c.area + (len[0] + len[1] + len[2]) * rm + 3.141592653589793 * rm * rm;
  if ((ext_x > B || ext_y > B) && cross != 0) {
    // Clipped exactly: the lens-centre triangle, and the triangle with its edges pushed out by R.
    c.clip = true;
    const double R = std::max({r[0], r[1], r[2]});
    const double sg = cross > 0 ? 1.0 : -1.0;
    double nx[3], ny[3], off[3];
    c.o_ok = len[0] > 0 && len[1] > 0 && len[2] > 0;
    for (int j = 0; j < 3 && c.o_ok; ++j) {
      const Pt& a = p[j];
      const Pt& e = p[(j + 1) % 3];
      nx[j] = (e.y - a.y) * sg / len[j], ny[j] = -(e.x - a.x) * sg / len[j];
      off[j] = nx[j] * a.x + ny[j] * a.y + R;
    }
    for (int j = 0; j < 3 && c.o_ok; ++j) {  // vertex j: the pushed edges (j-1, j) and (j, j+1) meet
      const int k = (j + 2) % 3;
      const double det = nx[k] * ny[j] - nx[j] * ny[k];
      c.o[j] = det != 0 ? Pt{(off[k] * ny[j] - off[j] * ny[k]) / det, (nx[k] * off[j] - nx[j] * off[k]) / det} : p[j];
    }
  }
  return c;
}

// Auxiliaries per bin: coverage, footprint and edge (samples).
constexpr int kBinAux = 3;

// One bin's auxiliaries (pixels; before the factor spp).
struct BinAux {
  double cover = 0, foot = 0, edge = 0;
  // Writes the kBinAux values of bin b, times spp.
  void store(std::vector<double>& out, std::size_t b, int spp) const {
    out[kBinAux * b] = cover * spp;
    out[kBinAux * b + 1] = foot * spp;
    out[kBinAux * b + 2] = edge * spp;
  }
};

// Adds triangle t's terms (c = triangle_covariates(t, bin size)) to the auxiliaries of the bin
// [x0, x1) x [y0, y1).
inline void bin_covariate_terms(const TriSetup& t, const TriangleCovariates& c, double x0, double y0, double x1,
                                double y1, BinAux& a) {
  using bin_covariates_detail::clipped_area;
  const double share = (std::min<double>(t.bx1, x1) - std::max<double>(t.bx0, x0)) *
                       (std::min<double>(t.by1, y1) - std::max<double>(t.by0, y0)) / c.bounds;
  a.edge += share * c.perim;
  if (!c.clip) {
    a.cover += share * c.area, a.foot += share * c.foot;
    return;
  }
  a.cover += clipped_area(c.p, 3, x0, y0, x1, y1);
  a.foot += c.o_ok ? clipped_area(c.o, 3, x0, y0, x1, y1) : share * c.bounds;
}

// out: kBinAux values per bin, row-major bins.
inline void bin_covariates(const std::vector<TriSetup>& setups, const std::vector<std::vector<std::uint32_t>>& bin_lists,
                           int bins_x, int bin_size, int width, int height, int spp, std::vector<double>& out) {
  const int n_bins = static_cast<int>(bin_lists.size());
  out.assign(static_cast<std::size_t>(n_bins) * kBinAux, 0.0);
  const double B = bin_size;
  std::vector<TriangleCovariates> tri(setups.size());
  std::vector<char> done(setups.size(), 0);
  for (const auto& list : bin_lists)
    for (std::uint32_t i : list)
      if (!done[i]) tri[i] = triangle_covariates(setups[i], B), done[i] = 1;
  for (int b = 0; b < n_bins; ++b) {
    const int bx = b % bins_x, by = b / bins_x;
    const double x0 = bx * B, y0 = by * B, x1 = std::min<double>(width, x0 + B), y1 = std::min<double>(height, y0 + B);
    BinAux a;
    for (std::uint32_t i : bin_lists[b]) bin_covariate_terms(setups[i], tri[i], x0, y0, x1, y1, a);
    a.store(out, static_cast<std::size_t>(b), spp);
  }
}

}  // namespace rast5d
