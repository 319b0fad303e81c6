// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

#include "fixtures/shapes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront {
namespace {

using V = Eigen::Vector3d;
constexpr double kTight = 1e-12;

TEST(QualityMetrics, EquilateralTriangleHasAlphaOne) {
  const V a(0, 0, 0), b(1, 0, 0), c(0.5, std::sqrt(3.0) / 2.0, 0);
  EXPECT_NEAR(triangle_alpha(a, b, c), 1.0, kTight);
  // Invariant under rotation, scaling and translation.
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, V(1, 2, 3).normalized()).toRotationMatrix();
  const V t(5, -3, 2);
  EXPECT_NEAR(triangle_alpha(3.0 * rot * a + t, 3.0 * rot * b + t, 3.0 * rot * c + t), 1.0, kTight);
  for (double angle : triangle_angles_deg(a, b, c)) EXPECT_NEAR(angle, 60.0, 1e-10);
}

TEST(QualityMetrics, RightIsoscelesTriangle) {
  // alpha = 4 sqrt(3) * 0.5 / (1 + 1 + 2) = sqrt(3) / 2.
  const V a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_NEAR(triangle_alpha(a, b, c), std::sqrt(3.0) / 2.0, kTight);
  const auto angles = triangle_angles_deg(a, b, c);
  EXPECT_NEAR(angles[0], 90.0, 1e-10);
  EXPECT_NEAR(angles[1], 45.0, 1e-10);
  EXPECT_NEAR(angles[2], 45.0, 1e-10);
}

TEST(QualityMetrics, ThirtySixtyNinetyTriangle) {
  // Legs 1 and sqrt(3), hypotenuse 2: A = sqrt(3)/2, sum of squares 1 + 3 + 4 = 8,
  // alpha = 4 sqrt(3) (sqrt(3)/2) / 8 = 3/4.
  const V a(0, 0, 0), b(std::sqrt(3.0), 0, 0), c(0, 1, 0);
  EXPECT_NEAR(triangle_alpha(a, b, c), 0.75, kTight);
  const auto angles = triangle_angles_deg(a, b, c);
  EXPECT_NEAR(angles[0], 90.0, 1e-10);
  EXPECT_NEAR(angles[1], 30.0, 1e-10);
  EXPECT_NEAR(angles[2], 60.0, 1e-10);
}

TEST(QualityMetrics, DegenerateTrianglesHaveAlphaZero) {
  EXPECT_EQ(triangle_alpha(V(0, 0, 0), V(1, 0, 0), V(2, 0, 0)), 0.0);  // collinear
  EXPECT_EQ(triangle_alpha(V(1, 1, 1), V(1, 1, 1), V(1, 1, 1)), 0.0);  // one point
  EXPECT_EQ(triangle_alpha(V(0, 0, 0), V(0, 0, 0), V(1, 0, 0)), 0.0);  // repeated corner
  const auto angles = triangle_angles_deg(V(0, 0, 0), V(1, 0, 0), V(2, 0, 0));
  EXPECT_NEAR(angles[0], 0.0, 1e-12);
  EXPECT_NEAR(angles[1], 180.0, 1e-12);
  EXPECT_NEAR(angles[2], 0.0, 1e-12);
}

TEST(QualityMetrics, AnglesSumTo180) {
  const V a(0.3, -1.2, 2.0), b(4.0, 0.1, -0.5), c(-1.0, 2.2, 0.7);
  const auto angles = triangle_angles_deg(a, b, c);
  EXPECT_NEAR(angles[0] + angles[1] + angles[2], 180.0, 1e-10);
  const double alpha = triangle_alpha(a, b, c);
  EXPECT_GT(alpha, 0.0);
  EXPECT_LT(alpha, 1.0);
}

