// SPDX-License-Identifier: BSD-3-Clause
#include "isosurface/surface_checks.h"

#include <gtest/gtest.h>

#include <algorithm>

#include <Eigen/Geometry>

#include "nurbsfront/core/tolerances.h"

namespace nurbsfront::test {

SurfaceFacts surface_facts(const TriangleSoup& soup) {
  SurfaceFacts f;
  const ManifoldCheck check = check_manifold(soup);
  f.manifold = check.ok();
  f.manifold_message = check.message();
  const double diag = bounding_box(soup).diagonal();
  const double min_area = tolerance::kDegenerateAreaRelative * diag * diag;
  std::vector<bool> used(soup.points.size(), false);
  for (const auto& t : soup.triangles) {
    for (auto v : t) {
      if (v < used.size()) used[v] = true;
    }
    if (t[0] >= soup.points.size() || t[1] >= soup.points.size() || t[2] >= soup.points.size()) continue;
    const Eigen::Vector3d& a = soup.points[t[0]];
    const Eigen::Vector3d& b = soup.points[t[1]];
    const Eigen::Vector3d& c = soup.points[t[2]];
    if (0.5 * (b - a).cross(c - a).norm() <= min_area) ++f.n_degenerate;
    f.signed_volume += a.dot(b.cross(c)) / 6.0;
  }
  f.n_unused_points = static_cast<std::size_t>(std::count(used.begin(), used.end(), false));
  std::vector<std::array<double, 3>> sorted;
  sorted.reserve(soup.points.size());
  for (const auto& p : soup.points) sorted.push_back({p.x(), p.y(), p.z()});
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 1; i < sorted.size(); ++i) f.n_duplicate_points += sorted[i] == sorted[i - 1] ? 1 : 0;
  if (f.manifold) {
    const TriMesh mesh = to_trimesh(soup);
    for (auto e : mesh.edges()) f.n_boundary_edges += mesh.is_boundary(e) ? 1 : 0;
    f.euler = static_cast<int>(mesh.n_vertices()) - static_cast<int>(mesh.n_edges()) + static_cast<int>(mesh.n_faces());
  }
  return f;
}

SurfaceFacts expect_clean_surface(const TriangleSoup& soup, bool closed, const std::string& what) {
  const SurfaceFacts f = surface_facts(soup);
  EXPECT_TRUE(f.manifold) << what << ": " << f.manifold_message;
  EXPECT_EQ(f.n_degenerate, 0u) << what;
  EXPECT_EQ(f.n_duplicate_points, 0u) << what;
  EXPECT_EQ(f.n_unused_points, 0u) << what;
  if (closed) {
    EXPECT_EQ(f.n_boundary_edges, 0u) << what;
    if (!soup.triangles.empty()) {
      EXPECT_GT(f.signed_volume, 0.0) << what;
    }
  }
  return f;
}

}  // namespace nurbsfront::test
