// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "fixtures/shapes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/quality/internal.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront {
namespace {

using V = Eigen::Vector3d;

// Coarser than the default sampling: keeps the suite fast (also under ASan).
DistanceOptions coarse(double spacing = 0.02) {
  DistanceOptions options;
  options.sample_spacing_relative = spacing;
  return options;
}

TEST(QualityDistance, ClosestPointOnTriangle) {
  const V a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(quality_detail::closest_point_on_triangle(V(0.2, 0.3, 5), a, b, c).isApprox(V(0.2, 0.3, 0)));
  EXPECT_TRUE(quality_detail::closest_point_on_triangle(V(-1, -1, 1), a, b, c).isApprox(a));
  EXPECT_TRUE(quality_detail::closest_point_on_triangle(V(2, -1, 0), a, b, c).isApprox(b));
  EXPECT_TRUE(quality_detail::closest_point_on_triangle(V(1, 1, 0), a, b, c).isApprox(V(0.5, 0.5, 0)));
  EXPECT_TRUE(quality_detail::closest_point_on_triangle(V(0.5, -2, 0), a, b, c).isApprox(V(0.5, 0, 0)));
}

TEST(QualityDistance, TreeQueryMatchesBruteForce) {
  const TriangleSoup s = test::torus(20, 10);
  std::vector<std::uint32_t> faces(s.triangles.size());
  for (std::uint32_t i = 0; i < faces.size(); ++i) faces[i] = i;
  const quality_detail::AabbTree tree(s, faces);
  for (int k = 0; k < 200; ++k) {
    const V p(std::sin(k * 1.3) * 1.5, std::cos(k * 0.7) * 1.5, std::sin(k * 0.31) * 0.6);
    double best = std::numeric_limits<double>::infinity();
    for (const auto& t : s.triangles) {
      const V q = quality_detail::closest_point_on_triangle(p, s.points[t[0]], s.points[t[1]], s.points[t[2]]);
      best = std::min(best, (q - p).squaredNorm());
    }
    EXPECT_DOUBLE_EQ(tree.closest(p, std::numeric_limits<std::uint32_t>::max()).squared_distance, best);
    EXPECT_DOUBLE_EQ(tree.closest(p, static_cast<std::uint32_t>(k)).squared_distance, best);
  }
}

// The tree built on 2 and 4 threads (per-face loops in chunks, the root's halves built
// apart) is the one-thread tree, node for node; its hinted queries (leaf and parent
// arrays) find the brute-force closest face. 20 480 faces: above the parallel build's
// size and the per-face chunk.
TEST(QualityDistance, TreeBuiltOnThreadsIsTheSerialTree) {
  const TriangleSoup s = test::icosphere(5);
  std::vector<std::uint32_t> faces;
  for (std::uint32_t i = 0; i < s.triangles.size(); ++i) {
    if (i % 7 != 3) faces.push_back(i);  // a subset: some faces in no leaf
  }
  const quality_detail::AabbTree serial(s, faces, 1);
  ASSERT_GT(serial.faces().size(), 4096u * 4);
  for (const unsigned threads : {2u, 4u}) {
    const quality_detail::AabbTree tree(s, faces, threads);
    ASSERT_EQ(tree.faces(), serial.faces());
    ASSERT_EQ(tree.nodes().size(), serial.nodes().size());
    for (std::size_t k = 0; k < tree.nodes().size(); ++k) {
      const auto& a = tree.nodes()[k];
      const auto& b = serial.nodes()[k];
      ASSERT_EQ(a.index, b.index) << k;
      ASSERT_EQ(a.count, b.count) << k;
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(a.box.lo[c], b.box.lo[c]) << k;
        ASSERT_EQ(a.box.hi[c], b.box.hi[c]) << k;
      }
    }
    for (int k = 0; k < 40; ++k) {
      const V p(std::sin(k * 1.3) * 1.2, std::cos(k * 0.7) * 1.2, std::sin(k * 0.31) * 1.1);
      double best = std::numeric_limits<double>::infinity();
      for (const std::uint32_t f : faces) {
        const auto& t = s.triangles[f];
        const V q = quality_detail::closest_point_on_triangle(p, s.points[t[0]], s.points[t[1]], s.points[t[2]]);
        best = std::min(best, (q - p).squaredNorm());
      }
      // Hints: a face of the tree far from p, and one that is in no leaf.
      EXPECT_DOUBLE_EQ(tree.closest(p, faces[static_cast<std::size_t>(k) * 401 % faces.size()]).squared_distance, best);
      EXPECT_DOUBLE_EQ(tree.closest(p, 3).squared_distance, best);
    }
  }
}

