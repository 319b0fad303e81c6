// SPDX-License-Identifier: BSD-3-Clause
// The stitch's whole-mesh scans on several threads: stitch_detail::select_in_order and
// small_away_faces give the serial loop's list at 1, 2 and 4 threads; smallest_angle_sine
// (no sort) equals the sorted formula bit for bit; face_alphas gives the serial list too.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <utility>
#include <vector>

#include "fixtures/shapes.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/stitch/stitch_internal.h"

namespace nurbsfront {
namespace {

using Vec = Eigen::Vector3d;

TEST(SelectInOrder, SerialListAtEveryThreadCount) {
  // Values depend on the index only; every third index kept, chunks of 7 (143 chunks).
  auto keep = [](std::size_t i, std::pair<std::size_t, double>& out) {
    if (i % 3 != 1) return false;
    out = {i, std::sqrt(static_cast<double>(i))};
    return true;
  };
  const std::size_t n = 1000;
  std::vector<std::pair<std::size_t, double>> expected;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 3 == 1) expected.emplace_back(i, std::sqrt(static_cast<double>(i)));
  }
  ASSERT_EQ(expected.size(), 333U);
  for (const unsigned threads : {1U, 2U, 4U}) {
    EXPECT_EQ((stitch_detail::select_in_order<std::pair<std::size_t, double>>(n, threads, 7, keep)), expected) << threads;
    // One chunk, and nothing.
    EXPECT_EQ((stitch_detail::select_in_order<std::pair<std::size_t, double>>(n, threads, n, keep)), expected) << threads;
    EXPECT_TRUE((stitch_detail::select_in_order<std::pair<std::size_t, double>>(0, threads, 7, keep)).empty());
  }
}

