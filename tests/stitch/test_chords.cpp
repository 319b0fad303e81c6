// SPDX-License-Identifier: BSD-3-Clause
// Chord compensation (stitch_detail::compensate_chords) on an icosphere: nodes on the unit
// sphere, flat triangles inside it; the moves give the chords' volume back.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <numeric>
#include <vector>

#include "fixtures/shapes.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/stitch/stitch_internal.h"

namespace nurbsfront {
namespace {

struct Sphere {
  TriMesh mesh;
  std::vector<int> vertex_node;
  std::vector<std::uint8_t> feature;
};

Sphere icosphere_mesh(int subdivisions) {
  Sphere s;
  s.mesh = to_trimesh(test::icosphere(subdivisions));
  s.vertex_node.resize(s.mesh.n_vertices());
  std::iota(s.vertex_node.begin(), s.vertex_node.end(), 0);
  s.feature.assign(s.mesh.n_vertices(), 0);
  return s;
}

double mean_edge(const TriMesh& mesh) {
  double sum = 0.0;
  for (auto e : mesh.edges()) sum += mesh.calc_edge_length(e);
  return sum / static_cast<double>(mesh.n_edges());
}

TEST(ChordCompensation, IcosphereGetsItsVolumeBack) {
  constexpr double kBall = 4.0 / 3.0 * std::numbers::pi;
  Sphere s = icosphere_mesh(3);
  const double v_before = enclosed_volume(to_soup(s.mesh));
  ASSERT_LT(v_before, kBall);
  const double h = mean_edge(s.mesh);
  // A feature node stays where it is.
  s.feature[0] = 1;
  const auto p0 = s.mesh.point(s.mesh.vertex_handle(0));
  const std::size_t n_moved = stitch_detail::compensate_chords(s.mesh, s.vertex_node, s.feature, 1.0, 0.0);
  EXPECT_EQ(n_moved, s.mesh.n_vertices() - 1);
  EXPECT_EQ(s.mesh.point(s.mesh.vertex_handle(0)), p0);
  // The chords' loss (about 3 h^2 / 8 of the ball for edge h) shrinks by far more than 10x,
  // and every other node moves outwards by about h^2 / 8, within the 0.1 h cap.
  const double v_after = enclosed_volume(to_soup(s.mesh));
  EXPECT_LT(std::abs(v_after - kBall), 0.1 * (kBall - v_before));
  for (auto v : s.mesh.vertices()) {
    if (v.idx() == 0) continue;
    const double r = s.mesh.point(v).norm();
    EXPECT_GT(r - 1.0, 0.5 * h * h / 8.0) << "vertex " << v.idx();
    EXPECT_LT(r - 1.0, 2.0 * h * h / 8.0) << "vertex " << v.idx();
  }
}

TEST(ChordCompensation, OffOrInputChordsOnlyMovesNothing) {
  Sphere s = icosphere_mesh(2);
  const TriangleSoup before = to_soup(s.mesh);
  // Strength 0: nothing moves.
  EXPECT_EQ(stitch_detail::compensate_chords(s.mesh, s.vertex_node, s.feature, 0.0, 0.0), 0u);
  EXPECT_EQ(to_soup(s.mesh).points, before.points);
  // Edges no longer than the input's: the input has the same chords, nothing to give back.
  double longest = 0.0;
  for (auto e : s.mesh.edges()) longest = std::max(longest, s.mesh.calc_edge_length(e));
  EXPECT_EQ(stitch_detail::compensate_chords(s.mesh, s.vertex_node, s.feature, 1.0, longest), 0u);
  EXPECT_EQ(to_soup(s.mesh).points, before.points);
}

}  // namespace
}  // namespace nurbsfront
