// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <cstdint>
#include <numbers>
#include <vector>

#include "isosurface/surface_checks.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"

namespace nurbsfront {
namespace {

const char* mode_name(SampleMode m) { return m == SampleMode::LevelSet ? "level set" : "occupancy"; }

// True if the scene's surface is provably within r of p. The scene's f satisfies
// |f(q)| <= dist(q, surface) (exact for sphere and torus, a CSG lower bound otherwise), so
// |f(p)| > r proves "no". A "yes" needs a witness: a point q with |q - p| <= r where f has the
// opposite sign (or f = 0): the segment p-q then meets the surface. Witnesses are searched first
// one step of about |f(p)| down the numerical gradient, then along the 26 grid directions at 32
// radii; marching-cubes vertices lie on grid edges, so the opposite-signed end of their edge is on
// one of these rays. The check is conservative: it never
// accepts a vertex that is farther than r from the true surface.
bool surface_within(const Scene& scene, const Eigen::Vector3d& p, double r) {
  const double f0 = signed_distance(scene, p);
  if (std::abs(f0) > r) return false;
  if (f0 == 0.0) return true;
  auto opposite = [&](const Eigen::Vector3d& q) { return (f0 < 0.0) != (signed_distance(scene, q) < 0.0); };
  // Fast witness: step towards the surface along the numerical gradient, about |f0| far.
  const double e = r * 1e-3;
  Eigen::Vector3d grad;
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d[a] = e;
    grad[a] = signed_distance(scene, p + d) - signed_distance(scene, p - d);
  }
  if (grad.norm() > 0.0) {
    const Eigen::Vector3d toward = -(f0 > 0.0 ? 1.0 : -1.0) * grad.normalized();
    for (const double s : {std::abs(f0) * 1.001, std::abs(f0) * 1.05 + r / 64, r}) {
      if (s <= r && opposite(p + s * toward)) return true;
    }
  }
  // Exhaustive: the 6 axis directions first (the opposite end of the vertex's grid edge), then the diagonals.
  constexpr int kSteps = 32;
  std::vector<Eigen::Vector3d> dirs;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        dirs.push_back(Eigen::Vector3d(dx, dy, dz).normalized());
      }
  std::stable_sort(dirs.begin(), dirs.end(), [](const auto& a, const auto& b) {
    return a.cwiseAbs().maxCoeff() > b.cwiseAbs().maxCoeff();
  });
  for (int s = 1; s <= kSteps; ++s) {
    for (const auto& d : dirs) {
      if (opposite(p + (r * s / kSteps) * d)) return true;
    }
  }
  return false;
}

struct Case {
  const char* name;
  int resolution;
  SampleMode mode;
  bool has_euler;
  int euler;
};

void check_scene(const Case& c) {
  SCOPED_TRACE(std::string(c.name) + " at " + std::to_string(c.resolution) + " " + mode_name(c.mode));
  const Scene scene = scene_by_name(c.name);
  const ScalarGrid grid = sample_scene(scene, c.resolution, c.mode);
  const TriangleSoup soup = marching_cubes(grid, scene_marching_cubes_options(c.mode));
  ASSERT_FALSE(soup.triangles.empty());
  const auto facts = test::expect_clean_surface(soup, true, c.name);
  if (c.has_euler) {
    EXPECT_EQ(facts.euler, c.euler);
  }
  // The surface lies in the scene's box (grown by one cell).
  const BoundingBox box = bounding_box(scene);
  const BoundingBox got = bounding_box(soup);
  const double h = grid.spacing.x();
  EXPECT_TRUE(((got.min - box.min).array() >= -h).all() && ((box.max - got.max).array() >= -h).all());
  const double r = 0.5 * std::sqrt(3.0) * h;
  std::size_t n_far = 0;
  for (const auto& p : soup.points) n_far += surface_within(scene, p, r) ? 0 : 1;
  EXPECT_EQ(n_far, 0u) << "vertices farther than half a voxel diagonal from the surface";
}

TEST(Scenes, SphereAndTorusAt64) {
  for (const SampleMode m : {SampleMode::LevelSet, SampleMode::Occupancy}) {
    check_scene({"sphere", 64, m, true, 2});
    check_scene({"torus", 64, m, true, 0});
  }
}

