// SPDX-License-Identifier: BSD-3-Clause
// nurbsfront remesh IN OUT: the remeshing pipeline on a mesh file or a built-in scene's
// marching-cubes surface; prints a summary, writes the mesh, optionally the JSON report
// and a VTK file with per-face patch id and alpha. Exits non-zero when the report has errors.
#include <cmath>
#include <cstddef>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/stopwatch.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/pipeline/remesh.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront::cli {

namespace {

// --vertices: remesh_to_vertex_count's tolerance and runs (its defaults).
constexpr double kVertexCountTolerance = 0.005;
constexpr int kVertexCountRuns = 4;

// CLI11 (2.1) reads "-1" into a std::size_t as its largest value (strtoull): the options
// held in a std::size_t refuse a minus sign.
const CLI::Validator kNoMinusSign(
    [](const std::string& text) {
      return text.find('-') == std::string::npos ? std::string{} : "a count cannot be negative, got " + text;
    },
    "");

struct RemeshArgs {
  std::vector<std::string> files;  // IN OUT, or OUT with --scene
  std::string input;
  std::string output;
  std::string scene;
  int resolution = 128;
  bool occupancy = false;
  std::vector<double> cell_grid;  // ORIGIN_X ORIGIN_Y ORIGIN_Z SPACING
  bool no_cell_grid = false;
  std::optional<double> size;
  std::optional<double> relative_size;
  std::optional<std::size_t> vertices;
  std::optional<double> detail_fit;
  bool bevel_creases = false;
  bool no_crease_gap = false;
  bool smoothed_boundary = false;
  bool project_border_nodes = false;
  bool no_self_intersection_check = false;
  bool no_obtuse_split_grid = false;
  bool no_flip_feature_chords = false;
  bool no_obtuse_collapse = false;
  bool no_distances = false;
  // The options the flags without a field above set directly (their defaults are
  // RemeshOptions' own); run_remesh starts from it.
  RemeshOptions base;
  std::optional<unsigned> threads;
  std::string report;
  std::string vtk;
  bool quiet = false;
};

// Loads IN or samples the scene. An occupancy scene switches the band fit on with its
// grid (CellGrid) unless --no-cell-grid is given.
PreparedMesh load_input(const RemeshArgs& args, RemeshOptions& remesh_options) {
  const ProgressCallback& progress = remesh_options.progress;
  if (args.input.empty() == args.scene.empty()) {
    throw InvalidInput("remesh: give either an input mesh IN or --scene NAME (exactly one)");
  }
  TriangleSoup soup;
  if (!args.scene.empty()) {
    const SampleMode mode = args.occupancy ? SampleMode::Occupancy : SampleMode::LevelSet;
    MarchingCubesOptions options = scene_marching_cubes_options(mode);
    options.progress = progress;
    const ScalarGrid grid = sample_scene(scene_by_name(args.scene), args.resolution, mode);
    if (args.occupancy && !args.no_cell_grid) remesh_options.surfmesh.cell_grid = {true, grid.origin, grid.spacing};
    soup = marching_cubes(grid, options);
  } else {
    if (args.occupancy) throw InvalidInput("remesh: --occupancy applies to --scene only");
    soup = read_soup(args.input);
  }
  CleanOptions clean_options;
  clean_options.threads = args.threads ? static_cast<int>(*args.threads) : 0;
  return prepare_mesh(soup, clean_options);
}

void run_remesh(RemeshArgs& args) {
  if (args.files.size() == 2) {
    args.input = args.files[0];
    args.output = args.files[1];
  } else if (args.files.size() == 1) {
    args.output = args.files[0];
  }
  if (args.output.empty()) throw InvalidInput("remesh: give the output file (IN OUT, or OUT with --scene)");
  RemeshOptions options = args.base;
  if (args.size) options.surfmesh.sizing.size = *args.size;
  if (args.relative_size) options.surfmesh.sizing.relative_size = *args.relative_size;
  if (args.detail_fit) options.surfmesh.fit.detail_spacing_edges = *args.detail_fit;
  if (args.bevel_creases) options.segment.bevel_creases = true;
  if (args.no_crease_gap) options.crease_gap = false;
  if (args.smoothed_boundary) options.surfmesh.unsmoothed_boundary_curves = false;
  if (args.project_border_nodes) options.surfmesh.project_border_nodes = true;
  if (args.no_self_intersection_check) options.stitch.check_self_intersections = false;
  if (args.no_obtuse_split_grid) options.stitch.obtuse_split_grid = false;
  if (args.no_flip_feature_chords) options.stitch.flip_feature_chords = false;
  if (args.no_obtuse_collapse) options.stitch.obtuse_collapse = false;
  if (args.no_distances) options.compute_distances = false;
  if (args.threads) options.set_threads(*args.threads);
  if (!args.cell_grid.empty()) {
    if (!args.scene.empty()) throw InvalidInput("remesh: --cell-grid applies to an input file (an occupancy scene sets it itself)");
    const double spacing = args.cell_grid[3];
    options.surfmesh.cell_grid = {true, {args.cell_grid[0], args.cell_grid[1], args.cell_grid[2]}, {spacing, spacing, spacing}};
  }
  if (args.detail_fit && *args.detail_fit > 0.0 && ((args.occupancy && !args.no_cell_grid) || !args.cell_grid.empty()))
    throw InvalidInput("remesh: --detail-fit refits the plain fit; with a cell grid (--occupancy, --cell-grid) the band fit "
                       "is used instead: drop one of them (--no-cell-grid keeps an occupancy scene on the plain fit)");
  options.progress = terminal_progress(args.quiet);
  options.validate();
  // Fail on an unwritable or unsupported output before the work.
  (void)mesh_format_from_path(args.output);
  if (!args.vtk.empty()) (void)mesh_format_from_path(args.vtk);

  Stopwatch watch;
  const PreparedMesh prepared = load_input(args, options);
  const TriMesh& input = prepared.mesh;
  options.validate();
  const double seconds_input = watch.seconds();
  const RemeshResult result = args.vertices ? remesh_to_vertex_count(input, *args.vertices, options, kVertexCountTolerance, kVertexCountRuns)
                                            : remesh(input, options);

  watch.restart();
  write_mesh(result.mesh, args.output);
  if (!args.vtk.empty()) {
    const TriangleSoup soup = to_soup(result.mesh);
    WriteOptions write_options;
    write_options.face_fields.push_back({"patch", std::vector<double>(result.face_patch.begin(), result.face_patch.end())});
    write_options.face_fields.push_back({"alpha", face_alpha(soup)});
    write_soup(soup, args.vtk, write_options);
  }
  if (!args.report.empty()) {
    std::ofstream file(args.report);
    file << to_json(result.report) << '\n';
    if (!file) throw IoError("remesh: cannot write the report " + args.report);
  }
  const double seconds_output = watch.seconds();
  std::cout << "input repairs: " << prepared.report.summary() << '\n'
            << to_summary(result.report);
  if (args.vertices) {
    std::cout << "output vertices " << result.mesh.n_vertices() << " (asked " << *args.vertices << "), target edge "
              << result.report.target_size << '\n';
    // remesh_to_vertex_count returns its closest run: say so when that is not the count asked.
    const double off = std::abs(static_cast<double>(result.mesh.n_vertices()) - static_cast<double>(*args.vertices)) /
                       static_cast<double>(*args.vertices);
    if (off > kVertexCountTolerance) {
      std::cerr << "warning: remesh: " << result.mesh.n_vertices() << " output vertices are " << std::fixed
                << std::setprecision(1) << 100.0 * off << "% from the " << *args.vertices
                << " asked (not reached within " << 100.0 * kVertexCountTolerance << "% in " << kVertexCountRuns
                << " runs, the size changing by at most 3x per run; a count far from the input's may be unreachable)\n"
                << std::defaultfloat;
    }
  }
  std::cout << "input " << seconds_input << " s, output " << seconds_output << " s\n"
            << "wrote " << args.output << (args.vtk.empty() ? "" : ", " + args.vtk)
            << (args.report.empty() ? "" : ", " + args.report) << '\n';
  const auto& n_self = result.report.output.topology.n_self_intersecting_pairs;
  if (n_self && *n_self > 0) {
    const std::string note = input_self_intersections(input, options.stitch.n_threads);
    if (!note.empty()) std::cout << "note: " << note << '\n';
  }
  if (!result.report.ok()) {
    throw std::runtime_error("remesh: the report has " + std::to_string(result.report.errors.size()) +
                             " errors (listed above); the mesh was written for inspection");
  }
}

// The options of the stages' finer settings, bound to RemeshArgs::base (help shows each
// default); out-of-range values are refused by RemeshOptions::validate().
void add_expert_options(CLI::App& cmd, RemeshArgs& args) {
  RemeshOptions& o = args.base;
  auto add = [&cmd](const std::string& name, auto& field, const std::string& help) {
    CLI::Option* option = cmd.add_option(name, field, help)->capture_default_str()->group("Finer settings");
    if constexpr (std::is_same_v<std::remove_reference_t<decltype(field)>, std::size_t>) option->check(kNoMinusSign);
  };
  // segment
  add("--normal-smoothing-rings", o.segment.normal_smoothing_rings,
      "Rings of area-weighted normal averaging behind the slope grouping (>= 0; SegmentOptions)");
  add("--min-patch-faces", o.segment.min_patch_faces,
      "Patches with fewer faces join a neighbour where the slope bound allows (0 = off)");
  add("--border-smoothing-iterations", o.segment.border_smoothing.iterations,
      "Taubin lambda|mu step pairs smoothing the border curves (>= 0; 0 = input positions)");
  add("--border-smoothing-lambda", o.segment.border_smoothing.lambda, "Taubin's shrinking step factor (in (0, 1])");
  add("--border-smoothing-mu", o.segment.border_smoothing.mu, "Taubin's inflating step factor (in [-1, 0])");
  add("--border-max-displacement", o.segment.border_smoothing.max_displacement,
      "Smoothed border points stay within this many mean curve edges of their input position (>= 0)");
  // surfmesh: sizing and per-patch front
  add("--gradation", o.surfmesh.sizing.gradation, "Sizing gradation: |grad h| <= this - 1 (> 1)");
  add("--min-size-fraction", o.surfmesh.sizing.min_size_fraction,
      "Smallest size --adaptive may ask for, as a fraction of the uniform size");
  add("--front-smoothing-passes", o.surfmesh.smoothing_passes, "Smoothing passes of the 2D front per patch (>= 0)");
  add("--max-node-offset", o.surfmesh.max_node_offset_edges,
      "New inner nodes stay within this many mean input edges of their patch's faces along its axis (0 = off)");
  cmd.add_flag("--project-border-nodes", args.project_border_nodes,
               "Move border nodes to the mean of their projections onto their patches' fits before meshing "
               "(always on with a cell grid)")
      ->group("Finer settings");
  // surfmesh: fits
  add("--fit-tolerance", o.surfmesh.fit.relative_tolerance, "Fit residual tolerance in mean input edges");
  add("--fit-min-spacing", o.surfmesh.fit.min_spacing_edges, "Finest fit lattice spacing in mean input edges");
  add("--fit-max-levels", o.surfmesh.fit.max_levels, "Fit lattice levels at most");
  add("--fit-polish-iterations", o.surfmesh.fit.least_squares_iterations,
      "Conjugate-gradient iterations of the fit's least-squares polish (0 = plain MBA)");
  add("--fit-final-passes", o.surfmesh.fit.final_passes,
      "BA passes on the finest fit lattice before the polish (also in the split check fits)");
  add("--fit-fine-smoothing", o.surfmesh.fit.least_squares_fine_smoothing,
      "Smoothing of the second polish of patches fitted within --fit-fine-below (0 = off)");
  add("--fit-fine-below", o.surfmesh.fit.fine_below_edges,
      "Largest residual (mean input edges) after the first polish for the second one");
  add("--split-rounds", o.surfmesh.fit.split_rounds, "Rounds of splitting patches whose fit leaves their input");
  add("--large-face-edges", o.surfmesh.fit.large_face_edges,
      "Input faces longer than this many mean edges are sampled inside for the fit (0 = off; not with a cell grid)");
  add("--detail-above", o.surfmesh.fit.detail_above_edges,
      "With --detail-fit: refit patches whose fit misses the input by more than this many mean edges");
  add("--detail-node-offset", o.surfmesh.fit.detail_node_offset_edges,
      "With --detail-fit: the refitted patches' new nodes stay within this many mean edges of the input");
  // stitch
  add("--optimisation-passes", o.stitch.optimisation_passes,
      "Rounds of the stitch's flips and smoothing across borders (0 = off)");
  add("--max-flip-dihedral", o.stitch.max_flip_dihedral_deg,
      "Largest angle (deg) between an edge's two triangle normals for a flip (in [0, 180))");
  add("--flip-gain", o.stitch.flip_gain, "Relative alpha gain a flip must bring (>= 0)");
  add("--smoothing-relaxation", o.stitch.smoothing_relaxation,
      "Relaxation of a smoothing move towards its triangles' centroid (in (0, 1])");
  add("--min-normal-dot", o.stitch.min_normal_dot,
      "Smoothing turns no triangle normal by more than acos(this) (in [-1, 1))");
  add("--alpha-floor", o.stitch.alpha_floor,
      "Smoothing keeps the smallest alpha around a node at min(old, this) (in [0, 1])");
  add("--angle-floor", o.stitch.angle_floor_deg,
      "Smoothing keeps the smallest angle (deg) around a node at min(old, this) (in [0, 60))");
  add("--collapse-below-angle", o.stitch.collapse_below_angle_deg,
      "Collapse the shortest edge of triangles with an angle (deg) below this before the optimisation "
      "(in [0, 60); 0 = off)");
  cmd.add_flag("--no-flip-feature-chords", args.no_flip_feature_chords,
               "Edges inside a patch between two nodes of one crease (no neighbours along it) stay locked as "
               "before session 19 (docs/stitch.md \"Chords between the nodes of a crease, session 19\")")
      ->group("Finer settings");
  cmd.add_option("--feature-corner-slides", o.stitch.feature_corner_slides,
                 "Feature slides also move the corners where one or two feature curves end (0 or 1; "
                 "docs/stitch.md \"Feature corners sliding, session 21\")")
      ->capture_default_str()
      ->group("Finer settings");
  cmd.add_flag("--no-obtuse-collapse", args.no_obtuse_collapse,
               "No obtuse collapses after the small-angle repair (by default a corner of an obtuse triangle that is "
               "no feature node is collapsed into a neighbour where that leaves fewer obtuse triangles; "
               "docs/stitch.md \"Obtuse collapses, session 20\")")
      ->group("Finer settings");
  cmd.add_flag("--no-obtuse-split-grid", args.no_obtuse_split_grid,
               "The obtuse splits try no grid of places for their node (off anyway with a cell grid; "
               "docs/stitch.md \"Split nodes on a grid, session 18\")")
      ->group("Finer settings");
  cmd.add_flag("--no-self-intersection-check", args.no_self_intersection_check,
               "Skip the exact self-intersection checks: the output's check, and with it the stitch's undo of moves "
               "that make crossings and the pipeline's crossing repair (the output can change and keep crossings)")
      ->group("Finer settings");
  // distances
  cmd.add_flag("--no-distances", args.no_distances, "Do not measure the output's distance to the input")
      ->group("Finer settings");
  add("--distance-spacing", o.distance.sample_spacing_relative,
      "Spacing of the distance's area samples, as a fraction of the input's bounding-box diagonal");
  add("--distance-max-samples", o.distance.max_samples, "Area samples per surface at most (the spacing grows)");
}

}  // namespace

