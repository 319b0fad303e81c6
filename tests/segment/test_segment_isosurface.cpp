// SPDX-License-Identifier: BSD-3-Clause
// Segmentation of marching-cubes surfaces of the isosurface module's analytic scenes:
// terraced (occupancy) and smooth (level-set) inputs.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/quality/aabb_tree.h"
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

// BorderSmoothingOptions::max_input_distance: the largest distance to the input of a curve's
// smoothed points, in mean curve edges, over all curves.
double largest_border_distance(const TriMesh& mesh, const SegmentOptions& options) {
  const Segmentation seg = segment(mesh, options);
  const TriangleSoup soup = to_soup(mesh);
  std::vector<std::uint32_t> faces(soup.triangles.size());
  std::iota(faces.begin(), faces.end(), 0U);
  const quality_detail::AabbTree tree(soup, faces);
  double worst = 0.0;
  for (const BorderCurve& curve : seg.curves) {
    const std::size_t n = curve.vertices.size();
    if (n < 3) continue;
    const std::size_t n_segments = curve.is_closed ? n : n - 1;
    double length = 0.0;
    for (std::size_t i = 0; i < n_segments; ++i) {
      length += (to_eigen(mesh.point(mesh.vertex_handle(static_cast<unsigned>(curve.vertices[(i + 1) % n])))) -
                 to_eigen(mesh.point(mesh.vertex_handle(static_cast<unsigned>(curve.vertices[i])))))
                    .norm();
    }
    const double mean_edge = length / static_cast<double>(n_segments);
    for (const auto& p : curve.smoothed) {
      worst = std::max(worst, std::sqrt(tree.closest(p, UINT32_MAX).squared_distance) / mean_edge);
    }
  }
  return worst;
}

TEST(SegmentIsosurface, SmoothedBordersStayWithinTheirBoundOfTheInput) {
  // Level-set torus: the Taubin steps cut the curves' bends across the curved surface; with
  // the bound every smoothed point lies within it of the input (the exact distance to the
  // whole input, at most the one to the faces around the curve that the bound reads).
  const TriMesh mesh = scene_mesh("torus", 32, SampleMode::LevelSet);
  SegmentOptions options;
  const double unbounded = largest_border_distance(mesh, options);
  EXPECT_GT(unbounded, 0.05);
  options.border_smoothing.max_input_distance = 0.05;
  EXPECT_LE(largest_border_distance(mesh, options), 0.05 * (1.0 + 1e-9));
  options.border_smoothing.max_input_distance = -1.0;
  EXPECT_THROW((void)segment(mesh, options), InvalidInput);
}

// The per-patch loops of segment() on the run's threads (session 21: the merges' first
// cones, the axes' refinement and the face lists' sorts, 16 patches a task): the same
// patches, axes and counts at 1, 2 and 4 threads, on an input with more than 32 patches
// (several tasks) whose fold splits run the second merge (after the splits).
TEST(SegmentIsosurface, PerPatchLoopsAreTheSameOnAnyThreadCount) {
  const TriMesh mesh = scene_mesh("dram", 64, SampleMode::Occupancy);
  SegmentOptions options;
  options.threads = 1;
  const Segmentation one = segment(mesh, options);
  ASSERT_GT(one.patches.size(), 32u);
  EXPECT_GT(one.n_fold_splits, 0u);
  for (const int threads : {2, 4}) {
    options.threads = threads;
    const Segmentation many = segment(mesh, options);
    EXPECT_EQ(one.face_patch, many.face_patch) << threads;
    EXPECT_EQ(one.n_fold_splits, many.n_fold_splits) << threads;
    EXPECT_EQ(one.n_islands_absorbed, many.n_islands_absorbed) << threads;
    ASSERT_EQ(one.patches.size(), many.patches.size()) << threads;
    for (std::size_t p = 0; p < one.patches.size(); ++p) {
      EXPECT_EQ(one.patches[p].axis, many.patches[p].axis) << threads << " patch " << p;
      EXPECT_EQ(one.patches[p].faces, many.patches[p].faces) << threads << " patch " << p;
    }
  }
}

