// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Slope-bounded patch segmentation of a triangle mesh: the first stage of the
//! remeshing pipeline (DESIGN.md, "Contracts: Segmentation").
//!
//! Every patch is a height field over the plane orthogonal to its axis, so the next
//! stages can fit z = f(x, y) per patch and mesh it in 2D.

#include <cstddef>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/mesh_types.h"
#include "nurbsfront/core/progress.h"

namespace nurbsfront {

//! Smallest allowed dot product between a (non-degenerate) face's raw unit normal and its
//! patch axis: every face keeps at least this share of its area in projection, so the
//! projected triangles are positively oriented and not needles (about 84 deg at most).
inline constexpr double kSegmentMinRawNormalDot = 0.1;

//! Largest patch (in faces) that joins the one patch around it across creases (step 7b of
//! segment()): a crease-bounded face or few inside one patch, whose border loop is shorter
//! than a target edge (level-set DRAM cell: single faces at the cups' bottoms).
inline constexpr std::size_t kSegmentTinyIslandFaces = 4;
//! ... and whose border is shorter than this many mean input edges (smaller than a normal
//! face, whose border is about 3).
inline constexpr double kSegmentTinyIslandPerimeterEdges = 2.0;

//! How the zig-zag border curves are smoothed (Taubin lambda|mu steps, corners fixed).
struct BorderSmoothingOptions {
  //! Number of lambda|mu step pairs. 0 keeps the input positions. Default 10.
  int iterations = 10;
  //! Shrinking step factor lambda, in (0, 1]. Default 0.5.
  double lambda = 0.5;
  //! Inflating step factor mu, in [-1, 0]; mu < -lambda avoids shrinking closed curves,
  //! 0 gives plain Laplacian smoothing. Default -0.53 (Taubin 1995).
  double mu = -0.53;
  //! Bound on how far a point may move from its input position, as a multiple of the
  //! curve's mean edge length (dimensionless, >= 0). Default 1.0.
  double max_displacement = 1.0;
  //! Bound on a smoothed point's distance to the input (the faces around the curve's input
  //! vertices up to two along the curve on either side), as a multiple of the curve's mean
  //! edge length: a point farther off is pulled back towards its input position until it
  //! is within (>= 0, not NaN; infinity = no bound). Default infinity.
  double max_input_distance = std::numeric_limits<double>::infinity();
  //! Throws InvalidInput if a field is out of range.
  void validate() const;
};

//! RemeshOptions::segment's sharp crease angle (SegmentOptions::sharp_crease_angle_deg):
//! remesh() has the marching-cubes gate that segment() alone lacks.
inline constexpr double kRemeshSharpCreaseAngleDeg = 15.0;

//! Options of segment().
struct SegmentOptions {
  //! Maximal angle (deg) between a face's smoothed normal and its patch axis, in (0, 90).
  //! Default 60: the height-field metric I + grad f grad f^T then stretches lengths at
  //! most by 2.
  double max_slope_deg = 60.0;
  //! Dihedral angle (deg, between the raw normals of two edge-adjacent faces) above which
  //! the edge is a crease and becomes a patch border, in (0, 180]; 180 disables creases.
  //! Default 80: above the 45, 54.7, 60 and 70.5 deg dihedrals that marching cubes on an
  //! occupancy (0/1) grid produces between its 26 normal directions on smooth parts, and
  //! below the 90 deg of box-like features. Blocky (cuberille) inputs with 90 deg steps
  //! need a value above 90.
  double crease_angle_deg = 80.0;
  //! Iterations of area-weighted normal averaging over edge-adjacent faces (never across
  //! a crease) that give the smoothed normals used for grouping (>= 0). Each iteration
  //! widens the averaging by one ring of faces. Default 6: enough to average the
  //! terraces of cell-based inputs (DESIGN.md, Pitfalls).
  int normal_smoothing_rings = 6;
  //! Also make creases of the bends of bevelled sharp edges: marching cubes cuts a 90 deg
  //! box edge into two ~45 deg bends around a strip of faces, below `crease_angle_deg`,
  //! and a patch then holds one bend inside, which its fit rounds off. An edge is such a
  //! crease when its dihedral is at least kBevelMinDihedralDeg (30), the faces within two
  //! vertex rings of each of its ends include two normals at least kBevelMinSpreadDeg (75)
  //! apart, and the mean normals of the faces within three rings on its two sides are at
  //! least kBevelMinSideAngleDeg (40) apart (the terraces of cell-based inputs have
  //! steep pairs of faces, but no such bend on the scale of three rings). Default false:
  //! it halves the Hausdorff distance to the input at bevelled edges (trench, fandisk) but
  //! each bevel strip becomes a narrow patch (about one target edge wide), and the surface
  //! mesher does not yet stagger the nodes of its two border curves: more obtuse and
  //! small-angle triangles (docs/segment.md, "Bevel creases").
  bool bevel_creases = false;
  //! Also make creases of sharp edges below the crease angle, as CAD meshes have them: an
  //! edge bending by at least this angle (deg) and at most crease_angle_deg is a crease when
  //! its sides are smooth (every edge within two vertex rings that bends by less bends by at
  //! most 0.6 x its angle), the bends near it form one line (no vertex within one ring with
  //! more than two edges bending by over 0.6 x its angle; no parallel line of edges bending by
  //! over 0.75 x it: the facets of a coarsely tessellated fillet or tube are not creases), and
  //! it lies on a chain of at least 8 such edges whose dihedrals are within a factor 1.5 and
  //! whose side edges bend on average by at most 5% of its mean dihedral (details in
  //! segment.cpp). Fandisk: its 78-80 deg crease, Hausdorff distance 0.0121 -> 0.0064; none
  //! on the scans of the corpus. The planar terraces of marching-cubes surfaces would qualify:
  //! remesh() turns it off on them (surfmesh's lattice gate) and with a cell grid
  //! (docs/segment.md, "Sharp creases"). In [0, 180]; 0, or a value not below
  //! crease_angle_deg, turns it off. Default 0 (off) for segment() alone, which has no
  //! marching-cubes gate; RemeshOptions::segment has 15 (kRemeshSharpCreaseAngleDeg).
  double sharp_crease_angle_deg = 0.0;
  //! Patches with fewer faces are merged into an edge-adjacent neighbour when the merged
  //! patch still meets the slope bound and no crease separates them (0 disables).
  //! Default 50.
  std::size_t min_patch_faces = 50;
  //! How border curves are smoothed.
  BorderSmoothingOptions border_smoothing;
  //! Worker threads for the per-face and per-patch steps (normals, projection and cliff
  //! checks); 0 = all hardware threads. The result does not depend on it (>= 0). Default 0.
  int threads = 0;
  //! Optional progress callback (stage "segment"); returning false cancels. Default none.
  ProgressCallback progress;
  //! Throws InvalidInput if a field is out of range.
  void validate() const;
};

//! One patch: a connected set of faces that is a height field over its plane.
struct Patch {
  std::vector<int> faces;  //!< input face ids, ascending
  //! Unit height-field direction: the area-weighted mean raw normal when it meets the
  //! bounds for every face, else the axis the patch was grown or merged with.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  std::vector<int> curves;  //!< ids of the border curves bounding this patch, ascending
};

//! A border curve: a chain of input edges between two patches, or between a patch and
//! the input's own boundary.
struct BorderCurve {
  //! Input vertex ids along the curve. An open curve runs from corner to corner (both
  //! may be the same vertex); a closed curve does not repeat its first vertex.
  std::vector<int> vertices;
  //! Input edge ids: edges[i] joins vertices[i] and vertices[i + 1] (cyclically if closed).
  std::vector<int> edges;
  //! The patch on the left when walking along the curve (seen from the side the face
  //! normals point to); never -1.
  int patch_left = -1;
  //! The patch on the right, or -1 when the curve is on the input's boundary. When both
  //! are patches, patch_left < patch_right.
  int patch_right = -1;
  bool is_closed = false;  //!< true for a loop without corners
  //! Smoothed positions, one per vertex; the ends of an open curve are exactly the input
  //! positions, every point stays within the displacement bound of its input position.
  std::vector<Eigen::Vector3d> smoothed;
};

//! The result of segment().
struct Segmentation {
  std::vector<int> face_patch;       //!< patch id of every input face
  std::vector<Patch> patches;        //!< patches, ordered by their smallest face id
  std::vector<BorderCurve> curves;   //!< every border edge lies on exactly one curve
  //! Vertices where three or more sides meet (patches, or patches and the input's
  //! boundary): the ends of the open curves. Ascending.
  std::vector<int> corners;
  //! Input vertices kept as corners (curve ends) although only two sides meet there: the
  //! tips of fin strips merged into a neighbour (the pipeline's fin-strip merge with pinned
  //! tips, docs/segment.md "Fin strips: pinned tips, session 20"). Ascending; edits keep
  //! them; one that is no border vertex (inside a patch) is no corner.
  std::vector<int> pinned_corners;
  std::size_t n_crease_edges = 0;     //!< crease edges (above the crease angle, or bevel bends)
  std::size_t n_bevel_crease_edges = 0;  //!< of those, bends of bevelled edges (SegmentOptions::bevel_creases)
  //! The input edges made creases as sharp crease edges (SegmentOptions::sharp_crease_angle_deg;
  //! counted in n_crease_edges), ascending. The surface mesher keeps the curves along them as
  //! features, at their input positions.
  std::vector<int> sharp_crease_edges;
  std::size_t n_degenerate_faces = 0; //!< faces without a normal (zero area)
  //! Faces whose raw and smoothed normals are so far apart (over 90 deg + max_slope,
  //! a flipped face) that no axis satisfies both bounds: only the raw bound holds.
  std::size_t n_slope_exceptions = 0;
  std::size_t n_fold_splits = 0;      //!< splits made because a projection folded
  //! Tiny patches that only one patch surrounded, joined to it across creases (step 7b).
  std::size_t n_islands_absorbed = 0;
  //! The faces of those islands, ascending: the only faces that may have a crease edge
  //! with a face of the same patch.
  std::vector<int> island_faces;
};

//! Splits the faces of `mesh` into slope-bounded patches and extracts their borders.
//!
//! Algorithm (details and measurements in docs/segment.md):
//! 1. Raw unit face normals and areas; crease edges (dihedral > crease_angle_deg, sharp
//!    crease chains above sharp_crease_angle_deg, and the bends of bevelled edges when
//!    `bevel_creases`).
//! 2. Smoothed normals: `normal_smoothing_rings` Jacobi iterations of area-weighted
//!    averaging over edge-adjacent faces, not across creases.
//! 3. Region growing, seeds in face-id order, breadth first through non-crease edges:
//!    a face joins when its smoothed normal is within 0.75 max_slope_deg of the seed's
//!    axis, its raw normal has dot >= kSegmentMinRawNormalDot with it, and no crease
//!    separates it from a face already in the region.
//! 4. Merging, smallest patch first, into a neighbour when one axis bounds both (union of
//!    bounding cones of the normals); patches below min_patch_faces may also join a
//!    neighbour whose axis bounds them or be dissolved into several neighbours.
//! 5. Border "ears" move to the neighbour they mostly touch where its axis allows.
//! 6. Axes are set to the mean raw normal where the bounds allow it.
//! 7. Each patch is projected onto its plane; where border segments cross, or a second
//!    outer loop appears (a region covered twice), the fold is cut out locally (two rings
//!    of faces) or the patch is bisected by a two-seed breadth-first partition; parts are
//!    checked again, then small parts are re-merged where the merged patch passes.
//! 7b. A patch of at most kSegmentTinyIslandFaces faces that only one patch surrounds (no
//!    input boundary), with a border shorter than kSegmentTinyIslandPerimeterEdges mean
//!    input edges, joins it across creases when its faces meet the bounds for that patch's
//!    axis and the union passes the projection check (island_faces).
//! 8. Border edges are chained into curves between corners (or closed loops), and each
//!    curve is smoothed by Taubin steps with its ends fixed and a bounded displacement.
//!
//! Guarantees: every face is in exactly one patch; each patch is connected through
//! edges; no crease edge has the same patch on both sides, except edges of island_faces; for every non-degenerate face
//! n_raw . axis >= kSegmentMinRawNormalDot (its projection is positively oriented) and,
//! except the n_slope_exceptions faces, n_smoothed . axis >= cos(max_slope_deg); the
//! projected border of each patch is a set of loops whose segments neither cross nor
//! touch, except that loops may share a vertex where the patch touches itself (always a
//! corner), with one outer (counter-clockwise) loop: the patch is a graph over its plane
//! (floating-point predicates). Every border edge is on exactly one curve. Patches
//! smaller than min_patch_faces remain where no neighbour can take them. Degenerate
//! (zero-area) faces join a neighbouring patch and are exempt from the normal bounds:
//! weld and drop them first (io module). The result depends only on the mesh and the
//! options, not on options.threads (no hashing; the parallel steps compute per face, per
//! patch or per curve what the serial ones would, and the order-dependent steps, region
//! growing, merging and the splits, run on one thread).
//!
//! \param mesh     a 2-manifold triangle mesh without deleted elements (open or closed)
//! \param options  see SegmentOptions
//! \return         the segmentation; empty for an empty mesh
//! \throw InvalidInput for invalid options, deleted elements or non-finite points.
//! \throw Cancelled if the progress callback returns false.
[[nodiscard]] Segmentation segment(const TriMesh& mesh, const SegmentOptions& options = {});

//! Splits each listed patch of a segmentation of `mesh` in connected parts by its face
//! normals, and rebuilds the border curves and corners (for a patch whose fitted surface
//! does not represent its faces: it spans bends sharper than its fit can follow).
//!
//! Each listed patch: two clusters of its smoothed normals (2-means, started from the normal
//! furthest from the axis and the one furthest from that), their connected components,
//! components below min(min_patch_faces, a quarter of the patch) merged into the neighbouring
//! component they share most edges with. A part's axis is its mean raw normal where every
//! face fits it, else its mean smoothed normal, else the patch's axis; a part whose
//! projection folds with its own axis keeps the patch's. Then every patch passes segment()'s
//! projection check and split (step 7) where it fails; no merging follows (it would join
//! the parts again). Patches whose normals do not separate stay as they are. Patch ids are
//! renumbered by smallest face as in segment(); all of segment()'s guarantees hold except
//! that patches below min_patch_faces may remain.
//! \param which  patch ids to split (any order, duplicates ignored)
//! \throw InvalidInput for invalid options, a mesh segment() refuses, a segmentation of
//!        another mesh or an unknown patch id.
[[nodiscard]] Segmentation split_patches(const TriMesh& mesh, const Segmentation& segmentation,
                                         const std::vector<int>& which, const SegmentOptions& options = {});

//! Each listed patch (in the order given) joins the neighbouring patch it shares the longest
//! border with, across creases, when every face of the union meets the slope bounds for an
//! axis (the neighbour's, else the union's area-weighted mean face normal) and the union
//! projects simply on that axis (segment()'s check); otherwise the next neighbour is tried,
//! and a patch no neighbour takes stays. The pipeline's last resort against crossings that
//! stitching left (docs/segment.md, "Re-segmenting crossing patches"); the joined faces are
//! added to island_faces (creases may now lie inside a patch there) and each join counts in
//! n_islands_absorbed (such a patch may have more than kSegmentTinyIslandFaces faces). Curves are rebuilt and patch
//! ids renumbered as in segment(); the segmentation is returned unchanged when nothing joined.
//! \param which  patch ids (duplicates and patches already joined are skipped)
//! \throw InvalidInput for invalid options, a mesh segment() refuses, a segmentation of
//!        another mesh or an unknown patch id.
[[nodiscard]] Segmentation merge_patches_into_neighbours(const TriMesh& mesh, const Segmentation& segmentation,
                                                         const std::vector<int>& which,
                                                         const SegmentOptions& options = {});

//! The patches narrower than max_width that share an edge with a patch at least max_width
//! wide, narrowest first (ties: lower id). A patch's width is 2 x its area / its border
//! length (the border shared with other patches and the input's boundary): the width of a
//! long strip. A patch without border (a whole closed component) is never narrow; patches
//! whose neighbours are all narrow (the sides of a box smaller than max_width) are not listed. The pipeline merges these into neighbours on marching-cubes inputs
//! (RemeshOptions::narrow_patch_merge; docs/segment.md "Narrow patches").
//! \throw InvalidInput for a segmentation of another mesh or a max_width that is not finite.
[[nodiscard]] std::vector<int> narrow_patches(const TriMesh& mesh, const Segmentation& segmentation, double max_width);

//! The patches of at most max_faces faces (and at least one) that the pipeline merges on
//! CAD-like meshes (RemeshOptions::tiny_patch_faces; docs/segment.md "Tiny patches behind
//! marginal creases"): every edge they share with another patch bends by at most
//! max_dihedral_deg (angle between the two faces' normals; their creases are marginal, as a
//! coarse bone's bends are, not a machined edge's), and they share an edge with a patch of more
//! than max_faces faces (a small closed shape of tiny patches stays whole) and with at least
//! two patches (one that a single patch surrounds is an island: segment()'s step 7b decides
//! those, and on fandisk such a face holds the end of a 90 deg crease). Smallest first (ties:
//! lower id). Edges on the input's boundary do not count.
//! \throw InvalidInput for a segmentation of another mesh or a max_dihedral_deg that is not finite.
[[nodiscard]] std::vector<int> tiny_patches(const TriMesh& mesh, const Segmentation& segmentation,
                                            std::size_t max_faces, double max_dihedral_deg);

//! A crease angle for a mesh whose bends leave a gap below crease_angle_deg: the largest c
//! (deg; crease_angle_deg - 5, - 10 or - 15, above 0) such that at least kCreaseGapMinShare
//! of the mesh's interior edges bend by more than c and at most crease_angle_deg, and the
//! edges bending by more than c - 15 and at most c are at most kCreaseGapMaxValley times as
//! many; else crease_angle_deg itself. A CAD mesh's machined edges meeting at 65-80 deg then
//! become creases (cheese.off: 2 422 edges at 65-80 deg, 117 at 50-65; the fits rounded them
//! off), while on a mesh whose bends spread evenly (femur, a marching-cubes surface) nothing
//! changes. The pipeline applies it on inputs not taken for marching cubes
//! (RemeshOptions::crease_gap; docs/segment.md "Creases at a gap in the bends"). Edges beside
//! a zero-area face do not count.
//! \throw InvalidInput for a crease_angle_deg outside (0, 180].
[[nodiscard]] double gap_crease_angle(const TriMesh& mesh, double crease_angle_deg);
inline constexpr double kCreaseGapMinShare = 0.02;
inline constexpr double kCreaseGapMaxValley = 0.1;

//! split_patches() in rounds on one mesh (surfmesh's split_unfitted_patches): the face
//! graph, creases and normals are computed once (at the first split), and when a round is
//! given the previous round's result, only the parts of the patches it splits go through
//! the projection and cliff checks (the others passed them in that round). Same results as
//! split_patches(). The mesh must outlive the splitter and must not change while it is
//! used (its face graph, points and normals are kept from the first split).
class PatchSplitter {
 public:
  //! \throw InvalidInput for invalid options or a mesh segment() refuses.
  PatchSplitter(const TriMesh& mesh, const SegmentOptions& options = {});
  ~PatchSplitter();
  PatchSplitter(const PatchSplitter&) = delete;
  PatchSplitter& operator=(const PatchSplitter&) = delete;
  //! split_patches(mesh, segmentation, which, options).
  [[nodiscard]] Segmentation split(const Segmentation& segmentation, const std::vector<int>& which);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

//! Splits a closed vertex sequence (the last vertex joins the first) that passes some
//! vertex more than once into simple cycles: where it returns to a vertex, the part since
//! that vertex's previous visit is one cycle (e.g. a border loop through a corner where
//! loops touch). A sequence without repeated vertices is returned as it is.
[[nodiscard]] std::vector<std::vector<int>> split_at_repeated_vertices(const std::vector<int>& loop);

//! Smooths a polyline by Taubin lambda|mu steps with uniform weights.
//!
//! The ends of an open polyline stay fixed; a closed one (last point joined to the first)
//! has no fixed point. After each step a point further than
//! options.max_displacement * (mean segment length) from its input position is pulled
//! back onto that sphere.
//! \param points    the input points (any count; fewer than 3 are returned unchanged)
//! \param is_closed whether the last point is joined to the first
//! \param options   see BorderSmoothingOptions
//! \throw InvalidInput for invalid options.
[[nodiscard]] std::vector<Eigen::Vector3d> smooth_polyline(const std::vector<Eigen::Vector3d>& points,
                                                           bool is_closed,
                                                           const BorderSmoothingOptions& options = {});

}  // namespace nurbsfront
