// SPDX-License-Identifier: BSD-3-Clause
// The height-field check of a patch (its projected border must be simple polygons with a
// single outer loop) and the split of a patch that fails it.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>

#include "nurbsfront/core/error.h"
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
  // the segments in index order.
  auto cell_range = [&](int i) {
    const Eigen::Vector2d& p = xy[segments[i].a];
    const Eigen::Vector2d& q = xy[segments[i].b];
    return std::array<int, 4>{
        cell_of(std::min(p.x(), q.x()), lo.x(), width_x), cell_of(std::max(p.x(), q.x()), lo.x(), width_x),
        cell_of(std::min(p.y(), q.y()), lo.y(), width_y), cell_of(std::max(p.y(), q.y()), lo.y(), width_y)};
  };
  std::vector<int> cell_start(static_cast<std::size_t>(cells) * cells + 1, 0);
  for (int i = 0; i < n; ++i) {
    const auto [x0, x1, y0, y1] = cell_range(i);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) ++cell_start[y * cells + x + 1];
  }
  for (std::size_t c = 1; c < cell_start.size(); ++c) cell_start[c] += cell_start[c - 1];
  std::vector<std::pair<int, int>> entries(static_cast<std::size_t>(cell_start.back()));
  std::vector<int> fill(cell_start.begin(), cell_start.end() - 1);
  for (int i = 0; i < n; ++i) {
    const auto [x0, x1, y0, y1] = cell_range(i);
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

bool polygon_contains(const std::vector<int>& cycle, const std::vector<Eigen::Vector2d>& xy, const Eigen::Vector2d& q) {
  bool inside = false;
  for (std::size_t i = 0, j = cycle.size() - 1; i < cycle.size(); j = i++) {
    const Eigen::Vector2d& a = xy[cycle[i]];
    const Eigen::Vector2d& b = xy[cycle[j]];
    if ((a.y() > q.y()) != (b.y() > q.y()) && q.x() < a.x() + (q.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y()))
      inside = !inside;
  }
  return inside;
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
      if (probe != in.end() && polygon_contains(out, xy, xy[*probe])) return in;
    }
  return {};
}

