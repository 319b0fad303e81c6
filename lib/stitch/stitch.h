// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Stitching: the last stage of the remeshing pipeline (DESIGN.md, "Pipeline", stitch).
//! The meshed patches (a SurfaceMesh with global node ids) become one OpenMesh TriMesh,
//! joined by id and never by distance; a cross-border optimisation (edge flips and
//! smoothing constrained to the fitted surfaces) follows, and the result is verified
//! against the contract of DESIGN.md ("Contracts: Stitch"). A violation is an error in
//! the report, never an exception and never hidden.

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "nurbsfront/core/mesh_types.h"
#include "nurbsfront/core/progress.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/surfmesh/surfmesh.h"

namespace nurbsfront {

//! Issue 5's bound on the smallest angle of the triangles away from features (deg).
inline constexpr double kAwayFromFeaturesAngleBoundDeg = 25.0;

//! Options of stitch().
struct StitchOptions {
  //! Rounds of the cross-border optimisation; each round is one sweep of edge flips and
  //! one of smoothing (>= 0; 0 switches these sweeps off; the obtuse repair and the chord
  //! compensation below have their own switches). Default 3.
  int optimisation_passes = 3;
  //! Largest angle (deg) between the normals of the two triangles of an edge, before and
  //! after a flip, for the flip to be allowed, in [0, 180). Default 30.
  double max_flip_dihedral_deg = 30.0;
  //! An edge inside a patch whose two ends lie on one feature curve (or at a corner and on a
  //! feature curve) but are no neighbours along it (a chord across the patch, not a piece of
  //! the crease) may flip like any edge inside a patch; false: locked like the crease's
  //! pieces, as before session 19 (docs/stitch.md "Chords between the nodes of a crease,
  //! session 19"). Default true.
  bool flip_feature_chords = true;
  //! Relative gain a flip must bring: the smaller alpha of the two new triangles must
  //! exceed (1 + flip_gain) times the smaller of the two old ones (>= 0). Default 1e-3.
  double flip_gain = 1e-3;
  //! Relaxation factor of a smoothing move towards the area-weighted centroid of the
  //! node's triangles, in (0, 1]. Default 0.5.
  double smoothing_relaxation = 0.5;
  //! A smoothing move is accepted only if no incident triangle's normal turns by more than
  //! acos(min_normal_dot) (cosine, in [-1, 1)). Default 0.5 (60 deg).
  double min_normal_dot = 0.5;
  //! ... and the smallest alpha of the incident triangles does not drop below min(its old
  //! value, alpha_floor) (Lo's alpha, in [0, 1]). Default 0.5.
  double alpha_floor = 0.5;
  //! A smoothing move is accepted only if the smallest angle (deg) of the incident
  //! triangles does not drop below min(its old value, angle_floor_deg), in [0, 60): a move
  //! never makes a triangle below issue 5's bound that was not there. Default 25.
  double angle_floor_deg = kAwayFromFeaturesAngleBoundDeg;
  //! Chord compensation after the optimisation (docs/stitch.md, "Volume: chords over curved
  //! surfaces"): a flat triangle whose corners lie on a curved surface lies on its concave
  //! side, by about (1/24) sum over its edges of kappa_e |e|^2 on average; every node that is
  //! no feature node nor on the input's boundary moves along its normal by this factor times
  //! the area-weighted mean gap of its triangles, less the part an edge as long as the
  //! input's mean edge has (the input's own chords; SurfaceMesh::input_mean_edge), at most
  //! 0.1 of its edges; an inner node of a detail-fitted patch then goes back within its
  //! patch's node bound of the input (PatchSurface::max_offset, along the patch axis).
  //! In [0, 2]; 0 switches it off. Default 1.
  double chord_compensation = 1.0;
  //! Volume compensation after the chord compensation (docs/stitch.md, "Volume: measured
  //! along the patch axis"): the volume between each triangle and its patch's input faces,
  //! measured along the patch axis, is taken back by moving the triangle's nodes that are no
  //! feature node nor on the input's boundary along their normals (a triangle between border
  //! nodes only: the free nodes of its patch), times this factor, at most 0.1 of their
  //! edges; only in patches of fewer than 100 input faces (larger ones are the chord
  //! compensation's), not on marching-cubes surfaces, and no move adds an obtuse triangle
  //! or an angle below min(the old smallest, 25 deg). In [0, 2]; 0 switches it off. Default 1.
  double volume_compensation = 1.0;
  //! The volume compensation measures and moves nothing where the mesh (closed, as the
  //! input) already encloses the input's volume within this fraction of it, before the
  //! compensation (after the chord compensation). In [0, 0.05]; default 0 (always
  //! compensate: the compensation also lowers the distance to the input where the volume is
  //! already right, bunny's Hausdorff 0.37 -> 0.27 mean edges). 0.0005 (a tenth of issue 5's
  //! 0.5%) skips it on DRAM 256's level set (-0.004%), whose compensation is 2.6 G of the
  //! main thread's 11 G instructions at 2 threads (docs/stitch.md "The volume compensation
  //! on level sets, session 15").
  double volume_compensation_skip_within = 0.0;
  //! Sweeps of the obtuse repair after the optimisation passes (>= 0; 0 switches it off):
  //! flips that leave fewer obtuse angles in their two triangles, then each movable node of
  //! an obtuse triangle moves towards the ideal apex of one of its obtuse triangles when
  //! that leaves fewer obtuse triangles around it and passes the smoothing tests above, the
  //! angle floor raised by 2.5 deg (counted in StitchReport::n_flips and n_smoothing_moves;
  //! docs/stitch.md "Obtuse repair"). When the volume compensation moved nodes, one more
  //! sweep follows it (docs/stitch.md "The CAD meshes' obtuse triangles, session 13").
  //! Default 2.
  int obtuse_repair_rounds = 2;
  //! The obtuse repair's search (in [0, 30]; 0 switches it off): an inner node of a patch
  //! that the apex steps above do not help searches the plane of its triangles, within half
  //! its shortest edge, for a place with fewer obtuse triangles (a compass search from a
  //! quarter of its shortest edge, the step halved this many times), kept when it passes the
  //! repair's tests once projected (docs/stitch.md "Obtuse repair: a search in the plane,
  //! session 17"; 0 = off). Default 5: cheese 2.43 -> 1.88%, couplingdown 1.11 -> 0.93%,
  //! rotor 1.25 -> 1.21% obtuse; bunny00 one obtuse triangle more (12 -> 13) and pinion
  //! 0.957 -> 0.972% (9 obtuse triangles either way, fewer splits), both under 1%.
  int obtuse_search_steps = 5;
  //! Rounds of feature slides after the obtuse repair (>= 0; 0 switches them off): a node of
  //! a feature curve (crease or input boundary; a corner only with feature_corner_slides) that has an obtuse triangle
  //! slides along its curve, on the polyline of the curve's nodes as the front placed them
  //! (SurfaceMesh::nodes along SurfaceMesh::curve_nodes), at most 0.4 of a piece either way
  //! from its own node, to the place that leaves the fewest obtuse triangles around it (then
  //! the smallest largest angle), when that removes an obtuse triangle, passes the obtuse
  //! repair's tests (normals, alpha floor, angle floor + 2.5 deg) and the crease polyline it
  //! leaves stays within 0.05 of a piece of the front's;
  //! each round ends with the obtuse repair's flips and moves (counted in
  //! StitchReport::n_feature_slides, n_flips and n_smoothing_moves; docs/stitch.md
  //! "Feature nodes sliding along their curves"). They belong to the obtuse repair: none run
  //! when obtuse_repair_rounds is 0. Default 2 (elephant 1.095 -> 0.912% obtuse; 0 = off).
  int feature_slide_rounds = 2;
  //! Feature slides (feature_slide_rounds) move feature corners too: a corner where exactly
  //! two feature curve ends meet (a crease running through a junction with smooth borders)
  //! slides along them as a node of a crease does, one where exactly one ends (a crease
  //! ending at smooth borders) back along it only; never a corner with three or more, nor a
  //! fin rim node. Same steps, tests and bounds as the other slides (counted in
  //! StitchReport::n_feature_slides). Default true (headsq@500 1.864 -> 1.812% obtuse,
  //! @1150 4.008 -> 3.907%, no Hausdorff change; docs/stitch.md "Feature corners sliding,
  //! session 21"); false: every feature corner stays where the front put it.
  bool feature_corner_slides = true;
  //! A feature slide that removes no obtuse triangle is also taken when it raises the cosine
  //! of the largest angle of the node's triangles by at least this (> 0; infinity: never).
  //! Default infinity: at 0.01 elephant, couplingdown and rotor lose more obtuse triangles
  //! (0.88, 1.04, 1.29% against 0.91, 1.11, 1.41%) but pinion gains some (0.96 -> 2.02%: the
  //! obtuse splits after such slides take fewer apart) and fandisk's Hausdorff grows 15%
  //! (docs/stitch.md "Feature nodes sliding along their curves").
  double feature_slide_cosine_gain = std::numeric_limits<double>::infinity();
  //! Sweeps of obtuse splits after the optimisation and the intersection checks (>= 0; 0
  //! switches them off): the longest edge of a triangle still obtuse is split at the foot of
  //! the altitude from the obtuse corner (clamped to [0.2, 0.8] of the edge, or at its
  //! midpoint), the new node on the segment for a crease, boundary edge or chord between two
  //! feature nodes of two patches (a feature node then), else on the fitted surface(s) (or its
  //! ring's mean), when the new triangles hold fewer obtuse angles and pass the smoothing's normal, alpha and
  //! angle floors; then the obtuse repair's flips and moves once around the new nodes. Splits
  //! whose triangles cross others are given up. Adds vertices (StitchReport::n_obtuse_splits);
  //! docs/stitch.md "Obtuse splits". Only when the mesh has no crossing left. Default 2.
  int obtuse_split_rounds = 2;
  //! A split that still leaves obtuse triangles also tries its node at 30 places on a grid
  //! beside the edge, in the obtuse triangle's plane, projected onto the fit (docs/stitch.md
  //! "Split nodes on a grid, session 18"). remesh() switches it off with a cell grid (the
  //! occupancy band fit sits off the marching-cubes input by design: the grid's nodes took DRAM
  //! occupancy 128's Hausdorff to the input from 0.89 to 1.05 voxel). Default true.
  bool obtuse_split_grid = true;
  //! The obtuse splits' angle floor (deg) for a new triangle with a feature node (not away
  //! from features), when the split takes the obtuse angle off a node that nothing moves (a
  //! feature node or corner): its smallest angle must stay at least min(the old triangles'
  //! smallest, this, the usual floor) instead of min(old, usual floor) (angle_floor_deg, or
  //! that + 2.5 deg for the relaxed split nodes). Issue 5's bound is on the angles away from
  //! features, which keep the usual floor. Where tunnel walls meet at a corner of 110-114
  //! deg between one-edge border pieces (cheese.off), the split of the closing triangle
  //! leaves 20-25 deg angles beside the corner. In [0, 60); at angle_floor_deg + 2.5 or
  //! above nothing changes. Default 20 (docs/surfmesh.md "Cheese's hole walls, session 15").
  double obtuse_split_feature_angle_deg = 20.0;
  //! Sweeps of the small-angle repair after the optimisation and the intersection checks
  //! (>= 0; 0 switches it off): each triangle with no feature node and a smallest angle
  //! below kAwayFromFeaturesAngleBoundDeg, worst first, gets the best flip or collapse of one
  //! of its edges (the survivor stays) that raises the smallest angle of the triangles it
  //! touches, leaves no more of them below the bound and no more obtuse ones (else the best
  //! such pair of changes, the first not better by itself); changes whose
  //! triangles cross others are given up. Only when the mesh has no crossing left.
  //! docs/stitch.md "Small angles left after the optimisation". Default 12 (the sweeps stop
  //! early when one changes nothing; the liver needs 3, headsq@1150 10: a node's moves a
  //! quarter of the way to an apex lift its triangle a little each sweep).
  int angle_repair_rounds = 12;
  //! Obtuse collapses after the small-angle repair's sweeps (within its crossing checks; not
  //! when angle_repair_rounds is 0): each triangle with an angle above 90 deg gets one of its
  //! corners that is no feature node collapsed into a neighbour (which stays) when that leaves
  //! fewer obtuse triangles around it, none more below the bound, the smallest angle away from
  //! features at least min(old, angle_floor_deg + 2.5), beside features at least min(old, that,
  //! obtuse_split_feature_angle_deg), the smallest alpha at least min(old, alpha_floor) and the
  //! removed node within 0.15 input mean edges of the new triangles; on a closed mesh the
  //! collapses' summed volume change stays within 0.05% of its enclosed volume (they come
  //! after the volume compensation). Counted in StitchReport::n_obtuse_collapses;
  //! docs/stitch.md "Obtuse collapses, session 20" and "... by default, session 21".
  //! Default true (femur 1.826 -> 1.604% obtuse, rotor 0.695 -> 0.580%, the liver 0.553 ->
  //! 0.462%, Hausdorff distances unchanged).
  bool obtuse_collapse = true;
  //! Triangles whose smallest angle (deg) is below this get their shortest edge collapsed
  //! before the optimisation, when the merge is allowed and improves the worst triangle
  //! around it (feature nodes never moved, and removed only into a feature corner less
  //! than 0.05 target sizes away at the other end of a one-piece curve; see
  //! docs/stitch.md), in [0, 60); 0
  //! switches it off. Default 25 (issue 5's bound away from features).
  double collapse_below_angle_deg = 25.0;
  //! Every stage of the stitch (the short-edge collapse's survivors, the smoothing, the obtuse
  //! repair and splits, the chord and volume compensations, the crossing settling and the
  //! small-angle repair) keeps every node of a fin rim curve (SurfaceMesh::curve_is_fin_rim;
  //! its corners included) within this many input mean edges (SurfaceMesh::input_mean_edge)
  //! of where the front put it (SurfaceMesh::nodes): a move beyond stops at the bound on the
  //! way to its target (a merge: not made when the survivor lies beyond). A fin
  //! rim is a crease the fits of its two narrow patches may round off (docs/stitch.md "Fin
  //! rims"). >= 0 (0: such nodes stay); infinity: no bound. Default infinity (opt-in with
  //! SurfMeshOptions::fin_rim_max_angle_deg 180 and fin_rim_max_gap_edges infinity; docs/stitch.md
  //! "Fin rims: a bound on the moves", "Lead decision").
  double fin_rim_max_move = std::numeric_limits<double>::infinity();
  //! Fidelity moves, last (docs/stitch.md "Fidelity moves"; issue 6): where a vertex is
  //! farther from the input than this many input mean edges (SurfaceMesh::input_mean_edge),
  //! or an input vertex that far from the output, a vertex moves onto the input when its
  //! triangles keep their shape (the smoothing's normal, alpha and angle floors, no more
  //! obtuse ones) and the distance there does not grow
  //! (stitch_detail::move_toward_input). Only with an input mesh (stitch(surface, input)).
  //! Finite, >= 0; 0 switches it off. Default 0 (the tool's `--fidelity-distance F`; 0.25
  //! puts bunny, headsq@500 and the brain within issue 6's 2x but costs DRAM 256's stitch
  //! 2.7x: docs/stitch.md "Fidelity moves, session 15").
  double fidelity_distance_edges = 0.0;
  //! The fidelity moves' shape floor per triangle: a move or split may not take a triangle's
  //! alpha below min(its old alpha, this) (a split's new triangle: its old triangle's), in
  //! [0, 1]; 0 leaves only the ring's floor (alpha_floor). Default 0 (docs/stitch.md
  //! "Fidelity moves, session 16").
  double fidelity_alpha_floor = 0.0;
  //! The fidelity moves only where a fit misses its input: only the input faces around an
  //! input vertex that its patch's fit misses by more than this many input mean edges (along
  //! the patch's axis; SurfaceMesh::input_face_patch) are measured against the output, and
  //! only the output vertices of the patches holding such faces (a corner of the output face
  //! nearest a measured input sample can still move, outside them: not measured afterwards).
  //! Finite, >= 0; 0 = everywhere (also when the SurfaceMesh has no input_face_patch).
  //! Default 0 (tool `--fidelity-gate G`; docs/stitch.md "Fidelity moves, session 20").
  double fidelity_gate_edges = 0.0;
  //! Run the exact self-intersection checks: the check of the result (the most expensive
  //! check) and the checks that undo moves, collapses and fidelity moves that make crossings;
  //! false skips all of them, so the result can change and keep crossings. Default true.
  bool check_self_intersections = true;
  //! Worker threads of the checks (results do not depend on it); >= 1. Default 2.
  unsigned n_threads = 2;
  //! Progress and cancellation (stages "stitch: assemble", "stitch: optimise",
  //! "stitch: verify"). Default none.
  ProgressCallback progress;
  //! \throw InvalidInput if a field is out of range.
  void validate() const;
};

//! Topology of one connected component (faces joined through shared vertices).
struct ComponentSignature {
  std::size_t n_vertices = 0;
  std::size_t n_edges = 0;
  std::size_t n_faces = 0;
  long euler_characteristic = 0;  //!< V - E + F
  bool is_closed = false;         //!< no boundary edge
  BoundingBox box;
};

//! Components of a mesh in order of their lowest face index (deleted faces skipped).
[[nodiscard]] std::vector<ComponentSignature> component_signatures(const TriMesh& mesh);

//! What stitch() did and found.
struct StitchReport {
  std::size_t n_input_nodes = 0;       //!< SurfaceMesh::nodes
  //! Nodes no triangle uses (dropped). Nodes merged away by collapses are counted in
  //! n_collapses and n_settled_collapses instead: the output has n_input_nodes -
  //! n_unused_nodes - n_collapses - n_settled_collapses - n_angle_collapses -
  //! n_obtuse_collapses + n_obtuse_splits + n_fidelity_splits vertices.
  std::size_t n_unused_nodes = 0;
  std::size_t n_input_triangles = 0;   //!< SurfaceMesh::triangles
  //! Triangles OpenMesh cannot add (repeated node, complex edge or vertex: a duplicated,
  //! flipped or overlapping triangle). Each is a contract violation (an error below).
  std::size_t n_rejected_triangles = 0;
  //! Short edges collapsed (node merges) before the optimisation.
  std::size_t n_collapses = 0;
  //! Collapses given up because the merged triangles intersected others.
  std::size_t n_collapses_undone = 0;
  std::size_t n_flips = 0;             //!< edge flips made
  std::size_t n_smoothing_moves = 0;   //!< node moves accepted
  std::size_t n_smoothing_rejected = 0;  //!< node moves refused by the quality/normal bounds
  std::size_t n_feature_slides = 0;  //!< feature nodes slid along their curves (StitchOptions::feature_slide_rounds)
  std::size_t n_chord_compensation_moves = 0;  //!< nodes moved by the chord compensation
  std::size_t n_volume_compensation_moves = 0;  //!< nodes moved by the volume compensation
  //! The volume compensation did nothing: the volume was already within
  //! StitchOptions::volume_compensation_skip_within of the input's.
  bool volume_compensation_skipped = false;
  //! Edges split by the obtuse splits (one new vertex each; StitchOptions::obtuse_split_rounds),
  //! and the splits given up because their triangles crossed others.
  std::size_t n_obtuse_splits = 0;
  std::size_t n_obtuse_splits_undone = 0;
  //! Nodes moved back to their assembled position because a triangle of theirs intersected
  //! another after the optimisation.
  std::size_t n_reverted_moves = 0;
  //! Edges a flip made that were flipped back because a triangle of theirs intersected
  //! another after the optimisation.
  std::size_t n_reverted_flips = 0;
  //! True when undoing the offending moves and flips did not remove the intersections the
  //! optimisation made, so the whole optimisation was undone (the assembled mesh is
  //! returned).
  bool optimisation_undone = false;
  //! Nodes moved onto their patches' input faces (along the patch axes) because a triangle
  //! of theirs intersected another in the assembled mesh (docs/stitch.md, "Crossings of the
  //! assembly").
  std::size_t n_settled_nodes = 0;
  //! Edges of such triangles flipped because the flip left fewer intersecting pairs.
  std::size_t n_settled_flips = 0;
  //! Edges of such triangles collapsed (the removed node merged into the other end, which
  //! stays) because the collapse left fewer intersecting pairs.
  std::size_t n_settled_collapses = 0;
  //! Flips and collapses of the small-angle repair (StitchOptions::angle_repair_rounds), and
  //! its changes given up because their triangles crossed others.
  std::size_t n_angle_flips = 0;
  std::size_t n_angle_collapses = 0;
  std::size_t n_angle_moves = 0;
  //! Pairs of changes of the small-angle repair where no single change was better (each
  //! change also counted above; docs/stitch.md "Two-step changes").
  std::size_t n_angle_two_steps = 0;
  //! Moves of the small-angle repair's finer search, where neither a single change nor a
  //! pair was better (each also counted in n_angle_moves; docs/stitch.md "The liver's last
  //! two").
  std::size_t n_angle_searches = 0;
  std::size_t n_angle_repairs_undone = 0;
  //! Collapses of the obtuse collapses (StitchOptions::obtuse_collapse; given up ones are
  //! counted in n_angle_repairs_undone).
  std::size_t n_obtuse_collapses = 0;
  //! Vertices the fidelity moves left elsewhere (StitchOptions::fidelity_distance_edges), and
  //! moves put back because their triangles crossed others.
  std::size_t n_fidelity_moves = 0;
  std::size_t n_fidelity_moves_undone = 0;
  //! New vertices the fidelity moves put on input vertices (edge splits).
  std::size_t n_fidelity_splits = 0;
  double alpha_mean_before = 0.0;      //!< mean alpha after assembly, before optimisation
  double alpha_min_before = 0.0;       //!< min alpha after assembly, before optimisation
  //! Triangles of the result away from features: none of their vertices is a crease node,
  //! i.e. a node of a feature curve (SurfaceMesh::curve_is_feature: crease or input
  //! boundary) or of a fin rim curve (SurfaceMesh::curve_is_fin_rim: a crease of the input by
  //! the same test, which stitch may move within StitchOptions::fin_rim_max_move), or a
  //! corner that ends one (with empty SurfaceMesh::curve_nodes: any corner). Corners where
  //! only smooth curves meet are not features. Issue 5's 25 deg bound on the smallest angle
  //! applies to these triangles.
  std::size_t n_away_from_features = 0;
  //! Smallest interior angle (deg) of those triangles; 0 when there is none.
  double min_angle_away_from_features_deg = 0.0;
  //! Those of them whose smallest angle is below kAwayFromFeaturesAngleBoundDeg (25 deg).
  std::size_t n_small_angle_away_from_features = 0;
  //! Triangles with a fin rim node but no node of a feature curve (nor a corner ending one):
  //! the ones the set above leaves out only because of the fin rims. Their smallest angle
  //! (deg; 0 when there is none) and those below kAwayFromFeaturesAngleBoundDeg; the sum of
  //! both small-angle counts is the count that treats fin rims as smooth borders.
  std::size_t n_at_fin_rims = 0;
  double min_angle_at_fin_rims_deg = 0.0;
  std::size_t n_small_angle_at_fin_rims = 0;
  //! Topology and quality of the result (no distances), from the quality module.
  MeshReport output;
  //! Components of the result, and of the input when stitch() was given one.
  std::vector<ComponentSignature> output_components;
  std::vector<ComponentSignature> input_components;
  double seconds_assemble = 0.0;
  double seconds_optimise = 0.0;
  double seconds_verify = 0.0;
  //! Contract violations, one human-readable line each. Empty when the contract holds.
  std::vector<std::string> errors;
  [[nodiscard]] bool ok() const { return errors.empty(); }
};

//! The stitched mesh and its report. face_patch and vertex_node give the provenance of
//! every face (patch id) and vertex (global node id of the SurfaceMesh), by index. A vertex
//! made by an obtuse split has a node id from SurfaceMesh::nodes.size() on (no node of the
//! SurfaceMesh).
struct StitchResult {
  TriMesh mesh;
  std::vector<int> face_patch;
  std::vector<int> vertex_node;
  StitchReport report;
};

//! Joins the patch meshes into one TriMesh, optimises across the borders and verifies.
//!
//! Algorithm:
//! 1. Assembly by global node id: every node used by a triangle becomes a vertex (in node
//!    order); triangles are added in order. A triangle OpenMesh cannot take (repeated
//!    node, an edge already used in that direction, a closed vertex fan) is counted and
//!    reported as an error; it is never silently dropped.
//! 1b. Short-edge collapse (collapse_below_angle_deg): the shortest edge of each triangle
//!    with a smaller angle is collapsed when allowed (never moving a feature node, never
//!    removing one but into a feature corner a hair away) and the smallest angle around it
//!    grows; the triangles are re-assembled by the
//!    merged node ids; merges whose faces intersect others are given up (docs/stitch.md).
//! 2. `optimisation_passes` rounds of
//!    a. edge flips: an interior edge whose two triangles are within the dihedral bound
//!       (before and after), whose new edge does not exist yet, and whose flip raises the
//!       smaller alpha of the pair by the gain. Never an edge of a feature curve
//!       (SurfaceMesh::curve_is_feature), of the input's boundary or between two patches
//!       when its curve cannot be identified (both ends corners);
//!    b. smoothing: an inner node moves towards the area-weighted centroid of its
//!       triangles and back onto its patch surface (PatchSurface::project); a border node
//!       of a non-feature curve onto the mean of its two patch surfaces' projections.
//!       A corner of smooth curves only onto the mean of all its patches' projections.
//!       Feature nodes (nodes of feature curves, corners ending one) and boundary nodes
//!       never move. No move whose projection would use a detail-fitted patch
//!       (SurfaceMesh::patches[p].detail_fit) that has no input face straight above or
//!       below it (its fit is not held to the input there). A move is kept only if it turns
//!       no incident triangle's normal too far and keeps their smallest alpha (bounds in
//!       StitchOptions).
//!    If the result has self-intersections (one exact check over the whole mesh, when
//!    check_self_intersections) that involve a triangle the optimisation changed, the
//!    nodes of those triangles go back to their assembled positions and the edges flips
//!    made in them are flipped back; only the faces around these changes are checked
//!    again (up to 6 rounds). If changed triangles still intersect, the optimisation is
//!    undone as a whole. Intersections already in the assembly: the nodes of the crossing
//!    triangles move onto their patches' input faces along the patch axes (a node of a
//!    detail-fitted patch with no input face straight below: to its ring's mean height
//!    along the axis), then their edges
//!    are flipped, each change kept only if fewer pairs cross; what still crosses is an
//!    error.
//! 2b. Small-angle repair (angle_repair_rounds), when nothing crosses: each triangle with no
//!    feature node and a smallest angle below kAwayFromFeaturesAngleBoundDeg gets the best
//!    flip, collapse (the survivor stays) or move onto the fitted surfaces around it that
//!    raises the smallest angle there; changes whose triangles cross others are given up.
//! 2c. Fidelity moves (fidelity_distance_edges > 0, with an input mesh), when nothing crosses:
//!    vertices onto the input, and new vertices on it by edge splits, where the output is
//!    farther from the input than the bound (stitch_detail::move_toward_input).
//! 3. Verification (quality module): 2-manifold, consistently oriented, no degenerate or
//!    self-intersecting triangles; with an input mesh also: closed iff the input is, and
//!    per component (matched to the input's by nearest bounding box) the same Euler
//!    characteristic and closedness, and the same number of components.
//!
//! \throw InvalidInput for invalid options, node ids out of range, array sizes that do not
//!        match, or non-finite node coordinates.
//! \throw Cancelled if the progress callback returns false.
[[nodiscard]] StitchResult stitch(const SurfaceMesh& surface, const StitchOptions& options = {});

//! As above, and compares the result's topology with the input's (closed iff the input is,
//! same components with the same Euler characteristics). `input` must be the mesh
//! mesh_surface() made `surface` from: the volume compensation's and the fidelity moves'
//! label-image gate read `surface.input_label_staircase` when it is set, not `input`.
[[nodiscard]] StitchResult stitch(const SurfaceMesh& surface, const TriMesh& input,
                                  const StitchOptions& options = {});

}  // namespace nurbsfront
