// SPDX-License-Identifier: BSD-3-Clause
// Small angles away from features (issue 5): after the optimisation and the crossing
// repair, each triangle with no feature node and a smallest angle below
// kAwayFromFeaturesAngleBoundDeg gets the best of a flip of one of its edges or a collapse
// of one of its edges (the survivor stays where it is), when the change raises the smallest
// angle of the triangles it touches and leaves fewer of them below the bound (docs/stitch.md,
// "Small angles left after the optimisation"). What the collapse before the optimisation
// and the sweeps leave: triangles of patches of one or two input faces between corners a
// fraction of h apart, whose nodes are all border nodes and corners (no collapse along a
// curve helps), and triangles the flips and moves made next to a worse one. Where no single
// change is better, a pair of changes is tried on a copy of the triangle's neighbourhood
// (repair_in_two_steps).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <span>

#include <Eigen/Geometry>

#include <OpenMesh/Core/Utils/Property.hh>

#include "nurbsfront/core/soup.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/stitch/stitch_internal.h"

namespace nurbsfront::stitch_detail {

namespace {

using Vec = Eigen::Vector3d;

// Rounds of the crossing check before the repair is given up as a whole.
constexpr int kCheckRounds = 4;
// A collapse's removed node stays within this many input mean edges of the new triangles
// (the survivor does not move: the surface changes only by the removed node's cone), a
// moved node within as much of its old triangles.
constexpr double kMaxCollapseOffsetEdges = 0.5;
// The obtuse collapses' angle floor above angle_floor_deg away from features (deg), as the
// obtuse repair's and splits' (Optimiser::kObtuseAngleMarginDeg).
constexpr double kObtuseCollapseMarginDeg = 2.5;
// The obtuse collapses' removed node stays within this many input mean edges of the new
// triangles (kMaxCollapseOffsetEdges for the others): at 0.5 the rotor's Hausdorff distance
// grew 24% and headsq@500's 4% (docs/stitch.md "Obtuse collapses, session 20").
constexpr double kObtuseCollapseOffsetEdges = 0.15;
// The obtuse collapses together change a closed mesh's enclosed volume by at most this
// fraction of it (their signed changes summed in the order made; a collapse that would take
// the sum beyond is refused): they come after the volume compensation, which nothing then
// makes up (the gear prism of Pipeline.GearPrismKeepsItsVolume went from 0.33% to 0.90% off
// without the bound; docs/stitch.md "Obtuse collapses by default, session 21").
constexpr double kObtuseCollapseVolumeBudget = 0.0005;

// What a set of triangles has: the sine of its smallest angle, how many are below the bound
// and how many are obtuse. A change is better when the smallest angle rises, no more
// triangles are below the bound and no more are obtuse, and (collapse) fewer are below.
// The obtuse collapses (AngleRepair::obtuse_sweep) also use the smallest alpha and the
// smallest angles of the triangles without and with a feature node apart.
struct Shape {
  double min_sine = 1.0;
  int n_small = 0;
  int n_obtuse = 0;
  double min_alpha = 1.0;
  double min_sine_away = 1.0;     // of the triangles with no feature node
  double min_sine_feature = 1.0;  // of the others
  void add(const Vec& a, const Vec& b, const Vec& c, double sin_bound, bool away = true) {
    const double s = smallest_angle_sine(a, b, c);
    double& side = away ? min_sine_away : min_sine_feature;
    side = std::min(side, s);
    const double sum_sq = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
    min_alpha = std::min(min_alpha, sum_sq > 0.0 ? 2.0 * std::numbers::sqrt3 * (b - a).cross(c - a).norm() / sum_sq : 0.0);
    min_sine = std::min(min_sine, s);
    n_small += s < sin_bound ? 1 : 0;
    n_obtuse += triangle_is_obtuse(a, b, c) ? 1 : 0;
  }
};

// Pushes of a node away from another sheet it crosses (lever (a), docs/stitch.md "Fin rims:
// moves away from the other sheet"): the factors of the neighbours' mean height over the
// crossed face by which a pushed node rises above the face's plane, tried in turn.
constexpr std::array<double, 3> kPushFactors{1.0, 2.0, 4.0};

class AngleRepair {
 public:
  AngleRepair(const SurfaceMesh& surface, const StitchOptions& options, const std::vector<std::uint8_t>& is_feature,
              const std::vector<std::uint8_t>& is_frozen, StitchResult& result)
      : surface_(surface), options_(options), is_feature_(is_feature), is_frozen_(is_frozen), result_(result),
        mesh_(result.mesh), own_rim_(fin_rim_bound(surface, options)), rim_(own_rim_) {
    const double diagonal = bounding_box(mesh_).diagonal();
    min_double_area_ = 2.0 * tolerance::kDegenerateAreaRelative * diagonal * diagonal;
    sin_bound_ = std::sin(kAwayFromFeaturesAngleBoundDeg * std::numbers::pi / 180.0);
    cos_dihedral_ = std::cos(options.max_flip_dihedral_deg * std::numbers::pi / 180.0);
    // A hand-made SurfaceMesh may have no input_mean_edge: its own mean edge then.
    max_offset_ = kMaxCollapseOffsetEdges * (surface.input_mean_edge > 0.0 ? surface.input_mean_edge : mean_edge_length(mesh_));
  }

  // The repair on a copy of a part of whole's mesh, with whole's bounds.
  AngleRepair(const SurfaceMesh& surface, const StitchOptions& options, const std::vector<std::uint8_t>& is_feature,
              const std::vector<std::uint8_t>& is_frozen, StitchResult& part, const AngleRepair& whole)
      : surface_(surface), options_(options), is_feature_(is_feature), is_frozen_(is_frozen), result_(part),
        mesh_(part.mesh), rim_(whole.rim_), min_double_area_(whole.min_double_area_), sin_bound_(whole.sin_bound_),
        cos_dihedral_(whole.cos_dihedral_), max_offset_(whole.max_offset_) {}

  // rim_ may refer to own_rim_: no copies.
  AngleRepair(const AngleRepair&) = delete;
  AngleRepair& operator=(const AngleRepair&) = delete;

  // The triangles below the bound with no feature node (not deleted), (sine, face index) in
  // face order: the whole-mesh scan, on options_.n_threads threads (select_in_order).
  std::vector<std::pair<double, int>> small_faces() const {
    return small_away_faces(mesh_, result_.vertex_node, is_feature_, sin_bound_, options_.n_threads);
  }

  // One sweep over the triangles below the bound (bad: small_faces() of the mesh now),
  // worst first. Returns the changes made.
  std::size_t sweep(std::vector<std::pair<double, int>> bad) {
    std::sort(bad.begin(), bad.end());
    std::size_t n_changes = 0;
    for (const auto& [unused, index] : bad) {
      const TriMesh::FaceHandle f(index);
      double s = 0.0;
      if (mesh_.status(f).deleted() || !is_small_away(f, s)) continue;
      n_changes += repair(f) ? 1 : 0;
    }
    return n_changes;
  }

