// SPDX-License-Identifier: BSD-3-Clause
// Segmentation of procedural meshes: contracts (contracts.h) and exact small cases.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <string>

#include "fixtures/shapes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/segment/segment.h"
#include "nurbsfront/segment/segment_internal.h"
#include "segment/contracts.h"

namespace nurbsfront {
namespace {

using segment_test::kPi;
using segment_test::radians;
using segment_test::run;

// The grid patch folded along x = 0.5 into a roof: faces tilted +-tilt_deg about y.
TriangleSoup roof(int n, double tilt_deg) {
  TriangleSoup s = test::grid_patch(n, n);
  for (auto& p : s.points) p.z() = -std::abs(p.x() - 0.5) * std::tan(radians(tilt_deg));
  return s;
}

// A helicoidal ramp: r in [1, 2], turning `turns` times, rising `pitch` per radian (small
// by default). Every normal is near +z, yet its projection overlaps itself after one turn.
TriangleSoup ramp(double turns, int n_around, int n_radial, double pitch = 0.05) {
  TriangleSoup s;
  const int n_theta = static_cast<int>(turns * n_around);
  for (int i = 0; i <= n_theta; ++i) {
    const double theta = 2 * kPi * i / n_around;
    for (int j = 0; j <= n_radial; ++j) {
      const double r = 1.0 + static_cast<double>(j) / n_radial;
      s.points.emplace_back(r * std::cos(theta), r * std::sin(theta), pitch * theta);
    }
  }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(i * (n_radial + 1) + j); };
  for (int i = 0; i < n_theta; ++i) {
    for (int j = 0; j < n_radial; ++j) {
      s.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return s;
}

// A terraced ramp z ~ 0.7 x: heights rounded to steps of two cells' height, so the raw
// normals alternate between flat (0 deg) and risers (63 deg).
TriangleSoup terraced_ramp(int n) {
  TriangleSoup s = test::grid_patch(n, n);
  const double step = 2.0 / n;
  for (auto& p : s.points) p.z() = std::round(0.7 * p.x() / step) * step;
  return s;
}

TEST(Segment, CubeHasSixPatchesTwelveCurvesEightCorners) {
  const TriMesh mesh = to_trimesh(test::cube());
  const SegmentOptions options;
  const Segmentation seg = run(mesh, options, 0.0);
  ASSERT_EQ(seg.patches.size(), 6u);
  EXPECT_EQ(seg.n_crease_edges, 12u);
  EXPECT_EQ(seg.curves.size(), 12u);
  EXPECT_EQ(seg.corners, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7}));
  std::set<std::array<int, 3>> axes;
  for (const Patch& p : seg.patches) {
    EXPECT_EQ(p.faces.size(), 2u);
    EXPECT_EQ(p.curves.size(), 4u);
    EXPECT_NEAR(p.axis.cwiseAbs().maxCoeff(), 1.0, 1e-12);
    axes.insert({static_cast<int>(std::lround(p.axis.x())), static_cast<int>(std::lround(p.axis.y())),
                 static_cast<int>(std::lround(p.axis.z()))});
  }
  EXPECT_EQ(axes.size(), 6u);
  for (const BorderCurve& c : seg.curves) {
    EXPECT_FALSE(c.is_closed);
    EXPECT_EQ(c.vertices.size(), 2u);
    EXPECT_GE(c.patch_right, 0);
  }
}

TEST(Segment, FlatGridIsOnePatchWithOneClosedBoundaryCurve) {
  const TriMesh mesh = to_trimesh(test::grid_patch(12, 9));
  const SegmentOptions options;
  const Segmentation seg = run(mesh, options, 0.0);
  ASSERT_EQ(seg.patches.size(), 1u);
  EXPECT_NEAR(seg.patches[0].axis.z(), 1.0, 1e-12);
  ASSERT_EQ(seg.curves.size(), 1u);
  EXPECT_TRUE(seg.curves[0].is_closed);
  EXPECT_EQ(seg.curves[0].patch_left, 0);
  EXPECT_EQ(seg.curves[0].patch_right, -1);
  EXPECT_EQ(seg.curves[0].vertices.size(), 2u * (12 + 9));
  EXPECT_TRUE(seg.corners.empty());
  EXPECT_EQ(seg.n_crease_edges, 0u);
}

TEST(Segment, RoofBelowTheCreaseAngleIsOnePatchAboveItTwo) {
  SegmentOptions options;
  options.sharp_crease_angle_deg = 0.0;  // the ridge between two planes would be a sharp crease
  {
    const TriMesh mesh = to_trimesh(roof(16, 20.0));  // 40 deg dihedral
    const Segmentation seg = run(mesh, options, 0.0);
    EXPECT_EQ(seg.patches.size(), 1u);
    EXPECT_EQ(seg.n_crease_edges, 0u);
  }
  {
    const TriMesh mesh = to_trimesh(roof(16, 50.0));  // 100 deg dihedral: a crease
    const Segmentation seg = run(mesh, options, 0.0);
    ASSERT_EQ(seg.patches.size(), 2u);
    EXPECT_EQ(seg.n_crease_edges, 16u);
    // The ridge is one curve between the two corners where it meets the boundary.
    EXPECT_EQ(seg.corners.size(), 2u);
    int n_ridge = 0;
    for (const BorderCurve& c : seg.curves) {
      if (c.patch_right < 0) continue;
      ++n_ridge;
      EXPECT_EQ(c.vertices.size(), 17u);
      for (int v : c.vertices) EXPECT_NEAR(mesh.point(mesh.vertex_handle(v))[0], 0.5, 1e-12);
    }
    EXPECT_EQ(n_ridge, 1);
    EXPECT_EQ(seg.curves.size(), 3u);  // the ridge and one boundary curve per side
  }
}

// The ridge of a roof between two planes is a sharp crease below the crease angle: exactly
// its edges, when it is a chain of at least 8 edges and the sharp crease angle is below its
// dihedral.
TEST(Segment, RidgeBetweenPlanesIsASharpCrease) {
  SegmentOptions options;  // crease angle 80
  options.sharp_crease_angle_deg = kRemeshSharpCreaseAngleDeg;  // sharp creases from 15 deg
  const TriMesh mesh = to_trimesh(roof(16, 20.0));  // 40 deg dihedral
  const Segmentation seg = run(mesh, options, 0.0);
  ASSERT_EQ(seg.patches.size(), 2u);
  ASSERT_EQ(seg.sharp_crease_edges.size(), 16u);
  EXPECT_EQ(seg.n_crease_edges, 16u);
  EXPECT_TRUE(std::is_sorted(seg.sharp_crease_edges.begin(), seg.sharp_crease_edges.end()));
  for (const int e : seg.sharp_crease_edges) {
    const auto h = mesh.halfedge_handle(mesh.edge_handle(e), 0);
    EXPECT_NEAR(mesh.point(mesh.from_vertex_handle(h))[0], 0.5, 1e-12) << "edge " << e;
    EXPECT_NEAR(mesh.point(mesh.to_vertex_handle(h))[0], 0.5, 1e-12) << "edge " << e;
  }
  // Each patch is one plane.
  for (const Patch& patch : seg.patches) {
    const Eigen::Vector3d first = segment_test::raw_normal(mesh, patch.faces.front());
    for (const int f : patch.faces) EXPECT_NEAR(segment_test::raw_normal(mesh, f).dot(first), 1.0, 1e-12);
  }
  // Off, or a sharp crease angle above the dihedral: one patch.
  for (const double angle : {0.0, 45.0}) {
    SegmentOptions off;
    off.sharp_crease_angle_deg = angle;
    const Segmentation one = run(mesh, off, 0.0);
    EXPECT_EQ(one.patches.size(), 1u) << angle;
    EXPECT_TRUE(one.sharp_crease_edges.empty()) << angle;
  }
  // A ridge of 6 edges is too short a chain; 8 is enough.
  EXPECT_TRUE(run(to_trimesh(roof(6, 20.0)), options, 0.0).sharp_crease_edges.empty());
  EXPECT_EQ(run(to_trimesh(roof(8, 20.0)), options, 0.0).sharp_crease_edges.size(), 8u);
  // Splitting patches keeps them.
  const Segmentation split = split_patches(mesh, seg, {0}, options);
  EXPECT_EQ(split.sharp_crease_edges, seg.sharp_crease_edges);
}

// The facets of a coarsely tessellated cylinder bend by the same angle on parallel lines one
// face apart: no line is a sharp crease (its smooth surface is the fit's to find). The same
// lines 4 faces apart are creases, and a rough side (every edge bending) is none.
TEST(Segment, ParallelFacetLinesAndRoughSidesAreNoSharpCreases) {
  // Half a cylinder along y of radius 1: `facets` planar facets of `rows` strips each
  // (x = cos, z = sin), 16 cells along y.
  auto half_cylinder = [](int facets, int rows) {
    TriangleSoup s;
    const int nu = facets * rows, nv = 16;
    for (int i = 0; i <= nu; ++i) {
      const int k = i / rows;
      const double t = static_cast<double>(i % rows) / rows;
      const double a0 = kPi * k / facets, a1 = kPi * std::min(k + 1, facets) / facets;
      const Eigen::Vector2d p = (1.0 - t) * Eigen::Vector2d(std::cos(a0), std::sin(a0)) +
                                t * Eigen::Vector2d(std::cos(a1), std::sin(a1));
      for (int j = 0; j <= nv; ++j) s.points.emplace_back(p.x(), 2.0 * j / nv, p.y());
    }
    auto id = [&](int i, int j) { return static_cast<std::uint32_t>(i * (nv + 1) + j); };
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        s.triangles.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
        s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
      }
    return s;
  };
  SegmentOptions options;
  options.max_slope_deg = 89.0;  // (the segmentation itself is not what is tested)
  options.min_patch_faces = 0;
  options.sharp_crease_angle_deg = kRemeshSharpCreaseAngleDeg;
  // 8 facets of 22.5 deg, one strip each: no sharp crease.
  EXPECT_TRUE(segment(to_trimesh(half_cylinder(8, 1)), options).sharp_crease_edges.empty());
  // 4 strips per facet: the 7 facet lines of 16 edges are.
  EXPECT_EQ(segment(to_trimesh(half_cylinder(8, 4)), options).sharp_crease_edges.size(), 7u * 16u);
  // The roof's ridge with every side edge bending by 3 deg (a rough, scanned side): none.
  TriangleSoup rough = roof(16, 20.0);
  for (std::size_t v = 0; v < rough.points.size(); ++v)
    if (std::abs(rough.points[v].x() - 0.5) > 1e-9) rough.points[v].z() += 0.004 * static_cast<double>(v % 3);
  SegmentOptions sharp;
  sharp.sharp_crease_angle_deg = kRemeshSharpCreaseAngleDeg;
  EXPECT_TRUE(segment(to_trimesh(rough), sharp).sharp_crease_edges.empty());
  EXPECT_EQ(segment(to_trimesh(roof(16, 20.0)), sharp).sharp_crease_edges.size(), 16u);  // (without the roughness)
}

