// SPDX-License-Identifier: BSD-3-Clause
// The library example of README.md, kept compiling and checked.
#include <gtest/gtest.h>

#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/pipeline/remesh.h"
#include "support/test_data.h"

namespace {

TEST(ReadmeExample, RemeshedSphereIsClosedManifoldAndWritten) {
  using namespace nurbsfront;
  const auto out = test::temp_dir("readme") / "sphere.ply";
  // --- as in README.md (resolution lowered from 64 to keep the test fast) ---
  ScalarGrid grid = sample_scene(scene_by_name("sphere"), 32, SampleMode::Occupancy);
  TriangleSoup surface = marching_cubes(grid, scene_marching_cubes_options(SampleMode::Occupancy));
  TriMesh input = to_trimesh(clean(surface).soup);
  RemeshOptions options;
  RemeshResult result = remesh(input, options);
  const RemeshReport& report = result.report;
  write_mesh(result.mesh, out);
  // ---
  EXPECT_TRUE(report.ok());
  EXPECT_TRUE(report.output.topology.is_closed);
  EXPECT_TRUE(report.output.topology.is_manifold);
  EXPECT_TRUE(report.output.topology.is_consistently_oriented);
  EXPECT_EQ(report.output.topology.euler_characteristic, 2);
  EXPECT_EQ(report.output.topology.n_self_intersecting_pairs.value_or(1), 0u);
  ASSERT_TRUE(report.output.distance.has_value());
  EXPECT_GT(report.output.quality.alpha_mean, 0.9);
  const TriMesh back = read_mesh(out);
  EXPECT_EQ(back.n_faces(), result.mesh.n_faces());
}

}  // namespace
