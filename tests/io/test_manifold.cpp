// SPDX-License-Identifier: BSD-3-Clause
// make_manifold(): hand-made non-manifold and misoriented soups (issue 6: inputs that can be
// made to work, work), checked by check_manifold() and the quality report's topology.
#include <gtest/gtest.h>

#include "fixtures/shapes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/quality/report.h"
#include "support/test_data.h"

namespace nurbsfront {
namespace {

using Tri = std::array<std::uint32_t, 3>;
using test::cube;
using test::grid_patch;
using test::torus;

TriangleSoup shifted_cube(const Eigen::Vector3d& offset) {
  TriangleSoup s = cube();
  for (auto& p : s.points) p += offset;
  return s;
}

//! The two soups in one, welded (shared positions become shared vertices).
TriangleSoup welded_union(const TriangleSoup& a, const TriangleSoup& b) {
  TriangleSoup s = a;
  const auto base = static_cast<std::uint32_t>(s.points.size());
  s.points.insert(s.points.end(), b.points.begin(), b.points.end());
  for (const Tri& t : b.triangles) s.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  return clean(s).soup;
}

TopologyReport topology(const TriangleSoup& soup) {
  ReportOptions options;
  options.self_intersections = false;
  return mesh_report(soup, options).topology;
}

//! Every component closed, oriented, a sphere, and the volume that of `n` unit cubes.
void expect_closed_unit_cubes(const TriangleSoup& soup, std::size_t n) {
  ASSERT_TRUE(check_manifold(soup).ok()) << check_manifold(soup).message();
  const TopologyReport t = topology(soup);
  EXPECT_EQ(t.n_components, n);
  EXPECT_TRUE(t.is_closed);
  EXPECT_TRUE(t.is_consistently_oriented);
  for (const auto& c : t.components) EXPECT_EQ(c.euler_characteristic, 2);
  ASSERT_TRUE(t.volume.has_value());
  EXPECT_NEAR(*t.volume, double(n), 1e-12);
}

TEST(MakeManifold, OrientedManifoldComesBackUnchanged) {
  for (const TriangleSoup& s : std::vector<TriangleSoup>{cube(), torus(12, 8), grid_patch(3, 2)}) {
    const ManifoldRepair r = make_manifold(s);
    EXPECT_EQ(r.report.n_changes(), 0u);
    EXPECT_EQ(r.soup.points, s.points);
    EXPECT_EQ(r.soup.triangles, s.triangles);
  }
}

TEST(MakeManifold, FlippedFaceTakesTheOrientationOfItsComponent) {
  TriangleSoup s = cube();
  std::swap(s.triangles[4][1], s.triangles[4][2]);
  ASSERT_FALSE(check_manifold(s).ok());
  const ManifoldRepair r = make_manifold(s);
  EXPECT_EQ(r.report.n_flipped_faces, 1u);
  EXPECT_EQ(r.report.n_split_vertices, 0u);
  EXPECT_EQ(r.soup.triangles, cube().triangles);
}

TEST(MakeManifold, InsideOutComponentIsLeftAsItIs) {
  TriangleSoup s = cube();
  for (auto& t : s.triangles) std::swap(t[1], t[2]);
  const ManifoldRepair r = make_manifold(s);
  EXPECT_EQ(r.report.n_changes(), 0u);  // consistent already: only the majority decides
  EXPECT_EQ(r.soup.triangles, s.triangles);
}

TEST(MakeManifold, CubesTouchingAtAVertexGetTwoVertices) {
  const TriangleSoup s = welded_union(cube(), shifted_cube({1, 1, 1}));
  ASSERT_EQ(s.points.size(), 15u);
  ASSERT_EQ(check_manifold(s).n_nonmanifold_vertices, 1u);
  const ManifoldRepair r = make_manifold(s);
  EXPECT_EQ(r.report.n_split_vertices, 1u);
  EXPECT_EQ(r.report.n_paired_edges, 0u);
  EXPECT_EQ(r.soup.points.size(), 16u);
  EXPECT_EQ(r.soup.points[15], Eigen::Vector3d(1, 1, 1));
  expect_closed_unit_cubes(r.soup, 2);
}

TEST(MakeManifold, CubesTouchingAlongAnEdgeArePairedByAngle) {
  // The edge x = y = 1 is shared by four faces; each cube's two faces must stay together.
  const TriangleSoup s = welded_union(cube(), shifted_cube({1, 1, 0}));
  ASSERT_EQ(s.points.size(), 14u);
  ASSERT_EQ(check_manifold(s).n_nonmanifold_edges, 1u);
  const ManifoldRepair r = make_manifold(s);
  EXPECT_EQ(r.report.n_paired_edges, 1u);
  EXPECT_EQ(r.report.n_cut_edges, 0u);
  EXPECT_EQ(r.report.n_flipped_faces, 0u);
  EXPECT_EQ(r.report.n_split_vertices, 2u);  // both ends of the edge
  expect_closed_unit_cubes(r.soup, 2);
}

TEST(MakeManifold, EdgeWithThreeFacesIsCutOpen) {
  // A fin: three triangles on the edge (0, 1); directions cannot alternate around it.
  TriangleSoup s;
  s.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  s.triangles = {Tri{0, 1, 2}, Tri{1, 0, 3}, Tri{0, 1, 4}};
  const ManifoldRepair r = make_manifold(s);
  EXPECT_EQ(r.report.n_cut_edges, 1u);
  EXPECT_EQ(r.report.n_split_vertices, 4u);  // three separate triangles
  ASSERT_TRUE(check_manifold(r.soup).ok());
  const TopologyReport t = topology(r.soup);
  EXPECT_EQ(t.n_components, 3u);
  EXPECT_EQ(t.n_boundary_edges, 9u);
}

TEST(MakeManifold, MoebiusBandIsCutWhereItCannotBeOriented) {
  // A band of 4 quads whose ends are glued with a half twist.
  TriangleSoup s;
  const int n = 4;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    s.points.emplace_back(std::cos(a), std::sin(a), -0.2);
    s.points.emplace_back(std::cos(a), std::sin(a), 0.2);
  }
  for (int i = 0; i < n; ++i) {
    std::uint32_t a = 2 * i, b = 2 * i + 1, c = 2 * (i + 1), d = 2 * (i + 1) + 1;
    if (i == n - 1) {
      c = 1;  // half twist: bottom meets top
      d = 0;
    }
    s.triangles.push_back({a, c, d});
    s.triangles.push_back({a, d, b});
  }
  const ManifoldRepair r = make_manifold(s);
  EXPECT_GE(r.report.n_nonorientable_edges, 1u);
  EXPECT_EQ(r.soup.triangles.size(), s.triangles.size());
  EXPECT_EQ(check_manifold(r.soup).n_misoriented_edges, 0u);
}

TEST(MakeManifold, RejectsAnUncleanedSoup) {
  TriangleSoup s = cube();
  s.triangles.push_back({0, 0, 1});
  EXPECT_THROW((void)make_manifold(s), InvalidInput);
  s.triangles.back() = {0, 1, 99};
  EXPECT_THROW((void)make_manifold(s), InvalidInput);
}

}  // namespace
}  // namespace nurbsfront

