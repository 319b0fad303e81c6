// SPDX-License-Identifier: BSD-3-Clause
// Slope-bounded patch segmentation: region growing on smoothed normals, merging of tiny
// patches, height-field check with splitting, then border extraction (borders.cpp).

#include "nurbsfront/segment/segment.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>
#include <string>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/core/team.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/segment/segment_internal.h"

namespace nurbsfront {

namespace {
// Faces per task of the parallel per-face loops.
constexpr std::size_t kFaceChunk = 8192;
// Patches per task of the per-patch loops (cones, axes, face-list sorts).
constexpr std::size_t kPatchChunk = 16;
}  // namespace

void SegmentOptions::validate() const {
  auto fail = [](const std::string& what) { throw InvalidInput("SegmentOptions: " + what); };
  if (!(max_slope_deg > 0.0 && max_slope_deg < 90.0))
    fail("max_slope_deg must be in (0, 90), got " + std::to_string(max_slope_deg));
  if (!(crease_angle_deg > 0.0 && crease_angle_deg <= 180.0))
    fail("crease_angle_deg must be in (0, 180], got " + std::to_string(crease_angle_deg));
  if (!(sharp_crease_angle_deg >= 0.0 && sharp_crease_angle_deg <= 180.0))
    fail("sharp_crease_angle_deg must be in [0, 180], got " + std::to_string(sharp_crease_angle_deg));
  if (normal_smoothing_rings < 0)
    fail("normal_smoothing_rings must be >= 0, got " + std::to_string(normal_smoothing_rings));
  if (threads < 0) fail("threads must be >= 0, got " + std::to_string(threads));
  border_smoothing.validate();
}

segment_detail::FaceGraph segment_detail::build_graph(const TriMesh& mesh, const unsigned workers) {
  FaceGraph graph;
  graph.mesh = &mesh;
  const auto n = static_cast<int>(mesh.n_faces());
  graph.vertices.resize(n);
  graph.neighbours.resize(n);
  graph.halfedges.resize(n);
  graph.crease.assign(n, 0);
  graph.points.reserve(mesh.n_vertices());
  for (const auto v : mesh.all_vertices()) graph.points.push_back(to_eigen(mesh.point(v)));
  segment_detail::parallel_chunks(n, workers, kFaceChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (auto f = static_cast<int>(begin); f < static_cast<int>(end); ++f) {
      auto h = mesh.halfedge_handle(mesh.face_handle(f));
      for (int i = 0; i < 3; ++i) {
        graph.vertices[f][i] = mesh.from_vertex_handle(h).idx();
        graph.halfedges[f][i] = h.idx();
        const auto g = mesh.face_handle(mesh.opposite_halfedge_handle(h));
        graph.neighbours[f][i] = g.is_valid() ? g.idx() : -1;
        h = mesh.next_halfedge_handle(h);
      }
    }
  });
  return graph;
}

namespace {

using segment_detail::FaceGraph;
using segment_detail::Scratch;

// Regions grow within this fraction of max_slope around their seed's axis, which leaves
// room for the merge step to re-centre the cones: growing to the full bound leaves slivers
// between full caps that fit no neighbour.
constexpr double kGrowthConeFraction = 0.75;
// Passes of clean_borders() (each moves every ear it finds; ears rarely chain further).
constexpr int kBorderCleanupPasses = 3;
// A local fold (a short extra outer loop, or two crossing border segments) is cut out
// with this many rings of faces around it.
constexpr int kCarveRings = 2;
// A "cliff" in a patch: two of its vertices closer than kCliffRunEdges mean input edges in
// its plane (the default fit lattice, PatchFitOptions::min_spacing_edges) and more than
// kCliffRiseEdges apart along its axis, at a rise over run above kCliffMinRiseOverRun
// (76 deg). No height field on that lattice holds both: the bunny's patch 0 wrapped around a
// near-vertical neighbour, its two arms 15 mean edges apart along the axis and 0.3 apart in
// the plane; its fit was 7.8 mean edges off (docs/segment.md, "Cliffs"). Such a patch is
// bisected like a folded one. Patches below kCliffMinFaces are not tested (a few steep
// faces may rise that much; the parts of a bisection get there in a few steps).
constexpr double kCliffRunEdges = 2.5;
constexpr double kCliffRiseEdges = 3.0;
constexpr double kCliffMinRiseOverRun = 4.0;
constexpr std::size_t kCliffMinFaces = 40;

// widen_patches(): at most this many rings of faces join a narrow patch.
constexpr int kWidenMaxRings = 8;

double radians(double degrees) { return degrees * std::numbers::pi / 180.0; }

struct FaceNormals {
  std::vector<Eigen::Vector3d> raw, smooth;  // unit, or zero when undefined
  std::vector<double> area;
  std::vector<std::uint8_t> degenerate, exception;
};

FaceNormals face_normals(const FaceGraph& graph, double diagonal, unsigned workers) {
  const int n = graph.n_faces();
  FaceNormals normals;
  normals.raw.assign(n, Eigen::Vector3d::Zero());
  normals.area.assign(n, 0.0);
  normals.degenerate.assign(n, 0);
  normals.exception.assign(n, 0);
  const double min_area = tolerance::kDegenerateAreaRelative * diagonal * diagonal;
  segment_detail::parallel_chunks(n, workers, kFaceChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (auto f = static_cast<int>(begin); f < static_cast<int>(end); ++f) {
      const auto& v = graph.vertices[f];
      const Eigen::Vector3d cross =
          (graph.points[v[1]] - graph.points[v[0]]).cross(graph.points[v[2]] - graph.points[v[0]]);
      const double area = 0.5 * cross.norm();
      if (!(area > min_area)) {
        normals.degenerate[f] = 1;
        continue;
      }
      normals.raw[f] = cross / (2.0 * area);
      normals.area[f] = area;
    }
  });
  return normals;
}

void mark_creases(FaceGraph& graph, const FaceNormals& normals, double cos_crease, unsigned workers) {
  const auto n = static_cast<std::size_t>(graph.n_faces());
  segment_detail::parallel_chunks(n, workers, kFaceChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (auto f = static_cast<int>(begin); f < static_cast<int>(end); ++f) {
      for (int i = 0; i < 3; ++i) {
        const int g = graph.neighbours[f][i];
        if (g < 0 || normals.degenerate[f] != 0 || normals.degenerate[g] != 0) continue;
        if (normals.raw[f].dot(normals.raw[g]) < cos_crease) graph.crease[f] |= static_cast<std::uint8_t>(1U << i);
      }
    }
  });
}

// Bevel creases (SegmentOptions::bevel_creases): smallest dihedral (deg) of a bend, the
// smallest angle between two face normals near both its ends, the smallest angle between
// the mean normals of its two sides, and the rings of faces those means take. Measured on
// marching cubes of the level-set DRAM cell at 128: box edges bend by 45 deg twice; the
// level-set sphere and the occupancy sphere and torus at 128 get no bevel crease (their
// terraces have steep face pairs within two rings, but side means at most ~35 deg apart).
constexpr double kBevelMinDihedralDeg = 30.0;
constexpr double kBevelMinSpreadDeg = 75.0;
constexpr double kBevelMinSideAngleDeg = 40.0;
constexpr int kBevelSideRings = 3;

// Marks the bends of bevelled sharp edges as creases (see the constants above); returns
// how many edges it marked that were not creases already.
std::size_t mark_bevel_creases(FaceGraph& graph, const FaceNormals& normals) {
  const int n = graph.n_faces();
  const TriMesh& mesh = *graph.mesh;
  const double cos_dihedral = std::cos(radians(kBevelMinDihedralDeg));
  const double cos_spread = std::cos(radians(kBevelMinSpreadDeg));
  const double cos_sides = std::cos(radians(kBevelMinSideAngleDeg));
  // Spread at a vertex: whether the faces around it and around its neighbours hold two
  // normals at least kBevelMinSpreadDeg apart (-1 unknown, 0 no, 1 yes; computed lazily).
  std::vector<std::int8_t> spread(graph.points.size(), -1);
  std::vector<int> near;
  auto has_spread = [&](int v) {
    if (spread[v] >= 0) return spread[v] == 1;
    near.clear();
    const TriMesh::VertexHandle vh(v);
    for (const auto f : mesh.vf_range(vh)) near.push_back(f.idx());
    for (const auto w : mesh.vv_range(vh))
      for (const auto f : mesh.vf_range(w)) near.push_back(f.idx());
    std::sort(near.begin(), near.end());
    near.erase(std::unique(near.begin(), near.end()), near.end());
    bool found = false;
    for (std::size_t i = 0; i < near.size() && !found; ++i) {
      if (normals.degenerate[near[i]] != 0) continue;
      for (std::size_t j = i + 1; j < near.size() && !found; ++j)
        found = normals.degenerate[near[j]] == 0 && normals.raw[near[i]].dot(normals.raw[near[j]]) <= cos_spread;
    }
    spread[v] = found ? 1 : 0;
    return found;
  };
  std::vector<int> stamp(n, -1), frontier, next;
  int epoch = 0;
  // Whether the mean normals of the faces within kBevelSideRings rings of faces f and g,
  // split by the plane through their shared edge (a, b) that bisects their normals, are at
  // least kBevelMinSideAngleDeg apart.
  auto sides_bend = [&](int f, int g, int a, int b) {
    const Eigen::Vector3d& pa = graph.points[a];
    const Eigen::Vector3d& pb = graph.points[b];
    const Eigen::Vector3d middle = 0.5 * (pa + pb);
    const Eigen::Vector3d across = (normals.raw[f] + normals.raw[g]).cross(pb - pa);
    ++epoch;
    frontier.assign({f, g});
    stamp[f] = stamp[g] = epoch;
    Eigen::Vector3d one = Eigen::Vector3d::Zero(), other = Eigen::Vector3d::Zero();
    for (int ring = 0; ring <= kBevelSideRings && !frontier.empty(); ++ring) {
      next.clear();
      for (const int h : frontier) {
        const auto& v = graph.vertices[h];
        const Eigen::Vector3d centroid = (graph.points[v[0]] + graph.points[v[1]] + graph.points[v[2]]) / 3.0;
        (across.dot(centroid - middle) > 0.0 ? one : other) += normals.area[h] * normals.raw[h];
        if (ring == kBevelSideRings) continue;
        for (const int q : graph.neighbours[h])
          if (q >= 0 && stamp[q] != epoch) {
            stamp[q] = epoch;
            next.push_back(q);
          }
      }
      std::swap(frontier, next);
    }
    const double length = one.norm() * other.norm();
    return length > 0.0 && one.dot(other) <= cos_sides * length;
  };
  std::size_t n_marked = 0;
  for (int f = 0; f < n; ++f) {
    if (normals.degenerate[f] != 0) continue;
    for (int i = 0; i < 3; ++i) {
      const int g = graph.neighbours[f][i];
      // Each edge once, from its lower face; crease edges are already borders.
      if (g < f || normals.degenerate[g] != 0 || graph.is_crease(f, i)) continue;
      if (normals.raw[f].dot(normals.raw[g]) > cos_dihedral) continue;
      const int a = graph.vertices[f][i];
      const int b = graph.vertices[f][(i + 1) % 3];
      if (!sides_bend(f, g, a, b) || !has_spread(a) || !has_spread(b)) continue;
      graph.crease[f] |= static_cast<std::uint8_t>(1U << i);
      for (int k = 0; k < 3; ++k)
        if (graph.neighbours[g][k] == f) graph.crease[g] |= static_cast<std::uint8_t>(1U << k);
      ++n_marked;
    }
  }
  return n_marked;
}

// Sharp crease chains (SegmentOptions::sharp_crease_angle_deg): a CAD mesh bends by a few
// degrees across its smooth parts and by much more on its creases, some of which are below
// the crease angle (fandisk: a straight chain of 20 edges at 78-80 deg between two planes,
// whose sides bend by 0.5 deg on average; the fit rounded it off by 0.0122, the whole
// Hausdorff distance). An edge whose dihedral d is at least the sharp crease angle and at
// most the crease angle passes when
// - every edge within two vertex rings of it with a dihedral below the sharp crease angle
//   bends by at most kSharpSideRatio x d,
// - every vertex within one ring of its ends has at most two edges bending by more than
//   kSharpSideRatio x d (up to the crease angle): one line of bends, not a crossing or a
//   rough patch,
// - every vertex within one ring of its ends with an edge bending by more than
//   kSharpChainRatio x d is reached from its ends along such edges inside that ring: no
//   parallel line of bends, as in the facets of a coarsely tessellated fillet or tube
//   (fandisk's rounded edges: 4 facets of 22.5 deg; knot1: tube facets of 20 deg), whose
//   smooth surface is the fit's to find.
// The passing edges joined at their vertices form chains; a chain of at least
// kSharpMinChainEdges edges becomes creases when its largest dihedral is at most
// kSharpMaxChainSpread times its smallest (one crease, not one that fades out: fandisk's
// 18-80 deg chain along the fan, where a shallow end of the crease cost obtuse triangles) and
// the edges below the sharp crease angle at its vertices bend on average by at most
// kSharpMaxSideShare of its mean dihedral (measured, scratch script on ../shared/data's CGAL
// meshes: fandisk 0.006, anchor_dense 0.000; rotor 0.078, turbine 0.068 and head 0.092, a
// coarse scan whose chain moved its Hausdorff distance 0.32 -> 0.46). No chain of the bunny,
// armadillo, elephant, femur, bones, blobby, knot1, couplingdown, cheese, pinion, rotor,
// turbine, head, three_peaks qualifies. Marching-cubes surfaces are not for this rule (their
// planar terraces qualify): remesh() turns it off on them.
constexpr double kSharpSideRatio = 0.6;
constexpr double kSharpChainRatio = 0.75;
constexpr std::size_t kSharpMinChainEdges = 8;
constexpr double kSharpMaxChainSpread = 1.5;
constexpr double kSharpMaxSideShare = 0.05;

