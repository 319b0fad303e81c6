// SPDX-License-Identifier: BSD-3-Clause
// Fidelity moves (StitchOptions::fidelity_distance_edges; docs/stitch.md "Fidelity moves"):
// after the repairs, nodes move onto the input where the output is farther from it than the
// bound, when the triangles around them keep their shape and the local distance to the input
// does not grow (issue 6: the fits smooth folds narrower than their lattice).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <tuple>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/parallel.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/quality/internal.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/stitch/stitch_internal.h"

namespace nurbsfront::stitch_detail {

namespace {

using Vec = Eigen::Vector3d;

// Sweeps of candidates (each from distances measured afresh).
constexpr int kFidelityRounds = 4;
// Rounds of the crossing check that put back the moves on crossing triangles.
constexpr int kFidelityCheckRounds = 4;
// Barycentric samples of a triangle for its distance to the input: the corners, two points
// on each edge and the centroid (a lattice of step 1/3).
constexpr int kSampleSteps = 3;
// The new triangles of a split may turn from their old ones by up to 90 deg (a node on a fold's
// crest makes steep triangles: the smoothing's 60 deg refused most of the brain's).
constexpr double kSplitNormalDot = 0.0;
// A move is taken only if the candidate's own distance falls by this share at least.
constexpr double kMinGain = 0.05;
// Steps of the first sweep's walk from the last sample's face towards a sample.
constexpr int kWalkSteps = 8;
// Samples per chunk of the threaded queries (fixed: the walks start afresh at each chunk,
// whatever the thread count).
constexpr std::size_t kQueryChunk = 4096;

double alpha_of(const Vec& a, const Vec& b, const Vec& c) {
  const double l2 = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  return l2 > 0.0 ? 2.0 * std::numbers::sqrt3 * (b - a).cross(c - a).norm() / l2 : 0.0;
}

// The triangles around one vertex, their corners with the vertex at a given place.
struct Ring {
  std::vector<TriMesh::FaceHandle> faces;
  std::vector<std::array<Vec, 3>> corners;   // as in the mesh
  std::vector<std::array<int, 3>> is_centre; // 1 where the corner is the vertex
};

class FidelityMover {
 public:
  FidelityMover(const TriMesh& input, const StitchOptions& options, double bound, double cell, const FinRimBound& rim,
                bool incremental, StitchResult& result, std::vector<std::uint8_t>& is_feature,
                std::vector<std::uint8_t> fixed, const quality_detail::IndexedSoup* input_index,
                const FidelityGate* gate = nullptr)
      : options_(options), bound_(bound), cell_(cell), rim_(rim), incremental_(incremental), cheap_first_(incremental),
        mesh_(result.mesh), result_(result),
        is_feature_(is_feature), fixed_(std::move(fixed)) {
    // The input's soup and tree: the caller's when given (shared with the report's distance
    // pass), else built here.
    if (input_index == nullptr) input_index = &own_input_.emplace(to_soup(input), options.n_threads);
    input_index_ = input_index;
    const TriangleSoup& input_soup = input_index_->soup();
    // The input's samples: its vertices here; the first sweep adds the centroid and edge
    // midpoints of the faces it cannot show within the bound (select_probes()).
    // With a gate only the input faces it measures and their corners (vertex_probe_: each input
    // vertex's sample, UINT32_MAX for none), and only the output vertices of its patches'
    // triangles (the vertices splits make later are measured too).
    if (gate != nullptr && !gate->input_face.empty()) {
      scope_face_ = gate->input_face;
      vertex_probe_.assign(input_soup.points.size(), UINT32_MAX);
      for (std::size_t f = 0; f < scope_face_.size(); ++f) {
        if (scope_face_[f] == 0) continue;
        for (const std::uint32_t v : input_soup.triangles[f]) vertex_probe_[v] = 0;
      }
      for (std::uint32_t v = 0; v < vertex_probe_.size(); ++v) {
        if (vertex_probe_[v] == UINT32_MAX) continue;
        vertex_probe_[v] = static_cast<std::uint32_t>(probes_.size());
        probes_.push_back(input_soup.points[v]);
        probe_id_.push_back(v);
      }
      scope_output_.assign(mesh_.n_vertices(), 0);
      for (auto f : mesh_.faces()) {
        const int patch = result.face_patch[static_cast<std::size_t>(f.idx())];
        if (patch < 0 || static_cast<std::size_t>(patch) >= gate->patch.size() || gate->patch[static_cast<std::size_t>(patch)] == 0) continue;
        for (auto u : mesh_.fv_range(f)) scope_output_[static_cast<std::size_t>(u.idx())] = 1;
      }
    } else {
      probes_ = input_soup.points;
      probe_id_.resize(probes_.size());
      std::iota(probe_id_.begin(), probe_id_.end(), 0U);
    }
    const double diagonal = bounding_box(mesh_).diagonal();
    min_double_area_ = 2.0 * tolerance::kDegenerateAreaRelative * diagonal * diagonal;
    sin_floor_ = std::sin(options.angle_floor_deg * std::numbers::pi / 180.0);
  }

