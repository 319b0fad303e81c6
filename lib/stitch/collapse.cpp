// SPDX-License-Identifier: BSD-3-Clause
// Constrained collapse of the short edges of the worst triangles, before the optimisation:
// where corners sit close together, a curve's last piece is short or a front node lands
// near a border node, no flip or smoothing move removes the short edge; merging its two
// nodes does. Decided on a copy of the assembled mesh, returned as node merges (stitch.cpp
// re-assembles the triangles by the merged ids, so the result is again joined by id).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include <Eigen/Geometry>

#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/stitch/stitch_internal.h"

namespace nurbsfront::stitch_detail {

namespace {

using Vec = Eigen::Vector3d;

// Faces per task of the candidate scan on several threads.
constexpr std::size_t kScanChunk = 8192;

// Two feature corners closer than this (in target edge lengths) may merge.
constexpr double kCoincidentCornersSize = 0.05;

double min_angle_deg(const Vec& a, const Vec& b, const Vec& c) {
  const std::array<double, 3> angles = triangle_angles_deg(a, b, c);
  return std::min({angles[0], angles[1], angles[2]});
}

class Collapser {
 public:
  Collapser(const SurfaceMesh& surface, const StitchOptions& options, const TriMesh& assembled,
            const std::vector<int>& vertex_node, const std::vector<int>& face_patch,
            const std::vector<std::uint8_t>& is_feature, const std::vector<std::uint8_t>& is_frozen)
      : surface_(surface), options_(options), mesh_(assembled), vertex_node_(vertex_node), face_patch_(face_patch),
        is_feature_(is_feature), is_frozen_(is_frozen), rim_(fin_rim_bound(surface, options)) {
    const double diagonal = bounding_box(mesh_).diagonal();
    min_double_area_ = 2.0 * tolerance::kDegenerateAreaRelative * diagonal * diagonal;
    // Position of every border node along its curve (curve, index), for the adjacency test.
    curve_of_.assign(surface.nodes.size(), -1);
    index_on_curve_.assign(surface.nodes.size(), -1);
    for (std::size_t c = 0; c < surface.curve_nodes.size(); ++c) {
      const auto& nodes = surface.curve_nodes[c];
      for (std::size_t i = 0; i < nodes.size(); ++i) {
        const auto g = static_cast<std::size_t>(nodes[i]);
        if (surface.node_kind[g] != NodeKind::Border) continue;
        curve_of_[g] = static_cast<int>(c);
        index_on_curve_[g] = static_cast<int>(i);
      }
    }
  }

  NodeMerges run() {
    NodeMerges out;
    out.target.resize(surface_.nodes.size());
    std::iota(out.target.begin(), out.target.end(), 0);
    // The triangles below the angle, worst first (scanned on n_threads threads:
    // select_in_order gives the serial scan's list).
    const double sin_bound = std::sin(options_.collapse_below_angle_deg * std::numbers::pi / 180.0);
    const bool has_status = mesh_.has_face_status();
    std::vector<std::pair<double, int>> bad = select_in_order<std::pair<double, int>>(
        mesh_.n_faces(), options_.n_threads, kScanChunk, [&](std::size_t i, std::pair<double, int>& found) {
          const TriMesh::FaceHandle f(static_cast<int>(i));
          if (has_status && mesh_.status(f).deleted()) return false;
          std::array<Vec, 3> p;
          int k = 0;
          for (auto v : mesh_.fv_range(f)) p[static_cast<std::size_t>(k++)] = point(mesh_, v);
          if (!may_have_angle_below(p[0], p[1], p[2], sin_bound)) return false;
          const double angle = min_angle_deg(p[0], p[1], p[2]);
          if (!(angle < options_.collapse_below_angle_deg)) return false;
          found = {angle, f.idx()};
          return true;
        });
    std::sort(bad.begin(), bad.end());
    for (const auto& [angle, index] : bad) {
      const TriMesh::FaceHandle f(index);
      if (mesh_.status(f).deleted()) continue;
      // Its shortest edge.
      TriMesh::HalfedgeHandle shortest;
      double length = std::numeric_limits<double>::infinity();
      for (auto h : mesh_.fh_range(f)) {
        const double l = mesh_.calc_edge_length(h);
        if (l < length) {
          length = l;
          shortest = h;
        }
      }
      if (try_collapse(shortest, out) || try_collapse(mesh_.opposite_halfedge_handle(shortest), out)) ++out.n_merges;
    }
    // Chains (b into a, later a into c) resolve to their last survivor.
    for (std::size_t g = 0; g < out.target.size(); ++g) {
      int t = out.target[g];
      while (out.target[static_cast<std::size_t>(t)] != t) t = out.target[static_cast<std::size_t>(t)];
      out.target[g] = t;
    }
    return out;
  }

 private:
  int node(TriMesh::VertexHandle v) const { return vertex_node_[static_cast<std::size_t>(v.idx())]; }

