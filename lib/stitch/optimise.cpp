// SPDX-License-Identifier: BSD-3-Clause
// Cross-border optimisation of the stitched mesh: edge flips and smoothing constrained to
// the fitted patch surfaces. Both sweeps run in index order (Gauss-Seidel), so the
// result depends only on the input (the flips' tests run in parallel, with the same flips).
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <queue>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/disjoint_sets.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/surfmesh/surfmesh_internal.h"
#include "nurbsfront/stitch/stitch_internal.h"
#include "nurbsfront/stitch/sweep_schedule.h"

namespace nurbsfront::stitch_detail {

namespace {

using Vec = Eigen::Vector3d;

// Twice the area vector (a, b, c counter-clockwise).
Vec area_vector(const Vec& a, const Vec& b, const Vec& c) { return (b - a).cross(c - a); }

// triangle_alpha(a, b, c) with twice_area = |area_vector(a, b, c)| already known: the same
// operations in the same order (the same cross product), so the same value bit for bit.
double alpha_with_area(const Vec& a, const Vec& b, const Vec& c, double twice_area) {
  const double sum_sq = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  if (!(sum_sq > 0.0)) return 0.0;
  const double area = 0.5 * twice_area;
  return 4.0 * std::numbers::sqrt3 * area / sum_sq;
}

// alpha (as alpha_with_area) and the sine of the smallest interior angle of (a, b, c):
// twice the area over the product of the two longest edges (the smallest angle is below
// 90 deg, so its sine orders it; 0 for a degenerate triangle), from one set of squared
// edge lengths. twice_area = |area_vector(a, b, c)|. With alpha above skip_sine_above the
// sine is not computed and 1 is returned in its place (see Optimiser::alpha_sine_skip_).
std::array<double, 2> alpha_and_min_angle_sine(const Vec& a, const Vec& b, const Vec& c, double twice_area,
                                               double skip_sine_above = std::numeric_limits<double>::infinity()) {
  const double x = (b - a).squaredNorm(), y = (c - b).squaredNorm(), z = (a - c).squaredNorm();
  const double sum_sq = x + y + z;
  const double area = 0.5 * twice_area;
  const double alpha = sum_sq > 0.0 ? 4.0 * std::numbers::sqrt3 * area / sum_sq : 0.0;
  if (alpha > skip_sine_above) return {alpha, 1.0};
  // The middle and the largest of the three squared edges (what sorting them gives, without
  // the sort: the same values, so the same sine bit for bit; smallest_angle_sine alike).
  const double largest = std::max(std::max(x, y), z);
  const double middle = std::max(std::min(x, y), std::min(std::max(x, y), z));
  const double product = std::sqrt(middle * largest);
  return {alpha, product > 0.0 ? twice_area / product : 0.0};
}

// What the optimisation may do with a vertex.
struct NodeInfo {
  bool is_movable = false;  // inner node, or border node of a non-feature curve between two patches
  int patch0 = -1;          // inner: its patch; border: the two patches it lies between
  int patch1 = -1;
  int curve = -1;           // border: its curve; -1 otherwise
  bool is_corner = false;
  int corner_slot = -1;     // movable corner: index into Optimiser::corner_patches_
  // A node of a fin rim curve (StitchOptions::fin_rim_max_move): its moves stay within
  // max_move of origin, where the front put it; infinity: no bound.
  double max_move = std::numeric_limits<double>::infinity();
  Vec origin = Vec::Zero();
};

class Optimiser {
  // The far corners of a smoothed vertex p's triangles (p, b, c), with their area vector
  // and its norm at p's old position.
  struct RingTriangle {
    Vec b, c, n_old;
    double l_old;
  };

  // A split of split_sweep: the halfedge (a, b) split, the new node m and its NodeInfo (on the
  // segment: a feature node), the edges to flip after it; best: its obtuse new triangles
  // (evaluate_split), -1 when no split of the edge passes.
  struct SplitPlan {
    TriMesh::HalfedgeHandle h;
    Vec m = Vec::Zero();
    NodeInfo info;
    bool on_segment = false, one_sided = false;
    int best = -1;
    std::vector<std::array<TriMesh::VertexHandle, 2>> flips;
  };

  // Scratch of plan_edge_split (one per thread): the flips of a split tried and of the best
  // one so far.
  struct SplitScratch {
    std::vector<std::array<TriMesh::VertexHandle, 2>> flips, best_flips;
  };

  // Per feature corner node that may slide (StitchOptions::feature_corner_slides): the ends of
  // the feature curves at it, each as {curve, place of the corner's neighbour along it, place
  // of the node beyond (-1: the neighbour ends the curve)}; empty for other nodes.
  using CornerEnds = std::vector<std::vector<std::array<int, 3>>>;

 public:
  Optimiser(const SurfaceMesh& surface, const StitchOptions& options, StitchResult& result,
            const std::vector<std::uint8_t>& is_feature)
      : surface_(surface),
        options_(options),
        mesh_(result.mesh),
        face_patch_(result.face_patch),
        is_feature_(is_feature),
        vertex_node_of_(result.vertex_node) {
    if (options.flip_feature_chords) collect_feature_pieces();
    const double diagonal = bounding_box(mesh_).diagonal();
    min_double_area_ = 2.0 * tolerance::kDegenerateAreaRelative * diagonal * diagonal;
    cos_dihedral_ = std::cos(options.max_flip_dihedral_deg * std::numbers::pi / 180.0);
    sin_angle_floor_ = std::sin(options.angle_floor_deg * std::numbers::pi / 180.0);
    alpha_sine_skip_ = std::numbers::sqrt3 * (sin_angle_floor_ + tolerance::kSineSkipMargin);
    sin_obtuse_floor_ = std::sin(std::min(options.angle_floor_deg + kObtuseAngleMarginDeg, 60.0) * std::numbers::pi / 180.0);
    obtuse_sine_skip_ = std::numbers::sqrt3 * (sin_obtuse_floor_ + tolerance::kSineSkipMargin);
    sin_split_feature_floor_ = std::sin(options.obtuse_split_feature_angle_deg * std::numbers::pi / 180.0);
    classify_nodes(result.vertex_node);
  }

  // One sweep of flips in edge order. With two or more threads every edge's flip test
  // (all but OpenMesh's is_flip_ok(), which looks beyond the edge's two triangles) is first
  // taken in parallel on the mesh as it is at the start of the sweep; the sweep then goes
  // through the edges in order as before, testing again only the edges of the two
  // triangles of a flip made earlier in the sweep (positions do not change during the
  // sweep, so no other edge's test can change). The flips are those of the serial sweep
  // for any thread count.
  std::size_t flip_sweep() {
    const unsigned n_threads = options_.n_threads;
    const std::size_t n_edges = mesh_.n_edges();
    std::vector<std::uint8_t> passes, retest;
    if (n_threads >= 2) {
      passes.assign(n_edges, 0);
      retest.assign(n_edges, 0);
      parallel::for_chunks(n_edges, n_threads, kEdgeChunk, [this, &passes](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t i = begin; i < end; ++i) passes[i] = passes_flip_test(TriMesh::EdgeHandle(static_cast<int>(i))) ? 1 : 0;
      });
    }
    std::size_t n_flips = 0;
    for (auto e : mesh_.edges()) {
      const auto i = static_cast<std::size_t>(e.idx());
      const bool passes_test = passes.empty() || retest[i] != 0 ? passes_flip_test(e) : passes[i] != 0;
      if (!passes_test || !mesh_.is_flip_ok(e)) continue;
      mesh_.flip(e);
      ++n_flips;
      if (!retest.empty()) {
        for (const auto h : {mesh_.halfedge_handle(e, 0), mesh_.halfedge_handle(e, 1)}) {
          for (auto g : mesh_.fh_range(mesh_.face_handle(h))) retest[static_cast<std::size_t>(mesh_.edge_handle(g).idx())] = 1;
        }
      }
    }
    return n_flips;
  }

  // Returns {accepted, rejected}. Gauss-Seidel in vertex order: a vertex sees the moves of
  // the vertices before it. With two or more threads the sweep runs on a SweepSchedule of
  // its vertices (sweep_schedule()): the same moves for any thread count.
  std::array<std::size_t, 2> smoothing_sweep() {
    if (options_.n_threads < 2) {
      std::array<std::size_t, 2> counts{0, 0};
      for (auto v : mesh_.vertices()) {
        const int outcome = smooth_vertex(v, ring_);
        if (outcome >= 0) ++counts[static_cast<std::size_t>(outcome == 1 ? 0 : 1)];
      }
      return counts;
    }
    const SweepSchedule schedule = sweep_schedule();
    std::vector<std::array<std::size_t, 2>> per_worker(options_.n_threads, {0, 0});
    run_schedule(schedule, [this, &per_worker](TriMesh::VertexHandle v, std::vector<RingTriangle>& ring, unsigned worker) {
      const int outcome = smooth_vertex(v, ring);
      if (outcome >= 0) ++per_worker[worker][static_cast<std::size_t>(outcome == 1 ? 0 : 1)];
    });
    std::array<std::size_t, 2> counts{0, 0};
    for (const auto& c : per_worker) counts[0] += c[0], counts[1] += c[1];
    return counts;
  }