// SegmentOptions::threads: the per-face loops (more than one chunk of faces here), the
// projection and cliff checks and the curve smoothing run on several workers; the result
// is the same for any thread count, the splitter's rounds too.
TEST(SegmentIsosurface, ResultDoesNotDependOnTheThreadCount) {
  const TriMesh mesh = scene_mesh("sphere", 40, SampleMode::Occupancy);
  ASSERT_GT(mesh.n_faces(), 8192u);  // two chunks of the per-face loops
  auto expect_same = [](const Segmentation& a, const Segmentation& b) {
    EXPECT_EQ(a.face_patch, b.face_patch);
    EXPECT_EQ(a.corners, b.corners);
    EXPECT_EQ(a.n_fold_splits, b.n_fold_splits);
    EXPECT_EQ(a.n_slope_exceptions, b.n_slope_exceptions);
    EXPECT_EQ(a.n_crease_edges, b.n_crease_edges);
    ASSERT_EQ(a.patches.size(), b.patches.size());
    for (std::size_t p = 0; p < a.patches.size(); ++p) EXPECT_EQ(a.patches[p].axis, b.patches[p].axis) << "patch " << p;
    ASSERT_EQ(a.curves.size(), b.curves.size());
    for (std::size_t c = 0; c < a.curves.size(); ++c) {
      EXPECT_EQ(a.curves[c].vertices, b.curves[c].vertices) << "curve " << c;
      EXPECT_EQ(a.curves[c].smoothed, b.curves[c].smoothed) << "curve " << c;
    }
  };
  SegmentOptions raw;  // raw normals: many small patches
  raw.normal_smoothing_rings = 0;
  raw.min_patch_faces = 0;
  for (SegmentOptions options : {SegmentOptions{}, raw}) {
    options.threads = 1;
    const Segmentation one = segment(mesh, options);
    PatchSplitter one_splitter(mesh, options);
    options.threads = 3;
    const Segmentation three = segment(mesh, options);
    PatchSplitter three_splitter(mesh, options);
    expect_same(one, three);
    ASSERT_GE(one.patches.size(), 4u);
    const std::vector<int> which{0, 1, 2, 3};
    expect_same(one_splitter.split(one, which), three_splitter.split(three, which));
  }
}

TEST(SegmentIsosurface, LevelSetSphereAndTorus) {
  const SegmentOptions options;
  const Segmentation sphere = segment_test::run(scene_mesh("sphere", 32, SampleMode::LevelSet), options, 10.0);
  EXPECT_LE(sphere.patches.size(), 30u);
  const Segmentation torus = segment_test::run(scene_mesh("torus", 32, SampleMode::LevelSet), options, 10.0);
  EXPECT_LE(torus.patches.size(), 60u);
}

// Edges with a dihedral of at least 30 deg whose two faces are in the same patch.
std::size_t bends_inside_patches(const TriMesh& mesh, const Segmentation& seg) {
  std::size_t n = 0;
  const double cos_bend = std::cos(30.0 * std::numbers::pi / 180.0);
  for (const auto e : mesh.edges()) {
    if (mesh.is_boundary(e)) continue;
    const auto f = mesh.face_handle(mesh.halfedge_handle(e, 0));
    const auto g = mesh.face_handle(mesh.halfedge_handle(e, 1));
    if (seg.face_patch[f.idx()] != seg.face_patch[g.idx()]) continue;
    const TriMesh::Normal nf = mesh.calc_face_normal(f);
    const TriMesh::Normal ng = mesh.calc_face_normal(g);
    if (nf.norm() > 0 && ng.norm() > 0 && (nf | ng) / (nf.norm() * ng.norm()) < cos_bend) ++n;
  }
  return n;
}

