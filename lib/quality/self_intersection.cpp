// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/quality/self_intersection.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <numeric>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/quality/internal.h"
#include "nurbsfront/quality/predicates.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront::quality_detail {
namespace {

using quality_detail::orient2d;
using quality_detail::orient3d;

// The coordinate axis to drop when projecting the plane of (p, q, r) to 2D: the one of
// the largest normal component, so the projected triangle keeps a non-zero area.
// Projection just drops a coordinate, so exact inputs stay exact.
int drop_axis(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
  const Eigen::Vector3d n = (q - p).cross(r - p).cwiseAbs();
  int axis = 0;
  n.maxCoeff(&axis);
  return axis;
}

Eigen::Vector2d project(const Eigen::Vector3d& x, int axis) {
  switch (axis) {
    case 0: return {x.y(), x.z()};
    case 1: return {x.z(), x.x()};
    default: return {x.x(), x.y()};
  }
}

bool mixed(int s1, int s2, int s3) {
  return (s1 > 0 || s2 > 0 || s3 > 0) && (s1 < 0 || s2 < 0 || s3 < 0);
}

// Closed 2D point-in-triangle for a non-degenerate triangle.
bool point_in_triangle_2d(const Eigen::Vector2d& x, const Eigen::Vector2d& p, const Eigen::Vector2d& q,
                          const Eigen::Vector2d& r) {
  return !mixed(orient2d(p, q, x), orient2d(q, r, x), orient2d(r, p, x));
}

bool on_collinear_segment(const Eigen::Vector2d& x, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::min(a.x(), b.x()) <= x.x() && x.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= x.y() && x.y() <= std::max(a.y(), b.y());
}

// Closed 2D segment-segment intersection.
bool segments_meet_2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                      const Eigen::Vector2d& d) {
  const int o1 = orient2d(a, b, c), o2 = orient2d(a, b, d);
  const int o3 = orient2d(c, d, a), o4 = orient2d(c, d, b);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  if (o1 == 0 && on_collinear_segment(c, a, b)) return true;
  if (o2 == 0 && on_collinear_segment(d, a, b)) return true;
  if (o3 == 0 && on_collinear_segment(a, c, d)) return true;
  if (o4 == 0 && on_collinear_segment(b, c, d)) return true;
  return false;
}

}  // namespace

namespace {

// segment_meets_triangle with the sides sa = orient3d(p, q, r, a), sb = orient3d(p, q, r, b)
// already known.
bool segment_meets_triangle_sides(const Eigen::Vector3d& a, const Eigen::Vector3d& b, int sa, int sb,
                                  const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
  if (sa * sb > 0) return false;
  if (sa == 0 && sb == 0) {
    const int axis = drop_axis(p, q, r);
    const Eigen::Vector2d a2 = project(a, axis), b2 = project(b, axis);
    const Eigen::Vector2d p2 = project(p, axis), q2 = project(q, axis), r2 = project(r, axis);
    return point_in_triangle_2d(a2, p2, q2, r2) || point_in_triangle_2d(b2, p2, q2, r2) ||
           segments_meet_2d(a2, b2, p2, q2) || segments_meet_2d(a2, b2, q2, r2) ||
           segments_meet_2d(a2, b2, r2, p2);
  }
  // The segment meets the plane in exactly one point: it lies in the closed triangle iff
  // the line (a, b) passes on the same side of all three edges (or on them).
  return !mixed(orient3d(a, b, p, q), orient3d(a, b, q, r), orient3d(a, b, r, p));
}

// True when (p, q, r) is certainly not collinear: the rounded cross product is far above its
// rounding error (a few ulps of the product of the edge lengths).
bool surely_not_collinear(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
  const Eigen::Vector3d u = q - p, v = r - p;
  return u.cross(v).cwiseAbs().maxCoeff() > 1e-12 * u.cwiseAbs().maxCoeff() * v.cwiseAbs().maxCoeff();
}

}  // namespace

bool segment_meets_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& p,
                            const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
  return segment_meets_triangle_sides(a, b, orient3d(p, q, r, a), orient3d(p, q, r, b), p, q, r);
}

