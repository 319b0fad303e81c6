// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/quality/aabb_tree.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <limits>

#include <Eigen/Geometry>

#include "nurbsfront/core/parallel.h"
#include "nurbsfront/quality/internal.h"

namespace nurbsfront::quality_detail {
namespace {

constexpr std::uint32_t kLeafSize = 4;
constexpr std::uint32_t kNoFace = std::numeric_limits<std::uint32_t>::max();
constexpr int kMaxDepth = 128;  // 63 Morton bits + log2 of a run of equal codes, with margin
// Faces per chunk of the constructor's per-face loops on several threads.
constexpr std::size_t kFaceChunk = 16384;
// Fewer faces than this: the root's two subtrees are built on one thread.
constexpr std::size_t kParallelBuildFaces = 4096;

// Spreads the low 21 bits of x so that two zero bits follow each bit (for Morton codes).
std::uint64_t spread_bits(std::uint64_t x) {
  x &= 0x1fffffu;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

constexpr double kMortonCells = 2097151.0;  // 2^21 - 1 cells per axis

// Morton code of p in the box [lo, lo + extent] (extent > 0 on every axis), 21 bits per axis.
std::uint64_t morton_code(const Eigen::Vector3d& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& extent) {
  const Eigen::Vector3d q = ((p - lo).cwiseQuotient(extent) * kMortonCells).cwiseMax(0.0).cwiseMin(kMortonCells);
  return spread_bits(static_cast<std::uint64_t>(q.x())) << 2 | spread_bits(static_cast<std::uint64_t>(q.y())) << 1 |
         spread_bits(static_cast<std::uint64_t>(q.z()));
}

// Largest float <= x and smallest float >= x (the largest finite float or infinity
// beyond the float range). One step of the bit pattern moves to the neighbouring float.
float float_below(double x) {
  const auto f = static_cast<float>(x);
  if (!(static_cast<double>(f) > x)) return f;
  if (f == 0.0f) return -std::numeric_limits<float>::denorm_min();
  const auto bits = std::bit_cast<std::uint32_t>(f);
  return std::bit_cast<float>(f > 0.0f ? bits - 1 : bits + 1);
}
float float_above(double x) { return -float_below(-x); }

// The outward-rounded float box of triangle t of the soup.
Box3f face_box_of(const TriangleSoup& soup, std::uint32_t face) {
  const auto& t = soup.triangles[face];
  const Eigen::Vector3d& a = soup.points[t[0]];
  const Eigen::Vector3d& b = soup.points[t[1]];
  const Eigen::Vector3d& c = soup.points[t[2]];
  const Eigen::Vector3d lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
  Box3f box;
  for (int k = 0; k < 3; ++k) {
    box.lo[k] = float_below(lo[k]);
    box.hi[k] = float_above(hi[k]);
  }
  return box;
}

Box3f merge(const Box3f& a, const Box3f& b) {
  Box3f r;
  for (int k = 0; k < 3; ++k) {
    r.lo[k] = std::min(a.lo[k], b.lo[k]);
    r.hi[k] = std::max(a.hi[k], b.hi[k]);
  }
  return r;
}

// Where build() splits faces [begin, end) (end - begin > kLeafSize): the middle when all
// codes are equal, else after the last position whose code shares more leading bits with
// the first code than the last code does.
std::uint32_t split_position(std::uint32_t begin, std::uint32_t end, const std::vector<std::uint64_t>& codes) {
  const std::uint64_t first = codes[begin], last = codes[end - 1];
  if (first == last) return begin + (end - begin) / 2;
  const int common = std::countl_zero(first ^ last);
  std::uint32_t lo = begin, hi = end - 1;  // codes[lo] shares more, codes[hi] does not
  while (hi - lo > 1) {
    const std::uint32_t m = lo + (hi - lo) / 2;
    if (std::countl_zero(first ^ codes[m]) > common) {
      lo = m;
    } else {
      hi = m;
    }
  }
  return hi;
}

}  // namespace

AabbTree::AabbTree(const TriangleSoup& soup, std::vector<std::uint32_t> faces, unsigned n_threads) : soup_(&soup) {
  if (faces.empty()) return;
  const std::size_t n = faces.size();
  n_threads = std::max(n_threads, 1U);
  // Per-face loops in chunks on n_threads threads (each index writes its own entries).
  auto for_faces = [n, n_threads](const auto& body) { parallel::for_each_index(n, n_threads, kFaceChunk, body); };
  // Faces sorted along a Morton (Z-order) curve of their centroids; each range is split
  // where the codes of its first and last face first differ (a linear BVH, Karras 2012),
  // so sibling boxes follow octree cells.
  std::vector<Eigen::Vector3d> centroids(n);
  const std::size_t n_chunks = (n + kFaceChunk - 1) / kFaceChunk;
  std::vector<BoundingBox> chunk_boxes(n_chunks);  // min and max: the same box in any order
  parallel::for_chunks(n, n_threads, kFaceChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) {
      const auto& t = soup.triangles[faces[i]];
      centroids[i] = (soup.points[t[0]] + soup.points[t[1]] + soup.points[t[2]]) / 3.0;
      // One call may cover several chunks (one thread: all of them).
      chunk_boxes[i / kFaceChunk].extend(centroids[i]);
    }
  });
  BoundingBox centroid_box;
  for (const auto& b : chunk_boxes) {
    centroid_box.min = centroid_box.min.cwiseMin(b.min);
    centroid_box.max = centroid_box.max.cwiseMax(b.max);
  }
  const Eigen::Vector3d extent = (centroid_box.max - centroid_box.min).cwiseMax(std::numeric_limits<double>::min());
  std::vector<std::uint64_t> codes(n);
  std::vector<std::uint32_t> order(n);
  for_faces([&](std::size_t i) {
    codes[i] = morton_code(centroids[i], centroid_box.min, extent);
    order[i] = static_cast<std::uint32_t>(i);
  });
  centroids = {};
  radix_sort(codes, order);
  faces_.resize(n);
  boxes_.resize(n);
  for_faces([&](std::size_t i) {
    faces_[i] = faces[order[i]];
    boxes_[i] = face_box_of(soup, faces_[i]);
  });
  if (n_threads >= 2 && n >= kParallelBuildFaces) {
    build_halves(codes);
  } else {
    nodes_.reserve(2 * n);  // a binary tree with at most n leaves
    parent_.reserve(2 * n);
    nodes_.emplace_back();
    parent_.push_back(0);
    build(nodes_, parent_, 0, 0, static_cast<std::uint32_t>(n), codes);
  }
  // Each face is in one leaf: the leaves' entries are written by one chunk each.
  leaf_of_.assign(soup.triangles.size(), kNoFace);
  parallel::for_chunks(nodes_.size(), n_threads, kFaceChunk, [this](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t k = begin; k < end; ++k) {
      const Node& node = nodes_[k];
      if (!node.is_leaf()) continue;
      for (std::uint32_t i = node.begin(); i < node.end(); ++i) leaf_of_[faces_[i]] = static_cast<std::uint32_t>(k);
    }
  });
}

