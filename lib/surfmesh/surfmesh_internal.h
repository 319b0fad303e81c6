// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal to the surfmesh module: border discretisation and per-patch work shared by its
// .cpp files (not installed API).

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/polygon.h"
#include "nurbsfront/nurbs/band_fit.h"
#include "nurbsfront/nurbs/mba.h"
#include "nurbsfront/segment/segment_internal.h"
#include "nurbsfront/surfmesh/surfmesh.h"

namespace nurbsfront {

//! A patch's input faces in its frame, bucketed in a uniform grid over the plane.
struct PatchInputHeights {
  PatchInputHeights(const TriMesh& mesh, const std::vector<int>& faces, const PatchFrame& frame);
  //! Height z (frame coordinates) of the face straight above or below (x, y); false when
  //! no face is there.
  [[nodiscard]] bool height(double x, double y, double& z) const;

 private:
  [[nodiscard]] int column_of(double x) const;
  [[nodiscard]] int row_of(double y) const;
  // A face in the frame as height() reads it: its first corner, the edge vectors from it to
  // the other two, the cross product of those (twice the signed area in the plane), and its
  // corners' heights. The differences are those height() computed per candidate, so the same
  // doubles.
  struct Face {
    double x0, y0;
    double ex1, ey1;  // corner 1 - corner 0
    double ex2, ey2;  // corner 2 - corner 0
    double area;      // ex1 ey2 - ey1 ex2
    double z0, z1, z2;
  };
  std::vector<Face> faces_;
  // Faces per grid cell, compressed: cell k holds cell_faces_[cell_start_[k] .. cell_start_[k + 1]),
  // in increasing face order; faces of zero (or NaN) area are left out (height() skips them).
  std::vector<std::size_t> cell_start_;
  std::vector<int> cell_faces_;
  Eigen::Vector2d lo_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d extent_ = Eigen::Vector2d::Ones();
  int nx_ = 1;
  int ny_ = 1;
};

}  // namespace nurbsfront