  // Removes the deleted elements, carrying face_patch and vertex_node along (OpenMesh's
  // garbage_collection() bit for bit, without its per-element property lookups).
  void collect_garbage() {
    if (n_collapses_ == 0) return;
    stitch_detail::collect_garbage(result_);
  }

  std::size_t n_flips_ = 0, n_collapses_ = 0, n_moves_ = 0, n_two_steps_ = 0, n_searches_ = 0;
  //! Of n_collapses_, those of obtuse_sweep().
  std::size_t n_obtuse_collapses_ = 0;
  //! Nodes whose triangles a change made (for the crossing check).
  std::vector<int> changed_nodes_;

 private:
  int node(TriMesh::VertexHandle v) const { return result_.vertex_node[static_cast<std::size_t>(v.idx())]; }
  bool is_feature(TriMesh::VertexHandle v) const { return is_feature_[static_cast<std::size_t>(node(v))] != 0; }
  // A node made by an obtuse split (no node of the SurfaceMesh) ranks as a border node.
  int rank_of(TriMesh::VertexHandle v) const {
    const auto g = static_cast<std::size_t>(node(v));
    return g < surface_.node_kind.size() ? node_rank(surface_.node_kind[g]) : 1;
  }
  bool is_frozen(TriMesh::VertexHandle v) const { return is_frozen_[static_cast<std::size_t>(node(v))] != 0; }

  // A triangle with no feature node whose smallest angle is below the bound (s: its sine).
  bool is_small_away(TriMesh::FaceHandle f, double& s) const {
    std::array<Vec, 3> p;
    int k = 0;
    for (auto v : mesh_.fv_range(f)) {
      if (is_feature(v)) return false;
      p[static_cast<std::size_t>(k++)] = point(mesh_, v);
    }
    s = smallest_angle_sine(p[0], p[1], p[2]);
    return s < sin_bound_;
  }

  using Step = AngleChange;

  // The best change around f (a flip or a collapse of one of its edges, or a move of one of
  // its nodes), made; else the best pair of changes there (repair_in_two_steps); false when
  // neither is better.
  bool repair(TriMesh::FaceHandle f) {
    Step step;
    if (best_step(f, step) >= 0.0) {
      apply(step);
      return true;
    }
    if (repair_in_two_steps(f)) return true;
    // Last, a finer search for a place of one of f's nodes (search_move).
    double best = -1.0;
    for (auto v : mesh_.fv_range(f)) {
      Vec q = Vec::Zero();
      const double s = search_move(v, q);
      if (s > best) {
        best = s;
        step = {Step::Kind::Move, v, TriMesh::VertexHandle(), q};
      }
    }
    if (!(best >= 0.0) || !apply(step)) return false;
    ++n_searches_;
    return true;
  }

  // The best change around f (see repair) and the sine of the smallest angle of the
  // triangles it makes; -1 when none is better.
  double best_step(TriMesh::FaceHandle f, Step& step) const {
    double best = -1.0;
    for (auto h : mesh_.fh_range(f)) {
      const double s = flip_gain(mesh_.edge_handle(h));
      if (s > best) {
        best = s;
        step = {Step::Kind::Flip, mesh_.from_vertex_handle(h), mesh_.to_vertex_handle(h), Vec::Zero()};
      }
      for (const auto g : {h, mesh_.opposite_halfedge_handle(h)}) {
        const double c = collapse_gain(g);
        if (c > best) {
          best = c;
          step = {Step::Kind::Collapse, mesh_.from_vertex_handle(g), mesh_.to_vertex_handle(g), Vec::Zero()};
        }
      }
    }
    for (auto v : mesh_.fv_range(f)) {
      Vec q = Vec::Zero();
      const double s = move_gain(v, q);
      if (s > best) {
        best = s;
        step = {Step::Kind::Move, v, TriMesh::VertexHandle(), q};
      }
    }
    return best;
  }

  // The changes allowed around f, better or not: flips and collapses of its edges, and the
  // best move of each of its nodes.
  void candidates(TriMesh::FaceHandle f, std::vector<Step>& out) const {
    for (auto h : mesh_.fh_range(f)) {
      if (flip_gain(mesh_.edge_handle(h), false) >= 0.0) out.push_back({Step::Kind::Flip, mesh_.from_vertex_handle(h), mesh_.to_vertex_handle(h), Vec::Zero()});
      for (const auto g : {h, mesh_.opposite_halfedge_handle(h)}) {
        if (collapse_gain(g, false) >= 0.0) out.push_back({Step::Kind::Collapse, mesh_.from_vertex_handle(g), mesh_.to_vertex_handle(g), Vec::Zero()});
      }
    }
    for (auto v : mesh_.fv_range(f)) {
      Vec q = Vec::Zero();
      if (move_gain(v, q) >= 0.0) out.push_back({Step::Kind::Move, v, TriMesh::VertexHandle(), q});
    }
  }

  // Makes the changes, all or none (make_angle_changes), and counts them; false (and
  // nothing made) when an edge is gone or OpenMesh refuses one.
  bool apply(std::span<const Step> steps) {
    touched_.clear();
    if (!make_angle_changes(result_, steps, &touched_)) return false;
    for (const Step& step : steps) {
      n_flips_ += step.kind == Step::Kind::Flip ? 1 : 0;
      n_collapses_ += step.kind == Step::Kind::Collapse ? 1 : 0;
      n_moves_ += step.kind == Step::Kind::Move ? 1 : 0;
    }
    for (const auto v : touched_) changed_nodes_.push_back(node(v));
    return true;
  }
  bool apply(const Step& step) { return apply(std::span<const Step>(&step, 1)); }

