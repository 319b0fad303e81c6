// SPDX-License-Identifier: BSD-3-Clause
// stitch(): assembly by global node id, optimisation (optimise.cpp), verification.
#include "nurbsfront/stitch/stitch.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <future>
#include <iterator>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <string>

#include "nurbsfront/core/disjoint_sets.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup_internal.h"
#include "nurbsfront/core/stopwatch.h"
#include "nurbsfront/stitch/stitch_internal.h"
#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront {

void StitchOptions::validate() const {
  auto fail = [](const std::string& what) { throw InvalidInput("stitch: " + what); };
  if (optimisation_passes < 0) fail("optimisation_passes must be >= 0");
  if (angle_repair_rounds < 0) fail("angle_repair_rounds must be >= 0");
  if (obtuse_repair_rounds < 0) fail("obtuse_repair_rounds must be >= 0");
  if (obtuse_search_steps < 0 || obtuse_search_steps > 30) fail("obtuse_search_steps must be in [0, 30]");
  if (feature_slide_rounds < 0) fail("feature_slide_rounds must be >= 0");
  if (!(feature_slide_cosine_gain > 0.0)) fail("feature_slide_cosine_gain must be > 0 (infinity: off)");
  if (obtuse_split_rounds < 0) fail("obtuse_split_rounds must be >= 0");
  if (!(obtuse_split_feature_angle_deg >= 0.0 && obtuse_split_feature_angle_deg < 60.0))
    fail("obtuse_split_feature_angle_deg must be in [0, 60)");
  if (!(max_flip_dihedral_deg >= 0.0 && max_flip_dihedral_deg < 180.0)) fail("max_flip_dihedral_deg must be in [0, 180)");
  if (!(flip_gain >= 0.0) || !std::isfinite(flip_gain)) fail("flip_gain must be finite and >= 0");
  if (!(smoothing_relaxation > 0.0 && smoothing_relaxation <= 1.0)) fail("smoothing_relaxation must be in (0, 1]");
  if (!(chord_compensation >= 0.0 && chord_compensation <= 2.0)) fail("chord_compensation must be in [0, 2]");
  if (!(volume_compensation >= 0.0 && volume_compensation <= 2.0)) fail("volume_compensation must be in [0, 2]");
  if (!(volume_compensation_skip_within >= 0.0 && volume_compensation_skip_within <= 0.05))
    fail("volume_compensation_skip_within must be in [0, 0.05]");
  if (!(min_normal_dot >= -1.0 && min_normal_dot < 1.0)) fail("min_normal_dot must be in [-1, 1)");
  if (!(alpha_floor >= 0.0 && alpha_floor <= 1.0)) fail("alpha_floor must be in [0, 1]");
  if (!(angle_floor_deg >= 0.0 && angle_floor_deg < 60.0)) fail("angle_floor_deg must be in [0, 60)");
  if (!(collapse_below_angle_deg >= 0.0 && collapse_below_angle_deg < 60.0)) fail("collapse_below_angle_deg must be in [0, 60)");
  if (!(fidelity_distance_edges >= 0.0 && std::isfinite(fidelity_distance_edges)))
    fail("fidelity_distance_edges must be finite and >= 0");
  if (!(fidelity_gate_edges >= 0.0 && std::isfinite(fidelity_gate_edges))) fail("fidelity_gate_edges must be finite and >= 0");
  if (!(fidelity_alpha_floor >= 0.0 && fidelity_alpha_floor <= 1.0)) fail("fidelity_alpha_floor must be in [0, 1]");
  if (!(fin_rim_max_move >= 0.0)) fail("fin_rim_max_move must be >= 0 (infinity: no bound)");
  if (n_threads == 0) fail("n_threads must be >= 1");
}

namespace {

void validate_surface(const SurfaceMesh& s) {
  auto fail = [](const std::string& what) { throw InvalidInput("stitch: invalid SurfaceMesh: " + what); };
  const std::size_t n = s.nodes.size();
  if (s.node_kind.size() != n) fail("node_kind has " + std::to_string(s.node_kind.size()) + " entries for " + std::to_string(n) + " nodes");
  if (s.node_owner.size() != n) fail("node_owner has " + std::to_string(s.node_owner.size()) + " entries for " + std::to_string(n) + " nodes");
  if (s.triangle_patch.size() != s.triangles.size()) {
    fail("triangle_patch has " + std::to_string(s.triangle_patch.size()) + " entries for " +
         std::to_string(s.triangles.size()) + " triangles");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!s.nodes[i].allFinite()) fail("node " + std::to_string(i) + " has non-finite coordinates");
    const int owner = s.node_owner[i];
    switch (s.node_kind[i]) {
      case NodeKind::Corner:
        break;
      case NodeKind::Border:
        if (owner < 0 || static_cast<std::size_t>(owner) >= s.curve_is_feature.size()) {
          fail("border node " + std::to_string(i) + " names curve " + std::to_string(owner) + " of " +
               std::to_string(s.curve_is_feature.size()));
        }
        break;
      case NodeKind::Inner:
        if (owner < 0 || static_cast<std::size_t>(owner) >= s.surfaces.size()) {
          fail("inner node " + std::to_string(i) + " names patch " + std::to_string(owner) + " of " +
               std::to_string(s.surfaces.size()));
        }
        break;
      default:
        fail("node " + std::to_string(i) + " has an unknown kind");
    }
  }
  if (!s.curve_is_fin_rim.empty() && s.curve_is_fin_rim.size() != s.curve_is_feature.size()) {
    fail("curve_is_fin_rim has " + std::to_string(s.curve_is_fin_rim.size()) + " entries for " +
         std::to_string(s.curve_is_feature.size()) + " curves");
  }
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    for (int k : s.triangles[t]) {
      if (k < 0 || static_cast<std::size_t>(k) >= n) fail("triangle " + std::to_string(t) + " names node " + std::to_string(k));
    }
    const int patch = s.triangle_patch[t];
    if (patch < 0 || static_cast<std::size_t>(patch) >= s.surfaces.size()) {
      fail("triangle " + std::to_string(t) + " names patch " + std::to_string(patch) + " of " + std::to_string(s.surfaces.size()));
    }
  }
}

