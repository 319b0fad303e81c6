// SPDX-License-Identifier: BSD-3-Clause
// Intersections already in the assembled surface mesh (two patches' triangles crossing on a
// thin sheet or a sharp fold): the nodes of the crossing triangles are moved onto their
// patches' own input faces, straight along the patch axes (an inner node keeps its place
// in its patch's plane), then edges of the triangles still crossing are flipped, then
// collapsed; each change is kept only if it leaves fewer crossing pairs (docs/stitch.md,
// "Crossings of the assembly").
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <OpenMesh/Core/Utils/Property.hh>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/stitch/stitch_internal.h"
#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront::stitch_detail {

namespace {

using Vec = Eigen::Vector3d;

// Rounds over the remaining pairs (a move can clear the way for another).
constexpr int kSettleRounds = 3;

}  // namespace

// OpenMesh 9's garbage_collection() (ArrayKernelT_impl.hh) step by step, inline here: its own
// copy, compiled in its library with its assertions on, looks up the status property per
// element through the property container and checks every handle it sets (on the liver it
// cost 0.26 G instructions for 3 swaps); these are a few array passes.
GarbageMaps collect_garbage(TriMesh& mesh) {
  using VH = TriMesh::VertexHandle;
  using HH = TriMesh::HalfedgeHandle;
  using EH = TriMesh::EdgeHandle;
  using FH = TriMesh::FaceHandle;
  const int n_vertices = static_cast<int>(mesh.n_vertices()), n_edges = static_cast<int>(mesh.n_edges());
  const int n_faces = static_cast<int>(mesh.n_faces());
  GarbageMaps maps;
  maps.vertex.resize(static_cast<std::size_t>(n_vertices));
  maps.face.resize(static_cast<std::size_t>(n_faces));
  std::vector<int> halfedge(2 * static_cast<std::size_t>(n_edges));
  std::iota(maps.vertex.begin(), maps.vertex.end(), 0);
  std::iota(maps.face.begin(), maps.face.end(), 0);
  std::iota(halfedge.begin(), halfedge.end(), 0);
  auto swap_props = [](auto begin, auto end, int i0, int i1) {
    for (auto it = begin; it != end; ++it) {
      if (*it != nullptr) (*it)->swap(static_cast<std::size_t>(i0), static_cast<std::size_t>(i1));
    }
  };
  // Kept count of one kind: deleted(i) says whether element i is deleted, swap(i0, i1) swaps two.
  auto compact = [](int n, const auto& deleted, const auto& swap) {
    if (n == 0) return 0;
    int i0 = 0, i1 = n - 1;
    for (;;) {
      while (!deleted(i0) && i0 < i1) ++i0;
      while (deleted(i1) && i0 < i1) --i1;
      if (i0 >= i1) break;
      swap(i0, i1);
    }
    return deleted(i0) ? i0 : i0 + 1;
  };
  const int kept_vertices = compact(
      n_vertices, [&](int i) { return mesh.status(VH(i)).deleted(); },
      [&](int i0, int i1) {
        std::swap(mesh.vertex(VH(i0)), mesh.vertex(VH(i1)));
        std::swap(maps.vertex[static_cast<std::size_t>(i0)], maps.vertex[static_cast<std::size_t>(i1)]);
        swap_props(mesh.vprops_begin(), mesh.vprops_end(), i0, i1);
      });
  const int kept_edges = compact(
      n_edges, [&](int i) { return mesh.status(EH(i)).deleted(); },
      [&](int i0, int i1) {
        std::swap(mesh.edge(EH(i0)), mesh.edge(EH(i1)));
        std::swap(halfedge[2 * static_cast<std::size_t>(i0)], halfedge[2 * static_cast<std::size_t>(i1)]);
        std::swap(halfedge[2 * static_cast<std::size_t>(i0) + 1], halfedge[2 * static_cast<std::size_t>(i1) + 1]);
        swap_props(mesh.eprops_begin(), mesh.eprops_end(), i0, i1);
        swap_props(mesh.hprops_begin(), mesh.hprops_end(), 2 * i0, 2 * i1);
        swap_props(mesh.hprops_begin(), mesh.hprops_end(), 2 * i0 + 1, 2 * i1 + 1);
      });
  const int kept_faces = compact(
      n_faces, [&](int i) { return mesh.status(FH(i)).deleted(); },
      [&](int i0, int i1) {
        std::swap(mesh.face(FH(i0)), mesh.face(FH(i1)));
        std::swap(maps.face[static_cast<std::size_t>(i0)], maps.face[static_cast<std::size_t>(i1)]);
        swap_props(mesh.fprops_begin(), mesh.fprops_end(), i0, i1);
      });
  // Cut: the items and every property vector (as garbage_collection's resizes).
  mesh.resize(static_cast<std::size_t>(kept_vertices), static_cast<std::size_t>(kept_edges), static_cast<std::size_t>(kept_faces));
  // The swaps are disjoint pairs, so each map sends an old index to its new one (and a new
  // one to its old one). The handles in garbage_collection's order: vertices' halfedges,
  // halfedges' vertices, then their next (which sets the next's previous) and faces, faces'
  // halfedges.
  auto new_halfedge = [&](HH h) { return HH(halfedge[static_cast<std::size_t>(h.idx())]); };
  for (int v = 0; v < kept_vertices; ++v) {
    const HH h = mesh.halfedge_handle(VH(v));
    if (h.is_valid()) mesh.set_halfedge_handle(VH(v), new_halfedge(h));
  }
  for (int h = 0; h < 2 * kept_edges; ++h) {
    mesh.set_vertex_handle(HH(h), VH(maps.vertex[static_cast<std::size_t>(mesh.to_vertex_handle(HH(h)).idx())]));
  }
  for (int h = 0; h < 2 * kept_edges; ++h) {
    mesh.set_next_halfedge_handle(HH(h), new_halfedge(mesh.next_halfedge_handle(HH(h))));
    const FH f = mesh.face_handle(HH(h));
    if (f.is_valid()) mesh.set_face_handle(HH(h), FH(maps.face[static_cast<std::size_t>(f.idx())]));
  }
  for (int f = 0; f < kept_faces; ++f) mesh.set_halfedge_handle(FH(f), new_halfedge(mesh.halfedge_handle(FH(f))));
  maps.vertex.resize(static_cast<std::size_t>(kept_vertices));
  maps.face.resize(static_cast<std::size_t>(kept_faces));
  return maps;
}

