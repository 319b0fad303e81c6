// SPDX-License-Identifier: BSD-3-Clause
// Edges that two patches may both create between their common border nodes (see
// resolve_shared_chords in surfmesh_internal.h).

#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>
#include <map>
#include <set>
#include <unordered_set>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront::surfmesh_detail {

namespace {

using Edge = std::pair<int, int>;

Edge key(int a, int b) { return std::minmax(a, b); }

// key(a, b) of two border node ids (>= 0) in one integer, in the same order as the pairs.
std::uint64_t packed(int a, int b) {
  const Edge e = key(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(e.first)) << 32) | static_cast<std::uint32_t>(e.second);
}

Edge unpacked(std::uint64_t k) { return {static_cast<int>(k >> 32), static_cast<int>(k & 0xffffffffU)}; }

// A point of patch `r`'s plane (frame x, y) of a node id of its triangles (>= 0: global
// border node, < 0: inner node -(id + 1) of the patch).
Eigen::Vector2d plane_point(const PatchResult& r, const BorderNodes& borders, int id) {
  const Eigen::Vector3d& world = id >= 0 ? borders.positions[static_cast<std::size_t>(id)]
                                         : r.inner_nodes[static_cast<std::size_t>(-id - 1)];
  return r.surface.frame.to_local(world).head<2>();
}

// A new inner node of patch r on its surface (clamped, PatchSurface::project) above the
// plane point xy; returns its id.
int add_inner_node(PatchResult& r, const Eigen::Vector2d& xy) {
  r.inner_nodes.push_back(r.surface.project(r.surface.frame.to_world(Eigen::Vector3d(xy.x(), xy.y(), 0.0))));
  return -static_cast<int>(r.inner_nodes.size());
}

// Splits the edge {a, b} of patch r at its midpoint in the plane: each triangle (a, b, w)
// (either direction) becomes (a, m, w) and (m, b, w), which keeps the orientation.
void split_edge(PatchResult& r, const BorderNodes& borders, int a, int b) {
  const int m = add_inner_node(r, 0.5 * (plane_point(r, borders, a) + plane_point(r, borders, b)));
  const std::size_t n = r.triangles.size();
  for (std::size_t t = 0; t < n; ++t) {
    for (int k = 0; k < 3; ++k) {
      std::array<int, 3>& tri = r.triangles[t];
      const int u = tri[static_cast<std::size_t>(k)];
      const int v = tri[static_cast<std::size_t>((k + 1) % 3)];
      if (key(u, v) != key(a, b)) continue;
      const int w = tri[static_cast<std::size_t>((k + 2) % 3)];
      tri = {u, m, w};
      r.triangles.push_back({m, v, w});
      break;
    }
  }
}

// The centroid of a triangle of patch r in its plane.
Eigen::Vector2d centre(const PatchResult& r, const BorderNodes& borders, const std::array<int, 3>& tri) {
  return (plane_point(r, borders, tri[0]) + plane_point(r, borders, tri[1]) + plane_point(r, borders, tri[2])) / 3.0;
}

// Height of patch r's surface above the centroid of its triangle of border nodes, along the
// triangle's normal (oriented like the patch's triangles: outwards).
double bulge(const PatchResult& r, const BorderNodes& borders, const std::array<int, 3>& tri) {
  const Eigen::Vector3d& a = borders.positions[static_cast<std::size_t>(tri[0])];
  const Eigen::Vector3d& b = borders.positions[static_cast<std::size_t>(tri[1])];
  const Eigen::Vector3d& c = borders.positions[static_cast<std::size_t>(tri[2])];
  const Eigen::Vector3d normal = (b - a).cross(c - a);
  const double length = normal.norm();
  if (!(length > 0.0)) return 0.0;
  const Eigen::Vector2d xy = centre(r, borders, tri);
  const Eigen::Vector3d m = r.surface.project(r.surface.frame.to_world(Eigen::Vector3d(xy.x(), xy.y(), 0.0)));
  const double height = (m - (a + b + c) / 3.0).dot(normal) / length;
  return std::isfinite(height) ? height : 0.0;
}

}  // namespace