// OpenMesh's add_face prints to std::cerr before refusing a face; the library is silent,
// so the cases it refuses are tested first: a repeated vertex, an edge already used in
// the same direction (a duplicated or flipped face), or a vertex whose fan is closed.
bool can_add_face(const TriMesh& mesh, const std::array<TriMesh::VertexHandle, 3>& v) {
  if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) return false;
  for (int k = 0; k < 3; ++k) {
    if (!mesh.is_boundary(v[k])) return false;
    const auto h = mesh.find_halfedge(v[k], v[(k + 1) % 3]);
    if (h.is_valid() && !mesh.is_boundary(h)) return false;
  }
  return true;
}

double mean_of(const std::vector<double>& x) {
  double sum = 0.0;
  for (double a : x) sum += a;
  return x.empty() ? std::numeric_limits<double>::quiet_NaN() : sum / double(x.size());
}

std::string component_text(std::size_t index, const ComponentSignature& c) {
  return "component " + std::to_string(index) + " (" + std::to_string(c.n_faces) + " faces, chi " +
         std::to_string(c.euler_characteristic) + (c.is_closed ? ", closed)" : ", open)");
}

void compare_with_input(StitchReport& report) {
  const auto& in = report.input_components;
  const auto& out = report.output_components;
  bool in_closed = true, out_closed = true;
  for (const auto& c : in) in_closed = in_closed && c.is_closed;
  for (const auto& c : out) out_closed = out_closed && c.is_closed;
  if (in_closed && !out_closed) {
    report.errors.push_back("output is open (" + std::to_string(report.output.topology.n_boundary_edges) +
                            " boundary edges) but the input is closed");
  }
  if (!in_closed && out_closed) report.errors.push_back("output is closed but the input is open");
  if (in.size() != out.size()) {
    report.errors.push_back("output has " + std::to_string(out.size()) + " components, the input " + std::to_string(in.size()));
  }
  // Each output component goes to the input component with the nearest bounding box.
  std::vector<std::vector<std::size_t>> matched(in.size());
  for (std::size_t o = 0; o < out.size() && !in.empty(); ++o) {
    std::size_t best = 0;
    double best_cost = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < in.size(); ++i) {
      const double cost = (out[o].box.min - in[i].box.min).norm() + (out[o].box.max - in[i].box.max).norm();
      if (cost < best_cost) {
        best_cost = cost;
        best = i;
      }
    }
    matched[best].push_back(o);
  }
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (matched[i].empty()) {
      report.errors.push_back("input " + component_text(i, in[i]) + " has no counterpart in the output");
    } else if (matched[i].size() > 1) {
      report.errors.push_back("input " + component_text(i, in[i]) + " became " + std::to_string(matched[i].size()) +
                              " output components");
    } else {
      const auto& o = out[matched[i][0]];
      if (o.euler_characteristic != in[i].euler_characteristic || o.is_closed != in[i].is_closed) {
        report.errors.push_back("input " + component_text(i, in[i]) + " became output " +
                                component_text(matched[i][0], o));
      }
    }
  }
}

// Per node: 1 for a feature node (a node of a feature curve, or a corner ending one; every
// corner when the curves' node lists are missing).
std::vector<std::uint8_t> feature_nodes(const SurfaceMesh& s) {
  std::vector<std::uint8_t> out(s.nodes.size(), 0);
  const bool has_curves = s.curve_nodes.size() == s.curve_is_feature.size();
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    if (s.node_kind[i] == NodeKind::Border) out[i] = s.curve_is_feature[static_cast<std::size_t>(s.node_owner[i])];
    if (s.node_kind[i] == NodeKind::Corner && !has_curves) out[i] = 1;
  }
  if (has_curves) {
    for (std::size_t c = 0; c < s.curve_nodes.size(); ++c) {
      if (s.curve_is_feature[c] == 0) continue;
      for (const int g : s.curve_nodes[c]) {
        if (g >= 0 && static_cast<std::size_t>(g) < out.size()) out[static_cast<std::size_t>(g)] = 1;
      }
    }
  }
  return out;
}

// The StitchReport figures of the triangles away from features (no feature node, no fin
// rim node: `rim` per SurfaceMesh node, may be empty) and of those at fin rims only.
void measure_away_from_features(const std::vector<std::uint8_t>& feature, const std::vector<std::uint8_t>& rim,
                                const StitchResult& result, StitchReport& report) {
  const TriMesh& mesh = result.mesh;
  // Smallest angle, the sine below which a triangle may change a figure, and the count below
  // the bound, of the two sets. Triangles surely above both min_angle and the bound change
  // neither figure: not measured (from a set's first triangle on, its min_angle <= 60 deg;
  // before it, every triangle is).
  struct Smallest {
    double min_angle = 180.0;
    double sin_bound = 2.0;
    std::size_t n = 0, n_small = 0;
    void add(const std::array<Eigen::Vector3d, 3>& p) {
      ++n;
      if (!stitch_detail::may_have_angle_below(p[0], p[1], p[2], sin_bound)) return;
      const std::array<double, 3> angles = triangle_angles_deg(p[0], p[1], p[2]);
      const double smallest = std::min({angles[0], angles[1], angles[2]});
      if (smallest < min_angle) {
        min_angle = smallest;
        sin_bound = std::sin(std::max(min_angle, kAwayFromFeaturesAngleBoundDeg) * std::numbers::pi / 180.0);
      }
      if (smallest < kAwayFromFeaturesAngleBoundDeg) ++n_small;
    }
  } away, at_rims;
  for (auto f : mesh.faces()) {
    std::array<Eigen::Vector3d, 3> p;
    bool at_feature = false, at_rim = false;
    int k = 0;
    for (auto v : mesh.fv_range(f)) {
      const auto node = static_cast<std::size_t>(result.vertex_node[static_cast<std::size_t>(v.idx())]);
      if (feature[node] != 0) at_feature = true;
      if (node < rim.size() && rim[node] != 0) at_rim = true;
      p[static_cast<std::size_t>(k++)] = to_eigen(mesh.point(v));
    }
    if (at_feature) continue;
    (at_rim ? at_rims : away).add(p);
  }
  report.n_away_from_features = away.n;
  report.min_angle_away_from_features_deg = away.n > 0 ? away.min_angle : 0.0;
  report.n_small_angle_away_from_features = away.n_small;
  report.n_at_fin_rims = at_rims.n;
  report.min_angle_at_fin_rims_deg = at_rims.n > 0 ? at_rims.min_angle : 0.0;
  report.n_small_angle_at_fin_rims = at_rims.n_small;
}

