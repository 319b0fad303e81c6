// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! B-spline basis functions (Cox-de Boor recursion, span search) for any degree up to
//! kMaxDegree, knot insertion, and rational B-spline (NURBS) curves. Algorithms follow
//! Piegl & Tiller, "The NURBS Book" (2nd ed., 1997), A2.1-A2.3, A4.2, A5.1, written here
//! from the book's description.

#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace nurbsfront {

//! Highest supported polynomial degree (fixed-size work arrays, no allocation per evaluation).
inline constexpr int kMaxDegree = 15;
//! Highest derivative order returned by the evaluators.
inline constexpr int kMaxDerivativeOrder = 2;

//! Values (row 0) and derivatives (rows 1, 2) of the p + 1 basis functions that are
//! non-zero on one knot span: entry [k][r] is the k-th derivative of N_{span-p+r,p}.
using BasisRows = std::array<std::array<double, kMaxDegree + 1>, kMaxDerivativeOrder + 1>;

//! A knot vector U_0 <= ... <= U_{m} for B-splines of one degree p.
struct KnotVector {
  int degree = 3;              //!< polynomial degree p, 1 <= p <= kMaxDegree
  std::vector<double> knots;   //!< non-decreasing knot values

  //! Number of basis functions (= control points): knots.size() - p - 1.
  [[nodiscard]] std::size_t n_basis() const { return knots.size() - static_cast<std::size_t>(degree) - 1; }
  //! Parameter domain [U_p, U_n].
  [[nodiscard]] double domain_min() const { return knots[static_cast<std::size_t>(degree)]; }
  [[nodiscard]] double domain_max() const { return knots[n_basis()]; }

  //! Checks the vector for a B-spline with n_control coefficients.
  //! \throw InvalidInput naming `what` if the degree is outside [1, kMaxDegree], the size is
  //!        not n_control + p + 1, a knot is not finite, the knots decrease, an interior
  //!        knot has multiplicity above p + 1 or the domain [U_p, U_n] is empty.
  void validate(std::size_t n_control, const char* what) const;

  //! Index i of the knot span [U_i, U_{i+1}) holding u, p <= i <= n_basis() - 1 (binary
  //! search). u is clamped to the domain; u at its end belongs to the last non-empty span.
  //! \pre validate() passed.
  [[nodiscard]] std::size_t find_span(double u) const;

  //! The p + 1 basis functions that are non-zero on `span`, and their first n_derivatives
  //! derivatives (n_derivatives <= kMaxDerivativeOrder; rows above are left zero).
  //! Cox-de Boor triangular scheme; the values are >= 0 and sum to 1.
  [[nodiscard]] BasisRows basis(std::size_t span, double u, int n_derivatives = 0) const;
};

//! A NURBS curve C(u) = sum N_i,p(u) w_i P_i / sum N_i,p(u) w_i in 3D; a B-spline curve when
//! all weights are 1 (the default when `weights` is left empty).
struct NurbsCurve {
  KnotVector u;                                //!< degree and knots, size n + p + 1
  std::vector<Eigen::Vector3d> control_points; //!< n control points P_i
  std::vector<double> weights;                 //!< n positive weights w_i, or empty for all 1

  //! \throw InvalidInput for a bad degree or knot vector, no or non-finite control points,
  //!        weights that are not positive and finite or of the wrong count.
  void validate() const;
  [[nodiscard]] bool is_rational() const;
  //! C(u); u is clamped to the domain. \pre validate() passed.
  [[nodiscard]] Eigen::Vector3d evaluate(double u) const;
  //! C(u), C'(u), C''(u) (rational quotient rule). \pre validate() passed.
  [[nodiscard]] std::array<Eigen::Vector3d, 3> derivatives(double u) const;
};

//! A B-spline function of one variable with coefficients of any dimension (one row
//! each); rational data goes in homogeneous form (rows w P, w).
struct BSplineRows {
  KnotVector u;                   //!< degree and knots
  Eigen::MatrixXd coefficients;   //!< n_basis() rows
};

//! Inserts the knot t `times` times (Boehm / NURBS Book A5.1). The function represented
//! is unchanged; the returned spline has `times` more knots and coefficient rows.
//! \throw InvalidInput if t is outside the domain or its multiplicity would exceed p.
[[nodiscard]] BSplineRows insert_knot(const BSplineRows& spline, double t, int times);

}  // namespace nurbsfront
