// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal: the upper Cholesky factor of a 2 x 2 metric tensor (not installed API).

#include <cmath>

#include <Eigen/Core>

namespace nurbsfront::detail {

//! The factor R of M = R^T R, the same numbers bit for bit as `M.llt().matrixU()` (Eigen 3.4's
//! unblocked LLT on the lower triangle: l00 = sqrt(m00), l10 = m10 / l00,
//! l11 = sqrt(m11 - l10 * l10); a pivot <= 0 stops it and leaves the rest of the input in
//! place, as Eigen does). The front asks for it at every step and every swap test; Eigen's
//! LLT also computes the matrix's L1 norm and keeps its state, which this does not.
[[nodiscard]] inline Eigen::Matrix2d cholesky_upper(const Eigen::Matrix2d& m) {
  double l00 = m(0, 0), l10 = m(1, 0), l11 = m(1, 1);
  if (!(l00 <= 0.0)) {
    l00 = std::sqrt(l00);
    l10 = l10 / l00;
    const double x = m(1, 1) - l10 * l10;
    if (!(x <= 0.0)) l11 = std::sqrt(x);
  }
  Eigen::Matrix2d r;
  r << l00, l10, 0.0, l11;
  return r;
}

}  // namespace nurbsfront::detail
