// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Helpers shared by the quality module's sources (not part of the public API).

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/soup.h"

namespace nurbsfront {
struct DistanceOptions;
struct DistanceReport;
}  // namespace nurbsfront

namespace nurbsfront::quality_detail {

class AabbTree;

//! Tree over all faces of `soup` (what count_self_intersections_with and
//! mesh_distance_with share when a report computes both), built on n_threads threads (the
//! same tree for any count).
AabbTree all_faces_tree(const TriangleSoup& soup, unsigned n_threads = 1);

//! count_self_intersections() on a given tree over all faces of the soup (validated).
std::size_t count_self_intersections_with(const TriangleSoup& soup, const AabbTree& tree, unsigned n_threads,
                                          std::vector<std::array<std::uint32_t, 2>>* pairs = nullptr);

//! mesh_distance() with the mesh's tree over all its faces given (nullptr: built here), and
//! the reference's (nullptr: built here; e.g. IndexedSoup::tree() of the input). The same
//! report either way. Not validated (mesh_distance() validates).
DistanceReport mesh_distance_with(const TriangleSoup& mesh, const TriangleSoup& reference,
                                  const DistanceOptions& options, const AabbTree* mesh_tree,
                                  const AabbTree* reference_tree = nullptr);

//! \throw InvalidInput naming `what` for out-of-range indices or non-finite points.
void validate_soup(const TriangleSoup& soup, const char* what);

//! Every edge has exactly two faces and no face repeats a vertex (orientation ignored).
bool is_closed_surface(const TriangleSoup& soup);

//! Sorts (key, value) pairs by key (stable).
void radix_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values);

//! Sorts `items` by `less` when `less` orders first by `bucket(item)`, an integer below
//! `n_buckets`: a stable counting sort by bucket, then a comparison sort inside each
//! bucket. Linear for the small buckets of mesh adjacency (edges or faces keyed by their
//! lowest vertex); the same result as std::sort for a strict total order.
template <class T, class Bucket, class Less>
void bucket_sort(std::vector<T>& items, std::size_t n_buckets, Bucket bucket, Less less) {
  std::vector<std::size_t> start(n_buckets + 1, 0);
  for (const T& x : items) ++start[bucket(x) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<T> sorted(items.size());
  for (const T& x : items) sorted[start[bucket(x)]++] = x;  // start[b] becomes the end of bucket b
  std::size_t begin = 0;
  for (std::size_t b = 0; b < n_buckets; ++b) {
    const std::size_t end = start[b];
    if (end - begin > 1) {
      std::sort(sorted.begin() + static_cast<std::ptrdiff_t>(begin), sorted.begin() + static_cast<std::ptrdiff_t>(end), less);
    }
    begin = end;
  }
  items.swap(sorted);
}

//! A uniform grid of cells over a set of closed boxes (items 0, 1, ...), each cell listing
//! the items whose box meets it: box-overlap candidates without a tree, for a few boxes
//! scattered over a large soup (intersecting_pairs_of). The cells are about the items'
//! mean largest side, at most 64 x items of them (at least 4096, at most 2^21). A point's cell is taken by
//! the same rounded, clamped arithmetic for every box (monotone in each coordinate), so
//! two boxes that meet always share a cell.
class BoxGrid {
 public:
  //! Grid over the boxes [lo[i], hi[i]] (same sizes, lo <= hi, finite).
  BoxGrid(std::vector<Eigen::Vector3d> lo, std::vector<Eigen::Vector3d> hi);

  //! Calls visit(i) exactly once for every item i whose box meets the closed box
  //! [lo, hi] (exact double comparisons), in no particular order.
  template <class Visit>
  void for_each_overlapping(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Visit& visit) const {
    if (lo_.empty()) return;
    const int x0 = cell_along(0, lo.x()), x1 = cell_along(0, hi.x());
    const int y0 = cell_along(1, lo.y()), y1 = cell_along(1, hi.y());
    const int z0 = cell_along(2, lo.z()), z1 = cell_along(2, hi.z());
    for (int z = z0; z <= z1; ++z) {
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
          const std::size_t cell = index(x, y, z);
          for (std::uint32_t k = start_[cell]; k < start_[cell + 1]; ++k) {
            const std::uint32_t i = items_[k];
            const Eigen::Vector3d& a = lo_[i];
            const Eigen::Vector3d& b = hi_[i];
            if (b.x() < lo.x() || hi.x() < a.x() || b.y() < lo.y() || hi.y() < a.y() || b.z() < lo.z() || hi.z() < a.z()) {
              continue;
            }
            // Each pair once: in the cell of the lowest corner of the two boxes' overlap
            // (in both boxes, so in both cell ranges).
            if (cell_along(0, std::max(a.x(), lo.x())) != x || cell_along(1, std::max(a.y(), lo.y())) != y ||
                cell_along(2, std::max(a.z(), lo.z())) != z) {
              continue;
            }
            visit(i);
          }
        }
      }
    }
  }

  //! False when no item's box meets [lo, hi] for sure (its cells are empty); a cheap test
  //! before for_each_overlapping().
  [[nodiscard]] bool may_overlap(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const {
    if (lo_.empty()) return false;
    const int x0 = cell_along(0, lo.x()), x1 = cell_along(0, hi.x());
    const int y0 = cell_along(1, lo.y()), y1 = cell_along(1, hi.y());
    const int z0 = cell_along(2, lo.z()), z1 = cell_along(2, hi.z());
    for (int z = z0; z <= z1; ++z) {
      for (int y = y0; y <= y1; ++y) {
        const std::size_t row = index(0, y, z);
        if (start_[row + static_cast<std::size_t>(x0)] != start_[row + static_cast<std::size_t>(x1) + 1]) return true;
      }
    }
    return false;
  }

  //! True when p lies in a cell some item's box meets (every point of an item's box does;
  //! points at one position share their cell).
  [[nodiscard]] bool is_occupied(const Eigen::Vector3d& p) const {
    if (lo_.empty()) return false;
    const std::size_t cell = index(cell_along(0, p.x()), cell_along(1, p.y()), cell_along(2, p.z()));
    return start_[cell] != start_[cell + 1];
  }

  //! Cells along x, y, z.
  [[nodiscard]] const std::array<int, 3>& dimensions() const { return n_; }

 private:
  // The cell of coordinate t along axis k, clamped to the grid (non-decreasing in t).
  [[nodiscard]] int cell_along(int k, double t) const {
    const double u = (t - origin_[k]) * inverse_[k];
    return static_cast<int>(std::min(std::max(u, 0.0), last_[k]));
  }
  [[nodiscard]] std::size_t index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * static_cast<std::size_t>(n_[1]) + static_cast<std::size_t>(y)) *
               static_cast<std::size_t>(n_[0]) +
           static_cast<std::size_t>(x);
  }

  std::vector<Eigen::Vector3d> lo_, hi_;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero(), inverse_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_ = Eigen::Vector3d::Zero();  //!< n_ - 1, as doubles
  std::array<int, 3> n_{1, 1, 1};
  std::vector<std::uint32_t> start_;  //!< per cell, its first entry in items_ (one more at the end)
  std::vector<std::uint32_t> items_;
};

}  // namespace nurbsfront::quality_detail
