// SPDX-License-Identifier: BSD-3-Clause
// Border curves: validation against the mesh, one discretisation per curve, feature flags.

#include <algorithm>
#include <map>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>
#include <utility>

#include <Eigen/Geometry>

#include "nurbsfront/core/disjoint_sets.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/front2d/predicates.h"
#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront::surfmesh_detail {

namespace {

[[noreturn]] void mismatch(const std::string& what) {
  throw InvalidInput("mesh_surface: the segmentation does not match the mesh: " + what);
}

Eigen::Vector3d point(const TriMesh& mesh, int v) { return to_eigen(mesh.point(TriMesh::VertexHandle(v))); }

int corner_index(const std::vector<int>& corners, int vertex) {
  const auto it = std::lower_bound(corners.begin(), corners.end(), vertex);
  if (it == corners.end() || *it != vertex) return -1;
  return static_cast<int>(it - corners.begin());
}

// Loops with fewer vertices use their input positions, not the smoothed ones (the Taubin
// steps can collapse a loop of three or four edges onto a line; measured on the level-set
// DRAM cell at 128 cells, a one-face patch).
constexpr std::size_t kMinSmoothedLoopVertices = 8;

// A piece may cut off at most this share of its chord length: where the curve turns
// more within one piece (a small loop, a sharp bend), the chords could fold in a patch's
// plane, so the curve gets more pieces.
constexpr double kMaxChordDeviation = 0.25;
// More pieces than this multiple of the size-driven count are never added for the chord rule.
constexpr int kMaxRefinement = 4;
// Deviations up to this multiple of the polyline's roughness (the mean distance of a point
// to the chord of its two neighbours) are the curve's own zig-zag, not a bend: on
// marching-cubes inputs the smoothed borders keep some of it, and refining for it put border
// nodes 4x closer than the target size (occupancy sphere at 64 cells: min angle 18 deg, 2%
// obtuse triangles). A straight polyline with a few sharp corners has almost no roughness
// and keeps the plain chord rule.
constexpr double kZigZagRoughness = 3.0;
// Rings of faces on each side of a curve vertex whose mean normals give its crease angle.
constexpr int kCreaseRings = 3;
// Curves per chunk of the parallel crease angles (most curves have a few dozen vertices).
constexpr std::size_t kCreaseCurveChunk = 16;
// Patches per chunk of the parallel per-patch border checks.
constexpr std::size_t kPatchChunk = 8;
// Curves per chunk of discretise_borders' parallel resampling (a curve costs tens of
// microseconds: a chunk amortises the shared counter).
constexpr std::size_t kDiscretiseCurveChunk = 16;

// The sorted, distinct curve ids that curves_of(p, out) appends to `out` for the patches p
// of [0, n_patches), the patches taken on `threads` workers: the same list for any count
// (each patch's ids depend on that patch only, and the union is sorted).
template <class CurvesOf>
std::vector<int> curves_over_patches(std::size_t n_patches, unsigned threads, const CurvesOf& curves_of) {
  std::vector<int> out;
  if (threads <= 1) {
    for (std::size_t p = 0; p < n_patches; ++p) curves_of(p, out);
  } else {
    std::vector<std::vector<int>> per_patch(n_patches);
    parallel::for_chunks(n_patches, threads, kPatchChunk, [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t p = begin; p < end; ++p) curves_of(p, per_patch[p]);
    });
    for (const auto& curves : per_patch) out.insert(out.end(), curves.begin(), curves.end());
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}
// Share of the crease angle above which that ring-averaged angle marks a feature: the
// averaging over 3 rings lowers the 90 deg of a bevelled box edge to 60..90 deg (measured on
// the DRAM cell and the trench); smooth parts stay below 45 deg on the sphere, torus and
// bunny, and below 60 deg on the DRAM's cylinders at 64..128 cells.
constexpr double kCreaseShare = 0.75;

double point_segment_distance(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((q - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - q).norm();
}

// Resamples a polyline (closed: the last point joins the first) into n pieces of equal
// integral of 1 / size, n = max(min_pieces, round(integral)), raised until no polyline
// point is further than kMaxChordDeviation x chord (and kZigZagRoughness x the roughness)
// from its piece's chord. Returns the
// interior points (open: n - 1 of them, the ends are the polyline's ends) or all n points
// starting at the first polyline point (closed).
std::vector<Eigen::Vector3d> resample(const std::vector<Eigen::Vector3d>& pts, bool is_closed, int min_pieces,
                                      const SizeAt& size_at) {
  std::vector<Eigen::Vector3d> poly = pts;
  if (is_closed) poly.push_back(pts.front());
  const std::size_t m = poly.size();
  std::vector<double> inv_size(m);
  for (std::size_t i = 0; i < m; ++i) inv_size[i] = 1.0 / size_at(poly[i]);
  std::vector<double> cumulative(m, 0.0);
  for (std::size_t i = 1; i < m; ++i)
    cumulative[i] = cumulative[i - 1] + (poly[i] - poly[i - 1]).norm() * 0.5 * (inv_size[i] + inv_size[i - 1]);
  const double total = cumulative.back();
  double roughness = 0.0;
  for (std::size_t i = 1; i + 1 < m; ++i) roughness += point_segment_distance(poly[i], poly[i - 1], poly[i + 1]);
  const double zig_zag = m > 2 ? kZigZagRoughness * roughness / static_cast<double>(m - 2) : 0.0;
  const long rounded = std::lround(total);
  const int n0 = std::max(min_pieces, static_cast<int>(std::min<long>(rounded, 1L << 30)));
  std::vector<Eigen::Vector3d> nodes;  // all n + 1 piece ends, first and last = the polyline's ends
  for (int n = n0; n <= kMaxRefinement * n0; ++n) {
    nodes.assign(1, poly.front());
    std::vector<std::size_t> first_after(1, 1);  // per piece end: index of the first polyline point after it
    std::size_t seg = 1;
    for (int k = 1; k < n; ++k) {
      const double target = total * static_cast<double>(k) / static_cast<double>(n);
      while (seg + 1 < m && cumulative[seg] < target) ++seg;
      const double span = cumulative[seg] - cumulative[seg - 1];
      const double t = span > 0.0 ? std::clamp((target - cumulative[seg - 1]) / span, 0.0, 1.0) : 0.5;
      nodes.push_back((1.0 - t) * poly[seg - 1] + t * poly[seg]);
      first_after.push_back(t >= 1.0 ? seg + 1 : seg);
    }
    nodes.push_back(poly.back());
    first_after.push_back(m);
    bool is_fine = true;
    for (int k = 0; k < n && is_fine; ++k) {
      const Eigen::Vector3d& a = nodes[static_cast<std::size_t>(k)];
      const Eigen::Vector3d& b = nodes[static_cast<std::size_t>(k) + 1];
      const double limit = std::max(kMaxChordDeviation * (b - a).norm(), zig_zag);
      for (std::size_t i = first_after[static_cast<std::size_t>(k)]; i < first_after[static_cast<std::size_t>(k) + 1] && i + 1 < m; ++i)
        if (point_segment_distance(poly[i], a, b) > limit) {
          is_fine = false;
          break;
        }
    }
    if (is_fine) break;
  }
  std::vector<Eigen::Vector3d> out;
  if (is_closed) out.push_back(nodes.front());
  out.insert(out.end(), nodes.begin() + 1, nodes.end() - 1);
  return out;
}

}  // namespace

void validate_segmentation(const TriMesh& mesh, const Segmentation& seg) {
  const int n_faces = static_cast<int>(mesh.n_faces());
  const int n_vertices = static_cast<int>(mesh.n_vertices());
  const int n_edges = static_cast<int>(mesh.n_edges());
  const int n_patches = static_cast<int>(seg.patches.size());
  const int n_curves = static_cast<int>(seg.curves.size());
  if (seg.face_patch.size() != mesh.n_faces())
    mismatch(std::to_string(seg.face_patch.size()) + " face labels for " + std::to_string(mesh.n_faces()) + " faces");
  for (const int p : seg.face_patch)
    if (p < 0 || p >= n_patches) mismatch("a face has patch id " + std::to_string(p));
  for (int p = 0; p < n_patches; ++p) {
    const Patch& patch = seg.patches[static_cast<std::size_t>(p)];
    for (const int f : patch.faces)
      if (f < 0 || f >= n_faces || seg.face_patch[static_cast<std::size_t>(f)] != p)
        mismatch("patch " + std::to_string(p) + " lists face " + std::to_string(f) + " that is not its own");
    for (const int c : patch.curves)
      if (c < 0 || c >= n_curves) mismatch("patch " + std::to_string(p) + " lists curve " + std::to_string(c));
    if (!(std::abs(patch.axis.norm() - 1.0) < 1e-6)) mismatch("patch " + std::to_string(p) + " has no unit axis");
  }
  for (const int v : seg.corners)
    if (v < 0 || v >= n_vertices) mismatch("corner vertex " + std::to_string(v) + " out of range");
  if (!std::is_sorted(seg.corners.begin(), seg.corners.end())) mismatch("corners are not ascending");
  for (int c = 0; c < n_curves; ++c) {
    const BorderCurve& curve = seg.curves[static_cast<std::size_t>(c)];
    const std::string name = "curve " + std::to_string(c);
    const std::size_t nv = curve.vertices.size();
    if (nv < 2) mismatch(name + " has fewer than 2 vertices");
    if (curve.smoothed.size() != nv) mismatch(name + " has " + std::to_string(curve.smoothed.size()) + " smoothed points");
    if (curve.edges.size() != (curve.is_closed ? nv : nv - 1)) mismatch(name + " has a wrong edge count");
    if (curve.patch_left < 0 || curve.patch_left >= n_patches || curve.patch_right < -1 ||
        curve.patch_right >= n_patches || curve.patch_left == curve.patch_right)
      mismatch(name + " has invalid patch ids");
    for (const int v : curve.vertices)
      if (v < 0 || v >= n_vertices) mismatch(name + " has vertex " + std::to_string(v) + " out of range");
    for (std::size_t i = 0; i < curve.edges.size(); ++i) {
      const int e = curve.edges[i];
      if (e < 0 || e >= n_edges) mismatch(name + " has edge " + std::to_string(e) + " out of range");
      const auto h = mesh.halfedge_handle(TriMesh::EdgeHandle(e), 0);
      const int a = mesh.from_vertex_handle(h).idx();
      const int b = mesh.to_vertex_handle(h).idx();
      const int u = curve.vertices[i];
      const int w = curve.vertices[(i + 1) % nv];
      if (!((a == u && b == w) || (a == w && b == u))) mismatch(name + ": edge " + std::to_string(e) + " does not join its vertices");
    }
    for (const auto& q : curve.smoothed)
      if (!q.allFinite()) mismatch(name + " has a non-finite smoothed point");
    if (!curve.is_closed &&
        (corner_index(seg.corners, curve.vertices.front()) < 0 || corner_index(seg.corners, curve.vertices.back()) < 0))
      mismatch(name + " does not end at corners");
  }
}

std::vector<int> tiny_curve_merges(const TriMesh& mesh, const Segmentation& seg, const SizeAt& size_at, double fraction) {
  const std::size_t n_corners = seg.corners.size();
  std::vector<int> target(n_corners);
  std::iota(target.begin(), target.end(), 0);
  if (!(fraction > 0.0)) return target;
  // Corners on the input's boundary stay; so do pairs joined by a second curve (the other
  // would become a loop).
  std::vector<std::uint8_t> is_fixed(n_corners, 0);
  std::map<std::pair<int, int>, int> n_joining;
  for (const BorderCurve& curve : seg.curves) {
    if (curve.is_closed) continue;
    const int a = corner_index(seg.corners, curve.vertices.front());
    const int b = corner_index(seg.corners, curve.vertices.back());
    ++n_joining[std::minmax(a, b)];
    if (curve.patch_right < 0) is_fixed[static_cast<std::size_t>(a)] = is_fixed[static_cast<std::size_t>(b)] = 1;
  }
  std::vector<std::uint8_t> is_taken(n_corners, 0);
  for (const BorderCurve& curve : seg.curves) {
    if (curve.is_closed || curve.vertices.size() != 2) continue;
    const int a = corner_index(seg.corners, curve.vertices.front());
    const int b = corner_index(seg.corners, curve.vertices.back());
    const auto ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
    if (a == b || is_fixed[ua] != 0 || is_fixed[ub] != 0 || is_taken[ua] != 0 || is_taken[ub] != 0 ||
        n_joining[std::minmax(a, b)] != 1)
      continue;
    const Eigen::Vector3d pa = point(mesh, curve.vertices.front()), pb = point(mesh, curve.vertices.back());
    if (!((pa - pb).norm() < fraction * size_at(0.5 * (pa + pb)))) continue;
    is_taken[ua] = is_taken[ub] = 1;
    target[std::max(ua, ub)] = std::min(a, b);
  }
  return target;
}

std::vector<int> corner_cluster_merges(const TriMesh& mesh, const Segmentation& seg, const SizeAt& size_at,
                                       double fraction, std::vector<int> target) {
  const std::size_t n_corners = seg.corners.size();
  if (target.size() != n_corners) {
    target.resize(n_corners);
    std::iota(target.begin(), target.end(), 0);
  }
  if (!(fraction > 0.0) || n_corners == 0) return target;
  // Links: open curves between two corners shorter (along their input vertices) than
  // `fraction` x the size at their middle, and the pairs merged already.
  const std::size_t n_curves = seg.curves.size();
  std::vector<std::array<int, 2>> ends(n_curves, {-1, -1});
  std::vector<std::uint8_t> is_link(n_curves, 0), is_fixed(n_corners, 0);
  DisjointSets sets(n_corners);
  for (std::size_t k = 0; k < n_corners; ++k) sets.unite(static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(target[k]));
  for (std::size_t c = 0; c < n_curves; ++c) {
    const BorderCurve& curve = seg.curves[c];
    if (curve.is_closed) continue;
    const int a = corner_index(seg.corners, curve.vertices.front());
    const int b = corner_index(seg.corners, curve.vertices.back());
    ends[c] = {a, b};
    if (curve.patch_right < 0) is_fixed[static_cast<std::size_t>(a)] = is_fixed[static_cast<std::size_t>(b)] = 1;
    if (a == b) continue;
    double length = 0.0;
    for (std::size_t i = 0; i + 1 < curve.vertices.size(); ++i)
      length += (point(mesh, curve.vertices[i + 1]) - point(mesh, curve.vertices[i])).norm();
    const Eigen::Vector3d mid = 0.5 * (point(mesh, curve.vertices.front()) + point(mesh, curve.vertices.back()));
    if (!(length < fraction * size_at(mid))) continue;
    is_link[c] = 1;
    sets.unite(static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b));
  }
  // The clusters (members ascending; the first, the lowest index, survives).
  std::vector<std::vector<int>> members(n_corners);
  for (std::size_t k = 0; k < n_corners; ++k) members[sets.find(static_cast<std::uint32_t>(k))].push_back(static_cast<int>(k));
  std::vector<int> cluster_of(n_corners, -1);
  for (std::size_t r = 0; r < n_corners; ++r)
    for (const int k : members[r]) cluster_of[static_cast<std::size_t>(k)] = static_cast<int>(r);
  // Per cluster: curves with both ends in it (all must be links: they vanish) and curves with
  // one or two ends in it (their patches' loops must pass the survivor once at most).
  std::vector<std::vector<int>> touching(n_corners);
  for (std::size_t c = 0; c < n_curves; ++c) {
    if (ends[c][0] < 0) continue;
    const int ra = cluster_of[static_cast<std::size_t>(ends[c][0])];
    const int rb = cluster_of[static_cast<std::size_t>(ends[c][1])];
    if (members[static_cast<std::size_t>(ra)].size() > 1) touching[static_cast<std::size_t>(ra)].push_back(static_cast<int>(c));
    if (rb != ra && members[static_cast<std::size_t>(rb)].size() > 1) touching[static_cast<std::size_t>(rb)].push_back(static_cast<int>(c));
  }
  for (std::size_t r = 0; r < n_corners; ++r) {
    const std::vector<int>& cluster = members[r];
    if (cluster.size() < 2) continue;
    // Already the pair tiny_curve_merges made: kept as it is.
    if (cluster.size() == 2 && target[static_cast<std::size_t>(cluster[1])] == cluster[0]) continue;
    bool ok = true;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const int k : cluster) {
      ok = ok && is_fixed[static_cast<std::size_t>(k)] == 0;
      centre += point(mesh, seg.corners[static_cast<std::size_t>(k)]);
    }
    centre /= static_cast<double>(cluster.size());
    // Small: every member within fraction x size of the survivor's place (no chains).
    const double radius = fraction * size_at(centre);
    for (const int k : cluster) ok = ok && (point(mesh, seg.corners[static_cast<std::size_t>(k)]) - centre).norm() < radius;
    // A curve between two members that is no link would become a loop; every patch at the
    // cluster keeps an open curve that does not vanish, and its loop passes the survivor once
    // at most (two curve ends there).
    auto inside = [&](int k) { return k >= 0 && cluster_of[static_cast<std::size_t>(k)] == static_cast<int>(r); };
    auto vanishes = [&](std::size_t c) { return inside(ends[c][0]) && inside(ends[c][1]) && ends[c][0] != ends[c][1]; };
    std::map<int, int> ends_at;  // patch -> curve ends at the survivor
    std::size_t n_vanishing = 0;
    for (const int ci : touching[r]) {
      const auto c = static_cast<std::size_t>(ci);
      if (vanishes(c) && is_link[c] == 0) ok = false;
      if (vanishes(c)) ++n_vanishing;
      for (const int p : {seg.curves[c].patch_left, seg.curves[c].patch_right})
        if (p >= 0) ends_at[p] += vanishes(c) ? 0 : static_cast<int>(inside(ends[c][0])) + static_cast<int>(inside(ends[c][1]));
    }
    // The vanishing curves form a tree: contracting a cycle of them would pinch the surface
    // (the cycle round a one-voxel tunnel) or collapse the faces inside it.
    ok = ok && n_vanishing + 1 == cluster.size();
    for (const auto& [p, n] : ends_at) {
      if (!ok) break;
      ok = n <= 2;
      bool open_kept = false;
      for (const int c : seg.patches[static_cast<std::size_t>(p)].curves)
        open_kept = open_kept || (ends[static_cast<std::size_t>(c)][0] >= 0 && !vanishes(static_cast<std::size_t>(c)));
      ok = ok && open_kept;
    }
    if (!ok) continue;
    for (const int k : cluster) target[static_cast<std::size_t>(k)] = cluster[0];
  }
  return target;
}