bool triangles_intersect(const std::array<std::uint32_t, 3>& ids1, const std::array<Eigen::Vector3d, 3>& t1,
                         const std::array<std::uint32_t, 3>& ids2, const std::array<Eigen::Vector3d, 3>& t2) {
  // Which corners are shared (by id)?
  int n_shared = 0;
  int shared1[3] = {-1, -1, -1};  // shared1[i] = corner of t2 equal to corner i of t1
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (ids1[i] == ids2[j]) {
        shared1[i] = j;
        ++n_shared;
      }
    }
  }
  if (n_shared >= 3) return false;
  if (n_shared == 0) {
    // The side of each corner of one triangle of the other's plane, each predicate once.
    // All corners of one strictly on one side: apart (the usual case for neighbours on a
    // smooth surface).
    int side1[3], side2[3];  // corners of t1 against t2's plane, of t2 against t1's
    for (int i = 0; i < 3; ++i) side1[i] = orient3d(t2[0], t2[1], t2[2], t1[i]);
    if (side1[0] != 0 && side1[0] == side1[1] && side1[0] == side1[2]) return false;
    for (int i = 0; i < 3; ++i) side2[i] = orient3d(t1[0], t1[1], t1[2], t2[i]);
    if (side2[0] != 0 && side2[0] == side2[1] && side2[0] == side2[2]) return false;
    // Two closed triangles meet iff an edge of one meets the other: the intersection is
    // convex and its extreme points lie on edges of one of them.
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      if (segment_meets_triangle_sides(t1[i], t1[j], side1[i], side1[j], t2[0], t2[1], t2[2])) return true;
      if (segment_meets_triangle_sides(t2[i], t2[j], side2[i], side2[j], t1[0], t1[1], t1[2])) return true;
    }
    return false;
  }
  if (n_shared == 1) {
    // Shared corner v: more than v in common iff the edge opposite v in one triangle meets
    // the other (a ray from v inside both leaves one of them through its opposite edge).
    int i1 = 0;
    while (shared1[i1] < 0) ++i1;
    const int i2 = shared1[i1];
    const Eigen::Vector3d& a = t1[(i1 + 1) % 3];
    const Eigen::Vector3d& b = t1[(i1 + 2) % 3];
    const int sa = orient3d(t2[0], t2[1], t2[2], a), sb = orient3d(t2[0], t2[1], t2[2], b);
    // a and b strictly on one side of t2's plane: t1 meets that plane only at v (the usual
    // case for neighbours on a smooth surface), so the test below from t2's side would
    // answer no as well.
    if (sa * sb > 0) return false;
    if (segment_meets_triangle_sides(a, b, sa, sb, t2[0], t2[1], t2[2])) return true;
    const Eigen::Vector3d& c = t2[(i2 + 1) % 3];
    const Eigen::Vector3d& d = t2[(i2 + 2) % 3];
    // t1 in the plane of a proper triangle t2 (marching cubes' flat regions): the planes
    // are one, and c and d lie in t1's (the exact predicates are not asked again).
    if (sa == 0 && sb == 0 && surely_not_collinear(t2[0], t2[1], t2[2]))
      return segment_meets_triangle_sides(c, d, 0, 0, t1[0], t1[1], t1[2]);
    return segment_meets_triangle(c, d, t1[0], t1[1], t1[2]);
  }
  // Shared edge (u, w): non-coplanar triangles meet only on it; coplanar ones overlap iff
  // their third corners lie on the same side of it (a fold-over).
  int free1 = 0;
  while (shared1[free1] >= 0) ++free1;
  int free2 = 0;
  while (free2 == shared1[0] || free2 == shared1[1] || free2 == shared1[2]) ++free2;
  const Eigen::Vector3d& u = t1[(free1 + 1) % 3];
  const Eigen::Vector3d& w = t1[(free1 + 2) % 3];
  if (orient3d(u, w, t1[free1], t2[free2]) != 0) return false;
  const int axis = drop_axis(u, w, t1[free1]);
  const Eigen::Vector2d u2 = project(u, axis), w2 = project(w, axis);
  return orient2d(u2, w2, project(t1[free1], axis)) * orient2d(u2, w2, project(t2[free2], axis)) > 0;
}

}  // namespace nurbsfront::quality_detail

