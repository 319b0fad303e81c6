// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! A static bounding-volume hierarchy of axis-aligned boxes over triangles (internal to
//! the quality module): faces ordered along a Morton curve of their centroids, split at
//! the middle, small leaves, nodes in one array. Used for self-intersection candidate pairs and
//! closest-point queries.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/soup.h"

namespace nurbsfront::quality_detail {

struct Box3 {
  Eigen::Vector3d lo;
  Eigen::Vector3d hi;
  [[nodiscard]] bool overlaps(const Box3& other) const {
    return (lo.array() <= other.hi.array()).all() && (other.lo.array() <= hi.array()).all();
  }
  //! Squared distance from p to the box (0 inside).
  [[nodiscard]] double squared_distance(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = (lo - p).cwiseMax(p - hi).cwiseMax(0.0);
    return d.squaredNorm();
  }
};

class AabbTree {
 public:
  struct Node {
    Box3 box;
    std::uint32_t left = 0;   //!< index of the left child (right = left + 1) for inner nodes
    std::uint32_t begin = 0;  //!< first entry in faces() for leaves
    std::uint32_t count = 0;  //!< number of faces for leaves, 0 for inner nodes
    [[nodiscard]] bool is_leaf() const { return count > 0; }
  };

  //! Builds the tree over the given faces of the soup (indices must be valid).
  AabbTree(const TriangleSoup& soup, std::vector<std::uint32_t> faces);

  [[nodiscard]] const std::vector<Node>& nodes() const { return nodes_; }
  //! Face indices in leaf order.
  [[nodiscard]] const std::vector<std::uint32_t>& faces() const { return faces_; }
  //! Box of faces()[i].
  [[nodiscard]] const Box3& face_box(std::size_t i) const { return boxes_[i]; }
  [[nodiscard]] bool empty() const { return faces_.empty(); }

  struct Closest {
    double squared_distance;
    std::uint32_t face;
  };
  //! Closest face to p; `hint` (a face index or UINT32_MAX) seeds the search bound.
  [[nodiscard]] Closest closest(const Eigen::Vector3d& p, std::uint32_t hint) const;

 private:
  void build(std::uint32_t node, std::uint32_t begin, std::uint32_t end);

  const TriangleSoup* soup_;
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> faces_;
  std::vector<Box3> boxes_;
};

//! Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5).
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace nurbsfront::quality_detail