BorderNodes discretise_borders(const TriMesh& mesh, const Segmentation& seg, const SizeAt& size_at,
                               const std::vector<CurveSource>& source, const std::vector<int>& corner_target,
                               const unsigned threads) {
  BorderNodes out;
  for (const int v : seg.corners) {
    out.positions.push_back(point(mesh, v));
    out.kind.push_back(NodeKind::Corner);
    out.owner.push_back(-1);
  }
  // The corner node of a curve end (after the merges); a survivor sits between the two.
  auto end_node = [&](int vertex) {
    const int k = corner_index(seg.corners, vertex);
    return corner_target.empty() ? k : corner_target[static_cast<std::size_t>(k)];
  };
  // A survivor sits at the mean of its cluster (of a pair: the middle).
  std::vector<int> n_merged(corner_target.size(), 1);
  for (std::size_t k = 0; k < corner_target.size(); ++k) {
    const auto t = static_cast<std::size_t>(corner_target[k]);
    if (t == k) continue;
    out.positions[t] += point(mesh, seg.corners[k]);
    ++n_merged[t];
  }
  for (std::size_t t = 0; t < corner_target.size(); ++t)
    if (n_merged[t] > 1) out.positions[t] *= 1.0 / static_cast<double>(n_merged[t]);
  // Open curves joining the same two corners: each needs 2 pieces at least, or a patch
  // bounded by two of them would get the same segment twice.
  std::vector<std::pair<int, int>> ends;
  for (const BorderCurve& curve : seg.curves)
    if (!curve.is_closed)
      ends.emplace_back(std::minmax(end_node(curve.vertices.front()), end_node(curve.vertices.back())));
  std::sort(ends.begin(), ends.end());
  // A merged tiny curve: no piece left (its two ends are the survivor).
  auto is_merged_away = [&](const BorderCurve& curve) {
    return !curve.is_closed && curve.vertices.front() != curve.vertices.back() &&
           end_node(curve.vertices.front()) == end_node(curve.vertices.back());
  };
  // Each curve's samples depend only on the curve (and the read-only inputs above): they are
  // computed per curve on the threads, and numbered in curve order below (the same nodes
  // for any thread count).
  std::vector<std::vector<Eigen::Vector3d>> curve_samples(seg.curves.size());
  parallel::for_chunks(seg.curves.size(), threads, kDiscretiseCurveChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t c = begin; c < end; ++c) {
      const BorderCurve& curve = seg.curves[c];
      if (is_merged_away(curve)) continue;
      int min_pieces = 1;
      if (curve.is_closed || curve.vertices.front() == curve.vertices.back()) {
        min_pieces = 3;
      } else {
        const std::pair<int, int> key = std::minmax(end_node(curve.vertices.front()), end_node(curve.vertices.back()));
        const auto range = std::equal_range(ends.begin(), ends.end(), std::pair<int, int>(key));
        if (range.second - range.first > 1) min_pieces = 2;
      }
      // Smoothing a short loop (closed, or from a corner to itself) can collapse it: such a
      // loop keeps its input positions.
      std::vector<Eigen::Vector3d> polyline = curve.smoothed;
      if (source[c] != CurveSource::Smoothed || (min_pieces == 3 && curve.vertices.size() < kMinSmoothedLoopVertices))
        for (std::size_t i = 0; i < polyline.size(); ++i) polyline[i] = point(mesh, curve.vertices[i]);
      if (source[c] == CurveSource::InputVertices)
        curve_samples[c].assign(polyline.begin() + (curve.is_closed ? 0 : 1), polyline.end() - (curve.is_closed ? 0 : 1));
      else
        curve_samples[c] = resample(polyline, curve.is_closed, min_pieces, size_at);
    }
  });
  out.curve_nodes.resize(seg.curves.size());
  for (std::size_t c = 0; c < seg.curves.size(); ++c) {
    const BorderCurve& curve = seg.curves[c];
    std::vector<int>& nodes = out.curve_nodes[c];
    if (is_merged_away(curve)) {
      nodes.assign(2, end_node(curve.vertices.front()));
      continue;
    }
    if (!curve.is_closed) nodes.push_back(end_node(curve.vertices.front()));
    for (const auto& q : curve_samples[c]) {
      nodes.push_back(static_cast<int>(out.positions.size()));
      out.positions.push_back(q);
      out.kind.push_back(NodeKind::Border);
      out.owner.push_back(static_cast<int>(c));
    }
    if (!curve.is_closed) nodes.push_back(end_node(curve.vertices.back()));
  }
  return out;
}