  // Two changes where no single one is better (two border nodes of tiny curves next to two
  // corners, each merge alone lowering the smallest angle a little because of the other):
  // each change at f that is allowed but not better by itself (candidates()), then each
  // allowed change at a triangle below the bound around the node(s) the first changed. Both
  // are made on a copy of the faces within three rings of f; the best pair (largest
  // smallest angle) is made on the whole mesh when, over the triangles the pair removes and
  // those it makes, the smallest angle rises, fewer are below the bound and at most one more
  // is obtuse per triangle lifted (is_better). The changes touch only nodes within two rings
  // of f, whose neighbours have all their faces in the copy, so OpenMesh's link and flip
  // checks answer there as on the whole mesh (apply() checks them again).
  bool repair_in_two_steps(TriMesh::FaceHandle f) {
    constexpr int kCopyRings = 3;
    // The copy: vertices by depth (ring) from f, faces of the vertices up to kCopyRings.
    local_of_.resize(mesh_.n_vertices(), -1);
    std::vector<TriMesh::VertexHandle> global_of;
    std::vector<int> depth;
    auto visit = [&](TriMesh::VertexHandle v, int d) {
      auto& l = local_of_[static_cast<std::size_t>(v.idx())];
      if (l >= 0) return;
      l = static_cast<int>(global_of.size());
      global_of.push_back(v);
      depth.push_back(d);
    };
    for (auto v : mesh_.fv_range(f)) visit(v, 0);
    for (std::size_t i = 0; i < global_of.size(); ++i) {
      if (depth[i] >= kCopyRings) continue;
      for (auto w : mesh_.vv_range(global_of[i])) visit(w, depth[i] + 1);
    }
    std::vector<int> faces;
    const std::size_t n_inner = global_of.size();
    for (std::size_t i = 0; i < n_inner; ++i) {
      for (auto g : mesh_.vf_range(global_of[i])) faces.push_back(g.idx());
    }
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    StitchResult copy;
    for (const int g : faces) {
      for (auto v : mesh_.fv_range(TriMesh::FaceHandle(g))) visit(v, kCopyRings + 1);
    }
    for (const auto v : global_of) {
      copy.mesh.add_vertex(mesh_.point(v));
      copy.vertex_node.push_back(node(v));
    }
    bool ok = true;
    for (const int g : faces) {
      std::array<TriMesh::VertexHandle, 3> t;
      int k = 0;
      for (auto v : mesh_.fv_range(TriMesh::FaceHandle(g))) t[static_cast<std::size_t>(k++)] = TriMesh::VertexHandle(local_of_[static_cast<std::size_t>(v.idx())]);
      if (!copy.mesh.add_face(t[0], t[1], t[2]).is_valid()) {
        ok = false;
        break;
      }
      copy.face_patch.push_back(result_.face_patch[static_cast<std::size_t>(g)]);
    }
    for (const auto v : global_of) local_of_[static_cast<std::size_t>(v.idx())] = -1;
    if (!ok) return false;
    // The copy's vertices are numbered as found, so f's are 0, 1, 2.
    const auto local_f = copy.mesh.face_handle(copy.mesh.find_halfedge(TriMesh::VertexHandle(0), TriMesh::VertexHandle(1)));
    AngleRepair local(surface_, options_, is_feature_, is_frozen_, copy, *this);
    std::vector<Step> firsts;
    local.candidates(local_f, firsts);
    double best = -1.0;
    std::array<Step, 2> best_pair;
    // A StitchResult with r's mesh, face patches and vertex nodes (what a change alters).
    auto mesh_copy = [](const StitchResult& r) {
      StitchResult c;
      c.mesh = r.mesh;
      c.face_patch = r.face_patch;
      c.vertex_node = r.vertex_node;
      return c;
    };
    for (const Step& first : firsts) {
      StitchResult trial = mesh_copy(copy);
      AngleRepair after_first(surface_, options_, is_feature_, is_frozen_, trial, *this);
      if (!after_first.apply(first)) continue;
      // The second: a change at a triangle below the bound that the first made.
      std::vector<TriMesh::VertexHandle> touched{first.kind == Step::Kind::Collapse ? first.to : first.from};
      if (first.kind == Step::Kind::Flip) touched.push_back(first.to);
      std::vector<Step> seconds;
      for (const auto t : touched) {
        for (auto g : trial.mesh.vf_range(t)) {
          std::array<Vec, 3> p;
          int k = 0;
          for (auto v : trial.mesh.fv_range(g)) p[static_cast<std::size_t>(k++)] = point(trial.mesh, v);
          if (!(smallest_angle_sine(p[0], p[1], p[2]) < sin_bound_)) continue;
          after_first.candidates(g, seconds);
        }
      }
      for (const Step& second : seconds) {
        StitchResult trial2 = mesh_copy(trial);
        AngleRepair after_second(surface_, options_, is_feature_, is_frozen_, trial2, *this);
        if (!after_second.apply(second)) continue;
        Shape removed, added;
        compare(copy.mesh, trial2.mesh, removed, added);
        if (!is_better(removed, added) || added.n_small >= removed.n_small || !(added.min_sine > best)) continue;
        best = added.min_sine;
        best_pair = {first, second};
      }
    }
    if (best < 0.0) return false;
    // Made on the whole mesh (the copy's vertices mapped back), both or neither: OpenMesh
    // answers there as on the copy, but should it refuse the second, the first is undone.
    for (Step& step : best_pair) {
      step.from = global_of[static_cast<std::size_t>(step.from.idx())];
      if (step.to.is_valid()) step.to = global_of[static_cast<std::size_t>(step.to.idx())];
    }
    if (!apply(best_pair)) return false;
    ++n_two_steps_;
    return true;
  }

  // What the triangles of `before` that `after` (the same vertices, changed) no longer has
  // are (removed) and what its new ones are (added); a triangle with a moved vertex counts
  // as both.
  void compare(const TriMesh& before, const TriMesh& after, Shape& removed, Shape& added) const {
    auto triangles = [](const TriMesh& m) {
      std::vector<std::array<int, 3>> t;
      for (auto g : m.faces()) {
        std::array<int, 3> x;
        int k = 0;
        for (auto v : m.fv_range(g)) x[static_cast<std::size_t>(k++)] = v.idx();
        std::rotate(x.begin(), std::min_element(x.begin(), x.end()), x.end());
        t.push_back(x);
      }
      std::sort(t.begin(), t.end());
      return t;
    };
    const auto t_before = triangles(before), t_after = triangles(after);
    auto moved = [&](const std::array<int, 3>& x) {
      return std::any_of(x.begin(), x.end(), [&](int i) { return before.point(TriMesh::VertexHandle(i)) != after.point(TriMesh::VertexHandle(i)); });
    };
    auto add = [&](const TriMesh& m, const std::array<int, 3>& x, Shape& shape) {
      shape.add(point(m, TriMesh::VertexHandle(x[0])), point(m, TriMesh::VertexHandle(x[1])), point(m, TriMesh::VertexHandle(x[2])), sin_bound_);
    };
    for (const auto& x : t_before) {
      if (moved(x) || !std::binary_search(t_after.begin(), t_after.end(), x)) add(before, x, removed);
    }
    for (const auto& x : t_after) {
      if (moved(x) || !std::binary_search(t_before.begin(), t_before.end(), x)) add(after, x, added);
    }
  }

