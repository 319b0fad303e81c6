// SPDX-License-Identifier: BSD-3-Clause
// PatchInputHeights::height(): the height of the first of the patch's faces (in the order
// given) whose projection holds the point, bit for bit as the barycentric formula on the
// face's corners gives it; no face, no height.

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "nurbsfront/core/soup.h"
#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront {
namespace {

// The patch's faces in the frame, in the given order: their corners as fv_range() gives them.
std::vector<std::array<Eigen::Vector3d, 3>> local_faces(const TriMesh& mesh, const std::vector<int>& faces,
                                                        const PatchFrame& frame) {
  std::vector<std::array<Eigen::Vector3d, 3>> local;
  for (const int f : faces) {
    std::array<Eigen::Vector3d, 3> t;
    std::size_t k = 0;
    for (auto v : mesh.fv_range(TriMesh::FaceHandle(f))) t[k++] = frame.to_local(to_eigen(mesh.point(v)));
    local.push_back(t);
  }
  return local;
}

// The reference: every face in order, the first whose barycentric coordinates (computed
// from its corners, as the look-up did before it stored each face's edges and area) are all
// >= 0.
bool reference_height(const std::vector<std::array<Eigen::Vector3d, 3>>& local, double x, double y, double& z) {
  if (!std::isfinite(x) || !std::isfinite(y)) return false;
  for (const auto& t : local) {
    const double area = (t[1].x() - t[0].x()) * (t[2].y() - t[0].y()) - (t[1].y() - t[0].y()) * (t[2].x() - t[0].x());
    if (!(std::abs(area) > 0.0)) continue;
    const double b1 = ((x - t[0].x()) * (t[2].y() - t[0].y()) - (y - t[0].y()) * (t[2].x() - t[0].x())) / area;
    const double b2 = ((t[1].x() - t[0].x()) * (y - t[0].y()) - (t[1].y() - t[0].y()) * (x - t[0].x())) / area;
    if (b1 < 0.0 || b2 < 0.0 || b1 + b2 > 1.0) continue;
    z = (1.0 - b1 - b2) * t[0].z() + b1 * t[1].z() + b2 * t[2].z();
    return true;
  }
  return false;
}

// A wavy grid of n x m quads over [0, n] x [0, m] with jittered inner vertices, two
// triangles a quad; the first quad's row of vertices is collinear in the plane (a zero-area
// triangle would be dropped by to_trimesh, so the degenerate case is a sliver).
TriMesh wavy_patch(int n, int m, std::mt19937& rng) {
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  TriangleSoup soup;
  for (int j = 0; j <= m; ++j) {
    for (int i = 0; i <= n; ++i) {
      const bool inner = i > 0 && i < n && j > 0 && j < m;
      const double x = i + (inner ? jitter(rng) : 0.0), y = j + (inner ? jitter(rng) : 0.0);
      soup.points.emplace_back(x, y, 0.4 * std::sin(0.9 * x) * std::cos(0.7 * y) + 0.05 * x);
    }
  }
  auto at = [n](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < n; ++i) {
      // Alternate diagonals so that both corner orders of shared edges occur.
      if ((i + j) % 2 == 0) {
        soup.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        soup.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      } else {
        soup.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        soup.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
  }
  return to_trimesh(soup);
}

TEST(InputHeights, EqualsTheFirstFaceInOrderOnRandomPointsVerticesAndEdges) {
  std::mt19937 rng(20261127);
  const TriMesh mesh = wavy_patch(13, 9, rng);
  // A tilted frame (the patch's axis off the world's z) and the faces in a shuffled order.
  PatchFrame frame;
  frame.origin = Eigen::Vector3d(3.1, -0.7, 0.2);
  frame.axes = (Eigen::AngleAxisd(0.3, Eigen::Vector3d(1.0, 2.0, 0.5).normalized())).toRotationMatrix();
  std::vector<int> faces(mesh.n_faces());
  std::iota(faces.begin(), faces.end(), 0);
  std::shuffle(faces.begin(), faces.end(), rng);
  faces.resize(faces.size() - 20);  // a patch of some of the faces: a hole and a ragged rim
  const PatchInputHeights heights(mesh, faces, frame);
  const auto local = local_faces(mesh, faces, frame);

  std::vector<Eigen::Vector2d> queries;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300), hi = -lo;
  for (auto v : mesh.vertices()) {
    const Eigen::Vector3d p = frame.to_local(to_eigen(mesh.point(v)));
    queries.push_back(p.head<2>());  // on corners: several faces hold them
    lo = lo.cwiseMin(p.head<2>());
    hi = hi.cwiseMax(p.head<2>());
  }
  for (auto e : mesh.edges()) {  // on edges: two faces hold them
    const auto h = mesh.halfedge_handle(e, 0);
    const Eigen::Vector3d a = frame.to_local(to_eigen(mesh.point(mesh.from_vertex_handle(h))));
    const Eigen::Vector3d b = frame.to_local(to_eigen(mesh.point(mesh.to_vertex_handle(h))));
    queries.push_back(0.5 * (a + b).head<2>());
  }
  const Eigen::Vector2d margin = 0.1 * (hi - lo);
  std::uniform_real_distribution<double> ux(lo.x() - margin.x(), hi.x() + margin.x());
  std::uniform_real_distribution<double> uy(lo.y() - margin.y(), hi.y() + margin.y());
  for (int k = 0; k < 6000; ++k) queries.emplace_back(ux(rng), uy(rng));
  queries.emplace_back(std::nan(""), 0.0);
  queries.emplace_back(0.0, std::numeric_limits<double>::infinity());

  std::size_t n_hits = 0, n_misses = 0;
  for (const auto& q : queries) {
    double z = -7.0, z_ref = -7.0;
    const bool hit = heights.height(q.x(), q.y(), z);
    const bool hit_ref = reference_height(local, q.x(), q.y(), z_ref);
    ASSERT_EQ(hit, hit_ref) << q.transpose();
    if (hit) {
      ASSERT_EQ(std::bit_cast<std::uint64_t>(z), std::bit_cast<std::uint64_t>(z_ref)) << q.transpose();
      ++n_hits;
    } else {
      EXPECT_EQ(z, -7.0);  // untouched
      ++n_misses;
    }
  }
  // Both outcomes occur many times (the margin and the hole miss; the rest hits).
  EXPECT_GT(n_hits, 3000U);
  EXPECT_GT(n_misses, 300U);
}

TEST(InputHeights, NoFacesNoHeight) {
  std::mt19937 rng(1);
  const TriMesh mesh = wavy_patch(2, 2, rng);
  const PatchInputHeights heights(mesh, {}, PatchFrame{});
  double z = 3.0;
  EXPECT_FALSE(heights.height(0.5, 0.5, z));
  EXPECT_EQ(z, 3.0);
}

}  // namespace
}  // namespace nurbsfront