TEST(SplitPatches, RoofSplitsAtItsRidgeIntoTwoPlanes) {
  SegmentOptions options;
  options.sharp_crease_angle_deg = 0.0;  // (else the ridge is a sharp crease)
  const TriMesh mesh = to_trimesh(roof(16, 20.0));  // one patch (40 deg dihedral)
  const Segmentation seg = run(mesh, options, 0.0);
  ASSERT_EQ(seg.patches.size(), 1u);
  const Segmentation split = split_patches(mesh, seg, {0}, options);
  segment_test::expect_contracts(mesh, split, options, 0.0);
  ASSERT_EQ(split.patches.size(), 2u);
  // Each part is one side of the ridge, with that plane's normal as its axis.
  for (const Patch& patch : split.patches) {
    const Eigen::Vector3d first = segment_test::raw_normal(mesh, patch.faces.front());
    EXPECT_NEAR(patch.axis.dot(first), 1.0, 1e-12);
    for (const int f : patch.faces) {
      EXPECT_NEAR(segment_test::raw_normal(mesh, f).dot(first), 1.0, 1e-12) << "face " << f;
      double x = 0.0;
      for (const auto v : mesh.fv_range(mesh.face_handle(f))) x += mesh.point(v)[0] / 3.0;
      EXPECT_EQ(x < 0.5, first.x() < 0.0) << "face " << f;  // the x < 0.5 side tilts towards -x
    }
  }
  // The ridge is the one curve between the parts, from corner to corner along x = 0.5.
  int n_ridge = 0;
  for (const BorderCurve& c : split.curves) {
    if (c.patch_right < 0) continue;
    ++n_ridge;
    EXPECT_EQ(c.vertices.size(), 17u);
    for (const int v : c.vertices) EXPECT_NEAR(mesh.point(mesh.vertex_handle(v))[0], 0.5, 1e-12);
  }
  EXPECT_EQ(n_ridge, 1);
  EXPECT_EQ(split.corners.size(), 2u);
  // Nothing to split: the same segmentation; a bad id throws.
  const Segmentation same = split_patches(mesh, seg, {}, options);
  EXPECT_EQ(same.face_patch, seg.face_patch);
  EXPECT_THROW((void)split_patches(mesh, seg, {1}, options), InvalidInput);
  EXPECT_THROW((void)split_patches(mesh, split, {-1}, options), InvalidInput);
}

TEST(SplitPatches, FlatPatchDoesNotSplit) {
  const SegmentOptions options;
  const TriMesh mesh = to_trimesh(test::grid_patch(8, 8));
  const Segmentation seg = run(mesh, options, 0.0);
  ASSERT_EQ(seg.patches.size(), 1u);
  // All normals equal: the clusters cannot separate, the patch stays.
  const Segmentation split = split_patches(mesh, seg, {0}, options);
  EXPECT_EQ(split.patches.size(), 1u);
  EXPECT_EQ(split.face_patch, seg.face_patch);
}

// PatchSplitter computes the graph and normals once and, given its last result, checks only
// the new parts: rounds give what split_patches() gives, also for an unrelated segmentation.
TEST(SplitPatches, SplitterRoundsMatchSplitPatches) {
  SegmentOptions options;
  options.min_patch_faces = 20;
  const TriMesh mesh = to_trimesh(test::torus(48, 24));
  const Segmentation seg = run(mesh, options, 10.0);
  ASSERT_GE(seg.patches.size(), 4u);
  auto expect_same = [](const Segmentation& a, const Segmentation& b) {
    EXPECT_EQ(a.face_patch, b.face_patch);
    ASSERT_EQ(a.patches.size(), b.patches.size());
    for (std::size_t p = 0; p < a.patches.size(); ++p) EXPECT_EQ(a.patches[p].axis, b.patches[p].axis) << "patch " << p;
    EXPECT_EQ(a.curves.size(), b.curves.size());
    EXPECT_EQ(a.corners.size(), b.corners.size());
    EXPECT_EQ(a.n_fold_splits, b.n_fold_splits);
    EXPECT_EQ(a.n_bevel_crease_edges, b.n_bevel_crease_edges);
  };
  PatchSplitter splitter(mesh, options);
  const Segmentation first = splitter.split(seg, {0, 1});
  expect_same(first, split_patches(mesh, seg, {0, 1}, options));
  ASSERT_GT(first.patches.size(), seg.patches.size());
  // The next round splits every patch again (the previous result: only parts are checked).
  std::vector<int> all(first.patches.size());
  for (std::size_t p = 0; p < all.size(); ++p) all[p] = static_cast<int>(p);
  const Segmentation second = splitter.split(first, {0, 2});
  expect_same(second, split_patches(mesh, first, {0, 2}, options));
  const Segmentation third = splitter.split(second, all);
  expect_same(third, split_patches(mesh, second, all, options));
  segment_test::expect_contracts(mesh, third, options, 10.0);
  // Not its last result: every patch is checked.
  expect_same(splitter.split(seg, {2}), split_patches(mesh, seg, {2}, options));
  EXPECT_THROW((void)splitter.split(seg, {-1}), InvalidInput);
}

// The pipeline's splitter: segment() hands over its face graph, normals and mean edge; the
// segmentation and every split round equal segment() and a PatchSplitter made afresh.
TEST(SplitPatches, SplitterFromSegmentMatchesPatchSplitter) {
  SegmentOptions options;
  options.min_patch_faces = 20;
  const TriMesh mesh = to_trimesh(test::torus(48, 24));
  segment_detail::SplitterPtr kept;
  const Segmentation seg = segment_detail::segment(mesh, options, mean_edge_length(mesh), &kept);
  ASSERT_TRUE(kept);
  const Segmentation plain = segment(mesh, options);
  EXPECT_EQ(seg.face_patch, plain.face_patch);
  ASSERT_EQ(seg.patches.size(), plain.patches.size());
  ASSERT_GE(seg.patches.size(), 4u);
  PatchSplitter fresh(mesh, options);
  const Segmentation first = segment_detail::split(*kept, seg, {0, 1});
  const Segmentation first_fresh = fresh.split(seg, {0, 1});
  ASSERT_GT(first.patches.size(), seg.patches.size());
  EXPECT_EQ(first.face_patch, first_fresh.face_patch);
  EXPECT_EQ(first.n_bevel_crease_edges, first_fresh.n_bevel_crease_edges);
  const Segmentation second = segment_detail::split(*kept, first, {0, 2});
  const Segmentation second_fresh = fresh.split(first_fresh, {0, 2});
  EXPECT_EQ(second.face_patch, second_fresh.face_patch);
  ASSERT_EQ(second.patches.size(), second_fresh.patches.size());
  for (std::size_t p = 0; p < second.patches.size(); ++p)
    EXPECT_EQ(second.patches[p].axis, second_fresh.patches[p].axis) << "patch " << p;
  segment_test::expect_contracts(mesh, second, options, 10.0);
}

// The splitter's results take segment()'s face counts (creases, degenerate faces, slope
// exceptions: computed once per splitter), and a split whose caller vouches for its input
// (checked_input, surfmesh's split rounds) is the checked split: on a ridge whose crest is
// a crease, through two rounds, against a PatchSplitter made afresh.
TEST(SplitPatches, SplitterCountsAndCheckedInputAreTheFreshSplitters) {
  SegmentOptions options;
  options.min_patch_faces = 20;
  TriangleSoup soup = test::grid_patch(24, 24);
  const double rise = std::tan(50.0 * std::numbers::pi / 180.0);  // 100 deg between the sides' normals
  for (auto& p : soup.points) p.z() = rise * (0.5 - std::abs(p.x() - 0.5)) + 0.05 * std::sin(9.0 * p.y());
  const TriMesh mesh = to_trimesh(soup);
  segment_detail::SplitterPtr kept;
  const Segmentation seg = segment_detail::segment(mesh, options, mean_edge_length(mesh), &kept, false);
  ASSERT_TRUE(kept);
  EXPECT_EQ(seg.n_crease_edges, 24u);  // the crest: one edge per row of cells
  ASSERT_GE(seg.patches.size(), 2u);
  PatchSplitter fresh(mesh, options);
  const Segmentation first = segment_detail::split(*kept, seg, {0, 1}, false, true);
  const Segmentation first_fresh = fresh.split(seg, {0, 1});
  ASSERT_GT(first.patches.size(), seg.patches.size());
  const Segmentation second = segment_detail::split(*kept, first, {0, 2}, false, true);
  const Segmentation second_fresh = fresh.split(first_fresh, {0, 2});
  for (const auto& [a, b] : {std::pair{&first, &first_fresh}, std::pair{&second, &second_fresh}}) {
    EXPECT_EQ(a->face_patch, b->face_patch);
    ASSERT_EQ(a->patches.size(), b->patches.size());
    for (std::size_t p = 0; p < a->patches.size(); ++p) EXPECT_EQ(a->patches[p].axis, b->patches[p].axis) << p;
    EXPECT_EQ(a->n_fold_splits, b->n_fold_splits);
    EXPECT_EQ(a->n_crease_edges, seg.n_crease_edges);
    EXPECT_EQ(b->n_crease_edges, seg.n_crease_edges);
    EXPECT_EQ(a->n_degenerate_faces, seg.n_degenerate_faces);
    EXPECT_EQ(b->n_degenerate_faces, seg.n_degenerate_faces);
    EXPECT_EQ(a->n_slope_exceptions, seg.n_slope_exceptions);
    EXPECT_EQ(b->n_slope_exceptions, seg.n_slope_exceptions);
  }
  // Unchecked, the same split still rejects a patch id out of range.
  EXPECT_THROW((void)segment_detail::split(*kept, second, {static_cast<int>(second.patches.size())}), InvalidInput);
}