  // The sine of the smallest angle of the two new triangles when flipping e is better than
  // leaving it (see Shape), the flip allowed and within the dihedral bound before and after,
  // the new triangles on the old side; else -1.
  double flip_gain(TriMesh::EdgeHandle e, bool require_better = true) const {
    if (mesh_.is_boundary(e)) return -1.0;
    const auto h0 = mesh_.halfedge_handle(e, 0), h1 = mesh_.halfedge_handle(e, 1);
    const auto va = mesh_.from_vertex_handle(h0), vb = mesh_.to_vertex_handle(h0);
    const auto vc = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h0));
    const auto vd = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h1));
    // Both ends are nodes of the small triangle (no feature nodes): never a crease segment.
    if (is_feature(va) || is_feature(vb)) return -1.0;
    if (is_frozen(va) || is_frozen(vb) || is_frozen(vc) || is_frozen(vd)) return -1.0;
    const Vec a = point(mesh_, va), b = point(mesh_, vb), c = point(mesh_, vc), d = point(mesh_, vd);
    const Vec n0 = (b - a).cross(c - a), n1 = (a - b).cross(d - b);
    const Vec n2 = (d - a).cross(c - a), n3 = (b - d).cross(c - d);
    const double l0 = n0.norm(), l1 = n1.norm(), l2 = n2.norm(), l3 = n3.norm();
    if (l2 <= min_double_area_ || l3 <= min_double_area_ || !(l0 > 0.0) || !(l1 > 0.0)) return -1.0;
    if (n0.dot(n1) < cos_dihedral_ * l0 * l1 || n2.dot(n3) < cos_dihedral_ * l2 * l3) return -1.0;
    const Vec old_normal = n0 / l0 + n1 / l1;
    if (!(n2.dot(old_normal) > 0.0) || !(n3.dot(old_normal) > 0.0)) return -1.0;
    Shape before, after;
    before.add(a, b, c, sin_bound_);
    before.add(b, a, d, sin_bound_);
    after.add(a, d, c, sin_bound_);
    after.add(d, b, c, sin_bound_);
    if ((require_better && !is_better(before, after)) || !mesh_.is_flip_ok(e)) return -1.0;
    return after.min_sine;
  }

  // Collapsing from(h) into to(h), which stays: the sine of the smallest angle of the
  // triangles around it afterwards when that is better than before (see Shape) and the
  // collapse allowed, else -1. Allowed: the removed node is no feature node, not on the
  // boundary and ranks no higher than the survivor (inner < border < corner); the link
  // condition holds, no two faces end on the same nodes, no triangle degenerates or turns its
  // normal by more than acos(min_normal_dot), and the removed node stays within
  // kMaxCollapseOffsetEdges input mean edges of the new triangles.
  double collapse_gain(TriMesh::HalfedgeHandle h, bool require_better = true) const {
    Shape before, after;
    if (!collapse_shapes(h, before, after)) return -1.0;
    if (require_better && (!is_better(before, after) || after.n_small >= before.n_small)) return -1.0;
    return after.min_sine;
  }

  // The triangles around from(h) before and after collapsing it into to(h) (collapse_gain):
  // false when the collapse is not allowed. max_offset: the bound on the removed node's
  // distance to the new triangles (max_offset_ when negative). survivor_feature: a triangle
  // after the collapse counts as beside a feature when the survivor to(h) is a feature node
  // (the obtuse collapses); the small-angle repair (false) counts it as before the collapse,
  // which keeps its outputs as they were (to revisit with a corpus run: session 20's review).
  bool collapse_shapes(TriMesh::HalfedgeHandle h, Shape& before, Shape& after, double max_offset = -1.0,
                       bool survivor_feature = false) const {
    const auto vb = mesh_.from_vertex_handle(h), va = mesh_.to_vertex_handle(h);
    if (is_feature(vb) || is_frozen(vb) || is_frozen(va) || mesh_.is_boundary(vb) || mesh_.is_boundary(va)) return false;
    if (rank_of(vb) > rank_of(va)) return false;
    if (!rim_.allows(node(vb), point(mesh_, va))) return false;  // the removed node goes to the survivor
    if (!mesh_.is_collapse_ok(h) || leaves_duplicate_face(mesh_, h)) return false;
    const TriMesh::FaceHandle f0 = mesh_.face_handle(h), f1 = mesh_.opposite_face_handle(h);
    const Vec pb = point(mesh_, vb), pa = point(mesh_, va);
    double offset = std::numeric_limits<double>::infinity();
    for (auto g : mesh_.vf_range(vb)) {
      std::array<Vec, 3> x;
      int k = 0;
      bool away = true;
      for (auto u : mesh_.fv_range(g)) {
        x[static_cast<std::size_t>(k++)] = point(mesh_, u);
        away = away && !is_feature(u);
      }
      before.add(x[0], x[1], x[2], sin_bound_, away);
      if (g == f0 || g == f1) continue;
      const Vec n_old = (x[1] - x[0]).cross(x[2] - x[0]);
      for (auto& y : x) {
        if (y == pb) y = pa;
      }
      const Vec n_new = (x[1] - x[0]).cross(x[2] - x[0]);
      const double l_old = n_old.norm(), l_new = n_new.norm();
      if (l_new <= min_double_area_ || (l_old > 0.0 && n_new.dot(n_old) <= options_.min_normal_dot * l_old * l_new)) return false;
      after.add(x[0], x[1], x[2], sin_bound_, away && !(survivor_feature && is_feature(va)));
      offset = std::min(offset, (quality_detail::closest_point_on_triangle(pb, x[0], x[1], x[2]) - pb).norm());
    }
    return offset <= (max_offset >= 0.0 ? max_offset : max_offset_);
  }

  // The change of the enclosed volume when from(h) collapses into to(h): the new fan's signed
  // volume minus the old's, both taken from the removed node's place (where every old term
  // vanishes). The two fans share their rim (the removed node's link), so the difference
  // does not depend on that place.
  double collapse_volume_change(TriMesh::HalfedgeHandle h) const {
    const auto vb = mesh_.from_vertex_handle(h);
    const TriMesh::FaceHandle f0 = mesh_.face_handle(h), f1 = mesh_.opposite_face_handle(h);
    const Vec pb = point(mesh_, vb), pa = point(mesh_, mesh_.to_vertex_handle(h));
    double six_volume = 0.0;
    for (auto g : mesh_.vf_range(vb)) {
      if (g == f0 || g == f1) continue;
      std::array<Vec, 3> x;
      int k = 0;
      for (auto u : mesh_.fv_range(g)) x[static_cast<std::size_t>(k++)] = (u == vb ? pa : point(mesh_, u)) - pb;
      six_volume += x[0].dot(x[1].cross(x[2]));
    }
    return six_volume / 6.0;
  }

 public:
  // Obtuse collapses (StitchOptions::obtuse_collapse; docs/stitch.md "Obtuse collapses,
  // session 20"): each triangle with an angle above 90 deg, in face order, gets one of its
  // corners that is no feature node collapsed into a neighbour (which stays): the collapse
  // that leaves the fewest obtuse triangles around the removed node (then the largest
  // smallest angle), when that is fewer than before, none more is below the bound, the
  // smallest angle of the triangles with no feature node stays at least min(old,
  // angle_floor_deg + kObtuseCollapseMarginDeg), that of the others at least min(old, that,
  // obtuse_split_feature_angle_deg) (the obtuse splits' floors), the smallest alpha at least
  // min(old, alpha_floor), with collapse_gain's other tests (rank, link condition, normals),
  // the removed node within kObtuseCollapseOffsetEdges input mean edges of the new triangles
  // and, on a closed mesh, the sum of the collapses' volume changes within
  // kObtuseCollapseVolumeBudget of its enclosed volume. Serial. Counted in n_collapses_ and
  // n_obtuse_collapses_. Returns the collapses made.
  std::size_t obtuse_sweep() {
    // The volume budget (none on an open mesh: no enclosed volume).
    const double budget = is_closed(mesh_) ? kObtuseCollapseVolumeBudget * std::abs(enclosed_volume_of(mesh_, options_.n_threads))
                                           : std::numeric_limits<double>::infinity();
    double volume_change = 0.0;  // the collapses' so far
    const double sin_floor = std::sin(std::min(options_.angle_floor_deg + kObtuseCollapseMarginDeg, 60.0) * std::numbers::pi / 180.0);
    const double sin_feature_floor = std::min(sin_floor, std::sin(options_.obtuse_split_feature_angle_deg * std::numbers::pi / 180.0));
    const double max_offset = max_offset_ * (kObtuseCollapseOffsetEdges / kMaxCollapseOffsetEdges);
    std::size_t n_made = 0;
    const std::size_t n_faces = mesh_.n_faces();
    for (std::size_t fi = 0; fi < n_faces; ++fi) {
      const TriMesh::FaceHandle f(static_cast<int>(fi));
      if (mesh_.status(f).deleted()) continue;
      TriMesh::VertexHandle v;
      std::array<TriMesh::VertexHandle, 3> corners;
      int k = 0;
      for (auto h : mesh_.fh_range(f)) {
        const auto vc = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h));
        corners[static_cast<std::size_t>(k++)] = vc;
        const Vec a = point(mesh_, mesh_.from_vertex_handle(h)), b = point(mesh_, mesh_.to_vertex_handle(h)), c = point(mesh_, vc);
        if ((a - c).dot(b - c) < 0.0) v = vc;
      }
      if (!v.is_valid()) continue;
      Step best_step;
      bool found = false;
      int best_obtuse = 0;  // the change in the count of obtuse triangles
      double best_sine = -1.0;
      double best_volume = 0.0;
      for (const auto u : corners) {
        if (!u.is_valid() || is_feature(u)) continue;
        for (auto h : mesh_.voh_range(u)) {
          Shape before, after;
          if (!collapse_shapes(h, before, after, max_offset, true)) continue;
          if (after.n_obtuse >= before.n_obtuse || after.n_small > before.n_small) continue;
          if (after.min_sine_away < std::min(before.min_sine_away, sin_floor) ||
              after.min_sine_feature < std::min(before.min_sine_feature, sin_feature_floor) ||
              after.min_alpha < std::min(before.min_alpha, options_.alpha_floor)) {
            continue;
          }
          if (found && (after.n_obtuse - before.n_obtuse > best_obtuse ||
                        (after.n_obtuse - before.n_obtuse == best_obtuse && !(after.min_sine > best_sine)))) {
            continue;
          }
          const double volume = collapse_volume_change(h);
          if (std::abs(volume_change + volume) > budget) continue;
          found = true;
          best_obtuse = after.n_obtuse - before.n_obtuse;
          best_sine = after.min_sine;
          best_volume = volume;
          best_step = {Step::Kind::Collapse, u, mesh_.to_vertex_handle(h), Vec::Zero()};
        }
      }
      if (!found || !apply(best_step)) continue;
      volume_change += best_volume;
      ++n_made;
    }
    n_obtuse_collapses_ += n_made;
    return n_made;
  }

 private:
  // Moving v (no feature node, not on the boundary) to the best of a few places on the
  // fitted surfaces of its triangles' patches (the mean of its projections onto them, as the
  // optimisation's smoothing does): halfway and all the way to the centroid of its
  // neighbours, and halfway and a quarter of the way to the apex of the equilateral triangle
  // over the far edge of each of its triangles below the bound. Returns the sine of the
  // smallest angle of its triangles at the best place (q) when that is better than before (see
  // Shape), no triangle degenerates or turns its normal by more than acos(min_normal_dot) and
  // q lies within kMaxCollapseOffsetEdges input mean edges of its old triangles; else -1.
  double move_gain(TriMesh::VertexHandle v, Vec& best_q) const {
    constexpr std::size_t kMaxPatches = 8;
    if (is_feature(v) || is_frozen(v) || mesh_.is_boundary(v)) return -1.0;
    const Vec p = point(mesh_, v);
    Shape before;
    gather_ring(v, p, before);
    if (ring_.empty() || ring_patches_.size() > kMaxPatches) return -1.0;
    Vec centroid = Vec::Zero();
    std::vector<Vec> targets;
    for (const RingTriangle& t : ring_) {
      centroid += t.b;
      if (smallest_angle_sine(p, t.b, t.c) < sin_bound_) {
        const Vec e = t.c - t.b, side = t.n.cross(e);
        const double side_norm = side.norm();
        if (side_norm > 0.0) {
          const Vec apex = 0.5 * (t.b + t.c) + (0.5 * std::numbers::sqrt3 * e.norm() / side_norm) * side;
          targets.push_back(p + 0.5 * (apex - p));
          targets.push_back(p + 0.25 * (apex - p));
        }
      }
    }
    centroid /= static_cast<double>(ring_.size());
    targets.push_back(centroid);
    targets.push_back(0.5 * (p + centroid));
    double best = -1.0;
    for (const Vec& target : targets) {
      const Vec q = project(v, ring_patches_, target);
      if (!q.allFinite() || q == p) continue;
      const std::optional<Shape> after = ring_shape(p, q);
      if (!after || !is_better(before, *after) || !(after->min_sine > best)) continue;
      best = after->min_sine;
      best_q = q;
    }
    return best;
  }

  // A finer search than move_gain's few places, where no change nor pair helps (liver: a
  // triangle at 23.9 deg whose node's best place lifts it to 26.3 deg but makes two obtuse
  // triangles, one more than the rule allows; one at 24.0 deg whose obtuse angle needs its
  // apex 0.01 h farther from the long edge): from v's place, steps in 8 directions of the
  // plane normal to its ring's area vector, each projected onto the fitted surfaces as
  // move_gain's places, the best step that raises the smallest angle of v's triangles taken
  // while it passes move_gain's tests (no more below the bound, at most one more obtuse per
  // triangle lifted, no triangle degenerate or turned too far, within kMaxCollapseOffsetEdges
  // input mean edges of the old triangles), the step halved when none does, from a quarter of
  // v's shortest edge down to 1/64 of that. Returns the sine of the smallest angle at the
  // place reached (q) when that is better than before (is_better); else -1.
  double search_move(TriMesh::VertexHandle v, Vec& best_q) const {
    constexpr int kDirections = 8;
    constexpr double kFirstStep = 0.25, kLastStep = kFirstStep / 64.0;
    constexpr int kMaxSteps = 64;
    if (is_feature(v) || is_frozen(v) || mesh_.is_boundary(v)) return -1.0;
    const Vec p = point(mesh_, v);
    Shape before;
    gather_ring(v, p, before);
    const std::vector<int>& patches = ring_patches_;
    Vec normal = Vec::Zero();
    double shortest = std::numeric_limits<double>::infinity();
    for (const RingTriangle& t : ring_) {
      normal += t.n;
      shortest = std::min(shortest, (t.b - p).norm());
    }
    if (ring_.empty() || !(normal.norm() > 0.0) || !(shortest > 0.0)) return -1.0;
    normal.normalize();
    const Vec t1 = normal.unitOrthogonal(), t2 = normal.cross(t1);
    // The shape of v's triangles with v at q, when q passes the tests; nullopt otherwise.
    auto shape_at = [&](const Vec& q) -> std::optional<Shape> {
      std::optional<Shape> after = ring_shape(p, q);
      if (after && (after->n_small > before.n_small ||
                    after->n_obtuse > before.n_obtuse + (before.n_small - after->n_small)))
        return std::nullopt;
      return after;
    };
    Vec at = p;
    Shape here = before;
    double step = kFirstStep * shortest;
    for (int i = 0; i < kMaxSteps && step >= kLastStep * shortest; ++i) {
      std::optional<Shape> best;
      Vec best_at = at;
      for (int k = 0; k < kDirections; ++k) {
        const double angle = 2.0 * std::numbers::pi * k / kDirections;
        const Vec q = project(v, patches, at + step * (std::cos(angle) * t1 + std::sin(angle) * t2));
        if (!q.allFinite()) continue;
        const std::optional<Shape> shape = shape_at(q);
        if (!shape || !(shape->min_sine > (best ? best->min_sine : here.min_sine))) continue;
        best = shape;
        best_at = q;
      }
      if (best) {
        at = best_at;
        here = *best;
      } else {
        step *= 0.5;
      }
    }
    if (!is_better(before, here)) return -1.0;
    best_q = at;
    return here.min_sine;
  }

  // target onto the fitted surfaces of `patches` as every stitch move (project_onto_patches;
  // NaN where a detail-fitted patch has no input face below), for a node of a fin rim curve
  // no farther than StitchOptions::fin_rim_max_move from where the front put it.
  Vec project(TriMesh::VertexHandle v, std::span<const int> patches, const Vec& target) const {
    return rim_.clamp(node(v), project_onto_patches(surface_, patches, target));
  }

  // v's triangles seen from its place p, for move_gain and search_move: ring_ (their far
  // corners and area vectors, around v), their shape (before) and ring_patches_ (their
  // patches, in the order first met: the order project_onto_patches averages in).
  void gather_ring(TriMesh::VertexHandle v, const Vec& p, Shape& before) const {
    ring_.clear();
    ring_patches_.clear();
    before = Shape{};
    for (auto h : mesh_.voh_range(v)) {
      const Vec b = point(mesh_, mesh_.to_vertex_handle(h));
      const Vec c = point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h)));
      ring_.push_back({b, c, (b - p).cross(c - p)});
      before.add(p, b, c, sin_bound_);
      const int patch = result_.face_patch[static_cast<std::size_t>(mesh_.face_handle(h).idx())];
      if (std::find(ring_patches_.begin(), ring_patches_.end(), patch) == ring_patches_.end()) ring_patches_.push_back(patch);
    }
  }

  // The shape of ring_'s triangles (a vertex's, from p) with the vertex at q; nullopt when one
  // degenerates or turns its normal by more than acos(min_normal_dot), or q lies farther than
  // max_offset_ from every old triangle.
  std::optional<Shape> ring_shape(const Vec& p, const Vec& q) const {
    Shape after;
    double offset = std::numeric_limits<double>::infinity();
    for (const RingTriangle& t : ring_) {
      const Vec n = (t.b - q).cross(t.c - q);
      const double l = n.norm(), l_old = t.n.norm();
      if (l <= min_double_area_ || (l_old > 0.0 && n.dot(t.n) <= options_.min_normal_dot * l * l_old)) return std::nullopt;
      after.add(q, t.b, t.c, sin_bound_);
      offset = std::min(offset, (quality_detail::closest_point_on_triangle(q, p, t.b, t.c) - q).norm());
    }
    if (!(offset <= max_offset_)) return std::nullopt;
    return after;
  }

  static bool is_better(const Shape& before, const Shape& after) {
    return after.min_sine > before.min_sine && after.n_small <= before.n_small &&
           after.n_obtuse <= before.n_obtuse + (before.n_small - after.n_small);
  }

  const SurfaceMesh& surface_;
  const StitchOptions& options_;
  const std::vector<std::uint8_t>& is_feature_;
  const std::vector<std::uint8_t>& is_frozen_;
  StitchResult& result_;
  TriMesh& mesh_;
  // StitchOptions::fin_rim_max_move: the whole mesh's repair owns it, a copy's refers to it.
  FinRimBound own_rim_;
  const FinRimBound& rim_;
  double min_double_area_ = 0.0;
  double sin_bound_ = 0.0;
  double cos_dihedral_ = 1.0;
  double max_offset_ = 0.0;
  // The far corners of a moved vertex's triangles and their old area vectors.
  struct RingTriangle {
    Vec b, c, n;
  };
  mutable std::vector<RingTriangle> ring_;
  mutable std::vector<int> ring_patches_;
  // The vertices whose triangles the last apply() changed.
  std::vector<TriMesh::VertexHandle> touched_;
  // Per vertex of mesh_, its index in repair_in_two_steps's copy (-1 between calls).
  std::vector<int> local_of_;
};

}  // namespace

