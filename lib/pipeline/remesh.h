// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! The remeshing pipeline, the library's main entry point (DESIGN.md, "Pipeline"):
//! segment -> surfmesh (border discretisation, fit, 2D front per patch) -> stitch ->
//! report (quality of the output and its distance to the input).

#include <cstddef>
#include <string>
#include <vector>

#include "nurbsfront/core/mesh_types.h"
#include "nurbsfront/core/progress.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/segment/segment.h"
#include "nurbsfront/stitch/stitch.h"
#include "nurbsfront/surfmesh/surfmesh.h"

namespace nurbsfront {

//! Options of remesh(): one sub-struct per stage.
struct RemeshOptions {
  //! Segmentation into slope-bounded patches (max slope, crease angle, ...); sharp creases
  //! on from kRemeshSharpCreaseAngleDeg (off on marching-cubes inputs and with a cell grid).
  SegmentOptions segment = [] {
    SegmentOptions o;
    o.sharp_crease_angle_deg = kRemeshSharpCreaseAngleDeg;
    return o;
  }();
  //! Sizing, fit and per-patch meshing (target edge length, threads, ...).
  //! surfmesh.crease_angle_deg is replaced by segment.crease_angle_deg.
  SurfMeshOptions surfmesh;
  //! Assembly, cross-border optimisation and verification.
  StitchOptions stitch;
  //! Rounds of the last resort against crossings stitching left (docs/segment.md,
  //! "Re-segmenting crossing patches"): the patches of the crossing pairs are merged into a
  //! neighbour or bisected and the surface meshed and stitched again, kept only when it
  //! crosses less. Runs without crossings never pay it. 0 = off. Default 4.
  int crossing_repair_rounds = 4;
  //! On marching-cubes inputs (surfmesh's lattice gate), patches narrower than this many
  //! target edges (width 2 x area / border length, segment's narrow_patches) join a neighbour
  //! after segmentation, across creases, where the union meets the slope bounds and projects
  //! simply (merge_patches_into_neighbours): one-voxel fins and strips otherwise become
  //! patches of a few triangles, most of them obtuse (docs/segment.md "Narrow patches").
  //! 0 = off. Default 0.5.
  double narrow_patch_merge = 0.5;
  //! On marching-cubes inputs (not a label image's staircase), after the narrow merge, patches
  //! still narrower than this many target edges next to a wider one (a thin fin's rim between
  //! its two creases, a lens a fraction of h wide) join the neighbour sharing the longest
  //! border that is not so narrow itself, their own faces exempt from the slope bounds (the
  //! neighbour's keep them; the union passes the projection and cliff checks): the fin's two
  //! rims become one border curve. Counted in RemeshReport::n_narrow_merged. In [0, 1];
  //! 0 = off. Default 0.25, with the corner guard below (headsq@500 obtuse 2.21 -> 2.00%,
  //! @1150 4.43 -> 4.22%, Hausdorff kept; docs/segment.md "Fin strips, session 18" and
  //! "Fin strips: a corner guard, session 19").
  double fin_strip_width = 0.25;
  //! The corner guard of that merge: a strip joins a neighbour only if at most this many of
  //! its vertices where 3+ sides meet (patches, or the input's boundary as one) are left with
  //! two: a fin's tip is pinned by its corners, and without them the output cut headsq@1150's
  //! tips off by up to 1.14 mean edges (docs/segment.md "Fin strips: a corner guard, session
  //! 19"). -1 = no guard; >= -1. Default 1 (pinned tips, below, were measured with 0).
  int fin_strip_max_lost_corners = 1;
  //! With the guard (fin_strip_max_lost_corners >= 0, else refused), > 0: a strip's corner that its join leaves with two sides does not count
  //! against fin_strip_max_lost_corners (only those left inside the union do), and stays a
  //! corner (a curve end, so a node on the input: the fin's tip pinned) where the border
  //! turns there: the angle at it between the border vertices two input edges away on both
  //! sides below this (deg; 180 = every such corner). In [0, 180]; 0 = off (then such a
  //! corner counts). Default 0 (opt-in: with the guard at 0 and 120 here, headsq@500 obtuse
  //! 1.86 -> 1.75%, @1150 4.01 -> 3.86%, Hausdorff kept, but brain 6 -> 9 obtuse triangles;
  //! docs/segment.md "Fin strips: pinned tips, session 20").
  double fin_strip_pin_angle_deg = 0.0;
  //! On inputs not taken for marching cubes (nor with a cell grid), patches of at most this
  //! many input faces whose every border edge with another patch bends by at most
  //! tiny_patch_max_dihedral_deg (segment's tiny_patches) join a neighbour after segmentation,
  //! across those marginal creases, where the union meets the slope bounds and projects
  //! simply: a coarse mesh's bends (femur) otherwise cut patches of 1-8 faces, meshed with a
  //! few triangles, half of them obtuse (docs/segment.md "Tiny patches behind marginal
  //! creases"). 0 = off. Default 8.
  int tiny_patch_faces = 8;
  //! The largest bend (deg, between face normals) of a tiny patch's border for that merge:
  //! in [0, 180]. Default 120 (the crease angle + 40; femur 5.48% obtuse at 100, 4.90% at
  //! 120, 4.81% at 140).
  double tiny_patch_max_dihedral_deg = 120.0;
  //! On inputs not taken for marching cubes (nor with a cell grid), after the tiny merge,
  //! patches narrower than this many target edges (width 2 x area / border length,
  //! segment's narrow_patches) that face away from every neighbour (some face's raw normal
  //! outside each neighbour's slope cone) join the neighbour sharing the longest border that
  //! is not so narrow itself, their own faces exempt from the slope bounds (the neighbour's
  //! keep them; the union passes the projection and cliff checks): a coarse mesh's strips
  //! folded back between two creases, whose two border curves nearly meet, otherwise become
  //! hairline patches whose triangles are mostly obtuse (femur 2.90 -> 2.65% obtuse at 0.05,
  //! 2.53% at 0.1; docs/segment.md "Hairline patches"). 0 = off. Default 0.05.
  double hairline_patch_width = 0.05;
  //! On inputs not taken for marching cubes (nor with a cell grid), after the hairline merge,
  //! every patch narrower than this many target edges next to a wider one joins the
  //! neighbour sharing the longest border that is not so narrow itself, facing it or not:
  //! its own faces are exempt from the slope cone but keep the raw orientation floor (raw
  //! normal . axis >= kSegmentMinRawNormalDot, no face folded over the union's plane); the
  //! neighbour's faces keep the bounds and the union passes the projection and cliff checks.
  //! Opt-in: femur 2.25 -> 1.87% obtuse at 0.3, but cheese, couplingdown, elephant, turbine
  //! and fandisk get worse (docs/segment.md "Narrow patches of CAD-like meshes, session 17").
  //! Counted in RemeshReport::n_narrow_merged. 0 = off (default).
  double narrow_cad_patch_width = 0.0;
  //! On inputs not taken for marching cubes (nor with a cell grid), after the merges above,
  //! every patch narrower than this many target edges next to a wider one takes rings of
  //! faces from its wider neighbours across their slope-bounded (non-crease) borders, where
  //! those faces meet the slope bounds for its axis, until it is this wide; the neighbours
  //! stay connected and this wide, the patch passes the projection and cliff checks and
  //! the neighbours the projection check, no axis
  //! changes (segment's widen_patches; docs/segment.md "Widening narrow patches, session 18").
  //! Crease-bounded strips are not touched. Opt-in: femur 2.10 -> 1.89% obtuse at 0.2, but
  //! armadillo 0.225 -> 0.258%. Counted in RemeshReport::n_narrow_widened. 0 = off (default).
  double narrow_widen_width = 0.0;
  //! On inputs not taken for marching cubes (nor with a cell grid), the crease angle
  //! (segment.crease_angle_deg, also surfmesh's) drops to segment's gap_crease_angle() where
  //! the input's bends leave a gap below it: a CAD mesh's machined edges at 65-80 deg become
  //! creases (cheese.off: obtuse 6.66 -> 4.06%; docs/segment.md "Creases at a gap in the
  //! bends"). Default true.
  bool crease_gap = true;
  //! Measure the two-sided distance of the output to the input (Hausdorff, mean,
  //! relative volume change) into the report. Default true.
  bool compute_distances = true;
  //! Options of that measurement (sample spacing, threads); see DistanceOptions.
  DistanceOptions distance;
  //! Progress and cancellation for the whole run. When set, it receives every stage's
  //! progress (stages "segment", "surfmesh: ...", "stitch: ...", "distance"); a stage's own
  //! callback, if set too, is called as well. Returning false cancels (Cancelled). Default none.
  ProgressCallback progress;
  //! The same thread count for every stage (segmentation, surfmesh workers, checks, distances); n >= 1.
  void set_threads(unsigned n);
  //! \throw InvalidInput if any stage's options are invalid.
  void validate() const;
};

//! Counts and timings of a run, the per-patch status, the output's quality and distances.
struct RemeshReport {
  std::size_t n_input_vertices = 0;
  std::size_t n_input_faces = 0;
  std::size_t n_patches = 0;
  //! Patches added by splitting patches whose fit leaves their input (split_unfitted_patches;
  //! included in n_patches; its time is in seconds_surfmesh).
  std::size_t n_patches_split = 0;
  std::size_t n_curves = 0;
  std::size_t n_corners = 0;
  //! The crease angle (deg) the segmentation used: segment.crease_angle_deg, or lower where
  //! RemeshOptions::crease_gap found a gap in the input's bends.
  double crease_angle_deg = 0.0;
  //! Input edges the segmentation made creases (Segmentation::n_crease_edges).
  std::size_t n_crease_edges = 0;
  std::size_t n_nodes = 0;        //!< nodes of the surface mesh (before stitching)
  std::size_t n_triangles = 0;    //!< triangles of the output
  std::size_t n_failed_patches = 0;  //!< patches whose status is not Ok
  //! Rounds of the last resort against crossings stitching left that were kept (at most one
  //! remedy per round: a patch of a crossing pair joined a neighbour or was bisected, the
  //! surface meshed and stitched again; RemeshOptions::crossing_repair_rounds; 0 on a run
  //! without crossings).
  std::size_t n_crossing_repairs = 0;
  //! Narrow patches joined to a neighbour after segmentation (RemeshOptions::narrow_patch_merge).
  std::size_t n_narrow_merged = 0;
  //! Tiny patches joined to a neighbour after segmentation (RemeshOptions::tiny_patch_faces).
  std::size_t n_tiny_merged = 0;
  //! Hairline patches joined to a neighbour after segmentation (RemeshOptions::hairline_patch_width).
  std::size_t n_hairline_merged = 0;
  //! Narrow patches widened into their neighbours (RemeshOptions::narrow_widen_width).
  std::size_t n_narrow_widened = 0;
  //! Crease curves along fins' narrow strips that stitch did not treat as features
  //! (SurfaceMesh::n_fin_rim_curves, SurfMeshOptions::fin_rim_width).
  std::size_t n_fin_rim_curves = 0;
  //! Feature sizing set the sizes (SurfaceMesh::feature_sizing_applied): false on inputs
  //! taken for marching-cubes surfaces and where no crease-bounded patch is narrow enough.
  bool feature_sizing_applied = false;
  //! The detail fit was asked for but the input was taken for a label image's staircase
  //! (SurfaceMesh::detail_fit_skipped).
  bool detail_fit_skipped = false;
  double target_size = 0.0;       //!< resolved uniform target edge length (length units)
  double input_mean_edge = 0.0;   //!< mean edge length of the input
  double seconds_segment = 0.0;
  double seconds_surfmesh = 0.0;
  double seconds_stitch = 0.0;
  double seconds_distance = 0.0;
  double seconds_total = 0.0;
  std::vector<PatchMeshReport> patches;  //!< one per patch (SurfaceMesh::patches)
  //! The stitch stage's counts (flips, moves, rejected triangles, components).
  StitchReport stitch;
  //! Topology and quality of the output, and (compute_distances) its distance to the
  //! input. (stitch.output holds the same report without the distance.)
  MeshReport output;
  //! Contract violations and failed patches, one line each.
  std::vector<std::string> errors;
  [[nodiscard]] bool ok() const { return errors.empty(); }
};

//! The remeshed surface, the patch of each of its faces, and the report.
struct RemeshResult {
  TriMesh mesh;
  std::vector<int> face_patch;
  RemeshReport report;
};

//! Remeshes a triangle surface (DESIGN.md, "Pipeline"): segment(), mesh_surface(),
//! stitch() against the input, then the output's quality and distance report.
//! Contract violations of the output and failed patches are errors in the report
//! (RemeshReport::ok() is false), never exceptions.
//! \param input a 2-manifold triangle mesh (open or closed, any number of components),
//!        without deleted elements; weld and clean it first (io's clean()).
//! \throw InvalidInput for invalid options, an empty mesh, non-finite coordinates, deleted
//!        elements or non-manifold vertices (the message names the problem).
//! \throw Cancelled if a progress callback returns false.
[[nodiscard]] RemeshResult remesh(const TriMesh& input, const RemeshOptions& options = {});

//! remesh() at a given output vertex count (issue 6 compares at equal vertex count, and a
//! decimater may stop above ours): the uniform target size is chosen from the count. The
//! first run uses options as given (its sizing.size, or relative_size); the second scales the
//! size by sqrt(vertices / target_vertices) (the vertex count of a surface meshed at a uniform
//! size h goes as 1 / h^2), later ones by (vertices / target_vertices)^(1 / p) with p measured
//! from the last two runs (in [0.5, 3]; about 1 with adaptive sizing), the size changing by
//! at most a factor 3 per run. Stops when the kept run is within relative_tolerance of the
//! target, or after max_runs runs, and returns the run closest to the target among those
//! whose report has no error (among all runs if none is clean; the first of equals). Every run is a full remesh() (with distances if options.compute_distances), so
//! a good first size (options.surfmesh.sizing.size) saves runs. Adaptive sizing and a
//! sizing callback keep their shape: the uniform size they start from is what is scaled
//! (a callback's sizes are not: it throws for a callback).
//! \throw InvalidInput for target_vertices < 4, relative_tolerance not in [0, 1), max_runs
//!        < 1, a sizing callback, or whatever remesh() throws.
[[nodiscard]] RemeshResult remesh_to_vertex_count(const TriMesh& input, std::size_t target_vertices,
                                                  RemeshOptions options, double relative_tolerance = 0.005,
                                                  int max_runs = 4);

//! JSON object: counts, seconds, patches (status counts and the failed ones), stitch,
//! output (the quality module's MeshReport JSON), errors.
[[nodiscard]] std::string to_json(const RemeshReport& report);

//! A short human-readable summary (a few lines).
[[nodiscard]] std::string to_summary(const RemeshReport& report);

//! Name of a patch status ("ok", "fit_failed", "mesh_failed").
[[nodiscard]] const char* to_string(PatchStatus status);

}  // namespace nurbsfront
