// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Band-constrained height-field fit: z = f(x, y) fitted to samples that are segments
//! ("bands") rather than points. Made for cell-based (0/1 occupancy) marching-cubes
//! surfaces: each vertex is the midpoint of a grid edge between an inside and an outside
//! cell centre, so the true surface crosses that edge somewhere within half a cell of the
//! vertex. A least-squares fit of the vertices reproduces the terraces' bias (a wide top
//! terrace stays flat while the truth bulges up to half a cell above it); the band fit asks
//! only that the surface cross every band, and otherwise be smooth.
//!
//! In the spirit of S. F. F. Gibson, "Constrained elastic surface nets", MERL TR 99-24 /
//! MICCAI 1998 (relax, then clamp each node into its cell), here as a penalised spline fit.

#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/nurbs/height_field.h"

namespace nurbsfront {

//! One sample: the segment [point - half_length direction, point + half_length direction],
//! or the point itself when half_length is 0.
struct BandSample {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();      //!< centre (the marching-cubes vertex)
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  //!< unit direction (any when half_length is 0)
  double half_length = 0.0;                             //!< >= 0; 0 = a plain point sample
};

//! Options of fit_height_field_to_bands().
struct BandFitOptions {
  //! Lattice cell size (unit of x, y), > 0. About one or two cells of the occupancy grid:
  //! the smoothness comes from smoothing_length, not from a coarse lattice. Required: the
  //! default 0 is refused by validate().
  double spacing = 0.0;
  //! Length (unit of x, y) over which the third derivatives of f are penalised (the energy
  //! integral of l^6 (f_xxx^2 + 3 f_xxy^2 + 3 f_xyy^2 + f_yyy^2) times the sample density over
  //! the lattice cells holding samples). Its null
  //! space is the quadrics, so the fit continues curvature over a flat terrace instead of
  //! flattening it. >= 0. Default 0 = 1.5 x spacing (with spacing 1.5 cells: 2.25 cells,
  //! measured best on terraced sphere caps between 1.5 and 2.5 cells).
  double smoothing_length = 0.0;
  //! Weight of every sample's pull towards its centre point, relative to the weight 1 of a
  //! band the surface misses (and of a point sample). In [0, 1]. Small: the centres of a
  //! terraced input are biased; the bands carry the information. Default 0.02.
  double centre_weight = 0.02;
  //! Weight of a missed band (its nearer end), relative to a point sample's 1: large, so
  //! the bands act nearly as hard constraints where the smoothness prior is biased (the
  //! steep flanks of a small tube). >= 1. Default 20.
  double band_weight = 20.0;
  //! Active-set iterations at most per pass (each one is a sparse least-squares solve). Default 20.
  int max_iterations = 20;
  //! Refits after the first fit, each with the third-derivative prior pulled towards the
  //! third derivatives that a surface of the previous fit's slope and curvature with a
  //! parallel second fundamental form (sphere, cylinder) has, instead of towards 0. In
  //! [0, 10]. Default 0.
  int curvature_passes = 0;
  //! The rectangle the field covers. Default: the bounding box of the sample centres.
  std::optional<Rectangle> domain;
  //! Warm start: when set, the fit starts from this field (sampled onto the fit's lattice by
  //! the cubic B-spline quasi-interpolant) instead of from the plain penalised fit of the
  //! band centres. The minimum is the same (the objective is convex); a start close to it
  //! (a fit of most of the same samples) saves active-set solves. Not owned; must outlive
  //! the call. Default none.
  const BicubicHeightField* start = nullptr;
  //! If >= 0 and the fit before the curvature passes misses no band by more than this
  //! (unit of z), that fit is returned without the passes (BandFitResult::passes 0): for a
  //! caller that refits such patches anyway. Default -1 (never).
  double skip_passes_max_miss = -1.0;

  //! \throw InvalidInput for a non-positive or non-finite spacing, a negative smoothing
  //!        length, centre_weight outside [0, 1], max_iterations outside [1, 1000], an
  //!        invalid domain, a start field without coefficients or with a non-finite one,
  //!        or a NaN skip_passes_max_miss.
  void validate() const;
};

//! The fitted field and how well it meets the bands.
struct BandFitResult {
  BicubicHeightField field;
  int iterations = 0;             //!< solves done
  bool converged = false;         //!< the set of missed bands stopped changing
  std::size_t n_bands = 0;        //!< samples with half_length > 0
  std::size_t n_missed = 0;       //!< bands the final surface does not cross
  //! Largest vertical distance |z_end - f(x_end, y_end)| at the nearer end of a missed band.
  double max_miss = 0.0;
  //! Largest |z - f(x, y)| at a point sample (0 if there is none).
  double max_point_residual = 0.0;
  //! Curvature passes done (fewer than asked when skip_passes_max_miss applied).
  int passes = 0;
};

//! Fits z = f(x, y) (uniform bicubic B-spline) so that it crosses every band, stays near
//! the point samples and is smooth.
//!
//! Minimises  band_weight sum_bands dist(f, band)^2 + sum_points (f - z)^2
//!          + centre_weight sum_bands (f(x_c, y_c) - z_c)^2 + lambda E3(f),
//! where dist(f, band) is 0 when the band's ends lie on opposite sides of the surface
//! (z_end - f(x_end, y_end) changes sign) and otherwise the vertical residual at the nearer
//! end; E3 penalises the third differences of the coefficients (a P-spline, Eilers & Marx
//! 1996) with lambda from smoothing_length and the sample density. The first solve pulls
//! every band to its centre (a plain penalised fit of the centres). Then a damped active-set
//! Newton iteration: solve with the currently missed bands pulled to their nearer ends, halve
//! the step until the objective decreases, re-test every band; stop when a full step keeps
//! the set of missed bands, when no step decreases the objective, or at max_iterations.
//!
//! \param samples at least 3 not collinear in xy; finite; unit direction where half_length > 0.
//! \throw InvalidInput for bad samples or options.
//! \throw SolverError if the sparse solve fails.
[[nodiscard]] BandFitResult fit_height_field_to_bands(const std::vector<BandSample>& samples,
                                                      const BandFitOptions& options);

//! Where the segment of a sample meets z = f(x, y): the sign change of z - f along it, found
//! by bisection (returns true and the crossing), or the nearer end when there is none
//! (returns false and that end). A point sample returns true and the point.
[[nodiscard]] bool band_target(const BicubicHeightField& field, const BandSample& sample, Eigen::Vector3d& target);

}  // namespace nurbsfront
