// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Exact orientation in the plane, shared by front2d (the advancing front's validity tests)
//! and quality (the self-intersection tests), and the expansion arithmetic behind it.
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

namespace nurbsfront {

namespace predicates_detail {

//! Knuth's TwoSum: s + e == a + b exactly, |e| <= ulp(s) / 2.
inline void two_sum(double a, double b, double& s, double& e) {
  s = a + b;
  const double bv = s - a;
  const double av = s - bv;
  e = (a - av) + (b - bv);
}

//! Adds b to the expansion h[0..n) (non-overlapping, increasing magnitude) exactly, in place,
//! zero-eliminating (Shewchuk's GROW-EXPANSION); returns the new length (at most n + 1).
inline int grow_expansion(double* h, int n, double b) {
  double q = b;
  int m = 0;
  for (int i = 0; i < n; ++i) {
    double s = 0.0;
    double e = 0.0;
    two_sum(q, h[i], s, e);
    q = s;
    if (e != 0.0) h[m++] = e;
  }
  if (q != 0.0) h[m++] = q;
  return m;
}

}  // namespace predicates_detail

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

}  // namespace nurbsfront
