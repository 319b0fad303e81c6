// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The segmentation contract (DESIGN.md, "Contracts: Segmentation"), checked independently
// of the implementation: own BFS, brute-force (grid-binned) projected-triangle overlap.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/soup.h"
#include "nurbsfront/segment/segment.h"

namespace nurbsfront::segment_test {

inline constexpr double kPi = std::numbers::pi;
inline double radians(double deg) { return deg * kPi / 180.0; }

inline Eigen::Vector3d raw_normal(const TriMesh& mesh, int f) {
  auto h = mesh.halfedge_handle(mesh.face_handle(f));
  const Eigen::Vector3d a = to_eigen(mesh.point(mesh.from_vertex_handle(h)));
  const Eigen::Vector3d b = to_eigen(mesh.point(mesh.to_vertex_handle(h)));
  const Eigen::Vector3d c = to_eigen(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(h))));
  return (b - a).cross(c - a).normalized();
}

inline int patch_of(const TriMesh& mesh, const Segmentation& seg, OpenMesh::HalfedgeHandle h) {
  const auto f = mesh.face_handle(h);
  return f.is_valid() ? seg.face_patch[f.idx()] : -1;
}

// 2D triangles (counter-clockwise) whose interiors overlap, by separating axes; touching
// along an edge or at a vertex is not an overlap.
inline bool interiors_overlap(const std::array<Eigen::Vector2d, 3>& s, const std::array<Eigen::Vector2d, 3>& t,
                       double eps) {
  for (const auto* tri : {&s, &t}) {
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector2d e = (*tri)[(i + 1) % 3] - (*tri)[i];
      const Eigen::Vector2d n(e.y(), -e.x());  // outward for a counter-clockwise triangle
      const double limit = n.dot((*tri)[i]);
      const auto& other = tri == &s ? t : s;
      if (std::all_of(other.begin(), other.end(), [&](const Eigen::Vector2d& p) { return n.dot(p) >= limit - eps * n.norm(); }))
        return false;
    }
  }
  return true;
}

