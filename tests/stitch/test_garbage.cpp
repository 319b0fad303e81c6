// SPDX-License-Identifier: BSD-3-Clause
// stitch_detail::collect_garbage against OpenMesh's garbage_collection(): the same mesh
// (element order, every handle, points, statuses, properties) after collapses and deletions.
#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

#include "fixtures/shapes.h"
#include "nurbsfront/core/soup.h"
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

}  // namespace
}  // namespace nurbsfront
