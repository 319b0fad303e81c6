// SPDX-License-Identifier: BSD-3-Clause
// The stitch's feature slides (StitchOptions::feature_slide_rounds; docs/stitch.md "Feature
// nodes sliding along their curves") on a hand-made strip between two crease curves.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <initializer_list>
#include <limits>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/stitch/stitch.h"
#include "patch_fits.h"

namespace nurbsfront {
namespace {

// Appends the triangle (u, v, w) of patch p to the soup, ordered so that its normal points
// along `up` (the patch's outward side).
void add_facing_triangle(TriangleSoup& soup, std::vector<int>& face_patch, int p, int u, int v, int w,
                         const Eigen::Vector3d& up) {
  const auto& q = soup.points;
  const double side = (q[static_cast<std::size_t>(v)] - q[static_cast<std::size_t>(u)])
                          .cross(q[static_cast<std::size_t>(w)] - q[static_cast<std::size_t>(u)])
                          .dot(up);
  if (side < 0.0) std::swap(v, w);
  soup.triangles.push_back({static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(v), static_cast<std::uint32_t>(w)});
  face_patch.push_back(p);
}

// The SurfaceMesh of a hand-made soup whose curves (m.curve_nodes, m.curve_is_feature) are
// set: its nodes and triangles, every node a border node of the curve listing it last, the
// given corners, and each of the n_patches patches fitted over its own faces.
void finish_surface(SurfaceMesh& m, const TriangleSoup& soup, const std::vector<int>& face_patch,
                    const std::vector<int>& corners, int n_patches) {
  m.nodes = soup.points;
  for (const auto& t : soup.triangles) m.triangles.push_back({int(t[0]), int(t[1]), int(t[2])});
  m.triangle_patch = face_patch;
  m.node_kind.assign(m.nodes.size(), NodeKind::Border);
  m.node_owner.assign(m.nodes.size(), -1);
  for (std::size_t c = 0; c < m.curve_nodes.size(); ++c) {
    for (const int node : m.curve_nodes[c]) m.node_owner[static_cast<std::size_t>(node)] = static_cast<int>(c);
  }
  for (const int node : corners) {
    m.node_kind[static_cast<std::size_t>(node)] = NodeKind::Corner;
    m.node_owner[static_cast<std::size_t>(node)] = -1;
  }
  m.n_border_nodes = m.nodes.size();
  m.surfaces = test::fit_patches(soup, face_patch, n_patches, 3);
  m.patches.resize(static_cast<std::size_t>(n_patches));
  m.target_size = 1.0;
  m.input_mean_edge = 1.0;
}

// A U-shaped open surface, turned by a generic rotation: a flat strip (patch 0, width 0.8)
// between two straight crease curves A and B (90 deg to the walls) whose nodes face each other
// one piece (1) apart, those of B shifted by +-0.1 from A's, so that each quad of the strip
// has an angle above 90 deg on either diagonal; two walls (patches 1 and 2) hang from the
// creases, their bottom rows staggered (acute triangles). The strip's ends and the walls'
// bottoms are the input's boundary. Corners: the creases' ends. Every curve's node list is
// set (SurfaceMesh::curve_nodes).
struct Strip {
  static constexpr int kPieces = 6;
  TriangleSoup soup;
  std::vector<int> face_patch;
  SurfaceMesh surface;
  std::vector<int> a, b, wall_a, wall_b;  // node ids: creases A and B; the walls' bottoms
  std::vector<int> corners;
};

Strip make_strip() {
  Strip s;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  constexpr double kWidth = 0.8, kDepth = 0.87;
  auto add = [&](double x, double y, double z) {
    s.soup.points.push_back(turn * Eigen::Vector3d(x, y, z));
    return static_cast<int>(s.soup.points.size()) - 1;
  };
  for (int i = 0; i <= Strip::kPieces; ++i) s.a.push_back(add(i, 0.0, 0.0));
  for (int i = 0; i <= Strip::kPieces; ++i) {
    const double shift = i == 0 || i == Strip::kPieces ? 0.0 : (i % 2 == 1 ? 0.1 : -0.1);
    s.b.push_back(add(i + shift, kWidth, 0.0));
  }
  // Bottom rows: under the ends and under the middles of the creases' pieces.
  for (const double y : {0.0, kWidth}) {
    std::vector<int>& row = y == 0.0 ? s.wall_a : s.wall_b;
    row.push_back(add(-0.1, y, -kDepth));
    for (int j = 1; j <= Strip::kPieces; ++j) row.push_back(add(j - 0.5, y, -kDepth));
    row.push_back(add(Strip::kPieces + 0.1, y, -kDepth));
  }
  // Triangles, each oriented along its patch's outward normal (+z, -y, +y before the turn).
  auto tri = [&](int p, int u, int v, int w) {
    const Eigen::Vector3d local(0.0, p == 0 ? 0.0 : (p == 1 ? -1.0 : 1.0), p == 0 ? 1.0 : 0.0);
    add_facing_triangle(s.soup, s.face_patch, p, u, v, w, turn * local);
  };
  for (int i = 0; i < Strip::kPieces; ++i) {
    tri(0, s.a[i], s.a[i + 1], s.b[i + 1]);
    tri(0, s.a[i], s.b[i + 1], s.b[i]);
  }
  for (int p = 1; p <= 2; ++p) {
    const std::vector<int>& top = p == 1 ? s.a : s.b;
    const std::vector<int>& row = p == 1 ? s.wall_a : s.wall_b;
    for (int j = 0; j <= Strip::kPieces; ++j) tri(p, top[j], row[j], row[j + 1]);
    for (int j = 0; j < Strip::kPieces; ++j) tri(p, top[j], top[j + 1], row[j + 1]);
  }
  // The SurfaceMesh: curves 0 (A) and 1 (B) are creases, 2 and 3 the walls' boundaries
  // (from a crease's end along the bottom to its other end).
  SurfaceMesh& m = s.surface;
  m.curve_is_feature = {1, 1, 1, 1};
  m.curve_nodes = {s.a, s.b, {}, {}};
  for (int c = 2; c <= 3; ++c) {
    const std::vector<int>& top = c == 2 ? s.a : s.b;
    std::vector<int>& list = m.curve_nodes[static_cast<std::size_t>(c)];
    list.push_back(top.front());
    const std::vector<int>& row = c == 2 ? s.wall_a : s.wall_b;
    list.insert(list.end(), row.begin(), row.end());
    list.push_back(top.back());
  }
  s.corners = {s.a.front(), s.a.back(), s.b.front(), s.b.back()};
  finish_surface(m, s.soup, s.face_patch, s.corners, 3);
  return s;
}

// Distance from p to the polyline through `points`.
double distance_to_polyline(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& points) {
  double best = (p - points.front()).norm();
  for (std::size_t i = 0; i + 1 < points.size(); ++i) {
    const Eigen::Vector3d d = points[i + 1] - points[i];
    const double u = std::clamp((p - points[i]).dot(d) / d.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (p - (points[i] + u * d)).norm());
  }
  return best;
}

std::size_t obtuse_faces(const StitchResult& r, int only_patch = -1) {
  std::size_t n = 0;
  for (auto f : r.mesh.faces()) {
    if (only_patch >= 0 && r.face_patch[static_cast<std::size_t>(f.idx())] != only_patch) continue;
    std::array<Eigen::Vector3d, 3> p;
    int k = 0;
    for (auto v : r.mesh.fv_range(f)) p[static_cast<std::size_t>(k++)] = to_eigen(r.mesh.point(v));
    for (int i = 0; i < 3; ++i) {
      if ((p[(i + 1) % 3] - p[i]).dot(p[(i + 2) % 3] - p[i]) < 0.0) ++n;
    }
  }
  return n;
}

StitchOptions strip_options(int slide_rounds) {
  StitchOptions o;
  o.feature_slide_rounds = slide_rounds;
  o.obtuse_split_rounds = 0;  // the slides alone (splits would add nodes)
  // Nor the flips of the chords from the strip's corners across it (flip_feature_chords):
  // with them this strip keeps 5 obtuse triangles without slides (6 without both) and 3 with
  // two rounds of slides (0 without the chord flips; docs/stitch.md "Chords between the
  // nodes of a crease, session 19").
  o.flip_feature_chords = false;
  o.n_threads = 1;
  return o;
}

// The strip's facing nodes leave obtuse triangles that no flip or move removes (all its
// nodes are feature nodes); sliding them along their creases staggers them: no obtuse
// triangle is left in the strip and fewer in all, every slid node lies on its curve's
// polyline (the front's nodes), the corners stay, the surface keeps its topology.
TEST(StitchSlide, FacingCreaseNodesSlideApartAlongTheirCurves) {
  const Strip s = make_strip();
  const TriMesh input = to_trimesh(s.soup);
  const StitchResult before = stitch(s.surface, input, strip_options(0));
  ASSERT_TRUE(before.report.ok());
  ASSERT_GT(obtuse_faces(before, 0), 0u);  // the planted defect survives flips and repair
  EXPECT_EQ(before.report.n_feature_slides, 0u);
  const StitchResult r = stitch(s.surface, input, strip_options(2));
  ASSERT_TRUE(r.report.ok());
  EXPECT_GT(r.report.n_feature_slides, 0u);
  EXPECT_EQ(obtuse_faces(r, 0), 0u);
  EXPECT_LT(obtuse_faces(r), obtuse_faces(before));
  EXPECT_TRUE(r.report.output.topology.is_manifold);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 1);
  EXPECT_EQ(r.report.output.topology.n_boundary_loops, 1u);
  ASSERT_EQ(r.mesh.n_vertices(), s.soup.points.size());
  const double scale = 1e-12 * Strip::kPieces;
  std::size_t n_moved = 0;
  for (auto v : r.mesh.vertices()) {
    const auto node = static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())]);
    const Eigen::Vector3d p = to_eigen(r.mesh.point(v));
    if (std::find(s.corners.begin(), s.corners.end(), static_cast<int>(node)) != s.corners.end()) {
      EXPECT_EQ(p, s.soup.points[node]) << "corner " << node;
      continue;
    }
    if (p == s.soup.points[node]) continue;
    ++n_moved;
    const int curve = s.surface.node_owner[node];
    ASSERT_GE(curve, 0);
    std::vector<Eigen::Vector3d> polyline;
    for (const int g : s.surface.curve_nodes[static_cast<std::size_t>(curve)]) polyline.push_back(s.soup.points[static_cast<std::size_t>(g)]);
    EXPECT_LT(distance_to_polyline(p, polyline), scale) << "node " << node;
    // Not past the middle of a piece: the node stays nearer its own front point than the
    // neighbours' (its curve's order is kept).
    EXPECT_LT((p - s.soup.points[node]).norm(), 0.5 * 1.2) << "node " << node;
  }
  EXPECT_GT(n_moved, 0u);
  // The same for any thread count.
  StitchOptions two = strip_options(2);
  two.n_threads = 3;
  const StitchResult r3 = stitch(s.surface, input, two);
  ASSERT_EQ(r3.mesh.n_vertices(), r.mesh.n_vertices());
  for (auto v : r.mesh.vertices()) EXPECT_EQ(to_eigen(r3.mesh.point(v)), to_eigen(r.mesh.point(v)));
}

