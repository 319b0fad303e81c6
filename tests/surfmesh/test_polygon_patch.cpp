// SPDX-License-Identifier: BSD-3-Clause
// mesh_polygon_patch(): the source method's single-polygon path (its Fig. 2), checked on a
// planar polygon (exact plane, exact area, a disk), on the built-in curved example (node
// count, 3D quality, distance to the analytic surface), orientation, the text reader and
// bad input.

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

#include "nurbsfront/core/error.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/surfmesh/polygon_patch.h"
#include "support/test_data.h"

namespace nurbsfront {
namespace {

TriangleSoup as_soup(const PolygonPatchMesh& m) {
  TriangleSoup soup;
  soup.points = m.nodes;
  for (const auto& t : m.triangles) {
    soup.triangles.push_back({static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]), static_cast<std::uint32_t>(t[2])});
  }
  return soup;
}

double total_area(const PolygonPatchMesh& m) {
  double a = 0.0;
  for (const auto& t : m.triangles) {
    a += 0.5 * (m.nodes[static_cast<std::size_t>(t[1])] - m.nodes[static_cast<std::size_t>(t[0])])
                   .cross(m.nodes[static_cast<std::size_t>(t[2])] - m.nodes[static_cast<std::size_t>(t[0])])
                   .norm();
  }
  return a;
}

// A 2 x 1 rectangle in the tilted plane spanned by u and v, counter-clockwise about u x v.
PolygonPatch tilted_rectangle(double density) {
  const Eigen::Vector3d origin(1.0, -2.0, 0.5);
  const Eigen::Vector3d u = Eigen::Vector3d(1.0, 0.0, 1.0).normalized();
  const Eigen::Vector3d v = Eigen::Vector3d(0.0, 1.0, 0.0);
  PolygonPatch p;
  p.polygon = {origin, origin + 2.0 * u, origin + 2.0 * u + v, origin + v};
  p.densities.assign(4, density);
  return p;
}

TEST(PolygonPatch, PlanarPolygonIsAnExactDiskInItsPlane) {
  const PolygonPatch input = tilted_rectangle(0.1);
  const PolygonPatchMesh m = mesh_polygon_patch(input);
  const Eigen::Vector3d normal = Eigen::Vector3d(-1.0, 0.0, 1.0).normalized();  // u x v
  for (const auto& p : m.nodes) EXPECT_NEAR((p - input.polygon[0]).dot(normal), 0.0, 1e-9);
  EXPECT_NEAR(total_area(m), 2.0, 1e-9);
  // The polygon's vertices come first and stay where they were (the plane is fitted exactly).
  for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR((m.nodes[i] - input.polygon[i]).norm(), 0.0, 1e-9);

  const MeshReport r = mesh_report(as_soup(m));
  EXPECT_TRUE(r.topology.is_manifold);
  EXPECT_TRUE(r.topology.is_consistently_oriented);
  EXPECT_EQ(r.topology.n_components, 1u);
  EXPECT_EQ(r.topology.euler_characteristic, 1);  // a disk
  EXPECT_EQ(r.topology.n_boundary_loops, 1u);
  EXPECT_EQ(r.topology.n_self_intersecting_pairs.value_or(1), 0u);
  // Perimeter 6 at density 0.1: 60 boundary edges.
  EXPECT_EQ(r.topology.n_boundary_edges, 60u);
  EXPECT_GE(r.quality.alpha_mean, 0.92);
  EXPECT_GE(r.quality.min_angle_deg, 30.0);
  // Every triangle faces the polygon's normal side.
  for (const auto& t : m.triangles) {
    const Eigen::Vector3d n = (m.nodes[static_cast<std::size_t>(t[1])] - m.nodes[static_cast<std::size_t>(t[0])])
                                  .cross(m.nodes[static_cast<std::size_t>(t[2])] - m.nodes[static_cast<std::size_t>(t[0])]);
    EXPECT_GT(n.dot(normal), 0.0);
  }
}

TEST(PolygonPatch, ReversedPolygonGivesReversedTriangles) {
  PolygonPatch input = tilted_rectangle(0.25);
  std::reverse(input.polygon.begin(), input.polygon.end());
  const PolygonPatchMesh m = mesh_polygon_patch(input);
  const Eigen::Vector3d normal = Eigen::Vector3d(-1.0, 0.0, 1.0).normalized();
  ASSERT_FALSE(m.triangles.empty());
  for (const auto& t : m.triangles) {
    const Eigen::Vector3d n = (m.nodes[static_cast<std::size_t>(t[1])] - m.nodes[static_cast<std::size_t>(t[0])])
                                  .cross(m.nodes[static_cast<std::size_t>(t[2])] - m.nodes[static_cast<std::size_t>(t[0])]);
    EXPECT_LT(n.dot(normal), 0.0);
  }
}

// The built-in example is sampled from z = 1.6 exp(-|p - c|^2 / 8) + 0.15 x.
double example_height(double x, double y) {
  const double dx = x - 0.6;
  const double dy = y + 0.4;
  return 1.6 * std::exp(-(dx * dx + dy * dy) / 8.0) + 0.15 * x;
}

