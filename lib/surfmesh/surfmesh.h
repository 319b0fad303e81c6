// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Surface meshing of a segmented mesh: the third stage of the remeshing pipeline
//! (DESIGN.md, "Pipeline", surfmesh). Every border curve is discretised once; every patch
//! gets a fitted height field in its own frame and is meshed by the 2D advancing front in
//! its plane with the surface metric; new nodes are lifted onto the fitted surface.
//!
//! The output is a triangle soup with global node ids, ready for the stitch stage.
//!
//! INTERFACE DRAFT (lead, 2026-11-25): the shapes below are the contract between the
//! surfmesh and stitch/pipeline work. Names may be refined by whoever implements them, as
//! long as both sides agree.

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/mesh_types.h"
#include "nurbsfront/core/progress.h"
#include "nurbsfront/nurbs/frame.h"
#include "nurbsfront/nurbs/height_field.h"
#include "nurbsfront/segment/segment.h"

namespace nurbsfront {

//! The 3D target edge length field h(x) (DESIGN.md, "Sizing").
struct SizingOptions {
  //! Absolute uniform target edge length (length units); 0 = use relative_size. Default 0.
  double size = 0.0;
  //! Target edge length as a multiple of the input's mean edge length, used when size is
  //! 0. Default 1.5 (about the level of detail of a marching-cubes input).
  double relative_size = 1.5;
  //! Curvature-adaptive sizing: h = min(uniform h, sqrt(8 e / kappa_max)) with the chord
  //! error e below, from the fitted surfaces' principal curvatures at the input's vertices,
  //! at least min_size_fraction x h, limited by `gradation` along the input's edges and
  //! interpolated on its triangles; used for the borders and the 2D fronts. The patches are
  //! then fitted before the borders are discretised. Default false.
  bool adaptive = false;
  //! Chord error e for adaptive sizing (length units); 0 = 0.05 * uniform h. Default 0.
  double chord_error = 0.0;
  //! Smallest size adaptive sizing may ask for, as a fraction of the uniform h. Default 0.2.
  double min_size_fraction = 0.2;
  //! Feature sizing: a patch bounded mostly (>= half its perimeter) by feature curves (a CAD
  //! face between creases, a hole's wall) gets at most this x its width (2 area / perimeter)
  //! as its size at its input vertices, at least min_size_fraction x h, graded along the
  //! input's edges (`gradation`) and used for the borders and the 2D fronts: with the uniform
  //! h of the input's mean edge, a CAD input's narrow faces and small holes were one row of
  //! triangles of border nodes (pinion, rotor). Applied only where it helps (see
  //! feature_size_everywhere): not on a marching-cubes surface (its vertices on the edges of
  //! a regular axis lattice, its edges inside one cell: there the crease-bounded strips are
  //! voxel staircases, and the finer sizes made
  //! headsq and the occupancy DRAM cell worse), and not when the patches it would limit hold
  //! less than kFeatureSizingMinAreaShare (1%) of the input's area (a few thin organic parts:
  //! armadillo, fandisk, mech-holes-shark got slightly worse). 0 = off. Default 1
  //! (docs/surfmesh.md "Feature sizing").
  double feature_size = 1.0;
  //! Apply feature sizing (feature_size > 0) to every input, also marching-cubes surfaces and
  //! inputs where it limits less than 1% of the area. Default false.
  bool feature_size_everywhere = false;
  //! Gradation of feature sizing's sizes along the input's edges: h_v <= h_w + (this - 1)
  //! |x_v - x_w| (the `gradation` below stays for adaptive sizing and the fronts). A gentler
  //! rise than 1.5 from the narrow crease-bounded patches into their wide neighbours: cheese's
  //! hole walls (patches of 9-50 input faces) were squeezed at sizes rising 50% per unit
  //! length into the block's faces; at 1.25 obtuse 3.55 -> 2.78%, volume +0.52 -> +0.42%, at
  //! 6% more triangles, fewer obtuse triangles than a finer feature_size at the same count
  //! (docs/surfmesh.md "Feature sizing: a gentler gradation"). Must be > 1. Default 1.25.
  double feature_gradation = 1.25;
  //! Optional user sizing h(x) at world points (length units, finite, > 0); when set it
  //! replaces the uniform size (adaptive still applies on top). Called concurrently from
  //! the worker threads (border discretisation, patch fronts): it must be thread-safe and a
  //! pure function of the point, or the output depends on the thread count.
  std::function<double(const Eigen::Vector3d&)> callback;
  //! Gradation: |grad h| <= gradation - 1. Must be > 1. Default 1.5.
  double gradation = 1.5;
  //! Border look-ahead: where the sizes are not uniform (feature or adaptive sizing, a
  //! callback), a border curve is discretised with the smallest size within this fraction of
  //! its own size around each point (14 samples: the axes and the cube's diagonals), not the
  //! size on the curve alone. Where the sizes fall steeply into a patch (graded down from a
  //! narrow face nearby), border pieces as long as the size on the curve met a first row
  //! of triangles half as large: flat, obtuse triangles along the border (docs/surfmesh.md
  //! "Border look-ahead"). In [0, 2]; 0 = the size on the curve. Default 0.35.
  double border_lookahead = 0.35;
  //! \throw InvalidInput on nonsense.
  void validate() const;
};

//! Options of the per-patch fit (see FitOptions in nurbs/mba.h).
struct PatchFitOptions {
  //! Residual tolerance as a multiple of the input's mean edge length. Default 0.05.
  double relative_tolerance = 0.05;
  //! Finest lattice spacing as a multiple of the input's mean edge length, so the fit
  //! averages a staircase instead of chasing it (DESIGN.md, Pitfalls). Default 2.5.
  double min_spacing_edges = 2.5;
  //! Lattice levels at most. Default 10.
  int max_levels = 10;
  //! Conjugate-gradient iterations of the least-squares polish after MBA on the finest
  //! lattice (FitOptions::least_squares_iterations): MBA's passes leave a smoothing bias of
  //! about h^2 f'' / 6 where a patch curves away from its plane (measured: 0.17 voxel on
  //! the sphere at 128 cells, all of nurbsfront's Hausdorff there; 25-30 iterations give
  //! nearly all of the gain). 0 = plain MBA. Default 30.
  int least_squares_iterations = 30;
  //! BA passes on the finest lattice before the polish (FitOptions::final_passes), also in
  //! split_unfitted_patches' check fits. With the polish on they only move its start; the
  //! check fits run no polish, so at 0 they are plain MBA (their split decisions were not
  //! compared with the 8 passes' of session 18; corpus and scenes hold). In [0, 1000].
  //! Default 0.
  int final_passes = 0;
  //! Smoothing of a second polish for patches whose data the first one fits within
  //! fine_below_edges (FitOptions::least_squares_fine_smoothing): the first polish's
  //! smoothing (1e-3) holds the coefficients at the edge of the data near MBA's biased
  //! values, and the fit sags along the patch borders (level-set sphere at 256 cells: the
  //! whole Hausdorff, 4 times the quadric decimater's). Not applied with adaptive sizing
  //! (measured worse there, see docs/surfmesh.md). 0 = off. Default 1e-5.
  double least_squares_fine_smoothing = 1e-5;
  //! Largest residual after the first polish, in mean input edges, for the second polish:
  //! above it (folds, noise, detail under the lattice spacing) the stronger smoothing stays.
  //! Default 0.2.
  double fine_below_edges = 0.2;
  //! split_unfitted_patches(): a patch whose fit leaves one of its own input vertices by
  //! more than this many mean input edges (along its axis) is split by its normals
  //! (split_patches) and its parts refitted. 0 = never. Default 4 (level-set DRAM cell at
  //! 256: one patch over a word line, a bit line's side and a plug's base left its input by
  //! 23 mean edges; its front then meshed with a metric far from the input's).
  double split_above_edges = 4.0;
  //! Rounds of split_unfitted_patches() at most (each splits the parts still above the
  //! bound again). Default 3.
  int split_rounds = 3;
  //! Input faces whose longest edge is above this many mean input edges are also sampled
  //! inside (barycentric grid of about one mean edge), not only at their corners: long fan
  //! faces (filled holes of scans, CAD meshes) otherwise leave gaps where the fit bulges
  //! (bunny: up to one mean edge off). Plain fit only (not with cell_grid). 0 = off.
  //! Default 2 (marching-cubes surfaces have no such faces).
  double large_face_edges = 2.0;
  //! Input faces whose longest edge is above this many mean input edges and which lie in
  //! one plane with at least two of their three neighbours (normals within 1 deg) are
  //! sampled inside too (as large_face_edges): flat faces, whose chords are the surface
  //! itself. A CAD flat ring of faces 1.8 mean edges long between two circles beside a
  //! fillet (rotor) left its fit 0.43 mean edges out (volume +4.2%). Not on curved faces
  //! (points on chords pull a fit inwards: elephant, object.stl lost 0.2-0.7% volume with
  //! every face above 1.5 sampled), nor on marching-cubes surfaces (the lattice-edge gate of
  //! feature sizing). Plain fit only; 0 = off. Default 1.5.
  double flat_face_edges = 1.5;
  //! Detail fit (off when 0; refused with a cell grid): a patch whose plain fit misses
  //! one of its own points by more than detail_above_edges mean input edges is refitted with
  //! this finest lattice spacing (mean input edges, instead of min_spacing_edges); the refit
  //! is kept when its mean miss at the patch's own vertices is not larger, and that
  //! patch's new inner nodes are then kept within
  //! detail_node_offset_edges of its input faces along its axis (instead of
  //! SurfMeshOptions::max_node_offset_edges). For inputs with real detail of one or two mean
  //! edges (range scans, smoothed-image level sets: bunny, brain), with adaptive sizing at
  //! equal vertex count; the 2.5-edge lattice is there to average marching-cubes staircases,
  //! which the detail fit would follow (label images: liver Hausdorff 0.96 -> 1.86 with it;
  //! docs/surfmesh.md "Detail fit"): an input taken for a label image's staircase (half or
  //! more of its vertices at their lattice edge's midpoint) is not refitted
  //! (SurfaceMesh::detail_fit_skipped). 0 (off) or below min_spacing_edges. Default 0.
  double detail_spacing_edges = 0.0;
  //! See detail_spacing_edges (mean input edges, >= 0). Default 0.25.
  double detail_above_edges = 0.25;
  //! See detail_spacing_edges (mean input edges, > 0). Default 0.05.
  double detail_node_offset_edges = 0.05;
  void validate() const;
};

//! The lattice of a cell-based (0/1 occupancy) input: its cell centres are origin +
//! (i, j, k) .* spacing, and its marching-cubes vertices (iso 0.5) are midpoints of lattice
//! edges between an inside and an outside centre, so the true surface crosses each such edge
//! within half a cell of the vertex. For a grid made by sample_scene(..., Occupancy) or read
//! from a voxel file: {true, grid.origin, grid.spacing}.
struct CellGrid {
  //! Fit the patches to these bands (fit_height_field_to_bands) instead of fitting the
  //! vertices (fit_height_field), and project the border nodes onto the fits as with
  //! project_border_nodes. Default false: level-set and other inputs keep the plain fit.
  bool enabled = false;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  //!< a cell centre (world)
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones(); //!< cell size along x, y, z (> 0)
  //! Band-fit lattice spacing in cells (smallest spacing component). Default 1.5.
  double lattice_cells = 1.5;
  //! Band-fit smoothing length in cells (BandFitOptions::smoothing_length). Default 2.25.
  double smoothing_cells = 2.25;
  //! Band-fit curvature passes (BandFitOptions::curvature_passes). Default 1.
  int curvature_passes = 1;
  //! A patch whose band fit (with one ring of its neighbours' faces, as every fit) misses
  //! no band by more than wide_overlap_max_miss_cells is refitted with this many rings of
  //! its neighbours' faces (those facing its axis), which carry their curvature over a wide
  //! terrace of the patch. In [0, 20]; 0 or 1 disables. Default 5.
  int wide_overlap_rings = 5;
  //! See wide_overlap_rings, in cells (> 0). Default 0.3.
  double wide_overlap_max_miss_cells = 0.3;
  //! A patch whose band fit (one ring, after its curvature passes) still misses a band by
  //! more than this (cells) holds a sharp, bevelled edge that the smooth fit rounds off: it
  //! gets the plain fit of its vertices instead (as without a cell grid), and the border
  //! nodes of its curves are not projected onto the fits. Finite and >= 0; 0 disables.
  //! Default 0.5 (occupancy DRAM cell at 128: Hausdorff to the input 1.18 -> 0.91 voxel;
  //! the sphere and the torus from 48 cells up unchanged: 0.3 took the torus at 64 from 0.21
  //! to 0.42 voxel max; docs/surfmesh.md).
  double plain_fit_miss_cells = 0.5;
  //! A curved patch's smoothing length: this times sqrt(2 R) cells, R the median over (at most
  //! 256 of) the patch's vertices of the smallest radius of curvature (cells) of a
  //! least-squares quadric of the marching-cubes vertices within 4.5 cells, estimated before
  //! the band fit (sqrt(2 R) is how far the surface runs from its tangent plane before it
  //! leaves it by one cell: about a terrace's half-width), at most smoothing_cells; only for
  //! a curved patch: sqrt(2 R) at most 2.4 smoothing_cells (R <= 14.6 cells with the default
  //! 2.25), R not below 5 cells, and the upper quartile of the curvature at most 1.5 times
  //! the median (else a rounded sharp edge's curvature, not a surface's). The tube of the
  //! occupancy torus (radius 6 and 8 cells at 48 and 64) was flattened by 2.25 cells
  //! (docs/surfmesh.md, "Smoothing length of curved patches"). Flat patches and the sphere at
  //! 48 cells (radius 23) keep smoothing_cells. Finite and >= 0; 0 disables. Default 0.325
  //! (0.375 left the torus at 48 cells at 2.88 of the 3 of issue 5's mean bound at triangle
  //! centroids through the tool; docs/surfmesh.md, "Torus at 48 cells").
  double curved_smoothing = 0.325;
  void validate() const;
};

//! Options of mesh_surface().
struct SurfMeshOptions {
  //! Target edge lengths (uniform, adaptive, feature sizing); see SizingOptions.
  SizingOptions sizing;
  //! Per-patch fits (lattice spacing, polish, splits of unfitted patches); see PatchFitOptions.
  PatchFitOptions fit;
  //! Cell-based input: fit every patch to the band of each vertex (see CellGrid). Vertices
  //! not at the midpoint of a lattice edge are plain point samples. Default off.
  CellGrid cell_grid;
  //! Smoothing passes of the 2D front per patch (FrontOptions::smoothing_passes). Default 3.
  int smoothing_passes = 3;
  //! The front's corner rule (FrontOptions::corner_split_angle_deg): a front corner at a
  //! border node wider than this in the patch metric gets a node on its bisector instead of
  //! one closing triangle (a right corner closed by one triangle is 90.0001 deg on the
  //! surface: obtuse; border nodes never move).
  //! In (0, 180]; 180 = off. Default 89.5 (measured: docs/front2d.md "Corner rule").
  double corner_split_angle_deg = 89.5;
  //! Crease angle (deg) for SurfaceMesh::curve_is_feature. Pass the segmentation's
  //! SegmentOptions::crease_angle_deg. A curve is a crease when the angle between the mean
  //! normals of the faces within 3 rings on each side (median over its vertices) exceeds
  //! 0.75 x this angle (marching cubes bevels a 90 deg edge into steps below the crease
  //! angle, and the averaging lowers it), or when most of its input edges have a dihedral
  //! above this angle. In (0, 180]. Default 80 (the segment default).
  double crease_angle_deg = 80.0;
  //! Move every border node to the mean of its vertical projections onto the fitted
  //! surfaces of its curve's patches before meshing (by at most one mean input edge), so the
  //! border lies near both (DESIGN.md, Pitfalls). Corners move the same way onto all their
  //! patches' surfaces, except corners of a feature curve (crease or input boundary), which
  //! keep their input position. Default false (always on with cell_grid).
  bool project_border_nodes = false;
  //! Discretise the curves on the input's boundary from their input positions instead of
  //! the smoothed ones (BorderCurve::smoothed): the input's boundary is its geometry, and
  //! the smoothing (up to one mean edge) rounds its corners off (terrain_stl_data: Hausdorff
  //! 1.23 -> 0.28 mean input edges). Not with cell_grid. Default true.
  bool unsmoothed_boundary_curves = true;
  //! The same for the crease curves between two patches (SurfaceMesh::curve_is_feature) whose
  //! crease angle (angle between the mean normals of the faces within 3 rings on each side,
  //! median over the curve) exceeds this (deg): the smoothing moves them off the sharp
  //! edge they follow, and the output then cuts the edge by up to one mean edge. At 100 only
  //! sharp folds qualify (headsq@500 Hausdorff 2.77 -> 2.16, obtuse share unchanged); lower
  //! values take the bevelled box edges of marching cubes too, whose border nodes then follow
  //! the zig-zag (every crease, 0: DRAM 128 0.0242 -> 0.0212 but obtuse 0.62 -> 0.96%, trench
  //! obtuse 0.23 -> 0.45%; docs/surfmesh.md). 180 = never. Not with cell_grid. In [0, 180].
  //! Default 100.
  double unsmoothed_crease_angle_deg = 100.0;
  //! Two corners joined by a curve of one input edge shorter than this many local target
  //! sizes become one node (at their middle) before the patches are meshed, unless the
  //! curves around them then cross in a patch plane: marching cubes makes such edges where
  //! the iso-surface passes near a grid vertex, and both patches' fronts would grade from
  //! that piece up to the target size (docs/surfmesh.md, "Tiny corner curves"). Corners on
  //! the input's boundary never merge; nothing merges with a cell grid (occupancy inputs).
  //! 0 disables. In [0, 0.5]. Default 0.3.
  double tiny_curve_merge_size = 0.3;
  //! Corners joined by curves shorter (along their input vertices) than this many local target
  //! sizes form a cluster; a cluster whose corners all lie within this many sizes of their mean
  //! becomes one node there before the patches are meshed (its curves vanish), unless a curve
  //! between two of its corners is longer, a patch would lose its last open curve or pass the
  //! node twice, a corner is on the input's boundary, or the curves around it then cross in a
  //! patch plane: marching cubes puts three or more corners a fraction of h apart at voxel-sized
  //! spikes and fin ends, and the fronts around them grade down to that size (docs/surfmesh.md,
  //! "Corner clusters"). Nothing merges with a cell grid. 0 disables. In [0, 1]. Default 0 (off).
  double corner_cluster_size = 0.0;
  //! Fin rims (docs/stitch.md "Fin rims"): on marching-cubes surfaces (the lattice gate) that
  //! are not a label image's staircase, a crease curve between two patches one of which is a
  //! strip narrower than this many target sizes next to a wide patch (segment's
  //! narrow_patches: width 2 x area / border length) and whose crease angle (curve_crease_angles,
  //! 3 rings) is at most fin_rim_max_angle_deg is no feature for stitch
  //! (SurfaceMesh::curve_is_feature 0, counted in SurfaceMesh::n_fin_rim_curves): its nodes
  //! and those of the strip may then be smoothed, repaired, split and collapsed on the fits of
  //! both sides. The patches are discretised and meshed as before (the curves' sources and
  //! sizes do not change). One-voxel fins of CT bone give strips between two creases that no
  //! triangle of the target size fits (most of headsq's obtuse triangles). 0 = off; >= 0.
  //! Default 1.
  double fin_rim_width = 1.0;
  //! The largest crease angle (deg) of a fin rim curve (fin_rim_width): sharper folds stay
  //! features. In [0, 180]. Default 120 (180 with StitchOptions::fin_rim_max_move 0.25 and
  //! fin_rim_max_gap_edges infinity: fewer obtuse triangles on headsq, but more below 25 deg
  //! away from features; docs/stitch.md "Fin rims: a bound on the moves").
  double fin_rim_max_angle_deg = 120.0;
  //! A fin rim curve's nodes have their projections onto both patches' fits within this many
  //! mean input edges of each other, and their mean within it of the node; infinity: no test.
  //! With a finite StitchOptions::fin_rim_max_move the test can be dropped (docs/stitch.md
  //! "Fin rims: a bound on the moves"). >= 0. Default 0.25.
  double fin_rim_max_gap_edges = 0.25;
  //! Largest distance, in mean input edges, of a new inner node from the patch's own input
  //! faces along the patch axis: a node the fit lifts further (the fit smooths thin fins,
  //! tips and sharp bends by several edges, and such a node can pass through the
  //! neighbouring sheet) is moved back to this distance. 0 disables. Default 1.
  double max_node_offset_edges = 1.0;
  //! The same bound for the inner nodes of a patch of fewer than 40 input faces (those fit
  //! their own vertices only, without the ring of their neighbours' faces): such a fit is
  //! held by a few vertices and is free between them, and the nodes of a small patch of long
  //! faces on a curved wall sat up to 0.7 mean edges off its faces (CGAL cheese: +4.3%
  //! volume; docs/surfmesh.md, "Small patches keep their nodes on their faces"). Not for
  //! band-fitted patches (cell_grid), nor on marching-cubes surfaces (the lattice-edge gate;
  //! with the fin rims of headsq@1150 unlocked it doubled the Hausdorff distance there).
  //! 0 = only max_node_offset_edges. Default 0.02.
  double small_patch_node_offset_edges = 0.02;
  //! The same bound for the inner nodes of every plain-fitted patch of an input that the
  //! marching-cubes lattice gate does not take (CAD meshes, scans): their vertices are the
  //! geometry, and a smooth fit rounds the sharp edges below the crease angle that a patch
  //! holds (fandisk's fading creases: the fit misses its own vertices by 0.36 target sizes, and
  //! with more vertices the Hausdorff distance grew, 0.0051 at 2 687 vertices, 0.0078 at 10 656;
  //! docs/surfmesh.md "Sharp-edged inputs, session 16"). Not on marching-cubes surfaces (their
  //! fits smooth the staircase), not for band fits; a detail-fitted patch keeps the smaller of
  //! this and PatchFitOptions::detail_node_offset_edges. 0 = only max_node_offset_edges; >= 0.
  //! Default 0.05.
  double polygon_node_offset_edges = 0.05;
  //! Worker threads for the patches; 0 = all hardware threads. The output is bit-identical
  //! for every thread count. Default 0.
  int threads = 0;
  //! Progress and cancellation (stages "surfmesh: borders", "surfmesh: patches"). Always
  //! called from the thread that called mesh_surface(). Default none.
  ProgressCallback progress;
  void validate() const;
};

//! A patch's input faces as heights over its plane (surfmesh internal).
struct PatchInputHeights;

//! A patch's smooth surface: a height field z = f(x, y) in the patch's frame.
struct PatchSurface {
  PatchFrame frame;           //!< local z = patch axis
  BicubicHeightField field;   //!< z = f(x, y) in frame coordinates
  //! When set (SurfMeshOptions::max_node_offset_edges > 0): the patch's input faces, and
  //! project() keeps its result within max_offset of them along the axis.
  std::shared_ptr<const PatchInputHeights> input_heights;
  double max_offset = 0.0;
  //! Vertical projection of a world point onto the surface (along the frame's z axis),
  //! clamped to max_offset from the input faces above or below it (if any, and if set).
  [[nodiscard]] Eigen::Vector3d project(const Eigen::Vector3d& world) const;
  //! Unit surface normal (world coordinates) at the vertical projection of a world point.
  [[nodiscard]] Eigen::Vector3d normal(const Eigen::Vector3d& world) const;
};

//! What happened to one patch.
enum class PatchStatus {
  Ok,          //!< fitted and meshed
  FitFailed,   //!< the fit threw (message says why)
  MeshFailed,  //!< the 2D front threw or left the front open (message says why)
};

struct PatchMeshReport {
  PatchStatus status = PatchStatus::Ok;
  std::string message;           //!< empty when Ok
  std::size_t n_input_faces = 0;
  std::size_t n_border_nodes = 0;
  std::size_t n_inner_nodes = 0;
  std::size_t n_triangles = 0;
  double fit_max_residual = 0.0; //!< at the patch's input vertices
  int fit_levels = 0;
  bool detail_fit = false;         //!< refitted on the detail lattice (PatchFitOptions::detail_spacing_edges)
  std::size_t n_clamped_nodes = 0; //!< inner nodes moved back (max_node_offset_edges)
  double seconds = 0.0;
};

//! Kind of a global node.
enum class NodeKind : std::uint8_t {
  Corner,  //!< an input corner (end of border curves): never moves
  Border,  //!< on a border curve (between two patches or on the input's boundary)
  Inner,   //!< inside one patch, on its fitted surface
};

//! The meshed patches with global node ids.
struct SurfaceMesh {
  //! Global nodes: border nodes (corners included) first, then the inner nodes patch by
  //! patch. A corner merged into another (SurfMeshOptions::tiny_curve_merge_size) stays a
  //! node that no curve and no triangle uses.
  std::vector<Eigen::Vector3d> nodes;
  std::vector<NodeKind> node_kind;
  //! Patch of an inner node; the curve id of a border node; -1 for a corner.
  std::vector<int> node_owner;
  std::size_t n_border_nodes = 0;
  //! Triangles by global node id, oriented like the input faces (normal on the same side).
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> triangle_patch;      //!< patch of each triangle
  std::vector<PatchSurface> surfaces;   //!< one per patch
  //! Per curve: true when the curve is a crease (see SurfMeshOptions::crease_angle_deg) or
  //! on the input's boundary; stitch never flips across or smooths such curves.
  std::vector<std::uint8_t> curve_is_feature;
  //! Crease curves that are no feature because they border a fin's narrow strip
  //! (SurfMeshOptions::fin_rim_width).
  std::size_t n_fin_rim_curves = 0;
  //! Per curve, 1 for those fin rim curves (else 0; may be empty: none). Stitch keeps their
  //! nodes within StitchOptions::fin_rim_max_move of where the front put them.
  std::vector<std::uint8_t> curve_is_fin_rim;
  //! Per curve, its global node ids along the curve (an open curve starts and ends at its
  //! corners; a closed one does not repeat its first node; a tiny curve whose corners
  //! merged is {survivor, survivor}). May be empty (a hand-made SurfaceMesh): stitch then
  //! counts every corner as a feature corner.
  std::vector<std::vector<int>> curve_nodes;
  std::vector<PatchMeshReport> patches; //!< one per patch
  //! Patch of every input face (the segmentation's face_patch; empty in a hand-made
  //! SurfaceMesh, and in remesh()'s without a fidelity gate): the stitch's fidelity gate
  //! (StitchOptions::fidelity_gate_edges), its one reader.
  std::vector<int> input_face_patch;
  double target_size = 0.0;             //!< the resolved uniform target edge length
  double input_mean_edge = 0.0;         //!< mean edge length of the input
  //! Chords (edges between two border nodes that are not a border segment) that two patches
  //! (or a patch and a border curve) both had, split in the later patch, plus triangles of
  //! three border nodes that two patches both had, given a centre node.
  std::size_t n_shared_chords_resolved = 0;
  //! True when feature sizing (SizingOptions::feature_size) set the sizes: the option is on,
  //! the input is not taken for a marching-cubes surface (or feature_size_everywhere), and
  //! the width-limited patches hold enough of the area for a size below the uniform one.
  bool feature_sizing_applied = false;
  //! The detail fit was asked for (PatchFitOptions::detail_spacing_edges) but not run: the
  //! input is taken for a label image's marching-cubes staircase (docs/surfmesh.md "Detail
  //! fit: where it runs").
  bool detail_fit_skipped = false;
  //! Whether the input is taken for a label image's marching-cubes staircase
  //! (surfmesh_detail::label_image_staircase), when mesh_surface() tested it (empty: not
  //! tested); the stitch's fidelity moves read it instead of testing the input again.
  std::optional<bool> input_label_staircase;
};

//! Splits the patches whose fitted surface does not represent their input: every patch is
//! fitted as mesh_surface() would (without the border nodes in its rectangle, as with
//! adaptive sizing), and those whose fit leaves one of their own input vertices by more than
//! options.fit.split_above_edges mean input edges along the axis are split by
//! split_patches(); the new parts are checked again, up to options.fit.split_rounds rounds.
//! The border curves are rebuilt from the new patches (segment's guarantees hold, see
//! split_patches). Returns the segmentation unchanged when nothing is above the bound.
//! \param n_split  if set, receives the number of patches the splits added (over all rounds)
//! \throw InvalidInput for invalid options or a segmentation that does not match the mesh.
//! \throw Cancelled if the progress callback returns false.
[[nodiscard]] Segmentation split_unfitted_patches(const TriMesh& input, const Segmentation& segmentation,
                                                  const SurfMeshOptions& options,
                                                  const SegmentOptions& segment_options,
                                                  std::size_t* n_split = nullptr);

//! Discretises the border curves, fits and meshes every patch.
//! \throw InvalidInput for invalid options or a segmentation that does not match the mesh.
//! \throw Cancelled if the progress callback returns false.
//! Patch failures do not throw: they are reported per patch (status != Ok) and the
//! patch's triangles are missing from the output.
[[nodiscard]] SurfaceMesh mesh_surface(const TriMesh& input, const Segmentation& segmentation,
                                       const SurfMeshOptions& options = {});

}  // namespace nurbsfront
