// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/front2d/sizing.h"

#include <cmath>
#include <string>

#include "nurbsfront/core/error.h"

namespace nurbsfront {

void SizingField::validate() const {
  if (!std::isfinite(gradation) || gradation <= 1.0)
    throw InvalidInput("SizingField: gradation must be a finite number > 1, got " + std::to_string(gradation));
  switch (kind) {
    case Kind::Uniform:
      if (!std::isfinite(uniform_size) || uniform_size < 0.0)
        throw InvalidInput("SizingField: uniform_size must be finite and >= 0 (0 = automatic), got " +
                           std::to_string(uniform_size));
      break;
    case Kind::PerVertex:
      for (double h : vertex_sizes)
        if (!std::isfinite(h) || h <= 0.0)
          throw InvalidInput("SizingField: every vertex size must be finite and > 0");
      break;
    case Kind::Callback:
      if (!callback) throw InvalidInput("SizingField: Kind::Callback without a callback");
      if (callback_grid_cells < 0 || callback_grid_cells > kMaxCallbackGridCells)
        throw InvalidInput("SizingField: callback_grid_cells must be in [0, " + std::to_string(kMaxCallbackGridCells) + "], got " + std::to_string(callback_grid_cells));
      break;
  }
}

}  // namespace nurbsfront
