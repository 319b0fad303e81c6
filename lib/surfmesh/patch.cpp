// SPDX-License-Identifier: BSD-3-Clause
// One patch: its frame and height-field fit, the PSLG of its border in the patch plane,
// the 2D front with the surface metric, and the lift of the new nodes.

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <memory>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <unordered_set>

#include "nurbsfront/core/stopwatch.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/front2d/front.h"
#include "nurbsfront/nurbs/mba.h"
#include "nurbsfront/surfmesh/height_field_metric.h"
#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront::surfmesh_detail {

namespace {

// A traced loop that passes a corner twice (a neighbouring patch inside this one touching
// its outer loop there, two lobes joined at a corner) is split into simple cycles
// (split_at_repeated_vertices): a touching hole becomes its own clockwise cycle and gets
// its hole point.

double signed_area(const std::vector<Eigen::Vector2d>& polygon) {
  double twice = 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const auto& a = polygon[i];
    const auto& b = polygon[(i + 1) % polygon.size()];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * twice;
}

// Rings of faces outside the patch added to its fit (1 measured best on level-set and
// occupancy spheres and tori: 2 and 3 pull the level-set fits off), and the smallest
// normal . axis such a
// face must have (a steeper face would fold the height field).
constexpr int kFitOverlapRings = 1;
constexpr double kFitOverlapMinNormalDot = 0.5;
// Faces whose normals differ by at most this (deg) lie in one plane (flat_face_edges).
constexpr double kFlatFaceDeg = 1.0;
// A patch with fewer input faces fits its own vertices only: on thin sheets and sharp folds
// (many patches of a few faces) the ring around it is mostly the other sheet or the steep
// side of the fold and pulled its surface across its neighbours' (self-intersecting pairs,
// 2026-11-25: headsq 76 -> 34, liver 30 -> 22; 8 faces: 66 / 22, 100 faces: 32 / 24).
constexpr std::size_t kFitOverlapMinFaces = 40;


// MBA doubles its lattice per level and stops before the spacing falls below min_spacing,
// so the finest spacing lands anywhere in [s, 2 s) (up to 3 s along the longer side of an
// oblong rectangle): measured on the sphere at 128 cells, 0.048-0.097 for s = 0.038, and the
// fit's error grows with the square of it. Grows the rectangle (about its centre) to
// a 2^L x b 2^L cells of exactly s and starts MBA with a x b cells, so the finest level
// has spacing s on both axes.
void fit_lattice_to_spacing(FitOptions& fit) {
  Rectangle& rect = *fit.domain;
  const double s = fit.min_spacing;
  const double n_x = std::max(1.0, std::ceil(rect.width() / s));
  const double n_y = std::max(1.0, std::ceil(rect.height() / s));
  int levels = 0;  // doublings after level 0
  while (levels + 1 < fit.max_levels && std::ldexp(1.0, levels + 1) <= std::min(n_x, n_y)) ++levels;
  const double scale = std::ldexp(1.0, levels);
  const double a = std::ceil(n_x / scale), b = std::ceil(n_y / scale);
  constexpr double kMaxBaseCells = 4096;  // FitOptions::base_cells' limit
  if (std::min(a, b) > kMaxBaseCells) return;
  const Eigen::Vector2d centre = 0.5 * (rect.min + rect.max);
  const Eigen::Vector2d half(0.5 * a * scale * s, 0.5 * b * scale * s);
  rect = Rectangle{centre - half, centre + half};
  fit.base_cells = static_cast<int>(std::min(a, b));
  fit.min_spacing = s * (1.0 - 1e-9);  // the last level's spacing is s up to round-off
}

// Points on a barycentric grid of spacing about one mean edge over every face whose longest
// edge is above `large_edges` mean edges, without the corners (input vertices, sampled
// already): the fit sees only points. The Stanford bunny's filled holes are fans of faces up
// to 7.5 mean edges long (5335 of its faces exceed 2), and its fit bulged up to one mean edge
// off them between their corners (docs/surfmesh.md, "Large input faces"). Marching-cubes
// surfaces have none (longest edges 1.6-1.9 mean edges).
// Also (flat_edges > 0, below large_edges) over the faces above flat_edges mean edges that lie
// in one plane with at least two of their neighbours (PatchFitOptions::flat_face_edges).
void add_large_face_samples(const TriMesh& mesh, const std::vector<int>& faces, double mean_edge, double large_edges,
                            double flat_edges, std::vector<Eigen::Vector3d>& points) {
  if (!(mean_edge > 0.0)) return;
  if (!(large_edges > 0.0)) large_edges = std::numeric_limits<double>::infinity();
  if (!(flat_edges > 0.0 && flat_edges < large_edges)) flat_edges = large_edges;
  if (std::isinf(flat_edges)) return;
  auto unit_normal = [&mesh](TriMesh::FaceHandle f) {
    std::array<Eigen::Vector3d, 3> y;
    int k = 0;
    for (const auto v : mesh.fv_range(f)) y[k++] = to_eigen(mesh.point(v));
    return (y[1] - y[0]).cross(y[2] - y[0]).normalized();
  };
  const double min_dot = std::cos(kFlatFaceDeg * std::numbers::pi / 180.0);
  for (const int f : faces) {
    std::array<Eigen::Vector3d, 3> x;
    int k = 0;
    for (const auto v : mesh.fv_range(TriMesh::FaceHandle(f))) x[k++] = to_eigen(mesh.point(v));
    const double longest = std::max({(x[1] - x[0]).norm(), (x[2] - x[1]).norm(), (x[0] - x[2]).norm()});
    if (!(longest > flat_edges * mean_edge)) continue;
    if (!(longest > large_edges * mean_edge)) {
      const Eigen::Vector3d n = (x[1] - x[0]).cross(x[2] - x[0]).normalized();
      int n_flat = 0;
      for (const auto g : mesh.ff_range(TriMesh::FaceHandle(f))) n_flat += unit_normal(g).dot(n) >= min_dot ? 1 : 0;
      if (n_flat < 2) continue;
    }
    const int n = static_cast<int>(std::ceil(longest / mean_edge));
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; i + j <= n; ++j) {
        if ((i == n) || (j == n) || (i + j == 0)) continue;  // the corners
        const double a = static_cast<double>(i) / n, b = static_cast<double>(j) / n;
        points.push_back((1.0 - a - b) * x[0] + a * x[1] + b * x[2]);
      }
    }
  }
}

