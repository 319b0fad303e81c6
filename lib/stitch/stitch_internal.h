// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Shared between the stitch sources (not part of the public API).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/parallel.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/stitch/stitch.h"

namespace nurbsfront::stitch_detail {

//! A vertex's position as an Eigen vector.
inline Eigen::Vector3d point(const TriMesh& mesh, TriMesh::VertexHandle v) { return to_eigen(mesh.point(v)); }

//! Node kinds ranked inner 0 < border 1 < corner 2 (a node merges only into one of equal or
//! higher rank).
inline int node_rank(NodeKind kind) {
  switch (kind) {
    case NodeKind::Inner: return 0;
    case NodeKind::Border: return 1;
    case NodeKind::Corner: return 2;
  }
  return 2;
}

//! Node merges of collapse_short_edges: target[g] is the node g merged into (g itself when
//! it stays); moved holds the new positions of survivors, in order (later ones win).
struct NodeMerges {
  std::vector<int> target;
  std::vector<std::pair<int, Eigen::Vector3d>> moved;
  std::size_t n_merges = 0;
};

//! The triangles with a smallest angle below StitchOptions::collapse_below_angle_deg, worst
//! first, get their shortest edge collapsed (either way round) when the removed node is no
//! feature node (is_feature; but a feature corner merges into a feature corner less than
//! 0.05 SurfaceMesh::target_size away at the other end of a one-piece curve, which stays)
//! nor frozen (is_frozen), ranks no higher than the survivor
//! (inner < border < corner), an inner node merges within its patch or into a border node, a
//! border node only into its neighbour along its own curve, a corner only into the other end
//! of a one-piece curve; the survivor goes onto the fitted surface(s) (midpoint) unless it
//! is a corner, a feature node or the removed node was inner (then it stays). A collapse is
//! made only if OpenMesh's link condition holds, no remaining triangle's normal turns by more
//! than acos(min_normal_dot) or degenerates, and the smallest alpha around both nodes grows.
//! Nothing when the option is 0; only inner nodes merge when the SurfaceMesh has no
//! curve_nodes.
NodeMerges collapse_short_edges(const SurfaceMesh& surface, const StitchOptions& options, const StitchResult& assembled,
                                const std::vector<std::uint8_t>& is_feature, const std::vector<std::uint8_t>& is_frozen);

//! True when node a comes just before or after position i of curve c
//! (SurfaceMesh::curve_nodes; a closed curve wraps around).
bool is_next_on_curve(const SurfaceMesh& surface, int c, int i, int a);

//! True when collapsing h leaves two faces on the same three nodes: faces (a, c, d) and
//! (b, c, d) exist, c and d the nodes opposite h (a closed component of four nodes, a
//! tetrahedron, would become two coinciding triangles; ironProt's one-voxel blobs).
bool leaves_duplicate_face(const TriMesh& mesh, TriMesh::HalfedgeHandle h);

//! Replaces the pairs of `pairs` (sorted, each once) that have a face f with
//! is_changed(f) by `fresh` (the pairs of the changed faces now); `pairs` stays sorted,
//! each pair once.
template <class IsChanged>
void replace_pairs(std::vector<std::array<std::uint32_t, 2>>& pairs, IsChanged is_changed,
                   const std::vector<std::array<std::uint32_t, 2>>& fresh) {
  std::erase_if(pairs, [&](const std::array<std::uint32_t, 2>& p) { return is_changed(p[0]) || is_changed(p[1]); });
  pairs.insert(pairs.end(), fresh.begin(), fresh.end());
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

//! The values keep(i, value) sets for the indices i in [0, n) where it returns true, in index
//! order: keep is called once per index on up to n_threads threads (parallel::for_chunks,
//! chunks of `chunk` indices), each chunk's values kept in order and the chunks joined in
//! order, so the list is the serial loop's at every thread count. keep only reads shared
//! state. For the whole-mesh scans of the stitch's serial stages (their candidate lists).
template <class T, class Keep>
std::vector<T> select_in_order(std::size_t n, unsigned n_threads, std::size_t chunk, const Keep& keep) {
  std::vector<T> out;
  if (n_threads <= 1 || n <= chunk) {
    T value{};
    for (std::size_t i = 0; i < n; ++i) {
      if (keep(i, value)) out.push_back(value);
    }
    return out;
  }
  std::vector<std::vector<T>> parts((n + chunk - 1) / chunk);
  parallel::for_chunks(n, n_threads, chunk, [&](std::size_t begin, std::size_t end, unsigned) {
    std::vector<T>& part = parts[begin / chunk];
    T value{};
    for (std::size_t i = begin; i < end; ++i) {
      if (keep(i, value)) part.push_back(value);
    }
  });
  std::size_t total = 0;
  for (const auto& part : parts) total += part.size();
  out.reserve(total);
  for (const auto& part : parts) out.insert(out.end(), part.begin(), part.end());
  return out;
}

//! The sine of the smallest interior angle of triangle (a, b, c): twice the area over the
//! product of the two longest edges (the smallest angle is at most 60 deg, so the sine orders
//! it); 0 for a degenerate triangle.
inline double smallest_angle_sine(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double x = (b - a).squaredNorm(), y = (c - b).squaredNorm(), z = (a - c).squaredNorm();
  // The middle and the largest of the three (what sorting them gives, without the sort's
  // call: the same values, so the same sine bit for bit).
  const double largest = std::max(std::max(x, y), z);
  const double middle = std::max(std::min(x, y), std::min(std::max(x, y), z));
  const double product = std::sqrt(middle * largest);
  return product > 0.0 ? (b - a).cross(c - a).norm() / product : 0.0;
}

//! True when triangle (a, b, c) has an angle above 90 deg.
inline bool triangle_is_obtuse(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return (b - a).dot(c - a) < 0.0 || (a - b).dot(c - b) < 0.0 || (a - c).dot(b - c) < 0.0;
}

//! False only when triangle (a, b, c) surely has no angle below the angle whose sine is
//! sin_bound (an angle below 60 deg): the sine of its smallest angle (twice the area over the
//! product of the two longest edges, off by a few ulps of 1 at most, slivers included)
//! exceeds sin_bound by far more than that rounding and triangle_angles_deg()'s. A cheap
//! pre-test that spares most triangles triangle_angles_deg()'s three atan2; the triangles
//! it lets through are measured as before, so the answers do not change.
inline bool may_have_angle_below(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                 double sin_bound) {
  constexpr double kSineMargin = 1e-9;
  return !(smallest_angle_sine(a, b, c) > sin_bound + kSineMargin);
}

//! The one projection of a stitch move (smoothing, obtuse repair, obtuse splits, short-edge
//! collapse, small-angle repair): target moved onto the mean of its projections onto the
//! fitted surfaces of `patches` (PatchSurface::project, in that order); NaN when one of them
//! is detail-fitted (SurfaceMesh::patches[p].detail_fit) and has none of its input faces
//! straight above or below target along its axis (PatchSurface::project cannot hold the node
//! within the patch's node bound there). A caller leaves a node with a NaN target where it is.
Eigen::Vector3d project_onto_patches(const SurfaceMesh& surface, std::span<const int> patches,
                                     const Eigen::Vector3d& target);

//! q, or the point of segment (origin, q) at distance r from origin when q lies farther (the
//! fin rim bound, StitchOptions::fin_rim_max_move).
inline Eigen::Vector3d clamp_to_ball(const Eigen::Vector3d& q, const Eigen::Vector3d& origin, double r) {
  const Eigen::Vector3d d = q - origin;
  const double l = d.norm();
  return l > r ? Eigen::Vector3d(origin + (r / l) * d) : q;
}

//! One change of the small-angle repair: a flip of the edge between from and to, a
//! collapse of from into to (which stays where it is), or a move of from to q.
struct AngleChange {
  enum class Kind { Flip, Collapse, Move } kind = Kind::Flip;
  TriMesh::VertexHandle from, to;
  Eigen::Vector3d q = Eigen::Vector3d::Zero();
};

//! The faces of mesh (deleted ones left out) with no feature node (is_feature, per node;
//! vertex_node maps vertices to nodes) whose smallest_angle_sine (corners in the
//! face-vertex circulator's order) is below sin_bound, as (sine, face index) in face order;
//! the scan on n_threads threads (select_in_order, `chunk` faces a task), the same list at
//! every count. The small-angle repair's candidates.
std::vector<std::pair<double, int>> small_away_faces(const TriMesh& mesh, const std::vector<int>& vertex_node,
                                                     const std::vector<std::uint8_t>& is_feature, double sin_bound,
                                                     unsigned n_threads, std::size_t chunk = 8192);

//! Makes `changes` on result.mesh in order, all or none: when an edge of one is gone or
//! OpenMesh refuses it (is_flip_ok, is_collapse_ok), the changes made before it are undone
//! (result's mesh, face_patch and vertex_node as they were) and false is returned. touched
//! (if given) is set to the vertices whose triangles the changes made (a flip's new edge's
//! ends, a collapse's survivor, a moved vertex); empty when false is returned.
bool make_angle_changes(StitchResult& result, std::span<const AngleChange> changes,
                        std::vector<TriMesh::VertexHandle>* touched = nullptr);

//! Where v goes to leave triangle g (of another sheet its triangles cross) behind: along v's
//! ring normal (area-weighted; g's normal instead when the two are more than 60 deg apart), to
//! the side of g's plane where the mean of v's ring neighbours lies, until v's height over that
//! plane is max(its height, 0) + factor x the neighbours' mean height. NaN when the neighbours'
//! mean lies on the plane, the move is longer than max_offset, or a triangle of v's then
//! degenerates (twice its area at most min_double_area), turns its normal by more than
//! acos(min_normal_dot), or more of them are below the angle whose sine is sin_bound or obtuse.
//! The small-angle repair moves the nodes its changes made of a crossing pair so (factors 1, 2,
//! 4; a fin rim node only within its bound) before it gives the changes up
//! (repair_small_angles; the moves counted in StitchReport::n_angle_moves).
Eigen::Vector3d push_away(const TriMesh& mesh, TriMesh::VertexHandle v, TriMesh::FaceHandle g, double factor,
                          double max_offset, double min_double_area, double min_normal_dot, double sin_bound);

//! What repair_small_angles() did.
struct AngleRepairResult {
  std::size_t n_flips = 0, n_collapses = 0, n_moves = 0;
  std::size_t n_obtuse_collapses = 0;  //!< collapses of the obtuse sweep (not in n_collapses)
  //! Nodes moved away from another sheet their changes crossed (not counted above).
  std::size_t n_pushes = 0;
  std::size_t n_two_steps = 0;  //!< pairs of changes (each also counted above)
  std::size_t n_searches = 0;   //!< moves of the finer search (each also counted in n_moves)
  std::size_t n_undone = 0;  //!< changes given up because their triangles crossed others
};

//! StitchOptions::angle_repair_rounds sweeps over the triangles with no feature node
//! (is_feature, per node) and a smallest angle below kAwayFromFeaturesAngleBoundDeg, worst
//! first: each gets the best of a flip of one of its edges (dihedral and side tests as the
//! optimisation's flips) or a collapse of one of its edges into the other end, which stays
//! (the removed node no feature node, on no boundary, ranking no higher than the survivor:
//! inner < border < corner; link condition; no duplicate face; no normal turned by more than
//! acos(min_normal_dot); the removed node within half an input mean edge of the new
//! triangles), when the triangles it touches then have a larger smallest angle, no more of
//! them below the bound (a collapse: fewer) and no more obtuse ones; where no single change
//! is better, the best pair of changes there that is (docs/stitch.md "two-step changes"). When
//! check_self_intersections, the faces around the changes are checked exactly; if some
//! cross, the nodes a change made on them move away from the faces they cross (push_away), and
//! if some still cross, the mesh goes back and the repair is made again with the nodes of the crossing
//! faces that a change made left alone (4 rounds). Collapses are garbage-collected (face_patch and vertex_node
//! follow).
AngleRepairResult repair_small_angles(const SurfaceMesh& surface, const StitchOptions& options,
                                      const std::vector<std::uint8_t>& is_feature, StitchResult& result);

//! StitchOptions::chord_compensation: moves the nodes that are no feature node (is_feature,
//! per node; vertex_node maps vertices to nodes) nor on the boundary along their normals so
//! that the triangles are on average on the surface through their corners, less the chords
//! an edge of length reference_edge has (0: none). Returns the number of nodes moved. The
//! per-face terms on n_threads threads, their sums in face order (the same moves at every count).
std::size_t compensate_chords(TriMesh& mesh, const std::vector<int>& vertex_node, const std::vector<std::uint8_t>& is_feature,
                              double strength, double reference_edge, unsigned n_threads = 1);

//! to_soup(mesh), the same points and triangles (each from its face's halfedge, as the
//! face-vertex circulator goes), read from the halfedges directly instead of through
//! circulators (to_soup: about 120 instructions a face); to_soup itself for a mesh with
//! deleted elements.
TriangleSoup mesh_soup(const TriMesh& mesh);

//! Every vertex's position, in vertex order.
std::vector<Eigen::Vector3d> vertex_points(const TriMesh& mesh);

//! 1 for each vertex on the boundary or at a feature node (creases and their corners), in
//! vertex order: what the chord and volume compensations do not move.
std::vector<std::uint8_t> fixed_vertices(const TriMesh& mesh, const std::vector<int>& vertex_node,
                                         const std::vector<std::uint8_t>& is_feature);

//! StitchOptions::fin_rim_max_move for every stage: the nodes of the fin rim curves
//! (SurfaceMesh::curve_is_fin_rim, corners included) stay within `radius` (the option times
//! SurfaceMesh::input_mean_edge) of where the front put them (SurfaceMesh::nodes). A merge
//! moves its removed node onto the survivor. Nothing is bounded when the option is infinite,
//! nor the nodes made by obtuse splits (no SurfaceMesh node).
struct FinRimBound {
  std::vector<std::uint8_t> on_rim;  //!< per SurfaceMesh node; empty: no bound
  double radius = std::numeric_limits<double>::infinity();
  const std::vector<Eigen::Vector3d>* origins = nullptr;  //!< SurfaceMesh::nodes
  //! A clamped position is at the radius up to rounding: allowed with this relative slack.
  static constexpr double kSlack = 1e-12;
  bool is_bounded(int node) const {
    return node >= 0 && static_cast<std::size_t>(node) < on_rim.size() && on_rim[static_cast<std::size_t>(node)] != 0;
  }
  //! True when node may be at q.
  bool allows(int node, const Eigen::Vector3d& q) const;
  //! q, or the point of the segment from node's origin to q at the radius when q lies beyond.
  Eigen::Vector3d clamp(int node, const Eigen::Vector3d& q) const;
};
FinRimBound fin_rim_bound(const SurfaceMesh& surface, const StitchOptions& options);
//! Per SurfaceMesh node, 1 for a node of a fin rim curve (SurfaceMesh::curve_is_fin_rim,
//! corners included); empty when there is none or the curves' node lists are missing.
std::vector<std::uint8_t> fin_rim_nodes(const SurfaceMesh& surface);

//! Moves every vertex of a bounded node (vertex_node) that lies beyond the bound back onto it,
//! towards its origin (after the chord and volume compensations). Returns the number moved.
std::size_t hold_fin_rim_nodes(TriMesh& mesh, const std::vector<int>& vertex_node, const FinRimBound& bound);

//! Moves each vertex that is an inner node of a detail-fitted patch (SurfaceMesh::patches[p].
//! detail_fit) back within the patch's PatchSurface::max_offset of its input faces along the
//! patch axis, keeping its other two coordinates (after the chord compensation, which moves
//! nodes along their normals). Returns the number of vertices moved.
std::size_t hold_detail_nodes(TriMesh& mesh, const SurfaceMesh& surface, const std::vector<int>& vertex_node);

//! The mean of f over the triangle abc, exact for f quadratic: the triangle cut into 9
//! similar ones, each by the mean of f at its edge midpoints, i.e. f at the 18 points
//! (i a + j b + k c) / 6 with i + j + k = 6 and two of i, j, k odd, weight 1 on abc's border
//! (one index 0: one sub-triangle's edge), 2 inside (two sub-triangles'), the sum over 27.
//! The lattice of step 1/3 (10 points, exact for linear f) reads the bulge l1 l2 + l2 l3 +
//! l3 l1 of a flat triangle under a curved surface as 1/6 where its mean is 1/4.
template <class F>
double mean_over_triangle(F&& f, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  double sum = 0.0;
  for (int i = 0; i <= 6; ++i) {
    for (int j = 0; i + j <= 6; ++j) {
      const int k = 6 - i - j;
      if (i % 2 + j % 2 + k % 2 != 2) continue;
      const double weight = i == 0 || j == 0 || k == 0 ? 1.0 : 2.0;
      sum += weight * f(Eigen::Vector3d((i * a + j * b + k * c) / 6.0));
    }
  }
  return sum / 27.0;
}

//! StitchOptions::volume_compensation: every triangle's volume between it and its patch's
//! input faces, measured along the patch axis (mean_over_triangle of the height difference
//! over the triangle's area projected on the patch plane; patches with
//! PatchSurface::input_heights; others add nothing), is shared by its corners that are no
//! feature node nor on the boundary (a triangle with none gives it to its patch's such
//! nodes, by area); each such node moves along its normal to take its share back, times
//! strength, at most 0.1 of its root-mean-square edge (the volume beyond that handed to its
//! free neighbours by area, four rounds), half that or not at all where the
//! move would add an obtuse triangle around it or take one of its triangles' smallest angle
//! below min(that triangle's old one, kAwayFromFeaturesAngleBoundDeg). Nothing when input
//! (may be null) is a label image's staircase (surfmesh_detail::on_label_image_staircase;
//! label_gate_done: the caller has tested that already, and input is still used for the
//! enclosed-volume check). With a closed input and mesh, nothing is measured nor moved when
//! the mesh's enclosed volume is already within skip_within of the input's (relative; then
//! *skipped is set, when given), and the moves are undone when they do not bring the
//! enclosed volume nearer the input's. The measure runs on n_threads threads (the same
//! moves for any count). Returns the number of nodes moved.
struct VolumeCompensation {
  double strength = 1.0;        //!< StitchOptions::volume_compensation
  double skip_within = 0.0;     //!< StitchOptions::volume_compensation_skip_within
  bool label_gate_done = false;  //!< the caller has tested the label-image gate
  unsigned n_threads = 1;
};
std::size_t compensate_volume(const SurfaceMesh& surface, const TriMesh* input, TriMesh& mesh,
                              const std::vector<int>& face_patch, const std::vector<int>& vertex_node,
                              const std::vector<std::uint8_t>& is_feature, const VolumeCompensation& how,
                              bool* skipped = nullptr);

//! Enclosed volume of mesh (the sum of a . (b x c) / 6 over its faces, deleted ones skipped):
//! the terms on n_threads threads, summed in face order (the same double at every count).
double enclosed_volume_of(const TriMesh& mesh, unsigned n_threads);
//! No vertex of mesh is on its boundary.
bool is_closed(const TriMesh& mesh);

//! alpha of every face (not deleted), in face order; the faces on n_threads threads
//! (select_in_order, `chunk` faces a task): the same list at every count.
std::vector<double> face_alphas(const TriMesh& mesh, unsigned n_threads = 1, std::size_t chunk = 8192);

//! Edge flips and constrained smoothing (StitchOptions::optimisation_passes rounds) on
//! result.mesh; result.face_patch stays valid (flips keep face handles).
//! is_feature: per node, 1 for a feature node (never moves); other corners move too.
void optimise(const SurfaceMesh& surface, const StitchOptions& options, const std::vector<std::uint8_t>& is_feature,
              StitchResult& result, StitchReport& report);

//! One sweep of the obtuse repair (its flips, then its moves) over the whole mesh, as
//! optimise() ends with; returns {flips, moves}. Run again after the volume compensation,
//! whose moves can make triangles obtuse that the splits then cannot take apart.
std::array<std::size_t, 2> repair_obtuse_once(const SurfaceMesh& surface, const StitchOptions& options,
                                              const std::vector<std::uint8_t>& is_feature, StitchResult& result);

//! What split_obtuse() did.
struct SplitResult {
  std::size_t n_splits = 0, n_flips = 0, n_moves = 0;
  std::vector<TriMesh::VertexHandle> made;           //!< the new vertices
  std::vector<std::array<int, 2>> split_edges;       //!< the split edges' end vertices (smaller first), per new vertex
  //! Per vertex, 1 for the new vertices and their ring neighbours after the splits: every
  //! face changed by the splits, their flips and the repair after them has one of these.
  std::vector<std::uint8_t> near;
};

//! StitchOptions::obtuse_split_rounds sweeps of obtuse splits on result.mesh (face_patch,
//! vertex_node and is_feature grow), then the obtuse repair's flips and moves once on the
//! edges and vertices around the new vertices. Edges in `refused` (sorted vertex pairs)
//! are not split. No intersection check (the caller's).
SplitResult split_obtuse(const SurfaceMesh& surface, const StitchOptions& options, std::vector<std::uint8_t>& is_feature,
                         StitchResult& result, const std::vector<std::array<int, 2>>& refused);

//! Where the fidelity moves measure (StitchOptions::fidelity_gate_edges).
struct FidelityGate {
  //! Per input face: 1 when measured (a corner of it, or of a face sharing a corner with it,
  //! is farther from its patch's fit than the gate). Empty: everything is measured.
  std::vector<std::uint8_t> input_face;
  std::vector<std::uint8_t> patch;  //!< per patch: 1 when it holds a measured face (its output vertices are measured)
};

//! The gate of options.fidelity_gate_edges over surface (its fits, input_face_patch): empty
//! (everywhere) for a gate of 0 or when input_face_patch does not hold one patch per input face.
//! The fits are evaluated on options.n_threads (the same gate for any count).
FidelityGate fidelity_gate(const SurfaceMesh& surface, const TriMesh& input, const StitchOptions& options);

//! What move_toward_input() did.
struct FidelityResult {
  std::size_t n_moved = 0;   //!< vertices left at another place
  std::size_t n_split = 0;   //!< new vertices on input vertices (edge splits)
  std::size_t n_undone = 0;  //!< moves put back because their triangles crossed others
  std::size_t n_sweeps_changing = 0;  //!< sweeps that moved or split something
  //! Face samples the first sweep left out, checked again by a later sweep (their vouching
  //! output face changed), and of them those no longer within the bound of it (made samples).
  std::size_t n_rechecked = 0, n_promoted = 0;
};

//! StitchOptions::fidelity_distance_edges (times reference_edge, the input's mean edge): up
//! to four sweeps; each measures, for every vertex that is no feature node nor on the
//! boundary (is_feature per node), its distance to the input, and for every input vertex
//! its distance to the output. Candidates farther than the bound, farthest first: a vertex
//! goes onto its closest input point; an input vertex pulls the nearest corner of its
//! nearest output face onto itself. A move (all the way, else half way) is made when no
//! triangle around the vertex degenerates or turns its normal by more than
//! acos(min_normal_dot), their smallest alpha stays at least min(old, alpha_floor), their
//! smallest angle at least min(old, angle_floor_deg), no more of them are obtuse, the
//! candidate's distance falls by 5% at least and the largest distance to the input of the
//! triangles (samples on a 1/3 lattice) and of the input vertices nearest to them does not
//! grow. A moved vertex and its neighbours wait for the next sweep. A fin rim node (rim)
//! moves only within its bound. When check_self_intersections, moves on triangles that
//! cross others are put back (four rounds, then all of them). Nothing for a bound of 0 or an
//! empty input. The input's samples are its vertices and those of its face samples that
//! no output face of their face's corners (the first sweep's) holds within the bound (a
//! face whose corners are within the bound of one output face is wholly: those can be no
//! candidates); the first sweep's queries run on options.n_threads (the same result for
//! any count). A move or split keeps each triangle's alpha at min(old, fidelity_alpha_floor).
//! incremental: the first sweep searches an input sample in the output's tree
//! only when a walk over the output's faces from the last sample's face (Morton order) does
//! not end on a face within the bound (the same candidates as a full search; the walk's face
//! stands for the nearest one in the checks); after the first sweep only the vertices and
//! input samples near the last sweep's changes are measured again and only the candidates
//! whose checks read a changed place are tried. false measures and tries everything in
//! every sweep. input_index: to_soup(input) and its tree when the caller has them (shared
//! with the report's distance pass; nullptr: built here); the same result either way.
//! gate: where the moves measure (StitchOptions::fidelity_gate_edges; nullptr or empty: everywhere).
FidelityResult move_toward_input(const TriMesh& input, const StitchOptions& options,
                                 std::vector<std::uint8_t>& is_feature, double reference_edge, const FinRimBound& rim,
                                 StitchResult& result, bool incremental = true,
                                 const quality_detail::IndexedSoup* input_index = nullptr,
                                 const FidelityGate* gate = nullptr);

//! stitch(surface, input, options) with to_soup(input) and its tree over all faces given
//! (the fidelity moves query them; the caller builds them once and shares them, e.g. with the
//! report's distance pass): the same result.
//! \throw InvalidInput when the index's point or triangle count is not the input's.
StitchResult stitch_with_input_index(const SurfaceMesh& surface, const TriMesh& input,
                                     const quality_detail::IndexedSoup& input_index, const StitchOptions& options);

//! The first sweep's candidates of move_toward_input() (tests and measurements).
struct FidelityCandidates {
  //! Input samples (index: the input's vertices, then per face its centroid and edge
  //! midpoints) and output vertices farther than the bound, with their distances, by index.
  std::vector<std::pair<std::uint32_t, double>> samples, vertices;
  std::size_t n_walked = 0;    //!< samples the walk alone showed within the bound
  std::size_t n_searched = 0;  //!< samples searched in the output's tree
  //! Face samples left out: their face's corners are within the bound of one output face.
  std::size_t n_certified = 0;
  //! With sweeps_before > 0: the moves and splits of those sweeps, the left-out samples
  //! checked again and made samples by them (and by the recorded sweep), and the output the
  //! recorded sweep measured.
  std::size_t n_changed_before = 0, n_rechecked = 0, n_promoted = 0;
  std::vector<std::uint32_t> promoted;  //!< the samples made so (sorted; numbered as samples)
  //! After those sweeps: the output faces whose largest sample distance to the input the
  //! moves keep (their old rings' distances), and of them those whose kept figure is not
  //! the one measured afresh where the face is now (0 when the kept figures are right).
  std::size_t n_kept_face_distances = 0, n_stale_face_distances = 0;
  TriMesh mesh;
};

//! The samples and vertices farther than the bound that move_toward_input()'s sweep number
//! sweeps_before + 1 measures (after sweeps_before sweeps that move), without moving
//! anything in it: walk = true is its incremental way (the first sweep searches a sample in
//! the output's tree only when a walk over the output from the last sample's face does not
//! end within the bound; later sweeps measure again only near the changes), false searches
//! every sample in every sweep.
FidelityCandidates fidelity_candidates(const TriMesh& input, const StitchOptions& options,
                                       std::vector<std::uint8_t> is_feature, double reference_edge, StitchResult result,
                                       bool walk, int sweeps_before = 0);

//! The old index of every kept element after collect_garbage() (vertices, faces).
struct GarbageMaps {
  std::vector<int> vertex, face;
};

//! mesh.garbage_collection() with the same result bit for bit (element order, every
//! handle, properties): each kind's first deleted element swaps items and properties with
//! its last kept one until they meet, the arrays are cut and the kept elements' handles
//! mapped, as in OpenMesh 9. Returns the kept elements' old indices.
GarbageMaps collect_garbage(TriMesh& mesh);

//! collect_garbage(result.mesh) with result.face_patch and result.vertex_node carried along.
GarbageMaps collect_garbage(StitchResult& result);

//! All self-intersecting pairs of `after` (sorted, each once: self_intersecting_pairs(after)),
//! from `before_pairs`, all the pairs of `before` (sorted), where `after` is `before` with
//! some triangles changed (other corners, or a corner moved), removed or renumbered:
//! old.vertex / old.face name the index in `before` of every point / triangle of `after`
//! (collect_garbage's maps; empty: the same indices). A pair of two triangles `before` has as
//! they are (same corners in the same order, same positions) is kept; the other triangles
//! are checked again against all of `after` (intersecting_pairs_of). The pair test depends
//! only on the two triangles' corners, their coincidences and the degenerate-area tolerance
//! (from the bounding box's diagonal): when that diagonal differs, all of `after` is
//! counted again.
std::vector<std::array<std::uint32_t, 2>> recount_pairs(const TriangleSoup& before,
                                                        const std::vector<std::array<std::uint32_t, 2>>& before_pairs,
                                                        const TriangleSoup& after, const GarbageMaps& old,
                                                        unsigned n_threads);

//! Intersecting pairs left after the optimisation's repair, i.e. of the assembled mesh
//! (`pairs`: all pairs of result.mesh, sorted, updated in place). Per pair, the nodes of
//! both triangles that are neither feature nodes nor on the input's boundary move to the
//! mean of their projections onto the input faces of the patches around them, along each
//! patch's axis (PatchSurface::project with no offset; not when a patch has no input
//! heights). The moves are kept when no triangle around the moved nodes degenerates or
//! turns its normal by more than acos(min_normal_dot), and those triangles then intersect in
//! fewer pairs than before (exact check against the whole mesh). Then each edge of a
//! triangle still crossing (not a segment of a feature curve: a chord between two feature
//! corners may flip; flippable) is flipped when both new triangles keep the old side and
//! take part in fewer pairs. Then each edge of a
//! triangle still crossing (shortest first) is collapsed into one of its ends, which stays,
//! when the removed node is no feature node (or a feature curve's node merging into its
//! neighbour along the curve) nor on the input's boundary, the link condition holds, the
//! removed node lies within one input mean edge of the new triangles, none of these folds
//! over or degenerates, and they take part in fewer pairs. Up to 3 rounds. Counts in
//! report.n_settled_nodes, n_settled_flips and n_settled_collapses. After a collapse the
//! mesh is garbage-collected (face_patch and vertex_node follow), `pairs` is left empty (the
//! caller counts again, recount_pairs) and the garbage collection's maps are returned (else
//! empty maps: indices unchanged).
GarbageMaps settle_intersections(const SurfaceMesh& surface, const StitchOptions& options,
                          const std::vector<std::uint8_t>& is_feature, StitchResult& result,
                          std::vector<std::array<std::uint32_t, 2>>& pairs, StitchReport& report);

}  // namespace nurbsfront::stitch_detail
