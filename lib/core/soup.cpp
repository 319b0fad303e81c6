// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/core/soup.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <sstream>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/core/soup_internal.h"
#include "nurbsfront/core/tolerances.h"

namespace nurbsfront {

BoundingBox bounding_box(const TriangleSoup& soup) {
  BoundingBox box;
  for (const auto& p : soup.points) box.extend(p);
  return box;
}

double mean_edge_length(const TriMesh& mesh) {
  const double zero = tolerance::kZeroLengthRelative * bounding_box(mesh).diagonal();
  double sum = 0.0;
  std::size_t count = 0;
  for (const auto e : mesh.edges()) {
    if (mesh.status(e).deleted()) continue;
    const double length = mesh.calc_edge_length(e);
    if (!(length > zero)) continue;
    sum += length;
    ++count;
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

double core_detail::mean_edge_length(const TriMesh& mesh, const unsigned n_threads) {
  // One code path for every thread count (a serial shortcut's separately inlined length
  // could round differently where the compiler contracts to FMA).
  constexpr std::size_t kChunk = 32768;
  // The box: per chunk of vertices, then combined (minima and maxima are exact).
  const std::size_t n_vertices = mesh.n_vertices();
  const bool vertex_status = mesh.has_vertex_status();
  std::vector<BoundingBox> boxes(n_vertices / kChunk + 1);
  parallel::for_chunks(n_vertices, n_threads, kChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    BoundingBox& box = boxes[begin / kChunk];
    for (std::size_t i = begin; i < end; ++i) {
      const TriMesh::VertexHandle v(static_cast<int>(i));
      if (vertex_status && mesh.status(v).deleted()) continue;
      box.extend(to_eigen(mesh.point(v)));
    }
  });
  BoundingBox box;
  for (const BoundingBox& part : boxes) {
    if (part.is_empty()) continue;
    box.extend(part.min);
    box.extend(part.max);
  }
  const double zero = tolerance::kZeroLengthRelative * box.diagonal();
  // Every edge's length on the threads (NaN for a deleted edge), summed in edge order.
  const std::size_t n_edges = mesh.n_edges();
  const bool edge_status = mesh.has_edge_status();
  std::vector<double> length(n_edges);
  parallel::for_chunks(n_edges, n_threads, kChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) {
      const TriMesh::EdgeHandle e(static_cast<int>(i));
      length[i] = edge_status && mesh.status(e).deleted() ? std::numeric_limits<double>::quiet_NaN()
                                                           : mesh.calc_edge_length(e);
    }
  });
  double sum = 0.0;
  std::size_t count = 0;
  for (const double l : length) {
    if (!(l > zero)) continue;
    sum += l;
    ++count;
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

BoundingBox bounding_box(const TriMesh& mesh) {
  BoundingBox box;
  for (auto v : mesh.vertices()) box.extend(to_eigen(mesh.point(v)));
  return box;
}

std::string ManifoldCheck::message() const {
  std::ostringstream out;
  const char* sep = "";
  auto item = [&](std::size_t n, const char* what) {
    if (n == 0) return;
    out << sep << n << ' ' << what;
    sep = ", ";
  };
  item(n_bad_indices, "triangles with out-of-range vertex indices");
  item(n_repeated_index, "triangles repeating a vertex");
  item(n_nonmanifold_edges, "non-manifold edges (more than two triangles)");
  item(n_misoriented_edges, "edges where neighbouring triangles have opposite orientation");
  item(n_nonmanifold_vertices, "non-manifold vertices (several fans of triangles)");
  return out.str();
}

ManifoldCheck check_manifold(const TriangleSoup& soup) {
  // Linear time: every pass is over the triangles or over compressed per-vertex lists
  // (no sort, no hash map), with per-vertex stamps instead of clearing arrays.
  ManifoldCheck check;
  const auto n_points = static_cast<std::uint64_t>(soup.points.size());
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  // Edges of the valid triangles, listed at their smaller vertex: (larger vertex, 1 if the
  // triangle runs small -> large, 2 if large -> small).
  std::vector<std::uint32_t> first(n_points + 1, 0);
  auto is_bad_index = [&](const std::array<std::uint32_t, 3>& t) {
    return t[0] >= n_points || t[1] >= n_points || t[2] >= n_points;
  };
  auto is_repeated = [](const std::array<std::uint32_t, 3>& t) {
    return t[0] == t[1] || t[1] == t[2] || t[2] == t[0];
  };
  for (const auto& t : soup.triangles) {
    if (is_bad_index(t)) {
      ++check.n_bad_indices;
    } else if (is_repeated(t)) {
      ++check.n_repeated_index;
    } else {
      for (int k = 0; k < 3; ++k) ++first[std::min(t[k], t[(k + 1) % 3]) + 1];
    }
  }
  const std::size_t n_bad_triangles = check.n_bad_indices + check.n_repeated_index;
  for (std::size_t i = 1; i < first.size(); ++i) first[i] += first[i - 1];
  std::vector<std::pair<std::uint32_t, std::uint8_t>> edges(first.back());
  std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
  for (const auto& t : soup.triangles) {
    if (is_bad_index(t) || is_repeated(t)) continue;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a < b) {
        edges[fill[a]++] = {b, 1};
      } else {
        edges[fill[b]++] = {a, 2};
      }
    }
  }
  // Per undirected edge: how often each direction occurs (a direction twice is a
  // misoriented edge, counted once; more than two triangles a non-manifold edge).
  std::vector<std::uint32_t> stamp(n_points, kNone);
  std::vector<std::uint32_t> n_forward(n_points, 0), n_backward(n_points, 0);
  for (std::uint64_t a = 0; a < n_points; ++a) {
    const auto tag = static_cast<std::uint32_t>(a);
    for (std::uint32_t i = first[a]; i < first[a + 1]; ++i) {
      const std::uint32_t b = edges[i].first;
      if (stamp[b] != tag) {
        stamp[b] = tag;
        n_forward[b] = n_backward[b] = 0;
      }
      ++(edges[i].second == 1 ? n_forward[b] : n_backward[b]);
    }
    for (std::uint32_t i = first[a]; i < first[a + 1]; ++i) {
      const std::uint32_t b = edges[i].first;
      if (stamp[b] != tag) continue;  // counted already
      stamp[b] = kNone;
      if (n_forward[b] + n_backward[b] > 2) ++check.n_nonmanifold_edges;
      if (n_forward[b] >= 2) ++check.n_misoriented_edges;
      if (n_backward[b] >= 2) ++check.n_misoriented_edges;
    }
  }
  if (check.n_nonmanifold_edges + check.n_misoriented_edges + n_bad_triangles > 0) {
    return check;  // the fan test below assumes a manifold, oriented edge structure
  }
  edges = {};
  // Vertex fans: at vertex a, triangle (a, b, c) links b -> c. With manifold oriented
  // edges every b has at most one successor and one predecessor; one fan means one chain
  // or one cycle.
  std::fill(first.begin(), first.end(), 0);
  for (const auto& t : soup.triangles) {
    for (int k = 0; k < 3; ++k) ++first[t[k] + 1];
  }
  for (std::size_t i = 1; i < first.size(); ++i) first[i] += first[i - 1];
  std::vector<std::pair<std::uint32_t, std::uint32_t>> links(first.back());
  std::copy(first.begin(), first.end() - 1, fill.begin());
  for (const auto& t : soup.triangles) {
    for (int k = 0; k < 3; ++k) links[fill[t[k]]++] = {t[(k + 1) % 3], t[(k + 2) % 3]};
  }
  // next[b] (valid when has_next[b] is a's tag) and is_target[b] (== a's tag).
  std::vector<std::uint32_t>& next = n_forward;
  std::vector<std::uint32_t>& has_next = stamp;
  std::vector<std::uint32_t>& is_target = n_backward;
  std::fill(has_next.begin(), has_next.end(), kNone);
  std::fill(is_target.begin(), is_target.end(), kNone);
  for (std::uint64_t v = 0; v < n_points; ++v) {
    const std::uint32_t begin = first[v], end = first[v + 1];
    if (end - begin <= 1) continue;
    const auto tag = static_cast<std::uint32_t>(v);
    for (std::uint32_t i = begin; i < end; ++i) {
      next[links[i].first] = links[i].second;
      has_next[links[i].first] = tag;
      is_target[links[i].second] = tag;
    }
    std::size_t n_chains = 0;
    std::size_t visited = 0;
    for (std::uint32_t i = begin; i < end; ++i) {
      std::uint32_t b = links[i].first;
      if (is_target[b] == tag) continue;  // not the start of an open chain
      ++n_chains;
      for (; has_next[b] == tag; b = next[b]) ++visited;
    }
    const std::size_t n_links = end - begin;
    // Links not on an open chain form cycles; one fan = one open chain covering all,
    // or no open chain and one cycle covering all (then every successor has a successor).
    bool single_fan = false;
    if (n_chains == 1 && visited == n_links) single_fan = true;
    if (n_chains == 0) {
      std::size_t cycle = 0;
      std::uint32_t b = links[begin].first;
      do {
        b = next[b];
        ++cycle;
      } while (b != links[begin].first && cycle <= n_links);
      single_fan = cycle == n_links;
    }
    if (!single_fan) ++check.n_nonmanifold_vertices;
  }
  return check;
}

