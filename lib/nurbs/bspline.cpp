// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/nurbs/bspline.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "nurbsfront/core/error.h"

namespace nurbsfront {

void KnotVector::validate(std::size_t n_control, const char* what) const {
  const std::string name(what);
  if (degree < 1 || degree > kMaxDegree) {
    throw InvalidInput(name + ": degree " + std::to_string(degree) + " outside [1, " +
                       std::to_string(kMaxDegree) + "]");
  }
  const auto p = static_cast<std::size_t>(degree);
  if (n_control < p + 1) {
    throw InvalidInput(name + ": " + std::to_string(n_control) + " control points, degree " +
                       std::to_string(degree) + " needs at least " + std::to_string(p + 1));
  }
  if (knots.size() != n_control + p + 1) {
    throw InvalidInput(name + ": knot vector has " + std::to_string(knots.size()) + " knots, expected " +
                       std::to_string(n_control + p + 1) + " (control points + degree + 1)");
  }
  std::size_t multiplicity = 1;
  for (std::size_t i = 0; i < knots.size(); ++i) {
    if (!std::isfinite(knots[i])) throw InvalidInput(name + ": knot " + std::to_string(i) + " is not finite");
    if (i == 0) continue;
    if (knots[i] < knots[i - 1]) {
      throw InvalidInput(name + ": knot vector is not non-decreasing at index " + std::to_string(i));
    }
    multiplicity = knots[i] == knots[i - 1] ? multiplicity + 1 : 1;
    if (multiplicity > p + 1) {
      throw InvalidInput(name + ": knot " + std::to_string(knots[i]) + " has multiplicity above degree + 1");
    }
  }
  if (!(domain_max() > domain_min())) throw InvalidInput(name + ": empty parameter domain [U_p, U_n]");
}

std::size_t KnotVector::find_span(double u) const {
  const auto p = static_cast<std::size_t>(degree);
  const std::size_t n = n_basis();  // spans p .. n-1
  if (!(u > knots[p])) u = knots[p];  // also catches NaN
  if (u >= knots[n]) {
    std::size_t span = n - 1;
    while (span > p && knots[span] == knots[span + 1]) --span;
    return span;
  }
  // First knot in U_{p+1} .. U_n that is > u; the span starts one before it.
  const auto it = std::upper_bound(knots.begin() + static_cast<std::ptrdiff_t>(p) + 1,
                                   knots.begin() + static_cast<std::ptrdiff_t>(n), u);
  return static_cast<std::size_t>(it - knots.begin()) - 1;
}

BasisRows KnotVector::basis(std::size_t span, double u, int n_derivatives) const {
  const int p = degree;
  NURBSFRONT_ASSERT(p >= 1 && p <= kMaxDegree);
  NURBSFRONT_ASSERT(n_derivatives >= 0 && n_derivatives <= kMaxDerivativeOrder);
  u = std::clamp(u, domain_min(), domain_max());
  constexpr int kSize = kMaxDegree + 1;
  // ndu: lower triangle holds knot differences, upper triangle the basis functions of
  // increasing degree (NURBS Book A2.3).
  std::array<std::array<double, kSize>, kSize> ndu{};
  std::array<double, kSize> left{};
  std::array<double, kSize> right{};
  const auto s = static_cast<std::ptrdiff_t>(span);
  ndu[0][0] = 1.0;
  for (int j = 1; j <= p; ++j) {
    left[j] = u - knots[static_cast<std::size_t>(s + 1 - j)];
    right[j] = knots[static_cast<std::size_t>(s + j)] - u;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      ndu[j][r] = right[r + 1] + left[j - r];
      const double temp = ndu[r][j - 1] / ndu[j][r];
      ndu[r][j] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    ndu[j][j] = saved;
  }
  BasisRows ders{};
  for (int j = 0; j <= p; ++j) ders[0][j] = ndu[j][p];
  const int n = std::min(n_derivatives, p);
  if (n == 0) return ders;
  std::array<std::array<double, kSize>, 2> a{};
  for (int r = 0; r <= p; ++r) {
    int s1 = 0;
    int s2 = 1;
    a[0][0] = 1.0;
    for (int k = 1; k <= n; ++k) {
      double d = 0.0;
      const int rk = r - k;
      const int pk = p - k;
      if (r >= k) {
        a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
        d = a[s2][0] * ndu[rk][pk];
      }
      const int j1 = rk >= -1 ? 1 : -rk;
      const int j2 = (r - 1 <= pk) ? k - 1 : p - r;
      for (int j = j1; j <= j2; ++j) {
        a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
        d += a[s2][j] * ndu[rk + j][pk];
      }
      if (r <= pk) {
        a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
        d += a[s2][k] * ndu[r][pk];
      }
      ders[k][r] = d;
      std::swap(s1, s2);
    }
  }
  double factor = p;
  for (int k = 1; k <= n; ++k) {
    for (int j = 0; j <= p; ++j) ders[k][j] *= factor;
    factor *= p - k;
  }
  return ders;
}

void NurbsCurve::validate() const {
  if (control_points.empty()) throw InvalidInput("NURBS curve: no control points");
  u.validate(control_points.size(), "NURBS curve");
  for (std::size_t i = 0; i < control_points.size(); ++i) {
    if (!control_points[i].allFinite()) {
      throw InvalidInput("NURBS curve: control point " + std::to_string(i) + " is not finite");
    }
  }
  if (!weights.empty()) {
    if (weights.size() != control_points.size()) {
      throw InvalidInput("NURBS curve: " + std::to_string(weights.size()) + " weights for " +
                         std::to_string(control_points.size()) + " control points");
    }
    for (std::size_t i = 0; i < weights.size(); ++i) {
      if (!(weights[i] > 0.0) || !std::isfinite(weights[i])) {
        throw InvalidInput("NURBS curve: weight " + std::to_string(i) + " is not positive and finite");
      }
    }
  }
}

bool NurbsCurve::is_rational() const {
  return std::any_of(weights.begin(), weights.end(), [this](double w) { return w != weights.front(); });
}

Eigen::Vector3d NurbsCurve::evaluate(double t) const { return derivatives(t)[0]; }

std::array<Eigen::Vector3d, 3> NurbsCurve::derivatives(double t) const {
  const std::size_t span = u.find_span(t);
  const BasisRows n = u.basis(span, t, 2);
  const std::size_t first = span - static_cast<std::size_t>(u.degree);
  std::array<Eigen::Vector3d, 3> a{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  std::array<double, 3> w{0.0, 0.0, 0.0};
  for (int r = 0; r <= u.degree; ++r) {
    const std::size_t i = first + static_cast<std::size_t>(r);
    const double wi = weights.empty() ? 1.0 : weights[i];
    for (int k = 0; k < 3; ++k) {
      a[k] += n[k][r] * wi * control_points[i];
      w[k] += n[k][r] * wi;
    }
  }
  std::array<Eigen::Vector3d, 3> c;
  c[0] = a[0] / w[0];
  c[1] = (a[1] - w[1] * c[0]) / w[0];
  c[2] = (a[2] - 2.0 * w[1] * c[1] - w[2] * c[0]) / w[0];
  return c;
}

BSplineRows insert_knot(const BSplineRows& spline, double t, int times) {
  const KnotVector& kv = spline.u;
  const int p = kv.degree;
  const auto& up = kv.knots;
  if (times < 0) throw InvalidInput("insert_knot: negative insertion count");
  if (!(t >= kv.domain_min() && t <= kv.domain_max() && t < up.back())) {
    throw InvalidInput("insert_knot: knot " + std::to_string(t) + " outside the parameter domain");
  }
  if (static_cast<std::size_t>(spline.coefficients.rows()) != kv.n_basis()) {
    throw InvalidInput("insert_knot: coefficient rows do not match the knot vector");
  }
  if (times == 0) return spline;
  // k: last index with U_k <= t; s: multiplicity of t.
  const int k = static_cast<int>(std::upper_bound(up.begin(), up.end(), t) - up.begin()) - 1;
  int s = 0;
  for (int i = k; i >= 0 && up[static_cast<std::size_t>(i)] == t; --i) ++s;
  if (s + times > p) throw InvalidInput("insert_knot: multiplicity would exceed the degree");
  const Eigen::MatrixXd& pw = spline.coefficients;
  const int np = static_cast<int>(pw.rows()) - 1;  // last control index
  const int dim = static_cast<int>(pw.cols());

  BSplineRows out;
  out.u.degree = p;
  out.u.knots.reserve(up.size() + static_cast<std::size_t>(times));
  for (int i = 0; i <= k; ++i) out.u.knots.push_back(up[static_cast<std::size_t>(i)]);
  for (int i = 0; i < times; ++i) out.u.knots.push_back(t);
  for (std::size_t i = static_cast<std::size_t>(k) + 1; i < up.size(); ++i) out.u.knots.push_back(up[i]);

  Eigen::MatrixXd& qw = out.coefficients;
  qw.resize(np + 1 + times, dim);
  for (int i = 0; i <= k - p; ++i) qw.row(i) = pw.row(i);
  for (int i = k - s; i <= np; ++i) qw.row(i + times) = pw.row(i);
  Eigen::MatrixXd rw(p - s + 1, dim);
  for (int i = 0; i <= p - s; ++i) rw.row(i) = pw.row(k - p + i);
  int last = 0;
  for (int j = 1; j <= times; ++j) {
    last = k - p + j;
    for (int i = 0; i <= p - j - s; ++i) {
      const double alpha = (t - up[static_cast<std::size_t>(last + i)]) /
                           (up[static_cast<std::size_t>(i + k + 1)] - up[static_cast<std::size_t>(last + i)]);
      rw.row(i) = alpha * rw.row(i + 1) + (1.0 - alpha) * rw.row(i);
    }
    qw.row(last) = rw.row(0);
    qw.row(k + times - j - s) = rw.row(p - j - s);
  }
  for (int i = last + 1; i < k - s; ++i) qw.row(i) = rw.row(i - last);
  return out;
}

}  // namespace nurbsfront
