// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/quality/predicates.h"

#include <cmath>

#include "nurbsfront/core/predicates.h"

namespace nurbsfront::quality_detail {
namespace {

// Expansions: sums of non-overlapping doubles in increasing magnitude, no zeros. Their
// sign is the sign of the last (largest) component. Written from Shewchuk's paper with
// fixed-size storage (no allocation); the largest one here, the 3x3 determinant of
// two-component differences, has at most 192 components.
constexpr int kMaxComponents = 192;
struct Expansion {
  double c[kMaxComponents];
  int n = 0;
};

constexpr double kEpsilon = 0x1p-53;  // half an ulp of 1: the unit roundoff of double
// Shewchuk's stage-A error bounds of the plain floating-point determinants.
constexpr double kOrient3dBound = (7.0 + 56.0 * kEpsilon) * kEpsilon;

// e += b, exactly (Shewchuk's GROW-EXPANSION with zero elimination), in place.
void grow(Expansion& e, double b) { e.n = predicates_detail::grow_expansion(e.c, e.n, b); }

void add(Expansion& e, const Expansion& f) {
  for (int i = 0; i < f.n; ++i) grow(e, f.c[i]);
}

void negate(Expansion& e) {
  for (int i = 0; i < e.n; ++i) e.c[i] = -e.c[i];
}

// h += e * b exactly: every component's product is split error-free with an FMA.
void add_scaled(Expansion& h, const Expansion& e, double b) {
  for (int i = 0; i < e.n; ++i) {
    const double product = e.c[i] * b;
    const double error = std::fma(e.c[i], b, -product);
    if (error != 0.0) grow(h, error);
    if (product != 0.0) grow(h, product);
  }
}

Expansion multiply(const Expansion& e, const Expansion& f) {
  Expansion h;
  for (int i = 0; i < f.n; ++i) add_scaled(h, e, f.c[i]);
  return h;
}

// a - b as an exact two-component expansion.
Expansion difference(double a, double b) {
  double x = 0.0, y = 0.0;
  predicates_detail::two_sum(a, -b, x, y);
  Expansion e;
  if (y != 0.0) e.c[e.n++] = y;
  if (x != 0.0) e.c[e.n++] = x;
  return e;
}

// e * f - g * h
Expansion cross_minor(const Expansion& e, const Expansion& f, const Expansion& g, const Expansion& h) {
  Expansion r = multiply(e, f);
  Expansion s = multiply(g, h);
  negate(s);
  add(r, s);
  return r;
}

int sign(const Expansion& e) {
  if (e.n == 0) return 0;
  return e.c[e.n - 1] > 0.0 ? 1 : -1;
}

int orient3d_exact(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   const Eigen::Vector3d& d) {
  // Four points with one coordinate in common lie in an axis-aligned plane: exactly
  // coplanar. Marching-cubes surfaces of label volumes are full of such faces, and the
  // expansion arithmetic below costs a hundred times the filter. (Tested here, not in
  // orient3d(), so the filter's code stays as small as it was.)
  for (int k = 0; k < 3; ++k)
    if (a[k] == d[k] && b[k] == d[k] && c[k] == d[k]) return 0;
  const Expansion adx = difference(a.x(), d.x()), ady = difference(a.y(), d.y()), adz = difference(a.z(), d.z());
  const Expansion bdx = difference(b.x(), d.x()), bdy = difference(b.y(), d.y()), bdz = difference(b.z(), d.z());
  const Expansion cdx = difference(c.x(), d.x()), cdy = difference(c.y(), d.y()), cdz = difference(c.z(), d.z());
  Expansion det = multiply(adz, cross_minor(bdx, cdy, bdy, cdx));
  add(det, multiply(bdz, cross_minor(cdx, ady, cdy, adx)));
  add(det, multiply(cdz, cross_minor(adx, bdy, ady, bdx)));
  return sign(det);
}

}  // namespace

int orient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
             const Eigen::Vector3d& d) {
  const double adx = a.x() - d.x(), ady = a.y() - d.y(), adz = a.z() - d.z();
  const double bdx = b.x() - d.x(), bdy = b.y() - d.y(), bdz = b.z() - d.z();
  const double cdx = c.x() - d.x(), cdy = c.y() - d.y(), cdz = c.z() - d.z();
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * std::abs(adz) +
                           (std::abs(cdxady) + std::abs(adxcdy)) * std::abs(bdz) +
                           (std::abs(adxbdy) + std::abs(bdxady)) * std::abs(cdz);
  const double bound = kOrient3dBound * permanent;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return orient3d_exact(a, b, c, d);
}

}  // namespace nurbsfront::quality_detail