// Marks the sharp crease edges (see the constants above) as creases; returns their input
// edge ids, ascending (none of them was a crease before, none bends by more than crease_deg).
std::vector<int> mark_sharp_creases(FaceGraph& graph, const FaceNormals& normals, double sharp_deg, double crease_deg,
                                    unsigned workers) {
  const TriMesh& mesh = *graph.mesh;
  const auto n_edges = static_cast<int>(mesh.n_edges());
  // Dihedral (deg) of every edge between two non-degenerate faces, -1 elsewhere.
  std::vector<double> dihedral(static_cast<std::size_t>(n_edges), -1.0);
  segment_detail::parallel_chunks(static_cast<std::size_t>(n_edges), workers, kFaceChunk,
                                  [&](std::size_t begin, std::size_t end, unsigned) {
    for (auto e = static_cast<int>(begin); e < static_cast<int>(end); ++e) {
      const auto h = mesh.halfedge_handle(TriMesh::EdgeHandle(e), 0);
      const TriMesh::FaceHandle f = mesh.face_handle(h), g = mesh.opposite_face_handle(h);
      if (!f.is_valid() || !g.is_valid() || normals.degenerate[f.idx()] != 0 || normals.degenerate[g.idx()] != 0)
        continue;
      dihedral[e] = std::acos(std::clamp(normals.raw[f.idx()].dot(normals.raw[g.idx()]), -1.0, 1.0)) * 180.0 /
                    std::numbers::pi;
    }
  });
  std::vector<int> candidates;
  for (int e = 0; e < n_edges; ++e)
    if (dihedral[e] >= sharp_deg && dihedral[e] <= crease_deg) candidates.push_back(e);
  std::vector<std::uint8_t> passes(candidates.size(), 0);
  segment_detail::parallel_chunks(candidates.size(), workers, 256, [&](std::size_t begin, std::size_t end, unsigned) {
    std::vector<int> ring, ring2, reached;
    for (std::size_t k = begin; k < end; ++k) {
      const int e = candidates[k];
      const double d = dihedral[e];
      const auto h = mesh.halfedge_handle(TriMesh::EdgeHandle(e), 0);
      const auto a = mesh.from_vertex_handle(h), b = mesh.to_vertex_handle(h);
      // The ends first (the same test as for the ring below, cheap): most candidates of a
      // rough mesh fail here.
      auto bent_at = [&](TriMesh::VertexHandle v) {
        int n = 0;
        for (const auto q : mesh.voh_range(v)) {
          const double x = dihedral[static_cast<std::size_t>(mesh.edge_handle(q).idx())];
          if (x > kSharpSideRatio * d && x <= crease_deg) ++n;
        }
        return n;
      };
      if (bent_at(a) > 2 || bent_at(b) > 2) continue;
      // One ring: the vertices of the faces around both ends; two rings: around those.
      ring.clear();
      for (const auto end_vertex : {a, b}) {
        ring.push_back(end_vertex.idx());
        for (const auto w : mesh.vv_range(end_vertex)) ring.push_back(w.idx());
      }
      std::sort(ring.begin(), ring.end());
      ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
      auto in_ring = [&](int v) { return std::binary_search(ring.begin(), ring.end(), v); };
      bool ok = true;
      // Smooth sides: the edges at the one-ring vertices reach two rings out.
      for (std::size_t i = 0; i < ring.size() && ok; ++i)
        for (const auto vh : mesh.voh_range(TriMesh::VertexHandle(ring[i]))) {
          const double x = dihedral[mesh.edge_handle(vh).idx()];
          if (x >= 0.0 && x < sharp_deg && x > kSharpSideRatio * d) {
            ok = false;
            break;
          }
        }
      // One line of bends, and no parallel line.
      reached.clear();
      for (std::size_t i = 0; i < ring.size() && ok; ++i) {
        int n_bent = 0;
        for (const auto vh : mesh.voh_range(TriMesh::VertexHandle(ring[i]))) {
          const double x = dihedral[mesh.edge_handle(vh).idx()];
          if (x > kSharpSideRatio * d && x <= crease_deg) ++n_bent;
        }
        ok = n_bent <= 2;
      }
      if (ok) {
        // Vertices reached from a along edges bending by more than kSharpChainRatio x d
        // inside the ring; every ring vertex with such an edge must be among them.
        auto chain_edge = [&](TriMesh::HalfedgeHandle q) {
          const double x = dihedral[mesh.edge_handle(q).idx()];
          return x > kSharpChainRatio * d && x <= crease_deg;
        };
        ring2.assign(1, a.idx());
        reached.assign(1, a.idx());
        while (!ring2.empty()) {
          const int v = ring2.back();
          ring2.pop_back();
          for (const auto q : mesh.voh_range(TriMesh::VertexHandle(v))) {
            const int w = mesh.to_vertex_handle(q).idx();
            if (!chain_edge(q) || !in_ring(w) || std::find(reached.begin(), reached.end(), w) != reached.end()) continue;
            reached.push_back(w);
            ring2.push_back(w);
          }
        }
        for (std::size_t i = 0; i < ring.size() && ok; ++i) {
          if (std::find(reached.begin(), reached.end(), ring[i]) != reached.end()) continue;
          for (const auto q : mesh.voh_range(TriMesh::VertexHandle(ring[i])))
            if (chain_edge(q)) {
              ok = false;
              break;
            }
        }
      }
      passes[k] = ok ? 1 : 0;
    }
  });
  // Chains: the passing edges joined at shared vertices (breadth first, in edge order).
  std::vector<std::uint8_t> passing(static_cast<std::size_t>(n_edges), 0), seen(static_cast<std::size_t>(n_edges), 0);
  for (std::size_t k = 0; k < candidates.size(); ++k)
    if (passes[k] != 0) passing[static_cast<std::size_t>(candidates[k])] = 1;
  std::vector<int> queue, members, sharp;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const int first = candidates[k];
    if (passes[k] == 0 || seen[static_cast<std::size_t>(first)] != 0) continue;
    seen[static_cast<std::size_t>(first)] = 1;
    queue.assign(1, first);
    members.clear();
    while (!queue.empty()) {
      const int e = queue.back();
      queue.pop_back();
      members.push_back(e);
      const auto h = mesh.halfedge_handle(TriMesh::EdgeHandle(e), 0);
      for (const auto v : {mesh.from_vertex_handle(h), mesh.to_vertex_handle(h)})
        for (const auto q : mesh.voh_range(v)) {
          const auto next = static_cast<std::size_t>(mesh.edge_handle(q).idx());
          if (seen[next] != 0 || passing[next] == 0) continue;
          seen[next] = 1;
          queue.push_back(static_cast<int>(next));
        }
    }
    if (members.size() < kSharpMinChainEdges) continue;
    // One angle along the chain, and smooth sides on average.
    double lowest = 180.0, highest = 0.0, sum = 0.0, side_sum = 0.0;
    std::size_t n_side = 0;
    for (const int e : members) {
      const double d = dihedral[static_cast<std::size_t>(e)];
      lowest = std::min(lowest, d);
      highest = std::max(highest, d);
      sum += d;
      const auto h = mesh.halfedge_handle(TriMesh::EdgeHandle(e), 0);
      for (const auto v : {mesh.from_vertex_handle(h), mesh.to_vertex_handle(h)})
        for (const auto q : mesh.voh_range(v)) {
          const double x = dihedral[static_cast<std::size_t>(mesh.edge_handle(q).idx())];
          if (x >= 0.0 && x < sharp_deg) {
            side_sum += x;
            ++n_side;
          }
        }
    }
    const double mean = sum / static_cast<double>(members.size());
    const double side_mean = n_side > 0 ? side_sum / static_cast<double>(n_side) : 0.0;
    if (highest <= kSharpMaxChainSpread * lowest && side_mean <= kSharpMaxSideShare * mean)
      sharp.insert(sharp.end(), members.begin(), members.end());
  }
  std::sort(sharp.begin(), sharp.end());
  for (int f = 0; f < graph.n_faces(); ++f)
    for (int i = 0; i < 3; ++i)
      if (std::binary_search(sharp.begin(), sharp.end(), graph.halfedges[f][i] >> 1))
        graph.crease[f] |= static_cast<std::uint8_t>(1U << i);
  return sharp;
}

// Jacobi iterations of area-weighted averaging over edge-adjacent faces, not across creases.
std::vector<Eigen::Vector3d> smooth_normals(const FaceGraph& graph, const FaceNormals& normals, int rings,
                                            unsigned workers) {
  const int n = graph.n_faces();
  std::vector<Eigen::Vector3d> current = normals.raw, next(n);
  for (int it = 0; it < rings; ++it) {
    segment_detail::parallel_chunks(n, workers, kFaceChunk, [&](std::size_t begin, std::size_t end, unsigned) {
      for (auto f = static_cast<int>(begin); f < static_cast<int>(end); ++f) {
        Eigen::Vector3d sum = normals.area[f] * current[f];
        for (int i = 0; i < 3; ++i) {
          const int g = graph.neighbours[f][i];
          if (g >= 0 && !graph.is_crease(f, i)) sum += normals.area[g] * current[g];
        }
        const double length = sum.norm();
        next[f] = length > 0.0 ? Eigen::Vector3d(sum / length) : current[f];
      }
    });
    std::swap(current, next);
  }
  return current;
}

// Everything the growing, merging and splitting steps share.
struct Grouping {
  const FaceGraph& graph;
  const FaceNormals& normals;
  double cos_slope;
  double max_slope;  // rad
  double cos_grow;   // the narrower cone used while growing

  // The face's normals meet the bounds for `axis` (smoothed normal within the cone of
  // cosine cos_limit).
  [[nodiscard]] bool fits(int f, const Eigen::Vector3d& axis, double cos_limit) const {
    if (normals.degenerate[f] != 0) return true;
    if (normals.raw[f].dot(axis) < kSegmentMinRawNormalDot) return false;
    return normals.exception[f] != 0 || normals.smooth[f].dot(axis) >= cos_limit;
  }
  [[nodiscard]] bool fits(int f, const Eigen::Vector3d& axis) const { return fits(f, axis, cos_slope); }

  // The axis a patch grown from `seed` uses: its smoothed normal, tilted towards its raw
  // normal just enough that both bounds hold.
  [[nodiscard]] Eigen::Vector3d seed_axis(int seed) const {
    const Eigen::Vector3d& smooth = normals.smooth[seed];
    if (normals.degenerate[seed] != 0) return smooth.squaredNorm() > 0.0 ? smooth : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d& raw = normals.raw[seed];
    if (normals.exception[seed] != 0) return raw;
    if (raw.dot(smooth) >= kSegmentMinRawNormalDot) return smooth;
    const double theta = std::acos(std::clamp(raw.dot(smooth), -1.0, 1.0));
    const double lowest = theta - std::acos(kSegmentMinRawNormalDot);
    const double phi = 0.5 * (lowest + max_slope);
    const Eigen::Vector3d tangent = (raw - raw.dot(smooth) * smooth).normalized();
    return (std::cos(phi) * smooth + std::sin(phi) * tangent).normalized();
  }
};

struct Patches {
  std::vector<int> face_patch;
  std::vector<std::vector<int>> faces;
  std::vector<Eigen::Vector3d> axes;
};

Patches grow_regions(const Grouping& grouping) {
  const FaceGraph& graph = grouping.graph;
  const int n = graph.n_faces();
  Patches patches;
  patches.face_patch.assign(n, -1);
  for (int seed = 0; seed < n; ++seed) {
    if (patches.face_patch[seed] != -1) continue;
    const int p = static_cast<int>(patches.axes.size());
    const Eigen::Vector3d axis = grouping.seed_axis(seed);
    NURBSFRONT_ASSERT(grouping.fits(seed, axis));
    patches.axes.push_back(axis);
    std::vector<int> region{seed};
    patches.face_patch[seed] = p;
    for (std::size_t head = 0; head < region.size(); ++head) {
      const int f = region[head];
      for (int i = 0; i < 3; ++i) {
        const int g = graph.neighbours[f][i];
        if (g < 0 || graph.is_crease(f, i) || patches.face_patch[g] != -1 ||
            !grouping.fits(g, axis, grouping.cos_grow))
          continue;
        bool creased = false;  // a crease must never end up inside a patch
        for (int k = 0; k < 3 && !creased; ++k) {
          const int h = graph.neighbours[g][k];
          creased = h >= 0 && graph.is_crease(g, k) && patches.face_patch[h] == p;
        }
        if (creased) continue;
        patches.face_patch[g] = p;
        region.push_back(g);
      }
    }
    patches.faces.push_back(std::move(region));
  }
  return patches;
}

// A cone of unit directions: every direction is within `radius` (rad) of `axis`.
struct Cone {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double radius = -1.0;  // < 0: empty
};

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.dot(b), -1.0, 1.0));
}

// The smallest cone containing two cones (exact for cones, O(1)).
Cone cone_union(const Cone& a, const Cone& b) {
  if (a.radius < 0) return b;
  if (b.radius < 0) return a;
  const double theta = angle_between(a.axis, b.axis);
  if (theta + b.radius <= a.radius) return a;
  if (theta + a.radius <= b.radius) return b;
  const double radius = 0.5 * (a.radius + b.radius + theta);
  const Eigen::Vector3d towards = b.axis - std::cos(theta) * a.axis;
  if (radius >= std::numbers::pi || !(towards.norm() > 0.0)) return {a.axis, std::numbers::pi};
  const double turn = radius - a.radius;
  return {(std::cos(turn) * a.axis + std::sin(turn) * towards.normalized()).normalized(), radius};
}

// Bounding cones of a patch's smoothed normals (exceptions left out) and raw normals.
struct PatchCones {
  Cone smooth, raw;
};

// The radius is the largest angle to the axis. acos is evaluated only for the faces whose
// dot product is within tolerance::kConeDotSlack of the smallest: acos decreases with a
// slope of at least 1, so any other face's angle is smaller by far more than acos' rounding
// error (the same radius as acos of every face, without relying on acos' monotone rounding).
PatchCones patch_cones(const Grouping& grouping, const std::vector<int>& faces, const Eigen::Vector3d& axis) {
  PatchCones cones{{axis, -1.0}, {axis, -1.0}};
  const FaceNormals& normals = grouping.normals;
  double raw_dot = std::numeric_limits<double>::infinity(), smooth_dot = raw_dot;
  for (int f : faces) {
    if (normals.degenerate[f] != 0) continue;
    raw_dot = std::min(raw_dot, normals.raw[f].dot(axis));
    if (normals.exception[f] == 0) smooth_dot = std::min(smooth_dot, normals.smooth[f].dot(axis));
  }
  for (int f : faces) {
    if (normals.degenerate[f] != 0) continue;
    if (normals.raw[f].dot(axis) <= raw_dot + tolerance::kConeDotSlack)
      cones.raw.radius = std::max(cones.raw.radius, angle_between(normals.raw[f], axis));
    if (normals.exception[f] == 0 && normals.smooth[f].dot(axis) <= smooth_dot + tolerance::kConeDotSlack)
      cones.smooth.radius = std::max(cones.smooth.radius, angle_between(normals.smooth[f], axis));
  }
  return cones;
}