PatchBorder patch_border(const Segmentation& seg, int p, const BorderNodes& borders) {
  PatchBorder out;
  // The edges with global ids first (into `edges`, made local at the end).
  std::vector<std::array<int, 2>>& edges = out.edges;
  for (const int c : seg.patches[static_cast<std::size_t>(p)].curves) {
    const BorderCurve& curve = seg.curves[static_cast<std::size_t>(c)];
    // The chain of nodes: the curve's, its first again at the end of a closed one; walked
    // with patch_left on its left, so backwards for the right patch.
    const std::vector<int>& nodes = borders.curve_nodes[static_cast<std::size_t>(c)];
    const std::size_t n = nodes.size();
    const std::size_t m = curve.is_closed && n > 0 ? n + 1 : n;
    const bool backwards = curve.patch_left != p;
    const auto chain = [&](std::size_t i) {
      const std::size_t k = backwards ? m - 1 - i : i;
      return nodes[k == n ? 0 : k];
    };
    for (std::size_t i = 0; i + 1 < m; ++i) {
      const int a = chain(i), b = chain(i + 1);
      if (a == b) continue;  // a merged tiny curve (discretise_borders)
      edges.push_back({a, b});
      out.edge_curve.push_back(c);
    }
  }
  // The nodes: every edge's ends (an edge's head is mostly the next edge's tail: pushed once).
  out.nodes.reserve(edges.size() + 1);
  for (std::size_t i = 0; i < edges.size(); ++i) {
    out.nodes.push_back(edges[i][0]);
    if (i + 1 == edges.size() || edges[i][1] != edges[i + 1][0]) out.nodes.push_back(edges[i][1]);
  }
  std::sort(out.nodes.begin(), out.nodes.end());
  out.nodes.erase(std::unique(out.nodes.begin(), out.nodes.end()), out.nodes.end());
  auto local = [&](int g) {
    return static_cast<int>(std::lower_bound(out.nodes.begin(), out.nodes.end(), g) - out.nodes.begin());
  };
  // Local ids; an edge's tail that is the previous edge's head takes that one's.
  int last_head = -1, last_local = -1;
  for (auto& e : edges) {
    const int tail = e[0] == last_head ? last_local : local(e[0]);
    last_head = e[1];
    last_local = local(e[1]);
    e = {tail, last_local};
  }
  return out;
}

