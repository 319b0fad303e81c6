// SPDX-License-Identifier: BSD-3-Clause
// remesh(): the stages in order, their timings and counts, and the output's report.
#include "nurbsfront/pipeline/remesh.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <optional>
#include <string>
#include <utility>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/core/soup_internal.h"
#include "nurbsfront/core/stopwatch.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/quality/internal.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/segment/segment_internal.h"
#include "nurbsfront/stitch/stitch_internal.h"
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
  if (crossing_repair_rounds < 0) throw InvalidInput("remesh: crossing_repair_rounds must be >= 0");
  if (!(std::isfinite(narrow_patch_merge) && narrow_patch_merge >= 0.0))
    throw InvalidInput("remesh: narrow_patch_merge must be finite and >= 0");
  if (tiny_patch_faces < 0) throw InvalidInput("remesh: tiny_patch_faces must be >= 0");
  if (!(std::isfinite(hairline_patch_width) && hairline_patch_width >= 0.0))
    throw InvalidInput("remesh: hairline_patch_width must be finite and >= 0");
  if (!(std::isfinite(fin_strip_width) && fin_strip_width >= 0.0 && fin_strip_width <= 1.0))
    throw InvalidInput("remesh: fin_strip_width must be in [0, 1]");
  if (fin_strip_max_lost_corners < -1) throw InvalidInput("remesh: fin_strip_max_lost_corners must be >= -1");
  if (!(fin_strip_pin_angle_deg >= 0.0 && fin_strip_pin_angle_deg <= 180.0))
    throw InvalidInput("remesh: fin_strip_pin_angle_deg must be in [0, 180]");
  if (fin_strip_pin_angle_deg > 0.0 && fin_strip_max_lost_corners < 0)
    throw InvalidInput("remesh: fin_strip_pin_angle_deg needs the corner guard (fin_strip_max_lost_corners >= 0)");
  if (!(std::isfinite(narrow_cad_patch_width) && narrow_cad_patch_width >= 0.0))
    throw InvalidInput("remesh: narrow_cad_patch_width must be finite and >= 0");
  if (!(std::isfinite(narrow_widen_width) && narrow_widen_width >= 0.0))
    throw InvalidInput("remesh: narrow_widen_width must be finite and >= 0");
  if (!(tiny_patch_max_dihedral_deg >= 0.0 && tiny_patch_max_dihedral_deg <= 180.0))
    throw InvalidInput("remesh: tiny_patch_max_dihedral_deg must be in [0, 180]");
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

// RemeshOptions::tiny_patch_faces: the tiny patches behind marginal creases join a neighbour
// (segment's merge into neighbours, across creases, slope and projection checks kept).
// Returns the number of patches merged.
std::size_t merge_tiny_patches(segment_detail::Splitter& splitter, const TriMesh& input, Segmentation& segmentation,
                               const RemeshOptions& options) {
  const std::vector<int> tiny = tiny_patches(input, segmentation, static_cast<std::size_t>(options.tiny_patch_faces),
                                             options.tiny_patch_max_dihedral_deg);
  if (tiny.empty()) return 0;
  const std::size_t n_before = segmentation.patches.size();
  segmentation = segment_detail::merge_into_neighbours(splitter, segmentation, tiny, false);
  return n_before - segmentation.patches.size();
}

