// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <limits>

#include "fixtures/shapes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup.h"

namespace nurbsfront {
namespace {

int euler(const TriMesh& m) {
  return static_cast<int>(m.n_vertices()) - static_cast<int>(m.n_edges()) + static_cast<int>(m.n_faces());
}

TEST(Soup, ClosedShapesBecomeManifoldMeshes) {
  for (const auto& [soup, chi] : {std::pair{test::tetrahedron(), 2}, std::pair{test::cube(), 2},
                                  std::pair{test::icosphere(2), 2}, std::pair{test::torus(12, 8), 0}}) {
    ASSERT_TRUE(check_manifold(soup).ok()) << check_manifold(soup).message();
    const TriMesh mesh = to_trimesh(soup);
    EXPECT_EQ(mesh.n_faces(), soup.triangles.size());
    EXPECT_EQ(euler(mesh), chi);
    for (auto h : mesh.halfedges()) EXPECT_FALSE(mesh.is_boundary(h));
    const TriangleSoup back = to_soup(mesh);
    EXPECT_EQ(back.points.size(), soup.points.size());
    EXPECT_EQ(back.triangles, soup.triangles);
  }
}

TEST(Soup, OpenPatchKeepsItsBoundary) {
  const TriMesh mesh = to_trimesh(test::grid_patch(3, 2));
  std::size_t n_boundary = 0;
  for (auto e : mesh.edges()) n_boundary += mesh.is_boundary(e) ? 1 : 0;
  EXPECT_EQ(n_boundary, 10u);  // 2 * (3 + 2)
  EXPECT_EQ(euler(mesh), 1);
}

TEST(Soup, NonManifoldEdgeIsRejectedWithReason) {
  TriangleSoup s = test::grid_patch(1, 1);
  s.points.emplace_back(0.5, 0.5, 1.0);
  s.triangles.push_back({0, 3, 4});  // third triangle on the diagonal (0, 3)
  const ManifoldCheck check = check_manifold(s);
  EXPECT_EQ(check.n_nonmanifold_edges, 1u);
  EXPECT_THROW((void)to_trimesh(s), TopologyError);
}

TEST(Soup, FlippedTriangleIsMisoriented) {
  TriangleSoup s = test::tetrahedron();
  std::swap(s.triangles[0][1], s.triangles[0][2]);
  EXPECT_EQ(check_manifold(s).n_misoriented_edges, 3u);
}

TEST(Soup, TwoFansAtOneVertexAreNonManifold) {
  // Two triangles touching only at vertex 0 (a bow tie).
  TriangleSoup s;
  s.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  s.triangles = {{0, 1, 2}, {0, 3, 4}};
  EXPECT_EQ(check_manifold(s).n_nonmanifold_vertices, 1u);
  EXPECT_THROW((void)to_trimesh(s), TopologyError);
}

TEST(Soup, BadIndicesAndNanAreErrors) {
  TriangleSoup s = test::tetrahedron();
  s.triangles.push_back({0, 1, 17});
  EXPECT_EQ(check_manifold(s).n_bad_indices, 1u);
  EXPECT_THROW((void)to_trimesh(s), TopologyError);
  TriangleSoup n = test::tetrahedron();
  n.points[2].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((void)to_trimesh(n), InvalidInput);
}

TEST(Soup, BoundingBoxDiagonal) {
  EXPECT_DOUBLE_EQ(bounding_box(test::cube()).diagonal(), std::sqrt(3.0));
  EXPECT_EQ(bounding_box(TriangleSoup{}).diagonal(), 0.0);
}

}  // namespace
}  // namespace nurbsfront
