// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/nurbs/height_field.h"

#include <cmath>
#include <string>

#include "nurbsfront/core/error.h"
#include "nurbsfront/nurbs/bspline.h"

namespace nurbsfront {
namespace {

using detail::Cell;
using detail::locate_cell;

inline void cubic_derivative_weights(double s, double* d1, double* d2) {
  const double s2 = s * s;
  d1[0] = -0.5 * (1.0 - s) * (1.0 - s);
  d1[1] = 1.5 * s2 - 2.0 * s;
  d1[2] = -1.5 * s2 + s + 0.5;
  d1[3] = 0.5 * s2;
  d2[0] = 1.0 - s;
  d2[1] = 3.0 * s - 2.0;
  d2[2] = 1.0 - 3.0 * s;
  d2[3] = s;
}

// The weights of the value and of the first and second derivatives along each axis at (x, y),
// and the first of its cell's 4 x 4 coefficients (jet() and gradient()).
struct JetWeights {
  double bx[4], by[4], dx1[4], dx2[4], dy1[4], dy2[4];
  std::size_t stride;
  const double* c;
};
inline JetWeights jet_weights(double x, double y, const Eigen::Vector2d& min, double inv_h_x, double inv_h_y, int n_x,
                              int n_y, const double* coefficients) {
  const Cell cx = locate_cell(x, min.x(), inv_h_x, n_x);
  const Cell cy = locate_cell(y, min.y(), inv_h_y, n_y);
  JetWeights w{};
  detail::cubic_weights(cx.s, w.bx);
  detail::cubic_weights(cy.s, w.by);
  cubic_derivative_weights(cx.s, w.dx1, w.dx2);
  cubic_derivative_weights(cy.s, w.dy1, w.dy2);
  w.stride = static_cast<std::size_t>(n_x) + 3;
  w.c = coefficients + static_cast<std::size_t>(cy.index) * w.stride + static_cast<std::size_t>(cx.index);
  return w;
}

// Knot insertion in integer knot space turns the uniform (unclamped) knots -3 .. n+3
// into the clamped vector 0^4, 1, ..., n-1, n^4; rows are the coefficients along one axis.
Eigen::MatrixXd clamp_uniform(const Eigen::MatrixXd& rows, int n) {
  BSplineRows spline;
  spline.u.degree = 3;
  for (int k = 0; k <= n + 6; ++k) spline.u.knots.push_back(static_cast<double>(k - 3));
  spline.coefficients = rows;
  spline = insert_knot(spline, 0.0, 2);
  spline = insert_knot(spline, static_cast<double>(n), 2);
  // The first and last two coefficients now only act outside [0, n]: drop them.
  return spline.coefficients.middleRows(2, n + 3);
}

}  // namespace

void Rectangle::validate() const {
  if (!min.allFinite() || !max.allFinite()) throw InvalidInput("rectangle: corner is not finite");
  if (!(width() > 0.0) || !(height() > 0.0)) {
    throw InvalidInput("rectangle: zero-size or inverted (width " + std::to_string(width()) + ", height " +
                       std::to_string(height()) + ")");
  }
}

BicubicHeightField::BicubicHeightField(const Rectangle& domain, int n_x, int n_y) : domain_(domain), n_x_(n_x), n_y_(n_y) {
  domain.validate();
  if (n_x < 1 || n_y < 1) throw InvalidInput("height field: cell counts must be at least 1");
  h_x_ = domain.width() / n_x;
  h_y_ = domain.height() / n_y;
  inv_h_x_ = n_x / domain.width();
  inv_h_y_ = n_y / domain.height();
  coefficients_.assign(static_cast<std::size_t>(n_x + 3) * static_cast<std::size_t>(n_y + 3), 0.0);
}

double BicubicHeightField::value(double x, double y) const {
  const Cell cx = locate_cell(x, domain_.min.x(), inv_h_x_, n_x_);
  const Cell cy = locate_cell(y, domain_.min.y(), inv_h_y_, n_y_);
  double bx[4];
  double by[4];
  detail::cubic_weights(cx.s, bx);
  detail::cubic_weights(cy.s, by);
  const std::size_t stride = static_cast<std::size_t>(n_x_) + 3;
  const double* c = coefficients_.data() + static_cast<std::size_t>(cy.index) * stride + static_cast<std::size_t>(cx.index);
  double z = 0.0;
  for (int l = 0; l < 4; ++l, c += stride) {
    z += by[l] * (bx[0] * c[0] + bx[1] * c[1] + bx[2] * c[2] + bx[3] * c[3]);
  }
  return z;
}

HeightJet BicubicHeightField::jet(double x, double y) const {
  const JetWeights w = jet_weights(x, y, domain_.min, inv_h_x_, inv_h_y_, n_x_, n_y_, coefficients_.data());
  const double *bx = w.bx, *by = w.by, *dx1 = w.dx1, *dx2 = w.dx2, *dy1 = w.dy1, *dy2 = w.dy2;
  const std::size_t stride = w.stride;
  const double* c = w.c;
  HeightJet j;
  for (int l = 0; l < 4; ++l, c += stride) {
    double r0 = 0.0;
    double r1 = 0.0;
    double r2 = 0.0;
    for (int k = 0; k < 4; ++k) {
      r0 += bx[k] * c[k];
      r1 += dx1[k] * c[k];
      r2 += dx2[k] * c[k];
    }
    j.z += by[l] * r0;
    j.zx += by[l] * r1;
    j.zxx += by[l] * r2;
    j.zy += dy1[l] * r0;
    j.zxy += dy1[l] * r1;
    j.zyy += dy2[l] * r0;
  }
  j.zx *= inv_h_x_;
  j.zy *= inv_h_y_;
  j.zxx *= inv_h_x_ * inv_h_x_;
  j.zxy *= inv_h_x_ * inv_h_y_;
  j.zyy *= inv_h_y_ * inv_h_y_;
  return j;
}

Eigen::Vector2d BicubicHeightField::gradient(double x, double y) const {
  // jet()'s first derivatives alone, with the same operations in the same order (the same
  // numbers bit for bit): the front2d metric asks for them at every step. The value and
  // derivative weights along x go in pairs (bx_k, dx1_k), so each row's two sums (r0, r1) are
  // one pair of products and additions, and the pair (zy, zx) takes (dy1_l r0, by_l r1).
  const Cell cx = locate_cell(x, domain_.min.x(), inv_h_x_, n_x_);
  const Cell cy = locate_cell(y, domain_.min.y(), inv_h_y_, n_y_);
  double bx[4], by[4], dx1[4], dx2[4], dy1[4], dy2[4];
  detail::cubic_weights(cx.s, bx);
  detail::cubic_weights(cy.s, by);
  cubic_derivative_weights(cx.s, dx1, dx2);
  cubic_derivative_weights(cy.s, dy1, dy2);
  const std::size_t stride = static_cast<std::size_t>(n_x_) + 3;
  const double* c = coefficients_.data() + static_cast<std::size_t>(cy.index) * stride + static_cast<std::size_t>(cx.index);
  const Eigen::Array2d w0(bx[0], dx1[0]), w1(bx[1], dx1[1]), w2(bx[2], dx1[2]), w3(bx[3], dx1[3]);
  Eigen::Array2d z = Eigen::Array2d::Zero();  // (zy, zx)
  for (int l = 0; l < 4; ++l, c += stride) {
    Eigen::Array2d r = Eigen::Array2d::Zero();  // (r0, r1)
    r += w0 * c[0];
    r += w1 * c[1];
    r += w2 * c[2];
    r += w3 * c[3];
    z += Eigen::Array2d(dy1[l], by[l]) * r;
  }
  return {z[1] * inv_h_x_, z[0] * inv_h_y_};
}

Eigen::Matrix2d BicubicHeightField::metric(double x, double y) const {
  const Eigen::Vector2d g = gradient(x, y);
  return Eigen::Matrix2d::Identity() + g * g.transpose();
}

Eigen::Vector3d BicubicHeightField::normal(double x, double y) const {
  const Eigen::Vector2d g = gradient(x, y);
  return Eigen::Vector3d(-g.x(), -g.y(), 1.0).normalized();
}

SurfaceDerivatives BicubicHeightField::derivatives(double x, double y) const {
  const HeightJet j = jet(x, y);
  SurfaceDerivatives d;
  d.point = {x, y, j.z};
  d.su = {1.0, 0.0, j.zx};
  d.sv = {0.0, 1.0, j.zy};
  d.suu = {0.0, 0.0, j.zxx};
  d.suv = {0.0, 0.0, j.zxy};
  d.svv = {0.0, 0.0, j.zyy};
  return d;
}

BicubicHeightField BicubicHeightField::refined() const {
  NURBSFRONT_ASSERT(!is_empty());
  BicubicHeightField fine(domain_, 2 * n_x_, 2 * n_y_);
  // 1D subdivision of the uniform cubic B-spline: fine 2c = (p_{c-1} + 6 p_c + p_{c+1}) / 8,
  // fine 2c+1 = (p_c + p_{c+1}) / 2. First along x into a temporary, then along y.
  const int fx = 2 * n_x_;
  std::vector<double> tmp(static_cast<std::size_t>(fx + 3) * static_cast<std::size_t>(n_y_ + 3));
  const auto t_index = [fx](int i, int j) {
    return static_cast<std::size_t>(j + 1) * static_cast<std::size_t>(fx + 3) + static_cast<std::size_t>(i + 1);
  };
  for (int j = -1; j <= n_y_ + 1; ++j) {
    for (int c = 0; c <= n_x_; ++c) {
      tmp[t_index(2 * c, j)] = (coefficient(c - 1, j) + 6.0 * coefficient(c, j) + coefficient(c + 1, j)) * 0.125;
    }
    for (int c = -1; c <= n_x_; ++c) tmp[t_index(2 * c + 1, j)] = (coefficient(c, j) + coefficient(c + 1, j)) * 0.5;
  }
  for (int i = -1; i <= fx + 1; ++i) {
    for (int c = 0; c <= n_y_; ++c) {
      fine.set_coefficient(i, 2 * c, (tmp[t_index(i, c - 1)] + 6.0 * tmp[t_index(i, c)] + tmp[t_index(i, c + 1)]) * 0.125);
    }
    for (int c = -1; c <= n_y_; ++c) fine.set_coefficient(i, 2 * c + 1, (tmp[t_index(i, c)] + tmp[t_index(i, c + 1)]) * 0.5);
  }
  return fine;
}

void BicubicHeightField::add(const BicubicHeightField& other) {
  NURBSFRONT_ASSERT(other.n_x_ == n_x_ && other.n_y_ == n_y_ && other.coefficients_.size() == coefficients_.size());
  for (std::size_t k = 0; k < coefficients_.size(); ++k) coefficients_[k] += other.coefficients_[k];
}

NurbsSurface BicubicHeightField::to_nurbs() const {
  NURBSFRONT_ASSERT(!is_empty());
  const int nx3 = n_x_ + 3;
  const int ny3 = n_y_ + 3;
  // Lattice as a matrix: rows along x, columns along y. Clamp along x, then along y.
  Eigen::MatrixXd lattice(nx3, ny3);
  for (int j = 0; j < ny3; ++j)
    for (int i = 0; i < nx3; ++i) lattice(i, j) = coefficient(i - 1, j - 1);
  const Eigen::MatrixXd along_x = clamp_uniform(lattice, n_x_);
  const Eigen::MatrixXd both = clamp_uniform(along_x.transpose(), n_y_).transpose();

  NurbsSurface s;
  const auto clamped_knots = [](int n) {
    KnotVector kv;
    kv.degree = 3;
    kv.knots.assign(4, 0.0);
    for (int k = 1; k < n; ++k) kv.knots.push_back(static_cast<double>(k) / n);
    for (int k = 0; k < 4; ++k) kv.knots.push_back(1.0);
    return kv;
  };
  s.u = clamped_knots(n_x_);
  s.v = clamped_knots(n_y_);
  s.n_u = static_cast<std::size_t>(nx3);
  s.n_v = static_cast<std::size_t>(ny3);
  // Greville abscissae (t_{i+1} + t_{i+2} + t_{i+3}) / 3 reproduce x(u) = x_min + u width exactly.
  const auto greville = [](const KnotVector& kv, std::size_t i) {
    return (kv.knots[i + 1] + kv.knots[i + 2] + kv.knots[i + 3]) / 3.0;
  };
  s.control_points.resize(s.n_u * s.n_v);
  for (std::size_t j = 0; j < s.n_v; ++j) {
    const double y = domain_.min.y() + greville(s.v, j) * domain_.height();
    for (std::size_t i = 0; i < s.n_u; ++i) {
      const double x = domain_.min.x() + greville(s.u, i) * domain_.width();
      s.control_points[j * s.n_u + i] = {x, y, both(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j))};
    }
  }
  s.weights.assign(s.control_points.size(), 1.0);
  return s;
}

}  // namespace nurbsfront