namespace {

// A patch border's nodes in the plane orthogonal to the axis.
std::vector<Eigen::Vector2d> plane_points(const Eigen::Vector3d& axis, const PatchBorder& border, const BorderNodes& borders) {
  const Eigen::Vector3d e1 = axis.unitOrthogonal();
  const Eigen::Vector3d e2 = axis.cross(e1);
  std::vector<Eigen::Vector2d> xy;
  xy.reserve(border.nodes.size());
  for (const int g : border.nodes) {
    const Eigen::Vector3d& x = borders.positions[static_cast<std::size_t>(g)];
    xy.emplace_back(x.dot(e1), x.dot(e2));
  }
  return xy;
}

}  // namespace

std::vector<int> crossing_curves(const Segmentation& seg, const BorderNodes& borders, unsigned threads) {
  return curves_over_patches(seg.patches.size(), threads, [&](std::size_t p, std::vector<int>& out) {
    const PatchBorder border = patch_border(seg, static_cast<int>(p), borders);
    const std::vector<Eigen::Vector2d> xy = plane_points(seg.patches[p].axis, border, borders);
    // Sweep along x: segments sorted by their smallest x, each compared with those that
    // start before it ends.
    const std::size_t n = border.edges.size();
    std::vector<std::size_t> order(n);
    std::vector<double> lo(n), hi(n);
    for (std::size_t i = 0; i < n; ++i) {
      order[i] = i;
      lo[i] = std::min(xy[static_cast<std::size_t>(border.edges[i][0])].x(), xy[static_cast<std::size_t>(border.edges[i][1])].x());
      hi[i] = std::max(xy[static_cast<std::size_t>(border.edges[i][0])].x(), xy[static_cast<std::size_t>(border.edges[i][1])].x());
    }
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return lo[a] < lo[b] || (lo[a] == lo[b] && a < b); });
    for (std::size_t ii = 0; ii < n; ++ii) {
      const std::size_t i = order[ii];
      const auto [a, b] = border.edges[i];
      for (std::size_t jj = ii + 1; jj < n && lo[order[jj]] <= hi[i]; ++jj) {
        const std::size_t j = order[jj];
        const auto [c, d] = border.edges[j];
        const auto at = [&](int k) -> const Eigen::Vector2d& { return xy[static_cast<std::size_t>(k)]; };
        bool bad = false;
        if (a != c && a != d && b != c && b != d) {
          bad = front2d::segments_intersect(at(a), at(b), at(c), at(d));
        } else if (!((a == c && b == d) || (a == d && b == c))) {
          // Sharing one node s: they overlap when the other ends are collinear with s and
          // on the same side of it.
          const int s = (a == c || a == d) ? a : b;
          const int u = s == a ? b : a;
          const int w = (c == s) ? d : c;
          bad = front2d::orient2d(at(s), at(u), at(w)) == 0 && (at(u) - at(s)).dot(at(w) - at(s)) > 0.0;
        }
        if (bad) {
          out.push_back(border.edge_curve[i]);
          out.push_back(border.edge_curve[j]);
        }
      }
    }
  });
}