namespace nurbsfront {
namespace {

std::size_t count_zero_area(const TriMesh& mesh) {
  std::size_t n = 0;
  for (auto f : mesh.faces()) n += mesh.calc_face_area(f) == 0.0 ? 1 : 0;
  return n;
}

TEST(PrepareMesh, ZeroAreaTriangleIsFlippedAway) {
  const TriangleSoup s = test::needle_cube();
  ASSERT_TRUE(check_manifold(s).ok());
  const PreparedMesh p = prepare_mesh(s);
  EXPECT_EQ(p.report.n_zero_area_flipped, 1u);
  EXPECT_EQ(p.report.n_zero_area_left, 0u);
  EXPECT_EQ(count_zero_area(p.mesh), 0u);
  EXPECT_EQ(p.mesh.n_faces(), 14u);  // a flip keeps the count
  const TopologyReport t = mesh_report(to_soup(p.mesh)).topology;
  EXPECT_TRUE(t.is_closed);
  EXPECT_TRUE(t.is_consistently_oriented);
  ASSERT_TRUE(t.volume.has_value());
  EXPECT_NEAR(*t.volume, 1.0, 1e-12);
  EXPECT_EQ(t.n_self_intersecting_pairs.value_or(1), 0u);
  EXPECT_NE(p.report.summary().find("1 zero-area triangles removed by an edge flip"), std::string::npos);
}

TEST(PrepareMesh, ZeroAreaTriangleOnTheBoundaryIsDropped) {
  // The square (0,0)-(2,1) as a fan around (1, 0.5), plus the needle (0, 1, 2) on the bottom
  // side whose middle point 1 is inside the fan.
  TriangleSoup s;
  s.points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0}, {1, 0.5, 0}};
  s.triangles = {Tri{0, 1, 5}, Tri{1, 2, 5}, Tri{2, 3, 5}, Tri{3, 4, 5}, Tri{4, 0, 5}, Tri{0, 2, 1}};
  ASSERT_TRUE(check_manifold(s).ok());
  const PreparedMesh p = prepare_mesh(s);
  EXPECT_EQ(p.report.n_zero_area_dropped, 1u);
  EXPECT_EQ(p.mesh.n_faces(), 5u);
  EXPECT_EQ(count_zero_area(p.mesh), 0u);
  EXPECT_TRUE(check_manifold(to_soup(p.mesh)).ok());
}

