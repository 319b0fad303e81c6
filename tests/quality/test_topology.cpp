// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <utility>

#include "fixtures/shapes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront {
namespace {

using V = Eigen::Vector3d;
using Tri = std::array<std::uint32_t, 3>;

// A closed, oriented, clean mesh: the counts every "planted defect" test starts from.
void expect_clean_closed(const TopologyReport& t) {
  EXPECT_TRUE(t.is_closed);
  EXPECT_TRUE(t.is_manifold);
  EXPECT_TRUE(t.is_consistently_oriented);
  EXPECT_EQ(t.n_boundary_edges, 0u);
  EXPECT_EQ(t.n_boundary_loops, 0u);
  EXPECT_EQ(t.n_nonmanifold_edges, 0u);
  EXPECT_EQ(t.n_nonmanifold_vertices, 0u);
  EXPECT_EQ(t.n_misoriented_edges, 0u);
  EXPECT_EQ(t.n_degenerate_faces, 0u);
  EXPECT_EQ(t.n_duplicate_faces, 0u);
  ASSERT_TRUE(t.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
}

TEST(QualityTopology, Cube) {
  const MeshReport r = mesh_report(test::cube());
  const TopologyReport& t = r.topology;
  EXPECT_EQ(t.n_vertices, 8u);
  EXPECT_EQ(t.n_faces, 12u);
  EXPECT_EQ(t.n_edges, 18u);
  EXPECT_EQ(t.n_components, 1u);
  EXPECT_EQ(t.euler_characteristic, 2);
  expect_clean_closed(t);
  ASSERT_EQ(t.components.size(), 1u);
  EXPECT_EQ(t.components[0].euler_characteristic, 2);
  ASSERT_TRUE(t.components[0].genus.has_value());
  EXPECT_EQ(*t.components[0].genus, 0);
  ASSERT_TRUE(t.volume.has_value());
  EXPECT_NEAR(*t.volume, 1.0, 1e-14);
  EXPECT_NEAR(enclosed_volume(test::cube()), 1.0, 1e-14);
  // Edges: 12 of length 1 and 6 face diagonals of length sqrt(2).
  EXPECT_NEAR(r.quality.edge_length_min, 1.0, 1e-14);
  EXPECT_NEAR(r.quality.edge_length_max, std::sqrt(2.0), 1e-14);
  EXPECT_NEAR(r.quality.edge_length_mean, (12.0 + 6.0 * std::sqrt(2.0)) / 18.0, 1e-14);
}

TEST(QualityTopology, TorusHasGenusOne) {
  const MeshReport r = mesh_report(test::torus(24, 12));
  expect_clean_closed(r.topology);
  EXPECT_EQ(r.topology.euler_characteristic, 0);
  ASSERT_EQ(r.topology.components.size(), 1u);
  ASSERT_TRUE(r.topology.components[0].genus.has_value());
  EXPECT_EQ(*r.topology.components[0].genus, 1);
}

TEST(QualityTopology, GenusPerComponent) {
  // A torus and a disjoint sphere in one soup: chi 0 + 2, genus 1 and 0.
  TriangleSoup s = test::torus(16, 8);
  const TriangleSoup sphere = test::icosphere(1, 0.2);
  const auto offset = static_cast<std::uint32_t>(s.points.size());
  for (const auto& p : sphere.points) s.points.push_back(p + V(5, 0, 0));
  for (const auto& t : sphere.triangles) s.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const MeshReport r = mesh_report(s);
  expect_clean_closed(r.topology);
  EXPECT_EQ(r.topology.n_components, 2u);
  EXPECT_EQ(r.topology.euler_characteristic, 2);
  ASSERT_EQ(r.topology.components.size(), 2u);
  EXPECT_EQ(r.topology.components[0].genus, 1);
  EXPECT_EQ(r.topology.components[1].genus, 0);
  EXPECT_EQ(r.topology.components[1].n_faces, sphere.triangles.size());
  EXPECT_EQ(r.topology.components[1].n_vertices, sphere.points.size());
}

TEST(QualityTopology, GridPatchHasOneBoundaryLoop) {
  const int nx = 5, ny = 3;
  const MeshReport r = mesh_report(test::grid_patch(nx, ny));
  const TopologyReport& t = r.topology;
  EXPECT_EQ(t.n_vertices, static_cast<std::size_t>((nx + 1) * (ny + 1)));
  EXPECT_EQ(t.n_boundary_edges, static_cast<std::size_t>(2 * (nx + ny)));
  EXPECT_EQ(t.n_boundary_loops, 1u);
  EXPECT_FALSE(t.is_closed);
  EXPECT_TRUE(t.is_manifold);
  EXPECT_TRUE(t.is_consistently_oriented);
  EXPECT_EQ(t.euler_characteristic, 1);  // a disc
  EXPECT_FALSE(t.components[0].genus.has_value());  // open: genus unknown
  EXPECT_FALSE(t.volume.has_value());
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
}

TEST(QualityTopology, Hole) {
  TriangleSoup s = test::icosphere(2);
  s.triangles.erase(s.triangles.begin() + 17);
  const TopologyReport t = mesh_report(s).topology;
  EXPECT_EQ(t.n_boundary_edges, 3u);
  EXPECT_EQ(t.n_boundary_loops, 1u);
  EXPECT_FALSE(t.is_closed);
  EXPECT_TRUE(t.is_manifold);
  EXPECT_TRUE(t.is_consistently_oriented);
  EXPECT_EQ(t.euler_characteristic, 1);
  EXPECT_FALSE(t.components[0].genus.has_value());
}

TEST(QualityTopology, DuplicateFace) {
  TriangleSoup s = test::cube();
  s.triangles.push_back(s.triangles[4]);
  s.triangles.push_back({s.triangles[7][2], s.triangles[7][1], s.triangles[7][0]});  // reversed copy
  const TopologyReport t = mesh_report(s).topology;
  EXPECT_EQ(t.n_duplicate_faces, 2u);
  EXPECT_EQ(t.n_nonmanifold_edges, 6u);  // the two faces' edges now have 3 or 4 faces
  EXPECT_FALSE(t.is_manifold);
  EXPECT_FALSE(t.is_closed);
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);  // duplicates are not counted twice
}

TEST(QualityTopology, NonManifoldEdge) {
  // Three triangles on edge (0, 1).
  TriangleSoup s;
  s.points = {V(0, 0, 0), V(1, 0, 0), V(0.5, 1, 0), V(0.5, -1, 0), V(0.5, 0, 1)};
  s.triangles = {Tri{0, 1, 2}, Tri{1, 0, 3}, Tri{0, 1, 4}};
  const TopologyReport t = mesh_report(s).topology;
  EXPECT_EQ(t.n_nonmanifold_edges, 1u);
  EXPECT_EQ(t.n_nonmanifold_vertices, 0u);
  EXPECT_EQ(t.n_boundary_edges, 6u);
  EXPECT_EQ(t.n_components, 1u);
  EXPECT_EQ(t.n_edges, 7u);
  EXPECT_EQ(t.euler_characteristic, 5 - 7 + 3);
  EXPECT_FALSE(t.is_manifold);
  EXPECT_FALSE(t.components[0].is_manifold);
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
}

TEST(QualityTopology, NonManifoldVertexBowTie) {
  TriangleSoup s;
  s.points = {V(0, 0, 0), V(1, 1, 0), V(-1, 1, 0), V(1, -1, 0), V(-1, -1, 0)};
  s.triangles = {Tri{0, 1, 2}, Tri{0, 4, 3}};
  const TopologyReport t = mesh_report(s).topology;
  EXPECT_EQ(t.n_nonmanifold_vertices, 1u);
  EXPECT_EQ(t.n_nonmanifold_edges, 0u);
  EXPECT_EQ(t.n_components, 1u);  // connected through the shared vertex
  EXPECT_EQ(t.n_boundary_edges, 6u);
  EXPECT_FALSE(t.is_manifold);
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
}

TEST(QualityTopology, FlippedFace) {
  TriangleSoup s = test::cube();
  std::swap(s.triangles[5][1], s.triangles[5][2]);
  const TopologyReport t = mesh_report(s).topology;
  EXPECT_EQ(t.n_misoriented_edges, 3u);
  EXPECT_FALSE(t.is_consistently_oriented);
  EXPECT_TRUE(t.is_closed);
  EXPECT_TRUE(t.is_manifold);
  EXPECT_FALSE(t.components[0].genus.has_value());
  EXPECT_FALSE(t.volume.has_value());
}

// Appends two degenerate faces on three new points: a collinear (zero-area) triangle and one
// with a repeated index.
void add_two_degenerate_faces(TriangleSoup& s) {
  const auto n = static_cast<std::uint32_t>(s.points.size());
  s.points.push_back(V(0.25, 0.5, 1.0));
  s.points.push_back(V(0.5, 0.5, 1.0));
  s.points.push_back(V(0.75, 0.5, 1.0));
  s.triangles.push_back({n, n + 1, n + 2});  // collinear: zero area
  s.triangles.push_back({n, n, n + 1});      // repeated index
}

TEST(QualityTopology, DegenerateFaces) {
  TriangleSoup s = test::grid_patch(2, 2);
  add_two_degenerate_faces(s);
  s.points.push_back(V(7, 7, 7));            // unreferenced
  const MeshReport r = mesh_report(s);
  EXPECT_EQ(r.topology.n_degenerate_faces, 2u);
  EXPECT_EQ(r.topology.n_unreferenced_points, 1u);
  EXPECT_EQ(r.topology.n_vertices, 9u + 3u);
  EXPECT_EQ(r.quality.alpha_min, 0.0);
  EXPECT_EQ(*r.topology.n_self_intersecting_pairs, 0u);
}

// The face counts and the triangles' quality figures run on another thread with 2+ threads
// (3+ with the self-intersection count): the same report at every thread count, and the
// planted defects counted (2 degenerate faces, 1 duplicate) either way.
TEST(QualityTopology, ReportSameAtEveryThreadCount) {
  TriangleSoup s = test::torus(16, 8);
  add_two_degenerate_faces(s);
  s.triangles.push_back(s.triangles[3]);     // duplicate
  for (const bool intersections : {false, true}) {
    ReportOptions options;
    options.self_intersections = intersections;
    options.n_threads = 1;
    const MeshReport serial = mesh_report(s, options);
    EXPECT_EQ(serial.topology.n_degenerate_faces, 2u);
    EXPECT_EQ(serial.topology.n_duplicate_faces, 1u);
    EXPECT_EQ(serial.topology.n_faces, 16u * 8u * 2u + 3u);
    EXPECT_GT(serial.quality.edge_length_mean, 0.0);
    EXPECT_EQ(serial.quality.alpha_min, 0.0);
    for (const unsigned threads : {2U, 3U, 4U}) {
      options.n_threads = threads;
      const MeshReport r = mesh_report(s, options);
      EXPECT_EQ(to_json(r), to_json(serial)) << threads << " threads, intersections " << intersections;
      // Bit for bit where the JSON rounds (10 digits).
      EXPECT_EQ(r.quality.alpha_mean, serial.quality.alpha_mean);
      EXPECT_EQ(r.quality.min_angle_deg, serial.quality.min_angle_deg);
      EXPECT_EQ(r.quality.max_angle_deg, serial.quality.max_angle_deg);
      EXPECT_EQ(r.quality.edge_length_stddev, serial.quality.edge_length_stddev);
      EXPECT_EQ(r.topology.n_degenerate_faces, 2u);
      EXPECT_EQ(r.topology.n_duplicate_faces, 1u);
    }
  }
}

TEST(QualityTopology, EmptySoupAndBadInput) {
  const MeshReport r = mesh_report(TriangleSoup{});
  EXPECT_EQ(r.topology.n_faces, 0u);
  EXPECT_EQ(r.topology.n_components, 0u);
  EXPECT_FALSE(r.topology.is_closed);
  EXPECT_TRUE(std::isnan(r.quality.alpha_mean));
  TriangleSoup bad = test::cube();
  bad.triangles[0][0] = 8;
  EXPECT_THROW((void)mesh_report(bad), InvalidInput);
  bad = test::cube();
  bad.points[2].x() = std::nan("");
  EXPECT_THROW((void)mesh_report(bad), InvalidInput);
}

TEST(QualityTopology, ProgressCanCancel) {
  ReportOptions options;
  options.progress = [](std::string_view, double) { return false; };
  EXPECT_THROW((void)mesh_report(test::cube(), options), Cancelled);
}

}  // namespace
}  // namespace nurbsfront
