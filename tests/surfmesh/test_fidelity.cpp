// SPDX-License-Identifier: BSD-3-Clause
// Fidelity to the true surface (issue 5): distance of the remeshed occupancy (0/1) sphere
// and torus to the analytic surface, in voxels, with the band fit of CellGrid against the
// marching-cubes input and against the plain fit; level-set inputs must not get worse.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/surfmesh/surfmesh.h"

namespace nurbsfront {
namespace {

struct Distance {
  double mean = 0.0;
  double max = 0.0;
};

// Distances to the scene's surface (in voxels) of the nodes, of the triangle centroids and
// of dense samples (the 10 points of a 4-step barycentric grid inside every triangle that are
// not vertices... plus the centroid).
struct Fidelity {
  Distance nodes;
  Distance centroids;
  Distance dense;
};

Fidelity fidelity(const std::vector<Eigen::Vector3d>& nodes, const std::vector<std::array<int, 3>>& triangles,
                  const Scene& scene, double voxel) {
  auto add = [&](Distance& d, const Eigen::Vector3d& x, std::size_t& n) {
    const double e = std::abs(signed_distance(scene, x)) / voxel;
    d.mean += e;
    d.max = std::max(d.max, e);
    ++n;
  };
  Fidelity f;
  std::size_t n_nodes = 0;
  std::size_t n_centroids = 0;
  std::size_t n_dense = 0;
  for (const auto& x : nodes) add(f.nodes, x, n_nodes);
  constexpr int kSteps = 4;
  for (const auto& t : triangles) {
    const Eigen::Vector3d& a = nodes[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = nodes[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = nodes[static_cast<std::size_t>(t[2])];
    add(f.centroids, (a + b + c) / 3.0, n_centroids);
    for (int i = 0; i <= kSteps; ++i)
      for (int j = 0; i + j <= kSteps; ++j) {
        const int k = kSteps - i - j;
        if (i == kSteps || j == kSteps || k == kSteps) continue;  // vertices are in `nodes`
        add(f.dense, (i * a + j * b + k * c) / kSteps, n_dense);
      }
  }
  f.nodes.mean /= static_cast<double>(n_nodes);
  f.centroids.mean /= static_cast<double>(n_centroids);
  f.dense.mean /= static_cast<double>(n_dense);
  return f;
}

Fidelity fidelity(const TriMesh& mesh, const Scene& scene, double voxel) {
  std::vector<Eigen::Vector3d> nodes;
  for (const auto v : mesh.vertices()) nodes.push_back(to_eigen(mesh.point(v)));
  std::vector<std::array<int, 3>> triangles;
  for (const auto f : mesh.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (const auto v : mesh.fv_range(f)) t[static_cast<std::size_t>(k++)] = v.idx();
    triangles.push_back(t);
  }
  return fidelity(nodes, triangles, scene, voxel);
}

void print(const std::string& what, const Fidelity& f) {
  std::printf("  %-28s nodes %.3f / %.3f  centroids %.3f / %.3f  dense %.3f / %.3f (mean / max, voxels)\n", what.c_str(),
              f.nodes.mean, f.nodes.max, f.centroids.mean, f.centroids.max, f.dense.mean, f.dense.max);
}

struct FidelityRun {
  Fidelity input;
  Fidelity plain;
  Fidelity bands;
  std::size_t n_failed = 0;
};

FidelityRun run(const std::string& name, int resolution, SampleMode mode) {
  const Scene scene = scene_by_name(name);
  const ScalarGrid grid = sample_scene(scene, resolution, mode);
  const TriMesh mesh = to_trimesh(marching_cubes(grid, scene_marching_cubes_options(mode)));
  const double voxel = grid.spacing.x();
  const Segmentation seg = segment(mesh);
  FidelityRun r;
  r.input = fidelity(mesh, scene, voxel);
  SurfMeshOptions options;
  options.threads = 2;
  const SurfaceMesh plain = mesh_surface(mesh, seg, options);
  r.plain = fidelity(plain.nodes, plain.triangles, scene, voxel);
  options.cell_grid = {true, grid.origin, grid.spacing};
  const SurfaceMesh bands = mesh_surface(mesh, seg, options);
  r.bands = fidelity(bands.nodes, bands.triangles, scene, voxel);
  for (const auto& p : bands.patches) r.n_failed += p.status == PatchStatus::Ok ? 0 : 1;
  for (const auto& p : plain.patches) r.n_failed += p.status == PatchStatus::Ok ? 0 : 1;
  std::printf("%s %d (%s):\n", name.c_str(), resolution, mode == SampleMode::Occupancy ? "occupancy" : "level set");
  print("marching-cubes input", r.input);
  print("surfmesh, plain fit", r.plain);
  print("surfmesh, band fit", r.bands);
  return r;
}

// The issue's bounds: mean at most a third of the input's, maximum under a quarter voxel,
// for nodes, triangle centroids and dense samples alike.
void expect_issue_bounds(const FidelityRun& r) {
  EXPECT_EQ(r.n_failed, 0u);
  EXPECT_LE(r.bands.nodes.mean, r.input.nodes.mean / 3.0);
  EXPECT_LE(r.bands.centroids.mean, r.input.centroids.mean / 3.0);
  EXPECT_LE(r.bands.dense.mean, r.input.dense.mean / 3.0);
  EXPECT_LT(r.bands.nodes.max, 0.25);
  EXPECT_LT(r.bands.centroids.max, 0.25);
  EXPECT_LT(r.bands.dense.max, 0.25);
}

TEST(SurfmeshFidelity, OccupancySphere48) { expect_issue_bounds(run("sphere", 48, SampleMode::Occupancy)); }

TEST(SurfmeshFidelitySlow, OccupancySphere96) { expect_issue_bounds(run("sphere", 96, SampleMode::Occupancy)); }

// The torus's tube (radius about 12 cells at 96) needs the curvature pass and the wider
// overlap of smooth patches (docs/surfmesh.md, "Cell-based inputs"): without them the top
// ring of the tube stayed 0.63 voxel low.
TEST(SurfmeshFidelitySlow, OccupancyTorus96) { expect_issue_bounds(run("torus", 96, SampleMode::Occupancy)); }

// The band fit's border projection must not make borders cross (it is undone curve by curve
// where it would): every patch of the occupancy DRAM cell at 128 is meshed.
TEST(SurfmeshFidelitySlow, OccupancyDramCell128AllPatchesOk) {
  const ScalarGrid grid = sample_scene(scene_by_name("dram"), 128, SampleMode::Occupancy);
  const TriMesh mesh = to_trimesh(marching_cubes(grid, scene_marching_cubes_options(SampleMode::Occupancy)));
  const Segmentation seg = segment(mesh);
  SurfMeshOptions options;
  options.threads = 2;
  options.cell_grid = {true, grid.origin, grid.spacing};
  const SurfaceMesh sm = mesh_surface(mesh, seg, options);
  ASSERT_EQ(sm.patches.size(), seg.patches.size());
  for (std::size_t p = 0; p < sm.patches.size(); ++p)
    EXPECT_EQ(sm.patches[p].status, PatchStatus::Ok) << "patch " << p << ": " << sm.patches[p].message;
}

}  // namespace
}  // namespace nurbsfront