TEST(PrepareMesh, WeldsRepairsAndNamesWhatItDid) {
  // Two cubes touching at a vertex, the second with its own copy of the shared point.
  TriangleSoup s = cube();
  TriangleSoup other = shifted_cube({1, 1, 1});
  for (auto& t : other.triangles) {
    for (auto& v : t) v += 8;
  }
  s.points.insert(s.points.end(), other.points.begin(), other.points.end());
  s.triangles.insert(s.triangles.end(), other.triangles.begin(), other.triangles.end());
  const PreparedMesh p = prepare_mesh(s);
  EXPECT_EQ(p.report.clean.n_welded_vertices, 1u);
  EXPECT_EQ(p.report.manifold.n_split_vertices, 1u);
  EXPECT_EQ(p.mesh.n_vertices(), 16u);
  EXPECT_EQ(p.report.summary(), "1 duplicate vertices welded, 1 vertices duplicated at non-manifold points");
  EXPECT_EQ(prepare_mesh(cube()).report.summary(), "nothing to repair");
  // With the manifold checks beside the builds (2 threads): the same repair and mesh.
  CleanOptions two;
  two.threads = 2;
  const PreparedMesh q = prepare_mesh(s, two);
  EXPECT_EQ(q.report.summary(), p.report.summary());
  EXPECT_EQ(to_soup(q.mesh).triangles, to_soup(p.mesh).triangles);
  EXPECT_EQ(to_soup(q.mesh).points, to_soup(p.mesh).points);
}

TEST(PrepareMesh, ReadMeshPointsToTheRepair) {
  const auto path = test::test_data("io/touching_cubes.off");
  try {
    (void)read_mesh(path);
    ADD_FAILURE() << "read_mesh accepted a non-manifold edge";
  } catch (const TopologyError& e) {
    EXPECT_NE(std::string(e.what()).find("convert --repair"), std::string::npos) << e.what();
  }
  CleanOptions two;
  two.threads = 2;
  EXPECT_THROW((void)read_mesh(path, two), TopologyError);
  const PreparedMesh p = prepare_mesh(read_soup(path));
  EXPECT_EQ(p.report.manifold.n_paired_edges, 1u);
  EXPECT_EQ(p.mesh.n_faces(), 24u);
}

TEST(PrepareMesh, WhatCannotBeRepairedIsNamed) {
  auto expect_invalid = [](const TriangleSoup& s, const std::string& word) {
    try {
      (void)prepare_mesh(s);
      ADD_FAILURE() << "no exception, expected one naming " << word;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  expect_invalid(TriangleSoup{}, "no triangles");
  TriangleSoup collapsed;
  collapsed.points = {{0, 0, 0}, {0, 0, 0}, {1, 0, 0}};
  collapsed.triangles = {Tri{0, 1, 2}};
  expect_invalid(collapsed, "collapsed");
  TriangleSoup nan = cube();
  nan.points[3].x() = std::nan("");
  expect_invalid(nan, "finite");
}

}  // namespace
}  // namespace nurbsfront
