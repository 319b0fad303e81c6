// SPDX-License-Identifier: BSD-3-Clause
// Fitting the vertices of a real marching-cubes patch (occupancy sphere, isosurface module)
// gives a surface within about half a voxel of the analytic sphere everywhere, and much
// closer on average: the fit smooths the staircase. The maximum sits at the apex, where
// the top terrace is a wide flat plateau that is itself up to h/2 off the sphere: no fit of
// those vertices can do better there, so the bound is 0.6 h, not 0.5 h.
#include <gtest/gtest.h>

#include <cmath>

#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/nurbs/mba.h"

namespace nurbsfront {
namespace {

TEST(MbaMarchingCubes, OccupancySphereCapIsFittedWithinHalfAVoxel) {
  SphereScene sphere;
  sphere.radius = 1.0;
  const ScalarGrid grid = sample_scene(sphere, 48, SampleMode::Occupancy);
  const TriangleSoup soup = marching_cubes(grid, scene_marching_cubes_options(SampleMode::Occupancy));
  const double h = grid.spacing.x();
  std::vector<Eigen::Vector3d> cap;
  for (const auto& p : soup.points) {
    if (p.z() > 0.0 && std::hypot(p.x(), p.y()) <= 0.65) cap.push_back(p);
  }
  ASSERT_GT(cap.size(), 300u);
  FitOptions o;
  o.tolerance = 1e-9;
  o.min_spacing = 3.0 * h;
  const FitResult fit = fit_height_field(cap, o);
  double max_err = 0.0;
  double sum_err = 0.0;
  int n = 0;
  for (double x = -0.5; x <= 0.5; x += 0.01) {
    for (double y = -0.5; y <= 0.5; y += 0.01) {
      if (std::hypot(x, y) > 0.5) continue;
      const double e = std::abs(fit.field.value(x, y) - std::sqrt(1.0 - x * x - y * y));
      max_err = std::max(max_err, e);
      sum_err += e;
      ++n;
    }
  }
  EXPECT_LT(max_err, 0.6 * h);
  EXPECT_LT(sum_err / n, 0.15 * h);
  // The raw vertices are farther off on average (vertical distance to the sphere).
  double raw_sum = 0.0;
  int raw_n = 0;
  for (const auto& p : cap) {
    if (std::hypot(p.x(), p.y()) > 0.5) continue;
    raw_sum += std::abs(p.z() - std::sqrt(1.0 - p.x() * p.x() - p.y() * p.y()));
    ++raw_n;
  }
  EXPECT_GT(raw_sum / raw_n, 1.5 * sum_err / n);
}

}  // namespace
}  // namespace nurbsfront