TEST(SegmentIsosurface, BevelCreasesKeepTheBevelledBoxEdgesOutOfThePatches) {
  // Marching cubes bevels the trench's 90 deg box edges into two ~45 deg bends, below the
  // crease angle: without bevel creases a patch holds one bend of every bevel inside.
  constexpr int kCells = 48;
  const TriMesh mesh = scene_mesh("trench", kCells, SampleMode::LevelSet);
  SegmentOptions options;
  const Segmentation plain = segment(mesh, options);  // the default path's contracts are tested above
  EXPECT_EQ(plain.n_bevel_crease_edges, 0u);
  EXPECT_GT(bends_inside_patches(mesh, plain), static_cast<std::size_t>(kCells));
  options.bevel_creases = true;
  // A bevel strip is its own patch: its raw normals may lean further from its axis than on a
  // smooth surface (the raw bound kSegmentMinRawNormalDot still holds, checked).
  const Segmentation bevel = segment_test::run(mesh, options, kTerracedSlack);
  EXPECT_GT(bevel.n_bevel_crease_edges, static_cast<std::size_t>(2 * kCells));
  EXPECT_EQ(bevel.n_crease_edges, plain.n_crease_edges + bevel.n_bevel_crease_edges);
  EXPECT_EQ(bends_inside_patches(mesh, bevel), 0u);
  // Terraces of cell-based inputs and smooth level sets are not bevels (the occupancy torus
  // at 48 cells, a tube of radius ~6 cells, gets some: see the slow test below).
  EXPECT_EQ(segment(scene_mesh("sphere", kCells, SampleMode::Occupancy), options).n_bevel_crease_edges, 0u);
  EXPECT_EQ(segment(scene_mesh("sphere", kCells, SampleMode::LevelSet), options).n_bevel_crease_edges, 0u);
}

TEST(SegmentIsosurfaceSlow, BevelCreasesLeaveTerracesAlone) {
  SegmentOptions options;
  options.bevel_creases = true;
  for (const char* name : {"sphere", "torus"}) {
    EXPECT_EQ(segment(scene_mesh(name, 96, SampleMode::Occupancy), options).n_bevel_crease_edges, 0u) << name;
    EXPECT_EQ(segment(scene_mesh(name, 96, SampleMode::LevelSet), options).n_bevel_crease_edges, 0u) << name;
  }
}

TEST(SegmentIsosurface, OccupancyTrench) {
  (void)segment_test::run(scene_mesh("trench", 32, SampleMode::Occupancy), {}, kTerracedSlack);
}

// The level-set DRAM cell has sliver faces at the cups' bottoms that creases bound on every
// side and one patch surrounds (at 256 cells one left a 23-deg triangle beside its loop of
// 0.93 target edges; at 80 cells there is one). They join the patch around them; none of
// that kind is left.
TEST(SegmentIsosurfaceSlow, TinyCreaseBoundedIslandsJoinThePatchAroundThem) {
  const TriMesh mesh = scene_mesh("dram", 80, SampleMode::LevelSet);
  double mean_edge = 0.0;
  for (const auto e : mesh.edges()) mean_edge += mesh.calc_edge_length(e);
  mean_edge /= static_cast<double>(mesh.n_edges());
  const Segmentation seg = segment_test::run(mesh, {}, kTerracedSlack);
  EXPECT_GE(seg.n_islands_absorbed, 1u);
  ASSERT_GE(seg.island_faces.size(), seg.n_islands_absorbed);
  for (const int f : seg.island_faces) {
    const Eigen::Vector3d& axis = seg.patches[static_cast<std::size_t>(seg.face_patch[f])].axis;
    EXPECT_GE(segment_test::raw_normal(mesh, f).dot(axis), kSegmentMinRawNormalDot) << "face " << f;
  }
  for (std::size_t p = 0; p < seg.patches.size(); ++p) {
    if (seg.patches[p].faces.size() > kSegmentTinyIslandFaces) continue;
    std::set<int> around;
    bool on_boundary = false;
    double perimeter = 0.0;
    for (const int f : seg.patches[p].faces) {
      for (const auto h : mesh.fh_range(mesh.face_handle(f))) {
        const auto g = mesh.opposite_face_handle(h);
        if (!g.is_valid()) on_boundary = true;
        if (g.is_valid() && seg.face_patch[g.idx()] == static_cast<int>(p)) continue;
        if (g.is_valid()) around.insert(seg.face_patch[g.idx()]);
        perimeter += mesh.calc_edge_length(h);
      }
    }
    if (on_boundary || around.size() != 1 || perimeter >= kSegmentTinyIslandPerimeterEdges * mean_edge) continue;
    // A tiny island is left only where its faces do not meet the raw bound of the patch
    // around it (or the union would not project simply; not the case here).
    const Eigen::Vector3d& axis = seg.patches[static_cast<std::size_t>(*around.begin())].axis;
    bool fits = true;
    for (const int f : seg.patches[p].faces) fits = fits && segment_test::raw_normal(mesh, f).dot(axis) >= kSegmentMinRawNormalDot;
    EXPECT_FALSE(fits) << "patch " << p << " is a tiny island that fits the patch around it";
  }
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
