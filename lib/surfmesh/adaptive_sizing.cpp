// SPDX-License-Identifier: BSD-3-Clause
// Curvature-adaptive sizing (SizingOptions::adaptive): h = min(base h, sqrt(8 e / kappa_max))
// at the input's vertices from the fitted patch surfaces, limited by the gradation along the
// input's edges, interpolated on the input's triangles. Feature sizing
// (SizingOptions::feature_size): the same with h = min(base h, factor x width) on the
// vertices of crease-bounded patches.

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numeric>
#include <queue>
#include <utility>

#include <Eigen/Geometry>

#include "nurbsfront/core/soup.h"
#include "nurbsfront/nurbs/nurbs_surface.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront::surfmesh_detail {

namespace {

// The sizes at the input's vertices and the tree to find the input triangle nearest to a
// point; shared (read-only) by every copy of the SizeAt it makes, from any thread.
struct VertexSizes {
  TriangleSoup soup;
  std::vector<double> size;  // per vertex
  std::unique_ptr<quality_detail::AabbTree> tree;

  // hint: a face near x (the last answer of coherent queries) or UINT32_MAX; receives the
  // closest face. The answer does not depend on it (ties go to the lowest face index).
  [[nodiscard]] double at(const Eigen::Vector3d& x, std::uint32_t& hint) const {
    const auto closest = tree->closest(x, hint);
    hint = closest.face;
    const auto& t = soup.triangles[closest.face];
    const Eigen::Vector3d& a = soup.points[t[0]];
    const Eigen::Vector3d& b = soup.points[t[1]];
    const Eigen::Vector3d& c = soup.points[t[2]];
    const Eigen::Vector3d q = quality_detail::closest_point_on_triangle(x, a, b, c);
    // Barycentric coordinates of q (areas of the sub-triangles; the closest point is in the
    // triangle, so they are >= 0 up to round-off).
    const Eigen::Vector3d n = (b - a).cross(c - a);
    const double area = n.squaredNorm();
    if (!(area > 0.0)) return std::min({size[t[0]], size[t[1]], size[t[2]]});
    const double wa = std::max(0.0, (c - b).cross(q - b).dot(n) / area);
    const double wb = std::max(0.0, (a - c).cross(q - c).dot(n) / area);
    const double wc = std::max(0.0, 1.0 - wa - wb);
    return wa * size[t[0]] + wb * size[t[1]] + wc * size[t[2]];
  }
};

// The SizeAt of VertexSizes: each call starts its closest-face search at the previous call's
// answer (the front's size grid asks row by row: 5x fewer box tests on femur). The hint is
// a relaxed atomic, so sharing one object between threads is safe; copies (one per patch)
// keep their own.
class HintedSizeAt {
 public:
  explicit HintedSizeAt(std::shared_ptr<const VertexSizes> sizes) : sizes_(std::move(sizes)) {}
  HintedSizeAt(const HintedSizeAt& other) : sizes_(other.sizes_), hint_(other.hint_.load(std::memory_order_relaxed)) {}
  HintedSizeAt& operator=(const HintedSizeAt&) = delete;
  double operator()(const Eigen::Vector3d& x) const {
    std::uint32_t hint = hint_.load(std::memory_order_relaxed);
    const double s = sizes_->at(x, hint);
    hint_.store(hint, std::memory_order_relaxed);
    return s;
  }

 private:
  std::shared_ptr<const VertexSizes> sizes_;
  mutable std::atomic<std::uint32_t> hint_{std::numeric_limits<std::uint32_t>::max()};
};

// Limits the per-vertex sizes along the input's edges (h_v <= h_w + (gradation - 1)
// |x_v - x_w|) and returns them interpolated on the nearest input triangle.
SizeAt graded_sizing(const TriMesh& mesh, std::shared_ptr<VertexSizes> sizes, double gradation) {
  const std::size_t n = mesh.n_vertices();
  // Gradation: h_v <= h_w + (gradation - 1) |x_v - x_w| along the edges, by a Dijkstra-like
  // sweep from the smallest sizes (ties by vertex index: the result does not depend on it,
  // the order of equal keys only fixes the work).
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (std::size_t v = 0; v < n; ++v) queue.emplace(sizes->size[v], static_cast<int>(v));
  const double slope = gradation - 1.0;
  while (!queue.empty()) {
    const auto [h, v] = queue.top();
    queue.pop();
    if (h > sizes->size[static_cast<std::size_t>(v)]) continue;  // stale
    const TriMesh::VertexHandle vh(v);
    for (const auto w : mesh.vv_range(vh)) {
      const double limit = h + slope * (mesh.point(w) - mesh.point(vh)).norm();
      double& hw = sizes->size[static_cast<std::size_t>(w.idx())];
      if (limit < hw) {
        hw = limit;
        queue.emplace(limit, w.idx());
      }
    }
  }
  std::vector<std::uint32_t> faces(sizes->soup.triangles.size());
  std::iota(faces.begin(), faces.end(), 0U);
  sizes->tree = std::make_unique<quality_detail::AabbTree>(sizes->soup, std::move(faces));
  return HintedSizeAt(std::move(sizes));
}

}  // namespace

