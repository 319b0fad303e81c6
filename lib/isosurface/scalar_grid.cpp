// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/isosurface/scalar_grid.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "nurbsfront/core/error.h"

namespace nurbsfront {

std::size_t ScalarGrid::size() const {
  if (dims[0] <= 0 || dims[1] <= 0 || dims[2] <= 0) return 0;
  return static_cast<std::size_t>(dims[0]) * static_cast<std::size_t>(dims[1]) * static_cast<std::size_t>(dims[2]);
}

BoundingBox ScalarGrid::bounds() const {
  BoundingBox box;
  if (size() == 0) return box;
  box.extend(point(0, 0, 0));
  box.extend(point(dims[0] - 1, dims[1] - 1, dims[2] - 1));
  return box;
}

std::array<float, 2> ScalarGrid::value_range() const {
  if (values.empty()) return {0.0f, 0.0f};
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  return {*lo, *hi};
}

void ScalarGrid::validate() const {
  for (int a = 0; a < 3; ++a) {
    if (dims[a] < 1) {
      throw InvalidInput("nurbsfront: ScalarGrid dims must be >= 1, got " + std::to_string(dims[0]) + " x " +
                         std::to_string(dims[1]) + " x " + std::to_string(dims[2]));
    }
  }
  if (values.size() != size()) {
    throw InvalidInput("nurbsfront: ScalarGrid has " + std::to_string(values.size()) + " values but its dims give " +
                       std::to_string(size()));
  }
  if (!origin.allFinite()) throw InvalidInput("nurbsfront: ScalarGrid origin is not finite");
  if (!spacing.allFinite() || (spacing.array() <= 0.0).any()) {
    throw InvalidInput("nurbsfront: ScalarGrid spacing must be finite and positive");
  }
  for (const float v : values) {
    if (!std::isfinite(v)) throw InvalidInput("nurbsfront: ScalarGrid contains a non-finite value");
  }
}

}  // namespace nurbsfront