// Input checks before any work: what segment() and mesh_surface() assume. The counts are
// made on `threads` threads (per chunk, then added up: the same counts for any count).
void check_input(const TriMesh& input, const unsigned threads) {
  if (input.n_faces() == 0) throw InvalidInput("remesh: the input mesh has no faces");
  constexpr std::size_t kChunk = 32768;
  if (input.has_vertex_status() && input.has_face_status()) {
    std::atomic<bool> deleted{false};
    parallel::for_chunks(input.n_vertices(), threads, kChunk, [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t i = begin; i < end; ++i)
        if (input.status(TriMesh::VertexHandle(static_cast<int>(i))).deleted()) deleted = true;
    });
    parallel::for_chunks(input.n_faces(), threads, kChunk, [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t i = begin; i < end; ++i)
        if (input.status(TriMesh::FaceHandle(static_cast<int>(i))).deleted()) deleted = true;
    });
    if (deleted) throw InvalidInput("remesh: the input mesh has deleted elements (call garbage_collection())");
  }
  // OpenMesh's is_manifold(v) (an outgoing boundary halfedge other than v's own halfedge,
  // which its circulator visits first) in one pass over the halfedges instead of a
  // circulation around every vertex: each chunk lists the vertices it finds (rarely any),
  // a vertex found several times counts once.
  std::vector<std::vector<int>> found(input.n_halfedges() / kChunk + 1);
  parallel::for_chunks(input.n_halfedges(), threads, kChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) {
      const TriMesh::HalfedgeHandle h(static_cast<int>(i));
      if (!input.is_boundary(h)) continue;
      const auto v = input.from_vertex_handle(h);
      if (input.halfedge_handle(v) != h) found[begin / kChunk].push_back(v.idx());
    }
  });
  std::vector<std::uint8_t> is_non_manifold(input.n_vertices(), 0);
  std::size_t n_non_manifold = 0;
  for (const auto& part : found) {
    for (const int v : part) {
      n_non_manifold += is_non_manifold[static_cast<std::size_t>(v)] == 0 ? 1 : 0;
      is_non_manifold[static_cast<std::size_t>(v)] = 1;
    }
  }
  std::vector<std::size_t> n_non_finite(input.n_vertices() / kChunk + 1, 0);
  parallel::for_chunks(input.n_vertices(), threads, kChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i)
      n_non_finite[begin / kChunk] += to_eigen(input.point(TriMesh::VertexHandle(static_cast<int>(i)))).allFinite() ? 0 : 1;
  });
  const std::size_t n_non_finite_total = std::accumulate(n_non_finite.begin(), n_non_finite.end(), std::size_t{0});
  if (n_non_finite_total > 0) {
    throw InvalidInput("remesh: the input mesh has " + std::to_string(n_non_finite_total) +
                       " vertices with non-finite (NaN or infinite) coordinates");
  }
  if (n_non_manifold > 0) {
    throw InvalidInput("remesh: the input mesh has " + std::to_string(n_non_manifold) +
                       " non-manifold vertices (several face fans meet at one vertex)");
  }
  // A triangle of exactly zero area has no normal: segmentation cannot place it and the
  // output silently loses the region around it (issue 6). io's prepare_mesh() flips them away.
  std::vector<std::size_t> n_zero_area(input.n_faces() / kChunk + 1, 0);
  parallel::for_chunks(input.n_faces(), threads, kChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) {
      const auto h = input.halfedge_handle(TriMesh::FaceHandle(static_cast<int>(i)));
      const auto& a = input.point(input.from_vertex_handle(h));
      const auto& b = input.point(input.to_vertex_handle(h));
      const auto& c = input.point(input.to_vertex_handle(input.next_halfedge_handle(h)));
      n_zero_area[begin / kChunk] += ((b - a) % (c - a)).sqrnorm() == 0.0 ? 1 : 0;
    }
  });
  const std::size_t n_zero_area_total = std::accumulate(n_zero_area.begin(), n_zero_area.end(), std::size_t{0});
  if (n_zero_area_total > 0) {
    throw InvalidInput("remesh: the input mesh has " + std::to_string(n_zero_area_total) +
                       " triangles of zero area (three collinear corners); io's prepare_mesh() removes them "
                       "by edge flips (the nurbsfront tool does so on reading)");
  }
}

std::size_t crossing_pairs(const StitchReport& report) {
  return report.output.topology.n_self_intersecting_pairs.value_or(0);
}

// The stitch errors other than the crossings' (one line when there are any).
std::size_t other_errors(const StitchReport& report) {
  return report.errors.size() - (crossing_pairs(report) > 0 ? 1 : 0);
}