  // One vertex of smoothing_sweep(), its triangles gathered in `ring` (scratch): 1 moved, 0
  // refused by the tests, -1 not tried (not movable, on the boundary, no area, no projection).
  int smooth_vertex(TriMesh::VertexHandle v, std::vector<RingTriangle>& ring) {
    const NodeInfo& info = nodes_[static_cast<std::size_t>(v.idx())];
    if (!info.is_movable || mesh_.is_boundary(v)) return -1;
    const Vec p = point(mesh_, v);
    // Area-weighted centroid of the incident triangles.
    Vec centroid = Vec::Zero();
    double total = 0.0;
    ring.clear();
    for (auto h : mesh_.voh_range(v)) {
      const auto vb = mesh_.to_vertex_handle(h);
      const auto vc = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h));
      const Vec b = point(mesh_, vb), c = point(mesh_, vc);
      const Vec n = area_vector(p, b, c);
      const double area = n.norm();
      centroid += area * (p + b + c) / 3.0;
      total += area;
      ring.push_back({b, c, n, area});
    }
    if (!(total > 0.0) || ring.empty()) return -1;
    centroid /= total;
    const Vec target = p + options_.smoothing_relaxation * (centroid - p);
    const Vec q = project(info, target);
    if (!q.allFinite()) return -1;
    if (!passes_ring_tests(ring, p, q, sin_angle_floor_, alpha_sine_skip_)) return 0;
    mesh_.set_point(v, to_openmesh(q));
    return 1;
  }

  // The vertices a smoothing sweep tries (movable, not on the boundary), cut so that several
  // threads give the serial sweep's result (stitch_detail::sweep_schedule): the border nodes
  // and corners run in vertex order on one thread, the inner nodes in groups.
  SweepSchedule sweep_schedule() const {
    // 0 not tried, 1 tried and serial, 2 tried in a group.
    std::vector<std::uint8_t> role(mesh_.n_vertices(), 0);
    for (auto v : mesh_.vertices()) {
      const NodeInfo& info = nodes_[static_cast<std::size_t>(v.idx())];
      if (!info.is_movable || mesh_.is_boundary(v)) continue;
      role[static_cast<std::size_t>(v.idx())] = info.curve >= 0 || info.is_corner ? 1 : 2;
    }
    return stitch_detail::sweep_schedule(mesh_, std::move(role));
  }

  // Runs visit(v, ring, worker) for every vertex of `schedule` on options_.n_threads threads
  // (ring: the worker's scratch; worker < n_threads; stitch_detail::run_schedule).
  template <class Visit>
  void run_schedule(const SweepSchedule& schedule, const Visit& visit) {
    std::vector<std::vector<RingTriangle>> rings(options_.n_threads);
    stitch_detail::run_schedule(schedule, options_.n_threads,
                                [&](TriMesh::VertexHandle v, unsigned worker) { visit(v, rings[worker], worker); });
  }

  // Obtuse repair (StitchOptions::obtuse_repair_rounds): each movable vertex of an obtuse
  // triangle, in index order, tries the apexes of its obtuse triangles' ideal (equilateral)
  // shapes over their far edges, on its own side of the edge (the worst triangle's first):
  // 1/2, then 1/4, 1/8 and 1/16 of the way to them; the first position, projected as in
  // smoothing, that leaves fewer obtuse triangles around the vertex and passes the
  // smoothing's tests (with the angle floor raised by kObtuseAngleMarginDeg) is taken.
  // In vertex order (the decisions planned on the run's threads: plan_ring_moves()).
  // Returns the number of moves.
  // only: when not empty, only the vertices v with only[v] != 0 are tried.
  std::size_t obtuse_sweep(const std::vector<std::uint8_t>& only = {}) {
    // Only a vertex of an obtuse triangle is tried: those at the start of the sweep, and the
    // ring of every vertex moved in it (their triangles changed). The others are skipped
    // before their ring is taken (the same moves: most vertices have no obtuse triangle).
    std::vector<std::uint8_t> candidate = obtuse_face_vertices();
    auto tried = [&](std::size_t i) { return candidate[i] != 0 && (only.empty() || only[i] != 0); };
    auto decide = [this](TriMesh::VertexHandle v, SweepScratch& scratch, Vec& to) { return obtuse_move(v, scratch, to); };
    return ring_move_sweep(candidate, tried, decide);
  }

  // Scratch of a vertex's decision in obtuse_sweep() and slide_sweep().
  struct SweepScratch {
    std::vector<RingTriangle> ring;
    std::vector<std::pair<double, Vec>> apexes;
  };

  // A sweep's decisions taken ahead (plan_ring_moves): per vertex 0 none (or dropped), 1 stays,
  // 2 moves to target.
  struct RingMovePlans {
    std::vector<std::uint8_t> state;
    std::vector<Vec> target;
  };

  // The decisions decide(v, scratch, to) (true: v moves to `to`) of the vertices i with
  // tried(i), on options_.n_threads threads on the mesh as it is now; nothing with one thread.
  // decide must read only v's ring (v's position, its faces' and its neighbours') and the
  // mesh's connectivity, and write only its scratch and `to`.
  template <class Tried, class Decide>
  RingMovePlans plan_ring_moves(const Tried& tried, const Decide& decide) const {
    RingMovePlans plans;
    const unsigned n_threads = options_.n_threads;
    if (n_threads < 2) return plans;
    const std::size_t n = mesh_.n_vertices();
    std::vector<int> vertices;
    for (std::size_t i = 0; i < n; ++i) {
      if (tried(i)) vertices.push_back(static_cast<int>(i));
    }
    if (vertices.empty()) return plans;
    plans.state.assign(n, 0);
    plans.target.resize(n);
    std::vector<SweepScratch> scratch(n_threads);
    constexpr std::size_t kVertexChunk = 256;
    parallel::for_chunks(vertices.size(), n_threads, kVertexChunk, [&](std::size_t begin, std::size_t end, unsigned worker) {
      for (std::size_t k = begin; k < end; ++k) {
        const auto i = static_cast<std::size_t>(vertices[k]);
        plans.state[i] = decide(TriMesh::VertexHandle(vertices[k]), scratch[worker], plans.target[i]) ? 2 : 1;
      }
    });
    return plans;
  }

  // A Gauss-Seidel sweep of moves in vertex order over the vertices i with tried(i), the
  // decision of each by decide() (plan_ring_moves); a moved vertex's neighbours become
  // candidates (candidate[w] = 1; tried() reads it). With two or more threads the decisions
  // are first planned on the threads; the sweep takes a vertex's plan unless a neighbour moved
  // earlier in the sweep (its plan is dropped then and it decides again): a decision reads
  // only the vertex's ring, which nothing else changes, so the moves are the serial sweep's
  // for any thread count. Returns the number of moves.
  template <class Tried, class Decide>
  std::size_t ring_move_sweep(std::vector<std::uint8_t>& candidate, const Tried& tried, const Decide& decide) {
    RingMovePlans plans = plan_ring_moves(tried, decide);
    SweepScratch scratch;
    std::size_t n_moves = 0;
    for (auto v : mesh_.vertices()) {
      const auto i = static_cast<std::size_t>(v.idx());
      if (!tried(i)) continue;
      Vec to;
      const bool planned = !plans.state.empty() && plans.state[i] != 0;
      const bool moves = planned ? plans.state[i] == 2 : decide(v, scratch, to);
#ifndef NDEBUG
      if (planned) {  // the plan is never stale
        Vec fresh;
        const bool fresh_moves = decide(v, scratch, fresh);
        NURBSFRONT_DEBUG_ASSERT(fresh_moves == moves && (!moves || fresh == plans.target[i]));
      }
#endif
      if (!moves) continue;
      if (planned) to = plans.target[i];
      mesh_.set_point(v, to_openmesh(to));
      ++n_moves;
      for (auto w : mesh_.vv_range(v)) {
        candidate[static_cast<std::size_t>(w.idx())] = 1;
        if (!plans.state.empty()) plans.state[static_cast<std::size_t>(w.idx())] = 0;
      }
    }
    return n_moves;
  }

  // The obtuse repair's search (StitchOptions::obtuse_search_steps; docs/stitch.md "Obtuse
  // repair: a search"): a compass search for the node at p (its triangles in ring, old_obtuse
  // of them obtuse) in the plane through p normal to the ring's area vector. From p, steps
  // of a quarter of the shortest ring edge in eight directions (the plane's axes and
  // diagonals); the best neighbour by (obtuse triangles, then the cosine of the largest
  // angle: larger is better) is taken while it is better, else the step halves,
  // obtuse_search_steps times. A place is allowed only where every ring triangle keeps its
  // orientation and its smallest angle's sine at least min(the ring's old one,
  // sin_obtuse_floor_), within kObtuseSearchReach of the shortest edge from p. Returns p
  // when no place has fewer obtuse triangles; the caller
  // projects the place and tests it as every move.
  Vec search_obtuse_place(std::span<const RingTriangle> ring, const Vec& p, std::size_t old_obtuse) const {
    Vec normal = Vec::Zero();
    double shortest = std::numeric_limits<double>::infinity();
    double old_sine = 1.0;
    for (const RingTriangle& r : ring) {
      normal += r.n_old;
      shortest = std::min(shortest, (r.b - p).norm());
      old_sine = std::min(old_sine, alpha_and_min_angle_sine(p, r.b, r.c, r.l_old)[1]);
    }
    const double normal_norm = normal.norm();
    if (!(normal_norm > 0.0) || !(shortest > 0.0)) return p;
    normal /= normal_norm;
    // Two axes of the plane: the cross product with the coordinate axis least along the normal.
    Vec axis = Vec::Zero();
    int least = 0;
    for (int k = 1; k < 3; ++k) {
      if (std::abs(normal[k]) < std::abs(normal[least])) least = k;
    }
    axis[least] = 1.0;
    const Vec u = normal.cross(axis).normalized();
    const Vec w = normal.cross(u);
    const double sine_floor = std::min(old_sine, sin_obtuse_floor_);
    const double reach = kObtuseSearchReach * shortest;
    // (obtuse triangles, -cosine of the largest angle) of q, or nothing when q is not allowed
    // or, with `below`, when its score would not be below *below. Both parts only grow
    // triangle by triangle, so once the score so far is not below *below the place is given
    // up before the rest of the ring and its sines are computed: the caller took a place only
    // when its score was below the best so far, so the same places are taken.
    using Score = std::pair<std::size_t, double>;
    auto score = [&](const Vec& q, const Score* below) -> std::optional<Score> {
      std::size_t n_obtuse = 0;
      double worst = 1.0;
      if ((q - p).squaredNorm() > reach * reach) return std::nullopt;
      for (const RingTriangle& r : ring) {
        const Vec n = area_vector(q, r.b, r.c);
        const double l = n.norm();
        if (l <= min_double_area_ || !(n.dot(r.n_old) > 0.0)) return std::nullopt;
        n_obtuse += triangle_is_obtuse(q, r.b, r.c) ? 1 : 0;
        worst = std::min(worst, largest_angle_cosine(q, r.b, r.c));
        if (below != nullptr && !(Score(n_obtuse, -worst) < *below)) return std::nullopt;
        if (alpha_and_min_angle_sine(q, r.b, r.c, l)[1] < sine_floor) return std::nullopt;
      }
      return Score(n_obtuse, -worst);
    };
    const auto start = score(p, nullptr);
    if (!start) return p;
    Score best = *start;
    Vec at = p;
    double step = 0.25 * shortest;
    constexpr std::array<std::array<double, 2>, 8> kDirections{
        {{1.0, 0.0}, {-1.0, 0.0}, {0.0, 1.0}, {0.0, -1.0}, {1.0, 1.0}, {1.0, -1.0}, {-1.0, 1.0}, {-1.0, -1.0}}};
    // A step that improves is taken again before the step halves; bounded so that the search
    // always ends (each improvement lowers the score, but take no chances).
    constexpr int kMaxMoves = 64;
    int halvings = 0, moves = 0;
    while (halvings < options_.obtuse_search_steps && moves < kMaxMoves) {
      std::optional<Score> best_here;
      Vec best_q = at;
      for (const auto& [du, dw] : kDirections) {
        const Vec q = at + (step * du) * u + (step * dw) * w;
        // best_here, when set, is below best.
        const auto s = score(q, best_here ? &*best_here : &best);
        if (s && *s < best && (!best_here || *s < *best_here)) {
          best_here = s;
          best_q = q;
        }
      }
      if (best_here) {
        best = *best_here;
        at = best_q;
        ++moves;
      } else {
        step *= 0.5;
        ++halvings;
      }
    }
    return best.first < old_obtuse ? at : p;
  }

  // One vertex of obtuse_sweep(): whether v moves, and where (to).
  bool obtuse_move(TriMesh::VertexHandle v, SweepScratch& scratch, Vec& to) const {
    const NodeInfo& info = nodes_[static_cast<std::size_t>(v.idx())];
    if (!info.is_movable || mesh_.is_boundary(v)) return false;
    std::vector<RingTriangle>& ring = scratch.ring;
    std::vector<std::pair<double, Vec>>& apexes = scratch.apexes;
    const Vec p = point(mesh_, v);
    ring.clear();
    apexes.clear();
    std::size_t old_obtuse = 0;
    for (auto h : mesh_.voh_range(v)) {
      const Vec b = point(mesh_, mesh_.to_vertex_handle(h));
      const Vec c = point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h)));
      const Vec n = area_vector(p, b, c);
      ring.push_back({b, c, n, n.norm()});
      if (!triangle_is_obtuse(p, b, c)) continue;
      ++old_obtuse;
      // The cosine of the largest angle (the worst triangle's apex is tried first).
      const double worst = std::min({cosine(b - p, c - p), cosine(p - b, c - b), cosine(p - c, b - c)});
      // p's ideal place: over the middle of bc, sqrt(3)/2 |bc| away, in the triangle's plane.
      const Vec e = c - b;
      const Vec side = n.cross(e);  // in the plane, perpendicular to bc, towards p
      const double side_norm = side.norm();
      if (!(side_norm > 0.0)) continue;
      apexes.push_back({worst, 0.5 * (b + c) + (0.5 * std::numbers::sqrt3 * e.norm() / side_norm) * side});
    }
    if (old_obtuse == 0) return false;
    // A projected place q is taken when it leaves fewer obtuse triangles and passes the ring tests.
    auto takes = [&](const Vec& q) {
      if (!q.allFinite()) return false;
      std::size_t new_obtuse = 0;
      for (const RingTriangle& r : ring) new_obtuse += triangle_is_obtuse(q, r.b, r.c) ? 1 : 0;
      if (new_obtuse >= old_obtuse || !passes_ring_tests(ring, p, q, sin_obtuse_floor_, obtuse_sine_skip_)) return false;
      to = q;
      return true;
    };
    std::sort(apexes.begin(), apexes.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    // Not all the way: whole steps moved border nodes far along their two fits' mean
    // (Hausdorff up 13% on the liver) and left smaller smallest angles, for no fewer
    // obtuse triangles.
    for (const double t : {0.5, 0.25, 0.125, 0.0625}) {
      for (const auto& apex : apexes) {
        if (takes(project(info, p + t * (apex.second - p)))) return true;
      }
    }
    // No apex step helps an inner node: search the tangent plane for a place with fewer
    // obtuse triangles. Not for border nodes (on the mean of two fits; with them bunny00's
    // Hausdorff rose 15%).
    if (options_.obtuse_search_steps == 0 || info.curve >= 0 || info.is_corner) return false;
    const Vec q = project(info, search_obtuse_place(ring, p, old_obtuse));
    return q != p && takes(q);
  }

  // Flips of the edges of obtuse triangles, in edge order, when the two new triangles
  // hold fewer obtuse angles than the old ones and the flip passes flip_keeps_shape()
  // and, instead of flip_sweep()'s alpha gain, floors (the smaller new alpha must stay at least
  // min(the smaller old one, alpha_floor), the smaller smallest angle at least min(the old
  // one, angle_floor_deg + kObtuseAngleMarginDeg)). Serial. Returns the number of flips.
  // only: when not empty, only the edges whose both ends have only[v] != 0 are tried.
  std::size_t obtuse_flip_sweep(const std::vector<std::uint8_t>& only = {}) {
    std::size_t n_flips = 0;
    FlipQuad q;
    // Per face, whether it is obtuse now (a flip changes its two faces only): an edge with
    // neither face obtuse is skipped before its quad is taken (the same flips).
    std::vector<std::uint8_t> obtuse = obtuse_faces();
    auto is_obtuse_face = [&](TriMesh::HalfedgeHandle h) {
      const auto f = mesh_.face_handle(h);
      return f.is_valid() && obtuse[static_cast<std::size_t>(f.idx())] != 0;
    };
    // The edges looked at, in edge order: those of the faces obtuse at the start, and (in
    // `later`) those after the current edge of a face a flip leaves obtuse. Any other edge has
    // neither face obtuse when its turn comes, so the scan over all edges skipped it: the same
    // flips.
    std::vector<int> edges;
    for (std::size_t fi = 0; fi < obtuse.size(); ++fi) {
      if (obtuse[fi] == 0) continue;
      for (auto h : mesh_.fh_range(TriMesh::FaceHandle(static_cast<int>(fi)))) edges.push_back(mesh_.edge_handle(h).idx());
    }
    std::sort(edges.begin(), edges.end());
    std::priority_queue<int, std::vector<int>, std::greater<>> later;
    std::size_t next = 0;
    int last = -1;
    while (next < edges.size() || !later.empty()) {
      int ei = 0;
      if (later.empty() || (next < edges.size() && edges[next] <= later.top())) {
        ei = edges[next++];
      } else {
        ei = later.top();
        later.pop();
      }
      if (ei == last) continue;
      last = ei;
      const TriMesh::EdgeHandle e(ei);
      if (!is_obtuse_face(mesh_.halfedge_handle(e, 0)) && !is_obtuse_face(mesh_.halfedge_handle(e, 1))) continue;
      if (!only.empty() && (only[static_cast<std::size_t>(mesh_.to_vertex_handle(mesh_.halfedge_handle(e, 0)).idx())] == 0 ||
                            only[static_cast<std::size_t>(mesh_.from_vertex_handle(mesh_.halfedge_handle(e, 0)).idx())] == 0)) {
        continue;
      }
      if (!flip_quad(e, q)) continue;
      const Vec &a = q.a, &b = q.b, &c = q.c, &d = q.d;
      const int old_obtuse = int(triangle_is_obtuse(a, b, c)) + int(triangle_is_obtuse(b, a, d));
      if (old_obtuse == 0 || int(triangle_is_obtuse(a, d, c)) + int(triangle_is_obtuse(d, b, c)) >= old_obtuse) continue;
      if (!flip_keeps_shape(q)) continue;
      const double bound = std::min(options_.alpha_floor, std::min(alpha_with_area(a, b, c, q.l0), alpha_with_area(b, a, d, q.l1)));
      if (std::min(alpha_with_area(a, d, c, q.l2), alpha_with_area(d, b, c, q.l3)) < bound) continue;
      const double sine_bound = std::min(sin_obtuse_floor_, std::min(alpha_and_min_angle_sine(a, b, c, q.l0)[1], alpha_and_min_angle_sine(b, a, d, q.l1)[1]));
      if (std::min(alpha_and_min_angle_sine(a, d, c, q.l2)[1], alpha_and_min_angle_sine(d, b, c, q.l3)[1]) < sine_bound) continue;
      if (!mesh_.is_flip_ok(e)) continue;
      mesh_.flip(e);
      ++n_flips;
      for (const auto h : {mesh_.halfedge_handle(e, 0), mesh_.halfedge_handle(e, 1)}) {
        const auto f = mesh_.face_handle(h);
        obtuse[static_cast<std::size_t>(f.idx())] = is_obtuse(f) ? 1 : 0;
        if (obtuse[static_cast<std::size_t>(f.idx())] == 0) continue;
        for (auto g : mesh_.fh_range(f)) {
          if (mesh_.edge_handle(g).idx() > ei) later.push(mesh_.edge_handle(g).idx());
        }
      }
    }
    return n_flips;
  }

  // Feature slides (StitchOptions::feature_slide_rounds; docs/stitch.md "Feature nodes
  // sliding along their curves"). A node of a feature curve never leaves its curve, but it may
  // move along it: on the polyline of the curve's nodes where the front put them
  // (SurfaceMesh::nodes), its place is P + x (Q - P), P its own node, Q the next node along the
  // curve (x > 0) or the previous one (x < 0), |x| <= kSlideMaxShare, so two neighbours never
  // meet or pass (a feature corner with StitchOptions::feature_corner_slides: on the pieces to
  // its neighbours along the feature curves ending at it, corner_slide_frame()). Each node of
  // a feature curve with an obtuse triangle, in index
  // order, tries the shares kSlideStep apart and takes the one that leaves the fewest obtuse
  // triangles around it, then the smallest largest angle, when that removes an obtuse triangle
  // (or raises the cosine of the ring's largest angle by StitchOptions::
  // feature_slide_cosine_gain, when that is finite), passes the obtuse repair's
  // ring tests, and the curve's two edges at the node stay within kSlideMaxSag of their piece
  // from the front's polyline points between their ends (the corner a slide cuts off).
  // In vertex order (the decisions planned on the run's threads: ring_move_sweep()). Returns
  // the number of slides.
  std::size_t slide_sweep(const std::vector<int>& vertex_node) {
    if (surface_.curve_nodes.size() != surface_.curve_is_feature.size()) return 0;
    // Per node: its vertex, and its place on its curve's node list.
    std::vector<int> vertex_of(surface_.nodes.size(), -1), place(surface_.nodes.size(), -1);
    for (auto v : mesh_.vertices()) {
      const int node = vertex_node[static_cast<std::size_t>(v.idx())];
      if (node >= 0 && static_cast<std::size_t>(node) < vertex_of.size()) vertex_of[static_cast<std::size_t>(node)] = v.idx();
    }
    for (std::size_t c = 0; c < surface_.curve_nodes.size(); ++c) {
      if (surface_.curve_is_feature[c] == 0) continue;
      const std::vector<int>& list = surface_.curve_nodes[c];
      for (std::size_t k = 0; k < list.size(); ++k) {
        const auto node = static_cast<std::size_t>(list[k]);
        if (surface_.node_kind[node] == NodeKind::Border) place[node] = static_cast<int>(k);
      }
    }
    const CornerEnds corner_ends = options_.feature_corner_slides ? feature_corner_ends() : CornerEnds{};
    std::vector<std::uint8_t> candidate = obtuse_face_vertices();
    auto tried = [&candidate](std::size_t i) { return candidate[i] != 0; };
    auto decide = [&](TriMesh::VertexHandle v, SweepScratch& scratch, Vec& to) {
      return slide_move(v, vertex_node, place, vertex_of, corner_ends, scratch.ring, to);
    };
    return ring_move_sweep(candidate, tried, decide);
  }

  // One vertex of slide_sweep(): whether v slides, and where (to). place, vertex_of: per
  // node, its place on its feature curve's node list (-1: none) and its vertex.
  bool slide_move(TriMesh::VertexHandle v, const std::vector<int>& vertex_node, const std::vector<int>& place,
                  const std::vector<int>& vertex_of, const CornerEnds& corner_ends, std::vector<RingTriangle>& ring,
                  Vec& to) const {
    const int node = vertex_node[static_cast<std::size_t>(v.idx())];
    if (node < 0 || static_cast<std::size_t>(node) >= surface_.nodes.size()) return false;  // a split's node
    const NodeInfo& info = nodes_[static_cast<std::size_t>(v.idx())];
    SlideFrame frame;
    if (info.is_corner) {
      if (!corner_slide_frame(v, node, vertex_of, corner_ends, frame)) return false;
    } else {
      if (info.curve < 0 || place[static_cast<std::size_t>(node)] < 0) return false;
      if (!slide_frame(v, info.curve, place[static_cast<std::size_t>(node)], vertex_of, frame)) return false;
    }
    const Vec p = point(mesh_, v);
    ring.clear();
    std::size_t old_obtuse = 0;
    double old_worst = 1.0;  // the cosine of the largest angle of the ring
    for (auto h : mesh_.voh_range(v)) {
      if (mesh_.is_boundary(h)) continue;
      const Vec b = point(mesh_, mesh_.to_vertex_handle(h));
      const Vec c = point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h)));
      const Vec n = area_vector(p, b, c);
      ring.push_back({b, c, n, n.norm()});
      old_obtuse += triangle_is_obtuse(p, b, c) ? 1 : 0;
      old_worst = std::min(old_worst, largest_angle_cosine(p, b, c));
    }
    if (old_obtuse == 0) return false;
    std::size_t best_obtuse = old_obtuse;
    double best_worst = old_worst + options_.feature_slide_cosine_gain;  // infinity: no slide by the angle alone
    Vec best = p;
    for (int step = -kSlideSteps; step <= (frame.one_sided ? 0 : kSlideSteps); ++step) {
      const double x = step * kSlideStep;
      if (x == frame.x) continue;
      const Vec q = slide_point(frame.at, frame.before, frame.after, x);
      std::size_t new_obtuse = 0;
      double new_worst = 1.0;
      for (const RingTriangle& r : ring) {
        new_obtuse += triangle_is_obtuse(q, r.b, r.c) ? 1 : 0;
        new_worst = std::min(new_worst, largest_angle_cosine(q, r.b, r.c));
      }
      if (new_obtuse > best_obtuse || (new_obtuse == best_obtuse && !(new_worst > best_worst))) continue;
      if (!slide_keeps_curve(frame, x) || !passes_ring_tests(ring, p, q, sin_obtuse_floor_, obtuse_sine_skip_)) continue;
      best_obtuse = new_obtuse;
      best_worst = new_worst;
      best = q;
    }
    if (best == p) return false;
    to = best;
    return true;
  }

  // A node's piece of its feature curve for slide_sweep: the front's points of the node
  // (at) and of its neighbours along the curve (before, after), the neighbours' shares
  // (x_before, x_after: where they are, as the node's x below) and the node's own share x.
  struct SlideFrame {
    Vec at, before, after, prev_point, next_point;
    double x = 0.0, x_before = 0.0, x_after = 0.0;
    // A feature corner ending one feature curve: it slides back along it only (x <= 0; no
    // `after`).
    bool one_sided = false;
  };

  // The feature curve ends of every corner where one or two feature curve ends meet, none of
  // whose vertices is bounded (a fin rim node: StitchOptions::fin_rim_max_move).
  CornerEnds feature_corner_ends() const {
    CornerEnds ends(surface_.nodes.size());
    for (std::size_t c = 0; c < surface_.curve_nodes.size(); ++c) {
      if (surface_.curve_is_feature[c] == 0) continue;
      const std::vector<int>& list = surface_.curve_nodes[c];
      const int n = static_cast<int>(list.size());
      if (n < 2 || surface_.node_kind[static_cast<std::size_t>(list.front())] != NodeKind::Corner) continue;
      const int curve = static_cast<int>(c);
      ends[static_cast<std::size_t>(list.front())].push_back({curve, 1, n > 2 ? 2 : -1});
      ends[static_cast<std::size_t>(list.back())].push_back({curve, n - 2, n > 2 ? n - 3 : -1});
    }
    for (auto& e : ends) {
      if (e.size() > 2) e.clear();
    }
    return ends;
  }

  // The frame of feature corner v (node `node`) for slide_sweep: its place is on the pieces of
  // the front's polyline to its neighbours along the feature curves ending at it (two: either
  // way; one: back along it only). False as slide_frame(), and for a corner with more than two
  // feature curve ends, on a fin rim, or whose neighbour is not on its own piece.
  bool corner_slide_frame(TriMesh::VertexHandle v, int node, const std::vector<int>& vertex_of,
                          const CornerEnds& corner_ends, SlideFrame& frame) const {
    if (static_cast<std::size_t>(node) >= corner_ends.size()) return false;
    const std::vector<std::array<int, 3>>& ends = corner_ends[static_cast<std::size_t>(node)];
    if (ends.empty() || std::isfinite(nodes_[static_cast<std::size_t>(v.idx())].max_move)) return false;
    frame.at = surface_.nodes[static_cast<std::size_t>(node)];
    frame.one_sided = ends.size() == 1;
    // The neighbour along end e: its front point, where it is now, and its share on its own
    // pieces (towards the corner: positive), or false.
    auto neighbour = [&](const std::array<int, 3>& e, Vec& front, Vec& now, double& share) {
      const std::vector<int>& list = surface_.curve_nodes[static_cast<std::size_t>(e[0])];
      const int w = list[static_cast<std::size_t>(e[1])];
      const int vw = vertex_of[static_cast<std::size_t>(w)];
      if (vw < 0 || vw == v.idx() || !mesh_.find_halfedge(v, TriMesh::VertexHandle(vw)).is_valid()) return false;
      front = surface_.nodes[static_cast<std::size_t>(w)];
      now = point(mesh_, TriMesh::VertexHandle(vw));
      if (e[2] < 0) {  // the neighbour is a corner: it must be where the front put it
        share = 0.0;
        return now == front;
      }
      share = slide_share(now, front, surface_.nodes[static_cast<std::size_t>(list[static_cast<std::size_t>(e[2])])], frame.at);
      return std::isfinite(share);
    };
    if (!neighbour(ends[0], frame.before, frame.prev_point, frame.x_before)) return false;
    if (frame.one_sided) {
      frame.after = frame.at;
      frame.next_point = frame.at;
      frame.x_after = 0.0;
    } else if (!neighbour(ends[1], frame.after, frame.next_point, frame.x_after)) {
      return false;
    } else {
      frame.x_after = -frame.x_after;  // slide_frame's sign: positive away from the node
    }
    frame.x = slide_share(point(mesh_, v), frame.at, frame.before, frame.after);
    return std::isfinite(frame.x) && (!frame.one_sided || frame.x <= 0.0);
  }

  // Where x (a share of the piece to the next node, negative: to the previous one) puts the
  // point of the node with front point `at` and neighbours' front points `before`, `after`.
  static Vec slide_point(const Vec& at, const Vec& before, const Vec& after, double x) {
    return x < 0.0 ? Vec(at + (-x) * (before - at)) : Vec(at + x * (after - at));
  }

  // The share x of the curve piece where p lies (slide_point), 0 at `at`; NaN when p lies on
  // neither piece (within tolerance::kSlideOnCurveRelative of the piece's length) or beyond kSlideMaxShare.
  static double slide_share(const Vec& p, const Vec& at, const Vec& before, const Vec& after) {
    if (p == at) return 0.0;
    for (const int side : {1, -1}) {
      const Vec d = (side > 0 ? after : before) - at;
      const double l2 = d.squaredNorm();
      if (!(l2 > 0.0)) continue;
      const double u = (p - at).dot(d) / l2;
      if (u < 0.0 || u > kSlideMaxShare + tolerance::kSlideOnCurveRelative) continue;
      if ((p - (at + u * d)).squaredNorm() <= tolerance::kSlideOnCurveRelative * tolerance::kSlideOnCurveRelative * l2) return side * u;
    }
    return std::numeric_limits<double>::quiet_NaN();
  }

  // The frame of vertex v, at place k of feature curve `curve` (slide_sweep): false when the
  // curve is too short, v is its end, a neighbour along the curve is not a vertex joined to v,
  // or v or a neighbour is not on the front's polyline (something else moved it).
  bool slide_frame(TriMesh::VertexHandle v, int curve, int k, const std::vector<int>& vertex_of, SlideFrame& frame) const {
    const std::vector<int>& list = surface_.curve_nodes[static_cast<std::size_t>(curve)];
    const int n = static_cast<int>(list.size());
    if (n < 3) return false;
    const bool closed = surface_.node_kind[static_cast<std::size_t>(list.front())] != NodeKind::Corner;
    if (!closed && (k == 0 || k == n - 1)) return false;
    const int kp = (k + n - 1) % n, kn = (k + 1) % n;
    const int vp = vertex_of[static_cast<std::size_t>(list[static_cast<std::size_t>(kp)])];
    const int vn = vertex_of[static_cast<std::size_t>(list[static_cast<std::size_t>(kn)])];
    if (vp < 0 || vn < 0 || vp == vn) return false;
    const TriMesh::VertexHandle hp(vp), hn(vn);
    if (!mesh_.find_halfedge(v, hp).is_valid() || !mesh_.find_halfedge(v, hn).is_valid()) return false;
    auto front = [&](int i) { return surface_.nodes[static_cast<std::size_t>(list[static_cast<std::size_t>((i + n) % n)])]; };
    frame.at = front(k);
    frame.before = front(kp);
    frame.after = front(kn);
    frame.x = slide_share(point(mesh_, v), frame.at, frame.before, frame.after);
    frame.prev_point = point(mesh_, hp);
    frame.next_point = point(mesh_, hn);
    // A neighbour that is a corner (an open curve's end): share 0 when it is at its front
    // point; a corner that slid (StitchOptions::feature_corner_slides) gives NaN, no slide.
    frame.x_before = slide_share(frame.prev_point, frame.before, front(kp - 1), frame.at);
    frame.x_after = slide_share(frame.next_point, frame.after, frame.at, front(kn + 1));
    if (!closed && kp == 0) frame.x_before = frame.prev_point == frame.before ? 0.0 : std::numeric_limits<double>::quiet_NaN();
    if (!closed && kn == n - 1) frame.x_after = frame.next_point == frame.after ? 0.0 : std::numeric_limits<double>::quiet_NaN();
    return std::isfinite(frame.x) && std::isfinite(frame.x_before) && std::isfinite(frame.x_after);
  }

  // Whether the node at share x keeps the crease within kSlideMaxSag of its piece from the
  // front's polyline: each of its two curve edges passes within that of the front's points
  // between its ends (the node's own point when x moves away from it on the other side, a
  // neighbour's when that neighbour moved away from it towards the far side).
  bool slide_keeps_curve(const SlideFrame& frame, double x) const {
    const Vec q = slide_point(frame.at, frame.before, frame.after, x);
    auto within = [](const Vec& a, const Vec& b, const Vec& point, double bound) {
      const Vec d = b - a;
      const double l2 = d.squaredNorm();
      const double u = l2 > 0.0 ? std::clamp((point - a).dot(d) / l2, 0.0, 1.0) : 0.0;
      return (point - (a + u * d)).norm() <= bound;
    };
    // The edge to the previous node: the front's points strictly between are `at` (x > 0)
    // and `before` (the previous node slid away from it backwards, x_before < 0).
    const double before_piece = kSlideMaxSag * (frame.at - frame.before).norm();
    if (x > 0.0 && !within(frame.prev_point, q, frame.at, before_piece)) return false;
    if (frame.x_before < 0.0 && !within(frame.prev_point, q, frame.before, before_piece)) return false;
    if (frame.one_sided) return true;
    const double after_piece = kSlideMaxSag * (frame.after - frame.at).norm();
    if (x < 0.0 && !within(q, frame.next_point, frame.at, after_piece)) return false;
    if (frame.x_after > 0.0 && !within(q, frame.next_point, frame.after, after_piece)) return false;
    return true;
  }

  // The cosine of the largest angle of triangle (a, b, c) (below 0: obtuse).
  static double largest_angle_cosine(const Vec& a, const Vec& b, const Vec& c) {
    return std::min({cosine(b - a, c - a), cosine(a - b, c - b), cosine(a - c, b - c)});
  }

  // Whether face f has an angle above 90 deg (triangle_is_obtuse of its corners, which
  // gives the same answer for every rotation of them: each dot product has the same terms).
  bool is_obtuse(TriMesh::FaceHandle f) const {
    const auto h = mesh_.halfedge_handle(f);
    return triangle_is_obtuse(point(mesh_, mesh_.from_vertex_handle(h)), point(mesh_, mesh_.to_vertex_handle(h)),
                              point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h))));
  }

  // is_obtuse() of every face, in face order (0 for a deleted face): the faces on
  // options_.n_threads threads, each writing its own entry.
  std::vector<std::uint8_t> obtuse_faces() const {
    constexpr std::size_t kFaceChunk = 8192;
    std::vector<std::uint8_t> obtuse(mesh_.n_faces(), 0);
    const bool has_status = mesh_.has_face_status();
    parallel::for_chunks(obtuse.size(), options_.n_threads, kFaceChunk, [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t i = begin; i < end; ++i) {
        const TriMesh::FaceHandle f(static_cast<int>(i));
        if (has_status && mesh_.status(f).deleted()) continue;
        obtuse[i] = is_obtuse(f) ? 1 : 0;
      }
    });
    return obtuse;
  }

  // 1 for every vertex of an obtuse face, in vertex order.
  std::vector<std::uint8_t> obtuse_face_vertices() const {
    const std::vector<std::uint8_t> obtuse = obtuse_faces();
    std::vector<std::uint8_t> marked(mesh_.n_vertices(), 0);
    for (std::size_t i = 0; i < obtuse.size(); ++i) {
      if (obtuse[i] == 0) continue;
      for (auto v : mesh_.fv_range(TriMesh::FaceHandle(static_cast<int>(i)))) marked[static_cast<std::size_t>(v.idx())] = 1;
    }
    return marked;
  }

  // Obtuse splits (StitchOptions::obtuse_split_rounds): every face that is still obtuse, in
  // face order (the faces at the start of the sweep), gets its longest edge (a, b) split at
  // the foot of the altitude from the obtuse corner c, clamped to [kSplitMin, 1 - kSplitMin]
  // of the edge, or at its midpoint when that fails. The new node goes onto the segment
  // when the edge is a crease, a chord between two feature nodes of two patches or on the
  // input's boundary (it is then a feature node: nothing moves it), else onto the fitted
  // surface as smoothing projects a node there (its patch, or the mean of the two patches
  // of a non-feature border edge). Accepted when the new triangles hold fewer obtuse
  // angles than the old ones, none degenerates or turns its normal from its old triangle's
  // by more than acos(min_normal_dot), their smallest alpha stays at least min(old,
  // alpha_floor) and their smallest angle at least min(old, angle_floor_deg). Edges in
  // `refused` (vertex pairs, smaller index first) are left alone. New vertices get the node
  // ids vertex_node.size() onwards of is_feature / vertex_node (both grow); their handles
  // are appended to `made`, the split edges' ends to `split_edges`.
  std::size_t split_sweep(std::vector<int>& vertex_node, std::vector<std::uint8_t>& is_feature,
                          const std::vector<std::array<int, 2>>& refused, std::vector<TriMesh::VertexHandle>& made,
                          std::vector<std::array<int, 2>>& split_edges) {
    std::size_t n_splits = 0;
    vertex_node_ = &vertex_node;
    is_split_feature_ = &is_feature;
    const std::size_t n_faces = mesh_.n_faces();
    // Every face's halfedge opposite its obtuse corner, taken at the start on
    // options_.n_threads threads; a face that a split or its flips changed is looked at again
    // when its turn comes (faces keep their halfedges and corners otherwise, and no vertex
    // moves): the handles of the face-by-face scan, with its serial work on the threads.
    constexpr std::size_t kFaceChunk = 8192;
    std::vector<TriMesh::HalfedgeHandle> opposite(n_faces);
    parallel::for_each_index(n_faces, options_.n_threads, kFaceChunk, [&](std::size_t fi) {
      opposite[fi] = obtuse_opposite(TriMesh::FaceHandle(static_cast<int>(fi)));
    });
    std::vector<std::uint8_t> changed(n_faces, 0);
    auto mark = [&](TriMesh::FaceHandle g) {
      if (g.is_valid() && static_cast<std::size_t>(g.idx()) < n_faces) changed[static_cast<std::size_t>(g.idx())] = 1;
    };
    // The plans of the faces obtuse at the start, taken ahead on the threads on the mesh as it
    // is now (two or more threads). A plan reads the faces around the corners a, b, c of its
    // face and d across (a, b) (and of the vertices across the edges of those triangles, for
    // the flips and the far piece): all of them around a, b, c, d or a neighbour of theirs. A
    // split or flip of the sweep marks every vertex of the faces it changed (`touched`; no
    // vertex moves, other faces keep their corners and patches), so a plan is the serial
    // sweep's when none of those vertices is marked; else the face is planned again here.
    std::vector<int> ahead_of(n_faces, -1);
    std::vector<SplitPlan> ahead;
    if (options_.n_threads >= 2) {
      std::vector<int> faces;
      for (std::size_t fi = 0; fi < n_faces; ++fi) {
        if (opposite[fi].is_valid()) faces.push_back(static_cast<int>(fi));
      }
      ahead.resize(faces.size());
      std::vector<SplitScratch> scratch(options_.n_threads);
      std::vector<SplitPlan> far_scratch(options_.n_threads);
      constexpr std::size_t kPlanChunk = 8;
      parallel::for_chunks(faces.size(), options_.n_threads, kPlanChunk, [&](std::size_t begin, std::size_t end, unsigned worker) {
        for (std::size_t k = begin; k < end; ++k) {
          const auto fi = static_cast<std::size_t>(faces[k]);
          ahead_of[fi] = static_cast<int>(k);
          plan_face_split(opposite[fi], vertex_node, is_feature, refused, scratch[worker], ahead[k], far_scratch[worker]);
        }
      });
    }
    std::vector<std::uint8_t> touched(ahead.empty() ? 0 : mesh_.n_vertices(), 0);
    auto touch_face = [&](TriMesh::FaceHandle g) {
      if (touched.empty() || !g.is_valid()) return;
      for (auto u : mesh_.fv_range(g)) {
        const auto i = static_cast<std::size_t>(u.idx());
        if (i >= touched.size()) touched.resize(i + 1, 0);
        touched[i] = 1;
      }
    };
    auto is_touched = [&](TriMesh::VertexHandle v) {
      const auto i = static_cast<std::size_t>(v.idx());
      return i >= touched.size() || touched[i] != 0;
    };
    // Whether no vertex around a, b, c (h's triangle) and d (across h) is touched.
    auto untouched_around = [&](TriMesh::HalfedgeHandle h) {
      const auto o = mesh_.opposite_halfedge_handle(h);
      std::array<TriMesh::VertexHandle, 4> corners{mesh_.from_vertex_handle(h), mesh_.to_vertex_handle(h),
                                                   mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h)),
                                                   mesh_.is_boundary(o) ? TriMesh::VertexHandle()
                                                                        : mesh_.to_vertex_handle(mesh_.next_halfedge_handle(o))};
      for (const auto v : corners) {
        if (!v.is_valid()) continue;
        if (is_touched(v)) return false;
        for (auto u : mesh_.vv_range(v)) {
          if (is_touched(u)) return false;
        }
      }
      return true;
    };
    SplitPlan plan, far;
    for (std::size_t fi = 0; fi < n_faces; ++fi) {
      const TriMesh::FaceHandle f(static_cast<int>(fi));
      // The halfedge (a, b) opposite the obtuse corner c.
      const TriMesh::HalfedgeHandle h = changed[fi] != 0 ? obtuse_opposite(f) : opposite[fi];
      NURBSFRONT_DEBUG_ASSERT(changed[fi] != 0 || h == obtuse_opposite(f));  // the cache is never stale
      if (!h.is_valid()) continue;
      if (changed[fi] == 0 && ahead_of[fi] >= 0 && untouched_around(h)) {
        std::swap(plan, ahead[static_cast<std::size_t>(ahead_of[fi])]);
      } else {
        plan_face_split(h, vertex_node, is_feature, refused, split_scratch_, plan, far);
      }
      if (plan.best < 0) continue;
      const auto o = mesh_.opposite_halfedge_handle(plan.h);
      const auto va = mesh_.from_vertex_handle(plan.h), vb = mesh_.to_vertex_handle(plan.h);
      const std::array<int, 2> key{std::min(va.idx(), vb.idx()), std::max(va.idx(), vb.idx())};
      const auto v = mesh_.add_vertex(to_openmesh(plan.m));
      const int patch_c = face_patch_[static_cast<std::size_t>(mesh_.face_handle(plan.h).idx())];
      const int patch_d = plan.one_sided ? -1 : face_patch_[static_cast<std::size_t>(mesh_.face_handle(o).idx())];
      const auto vc = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(plan.h));
      mesh_.split_edge(mesh_.edge_handle(plan.h), v);
      for (auto face : mesh_.vf_range(v)) {  // the two split faces and the new ones
        mark(face);
        touch_face(face);
      }
      face_patch_.resize(mesh_.n_faces(), -1);
      for (auto e : mesh_.vf_range(v)) {
        int& patch = face_patch_[static_cast<std::size_t>(e.idx())];
        if (patch >= 0) continue;
        bool has_c = false;
        for (auto u : mesh_.fv_range(e)) has_c = has_c || u == vc;
        patch = has_c ? patch_c : patch_d;
      }
      vertex_node.push_back(static_cast<int>(is_feature.size()));
      is_feature.push_back(plan.on_segment ? 1 : 0);
      nodes_.push_back(plan.info);
      made.push_back(v);
      split_edges.push_back(key);
      ++n_splits;
      for (const auto& [u, w] : plan.flips) {
        const auto e = mesh_.edge_handle(mesh_.find_halfedge(u, w));
        if (mesh_.is_flip_ok(e)) {
          mesh_.flip(e);
          for (const int k : {0, 1}) {
            mark(mesh_.face_handle(mesh_.halfedge_handle(e, k)));
            touch_face(mesh_.face_handle(mesh_.halfedge_handle(e, k)));
          }
          ++n_split_flips_;
        }
      }
    }
    return n_splits;
  }

  // The split of a face whose obtuse corner c is opposite h (split_sweep): the plan of h's
  // edge, or of the far piece of a strip (docs/stitch.md "Far pieces of strips") when that
  // leaves fewer obtuse triangles. Only a plan that flips h relieves the face (the two plans'
  // counts are over different triangles otherwise; reviewer, session 15). `far`: scratch.
  void plan_face_split(TriMesh::HalfedgeHandle h, const std::vector<int>& vertex_node,
                       const std::vector<std::uint8_t>& is_feature, const std::vector<std::array<int, 2>>& refused,
                       SplitScratch& scratch, SplitPlan& plan, SplitPlan& far) const {
    const Vec c = point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h)));
    plan_edge_split(h, c, vertex_node, is_feature, refused, scratch, plan);
    const TriMesh::HalfedgeHandle g = far_piece(h);
    if (!g.is_valid()) return;
    plan_edge_split(g, c, vertex_node, is_feature, refused, scratch, far);
    const auto ha = mesh_.from_vertex_handle(h), hb = mesh_.to_vertex_handle(h);
    const bool flips_h = std::any_of(far.flips.begin(), far.flips.end(), [&](const auto& e) {
      return (e[0] == ha && e[1] == hb) || (e[0] == hb && e[1] == ha);
    });
    if (flips_h && far.best >= 0 && (plan.best < 0 || far.best < plan.best)) std::swap(plan, far);
  }

  // The halfedge (a, b) of face f opposite its obtuse corner c ((a - c) . (b - c) < 0; the
  // last such of fh_range's order), or an invalid handle.
  TriMesh::HalfedgeHandle obtuse_opposite(TriMesh::FaceHandle f) const {
    TriMesh::HalfedgeHandle h;
    for (auto g : mesh_.fh_range(f)) {
      const Vec a = point(mesh_, mesh_.from_vertex_handle(g)), b = point(mesh_, mesh_.to_vertex_handle(g));
      const Vec c = point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(g)));
      if ((a - c).dot(b - c) < 0.0) h = g;
    }
    return h;
  }

  // The best split of h's edge (a, b) (split_sweep): at the foot of the altitude from apex
  // (clamped to [kSplitMin, 1 - kSplitMin] of the edge) or the midpoint, each without and
  // with flips, then relaxed_split's candidates off the segments; plan.best < 0 when none
  // passes (or the edge is refused or may not be split).
  void plan_edge_split(TriMesh::HalfedgeHandle h, const Vec& apex, const std::vector<int>& vertex_node,
                       const std::vector<std::uint8_t>& is_feature, const std::vector<std::array<int, 2>>& refused,
                       SplitScratch& scratch, SplitPlan& plan) const {
    plan.h = h;
    plan.best = -1;
    const auto va = mesh_.from_vertex_handle(h), vb = mesh_.to_vertex_handle(h);
    const std::array<int, 2> key{std::min(va.idx(), vb.idx()), std::max(va.idx(), vb.idx())};
    if (std::binary_search(refused.begin(), refused.end(), key)) return;
    if (!plan_split(h, vertex_node, is_feature, plan.info, plan.on_segment)) return;
    const Vec a = point(mesh_, va), b = point(mesh_, vb);
    plan.one_sided = mesh_.is_boundary(mesh_.opposite_halfedge_handle(h));
    const double foot = std::clamp((apex - a).dot(b - a) / (b - a).squaredNorm(), kSplitMin, 1.0 - kSplitMin);
    // The best of: the foot, the midpoint; each without and with flips (fewest obtuse
    // triangles; the first of equals).
    scratch.best_flips.clear();
    for (const double t : {foot, 0.5}) {
      const Vec m0 = a + t * (b - a);
      const Vec m = plan.on_segment ? m0 : project(plan.info, m0);
      // Not far off the edge: a fit far off there (a border of a patch fitted badly).
      if (!m.allFinite() || (m - m0).norm() > kSplitMaxOffset * (b - a).norm()) continue;
      for (const bool with_flips : {false, true}) {
        const int n = evaluate_split(h, plan.one_sided, m, plan.on_segment, with_flips, false, scratch.flips, plan.best);
        if (n >= 0 && (plan.best < 0 || n < plan.best)) {
          plan.best = n;
          plan.m = m;
          scratch.best_flips = scratch.flips;
        }
      }
    }
    if (!plan.on_segment) relaxed_split(h, plan.one_sided, plan.info, a, b, scratch, plan.best, plan.m);
    if (!plan.on_segment && plan.best != 0 && options_.obtuse_split_grid)
      grid_split(h, plan.one_sided, plan.info, a, b, scratch, plan.best, plan.m);
    plan.flips = scratch.best_flips;
  }

  // The far piece of a strip (issue 5; docs/stitch.md "Far pieces of strips"): h is the edge
  // (a, b) opposite the obtuse corner c of its triangle, c a node on a patch border (or the
  // input's boundary) with only two triangles of that patch, whose angles there sum to about
  // 180 deg: one of them stays obtuse wherever the nodes move. When the triangle across h is
  // of the same patch and exactly one of its other two edges is on a patch border (the far
  // border of a strip, facing c), that edge, as a halfedge of the triangle across h, is
  // returned: its split with the flip of h gives c a third triangle. Else an invalid handle.
  TriMesh::HalfedgeHandle far_piece(TriMesh::HalfedgeHandle h) const {
    const auto o = mesh_.opposite_halfedge_handle(h);
    if (mesh_.is_boundary(o)) return TriMesh::HalfedgeHandle();
    const int patch = face_patch_[static_cast<std::size_t>(mesh_.face_handle(h).idx())];
    if (face_patch_[static_cast<std::size_t>(mesh_.face_handle(o).idx())] != patch) return TriMesh::HalfedgeHandle();
    const auto vc = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h));
    int n_own = 0;
    bool on_border = mesh_.is_boundary(vc);
    for (auto g : mesh_.vf_range(vc)) {
      const int p = face_patch_[static_cast<std::size_t>(g.idx())];
      n_own += p == patch ? 1 : 0;
      on_border = on_border || p != patch;
    }
    if (n_own != 2 || !on_border) return TriMesh::HalfedgeHandle();
    auto is_border = [&](TriMesh::HalfedgeHandle g) {
      const auto r = mesh_.opposite_halfedge_handle(g);
      return mesh_.is_boundary(r) || face_patch_[static_cast<std::size_t>(mesh_.face_handle(r).idx())] != patch;
    };
    const auto g1 = mesh_.next_halfedge_handle(o), g2 = mesh_.next_halfedge_handle(g1);
    const bool b1 = is_border(g1), b2 = is_border(g2);
    if (b1 == b2) return TriMesh::HalfedgeHandle();
    return b1 ? g1 : g2;
  }

  // Relaxed split nodes (issue 5; docs/stitch.md "Relaxed split nodes"). The largest class
  // of obtuse triangles on the CAD meshes: a node of a straight feature border with two
  // triangles of its patch. Their angles there sum to 180 deg, so one is at least 90 deg
  // wherever the other nodes go, and nothing moves the node: only a third triangle removes
  // it, which the split of the opposite edge gives. At the altitude's foot or the midpoint
  // the new node makes right angles at itself (the split then holds as many obtuse
  // triangles); so for every split off the segments the node is also tried at the mean of
  // its ring after the split (and its flips), projected as the split's node, a few times
  // over (each mean from the ring of the last position): where smoothing would take it.
  // These candidates are evaluated `relaxed` (evaluate_split): the obtuse repair's angle
  // floor (at angle_floor_deg itself the DRAM scene's smallest angle away from features fell
  // 27.4 -> 25.2 deg), and a split that moves an obtuse angle off a fixed node passes. Updates
  // best (fewest obtuse new triangles; only a strictly better one replaces it), best_m and
  // the best flips as split_sweep's own candidates do.
  void relaxed_split(TriMesh::HalfedgeHandle h, bool one_sided, const NodeInfo& info, const Vec& a, const Vec& b,
                     SplitScratch& scratch, int& best, Vec& best_m) const {
    const auto o = mesh_.opposite_halfedge_handle(h);
    const Vec c = point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h)));
    const Vec d = one_sided ? Vec::Zero() : point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(o)));
    Vec m = best >= 0 ? best_m : Vec(0.5 * (a + b));
    for (int iteration = 0; iteration < kRelaxedSplitIterations; ++iteration) {
      // The ring of m after the split with flips: a, c, b (, d) and the far corners of the flips.
      (void)evaluate_split(h, one_sided, m, false, true, true, scratch.flips);
      Vec sum = a + b + c + (one_sided ? Vec::Zero() : d);
      int n_ring = one_sided ? 3 : 4;
      for (const auto& [u, w] : scratch.flips) {
        const auto g = mesh_.find_halfedge(w, u);
        sum += point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(g)));
        ++n_ring;
      }
      const Vec target = sum / static_cast<double>(n_ring);
      const Vec q = project(info, target);
      if (!q.allFinite() || (q - target).norm() > kSplitMaxOffset * (b - a).norm()) return;
      m = q;
      take_relaxed_place(h, one_sided, m, scratch, best, best_m);
    }
  }

  // A place m off the segment for the split of h's edge, evaluated `relaxed` without and with
  // flips (relaxed_split's and grid_split's candidates): it replaces best (and best_m, the
  // flips) when it leaves strictly fewer obtuse triangles.
  void take_relaxed_place(TriMesh::HalfedgeHandle h, bool one_sided, const Vec& m, SplitScratch& scratch, int& best,
                          Vec& best_m) const {
    for (const bool with_flips : {false, true}) {
      const int n = evaluate_split(h, one_sided, m, false, with_flips, true, scratch.flips, best);
      if (n >= 0 && (best < 0 || n < best)) {
        best = n;
        best_m = m;
        scratch.best_flips = scratch.flips;
      }
    }
  }

  // Split nodes on a grid (issue 5; docs/stitch.md "Split nodes on a grid, session 18"). At
  // the altitude's foot, the midpoint and the ring means the new node of a split often
  // leaves two obtuse triangles (cheese's 114-deg corners at the triple points, closed by one
  // triangle between two fixed legs: a right angle at the node on the corner's side, an
  // obtuse one on the far side). So the node is also tried on a grid in the plane of h's
  // triangle (a, b, c), c its obtuse corner: kSplitGridStep of (b - a) along the edge
  // (-2 ... 2 steps from its middle) and away from c (-1 ... 4), each projected as the
  // split's node (not more than kSplitMaxOffset of the edge off) and evaluated `relaxed`
  // without and with flips, in this fixed order; a candidate replaces best only when it
  // leaves strictly fewer obtuse triangles (the first of equals).
  void grid_split(TriMesh::HalfedgeHandle h, bool one_sided, const NodeInfo& info, const Vec& a, const Vec& b,
                  SplitScratch& scratch, int& best, Vec& best_m) const {
    if (one_sided) return;
    const Vec c = point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h)));
    if ((a - c).dot(b - c) >= 0.0) return;
    const double length = (b - a).norm();
    const Vec along = (b - a) / length;
    Vec across = along.cross(area_vector(a, b, c)).normalized();  // in the plane, normal to (a, b)
    if (across.dot(c - a) > 0.0) across = -across;                // away from c
    const double step = kSplitGridStep * length;
    const Vec middle = 0.5 * (a + b);
    for (int j = -1; j <= 4; ++j) {
      for (int i = -2; i <= 2; ++i) {
        const Vec target = middle + (i * step) * along + (j * step) * across;
        const Vec m = project(info, target);
        if (!m.allFinite() || (m - target).norm() > kSplitMaxOffset * length) continue;
        take_relaxed_place(h, one_sided, m, scratch, best, best_m);
      }
    }
  }

 private:
  // Where the node of a split of h's edge goes and what it may do (split_sweep): on the
  // segment (on_segment; a feature node) for an edge on the input's boundary or between
  // two patches with both ends feature nodes; else info for the projection (its patch, or
  // the two patches of a non-feature border curve). False when the edge is a locked border
  // edge whose curve is unknown.
  bool plan_split(TriMesh::HalfedgeHandle h, const std::vector<int>& vertex_node, const std::vector<std::uint8_t>& is_feature,
                  NodeInfo& info, bool& on_segment) const {
    const auto va = mesh_.from_vertex_handle(h), vb = mesh_.to_vertex_handle(h);
    const NodeInfo& a = nodes_[static_cast<std::size_t>(va.idx())];
    const NodeInfo& b = nodes_[static_cast<std::size_t>(vb.idx())];
    const auto e = mesh_.edge_handle(h);
    const int pf = face_patch_[static_cast<std::size_t>(mesh_.face_handle(h).idx())];
    const int pg = mesh_.is_boundary(e) ? pf : face_patch_[static_cast<std::size_t>(mesh_.opposite_face_handle(h).idx())];
    const bool both_features = is_feature[static_cast<std::size_t>(vertex_node[static_cast<std::size_t>(va.idx())])] != 0 &&
                               is_feature[static_cast<std::size_t>(vertex_node[static_cast<std::size_t>(vb.idx())])] != 0;
    info = NodeInfo{};
    info.curve = a.curve >= 0 ? a.curve : b.curve;
    if (mesh_.is_boundary(e) || (pf != pg && both_features)) {
      on_segment = true;
      info.is_corner = info.curve < 0;  // its edges along the segment stay locked
      return true;
    }
    on_segment = false;
    info.is_movable = true;
    info.patch0 = pf;
    if (pf == pg) {
      info.curve = -1;
      return true;
    }
    info.patch1 = pg;
    return !is_locked(e) && info.curve >= 0;
  }

  // A split of h's edge (a, b) (triangles (a, b, c) and, unless one_sided, (b, a, d)) at m:
  // the new triangles (m, u, w) are (m, c, a), (m, b, c), (m, d, b), (m, a, d), (u, w) an
  // old edge. With `with_flips`, a new triangle obtuse at m whose edge (u, w) may flip (not
  // locked nor on the boundary, the far corner x of the triangle (w, u, x) across it not
  // next to m, each x once) is replaced by (m, u, x) and (m, x, w) when the flip passes
  // flip_keeps_shape(). Passes (split_sweep) when every new triangle passes the normal, alpha
  // and angle tests against the old ones (the split triangles and those across the flipped
  // edges) and they hold fewer obtuse angles. Returns the number of obtuse new triangles
  // (-1 when the split fails) and the edges to flip in `flips`.
  // `relaxed` (relaxed_split's candidates): the angle floor is angle_floor_deg +
  // kObtuseAngleMarginDeg, and as many obtuse triangles as before also pass when fewer of
  // them have their obtuse angle at a node that nothing moves (the repair after the splits
  // may then remove it).
  // A new triangle none of whose corners is a feature node (m_is_feature for m) also keeps
  // its smallest angle at least min(that of the old triangles without a feature node,
  // angle_floor_deg): issue 5's bound away from features. The others, when the split takes
  // the obtuse angle off a node that nothing moves (c), need only min(old, the floor,
  // obtuse_split_feature_angle_deg) (sin_split_feature_floor_).
  // below >= 0 (a caller that takes only a count below it): -1 as soon as the count reaches
  // it, before the other new triangles' tests; the count returned otherwise, so the caller
  // takes the same candidates.
  int evaluate_split(TriMesh::HalfedgeHandle h, bool one_sided, const Vec& m, bool m_is_feature, bool with_flips, bool relaxed,
                     std::vector<std::array<TriMesh::VertexHandle, 2>>& flips, int below = -1) const {
    flips.clear();
    if (below == 0) return -1;  // no count is below 0 (flips: none; the caller reads them only when it takes the split)
    const double sin_floor = relaxed ? sin_obtuse_floor_ : sin_angle_floor_;
    auto away = [&](std::initializer_list<TriMesh::VertexHandle> vs) {
      for (const auto v : vs) {
        if ((*is_split_feature_)[static_cast<std::size_t>((*vertex_node_)[static_cast<std::size_t>(v.idx())])] != 0) return false;
      }
      return true;
    };
    const auto o = mesh_.opposite_halfedge_handle(h);
    const auto va = mesh_.from_vertex_handle(h), vb = mesh_.to_vertex_handle(h);
    const auto vc = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h));
    const auto vd = one_sided ? TriMesh::VertexHandle() : mesh_.to_vertex_handle(mesh_.next_halfedge_handle(o));
    const Vec a = point(mesh_, va), b = point(mesh_, vb), c = point(mesh_, vc);
    const Vec d = one_sided ? Vec::Zero() : point(mesh_, vd);
    const Vec n_c = area_vector(a, b, c), n_d = one_sided ? Vec::Zero() : area_vector(b, a, d);
    double old_alpha = alpha_with_area(a, b, c, n_c.norm());
    double old_sine = alpha_and_min_angle_sine(a, b, c, n_c.norm())[1];
    double old_sine_away = away({va, vb, vc}) ? old_sine : 1.0;
    auto movable = [&](TriMesh::VertexHandle v) { return nodes_[static_cast<std::size_t>(v.idx())].is_movable; };
    // 1 when (p0, p1, p2) has its obtuse angle at a node that nothing moves.
    auto fixed_obtuse = [&](TriMesh::VertexHandle h0, const Vec& p0, TriMesh::VertexHandle h1, const Vec& p1,
                            TriMesh::VertexHandle h2, const Vec& p2) {
      return int((!movable(h0) && (p1 - p0).dot(p2 - p0) < 0.0) || (!movable(h1) && (p2 - p1).dot(p0 - p1) < 0.0) ||
                 (!movable(h2) && (p0 - p2).dot(p1 - p2) < 0.0));
    };
    int old_fixed = fixed_obtuse(va, a, vb, b, vc, c);
    int old_obtuse = int(triangle_is_obtuse(a, b, c));
    if (!one_sided) {
      old_fixed += fixed_obtuse(vb, b, va, a, vd, d);
      old_alpha = std::min(old_alpha, alpha_with_area(b, a, d, n_d.norm()));
      const double sine_d = alpha_and_min_angle_sine(b, a, d, n_d.norm())[1];
      old_sine = std::min(old_sine, sine_d);
      if (away({va, vb, vd})) old_sine_away = std::min(old_sine_away, sine_d);
      old_obtuse += int(triangle_is_obtuse(b, a, d));
    }
    struct New {
      TriMesh::VertexHandle u, w;
      const Vec* parent;
    };
    std::array<New, 4> sides{New{vc, va, &n_c}, New{vb, vc, &n_c}, New{vd, vb, &n_d}, New{va, vd, &n_d}};
    const std::size_t n_sides = one_sided ? 2 : 4;
    // The new triangles with the normal they are compared with (none: a flip's, tested by
    // flip_keeps_shape()).
    struct Tri {
      std::array<Vec, 3> p;
      const Vec* parent;
      bool is_away;
      TriMesh::VertexHandle h1, h2;
    };
    std::array<Tri, 8> tris;
    std::size_t n_tris = 0;
    std::array<TriMesh::VertexHandle, 4> far;  // invalid handles
    for (std::size_t k = 0; k < n_sides; ++k) {
      const New& t = sides[k];
      const Vec u = point(mesh_, t.u), w = point(mesh_, t.w);
      if (with_flips && (u - m).dot(w - m) < 0.0) {
        const auto g = mesh_.find_halfedge(t.w, t.u);
        const auto e = mesh_.edge_handle(g);
        const auto vx = mesh_.is_boundary(g) ? TriMesh::VertexHandle() : mesh_.to_vertex_handle(mesh_.next_halfedge_handle(g));
        const bool free_x = vx.is_valid() && vx != va && vx != vb && vx != vc && vx != vd &&
                            std::find(far.begin(), far.end(), vx) == far.end();
        FlipQuad q;
        if (free_x && !mesh_.is_boundary(e) && !is_locked(e)) {
          q.a = u, q.b = w, q.c = m, q.d = point(mesh_, vx);
          if (flip_keeps_shape(q)) {
            far[k] = vx;
            const Vec x = q.d;
            old_alpha = std::min(old_alpha, alpha_with_area(w, u, x, q.l1));
            const double sine_x = alpha_and_min_angle_sine(w, u, x, q.l1)[1];
            old_sine = std::min(old_sine, sine_x);
            if (away({t.w, t.u, vx})) old_sine_away = std::min(old_sine_away, sine_x);
            old_obtuse += int(triangle_is_obtuse(w, u, x));
            old_fixed += fixed_obtuse(t.w, w, t.u, u, vx, x);
            tris[n_tris++] = {{m, u, x}, nullptr, !m_is_feature && away({t.u, vx}), t.u, vx};
            tris[n_tris++] = {{m, x, w}, nullptr, !m_is_feature && away({vx, t.w}), vx, t.w};
            flips.push_back({t.u, t.w});
            continue;
          }
        }
      }
      tris[n_tris++] = {{m, u, w}, t.parent, !m_is_feature && away({t.u, t.w}), t.u, t.w};
    }
    int new_obtuse = 0, new_fixed = 0;
    // The obtuse angle at c, a node that nothing moves: only a split takes it off.
    const bool off_fixed = !movable(vc) && (a - c).dot(b - c) < 0.0;
    const double sin_feature_floor = off_fixed ? std::min(sin_floor, sin_split_feature_floor_) : sin_floor;
    for (std::size_t k = 0; k < n_tris; ++k) {
      const auto& [p, parent, is_away, h1, h2] = tris[k];
      const bool obtuse = triangle_is_obtuse(p[0], p[1], p[2]);
      if (below >= 0 && new_obtuse + int(obtuse) >= below) return -1;
      const Vec n = area_vector(p[0], p[1], p[2]);
      const double l = n.norm();
      if (l <= min_double_area_) return -1;
      if (parent != nullptr && n.dot(*parent) <= options_.min_normal_dot * l * parent->norm()) return -1;
      const auto [alpha, sine] = alpha_and_min_angle_sine(p[0], p[1], p[2], l);
      if (alpha < std::min(old_alpha, options_.alpha_floor)) return -1;
      if (sine < std::min(old_sine, is_away ? sin_floor : sin_feature_floor) * (1.0 - tolerance::kSplitSineRelative)) return -1;
      if (is_away && sine < std::min(old_sine_away, sin_floor) * (1.0 - tolerance::kSplitSineRelative)) return -1;
      new_obtuse += int(obtuse);
      new_fixed += int((!movable(h1) && (p[2] - p[1]).dot(p[0] - p[1]) < 0.0) || (!movable(h2) && (p[0] - p[2]).dot(p[1] - p[2]) < 0.0));
    }
    if (relaxed && new_obtuse == old_obtuse && new_fixed < old_fixed) return new_obtuse;
    return new_obtuse < old_obtuse ? new_obtuse : -1;
  }

  // The cosine of the angle between x and y (1 when one is zero).
  static double cosine(const Vec& x, const Vec& y) {
    const double l = x.norm() * y.norm();
    return l > 0.0 ? x.dot(y) / l : 1.0;
  }

  // target moved onto the fitted surface(s) of a movable node (see smoothing_sweep) by
  // project_onto_patches (NaN where a detail-fitted patch has none of its input faces below:
  // its projection there is the fit's, unheld, off the input by up to the fit's miss;
  // headsq@500 with the detail fit: a movable corner 1.8 voxels off, the run's Hausdorff
  // 2.47 -> 1.74 without); for a node of a fin rim curve, no farther than info.max_move from
  // info.origin.
  Vec project(const NodeInfo& info, const Vec& target) const {
    std::array<int, 2> pair{info.patch0, info.patch1};
    const std::span<const int> patches =
        info.corner_slot >= 0 ? std::span<const int>(corner_patches_[static_cast<std::size_t>(info.corner_slot)])
                              : std::span<const int>(pair.data(), info.curve < 0 ? 1 : 2);
    const Vec q = project_onto_patches(surface_, patches, target);
    return std::isfinite(info.max_move) ? clamp_to_ball(q, info.origin, info.max_move) : q;
  }

  // The tests of a move of a node from p to q, its triangles in `ring`: no triangle
  // degenerates or turns its normal by more than acos(min_normal_dot); the smallest alpha
  // stays at least min(old smallest, alpha_floor) and the sine of the smallest angle at
  // least min(old, sin_floor): the old ring is needed only below the floors. sine_skip:
  // sqrt(3) (sin_floor + tolerance::kSineSkipMargin), see alpha_sine_skip_.
  bool passes_ring_tests(const std::vector<RingTriangle>& ring, const Vec& p, const Vec& q, double sin_floor,
                         double sine_skip) const {
    double new_min = 1.0, new_sine = 1.0;  // smallest alpha, sine of the smallest angle
    for (const RingTriangle& t : ring) {
      const Vec n_new = area_vector(q, t.b, t.c);
      const double l_new = n_new.norm();
      if (l_new <= min_double_area_ || (t.l_old > 0.0 && n_new.dot(t.n_old) <= options_.min_normal_dot * t.l_old * l_new)) {
        return false;
      }
      const auto [alpha, sine] = alpha_and_min_angle_sine(q, t.b, t.c, l_new, sine_skip);
      new_min = std::min(new_min, alpha);
      new_sine = std::min(new_sine, sine);
    }
    if (new_min < options_.alpha_floor) {
      double old_min = 1.0;
      for (const RingTriangle& t : ring) old_min = std::min(old_min, alpha_with_area(p, t.b, t.c, t.l_old));
      if (!(new_min >= old_min)) return false;
    }
    if (new_sine < sin_floor) {
      double old_sine = 1.0;
      for (const RingTriangle& t : ring) old_sine = std::min(old_sine, alpha_and_min_angle_sine(p, t.b, t.c, t.l_old)[1]);
      if (!(new_sine >= old_sine)) return false;
    }
    return true;
  }

  // StitchOptions::fin_rim_max_move: the vertices of the nodes of fin rim curves (corners
  // included) get their bound and origin.
  void bound_fin_rim_nodes(const std::vector<int>& vertex_node) {
    const FinRimBound bound = fin_rim_bound(surface_, options_);
    if (bound.on_rim.empty()) return;
    for (auto v : mesh_.vertices()) {
      const int node = vertex_node[static_cast<std::size_t>(v.idx())];
      if (!bound.is_bounded(node)) continue;
      NodeInfo& info = nodes_[static_cast<std::size_t>(v.idx())];
      info.max_move = bound.radius;
      info.origin = surface_.nodes[static_cast<std::size_t>(node)];
    }
  }

  void classify_nodes(const std::vector<int>& vertex_node) {
    nodes_.assign(mesh_.n_vertices(), NodeInfo{});
    bound_fin_rim_nodes(vertex_node);
    for (auto v : mesh_.vertices()) {
      const auto node = static_cast<std::size_t>(vertex_node[static_cast<std::size_t>(v.idx())]);
      NodeInfo& info = nodes_[static_cast<std::size_t>(v.idx())];
      switch (surface_.node_kind[node]) {
        case NodeKind::Corner: {
          info.is_corner = true;
          // A corner where only smooth curves meet moves onto the mean of its patches'
          // surfaces: two corners close together otherwise keep a short edge.
          if (is_feature_[node] != 0 || mesh_.is_boundary(v)) break;
          std::vector<int> patches;
          for (auto f : mesh_.vf_range(v)) patches.push_back(face_patch_[static_cast<std::size_t>(f.idx())]);
          std::sort(patches.begin(), patches.end());
          patches.erase(std::unique(patches.begin(), patches.end()), patches.end());
          info.corner_slot = static_cast<int>(corner_patches_.size());
          info.is_movable = true;
          corner_patches_.push_back(std::move(patches));
          break;
        }
        case NodeKind::Inner:
          info.patch0 = surface_.node_owner[node];
          info.is_movable = true;
          break;
        case NodeKind::Border: {
          info.curve = surface_.node_owner[node];
          // The patches of its triangles, before any flip: exactly two for a node that may move.
          int p0 = -1, p1 = -1;
          bool more = false;
          for (auto f : mesh_.vf_range(v)) {
            const int p = face_patch_[static_cast<std::size_t>(f.idx())];
            if (p0 < 0 || p == p0) {
              p0 = p;
            } else if (p1 < 0 || p == p1) {
              p1 = p;
            } else {
              more = true;
            }
          }
          info.patch0 = p0;
          info.patch1 = p1;
          info.is_movable = !more && p1 >= 0 && !surface_.curve_is_feature[static_cast<std::size_t>(info.curve)];
          break;
        }
      }
    }
  }

  // Every test of a flip of e but OpenMesh's is_flip_ok() (it circulates a vertex and is
  // asked last: few edges pass the quality test). c and d may be one vertex here; the area
  // test then refuses. Reads the mesh only.
  bool passes_flip_test(TriMesh::EdgeHandle e) const {
    FlipQuad q;
    if (!flip_quad(e, q) || !flip_keeps_shape(q)) return false;
    // The smaller new alpha must exceed the bound: the second new triangle is measured
    // only when the first does.
    const double bound =
        (1.0 + options_.flip_gain) * std::min(alpha_with_area(q.a, q.b, q.c, q.l0), alpha_with_area(q.b, q.a, q.d, q.l1));
    return alpha_with_area(q.a, q.d, q.c, q.l2) > bound && alpha_with_area(q.d, q.b, q.c, q.l3) > bound;
  }

  // The two triangles of an edge (a, b) and their far corners c, d: old triangles
  // (a, b, c), (b, a, d), after a flip (a, d, c), (d, b, c); n0..n3 their area vectors,
  // l0..l3 the norms (set by flip_keeps_shape).
  struct FlipQuad {
    Vec a, b, c, d, n0, n1, n2, n3;
    double l0 = 0.0, l1 = 0.0, l2 = 0.0, l3 = 0.0;
  };

  // The corners of e's flip; false for a boundary or locked edge.
  bool flip_quad(TriMesh::EdgeHandle e, FlipQuad& q) const {
    if (mesh_.is_boundary(e) || is_locked(e)) return false;
    const auto h0 = mesh_.halfedge_handle(e, 0);
    const auto h1 = mesh_.halfedge_handle(e, 1);
    q.a = point(mesh_, mesh_.from_vertex_handle(h0));
    q.b = point(mesh_, mesh_.to_vertex_handle(h0));
    q.c = point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h0)));
    q.d = point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h1)));
    return true;
  }

  // The shape tests every flip passes: the new triangles are not degenerate, old and new
  // pairs are within max_flip_dihedral_deg, and the new triangles keep the old side.
  bool flip_keeps_shape(FlipQuad& q) const {
    q.n0 = area_vector(q.a, q.b, q.c), q.n1 = area_vector(q.b, q.a, q.d);
    q.n2 = area_vector(q.a, q.d, q.c), q.n3 = area_vector(q.d, q.b, q.c);
    q.l2 = q.n2.norm(), q.l3 = q.n3.norm();
    if (q.l2 <= min_double_area_ || q.l3 <= min_double_area_) return false;
    q.l0 = q.n0.norm(), q.l1 = q.n1.norm();
    if (!within_dihedral(q.n0, q.n1, q.l0, q.l1) || !within_dihedral(q.n2, q.n3, q.l2, q.l3)) return false;
    // n / |n| as Eigen's normalized() (a zero vector stays zero).
    const Vec old_normal = (q.l0 > 0.0 ? Vec(q.n0 / q.l0) : q.n0) + (q.l1 > 0.0 ? Vec(q.n1 / q.l1) : q.n1);
    return q.n2.dot(old_normal) > 0.0 && q.n3.dot(old_normal) > 0.0;
  }

  // feature_pieces_ from SurfaceMesh::curve_nodes (an open curve runs from corner to corner;
  // a closed one, its first node no corner, also joins its last node to its first).
  void collect_feature_pieces() {
    if (surface_.curve_nodes.size() != surface_.curve_is_feature.size()) return;
    has_feature_pieces_ = true;
    auto add = [this](int x, int y) { feature_pieces_.emplace_back(std::min(x, y), std::max(x, y)); };
    for (std::size_t c = 0; c < surface_.curve_nodes.size(); ++c) {
      if (surface_.curve_is_feature[c] == 0) continue;
      const std::vector<int>& list = surface_.curve_nodes[c];
      for (std::size_t k = 0; k + 1 < list.size(); ++k) add(list[k], list[k + 1]);
      if (list.size() >= 3 && surface_.node_kind[static_cast<std::size_t>(list.front())] != NodeKind::Corner) add(list.back(), list.front());
    }
    std::sort(feature_pieces_.begin(), feature_pieces_.end());
  }

  // Whether the nodes of u and w are next to each other along a feature curve (a split's
  // node is on none: its pieces of a crease lie between two patches, never inside one).
  bool is_feature_piece(TriMesh::VertexHandle u, TriMesh::VertexHandle w) const {
    const int x = vertex_node_of_[static_cast<std::size_t>(u.idx())];
    const int y = vertex_node_of_[static_cast<std::size_t>(w.idx())];
    return std::binary_search(feature_pieces_.begin(), feature_pieces_.end(), std::pair<int, int>(std::min(x, y), std::max(x, y)));
  }

  // An edge between two patches lies on a border curve; it may flip only when the curve
  // is known (one end is a border node) and is not a feature. An edge inside a patch joining
  // two nodes of one feature curve (or a corner and a feature curve's node) is locked too,
  // unless StitchOptions::flip_feature_chords and the two nodes are no neighbours along a
  // feature curve (feature_pieces_): a chord across the patch, not a piece of the crease.
  bool is_locked(TriMesh::EdgeHandle e) const {
    const auto h = mesh_.halfedge_handle(e, 0);
    const int pf = face_patch_[static_cast<std::size_t>(mesh_.face_handle(h).idx())];
    const int pg = face_patch_[static_cast<std::size_t>(mesh_.opposite_face_handle(h).idx())];
    const NodeInfo& a = nodes_[static_cast<std::size_t>(mesh_.from_vertex_handle(h).idx())];
    const NodeInfo& b = nodes_[static_cast<std::size_t>(mesh_.to_vertex_handle(h).idx())];
    // Both ends on one feature curve (or a corner and a feature curve's node): a crease edge.
    const int curve = a.curve >= 0 ? a.curve : b.curve;
    const bool on_curve = (a.curve >= 0 || a.is_corner) && (b.curve >= 0 || b.is_corner) &&
                          (a.curve < 0 || b.curve < 0 || a.curve == b.curve);
    if (on_curve && curve >= 0 && surface_.curve_is_feature[static_cast<std::size_t>(curve)]) {
      return pf != pg || !has_feature_pieces_ || is_feature_piece(mesh_.from_vertex_handle(h), mesh_.to_vertex_handle(h));
    }
    if (pf == pg) return false;
    return !on_curve || curve < 0;
  }

  // l0, l1: the norms of n0, n1.
  bool within_dihedral(const Vec& n0, const Vec& n1, double l0, double l1) const {
    return n0.dot(n1) >= cos_dihedral_ * l0 * l1;
  }

  const SurfaceMesh& surface_;
  const StitchOptions& options_;
  TriMesh& mesh_;
  std::vector<int>& face_patch_;  // grows with obtuse splits
  const std::vector<std::uint8_t>& is_feature_;
  std::vector<NodeInfo> nodes_;
  // The node of each vertex (StitchResult::vertex_node: it grows with the splits).
  const std::vector<int>& vertex_node_of_;
  // StitchOptions::flip_feature_chords: the pairs of nodes next to each other along a feature
  // curve (SurfaceMesh::curve_nodes; lower id first, sorted), and whether they are known (a
  // hand-made SurfaceMesh without curve_nodes: every such chord stays locked).
  std::vector<std::pair<int, int>> feature_pieces_;
  bool has_feature_pieces_ = false;
  std::vector<std::vector<int>> corner_patches_;
  std::vector<RingTriangle> ring_;
  double min_double_area_ = 0.0;
  double cos_dihedral_ = 1.0;
  double sin_angle_floor_ = 0.0;
  // The sine of a triangle's smallest angle is at least alpha / sqrt(3) (twice the area is
  // alpha (l1^2 + l2^2 + l3^2) / (2 sqrt(3)), and the two longest edges' squares sum to at
  // least twice their product). A new ring triangle with alpha above sqrt(3) (floor + a
  // margin tolerance::kSineSkipMargin, far above the rounding) is surely not below the angle
  // floor: its sine is not computed (1 in its place). new_sine is compared only with the
  // floor, and below the floor it is the smallest computed sine: the same decisions as with
  // every sine.
  double alpha_sine_skip_ = 0.0;
  // Edges per chunk of the parallel flip tests.
  static constexpr std::size_t kEdgeChunk = 4096;
  // The obtuse repair's moves and flips keep the smallest angle around them at least
  // min(old, angle_floor_deg + this margin): at the floor itself the scenes' smallest angles
  // away from features fell to it (sphere at 128 cells 30.2 -> 25.8 deg, DRAM 25.7 -> 25.0);
  // a 5 deg margin kept more obtuse triangles (liver 0.94 -> 1.00%, headsq@1150 7.66 -> 7.97%).
  static constexpr double kObtuseAngleMarginDeg = 2.5;
  // The obtuse repair's search stays within this share of the node's shortest edge from it
  // (without a bound, bunny00's Hausdorff rose 15%: nodes far along a fit that leaves the input).
  static constexpr double kObtuseSearchReach = 0.5;
  double sin_obtuse_floor_ = 0.0;
  double obtuse_sine_skip_ = 0.0;
  // slide_sweep: the shares of a piece a feature node tries (kSlideStep apart, up to
  // kSlideSteps steps either way: at most kSlideMaxShare, so neighbours stay 0.2 of a piece
  // apart), the sag bound (share of the piece) of the crease's edges from the front's polyline; a
  // node is on its piece within tolerance::kSlideOnCurveRelative (share of the piece).
  static constexpr double kSlideStep = 0.1;
  static constexpr int kSlideSteps = 4;
  static constexpr double kSlideMaxShare = kSlideStep * kSlideSteps;
  static constexpr double kSlideMaxSag = 0.05;
  // The sine of StitchOptions::obtuse_split_feature_angle_deg (evaluate_split).
  double sin_split_feature_floor_ = 0.0;
  // An obtuse split's node stays at least this share of the edge away from its ends.
  static constexpr double kSplitMin = 0.2;
  // A split's node projected onto the fitted surface(s) stays within this share of the
  // edge's length from the edge (a chord's sag over a radius of the edge's length is 1/8).
  static constexpr double kSplitMaxOffset = 0.125;
  // relaxed_split's rounds of moving the split's node to the mean of its ring.
  static constexpr int kRelaxedSplitIterations = 3;
  // grid_split's step, a share of the split edge's length (session 18, the grid only for
  // obtuse angles at fixed nodes: cheese 1.644 / 1.648 / 1.681 / 1.729% obtuse at 0.05 / 0.1 /
  // 0.15 / 0.2; rotor 1.087% at 0.05, 1.010% at 0.075 and 0.1).
  static constexpr double kSplitGridStep = 0.1;
  // split_sweep's node ids and feature flags (they grow with the splits).
  const std::vector<int>* vertex_node_ = nullptr;
  const std::vector<std::uint8_t>* is_split_feature_ = nullptr;
  // split_sweep's scratch on the calling thread (SplitScratch).
  SplitScratch split_scratch_;

 public:
  std::size_t n_split_flips_ = 0;  // flips made by split_sweep
};

}  // namespace