double max_abs_curvature(const BicubicHeightField& field, double x, double y) {
  const SurfaceCurvature c = curvature_from_derivatives(field.derivatives(x, y));
  const double k = std::max(std::abs(c.k1), std::abs(c.k2));
  return std::isfinite(k) ? k : 0.0;
}

double max_abs_curvature(const PatchSurface& surface, const Eigen::Vector3d& world) {
  const Eigen::Vector3d local = surface.frame.to_local(world);
  return max_abs_curvature(surface.field, local.x(), local.y());
}

SizeAt adaptive_sizing(const TriMesh& mesh, const Segmentation& segmentation, const std::vector<PatchResult>& fits,
                       const SizeAt& base, double chord_error, double min_size, double gradation) {
  auto sizes = std::make_shared<VertexSizes>();
  sizes->soup = to_soup(mesh);
  const std::size_t n = mesh.n_vertices();
  sizes->size.assign(n, 0.0);
  // Curvature-limited size at each vertex: the largest principal curvature of the fitted
  // surfaces of its faces' patches (at the vertex's vertical projection onto each).
  for (const auto v : mesh.vertices()) {
    const Eigen::Vector3d x = to_eigen(mesh.point(v));
    double kappa = 0.0;
    int last_patch = -1;
    for (const auto f : mesh.vf_range(v)) {
      const int p = segmentation.face_patch[static_cast<std::size_t>(f.idx())];
      if (p == last_patch) continue;
      last_patch = p;
      const PatchResult& fit = fits[static_cast<std::size_t>(p)];
      if (fit.has_surface) kappa = std::max(kappa, max_abs_curvature(fit.surface, x));
    }
    double h = base(x);
    if (kappa > 0.0) h = std::min(h, std::sqrt(8.0 * chord_error / kappa));
    sizes->size[static_cast<std::size_t>(v.idx())] = std::max(h, std::min(min_size, base(x)));
  }
  return graded_sizing(mesh, std::move(sizes), gradation);
}

double lattice_edge_vertex_share(const TriMesh& mesh) { return lattice_edge_shares(mesh).on_lattice_edges; }

LatticeShares lattice_edge_shares(const TriMesh& mesh) {
  return mesh.n_vertices() == 0 || mesh.n_edges() == 0 ? LatticeShares{} : lattice_edge_shares(mesh, mean_edge_length(mesh));
}

