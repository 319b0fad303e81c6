// SPDX-License-Identifier: BSD-3-Clause
// The height-field check of a patch (its projected border must be simple polygons with a
// single outer loop) and the split of a patch that fails it.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/polygon.h"
#include "nurbsfront/segment/segment_internal.h"

namespace nurbsfront::segment_detail {
namespace {

double orient(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

// c lies in the bounding box of segment ab (used when the three points are collinear).
bool in_box(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return std::min(a.x(), b.x()) <= c.x() && c.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= c.y() && c.y() <= std::max(a.y(), b.y());
}

// Closed segments ab and cd meet (crossing, touching or overlapping).
bool segments_meet(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                   const Eigen::Vector2d& d) {
  const double d1 = orient(c, d, a), d2 = orient(c, d, b), d3 = orient(a, b, c), d4 = orient(a, b, d);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  return (d1 == 0 && in_box(c, d, a)) || (d2 == 0 && in_box(c, d, b)) || (d3 == 0 && in_box(a, b, c)) ||
         (d4 == 0 && in_box(a, b, d));
}

struct Segment {
  int a = -1, b = -1;
};

// Extra outer loops up to this many edges are reported as local trouble.
constexpr std::size_t kMaxTroubleLoopEdges = 24;
// Crossing border segment pairs reported as local trouble by one check: all of a patch's
// local folds are cut out at once instead of one per check of the whole patch.
constexpr std::size_t kMaxTroubleCrossings = 256;

// Pairs of segments that share no vertex but meet (as indices), at most max_pairs of them
// (each pair once); a uniform grid keeps the search near linear.
std::vector<std::pair<int, int>> find_crossings(const std::vector<Segment>& segments, const std::vector<Eigen::Vector2d>& xy,
                                                std::size_t max_pairs) {
  const auto n = static_cast<int>(segments.size());
  Eigen::Vector2d lo = xy[segments[0].a], hi = lo;
  for (const Segment& s : segments) {
    lo = lo.cwiseMin(xy[s.a]);
    hi = hi.cwiseMax(xy[s.a]);
  }
  const int cells = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(n))));
  const Eigen::Vector2d extent = hi - lo;
  const double width_x = extent.x() > 0 ? extent.x() / cells : 1.0;
  const double width_y = extent.y() > 0 ? extent.y() / cells : 1.0;
  auto cell_of = [&](double value, double origin, double width) {
    return std::clamp(static_cast<int>((value - origin) / width), 0, cells - 1);
  };
  // (cell, segment) entries ordered by cell, then segment: a counting sort by cell over
  // the segments in index order. Each segment's cell range is computed once (both passes
  // read it).
  std::vector<std::array<int, 4>> ranges(segments.size());
  std::vector<int> cell_start(static_cast<std::size_t>(cells) * cells + 1, 0);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d& p = xy[segments[i].a];
    const Eigen::Vector2d& q = xy[segments[i].b];
    const int x0 = cell_of(std::min(p.x(), q.x()), lo.x(), width_x), x1 = cell_of(std::max(p.x(), q.x()), lo.x(), width_x);
    const int y0 = cell_of(std::min(p.y(), q.y()), lo.y(), width_y), y1 = cell_of(std::max(p.y(), q.y()), lo.y(), width_y);
    ranges[i] = {x0, x1, y0, y1};
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) ++cell_start[y * cells + x + 1];
  }
  for (std::size_t c = 1; c < cell_start.size(); ++c) cell_start[c] += cell_start[c - 1];
  std::vector<std::pair<int, int>> entries(static_cast<std::size_t>(cell_start.back()));
  std::vector<int> fill(cell_start.begin(), cell_start.end() - 1);
  for (int i = 0; i < n; ++i) {
    const auto [x0, x1, y0, y1] = ranges[i];
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) entries[fill[y * cells + x]++] = {y * cells + x, i};
  }
  std::vector<std::pair<int, int>> found;
  for (std::size_t begin = 0; begin < entries.size();) {
    std::size_t end = begin;
    while (end < entries.size() && entries[end].first == entries[begin].first) ++end;
    for (std::size_t i = begin; i < end; ++i) {
      const Segment& s = segments[entries[i].second];
      for (std::size_t j = i + 1; j < end; ++j) {
        const Segment& t = segments[entries[j].second];
        if (s.a == t.a || s.a == t.b || s.b == t.a || s.b == t.b) continue;
        if (segments_meet(xy[s.a], xy[s.b], xy[t.a], xy[t.b])) {
          found.emplace_back(std::min(entries[i].second, entries[j].second), std::max(entries[i].second, entries[j].second));
        }
      }
    }
    if (found.size() >= max_pairs) break;
    begin = end;
  }
  // A pair in several common cells is found once per cell.
  std::sort(found.begin(), found.end());
  found.erase(std::unique(found.begin(), found.end()), found.end());
  if (found.size() > max_pairs) found.resize(max_pairs);
  return found;
}