// StitchOptions::flip_feature_chords (docs/stitch.md "Chords between the nodes of a crease,
// session 19"): a flat patch 0 above a crease K (corner k0, nodes k1, k2, corner k3; k1 dips
// 0.25 below the line) whose chord k0-k2 closes the triangle (k0, k1, k2), obtuse at k1
// (152 deg); a wall (patch 1) hangs from K, the rest is the input's boundary, so every node is
// fixed and only a flip can help. The chord is no piece of K but both its ends are on K: it
// was locked like K's pieces. With the option it flips to k1-c: no obtuse triangle, K's pieces
// kept; without it the obtuse triangle stays.
struct ChordFan {
  TriangleSoup soup;
  SurfaceMesh surface;
  std::vector<int> k, wall;
  int c = -1, t = -1;
};

ChordFan make_chord_fan() {
  ChordFan s;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.4, Eigen::Vector3d(3.0, -1.0, 2.0).normalized()).toRotationMatrix();
  auto add = [&](double x, double y, double z) {
    s.soup.points.push_back(turn * Eigen::Vector3d(x, y, z));
    return static_cast<int>(s.soup.points.size()) - 1;
  };
  const std::array<std::array<double, 2>, 4> ks{{{0.0, 0.0}, {1.0, -0.25}, {2.0, 0.0}, {3.0, 0.0}}};
  for (const auto& q : ks) s.k.push_back(add(q[0], q[1], 0.0));
  // The wall's bottom row under K's ends and the middles of its pieces (acute triangles).
  const std::array<std::array<double, 2>, 5> ws{{{-0.1, 0.0}, {0.5, -0.125}, {1.5, -0.125}, {2.5, 0.0}, {3.1, 0.0}}};
  for (const auto& q : ws) s.wall.push_back(add(q[0], q[1], -0.87));
  s.c = add(1.1, 1.0, 0.0);
  s.t = add(2.5, 1.1, 0.0);
  std::vector<int> face_patch;
  auto tri = [&](int p, int u, int v, int w) {
    const Eigen::Vector3d up = turn * (p == 0 ? Eigen::Vector3d(0.0, 0.0, 1.0) : Eigen::Vector3d(0.0, -1.0, 0.0));
    add_facing_triangle(s.soup, face_patch, p, u, v, w, up);
  };
  tri(0, s.k[0], s.k[1], s.k[2]);
  tri(0, s.k[0], s.k[2], s.c);
  tri(0, s.c, s.k[2], s.t);
  tri(0, s.k[2], s.k[3], s.t);
  for (int i = 0; i < 4; ++i) tri(1, s.k[i], s.wall[i], s.wall[i + 1]);
  for (int i = 0; i < 3; ++i) tri(1, s.k[i], s.wall[i + 1], s.k[i + 1]);
  SurfaceMesh& m = s.surface;
  // Curves: 0 the crease K, 1 patch 0's boundary (k3, t, c, k0), 2 the wall's boundary.
  m.curve_is_feature = {1, 1, 1};
  m.curve_nodes = {s.k, {s.k[3], s.t, s.c, s.k[0]}, {s.k[0]}};
  m.curve_nodes[2].insert(m.curve_nodes[2].end(), s.wall.begin(), s.wall.end());
  m.curve_nodes[2].push_back(s.k[3]);
  finish_surface(m, s.soup, face_patch, {s.k[0], s.k[3]}, 2);
  return s;
}

