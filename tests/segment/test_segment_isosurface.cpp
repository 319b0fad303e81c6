// SPDX-License-Identifier: BSD-3-Clause
// Segmentation of marching-cubes surfaces of the isosurface module's analytic scenes:
// terraced (occupancy) and smooth (level-set) inputs.

#include <gtest/gtest.h>

#include <string>

#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/segment/segment.h"
#include "segment/contracts.h"

namespace nurbsfront {
namespace {

TriMesh scene_mesh(const std::string& name, int resolution, SampleMode mode) {
  const ScalarGrid grid = sample_scene(scene_by_name(name), resolution, mode);
  return to_trimesh(marching_cubes(grid, scene_marching_cubes_options(mode)));
}

// Raw normals of terraced faces sit up to ~50 deg from the smoothed ones: the raw slope is
// only bounded by the orientation guarantee (kSegmentMinRawNormalDot), checked anyway.
constexpr double kTerracedSlack = 30.0;

TEST(SegmentIsosurface, OccupancySphereGivesFewPatchesAllHeightFields) {
  const TriMesh mesh = scene_mesh("sphere", 40, SampleMode::Occupancy);
  const SegmentOptions options;
  const Segmentation seg = segment_test::run(mesh, options, kTerracedSlack);
  EXPECT_EQ(seg.n_crease_edges, 0u);  // terraces are not creases at the default angle
  EXPECT_GE(seg.patches.size(), 4u);
  EXPECT_LE(seg.patches.size(), 30u);
  // Patches below min_patch_faces remain only where no neighbour's axis can take them
  // (steep terrace faces at cap borders): a small share of the surface.
  std::size_t n_small_faces = 0;
  for (const Patch& p : seg.patches) n_small_faces += p.faces.size() < options.min_patch_faces ? p.faces.size() : 0;
  EXPECT_LT(n_small_faces, mesh.n_faces() / 50);
}

TEST(SegmentIsosurface, RawNormalsFragmentTheTerracedSphere) {
  // The pitfall the smoothing exists for: without it the same sphere falls apart.
  const TriMesh mesh = scene_mesh("sphere", 40, SampleMode::Occupancy);
  SegmentOptions options;
  const std::size_t smoothed = segment(mesh, options).patches.size();
  options.normal_smoothing_rings = 0;
  options.min_patch_faces = 0;
  const Segmentation raw = segment_test::run(mesh, options, kTerracedSlack);
  EXPECT_GT(raw.patches.size(), 2 * smoothed);
}

TEST(SegmentIsosurface, LevelSetSphereAndTorus) {
  const SegmentOptions options;
  const Segmentation sphere = segment_test::run(scene_mesh("sphere", 32, SampleMode::LevelSet), options, 10.0);
  EXPECT_LE(sphere.patches.size(), 30u);
  const Segmentation torus = segment_test::run(scene_mesh("torus", 32, SampleMode::LevelSet), options, 10.0);
  EXPECT_LE(torus.patches.size(), 60u);
}

TEST(SegmentIsosurface, OccupancyTrench) {
  (void)segment_test::run(scene_mesh("trench", 32, SampleMode::Occupancy), {}, kTerracedSlack);
}

TEST(SegmentIsosurfaceSlow, DramCellBothModes) {
  for (const SampleMode mode : {SampleMode::Occupancy, SampleMode::LevelSet}) {
    const TriMesh mesh = scene_mesh("dram", 96, mode);
    const Segmentation seg = segment_test::run(mesh, {}, kTerracedSlack);
    EXPECT_GT(seg.n_crease_edges, 0u);
  }
}

TEST(SegmentIsosurfaceSlow, FineOccupancySphere) {
  const TriMesh mesh = scene_mesh("sphere", 128, SampleMode::Occupancy);
  const Segmentation seg = segment_test::run(mesh, {}, kTerracedSlack);
  EXPECT_LE(seg.patches.size(), 100u);
}

}  // namespace
}  // namespace nurbsfront