// A tree refitted after faces changed (points moved, corners of some faces replaced) answers
// every query as a tree built anew over the changed soup (the same face and distance, hinted
// or not), though its structure is the old one; without the refit it answers some wrongly.
TEST(QualityDistance, RefitTreeAnswersAsARebuiltOne) {
  TriangleSoup s = test::icosphere(4);
  std::vector<std::uint32_t> faces(s.triangles.size());
  for (std::uint32_t i = 0; i < faces.size(); ++i) faces[i] = i;
  quality_detail::AabbTree refitted(s, faces, 2);
  const quality_detail::AabbTree stale_structure(s, faces);
  TriangleSoup changed = s;
  // Every 9th point pushed out or in by up to 30% (far beyond its faces' old boxes), and every
  // 50th face given another corner (the edge flips and splits of the fidelity moves).
  std::vector<std::uint8_t> point_moved(s.points.size(), 0);
  for (std::size_t i = 0; i < changed.points.size(); i += 9) {
    changed.points[i] *= 1.0 + 0.3 * std::sin(double(i));
    point_moved[i] = 1;
  }
  std::vector<std::uint32_t> changed_faces;
  for (std::uint32_t f = 0; f < changed.triangles.size(); ++f) {
    auto& t = changed.triangles[f];
    if (f % 50 == 7) t[2] = (t[2] + 17) % static_cast<std::uint32_t>(changed.points.size());
    if (f % 50 == 7 || point_moved[t[0]] != 0 || point_moved[t[1]] != 0 || point_moved[t[2]] != 0) changed_faces.push_back(f);
  }
  refitted.refit(changed, changed_faces);
  const quality_detail::AabbTree rebuilt(changed, faces);
  std::size_t n_stale_wrong = 0;
  for (int k = 0; k < 400; ++k) {
    const V p(std::sin(k * 1.3) * 1.3, std::cos(k * 0.7) * 1.3, std::sin(k * 0.31) * 1.25);
    const auto want = rebuilt.closest(p, UINT32_MAX);
    for (const std::uint32_t hint : {UINT32_MAX, static_cast<std::uint32_t>(k * 13 % faces.size()), want.face}) {
      const auto got = refitted.closest(p, hint);
      EXPECT_EQ(got.squared_distance, want.squared_distance) << k;
      EXPECT_EQ(got.face, want.face) << k;
    }
    // The old boxes over the new soup (a refit with nothing listed): pruned wrongly somewhere.
    quality_detail::AabbTree stale = stale_structure;
    stale.refit(changed, {});
    const auto old = stale.closest(p, UINT32_MAX);
    n_stale_wrong += old.face != want.face || old.squared_distance != want.squared_distance ? 1 : 0;
  }
  EXPECT_GT(n_stale_wrong, 0u);
}

// The distance pass on a reference tree built beforehand (IndexedSoup, shared with the
// fidelity moves) gives the report it builds itself, on one thread and on two.
TEST(QualityDistance, SharedReferenceTreeGivesTheSameDistances) {
  const TriangleSoup mesh = test::icosphere(2, 1.05);
  const quality_detail::IndexedSoup reference(test::torus(20, 8, 0.8, 0.3), 2);
  for (const unsigned threads : {1u, 2u}) {
    DistanceOptions options = coarse(0.03);
    options.n_threads = threads;
    const DistanceReport own = mesh_distance(mesh, reference.soup(), options);
    const DistanceReport shared =
        quality_detail::mesh_distance_with(mesh, reference.soup(), options, nullptr, &reference.tree());
    EXPECT_GT(own.hausdorff, 0.1);
    EXPECT_EQ(shared.hausdorff, own.hausdorff);
    EXPECT_EQ(shared.mean, own.mean);
    EXPECT_EQ(shared.mesh_to_reference_max, own.mesh_to_reference_max);
    EXPECT_EQ(shared.reference_to_mesh_max, own.reference_to_mesh_max);
    EXPECT_EQ(shared.mesh_to_reference_mean, own.mesh_to_reference_mean);
    EXPECT_EQ(shared.reference_to_mesh_mean, own.reference_to_mesh_mean);
    EXPECT_EQ(shared.n_mesh_samples, own.n_mesh_samples);
    EXPECT_EQ(shared.n_reference_samples, own.n_reference_samples);
  }
}