// The pipeline's order: segment(), merges and split rounds without border curves, the
// borders extracted once at the end (with_borders) are those each step would have
// extracted: the same curves (vertices, edges, sides, smoothed points), corners and
// per-patch curve lists; the rest of every step's result is the same either way.
TEST(SplitPatches, BordersExtractedOnceAtTheEndEqualEachStepsBorders) {
  SegmentOptions options;
  options.min_patch_faces = 20;
  const TriMesh mesh = to_trimesh(test::torus(48, 24));
  const double mean_edge = mean_edge_length(mesh);
  auto expect_same = [](const Segmentation& a, const Segmentation& b) {
    EXPECT_EQ(a.face_patch, b.face_patch);
    ASSERT_EQ(a.patches.size(), b.patches.size());
    for (std::size_t p = 0; p < a.patches.size(); ++p) {
      EXPECT_EQ(a.patches[p].faces, b.patches[p].faces) << "patch " << p;
      EXPECT_EQ(a.patches[p].axis, b.patches[p].axis) << "patch " << p;
      EXPECT_EQ(a.patches[p].curves, b.patches[p].curves) << "patch " << p;
    }
    ASSERT_EQ(a.curves.size(), b.curves.size());
    for (std::size_t c = 0; c < a.curves.size(); ++c) {
      EXPECT_EQ(a.curves[c].vertices, b.curves[c].vertices) << "curve " << c;
      EXPECT_EQ(a.curves[c].edges, b.curves[c].edges) << "curve " << c;
      EXPECT_EQ(a.curves[c].patch_left, b.curves[c].patch_left) << "curve " << c;
      EXPECT_EQ(a.curves[c].patch_right, b.curves[c].patch_right) << "curve " << c;
      EXPECT_EQ(a.curves[c].is_closed, b.curves[c].is_closed) << "curve " << c;
      EXPECT_EQ(a.curves[c].smoothed, b.curves[c].smoothed) << "curve " << c;
    }
    EXPECT_EQ(a.corners, b.corners);
    EXPECT_EQ(a.n_crease_edges, b.n_crease_edges);
    EXPECT_EQ(a.n_fold_splits, b.n_fold_splits);
    EXPECT_EQ(a.n_islands_absorbed, b.n_islands_absorbed);
    EXPECT_EQ(a.island_faces, b.island_faces);
  };
  segment_detail::SplitterPtr with, without;
  const Segmentation seg = segment_detail::segment(mesh, options, mean_edge, &with);
  const Segmentation bare = segment_detail::segment(mesh, options, mean_edge, &without, false);
  ASSERT_GE(seg.patches.size(), 4u);
  ASSERT_FALSE(seg.curves.empty());
  EXPECT_TRUE(bare.curves.empty());
  EXPECT_TRUE(bare.corners.empty());
  for (const Patch& patch : bare.patches) EXPECT_TRUE(patch.curves.empty());
  expect_same(segment_detail::with_borders(mesh, options, bare), seg);
  // Two split rounds and a merge, each step on the previous result.
  const Segmentation first = segment_detail::split(*with, seg, {0, 1});
  const Segmentation first_bare = segment_detail::split(*without, bare, {0, 1}, false);
  ASSERT_GT(first.patches.size(), seg.patches.size());
  EXPECT_TRUE(first_bare.curves.empty());
  expect_same(segment_detail::with_borders(mesh, options, first_bare), first);
  const Segmentation second = segment_detail::split(*with, first, {0, 2});
  const Segmentation second_bare = segment_detail::split(*without, first_bare, {0, 2}, false);
  const Segmentation second_late = segment_detail::with_borders(mesh, options, second_bare);
  expect_same(second_late, second);
  segment_test::expect_contracts(mesh, second_late, options, 10.0);
  const int smallest = static_cast<int>(std::min_element(second.patches.begin(), second.patches.end(),
                                                         [](const Patch& a, const Patch& b) {
                                                           return a.faces.size() < b.faces.size();
                                                         }) -
                                        second.patches.begin());
  const Segmentation merged = segment_detail::merge_into_neighbours(*with, second, {smallest});
  const Segmentation merged_bare = segment_detail::merge_into_neighbours(*without, second_bare, {smallest}, false);
  ASSERT_LT(merged.patches.size(), second.patches.size());
  EXPECT_TRUE(merged_bare.curves.empty());
  expect_same(segment_detail::with_borders(mesh, options, merged_bare), merged);
  // A segmentation of another mesh is refused.
  const TriMesh other = to_trimesh(test::torus(24, 12));
  EXPECT_THROW((void)segment_detail::with_borders(other, options, bare), InvalidInput);
}

TEST(Segment, SphereGivesFewLargePatches) {
  const TriMesh mesh = to_trimesh(test::icosphere(3));
  SegmentOptions options;
  options.min_patch_faces = 20;
  const Segmentation seg = run(mesh, options, 5.0);
  // A cap of normals within 60 deg covers a quarter of the sphere: at least 4 patches.
  EXPECT_GE(seg.patches.size(), 4u);
  EXPECT_LE(seg.patches.size(), 30u);
  for (const Patch& p : seg.patches) EXPECT_GE(p.faces.size(), options.min_patch_faces);
  EXPECT_EQ(seg.n_fold_splits, 0u);
  // Closed surface: every curve is between two patches.
  for (const BorderCurve& c : seg.curves) EXPECT_GE(c.patch_right, 0);
}

TEST(Segment, SlopeBoundIsRespectedForSmallerAngles) {
  const TriMesh mesh = to_trimesh(test::icosphere(3));
  SegmentOptions options;
  options.max_slope_deg = 30.0;
  const Segmentation narrow = run(mesh, options, 5.0);
  options.max_slope_deg = 60.0;
  const Segmentation wide = segment(mesh, options);
  EXPECT_GT(narrow.patches.size(), wide.patches.size());
}

TEST(Segment, TorusSegmentsIntoHeightFields) {
  const TriMesh mesh = to_trimesh(test::torus(48, 24));
  const SegmentOptions options;
  const Segmentation seg = run(mesh, options, 10.0);
  EXPECT_LE(seg.patches.size(), 60u);
  for (const BorderCurve& c : seg.curves) EXPECT_GE(c.patch_right, 0);
}

TEST(Segment, SelfOverlappingRampIsSplit) {
  const TriMesh mesh = to_trimesh(ramp(2.5, 48, 4));
  const SegmentOptions options;
  const Segmentation seg = run(mesh, options, 0.0);
  EXPECT_GE(seg.n_fold_splits, 1u);
  // Two and a half turns cannot be a height field in fewer than three patches.
  EXPECT_GE(seg.patches.size(), 3u);
}

// The checks of split_folds run in parallel first (SegmentOptions::threads); the patches
// that fail them are split the same way as with one thread.
TEST(Segment, FoldSplitsDoNotDependOnTheThreadCount) {
  // Two ramps side by side: two patches checked in parallel, both folded.
  TriangleSoup soup = ramp(2.5, 48, 4);
  const TriangleSoup other = ramp(1.5, 40, 3);
  const auto offset = static_cast<std::uint32_t>(soup.points.size());
  for (const auto& p : other.points) soup.points.push_back(p + Eigen::Vector3d(10.0, 0.0, 0.0));
  for (const auto& t : other.triangles) soup.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const TriMesh mesh = to_trimesh(soup);
  SegmentOptions options;
  options.threads = 1;
  const Segmentation one = segment(mesh, options);
  options.threads = 3;
  const Segmentation three = run(mesh, options, 0.0);
  EXPECT_GE(one.n_fold_splits, 2u);
  EXPECT_EQ(one.n_fold_splits, three.n_fold_splits);
  EXPECT_EQ(one.face_patch, three.face_patch);
  ASSERT_EQ(one.patches.size(), three.patches.size());
  for (std::size_t p = 0; p < one.patches.size(); ++p) EXPECT_EQ(one.patches[p].axis, three.patches[p].axis);
}