std::vector<double> face_alphas(const TriMesh& mesh, unsigned n_threads, std::size_t chunk) {
  const bool has_status = mesh.has_face_status();
  return select_in_order<double>(mesh.n_faces(), n_threads, chunk, [&mesh, has_status](std::size_t i, double& alpha) {
    const TriMesh::FaceHandle f(static_cast<int>(i));
    if (has_status && mesh.status(f).deleted()) return false;
    std::array<Vec, 3> p;
    int k = 0;
    for (auto v : mesh.fv_range(f)) p[static_cast<std::size_t>(k++)] = point(mesh, v);
    alpha = triangle_alpha(p[0], p[1], p[2]);
    return true;
  });
}

void optimise(const SurfaceMesh& surface, const StitchOptions& options, const std::vector<std::uint8_t>& is_feature,
              StitchResult& result, StitchReport& report) {
  Optimiser optimiser(surface, options, result, is_feature);
  for (int pass = 0; pass < options.optimisation_passes; ++pass) {
    report_progress(options.progress, "stitch: optimise", double(pass) / options.optimisation_passes);
    report.n_flips += optimiser.flip_sweep();
    const auto counts = optimiser.smoothing_sweep();
    report.n_smoothing_moves += counts[0];
    report.n_smoothing_rejected += counts[1];
  }
  for (int round = 0; round < options.obtuse_repair_rounds; ++round) {
    report.n_flips += optimiser.obtuse_flip_sweep();
    report.n_smoothing_moves += optimiser.obtuse_sweep();
  }
  // The slides are part of the obtuse repair: none without it.
  for (int round = 0; options.obtuse_repair_rounds > 0 && round < options.feature_slide_rounds; ++round) {
    const std::size_t n_slides = optimiser.slide_sweep(result.vertex_node);
    report.n_feature_slides += n_slides;
    if (n_slides == 0) break;
    report.n_flips += optimiser.obtuse_flip_sweep();
    report.n_smoothing_moves += optimiser.obtuse_sweep();
  }
  report_progress(options.progress, "stitch: optimise", 1.0);
}

