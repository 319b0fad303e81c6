// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Tensor-product NURBS surfaces: the source paper's equation (1),
//!   S(u,v) = sum_i sum_j N_i,p(u) N_j,q(v) w_ij P_ij / sum_i sum_j N_i,p(u) N_j,q(v) w_ij,
//! with first and second partial derivatives (rational quotient rule, NURBS Book A4.4),
//! unit normal and the principal, mean and Gaussian curvatures.

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/nurbs/bspline.h"

namespace nurbsfront {

//! S and its partial derivatives at one (u, v).
struct SurfaceDerivatives {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  //!< S
  Eigen::Vector3d su = Eigen::Vector3d::Zero();     //!< dS/du
  Eigen::Vector3d sv = Eigen::Vector3d::Zero();     //!< dS/dv
  Eigen::Vector3d suu = Eigen::Vector3d::Zero();    //!< d2S/du2
  Eigen::Vector3d suv = Eigen::Vector3d::Zero();    //!< d2S/dudv
  Eigen::Vector3d svv = Eigen::Vector3d::Zero();    //!< d2S/dv2
};

//! Curvatures at one point. Signs follow the unit normal n = Su x Sv / |Su x Sv|: a
//! curvature is positive where the surface bends towards n (a sphere with n pointing
//! inwards has k1 = k2 = +1/R; with n outwards, -1/R).
struct SurfaceCurvature {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  //!< unit normal n
  double k1 = 0.0;        //!< larger principal curvature
  double k2 = 0.0;        //!< smaller principal curvature
  double mean = 0.0;      //!< H = (k1 + k2) / 2
  double gaussian = 0.0;  //!< K = k1 k2
  Eigen::Vector3d direction1 = Eigen::Vector3d::Zero();  //!< unit principal direction of k1 (3D)
  Eigen::Vector3d direction2 = Eigen::Vector3d::Zero();  //!< unit principal direction of k2 (3D)
};

//! A rational B-spline surface of degrees p (in u) and q (in v). Control points are stored
//! with u fastest: P_ij at index j * n_u + i.
struct NurbsSurface {
  KnotVector u;                                 //!< degree p and knots in u (n_u + p + 1)
  KnotVector v;                                 //!< degree q and knots in v (n_v + q + 1)
  std::size_t n_u = 0;                          //!< control points along u
  std::size_t n_v = 0;                          //!< control points along v
  std::vector<Eigen::Vector3d> control_points;  //!< n_u * n_v points, u fastest
  std::vector<double> weights;                  //!< n_u * n_v positive weights, or empty for all 1

  //! \throw InvalidInput for wrongly sized or non-monotone knot vectors, a degree outside
  //!        [1, kMaxDegree], a control net of the wrong size, non-finite control points or
  //!        weights that are not positive and finite. The message names the problem.
  void validate() const;

  [[nodiscard]] const Eigen::Vector3d& control_point(std::size_t i, std::size_t j) const {
    return control_points[j * n_u + i];
  }
  [[nodiscard]] double weight(std::size_t i, std::size_t j) const {
    return weights.empty() ? 1.0 : weights[j * n_u + i];
  }
  //! True if the weights are not all equal (all-equal weights give a polynomial surface).
  [[nodiscard]] bool is_rational() const;

  //! S(u, v); parameters are clamped to the domain. \pre validate() passed.
  [[nodiscard]] Eigen::Vector3d evaluate(double s, double t) const;
  //! S with first and second partial derivatives at (u, v). \pre validate() passed.
  [[nodiscard]] SurfaceDerivatives derivatives(double s, double t) const;
  //! Unit normal Su x Sv / |Su x Sv|; zero at a degenerate point (e.g. a collapsed edge).
  [[nodiscard]] Eigen::Vector3d normal(double s, double t) const;
  //! Principal, mean and Gaussian curvature from the first and second fundamental forms.
  //! At a degenerate point (Su x Sv = 0) everything is zero.
  [[nodiscard]] SurfaceCurvature curvature(double s, double t) const;

  //! The same surface after p -> R p + t applied to every control point (NURBS are
  //! affinely invariant, so this is exact).
  [[nodiscard]] NurbsSurface transformed(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) const;
};

//! Curvatures from given derivatives (shared by NurbsSurface and the height field).
[[nodiscard]] SurfaceCurvature curvature_from_derivatives(const SurfaceDerivatives& d);

}  // namespace nurbsfront