TEST(PolygonPatch, CurvedExampleLikeTheSourceMethodsFigure2) {
  const PolygonPatchMesh m = mesh_polygon_patch(example_polygon_patch());
  // The source method: 512 nodes, mean quality 0.92.
  EXPECT_GE(m.nodes.size(), 400u);
  EXPECT_LE(m.nodes.size(), 650u);
  const MeshReport r = mesh_report(as_soup(m));
  EXPECT_TRUE(r.topology.is_manifold);
  EXPECT_TRUE(r.topology.is_consistently_oriented);
  EXPECT_EQ(r.topology.euler_characteristic, 1);
  EXPECT_EQ(r.topology.n_self_intersecting_pairs.value_or(1), 0u);
  EXPECT_GE(r.quality.alpha_mean, 0.92);  // measured in 3D
  EXPECT_GE(r.quality.min_angle_deg, 25.0);
  EXPECT_LE(r.quality.obtuse_fraction, 0.01);
  // Every node on the analytic surface, within 1e-3 of the patch size (about 10): the fit
  // of 406 samples of a smooth bump, at most 0.6 apart.
  double worst = 0.0;
  for (const auto& p : m.nodes) worst = std::max(worst, std::abs(p.z() - example_height(p.x(), p.y())));
  EXPECT_LT(worst, 1e-2);
  std::printf("example: %zu nodes, %zu triangles, alpha mean %.4f min %.4f, min angle %.1f, max |dz| %.2e\n",
              m.nodes.size(), m.triangles.size(), r.quality.alpha_mean, r.quality.alpha_min,
              r.quality.min_angle_deg, worst);
  EXPECT_EQ(m.front.status, FrontStatus::Ok);
}

TEST(PolygonPatch, DensitiesSetTheEdgeLengths) {
  // The same square at two densities: edge lengths follow (within the front's spread).
  PolygonPatch coarse = tilted_rectangle(0.2);
  PolygonPatch fine = tilted_rectangle(0.05);
  const MeshReport rc = mesh_report(as_soup(mesh_polygon_patch(coarse)));
  const MeshReport rf = mesh_report(as_soup(mesh_polygon_patch(fine)));
  EXPECT_NEAR(rc.quality.edge_length_mean, 0.2, 0.03);
  EXPECT_NEAR(rf.quality.edge_length_mean, 0.05, 0.0075);
}

TEST(PolygonPatch, ReadsTheTextFormat) {
  const auto dir = test::temp_dir("polygon_patch");
  const auto path = dir / "patch.txt";
  {
    std::ofstream out(path);
    out << "# a square over a plane\npolygon 4\n0 0 0 0.25\n1 0 0 0.25\n1 1 0 0.25\n0 1 0 0.25\n"
           "points 2  # scattered samples\n0.5 0.5 0\n0.2 0.7 0\n";
  }
  const PolygonPatch p = read_polygon_patch(path);
  ASSERT_EQ(p.polygon.size(), 4u);
  EXPECT_EQ(p.densities, std::vector<double>(4, 0.25));
  ASSERT_EQ(p.points.size(), 2u);
  EXPECT_EQ(p.points[1], Eigen::Vector3d(0.2, 0.7, 0.0));
  const PolygonPatchMesh m = mesh_polygon_patch(p);
  EXPECT_NEAR(total_area(m), 1.0, 1e-12);

  {
    std::ofstream out(dir / "truncated.txt");
    out << "polygon 4\n0 0 0 0.25\n1 0 0 0.25\n";
  }
  EXPECT_THROW((void)read_polygon_patch(dir / "truncated.txt"), IoError);
  {
    std::ofstream out(dir / "no_density.txt");
    out << "polygon 3\n0 0 0\n1 0 0\n0 1 0\n";
  }
  EXPECT_THROW((void)read_polygon_patch(dir / "no_density.txt"), IoError);
  EXPECT_THROW((void)read_polygon_patch(dir / "missing.txt"), IoError);
}

TEST(PolygonPatch, BadInputIsRejected) {
  PolygonPatch two;
  two.polygon = {{0, 0, 0}, {1, 0, 0}};
  two.densities = {0.1, 0.1};
  EXPECT_THROW((void)mesh_polygon_patch(two), InvalidInput);

  PolygonPatch counts = tilted_rectangle(0.1);
  counts.densities.pop_back();
  EXPECT_THROW((void)mesh_polygon_patch(counts), InvalidInput);

  PolygonPatch nan = tilted_rectangle(0.1);
  nan.polygon[2].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((void)mesh_polygon_patch(nan), InvalidInput);

  PolygonPatch zero_density = tilted_rectangle(0.1);
  zero_density.densities[1] = 0.0;
  EXPECT_THROW((void)mesh_polygon_patch(zero_density), InvalidInput);

  PolygonPatch collinear;
  collinear.polygon = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
  collinear.densities = {0.1, 0.1, 0.1};
  EXPECT_THROW((void)mesh_polygon_patch(collinear), InvalidInput);

  PolygonPatch bow_tie;  // crosses itself in its plane
  bow_tie.polygon = {{0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0.5, 0}};
  bow_tie.densities.assign(5, 0.1);
  EXPECT_THROW((void)mesh_polygon_patch(bow_tie), InvalidInput);

  PolygonPatchOptions bad;
  bad.gradation = 1.0;
  EXPECT_THROW((void)mesh_polygon_patch(tilted_rectangle(0.1), bad), InvalidInput);
}

}  // namespace
}  // namespace nurbsfront