// Hands the faces of patch p one by one to edge-adjacent patches whose axis bounds them
// (each joins through an edge, so the receivers stay connected; never across or beside a
// crease to the receiver). All or nothing: returns the moves (face, receiver), or nothing
// (p restored) if a face is left.
std::vector<std::pair<int, int>> dissolve(const Grouping& grouping, int p, Patches& patches) {
  const FaceGraph& graph = grouping.graph;
  std::vector<std::pair<int, int>> moved;  // (face, receiving patch)
  bool progress = true;
  while (progress && moved.size() < patches.faces[p].size()) {
    progress = false;
    for (int f : patches.faces[p]) {
      if (patches.face_patch[f] != p) continue;
      for (int i = 0; i < 3; ++i) {
        const int g = graph.neighbours[f][i];
        if (g < 0 || graph.is_crease(f, i)) continue;
        const int q = patches.face_patch[g];
        if (q == p || !grouping.fits(f, patches.axes[q])) continue;
        bool creased = false;
        for (int k = 0; k < 3 && !creased; ++k) {
          const int h = graph.neighbours[f][k];
          creased = h >= 0 && graph.is_crease(f, k) && patches.face_patch[h] == q;
        }
        if (creased) continue;
        patches.face_patch[f] = q;
        moved.emplace_back(f, q);
        progress = true;
        break;
      }
    }
  }
  if (moved.size() < patches.faces[p].size()) {
    for (const auto& [f, q] : moved) patches.face_patch[f] = p;
    return {};
  }
  for (const auto& [f, q] : moved) patches.faces[q].push_back(f);
  patches.faces[p].clear();
  return moved;
}

// Merges each patch, smallest first, into an edge-adjacent neighbour (longest shared
// border first, then the smaller id) when one axis bounds both (union of bounding cones).
// A patch below min_faces may also join a neighbour whose current axis bounds its faces,
// or be dissolved into several neighbours. Never across a crease.
// With `scratch` set (after the fold splits), only small patches are merged, without
// dissolving, and a merge is kept only if the merged patch passes the projection check.
// The first cones (each a function of its patch alone) are computed on `workers` threads.
void merge_patches(const Grouping& grouping, std::size_t min_faces, Patches& patches, Scratch* scratch,
                   unsigned workers) {
  const FaceGraph& graph = grouping.graph;
  const auto n_patches = static_cast<int>(patches.faces.size());
  std::vector<int> order(n_patches);
  for (int p = 0; p < n_patches; ++p) order[p] = p;
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return patches.faces[a].size() < patches.faces[b].size(); });
  struct Neighbour {
    int patch = -1, shared = 0;
    bool blocked = false;
  };
  // Merges refused by the projection check, as (neighbour, own size, neighbour's size): a
  // patch's faces change only by merges, which change its size, so an attempt with both
  // sizes unchanged would be refused again and is skipped (the check costs the size of
  // the merged patch).
  std::vector<std::vector<std::array<std::size_t, 3>>> refused(scratch != nullptr ? n_patches : 0);
  // Border halfedges per patch (scratch mode), valid while the patch keeps the size they
  // were taken at: the merged patch's border comes from its two parts' borders, so a merge
  // check costs the borders, not the faces.
  std::vector<std::vector<OpenMesh::HalfedgeHandle>> border(scratch != nullptr ? n_patches : 0);
  std::vector<std::size_t> border_size(border.size(), 0);
  auto border_of = [&](int p) -> const std::vector<OpenMesh::HalfedgeHandle>& {
    if (border_size[p] != patches.faces[p].size() || patches.faces[p].empty()) {
      border[p] = segment_detail::patch_border(graph, patches.faces[p], patches.face_patch);
      border_size[p] = patches.faces[p].size();
    }
    return border[p];
  };
  std::vector<OpenMesh::HalfedgeHandle> merged_border;
  std::vector<PatchCones> cones(n_patches);
  segment_detail::parallel_chunks(static_cast<std::size_t>(n_patches), workers, kPatchChunk,
                                  [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t p = begin; p < end; ++p) cones[p] = patch_cones(grouping, patches.faces[p], patches.axes[p]);
  });
  const double max_smooth = grouping.max_slope - tolerance::kAngleMarginRad;
  const double max_raw = std::acos(kSegmentMinRawNormalDot) - tolerance::kAngleMarginRad;
  // A patch's attempt depends only on its own faces and cones and on its neighbours (which
  // faces around it are theirs, their axes and cones). Every change of a patch bumps its
  // version; a face around p changes hands only when its patch changes. An attempt that
  // merged nothing is not repeated while p and the neighbours it saw keep their versions.
  std::vector<std::uint32_t> version(n_patches, 0);
  struct Attempt {
    std::uint32_t version = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::pair<int, std::uint32_t>> neighbours;  // (patch, version) seen
  };
  std::vector<Attempt> failed(n_patches);
  bool changed = true;
  while (changed) {
    changed = false;
    for (int p : order) {
      const std::size_t size = patches.faces[p].size();
      if (size == 0) continue;
      const bool is_small = size < min_faces;
      if (scratch != nullptr && !is_small) continue;
      if (failed[p].version == version[p] &&
          std::all_of(failed[p].neighbours.begin(), failed[p].neighbours.end(),
                      [&](const auto& seen) { return version[seen.first] == seen.second; }))
        continue;
      std::vector<Neighbour> neighbours;
      for (int f : patches.faces[p]) {
        for (int i = 0; i < 3; ++i) {
          const int g = graph.neighbours[f][i];
          if (g < 0 || patches.face_patch[g] == p) continue;
          const int q = patches.face_patch[g];
          auto it = std::find_if(neighbours.begin(), neighbours.end(), [q](const Neighbour& x) { return x.patch == q; });
          if (it == neighbours.end()) it = neighbours.insert(neighbours.end(), Neighbour{q, 0, false});
          ++it->shared;
          it->blocked = it->blocked || graph.is_crease(f, i);
        }
      }
      std::sort(neighbours.begin(), neighbours.end(), [](const Neighbour& a, const Neighbour& b) {
        return a.shared != b.shared ? a.shared > b.shared : a.patch < b.patch;
      });
      bool merged = false;
      for (const Neighbour& q : neighbours) {
        if (q.blocked) continue;
        const std::array<std::size_t, 3> attempt{static_cast<std::size_t>(q.patch), size, patches.faces[q.patch].size()};
        if (scratch != nullptr && std::find(refused[p].begin(), refused[p].end(), attempt) != refused[p].end()) continue;
        const PatchCones old_cones = cones[q.patch];
        const Eigen::Vector3d old_axis = patches.axes[q.patch];
        // First the union of the bounding cones: its axis may bound both patches.
        const Cone smooth = cone_union(cones[q.patch].smooth, cones[p].smooth);
        const Cone raw = cone_union(cones[q.patch].raw, cones[p].raw);
        if (smooth.radius <= max_smooth && angle_between(smooth.axis, raw.axis) + raw.radius <= max_raw &&
            smooth.radius >= 0) {
          patches.axes[q.patch] = smooth.axis;
          cones[q.patch].smooth = smooth;
          cones[q.patch].raw = {smooth.axis, angle_between(smooth.axis, raw.axis) + raw.radius};
        } else {
          if (!is_small) continue;
          const Eigen::Vector3d& axis = patches.axes[q.patch];
          const bool ok = std::all_of(patches.faces[p].begin(), patches.faces[p].end(),
                                      [&](int f) { return grouping.fits(f, axis); });
          if (!ok) continue;
          cones[q.patch].smooth = cone_union(cones[q.patch].smooth, cones[p].smooth);
          cones[q.patch].raw = cone_union(cones[q.patch].raw, cones[p].raw);
        }
        if (scratch != nullptr) {
          // Both borders before the faces change hands (face_patch decides what is border).
          (void)border_of(q.patch);
          (void)border_of(p);
        }
        for (int f : patches.faces[p]) patches.face_patch[f] = q.patch;
        auto& target = patches.faces[q.patch];
        target.insert(target.end(), patches.faces[p].begin(), patches.faces[p].end());
        // Every patch passed the projection check with its current axis (split_folds, then
        // every kept merge): where the axis stays, q's remaining border segments are known
        // not to cross each other.
        std::size_t n_known = 0;
        if (scratch != nullptr) {
          merged_border.clear();
          for (const auto* part : {&border[q.patch], &border[p]}) {
            for (const auto h : *part) {
              const auto g = graph.mesh->opposite_face_handle(h);
              if (!g.is_valid() || patches.face_patch[g.idx()] != q.patch) merged_border.push_back(h);
            }
            if (part == &border[q.patch] && patches.axes[q.patch] == old_axis) n_known = merged_border.size();
          }
        }
        if (scratch != nullptr && !segment_detail::check_projection(graph, merged_border, patches.face_patch,
                                                                    patches.axes[q.patch], *scratch, n_known)
                                       .is_simple) {
          target.resize(target.size() - patches.faces[p].size());
          for (int f : patches.faces[p]) patches.face_patch[f] = p;
          cones[q.patch] = old_cones;
          patches.axes[q.patch] = old_axis;
          refused[p].push_back(attempt);
          continue;
        }
        if (scratch != nullptr) {
          border[q.patch].swap(merged_border);
          border_size[q.patch] = target.size();
        }
        patches.faces[p].clear();
        ++version[p];
        ++version[q.patch];
        merged = true;
        break;
      }
      if (!merged && is_small && scratch == nullptr) {
        for (const auto& [f, q] : dissolve(grouping, p, patches)) {
          merged = true;
          ++version[q];
          if (grouping.normals.degenerate[f] != 0) continue;
          cones[q].raw = cone_union(cones[q].raw, {grouping.normals.raw[f], 0.0});
          if (grouping.normals.exception[f] == 0)
            cones[q].smooth = cone_union(cones[q].smooth, {grouping.normals.smooth[f], 0.0});
        }
        if (merged) ++version[p];
      }
      if (!merged) {
        failed[p].version = version[p];
        failed[p].neighbours.clear();
        for (const Neighbour& q : neighbours) failed[p].neighbours.emplace_back(q.patch, version[q.patch]);
      }
      changed = changed || merged;
    }
  }
}

// Moves border "ears" (a face with two or more edges on one neighbouring patch) into that
// neighbour when its axis bounds the face and no crease is in the way: smoother borders,
// fewer vertices where a patch touches itself. The face is a leaf of its own patch, so
// both patches stay connected.
void clean_borders(const Grouping& grouping, Patches& patches) {
  const FaceGraph& graph = grouping.graph;
  std::vector<std::size_t> size(patches.faces.size());
  for (std::size_t p = 0; p < size.size(); ++p) size[p] = patches.faces[p].size();
  bool changed = false;
  for (int pass = 0; pass < kBorderCleanupPasses; ++pass) {
    bool moved_any = false;
    for (int f = 0; f < graph.n_faces(); ++f) {
      const int p = patches.face_patch[f];
      std::array<int, 3> side{};
      int n_own = 0;
      for (int i = 0; i < 3; ++i) {
        const int g = graph.neighbours[f][i];
        side[i] = g < 0 ? -1 : patches.face_patch[g];
        n_own += side[i] == p ? 1 : 0;
      }
      if (n_own > 1 || (n_own == 0 && size[p] > 1)) continue;
      for (int i = 0; i < 3; ++i) {
        const int q = side[i];
        if (q < 0 || q == p) continue;
        int n_shared = 0;
        bool creased = false;
        for (int k = 0; k < 3; ++k) {
          if (side[k] != q) continue;
          ++n_shared;
          creased = creased || graph.is_crease(f, k);
        }
        if (n_shared < 2 || creased || !grouping.fits(f, patches.axes[q])) continue;
        patches.face_patch[f] = q;
        --size[p];
        ++size[q];
        moved_any = changed = true;
        break;
      }
    }
    if (!moved_any) break;
  }
  if (!changed) return;
  for (auto& faces : patches.faces) faces.clear();
  for (int f = 0; f < graph.n_faces(); ++f) patches.faces[patches.face_patch[f]].push_back(f);
}

// Drops empty patches and numbers the rest by their smallest face id; sorts face lists
// (each on its own: on `workers` threads).
void renumber(Patches& patches, unsigned workers) {
  segment_detail::parallel_chunks(patches.faces.size(), workers, kPatchChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t p = begin; p < end; ++p) {
      auto& faces = patches.faces[p];
      if (!std::is_sorted(faces.begin(), faces.end())) std::sort(faces.begin(), faces.end());
    }
  });
  std::vector<int> order;
  for (int p = 0; p < static_cast<int>(patches.faces.size()); ++p) {
    if (!patches.faces[p].empty()) order.push_back(p);
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) { return patches.faces[a][0] < patches.faces[b][0]; });
  Patches result;
  result.face_patch.assign(patches.face_patch.size(), -1);
  for (int p : order) {
    const int id = static_cast<int>(result.faces.size());
    for (int f : patches.faces[p]) result.face_patch[f] = id;
    result.faces.push_back(std::move(patches.faces[p]));
    result.axes.push_back(patches.axes[p]);
  }
  patches = std::move(result);
}

// The axis becomes the area-weighted mean raw normal where every face fits it (each patch
// on its own: on `workers` threads).
void refine_axes(const Grouping& grouping, Patches& patches, unsigned workers) {
  segment_detail::parallel_chunks(patches.faces.size(), workers, kPatchChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t p = begin; p < end; ++p) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int f : patches.faces[p]) sum += grouping.normals.area[f] * grouping.normals.raw[f];
      if (!(sum.norm() > 0.0)) continue;
      const Eigen::Vector3d mean = sum.normalized();
      if (std::all_of(patches.faces[p].begin(), patches.faces[p].end(), [&](int f) { return grouping.fits(f, mean); }))
        patches.axes[p] = mean;
    }
  });
}

// Splits `faces` (one patch) into the connected components of the carved faces and of
// the others (scratch.face_owner: 1 carved, 0 not); returns the components.
std::vector<std::vector<int>> carve_components(const FaceGraph& graph, const std::vector<int>& faces,
                                               const std::vector<int>& face_patch, Scratch& scratch) {
  const int patch = face_patch[faces[0]];
  const int epoch = ++scratch.face_epoch;
  std::vector<std::vector<int>> components;
  // Each component is searched in scratch.face_queue (as long as the patch), then copied.
  std::vector<int>& queue = scratch.face_queue;
  if (queue.size() < faces.size()) queue.resize(faces.size());
  for (int seed : faces) {
    if (scratch.face_stamp[seed] == epoch) continue;
    std::size_t tail = 0;
    queue[tail++] = seed;
    scratch.face_stamp[seed] = epoch;
    for (std::size_t head = 0; head < tail; ++head) {
      const int f = queue[head];
      for (int i = 0; i < 3; ++i) {
        const int g = graph.neighbours[f][i];
        if (g < 0 || face_patch[g] != patch || scratch.face_stamp[g] == epoch ||
            scratch.face_owner[g] != scratch.face_owner[f])
          continue;
        NURBSFRONT_ASSERT(tail < faces.size());
        scratch.face_stamp[g] = epoch;
        queue[tail++] = g;
      }
    }
    components.emplace_back(queue.begin(), queue.begin() + static_cast<std::ptrdiff_t>(tail));
  }
  return components;
}

}  // namespace

