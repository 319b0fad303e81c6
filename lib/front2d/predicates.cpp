// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/front2d/predicates.h"

namespace nurbsfront::front2d {

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
