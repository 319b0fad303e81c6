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
#include <numeric>
#include <utility>
#include <vector>

#include "fixtures/shapes.h"
#include "nurbsfront/core/disjoint_sets.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/stitch/stitch_internal.h"
#include "nurbsfront/stitch/sweep_schedule.h"

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

// stitch_detail::sweep_schedule as it was written before session 21: the edges by the
// mesh's edge iterator (deleted ones skipped), once for the groups and once for `ready`.
stitch_detail::SweepSchedule reference_schedule(const TriMesh& mesh, std::vector<std::uint8_t> role) {
  const std::size_t n = mesh.n_vertices();
  for (std::size_t i = n; i-- > 0;) {
    if (role[i] != 1) continue;
    for (auto u : mesh.vv_range(TriMesh::VertexHandle(static_cast<int>(i)))) {
      const auto j = static_cast<std::size_t>(u.idx());
      if (j < i && role[j] == 2) role[j] = 1;
    }
  }
  stitch_detail::SweepSchedule s;
  std::vector<std::size_t> position(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (role[i] != 1) continue;
    s.serial.push_back(static_cast<int>(i));
    position[i] = s.serial.size();
  }
  DisjointSets sets(n);
  for (auto e : mesh.edges()) {
    const auto h = mesh.halfedge_handle(e, 0);
    const int a = mesh.from_vertex_handle(h).idx(), b = mesh.to_vertex_handle(h).idx();
    if (role[static_cast<std::size_t>(a)] != 2 || role[static_cast<std::size_t>(b)] != 2) continue;
    sets.unite(static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b));
  }
  std::vector<int> group(n, -1);
  std::size_t n_groups = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (role[i] != 2) continue;
    const auto r = static_cast<std::size_t>(sets.find(static_cast<std::uint32_t>(i)));
    if (group[r] < 0) group[r] = static_cast<int>(n_groups++);
    group[i] = group[r];
  }
  s.group_begin.assign(n_groups + 1, 0);
  s.group_ready.assign(n_groups, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (role[i] == 2) ++s.group_begin[static_cast<std::size_t>(group[i]) + 1];
  }
  for (std::size_t g = 0; g < n_groups; ++g) s.group_begin[g + 1] += s.group_begin[g];
  s.group_vertices.resize(s.group_begin[n_groups]);
  std::vector<std::size_t> fill(s.group_begin.begin(), s.group_begin.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    if (role[i] == 2) s.group_vertices[fill[static_cast<std::size_t>(group[i])]++] = static_cast<int>(i);
  }
  for (auto e : mesh.edges()) {
    const auto h = mesh.halfedge_handle(e, 0);
    auto a = static_cast<std::size_t>(mesh.from_vertex_handle(h).idx()), b = static_cast<std::size_t>(mesh.to_vertex_handle(h).idx());
    if (role[a] == 2) std::swap(a, b);
    if (role[a] != 1 || role[b] != 2) continue;
    std::size_t& ready = s.group_ready[static_cast<std::size_t>(group[b])];
    ready = std::max(ready, position[a]);
  }
  s.order.resize(n_groups);
  std::iota(s.order.begin(), s.order.end(), std::size_t{0});
  std::stable_sort(s.order.begin(), s.order.end(),
                   [&s](std::size_t x, std::size_t y) { return s.group_ready[x] < s.group_ready[y]; });
  return s;
}

TEST(SweepSchedule, SameAsTheEdgeIteratorSchedule) {
  // A torus with every 7th collapsible edge collapsed (deleted edges to skip) and a whole
  // one; roles: bands of serial vertices (role 1) across the torus cut the inner vertices
  // (role 2) into groups, every 11th vertex not tried (role 0).
  for (const int k : {7, 1000000}) {
    const TriMesh mesh = torus_with_collapses(k);
    std::vector<std::uint8_t> role(mesh.n_vertices(), 2);
    for (std::size_t v = 0; v < role.size(); ++v) {
      if (v % 11 == 5) role[v] = 0;
      const Vec p = stitch_detail::point(mesh, TriMesh::VertexHandle(static_cast<int>(v)));
      if (std::abs(p.x()) < 0.15 || std::abs(p.y()) < 0.15) role[v] = 1;
    }
    const stitch_detail::SweepSchedule expected = reference_schedule(mesh, role);
    const stitch_detail::SweepSchedule s = stitch_detail::sweep_schedule(mesh, role);
    ASSERT_GE(expected.group_ready.size(), 3U) << k;
    ASSERT_GT(*std::max_element(expected.group_ready.begin(), expected.group_ready.end()), 0U) << k;
    ASSERT_GT(expected.serial.size(), 20U) << k;
    EXPECT_EQ(s.serial, expected.serial) << k;
    EXPECT_EQ(s.group_vertices, expected.group_vertices) << k;
    EXPECT_EQ(s.group_begin, expected.group_begin) << k;
    EXPECT_EQ(s.group_ready, expected.group_ready) << k;
    EXPECT_EQ(s.order, expected.order) << k;
  }
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
