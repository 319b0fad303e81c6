// SPDX-License-Identifier: BSD-3-Clause
// clean(): exact counts on small hand-made soups, and the grid-hash weld against a
// brute-force reference on random clustered points.
#include <gtest/gtest.h>

#include <random>

#include "fixtures/shapes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/io/mesh_io.h"

namespace nurbsfront {
namespace {

using Tri = std::array<std::uint32_t, 3>;

//! Two triangles of the unit square, the second with its own copies of the shared points.
TriangleSoup split_square(double offset) {
  TriangleSoup s;
  s.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0 + offset, 0, 0}, {1, 1 + offset, 0}, {0, 1, 0}};
  s.triangles = {{0, 1, 2}, {3, 4, 5}};
  return s;
}

TEST(Clean, DuplicateVerticesWithinToleranceAreMerged) {
  // diagonal sqrt(2); default tolerance 1e-10 * sqrt(2): 1e-12 is inside, 1e-6 outside
  const CleanResult near = clean(split_square(1e-12));
  EXPECT_EQ(near.report.n_welded_vertices, 2u);
  EXPECT_EQ(near.report.n_degenerate_faces, 0u);
  ASSERT_EQ(near.soup.points.size(), 4u);
  EXPECT_EQ(near.soup.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(near.soup.triangles[1], (Tri{0, 2, 3}));  // first occurrence kept, input order
  EXPECT_TRUE(check_manifold(near.soup).ok());

  const CleanResult far = clean(split_square(1e-6));
  EXPECT_EQ(far.report.n_welded_vertices, 0u);
  EXPECT_EQ(far.soup.points.size(), 6u);

  CleanOptions wide;
  wide.weld_tolerance_relative = 1e-5;
  EXPECT_EQ(clean(split_square(1e-6), wide).report.n_welded_vertices, 2u);
}

TEST(Clean, ExactWeldingWithZeroTolerance) {
  TriangleSoup s = split_square(0.0);
  s.points[3] = Eigen::Vector3d(-0.0, 0.0, -0.0);  // equal to +0
  CleanOptions exact;
  exact.weld_tolerance_relative = 0.0;
  EXPECT_EQ(clean(s, exact).report.n_welded_vertices, 2u);
  EXPECT_EQ(clean(split_square(1e-15), exact).report.n_welded_vertices, 0u);
}

TEST(Clean, CollapsedTriangleIsDropped) {
  TriangleSoup s = split_square(0.0);
  s.points.emplace_back(1.0, 1e-13, 0.0);  // welds onto point 1
  s.triangles.push_back({1, 6, 2});        // collapses to an edge after welding
  s.triangles.push_back({2, 2, 0});        // names a vertex twice in the input
  const CleanResult r = clean(s);
  EXPECT_EQ(r.report.n_welded_vertices, 3u);
  EXPECT_EQ(r.report.n_degenerate_faces, 2u);
  EXPECT_EQ(r.soup.triangles.size(), 2u);
  EXPECT_EQ(r.soup.points.size(), 4u);

  CleanOptions keep;
  keep.drop_degenerate = false;
  EXPECT_EQ(clean(s, keep).soup.triangles.size(), 4u);
}

TEST(Clean, CollinearTriangleIsKeptAndCounted) {
  TriangleSoup s;
  s.points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  s.triangles = {{0, 1, 2}};
  const CleanResult r = clean(s);
  EXPECT_EQ(r.report.n_collinear_faces, 1u);
  EXPECT_EQ(r.report.n_degenerate_faces, 0u);
  EXPECT_EQ(r.soup.triangles.size(), 1u);
}

TEST(Clean, DuplicateFacesAreDroppedInAnyOrderOrOrientation) {
  TriangleSoup s = test::tetrahedron();
  const std::size_t n = s.triangles.size();
  const Tri t = s.triangles[1];
  s.triangles.push_back({t[1], t[2], t[0]});  // same, rotated
  s.triangles.push_back({t[0], t[2], t[1]});  // same vertices, flipped
  const CleanResult r = clean(s);
  EXPECT_EQ(r.report.n_duplicate_faces, 2u);
  EXPECT_EQ(r.soup.triangles.size(), n);
  EXPECT_EQ(r.soup.triangles[1], t);
  EXPECT_TRUE(check_manifold(r.soup).ok());

  CleanOptions keep;
  keep.drop_duplicate_faces = false;
  EXPECT_EQ(clean(s, keep).soup.triangles.size(), n + 2);
}

TEST(Clean, UnreferencedVertexIsDroppedAndIndicesRenumbered) {
  TriangleSoup s;
  s.points = {{5, 5, 5}, {0, 0, 0}, {1, 0, 0}, {9, 9, 9}, {0, 1, 0}};
  s.triangles = {{1, 2, 4}};
  const CleanResult r = clean(s);
  EXPECT_EQ(r.report.n_unreferenced_vertices, 2u);
  ASSERT_EQ(r.soup.points.size(), 3u);
  EXPECT_EQ(r.soup.points[0], Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(r.soup.triangles[0], (Tri{0, 1, 2}));

  CleanOptions keep;
  keep.drop_unreferenced = false;
  const CleanResult k = clean(s, keep);
  EXPECT_EQ(k.soup.points.size(), 5u);
  EXPECT_EQ(k.report.n_unreferenced_vertices, 0u);
  EXPECT_EQ(k.soup.triangles[0], (Tri{1, 2, 4}));
}

TEST(Clean, CleanSoupIsUnchanged) {
  const TriangleSoup s = test::torus(16, 8);
  const CleanResult r = clean(s);
  EXPECT_EQ(r.soup.points, s.points);
  EXPECT_EQ(r.soup.triangles, s.triangles);
  EXPECT_EQ(r.report.n_welded_vertices + r.report.n_degenerate_faces + r.report.n_duplicate_faces +
                r.report.n_unreferenced_vertices,
            0u);
}

TEST(Clean, GridHashWeldMatchesBruteForce) {
  // Clusters of points at distances around the tolerance: the hashed weld must merge each
  // point into the lowest-index earlier representative within the tolerance, exactly as
  // the quadratic reference does.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> centre(0.0, 1.0);
  std::uniform_real_distribution<double> jitter(-1.5e-3, 1.5e-3);
  TriangleSoup s;
  for (int c = 0; c < 60; ++c) {
    const Eigen::Vector3d p(centre(rng), centre(rng), centre(rng));
    for (int k = 0; k < 8; ++k) s.points.push_back(p + Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng)));
  }
  s.points.emplace_back(0, 0, 0);
  s.points.emplace_back(1, 1, 1);  // fixes the bbox diagonal to sqrt(3)
  CleanOptions options;
  options.weld_tolerance_relative = 1e-3;
  options.drop_unreferenced = false;
  const double tol = options.weld_tolerance_relative * std::sqrt(3.0);
  std::vector<std::size_t> reps;
  std::size_t n_welded = 0;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    bool merged = false;
    for (const std::size_t j : reps) {
      if ((s.points[j] - s.points[i]).norm() <= tol) {
        merged = true;
        break;
      }
    }
    if (merged) {
      ++n_welded;
    } else {
      reps.push_back(i);
    }
  }
  const CleanResult r = clean(s, options);
  EXPECT_GT(n_welded, 0u);
  EXPECT_GT(reps.size(), 62u);  // some cluster members stay apart: a real test of the boundary
  EXPECT_EQ(r.report.n_welded_vertices, n_welded);
  ASSERT_EQ(r.soup.points.size(), reps.size());
  for (std::size_t k = 0; k < reps.size(); ++k) EXPECT_EQ(r.soup.points[k], s.points[reps[k]]);
}