TEST(StitchFeatureChords, AChordBetweenTwoNodesOfACreaseFlips) {
  const ChordFan s = make_chord_fan();
  const TriMesh input = to_trimesh(s.soup);
  StitchOptions o;
  o.obtuse_split_rounds = 0;  // the flip alone (a split of the chord would add a node)
  o.n_threads = 1;
  o.flip_feature_chords = false;
  const StitchResult locked = stitch(s.surface, input, o);
  ASSERT_TRUE(locked.report.ok());
  EXPECT_EQ(obtuse_faces(locked), 1u);  // (k0, k1, k2): every node is fixed, the chord locked
  o.flip_feature_chords = true;
  const StitchResult r = stitch(s.surface, input, o);
  ASSERT_TRUE(r.report.ok());
  EXPECT_EQ(obtuse_faces(r), 0u);
  EXPECT_GT(r.report.n_flips, locked.report.n_flips);
  EXPECT_TRUE(r.report.output.topology.is_manifold);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 1);
  EXPECT_EQ(r.report.output.topology.n_boundary_loops, 1u);
  ASSERT_EQ(r.mesh.n_vertices(), s.soup.points.size());
  // Every node in place; K's pieces are still edges, the chord k0-k2 is gone, k1-c is there.
  auto vertex = [&](int node) -> TriMesh::VertexHandle {
    for (auto v : r.mesh.vertices()) {
      if (r.vertex_node[static_cast<std::size_t>(v.idx())] == node) return v;
    }
    return TriMesh::VertexHandle();
  };
  for (auto v : r.mesh.vertices()) {
    EXPECT_EQ(to_eigen(r.mesh.point(v)), s.soup.points[static_cast<std::size_t>(r.vertex_node[static_cast<std::size_t>(v.idx())])]);
  }
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(r.mesh.find_halfedge(vertex(s.k[i]), vertex(s.k[i + 1])).is_valid()) << i;
  EXPECT_FALSE(r.mesh.find_halfedge(vertex(s.k[0]), vertex(s.k[2])).is_valid());
  EXPECT_TRUE(r.mesh.find_halfedge(vertex(s.k[1]), vertex(s.c)).is_valid());
}