void add_remesh_command(CLI::App& app) {
  auto args = std::make_shared<RemeshArgs>();
  auto* cmd = app.add_subcommand("remesh", "Remesh a surface: slope-bounded patches, NURBS fits, advancing front, stitch");
  cmd->add_option("files", args->files,
                  "IN OUT: input mesh (.obj .ply .stl .off .vtk; welded, cleaned and made manifold first, see "
                  "`convert --repair`) and output mesh "
                  "(.ply .obj .stl .off .vtk .vtu); only OUT with --scene")
      ->required()
      ->expected(1, 2);
  cmd->add_option("--scene", args->scene, "Built-in scene's marching-cubes surface instead of IN: sphere, torus, trench, dram");
  cmd->add_option("--res", args->resolution, "Scene cells along the longest side (default 128)");
  cmd->add_flag("--occupancy", args->occupancy, "Sample the scene as 0/1 cell occupancy instead of a signed distance");
  auto* cell_grid = cmd->add_option("--cell-grid", args->cell_grid,
                                    "ORIGIN_X ORIGIN_Y ORIGIN_Z SPACING: IN is the marching-cubes surface of 0/1 cells "
                                    "(centres at ORIGIN + SPACING * (i, j, k)); fit the patches to the cell bands")
                        ->expected(4);
  auto* no_cell_grid = cmd->add_flag("--no-cell-grid", args->no_cell_grid,
                                     "With --scene --occupancy: plain fit of the vertices instead of the band fit");
  cell_grid->excludes(no_cell_grid);
  auto* size = cmd->add_option("--size", args->size, "Target edge length (length units)");
  auto* relative = cmd->add_option("--relative-size", args->relative_size,
                                   "Target edge length as a multiple of the input's mean edge length (default 1.5)");
  size->excludes(relative);
  cmd->add_option("--vertices", args->vertices,
                  "Output vertex count to aim at: the uniform size (from --size, --relative-size or the default) is "
                  "scaled by (vertices / N)^(1/p) (p = 2, then measured) and the remesh rerun, at most 4 runs, until within 0.5% "
                  "(remesh_to_vertex_count; docs/pipeline.md)")
      ->check(kNoMinusSign)
      ->check(CLI::Range(std::size_t{4}, std::numeric_limits<std::size_t>::max()));
  cmd->add_flag("--adaptive", args->base.surfmesh.sizing.adaptive, "Curvature-adaptive sizing (chord error)");
  cmd->add_option("--detail-fit", args->detail_fit,
                  "Refit a patch whose fit misses its input by more than 0.25 mean edges on a lattice of this many mean "
                  "edges (e.g. 1; default 0 = off; not with a cell grid) and keep its new nodes within 0.05 mean edges "
                  "of the input: for inputs with detail of 1-2 mean edges (scans, smoothed-image level sets), with "
                  "--adaptive; not for label-image surfaces (it follows their terraces; docs/surfmesh.md \"Detail fit\")");
  cmd->add_option("--feature-size", args->base.surfmesh.sizing.feature_size,
                  "Size of a patch bounded mostly by feature curves at most F x its width (2 area / perimeter); "
                  "0 = off (default 1; not on marching-cubes surfaces nor where it limits under 1% of the area; "
                  "docs/surfmesh.md \"Feature sizing\")");
  cmd->add_flag("--feature-size-everywhere", args->base.surfmesh.sizing.feature_size_everywhere,
                "Feature sizing also on marching-cubes surfaces and where it limits under 1% of the area");
  cmd->add_option("--feature-gradation", args->base.surfmesh.sizing.feature_gradation,
                  "Feature sizing's sizes grow by at most this - 1 per unit length away from the narrow patches "
                  "(> 1; default 1.25; docs/surfmesh.md \"Feature sizing: a gentler gradation\")");
  cmd->add_option("--border-lookahead", args->base.surfmesh.sizing.border_lookahead,
                  "Where the sizes vary (feature or adaptive sizing), discretise the borders with the smallest size "
                  "within this fraction of the size around each point (default 0.35; 0 = the size on the border; "
                  "docs/surfmesh.md \"Border look-ahead\")");
  cmd->add_option("--crossing-repair-rounds", args->base.crossing_repair_rounds,
                  "Rounds of re-segmenting the patches of crossings the stitch left (default 4; 0 = off; "
                  "docs/segment.md \"Re-segmenting crossing patches\")");
  cmd->add_option("--fin-rim-width", args->base.surfmesh.fin_rim_width,
                  "On marching-cubes inputs, crease curves beside a strip narrower than this many target edges "
                  "are no features for stitch (fin rims; docs/stitch.md); 0 = off (default 1)");
  cmd->add_option("--fin-rim-angle", args->base.surfmesh.fin_rim_max_angle_deg,
                  "Largest crease angle (deg) of such a fin rim curve (default 120; 180 with --fin-rim-gap inf "
                  "--fin-rim-max-move 0.25: fewer obtuse triangles on CT bone, more small angles)");
  cmd->add_option("--fin-rim-gap", args->base.surfmesh.fin_rim_max_gap_edges,
                  "A fin rim's nodes have their projections onto both sides' fits within this many mean input "
                  "edges (default 0.25; inf = no test)");
  cmd->add_option("--fin-rim-max-move", args->base.stitch.fin_rim_max_move,
                  "Stitch moves the nodes of fin rims at most this many mean input edges from where the front "
                  "put them (default inf = no bound; docs/stitch.md \"Fin rims: a bound on the moves\")");
  cmd->add_option("--narrow-merge", args->base.narrow_patch_merge,
                  "On marching-cubes inputs, patches narrower than this many target edges join a neighbour "
                  "(default 0.5; 0 = off; docs/segment.md \"Narrow patches\")");
  cmd->add_option("--tiny-merge", args->base.tiny_patch_faces,
                  "On inputs not taken for marching cubes, patches of at most this many input faces whose border "
                  "bends by at most --tiny-merge-angle join a neighbour (default 8; 0 = off; docs/segment.md "
                  "\"Tiny patches behind marginal creases\")");
  cmd->add_option("--tiny-merge-angle", args->base.tiny_patch_max_dihedral_deg,
                  "Largest bend (deg) of such a tiny patch's border (default 120)")
      ->check(CLI::Range(0.0, 180.0));
  cmd->add_option("--hairline-merge", args->base.hairline_patch_width,
                  "On inputs not taken for marching cubes (nor with a cell grid), patches narrower than this many target edges facing away "
                  "from every neighbour join a wider one, their own faces exempt from the slope bound (strips folded back between two "
                  "creases; default 0.05; 0 = off; docs/segment.md \"Hairline patches\")");
  cmd->add_option("--narrow-cad-merge", args->base.narrow_cad_patch_width,
                  "On inputs not taken for marching cubes, patches narrower than this many target edges join a wider "
                  "neighbour whichever way they face, their own faces exempt from the slope bound but not folded over "
                  "its plane (opt-in: femur 2.25 -> 1.87% obtuse at 0.3, cheese and couplingdown worse; default 0 = "
                  "off; docs/segment.md \"Narrow patches of CAD-like meshes, session 17\")");
  cmd->add_option("--fin-strip-merge", args->base.fin_strip_width,
                  "On marching-cubes inputs, after the narrow merge, patches still narrower than this many target "
                  "edges join a wider neighbour, their own faces exempt from the slope bound (a thin fin's rim: its "
                  "two creases become one; 0 = off; default 0.25, with the corner guard below; docs/segment.md \"Fin strips, session 18\")")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--fin-strip-max-lost-corners", args->base.fin_strip_max_lost_corners,
                  "The fin-strip merge's corner guard: a strip joins a neighbour only if at most this many of its "
                  "corners (vertices with 3+ sides: patches, or the input's boundary as one) are left with two (a fin's "
                  "tip is pinned by its corners; >= -1, -1 = no guard; default 1; docs/segment.md \"Fin strips: a corner "
                  "guard, session 19\")");
  cmd->add_option("--fin-strip-pin-angle", args->base.fin_strip_pin_angle_deg,
                  "With the corner guard, > 0: a strip's corner that its join leaves with two sides does not count "
                  "against the guard, and stays a corner (the fin's tip pinned on the input) where the border's angle "
                  "there is below this (deg; 180 = always; 0 = off, default; opt-in with --fin-strip-max-lost-corners 0 "
                  "and 120: fewer obtuse triangles on headsq; docs/segment.md \"Fin strips: pinned tips, session "
                  "20\")")
      ->check(CLI::Range(0.0, 180.0));
  cmd->add_option("--narrow-widen", args->base.narrow_widen_width,
                  "On inputs not taken for marching cubes, patches narrower than this many target edges take faces "
                  "from their wider neighbours across borders that are no crease, within the slope bound, until "
                  "this wide (opt-in: femur 2.10 -> 1.89% obtuse at 0.2, armadillo worse; default 0 = off; docs/segment.md \"Widening narrow patches, session 18\")");
  cmd->add_option("--obtuse-repair-rounds", args->base.stitch.obtuse_repair_rounds,
                  "Sweeps of the stitch's obtuse repair after its optimisation (default 2; 0 = off; "
                  "docs/stitch.md \"Obtuse repair\")");
  cmd->add_option("--obtuse-search", args->base.stitch.obtuse_search_steps,
                  "Halvings of the obtuse repair's search in the plane for nodes the apex steps do not help "
                  "(in [0, 30]; default 5; 0 = off; docs/stitch.md \"Obtuse repair: a search in the plane, session 17\")");
  cmd->add_option("--feature-slide-rounds", args->base.stitch.feature_slide_rounds,
                  "Rounds of the stitch's feature slides: nodes of creases and of the boundary slide along their "
                  "curve where that removes an obtuse triangle (default 2; 0 = off; part of the obtuse repair: none when "
                  "--obtuse-repair-rounds is 0; docs/stitch.md \"Feature nodes "
                  "sliding along their curves\")");
  cmd->add_option("--feature-slide-cosine-gain", args->base.stitch.feature_slide_cosine_gain,
                  "Also slide a feature node where that raises the cosine of its ring's largest angle by this "
                  "(> 0; default inf = only where an obtuse triangle goes; 0.01: fewer obtuse triangles on elephant, "
                  "couplingdown, rotor, more on pinion; docs/stitch.md \"Feature nodes sliding along their curves\")");
  cmd->add_option("--obtuse-split-rounds", args->base.stitch.obtuse_split_rounds,
                  "Sweeps of the stitch's obtuse splits (longest edge split at the altitude's foot; default 2; "
                  "0 = off; docs/stitch.md \"Obtuse splits\")");
  cmd->add_option("--obtuse-split-feature-angle", args->base.stitch.obtuse_split_feature_angle_deg,
                  "The obtuse splits' angle floor (deg) beside a feature node when the split takes an obtuse angle "
                  "off a node that never moves (default 20; 27.5 or more = the usual floor; docs/surfmesh.md "
                  "\"Cheese's hole walls, session 15\")");
  cmd->add_option("--angle-repair-rounds", args->base.stitch.angle_repair_rounds,
                  "Sweeps of the stitch's small-angle repair (flips and collapses at the triangles below 25 deg away "
                  "from features; default 12; 0 = off; docs/stitch.md \"Small angles left after the optimisation\")");
  cmd->add_option("--fidelity-distance", args->base.stitch.fidelity_distance_edges,
                  "The stitch's fidelity moves: vertices move onto the input where the output is farther from it "
                  "than this many input mean edges (default 0 = off; 0.25 recommended for fidelity; not on label images; docs/stitch.md "
                  "\"Fidelity moves\")");
  cmd->add_option("--fidelity-gate", args->base.stitch.fidelity_gate_edges,
                  "The fidelity moves measure only around the input vertices their patch's fit misses by more than this "
                  "many input mean edges (>= 0; default 0 = everywhere; docs/stitch.md \"Fidelity moves, session 20\")");
  cmd->add_option("--fidelity-alpha-floor", args->base.stitch.fidelity_alpha_floor,
                  "The fidelity moves keep each triangle's alpha at min(its old alpha, this) (in [0, 1]; default 0; "
                  "docs/stitch.md \"Fidelity moves, session 16\")");
  cmd->add_option("--border-input-distance", args->base.segment.border_smoothing.max_input_distance,
                  "Smoothed border curves stay within this many mean curve edges of the input (>= 0; default "
                  "infinity = no bound; docs/segment.md \"Border curves near the input\")");
  cmd->add_option("--corner-angle", args->base.surfmesh.corner_split_angle_deg,
                  "Patch corners wider than this (deg, in the surface metric) get a node on their bisector "
                  "instead of one closing triangle (in (0, 180]; default 89.5; 180 = off; docs/front2d.md "
                  "\"Corner rule\")");
  cmd->add_option("--flat-face-edges", args->base.surfmesh.fit.flat_face_edges,
                  "Input faces longer than this many mean edges lying in one plane with two neighbours are "
                  "sampled inside for the fit (default 1.5; 0 = off; not on marching-cubes inputs; "
                  "docs/surfmesh.md \"Flat faces beside a fillet\")");
  cmd->add_option("--small-patch-offset", args->base.surfmesh.small_patch_node_offset_edges,
                  "Inner nodes of patches of fewer than 40 input faces stay within this many mean edges of "
                  "their faces (default 0.02; 0 = only the 1-edge bound of every patch; docs/surfmesh.md "
                  "\"Small patches keep their nodes on their faces\")");
  cmd->add_option("--polygon-offset", args->base.surfmesh.polygon_node_offset_edges,
                  "On inputs that are not marching-cubes surfaces (CAD meshes, scans), inner nodes stay within "
                  "this many mean edges of their patch's faces (default 0.05; 0 = only the 1-edge bound; "
                  "docs/surfmesh.md \"Sharp-edged inputs, session 16\")");
  cmd->add_option("--chord", args->base.surfmesh.sizing.chord_error, "Chord error for --adaptive (length units; default 0.05 x size)");
  cmd->add_option("--max-slope", args->base.segment.max_slope_deg, "Largest angle (deg) between a face normal and its patch axis (default 60)");
  cmd->add_option("--split-above", args->base.surfmesh.fit.split_above_edges,
                  "Split patches whose fit leaves their input by more than this many mean edges (default 4; 0 = never)");
  cmd->add_option("--crease", args->base.segment.crease_angle_deg, "Dihedral angle (deg) above which an edge is a crease (default 80)");
  cmd->add_option("--sharp-crease", args->base.segment.sharp_crease_angle_deg,
                  "Edges bending by at least this (deg) are creases where they form a clean line of at least 8 "
                  "edges between smooth sides, as a CAD mesh's shallow creases (default 15; 0 = off; "
                  "docs/segment.md \"Sharp creases\")");
  cmd->add_flag("--bevel-creases", args->bevel_creases,
                "Also make creases of the ~45 deg bends of bevelled (marching-cubes) sharp edges: closer to "
                "the input at box edges, more narrow patches (docs/segment.md)");
  cmd->add_option("--unsmoothed-crease-angle", args->base.surfmesh.unsmoothed_crease_angle_deg,
                  "Crease curves sharper than this (deg, 3-ring normals) keep the input's crease instead of "
                  "its smoothed curve (default 100; 0 = every crease: closer at bevelled edges, more obtuse "
                  "triangles; 180 = never; docs/surfmesh.md)");
  cmd->add_option("--chord-compensation", args->base.stitch.chord_compensation,
                  "Move the nodes along their normals by this times the chords' mean gap to the surface, so the "
                  "triangles do not lose volume over convex parts (in [0, 2]; default 1; 0 = off; docs/stitch.md)");
  cmd->add_option("--volume-compensation", args->base.stitch.volume_compensation,
                  "Then move them by this times the volume between each triangle and its patch's input faces, "
                  "measured along the patch axis (in [0, 2]; default 1; 0 = off; docs/stitch.md)");
  cmd->add_option("--volume-skip-within", args->base.stitch.volume_compensation_skip_within,
                  "No volume compensation where the closed output already encloses the input's volume within "
                  "this fraction of it (in [0, 0.05]; default 0 = always; 0.0005 skips it on DRAM 256's level set; "
                  "docs/stitch.md \"The volume compensation on level sets, session 15\")");
  cmd->add_option("--tiny-curve-merge", args->base.surfmesh.tiny_curve_merge_size,
                  "Merge the two corners of a one-edge border curve shorter than this many target edges "
                  "(default 0.3; 0 = never; not with a cell grid; docs/surfmesh.md)");
  cmd->add_option("--corner-cluster", args->base.surfmesh.corner_cluster_size,
                  "Merge corners joined by border curves shorter than this many target edges into one node "
                  "when they all lie within that distance of their mean (in [0, 1]; default 0 = never; "
                  "not with a cell grid; docs/surfmesh.md \"Corner clusters\")");
  cmd->add_flag("--no-crease-gap", args->no_crease_gap,
                "Keep --crease where a non-marching-cubes input's bends leave a gap below it (by default the "
                "crease angle drops to that gap, by at most 15 deg: a CAD mesh's 65-80 deg edges become creases; "
                "docs/segment.md \"Creases at a gap in the bends\")");
  cmd->add_flag("--smoothed-boundary", args->smoothed_boundary,
                "Place the border nodes of the input's boundary on its smoothed curve (rounds its corners; "
                "the default keeps the input's boundary polyline)");
  add_expert_options(*cmd, *args);
  cmd->add_option("--threads", args->threads, "Worker threads for every stage (default: all hardware threads for segmentation and patches, 2 for the stitch and checks)");
  cmd->add_option("--report", args->report, "Write the report as JSON");
  cmd->add_option("--vtk", args->vtk, "Write the output with per-face patch id and alpha (.vtk/.vtu)");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress display");
  cmd->callback([args] { run_remesh(*args); });
}

}  // namespace nurbsfront::cli