std::vector<int> flipped_loops(const TriMesh& mesh, const Segmentation& seg, const BorderNodes& borders) {
  std::vector<int> out;
  for (std::size_t c = 0; c < seg.curves.size(); ++c) {
    const BorderCurve& curve = seg.curves[c];
    if (!curve.is_closed) continue;
    for (const int p : {curve.patch_left, curve.patch_right}) {
      if (p < 0) continue;
      const Eigen::Vector3d& axis = seg.patches[static_cast<std::size_t>(p)].axis;
      const Eigen::Vector3d e1 = axis.unitOrthogonal();
      const Eigen::Vector3d e2 = axis.cross(e1);
      // Twice the signed area of a closed polyline in the plane (e1, e2).
      auto twice_area = [&](const auto& n, const auto& at) {
        double sum = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
          const Eigen::Vector3d& a = at(i);
          const Eigen::Vector3d& b = at((i + 1) % n);
          sum += a.dot(e1) * b.dot(e2) - a.dot(e2) * b.dot(e1);
        }
        return sum;
      };
      const std::vector<int>& nodes = borders.curve_nodes[c];
      const double input = twice_area(curve.vertices.size(), [&](std::size_t i) { return point(mesh, curve.vertices[i]); });
      const double nodes_area = twice_area(nodes.size(), [&](std::size_t i) -> const Eigen::Vector3d& {
        return borders.positions[static_cast<std::size_t>(nodes[i])];
      });
      if (!(input * nodes_area > 0.0)) {
        out.push_back(static_cast<int>(c));
        break;
      }
    }
  }
  return out;
}