// ---------------------------------------------------------------------------------------
// Whole-mesh self-intersection count.

namespace nurbsfront {
namespace {

// Maps every point to the lowest index of a point at exactly the same position, so that
// unwelded copies of a vertex count as shared corners and not as a touching contact.
// Points are grouped by a hash of their coordinates (radix-sorted, stable, so each group
// lists its points in index order); inside a group, exact comparisons decide. With `within`,
// only the points in that closed box are grouped, each other point keeps its own index: the
// same ids for the points in the box (a point at the same position as one in the box is in
// it), and ids equal only at equal positions for all points. With `in_region` (a grid's
// occupied cells, with the box around them) alike: only the points in it are grouped, and
// a point at the same position as one in it is in it.
std::vector<std::uint32_t> canonical_ids(const TriangleSoup& soup, const BoundingBox* within = nullptr,
                                         const quality_detail::BoxGrid* in_region = nullptr) {
  const std::size_t n = soup.points.size();
  std::vector<std::uint32_t> id(n);
  std::vector<std::uint32_t> order;
  if (within == nullptr) {
    order.resize(n);
    std::iota(order.begin(), order.end(), 0u);
  } else {
    std::iota(id.begin(), id.end(), 0u);
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d& p = soup.points[i];
      if ((within->min.array() <= p.array()).all() && (p.array() <= within->max.array()).all() &&
          (in_region == nullptr || in_region->is_occupied(p))) {
        order.push_back(static_cast<std::uint32_t>(i));
      }
    }
  }
  const std::size_t m = order.size();
  std::vector<std::uint64_t> hashes(m);
  for (std::size_t i = 0; i < m; ++i) {
    std::uint64_t h = 0x9e3779b97f4a7c15ULL;
    for (int k = 0; k < 3; ++k) {
      // + 0.0 turns -0.0 into 0.0: equal coordinates hash equally.
      h = (h ^ std::bit_cast<std::uint64_t>(soup.points[order[i]][k] + 0.0)) * 0xff51afd7ed558ccdULL;
      h ^= h >> 33;
    }
    hashes[i] = h;
  }
  quality_detail::radix_sort(hashes, order);
  std::vector<std::uint32_t> distinct;  // first point of each distinct position in the group
  for (std::size_t i = 0; i < m;) {
    std::size_t j = i;
    while (j < m && hashes[j] == hashes[i]) ++j;
    distinct.clear();
    for (std::size_t k = i; k < j; ++k) {
      const std::uint32_t v = order[k];
      auto same = std::find_if(distinct.begin(), distinct.end(),
                               [&](std::uint32_t u) { return soup.points[u] == soup.points[v]; });
      if (same == distinct.end()) {
        distinct.push_back(v);
        id[v] = v;
      } else {
        id[v] = *same;
      }
    }
    i = j;
  }
  return id;
}

using FacePair = std::array<std::uint32_t, 2>;

// Intersecting pairs found by one traversal: counted, and listed when `pairs` is set.
struct Hits {
  std::size_t count = 0;
  std::vector<FacePair>* pairs = nullptr;
  void add(std::uint32_t f, std::uint32_t g) {
    ++count;
    if (pairs != nullptr) pairs->push_back({std::min(f, g), std::max(f, g)});
  }
};

struct NodePair {
  std::uint32_t a;
  std::uint32_t b;  // a == b: pairs inside one subtree
};

class SelfIntersectionCounter {
 public:
  SelfIntersectionCounter(const TriangleSoup& soup, const quality_detail::AabbTree& tree, const std::vector<std::uint32_t>& ids,
                          const std::vector<char>& usable)
      : soup_(soup), tree_(tree), ids_(ids), usable_(usable) {}

  std::size_t run(NodePair task, std::vector<FacePair>* pairs = nullptr) const {
    Hits count;
    count.pairs = pairs;
    if (task.a == task.b) {
      self(task.a, count);
    } else {
      pair(task.a, task.b, count);
    }
    return count.count;
  }