// StitchOptions::feature_corner_slides (docs/stitch.md "Feature corners sliding, session 21"):
// a flat top (z = 0) over a crease A (along the x axis, bent at c: corner a0, a1, corner c, a3
// 0.2 off the axis, corner a4) with a wall (patch 2) hanging from A; the top is cut at c by a
// smooth one-piece curve S to the corner d on the top's boundary, 10 deg off the normal to A, so
// that patch 0's wedge at c is 100 deg, closed by the one triangle (a1, c, d), patch 1's 69 deg
// (a slide of 0.3 towards a3 leaves both acute). Every node is a corner or on
// a feature curve; c and d end two feature curves each (a0 and a4 three). Without the corner
// slides the obtuse triangle stays (no flip helps, a1 only slides along c -> a1); with them a
// corner slides along its feature curves: no obtuse triangle is left, every moved corner lies on
// the polyline of its feature curves within 0.4 of a piece of its node, a0 and a4 stay, the
// surface keeps its topology, the same result for any thread count.
struct TJunction {
  TriangleSoup soup;
  SurfaceMesh surface;
  int a0 = -1, a1 = -1, c = -1, a3 = -1, a4 = -1, d = -1, t0 = -1, t1 = -1;
  std::vector<int> wall;
};

TJunction make_t_junction() {
  TJunction s;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.5, Eigen::Vector3d(2.0, -1.0, 3.0).normalized()).toRotationMatrix();
  auto add = [&](double x, double y, double z) {
    s.soup.points.push_back(turn * Eigen::Vector3d(x, y, z));
    return static_cast<int>(s.soup.points.size()) - 1;
  };
  s.a0 = add(0.0, 0.0, 0.0);
  s.a1 = add(1.0, 0.0, 0.0);
  s.c = add(2.0, 0.0, 0.0);
  s.a3 = add(3.0, 0.2, 0.0);  // A bends at c: patch 1's wedge 70 deg, so a slide can make both acute
  s.a4 = add(4.0, 0.0, 0.0);
  const double slant = std::tan(10.0 * std::numbers::pi / 180.0);
  s.d = add(2.0 + slant, 1.0, 0.0);
  s.t0 = add(0.3, 1.0, 0.0);
  s.t1 = add(3.4, 1.0, 0.0);
  for (const double x : {-0.1, 0.5, 1.5, 2.5, 3.5, 4.1}) s.wall.push_back(add(x, 0.0, -0.87));
  std::vector<int> face_patch;
  auto tri = [&](int p, int u, int v, int w) {
    const Eigen::Vector3d up = turn * (p == 2 ? Eigen::Vector3d(0.0, -1.0, 0.0) : Eigen::Vector3d(0.0, 0.0, 1.0));
    add_facing_triangle(s.soup, face_patch, p, u, v, w, up);
  };
  tri(0, s.a0, s.a1, s.t0);
  tri(0, s.a1, s.d, s.t0);
  tri(0, s.a1, s.c, s.d);  // obtuse at c: 100 deg
  tri(1, s.c, s.a3, s.d);
  tri(1, s.a3, s.t1, s.d);
  tri(1, s.a3, s.a4, s.t1);
  const std::array<int, 5> top{s.a0, s.a1, s.c, s.a3, s.a4};
  for (int j = 0; j < 5; ++j) tri(2, top[static_cast<std::size_t>(j)], s.wall[static_cast<std::size_t>(j)], s.wall[static_cast<std::size_t>(j) + 1]);
  for (int j = 0; j < 4; ++j) tri(2, top[static_cast<std::size_t>(j)], top[static_cast<std::size_t>(j) + 1], s.wall[static_cast<std::size_t>(j) + 1]);
  SurfaceMesh& m = s.surface;
  // Curves: 0, 1 the crease A's halves, 2 the smooth S, 3 the wall's bottom (the input's
  // boundary), 4 and 5 the top's boundary.
  m.curve_is_feature = {1, 1, 0, 1, 1, 1};
  m.curve_nodes = {{s.a0, s.a1, s.c}, {s.c, s.a3, s.a4}, {s.c, s.d}, {s.a0}, {s.a4, s.t1, s.d}, {s.d, s.t0, s.a0}};
  m.curve_nodes[3].insert(m.curve_nodes[3].end(), s.wall.begin(), s.wall.end());
  m.curve_nodes[3].push_back(s.a4);
  finish_surface(m, s.soup, face_patch, {s.a0, s.c, s.a4, s.d}, 3);
  return s;
}

