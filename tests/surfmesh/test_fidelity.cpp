// SPDX-License-Identifier: BSD-3-Clause
// Fidelity to the true surface (issue 5): distance of the remeshed occupancy (0/1) sphere
// and torus to the analytic surface, in voxels, with the band fit of CellGrid against the
// marching-cubes input and against the plain fit; level-set inputs must not get worse.

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/surfmesh/surfmesh.h"

namespace nurbsfront {
namespace {

// Distances to the scene's surface (distance_to_scene, in voxels) of the nodes, of the
// triangle centroids and of dense samples (the 12 points of a 4-step barycentric grid in every
// triangle that are not its vertices).
struct Fidelity {
  DistanceSummary nodes;
  DistanceSummary centroids;
  DistanceSummary dense;
};

Fidelity fidelity(const TriangleSoup& soup, const Scene& scene, double voxel) {
  const SceneDistance d = distance_to_scene(soup, scene, 4);
  auto in_voxels = [voxel](DistanceSummary s) {
    s.mean /= voxel;
    s.max /= voxel;
    return s;
  };
  return {in_voxels(d.vertices), in_voxels(d.centroids), in_voxels(d.dense)};
}

Fidelity fidelity(const SurfaceMesh& mesh, const Scene& scene, double voxel) {
  TriangleSoup soup;
  soup.points = mesh.nodes;
  for (const auto& t : mesh.triangles)
    soup.triangles.push_back({static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]), static_cast<std::uint32_t>(t[2])});
  return fidelity(soup, scene, voxel);
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
  r.input = fidelity(to_soup(mesh), scene, voxel);
  SurfMeshOptions options;
  options.threads = 2;
  const SurfaceMesh plain = mesh_surface(mesh, seg, options);
  r.plain = fidelity(plain, scene, voxel);
  options.cell_grid = {true, grid.origin, grid.spacing};
  const SurfaceMesh bands = mesh_surface(mesh, seg, options);
  r.bands = fidelity(bands, scene, voxel);
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

// At 64 cells the tube's radius is 8 cells: its patches need the shorter smoothing length of
// CellGrid::curved_smoothing (2.25 cells left the dense mean at 0.047 voxel, a third of the
// input's is 0.046; docs/surfmesh.md, "Smoothing length of curved patches").
TEST(SurfmeshFidelitySlow, OccupancyTorus64) { expect_issue_bounds(run("torus", 64, SampleMode::Occupancy)); }

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
