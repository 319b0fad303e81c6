// SPDX-License-Identifier: BSD-3-Clause
// fit_height_field_to_bands(): exact reproduction of planes and quadrics, band crossing,
// and the point of it: a terraced (0/1 voxel) sphere cap is recovered much better than by
// the plain fit of its vertices, the flat top terrace included.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <numbers>
#include <random>

#include "nurbsfront/core/error.h"
#include "nurbsfront/nurbs/band_fit.h"
#include "nurbsfront/nurbs/mba.h"

namespace nurbsfront {
namespace {

using Height = std::function<double(double, double)>;

// Samples of z = g(x, y) on a jittered grid, each with a band in a random direction.
std::vector<BandSample> exact_samples(const Height& g, int n, double half_length, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<BandSample> out;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x = (i + 0.3 * unit(rng)) / n;
      const double y = (j + 0.3 * unit(rng)) / n;
      BandSample s;
      s.point = {x, y, g(x, y)};
      // Slanted up to 63 deg from z, so every band crosses the surface well inside its ends.
      s.direction = Eigen::Vector3d(unit(rng), unit(rng), 1.0).normalized();
      s.half_length = (i + j) % 3 == 0 ? 0.0 : half_length;  // some plain points too
      out.push_back(s);
    }
  return out;
}

TEST(BandFit, ReproducesPlanesAndQuadricsThroughTheCentres) {
  const std::vector<Height> exact{
      [](double x, double y) { return 0.3 * x - 0.2 * y + 1.0; },
      [](double x, double y) { return 0.5 * x * x - 0.7 * x * y + 0.2 * y * y + 0.1 * x; },
  };
  for (const auto& g : exact) {
    const auto samples = exact_samples(g, 20, 0.02, 7);
    // Weak and strong smoothing: the third-difference penalty leaves quadrics alone (the
    // strong one makes the system stiff: round-off grows to about 1e-9).
    for (const double length : {0.05, 0.4}) {
      BandFitOptions o;
      o.spacing = 0.1;
      o.smoothing_length = length;
      const BandFitResult r = fit_height_field_to_bands(samples, o);
      EXPECT_TRUE(r.converged);
      EXPECT_EQ(r.n_missed, 0u);
      EXPECT_LT(r.max_point_residual, 1e-7);
      for (double x = 0.05; x < 0.95; x += 0.05)
        for (double y = 0.05; y < 0.95; y += 0.05) EXPECT_NEAR(r.field.value(x, y), g(x, y), 1e-7);
    }
  }
}

TEST(BandFit, PlaneInsideItsBandsIsCrossedByEveryBand) {
  // Centres scattered up to 0.9 half-lengths off the plane along their (vertical or
  // slanted) bands: the plane crosses every band, so the fit must too.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto plane = [](double x, double y) { return 0.2 * x + 0.1 * y; };
  std::vector<BandSample> samples;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) {
      BandSample s;
      const double x = (i + 0.5) / 30.0;
      const double y = (j + 0.5) / 30.0;
      s.direction = Eigen::Vector3d(0.3 * unit(rng), 0.3 * unit(rng), 1.0).normalized();
      s.half_length = 0.02;
      s.point = Eigen::Vector3d(x, y, plane(x, y)) + 0.9 * unit(rng) * s.half_length * s.direction;
      samples.push_back(s);
    }
  // Without the pull towards the (scattered) centres, the objective is convex and the plane
  // makes it 0 (every band crossed, no third derivative): a converged fit crosses every band.
  BandFitOptions o;
  o.spacing = 0.05;
  o.centre_weight = 0.0;
  const BandFitResult r = fit_height_field_to_bands(samples, o);
  // Slanted bands make the objective only nearly exact (vertical residual at the nearer
  // end): a few bands stay missed by a small fraction of their half-length.
  EXPECT_LE(r.max_miss, 0.05 * 0.02);
  for (const auto& s : samples) EXPECT_NEAR(r.field.value(s.point.x(), s.point.y()), plane(s.point.x(), s.point.y()), 0.02);
  double worst = 0.0;
  for (const auto& s : samples) {
    Eigen::Vector3d target;
    const bool crossed = band_target(r.field, s, target);
    worst = std::max(worst, crossed ? 0.0 : std::abs(target.z() - r.field.value(target.x(), target.y())));
    if (crossed) {
      EXPECT_NEAR(target.z(), r.field.value(target.x(), target.y()), 1e-9);
      EXPECT_LE((target - s.point).norm(), s.half_length * (1.0 + 1e-12));
    }
  }
  EXPECT_LE(worst, 0.05 * 0.02);
}

