// SPDX-License-Identifier: BSD-3-Clause
// mesh_surface(): options, the two parallel phases (fit, then mesh) and the global
// numbering of the nodes.

#include "nurbsfront/surfmesh/surfmesh.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <memory>
#include <string>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront {

namespace {

[[noreturn]] void bad_option(const std::string& what) { throw InvalidInput("SurfMeshOptions: " + what); }

bool finite_positive(double x) { return std::isfinite(x) && x > 0.0; }

// split_unfitted_patches() fits every this many points of a patch.
constexpr std::size_t kSplitCheckStride = 4;

// SizingOptions::chord_error = 0: this fraction of the uniform h.
constexpr double kDefaultChordRelative = 0.05;

// Runs task(i) for every i in [0, n) on `threads` workers (parallel::for_chunks, one index
// per chunk). The calling thread is worker 0 and reports the progress (fraction f0 .. f1)
// after each of its own indices and once at the end; returning false from the callback
// stops the workers and throws Cancelled. A task's exception is rethrown here after the
// workers joined; a cancel is seen after worker 0's current patch. (A for_chunks monitor was
// woken by the workers after every index before session 20: on the liver's 2 028 patches
// about 6 000 wake-ups of the calling thread, each taking a core from a worker. It now looks
// every kMonitorPeriod, but then the calling thread only watches; here it works as worker 0.
// docs/benchmarks/pipeline.md, session 20.)
template <class Task>
void run_parallel(std::size_t n, unsigned threads, const ProgressCallback& progress, double f0, double f1, const Task& task) {
  constexpr std::string_view kStage = "surfmesh: patches";
  if (n == 0) return;
  const auto fraction = [&](std::size_t done) {
    return f0 + (f1 - f0) * static_cast<double>(done) / static_cast<double>(n);
  };
  std::atomic<std::size_t> done{0};
  std::size_t reported = 0;  // written by worker 0 (the calling thread) only
  parallel::for_chunks(n, threads, 1, [&](std::size_t begin, std::size_t end, unsigned worker) {
    for (std::size_t i = begin; i < end; ++i) {
      task(i);
      const std::size_t now = done.fetch_add(1) + 1;
      if (worker != 0 || !progress) continue;
      reported = now;
      if (!progress(kStage, fraction(now))) throw Cancelled();
    }
  });
  if (progress && reported != n && !progress(kStage, f1)) throw Cancelled();
}

// Moves each border node to the mean of its vertical projections onto the fitted surfaces
// of its curve's patches, by at most one mean edge length, so the border lies near both
// surfaces. Corners move the same way (onto all their patches' surfaces) unless one of
// their curves is a feature: crease corners stay where the input has them. With
// `band_fits_only`, the nodes of a patch without a band fit (PatchResult::band_fit) stay
// where they are: that patch holds a sharp edge, and the mean of its plain fit and its
// neighbours' band fits put nodes at its concave corners a voxel off the input.
void project_border_nodes(const Segmentation& seg, const std::vector<surfmesh_detail::PatchResult>& results,
                          const std::vector<std::uint8_t>& is_feature, double max_move, bool band_fits_only,
                          surfmesh_detail::BorderNodes& borders) {
  const std::size_t n_corners = seg.corners.size();
  std::vector<std::vector<int>> node_patches(borders.positions.size());
  std::vector<std::uint8_t> corner_fixed(n_corners, 0);
  for (std::size_t c = 0; c < seg.curves.size(); ++c) {
    const BorderCurve& curve = seg.curves[c];
    for (const int g : borders.curve_nodes[c]) {
      auto& patches = node_patches[static_cast<std::size_t>(g)];
      for (const int p : {curve.patch_left, curve.patch_right})
        if (p >= 0 && std::find(patches.begin(), patches.end(), p) == patches.end()) patches.push_back(p);
      if (static_cast<std::size_t>(g) < n_corners && is_feature[c] != 0) corner_fixed[static_cast<std::size_t>(g)] = 1;
    }
  }
  for (std::size_t g = 0; g < borders.positions.size(); ++g) {
    if (g < n_corners && corner_fixed[g] != 0) continue;
    auto& patches = node_patches[g];
    std::sort(patches.begin(), patches.end());  // the same summation order on every run
    Eigen::Vector3d& x = borders.positions[g];
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    if (band_fits_only && std::any_of(patches.begin(), patches.end(),
                                      [&](int p) { return !results[static_cast<std::size_t>(p)].band_fit; }))
      continue;
    for (const int p : patches) {
      const auto& r = results[static_cast<std::size_t>(p)];
      if (!r.has_surface) continue;
      sum += r.surface.project(x);
      ++count;
    }
    if (count == 0) continue;
    Eigen::Vector3d move = sum / count - x;
    const double length = move.norm();
    if (!std::isfinite(length)) continue;
    if (length > max_move) move *= max_move / length;
    x += move;
  }
}

// Whether a fit of the patch's own vertices leaves one of them by more than `bound` along
// the axis. A cheaper fit than mesh_surface's (every kSplitCheckStride-th vertex, no overlap
// ring, no least-squares polish, the plain fit also on cell-based inputs, whose terraces
// are far below the bound): the bound is for gross misfits, and the full fit of every
// patch cost 16% of a DRAM 256 run. Any exception counts as no misfit (mesh_surface will
// report the patch).
bool fit_leaves_input(const TriMesh& input, const Patch& patch, const SurfMeshOptions& options, double mean_edge,
                      double bound) {
  try {
    const std::vector<Eigen::Vector3d> points = surfmesh_detail::patch_vertex_points(input, patch);
    const PatchFrame frame = patch_frame(points, std::vector<Eigen::Vector3d>(points.size(), patch.axis));
    const std::vector<Eigen::Vector3d> local = frame.to_local(points);
    std::vector<Eigen::Vector3d> sample;
    sample.reserve(local.size() / kSplitCheckStride + 1);
    Eigen::Vector2d lo = local.front().head<2>(), hi = lo;
    for (std::size_t i = 0; i < local.size(); ++i) {
      lo = lo.cwiseMin(local[i].head<2>());
      hi = hi.cwiseMax(local[i].head<2>());
      if (i % kSplitCheckStride == 0) sample.push_back(local[i]);
    }
    SurfMeshOptions plain = options;
    plain.cell_grid.enabled = false;
    FitOptions fit = surfmesh_detail::plain_fit_options(plain, mean_edge, lo, hi);
    fit.least_squares_iterations = 0;
    const FitResult fitted = fit_height_field(sample, fit);
    if (fitted.max_residual() > bound) return true;
    for (const auto& q : local)
      if (std::abs(fitted.field.value(q.x(), q.y()) - q.z()) > bound) return true;
  } catch (...) {
  }
  return false;
}

}  // namespace