TEST(Scenes, TrenchAndDramAt64) {
  for (const SampleMode m : {SampleMode::LevelSet, SampleMode::Occupancy}) {
    check_scene({"trench", 64, m, true, 2});
    check_scene({"dram", 64, m, false, 0});
  }
}

TEST(ScenesSlow, DramLevelSetAt128HasItsGenus) {
  // Genus 10: each of the 2 bit lines rests on 4 word lines (3 tunnels each) and each of the
  // 4 plugs joins a bit line to the substrate (1 more loop each). chi = 2 - 2 * 10.
  check_scene({"dram", 128, SampleMode::LevelSet, true, -18});
}

TEST(ScenesSlow, AllScenesAt256BothModes) {
  for (const SampleMode m : {SampleMode::LevelSet, SampleMode::Occupancy}) {
    check_scene({"sphere", 256, m, true, 2});
    check_scene({"torus", 256, m, true, 0});
    check_scene({"trench", 256, m, true, 2});
    check_scene({"dram", 256, m, m == SampleMode::LevelSet, -18});
  }
}

TEST(ScenesSlow, AllScenesAt128BothModes) {
  for (const SampleMode m : {SampleMode::LevelSet, SampleMode::Occupancy}) {
    check_scene({"sphere", 128, m, true, 2});
    check_scene({"torus", 128, m, true, 0});
    check_scene({"trench", 128, m, true, 2});
    check_scene({"dram", 128, m, m == SampleMode::LevelSet, -18});
  }
}

TEST(Scenes, SphereVolumeIsClose) {
  const Scene scene = SphereScene{};
  const TriangleSoup soup = marching_cubes(sample_scene(scene, 64), scene_marching_cubes_options(SampleMode::LevelSet));
  const double exact = 4.0 / 3.0 * std::numbers::pi;
  EXPECT_NEAR(test::surface_facts(soup).signed_volume, exact, 0.01 * exact);
}

TEST(Scenes, ExactDistancesAndBoxes) {
  EXPECT_DOUBLE_EQ(signed_distance(SphereScene{}, Eigen::Vector3d(2, 0, 0)), 1.0);
  EXPECT_DOUBLE_EQ(signed_distance(SphereScene{}, Eigen::Vector3d(0, 0, 0)), -1.0);
  EXPECT_NEAR(signed_distance(TorusScene{}, Eigen::Vector3d(1, 0, 0)), -0.35, 1e-15);
  EXPECT_NEAR(signed_distance(TorusScene{}, Eigen::Vector3d(0, 0, 0)), 1.0 - 0.35, 1e-15);
  // Trench: above the groove's centre the surface is the groove bottom, depth 0.6 below the top.
  const TrenchScene trench;
  EXPECT_NEAR(signed_distance(trench, Eigen::Vector3d(1.0, 0.75, 0.3)), -0.1, 1e-12);
  EXPECT_LT(signed_distance(trench, Eigen::Vector3d(0.2, 0.75, 0.5)), 0.0);
  TrenchScene round = trench;
  round.rounded = true;
  EXPECT_NEAR(signed_distance(round, Eigen::Vector3d(1.0, 0.75, 0.3)), -0.1, 1e-12);
  EXPECT_GT(signed_distance(round, Eigen::Vector3d(1.0, 0.75, 0.45)), 0.0);
  const BoundingBox dram = bounding_box(DramScene{});
  EXPECT_TRUE(dram.max.isApprox(Eigen::Vector3d(2.25, 1.75, 3.45)));
  EXPECT_TRUE(dram.min.isZero());
  // Inside the substrate, inside a cup wall, in a cup's hollow, between the cups.
  const DramScene d;
  EXPECT_LT(signed_distance(d, Eigen::Vector3d(1.0, 1.0, 0.25)), 0.0);
  EXPECT_LT(signed_distance(d, Eigen::Vector3d(0.5625 + 0.33, 0.4375, 3.0)), 0.0);
  EXPECT_GT(signed_distance(d, Eigen::Vector3d(0.5625, 0.4375, 3.0)), 0.0);
  EXPECT_GT(signed_distance(d, Eigen::Vector3d(1.125, 0.875, 3.0)), 0.0);
}

