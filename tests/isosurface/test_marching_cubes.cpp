// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include <Eigen/Geometry>

#include "isosurface/surface_checks.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/isosurface/marching_cubes.h"

namespace nurbsfront {
namespace {

ScalarGrid make_grid(int nx, int ny, int nz, float fill = 0.0f) {
  ScalarGrid g;
  g.dims = {nx, ny, nz};
  g.values.assign(g.size(), fill);
  return g;
}

// The 2x2x2 grid whose corner c (offset (c&1, c>>1&1, c>>2&1)) is inside iff bit c of mask.
ScalarGrid cube_case(unsigned mask) {
  ScalarGrid g = make_grid(2, 2, 2);
  for (int c = 0; c < 8; ++c) g.values[g.index(c & 1, (c >> 1) & 1, (c >> 2) & 1)] = ((mask >> c) & 1) ? -1.0f : 1.0f;
  return g;
}

TEST(MarchingCubesTable, EveryCaseUsesEachCutEdgeAndOrientsOutward) {
  // The per-face rule gives each cut edge exactly one loop; triangles use exactly the cut edges.
  for (unsigned mask = 0; mask < 256; ++mask) {
    const MarchingCubesCase& c = marching_cubes_case(static_cast<std::uint8_t>(mask));
    std::set<int> cut, used;
    for (int e = 0; e < 12; ++e) {
      const int axis = e / 4, r = e % 4;
      const int lo = axis == 0 ? ((r & 1) << 1 | (r >> 1) << 2) : axis == 1 ? ((r & 1) | (r >> 1) << 2) : ((r & 1) | (r >> 1) << 1);
      const int hi = lo | (1 << axis);
      if (((mask >> lo) & 1) != ((mask >> hi) & 1)) cut.insert(e);
    }
    for (int t = 0; t < c.n_triangles; ++t) {
      for (int k = 0; k < 3; ++k) used.insert(c.triangles[t][k]);
    }
    EXPECT_EQ(cut, used) << "case " << mask;
    if (mask == 0 || mask == 255) {
      EXPECT_EQ(c.n_triangles, 0) << mask;
    }
  }
}

TEST(MarchingCubes, SingleInsideCornerGivesOneOutwardTriangle) {
  ScalarGrid g = make_grid(2, 2, 2, -1.0f);
  g.values[g.index(0, 0, 0)] = 1.0f;  // inside above 0
  MarchingCubesOptions o;
  o.inside_above = true;
  const TriangleSoup s = marching_cubes(g, o);
  ASSERT_EQ(s.triangles.size(), 1u);
  ASSERT_EQ(s.points.size(), 3u);
  for (const auto& p : s.points) EXPECT_NEAR(p.sum(), 0.5, 1e-12);  // each cut at the middle of its edge
  const auto& t = s.triangles[0];
  const Eigen::Vector3d n = (s.points[t[1]] - s.points[t[0]]).cross(s.points[t[2]] - s.points[t[0]]);
  EXPECT_GT(n.dot(Eigen::Vector3d(1, 1, 1)), 0.0);  // points away from the inside corner
}

TEST(MarchingCubes, DiagonalInsideCornersOnAFaceAreSeparated) {
  // Corners 0 = (0,0,0) and 3 = (1,1,0) inside: the rule separates inside corners -> 2 triangles.
  const TriangleSoup two = marching_cubes(cube_case(0b00001001));
  EXPECT_EQ(two.triangles.size(), 2u);
  EXPECT_EQ(two.points.size(), 6u);
  // The complement: outside corners 0 and 3 are then joined through the face -> one hexagon loop.
  const TriangleSoup hexagon = marching_cubes(cube_case(0b11110110));
  EXPECT_EQ(hexagon.triangles.size(), 4u);
  EXPECT_EQ(hexagon.points.size(), 6u);
  test::expect_clean_surface(hexagon, false, "hexagon");
}

TEST(MarchingCubes, EveryCubeCaseIsClosedWhenPadded) {
  for (unsigned mask = 1; mask < 256; ++mask) {
    MarchingCubesOptions o;
    o.pad = true;
    const TriangleSoup s = marching_cubes(cube_case(mask), o);
    const auto f = test::expect_clean_surface(s, true, "case " + std::to_string(mask));
    if (HasFailure()) return;
    (void)f;
  }
}

TEST(MarchingCubes, IntegerGridWithExactIsoHasNoDegenerateTriangles) {
  // Values in {0, 1, 2} with iso 1: many samples equal the iso-value exactly.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> value(0, 2);
  ScalarGrid g = make_grid(12, 10, 9);
  for (auto& v : g.values) v = static_cast<float>(value(rng));
  for (const bool inside_above : {false, true}) {
    for (const bool pad : {false, true}) {
      MarchingCubesOptions o;
      o.iso = 1.0;
      o.inside_above = inside_above;
      o.pad = pad;
      const TriangleSoup s = marching_cubes(g, o);
      EXPECT_FALSE(s.triangles.empty());
      test::expect_clean_surface(s, pad, "integer grid");
    }
  }
}

TEST(MarchingCubes, ThousandsOfRandomGridsAreManifoldAndClosedWhenPadded) {
  std::mt19937 rng(12345);
  std::uniform_int_distribution<int> dim(2, 5), level(-2, 2), coin(0, 1);
  std::uniform_real_distribution<float> real(-1.0f, 1.0f);
  for (int trial = 0; trial < 3000; ++trial) {
    ScalarGrid g = make_grid(dim(rng), dim(rng), dim(rng));
    const bool integer = coin(rng) == 1;
    for (auto& v : g.values) v = integer ? static_cast<float>(level(rng)) : real(rng);
    MarchingCubesOptions o;
    o.inside_above = coin(rng) == 1;
    o.pad = coin(rng) == 1;
    const TriangleSoup s = marching_cubes(g, o);
    test::expect_clean_surface(s, o.pad, "random grid " + std::to_string(trial));
    if (HasFailure()) return;  // one report is enough
  }
}

TEST(MarchingCubes, SurfaceLeavingTheGridIsOpenUnlessPadded) {
  // A half-space z < 1.5 through a 4^3 grid: an open square sheet, or a closed box when padded.
  ScalarGrid g = make_grid(4, 4, 4);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) g.values[g.index(i, j, k)] = static_cast<float>(k - 1.5);
  const auto open = test::expect_clean_surface(marching_cubes(g), false, "sheet");
  EXPECT_EQ(open.n_boundary_edges, 12u);
  EXPECT_EQ(open.euler, 1);
  MarchingCubesOptions o;
  o.pad = true;
  const TriangleSoup closed_soup = marching_cubes(g, o);
  const auto closed = test::expect_clean_surface(closed_soup, true, "padded sheet");
  EXPECT_EQ(closed.euler, 2);
  for (const auto& p : closed_soup.points) EXPECT_LE(p.z(), 1.5 + 1e-12);
}

TEST(MarchingCubes, SpacingAndOriginPlaceVertices) {
  ScalarGrid g = make_grid(2, 2, 2);
  g.origin = {10, 20, 30};
  g.spacing = {2, 3, 4};
  for (int c = 0; c < 8; ++c) g.values[c] = (c & 4) ? 1.0f : -3.0f;  // z plane at t = 0.75
  const TriangleSoup s = marching_cubes(g);
  ASSERT_EQ(s.triangles.size(), 2u);
  for (const auto& p : s.points) EXPECT_NEAR(p.z(), 30 + 0.75 * 4, 1e-12);
  // Normals point from inside (below) to outside (above).
  for (const auto& t : s.triangles) {
    EXPECT_GT((s.points[t[1]] - s.points[t[0]]).cross(s.points[t[2]] - s.points[t[0]]).z(), 0.0);
  }
}

TEST(MarchingCubes, RejectsBadInput) {
  EXPECT_THROW((void)marching_cubes(make_grid(1, 4, 4)), InvalidInput);
  ScalarGrid g = make_grid(3, 3, 3);
  g.values.pop_back();
  EXPECT_THROW((void)marching_cubes(g), InvalidInput);
  ScalarGrid nan = make_grid(3, 3, 3);
  nan.values[4] = std::nanf("");
  EXPECT_THROW((void)marching_cubes(nan), InvalidInput);
  ScalarGrid neg = make_grid(3, 3, 3);
  neg.spacing.x() = 0.0;
  EXPECT_THROW((void)marching_cubes(neg), InvalidInput);
  MarchingCubesOptions o;
  o.iso = std::numeric_limits<double>::infinity();
  EXPECT_THROW((void)marching_cubes(make_grid(3, 3, 3), o), InvalidInput);
}

TEST(MarchingCubes, ProgressCanCancel) {
  MarchingCubesOptions o;
  int calls = 0;
  o.progress = [&](std::string_view, double) { return ++calls < 2; };
  EXPECT_THROW((void)marching_cubes(make_grid(5, 5, 5), o), Cancelled);
  EXPECT_EQ(calls, 2);
}

}  // namespace
}  // namespace nurbsfront