void AabbTree::build(std::vector<Node>& nodes, std::vector<std::uint32_t>& parent, std::uint32_t node, std::uint32_t begin,
                     std::uint32_t end, const std::vector<std::uint64_t>& codes) const {
  if (end - begin <= kLeafSize) {
    Box3f box = boxes_[begin];
    for (std::uint32_t i = begin + 1; i < end; ++i) box = merge(box, boxes_[i]);
    nodes[node] = Node{box, begin, end - begin};
    return;
  }
  const std::uint32_t mid = split_position(begin, end, codes);
  const auto left = static_cast<std::uint32_t>(nodes.size());
  nodes[node].index = left;
  nodes.emplace_back();
  nodes.emplace_back();
  parent.push_back(node);
  parent.push_back(node);
  build(nodes, parent, left, begin, mid, codes);
  build(nodes, parent, left + 1, mid, end, codes);
  nodes[node].box = merge(nodes[left].box, nodes[left + 1].box);
}

void AabbTree::build_halves(const std::vector<std::uint64_t>& codes) {
  const auto n = static_cast<std::uint32_t>(faces_.size());
  const std::uint32_t mid = split_position(0, n, codes);
  const std::uint32_t range[2][2] = {{0, mid}, {mid, n}};
  // Each half's subtree with its root (a child of the tree's root) at local index 0.
  std::vector<Node> local[2];
  std::vector<std::uint32_t> local_parent[2];
  parallel::for_chunks(2, 2, 1, [&](std::size_t k, std::size_t, unsigned) {
    local[k].reserve(2 * static_cast<std::size_t>(range[k][1] - range[k][0]));
    local[k].emplace_back();
    local_parent[k].reserve(local[k].capacity());
    local_parent[k].push_back(0);
    build(local[k], local_parent[k], 0, range[k][0], range[k][1], codes);
  });
  // build() on one thread puts the root's children at 1 and 2, then the left child's
  // descendants from 3, then the right child's: local index i > 0 of half k goes to
  // i + shift[k], local index 0 to 1 + k.
  const std::size_t shift[2] = {2, local[0].size() + 1};
  nodes_.resize(1 + local[0].size() + local[1].size());
  parent_.assign(nodes_.size(), 0);
  nodes_[0].index = 1;
  parallel::for_chunks(2, 2, 1, [&](std::size_t k, std::size_t, unsigned) {
    auto global = [&](std::uint32_t i) { return static_cast<std::uint32_t>(i == 0 ? 1 + k : i + shift[k]); };
    for (std::size_t i = 0; i < local[k].size(); ++i) {
      Node node = local[k][i];
      if (!node.is_leaf()) node.index = global(node.index);
      const std::uint32_t g = global(static_cast<std::uint32_t>(i));
      nodes_[g] = node;
      parent_[g] = i == 0 ? 0 : global(local_parent[k][i]);
    }
  });
  nodes_[0].box = merge(nodes_[1].box, nodes_[2].box);
}