std::string what_of(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "unknown error";
  }
}

}  // namespace

bool fits_own_vertices_only(const Patch& patch) { return patch.faces.size() < kFitOverlapMinFaces; }

std::vector<int> overlap_vertices(const TriMesh& mesh, const Segmentation& seg, int p, int rings) {
  const Patch& patch = seg.patches[static_cast<std::size_t>(p)];
  std::vector<int> frontier;
  // Not across a sharp crease curve: the faces beyond it are another smooth surface, seen
  // from above at a shallow crease (a 40 deg roof: each plane's fit bent by 0.0023 at 1/24
  // cells); faces beyond the steeper creases fail the normal test below anyway.
  // (nor from the corners at its ends).
  std::vector<int> sharp_vertices;
  for (const int c : patch.curves)
    if (is_sharp_crease_curve(seg, c)) {
      const std::vector<int>& vertices = seg.curves[static_cast<std::size_t>(c)].vertices;
      sharp_vertices.insert(sharp_vertices.end(), vertices.begin(), vertices.end());
    }
  std::sort(sharp_vertices.begin(), sharp_vertices.end());
  for (const int c : patch.curves)
    for (const int v : seg.curves[static_cast<std::size_t>(c)].vertices)
      if (!std::binary_search(sharp_vertices.begin(), sharp_vertices.end(), v)) frontier.push_back(v);
  std::unordered_set<int> taken_faces;
  std::vector<int> added;
  const int n_rings = fits_own_vertices_only(patch) ? 0 : rings;
  for (int ring = 0; ring < n_rings && !frontier.empty(); ++ring) {
    std::vector<int> next;
    for (const int v : frontier) {
      for (const auto f : mesh.vf_range(TriMesh::VertexHandle(v))) {
        if (seg.face_patch[static_cast<std::size_t>(f.idx())] == p || taken_faces.count(f.idx()) != 0) continue;
        const Eigen::Vector3d n = to_eigen(mesh.calc_face_normal(f));
        if (!(n.dot(patch.axis) >= kFitOverlapMinNormalDot)) continue;
        taken_faces.insert(f.idx());
        for (const auto w : mesh.fv_range(f)) next.push_back(w.idx());
      }
    }
    added.insert(added.end(), next.begin(), next.end());
    frontier = std::move(next);
  }
  std::sort(added.begin(), added.end());
  added.erase(std::unique(added.begin(), added.end()), added.end());
  // Keep only vertices outside the patch (its own are fitted already).
  std::vector<int> out;
  for (const int v : added) {
    bool in_patch = false;
    for (const auto f : mesh.vf_range(TriMesh::VertexHandle(v)))
      if (seg.face_patch[static_cast<std::size_t>(f.idx())] == p) in_patch = true;
    if (!in_patch) out.push_back(v);
  }
  return out;
}

