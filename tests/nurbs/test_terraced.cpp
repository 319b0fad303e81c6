// SPDX-License-Identifier: BSD-3-Clause
// The fit must average a staircase, not chase it (DESIGN.md pitfalls): fitting the
// vertices of a 0/1 voxel surface gives a surface within half a voxel of the true one.
#include <gtest/gtest.h>

#include <cmath>

#include "nurbsfront/nurbs/mba.h"

namespace nurbsfront {
namespace {

// The vertices marching cubes produces on a 0/1 occupancy grid (grid points = voxel
// centres at integer multiples of h, iso 0.5: every vertex is the midpoint of a grid edge
// between an inside and an outside point) for the top cap of the ball |p| <= radius.
std::vector<Eigen::Vector3d> staircase_cap(double radius, double h, double cap_radius) {
  const int n = static_cast<int>(std::ceil(cap_radius / h)) + 1;
  const auto top = [&](int i, int j) {  // highest inside grid level of column (i, j)
    const double r2 = radius * radius - (i * h) * (i * h) - (j * h) * (j * h);
    return static_cast<int>(std::floor(std::sqrt(r2) / h));
  };
  const auto in_cap = [&](int i, int j) { return std::hypot(i * h, j * h) <= cap_radius; };
  std::vector<Eigen::Vector3d> pts;
  for (int i = -n; i <= n; ++i) {
    for (int j = -n; j <= n; ++j) {
      if (!in_cap(i, j)) continue;
      const int k = top(i, j);
      pts.emplace_back(i * h, j * h, (k + 0.5) * h);  // vertical edge crossing
      for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{0, 1}}) {
        if (!in_cap(i + di, j + dj)) continue;
        const int k2 = top(i + di, j + dj);
        for (int level = std::min(k, k2) + 1; level <= std::max(k, k2); ++level) {
          pts.emplace_back((i + 0.5 * di) * h, (j + 0.5 * dj) * h, level * h);  // riser
        }
      }
    }
  }
  return pts;
}

TEST(MbaTerraced, VoxelStaircaseIsSmoothedToWithinHalfAVoxel) {
  const double radius = 1.0;
  const double h = radius / 24.0;  // a 48-voxel sphere
  const auto pts = staircase_cap(radius, h, 0.65 * radius);
  ASSERT_GT(pts.size(), 500u);
  // The staircase itself is up to half a voxel off, and terraced.
  FitOptions o;
  o.tolerance = 1e-9 * radius;  // residual-driven refinement alone would chase the steps...
  o.min_spacing = 3.0 * h;      // ...so the finest lattice is capped at three voxels.
  const FitResult fit = fit_height_field(pts, o);
  EXPECT_EQ(fit.stop, FitStop::kSpacingLimit);
  double max_err = 0.0;
  double sum_err = 0.0;
  int n = 0;
  for (double x = -0.5; x <= 0.5; x += 0.01) {
    for (double y = -0.5; y <= 0.5; y += 0.01) {
      if (std::hypot(x, y) > 0.5 * radius) continue;
      const double e = std::abs(fit.field.value(x, y) - std::sqrt(radius * radius - x * x - y * y));
      max_err = std::max(max_err, e);
      sum_err += e;
      ++n;
    }
  }
  EXPECT_LT(max_err, 0.5 * h);
  EXPECT_LT(sum_err / n, 0.25 * h);
  // Without the cap the fit follows the steps: much rougher slopes (the terraces come back).
  FitOptions chase = o;
  chase.min_spacing = 0.0;
  chase.max_levels = 10;
  const FitResult rough = fit_height_field(pts, chase);
  const auto slope_error = [&](const BicubicHeightField& f) {
    double worst = 0.0;
    for (double x = -0.4; x <= 0.4; x += 0.0037) {
      const double y = 0.1;
      const double zt = std::sqrt(radius * radius - x * x - y * y);
      const Eigen::Vector2d g = f.gradient(x, y);
      worst = std::max(worst, std::abs(g.x() - (-x / zt)));
    }
    return worst;
  };
  EXPECT_LT(slope_error(fit.field), 0.1);
  EXPECT_GT(slope_error(rough.field), 2.0 * slope_error(fit.field));
}

}  // namespace
}  // namespace nurbsfront
