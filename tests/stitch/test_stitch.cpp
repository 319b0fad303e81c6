// SPDX-License-Identifier: BSD-3-Clause
// stitch() on SurfaceMesh values built from procedural meshes split into patches by the
// dominant axis of their face normals (a cube map): every patch is a graph over its
// plane, fitted by multilevel B-spline approximation. Planted defects must be reported.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <utility>

#include <Eigen/Geometry>

#include "fixtures/shapes.h"
#include "patch_fits.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/nurbs/frame.h"
#include "nurbsfront/nurbs/mba.h"
#include "nurbsfront/stitch/stitch.h"
#include "nurbsfront/stitch/stitch_internal.h"

namespace nurbsfront {
namespace {

// A stitch with no optimisation passes, no obtuse repair (and so no feature slides) and no
// chord compensation: the tests' common start, each switching off what else it needs.
StitchOptions without_optimisation() {
  StitchOptions o;
  o.optimisation_passes = 0;
  o.obtuse_repair_rounds = 0;
  o.chord_compensation = 0.0;
  return o;
}

Eigen::Vector3d face_normal(const TriangleSoup& s, std::size_t t) {
  const auto& tri = s.triangles[t];
  return (s.points[tri[1]] - s.points[tri[0]]).cross(s.points[tri[2]] - s.points[tri[0]]).normalized();
}

// The patch of a face: the index (0..5) of the axis direction closest to its normal.
int axis_patch(const Eigen::Vector3d& n) {
  int axis = 0;
  n.cwiseAbs().maxCoeff(&axis);
  return 2 * axis + (n[axis] < 0 ? 1 : 0);
}

// A SurfaceMesh with the soup's points as nodes and triangles by the given patches.
// Nodes with two patches are border nodes (one curve per patch pair), with three or more
// (or two and the input's boundary) corners; boundary nodes of one patch lie on a feature
// curve of the input's boundary. Each patch gets a height field fitted to its vertices.
SurfaceMesh make_surface(const TriangleSoup& soup, const std::vector<int>& face_patch, int n_patches) {
  SurfaceMesh s;
  s.nodes = soup.points;
  s.triangles.reserve(soup.triangles.size());
  for (const auto& t : soup.triangles) s.triangles.push_back({int(t[0]), int(t[1]), int(t[2])});
  s.triangle_patch = face_patch;
  const std::size_t n = soup.points.size();
  std::vector<std::set<int>> patches(n);
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edge_count;
  for (std::size_t t = 0; t < soup.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const auto a = soup.triangles[t][k], b = soup.triangles[t][(k + 1) % 3];
      patches[a].insert(face_patch[t]);
      ++edge_count[{std::min(a, b), std::max(a, b)}];
    }
  }
  std::vector<char> on_boundary(n, 0);
  for (const auto& [edge, count] : edge_count) {
    if (count == 1) on_boundary[edge.first] = on_boundary[edge.second] = 1;
  }
  std::map<std::pair<int, int>, int> curve_of;  // (patch, patch) or (patch, -1) -> curve id
  auto curve = [&](int p, int q, bool feature) {
    const auto [it, is_new] = curve_of.emplace(std::make_pair(p, q), int(curve_of.size()));
    if (is_new) s.curve_is_feature.push_back(feature);
    return it->second;
  };
  s.node_kind.resize(n);
  s.node_owner.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t sides = patches[i].size() + (on_boundary[i] ? 1 : 0);
    if (sides >= 3) {
      s.node_kind[i] = NodeKind::Corner;
      s.node_owner[i] = -1;
    } else if (sides == 2) {
      s.node_kind[i] = NodeKind::Border;
      const int p = *patches[i].begin();
      s.node_owner[i] = on_boundary[i] ? curve(p, -1, true) : curve(p, *patches[i].rbegin(), false);
    } else {
      s.node_kind[i] = NodeKind::Inner;
      s.node_owner[i] = patches[i].empty() ? 0 : *patches[i].begin();
    }
  }
  s.surfaces = test::fit_patches(soup, face_patch, n_patches, 5);
  return s;
}

SurfaceMesh cube_map_surface(const TriangleSoup& soup) {
  std::vector<int> face_patch(soup.triangles.size());
  for (std::size_t t = 0; t < soup.triangles.size(); ++t) face_patch[t] = axis_patch(face_normal(soup, t));
  return make_surface(soup, face_patch, 6);
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

bool mentions(const StitchReport& report, const std::string& word) {
  return std::any_of(report.errors.begin(), report.errors.end(),
                     [&](const std::string& e) { return e.find(word) != std::string::npos; });
}

// The icosphere with every vertex moved tangentially by up to `amount` times its mean edge
// length and put back on the unit sphere: worse triangles, same surface.
TriangleSoup jittered_sphere(int subdivisions, double amount) {
  TriangleSoup s = test::icosphere(subdivisions);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double edge = (s.points[s.triangles[0][0]] - s.points[s.triangles[0][1]]).norm();
  for (auto& p : s.points) {
    p += amount * edge * Eigen::Vector3d(u(rng), u(rng), u(rng));
    p.normalize();
  }
  return s;
}

// Whether v lies on the segment between its two neighbours u along a curve (the edges v-u
// for which on_curve(halfedge v -> u) holds; exactly two of them), collinear within 1e-9 of
// their distance: where an obtuse split puts its node on a crease or the boundary.
template <class OnCurve>
bool between_its_curve_neighbours(const TriMesh& mesh, TriMesh::VertexHandle v, OnCurve on_curve) {
  std::vector<Eigen::Vector3d> ends;
  for (auto h : mesh.voh_range(v)) {
    if (on_curve(h)) ends.push_back(to_eigen(mesh.point(mesh.to_vertex_handle(h))));
  }
  if (ends.size() != 2) return false;
  const Eigen::Vector3d p = to_eigen(mesh.point(v)), u = ends[0] - p, w = ends[1] - p;
  return u.cross(w).norm() <= 1e-9 * (ends[1] - ends[0]).squaredNorm() && u.dot(w) < 0.0;
}

TEST(Stitch, SphereOfSixPatchesIsClosedOrientedWithEulerTwo) {
  const TriangleSoup soup = test::icosphere(3);
  const SurfaceMesh surface = cube_map_surface(soup);
  const StitchResult r = stitch(surface, to_trimesh(soup));
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  const TopologyReport& t = r.report.output.topology;
  EXPECT_TRUE(t.is_closed);
  EXPECT_TRUE(t.is_manifold);
  EXPECT_TRUE(t.is_consistently_oriented);
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_EQ(t.n_components, 1u);
  ASSERT_TRUE(t.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*t.n_self_intersecting_pairs, 0u);
  EXPECT_EQ(r.mesh.n_faces(), soup.triangles.size());
  EXPECT_EQ(r.mesh.n_vertices(), soup.points.size());
  EXPECT_EQ(r.report.n_rejected_triangles, 0u);
  EXPECT_EQ(r.face_patch.size(), r.mesh.n_faces());
  EXPECT_EQ(r.vertex_node.size(), r.mesh.n_vertices());
  // The optimisation never lowers the worst element's quality below its start (a move
  // keeps the ring's smallest alpha above min(old, floor); flips raise the pair's minimum).
  EXPECT_GE(r.report.output.quality.alpha_min, std::min(r.report.alpha_min_before, StitchOptions{}.alpha_floor) - 1e-12);
  // The vertices stay on the (fitted) sphere.
  for (auto v : r.mesh.vertices()) EXPECT_NEAR(to_eigen(r.mesh.point(v)).norm(), 1.0, 0.01);
  // Oriented like the input: positive enclosed volume near the sphere's.
  ASSERT_TRUE(t.volume.has_value());
  EXPECT_NEAR(*t.volume, 4.0 / 3.0 * std::acos(-1.0), 0.1);
}

TEST(Stitch, TorusKeepsEulerZero) {
  const TriangleSoup soup = test::torus(48, 16, 1.0, 0.35);
  const StitchResult r = stitch(cube_map_surface(soup), to_trimesh(soup));
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_TRUE(r.report.output.topology.is_closed);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 0);
  ASSERT_EQ(r.report.output_components.size(), 1u);
  EXPECT_EQ(r.report.output_components[0].euler_characteristic, 0);
}

TEST(Stitch, OptimisationImprovesAJitteredSphereAcrossBorders) {
  const TriangleSoup soup = jittered_sphere(3, 0.3);
  const SurfaceMesh surface = cube_map_surface(soup);
  const StitchResult r = stitch(surface, to_trimesh(soup));
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GT(r.report.n_flips, 0u);
  EXPECT_GT(r.report.n_smoothing_moves, 0u);
  EXPECT_GT(r.report.output.quality.alpha_mean, r.report.alpha_mean_before + 0.01);
  EXPECT_GT(r.report.output.quality.alpha_min, r.report.alpha_min_before);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 2);
  // Corners never move; border nodes moved stay near the sphere (the mean of two fits).
  for (auto v : r.mesh.vertices()) {
    const auto node = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())]);
    const Eigen::Vector3d p = to_eigen(r.mesh.point(v));
    if (node < surface.nodes.size() && surface.node_kind[node] == NodeKind::Corner) {  // else an obtuse split's
      EXPECT_EQ(p, surface.nodes[node]);
    }
    EXPECT_NEAR(p.norm(), 1.0, 0.02);
  }
  // Without optimisation and collapses the quality stays that of the assembly.
  StitchOptions none = without_optimisation();
  none.collapse_below_angle_deg = 0.0;
  none.obtuse_split_rounds = 0;
  none.angle_repair_rounds = 0;
  const StitchResult raw = stitch(surface, to_trimesh(soup), none);
  EXPECT_EQ(raw.report.n_flips + raw.report.n_smoothing_moves, 0u);
  EXPECT_DOUBLE_EQ(raw.report.output.quality.alpha_mean, raw.report.alpha_mean_before);
}

// Issue 5 (obtuse triangles): the obtuse repair after the optimisation leaves fewer obtuse
// triangles than the optimisation alone, with no new triangle below the floors: the
// smallest angle away from features and the smallest alpha stay at least the smaller of
// their values without the repair and the floors.
TEST(Stitch, ObtuseRepairLeavesFewerObtuseTriangles) {
  for (const double jitter : {0.2, 0.35}) {
    SCOPED_TRACE(jitter);
    const TriangleSoup soup = jittered_sphere(3, jitter);
    const SurfaceMesh surface = cube_map_surface(soup);
    const TriMesh input = to_trimesh(soup);
    // Without the obtuse splits and collapses on both sides: they add and remove vertices (a
    // different count after the repair), the repair none.
    StitchOptions plain;
    plain.obtuse_repair_rounds = 0;
    plain.obtuse_split_rounds = 0;
    plain.obtuse_collapse = false;
    const StitchResult before = stitch(surface, input, plain);
    ASSERT_TRUE(before.report.ok()) << joined(before.report.errors);
    ASSERT_GT(before.report.output.quality.obtuse_fraction, 0.0);  // something to repair
    StitchOptions repair;
    repair.obtuse_split_rounds = 0;
    repair.obtuse_collapse = false;
    const StitchResult r = stitch(surface, input, repair);
    EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
    EXPECT_EQ(r.report.output.topology.euler_characteristic, 2);
    EXPECT_EQ(r.report.output.topology.n_faces, before.report.output.topology.n_faces);
    EXPECT_LT(r.report.output.quality.obtuse_fraction, before.report.output.quality.obtuse_fraction);
    EXPECT_GE(r.report.min_angle_away_from_features_deg,
              std::min(before.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg));
    EXPECT_GE(r.report.output.quality.alpha_min, std::min(before.report.output.quality.alpha_min, plain.alpha_floor));
    for (auto v : r.mesh.vertices()) EXPECT_NEAR(to_eigen(r.mesh.point(v)).norm(), 1.0, 0.02);
  }
  StitchOptions bad;
  bad.obtuse_repair_rounds = -1;
  EXPECT_THROW((void)stitch(cube_map_surface(test::icosphere(1)), bad), InvalidInput);
}