namespace {

// Corners (or vertices, edges, faces) per chunk of to_trimesh_checked()'s parallel steps.
constexpr std::size_t kBuildChunk = 32768;

void require_finite(const TriangleSoup& soup) {
  for (const auto& p : soup.points) {
    if (!p.allFinite()) throw InvalidInput("nurbsfront: mesh has non-finite (NaN or infinite) coordinates");
  }
}

}  // namespace

TriMesh to_trimesh(const TriangleSoup& soup) {
  TriMesh mesh;
  to_trimesh(soup, mesh);
  return mesh;
}

void to_trimesh(const TriangleSoup& soup, TriMesh& mesh) { to_trimesh(soup, mesh, 1); }

void to_trimesh(const TriangleSoup& soup, TriMesh& mesh, unsigned n_threads) {
  mesh.clear();
  require_finite(soup);
  const ManifoldCheck check = core_detail::check_and_build(soup, mesh, n_threads);
  if (!check.ok()) throw TopologyError("nurbsfront: mesh is not an oriented 2-manifold: " + check.message());
}

ManifoldCheck core_detail::check_and_build(const TriangleSoup& soup, TriMesh& mesh, unsigned n_threads) {
  const std::size_t n_points = soup.points.size();
  const bool buildable = std::all_of(soup.triangles.begin(), soup.triangles.end(), [n_points](const auto& t) {
    return t[0] < n_points && t[1] < n_points && t[2] < n_points && t[0] != t[1] && t[1] != t[2] && t[2] != t[0];
  });
  if (n_threads < 2 || !buildable || soup.triangles.empty()) {
    const ManifoldCheck check = check_manifold(soup);
    if (check.ok()) {
      to_trimesh_checked(soup, mesh);
    } else {
      mesh.clear();
    }
    return check;
  }
  ManifoldCheck check;
  std::exception_ptr build_error;  // reported only when the check accepts the soup
  // The build's own steps on n_threads threads too (they outlast the check).
  parallel::for_chunks(2, 2, 1, [&](std::size_t begin, std::size_t, unsigned) {
    if (begin == 0) {
      check = check_manifold(soup);
      return;
    }
    try {
      to_trimesh_checked(soup, mesh, n_threads);
    } catch (const InvalidInput&) {
      build_error = std::current_exception();
    }
  });
  if (!check.ok()) {
    mesh.clear();
    return check;
  }
  if (build_error) {
    mesh.clear();
    std::rethrow_exception(build_error);
  }
  return check;
}