TEST(QualityMetrics, RegularTetrahedronHasGammaOne) {
  const auto tet = test::tetrahedron();
  EXPECT_NEAR(tetrahedron_gamma(tet.points[0], tet.points[1], tet.points[2], tet.points[3]), 1.0, kTight);
  // Orientation does not matter; a flat tetrahedron has 0.
  EXPECT_NEAR(tetrahedron_gamma(tet.points[1], tet.points[0], tet.points[2], tet.points[3]), 1.0, kTight);
  EXPECT_EQ(tetrahedron_gamma(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(1, 1, 0)), 0.0);
  // Corner tetrahedron (0, e1, e2, e3): V = 1/6, sum of squares = 3 + 3 * 2 = 9,
  // gamma = 72 sqrt(3) / 6 / 27 = 4 sqrt(3) / 9.
  EXPECT_NEAR(tetrahedron_gamma(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0, 0, 1)), 4.0 * std::sqrt(3.0) / 9.0, kTight);
}

TEST(QualityMetrics, FaceAlphaAndMinAngle) {
  const auto cube = test::cube();
  const auto alpha = face_alpha(cube);
  const auto min_angle = face_min_angle_deg(cube);
  ASSERT_EQ(alpha.size(), 12u);
  ASSERT_EQ(min_angle.size(), 12u);
  for (double x : alpha) EXPECT_NEAR(x, std::sqrt(3.0) / 2.0, kTight);
  for (double x : min_angle) EXPECT_NEAR(x, 45.0, 1e-10);
  TriangleSoup bad = cube;
  bad.triangles[3][1] = 99;
  EXPECT_THROW((void)face_alpha(bad), InvalidInput);
}

TEST(QualityMetrics, QualityReportOfHandMadeMesh) {
  // One equilateral, one right isosceles, one 30-60-90 triangle, disjoint.
  TriangleSoup s;
  s.points = {V(0, 0, 0), V(1, 0, 0), V(0.5, std::sqrt(3.0) / 2.0, 0),
              V(0, 0, 1), V(1, 0, 1), V(0, 1, 1),
              V(0, 0, 2), V(std::sqrt(3.0), 0, 2), V(0, 1, 2)};
  s.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
  const MeshReport r = mesh_report(s);
  EXPECT_NEAR(r.quality.alpha_mean, (1.0 + std::sqrt(3.0) / 2.0 + 0.75) / 3.0, kTight);
  EXPECT_NEAR(r.quality.alpha_min, 0.75, kTight);
  EXPECT_NEAR(r.quality.alpha_p1, 0.75, kTight);  // rank floor(0.01 * 2) = 0
  EXPECT_NEAR(r.quality.min_angle_deg, 30.0, 1e-10);
  EXPECT_NEAR(r.quality.max_angle_deg, 90.0, 1e-10);
  EXPECT_EQ(r.quality.obtuse_fraction, 0.0);  // right angles are not obtuse
  EXPECT_EQ(r.topology.n_components, 3u);
  EXPECT_EQ(r.topology.n_boundary_loops, 3u);
  EXPECT_EQ(r.topology.n_edges, 9u);
  EXPECT_NEAR(r.quality.edge_length_min, 1.0, kTight);
  EXPECT_NEAR(r.quality.edge_length_max, 2.0, kTight);
}

TEST(QualityMetrics, ObtuseAndSmallAngleFractions) {
  TriangleSoup s;
  s.points = {V(0, 0, 0), V(4, 0, 0), V(2, 0.5, 0), V(0, 0, 1), V(1, 0, 1), V(0.5, std::sqrt(3.0) / 2.0, 1)};
  s.triangles = {{0, 1, 2}, {3, 4, 5}};  // a flat obtuse one (angle ~152 deg) and an equilateral one
  const MeshReport r = mesh_report(s);
  EXPECT_DOUBLE_EQ(r.quality.obtuse_fraction, 0.5);
  EXPECT_DOUBLE_EQ(r.quality.small_angle_fraction, 0.5);
  EXPECT_NEAR(r.quality.max_angle_deg, 180.0 - 2.0 * std::atan(0.25) * 180.0 / std::numbers::pi, 1e-10);
}

