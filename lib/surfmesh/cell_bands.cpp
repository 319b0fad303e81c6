// SPDX-License-Identifier: BSD-3-Clause
// Bands of a cell-based (0/1 occupancy) input's marching-cubes vertices and the band fit of
// a patch (docs/surfmesh.md, "Cell-based inputs").

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <Eigen/Dense>

#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/nurbs/nurbs_surface.h"
#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront::surfmesh_detail {

namespace {

// Fewest vertices of a local quadric fit (six unknowns, terraced data).
constexpr std::size_t kMinJetVertices = 12;
// Radius (cells) of the local quadric fits that estimate a patch's curvature before its band
// fit: large enough to average the terraces (2.5 cells let the median wander by a factor 2 on
// the occupancy torus at 64), small enough for the tube of the torus at 48 (radius 6 cells).
constexpr double kCurvatureJetRadiusCells = 4.5;
// Rings of the neighbours' faces (facing the patch's axis) the quadrics reach into: a narrow
// patch (the torus's inner equator at 64, two or three cells wide) has no two-dimensional
// neighbourhood of its own.
constexpr int kCurvatureJetRings = 3;
// A patch counts as curved (gets CellGrid::curved_smoothing's length) only when sqrt(2 R) is
// at most this many smoothing_cells (R <= 14.6 cells with the default 2.25): the terraces'
// noise biases each quadric's largest |k| up (the sphere at 48, radius 23 cells, came out as
// 19-21 cells), so only a radius clearly below the smoothing length's own scale is taken. It
// is 0.9 / 0.375, the gate of the earlier rule (length 0.375 sqrt(2 R) at most 0.9
// smoothing_cells), so the set of curved patches does not move with curved_smoothing.
constexpr double kCurvedMaxTerraceRatio = 2.4;
// Vertices at most sampled per patch (evenly by id).
constexpr std::size_t kCurvatureJetSamples = 256;

// The largest |principal curvature| at the origin of the quadric w = a0 + a1 u + a2 v + a3 u^2
// + a4 u v + a5 v^2 fitted (least squares) to `points` (relative to the centre vertex) in the
// frame of their best plane; -1 if the fit is degenerate.
double jet_curvature(const std::vector<Eigen::Vector3d>& points, double radius) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& q : points) mean += q;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& q : points) cov += (q - mean) * (q - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(cov);
  const Eigen::Vector3d n = eigen.eigenvectors().col(0);
  const Eigen::Vector3d t1 = eigen.eigenvectors().col(2);
  const Eigen::Vector3d t2 = n.cross(t1);
  // Coordinates scaled by the radius (conditioning); the coefficients are unscaled below.
  Eigen::Matrix<double, 6, 6> normal = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
  for (const auto& q : points) {
    const double u = q.dot(t1) / radius;
    const double v = q.dot(t2) / radius;
    const Eigen::Matrix<double, 6, 1> row(1.0, u, v, u * u, u * v, v * v);
    normal.selfadjointView<Eigen::Lower>().rankUpdate(row);
    rhs += row * (q.dot(n) / radius);
  }
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(normal.selfadjointView<Eigen::Lower>());
  // LDLT reports success on a singular matrix too (points on a line or a conic): no estimate.
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-12)) return -1.0;
  const Eigen::Matrix<double, 6, 1> a = ldlt.solve(rhs);
  if (!a.allFinite()) return -1.0;
  SurfaceDerivatives d;
  d.su = Eigen::Vector3d(1.0, 0.0, a[1]);
  d.sv = Eigen::Vector3d(0.0, 1.0, a[2]);
  d.suu = Eigen::Vector3d(0.0, 0.0, 2.0 * a[3] / radius);
  d.suv = Eigen::Vector3d(0.0, 0.0, a[4] / radius);
  d.svv = Eigen::Vector3d(0.0, 0.0, 2.0 * a[5] / radius);
  const SurfaceCurvature c = curvature_from_derivatives(d);
  const double k = std::max(std::abs(c.k1), std::abs(c.k2));
  return std::isfinite(k) ? k : -1.0;
}

}  // namespace

std::vector<BandSample> cell_band_samples(const std::vector<Eigen::Vector3d>& world, const PatchFrame& frame,
                                          const CellGrid& grid) {
  std::vector<BandSample> out;
  out.reserve(world.size());
  for (const auto& x : world) {
    BandSample s;
    s.point = frame.to_local(x);
    const Eigen::Vector3d t = (x - grid.origin).cwiseQuotient(grid.spacing);
    int n_half = 0;
    int n_whole = 0;
    int axis = -1;
    for (int d = 0; d < 3; ++d) {
      const double frac = t[d] - std::floor(t[d]);
      if (std::abs(frac - 0.5) <= tolerance::kLatticeCells) {
        ++n_half;
        axis = d;
      } else if (frac <= tolerance::kLatticeCells || frac >= 1.0 - tolerance::kLatticeCells) {
        ++n_whole;
      }
    }
    if (n_half == 1 && n_whole == 2) {
      s.direction = frame.direction_to_local(Eigen::Vector3d::Unit(axis));
      s.half_length = 0.5 * grid.spacing[axis];
    }
    out.push_back(s);
  }
  return out;
}

