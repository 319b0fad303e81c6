// SPDX-License-Identifier: BSD-3-Clause
// The stitch's fidelity moves (StitchOptions::fidelity_distance_edges; docs/stitch.md
// "Fidelity moves"): vertices onto the input where the output is far from it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/segment/segment.h"
#include "nurbsfront/stitch/stitch.h"
#include "nurbsfront/surfmesh/surfmesh.h"
#include "support/test_data.h"

namespace nurbsfront {
namespace {

std::size_t obtuse_triangles(const TriMesh& mesh) {
  std::size_t n = 0;
  for (const auto f : mesh.faces()) {
    std::vector<Eigen::Vector3d> p;
    for (const auto v : mesh.fv_range(f)) p.push_back(to_eigen(mesh.point(v)));
    for (int i = 0; i < 3; ++i) {
      const auto& a = p[static_cast<std::size_t>(i)];
      if ((p[static_cast<std::size_t>((i + 1) % 3)] - a).dot(p[static_cast<std::size_t>((i + 2) % 3)] - a) < 0.0) ++n;
    }
  }
  return n;
}

TEST(StitchFidelitySlow, MovesAndSplitsBringTheBrainCloserToItsInputAndKeepItsShape) {
  // The brain (a smoothed image's level set): the 2.5-edge fits smooth its folds, and the
  // output misses the input by 1.2 voxels (0.82 mean edges) by default. With the bound at
  // half a mean edge the moves and splits shrink the two-sided distance, add no obtuse
  // triangle, keep the smallest angle away from features at min(before, 25 deg), and every
  // new vertex sits on the input.
  const TriMesh input = read_mesh(test::test_data("io/brainImageSmooth.vtk"));
  const Segmentation seg = segment(input);
  const SurfaceMesh surface = mesh_surface(input, seg);
  StitchOptions options;
  const StitchResult plain = stitch(surface, input, options);
  options.fidelity_distance_edges = 0.5;
  const StitchResult moved = stitch(surface, input, options);
  ASSERT_TRUE(plain.report.ok());
  ASSERT_TRUE(moved.report.ok());
  EXPECT_EQ(plain.report.n_fidelity_moves + plain.report.n_fidelity_splits, 0u);
  EXPECT_GT(moved.report.n_fidelity_moves, 10u);
  EXPECT_GT(moved.report.n_fidelity_splits, 0u);
  EXPECT_EQ(moved.mesh.n_vertices(), plain.mesh.n_vertices() + moved.report.n_fidelity_splits);
  EXPECT_EQ(moved.report.output_components.size(), plain.report.output_components.size());
  EXPECT_EQ(moved.report.output_components[0].euler_characteristic, plain.report.output_components[0].euler_characteristic);
  EXPECT_TRUE(moved.report.output_components[0].is_closed);

  const TriangleSoup reference = to_soup(input);
  DistanceOptions sampling;
  sampling.sample_spacing_relative = 0.01;
  const DistanceReport before = mesh_distance(to_soup(plain.mesh), reference, sampling);
  const DistanceReport after = mesh_distance(to_soup(moved.mesh), reference, sampling);
  EXPECT_LT(after.hausdorff, 0.9 * before.hausdorff);
  EXPECT_LT(after.mean, before.mean);

  EXPECT_LE(obtuse_triangles(moved.mesh), obtuse_triangles(plain.mesh));
  EXPECT_GE(moved.report.min_angle_away_from_features_deg,
            std::min(plain.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg) - 1e-9);

  // The split vertices lie on the input (on its vertices, face centroids or edge midpoints).
  std::vector<std::uint32_t> faces(reference.triangles.size());
  std::iota(faces.begin(), faces.end(), 0U);
  const quality_detail::AabbTree tree(reference, faces);
  for (std::size_t i = plain.mesh.n_vertices(); i < moved.mesh.n_vertices(); ++i) {
    const Eigen::Vector3d p = to_eigen(moved.mesh.point(TriMesh::VertexHandle(static_cast<int>(i))));
    EXPECT_LT(std::sqrt(tree.closest(p, UINT32_MAX).squared_distance), 1e-9 * before.reference_diagonal) << "split vertex " << i;
  }
}

TEST(StitchFidelity, ZeroLeavesTheStitchAsItWasAndBadBoundsThrow) {
  const TriMesh input = read_mesh(test::test_data("io/brainImageSmooth.vtk"));
  const SurfaceMesh surface = mesh_surface(input, segment(input));
  // No input mesh: nothing to move towards.
  StitchOptions options;
  const StitchResult off = stitch(surface, options);
  options.fidelity_distance_edges = 0.5;
  const StitchResult no_input = stitch(surface, options);
  ASSERT_EQ(off.mesh.n_vertices(), no_input.mesh.n_vertices());
  for (const auto v : off.mesh.vertices()) EXPECT_EQ(off.mesh.point(v), no_input.mesh.point(v));
  EXPECT_EQ(no_input.report.n_fidelity_moves, 0u);
  for (const double bad : {-0.1, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    options.fidelity_distance_edges = bad;
    EXPECT_THROW((void)stitch(surface, input, options), InvalidInput);
  }
}

}  // namespace
}  // namespace nurbsfront