GarbageMaps collect_garbage(StitchResult& result) {
  GarbageMaps old = collect_garbage(result.mesh);
  std::vector<int> face_patch(old.face.size()), vertex_node(old.vertex.size());
  for (std::size_t f = 0; f < old.face.size(); ++f) face_patch[f] = result.face_patch[static_cast<std::size_t>(old.face[f])];
  for (std::size_t v = 0; v < old.vertex.size(); ++v) vertex_node[v] = result.vertex_node[static_cast<std::size_t>(old.vertex[v])];
  result.face_patch = std::move(face_patch);
  result.vertex_node = std::move(vertex_node);
  return old;
}

GarbageMaps settle_intersections(const SurfaceMesh& surface, const StitchOptions& options,
                                 const std::vector<std::uint8_t>& is_feature, StitchResult& result,
                                 std::vector<std::array<std::uint32_t, 2>>& pairs, StitchReport& report) {
  if (pairs.empty()) return {};
  TriMesh& mesh = result.mesh;
  // The patches' surfaces with no offset allowed from their input faces (the projection
  // then lands on the input face straight above or below, where there is one).
  std::vector<PatchSurface> on_input(surface.surfaces.size());
  std::vector<std::uint8_t> has_on_input(surface.surfaces.size(), 0);
  auto surface_on_input = [&](std::size_t p) -> const PatchSurface& {
    if (has_on_input[p] == 0) {
      on_input[p] = surface.surfaces[p];
      on_input[p].max_offset = 0.0;
      has_on_input[p] = 1;
    }
    return on_input[p];
  };
  // The mean of the projections of p onto the input faces of the patches around node v.
  std::vector<std::size_t> patches;
  const FinRimBound rim = fin_rim_bound(surface, options);
  auto target_of = [&](TriMesh::VertexHandle v, const Vec& p, Vec& target) {
    const auto g = static_cast<std::size_t>(result.vertex_node[static_cast<std::size_t>(v.idx())]);
    if (is_feature[g] != 0 || mesh.is_boundary(v)) return false;
    patches.clear();
    for (auto f : mesh.vf_range(v)) patches.push_back(static_cast<std::size_t>(result.face_patch[static_cast<std::size_t>(f.idx())]));
    std::sort(patches.begin(), patches.end());
    patches.erase(std::unique(patches.begin(), patches.end()), patches.end());
    target = Vec::Zero();
    for (const std::size_t patch : patches) {
      if (!surface.surfaces[patch].input_heights) return false;
      const PatchSurface& s = surface_on_input(patch);
      const Vec local = s.frame.to_local(p);
      double z = 0.0;
      // (A hand-made SurfaceMesh may have no patch reports: no detail fit then.)
      const bool detail = patch < surface.patches.size() && surface.patches[patch].detail_fit;
      if (!detail || s.input_heights->height(local.x(), local.y(), z)) {
        target += s.project(p);
        continue;
      }
      // A detail-fitted patch with no input face straight below: its fit is not held to the
      // input there (past a crease its extrapolation can stand an edge off it, and two such
      // patches' rows beside a valley cross). Along the axis to the mean height of the ring,
      // whose nodes are on the input faces or the border.
      double height = 0.0;
      double n = 0.0;
      for (auto w : mesh.vv_range(v)) {
        height += s.frame.to_local(to_eigen(mesh.point(w))).z();
        n += 1.0;
      }
      if (n == 0.0) return false;
      target += s.frame.to_world(Vec(local.x(), local.y(), height / n));
    }
    target /= static_cast<double>(patches.size());
    target = rim.clamp(static_cast<int>(g), target);
    return target.allFinite() && target != to_eigen(mesh.point(v));
  };

  // The checks run on the triangles near the crossings only (the whole mesh is checked
  // again by the caller): those whose box meets the box of a pair's triangles and their
  // neighbours, grown by twice the longest edge there. A change that would touch a triangle
  // outside is not made, nor one that takes a triangle's box out of every grown box (a
  // triangle inside a grown box can only cross triangles whose box meets it, all local,
  // and the triangles outside never change).
  const TriangleSoup whole = mesh_soup(mesh);
  const double diagonal = bounding_box(whole).diagonal();
  const double min_double_area = 2.0 * tolerance::kDegenerateAreaRelative * diagonal * diagonal;
  std::vector<BoundingBox> boxes;
  for (const auto& pair : pairs) {
    BoundingBox box;
    double longest = 0.0;
    for (const std::uint32_t f : pair) {
      for (auto v : mesh.fv_range(TriMesh::FaceHandle(static_cast<int>(f)))) {
        for (auto h : mesh.voh_range(v)) {
          const Vec a = to_eigen(mesh.point(mesh.from_vertex_handle(h))), b = to_eigen(mesh.point(mesh.to_vertex_handle(h)));
          box.extend(b);
          longest = std::max(longest, (b - a).norm());
        }
      }
    }
    box.min.array() -= 2.0 * longest;
    box.max.array() += 2.0 * longest;
    boxes.push_back(box);
  }
  TriangleSoup soup;
  std::vector<std::int64_t> local_point(whole.points.size(), -1);
  std::vector<std::int64_t> local_of(whole.triangles.size(), -1);
  std::vector<std::uint32_t> global_of;
  for (std::size_t f = 0; f < whole.triangles.size(); ++f) {
    BoundingBox box;
    for (const std::uint32_t v : whole.triangles[f]) box.extend(whole.points[v]);
    const bool near = std::any_of(boxes.begin(), boxes.end(), [&](const BoundingBox& b) {
      return (box.min.array() <= b.max.array()).all() && (b.min.array() <= box.max.array()).all();
    });
    if (!near) continue;
    local_of[f] = static_cast<std::int64_t>(soup.triangles.size());
    global_of.push_back(static_cast<std::uint32_t>(f));
    std::array<std::uint32_t, 3> t{};
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t v = whole.triangles[f][k];
      if (local_point[v] < 0) {
        local_point[v] = static_cast<std::int64_t>(soup.points.size());
        soup.points.push_back(whole.points[v]);
      }
      t[k] = static_cast<std::uint32_t>(local_point[v]);
    }
    soup.triangles.push_back(t);
  }
  auto point_of = [&](TriMesh::VertexHandle v) -> Vec& { return soup.points[static_cast<std::size_t>(local_point[static_cast<std::size_t>(v.idx())])]; };
  auto tri = [&](std::uint32_t f) -> std::array<std::uint32_t, 3>& { return soup.triangles[static_cast<std::size_t>(local_of[f])]; };
  auto is_local = [&](const std::vector<std::uint32_t>& faces) {
    return std::all_of(faces.begin(), faces.end(), [&](std::uint32_t f) { return local_of[f] >= 0; });
  };
  auto area_vector = [&](std::uint32_t f) {
    const auto& t = tri(f);
    return Vec((soup.points[t[1]] - soup.points[t[0]]).cross(soup.points[t[2]] - soup.points[t[0]]));
  };
  // Intersecting pairs (face indices of the mesh, sorted) of local faces with local faces.
  // intersecting_pairs_of() skips the faces degenerate by the local soup's diagonal, a
  // smaller tolerance than the whole mesh's: the pairs with a face degenerate by the whole
  // mesh's tolerance (min_double_area, as the caller's recount) are dropped too.
  auto pairs_of = [&](const std::vector<std::uint32_t>& faces) {
    std::vector<std::uint32_t> local;
    for (const std::uint32_t f : faces) local.push_back(static_cast<std::uint32_t>(local_of[f]));
    std::vector<std::array<std::uint32_t, 2>> out = intersecting_pairs_of(soup, local);
    std::erase_if(out, [&](const auto& p) {
      return area_vector(global_of[p[0]]).norm() <= min_double_area || area_vector(global_of[p[1]]).norm() <= min_double_area;
    });
    for (auto& p : out) {
      p = {global_of[p[0]], global_of[p[1]]};
      if (p[0] > p[1]) std::swap(p[0], p[1]);
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  auto inside_grown_box = [&](std::uint32_t f) {
    BoundingBox box;
    for (const std::uint32_t v : tri(f)) box.extend(soup.points[v]);
    return std::any_of(boxes.begin(), boxes.end(), [&](const BoundingBox& b) {
      return (b.min.array() <= box.min.array()).all() && (box.max.array() <= b.max.array()).all();
    });
  };
  // The soup's triangles of `faces` read again from the mesh (after flips).
  auto sync_faces = [&](const std::vector<std::uint32_t>& faces) {
    for (const std::uint32_t g : faces) {
      int k = 0;
      for (auto v : mesh.fv_range(TriMesh::FaceHandle(static_cast<int>(g)))) {
        tri(g)[static_cast<std::size_t>(k++)] = static_cast<std::uint32_t>(local_point[static_cast<std::size_t>(v.idx())]);
      }
    }
  };

  // Applies the moves when they leave fewer pairs among the triangles around the moved
  // nodes and none of these degenerates or turns too far; returns whether it did.
  using Moves = std::vector<std::pair<TriMesh::VertexHandle, Vec>>;
  std::vector<std::uint8_t> was_moved(mesh.n_vertices(), 0);  // nodes counted in n_settled_nodes
  auto try_moves = [&](const Moves& moves) {
    if (moves.empty()) return false;
    std::vector<std::uint32_t> touched;
    for (const auto& m : moves) {
      for (auto f : mesh.vf_range(m.first)) touched.push_back(static_cast<std::uint32_t>(f.idx()));
    }
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    if (!is_local(touched)) return false;
    std::vector<Vec> old_normal;
    for (const std::uint32_t f : touched) old_normal.push_back(area_vector(f));
    std::vector<Vec> old_point;
    for (const auto& m : moves) {
      old_point.push_back(point_of(m.first));
      point_of(m.first) = m.second;
    }
    bool ok = true;
    for (std::size_t i = 0; i < touched.size() && ok; ++i) {
      const Vec n = area_vector(touched[i]);
      ok = n.norm() > min_double_area && n.normalized().dot(old_normal[i].normalized()) >= options.min_normal_dot &&
           inside_grown_box(touched[i]);
    }
    std::vector<std::array<std::uint32_t, 2>> fresh;
    if (ok) fresh = pairs_of(touched);
    auto is_touched = [&](std::uint32_t f) { return std::binary_search(touched.begin(), touched.end(), f); };
    const auto n_before = static_cast<std::size_t>(std::count_if(pairs.begin(), pairs.end(), [&](const auto& p) {
      return is_touched(p[0]) || is_touched(p[1]);
    }));
    if (!ok || fresh.size() >= n_before) {
      for (std::size_t i = 0; i < moves.size(); ++i) point_of(moves[i].first) = old_point[i];
      return false;
    }
    for (const auto& m : moves) {
      mesh.set_point(m.first, to_openmesh(m.second));
      auto& moved = was_moved[static_cast<std::size_t>(m.first.idx())];
      if (moved == 0) ++report.n_settled_nodes;
      moved = 1;
    }
    replace_pairs(pairs, is_touched, fresh);
    return true;
  };

  // The segments of the feature curves (node pairs, smaller first): never flipped. Without
  // curves, every edge between two feature nodes counts as one.
  std::vector<std::pair<int, int>> feature_segments;
  const bool has_curves = surface.curve_nodes.size() == surface.curve_is_feature.size();
  if (has_curves) {
    for (std::size_t c = 0; c < surface.curve_nodes.size(); ++c) {
      const auto& nodes = surface.curve_nodes[c];
      if (surface.curve_is_feature[c] == 0 || nodes.size() < 2) continue;
      const bool is_closed = surface.node_kind[static_cast<std::size_t>(nodes.front())] == NodeKind::Border;
      for (std::size_t i = 0; i + (is_closed ? 0 : 1) < nodes.size(); ++i) {
        const int a = nodes[i], b = nodes[(i + 1) % nodes.size()];
        feature_segments.emplace_back(std::min(a, b), std::max(a, b));
      }
    }
    std::sort(feature_segments.begin(), feature_segments.end());
  }
  auto is_feature_segment = [&](std::size_t ga, std::size_t gb) {
    if (is_feature[ga] == 0 || is_feature[gb] == 0) return false;
    if (!has_curves) return true;
    const auto a = static_cast<int>(std::min(ga, gb)), b = static_cast<int>(std::max(ga, gb));
    return std::binary_search(feature_segments.begin(), feature_segments.end(), std::make_pair(a, b));
  };
  // Node gb may merge into node ga: gb is no feature node, or a node of a feature curve
  // (not a corner) and ga its neighbour along that curve.
  auto is_removable = [&](std::size_t gb, std::size_t ga) {
    if (is_feature[gb] == 0) return true;
    if (!has_curves || surface.node_kind[gb] != NodeKind::Border) return false;
    const int c = surface.node_owner[gb];
    const auto& nodes = surface.curve_nodes[static_cast<std::size_t>(c)];
    const auto at = std::find(nodes.begin(), nodes.end(), static_cast<int>(gb));
    return at != nodes.end() && is_next_on_curve(surface, c, static_cast<int>(at - nodes.begin()), static_cast<int>(ga));
  };
  // Collapses from(h) into to(h), which stays where it is, when the removed node may merge
  // (is_removable) and is not on the input's boundary, the collapse keeps the mesh a
  // manifold without duplicate faces (link condition), the removed node lies within one
  // input mean edge of the new triangles, none of these degenerates, folds over (normal
  // turned by 90 deg or more: the triangles of a crossing often stand on edge already) or
  // leaves the grown boxes, and the triangles around the removed node then take part in
  // fewer pairs.
  bool any_collapse = false;
  auto try_collapse = [&](TriMesh::HalfedgeHandle h) {
    const auto vb = mesh.from_vertex_handle(h);
    const auto va = mesh.to_vertex_handle(h);
    const auto gb = static_cast<std::size_t>(result.vertex_node[static_cast<std::size_t>(vb.idx())]);
    if (!is_removable(gb, static_cast<std::size_t>(result.vertex_node[static_cast<std::size_t>(va.idx())])) ||
        mesh.is_boundary(vb) || !mesh.is_collapse_ok(h) || leaves_duplicate_face(mesh, h)) {
      return false;
    }
    const auto gone0 = static_cast<std::uint32_t>(mesh.face_handle(h).idx());
    const auto gone1 = static_cast<std::uint32_t>(mesh.opposite_face_handle(h).idx());
    std::vector<std::uint32_t> around;
    for (auto f : mesh.vf_range(vb)) around.push_back(static_cast<std::uint32_t>(f.idx()));
    std::sort(around.begin(), around.end());
    if (!is_local(around)) return false;
    std::vector<std::uint32_t> kept;
    for (const std::uint32_t f : around) {
      if (f != gone0 && f != gone1) kept.push_back(f);
    }
    std::vector<Vec> old_normal;
    for (const std::uint32_t f : kept) old_normal.push_back(area_vector(f));
    std::vector<std::array<std::uint32_t, 3>> old_tri;
    for (const std::uint32_t f : around) old_tri.push_back(tri(f));
    const auto lb = static_cast<std::uint32_t>(local_point[static_cast<std::size_t>(vb.idx())]);
    const auto la = static_cast<std::uint32_t>(local_point[static_cast<std::size_t>(va.idx())]);
    for (const std::uint32_t f : kept) std::replace(tri(f).begin(), tri(f).end(), lb, la);
    tri(gone0) = {la, la, la};  // repeated corners: skipped by the pair checks
    tri(gone1) = {la, la, la};
    bool ok = true;
    double distance = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < kept.size() && ok; ++i) {
      const Vec n = area_vector(kept[i]);
      ok = n.norm() > min_double_area && n.normalized().dot(old_normal[i].normalized()) > 0.0 &&
           inside_grown_box(kept[i]);
      const auto& t = tri(kept[i]);
      const Vec& p = soup.points[lb];
      distance = std::min(distance, (quality_detail::closest_point_on_triangle(p, soup.points[t[0]], soup.points[t[1]],
                                                                               soup.points[t[2]]) - p).norm());
    }
    ok = ok && distance <= surface.input_mean_edge;
    std::vector<std::array<std::uint32_t, 2>> fresh;
    if (ok) fresh = pairs_of(kept);
    auto is_around = [&](std::uint32_t f) { return std::binary_search(around.begin(), around.end(), f); };
    const auto n_before = static_cast<std::size_t>(
        std::count_if(pairs.begin(), pairs.end(), [&](const auto& p) { return is_around(p[0]) || is_around(p[1]); }));
    if (!ok || fresh.size() >= n_before) {
      for (std::size_t i = 0; i < around.size(); ++i) tri(around[i]) = old_tri[i];
      return false;
    }
    mesh.collapse(h);
    sync_faces(kept);
    ++report.n_settled_collapses;
    any_collapse = true;
    replace_pairs(pairs, is_around, fresh);
    return true;
  };

  for (int round = 0; round < kSettleRounds && !pairs.empty(); ++round) {
    bool changed = false;
    const std::vector<std::array<std::uint32_t, 2>> todo = pairs;
    for (const auto& pair : todo) {
      // Already resolved by an earlier move of this round?
      if (!std::binary_search(pairs.begin(), pairs.end(), pair)) continue;
      Moves moves;
      for (const std::uint32_t f : pair) {
        for (auto v : mesh.fv_range(TriMesh::FaceHandle(static_cast<int>(f)))) {
          Vec target;
          if (std::none_of(moves.begin(), moves.end(), [&](const auto& m) { return m.first == v; }) &&
              target_of(v, to_eigen(mesh.point(v)), target)) {
            moves.emplace_back(v, target);
          }
        }
      }
      if (try_moves(moves)) {
        changed = true;
        continue;
      }
      // One node at a time to the centroid of its neighbours, onto the input faces.
      for (const auto& [v, unused] : moves) {
        Vec centroid = Vec::Zero();
        double n = 0.0;
        for (auto w : mesh.vv_range(v)) {
          centroid += to_eigen(mesh.point(w));
          n += 1.0;
        }
        Vec target;
        if (n > 0.0 && target_of(v, centroid / n, target) && try_moves({{v, target}})) {
          changed = true;
          break;
        }
      }
    }
    // Then edge flips of the triangles still crossing.
    const std::vector<std::array<std::uint32_t, 2>> left = pairs;
    for (const auto& pair : left) {
      if (!std::binary_search(pairs.begin(), pairs.end(), pair)) continue;
      std::vector<TriMesh::EdgeHandle> edges;
      for (const std::uint32_t f : pair) {
        for (auto h : mesh.fh_range(TriMesh::FaceHandle(static_cast<int>(f)))) edges.push_back(mesh.edge_handle(h));
      }
      for (const auto e : edges) {
        if (mesh.is_boundary(e) || !mesh.is_flip_ok(e)) continue;
        const auto h = mesh.halfedge_handle(e, 0);
        const auto ga = static_cast<std::size_t>(result.vertex_node[static_cast<std::size_t>(mesh.from_vertex_handle(h).idx())]);
        const auto gb = static_cast<std::size_t>(result.vertex_node[static_cast<std::size_t>(mesh.to_vertex_handle(h).idx())]);
        if (is_feature_segment(ga, gb)) continue;
        const auto f0 = static_cast<std::uint32_t>(mesh.face_handle(h).idx());
        const auto f1 = static_cast<std::uint32_t>(mesh.opposite_face_handle(h).idx());
        if (local_of[f0] < 0 || local_of[f1] < 0) continue;
        const Vec old_normal = area_vector(f0).normalized() + area_vector(f1).normalized();
        const std::vector<std::uint32_t> two{std::min(f0, f1), std::max(f0, f1)};
        auto is_two = [&](std::uint32_t g) { return g == f0 || g == f1; };
        const auto n_before = static_cast<std::size_t>(
            std::count_if(pairs.begin(), pairs.end(), [&](const auto& p) { return is_two(p[0]) || is_two(p[1]); }));
        auto sorted_ids = [&](std::uint32_t g) {
          std::array<std::uint32_t, 3> t = tri(g);
          std::sort(t.begin(), t.end());
          return t;
        };
        const std::array<std::uint32_t, 3> ids0 = sorted_ids(f0);
        mesh.flip(e);
        sync_faces(two);
        bool ok = true;
        for (const std::uint32_t g : two) {
          const Vec n = area_vector(g);
          ok = ok && n.norm() > min_double_area && n.dot(old_normal) > 0.0 && inside_grown_box(g);
        }
        std::vector<std::array<std::uint32_t, 2>> fresh;
        if (ok) fresh = pairs_of(two);
        if (!ok || fresh.size() >= n_before) {
          // Flipping back restores both triangles, possibly under each other's face index:
          // their pairs are taken again.
          mesh.flip(e);
          sync_faces(two);
          if (sorted_ids(f0) != ids0) std::swap(result.face_patch[f0], result.face_patch[f1]);
          fresh = pairs_of(two);
          ok = false;
        } else {
          ++report.n_settled_flips;
          changed = true;
          // Each new face takes, of the two faces' patches, the one more of its nodes have
          // another face of (on a tie, the patch of the face whose index it keeps).
          const std::array<int, 2> two_patches{result.face_patch[two[0]], result.face_patch[two[1]]};
          std::array<int, 2> new_patch = two_patches;
          for (std::size_t i = 0; i < 2 && two_patches[0] != two_patches[1]; ++i) {
            std::array<int, 2> votes{0, 0};
            for (auto v : mesh.fv_range(TriMesh::FaceHandle(static_cast<int>(two[i])))) {
              for (std::size_t k = 0; k < 2; ++k) {
                votes[k] += std::any_of(mesh.vf_begin(v), mesh.vf_end(v), [&](TriMesh::FaceHandle g) {
                  const auto gi = static_cast<std::uint32_t>(g.idx());
                  return !is_two(gi) && result.face_patch[gi] == two_patches[k];
                }) ? 1 : 0;
              }
            }
            if (votes[0] != votes[1]) new_patch[i] = two_patches[votes[0] > votes[1] ? 0 : 1];
          }
          for (std::size_t i = 0; i < 2; ++i) result.face_patch[two[i]] = new_patch[i];
        }
        replace_pairs(pairs, is_two, fresh);
        if (ok) break;
      }
    }
    // Then collapses of the edges of the triangles still crossing, shortest first.
    const std::vector<std::array<std::uint32_t, 2>> remaining = pairs;
    for (const auto& pair : remaining) {
      if (!std::binary_search(pairs.begin(), pairs.end(), pair)) continue;
      std::vector<std::pair<double, TriMesh::HalfedgeHandle>> candidates;
      for (const std::uint32_t f : pair) {
        for (auto h : mesh.fh_range(TriMesh::FaceHandle(static_cast<int>(f)))) {
          const double length = mesh.calc_edge_length(h);
          candidates.emplace_back(length, h);
          candidates.emplace_back(length, mesh.opposite_halfedge_handle(h));
        }
      }
      std::stable_sort(candidates.begin(), candidates.end(),
                       [](const auto& a, const auto& b) { return a.first < b.first; });
      for (const auto& candidate : candidates) {
        if (try_collapse(candidate.second)) {
          changed = true;
          break;
        }
      }
    }
    if (!changed) break;
  }
  if (any_collapse) {
    // The collapses left deleted elements: removed, with the per-face patch ids and the
    // per-vertex node ids carried along (the caller counts the pairs again).
    const GarbageMaps old = collect_garbage(result);
    pairs.clear();
    return old;
  }
  return {};
}