  // One sweep: returns the number of moves and splits. The first sweep (and every sweep
  // when not incremental) measures every vertex and input sample and tries every candidate;
  // later incremental sweeps measure again only the vertices changed in the last sweep and
  // the samples whose nearest output face changed or that a changed face may now be nearer
  // to, and try only the candidates whose checks read a changed place (a refused candidate
  // with nothing changed around it is refused again): the same moves as a full sweep.
  std::size_t sweep() {
    update_output();
    const TriangleSoup& out = out_;
    const bool full = !incremental_ || first_sweep_;
    const bool first = first_sweep_;
    if (first_sweep_) select_probes(out, *out_tree_);
    first_sweep_ = false;
    const std::size_t n_v = mesh_.n_vertices();
    // changed: vertices moved or made in the last sweep (all of them in a full sweep).
    std::vector<std::uint8_t> changed(n_v, full ? 1 : 0);
    for (const int v : changed_vertices_) changed[static_cast<std::size_t>(v)] = 1;
    changed_vertices_.clear();
    // Output nodes off the input: their closest input point (kept for unchanged vertices).
    vertex_distance_.resize(n_v, 0.0);
    vertex_target_.resize(n_v, Vec::Zero());
    // (On the run's threads, in Morton order of the points in a full sweep (each query starts
    // at the last one's face, near it): each closest face is exact whatever the hint, ties go
    // to the lowest face index.)
    const std::vector<std::uint32_t> vertex_order = full ? quality_detail::morton_order(out.points) : std::vector<std::uint32_t>{};
    parallel::for_chunks(n_v, options_.n_threads, kQueryChunk, [&](std::size_t begin, std::size_t end, unsigned) {
      std::uint32_t input_hint = UINT32_MAX;
      for (std::size_t k = begin; k < end; ++k) {
        const std::size_t i = full ? vertex_order[k] : k;
        if (changed[i] == 0 || fixed_[i] != 0 || !output_in_scope(i)) continue;
        const Vec p = point(mesh_, TriMesh::VertexHandle(static_cast<int>(i)));
        vertex_target_[i] = closest_input(p, input_hint);
        vertex_distance_[i] = (p - vertex_target_[i]).norm();
      }
    });
    // dirty: the corners of the faces that changed or whose listed samples did.
    std::vector<std::uint8_t> dirty(n_v, full ? 1 : 0);
    std::vector<std::uint8_t> face_changed(out.triangles.size(), full ? 1 : 0);
    if (!full) {
      for (std::size_t i = 0; i < n_v; ++i) {
        if (changed[i] == 0) continue;
        for (auto f : mesh_.vf_range(TriMesh::VertexHandle(static_cast<int>(i)))) face_changed[static_cast<std::size_t>(f.idx())] = 1;
      }
    }
    // Input samples: their nearest output face and distance (again where it may differ).
    // The first sweep measured every sample in select_probes(); a sweep that measures
    // everything again (not incremental) searches each in the tree.
    std::vector<std::uint8_t> requery(probes_.size(), full && !just_selected_ ? 1 : 0);
    just_selected_ = false;
    if (!full) mark_near_changed_faces(out, face_changed, requery);
    // The samples the first sweep left out whose vouching face changed and no longer holds
    // them within the bound: samples from now on, searched below.
    if (!first) recheck_left_out(out, face_changed);
    const std::size_t n_in = probes_.size();
    requery.resize(n_in, 1);
    near_face_.resize(n_in, UINT32_MAX);
    near_distance_.resize(n_in, 0.0);
    std::uint32_t hint = UINT32_MAX;
    for (const std::uint32_t i : probe_order_) {
      if (requery[i] == 0) continue;
      ++n_searched_;
      const auto c = closest_output(probes_[i], hint);
      hint = c.face;
      const double d = std::sqrt(c.squared_distance);
      if (!full && (c.face != near_face_[i] || d != near_distance_[i])) {
        for (const std::uint32_t f : {near_face_[i], c.face}) {
          if (f >= out.triangles.size()) continue;
          for (const auto k : out.triangles[f]) dirty[k] = 1;
        }
      }
      near_face_[i] = c.face;
      near_distance_[i] = d;
    }
    if (!full) {
      for (std::size_t f = 0; f < face_changed.size(); ++f) {
        if (face_changed[f] == 0) continue;
        for (const auto k : out.triangles[f]) dirty[k] = 1;
      }
    }
    // A vertex's move reads its ring (dirty within one ring), a sample's move or split the
    // faces around its face's corners and their neighbours (within two rings).
    const std::vector<std::uint8_t> dirty1 = full ? dirty : grow(dirty);
    const std::vector<std::uint8_t> dirty2 = full ? dirty : grow(dirty1);
    struct Candidate {
      double distance;
      int vertex;
      Vec target;
      Vec probe;  // the point whose distance the move must shrink (input or output side)
      bool input_side;
      std::uint32_t face = UINT32_MAX;  // input side: the nearest output face
      std::uint32_t sample = UINT32_MAX;  // input side: the sample
    };
    std::vector<Candidate> candidates;
    for (std::size_t i = 0; i < n_v; ++i) {
      if (fixed_[i] != 0 || dirty1[i] == 0 || !(vertex_distance_[i] > bound_)) continue;
      const Vec p = point(mesh_, TriMesh::VertexHandle(static_cast<int>(i)));
      candidates.push_back({vertex_distance_[i], static_cast<int>(i), vertex_target_[i], p, false, UINT32_MAX});
    }
    // Input samples far from the output: the nearest free corner of their nearest output face
    // onto them (else a split there).
    for (std::uint32_t i = 0; i < n_in; ++i) {
      if (near_distance_[i] <= bound_) continue;
      const auto& t = out.triangles[near_face_[i]];
      if (dirty2[t[0]] == 0 && dirty2[t[1]] == 0 && dirty2[t[2]] == 0) continue;
      const Vec& u = probes_[i];
      const Vec q = quality_detail::closest_point_on_triangle(u, out.points[t[0]], out.points[t[1]], out.points[t[2]]);
      int best = -1;  // none: only a split
      double best_d = 0.0;
      for (const auto k : t) {
        if (fixed_[k] != 0) continue;
        const double d = (out.points[k] - q).squaredNorm();
        if (best < 0 || d < best_d) best = static_cast<int>(k), best_d = d;
      }
      candidates.push_back({near_distance_[i], best, u, u, true, near_face_[i], i});
    }
    if (record_only_) {
      // Every sample and vertex farther than the bound (later sweeps try only those near
      // the last sweep's changes).
      for (std::uint32_t i = 0; i < n_in; ++i) {
        if (near_distance_[i] > bound_) recorded_samples_.push_back({probe_id_[i], near_distance_[i]});
      }
      for (std::size_t i = 0; i < n_v; ++i) {
        if (fixed_[i] == 0 && vertex_distance_[i] > bound_) recorded_vertices_.push_back({static_cast<std::uint32_t>(i), vertex_distance_[i]});
      }
      return 0;
    }
    // Input samples by nearest output face (the local checks).
    face_start_.assign(out.triangles.size() + 1, 0);
    for (const std::uint32_t f : near_face_) ++face_start_[f + 1];
    std::partial_sum(face_start_.begin(), face_start_.end(), face_start_.begin());
    face_inputs_.assign(n_in, 0);
    {
      std::vector<std::uint32_t> at(face_start_.begin(), face_start_.end() - 1);
      for (std::uint32_t i = 0; i < n_in; ++i) face_inputs_[at[near_face_[i]]++] = i;
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
      if (a.distance != b.distance) return a.distance > b.distance;
      if (a.vertex != b.vertex) return a.vertex < b.vertex;
      return a.input_side < b.input_side;
    });
    std::vector<std::uint8_t> touched(mesh_.n_vertices(), 0);
    std::size_t n_moves = 0;
    auto mark = [&](TriMesh::VertexHandle v) {
      touched.resize(mesh_.n_vertices(), 0);
      touched[static_cast<std::size_t>(v.idx())] = 1;
      for (auto u : mesh_.vv_range(v)) touched[static_cast<std::size_t>(u.idx())] = 1;
    };
    for (const Candidate& c : candidates) {
      if (c.vertex >= 0 && touched[static_cast<std::size_t>(c.vertex)] != 0) continue;
      if (c.vertex >= 0 && try_move(TriMesh::VertexHandle(c.vertex), c.target, c.probe, c.input_side, c.distance)) {
        ++n_moves;
        mark(TriMesh::VertexHandle(c.vertex));
        changed_vertices_.push_back(c.vertex);
        continue;
      }
      // An input sample the moves cannot reach: a new node on it, splitting an edge of its
      // nearest output face (the faces untouched in this sweep).
      if (!c.input_side || c.face >= out.triangles.size()) continue;
      const TriMesh::FaceHandle f(static_cast<int>(c.face));
      bool free = true;
      for (auto u : mesh_.fv_range(f)) free = free && touched[static_cast<std::size_t>(u.idx())] == 0;
      if (!free) continue;
      const TriMesh::VertexHandle made = try_split(f, c.target, c.distance);
      if (!made.is_valid()) continue;
      ++n_splits_;
      ++n_moves;
      mark(made);
      changed_vertices_.push_back(made.idx());
    }
    return n_moves;
  }

 private:
  const TriangleSoup& input_soup() const { return input_index_->soup(); }

  // The output as a soup and its tree, for this sweep: built in the first sweep; later the
  // soup takes the last sweep's changes (the points of the vertices moved or made, the faces
  // around them, the faces made) and the tree is refitted over the faces it was built on (their
  // boxes where they are now), the faces made by splits in a small tree of their own
  // (closest_output()). The answers are those of a tree built anew over the whole output.
  void update_output() {
    if (!out_tree_) {
      out_ = to_soup(mesh_);
      std::vector<std::uint32_t> all(out_.triangles.size());
      std::iota(all.begin(), all.end(), 0U);
      out_tree_.emplace(out_, std::move(all), options_.n_threads);
      n_tree_faces_ = out_.triangles.size();
      return;
    }
    out_.points.resize(mesh_.n_vertices());
    out_.triangles.resize(mesh_.n_faces());
    std::vector<std::uint32_t> changed_faces;
    for (const int i : changed_vertices_) {
      const TriMesh::VertexHandle v(i);
      out_.points[static_cast<std::size_t>(i)] = point(mesh_, v);
      for (auto f : mesh_.vf_range(v)) changed_faces.push_back(static_cast<std::uint32_t>(f.idx()));
    }
    for (std::size_t f = n_tree_faces_; f < mesh_.n_faces(); ++f) changed_faces.push_back(static_cast<std::uint32_t>(f));
    std::sort(changed_faces.begin(), changed_faces.end());
    changed_faces.erase(std::unique(changed_faces.begin(), changed_faces.end()), changed_faces.end());
    for (const std::uint32_t f : changed_faces) {
      auto& t = out_.triangles[f];
      int k = 0;
      for (auto u : mesh_.fv_range(TriMesh::FaceHandle(static_cast<int>(f)))) t[static_cast<std::size_t>(k++)] = static_cast<std::uint32_t>(u.idx());
    }
    out_tree_->refit(out_, changed_faces);
    extra_tree_.reset();
    if (out_.triangles.size() > n_tree_faces_) {
      std::vector<std::uint32_t> made(out_.triangles.size() - n_tree_faces_);
      std::iota(made.begin(), made.end(), static_cast<std::uint32_t>(n_tree_faces_));
      extra_tree_.emplace(out_, std::move(made), 1);
    }
  }