// Vertices bucketed in the patch plane on a grid of the run, sorted by height within a
// bucket; only pairs of neighbouring buckets whose height ranges together span more than
// the rise are compared, and of those only the vertices more than the rise above (or below)
// each other: a suffix (prefix) of the other bucket, found by two pointers since the heights
// are sorted.
bool segment_detail::has_cliff(const FaceGraph& graph, const std::vector<int>& faces, const Eigen::Vector3d& axis,
                               double mean_edge, Scratch& scratch, CliffPairs* pairs) {
  if (pairs != nullptr) {
    pairs->pairs.clear();
    pairs->is_complete = true;
  }
  if (faces.size() < kCliffMinFaces || !(mean_edge > 0.0)) return false;
  const auto [e1, e2] = segment_detail::plane_frame(axis);
  const double run = kCliffRunEdges * mean_edge;
  const double rise = kCliffRiseEdges * mean_edge;
  struct Entry {
    std::int64_t i, j;
    Eigen::Vector3d local;
    int vertex;
  };
  std::vector<Entry> entries;
  entries.reserve(faces.size());
  double z_min = std::numeric_limits<double>::infinity(), z_max = -z_min;
  std::int64_t i_min = std::numeric_limits<std::int64_t>::max(), i_max = std::numeric_limits<std::int64_t>::min();
  std::int64_t j_min = i_min, j_max = i_max;
  const int epoch = ++scratch.vertex_epoch;  // each vertex once
  for (const int f : faces) {
    for (const int v : graph.vertices[f]) {
      if (scratch.vertex_stamp[v] == epoch) continue;
      scratch.vertex_stamp[v] = epoch;
      const Eigen::Vector3d& x = graph.points[v];
      const Eigen::Vector3d local(x.dot(e1), x.dot(e2), x.dot(axis));
      entries.push_back({static_cast<std::int64_t>(std::floor(local.x() / run)),
                         static_cast<std::int64_t>(std::floor(local.y() / run)), local, v});
      z_min = std::min(z_min, local.z());
      z_max = std::max(z_max, local.z());
      i_min = std::min(i_min, entries.back().i);
      i_max = std::max(i_max, entries.back().i);
      j_min = std::min(j_min, entries.back().j);
      j_max = std::max(j_max, entries.back().j);
    }
  }
  if (!(z_max - z_min > rise)) return false;
  // Ordered by bucket (i, then j), heights ascending within a bucket (the order of equal
  // heights does not matter: the test below treats them alike). A counting sort by bucket
  // over the buckets' range, then a sort of each bucket, where that range is not much
  // larger than the vertex count; else one comparison sort.
  auto by_height = [](const Entry& a, const Entry& b) { return a.local.z() < b.local.z(); };
  const auto n_i = static_cast<std::uint64_t>(i_max - i_min) + 1, n_j = static_cast<std::uint64_t>(j_max - j_min) + 1;
  const std::uint64_t max_cells = 4 * static_cast<std::uint64_t>(entries.size()) + 64;
  if (n_i <= max_cells && n_j <= max_cells && n_i * n_j <= max_cells) {
    auto cell = [&](const Entry& e) {
      return static_cast<std::size_t>(static_cast<std::uint64_t>(e.i - i_min) * n_j + static_cast<std::uint64_t>(e.j - j_min));
    };
    std::vector<std::size_t> start(static_cast<std::size_t>(n_i * n_j) + 1, 0);
    for (const Entry& e : entries) ++start[cell(e) + 1];
    for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
    std::vector<Entry> sorted(entries.size());
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (const Entry& e : entries) sorted[fill[cell(e)]++] = e;
    for (std::size_t c = 0; c + 1 < start.size(); ++c)
      if (start[c + 1] - start[c] > 1)
        std::sort(sorted.begin() + static_cast<std::ptrdiff_t>(start[c]), sorted.begin() + static_cast<std::ptrdiff_t>(start[c + 1]),
                  by_height);
    entries.swap(sorted);
  } else {
    std::sort(entries.begin(), entries.end(), [&](const Entry& a, const Entry& b) {
      if (a.i != b.i) return a.i < b.i;
      if (a.j != b.j) return a.j < b.j;
      return by_height(a, b);
    });
  }
  struct Bucket {
    std::int64_t i, j;
    std::size_t begin, end;  // heights ascending
  };
  std::vector<Bucket> buckets;
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const Entry& e = entries[k];
    if (buckets.empty() || buckets.back().i != e.i || buckets.back().j != e.j) buckets.push_back({e.i, e.j, k, k});
    buckets.back().end = k + 1;
  }
  auto find = [&](std::int64_t i, std::int64_t j) -> const Bucket* {
    const auto it = std::lower_bound(buckets.begin(), buckets.end(), std::pair(i, j), [](const Bucket& b, const std::pair<std::int64_t, std::int64_t>& k) {
      return b.i != k.first ? b.i < k.first : b.j < k.second;
    });
    return it != buckets.end() && it->i == i && it->j == j ? &*it : nullptr;
  };
  auto z = [&](std::size_t k) { return entries[k].local.z(); };
  // Whether vertex `high` rises by dz over `low` as a cliff; with `pairs`, every cliff is
  // listed (as long as the list is not full) and the search goes on.
  bool found = false;
  auto is_cliff = [&](std::size_t low, std::size_t high, double dz) {
    const double dxy = (entries[high].local.head<2>() - entries[low].local.head<2>()).norm();
    if (!(dxy < run && dz > kCliffMinRiseOverRun * dxy)) return false;
    found = true;
    if (pairs == nullptr || !pairs->is_complete) return true;
    if (pairs->pairs.size() == kMaxCliffPairs) {
      pairs->pairs.clear();
      pairs->is_complete = false;
      return true;
    }
    pairs->pairs.push_back({entries[low].vertex, entries[high].vertex});
    return false;
  };
  for (const Bucket& a : buckets) {
    // Each unordered pair of buckets once: itself and the neighbours after it in (i, j) order.
    for (const auto& [di, dj] : {std::pair(0, 0), std::pair(0, 1), std::pair(1, -1), std::pair(1, 0), std::pair(1, 1)}) {
      const Bucket* b = (di == 0 && dj == 0) ? &a : find(a.i + di, a.j + dj);
      if (b == nullptr || !(std::max(z(a.end - 1), z(b->end - 1)) - std::min(z(a.begin), z(b->begin)) > rise)) continue;
      // For p rising through a: b's vertices more than the rise above p start at `above`
      // (moves up), those more than the rise below p end at `below` (moves up). The
      // differences are those of the exhaustive test (rounding is monotone).
      std::size_t above = b->begin, below = b->begin;
      for (std::size_t p = a.begin; p < a.end; ++p) {
        while (above < b->end && !(z(above) - z(p) > rise)) ++above;
        for (std::size_t q = std::max(above, b == &a ? p + 1 : b->begin); q < b->end; ++q)
          if (is_cliff(p, q, z(q) - z(p))) return true;
        if (b == &a) continue;  // pairs within a: the higher one is above
        while (below < b->end && z(p) - z(below) > rise) ++below;
        for (std::size_t q = b->begin; q < below; ++q)
          if (is_cliff(q, p, z(p) - z(q))) return true;
      }
    }
  }
  return found;
}

namespace {

// Splits every patch whose projection is not a set of simple loops, or that holds a cliff
// (has_cliff); returns the count.
// A local fold (a short extra outer loop around a flipped face, or two crossing border
// segments at a steep border face, typical of terraced inputs) is cut out with a few rings
// of faces around it; anything else is bisected. Parts are checked again until every patch passes.
// `work`: the patches to check, taken from the back (every patch unless some are known to pass).
// With workers > 1, the patches of `work` are first checked in parallel, each worker but the
// first with its own scratch from `worker_scratch` (made at first use, kept for later calls).
constexpr unsigned kMaxFoldCheckWorkers = 4;
// A precheck whose patches other than the largest hold fewer faces than this runs on the
// calling thread: waking a Team worker costs more than checking them (about 0.1 us a face;
// on the liver 968 of the 1 046 prechecks of split parts, 4% of their faces; session 20).
constexpr std::size_t kMinPrecheckHandOffFaces = 1000;

std::size_t split_folds(const Grouping& grouping, double mean_edge, Scratch& scratch, Patches& patches,
                        std::vector<int> work, unsigned workers,
                        std::vector<std::unique_ptr<Scratch>>& worker_scratch) {
  // Each worker but the first holds a whole-mesh scratch (tens of MB on large inputs): at
  // most kMaxFoldCheckWorkers of them, whatever the thread count.
  workers = std::min(workers, kMaxFoldCheckWorkers);
  const FaceGraph& graph = grouping.graph;
  const TriMesh& mesh = *graph.mesh;
  // Per patch: the cliffs of an ancestor that was bisected for them, those with both
  // vertices in the patch (where listed[p] != 0). Every part keeps its ancestor's axis, so
  // these are all of the patch's cliffs (segment_detail::has_cliff).
  std::vector<segment_detail::CliffPairs> cliffs(patches.faces.size());
  std::vector<std::uint8_t> listed(patches.faces.size(), 0);
  // A patch fails when its projection is not simple or it holds a cliff: decided by its
  // listed cliffs, else by a search that lists them all in `found` (a patch that fails for a
  // cliff is bisected, and its parts then need no search).
  auto check_patch = [&](int p, Scratch& own, bool& fails, segment_detail::CliffPairs& found) {
    const std::vector<int>& faces = patches.faces[p];
    segment_detail::ProjectionCheck check =
        segment_detail::check_projection(graph, faces, patches.face_patch, patches.axes[p], own);
    if (!check.is_simple)
      fails = true;
    else if (listed[p] != 0)
      fails = faces.size() >= kCliffMinFaces && mean_edge > 0.0 && !cliffs[p].pairs.empty();
    else
      fails = segment_detail::has_cliff(graph, faces, patches.axes[p], mean_edge, own, &found);
    return check;
  };
  // The parallel checks: a patch's check depends only on its faces and axis and on which
  // faces around it are not its own, which splitting other patches does not change, so a
  // patch not split since it was checked here takes this result (the same as checking it
  // in the loop: results do not depend on the thread count). First every patch of `work`,
  // then the parts of each split (each is checked before anything changes its faces).
  // A patch that fails without local trouble is bisected (bisect_patch depends only on its
  // faces, as the check does): the parallel check bisects it too, and the loop takes those
  // parts (prebisected) instead of bisecting on the calling thread.
  std::vector<std::uint8_t> prechecked, prefails, prebisected;
  std::vector<segment_detail::ProjectionCheck> prechecks;
  std::vector<segment_detail::CliffPairs> precliffs;
  std::vector<std::pair<std::vector<int>, std::vector<int>>> prehalves;
  // The prechecks' threads, kept across the loop: it prechecks the parts of every split
  // (1 047 small loops on the liver at 2 threads), and parallel::for_chunks started and
  // joined a thread for each (docs/benchmarks/pipeline.md, session 19).
  parallel::Team team(workers);
  auto precheck = [&](const std::vector<int>& which) {
    const std::size_t n = patches.faces.size();
    prechecked.resize(n, 0);
    prefails.resize(n, 0);
    prebisected.resize(n, 0);
    prechecks.resize(n);
    precliffs.resize(n);
    prehalves.resize(n);
    if (worker_scratch.size() < workers) worker_scratch.resize(workers);
    std::size_t n_faces = 0, most_faces = 0;
    for (const int q : which) {
      n_faces += patches.faces[q].size();
      most_faces = std::max(most_faces, patches.faces[q].size());
    }
    const std::size_t chunk = n_faces - most_faces < kMinPrecheckHandOffFaces ? which.size() : 1;
    team.for_chunks(which.size(), chunk, [&](std::size_t begin, std::size_t end, unsigned worker) {
      if (worker > 0 && !worker_scratch[worker]) worker_scratch[worker] = std::make_unique<Scratch>(mesh);
      Scratch& own = worker == 0 ? scratch : *worker_scratch[worker];
      for (std::size_t i = begin; i < end; ++i) {
        const int p = which[i];
        bool fails = false;
        prechecks[p] = check_patch(p, own, fails, precliffs[p]);
        prefails[p] = fails ? 1 : 0;
        prebisected[p] = fails && prechecks[p].trouble.empty() && patches.faces[p].size() >= 2 ? 1 : 0;
        if (prebisected[p] != 0) prehalves[p] = segment_detail::bisect_patch(graph, patches.faces[p], patches.face_patch, own);
        prechecked[p] = 1;
      }
    });
  };
  if (workers > 1 && work.size() > 1) precheck(work);
  std::vector<int> split_parts;
  std::size_t n_splits = 0;
  while (!work.empty()) {
    const int p = work.back();
    work.pop_back();
    segment_detail::ProjectionCheck check;
    segment_detail::CliffPairs found;
    bool fails = false;
    std::pair<std::vector<int>, std::vector<int>> halves;
    bool bisected = false;
    if (static_cast<std::size_t>(p) < prechecked.size() && prechecked[p] != 0) {
      prechecked[p] = 0;  // p's faces change if it is split
      check = std::move(prechecks[p]);
      fails = prefails[p] != 0;
      found = std::move(precliffs[p]);
      bisected = prebisected[p] != 0;
      if (bisected) halves = std::move(prehalves[p]);
    } else {
      check = check_patch(p, scratch, fails, found);
    }
    if (!fails) {
      cliffs[p] = {};
      continue;
    }
    ++n_splits;
    // Failed for a cliff, found by a search: every cliff of p is in `found`.
    if (listed[p] == 0 && check.is_simple && found.is_complete) {
      cliffs[p] = std::move(found);
      listed[p] = 1;
    }
    std::vector<std::vector<int>> parts;
    if (!check.trouble.empty()) {
      for (int f : patches.faces[p]) scratch.face_owner[f] = 0;
      std::vector<int> carved;
      for (int v : check.trouble) {
        for (const auto f : mesh.vf_range(mesh.vertex_handle(v))) {
          if (patches.face_patch[f.idx()] != p || scratch.face_owner[f.idx()] != 0) continue;
          scratch.face_owner[f.idx()] = 1;
          carved.push_back(f.idx());
        }
      }
      for (int ring = 1; ring < kCarveRings; ++ring) {
        const std::size_t n_carved = carved.size();
        for (std::size_t k = 0; k < n_carved; ++k) {
          for (int i = 0; i < 3; ++i) {
            const int g = graph.neighbours[carved[k]][i];
            if (g < 0 || patches.face_patch[g] != p || scratch.face_owner[g] != 0) continue;
            scratch.face_owner[g] = 1;
            carved.push_back(g);
          }
        }
      }
      if (carved.size() < patches.faces[p].size()) parts = carve_components(graph, patches.faces[p], patches.face_patch, scratch);
    }
    if (parts.size() < 2) {
      // Prebisected only where the trouble is empty, so no carve was tried above.
      auto [first, second] =
          bisected ? std::move(halves) : segment_detail::bisect_patch(graph, patches.faces[p], patches.face_patch, scratch);
      parts.clear();
      parts.push_back(std::move(first));
      parts.push_back(std::move(second));
    }
    // Each part's cliffs: those of p with both vertices in the part.
    std::vector<segment_detail::CliffPairs> part_cliffs(listed[p] != 0 ? parts.size() : 0);
    for (std::size_t k = 0; k < part_cliffs.size(); ++k) {
      const int epoch = ++scratch.vertex_epoch;
      for (const int f : parts[k])
        for (const int v : graph.vertices[f]) scratch.vertex_stamp[v] = epoch;
      for (const auto& pair : cliffs[p].pairs)
        if (scratch.vertex_stamp[pair[0]] == epoch && scratch.vertex_stamp[pair[1]] == epoch)
          part_cliffs[k].pairs.push_back(pair);
    }
    const bool parts_listed = listed[p] != 0;
    const Eigen::Vector3d axis = patches.axes[p];
    patches.faces[p] = std::move(parts[0]);
    cliffs[p] = parts_listed ? std::move(part_cliffs[0]) : segment_detail::CliffPairs{};
    work.push_back(p);
    split_parts.assign(1, p);
    for (std::size_t k = 1; k < parts.size(); ++k) {
      const int q = static_cast<int>(patches.faces.size());
      for (int f : parts[k]) patches.face_patch[f] = q;
      patches.faces.push_back(std::move(parts[k]));
      patches.axes.push_back(axis);
      cliffs.push_back(parts_listed ? std::move(part_cliffs[k]) : segment_detail::CliffPairs{});
      listed.push_back(parts_listed ? 1 : 0);
      work.push_back(q);
      split_parts.push_back(q);
    }
    if (workers > 1) precheck(split_parts);
  }
  return n_splits;
}

// split_folds()' work list of every patch (the lowest id checked first).
std::vector<int> all_patches(const Patches& patches) {
  std::vector<int> work;
  for (int p = static_cast<int>(patches.faces.size()) - 1; p >= 0; --p) work.push_back(p);
  return work;
}

void validate_mesh(const TriMesh& mesh) {
  for (const auto f : mesh.all_faces())
    if (mesh.status(f).deleted())
      throw InvalidInput("segment: the mesh has deleted faces; call garbage_collection() first");
  for (const auto v : mesh.all_vertices()) {
    if (mesh.status(v).deleted())
      throw InvalidInput("segment: the mesh has deleted vertices; call garbage_collection() first");
    const auto& p = mesh.point(v);
    if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])))
      throw InvalidInput("segment: vertex " + std::to_string(v.idx()) + " has a non-finite coordinate");
  }
  for (const auto e : mesh.all_edges())
    if (mesh.status(e).deleted())
      throw InvalidInput("segment: the mesh has deleted edges; call garbage_collection() first");
}