// Traces the directed edges into loops. Where loops touch (a node with several outgoing
// edges), the next edge is the first outgoing one clockwise from the incoming edge's
// reverse: it bounds the domain sector on the left of the incoming edge.
std::vector<std::vector<int>> trace_loops(const std::vector<Eigen::Vector2d>& xy, const std::vector<std::array<int, 2>>& edges) {
  // The edges leaving each node, in edge order (compressed rows: no allocation per node).
  std::vector<int> out_start(xy.size() + 1, 0), out_edges(edges.size());
  for (const auto& edge : edges) ++out_start[static_cast<std::size_t>(edge[0]) + 1];
  for (std::size_t i = 0; i < xy.size(); ++i) out_start[i + 1] += out_start[i];
  {
    std::vector<int> fill(out_start.begin(), out_start.end() - 1);
    for (std::size_t e = 0; e < edges.size(); ++e)
      out_edges[static_cast<std::size_t>(fill[static_cast<std::size_t>(edges[e][0])]++)] = static_cast<int>(e);
  }
  const auto outgoing = [&](int v) {
    return std::span<const int>(out_edges.data() + out_start[static_cast<std::size_t>(v)],
                                static_cast<std::size_t>(out_start[static_cast<std::size_t>(v) + 1] - out_start[static_cast<std::size_t>(v)]));
  };
  std::vector<bool> used(edges.size(), false);
  std::vector<std::vector<int>> loops;
  for (std::size_t start = 0; start < edges.size(); ++start) {
    if (used[start]) continue;
    std::vector<int> loop;
    int e = static_cast<int>(start);
    while (e >= 0 && !used[static_cast<std::size_t>(e)]) {
      used[static_cast<std::size_t>(e)] = true;
      const auto [u, v] = edges[static_cast<std::size_t>(e)];
      loop.push_back(u);
      // One edge leaves v (most nodes): it is the next one if unused, without the angles.
      const std::span<const int> out_v = outgoing(v);
      if (out_v.size() == 1) {
        e = used[static_cast<std::size_t>(out_v.front())] ? -1 : out_v.front();
        continue;
      }
      const Eigen::Vector2d back = xy[static_cast<std::size_t>(u)] - xy[static_cast<std::size_t>(v)];
      const double a0 = std::atan2(back.y(), back.x());
      int best = -1;
      double best_sweep = 0.0;
      for (const int cand : out_v) {
        if (used[static_cast<std::size_t>(cand)]) continue;
        const Eigen::Vector2d d = xy[static_cast<std::size_t>(edges[static_cast<std::size_t>(cand)][1])] - xy[static_cast<std::size_t>(v)];
        double sweep = a0 - std::atan2(d.y(), d.x());
        while (sweep <= 0.0) sweep += 2.0 * std::numbers::pi;
        if (best < 0 || sweep < best_sweep) {
          best = cand;
          best_sweep = sweep;
        }
      }
      e = best;
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

bool point_inside_polygon(const std::vector<Eigen::Vector2d>& polygon, Eigen::Vector2d& inside) {
  const std::size_t n = polygon.size();
  if (n < 3) return false;
  // The leftmost (then lowest) vertex is convex: points just inside its corner are inside.
  std::size_t v = 0;
  for (std::size_t i = 1; i < n; ++i)
    if (polygon[i].x() < polygon[v].x() || (polygon[i].x() == polygon[v].x() && polygon[i].y() < polygon[v].y())) v = i;
  const Eigen::Vector2d& c = polygon[v];
  const Eigen::Vector2d d = (polygon[(v + n - 1) % n] - c) + (polygon[(v + 1) % n] - c);
  double s = 1.0 / 3.0;
  for (int k = 0; k < 40; ++k, s *= 0.5) {
    const Eigen::Vector2d q = c + s * d;
    if (polygon_contains(polygon, q)) {
      inside = q;
      return true;
    }
  }
  return false;
}

BorderCycles border_cycles(const std::vector<Eigen::Vector2d>& xy, const std::vector<std::array<int, 2>>& edges) {
  BorderCycles out;
  for (const auto& loop : trace_loops(xy, edges)) {
    double loop_area = 0.0;
    for (auto& cycle : split_at_repeated_vertices(loop)) {
      std::vector<Eigen::Vector2d>& polygon = out.polygons.emplace_back();
      for (const int i : cycle) polygon.push_back(xy[static_cast<std::size_t>(i)]);
      out.areas.push_back(signed_area(polygon));
      loop_area += out.areas.back();
      out.cycles.push_back(std::move(cycle));
    }
    out.area += loop_area;
    if (loop_area >= 0.0) ++out.n_ccw_loops;
  }
  // Faces of the loop arrangement with winding number 0 are holes, 1 is the domain; the
  // y range of each cycle skips most even-odd tests (exactly: no edge straddles a point
  // outside it).
  const std::size_t n = out.polygons.size();
  std::vector<double> orientation(n), y_lo(n), y_hi(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto& polygon = out.polygons[k];
    orientation[k] = out.areas[k] >= 0.0 ? 1.0 : -1.0;
    y_lo[k] = y_hi[k] = polygon.front().y();
    for (const auto& q : polygon) {
      y_lo[k] = std::min(y_lo[k], q.y());
      y_hi[k] = std::max(y_hi[k], q.y());
    }
  }
  out.has_inside.assign(n, 0);
  out.inside.assign(n, Eigen::Vector2d::Zero());
  out.winding.assign(n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    Eigen::Vector2d& q = out.inside[k];
    if (!point_inside_polygon(out.polygons[k], q)) continue;
    out.has_inside[k] = 1;
    for (std::size_t j = 0; j < n; ++j)
      if (q.y() >= y_lo[j] && q.y() < y_hi[j] && polygon_contains(out.polygons[j], q)) out.winding[k] += orientation[j];
  }
  return out;
}

bool BorderCycles::meshable() const {
  if (n_ccw_loops != 1) return false;
  for (std::size_t k = 0; k < cycles.size(); ++k)
    if (has_inside[k] == 0 || (winding[k] != 0.0 && winding[k] != 1.0)) return false;
  return true;
}

std::vector<Eigen::Vector3d> patch_vertex_points(const TriMesh& mesh, const Patch& patch) {
  std::vector<int> vertices;
  vertices.reserve(3 * patch.faces.size());
  for (const int f : patch.faces)
    for (const auto v : mesh.fv_range(TriMesh::FaceHandle(f))) vertices.push_back(v.idx());
  std::vector<Eigen::Vector3d> points;
  if (vertices.empty()) return points;
  // Ascending ids, each once: a bit per id from the smallest to the largest (cheaper than
  // sorting the three ids of every face).
  const auto [lowest, highest] = std::minmax_element(vertices.begin(), vertices.end());
  const int first = *lowest;
  std::vector<std::uint64_t> bits(static_cast<std::size_t>(*highest - first) / 64 + 1, 0);
  for (const int v : vertices) {
    const auto bit = static_cast<std::size_t>(v - first);
    bits[bit / 64] |= std::uint64_t{1} << (bit % 64);
  }
  std::size_t n = 0;
  for (const std::uint64_t word : bits) n += static_cast<std::size_t>(std::popcount(word));
  points.reserve(n);
  for (std::size_t w = 0; w < bits.size(); ++w)
    for (std::uint64_t word = bits[w]; word != 0; word &= word - 1)
      points.push_back(to_eigen(mesh.point(TriMesh::VertexHandle(first + static_cast<int>(64 * w) + std::countr_zero(word)))));
  return points;
}

namespace {
// The margin around a fit's rectangle, so every evaluation during meshing is inside.
double fit_margin(double mean_edge, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  return 0.02 * (hi - lo).norm() + mean_edge;
}
}  // namespace

FitOptions plain_fit_options(const SurfMeshOptions& options, double mean_edge, const Eigen::Vector2d& lo,
                             const Eigen::Vector2d& hi) {
  const double margin = fit_margin(mean_edge, lo, hi);
  FitOptions fit;
  fit.tolerance = options.fit.relative_tolerance * mean_edge;
  fit.min_spacing = options.fit.min_spacing_edges * mean_edge;
  fit.max_levels = options.fit.max_levels;
  fit.least_squares_iterations = options.fit.least_squares_iterations;
  fit.final_passes = options.fit.final_passes;
  // Not with adaptive sizing: SurfmeshAdaptiveSlow's flat ellipsoid got 750 instead of 791
  // nodes and 0.0105 instead of 0.0090 max deviation with it (not diagnosed).
  fit.least_squares_fine_smoothing = options.sizing.adaptive ? 0.0 : options.fit.least_squares_fine_smoothing;
  fit.least_squares_fine_below = options.fit.fine_below_edges * mean_edge;
  fit.domain = Rectangle{lo - Eigen::Vector2d::Constant(margin), hi + Eigen::Vector2d::Constant(margin)};
  if (!options.cell_grid.enabled && fit.min_spacing > 0.0) fit_lattice_to_spacing(fit);
  return fit;
}

void fit_patch(const TriMesh& mesh, const Segmentation& seg, int p, const BorderNodes& borders,
               const SurfMeshOptions& options, double mean_edge, PatchResult& result) {
  const Stopwatch clock;
  const Patch& patch = seg.patches[static_cast<std::size_t>(p)];
  result.report.n_input_faces = patch.faces.size();
  try {
    std::vector<Eigen::Vector3d> points = patch_vertex_points(mesh, patch);
    const std::vector<Eigen::Vector3d> normals(points.size(), patch.axis);
    const PatchFrame frame = patch_frame(points, normals);
    // The fit also sees a few rings of the neighbouring patches' faces (those the axis
    // still sees from above), so it is determined beyond the border, where MBA alone is
    // weakest and both patches' surfaces must agree.
    const std::size_t n_own = points.size();
    for (const int v : overlap_vertices(mesh, seg, p, kFitOverlapRings)) points.push_back(to_eigen(mesh.point(TriMesh::VertexHandle(v))));
    // The band fit (cell_grid) takes bands at vertices only; plain points on faces would bias it.
    if (!options.cell_grid.enabled)
      add_large_face_samples(mesh, patch.faces, mean_edge, options.fit.large_face_edges, options.fit.flat_face_edges, points);
    std::vector<Eigen::Vector3d> local = frame.to_local(points);

    // The rectangle covers the vertices and the border nodes, slightly enlarged, so every
    // evaluation during meshing is inside.
    Eigen::Vector2d lo = local.front().head<2>();
    Eigen::Vector2d hi = lo;
    auto extend = [&](const Eigen::Vector3d& q) {
      lo = lo.cwiseMin(q.head<2>());
      hi = hi.cwiseMax(q.head<2>());
    };
    for (const auto& q : local) extend(q);
    for (const int c : patch.curves)
      for (const int g : borders.curve_nodes[static_cast<std::size_t>(c)])
        extend(frame.to_local(borders.positions[static_cast<std::size_t>(g)]));
    FitOptions fit = plain_fit_options(options, mean_edge, lo, hi);
    result.surface.frame = frame;
    bool plain = !options.cell_grid.enabled;
    if (!plain) {
      // Cell-based input: fit the bands of the vertices (docs/surfmesh.md, "Cell-based inputs").
      const CellGrid& grid_in = options.cell_grid;
      // A patch whose fit meets its bands closely is smooth there: it is refitted with more
      // rings of its neighbours' faces, which carry their curvature over a wide terrace that
      // one ring leaves to the prior (the top ring of the occupancy torus's tube sat 0.4 voxel
      // low). Not where the fit misses bands (a patch across a sharp edge: the wider rings
      // rounded the occupancy DRAM cell's edges off, volume -0.35% -> -0.9%). The test is
      // made on the fit before its curvature passes, which such a patch then skips (the wide
      // refit does them), and the wide refit starts from that fit.
      const bool wide = grid_in.wide_overlap_rings > kFitOverlapRings;
      const double gate = grid_in.wide_overlap_max_miss_cells * grid_in.spacing.minCoeff();
      // A curved patch gets a shorter smoothing length, estimated from its vertices before the
      // fit: 2.25 cells flattened the tube of the occupancy torus at 48 and 64 cells (radius 6
      // and 8 cells; docs/surfmesh.md, "Smoothing length of curved patches").
      CellGrid grid = grid_in;
      grid.smoothing_cells = curved_smoothing_cells(mesh, seg, p, grid_in);
      BandFitResult fitted = fit_cell_bands(points, frame, grid, *fit.domain, nullptr, wide ? gate : -1.0);
      // A patch whose band fit still misses a band by more than plain_fit_miss_cells holds
      // a sharp (bevelled) edge that the smooth fit rounds off: it gets the plain fit of its
      // vertices instead (occupancy DRAM cell at 128: Hausdorff to the input 1.18 -> 0.91
      // voxel; docs/surfmesh.md, "Sharp edges on cell-based inputs").
      if (grid.plain_fit_miss_cells > 0.0 && fitted.max_miss > grid.plain_fit_miss_cells * grid.spacing.minCoeff()) {
        plain = true;
      } else if (wide && fitted.max_miss <= gate) {
        points.resize(n_own);
        for (const int v : overlap_vertices(mesh, seg, p, grid.wide_overlap_rings)) points.push_back(to_eigen(mesh.point(TriMesh::VertexHandle(v))));
        Rectangle domain = *fit.domain;
        const double margin = fit_margin(mean_edge, lo, hi);
        for (const auto& q : frame.to_local(points)) {
          domain.min = domain.min.cwiseMin(q.head<2>() - Eigen::Vector2d::Constant(margin));
          domain.max = domain.max.cwiseMax(q.head<2>() + Eigen::Vector2d::Constant(margin));
        }
        const BicubicHeightField first = std::move(fitted.field);
        fitted = fit_cell_bands(points, frame, grid, domain, &first);
      }
      if (!plain) {
        result.band_fit = true;
        result.surface.field = std::move(fitted.field);
        result.report.fit_max_residual = fitted.max_miss;
        result.report.fit_levels = 1;
      } else {
        add_large_face_samples(mesh, patch.faces, mean_edge, options.fit.large_face_edges, options.fit.flat_face_edges, points);
        local = frame.to_local(points);
        if (fit.min_spacing > 0.0) fit_lattice_to_spacing(fit);
      }
    }
    if (plain) {
      FitResult fitted = fit_height_field(local, fit);
      // Detail fit (PatchFitOptions::detail_spacing_edges): a patch that the lattice misses
      // is refitted on the finer one.
      const PatchFitOptions& o = options.fit;
      if (o.detail_spacing_edges > 0.0 && !options.cell_grid.enabled && fitted.max_residual() > o.detail_above_edges * mean_edge) {
        SurfMeshOptions detail = options;
        detail.fit.min_spacing_edges = o.detail_spacing_edges;
        FitResult refit = fit_height_field(local, plain_fit_options(detail, mean_edge, lo, hi));
        // The refit is kept unless it misses the patch's own points by more on average (sums
        // over the same n_own points; not the largest miss: on the brain 3 of 39 refits miss
        // one point by 2-20% more, with a mean miss a third of the plain fit's; nor the
        // overlap ring's points, other patches' faces, which can dominate both fits' largest
        // residual).
        const auto own_miss_sum = [&](const BicubicHeightField& field) {
          double sum = 0.0;
          for (std::size_t i = 0; i < n_own; ++i) sum += std::abs(local[i].z() - field.value(local[i].x(), local[i].y()));
          return sum;
        };
        if (own_miss_sum(refit.field) <= own_miss_sum(fitted.field)) {
          fitted = std::move(refit);
          result.report.detail_fit = true;
        }
      }
      result.surface.field = std::move(fitted.field);
      result.report.fit_max_residual = fitted.max_residual();
      result.report.fit_levels = static_cast<int>(fitted.levels.size());
    }
    result.has_surface = true;
  } catch (...) {
    result.report.status = PatchStatus::FitFailed;
    result.report.message = "fit failed: " + what_of(std::current_exception());
  }
  result.report.seconds += clock.seconds();
}

}  // namespace nurbsfront::surfmesh_detail

namespace nurbsfront {

PatchInputHeights::PatchInputHeights(const TriMesh& mesh, const std::vector<int>& faces, const PatchFrame& frame) {
  // The faces in the frame, in a uniform grid of about one face per cell.
  faces_.resize(faces.size());
  lo_ = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo_;
  std::vector<std::array<double, 4>> box(faces.size());  // per face: min x, min y, max x, max y
  for (std::size_t i = 0; i < faces.size(); ++i) {
    // The face's vertices in fv_range's order (the halfedge's head, then on along the face)
    // without its circulator.
    std::array<Eigen::Vector3d, 3> t;
    TriMesh::HalfedgeHandle h = mesh.halfedge_handle(TriMesh::FaceHandle(faces[i]));
    for (std::size_t k = 0; k < 3; ++k, h = mesh.next_halfedge_handle(h)) {
      t[k] = frame.to_local(to_eigen(mesh.point(mesh.to_vertex_handle(h))));
      lo_ = lo_.cwiseMin(t[k].head<2>());
      hi = hi.cwiseMax(t[k].head<2>());
    }
    box[i] = {std::min({t[0].x(), t[1].x(), t[2].x()}), std::min({t[0].y(), t[1].y(), t[2].y()}),
              std::max({t[0].x(), t[1].x(), t[2].x()}), std::max({t[0].y(), t[1].y(), t[2].y()})};
    Face& f = faces_[i];
    f.x0 = t[0].x();
    f.y0 = t[0].y();
    f.ex1 = t[1].x() - t[0].x();
    f.ey1 = t[1].y() - t[0].y();
    f.ex2 = t[2].x() - t[0].x();
    f.ey2 = t[2].y() - t[0].y();
    f.area = f.ex1 * f.ey2 - f.ey1 * f.ex2;
    f.z0 = t[0].z();
    f.z1 = t[1].z();
    f.z2 = t[2].z();
  }
  if (faces.empty()) return;
  extent_ = (hi - lo_).cwiseMax(std::numeric_limits<double>::min());
  const double cell = std::sqrt(extent_.x() * extent_.y() / static_cast<double>(faces.size())) + std::numeric_limits<double>::min();
  nx_ = std::clamp(static_cast<int>(extent_.x() / cell) + 1, 1, 4096);
  ny_ = std::clamp(static_cast<int>(extent_.y() / cell) + 1, 1, 4096);
  // Two sweeps over the faces' cell ranges: count per cell, then fill (a counting sort).
  // A face of zero (or NaN) area goes into no cell: height() skipped it.
  const std::size_t nx = static_cast<std::size_t>(nx_);
  std::vector<std::array<int, 4>> range(faces_.size());  // per face: first and last column, first and last row
  cell_start_.assign(nx * static_cast<std::size_t>(ny_) + 1, 0);
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    if (!(std::abs(faces_[f].area) > 0.0)) {
      range[f] = {1, 0, 1, 0};
      continue;
    }
    range[f] = {column_of(box[f][0]), column_of(box[f][2]), row_of(box[f][1]), row_of(box[f][3])};
    for (int j = range[f][2]; j <= range[f][3]; ++j)
      for (int i = range[f][0]; i <= range[f][1]; ++i) ++cell_start_[static_cast<std::size_t>(j) * nx + static_cast<std::size_t>(i) + 1];
  }
  for (std::size_t k = 1; k < cell_start_.size(); ++k) cell_start_[k] += cell_start_[k - 1];
  cell_faces_.resize(cell_start_.back());
  std::vector<std::size_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t f = 0; f < faces_.size(); ++f)
    for (int j = range[f][2]; j <= range[f][3]; ++j)
      for (int i = range[f][0]; i <= range[f][1]; ++i)
        cell_faces_[fill[static_cast<std::size_t>(j) * nx + static_cast<std::size_t>(i)]++] = static_cast<int>(f);
}

int PatchInputHeights::column_of(double x) const { return std::clamp(static_cast<int>((x - lo_.x()) / extent_.x() * nx_), 0, nx_ - 1); }

int PatchInputHeights::row_of(double y) const { return std::clamp(static_cast<int>((y - lo_.y()) / extent_.y() * ny_), 0, ny_ - 1); }

bool PatchInputHeights::height(double x, double y, double& z) const {
  if (cell_start_.empty() || !std::isfinite(x) || !std::isfinite(y)) return false;
  const std::size_t cell = static_cast<std::size_t>(row_of(y)) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(column_of(x));
  for (std::size_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
    const Face& t = faces_[static_cast<std::size_t>(cell_faces_[k])];
    const double dx = x - t.x0, dy = y - t.y0;
    const double b1 = (dx * t.ey2 - dy * t.ex2) / t.area;
    if (b1 < 0.0) continue;  // most candidates: the second division is not needed
    const double b2 = (t.ex1 * dy - t.ey1 * dx) / t.area;
    if (b2 < 0.0 || b1 + b2 > 1.0) continue;
    z = (1.0 - b1 - b2) * t.z0 + b1 * t.z1 + b2 * t.z2;
    return true;
  }
  return false;
}

}  // namespace nurbsfront