// find_crossings() when the segments before n_known are known to meet none of each other
// (a patch's border that passed the check in the same plane): only pairs with a later
// segment are tested, against the segments whose boxes meet the later ones' box. Falls back
// to the grid when that would test too many pairs.
std::vector<std::pair<int, int>> find_crossings_after(const std::vector<Segment>& segments,
                                                      const std::vector<Eigen::Vector2d>& xy,
                                                      std::size_t n_known, std::size_t max_pairs) {
  const std::size_t n = segments.size();
  if (n_known == 0 || n_known >= n)
    return n_known >= n ? std::vector<std::pair<int, int>>{} : find_crossings(segments, xy, max_pairs);
  Eigen::Vector2d lo = xy[segments[n_known].a], hi = lo;
  for (std::size_t j = n_known; j < n; ++j) {
    for (int v : {segments[j].a, segments[j].b}) {
      lo = lo.cwiseMin(xy[v]);
      hi = hi.cwiseMax(xy[v]);
    }
  }
  std::vector<int> near;  // known segments whose box meets the later segments' box
  for (std::size_t i = 0; i < n_known; ++i) {
    const Eigen::Vector2d& p = xy[segments[i].a];
    const Eigen::Vector2d& q = xy[segments[i].b];
    if (std::max(p.x(), q.x()) < lo.x() || std::min(p.x(), q.x()) > hi.x() ||
        std::max(p.y(), q.y()) < lo.y() || std::min(p.y(), q.y()) > hi.y())
      continue;
    near.push_back(static_cast<int>(i));
  }
  const std::size_t n_new = n - n_known;
  if (n_new * (near.size() + n_new) > 16 * n) return find_crossings(segments, xy, max_pairs);
  std::vector<std::pair<int, int>> found;
  auto test = [&](int i, int j) {
    const Segment& s = segments[i];
    const Segment& t = segments[j];
    if (s.a == t.a || s.a == t.b || s.b == t.a || s.b == t.b) return;
    if (segments_meet(xy[s.a], xy[s.b], xy[t.a], xy[t.b])) found.emplace_back(i, j);
  };
  for (std::size_t j = n_known; j < n; ++j) {
    for (const int i : near) test(i, static_cast<int>(j));
    for (std::size_t k = n_known; k < j; ++k) test(static_cast<int>(k), static_cast<int>(j));
  }
  std::sort(found.begin(), found.end());
  if (found.size() > max_pairs) found.resize(max_pairs);
  return found;
}

// The vertices of a counter-clockwise cycle lying inside another counter-clockwise cycle,
// or empty. Cycles of different loops never nest that way when the loops' segments do not
// cross, and each cycle is tested by one vertex it does not share with the other.
std::vector<int> nested_ccw_cycle(const std::vector<std::vector<int>>& cycles, const std::vector<Eigen::Vector2d>& xy) {
  std::vector<std::size_t> ccw;
  for (std::size_t k = 0; k < cycles.size(); ++k) {
    const std::vector<int>& c = cycles[k];
    if (c.size() < 3) continue;
    double twice_area = 0.0;
    for (std::size_t i = 1; i + 1 < c.size(); ++i) twice_area += orient(xy[c[0]], xy[c[i]], xy[c[i + 1]]);
    if (twice_area > 0) ccw.push_back(k);
  }
  if (ccw.size() < 2) return {};
  for (const std::size_t inner : ccw)
    for (const std::size_t outer : ccw) {
      if (inner == outer) continue;
      const std::vector<int>& in = cycles[inner];
      const std::vector<int>& out = cycles[outer];
      const auto probe = std::find_if(in.begin(), in.end(), [&](int v) { return std::find(out.begin(), out.end(), v) == out.end(); });
      if (probe == in.end()) continue;
      const auto corner = [&](std::size_t i) -> const Eigen::Vector2d& { return xy[static_cast<std::size_t>(out[i])]; };
      if (polygon_contains(out.size(), corner, xy[static_cast<std::size_t>(*probe)])) return in;
    }
  return {};
}