std::vector<int> extra_outer_loop_curves(const Segmentation& seg, const BorderNodes& borders, unsigned threads) {
  return curves_over_patches(seg.patches.size(), threads, [&](std::size_t p, std::vector<int>& out) {
    const PatchBorder border = patch_border(seg, static_cast<int>(p), borders);
    const std::vector<Eigen::Vector2d> xy = plane_points(seg.patches[p].axis, border, borders);
    std::vector<std::vector<int>> ccw;
    std::size_t largest = 0;
    double largest_area = 0.0;
    std::vector<std::vector<int>> cycles;
    for (const auto& loop : trace_loops(xy, border.edges))
      for (auto& cycle : split_at_repeated_vertices(loop)) cycles.push_back(std::move(cycle));
    for (const auto& loop : cycles) {
      double twice = 0.0;
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const Eigen::Vector2d& a = xy[static_cast<std::size_t>(loop[i])];
        const Eigen::Vector2d& b = xy[static_cast<std::size_t>(loop[(i + 1) % loop.size()])];
        twice += a.x() * b.y() - a.y() * b.x();
      }
      if (!(twice >= 0.0)) continue;
      if (ccw.empty() || twice > largest_area) {
        largest = ccw.size();
        largest_area = twice;
      }
      ccw.push_back(loop);
    }
    if (ccw.size() < 2) return;  // one outer loop (almost every patch): no curve to name
    std::map<std::pair<int, int>, int> edge_curve;
    for (std::size_t e = 0; e < border.edges.size(); ++e)
      edge_curve[{border.edges[e][0], border.edges[e][1]}] = border.edge_curve[e];
    for (std::size_t k = 0; k < ccw.size(); ++k) {
      if (k == largest) continue;
      for (std::size_t i = 0; i < ccw[k].size(); ++i) {
        const auto it = edge_curve.find({ccw[k][i], ccw[k][(i + 1) % ccw[k].size()]});
        if (it != edge_curve.end()) out.push_back(it->second);
      }
    }
  });
}