// split_patches(): 2-means iterations on the smoothed normals of a patch.
constexpr int kSplitClusterIterations = 10;

// Splits one patch (faces, all in patch p of face_patch) in connected parts by its smoothed
// normals: two clusters (2-means, started from the normal furthest from the axis and the
// one furthest from that), their connected components, and components smaller than
// min_part faces merged into the neighbouring component they share most edges with. Each
// part gets its mean raw normal as axis where every face fits it, else the cluster's mean
// smoothed normal, else the patch's axis (which bounds every subset of the patch). Returns
// fewer than two parts when the normals do not separate.
std::vector<std::pair<std::vector<int>, Eigen::Vector3d>> split_by_normals(const Grouping& grouping,
                                                                           const std::vector<int>& faces, int p,
                                                                           const std::vector<int>& face_patch,
                                                                           const Eigen::Vector3d& axis,
                                                                           std::size_t min_part, Scratch& scratch) {
  const FaceGraph& graph = grouping.graph;
  const FaceNormals& normals = grouping.normals;
  std::vector<std::pair<std::vector<int>, Eigen::Vector3d>> parts;
  if (faces.size() < 2) return parts;
  auto usable = [&](int f) { return normals.degenerate[f] == 0 && normals.exception[f] == 0; };
  int first = -1;
  for (const int f : faces)
    if (usable(f) && (first < 0 || normals.smooth[f].dot(axis) < normals.smooth[first].dot(axis))) first = f;
  if (first < 0) return parts;
  std::array<Eigen::Vector3d, 2> centre{normals.smooth[first], normals.smooth[first]};
  for (const int f : faces)
    if (usable(f) && normals.smooth[f].dot(centre[0]) < centre[1].dot(centre[0])) centre[1] = normals.smooth[f];
  std::vector<int> label(faces.size(), 0);
  auto nearer = [&](int f) { return normals.smooth[f].dot(centre[0]) >= normals.smooth[f].dot(centre[1]) ? 0 : 1; };
  for (int it = 0; it < kSplitClusterIterations; ++it) {
    std::array<Eigen::Vector3d, 2> sum{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    for (std::size_t i = 0; i < faces.size(); ++i) {
      if (!usable(faces[i])) continue;
      label[i] = nearer(faces[i]);
      sum[label[i]] += normals.area[faces[i]] * normals.smooth[faces[i]];
    }
    if (!(sum[0].norm() > 0.0 && sum[1].norm() > 0.0)) return parts;
    centre = {sum[0].normalized(), sum[1].normalized()};
  }
  // Faces without a usable normal take the label of the nearer centre by their raw normal
  // (degenerate ones 0); the components absorb them anyway when they are few.
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const int f = faces[i];
    if (usable(f)) label[i] = nearer(f);
    else label[i] = normals.degenerate[f] != 0 ? 0 : (normals.raw[f].dot(centre[0]) >= normals.raw[f].dot(centre[1]) ? 0 : 1);
  }
  // Components of equal labels (face_owner: index into faces, face_stamp: this call).
  const int epoch = ++scratch.face_epoch;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    scratch.face_stamp[faces[i]] = epoch;
    scratch.face_owner[faces[i]] = static_cast<int>(i);
  }
  std::vector<int> component(faces.size(), -1);
  std::vector<std::size_t> size;
  for (std::size_t seed = 0; seed < faces.size(); ++seed) {
    if (component[seed] >= 0) continue;
    const int id = static_cast<int>(size.size());
    std::vector<std::size_t> queue{seed};
    component[seed] = id;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const int f = faces[queue[head]];
      for (const int g : graph.neighbours[f]) {
        if (g < 0 || face_patch[g] != p || scratch.face_stamp[g] != epoch) continue;
        const auto j = static_cast<std::size_t>(scratch.face_owner[g]);
        if (component[j] >= 0 || label[j] != label[queue[head]]) continue;
        component[j] = id;
        queue.push_back(j);
      }
    }
    size.push_back(queue.size());
  }
  // Small components join the neighbouring component with the longest shared border,
  // smallest first, until every component has min_part faces or one is left.
  for (;;) {
    std::size_t n_alive = 0;
    int smallest = -1;
    for (std::size_t c = 0; c < size.size(); ++c) {
      if (size[c] == 0) continue;
      ++n_alive;
      if (smallest < 0 || size[c] < size[static_cast<std::size_t>(smallest)]) smallest = static_cast<int>(c);
    }
    if (n_alive < 2 || size[static_cast<std::size_t>(smallest)] >= min_part) break;
    std::vector<int> shared(size.size(), 0);
    for (std::size_t i = 0; i < faces.size(); ++i) {
      if (component[i] != smallest) continue;
      for (const int g : graph.neighbours[faces[i]]) {
        if (g < 0 || face_patch[g] != p || scratch.face_stamp[g] != epoch) continue;
        const int c = component[static_cast<std::size_t>(scratch.face_owner[g])];
        if (c != smallest) ++shared[static_cast<std::size_t>(c)];
      }
    }
    const auto target = static_cast<int>(std::max_element(shared.begin(), shared.end()) - shared.begin());
    NURBSFRONT_ASSERT(shared[static_cast<std::size_t>(target)] > 0);  // the patch is connected
    for (auto& c : component)
      if (c == smallest) c = target;
    size[static_cast<std::size_t>(target)] += size[static_cast<std::size_t>(smallest)];
    size[static_cast<std::size_t>(smallest)] = 0;
  }
  for (std::size_t c = 0; c < size.size(); ++c) {
    if (size[c] == 0) continue;
    std::vector<int> part;
    part.reserve(size[c]);
    std::array<Eigen::Vector3d, 2> sum{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    for (std::size_t i = 0; i < faces.size(); ++i) {
      if (component[i] != static_cast<int>(c)) continue;
      part.push_back(faces[i]);
      sum[0] += normals.area[faces[i]] * normals.raw[faces[i]];
      if (usable(faces[i])) sum[1] += normals.area[faces[i]] * normals.smooth[faces[i]];
    }
    Eigen::Vector3d part_axis = axis;
    for (const Eigen::Vector3d& candidate : sum) {
      if (!(candidate.norm() > 0.0)) continue;
      const Eigen::Vector3d unit = candidate.normalized();
      if (std::all_of(part.begin(), part.end(), [&](int f) { return grouping.fits(f, unit); })) {
        part_axis = unit;
        break;
      }
    }
    parts.emplace_back(std::move(part), part_axis);
  }
  if (parts.size() < 2) parts.clear();
  return parts;
}

// Step 7b. Tiny islands (at most kSegmentTinyIslandFaces faces, every border edge shared
// with one patch, none on the input's boundary, border shorter than max_perimeter) join
// the patch around them across creases when their faces meet the bounds for its axis: a
// crease-bounded sliver face (level-set DRAM cell: at the cups' bottoms) otherwise becomes
// its own patch, whose border loop is shorter than a target edge and whose few triangles
// leave small angles around it. Only islands smaller than a normal face: larger ones
// (crease-bounded spikes of medical marching-cubes surfaces) are detail the fit would
// round off. The union must pass the projection check. Every joined face is appended to
// island_faces. Returns how many islands joined.
std::size_t absorb_tiny_islands(const Grouping& grouping, double max_perimeter, Patches& patches, Scratch& scratch,
                                std::vector<int>& island_faces) {
  const FaceGraph& graph = grouping.graph;
  std::size_t n_absorbed = 0;
  for (std::size_t p = 0; p < patches.faces.size(); ++p) {
    const auto& faces = patches.faces[p];
    if (faces.empty() || faces.size() > kSegmentTinyIslandFaces) continue;
    int around = -1;
    bool island = true;
    double perimeter = 0.0;
    for (int f : faces) {
      for (int i = 0; i < 3 && island; ++i) {
        const int g = graph.neighbours[f][i];
        if (g >= 0 && patches.face_patch[g] == static_cast<int>(p)) continue;
        const int q = g < 0 ? -1 : patches.face_patch[g];
        island = q >= 0 && (around < 0 || around == q);
        around = q;
        const auto a = graph.mesh->point(graph.mesh->vertex_handle(static_cast<unsigned>(graph.vertices[f][i])));
        const auto b = graph.mesh->point(graph.mesh->vertex_handle(static_cast<unsigned>(graph.vertices[f][(i + 1) % 3])));
        perimeter += (a - b).norm();
      }
    }
    if (!island || around < 0 || !(perimeter < max_perimeter)) continue;
    const Eigen::Vector3d& axis = patches.axes[static_cast<std::size_t>(around)];
    if (!std::all_of(faces.begin(), faces.end(), [&](int f) { return grouping.fits(f, axis); })) continue;
    auto& target = patches.faces[static_cast<std::size_t>(around)];
    for (int f : faces) patches.face_patch[f] = around;
    target.insert(target.end(), faces.begin(), faces.end());
    if (!segment_detail::check_projection(graph, target, patches.face_patch, axis, scratch).is_simple) {
      target.resize(target.size() - faces.size());
      for (int f : faces) patches.face_patch[f] = static_cast<int>(p);
      continue;
    }
    island_faces.insert(island_faces.end(), faces.begin(), faces.end());
    patches.faces[p].clear();
    ++n_absorbed;
  }
  return n_absorbed;
}

// Steps 1-2 of segment(): creases (bevel bends counted in result), raw and smoothed
// normals, and the faces that admit no axis.
FaceNormals prepare_normals(FaceGraph& graph, const SegmentOptions& options, Segmentation& result) {
  const unsigned workers = segment_detail::worker_count(options.threads);
  FaceNormals normals = face_normals(graph, bounding_box(*graph.mesh).diagonal(), workers);
  mark_creases(graph, normals, std::cos(radians(options.crease_angle_deg)), workers);
  if (options.sharp_crease_angle_deg > 0.0 && options.sharp_crease_angle_deg < options.crease_angle_deg)
    result.sharp_crease_edges =
        mark_sharp_creases(graph, normals, options.sharp_crease_angle_deg, options.crease_angle_deg, workers);
  if (options.bevel_creases) result.n_bevel_crease_edges = mark_bevel_creases(graph, normals);
  normals.smooth = smooth_normals(graph, normals, options.normal_smoothing_rings, workers);
  const double max_slope = radians(options.max_slope_deg);
  // A face whose raw and smoothed normals are further apart than this admits no axis.
  const double max_spread = max_slope + std::acos(kSegmentMinRawNormalDot) - tolerance::kAngleMarginRad;
  segment_detail::parallel_chunks(graph.vertices.size(), workers, kFaceChunk,
                                  [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t f = begin; f < end; ++f) {
      if (normals.degenerate[f] != 0) continue;
      const double spread = std::acos(std::clamp(normals.raw[f].dot(normals.smooth[f]), -1.0, 1.0));
      normals.exception[f] = spread > max_spread ? 1 : 0;
    }
  });
  return normals;
}

// The border curves and corners of a segmentation's face -> patch map, and each patch's
// list of its curves (replacing any it had).
void attach_borders(const TriMesh& mesh, const SegmentOptions& options, Segmentation& result) {
  segment_detail::Borders borders =
      segment_detail::extract_borders(mesh, result.face_patch, options.border_smoothing,
                                      segment_detail::worker_count(options.threads), &result.pinned_corners);
  for (Patch& patch : result.patches) patch.curves.clear();
  for (std::size_t c = 0; c < borders.curves.size(); ++c) {
    const BorderCurve& curve = borders.curves[c];
    result.patches[curve.patch_left].curves.push_back(static_cast<int>(c));
    if (curve.patch_right >= 0) result.patches[curve.patch_right].curves.push_back(static_cast<int>(c));
  }
  result.curves = std::move(borders.curves);
  result.corners = std::move(borders.corners);
}

// The segmentation's face counts that depend only on the face graph (its creases) and the
// normals: the same for every result of one splitter.
struct FaceCounts {
  std::size_t n_crease_edges = 0, n_degenerate_faces = 0, n_slope_exceptions = 0;
};

