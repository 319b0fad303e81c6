// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal to the segment module: flat face adjacency shared by its .cpp files.

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <exception>
#include <limits>
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

//! The projection checks of merges into patches that passed check_projection() with their
//! axis (merge_patches after the fold splits), made incrementally: each receiving patch keeps
//! its border segments (projected), its loops' areas and the count of vertices its border
//! passes twice, so a merge costs the small patch's border and a scan of the receiver's
//! segments instead of tracing every loop again. check() answers what check_projection() of
//! the merged border would answer (is_simple), or "unknown" where the merge is not the simple
//! case (the receiver's axis changes, the border passes a vertex twice, the shared border is
//! not one run, a loop's orientation is too close to call): the caller then checks in full.
//! An area's sign is taken only when it is farther from zero than a bound on the rounding of
//! both sums (this one's, kept with fixed origin, and check_projection()'s), so it is the sign
//! check_projection() computes. Crossings are tested between the new segments and all others,
//! the receiver's own being known not to cross (it passed the check with this axis).
class MergeProjection {
 public:
  explicit MergeProjection(const FaceGraph& graph);
  //! Before the faces of patch `from` join patch `into` (face_patch still has them as
  //! from's): the two patches' current borders (patch_border()), into's axis before the
  //! merge and the merged patch's axis.
  void prepare(int into, int from, const std::vector<OpenMesh::HalfedgeHandle>& into_border,
               const std::vector<OpenMesh::HalfedgeHandle>& from_border, const std::vector<int>& face_patch,
               const Eigen::Vector3d& old_axis, const Eigen::Vector3d& new_axis);
  //! After the faces changed hands: 1 the merged patch passes check_projection() with the
  //! new axis, 0 it does not, -1 unknown.
  [[nodiscard]] int check(const std::vector<int>& face_patch);
  //! The merge of the last prepare() is kept (it passed).
  void keep();
  //! Checks that took the incremental path (answered 0 or 1), for tests.
  [[nodiscard]] std::size_t n_incremental() const { return n_incremental_; }

 private:
  struct Loop {
    double sum = 0.0, error = 0.0;  // twice the area (origin fixed per patch), bound on its rounding
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());  // a box around
    Eigen::Vector2d hi = -lo;                                                                 // its vertices
    std::size_t n = 0;               // segments; 0: gone
    void add(const Eigen::Vector2d& origin, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double sign);
    [[nodiscard]] int sign() const;  // +1, -1, 0: too close to call
  };
  struct Segment {
    int h = -1, a = -1, b = -1;  // halfedge, from and to vertex
    Eigen::Vector2d xa, xb;
  };
  struct PatchState {
    int pinched = -1;  // vertices with two or more outgoing border halfedges; -1 unknown
    bool has_loops = false;  // the loops and segments below are those of the current border
    Eigen::Vector3d axis = Eigen::Vector3d::Zero();
    Eigen::Vector2d origin = Eigen::Vector2d::Zero();
    std::vector<Loop> loops;
    std::size_t n_live = 0, n_outer = 0, n_unsure = 0;
    std::vector<Segment> segments;
  };
  void build(PatchState& state, const std::vector<OpenMesh::HalfedgeHandle>& border, bool with_loops);
  [[nodiscard]] int degree(int v, int patch, const std::vector<int>& face_patch) const;
  [[nodiscard]] Eigen::Vector2d xy(int v) const;

  const FaceGraph& graph_;
  std::vector<PatchState> states_;
  std::vector<int> vertex_stamp_, vertex_out_, halfedge_stamp_, halfedge_pos_, halfedge_loop_, halfedge_slot_;
  int vertex_epoch_ = 0, halfedge_epoch_ = 0;
  Eigen::Vector3d e1_ = Eigen::Vector3d::UnitX(), e2_ = Eigen::Vector3d::UnitY();  // the frame of the patch being checked
  // The attempt between prepare() and keep().
  struct Pending {
    int into = -1, from = -1;
    Eigen::Vector3d axis = Eigen::Vector3d::Zero();
    std::vector<OpenMesh::HalfedgeHandle> from_border;
    std::vector<int> vertices;  // from's border vertices
    int removed_pinched = 0;
    int pinched = -1;     // the merged patch's, -1 unknown
    bool incremental = false;
    std::vector<int> shared;  // into's border halfedges that become inner ones
    std::vector<Segment> added;  // from's that stay border
    std::vector<int> added_loop;  // per added segment: -1 the loop it joins, else index into new_loops
    int joined = -1;  // into's loop the run joins (or that closes, when `closes`)
    bool closes = false;
    Loop joined_after;
    std::vector<Loop> new_loops;
    std::size_t n_live = 0, n_outer = 0;
  } pending_;
  std::size_t n_incremental_ = 0;
};

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
//! The curves are smoothed on `workers` threads.
[[nodiscard]] Borders extract_borders(const TriMesh& mesh, const std::vector<int>& face_patch,
                                      const BorderSmoothingOptions& options, unsigned workers = 1);

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
[[nodiscard]] Segmentation split(Splitter& splitter, const Segmentation& segmentation, const std::vector<int>& which,
                                 bool with_borders = true);

//! Each listed patch bisected (bisect_patch), the parts checked as segment()'s step 7.
[[nodiscard]] Segmentation bisect_patches(Splitter& splitter, const Segmentation& segmentation,
                                          const std::vector<int>& which);

//! merge_patches_into_neighbours() on a splitter made by segment() (its graph and normals;
//! with_borders: as segment()'s).
[[nodiscard]] Segmentation merge_into_neighbours(Splitter& splitter, const Segmentation& segmentation,
                                                 const std::vector<int>& which, bool with_borders = true);

}  // namespace nurbsfront::segment_detail