std::size_t resolve_shared_chords(const Segmentation& seg, const BorderNodes& borders, std::vector<PatchResult>& results) {
  // Every border segment, then the chords of the patches done so far (packed keys: only
  // looked up and added to, never walked).
  std::unordered_set<std::uint64_t> taken;
  taken.reserve(2 * borders.positions.size());
  for (std::size_t c = 0; c < borders.curve_nodes.size(); ++c) {
    const std::vector<int>& nodes = borders.curve_nodes[c];
    for (std::size_t i = 0; i + 1 < nodes.size(); ++i) taken.insert(packed(nodes[i], nodes[i + 1]));
    if (seg.curves[c].is_closed && nodes.size() > 1) taken.insert(packed(nodes.back(), nodes.front()));
  }
  std::vector<std::uint64_t> own;     // the patch's border segments, sorted
  std::vector<std::uint64_t> chords;  // the patch's chords (repeats allowed)
  // Node-sorted triangles of border segments only -> (patch, triangle index).
  std::map<std::array<int, 3>, std::pair<std::size_t, std::size_t>> border_triangles;
  std::size_t n_changes = 0;
  for (std::size_t p = 0; p < results.size(); ++p) {
    PatchResult& r = results[p];
    if (r.report.status != PatchStatus::Ok || r.triangles.empty()) continue;
    // The segments of patch_border(), from the curves' nodes (the closing one of a closed
    // curve too; a merged tiny curve's segment joins a node to itself: no triangle's edge).
    own.clear();
    for (const int c : seg.patches[p].curves) {
      const std::vector<int>& nodes = borders.curve_nodes[static_cast<std::size_t>(c)];
      for (std::size_t i = 0; i + 1 < nodes.size(); ++i) own.push_back(packed(nodes[i], nodes[i + 1]));
      if (seg.curves[static_cast<std::size_t>(c)].is_closed && !nodes.empty()) own.push_back(packed(nodes.back(), nodes.front()));
    }
    std::sort(own.begin(), own.end());
    chords.clear();
    std::set<Edge> to_split;
    std::vector<std::pair<std::size_t, std::size_t>> to_fill;  // (patch, triangle)
    for (std::size_t t = 0; t < r.triangles.size(); ++t) {
      const std::array<int, 3>& tri = r.triangles[t];
      // Chords are edges between two border nodes, also in a triangle with an inner node
      // (headsq at iso 1150: both sides of a fin had the same chord, one patch between two
      // of its own triangles, the other between two triangles with an inner node each).
      bool all_border = tri[0] >= 0 && tri[1] >= 0 && tri[2] >= 0;
      for (int k = 0; k < 3; ++k) {
        const int u = tri[static_cast<std::size_t>(k)], v = tri[static_cast<std::size_t>((k + 1) % 3)];
        if (u < 0 || v < 0) continue;
        const std::uint64_t e = packed(u, v);
        if (std::binary_search(own.begin(), own.end(), e)) continue;
        all_border = false;
        chords.push_back(e);
        if (taken.count(e) != 0) to_split.insert(key(u, v));
      }
      std::array<int, 3> sorted = tri;
      std::sort(sorted.begin(), sorted.end());
      if (!all_border) continue;
      const auto [it, is_new] = border_triangles.emplace(sorted, std::make_pair(p, t));
      if (is_new) continue;
      // The node goes to the side that bulges: a blob of one voxel split into a one-face
      // patch and the rest has the triangle in the plane of that face, and a node on that
      // patch's surface made a flat tetrahedron (ironProt: stitch collapsed it into two
      // coinciding triangles).
      const auto& [q, u] = it->second;
      to_fill.push_back(bulge(results[q], borders, results[q].triangles[u]) > bulge(r, borders, tri) ? it->second
                                                                                                      : std::make_pair(p, t));
    }
    for (const Edge& e : to_split) split_edge(r, borders, e.first, e.second);
    for (const auto& [q, t] : to_fill) {
      PatchResult& f = results[q];
      const std::array<int, 3> tri = f.triangles[t];
      const int m = add_inner_node(f, centre(f, borders, tri));
      f.triangles[t] = {tri[0], tri[1], m};
      f.triangles.push_back({tri[1], tri[2], m});
      f.triangles.push_back({tri[2], tri[0], m});
      f.report.n_inner_nodes = f.inner_nodes.size();
      f.report.n_triangles = f.triangles.size();
    }
    for (const std::uint64_t e : chords)
      if (to_split.count(unpacked(e)) == 0) taken.insert(e);
    n_changes += to_split.size() + to_fill.size();
    r.report.n_inner_nodes = r.inner_nodes.size();
    r.report.n_triangles = r.triangles.size();
  }
  return n_changes;
}

}  // namespace nurbsfront::surfmesh_detail
