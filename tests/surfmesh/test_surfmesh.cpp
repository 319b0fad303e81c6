// SPDX-License-Identifier: BSD-3-Clause
// mesh_surface() on marching-cubes surfaces of the analytic scenes and on small hand-made
// meshes: closed 2-manifold soups with the input's Euler characteristic, orientation,
// distance to the true surface, quality, shared border nodes, determinism.

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <functional>
#include <set>
#include <string>

#include "fixtures/shapes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/surfmesh/surfmesh.h"

namespace nurbsfront {
namespace {

TriMesh scene_mesh(const std::string& name, int resolution, SampleMode mode) {
  const ScalarGrid grid = sample_scene(scene_by_name(name), resolution, mode);
  return to_trimesh(marching_cubes(grid, scene_marching_cubes_options(mode)));
}

TriangleSoup as_soup(const SurfaceMesh& sm) {
  TriangleSoup soup;
  soup.points = sm.nodes;
  for (const auto& t : sm.triangles)
    soup.triangles.push_back({static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]), static_cast<std::uint32_t>(t[2])});
  return soup;
}

// Structural checks valid for any input: every patch Ok, every node used, border nodes
// only by triangles of their curve's patches and by both of them.
void expect_consistent(const Segmentation& seg, const SurfaceMesh& sm) {
  ASSERT_EQ(sm.patches.size(), seg.patches.size());
  ASSERT_EQ(sm.nodes.size(), sm.node_kind.size());
  ASSERT_EQ(sm.nodes.size(), sm.node_owner.size());
  ASSERT_EQ(sm.triangles.size(), sm.triangle_patch.size());
  ASSERT_EQ(sm.curve_is_feature.size(), seg.curves.size());
  for (std::size_t p = 0; p < sm.patches.size(); ++p)
    EXPECT_EQ(sm.patches[p].status, PatchStatus::Ok) << "patch " << p << ": " << sm.patches[p].message;
  std::vector<std::set<int>> node_patches(sm.nodes.size());
  for (std::size_t t = 0; t < sm.triangles.size(); ++t)
    for (const int v : sm.triangles[t]) {
      ASSERT_GE(v, 0);
      ASSERT_LT(v, static_cast<int>(sm.nodes.size()));
      node_patches[static_cast<std::size_t>(v)].insert(sm.triangle_patch[t]);
    }
  for (std::size_t v = 0; v < sm.nodes.size(); ++v) {
    EXPECT_FALSE(node_patches[v].empty()) << "node " << v << " is unused";
    switch (sm.node_kind[v]) {
      case NodeKind::Inner:
        EXPECT_GE(v, sm.n_border_nodes);
        EXPECT_EQ(node_patches[v], std::set<int>{sm.node_owner[v]});
        break;
      case NodeKind::Border: {
        EXPECT_LT(v, sm.n_border_nodes);
        const BorderCurve& c = seg.curves[static_cast<std::size_t>(sm.node_owner[v])];
        std::set<int> expected{c.patch_left};
        if (c.patch_right >= 0) expected.insert(c.patch_right);
        EXPECT_EQ(node_patches[v], expected) << "border node " << v;
        break;
      }
      case NodeKind::Corner:
        EXPECT_LT(v, sm.n_border_nodes);
        EXPECT_EQ(sm.node_owner[v], -1);
        break;
    }
  }
}

struct SoupFigures {
  long euler = 0;
  bool closed = false;
  double mean_alpha = 0.0;
  double min_alpha = 1.0;
  double mean_edge = 0.0;
  double min_edge = 1e300;
  double max_edge = 0.0;
};

SoupFigures figures(const SurfaceMesh& sm) {
  const TriangleSoup soup = as_soup(sm);
  const ManifoldCheck check = check_manifold(soup);
  EXPECT_TRUE(check.ok()) << check.message();
  SoupFigures f;
  if (!check.ok()) return f;
  const TriMesh mesh = to_trimesh(soup);
  f.euler = static_cast<long>(mesh.n_vertices()) - static_cast<long>(mesh.n_edges()) + static_cast<long>(mesh.n_faces());
  f.closed = true;
  for (const auto h : mesh.halfedges())
    if (mesh.is_boundary(h)) f.closed = false;
  const std::vector<double> alpha = face_alpha(soup);
  for (const double a : alpha) {
    f.mean_alpha += a;
    f.min_alpha = std::min(f.min_alpha, a);
  }
  f.mean_alpha /= static_cast<double>(alpha.size());
  for (const auto e : mesh.edges()) {
    const double l = mesh.calc_edge_length(e);
    f.mean_edge += l;
    f.min_edge = std::min(f.min_edge, l);
    f.max_edge = std::max(f.max_edge, l);
  }
  f.mean_edge /= static_cast<double>(mesh.n_edges());
  return f;
}

using OutwardNormal = std::function<Eigen::Vector3d(const Eigen::Vector3d&)>;

// Every triangle's normal on the analytic outward side; every node near the surface.
void expect_on_true_surface(const SurfaceMesh& sm, const Scene& scene, const OutwardNormal& outward, double max_distance) {
  double worst = 0.0;
  for (const auto& x : sm.nodes) worst = std::max(worst, std::abs(signed_distance(scene, x)));
  EXPECT_LE(worst, max_distance);
  std::size_t n_flipped = 0;
  for (const auto& t : sm.triangles) {
    const Eigen::Vector3d& a = sm.nodes[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = sm.nodes[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = sm.nodes[static_cast<std::size_t>(t[2])];
    if ((b - a).cross(c - a).dot(outward((a + b + c) / 3.0)) <= 0.0) ++n_flipped;
  }
  EXPECT_EQ(n_flipped, 0u);
}

TEST(Surfmesh, LevelSetSphere) {
  constexpr int kRes = 40;
  const TriMesh mesh = scene_mesh("sphere", kRes, SampleMode::LevelSet);
  const Segmentation seg = segment(mesh);
  SurfMeshOptions options;
  options.threads = 1;
  const SurfaceMesh sm = mesh_surface(mesh, seg, options);
  expect_consistent(seg, sm);
  const SoupFigures f = figures(sm);
  EXPECT_TRUE(f.closed);
  EXPECT_EQ(f.euler, 2);
  const double voxel = 2.0 / kRes;
  expect_on_true_surface(sm, scene_by_name("sphere"), [](const Eigen::Vector3d& x) { return x.normalized(); }, 0.25 * voxel);
  EXPECT_GE(f.mean_alpha, 0.85);
  EXPECT_GT(f.mean_edge, 0.7 * sm.target_size);
  EXPECT_LT(f.mean_edge, 1.3 * sm.target_size);
  std::printf("sphere: patches %zu nodes %zu triangles %zu mean alpha %.3f min alpha %.3f edges %.3f/%.3f/%.3f h %.3f\n",
              sm.patches.size(), sm.nodes.size(), sm.triangles.size(), f.mean_alpha, f.min_alpha, f.min_edge / sm.target_size,
              f.mean_edge / sm.target_size, f.max_edge / sm.target_size, sm.target_size);
  for (const auto& c : sm.curve_is_feature) EXPECT_EQ(c, 0);

  options.threads = 2;
  const SurfaceMesh again = mesh_surface(mesh, seg, options);
  EXPECT_EQ(again.nodes, sm.nodes);
  EXPECT_EQ(again.triangles, sm.triangles);
}

}  // namespace
}  // namespace nurbsfront
