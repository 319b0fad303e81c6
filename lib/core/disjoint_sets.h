// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Union-find over 0..n-1 with path halving; a class is represented by its smallest index,
//! so the roots do not depend on the order of the unions.

#include <cstddef>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

namespace nurbsfront {

class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), std::uint32_t{0}); }
  [[nodiscard]] std::size_t size() const { return parent_.size(); }
  //! The smallest index of x's class.
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  //! Joins the classes of a and b; false when they were one already.
  bool unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return false;
    if (a < b) std::swap(a, b);
    parent_[a] = b;
    return true;
  }

 private:
  std::vector<std::uint32_t> parent_;
};

}  // namespace nurbsfront