// A patch that fails its check without local trouble (a cliff) is bisected by the
// parallel check that found it (split_folds' prebisection); the splits are those of one
// thread. Three 345-degree ramps side by side (each one patch, each holding a cliff: no
// crossing, so no trouble to carve) and a folded 2.5-turn ramp (crossings: carved).
// At resolution 1 only the first precheck (every patch) goes to the Team's workers: each
// split's parts hold under 1 000 faces besides the largest (split_folds'
// kMinPrecheckHandOffFaces) and are checked on the calling thread; at resolution 2 (4x the
// faces) the 23 parts of the folded ramp's first split go to the workers too.
TEST(Segment, PrebisectedFoldSplitsAreTheSameOnAnyThreadCount) {
  for (const int res : {1, 2}) {
    TriangleSoup soup = ramp(2.5, 48 * res, 4 * res);
    for (int k = 1; k <= 3; ++k) {
      const TriangleSoup other = ramp(345.0 / 360.0, (40 + 4 * k) * res, 4 * res, 0.3);
      const auto offset = static_cast<std::uint32_t>(soup.points.size());
      for (const auto& p : other.points) soup.points.push_back(p + Eigen::Vector3d(6.0 * k, 0.0, 0.0));
      for (const auto& t : other.triangles) soup.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    }
    const TriMesh mesh = to_trimesh(soup);
    SegmentOptions options;
    options.threads = 1;
    const Segmentation one = segment(mesh, options);
    // Each ramp is split: the folded one at least twice, each cliff ramp at least once.
    EXPECT_GE(one.n_fold_splits, 5u) << res;
    for (const int threads : {2, 4}) {
      options.threads = threads;
      const Segmentation many = run(mesh, options, 0.0);
      EXPECT_EQ(one.n_fold_splits, many.n_fold_splits) << res << " " << threads;
      EXPECT_EQ(one.face_patch, many.face_patch) << res << " " << threads;
      ASSERT_EQ(one.patches.size(), many.patches.size()) << res << " " << threads;
      for (std::size_t p = 0; p < one.patches.size(); ++p)
        EXPECT_EQ(one.patches[p].axis, many.patches[p].axis) << res << " " << threads;
    }
  }
}

// 345 of 360 deg of a steeper ramp (normals within 17 deg of +z): no overlap, but its two
// ends are 0.26 apart in the plane (about one mean edge) and 1.8 (8 mean edges) apart in
// height, a cliff no fit lattice of 2.5 mean edges holds. Half a turn has no cliff.
TEST(Segment, RampShortOfOneTurnIsSplitAtItsCliff) {
  const SegmentOptions options;
  const TriMesh half = to_trimesh(ramp(0.5, 48, 4, 0.3));
  const Segmentation whole = run(half, options, 0.0);
  EXPECT_EQ(whole.patches.size(), 1u);
  EXPECT_EQ(whole.n_fold_splits, 0u);
  const TriMesh mesh = to_trimesh(ramp(345.0 / 360.0, 48, 4, 0.3));
  const Segmentation seg = run(mesh, options, 0.0);
  EXPECT_GE(seg.n_fold_splits, 1u);
  ASSERT_GE(seg.patches.size(), 2u);
  // The two ends (first and last ring of faces) are in different patches.
  EXPECT_NE(seg.face_patch.front(), seg.face_patch.back());
}

// has_cliff's list of every cliff equals the exhaustive test over all vertex pairs (the
// definition: closer than 2.5 mean edges in the plane, more than 3 apart along the axis,
// rise over run above 4), and a part of the patch has a cliff exactly when it has 40 faces
// or more and both vertices of a listed pair (what split_folds uses for bisected parts).
TEST(Segment, CliffPairsAreEveryCliffAndDecideTheParts) {
  const TriMesh mesh = to_trimesh(ramp(345.0 / 360.0, 48, 4, 0.3));
  const segment_detail::FaceGraph graph = segment_detail::build_graph(mesh);
  segment_detail::Scratch scratch(mesh);
  const Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  const double mean_edge = mean_edge_length(mesh);
  const int n_faces = static_cast<int>(mesh.n_faces());
  std::vector<int> all(n_faces);
  for (int f = 0; f < n_faces; ++f) all[f] = f;
  segment_detail::CliffPairs listed;
  ASSERT_TRUE(segment_detail::has_cliff(graph, all, axis, mean_edge, scratch, &listed));
  EXPECT_TRUE(segment_detail::has_cliff(graph, all, axis, mean_edge, scratch));
  ASSERT_TRUE(listed.is_complete);
  // Exhaustive: every pair of vertices, lower first.
  const auto [e1, e2] = segment_detail::plane_frame(axis);
  std::set<std::array<int, 2>> expected;
  const auto& points = graph.points;
  for (int a = 0; a < static_cast<int>(points.size()); ++a) {
    for (int b = 0; b < static_cast<int>(points.size()); ++b) {
      const double dz = points[b].dot(axis) - points[a].dot(axis);
      const Eigen::Vector2d d(points[b].dot(e1) - points[a].dot(e1), points[b].dot(e2) - points[a].dot(e2));
      if (dz > 3.0 * mean_edge && d.norm() < 2.5 * mean_edge && dz > 4.0 * d.norm()) expected.insert({a, b});
    }
  }
  ASSERT_FALSE(expected.empty());
  const std::set<std::array<int, 2>> found(listed.pairs.begin(), listed.pairs.end());
  EXPECT_EQ(found.size(), listed.pairs.size());  // each pair once
  EXPECT_EQ(found, expected);
  // Parts: runs of faces along the ramp (the ends hold the cliff's two sides).
  int n_with = 0, n_without = 0;
  for (const int begin : {0, n_faces / 8, n_faces / 2}) {
    for (const int end : {begin + 30, begin + 60, n_faces * 3 / 4, n_faces}) {
      if (end <= begin || end > n_faces) continue;
      const std::vector<int> part(all.begin() + begin, all.begin() + end);
      std::set<int> vertices;
      for (const int f : part) vertices.insert(graph.vertices[f].begin(), graph.vertices[f].end());
      const bool holds_pair = std::any_of(listed.pairs.begin(), listed.pairs.end(), [&](const auto& pair) {
        return vertices.count(pair[0]) > 0 && vertices.count(pair[1]) > 0;
      });
      const bool has = segment_detail::has_cliff(graph, part, axis, mean_edge, scratch);
      EXPECT_EQ(has, part.size() >= 40 && holds_pair) << begin << " " << end;
      (has ? n_with : n_without) += 1;
    }
  }
  EXPECT_GT(n_with, 0);
  EXPECT_GT(n_without, 0);
}

TEST(Segment, SmoothedNormalsKeepATerracedRampInOnePiece) {
  const TriMesh mesh = to_trimesh(terraced_ramp(40));
  SegmentOptions options;
  options.max_slope_deg = 30.0;  // below half the 63 deg between treads and risers
  const Segmentation smoothed = run(mesh, options, 35.0);
  options.normal_smoothing_rings = 0;
  options.min_patch_faces = 0;
  const Segmentation raw = run(mesh, options, 0.0);
  EXPECT_LE(smoothed.patches.size(), 2u);
  EXPECT_GT(raw.patches.size(), 4 * smoothed.patches.size());
}

// The merge check's shortcut: with the border of a patch that passed the check first
// (n_known), only pairs with a later segment are tested for crossings; the verdict must
// be that of the full check. The ramp's first and last turns cross in projection.
TEST(Segment, ProjectionCheckWithAKnownSimplePrefixAgrees) {
  const TriMesh mesh = to_trimesh(ramp(1.5, 24, 3));
  const segment_detail::FaceGraph graph = segment_detail::build_graph(mesh);
  segment_detail::Scratch scratch(mesh);
  const Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  const int n_faces = static_cast<int>(mesh.n_faces());
  int n_simple = 0, n_not_simple = 0;
  for (const int split : {n_faces / 4, n_faces / 2, 2 * n_faces / 3}) {
    for (const int end : {split + 6, n_faces * 5 / 6, n_faces}) {
      // Patch 0: faces [0, split), known simple; patch 1: faces [split, end); the rest 2.
      std::vector<int> face_patch(n_faces, 2);
      std::vector<int> first, second;
      for (int f = 0; f < n_faces; ++f) {
        if (f < split) {
          face_patch[f] = 0;
          first.push_back(f);
        } else if (f < end) {
          face_patch[f] = 1;
          second.push_back(f);
        }
      }
      ASSERT_TRUE(segment_detail::check_projection(graph, first, face_patch, axis, scratch).is_simple);
      const auto border_first = segment_detail::patch_border(graph, first, face_patch);
      const auto border_second = segment_detail::patch_border(graph, second, face_patch);
      // Merge as merge_patches does: the first part's remaining border, then the second's.
      for (int f : second) face_patch[f] = 0;
      std::vector<OpenMesh::HalfedgeHandle> merged;
      std::size_t n_known = 0;
      for (const auto* part : {&border_first, &border_second}) {
        for (const auto h : *part) {
          const auto g = mesh.opposite_face_handle(h);
          if (!g.is_valid() || face_patch[g.idx()] != 0) merged.push_back(h);
        }
        if (part == &border_first) n_known = merged.size();
      }
      const bool full = segment_detail::check_projection(graph, merged, face_patch, axis, scratch).is_simple;
      const bool shortcut =
          segment_detail::check_projection(graph, merged, face_patch, axis, scratch, n_known).is_simple;
      EXPECT_EQ(full, shortcut) << split << " " << end;
      std::vector<int> all = first;
      all.insert(all.end(), second.begin(), second.end());
      EXPECT_EQ(full, segment_detail::check_projection(graph, all, face_patch, axis, scratch).is_simple);
      (full ? n_simple : n_not_simple) += 1;
    }
  }
  EXPECT_GT(n_simple, 0);
  EXPECT_GT(n_not_simple, 0);
}