// The marching-cubes vertices of a 0/1 occupancy grid (voxel centres at (i, j, k) h + offset,
// iso 0.5) on the top cap of the ball |p| <= radius, with their bands: the grid edge
// between the inside and the outside voxel centre (half-length h / 2 along its axis).
std::vector<BandSample> occupancy_cap(double radius, double h, double z_offset, double cap_radius) {
  const int n = static_cast<int>(std::ceil(cap_radius / h)) + 1;
  const auto top = [&](int i, int j) {  // highest inside level of column (i, j)
    const double r2 = radius * radius - (i * h) * (i * h) - (j * h) * (j * h);
    return static_cast<int>(std::floor((std::sqrt(r2) - z_offset) / h));
  };
  const auto in_cap = [&](int i, int j) { return std::hypot(i * h, j * h) <= cap_radius; };
  std::vector<BandSample> out;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) {
      if (!in_cap(i, j)) continue;
      const int k = top(i, j);
      out.push_back({{i * h, j * h, (k + 0.5) * h + z_offset}, Eigen::Vector3d::UnitZ(), 0.5 * h});
      for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{0, 1}}) {
        if (!in_cap(i + di, j + dj)) continue;
        const int k2 = top(i + di, j + dj);
        const Eigen::Vector3d axis(di, dj, 0.0);
        for (int level = std::min(k, k2) + 1; level <= std::max(k, k2); ++level)
          out.push_back({{(i + 0.5 * di) * h, (j + 0.5 * dj) * h, level * h + z_offset}, axis, 0.5 * h});
      }
    }
  return out;
}

struct CapError {
  double mean = 0.0;
  double max = 0.0;
};

CapError cap_error(const Height& f, double radius, double r_max) {
  CapError e;
  int n = 0;
  for (double x = -r_max; x <= r_max; x += 0.01 * radius)
    for (double y = -r_max; y <= r_max; y += 0.01 * radius) {
      if (std::hypot(x, y) > r_max) continue;
      const double d = std::abs(f(x, y) - std::sqrt(radius * radius - x * x - y * y));
      e.mean += d;
      e.max = std::max(e.max, d);
      ++n;
    }
  e.mean /= n;
  return e;
}

TEST(BandFit, TerracedSphereCapBeatsThePlainFit) {
  const double radius = 1.0;
  const double h = radius / 48.0;  // a 96-voxel sphere
  // Offsets putting the top terrace at different heights below the apex (0.5 h below: the
  // worst case of the plain fit).
  for (const double offset : {0.0, 0.25 * h, 0.5 * h}) {
    const auto samples = occupancy_cap(radius, h, offset, 0.7 * radius);
    std::vector<Eigen::Vector3d> points;
    for (const auto& s : samples) points.push_back(s.point);
    FitOptions plain;
    plain.tolerance = 0.05 * 0.6 * h;
    plain.min_spacing = 2.5 * 0.6 * h;  // the surfmesh defaults in a voxel's mean edge
    const FitResult p = fit_height_field(points, plain);
    BandFitOptions o;
    o.spacing = 1.5 * h;
    const BandFitResult b = fit_height_field_to_bands(samples, o);
    const CapError ep = cap_error([&](double x, double y) { return p.field.value(x, y); }, radius, 0.6 * radius);
    const CapError eb = cap_error([&](double x, double y) { return b.field.value(x, y); }, radius, 0.6 * radius);
    std::printf("offset %.2f h: plain mean %.3f max %.3f h; band mean %.3f max %.3f h (%d iterations, %s, missed %zu of %zu, max miss %.3f h)\n",
                offset / h, ep.mean / h, ep.max / h, eb.mean / h, eb.max / h, b.iterations, b.converged ? "converged" : "not converged",
                b.n_missed, b.n_bands, b.max_miss / h);
    EXPECT_LT(eb.max, 0.25 * h);
    EXPECT_LT(eb.mean, 0.5 * ep.mean);
  }
}