// Issue 5 (obtuse triangles): the obtuse collapses (StitchOptions::obtuse_collapse, the
// default since session 21; docs/stitch.md "Obtuse collapses, session 20") leave fewer obtuse
// triangles than the same stitch without them, with no new triangle below the floors and
// every node still on the sphere; the same mesh at 1 and 2 threads.
TEST(Stitch, ObtuseCollapsesLeaveFewerObtuseTriangles) {
  const TriangleSoup soup = jittered_sphere(3, 0.35);
  const SurfaceMesh surface = cube_map_surface(soup);
  const TriMesh input = to_trimesh(soup);
  StitchOptions off;
  off.obtuse_collapse = false;
  const StitchResult before = stitch(surface, input, off);
  ASSERT_TRUE(before.report.ok()) << joined(before.report.errors);
  ASSERT_GT(before.report.output.quality.obtuse_fraction, 0.0);  // something to collapse
  EXPECT_EQ(before.report.n_obtuse_collapses, 0u);
  StitchOptions on;
  ASSERT_TRUE(on.obtuse_collapse);  // the default
  const StitchResult r = stitch(surface, input, on);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GE(r.report.n_obtuse_collapses, 1u);
  EXPECT_EQ(r.mesh.n_vertices() + r.report.n_angle_collapses + r.report.n_obtuse_collapses,
            before.mesh.n_vertices() + before.report.n_angle_collapses);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 2);
  EXPECT_TRUE(r.report.output.topology.is_manifold);
  const auto obtuse_count = [](const StitchResult& s) {
    return s.report.output.quality.obtuse_fraction * static_cast<double>(s.mesh.n_faces());
  };
  EXPECT_LT(obtuse_count(r), obtuse_count(before) - 0.5);
  EXPECT_GE(r.report.min_angle_away_from_features_deg,
            std::min(before.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg));
  EXPECT_GE(r.report.output.quality.alpha_min, std::min(before.report.output.quality.alpha_min, on.alpha_floor));
  for (auto v : r.mesh.vertices()) EXPECT_NEAR(to_eigen(r.mesh.point(v)).norm(), 1.0, 0.02);
  on.n_threads = 1;
  const StitchResult one = stitch(surface, input, on);
  on.n_threads = 2;
  const StitchResult two = stitch(surface, input, on);
  ASSERT_EQ(one.mesh.n_vertices(), two.mesh.n_vertices());
  for (auto v : one.mesh.vertices()) ASSERT_EQ(one.mesh.point(v), two.mesh.point(v)) << v.idx();
}

// Two triangles on a crease (patches 0 and 1 in different planes), both obtuse at their
// far corners: their shared longest edge A-B is a feature edge (both ends feature corners,
// the others on the input's boundary), so neither a flip nor a move can touch them. The
// split puts a node on A-B at the altitudes' foot (the midpoint here, exact): four right
// triangles, the crease straight, the node a feature node of a new id.
TEST(Stitch, ObtuseSplitOfAFeatureEdgeKeepsTheCreaseStraight) {
  TriangleSoup roof;
  const Eigen::Vector3d A(0.0, 0.0, 0.0), B(1.0, 0.0, 0.0), C(0.5, 0.3, 0.0), D(0.5, -0.2, -0.2);
  roof.points = {A, B, C, D};
  roof.triangles = {{0, 1, 2}, {1, 0, 3}};
  const SurfaceMesh surface = make_surface(roof, {0, 1}, 2);
  const TriMesh input = to_trimesh(roof);
  StitchOptions off;
  off.obtuse_split_rounds = 0;
  const StitchResult before = stitch(surface, input, off);
  ASSERT_TRUE(before.report.ok()) << joined(before.report.errors);
  EXPECT_EQ(before.report.output.quality.obtuse_fraction, 1.0);  // the planted defect works
  const StitchResult r = stitch(surface, input);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_EQ(r.report.n_obtuse_splits, 1u);
  EXPECT_EQ(r.mesh.n_vertices(), 5u);
  EXPECT_EQ(r.mesh.n_faces(), 4u);
  EXPECT_EQ(r.report.output.quality.obtuse_fraction, 0.0);
  EXPECT_TRUE(r.report.output.topology.is_manifold);
  ASSERT_EQ(r.report.output_components.size(), 1u);
  EXPECT_EQ(r.report.output_components[0].euler_characteristic, r.report.input_components[0].euler_characteristic);
  ASSERT_EQ(r.vertex_node.size(), 5u);
  ASSERT_EQ(r.face_patch.size(), 4u);
  EXPECT_EQ(std::count(r.face_patch.begin(), r.face_patch.end(), 0), 2);
  for (auto v : r.mesh.vertices()) {
    const int g = r.vertex_node[static_cast<std::size_t>(v.idx())];
    const Eigen::Vector3d p = to_eigen(r.mesh.point(v));
    if (g < 4) {
      EXPECT_EQ(p, roof.points[static_cast<std::size_t>(g)]);  // nothing else moved
      continue;
    }
    EXPECT_EQ(g, 4);  // a new node id
    EXPECT_EQ(r.mesh.valence(v), 4u);
    EXPECT_LT((p - A).cross(B - A).norm(), 1e-12);  // on the crease
    EXPECT_TRUE(between_its_curve_neighbours(r.mesh, v, [&](TriMesh::HalfedgeHandle h) {
      const int left = r.mesh.face_handle(h).idx(), right = r.mesh.opposite_face_handle(h).idx();
      return r.face_patch[static_cast<std::size_t>(left)] != r.face_patch[static_cast<std::size_t>(right)];
    }));
    EXPECT_NEAR(p.x(), 0.5, 1e-12);
    // The faces around it keep their sides' patches: those with C patch 0, with D patch 1.
    for (auto f : r.mesh.vf_range(v)) {
      bool has_c = false;
      for (auto u : r.mesh.fv_range(f)) has_c = has_c || r.vertex_node[static_cast<std::size_t>(u.idx())] == 2;
      EXPECT_EQ(r.face_patch[static_cast<std::size_t>(f.idx())], has_c ? 0 : 1);
    }
  }
  StitchOptions bad;
  bad.obtuse_split_rounds = -1;
  EXPECT_THROW((void)stitch(surface, bad), InvalidInput);
}

// One triangle obtuse at C, its longest edge A-B on the input's boundary: the split puts a
// feature node on the segment (at the altitude's foot, the midpoint), between A and B along
// the boundary; two right triangles, nothing else moved.
TEST(Stitch, ObtuseSplitOfABoundaryEdgeKeepsTheBoundaryStraight) {
  TriangleSoup one;
  one.points = {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.5, 0.3, 0.0}};
  one.triangles = {{0, 1, 2}};
  const StitchResult r = stitch(make_surface(one, {0}, 1), to_trimesh(one));
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_EQ(r.report.n_obtuse_splits, 1u);
  ASSERT_EQ(r.mesh.n_vertices(), 4u);
  ASSERT_EQ(r.mesh.n_faces(), 2u);
  ASSERT_EQ(r.vertex_node.size(), 4u);
  ASSERT_EQ(r.face_patch.size(), 2u);
  EXPECT_EQ(r.report.output.quality.obtuse_fraction, 0.0);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 1);
  EXPECT_EQ(r.report.output.topology.n_boundary_loops, 1u);
  for (auto v : r.mesh.vertices()) {
    const auto g = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())]);
    if (g < one.points.size()) {
      EXPECT_EQ(to_eigen(r.mesh.point(v)), one.points[g]);
      continue;
    }
    EXPECT_TRUE(r.mesh.is_boundary(v));
    EXPECT_TRUE(between_its_curve_neighbours(r.mesh, v, [&](TriMesh::HalfedgeHandle h) { return r.mesh.is_boundary(r.mesh.edge_handle(h)); }));
    EXPECT_NEAR(r.mesh.point(v)[0], 0.5, 1e-12);
  }
}

// Issue 5, cheese.off's tunnel walls: a triangle obtuse at a node that nothing moves (here
// C, on the input's boundary) whose split leaves angles between 20 and 25 deg beside feature
// nodes. A flat kite of one patch, every node on the boundary: (A, B, C) is 118 deg at C,
// (B, A, D) 43.6 deg at D; flips only make two obtuse triangles, nothing can move. The split
// of A-B at the altitude's foot makes four right triangles, two of them 21.8 deg at D: refused
// under the usual floor (min(31 deg, 25 deg)), taken under obtuse_split_feature_angle_deg 20.
TEST(Stitch, ObtuseSplitOffAFixedNodeMayLeaveAngleBelowTheFloorAtFeatures) {
  TriangleSoup kite;
  kite.points = {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.5, 0.3, 0.0}, {0.5, -1.25, 0.0}};
  kite.triangles = {{0, 1, 2}, {1, 0, 3}};
  const SurfaceMesh surface = make_surface(kite, {0, 0}, 1);
  const TriMesh input = to_trimesh(kite);
  StitchOptions usual;
  usual.obtuse_split_feature_angle_deg = 27.5;  // the usual floor: nothing changes
  const StitchResult before = stitch(surface, input, usual);
  ASSERT_TRUE(before.report.ok()) << joined(before.report.errors);
  EXPECT_EQ(before.report.n_obtuse_splits, 0u);
  EXPECT_EQ(before.report.output.quality.obtuse_fraction, 0.5);  // the planted defect works
  const StitchResult r = stitch(surface, input);
  ASSERT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_EQ(r.report.n_obtuse_splits, 1u);
  ASSERT_EQ(r.mesh.n_vertices(), 5u);
  EXPECT_EQ(r.mesh.n_faces(), 4u);
  EXPECT_EQ(r.report.output.quality.obtuse_fraction, 0.0);
  const double d_half = std::atan(0.5 / 1.25) * 180.0 / std::numbers::pi;  // 21.8 deg
  EXPECT_NEAR(r.report.output.quality.min_angle_deg, d_half, 1e-6);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 1);
  for (auto v : r.mesh.vertices()) {
    const auto g = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())]);
    const Eigen::Vector3d p = to_eigen(r.mesh.point(v));
    if (g < kite.points.size()) {
      EXPECT_EQ(p, kite.points[g]);  // nothing else moved
      continue;
    }
    EXPECT_EQ(r.mesh.valence(v), 4u);  // the new node, inside, on A-B
    EXPECT_NEAR(p.x(), 0.5, 1e-12);
    EXPECT_NEAR(p.y(), 0.0, 1e-12);
  }
  // Above the angle at D the split is refused again.
  StitchOptions tight;
  tight.obtuse_split_feature_angle_deg = 22.0;
  EXPECT_EQ(stitch(surface, input, tight).report.n_obtuse_splits, 0u);
  for (const double bad : {-1.0, 60.0, std::numeric_limits<double>::quiet_NaN()}) {
    StitchOptions o;
    o.obtuse_split_feature_angle_deg = bad;
    EXPECT_THROW((void)stitch(surface, input, o), InvalidInput) << bad;
  }
}

// A split whose new triangles cross another component is undone. A flat rhombus of one
// patch, A-B its long diagonal (both triangles obtuse at C and D; flips and moves off, so
// only the split can repair them). The patch's fit is planted 0.1 above the rhombus, so the
// split's node goes 0.1 above the middle of A-B (under the 1/8 of the edge it may be off)
// and its four triangles form a low tent. A small upright triangle (a component of its
// own) stands over the middle, above the rhombus (which it does not cross) but through
// the tent: the split is undone and the output is the input.
TEST(Stitch, AnObtuseSplitThroughANearbySheetIsUndone) {
  TriangleSoup soup;
  soup.points = {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.5, 0.3, 0.0}, {0.5, -0.3, 0.0},
                 {0.45, -0.05, 0.03}, {0.45, 0.05, 0.03}, {0.45, 0.0, 0.2}};
  soup.triangles = {{0, 1, 2}, {1, 0, 3}, {4, 5, 6}};
  const std::vector<int> face_patch{0, 0, 1};
  ASSERT_EQ(count_self_intersections(soup), 0u);
  SurfaceMesh surface = make_surface(soup, face_patch, 2);
  const double local_z = surface.surfaces[0].frame.to_local(Eigen::Vector3d(0.5, 0.0, 0.1)).z();
  for (double& c : surface.surfaces[0].field.mutable_coefficients()) c = local_z;
  const TriMesh input = to_trimesh(soup);
  StitchOptions options = without_optimisation();
  // The planted defect works: unchecked, the split is made and crosses the sheet.
  StitchOptions unchecked = options;
  unchecked.check_self_intersections = false;
  const StitchResult crossing = stitch(surface, input, unchecked);
  EXPECT_EQ(crossing.report.n_obtuse_splits, 1u);
  EXPECT_GT(count_self_intersections(to_soup(crossing.mesh)), 0u);
  const StitchResult r = stitch(surface, input, options);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GE(r.report.n_obtuse_splits_undone, 1u);
  EXPECT_EQ(r.report.n_obtuse_splits, 0u);
  ASSERT_TRUE(r.report.output.topology.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*r.report.output.topology.n_self_intersecting_pairs, 0u);
  EXPECT_EQ(count_self_intersections(to_soup(r.mesh)), 0u);
  // The arrays went back with the mesh.
  EXPECT_EQ(r.mesh.n_vertices(), soup.points.size());
  EXPECT_EQ(r.mesh.n_faces(), soup.triangles.size());
  ASSERT_EQ(r.vertex_node.size(), r.mesh.n_vertices());
  ASSERT_EQ(r.face_patch.size(), r.mesh.n_faces());
  for (auto v : r.mesh.vertices()) {
    const int g = r.vertex_node[static_cast<std::size_t>(v.idx())];
    ASSERT_LT(static_cast<std::size_t>(g), soup.points.size());
    EXPECT_EQ(to_eigen(r.mesh.point(v)), soup.points[static_cast<std::size_t>(g)]);
  }
  EXPECT_EQ(std::count(r.face_patch.begin(), r.face_patch.end(), 0), 2);
  EXPECT_EQ(std::count(r.face_patch.begin(), r.face_patch.end(), 1), 1);
  ASSERT_EQ(r.report.output_components.size(), r.report.input_components.size());
  for (std::size_t k = 0; k < r.report.output_components.size(); ++k) {
    EXPECT_EQ(r.report.output_components[k].euler_characteristic, r.report.input_components[k].euler_characteristic);
  }
  // With the sheet out of the way the split is kept.
  TriangleSoup away = soup;
  for (std::size_t k = 4; k < 7; ++k) away.points[k].y() += 2.0;
  SurfaceMesh away_surface = make_surface(away, face_patch, 2);
  away_surface.surfaces[0] = surface.surfaces[0];
  const StitchResult kept = stitch(away_surface, to_trimesh(away), options);
  EXPECT_TRUE(kept.report.ok()) << joined(kept.report.errors);
  EXPECT_EQ(kept.report.n_obtuse_splits, 1u);
  EXPECT_EQ(kept.report.n_obtuse_splits_undone, 0u);
  EXPECT_EQ(kept.vertex_node.size(), kept.mesh.n_vertices());
  EXPECT_EQ(kept.face_patch.size(), kept.mesh.n_faces());
}

