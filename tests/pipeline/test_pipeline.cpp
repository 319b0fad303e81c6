// SPDX-License-Identifier: BSD-3-Clause
// remesh() end to end on marching-cubes surfaces of the analytic scenes: the DESIGN.md
// contract, quality, distance to the input and to the true (analytic) surface; bad input.

#include <gtest/gtest.h>

#include <iomanip>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numbers>
#include <set>
#include <string>
#include <tuple>

#include "fixtures/shapes.h"
#include "fixtures/volumes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/isosurface/volume_io.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/pipeline/remesh.h"
#include "nurbsfront/segment/segment_internal.h"
#include "support/test_data.h"

namespace nurbsfront {
namespace {

struct SceneInput {
  Scene scene;
  TriMesh mesh;
  double voxel = 0.0;
  CellGrid cells;  // the sampled grid as a cell grid (enabled: false)
};

SceneInput scene_input(const std::string& name, int resolution, SampleMode mode) {
  SceneInput in;
  in.scene = scene_by_name(name);
  const ScalarGrid grid = sample_scene(in.scene, resolution, mode);
  in.voxel = grid.spacing.x();
  in.cells.origin = grid.origin;
  in.cells.spacing = grid.spacing;
  in.mesh = to_trimesh(marching_cubes(grid, scene_marching_cubes_options(mode)));
  return in;
}

// |signed distance| to the analytic surface at the vertices and triangle centroids.
DistanceSummary truth_error(const TriMesh& mesh, const Scene& scene) {
  const SceneDistance d = distance_to_scene(to_soup(mesh), scene);
  return d.vertices.merged(d.centroids);
}

// The same and at the 12 points of a 4-step barycentric grid in every triangle that are not
// its vertices.
DistanceSummary dense_truth_error(const TriMesh& mesh, const Scene& scene) {
  return distance_to_scene(to_soup(mesh), scene, 4).all();
}

std::string errors_of(const RemeshReport& r) {
  std::string s;
  for (const auto& e : r.errors) s += e + "\n";
  return s;
}

// The output contract every remesh() test checks: no report error; closed, 2-manifold,
// oriented like the input, the given Euler characteristic, no degenerate face and no
// self-intersecting pair (counted).
void expect_closed_clean(const RemeshResult& r, long euler) {
  EXPECT_TRUE(r.report.ok()) << errors_of(r.report);
  const TopologyReport& t = r.report.output.topology;
  EXPECT_TRUE(t.is_closed);
  EXPECT_TRUE(t.is_manifold);
  EXPECT_TRUE(t.is_consistently_oriented);
  EXPECT_EQ(t.euler_characteristic, euler);
  EXPECT_EQ(t.n_degenerate_faces, 0u);
  ASSERT_TRUE(t.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
}

// The properties of the issue's "Must show" that hold for every scene input.
void expect_contract_and_quality(const RemeshResult& r, const SceneInput& in, long euler) {
  const RemeshReport& rep = r.report;
  expect_closed_clean(r, euler);
  EXPECT_EQ(r.face_patch.size(), r.mesh.n_faces());
  EXPECT_EQ(rep.n_failed_patches, 0u);
  const QualityReport& q = rep.output.quality;
  EXPECT_GE(q.alpha_mean, 0.9);
  EXPECT_LT(q.obtuse_fraction, 0.01);
  ASSERT_TRUE(rep.output.distance.has_value());
  const DistanceReport& d = *rep.output.distance;
  EXPECT_LE(d.hausdorff, in.voxel);
  EXPECT_TRUE(d.relative_volume_change.has_value());
}

double volume_change(const RemeshResult& r) {
  return r.report.output.distance && r.report.output.distance->relative_volume_change
             ? std::abs(*r.report.output.distance->relative_volume_change)
             : 1.0;
}

RemeshOptions fast_options() {
  RemeshOptions options;
  options.set_threads(2);
  return options;
}

// Issue 5: the smallest angle of the triangles away from features (no vertex on a crease,
// the input's boundary or a corner ending one) is at least 25 deg.
void expect_min_angle_away_from_features(const RemeshResult& r) {
  const StitchReport& s = r.report.stitch;
  EXPECT_GT(s.n_away_from_features, r.mesh.n_faces() / 2);
  EXPECT_GE(s.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg);
  EXPECT_EQ(s.n_small_angle_away_from_features, 0u);
  EXPECT_LE(s.min_angle_away_from_features_deg, 60.0);
  EXPECT_GE(s.min_angle_away_from_features_deg, r.report.output.quality.min_angle_deg);
}

TEST(Pipeline, LevelSetSphere) {
  const SceneInput in = scene_input("sphere", 40, SampleMode::LevelSet);
  const RemeshResult r = remesh(in.mesh, fast_options());
  expect_contract_and_quality(r, in, 2);
  expect_min_angle_away_from_features(r);
  // No crease on a sphere: every triangle is away from features.
  EXPECT_EQ(r.report.stitch.n_away_from_features, r.mesh.n_faces());
  EXPECT_LT(volume_change(r), 0.005);
  const DistanceSummary before = truth_error(in.mesh, in.scene), after = truth_error(r.mesh, in.scene);
  EXPECT_LE(after.mean, before.mean + 0.05 * in.voxel);
  // Issue 5: no further from the truth than the input, beyond 0.05 voxel (dense samples,
  // 2026-11-25: 0.043 voxel without the fit's second polish, 0.032 with it; input 0.019).
  EXPECT_LE(after.max, before.max + 0.05 * in.voxel);
}

// An open height field over a square (a terrain): its boundary has four 90 deg corners. The
// boundary curve is one loop without corners; smoothing it would round the corners off by
// up to one mean edge (terrain_stl_data: Hausdorff 1.23 mean input edges), so boundary
// curves keep their input polyline (SurfMeshOptions::unsmoothed_boundary_curves).
TEST(Pipeline, OpenSquareKeepsBoundaryCorners) {
  TriangleSoup soup = test::grid_patch(30, 30);
  for (auto& p : soup.points) p.z() = 0.1 * std::sin(3.0 * p.x()) * std::cos(2.0 * p.y());
  const TriMesh input = to_trimesh(soup);
  const double mean_edge = mean_edge_length(input);
  RemeshOptions options = fast_options();
  const RemeshResult kept = remesh(input, options);
  EXPECT_TRUE(kept.report.ok()) << errors_of(kept.report);
  EXPECT_FALSE(kept.report.output.topology.is_closed);
  EXPECT_EQ(kept.report.output.topology.euler_characteristic, 1);
  ASSERT_TRUE(kept.report.output.distance.has_value());
  options.surfmesh.unsmoothed_boundary_curves = false;
  const RemeshResult rounded = remesh(input, options);
  ASSERT_TRUE(rounded.report.output.distance.has_value());
  EXPECT_LT(kept.report.output.distance->hausdorff, 0.3 * mean_edge);
  EXPECT_GT(rounded.report.output.distance->hausdorff, 0.45 * mean_edge);
}

// A CAD-like roof: two planes meeting at a straight 40 deg ridge (below the 80 deg crease
// angle), turned so that no coordinate lies on a lattice (not taken for marching cubes). The
// ridge is a sharp crease (SegmentOptions::sharp_crease_angle_deg): a feature curve
// discretised from its input polyline, whose nodes never move, so every output node near the
// ridge lies on it, and the two planar patches are fitted exactly (their fits see no faces
// across the ridge): the output is within 1e-9 of the input; the input is within 5% of a mean
// edge of the output (the square's own corners are not segmentation corners: the boundary loop
// is resampled there). Without sharp creases the ridge is inside one patch and its fit rounds
// it off by more than a tenth of a mean edge.
TEST(Pipeline, SharpCreaseNodesStayOnTheRidge) {
  constexpr int kCells = 24;
  const double tan_tilt = std::tan(20.0 * std::numbers::pi / 180.0);
  TriangleSoup soup = test::grid_patch(kCells, kCells);
  const Eigen::Matrix3d turn = (Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(0.3, Eigen::Vector3d(1.0, 2.0, 0.5).normalized()))
                                   .toRotationMatrix();
  for (auto& p : soup.points) {
    p.z() = -std::abs(p.x() - 0.5) * tan_tilt;
    p = turn * p;
  }
  const Eigen::Vector3d ridge_point = turn * Eigen::Vector3d(0.5, 0.0, 0.0);
  const Eigen::Vector3d ridge_direction = turn * Eigen::Vector3d::UnitY();
  const TriMesh input = to_trimesh(soup);
  const RemeshResult r = remesh(input, fast_options());
  EXPECT_TRUE(r.report.ok()) << errors_of(r.report);
  EXPECT_EQ(r.report.n_patches, 2u);
  EXPECT_EQ(r.report.n_crease_edges, static_cast<std::size_t>(kCells));
  ASSERT_TRUE(r.report.output.distance.has_value());
  EXPECT_LT(r.report.output.distance->mesh_to_reference_max, 1e-9);
  const double mean_edge = 1.0 / kCells;  // (the diagonals are longer: a bound on the safe side)
  EXPECT_LT(r.report.output.distance->hausdorff, 0.05 * mean_edge);
  // The output nodes within a tenth of the target size of the ridge line lie on it.
  int n_on_ridge = 0;
  for (const auto v : r.mesh.vertices()) {
    const Eigen::Vector3d p = to_eigen(r.mesh.point(v)) - ridge_point;
    const double off = (p - p.dot(ridge_direction) * ridge_direction).norm();
    if (off > 0.1 * r.report.target_size) continue;
    EXPECT_LT(off, 1e-9);
    ++n_on_ridge;
  }
  EXPECT_GE(n_on_ridge, static_cast<int>(0.5 / r.report.target_size));
  RemeshOptions off = fast_options();
  off.segment.sharp_crease_angle_deg = 0.0;
  const RemeshResult rounded = remesh(input, off);
  ASSERT_TRUE(rounded.report.output.distance.has_value());
  EXPECT_EQ(rounded.report.n_crease_edges, 0u);
  EXPECT_GT(rounded.report.output.distance->hausdorff, 0.1 * mean_edge);
}

TEST(Pipeline, LevelSetTorus) {
  // Resolution 64, the issue's smallest: at 40 cells the tube (minor radius about 5 cells)
  // is too thin for 1.5 mean edges and the obtuse share reaches 1%.
  const SceneInput in = scene_input("torus", 64, SampleMode::LevelSet);
  const RemeshResult r = remesh(in.mesh, fast_options());
  expect_contract_and_quality(r, in, 0);
  expect_min_angle_away_from_features(r);
  const DistanceSummary before = truth_error(in.mesh, in.scene), after = truth_error(r.mesh, in.scene);
  EXPECT_LE(after.mean, before.mean + 0.05 * in.voxel);
  EXPECT_LE(after.max, before.max + 0.05 * in.voxel);
  // Not asserted (not met yet, reported): volume change < 0.5%.
}

// The DRAM cell (box edges, creases, corners close together) at a small resolution: the
// contract and issue 5's 25 deg away from features. Not asserted (not met at 48 cells):
// the Hausdorff bound, obtuse share and volume change (the cell is 3 voxels thick there).
TEST(Pipeline, LevelSetDramCellMinAngleAwayFromFeatures) {
  const SceneInput in = scene_input("dram", 48, SampleMode::LevelSet);
  RemeshOptions options = fast_options();
  options.compute_distances = false;  // not asserted here; most of the run's time
  const RemeshResult r = remesh(in.mesh, options);
  expect_closed_clean(r, static_cast<long>(in.mesh.n_vertices()) - static_cast<long>(in.mesh.n_edges()) +
                             static_cast<long>(in.mesh.n_faces()));
  EXPECT_GT(r.report.stitch.n_collapses, 0u);
  expect_min_angle_away_from_features(r);
  // A marching-cubes surface: no feature sizing, although its crease-bounded strips (voxel
  // steps) hold more than the 1% of the area that would apply it to another input (DRAM 64:
  // 2.1%, docs/surfmesh.md "Feature sizing by default").
  EXPECT_FALSE(r.report.feature_sizing_applied);
  EXPECT_NE(to_json(r.report).find("\"feature_sizing_applied\": false"), std::string::npos);
}

TEST(Pipeline, ReportCountsTimesAndJson) {
  const SceneInput in = scene_input("sphere", 24, SampleMode::LevelSet);
  RemeshOptions options = fast_options();
  std::set<std::string> stages;
  options.progress = [&](std::string_view stage, double) {
    stages.insert(std::string(stage));
    return true;
  };
  const RemeshResult r = remesh(in.mesh, options);
  const RemeshReport& rep = r.report;
  EXPECT_EQ(rep.n_input_faces, in.mesh.n_faces());
  EXPECT_EQ(rep.n_triangles, r.mesh.n_faces());
  EXPECT_EQ(rep.patches.size(), rep.n_patches);
  EXPECT_GT(rep.n_patches, 1u);
  // Every output vertex is a node of the surface mesh or an obtuse split's new node.
  EXPECT_GE(rep.n_nodes + rep.stitch.n_obtuse_splits, r.mesh.n_vertices());
  EXPECT_GT(rep.target_size, 0.0);
  EXPECT_GE(rep.seconds_total, rep.seconds_segment + rep.seconds_surfmesh + rep.seconds_stitch);
  for (const char* stage : {"segment", "stitch: verify", "distance"}) EXPECT_TRUE(stages.count(stage)) << stage;
  const std::string json = to_json(rep);
  EXPECT_EQ(json.front(), '{');
  EXPECT_EQ(json.back(), '}');
  EXPECT_NE(json.find("\"ok\": " + std::string(rep.ok() ? "true" : "false")), std::string::npos);
  EXPECT_NE(json.find("\"hausdorff\""), std::string::npos);
  EXPECT_NE(json.find("\"errors\": ["), std::string::npos);
  EXPECT_NE(to_summary(rep).find("alpha mean"), std::string::npos);
  EXPECT_NE(json.find("\"min_angle_away_from_features_deg\""), std::string::npos);
  EXPECT_NE(json.find("\"collapses\": " + std::to_string(rep.stitch.n_collapses)), std::string::npos);
  // A smooth level-set sphere has no creases; a cube has its 12 edges (the diagonals are flat).
  EXPECT_EQ(rep.n_crease_edges, 0u);
  EXPECT_NE(json.find("\"crease_edges\": 0"), std::string::npos);
  EXPECT_EQ(remesh(to_trimesh(test::cube()), options).report.n_crease_edges, 12u);
  EXPECT_NE(to_summary(rep).find("away from features"), std::string::npos);
  // Without distances the report has none and takes no distance time.
  options.compute_distances = false;
  EXPECT_FALSE(remesh(in.mesh, options).report.output.distance.has_value());
}

TEST(Pipeline, CancelFromAnyStage) {
  const SceneInput in = scene_input("sphere", 16, SampleMode::LevelSet);
  for (const std::string stop : {"segment", "surfmesh", "stitch", "distance"}) {
    RemeshOptions options = fast_options();
    options.progress = [stop](std::string_view stage, double) { return stage.substr(0, stop.size()) != stop; };
    EXPECT_THROW((void)remesh(in.mesh, options), Cancelled) << stop;
  }
}

// Issue 6 compares at equal vertex count: where the decimater stops above ours, nurbsfront
// reruns at its count. A 40% finer count is reached within the tolerance, by a finer size.
TEST(Pipeline, RemeshToVertexCount) {
  const SceneInput in = scene_input("sphere", 16, SampleMode::LevelSet);
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  const RemeshResult first = remesh(in.mesh, options);
  const std::size_t target = first.mesh.n_vertices() * 7 / 5;
  const RemeshResult r = remesh_to_vertex_count(in.mesh, target, options, 0.02, 4);
  EXPECT_TRUE(r.report.ok());
  EXPECT_NEAR(double(r.mesh.n_vertices()), double(target), 0.02 * double(target));
  EXPECT_LT(r.report.target_size, first.report.target_size);
  // One run when the first size already gives the count.
  const RemeshResult same = remesh_to_vertex_count(in.mesh, first.mesh.n_vertices(), options, 0.0, 1);
  EXPECT_EQ(same.mesh.n_vertices(), first.mesh.n_vertices());
  EXPECT_THROW((void)remesh_to_vertex_count(in.mesh, 3, options), InvalidInput);
  EXPECT_THROW((void)remesh_to_vertex_count(in.mesh, target, options, 1.0), InvalidInput);
  EXPECT_THROW((void)remesh_to_vertex_count(in.mesh, target, options, 0.01, 0), InvalidInput);
  options.surfmesh.sizing.callback = [](const Eigen::Vector3d&) { return 0.1; };
  EXPECT_THROW((void)remesh_to_vertex_count(in.mesh, target, options), InvalidInput);
}

TEST(Pipeline, BadInputIsNamed) {
  auto expect_invalid = [](const TriMesh& mesh, const std::string& word) {
    try {
      (void)remesh(mesh);
      ADD_FAILURE() << "no exception, expected one naming " << word;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  expect_invalid(TriMesh{}, "no faces");
  // Two triangles touching at one vertex: OpenMesh holds it, the pipeline refuses it.
  TriMesh bowtie;
  const auto o = bowtie.add_vertex({0, 0, 0});
  const auto a = bowtie.add_vertex({1, 0, 0}), b = bowtie.add_vertex({0, 1, 0});
  const auto c = bowtie.add_vertex({-1, 0, 0}), d = bowtie.add_vertex({0, -1, 0});
  bowtie.add_face(o, a, b);
  bowtie.add_face(o, c, d);
  expect_invalid(bowtie, "non-manifold");
  // The input checks count on the run's threads: the same counts for any thread count.
  for (const unsigned threads : {1u, 3u}) {
    RemeshOptions options;
    options.set_threads(threads);
    try {
      (void)remesh(bowtie, options);
      ADD_FAILURE() << "no exception";
    } catch (const InvalidInput& e) {
      EXPECT_STREQ(e.what(), "remesh: the input mesh has 1 non-manifold vertices (several face fans meet at one vertex)");
    }
  }
  // A triangle of exactly zero area has no normal (issue 6: it used to lose half the cube).
  expect_invalid(to_trimesh(test::needle_cube()), "zero area");
  SceneInput in = scene_input("sphere", 12, SampleMode::LevelSet);
  in.mesh.set_point(TriMesh::VertexHandle(3), {std::nan(""), 0, 0});
  expect_invalid(in.mesh, "non-finite");
  RemeshOptions bad;
  bad.segment.max_slope_deg = 95.0;
  EXPECT_THROW((void)remesh(scene_input("sphere", 12, SampleMode::LevelSet).mesh, bad), InvalidInput);
  RemeshOptions negative_rounds;
  negative_rounds.crossing_repair_rounds = -1;
  EXPECT_THROW((void)remesh(scene_input("sphere", 12, SampleMode::LevelSet).mesh, negative_rounds), InvalidInput);
}

TEST(Pipeline, OccupancySphere) {
  const SceneInput in = scene_input("sphere", 64, SampleMode::Occupancy);
  const RemeshResult r = remesh(in.mesh, fast_options());
  expect_contract_and_quality(r, in, 2);
  EXPECT_LT(volume_change(r), 0.005);
  const DistanceSummary before = truth_error(in.mesh, in.scene), after = truth_error(r.mesh, in.scene);
  EXPECT_LT(after.mean, before.mean / 2.0);
  // Not asserted (not met yet, reported): mean at most a third of the input's and max
  // under 0.25 voxel. Corners are input vertices and never move, so they keep the
  // terraces' error (up to 0.5 voxel).
}

// Issue 5's fidelity bounds end to end: with the band fit (the grid of the cells as
// CellGrid) the remeshed occupancy sphere is within a third of the input's mean error of
// the analytic sphere and under a quarter voxel everywhere, after stitching and its
// cross-border optimisation, with the whole contract met.
TEST(Pipeline, OccupancySphereBandFit) {
  const SceneInput in = scene_input("sphere", 48, SampleMode::Occupancy);
  const Scene& scene = in.scene;
  RemeshOptions options = fast_options();
  options.surfmesh.cell_grid = in.cells;
  options.surfmesh.cell_grid.enabled = true;
  const RemeshResult r = remesh(in.mesh, options);
  expect_contract_and_quality(r, in, 2);
  EXPECT_LT(volume_change(r), 0.005);
  const DistanceSummary before = dense_truth_error(in.mesh, scene), after = dense_truth_error(r.mesh, scene);
  EXPECT_LE(after.mean, before.mean / 3.0) << "input mean " << before.mean / in.voxel << " voxel";
  EXPECT_LT(after.max, 0.25 * in.voxel);
  std::printf("occupancy sphere 48, band fit: truth error mean %.3f max %.3f voxel (input %.3f / %.3f), alpha mean %.3f\n",
              after.mean / in.voxel, after.max / in.voxel, before.mean / in.voxel, before.max / in.voxel,
              r.report.output.quality.alpha_mean);
}

// The fidelity moves with the distance report: remesh() builds the input's soup and tree once
// and shares them between the stitch and the distance pass. The mesh is the one the stitch
// makes with its own tree (the run without the report), the report the one mesh_distance()
// gives on the output.
TEST(PipelineSlow, FidelityMovesShareTheInputTreeWithTheDistancePass) {
  const TriMesh input = read_mesh(test::test_data("io/brainImageSmooth.vtk"));
  RemeshOptions options;
  options.stitch.fidelity_distance_edges = 0.25;
  const RemeshResult shared = remesh(input, options);
  options.compute_distances = false;
  const RemeshResult own = remesh(input, options);
  ASSERT_TRUE(shared.report.ok());
  EXPECT_GT(shared.report.stitch.n_fidelity_moves, 10u);
  ASSERT_EQ(shared.mesh.n_vertices(), own.mesh.n_vertices());
  ASSERT_EQ(shared.mesh.n_faces(), own.mesh.n_faces());
  for (const auto v : own.mesh.vertices()) EXPECT_EQ(shared.mesh.point(v), own.mesh.point(v));
  for (const auto f : own.mesh.faces()) {
    auto a = own.mesh.cfv_iter(f);
    auto b = shared.mesh.cfv_iter(shared.mesh.face_handle(f.idx()));
    for (int k = 0; k < 3; ++k, ++a, ++b) EXPECT_EQ(a->idx(), b->idx());
  }
  ASSERT_TRUE(shared.report.output.distance.has_value());
  const DistanceReport want = mesh_distance(to_soup(shared.mesh), to_soup(input), options.distance);
  EXPECT_EQ(shared.report.output.distance->hausdorff, want.hausdorff);
  EXPECT_EQ(shared.report.output.distance->mean, want.mean);
  EXPECT_EQ(shared.report.output.distance->relative_volume_change, want.relative_volume_change);
}

// Issue 5's bounds on the occupancy torus at 48 cells (tube radius 6.2 cells, the tightest
// curvature of the occupancy scenes), end to end as the tool runs it: the mean distance to the
// analytic torus at most a third of the marching-cubes input's and the largest under a quarter
// voxel, each at the vertices, the triangle centroids and the dense samples. The band fit also
// takes the volume towards the truth's (the terraced input is 1% below it). With
// CellGrid::curved_smoothing 0.375 the centroids' mean was 1 / 2.88 of the input's and a node
// 0.29 voxel out (docs/surfmesh.md, "Torus at 48 cells").
TEST(PipelineSlow, OccupancyTorus48BandFitWithinIssueBounds) {
  const SceneInput in = scene_input("torus", 48, SampleMode::Occupancy);
  RemeshOptions options = fast_options();
  options.surfmesh.cell_grid = in.cells;
  options.surfmesh.cell_grid.enabled = true;
  const RemeshResult r = remesh(in.mesh, options);
  expect_contract_and_quality(r, in, 0);
  expect_min_angle_away_from_features(r);
  const TorusScene& torus = std::get<TorusScene>(in.scene);
  const double truth = 2.0 * std::numbers::pi * std::numbers::pi * torus.major_radius * torus.minor_radius * torus.minor_radius;
  const TriangleSoup input = to_soup(in.mesh), output = to_soup(r.mesh);
  EXPECT_LT(std::abs(enclosed_volume(output) - truth), std::abs(enclosed_volume(input) - truth));
  const SceneDistance before = distance_to_scene(input, in.scene, 4), after = distance_to_scene(output, in.scene, 4);
  const auto check = [&](const char* what, const DistanceSummary& b, const DistanceSummary& a) {
    EXPECT_LE(a.mean, b.mean / 3.0) << what << ": input mean " << b.mean / in.voxel << " voxel";
    EXPECT_LT(a.max, 0.25 * in.voxel) << what;
    std::printf("occupancy torus 48, %s: truth error mean %.4f max %.3f voxel (input %.4f / %.3f, ratio %.2f)\n", what,
                a.mean / in.voxel, a.max / in.voxel, b.mean / in.voxel, b.max / in.voxel, b.mean / a.mean);
  };
  check("vertices", before.vertices, after.vertices);
  check("centroids", before.centroids, after.centroids);
  check("dense", before.dense, after.dense);
}

// The occupancy DRAM cell with the band fit: its bevelled box edges inside patches were rounded
// off by the band fit (Hausdorff 1.18 voxel); such patches now get the plain fit
// (CellGrid::plain_fit_miss_cells).
TEST(PipelineSlow, OccupancyDramCell128WithinOneVoxel) {
  const SceneInput in = scene_input("dram", 128, SampleMode::Occupancy);
  RemeshOptions options = fast_options();
  options.surfmesh.cell_grid = in.cells;
  options.surfmesh.cell_grid.enabled = true;
  const RemeshResult r = remesh(in.mesh, options);
  expect_contract_and_quality(r, in, -18);  // Hausdorff to the input at most one voxel
  EXPECT_LT(volume_change(r), 0.005);
  expect_min_angle_away_from_features(r);
}

// CGAL's rotor (600 vertices, genus 1): a thin disc whose faces are fans of long input
// triangles, so the fits of its small patches have no data inside and bulge by more than
// the disc is thick; the two sides' triangles crossed in 32 pairs in the assembled mesh
// (before the optimisation). Stitch moves the nodes of crossing triangles onto their
// patches' input faces (settle_intersections): no pair is left, the topology is kept.
TEST(Pipeline, ThinDiscCrossingsSettledOntoInput) {
  const TriMesh mesh = prepare_mesh(read_soup(test::test_data("meshes/rotor.off"))).mesh;
  // The rotor's long fan faces, sampled at their corners only, give fits that cross; the
  // samples inside large faces (on by default, next test) avoid that before settle, and so
  // does the bound on the nodes of polygon inputs (polygon_node_offset_edges: no crossing left).
  RemeshOptions options = fast_options();
  options.surfmesh.fit.large_face_edges = 0.0;
  options.surfmesh.fit.flat_face_edges = 0.0;
  options.surfmesh.polygon_node_offset_edges = 0.0;
  const RemeshResult r = remesh(mesh, options);
  const RemeshReport& rep = r.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  const TopologyReport& t = rep.output.topology;
  ASSERT_TRUE(t.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
  EXPECT_GT(rep.stitch.n_settled_nodes, 0u);
  EXPECT_TRUE(t.is_closed);
  EXPECT_TRUE(t.is_manifold);
  EXPECT_TRUE(t.is_consistently_oriented);
  EXPECT_EQ(t.n_components, 1u);
  EXPECT_EQ(t.euler_characteristic, 0);
  EXPECT_EQ(t.n_degenerate_faces, 0u);
  ASSERT_TRUE(rep.output.distance.has_value());
  EXPECT_LE(rep.output.distance->hausdorff, rep.input_mean_edge);
}

// CGAL's cheese (17786 faces, genus 133): thin walls between holes, where patches of a few
// input faces meet in corner clusters; the assembled mesh crosses itself there, and moves
// and flips leave 5 pairs (main df5b51c). Stitch collapses short edges of the crossing
// triangles (settle_intersections): no pair is left, the topology is kept, and the
// provenance arrays follow the collapses. Slow label: 1.2 s in RelWithDebInfo, but 54 s CPU
// under ASan + UBSan in Debug (passed there on 2026-11-26).
TEST(PipelineSlow, CornerClusterCrossingsCollapsed) {
  const TriMesh mesh = prepare_mesh(read_soup(test::test_data("meshes/cheese.off"))).mesh;
  RemeshOptions options = fast_options();
  options.compute_distances = false;  // the crossings and the topology are the point (ASan time)
  // Without the samples inside large faces (main df5b51c's fit), where cheese's corner
  // clusters cross after moves and flips; with them there is nothing left to collapse.
  options.surfmesh.fit.large_face_edges = 0.0;
  options.surfmesh.fit.flat_face_edges = 0.0;
  options.surfmesh.polygon_node_offset_edges = 0.0;  // the bound on polygon inputs' nodes avoids them too
  const RemeshResult r = remesh(mesh, options);
  const RemeshReport& rep = r.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  EXPECT_GT(rep.stitch.n_settled_collapses, 0u);
  const TopologyReport& t = rep.output.topology;
  ASSERT_TRUE(t.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
  EXPECT_EQ(count_self_intersections(to_soup(r.mesh)), 0u);
  EXPECT_TRUE(t.is_closed);
  EXPECT_TRUE(t.is_manifold);
  EXPECT_TRUE(t.is_consistently_oriented);
  EXPECT_EQ(t.n_components, 1u);
  EXPECT_EQ(t.euler_characteristic, -264);
  EXPECT_EQ(t.n_degenerate_faces, 0u);
  EXPECT_EQ(t.n_duplicate_faces, 0u);
  EXPECT_EQ(r.face_patch.size(), r.mesh.n_faces());
  // Every node of the surface mesh is an output vertex, unused, or merged by a collapse;
  // the obtuse splits add vertices.
  const StitchReport& s = rep.stitch;
  EXPECT_EQ(r.mesh.n_vertices() + s.n_unused_nodes + s.n_collapses + s.n_settled_collapses + s.n_angle_collapses +
                s.n_obtuse_collapses,
            s.n_input_nodes + s.n_obtuse_splits);
}

// CGAL's cheese: its holes' walls are split into hundreds of patches of fewer than 40 long
// faces, whose fits (their own vertices only) are free between the vertices; the nodes of
// such patches sat up to 0.7 mean edges into the holes and the solid gained 4.3% volume
// (main 2363222). Held within small_patch_node_offset_edges (0.02) of their faces: 1.9%
// measured, still above issue 5's 0.5% (docs/surfmesh.md "Small patches keep their nodes on
// their faces"). The bound here is the measured gain with a margin, and the topology kept.
TEST(PipelineSlow, CheeseSmallPatchesKeepTheirVolume) {
  const TriMesh mesh = prepare_mesh(read_soup(test::test_data("meshes/cheese.off"))).mesh;
  RemeshOptions options = fast_options();
  options.compute_distances = false;  // the volume is the point (ASan time)
  const RemeshResult r = remesh(mesh, options);
  const RemeshReport& rep = r.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  const TopologyReport& t = rep.output.topology;
  EXPECT_TRUE(t.is_closed);
  EXPECT_EQ(t.euler_characteristic, -264);
  const double volume_in = enclosed_volume(to_soup(mesh));
  EXPECT_LT(std::abs(enclosed_volume(to_soup(r.mesh)) - volume_in), 0.025 * volume_in);
}

// The same rotor with its large faces sampled inside (the default): no crossings to settle.
TEST(Pipeline, ThinDiscLargeFacesSampledNoCrossings) {
  const TriMesh mesh = prepare_mesh(read_soup(test::test_data("meshes/rotor.off"))).mesh;
  const RemeshResult r = remesh(mesh, fast_options());
  const RemeshReport& rep = r.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  const TopologyReport& t = rep.output.topology;
  ASSERT_TRUE(t.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
  EXPECT_EQ(rep.stitch.n_settled_nodes + rep.stitch.n_settled_flips + rep.stitch.n_settled_collapses, 0u);  // nothing crossed before settle
  EXPECT_TRUE(t.is_closed);
  EXPECT_EQ(t.euler_characteristic, 0);
  ASSERT_TRUE(rep.output.distance.has_value());
  EXPECT_LE(rep.output.distance->hausdorff, rep.input_mean_edge);
}

// The rotor's flat end faces are rings of input faces 1.8 mean edges long between two circles
// (no vertex inside the ring), beside a fillet in the same patch: sampled at their corners
// only, the fit bulged out over the ring by up to 0.43 mean edges and the volume grew by 4.2%
// (main fa97a30). Sampled inside as flat faces (PatchFitOptions::flat_face_edges), the
// output stays within a quarter of a mean edge of the ends' planes (measured 0.16: the fit still
// overshoots beside the fillet, R = half a mean edge) and the volume within 1.5% (measured -0.76%).
TEST(Pipeline, ThinDiscFlatRingsSampledKeepVolume) {
  const TriMesh mesh = prepare_mesh(read_soup(test::test_data("meshes/rotor.off"))).mesh;
  double in_lo = 0.0, in_hi = 0.0;
  for (auto v : mesh.vertices()) {
    in_lo = std::min(in_lo, static_cast<double>(mesh.point(v)[0]));
    in_hi = std::max(in_hi, static_cast<double>(mesh.point(v)[0]));
  }
  RemeshOptions options = fast_options();
  options.compute_distances = false;  // the planes and the volume are the point (ASan time)
  const RemeshResult r = remesh(mesh, options);
  const RemeshReport& rep = r.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  double lo = 0.0, hi = 0.0;
  for (auto v : r.mesh.vertices()) {
    lo = std::min(lo, static_cast<double>(r.mesh.point(v)[0]));
    hi = std::max(hi, static_cast<double>(r.mesh.point(v)[0]));
  }
  EXPECT_GE(lo, in_lo - 0.25 * rep.input_mean_edge);
  EXPECT_LE(hi, in_hi + 0.25 * rep.input_mean_edge);
  const double volume_in = enclosed_volume(to_soup(mesh));
  EXPECT_LT(std::abs(enclosed_volume(to_soup(r.mesh)) - volume_in), 0.015 * volume_in);
}

// A gear-like prism (issue 5 volume; docs/stitch.md "Volume: measured along the patch
// axis"): radius 1 + 0.15 cos(6 t) sampled at 48 points, height 0.5, one row of long side
// faces and fan caps. Its volume is the polygon's shoelace area times the height. The side
// splits into small slope-bounded patches (convex lobes, concave roots) whose output
// triangles, 1.5 input edges long, cut the lobes and bridge the roots: -1.30% without the
// volume compensation, -0.33% with it (remesh --threads 1 --obtuse-split-rounds 0; -0.43%
// before the exact quadrature and the cap's hand-over, -0.47% with the quadrature alone:
// the cap cut the lobes' outward moves only, docs/stitch.md "The volume compensation's cap
// hands on the rest").
TriangleSoup gear_prism() {
  constexpr int kPoints = 48;
  constexpr double kHeight = 0.5;
  TriangleSoup soup;
  for (int level = 0; level < 2; ++level) {
    for (int i = 0; i < kPoints; ++i) {
      const double t = 2.0 * std::numbers::pi * i / kPoints;
      const double r = 1.0 + 0.15 * std::cos(6.0 * t);
      soup.points.emplace_back(r * std::cos(t), r * std::sin(t), level * kHeight);
    }
  }
  soup.points.emplace_back(0.0, 0.0, 0.0);
  soup.points.emplace_back(0.0, 0.0, kHeight);
  const auto n = static_cast<std::uint32_t>(kPoints);
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t j = (i + 1) % n;
    soup.triangles.push_back({i, j, n + j});
    soup.triangles.push_back({i, n + j, n + i});
    soup.triangles.push_back({2 * n, j, i});
    soup.triangles.push_back({2 * n + 1, n + i, n + j});
  }
  return soup;
}

TEST(Pipeline, GearPrismKeepsItsVolume) {
  const TriangleSoup soup = gear_prism();
  double shoelace = 0.0;
  for (std::size_t i = 0; i < 48; ++i) {
    const Eigen::Vector3d& a = soup.points[i];
    const Eigen::Vector3d& b = soup.points[(i + 1) % 48];
    shoelace += 0.5 * (a.x() * b.y() - b.x() * a.y());
  }
  const double exact = shoelace * 0.5;
  const TriMesh mesh = prepare_mesh(soup).mesh;
  ASSERT_NEAR(enclosed_volume(to_soup(mesh)), exact, 1e-12 * exact);
  RemeshOptions options = fast_options();
  options.compute_distances = false;  // the volume is the point
  // The obtuse splits come after the compensation and put their nodes on the fits (their
  // relaxed nodes too): on this prism they give back part of it (0.64% with 4 splits; 1.77%
  // without the compensation). The test is of the compensation.
  options.stitch.obtuse_split_rounds = 0;
  const RemeshResult r = remesh(mesh, options);
  expect_closed_clean(r, 2);
  EXPECT_GT(r.report.stitch.n_volume_compensation_moves, 0u);
  const double with = std::abs(enclosed_volume(to_soup(r.mesh)) - exact) / exact;
  options.stitch.volume_compensation = 0.0;
  const RemeshResult off = remesh(mesh, options);
  EXPECT_EQ(off.report.stitch.n_volume_compensation_moves, 0u);
  const double without = std::abs(enclosed_volume(to_soup(off.mesh)) - exact) / exact;
  EXPECT_LT(with, 0.005);  // issue 5's bound
  EXPECT_LT(with, 0.5 * without);
}

// A coarse tube (issue 5 volume; docs/stitch.md "The volume compensation's cap hands on the
// rest"): a torus of 40 x 10 quads, radii 1 and 0.3, whose output triangles are chords of
// the tube's curved patches, larger ones than the 100-input-face patches the compensation
// once left out. Closed, genus 1, no crossings; the compensation takes the volume within
// issue 5's 0.5% and under 0.3 of the loss without it (measured -0.34% against -1.52%;
// main 8ed1cb8's lattice quadrature and 100-face gate left -0.97%).
TEST(Pipeline, CoarseTubeKeepsItsVolume) {
  const TriMesh mesh = prepare_mesh(test::torus(40, 10, 1.0, 0.3)).mesh;
  const double volume_in = enclosed_volume(to_soup(mesh));
  RemeshOptions options = fast_options();
  options.compute_distances = false;  // the volume is the point
  double change[2] = {0.0, 0.0};
  for (const int with : {1, 0}) {
    options.stitch.volume_compensation = with ? 1.0 : 0.0;
    const RemeshResult r = remesh(mesh, options);
    expect_closed_clean(r, 0);
    change[with] = (enclosed_volume(to_soup(r.mesh)) - volume_in) / volume_in;
  }
  EXPECT_LT(std::abs(change[1]), 0.005) << "issue 5's bound";
  EXPECT_LT(std::abs(change[1]), 0.3 * std::abs(change[0]));
}

// A marching-cubes surface (issue 5 volume; docs/stitch.md "Volume on marching-cubes
// surfaces"): the volume compensation acts on it too (until session 14 the lattice-edge gate
// kept it off). The level-set torus at 16 cells, coarse enough for the chords to cost
// volume (+1.72% without the compensation, +0.11% with; remesh --threads 1): with it its nodes
// move, the volume stays within issue 5's 0.5% of
// the input's and nearer it than without, no triangle away from features is below 25 deg
// (the compensation's per-triangle angle floor) and the output is no further from the
// analytic torus than without, beyond 0.02 voxel.
TEST(Pipeline, MarchingCubesTorusKeepsItsVolume) {
  const SceneInput in = scene_input("torus", 16, SampleMode::LevelSet);
  RemeshOptions options = fast_options();
  const RemeshResult with = remesh(in.mesh, options);
  options.stitch.volume_compensation = 0.0;
  const RemeshResult without = remesh(in.mesh, options);
  for (const RemeshResult* r : {&with, &without}) {
    EXPECT_TRUE(r->report.ok()) << errors_of(r->report);
    const TopologyReport& t = r->report.output.topology;
    EXPECT_TRUE(t.is_closed);
    EXPECT_TRUE(t.is_manifold);
    EXPECT_EQ(t.euler_characteristic, 0);
    ASSERT_TRUE(t.n_self_intersecting_pairs.has_value());
    EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
  }
  EXPECT_GT(with.report.stitch.n_volume_compensation_moves, 0u);
  EXPECT_EQ(without.report.stitch.n_volume_compensation_moves, 0u);
  expect_min_angle_away_from_features(with);
  EXPECT_LT(volume_change(with), 0.005) << "issue 5's bound";
  EXPECT_LT(volume_change(with), volume_change(without));
  const DistanceSummary truth_with = truth_error(with.mesh, in.scene), truth_without = truth_error(without.mesh, in.scene);
  EXPECT_LE(truth_with.mean, truth_without.mean + 0.02 * in.voxel);
  std::printf("torus 16 volume change with / without compensation %.5f / %.5f, truth mean %.4f / %.4f max %.4f / %.4f voxel, min away %.2f, moves %zu\n",
              volume_change(with), volume_change(without), truth_with.mean / in.voxel, truth_without.mean / in.voxel,
              truth_with.max / in.voxel, truth_without.max / in.voxel, with.report.stitch.min_angle_away_from_features_deg,
              with.report.stitch.n_volume_compensation_moves);
}

// CGAL's pinion (issue 5 volume): the triangles between the teeth's border nodes bridge the
// concave roots and the output gained +1.65% without the volume compensation; with it the
// change is within issue 5's bound (the current figure: docs/benchmarks/corpus.md; the
// method: docs/stitch.md "Volume: measured along the patch axis" and session 13's cap
// hand-over). Closed, genus 1, no crossings either way.
TEST(Pipeline, PinionRootsKeepTheirVolume) {
  const TriMesh mesh = prepare_mesh(read_soup(test::test_data("meshes/pinion.off"))).mesh;
  const double volume_in = enclosed_volume(to_soup(mesh));
  RemeshOptions options = fast_options();
  options.compute_distances = false;  // the volume is the point
  for (const double strength : {1.0, 0.0}) {
    options.stitch.volume_compensation = strength;
    const RemeshResult r = remesh(mesh, options);
    expect_closed_clean(r, 0);
    const double change = (enclosed_volume(to_soup(r.mesh)) - volume_in) / volume_in;
    if (strength > 0.0) {
      EXPECT_LT(std::abs(change), 0.005) << "issue 5's bound";
    } else {
      EXPECT_GT(change, 0.01) << "the roots' gain the compensation takes back";
    }
  }
}

// Obtuse triangles in a mesh (an angle above 90 deg, as the quality report counts them).
std::size_t count_obtuse(const TriMesh& mesh) {
  std::size_t n = 0;
  for (const auto f : mesh.faces()) {
    std::array<Eigen::Vector3d, 3> p;
    std::size_t k = 0;
    for (const auto v : mesh.fv_range(f)) p[k++] = to_eigen(mesh.point(v));
    for (std::size_t i = 0; i < 3; ++i) {
      if ((p[(i + 1) % 3] - p[i]).dot(p[(i + 2) % 3] - p[i]) < 0.0) {
        ++n;
        break;
      }
    }
  }
  return n;
}

// CGAL's rotor (issue 5): the volume compensation moves nodes after the obtuse repair, and
// some of its moves made triangles obtuse that the splits then could not remove: 39 obtuse
// triangles with it, 37 without (main 8ed1cb8, 1 thread). The repair's flips and moves once
// more after the compensation (stitch.cpp) leave no more with it than without; the volume
// stays within issue 5's bound.
//
// Session 14: with feature sizing graded at 1.25 (the new default) the rotor's output has 39
// obtuse triangles with the compensation and 38 without (docs/stitch.md "Volume on
// marching-cubes surfaces", the lead's note): the repair sweep's property is tested on the
// sizing it was written for (gradation 1.5). Session 15: refusing the compensation's moves
// that make an obtuse triangle more obtuse gives 38 at 1.25 but costs cheese the 0.5% volume
// bound; not landed (docs/stitch.md "The volume compensation on level sets, session 15").
// Session 21: without the obtuse collapses (on by default since), which come after the
// compensation and its repair sweep and take a different share on each mesh (13 obtuse
// triangles with the compensation, 12 without, with them): the test is of the sweep.
TEST(PipelineSlow, VolumeCompensationAddsNoObtuseTriangles) {
  const TriMesh mesh = prepare_mesh(read_soup(test::test_data("meshes/rotor.off"))).mesh;
  const double volume_in = enclosed_volume(to_soup(mesh));
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  options.surfmesh.sizing.feature_gradation = 1.5;
  options.stitch.obtuse_collapse = false;
  const RemeshResult with = remesh(mesh, options);
  ASSERT_TRUE(with.report.ok()) << errors_of(with.report);
  EXPECT_GT(with.report.stitch.n_volume_compensation_moves, 0u);
  options.stitch.volume_compensation = 0.0;
  const RemeshResult without = remesh(mesh, options);
  ASSERT_TRUE(without.report.ok()) << errors_of(without.report);
  EXPECT_LE(count_obtuse(with.mesh), count_obtuse(without.mesh));
  EXPECT_LT(std::abs(enclosed_volume(to_soup(with.mesh)) - volume_in), 0.01 * volume_in);
}

// The volume compensation's gate (StitchOptions::volume_compensation_skip_within; docs/stitch.md
// "The volume compensation on level sets, session 15"): where the mesh already encloses the
// input's volume within the threshold, nothing is moved (the output is the one without the
// compensation); the gear prism, about 1.3% short without the compensation, is outside
// 0.05% and is brought within issue 5's 0.5%.
TEST(Pipeline, VolumeCompensationSkippedWithinItsThreshold) {
  const TriMesh mesh = prepare_mesh(gear_prism()).mesh;
  const double volume_in = enclosed_volume(to_soup(mesh));
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  options.stitch.obtuse_split_rounds = 0;  // as GearPrismKeepsItsVolume
  options.stitch.volume_compensation = 0.0;
  const RemeshResult off = remesh(mesh, options);
  ASSERT_TRUE(off.report.ok()) << errors_of(off.report);
  const double change_off = std::abs(enclosed_volume(to_soup(off.mesh)) - volume_in) / volume_in;
  ASSERT_GT(change_off, 0.005);
  ASSERT_LT(change_off, 0.05);
  options.stitch.volume_compensation = 1.0;
  options.stitch.volume_compensation_skip_within = 0.05;  // above the prism's change: skipped
  const RemeshResult skipped = remesh(mesh, options);
  ASSERT_TRUE(skipped.report.ok()) << errors_of(skipped.report);
  EXPECT_TRUE(skipped.report.stitch.volume_compensation_skipped);
  EXPECT_EQ(skipped.report.stitch.n_volume_compensation_moves, 0u);
  ASSERT_EQ(skipped.mesh.n_vertices(), off.mesh.n_vertices());
  ASSERT_EQ(skipped.mesh.n_faces(), off.mesh.n_faces());
  for (const auto v : off.mesh.vertices()) {
    ASSERT_EQ(off.mesh.point(v), skipped.mesh.point(v)) << v.idx();
  }
  options.stitch.volume_compensation_skip_within = 0.0005;
  const RemeshResult moved = remesh(mesh, options);
  ASSERT_TRUE(moved.report.ok()) << errors_of(moved.report);
  EXPECT_FALSE(moved.report.stitch.volume_compensation_skipped);
  EXPECT_GT(moved.report.stitch.n_volume_compensation_moves, 0u);
  EXPECT_LT(std::abs(enclosed_volume(to_soup(moved.mesh)) - volume_in) / volume_in, 0.005);
  // The measure runs on the threads: the same moves on one.
  options.set_threads(1);
  const RemeshResult one = remesh(mesh, options);
  EXPECT_EQ(one.report.stitch.n_volume_compensation_moves, moved.report.stitch.n_volume_compensation_moves);
  ASSERT_EQ(one.mesh.n_vertices(), moved.mesh.n_vertices());
  for (const auto v : one.mesh.vertices()) {
    ASSERT_EQ(one.mesh.point(v), moved.mesh.point(v)) << v.idx();
  }
  options.stitch.volume_compensation_skip_within = -0.001;
  EXPECT_THROW(remesh(mesh, options), InvalidInput);
  options.stitch.volume_compensation_skip_within = 0.06;
  EXPECT_THROW(remesh(mesh, options), InvalidInput);
}

// CGAL's blobby (a closed smooth blob, not a marching-cubes surface): the volume compensation
// moves nodes and then keeps the moves only if the enclosed volume gets nearer the input's.
// With 2+ threads the compensation's marching-cubes gate runs on a helper thread; the volume
// check must still run: on blobby it undoes the moves (0 kept); without the check at 2 threads
// the moves stayed and the output differed from the 1-thread one.
TEST(Pipeline, VolumeCompensationSameForAnyThreadCount) {
  const TriMesh mesh = prepare_mesh(read_soup(test::test_data("meshes/blobby.off"))).mesh;
  RemeshOptions options;
  options.compute_distances = false;
  options.set_threads(1);
  const RemeshResult one = remesh(mesh, options);
  options.set_threads(2);
  const RemeshResult two = remesh(mesh, options);
  ASSERT_TRUE(one.report.ok()) << errors_of(one.report);
  ASSERT_TRUE(two.report.ok()) << errors_of(two.report);
  EXPECT_EQ(one.report.stitch.n_volume_compensation_moves, two.report.stitch.n_volume_compensation_moves);
  ASSERT_EQ(one.mesh.n_vertices(), two.mesh.n_vertices());
  ASSERT_EQ(one.mesh.n_faces(), two.mesh.n_faces());
  for (const auto v : one.mesh.vertices()) {
    ASSERT_EQ(one.mesh.point(v), two.mesh.point(two.mesh.vertex_handle(static_cast<unsigned>(v.idx())))) << v.idx();
  }
}

// The volume compensation's measure runs in chunks of 4096 faces on the run's threads
// (session 15), and its sums onto the vertices (normals, areas, edge terms, shares, pools)
// gather each vertex's face terms in face order in chunks of 4096 vertices (session 18): on
// a level-set torus of some 17 000 output faces (several chunks of both, so the threads
// really share the work) the moves are the same points, bit for bit, at 1, 2, 3 and 4
// threads (the reviewer's note: the gear prism's output is one chunk).
TEST(PipelineSlow, VolumeCompensationMeasureSameForAnyThreadCount) {
  const SceneInput in = scene_input("torus", 96, SampleMode::LevelSet);
  RemeshOptions options;
  options.compute_distances = false;
  options.set_threads(1);
  const RemeshResult one = remesh(in.mesh, options);
  ASSERT_TRUE(one.report.ok()) << errors_of(one.report);
  ASSERT_GT(one.mesh.n_faces(), 3u * 4096u);
  ASSERT_GT(one.mesh.n_vertices(), 2u * 4096u);
  EXPECT_GT(one.report.stitch.n_volume_compensation_moves, 0u);
  for (const unsigned threads : {2u, 3u, 4u}) {
    options.set_threads(threads);
    const RemeshResult many = remesh(in.mesh, options);
    ASSERT_TRUE(many.report.ok()) << errors_of(many.report);
    EXPECT_EQ(many.report.stitch.n_volume_compensation_moves, one.report.stitch.n_volume_compensation_moves);
    ASSERT_EQ(many.mesh.n_vertices(), one.mesh.n_vertices());
    for (const auto v : one.mesh.vertices()) {
      ASSERT_EQ(one.mesh.point(v), many.mesh.point(v)) << threads << " threads, vertex " << v.idx();
    }
  }
}

// CGAL's rotor by default (feature sizing, SizingOptions::feature_size, applies: a CAD mesh,
// not a marching-cubes one): its narrow crease-bounded faces (hub walls, blade rims, narrower
// than the uniform 1.5 mean input edges of a mesh of long fan triangles) were single rows of
// triangles of border nodes without it (mean alpha 0.85, 19% obtuse: docs/surfmesh.md
// "Feature sizing"). Sized from their width (2 area / perimeter) they hold well-shaped
// triangles; the surface stays closed, of genus 1 and free of crossings.
TEST(Pipeline, CreaseBoundedNarrowFacesSizedFromTheirWidth) {
  const TriMesh mesh = prepare_mesh(read_soup(test::test_data("meshes/rotor.off"))).mesh;
  RemeshOptions options = fast_options();
  options.compute_distances = false;  // the shapes and the topology are the point (ASan time)
  const RemeshResult r = remesh(mesh, options);
  const RemeshReport& rep = r.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  const TopologyReport& t = rep.output.topology;
  ASSERT_TRUE(t.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
  EXPECT_TRUE(t.is_closed);
  EXPECT_TRUE(t.is_manifold);
  EXPECT_EQ(t.n_components, 1u);
  EXPECT_EQ(t.euler_characteristic, 0);
  const QualityReport& q = rep.output.quality;
  EXPECT_GE(q.alpha_mean, 0.9);
  EXPECT_LE(q.obtuse_fraction, 0.08);
  EXPECT_GE(q.min_angle_deg, 20.0);
  EXPECT_TRUE(rep.feature_sizing_applied);
  EXPECT_NE(to_json(rep).find("\"feature_sizing_applied\": true"), std::string::npos);
}

// A hand-made volume: a slab with two crossing fins one voxel thick on top (their rims and
// ends are strips about one voxel wide: patches narrower than half a target edge). Its
// marching-cubes surface (intensities with a wobble, as in a CT image) passes the lattice gate, so narrow patches join a neighbour
// (RemeshOptions::narrow_patch_merge, docs/segment.md "Narrow patches"): fewer patches, the
// contract and topology kept, no crossing, mean alpha and obtuse share not worse. The same
// surface turned by 30 deg is not taken for marching cubes, and the label image's surface (0/1
// intensities: every vertex at its lattice edge's midpoint) is not merged either.
TriMesh slab_with_fins(bool label_image = false) {
  // A CT-like image: intensities vary a little, so the iso-surface crosses its lattice
  // edges at varying points (not at their midpoints, as a label image's does). (With a
  // wobble of 0.05 or more the fins' rims are no longer narrow patches: no merge.)
  const ScalarGrid grid = test::slab_with_thin_fin(label_image ? 0.0 : 0.02, true);
  MarchingCubesOptions mc;
  mc.iso = 0.5;
  mc.inside_above = true;
  mc.pad = true;
  return prepare_mesh(marching_cubes(grid, mc)).mesh;
}

// A patch merge of the fin slab (`with`, against the run without it): no report error,
// fewer patches, the output closed, manifold, oriented, of Euler characteristic 2, without
// crossings (counted: the runs measure no distances), and no lower mean alpha.
void expect_fewer_patches_closed_no_worse(const RemeshResult& with, const RemeshResult& without) {
  const RemeshReport& rep = with.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  EXPECT_LT(rep.n_patches, without.report.n_patches);
  const TopologyReport& t = rep.output.topology;
  EXPECT_TRUE(t.is_closed && t.is_manifold && t.is_consistently_oriented);
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_EQ(count_self_intersections(to_soup(with.mesh)), 0u);
  EXPECT_GE(rep.output.quality.alpha_mean, without.report.output.quality.alpha_mean);
}

TEST(Pipeline, NarrowFinPatchesJoinANeighbour) {
  const TriMesh mesh = slab_with_fins();
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  const RemeshResult with = remesh(mesh, options);
  options.narrow_patch_merge = 0.0;
  const RemeshResult without = remesh(mesh, options);
  EXPECT_EQ(without.report.n_narrow_merged, 0u);
  const RemeshReport& rep = with.report;
  EXPECT_GE(rep.n_narrow_merged, 1u);
  expect_fewer_patches_closed_no_worse(with, without);
  // No more obtuse triangles (counted: the merged run has fewer triangles, so an equal
  // count is a larger share).
  auto n_obtuse = [](const RemeshResult& r) {
    return std::llround(r.report.output.quality.obtuse_fraction * static_cast<double>(r.mesh.n_faces()));
  };
  EXPECT_LE(n_obtuse(with), n_obtuse(without));
  EXPECT_NE(to_json(rep).find("\"narrow_patches_merged\": " + std::to_string(rep.n_narrow_merged)), std::string::npos);

  TriMesh turned = mesh;
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(std::numbers::pi / 6.0, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  for (const auto v : turned.vertices()) {
    const auto p = turned.point(v);
    const Eigen::Vector3d q = rotation * Eigen::Vector3d(p[0], p[1], p[2]);
    turned.set_point(v, {q.x(), q.y(), q.z()});
  }
  options.narrow_patch_merge = 0.5;
  EXPECT_EQ(remesh(turned, options).report.n_narrow_merged, 0u);
  EXPECT_EQ(remesh(slab_with_fins(true), options).report.n_narrow_merged, 0u);
  options.narrow_patch_merge = -1.0;
  EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
}

// Session 18 (issue 5, docs/segment.md "Fin strips, session 18"): the fin slab's rims (with
// the narrow merge off, all of them left) join a neighbour when RemeshOptions::fin_strip_width
// asks, their own faces exempt from the slope bounds: fewer patches, the output still closed,
// manifold, of Euler characteristic 2, without crossings, no lower mean alpha; a bound below
// their width takes none. On by default (0.25) since session 19; not on a label image.
TEST(Pipeline, FinStripsJoinANeighbourWhenAsked) {
  const TriMesh mesh = slab_with_fins();
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  EXPECT_EQ(options.fin_strip_width, 0.25);
  // Without the narrow merge (whose slope bounds take one strip of this slab): every strip
  // left to the fin-strip merge.
  options.narrow_patch_merge = 0.0;
  const RemeshResult without = remesh(mesh, options);
  EXPECT_EQ(without.report.n_narrow_merged, 0u);
  options.fin_strip_width = 1.0;
  const RemeshResult with = remesh(mesh, options);
  const RemeshReport& rep = with.report;
  EXPECT_GT(rep.n_narrow_merged, without.report.n_narrow_merged);
  expect_fewer_patches_closed_no_worse(with, without);
  // (Obtuse triangles are not asserted: on this slab 6 -> 7, see the docs.) The two strips
  // taken are wider than half a target edge: a bound of 0.5 takes none.
  options.fin_strip_width = 0.5;
  EXPECT_EQ(remesh(mesh, options).report.n_narrow_merged, 0u);
  options.fin_strip_width = 1.0;
  // A label image's staircase is left alone (as by the narrow merge).
  EXPECT_EQ(remesh(slab_with_fins(true), options).report.n_narrow_merged, 0u);
  for (const double bad : {-0.1, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    options.fin_strip_width = bad;
    EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
  }
}

// The grids below: the point (x, y, z) turned by 0.5 rad about z and shifted, off any lattice.
void add_turned_point(TriangleSoup& soup, double x, double y, double z) {
  soup.points.emplace_back(std::cos(0.5) * x - std::sin(0.5) * y + 0.123, std::sin(0.5) * x + std::cos(0.5) * y + 0.0456, z);
}

// Two triangles per cell of a grid of rows + 1 rows of points, added row by row, `columns` to a row.
void add_grid_triangles(TriangleSoup& soup, int rows, int columns) {
  const auto m = static_cast<unsigned>(columns);
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i + 1 < columns; ++i) {
      const auto a = static_cast<unsigned>(j * columns + i);
      soup.triangles.push_back({a, a + 1, a + m + 1});
      soup.triangles.push_back({a, a + m + 1, a + m});
    }
}

// A 12 x 12 grid of side 1 (turned, off any lattice) with its middle vertex raised by 0.05:
// with a 25 deg crease angle each of the six faces around it is a patch of one face, bounded
// by creases (a coarse mesh's bends, as on femur.off).
TriMesh grid_with_bump() {
  constexpr int n = 12;
  TriangleSoup soup;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = i / double(n), y = j / double(n), z = (i == n / 2 && j == n / 2) ? 0.6 / n : 0.0;
      add_turned_point(soup, x, y, z);
    }
  add_grid_triangles(soup, n, n + 1);
  return to_trimesh(soup);
}

TEST(Pipeline, TinyPatchesBehindMarginalCreasesJoinANeighbour) {
  const TriMesh mesh = grid_with_bump();
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  options.segment.crease_angle_deg = 25.0;
  const Segmentation seg = segment(mesh, options.segment);
  ASSERT_EQ(seg.patches.size(), 7u);
  ASSERT_EQ(tiny_patches(mesh, seg, 8, options.tiny_patch_max_dihedral_deg).size(), 6u);

  const RemeshResult with = remesh(mesh, options);
  options.tiny_patch_faces = 0;
  const RemeshResult without = remesh(mesh, options);
  EXPECT_EQ(without.report.n_tiny_merged, 0u);
  EXPECT_EQ(without.report.n_patches, 7u);
  const RemeshReport& rep = with.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  EXPECT_EQ(rep.n_tiny_merged, 6u);
  EXPECT_EQ(rep.n_patches, 1u);
  const auto& t = rep.output.topology;
  EXPECT_TRUE(t.is_manifold);
  EXPECT_EQ(t.n_boundary_loops, 1u);
  EXPECT_EQ(t.euler_characteristic, 1);
  // The bump's one-face patches no longer leave obtuse triangles.
  EXPECT_EQ(rep.output.quality.obtuse_fraction, 0.0);
  EXPECT_LE(rep.output.quality.obtuse_fraction, without.report.output.quality.obtuse_fraction);
  EXPECT_GT(rep.output.quality.alpha_mean, without.report.output.quality.alpha_mean);

  // Below the creases' bends (all above the 25 deg crease angle) nothing qualifies.
  options.tiny_patch_faces = 8;
  options.tiny_patch_max_dihedral_deg = 20.0;
  EXPECT_EQ(remesh(mesh, options).report.n_tiny_merged, 0u);
  options.tiny_patch_faces = -1;
  EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
  options.tiny_patch_faces = 8;
  options.tiny_patch_max_dihedral_deg = 181.0;
  EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
}

// A 12 x 12 grid of side 1 (turned, off any lattice) with a pleat across it: the plane steps
// up by 0.004 at x = 1/2 through a strip of faces that leans back by 0.001 (an overhang, as the
// strips folded back between two creases on femur.off), forward by 0.001 at the two boundary
// rows. The strip bends by about 104 deg to both sides (creases) and faces away from both
// (raw normal . z = -0.24): no neighbour's slope bound takes it, and meshed on its own it is a
// hairline patch 0.004 wide.
TriMesh grid_with_pleat() {
  constexpr int n = 12;
  constexpr double kStep = 0.004, kBack = 0.001;
  TriangleSoup soup;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n + 1; ++i) {  // column n/2 + 1 is the strip's top edge
      const double y = j / double(n);
      const bool top = i > n / 2;
      double x = (top ? i - 1 : i) / double(n);
      if (i == n / 2 + 1) x -= (j == 0 || j == n) ? -kBack : kBack;
      const double z = top ? kStep : 0.0;
      add_turned_point(soup, x, y, z);
    }
  add_grid_triangles(soup, n, n + 2);
  return to_trimesh(soup);
}

TEST(Pipeline, HairlinePatchesJoinAWideNeighbour) {
  const TriMesh mesh = grid_with_pleat();
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  const Segmentation seg = segment(mesh, options.segment);
  ASSERT_EQ(seg.patches.size(), 3u);  // the two planes and the strip
  const double h = 1.5 * mean_edge_length(mesh);
  ASSERT_EQ(narrow_patches(mesh, seg, options.hairline_patch_width * h).size(), 1u);

  const RemeshResult with = remesh(mesh, options);
  options.hairline_patch_width = 0.0;
  const RemeshResult without = remesh(mesh, options);
  EXPECT_EQ(without.report.n_hairline_merged, 0u);
  EXPECT_EQ(without.report.n_patches, 3u);
  const RemeshReport& rep = with.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  EXPECT_EQ(rep.n_hairline_merged, 1u);
  EXPECT_EQ(rep.n_patches, 2u);
  for (const RemeshResult* r : {&with, &without}) {
    const auto& t = r->report.output.topology;
    EXPECT_TRUE(t.is_manifold);
    EXPECT_EQ(t.n_boundary_loops, 1u);
    EXPECT_EQ(t.euler_characteristic, 1);
    EXPECT_EQ(t.n_self_intersecting_pairs.value_or(1), 0u);
  }
  // The strip meshed on its own leaves obtuse triangles; joined, it leaves none.
  EXPECT_GT(without.report.output.quality.obtuse_fraction, 0.0);
  EXPECT_EQ(rep.output.quality.obtuse_fraction, 0.0);
  EXPECT_GT(rep.output.quality.alpha_mean, without.report.output.quality.alpha_mean);
  // The output stays on the pleated plane: every output vertex within the step of z in [0, 0.004].
  for (const auto v : with.mesh.vertices()) {
    EXPECT_GE(with.mesh.point(v)[2], -0.004);
    EXPECT_LE(with.mesh.point(v)[2], 0.008);
  }

  // A bound below the strip's width takes nothing; a bad bound is refused.
  options.hairline_patch_width = 0.004 / h * 0.5;
  EXPECT_EQ(remesh(mesh, options).report.n_hairline_merged, 0u);
  options.hairline_patch_width = -1.0;
  EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
  options.hairline_patch_width = std::numeric_limits<double>::infinity();
  EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
}

// Two pleats like grid_with_pleat's (12 x 12 cells of side 1/12, turned): the plane steps up
// by 0.003 at x = 1/3 and down by 0.004 at the right boundary, each strip leaning back by 0.001
// (forward at the two boundary rows). Both strips are hairlines of the middle plane: the
// first (narrower, joined first) shares its longer, zigzag side with it, and the second has
// no other neighbour (its far side is the mesh's boundary).
TriMesh grid_with_two_pleats() {
  constexpr int n = 12;
  constexpr double kFirst = 0.003, kSecond = 0.004, kBack = 0.001;
  TriangleSoup soup;
  constexpr int m = n + 3;  // points per row
  for (int j = 0; j <= n; ++j) {
    const double y = j / double(n);
    const double back = (j == 0 || j == n) ? -kBack : kBack;
    for (int k = 0; k < m; ++k) {
      double x = 0.0, z = kFirst;
      if (k <= 4) {
        x = k / double(n);
        z = 0.0;
      } else if (k == 5) {
        x = 4.0 / n - back;  // the first strip's top edge
      } else if (k < m - 2) {
        x = (k - 1) / double(n);
      } else if (k == m - 2) {
        x = 1.0 + back;  // the second strip's top edge
      } else {
        x = 1.0;
        z = kFirst - kSecond;
      }
      add_turned_point(soup, x, y, z);
    }
  }
  add_grid_triangles(soup, n, m);
  return to_trimesh(soup);
}

// A second hairline joining the same neighbour: the first one's faces, now in the neighbour,
// stay exempt from the slope bounds (they were checked against them, and the second strip,
// with no other neighbour, stayed a patch of its own: 3 patches, a 129 deg triangle).
TEST(Pipeline, TwoHairlinesJoinTheSameNeighbour) {
  const TriMesh mesh = grid_with_two_pleats();
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  const Segmentation seg = segment(mesh, options.segment);
  ASSERT_EQ(seg.patches.size(), 4u);  // the two planes and the two strips
  const double h = 1.5 * mean_edge_length(mesh);
  ASSERT_EQ(narrow_patches(mesh, seg, options.hairline_patch_width * h).size(), 2u);

  const RemeshResult with = remesh(mesh, options);
  options.hairline_patch_width = 0.0;
  const RemeshResult without = remesh(mesh, options);
  const RemeshReport& rep = with.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  EXPECT_EQ(rep.n_hairline_merged, 2u);
  EXPECT_EQ(rep.n_patches, 2u);
  EXPECT_EQ(without.report.n_patches, 4u);
  const auto& t = rep.output.topology;
  EXPECT_TRUE(t.is_manifold);
  EXPECT_EQ(t.n_boundary_loops, 1u);
  EXPECT_EQ(t.euler_characteristic, 1);
  EXPECT_EQ(t.n_self_intersecting_pairs.value_or(1), 0u);
  // The strips meshed on their own leave triangles of almost 180 deg; joined, none is
  // obtuse by more than a rounding of the grid's right angles.
  EXPECT_GT(without.report.output.quality.max_angle_deg, 150.0);
  EXPECT_LT(rep.output.quality.max_angle_deg, 91.0);
  EXPECT_GT(rep.output.quality.alpha_mean, without.report.output.quality.alpha_mean);
  for (const auto v : with.mesh.vertices()) {
    EXPECT_GE(with.mesh.point(v)[2], -0.005);
    EXPECT_LE(with.mesh.point(v)[2], 0.007);
  }
}

// remesh() joins hairlines and (opt-in) steep narrow patches in two calls of
// merge_into_neighbours(): the faces the first call joined to a neighbour must stay exempt
// from its slope bounds in the second, through the marks the calls share (else the second
// strip, whose only neighbour holds the first one's faces, is refused). Here each call
// takes one of the two pleats.
TEST(Pipeline, ExemptMarksCarryAcrossMergeCalls) {
  const TriMesh mesh = grid_with_two_pleats();
  const RemeshOptions options = fast_options();
  const double mean_edge = mean_edge_length(mesh);
  const double width = options.hairline_patch_width * 1.5 * mean_edge;
  segment_detail::SplitterPtr splitter;
  const Segmentation seg = segment_detail::segment(mesh, options.segment, mean_edge, &splitter);
  ASSERT_EQ(seg.patches.size(), 4u);
  const std::vector<int> strips = narrow_patches(mesh, seg, width);
  ASSERT_EQ(strips.size(), 2u);
  std::vector<std::uint8_t> marks;
  const Segmentation first =
      segment_detail::merge_into_neighbours(*splitter, seg, {strips[0]}, false, true, false, &marks);
  ASSERT_EQ(first.patches.size(), 3u);
  ASSERT_EQ(marks.size(), mesh.n_faces());
  EXPECT_EQ(static_cast<std::size_t>(std::count(marks.begin(), marks.end(), std::uint8_t{1})),
            seg.patches[static_cast<std::size_t>(strips[0])].faces.size());
  const std::vector<int> rest = narrow_patches(mesh, first, width);
  ASSERT_EQ(rest.size(), 1u);
  // Without the first call's marks the second strip stays a patch of its own ...
  const Segmentation fresh = segment_detail::merge_into_neighbours(*splitter, first, rest, false, true, false);
  EXPECT_EQ(fresh.patches.size(), 3u);
  // ... with them it joins the same neighbour.
  const Segmentation second = segment_detail::merge_into_neighbours(*splitter, first, rest, false, true, false, &marks);
  EXPECT_EQ(second.patches.size(), 2u);
}

// Session 19 (docs/segment.md "Fin strips: a corner guard, session 19"): the corner guard of
// the fin-strip merge on the fin slab's two strips (narrow merge off, F = 1). One strip's
// join would leave 2 of its corners with two sides (its tip no longer pinned by output nodes
// on the input): refused at a bound of 1 and 0; the other loses at most 1: joined at 1, refused
// at 0; without the guard or at 2 both join. Every output ok, closed, manifold, chi 2.
TEST(Pipeline, FinStripCornerGuardRefusesAJoinThatTakesCornersAway) {
  const TriMesh mesh = slab_with_fins();
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  options.narrow_patch_merge = 0.0;
  options.fin_strip_width = 1.0;
  EXPECT_EQ(options.fin_strip_max_lost_corners, 1);
  EXPECT_EQ(options.fin_strip_pin_angle_deg, 0.0);  // opt-in
  // The guard alone (no pins), then at 0 with pins (session 20): the strips' corners left with
  // two sides no longer count, so both join as without the guard.
  for (const auto& [guard, pin, n_merged] : std::vector<std::tuple<int, double, std::size_t>>{
           {-1, 0.0, 2}, {2, 0.0, 2}, {1, 0.0, 1}, {0, 0.0, 0}, {0, 180.0, 2}}) {
    options.fin_strip_max_lost_corners = guard;
    options.fin_strip_pin_angle_deg = pin;
    const RemeshResult r = remesh(mesh, options);
    EXPECT_EQ(r.report.n_narrow_merged, n_merged) << "guard " << guard << " pin " << pin;
    EXPECT_TRUE(r.report.ok()) << errors_of(r.report);
    const TopologyReport& t = r.report.output.topology;
    EXPECT_TRUE(t.is_closed && t.is_manifold && t.is_consistently_oriented);
    EXPECT_EQ(t.euler_characteristic, 2);
  }
  options.fin_strip_max_lost_corners = -2;
  EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
  options.fin_strip_max_lost_corners = 0;
  for (const double bad : {-1.0, 181.0, std::nan("")}) {
    options.fin_strip_pin_angle_deg = bad;
    EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
  }
  options.fin_strip_pin_angle_deg = 120.0;  // pins need the guard
  options.fin_strip_max_lost_corners = -1;
  EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
}

// A 12 x 12 grid of side 1 (turned) with a steep step across it: the plane rises by 0.02 at
// x = 1/2 through one column of faces tilted 70 deg from the planes (raw normal . z = 0.34:
// outside the 60 deg slope cone, above the 0.1 orientation floor).
// In remesh() (its crease rules) the step is a patch of its own, 0.02 wide (0.16 h), facing
// both planes.
TriMesh grid_with_steep_step() {
  constexpr int n = 12;
  constexpr double kRise = 0.02;
  const double run = kRise / std::tan(70.0 * std::numbers::pi / 180.0);
  TriangleSoup soup;
  constexpr int m = n + 2;  // points per row
  for (int j = 0; j <= n; ++j) {
    const double y = j / double(n);
    for (int k = 0; k < m; ++k) {
      const bool top = k > n / 2;
      const double x = top ? (k - 1) / double(n) + run : k / double(n);
      add_turned_point(soup, x, y, top ? kRise : 0.0);
    }
  }
  add_grid_triangles(soup, n, m);
  return to_trimesh(soup);
}

TEST(Pipeline, NarrowCadPatchesJoinANeighbourWhenAsked) {
  const TriMesh mesh = grid_with_steep_step();
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  const RemeshResult without = remesh(mesh, options);  // off by default
  options.narrow_cad_patch_width = 0.3;
  const RemeshResult with = remesh(mesh, options);
  EXPECT_EQ(without.report.n_narrow_merged, 0u);
  EXPECT_EQ(without.report.n_hairline_merged, 0u);  // it faces both planes
  ASSERT_EQ(without.report.n_patches, 3u);  // the two planes and the step (the pipeline's creases)
  const RemeshReport& rep = with.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  EXPECT_EQ(rep.n_narrow_merged, 1u);
  EXPECT_EQ(rep.n_patches, 2u);
  EXPECT_EQ(rep.n_failed_patches, 0u);  // the union projects without folds and is meshed
  const auto& t = rep.output.topology;
  EXPECT_TRUE(t.is_manifold);
  EXPECT_EQ(t.n_boundary_loops, 1u);
  EXPECT_EQ(t.euler_characteristic, 1);
  EXPECT_EQ(t.n_self_intersecting_pairs.value_or(1), 0u);
  // The step meshed on its own leaves obtuse triangles; joined to a plane, it leaves none.
  EXPECT_GT(without.report.output.quality.obtuse_fraction, 0.0);
  EXPECT_EQ(rep.output.quality.obtuse_fraction, 0.0);
  EXPECT_GT(rep.output.quality.alpha_mean, without.report.output.quality.alpha_mean);
  // The fit of the plane that takes the step rounds it off and overshoots below the lower
  // plane (by 0.012, 0.6 of the rise, measured): the output stays within one rise of the input.
  for (const auto v : with.mesh.vertices()) {
    EXPECT_GE(with.mesh.point(v)[2], -0.02);
    EXPECT_LE(with.mesh.point(v)[2], 0.04);
  }

  // A bound below the step's width takes nothing; a bad bound is refused.
  options.narrow_cad_patch_width = 0.1;
  EXPECT_EQ(remesh(mesh, options).report.n_narrow_merged, 0u);
  options.narrow_cad_patch_width = -1.0;
  EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
  options.narrow_cad_patch_width = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
}

// RemeshOptions::narrow_widen_width (opt-in; segment's widen_patches, tested in
// tests/segment): off by default, a negative or non-finite width refused.
TEST(Pipeline, NarrowWidenWidthIsOptInAndValidated) {
  RemeshOptions options;
  EXPECT_EQ(options.narrow_widen_width, 0.0);
  options.narrow_widen_width = 0.3;
  EXPECT_NO_THROW(options.validate());
  options.narrow_widen_width = -1.0;
  EXPECT_THROW(options.validate(), InvalidInput);
  options.narrow_widen_width = std::numeric_limits<double>::infinity();
  EXPECT_THROW(options.validate(), InvalidInput);
}

// Issue 5 on CAD meshes whose machined edges bend by less than the crease angle (cheese.off:
// 2 422 edges at 65-80 deg): RemeshOptions::crease_gap lowers the crease angle to the gap
// below them (segment's gap_crease_angle). A roof of two planes meeting at a 72 deg bend (8 x 8
// cells, turned so that it is not taken for marching cubes): without it the ridge is no
// crease and the fits round it off; with it the two planes are two patches meeting at the
// ridge, which the output keeps. The sharp crease rule, which also takes such a clean line,
// is off here: on cheese it takes none of them (rims whose ends meet other bent edges).
TriMesh roof(double bend_deg) {
  constexpr int n = 8;
  TriangleSoup soup = test::grid_patch(n, n);
  const double bend = bend_deg * std::numbers::pi / 180.0;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  for (auto& p : soup.points) {
    if (p.x() > 0.5) {
      const double d = p.x() - 0.5;
      p.x() = 0.5 + d * std::cos(bend);
      p.z() = d * std::sin(bend);
    }
    p = turn * p + Eigen::Vector3d(0.123, 0.0456, 0.0789);
  }
  return to_trimesh(soup);
}

TEST(Pipeline, CreasesAtAGapInTheBends) {
  const TriMesh mesh = roof(72.0);
  RemeshOptions options = fast_options();
  options.segment.sharp_crease_angle_deg = 0.0;
  const RemeshResult with = remesh(mesh, options);
  options.crease_gap = false;
  const RemeshResult without = remesh(mesh, options);
  const RemeshReport& rep = with.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  EXPECT_TRUE(without.report.ok()) << errors_of(without.report);
  // 8 ridge edges among 64 + 56 + 56 = 176 interior edges (4.5%), nothing between 55 and 70.
  EXPECT_EQ(rep.crease_angle_deg, 70.0);
  EXPECT_EQ(rep.n_crease_edges, 8u);
  EXPECT_EQ(rep.n_patches, 2u);
  EXPECT_EQ(without.report.crease_angle_deg, 80.0);
  EXPECT_EQ(without.report.n_crease_edges, 0u);  // (its fit's split cuts near the ridge, not on it)
  const auto& t = rep.output.topology;
  EXPECT_TRUE(t.is_manifold && t.is_consistently_oriented);
  EXPECT_EQ(t.n_boundary_loops, 1u);
  EXPECT_EQ(t.euler_characteristic, 1);
  // Two planes meshed on their own: the output lies on the input (the rounded ridge does not).
  ASSERT_TRUE(rep.output.distance && without.report.output.distance);
  EXPECT_LT(rep.output.distance->hausdorff, 1e-6);
  EXPECT_GT(without.report.output.distance->hausdorff, 0.01);
  EXPECT_LE(rep.output.quality.obtuse_fraction, without.report.output.quality.obtuse_fraction);
  EXPECT_NE(to_json(rep).find("\"crease_angle_deg\": 70"), std::string::npos);
  // A bend of 60 deg has no gap within 15 deg below the crease angle: nothing changes.
  options.crease_gap = true;
  options.compute_distances = false;
  EXPECT_EQ(remesh(roof(60.0), options).report.crease_angle_deg, 80.0);
}

// Issue 5, fin rims (docs/stitch.md "Fin rims"): a one-voxel fin of a CT-like image has a rim
// strip narrower than one target edge between two creases; locked, its triangles stay obtuse.
// With SurfMeshOptions::fin_rim_width those curves are no features for stitch: fewer obtuse
// triangles (under issue 5's 1% here), the contract, topology and distance kept. The same
// surface turned by 30 deg (not taken for marching cubes) and the label image's surface are
// left alone.
TriMesh fin_surface(double wobble) {
  MarchingCubesOptions mc;
  mc.iso = 0.5;
  mc.inside_above = true;
  mc.pad = true;
  return prepare_mesh(marching_cubes(test::slab_with_thin_fin(wobble), mc)).mesh;
}

TEST(Pipeline, FinRimCurvesAreNoFeatures) {
  const TriMesh mesh = fin_surface(0.02);
  RemeshOptions options = fast_options();
  // The fits of session 18 (8 final BA passes): with session 19's default (0) the slab keeps
  // 10 obtuse triangles with and without the rim curves, so there is no gain to assert: at
  // the defaults the rim curves' gain is not tested on this slab.
  options.surfmesh.fit.final_passes = 8;
  const RemeshResult with = remesh(mesh, options);
  options.surfmesh.fin_rim_width = 0.0;
  const RemeshResult without = remesh(mesh, options);
  const RemeshReport& rep = with.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  EXPECT_GE(rep.n_fin_rim_curves, 2u);  // both sides of the rim strip
  EXPECT_EQ(without.report.n_fin_rim_curves, 0u);
  const TopologyReport& t = rep.output.topology;
  EXPECT_TRUE(t.is_closed && t.is_manifold && t.is_consistently_oriented);
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_EQ(count_self_intersections(to_soup(with.mesh)), 0u);
  EXPECT_LT(rep.output.quality.obtuse_fraction, without.report.output.quality.obtuse_fraction);
  EXPECT_LT(rep.output.quality.obtuse_fraction, 0.01);
  EXPECT_GE(rep.output.quality.alpha_mean, without.report.output.quality.alpha_mean);
  EXPECT_GE(rep.stitch.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg);
  ASSERT_TRUE(rep.output.distance && without.report.output.distance);
  EXPECT_LE(rep.output.distance->hausdorff, 1.01 * without.report.output.distance->hausdorff);
  EXPECT_NE(to_json(rep).find("\"fin_rim_curves\": " + std::to_string(rep.n_fin_rim_curves)), std::string::npos);

  options = fast_options();
  options.compute_distances = false;
  TriMesh turned = mesh;
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(std::numbers::pi / 6.0, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  for (const auto v : turned.vertices()) {
    const auto p = turned.point(v);
    const Eigen::Vector3d q = rotation * Eigen::Vector3d(p[0], p[1], p[2]);
    turned.set_point(v, {q.x(), q.y(), q.z()});
  }
  EXPECT_EQ(remesh(turned, options).report.n_fin_rim_curves, 0u);
  EXPECT_EQ(remesh(fin_surface(0.0), options).report.n_fin_rim_curves, 0u);  // a label image
  options.surfmesh.fin_rim_width = -1.0;
  EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
  options.surfmesh.fin_rim_width = 1.0;
  options.surfmesh.fin_rim_max_angle_deg = 181.0;
  EXPECT_THROW((void)remesh(mesh, options), InvalidInput);
}

// Issue 5, fin rims with a bound on the moves (docs/stitch.md "Fin rims: a bound on the
// moves"): stitch keeps every node of a fin rim curve (corners included) within
// StitchOptions::fin_rim_max_move mean input edges of where the front put it. The chord
// compensation and the short-edge collapse move nodes by their own rules and are off here;
// without the bound some rim node of this fin moves farther (the test can fail).
double largest_fin_rim_move(const SurfaceMesh& surface, const StitchResult& r) {
  std::vector<std::uint8_t> on_rim(surface.nodes.size(), 0);
  for (std::size_t c = 0; c < surface.curve_is_fin_rim.size(); ++c) {
    if (surface.curve_is_fin_rim[c] == 0) continue;
    for (const int g : surface.curve_nodes[c]) on_rim[static_cast<std::size_t>(g)] = 1;
  }
  double largest = 0.0;
  for (const auto v : r.mesh.vertices()) {
    const auto g = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())]);
    if (g >= surface.nodes.size() || on_rim[g] == 0) continue;
    const auto p = r.mesh.point(v);
    largest = std::max(largest, (Eigen::Vector3d(p[0], p[1], p[2]) - surface.nodes[g]).norm());
  }
  return largest;
}

TEST(Pipeline, FinRimNodesMoveWithinTheBound) {
  const TriMesh mesh = fin_surface(0.02);
  const Segmentation segmentation = segment(mesh);
  SurfMeshOptions surfmesh;
  surfmesh.crease_angle_deg = SegmentOptions{}.crease_angle_deg;
  const SurfaceMesh surface = mesh_surface(mesh, segmentation, surfmesh);
  ASSERT_GE(surface.n_fin_rim_curves, 2u);
  ASSERT_EQ(surface.curve_is_fin_rim.size(), surface.curve_is_feature.size());
  const double me = surface.input_mean_edge;
  StitchOptions options;
  options.chord_compensation = 0.0;
  options.collapse_below_angle_deg = 0.0;
  for (const double bound : {0.25, 0.1}) {
    options.fin_rim_max_move = bound;
    const StitchResult r = stitch(surface, mesh, options);
    EXPECT_TRUE(r.report.ok());
    const double moved = largest_fin_rim_move(surface, r);
    EXPECT_GT(moved, 0.0);  // they do move
    EXPECT_LE(moved, bound * me * (1.0 + 1e-9)) << "bound " << bound;
  }
  options.fin_rim_max_move = 0.0;  // the rim nodes stay
  EXPECT_EQ(largest_fin_rim_move(surface, stitch(surface, mesh, options)), 0.0);
  options.fin_rim_max_move = std::numeric_limits<double>::infinity();
  EXPECT_GT(largest_fin_rim_move(surface, stitch(surface, mesh, options)), 0.1 * me);
  options.fin_rim_max_move = -0.1;
  EXPECT_THROW((void)stitch(surface, mesh, options), InvalidInput);
  surfmesh.fin_rim_max_gap_edges = -1.0;
  EXPECT_THROW((void)mesh_surface(mesh, segmentation, surfmesh), InvalidInput);
}

// Issue 5, fin rims: every stage of the stitch honours the bound (docs/stitch.md "Fin rims:
// every stage within the bound"): with the short-edge collapse, the chord compensation, the
// crossing settling, the obtuse splits and the small-angle repair on (stitch's defaults), and
// the rims of the opt-in setting (crease angle up to 180 deg, no fits' agreement test), no
// rim node ends farther than the bound from where the front put it, and no triangle away from
// features is below issue 5's 25 deg. Before, the collapse (midpoint survivors) and the chord
// compensation moved rim nodes of this fin beyond 0.1 mean edges.
TEST(Pipeline, FinRimNodesStayWithinTheBoundInEveryStage) {
  const TriMesh mesh = fin_surface(0.02);
  const Segmentation segmentation = segment(mesh);
  SurfMeshOptions surfmesh;
  surfmesh.crease_angle_deg = SegmentOptions{}.crease_angle_deg;
  surfmesh.fin_rim_max_angle_deg = 180.0;
  surfmesh.fin_rim_max_gap_edges = std::numeric_limits<double>::infinity();
  const SurfaceMesh surface = mesh_surface(mesh, segmentation, surfmesh);
  ASSERT_GE(surface.n_fin_rim_curves, 2u);
  const double me = surface.input_mean_edge;
  StitchOptions options;
  for (const double bound : {0.25, 0.1}) {
    options.fin_rim_max_move = bound;
    const StitchResult r = stitch(surface, mesh, options);
    EXPECT_TRUE(r.report.ok());
    EXPECT_GT(r.report.n_chord_compensation_moves, 0u);
    const double moved = largest_fin_rim_move(surface, r);
    EXPECT_GT(moved, 0.0);
    EXPECT_LE(moved, bound * me * (1.0 + 1e-9)) << "bound " << bound;
    EXPECT_EQ(r.report.n_small_angle_away_from_features, 0u) << "bound " << bound;
    EXPECT_GE(r.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg) << "bound " << bound;
    // The rims are creases of the input: their triangles are counted apart, and here they
    // meet the bound too (the count that treats rims as smooth borders is 0 as well).
    EXPECT_GT(r.report.n_at_fin_rims, 0u) << "bound " << bound;
    EXPECT_EQ(r.report.n_small_angle_at_fin_rims, 0u) << "bound " << bound;
    EXPECT_GE(r.report.min_angle_at_fin_rims_deg, kAwayFromFeaturesAngleBoundDeg) << "bound " << bound;
  }
}

// The DRAM cell's marching-cubes surface: its planar faces meet in clean lines of equal bends
// (bevelled box edges), which segment() takes for sharp creases; remesh() turns them off on inputs
// that pass the marching-cubes lattice gate (docs/segment.md "Sharp creases"): the same
// output as with them off.
TEST(Pipeline, NoSharpCreasesOnMarchingCubesSurfaces) {
  const TriMesh mesh = scene_input("dram", 24, SampleMode::LevelSet).mesh;
  SegmentOptions sharp;
  sharp.sharp_crease_angle_deg = kRemeshSharpCreaseAngleDeg;
  const Segmentation own = segment(mesh, sharp);
  EXPECT_FALSE(own.sharp_crease_edges.empty());
  EXPECT_TRUE(segment(mesh).sharp_crease_edges.empty());  // off in segment() alone
  SegmentOptions off;
  off.sharp_crease_angle_deg = 0.0;
  const Segmentation without = segment(mesh, off);
  EXPECT_EQ(own.n_crease_edges, without.n_crease_edges + own.sharp_crease_edges.size());
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  const RemeshResult r = remesh(mesh, options);
  EXPECT_TRUE(r.report.ok()) << errors_of(r.report);
  EXPECT_EQ(r.report.n_crease_edges, without.n_crease_edges);
}

// The marching-cubes surface of VTK's head CT at iso 500 (the skin), padded.
TriMesh headsq_skin() {
  MarchingCubesOptions mc;
  mc.iso = 500.0;
  mc.inside_above = true;
  mc.pad = true;
  return prepare_mesh(marching_cubes(read_volume(test::test_data("volumes/headsq.mha")), mc)).mesh;
}

// VTK's head CT at iso 500 (65k faces; corner clusters where patches of 1-5 faces meet):
// settling acts (moves or flips), the topology is kept, and the reported number of crossing
// pairs is the one an independent whole-mesh count finds (settling keeps a pair list by face
// index across flips that OpenMesh may undo under swapped indices).
TEST(PipelineSlow, HeadsqSettledCrossingsCountedRight) {
  const TriMesh mesh = headsq_skin();
  const RemeshResult r = remesh(mesh, fast_options());
  const RemeshReport& rep = r.report;
  EXPECT_GT(rep.stitch.n_settled_nodes + rep.stitch.n_settled_flips + rep.stitch.n_settled_collapses, 0u);
  const TopologyReport& t = rep.output.topology;
  ASSERT_TRUE(t.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*t.n_self_intersecting_pairs, count_self_intersections(to_soup(r.mesh)));
  EXPECT_TRUE(t.is_closed);
  EXPECT_TRUE(t.is_manifold);
  EXPECT_TRUE(t.is_consistently_oriented);
  EXPECT_EQ(t.n_degenerate_faces, 0u);
  auto eulers = [](const std::vector<ComponentSignature>& components) {
    std::vector<long> out;
    for (const auto& c : components) out.push_back(c.euler_characteristic);
    std::sort(out.begin(), out.end());
    return out;
  };
  EXPECT_EQ(eulers(rep.stitch.output_components), eulers(rep.stitch.input_components));
}

// Short-edge collapses next to an intersection are given up round by round; the others are
// kept. On the head CT at iso 500 (corner clusters, tiny patches) the merges needed 4 rounds
// to cross nothing, and with 3 every merge was given up: the collapse must keep merges and
// leave fewer triangles below 25 deg away from features than no collapse at all, without
// crossings.
TEST(PipelineSlow, HeadsqShortEdgeCollapsesKept) {
  const TriMesh mesh = headsq_skin();
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  // The collapse alone: the obtuse repair moves nodes in both runs differently (it may keep a
  // ring's smallest angle where it was, under 25 deg, and trade another). The narrow-patch
  // merge before it removes most of the one-voxel fin patches whose corner clusters the
  // collapse is for (with it, 9 triangles under 25 deg with and without the collapse).
  options.stitch.obtuse_repair_rounds = 0;
  options.narrow_patch_merge = 0.0;
  // The fin-strip merge (default since session 19) too: with it the collapse run's smallest
  // angle away from features was 11.4205 deg against 11.5348 without the collapse.
  options.fin_strip_width = 0.0;
  // The small-angle repair after the optimisation mends what the collapse leaves (with and
  // without the collapse: 2 triangles under 25 deg each), so it is off here too.
  options.stitch.angle_repair_rounds = 0;
  const RemeshResult with = remesh(mesh, options);
  options.stitch.collapse_below_angle_deg = 0.0;
  const RemeshResult without = remesh(mesh, options);
  const StitchReport& s = with.report.stitch;
  EXPECT_TRUE(with.report.ok()) << errors_of(with.report);
  EXPECT_GT(s.n_collapses, s.n_collapses_undone);
  EXPECT_LT(with.mesh.n_faces(), without.mesh.n_faces());
  EXPECT_LT(s.n_small_angle_away_from_features, without.report.stitch.n_small_angle_away_from_features);
  // (The smallest angle may sit where no merge reaches: never smaller, not always larger. Since
  // triangles at fin rim nodes count apart (session 13), both runs' smallest is the same
  // triangle away from the merges, 11.5575 deg, whose nodes the sweeps after the collapse
  // leave 5.6e-9 deg apart (rounding): equal within 1e-6 deg counts as not smaller.)
  EXPECT_GE(s.min_angle_away_from_features_deg + 1e-6, without.report.stitch.min_angle_away_from_features_deg)
      << std::setprecision(12) << s.min_angle_away_from_features_deg << " vs "
      << without.report.stitch.min_angle_away_from_features_deg;
  EXPECT_GT(with.report.output.quality.alpha_mean, without.report.output.quality.alpha_mean);
  ASSERT_TRUE(with.report.output.topology.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*with.report.output.topology.n_self_intersecting_pairs, 0u);
}

// remesh() with the crossing repair off: the inputs it is tested on cross themselves then.
RemeshResult remesh_unrepaired(const TriMesh& mesh, RemeshOptions options) {
  options.crossing_repair_rounds = 0;
  RemeshResult r = remesh(mesh, options);
  EXPECT_GT(r.report.output.topology.n_self_intersecting_pairs.value_or(0), 0u);
  EXPECT_EQ(r.report.n_crossing_repairs, 0u);
  return r;
}

// The last resort against crossings stitching left (docs/segment.md, "Re-segmenting crossing
// patches"). VTK's head CT at iso 1150 (the bone): a thin fin of two patches about 100 deg
// apart wrapped by a third, whose triangles stitching could not pull out of the fin's; with
// the repair off the output crosses itself (the case the repair is for; if a change removes
// those crossings at the source, pick another input). With it the wrapping patch is
// re-segmented: no crossing, nothing else broken, the same output for any thread count.
TEST(PipelineSlow, HeadsqBoneCrossingsResegmented) {
  MarchingCubesOptions mc;
  mc.iso = 1150.0;
  mc.inside_above = true;
  mc.pad = true;
  const TriMesh mesh = prepare_mesh(marching_cubes(read_volume(test::test_data("volumes/headsq.mha")), mc)).mesh;
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  const RemeshResult without = remesh_unrepaired(mesh, options);
  const RemeshResult with = remesh(mesh, options);
  const RemeshReport& rep = with.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  EXPECT_GE(rep.n_crossing_repairs, 1u);
  const TopologyReport& t = rep.output.topology;
  ASSERT_TRUE(t.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
  EXPECT_EQ(count_self_intersections(to_soup(with.mesh)), 0u);
  EXPECT_TRUE(t.is_closed && t.is_manifold && t.is_consistently_oriented);
  EXPECT_EQ(t.euler_characteristic, without.report.output.topology.euler_characteristic);
  EXPECT_EQ(rep.stitch.output_components.size(), rep.stitch.input_components.size());
  // face_patch and the report describe the re-segmented surface.
  ASSERT_EQ(with.face_patch.size(), with.mesh.n_faces());
  EXPECT_EQ(rep.patches.size(), rep.n_patches);
  for (const int p : with.face_patch) EXPECT_LT(static_cast<std::size_t>(p), rep.n_patches);

  options.set_threads(1);
  const RemeshResult serial = remesh(mesh, options);
  ASSERT_EQ(serial.mesh.n_vertices(), with.mesh.n_vertices());
  ASSERT_EQ(serial.mesh.n_faces(), with.mesh.n_faces());
  for (auto v : with.mesh.vertices()) EXPECT_EQ(serial.mesh.point(v), with.mesh.point(v));
}

// The same last resort on CGAL's femur (7798 faces, genus 2): a big patch reaches one face
// wide between crease-bounded patches of 3-7 faces, and stitching left its triangles crossing
// theirs (docs/stitch.md). With the repair on, a small patch of the crossing pairs joins a
// neighbour: no crossing, the genus kept. The defaults no longer reach those crossings (feature
// sizing and the tiny-curve merge each avoid them), so both are off here to keep the case.
TEST(PipelineSlow, FemurCrossingsResegmented) {
  const TriMesh mesh = prepare_mesh(read_soup(test::test_data("meshes/femur.off"))).mesh;
  RemeshOptions options = fast_options();
  options.compute_distances = false;
  options.surfmesh.sizing.feature_size = 0.0;
  options.surfmesh.tiny_curve_merge_size = 0.0;
  // The front's corner rule (on by default) meshes femur without this crossing; the test
  // needs one to exercise the re-segmentation.
  options.surfmesh.corner_split_angle_deg = 180.0;
  options.tiny_patch_faces = 0;  // merging femur's tiny patches also avoids it
  options.surfmesh.polygon_node_offset_edges = 0.0;  // and so does the bound on polygon inputs' nodes
  const RemeshResult without = remesh_unrepaired(mesh, options);
  const RemeshResult with = remesh(mesh, options);
  const RemeshReport& rep = with.report;
  EXPECT_TRUE(rep.ok()) << errors_of(rep);
  EXPECT_GE(rep.n_crossing_repairs, 1u);
  EXPECT_LT(rep.n_patches, without.report.n_patches);  // a patch joined a neighbour
  EXPECT_EQ(count_self_intersections(to_soup(with.mesh)), 0u);
  const TopologyReport& t = rep.output.topology;
  EXPECT_TRUE(t.is_closed && t.is_manifold && t.is_consistently_oriented);
  EXPECT_EQ(t.n_components, 1u);
  EXPECT_EQ(t.euler_characteristic, -2);
}

}  // namespace
}  // namespace nurbsfront
