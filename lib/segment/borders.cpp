// SPDX-License-Identifier: BSD-3-Clause
// Border curves between patches (and along the input's boundary), their corners, and
// the smoothing of the zig-zag curves that marching cubes leaves.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "nurbsfront/core/error.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/segment/segment_internal.h"

namespace nurbsfront {

void BorderSmoothingOptions::validate() const {
  auto fail = [](const std::string& what) { throw InvalidInput("BorderSmoothingOptions: " + what); };
  if (iterations < 0) fail("iterations must be >= 0, got " + std::to_string(iterations));
  if (!(lambda > 0.0 && lambda <= 1.0)) fail("lambda must be in (0, 1], got " + std::to_string(lambda));
  if (!(mu >= -1.0 && mu <= 0.0)) fail("mu must be in [-1, 0], got " + std::to_string(mu));
  if (!(max_displacement >= 0.0 && std::isfinite(max_displacement)))
    fail("max_displacement must be finite and >= 0, got " + std::to_string(max_displacement));
  if (!(max_input_distance >= 0.0)) fail("max_input_distance must be >= 0, got " + std::to_string(max_input_distance));
}

std::vector<Eigen::Vector3d> smooth_polyline(const std::vector<Eigen::Vector3d>& points, bool is_closed,
                                             const BorderSmoothingOptions& options) {
  options.validate();
  const auto n = static_cast<int>(points.size());
  if (n < 3 || options.iterations == 0) return points;
  double length = 0.0;
  const int n_segments = is_closed ? n : n - 1;
  for (int i = 0; i < n_segments; ++i) length += (points[(i + 1) % n] - points[i]).norm();
  const double bound = options.max_displacement * length / n_segments;
  const int first = is_closed ? 0 : 1;
  const int last = is_closed ? n : n - 1;  // exclusive
  std::vector<Eigen::Vector3d> current = points, next = points;
  auto step = [&](double factor) {
    for (int i = first; i < last; ++i) {
      const Eigen::Vector3d& prev = current[(i + n - 1) % n];
      const Eigen::Vector3d& succ = current[(i + 1) % n];
      Eigen::Vector3d p = current[i] + factor * (0.5 * (prev + succ) - current[i]);
      const Eigen::Vector3d moved = p - points[i];
      const double distance = moved.norm();
      if (distance > bound) p = points[i] + moved * (bound / distance);
      next[i] = p;
    }
    std::swap(current, next);
  };
  for (int it = 0; it < options.iterations; ++it) {
    step(options.lambda);
    if (options.mu != 0.0) step(options.mu);
  }
  return current;
}

namespace segment_detail {

namespace {

// BorderSmoothingOptions::max_input_distance: each smoothed point of the curve farther than
// the bound (times the curve's mean edge) from the input faces around the curve's vertices
// up to two away goes back towards its input position: three quarters, half, a quarter of
// its move, or none, the first within the bound.
void hold_near_input(const TriMesh& mesh, const BorderCurve& curve, const std::vector<Eigen::Vector3d>& positions,
                     const BorderSmoothingOptions& options, std::vector<Eigen::Vector3d>& smoothed) {
  const auto n = static_cast<int>(positions.size());
  if (!std::isfinite(options.max_input_distance) || n < 3 || smoothed.size() != positions.size()) return;
  const int n_segments = curve.is_closed ? n : n - 1;
  double length = 0.0;
  for (int i = 0; i < n_segments; ++i) length += (positions[static_cast<std::size_t>((i + 1) % n)] - positions[static_cast<std::size_t>(i)]).norm();
  const double bound = options.max_input_distance * length / n_segments;
  std::vector<std::array<Eigen::Vector3d, 3>> faces;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (smoothed[k] == positions[k]) continue;
    faces.clear();
    for (int j = i - 2; j <= i + 2; ++j) {
      if (!curve.is_closed && (j < 0 || j >= n)) continue;
      const int w = curve.vertices[static_cast<std::size_t>((j % n + n) % n)];
      for (const auto f : mesh.vf_range(mesh.vertex_handle(static_cast<unsigned>(w)))) {
        std::array<Eigen::Vector3d, 3> t;
        int c = 0;
        for (const auto u : mesh.fv_range(f)) t[static_cast<std::size_t>(c++)] = to_eigen(mesh.point(u));
        faces.push_back(t);
      }
    }
    auto distance = [&](const Eigen::Vector3d& q) {
      double best = std::numeric_limits<double>::infinity();
      for (const auto& t : faces) best = std::min(best, (q - quality_detail::closest_point_on_triangle(q, t[0], t[1], t[2])).norm());
      return best;
    };
    if (distance(smoothed[k]) <= bound) continue;
    const Eigen::Vector3d move = smoothed[k] - positions[k];
    Eigen::Vector3d held = positions[k];
    for (const double share : {0.75, 0.5, 0.25}) {
      const Eigen::Vector3d q = positions[k] + share * move;
      if (distance(q) <= bound) {
        held = q;
        break;
      }
    }
    smoothed[k] = held;
  }
}

}  // namespace

Borders extract_borders(const TriMesh& mesh, const std::vector<int>& face_patch,
                        const BorderSmoothingOptions& options, const unsigned workers,
                        const std::vector<int>* pinned) {
  const auto n_vertices = static_cast<int>(mesh.n_vertices());
  const auto n_edges = static_cast<int>(mesh.n_edges());
  auto patch_of = [&](OpenMesh::HalfedgeHandle h) {
    const auto f = mesh.face_handle(h);
    return f.is_valid() ? face_patch[f.idx()] : -1;
  };
  auto sides = [&](OpenMesh::EdgeHandle e) {
    const int a = patch_of(mesh.halfedge_handle(e, 0)), b = patch_of(mesh.halfedge_handle(e, 1));
    return std::pair{std::min(a, b), std::max(a, b)};
  };
  std::vector<std::uint8_t> is_border(n_edges, 0), visited(n_edges, 0);
  std::vector<std::uint8_t> is_corner(n_vertices, 0);
  // The border edges, then per vertex: a corner where its border edges are not two, or
  // where two of them separate different patch pairs. Both loops in parallel (each task
  // writes only its own edges' or vertices' entries).
  constexpr std::size_t kChunk = 16384;
  parallel_chunks(static_cast<std::size_t>(n_edges), workers, kChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t e = begin; e < end; ++e) {
      const auto s = sides(OpenMesh::EdgeHandle(static_cast<int>(e)));
      is_border[e] = s.first != s.second ? 1 : 0;
    }
  });
  parallel_chunks(static_cast<std::size_t>(n_vertices), workers, kChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t v = begin; v < end; ++v) {
      int degree = 0;
      std::pair<int, int> first{-2, -2};
      bool corner = false;
      for (const auto out : mesh.voh_range(mesh.vertex_handle(static_cast<unsigned>(v)))) {
        const auto e = mesh.edge_handle(out);
        if (is_border[e.idx()] == 0) continue;
        const auto s = sides(e);
        if (++degree == 1) first = s;
        else if (s != first) corner = true;  // two different patch pairs meet
      }
      is_corner[v] = corner || (degree > 0 && degree != 2) ? 1 : 0;
    }
  });
  // Pinned vertices end their curves where they lie on a border (a closed curve through one
  // becomes an open curve from it to itself).
  if (pinned != nullptr)
    for (const int v : *pinned)
      for (const auto out : mesh.voh_range(mesh.vertex_handle(static_cast<unsigned>(v))))
        if (is_border[mesh.edge_handle(out).idx()] != 0) is_corner[v] = 1;
  Borders borders;
  for (int v = 0; v < n_vertices; ++v)
    if (is_corner[v] != 0) borders.corners.push_back(v);

  // Walks from halfedge h until a corner or back at the start vertex.
  auto trace = [&](OpenMesh::HalfedgeHandle h) {
    BorderCurve curve;
    const int start = mesh.from_vertex_handle(h).idx();
    curve.vertices.push_back(start);
    curve.patch_left = patch_of(h);
    curve.patch_right = patch_of(mesh.opposite_halfedge_handle(h));
    while (true) {
      const auto e = mesh.edge_handle(h);
      visited[e.idx()] = 1;
      curve.edges.push_back(e.idx());
      const auto v = mesh.to_vertex_handle(h);
      if (v.idx() == start && is_corner[start] == 0) {
        curve.is_closed = true;
        break;
      }
      curve.vertices.push_back(v.idx());
      if (is_corner[v.idx()] != 0) break;
      OpenMesh::HalfedgeHandle next;
      for (const auto out : mesh.voh_range(v)) {
        const auto oe = mesh.edge_handle(out);
        if (is_border[oe.idx()] != 0 && visited[oe.idx()] == 0) {
          next = out;
          break;
        }
      }
      NURBSFRONT_ASSERT(next.is_valid());
      NURBSFRONT_ASSERT(patch_of(next) == curve.patch_left);
      h = next;
    }
    // Normal form: the left side is a patch, the smaller one when both are patches.
    if (curve.patch_left == -1 || (curve.patch_right != -1 && curve.patch_left > curve.patch_right)) {
      std::swap(curve.patch_left, curve.patch_right);
      std::reverse(curve.edges.begin(), curve.edges.end());
      if (curve.is_closed) std::reverse(curve.vertices.begin() + 1, curve.vertices.end());
      else std::reverse(curve.vertices.begin(), curve.vertices.end());
    }
    return curve;
  };

  for (int c : borders.corners) {
    for (const auto out : mesh.voh_range(mesh.vertex_handle(c))) {
      const auto e = mesh.edge_handle(out);
      if (is_border[e.idx()] != 0 && visited[e.idx()] == 0) borders.curves.push_back(trace(out));
    }
  }
  for (int e = 0; e < n_edges; ++e) {
    if (is_border[e] != 0 && visited[e] == 0)
      borders.curves.push_back(trace(mesh.halfedge_handle(mesh.edge_handle(e), 0)));
  }
  // Each curve is smoothed on its own: in parallel, the same positions for any thread count.
  parallel_chunks(borders.curves.size(), workers, 64, [&](std::size_t begin, std::size_t end, unsigned) {
    std::vector<Eigen::Vector3d> positions;
    for (std::size_t c = begin; c < end; ++c) {
      BorderCurve& curve = borders.curves[c];
      positions.clear();
      positions.reserve(curve.vertices.size());
      for (int w : curve.vertices) positions.push_back(to_eigen(mesh.point(mesh.vertex_handle(w))));
      curve.smoothed = smooth_polyline(positions, curve.is_closed, options);
      hold_near_input(mesh, curve, positions, options, curve.smoothed);
    }
  });
  return borders;
}

}  // namespace segment_detail
}  // namespace nurbsfront
