// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Exact geometric predicates in the plane.
//!
//! orient2d() is evaluated with a static error filter (Shewchuk's first-stage bound) and,
//! when the filter cannot decide, exactly: the determinant is expanded into six products of
//! input coordinates, each split into two doubles by an FMA error-free transform, and the
//! twelve terms are summed into a non-overlapping floating-point expansion whose largest
//! component gives the sign. The answer is exact for all finite inputs whose products
//! neither overflow nor underflow.
//! \cite Shewchuk 1997, "Adaptive precision floating-point arithmetic and fast robust
//! geometric predicates".

#include <Eigen/Core>

namespace nurbsfront::front2d {

//! Sign of the signed area of (a, b, c): +1 if counter-clockwise, -1 if clockwise, 0 if
//! collinear. Exact.
[[nodiscard]] int orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

//! The same sign computed only from the exact expansion (no filter); for tests.
[[nodiscard]] int orient2d_exact(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

//! Naive double evaluation of 2 * signed area of (a, b, c) (not exact; for tests and for
//! quality measures).
[[nodiscard]] double orient2d_naive(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

//! Positive if d lies inside the circle through the counter-clockwise triangle (a, b, c),
//! negative outside, about zero on it. Evaluated in long double, not exact: only used to
//! choose between valid candidates, never to decide validity.
[[nodiscard]] double incircle(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                              const Eigen::Vector2d& d);

//! True if the closed segments [p1, p2] and [q1, q2] have a point in common. Exact.
[[nodiscard]] bool segments_intersect(const Eigen::Vector2d& p1, const Eigen::Vector2d& p2,
                                      const Eigen::Vector2d& q1, const Eigen::Vector2d& q2);

}  // namespace nurbsfront::front2d