  // The output's closest face to p (ties: the lowest face index), as AabbTree::closest over
  // the whole output: the refitted tree's answer, or the faces made since it was built
  // (higher indices) where nearer.
  quality_detail::AabbTree::Closest closest_output(const Vec& p, std::uint32_t hint) const {
    auto best = out_tree_->closest(p, hint);
    if (extra_tree_) {
      const auto e = extra_tree_->closest(p, hint);
      if (e.squared_distance < best.squared_distance) best = e;
    }
    return best;
  }

  // The first sweep's input samples and their distances to the output. Every input vertex
  // is a sample (the walk first when incremental: a vertex whose walk from the last vertex's
  // face, Morton order, ends on a face within the bound keeps that face and distance, an
  // upper bound; else searched in the output's tree). An input face whose three corners are
  // within the bound of one output face T (one of the corners' faces) lies within the bound
  // of T wholly (the distance to a triangle is convex): its other samples (centroid, edge
  // midpoints) can be no candidates and are left out; so is any other face sample within the
  // bound of one of its face's corners' faces. The samples left are added and measured as
  // the vertices. On the run's threads, in chunks of kQueryChunk samples
  // whose walks start afresh: the same samples and distances for any thread count.
  void select_probes(const TriangleSoup& out, const quality_detail::AabbTree& out_tree) {
    const bool walk = cheap_first_;
    // The walks' steps: each output face's edge neighbours (UINT32_MAX across the boundary),
    // read once from the mesh (its circulators cost more than the steps' distances).
    if (walk) {
      face_neighbours_.assign(mesh_.n_faces(), {UINT32_MAX, UINT32_MAX, UINT32_MAX});
      parallel::for_each_index(mesh_.n_faces(), options_.n_threads, kQueryChunk, [&](std::size_t f) {
        std::size_t k = 0;
        for (auto h : mesh_.fh_range(TriMesh::FaceHandle(static_cast<int>(f)))) {
          const auto g = mesh_.face_handle(mesh_.opposite_halfedge_handle(h));
          if (g.is_valid()) face_neighbours_[f][k] = static_cast<std::uint32_t>(g.idx());
          ++k;
        }
      });
    }
    const double bound2 = bound_ * bound_;
    auto locate = [&](const std::vector<std::uint32_t>& order, std::size_t first) {
      near_face_.resize(probes_.size(), 0);
      near_distance_.resize(probes_.size(), 0.0);
      std::vector<std::uint8_t> walked(order.size(), 0);
      parallel::for_chunks(order.size(), options_.n_threads, kQueryChunk, [&](std::size_t begin, std::size_t end, unsigned) {
        std::uint32_t hint = UINT32_MAX;
        for (std::size_t k = begin; k < end; ++k) {
          const std::size_t i = first + order[k];
          if (walk && hint != UINT32_MAX) {
            const auto w = walk_to(out, probes_[i], hint);
            hint = w.face;
            if (w.squared_distance <= bound2) {
              near_face_[i] = w.face;
              near_distance_[i] = std::sqrt(w.squared_distance);
              walked[k] = 1;
              continue;
            }
          }
          const auto c = out_tree.closest(probes_[i], hint);
          hint = c.face;
          near_face_[i] = c.face;
          near_distance_[i] = std::sqrt(c.squared_distance);
        }
      });
      for (const std::uint8_t w : walked) (w != 0 ? n_walked_ : n_searched_) += 1;
    };
    const std::size_t n_vertices = probes_.size();  // the input vertices measured
    const std::size_t n_input_vertices = input_soup().points.size();
    locate(quality_detail::morton_order(probes_), 0);
    const std::size_t n_faces = input_soup().triangles.size();
    // An input vertex's sample (all of them without a gate).
    auto sample_of = [&](std::uint32_t v) { return vertex_probe_.empty() ? v : vertex_probe_[v]; };
    // Per input face the output face that holds it wholly within the bound (UINT32_MAX: none).
    std::vector<std::uint32_t> certified(n_faces, UINT32_MAX);
    auto to_face2 = [&](const Vec& u, std::uint32_t g) {
      const auto& t = out.triangles[g];
      return (quality_detail::closest_point_on_triangle(u, out.points[t[0]], out.points[t[1]], out.points[t[2]]) - u)
          .squaredNorm();
    };
    parallel::for_each_index(n_faces, options_.n_threads, kQueryChunk, [&](std::size_t f) {
      if (!input_face_in_scope(f)) return;
      const auto& tv = input_soup().triangles[f];
      const std::array<std::uint32_t, 3> t{sample_of(tv[0]), sample_of(tv[1]), sample_of(tv[2])};
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t g = near_face_[t[static_cast<std::size_t>(k)]];
        if (k > 0 && g == near_face_[t[0]]) continue;
        if (k > 1 && g == near_face_[t[1]]) continue;
        bool within = true;
        for (int j = 0; j < 3 && within; ++j) {
          const std::uint32_t v = t[static_cast<std::size_t>(j)];
          within = (j == k ? near_distance_[v] * near_distance_[v] : to_face2(probes_[v], g)) <= bound2;
        }
        if (within) {
          certified[f] = g;
          return;
        }
      }
    });
    // The other faces: a sample within the bound of one of its corners' faces is left out
    // (bit k of kept[f]: sample k is kept).
    // Per face sample its vouching output face (UINT32_MAX: kept as a sample).
    std::vector<std::array<std::uint32_t, 4>> vouch(n_faces);
    // (kOutOfScope: a face the gate does not measure: no sample, vouched for by none.)
    constexpr std::uint32_t kOutOfScope = UINT32_MAX - 1;
    parallel::for_each_index(n_faces, options_.n_threads, kQueryChunk, [&](std::size_t f) {
      if (!input_face_in_scope(f)) {
        vouch[f].fill(kOutOfScope);
        return;
      }
      if (certified[f] != UINT32_MAX) {
        vouch[f].fill(certified[f]);
        return;
      }
      const auto& t = input_soup().triangles[f];
      const auto u = face_samples(f);
      for (std::size_t k = 0; k < u.size(); ++k) {
        vouch[f][k] = UINT32_MAX;
        for (std::size_t j = 0; j < 3; ++j) {
          const std::uint32_t g = near_face_[sample_of(t[j])];
          if (to_face2(u[k], g) <= bound2) {
            vouch[f][k] = g;
            break;
          }
        }
      }
    });
    // The left-out samples by vouching face (face_samples() index 4 f + k): a later sweep
    // checks them again where that face changed (recheck_left_out()).
    vouched_start_.assign(out.triangles.size() + 1, 0);
    for (std::size_t f = 0; f < n_faces; ++f) {
      if (vouch[f][0] == kOutOfScope) continue;
      const auto u = face_samples(f);
      for (std::size_t k = 0; k < u.size(); ++k) {
        if (vouch[f][k] != UINT32_MAX) {
          ++n_certified_;
          ++vouched_start_[vouch[f][k] + 1];
          continue;
        }
        probe_id_.push_back(static_cast<std::uint32_t>(n_input_vertices + 4 * f + k));
        probes_.push_back(u[k]);
      }
    }
    std::partial_sum(vouched_start_.begin(), vouched_start_.end(), vouched_start_.begin());
    vouched_items_.assign(vouched_start_.back(), 0);
    {
      std::vector<std::uint32_t> at(vouched_start_.begin(), vouched_start_.end() - 1);
      for (std::size_t f = 0; f < n_faces; ++f) {
        for (std::size_t k = 0; k < 4; ++k) {
          if (vouch[f][k] != UINT32_MAX && vouch[f][k] != kOutOfScope) vouched_items_[at[vouch[f][k]]++] = static_cast<std::uint32_t>(4 * f + k);
        }
      }
    }
    std::vector<std::uint32_t> added(probes_.size() - n_vertices);
    std::iota(added.begin(), added.end(), 0U);
    locate(added, n_vertices);
    face_neighbours_ = {};
    build_probe_grid(cell_);
    just_selected_ = true;
  }

  // Whether the gate measures input face f, output vertex i (everything without a gate).
  bool input_face_in_scope(std::size_t f) const { return scope_face_.empty() || scope_face_[f] != 0; }
  bool output_in_scope(std::size_t i) const { return scope_output_.empty() || i >= scope_output_.size() || scope_output_[i] != 0; }

  // Input face f's samples besides its corners: its centroid and edge midpoints.
  std::array<Vec, 4> face_samples(std::size_t f) const {
    const auto& t = input_soup().triangles[f];
    const Vec &a = input_soup().points[t[0]], &b = input_soup().points[t[1]], &c = input_soup().points[t[2]];
    return {Vec((a + b + c) / 3.0), Vec(0.5 * (a + b)), Vec(0.5 * (b + c)), Vec(0.5 * (c + a))};
  }