using FacePair = std::array<std::uint32_t, 2>;

// The soup of an assembly: every node used by a triangle becomes a point (in node order,
// vertex_node names it), the triangles follow in order by those points.
struct AssemblySoup {
  TriangleSoup soup;
  std::vector<int> vertex_node;
  std::size_t n_unused_nodes = 0;
};

AssemblySoup assembly_soup(const std::vector<Eigen::Vector3d>& nodes, const std::vector<std::array<int, 3>>& triangles) {
  AssemblySoup out;
  std::vector<char> used(nodes.size(), 0);
  for (const auto& t : triangles) {
    for (int k : t) used[static_cast<std::size_t>(k)] = 1;
  }
  std::vector<std::uint32_t> index(nodes.size(), 0);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (!used[i]) {
      ++out.n_unused_nodes;
      continue;
    }
    index[i] = static_cast<std::uint32_t>(out.soup.points.size());
    out.soup.points.push_back(nodes[i]);
    out.vertex_node.push_back(static_cast<int>(i));
  }
  out.soup.triangles.reserve(triangles.size());
  for (const auto& t : triangles) {
    out.soup.triangles.push_back({index[static_cast<std::size_t>(t[0])], index[static_cast<std::size_t>(t[1])],
                                  index[static_cast<std::size_t>(t[2])]});
  }
  return out;
}

// Every node used by a triangle becomes a vertex (in node order); triangles are added in
// order, those OpenMesh cannot take are counted (n_rejected_triangles). `prepared`: the
// triangles' assembly_soup() already found an oriented 2-manifold by check_manifold().
void assemble(const std::vector<Eigen::Vector3d>& nodes, const std::vector<std::array<int, 3>>& triangles,
              const std::vector<int>& triangle_patch, unsigned n_threads, StitchResult& result, StitchReport& report,
              AssemblySoup* prepared = nullptr) {
  result.mesh = TriMesh();
  result.vertex_node.clear();
  result.face_patch.clear();
  report.n_unused_nodes = 0;
  report.n_rejected_triangles = 0;
  // The usual case, an oriented 2-manifold: built directly by to_trimesh(), which gives
  // exactly the mesh that add_face() in triangle order gives (same vertex, edge, halfedge
  // and face numbering; add_face() never refuses a triangle of such a soup), at about half
  // the cost. Otherwise face by face below, skipping the triangles add_face() refuses.
  // With 2+ threads the manifold check runs beside the direct build (check_and_build).
  std::optional<AssemblySoup> own;
  if (prepared == nullptr) own = assembly_soup(nodes, triangles);
  AssemblySoup& a = prepared != nullptr ? *prepared : *own;
  report.n_unused_nodes = a.n_unused_nodes;
  if (prepared != nullptr) {
    core_detail::to_trimesh_checked(a.soup, result.mesh, n_threads);
    result.vertex_node = std::move(a.vertex_node);
    result.face_patch = triangle_patch;
    return;
  }
  if (core_detail::check_and_build(a.soup, result.mesh, n_threads).ok()) {
    result.vertex_node = std::move(a.vertex_node);
    result.face_patch = triangle_patch;
    return;
  }
  result.mesh = TriMesh();
  TriMesh& mesh = result.mesh;
  std::vector<TriMesh::VertexHandle> handle(nodes.size());
  for (const int i : a.vertex_node) {
    handle[static_cast<std::size_t>(i)] = mesh.add_vertex(to_openmesh(nodes[static_cast<std::size_t>(i)]));
    result.vertex_node.push_back(i);
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const auto& tri = triangles[t];
    const std::array<TriMesh::VertexHandle, 3> v{handle[tri[0]], handle[tri[1]], handle[tri[2]]};
    if (!can_add_face(mesh, v) || !mesh.add_face(v[0], v[1], v[2]).is_valid()) {
      ++report.n_rejected_triangles;
      continue;
    }
    result.face_patch.push_back(triangle_patch[t]);
  }
}

// Rounds of collapse_short_edges before its merges are given up. Each round freezes the
// nodes of the merges next to an intersection and decides again; the other merges of a
// round change little, so the rounds converge. Three were too few: on headsq at iso 500 the
// 4th round was the first without intersections (16, 7, 6, 0 pairs) and all 99 merges were
// given up, femur alike (10, 6, 5, 0; 114 merges).
constexpr int kCollapseRounds = 12;