FaceCounts face_counts(const FaceGraph& graph, const FaceNormals& normals) {
  FaceCounts counts;
  for (int f = 0; f < graph.n_faces(); ++f) {
    for (int i = 0; i < 3; ++i)
      if (graph.is_crease(f, i) && graph.vertices[f][i] < graph.vertices[f][(i + 1) % 3]) ++counts.n_crease_edges;
    counts.n_degenerate_faces += normals.degenerate[f];
    counts.n_slope_exceptions += normals.exception[f];
  }
  return counts;
}

// Step 8 of segment(): border curves of the final (renumbered) patches (unless
// `with_borders` is false: segment_detail::with_borders() adds them later), and the result
// with `counts` (face_counts() of the graph and normals).
void finish_segmentation(const TriMesh& mesh, const FaceCounts& counts, Patches& patches, const SegmentOptions& options,
                         Segmentation& result, bool with_borders) {
  result.face_patch = std::move(patches.face_patch);
  result.patches.assign(patches.faces.size(), Patch{});
  for (std::size_t p = 0; p < patches.faces.size(); ++p) {
    result.patches[p].faces = std::move(patches.faces[p]);
    result.patches[p].axis = patches.axes[p];
  }
  result.curves.clear();
  result.corners.clear();
  if (with_borders) attach_borders(mesh, options, result);
  result.n_crease_edges = counts.n_crease_edges;
  result.n_degenerate_faces = counts.n_degenerate_faces;
  result.n_slope_exceptions = counts.n_slope_exceptions;
}

}  // namespace

struct segment_detail::Splitter {
  Splitter(const TriMesh& m, const SegmentOptions& o) : mesh(m), options(o) {}
  const TriMesh& mesh;
  SegmentOptions options;
  // Computed at the first split (segment()'s steps 1-2), or handed over by segment().
  bool prepared = false;
  FaceGraph graph;
  FaceNormals normals;
  std::size_t n_bevel_crease_edges = 0;
  std::vector<int> sharp_crease_edges;
  // face_counts() of graph and normals (every result's counts: a pass over the faces once).
  FaceCounts counts;
  double mean_edge = 0.0;
  // The last result: each of its patches passed split_folds' checks with its axis.
  std::vector<int> last_face_patch;
  std::vector<Eigen::Vector3d> last_axes;
  // The scratch of the checks (kept between rounds), and split_folds' scratches of the
  // workers but the first.
  std::unique_ptr<Scratch> scratch;
  std::vector<std::unique_ptr<Scratch>> worker_scratch;

  void prepare() {
    if (prepared) return;
    graph = segment_detail::build_graph(mesh, segment_detail::worker_count(options.threads));
    Segmentation counts;
    normals = prepare_normals(graph, options, counts);
    n_bevel_crease_edges = counts.n_bevel_crease_edges;
    sharp_crease_edges = std::move(counts.sharp_crease_edges);
    this->counts = face_counts(graph, normals);
    mean_edge = mean_edge_length(mesh);
    prepared = true;
  }
};

void segment_detail::SplitterDeleter::operator()(Splitter* splitter) const { delete splitter; }

segment_detail::SplitterPtr segment_detail::make_splitter(const TriMesh& mesh, const SegmentOptions& options) {
  options.validate();
  validate_mesh(mesh);
  return SplitterPtr(new Splitter(mesh, options));
}

namespace {

// The checks of an edit of a segmentation of the splitter's mesh (`what`: the function's name).
void check_edit(const segment_detail::Splitter& s, const Segmentation& segmentation, const std::vector<int>& which,
                const std::string& what) {
  if (segmentation.face_patch.size() != s.mesh.n_faces())
    throw InvalidInput(what + ": the segmentation has " + std::to_string(segmentation.face_patch.size()) +
                       " face labels for " + std::to_string(s.mesh.n_faces()) + " faces");
  const auto n_patches = static_cast<int>(segmentation.patches.size());
  for (const int p : which)
    if (p < 0 || p >= n_patches) throw InvalidInput(what + ": no patch " + std::to_string(p));
  for (std::size_t f = 0; f < segmentation.face_patch.size(); ++f) {
    const int p = segmentation.face_patch[f];
    if (p < 0 || p >= n_patches) throw InvalidInput(what + ": face " + std::to_string(f) + " has no valid patch");
  }
  for (int p = 0; p < n_patches; ++p)
    for (const int f : segmentation.patches[static_cast<std::size_t>(p)].faces)
      if (f < 0 || static_cast<std::size_t>(f) >= segmentation.face_patch.size() ||
          segmentation.face_patch[static_cast<std::size_t>(f)] != p)
        throw InvalidInput(what + ": patch " + std::to_string(p) + " lists face " + std::to_string(f) +
                           ", which is not labelled with it");
  // Pinned corners are vertex indices of the mesh, ascending (the edits binary-search them).
  const std::vector<int>& pins = segmentation.pinned_corners;
  for (std::size_t i = 0; i < pins.size(); ++i) {
    if (pins[i] < 0 || static_cast<std::size_t>(pins[i]) >= s.mesh.n_vertices())
      throw InvalidInput(what + ": pinned corner " + std::to_string(pins[i]) + " is no vertex of the mesh");
    if (i > 0 && pins[i] <= pins[i - 1]) throw InvalidInput(what + ": the pinned corners are not ascending");
  }
}

Grouping splitter_grouping(const segment_detail::Splitter& s) {
  const double max_slope = radians(s.options.max_slope_deg);
  return Grouping{s.graph, s.normals, std::cos(max_slope), max_slope, std::cos(kGrowthConeFraction * max_slope)};
}

Patches editable_patches(const Segmentation& segmentation) {
  Patches patches;
  patches.face_patch = segmentation.face_patch;
  for (const Patch& patch : segmentation.patches) {
    patches.faces.push_back(patch.faces);
    patches.axes.push_back(patch.axis);
  }
  return patches;
}

// The edited patches renumbered, with their curves; counts, island faces and pinned corners as
// given.
Segmentation finish_edit(const segment_detail::Splitter& s, Patches& patches,
                         std::size_t n_fold_splits, std::size_t n_islands_absorbed, std::vector<int> island_faces,
                         bool with_borders, std::vector<int> pinned_corners) {
  Segmentation result;
  std::sort(pinned_corners.begin(), pinned_corners.end());
  pinned_corners.erase(std::unique(pinned_corners.begin(), pinned_corners.end()), pinned_corners.end());
  result.pinned_corners = std::move(pinned_corners);
  result.n_fold_splits = n_fold_splits;
  result.n_bevel_crease_edges = s.n_bevel_crease_edges;
  result.sharp_crease_edges = s.sharp_crease_edges;
  result.n_islands_absorbed = n_islands_absorbed;
  std::sort(island_faces.begin(), island_faces.end());
  island_faces.erase(std::unique(island_faces.begin(), island_faces.end()), island_faces.end());
  result.island_faces = std::move(island_faces);
  renumber(patches, segment_detail::worker_count(s.options.threads));
  finish_segmentation(s.mesh, s.counts, patches, s.options, result, with_borders);
  return result;
}

}  // namespace

Segmentation segment(const TriMesh& mesh, const SegmentOptions& options) {
  return segment_detail::segment(mesh, options, mean_edge_length(mesh));
}

Segmentation segment_detail::segment(const TriMesh& mesh, const SegmentOptions& options, const double mean_edge,
                                     SplitterPtr* splitter, const bool with_borders) {
  options.validate();
  validate_mesh(mesh);
  Segmentation result;
  if (mesh.n_faces() == 0) return result;
  constexpr std::string_view kStage = "segment";
  report_progress(options.progress, kStage, 0.0);

  FaceGraph graph = segment_detail::build_graph(mesh, segment_detail::worker_count(options.threads));
  FaceNormals normals = prepare_normals(graph, options, result);
  const double max_slope = radians(options.max_slope_deg);
  report_progress(options.progress, kStage, 0.3);

  const Grouping grouping{graph, normals, std::cos(max_slope), max_slope,
                          std::cos(kGrowthConeFraction * max_slope)};
  Patches patches = grow_regions(grouping);
  report_progress(options.progress, kStage, 0.5);
  const unsigned workers = segment_detail::worker_count(options.threads);
  merge_patches(grouping, options.min_patch_faces, patches, nullptr, workers);
  clean_borders(grouping, patches);
  renumber(patches, workers);
  refine_axes(grouping, patches, workers);
  auto own_scratch = std::make_unique<Scratch>(mesh);
  Scratch& scratch = *own_scratch;
  std::vector<std::unique_ptr<Scratch>> worker_scratch;
  result.n_fold_splits = split_folds(grouping, mean_edge, scratch, patches, all_patches(patches),
                                     segment_detail::worker_count(options.threads), worker_scratch);
  if (result.n_fold_splits > 0) merge_patches(grouping, options.min_patch_faces, patches, &scratch, workers);
  result.n_islands_absorbed =
      absorb_tiny_islands(grouping, kSegmentTinyIslandPerimeterEdges * mean_edge, patches, scratch,
                          result.island_faces);
  std::sort(result.island_faces.begin(), result.island_faces.end());
  renumber(patches, workers);
  report_progress(options.progress, kStage, 0.7);

  const FaceCounts counts = face_counts(graph, normals);
  finish_segmentation(mesh, counts, patches, options, result, with_borders);
  if (splitter != nullptr) {
    splitter->reset(new Splitter(mesh, options));
    Splitter& kept = **splitter;
    kept.graph = std::move(graph);
    kept.normals = std::move(normals);
    kept.n_bevel_crease_edges = result.n_bevel_crease_edges;
    kept.sharp_crease_edges = result.sharp_crease_edges;
    kept.counts = counts;
    kept.mean_edge = mean_edge;
    kept.prepared = true;
    kept.scratch = std::move(own_scratch);
    kept.worker_scratch = std::move(worker_scratch);
  }
  report_progress(options.progress, kStage, 1.0);
  return result;
}

struct PatchSplitter::Impl : segment_detail::Splitter {
  using Splitter::Splitter;
};

PatchSplitter::PatchSplitter(const TriMesh& mesh, const SegmentOptions& options) : impl_(std::make_unique<Impl>(mesh, options)) {
  options.validate();
  validate_mesh(mesh);
}

PatchSplitter::~PatchSplitter() = default;

Segmentation PatchSplitter::split(const Segmentation& segmentation, const std::vector<int>& which) {
  return segment_detail::split(*impl_, segmentation, which);
}

Segmentation segment_detail::split(Splitter& s, const Segmentation& segmentation, const std::vector<int>& which,
                                   const bool with_borders, const bool checked_input) {
  const auto n_faces = static_cast<int>(s.mesh.n_faces());
  const auto n_patches = static_cast<int>(segmentation.patches.size());
  if (!checked_input) check_edit(s, segmentation, which, "split_patches");
  Segmentation result;
  result.n_fold_splits = segmentation.n_fold_splits;
  if (n_faces == 0 || which.empty()) return segmentation;

  s.prepare();
  result.n_bevel_crease_edges = s.n_bevel_crease_edges;
  result.sharp_crease_edges = s.sharp_crease_edges;
  result.n_islands_absorbed = segmentation.n_islands_absorbed;  // they stay where they are
  result.island_faces = segmentation.island_faces;
  result.pinned_corners = segmentation.pinned_corners;
  const Grouping grouping = splitter_grouping(s);
  Patches patches = editable_patches(segmentation);
  // The last result again: its patches that are not split pass split_folds' checks as they did.
  const bool checked = segmentation.face_patch == s.last_face_patch && patches.axes == s.last_axes;
  if (!s.scratch) s.scratch = std::make_unique<Scratch>(s.mesh);
  Scratch& scratch = *s.scratch;
  std::vector<int> sorted = which;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  for (const int p : sorted) {
    const std::vector<int>& faces = patches.faces[static_cast<std::size_t>(p)];
    const std::size_t min_part = std::max<std::size_t>(1, std::min(s.options.min_patch_faces, faces.size() / 4));
    auto parts = split_by_normals(grouping, faces, p, patches.face_patch, patches.axes[static_cast<std::size_t>(p)],
                                  min_part, scratch);
    if (parts.empty()) continue;
    const Eigen::Vector3d old_axis = patches.axes[static_cast<std::size_t>(p)];
    for (std::size_t k = 0; k < parts.size(); ++k) {
      const int q = k == 0 ? p : static_cast<int>(patches.faces.size());
      if (k > 0) {
        patches.faces.emplace_back();
        patches.axes.push_back(old_axis);
      }
      for (const int f : parts[k].first) patches.face_patch[f] = q;
      patches.faces[static_cast<std::size_t>(q)] = std::move(parts[k].first);
      patches.axes[static_cast<std::size_t>(q)] = parts[k].second;
    }
    // A part's own axis may fold its projection where the patch's did not: the patch's axis
    // then (any subset of a graph is a graph); split_folds handles what is still left.
    for (std::size_t k = 0; k < parts.size(); ++k) {
      const int q = k == 0 ? p : static_cast<int>(patches.faces.size() - parts.size() + k);
      auto& axis = patches.axes[static_cast<std::size_t>(q)];
      if (axis == old_axis) continue;
      if (!segment_detail::check_projection(s.graph, patches.faces[static_cast<std::size_t>(q)], patches.face_patch, axis,
                                            scratch)
               .is_simple)
        axis = old_axis;
    }
  }
  std::vector<int> work = all_patches(patches);
  if (checked)
    std::erase_if(work, [&](int p) { return p < n_patches && !std::binary_search(sorted.begin(), sorted.end(), p); });
  result.n_fold_splits += split_folds(grouping, s.mean_edge, scratch, patches, std::move(work),
                                      segment_detail::worker_count(s.options.threads), s.worker_scratch);
  renumber(patches, segment_detail::worker_count(s.options.threads));
  finish_segmentation(s.mesh, s.counts, patches, s.options, result, with_borders);
  s.last_face_patch = result.face_patch;
  s.last_axes.clear();
  for (const Patch& patch : result.patches) s.last_axes.push_back(patch.axis);
  return result;
}