  // The left-out samples vouched for by a changed output face: those it no longer holds
  // within the bound (its corners where they are now) become samples (appended; searched in
  // the output's tree by the caller; their grid cells in extra_cells_); the others stay vouched for by it (an unchanged face holds its
  // samples as before). Serial, in face and sample order: the same for any thread count.
  void recheck_left_out(const TriangleSoup& out, const std::vector<std::uint8_t>& face_changed) {
    const double bound2 = bound_ * bound_;
    const std::size_t n_vertices = input_soup().points.size();
    const std::size_t n_vouching = vouched_start_.empty() ? 0 : vouched_start_.size() - 1;
    for (std::size_t g = 0; g < n_vouching; ++g) {
      if (face_changed[g] == 0) continue;
      const auto& t = out.triangles[g];
      for (std::uint32_t k = vouched_start_[g]; k < vouched_start_[g + 1]; ++k) {
        std::uint32_t& item = vouched_items_[k];
        if (item == UINT32_MAX) continue;
        ++n_rechecked_;
        const Vec u = face_samples(item / 4)[item % 4];
        const double d2 =
            (quality_detail::closest_point_on_triangle(u, out.points[t[0]], out.points[t[1]], out.points[t[2]]) - u).squaredNorm();
        if (d2 <= bound2) continue;
        probe_order_.push_back(static_cast<std::uint32_t>(probes_.size()));
        extra_cells_.emplace_back(grid_key(cell_of(u)), static_cast<std::uint32_t>(probes_.size()));
        probe_id_.push_back(static_cast<std::uint32_t>(n_vertices + item));
        probes_.push_back(u);
        item = UINT32_MAX;
        ++n_promoted_;
      }
    }
    std::sort(extra_cells_.begin(), extra_cells_.end());
  }

  // From face f, steps to the edge neighbour nearer to u while there is one (at most
  // kWalkSteps): a face of the output and u's squared distance to it (an upper bound of
  // u's distance to the output; computed as AabbTree::closest does).
  quality_detail::AabbTree::Closest walk_to(const TriangleSoup& out, const Vec& u, std::uint32_t f) const {
    auto to_face = [&](std::uint32_t g) {
      const auto& t = out.triangles[g];
      return (quality_detail::closest_point_on_triangle(u, out.points[t[0]], out.points[t[1]], out.points[t[2]]) - u)
          .squaredNorm();
    };
    quality_detail::AabbTree::Closest best{to_face(f), f};
    for (int step = 0; step < kWalkSteps; ++step) {
      const std::uint32_t from = best.face;
      for (const std::uint32_t gi : face_neighbours_[from]) {
        if (gi == UINT32_MAX) continue;
        const double d = to_face(gi);
        if (d < best.squared_distance || (d == best.squared_distance && gi < best.face)) best = {d, gi};
      }
      if (best.face == from) break;
    }
    return best;
  }

  // The input samples in a uniform grid of cubic cells (kept for every sweep: the samples
  // do not move).
  void build_probe_grid(double cell) {
    probe_order_ = quality_detail::morton_order(probes_);
    n_gridded_ = probes_.size();
    if (probes_.empty()) return;
    grid_origin_ = probes_[0];
    Vec top_corner = probes_[0];
    for (const Vec& p : probes_) {
      grid_origin_ = grid_origin_.cwiseMin(p);
      top_corner = top_corner.cwiseMax(p);
    }
    grid_cell_ = cell > 0.0 ? cell : 1.0;
    // By cell key, then sample (a stable radix sort of the samples in order). Sorted by the
    // cells packed into as many bits as the grid's extent needs (3 radix passes where the
    // 21-bit fields of grid_key() took 5; the same order), unpacked into grid keys after.
    // The largest cell on each axis is the cell of the samples' largest coordinates
    // (cell_of() does not decrease along an axis).
    const auto top = cell_of(top_corner);
    std::array<int, 3> bits{};
    for (std::size_t k = 0; k < 3; ++k) bits[k] = static_cast<int>(std::bit_width(static_cast<std::uint64_t>(top[k])));
    std::vector<std::uint64_t> keys(probes_.size());
    grid_items_.resize(probes_.size());
    for (std::uint32_t i = 0; i < probes_.size(); ++i) {
      const auto c = cell_of(probes_[i]);
      keys[i] = (static_cast<std::uint64_t>(c[0]) << (bits[1] + bits[2])) | (static_cast<std::uint64_t>(c[1]) << bits[2]) |
                static_cast<std::uint64_t>(c[2]);
      grid_items_[i] = i;
    }
    quality_detail::radix_sort(keys, grid_items_);
    const std::uint64_t mask1 = (std::uint64_t{1} << bits[1]) - 1, mask2 = (std::uint64_t{1} << bits[2]) - 1;
    for (std::size_t k = 0; k < keys.size(); ++k) {
      if (k == 0 || keys[k] != keys[k - 1]) {
        const std::uint64_t key = keys[k];
        grid_keys_.push_back(grid_key({static_cast<std::int64_t>(key >> (bits[1] + bits[2])),
                                       static_cast<std::int64_t>((key >> bits[2]) & mask1), static_cast<std::int64_t>(key & mask2)}));
        grid_start_.push_back(static_cast<std::uint32_t>(k));
      }
    }
    grid_start_.push_back(static_cast<std::uint32_t>(keys.size()));
  }

  static constexpr std::int64_t kGridAxis = std::int64_t{1} << 21;
  std::array<std::int64_t, 3> cell_of(const Vec& p) const {
    std::array<std::int64_t, 3> c{};
    for (int k = 0; k < 3; ++k) {
      const double x = std::floor((p[k] - grid_origin_[k]) / grid_cell_);
      c[static_cast<std::size_t>(k)] = static_cast<std::int64_t>(std::clamp(x, 0.0, double(kGridAxis - 1)));
    }
    return c;
  }
  static std::uint64_t grid_key(const std::array<std::int64_t, 3>& c) {
    return (static_cast<std::uint64_t>(c[0]) << 42) | (static_cast<std::uint64_t>(c[1]) << 21) | static_cast<std::uint64_t>(c[2]);
  }

  // Marks for a new query the samples whose nearest face changed and those a changed face
  // (face_changed, its corners where they are now) may be as near to as their nearest one.
  void mark_near_changed_faces(const TriangleSoup& out, const std::vector<std::uint8_t>& face_changed,
                               std::vector<std::uint8_t>& requery) const {
    // Per sample its own radius: the grid is scanned within one cell of a changed face's
    // box for the samples nearer than that to the output; the farther ones (few) are tested
    // against every changed face (one far sample would make every face scan a large box).
    const double reach = grid_cell_;
    std::vector<std::uint32_t> far;
    for (std::uint32_t i = 0; i < probes_.size(); ++i) {
      if (face_changed[near_face_[i]] != 0) requery[i] = 1;
      if (near_distance_[i] > reach) far.push_back(i);
    }
    for (std::size_t f = 0; f < face_changed.size(); ++f) {
      if (face_changed[f] == 0) continue;
      const auto& t = out.triangles[f];
      const Vec lo = out.points[t[0]].cwiseMin(out.points[t[1]]).cwiseMin(out.points[t[2]]);
      const Vec hi = out.points[t[0]].cwiseMax(out.points[t[1]]).cwiseMax(out.points[t[2]]);
      auto test = [&](std::uint32_t i) {
        const Vec& u = probes_[i];
        const double s = (u - u.cwiseMax(lo).cwiseMin(hi)).squaredNorm();
        if (s <= near_distance_[i] * near_distance_[i]) requery[i] = 1;
      };
      for (const std::uint32_t i : far) test(i);
      const auto a = cell_of(lo - Vec::Constant(reach)), b = cell_of(hi + Vec::Constant(reach));
      const std::int64_t n_cells = (b[0] - a[0] + 1) * (b[1] - a[1] + 1) * (b[2] - a[2] + 1);
      if (n_cells > static_cast<std::int64_t>(grid_keys_.size())) {
        for (std::uint32_t i = 0; i < probes_.size(); ++i) test(i);
        continue;
      }
      for (std::int64_t x = a[0]; x <= b[0]; ++x) {
        for (std::int64_t y = a[1]; y <= b[1]; ++y) {
          for (std::int64_t z = a[2]; z <= b[2]; ++z) {
            const std::uint64_t key = grid_key({x, y, z});
            const auto extra = std::equal_range(extra_cells_.begin(), extra_cells_.end(), std::pair{key, std::uint32_t{0}},
                                                [](const auto& l, const auto& r) { return l.first < r.first; });
            for (auto e = extra.first; e != extra.second; ++e) test(e->second);
            const auto it = std::lower_bound(grid_keys_.begin(), grid_keys_.end(), key);
            if (it == grid_keys_.end() || *it != key) continue;
            const auto k = static_cast<std::size_t>(it - grid_keys_.begin());
            for (std::uint32_t j = grid_start_[k]; j < grid_start_[k + 1]; ++j) test(grid_items_[j]);
          }
        }
      }
    }
  }