TEST(StitchSlide, FeatureCornersSlideAlongTheirCurves) {
  const TJunction s = make_t_junction();
  const TriMesh input = to_trimesh(s.soup);
  StitchOptions o;
  o.obtuse_split_rounds = 0;  // the slides alone (a split of a1-d would take the angle apart)
  o.n_threads = 1;
  o.feature_corner_slides = false;
  const StitchResult fixed = stitch(s.surface, input, o);
  ASSERT_TRUE(fixed.report.ok());
  EXPECT_EQ(obtuse_faces(fixed), 1u);  // (a1, c, d): every corner stays
  o.feature_corner_slides = true;
  const StitchResult r = stitch(s.surface, input, o);
  ASSERT_TRUE(r.report.ok());
  EXPECT_GT(r.report.n_feature_slides, fixed.report.n_feature_slides);
  EXPECT_EQ(obtuse_faces(r), 0u);
  EXPECT_TRUE(r.report.output.topology.is_manifold);
  EXPECT_EQ(r.report.output.topology.euler_characteristic, 1);
  EXPECT_EQ(r.report.output.topology.n_boundary_loops, 1u);
  ASSERT_EQ(r.mesh.n_vertices(), s.soup.points.size());
  // The feature curves through each corner that may slide, as one polyline.
  auto polyline = [&](std::initializer_list<int> nodes) {
    std::vector<Eigen::Vector3d> out;
    for (const int g : nodes) out.push_back(s.soup.points[static_cast<std::size_t>(g)]);
    return out;
  };
  std::size_t n_moved = 0;
  for (auto v : r.mesh.vertices()) {
    const int node = r.vertex_node[static_cast<std::size_t>(v.idx())];
    const Eigen::Vector3d p = to_eigen(r.mesh.point(v));
    const Eigen::Vector3d at = s.soup.points[static_cast<std::size_t>(node)];
    if (node == s.a0 || node == s.a4) {
      EXPECT_EQ(p, at) << "corner " << node;  // three feature curve ends: fixed
      continue;
    }
    if (node != s.c && node != s.d) continue;
    if (p == at) continue;
    ++n_moved;
    const std::vector<Eigen::Vector3d> line =
        node == s.c ? polyline({s.a1, s.c, s.a3}) : polyline({s.t1, s.d, s.t0});
    EXPECT_LT(distance_to_polyline(p, line), 1e-12) << "corner " << node;
    // The longer of the corner's two pieces (c-a3 is sqrt(1.04) long, not 1).
    const int before = node == s.c ? s.a1 : s.t1, after = node == s.c ? s.a3 : s.t0;
    const double piece = std::max((s.soup.points[static_cast<std::size_t>(before)] - at).norm(),
                                  (s.soup.points[static_cast<std::size_t>(after)] - at).norm());
    EXPECT_LE((p - at).norm(), 0.4 * piece + 1e-12) << "corner " << node;
  }
  EXPECT_GT(n_moved, 0u);
  // The same for any thread count.
  o.n_threads = 3;
  const StitchResult r3 = stitch(s.surface, input, o);
  ASSERT_EQ(r3.mesh.n_vertices(), r.mesh.n_vertices());
  for (auto v : r.mesh.vertices()) EXPECT_EQ(to_eigen(r3.mesh.point(v)), to_eigen(r.mesh.point(v)));
}