// Lever (a) of docs/stitch.md "Fin rims: moves away from the other sheet" (stitch_internal.h).
Vec push_away(const TriMesh& mesh, TriMesh::VertexHandle v, TriMesh::FaceHandle g, double factor, double max_offset,
              double min_double_area, double min_normal_dot, double sin_bound) {
  const Vec none = Vec::Constant(std::numeric_limits<double>::quiet_NaN());
  std::array<Vec, 3> x;
  int k = 0;
  for (auto u : mesh.fv_range(g)) x[static_cast<std::size_t>(k++)] = point(mesh, u);
  Vec normal_g = (x[1] - x[0]).cross(x[2] - x[0]);
  if (!(normal_g.norm() > 0.0)) return none;
  normal_g.normalize();
  const Vec p = point(mesh, v);
  Vec normal_v = Vec::Zero();
  double height_sum = 0.0;
  int n_ring = 0;
  for (auto h : mesh.voh_range(v)) {
    const Vec b = point(mesh, mesh.to_vertex_handle(h));
    height_sum += normal_g.dot(b - x[0]);
    ++n_ring;
    if (!mesh.is_boundary(h)) normal_v += (b - p).cross(point(mesh, mesh.to_vertex_handle(mesh.next_halfedge_handle(h))) - p);
  }
  if (n_ring == 0 || !(std::abs(height_sum) > 0.0) || !(normal_v.norm() > 0.0)) return none;
  const Vec up = height_sum > 0.0 ? normal_g : Vec(-normal_g);  // towards the ring's side
  const double ring_height = std::abs(height_sum) / n_ring;
  normal_v.normalize();
  constexpr double kMinCosine = 0.5;
  Vec direction = up.dot(normal_v) >= 0.0 ? normal_v : Vec(-normal_v);
  if (up.dot(direction) < kMinCosine) direction = up;
  const double height = up.dot(p - x[0]);
  const double rise = std::max(height, 0.0) + factor * ring_height - height;
  const double distance = rise / up.dot(direction);
  if (!(distance > 0.0) || !(distance <= max_offset)) return none;
  const Vec q = p + distance * direction;
  Shape before, after;
  for (auto h : mesh.voh_range(v)) {
    if (mesh.is_boundary(h)) continue;
    const Vec b = point(mesh, mesh.to_vertex_handle(h));
    const Vec c = point(mesh, mesh.to_vertex_handle(mesh.next_halfedge_handle(h)));
    const Vec n_old = (b - p).cross(c - p), n_new = (b - q).cross(c - q);
    const double l_old = n_old.norm(), l_new = n_new.norm();
    if (l_new <= min_double_area || (l_old > 0.0 && n_new.dot(n_old) <= min_normal_dot * l_old * l_new)) return none;
    before.add(p, b, c, sin_bound);
    after.add(q, b, c, sin_bound);
  }
  if (after.n_small > before.n_small || after.n_obtuse > before.n_obtuse) return none;
  return q;
}

