// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Uniform bicubic B-spline height field z = f(x, y) over a rectangle: the surface that
//! multilevel B-spline approximation produces (Lee, Wolberg & Shin 1997). Evaluation is
//! direct (uniform cubic B-spline weights, no knot search). Exact conversion to a
//! NurbsSurface and exact dyadic refinement.

#include <vector>

#include <Eigen/Core>

#include "nurbsfront/nurbs/nurbs_surface.h"

namespace nurbsfront {

//! Axis-aligned rectangle [min.x, max.x] x [min.y, max.y] in the xy-plane.
struct Rectangle {
  Eigen::Vector2d min = Eigen::Vector2d::Zero();  //!< lower-left corner
  Eigen::Vector2d max = Eigen::Vector2d::Ones();  //!< upper-right corner
  [[nodiscard]] double width() const { return max.x() - min.x(); }
  [[nodiscard]] double height() const { return max.y() - min.y(); }
  [[nodiscard]] double diagonal() const { return (max - min).norm(); }
  //! \throw InvalidInput if a corner is not finite or the width or height is not positive.
  void validate() const;
};

//! f and its first and second partial derivatives at one (x, y).
struct HeightJet {
  double z = 0.0;    //!< f
  double zx = 0.0;   //!< df/dx
  double zy = 0.0;   //!< df/dy
  double zxx = 0.0;  //!< d2f/dx2
  double zxy = 0.0;  //!< d2f/dxdy
  double zyy = 0.0;  //!< d2f/dy2
};

//! f(x, y) = sum_{k,l=0..3} B_k(s) B_l(t) phi_{i+k-1, j+l-1}, with (i, j) the lattice cell holding
//! (x, y), (s, t) in [0, 1] the position inside it and B_k the uniform cubic B-spline pieces.
//! The control lattice has (n_x + 3) x (n_y + 3) coefficients phi_ij, i = -1 .. n_x + 1,
//! j = -1 .. n_y + 1; phi_ij sits at (x_min + i h_x, y_min + j h_y) (its Greville point).
//! Outside the rectangle f continues as the polynomial of the nearest border cell.
class BicubicHeightField {
 public:
  //! An empty field (no lattice); evaluating it is a precondition violation.
  BicubicHeightField() = default;
  //! n_x by n_y cells over `domain`, all coefficients zero.
  //! \throw InvalidInput for an invalid rectangle or a cell count below 1.
  BicubicHeightField(const Rectangle& domain, int n_x, int n_y);

  [[nodiscard]] const Rectangle& domain() const { return domain_; }
  [[nodiscard]] int n_cells_x() const { return n_x_; }
  [[nodiscard]] int n_cells_y() const { return n_y_; }
  [[nodiscard]] double spacing_x() const { return h_x_; }
  [[nodiscard]] double spacing_y() const { return h_y_; }
  [[nodiscard]] bool is_empty() const { return coefficients_.empty(); }

  //! Coefficient phi_ij, -1 <= i <= n_x + 1, -1 <= j <= n_y + 1.
  [[nodiscard]] double coefficient(int i, int j) const { return coefficients_[index(i, j)]; }
  void set_coefficient(int i, int j, double value) { coefficients_[index(i, j)] = value; }
  //! All coefficients, i fastest, starting at phi_{-1,-1}.
  [[nodiscard]] const std::vector<double>& coefficients() const { return coefficients_; }
  [[nodiscard]] std::vector<double>& mutable_coefficients() { return coefficients_; }

  //! f(x, y).
  [[nodiscard]] double value(double x, double y) const;
  //! f and its first and second derivatives.
  [[nodiscard]] HeightJet jet(double x, double y) const;
  //! grad f = (df/dx, df/dy).
  [[nodiscard]] Eigen::Vector2d gradient(double x, double y) const;
  //! First fundamental form of (x, y) -> (x, y, f): the metric I + grad f grad f^T that
  //! measures 3D lengths of xy-plane steps (for meshing in the plane).
  [[nodiscard]] Eigen::Matrix2d metric(double x, double y) const;
  //! Upward unit normal (-f_x, -f_y, 1) / |.|.
  [[nodiscard]] Eigen::Vector3d normal(double x, double y) const;
  //! Vertical lift of (x, y) onto the surface: (x, y, f(x, y)).
  [[nodiscard]] Eigen::Vector3d lift(double x, double y) const { return {x, y, value(x, y)}; }
  //! Derivatives of the parametrisation (x, y) -> (x, y, f(x, y)) (for curvature).
  [[nodiscard]] SurfaceDerivatives derivatives(double x, double y) const;

  //! The same function on a lattice of 2 n_x by 2 n_y cells (exact B-spline subdivision).
  [[nodiscard]] BicubicHeightField refined() const;
  //! Adds another field's coefficients. \pre same domain and cell counts.
  void add(const BicubicHeightField& other);

  //! The exact NURBS form S(u, v) = (x(u), y(v), f(x(u), y(v))), u, v in [0, 1]:
  //! bicubic, clamped knot vectors with n_x (n_y) uniform spans (end knots inserted by
  //! Boehm's algorithm), weights 1, control point x and y at the Greville abscissae.
  //! S(u, v) agrees with lift(x_min + u width, y_min + v height) to round-off.
  [[nodiscard]] NurbsSurface to_nurbs() const;

 private:
  [[nodiscard]] std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j + 1) * static_cast<std::size_t>(n_x_ + 3) + static_cast<std::size_t>(i + 1);
  }

  Rectangle domain_;
  int n_x_ = 0;
  int n_y_ = 0;
  double h_x_ = 0.0;
  double h_y_ = 0.0;
  double inv_h_x_ = 0.0;
  double inv_h_y_ = 0.0;
  std::vector<double> coefficients_;
};

namespace detail {
//! Uniform cubic B-spline pieces B_0..B_3 at s in [0, 1] (they sum to 1).
inline void cubic_weights(double s, double* b) {
  const double s2 = s * s;
  const double s3 = s2 * s;
  const double t = 1.0 - s;
  constexpr double kSixth = 1.0 / 6.0;
  b[0] = t * t * t * kSixth;
  b[1] = (3.0 * s3 - 6.0 * s2 + 4.0) * kSixth;
  b[2] = (-3.0 * s3 + 3.0 * s2 + 3.0 * s + 1.0) * kSixth;
  b[3] = s3 * kSixth;
}

//! A lattice cell along one axis and the local parameter in it.
struct Cell {
  int index;  //!< in [0, n - 1]
  double s;   //!< (x - x0) / h - index; leaves [0, 1] outside the rectangle
};

//! The cell holding coordinate x on a lattice of n cells of width 1 / inv_h from x0,
//! clamped to the border cells (so s extrapolates the border polynomial); NaN gives cell 0
//! and a NaN parameter, never an out-of-range index.
inline Cell locate_cell(double x, double x0, double inv_h, int n) {
  const double f = (x - x0) * inv_h;
  int i = 0;
  if (!(f >= 0.0)) {
    i = 0;
  } else if (f >= static_cast<double>(n)) {
    i = n - 1;
  } else {
    i = static_cast<int>(f);
  }
  return {i, f - static_cast<double>(i)};
}
}  // namespace detail

}  // namespace nurbsfront