// Collapses short edges (collapse_short_edges) and re-assembles the triangles by the merged
// node ids. Merges whose triangles intersect others (exact check of the faces around the
// survivors, when check_self_intersections) or that OpenMesh cannot assemble are given up:
// their removed nodes are frozen and the collapses are decided again.
// A trial is checked on its assembly soup (the points and triangles to_soup() of its
// assembled mesh gives), so result keeps the assembly until a trial is kept: only the kept
// trial is built (a trial given up costs no mesh build and no copy back). With 2+ threads the
// soup's manifold check runs beside the crossing check. A soup that is no oriented
// 2-manifold (OpenMesh's face-by-face path) is assembled apart and checked as a mesh.
void collapse(const SurfaceMesh& surface, const StitchOptions& options, const std::vector<std::uint8_t>& feature,
              StitchResult& result, StitchReport& report) {
  if (!(options.collapse_below_angle_deg > 0.0) || result.mesh.n_faces() == 0) return;
  std::vector<std::uint8_t> frozen(surface.nodes.size(), 0);
  for (int round = 0; round < kCollapseRounds; ++round) {
    const stitch_detail::NodeMerges merges = stitch_detail::collapse_short_edges(surface, options, result, feature, frozen);
    if (merges.n_merges == 0) return;
    std::vector<Eigen::Vector3d> nodes = surface.nodes;
    for (const auto& [g, q] : merges.moved) nodes[static_cast<std::size_t>(g)] = q;
    std::vector<std::array<int, 3>> triangles;
    std::vector<int> triangle_patch;
    triangles.reserve(surface.triangles.size());
    triangle_patch.reserve(surface.triangles.size());
    for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
      std::array<int, 3> tri{};
      for (int k = 0; k < 3; ++k) tri[static_cast<std::size_t>(k)] = merges.target[static_cast<std::size_t>(surface.triangles[t][static_cast<std::size_t>(k)])];
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) continue;
      triangles.push_back(tri);
      triangle_patch.push_back(surface.triangle_patch[t]);
    }
    // The faces around the survivors that moved or took a node: with every triangle
    // assembled (checked below), face t is triangle t.
    std::vector<std::uint8_t> is_survivor(surface.nodes.size(), 0);
    for (std::size_t g = 0; g < merges.target.size(); ++g) {
      if (merges.target[g] != static_cast<int>(g)) is_survivor[static_cast<std::size_t>(merges.target[g])] = 1;
    }
    std::vector<std::uint32_t> touched;
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const auto& tri = triangles[t];
      if (is_survivor[static_cast<std::size_t>(tri[0])] != 0 || is_survivor[static_cast<std::size_t>(tri[1])] != 0 ||
          is_survivor[static_cast<std::size_t>(tri[2])] != 0) {
        touched.push_back(static_cast<std::uint32_t>(t));
      }
    }
    AssemblySoup soup = assembly_soup(nodes, triangles);
    std::future<bool> manifold_check;
    if (options.n_threads >= 2) {
      manifold_check = std::async(std::launch::async, [&soup] { return check_manifold(soup.soup).ok(); });
    }
    std::vector<FacePair> pairs;
    if (options.check_self_intersections) pairs = intersecting_pairs_of(soup.soup, touched, options.n_threads);
    const bool is_manifold = manifold_check.valid() ? manifold_check.get() : check_manifold(soup.soup).ok();
    std::optional<StitchResult> apart;  // the trial of a soup that is no oriented 2-manifold
    if (!is_manifold) {
      apart.emplace();
      StitchReport apart_report;
      assemble(nodes, triangles, triangle_patch, options.n_threads, *apart, apart_report);
      if (apart_report.n_rejected_triangles > 0) {
        report.n_collapses_undone += merges.n_merges;
        return;
      }
      pairs.clear();
      if (options.check_self_intersections) pairs = intersecting_pairs_of(stitch_detail::mesh_soup(apart->mesh), touched, options.n_threads);
    }
    if (pairs.empty()) {
      report.n_unused_nodes = soup.n_unused_nodes - merges.n_merges;
      report.n_collapses = merges.n_merges;
      if (apart) {
        result.mesh = apart->mesh;
        result.face_patch = std::move(apart->face_patch);
        result.vertex_node = std::move(apart->vertex_node);
      } else {
        StitchReport trial_report;
        assemble(nodes, triangles, triangle_patch, options.n_threads, result, trial_report, &soup);
      }
      return;
    }
    // Freeze the nodes merged into a survivor of an intersecting face.
    for (const auto& pair : pairs) {
      for (const std::uint32_t f : pair) {
        for (const int s : triangles[f]) {
          if (is_survivor[static_cast<std::size_t>(s)] == 0) continue;
          for (std::size_t g = 0; g < merges.target.size(); ++g) {
            if (merges.target[g] == s && static_cast<int>(g) != s && frozen[g] == 0) {
              frozen[g] = 1;
              ++report.n_collapses_undone;
            }
          }
        }
      }
    }
  }
}

// Rounds of local repair before the optimisation is undone as a whole.
constexpr int kRepairRounds = 6;

