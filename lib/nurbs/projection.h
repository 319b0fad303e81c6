// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Point projection onto NURBS surfaces: closest point by Newton iteration on the
//! squared distance, safeguarded by a sampled start and a backtracking line search.
//! (For height fields the vertical lift is BicubicHeightField::lift().)

#include <optional>

#include <Eigen/Core>

#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/nurbs/nurbs_surface.h"

namespace nurbsfront {

//! Options of closest_point().
struct ProjectionOptions {
  //! Samples per knot span and direction for the start point (when no initial guess). Default 4.
  int samples_per_span = 4;
  //! Newton iterations at most. Default 30.
  int max_iterations = 30;
  //! Converged when a step moves the surface point by less than this times the control
  //! net's bounding-box diagonal. Default tolerance::kSolverRelative (1e-12).
  double relative_tolerance = tolerance::kSolverRelative;
  //! Start from this (u, v) instead of sampling. Default none.
  std::optional<Eigen::Vector2d> initial_guess;
  //! \throw InvalidInput for samples_per_span < 1, max_iterations < 1, a tolerance that is
  //!        not positive and finite or a non-finite initial guess.
  void validate() const;
};

//! Result of closest_point().
struct ClosestPoint {
  double u = 0.0;                                   //!< parameter of the closest point
  double v = 0.0;                                   //!< parameter of the closest point
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  //!< S(u, v)
  double distance = 0.0;                            //!< |S(u, v) - query|
  int iterations = 0;                               //!< Newton iterations done
  bool converged = false;  //!< the step criterion was met (else: best point found is returned)
};

//! Closest point of the surface to `query` (a local minimum of the distance near the best
//! sample; the global one when the sampling resolves the surface).
//!
//! Algorithm: best of a sample grid (or the initial guess); Newton steps on
//! D(u, v) = |S(u, v) - q|^2 / 2 with the exact Hessian, replaced by the Gauss-Newton
//! matrix when not positive definite; each step is halved until D decreases (never worse
//! than the start); parameters are clamped to the domain (border minima are found).
//! \throw InvalidInput for a non-finite query or invalid options. \pre surface.validate() passed.
[[nodiscard]] ClosestPoint closest_point(const NurbsSurface& surface, const Eigen::Vector3d& query,
                                         const ProjectionOptions& options = {});

}  // namespace nurbsfront