// Patches of one to six faces grown breadth-first from seeds taken in a shuffled face order
// (a fixed seed): the patches the narrow-patch test below starts from.
std::vector<int> random_blobs(const segment_detail::FaceGraph& graph, unsigned seed, int* n_blobs) {
  const int n_faces = graph.n_faces();
  std::vector<int> order(static_cast<std::size_t>(n_faces));
  for (int f = 0; f < n_faces; ++f) order[static_cast<std::size_t>(f)] = f;
  std::mt19937 random(seed);
  std::shuffle(order.begin() + 1, order.end(), random);  // face 0 seeds blob 0
  std::vector<int> face_patch(static_cast<std::size_t>(n_faces), -1);
  int n = 0;
  for (const int seed_face : order) {
    if (face_patch[static_cast<std::size_t>(seed_face)] >= 0) continue;
    const std::size_t size = 1 + random() % 6;
    std::vector<int> blob{seed_face};
    face_patch[static_cast<std::size_t>(seed_face)] = n;
    for (std::size_t head = 0; head < blob.size() && blob.size() < size; ++head)
      for (const int g : graph.neighbours[static_cast<std::size_t>(blob[head])])
        if (g >= 0 && face_patch[static_cast<std::size_t>(g)] < 0 && blob.size() < size) {
          face_patch[static_cast<std::size_t>(g)] = n;
          blob.push_back(g);
        }
    ++n;
  }
  *n_blobs = n;
  return face_patch;
}

// narrow_patches on 1, 2 and 4 threads: the serial list (the faces and edges span several
// chunks of the parallel pass).
TEST(Segment, NarrowPatchesAreTheSameOnAnyThreadCount) {
  const TriMesh mesh = to_trimesh(test::torus(160, 64));  // 20 480 faces
  const segment_detail::FaceGraph graph = segment_detail::build_graph(mesh);
  Segmentation seg;
  int n_blobs = 0;
  seg.face_patch = random_blobs(graph, 3, &n_blobs);
  seg.patches.resize(static_cast<std::size_t>(n_blobs));
  for (int f = 0; f < graph.n_faces(); ++f)
    seg.patches[static_cast<std::size_t>(seg.face_patch[static_cast<std::size_t>(f)])].faces.push_back(f);
  const double mean_edge = mean_edge_length(mesh);
  bool some = false;
  for (const double width : {0.2, 0.35, 0.5}) {
    const std::vector<int> serial = narrow_patches(mesh, seg, width * mean_edge);
    some = some || !serial.empty();
    for (const unsigned threads : {1U, 2U, 4U})
      EXPECT_EQ(segment_detail::narrow_patches(mesh, seg, width * mean_edge, threads), serial) << width << " " << threads;
  }
  EXPECT_TRUE(some);
}

TEST(Segment, IsDeterministic) {
  const TriMesh mesh = to_trimesh(test::torus(32, 16));
  const Segmentation a = segment(mesh);
  const Segmentation b = segment(mesh);
  EXPECT_EQ(a.face_patch, b.face_patch);
  EXPECT_EQ(a.corners, b.corners);
  ASSERT_EQ(a.curves.size(), b.curves.size());
  for (std::size_t c = 0; c < a.curves.size(); ++c) EXPECT_EQ(a.curves[c].vertices, b.curves[c].vertices);
}

TEST(Segment, EmptyMeshGivesEmptySegmentation) {
  const Segmentation seg = segment(TriMesh{});
  EXPECT_TRUE(seg.patches.empty());
  EXPECT_TRUE(seg.face_patch.empty());
  EXPECT_TRUE(seg.curves.empty());
}

TEST(Segment, InvalidOptionsAndMeshesThrow) {
  const TriMesh mesh = to_trimesh(test::cube());
  auto with = [](auto change) {
    SegmentOptions o;
    change(o);
    return o;
  };
  EXPECT_THROW((void)segment(mesh, with([](SegmentOptions& o) { o.max_slope_deg = 90.0; })), InvalidInput);
  EXPECT_THROW((void)segment(mesh, with([](SegmentOptions& o) { o.max_slope_deg = 0.0; })), InvalidInput);
  EXPECT_THROW((void)segment(mesh, with([](SegmentOptions& o) { o.crease_angle_deg = 181.0; })), InvalidInput);
  EXPECT_THROW((void)segment(mesh, with([](SegmentOptions& o) { o.sharp_crease_angle_deg = -1.0; })), InvalidInput);
  EXPECT_THROW((void)segment(mesh, with([](SegmentOptions& o) { o.sharp_crease_angle_deg = 181.0; })), InvalidInput);
  EXPECT_THROW((void)segment(mesh, with([](SegmentOptions& o) { o.normal_smoothing_rings = -1; })), InvalidInput);
  EXPECT_THROW((void)segment(mesh, with([](SegmentOptions& o) { o.threads = -1; })), InvalidInput);
  EXPECT_THROW((void)segment(mesh, with([](SegmentOptions& o) { o.border_smoothing.lambda = 0.0; })), InvalidInput);
  EXPECT_THROW((void)segment(mesh, with([](SegmentOptions& o) { o.border_smoothing.mu = 0.5; })), InvalidInput);
  EXPECT_THROW((void)segment(mesh, with([](SegmentOptions& o) { o.border_smoothing.iterations = -2; })), InvalidInput);
  TriMesh broken = mesh;
  broken.delete_face(broken.face_handle(0), false);
  EXPECT_THROW((void)segment(broken), InvalidInput);
  TriMesh nan = mesh;
  nan.set_point(nan.vertex_handle(0), Point3(std::nan(""), 0, 0));
  EXPECT_THROW((void)segment(nan), InvalidInput);
}

TEST(Segment, ProgressIsReportedAndCancels) {
  const TriMesh mesh = to_trimesh(test::icosphere(2));
  SegmentOptions options;
  double last = -1.0;
  options.progress = [&](std::string_view stage, double fraction) {
    EXPECT_EQ(stage, "segment");
    EXPECT_GE(fraction, last);
    last = fraction;
    return true;
  };
  (void)segment(mesh, options);
  EXPECT_EQ(last, 1.0);
  options.progress = [](std::string_view, double fraction) { return fraction < 0.5; };
  EXPECT_THROW((void)segment(mesh, options), Cancelled);
}

TEST(SplitAtRepeatedVertices, SimpleLoopsStayWholeTouchingLoopsSplit) {
  using Cycles = std::vector<std::vector<int>>;
  EXPECT_EQ(split_at_repeated_vertices({4, 5, 6, 7}), (Cycles{{4, 5, 6, 7}}));
  // An outer loop 0..3 through vertex 2 twice, with a loop 2, 8, 9 hanging there.
  EXPECT_EQ(split_at_repeated_vertices({0, 1, 2, 8, 9, 2, 3}), (Cycles{{2, 8, 9}, {0, 1, 2, 3}}));
  // Starting at the touching vertex, and two loops hanging at different vertices.
  EXPECT_EQ(split_at_repeated_vertices({2, 8, 9, 2, 3, 0, 5, 6, 0, 1}), (Cycles{{2, 8, 9}, {0, 5, 6}, {2, 3, 0, 1}}));
  // Nested: a loop hanging inside a loop that hangs at the same vertex.
  EXPECT_EQ(split_at_repeated_vertices({0, 1, 7, 1, 2, 0, 3, 4}), (Cycles{{1, 7}, {0, 1, 2}, {0, 3, 4}}));
}

TEST(SmoothPolyline, ZigZagFlattensWithFixedEndsAndBoundedMoves) {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i <= 20; ++i) points.emplace_back(i, (i % 2) * 0.5, 0.0);
  BorderSmoothingOptions options;
  const auto smoothed = smooth_polyline(points, false, options);
  ASSERT_EQ(smoothed.size(), points.size());
  EXPECT_EQ(smoothed.front(), points.front());
  EXPECT_EQ(smoothed.back(), points.back());
  const double mean_length = std::sqrt(1.0 + 0.25);
  double input_spread = 0.0, output_spread = 0.0, middle_spread = 0.0;
  for (std::size_t i = 1; i + 1 < points.size(); ++i) {
    EXPECT_LE((smoothed[i] - points[i]).norm(), options.max_displacement * mean_length * (1 + 1e-12));
    EXPECT_NEAR(smoothed[i].z(), 0.0, 1e-15);
    input_spread = std::max(input_spread, std::abs(points[i].y() - 0.25));
    output_spread = std::max(output_spread, std::abs(smoothed[i].y() - 0.25));
    if (i >= 5 && i <= 15) middle_spread = std::max(middle_spread, std::abs(smoothed[i].y() - 0.25));
  }
  EXPECT_LT(output_spread, 0.5 * input_spread);   // near the fixed ends
  EXPECT_LT(middle_spread, 0.05 * input_spread);  // away from them the zig-zag is gone
  // A zero bound keeps every point.
  options.max_displacement = 0.0;
  EXPECT_EQ(smooth_polyline(points, false, options), points);
}

TEST(SmoothPolyline, ClosedNoisyCircleKeepsItsRadius) {
  std::vector<Eigen::Vector3d> points;
  const int n = 64;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * kPi * i / n;
    const double r = 1.0 + ((i % 2) != 0 ? 0.03 : -0.03);
    points.emplace_back(r * std::cos(t), r * std::sin(t), 0.0);
  }
  const auto smoothed = smooth_polyline(points, true, {});
  double min_r = 1e9, max_r = 0.0;
  for (const auto& p : smoothed) {
    min_r = std::min(min_r, p.norm());
    max_r = std::max(max_r, p.norm());
  }
  EXPECT_GT(min_r, 0.98);  // Taubin steps do not shrink the loop
  EXPECT_LT(max_r, 1.02);  // and the zig-zag (+-0.03) is damped
}