  // Splits the top of the traversal into independent tasks.
  std::vector<NodePair> split(std::size_t target) const {
    std::vector<NodePair> tasks{{0, 0}};
    const auto& nodes = tree_.nodes();
    for (int round = 0; round < 32 && tasks.size() < target; ++round) {
      std::vector<NodePair> next;
      bool changed = false;
      for (const auto& t : tasks) {
        const auto& a = nodes[t.a];
        const auto& b = nodes[t.b];
        if (t.a == t.b) {
          if (a.is_leaf()) {
            next.push_back(t);
            continue;
          }
          next.push_back({a.left(), a.left()});
          next.push_back({a.right(), a.right()});
          next.push_back({a.left(), a.right()});
          changed = true;
          continue;
        }
        if (!a.box.overlaps(b.box)) {
          changed = true;
          continue;
        }
        if (a.is_leaf() && b.is_leaf()) {
          next.push_back(t);
        } else if (b.is_leaf() || (!a.is_leaf() && a.box.squared_extent() >=
                                                        b.box.squared_extent())) {
          next.push_back({a.left(), t.b});
          next.push_back({a.right(), t.b});
          changed = true;
        } else {
          next.push_back({t.a, b.left()});
          next.push_back({t.a, b.right()});
          changed = true;
        }
      }
      tasks = std::move(next);
      if (!changed) break;
    }
    return tasks;
  }

 private:
  void self(std::uint32_t n, Hits& count) const {
    const auto& node = tree_.nodes()[n];
    if (node.is_leaf()) {
      for (std::uint32_t i = node.begin(); i < node.end(); ++i) {
        for (std::uint32_t j = i + 1; j < node.end(); ++j) test(i, j, count);
      }
      return;
    }
    self(node.left(), count);
    self(node.right(), count);
    pair(node.left(), node.right(), count);
  }

  void pair(std::uint32_t na, std::uint32_t nb, Hits& count) const {
    const auto& a = tree_.nodes()[na];
    const auto& b = tree_.nodes()[nb];
    if (!a.box.overlaps(b.box)) return;
    if (a.is_leaf() && b.is_leaf()) {
      for (std::uint32_t i = a.begin(); i < a.end(); ++i) {
        for (std::uint32_t j = b.begin(); j < b.end(); ++j) test(i, j, count);
      }
      return;
    }
    // Descend the inner node with the larger box (the non-leaf if one is a leaf).
    const bool split_a = b.is_leaf() || (!a.is_leaf() && a.box.squared_extent() >=
                                                             b.box.squared_extent());
    if (split_a) {
      pair(a.left(), nb, count);
      pair(a.right(), nb, count);
    } else {
      pair(na, b.left(), count);
      pair(na, b.right(), count);
    }
  }

  void test(std::uint32_t i, std::uint32_t j, Hits& count) const {
    if (!usable_[i] || !usable_[j] || !tree_.face_box(i).overlaps(tree_.face_box(j))) return;
    const auto& fi = soup_.triangles[tree_.faces()[i]];
    const auto& fj = soup_.triangles[tree_.faces()[j]];
    const std::array<std::uint32_t, 3> ids_i{ids_[fi[0]], ids_[fi[1]], ids_[fi[2]]};
    const std::array<std::uint32_t, 3> ids_j{ids_[fj[0]], ids_[fj[1]], ids_[fj[2]]};
    const std::array<Eigen::Vector3d, 3> ti{soup_.points[fi[0]], soup_.points[fi[1]], soup_.points[fi[2]]};
    const std::array<Eigen::Vector3d, 3> tj{soup_.points[fj[0]], soup_.points[fj[1]], soup_.points[fj[2]]};
    if (quality_detail::triangles_intersect(ids_i, ti, ids_j, tj)) count.add(tree_.faces()[i], tree_.faces()[j]);
  }

  const TriangleSoup& soup_;
  const quality_detail::AabbTree& tree_;
  const std::vector<std::uint32_t>& ids_;
  const std::vector<char>& usable_;  //!< by tree position: not degenerate
};

}  // namespace