  // The flags and those of every neighbour of a flagged vertex.
  std::vector<std::uint8_t> grow(const std::vector<std::uint8_t>& flags) const {
    std::vector<std::uint8_t> out = flags;
    for (auto v : mesh_.vertices()) {
      if (flags[static_cast<std::size_t>(v.idx())] == 0) continue;
      for (auto u : mesh_.vv_range(v)) out[static_cast<std::size_t>(u.idx())] = 1;
    }
    return out;
  }

  // p's closest input point; hint as for input_distance().
  Vec closest_input(const Vec& p, std::uint32_t& hint) const {
    const auto c = input_index_->tree().closest(p, hint);
    hint = c.face;
    const auto& t = input_soup().triangles[c.face];
    return quality_detail::closest_point_on_triangle(p, input_soup().points[t[0]], input_soup().points[t[1]],
                                                     input_soup().points[t[2]]);
  }

  // Distance of p to the input; hint: an input face near p (UINT32_MAX: none), set to p's
  // nearest face (coherent queries start there: the same answer, sooner).
  double input_distance(const Vec& p, std::uint32_t& hint) const {
    const auto c = input_index_->tree().closest(p, hint);
    hint = c.face;
    return std::sqrt(c.squared_distance);
  }
  double input_distance(const Vec& p) const {
    std::uint32_t hint = UINT32_MAX;
    return input_distance(p, hint);
  }

  // The ring's largest sample distance to the input with the vertex moved to q, as it is
  // compared with cap: stops at the first sample farther than cap (a value above cap then).
  // Leaves out the samples that do not depend on the vertex (its weight exactly 0: the same
  // points, bit for bit, as at the old place) and the vertex's own place after its first
  // face. cap must be at least the ring's largest distance at the old place: the left-out
  // samples are within it, so the answer is above cap exactly when the full one is, and
  // max(answer, x) > cap exactly when max(full, x) > cap.
  double moved_ring_to_input(const Ring& ring, const Vec& q, double cap) const {
    double worst = 0.0;
    std::uint32_t hint = UINT32_MAX;
    bool centre_done = false;
    for (std::size_t k = 0; k < ring.faces.size(); ++k) {
      const auto p = corners_at(ring, k, q);
      for (int i = 0; i <= kSampleSteps; ++i) {
        for (int j = 0; i + j <= kSampleSteps; ++j) {
          const double s = double(i) / kSampleSteps, t = double(j) / kSampleSteps;
          const std::array<double, 3> w{1.0 - s - t, s, t};
          double wc = 0.0;
          for (std::size_t c = 0; c < 3; ++c) {
            if (ring.is_centre[k][c] != 0) wc = w[c];
          }
          if (wc == 0.0) continue;
          if (wc == 1.0) {
            if (centre_done) continue;
            centre_done = true;
          }
          worst = std::max(worst, input_distance(w[0] * p[0] + w[1] * p[1] + w[2] * p[2], hint));
          if (worst > cap) return worst;
        }
      }
    }
    return worst;
  }

  // The largest distance to the input of face f's samples (triangle_to_input() of its corners
  // in the mesh's order, given), kept until a move or split changes the face (forget_faces()).
  double face_to_input(TriMesh::FaceHandle f, const std::array<Vec, 3>& corners) {
    const auto i = static_cast<std::size_t>(f.idx());
    if (i >= face_worst_.size()) face_worst_.resize(mesh_.n_faces(), -1.0);
    if (face_worst_[i] < 0.0) face_worst_[i] = triangle_to_input(corners);
    return face_worst_[i];
  }
  // The faces around v changed (a move of v, or v made by a split and its flips).
  void forget_faces(TriMesh::VertexHandle v) {
    face_worst_.resize(mesh_.n_faces(), -1.0);
    for (auto f : mesh_.vf_range(v)) face_worst_[static_cast<std::size_t>(f.idx())] = -1.0;
  }