Segmentation segment_detail::merge_into_neighbours(Splitter& s, const Segmentation& segmentation,
                                                   const std::vector<int>& which, const bool with_borders,
                                                   const bool hairlines, const bool steep,
                                                   std::vector<std::uint8_t>* exempt_faces, const int max_lost_corners,
                                                   const double pin_below_deg) {
  const bool pin_lost_corners = max_lost_corners >= 0 && pin_below_deg > 0.0;
  const double cos_pin = std::cos(radians(std::min(pin_below_deg, 180.0)));
  check_edit(s, segmentation, which, "merge_patches_into_neighbours");
  if (s.mesh.n_faces() == 0 || which.empty()) return segmentation;
  s.prepare();
  const Grouping grouping = splitter_grouping(s);
  Patches patches = editable_patches(segmentation);
  Scratch scratch(s.mesh);
  std::vector<int> island_faces = segmentation.island_faces;
  std::vector<int> pinned = segmentation.pinned_corners;  // ascending
  const auto is_pinned = [&](int v) { return std::binary_search(pinned.begin(), pinned.end(), v); };
  std::size_t n_merged = 0;
  // Hairlines go only into a patch that is not listed itself (a wide one).
  std::vector<int> listed = hairlines ? which : std::vector<int>{};
  std::sort(listed.begin(), listed.end());
  // The faces of the hairlines (1) and steep patches (2) joined so far, by this call or an
  // earlier one: exempt from the bounds again when a second one joins the same neighbour.
  std::vector<std::uint8_t> own_exempt;
  std::vector<std::uint8_t>& exempt = exempt_faces != nullptr ? *exempt_faces : own_exempt;
  if (hairlines && exempt.size() != s.mesh.n_faces()) exempt.assign(s.mesh.n_faces(), 0);
  for (const int p : which) {
    auto& faces = patches.faces[static_cast<std::size_t>(p)];
    if (faces.empty()) continue;  // merged already
    // Neighbours by the length of the border shared with p, longest first (ties: lower id).
    std::vector<std::pair<double, int>> shared;
    for (const int f : faces) {
      for (int i = 0; i < 3; ++i) {
        const int g = s.graph.neighbours[f][i];
        if (g < 0 || patches.face_patch[g] == p) continue;
        const int q = patches.face_patch[g];
        const auto a = s.mesh.point(s.mesh.vertex_handle(static_cast<unsigned>(s.graph.vertices[f][i])));
        const auto b = s.mesh.point(s.mesh.vertex_handle(static_cast<unsigned>(s.graph.vertices[f][(i + 1) % 3])));
        auto it = std::find_if(shared.begin(), shared.end(), [&](const auto& e) { return e.second == q; });
        if (it == shared.end()) it = shared.insert(shared.end(), {0.0, q});
        it->first += (a - b).norm();
      }
    }
    std::sort(shared.begin(), shared.end(),
              [](const auto& x, const auto& y) { return x.first != y.first ? x.first > y.first : x.second < y.second; });
    // A hairline faces away: for every neighbour's axis some face of it has its raw normal
    // outside the slope cone. A narrow patch whose faces all lie in a neighbour's cone (a
    // designed chamfer, fandisk's crease end) is left alone.
    if (hairlines && !steep && std::any_of(shared.begin(), shared.end(), [&](const auto& entry) {
          const Eigen::Vector3d& axis = patches.axes[static_cast<std::size_t>(entry.second)];
          return std::all_of(faces.begin(), faces.end(),
                             [&](int f) { return s.normals.raw[f].dot(axis) >= grouping.cos_slope; });
        }))
      continue;
    // The corners among p's vertices (3+ sides meet: patches, or the input's boundary as one;
    // or pinned), counted before a join; a join that leaves more than max_lost_corners of them
    // with two sides is refused (the corner guard). With pin_lost_corners, a corner left with
    // two sides is pinned instead (it stays a curve end) and only one left inside the union
    // counts.
    std::vector<int> corners;
    const auto n_sides = [&](int v) {
      int ids[16];
      int n = 0;
      bool open = false;
      for (auto h : s.mesh.voh_range(TriMesh::VertexHandle(v))) {
        const auto f = s.mesh.face_handle(h);
        if (!f.is_valid()) {
          open = true;
          continue;
        }
        const int id = patches.face_patch[f.idx()];
        if (std::find(ids, ids + n, id) == ids + n && n < 16) ids[n++] = id;
      }
      return n + (open ? 1 : 0);
    };
    if (max_lost_corners >= 0) {
      for (const int f : faces)
        for (int i = 0; i < 3; ++i) corners.push_back(s.graph.vertices[f][i]);
      std::sort(corners.begin(), corners.end());
      corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
      std::erase_if(corners, [&](int v) { return n_sides(v) < 3 && !(pin_lost_corners && is_pinned(v)); });
    }
    // Whether the border through v (two sides) turns by more than a pin allows: the angle at v
    // between the border vertices kPinWalk edges away on both sides below pin_below_deg (a
    // fin's tip); a vertex with other than two border edges is pinned.
    constexpr int kPinWalk = 2;
    const auto is_border = [&](OpenMesh::HalfedgeHandle h) {
      const OpenMesh::FaceHandle f = s.mesh.face_handle(h), g = s.mesh.opposite_face_handle(h);
      return !f.is_valid() || !g.is_valid() || patches.face_patch[f.idx()] != patches.face_patch[g.idx()];
    };
    const auto is_sharp = [&](int v) {
      if (pin_below_deg >= 180.0) return true;
      std::array<Eigen::Vector3d, 2> ends;
      int n_ends = 0;
      for (auto out : s.mesh.voh_range(TriMesh::VertexHandle(v))) {
        if (!is_border(out)) continue;
        if (n_ends == 2) return true;
        OpenMesh::HalfedgeHandle h = out;
        for (int step = 1; step < kPinWalk; ++step) {
          OpenMesh::HalfedgeHandle next;
          int n_next = 0;
          for (auto o : s.mesh.voh_range(s.mesh.to_vertex_handle(h)))
            if (o != s.mesh.opposite_halfedge_handle(h) && is_border(o)) {
              next = o;
              ++n_next;
            }
          if (n_next != 1) break;
          h = next;
        }
        ends[static_cast<std::size_t>(n_ends++)] = s.graph.points[s.mesh.to_vertex_handle(h).idx()];
      }
      if (n_ends != 2) return true;
      const Eigen::Vector3d a = ends[0] - s.graph.points[v], b = ends[1] - s.graph.points[v];
      return a.dot(b) > cos_pin * a.norm() * b.norm();
    };
    const auto is_lost = [&](int v) {
      const int n = n_sides(v);
      return n < 3 && !(pin_lost_corners && n == 2);
    };
    // Joins p to q if the union fits an axis (faces joined across creases are island faces).
    const auto join = [&](int q) {
      auto& target = patches.faces[static_cast<std::size_t>(q)];
      const std::size_t n_target = target.size();
      target.insert(target.end(), faces.begin(), faces.end());
      for (const int f : faces) patches.face_patch[f] = q;
      // The corner guard: a fin's tip is pinned by its corners (the output has nodes there, on
      // the input); joined away, they leave the tip to the smoothed curve and the fit
      // (headsq@1150: 1.14 mean edges off, docs/segment.md "Fin strips: a corner guard").
      const bool keeps_corners =
          max_lost_corners < 0 || std::count_if(corners.begin(), corners.end(), is_lost) <= max_lost_corners;
      // The neighbour's axis, else the union's area-weighted mean raw normal.
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const int f : target) mean += s.normals.area[f] * s.normals.raw[f];
      std::vector<Eigen::Vector3d> axes{patches.axes[static_cast<std::size_t>(q)]};
      if (mean.norm() > 0.0) axes.push_back(mean.normalized());
      for (const Eigen::Vector3d& axis : keeps_corners ? axes : std::vector<Eigen::Vector3d>{}) {
        // A hairline's own faces are exempt from the bounds (and those of the hairlines
        // joined to q before): a strip folded back between two creases faces away from both
        // sides (docs/segment.md "Hairline patches").
        const auto bounded_end = target.begin() + static_cast<std::ptrdiff_t>(hairlines ? n_target : target.size());
        if (!std::all_of(target.begin(), bounded_end,
                         [&](int f) {
                           const std::uint8_t mark = hairlines ? exempt[static_cast<std::size_t>(f)] : 0;
                           return mark == 1 || (mark == 2 && s.normals.raw[f].dot(axis) >= kSegmentMinRawNormalDot) ||
                                  grouping.fits(f, axis);
                         }))
          continue;
        // Steep narrow patches face the union's plane: no face of theirs folds over it.
        if (steep && !std::all_of(bounded_end, target.end(),
                                  [&](int f) { return s.normals.raw[f].dot(axis) >= kSegmentMinRawNormalDot; }))
          continue;
        if (!segment_detail::check_projection(s.graph, target, patches.face_patch, axis, scratch).is_simple) continue;
        if (segment_detail::has_cliff(s.graph, target, axis, s.mean_edge, scratch)) continue;  // segment()'s step 7, both halves
        patches.axes[static_cast<std::size_t>(q)] = axis;
        island_faces.insert(island_faces.end(), faces.begin(), faces.end());
        if (hairlines)
          for (const int f : faces) exempt[static_cast<std::size_t>(f)] = steep ? 2 : 1;
        if (pin_lost_corners)
          for (const int v : corners)
            if (n_sides(v) == 2 && !is_pinned(v) && is_sharp(v))
              pinned.insert(std::upper_bound(pinned.begin(), pinned.end(), v), v);
        faces.clear();
        return true;
      }
      target.resize(n_target);
      for (const int f : faces) patches.face_patch[f] = p;
      return false;
    };
    for (const auto& entry : shared) {
      if (std::binary_search(listed.begin(), listed.end(), entry.second)) continue;
      if (!join(entry.second)) continue;
      ++n_merged;
      break;
    }
  }
  if (n_merged == 0) return segmentation;
  return finish_edit(s, patches, segmentation.n_fold_splits, segmentation.n_islands_absorbed + n_merged,
                     std::move(island_faces), with_borders, std::move(pinned));
}

Segmentation segment_detail::widen_patches(Splitter& s, const Segmentation& segmentation, const std::vector<int>& which,
                                          const double min_width, const bool with_borders, std::size_t* n_widened) {
  check_edit(s, segmentation, which, "widen_patches");
  if (!(std::isfinite(min_width) && min_width >= 0.0)) throw InvalidInput("widen_patches: min_width must be finite and >= 0");
  if (n_widened != nullptr) *n_widened = 0;
  if (s.mesh.n_faces() == 0 || which.empty() || min_width == 0.0) return segmentation;
  s.prepare();
  const Grouping grouping = splitter_grouping(s);
  const FaceGraph& graph = s.graph;
  Patches patches = editable_patches(segmentation);
  Scratch scratch(s.mesh);
  std::vector<int> listed = which;
  std::sort(listed.begin(), listed.end());
  const auto is_listed = [&](int q) { return std::binary_search(listed.begin(), listed.end(), q); };
  // 2 area / border length of a patch's input faces (the border: edges to another patch or none).
  const auto width_of = [&](const std::vector<int>& faces, int p) {
    double area = 0.0, border = 0.0;
    for (const int f : faces) {
      area += s.normals.area[f];
      for (int i = 0; i < 3; ++i) {
        const int g = graph.neighbours[f][i];
        if (g >= 0 && patches.face_patch[g] == p) continue;
        border += (graph.points[graph.vertices[f][i]] - graph.points[graph.vertices[f][(i + 1) % 3]]).norm();
      }
    }
    return border > 0.0 ? 2.0 * area / border : std::numeric_limits<double>::infinity();
  };
  // Whether the faces of patch q form one edge-connected piece.
  std::vector<int> seen(static_cast<std::size_t>(graph.n_faces()), -1);
  int stamp = 0;
  const auto is_connected = [&](const std::vector<int>& faces, int q) {
    if (faces.empty()) return false;
    ++stamp;
    std::vector<int> queue{faces.front()};
    seen[faces.front()] = stamp;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const int f = queue[head];
      for (int i = 0; i < 3; ++i) {
        const int g = graph.neighbours[f][i];
        if (g < 0 || patches.face_patch[g] != q || seen[g] == stamp) continue;
        seen[g] = stamp;
        queue.push_back(g);
      }
    }
    return queue.size() == faces.size();
  };
  // Per face: the last (patch, ring) that took it as a candidate.
  std::vector<int> in_ring(static_cast<std::size_t>(graph.n_faces()), -1);
  std::size_t n_changed = 0;
  for (std::size_t k_patch = 0; k_patch < which.size(); ++k_patch) {
    const int p = which[k_patch];
    const Eigen::Vector3d axis = patches.axes[static_cast<std::size_t>(p)];
    bool widened = false;
    for (int round = 0; round < kWidenMaxRings; ++round) {
      const int ring_stamp = static_cast<int>(k_patch) * kWidenMaxRings + round;
      std::vector<int>& faces = patches.faces[static_cast<std::size_t>(p)];
      const double old_width = width_of(faces, p);
      if (old_width >= min_width) break;
      // The ring: faces of unlisted neighbours across an edge that is no crease, within p's bounds.
      std::vector<int> ring;
      for (const int f : faces) {
        for (int i = 0; i < 3; ++i) {
          const int g = graph.neighbours[f][i];
          if (g < 0 || graph.is_crease(f, i) || in_ring[g] == ring_stamp) continue;
          const int q = patches.face_patch[g];
          if (q == p || is_listed(q) || !grouping.fits(g, axis)) continue;
          in_ring[g] = ring_stamp;
          ring.push_back(g);
        }
      }
      // Faces of the givers left with two edges on p and the ring (the teeth between ring faces)
      // join too: else the ring's sawtooth lengthens p's border more than it adds area.
      for (std::size_t k = 0; k < ring.size(); ++k) {
        for (int i = 0; i < 3; ++i) {
          const int g = graph.neighbours[ring[k]][i];
          if (g < 0 || graph.is_crease(ring[k], i) || in_ring[g] == ring_stamp) continue;
          const int q = patches.face_patch[g];
          if (q == p || is_listed(q) || !grouping.fits(g, axis)) continue;
          int n_inside = 0;
          for (int j = 0; j < 3; ++j) {
            const int h = graph.neighbours[g][j];
            n_inside += h >= 0 && (patches.face_patch[h] == p || in_ring[h] == ring_stamp) ? 1 : 0;
          }
          if (n_inside < 2) continue;
          in_ring[g] = ring_stamp;
          ring.push_back(g);
        }
      }
      // No crease inside p: a ring face with a crease edge to p or to another ring face stays.
      // The faces dropped keep their stamp on purpose: both faces across a crease inside the
      // ring go, whatever their order (clearing stamps as faces go would keep the later one
      // of each pair, depending on the ring's order). No later test reads these stamps: each
      // (patch, round) has its own ring_stamp.
      std::erase_if(ring, [&](int g) {
        for (int k = 0; k < 3; ++k) {
          const int h = graph.neighbours[g][k];
          if (h >= 0 && graph.is_crease(g, k) && (patches.face_patch[h] == p || in_ring[h] == ring_stamp)) return true;
        }
        return false;
      });
      if (ring.empty()) break;
      std::sort(ring.begin(), ring.end());
      // Move the ring, then check p and every neighbour that gave faces; undo it all otherwise.
      std::vector<int> from(ring.size());
      std::vector<int> givers;
      for (std::size_t k = 0; k < ring.size(); ++k) {
        from[k] = patches.face_patch[ring[k]];
        givers.push_back(from[k]);
        patches.face_patch[ring[k]] = p;
      }
      std::sort(givers.begin(), givers.end());
      givers.erase(std::unique(givers.begin(), givers.end()), givers.end());
      for (const int q : givers)
        std::erase_if(patches.faces[static_cast<std::size_t>(q)], [&](int f) { return patches.face_patch[f] != q; });
      const std::size_t n_old = faces.size();
      faces.insert(faces.end(), ring.begin(), ring.end());
      bool ok = width_of(faces, p) > old_width &&
                segment_detail::check_projection(graph, faces, patches.face_patch, axis, scratch).is_simple &&
                !segment_detail::has_cliff(graph, faces, axis, s.mean_edge, scratch);
      for (std::size_t k = 0; ok && k < givers.size(); ++k) {
        const int q = givers[k];
        const auto& given = patches.faces[static_cast<std::size_t>(q)];
        ok = is_connected(given, q) && width_of(given, q) >= min_width &&
             segment_detail::check_projection(graph, given, patches.face_patch, patches.axes[static_cast<std::size_t>(q)],
                                              scratch)
                 .is_simple;
      }
      if (!ok) {
        faces.resize(n_old);
        for (std::size_t k = 0; k < ring.size(); ++k) {
          patches.face_patch[ring[k]] = from[k];
          patches.faces[static_cast<std::size_t>(from[k])].push_back(ring[k]);
        }
        for (const int q : givers) std::sort(patches.faces[static_cast<std::size_t>(q)].begin(), patches.faces[static_cast<std::size_t>(q)].end());
        break;
      }
      widened = true;
    }
    n_changed += widened ? 1 : 0;
  }
  if (n_widened != nullptr) *n_widened = n_changed;
  if (n_changed == 0) return segmentation;
  return finish_edit(s, patches, segmentation.n_fold_splits, segmentation.n_islands_absorbed, segmentation.island_faces,
                     with_borders, segmentation.pinned_corners);
}