void core_detail::to_trimesh_checked(const TriangleSoup& soup, TriMesh& mesh, unsigned n_threads) {
  mesh.clear();
  require_finite(soup);
  // The halfedge structure is built directly (the soup is an oriented 2-manifold), exactly
  // as OpenMesh's add_face() would build it face by face: edges numbered in order of first
  // use, each edge's first halfedge in the direction of that use; a face's halfedge is
  // its third one; an interior vertex keeps the halfedge leaving it in its last face; a
  // boundary vertex and a boundary halfedge's successor are the vertex's one outgoing
  // boundary halfedge. (Test Soup.DirectBuildMatchesAddFace compares with add_face.)
  // The per-corner, per-edge, per-face and per-vertex steps run in chunks on n_threads
  // threads, each writing only its own elements: the same mesh for any thread count.
  const std::size_t n_points = soup.points.size(), n_corners = 3 * soup.triangles.size();
  n_threads = std::max(n_threads, 1U);
  auto in_chunks = [n_threads](std::size_t n, const auto& body, std::size_t chunk = kBuildChunk) {
    parallel::for_each_index(n, n_threads, chunk, body);
  };
  // Corners c = 3 f + k (edge t[k] -> t[k + 1]) listed by their start vertex, in corner order.
  std::vector<std::uint32_t> first(n_points + 1, 0);
  for (const auto& t : soup.triangles) {
    for (const std::uint32_t v : t) ++first[v + 1];
  }
  for (std::size_t i = 1; i < first.size(); ++i) first[i] += first[i - 1];
  // With each listed corner, its end vertex: the twin search below reads one array.
  std::vector<std::uint32_t> outgoing(n_corners), outgoing_end(n_corners);
  auto corner_end = [&](std::size_t c) { return soup.triangles[c / 3][(c % 3 + 1) % 3]; };
  {
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    for (std::size_t f = 0; f < soup.triangles.size(); ++f) {
      const auto& t = soup.triangles[f];
      for (std::size_t k = 0; k < 3; ++k) {
        const std::uint32_t slot = fill[t[k]]++;
        outgoing[slot] = static_cast<std::uint32_t>(3 * f + k);
        outgoing_end[slot] = t[(k + 1) % 3];
      }
    }
  }
  constexpr auto kNoCorner = std::numeric_limits<std::uint32_t>::max();
  // Each corner's twin (the first listed corner b -> a of its edge a -> b, if any); a corner
  // starts an edge when it has no twin or a later one.
  std::vector<std::uint32_t> twin(n_corners);
  in_chunks(n_corners, [&](std::size_t c) {
    const std::uint32_t a = soup.triangles[c / 3][c % 3], b = corner_end(c);
    std::uint32_t found = kNoCorner;
    for (std::uint32_t i = first[b]; i < first[b + 1]; ++i) {
      if (outgoing_end[i] == a) {
        found = outgoing[i];
        break;
      }
    }
    twin[c] = found;
  });
  outgoing_end = {};
  auto starts_edge = [&twin](std::size_t c) { return twin[c] == kNoCorner || twin[c] > c; };
  // Edges numbered in corner order: each chunk's count, then its first edge number.
  const std::size_t n_chunks = (n_corners + kBuildChunk - 1) / kBuildChunk;
  std::vector<std::size_t> chunk_edges(n_chunks + 1, 0);
  in_chunks(n_chunks, [&](std::size_t k) {
    const std::size_t end = std::min(n_corners, (k + 1) * kBuildChunk);
    for (std::size_t c = k * kBuildChunk; c < end; ++c) chunk_edges[k + 1] += starts_edge(c) ? 1 : 0;
  }, 1);
  for (std::size_t k = 0; k < n_chunks; ++k) chunk_edges[k + 1] += chunk_edges[k];
  const std::size_t n_edges = chunk_edges[n_chunks];
  std::vector<TriMesh::HalfedgeHandle> halfedge(n_corners);
  std::vector<std::uint32_t> edge_corner(n_edges);  // per edge, the corner of its first use
  in_chunks(n_chunks, [&](std::size_t k) {
    const std::size_t end = std::min(n_corners, (k + 1) * kBuildChunk);
    std::size_t e = chunk_edges[k];
    for (std::size_t c = k * kBuildChunk; c < end; ++c) {
      if (!starts_edge(c)) continue;
      // Edge e's halfedges are 2 e (first use, a -> b) and 2 e + 1, as new_edge() numbers them.
      halfedge[c] = TriMesh::HalfedgeHandle(static_cast<int>(2 * e));
      edge_corner[e++] = static_cast<std::uint32_t>(c);
    }
  }, 1);
  // The other corners take their twin's opposite halfedge. A twin that starts no edge
  // itself, or whose own twin is another corner, means an edge used twice in one
  // direction: no oriented 2-manifold (undefined result; left empty, with no two corners
  // on one halfedge: the steps below write each element once).
  std::atomic<bool> refused{false};
  in_chunks(n_corners, [&](std::size_t c) {
    if (starts_edge(c)) return;
    const std::uint32_t t = twin[c];
    if (!starts_edge(t) || twin[t] != c) {
      refused = true;
      return;
    }
    halfedge[c] = mesh.opposite_halfedge_handle(halfedge[t]);
  });
  if (refused.load()) return;
  std::vector<std::uint32_t> boundary;  // corners whose edge has no other face, in corner order
  for (const std::uint32_t c : edge_corner) {
    if (twin[c] == kNoCorner) boundary.push_back(c);
  }
  // All elements at once (add_vertex/new_edge/new_face resize every property per element);
  // the items and properties are the same as when they are added one by one.
  mesh.resize(n_points, n_edges, soup.triangles.size());
  in_chunks(n_points, [&](std::size_t v) {
    const TriMesh::VertexHandle vh(static_cast<int>(v));
    mesh.set_point(vh, to_openmesh(soup.points[v]));
    // add_face() leaves a vertex the halfedge leaving it in its last face: its last listed
    // corner (boundary vertices are set again below).
    if (first[v + 1] > first[v]) mesh.set_halfedge_handle(vh, halfedge[outgoing[first[v + 1] - 1]]);
  });
  outgoing = {};
  in_chunks(n_edges, [&](std::size_t e) {
    const std::uint32_t c = edge_corner[e];
    mesh.set_vertex_handle(halfedge[c], TriMesh::VertexHandle(static_cast<int>(corner_end(c))));
    mesh.set_vertex_handle(mesh.opposite_halfedge_handle(halfedge[c]),
                           TriMesh::VertexHandle(static_cast<int>(soup.triangles[c / 3][c % 3])));
  });
  in_chunks(soup.triangles.size(), [&](std::size_t f) {
    const TriMesh::FaceHandle fh(static_cast<int>(f));
    mesh.set_halfedge_handle(fh, halfedge[3 * f + 2]);
    for (std::size_t k = 0; k < 3; ++k) {
      const auto h = halfedge[3 * f + k];
      mesh.set_face_handle(h, fh);
      mesh.set_next_halfedge_handle(h, halfedge[3 * f + (k + 1) % 3]);
    }
  });
  for (const std::uint32_t c : boundary) {
    const auto h = mesh.opposite_halfedge_handle(halfedge[c]);
    mesh.set_halfedge_handle(mesh.from_vertex_handle(h), h);
  }
  for (const std::uint32_t c : boundary) {
    const auto h = mesh.opposite_halfedge_handle(halfedge[c]);
    mesh.set_next_halfedge_handle(h, mesh.halfedge_handle(mesh.to_vertex_handle(h)));
  }
}

TriangleSoup to_soup(const TriMesh& mesh) {
  TriangleSoup soup;
  std::vector<std::uint32_t> index(mesh.n_vertices(), 0);
  soup.points.reserve(mesh.n_vertices());
  for (auto v : mesh.vertices()) {
    index[v.idx()] = static_cast<std::uint32_t>(soup.points.size());
    soup.points.push_back(to_eigen(mesh.point(v)));
  }
  soup.triangles.reserve(mesh.n_faces());
  for (auto f : mesh.faces()) {
    std::array<std::uint32_t, 3> t{};
    int k = 0;
    for (auto v : f.vertices()) t[k++] = index[v.idx()];
    soup.triangles.push_back(t);
  }
  return soup;
}

}  // namespace nurbsfront