TEST(StitchSlide, NegativeRoundsAreRefused) {
  StitchOptions o;
  o.feature_slide_rounds = -1;
  EXPECT_THROW(o.validate(), InvalidInput);
}

// The slides are part of the obtuse repair: with the repair off they do not run, even on
// the strip whose planted defect they remove.
TEST(StitchSlide, NoSlidesWithoutTheObtuseRepair) {
  const Strip s = make_strip();
  const TriMesh input = to_trimesh(s.soup);
  StitchOptions o = strip_options(2);
  o.obtuse_repair_rounds = 0;
  const StitchResult r = stitch(s.surface, input, o);
  ASSERT_TRUE(r.report.ok());
  EXPECT_EQ(r.report.n_feature_slides, 0u);
  EXPECT_GT(obtuse_faces(r, 0), 0u);
}

TEST(StitchSlide, CosineGainMustBePositive) {
  StitchOptions o;
  EXPECT_NO_THROW(o.validate());  // default: infinity (off)
  for (const double bad : {0.0, -0.01, std::numeric_limits<double>::quiet_NaN()}) {
    o.feature_slide_cosine_gain = bad;
    EXPECT_THROW(o.validate(), InvalidInput) << bad;
  }
  o.feature_slide_cosine_gain = 0.01;
  EXPECT_NO_THROW(o.validate());
}

}  // namespace
}  // namespace nurbsfront
