// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <cstdint>
#include <vector>

#include "nurbsfront/quality/internal.h"

namespace nurbsfront::quality_detail {

// Sorts (key, value) pairs by key: least-significant-digit radix sort with 11-bit digits
// (2048 buckets: few enough output streams to stay in cache), skipping the digits in
// which all keys agree. Stable, so equal keys keep their order.
void radix_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values) {
  const std::size_t n = keys.size();
  std::uint64_t all_or = 0, all_and = ~std::uint64_t{0};
  for (auto k : keys) {
    all_or |= k;
    all_and &= k;
  }
  std::vector<std::uint64_t> keys2(n);
  std::vector<std::uint32_t> values2(n);
  constexpr int kBits = 11;
  constexpr std::uint64_t kMask = (1u << kBits) - 1;
  std::vector<std::size_t> offset(std::size_t{1} << kBits);
  for (int shift = 0; shift < 64; shift += kBits) {
    if ((((all_or ^ all_and) >> shift) & kMask) == 0) continue;  // same digit everywhere
    std::fill(offset.begin(), offset.end(), 0);
    for (auto k : keys) ++offset[(k >> shift) & kMask];
    std::size_t sum = 0;
    for (auto& o : offset) {
      const std::size_t c = o;
      o = sum;
      sum += c;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t to = offset[(keys[i] >> shift) & kMask]++;
      keys2[to] = keys[i];
      values2[to] = values[i];
    }
    keys.swap(keys2);
    values.swap(values2);
  }
}

}  // namespace nurbsfront::quality_detail