// The triangles around the vertex of node `node` in r, a feature node (checked: it stays at
// `where`), and whether one of them is obtuse at it.
std::size_t triangles_at_node(const StitchResult& r, int node, const Eigen::Vector3d& where, bool& obtuse_at_node) {
  obtuse_at_node = false;
  std::size_t n = 0;
  for (auto v : r.mesh.vertices()) {
    if (r.vertex_node[static_cast<std::size_t>(v.idx())] != node) continue;
    EXPECT_EQ(to_eigen(r.mesh.point(v)), where);  // a feature node: it never moves
    for (auto h : r.mesh.voh_range(v)) {
      if (r.mesh.is_boundary(h)) continue;
      ++n;
      const Eigen::Vector3d p = to_eigen(r.mesh.point(v));
      const Eigen::Vector3d b = to_eigen(r.mesh.point(r.mesh.to_vertex_handle(h)));
      const Eigen::Vector3d c = to_eigen(r.mesh.point(r.mesh.to_vertex_handle(r.mesh.next_halfedge_handle(h))));
      obtuse_at_node = obtuse_at_node || (b - p).dot(c - p) < 0.0;
    }
  }
  return n;
}

// Issue 5, the largest class on the CAD meshes: a node V of a straight feature border (here
// the input's boundary, y = 0) with two triangles of its patch. Their angles at V sum to
// 180 deg, so one of them is at least 90 deg wherever the inner node W goes, and neither a
// flip (the border edges are locked) nor a move (V is fixed) can help: V needs a third
// triangle. The split of the edge A-W opposite V's obtuse angle gives it one, with its
// node where the smoothing would put it (relaxed_split); at the altitude's foot or the
// midpoint the node makes right angles at itself. The patch is flat (z = 0), a fan of 7
// triangles around W, only (A, V, W) obtuse (97.1 deg at V).
TEST(Stitch, AStraightBorderNodeWithTwoTrianglesGetsAThirdOne) {
  TriangleSoup fan;
  fan.points = {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {2.0, 0.0, 0.0}, {2.5, 0.9, 0.0}, {1.5, 1.7, 0.0},
                {0.5, 1.7, 0.0}, {-0.5, 0.9, 0.0}, {1.1, 0.8, 0.0}};
  constexpr int kA = 0, kV = 1, kW = 7;
  fan.triangles = {{0, 1, 7}, {1, 2, 7}, {2, 3, 7}, {3, 4, 7}, {4, 5, 7}, {5, 6, 7}, {6, 0, 7}};
  const SurfaceMesh surface = make_surface(fan, std::vector<int>(fan.triangles.size(), 0), 1);
  const TriMesh input = to_trimesh(fan);
  // V's triangles and whether one of them is obtuse at V.
  auto at_v = [&](const StitchResult& r, bool& obtuse_at_v) {
    return triangles_at_node(r, kV, fan.points[kV], obtuse_at_v);
  };
  StitchOptions off;
  off.obtuse_split_rounds = 0;
  const StitchResult before = stitch(surface, input, off);
  ASSERT_TRUE(before.report.ok()) << joined(before.report.errors);
  bool obtuse_before = false;
  EXPECT_EQ(at_v(before, obtuse_before), 2u);
  EXPECT_TRUE(obtuse_before);  // the planted defect survives the flips and the obtuse repair
  ASSERT_GT(before.report.output.quality.obtuse_fraction, 0.0);
  for (const bool sweeps : {true, false}) {
    SCOPED_TRACE(sweeps);
    StitchOptions options;
    if (!sweeps) {
      options.optimisation_passes = 0;
      options.obtuse_repair_rounds = 0;
    }
    const StitchResult r = stitch(surface, input, options);
    EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
    EXPECT_EQ(r.report.n_obtuse_splits, 1u);
    bool obtuse_at_v = true;
    EXPECT_EQ(at_v(r, obtuse_at_v), 3u);
    EXPECT_FALSE(obtuse_at_v);
    EXPECT_EQ(r.report.output.quality.obtuse_fraction, 0.0);
    EXPECT_EQ(r.report.output.topology.euler_characteristic, 1);
    EXPECT_EQ(r.report.output.topology.n_boundary_loops, 1u);
    EXPECT_TRUE(r.report.output.topology.is_manifold);
    EXPECT_GE(r.report.output.quality.alpha_min, std::min(before.report.output.quality.alpha_min, options.alpha_floor));
    // The new node is an inner node of the patch, on its (flat) surface, off the edge A-W.
    ASSERT_EQ(r.mesh.n_vertices(), fan.points.size() + 1);
    const Eigen::Vector3d m = to_eigen(r.mesh.point(TriMesh::VertexHandle(static_cast<int>(fan.points.size()))));
    EXPECT_NEAR(m.z(), 0.0, 1e-9);
    const Eigen::Vector3d aw = fan.points[kW] - fan.points[kA];
    EXPECT_GT(aw.cross(m - fan.points[kA]).norm() / aw.norm(), 0.01);
  }
}

// Issue 5, the obtuse repair's search in the plane (docs/stitch.md "Obtuse repair: a search in
// the plane, session 17"): a flat fan of six triangles around one inner node W = (-0.2, 0),
// its ring fixed (the input's boundary). W's triangle (W, (-1, 0), (-0.5, -1.1)) is obtuse at
// W (103.1 deg); no step towards the apexes over the far edges of W's obtuse triangle (1/2 ...
// 1/16 of the way) leaves fewer obtuse triangles with the smallest angle kept, so without
// the search the defect stays; a place near (0, 0) has none. The optimisation passes and the
// splits are off: the repair alone.
TEST(Stitch, ObtuseRepairSearchFindsAPlaceTheApexStepsMiss) {
  TriangleSoup fan;
  fan.points = {{0.6, 0.0, 0.0}, {0.5, 1.2, 0.0}, {-0.4, 0.7, 0.0}, {-1.0, 0.0, 0.0},
                {-0.5, -1.1, 0.0}, {0.6, -0.8, 0.0}, {-0.2, 0.0, 0.0}};
  constexpr int kW = 6;
  fan.triangles = {{0, 1, 6}, {1, 2, 6}, {2, 3, 6}, {3, 4, 6}, {4, 5, 6}, {5, 0, 6}};
  const SurfaceMesh surface = make_surface(fan, std::vector<int>(fan.triangles.size(), 0), 1);
  const TriMesh input = to_trimesh(fan);
  auto options_with = [](int steps, unsigned n_threads) {
    StitchOptions o;
    o.optimisation_passes = 0;
    o.obtuse_split_rounds = 0;
    o.obtuse_search_steps = steps;
    o.n_threads = n_threads;
    return o;
  };
  const StitchResult before = stitch(surface, input, options_with(0, 1));
  ASSERT_TRUE(before.report.ok()) << joined(before.report.errors);
  EXPECT_GT(before.report.output.quality.obtuse_fraction, 0.0);  // the planted defect survives
  const StitchResult after = stitch(surface, input, options_with(5, 1));
  ASSERT_TRUE(after.report.ok()) << joined(after.report.errors);
  EXPECT_EQ(after.report.output.quality.obtuse_fraction, 0.0);
  EXPECT_EQ(after.report.output.topology.euler_characteristic, 1);
  EXPECT_EQ(after.report.output.topology.n_boundary_loops, 1u);
  EXPECT_TRUE(after.report.output.topology.is_manifold);
  EXPECT_GE(after.report.output.quality.alpha_min, std::min(before.report.output.quality.alpha_min, StitchOptions{}.alpha_floor));
  EXPECT_GE(after.report.output.quality.min_angle_deg, std::min(before.report.output.quality.min_angle_deg, 27.5) - 1e-9);
  ASSERT_EQ(after.mesh.n_vertices(), fan.points.size());
  for (auto v : after.mesh.vertices()) {
    const int node = after.vertex_node[static_cast<std::size_t>(v.idx())];
    const Eigen::Vector3d p = to_eigen(after.mesh.point(v));
    if (node == kW) {
      EXPECT_NEAR(p.z(), 0.0, 1e-9);  // on the patch's (flat) surface
      EXPECT_GT((p - fan.points[kW]).norm(), 0.05);  // it moved
    } else {
      EXPECT_EQ(p, fan.points[static_cast<std::size_t>(node)]);  // the ring is fixed
    }
  }
  // The same places for any thread count.
  const StitchResult two = stitch(surface, input, options_with(5, 2));
  ASSERT_EQ(two.mesh.n_vertices(), after.mesh.n_vertices());
  for (auto v : after.mesh.vertices()) EXPECT_EQ(to_eigen(two.mesh.point(v)), to_eigen(after.mesh.point(v)));
  for (const int bad : {-1, 31}) EXPECT_THROW((void)stitch(surface, input, options_with(bad, 1)), InvalidInput) << bad;
}

// Issue 5, a split opposite a fixed node (docs/stitch.md "Split nodes on a grid, session
// 18"): cheese's triple-point corners, a fixed corner C closed by one triangle (C, B, A) of
// 114.3 deg between two legs, all three nodes on the input's boundary (fixed), the triangle
// across A-B (A, B, D), D an inner node off the corner's bisector, the rest a fan around D.
// Flat (z = 0); optimisation passes and the obtuse repair's sweeps off. Without grid_split
// (a scratch switch) one obtuse triangle is left (one split, at the foot, midpoint or ring
// means); with it none (three splits).
void expect_same_mesh(const StitchResult& r, const StitchResult& r1, unsigned n);

TEST(Stitch, ASplitOppositeAFixedCornerTakesItsObtuseAngle) {
  TriangleSoup fan;
  fan.points = {{0.0, 0.0, 0.0},  {0.8403, 0.5422, 0.0}, {2.0, 0.8, 0.0},         {1.8, 3.2, 0.0}, {0.0, 3.6, 0.0},
                {-1.8, 3.2, 0.0}, {-2.0, 0.8, 0.0},      {-0.8403, 0.5422, 0.0}, {-0.8, 1.25, 0.0}};
  constexpr int kC = 0, kD = 8;
  fan.triangles = {{0, 1, 7}, {7, 1, 8}, {1, 2, 8}, {2, 3, 8}, {3, 4, 8}, {4, 5, 8}, {5, 6, 8}, {6, 7, 8}};
  const SurfaceMesh surface = make_surface(fan, std::vector<int>(fan.triangles.size(), 0), 1);
  const TriMesh input = to_trimesh(fan);
  // C's triangles and whether one of them is obtuse at C.
  auto at_c = [&](const StitchResult& r, bool& obtuse_at_c) {
    return triangles_at_node(r, kC, fan.points[kC], obtuse_at_c);
  };
  auto options_with = [](int split_rounds, unsigned n_threads) {
    StitchOptions o;
    o.optimisation_passes = 0;
    o.obtuse_repair_rounds = 0;
    o.obtuse_split_rounds = split_rounds;
    o.n_threads = n_threads;
    return o;
  };
  const StitchResult before = stitch(surface, input, options_with(0, 1));
  ASSERT_TRUE(before.report.ok()) << joined(before.report.errors);
  bool obtuse_before = false;
  EXPECT_EQ(at_c(before, obtuse_before), 1u);
  EXPECT_TRUE(obtuse_before);  // the planted defect
  const StitchResult r = stitch(surface, input, options_with(2, 1));
  ASSERT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GE(r.report.n_obtuse_splits, 1u);
  bool obtuse_at_c = true;
  EXPECT_GE(at_c(r, obtuse_at_c), 2u);
  EXPECT_FALSE(obtuse_at_c);
  EXPECT_EQ(r.report.output.quality.obtuse_fraction, 0.0);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 1);
  EXPECT_EQ(r.report.output.topology.n_boundary_loops, 1u);
  EXPECT_TRUE(r.report.output.topology.is_manifold);
  EXPECT_GE(r.report.output.quality.alpha_min, std::min(before.report.output.quality.alpha_min, StitchOptions{}.alpha_floor));
  // The old nodes on the boundary in place, every node on the plane.
  for (auto v : r.mesh.vertices()) {
    const auto node = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())]);
    const Eigen::Vector3d p = to_eigen(r.mesh.point(v));
    if (node < fan.points.size() && node != kD) {
      EXPECT_EQ(p, fan.points[node]);
    }
    EXPECT_NEAR(p.z(), 0.0, 1e-9);
  }
  // The same mesh for any thread count.
  expect_same_mesh(stitch(surface, input, options_with(2, 2)), r, 2);
}

