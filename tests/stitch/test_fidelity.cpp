// SPDX-License-Identifier: BSD-3-Clause
// The stitch's fidelity moves (StitchOptions::fidelity_distance_edges; docs/stitch.md
// "Fidelity moves"): vertices onto the input where the output is far from it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/segment/segment.h"
#include "nurbsfront/stitch/stitch.h"
#include "nurbsfront/stitch/stitch_internal.h"
#include "nurbsfront/surfmesh/surfmesh.h"
#include "support/test_data.h"

namespace nurbsfront {
namespace {

std::size_t obtuse_triangles(const TriMesh& mesh) {
  std::size_t n = 0;
  for (const auto f : mesh.faces()) {
    std::vector<Eigen::Vector3d> p;
    for (const auto v : mesh.fv_range(f)) p.push_back(to_eigen(mesh.point(v)));
    for (int i = 0; i < 3; ++i) {
      const auto& a = p[static_cast<std::size_t>(i)];
      if ((p[static_cast<std::size_t>((i + 1) % 3)] - a).dot(p[static_cast<std::size_t>((i + 2) % 3)] - a) < 0.0) ++n;
    }
  }
  return n;
}

// The brain's set-up of the tests below: the input (a smoothed image's level set), its surface
// (segment(), mesh_surface() with default options) and the plain stitch (no fidelity moves).
struct Brain {
  Brain() : input(read_mesh(test::test_data("io/brainImageSmooth.vtk"))), surface(mesh_surface(input, segment(input))) {
    options.fidelity_distance_edges = 0.0;
    plain = stitch(surface, input, options);
  }
  TriMesh input;
  SurfaceMesh surface;
  StitchOptions options;  // the plain stitch's
  StitchResult plain;
};

TEST(StitchFidelitySlow, MovesAndSplitsBringTheBrainCloserToItsInputAndKeepItsShape) {
  // The brain (a smoothed image's level set): the 2.5-edge fits smooth its folds, and the
  // output misses the input by 1.2 voxels (0.82 mean edges) by default. With the bound at
  // half a mean edge the moves and splits shrink the two-sided distance, add no obtuse
  // triangle, keep the smallest angle away from features at min(before, 25 deg), and every
  // new vertex sits on the input.
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  StitchOptions options = plain_options;
  options.fidelity_distance_edges = 0.5;
  const StitchResult moved = stitch(surface, input, options);
  ASSERT_TRUE(plain.report.ok());
  ASSERT_TRUE(moved.report.ok());
  EXPECT_EQ(plain.report.n_fidelity_moves + plain.report.n_fidelity_splits, 0u);
  EXPECT_GT(moved.report.n_fidelity_moves, 10u);
  EXPECT_GT(moved.report.n_fidelity_splits, 0u);
  EXPECT_EQ(moved.mesh.n_vertices(), plain.mesh.n_vertices() + moved.report.n_fidelity_splits);
  EXPECT_EQ(moved.report.output_components.size(), plain.report.output_components.size());
  EXPECT_EQ(moved.report.output_components[0].euler_characteristic, plain.report.output_components[0].euler_characteristic);
  EXPECT_TRUE(moved.report.output_components[0].is_closed);

  const TriangleSoup reference = to_soup(input);
  DistanceOptions sampling;
  sampling.sample_spacing_relative = 0.01;
  const DistanceReport before = mesh_distance(to_soup(plain.mesh), reference, sampling);
  const DistanceReport after = mesh_distance(to_soup(moved.mesh), reference, sampling);
  EXPECT_LT(after.hausdorff, 0.9 * before.hausdorff);
  EXPECT_LT(after.mean, before.mean);

  EXPECT_LE(obtuse_triangles(moved.mesh), obtuse_triangles(plain.mesh));
  EXPECT_GE(moved.report.min_angle_away_from_features_deg,
            std::min(plain.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg) - 1e-9);

  // The split vertices lie on the input (on its vertices, face centroids or edge midpoints).
  std::vector<std::uint32_t> faces(reference.triangles.size());
  std::iota(faces.begin(), faces.end(), 0U);
  const quality_detail::AabbTree tree(reference, faces);
  for (std::size_t i = plain.mesh.n_vertices(); i < moved.mesh.n_vertices(); ++i) {
    const Eigen::Vector3d p = to_eigen(moved.mesh.point(TriMesh::VertexHandle(static_cast<int>(i))));
    EXPECT_LT(std::sqrt(tree.closest(p, UINT32_MAX).squared_distance), 1e-9 * before.reference_diagonal) << "split vertex " << i;
  }
}

TEST(StitchFidelity, ZeroLeavesTheStitchAsItWasAndBadBoundsThrow) {
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  // No input mesh: nothing to move towards.
  StitchOptions options = plain_options;
  const StitchResult off = stitch(surface, options);
  options.fidelity_distance_edges = 0.5;
  const StitchResult no_input = stitch(surface, options);
  ASSERT_EQ(off.mesh.n_vertices(), no_input.mesh.n_vertices());
  for (const auto v : off.mesh.vertices()) EXPECT_EQ(off.mesh.point(v), no_input.mesh.point(v));
  EXPECT_EQ(no_input.report.n_fidelity_moves, 0u);
  for (const double bad : {-0.1, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    options.fidelity_distance_edges = bad;
    EXPECT_THROW((void)stitch(surface, input, options), InvalidInput);
  }
}

// Per node of the stitched mesh: 1 for the surface's border nodes and corners (the test's
// stand-in for the feature nodes; the fidelity moves leave them alone), 0 for inner nodes and
// the nodes the stitch made.
std::vector<std::uint8_t> border_nodes(const SurfaceMesh& surface, const StitchResult& result) {
  std::size_t n = surface.nodes.size();
  for (const int node : result.vertex_node) n = std::max(n, static_cast<std::size_t>(node + 1));
  std::vector<std::uint8_t> out(n, 0);
  for (std::size_t i = 0; i < surface.nodes.size(); ++i) out[i] = surface.node_kind[i] == NodeKind::Inner ? 0 : 1;
  return out;
}

// The vertex indices of face f's corners, in order.
std::vector<int> corners(const TriMesh& mesh, TriMesh::FaceHandle f) {
  std::vector<int> out;
  for (const auto v : mesh.fv_range(f)) out.push_back(v.idx());
  return out;
}

TEST(StitchFidelitySlow, IncrementalSweepsGiveTheFullSweepsResult) {
  // (Slow: 1.5 s in RelWithDebInfo, 92 s under ASan; the CI runs it in the slow suite.)
  // The brain with the bound at 0.3 mean edges: several sweeps change the mesh. Measuring
  // again only near the last sweep's changes (and trying only the candidates there) makes
  // exactly the moves and splits of sweeps that measure and try everything.
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  ASSERT_TRUE(plain.report.ok());
  StitchOptions options = plain_options;
  options.fidelity_distance_edges = 0.3;
  const stitch_detail::FinRimBound no_bound;
  StitchResult full = plain, incremental = plain;
  std::vector<std::uint8_t> feature_full = border_nodes(surface, plain), feature_incremental = feature_full;
  const auto a = stitch_detail::move_toward_input(input, options, feature_full, surface.input_mean_edge, no_bound, full, false);
  const auto b =
      stitch_detail::move_toward_input(input, options, feature_incremental, surface.input_mean_edge, no_bound, incremental, true);
  EXPECT_GE(a.n_sweeps_changing, 2u);
  EXPECT_GT(a.n_moved, 20u);
  EXPECT_GT(a.n_split, 0u);
  EXPECT_EQ(a.n_moved, b.n_moved);
  EXPECT_EQ(a.n_split, b.n_split);
  EXPECT_EQ(a.n_undone, b.n_undone);
  EXPECT_EQ(a.n_sweeps_changing, b.n_sweeps_changing);
  ASSERT_EQ(full.mesh.n_vertices(), incremental.mesh.n_vertices());
  ASSERT_EQ(full.mesh.n_faces(), incremental.mesh.n_faces());
  for (const auto v : full.mesh.vertices()) EXPECT_EQ(full.mesh.point(v), incremental.mesh.point(v)) << "vertex " << v.idx();
  for (const auto f : full.mesh.faces()) EXPECT_EQ(corners(full.mesh, f), corners(incremental.mesh, f)) << "face " << f.idx();
  EXPECT_EQ(full.face_patch, incremental.face_patch);
  EXPECT_EQ(feature_full, feature_incremental);
}

TEST(StitchFidelitySlow, BoundedNodesStayWithinTheirBound) {
  // (Slow: about 1.5 s in RelWithDebInfo, 104 s under ASan; the CI runs it in the slow suite.)
  // Every node bounded at a tenth of a mean edge from where the front put it: after the moves
  // each vertex of a bounded node is where it was or within the bound of its origin.
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  StitchOptions options = plain_options;
  StitchResult result = plain;
  ASSERT_TRUE(result.report.ok());
  const StitchResult before = result;
  options.fidelity_distance_edges = 0.3;
  stitch_detail::FinRimBound rim;
  rim.on_rim.assign(surface.nodes.size(), 1);
  rim.radius = 0.1 * surface.input_mean_edge;
  rim.origins = &surface.nodes;
  std::vector<std::uint8_t> feature = border_nodes(surface, result);
  StitchResult unbounded = result;
  std::vector<std::uint8_t> feature_unbounded = feature;
  const auto free_run = stitch_detail::move_toward_input(input, options, feature_unbounded, surface.input_mean_edge,
                                                         stitch_detail::FinRimBound{}, unbounded);
  (void)stitch_detail::move_toward_input(input, options, feature, surface.input_mean_edge, rim, result);
  // Without the bound some vertex goes farther than it from its origin.
  std::size_t n_beyond_unbounded = 0;
  for (const auto v : before.mesh.vertices()) {
    const auto i = static_cast<std::size_t>(v.idx());
    const int node = result.vertex_node[i];
    if (node < 0 || static_cast<std::size_t>(node) >= surface.nodes.size()) continue;
    const Eigen::Vector3d origin = surface.nodes[static_cast<std::size_t>(node)];
    const Eigen::Vector3d p = to_eigen(result.mesh.point(v)), q = to_eigen(unbounded.mesh.point(v));
    if (p != to_eigen(before.mesh.point(v))) {
      EXPECT_LE((p - origin).norm(), rim.radius * (1.0 + 1e-9)) << "vertex " << i;
    }
    if (q != to_eigen(before.mesh.point(v)) && (q - origin).norm() > rim.radius) ++n_beyond_unbounded;
  }
  EXPECT_GT(free_run.n_moved, 0u);
  EXPECT_GT(n_beyond_unbounded, 0u);
}

TEST(StitchFidelity, WalkingFirstSweepSelectsTheFullSearchsCandidates) {
  // The brain, bounds of 0.3 and 0.5 mean edges: the first sweep that searches a sample in
  // the output's tree only when its walk over the output ends farther than the bound picks
  // exactly the candidates (samples and vertices, with their distances) of the sweep that
  // searches every sample, and the walk alone settles most samples.
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  ASSERT_TRUE(plain.report.ok());
  StitchOptions options = plain_options;
  const std::size_t n_samples = input.n_vertices() + 4 * input.n_faces();
  for (const double bound : {0.3, 0.5}) {
    options.fidelity_distance_edges = bound;
    const std::vector<std::uint8_t> feature = border_nodes(surface, plain);
    const auto full = stitch_detail::fidelity_candidates(input, options, feature, surface.input_mean_edge, plain, false);
    const auto walk = stitch_detail::fidelity_candidates(input, options, feature, surface.input_mean_edge, plain, true);
    EXPECT_GT(full.samples.size(), 10u) << bound;
    EXPECT_EQ(full.n_walked, 0u);
    EXPECT_EQ(full.n_searched + full.n_certified, n_samples);
    EXPECT_EQ(walk.n_walked + walk.n_searched + walk.n_certified, n_samples);
    EXPECT_GT(walk.n_walked + walk.n_certified, n_samples * 9 / 10) << bound;
    EXPECT_EQ(walk.samples, full.samples) << bound;
    EXPECT_EQ(walk.vertices, full.vertices) << bound;
    for (const auto& [sample, distance] : full.samples) EXPECT_GT(distance, bound * surface.input_mean_edge);
  }
}

// Every input sample (its vertices, then per face its centroid and edge midpoints, as
// FidelityCandidates::samples numbers them) farther than bound from `output`, with its
// distance, by index (a search of each in the output's tree).
std::vector<std::pair<std::uint32_t, double>> far_samples(const TriMesh& input, const TriMesh& output, double bound) {
  const TriangleSoup out = to_soup(output), in = to_soup(input);
  std::vector<std::uint32_t> faces(out.triangles.size());
  std::iota(faces.begin(), faces.end(), 0U);
  const quality_detail::AabbTree tree(out, faces);
  std::vector<Eigen::Vector3d> samples = in.points;
  for (const auto& t : in.triangles) {
    const Eigen::Vector3d &a = in.points[t[0]], &b = in.points[t[1]], &c = in.points[t[2]];
    samples.push_back((a + b + c) / 3.0);
    samples.push_back(0.5 * (a + b));
    samples.push_back(0.5 * (b + c));
    samples.push_back(0.5 * (c + a));
  }
  std::vector<std::pair<std::uint32_t, double>> far;
  for (std::uint32_t i = 0; i < samples.size(); ++i) {
    const double d = std::sqrt(tree.closest(samples[i], UINT32_MAX).squared_distance);
    if (d > bound) far.emplace_back(i, d);
  }
  return far;
}

// The sweep's input-side candidates `picked` are exactly `far` (far_samples()): the same
// samples, with the same distances (within 1e-12 mean edges: far_samples() computes the face
// samples itself).
void expect_same_samples(const std::vector<std::pair<std::uint32_t, double>>& picked,
                         const std::vector<std::pair<std::uint32_t, double>>& far, double mean_edge) {
  ASSERT_EQ(picked.size(), far.size());
  for (std::size_t k = 0; k < far.size(); ++k) {
    EXPECT_EQ(picked[k].first, far[k].first);
    EXPECT_NEAR(picked[k].second, far[k].second, 1e-12 * mean_edge);
  }
}

// fidelity_candidates() at a bound of 0.25 mean edges (issue 6's setting) on the brain's plain
// stitch, its border nodes fixed.
stitch_detail::FidelityCandidates quarter_edge_candidates(const Brain& brain, bool walk, int sweeps_before = 0) {
  StitchOptions options = brain.options;
  options.fidelity_distance_edges = 0.25;
  return stitch_detail::fidelity_candidates(brain.input, options, border_nodes(brain.surface, brain.plain),
                                            brain.surface.input_mean_edge, brain.plain, walk, sweeps_before);
}

TEST(StitchFidelity, FacesLeftOutHoldNoCandidate) {
  // The first sweep leaves out the samples of the input faces whose corners are within the
  // bound of one output face, and the face samples within the bound of one of their corners'
  // output faces. Every sample of the input (its vertices, face centroids and
  // edge midpoints) measured in the output's tree: those farther than the bound are exactly
  // the sweep's input-side candidates, with the same distances, and most face samples were
  // left out unmeasured.
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  ASSERT_TRUE(plain.report.ok());
  const auto picked = quarter_edge_candidates(brain, true);
  const auto far = far_samples(input, plain.mesh, 0.25 * surface.input_mean_edge);
  ASSERT_GT(far.size(), 10u);
  expect_same_samples(picked.samples, far, surface.input_mean_edge);
  EXPECT_GT(picked.n_certified, 4 * input.n_faces() * 4 / 5);  // 86% on the brain
}

TEST(StitchFidelitySlow, LeftOutSamplesAreCheckedAgainAfterLaterMoves) {
  // The first sweep leaves out the face samples some output face holds within the bound;
  // the moves of a sweep may then push the output away from such a sample (its own input
  // vertices stay near). The brain at 0.25 mean edges: after one and after two sweeps that
  // move, the samples the next sweep measures farther than the bound are exactly those a
  // search of every sample in the output's tree finds, with the same distances, and some of
  // them were left out by the first sweep (checked again because their vouching face
  // changed). Without the re-check those are missed.
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  ASSERT_TRUE(plain.report.ok());
  const double bound = 0.25 * surface.input_mean_edge;
  std::size_t n_promoted_far = 0;
  for (const int before : {1, 2}) {
    const auto picked = quarter_edge_candidates(brain, true, before);
    ASSERT_GT(picked.n_changed_before, 0u) << before;
    EXPECT_GT(picked.n_rechecked, 0u) << before;
    const auto far = far_samples(input, picked.mesh, bound);
    {
      SCOPED_TRACE(before);
      expect_same_samples(picked.samples, far, surface.input_mean_edge);
    }
    // Far samples the first sweep had left out.
    for (const auto& [sample, distance] : far) {
      if (std::binary_search(picked.promoted.begin(), picked.promoted.end(), sample)) ++n_promoted_far;
    }
  }
  EXPECT_GT(n_promoted_far, 0u);
}

TEST(StitchFidelitySlow, RefittedOutputTreeAnswersAsARebuiltOne) {
  // Reviewer's leftover of session 18. After a sweep's moves and splits, the output's tree is
  // refitted over the faces it was built on and the faces made get a small tree of their own
  // (FidelityMover::update_output()). Sweeps that measure everything (walk = false) search
  // every sample again in those trees: after two sweeps that move and split on the brain at
  // 0.25 mean edges, the samples the third measures farther than the bound, with their
  // distances, are exactly those of a tree built anew over its output.
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  ASSERT_TRUE(plain.report.ok());
  const auto picked = quarter_edge_candidates(brain, false, 2);
  EXPECT_GT(picked.n_changed_before, 10u);
  EXPECT_GT(picked.mesh.n_vertices(), plain.mesh.n_vertices());  // splits: faces made after the tree
  EXPECT_EQ(picked.n_walked, 0u);
  const auto far = far_samples(input, picked.mesh, 0.25 * surface.input_mean_edge);
  EXPECT_GT(far.size(), 10u);
  expect_same_samples(picked.samples, far, surface.input_mean_edge);
}

TEST(StitchFidelitySlow, KeptFaceDistancesEqualFreshOnes) {
  // A move's check reads the old ring's largest sample distance to the input from figures
  // kept per output face (forgotten where a move or split changes a face). The brain at 0.25
  // mean edges, after one and after two sweeps that move and split: every kept figure equals
  // the face's distance measured afresh where it is now, and many are kept.
  const Brain brain;
  ASSERT_TRUE(brain.plain.report.ok());
  for (const int before : {1, 2}) {
    const auto picked = quarter_edge_candidates(brain, true, before);
    ASSERT_GT(picked.n_changed_before, 0u) << before;
    EXPECT_GT(picked.n_kept_face_distances, 50u) << before;  // 113 and 238
    EXPECT_EQ(picked.n_stale_face_distances, 0u) << before;
  }
}

TEST(StitchFidelitySlow, MovesDoNotDependOnTheThreadCount) {
  // (Slow: 4 s in RelWithDebInfo.) The first sweep's threaded queries (chunks of a fixed size): the same moves and splits,
  // point for point, with one and with two threads.
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  StitchOptions options = plain_options;
  options.fidelity_distance_edges = 0.25;
  StitchResult one = plain, two = plain;
  std::vector<std::uint8_t> feature_one = border_nodes(surface, plain), feature_two = feature_one;
  options.n_threads = 1;
  const auto a = stitch_detail::move_toward_input(input, options, feature_one, surface.input_mean_edge,
                                                  stitch_detail::FinRimBound{}, one);
  options.n_threads = 2;
  const auto b = stitch_detail::move_toward_input(input, options, feature_two, surface.input_mean_edge,
                                                  stitch_detail::FinRimBound{}, two);
  EXPECT_GT(a.n_moved, 10u);
  EXPECT_EQ(a.n_moved, b.n_moved);
  EXPECT_EQ(a.n_split, b.n_split);
  ASSERT_EQ(one.mesh.n_vertices(), two.mesh.n_vertices());
  for (const auto v : one.mesh.vertices()) EXPECT_EQ(one.mesh.point(v), two.mesh.point(v)) << "vertex " << v.idx();
  EXPECT_EQ(one.face_patch, two.face_patch);
}

TEST(StitchFidelitySlow, GateMeasuresOnlyWhereTheFitsMiss) {
  // (Slow: the brain's moves twice.) StitchOptions::fidelity_gate_edges: the measured input
  // faces are those sharing a corner with a face one of whose corners its patch's fit misses by
  // more than the gate along the patch's axis (computed here face by face); with the gate at
  // the bound (0.25) the moves still bring the brain closer to its input; with the gate above
  // every patch's miss nothing moves.
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  ASSERT_EQ(surface.input_face_patch.size(), input.n_faces());
  StitchOptions options = plain_options;
  options.fidelity_distance_edges = 0.25;
  options.fidelity_gate_edges = 0.25;
  const double bound = options.fidelity_gate_edges * surface.input_mean_edge;
  std::vector<std::uint8_t> near_miss(input.n_vertices(), 0);
  std::size_t n_missing_faces = 0;
  for (const auto f : input.faces()) {
    const PatchSurface& fit = surface.surfaces[static_cast<std::size_t>(surface.input_face_patch[static_cast<std::size_t>(f.idx())])];
    bool misses = false;
    for (const auto v : input.fv_range(f)) {
      const Eigen::Vector3d local = fit.frame.to_local(to_eigen(input.point(v)));
      misses = misses || std::abs(local.z() - fit.field.value(local.x(), local.y())) > bound;
    }
    if (!misses) continue;
    ++n_missing_faces;
    for (const auto v : input.fv_range(f)) near_miss[static_cast<std::size_t>(v.idx())] = 1;
  }
  const stitch_detail::FidelityGate gate = stitch_detail::fidelity_gate(surface, input, options);
  ASSERT_EQ(gate.input_face.size(), input.n_faces());
  std::size_t n_measured = 0;
  for (const auto f : input.faces()) {
    bool expected = false;
    for (const auto v : input.fv_range(f)) expected = expected || near_miss[static_cast<std::size_t>(v.idx())] != 0;
    EXPECT_EQ(gate.input_face[static_cast<std::size_t>(f.idx())] != 0, expected) << "face " << f.idx();
    n_measured += expected ? 1 : 0;
  }
  EXPECT_GT(n_missing_faces, 0u);
  EXPECT_LT(n_measured, input.n_faces());  // the gate leaves some faces out

  const StitchResult gated = stitch(surface, input, options);
  ASSERT_TRUE(gated.report.ok());
  EXPECT_GT(gated.report.n_fidelity_moves, 10u);
  const TriangleSoup reference = to_soup(input);
  DistanceOptions sampling;
  sampling.sample_spacing_relative = 0.01;
  EXPECT_LT(mesh_distance(to_soup(gated.mesh), reference, sampling).hausdorff,
            mesh_distance(to_soup(plain.mesh), reference, sampling).hausdorff);

  double largest_miss = 0.0;
  for (const auto& p : surface.patches) largest_miss = std::max(largest_miss, p.fit_max_residual / surface.input_mean_edge);
  options.fidelity_gate_edges = largest_miss + 0.01;
  const StitchResult none = stitch(surface, input, options);
  EXPECT_EQ(none.report.n_fidelity_moves + none.report.n_fidelity_splits, 0u);
  ASSERT_EQ(none.mesh.n_vertices(), plain.mesh.n_vertices());
  for (const auto v : plain.mesh.vertices()) EXPECT_EQ(none.mesh.point(v), plain.mesh.point(v));
  options.fidelity_gate_edges = -1.0;
  EXPECT_THROW((void)stitch(surface, input, options), InvalidInput);
}

TEST(StitchFidelitySlow, GatedMovesHoldTheBrainWithinTwiceTheDecimatersDistance) {
  // (Slow: the brain's stitch twice.) Issue 6 on the brain: the quadric decimater at the same
  // vertex count is 0.421 voxel (0.29 mean edges) from the input, the plain stitch 1.03
  // (0.71 mean edges: its fits smooth folds narrower than their lattice). The moves at 0.4
  // mean edges, gated at 0.5 (measured only where a fit misses its input by more than that;
  // docs/stitch.md "Fidelity moves, session 21"), bring the two-sided distance under twice the
  // decimater's (0.58 mean edges) with no more obtuse triangles, the smallest angle away from
  // features at min(before, 25 deg) and the topology kept.
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  ASSERT_TRUE(plain.report.ok());
  StitchOptions options = plain_options;
  options.fidelity_distance_edges = 0.4;
  options.fidelity_gate_edges = 0.5;
  const StitchResult gated = stitch(surface, input, options);
  ASSERT_TRUE(gated.report.ok());
  EXPECT_GT(gated.report.n_fidelity_moves, 10u);
  const TriangleSoup reference = to_soup(input);
  DistanceOptions sampling;
  sampling.sample_spacing_relative = 0.01;
  const double edge = surface.input_mean_edge;
  const double twice_decimater = 2.0 * 0.421 / 1.453;  // mean edges (brain: 1.453 voxels)
  EXPECT_GT(mesh_distance(to_soup(plain.mesh), reference, sampling).hausdorff / edge, twice_decimater);
  EXPECT_LT(mesh_distance(to_soup(gated.mesh), reference, sampling).hausdorff / edge, twice_decimater);
  EXPECT_LE(obtuse_triangles(gated.mesh), obtuse_triangles(plain.mesh));
  EXPECT_GE(gated.report.min_angle_away_from_features_deg,
            std::min(plain.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg) - 1e-9);
  EXPECT_EQ(gated.report.output_components.size(), plain.report.output_components.size());
  EXPECT_EQ(gated.report.output_components[0].euler_characteristic, plain.report.output_components[0].euler_characteristic);
  EXPECT_TRUE(gated.report.output_components[0].is_closed);
}

double alpha_of(const TriMesh& mesh, TriMesh::FaceHandle f) {
  std::vector<Eigen::Vector3d> p;
  for (const auto v : mesh.fv_range(f)) p.push_back(to_eigen(mesh.point(v)));
  const double l2 = (p[1] - p[0]).squaredNorm() + (p[2] - p[1]).squaredNorm() + (p[0] - p[2]).squaredNorm();
  return 2.0 * std::sqrt(3.0) * (p[1] - p[0]).cross(p[2] - p[0]).norm() / l2;
}

TEST(StitchFidelitySlow, AlphaFloorHoldsForEveryMovedTriangle) {
  // (Slow: 4 s in RelWithDebInfo.) fidelity_alpha_floor 0.8 on the brain: every triangle of the plain stitch still there
  // (the same corners) keeps min(its old alpha, 0.8); without the floor some falls below.
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  StitchOptions options = plain_options;
  options.fidelity_distance_edges = 0.25;
  // The largest min(old alpha, 0.8) - new alpha over the triangles kept, with the option at floor.
  auto worst_drop = [&](double floor, std::size_t& n_moved) {
    options.fidelity_alpha_floor = floor;
    StitchResult result = plain;
    std::vector<std::uint8_t> feature = border_nodes(surface, plain);
    const auto r = stitch_detail::move_toward_input(input, options, feature, surface.input_mean_edge,
                                                    stitch_detail::FinRimBound{}, result);
    EXPECT_EQ(r.n_undone, 0u);
    n_moved = r.n_moved;
    double worst = -1.0;
    for (const auto f : plain.mesh.faces()) {
      if (corners(plain.mesh, f) != corners(result.mesh, f)) continue;
      worst = std::max(worst, std::min(alpha_of(plain.mesh, f), 0.8) - alpha_of(result.mesh, f));
    }
    return worst;
  };
  std::size_t n_floor = 0, n_free = 0;
  EXPECT_LE(worst_drop(0.8, n_floor), 1e-12);
  EXPECT_GT(worst_drop(0.0, n_free), 0.01);  // the ring's floor (alpha_floor 0.5) alone
  EXPECT_GT(n_floor, 10u);
  StitchOptions bad;
  for (const double b : {-0.1, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    bad.fidelity_alpha_floor = b;
    EXPECT_THROW(bad.validate(), InvalidInput);
  }
}

TEST(StitchFidelitySlow, QuarterEdgeBoundBringsTheBrainCloserToItsInput) {
  // A bound of 0.25 mean edges (issue 6's setting): on the brain the moves shrink the
  // two-sided distance to the input by a tenth at least, add no obtuse triangle, keep the
  // smallest angle away from features at min(before, 25 deg) and the topology. With the
  // input's soup and tree built by the caller (the pipeline shares them with the distance
  // pass): the same moves, splits and mesh as the stitch that builds its own (this stitch,
  // shared with the test of that since session 20).
  const Brain brain;
  const auto& [input, surface, plain_options, plain] = brain;
  ASSERT_TRUE(plain.report.ok());
  EXPECT_EQ(StitchOptions{}.fidelity_distance_edges, 0.0);  // opt-in (lead, session 15)
  StitchOptions quarter;
  quarter.fidelity_distance_edges = 0.25;
  const StitchResult moved = stitch(surface, input, quarter);
  ASSERT_TRUE(moved.report.ok());
  EXPECT_GT(moved.report.n_fidelity_moves, 10u);
  EXPECT_EQ(moved.report.output_components[0].euler_characteristic, plain.report.output_components[0].euler_characteristic);
  EXPECT_LE(obtuse_triangles(moved.mesh), obtuse_triangles(plain.mesh));
  EXPECT_GE(moved.report.min_angle_away_from_features_deg,
            std::min(plain.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg) - 1e-9);
  const TriangleSoup reference = to_soup(input);
  DistanceOptions sampling;
  sampling.sample_spacing_relative = 0.01;
  EXPECT_LT(mesh_distance(to_soup(moved.mesh), reference, sampling).hausdorff,
            0.9 * mesh_distance(to_soup(plain.mesh), reference, sampling).hausdorff);

  const quality_detail::IndexedSoup index(to_soup(input), 2);
  const StitchResult shared = stitch_detail::stitch_with_input_index(surface, input, index, quarter);
  EXPECT_EQ(shared.report.n_fidelity_moves, moved.report.n_fidelity_moves);
  EXPECT_EQ(shared.report.n_fidelity_splits, moved.report.n_fidelity_splits);
  ASSERT_EQ(shared.mesh.n_vertices(), moved.mesh.n_vertices());
  ASSERT_EQ(shared.mesh.n_faces(), moved.mesh.n_faces());
  for (const auto v : moved.mesh.vertices()) EXPECT_EQ(shared.mesh.point(v), moved.mesh.point(v));
  for (const auto f : moved.mesh.faces()) {
    auto a = moved.mesh.fv_range(f).begin();
    for (const auto w : shared.mesh.fv_range(f)) EXPECT_EQ(w, *a++);
  }
}

TEST(StitchFidelity, LabelImageStaircaseIsLeftAsItWas) {
  // An occupancy (0/1) sphere's marching-cubes staircase: the moves would pull the output
  // onto the staircase, away from the smooth truth the band fits follow, so the stitch does
  // not make them there (the same mesh as without the bound) although they would move
  // vertices (called directly).
  const Scene scene = scene_by_name("sphere");
  const ScalarGrid grid = sample_scene(scene, 20, SampleMode::Occupancy);
  const TriMesh input = to_trimesh(marching_cubes(grid, scene_marching_cubes_options(SampleMode::Occupancy)));
  SurfMeshOptions surf;
  surf.cell_grid = {true, grid.origin, grid.spacing};
  const SurfaceMesh surface = mesh_surface(input, segment(input), surf);
  StitchOptions options;
  options.fidelity_distance_edges = 0.0;  // the plain stitch
  const StitchResult plain = stitch(surface, input, options);
  options.fidelity_distance_edges = 0.25;
  const StitchResult with_bound = stitch(surface, input, options);
  ASSERT_TRUE(plain.report.ok());
  EXPECT_EQ(with_bound.report.n_fidelity_moves + with_bound.report.n_fidelity_splits, 0u);
  ASSERT_EQ(plain.mesh.n_vertices(), with_bound.mesh.n_vertices());
  for (const auto v : plain.mesh.vertices()) EXPECT_EQ(plain.mesh.point(v), with_bound.mesh.point(v));
  StitchResult direct = plain;
  std::vector<std::uint8_t> feature = border_nodes(surface, plain);
  const auto moved = stitch_detail::move_toward_input(input, options, feature, surface.input_mean_edge,
                                                      stitch_detail::FinRimBound{}, direct);
  EXPECT_GT(moved.n_moved + moved.n_split, 0u);
}

}  // namespace
}  // namespace nurbsfront