LatticeShares lattice_edge_shares(const TriMesh& mesh, const double mean_edge) {
  const std::size_t n = mesh.n_vertices();
  const std::size_t m = mesh.n_edges();
  if (n == 0 || m == 0) return {};
  // A cell is not much smaller than an edge: shorter extents are rounding or slivers.
  const double shortest = 0.2 * mean_edge;
  std::vector<std::uint8_t> on_lattice(n, 0);  // per vertex: axes on which it is a lattice value
  std::vector<std::uint8_t> on_half(n, 0);     // per vertex: axes on which it is half-way between two
  // The spacing is found from at most ~64k edges (evenly spread over the indices).
  const std::size_t stride = std::max<std::size_t>(1, m / 65536);
  std::vector<std::pair<double, int>> extent;  // per sampled edge: extent along the axis, edge
  extent.reserve(m / stride + 1);
  for (int axis = 0; axis < 3; ++axis) {
    extent.clear();
    for (std::size_t i = 0; i < m; i += stride) {
      const TriMesh::EdgeHandle e(static_cast<int>(i));
      const auto h = mesh.halfedge_handle(e, 0);
      const double x = std::abs(mesh.point(mesh.to_vertex_handle(h))[axis] - mesh.point(mesh.from_vertex_handle(h))[axis]);
      if (x >= shortest && x > 0.0) extent.emplace_back(x, e.idx());
    }
    std::sort(extent.begin(), extent.end());
    // Spacing: the extent most edges share (to 1e-6): marching cubes joins two points of one
    // cell, and every edge between points on two opposite lattice planes spans one spacing.
    std::size_t group = 0, group_size = 0;
    for (std::size_t i = 0; i < extent.size();) {
      std::size_t j = i + 1;
      while (j < extent.size() && extent[j].first <= extent[i].first * (1.0 + 1e-6)) ++j;
      if (j - i > group_size) group = i, group_size = j - i;
      i = j;
    }
    if (group_size < 2) continue;
    const double spacing = extent[group].first;
    // Origin: the lattice's phase is the one most of the group's ends share (to 1e-3 spacing;
    // marching cubes: both ends of most, on lattice planes), the origin an end of that phase.
    const auto end_value = [&](std::size_t k, int side) {
      const auto h = mesh.halfedge_handle(TriMesh::EdgeHandle(extent[k].second), 0);
      return mesh.point(side == 0 ? mesh.from_vertex_handle(h) : mesh.to_vertex_handle(h))[axis];
    };
    const double reference = end_value(group, 0);
    const auto phase_bin = [&](double x) {
      const double t = (x - reference) / spacing;
      return std::isfinite(t) ? std::min(999, static_cast<int>((t - std::floor(t)) * 1000.0)) : 0;
    };
    std::array<std::uint32_t, 1000> votes{};
    for (std::size_t k = group; k < group + group_size; ++k)
      for (int side = 0; side < 2; ++side) ++votes[static_cast<std::size_t>(phase_bin(end_value(k, side)))];
    // The phase is circular: a lattice value's ends fall into bins 0 and 999 by round-off,
    // so a bin's score also counts its two neighbours (modulo 1000).
    const auto score = [&](int b) {
      return votes[static_cast<std::size_t>((b + 999) % 1000)] + votes[static_cast<std::size_t>(b)] +
             votes[static_cast<std::size_t>((b + 1) % 1000)];
    };
    int bin = 0;
    for (int b = 1; b < 1000; ++b)
      if (score(b) > score(bin)) bin = b;
    const auto near_bin = [&](double x) {
      const int d = std::abs(phase_bin(x) - bin);
      return std::min(d, 1000 - d) <= 1;
    };
    double origin = reference;
    for (std::size_t k = group; k < group + group_size; ++k)
      if (near_bin(end_value(k, 0)) || near_bin(end_value(k, 1))) {
        origin = near_bin(end_value(k, 0)) ? end_value(k, 0) : end_value(k, 1);
        break;
      }
    for (std::size_t w = 0; w < n; ++w) {
      const double t = (mesh.point(TriMesh::VertexHandle(static_cast<int>(w)))[axis] - origin) / spacing;
      const double off = std::abs(t - std::round(t));
      if (off < 1e-3) ++on_lattice[w];
      else if (std::abs(off - 0.5) < 1e-3) ++on_half[w];
    }
  }
  std::size_t count = 0, midpoints = 0;
  for (std::size_t w = 0; w < n; ++w) {
    count += on_lattice[w] >= 2 ? 1 : 0;
    // A label image's edges between two midpoints span half a spacing along an axis; where
    // those are the most common extent, the lattice found is the half one and a midpoint
    // has all three coordinates on it.
    midpoints += on_lattice[w] == 3 || (on_lattice[w] == 2 && on_half[w] == 1) ? 1 : 0;
  }
  return {static_cast<double>(count) / static_cast<double>(n), static_cast<double>(midpoints) / static_cast<double>(n)};
}

bool marching_cubes_lattice(const LatticeShares& shares) { return shares.on_lattice_edges >= 0.5; }

bool vertices_on_lattice_edges(const TriMesh& mesh) { return marching_cubes_lattice(lattice_edge_shares(mesh)); }

bool label_image_staircase(const LatticeShares& shares) { return shares.at_edge_midpoints >= 0.5; }

bool on_label_image_staircase(const TriMesh& mesh) { return label_image_staircase(lattice_edge_shares(mesh)); }