namespace nurbsfront::surfmesh_detail {

//! The median of values (the upper one of an even count; values reordered, not empty).
inline double median_of(std::vector<double>& values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

//! Target 3D edge length at a world point.
using SizeAt = std::function<double(const Eigen::Vector3d&)>;


//! Throws InvalidInput when the segmentation does not describe `mesh` (sizes, ids, curve
//! edges that do not join their vertices, curve ends that are not corners).
void validate_segmentation(const TriMesh& mesh, const Segmentation& segmentation);

//! The discretised border curves.
struct BorderNodes {
  std::vector<Eigen::Vector3d> positions;  //!< corners first (in Segmentation::corners order)
  std::vector<NodeKind> kind;
  std::vector<int> owner;                  //!< curve id, -1 for a corner
  //! Per curve, its global node ids along the curve; an open curve starts and ends at its
  //! corners, a closed one does not repeat its first node.
  std::vector<std::vector<int>> curve_nodes;
};

//! What a curve's nodes are taken from.
enum class CurveSource : std::uint8_t {
  Smoothed,       //!< the smoothed polyline, resampled (default)
  Input,          //!< the input positions of its vertices, resampled
  InputVertices,  //!< its input vertices themselves (the segmentation guarantees that
                  //!< these never cross in a patch's plane)
};

//! Resamples every curve once, n segments of about size_at() each (closed curves and
//! curves from a corner to itself at least 3; an open curve sharing both ends with another
//! curve at least 2, so no patch gets a doubled segment), from the polyline `source` says
//! (one entry per curve). Short loops are resampled from their input positions, never
//! from the smoothed ones. `corner_target` (empty: none) merges corners (tiny_curve_merges):
//! a merged corner's curves end at its survivor, which sits at the middle of the two, and
//! the curve between them becomes the one degenerate piece {survivor, survivor}.
//! The curves are resampled on `threads` threads (size_at is called from them; the nodes
//! are numbered in curve order afterwards: the same result for any count).
[[nodiscard]] BorderNodes discretise_borders(const TriMesh& mesh, const Segmentation& segmentation,
                                             const SizeAt& size_at, const std::vector<CurveSource>& source,
                                             const std::vector<int>& corner_target = {}, unsigned threads = 1);

//! Per corner (index into Segmentation::corners): the corner it merges into, itself when
//! none. Two corners merge when a curve of one input edge joins them, shorter than
//! `fraction` x size_at at its middle, no other curve joins the same two, neither is on the
//! input's boundary and neither merges with a third (the lower index survives). Without
//! this the 2D fronts of both patches grade from that piece up to the target size, a
//! cascade of tiny, often obtuse triangles (docs/surfmesh.md, "Tiny corner curves").
[[nodiscard]] std::vector<int> tiny_curve_merges(const TriMesh& mesh, const Segmentation& segmentation,
                                                 const SizeAt& size_at, double fraction);

//! `target` (tiny_curve_merges's, or empty: none) with corner clusters merged too: corners
//! joined (through any chain) by open curves shorter along their input vertices than
//! `fraction` x size_at at the middle of their ends, or by a merge of `target`, form a
//! cluster; every member of a cluster then merges into its lowest index when all members lie
//! within `fraction` x size_at of their mean (where discretise_borders puts the survivor),
//! none is on the input's boundary, every curve between two members is such a short curve
//! (all of them vanish), and every patch at the cluster keeps an open curve that does not
//! vanish and meets the survivor with two curve ends at most (its loop stays simple). A
//! cluster that fails keeps the merges of `target`.
[[nodiscard]] std::vector<int> corner_cluster_merges(const TriMesh& mesh, const Segmentation& segmentation,
                                                     const SizeAt& size_at, double fraction, std::vector<int> target);

//! Border of one patch as directed edges (domain on the left) between its border nodes.
struct PatchBorder {
  std::vector<int> nodes;                 //!< global ids, ascending
  std::vector<std::array<int, 2>> edges;  //!< local indices into nodes
  std::vector<int> edge_curve;            //!< the curve of each edge
};
[[nodiscard]] PatchBorder patch_border(const Segmentation& segmentation, int p, const BorderNodes& borders);

//! Curves (ascending ids) with a segment that meets a segment it shares no node with, or
//! overlaps a neighbouring one, in the plane of one of their patches (orthogonal to its
//! axis; exact predicates).
//! The patches are taken on `threads` workers (the same list for any count); so are those of
//! extra_outer_loop_curves and folded_border_curves.
[[nodiscard]] std::vector<int> crossing_curves(const Segmentation& segmentation, const BorderNodes& borders,
                                               unsigned threads = 1);

//! Closed curves (ascending ids) whose discretised loop turns the other way round (or has no
//! area) in the plane of one of their patches than their input vertices: a small hole loop
//! resampled into three or four nodes can flip, and the patch then has a second outer loop.
[[nodiscard]] std::vector<int> flipped_loops(const TriMesh& mesh, const Segmentation& segmentation, const BorderNodes& borders);

//! Per curve (deg): the median over its vertices (the interior ones of an open curve) of
//! the angle between the area-weighted mean normals of the faces within `rings`
//! edge-adjacent rings around the vertex on each side (starting in one patch, never entering
//! the other one, so a narrow bevel patch does not hide the faces beyond it); 180 for curves on
//! the input's boundary. Unlike the dihedral of single edges, this sees a crease that
//! marching cubes bevelled into steps below the crease angle. The curves are taken on
//! `threads` workers (the same angles for any count).
[[nodiscard]] std::vector<double> curve_crease_angles(const TriMesh& mesh, const Segmentation& segmentation, int rings,
                                                      unsigned threads = 1);

//! Whether most input edges of curve c are sharp crease edges of the segmentation
//! (Segmentation::sharp_crease_edges).
[[nodiscard]] bool is_sharp_crease_curve(const Segmentation& segmentation, int c);
//! Per curve: 1 for a sharp crease curve (is_sharp_crease_curve), else 0.
[[nodiscard]] std::vector<std::uint8_t> sharp_crease_curves(const Segmentation& segmentation);

//! Per curve: on the input's boundary, or its crease angle (curve_crease_angles, 3 rings)
//! is above 0.75 x the given angle, or most of its input edges have a dihedral above it, or
//! it is a sharp crease curve (sharp_crease_curves). `angles`, when given, receives those
//! crease angles. `threads`: curve_crease_angles's.
[[nodiscard]] std::vector<std::uint8_t> feature_curves(const TriMesh& mesh, const Segmentation& segmentation,
                                                       double crease_angle_deg, std::vector<double>* angles = nullptr,
                                                       unsigned threads = 1);

//! SurfMeshOptions::fin_rim_width: the feature curves (surface.curve_is_feature) between two
//! patches, one of which is in narrow_patches(mesh, segmentation, max_width), whose crease
//! angle (`angles`, per curve) is at most max_angle_deg and at each of whose nodes the
//! projections onto the two patches' surfaces, and their mean to the node, are at most max_gap
//! apart; ascending ids. narrow_patches' pass over the faces and edges runs on `threads`.
[[nodiscard]] std::vector<int> fin_rim_curves(const TriMesh& mesh, const Segmentation& segmentation,
                                              const SurfaceMesh& surface, const std::vector<double>& angles,
                                              double max_width, double max_angle_deg, double max_gap,
                                              unsigned threads = 1);

//! The band samples of points (world) in a patch frame: a point at the midpoint of a cell
//! lattice edge (one coordinate half-way between centres, the other two on centres) gets
//! that edge as its band, any other point is a plain point sample.
[[nodiscard]] std::vector<BandSample> cell_band_samples(const std::vector<Eigen::Vector3d>& world, const PatchFrame& frame,
                                                        const CellGrid& grid);

//! The band fit of a patch's points (world) in its frame over `domain` (frame coordinates),
//! from `start` if given, without the curvature passes if the fit before them misses no band
//! by more than skip_passes_max_miss (if >= 0; BandFitOptions).
[[nodiscard]] BandFitResult fit_cell_bands(const std::vector<Eigen::Vector3d>& world, const PatchFrame& frame,
                                           const CellGrid& grid, const Rectangle& domain,
                                           const BicubicHeightField* start = nullptr, double skip_passes_max_miss = -1.0);

//! Smallest radius of curvature (cells) that CellGrid::curved_smoothing takes for a curved
//! surface: below it the curvature is that of a rounded sharp edge (the bevels of the
//! occupancy trench and DRAM cell, 1-4 cells), and the patch keeps smoothing_cells.
inline constexpr double kMinCurvedRadiusCells = 5.0;
//! Largest ratio of the upper quartile to the median of a patch's curvature for which
//! CellGrid::curved_smoothing applies: the occupancy torus's patches 1.04-1.24 (48 cells), a
//! flat trench patch holding a rounded edge 2.1.
inline constexpr double kCurvedQuartileRatio = 1.5;

//! The band-fit smoothing length (cells) of patch p, chosen before its fit: grid.smoothing_cells,
//! or less on a curved patch (CellGrid::curved_smoothing), from the median over (at most 256 of)
//! its vertices of the largest |principal curvature| of a least-squares quadric of the
//! vertices within 4.5 cells (in the frame of their best plane; the patch's own vertices and
//! those of its neighbours' faces within 3 rings that face its axis).
[[nodiscard]] double curved_smoothing_cells(const TriMesh& mesh, const Segmentation& segmentation, int p, const CellGrid& grid);

//! One patch's result before global numbering.
struct PatchResult {
  PatchMeshReport report;
  PatchSurface surface;
  bool has_surface = false;
  //! The surface is a band fit (CellGrid), not a plain fit of the vertices.
  bool band_fit = false;
  //! New nodes on the surface (world coordinates).
  std::vector<Eigen::Vector3d> inner_nodes;
  //! Triangles: ids >= 0 are global border nodes, id < 0 is inner node -(id + 1).
  std::vector<std::array<int, 3>> triangles;
};

//! True for a patch of fewer than 40 input faces: its fit sees its own vertices only
//! (overlap_vertices adds no ring).
[[nodiscard]] bool fits_own_vertices_only(const Patch& patch);

//! The neighbours' vertices added to patch p's fit: those of the faces of other patches
//! within `rings` vertex rings of p's border (not counting its sharp crease curves,
//! is_sharp_crease_curve) that face its axis, not in p, ascending; none for a patch of fewer
//! than 40 input faces (it fits its own vertices only).
[[nodiscard]] std::vector<int> overlap_vertices(const TriMesh& mesh, const Segmentation& segmentation, int p, int rings = 1);

//! The positions of a patch's input vertices, in ascending vertex id order.
[[nodiscard]] std::vector<Eigen::Vector3d> patch_vertex_points(const TriMesh& mesh, const Patch& patch);

//! The plain fit's options (SurfMeshOptions::fit) for points whose (x, y) in the patch
//! frame span [lo, hi]: the rectangle grown by 2% of its diagonal + one mean edge, then to
//! whole lattice cells of the finest spacing (not with a cell grid, whose band fit has its
//! own lattice).
[[nodiscard]] FitOptions plain_fit_options(const SurfMeshOptions& options, double mean_edge, const Eigen::Vector2d& lo,
                                           const Eigen::Vector2d& hi);

//! Frame and fit of patch p (fills result.surface, has_surface, report fit fields or
//! FitFailed). Never throws except Cancelled-free internal errors caught by the caller.
void fit_patch(const TriMesh& mesh, const Segmentation& segmentation, int p, const BorderNodes& borders,
               const SurfMeshOptions& options, double mean_edge, PatchResult& result);

//! The 2D front of patch p in its plane and the lift of the new nodes (fills triangles,
//! inner_nodes, report mesh fields or MeshFailed). The front's size is uniform_size, or
//! size_at() at the lifted points when size_at is set (user callback, adaptive sizing):
//! sampled on a grid of about sizing_grid spacing over the fit's rectangle and interpolated
//! bilinearly when sizing_grid > 0, called directly otherwise.
void mesh_patch(const Segmentation& segmentation, int p, const BorderNodes& borders, const SurfMeshOptions& options,
                double uniform_size, const SizeAt& size_at, double sizing_grid, PatchResult& result);

//! Largest |principal curvature| of a patch surface at the vertical projection of a world
//! point (0 where it is not finite).
[[nodiscard]] double max_abs_curvature(const PatchSurface& surface, const Eigen::Vector3d& world);
//! The same for a height field at (x, y) (frame coordinates).
[[nodiscard]] double max_abs_curvature(const BicubicHeightField& field, double x, double y);

//! Curvature-adaptive sizing (SizingOptions::adaptive): at every input vertex
//! h = max(min(base(x), sqrt(8 chord_error / kappa_max)), min(min_size, base(x))), kappa_max
//! the largest |principal curvature| of the fitted surfaces of its patches (fits without a
//! surface are skipped), then limited along the input's edges by
//! h_v <= h_w + (gradation - 1) |x_v - x_w|; at a world point, interpolated on the nearest
//! input triangle. The returned function is thread-safe and deterministic.
[[nodiscard]] SizeAt adaptive_sizing(const TriMesh& mesh, const Segmentation& segmentation,
                                     const std::vector<PatchResult>& fits, const SizeAt& base, double chord_error,
                                     double min_size, double gradation);

//! Share of a patch's perimeter on feature curves above which feature_sizing limits its size.
inline constexpr double kFeatureSizingShare = 0.5;
//! Least share of the input's area in the patches whose width limits their size for
//! feature_sizing to apply (unless SizingOptions::feature_size_everywhere). Measured shares:
//! the CAD meshes it helps 2.7% (turbine) to 80% (pinion); armadillo 0.29%, fandisk 0.18%,
//! mech-holes-shark 0.01% (slightly worse with it).
inline constexpr double kFeatureSizingMinAreaShare = 0.01;

//! Share of the input's vertices on lattice edges, as marching cubes puts them: marching
//! cubes puts every vertex on a lattice edge (two of its coordinates on lattice planes) and
//! joins only points of one cell, so many edges span exactly one spacing along an axis. Per
//! axis, the spacing is the edge extent (>= 0.2 mean edges; from at most ~64k edges) most
//! edges share to 1e-6, the lattice's phase the one most of those edges' ends share; the
//! share is that of the vertices with two or more coordinates on those lattices (to 1e-3
//! spacing). O(n + E).
[[nodiscard]] double lattice_edge_vertex_share(const TriMesh& mesh);

//! Shares of the input's vertices (lattice_edge_shares).
struct LatticeShares {
  double on_lattice_edges = 0.0;  //!< lattice_edge_vertex_share
  //! Vertices at the midpoint of their lattice edge (two coordinates on lattice planes, the
  //! third half a spacing from both, to 1e-3 spacing; or all three on the lattice, which is
  //! what a midpoint is when the edges' most common extent, the spacing found, is half the
  //! image's spacing): marching cubes of a label (0/1) image at the middle iso-value puts
  //! every vertex there, a smooth image almost none.
  double at_edge_midpoints = 0.0;
};

//! lattice_edge_vertex_share and the share of vertices at their lattice edge's midpoint in
//! one pass. Measured (2026-11-26): see docs/surfmesh.md "Detail fit: where it runs".
[[nodiscard]] LatticeShares lattice_edge_shares(const TriMesh& mesh);
//! lattice_edge_shares(mesh) with mean_edge = mean_edge_length(mesh) given by a caller that
//! already has it (the pipeline).
[[nodiscard]] LatticeShares lattice_edge_shares(const TriMesh& mesh, double mean_edge);

//! True when the input looks like the marching-cubes surface of a label image (staircases):
//! lattice_edge_shares(mesh).at_edge_midpoints >= 0.5.
[[nodiscard]] bool label_image_staircase(const LatticeShares& shares);
//! label_image_staircase(lattice_edge_shares(mesh)): the gate of the stitch's volume
//! compensation and fidelity moves (and of remesh()'s shortcut that switches the former off).
[[nodiscard]] bool on_label_image_staircase(const TriMesh& mesh);

//! True when the input looks like a marching-cubes surface: lattice_edge_vertex_share >= 0.5.
//! Measured (2026-11-26; docs/surfmesh.md "The marching-cubes gate"): 1 on the scenes (level
//! set and occupancy, res 24-256), the headsq, ironProt and liver surfaces and
//! brainImageSmooth; at most 0.04 on the CAD and scanned meshes (cheese 0.001: its vertices
//! share coordinates, but on no regular lattice), except three_peaks (1, a terrain on a grid).
[[nodiscard]] bool vertices_on_lattice_edges(const TriMesh& mesh);

//! The uniform target edge length: sizing.size when set (> 0), else sizing.relative_size x
//! the input's mean edge.
[[nodiscard]] inline double uniform_size(const SizingOptions& sizing, double mean_edge) {
  return sizing.size > 0.0 ? sizing.size : sizing.relative_size * mean_edge;
}

//! vertices_on_lattice_edges from shares already computed: shares.on_lattice_edges >= 0.5.
[[nodiscard]] bool marching_cubes_lattice(const LatticeShares& shares);

//! Feature sizing's result: size_at empty when no vertex's size is below base.
struct FeatureSizing {
  SizeAt size_at;
  double smallest = 0.0;  //!< smallest size at a vertex
  //! Per patch: 1 when a vertex of its faces has a size below base (else its front is uniform).
  std::vector<std::uint8_t> patch_limited;
  //! Per patch: the smallest graded size at a vertex of its faces.
  std::vector<double> patch_smallest;
};

//! Sizing from the feature size of crease-bounded patches (SizingOptions::feature_size):
//! a patch with at least kFeatureSizingShare of its perimeter on feature curves has width
//! w = 2 area / perimeter, and at each vertex of its faces h = max(min(base(x), factor w),
//! min(min_size, base(x))); graded along the input's edges and interpolated as in
//! adaptive_sizing. Thread-safe and deterministic. With min_area_share > 0, nothing is
//! limited (size_at empty) when the patches whose factor x width is below base at a vertex
//! hold less than that share of the input's area.
[[nodiscard]] FeatureSizing feature_sizing(const TriMesh& mesh, const Segmentation& segmentation,
                                           const std::vector<std::uint8_t>& curve_is_feature, const SizeAt& base,
                                           double factor, double min_size, double gradation,
                                           double min_area_share = 0.0);

//! The border curves' sizing (SizingOptions::border_lookahead): at x, the smallest of
//! size_at at x and at the 14 points x + r d, r = fraction x size_at(x), d the unit axes and
//! the cube's unit diagonals, both ways. So a border piece is no longer than the sizes just
//! inside the patches it bounds (their first row of triangles). Thread-safe when size_at is.
[[nodiscard]] SizeAt looked_ahead_sizing(SizeAt size_at, double fraction);

//! Independently meshed patches can join the same two border nodes by an edge that is not
//! their border segment (a chord): two patches on either side of a thin fin or of a tiny
//! closed component cut the same ear off their common border (the 3D edge then has four
//! triangles, a duplicated triangle when the third node agrees too), or a chord of one
//! patch is a border segment of another curve. In patch order, every chord that is a
//! border segment or a chord of an earlier patch is split at its midpoint in the patch
//! plane (a new inner node lifted onto the patch's surface), and a triangle of three border
//! segments that an earlier patch already has (a closed curve of three nodes) gets a node
//! at its centroid. Deterministic. Returns the number of chords split plus triangles
//! filled.
std::size_t resolve_shared_chords(const Segmentation& segmentation, const BorderNodes& borders,
                                  std::vector<PatchResult>& results);

//! Traces directed edges (xy: node positions) into loops of node indices. Where loops
//! touch (a node with several outgoing edges), the next edge is the first outgoing one
//! clockwise from the incoming edge's reverse.
[[nodiscard]] std::vector<std::vector<int>> trace_loops(const std::vector<Eigen::Vector2d>& xy,
                                                      const std::vector<std::array<int, 2>>& edges);

//! Curves (ascending ids) of the simple cycles of a patch's traced border loops (split at
//! repeated nodes) that turn counter-clockwise in its plane besides its largest one: a
//! small hole bounded by a few nodes can flip (the segmentation guarantees one
//! counter-clockwise loop for the input vertices).
[[nodiscard]] std::vector<int> extra_outer_loop_curves(const Segmentation& segmentation, const BorderNodes& borders,
                                                       unsigned threads = 1);

//! A patch border's traced loops split into simple cycles (split_at_repeated_vertices), as
//! mesh_patch() checks them: the border is meshable when exactly one traced loop turns
//! counter-clockwise and the border's winding number at a point inside every cycle is 0 (a
//! hole) or 1 (the domain).
struct BorderCycles {
  std::vector<std::vector<int>> cycles;       //!< node indices (into xy)
  std::vector<std::vector<Eigen::Vector2d>> polygons;  //!< the cycles' points
  std::vector<double> areas;                  //!< signed areas of the cycles
  std::vector<std::uint8_t> has_inside;       //!< 0: no inside point found (degenerate cycle)
  std::vector<Eigen::Vector2d> inside;        //!< a point inside each cycle
  std::vector<double> winding;                //!< the border's winding number there
  std::size_t n_ccw_loops = 0;                //!< traced loops of area >= 0
  double area = 0.0;                          //!< area on the left of the directed border
  //! Exactly one counter-clockwise loop, no degenerate cycle, windings 0 or 1.
  [[nodiscard]] bool meshable() const;
};
[[nodiscard]] BorderCycles border_cycles(const std::vector<Eigen::Vector2d>& xy, const std::vector<std::array<int, 2>>& edges);

//! Curves of the patches whose discretised border is not meshable in their plane
//! (BorderCycles::meshable; simple polygons turning the wrong way round are not crossings):
//! per such patch, the curves of its bad cycles (winding other than 0 and 1, degenerate, or
//! a counter-clockwise cycle besides the largest) and every curve of the patch with a
//! segment whose bounding box meets theirs; all its curves when every one of those already
//! takes its input vertices (`source`). Ascending, no repeats.
[[nodiscard]] std::vector<int> folded_border_curves(const Segmentation& segmentation, const BorderNodes& borders,
                                                    const std::vector<CurveSource>& source,
                                                    unsigned threads = 1);

//! Sets patch p's surface to keep projections within max_offset of the patch's own input
//! faces along its axis (PatchSurface::input_heights; the patch's faces are a graph over
//! its plane, so the face straight above or below a point is unique) and moves the inner
//! nodes accordingly. The fit smooths spikes, thin fins and sharp bends by more than a mean
//! edge, and a node lifted that far can pass through the neighbouring sheet. Points over
//! no face (outside the input's projection) are not clamped. Returns the number of nodes
//! moved.
std::size_t clamp_inner_nodes(const TriMesh& mesh, const Segmentation& segmentation, int p, double max_offset,
                              PatchResult& result);

//! A point strictly inside a simple polygon (either orientation), near its leftmost vertex.
//! Returns false when no such point was found (a degenerate polygon).
[[nodiscard]] bool point_inside_polygon(const std::vector<Eigen::Vector2d>& polygon, Eigen::Vector2d& inside);

//! Even-odd point-in-polygon test (floating point; nurbsfront/core/polygon.h).
using nurbsfront::polygon_contains;

//! mesh_surface() and split_unfitted_patches() with mean_edge = mean_edge_length(input)
//! given by a caller that already has it (the pipeline computes it once per remesh);
//! splitter, when given, is the one segment() left for the same input and segment_options;
//! shares, when given, are lattice_edge_shares(input) computed by the caller (not again).
//! split_unfitted_patches() with with_borders false returns a result without curves and
//! corners wherever it split (segment_detail::with_borders() adds them), and the given
//! segmentation as it is where it did not. mesh_surface() with keep_face_patch false leaves
//! SurfaceMesh::input_face_patch empty (a caller whose stitch has no fidelity gate: no copy).
[[nodiscard]] SurfaceMesh mesh_surface(const TriMesh& input, const Segmentation& segmentation,
                                       const SurfMeshOptions& options, double mean_edge,
                                       const LatticeShares* shares = nullptr, bool keep_face_patch = true);
[[nodiscard]] Segmentation split_unfitted_patches(const TriMesh& input, const Segmentation& segmentation,
                                                  const SurfMeshOptions& options,
                                                  const SegmentOptions& segment_options, std::size_t* n_split,
                                                  double mean_edge, segment_detail::Splitter* splitter = nullptr,
                                                  bool with_borders = true);

}  // namespace nurbsfront::surfmesh_detail