// A height field's third derivatives grow with the slope even where the curvature is
// constant, so the plain third-derivative prior flattens a cylinder or a sphere of radius 12
// lattice units seen up to 60 deg (0.30 / 0.33 max error at smoothing length 2.25); the
// curvature pass pulls the prior towards the third derivatives of a surface with a parallel
// second fundamental form, which both have.
TEST(BandFit, CurvaturePassRemovesTheSlopeBiasOfThePrior) {
  const double radius = 12.0;
  const double reach = radius * std::sin(std::numbers::pi / 3.0);
  for (const bool sphere : {false, true}) {
    auto r2 = [&](double x, double y) { return sphere ? x * x + y * y : x * x; };
    std::vector<BandSample> samples;
    for (double x = -reach; x <= reach; x += 0.5)
      for (double y = -reach; y <= reach; y += 0.5) {
        if (r2(x, y) > reach * reach) continue;
        BandSample s;
        s.point = {x, y, std::sqrt(radius * radius - r2(x, y))};
        samples.push_back(s);
      }
    double max_error[2] = {0.0, 0.0};
    for (const int passes : {0, 1}) {
      BandFitOptions o;
      o.spacing = 1.5;
      o.smoothing_length = 2.25;
      o.curvature_passes = passes;
      const BandFitResult r = fit_height_field_to_bands(samples, o);
      EXPECT_TRUE(r.converged);
      for (const auto& s : samples)
        max_error[passes] = std::max(max_error[passes], std::abs(r.field.value(s.point.x(), s.point.y()) - s.point.z()));
    }
    EXPECT_GT(max_error[0], 0.25) << (sphere ? "sphere" : "cylinder");  // the bias this removes
    EXPECT_LT(max_error[1], 0.6 * max_error[0]) << (sphere ? "sphere" : "cylinder");
  }
}

TEST(BandFit, BadInput) {
  BandFitOptions o;
  o.spacing = 0.1;
  std::vector<BandSample> samples{{{0, 0, 0}, {0, 0, 1}, 0.1}, {{1, 0, 0}, {0, 0, 1}, 0.1}, {{0, 1, 0}, {0, 0, 1}, 0.1}};
  EXPECT_NO_THROW((void)fit_height_field_to_bands(samples, o));
  auto bad = samples;
  bad[1].direction = {0, 0, 2};
  EXPECT_THROW((void)fit_height_field_to_bands(bad, o), InvalidInput);
  bad = samples;
  bad[2].point.x() = std::nan("");
  EXPECT_THROW((void)fit_height_field_to_bands(bad, o), InvalidInput);
  bad = samples;
  bad[2].point = {2, 0, 0};  // collinear
  EXPECT_THROW((void)fit_height_field_to_bands(bad, o), InvalidInput);
  bad = samples;
  bad[0].half_length = -1.0;
  EXPECT_THROW((void)fit_height_field_to_bands(bad, o), InvalidInput);
  EXPECT_THROW((void)fit_height_field_to_bands({samples[0], samples[1]}, o), InvalidInput);
  BandFitOptions spoiled = o;
  spoiled.spacing = 0.0;
  EXPECT_THROW((void)fit_height_field_to_bands(samples, spoiled), InvalidInput);
  spoiled = o;
  spoiled.centre_weight = 2.0;
  EXPECT_THROW((void)fit_height_field_to_bands(samples, spoiled), InvalidInput);
  spoiled = o;
  spoiled.max_iterations = 0;
  EXPECT_THROW((void)fit_height_field_to_bands(samples, spoiled), InvalidInput);
  spoiled = o;
  spoiled.curvature_passes = -1;
  EXPECT_THROW((void)fit_height_field_to_bands(samples, spoiled), InvalidInput);
  spoiled.curvature_passes = 11;
  EXPECT_THROW((void)fit_height_field_to_bands(samples, spoiled), InvalidInput);
  spoiled = o;
  const BicubicHeightField empty;
  spoiled.start = &empty;
  EXPECT_THROW((void)fit_height_field_to_bands(samples, spoiled), InvalidInput);
  BicubicHeightField spoiled_start(Rectangle{}, 2, 2);
  spoiled_start.set_coefficient(0, 0, std::numeric_limits<double>::quiet_NaN());
  spoiled.start = &spoiled_start;
  EXPECT_THROW((void)fit_height_field_to_bands(samples, spoiled), InvalidInput);
  spoiled = o;
  spoiled.skip_passes_max_miss = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((void)fit_height_field_to_bands(samples, spoiled), InvalidInput);
}

