// SPDX-License-Identifier: BSD-3-Clause
// Fitting the vertices of a real marching-cubes patch (occupancy sphere, isosurface module)
// gives a surface within about half a voxel of the analytic sphere everywhere, and much
// closer on average: the fit smooths the staircase. The maximum sits at the apex, where
// the top terrace is a wide flat plateau that is itself up to h/2 off the sphere: no fit of
// those vertices can do better there, so the bound of the plain fit is 0.6 h, not 0.5 h.
// The band fit of the same vertices (each one the midpoint of a grid edge the true surface
// crosses) lifts that floor: it meets the half voxel, with a margin.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/nurbs/band_fit.h"
#include "nurbsfront/nurbs/mba.h"

namespace nurbsfront {
namespace {

// The upper cap (r_xy <= 0.65) of the marching-cubes surface of a unit occupancy sphere.
struct OccupancyCap {
  ScalarGrid grid;
  std::vector<Eigen::Vector3d> points;
};

OccupancyCap occupancy_cap(int resolution) {
  SphereScene sphere;
  sphere.radius = 1.0;
  OccupancyCap cap;
  cap.grid = sample_scene(sphere, resolution, SampleMode::Occupancy);
  const TriangleSoup soup = marching_cubes(cap.grid, scene_marching_cubes_options(SampleMode::Occupancy));
  for (const auto& p : soup.points) {
    if (p.z() > 0.0 && std::hypot(p.x(), p.y()) <= 0.65) cap.points.push_back(p);
  }
  return cap;
}

// Mean and max vertical distance of z = f(x, y) to the unit sphere over r_xy <= 0.5.
struct CapError {
  double mean = 0.0;
  double max = 0.0;
};

template <class F>
CapError cap_error(const F& f) {
  CapError e;
  int n = 0;
  for (double x = -0.5; x <= 0.5; x += 0.01) {
    for (double y = -0.5; y <= 0.5; y += 0.01) {
      if (std::hypot(x, y) > 0.5) continue;
      const double d = std::abs(f(x, y) - std::sqrt(1.0 - x * x - y * y));
      e.max = std::max(e.max, d);
      e.mean += d;
      ++n;
    }
  }
  e.mean /= n;
  return e;
}

TEST(MbaMarchingCubes, OccupancySphereCapIsFittedWithinHalfAVoxel) {
  const OccupancyCap cap = occupancy_cap(48);
  const double h = cap.grid.spacing.x();
  ASSERT_GT(cap.points.size(), 300u);
  FitOptions o;
  o.tolerance = 1e-9;
  o.min_spacing = 3.0 * h;
  const FitResult fit = fit_height_field(cap.points, o);
  const CapError e = cap_error([&](double x, double y) { return fit.field.value(x, y); });
  EXPECT_LT(e.max, 0.6 * h);
  EXPECT_LT(e.mean, 0.15 * h);
  // The raw vertices are farther off on average (vertical distance to the sphere).
  double raw_sum = 0.0;
  int raw_n = 0;
  for (const auto& p : cap.points) {
    if (std::hypot(p.x(), p.y()) > 0.5) continue;
    raw_sum += std::abs(p.z() - std::sqrt(1.0 - p.x() * p.x() - p.y() * p.y()));
    ++raw_n;
  }
  EXPECT_GT(raw_sum / raw_n, 1.5 * e.mean);
}

// Issue 3's bound, met with the band fit: every cap vertex with one coordinate at a
// half-integer lattice position (the midpoint of a grid edge between an inside and an
// outside cell centre) is a band of half a cell along that axis; the fit crosses the bands.
// At 32, 48 and 64 cells the top terrace lies h/2 below the apex (the plain fit's floor).
TEST(MbaMarchingCubes, OccupancySphereCapBandFitIsWithinHalfAVoxel) {
  for (const int resolution : {32, 48, 64}) {
    const OccupancyCap cap = occupancy_cap(resolution);
    const double h = cap.grid.spacing.x();
    std::vector<BandSample> samples;
    std::size_t n_bands = 0;
    for (const auto& p : cap.points) {
      BandSample s;
      s.point = p;
      const Eigen::Vector3d t = (p - cap.grid.origin) / h;
      for (int d = 0; d < 3; ++d) {
        if (std::abs(t[d] - std::floor(t[d]) - 0.5) < 1e-6) {
          s.direction = Eigen::Vector3d::Unit(d);
          s.half_length = 0.5 * h;
        }
      }
      n_bands += s.half_length > 0.0 ? 1 : 0;
      samples.push_back(s);
    }
    EXPECT_EQ(n_bands, samples.size());  // every occupancy vertex is an edge midpoint
    BandFitOptions o;
    o.spacing = 1.5 * h;
    const BandFitResult band = fit_height_field_to_bands(samples, o);
    FitOptions plain;
    plain.tolerance = 1e-9;
    plain.min_spacing = 3.0 * h;
    const FitResult fit = fit_height_field(cap.points, plain);
    const CapError eb = cap_error([&](double x, double y) { return band.field.value(x, y); });
    const CapError ep = cap_error([&](double x, double y) { return fit.field.value(x, y); });
    std::printf("occupancy sphere %d, cap: band fit mean %.3f max %.3f h; plain MBA mean %.3f max %.3f h\n", resolution,
                eb.mean / h, eb.max / h, ep.mean / h, ep.max / h);
    EXPECT_LT(eb.max, 0.5 * h) << resolution;
    EXPECT_LT(eb.mean, ep.mean) << resolution;
  }
}

}  // namespace
}  // namespace nurbsfront