// The sine of the smallest angle as it was written before (sorted squared edges).
double sorted_sine(const Vec& a, const Vec& b, const Vec& c) {
  std::array<double, 3> l2{(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()};
  std::sort(l2.begin(), l2.end());
  const double product = std::sqrt(l2[1] * l2[2]);
  return product > 0.0 ? (b - a).cross(c - a).norm() / product : 0.0;
}

TEST(SmallestAngleSine, EqualsTheSortedFormulaBitForBit) {
  // Slivers, right and obtuse triangles, isosceles ones (equal edges), a repeated point;
  // every order of the corners.
  const std::vector<std::array<Vec, 3>> triangles{
      {Vec(0, 0, 0), Vec(1, 0, 0), Vec(0.5, 1e-7, 0)},   {Vec(0, 0, 0), Vec(1, 0, 0), Vec(0, 1, 0)},
      {Vec(0, 0, 0), Vec(3, 0, 0), Vec(1.4, 0.2, 0.1)},  {Vec(0, 0, 0), Vec(1, 0, 0), Vec(0.5, 2, 0)},
      {Vec(0.1, 0.2, 0.3), Vec(1.7, -0.4, 2.2), Vec(-0.9, 1.3, 0.5)}, {Vec(1, 1, 1), Vec(1, 1, 1), Vec(2, 0, 1)},
      {Vec(0, 0, 0), Vec(1, 0, 0), Vec(0.5, 0.5 * std::numbers::sqrt3, 0)}};
  for (const auto& t : triangles) {
    std::array<int, 3> order{0, 1, 2};
    do {
      const Vec &a = t[order[0]], &b = t[order[1]], &c = t[order[2]];
      EXPECT_EQ(stitch_detail::smallest_angle_sine(a, b, c), sorted_sine(a, b, c));
    } while (std::next_permutation(order.begin(), order.end()));
  }
  EXPECT_NEAR(stitch_detail::smallest_angle_sine(Vec(0, 0, 0), Vec(1, 0, 0), Vec(0, 1, 0)), std::sqrt(0.5), 1e-15);
  EXPECT_EQ(stitch_detail::smallest_angle_sine(Vec(1, 1, 1), Vec(1, 1, 1), Vec(1, 1, 1)), 0.0);
}

// A 24 x 12 torus with every k-th collapsible edge (in edge order) collapsed, not garbage
// collected: deleted faces and squeezed triangles for the scans to skip or list.
TriMesh torus_with_collapses(int k) {
  TriMesh mesh = to_trimesh(test::torus(24, 12));
  int n = 0;
  for (int e = 0; e < static_cast<int>(mesh.n_edges()); ++e) {
    const TriMesh::EdgeHandle edge(e);
    if (mesh.status(edge).deleted()) continue;
    const auto h = mesh.halfedge_handle(edge, 0);
    if (!mesh.is_collapse_ok(h) || ++n % k != 0) continue;
    mesh.collapse(h);
  }
  return mesh;
}

TEST(SmallAwayFaces, SerialListAtEveryThreadCount) {
  // A torus with every 9th collapsible edge collapsed (deleted faces, squeezed triangles);
  // every 7th vertex is a feature node.
  TriMesh mesh = torus_with_collapses(9);
  std::vector<int> vertex_node(mesh.n_vertices());
  std::vector<std::uint8_t> is_feature(mesh.n_vertices(), 0);
  for (std::size_t v = 0; v < vertex_node.size(); ++v) {
    vertex_node[v] = static_cast<int>(v);
    is_feature[v] = v % 7 == 0 ? 1 : 0;
  }
  const double sin_bound = std::sin(30.0 * std::numbers::pi / 180.0);
  // The serial scan, as the repair made it: the faces the iterator gives (deleted ones
  // skipped), their corners by the circulator.
  std::vector<std::pair<double, int>> expected;
  std::size_t n_deleted = 0, n_small_at_feature = 0;
  for (auto f : mesh.all_faces()) n_deleted += mesh.status(f).deleted() ? 1 : 0;
  for (auto f : mesh.faces()) {
    std::array<Vec, 3> p;
    bool feature = false;
    int k = 0;
    for (auto v : mesh.fv_range(f)) {
      feature = feature || is_feature[static_cast<std::size_t>(v.idx())] != 0;
      p[static_cast<std::size_t>(k++)] = stitch_detail::point(mesh, v);
    }
    const double s = stitch_detail::smallest_angle_sine(p[0], p[1], p[2]);
    if (!(s < sin_bound)) continue;
    if (feature) {
      ++n_small_at_feature;
      continue;
    }
    expected.emplace_back(s, f.idx());
  }
  ASSERT_GT(n_deleted, 20U);
  ASSERT_GT(expected.size(), 20U);
  ASSERT_GT(n_small_at_feature, 5U);
  for (const unsigned threads : {1U, 2U, 4U}) {
    for (const std::size_t chunk : {std::size_t{16}, std::size_t{8192}}) {
      EXPECT_EQ(stitch_detail::small_away_faces(mesh, vertex_node, is_feature, sin_bound, threads, chunk), expected)
          << threads << " threads, chunk " << chunk;
    }
  }
}

TEST(FaceAlphas, SerialListAtEveryThreadCount) {
  // A torus with every 5th collapsible edge collapsed: deleted faces are skipped, the
  // others' alphas listed in face order, bit for bit at 1, 2 and 4 threads.
  TriMesh mesh = torus_with_collapses(5);
  std::vector<double> expected;
  for (auto f : mesh.faces()) {
    std::array<Vec, 3> p;
    int k = 0;
    for (auto v : mesh.fv_range(f)) p[static_cast<std::size_t>(k++)] = stitch_detail::point(mesh, v);
    expected.push_back(triangle_alpha(p[0], p[1], p[2]));
  }
  ASSERT_LT(expected.size() + 50, mesh.n_faces());  // deleted faces in the middle
  ASSERT_LT(*std::min_element(expected.begin(), expected.end()), 0.9);
  for (const unsigned threads : {1U, 2U, 4U}) {
    for (const std::size_t chunk : {std::size_t{16}, std::size_t{8192}}) {
      EXPECT_EQ(stitch_detail::face_alphas(mesh, threads, chunk), expected) << threads << " threads, chunk " << chunk;
    }
  }
}

}  // namespace
}  // namespace nurbsfront