Segmentation segment_detail::bisect_patches(Splitter& s, const Segmentation& segmentation, const std::vector<int>& which) {
  check_edit(s, segmentation, which, "bisect_patches");
  s.prepare();
  const Grouping grouping = splitter_grouping(s);
  Patches patches = editable_patches(segmentation);
  Scratch scratch(s.mesh);
  std::vector<int> work;
  std::vector<int> sorted = which;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  for (const int p : sorted) {
    auto& faces = patches.faces[static_cast<std::size_t>(p)];
    if (faces.size() < 2) continue;
    auto [first, second] = segment_detail::bisect_patch(s.graph, faces, patches.face_patch, scratch);
    const int q = static_cast<int>(patches.faces.size());
    for (const int f : second) patches.face_patch[f] = q;
    faces = std::move(first);
    patches.faces.push_back(std::move(second));
    patches.axes.push_back(patches.axes[static_cast<std::size_t>(p)]);
    work.push_back(p);
    work.push_back(q);
  }
  if (work.empty()) return segmentation;
  const std::size_t n_fold_splits =
      segmentation.n_fold_splits + split_folds(grouping, s.mean_edge, scratch, patches, work,
                                               segment_detail::worker_count(s.options.threads), s.worker_scratch);
  return finish_edit(s, patches, n_fold_splits, segmentation.n_islands_absorbed, segmentation.island_faces, true,
                     segmentation.pinned_corners);
}

Segmentation segment_detail::with_borders(const TriMesh& mesh, const SegmentOptions& options, Segmentation segmentation) {
  options.validate();
  if (segmentation.face_patch.size() != mesh.n_faces())
    throw InvalidInput("with_borders: the segmentation has " + std::to_string(segmentation.face_patch.size()) +
                       " face labels for " + std::to_string(mesh.n_faces()) + " faces");
  const auto n_patches = static_cast<int>(segmentation.patches.size());
  for (const int p : segmentation.face_patch)
    if (p < 0 || p >= n_patches) throw InvalidInput("with_borders: a face has patch id " + std::to_string(p));
  attach_borders(mesh, options, segmentation);
  return segmentation;
}

Segmentation merge_patches_into_neighbours(const TriMesh& mesh, const Segmentation& segmentation,
                                           const std::vector<int>& which, const SegmentOptions& options) {
  options.validate();
  validate_mesh(mesh);
  segment_detail::Splitter splitter(mesh, options);
  return segment_detail::merge_into_neighbours(splitter, segmentation, which);
}

std::vector<int> narrow_patches(const TriMesh& mesh, const Segmentation& segmentation, double max_width) {
  return segment_detail::narrow_patches(mesh, segmentation, max_width, 1);
}

std::vector<int> segment_detail::narrow_patches(const TriMesh& mesh, const Segmentation& segmentation, double max_width,
                                                unsigned workers) {
  if (!std::isfinite(max_width)) throw InvalidInput("narrow_patches: max_width must be finite");
  if (segmentation.face_patch.size() != mesh.n_faces())
    throw InvalidInput("narrow_patches: the segmentation is not one of this mesh");
  const std::size_t n_patches = segmentation.patches.size();
  for (const int p : segmentation.face_patch)
    if (p < 0 || static_cast<std::size_t>(p) >= n_patches) throw InvalidInput("narrow_patches: a face has no valid patch");
  const auto patch_of = [&](OpenMesh::HalfedgeHandle h) {
    const auto f = mesh.face_handle(h);
    return f.is_valid() ? segmentation.face_patch[static_cast<std::size_t>(f.idx())] : -1;
  };
  // The faces' areas and the edges between two patches (or on the boundary) with their
  // lengths on `workers` threads; the sums below add them in face and edge order on this
  // thread, as one serial pass would (the same doubles for any thread count).
  struct BorderEdge {
    int a, b;
    double length;
  };
  const std::size_t n_faces = mesh.n_faces(), n_edges = mesh.n_edges();
  const std::size_t n_face_chunks = (n_faces + kFaceChunk - 1) / kFaceChunk;
  const std::size_t n_edge_chunks = (n_edges + kFaceChunk - 1) / kFaceChunk;
  std::vector<double> face_area(n_faces);
  std::vector<std::vector<BorderEdge>> chunk_edges(n_edge_chunks);  // each chunk's in edge order
  segment_detail::parallel_chunks(n_face_chunks + n_edge_chunks, workers, 1, [&](std::size_t first, std::size_t last, unsigned) {
    for (std::size_t c = first; c < last; ++c) {
      if (c < n_face_chunks) {
        for (std::size_t f = c * kFaceChunk; f < std::min(n_faces, (c + 1) * kFaceChunk); ++f) {
          const auto fh = mesh.face_handle(static_cast<int>(f));
          face_area[f] = mesh.has_face_status() && mesh.status(fh).deleted() ? 0.0 : mesh.calc_face_area(fh);
        }
        continue;
      }
      const std::size_t k = c - n_face_chunks;
      for (std::size_t i = k * kFaceChunk; i < std::min(n_edges, (k + 1) * kFaceChunk); ++i) {
        const auto e = mesh.edge_handle(static_cast<int>(i));
        if (mesh.has_edge_status() && mesh.status(e).deleted()) continue;  // as edges() skips them
        const int a = patch_of(mesh.halfedge_handle(e, 0)), b = patch_of(mesh.halfedge_handle(e, 1));
        if (a != b) chunk_edges[k].push_back({a, b, mesh.calc_edge_length(e)});
      }
    }
  });
  std::vector<double> area(n_patches, 0.0);
  std::vector<double> border(n_patches, 0.0);
  for (std::size_t f = 0; f < n_faces; ++f) area[static_cast<std::size_t>(segmentation.face_patch[f])] += face_area[f];
  for (const auto& edges : chunk_edges)
    for (const BorderEdge& e : edges) {
      if (e.a >= 0) border[static_cast<std::size_t>(e.a)] += e.length;
      if (e.b >= 0) border[static_cast<std::size_t>(e.b)] += e.length;
    }
  std::vector<double> width(n_patches, std::numeric_limits<double>::infinity());
  for (std::size_t p = 0; p < n_patches; ++p)
    if (border[p] > 0.0) width[p] = 2.0 * area[p] / border[p];
  // Only a narrow patch next to a wide one: a small closed shape whose every side is narrow
  // (a box smaller than max_width) would collapse if its sides joined one another.
  std::vector<std::uint8_t> wide_neighbour(n_patches, 0);
  for (const auto& edges : chunk_edges)
    for (const BorderEdge& e : edges) {
      if (e.a < 0 || e.b < 0) continue;
      if (width[static_cast<std::size_t>(e.b)] >= max_width) wide_neighbour[static_cast<std::size_t>(e.a)] = 1;
      if (width[static_cast<std::size_t>(e.a)] >= max_width) wide_neighbour[static_cast<std::size_t>(e.b)] = 1;
    }
  std::vector<std::pair<double, int>> narrow;
  for (std::size_t p = 0; p < n_patches; ++p)
    if (width[p] < max_width && wide_neighbour[p] != 0) narrow.emplace_back(width[p], static_cast<int>(p));
  std::sort(narrow.begin(), narrow.end());
  std::vector<int> result;
  result.reserve(narrow.size());
  for (const auto& entry : narrow) result.push_back(entry.second);
  return result;
}

std::vector<int> tiny_patches(const TriMesh& mesh, const Segmentation& segmentation, std::size_t max_faces,
                              double max_dihedral_deg) {
  if (!std::isfinite(max_dihedral_deg)) throw InvalidInput("tiny_patches: max_dihedral_deg must be finite");
  if (segmentation.face_patch.size() != mesh.n_faces())
    throw InvalidInput("tiny_patches: the segmentation is not one of this mesh");
  const std::size_t n_patches = segmentation.patches.size();
  const auto is_tiny = [&](int p) {
    const std::size_t n = segmentation.patches[static_cast<std::size_t>(p)].faces.size();
    return n >= 1 && n <= max_faces;
  };
  // Per patch: every shared edge bends by at most the bound; it touches a larger patch.
  std::vector<std::uint8_t> marginal(n_patches, 1);
  std::vector<std::uint8_t> large_neighbour(n_patches, 0);
  std::vector<int> first_neighbour(n_patches, -1);
  std::vector<std::uint8_t> two_neighbours(n_patches, 0);
  const double cos_max = std::cos(max_dihedral_deg * std::numbers::pi / 180.0);
  for (const auto e : mesh.edges()) {
    if (e.is_boundary()) continue;
    const auto f0 = e.h0().face(), f1 = e.h1().face();
    const int a = segmentation.face_patch[static_cast<std::size_t>(f0.idx())];
    const int b = segmentation.face_patch[static_cast<std::size_t>(f1.idx())];
    if (a < 0 || b < 0 || static_cast<std::size_t>(a) >= n_patches || static_cast<std::size_t>(b) >= n_patches)
      throw InvalidInput("tiny_patches: a face has no valid patch");
    if (a == b || !(is_tiny(a) || is_tiny(b))) continue;
    const auto n0 = mesh.calc_face_normal(f0), n1 = mesh.calc_face_normal(f1);
    // A degenerate face (zero normal) bends by nothing we can measure: not marginal.
    const bool bends_little = n0.sqrnorm() > 0.0 && n1.sqrnorm() > 0.0 && OpenMesh::dot(n0, n1) >= cos_max;
    for (const auto& [p, q] : {std::pair{a, b}, std::pair{b, a}}) {
      if (!bends_little) marginal[static_cast<std::size_t>(p)] = 0;
      if (!is_tiny(q)) large_neighbour[static_cast<std::size_t>(p)] = 1;
      int& first = first_neighbour[static_cast<std::size_t>(p)];
      if (first < 0) first = q;
      else if (first != q) two_neighbours[static_cast<std::size_t>(p)] = 1;
    }
  }
  std::vector<std::pair<std::size_t, int>> tiny;
  for (std::size_t p = 0; p < n_patches; ++p) {
    const int id = static_cast<int>(p);
    if (is_tiny(id) && marginal[p] != 0 && large_neighbour[p] != 0 && two_neighbours[p] != 0)
      tiny.emplace_back(segmentation.patches[p].faces.size(), id);
  }
  std::sort(tiny.begin(), tiny.end());
  std::vector<int> result;
  result.reserve(tiny.size());
  for (const auto& entry : tiny) result.push_back(entry.second);
  return result;
}

double gap_crease_angle(const TriMesh& mesh, double crease_angle_deg) {
  if (!(crease_angle_deg > 0.0 && crease_angle_deg <= 180.0))
    throw InvalidInput("gap_crease_angle: crease_angle_deg must be in (0, 180]");
  // Interior edges per 5-deg bin of bend up to the crease angle (an edge bending by exactly
  // the crease angle is no crease): bin i holds (crease - 5 (i + 1), crease - 5 i].
  constexpr double kStep = 5.0;
  constexpr int kSteps = 3;     // candidates down to crease - 15
  constexpr int kValley = 3;    // the valley: 15 deg below a candidate
  std::array<std::size_t, kSteps + kValley> bins{};
  std::size_t n_edges = 0;
  for (const auto e : mesh.edges()) {
    if (e.is_boundary()) continue;
    const auto n0 = mesh.calc_face_normal(e.h0().face()), n1 = mesh.calc_face_normal(e.h1().face());
    const double l0 = n0.norm(), l1 = n1.norm();
    if (!(l0 > 0.0 && l1 > 0.0)) continue;
    ++n_edges;
    const double bend = std::acos(std::clamp(OpenMesh::dot(n0, n1) / (l0 * l1), -1.0, 1.0)) * 180.0 / std::numbers::pi;
    if (!(bend <= crease_angle_deg)) continue;  // also a NaN bend (non-finite coordinates)
    const auto bin = static_cast<std::size_t>((crease_angle_deg - bend) / kStep);
    if (bin < bins.size()) ++bins[bin];
  }
  std::size_t above = 0;  // edges bending by more than c, at most the crease angle
  for (int i = 0; i < kSteps; ++i) {
    above += bins[static_cast<std::size_t>(i)];
    const double c = crease_angle_deg - kStep * (i + 1);
    if (c <= 0.0) break;
    std::size_t valley = 0;
    for (int j = 1; j <= kValley; ++j) valley += bins[static_cast<std::size_t>(i + j)];
    if (static_cast<double>(above) >= kCreaseGapMinShare * static_cast<double>(n_edges) &&
        static_cast<double>(valley) <= kCreaseGapMaxValley * static_cast<double>(above))
      return c;
  }
  return crease_angle_deg;
}

Segmentation split_patches(const TriMesh& mesh, const Segmentation& segmentation, const std::vector<int>& which,
                           const SegmentOptions& options) {
  return PatchSplitter(mesh, options).split(segmentation, which);
}

}  // namespace nurbsfront