std::vector<std::array<std::uint32_t, 2>> recount_pairs(const TriangleSoup& before,
                                                        const std::vector<std::array<std::uint32_t, 2>>& before_pairs,
                                                        const TriangleSoup& after, const GarbageMaps& old,
                                                        unsigned n_threads) {
  const std::size_t n_before = before.triangles.size(), n_after = after.triangles.size();
  if ((!old.vertex.empty() && old.vertex.size() != after.points.size()) ||
      (!old.face.empty() && old.face.size() != n_after)) {
    throw InternalError("nurbsfront: recount_pairs: maps of " + std::to_string(old.vertex.size()) + " vertices and " +
                        std::to_string(old.face.size()) + " faces for a soup of " +
                        std::to_string(after.points.size()) + " and " + std::to_string(n_after));
  }
  if (bounding_box(before).diagonal() != bounding_box(after).diagonal()) return self_intersecting_pairs(after, n_threads);
  auto old_vertex = [&](std::uint32_t v) {
    return old.vertex.empty() ? static_cast<std::size_t>(v) : static_cast<std::size_t>(old.vertex[v]);
  };
  // Per triangle of `before`, its index in `after` when it is there unchanged (else -1).
  std::vector<std::int64_t> kept(n_before, -1);
  std::vector<std::uint32_t> changed;
  for (std::size_t f = 0; f < n_after; ++f) {
    const auto o = old.face.empty() ? f : static_cast<std::size_t>(old.face[f]);
    bool same = o < n_before;
    for (std::size_t k = 0; k < 3 && same; ++k) {
      const std::uint32_t v = after.triangles[f][k];
      const std::size_t ov = old_vertex(v);
      same = ov < before.points.size() && before.triangles[o][k] == ov && before.points[ov] == after.points[v];
    }
    if (same) {
      kept[o] = static_cast<std::int64_t>(f);
    } else {
      changed.push_back(static_cast<std::uint32_t>(f));
    }
  }
  std::vector<std::array<std::uint32_t, 2>> pairs;
  for (const auto& p : before_pairs) {
    if (p[0] >= n_before || p[1] >= n_before) {
      throw InternalError("nurbsfront: recount_pairs: pair of face " + std::to_string(std::max(p[0], p[1])) + " of " +
                          std::to_string(n_before));
    }
    const std::int64_t a = kept[p[0]], b = kept[p[1]];
    if (a >= 0 && b >= 0) pairs.push_back({static_cast<std::uint32_t>(std::min(a, b)), static_cast<std::uint32_t>(std::max(a, b))});
  }
  const std::vector<std::array<std::uint32_t, 2>> fresh = intersecting_pairs_of(after, changed, n_threads);
  pairs.insert(pairs.end(), fresh.begin(), fresh.end());
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

}  // namespace nurbsfront::stitch_detail
