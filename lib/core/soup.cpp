// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/core/soup.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include "nurbsfront/core/error.h"

namespace nurbsfront {

BoundingBox bounding_box(const TriangleSoup& soup) {
  BoundingBox box;
  for (const auto& p : soup.points) box.extend(p);
  return box;
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
  ManifoldCheck check;
  const auto n_points = static_cast<std::uint64_t>(soup.points.size());
  // Directed edges (from, to) of the valid triangles.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> directed;
  directed.reserve(soup.triangles.size() * 3);
  for (const auto& t : soup.triangles) {
    if (t[0] >= n_points || t[1] >= n_points || t[2] >= n_points) {
      ++check.n_bad_indices;
      continue;
    }
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
      ++check.n_repeated_index;
      continue;
    }
    for (int k = 0; k < 3; ++k) directed.emplace_back(t[k], t[(k + 1) % 3]);
  }
  // Undirected multiplicity and orientation of each edge.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> undirected(directed.size());
  std::transform(directed.begin(), directed.end(), undirected.begin(), [](auto e) {
    return std::make_pair(std::min(e.first, e.second), std::max(e.first, e.second));
  });
  std::sort(undirected.begin(), undirected.end());
  for (std::size_t i = 0; i < undirected.size();) {
    std::size_t j = i;
    while (j < undirected.size() && undirected[j] == undirected[i]) ++j;
    if (j - i > 2) ++check.n_nonmanifold_edges;
    i = j;
  }
  std::sort(directed.begin(), directed.end());
  for (std::size_t i = 1; i < directed.size(); ++i) {
    if (directed[i] == directed[i - 1] && (i < 2 || directed[i - 2] != directed[i])) {
      ++check.n_misoriented_edges;
    }
  }
  if (check.n_nonmanifold_edges + check.n_misoriented_edges + check.n_bad_indices +
          check.n_repeated_index > 0) {
    return check;  // the fan test below assumes a manifold, oriented edge structure
  }
  // Vertex fans: at vertex a, triangle (a, b, c) links b -> c. With manifold oriented
  // edges every b has at most one successor; one fan means one chain or one cycle.
  std::vector<std::uint32_t> first(n_points + 1, 0);
  for (const auto& t : soup.triangles) {
    for (int k = 0; k < 3; ++k) ++first[t[k] + 1];
  }
  for (std::size_t i = 1; i < first.size(); ++i) first[i] += first[i - 1];
  std::vector<std::pair<std::uint32_t, std::uint32_t>> links(first.back());
  std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
  for (const auto& t : soup.triangles) {
    for (int k = 0; k < 3; ++k) links[fill[t[k]]++] = {t[(k + 1) % 3], t[(k + 2) % 3]};
  }
  std::unordered_map<std::uint32_t, std::uint32_t> next;
  std::unordered_map<std::uint32_t, bool> is_target;
  for (std::uint64_t v = 0; v < n_points; ++v) {
    const std::uint32_t begin = first[v], end = first[v + 1];
    if (end - begin <= 1) continue;
    next.clear();
    is_target.clear();
    for (std::uint32_t i = begin; i < end; ++i) {
      next[links[i].first] = links[i].second;
      is_target[links[i].second] = true;
    }
    std::size_t n_chains = 0;
    std::size_t visited = 0;
    for (std::uint32_t i = begin; i < end; ++i) {
      std::uint32_t b = links[i].first;
      if (is_target.count(b)) continue;  // not the start of an open chain
      ++n_chains;
      for (auto it = next.find(b); it != next.end(); it = next.find(it->second)) ++visited;
    }
    const std::size_t n_links = end - begin;
    // Links not on an open chain form cycles; one fan = one open chain covering all,
    // or no open chain and one cycle covering all.
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

TriMesh to_trimesh(const TriangleSoup& soup) {
  for (const auto& p : soup.points) {
    if (!p.allFinite()) throw InvalidInput("nurbsfront: mesh has non-finite (NaN or infinite) coordinates");
  }
  const ManifoldCheck check = check_manifold(soup);
  if (!check.ok()) throw TopologyError("nurbsfront: mesh is not an oriented 2-manifold: " + check.message());
  TriMesh mesh;
  mesh.reserve(soup.points.size(), soup.triangles.size() * 3 / 2 + soup.points.size(), soup.triangles.size());
  std::vector<TriMesh::VertexHandle> handles;
  handles.reserve(soup.points.size());
  for (const auto& p : soup.points) handles.push_back(mesh.add_vertex(to_openmesh(p)));
  for (const auto& t : soup.triangles) {
    const auto f = mesh.add_face(handles[t[0]], handles[t[1]], handles[t[2]]);
    if (!f.is_valid()) throw InternalError("nurbsfront: OpenMesh rejected a face that passed check_manifold");
  }
  return mesh;
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