  // Where the survivor a may go when b (the removed node) merges into it: up to 3
  // candidates, 0 when the merge is not allowed. b has the lower rank (inner < border <
  // corner) and is no feature node; a feature survivor never moves.
  int candidates(TriMesh::HalfedgeHandle h, std::array<Vec, 3>& q) const {
    const auto vb = mesh_.from_vertex_handle(h);
    const auto va = mesh_.to_vertex_handle(h);
    const auto b = static_cast<std::size_t>(node(vb));
    const auto a = static_cast<std::size_t>(node(va));
    if (is_frozen_[b] != 0 || mesh_.is_boundary(vb) || mesh_.is_boundary(va)) return 0;
    const NodeKind kb = surface_.node_kind[b];
    const NodeKind ka = surface_.node_kind[a];
    if (node_rank(kb) > node_rank(ka)) return 0;
    const Vec pa = point(mesh_, va), pb = point(mesh_, vb);
    const Vec middle = 0.5 * (pa + pb);
    q[0] = pa;
    // A feature node goes only into a feature corner it nearly coincides with, at the other
    // end of a one-piece curve (two corners the segmentation put a hair apart): the features
    // move by that hair and the survivor stays.
    if (is_feature_[b] != 0) {
      const bool coincident = kb == NodeKind::Corner && ka == NodeKind::Corner && is_feature_[a] != 0 &&
                              (pa - pb).norm() < kCoincidentCornersSize * surface_.target_size &&
                              is_one_piece_curve(static_cast<int>(a), static_cast<int>(b));
      return coincident ? 1 : 0;
    }
    if (is_feature_[a] != 0) return 1;
    if (kb == NodeKind::Inner) {
      if (ka != NodeKind::Inner) return 1;  // into the border (or corner) node, which stays
      if (surface_.node_owner[a] != surface_.node_owner[b]) return 0;
      const std::array<int, 1> own{surface_.node_owner[a]};
      q[1] = project_onto_patches(surface_, own, middle);
      return q[1].allFinite() ? 2 : 1;
    }
    // b on a border: only along its own curve, so the curve keeps its course.
    const TriMesh::FaceHandle f0 = mesh_.face_handle(h), f1 = mesh_.opposite_face_handle(h);
    const int p0 = face_patch_[static_cast<std::size_t>(f0.idx())];
    const int p1 = face_patch_[static_cast<std::size_t>(f1.idx())];
    if (p0 == p1) return 0;
    if (kb == NodeKind::Border) {
      const int c = curve_of_[b];
      if (c < 0 || c != surface_.node_owner[b]) return 0;
      if (!is_next_on_curve(surface_, c, index_on_curve_[b], static_cast<int>(a))) return 0;
      if (ka == NodeKind::Corner) return 1;
      const std::array<int, 2> both{p0, p1};
      q[1] = project_onto_patches(surface_, both, middle);
      return q[1].allFinite() ? 2 : 1;
    }
    // Two corners: only when the edge is a whole curve (one piece).
    if (!is_one_piece_curve(static_cast<int>(a), static_cast<int>(b))) return 0;
    q[1] = middle;
    q[2] = pb;
    return 3;
  }

  // A curve of exactly the two nodes a and b.
  bool is_one_piece_curve(int a, int b) const {
    return std::any_of(
        surface_.curve_nodes.begin(), surface_.curve_nodes.end(), [&](const std::vector<int>& nodes) {
          return nodes.size() == 2 && ((nodes[0] == a && nodes[1] == b) || (nodes[0] == b && nodes[1] == a));
        });
  }

  // Smallest angle (deg) of the triangles around va and vb after collapsing h (b = from(h)
  // into a = to(h)) with a at q; -1 when a triangle degenerates or its normal turns too far.
  double min_angle_after(TriMesh::HalfedgeHandle h, const Vec& q) const {
    const auto vb = mesh_.from_vertex_handle(h);
    const auto va = mesh_.to_vertex_handle(h);
    const TriMesh::FaceHandle f0 = mesh_.face_handle(h), f1 = mesh_.opposite_face_handle(h);
    double smallest = 180.0;
    for (const auto v : {va, vb}) {
      for (auto g : mesh_.vf_range(v)) {
        if (g == f0 || g == f1) continue;
        std::array<TriMesh::VertexHandle, 3> w;
        int k = 0;
        for (auto u : mesh_.fv_range(g)) w[static_cast<std::size_t>(k++)] = u;
        if (v == va && (w[0] == vb || w[1] == vb || w[2] == vb)) continue;  // seen from vb
        std::array<Vec, 3> x, y;
        for (std::size_t i = 0; i < 3; ++i) {
          x[i] = point(mesh_, w[i]);
          y[i] = w[i] == va || w[i] == vb ? q : x[i];
        }
        const Vec n_old = (x[1] - x[0]).cross(x[2] - x[0]), n_new = (y[1] - y[0]).cross(y[2] - y[0]);
        const double l_old = n_old.norm(), l_new = n_new.norm();
        if (l_new <= min_double_area_ || (l_old > 0.0 && n_new.dot(n_old) <= options_.min_normal_dot * l_old * l_new)) return -1.0;
        smallest = std::min(smallest, min_angle_deg(y[0], y[1], y[2]));
      }
    }
    return smallest;
  }

