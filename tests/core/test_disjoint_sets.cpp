// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/core/disjoint_sets.h"

#include <gtest/gtest.h>

#include <cstdint>

namespace nurbsfront {
namespace {

TEST(DisjointSets, ClassesAreRepresentedByTheirSmallestIndexWhateverTheOrder) {
  DisjointSets sets(7);
  EXPECT_EQ(sets.size(), 7u);
  for (std::uint32_t i = 0; i < 7; ++i) EXPECT_EQ(sets.find(i), i);
  // {5, 3, 6} joined from the top down, then {1, 4}; 0 and 2 stay alone.
  EXPECT_TRUE(sets.unite(6, 5));
  EXPECT_TRUE(sets.unite(5, 3));
  EXPECT_TRUE(sets.unite(4, 1));
  EXPECT_FALSE(sets.unite(6, 3));  // one class already
  const std::uint32_t expected[7] = {0, 1, 2, 3, 1, 3, 3};
  for (std::uint32_t i = 0; i < 7; ++i) EXPECT_EQ(sets.find(i), expected[i]) << i;
  // Joining the two classes through their largest members: the root is the smallest, 1.
  EXPECT_TRUE(sets.unite(6, 4));
  for (const std::uint32_t i : {1u, 3u, 4u, 5u, 6u}) EXPECT_EQ(sets.find(i), 1u) << i;
  EXPECT_EQ(sets.find(0), 0u);
  EXPECT_EQ(sets.find(2), 2u);
}

TEST(DisjointSets, AChainJoinedInEitherOrderEndsAtIndexZero) {
  const std::uint32_t n = 1000;
  DisjointSets up(n), down(n);
  for (std::uint32_t i = 1; i < n; ++i) EXPECT_TRUE(up.unite(i - 1, i));
  for (std::uint32_t i = n - 1; i > 0; --i) EXPECT_TRUE(down.unite(i, i - 1));
  for (std::uint32_t i = 0; i < n; ++i) {
    EXPECT_EQ(up.find(i), 0u);
    EXPECT_EQ(down.find(i), 0u);
  }
}

}  // namespace
}  // namespace nurbsfront