std::vector<std::pair<double, int>> small_away_faces(const TriMesh& mesh, const std::vector<int>& vertex_node,
                                                     const std::vector<std::uint8_t>& is_feature, double sin_bound,
                                                     unsigned n_threads, std::size_t chunk) {
  const bool has_status = mesh.has_face_status();
  return select_in_order<std::pair<double, int>>(
      mesh.n_faces(), n_threads, chunk, [&](std::size_t i, std::pair<double, int>& out) {
        const TriMesh::FaceHandle f(static_cast<int>(i));
        if (has_status && mesh.status(f).deleted()) return false;
        // The corners as the face-vertex circulator gives them (the sine's rounding depends
        // on their order).
        std::array<Vec, 3> p;
        auto h = mesh.halfedge_handle(f);
        for (std::size_t k = 0; k < 3; ++k, h = mesh.next_halfedge_handle(h)) {
          const auto v = mesh.to_vertex_handle(h);
          if (is_feature[static_cast<std::size_t>(vertex_node[static_cast<std::size_t>(v.idx())])] != 0) return false;
          p[k] = point(mesh, v);
        }
        const double s = smallest_angle_sine(p[0], p[1], p[2]);
        if (!(s < sin_bound)) return false;
        out = {s, f.idx()};
        return true;
      });
}