// split_at_repeated_vertices() of a loop, appended to `out`, with a per-vertex position
// array (all -1 before and after) instead of a sort and a hash map: the same cycles in
// the same order, in time linear in the loop.
void split_loop(const int* first, const int* last, std::vector<int>& position, std::vector<std::vector<int>>& out) {
  std::vector<int> stack;
  for (const int v : std::span<const int>(first, last)) {
    const int at = position[v];
    if (at < 0) {
      position[v] = static_cast<int>(stack.size());
      stack.push_back(v);
      continue;
    }
    // v closes the cycle stack[at ..]: emit it and keep v on the stack.
    out.emplace_back(stack.begin() + at, stack.end());
    for (std::size_t i = static_cast<std::size_t>(at) + 1; i < stack.size(); ++i) position[stack[i]] = -1;
    stack.resize(static_cast<std::size_t>(at) + 1);
  }
  for (const int v : stack) position[v] = -1;
  if (!stack.empty()) out.push_back(std::move(stack));
}

// Breadth-first search inside the patch (of n_faces faces) from `sources`; every reached
// face gets the index of the source it was reached from in scratch.face_owner. Returns the
// last face reached. The queue is scratch.face_queue, at least n_faces long (no growth).
template <std::size_t N>
int breadth_first(const FaceGraph& graph, const std::array<int, N>& sources, std::size_t n_faces,
                  const std::vector<int>& face_patch, Scratch& scratch) {
  const int patch = face_patch[sources[0]];
  const int epoch = ++scratch.face_epoch;
  std::vector<int>& queue = scratch.face_queue;
  if (queue.size() < n_faces) queue.resize(n_faces);
  std::size_t tail = 0;
  for (std::size_t k = 0; k < N; ++k) {
    scratch.face_stamp[sources[k]] = epoch;
    scratch.face_owner[sources[k]] = static_cast<int>(k);
    queue[tail++] = sources[k];
  }
  for (std::size_t head = 0; head < tail; ++head) {
    const int f = queue[head];
    for (int i = 0; i < 3; ++i) {
      const int g = graph.neighbours[f][i];
      if (g < 0 || face_patch[g] != patch || scratch.face_stamp[g] == epoch) continue;
      NURBSFRONT_ASSERT(tail < n_faces);
      scratch.face_stamp[g] = epoch;
      scratch.face_owner[g] = scratch.face_owner[f];
      queue[tail++] = g;
    }
  }
  return queue[tail - 1];
}

}  // namespace

std::pair<Eigen::Vector3d, Eigen::Vector3d> plane_frame(const Eigen::Vector3d& axis) {
  Eigen::Index smallest = 0;
  axis.cwiseAbs().minCoeff(&smallest);
  const Eigen::Vector3d helper = Eigen::Vector3d::Unit(smallest);
  const Eigen::Vector3d e1 = (helper - helper.dot(axis) * axis).normalized();
  return {e1, axis.cross(e1)};
}

std::vector<OpenMesh::HalfedgeHandle> patch_border(const FaceGraph& graph, const std::vector<int>& faces,
                                                   const std::vector<int>& face_patch) {
  std::vector<OpenMesh::HalfedgeHandle> border;
  if (faces.empty()) return border;
  const int patch = face_patch[faces[0]];
  // The face graph's arrays hold the mesh's halfedges of each face in its halfedge order.
  for (int f : faces) {
    for (int i = 0; i < 3; ++i) {
      const int g = graph.neighbours[f][i];
      if (g < 0 || face_patch[g] != patch) border.emplace_back(graph.halfedges[f][i]);
    }
  }
  return border;
}

ProjectionCheck check_projection(const FaceGraph& graph, const std::vector<int>& faces,
                                 const std::vector<int>& face_patch, const Eigen::Vector3d& axis, Scratch& scratch) {
  if (faces.size() <= 1) return {true, {}};
  return check_projection(graph, patch_border(graph, faces, face_patch), face_patch, axis, scratch);
}