void SizingOptions::validate() const {
  if (!(std::isfinite(size) && size >= 0.0)) bad_option("sizing.size must be finite and >= 0, got " + std::to_string(size));
  if (!finite_positive(relative_size)) bad_option("sizing.relative_size must be finite and > 0, got " + std::to_string(relative_size));
  if (!(std::isfinite(chord_error) && chord_error >= 0.0))
    bad_option("sizing.chord_error must be finite and >= 0, got " + std::to_string(chord_error));
  if (!(min_size_fraction > 0.0 && min_size_fraction <= 1.0))
    bad_option("sizing.min_size_fraction must be in (0, 1], got " + std::to_string(min_size_fraction));
  if (!(std::isfinite(feature_size) && feature_size >= 0.0))
    bad_option("sizing.feature_size must be finite and >= 0, got " + std::to_string(feature_size));
  if (!(std::isfinite(gradation) && gradation > 1.0)) bad_option("sizing.gradation must be > 1, got " + std::to_string(gradation));
  if (!(std::isfinite(feature_gradation) && feature_gradation > 1.0))
    bad_option("sizing.feature_gradation must be finite and > 1, got " + std::to_string(feature_gradation));
  if (!(border_lookahead >= 0.0 && border_lookahead <= 2.0))
    bad_option("sizing.border_lookahead must be in [0, 2], got " + std::to_string(border_lookahead));
}

