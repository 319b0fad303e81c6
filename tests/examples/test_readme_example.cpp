// SPDX-License-Identifier: BSD-3-Clause
// The library example of README.md, kept compiling and checked.
#include <gtest/gtest.h>

#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/quality/report.h"
#include "support/test_data.h"

namespace {

TEST(ReadmeExample, DramSurfaceIsClosedManifoldAndWritten) {
  using namespace nurbsfront;
  const auto out = test::temp_dir("readme") / "dram.ply";
  // --- as in README.md (resolution lowered from 128 to keep the test fast) ---
  ScalarGrid grid = sample_scene(scene_by_name("dram"), 48, SampleMode::LevelSet);
  TriangleSoup surface = marching_cubes(grid, scene_marching_cubes_options(SampleMode::LevelSet));
  MeshReport report = mesh_report(surface);
  write_soup(surface, out);
  // ---
  EXPECT_TRUE(report.topology.is_closed);
  EXPECT_TRUE(report.topology.is_manifold);
  EXPECT_TRUE(report.topology.is_consistently_oriented);
  EXPECT_EQ(report.topology.n_self_intersecting_pairs.value_or(1), 0u);
  EXPECT_GT(report.quality.alpha_mean, 0.0);
  const TriMesh back = read_mesh(out);
  EXPECT_EQ(back.n_faces(), surface.triangles.size());
}

}  // namespace