namespace quality_detail {

// Cells per item at most (at least kMinCells, at most kMaxCells in all): the grid's memory
// stays linear and bounded. With 16 per item the liver's collapse check (5 k faces spread
// over the mesh) had cells of 4 mean edges, and most faces of the soup went through them.
constexpr std::size_t kCellsPerItem = 64;
constexpr std::size_t kMinCells = 4096;
constexpr std::size_t kMaxCells = std::size_t{1} << 21;

BoxGrid::BoxGrid(std::vector<Eigen::Vector3d> lo, std::vector<Eigen::Vector3d> hi) : lo_(std::move(lo)), hi_(std::move(hi)) {
  if (lo_.size() != hi_.size()) throw InternalError("nurbsfront: BoxGrid: " + std::to_string(lo_.size()) + " lows, " +
                                                    std::to_string(hi_.size()) + " highs");
  if (lo_.empty()) return;
  Eigen::Vector3d min = lo_[0], max = hi_[0];
  double side_sum = 0.0;
  for (std::size_t i = 0; i < lo_.size(); ++i) {
    min = min.cwiseMin(lo_[i]);
    max = max.cwiseMax(hi_[i]);
    side_sum += (hi_[i] - lo_[i]).maxCoeff();
  }
  const Eigen::Vector3d extent = max - min;
  const std::size_t max_cells = std::clamp(kCellsPerItem * lo_.size(), kMinCells, kMaxCells);
  // About the items' mean largest side, larger while the grid would have too many cells.
  double cell = side_sum / static_cast<double>(lo_.size());
  if (!(cell > 0.0)) cell = extent.maxCoeff() > 0.0 ? extent.maxCoeff() / 16.0 : 1.0;
  auto cells_along = [&](int k) {
    return static_cast<int>(std::min(std::ceil(extent[k] / cell), static_cast<double>(max_cells)));
  };
  for (;;) {
    double total = 1.0;
    for (int k = 0; k < 3; ++k) {
      n_[static_cast<std::size_t>(k)] = std::max(1, cells_along(k));
      total *= n_[static_cast<std::size_t>(k)];
    }
    if (total <= static_cast<double>(max_cells)) break;
    cell *= 1.26;  // about a cube root of 2: half the cells
  }
  origin_ = min;
  for (int k = 0; k < 3; ++k) {
    inverse_[k] = extent[k] > 0.0 ? n_[static_cast<std::size_t>(k)] / extent[k] : 0.0;
    last_[k] = n_[static_cast<std::size_t>(k)] - 1;
  }
  const std::size_t n_cells = static_cast<std::size_t>(n_[0]) * static_cast<std::size_t>(n_[1]) * static_cast<std::size_t>(n_[2]);
  // Counting sort of (cell, item) by cell.
  start_.assign(n_cells + 1, 0);
  auto for_cells = [&](std::size_t i, const auto& f) {
    const Eigen::Vector3d& a = lo_[i];
    const Eigen::Vector3d& b = hi_[i];
    for (int z = cell_along(2, a.z()); z <= cell_along(2, b.z()); ++z) {
      for (int y = cell_along(1, a.y()); y <= cell_along(1, b.y()); ++y) {
        for (int x = cell_along(0, a.x()); x <= cell_along(0, b.x()); ++x) f(index(x, y, z));
      }
    }
  };
  for (std::size_t i = 0; i < lo_.size(); ++i) for_cells(i, [&](std::size_t c) { ++start_[c + 1]; });
  std::partial_sum(start_.begin(), start_.end(), start_.begin());
  items_.resize(start_.back());
  std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
  for (std::size_t i = 0; i < lo_.size(); ++i) {
    for_cells(i, [&](std::size_t c) { items_[fill[c]++] = static_cast<std::uint32_t>(i); });
  }
}

// Faces per task of the usable-face flags on several threads.
constexpr std::size_t kUsableChunk = 16384;

AabbTree all_faces_tree(const TriangleSoup& soup, unsigned n_threads) {
  std::vector<std::uint32_t> faces(soup.triangles.size());
  std::iota(faces.begin(), faces.end(), 0u);
  return AabbTree(soup, std::move(faces), n_threads);
}

std::size_t count_self_intersections_with(const TriangleSoup& soup, const AabbTree& tree, unsigned n_threads,
                                          std::vector<std::array<std::uint32_t, 2>>* pairs) {
  if (tree.empty()) return 0;
  const std::vector<std::uint32_t> ids = canonical_ids(soup);
  // Degenerate faces (repeated corner, or area at the degenerate tolerance) are counted
  // elsewhere and skipped here: the predicates need a proper plane per triangle.
  const double diagonal = bounding_box(soup).diagonal();
  const double area_floor = tolerance::kDegenerateAreaRelative * diagonal * diagonal;
  std::vector<char> usable(tree.faces().size());  // by position in the tree; on n_threads threads
  parallel::for_chunks(usable.size(), n_threads, kUsableChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) {
      const auto& t = soup.triangles[tree.faces()[i]];
      if (ids[t[0]] == ids[t[1]] || ids[t[1]] == ids[t[2]] || ids[t[2]] == ids[t[0]]) continue;
      const double area =
          0.5 * (soup.points[t[1]] - soup.points[t[0]]).cross(soup.points[t[2]] - soup.points[t[0]]).norm();
      usable[i] = area > area_floor;
    }
  });
  const SelfIntersectionCounter counter(soup, tree, ids, usable);
  if (n_threads == 1) return counter.run({0, 0}, pairs);
  // Independent subtree pairs, handed out dynamically; the total does not depend on
  // which thread counted which pair (listed pairs are sorted by the caller).
  const std::vector<NodePair> tasks = counter.split(256 * static_cast<std::size_t>(n_threads));
  std::vector<std::size_t> counts(n_threads, 0);
  std::vector<std::vector<FacePair>> found(n_threads);
  parallel::for_chunks(tasks.size(), n_threads, 1, [&](std::size_t begin, std::size_t end, unsigned worker) {
    for (std::size_t k = begin; k < end; ++k)
      counts[worker] += counter.run(tasks[k], pairs != nullptr ? &found[worker] : nullptr);
  });
  if (pairs != nullptr) {
    for (const auto& f : found) pairs->insert(pairs->end(), f.begin(), f.end());
  }
  return std::accumulate(counts.begin(), counts.end(), std::size_t{0});
}

}  // namespace quality_detail