TEST(QualityMetrics, AngleExtremesEqualEveryTrianglesAngles) {
  // The report measures the angles of only the triangles that may change the extremes or
  // the small-angle count: its figures must be exactly those of every triangle's angles.
  // Triangles of every shape (near-equilateral, right, obtuse up to ~180 deg, slivers
  // near 0 deg, angles near 30 deg), in an order where the extremes move several times.
  TriangleSoup s;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int i = 0; i < 2000; ++i) {
    const double spread = std::pow(10.0, -6.0 * std::abs(unit(rng)));  // third corner's distance off the base
    const V o(3.0 * i, unit(rng), unit(rng));
    const V a = o, b = o + V(1.0 + 0.5 * unit(rng), 0.2 * unit(rng), 0);
    V c = o + V(0.5 + 1.5 * unit(rng), spread * (1.0 + unit(rng)), 0.3 * unit(rng) * spread);
    if (i % 7 == 0) c = o + V(0.5 * (b - a).x(), std::tan(std::numbers::pi / 6.0) * 0.5 * (b - a).x() * (1.0 + 1e-12 * unit(rng)), 0);
    const auto base = static_cast<std::uint32_t>(s.points.size());
    s.points.insert(s.points.end(), {a, b, c});
    s.triangles.push_back({base, base + 1, base + 2});
  }
  double lo = 180.0, hi = 0.0;
  std::size_t n_small = 0;
  for (const auto& t : s.triangles) {
    const auto angles = triangle_angles_deg(s.points[t[0]], s.points[t[1]], s.points[t[2]]);
    const double smallest = std::min({angles[0], angles[1], angles[2]});
    lo = std::min(lo, smallest);
    hi = std::max({hi, angles[0], angles[1], angles[2]});
    if (smallest < 30.0) ++n_small;
  }
  ASSERT_GT(n_small, 0u);
  ASSERT_LT(n_small, s.triangles.size());
  const MeshReport r = mesh_report(s);
  EXPECT_EQ(r.quality.min_angle_deg, lo);
  EXPECT_EQ(r.quality.max_angle_deg, hi);
  EXPECT_EQ(r.quality.small_angle_fraction, static_cast<double>(n_small) / static_cast<double>(s.triangles.size()));
}

TEST(QualityMetrics, AlphaFirstPercentileOfManyFaces) {
  // 200 faces: 198 equilateral, two with known lower alpha. Rank floor(0.01 * 199) = 1.
  TriangleSoup s;
  for (int i = 0; i < 200; ++i) {
    const V o(3.0 * i, 0, 0);
    const auto base = static_cast<std::uint32_t>(s.points.size());
    s.points.push_back(o);
    s.points.push_back(o + V(1, 0, 0));
    if (i == 7) {
      s.points.push_back(o + V(0, 1, 0));  // alpha sqrt(3)/2
    } else if (i == 120) {
      s.points.push_back(o + V(0, 1.0 / std::sqrt(3.0), 0));  // 30-60-90 with legs 1, 1/sqrt3: alpha 3/4
    } else {
      s.points.push_back(o + V(0.5, std::sqrt(3.0) / 2.0, 0));
    }
    s.triangles.push_back({base, base + 1, base + 2});
  }
  ReportOptions options;
  options.self_intersections = false;
  const MeshReport r = mesh_report(s, options);
  EXPECT_NEAR(r.quality.alpha_min, 0.75, kTight);
  EXPECT_NEAR(r.quality.alpha_p1, std::sqrt(3.0) / 2.0, kTight);
  EXPECT_FALSE(r.topology.n_self_intersecting_pairs.has_value());
}

TEST(QualityMetrics, OptionsAreValidated) {
  ReportOptions options;
  options.n_threads = 0;
  EXPECT_THROW(options.validate(), InvalidInput);
  EXPECT_THROW((void)mesh_report(test::cube(), options), InvalidInput);
  DistanceOptions distance;
  distance.sample_spacing_relative = -1.0;
  EXPECT_THROW(distance.validate(), InvalidInput);
  distance.sample_spacing_relative = std::nan("");
  EXPECT_THROW(distance.validate(), InvalidInput);
}

}  // namespace
}  // namespace nurbsfront
