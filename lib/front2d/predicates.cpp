// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/front2d/predicates.h"

#include <array>
#include <cmath>
#include <limits>

namespace nurbsfront::front2d {
namespace {

// Knuth's TwoSum: s + e == a + b exactly.
inline void two_sum(double a, double b, double& s, double& e) {
  s = a + b;
  const double bv = s - a;
  const double av = s - bv;
  e = (a - av) + (b - bv);
}

// Adds b to the expansion h[0..n) (non-overlapping, increasing magnitude), zero-eliminating.
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

double incircle(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                const Eigen::Vector2d& d) {
  using L = long double;
  const L adx = L(a.x()) - d.x(), ady = L(a.y()) - d.y();
  const L bdx = L(b.x()) - d.x(), bdy = L(b.y()) - d.y();
  const L cdx = L(c.x()) - d.x(), cdy = L(c.y()) - d.y();
  const L alift = adx * adx + ady * ady;
  const L blift = bdx * bdx + bdy * bdy;
  const L clift = cdx * cdx + cdy * cdy;
  return static_cast<double>(alift * (bdx * cdy - cdx * bdy) + blift * (cdx * ady - adx * cdy) +
                             clift * (adx * bdy - bdx * ady));
}

namespace {
// Lexicographic order, used for collinear overlap tests.
inline bool lex_less(const Eigen::Vector2d& p, const Eigen::Vector2d& q) {
  return p.x() < q.x() || (p.x() == q.x() && p.y() < q.y());
}
}  // namespace

bool segments_intersect(const Eigen::Vector2d& p1, const Eigen::Vector2d& p2, const Eigen::Vector2d& q1,
                        const Eigen::Vector2d& q2) {
  const int o1 = orient2d(p1, p2, q1);
  const int o2 = orient2d(p1, p2, q2);
  if (o1 * o2 > 0) return false;
  const int o3 = orient2d(q1, q2, p1);
  const int o4 = orient2d(q1, q2, p2);
  if (o3 * o4 > 0) return false;
  if (o1 == 0 && o2 == 0) {
    // Collinear (o3 == o4 == 0 too): overlap of the lexicographic intervals.
    const Eigen::Vector2d& pmin = lex_less(p1, p2) ? p1 : p2;
    const Eigen::Vector2d& pmax = lex_less(p1, p2) ? p2 : p1;
    const Eigen::Vector2d& qmin = lex_less(q1, q2) ? q1 : q2;
    const Eigen::Vector2d& qmax = lex_less(q1, q2) ? q2 : q1;
    return !lex_less(pmax, qmin) && !lex_less(qmax, pmin);
  }
  return true;
}

}  // namespace nurbsfront::front2d