void PatchFitOptions::validate() const {
  if (!finite_positive(relative_tolerance))
    bad_option("fit.relative_tolerance must be finite and > 0, got " + std::to_string(relative_tolerance));
  if (!(std::isfinite(min_spacing_edges) && min_spacing_edges >= 0.0))
    bad_option("fit.min_spacing_edges must be finite and >= 0, got " + std::to_string(min_spacing_edges));
  if (max_levels < 1 || max_levels > 20) bad_option("fit.max_levels must be in [1, 20], got " + std::to_string(max_levels));
  if (least_squares_iterations < 0 || least_squares_iterations > 100000)
    bad_option("fit.least_squares_iterations must be in [0, 100000], got " + std::to_string(least_squares_iterations));
  if (final_passes < 0 || final_passes > 1000)
    bad_option("fit.final_passes must be in [0, 1000], got " + std::to_string(final_passes));
  if (!(std::isfinite(least_squares_fine_smoothing) && least_squares_fine_smoothing >= 0.0))
    bad_option("fit.least_squares_fine_smoothing must be finite and >= 0, got " + std::to_string(least_squares_fine_smoothing));
  if (!(std::isfinite(fine_below_edges) && fine_below_edges >= 0.0))
    bad_option("fit.fine_below_edges must be finite and >= 0, got " + std::to_string(fine_below_edges));
  if (!(std::isfinite(split_above_edges) && split_above_edges >= 0.0))
    bad_option("fit.split_above_edges must be finite and >= 0, got " + std::to_string(split_above_edges));
  if (split_rounds < 0 || split_rounds > 20) bad_option("fit.split_rounds must be in [0, 20], got " + std::to_string(split_rounds));
  if (!(std::isfinite(large_face_edges) && large_face_edges >= 0.0))
    bad_option("fit.large_face_edges must be finite and >= 0, got " + std::to_string(large_face_edges));
  if (!(std::isfinite(flat_face_edges) && flat_face_edges >= 0.0))
    bad_option("fit.flat_face_edges must be finite and >= 0, got " + std::to_string(flat_face_edges));
  if (!(std::isfinite(detail_spacing_edges) && detail_spacing_edges >= 0.0))
    bad_option("fit.detail_spacing_edges must be finite and >= 0, got " + std::to_string(detail_spacing_edges));
  if (detail_spacing_edges > 0.0 && min_spacing_edges > 0.0 && !(detail_spacing_edges < min_spacing_edges))
    bad_option("fit.detail_spacing_edges must be below fit.min_spacing_edges (" + std::to_string(min_spacing_edges) +
               ": the detail lattice is the finer one), got " + std::to_string(detail_spacing_edges));
  if (!(std::isfinite(detail_above_edges) && detail_above_edges >= 0.0))
    bad_option("fit.detail_above_edges must be finite and >= 0, got " + std::to_string(detail_above_edges));
  if (!finite_positive(detail_node_offset_edges))
    bad_option("fit.detail_node_offset_edges must be finite and > 0, got " + std::to_string(detail_node_offset_edges));
}

void CellGrid::validate() const {
  if (!enabled) return;
  if (!origin.allFinite()) bad_option("cell_grid.origin must be finite");
  if (!(spacing.allFinite() && spacing.minCoeff() > 0.0)) bad_option("cell_grid.spacing must be finite and > 0");
  if (!finite_positive(lattice_cells)) bad_option("cell_grid.lattice_cells must be finite and > 0, got " + std::to_string(lattice_cells));
  if (!(std::isfinite(smoothing_cells) && smoothing_cells >= 0.0))
    bad_option("cell_grid.smoothing_cells must be finite and >= 0, got " + std::to_string(smoothing_cells));
  if (curvature_passes < 0 || curvature_passes > 10)
    bad_option("cell_grid.curvature_passes must be in [0, 10], got " + std::to_string(curvature_passes));
  if (wide_overlap_rings < 0 || wide_overlap_rings > 20)
    bad_option("cell_grid.wide_overlap_rings must be in [0, 20], got " + std::to_string(wide_overlap_rings));
  if (!finite_positive(wide_overlap_max_miss_cells))
    bad_option("cell_grid.wide_overlap_max_miss_cells must be finite and > 0, got " + std::to_string(wide_overlap_max_miss_cells));
  if (!(std::isfinite(plain_fit_miss_cells) && plain_fit_miss_cells >= 0.0))
    bad_option("cell_grid.plain_fit_miss_cells must be finite and >= 0, got " + std::to_string(plain_fit_miss_cells));
  if (!(std::isfinite(curved_smoothing) && curved_smoothing >= 0.0))
    bad_option("cell_grid.curved_smoothing must be finite and >= 0, got " + std::to_string(curved_smoothing));
}