ProjectionCheck check_projection(const FaceGraph& graph, const std::vector<OpenMesh::HalfedgeHandle>& border,
                                 const std::vector<int>& face_patch, const Eigen::Vector3d& axis,
                                 Scratch& scratch, std::size_t n_known) {
  if (border.empty()) return {false, {}};  // a closed surface is never a height field
  const TriMesh& mesh = *graph.mesh;
  const int patch = face_patch[mesh.face_handle(border[0]).idx()];
  const int epoch = ++scratch.vertex_epoch;
  const auto [e1, e2] = plane_frame(axis);
  auto in_patch = [&](OpenMesh::HalfedgeHandle h) {
    const auto f = mesh.face_handle(h);
    return f.is_valid() && face_patch[f.idx()] == patch;
  };
  std::vector<Segment> segments;
  segments.reserve(border.size());
  for (const auto h : border) {
    const int a = mesh.from_vertex_handle(h).idx(), b = mesh.to_vertex_handle(h).idx();
    for (int v : {a, b}) {
      if (scratch.vertex_stamp[v] == epoch) continue;
      scratch.vertex_stamp[v] = epoch;
      scratch.border_out[v] = -2;  // none seen yet
      const Eigen::Vector3d& p = graph.points[v];
      scratch.xy[v] = Eigen::Vector2d(p.dot(e1), p.dot(e2));
    }
    scratch.border_out[a] = scratch.border_out[a] == -2 ? h.idx() : -1;
    segments.push_back({a, b});
  }
  // The border halfedge after h: the one leaving h's end, found by turning through the
  // patch's faces around that vertex where several leave it.
  auto next_border = [&](OpenMesh::HalfedgeHandle h) {
    const int out = scratch.border_out[mesh.to_vertex_handle(h).idx()];
    if (out >= 0) return OpenMesh::HalfedgeHandle(out);
    auto next = mesh.next_halfedge_handle(h);
    while (in_patch(mesh.opposite_halfedge_handle(next)))
      next = mesh.next_halfedge_handle(mesh.opposite_halfedge_handle(next));
    return next;
  };
  // Loops, traced through the patch's own faces around each vertex, so a loop passing a
  // vertex twice (where the patch touches itself) stays apart from the other. At most one
  // loop may be counter-clockwise (the outer loop); two would mean a region covered twice.
  std::vector<std::pair<std::size_t, OpenMesh::HalfedgeHandle>> outer;  // (edges, start) per outer loop
  // Each loop's vertices in order, one after the other (loop k is loop_vertices[loop_begin[k]
  // .. loop_begin[k + 1])), and whether any loop passes a vertex twice.
  std::vector<int> loop_vertices, loop_begin;
  std::vector<std::uint8_t> loop_repeats;
  loop_vertices.reserve(segments.size());
  for (const auto start : border) {
    if (scratch.halfedge_stamp[start.idx()] == epoch) continue;
    const Eigen::Vector2d origin = scratch.xy[mesh.from_vertex_handle(start).idx()];
    double twice_area = 0.0;
    auto h = start;
    std::size_t steps = 0;
    loop_begin.push_back(static_cast<int>(loop_vertices.size()));
    const int loop = ++scratch.loop_epoch;
    bool repeats = false;
    do {
      scratch.halfedge_stamp[h.idx()] = epoch;
      const int from = mesh.from_vertex_handle(h).idx();
      loop_vertices.push_back(from);
      repeats = repeats || scratch.loop_stamp[from] == loop;
      scratch.loop_stamp[from] = loop;
      twice_area += orient(origin, scratch.xy[from], scratch.xy[mesh.to_vertex_handle(h).idx()]);
      h = next_border(h);
      NURBSFRONT_ASSERT(++steps <= segments.size());
    } while (h != start);
    loop_repeats.push_back(repeats ? 1 : 0);
    if (twice_area > 0) outer.emplace_back(steps, start);
  }
  loop_begin.push_back(static_cast<int>(loop_vertices.size()));
  if (outer.size() > 1) {
    // Every outer loop but the largest one is extra; the short ones are local trouble
    // (all reported, so they are cut out together). Ties keep the first loop found.
    std::stable_sort(outer.begin(), outer.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    ProjectionCheck check{false, {}};
    if (outer[0].first > kMaxTroubleLoopEdges) return check;
    for (std::size_t k = 0; k + 1 < outer.size() && outer[k].first <= kMaxTroubleLoopEdges; ++k) {
      auto h = outer[k].second;
      do {
        check.trouble.push_back(mesh.from_vertex_handle(h).idx());
        h = next_border(h);
      } while (h != outer[k].second);
    }
    return check;
  }
  // A loop that passes a vertex twice may hide a counter-clockwise cycle inside another
  // one (a neighbour's face seen from below, touching the outer loop at a corner): the
  // region inside both is covered twice although the loop's total area looks right.
  // Where no loop passes a vertex twice, the cycles are the loops, and a loop's twice-area
  // from its first vertex is the cycle's sum in nested_ccw_cycle() (the same products in the
  // same order, plus two exact zeros): at most one of them (the outer loop) is
  // counter-clockwise, so none is nested and the cycles are not built.
  if (std::find(loop_repeats.begin(), loop_repeats.end(), 1) != loop_repeats.end()) {
    std::vector<std::vector<int>> cycles;  // the loops' simple cycles (split where a loop passes a vertex twice)
    for (std::size_t k = 0; k < loop_repeats.size(); ++k) {
      const int* first = loop_vertices.data() + loop_begin[k];
      const int* last = loop_vertices.data() + loop_begin[k + 1];
      if (loop_repeats[k] != 0) {
        split_loop(first, last, scratch.cycle_position, cycles);
      } else {
        cycles.emplace_back(first, last);
      }
    }
    const std::vector<int> nested = nested_ccw_cycle(cycles, scratch.xy);
    if (!nested.empty()) return {false, nested.size() <= kMaxTroubleLoopEdges ? nested : std::vector<int>{}};
  }
  const std::vector<std::pair<int, int>> crossings =
      find_crossings_after(segments, scratch.xy, n_known, kMaxTroubleCrossings);
  if (crossings.empty()) return {true, {}};
  ProjectionCheck check{false, {}};
  for (const auto& [i, j] : crossings) check.trouble.insert(check.trouble.end(), {segments[i].a, segments[i].b, segments[j].a, segments[j].b});
  return check;
}

std::pair<std::vector<int>, std::vector<int>> bisect_patch(const FaceGraph& graph, const std::vector<int>& faces,
                                                           const std::vector<int>& face_patch, Scratch& scratch) {
  NURBSFRONT_ASSERT(faces.size() >= 2);
  const int far = breadth_first(graph, std::array{faces[0]}, faces.size(), face_patch, scratch);
  const int farther = breadth_first(graph, std::array{far}, faces.size(), face_patch, scratch);
  NURBSFRONT_ASSERT(far != farther);
  (void)breadth_first(graph, std::array{far, farther}, faces.size(), face_patch, scratch);
  std::pair<std::vector<int>, std::vector<int>> parts;
  for (int f : faces) {
    NURBSFRONT_ASSERT(scratch.face_stamp[f] == scratch.face_epoch);  // the patch is connected
    (scratch.face_owner[f] == 0 ? parts.first : parts.second).push_back(f);
  }
  return parts;
}

}  // namespace nurbsfront::segment_detail

namespace nurbsfront {

std::vector<std::vector<int>> split_at_repeated_vertices(const std::vector<int>& loop) {
  std::vector<int> sorted = loop;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end()) return {loop};  // the usual case
  // The loop's vertices renumbered 0 .. k-1, so split_loop's position array is as long as
  // the loop, whatever the vertex ids.
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  std::vector<int> local(loop.size());
  for (std::size_t i = 0; i < loop.size(); ++i)
    local[i] = static_cast<int>(std::lower_bound(sorted.begin(), sorted.end(), loop[i]) - sorted.begin());
  std::vector<int> position(sorted.size(), -1);
  std::vector<std::vector<int>> out;
  segment_detail::split_loop(local.data(), local.data() + local.size(), position, out);
  for (auto& cycle : out)
    for (int& v : cycle) v = sorted[static_cast<std::size_t>(v)];
  return out;
}

}  // namespace nurbsfront