std::size_t count_self_intersections(const TriangleSoup& soup, unsigned n_threads) {
  quality_detail::validate_soup(soup, "count_self_intersections");
  if (n_threads == 0) throw InvalidInput("nurbsfront: count_self_intersections needs at least one thread");
  return quality_detail::count_self_intersections_with(soup, quality_detail::all_faces_tree(soup, n_threads), n_threads);
}

std::vector<std::array<std::uint32_t, 2>> self_intersecting_pairs(const TriangleSoup& soup, unsigned n_threads) {
  quality_detail::validate_soup(soup, "self_intersecting_pairs");
  if (n_threads == 0) throw InvalidInput("nurbsfront: self_intersecting_pairs needs at least one thread");
  std::vector<FacePair> pairs;
  quality_detail::count_self_intersections_with(soup, quality_detail::all_faces_tree(soup, n_threads), n_threads, &pairs);
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// Soup faces per chunk of intersecting_pairs_of's parallel loop.
constexpr std::size_t kPairsOfChunk = 4096;

std::vector<std::array<std::uint32_t, 2>> intersecting_pairs_of(const TriangleSoup& soup,
                                                                 const std::vector<std::uint32_t>& faces, unsigned n_threads) {
  quality_detail::validate_soup(soup, "intersecting_pairs_of");
  if (n_threads == 0) throw InvalidInput("nurbsfront: intersecting_pairs_of needs at least one thread");
  const std::size_t n = soup.triangles.size();
  std::vector<std::uint32_t> subset = faces;
  std::sort(subset.begin(), subset.end());
  subset.erase(std::unique(subset.begin(), subset.end()), subset.end());
  if (!subset.empty() && subset.back() >= n) {
    throw InvalidInput("nurbsfront: intersecting_pairs_of: face " + std::to_string(subset.back()) + " of " +
                       std::to_string(n));
  }
  std::vector<FacePair> pairs;
  if (subset.empty()) return pairs;
  // The subset's faces in a uniform grid of their boxes (quality_detail::BoxGrid): each
  // face of the soup meets the few subset faces in its cells, and the faces away from the
  // subset cost a box and a cell look-up (a tree over the subset, searched from its root
  // for every face of the soup, cost the liver's stitch 0.4 G instructions when the
  // subset was spread over the whole mesh). Only the points in the grid's occupied cells
  // are grouped by position (canonical ids): the corners shared with a subset face are
  // there.
  BoundingBox subset_box;
  std::vector<Eigen::Vector3d> lo(subset.size()), hi(subset.size());
  for (std::size_t i = 0; i < subset.size(); ++i) {
    const auto& t = soup.triangles[subset[i]];
    lo[i] = soup.points[t[0]].cwiseMin(soup.points[t[1]]).cwiseMin(soup.points[t[2]]);
    hi[i] = soup.points[t[0]].cwiseMax(soup.points[t[1]]).cwiseMax(soup.points[t[2]]);
    subset_box.extend(lo[i]);
    subset_box.extend(hi[i]);
  }
  const quality_detail::BoxGrid grid(std::move(lo), std::move(hi));
  const std::vector<std::uint32_t> ids = canonical_ids(soup, &subset_box, &grid);
  const double diagonal = bounding_box(soup).diagonal();
  const double area_floor = tolerance::kDegenerateAreaRelative * diagonal * diagonal;
  // The same faces as count_self_intersections_with() skips (repeated corner, degenerate area).
  auto usable = [&](std::uint32_t f) {
    const auto& t = soup.triangles[f];
    if (ids[t[0]] == ids[t[1]] || ids[t[1]] == ids[t[2]] || ids[t[2]] == ids[t[0]]) return false;
    return 0.5 * (soup.points[t[1]] - soup.points[t[0]]).cross(soup.points[t[2]] - soup.points[t[0]]).norm() > area_floor;
  };
  std::vector<char> in_subset(n, 0);
  bool any_usable = false;
  for (std::uint32_t f : subset) {
    in_subset[f] = usable(f) ? 1 : 0;
    any_usable = any_usable || in_subset[f] != 0;
  }
  if (!any_usable) return pairs;
  // The soup's faces in chunks on n_threads workers, each listing its pairs; the union is
  // sorted below, so the result does not depend on the thread count. The exact boxes of
  // two intersecting triangles meet, so the grid finds every pair (the test is exact).
  std::vector<std::vector<FacePair>> found(n_threads);
  parallel::for_chunks(n, n_threads, kPairsOfChunk, [&](std::size_t begin, std::size_t end, unsigned worker) {
    std::vector<FacePair>& out = found[worker];
    for (auto g = static_cast<std::uint32_t>(begin); g < end; ++g) {
      const auto& tg = soup.triangles[g];
      const Eigen::Vector3d& a = soup.points[tg[0]];
      const Eigen::Vector3d& b = soup.points[tg[1]];
      const Eigen::Vector3d& c = soup.points[tg[2]];
      const Eigen::Vector3d lo_g = a.cwiseMin(b).cwiseMin(c), hi_g = a.cwiseMax(b).cwiseMax(c);
      if ((hi_g.array() < subset_box.min.array()).any() || (subset_box.max.array() < lo_g.array()).any() ||
          !grid.may_overlap(lo_g, hi_g)) {
        continue;
      }
      bool g_usable = true, g_checked = false;
      const std::array<std::uint32_t, 3> ids_g{ids[tg[0]], ids[tg[1]], ids[tg[2]]};
      const std::array<Eigen::Vector3d, 3> points_g{a, b, c};
      grid.for_each_overlapping(lo_g, hi_g, [&](std::uint32_t i) {
        const std::uint32_t f = subset[i];
        // A pair of two subset faces is tested once, from its larger face.
        if (!g_usable || f == g || in_subset[f] == 0 || (in_subset[g] != 0 && f > g)) return;
        if (!g_checked) {
          g_usable = usable(g);
          g_checked = true;
          if (!g_usable) return;
        }
        const auto& tf = soup.triangles[f];
        const std::array<std::uint32_t, 3> ids_f{ids[tf[0]], ids[tf[1]], ids[tf[2]]};
        const std::array<Eigen::Vector3d, 3> points_f{soup.points[tf[0]], soup.points[tf[1]], soup.points[tf[2]]};
        if (quality_detail::triangles_intersect(ids_f, points_f, ids_g, points_g)) {
          out.push_back({std::min(f, g), std::max(f, g)});
        }
      });
    }
  });
  for (const auto& f : found) pairs.insert(pairs.end(), f.begin(), f.end());
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

}  // namespace nurbsfront