// The optimisation may push a node through a nearby sheet (thin walls) or flip an edge
// into one. `pairs` (all intersecting pairs of `mesh`, sorted) is updated in place while
// the offending changes are undone: the nodes of an intersecting face the optimisation
// changed go back to their assembled positions, and its edges that a flip made are
// flipped back (flips keep vertex and face indices). Only the faces around the undone
// changes are checked again (intersecting_pairs_of). Pairs of two faces the optimisation
// did not change (same vertices at the same positions as assembled) were there before
// and stay. Returns false when changed faces still intersect after kRepairRounds.
bool repair_intersections(const TriMesh& assembled, TriMesh& mesh, std::vector<FacePair>& pairs, StitchReport& report) {
  // A face is untouched when the assembled mesh has the same triangle (same vertices, same
  // orientation, same positions), under any face index: undoing flips in another order
  // than they were made can restore a triangle under its neighbour's index.
  auto is_untouched = [&](std::uint32_t f) {
    std::array<TriMesh::VertexHandle, 3> v;
    int k = 0;
    for (auto u : mesh.fv_range(TriMesh::FaceHandle(static_cast<int>(f)))) {
      if (mesh.point(u) != assembled.point(u)) return false;
      v[static_cast<std::size_t>(k++)] = u;
    }
    const auto h = assembled.find_halfedge(v[0], v[1]);
    return h.is_valid() && !assembled.is_boundary(h) && assembled.to_vertex_handle(assembled.next_halfedge_handle(h)) == v[2];
  };
  auto offending = [&] {
    std::vector<std::uint32_t> faces;
    for (const auto& pair : pairs) {
      for (const std::uint32_t f : pair) {
        if (!is_untouched(f)) faces.push_back(f);
      }
    }
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    return faces;
  };
  std::vector<char> changed(mesh.n_faces(), 0);
  for (int round = 0; round < kRepairRounds; ++round) {
    const std::vector<std::uint32_t> faces = offending();
    if (faces.empty()) return true;
    std::vector<std::uint32_t> touched;
    auto touch = [&](TriMesh::FaceHandle f) {
      if (!f.is_valid() || changed[static_cast<std::size_t>(f.idx())] != 0) return;
      changed[static_cast<std::size_t>(f.idx())] = 1;
      touched.push_back(static_cast<std::uint32_t>(f.idx()));
    };
    std::vector<TriMesh::EdgeHandle> flipped;
    for (const std::uint32_t f : faces) {
      const TriMesh::FaceHandle face(static_cast<int>(f));
      touch(face);
      for (auto h : mesh.fh_range(face)) {
        const auto v = mesh.to_vertex_handle(h);
        if (mesh.point(v) != assembled.point(v)) {
          mesh.set_point(v, assembled.point(v));
          ++report.n_reverted_moves;
          for (auto g : mesh.vf_range(v)) touch(g);
        }
        if (!assembled.find_halfedge(mesh.from_vertex_handle(h), v).is_valid()) flipped.push_back(mesh.edge_handle(h));
      }
    }
    std::sort(flipped.begin(), flipped.end());
    flipped.erase(std::unique(flipped.begin(), flipped.end()), flipped.end());
    for (const auto e : flipped) {
      const auto h = mesh.halfedge_handle(e, 0);
      // Still an edge the flips made, and flippable (the other diagonal is not an edge).
      if (assembled.find_halfedge(mesh.from_vertex_handle(h), mesh.to_vertex_handle(h)).is_valid() ||
          !mesh.is_flip_ok(e)) {
        continue;
      }
      mesh.flip(e);
      ++report.n_reverted_flips;
      touch(mesh.face_handle(h));
      touch(mesh.opposite_face_handle(h));
    }
    // Pairs with a changed face are replaced by that face's pairs now.
    stitch_detail::replace_pairs(pairs, [&](std::uint32_t f) { return changed[f] != 0; }, intersecting_pairs_of(stitch_detail::mesh_soup(mesh), touched));
    for (const std::uint32_t f : touched) changed[f] = 0;
  }
  return offending().empty();
}

// Rounds of obtuse splits before those whose triangles cross others are given up as a whole.
constexpr int kSplitRounds = 3;

// stitch_detail::split_obtuse, checked: the faces around the changed vertices (the new ones
// and their rings, SplitResult::near) are checked exactly against the whole mesh; when some cross, the mesh
// goes back to how it was and the splits again, without those whose new vertex is on a
// crossing face (all of them when none is). Faces are appended and vertices added by the
// splits, so the earlier ones keep their indices.
void split_obtuse_checked(const SurfaceMesh& surface, const StitchOptions& options, std::vector<std::uint8_t>& feature,
                          StitchResult& result, StitchReport& report) {
  // The copy to go back to exists only when a crossing can make the splits go back.
  std::optional<TriMesh> before;
  if (options.check_self_intersections) before = result.mesh;
  const std::size_t n_faces = result.face_patch.size(), n_vertices = result.vertex_node.size(), n_nodes = feature.size();
  auto restore = [&] {
    result.mesh = *before;
    result.face_patch.resize(n_faces);
    result.vertex_node.resize(n_vertices);
    feature.resize(n_nodes);
  };
  std::vector<std::array<int, 2>> refused;
  for (int round = 0; round < kSplitRounds; ++round) {
    const stitch_detail::SplitResult split = stitch_detail::split_obtuse(surface, options, feature, result, refused);
    if (split.n_splits == 0) return;
    std::vector<FacePair> pairs;
    if (options.check_self_intersections) {
      const std::vector<std::uint8_t>& near = split.near;
      std::vector<std::uint32_t> touched;
      for (auto f : result.mesh.faces()) {
        for (auto v : result.mesh.fv_range(f)) {
          if (near[static_cast<std::size_t>(v.idx())] != 0) {
            touched.push_back(static_cast<std::uint32_t>(f.idx()));
            break;
          }
        }
      }
      pairs = intersecting_pairs_of(stitch_detail::mesh_soup(result.mesh), touched, options.n_threads);
    }
    if (pairs.empty()) {
      report.n_obtuse_splits = split.n_splits;
      report.n_flips += split.n_flips;
      report.n_smoothing_moves += split.n_moves;
      return;
    }
    // The splits whose new vertex (or a ring neighbour of it) is on a crossing face.
    const std::size_t refused_before = refused.size();
    for (std::size_t k = 0; k < split.made.size(); ++k) {
      const auto v = split.made[k];
      bool crossing = false;
      for (const auto& pair : pairs) {
        for (const std::uint32_t f : pair) {
          for (auto u : result.mesh.fv_range(TriMesh::FaceHandle(static_cast<int>(f)))) {
            crossing = crossing || u == v || result.mesh.find_halfedge(u, v).is_valid();
          }
        }
      }
      // An edge is refused by its two vertices, so only an edge of the mesh before the splits
      // (a vertex made by a split gets another index in the next round).
      const auto& edge = split.split_edges[k];
      const bool original = static_cast<std::size_t>(edge[0]) < n_vertices && static_cast<std::size_t>(edge[1]) < n_vertices;
      if (crossing && original) refused.push_back(edge);
    }
    const std::size_t blamed = refused.size() - refused_before;
    restore();
    if (blamed == 0 || round + 1 == kSplitRounds) {
      // Given up: every split of this round is undone.
      report.n_obtuse_splits_undone += split.n_splits;
      return;
    }
    report.n_obtuse_splits_undone += blamed;
    std::sort(refused.begin(), refused.end());
  }
}