namespace {
std::vector<std::uint32_t> all_faces_of(const TriangleSoup& soup) {
  std::vector<std::uint32_t> faces(soup.triangles.size());
  for (std::size_t i = 0; i < faces.size(); ++i) faces[i] = static_cast<std::uint32_t>(i);
  return faces;
}
}  // namespace

IndexedSoup::IndexedSoup(TriangleSoup soup, unsigned n_threads)
    : soup_(std::move(soup)), tree_(soup_, all_faces_of(soup_), n_threads) {}

void AabbTree::refit(const TriangleSoup& soup, const std::vector<std::uint32_t>& changed_faces) {
  soup_ = &soup;
  // Leaves first (each changed face's entry), then every ancestor of a changed leaf once,
  // children before parents: nodes are numbered after their parents, so the marked nodes in
  // decreasing index order.
  std::vector<std::uint32_t> touched;
  for (const std::uint32_t f : changed_faces) {
    if (f >= leaf_of_.size() || leaf_of_[f] == kNoFace) continue;
    const std::uint32_t leaf = leaf_of_[f];
    const Node& node = nodes_[leaf];
    for (std::uint32_t i = node.begin(); i < node.end(); ++i) {
      if (faces_[i] == f) boxes_[i] = face_box_of(soup, f);
    }
    touched.push_back(leaf);
  }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  std::vector<std::uint8_t> marked(nodes_.size(), 0);
  std::vector<std::uint32_t> stale;
  for (std::uint32_t node : touched) {
    for (;;) {
      if (marked[node] != 0) break;
      marked[node] = 1;
      stale.push_back(node);
      if (node == 0) break;
      node = parent_[node];
    }
  }
  std::sort(stale.begin(), stale.end(), std::greater<>());
  for (const std::uint32_t k : stale) {
    Node& node = nodes_[k];
    if (node.is_leaf()) {
      Box3f box = boxes_[node.begin()];
      for (std::uint32_t i = node.begin() + 1; i < node.end(); ++i) box = merge(box, boxes_[i]);
      node.box = box;
    } else {
      node.box = merge(nodes_[node.left()].box, nodes_[node.right()].box);
    }
  }
}