std::vector<int> folded_border_curves(const Segmentation& seg, const BorderNodes& borders, const std::vector<CurveSource>& source,
                                      unsigned threads) {
  return curves_over_patches(seg.patches.size(), threads, [&](std::size_t p, std::vector<int>& out) {
    const PatchBorder border = patch_border(seg, static_cast<int>(p), borders);
    if (border.edges.size() < 3) return;
    const std::vector<Eigen::Vector2d> xy = plane_points(seg.patches[p].axis, border, borders);
    const BorderCycles cycles = border_cycles(xy, border.edges);
    if (cycles.meshable()) return;
    // The bad cycles: a winding other than 0 and 1 (a hole poking out of the outer loop, a
    // loop turning the wrong way round), degenerate, or counter-clockwise besides the largest.
    std::size_t largest = cycles.polygons.size();
    for (std::size_t k = 0; k < cycles.polygons.size(); ++k)
      if (cycles.areas[k] >= 0.0 && (largest == cycles.polygons.size() || cycles.areas[k] > cycles.areas[largest])) largest = k;
    Eigen::AlignedBox2d bad_box;
    std::vector<std::uint8_t> is_bad(cycles.polygons.size(), 0);
    for (std::size_t k = 0; k < cycles.polygons.size(); ++k) {
      is_bad[k] = cycles.has_inside[k] == 0 || (cycles.winding[k] != 0.0 && cycles.winding[k] != 1.0) ||
                  (cycles.n_ccw_loops != 1 && cycles.areas[k] >= 0.0 && k != largest);
      if (is_bad[k] != 0)
        for (const auto& q : cycles.polygons[k]) bad_box.extend(q);
    }
    std::vector<int> curves;
    std::map<std::pair<int, int>, int> edge_curve;
    for (std::size_t e = 0; e < border.edges.size(); ++e) {
      edge_curve[{border.edges[e][0], border.edges[e][1]}] = border.edge_curve[e];
      Eigen::AlignedBox2d box(xy[static_cast<std::size_t>(border.edges[e][0])]);
      box.extend(xy[static_cast<std::size_t>(border.edges[e][1])]);
      if (!bad_box.isEmpty() && box.intersects(bad_box)) curves.push_back(border.edge_curve[e]);
    }
    for (std::size_t k = 0; k < cycles.cycles.size(); ++k) {
      if (is_bad[k] == 0) continue;
      const auto& cycle = cycles.cycles[k];
      for (std::size_t i = 0; i < cycle.size(); ++i) {
        const auto it = edge_curve.find({cycle[i], cycle[(i + 1) % cycle.size()]});
        if (it != edge_curve.end()) curves.push_back(it->second);
      }
    }
    const bool all_input = std::all_of(curves.begin(), curves.end(), [&](int c) {
      return source[static_cast<std::size_t>(c)] == CurveSource::InputVertices;
    });
    if (all_input) curves = seg.patches[p].curves;
    out.insert(out.end(), curves.begin(), curves.end());
  });
}

