// SPDX-License-Identifier: BSD-3-Clause
// Curvature-adaptive sizing (issue 5, SizingOptions::adaptive): on a flat ellipsoid, whose
// largest principal curvature runs from c / a^2 at the poles to a / c^2 on the rim, the
// adaptive mesh keeps the chord deviation near the tolerance with fewer nodes than a
// uniform mesh sized for the rim (slow test); rim and cap edges follow the curvature and the
// output is the same for any thread count (fast test).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/surfmesh/surfmesh.h"

namespace nurbsfront {
namespace {

constexpr double kA = 1.0;   // x and y radius
constexpr double kC = 0.35;  // z radius

// Algebraic g(p) = |p / r| - 1 and the first-order distance |g| / |grad g| (accurate for
// points near the surface, which is all we measure).
double ellipsoid_g(const Eigen::Vector3d& p) {
  return std::sqrt((p.x() / kA) * (p.x() / kA) + (p.y() / kA) * (p.y() / kA) + (p.z() / kC) * (p.z() / kC)) - 1.0;
}
double ellipsoid_distance(const Eigen::Vector3d& p) {
  const Eigen::Vector3d q(p.x() / (kA * kA), p.y() / (kA * kA), p.z() / (kC * kC));
  const double r = std::sqrt((p.x() / kA) * (p.x() / kA) + (p.y() / kA) * (p.y() / kA) + (p.z() / kC) * (p.z() / kC));
  return std::abs(ellipsoid_g(p)) / (q.norm() / r);
}

TriMesh ellipsoid_surface(int resolution) {
  ScalarGrid grid;
  const double h = 2.4 * kA / resolution;
  grid.spacing = Eigen::Vector3d::Constant(h);
  grid.dims = {resolution + 1, resolution + 1, static_cast<int>(std::ceil(2.4 * kC / h)) + 1};
  grid.origin = -0.5 * h * Eigen::Vector3d(grid.dims[0] - 1, grid.dims[1] - 1, grid.dims[2] - 1);
  grid.values.resize(grid.size());
  for (int k = 0; k < grid.dims[2]; ++k)
    for (int j = 0; j < grid.dims[1]; ++j)
      for (int i = 0; i < grid.dims[0]; ++i)
        grid.values[grid.index(i, j, k)] = static_cast<float>(kC * ellipsoid_g(grid.point(i, j, k)));
  MarchingCubesOptions mc;
  mc.iso = 0.0;
  return to_trimesh(clean(marching_cubes(grid, mc)).soup);
}

// Largest distance to the ellipsoid of the nodes and of the midpoints and centroids of the
// triangles (where the chord sags most).
double max_deviation(const SurfaceMesh& sm) {
  double d = 0.0;
  for (const auto& x : sm.nodes) d = std::max(d, ellipsoid_distance(x));
  for (const auto& t : sm.triangles) {
    const Eigen::Vector3d& a = sm.nodes[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = sm.nodes[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = sm.nodes[static_cast<std::size_t>(t[2])];
    for (const Eigen::Vector3d& q : {Eigen::Vector3d((a + b + c) / 3.0), Eigen::Vector3d(0.5 * (a + b)),
                                     Eigen::Vector3d(0.5 * (b + c)), Eigen::Vector3d(0.5 * (c + a))})
      d = std::max(d, ellipsoid_distance(q));
  }
  return d;
}

std::size_t n_failed(const SurfaceMesh& sm) {
  return static_cast<std::size_t>(
      std::count_if(sm.patches.begin(), sm.patches.end(), [](const PatchMeshReport& p) { return p.status != PatchStatus::Ok; }));
}

// Slow: about 0.4 s in RelWithDebInfo, 45 s under ASan+UBSan in Debug (three runs at 48 cells).
TEST(SurfmeshAdaptiveSlow, FlatEllipsoidMeetsTheChordToleranceWithFewerNodesThanUniform) {
  const TriMesh mesh = ellipsoid_surface(48);
  const Segmentation seg = segment(mesh);
  const double chord = 0.004;
  const double kappa_max = kA / (kC * kC);
  const double h_rim = std::sqrt(8.0 * chord / kappa_max);

  SurfMeshOptions adaptive;
  adaptive.sizing.size = 0.2;  // coarse: the curvature decides almost everywhere
  adaptive.sizing.adaptive = true;
  adaptive.sizing.chord_error = chord;
  adaptive.threads = 1;
  const SurfaceMesh a = mesh_surface(mesh, seg, adaptive);
  ASSERT_EQ(n_failed(a), 0U);

  SurfMeshOptions uniform;  // every edge as short as the rim needs
  uniform.sizing.size = h_rim;
  uniform.threads = 1;
  const SurfaceMesh u = mesh_surface(mesh, seg, uniform);
  ASSERT_EQ(n_failed(u), 0U);

  SurfMeshOptions coarse;  // the adaptive run's uniform size without adaptation
  coarse.sizing.size = adaptive.sizing.size;
  coarse.threads = 1;
  const SurfaceMesh c = mesh_surface(mesh, seg, coarse);

  const double dev_a = max_deviation(a), dev_u = max_deviation(u), dev_c = max_deviation(c);
  std::printf("chord %.4g: adaptive %zu nodes, max deviation %.4g; uniform h %.4g: %zu nodes, %.4g; "
              "uniform h %.4g: %zu nodes, %.4g\n",
              chord, a.nodes.size(), dev_a, h_rim, u.nodes.size(), dev_u, coarse.sizing.size, c.nodes.size(), dev_c);
  // The chord sag of a triangle is up to about 4/3 of an edge's, and the fit of the rim
  // (48 cells, lattice 2.5 input edges) adds about as much: the uniform mesh sized for the rim
  // is off by about twice the tolerance too. Same deviation, far fewer nodes:
  EXPECT_LT(dev_a, 2.5 * chord);
  EXPECT_LT(dev_a, 1.5 * dev_u);
  EXPECT_GT(dev_c, 2.5 * chord);  // without adaptation the tolerance is missed
  EXPECT_LT(a.nodes.size(), u.nodes.size() / 2);

  // Bit-identical for any thread count.
  adaptive.threads = 2;
  const SurfaceMesh a2 = mesh_surface(mesh, seg, adaptive);
  EXPECT_EQ(a.nodes, a2.nodes);
  EXPECT_EQ(a.triangles, a2.triangles);
}

TEST(SurfmeshAdaptive, SizesFollowTheCurvatureAndTheGradation) {
  // A coarse uniform h and a chord tolerance give edges on the rim near sqrt(8 e / kappa)
  // and longer ones on the flat caps.
  const TriMesh mesh = ellipsoid_surface(40);
  const Segmentation seg = segment(mesh);
  SurfMeshOptions o;
  o.sizing.size = 0.25;
  o.sizing.adaptive = true;
  o.sizing.chord_error = 0.004;
  o.threads = 1;
  const SurfaceMesh sm = mesh_surface(mesh, seg, o);
  ASSERT_EQ(n_failed(sm), 0U);
  double rim_sum = 0.0, cap_sum = 0.0, shortest = 1e9;
  std::size_t n_rim = 0, n_cap = 0;
  for (const auto& t : sm.triangles) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = sm.nodes[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])];
      const Eigen::Vector3d& q = sm.nodes[static_cast<std::size_t>(t[static_cast<std::size_t>((k + 1) % 3)])];
      const double length = (p - q).norm();
      shortest = std::min(shortest, length);
      const double z = std::abs(0.5 * (p.z() + q.z()));
      if (z < 0.1 * kC) {
        rim_sum += length;
        ++n_rim;
      } else if (z > 0.95 * kC) {
        cap_sum += length;
        ++n_cap;
      }
    }
  }
  ASSERT_GT(n_rim, 0U);
  ASSERT_GT(n_cap, 0U);
  const double rim = rim_sum / static_cast<double>(n_rim), cap = cap_sum / static_cast<double>(n_cap);
  const double h_rim = std::sqrt(8.0 * o.sizing.chord_error * kC * kC / kA);
  std::printf("rim mean edge %.4g (sqrt(8 e / kappa) = %.4g), cap mean edge %.4g, shortest %.4g\n", rim, h_rim, cap, shortest);
  EXPECT_LT(rim, 1.6 * h_rim);
  EXPECT_GT(rim, 0.5 * h_rim);
  EXPECT_GT(cap, 2.0 * rim);

  // Bit-identical for any thread count.
  o.threads = 2;
  const SurfaceMesh sm2 = mesh_surface(mesh, seg, o);
  EXPECT_EQ(sm.nodes, sm2.nodes);
  EXPECT_EQ(sm.triangles, sm2.triangles);
}

}  // namespace
}  // namespace nurbsfront
