// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <map>
#include <random>
#include <set>

#include "fixtures/shapes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/core/soup_internal.h"

namespace nurbsfront {
namespace {

int euler(const TriMesh& m) {
  return static_cast<int>(m.n_vertices()) - static_cast<int>(m.n_edges()) + static_cast<int>(m.n_faces());
}

TEST(Soup, ClosedShapesBecomeManifoldMeshes) {
  for (const auto& [soup, chi] : {std::pair{test::tetrahedron(), 2}, std::pair{test::cube(), 2},
                                  std::pair{test::icosphere(2), 2}, std::pair{test::torus(12, 8), 0}}) {
    ASSERT_TRUE(check_manifold(soup).ok()) << check_manifold(soup).message();
    const TriMesh mesh = to_trimesh(soup);
    EXPECT_EQ(mesh.n_faces(), soup.triangles.size());
    EXPECT_EQ(euler(mesh), chi);
    for (auto h : mesh.halfedges()) EXPECT_FALSE(mesh.is_boundary(h));
    const TriangleSoup back = to_soup(mesh);
    EXPECT_EQ(back.points.size(), soup.points.size());
    EXPECT_EQ(back.triangles, soup.triangles);
  }
}

TEST(Soup, OpenPatchKeepsItsBoundary) {
  const TriMesh mesh = to_trimesh(test::grid_patch(3, 2));
  std::size_t n_boundary = 0;
  for (auto e : mesh.edges()) n_boundary += mesh.is_boundary(e) ? 1 : 0;
  EXPECT_EQ(n_boundary, 10u);  // 2 * (3 + 2)
  EXPECT_EQ(euler(mesh), 1);
}

TEST(Soup, NonManifoldEdgeIsRejectedWithReason) {
  TriangleSoup s = test::grid_patch(1, 1);
  s.points.emplace_back(0.5, 0.5, 1.0);
  s.triangles.push_back({0, 3, 4});  // third triangle on the diagonal (0, 3)
  const ManifoldCheck check = check_manifold(s);
  EXPECT_EQ(check.n_nonmanifold_edges, 1u);
  EXPECT_THROW((void)to_trimesh(s), TopologyError);
}

TEST(Soup, FlippedTriangleIsMisoriented) {
  TriangleSoup s = test::tetrahedron();
  std::swap(s.triangles[0][1], s.triangles[0][2]);
  EXPECT_EQ(check_manifold(s).n_misoriented_edges, 3u);
}

TEST(Soup, TwoFansAtOneVertexAreNonManifold) {
  // Two triangles touching only at vertex 0 (a bow tie).
  TriangleSoup s;
  s.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  s.triangles = {{0, 1, 2}, {0, 3, 4}};
  EXPECT_EQ(check_manifold(s).n_nonmanifold_vertices, 1u);
  EXPECT_THROW((void)to_trimesh(s), TopologyError);
}

TEST(Soup, BadIndicesAndNanAreErrors) {
  TriangleSoup s = test::tetrahedron();
  s.triangles.push_back({0, 1, 17});
  EXPECT_EQ(check_manifold(s).n_bad_indices, 1u);
  EXPECT_THROW((void)to_trimesh(s), TopologyError);
  TriangleSoup n = test::tetrahedron();
  n.points[2].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((void)to_trimesh(n), InvalidInput);
  TriMesh built;
  EXPECT_THROW(to_trimesh(n, built, 2), InvalidInput);
  EXPECT_THROW(to_trimesh(s, built, 2), TopologyError);
  EXPECT_EQ(built.n_faces(), 0u);
}

// The same vertices, halfedges and faces (every handle and point).
void expect_same_mesh(const TriMesh& built, const TriMesh& expected, int round) {
  ASSERT_EQ(built.n_vertices(), expected.n_vertices()) << round;
  ASSERT_EQ(built.n_edges(), expected.n_edges()) << round;
  ASSERT_EQ(built.n_faces(), expected.n_faces()) << round;
  for (const auto h : expected.halfedges()) {
    ASSERT_EQ(built.to_vertex_handle(h), expected.to_vertex_handle(h)) << round;
    ASSERT_EQ(built.next_halfedge_handle(h), expected.next_halfedge_handle(h)) << round;
    ASSERT_EQ(built.prev_halfedge_handle(h), expected.prev_halfedge_handle(h)) << round;
    ASSERT_EQ(built.face_handle(h), expected.face_handle(h)) << round;
  }
  for (const auto v : expected.vertices()) {
    ASSERT_EQ(built.halfedge_handle(v), expected.halfedge_handle(v)) << round << " vertex " << v.idx();
    ASSERT_EQ(built.point(v), expected.point(v)) << round;
  }
  for (const auto f : expected.faces()) ASSERT_EQ(built.halfedge_handle(f), expected.halfedge_handle(f)) << round;
}

// The definitions of ManifoldCheck's counts, computed the slow and obvious way.
ManifoldCheck reference_check(const TriangleSoup& soup) {
  ManifoldCheck check;
  const std::size_t n = soup.points.size();
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  std::vector<std::array<std::uint32_t, 3>> good;
  for (const auto& t : soup.triangles) {
    if (t[0] >= n || t[1] >= n || t[2] >= n) {
      ++check.n_bad_indices;
    } else if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
      ++check.n_repeated_index;
    } else {
      good.push_back(t);
      for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
    }
  }
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> undirected;
  for (const auto& [e, count] : directed) {
    if (count >= 2) ++check.n_misoriented_edges;
    undirected[{std::min(e.first, e.second), std::max(e.first, e.second)}] += count;
  }
  for (const auto& [e, count] : undirected) check.n_nonmanifold_edges += count > 2 ? 1 : 0;
  if (!check.ok()) return check;
  // One fan per vertex: the triangles around it are connected through shared edges.
  for (std::uint32_t v = 0; v < n; ++v) {
    std::vector<std::array<std::uint32_t, 3>> around;
    for (const auto& t : good) {
      if (std::find(t.begin(), t.end(), v) != t.end()) around.push_back(t);
    }
    if (around.size() <= 1) continue;
    std::vector<bool> reached(around.size(), false);
    std::vector<std::size_t> stack{0};
    reached[0] = true;
    while (!stack.empty()) {
      const auto i = stack.back();
      stack.pop_back();
      for (std::size_t j = 0; j < around.size(); ++j) {
        if (reached[j]) continue;
        int shared = 0;  // vertices shared besides v: one means a common edge at v
        for (auto a : around[i])
          shared += a != v && std::find(around[j].begin(), around[j].end(), a) != around[j].end() ? 1 : 0;
        if (shared > 0) {
          reached[j] = true;
          stack.push_back(j);
        }
      }
    }
    if (std::find(reached.begin(), reached.end(), false) != reached.end()) ++check.n_nonmanifold_vertices;
  }
  return check;
}

TEST(Soup, CheckManifoldMatchesTheDefinitionsOnRandomSoups) {
  std::mt19937 random(5);
  int n_manifold = 0, n_fan_failures = 0;
  for (int round = 0; round < 400; ++round) {
    // A closed or open shape, then a few random edits: extra, flipped, removed triangles.
    TriangleSoup s =
        round % 3 == 0 ? test::icosphere(1) : (round % 3 == 1 ? test::torus(6, 4) : test::grid_patch(4, 3));
    const auto n = static_cast<std::uint32_t>(s.points.size());
    std::uniform_int_distribution<std::uint32_t> vertex(0, n);  // n: out of range
    const int n_edits = static_cast<int>(random() % 4);
    for (int e = 0; e < n_edits; ++e) {
      const auto kind = random() % 4;
      if (kind == 0 && !s.triangles.empty()) {
        s.triangles.erase(s.triangles.begin() + static_cast<std::ptrdiff_t>(random() % s.triangles.size()));
      } else if (kind == 1 && !s.triangles.empty()) {
        auto& t = s.triangles[random() % s.triangles.size()];
        std::swap(t[1], t[2]);
      } else if (kind == 2 && !s.triangles.empty()) {
        s.triangles.push_back(s.triangles[random() % s.triangles.size()]);
      } else {
        s.triangles.push_back(
            {vertex(random) % n, vertex(random) % n, round % 50 == 0 ? vertex(random) : vertex(random) % n});
      }
    }
    const ManifoldCheck fast = check_manifold(s);
    const ManifoldCheck slow = reference_check(s);
    ASSERT_EQ(fast.n_bad_indices, slow.n_bad_indices) << round;
    ASSERT_EQ(fast.n_repeated_index, slow.n_repeated_index) << round;
    ASSERT_EQ(fast.n_nonmanifold_edges, slow.n_nonmanifold_edges) << round;
    ASSERT_EQ(fast.n_misoriented_edges, slow.n_misoriented_edges) << round;
    ASSERT_EQ(fast.n_nonmanifold_vertices, slow.n_nonmanifold_vertices) << round;
    n_manifold += fast.ok() ? 1 : 0;
    n_fan_failures += fast.n_nonmanifold_vertices > 0 ? 1 : 0;
    // With the check beside the build (2 threads): the serial mesh, or the same refusal and
    // an empty mesh (the build of a refused soup runs and is thrown away: ASan sees it).
    TriMesh built;
    if (fast.ok()) {
      to_trimesh(s, built, 2);
      expect_same_mesh(built, to_trimesh(s), round);
    } else {
      EXPECT_THROW(to_trimesh(s, built, 2), TopologyError) << round;
      EXPECT_EQ(built.n_vertices() + built.n_faces(), 0u) << round;
    }
  }
  // Both outcomes and the fan test were exercised.
  EXPECT_GT(n_manifold, 20);
  EXPECT_LT(n_manifold, 380);
  EXPECT_GT(n_fan_failures, 5);
}

// to_trimesh() builds the halfedge structure itself; it must be the very mesh OpenMesh's
// add_face() builds (same handles everywhere), or every later stage could differ.
TEST(Soup, DirectBuildMatchesAddFace) {
  std::mt19937 random(11);
  std::vector<TriangleSoup> shapes{test::tetrahedron(), test::cube(), test::icosphere(2), test::torus(12, 8),
                                   test::grid_patch(5, 4)};
  int n_compared = 0;
  for (int round = 0; round < 60; ++round) {
    TriangleSoup s = shapes[round % shapes.size()];
    if (round >= 5) std::shuffle(s.triangles.begin(), s.triangles.end(), random);
    if (round >= 20 && s.triangles.size() > 8) {  // holes
      for (int k = 0; k < 3; ++k)
        s.triangles.erase(s.triangles.begin() + static_cast<std::ptrdiff_t>(random() % s.triangles.size()));
    }
    if (round % 4 == 3) {  // rotated corners: another halfedge is each face's first
      for (auto& t : s.triangles) std::rotate(t.begin(), t.begin() + 1, t.end());
    }
    if (!check_manifold(s).ok()) continue;
    TriMesh expected;
    std::vector<TriMesh::VertexHandle> handles;
    for (const auto& p : s.points) handles.push_back(expected.add_vertex(to_openmesh(p)));
    for (const auto& t : s.triangles)
      ASSERT_TRUE(expected.add_face(handles[t[0]], handles[t[1]], handles[t[2]]).is_valid());
    expect_same_mesh(to_trimesh(s), expected, round);
    if (HasFatalFailure()) return;
    ++n_compared;
  }
  EXPECT_GT(n_compared, 40);
}

// The direct build's steps on 2 and 4 threads: add_face()'s mesh, as on one thread, for a
// grid of 33 800 faces (101 400 corners: four chunks of 32 768) shuffled, with holes and
// rotated corners. A soup with an edge used twice in one direction (no oriented
// 2-manifold) is read safely: check_and_build() refuses it and leaves the mesh empty.
TEST(Soup, DirectBuildOnThreadsMatchesAddFace) {
  std::mt19937 random(5);
  TriangleSoup s = test::grid_patch(130, 130);
  std::shuffle(s.triangles.begin(), s.triangles.end(), random);
  for (int k = 0; k < 40; ++k)
    s.triangles.erase(s.triangles.begin() + static_cast<std::ptrdiff_t>(random() % s.triangles.size()));
  for (std::size_t f = 0; f < s.triangles.size(); f += 3) {
    std::rotate(s.triangles[f].begin(), s.triangles[f].begin() + 1, s.triangles[f].end());
  }
  ASSERT_TRUE(check_manifold(s).ok());
  TriMesh expected;
  std::vector<TriMesh::VertexHandle> handles;
  for (const auto& p : s.points) handles.push_back(expected.add_vertex(to_openmesh(p)));
  for (const auto& t : s.triangles) ASSERT_TRUE(expected.add_face(handles[t[0]], handles[t[1]], handles[t[2]]).is_valid());
  for (const unsigned threads : {1u, 2u, 4u}) {
    TriMesh built;
    core_detail::to_trimesh_checked(s, built, threads);
    expect_same_mesh(built, expected, static_cast<int>(threads));
    if (HasFatalFailure()) return;
    TriMesh checked;
    ASSERT_TRUE(core_detail::check_and_build(s, checked, threads).ok());
    expect_same_mesh(checked, expected, static_cast<int>(threads));
    if (HasFatalFailure()) return;
  }
  TriangleSoup twice = s;
  twice.triangles.push_back(twice.triangles[100]);  // the same face again: its edges twice
  std::rotate(twice.triangles.back().begin(), twice.triangles.back().begin() + 1, twice.triangles.back().end());
  for (const unsigned threads : {2u, 4u}) {
    TriMesh built = to_trimesh(test::cube());
    EXPECT_FALSE(core_detail::check_and_build(twice, built, threads).ok());
    EXPECT_EQ(built.n_faces(), 0u);
    core_detail::to_trimesh_checked(twice, built, threads);  // refused: no bad access, an empty mesh
    EXPECT_EQ(built.n_faces(), 0u);
  }
}

TEST(Soup, MeanEdgeLengthIsTheSameForAnyThreadCount) {
  // A 160 x 160 grid (77 120 edges, more than two chunks of 32 768): the mean of its edges
  // (n_axis of length h, n_diagonal of length h sqrt(2)), bit for bit the same on 1, 2 and
  // 3 threads, also with deleted edges (a face deleted, not collected) and on a closed mesh.
  const int n = 160;
  const double h = 1.0 / n;
  TriMesh grid = to_trimesh(test::grid_patch(n, n));
  const double n_axis = 2.0 * n * (n + 1), n_diagonal = static_cast<double>(n) * n;
  ASSERT_EQ(static_cast<double>(grid.n_edges()), n_axis + n_diagonal);
  const double serial = mean_edge_length(grid);
  EXPECT_NEAR(serial, (n_axis * h + n_diagonal * h * std::sqrt(2.0)) / (n_axis + n_diagonal), 1e-12);
  for (const unsigned threads : {1u, 2u, 3u}) EXPECT_EQ(core_detail::mean_edge_length(grid, threads), serial) << threads;
  grid.request_face_status();
  grid.request_edge_status();
  grid.request_vertex_status();
  grid.delete_face(TriMesh::FaceHandle(0), true);  // the corner square: 3 edges and a vertex go
  grid.delete_face(TriMesh::FaceHandle(1), true);
  const double after = mean_edge_length(grid);
  EXPECT_NE(after, serial);
  for (const unsigned threads : {2u, 3u}) EXPECT_EQ(core_detail::mean_edge_length(grid, threads), after) << threads;
  const TriMesh sphere = to_trimesh(test::icosphere(6));
  for (const unsigned threads : {2u, 3u}) EXPECT_EQ(core_detail::mean_edge_length(sphere, threads), mean_edge_length(sphere)) << threads;
}

TEST(Soup, BoundingBoxDiagonal) {
  EXPECT_DOUBLE_EQ(bounding_box(test::cube()).diagonal(), std::sqrt(3.0));
  EXPECT_EQ(bounding_box(TriangleSoup{}).diagonal(), 0.0);
}

}  // namespace
}  // namespace nurbsfront