  // Collapses b = from(h) into a = to(h) at the best candidate position when the smallest
  // angle around them grows; records the merge.
  bool try_collapse(TriMesh::HalfedgeHandle h, NodeMerges& merges) {
    std::array<Vec, 3> q;
    const int n = candidates(h, q);
    if (n == 0 || !mesh_.is_collapse_ok(h) || leaves_duplicate_face(mesh_, h)) return false;
    const auto vb = mesh_.from_vertex_handle(h);
    const auto va = mesh_.to_vertex_handle(h);
    double old_min = 180.0;
    for (const auto v : {va, vb}) {
      for (auto g : mesh_.vf_range(v)) {
        std::array<Vec, 3> x;
        int k = 0;
        for (auto u : mesh_.fv_range(g)) x[static_cast<std::size_t>(k++)] = point(mesh_, u);
        old_min = std::min(old_min, min_angle_deg(x[0], x[1], x[2]));
      }
    }
    int best = -1;
    double best_min = old_min;
    for (int i = 0; i < n; ++i) {
      // The survivor within the fin rim bound. A removed rim node goes into its neighbour along
      // its own curve (candidates()): the rim keeps its course.
      if (!rim_.allows(node(va), q[static_cast<std::size_t>(i)])) continue;
      const double m = min_angle_after(h, q[static_cast<std::size_t>(i)]);
      if (m > best_min) {
        best_min = m;
        best = i;
      }
    }
    if (best < 0) return false;
    mesh_.collapse(h);
    mesh_.set_point(va, to_openmesh(q[static_cast<std::size_t>(best)]));
    merges.target[static_cast<std::size_t>(node(vb))] = node(va);
    merges.moved.emplace_back(node(va), q[static_cast<std::size_t>(best)]);
    return true;
  }

  const SurfaceMesh& surface_;
  const StitchOptions& options_;
  TriMesh mesh_;
  const std::vector<int>& vertex_node_;
  const std::vector<int>& face_patch_;
  const std::vector<std::uint8_t>& is_feature_;
  const std::vector<std::uint8_t>& is_frozen_;
  FinRimBound rim_;
  std::vector<int> curve_of_;
  std::vector<int> index_on_curve_;
  double min_double_area_ = 0.0;
};

}  // namespace

bool is_next_on_curve(const SurfaceMesh& surface, int c, int i, int a) {
  const auto& nodes = surface.curve_nodes[static_cast<std::size_t>(c)];
  const int n = static_cast<int>(nodes.size());
  const bool is_closed = surface.node_kind[static_cast<std::size_t>(nodes.front())] == NodeKind::Border;
  auto at = [&](int k) { return nodes[static_cast<std::size_t>(is_closed ? (k + n) % n : k)]; };
  return ((is_closed || i > 0) && at(i - 1) == a) || ((is_closed || i + 1 < n) && at(i + 1) == a);
}

bool leaves_duplicate_face(const TriMesh& mesh, TriMesh::HalfedgeHandle h) {
  const auto vb = mesh.from_vertex_handle(h);
  const auto va = mesh.to_vertex_handle(h);
  const auto vc = mesh.to_vertex_handle(mesh.next_halfedge_handle(h));
  const auto vd = mesh.to_vertex_handle(mesh.next_halfedge_handle(mesh.opposite_halfedge_handle(h)));
  const auto cd = mesh.find_halfedge(vc, vd);
  if (!cd.is_valid()) return false;
  int n_found = 0;
  for (const auto g : {cd, mesh.opposite_halfedge_handle(cd)}) {
    if (mesh.is_boundary(g)) continue;
    const auto w = mesh.to_vertex_handle(mesh.next_halfedge_handle(g));
    if (w == va || w == vb) ++n_found;
  }
  return n_found == 2;
}

NodeMerges collapse_short_edges(const SurfaceMesh& surface, const StitchOptions& options, const StitchResult& assembled,
                                const std::vector<std::uint8_t>& is_feature, const std::vector<std::uint8_t>& is_frozen) {
  if (!(options.collapse_below_angle_deg > 0.0)) {
    NodeMerges none;
    none.target.resize(surface.nodes.size());
    std::iota(none.target.begin(), none.target.end(), 0);
    return none;
  }
  Collapser collapser(surface, options, assembled.mesh, assembled.vertex_node, assembled.face_patch, is_feature, is_frozen);
  return collapser.run();
}

}  // namespace nurbsfront::stitch_detail