void SurfMeshOptions::validate() const {
  sizing.validate();
  fit.validate();
  cell_grid.validate();
  if (smoothing_passes < 0) bad_option("smoothing_passes must be >= 0, got " + std::to_string(smoothing_passes));
  if (!(corner_split_angle_deg > 0.0 && corner_split_angle_deg <= 180.0))
    bad_option("corner_split_angle_deg must be in (0, 180], got " + std::to_string(corner_split_angle_deg));
  if (!(crease_angle_deg > 0.0 && crease_angle_deg <= 180.0))
    bad_option("crease_angle_deg must be in (0, 180], got " + std::to_string(crease_angle_deg));
  if (!(unsmoothed_crease_angle_deg >= 0.0 && unsmoothed_crease_angle_deg <= 180.0))
    bad_option("unsmoothed_crease_angle_deg must be in [0, 180], got " + std::to_string(unsmoothed_crease_angle_deg));
  if (!(fin_rim_width >= 0.0 && std::isfinite(fin_rim_width)))
    bad_option("fin_rim_width must be finite and >= 0, got " + std::to_string(fin_rim_width));
  if (!(fin_rim_max_angle_deg >= 0.0 && fin_rim_max_angle_deg <= 180.0))
    bad_option("fin_rim_max_angle_deg must be in [0, 180], got " + std::to_string(fin_rim_max_angle_deg));
  if (!(fin_rim_max_gap_edges >= 0.0))
    bad_option("fin_rim_max_gap_edges must be >= 0 (infinity: no test), got " + std::to_string(fin_rim_max_gap_edges));
  if (!(tiny_curve_merge_size >= 0.0 && tiny_curve_merge_size <= 0.5))
    bad_option("tiny_curve_merge_size must be in [0, 0.5], got " + std::to_string(tiny_curve_merge_size));
  if (!(corner_cluster_size >= 0.0 && corner_cluster_size <= 1.0))
    bad_option("corner_cluster_size must be in [0, 1], got " + std::to_string(corner_cluster_size));
  if (!(std::isfinite(max_node_offset_edges) && max_node_offset_edges >= 0.0))
    bad_option("max_node_offset_edges must be finite and >= 0, got " + std::to_string(max_node_offset_edges));
  if (!(std::isfinite(small_patch_node_offset_edges) && small_patch_node_offset_edges >= 0.0))
    bad_option("small_patch_node_offset_edges must be finite and >= 0, got " + std::to_string(small_patch_node_offset_edges));
  if (!(std::isfinite(polygon_node_offset_edges) && polygon_node_offset_edges >= 0.0))
    bad_option("polygon_node_offset_edges must be finite and >= 0, got " + std::to_string(polygon_node_offset_edges));
  if (threads < 0) bad_option("threads must be >= 0, got " + std::to_string(threads));
  if (cell_grid.enabled && fit.detail_spacing_edges > 0.0)
    bad_option("fit.detail_spacing_edges refits the plain fit; with a cell grid the band fit is used instead: "
               "set one of them to off, got detail_spacing_edges " + std::to_string(fit.detail_spacing_edges));
}

Eigen::Vector3d PatchSurface::project(const Eigen::Vector3d& world) const {
  const Eigen::Vector3d local = frame.to_local(world);
  Eigen::Vector3d q = field.lift(local.x(), local.y());
  double z = 0.0;
  if (input_heights && input_heights->height(q.x(), q.y(), z)) q.z() = z + std::clamp(q.z() - z, -max_offset, max_offset);
  return frame.to_world(q);
}

Eigen::Vector3d PatchSurface::normal(const Eigen::Vector3d& world) const {
  const Eigen::Vector3d local = frame.to_local(world);
  return frame.direction_to_world(field.normal(local.x(), local.y()));
}

SurfaceMesh mesh_surface(const TriMesh& input, const Segmentation& segmentation, const SurfMeshOptions& options) {
  return surfmesh_detail::mesh_surface(input, segmentation, options, mean_edge_length(input));
}