std::size_t failed_patches(const SurfaceMesh& surface) {
  return static_cast<std::size_t>(std::count_if(surface.patches.begin(), surface.patches.end(), [](const auto& p) {
    return p.status != PatchStatus::Ok;
  }));
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
  // The input pass's threads: the segmentation's (its first stage).
  const unsigned input_threads = parallel::thread_count(options.segment.threads);
  check_input(input, input_threads);
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
  const double mean_edge = core_detail::mean_edge_length(input, input_threads);
  // The input's lattice shares (the marching-cubes gate), computed when first needed.
  std::optional<surfmesh_detail::LatticeShares> lattice;
  auto input_lattice = [&]() -> const surfmesh_detail::LatticeShares& {
    if (!lattice) lattice = surfmesh_detail::lattice_edge_shares(input, mean_edge);
    return *lattice;
  };
  // Sharp creases are for CAD-like meshes: the terraces of a marching-cubes surface are
  // planar and their steps lines of equal bends (occupancy DRAM cell at 128: 9424 such
  // edges, 4764 patches), and a band fit takes no creases below the crease angle either.
  if (segment_options.sharp_crease_angle_deg > 0.0 &&
      (surfmesh_options.cell_grid.enabled || surfmesh_detail::marching_cubes_lattice(input_lattice())))
    segment_options.sharp_crease_angle_deg = 0.0;
  // A gap in a CAD mesh's bends below the crease angle: its machined edges there are creases.
  if (options.crease_gap && !surfmesh_options.cell_grid.enabled &&
      !surfmesh_detail::marching_cubes_lattice(input_lattice())) {
    segment_options.crease_angle_deg = gap_crease_angle(input, segment_options.crease_angle_deg);
    surfmesh_options.crease_angle_deg = segment_options.crease_angle_deg;
  }
  report.crease_angle_deg = segment_options.crease_angle_deg;
  // segment()'s face graph and normals, kept for the splits of split_unfitted_patches.
  // The border curves are extracted once, after the merges and splits below (each of
  // them would extract all of them again: 0.13 G instructions a time on the liver).
  segment_detail::SplitterPtr splitter;
  Segmentation first_segmentation = segment_detail::segment(input, segment_options, mean_edge, &splitter, false);
  report.n_crease_edges = first_segmentation.n_crease_edges;
  // Narrow patches (one-voxel fins and strips of marching-cubes surfaces) join a neighbour.
  // Not on label images (0/1 cells: vertices at their lattice edges' midpoints): the liver's
  // merges cost one crossing repair and twice the run's CPU (2.8 -> 5.4 s) for no bound it
  // did not meet already (docs/segment.md, "Narrow patches"). The gate first: the search for
  // narrow patches is a serial pass over every face (0.15 G instructions on the liver).
  // The patches narrower than width target edges join a neighbour (hairlines: their own
  // faces exempt from the slope bounds; steep: whichever way they face, above the raw
  // orientation floor); the number of patches merged away.
  // The faces the hairline and steep merges joined, kept across their two calls.
  std::vector<std::uint8_t> exempt_faces;
  auto merge_narrower_than = [&](double width, bool hairlines, bool steep, int max_lost_corners = -1,
                                 double pin_below_deg = 0.0) -> std::size_t {
    const double h = surfmesh_detail::uniform_size(surfmesh_options.sizing, mean_edge);
    const std::vector<int> narrow = segment_detail::narrow_patches(input, first_segmentation, width * h, input_threads);
    if (narrow.empty()) return 0;
    const std::size_t n_before = first_segmentation.patches.size();
    first_segmentation =
        segment_detail::merge_into_neighbours(*splitter, first_segmentation, narrow, false, hairlines, steep, &exempt_faces,
                                              max_lost_corners, pin_below_deg);
    return n_before - first_segmentation.patches.size();
  };
  if (options.narrow_patch_merge > 0.0 && surfmesh_detail::marching_cubes_lattice(input_lattice()) &&
      !surfmesh_detail::label_image_staircase(input_lattice()))
    report.n_narrow_merged = merge_narrower_than(options.narrow_patch_merge, false, false);
  // The fin strips the narrow merge left (no neighbour's cone holds them: a fin's
  // rim faces away from both sides) join a neighbour as hairlines do, their own faces exempt
  // (docs/segment.md "Fin strips, session 18"), unless the join takes more than
  // fin_strip_max_lost_corners of their corners away (the corner guard, session 19).
  if (options.fin_strip_width > 0.0 && surfmesh_detail::marching_cubes_lattice(input_lattice()) &&
      !surfmesh_detail::label_image_staircase(input_lattice()))
    report.n_narrow_merged += merge_narrower_than(options.fin_strip_width, true, false, options.fin_strip_max_lost_corners,
                                                  options.fin_strip_pin_angle_deg);
  // Tiny patches behind marginal creases (a coarse CAD-like mesh's bends) join a neighbour.
  if (options.tiny_patch_faces > 0 && !surfmesh_options.cell_grid.enabled &&
      !surfmesh_detail::marching_cubes_lattice(input_lattice()))
    report.n_tiny_merged = merge_tiny_patches(*splitter, input, first_segmentation, options);
  // Hairline patches (a coarse mesh's strips folded back between two creases: their two
  // border curves nearly meet) join a wide neighbour, their own faces exempt from the slope
  // bounds (docs/segment.md "Hairline patches").
  if (options.hairline_patch_width > 0.0 && !surfmesh_options.cell_grid.enabled &&
      !surfmesh_detail::marching_cubes_lattice(input_lattice()))
    report.n_hairline_merged = merge_narrower_than(options.hairline_patch_width, true, false);
  // Opt-in: the narrow patches of a CAD-like mesh that face a neighbour (slope-bounded strips
  // a fraction of h wide) join it too (docs/segment.md "Narrow patches of CAD-like meshes").
  if (options.narrow_cad_patch_width > 0.0 && !surfmesh_options.cell_grid.enabled &&
      !surfmesh_detail::marching_cubes_lattice(input_lattice()))
    report.n_narrow_merged = merge_narrower_than(options.narrow_cad_patch_width, true, true);
  // Narrow slope-bounded patches of a CAD-like mesh (a rough triangulation of a smooth
  // surface: femur) take faces from their wider neighbours (docs/segment.md "Widening
  // narrow patches, session 18").
  if (options.narrow_widen_width > 0.0 && !surfmesh_options.cell_grid.enabled &&
      !surfmesh_detail::marching_cubes_lattice(input_lattice())) {
    const double width = options.narrow_widen_width * surfmesh_detail::uniform_size(surfmesh_options.sizing, mean_edge);
    const std::vector<int> narrow = segment_detail::narrow_patches(input, first_segmentation, width, input_threads);
    if (!narrow.empty())
      first_segmentation = segment_detail::widen_patches(*splitter, first_segmentation, narrow, width, false,
                                                         &report.n_narrow_widened);
  }
  report.seconds_segment = watch.seconds();

  watch.restart();
  // Patches whose fit leaves their input (sharp bends inside) are split and refitted.
  Segmentation segmentation = segment_detail::with_borders(
      input, segment_options,
      surfmesh_detail::split_unfitted_patches(input, first_segmentation, surfmesh_options, segment_options,
                                              &report.n_patches_split, mean_edge, splitter.get(), false));
  // The splitter's graph and normals are not held through surfmesh and stitch (about 100 MB
  // on DRAM 256); the rare crossing repair below makes a new one (the same graph and normals).
  splitter.reset();
  // The shares when computed above (mesh_surface does not compute them again).
  const surfmesh_detail::LatticeShares* shares = lattice ? &*lattice : nullptr;
  // The stitch's volume compensation makes no move on a label image's staircase (its own
  // gate, the same test as here, surfmesh_detail::label_image_staircase: a pass over the
  // input's edges, 0.13 G instructions on the liver): with the answer known, it is switched
  // off instead of tested again. Only where the stitch optimises anyway (volume compensation
  // alone would start its optimisation).
  if (lattice && surfmesh_detail::label_image_staircase(*lattice) &&
      (stitch_options.optimisation_passes > 0 || stitch_options.obtuse_repair_rounds > 0 ||
       stitch_options.chord_compensation > 0.0))
    stitch_options.volume_compensation = 0.0;
  // The split grid's nodes sit on the fit, which with a cell grid (the occupancy band fit) is
  // off the marching-cubes input by design: DRAM occupancy 128's Hausdorff to the input rose
  // from 0.89 to 1.05 voxel with them (StitchOptions::obtuse_split_grid).
  if (surfmesh_options.cell_grid.enabled) stitch_options.obtuse_split_grid = false;
  // The segmentation's face_patch is copied into the surface only for the fidelity gate
  // (its one reader; 4 bytes per input face).
  const bool gate = stitch_options.fidelity_gate_edges > 0.0;
  SurfaceMesh surface = surfmesh_detail::mesh_surface(input, segmentation, surfmesh_options, mean_edge, shares, gate);
  report.seconds_surfmesh = watch.seconds();

  watch.restart();
  // The input's soup and tree over all faces, built once for the fidelity moves and the
  // distance pass (docs/stitch.md "Fidelity moves, session 18").
  std::optional<quality_detail::IndexedSoup> input_index;
  if (stitch_options.fidelity_distance_edges > 0.0 && options.compute_distances) {
    input_index.emplace(to_soup(input), stitch_options.n_threads);
  }
  auto run_stitch = [&](const SurfaceMesh& meshed) {
    return input_index ? stitch_detail::stitch_with_input_index(meshed, input, *input_index, stitch_options)
                       : stitch(meshed, input, stitch_options);
  };
  StitchResult stitched = run_stitch(surface);
  report.seconds_stitch = watch.seconds();

  // Last resort against crossings that stitching left (docs/segment.md, "Re-segmenting
  // crossing patches"). Remedies in order, each on the patches of every crossing pair: the
  // smaller patch joins a neighbour, the larger joins one, the larger is bisected, the smaller
  // is bisected. After a remedy the surface is meshed and stitched again, and that result is
  // kept only if it crosses less, has no other error and no more failed patches; the first
  // remedy kept ends the round. The output stays the same for any thread count (the pairs
  // are sorted, the stages deterministic).
  // A self-intersecting input is not repaired: its output inherits the crossings (the tool
  // names them), and removing them would move the surface away from the input.
  // (The input's crossings counted on its soup and tree of the fidelity moves when built.)
  const auto input_crossings = [&] {
    return input_index ? quality_detail::count_self_intersections_with(input_index->soup(), input_index->tree(),
                                                                       stitch_options.n_threads)
                       : count_self_intersections(to_soup(input), stitch_options.n_threads);
  };
  const bool repair =
      options.crossing_repair_rounds > 0 && crossing_pairs(stitched.report) > 0 && input_crossings() == 0;
  for (int round = 0; repair && round < options.crossing_repair_rounds; ++round) {
    const std::size_t n_pairs = crossing_pairs(stitched.report);
    if (n_pairs == 0) break;
    const auto pairs = self_intersecting_pairs(to_soup(stitched.mesh), stitch_options.n_threads);
    bool improved = false;
    for (int remedy = 0; remedy < 4; ++remedy) {
      const bool smaller = remedy == 0 || remedy == 3;
      std::vector<int> which;
      for (const auto& pair : pairs) {
        const int a = stitched.face_patch[pair[0]], b = stitched.face_patch[pair[1]];
        const bool a_first = segmentation.patches[static_cast<std::size_t>(a)].faces.size() <=
                             segmentation.patches[static_cast<std::size_t>(b)].faces.size();
        which.push_back(a_first == smaller ? a : b);
      }
      std::sort(which.begin(), which.end(), [&](int x, int y) {
        const std::size_t nx = segmentation.patches[static_cast<std::size_t>(x)].faces.size();
        const std::size_t ny = segmentation.patches[static_cast<std::size_t>(y)].faces.size();
        return nx != ny ? nx < ny : x < y;
      });
      which.erase(std::unique(which.begin(), which.end()), which.end());
      if (!splitter) splitter = segment_detail::make_splitter(input, segment_options);
      Segmentation merged = remedy < 2 ? segment_detail::merge_into_neighbours(*splitter, segmentation, which)
                                       : segment_detail::bisect_patches(*splitter, segmentation, which);
      if (merged.patches.size() == segmentation.patches.size()) continue;
      watch.restart();
      SurfaceMesh merged_surface = surfmesh_detail::mesh_surface(input, merged, surfmesh_options, mean_edge, shares, gate);
      report.seconds_surfmesh += watch.seconds();
      watch.restart();
      StitchResult merged_stitched = run_stitch(merged_surface);
      report.seconds_stitch += watch.seconds();
      if (crossing_pairs(merged_stitched.report) >= n_pairs || other_errors(merged_stitched.report) > 0 ||
          failed_patches(merged_surface) > failed_patches(surface))
        continue;
      ++report.n_crossing_repairs;
      segmentation = std::move(merged);
      surface = std::move(merged_surface);
      stitched = std::move(merged_stitched);
      improved = true;
      break;
    }
    if (!improved) break;
  }
  splitter.reset();
  report.n_patches = segmentation.patches.size();
  report.n_curves = segmentation.curves.size();
  report.n_corners = segmentation.corners.size();
  report.n_nodes = surface.nodes.size();
  report.feature_sizing_applied = surface.feature_sizing_applied;
  report.n_fin_rim_curves = surface.n_fin_rim_curves;
  report.detail_fit_skipped = surface.detail_fit_skipped;
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
    if (input_index) {
      // mesh_distance() on the input's tree built for the stitch (the same report).
      distance.validate();
      const TriangleSoup output_soup = to_soup(result.mesh);
      quality_detail::validate_soup(output_soup, "mesh_distance (mesh)");
      quality_detail::validate_soup(input_index->soup(), "mesh_distance (reference)");
      report.output.distance =
          quality_detail::mesh_distance_with(output_soup, input_index->soup(), distance, nullptr, &input_index->tree());
    } else {
      report.output.distance = mesh_distance(to_soup(result.mesh), to_soup(input), distance);
    }
  }
  report.seconds_distance = watch.seconds();
  report.seconds_total = total.seconds();
  return result;
}