FeatureSizing feature_sizing(const TriMesh& mesh, const Segmentation& segmentation,
                             const std::vector<std::uint8_t>& curve_is_feature, const SizeAt& base, double factor,
                             double min_size, double gradation, double min_area_share) {
  FeatureSizing out;
  std::vector<double> curve_length(segmentation.curves.size(), 0.0);
  for (std::size_t c = 0; c < segmentation.curves.size(); ++c)
    for (const int e : segmentation.curves[c].edges) curve_length[c] += mesh.calc_edge_length(TriMesh::EdgeHandle(e));
  // Width of each patch bounded mostly by feature curves: 2 area / perimeter (a strip of
  // width w: about w; a disk of radius r: r). Elsewhere (no creases) no limit: stitch's
  // flips and smoothing cross those borders.
  std::vector<double> width(segmentation.patches.size(), std::numeric_limits<double>::infinity());
  for (std::size_t p = 0; p < segmentation.patches.size(); ++p) {
    const Patch& patch = segmentation.patches[p];
    double perimeter = 0.0, feature = 0.0;
    for (const int c : patch.curves) {
      perimeter += curve_length[static_cast<std::size_t>(c)];
      if (curve_is_feature[static_cast<std::size_t>(c)] != 0) feature += curve_length[static_cast<std::size_t>(c)];
    }
    if (!(perimeter > 0.0) || feature < kFeatureSizingShare * perimeter) continue;
    double area = 0.0;
    for (const int f : patch.faces) area += mesh.calc_face_area(TriMesh::FaceHandle(f));
    width[p] = 2.0 * area / perimeter;
  }
  if (min_area_share > 0.0) {
    // Area of the faces whose patch's factor x width is below base at their first vertex.
    double total = 0.0, limited_area = 0.0;
    for (const auto f : mesh.faces()) {
      const double a = mesh.calc_face_area(f);
      total += a;
      const double w = width[static_cast<std::size_t>(segmentation.face_patch[static_cast<std::size_t>(f.idx())])];
      if (std::isfinite(w) && factor * w < base(to_eigen(mesh.point(*mesh.cfv_begin(f))))) limited_area += a;
    }
    if (!(limited_area >= min_area_share * total)) return out;
  }
  auto sizes = std::make_shared<VertexSizes>();
  sizes->soup = to_soup(mesh);
  sizes->size.assign(mesh.n_vertices(), 0.0);
  bool limited = false;
  for (const auto v : mesh.vertices()) {
    const Eigen::Vector3d x = to_eigen(mesh.point(v));
    const double h = base(x);
    double w = std::numeric_limits<double>::infinity();
    for (const auto f : mesh.vf_range(v)) w = std::min(w, width[static_cast<std::size_t>(segmentation.face_patch[static_cast<std::size_t>(f.idx())])]);
    const double s = std::max(std::min(h, factor * w), std::min(min_size, h));
    limited = limited || s < h;
    sizes->size[static_cast<std::size_t>(v.idx())] = s;
  }
  if (!limited) return out;
  out.size_at = graded_sizing(mesh, sizes, gradation);
  out.smallest = *std::min_element(sizes->size.begin(), sizes->size.end());
  // Patches whose graded sizes are all base's keep the uniform front (no sizing grid); the
  // others' smallest size sets their sizing grid.
  out.patch_limited.assign(segmentation.patches.size(), 0);
  out.patch_smallest.assign(segmentation.patches.size(), std::numeric_limits<double>::infinity());
  for (std::size_t p = 0; p < segmentation.patches.size(); ++p) {
    for (const int f : segmentation.patches[p].faces) {
      for (const auto v : mesh.fv_range(TriMesh::FaceHandle(f))) {
        const double s = sizes->size[static_cast<std::size_t>(v.idx())];
        out.patch_smallest[p] = std::min(out.patch_smallest[p], s);
        if (s < base(to_eigen(mesh.point(v)))) out.patch_limited[p] = 1;
      }
    }
  }
  return out;
}

SizeAt looked_ahead_sizing(SizeAt size_at, double fraction) {
  return [size_at = std::move(size_at), fraction](const Eigen::Vector3d& x) {
    // The axes and the cube's diagonals: one of the 14 within 35 deg of any direction into
    // a patch, so r cos(35 deg) >= 0.8 r of the look-ahead is taken whichever way the patch lies.
    static constexpr double kD = 0.57735026918962576;  // 1 / sqrt(3)
    static constexpr std::array<std::array<double, 3>, 7> kDirections{{{1.0, 0.0, 0.0},
                                                                      {0.0, 1.0, 0.0},
                                                                      {0.0, 0.0, 1.0},
                                                                      {kD, kD, kD},
                                                                      {kD, kD, -kD},
                                                                      {kD, -kD, kD},
                                                                      {-kD, kD, kD}}};
    const double s = size_at(x);
    const double r = fraction * s;
    double smallest = s;
    for (const auto& d : kDirections) {
      const Eigen::Vector3d step(r * d[0], r * d[1], r * d[2]);
      smallest = std::min({smallest, size_at(x + step), size_at(x - step)});
    }
    return smallest;
  };
}

}  // namespace nurbsfront::surfmesh_detail
