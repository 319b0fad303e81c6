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

#include <cmath>
#include <limits>

#include <Eigen/Core>

namespace nurbsfront::front2d {

//! The same sign as orient2d() computed only from the exact expansion (no filter); for tests
//! and as orient2d's fallback.
[[nodiscard]] int orient2d_exact(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

//! Second stage of orient2d(): exact when the coordinate differences are exact (a 4-term
//! expansion of two FMA-split products), else orient2d_exact().
[[nodiscard]] int orient2d_adapt(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

//! Sign of the signed area of (a, b, c): +1 if counter-clockwise, -1 if clockwise, 0 if
//! collinear. Exact. Inline: the filter decides almost every call; a difference that is
//! exactly zero (equal coordinates: a subtraction never rounds to zero) makes its product
//! exactly zero, and the sign is then the product of the signs of the other two differences,
//! which rounding keeps (this decides axis-parallel collinear points without the expansion).
[[nodiscard]] inline int orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  constexpr double kEps = std::numeric_limits<double>::epsilon() / 2.0;  // 2^-53
  constexpr double kErrBound = (3.0 + 16.0 * kEps) * kEps;              // Shewchuk's first stage
  const double acx = a.x() - c.x(), bcy = b.y() - c.y();
  const double acy = a.y() - c.y(), bcx = b.x() - c.x();
  const double left = acx * bcy;
  const double right = acy * bcx;
  const double det = left - right;
  const double bound = kErrBound * (std::abs(left) + std::abs(right));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  auto sgn = [](double x) { return (x > 0.0) - (x < 0.0); };
  if (acx == 0.0 || bcy == 0.0) return -sgn(acy) * sgn(bcx);
  if (acy == 0.0 || bcx == 0.0) return sgn(acx) * sgn(bcy);
  return orient2d_adapt(a, b, c);
}

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
