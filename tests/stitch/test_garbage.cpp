// SPDX-License-Identifier: BSD-3-Clause
// stitch_detail::collect_garbage against OpenMesh's garbage_collection(): the same mesh
// (element order, every handle, points, statuses, properties) after collapses and deletions;
// stitch_detail::recount_pairs against a whole-mesh count after moves, flips and collapses;
// stitch_detail::make_angle_changes all or none; stitch_detail::mesh_soup against to_soup.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "fixtures/shapes.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/stitch/stitch_internal.h"

namespace nurbsfront {
namespace {

using VH = TriMesh::VertexHandle;
using HH = TriMesh::HalfedgeHandle;
using EH = TriMesh::EdgeHandle;
using FH = TriMesh::FaceHandle;

// A torus with every `step`-th collapsible edge collapsed (an edge of a collapse's ring is
// skipped once it is gone) and, when `faces` > 0, every faces-th remaining face deleted
// (which opens the surface and can leave isolated vertices).
TriMesh damaged_torus(int step, int faces) {
  TriMesh mesh = to_trimesh(test::torus(24, 12));
  int n = 0;
  for (int e = 0; e < static_cast<int>(mesh.n_edges()); ++e) {
    if (mesh.status(EH(e)).deleted()) continue;
    const HH h = mesh.halfedge_handle(EH(e), 0);
    if (!mesh.is_collapse_ok(h) || ++n % step != 0) continue;
    mesh.collapse(h);
  }
  for (int f = 0; faces > 0 && f < static_cast<int>(mesh.n_faces()); f += faces) {
    if (!mesh.status(FH(f)).deleted()) mesh.delete_face(FH(f), true);
  }
  return mesh;
}

void expect_same(const TriMesh& a, const TriMesh& b) {
  ASSERT_EQ(a.n_vertices(), b.n_vertices());
  ASSERT_EQ(a.n_edges(), b.n_edges());
  ASSERT_EQ(a.n_faces(), b.n_faces());
  for (int v = 0; v < static_cast<int>(a.n_vertices()); ++v) {
    EXPECT_EQ(a.point(VH(v)), b.point(VH(v))) << "vertex " << v;
    EXPECT_EQ(a.halfedge_handle(VH(v)), b.halfedge_handle(VH(v))) << "vertex " << v;
    EXPECT_EQ(a.status(VH(v)).bits(), b.status(VH(v)).bits()) << "vertex " << v;
  }
  for (int h = 0; h < static_cast<int>(a.n_halfedges()); ++h) {
    EXPECT_EQ(a.to_vertex_handle(HH(h)), b.to_vertex_handle(HH(h))) << "halfedge " << h;
    EXPECT_EQ(a.next_halfedge_handle(HH(h)), b.next_halfedge_handle(HH(h))) << "halfedge " << h;
    EXPECT_EQ(a.prev_halfedge_handle(HH(h)), b.prev_halfedge_handle(HH(h))) << "halfedge " << h;
    EXPECT_EQ(a.face_handle(HH(h)), b.face_handle(HH(h))) << "halfedge " << h;
  }
  for (int e = 0; e < static_cast<int>(a.n_edges()); ++e) EXPECT_EQ(a.status(EH(e)).bits(), b.status(EH(e)).bits());
  for (int f = 0; f < static_cast<int>(a.n_faces()); ++f) {
    EXPECT_EQ(a.halfedge_handle(FH(f)), b.halfedge_handle(FH(f))) << "face " << f;
    EXPECT_EQ(a.status(FH(f)).bits(), b.status(FH(f)).bits()) << "face " << f;
  }
}

void check_against_openmesh(int step, int faces) {
  const TriMesh damaged = damaged_torus(step, faces);
  std::size_t n_deleted_vertices = 0, n_deleted_faces = 0;
  for (const auto v : damaged.all_vertices()) n_deleted_vertices += damaged.status(v).deleted() ? 1 : 0;
  for (const auto f : damaged.all_faces()) n_deleted_faces += damaged.status(f).deleted() ? 1 : 0;
  ASSERT_GT(n_deleted_vertices, 10U);
  ASSERT_GT(n_deleted_faces, 20U);
  // A user property travels with its element in both.
  TriMesh expected = damaged, actual = damaged;
  OpenMesh::FPropHandleT<int> expected_id, actual_id;
  expected.add_property(expected_id);
  actual.add_property(actual_id);
  for (int f = 0; f < static_cast<int>(damaged.n_faces()); ++f) {
    expected.property(expected_id, FH(f)) = f;
    actual.property(actual_id, FH(f)) = f;
  }
  expected.garbage_collection();
  const stitch_detail::GarbageMaps old = stitch_detail::collect_garbage(actual);
  expect_same(expected, actual);
  EXPECT_EQ(actual.n_vertices(), damaged.n_vertices() - n_deleted_vertices);
  EXPECT_EQ(actual.n_faces(), damaged.n_faces() - n_deleted_faces);
  // The maps name each kept element's old index.
  ASSERT_EQ(old.vertex.size(), actual.n_vertices());
  ASSERT_EQ(old.face.size(), actual.n_faces());
  for (int v = 0; v < static_cast<int>(actual.n_vertices()); ++v) {
    EXPECT_EQ(actual.point(VH(v)), damaged.point(VH(old.vertex[static_cast<std::size_t>(v)])));
    EXPECT_FALSE(damaged.status(VH(old.vertex[static_cast<std::size_t>(v)])).deleted());
  }
  for (int f = 0; f < static_cast<int>(actual.n_faces()); ++f) {
    EXPECT_EQ(actual.property(actual_id, FH(f)), old.face[static_cast<std::size_t>(f)]);
    EXPECT_EQ(expected.property(expected_id, FH(f)), old.face[static_cast<std::size_t>(f)]);
  }
}

TEST(CollectGarbage, MatchesOpenMeshAfterCollapses) { check_against_openmesh(7, 0); }

TEST(CollectGarbage, MatchesOpenMeshAfterCollapsesAndDeletedFaces) { check_against_openmesh(5, 11); }

TEST(CollectGarbage, NothingDeletedChangesNothing) {
  const TriMesh mesh = to_trimesh(test::torus(12, 8));
  TriMesh actual = mesh;
  const stitch_detail::GarbageMaps old = stitch_detail::collect_garbage(actual);
  expect_same(mesh, actual);
  for (std::size_t v = 0; v < old.vertex.size(); ++v) EXPECT_EQ(old.vertex[v], static_cast<int>(v));
  for (std::size_t f = 0; f < old.face.size(); ++f) EXPECT_EQ(old.face[f], static_cast<int>(f));
}

using Pairs = std::vector<std::array<std::uint32_t, 2>>;

// Two unit spheres (icosphere 3, 1280 triangles each) 0.8 apart along x: they cross along
// the circle x = 0.4, in one mesh of two components.
TriMesh crossing_spheres() {
  TriangleSoup soup = test::icosphere(3);
  const TriangleSoup other = test::icosphere(3);
  const auto offset = static_cast<std::uint32_t>(soup.points.size());
  for (const auto& p : other.points) soup.points.push_back(p + Eigen::Vector3d(0.8, 0.0, 0.0));
  for (const auto& t : other.triangles) soup.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return to_trimesh(soup);
}

// The vertices near the crossing (|x - 0.4| < 0.25): every third moves 3% towards its
// sphere's centre, every edge between two of them whose index is a multiple of 5 flips and
// every 4th collapsible edge there collapses; the mesh is garbage-collected when `collect`.
// None of these vertices is on the bounding box, so its diagonal stays.
stitch_detail::GarbageMaps settle_like_changes(TriMesh& mesh, bool collect) {
  auto near = [&](VH v) { return std::abs(mesh.point(v)[0] - 0.4) < 0.25; };
  for (int v = 0; v < static_cast<int>(mesh.n_vertices()); v += 3) {
    if (!near(VH(v))) continue;
    const OpenMesh::Vec3d centre(v < static_cast<int>(mesh.n_vertices()) / 2 ? 0.0 : 0.8, 0.0, 0.0);
    mesh.set_point(VH(v), centre + 0.97 * (mesh.point(VH(v)) - centre));
  }
  for (int e = 0; e < static_cast<int>(mesh.n_edges()); e += 5) {
    const HH h = mesh.halfedge_handle(EH(e), 0);
    if (near(mesh.from_vertex_handle(h)) && near(mesh.to_vertex_handle(h)) && mesh.is_flip_ok(EH(e))) mesh.flip(EH(e));
  }
  if (!collect) return {};
  int n = 0;
  for (int e = 0; e < static_cast<int>(mesh.n_edges()); ++e) {
    if (mesh.status(EH(e)).deleted()) continue;
    const HH h = mesh.halfedge_handle(EH(e), 0);
    if (!near(mesh.from_vertex_handle(h)) || !mesh.is_collapse_ok(h) || ++n % 4 != 0) continue;
    mesh.collapse(h);
  }
  return stitch_detail::collect_garbage(mesh);
}

// The pairs of `before` between faces that are in `after` unchanged (by the maps), without
// any new pair: what a recount that checked nothing again would return.
Pairs kept_pairs_only(const TriangleSoup& before, const Pairs& pairs, const TriangleSoup& after,
                      const stitch_detail::GarbageMaps& old) {
  std::vector<std::int64_t> now(before.triangles.size(), -1);
  for (std::size_t f = 0; f < after.triangles.size(); ++f) {
    const std::size_t o = old.face.empty() ? f : static_cast<std::size_t>(old.face[f]);
    bool same = true;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t v = after.triangles[f][k];
      const std::size_t ov = old.vertex.empty() ? v : static_cast<std::size_t>(old.vertex[v]);
      same = same && before.triangles[o][k] == ov && before.points[ov] == after.points[v];
    }
    if (same) now[o] = static_cast<std::int64_t>(f);
  }
  Pairs out;
  for (const auto& p : pairs) {
    if (now[p[0]] >= 0 && now[p[1]] >= 0) {
      out.push_back({static_cast<std::uint32_t>(std::min(now[p[0]], now[p[1]])),
                     static_cast<std::uint32_t>(std::max(now[p[0]], now[p[1]]))});
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

void check_recount(bool collect) {
  TriMesh mesh = crossing_spheres();
  const TriangleSoup before = to_soup(mesh);
  const Pairs before_pairs = self_intersecting_pairs(before, 1);
  ASSERT_GT(before_pairs.size(), 50U);
  const stitch_detail::GarbageMaps old = settle_like_changes(mesh, collect);
  const TriangleSoup after = to_soup(mesh);
  ASSERT_EQ(after.triangles.size(), mesh.n_faces());  // no deleted face left
  if (collect) {
    ASSERT_LT(after.triangles.size(), before.triangles.size());
  }
  ASSERT_EQ(bounding_box(after).diagonal(), bounding_box(before).diagonal());
  const Pairs expected = self_intersecting_pairs(after, 1);
  ASSERT_GT(expected.size(), 50U);
  // The changes made and removed pairs: keeping the old ones only would be wrong.
  ASSERT_NE(kept_pairs_only(before, before_pairs, after, old), expected);
  EXPECT_EQ(stitch_detail::recount_pairs(before, before_pairs, after, old, 1), expected);
  EXPECT_EQ(stitch_detail::recount_pairs(before, before_pairs, after, old, 2), expected);
}

TEST(RecountPairs, EqualsTheWholeCountAfterMovesFlipsAndCollapses) { check_recount(true); }

TEST(RecountPairs, EqualsTheWholeCountAfterMovesAndFlipsWithoutMaps) { check_recount(false); }

TEST(RecountPairs, CountsTheWholeMeshWhenTheDiagonalChanges) {
  TriMesh mesh = crossing_spheres();
  const TriangleSoup before = to_soup(mesh);
  const Pairs before_pairs = self_intersecting_pairs(before, 1);
  settle_like_changes(mesh, false);
  // The first sphere's vertex furthest along -x moves out: a larger box, another tolerance.
  VH far(0);
  for (const auto v : mesh.vertices()) {
    if (mesh.point(v)[0] < mesh.point(far)[0]) far = v;
  }
  mesh.set_point(far, mesh.point(far) * 1.5);
  const TriangleSoup after = to_soup(mesh);
  ASSERT_NE(bounding_box(after).diagonal(), bounding_box(before).diagonal());
  EXPECT_EQ(stitch_detail::recount_pairs(before, before_pairs, after, {}, 2), self_intersecting_pairs(after, 1));
}

TEST(RecountPairs, RefusesMapsOfAnotherMesh) {
  const TriMesh mesh = crossing_spheres();
  const TriangleSoup soup = to_soup(mesh);
  stitch_detail::GarbageMaps wrong;
  wrong.vertex.assign(soup.points.size() - 1, 0);
  EXPECT_THROW((void)stitch_detail::recount_pairs(soup, {}, soup, wrong, 1), InternalError);
  EXPECT_THROW((void)stitch_detail::recount_pairs(soup, {{0, static_cast<std::uint32_t>(soup.triangles.size())}}, soup, {}, 1),
               InternalError);
}

// stitch_detail::make_angle_changes makes a pair of changes on the whole mesh only when
// OpenMesh takes both: a second change it refuses undoes the first (liver's two-step
// repair; before, only an assert caught it and the first change stayed).
StitchResult result_of(const TriangleSoup& soup) {
  StitchResult r;
  to_trimesh(soup, r.mesh);
  r.face_patch.assign(r.mesh.n_faces(), 0);
  for (std::size_t i = 0; i < r.mesh.n_faces(); ++i) r.face_patch[i] = static_cast<int>(i % 3);
  for (auto v : r.mesh.vertices()) r.vertex_node.push_back(v.idx());
  return r;
}

// Every face's corners in order and every point, deleted elements included.
std::vector<double> fingerprint(const TriMesh& mesh) {
  std::vector<double> x;
  for (auto v : mesh.all_vertices()) {
    const auto p = mesh.point(v);
    x.insert(x.end(), {p[0], p[1], p[2], mesh.status(v).deleted() ? 1.0 : 0.0});
  }
  for (auto f : mesh.all_faces()) {
    x.push_back(mesh.status(f).deleted() ? -1.0 : -2.0);
    for (auto v : mesh.fv_range(f)) x.push_back(v.idx());
  }
  return x;
}

// stitch_detail::mesh_soup reads the halfedges directly: the soup to_soup() gives, after
// flips (which change faces' halfedges) and, through to_soup itself, with deleted elements.
TEST(MeshSoup, EqualsToSoupAfterFlipsAndWithDeletedElements) {
  TriMesh mesh = to_trimesh(test::torus(24, 12));
  std::size_t n_flips = 0;
  for (int e = 0; e < static_cast<int>(mesh.n_edges()); e += 3) {
    if (!mesh.is_flip_ok(EH(e))) continue;
    mesh.flip(EH(e));
    ++n_flips;
  }
  ASSERT_GT(n_flips, 10u);
  mesh.set_point(VH(5), mesh.point(VH(5)) + Point3(0.01, -0.02, 0.03));
  const TriangleSoup a = stitch_detail::mesh_soup(mesh), b = to_soup(mesh);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.triangles, b.triangles);
  const TriMesh damaged = damaged_torus(7, 11);
  const TriangleSoup c = stitch_detail::mesh_soup(damaged), d = to_soup(damaged);
  EXPECT_LT(d.triangles.size(), damaged.n_faces());  // deleted faces left out
  EXPECT_EQ(c.points, d.points);
  EXPECT_EQ(c.triangles, d.triangles);
}

TEST(AngleChanges, ARefusedSecondFlipUndoesTheFirstMove) {
  // A tetrahedron: every flip would make an edge that exists, so OpenMesh refuses it.
  StitchResult r = result_of(test::tetrahedron());
  const auto before = fingerprint(r.mesh);
  const std::vector<stitch_detail::AngleChange> changes{
      {stitch_detail::AngleChange::Kind::Move, VH(0), VH(), Eigen::Vector3d(0.1, 0.2, 0.3)},
      {stitch_detail::AngleChange::Kind::Flip, VH(1), VH(2), Eigen::Vector3d::Zero()}};
  ASSERT_FALSE(r.mesh.is_flip_ok(r.mesh.edge_handle(r.mesh.find_halfedge(VH(1), VH(2)))));
  std::vector<VH> touched{VH(7)};
  EXPECT_FALSE(stitch_detail::make_angle_changes(r, changes, &touched));
  EXPECT_EQ(fingerprint(r.mesh), before);
  EXPECT_TRUE(touched.empty());
  // The move alone is made.
  EXPECT_TRUE(stitch_detail::make_angle_changes(r, std::span(changes).first(1), &touched));
  EXPECT_EQ(to_eigen(r.mesh.point(VH(0))), Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(touched, std::vector<VH>{VH(0)});
}

TEST(AngleChanges, ARefusedSecondChangeUndoesTheFirstCollapse) {
  // An open grid: an inner edge collapses; a boundary edge never flips (refused), and the
  // collapsed edge is gone for a second collapse.
  const TriangleSoup soup = test::grid_patch(4, 4);
  StitchResult r = result_of(soup);
  HH inner, boundary;
  for (auto h : r.mesh.halfedges()) {
    if (!inner.is_valid() && !r.mesh.is_boundary(r.mesh.from_vertex_handle(h)) &&
        !r.mesh.is_boundary(r.mesh.to_vertex_handle(h)) && r.mesh.is_collapse_ok(h))
      inner = h;
    if (!boundary.is_valid() && r.mesh.is_boundary(r.mesh.edge_handle(h))) boundary = h;
  }
  ASSERT_TRUE(inner.is_valid() && boundary.is_valid());
  const VH a = r.mesh.from_vertex_handle(inner), b = r.mesh.to_vertex_handle(inner);
  const stitch_detail::AngleChange collapse{stitch_detail::AngleChange::Kind::Collapse, a, b, Eigen::Vector3d::Zero()};
  const auto before = fingerprint(r.mesh);
  const std::vector<int> patches_before = r.face_patch, nodes_before = r.vertex_node;
  for (const auto& second :
       {stitch_detail::AngleChange{stitch_detail::AngleChange::Kind::Flip, r.mesh.from_vertex_handle(boundary),
                                   r.mesh.to_vertex_handle(boundary), Eigen::Vector3d::Zero()},
        collapse}) {
    const std::vector<stitch_detail::AngleChange> changes{collapse, second};
    EXPECT_FALSE(stitch_detail::make_angle_changes(r, changes));
    EXPECT_EQ(fingerprint(r.mesh), before);
    EXPECT_EQ(r.face_patch, patches_before);
    EXPECT_EQ(r.vertex_node, nodes_before);
  }
  // The collapse alone is made: a deleted, b survives.
  EXPECT_TRUE(stitch_detail::make_angle_changes(r, std::span(&collapse, 1)));
  EXPECT_TRUE(r.mesh.status(a).deleted());
  EXPECT_FALSE(r.mesh.status(b).deleted());
}

}  // namespace
}  // namespace nurbsfront