// The pipeline's last resort against crossings: a patch joins the neighbour it shares the
// longest border with (ties: the lower id) across creases, with the union's mean normal as
// the axis when the neighbour's own does not fit; the joined faces become island faces, so
// segment()'s guarantees still hold.
TEST(MergePatchesIntoNeighbours, CubeSideJoinsANeighbourAcrossItsCrease) {
  const TriMesh mesh = to_trimesh(test::cube());
  const SegmentOptions options;
  const Segmentation seg = run(mesh, options, 0.0);
  ASSERT_EQ(seg.patches.size(), 6u);
  const Segmentation merged = merge_patches_into_neighbours(mesh, seg, {0}, options);
  segment_test::expect_contracts(mesh, merged, options, 0.0);
  ASSERT_EQ(merged.patches.size(), 5u);
  EXPECT_EQ(merged.island_faces, seg.patches[0].faces);
  // Every side shares one unit edge with patch 0: the lowest neighbour id takes it.
  int lowest = -1;
  for (const int f : seg.patches[0].faces) {
    for (const auto g : mesh.ff_range(mesh.face_handle(f))) {
      const int q = seg.face_patch[g.idx()];
      if (q != 0 && (lowest < 0 || q < lowest)) lowest = q;
    }
  }
  ASSERT_GE(lowest, 1);
  const int joined = merged.face_patch[seg.patches[0].faces.front()];
  for (const int f : seg.patches[0].faces) EXPECT_EQ(merged.face_patch[f], joined);
  for (const int f : seg.patches[lowest].faces) EXPECT_EQ(merged.face_patch[f], joined);
  EXPECT_EQ(merged.patches[joined].faces.size(), 4u);
  // Two perpendicular sides: the axis is their mean normal, 45 deg from each.
  const Eigen::Vector3d expected = (seg.patches[0].axis + seg.patches[lowest].axis).normalized();
  EXPECT_NEAR(merged.patches[joined].axis.dot(expected), 1.0, 1e-12);
  // Nothing listed: the same segmentation; a bad id throws.
  EXPECT_EQ(merge_patches_into_neighbours(mesh, seg, {}, options).face_patch, seg.face_patch);
  EXPECT_THROW((void)merge_patches_into_neighbours(mesh, seg, {6}, options), InvalidInput);
  // A malformed segmentation is refused, not read out of bounds: a face labelled with no
  // patch, and a patch listing a face labelled with another one.
  Segmentation bad_label = seg;
  bad_label.face_patch[0] = 6;
  EXPECT_THROW((void)merge_patches_into_neighbours(mesh, bad_label, {1}, options), InvalidInput);
  Segmentation bad_list = seg;
  bad_list.patches[1].faces.push_back(seg.patches[0].faces.front());
  EXPECT_THROW((void)merge_patches_into_neighbours(mesh, bad_list, {1}, options), InvalidInput);
}

// narrow_patches: width 2 x area / border length, exact on a hand-made strip. An open 4 x 3
// grid whose rows are 2, 0.5 and 2 high (x from 0 to 4), one patch per row: the middle row
// has area 2 and border 4 + 4 (its neighbours) + 2 x 0.5 (the input's boundary), width 4/9;
// the outer rows area 8, border 4 + 4 + 2 x 2, width 4/3. A whole closed surface as one
// patch has no border and is never narrow.
TEST(NarrowPatches, StripWidthIsTwiceAreaOverBorder) {
  TriangleSoup soup = test::grid_patch(4, 3);
  for (auto& p : soup.points) {
    const int row = static_cast<int>(std::lround(p.y() * 3.0));
    p.x() *= 4.0;
    p.y() = std::array<double, 4>{0.0, 2.0, 2.5, 4.5}[static_cast<std::size_t>(row)];
  }
  const TriMesh mesh = to_trimesh(soup);
  Segmentation seg;
  seg.patches.resize(3);
  for (const auto f : mesh.faces()) {
    const double y = mesh.calc_face_centroid(f)[1];
    const int p = y < 2.0 ? 0 : (y < 2.5 ? 1 : 2);
    seg.face_patch.push_back(p);
    seg.patches[static_cast<std::size_t>(p)].faces.push_back(f.idx());
  }
  EXPECT_EQ(narrow_patches(mesh, seg, 4.0 / 9.0 + 1e-9), std::vector<int>{1});
  EXPECT_TRUE(narrow_patches(mesh, seg, 4.0 / 9.0 - 1e-9).empty());
  EXPECT_EQ(narrow_patches(mesh, seg, 4.0 / 3.0 - 1e-9), std::vector<int>{1});
  // Every row narrow: none has a wide neighbour, none is listed.
  EXPECT_TRUE(narrow_patches(mesh, seg, 4.0 / 3.0 + 1e-9).empty());
  // Two strips of width 4/9 between the outer rows: both listed, narrowest first.
  Segmentation two = seg;
  two.patches.resize(4);
  for (auto& patch : two.patches) patch.faces.clear();
  for (const auto f : mesh.faces()) {
    const auto c = mesh.calc_face_centroid(f);
    int& p = two.face_patch[static_cast<std::size_t>(f.idx())];
    if (p == 1 && c[0] > 3.0) p = 3;  // the strip's last unit: width 2 x 0.5 / (1 + 1 + 0.5 + 0.5)
    two.patches[static_cast<std::size_t>(p)].faces.push_back(f.idx());
  }
  EXPECT_EQ(narrow_patches(mesh, two, 0.5), (std::vector<int>{3, 1}));

  const TriMesh cube = to_trimesh(test::cube());
  Segmentation whole;
  whole.patches.resize(1);
  for (const auto f : cube.faces()) {
    whole.face_patch.push_back(0);
    whole.patches[0].faces.push_back(f.idx());
  }
  EXPECT_TRUE(narrow_patches(cube, whole, 1e9).empty());
  // A box smaller than max_width, one patch per side: every side narrow, none listed.
  Segmentation sides;
  sides.patches.resize(6);
  for (const auto f : cube.faces()) {
    const auto n = cube.calc_face_normal(f);
    int axis = 0;
    for (int i = 1; i < 3; ++i)
      if (std::abs(n[i]) > std::abs(n[axis])) axis = i;
    const int p = 2 * axis + (n[axis] > 0.0 ? 1 : 0);
    sides.face_patch.push_back(p);
    sides.patches[static_cast<std::size_t>(p)].faces.push_back(f.idx());
  }
  EXPECT_TRUE(narrow_patches(cube, sides, 10.0).empty());
  EXPECT_THROW((void)narrow_patches(mesh, seg, std::nan("")), InvalidInput);
  EXPECT_THROW((void)narrow_patches(cube, seg, 1.0), InvalidInput);  // another mesh's segmentation
}

// segment_detail::widen_patches (the pipeline's RemeshOptions::narrow_widen_width): an open
// 8 x 4 grid of unit cells bent by bend_deg along x = 6; patch 0 = the flat cells x < 6, patch 1
// = the two bent columns (area 8, border 4 + 4 + 2 + 2: width 4/3; patch 0: width 2.4). At
// min_width 1.6 patch 1 takes, where patch 0's faces meet the slope bound for its axis and the
// bend is no crease, the column 5 < x < 6 but its top left triangle: the 4 triangles on the
// bend and the 3 teeth between them (2 edges on patch 1 and the ring; the top one has 1): area
// 11.5, border 4 + 3 + 2 + 3 + sqrt 2, width 1.71 (patch 0: 20.5 / 19.41 x 2 = 2.11).
struct BentGrid {
  TriMesh mesh;
  Segmentation seg;
};
BentGrid bent_grid(double bend_deg) {
  TriangleSoup soup = test::grid_patch(8, 4);
  const double bend = bend_deg * std::numbers::pi / 180.0;
  for (auto& p : soup.points) {
    p.x() *= 8.0;
    p.y() *= 4.0;
    if (p.x() > 6.0) {
      const double d = p.x() - 6.0;
      p.x() = 6.0 + d * std::cos(bend);
      p.z() = d * std::sin(bend);
    }
  }
  BentGrid g;
  g.mesh = to_trimesh(soup);
  g.seg.patches.resize(2);
  for (const auto f : g.mesh.faces()) {
    const int p = g.mesh.calc_face_centroid(f)[0] < 6.0 - 1e-9 ? 0 : 1;
    g.seg.face_patch.push_back(p);
    g.seg.patches[static_cast<std::size_t>(p)].faces.push_back(f.idx());
  }
  for (auto& patch : g.seg.patches) {
    const auto n = g.mesh.calc_face_normal(g.mesh.face_handle(patch.faces.front()));
    patch.axis = Eigen::Vector3d(n[0], n[1], n[2]);
  }
  return g;
}

TEST(WidenPatches, NarrowPatchTakesARingAcrossASlopeBoundedBorder) {
  const SegmentOptions options;
  const BentGrid g = bent_grid(30.0);
  ASSERT_EQ(g.seg.patches[1].faces.size(), 16u);
  auto splitter = segment_detail::make_splitter(g.mesh, options);
  std::size_t n_widened = 0;
  const Segmentation wide = segment_detail::widen_patches(*splitter, g.seg, {1}, 1.6, true, &n_widened);
  EXPECT_EQ(n_widened, 1u);
  ASSERT_EQ(wide.patches.size(), 2u);
  segment_test::expect_contracts(g.mesh, wide, options, 0.0);
  // The column 5 < x < 6 moved but its top left triangle; the axes stay.
  for (const auto f : g.mesh.faces()) {
    const auto c = g.mesh.calc_face_centroid(f);
    const bool top_left = c[0] > 5.0 && c[0] < 5.5 && c[1] > 3.5;
    EXPECT_EQ(wide.face_patch[static_cast<std::size_t>(f.idx())], c[0] < 5.0 || top_left ? 0 : 1)
        << "face " << f.idx() << " at x " << c[0];
  }
  EXPECT_EQ(wide.patches[1].faces.size(), 23u);
  for (std::size_t p = 0; p < 2; ++p) EXPECT_NEAR(wide.patches[p].axis.dot(g.seg.patches[p].axis), 1.0, 1e-12);
  const auto widths = [&](const Segmentation& s, double bound) { return narrow_patches(g.mesh, s, bound); };
  EXPECT_EQ(widths(g.seg, 1.6), std::vector<int>{1});
  EXPECT_TRUE(widths(wide, 1.6).empty());  // 12/7 and 2 wide now
  // A bound it meets already, or none: the same segmentation.
  EXPECT_EQ(segment_detail::widen_patches(*splitter, g.seg, {1}, 1.3, true, &n_widened).face_patch, g.seg.face_patch);
  EXPECT_EQ(n_widened, 0u);
  EXPECT_EQ(segment_detail::widen_patches(*splitter, g.seg, {}, 1.6).face_patch, g.seg.face_patch);
  // A bound the giver cannot keep (patch 0 would fall to 2.11 < 2.3): nothing moves.
  EXPECT_EQ(segment_detail::widen_patches(*splitter, g.seg, {1}, 2.3).face_patch, g.seg.face_patch);
  EXPECT_THROW((void)segment_detail::widen_patches(*splitter, g.seg, {1}, std::nan("")), InvalidInput);
  EXPECT_THROW((void)segment_detail::widen_patches(*splitter, g.seg, {1}, -1.0), InvalidInput);
  EXPECT_THROW((void)segment_detail::widen_patches(*splitter, g.seg, {2}, 1.6), InvalidInput);
}

