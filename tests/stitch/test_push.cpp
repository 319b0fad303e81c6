// SPDX-License-Identifier: BSD-3-Clause
// stitch_detail::push_away: a node whose triangles cross another sheet moves away from it
// (docs/stitch.md "Fin rims: moves away from the other sheet (session 14)").
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>

#include <Eigen/Geometry>

#include "fixtures/shapes.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/stitch/stitch_internal.h"

namespace nurbsfront {
namespace {

// Smallest interior angle (deg) of v's triangles.
double ring_min_angle(const TriMesh& mesh, TriMesh::VertexHandle v) {
  double smallest = 180.0;
  for (auto f : mesh.vf_range(v)) {
    std::array<Eigen::Vector3d, 3> p;
    int k = 0;
    for (auto u : mesh.fv_range(f)) p[static_cast<std::size_t>(k++)] = to_eigen(mesh.point(u));
    const std::array<double, 3> a = triangle_angles_deg(p[0], p[1], p[2]);
    smallest = std::min({smallest, a[0], a[1], a[2]});
  }
  return smallest;
}

// A plate of two sheets 0.1 apart: the lower one (z = 0, normals -z, faces 0..31) and the upper
// one (z = 0.1, normals +z), 4 x 4 squares of side 1 each. The upper sheet's middle node sags to
// z = -0.15: its triangles cross the lower sheet.
TEST(StitchPush, NodeMovedAwayFromTheOtherSheetLeavesNoCrossing) {
  constexpr double kGap = 0.1, kSag = -0.15;
  TriangleSoup plate = test::grid_patch(4, 4, 4.0);
  const std::size_t n_lower = plate.points.size(), n_lower_faces = plate.triangles.size();
  for (auto& t : plate.triangles) std::swap(t[1], t[2]);  // the lower sheet faces down
  const TriangleSoup upper = test::grid_patch(4, 4, 4.0);
  for (const auto& p : upper.points) plate.points.push_back(p + Eigen::Vector3d(0.0, 0.0, kGap));
  for (const auto& t : upper.triangles) {
    plate.triangles.push_back({t[0] + static_cast<std::uint32_t>(n_lower), t[1] + static_cast<std::uint32_t>(n_lower),
                               t[2] + static_cast<std::uint32_t>(n_lower)});
  }
  const std::size_t middle = n_lower + 2 * 5 + 2;  // node (2, 2) of the upper sheet
  ASSERT_TRUE(self_intersecting_pairs(plate).empty());
  plate.points[middle].z() = kSag;
  const std::vector<std::array<std::uint32_t, 2>> pairs = self_intersecting_pairs(plate);
  ASSERT_FALSE(pairs.empty());
  TriMesh mesh = to_trimesh(plate);
  const TriMesh::VertexHandle v(static_cast<int>(middle));
  // A lower-sheet face the sagging node's triangles cross.
  TriMesh::FaceHandle crossed;
  for (const auto& pair : pairs) {
    ASSERT_LT(pair[0], n_lower_faces);  // every pair: a lower face and an upper one at the node
    ASSERT_GE(pair[1], n_lower_faces);
    crossed = TriMesh::FaceHandle(static_cast<int>(pair[0]));
  }
  const double min_double_area = 1e-12, min_normal_dot = 0.5;
  const double sin_bound = std::sin(kAwayFromFeaturesAngleBoundDeg * std::numbers::pi / 180.0);
  const double before = ring_min_angle(mesh, v);

  // Factor 1: straight up (the ring is centrally symmetric, its normal +z) to the neighbours'
  // mean height over the crossed face's plane, 0.1: 0.25 up.
  const Eigen::Vector3d q = stitch_detail::push_away(mesh, v, crossed, 1.0, 0.5, min_double_area, min_normal_dot, sin_bound);
  ASSERT_TRUE(q.allFinite());
  EXPECT_NEAR(q.x(), 2.0, 1e-12);
  EXPECT_NEAR(q.y(), 2.0, 1e-12);
  EXPECT_NEAR(q.z(), kGap, 1e-12);
  // Factor 2: twice the neighbours' height over the plane, from height 0 (the node is below it).
  EXPECT_NEAR(stitch_detail::push_away(mesh, v, crossed, 2.0, 0.5, min_double_area, min_normal_dot, sin_bound).z(),
              2.0 * kGap, 1e-12);
  // A move longer than the offset allowed (0.25 > 0.2) is refused.
  EXPECT_FALSE(stitch_detail::push_away(mesh, v, crossed, 1.0, 0.2, min_double_area, min_normal_dot, sin_bound).allFinite());
  // A node of the crossed sheet itself has its neighbours on the plane: nowhere to go.
  EXPECT_FALSE(stitch_detail::push_away(mesh, TriMesh::VertexHandle(2 * 5 + 2), crossed, 1.0, 0.5, min_double_area,
                                        min_normal_dot, sin_bound)
                   .allFinite());

  mesh.set_point(v, to_openmesh(q));
  EXPECT_TRUE(self_intersecting_pairs(to_soup(mesh)).empty());
  const double after = ring_min_angle(mesh, v);
  EXPECT_GT(after, before) << before << " -> " << after;
  EXPECT_NEAR(after, 45.0, 1e-9);  // the flat grid's right isosceles triangles again
}

}  // namespace
}  // namespace nurbsfront
