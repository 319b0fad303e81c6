// SPDX-License-Identifier: BSD-3-Clause
// Chord compensation: the nodes lie on the fitted surfaces, so a flat triangle between them
// lies on the concave side of the surface and a convex part loses volume (docs/stitch.md,
// "Volume: chords over curved surfaces").
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/stitch/stitch_internal.h"

namespace nurbsfront::stitch_detail {

std::vector<Eigen::Vector3d> vertex_points(const TriMesh& mesh) {
  std::vector<Eigen::Vector3d> point(mesh.n_vertices());
  for (auto v : mesh.vertices()) point[static_cast<std::size_t>(v.idx())] = to_eigen(mesh.point(v));
  return point;
}

std::vector<std::uint8_t> fixed_vertices(const TriMesh& mesh, const std::vector<int>& vertex_node,
                                         const std::vector<std::uint8_t>& is_feature) {
  std::vector<std::uint8_t> fixed(mesh.n_vertices(), 0);
  for (auto v : mesh.vertices()) {
    const auto i = static_cast<std::size_t>(v.idx());
    fixed[i] = mesh.is_boundary(v) || is_feature[static_cast<std::size_t>(vertex_node[i])] != 0;
  }
  return fixed;
}

std::size_t compensate_chords(TriMesh& mesh, const std::vector<int>& vertex_node, const std::vector<std::uint8_t>& is_feature,
                              double strength, double reference_edge, unsigned n_threads) {
  if (!(strength > 0.0) || mesh.n_faces() == 0) return 0;
  const std::size_t nv = mesh.n_vertices();
  std::vector<Eigen::Vector3d> point = vertex_points(mesh);
  const std::vector<std::uint8_t> fixed = fixed_vertices(mesh, vertex_node, is_feature);
  // Area-weighted vertex normals (the sum of the incident triangles' area vectors). Each
  // face's corners and area vector on n_threads threads; the sums in face order here.
  constexpr std::size_t kFaceChunk = 8192;
  std::vector<Eigen::Vector3d> normal(nv, Eigen::Vector3d::Zero());
  std::vector<std::array<int, 3>> corners(mesh.n_faces());
  std::vector<Eigen::Vector3d> area_vector(mesh.n_faces());
  const bool face_status = mesh.has_face_status();
  parallel::for_chunks(corners.size(), n_threads, kFaceChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t fi = begin; fi < end; ++fi) {
      auto& c = corners[fi];
      const TriMesh::FaceHandle face(static_cast<int>(fi));
      if (face_status && mesh.status(face).deleted()) {  // adds nothing (zero area) below
        c = {0, 0, 0};
        area_vector[fi].setZero();
        continue;
      }
      auto h = mesh.halfedge_handle(face);
      for (std::size_t k = 0; k < 3; ++k, h = mesh.next_halfedge_handle(h)) c[k] = mesh.to_vertex_handle(h).idx();
      area_vector[fi] = (point[c[1]] - point[c[0]]).cross(point[c[2]] - point[c[0]]);
    }
  });
  for (std::size_t fi = 0; fi < corners.size(); ++fi) {
    for (const int v : corners[fi]) normal[static_cast<std::size_t>(v)] += area_vector[fi];
  }
  for (auto& n : normal) {
    const double l = n.norm();
    if (l > 0.0) n /= l;
  }
  // Per triangle: the mean gap between the surface and the flat triangle over its area,
  // (1/24) sum over its edges (i, j) of (n_j - n_i).(p_j - p_i) (kappa_e |e|^2 with kappa_e
  // the normal curvature along the edge; exact for a quadric through the corners), spread
  // area-weighted onto its corners. Triangles with a fixed corner (whose normal averages
  // across a crease) or whose corner normals turn by more than kMaxTurnDeg from the
  // triangle's own add nothing.
  constexpr double kMaxTurnDeg = 30.0;
  const double min_dot = std::cos(kMaxTurnDeg * std::numbers::pi / 180.0);
  // Per face (on n_threads threads): twice its area, its gap, the sum of its squared edges
  // and whether it counts; spread onto the corners in face order below.
  struct FaceGap {
    double twice_area = 0.0, gap = 0.0, sum_sq = 0.0;
    bool counts = false;
  };
  std::vector<FaceGap> face_gap(corners.size());
  parallel::for_chunks(corners.size(), n_threads, kFaceChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t f = begin; f < end; ++f) {
      const auto& c = corners[f];
      FaceGap& g = face_gap[f];
      g.twice_area = area_vector[f].norm();
      if (!(g.twice_area > 0.0)) continue;
      const Eigen::Vector3d n = area_vector[f] / g.twice_area;
      bool counts = true;
      double gap = 0.0, sum_sq = 0.0;
      for (int k = 0; k < 3; ++k) {
        const auto i = static_cast<std::size_t>(c[k]), j = static_cast<std::size_t>(c[(k + 1) % 3]);
        counts = counts && fixed[i] == 0 && normal[i].dot(n) >= min_dot;
        gap += (normal[j] - normal[i]).dot(point[j] - point[i]);
        sum_sq += (point[j] - point[i]).squaredNorm();
      }
      // The input's own chords (edges of reference_edge) are not compensated.
      g.gap = gap * (std::max(0.0, 1.0 - 3.0 * reference_edge * reference_edge / sum_sq) / 24.0);
      g.sum_sq = sum_sq;
      g.counts = counts;
    }
  });
  std::vector<double> weighted_gap(nv, 0.0), area(nv, 0.0), edge_sq(nv, 0.0);
  for (std::size_t f = 0; f < corners.size(); ++f) {
    const auto& c = corners[f];
    const double twice_area = face_gap[f].twice_area;
    if (!(twice_area > 0.0)) continue;
    const double gap = face_gap[f].gap, sum_sq = face_gap[f].sum_sq;
    const bool counts = face_gap[f].counts;
    for (const int v : c) {
      const auto i = static_cast<std::size_t>(v);
      area[i] += twice_area;
      edge_sq[i] += twice_area * sum_sq / 3.0;
      if (counts) weighted_gap[i] += twice_area * gap;
    }
  }
  // Each free node moves along its normal by the area-weighted mean gap of its triangles
  // (times strength): moving node v by d changes the volume by about d A_v, A_v a third of
  // its triangles' area, so the moves give back the triangles' volume. A move is at most
  // kMaxMoveEdges of the node's root-mean-square edge (where the curvature is of the order
  // of 1 / edge the estimate no longer holds).
  constexpr double kMaxMoveEdges = 0.1;
  std::size_t n_moved = 0;
  for (std::size_t i = 0; i < nv; ++i) {
    if (fixed[i] != 0 || !(area[i] > 0.0) || weighted_gap[i] == 0.0) continue;
    const double limit = kMaxMoveEdges * std::sqrt(edge_sq[i] / area[i]);
    const double d = std::clamp(strength * weighted_gap[i] / area[i], -limit, limit);
    mesh.set_point(mesh.vertex_handle(static_cast<unsigned>(i)), to_openmesh(point[i] + d * normal[i]));
    ++n_moved;
  }
  return n_moved;
}

}  // namespace nurbsfront::stitch_detail