TEST(Scenes, SamplingGridCoversTheBoxWithAMargin) {
  const ScalarGrid g = sample_scene(SphereScene{}, 32, SampleMode::Occupancy);
  EXPECT_EQ(g.dims[0], 32 + 1 + 2 * kSceneMarginCells);
  EXPECT_DOUBLE_EQ(g.spacing.x(), 2.0 / 32);
  EXPECT_NEAR(g.point(0, 0, 0).x(), -1.0 - kSceneMarginCells * g.spacing.x(), 1e-12);
  for (const float v : g.values) EXPECT_TRUE(v == 0.0f || v == 1.0f);
  // The margin is outside.
  EXPECT_EQ(g.value(0, 0, 0), 0.0f);
}

TEST(Scenes, NamesAndValidation) {
  for (const auto& name : scene_names()) EXPECT_NO_THROW((void)scene_by_name(name));
  EXPECT_THROW((void)scene_by_name("teapot"), InvalidInput);
  EXPECT_THROW((void)sample_scene(SphereScene{}, 2), InvalidInput);
  SphereScene bad;
  bad.radius = -1.0;
  EXPECT_THROW((void)sample_scene(bad, 32), InvalidInput);
  TrenchScene deep;
  deep.groove_depth = 2.0;
  EXPECT_THROW(validate(Scene{deep}), InvalidInput);
}

// distance_to_scene: hand-computed distances of an octahedron inscribed in the unit sphere
// (vertices on it, face centroids at 1/sqrt(3), edge midpoints at 1/sqrt(2) from the centre)
// and of a triangle parallel to the trench's top face.
TEST(Scenes, DistanceToSceneIsExactOnKnownShapes) {
  TriangleSoup octahedron;
  for (int a = 0; a < 3; ++a)
    for (const double s : {1.0, -1.0}) octahedron.points.push_back(s * Eigen::Vector3d::Unit(a));
  for (const std::uint32_t x : {0u, 1u})
    for (const std::uint32_t y : {2u, 3u})
      for (const std::uint32_t z : {4u, 5u}) octahedron.triangles.push_back({x, y, z});
  const double centroid = 1.0 - 1.0 / std::sqrt(3.0);
  const double midpoint = 1.0 - 1.0 / std::sqrt(2.0);
  const SceneDistance d = distance_to_scene(octahedron, SphereScene{}, 2);
  EXPECT_EQ(d.vertices.count, 6u);
  EXPECT_NEAR(d.vertices.max, 0.0, 1e-15);
  EXPECT_EQ(d.centroids.count, 8u);
  EXPECT_NEAR(d.centroids.mean, centroid, 1e-15);
  EXPECT_NEAR(d.centroids.max, centroid, 1e-15);
  EXPECT_EQ(d.dense.count, 24u);  // 3 edge midpoints per triangle
  EXPECT_NEAR(d.dense.mean, midpoint, 1e-15);
  const DistanceSummary all = d.all();
  EXPECT_EQ(all.count, 38u);
  EXPECT_NEAR(all.mean, (8.0 * centroid + 24.0 * midpoint) / 38.0, 1e-15);
  EXPECT_NEAR(all.max, centroid, 1e-15);
  EXPECT_EQ(distance_to_scene(octahedron, SphereScene{}).dense.count, 0u);

  // 0.1 above the slab's top face, away from the groove: every sample at 0.1.
  TriangleSoup above;
  above.points = {{0.2, 0.2, 1.1}, {0.5, 0.2, 1.1}, {0.2, 0.5, 1.1}};
  above.triangles = {{0, 1, 2}};
  const SceneDistance t = distance_to_scene(above, TrenchScene{}, 4);
  EXPECT_EQ(t.dense.count, 12u);
  for (const DistanceSummary& s : {t.vertices, t.centroids, t.dense}) {
    EXPECT_NEAR(s.mean, 0.1, 1e-12);
    EXPECT_NEAR(s.max, 0.1, 1e-12);
  }

  above.triangles = {{0, 1, 3}};
  EXPECT_THROW((void)distance_to_scene(above, TrenchScene{}), InvalidInput);
  above.triangles = {{0, 1, 2}};
  EXPECT_THROW((void)distance_to_scene(above, TrenchScene{}, -1), InvalidInput);
  EXPECT_THROW((void)distance_to_scene(above, SphereScene{{0, 0, 0}, -1.0}), InvalidInput);
}

}  // namespace
}  // namespace nurbsfront