TEST(WidenPatches, NoRingAcrossASteepBendOrACrease) {
  // Bent by 30 deg with a 5-deg slope bound: patch 0's faces (smoothed normals at most half
  // way round the bend) are outside patch 1's cone. (At 70 deg and 60 the smoothed normals
  // beside the bend, no crease stopping the averaging, are within it: the column moves.)
  const BentGrid steep = bent_grid(30.0);
  SegmentOptions steep_options;
  steep_options.max_slope_deg = 5.0;
  auto splitter = segment_detail::make_splitter(steep.mesh, steep_options);
  std::size_t n_widened = 1;
  EXPECT_EQ(segment_detail::widen_patches(*splitter, steep.seg, {1}, 1.6, true, &n_widened).face_patch,
            steep.seg.face_patch);
  EXPECT_EQ(n_widened, 0u);
  // Bent by 50 deg with a 40-deg crease angle: within the cone, but the bend is a crease.
  const BentGrid creased = bent_grid(50.0);
  SegmentOptions crease_options;
  crease_options.crease_angle_deg = 40.0;
  auto crease_splitter = segment_detail::make_splitter(creased.mesh, crease_options);
  EXPECT_EQ(segment_detail::widen_patches(*crease_splitter, creased.seg, {1}, 1.6, true, &n_widened).face_patch,
            creased.seg.face_patch);
  EXPECT_EQ(n_widened, 0u);
  // The same bend without the crease: the column moves.
  auto plain_splitter = segment_detail::make_splitter(creased.mesh, SegmentOptions{});
  EXPECT_NE(segment_detail::widen_patches(*plain_splitter, creased.seg, {1}, 1.6, true, &n_widened).face_patch,
            creased.seg.face_patch);
  EXPECT_EQ(n_widened, 1u);
}

// Session 20 (docs/segment.md "Fin strips: pinned tips, session 20"): a 4 x 4 grid of side 1,
// patch 0 = x < 1/2, patch 1 = x > 1/2 but the cell [1/2, 3/4] x [1/2, 3/4], a strip (patch 2)
// whose vertices (1/2, 1/2) and (1/2, 3/4) are corners (3 sides). Joined into patch 1 (its
// longest border), both are left with two sides: the corner guard at 0 refuses the join; with
// pinned tips it is made, both vertices stay corners (the border x = 1/2 ends there: three
// curves instead of one) and later edits keep them; at guard 1 without pins the curve is one.
TEST(MergeIntoNeighbours, PinnedTipsStayCorners) {
  const TriMesh mesh = to_trimesh(test::grid_patch(4, 4));
  Segmentation seg;
  seg.patches.resize(3);
  for (const auto f : mesh.faces()) {
    const auto c = mesh.calc_face_centroid(f);
    const int p = c[0] < 0.5 ? 0 : (c[0] < 0.75 && c[1] > 0.5 && c[1] < 0.75 ? 2 : 1);
    seg.face_patch.push_back(p);
    seg.patches[static_cast<std::size_t>(p)].faces.push_back(f.idx());
  }
  ASSERT_EQ(seg.patches[2].faces.size(), 2u);
  seg = segment_detail::with_borders(mesh, SegmentOptions{}, seg);
  const auto vertex_at = [&](double x, double y) {
    for (const auto v : mesh.vertices())
      if (std::abs(mesh.point(v)[0] - x) < 1e-9 && std::abs(mesh.point(v)[1] - y) < 1e-9) return v.idx();
    return -1;
  };
  const std::vector<int> tips{vertex_at(0.5, 0.5), vertex_at(0.5, 0.75)};
  for (const int v : tips) EXPECT_TRUE(std::binary_search(seg.corners.begin(), seg.corners.end(), v));
  // Curves along x = 1/2 (between patches 0 and the other side), counted.
  const auto n_middle_curves = [&](const Segmentation& s) {
    return std::count_if(s.curves.begin(), s.curves.end(), [&](const BorderCurve& c) {
      return c.patch_right >= 0 && std::all_of(c.vertices.begin(), c.vertices.end(), [&](int v) {
               return std::abs(mesh.point(mesh.vertex_handle(static_cast<unsigned>(v)))[0] - 0.5) < 1e-9;
             });
    });
  };
  auto splitter = segment_detail::make_splitter(mesh, SegmentOptions{});
  // The guard at 0 without pins: refused.
  const Segmentation refused = segment_detail::merge_into_neighbours(*splitter, seg, {2}, true, false, false, nullptr, 0);
  EXPECT_EQ(refused.patches.size(), 3u);
  // At 1 without pins: refused too (two corners lost); no guard: joined, one curve along x = 1/2.
  EXPECT_EQ(segment_detail::merge_into_neighbours(*splitter, seg, {2}, true, false, false, nullptr, 1).patches.size(), 3u);
  const Segmentation plain = segment_detail::merge_into_neighbours(*splitter, seg, {2}, true, false, false, nullptr, -1);
  ASSERT_EQ(plain.patches.size(), 2u);
  EXPECT_TRUE(plain.pinned_corners.empty());
  for (const int v : tips) EXPECT_FALSE(std::binary_search(plain.corners.begin(), plain.corners.end(), v));
  EXPECT_EQ(n_middle_curves(plain), 1);
  // Pinned: joined, both tips corners, the border cut at both.
  const Segmentation pinned = segment_detail::merge_into_neighbours(*splitter, seg, {2}, true, false, false, nullptr, 0, 180.0);
  ASSERT_EQ(pinned.patches.size(), 2u);
  EXPECT_EQ(pinned.face_patch, plain.face_patch);
  EXPECT_EQ(pinned.pinned_corners, (std::vector<int>{std::min(tips[0], tips[1]), std::max(tips[0], tips[1])}));
  for (const int v : tips) EXPECT_TRUE(std::binary_search(pinned.corners.begin(), pinned.corners.end(), v));
  EXPECT_EQ(n_middle_curves(pinned), 3);
  segment_test::expect_contracts(mesh, pinned, SegmentOptions{}, 0.0);
  // Without borders, then with them (the pipeline's order), and through a split: kept.
  const Segmentation later = segment_detail::with_borders(
      mesh, SegmentOptions{},
      segment_detail::merge_into_neighbours(*splitter, seg, {2}, false, false, false, nullptr, 0, 180.0));
  EXPECT_EQ(later.corners, pinned.corners);
  EXPECT_EQ(segment_detail::split(*splitter, later, {1}).pinned_corners, pinned.pinned_corners);
}

// A 4 x 4 grid of side 1 folded by `fold_deg` along x = 0.75; patches: 1 = the two faces of
// the cell [0.25, 0.5] x [0.25, 0.5], 2 = those of [0.5, 0.75] x [0.25, 0.5] (its right edge on
// the fold), 3 = one face of the cell [0.25, 0.5] x [0.75, 1] (only patch 0 around it), 0 = the rest.
TEST(TinyPatches, SmallPatchesBehindMarginalBendsOnly) {
  const double fold = 30.0 * std::numbers::pi / 180.0;
  TriangleSoup soup = test::grid_patch(4, 4);
  for (auto& p : soup.points) {
    if (p.x() <= 0.75) continue;
    const double d = p.x() - 0.75;
    p.x() = 0.75 + d * std::cos(fold);
    p.z() = d * std::sin(fold);
  }
  const TriMesh mesh = to_trimesh(soup);
  Segmentation seg;
  seg.patches.resize(4);
  bool island_taken = false;
  for (const auto f : mesh.faces()) {
    const auto c = mesh.calc_face_centroid(f);
    int p = 0;
    if (c[1] > 0.25 && c[1] < 0.5 && c[0] > 0.25 && c[0] < 0.5) p = 1;
    if (c[1] > 0.25 && c[1] < 0.5 && c[0] > 0.5 && c[0] < 0.75) p = 2;
    if (c[1] > 0.75 && c[0] > 0.25 && c[0] < 0.5 && !island_taken) {
      p = 3;
      island_taken = true;
    }
    seg.face_patch.push_back(p);
    seg.patches[static_cast<std::size_t>(p)].faces.push_back(f.idx());
  }
  ASSERT_EQ(seg.patches[1].faces.size(), 2u);
  ASSERT_EQ(seg.patches[2].faces.size(), 2u);
  ASSERT_EQ(seg.patches[3].faces.size(), 1u);
  // Patch 2 borders the 30 deg fold: listed from a 30 deg bound on (1e-6 for rounding).
  EXPECT_EQ(tiny_patches(mesh, seg, 2, 30.0 + 1e-6), (std::vector<int>{1, 2}));
  EXPECT_EQ(tiny_patches(mesh, seg, 2, 30.0 - 1e-6), std::vector<int>{1});
  EXPECT_EQ(tiny_patches(mesh, seg, 2, 0.0), std::vector<int>{1});  // a flat border bends by 0
  // Patch 3 (one face, surrounded by patch 0) is an island: never listed.
  EXPECT_TRUE(tiny_patches(mesh, seg, 1, 180.0).empty());
  // Every patch tiny: none has a larger neighbour, none is listed.
  EXPECT_TRUE(tiny_patches(mesh, seg, 100, 180.0).empty());
  EXPECT_TRUE(tiny_patches(mesh, seg, 0, 180.0).empty());
  EXPECT_THROW((void)tiny_patches(mesh, seg, 2, std::numeric_limits<double>::quiet_NaN()), InvalidInput);
  Segmentation other = seg;
  other.face_patch.pop_back();
  EXPECT_THROW((void)tiny_patches(mesh, other, 2, 90.0), InvalidInput);
}

