// SPDX-License-Identifier: BSD-3-Clause
// make_manifold(): consistent orientation per component, non-manifold edges paired by the
// angle of their faces around the edge (or cut), then every vertex split into one copy per
// face fan.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/disjoint_sets.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/io/mesh_io.h"

namespace nurbsfront {
namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

//! One face's use of an undirected edge: the face, the corner k the edge starts at
//! (edge t[k] -> t[k+1]), and whether it runs from the smaller to the larger vertex id.
struct EdgeUse {
  std::uint64_t key;  // min << 32 | max
  std::uint32_t face;
  std::uint8_t corner;
  bool ascending;
};

}  // namespace

std::size_t ManifoldRepairReport::n_changes() const {
  return n_flipped_faces + n_paired_edges + n_cut_edges + n_nonorientable_edges + n_split_vertices;
}

ManifoldRepair make_manifold(const TriangleSoup& soup) {
  const std::size_t n_points = soup.points.size();
  const std::size_t n_faces = soup.triangles.size();
  if (n_points >= kNone || 3 * n_faces >= kNone) throw InvalidInput("make_manifold: more than 2^32-2 points or corners");
  for (std::size_t f = 0; f < n_faces; ++f) {
    const auto& t = soup.triangles[f];
    for (const std::uint32_t v : t) {
      if (v >= n_points) throw InvalidInput("make_manifold: triangle " + std::to_string(f) + " has out-of-range index " + std::to_string(v));
    }
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
      throw InvalidInput("make_manifold: triangle " + std::to_string(f) + " repeats a vertex (call clean() first)");
    }
  }
  ManifoldRepair result;
  ManifoldRepairReport& report = result.report;

  // 1. Undirected edges: the uses of each, grouped by sorting.
  std::vector<EdgeUse> uses;
  uses.reserve(3 * n_faces);
  for (std::uint32_t f = 0; f < n_faces; ++f) {
    const auto& t = soup.triangles[f];
    for (std::uint8_t k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      uses.push_back({(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), f, k, a < b});
    }
  }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return x.key != y.key ? x.key < y.key : x.face < y.face;
  });
  std::vector<std::pair<std::size_t, std::size_t>> groups;  // [begin, end) in uses, 2+ uses only
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].key == uses[i].key) ++j;
    if (j - i >= 2) groups.emplace_back(i, j);
    i = j;
  }

  // 2. Orientation: breadth-first over the edges with exactly two faces; a neighbour using
  // the shared edge in the same direction must be flipped relative to the current face. A
  // contradiction (a Moebius-like band) cuts that edge.
  std::vector<std::array<std::uint32_t, 3>> neighbour(n_faces, {kNone, kNone, kNone});  // across edge k
  for (const auto& [b, e] : groups) {
    if (e - b != 2) continue;
    neighbour[uses[b].face][uses[b].corner] = uses[b + 1].face;
    neighbour[uses[b + 1].face][uses[b + 1].corner] = uses[b].face;
  }
  auto ascending_of = [&](std::uint32_t f, int k) {
    const auto& t = soup.triangles[f];
    return t[k] < t[(k + 1) % 3];
  };
  // The corner k of face g whose edge t[k] -> t[k+1] joins a and b (either direction).
  auto edge_corner = [&](std::uint32_t g, std::uint32_t a, std::uint32_t b) {
    const auto& t = soup.triangles[g];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t p = t[k], q = t[(k + 1) % 3];
      if ((p == a && q == b) || (p == b && q == a)) return k;
    }
    throw InternalError("make_manifold: a neighbour does not share the edge");
  };
  std::vector<char> flip(n_faces, 0), seen(n_faces, 0);
  std::vector<std::uint32_t> component_faces;
  for (std::uint32_t seed = 0; seed < n_faces; ++seed) {
    if (seen[seed]) continue;
    component_faces.clear();
    std::queue<std::uint32_t> queue;
    queue.push(seed);
    seen[seed] = 1;
    std::size_t n_flipped = 0;
    while (!queue.empty()) {
      const std::uint32_t f = queue.front();
      queue.pop();
      component_faces.push_back(f);
      n_flipped += flip[f] ? 1 : 0;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t g = neighbour[f][k];
        if (g == kNone) continue;
        const int kg = edge_corner(g, soup.triangles[f][k], soup.triangles[f][(k + 1) % 3]);
        const char wanted = static_cast<char>(flip[f] ^ (ascending_of(f, k) == ascending_of(g, kg) ? 1 : 0));
        if (!seen[g]) {
          seen[g] = 1;
          flip[g] = wanted;
          queue.push(g);
        } else if (flip[g] != wanted && f < g) {
          neighbour[f][k] = neighbour[g][kg] = kNone;  // cut: the band cannot be oriented
          ++report.n_nonorientable_edges;
        }
      }
    }
    // Keep the orientation of the majority of the component's faces.
    if (2 * n_flipped > component_faces.size()) {
      for (const std::uint32_t f : component_faces) flip[f] ^= 1;
      n_flipped = component_faces.size() - n_flipped;
    }
    report.n_flipped_faces += n_flipped;
  }

  // 3. Edges with more than two faces: sorted by the angle of their third vertex around
  // the edge a -> b (a < b). A face running a -> b has its normal towards increasing angle,
  // so the solid it bounds lies towards decreasing angle, up to the previous face, which
  // must run b -> a. When the directions alternate around the edge, each face running
  // a -> b is paired with its predecessor; otherwise every face is cut off the edge.
  for (const auto& [b, e] : groups) {
    if (e - b == 2) continue;
    const std::uint32_t va = static_cast<std::uint32_t>(uses[b].key >> 32);
    const std::uint32_t vb = static_cast<std::uint32_t>(uses[b].key & 0xffffffffu);
    const Eigen::Vector3d& pa = soup.points[va];
    const Eigen::Vector3d axis = soup.points[vb] - pa;
    Eigen::Vector3d u = axis.unitOrthogonal();
    const Eigen::Vector3d w = axis.normalized().cross(u);
    struct Around {
      double angle;
      std::uint32_t face;
      std::uint8_t corner;
      bool forward;  // runs a -> b after the orientation step
    };
    std::vector<Around> around;
    for (std::size_t i = b; i < e; ++i) {
      const auto& t = soup.triangles[uses[i].face];
      const Eigen::Vector3d r = soup.points[t[(uses[i].corner + 2) % 3]] - pa;
      const bool forward = uses[i].ascending != (flip[uses[i].face] != 0);
      around.push_back({std::atan2(r.dot(w), r.dot(u)), uses[i].face, uses[i].corner, forward});
    }
    std::sort(around.begin(), around.end(), [](const Around& x, const Around& y) {
      return x.angle != y.angle ? x.angle < y.angle : x.face < y.face;
    });
    const std::size_t n = around.size();
    bool alternate = n % 2 == 0;
    for (std::size_t i = 0; alternate && i < n; ++i) alternate = around[i].forward != around[(i + 1) % n].forward;
    if (!alternate) {
      ++report.n_cut_edges;
      continue;
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (!around[i].forward) continue;
      const Around& prev = around[(i + n - 1) % n];
      neighbour[around[i].face][around[i].corner] = prev.face;
      neighbour[prev.face][prev.corner] = around[i].face;
    }
    ++report.n_paired_edges;
  }

  // 4. Vertex fans: corners (3 f + k) of faces adjacent across an edge are joined at both
  // ends of the edge; each class of corners at one vertex is one fan. The fan with the
  // lowest corner keeps the vertex, every other fan gets a copy of the point.
  DisjointSets fans(3 * n_faces);
  for (std::uint32_t f = 0; f < n_faces; ++f) {
    const auto& t = soup.triangles[f];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t g = neighbour[f][k];
      if (g == kNone || g < f) continue;
      const auto& s = soup.triangles[g];
      for (const std::uint32_t v : {t[k], t[(k + 1) % 3]}) {
        const int kf = v == t[0] ? 0 : v == t[1] ? 1 : 2;
        const int kg = v == s[0] ? 0 : v == s[1] ? 1 : 2;
        fans.unite(3 * f + kf, 3 * g + kg);
      }
    }
  }
  result.soup.points = soup.points;
  result.soup.triangles.resize(n_faces);
  std::vector<std::uint32_t> owner(n_points, kNone);       // the corner class that keeps each vertex
  std::vector<std::uint32_t> class_vertex(3 * n_faces, kNone);  // the vertex id given to a class
  for (std::uint32_t f = 0; f < n_faces; ++f) {
    const auto& t = soup.triangles[f];
    std::array<std::uint32_t, 3> out{};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t c = fans.find(3 * f + k);
      if (class_vertex[c] == kNone) {
        if (owner[t[k]] == kNone) {
          owner[t[k]] = c;
          class_vertex[c] = t[k];
        } else {
          class_vertex[c] = static_cast<std::uint32_t>(result.soup.points.size());
          result.soup.points.push_back(soup.points[t[k]]);
          ++report.n_split_vertices;
        }
      }
      out[k] = class_vertex[c];
    }
    if (flip[f]) std::swap(out[1], out[2]);
    result.soup.triangles[f] = out;
  }
  return result;
}

}  // namespace nurbsfront