bool make_angle_changes(StitchResult& result, std::span<const AngleChange> changes,
                        std::vector<TriMesh::VertexHandle>* touched) {
  TriMesh& mesh = result.mesh;
  if (touched != nullptr) touched->clear();
  // What to go back to when a change after the first is refused.
  std::optional<StitchResult> before;
  if (changes.size() > 1) {
    before.emplace();
    before->mesh = mesh;
    before->face_patch = result.face_patch;
    before->vertex_node = result.vertex_node;
  }
  auto undo = [&] {
    if (!before) return false;
    result.mesh = before->mesh;
    result.face_patch = std::move(before->face_patch);
    result.vertex_node = std::move(before->vertex_node);
    if (touched != nullptr) touched->clear();
    return false;
  };
  for (const AngleChange& change : changes) {
    if (change.kind == AngleChange::Kind::Move) {
      mesh.set_point(change.from, to_openmesh(change.q));
      if (touched != nullptr) touched->push_back(change.from);
      continue;
    }
    const auto h = mesh.find_halfedge(change.from, change.to);
    if (!h.is_valid()) return undo();
    if (change.kind == AngleChange::Kind::Flip) {
      const auto e = mesh.edge_handle(h);
      if (!mesh.is_flip_ok(e)) return undo();
      mesh.flip(e);
      if (touched != nullptr) {
        for (const auto g : {mesh.halfedge_handle(e, 0), mesh.halfedge_handle(e, 1)}) touched->push_back(mesh.to_vertex_handle(g));
      }
      continue;
    }
    if (!mesh.is_collapse_ok(h)) return undo();
    mesh.collapse(h);
    if (touched != nullptr) touched->push_back(change.to);
  }
  return true;
}