// Issue 5, a strip's far piece (docs/stitch.md "Far pieces of strips"): a flat strip one
// triangle wide between two straight feature borders (both the input's boundary, y = 0 and
// y = 0.8) whose far border has fewer nodes: the node V = (1, 0) has two triangles, both
// with the far node X = (0.9, 0.8), and 97.1 deg at V in (V, A2, X). V, X and A2 are fixed,
// a flip of A2-X leaves (V, A2, Y) obtuse at A2 (116.6 deg), and a split of A2-X puts a node
// inside a strip too narrow for it. The split of the far piece X-Y (node on the segment)
// with the flip of A2-X gives V a third triangle: no obtuse triangle is left.
TEST(Stitch, AStripNodeFacingAFarPieceGetsAThirdTriangle) {
  TriangleSoup strip;
  strip.points = {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {2.0, 0.0, 0.0}, {3.0, 0.0, 0.0},
                  {2.4, 0.8, 0.0}, {0.9, 0.8, 0.0}, {-0.5, 0.8, 0.0}};
  constexpr int kV = 1, kY = 4, kX = 5;
  strip.triangles = {{0, 1, 5}, {1, 2, 5}, {2, 4, 5}, {0, 5, 6}, {2, 3, 4}};
  SurfaceMesh surface = make_surface(strip, std::vector<int>(strip.triangles.size(), 0), 1);
  // The far border is a curve of its own (make_surface gives the whole boundary one curve,
  // and an edge between two nodes of one feature curve is a crease that never flips).
  surface.curve_is_feature.push_back(true);
  for (const int node : {kY, kX, 6}) surface.node_owner[node] = static_cast<int>(surface.curve_is_feature.size()) - 1;
  const TriMesh input = to_trimesh(strip);
  auto triangles_at = [](const StitchResult& r, int node) {
    std::size_t n = 0;
    for (auto v : r.mesh.vertices()) {
      if (r.vertex_node[static_cast<std::size_t>(v.idx())] != node) continue;
      for (auto f : r.mesh.vf_range(v)) n += f.is_valid() ? 1 : 0;
    }
    return n;
  };
  StitchOptions off;
  off.obtuse_split_rounds = 0;
  const StitchResult before = stitch(surface, input, off);
  ASSERT_TRUE(before.report.ok()) << joined(before.report.errors);
  EXPECT_EQ(triangles_at(before, kV), 2u);
  ASSERT_GT(before.report.output.quality.obtuse_fraction, 0.0);  // the planted defect survives the repair
  const StitchResult r = stitch(surface, input, StitchOptions{});
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_EQ(r.report.n_obtuse_splits, 1u);
  EXPECT_EQ(r.report.output.quality.obtuse_fraction, 0.0);
  EXPECT_EQ(triangles_at(r, kV), 3u);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 1);
  EXPECT_EQ(r.report.output.topology.n_boundary_loops, 1u);
  EXPECT_TRUE(r.report.output.topology.is_manifold);
  EXPECT_GE(r.report.output.quality.alpha_min, std::min(before.report.output.quality.alpha_min, StitchOptions{}.alpha_floor));
  // The new node is on the far piece X-Y (a boundary segment: on it, strictly between its
  // ends), the old nodes where they were.
  ASSERT_EQ(r.mesh.n_vertices(), strip.points.size() + 1);
  for (auto v : r.mesh.vertices()) {
    const auto g = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())]);
    const Eigen::Vector3d p = to_eigen(r.mesh.point(v));
    if (g < strip.points.size()) {
      EXPECT_EQ(p, strip.points[g]);
      continue;
    }
    EXPECT_TRUE(r.mesh.is_boundary(v));
    EXPECT_EQ(p.y(), 0.8);
    EXPECT_EQ(p.z(), 0.0);
    EXPECT_GT(p.x(), strip.points[kX].x());
    EXPECT_LT(p.x(), strip.points[kY].x());
  }
}

// The obtuse repair and the chord compensation have their own switches: they run with the
// flip and smoothing sweeps off, and nothing moves with all three off. Bad strengths are
// refused.
TEST(Stitch, ObtuseRepairAndChordCompensationRunWithoutTheSweeps) {
  const TriangleSoup soup = jittered_sphere(3, 0.35);
  const SurfaceMesh surface = cube_map_surface(soup);
  const TriMesh input = to_trimesh(soup);
  StitchOptions options;
  options.optimisation_passes = 0;
  const StitchResult r = stitch(surface, input, options);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GT(r.report.n_chord_compensation_moves, 0U);
  EXPECT_GT(r.report.n_flips + r.report.n_smoothing_moves, 0U);  // the obtuse repair's
  options.obtuse_repair_rounds = 0;
  options.chord_compensation = 0.0;
  options.volume_compensation = 0.0;
  options.obtuse_split_rounds = 0;
  const StitchResult still = stitch(surface, input, options);
  EXPECT_TRUE(still.report.ok()) << joined(still.report.errors);
  EXPECT_EQ(still.report.n_chord_compensation_moves, 0U);
  EXPECT_EQ(still.report.n_volume_compensation_moves, 0U);
  EXPECT_EQ(still.report.n_flips + still.report.n_smoothing_moves, 0U);
  for (const double bad : {-0.5, 2.5, std::numeric_limits<double>::quiet_NaN()}) {
    StitchOptions o;
    o.chord_compensation = bad;
    EXPECT_THROW((void)stitch(surface, input, o), InvalidInput) << bad;
    StitchOptions v;
    v.volume_compensation = bad;
    EXPECT_THROW((void)stitch(surface, input, v), InvalidInput) << bad;
  }
}

// The flips' tests run in parallel and the verification's signatures on helper threads:
// the same flips, positions and report for any thread count.
// r's mesh is r1's bit for bit: the same vertices at the same points, the same faces with the
// same corners (n: r's thread count, for the messages).
void expect_same_mesh(const StitchResult& r, const StitchResult& r1, unsigned n) {
  ASSERT_EQ(r.mesh.n_vertices(), r1.mesh.n_vertices()) << n << " threads";
  ASSERT_EQ(r.mesh.n_faces(), r1.mesh.n_faces()) << n << " threads";
  for (auto v : r.mesh.vertices()) ASSERT_EQ(r.mesh.point(v), r1.mesh.point(v)) << "vertex " << v.idx() << ", " << n << " threads";
  for (auto f : r.mesh.faces()) {
    auto a = r.mesh.fv_range(f).begin();
    auto b = r1.mesh.fv_range(TriMesh::FaceHandle(f.idx())).begin();
    for (int k = 0; k < 3; ++k, ++a, ++b) ASSERT_EQ((*a).idx(), (*b).idx()) << "face " << f.idx() << ", " << n << " threads";
  }
}

// Stitches with `options` at 1 thread, then at 2 and 4: the same counts of obtuse splits,
// flips and smoothing moves and the same mesh bit for bit. Returns the 1-thread result.
StitchResult expect_same_at_1_2_4_threads(const SurfaceMesh& surface, const TriMesh& input, StitchOptions options) {
  options.n_threads = 1;
  StitchResult r1 = stitch(surface, input, options);
  EXPECT_TRUE(r1.report.ok()) << joined(r1.report.errors);
  for (const unsigned n : {2U, 4U}) {
    options.n_threads = n;
    const StitchResult r = stitch(surface, input, options);
    EXPECT_EQ(r.report.n_obtuse_splits, r1.report.n_obtuse_splits) << n;
    EXPECT_EQ(r.report.n_flips, r1.report.n_flips) << n;
    EXPECT_EQ(r.report.n_smoothing_moves, r1.report.n_smoothing_moves) << n;
    expect_same_mesh(r, r1, n);
  }
  return r1;
}

TEST(Stitch, SameResultForAnyThreadCount) {
  const TriangleSoup soup = jittered_sphere(3, 0.6);
  const SurfaceMesh surface = cube_map_surface(soup);
  const TriMesh input = to_trimesh(soup);
  StitchOptions one;
  one.n_threads = 1;
  const StitchResult r1 = stitch(surface, input, one);
  ASSERT_GT(r1.report.n_flips, 0u);
  for (const unsigned n : {2u, 3u}) {
    StitchOptions options;
    options.n_threads = n;
    const StitchResult r = stitch(surface, input, options);
    EXPECT_EQ(r.report.n_flips, r1.report.n_flips);
    EXPECT_EQ(r.report.n_smoothing_moves, r1.report.n_smoothing_moves);
    EXPECT_EQ(r.report.min_angle_away_from_features_deg, r1.report.min_angle_away_from_features_deg);
    EXPECT_EQ(r.report.n_away_from_features, r1.report.n_away_from_features);
    EXPECT_EQ(r.report.output.quality.alpha_mean, r1.report.output.quality.alpha_mean);
    ASSERT_EQ(r.report.input_components.size(), r1.report.input_components.size());
    ASSERT_EQ(r.report.output_components.size(), r1.report.output_components.size());
    EXPECT_EQ(r.report.output_components[0].n_faces, r1.report.output_components[0].n_faces);
    EXPECT_EQ(r.report.input_components[0].n_vertices, r1.report.input_components[0].n_vertices);
    expect_same_mesh(r, r1, n);
  }
}

// The obtuse splits' scan takes every face's obtuse corner on the run's threads first and
// looks again only at the faces a split or its flips changed: the same splits, flips and
// positions at 1, 2 and 4 threads on a mesh of several scan chunks (8192 faces) with many
// splits (slow: three stitches of 20 480 faces).
TEST(StitchSlow, ObtuseSplitsSameForAnyThreadCount) {
  const TriangleSoup soup = jittered_sphere(5, 0.3);
  ASSERT_GT(soup.triangles.size(), 2U * 8192U);
  const SurfaceMesh surface = cube_map_surface(soup);
  const TriMesh input = to_trimesh(soup);
  StitchOptions options = without_optimisation();
  options.angle_repair_rounds = 0;
  options.collapse_below_angle_deg = 0.0;
  options.volume_compensation = 0.0;
  const StitchResult r1 = expect_same_at_1_2_4_threads(surface, input, options);
  EXPECT_GT(r1.report.n_obtuse_splits, 20U);
}

// The obtuse repair's moves are Gauss-Seidel in vertex order; with 2+ threads every
// candidate's move is planned on the threads first and the sweep drops the plan of a vertex
// whose neighbour moved before it (decides again). On a jittered sphere of 5 120 faces (many
// obtuse triangles side by side, so neighbours move in one sweep: 613 moves) the obtuse
// repair alone gives the same moves, flips and positions bit for bit at 1, 2 and 4 threads
// (with the plans kept where a neighbour moved, this test and SameResultForAnyThreadCount
// failed).
TEST(Stitch, PlannedObtuseMovesGiveTheSerialSweep) {
  const TriangleSoup soup = jittered_sphere(4, 0.3);
  const SurfaceMesh surface = cube_map_surface(soup);
  const TriMesh input = to_trimesh(soup);
  StitchOptions options = without_optimisation();
  options.obtuse_repair_rounds = 2;
  options.obtuse_split_rounds = 0;
  options.angle_repair_rounds = 0;
  options.collapse_below_angle_deg = 0.0;
  options.volume_compensation = 0.0;
  const StitchResult r1 = expect_same_at_1_2_4_threads(surface, input, options);
  EXPECT_GT(r1.report.n_smoothing_moves, 200U);
}

// The obtuse splits go face by face; with 2+ threads every face obtuse at the sweep's start
// is planned on the threads first, and the sweep drops the plan of a face near a split or
// flip made before it (around its corners and the corner across its split edge, and their
// neighbours) and plans it again. On a jittered sphere of 5 120 faces (obtuse triangles
// side by side: splits next to each other in one sweep) the splits alone give the same
// splits, flips and mesh bit for bit at 1, 2 and 4 threads.
TEST(Stitch, PlannedObtuseSplitsGiveTheSerialSweep) {
  const TriangleSoup soup = jittered_sphere(4, 0.3);
  const SurfaceMesh surface = cube_map_surface(soup);
  const TriMesh input = to_trimesh(soup);
  StitchOptions options = without_optimisation();
  options.angle_repair_rounds = 0;
  options.collapse_below_angle_deg = 0.0;
  options.volume_compensation = 0.0;
  const StitchResult r1 = expect_same_at_1_2_4_threads(surface, input, options);
  EXPECT_GT(r1.report.n_obtuse_splits, 20U);
}