//! A grid of n x n squares of side 1/128 (every coordinate exact in binary) as a raw soup with everything clean() removes:
//! each square's second triangle has its own copies of its points (welded), every 7th
//! square repeats its first triangle reversed (a duplicate), every 11th has an extra
//! triangle naming one point twice after welding (collapsed), every 13th one with three
//! collinear corners (kept and counted), and points no triangle uses (unreferenced).
TriangleSoup dirty_grid(int n) {
  TriangleSoup s;
  const double h = 1.0 / 128.0;
  auto add = [&](double x, double y) {
    s.points.emplace_back(x, y, 0.25 * y * y);  // z by y alone: points of one y are collinear
    return static_cast<std::uint32_t>(s.points.size() - 1);
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = i * h, y = j * h;
      const std::uint32_t a = add(x, y), b = add(x + h, y), c = add(x + h, y + h);
      s.triangles.push_back({a, b, c});
      const std::uint32_t a2 = add(x, y), c2 = add(x + h, y + h), d = add(x, y + h);
      s.triangles.push_back({a2, c2, d});
      const int k = j * n + i;
      if (k % 7 == 0) s.triangles.push_back({c, b, a});
      if (k % 11 == 0) s.triangles.push_back({a, a2, b});
      if (k % 13 == 0) s.triangles.push_back({a, add(x + 0.5 * h, y), b});
      if (k % 17 == 0) (void)add(x + 0.5 * h, y + 0.5 * h);
    }
  }
  return s;
}

