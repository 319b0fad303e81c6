// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "fixtures/shapes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/quality/internal.h"
#include "nurbsfront/quality/predicates.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/quality/self_intersection.h"

namespace nurbsfront {
namespace {

using V = Eigen::Vector3d;
using V2 = Eigen::Vector2d;
using Tri = std::array<std::uint32_t, 3>;

TEST(QualityPredicates, Orient3dSigns) {
  const V a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(quality_detail::orient3d(a, b, c, V(0, 0, -1)), 1);  // below the ccw plane
  EXPECT_EQ(quality_detail::orient3d(a, b, c, V(0, 0, 1)), -1);
  EXPECT_EQ(quality_detail::orient3d(a, b, c, V(0.3, 0.3, 0)), 0);
}

TEST(QualityPredicates, NearlyDegenerateCasesAreExact) {
  // Kettner et al.'s classroom example: p = (0.5 + i u, 0.5 + j u), u = 2^-53, against the
  // line through (12, 12) and (24, 24). The exact sign is sign(p.y - p.x); the naive
  // floating-point determinant gets many of these wrong.
  const double u = std::ldexp(1.0, -53);
  const V2 q(12, 12), r(24, 24);
  const V q3(12, 12, 0), r3(24, 24, 0), s3(12, 12, 1);  // the plane x = y
  const int side = quality_detail::orient3d(q3, r3, s3, V(0, 1, 0));
  ASSERT_NE(side, 0);
  for (int i = 0; i < 16; ++i) {
    for (int j = 0; j < 16; ++j) {
      const V2 p(0.5 + i * u, 0.5 + j * u);
      const int expected = (j > i) - (j < i);
      EXPECT_EQ(quality_detail::orient2d(p, q, r), expected) << i << ' ' << j;
      EXPECT_EQ(quality_detail::orient3d(q3, r3, s3, V(p.x(), p.y(), 0.3)), expected * side) << i << ' ' << j;
    }
  }
  // Large translation: differences are inexact in floating point.
  const double big = 1e15;
  EXPECT_EQ(quality_detail::orient3d(V(big, 0, 0), V(big + 1, 0, 0), V(big, 1, 0), V(big + 0.5, 0.25, 1e-300)), -1);
  EXPECT_EQ(quality_detail::orient3d(V(big, 0, 0), V(big + 1, 0, 0), V(big, 1, 0), V(big + 0.5, 0.25, -1e-300)), 1);
}

TEST(QualityPredicates, AxisAlignedPlanesAndLinesAreExactlyDegenerate) {
  // Points sharing one coordinate (the axis-aligned faces of marching cubes on label
  // volumes) are coplanar / collinear; one ulp off that coordinate they are not.
  const double x = 0.617188 * 129.5, big = 1e15;
  const V a(x, 0.1, 0.3), b(x, big, -7.25), c(x, -3.0, big);
  EXPECT_EQ(quality_detail::orient3d(a, b, c, V(x, 1e-300, 2.5)), 0);
  const double next = std::nextafter(x, 2 * x);
  const int off = quality_detail::orient3d(a, b, c, V(next, 1e-300, 2.5));
  EXPECT_NE(off, 0);
  EXPECT_EQ(quality_detail::orient3d(a, b, c, V(std::nextafter(x, 0.0), 1e-300, 2.5)), -off);
  const V2 p(x, 0.1), q(x, big), r(x, -3.0);
  EXPECT_EQ(quality_detail::orient2d(p, q, r), 0);
  EXPECT_EQ(quality_detail::orient2d(V2(0.1, x), V2(big, x), V2(-3.0, x)), 0);
  EXPECT_NE(quality_detail::orient2d(p, q, V2(next, -3.0)), 0);
}

TEST(QualityPredicates, SegmentTriangle) {
  const V p(0, 0, 0), q(1, 0, 0), r(0, 1, 0);
  EXPECT_TRUE(quality_detail::segment_meets_triangle(V(0.2, 0.2, -1), V(0.2, 0.2, 1), p, q, r));
  EXPECT_FALSE(quality_detail::segment_meets_triangle(V(0.8, 0.8, -1), V(0.8, 0.8, 1), p, q, r));
  EXPECT_TRUE(quality_detail::segment_meets_triangle(V(0.5, 0.5, -1), V(0.5, 0.5, 1), p, q, r));  // through an edge
  EXPECT_TRUE(quality_detail::segment_meets_triangle(V(0.2, 0.2, 0), V(0.2, 0.2, 1), p, q, r));   // endpoint touches
  EXPECT_FALSE(quality_detail::segment_meets_triangle(V(0.2, 0.2, 0.1), V(0.2, 0.2, 1), p, q, r));
  // Coplanar: crossing, inside, outside.
  EXPECT_TRUE(quality_detail::segment_meets_triangle(V(-1, 0.3, 0), V(2, 0.3, 0), p, q, r));
  EXPECT_TRUE(quality_detail::segment_meets_triangle(V(0.1, 0.1, 0), V(0.2, 0.1, 0), p, q, r));
  EXPECT_FALSE(quality_detail::segment_meets_triangle(V(1, 1, 0), V(2, 0.5, 0), p, q, r));
}

TEST(QualitySelfIntersection, CrossingTriangles) {
  TriangleSoup s;
  s.points = {V(0, 0, 0), V(2, 0, 0), V(0, 2, 0), V(0.5, 0.5, -1), V(0.5, 0.5, 1), V(3, 3, 0.2)};
  s.triangles = {Tri{0, 1, 2}, Tri{3, 4, 5}};
  EXPECT_EQ(count_self_intersections(s), 1u);
  EXPECT_EQ(*mesh_report(s).topology.n_self_intersecting_pairs, 1u);
  // Move the second one away: none.
  for (std::size_t i = 3; i < 6; ++i) s.points[i].z() += 5.0;
  EXPECT_EQ(count_self_intersections(s), 0u);
}

TEST(QualitySelfIntersection, TouchingAtAPointCounts) {
  // Separate vertices (different positions) but a corner of one lies inside the other.
  TriangleSoup s;
  s.points = {V(0, 0, 0), V(2, 0, 0), V(0, 2, 0), V(0.5, 0.5, 0), V(0.5, 0.5, 1), V(1, 0.5, 1)};
  s.triangles = {Tri{0, 1, 2}, Tri{3, 4, 5}};
  EXPECT_EQ(count_self_intersections(s), 1u);
}

TEST(QualitySelfIntersection, FoldOverOfTrianglesSharingAnEdge) {
  // Both triangles in z = 0 on the same side of their shared edge (0, 1).
  TriangleSoup s;
  s.points = {V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0.6, 0.3, 0)};
  s.triangles = {Tri{0, 1, 2}, Tri{1, 0, 3}};
  EXPECT_EQ(count_self_intersections(s), 1u);
  // A proper (unfolded) neighbour does not count; nor does a bent, non-coplanar one.
  s.points[3] = V(0.6, -0.3, 0);
  EXPECT_EQ(count_self_intersections(s), 0u);
  s.points[3] = V(0.6, 0.3, 0.01);
  EXPECT_EQ(count_self_intersections(s), 0u);
}

TEST(QualitySelfIntersection, TrianglesSharingAVertex) {
  TriangleSoup s;
  s.points = {V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0.5, 0.5, -0.5), V(0.5, 0.5, 0.5)};
  // Second triangle pierces the first through its edge opposite the shared vertex 0.
  s.triangles = {Tri{0, 1, 2}, Tri{0, 3, 4}};
  EXPECT_EQ(count_self_intersections(s), 1u);
  // Coplanar, overlapping wedge at the shared vertex.
  s.points[3] = V(1, 0.5, 0);
  s.points[4] = V(0.5, 1, 0);
  EXPECT_EQ(count_self_intersections(s), 1u);
  // Coplanar, only the vertex in common.
  s.points[3] = V(-1, -0.5, 0);
  s.points[4] = V(-0.5, -1, 0);
  EXPECT_EQ(count_self_intersections(s), 0u);
  // Unwelded copy of the shared vertex: same answer (positions identify corners).
  s.points.push_back(V(0, 0, 0));
  s.triangles[1][0] = 5;
  EXPECT_EQ(count_self_intersections(s), 0u);
}

