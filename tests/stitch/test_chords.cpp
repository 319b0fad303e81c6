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

// The per-face terms run on several threads (chunks of 8192 faces: icosphere 5 has 20 480),
// their sums in face order: the same points at 1, 2 and 4 threads, bumpy sphere and some
// feature nodes included.
TEST(ChordCompensation, SamePointsAtEveryThreadCount) {
  Sphere s = icosphere_mesh(5);
  for (auto v : s.mesh.vertices()) {
    const double bump = 1.0 + 0.05 * std::sin(3.0 * v.idx()) * std::cos(0.7 * v.idx());
    s.mesh.set_point(v, s.mesh.point(v) * bump);
    s.feature[static_cast<std::size_t>(v.idx())] = v.idx() % 11 == 0 ? 1 : 0;
  }
  const double h = mean_edge(s.mesh);
  Sphere serial = s;
  const std::size_t n_serial = stitch_detail::compensate_chords(serial.mesh, serial.vertex_node, serial.feature, 1.0, 0.5 * h, 1);
  ASSERT_GT(n_serial, 1000U);  // of 5 121 (turned normals and feature corners add nothing)
  const TriangleSoup expected = to_soup(serial.mesh);
  for (const unsigned threads : {2U, 4U}) {
    Sphere t = s;
    EXPECT_EQ(stitch_detail::compensate_chords(t.mesh, t.vertex_node, t.feature, 1.0, 0.5 * h, threads), n_serial);
    EXPECT_EQ(to_soup(t.mesh).points, expected.points) << threads << " threads";
  }
}

}  // namespace
// stitch_detail::mean_over_triangle, the volume compensation's quadrature (docs/stitch.md,
// "The volume measure's quadrature"): exact for quadratics. A flat triangle with its corners
// on the paraboloid z = x^2 + y^2, over (0,0), (1,0), (0,1): the plane is z = x + y, the gap
// x + y - x^2 - y^2 has the integral 1/6 + 1/6 - 1/12 - 1/12 = 1/6 over the half-unit
// triangle, so its mean is 1/3.
TEST(VolumeQuadrature, ExactForAFlatTriangleOverAParaboloid) {
  const Eigen::Vector3d a(0.0, 0.0, 0.0), b(1.0, 0.0, 1.0), c(0.0, 1.0, 1.0);
  auto gap = [](const Eigen::Vector3d& p) { return p.z() - (p.x() * p.x() + p.y() * p.y()); };
  EXPECT_NEAR(stitch_detail::mean_over_triangle(gap, a, b, c), 1.0 / 3.0, 1e-15);
  // The volume between the flat triangle and the paraboloid: the mean times the area 1/2.
  EXPECT_NEAR(0.5 * stitch_detail::mean_over_triangle(gap, a, b, c), 1.0 / 6.0, 1e-15);
}

// The bulge b = l1 l2 + l2 l3 + l3 l1 (barycentric; 0 at the corners) has the mean 1/4 over
// any triangle (each l_i l_j integrates to A / 12); the 10-point lattice of step 1/3 gives 1/6.
TEST(VolumeQuadrature, ReadsTheWholeBulgeOfAnyTriangle) {
  const Eigen::Vector3d a(0.3, -0.2, 0.7), b(1.7, 0.4, -0.1), c(0.5, 1.9, 0.2);
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double twice_area = n.squaredNorm();
  // Barycentric coordinates of p (in the triangle's plane) by area vectors.
  auto bulge = [&](const Eigen::Vector3d& p) {
    const double l1 = (b - p).cross(c - p).dot(n) / twice_area;
    const double l2 = (c - p).cross(a - p).dot(n) / twice_area;
    const double l3 = 1.0 - l1 - l2;
    return l1 * l2 + l2 * l3 + l3 * l1;
  };
  EXPECT_NEAR(stitch_detail::mean_over_triangle(bulge, a, b, c), 0.25, 1e-14);
  // A general quadratic against the three-edge-midpoint rule (exact for quadratics too).
  auto q = [](const Eigen::Vector3d& p) { return 2.0 * p.x() * p.x() - p.x() * p.y() + 0.5 * p.y() * p.y() + 3.0 * p.z() - 1.0; };
  const double midpoints = (q(0.5 * (a + b)) + q(0.5 * (b + c)) + q(0.5 * (c + a))) / 3.0;
  EXPECT_NEAR(stitch_detail::mean_over_triangle(q, a, b, c), midpoints, 1e-13);
  // Of degree 2, not more: x^3 over the unit right triangle (integral 1/4 - 1/5 = 1/20, mean
  // 1/10) is not read exactly.
  auto cubic = [](const Eigen::Vector3d& p) { return p.x() * p.x() * p.x(); };
  const Eigen::Vector3d o(0.0, 0.0, 0.0), x(1.0, 0.0, 0.0), y(0.0, 1.0, 0.0);
  EXPECT_GT(std::abs(stitch_detail::mean_over_triangle(cubic, o, x, y) - 0.1), 1e-4);
}

}  // namespace nurbsfront