  // Distance of u to the ring's triangles with the vertex at q.
  static double to_ring(const Ring& ring, const Vec& q, const Vec& u) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < ring.faces.size(); ++k) {
      const auto p = corners_at(ring, k, q);
      best = std::min(best, (u - quality_detail::closest_point_on_triangle(u, p[0], p[1], p[2])).norm());
    }
    return best;
  }

  static std::array<Vec, 3> corners_at(const Ring& ring, std::size_t k, const Vec& q) {
    std::array<Vec, 3> p = ring.corners[k];
    for (int i = 0; i < 3; ++i) {
      if (ring.is_centre[k][static_cast<std::size_t>(i)] != 0) p[static_cast<std::size_t>(i)] = q;
    }
    return p;
  }

  // The shape tests of a move of the ring's vertex from p to q: no triangle degenerates or
  // turns its normal by more than acos(min_normal_dot); the smallest alpha stays at least
  // min(old, alpha_floor), each triangle's smallest angle at least min(its old one,
  // angle_floor_deg), and no more triangles are obtuse.
  bool keeps_shape(const Ring& ring, const Vec& p, const Vec& q) const {
    double old_alpha = 1.0, new_alpha = 1.0, old_sine = 1.0, new_sine = 1.0;
    int old_obtuse = 0, new_obtuse = 0;
    for (std::size_t k = 0; k < ring.faces.size(); ++k) {
      const auto a = corners_at(ring, k, p), b = corners_at(ring, k, q);
      const Vec na = (a[1] - a[0]).cross(a[2] - a[0]), nb = (b[1] - b[0]).cross(b[2] - b[0]);
      const double lb = nb.norm();
      if (lb <= min_double_area_) return false;
      if (nb.dot(na) <= options_.min_normal_dot * lb * na.norm()) return false;
      const double alpha_a = alpha_of(a[0], a[1], a[2]), alpha_b = alpha_of(b[0], b[1], b[2]);
      // Each triangle keeps min(its own alpha, fidelity_alpha_floor): the moves' quality cost.
      if (alpha_b < std::min(alpha_a, options_.fidelity_alpha_floor)) return false;
      old_alpha = std::min(old_alpha, alpha_a);
      new_alpha = std::min(new_alpha, alpha_b);
      const double sine_a = smallest_angle_sine(a[0], a[1], a[2]), sine_b = smallest_angle_sine(b[0], b[1], b[2]);
      // Each triangle keeps min(its own smallest angle, the floor): none falls below issue
      // 5's bound that was not there.
      if (sine_b < std::min(sine_a, sin_floor_)) return false;
      old_sine = std::min(old_sine, sine_a);
      new_sine = std::min(new_sine, sine_b);
      old_obtuse += int(triangle_is_obtuse(a[0], a[1], a[2]));
      new_obtuse += int(triangle_is_obtuse(b[0], b[1], b[2]));
    }
    return new_alpha >= std::min(old_alpha, options_.alpha_floor) && new_sine >= std::min(old_sine, sin_floor_) &&
           new_obtuse <= old_obtuse;
  }

  // Moves v towards target (all the way, else half way) when the move keeps the shape,
  // shrinks the distance of the probe (the vertex itself, or an input vertex to the ring)
  // by kMinGain at least and the ring's largest distance to the input (its samples, and the
  // input vertices whose nearest output face is in the ring) does not grow.
  bool try_move(TriMesh::VertexHandle v, const Vec& target, const Vec& probe, bool input_side, double distance) {
    Ring ring;
    for (auto f : mesh_.vf_range(v)) {
      ring.faces.push_back(f);
      std::array<Vec, 3> p;
      std::array<int, 3> centre{0, 0, 0};
      int i = 0;
      for (auto u : mesh_.fv_range(f)) {
        p[static_cast<std::size_t>(i)] = point(mesh_, u);
        centre[static_cast<std::size_t>(i)] = u == v ? 1 : 0;
        ++i;
      }
      ring.corners.push_back(p);
      ring.is_centre.push_back(centre);
    }
    if (ring.faces.empty()) return false;
    const Vec p = point(mesh_, v);
    // A fin rim node stays within its bound (StitchOptions::fin_rim_max_move): the target
    // is cut there (the half-way point then lies within it too).
    const int node = result_.vertex_node[static_cast<std::size_t>(v.idx())];
    const Vec goal = rim_.clamp(node, target);
    // The input vertices listed under the ring's faces.
    std::vector<std::uint32_t> near;
    double old_in = 0.0;
    for (const auto f : ring.faces) {
      const auto fi = static_cast<std::size_t>(f.idx());
      if (fi + 1 >= face_start_.size()) continue;
      for (std::uint32_t k = face_start_[fi]; k < face_start_[fi + 1]; ++k) {
        near.push_back(face_inputs_[k]);
        old_in = std::max(old_in, near_distance_[face_inputs_[k]]);
      }
    }
    // The ring's old largest distance: measured when a place passes the cheaper tests first
    // (most candidates fail them; the same answer either way).
    std::optional<double> old_worst;
    for (const double t : {1.0, 0.5}) {
      const Vec q = p + t * (goal - p);
      if (!rim_.allows(node, q) || !keeps_shape(ring, p, q)) continue;
      const double gain_distance = input_side ? to_ring(ring, q, probe) : input_distance(q);
      if (gain_distance > (1.0 - kMinGain) * distance) continue;
      if (!old_worst) {
        double worst = old_in;
        for (std::size_t k = 0; k < ring.faces.size(); ++k) worst = std::max(worst, face_to_input(ring.faces[k], ring.corners[k]));
        old_worst = worst;
      }
      double new_worst = moved_ring_to_input(ring, q, *old_worst);
      for (const std::uint32_t i : near) new_worst = std::max(new_worst, to_ring(ring, q, probes_[i]));
      if (new_worst > *old_worst) continue;
      mesh_.set_point(v, to_openmesh(q));
      forget_faces(v);
      return true;
    }
    return false;
  }

  // A split of f's edge h = (a, b) with the new node at u: the new triangles (u, c, a),
  // (u, b, c), (u, d, b), (u, a, d) ((b, a, d) the face across); with `with_flips`, a new
  // triangle obtuse at u whose far edge (s0, s1) may flip (not on the boundary nor a crease
  // segment, its far corner x across it not one of a, b, c, d nor taken twice) is replaced
  // by (u, s0, x) and (u, x, s1). Passes when no new triangle degenerates or turns its
  // normal from its old one's by 90 deg or more, their smallest alpha stays at least
  // min(old, alpha_floor), their smallest angle at least min(old, angle_floor_deg), no more
  // of them are obtuse, and their largest distance to the input (samples, and the input's
  // samples listed under the old faces) is below the old one and below the candidate's
  // distance by kMinGain. Returns the sine of the smallest new angle (-1: fails) and the
  // edges to flip after the split.
  double evaluate_split(TriMesh::HalfedgeHandle h, const Vec& u, double distance, bool with_flips,
                        std::vector<std::array<TriMesh::VertexHandle, 2>>& flips) const {
    flips.clear();
    const auto o = mesh_.opposite_halfedge_handle(h);
    const auto va = mesh_.from_vertex_handle(h), vb = mesh_.to_vertex_handle(h);
    const auto vc = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h));
    const auto vd = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(o));
    struct Tri {
      std::array<Vec, 3> p;
      Vec parent;  // the old triangle's area vector
      double parent_alpha;
      TriMesh::VertexHandle v1, v2;  // the corners besides the new node
    };
    std::vector<Tri> made;
    std::vector<std::array<Vec, 3>> old;
    std::vector<TriMesh::FaceHandle> old_faces{mesh_.face_handle(h), mesh_.face_handle(o)};
    auto corners = [&](TriMesh::VertexHandle x, TriMesh::VertexHandle y, TriMesh::VertexHandle z) {
      return std::array<Vec, 3>{point(mesh_, x), point(mesh_, y), point(mesh_, z)};
    };
    auto area = [](const std::array<Vec, 3>& t) { return Vec((t[1] - t[0]).cross(t[2] - t[0])); };
    old.push_back(corners(va, vb, vc));
    old.push_back(corners(vb, va, vd));
    const std::array<std::array<TriMesh::VertexHandle, 2>, 4> sides{{{vc, va}, {vb, vc}, {vd, vb}, {va, vd}}};
    std::vector<TriMesh::VertexHandle> far{va, vb, vc, vd};
    for (std::size_t k = 0; k < sides.size(); ++k) {
      const auto [s0, s1] = sides[k];
      const Vec p0 = point(mesh_, s0), p1 = point(mesh_, s1);
      const Vec parent = area(old[k / 2]);
      if (with_flips && (p0 - u).dot(p1 - u) < 0.0) {
        const auto g = mesh_.find_halfedge(s1, s0);
        const auto e = mesh_.edge_handle(g);
        const auto vx = mesh_.is_boundary(g) ? TriMesh::VertexHandle() : mesh_.to_vertex_handle(mesh_.next_halfedge_handle(g));
        if (vx.is_valid() && !mesh_.is_boundary(e) && !is_crease(g) && std::find(far.begin(), far.end(), vx) == far.end()) {
          far.push_back(vx);
          const auto across = corners(s1, s0, vx);
          old.push_back(across);
          old_faces.push_back(mesh_.face_handle(g));
          const Vec n_across = area(across);
          const double alpha_across = std::min(alpha_of(across[0], across[1], across[2]),
                                               alpha_of(old[k / 2][0], old[k / 2][1], old[k / 2][2]));
          made.push_back({{u, p0, across[2]}, n_across, alpha_across, s0, vx});
          made.push_back({{u, across[2], p1}, n_across, alpha_across, vx, s1});
          flips.push_back({s0, s1});
          continue;
        }
      }
      made.push_back({{u, p0, p1}, parent, alpha_of(old[k / 2][0], old[k / 2][1], old[k / 2][2]), s0, s1});
    }
    double old_alpha = 1.0, old_sine = 1.0, old_sine_free = 1.0, new_alpha = 1.0, new_sine = 1.0;
    int old_obtuse = 0, new_obtuse = 0;
    for (std::size_t k = 0; k < old.size(); ++k) {
      const auto& t = old[k];
      old_alpha = std::min(old_alpha, alpha_of(t[0], t[1], t[2]));
      const double sine = smallest_angle_sine(t[0], t[1], t[2]);
      old_sine = std::min(old_sine, sine);
      if (free_face(old_faces[k])) old_sine_free = std::min(old_sine_free, sine);
      old_obtuse += int(triangle_is_obtuse(t[0], t[1], t[2]));
    }
    for (const auto& t : made) {
      const Vec n = area(t.p);
      const double l = n.norm();
      if (!(l > min_double_area_ && n.dot(t.parent) > kSplitNormalDot * l * t.parent.norm())) return -1.0;
      const double alpha = alpha_of(t.p[0], t.p[1], t.p[2]);
      // Each new triangle keeps min(its old triangle's alpha, fidelity_alpha_floor) (across a
      // flipped edge: the smaller of the two old ones').
      if (alpha < std::min(t.parent_alpha, options_.fidelity_alpha_floor)) return -1.0;
      new_alpha = std::min(new_alpha, alpha);
      const double sine = smallest_angle_sine(t.p[0], t.p[1], t.p[2]);
      new_sine = std::min(new_sine, sine);
      // A new triangle of free vertices only (the new node is free) keeps min(the old free
      // triangles' smallest angle, the floor): issue 5's bound away from features.
      if (free_vertex(t.v1) && free_vertex(t.v2) && sine < std::min(old_sine_free, sin_floor_)) return -1.0;
      new_obtuse += int(triangle_is_obtuse(t.p[0], t.p[1], t.p[2]));
    }
    if (new_alpha < std::min(old_alpha, options_.alpha_floor) || new_sine < std::min(old_sine, sin_floor_) ||
        new_obtuse > old_obtuse)
      return -1.0;
    double old_worst = 0.0, new_worst = 0.0;
    for (const auto& t : old) old_worst = std::max(old_worst, triangle_to_input(t));
    for (const auto& t : made) new_worst = std::max(new_worst, triangle_to_input(t.p));
    for (const auto g : old_faces) {
      const auto fi = static_cast<std::size_t>(g.idx());
      if (fi + 1 >= face_start_.size()) continue;
      for (std::uint32_t k = face_start_[fi]; k < face_start_[fi + 1]; ++k) {
        const std::uint32_t i = face_inputs_[k];
        old_worst = std::max(old_worst, near_distance_[i]);
        double to_new = std::numeric_limits<double>::infinity();
        for (const auto& t : made) {
          to_new = std::min(to_new, (probes_[i] - quality_detail::closest_point_on_triangle(probes_[i], t.p[0], t.p[1], t.p[2])).norm());
        }
        new_worst = std::max(new_worst, to_new);
      }
    }
    if (new_worst >= old_worst || new_worst > (1.0 - kMinGain) * distance) return -1.0;
    return new_sine;
  }

  bool free_vertex(TriMesh::VertexHandle v) const { return fixed_[static_cast<std::size_t>(v.idx())] == 0; }
  bool free_face(TriMesh::FaceHandle f) const {
    for (auto v : mesh_.fv_range(f)) {
      if (!free_vertex(v)) return false;
    }
    return true;
  }

  // An edge between two patches whose ends are both fixed: a crease segment (or a chord
  // of one), never split nor flipped.
  bool is_crease(TriMesh::HalfedgeHandle g) const {
    const auto o = mesh_.opposite_halfedge_handle(g);
    if (mesh_.is_boundary(g) || mesh_.is_boundary(o)) return true;
    return fixed_[static_cast<std::size_t>(mesh_.from_vertex_handle(g).idx())] != 0 &&
           fixed_[static_cast<std::size_t>(mesh_.to_vertex_handle(g).idx())] != 0 &&
           result_.face_patch[static_cast<std::size_t>(mesh_.face_handle(g).idx())] !=
               result_.face_patch[static_cast<std::size_t>(mesh_.face_handle(o).idx())];
  }

  // A new node at u on an edge of f: the split (evaluate_split, without and with flips)
  // whose smallest new angle is largest. Not an edge on the boundary nor a crease segment.
  // Returns the new vertex (invalid: none).
  TriMesh::VertexHandle try_split(TriMesh::FaceHandle f, const Vec& u, double distance) {
    TriMesh::HalfedgeHandle best;
    double best_sine = -1.0;
    std::vector<std::array<TriMesh::VertexHandle, 2>> flips, best_flips;
    for (auto h : mesh_.fh_range(f)) {
      if (is_crease(h)) continue;
      for (const bool with_flips : {false, true}) {
        const double sine = evaluate_split(h, u, distance, with_flips, flips);
        if (sine > best_sine) {
          best = h;
          best_sine = sine;
          best_flips = flips;
        }
      }
    }
    if (!best.is_valid()) return TriMesh::VertexHandle();
    const auto o = mesh_.opposite_halfedge_handle(best);
    const int patch_c = result_.face_patch[static_cast<std::size_t>(f.idx())];
    const int patch_d = result_.face_patch[static_cast<std::size_t>(mesh_.face_handle(o).idx())];
    const auto vc = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(best));
    const auto v = mesh_.add_vertex(to_openmesh(u));
    mesh_.split_edge(mesh_.edge_handle(best), v);
    result_.face_patch.resize(mesh_.n_faces(), -1);
    for (auto g : mesh_.vf_range(v)) {
      int& patch = result_.face_patch[static_cast<std::size_t>(g.idx())];
      if (patch >= 0) continue;
      bool has_c = false;
      for (auto w : mesh_.fv_range(g)) has_c = has_c || w == vc;
      patch = has_c ? patch_c : patch_d;
    }
    result_.vertex_node.push_back(static_cast<int>(is_feature_.size()));
    is_feature_.push_back(0);
    fixed_.push_back(0);
    for (const auto& [s0, s1] : best_flips) {
      const auto e = mesh_.edge_handle(mesh_.find_halfedge(s0, s1));
      if (mesh_.is_flip_ok(e)) mesh_.flip(e);
    }
    forget_faces(v);
    return v;
  }

  double triangle_to_input(const std::array<Vec, 3>& p) const {
    double worst = 0.0;
    std::uint32_t hint = UINT32_MAX;
    for (int i = 0; i <= kSampleSteps; ++i) {
      for (int j = 0; i + j <= kSampleSteps; ++j) {
        const double s = double(i) / kSampleSteps, t = double(j) / kSampleSteps;
        worst = std::max(worst, input_distance((1.0 - s - t) * p[0] + s * p[1] + t * p[2], hint));
      }
    }
    return worst;
  }

 public:
  std::size_t n_splits_ = 0;
  // Input samples measured by the first sweep's walk alone, and searched in the tree.
  std::size_t n_walked_ = 0, n_searched_ = 0;
  // Face samples the first sweep left out (their face is within the bound of one output face).
  std::size_t n_certified_ = 0;
  // Left-out samples checked again (their vouching face changed), and of them those made
  // samples (no longer within the bound of it).
  std::size_t n_rechecked_ = 0, n_promoted_ = 0;
  // The sample numbers (probe_id_) of the samples recheck_left_out() made, sorted.
  std::vector<std::uint32_t> promoted_ids() const {
    std::vector<std::uint32_t> ids(probe_id_.begin() + static_cast<std::ptrdiff_t>(n_gridded_), probe_id_.end());
    std::sort(ids.begin(), ids.end());
    return ids;
  }
  // The output faces whose sample distance to the input is kept (face_to_input()), and of
  // them those whose kept distance is not the one triangle_to_input() gives for the face
  // where it is now (tests: none).
  std::pair<std::size_t, std::size_t> check_kept_face_distances() const {
    std::size_t n_kept = 0, n_stale = 0;
    for (std::size_t f = 0; f < face_worst_.size() && f < mesh_.n_faces(); ++f) {
      if (face_worst_[f] < 0.0) continue;
      ++n_kept;
      std::array<Vec, 3> p;
      std::size_t i = 0;
      for (auto u : mesh_.fv_range(TriMesh::FaceHandle(static_cast<int>(f)))) p[i++] = point(mesh_, u);
      if (triangle_to_input(p) != face_worst_[f]) ++n_stale;
    }
    return {n_kept, n_stale};
  }
  // When set, a sweep only records its candidates (fidelity_candidates()).
  bool record_only_ = false;
  std::vector<std::pair<std::uint32_t, double>> recorded_samples_, recorded_vertices_;

 private:
  const StitchOptions& options_;
  double bound_;
  double cell_;
  const FinRimBound& rim_;
  bool incremental_;
  bool cheap_first_;
  bool first_sweep_ = true;
  bool just_selected_ = false;
  // Vertices moved or made in this sweep (measured again in the next one).
  std::vector<int> changed_vertices_;
  // Per vertex: its distance to the input and its closest input point (free vertices).
  std::vector<double> vertex_distance_;
  std::vector<Vec> vertex_target_;
  // The input samples in Morton order, and in a grid: cell keys (sorted), the start of each
  // cell's samples in grid_items_ (one more at the end).
  std::vector<std::uint32_t> probe_order_;
  // The samples in the grid (the first ones; those made later by recheck_left_out() are in
  // extra_cells_: (cell key, sample), sorted).
  std::size_t n_gridded_ = 0;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> extra_cells_;
  // The first sweep's left-out face samples (4 f + k, UINT32_MAX once made a sample) by the
  // output face that vouched for them (its start in vouched_items_; one more at the end).
  std::vector<std::uint32_t> vouched_start_, vouched_items_;
  Vec grid_origin_ = Vec::Zero();
  double grid_cell_ = 1.0;
  std::vector<std::uint64_t> grid_keys_;
  std::vector<std::uint32_t> grid_start_, grid_items_;
  // Per output face its edge neighbours (the first sweep's walks).
  std::vector<std::array<std::uint32_t, 3>> face_neighbours_;
  // The output's soup and trees (update_output()).
  TriangleSoup out_;
  std::optional<quality_detail::AabbTree> out_tree_, extra_tree_;
  std::size_t n_tree_faces_ = 0;
  TriMesh& mesh_;
  StitchResult& result_;
  std::vector<std::uint8_t>& is_feature_;
  std::vector<std::uint8_t> fixed_;
  std::optional<quality_detail::IndexedSoup> own_input_;
  const quality_detail::IndexedSoup* input_index_ = nullptr;
  std::vector<Vec> probes_;
  // Per sample its index among all the input's samples (its vertices, then per face its
  // centroid and edge midpoints): FidelityCandidates::samples.
  std::vector<std::uint32_t> probe_id_;
  double min_double_area_ = 0.0;
  double sin_floor_ = 0.0;
  std::vector<std::uint32_t> near_face_;
  std::vector<double> near_distance_;
  // The gate's scope (empty: everything): input faces and output vertices measured, each input
  // vertex's sample (UINT32_MAX: not measured).
  std::vector<std::uint8_t> scope_face_, scope_output_;
  std::vector<std::uint32_t> vertex_probe_;
  std::vector<std::uint32_t> face_start_, face_inputs_;
  // Per output face its largest sample distance to the input (face_to_input(); -1: not known).
  std::vector<double> face_worst_;
};

}  // namespace