AngleRepairResult repair_small_angles(const SurfaceMesh& surface, const StitchOptions& options,
                                      const std::vector<std::uint8_t>& is_feature, StitchResult& result) {
  AngleRepairResult out;
  if (options.angle_repair_rounds <= 0 || result.mesh.n_faces() == 0) return out;
  std::vector<std::uint8_t> frozen(is_feature.size(), 0);
  const FinRimBound rim = fin_rim_bound(surface, options);
  const double diagonal = bounding_box(result.mesh).diagonal();
  const double min_double_area = 2.0 * tolerance::kDegenerateAreaRelative * diagonal * diagonal;
  const double sin_bound = std::sin(kAwayFromFeaturesAngleBoundDeg * std::numbers::pi / 180.0);
  const double max_offset =
      kMaxCollapseOffsetEdges * (surface.input_mean_edge > 0.0 ? surface.input_mean_edge : mean_edge_length(result.mesh));
  // The mesh to go back to when a change crosses another triangle (only when the checks run).
  std::optional<StitchResult> before;
  // The first sweep's triangles: every check round starts from the same mesh (the crossing
  // check puts it back as it was), so they are scanned once.
  std::vector<std::pair<double, int>> first_bad;
  for (int check = 0; check < kCheckRounds; ++check) {
    AngleRepair repair(surface, options, is_feature, frozen, result);
    if (check == 0) {
      first_bad = repair.small_faces();
      if (first_bad.empty() && !options.obtuse_collapse) return out;
    }
    if (!before && options.check_self_intersections) {
      before.emplace();
      before->mesh = result.mesh;
      before->face_patch = result.face_patch;
      before->vertex_node = result.vertex_node;
    }
    for (int round = 0; round < options.angle_repair_rounds; ++round) {
      if (repair.sweep(round == 0 ? first_bad : repair.small_faces()) == 0) break;
    }
    if (options.obtuse_collapse) (void)repair.obtuse_sweep();
    repair.collect_garbage();
    if (repair.n_flips_ + repair.n_collapses_ + repair.n_moves_ == 0) return out;
    std::vector<std::array<std::uint32_t, 2>> pairs;
    std::size_t n_pushes = 0;
    if (options.check_self_intersections) {
      std::vector<std::uint8_t> is_changed(is_feature.size(), 0);
      for (const int g : repair.changed_nodes_) is_changed[static_cast<std::size_t>(g)] = 1;
      std::vector<std::uint32_t> touched;
      for (auto f : result.mesh.faces()) {
        for (auto v : result.mesh.fv_range(f)) {
          if (is_changed[static_cast<std::size_t>(result.vertex_node[static_cast<std::size_t>(v.idx())])] != 0) {
            touched.push_back(static_cast<std::uint32_t>(f.idx()));
            break;
          }
        }
      }
      pairs = intersecting_pairs_of(mesh_soup(result.mesh), touched, options.n_threads);
      // A change that crosses another sheet (a thin plate, a fin's two sides): its nodes move
      // away from the sheet crossed (push_away) before the change is given up.
      std::vector<std::uint32_t> pushed_faces;
      // Where each pushed node was before its first push: every factor's push is measured
      // from there (the factors are 1, 2, 4 of the ring's height, not their sum), so a node
      // ends within max_offset of where the repair left it.
      std::vector<std::pair<TriMesh::VertexHandle, Vec>> origin;
      auto origin_of = [&origin](TriMesh::VertexHandle v) {
        const auto it = std::find_if(origin.begin(), origin.end(), [v](const auto& o) { return o.first == v; });
        return it == origin.end() ? nullptr : &it->second;
      };
      for (const double factor : kPushFactors) {
        if (pairs.empty()) break;
        std::vector<std::pair<TriMesh::VertexHandle, Vec>> pushes;
        auto in_pushes = [&pushes](TriMesh::VertexHandle u) {
          return std::any_of(pushes.begin(), pushes.end(), [u](const auto& push) { return push.first == u; });
        };
        for (const auto& pair : pairs) {
          for (int side = 0; side < 2; ++side) {
            const TriMesh::FaceHandle f(static_cast<int>(pair[static_cast<std::size_t>(side)]));
            const TriMesh::FaceHandle g(static_cast<int>(pair[static_cast<std::size_t>(1 - side)]));
            for (auto v : result.mesh.fv_range(f)) {
              const int g_node = result.vertex_node[static_cast<std::size_t>(v.idx())];
              if (is_changed[static_cast<std::size_t>(g_node)] == 0 || is_feature[static_cast<std::size_t>(g_node)] != 0 ||
                  result.mesh.is_boundary(v) || in_pushes(v)) {
                continue;
              }
              // No two neighbours in one round: push_away tests a node's ring with its
              // neighbours where they are.
              bool neighbour_pushed = false;
              for (auto u : result.mesh.vv_range(v)) neighbour_pushed = neighbour_pushed || in_pushes(u);
              if (neighbour_pushed) continue;
              // From the node's place before its first push.
              const Vec now = point(result.mesh, v);
              const Vec* from = origin_of(v);
              if (from != nullptr) result.mesh.set_point(v, to_openmesh(*from));
              // Within the fin rim bound (a clamped place would skip push_away's shape tests).
              const Vec q = push_away(result.mesh, v, g, factor, max_offset, min_double_area, options.min_normal_dot, sin_bound);
              if (from != nullptr) result.mesh.set_point(v, to_openmesh(now));
              if (q.allFinite() && rim.allows(g_node, q)) pushes.emplace_back(v, q);
            }
          }
        }
        if (pushes.empty()) break;
        for (const auto& [v, q] : pushes) {
          if (origin_of(v) == nullptr) origin.emplace_back(v, point(result.mesh, v));
          result.mesh.set_point(v, to_openmesh(q));
          for (auto f : result.mesh.vf_range(v)) pushed_faces.push_back(static_cast<std::uint32_t>(f.idx()));
        }
        n_pushes = origin.size();
        std::vector<std::uint32_t> faces = touched;
        faces.insert(faces.end(), pushed_faces.begin(), pushed_faces.end());
        pairs = intersecting_pairs_of(mesh_soup(result.mesh), faces, options.n_threads);
      }
    }
    if (pairs.empty()) {
      out.n_flips = repair.n_flips_;
      out.n_collapses = repair.n_collapses_ - repair.n_obtuse_collapses_;
      out.n_obtuse_collapses = repair.n_obtuse_collapses_;
      out.n_moves = repair.n_moves_;
      out.n_pushes = n_pushes;
      out.n_two_steps = repair.n_two_steps_;
      out.n_searches = repair.n_searches_;
      return out;
    }
    // The nodes of the crossing faces that a change made (changed_nodes_) are frozen and the
    // repair made again from the start; the faces' other nodes (the sheet crossed, the
    // triangle's unchanged corners) stay free: freezing them left the slivers of a thin place
    // unrepaired (headsq@500 with the fin rim bound: 33 -> 27 triangles below 25 deg away from
    // features, docs/stitch.md "Fin rims: every stage within the bound").
    std::size_t n_frozen = 0;
    std::vector<std::uint8_t> is_changed(is_feature.size(), 0);
    for (const int g : repair.changed_nodes_) is_changed[static_cast<std::size_t>(g)] = 1;
    for (const auto& pair : pairs) {
      for (const std::uint32_t f : pair) {
        for (auto v : result.mesh.fv_range(TriMesh::FaceHandle(static_cast<int>(f)))) {
          const auto g = static_cast<std::size_t>(result.vertex_node[static_cast<std::size_t>(v.idx())]);
          if (is_changed[g] == 0) continue;
          n_frozen += frozen[g] == 0 ? 1 : 0;
          frozen[g] = 1;
        }
      }
    }
    out.n_undone += repair.n_flips_ + repair.n_collapses_ + repair.n_moves_;
    result.mesh = before->mesh;
    result.face_patch = before->face_patch;
    result.vertex_node = before->vertex_node;
    if (n_frozen == 0) return out;
  }
  return out;
}

}  // namespace nurbsfront::stitch_detail