SurfaceMesh surfmesh_detail::mesh_surface(const TriMesh& input, const Segmentation& segmentation,
                                          const SurfMeshOptions& options, const double mean_edge,
                                          const LatticeShares* shares, const bool keep_face_patch) {
  options.validate();
  validate_segmentation(input, segmentation);
  SurfaceMesh out;
  if (input.n_faces() == 0) return out;
  report_progress(options.progress, "surfmesh: borders", 0.0);

  if (!(mean_edge > 0.0)) throw InvalidInput("mesh_surface: the mesh has no edge of positive length");
  const double h = uniform_size(options.sizing, mean_edge);
  out.input_mean_edge = mean_edge;
  out.target_size = h;
  if (keep_face_patch) out.input_face_patch = segmentation.face_patch;
  SizeAt size_at = [h](const Eigen::Vector3d&) { return h; };
  SizeAt front_size;  // empty: the front meshes with the uniform h
  if (options.sizing.callback) {
    const auto& callback = options.sizing.callback;
    size_at = [&callback](const Eigen::Vector3d& x) {
      const double s = callback(x);
      if (!(std::isfinite(s) && s > 0.0)) throw InvalidInput("mesh_surface: the sizing callback returned " + std::to_string(s));
      return s;
    };
    front_size = size_at;
  }
  const std::size_t n_patches = segmentation.patches.size();
  const unsigned threads = parallel::thread_count(options.threads);
  std::vector<PatchResult> results(n_patches);
  // The marching-cubes gate (lattice edges: no feature sizing and no flat-face samples there,
  // PatchFitOptions::flat_face_edges) and the label-image test (detail fit) in one pass.
  const bool feature_sizing_gate = options.sizing.feature_size > 0.0 && !options.sizing.feature_size_everywhere;
  const bool detail_fit = options.fit.detail_spacing_edges > 0.0;
  const bool fin_rims = options.fin_rim_width > 0.0;
  const bool lattice_tested = shares != nullptr || detail_fit || feature_sizing_gate || fin_rims ||
                              options.fit.flat_face_edges > 0.0 || options.small_patch_node_offset_edges > 0.0 ||
                              options.polygon_node_offset_edges > 0.0;
  const LatticeShares lattice = shares != nullptr ? *shares : lattice_tested ? lattice_edge_shares(input) : LatticeShares{};
  if (lattice_tested) out.input_label_staircase = label_image_staircase(lattice);
  const bool marching_cubes = marching_cubes_lattice(lattice);
  SurfMeshOptions fit_options = options;
  if (marching_cubes) fit_options.fit.flat_face_edges = 0.0;
  // The detail fit would follow a label image's staircases (docs/surfmesh.md "Detail fit:
  // where it runs"): such an input keeps the plain fit.
  if (detail_fit && label_image_staircase(lattice)) {
    fit_options.fit.detail_spacing_edges = 0.0;
    out.detail_fit_skipped = true;
  }
  auto fit_all = [&](const BorderNodes& nodes) {
    run_parallel(n_patches, threads, options.progress, 0.0, 0.5, [&](std::size_t p) {
      fit_patch(input, segmentation, static_cast<int>(p), nodes, fit_options, mean_edge, results[p]);
    });
  };
  double sizing_grid = 0.0;  // > 0: the front's sizes are sampled on a grid (adaptive, feature)
  std::vector<std::uint8_t> feature_limited;  // feature sizing alone: patches not at the uniform h
  std::vector<double> patch_grid;  // feature sizing alone: per patch sizing grid spacing
  std::vector<double> crease_angles;
  out.curve_is_feature = feature_curves(input, segmentation, options.crease_angle_deg, &crease_angles, threads);
  // Feature sizing where it helps (SizingOptions::feature_size): not on marching-cubes
  // surfaces, not for a few thin parts.
  if (options.sizing.feature_size > 0.0 && (options.sizing.feature_size_everywhere || !marching_cubes)) {
    FeatureSizing feature = feature_sizing(input, segmentation, out.curve_is_feature, size_at, options.sizing.feature_size,
                                           options.sizing.min_size_fraction * h, options.sizing.feature_gradation,
                                           options.sizing.feature_size_everywhere ? 0.0 : kFeatureSizingMinAreaShare);
    if (feature.size_at) {
      out.feature_sizing_applied = true;
      size_at = std::move(feature.size_at);
      front_size = size_at;
      feature_limited = std::move(feature.patch_limited);
      // The grid follows the smallest size (a narrow face is narrower than a mean edge),
      // but no finer than a twentieth of a mean edge (a tiny min_size_fraction or callback
      // size must not make the grid's cell count overflow).
      sizing_grid = std::max(std::min(mean_edge, feature.smallest), 0.05 * mean_edge);
      // Under feature sizing alone each patch's grid follows its own smallest size: a
      // patch far from the narrow ones needs no grid of their size (the closest-point
      // lookups of size_at were half of the run's CPU on femur).
      if (!options.sizing.adaptive && !options.sizing.callback) {
        patch_grid.resize(n_patches);
        for (std::size_t p = 0; p < n_patches; ++p)
          patch_grid[p] = std::max(std::min(mean_edge, feature.patch_smallest[p]), 0.05 * mean_edge);
      }
    }
  }
  if (options.sizing.adaptive) {
    // The sizes come from the fits' curvature, so the patches are fitted before the borders
    // are discretised (their rectangles then cover the patch's and overlap vertices only).
    BorderNodes no_nodes;
    no_nodes.curve_nodes.resize(segmentation.curves.size());
    fit_all(no_nodes);
    const double chord = options.sizing.chord_error > 0.0 ? options.sizing.chord_error : kDefaultChordRelative * h;
    size_at = adaptive_sizing(input, segmentation, results, size_at, chord, options.sizing.min_size_fraction * h,
                              options.sizing.gradation);
    front_size = size_at;
    // The adaptive sizes are piecewise linear on the input's triangles: a grid of the input's
    // resolution in each patch plane holds them.
    sizing_grid = sizing_grid > 0.0 ? std::min(sizing_grid, mean_edge) : mean_edge;
  }
  // Chords of the smoothed curves may cross in a small patch's plane, a small loop
  // resampled into a few nodes may turn the other way round, and the chords and smoothed
  // nodes of a patch thinner than the smoothing moves or the chords' sag can make its border
  // a simple polygon turning the wrong way round (folded_border_curves): such curves are
  // resampled from their input positions, and if that is still wrong, take their input
  // vertices (which the segmentation guarantees not to cross).
  std::vector<CurveSource> source(segmentation.curves.size(), CurveSource::Smoothed);
  // The input's boundary and its sharpest creases are discretised from their input positions
  // (the smoothing moves them off the corners and folds they follow).
  // So are the sharp crease curves (SegmentOptions::sharp_crease_angle_deg): found only
  // between smooth sides of clean (CAD-like) inputs, whose crease edges are the geometry.
  const std::vector<std::uint8_t> sharp = sharp_crease_curves(segmentation);
  for (std::size_t c = 0; c < source.size() && !options.cell_grid.enabled; ++c) {
    if (out.curve_is_feature[c] == 0) continue;
    const bool keep = segmentation.curves[c].patch_right < 0
                          ? options.unsmoothed_boundary_curves
                          : sharp[c] != 0 || crease_angles[c] > options.unsmoothed_crease_angle_deg;
    if (keep) source[c] = CurveSource::Input;
  }
  // Tiny corner curves merge their corners, except where a curve at such a corner crosses
  // or folds (below): that merge is undone first.
  std::vector<int> corner_target =
      options.cell_grid.enabled ? std::vector<int>() : tiny_curve_merges(input, segmentation, size_at, options.tiny_curve_merge_size);
  if (!options.cell_grid.enabled && options.corner_cluster_size > 0.0)
    corner_target = corner_cluster_merges(input, segmentation, size_at, options.corner_cluster_size, std::move(corner_target));
  auto undo_merges = [&](int c) {
    const BorderCurve& curve = segmentation.curves[static_cast<std::size_t>(c)];
    if (curve.is_closed || corner_target.empty()) return false;
    bool undone = false;
    for (const int v : {curve.vertices.front(), curve.vertices.back()}) {
      const auto k = static_cast<std::size_t>(std::lower_bound(segmentation.corners.begin(), segmentation.corners.end(), v) -
                                              segmentation.corners.begin());
      // The whole cluster of k (corner_cluster_merges; of a pair: both) is undone.
      const int t = corner_target[k];
      for (std::size_t j = 0; j < corner_target.size(); ++j) {
        if (static_cast<std::size_t>(corner_target[j]) == j || corner_target[j] != t) continue;
        corner_target[j] = static_cast<int>(j);
        undone = true;
      }
    }
    return undone;
  };
  // The borders' sizes look ahead into the patches where the sizes vary (SizingOptions::border_lookahead).
  const bool varying = options.sizing.callback || options.sizing.adaptive || out.feature_sizing_applied;
  const SizeAt border_size = varying && options.sizing.border_lookahead > 0.0
                                 ? looked_ahead_sizing(size_at, options.sizing.border_lookahead)
                                 : size_at;
  BorderNodes borders = discretise_borders(input, segmentation, border_size, source, corner_target, threads);
  for (bool changed = true; changed;) {
    changed = false;
    std::vector<int> bad = crossing_curves(segmentation, borders, threads);
    const std::vector<int> flipped = flipped_loops(input, segmentation, borders);
    bad.insert(bad.end(), flipped.begin(), flipped.end());
    const std::vector<int> extra = extra_outer_loop_curves(segmentation, borders, threads);
    bad.insert(bad.end(), extra.begin(), extra.end());
    // Last: borders that still fold with all the above resolved (escalating their curves
    // earlier changed more curves than needed: cheese, 8 of 9 such patches unfold with the
    // crossing curves resampled).
    if (bad.empty()) bad = folded_border_curves(segmentation, borders, source, threads);
    std::sort(bad.begin(), bad.end());
    bad.erase(std::unique(bad.begin(), bad.end()), bad.end());
    for (const int c : bad) {
      if (undo_merges(c)) {
        changed = true;
        continue;
      }
      CurveSource& s = source[static_cast<std::size_t>(c)];
      if (s == CurveSource::InputVertices) continue;  // crossing anyway: the patch will fail
      s = s == CurveSource::Smoothed ? CurveSource::Input : CurveSource::InputVertices;
      changed = true;
    }
    if (changed) borders = discretise_borders(input, segmentation, border_size, source, corner_target, threads);
  }
  report_progress(options.progress, "surfmesh: borders", 1.0);

  if (!options.sizing.adaptive) fit_all(borders);

  // With a cell grid the smoothed marching-cubes border is up to half a cell off the truth
  // while the band fits are not: border nodes go onto them too (not the nodes of a patch
  // that fell back to the plain fit, CellGrid::plain_fit_miss_cells).
  if (options.project_border_nodes || options.cell_grid.enabled) {
    // A projection that makes a curve cross another one in a patch plane is undone for that
    // curve's nodes (its corners included), until nothing crosses that did not before.
    const std::vector<int> crossing_before = crossing_curves(segmentation, borders, threads);
    const std::vector<Eigen::Vector3d> unprojected = borders.positions;
    project_border_nodes(segmentation, results, out.curve_is_feature, mean_edge, options.cell_grid.enabled, borders);
    std::vector<std::uint8_t> restored(segmentation.curves.size(), 0);
    for (bool changed = true; changed;) {
      changed = false;
      for (const int c : crossing_curves(segmentation, borders, threads)) {
        if (restored[static_cast<std::size_t>(c)] != 0 ||
            std::binary_search(crossing_before.begin(), crossing_before.end(), c))
          continue;
        restored[static_cast<std::size_t>(c)] = 1;
        for (const int g : borders.curve_nodes[static_cast<std::size_t>(c)])
          borders.positions[static_cast<std::size_t>(g)] = unprojected[static_cast<std::size_t>(g)];
        changed = true;
      }
    }
  }

  run_parallel(n_patches, threads, options.progress, 0.5, 1.0, [&](std::size_t p) {
    // Under feature sizing alone, a patch whose sizes are all h is meshed with the uniform h.
    const bool uniform = !options.sizing.adaptive && !options.sizing.callback && !feature_limited.empty() &&
                         feature_limited[p] == 0;
    mesh_patch(segmentation, static_cast<int>(p), borders, options, h, uniform ? SizeAt() : front_size,
               patch_grid.empty() ? sizing_grid : patch_grid[p], results[p]);
    // A detail-fitted patch keeps its nodes closer to its input (PatchFitOptions::detail_spacing_edges).
    double offset = results[p].report.detail_fit ? options.fit.detail_node_offset_edges : options.max_node_offset_edges;
    // A small patch's fit is held by its few vertices only (no overlap ring): its nodes keep
    // closer to its faces (SurfMeshOptions::small_patch_node_offset_edges).
    // Not on marching-cubes surfaces: there the fit is to smooth the terraces, and with the fin
    // rims unlocked headsq@1150's Hausdorff distance went from 1.03 to 2.11 mean edges with it.
    const double small = marching_cubes ? 0.0 : options.small_patch_node_offset_edges;
    if (small > 0.0 && !results[p].band_fit && fits_own_vertices_only(segmentation.patches[p]))
      offset = offset > 0.0 ? std::min(offset, small) : small;
    // On an input that is not a marching-cubes surface the vertices are the geometry: every
    // plain-fitted patch keeps its nodes near its faces (SurfMeshOptions::polygon_node_offset_edges),
    // where its smooth fit rounds a sharp edge below the crease angle.
    const double polygon = marching_cubes ? 0.0 : options.polygon_node_offset_edges;
    if (polygon > 0.0 && !results[p].band_fit) offset = offset > 0.0 ? std::min(offset, polygon) : polygon;
    if (offset > 0.0)
      results[p].report.n_clamped_nodes = clamp_inner_nodes(input, segmentation, static_cast<int>(p), offset * mean_edge, results[p]);
  });
  // Patches meshed independently can join the same two border nodes (a thin fin, a tiny
  // closed component): split such shared chords before the numbering.
  out.n_shared_chords_resolved = resolve_shared_chords(segmentation, borders, results);

  // Global numbering: border nodes, then the inner nodes patch by patch.
  out.n_border_nodes = borders.positions.size();
  out.nodes = std::move(borders.positions);
  out.node_kind = std::move(borders.kind);
  out.node_owner = std::move(borders.owner);
  out.curve_nodes = std::move(borders.curve_nodes);
  out.surfaces.resize(n_patches);
  out.patches.resize(n_patches);
  for (std::size_t p = 0; p < n_patches; ++p) {
    PatchResult& r = results[p];
    const int offset = static_cast<int>(out.nodes.size());
    for (const auto& x : r.inner_nodes) {
      out.nodes.push_back(x);
      out.node_kind.push_back(NodeKind::Inner);
      out.node_owner.push_back(static_cast<int>(p));
    }
    for (const auto& t : r.triangles) {
      std::array<int, 3> g{};
      for (int k = 0; k < 3; ++k) g[static_cast<std::size_t>(k)] = t[static_cast<std::size_t>(k)] >= 0 ? t[static_cast<std::size_t>(k)] : offset - t[static_cast<std::size_t>(k)] - 1;
      out.triangles.push_back(g);
      out.triangle_patch.push_back(static_cast<int>(p));
    }
    out.surfaces[p] = std::move(r.surface);
    out.patches[p] = std::move(r.report);
  }
  // Fin rims are no features for stitch; the borders and patches above kept them as creases
  // (their sources, the unsmoothed sharp ones).
  if (fin_rims && marching_cubes && !label_image_staircase(lattice)) {
    for (const int c : fin_rim_curves(input, segmentation, out, crease_angles, options.fin_rim_width * h,
                                      options.fin_rim_max_angle_deg, options.fin_rim_max_gap_edges * mean_edge,
                                      threads)) {
      out.curve_is_feature[static_cast<std::size_t>(c)] = 0;
      if (out.curve_is_fin_rim.empty()) out.curve_is_fin_rim.assign(out.curve_is_feature.size(), 0);
      out.curve_is_fin_rim[static_cast<std::size_t>(c)] = 1;
      ++out.n_fin_rim_curves;
    }
  }
  return out;
}

