// SPDX-License-Identifier: BSD-3-Clause
// Bands of a cell-based (0/1 occupancy) input's marching-cubes vertices and the band fit of
// a patch (docs/surfmesh.md, "Cell-based inputs").

#include <algorithm>
#include <cmath>

#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront::surfmesh_detail {

namespace {

// How far (in cells) a lattice coordinate may be from an integer or a half-integer and
// still count as one: marching cubes puts an occupancy vertex at the exact midpoint, so only
// round-off separates it.
constexpr double kLatticeTolerance = 1e-6;

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
      if (std::abs(frac - 0.5) <= kLatticeTolerance) {
        ++n_half;
        axis = d;
      } else if (frac <= kLatticeTolerance || frac >= 1.0 - kLatticeTolerance) {
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

double curved_smoothing_cells(const BicubicHeightField& field, std::span<const Eigen::Vector3d> local,
                              const CellGrid& grid) {
  if (grid.curved_smoothing <= 0.0 || local.empty()) return grid.smoothing_cells;
  std::vector<double> kappa;
  kappa.reserve(local.size());
  for (const auto& q : local) kappa.push_back(max_abs_curvature(field, q.x(), q.y()));
  const auto middle = kappa.begin() + static_cast<std::ptrdiff_t>(kappa.size() / 2);
  std::nth_element(kappa.begin(), middle, kappa.end());
  const double median = *middle;
  const double radius = 1.0 / (median * grid.spacing.minCoeff());  // cells
  if (!(radius >= kMinCurvedRadiusCells)) return grid.smoothing_cells;
  // A surface curved alike over the patch, not a flat patch with a rounded edge in it: the
  // upper quartile of the curvature at most kCurvedQuartileRatio times the median.
  const auto upper = middle + static_cast<std::ptrdiff_t>((kappa.end() - middle) / 2);
  std::nth_element(middle, upper, kappa.end());
  if (*upper > kCurvedQuartileRatio * median) return grid.smoothing_cells;
  return std::min(grid.curved_smoothing * std::sqrt(2.0 * radius), grid.smoothing_cells);
}

}  // namespace nurbsfront::surfmesh_detail