// split_at_repeated_vertices() of a loop, appended to `out`, with a per-vertex position
// array (all -1 before and after) instead of a sort and a hash map: the same cycles in
// the same order, in time linear in the loop.
void split_loop(const std::vector<int>& loop, std::vector<int>& position, std::vector<std::vector<int>>& out) {
  std::vector<int> stack;
  for (const int v : loop) {
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
  std::vector<std::vector<int>> cycles;  // the loops' simple cycles (split where a loop passes a vertex twice)
  std::vector<int> loop_vertices;
  for (const auto start : border) {
    if (scratch.halfedge_stamp[start.idx()] == epoch) continue;
    const Eigen::Vector2d origin = scratch.xy[mesh.from_vertex_handle(start).idx()];
    double twice_area = 0.0;
    auto h = start;
    std::size_t steps = 0;
    loop_vertices.clear();
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
    if (repeats) {
      split_loop(loop_vertices, scratch.cycle_position, cycles);
    } else {
      cycles.push_back(loop_vertices);
    }
    if (twice_area > 0) outer.emplace_back(steps, start);
  }
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
  const std::vector<int> nested = nested_ccw_cycle(cycles, scratch.xy);
  if (!nested.empty()) return {false, nested.size() <= kMaxTroubleLoopEdges ? nested : std::vector<int>{}};
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

namespace {
// The unit roundoff of double (2^-53).
constexpr double kRoundoff = std::numeric_limits<double>::epsilon() / 2.0;
}  // namespace

void MergeProjection::Loop::add(const Eigen::Vector2d& origin, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                const double sign) {
  // orient(origin, a, b) with the rounding of each of its terms bounded: the exact value is
  // within 4 roundoffs of the two products' sum of magnitudes (5 taken), the running sum
  // within one of its magnitude per step.
  const double p1 = (a.x() - origin.x()) * (b.y() - origin.y());
  const double p2 = (a.y() - origin.y()) * (b.x() - origin.x());
  sum += sign * (p1 - p2);
  error += 5.0 * kRoundoff * (std::abs(p1) + std::abs(p2)) + kRoundoff * std::abs(sum);
  lo = lo.cwiseMin(a).cwiseMin(b);
  hi = hi.cwiseMax(a).cwiseMax(b);
}

int MergeProjection::Loop::sign() const {
  // check_projection() sums a loop's n terms from one of its vertices: each term is at most
  // 2 w_x w_y (the box's sides) and is rounded by at most 4 roundoffs of that, each partial
  // sum by one roundoff of at most k terms, so its sum is within 2 w_x w_y u n (n + 12) of
  // the exact twice-area. Beyond both bounds the exact area, and so that sum, has this sign.
  const Eigen::Vector2d w = hi - lo;
  const auto m = static_cast<double>(n);
  const double theirs = 2.0 * w.x() * w.y() * kRoundoff * m * (m + 12.0);
  const double bound = 1.01 * (error + theirs);
  if (sum > bound) return 1;
  if (sum < -bound) return -1;
  return 0;
}

MergeProjection::MergeProjection(const FaceGraph& graph)
    : graph_(graph),
      vertex_stamp_(graph.points.size(), -1),
      vertex_out_(graph.points.size(), -1),
      halfedge_stamp_(graph.mesh->n_halfedges(), -1),
      halfedge_pos_(graph.mesh->n_halfedges(), -1),
      halfedge_loop_(graph.mesh->n_halfedges(), -1),
      halfedge_slot_(graph.mesh->n_halfedges(), -1) {}

Eigen::Vector2d MergeProjection::xy(const int v) const {
  // As check_projection() projects (the same doubles).
  const Eigen::Vector3d& p = graph_.points[v];
  return Eigen::Vector2d(p.dot(e1_), p.dot(e2_));
}

int MergeProjection::degree(const int v, const int patch, const std::vector<int>& face_patch) const {
  const TriMesh& mesh = *graph_.mesh;
  int n = 0;
  for (const auto h : mesh.voh_range(mesh.vertex_handle(static_cast<unsigned>(v)))) {
    const auto f = mesh.face_handle(h);
    if (!f.is_valid() || face_patch[f.idx()] != patch) continue;
    const auto g = mesh.opposite_face_handle(h);
    if (!g.is_valid() || face_patch[g.idx()] != patch) ++n;
  }
  return n;
}

void MergeProjection::build(PatchState& state, const std::vector<OpenMesh::HalfedgeHandle>& border,
                            const bool with_loops) {
  const TriMesh& mesh = *graph_.mesh;
  const int epoch = ++vertex_epoch_;
  state.pinched = 0;
  for (const auto h : border) {
    const int a = mesh.from_vertex_handle(h).idx();
    if (vertex_stamp_[a] != epoch) {
      vertex_stamp_[a] = epoch;
      vertex_out_[a] = h.idx();
    } else if (vertex_out_[a] >= 0) {
      vertex_out_[a] = -1;
      ++state.pinched;
    }
  }
  state.has_loops = false;
  state.loops.clear();
  state.segments.clear();
  state.n_live = state.n_outer = state.n_unsure = 0;
  if (!with_loops || state.pinched != 0 || border.empty()) return;
  state.origin = xy(mesh.from_vertex_handle(border[0]).idx());
  state.segments.reserve(border.size());
  for (const auto h : border) {
    const int a = mesh.from_vertex_handle(h).idx(), b = mesh.to_vertex_handle(h).idx();
    halfedge_slot_[h.idx()] = static_cast<int>(state.segments.size());
    state.segments.push_back({h.idx(), a, b, xy(a), xy(b)});
  }
  // No vertex is passed twice: a loop follows each vertex's only outgoing border halfedge.
  const int loop_epoch = ++halfedge_epoch_;
  for (const auto start : border) {
    if (halfedge_stamp_[start.idx()] == loop_epoch) continue;
    const int id = static_cast<int>(state.loops.size());
    Loop loop;
    int h = start.idx();
    do {
      halfedge_stamp_[h] = loop_epoch;
      halfedge_loop_[h] = id;
      const Segment& s = state.segments[static_cast<std::size_t>(halfedge_slot_[h])];
      loop.add(state.origin, s.xa, s.xb, 1.0);
      ++loop.n;
      NURBSFRONT_ASSERT(vertex_stamp_[s.b] == epoch && loop.n <= border.size());
      h = vertex_out_[s.b];
    } while (h != start.idx());
    const int sign = loop.sign();
    state.n_outer += sign > 0 ? 1 : 0;
    state.n_unsure += sign == 0 ? 1 : 0;
    state.loops.push_back(loop);
  }
  state.n_live = state.loops.size();
  state.has_loops = true;
}

void MergeProjection::prepare(const int into, const int from, const std::vector<OpenMesh::HalfedgeHandle>& into_border,
                              const std::vector<OpenMesh::HalfedgeHandle>& from_border,
                              const std::vector<int>& face_patch, const Eigen::Vector3d& old_axis,
                              const Eigen::Vector3d& new_axis) {
  const TriMesh& mesh = *graph_.mesh;
  const auto needed = static_cast<std::size_t>(std::max(into, from)) + 1;
  if (states_.size() < needed) states_.resize(needed);
  PatchState& state = states_[static_cast<std::size_t>(into)];
  Pending& pd = pending_;
  pd.into = into;
  pd.from = from;
  pd.axis = new_axis;
  pd.from_border = from_border;
  pd.incremental = false;
  pd.pinched = -1;
  const bool same_axis = old_axis == new_axis;
  if (state.pinched < 0 || (state.has_loops && state.axis != old_axis) ||
      (state.pinched == 0 && !state.has_loops && same_axis)) {
    std::tie(e1_, e2_) = plane_frame(old_axis);
    build(state, into_border, same_axis);
    state.axis = old_axis;
  }
  // from's border vertices, and how many of them into's border passes twice.
  pd.vertices.clear();
  const int epoch = ++vertex_epoch_;
  for (const auto h : from_border) {
    const int v = mesh.from_vertex_handle(h).idx();
    if (vertex_stamp_[v] == epoch) continue;
    vertex_stamp_[v] = epoch;
    pd.vertices.push_back(v);
  }
  pd.removed_pinched = 0;
  for (const int v : pd.vertices) pd.removed_pinched += degree(v, into, face_patch) >= 2 ? 1 : 0;
}

int MergeProjection::check(const std::vector<int>& face_patch) {
  const TriMesh& mesh = *graph_.mesh;
  Pending& pd = pending_;
  const PatchState& state = states_[static_cast<std::size_t>(pd.into)];
  const int into = pd.into;
  // Only from's border vertices change how often the border passes them.
  int added_pinched = 0;
  for (const int v : pd.vertices) added_pinched += degree(v, into, face_patch) >= 2 ? 1 : 0;
  pd.pinched = state.pinched - pd.removed_pinched + added_pinched;
  if (!state.has_loops || state.axis != pd.axis || state.pinched != 0 || pd.pinched != 0 || state.n_unsure != 0)
    return -1;
  std::tie(e1_, e2_) = plane_frame(pd.axis);
  // into's border halfedges across from's border become inner; from's others stay border.
  pd.shared.clear();
  pd.added.clear();
  const int shared_epoch = ++halfedge_epoch_;
  for (const auto h : pd.from_border) {
    const auto o = mesh.opposite_halfedge_handle(h);
    const auto g = mesh.face_handle(o);
    if (g.is_valid() && face_patch[g.idx()] == into) {
      pd.shared.push_back(o.idx());
      halfedge_stamp_[o.idx()] = shared_epoch;
    } else {
      const int a = mesh.from_vertex_handle(h).idx(), b = mesh.to_vertex_handle(h).idx();
      pd.added.push_back({h.idx(), a, b, xy(a), xy(b)});
    }
  }
  if (pd.shared.empty()) return -1;
  auto registered = [&](int h) {
    const int slot = halfedge_slot_[h];
    return slot >= 0 && static_cast<std::size_t>(slot) < state.segments.size() &&
           state.segments[static_cast<std::size_t>(slot)].h == h;
  };
  const int joined = halfedge_loop_[pd.shared[0]];
  for (const int o : pd.shared)
    if (!registered(o) || halfedge_loop_[o] != joined) return -1;
  // The shared halfedges are one run of the joined loop (one end) or all of it (none).
  const int run_epoch = ++vertex_epoch_;
  for (const int o : pd.shared) vertex_stamp_[mesh.from_vertex_handle(OpenMesh::HalfedgeHandle(o)).idx()] = run_epoch;
  std::size_t ends = 0;
  for (const int o : pd.shared)
    ends += vertex_stamp_[mesh.to_vertex_handle(OpenMesh::HalfedgeHandle(o)).idx()] != run_epoch ? 1 : 0;
  const Loop& old_loop = state.loops[static_cast<std::size_t>(joined)];
  if (ends > 1 || (ends == 0) != (pd.shared.size() == old_loop.n) || pd.shared.size() > old_loop.n) return -1;
  // The added segments' successors in the merged border (one outgoing halfedge per vertex).
  const int added_epoch = ++halfedge_epoch_;
  const std::size_t n_added = pd.added.size();
  for (std::size_t i = 0; i < n_added; ++i) {
    halfedge_stamp_[pd.added[i].h] = added_epoch;
    halfedge_pos_[pd.added[i].h] = static_cast<int>(i);
  }
  auto in_merged = [&](OpenMesh::HalfedgeHandle h) {
    const auto f = mesh.face_handle(h);
    return f.is_valid() && face_patch[f.idx()] == into;
  };
  std::vector<int> next(n_added, -1);
  std::vector<std::uint8_t> has_previous(n_added, 0);
  std::size_t n_exits = 0, exit = 0;
  for (std::size_t i = 0; i < n_added; ++i) {
    auto h = mesh.next_halfedge_handle(OpenMesh::HalfedgeHandle(pd.added[i].h));
    while (in_merged(mesh.opposite_halfedge_handle(h))) h = mesh.next_halfedge_handle(mesh.opposite_halfedge_handle(h));
    if (halfedge_stamp_[h.idx()] == added_epoch) {
      next[i] = halfedge_pos_[h.idx()];
      has_previous[static_cast<std::size_t>(next[i])] = 1;
      continue;
    }
    // Leaves from's segments: into the joined loop where the run ends.
    if (halfedge_stamp_[h.idx()] == shared_epoch || !registered(h.idx()) || halfedge_loop_[h.idx()] != joined) return -1;
    ++n_exits;
    exit = i;
  }
  if (n_exits != ends) return -1;
  // The run's replacement (from the one added segment without a predecessor to the exit),
  // then closed loops of added segments only (from's holes).
  pd.added_loop.assign(n_added, -2);
  pd.new_loops.clear();
  pd.joined = joined;
  pd.closes = ends == 0;
  if (!pd.closes) {
    std::size_t start = n_added;
    for (std::size_t i = 0; i < n_added; ++i) {
      if (has_previous[i] != 0) continue;
      if (start != n_added) return -1;
      start = i;
    }
    if (start == n_added) return -1;
    Loop after = old_loop;
    for (const int o : pd.shared) {
      const Segment& s = state.segments[static_cast<std::size_t>(halfedge_slot_[o])];
      after.add(state.origin, s.xa, s.xb, -1.0);
    }
    after.n -= pd.shared.size();
    for (std::size_t i = start;; i = static_cast<std::size_t>(next[i])) {
      if (pd.added_loop[i] != -2) return -1;
      pd.added_loop[i] = -1;
      after.add(state.origin, pd.added[i].xa, pd.added[i].xb, 1.0);
      ++after.n;
      if (i == exit) break;
      if (next[i] < 0) return -1;
    }
    pd.joined_after = after;
  }
  for (std::size_t first = 0; first < n_added; ++first) {
    if (pd.added_loop[first] != -2) continue;
    Loop loop;
    const int id = static_cast<int>(pd.new_loops.size());
    std::size_t i = first;
    do {
      if (next[i] < 0 || pd.added_loop[i] != -2) return -1;
      pd.added_loop[i] = id;
      loop.add(state.origin, pd.added[i].xa, pd.added[i].xb, 1.0);
      ++loop.n;
      i = static_cast<std::size_t>(next[i]);
    } while (i != first);
    pd.new_loops.push_back(loop);
  }
  // Orientations: at most one counter-clockwise loop.
  const int old_sign = old_loop.sign();
  if (old_sign == 0) return -1;
  std::size_t n_outer = state.n_outer - (old_sign > 0 ? 1 : 0);
  std::size_t n_live = state.n_live - 1;
  if (!pd.closes) {
    const int sign = pd.joined_after.sign();
    if (sign == 0) return -1;
    n_outer += sign > 0 ? 1 : 0;
    ++n_live;
  }
  for (const Loop& loop : pd.new_loops) {
    const int sign = loop.sign();
    if (sign == 0) return -1;
    n_outer += sign > 0 ? 1 : 0;
    ++n_live;
  }
  pd.n_outer = n_outer;
  pd.n_live = n_live;
  pd.incremental = true;
  ++n_incremental_;
  // No border (a closed surface) or two counter-clockwise loops: not a height field. No
  // loop passes a vertex twice, so no counter-clockwise cycle can hide inside another.
  if (n_live == 0 || n_outer > 1) return 0;
  // Crossings: each added segment against the receiver's remaining ones near the added
  // segments' box, and against the other added ones (check_projection's pairs).
  if (n_added == 0) return 1;
  Eigen::Vector2d lo = pd.added[0].xa, hi = lo;
  for (const Segment& s : pd.added) {
    lo = lo.cwiseMin(s.xa).cwiseMin(s.xb);
    hi = hi.cwiseMax(s.xa).cwiseMax(s.xb);
  }
  auto meet = [](const Segment& s, const Segment& t) {
    if (s.a == t.a || s.a == t.b || s.b == t.a || s.b == t.b) return false;
    return segments_meet(s.xa, s.xb, t.xa, t.xb);
  };
  for (const Segment& s : state.segments) {
    if (std::max(s.xa.x(), s.xb.x()) < lo.x() || std::min(s.xa.x(), s.xb.x()) > hi.x() ||
        std::max(s.xa.y(), s.xb.y()) < lo.y() || std::min(s.xa.y(), s.xb.y()) > hi.y())
      continue;
    if (halfedge_stamp_[s.h] == shared_epoch) continue;
    for (const Segment& t : pd.added)
      if (meet(s, t)) return 0;
  }
  for (std::size_t j = 0; j < n_added; ++j)
    for (std::size_t k = 0; k < j; ++k)
      if (meet(pd.added[k], pd.added[j])) return 0;
  return 1;
}

void MergeProjection::keep() {
  Pending& pd = pending_;
  PatchState& state = states_[static_cast<std::size_t>(pd.into)];
  state.pinched = pd.pinched;
  if (pd.incremental) {
    for (const int o : pd.shared) {
      const auto slot = static_cast<std::size_t>(halfedge_slot_[o]);
      state.segments[slot] = state.segments.back();
      halfedge_slot_[state.segments[slot].h] = static_cast<int>(slot);
      state.segments.pop_back();
      halfedge_slot_[o] = -1;
    }
    const auto base = static_cast<int>(state.loops.size());
    for (std::size_t i = 0; i < pd.added.size(); ++i) {
      const int h = pd.added[i].h;
      halfedge_slot_[h] = static_cast<int>(state.segments.size());
      halfedge_loop_[h] = pd.added_loop[i] < 0 ? pd.joined : base + pd.added_loop[i];
      state.segments.push_back(pd.added[i]);
    }
    Loop& joined = state.loops[static_cast<std::size_t>(pd.joined)];
    if (pd.closes) {
      joined = Loop{};
    } else {
      joined = pd.joined_after;
    }
    state.loops.insert(state.loops.end(), pd.new_loops.begin(), pd.new_loops.end());
    state.n_live = pd.n_live;
    state.n_outer = pd.n_outer;
  } else {
    // Checked in full: the loops are traced again when next needed.
    state.has_loops = false;
    state.loops.clear();
    state.segments.clear();
  }
  states_[static_cast<std::size_t>(pd.from)] = PatchState{};
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
  segment_detail::split_loop(local, position, out);
  for (auto& cycle : out)
    for (int& v : cycle) v = sorted[static_cast<std::size_t>(v)];
  return out;
}

}  // namespace nurbsfront
