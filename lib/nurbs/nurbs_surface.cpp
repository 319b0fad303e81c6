// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/nurbs/nurbs_surface.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"

namespace nurbsfront {

void NurbsSurface::validate() const {
  if (n_u == 0 || n_v == 0) throw InvalidInput("NURBS surface: empty control net");
  u.validate(n_u, "NURBS surface (u)");
  v.validate(n_v, "NURBS surface (v)");
  if (control_points.size() != n_u * n_v) {
    throw InvalidInput("NURBS surface: " + std::to_string(control_points.size()) + " control points for a " +
                       std::to_string(n_u) + " x " + std::to_string(n_v) + " net");
  }
  for (std::size_t k = 0; k < control_points.size(); ++k) {
    if (!control_points[k].allFinite()) {
      throw InvalidInput("NURBS surface: control point (" + std::to_string(k % n_u) + ", " +
                         std::to_string(k / n_u) + ") is not finite");
    }
  }
  if (!weights.empty()) {
    if (weights.size() != control_points.size()) {
      throw InvalidInput("NURBS surface: " + std::to_string(weights.size()) + " weights for " +
                         std::to_string(control_points.size()) + " control points");
    }
    for (std::size_t k = 0; k < weights.size(); ++k) {
      if (!(weights[k] > 0.0) || !std::isfinite(weights[k])) {
        throw InvalidInput("NURBS surface: weight (" + std::to_string(k % n_u) + ", " + std::to_string(k / n_u) +
                           ") is not positive and finite");
      }
    }
  }
}

bool NurbsSurface::is_rational() const {
  return std::any_of(weights.begin(), weights.end(), [this](double w) { return w != weights.front(); });
}

Eigen::Vector3d NurbsSurface::evaluate(double s, double t) const {
  const std::size_t span_u = u.find_span(s);
  const std::size_t span_v = v.find_span(t);
  const BasisRows nu = u.basis(span_u, s);
  const BasisRows nv = v.basis(span_v, t);
  const std::size_t iu = span_u - static_cast<std::size_t>(u.degree);
  const std::size_t jv = span_v - static_cast<std::size_t>(v.degree);
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  double w = 0.0;
  for (int l = 0; l <= v.degree; ++l) {
    const std::size_t j = jv + static_cast<std::size_t>(l);
    Eigen::Vector3d row = Eigen::Vector3d::Zero();
    double row_w = 0.0;
    for (int k = 0; k <= u.degree; ++k) {
      const std::size_t i = iu + static_cast<std::size_t>(k);
      const double nw = nu[0][k] * weight(i, j);
      row += nw * control_point(i, j);
      row_w += nw;
    }
    a += nv[0][l] * row;
    w += nv[0][l] * row_w;
  }
  return a / w;
}

SurfaceDerivatives NurbsSurface::derivatives(double s, double t) const {
  const std::size_t span_u = u.find_span(s);
  const std::size_t span_v = v.find_span(t);
  const BasisRows nu = u.basis(span_u, s, 2);
  const BasisRows nv = v.basis(span_v, t, 2);
  const std::size_t iu = span_u - static_cast<std::size_t>(u.degree);
  const std::size_t jv = span_v - static_cast<std::size_t>(v.degree);
  // Homogeneous derivatives A^(k,l) (weighted points) and w^(k,l), k + l <= 2.
  Eigen::Vector3d a[3][3];
  double w[3][3] = {};
  for (auto& row : a)
    for (auto& x : row) x.setZero();
  for (int l = 0; l <= v.degree; ++l) {
    const std::size_t j = jv + static_cast<std::size_t>(l);
    Eigen::Vector3d tmp[3] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    double tmp_w[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k <= u.degree; ++k) {
      const std::size_t i = iu + static_cast<std::size_t>(k);
      const double wij = weight(i, j);
      const Eigen::Vector3d pw = wij * control_point(i, j);
      for (int du = 0; du < 3; ++du) {
        tmp[du] += nu[du][k] * pw;
        tmp_w[du] += nu[du][k] * wij;
      }
    }
    for (int du = 0; du < 3; ++du) {
      for (int dv = 0; du + dv < 3; ++dv) {
        a[du][dv] += nv[dv][l] * tmp[du];
        w[du][dv] += nv[dv][l] * tmp_w[du];
      }
    }
  }
  SurfaceDerivatives d;
  const double w0 = w[0][0];
  d.point = a[0][0] / w0;
  d.su = (a[1][0] - w[1][0] * d.point) / w0;
  d.sv = (a[0][1] - w[0][1] * d.point) / w0;
  d.suu = (a[2][0] - 2.0 * w[1][0] * d.su - w[2][0] * d.point) / w0;
  d.svv = (a[0][2] - 2.0 * w[0][1] * d.sv - w[0][2] * d.point) / w0;
  d.suv = (a[1][1] - w[1][0] * d.sv - w[0][1] * d.su - w[1][1] * d.point) / w0;
  return d;
}

Eigen::Vector3d NurbsSurface::normal(double s, double t) const {
  const SurfaceDerivatives d = derivatives(s, t);
  const Eigen::Vector3d n = d.su.cross(d.sv);
  const double len = n.norm();
  return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

SurfaceCurvature NurbsSurface::curvature(double s, double t) const {
  return curvature_from_derivatives(derivatives(s, t));
}

SurfaceCurvature curvature_from_derivatives(const SurfaceDerivatives& d) {
  SurfaceCurvature c;
  const Eigen::Vector3d cross = d.su.cross(d.sv);
  const double len = cross.norm();
  const double e = d.su.dot(d.su);
  const double f = d.su.dot(d.sv);
  const double g = d.sv.dot(d.sv);
  const double det = e * g - f * f;
  // A degenerate parametrisation (collapsed edge, pole) has no tangent plane.
  if (!(len > 0.0) || !(det > 0.0)) return c;
  c.normal = cross / len;
  const double l = d.suu.dot(c.normal);
  const double m = d.suv.dot(c.normal);
  const double n = d.svv.dot(c.normal);
  // Shape operator W = I^-1 II in the (Su, Sv) basis; its eigenvalues are k1, k2.
  Eigen::Matrix2d first;
  first << e, f, f, g;
  Eigen::Matrix2d second;
  second << l, m, m, n;
  const Eigen::Matrix2d shape = first.inverse() * second;
  c.gaussian = (l * n - m * m) / det;
  c.mean = (e * n - 2.0 * f * m + g * l) / (2.0 * det);
  const double disc = std::sqrt(std::max(0.0, c.mean * c.mean - c.gaussian));
  c.k1 = c.mean + disc;
  c.k2 = c.mean - disc;
  // Principal directions: eigenvectors of the shape operator mapped to 3D.
  const auto direction = [&](double k) {
    const Eigen::Matrix2d a = shape - k * Eigen::Matrix2d::Identity();
    // Null vector of the 2x2 matrix a: take the row with the larger norm.
    Eigen::Vector2d r = a.row(0).norm() >= a.row(1).norm() ? Eigen::Vector2d(a.row(0)) : Eigen::Vector2d(a.row(1));
    Eigen::Vector2d x(-r.y(), r.x());
    if (!(x.norm() > 0.0)) x = Eigen::Vector2d(1.0, 0.0);
    Eigen::Vector3d dir = x.x() * d.su + x.y() * d.sv;
    return Eigen::Vector3d(dir.normalized());
  };
  c.direction1 = direction(c.k1);
  c.direction2 = direction(c.k2);
  if (disc == 0.0) {  // umbilic: any orthonormal pair of tangents
    c.direction1 = d.su.normalized();
    c.direction2 = c.normal.cross(c.direction1);
  }
  return c;
}

NurbsSurface NurbsSurface::transformed(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) const {
  NurbsSurface out = *this;
  for (auto& p : out.control_points) p = rotation * p + translation;
  return out;
}

}  // namespace nurbsfront
