// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <cstdint>
#include <vector>

#include "nurbsfront/quality/internal.h"

namespace nurbsfront::quality_detail {

// Sorts (key, value) pairs by key: least-significant-digit radix sort with 16-bit digits,
// skipping the digits in which all keys agree. Stable, so equal keys keep their order.
void radix_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values) {
  const std::size_t n = keys.size();
  std::uint64_t all_or = 0, all_and = ~std::uint64_t{0};
  for (auto k : keys) {
    all_or |= k;
    all_and &= k;
  }
  std::vector<std::uint64_t> keys2(n);
  std::vector<std::uint32_t> values2(n);
  std::vector<std::size_t> offset(1u << 16);
  for (int shift = 0; shift < 64; shift += 16) {
    if ((((all_or ^ all_and) >> shift) & 0xffffu) == 0) continue;  // same digit everywhere
    std::fill(offset.begin(), offset.end(), 0);
    for (auto k : keys) ++offset[(k >> shift) & 0xffffu];
    std::size_t sum = 0;
    for (auto& o : offset) {
      const std::size_t c = o;
      o = sum;
      sum += c;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t to = offset[(keys[i] >> shift) & 0xffffu]++;
      keys2[to] = keys[i];
      values2[to] = values[i];
    }
    keys.swap(keys2);
    values.swap(values2);
  }
}

}  // namespace nurbsfront::quality_detail