FidelityCandidates fidelity_candidates(const TriMesh& input, const StitchOptions& options,
                                       std::vector<std::uint8_t> is_feature, double reference_edge, StitchResult result,
                                       bool walk, int sweeps_before) {
  FidelityCandidates out;
  const double bound = options.fidelity_distance_edges * reference_edge;
  if (!(bound > 0.0) || input.n_faces() == 0 || result.mesh.n_faces() == 0) return out;
  const FinRimBound rim;
  FidelityMover mover(input, options, bound, reference_edge, rim, walk, result, is_feature,
                      fixed_vertices(result.mesh, result.vertex_node, is_feature), nullptr);
  for (int k = 0; k < sweeps_before; ++k) out.n_changed_before += mover.sweep();
  std::tie(out.n_kept_face_distances, out.n_stale_face_distances) = mover.check_kept_face_distances();
  mover.record_only_ = true;
  (void)mover.sweep();
  out.mesh = result.mesh;
  out.n_rechecked = mover.n_rechecked_;
  out.n_promoted = mover.n_promoted_;
  out.promoted = mover.promoted_ids();
  out.samples = std::move(mover.recorded_samples_);
  out.vertices = std::move(mover.recorded_vertices_);
  std::sort(out.samples.begin(), out.samples.end());
  std::sort(out.vertices.begin(), out.vertices.end());
  out.n_walked = mover.n_walked_;
  out.n_searched = mover.n_searched_;
  out.n_certified = mover.n_certified_;
  return out;
}