std::array<std::size_t, 2> repair_obtuse_once(const SurfaceMesh& surface, const StitchOptions& options,
                                              const std::vector<std::uint8_t>& is_feature, StitchResult& result) {
  Optimiser optimiser(surface, options, result, is_feature);
  const std::size_t n_flips = optimiser.obtuse_flip_sweep();
  return {n_flips, optimiser.obtuse_sweep()};
}

SplitResult split_obtuse(const SurfaceMesh& surface, const StitchOptions& options, std::vector<std::uint8_t>& is_feature,
                         StitchResult& result, const std::vector<std::array<int, 2>>& refused) {
  SplitResult out;
  Optimiser optimiser(surface, options, result, is_feature);
  for (int round = 0; round < options.obtuse_split_rounds; ++round) {
    const std::size_t n = optimiser.split_sweep(result.vertex_node, is_feature, refused, out.made, out.split_edges);
    if (n == 0) break;
    out.n_splits += n;
  }
  if (out.n_splits == 0) return out;
  // The repair once more around the new nodes: their rings' vertices.
  std::vector<std::uint8_t>& near = out.near;
  near.assign(result.mesh.n_vertices(), 0);
  for (const auto v : out.made) {
    near[static_cast<std::size_t>(v.idx())] = 1;
    for (auto u : result.mesh.vv_range(v)) near[static_cast<std::size_t>(u.idx())] = 1;
  }
  out.n_flips = optimiser.n_split_flips_ + optimiser.obtuse_flip_sweep(near);
  out.n_moves = optimiser.obtuse_sweep(near);
  return out;
}

Vec project_onto_patches(const SurfaceMesh& surface, std::span<const int> patches, const Vec& target) {
  for (const int patch : patches) {
    // (A hand-made SurfaceMesh may have no patch reports: no detail fit then.)
    if (patch < 0 || static_cast<std::size_t>(patch) >= surface.patches.size() ||
        !surface.patches[static_cast<std::size_t>(patch)].detail_fit)
      continue;
    const PatchSurface& s = surface.surfaces[static_cast<std::size_t>(patch)];
    if (!s.input_heights) continue;
    const Vec l = s.frame.to_local(target);
    double z = 0.0;
    if (!s.input_heights->height(l.x(), l.y(), z)) return Vec::Constant(std::numeric_limits<double>::quiet_NaN());
  }
  Vec q = Vec::Zero();
  for (const int patch : patches) q += surface.surfaces[static_cast<std::size_t>(patch)].project(target);
  return q / static_cast<double>(patches.size());
}

}  // namespace nurbsfront::stitch_detail