// The smoothing sweep is Gauss-Seidel in vertex order; with 2+ threads it runs on a schedule
// (border nodes and corners, and every node before a neighbour of theirs, in order on one
// thread; the other inner nodes in connected groups, each after the border nodes it touches).
// The same positions bit for bit and the same counts for any thread count, with the nodes in
// the icosphere's order (inner and border nodes mixed: many inner nodes go with the border
// nodes) and with the inner nodes last (as mesh_surface numbers them: one group per patch).
TEST(Stitch, ScheduledSmoothingGivesTheSerialSweep) {
  const TriangleSoup sphere = jittered_sphere(3, 0.6);
  // The inner nodes last, else in the same order.
  const SurfaceMesh mixed = cube_map_surface(sphere);
  std::vector<std::uint32_t> order;
  for (const bool inner : {false, true}) {
    for (std::uint32_t i = 0; i < sphere.points.size(); ++i) {
      if ((mixed.node_kind[i] == NodeKind::Inner) == inner) order.push_back(i);
    }
  }
  std::vector<std::uint32_t> new_index(order.size());
  for (std::uint32_t k = 0; k < order.size(); ++k) new_index[order[k]] = k;
  TriangleSoup inner_last;
  for (const std::uint32_t i : order) inner_last.points.push_back(sphere.points[i]);
  for (const auto& t : sphere.triangles) inner_last.triangles.push_back({new_index[t[0]], new_index[t[1]], new_index[t[2]]});
  for (const TriangleSoup* soup : std::array<const TriangleSoup*, 2>{&sphere, &inner_last}) {
    const SurfaceMesh surface = cube_map_surface(*soup);
    const TriMesh input = to_trimesh(*soup);
    StitchOptions options;
    options.obtuse_repair_rounds = 0;
    options.obtuse_split_rounds = 0;
    options.angle_repair_rounds = 0;
    options.collapse_below_angle_deg = 0.0;
    options.chord_compensation = 0.0;
    options.volume_compensation = 0.0;
    options.n_threads = 1;
    const StitchResult r1 = stitch(surface, input, options);
    ASSERT_GT(r1.report.n_smoothing_moves, 100u);
    for (const unsigned n : {2u, 4u}) {
      options.n_threads = n;
      const StitchResult r = stitch(surface, input, options);
      EXPECT_EQ(r.report.n_flips, r1.report.n_flips);
      EXPECT_EQ(r.report.n_smoothing_moves, r1.report.n_smoothing_moves);
      EXPECT_EQ(r.report.n_smoothing_rejected, r1.report.n_smoothing_rejected);
      expect_same_mesh(r, r1, n);
    }
  }
}

// The first edge of the assembly (in triangle order) whose two nodes are inner nodes of the
// same patch, as (v, w); (-1, -1) if there is none.
std::pair<int, int> inner_edge_of_one_patch(const SurfaceMesh& surface) {
  for (const auto& t : surface.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      if (surface.node_kind[a] == NodeKind::Inner && surface.node_kind[b] == NodeKind::Inner &&
          surface.node_owner[a] == surface.node_owner[b]) {
        return {a, b};
      }
    }
  }
  return {-1, -1};
}

// Issue 5: a short edge no flip or smoothing removes (an inner node planted next to
// another) is collapsed; the result keeps the contract and its worst triangle improves.
TEST(Stitch, CollapsesAPlantedShortEdge) {
  TriangleSoup soup = test::icosphere(3);
  SurfaceMesh surface = cube_map_surface(soup);
  const auto [v, w] = inner_edge_of_one_patch(surface);  // an inner node, an inner neighbour
  ASSERT_GE(v, 0);
  const double edge = (surface.nodes[v] - surface.nodes[w]).norm();
  surface.nodes[v] = (surface.nodes[w] + 0.03 * (surface.nodes[v] - surface.nodes[w])).normalized();
  soup.points[v] = surface.nodes[v];
  StitchOptions off;
  off.collapse_below_angle_deg = 0.0;
  const StitchResult kept = stitch(surface, to_trimesh(soup), off);
  EXPECT_EQ(kept.report.n_collapses, 0u);
  const StitchResult r = stitch(surface, to_trimesh(soup));
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GE(r.report.n_collapses, 1u);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 2);
  EXPECT_TRUE(r.report.output.topology.is_closed);
  EXPECT_EQ(r.mesh.n_vertices(), soup.points.size() - r.report.n_collapses);
  EXPECT_EQ(r.report.n_unused_nodes, 0u);
  double shortest = edge;
  for (auto e : r.mesh.edges()) shortest = std::min(shortest, r.mesh.calc_edge_length(e));
  EXPECT_GT(shortest, 0.2 * edge);
  EXPECT_GT(r.report.output.quality.min_angle_deg, kept.report.output.quality.min_angle_deg + 5.0);
  EXPECT_GT(r.report.min_angle_away_from_features_deg, kept.report.min_angle_away_from_features_deg);
  // Without curve_nodes every corner counts as a feature; the curves are smooth.
  for (auto u : r.mesh.vertices()) {
    const auto node = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(u.idx())]);
    if (surface.node_kind[node] == NodeKind::Corner) {
      EXPECT_EQ(to_eigen(r.mesh.point(u)), surface.nodes[node]);
    }
  }
}

// The stitch with only the small-angle repair (rounds) after the assembly: the collapse
// before the optimisation, the sweeps, the chord compensation and the splits are off.
StitchResult stitch_with_angle_repair(const SurfaceMesh& surface, const TriangleSoup& soup, int rounds) {
  StitchOptions options = without_optimisation();
  options.collapse_below_angle_deg = 0.0;
  options.obtuse_split_rounds = 0;
  options.angle_repair_rounds = rounds;
  return stitch(surface, to_trimesh(soup), options);
}

// Issue 5: a triangle away from features below 25 deg that nothing before the small-angle
// repair removes (a node planted 0.03 edges from its neighbour) is gone after it, the mesh
// stays closed with Euler characteristic 2, and the survivor stays where it was (every vertex
// still on the unit sphere).
TEST(Stitch, AngleRepairCollapsesAShortEdgeAwayFromFeatures) {
  TriangleSoup soup = test::icosphere(3);
  SurfaceMesh surface = cube_map_surface(soup);
  const auto [v, w] = inner_edge_of_one_patch(surface);
  ASSERT_GE(v, 0);
  surface.nodes[v] = (surface.nodes[w] + 0.03 * (surface.nodes[v] - surface.nodes[w])).normalized();
  soup.points[v] = surface.nodes[v];
  const StitchResult off = stitch_with_angle_repair(surface, soup, 0);
  ASSERT_GE(off.report.n_small_angle_away_from_features, 2u);
  EXPECT_EQ(off.report.n_angle_collapses + off.report.n_angle_flips + off.report.n_angle_moves, 0u);
  const StitchResult r = stitch_with_angle_repair(surface, soup, 2);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_EQ(r.report.n_small_angle_away_from_features, 0u);
  EXPECT_GE(r.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg);
  EXPECT_GE(r.report.n_angle_collapses, 1u);
  EXPECT_EQ(r.report.n_angle_moves, 0u);  // so every vertex is where it was assembled
  EXPECT_EQ(r.report.n_angle_repairs_undone, 0u);
  const TopologyReport& t = r.report.output.topology;
  EXPECT_TRUE(t.is_closed);
  EXPECT_TRUE(t.is_manifold);
  EXPECT_TRUE(t.is_consistently_oriented);
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_EQ(t.n_self_intersecting_pairs.value_or(1), 0u);
  EXPECT_EQ(r.face_patch.size(), r.mesh.n_faces());
  EXPECT_EQ(r.vertex_node.size(), r.mesh.n_vertices());
  EXPECT_EQ(r.mesh.n_vertices() + r.report.n_unused_nodes + r.report.n_angle_collapses + r.report.n_obtuse_collapses,
            surface.nodes.size());
  for (auto u : r.mesh.vertices()) {
    const auto node = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(u.idx())]);
    EXPECT_EQ(to_eigen(r.mesh.point(u)), surface.nodes[node]);
  }
}

// A cap (an inner node pushed next to the middle of its far edge): its small angles go by a
// flip, a collapse or a move, the mesh stays valid.
TEST(Stitch, AngleRepairRemovesACapAwayFromFeatures) {
  TriangleSoup soup = test::icosphere(3);
  SurfaceMesh surface = cube_map_surface(soup);
  // An inner node v of a triangle (v, b, c) of one patch whose nodes are all inner.
  int v = -1, b = -1, c = -1;
  for (const auto& t : surface.triangles) {
    if (v >= 0) break;
    if (std::all_of(t.begin(), t.end(), [&](int g) { return surface.node_kind[g] == NodeKind::Inner; })) {
      v = t[0];
      b = t[1];
      c = t[2];
    }
  }
  ASSERT_GE(v, 0);
  const Eigen::Vector3d middle = 0.5 * (surface.nodes[b] + surface.nodes[c]);
  surface.nodes[v] = (middle + 0.12 * (surface.nodes[v] - middle)).normalized();
  soup.points[v] = surface.nodes[v];
  const StitchResult off = stitch_with_angle_repair(surface, soup, 0);
  ASSERT_GE(off.report.n_small_angle_away_from_features, 1u);
  const StitchResult r = stitch_with_angle_repair(surface, soup, 2);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_LT(r.report.n_small_angle_away_from_features, off.report.n_small_angle_away_from_features);
  EXPECT_GT(r.report.min_angle_away_from_features_deg, off.report.min_angle_away_from_features_deg);
  EXPECT_GE(r.report.n_angle_flips + r.report.n_angle_collapses + r.report.n_angle_moves, 1u);
  EXPECT_TRUE(r.report.output.topology.is_closed);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 2);
  EXPECT_EQ(r.report.output.topology.n_self_intersecting_pairs.value_or(1), 0u);
}

TEST(Stitch, FeatureCurvesAndCornersStayPut) {
  const TriangleSoup soup = jittered_sphere(2, 0.3);
  SurfaceMesh surface = cube_map_surface(soup);
  std::fill(surface.curve_is_feature.begin(), surface.curve_is_feature.end(), std::uint8_t{1});
  const StitchResult r = stitch(surface, to_trimesh(soup));
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  std::set<std::pair<int, int>> border_edges_before, border_edges_after;
  for (const auto& t : surface.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      if (surface.node_kind[a] != NodeKind::Inner && surface.node_kind[b] != NodeKind::Inner) {
        border_edges_before.insert({std::min(a, b), std::max(a, b)});
      }
    }
  }
  auto patch_of = [&](TriMesh::FaceHandle f) { return r.face_patch[static_cast<std::size_t>(f.idx())]; };
  auto on_crease = [&](TriMesh::HalfedgeHandle h) {
    return !r.mesh.is_boundary(r.mesh.edge_handle(h)) && patch_of(r.mesh.face_handle(h)) != patch_of(r.mesh.opposite_face_handle(h));
  };
  for (auto v : r.mesh.vertices()) {
    const auto node = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())]);
    if (node >= surface.nodes.size()) {
      // An obtuse split's: one on a crease lies on the crease's segment.
      std::set<int> patches;
      for (auto f : r.mesh.vf_range(v)) patches.insert(patch_of(f));
      if (patches.size() > 1) {
        EXPECT_TRUE(between_its_curve_neighbours(r.mesh, v, on_crease)) << to_eigen(r.mesh.point(v)).transpose();
      }
      continue;
    }
    if (surface.node_kind[node] != NodeKind::Inner) {
      EXPECT_EQ(to_eigen(r.mesh.point(v)), surface.nodes[node]);
    }
  }
  // Every crease edge between two patches is still there.
  for (auto e : r.mesh.edges()) {
    const auto h = r.mesh.halfedge_handle(e, 0);
    const int fa = r.face_patch[static_cast<std::size_t>(r.mesh.face_handle(h).idx())];
    const int fb = r.face_patch[static_cast<std::size_t>(r.mesh.opposite_face_handle(h).idx())];
    if (fa == fb) continue;
    const int a = r.vertex_node[static_cast<std::size_t>(r.mesh.from_vertex_handle(h).idx())];
    const int b = r.vertex_node[static_cast<std::size_t>(r.mesh.to_vertex_handle(h).idx())];
    const int n_nodes = static_cast<int>(surface.nodes.size());
    if (a >= n_nodes || b >= n_nodes) continue;  // a piece of a split crease edge
    border_edges_after.insert({std::min(a, b), std::max(a, b)});
  }
  for (const auto& e : border_edges_after) EXPECT_TRUE(border_edges_before.count(e));
}

TEST(Stitch, OpenInputKeepsItsBoundary) {
  TriangleSoup soup = test::grid_patch(12, 12);
  for (auto& p : soup.points) p.z() = 0.2 * std::sin(3.0 * p.x()) * std::cos(2.0 * p.y());
  std::vector<int> face_patch(soup.triangles.size());
  for (std::size_t t = 0; t < soup.triangles.size(); ++t) {
    const auto& tri = soup.triangles[t];
    const double x = (soup.points[tri[0]].x() + soup.points[tri[1]].x() + soup.points[tri[2]].x()) / 3.0;
    face_patch[t] = x < 0.5 ? 0 : 1;
  }
  const SurfaceMesh surface = make_surface(soup, face_patch, 2);
  const StitchResult r = stitch(surface, to_trimesh(soup));
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_FALSE(r.report.output.topology.is_closed);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 1);
  EXPECT_EQ(r.report.output.topology.n_boundary_loops, 1u);
  for (auto v : r.mesh.vertices()) {
    if (!r.mesh.is_boundary(v)) continue;
    const auto node = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())]);
    if (node >= surface.nodes.size()) {  // an obtuse split's: on the boundary's segment
      EXPECT_TRUE(between_its_curve_neighbours(r.mesh, v, [&](TriMesh::HalfedgeHandle h) { return r.mesh.is_boundary(r.mesh.edge_handle(h)); }))
          << to_eigen(r.mesh.point(v)).transpose();
      continue;
    }
    EXPECT_EQ(to_eigen(r.mesh.point(v)), surface.nodes[node]);
  }
}