std::vector<double> curve_crease_angles(const TriMesh& mesh, const Segmentation& seg, int rings, unsigned threads) {
  std::vector<double> out(seg.curves.size(), 180.0);
  // Per worker: face stamps and the breadth-first rings. A curve's angle depends only on the
  // mesh and the segmentation (the stamps only mark faces seen in one side_normal call), so
  // the curves may be taken in any order, on any worker.
  struct Scratch {
    std::vector<int> stamp;
    int epoch = 0;
    std::vector<int> frontier, next;
    std::vector<double> angles;
  };
  std::vector<Scratch> scratch(std::max(1U, threads));
  // Area-weighted mean normal (not normalised) of the faces within `rings` edge-adjacent
  // rings of the faces of patch p around vertex v, not entering patch `other`: a narrow
  // patch (a bevel strip) does not hide the faces beyond it.
  auto side_normal = [&](Scratch& s, int v, int p, int other) {
    ++s.epoch;
    s.frontier.clear();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto f : mesh.vf_range(TriMesh::VertexHandle(v)))
      if (seg.face_patch[static_cast<std::size_t>(f.idx())] == p) {
        s.stamp[static_cast<std::size_t>(f.idx())] = s.epoch;
        s.frontier.push_back(f.idx());
      }
    for (int ring = 0; ring <= rings && !s.frontier.empty(); ++ring) {
      s.next.clear();
      for (const int f : s.frontier) {
        const TriMesh::FaceHandle fh(f);
        const auto h = mesh.halfedge_handle(fh);
        const Eigen::Vector3d a = to_eigen(mesh.point(mesh.from_vertex_handle(h)));
        const Eigen::Vector3d b = to_eigen(mesh.point(mesh.to_vertex_handle(h)));
        const Eigen::Vector3d c = to_eigen(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(h))));
        sum += (b - a).cross(c - a);  // twice the area times the unit normal
        if (ring == rings) continue;
        for (const auto g : mesh.ff_range(fh))
          if (seg.face_patch[static_cast<std::size_t>(g.idx())] != other && s.stamp[static_cast<std::size_t>(g.idx())] != s.epoch) {
            s.stamp[static_cast<std::size_t>(g.idx())] = s.epoch;
            s.next.push_back(g.idx());
          }
      }
      std::swap(s.frontier, s.next);
    }
    return sum;
  };
  parallel::for_chunks(seg.curves.size(), threads, kCreaseCurveChunk, [&](std::size_t begin, std::size_t end, unsigned worker) {
    Scratch& s = scratch[worker];
    if (s.stamp.empty()) s.stamp.assign(mesh.n_faces(), -1);
    std::vector<double>& angles = s.angles;
    for (std::size_t c = begin; c < end; ++c) {
      const BorderCurve& curve = seg.curves[c];
      if (curve.patch_right < 0) continue;
      angles.clear();
      const std::size_t n = curve.vertices.size();
      // Interior vertices of an open curve (its corners also touch other patches), every
      // vertex of a closed one, both ends of a one-edge curve.
      const std::size_t first = curve.is_closed || n <= 2 ? 0 : 1;
      const std::size_t last = curve.is_closed || n <= 2 ? n : n - 1;
      for (std::size_t i = first; i < last; ++i) {
        const Eigen::Vector3d left = side_normal(s, curve.vertices[i], curve.patch_left, curve.patch_right);
        const Eigen::Vector3d right = side_normal(s, curve.vertices[i], curve.patch_right, curve.patch_left);
        const double l = left.norm() * right.norm();
        if (!(l > 0.0)) continue;
        angles.push_back(std::acos(std::clamp(left.dot(right) / l, -1.0, 1.0)) * 180.0 / std::numbers::pi);
      }
      if (angles.empty()) continue;
      out[c] = median_of(angles);
    }
  });
  return out;
}

bool is_sharp_crease_curve(const Segmentation& seg, int c) {
  if (seg.sharp_crease_edges.empty()) return false;
  const std::vector<int>& edges = seg.curves[static_cast<std::size_t>(c)].edges;
  const auto n_sharp = std::count_if(edges.begin(), edges.end(), [&](int e) {
    return std::binary_search(seg.sharp_crease_edges.begin(), seg.sharp_crease_edges.end(), e);
  });
  return 2 * static_cast<std::size_t>(n_sharp) > edges.size();
}

std::vector<std::uint8_t> sharp_crease_curves(const Segmentation& seg) {
  std::vector<std::uint8_t> out(seg.curves.size(), 0);
  if (seg.sharp_crease_edges.empty()) return out;
  for (std::size_t c = 0; c < seg.curves.size(); ++c) out[c] = is_sharp_crease_curve(seg, static_cast<int>(c)) ? 1 : 0;
  return out;
}

std::vector<std::uint8_t> feature_curves(const TriMesh& mesh, const Segmentation& seg, double crease_angle_deg,
                                         std::vector<double>* crease_angles, unsigned threads) {
  const std::vector<double> angles = curve_crease_angles(mesh, seg, kCreaseRings, threads);
  if (crease_angles != nullptr) *crease_angles = angles;
  std::vector<std::uint8_t> out = sharp_crease_curves(seg);
  const double cos_crease = std::cos(crease_angle_deg * std::numbers::pi / 180.0);
  for (std::size_t c = 0; c < seg.curves.size(); ++c) {
    const BorderCurve& curve = seg.curves[c];
    if (out[c] != 0) continue;
    if (curve.patch_right < 0 || angles[c] > kCreaseShare * crease_angle_deg) {
      out[c] = 1;
      continue;
    }
    // An unbevelled crease: most input edges have a dihedral above the crease angle.
    std::size_t n_crease = 0;
    for (const int e : curve.edges) {
      const auto h = mesh.halfedge_handle(TriMesh::EdgeHandle(e), 0);
      const Eigen::Vector3d n0 = to_eigen(mesh.calc_face_normal(mesh.face_handle(h)));
      const Eigen::Vector3d n1 = to_eigen(mesh.calc_face_normal(mesh.opposite_face_handle(h)));
      const double l = n0.norm() * n1.norm();
      if (l > 0.0 && n0.dot(n1) / l < cos_crease) ++n_crease;  // a degenerate face has no dihedral
    }
    out[c] = 2 * n_crease > curve.edges.size() ? 1 : 0;
  }
  return out;
}

}  // namespace nurbsfront::surfmesh_detail