TEST(QualitySelfIntersection, ClosedShapesHaveNone) {
  EXPECT_EQ(count_self_intersections(test::cube()), 0u);
  EXPECT_EQ(count_self_intersections(test::icosphere(4)), 0u);
  EXPECT_EQ(count_self_intersections(test::torus(32, 16)), 0u);
  EXPECT_EQ(count_self_intersections(test::grid_patch(20, 20)), 0u);  // many coplanar neighbours
}

TEST(QualitySelfIntersection, TwoInterpenetratingSpheres) {
  // Two spheres whose surfaces cross along a circle: many pairs, the same count with
  // one or two threads (determinism), none once they are apart.
  TriangleSoup s = test::icosphere(3);
  const TriangleSoup other = test::icosphere(3);
  const auto offset = static_cast<std::uint32_t>(s.points.size());
  for (const auto& p : other.points) s.points.push_back(p + V(0.93, 0.11, 0.07));
  for (const auto& t : other.triangles) s.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const std::size_t n1 = count_self_intersections(s, 1);
  EXPECT_GT(n1, 20u);
  EXPECT_EQ(count_self_intersections(s, 2), n1);
  EXPECT_EQ(count_self_intersections(s, 3), n1);
  for (std::size_t i = offset; i < s.points.size(); ++i) s.points[i].x() += 2.5;
  EXPECT_EQ(count_self_intersections(s, 2), 0u);
}