TEST(Stitch, UnusedNodesAreDroppedAndCounted) {
  const TriangleSoup soup = test::icosphere(2);
  SurfaceMesh surface = cube_map_surface(soup);
  surface.nodes.push_back(Eigen::Vector3d(5, 5, 5));
  surface.node_kind.push_back(NodeKind::Inner);
  surface.node_owner.push_back(0);
  const StitchResult r = stitch(surface, to_trimesh(soup));
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_EQ(r.report.n_unused_nodes, 1u);
  EXPECT_EQ(r.mesh.n_vertices(), soup.points.size());
}

TEST(Stitch, ATetrahedronIsNotCollapsedIntoTwoCoincidingTriangles) {
  // The smallest closed surface: a base triangle (patch 1) and an inner node close to the
  // middle of one of its edges, slightly above it (patch 0, three slivers). Collapsing that
  // node into a base node would raise the smallest angle but leave the base triangle twice
  // (ironProt's one-voxel blobs: "output has 3 duplicate triangles").
  TriangleSoup soup;
  soup.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.45, 0.45, 0.02}};
  soup.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  const SurfaceMesh surface = make_surface(soup, {1, 0, 0, 0}, 2);
  ASSERT_EQ(surface.node_kind[3], NodeKind::Inner);
  // The obtuse splits off: since session 18 their grid (grid_split) splits the slivers, which
  // is not what this test is about (the collapse).
  StitchOptions options;
  options.obtuse_split_rounds = 0;
  const StitchResult r = stitch(surface, to_trimesh(soup), options);
  EXPECT_EQ(r.report.n_collapses, 0u);
  EXPECT_EQ(r.report.output.topology.n_duplicate_faces, 0u);
  EXPECT_EQ(r.mesh.n_faces(), 4u);
  EXPECT_TRUE(r.report.output.topology.is_closed);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 2);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
}

TEST(Stitch, DuplicatedTriangleIsAnError) {
  const TriangleSoup soup = test::icosphere(2);
  SurfaceMesh surface = cube_map_surface(soup);
  surface.triangles.push_back(surface.triangles[17]);
  surface.triangle_patch.push_back(surface.triangle_patch[17]);
  const StitchResult r = stitch(surface, to_trimesh(soup));
  EXPECT_FALSE(r.report.ok());
  EXPECT_EQ(r.report.n_rejected_triangles, 1u);
  EXPECT_TRUE(mentions(r.report, "could not be added")) << joined(r.report.errors);
}

TEST(Stitch, MissingTriangleOpensAClosedInputAndIsAnError) {
  const TriangleSoup soup = test::icosphere(2);
  SurfaceMesh surface = cube_map_surface(soup);
  surface.triangles.erase(surface.triangles.begin() + 40);
  surface.triangle_patch.erase(surface.triangle_patch.begin() + 40);
  const StitchResult r = stitch(surface, to_trimesh(soup));
  EXPECT_FALSE(r.report.ok());
  EXPECT_EQ(r.report.n_rejected_triangles, 0u);
  EXPECT_FALSE(r.report.output.topology.is_closed);
  EXPECT_TRUE(mentions(r.report, "open")) << joined(r.report.errors);
  // Without the input only the intrinsic checks run, and an open mesh passes them.
  EXPECT_TRUE(stitch(surface).report.ok());
}

TEST(Stitch, FlippedTriangleIsAnError) {
  const TriangleSoup soup = test::icosphere(2);
  SurfaceMesh surface = cube_map_surface(soup);
  std::swap(surface.triangles[60][1], surface.triangles[60][2]);
  const StitchResult r = stitch(surface, to_trimesh(soup));
  EXPECT_FALSE(r.report.ok());
  EXPECT_GE(r.report.n_rejected_triangles, 1u);
  EXPECT_FALSE(stitch(surface).report.ok());
}

TEST(Stitch, MissingComponentIsAnError) {
  TriangleSoup two = test::icosphere(2);
  const TriangleSoup other = test::icosphere(2);
  const auto offset = static_cast<std::uint32_t>(two.points.size());
  for (const auto& p : other.points) two.points.push_back(p + Eigen::Vector3d(3, 0, 0));
  for (const auto& t : other.triangles) two.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const TriMesh input = to_trimesh(two);
  SurfaceMesh surface = cube_map_surface(two);
  EXPECT_TRUE(stitch(surface, input).report.ok());
  surface.triangles.resize(surface.triangles.size() / 2);
  surface.triangle_patch.resize(surface.triangles.size());
  const StitchResult r = stitch(surface, input);
  EXPECT_FALSE(r.report.ok());
  EXPECT_TRUE(mentions(r.report, "no counterpart")) << joined(r.report.errors);
  EXPECT_TRUE(mentions(r.report, "components")) << joined(r.report.errors);
}

TEST(Stitch, ComponentSignaturesCountEachComponent) {
  // A torus, an icosphere and an open grid, in that face order: chi 0, 2, 1.
  TriangleSoup s = test::torus(24, 12);
  auto append = [&](const TriangleSoup& other, const Eigen::Vector3d& offset) {
    const auto first = static_cast<std::uint32_t>(s.points.size());
    for (const auto& p : other.points) s.points.push_back(p + offset);
    for (const auto& t : other.triangles) s.triangles.push_back({t[0] + first, t[1] + first, t[2] + first});
  };
  const TriangleSoup sphere = test::icosphere(2);
  const TriangleSoup grid = test::grid_patch(5, 4);
  append(sphere, Eigen::Vector3d(5, 0, 0));
  append(grid, Eigen::Vector3d(0, 5, 0));
  const std::vector<ComponentSignature> c = component_signatures(to_trimesh(s));
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[0].euler_characteristic, 0);
  EXPECT_TRUE(c[0].is_closed);
  EXPECT_EQ(c[1].euler_characteristic, 2);
  EXPECT_TRUE(c[1].is_closed);
  EXPECT_EQ(c[1].n_faces, sphere.triangles.size());
  EXPECT_EQ(c[1].n_vertices, sphere.points.size());
  EXPECT_EQ(c[2].euler_characteristic, 1);
  EXPECT_FALSE(c[2].is_closed);
  EXPECT_EQ(c[2].n_faces, 40u);
  EXPECT_EQ(c[2].n_vertices, 30u);
  EXPECT_EQ(c[2].n_edges, 69u);
  EXPECT_NEAR(c[2].box.min.y(), 5.0, 1e-12);
  EXPECT_NEAR(c[1].box.min.x(), 4.0, 1e-6);
}

TEST(Stitch, MovesThroughANearbySheetAreUndone) {
  // Two parallel open sheets 0.002 apart; the upper one's surface is planted 0.002 below
  // the lower one, so projecting its inner nodes pushes them through the lower sheet.
  TriangleSoup sheets = test::grid_patch(8, 8);
  const TriangleSoup upper = test::grid_patch(8, 8);
  const auto offset = static_cast<std::uint32_t>(sheets.points.size());
  for (const auto& p : upper.points) sheets.points.push_back(p + Eigen::Vector3d(0, 0, 0.002));
  for (const auto& t : upper.triangles) sheets.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  std::vector<int> face_patch(sheets.triangles.size(), 0);
  std::fill(face_patch.begin() + static_cast<long>(face_patch.size() / 2), face_patch.end(), 1);
  SurfaceMesh surface = make_surface(sheets, face_patch, 2);
  const double local_z = surface.surfaces[1].frame.to_local(Eigen::Vector3d(0.5, 0.5, -0.002)).z();
  for (double& c : surface.surfaces[1].field.mutable_coefficients()) c = local_z;
  const TriMesh input = to_trimesh(sheets);
  StitchOptions unchecked;
  unchecked.check_self_intersections = false;
  const StitchResult pushed = stitch(surface, input, unchecked);
  EXPECT_GT(count_self_intersections(to_soup(pushed.mesh)), 0u);  // the planted defect works
  const StitchResult r = stitch(surface, input);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_TRUE(r.report.n_reverted_moves > 0 || r.report.optimisation_undone);
  ASSERT_TRUE(r.report.output.topology.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*r.report.output.topology.n_self_intersecting_pairs, 0u);
}

// Issue 5, DRAM cell at 256 cells: where one patch's fit is far off (steep where the input
// is not), a border node's smoothing target (the mean of its projections onto both fits)
// lies off the curve, and the move turned good triangles into needles. A move never takes
// the smallest angle of its triangles below min(old, angle_floor_deg).
TEST(Stitch, SmoothingMakesNoNewTriangleBelowTheAngleFloor) {
  const TriangleSoup sheet = test::grid_patch(8, 8);  // unit square, edges 1/8
  std::vector<int> face_patch(sheet.triangles.size());
  for (std::size_t t = 0; t < sheet.triangles.size(); ++t) {
    const auto& tri = sheet.triangles[t];
    face_patch[t] = (sheet.points[tri[0]] + sheet.points[tri[1]] + sheet.points[tri[2]]).x() < 1.5 ? 0 : 1;
  }
  SurfaceMesh surface = make_surface(sheet, face_patch, 2);
  // Patch 1's fit planted as a plane tilted by 30 deg about the curve's direction (y),
  // through (0.5, 0.5, -0.05): 0.4 edges off the sheet along its axis.
  PatchSurface& planted = surface.surfaces[1];
  planted.frame.axes = Eigen::AngleAxisd(M_PI / 6.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const double local_z = planted.frame.to_local(Eigen::Vector3d(0.5, 0.5, -0.05)).z();
  for (double& c : planted.field.mutable_coefficients()) c = local_z;
  const TriMesh input = to_trimesh(sheet);
  StitchOptions unguarded;
  unguarded.angle_floor_deg = 0.0;
  unguarded.angle_repair_rounds = 0;  // the smoothing's floor alone (the repair would mend them)
  const StitchResult bad = stitch(surface, input, unguarded);
  EXPECT_GT(bad.report.n_small_angle_away_from_features, 0u);  // the planted defect works
  StitchOptions assembled_only = without_optimisation();
  const StitchResult assembled = stitch(surface, input, assembled_only);
  ASSERT_EQ(assembled.report.n_small_angle_away_from_features, 0u);
  const StitchResult r = stitch(surface, input);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GT(r.report.n_smoothing_moves, 0u);
  EXPECT_EQ(r.report.n_small_angle_away_from_features, 0u);
  EXPECT_GE(r.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg);
  EXPECT_GE(r.report.output.quality.min_angle_deg,
            std::min(assembled.report.output.quality.min_angle_deg, 25.0));
}

// Issue 5, DRAM cell at 256 cells: two feature corners 0.001 h apart at the ends of a
// one-piece curve (a cup's rim) made 0.6 and 1.0 deg triangles that no move removes. A
// feature corner merges into a feature corner a hair away (under 0.05 h), which stays.
TEST(Stitch, FeatureCornersAHairApartMerge) {
  TriangleSoup sheet = test::grid_patch(8, 8);  // unit square, edges 1/8; node (i, j) is 9 j + i
  // Quadrants, the right ones split one row higher: corners a = (4, 4) (patches 0, 1, 3)
  // and b = (4, 5) (patches 0, 2, 3), joined by the one-edge curve between patches 0 and 3.
  std::vector<int> face_patch(sheet.triangles.size());
  for (std::size_t t = 0; t < sheet.triangles.size(); ++t) {
    const std::size_t cell = t / 2;
    const std::size_t i = cell % 8, j = cell / 8;
    face_patch[t] = i < 4 ? (j >= 4 ? 0 : 1) : (j >= 5 ? 2 : 3);
  }
  const int a = 9 * 4 + 4, b = 9 * 5 + 4;
  sheet.points[static_cast<std::size_t>(b)] =
      sheet.points[static_cast<std::size_t>(a)] + Eigen::Vector3d(0.0, 5e-4, 0.0);
  SurfaceMesh surface = make_surface(sheet, face_patch, 4);
  ASSERT_EQ(surface.node_kind[static_cast<std::size_t>(a)], NodeKind::Corner);
  ASSERT_EQ(surface.node_kind[static_cast<std::size_t>(b)], NodeKind::Corner);
  surface.target_size = 0.125;
  // Every curve a crease, with its nodes (order matters only for the one-piece curve a-b).
  std::map<std::pair<int, int>, std::vector<int>> curve_of_pair;
  for (std::size_t g = 0; g < surface.nodes.size(); ++g) {
    std::set<int> patches;
    for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
      for (int k : surface.triangles[t]) {
        if (k == static_cast<int>(g)) patches.insert(surface.triangle_patch[t]);
      }
    }
    const Eigen::Vector3d& x = surface.nodes[g];
    if (x.x() == 0.0 || x.x() == 1.0 || x.y() == 0.0 || x.y() == 1.0)
      patches.insert(-1);  // the sheet's boundary
    for (int p : patches) {
      for (int q : patches) {
        if (p < q) curve_of_pair[{p, q}].push_back(static_cast<int>(g));
      }
    }
  }
  surface.curve_nodes.clear();
  for (const auto& [pair, nodes] : curve_of_pair) {
    if (pair.first == 0 && pair.second == 3) {
      ASSERT_EQ(nodes, (std::vector<int>{a, b}));
    }
    surface.curve_nodes.push_back(nodes);
  }
  surface.curve_is_feature.assign(surface.curve_nodes.size(), 1);
  for (std::size_t g = 0; g < surface.nodes.size(); ++g) {
    if (surface.node_kind[g] != NodeKind::Border) continue;
    for (std::size_t c = 0; c < surface.curve_nodes.size(); ++c) {
      const auto& nodes = surface.curve_nodes[c];
      if (std::find(nodes.begin(), nodes.end(), static_cast<int>(g)) != nodes.end())
        surface.node_owner[g] = static_cast<int>(c);
    }
  }
  const TriMesh input = to_trimesh(sheet);
  StitchOptions off;
  off.collapse_below_angle_deg = 0.0;
  const StitchResult kept = stitch(surface, input, off);
  EXPECT_LT(kept.report.output.quality.min_angle_deg, 1.0);  // the planted defect works
  const StitchResult r = stitch(surface, input);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GE(r.report.n_collapses, 1u);
  EXPECT_GT(r.report.output.quality.min_angle_deg, 20.0);
  // One of the two corners is gone, the other is where it was; no other node moved (all
  // curves are creases, the sheet's inner nodes are already on their plane).
  int n_corners = 0;
  for (auto v : r.mesh.vertices()) {
    const auto g = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())]);
    if (g == static_cast<std::size_t>(a) || g == static_cast<std::size_t>(b)) {
      ++n_corners;
      EXPECT_EQ(to_eigen(r.mesh.point(v)), surface.nodes[g]);
    }
  }
  EXPECT_EQ(n_corners, 1);
  // Two crease corners further apart (0.1 h) stay apart.
  sheet.points[static_cast<std::size_t>(b)] =
      sheet.points[static_cast<std::size_t>(a)] + Eigen::Vector3d(0.0, 0.0125, 0.0);
  surface.nodes[static_cast<std::size_t>(b)] = sheet.points[static_cast<std::size_t>(b)];
  const StitchResult apart = stitch(surface, to_trimesh(sheet));
  int n_apart = 0;
  for (auto v : apart.mesh.vertices()) {
    const int g = apart.vertex_node[static_cast<std::size_t>(v.idx())];
    n_apart += g == a || g == b ? 1 : 0;
  }
  EXPECT_EQ(n_apart, 2);
}