std::vector<std::uint32_t> morton_order(const std::vector<Eigen::Vector3d>& points) {
  BoundingBox box;
  for (const auto& p : points) box.extend(p);
  const Eigen::Vector3d extent = (box.max - box.min).cwiseMax(std::numeric_limits<double>::min());
  std::vector<std::uint64_t> codes(points.size());
  std::vector<std::uint32_t> order(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    codes[i] = morton_code(points[i], box.min, extent);
    order[i] = static_cast<std::uint32_t>(i);
  }
  radix_sort(codes, order);
  return order;
}

Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + (d1 / (d1 - d3)) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0.0)) {  // degenerate triangle: fall back to the closest of its edges' ends
    const double da = (p - a).squaredNorm(), db = (p - b).squaredNorm(), dc = (p - c).squaredNorm();
    return da <= db && da <= dc ? a : (db <= dc ? b : c);
  }
  const double denom = 1.0 / sum;
  return a + ab * (vb * denom) + ac * (vc * denom);
}

void AabbTree::search(const Eigen::Vector3d& p, std::uint32_t start, Closest& best) const {
  auto test_face = [&](std::uint32_t face) {
    const auto& t = soup_->triangles[face];
    const Eigen::Vector3d q =
        closest_point_on_triangle(p, soup_->points[t[0]], soup_->points[t[1]], soup_->points[t[2]]);
    const double d = (q - p).squaredNorm();
    if (d < best.squared_distance || (d == best.squared_distance && face < best.face)) best = {d, face};
  };
  // Stack of (node, squared distance to its box), nearer child popped first. Subtrees
  // whose box is farther than the best face so far are skipped: every face at the best
  // distance is still tested, so ties go to the lowest face index whatever the order.
  struct Entry {
    std::uint32_t node;
    double box_distance;
  };
  Entry stack[kMaxDepth + 1];
  int top = 0;
  stack[top++] = {start, nodes_[start].box.squared_distance(p)};
  while (top > 0) {
    const Entry entry = stack[--top];
    if (entry.box_distance > best.squared_distance) continue;
    const Node& node = nodes_[entry.node];
    if (node.is_leaf()) {
      for (std::uint32_t i = node.begin(); i < node.end(); ++i) {
        if (boxes_[i].squared_distance(p) <= best.squared_distance) test_face(faces_[i]);
      }
      continue;
    }
    const double dl = nodes_[node.left()].box.squared_distance(p);
    const double dr = nodes_[node.right()].box.squared_distance(p);
    if (dl <= dr) {
      if (dr <= best.squared_distance) stack[top++] = {node.right(), dr};
      if (dl <= best.squared_distance) stack[top++] = {node.left(), dl};
    } else {
      if (dl <= best.squared_distance) stack[top++] = {node.left(), dl};
      if (dr <= best.squared_distance) stack[top++] = {node.right(), dr};
    }
  }
}

AabbTree::Closest AabbTree::closest(const Eigen::Vector3d& p, std::uint32_t hint) const {
  Closest best{std::numeric_limits<double>::infinity(), kNoFace};
  if (nodes_.empty()) return best;
  if (hint < leaf_of_.size() && leaf_of_[hint] != kNoFace) {
    // Bottom-up from the hint's leaf: its faces give a tight bound at once, then the
    // sibling of every ancestor is searched (usually pruned by its box alone).
    std::uint32_t node = leaf_of_[hint];
    search(p, node, best);
    for (; node != 0; node = parent_[node]) {
      // The sibling's box is tested here: search() would only pop it and skip it.
      const std::uint32_t sibling = node % 2 == 1 ? node + 1 : node - 1;
      if (nodes_[sibling].box.squared_distance(p) <= best.squared_distance) search(p, sibling, best);
    }
    return best;
  }
  search(p, 0, best);
  return best;
}

}  // namespace nurbsfront::quality_detail
