// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/core/predicates.h"

#include <array>
#include <cmath>

namespace nurbsfront {
namespace {

using predicates_detail::grow_expansion;

// Knuth's TwoDiff: x + y == a - b exactly.
inline void two_diff(double a, double b, double& x, double& y) {
  x = a - b;
  const double bv = a - x;
  const double av = x + bv;
  y = (a - av) + (bv - b);
}

}  // namespace

int orient2d_adapt(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  // When the four coordinate differences are exact (neighbouring coordinates within a factor
  // 2 of each other, Sterbenz), det = acx bcy - acy bcx is a sum of two exact products, each
  // split into two doubles by an FMA: a 4-term expansion decides the sign.
  double acx = 0, acy = 0, bcx = 0, bcy = 0, t1 = 0, t2 = 0, t3 = 0, t4 = 0;
  two_diff(a.x(), c.x(), acx, t1);
  two_diff(a.y(), c.y(), acy, t2);
  two_diff(b.x(), c.x(), bcx, t3);
  two_diff(b.y(), c.y(), bcy, t4);
  if (t1 != 0.0 || t2 != 0.0 || t3 != 0.0 || t4 != 0.0) return orient2d_exact(a, b, c);
  const double p = acx * bcy;
  const double q = acy * bcx;
  const std::array<double, 4> terms = {std::fma(acx, bcy, -p), p, -std::fma(acy, bcx, -q), -q};
  std::array<double, 4> h{};
  int n = 0;
  for (double t : terms) n = grow_expansion(h.data(), n, t);
  if (n == 0) return 0;
  return h[static_cast<std::size_t>(n - 1)] > 0.0 ? 1 : -1;
}

int orient2d_exact(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  // det = ax*by - ax*cy - cx*by - ay*bx + ay*cx + cy*bx  (the cx*cy terms cancel).
  const std::array<std::array<double, 2>, 6> products = {{{a.x(), b.y()},
                                                          {-a.x(), c.y()},
                                                          {-c.x(), b.y()},
                                                          {-a.y(), b.x()},
                                                          {a.y(), c.x()},
                                                          {c.y(), b.x()}}};
  std::array<double, 12> h{};
  int n = 0;
  for (const auto& [u, v] : products) {
    const double p = u * v;
    const double e = std::fma(u, v, -p);
    n = grow_expansion(h.data(), n, e);
    n = grow_expansion(h.data(), n, p);
  }
  if (n == 0) return 0;
  return h[static_cast<std::size_t>(n - 1)] > 0.0 ? 1 : -1;
}

}  // namespace nurbsfront