TEST(Stitch, OnlyTheOffendingMovesAreUndone) {
  // The two sheets of the test above (the upper one pushed through the lower one) and a
  // third, jittered sheet far away whose smoothing moves are harmless: they must stay.
  TriangleSoup sheets = test::grid_patch(8, 8);
  const TriangleSoup grid = test::grid_patch(8, 8);
  auto append = [&](const Eigen::Vector3d& offset, double jitter) {
    const auto first = static_cast<std::uint32_t>(sheets.points.size());
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-jitter, jitter);
    for (const auto& p : grid.points) {
      const bool inner = p.x() > 1e-9 && p.x() < 1 - 1e-9 && p.y() > 1e-9 && p.y() < 1 - 1e-9;
      sheets.points.push_back(p + offset + (inner ? Eigen::Vector3d(u(rng), u(rng), 0.0) : Eigen::Vector3d::Zero()));
    }
    for (const auto& t : grid.triangles) sheets.triangles.push_back({t[0] + first, t[1] + first, t[2] + first});
  };
  append(Eigen::Vector3d(0, 0, 0.002), 0.0);
  append(Eigen::Vector3d(0, 0, 5.0), 0.03);
  const std::size_t n_grid = grid.triangles.size();
  std::vector<int> face_patch(sheets.triangles.size(), 0);
  std::fill(face_patch.begin() + static_cast<long>(n_grid), face_patch.end(), 1);
  std::fill(face_patch.begin() + static_cast<long>(2 * n_grid), face_patch.end(), 2);
  SurfaceMesh surface = make_surface(sheets, face_patch, 3);
  const double local_z = surface.surfaces[1].frame.to_local(Eigen::Vector3d(0.5, 0.5, -0.002)).z();
  for (double& c : surface.surfaces[1].field.mutable_coefficients()) c = local_z;
  const StitchResult r = stitch(surface, to_trimesh(sheets));
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_FALSE(r.report.optimisation_undone);
  EXPECT_GT(r.report.n_reverted_moves, 0u);
  ASSERT_TRUE(r.report.output.topology.n_self_intersecting_pairs.has_value());
  EXPECT_EQ(*r.report.output.topology.n_self_intersecting_pairs, 0u);
  // The third sheet's nodes moved and stayed moved.
  std::size_t n_moved = 0;
  for (auto v : r.mesh.vertices()) {
    const auto node = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())]);
    if (node >= sheets.points.size()) continue;  // an obtuse split's
    if (node >= 2 * grid.points.size() && (to_eigen(r.mesh.point(v)) - sheets.points[node]).norm() > 1e-9) ++n_moved;
  }
  EXPECT_GT(n_moved, 10u);
}

TEST(Stitch, ACollapseThroughANearbySheetIsUndone) {
  // A grid of two patches (x < 0.5, x > 0.5): the border node w = (0.5, 0.5) dips 0.01
  // below the grid and the inner node v = (0.625, 0.5) sits 0.01 beside it, so the
  // triangles at v are needles and v merges into w (an inner node into a border node, w
  // stays). v's fan then slopes down to w and passes through a small sheet 0.004 below the
  // grid that nothing crosses before: the collapse is undone and the mesh is the one
  // assembled without collapses.
  TriangleSoup soup = test::grid_patch(8, 8);
  const std::uint32_t w = 4 * 9 + 4, v = 4 * 9 + 5;
  soup.points[w].z() = -0.01;
  soup.points[v] = Eigen::Vector3d(0.51, 0.5, 0.0);
  std::vector<int> face_patch(soup.triangles.size(), 0);
  for (std::size_t t = 0; t < soup.triangles.size(); ++t) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const std::uint32_t k : soup.triangles[t]) c += test::grid_patch(8, 8).points[k];
    face_patch[t] = c.x() / 3.0 > 0.5 ? 1 : 0;
  }
  const auto offset = static_cast<std::uint32_t>(soup.points.size());
  soup.points.emplace_back(0.56, 0.47, -0.004);
  soup.points.emplace_back(0.74, 0.47, -0.004);
  soup.points.emplace_back(0.65, 0.53, -0.004);
  soup.triangles.push_back({offset, offset + 1, offset + 2});
  face_patch.push_back(2);
  ASSERT_EQ(count_self_intersections(soup), 0u);
  const SurfaceMesh surface = make_surface(soup, face_patch, 3);
  ASSERT_EQ(surface.node_kind[w], NodeKind::Border);
  ASSERT_EQ(surface.node_kind[v], NodeKind::Inner);
  const TriMesh input = to_trimesh(soup);
  StitchOptions off;
  off.collapse_below_angle_deg = 0.0;
  const StitchResult plain = stitch(surface, input, off);
  const StitchResult r = stitch(surface, input);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GT(r.report.n_collapses_undone, 0u);
  EXPECT_EQ(r.report.n_collapses, 0u);
  ASSERT_EQ(r.mesh.n_vertices(), plain.mesh.n_vertices());
  ASSERT_EQ(r.mesh.n_faces(), plain.mesh.n_faces());
  EXPECT_EQ(r.vertex_node, plain.vertex_node);
  EXPECT_EQ(r.face_patch, plain.face_patch);
  for (auto u : r.mesh.vertices()) EXPECT_EQ(r.mesh.point(u), plain.mesh.point(u));
  const TriangleSoup a = to_soup(r.mesh), b = to_soup(plain.mesh);
  EXPECT_EQ(a.triangles, b.triangles);
  // The planted defect works: with the small sheet out of the way the collapse is kept.
  TriangleSoup away = soup;
  for (std::uint32_t k = offset; k < offset + 3; ++k) away.points[k].y() += 2.0;
  const StitchResult kept = stitch(make_surface(away, face_patch, 3), to_trimesh(away));
  EXPECT_TRUE(kept.report.ok()) << joined(kept.report.errors);
  EXPECT_GE(kept.report.n_collapses, 1u);
  EXPECT_EQ(kept.report.n_collapses_undone, 0u);
}

TEST(Stitch, SettleFlipsAValleyOutOfASmallSheet) {
  // One grid cell a b c d with b and d raised 0.1: the input splits it along b-d (a ridge),
  // the patch mesh along a-c (a valley), and a thin sheet at 0.03 above a-c's midpoint,
  // along b-d, lies under the ridge but crosses the valley. No optimisation: the assembled
  // crossing is left to the settle, whose flip of a-c removes it.
  TriangleSoup valley = test::grid_patch(8, 8);
  const std::uint32_t a = 4 * 9 + 4, b = 4 * 9 + 5, c = 5 * 9 + 5, d = 5 * 9 + 4;
  valley.points[b].z() = 0.1;
  valley.points[d].z() = 0.1;
  const auto offset = static_cast<std::uint32_t>(valley.points.size());
  const Eigen::Vector3d centre(0.5625, 0.5625, 0.03), along(-0.5, 0.5, 0.0), across(0.5, 0.5, 0.0);
  valley.points.push_back(centre + 0.06 * along - 0.01 * across);
  valley.points.push_back(centre - 0.06 * along - 0.01 * across);
  valley.points.push_back(centre + 0.01 * across);
  valley.triangles.push_back({offset, offset + 1, offset + 2});
  std::vector<int> face_patch(valley.triangles.size(), 0);
  face_patch.back() = 1;
  TriangleSoup ridge = valley;
  std::size_t n_replaced = 0;
  for (auto& t : ridge.triangles) {
    if (t == std::array<std::uint32_t, 3>{a, b, c}) t = {a, b, d}, ++n_replaced;
    else if (t == std::array<std::uint32_t, 3>{a, c, d}) t = {b, c, d}, ++n_replaced;
  }
  ASSERT_EQ(n_replaced, 2u);
  ASSERT_EQ(count_self_intersections(ridge), 0u);
  ASSERT_GT(count_self_intersections(valley), 0u);
  StitchOptions options = without_optimisation();
  options.collapse_below_angle_deg = 0.0;
  const StitchResult r = stitch(make_surface(valley, face_patch, 2), to_trimesh(ridge), options);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GE(r.report.n_settled_flips, 1u);
  EXPECT_EQ(count_self_intersections(to_soup(r.mesh)), 0u);
  EXPECT_TRUE(r.mesh.find_halfedge(TriMesh::VertexHandle(static_cast<int>(b)), TriMesh::VertexHandle(static_cast<int>(d))).is_valid());
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 1 + 1);
}

TEST(Stitch, IntersectionsOfTheInputStayReportedAndKeepTheOptimisation) {
  // A horizontal and a vertical sheet crossing each other: intersecting before any move.
  TriangleSoup sheets = test::grid_patch(8, 8);
  const TriangleSoup wall = test::grid_patch(8, 8);
  const auto offset = static_cast<std::uint32_t>(sheets.points.size());
  for (const auto& p : wall.points) sheets.points.push_back(Eigen::Vector3d(p.x() + 0.03, 0.51, p.y() - 0.5));
  for (const auto& t : wall.triangles) sheets.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  std::vector<int> face_patch(sheets.triangles.size(), 0);
  std::fill(face_patch.begin() + static_cast<long>(face_patch.size() / 2), face_patch.end(), 1);
  const StitchResult r = stitch(make_surface(sheets, face_patch, 2), to_trimesh(sheets));
  EXPECT_FALSE(r.report.ok());
  EXPECT_TRUE(mentions(r.report, "self-intersecting")) << joined(r.report.errors);
  EXPECT_FALSE(r.report.optimisation_undone);
}

TEST(Stitch, InvalidInputThrows) {
  const TriangleSoup soup = test::icosphere(1);
  SurfaceMesh surface = cube_map_surface(soup);
  SurfaceMesh bad = surface;
  bad.triangles[0][1] = int(bad.nodes.size());
  EXPECT_THROW((void)stitch(bad), InvalidInput);
  bad = surface;
  bad.triangle_patch.pop_back();
  EXPECT_THROW((void)stitch(bad), InvalidInput);
  bad = surface;
  bad.nodes[3].x() = std::nan("");
  EXPECT_THROW((void)stitch(bad), InvalidInput);
  StitchOptions options;
  options.max_flip_dihedral_deg = 180.0;
  EXPECT_THROW((void)stitch(surface, options), InvalidInput);
  options = {};
  options.smoothing_relaxation = 0.0;
  EXPECT_THROW((void)stitch(surface, options), InvalidInput);
  options = {};
  options.collapse_below_angle_deg = 60.0;
  EXPECT_THROW((void)stitch(surface, options), InvalidInput);
  options = {};
  options.angle_repair_rounds = -1;
  EXPECT_THROW((void)stitch(surface, options), InvalidInput);
}