TEST(QualitySelfIntersection, PlantedIntersectionInClosedMesh) {
  // Push one vertex of an icosphere through the opposite side of the sphere.
  TriangleSoup s = test::icosphere(2);
  s.points[0] = -1.5 * s.points[0];
  const std::size_t n = count_self_intersections(s);
  EXPECT_GT(n, 0u);
  EXPECT_TRUE(mesh_report(s).topology.is_closed);  // topology alone does not see it
}

TEST(QualitySelfIntersection, PairsOfSubsetMatchTheGlobalPairs) {
  // Two interpenetrating spheres: the pairs involving a chosen set of faces are exactly
  // the global pairs with a face in the set (subset faces on both sides, one side, none).
  TriangleSoup s = test::icosphere(3);
  const TriangleSoup other = test::icosphere(3);
  const auto offset = static_cast<std::uint32_t>(s.points.size());
  const auto n_first = static_cast<std::uint32_t>(s.triangles.size());
  for (const auto& p : other.points) s.points.push_back(p + V(0.93, 0.11, 0.07));
  for (const auto& t : other.triangles) s.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const auto all = self_intersecting_pairs(s, 2);
  ASSERT_GT(all.size(), 20u);
  // Every third face of the first sphere, and every fifth of the second, some repeated.
  std::vector<std::uint32_t> subset;
  std::vector<char> chosen(s.triangles.size(), 0);
  for (std::uint32_t f = 0; f < s.triangles.size(); ++f) {
    if ((f < n_first && f % 3 == 0) || (f >= n_first && f % 5 == 0)) {
      subset.push_back(f);
      subset.push_back(f);
      chosen[f] = 1;
    }
  }
  std::vector<std::array<std::uint32_t, 2>> expected;
  for (const auto& p : all) {
    if (chosen[p[0]] != 0 || chosen[p[1]] != 0) expected.push_back(p);
  }
  ASSERT_FALSE(expected.empty());
  ASSERT_LT(expected.size(), all.size());
  EXPECT_EQ(intersecting_pairs_of(s, subset), expected);
  std::vector<std::uint32_t> everything(s.triangles.size());
  for (std::uint32_t f = 0; f < everything.size(); ++f) everything[f] = f;
  EXPECT_EQ(intersecting_pairs_of(s, everything), all);
  EXPECT_TRUE(intersecting_pairs_of(s, {}).empty());
  EXPECT_TRUE(intersecting_pairs_of(test::icosphere(3), {0, 1, 2}).empty());
  EXPECT_THROW((void)intersecting_pairs_of(s, {static_cast<std::uint32_t>(s.triangles.size())}), InvalidInput);
}

TEST(QualitySelfIntersection, PairsOfALocalSubsetOfAnUnweldedSoup) {
  // Two interpenetrating spheres with every triangle on its own three points (neighbours
  // share corners only by position) and a face with two corners at one position far from
  // the subset: the pairs of a subset in a small region (its box holds a few of the
  // soup's points) are the global pairs with a face in it; a neighbour of a subset face
  // touching it along an edge is no pair.
  TriangleSoup welded = test::icosphere(3);
  const TriangleSoup other = test::icosphere(3);
  const auto offset = static_cast<std::uint32_t>(welded.points.size());
  for (const auto& p : other.points) welded.points.push_back(p + V(0.93, 0.11, 0.07));
  for (const auto& t : other.triangles) welded.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  TriangleSoup s;
  for (const auto& t : welded.triangles) {
    const auto first = static_cast<std::uint32_t>(s.points.size());
    for (const std::uint32_t v : t) s.points.push_back(welded.points[v]);
    s.triangles.push_back({first, first + 1, first + 2});
  }
  const auto far = static_cast<std::uint32_t>(s.points.size());
  s.points.push_back(V(-0.9, 0.0, 0.0));
  s.points.push_back(V(-0.9, 0.0, 0.0));
  s.points.push_back(V(-0.9, 0.3, 0.0));
  s.triangles.push_back({far, far + 1, far + 2});
  const auto all = self_intersecting_pairs(s, 1);
  ASSERT_EQ(all, self_intersecting_pairs(welded, 1));  // the same pairs, welded or not
  // The faces with a corner within 0.3 of the first crossing pair's first corner.
  ASSERT_FALSE(all.empty());
  const V centre = s.points[s.triangles[all.front()[0]][0]];
  std::vector<std::uint32_t> subset;
  std::vector<char> chosen(s.triangles.size(), 0);
  for (std::uint32_t f = 0; f < s.triangles.size(); ++f) {
    for (const std::uint32_t v : s.triangles[f]) {
      if ((s.points[v] - centre).norm() < 0.3 && chosen[f] == 0) {
        subset.push_back(f);
        chosen[f] = 1;
      }
    }
  }
  ASSERT_LT(subset.size(), s.triangles.size() / 10);
  std::vector<std::array<std::uint32_t, 2>> expected;
  for (const auto& p : all) {
    if (chosen[p[0]] != 0 || chosen[p[1]] != 0) expected.push_back(p);
  }
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(intersecting_pairs_of(s, subset, 1), expected);
  EXPECT_EQ(intersecting_pairs_of(s, subset, 2), expected);
  EXPECT_TRUE(intersecting_pairs_of(s, {far / 3}, 1).empty());  // degenerate: skipped
}

