// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Gauss-Seidel sweeps in vertex order on several threads with the serial sweep's result
// (stitch internal: the smoothing sweeps and the volume compensation's moves).
#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

#include "nurbsfront/core/disjoint_sets.h"
#include "nurbsfront/core/mesh_types.h"
#include "nurbsfront/core/parallel.h"

namespace nurbsfront::stitch_detail {

//! The vertices a sweep tries, cut so that several threads give the serial sweep's result. A
//! vertex reads only its ring (the corners of its faces), so the order matters only between
//! neighbours, the lower index first. `serial`: the vertices given role 1 (border nodes and
//! corners) and every tried vertex before a neighbour of theirs (closed downwards: a tried
//! neighbour of a serial vertex with a lower index is serial), run in vertex order by one
//! thread. The others (role 2: inner nodes) form groups, connected through their edges (a
//! patch's inner nodes, joined where flips made an edge across a border), each run in vertex
//! order by one thread; a group's serial neighbours all have lower indices (the closure), so
//! it starts once the serial run has done the first `ready` of them, and groups share no edge.
struct SweepSchedule {
  std::vector<int> serial;
  std::vector<int> group_vertices;         // group after group, each in vertex order
  std::vector<std::size_t> group_begin;    // group g: group_vertices[group_begin[g], group_begin[g + 1])
  std::vector<std::size_t> group_ready;    // serial vertices done before group g starts
  std::vector<std::size_t> order;          // groups by ready, then by first vertex
};

//! The schedule of the vertices with role[i] != 0 (1: serial, 2: grouped; per vertex index).
inline SweepSchedule sweep_schedule(const TriMesh& mesh, std::vector<std::uint8_t> role) {
  const std::size_t n = mesh.n_vertices();
  for (std::size_t i = n; i-- > 0;) {
    if (role[i] != 1) continue;
    for (auto u : mesh.vv_range(TriMesh::VertexHandle(static_cast<int>(i)))) {
      const auto j = static_cast<std::size_t>(u.idx());
      if (j < i && role[j] == 2) role[j] = 1;
    }
  }
  SweepSchedule s;
  std::vector<std::size_t> position(n, 0);  // serial vertex: 1 + its place in s.serial
  for (std::size_t i = 0; i < n; ++i) {
    if (role[i] != 1) continue;
    s.serial.push_back(static_cast<int>(i));
    position[i] = s.serial.size();
  }
  // One pass over the edges (by index, their two halfedges' vertices; deleted edges
  // skipped as mesh.edges() does): groups by union-find over the edges between group
  // vertices (a class's root is its smallest vertex, whatever the order of the unions), and
  // the edges from a serial vertex to a group vertex kept for the groups' `ready` below.
  DisjointSets sets(n);
  std::vector<std::array<int, 2>> serial_to_group;  // (serial vertex, group vertex)
  const std::size_t n_edges = mesh.n_edges();
  const bool has_status = mesh.has_edge_status();
  for (std::size_t e = 0; e < n_edges; ++e) {
    const TriMesh::EdgeHandle edge(static_cast<int>(e));
    if (has_status && mesh.status(edge).deleted()) continue;
    const auto h = mesh.halfedge_handle(edge, 0);
    const int a = mesh.from_vertex_handle(h).idx(), b = mesh.to_vertex_handle(h).idx();
    const std::uint8_t ra = role[static_cast<std::size_t>(a)], rb = role[static_cast<std::size_t>(b)];
    if (ra == 2 && rb == 2) {
      sets.unite(static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b));
    } else if (ra == 1 && rb == 2) {
      serial_to_group.push_back({a, b});
    } else if (ra == 2 && rb == 1) {
      serial_to_group.push_back({b, a});
    }
  }
  // Group ids in order of their first vertex; then the vertices bucketed by group.
  std::vector<int> group(n, -1);
  std::size_t n_groups = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (role[i] != 2) continue;
    const auto r = static_cast<std::size_t>(sets.find(static_cast<std::uint32_t>(i)));
    if (group[r] < 0) group[r] = static_cast<int>(n_groups++);
    group[i] = group[r];
  }
  s.group_begin.assign(n_groups + 1, 0);
  s.group_ready.assign(n_groups, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (role[i] == 2) ++s.group_begin[static_cast<std::size_t>(group[i]) + 1];
  }
  for (std::size_t g = 0; g < n_groups; ++g) s.group_begin[g + 1] += s.group_begin[g];
  s.group_vertices.resize(s.group_begin[n_groups]);
  std::vector<std::size_t> fill(s.group_begin.begin(), s.group_begin.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    if (role[i] == 2) s.group_vertices[fill[static_cast<std::size_t>(group[i])]++] = static_cast<int>(i);
  }
  for (const auto& [a, b] : serial_to_group) {
    std::size_t& ready = s.group_ready[static_cast<std::size_t>(group[static_cast<std::size_t>(b)])];
    ready = std::max(ready, position[static_cast<std::size_t>(a)]);
  }
  s.order.resize(n_groups);
  std::iota(s.order.begin(), s.order.end(), std::size_t{0});
  std::stable_sort(s.order.begin(), s.order.end(),
                   [&s](std::size_t x, std::size_t y) { return s.group_ready[x] < s.group_ready[y]; });
  return s;
}

//! Runs visit(v, worker) for every vertex of `schedule` on n_threads threads (worker <
//! n_threads): the serial vertices in order on one thread, each group in order on one
//! thread once the serial run has done its `ready` vertices. visit must read only v's ring
//! and write only v (and per-worker state).
template <class Visit>
void run_schedule(const SweepSchedule& schedule, unsigned n_threads, const Visit& visit) {
  std::atomic<std::size_t> done{0};        // serial vertices done
  std::atomic<std::size_t> next_group{0};  // next place in schedule.order to take
  std::atomic<bool> failed{false};
  constexpr std::size_t kNotifyEvery = 64;
  const std::size_t n_serial = schedule.serial.size();
  auto run_groups = [&](unsigned worker) {
    for (;;) {
      const std::size_t k = next_group.fetch_add(1);
      if (k >= schedule.order.size() || failed.load()) return;
      const std::size_t g = schedule.order[k];
      const std::size_t ready = schedule.group_ready[g];
      for (std::size_t seen = done.load(std::memory_order_acquire); seen < ready;
           seen = done.load(std::memory_order_acquire)) {
        done.wait(seen, std::memory_order_acquire);
      }
      if (failed.load()) return;
      for (std::size_t i = schedule.group_begin[g]; i < schedule.group_begin[g + 1]; ++i) {
        visit(TriMesh::VertexHandle(schedule.group_vertices[i]), worker);
      }
    }
  };
  parallel::for_chunks(n_threads, n_threads, 1, [&](std::size_t role, std::size_t, unsigned worker) {
    if (role == 0) {
      try {
        for (std::size_t i = 0; i < n_serial; ++i) {
          visit(TriMesh::VertexHandle(schedule.serial[i]), worker);
          done.store(i + 1, std::memory_order_release);
          if ((i + 1) % kNotifyEvery == 0) done.notify_all();
        }
      } catch (...) {
        failed = true;
        done.store(n_serial, std::memory_order_release);
        done.notify_all();
        throw;
      }
      done.notify_all();
    }
    run_groups(worker);
  });
}

}  // namespace nurbsfront::stitch_detail