// stitch_with_input_index() checks that the index is the input's (its sizes) before any work:
// another mesh's index, or one missing a triangle, throws; the input's own does not.
TEST(Stitch, InputIndexOfAnotherMeshThrows) {
  const TriangleSoup soup = test::icosphere(1);
  const SurfaceMesh surface = cube_map_surface(soup);
  const TriMesh input = to_trimesh(soup);
  StitchOptions options;
  options.fidelity_distance_edges = 0.25;
  const quality_detail::IndexedSoup other(to_soup(to_trimesh(test::icosphere(2))), 1);
  EXPECT_THROW((void)stitch_detail::stitch_with_input_index(surface, input, other, options), InvalidInput);
  TriangleSoup short_soup = to_soup(input);
  short_soup.triangles.pop_back();
  const quality_detail::IndexedSoup missing(std::move(short_soup), 1);
  EXPECT_THROW((void)stitch_detail::stitch_with_input_index(surface, input, missing, options), InvalidInput);
  const quality_detail::IndexedSoup own(to_soup(input), 1);
  EXPECT_NO_THROW((void)stitch_detail::stitch_with_input_index(surface, input, own, options));
}

TEST(Stitch, ProgressCanCancel) {
  const TriangleSoup soup = test::icosphere(2);
  const SurfaceMesh surface = cube_map_surface(soup);
  StitchOptions options;
  std::set<std::string> stages;
  options.progress = [&](std::string_view stage, double) {
    stages.insert(std::string(stage));
    return true;
  };
  (void)stitch(surface, options);
  EXPECT_TRUE(stages.count("stitch: assemble"));
  EXPECT_TRUE(stages.count("stitch: optimise"));
  EXPECT_TRUE(stages.count("stitch: verify"));
  options.progress = [](std::string_view stage, double) { return stage != "stitch: optimise"; };
  EXPECT_THROW((void)stitch(surface, options), Cancelled);
}

}  // namespace

// Issue 5, two-step changes: three nodes near a corner of the cube-map sphere (patches of
// one axis each, every corner a feature corner) pulled toward a neighbour, one of them to
// 0.023 of its distance (found by a seeded search over such plantings, session 11). Some
// triangle below 25 deg there has no single flip, collapse or move that is better; a pair is,
// and the repair ends with none below 25 deg and a valid mesh.
TEST(Stitch, AngleRepairMakesAPairOfChangesWhereNoSingleOneHelps) {
  TriangleSoup soup = test::icosphere(3);
  SurfaceMesh surface = cube_map_surface(soup);
  ASSERT_EQ(surface.nodes.size(), 642u);
  ASSERT_EQ(surface.node_kind[603], NodeKind::Corner);
  const std::array<std::tuple<int, int, double>, 3> pulls{{{594, 153, 0.35108247410866811},
                                                           {37, 589, 0.022960170366147139},
                                                           {605, 603, 0.42551306213699386}}};
  for (const auto& [v, toward, t] : pulls) {
    surface.nodes[v] = (surface.nodes[toward] + t * (surface.nodes[v] - surface.nodes[toward])).normalized();
    soup.points[v] = surface.nodes[v];
  }
  const StitchResult off = stitch_with_angle_repair(surface, soup, 0);
  ASSERT_GE(off.report.n_small_angle_away_from_features, 3u);
  const StitchResult r = stitch_with_angle_repair(surface, soup, 4);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GE(r.report.n_angle_two_steps, 1u);
  EXPECT_EQ(r.report.n_small_angle_away_from_features, 0u);
  EXPECT_GE(r.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg);
  EXPECT_EQ(r.report.n_angle_repairs_undone, 0u);
  const TopologyReport& topology = r.report.output.topology;
  EXPECT_TRUE(topology.is_closed);
  EXPECT_TRUE(topology.is_manifold);
  EXPECT_TRUE(topology.is_consistently_oriented);
  EXPECT_EQ(topology.euler_characteristic, 2);
  EXPECT_EQ(topology.n_self_intersecting_pairs.value_or(1), 0u);
  EXPECT_EQ(r.face_patch.size(), r.mesh.n_faces());
  EXPECT_EQ(r.vertex_node.size(), r.mesh.n_vertices());
  EXPECT_EQ(r.mesh.n_vertices() + r.report.n_unused_nodes + r.report.n_angle_collapses + r.report.n_obtuse_collapses,
            surface.nodes.size());
  // Every node stays on the sphere (moves go onto the patches' fits, collapses keep the survivor).
  for (auto u : r.mesh.vertices()) EXPECT_NEAR(to_eigen(r.mesh.point(u)).norm(), 1.0, 0.02);
}

// Issue 5, the step search (AngleRepair::search_move): a node of the cube-map sphere pulled
// toward a neighbour (to 0.466 of its distance; found by a seeded search over such
// plantings, session 13) under an input far finer than the output (input mean edge 0.00075,
// the sphere's edges about 0.15: the repair's collapses and moves must stay within half an
// input mean edge of the old triangles). One triangle is below 25 deg; the search runs only
// where no flip, collapse, move_gain place or pair of changes is better, and here its small
// steps on the fits lift the triangle over the bound: every change the repair makes is one
// of the search's.
TEST(Stitch, AngleRepairStepSearchLiftsATriangleWhereNoOtherChangeHelps) {
  TriangleSoup soup = test::icosphere(3);
  ASSERT_EQ(cube_map_surface(soup).node_kind[377], NodeKind::Inner);
  soup.points[377] = (soup.points[616] + 0.46576536456057949 * (soup.points[377] - soup.points[616])).normalized();
  SurfaceMesh surface = cube_map_surface(soup);
  surface.input_mean_edge = 0.00075;
  const StitchResult off = stitch_with_angle_repair(surface, soup, 0);
  ASSERT_GE(off.report.n_small_angle_away_from_features, 1u);
  ASSERT_LT(off.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg);
  const StitchResult r = stitch_with_angle_repair(surface, soup, 4);
  EXPECT_TRUE(r.report.ok()) << joined(r.report.errors);
  EXPECT_GE(r.report.n_angle_searches, 1u);
  EXPECT_EQ(r.report.n_angle_moves, r.report.n_angle_searches);
  EXPECT_EQ(r.report.n_angle_flips + r.report.n_angle_collapses + r.report.n_angle_two_steps, 0u);
  EXPECT_EQ(r.report.n_small_angle_away_from_features, 0u);
  EXPECT_GE(r.report.min_angle_away_from_features_deg, kAwayFromFeaturesAngleBoundDeg);
  EXPECT_EQ(r.report.n_angle_repairs_undone, 0u);
  const TopologyReport& topology = r.report.output.topology;
  EXPECT_TRUE(topology.is_closed);
  EXPECT_TRUE(topology.is_manifold);
  EXPECT_EQ(topology.euler_characteristic, 2);
  EXPECT_EQ(topology.n_self_intersecting_pairs.value_or(1), 0u);
  EXPECT_EQ(r.mesh.n_vertices(), off.mesh.n_vertices());
  // The moved nodes stay on the fits (the sphere).
  for (auto u : r.mesh.vertices()) EXPECT_NEAR(to_eigen(r.mesh.point(u)).norm(), 1.0, 0.02);
}

}  // namespace nurbsfront

namespace nurbsfront {
namespace {

// The report's away-from-features set leaves out the triangles at a fin rim node (a crease of
// the input that stitch may move within a bound: docs/pipeline.md "Report"), and counts them
// apart. Unit square, edges h = 1/8, node (i, j) = 9 j + i; patches left and right of x = 1/2,
// the curve between them (nodes (4, 1..7), corners (4, 0) and (4, 8)) a fin rim; the square's
// boundary is a feature. Two slivers planted the same way: the rim node (4, 4) and the inner
// node (2, 2) moved 0.8 of the way to (5, 5) and (3, 3). Each leaves six triangles inside the
// boundary ring below 25 deg: two at atan(1/4) = 14.036 deg, four at 21.04 deg. The ring
// holds 56 triangles, the columns i = 3, 4 inside it 24 (at the rim), the rest 48.
TEST(Stitch, TrianglesAtFinRimNodesAreNotAwayFromFeatures) {
  TriangleSoup sheet = test::grid_patch(8, 8);
  std::vector<int> face_patch(sheet.triangles.size());
  for (std::size_t t = 0; t < sheet.triangles.size(); ++t) {
    const auto& tri = sheet.triangles[t];
    face_patch[t] = (sheet.points[tri[0]] + sheet.points[tri[1]] + sheet.points[tri[2]]).x() < 1.5 ? 0 : 1;
  }
  const double h = 0.125;
  auto id = [](int i, int j) { return static_cast<std::size_t>(9 * j + i); };
  sheet.points[id(4, 4)] += Eigen::Vector3d(0.8 * h, 0.8 * h, 0.0);
  sheet.points[id(2, 2)] += Eigen::Vector3d(0.8 * h, 0.8 * h, 0.0);
  SurfaceMesh surface = make_surface(sheet, face_patch, 2);
  surface.target_size = h;
  // Curves: their border nodes, then both corners (each ends all three curves).
  surface.curve_nodes.assign(surface.curve_is_feature.size(), {});
  for (std::size_t g = 0; g < surface.nodes.size(); ++g) {
    if (surface.node_kind[g] == NodeKind::Border)
      surface.curve_nodes[static_cast<std::size_t>(surface.node_owner[g])].push_back(static_cast<int>(g));
  }
  for (auto& nodes : surface.curve_nodes) {
    nodes.insert(nodes.begin(), static_cast<int>(id(4, 0)));
    nodes.push_back(static_cast<int>(id(4, 8)));
  }
  const int rim_curve = surface.node_owner[id(4, 1)];
  ASSERT_EQ(surface.curve_is_feature[static_cast<std::size_t>(rim_curve)], 0);
  ASSERT_EQ(surface.curve_nodes[static_cast<std::size_t>(rim_curve)].size(), 9u);
  const TriMesh input = to_trimesh(sheet);
  StitchOptions as_assembled = without_optimisation();  // no stage moves, flips, collapses or splits
  as_assembled.volume_compensation = 0.0;
  as_assembled.obtuse_split_rounds = 0;
  as_assembled.angle_repair_rounds = 0;
  as_assembled.collapse_below_angle_deg = 0.0;
  const double sliver = std::atan(0.25) * 180.0 / M_PI;

  // A smooth border: every triangle off the boundary ring is away from features.
  const StitchResult smooth = stitch(surface, input, as_assembled);
  ASSERT_TRUE(smooth.report.ok()) << joined(smooth.report.errors);
  ASSERT_EQ(smooth.mesh.n_faces(), 128u);
  EXPECT_EQ(smooth.report.n_away_from_features, 72u);
  EXPECT_EQ(smooth.report.n_small_angle_away_from_features, 12u);
  EXPECT_NEAR(smooth.report.min_angle_away_from_features_deg, sliver, 1e-9);
  EXPECT_EQ(smooth.report.n_at_fin_rims, 0u);
  EXPECT_EQ(smooth.report.n_small_angle_at_fin_rims, 0u);
  EXPECT_EQ(smooth.report.min_angle_at_fin_rims_deg, 0.0);

  // A fin rim: the triangles at its nodes are counted apart, the others as before.
  surface.curve_is_fin_rim.assign(surface.curve_is_feature.size(), 0);
  surface.curve_is_fin_rim[static_cast<std::size_t>(rim_curve)] = 1;
  for (const double bound : {std::numeric_limits<double>::infinity(), 1.0}) {
    StitchOptions options = as_assembled;
    options.fin_rim_max_move = bound;
    const StitchResult rim = stitch(surface, input, options);
    ASSERT_TRUE(rim.report.ok()) << joined(rim.report.errors);
    EXPECT_EQ(rim.report.n_away_from_features, 48u) << "bound " << bound;
    EXPECT_EQ(rim.report.n_small_angle_away_from_features, 6u) << "bound " << bound;
    EXPECT_NEAR(rim.report.min_angle_away_from_features_deg, sliver, 1e-9);
    EXPECT_EQ(rim.report.n_at_fin_rims, 24u) << "bound " << bound;
    EXPECT_EQ(rim.report.n_small_angle_at_fin_rims, 6u) << "bound " << bound;
    EXPECT_NEAR(rim.report.min_angle_at_fin_rims_deg, sliver, 1e-9);
  }

  // Without the planted sliver at (2, 2) nothing away from features is below 25 deg.
  sheet.points[id(2, 2)] -= Eigen::Vector3d(0.8 * h, 0.8 * h, 0.0);
  surface.nodes[id(2, 2)] = sheet.points[id(2, 2)];
  const StitchResult clean = stitch(surface, to_trimesh(sheet), as_assembled);
  ASSERT_TRUE(clean.report.ok()) << joined(clean.report.errors);
  EXPECT_EQ(clean.report.n_small_angle_away_from_features, 0u);
  EXPECT_NEAR(clean.report.min_angle_away_from_features_deg, 45.0, 1e-9);
  EXPECT_EQ(clean.report.n_small_angle_at_fin_rims, 6u);
}

}  // namespace
}  // namespace nurbsfront