FidelityGate fidelity_gate(const SurfaceMesh& surface, const TriMesh& input, const StitchOptions& options) {
  FidelityGate gate;
  if (!(options.fidelity_gate_edges > 0.0) || surface.input_face_patch.size() != input.n_faces() ||
      surface.surfaces.size() != surface.patches.size()) {
    return gate;
  }
  const double bound = options.fidelity_gate_edges * surface.input_mean_edge;
  // Faces with a corner farther from their patch's fit than the gate, along the patch's axis
  // (a face of no patch: measured).
  std::vector<std::uint8_t> far(input.n_faces(), 0);
  parallel::for_each_index(input.n_faces(), options.n_threads, kQueryChunk, [&](std::size_t f) {
    const int p = surface.input_face_patch[f];
    if (p < 0 || static_cast<std::size_t>(p) >= surface.surfaces.size()) {
      far[f] = 1;
      return;
    }
    if (!(surface.patches[static_cast<std::size_t>(p)].fit_max_residual > bound)) return;
    const PatchSurface& fit = surface.surfaces[static_cast<std::size_t>(p)];
    for (auto v : input.fv_range(TriMesh::FaceHandle(static_cast<int>(f)))) {
      const Vec local = fit.frame.to_local(point(input, v));
      if (std::abs(local.z() - fit.field.value(local.x(), local.y())) > bound) {
        far[f] = 1;
        return;
      }
    }
  });
  // Measured: those faces and the faces around their corners.
  std::vector<std::uint8_t> near_far(input.n_vertices(), 0);
  for (auto f : input.faces()) {
    if (far[static_cast<std::size_t>(f.idx())] == 0) continue;
    for (auto v : input.fv_range(f)) near_far[static_cast<std::size_t>(v.idx())] = 1;
  }
  gate.input_face.assign(input.n_faces(), 0);
  for (auto f : input.faces()) {
    for (auto v : input.fv_range(f)) {
      if (near_far[static_cast<std::size_t>(v.idx())] != 0) gate.input_face[static_cast<std::size_t>(f.idx())] = 1;
    }
  }
  // Output vertices measured: those of the patches with a measured face.
  gate.patch.assign(surface.patches.size(), 0);
  for (std::size_t f = 0; f < gate.input_face.size(); ++f) {
    const int p = surface.input_face_patch[f];
    if (gate.input_face[f] != 0 && p >= 0 && static_cast<std::size_t>(p) < gate.patch.size()) gate.patch[static_cast<std::size_t>(p)] = 1;
  }
  return gate;
}

FidelityResult move_toward_input(const TriMesh& input, const StitchOptions& options,
                                 std::vector<std::uint8_t>& is_feature, double reference_edge, const FinRimBound& rim,
                                 StitchResult& result, bool incremental,
                                 const quality_detail::IndexedSoup* input_index, const FidelityGate* gate) {
  FidelityResult out;
  const double bound = options.fidelity_distance_edges * reference_edge;
  TriMesh& mesh = result.mesh;
  if (!(bound > 0.0) || input.n_faces() == 0 || mesh.n_faces() == 0) return out;
  const std::size_t n_vertices = mesh.n_vertices(), n_faces = result.face_patch.size(), n_nodes = is_feature.size();
  std::optional<TriMesh> before;
  if (options.check_self_intersections) before = mesh;
  const std::vector<Vec> start = vertex_points(mesh);
  FidelityMover mover(input, options, bound, reference_edge, rim, incremental, result, is_feature,
                      fixed_vertices(mesh, result.vertex_node, is_feature), input_index, gate);
  for (int round = 0; round < kFidelityRounds; ++round) {
    if (mover.sweep() == 0) break;
    ++out.n_sweeps_changing;
  }
  out.n_split = mover.n_splits_;
  out.n_rechecked = mover.n_rechecked_;
  out.n_promoted = mover.n_promoted_;
  auto moved = [&](TriMesh::VertexHandle v) {
    const auto i = static_cast<std::size_t>(v.idx());
    return i >= n_vertices || point(mesh, v) != start[i];
  };
  if (options.check_self_intersections) {
    // Moves on triangles that cross others go back; crossings left after the last round,
    // or at new nodes: everything goes back.
    bool restore = false;
    for (int round = 0; round < kFidelityCheckRounds; ++round) {
      std::vector<std::uint32_t> faces;
      for (auto f : mesh.faces()) {
        for (auto u : mesh.fv_range(f)) {
          if (moved(u)) {
            faces.push_back(static_cast<std::uint32_t>(f.idx()));
            break;
          }
        }
      }
      if (faces.empty()) break;
      const auto pairs = intersecting_pairs_of(to_soup(mesh), faces, options.n_threads);
      if (pairs.empty()) break;
      std::size_t n_put_back = 0;
      for (const auto& pair : pairs) {
        for (const std::uint32_t f : pair) {
          for (auto u : mesh.fv_range(TriMesh::FaceHandle(static_cast<int>(f)))) {
            const auto i = static_cast<std::size_t>(u.idx());
            if (i >= n_vertices || !moved(u)) continue;
            mesh.set_point(u, to_openmesh(start[i]));
            ++n_put_back;
          }
        }
      }
      out.n_undone += n_put_back;
      if (n_put_back == 0 || round + 1 == kFidelityCheckRounds) {
        restore = true;
        break;
      }
    }
    if (restore) {
      std::size_t n_changed = mover.n_splits_;
      for (auto u : mesh.vertices()) n_changed += static_cast<std::size_t>(u.idx()) < n_vertices && moved(u) ? 1 : 0;
      mesh = std::move(*before);
      result.face_patch.resize(n_faces);
      result.vertex_node.resize(n_vertices);
      is_feature.resize(n_nodes);
      out.n_undone += n_changed;
      out.n_split = 0;
      out.n_moved = 0;
      return out;
    }
  }
  for (auto u : mesh.vertices()) out.n_moved += static_cast<std::size_t>(u.idx()) < n_vertices && moved(u) ? 1 : 0;
  return out;
}

}  // namespace nurbsfront::stitch_detail
