// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Helpers shared by the quality module's sources (not part of the public API).

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <vector>

#include "nurbsfront/core/soup.h"

namespace nurbsfront {
struct DistanceOptions;
struct DistanceReport;
}  // namespace nurbsfront

namespace nurbsfront::quality_detail {

class AabbTree;

//! Tree over all faces of `soup` (what count_self_intersections_with and
//! mesh_distance_with share when a report computes both).
AabbTree all_faces_tree(const TriangleSoup& soup);

//! count_self_intersections() on a given tree over all faces of the soup (validated).
std::size_t count_self_intersections_with(const TriangleSoup& soup, const AabbTree& tree, unsigned n_threads,
                                          std::vector<std::array<std::uint32_t, 2>>* pairs = nullptr);

//! mesh_distance() with the mesh's tree over all its faces given (nullptr: built here).
DistanceReport mesh_distance_with(const TriangleSoup& mesh, const TriangleSoup& reference,
                                  const DistanceOptions& options, const AabbTree* mesh_tree);

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

}  // namespace nurbsfront::quality_detail
