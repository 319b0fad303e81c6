// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Exact geometric predicates in the plane: orient2d() (shared with the quality module, in
//! nurbsfront/core/predicates.h) and the front's segment test.

#include <Eigen/Core>

#include "nurbsfront/core/predicates.h"

namespace nurbsfront::front2d {

using nurbsfront::orient2d;
using nurbsfront::orient2d_adapt;
using nurbsfront::orient2d_exact;

//! Naive double evaluation of 2 * signed area of (a, b, c) (not exact; for tests and for
//! quality measures).
[[nodiscard]] inline double orient2d_naive(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return (a.x() - c.x()) * (b.y() - c.y()) - (a.y() - c.y()) * (b.x() - c.x());
}

//! Positive if d lies inside the circle through the counter-clockwise triangle (a, b, c),
//! negative outside, about zero on it. Evaluated in long double, not exact: only used to
//! choose between valid candidates, never to decide validity.
[[nodiscard]] double incircle(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                              const Eigen::Vector2d& d);

//! True if the closed segments [p1, p2] and [q1, q2] have a point in common. Exact.
[[nodiscard]] bool segments_intersect(const Eigen::Vector2d& p1, const Eigen::Vector2d& p2,
                                      const Eigen::Vector2d& q1, const Eigen::Vector2d& q2);

}  // namespace nurbsfront::front2d
