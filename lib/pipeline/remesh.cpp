// SPDX-License-Identifier: BSD-3-Clause
// remesh(): the stages in order, their timings and counts, and the output's report.
#include "nurbsfront/pipeline/remesh.h"

#include <cstdint>
#include <string>
#include <utility>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/core/stopwatch.h"
#include "nurbsfront/segment/segment_internal.h"
#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront {

void RemeshOptions::set_threads(unsigned n) {
  if (n == 0) throw InvalidInput("remesh: the thread count must be >= 1");
  segment.threads = static_cast<int>(n);
  surfmesh.threads = static_cast<int>(n);
  stitch.n_threads = n;
  distance.n_threads = n;
}

void RemeshOptions::validate() const {
  segment.validate();
  surfmesh.validate();
  stitch.validate();
  if (compute_distances) distance.validate();
}

const char* to_string(PatchStatus status) {
  switch (status) {
    case PatchStatus::Ok: return "ok";
    case PatchStatus::FitFailed: return "fit_failed";
    case PatchStatus::MeshFailed: return "mesh_failed";
  }
  return "unknown";
}

namespace {

// Input checks before any work: what segment() and mesh_surface() assume.
void check_input(const TriMesh& input) {
  if (input.n_faces() == 0) throw InvalidInput("remesh: the input mesh has no faces");
  if (input.has_vertex_status() && input.has_face_status()) {
    for (auto v : input.all_vertices()) {
      if (input.status(v).deleted()) throw InvalidInput("remesh: the input mesh has deleted elements (call garbage_collection())");
    }
    for (auto f : input.all_faces()) {
      if (input.status(f).deleted()) throw InvalidInput("remesh: the input mesh has deleted elements (call garbage_collection())");
    }
  }
  // OpenMesh's is_manifold(v) (an outgoing boundary halfedge other than v's own halfedge,
  // which its circulator visits first) in one pass over the halfedges instead of a
  // circulation around every vertex.
  std::vector<std::uint8_t> is_non_manifold(input.n_vertices(), 0);
  for (auto h : input.halfedges()) {
    if (!input.is_boundary(h)) continue;
    const auto v = input.from_vertex_handle(h);
    if (input.halfedge_handle(v) != h) is_non_manifold[static_cast<std::size_t>(v.idx())] = 1;
  }
  std::size_t n_non_finite = 0, n_non_manifold = 0;
  for (auto v : input.vertices()) {
    if (!to_eigen(input.point(v)).allFinite()) ++n_non_finite;
    if (is_non_manifold[static_cast<std::size_t>(v.idx())] != 0) ++n_non_manifold;
  }
  if (n_non_finite > 0) {
    throw InvalidInput("remesh: the input mesh has " + std::to_string(n_non_finite) +
                       " vertices with non-finite (NaN or infinite) coordinates");
  }
  if (n_non_manifold > 0) {
    throw InvalidInput("remesh: the input mesh has " + std::to_string(n_non_manifold) +
                       " non-manifold vertices (several face fans meet at one vertex)");
  }
  // A triangle of exactly zero area has no normal: segmentation cannot place it and the
  // output silently loses the region around it (issue 6). io's prepare_mesh() flips them away.
  std::size_t n_zero_area = 0;
  for (auto f : input.faces()) {
    const auto h = input.halfedge_handle(f);
    const auto& a = input.point(input.from_vertex_handle(h));
    const auto& b = input.point(input.to_vertex_handle(h));
    const auto& c = input.point(input.to_vertex_handle(input.next_halfedge_handle(h)));
    n_zero_area += ((b - a) % (c - a)).sqrnorm() == 0.0 ? 1 : 0;
  }
  if (n_zero_area > 0) {
    throw InvalidInput("remesh: the input mesh has " + std::to_string(n_zero_area) +
                       " triangles of zero area (three collinear corners); io's prepare_mesh() removes them "
                       "by edge flips (the nurbsfront tool does so on reading)");
  }
}

// A stage's callback that also feeds the run's callback (both must agree to go on).
ProgressCallback chained(const ProgressCallback& top, const ProgressCallback& own) {
  if (!top) return own;
  return [top, own](std::string_view stage, double fraction) {
    const bool go_on = !own || own(stage, fraction);
    return top(stage, fraction) && go_on;
  };
}

}  // namespace

RemeshResult remesh(const TriMesh& input, const RemeshOptions& options) {
  options.validate();
  check_input(input);
  Stopwatch total;
  RemeshResult result;
  RemeshReport& report = result.report;
  report.n_input_vertices = input.n_vertices();
  report.n_input_faces = input.n_faces();

  SegmentOptions segment_options = options.segment;
  segment_options.progress = chained(options.progress, options.segment.progress);
  SurfMeshOptions surfmesh_options = options.surfmesh;
  surfmesh_options.crease_angle_deg = options.segment.crease_angle_deg;
  surfmesh_options.progress = chained(options.progress, options.surfmesh.progress);
  StitchOptions stitch_options = options.stitch;
  stitch_options.progress = chained(options.progress, options.stitch.progress);

  Stopwatch watch;
  // mean_edge_length(input), once for segment() and surfmesh (a pass over every edge).
  const double mean_edge = mean_edge_length(input);
  // segment()'s face graph and normals, kept for the splits of split_unfitted_patches.
  segment_detail::SplitterPtr splitter;
  const Segmentation first_segmentation = segment_detail::segment(input, segment_options, mean_edge, &splitter);
  report.seconds_segment = watch.seconds();
  report.n_crease_edges = first_segmentation.n_crease_edges;

  watch.restart();
  // Patches whose fit leaves their input (sharp bends inside) are split and refitted.
  const Segmentation segmentation =
      surfmesh_detail::split_unfitted_patches(input, first_segmentation, surfmesh_options, segment_options,
                                              &report.n_patches_split, mean_edge, splitter.get());
  splitter.reset();
  report.n_patches = segmentation.patches.size();
  report.n_curves = segmentation.curves.size();
  report.n_corners = segmentation.corners.size();
  const SurfaceMesh surface = surfmesh_detail::mesh_surface(input, segmentation, surfmesh_options, mean_edge);
  report.seconds_surfmesh = watch.seconds();
  report.n_nodes = surface.nodes.size();
  report.target_size = surface.target_size;
  report.input_mean_edge = surface.input_mean_edge;
  report.patches = surface.patches;
  for (std::size_t p = 0; p < surface.patches.size(); ++p) {
    const PatchMeshReport& patch = surface.patches[p];
    if (patch.status == PatchStatus::Ok) continue;
    ++report.n_failed_patches;
    report.errors.push_back("patch " + std::to_string(p) + " (" + std::to_string(patch.n_input_faces) +
                            " input faces): " + to_string(patch.status) + ": " + patch.message);
  }

  watch.restart();
  StitchResult stitched = stitch(surface, input, stitch_options);
  report.seconds_stitch = watch.seconds();
  for (const auto& e : stitched.report.errors) report.errors.push_back("stitch: " + e);
  report.output = stitched.report.output;
  report.stitch = std::move(stitched.report);
  result.mesh = std::move(stitched.mesh);
  result.face_patch = std::move(stitched.face_patch);
  report.n_triangles = result.mesh.n_faces();

  watch.restart();
  if (options.compute_distances && result.mesh.n_faces() > 0) {
    DistanceOptions distance = options.distance;
    distance.progress = chained(options.progress, options.distance.progress);
    report.output.distance = mesh_distance(to_soup(result.mesh), to_soup(input), distance);
  }
  report.seconds_distance = watch.seconds();
  report.seconds_total = total.seconds();
  return result;
}

}  // namespace nurbsfront