StitchResult stitch_impl(const SurfaceMesh& surface, const TriMesh* input, const StitchOptions& options,
                         const quality_detail::IndexedSoup* input_index) {
  options.validate();
  validate_surface(surface);
  StitchResult result;
  StitchReport& report = result.report;
  report.n_input_nodes = surface.nodes.size();
  report.n_input_triangles = surface.triangles.size();
  report_progress(options.progress, "stitch: assemble", 0.0);
  Stopwatch watch;
  // With two or more threads the input's component signatures (only read from the input)
  // are taken on a helper thread while this one stitches; the same values either way.
  std::future<std::vector<ComponentSignature>> input_components;
  if (input != nullptr && options.n_threads >= 2) {
    input_components = std::async(std::launch::async, [input] { return component_signatures(*input); });
  }
  // The volume compensation's label-image gate (a pass over the input's edges: 0.13 G
  // instructions on the liver), likewise, unless mesh_surface() has the answer; compensate_volume()
  // then skips it (it still needs the input for its enclosed-volume check).
  std::future<bool> input_on_lattice;
  if (input != nullptr && options.n_threads >= 2 && options.volume_compensation > 0.0 && !surface.triangles.empty() &&
      !surface.input_label_staircase) {
    input_on_lattice = std::async(std::launch::async, [input] { return surfmesh_detail::on_label_image_staircase(*input); });
  }
  // Whether the input is a label image's staircase (the volume compensation's and the fidelity
  // moves' gate): mesh_surface()'s answer, else the helper thread's, else tested here once.
  std::optional<bool> label_staircase = surface.input_label_staircase;
  auto is_label_staircase = [&]() {
    if (!label_staircase) {
      label_staircase =
          input_on_lattice.valid() ? input_on_lattice.get() : surfmesh_detail::on_label_image_staircase(*input);
    }
    return *label_staircase;
  };

  // 1. Assembly by id.
  assemble(surface.nodes, surface.triangles, surface.triangle_patch, options.n_threads, result, report);
  TriMesh& mesh = result.mesh;
  if (report.n_rejected_triangles > 0) {
    report.errors.push_back(std::to_string(report.n_rejected_triangles) +
                            " triangles could not be added by node id (a repeated node, an edge used twice in one "
                            "direction, or a closed vertex fan: duplicated, flipped or overlapping triangles)");
  }
  {
    const std::vector<double> alpha = stitch_detail::face_alphas(mesh, options.n_threads);
    report.alpha_mean_before = mean_of(alpha);
    double min_alpha = std::numeric_limits<double>::quiet_NaN();
    for (double a : alpha) min_alpha = std::isnan(min_alpha) ? a : std::min(min_alpha, a);
    report.alpha_min_before = min_alpha;
  }
  std::vector<std::uint8_t> feature = feature_nodes(surface);  // grows with obtuse splits
  if (report.n_rejected_triangles == 0) collapse(surface, options, feature, result, report);
  report.seconds_assemble = watch.seconds();

  // 2. Cross-border optimisation.
  watch.restart();
  const bool optimise = mesh.n_faces() > 0 && (options.optimisation_passes > 0 || options.obtuse_repair_rounds > 0 ||
                                                options.chord_compensation > 0.0 || options.volume_compensation > 0.0);
  TriMesh assembled;
  std::vector<int> assembled_patch;
  if (optimise) {
    assembled = mesh;
    assembled_patch = result.face_patch;
    stitch_detail::optimise(surface, options, feature, result, report);
    report.n_chord_compensation_moves = stitch_detail::compensate_chords(mesh, result.vertex_node, feature,
                                                                         options.chord_compensation, surface.input_mean_edge,
                                                                         options.n_threads);
    // compensate_volume()'s label-image gate, taken here (it is told so).
    const bool gated = input != nullptr && options.volume_compensation > 0.0 && mesh.n_faces() > 0 && is_label_staircase();
    stitch_detail::VolumeCompensation how;
    how.strength = options.volume_compensation;
    how.skip_within = options.volume_compensation_skip_within;
    how.label_gate_done = true;
    how.n_threads = options.n_threads;
    report.n_volume_compensation_moves =
        gated ? 0
              : stitch_detail::compensate_volume(surface, input, mesh, result.face_patch, result.vertex_node, feature,
                                                 how, &report.volume_compensation_skipped);
    // The compensation's moves come after the obtuse repair and can leave triangles obtuse
    // that the splits cannot take apart (rotor: 39 obtuse with it, 37 without): the repair once
    // more. Not where the compensation is gated off (label-image staircases).
    if (options.obtuse_repair_rounds > 0 && report.n_volume_compensation_moves > 0) {
      const auto repaired = stitch_detail::repair_obtuse_once(surface, options, feature, result);
      report.n_flips += repaired[0];
      report.n_smoothing_moves += repaired[1];
    }
    if (report.n_chord_compensation_moves > 0 || report.n_volume_compensation_moves > 0) {
      stitch_detail::hold_detail_nodes(mesh, surface, result.vertex_node);
      stitch_detail::hold_fin_rim_nodes(mesh, result.vertex_node, stitch_detail::fin_rim_bound(surface, options));
    }
  }
  report.seconds_optimise = watch.seconds();

  // 3. Verification. The exact self-intersection check over the whole mesh runs once;
  // intersections the optimisation made are then repaired locally (repair_intersections)
  // and only the changed faces are checked again.
  watch.restart();
  report_progress(options.progress, "stitch: verify", 0.0);
  std::vector<FacePair> pairs;
  // The output's soup, kept for the report while the mesh stays as checked: with no pair
  // found, neither the repair nor settling changes the mesh.
  std::optional<TriangleSoup> soup;
  if (options.check_self_intersections) {
    soup = stitch_detail::mesh_soup(mesh);
    pairs = self_intersecting_pairs(*soup, options.n_threads);
    // The last whole-mesh count and its soup, while pairs are left: settling's changes are
    // counted again from them (recount_pairs checks again every face not as it was then:
    // those the repair and settling changed).
    std::optional<TriangleSoup> counted;
    std::vector<FacePair> counted_pairs;
    if (!pairs.empty()) {
      counted = std::move(soup);
      counted_pairs = pairs;
      soup.reset();
    }
    report_progress(options.progress, "stitch: verify", 0.5);
    if (optimise && !repair_intersections(assembled, mesh, pairs, report)) {
      // Local repair did not converge: the assembled mesh (whose own intersections are
      // the surface mesh's) is returned.
      mesh = std::move(assembled);
      result.face_patch = std::move(assembled_patch);
      report.optimisation_undone = true;
      counted = stitch_detail::mesh_soup(mesh);
      pairs = self_intersecting_pairs(*counted, options.n_threads);
      counted_pairs = pairs;
    }
    // The soup's indices are the mesh's (no deleted element), so the garbage maps apply.
    if (counted && (counted->points.size() != mesh.n_vertices() || counted->triangles.size() != mesh.n_faces())) counted.reset();
    // What remains was in the assembly (the surface mesh's own crossings). The pairs are
    // counted again when settling changed anything.
    const stitch_detail::GarbageMaps old = stitch_detail::settle_intersections(surface, options, feature, result, pairs, report);
    if (report.n_settled_nodes + report.n_settled_flips + report.n_settled_collapses > 0) {
      pairs = counted ? stitch_detail::recount_pairs(*counted, counted_pairs, stitch_detail::mesh_soup(mesh), old, options.n_threads)
                      : self_intersecting_pairs(stitch_detail::mesh_soup(mesh), options.n_threads);
    }
  }
  if (options.obtuse_split_rounds > 0 && pairs.empty() && mesh.n_faces() > 0) {
    split_obtuse_checked(surface, options, feature, result, report);
    if (report.n_obtuse_splits > 0) soup.reset();
  }
  if (options.angle_repair_rounds > 0 && pairs.empty() && mesh.n_faces() > 0) {
    const stitch_detail::AngleRepairResult angles = stitch_detail::repair_small_angles(surface, options, feature, result);
    report.n_angle_flips = angles.n_flips;
    report.n_angle_collapses = angles.n_collapses;
    report.n_obtuse_collapses = angles.n_obtuse_collapses;
    report.n_angle_moves = angles.n_moves + angles.n_pushes;
    report.n_angle_two_steps = angles.n_two_steps;
    report.n_angle_searches = angles.n_searches;
    report.n_angle_repairs_undone = angles.n_undone;
    if (angles.n_flips + angles.n_collapses + angles.n_obtuse_collapses + angles.n_moves > 0) soup.reset();
  }
  // Not on a label image's marching-cubes staircase (0/1 cells, occupancy scenes): its
  // truth is the smooth surface the fits follow, not the staircase (docs/stitch.md,
  // "Fidelity moves: where they apply").
  if (options.fidelity_distance_edges > 0.0 && input != nullptr && pairs.empty() && mesh.n_faces() > 0 &&
      !is_label_staircase()) {
    const stitch_detail::FidelityGate gate = stitch_detail::fidelity_gate(surface, *input, options);
    const stitch_detail::FidelityResult fidelity = stitch_detail::move_toward_input(
        *input, options, feature, surface.input_mean_edge, stitch_detail::fin_rim_bound(surface, options), result, true,
        input_index, &gate);
    report.n_fidelity_moves = fidelity.n_moved;
    report.n_fidelity_moves_undone = fidelity.n_undone;
    report.n_fidelity_splits = fidelity.n_split;
    if (fidelity.n_moved + fidelity.n_undone + fidelity.n_split > 0) soup.reset();
  }
  ReportOptions check;
  check.self_intersections = false;  // counted above
  check.n_threads = options.n_threads;
  if (options.progress) {
    check.progress = [&options](std::string_view, double fraction) {
      return options.progress("stitch: verify", 0.5 + 0.5 * fraction);
    };
  }
  if (!soup) soup = stitch_detail::mesh_soup(mesh);
  const std::vector<std::uint8_t> rim = stitch_detail::fin_rim_nodes(surface);
  // The mesh is final here: with two or more threads its component signatures and the
  // figures away from features are taken on a helper thread while this one makes the
  // report (they write other members of the report).
  std::future<std::vector<ComponentSignature>> output_components;
  if (options.n_threads >= 2) {
    output_components = std::async(std::launch::async, [&feature, &rim, &result, &report] {
      measure_away_from_features(feature, rim, result, report);
      return component_signatures(result.mesh);
    });
  }
  report.output = mesh_report(*soup, check);
  soup.reset();
  if (options.check_self_intersections) report.output.topology.n_self_intersecting_pairs = pairs.size();
  const TopologyReport& topo = report.output.topology;
  if (!topo.is_manifold) {
    report.errors.push_back("output is not 2-manifold (" + std::to_string(topo.n_nonmanifold_edges) + " edges, " +
                            std::to_string(topo.n_nonmanifold_vertices) + " vertices)");
  }
  if (!topo.is_consistently_oriented) {
    report.errors.push_back("output is not consistently oriented (" + std::to_string(topo.n_misoriented_edges) +
                            " misoriented edges)");
  }
  if (topo.n_degenerate_faces > 0) {
    report.errors.push_back("output has " + std::to_string(topo.n_degenerate_faces) + " degenerate triangles");
  }
  if (topo.n_duplicate_faces > 0) {
    report.errors.push_back("output has " + std::to_string(topo.n_duplicate_faces) + " duplicate triangles");
  }
  if (topo.n_self_intersecting_pairs && *topo.n_self_intersecting_pairs > 0) {
    report.errors.push_back("output has " + std::to_string(*topo.n_self_intersecting_pairs) +
                            " self-intersecting triangle pairs");
  }
  if (mesh.n_faces() == 0 && !surface.triangles.empty()) report.errors.push_back("output has no triangles");
  if (output_components.valid()) {
    report.output_components = output_components.get();
  } else {
    measure_away_from_features(feature, rim, result, report);
    report.output_components = component_signatures(mesh);
  }
  if (input != nullptr) {
    report.input_components = input_components.valid() ? input_components.get() : component_signatures(*input);
    compare_with_input(report);
  }
  report.seconds_verify = watch.seconds();
  report_progress(options.progress, "stitch: verify", 1.0);
  return result;
}

}  // namespace