namespace nurbsfront {
namespace {

bool has_zero_area(const TriMesh& mesh, TriMesh::FaceHandle f) { return mesh.calc_face_area(f) == 0.0; }

//! Rounds of flips over the faces of exactly zero area (three distinct collinear corners:
//! a needle a, m, b with m on the segment ab). Flipping the long edge ab replaces the
//! needle and its neighbour (b, a, y) by (a, m, y) and (m, b, y), which cover the same
//! area. A needle on the boundary is dropped when m is inside the surface: the boundary
//! then runs a, m, b, which is the same curve. Stops when a round changes nothing.
void remove_zero_area_faces(TriMesh& mesh, PrepareReport& report) {
  bool deleted = false;
  for (int round = 0; round < 16; ++round) {
    std::size_t n_changed = 0;
    for (auto f : mesh.faces()) {
      if (mesh.status(f).deleted() || !has_zero_area(mesh, f)) continue;
      TriMesh::HalfedgeHandle longest;
      double longest_length = -1.0;
      for (auto h : mesh.fh_range(f)) {
        const double length = mesh.calc_edge_sqr_length(h);
        if (length > longest_length) {
          longest_length = length;
          longest = h;
        }
      }
      const auto e = mesh.edge_handle(longest);
      const auto apex = mesh.to_vertex_handle(mesh.next_halfedge_handle(longest));
      if (mesh.is_boundary(e)) {
        if (mesh.is_boundary(apex)) continue;
        mesh.delete_face(f, true);
        deleted = true;
        ++report.n_zero_area_dropped;
        ++n_changed;
      } else if (mesh.is_flip_ok(e)) {
        mesh.flip(e);
        ++report.n_zero_area_flipped;
        ++n_changed;
      }
    }
    if (n_changed == 0) break;
  }
  if (deleted) mesh.garbage_collection();
  for (auto f : mesh.faces()) report.n_zero_area_left += has_zero_area(mesh, f) ? 1 : 0;
}

void append_count(std::string& text, std::size_t n, const char* what) {
  if (n == 0) return;
  text += (text.empty() ? "" : ", ") + std::to_string(n) + " " + what;
}

}  // namespace

std::string PrepareReport::summary() const {
  std::string text;
  append_count(text, clean.n_welded_vertices, "duplicate vertices welded");
  append_count(text, clean.n_degenerate_faces, "collapsed triangles dropped");
  append_count(text, clean.n_duplicate_faces, "duplicate triangles dropped");
  append_count(text, clean.n_unreferenced_vertices, "unreferenced vertices dropped");
  append_count(text, manifold.n_flipped_faces, "triangles reoriented");
  append_count(text, manifold.n_paired_edges, "non-manifold edges split into pairs of faces");
  append_count(text, manifold.n_cut_edges, "non-manifold edges cut open");
  append_count(text, manifold.n_nonorientable_edges, "edges cut where the surface cannot be oriented");
  append_count(text, manifold.n_split_vertices, "vertices duplicated at non-manifold points");
  append_count(text, n_zero_area_flipped, "zero-area triangles removed by an edge flip");
  append_count(text, n_zero_area_dropped, "zero-area triangles dropped from the boundary");
  append_count(text, n_zero_area_left, "zero-area triangles left");
  return text.empty() ? "nothing to repair" : text;
}

//! The cleaned soup as a TriMesh, repaired by make_manifold() only when to_trimesh refuses
//! it: the common case, an oriented 2-manifold, costs one check, as before. Returned by
//! value into its final place (OpenMesh meshes declare no move operations: a copy of a 1 M
//! face mesh costs about 75 ms).
TriMesh manifold_mesh(const TriangleSoup& cleaned, PrepareReport& report, unsigned n_threads) {
  TriMesh mesh;  // the one return value (named return value: no copy)
  bool built = false;
  try {
    to_trimesh(cleaned, mesh, n_threads);
    built = true;
  } catch (const TopologyError&) {
  }
  if (!built) {
    const ManifoldRepair repaired = make_manifold(cleaned);
    report.manifold = repaired.report;
    try {
      to_trimesh(repaired.soup, mesh, n_threads);
    } catch (const TopologyError& e) {
      throw InvalidInput("the input is not an oriented 2-manifold even after repair (" + report.summary() + "): " +
                         e.what() + "; a non-orientable part (such as a Moebius band) cannot be remeshed");
    }
  }
  return mesh;
}

PreparedMesh prepare_mesh(const TriangleSoup& soup, const CleanOptions& options) {
  PrepareReport report;
  const CleanResult cleaned = clean(soup, options);
  report.clean = cleaned.report;
  if (cleaned.soup.triangles.empty()) {
    throw InvalidInput("the input has no triangles" +
                       std::string(soup.triangles.empty() ? "" : " left after dropping collapsed ones (" + report.summary() + ")"));
  }
  PreparedMesh result{manifold_mesh(cleaned.soup, report, parallel::thread_count(options.threads)), report};  // braced: evaluated left to right
  // clean() counted the triangles with three distinct collinear corners; make_manifold
  // moves no point, so there are none to remove when it counted none.
  if (result.report.clean.n_collinear_faces > 0) remove_zero_area_faces(result.mesh, result.report);
  return result;
}

}  // namespace nurbsfront