namespace nurbsfront::surfmesh_detail {

std::size_t clamp_inner_nodes(const TriMesh& mesh, const Segmentation& seg, int p, double max_offset, PatchResult& result) {
  if (!result.has_surface) return 0;
  result.surface.input_heights =
      std::make_shared<const PatchInputHeights>(mesh, seg.patches[static_cast<std::size_t>(p)].faces, result.surface.frame);
  result.surface.max_offset = max_offset;
  std::size_t n_clamped = 0;
  for (auto& node : result.inner_nodes) {
    const Eigen::Vector3d q = result.surface.project(node);
    if (q != node) ++n_clamped;
    node = q;
  }
  return n_clamped;
}

void mesh_patch(const Segmentation& seg, int p, const BorderNodes& borders, const SurfMeshOptions& options,
                double uniform_size, const SizeAt& size_at, double sizing_grid, PatchResult& result) {
  if (!result.has_surface) return;
  const Stopwatch clock;
  try {
    const PatchSurface& surface = result.surface;
    const PatchBorder border = patch_border(seg, p, borders);
    result.report.n_border_nodes = border.nodes.size();
    if (border.edges.size() < 3) throw std::runtime_error("the patch has no closed border");
    Pslg pslg;
    pslg.points.reserve(border.nodes.size());
    for (const int g : border.nodes)
      pslg.points.push_back(surface.frame.to_local(borders.positions[static_cast<std::size_t>(g)]).head<2>());
    pslg.segments = border.edges;
    // Faces of the loop arrangement with winding number 0 are holes (front2d needs a point
    // inside each); 1 is the domain; anything else means the projected border folds.
    const BorderCycles cycles = border_cycles(pslg.points, border.edges);
    const double border_area = cycles.area;  // area on the left of the directed border
    // The segmentation guarantees one counter-clockwise (outer) loop; a second one means
    // the discretised border folds in this plane.
    if (cycles.n_ccw_loops != 1)
      throw std::runtime_error("the border has " + std::to_string(cycles.n_ccw_loops) +
                               " counter-clockwise loops in the patch plane (expected 1: it folds)");
    for (std::size_t k = 0; k < cycles.cycles.size(); ++k) {
      if (cycles.has_inside[k] == 0) throw std::runtime_error("a border loop is degenerate in the patch plane");
      if (cycles.winding[k] == 0.0) {
        pslg.holes.push_back(cycles.inside[k]);
      } else if (cycles.winding[k] != 1.0) {
        throw std::runtime_error("the border folds in the patch plane (winding number " + std::to_string(cycles.winding[k]) + ")");
      }
    }

    FrontOptions front;
    const BicubicHeightField& field = surface.field;
    const PatchFrame& frame = surface.frame;
    // Adaptive sizes sampled once on a grid over the fit's rectangle (bilinear in between):
    // the front asks for sizes far more often than there are grid points.
    const auto lifted_size = [&size_at, &field, &frame](double x, double y) { return size_at(frame.to_world(field.lift(x, y))); };
    std::vector<double> grid;
    int n_x = 0, n_y = 0;
    double step_x = 0.0, step_y = 0.0;
    // The grid covers the border's box (the front places nodes inside the border only), one
    // grid step wider, within the fit's rectangle (often much larger: overlap ring), whose
    // far corners lifted off the input made the size lookups slow.
    Rectangle box = field.domain();
    if (size_at && sizing_grid > 0.0) {
      Eigen::Vector2d lo = pslg.points.front(), hi = pslg.points.front();
      for (const auto& q : pslg.points) {
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
      }
      const Eigen::Vector2d margin = Eigen::Vector2d::Constant(sizing_grid);
      const Eigen::Vector2d new_min = box.min.cwiseMax(lo - margin), new_max = box.max.cwiseMin(hi + margin);
      if ((new_max - new_min).minCoeff() > 0.0) {
        box.min = new_min;
        box.max = new_max;
      }
    }
    if (size_at && sizing_grid > 0.0) {
      n_x = std::max(1, static_cast<int>(std::ceil(box.width() / sizing_grid)));
      n_y = std::max(1, static_cast<int>(std::ceil(box.height() / sizing_grid)));
      step_x = box.width() / n_x;
      step_y = box.height() / n_y;
      grid.resize(static_cast<std::size_t>(n_x + 1) * static_cast<std::size_t>(n_y + 1));
      for (int j = 0; j <= n_y; ++j)
        for (int i = 0; i <= n_x; ++i)
          grid[static_cast<std::size_t>(j) * static_cast<std::size_t>(n_x + 1) + static_cast<std::size_t>(i)] =
              lifted_size(box.min.x() + i * step_x, box.min.y() + j * step_y);
    }
    if (!grid.empty()) {
      front.sizing = SizingField::from_callback([&grid, n_x, n_y, step_x, step_y, box](const Eigen::Vector2d& xy) {
        const double u = std::clamp((xy.x() - box.min.x()) / step_x, 0.0, static_cast<double>(n_x));
        const double v = std::clamp((xy.y() - box.min.y()) / step_y, 0.0, static_cast<double>(n_y));
        const int i = std::min(static_cast<int>(u), n_x - 1), j = std::min(static_cast<int>(v), n_y - 1);
        const double s = u - i, t = v - j;
        const auto at = [&](int a, int b) {
          return grid[static_cast<std::size_t>(b) * static_cast<std::size_t>(n_x + 1) + static_cast<std::size_t>(a)];
        };
        return (1.0 - t) * ((1.0 - s) * at(i, j) + s * at(i + 1, j)) + t * ((1.0 - s) * at(i, j + 1) + s * at(i + 1, j + 1));
      });
      // The sampled sizes are graded already (along the input's edges): front2d's gradation
      // grid need not be finer than theirs (its 128 x 128 sweeps were a quarter of the CPU
      // of feature sizing on femur). At least 8 cells.
      front.sizing.callback_grid_cells = std::clamp(std::max(n_x, n_y), 8, SizingField::kMaxCallbackGridCells);
    } else if (size_at) {
      front.sizing = SizingField::from_callback([&lifted_size](const Eigen::Vector2d& xy) { return lifted_size(xy.x(), xy.y()); });
    } else {
      front.sizing = SizingField::uniform(uniform_size);
    }
    front.sizing.gradation = options.sizing.gradation;
    front.metric = std::make_shared<HeightFieldMetric>(field);
    front.split_segments = false;
    front.smoothing_passes = options.smoothing_passes;
    front.corner_split_angle_deg = options.corner_split_angle_deg;
    const Mesh2d mesh2d = mesh_pslg(pslg, front);
    if (mesh2d.report.status != FrontStatus::Ok)
      throw std::runtime_error("the 2D front did not close: " + mesh2d.report.message);
    // front2d meshes every bounded face without a hole point; where the discretised border
    // folds (a loop on the wrong side), that differs from the area left of the border.
    double meshed_area = 0.0;
    for (const auto& t : mesh2d.triangles) {
      const Eigen::Vector2d& a = mesh2d.points[static_cast<std::size_t>(t[0])];
      meshed_area += 0.5 * ((mesh2d.points[static_cast<std::size_t>(t[1])] - a).x() * (mesh2d.points[static_cast<std::size_t>(t[2])] - a).y() -
                            (mesh2d.points[static_cast<std::size_t>(t[1])] - a).y() * (mesh2d.points[static_cast<std::size_t>(t[2])] - a).x());
    }
    if (!(std::abs(meshed_area - border_area) <= tolerance::kMeshedAreaRelative * std::abs(border_area)))
      throw std::runtime_error("the meshed area differs from the area inside the border (the border folds in the patch plane)");
    for (const auto& chain : mesh2d.segment_chains)
      if (chain.size() != 2) throw std::runtime_error("the 2D front split a border segment");
    const int n_input = static_cast<int>(pslg.points.size());
    auto node_id = [&](int i) {
      return i < n_input ? border.nodes[static_cast<std::size_t>(i)] : -(i - n_input + 1);
    };
    for (std::size_t i = pslg.points.size(); i < mesh2d.points.size(); ++i) {
      const Eigen::Vector2d& xy = mesh2d.points[i];
      result.inner_nodes.push_back(frame.to_world(field.lift(xy.x(), xy.y())));
    }
    result.triangles.reserve(mesh2d.triangles.size());
    for (const auto& t : mesh2d.triangles) result.triangles.push_back({node_id(t[0]), node_id(t[1]), node_id(t[2])});
    result.report.n_inner_nodes = result.inner_nodes.size();
    result.report.n_triangles = result.triangles.size();
  } catch (...) {
    result.inner_nodes.clear();
    result.triangles.clear();
    result.report.n_inner_nodes = 0;
    result.report.n_triangles = 0;
    result.report.status = PatchStatus::MeshFailed;
    result.report.message = "meshing failed: " + what_of(std::current_exception());
  }
  result.report.seconds += clock.seconds();
}

}  // namespace nurbsfront::surfmesh_detail
