// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/quality/aabb_tree.h"

#include <algorithm>
#include <limits>

#include <Eigen/Geometry>

namespace nurbsfront::quality_detail {
namespace {
constexpr std::uint32_t kLeafSize = 4;
constexpr std::uint32_t kNoFace = std::numeric_limits<std::uint32_t>::max();
}  // namespace

namespace {

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

}  // namespace

AabbTree::AabbTree(const TriangleSoup& soup, std::vector<std::uint32_t> faces) : soup_(&soup) {
  if (faces.empty()) return;
  const std::size_t n = faces.size();
  // Faces sorted along a Morton (Z-order) curve of their centroids, then split at the
  // middle of the range: a balanced tree built with one sort and sequential passes
  // (as in Karras's linear BVH, with midpoint instead of bit splits).
  std::vector<Box3> boxes(n);
  BoundingBox centroid_box;
  std::vector<Eigen::Vector3d> centroids(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& t = soup.triangles[faces[i]];
    const Eigen::Vector3d& a = soup.points[t[0]];
    const Eigen::Vector3d& b = soup.points[t[1]];
    const Eigen::Vector3d& c = soup.points[t[2]];
    boxes[i] = Box3{a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c)};
    centroids[i] = (a + b + c) / 3.0;
    centroid_box.extend(centroids[i]);
  }
  const Eigen::Vector3d extent = (centroid_box.max - centroid_box.min).cwiseMax(std::numeric_limits<double>::min());
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keys(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d q = (centroids[i] - centroid_box.min).cwiseQuotient(extent) * kMortonCells;
    keys[i] = {spread_bits(static_cast<std::uint64_t>(q.x())) << 2 | spread_bits(static_cast<std::uint64_t>(q.y())) << 1 |
                   spread_bits(static_cast<std::uint64_t>(q.z())),
               static_cast<std::uint32_t>(i)};
  }
  centroids = {};
  std::sort(keys.begin(), keys.end());
  faces_.resize(n);
  boxes_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    faces_[i] = faces[keys[i].second];
    boxes_[i] = boxes[keys[i].second];
  }
  nodes_.reserve(n + 1);  // midpoint splits: leaves of 2..kLeafSize faces, fewer than n nodes
  nodes_.emplace_back();
  build(0, 0, static_cast<std::uint32_t>(n));
}

void AabbTree::build(std::uint32_t node, std::uint32_t begin, std::uint32_t end) {
  if (end - begin <= kLeafSize) {
    Box3 box = boxes_[begin];
    for (std::uint32_t i = begin + 1; i < end; ++i) {
      box.lo = box.lo.cwiseMin(boxes_[i].lo);
      box.hi = box.hi.cwiseMax(boxes_[i].hi);
    }
    nodes_[node].box = box;
    nodes_[node].begin = begin;
    nodes_[node].count = end - begin;
    return;
  }
  const std::uint32_t mid = begin + (end - begin) / 2;
  const auto left = static_cast<std::uint32_t>(nodes_.size());
  nodes_[node].left = left;
  nodes_.emplace_back();
  nodes_.emplace_back();
  build(left, begin, mid);
  build(left + 1, mid, end);
  nodes_[node].box = Box3{nodes_[left].box.lo.cwiseMin(nodes_[left + 1].box.lo),
                          nodes_[left].box.hi.cwiseMax(nodes_[left + 1].box.hi)};
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

AabbTree::Closest AabbTree::closest(const Eigen::Vector3d& p, std::uint32_t hint) const {
  Closest best{std::numeric_limits<double>::infinity(), kNoFace};
  auto test_face = [&](std::uint32_t face) {
    const auto& t = soup_->triangles[face];
    const Eigen::Vector3d q =
        closest_point_on_triangle(p, soup_->points[t[0]], soup_->points[t[1]], soup_->points[t[2]]);
    const double d = (q - p).squaredNorm();
    if (d < best.squared_distance || (d == best.squared_distance && face < best.face)) best = {d, face};
  };
  if (hint != kNoFace) test_face(hint);
  if (nodes_.empty()) return best;
  // Stack of (node, squared distance to its box), nearer child popped first.
  std::pair<std::uint32_t, double> stack[64];
  int top = 0;
  stack[top++] = {0u, nodes_[0].box.squared_distance(p)};
  while (top > 0) {
    const auto [index, box_distance] = stack[--top];
    if (box_distance > best.squared_distance) continue;
    const Node& node = nodes_[index];
    if (node.is_leaf()) {
      for (std::uint32_t i = node.begin; i < node.begin + node.count; ++i) {
        if (boxes_[i].squared_distance(p) <= best.squared_distance) test_face(faces_[i]);
      }
      continue;
    }
    const double dl = nodes_[node.left].box.squared_distance(p);
    const double dr = nodes_[node.left + 1].box.squared_distance(p);
    if (dl <= dr) {
      if (dr <= best.squared_distance) stack[top++] = {node.left + 1, dr};
      if (dl <= best.squared_distance) stack[top++] = {node.left, dl};
    } else {
      if (dl <= best.squared_distance) stack[top++] = {node.left, dl};
      if (dr <= best.squared_distance) stack[top++] = {node.left + 1, dr};
    }
  }
  return best;
}

}  // namespace nurbsfront::quality_detail