TEST(Clean, SameResultForAnyThreadCount) {
  // More points and triangles than one parallel chunk (16384): each count and every index
  // of the result is the same for 1, 2 and 3 threads, and the counts are the grid's.
  const int n = 90;
  const TriangleSoup s = dirty_grid(n);
  ASSERT_GT(s.points.size(), 2u * 16384u);
  CleanOptions one;
  one.threads = 1;
  const CleanResult serial = clean(s, one);
  const std::size_t squares = static_cast<std::size_t>(n) * n;
  EXPECT_EQ(serial.soup.points.size(), static_cast<std::size_t>((n + 1) * (n + 1)) + (squares + 12) / 13);
  EXPECT_EQ(serial.report.n_duplicate_faces, (squares + 6) / 7);
  EXPECT_EQ(serial.report.n_degenerate_faces, (squares + 10) / 11);
  EXPECT_EQ(serial.report.n_collinear_faces, (squares + 12) / 13);
  EXPECT_EQ(serial.report.n_unreferenced_vertices, (squares + 16) / 17);
  EXPECT_EQ(serial.soup.triangles.size(), 2 * squares + (squares + 12) / 13);
  for (const int threads : {2, 3}) {
    CleanOptions options;
    options.threads = threads;
    const CleanResult parallel = clean(s, options);
    EXPECT_EQ(parallel.soup.points, serial.soup.points) << threads;
    EXPECT_EQ(parallel.soup.triangles, serial.soup.triangles) << threads;
    EXPECT_EQ(parallel.report.n_welded_vertices, serial.report.n_welded_vertices);
    EXPECT_EQ(parallel.report.n_degenerate_faces, serial.report.n_degenerate_faces);
    EXPECT_EQ(parallel.report.n_duplicate_faces, serial.report.n_duplicate_faces);
    EXPECT_EQ(parallel.report.n_unreferenced_vertices, serial.report.n_unreferenced_vertices);
    EXPECT_EQ(parallel.report.n_collinear_faces, serial.report.n_collinear_faces);
  }
}

TEST(Clean, FirstBadElementIsReportedForAnyThreadCount) {
  // Bad elements in two chunks: the error names the first one whatever the thread count.
  TriangleSoup s = dirty_grid(90);
  s.points[40000].y() = std::numeric_limits<double>::quiet_NaN();
  s.points[20000].x() = std::numeric_limits<double>::infinity();
  s.triangles[18000][1] = 999999999;
  s.triangles[3000][2] = 888888888;
  for (const int threads : {1, 2, 3}) {
    CleanOptions options;
    options.threads = threads;
    try {
      (void)clean(s, options);
      ADD_FAILURE() << "no error";
    } catch (const InvalidInput& e) {
      EXPECT_STREQ(e.what(), "clean: point 20000 is not finite") << threads;
    }
    TriangleSoup finite = s;
    finite.points[40000].y() = 0.0;
    finite.points[20000].x() = 0.0;
    try {
      (void)clean(finite, options);
      ADD_FAILURE() << "no error";
    } catch (const InvalidInput& e) {
      EXPECT_STREQ(e.what(), "clean: triangle 3000 has out-of-range index 888888888") << threads;
    }
  }
}

TEST(Clean, RejectsBadInputAndOptions) {
  CleanOptions bad;
  bad.weld_tolerance_relative = -1.0;
  EXPECT_THROW(bad.validate(), InvalidInput);
  EXPECT_THROW((void)clean(test::cube(), bad), InvalidInput);
  bad.weld_tolerance_relative = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(bad.validate(), InvalidInput);
  CleanOptions bad_threads;
  bad_threads.threads = -1;
  EXPECT_THROW(bad_threads.validate(), InvalidInput);
  TriangleSoup s = test::cube();
  s.triangles.push_back({0, 1, 99});
  EXPECT_THROW((void)clean(s), InvalidInput);
  s = test::cube();
  s.points[0].x() = std::numeric_limits<double>::infinity();
  EXPECT_THROW((void)clean(s), InvalidInput);
}

}  // namespace
}  // namespace nurbsfront