TEST(QualitySelfIntersection, PairsOfDoNotDependOnTheThreadCount) {
  // Two overlapping spheres of 5120 faces each: the soup's faces span several chunks.
  TriangleSoup s = test::icosphere(4);
  const TriangleSoup other = test::icosphere(4);
  const auto offset = static_cast<std::uint32_t>(s.points.size());
  for (const auto& p : other.points) s.points.push_back(p + V(0.93, 0.11, 0.07));
  for (const auto& t : other.triangles) s.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const auto all = self_intersecting_pairs(s, 1);
  ASSERT_GT(all.size(), 50u);
  std::vector<std::uint32_t> subset, everything(s.triangles.size());
  for (std::uint32_t f = 0; f < s.triangles.size(); ++f) {
    everything[f] = f;
    if (f % 7 == 0) subset.push_back(f);
  }
  const auto one = intersecting_pairs_of(s, subset, 1);
  ASSERT_FALSE(one.empty());
  for (const unsigned threads : {2U, 3U}) {
    EXPECT_EQ(intersecting_pairs_of(s, subset, threads), one) << threads;
    EXPECT_EQ(intersecting_pairs_of(s, everything, threads), all) << threads;
  }
  EXPECT_THROW((void)intersecting_pairs_of(s, subset, 0), InvalidInput);
}

TEST(QualityBoxGrid, VisitsExactlyTheOverlappingBoxesOnce) {
  // 400 small boxes in 4 clusters far apart (a grid over the whole span, mostly empty
  // cells), some of them points or flat, queried by 300 boxes of every size, touching ones
  // included: every box that meets the query (closed, exact comparison) is visited, once,
  // and no other (brute force).
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const std::array<V, 4> centre{V(0, 0, 0), V(50, 0, 0), V(0, 40, 10), V(30, 30, 30)};
  std::vector<V> lo, hi;
  for (int i = 0; i < 400; ++i) {
    const V c = centre[static_cast<std::size_t>(i % 4)] + V(unit(random), unit(random), unit(random)) * 4.0;
    V size = V(unit(random), unit(random), unit(random)) * 0.5;
    if (i % 10 == 0) size = V::Zero();   // a point
    if (i % 10 == 1) size.z() = 0.0;     // flat
    lo.push_back(c);
    hi.push_back(c + size);
  }
  const quality_detail::BoxGrid grid(lo, hi);
  const auto& n = grid.dimensions();
  ASSERT_GT(n[0] * n[1] * n[2], 100);  // a real grid, not one cell
  std::vector<std::pair<V, V>> queries;
  for (int q = 0; q < 300; ++q) {
    const V c = centre[static_cast<std::size_t>(q % 4)] + V(unit(random), unit(random), unit(random)) * 5.0 - V::Constant(0.5);
    const double scale = q % 3 == 0 ? 0.05 : (q % 3 == 1 ? 1.0 : 20.0);
    queries.emplace_back(c, c + V(unit(random), unit(random), unit(random)) * scale);
  }
  // Boxes touching an item's box at its corner and along a face, and one outside the grid.
  queries.emplace_back(hi[5], hi[5] + V(1, 1, 1));
  queries.emplace_back(V(lo[6].x() - 1.0, lo[6].y(), lo[6].z()), V(lo[6].x(), hi[6].y(), hi[6].z()));
  queries.emplace_back(V(-100, -100, -100), V(-90, -90, -90));
  std::size_t n_found = 0;
  for (const auto& [qlo, qhi] : queries) {
    std::vector<int> visits(lo.size(), 0);
    grid.for_each_overlapping(qlo, qhi, [&](std::uint32_t i) { ++visits[i]; });
    for (std::size_t i = 0; i < lo.size(); ++i) {
      const bool meets = (lo[i].array() <= qhi.array()).all() && (qlo.array() <= hi[i].array()).all();
      EXPECT_EQ(visits[i], meets ? 1 : 0) << i;
      n_found += meets ? 1 : 0;
    }
  }
  EXPECT_GT(n_found, 300u);
  // Every point of an item's box is in an occupied cell; far from every box, none is.
  for (std::size_t i = 0; i < lo.size(); ++i) {
    EXPECT_TRUE(grid.is_occupied(lo[i]));
    EXPECT_TRUE(grid.is_occupied(0.5 * (lo[i] + hi[i])));
    EXPECT_TRUE(grid.is_occupied(hi[i]));
  }
  EXPECT_FALSE(grid.is_occupied(V(25, 20, 15)));
}