// The objective is convex: a fit started from another field (here the fit of the inner part
// of the samples, on its own smaller lattice, sampled onto the full one) reaches the same
// field as the fit from scratch, curvature pass included. The terraced cap has missed bands,
// so the active set is exercised.
TEST(BandFit, WarmStartReachesTheSameFit) {
  const double radius = 1.0;
  const double h = radius / 24.0;
  const auto samples = occupancy_cap(radius, h, 0.5 * h, 0.6 * radius);
  const auto inner = occupancy_cap(radius, h, 0.5 * h, 0.4 * radius);
  BandFitOptions o;
  o.spacing = 1.5 * h;
  o.curvature_passes = 1;
  const BandFitResult cold = fit_height_field_to_bands(samples, o);
  const BandFitResult first = fit_height_field_to_bands(inner, o);
  BandFitOptions warm_options = o;
  warm_options.start = &first.field;
  const BandFitResult warm = fit_height_field_to_bands(samples, warm_options);
  EXPECT_GT(cold.n_missed, 0u);
  EXPECT_EQ(warm.n_missed, cold.n_missed);
  EXPECT_EQ(warm.passes, 1);
  double worst = 0.0;
  for (const auto& s : samples)
    worst = std::max(worst, std::abs(warm.field.value(s.point.x(), s.point.y()) - cold.field.value(s.point.x(), s.point.y())));
  EXPECT_LT(worst, 1e-6 * h);
  // From the fit itself (the quasi-interpolant reproduces it on the same lattice), the
  // descent has nothing to do: one solve to confirm each stage.
  warm_options.curvature_passes = 0;
  o.curvature_passes = 0;
  const BandFitResult base = fit_height_field_to_bands(samples, o);
  warm_options.start = &base.field;
  EXPECT_EQ(fit_height_field_to_bands(samples, warm_options).iterations, 1);
}

// skip_passes_max_miss returns the fit before the curvature passes when it meets its bands
// within the bound, and runs them otherwise.
TEST(BandFit, SkipPassesWhenTheBandsAreMet) {
  const double h = 1.0 / 24.0;
  const auto samples = occupancy_cap(1.0, h, 0.5 * h, 0.6);
  BandFitOptions o;
  o.spacing = 1.5 * h;
  o.curvature_passes = 0;
  const BandFitResult base = fit_height_field_to_bands(samples, o);
  ASSERT_GT(base.max_miss, 0.0);
  o.curvature_passes = 1;
  o.skip_passes_max_miss = base.max_miss;
  const BandFitResult skipped = fit_height_field_to_bands(samples, o);
  EXPECT_EQ(skipped.passes, 0);
  EXPECT_EQ(skipped.field.coefficients(), base.field.coefficients());
  EXPECT_EQ(skipped.max_miss, base.max_miss);
  o.skip_passes_max_miss = 0.5 * base.max_miss;
  EXPECT_EQ(fit_height_field_to_bands(samples, o).passes, 1);
  o.skip_passes_max_miss = -1.0;
  EXPECT_EQ(fit_height_field_to_bands(samples, o).passes, 1);
}

}  // namespace
}  // namespace nurbsfront