RemeshResult remesh_to_vertex_count(const TriMesh& input, std::size_t target_vertices, RemeshOptions options,
                                    double relative_tolerance, int max_runs) {
  if (target_vertices < 4) throw InvalidInput("remesh_to_vertex_count: the target vertex count must be >= 4");
  if (!(relative_tolerance >= 0.0 && relative_tolerance < 1.0)) {
    throw InvalidInput("remesh_to_vertex_count: relative_tolerance must be in [0, 1)");
  }
  if (max_runs < 1) throw InvalidInput("remesh_to_vertex_count: max_runs must be >= 1");
  if (options.surfmesh.sizing.callback) {
    throw InvalidInput("remesh_to_vertex_count: a sizing callback cannot be scaled to a vertex count");
  }
  const double target = static_cast<double>(target_vertices);
  auto miss = [target](const RemeshResult& r) { return std::abs(static_cast<double>(r.mesh.n_vertices()) - target); };
  RemeshResult best;
  bool have_best = false;
  // vertices ~ size^-exponent: 2 for a uniform size; from the last two runs once there are
  // two (adaptive sizing's curvature bound sqrt(8 e / kappa) with e ~ size gives about 1).
  double exponent = 2.0;
  double last_size = 0.0, last_vertices = 0.0;
  for (int run = 0; run < max_runs; ++run) {
    RemeshResult result = remesh(input, options);
    const auto vertices = static_cast<double>(result.mesh.n_vertices());
    const double size = result.report.target_size;
    // A run without errors is preferred to any run with some, then the closest count.
    const bool better = !have_best || (result.report.ok() && !best.report.ok()) ||
                        (result.report.ok() == best.report.ok() && miss(result) < miss(best));
    if (better) {
      best = std::move(result);
      have_best = true;
    }
    if (miss(best) <= relative_tolerance * target || vertices == 0.0 || !(size > 0.0)) break;
    if (last_size > 0.0 && last_size != size && last_vertices != vertices) {
      exponent = std::clamp(std::log(vertices / last_vertices) / std::log(last_size / size), 0.5, 3.0);
    }
    last_size = size;
    last_vertices = vertices;
    // At most a factor 3 per run: a far or unreachable target moves the size step by step.
    options.surfmesh.sizing.size = size * std::clamp(std::pow(vertices / target, 1.0 / exponent), 1.0 / 3.0, 3.0);
  }
  return best;
}

}  // namespace nurbsfront