TEST(QualityBoxGrid, FlatAndSingleBoxes) {
  // All boxes in the plane z = 1 (the grid has one cell along z), one box, no box.
  std::vector<V> lo, hi;
  for (int i = 0; i < 20; ++i) {
    lo.emplace_back(i, 0.5 * i, 1.0);
    hi.emplace_back(i + 0.5, 0.5 * i + 0.5, 1.0);
  }
  const quality_detail::BoxGrid flat(lo, hi);
  EXPECT_EQ(flat.dimensions()[2], 1);
  std::vector<std::uint32_t> seen;
  flat.for_each_overlapping(V(2.5, 0, 0), V(4.0, 10, 2), [&](std::uint32_t i) { seen.push_back(i); });
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, (std::vector<std::uint32_t>{2, 3, 4}));  // box 2 touches x = 2.5
  seen.clear();
  flat.for_each_overlapping(V(0, 0, 1.5), V(30, 30, 2), [&](std::uint32_t i) { seen.push_back(i); });
  EXPECT_TRUE(seen.empty());  // above the plane
  const quality_detail::BoxGrid one({V(1, 2, 3)}, {V(1, 2, 3)});
  int n_one = 0;
  one.for_each_overlapping(V(0, 0, 0), V(1, 2, 3), [&](std::uint32_t) { ++n_one; });
  EXPECT_EQ(n_one, 1);
  EXPECT_TRUE(one.is_occupied(V(1, 2, 3)));
  const quality_detail::BoxGrid none({}, {});
  int n_none = 0;
  none.for_each_overlapping(V(0, 0, 0), V(1, 1, 1), [&](std::uint32_t) { ++n_none; });
  EXPECT_EQ(n_none, 0);
  EXPECT_FALSE(none.is_occupied(V(0, 0, 0)));
  EXPECT_THROW(quality_detail::BoxGrid({V(0, 0, 0)}, {}), InternalError);
}

TEST(QualitySelfIntersection, PairsOfAScatteredSubsetMatchTheGlobalPairs) {
  // Two interpenetrating spheres of 5120 faces each and a subset of 1 face in 40 spread
  // over both (its box is the whole soup's; the grid leaves most faces in empty cells): the
  // pairs are the global pairs with a face in the subset.
  TriangleSoup s = test::icosphere(4);
  const TriangleSoup other = test::icosphere(4);
  const auto offset = static_cast<std::uint32_t>(s.points.size());
  for (const auto& p : other.points) s.points.push_back(p + V(0.93, 0.11, 0.07));
  for (const auto& t : other.triangles) s.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const auto all = self_intersecting_pairs(s, 1);
  std::vector<std::uint32_t> subset;
  std::vector<char> chosen(s.triangles.size(), 0);
  for (std::uint32_t f = 0; f < s.triangles.size(); f += 40) {
    subset.push_back(f);
    chosen[f] = 1;
  }
  // And every face of the first crossing pair's first face's ring of crossings.
  ASSERT_FALSE(all.empty());
  subset.push_back(all.front()[0]);
  chosen[all.front()[0]] = 1;
  std::vector<std::array<std::uint32_t, 2>> expected;
  for (const auto& p : all) {
    if (chosen[p[0]] != 0 || chosen[p[1]] != 0) expected.push_back(p);
  }
  ASSERT_GE(expected.size(), 5u);
  EXPECT_EQ(intersecting_pairs_of(s, subset, 1), expected);
  EXPECT_EQ(intersecting_pairs_of(s, subset, 2), expected);
}

}  // namespace
}  // namespace nurbsfront