BandFitResult fit_cell_bands(const std::vector<Eigen::Vector3d>& world, const PatchFrame& frame, const CellGrid& grid,
                             const Rectangle& domain, const BicubicHeightField* start, double skip_passes_max_miss) {
  const double cell = grid.spacing.minCoeff();
  BandFitOptions options;
  options.spacing = grid.lattice_cells * cell;
  options.smoothing_length = grid.smoothing_cells * cell;
  options.curvature_passes = grid.curvature_passes;
  options.domain = domain;
  options.start = start;
  options.skip_passes_max_miss = skip_passes_max_miss;
  return fit_height_field_to_bands(cell_band_samples(world, frame, grid), options);
}

double curved_smoothing_cells(const TriMesh& mesh, const Segmentation& segmentation, int p, const CellGrid& grid) {
  const Patch& patch = segmentation.patches[static_cast<std::size_t>(p)];
  if (grid.curved_smoothing <= 0.0 || patch.faces.empty()) return grid.smoothing_cells;
  const double cell = grid.spacing.minCoeff();
  const double radius = kCurvatureJetRadiusCells * cell;
  // The patch's vertices (the samples) and those of its neighbours' faces within `rings`
  // that face its axis (overlap_vertices: a narrow patch's neighbourhoods reach across its
  // width, a sharp edge's other side is left out), ascending.
  std::vector<int> own;
  own.reserve(3 * patch.faces.size());
  for (const int f : patch.faces)
    for (const auto v : mesh.fv_range(TriMesh::FaceHandle(f))) own.push_back(v.idx());
  std::sort(own.begin(), own.end());
  own.erase(std::unique(own.begin(), own.end()), own.end());
  std::vector<int> reach = own;
  const std::vector<int> more = overlap_vertices(mesh, segmentation, p, kCurvatureJetRings);
  reach.insert(reach.end(), more.begin(), more.end());
  std::inplace_merge(reach.begin(), reach.begin() + static_cast<std::ptrdiff_t>(own.size()), reach.end());
  const std::size_t stride = (own.size() + kCurvatureJetSamples - 1) / kCurvatureJetSamples;
  std::vector<std::size_t> stamp(reach.size(), reach.size());
  std::vector<std::size_t> queue;
  std::vector<Eigen::Vector3d> near;
  std::vector<double> largest_abs;
  auto index_of = [&](int v) {
    const auto it = std::lower_bound(reach.begin(), reach.end(), v);
    return it == reach.end() || *it != v ? reach.size() : static_cast<std::size_t>(it - reach.begin());
  };
  for (std::size_t s = 0; s < own.size(); s += stride) {
    const Eigen::Vector3d centre = to_eigen(mesh.point(TriMesh::VertexHandle(own[s])));
    // The vertices within the radius, reached through the patch's and the overlap's vertices.
    const std::size_t first = index_of(own[s]);
    queue.assign(1, first);
    stamp[first] = s;
    near.clear();
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const TriMesh::VertexHandle vh(reach[queue[head]]);
      near.push_back(to_eigen(mesh.point(vh)) - centre);
      for (const auto w : mesh.vv_range(vh)) {
        const std::size_t k = index_of(w.idx());
        if (k == reach.size() || stamp[k] == s) continue;
        stamp[k] = s;
        if ((to_eigen(mesh.point(w)) - centre).norm() <= radius) queue.push_back(k);
      }
    }
    if (near.size() < kMinJetVertices) continue;
    const double k = jet_curvature(near, radius);
    if (k >= 0.0) largest_abs.push_back(k * cell);
  }
  if (largest_abs.empty()) return grid.smoothing_cells;
  const double median = median_of(largest_abs);
  const double radius_cells = 1.0 / median;
  if (!(radius_cells >= kMinCurvedRadiusCells)) return grid.smoothing_cells;
  // A surface curved alike over the patch, not a flat patch with a rounded edge in it: the
  // upper quartile of the curvature at most kCurvedQuartileRatio times the median.
  const auto upper = largest_abs.begin() + static_cast<std::ptrdiff_t>(3 * largest_abs.size() / 4);
  std::nth_element(largest_abs.begin(), upper, largest_abs.end());
  if (*upper > kCurvedQuartileRatio * median) return grid.smoothing_cells;
  // Only a radius clearly below the smoothing length's scale (kCurvedMaxTerraceRatio).
  const double terrace = std::sqrt(2.0 * radius_cells);
  if (terrace > kCurvedMaxTerraceRatio * grid.smoothing_cells) return grid.smoothing_cells;
  return std::min(grid.curved_smoothing * terrace, grid.smoothing_cells);
}

}  // namespace nurbsfront::surfmesh_detail