TriangleSoup stitch_detail::mesh_soup(const TriMesh& mesh) {
  for (auto v : mesh.all_vertices()) {
    if (mesh.status(v).deleted()) return to_soup(mesh);
  }
  for (auto f : mesh.all_faces()) {
    if (mesh.status(f).deleted()) return to_soup(mesh);
  }
  TriangleSoup soup;
  soup.points.reserve(mesh.n_vertices());
  for (std::size_t v = 0; v < mesh.n_vertices(); ++v) soup.points.push_back(to_eigen(mesh.point(TriMesh::VertexHandle(static_cast<int>(v)))));
  soup.triangles.resize(mesh.n_faces());
  for (std::size_t f = 0; f < mesh.n_faces(); ++f) {
    const auto h0 = mesh.halfedge_handle(TriMesh::FaceHandle(static_cast<int>(f)));
    const auto h1 = mesh.next_halfedge_handle(h0);
    const auto h2 = mesh.next_halfedge_handle(h1);
    soup.triangles[f] = {static_cast<std::uint32_t>(mesh.to_vertex_handle(h0).idx()),
                         static_cast<std::uint32_t>(mesh.to_vertex_handle(h1).idx()),
                         static_cast<std::uint32_t>(mesh.to_vertex_handle(h2).idx())};
  }
  return soup;
}