Segmentation split_unfitted_patches(const TriMesh& input, const Segmentation& segmentation,
                                    const SurfMeshOptions& options, const SegmentOptions& segment_options,
                                    std::size_t* n_split) {
  return surfmesh_detail::split_unfitted_patches(input, segmentation, options, segment_options, n_split,
                                                 mean_edge_length(input));
}

Segmentation surfmesh_detail::split_unfitted_patches(const TriMesh& input, const Segmentation& segmentation,
                                                     const SurfMeshOptions& options,
                                                     const SegmentOptions& segment_options, std::size_t* n_split,
                                                     const double mean_edge, segment_detail::Splitter* splitter,
                                                     const bool with_borders) {
  options.validate();
  segment_options.validate();
  validate_segmentation(input, segmentation);
  if (n_split != nullptr) *n_split = 0;
  if (input.n_faces() == 0 || options.fit.split_above_edges <= 0.0 || options.fit.split_rounds == 0) return segmentation;
  if (!(mean_edge > 0.0)) throw InvalidInput("split_unfitted_patches: the mesh has no edge of positive length");
  const double bound = options.fit.split_above_edges * mean_edge;
  const unsigned threads = parallel::thread_count(options.threads);
  Segmentation seg = segmentation;
  segment_detail::SplitterPtr own_splitter;  // made at the first split when none is given
  // The rounds' splits leave the borders out (only the last result's are used): they are
  // extracted once at the end.
  bool split_any = false;
  std::vector<int> candidates(seg.patches.size());
  for (std::size_t p = 0; p < candidates.size(); ++p) candidates[p] = static_cast<int>(p);
  for (int round = 0; round < options.fit.split_rounds && !candidates.empty(); ++round) {
    std::vector<std::uint8_t> is_bad(candidates.size(), 0);
    run_parallel(candidates.size(), threads, options.progress, 0.0, 0.0, [&](std::size_t i) {
      is_bad[i] = fit_leaves_input(input, seg.patches[static_cast<std::size_t>(candidates[i])], options, mean_edge, bound);
    });
    std::vector<int> bad;
    for (std::size_t i = 0; i < candidates.size(); ++i)
      if (is_bad[i] != 0) bad.push_back(candidates[i]);
    if (bad.empty()) break;
    // The parts of the split patches are the next round's candidates: the new patches
    // holding a face of a split one.
    std::vector<std::uint8_t> was_bad(seg.patches.size(), 0);
    for (const int p : bad) was_bad[static_cast<std::size_t>(p)] = 1;
    const std::size_t n_before = seg.patches.size();
    if (splitter == nullptr && !own_splitter) own_splitter = segment_detail::make_splitter(input, segment_options);
    // seg is the validated input or the last round's result; bad lists its patch ids.
    Segmentation next = segment_detail::split(splitter != nullptr ? *splitter : *own_splitter, seg, bad, false, true);
    split_any = true;
    if (n_split != nullptr) *n_split += next.patches.size() - n_before;
    candidates.clear();
    for (std::size_t q = 0; q < next.patches.size(); ++q) {
      const int old = seg.face_patch[static_cast<std::size_t>(next.patches[q].faces.front())];
      if (was_bad[static_cast<std::size_t>(old)] != 0) candidates.push_back(static_cast<int>(q));
    }
    const bool changed = next.patches.size() > n_before;
    seg = std::move(next);
    if (!changed) break;
  }
  if (split_any && with_borders) seg = segment_detail::with_borders(input, segment_options, std::move(seg));
  return seg;
}

}  // namespace nurbsfront
