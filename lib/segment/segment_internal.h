// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal to the segment module: flat face adjacency shared by its .cpp files.

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "nurbsfront/core/mesh_types.h"
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/segment/segment.h"

namespace nurbsfront::segment_detail {

//! The worker count of SegmentOptions::threads (0: all hardware threads).
[[nodiscard]] inline unsigned worker_count(int threads) { return parallel::thread_count(threads); }

//! parallel::for_chunks without a monitor: task(begin, end, worker) over [0, n) in chunks
//! of `chunk` indices on up to `workers` threads (the calling thread is worker 0; worker <
//! workers). A task writes only the results of its own indices, and per-worker state must
//! not change them (results never depend on the thread count). A task's exception is
//! rethrown here once every thread has stopped.
template <class Task>
void parallel_chunks(std::size_t n, unsigned workers, std::size_t chunk, const Task& task) {
  parallel::for_chunks(n, workers, chunk, task);
}

//! Faces as flat arrays: edge i of face f joins vertices[f][i] -> vertices[f][(i + 1) % 3]
//! (counter-clockwise), neighbours[f][i] is the face across it (-1 on the boundary).
struct FaceGraph {
  std::vector<std::array<int, 3>> vertices;
  std::vector<std::array<int, 3>> neighbours;
  std::vector<std::array<int, 3>> halfedges;  // halfedges[f][i]: the halfedge of edge i (inside f)
  std::vector<std::uint8_t> crease;  // bit i set: edge i of the face is a crease
  std::vector<Eigen::Vector3d> points;
  const TriMesh* mesh = nullptr;  // the input, for halfedge walks
  [[nodiscard]] bool is_crease(int f, int i) const { return ((crease[f] >> i) & 1U) != 0; }
  [[nodiscard]] int n_faces() const { return static_cast<int>(vertices.size()); }
};

//! The face graph of a mesh (crease bits all clear), its faces read on `workers` threads.
[[nodiscard]] FaceGraph build_graph(const TriMesh& mesh, unsigned workers = 1);

//! Reusable per-call buffers (sized once per segment() call; no global state).
struct Scratch {
  std::vector<int> vertex_stamp, halfedge_stamp;
  std::vector<Eigen::Vector2d> xy;
  //! Per vertex (valid where vertex_stamp is the current epoch): the border halfedge
  //! leaving it, or -1 where several do (the patch touches itself there).
  std::vector<int> border_out;
  //! Per vertex: the last loop (loop_epoch) that passed it.
  std::vector<int> loop_stamp;
  std::vector<int> face_stamp, face_owner;
  //! Per vertex: its index in the cycle being cut out of a loop, -1 outside that (all -1
  //! between calls; check_projection's split of loops passing a vertex twice).
  std::vector<int> cycle_position;
  //! A face queue for breadth-first searches inside a patch (grown to the largest patch).
  std::vector<int> face_queue;
  int vertex_epoch = 0;
  int loop_epoch = 0;
  int face_epoch = 0;
  explicit Scratch(const TriMesh& mesh)
      : vertex_stamp(mesh.n_vertices(), -1),
        halfedge_stamp(mesh.n_halfedges(), -1),
        xy(mesh.n_vertices()),
        border_out(mesh.n_vertices(), -1),
        loop_stamp(mesh.n_vertices(), -1),
        face_stamp(mesh.n_faces(), -1),
        face_owner(mesh.n_faces(), -1),
        cycle_position(mesh.n_vertices(), -1) {}
};

//! The result of check_projection().
struct ProjectionCheck {
  bool is_simple = true;
  //! Where it fails, when that is local: the vertices of every short extra outer loop, or
  //! of the crossing border segments (up to 256 pairs), so all local folds of a patch can be
  //! cut out at once. Empty when the failure is not local.
  std::vector<int> trouble;
};

//! Whether a patch (its `faces`, with face_patch giving every face's patch) projects onto
//! the plane orthogonal to `axis` as border loops whose segments never cross or touch
//! except at shared vertices, with at most one counter-clockwise (outer) loop.
[[nodiscard]] ProjectionCheck check_projection(const FaceGraph& graph, const std::vector<int>& faces,
                                               const std::vector<int>& face_patch, const Eigen::Vector3d& axis,
                                               Scratch& scratch);

//! The border halfedges of a patch (inside the patch, the face across is another patch's
//! or none), face by face in the order of `faces`.
[[nodiscard]] std::vector<OpenMesh::HalfedgeHandle> patch_border(const FaceGraph& graph, const std::vector<int>& faces,
                                                                 const std::vector<int>& face_patch);

//! check_projection() of the patch with these border halfedges (patch_border()): the cost
//! is that of the border, not of the faces. An empty border (a closed surface) fails.
//! `n_known`: the first n_known border halfedges are known to cross none of each other in
//! this plane (they were all of a patch's border when it passed the check with this axis),
//! so only pairs with a later one are tested for crossings; is_simple is the same, the
//! crossing pairs reported as trouble may be others (also at most 256).
[[nodiscard]] ProjectionCheck check_projection(const FaceGraph& graph,
                                               const std::vector<OpenMesh::HalfedgeHandle>& border,
                                               const std::vector<int>& face_patch,
                                               const Eigen::Vector3d& axis, Scratch& scratch,
                                               std::size_t n_known = 0);

//! narrow_patches(mesh, segmentation, max_width) with the faces' areas and the border edges'
//! lengths computed on `workers` threads (the sums in face and edge order on the calling
//! thread: the same list for any count).
[[nodiscard]] std::vector<int> narrow_patches(const TriMesh& mesh, const Segmentation& segmentation, double max_width,
                                              unsigned workers);

//! Every cliff of a patch (has_cliff()) as vertex ids (lower, higher), each pair once.
struct CliffPairs {
  std::vector<std::array<int, 2>> pairs;
  //! False when the patch has more than kMaxCliffPairs cliffs: `pairs` is then empty.
  bool is_complete = true;
};
//! The longest list has_cliff() makes (a steep wall of n vertices has O(n) pairs).
inline constexpr std::size_t kMaxCliffPairs = std::size_t{1} << 20;

//! Whether two vertices of a patch (of at least kCliffMinFaces faces, mean_edge > 0) form a
//! cliff: closer than kCliffRunEdges mean input edges in the plane orthogonal to `axis`,
//! more than kCliffRiseEdges apart along it, at a rise over run above kCliffMinRiseOverRun
//! (segment.cpp; segment()'s step 7). With `pairs`, every cliff is listed (the search does
//! not stop at the first). A cliff is a property of its two vertices alone, so a part of
//! the patch with the same axis has one exactly when it has kCliffMinFaces faces or more
//! and both vertices of a listed pair (split_folds decides the parts of a bisected patch
//! that way instead of by a new search).
[[nodiscard]] bool has_cliff(const FaceGraph& graph, const std::vector<int>& faces, const Eigen::Vector3d& axis,
                             double mean_edge, Scratch& scratch, CliffPairs* pairs = nullptr);

//! Splits a connected patch of at least two faces in two connected parts: breadth-first
//! regions around two faces far apart (the farthest face from the farthest face of
//! faces[0]).
[[nodiscard]] std::pair<std::vector<int>, std::vector<int>> bisect_patch(
    const FaceGraph& graph, const std::vector<int>& faces, const std::vector<int>& face_patch,
    Scratch& scratch);

//! A unit frame (e1, e2) with e1 x e2 = axis.
[[nodiscard]] std::pair<Eigen::Vector3d, Eigen::Vector3d> plane_frame(const Eigen::Vector3d& axis);

//! Border curves and corners of a finished face -> patch map.
struct Borders {
  std::vector<BorderCurve> curves;
  std::vector<int> corners;
};
//! The curves are smoothed on `workers` threads. pinned (ascending, may be null): vertices
//! that are corners too where they lie on a border (Segmentation::pinned_corners).
[[nodiscard]] Borders extract_borders(const TriMesh& mesh, const std::vector<int>& face_patch,
                                      const BorderSmoothingOptions& options, unsigned workers = 1,
                                      const std::vector<int>* pinned = nullptr);

//! A PatchSplitter's state (face graph, normals, mean edge, last result); defined in
//! segment.cpp.
struct Splitter;
struct SplitterDeleter {
  void operator()(Splitter* splitter) const;
};
using SplitterPtr = std::unique_ptr<Splitter, SplitterDeleter>;

//! segment(mesh, options) with mean_edge = mean_edge_length(mesh) given by a caller that
//! already has it (the pipeline computes it once per remesh). With splitter, *splitter
//! becomes a splitter for the same mesh and options holding segment()'s face graph and
//! normals (split() then does not compute them again).
//! With with_borders false, the result has no curves and no corners (each patch lists no
//! curve): a caller that edits the patches further (split(), merge_into_neighbours())
//! extracts the borders once at the end with with_borders(mesh, options, result). The
//! face -> patch map, axes and counts are the same either way.
[[nodiscard]] Segmentation segment(const TriMesh& mesh, const SegmentOptions& options, double mean_edge,
                                   SplitterPtr* splitter = nullptr, bool with_borders = true);

//! The segmentation with the curves, corners and per-patch curve lists of its face -> patch
//! map (step 8 of segment(), with options.border_smoothing and options.threads): what
//! segment() gives with with_borders true, for a segmentation made without them.
//! \throw InvalidInput when the face labels do not fit the mesh or the patches.
[[nodiscard]] Segmentation with_borders(const TriMesh& mesh, const SegmentOptions& options, Segmentation segmentation);

//! A splitter for mesh and options that computes its face graph and normals at first use
//! (the same as segment()'s), for callers that let segment()'s splitter go to save memory.
[[nodiscard]] SplitterPtr make_splitter(const TriMesh& mesh, const SegmentOptions& options);

//! PatchSplitter::split() on a splitter made by segment() (with_borders: as segment()'s).
//! With checked_input, the caller vouches for what split_patches checks (face labels and
//! patch lists of the splitter's mesh, valid patch ids in `which`; surfmesh's
//! split_unfitted_patches validates its input once and then passes split()'s own results):
//! the pass over every face is not made again.
[[nodiscard]] Segmentation split(Splitter& splitter, const Segmentation& segmentation, const std::vector<int>& which,
                                 bool with_borders = true, bool checked_input = false);

//! Each listed patch bisected (bisect_patch), the parts checked as segment()'s step 7.
[[nodiscard]] Segmentation bisect_patches(Splitter& splitter, const Segmentation& segmentation,
                                          const std::vector<int>& which);

//! merge_patches_into_neighbours() on a splitter made by segment() (its graph and normals;
//! with_borders: as segment()'s).
//! With hairlines (the pipeline's hairline merge, docs/segment.md "Hairline patches"), only
//! a listed patch facing away from every neighbour (for each neighbour's axis some face
//! with raw normal . axis < cos(max_slope_deg)) is joined, only to a neighbour that is
//! not listed itself, and its own faces need not meet the slope bounds for the union's axis,
//! nor those of the hairlines joined to the same neighbour before (the neighbour's own faces
//! still must; the union still passes the projection and cliff checks).
//! With hairlines and steep (the pipeline's opt-in narrow merge of CAD-like meshes), every
//! listed patch is joined whichever way it faces, its own faces exempt from the slope cone
//! but not from the raw orientation floor (raw normal . axis >= kSegmentMinRawNormalDot).
//! exempt (with hairlines; may be null): per input face, 1 for a hairline's face joined
//! before (exempt from the bounds), 2 for a steep patch's face joined before (exempt from the
//! slope cone, not from the raw floor); read and extended, so the marks of an earlier call
//! hold in a later one (sized to the mesh's faces when empty).
//! max_lost_corners >= 0 (the pipeline's fin-strip merge; docs/segment.md "Fin strips: a
//! corner guard, session 19"): a listed patch joins a neighbour only if at most that many of
//! its vertices where 3+ sides meet (patches, the input's boundary counting as one side) are
//! left with fewer than 3 by the join; -1 = no guard. pin_below_deg > 0 (with the guard): a
//! corner left with two sides does not count against the guard, and is kept as a corner
//! (Segmentation::pinned_corners: the fin's tip pinned, docs/segment.md "Fin strips: pinned
//! tips, session 20") where the border turns there: the angle at it between the border
//! vertices two edges away on both sides below pin_below_deg (180 = every such corner);
//! only corners left inside the union count (pinned corners of earlier joins count as
//! corners).
[[nodiscard]] Segmentation merge_into_neighbours(Splitter& splitter, const Segmentation& segmentation,
                                                 const std::vector<int>& which, bool with_borders = true,
                                                 bool hairlines = false, bool steep = false,
                                                 std::vector<std::uint8_t>* exempt = nullptr,
                                                 int max_lost_corners = -1, double pin_below_deg = 0.0);

//! The pipeline's widening of narrow slope-bounded patches (docs/segment.md "Widening narrow
//! patches, session 18"): each listed patch p, in the order given, takes rings of faces from
//! its unlisted neighbours, across edges that are no crease, where a face meets the slope
//! bounds for p's axis (grouping's fits), ring by ring (at most kWidenMaxRings) until its
//! width (2 area / border length of its input faces) is at least min_width. A ring is kept
//! only when p gets wider and passes the projection and cliff checks with its axis, and
//! every neighbour that gave faces stays connected, at least min_width wide and passes the
//! projection check with its axis; else it is undone and p stops. Axes do not change, so
//! segment()'s slope bounds hold for every face. n_widened (may be null): the patches widened.
[[nodiscard]] Segmentation widen_patches(Splitter& splitter, const Segmentation& segmentation,
                                         const std::vector<int>& which, double min_width, bool with_borders = true,
                                         std::size_t* n_widened = nullptr);

}  // namespace nurbsfront::segment_detail