std::vector<ComponentSignature> component_signatures(const TriMesh& mesh) {
  // Union-find over the vertices of every face (faces joined through shared vertices):
  // linear, no vertex-face circulation.
  DisjointSets sets(mesh.n_vertices());
  for (auto f : mesh.faces()) {
    const auto h = mesh.halfedge_handle(f);
    const auto a = static_cast<std::uint32_t>(mesh.to_vertex_handle(h).idx());
    for (auto v : mesh.fv_range(f)) sets.unite(a, static_cast<std::uint32_t>(v.idx()));
  }
  auto find = [&sets](int x) { return static_cast<int>(sets.find(static_cast<std::uint32_t>(x))); };
  std::vector<ComponentSignature> components;
  std::vector<int> component_of_root(mesh.n_vertices(), -1);
  std::vector<int> face_component(mesh.n_faces(), -1);
  for (auto f : mesh.faces()) {
    const int root = find(mesh.to_vertex_handle(mesh.halfedge_handle(f)).idx());
    int& id = component_of_root[static_cast<std::size_t>(root)];
    if (id < 0) {
      id = static_cast<int>(components.size());
      components.emplace_back();
    }
    face_component[static_cast<std::size_t>(f.idx())] = id;
    ++components[static_cast<std::size_t>(id)].n_faces;
  }
  for (auto v : mesh.vertices()) {
    const int id = component_of_root[static_cast<std::size_t>(find(v.idx()))];
    if (id < 0) continue;  // on no face
    ComponentSignature& c = components[static_cast<std::size_t>(id)];
    ++c.n_vertices;
    c.box.extend(to_eigen(mesh.point(v)));
  }
  for (auto e : mesh.edges()) {
    auto f = mesh.face_handle(mesh.halfedge_handle(e, 0));
    if (!f.is_valid()) f = mesh.face_handle(mesh.halfedge_handle(e, 1));
    if (f.is_valid()) ++components[static_cast<std::size_t>(face_component[static_cast<std::size_t>(f.idx())])].n_edges;
  }
  // Closedness: a component is closed when none of its halfedges is a boundary halfedge.
  for (auto& c : components) {
    c.euler_characteristic = static_cast<long>(c.n_vertices) - static_cast<long>(c.n_edges) + static_cast<long>(c.n_faces);
    c.is_closed = true;
  }
  for (auto h : mesh.halfedges()) {
    if (!mesh.is_boundary(h)) continue;
    const auto g = mesh.face_handle(mesh.opposite_halfedge_handle(h));
    if (g.is_valid()) components[static_cast<std::size_t>(face_component[static_cast<std::size_t>(g.idx())])].is_closed = false;
  }
  return components;
}

StitchResult stitch(const SurfaceMesh& surface, const StitchOptions& options) {
  return stitch_impl(surface, nullptr, options, nullptr);
}

StitchResult stitch(const SurfaceMesh& surface, const TriMesh& input, const StitchOptions& options) {
  return stitch_impl(surface, &input, options, nullptr);
}

StitchResult stitch_detail::stitch_with_input_index(const SurfaceMesh& surface, const TriMesh& input,
                                                    const quality_detail::IndexedSoup& input_index,
                                                    const StitchOptions& options) {
  // The index must be to_soup(input)'s: a cheap check of its sizes (a stale or other mesh's
  // index would give wrong distances silently).
  const auto n_vertices = static_cast<std::size_t>(std::distance(input.vertices().begin(), input.vertices().end()));
  const auto n_faces = static_cast<std::size_t>(std::distance(input.faces().begin(), input.faces().end()));
  const TriangleSoup& soup = input_index.soup();
  if (soup.points.size() != n_vertices || soup.triangles.size() != n_faces) {
    throw InvalidInput("stitch_with_input_index: the input index holds " + std::to_string(soup.points.size()) + " points and " +
                       std::to_string(soup.triangles.size()) + " triangles, the input mesh " + std::to_string(n_vertices) +
                       " vertices and " + std::to_string(n_faces) + " faces: build the index from to_soup(input)");
  }
  return stitch_impl(surface, &input, options, &input_index);
}

}  // namespace nurbsfront