// An accordion: a grid of nx x 4 unit cells whose column lines x = 1 .. nx - 1 are folds
// bending by folds_deg[i - 1] (alternately up and down); the cells' diagonals and the rows'
// edges stay flat. Each fold is 4 edges of that bend among the grid's interior edges.
TriMesh accordion(const std::vector<double>& folds_deg) {
  const int nx = static_cast<int>(folds_deg.size()) + 1;
  TriangleSoup soup = test::grid_patch(nx, 4, static_cast<double>(nx));
  std::vector<Eigen::Vector2d> profile{{0.0, 0.0}};  // (x, z) of each column line
  double direction = 0.0;
  for (int i = 1; i <= nx; ++i) {
    profile.push_back(profile.back() + Eigen::Vector2d(std::cos(direction), std::sin(direction)));
    if (i < nx) direction += (i % 2 == 1 ? 1.0 : -1.0) * radians(folds_deg[static_cast<std::size_t>(i - 1)]);
  }
  for (auto& p : soup.points) {
    const auto column = static_cast<std::size_t>(std::lround(p.x()));
    p.x() = profile[column].x();
    p.z() = profile[column].y();
  }
  return to_trimesh(soup);
}

// segment's gap_crease_angle (docs/segment.md "Creases at a gap in the bends"): 9 folds of 4
// edges each among the accordion's interior edges (10 x 4 cells: 30 + 36 + 40 = 106 edges,
// each fold 3.8% of them, above kCreaseGapMinShare).
TEST(GapCreaseAngle, DropsToAGapBelowTheCreaseAngle) {
  // Every fold at 72 deg, nothing between 55 and 70: the crease angle drops to 70.
  EXPECT_EQ(gap_crease_angle(accordion(std::vector<double>(9, 72.0)), 80.0), 70.0);
  // Folds at 77 and 67 (cheese's rims), nothing between 50 and 65: both kinds are creases at 65.
  const std::vector<double> pairs{77, 67, 77, 67, 77, 67, 77, 67, 77};
  EXPECT_EQ(gap_crease_angle(accordion(pairs), 80.0), 65.0);
  // Folds at 72 and 62: no gap within 15 deg below the 72 deg folds: unchanged.
  EXPECT_EQ(gap_crease_angle(accordion({72, 62, 72, 62, 72, 62, 72, 62, 72}), 80.0), 80.0);
  // Bends spread evenly (femur): unchanged.
  EXPECT_EQ(gap_crease_angle(accordion({78, 74, 71, 66, 62, 58, 54, 50, 46}), 80.0), 80.0);
  // Folds above the crease angle are creases already; a flat grid has no bend at all.
  EXPECT_EQ(gap_crease_angle(accordion(std::vector<double>(9, 85.0)), 80.0), 80.0);
  EXPECT_EQ(gap_crease_angle(accordion(std::vector<double>(9, 0.0)), 80.0), 80.0);
  // One fold of 4 edges among 106 (3.8%) is enough; a share under 2% is not (one fold of a
  // 30 x 4 grid: 4 of 90 + 116 + 120 = 326 edges).
  EXPECT_EQ(gap_crease_angle(accordion({0, 0, 0, 0, 72, 0, 0, 0, 0}), 80.0), 70.0);
  std::vector<double> long_grid(29, 0.0);
  long_grid[14] = 72.0;
  EXPECT_EQ(gap_crease_angle(accordion(long_grid), 80.0), 80.0);
  // The candidates stay above 0 and follow the crease angle given.
  EXPECT_EQ(gap_crease_angle(accordion(std::vector<double>(9, 22.0)), 30.0), 20.0);
  EXPECT_EQ(gap_crease_angle(accordion(std::vector<double>(9, 12.0)), 20.0), 20.0);  // the flat edges: no gap
  EXPECT_EQ(gap_crease_angle(accordion(std::vector<double>(9, 3.0)), 5.0), 5.0);
  EXPECT_THROW((void)gap_crease_angle(accordion(pairs), 0.0), InvalidInput);
  EXPECT_THROW((void)gap_crease_angle(accordion(pairs), 181.0), InvalidInput);
  EXPECT_THROW((void)gap_crease_angle(accordion(pairs), std::nan("")), InvalidInput);
}

// The pipeline's other remedy against crossings: segment_detail::bisect_patches cuts a patch
// in two by a breadth-first partition from its two most distant faces. On a strip of 2 n
// triangles (a chain through their shared edges) the cut is exactly at the middle.
// A mesh segmented into one patch, and that patch bisected.
struct Bisected {
  Segmentation seg;
  segment_detail::SplitterPtr splitter;
  Segmentation halves;
};

Bisected bisect_single_patch(const TriMesh& mesh, const SegmentOptions& options) {
  Bisected b;
  b.seg = run(mesh, options, 0.0);
  EXPECT_EQ(b.seg.patches.size(), 1u);
  b.splitter = segment_detail::make_splitter(mesh, options);
  b.halves = segment_detail::bisect_patches(*b.splitter, b.seg, {0});
  // Partition, connected halves, projections simple, curves and corners consistent.
  segment_test::expect_contracts(mesh, b.halves, options, 0.0);
  return b;
}

TEST(BisectPatches, StripIsCutAtItsMiddle) {
  const int n = 6;
  const TriMesh mesh = to_trimesh(test::grid_patch(n, 1));
  const SegmentOptions options;
  const auto [seg, splitter, halves] = bisect_single_patch(mesh, options);
  ASSERT_EQ(halves.patches.size(), 2u);
  for (const Patch& half : halves.patches) {
    ASSERT_EQ(half.faces.size(), static_cast<std::size_t>(n));
    // The faces of a half all lie on one side of x = 1/2 (the strip's middle edge).
    const bool left = mesh.calc_face_centroid(mesh.face_handle(half.faces.front()))[0] < 0.5;
    for (const int f : half.faces) {
      EXPECT_EQ(mesh.calc_face_centroid(mesh.face_handle(f))[0] < 0.5, left) << "face " << f;
    }
    EXPECT_NEAR(half.axis.dot(Eigen::Vector3d::UnitZ()), 1.0, 1e-12);
  }
  // The two halves meet along the middle edge, from (1/2, 0) to (1/2, 1): one curve of one
  // edge between patches 0 and 1, its ends the two corners (vertices 3 and n + 1 + 3).
  const std::vector<int> corners{n / 2, n + 1 + n / 2};
  EXPECT_EQ(halves.corners, corners);
  int n_shared = 0;
  for (const BorderCurve& curve : halves.curves) {
    if (curve.patch_right < 0) continue;  // the input's boundary
    ++n_shared;
    EXPECT_EQ(curve.patch_left, 0);
    EXPECT_EQ(curve.patch_right, 1);
    ASSERT_EQ(curve.edges.size(), 1u);
    std::vector<int> ends{curve.vertices.front(), curve.vertices.back()};
    std::sort(ends.begin(), ends.end());
    EXPECT_EQ(ends, corners);
  }
  EXPECT_EQ(n_shared, 1);
  // Nothing listed: the same segmentation; a bad id throws.
  EXPECT_EQ(segment_detail::bisect_patches(*splitter, seg, {}).face_patch, seg.face_patch);
  EXPECT_THROW((void)segment_detail::bisect_patches(*splitter, seg, {1}), InvalidInput);
}

// A square: both halves non-empty, together the patch, each connected and projecting, cut
// along one curve from boundary to boundary.
TEST(BisectPatches, SquareHalvesPartitionThePatch) {
  const TriMesh mesh = to_trimesh(test::grid_patch(5, 5));
  const Segmentation halves = bisect_single_patch(mesh, SegmentOptions{}).halves;
  ASSERT_EQ(halves.patches.size(), 2u);
  for (const Patch& half : halves.patches) EXPECT_FALSE(half.faces.empty());
  EXPECT_EQ(halves.patches[0].faces.size() + halves.patches[1].faces.size(), mesh.n_faces());
  // One cut: the halves share exactly one border curve, which ends at two corners on the
  // square's boundary.
  int n_shared = 0;
  for (const BorderCurve& curve : halves.curves) {
    if (curve.patch_right < 0) continue;
    ++n_shared;
    EXPECT_FALSE(curve.is_closed);
    for (const int end : {curve.vertices.front(), curve.vertices.back()}) {
      EXPECT_TRUE(mesh.is_boundary(mesh.vertex_handle(static_cast<unsigned>(end)))) << "vertex " << end;
    }
  }
  EXPECT_EQ(n_shared, 1);
  EXPECT_EQ(halves.corners.size(), 2u);
}

}  // namespace
}  // namespace nurbsfront
