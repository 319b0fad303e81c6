// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! A static bounding-volume hierarchy of axis-aligned boxes over triangles (internal to
//! the quality module): faces ordered along a Morton curve of their centroids, split where
//! the Morton codes first differ (Karras's linear BVH), small leaves, nodes of 32 bytes in
//! one array. Boxes are stored in single precision, rounded outwards, so they always
//! contain the exact double-precision boxes: they only prune, every decision on a
//! candidate is taken in double precision (closest points) or exactly (intersections).
//! Used for self-intersection candidate pairs and closest-point queries.

#include <algorithm>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/soup.h"

namespace nurbsfront::quality_detail {

//! Axis-aligned box in single precision (outward-rounded from double).
struct Box3f {
  float lo[3];
  float hi[3];
  [[nodiscard]] bool overlaps(const Box3f& other) const {
    return lo[0] <= other.hi[0] && other.lo[0] <= hi[0] && lo[1] <= other.hi[1] && other.lo[1] <= hi[1] &&
           lo[2] <= other.hi[2] && other.lo[2] <= hi[2];
  }
  //! Squared distance from p to the box (0 inside), in double precision; never more than
  //! the distance to the exact box the float box encloses.
  [[nodiscard]] double squared_distance(const Eigen::Vector3d& p) const {
    double s = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double d = std::max({static_cast<double>(lo[k]) - p[k], p[k] - static_cast<double>(hi[k]), 0.0});
      s += d * d;
    }
    return s;
  }
  //! Squared length of the diagonal (a size measure for traversal decisions).
  [[nodiscard]] float squared_extent() const {
    const float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    return dx * dx + dy * dy + dz * dz;
  }
};

class AabbTree {
 public:
  struct Node {
    Box3f box;
    std::uint32_t index = 0;  //!< left child (right = left + 1) for inner nodes, first entry in faces() for leaves
    std::uint32_t count = 0;  //!< number of faces for leaves, 0 for inner nodes
    [[nodiscard]] bool is_leaf() const { return count > 0; }
    [[nodiscard]] std::uint32_t left() const { return index; }
    [[nodiscard]] std::uint32_t right() const { return index + 1; }
    [[nodiscard]] std::uint32_t begin() const { return index; }
    [[nodiscard]] std::uint32_t end() const { return index + count; }
  };

  //! Builds the tree over the given faces of the soup (indices must be valid). With
  //! n_threads >= 2 the per-face work runs in chunks and the root's two subtrees are built
  //! in parallel: the same tree (the same nodes at the same indices) for any thread count.
  AabbTree(const TriangleSoup& soup, std::vector<std::uint32_t> faces, unsigned n_threads = 1);

  [[nodiscard]] const std::vector<Node>& nodes() const { return nodes_; }
  //! Face indices in leaf order.
  [[nodiscard]] const std::vector<std::uint32_t>& faces() const { return faces_; }
  //! Box of faces()[i].
  [[nodiscard]] const Box3f& face_box(std::size_t i) const { return boxes_[i]; }
  [[nodiscard]] bool empty() const { return faces_.empty(); }

  struct Closest {
    double squared_distance;
    std::uint32_t face;
  };
  //! Closest face of the tree to p (ties: the lowest face index). `hint` (a face index or
  //! UINT32_MAX) only speeds the search up: with a face of the tree near p (e.g. the
  //! previous answer for coherent queries) the search starts at its leaf.
  [[nodiscard]] Closest closest(const Eigen::Vector3d& p, std::uint32_t hint) const;

  //! Refit after some faces changed: the tree now reads `soup` (the same face indices; it may
  //! hold more faces and points, which the tree does not see) and the boxes of the listed
  //! faces that are in the tree, and of their ancestors, are computed again from it (faces not
  //! in the tree are ignored). The structure stays: closest() gives the same answers as a tree
  //! built anew over the same faces of `soup` (its answer does not depend on the structure),
  //! only the pruning may be looser where faces moved far. `soup` must outlive the tree.
  void refit(const TriangleSoup& soup, const std::vector<std::uint32_t>& changed_faces);

 private:
  //! The subtree of faces_[begin, end) at nodes[node]: its descendants appended to nodes
  //! (children in pairs, each pair before the descendants of its left child), their
  //! parents to parent.
  void build(std::vector<Node>& nodes, std::vector<std::uint32_t>& parent, std::uint32_t node, std::uint32_t begin,
             std::uint32_t end, const std::vector<std::uint64_t>& codes) const;
  //! build() of the root with its two subtrees built on two threads, then placed where
  //! build() puts them.
  void build_halves(const std::vector<std::uint64_t>& codes);
  //! Improves `best` by the faces of the subtree at `start` closer than best.squared_distance.
  void search(const Eigen::Vector3d& p, std::uint32_t start, Closest& best) const;

  const TriangleSoup* soup_;
  std::vector<Node> nodes_;         //!< root first; siblings at (odd, odd + 1)
  std::vector<std::uint32_t> parent_;   //!< per node (the root's is 0)
  std::vector<std::uint32_t> leaf_of_;  //!< per soup face: its leaf, or UINT32_MAX if not in the tree
  std::vector<std::uint32_t> faces_;
  std::vector<Box3f> boxes_;
};

//! A soup with its tree over all its faces, built once and read by every stage that queries
//! that surface (the input: the fidelity moves and the report's distance pass). The tree reads
//! the soup, so the pair is neither copied nor moved (hold it in place, e.g. std::optional).
class IndexedSoup {
 public:
  //! Takes the soup and builds the tree on n_threads threads (the same tree for any count).
  explicit IndexedSoup(TriangleSoup soup, unsigned n_threads = 1);
  IndexedSoup(const IndexedSoup&) = delete;
  IndexedSoup& operator=(const IndexedSoup&) = delete;
  [[nodiscard]] const TriangleSoup& soup() const { return soup_; }
  [[nodiscard]] const AabbTree& tree() const { return tree_; }

 private:
  TriangleSoup soup_;
  AabbTree tree_;
};

//! The indices of `points` in Morton (Z-curve) order of the points' bounding box: queries
//! made in this order visit the tree's nodes coherently (cache-friendly).
std::vector<std::uint32_t> morton_order(const std::vector<Eigen::Vector3d>& points);

//! Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5).
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace nurbsfront::quality_detail