// Every contract of the segmentation, checked from scratch.
inline void expect_contracts(const TriMesh& mesh, const Segmentation& seg, const SegmentOptions& options,
                      double raw_slope_slack_deg) {
  const auto n_faces = static_cast<int>(mesh.n_faces());
  const auto n_patches = static_cast<int>(seg.patches.size());
  ASSERT_EQ(seg.face_patch.size(), mesh.n_faces());
  // Every face in exactly one patch, patch lists consistent.
  std::vector<int> count(n_faces, 0);
  for (int p = 0; p < n_patches; ++p) {
    const auto& faces = seg.patches[p].faces;
    ASSERT_FALSE(faces.empty());
    EXPECT_TRUE(std::is_sorted(faces.begin(), faces.end()));
    for (int f : faces) {
      ++count[f];
      EXPECT_EQ(seg.face_patch[f], p);
    }
    EXPECT_NEAR(seg.patches[p].axis.norm(), 1.0, 1e-12);
  }
  for (int f = 0; f < n_faces; ++f) ASSERT_EQ(count[f], 1) << "face " << f;

  // Each patch connected through edges (own BFS).
  for (int p = 0; p < n_patches; ++p) {
    std::set<int> reached{seg.patches[p].faces[0]};
    std::vector<int> queue{seg.patches[p].faces[0]};
    for (std::size_t head = 0; head < queue.size(); ++head) {
      for (const auto g : mesh.ff_range(mesh.face_handle(queue[head]))) {
        if (seg.face_patch[g.idx()] == p && reached.insert(g.idx()).second) queue.push_back(g.idx());
      }
    }
    EXPECT_EQ(reached.size(), seg.patches[p].faces.size()) << "patch " << p << " is not connected";
  }

  // Creases are never inside a patch, except around absorbed tiny islands.
  EXPECT_TRUE(std::is_sorted(seg.island_faces.begin(), seg.island_faces.end()));
  EXPECT_LE(seg.island_faces.size(), kSegmentTinyIslandFaces * seg.n_islands_absorbed);
  const double cos_crease = std::cos(radians(options.crease_angle_deg));
  for (const auto e : mesh.edges()) {
    if (mesh.is_boundary(e)) continue;
    const int f = mesh.face_handle(mesh.halfedge_handle(e, 0)).idx();
    const int g = mesh.face_handle(mesh.halfedge_handle(e, 1)).idx();
    const auto is_island = [&](int h) {
      return std::binary_search(seg.island_faces.begin(), seg.island_faces.end(), h);
    };
    if (raw_normal(mesh, f).dot(raw_normal(mesh, g)) < cos_crease && !is_island(f) && !is_island(g)) {
      EXPECT_NE(seg.face_patch[f], seg.face_patch[g]) << "crease edge " << e.idx() << " inside a patch";
    }
  }

  // Normal bounds and the height-field property: projected faces positively oriented and
  // pairwise without interior overlap; no vertex where a patch touches itself.
  const double diagonal = bounding_box(mesh).diagonal();
  for (int p = 0; p < n_patches; ++p) {
    const Eigen::Vector3d axis = seg.patches[p].axis;
    Eigen::Vector3d e1 = axis.unitOrthogonal();
    Eigen::Vector3d e2 = axis.cross(e1);
    std::vector<std::array<Eigen::Vector2d, 3>> projected;
    for (int f : seg.patches[p].faces) {
      const Eigen::Vector3d n = raw_normal(mesh, f);
      EXPECT_GE(n.dot(axis), kSegmentMinRawNormalDot) << "face " << f;
      EXPECT_GE(n.dot(axis), std::cos(radians(options.max_slope_deg + raw_slope_slack_deg))) << "face " << f;
      std::array<Eigen::Vector2d, 3> tri;
      int k = 0;
      for (const auto v : mesh.fv_range(mesh.face_handle(f))) {
        const Eigen::Vector3d q = to_eigen(mesh.point(v));
        tri[k++] = Eigen::Vector2d(q.dot(e1), q.dot(e2));
      }
      const double area2 = (tri[1] - tri[0]).x() * (tri[2] - tri[0]).y() - (tri[1] - tri[0]).y() * (tri[2] - tri[0]).x();
      EXPECT_GT(area2, 0.0) << "face " << f << " flips in projection";
      projected.push_back(tri);
    }
    // All pairs, binned on a grid over the projected bounding boxes (pairs in one cell).
    Eigen::Vector2d lo = projected[0][0], hi = lo;
    for (const auto& tri : projected)
      for (const auto& q : tri) {
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
      }
    const int cells = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(projected.size()))));
    const Eigen::Vector2d width = ((hi - lo) / cells).cwiseMax(Eigen::Vector2d::Constant(1e-300));
    std::vector<std::vector<int>> bins(static_cast<std::size_t>(cells) * cells);
    for (std::size_t i = 0; i < projected.size(); ++i) {
      Eigen::Vector2d a = projected[i][0], b = a;
      for (const auto& q : projected[i]) {
        a = a.cwiseMin(q);
        b = b.cwiseMax(q);
      }
      const auto cell = [&](double x, double origin, double w) {
        return std::clamp(static_cast<int>((x - origin) / w), 0, cells - 1);
      };
      for (int y = cell(a.y(), lo.y(), width.y()); y <= cell(b.y(), lo.y(), width.y()); ++y)
        for (int x = cell(a.x(), lo.x(), width.x()); x <= cell(b.x(), lo.x(), width.x()); ++x)
          bins[static_cast<std::size_t>(y) * cells + x].push_back(static_cast<int>(i));
    }
    for (const auto& bin : bins)
      for (std::size_t i = 0; i < bin.size(); ++i)
        for (std::size_t j = i + 1; j < bin.size(); ++j)
          ASSERT_FALSE(interiors_overlap(projected[bin[i]], projected[bin[j]], 1e-12 * diagonal))
              << "patch " << p << " folds: faces " << seg.patches[p].faces[bin[i]] << ", "
              << seg.patches[p].faces[bin[j]];
  }
  // Where a patch touches itself at a vertex (allowed: its loops share that vertex), the
  // vertex is a corner.
  const std::set<int> corner_set(seg.corners.begin(), seg.corners.end());
  for (const auto v : mesh.vertices()) {
    std::vector<int> out_patches;
    for (const auto h : mesh.voh_range(v)) {
      const int left = patch_of(mesh, seg, h);
      if (left >= 0 && left != patch_of(mesh, seg, mesh.opposite_halfedge_handle(h))) out_patches.push_back(left);
    }
    std::sort(out_patches.begin(), out_patches.end());
    if (std::adjacent_find(out_patches.begin(), out_patches.end()) != out_patches.end()) {
      EXPECT_EQ(corner_set.count(v.idx()), 1u) << "vertex " << v.idx();
    }
  }

  // Border curves: every border edge on exactly one curve, sides as documented.
  std::vector<int> on_curve(mesh.n_edges(), 0);
  const std::set<int> corners(seg.corners.begin(), seg.corners.end());
  EXPECT_TRUE(std::is_sorted(seg.corners.begin(), seg.corners.end()));
  std::vector<std::vector<int>> patch_curves(n_patches);
  for (std::size_t c = 0; c < seg.curves.size(); ++c) {
    const BorderCurve& curve = seg.curves[c];
    const auto nv = curve.vertices.size();
    ASSERT_EQ(curve.edges.size(), curve.is_closed ? nv : nv - 1);
    ASSERT_EQ(curve.smoothed.size(), nv);
    ASSERT_GE(curve.patch_left, 0);
    if (curve.patch_right >= 0) {
      EXPECT_LT(curve.patch_left, curve.patch_right);
    }
    patch_curves[curve.patch_left].push_back(static_cast<int>(c));
    if (curve.patch_right >= 0) patch_curves[curve.patch_right].push_back(static_cast<int>(c));
    double length = 0.0;
    for (std::size_t i = 0; i < curve.edges.size(); ++i) {
      const auto a = mesh.vertex_handle(curve.vertices[i]);
      const auto b = mesh.vertex_handle(curve.vertices[(i + 1) % nv]);
      const auto h = mesh.find_halfedge(a, b);
      ASSERT_TRUE(h.is_valid());
      EXPECT_EQ(mesh.edge_handle(h).idx(), curve.edges[i]);
      EXPECT_EQ(patch_of(mesh, seg, h), curve.patch_left);
      EXPECT_EQ(patch_of(mesh, seg, mesh.opposite_halfedge_handle(h)), curve.patch_right);
      ++on_curve[curve.edges[i]];
      length += (mesh.point(a) - mesh.point(b)).norm();
    }
    for (std::size_t i = 0; i < nv; ++i) {
      const bool is_end = !curve.is_closed && (i == 0 || i + 1 == nv);
      EXPECT_EQ(corners.count(curve.vertices[i]) == 1, is_end) << "curve " << c << " vertex " << i;
    }
    // Smoothing: ends fixed, displacement bounded.
    const double bound = options.border_smoothing.max_displacement * length / static_cast<double>(curve.edges.size());
    for (std::size_t i = 0; i < nv; ++i) {
      const Eigen::Vector3d input = to_eigen(mesh.point(mesh.vertex_handle(curve.vertices[i])));
      EXPECT_LE((curve.smoothed[i] - input).norm(), bound * (1 + 1e-12));
      if (!curve.is_closed && (i == 0 || i + 1 == nv)) {
        EXPECT_EQ(curve.smoothed[i], input);
      }
    }
  }
  for (const auto e : mesh.edges()) {
    const bool is_border = patch_of(mesh, seg, mesh.halfedge_handle(e, 0)) != patch_of(mesh, seg, mesh.halfedge_handle(e, 1));
    EXPECT_EQ(on_curve[e.idx()], is_border ? 1 : 0) << "edge " << e.idx();
  }
  for (int p = 0; p < n_patches; ++p) EXPECT_EQ(seg.patches[p].curves, patch_curves[p]);
}

inline Segmentation run(const TriMesh& mesh, const SegmentOptions& options, double raw_slope_slack_deg) {
  Segmentation seg = segment(mesh, options);
  expect_contracts(mesh, seg, options, raw_slope_slack_deg);
  return seg;
}

}  // namespace nurbsfront::segment_test