TEST(QualityDistance, MeshToItselfIsZero) {
  const TriangleSoup s = test::icosphere(3);
  const DistanceReport d = mesh_distance(s, s, coarse());
  // Zero up to the rounding of the sample positions inside the triangles.
  EXPECT_LE(d.hausdorff, 1e-14);
  EXPECT_LE(d.mean, 1e-15);
  EXPECT_GT(d.n_mesh_samples, s.points.size());
  ASSERT_TRUE(d.relative_volume_change.has_value());
  EXPECT_EQ(*d.relative_volume_change, 0.0);
}

TEST(QualityDistance, ConcentricSpheres) {
  const TriangleSoup inner = test::icosphere(4, 1.0);
  const TriangleSoup outer = test::icosphere(4, 1.1);
  const DistanceReport d = mesh_distance(outer, inner, coarse(0.01));
  EXPECT_NEAR(d.hausdorff, 0.1, 0.001);
  EXPECT_NEAR(d.mesh_to_reference_max, 0.1, 0.001);
  EXPECT_NEAR(d.reference_to_mesh_max, 0.1, 0.001);
  EXPECT_LE(d.mean, d.hausdorff);
  EXPECT_GT(d.mean, 0.098);
  EXPECT_NEAR(d.reference_diagonal, bounding_box(inner).diagonal(), 1e-15);
  EXPECT_NEAR(d.hausdorff_relative, d.hausdorff / d.reference_diagonal, 1e-15);
  // Same vertex directions scaled by 1.1: the volume ratio is exactly 1.1^3.
  ASSERT_TRUE(d.relative_volume_change.has_value());
  EXPECT_NEAR(*d.relative_volume_change, 1.1 * 1.1 * 1.1 - 1.0, 1e-12);
}

TEST(QualityDistance, ScaledCubeVolumeChangeIsExact) {
  TriangleSoup big = test::cube();
  for (auto& p : big.points) p *= 2.0;
  const DistanceReport d = mesh_distance(big, test::cube(), coarse());
  ASSERT_TRUE(d.relative_volume_change.has_value());
  EXPECT_EQ(*d.relative_volume_change, 7.0);
  EXPECT_NEAR(d.hausdorff, std::sqrt(3.0), 1e-12);  // the corner (2, 2, 2) to (1, 1, 1)
  // Open surfaces: no volume change.
  const DistanceReport open = mesh_distance(test::grid_patch(4, 4), test::grid_patch(3, 3), coarse());
  EXPECT_FALSE(open.relative_volume_change.has_value());
  EXPECT_NEAR(open.hausdorff, 0.0, 1e-15);
}

TEST(QualityDistance, OffsetPlanesAndThreads) {
  TriangleSoup lifted = test::grid_patch(7, 5);
  for (auto& p : lifted.points) p.z() = 0.25;
  const TriangleSoup base = test::grid_patch(3, 3);
  DistanceOptions one = coarse(0.01);
  one.n_threads = 1;
  const DistanceReport d1 = mesh_distance(lifted, base, one);
  const DistanceReport d2 = mesh_distance(lifted, base, coarse(0.01));
  EXPECT_DOUBLE_EQ(d1.hausdorff, 0.25);
  EXPECT_DOUBLE_EQ(d1.mean, 0.25);
  EXPECT_EQ(d1.hausdorff, d2.hausdorff);
  EXPECT_EQ(d1.mean, d2.mean);
  EXPECT_EQ(d1.n_mesh_samples, d2.n_mesh_samples);
}

TEST(QualityDistance, ReportWithReference) {
  ReportOptions options;
  options.distance = coarse();
  const MeshReport r = mesh_report(test::icosphere(2), test::icosphere(2), options);
  ASSERT_TRUE(r.distance.has_value());
  EXPECT_LE(r.distance->hausdorff, 1e-14);
  EXPECT_THROW((void)mesh_distance(TriangleSoup{}, test::cube()), InvalidInput);
}

}  // namespace
}  // namespace nurbsfront
