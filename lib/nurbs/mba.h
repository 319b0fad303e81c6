// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Multilevel B-spline approximation (MBA) of scattered data by a uniform bicubic
//! B-spline height field, after S. Lee, G. Wolberg, S. Y. Shin, "Scattered data
//! interpolation with multilevel B-splines", IEEE TVCG 3(3), 1997 (written here from the
//! paper's description).

#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/progress.h"
#include "nurbsfront/nurbs/height_field.h"

namespace nurbsfront {

//! Options of fit_height_field().
struct FitOptions {
  //! Stop adding levels once the maximum |residual| at the points is <= this (unit of z).
  //! 0 (default) means relative_tolerance times the rectangle's diagonal.
  double tolerance = 0.0;
  //! Used when tolerance is 0: tolerance = relative_tolerance * rectangle diagonal. Default 1e-4.
  double relative_tolerance = 1e-4;
  //! Most lattice levels (level 0 included). Default 10 (base_cells * 512 cells at the finest).
  int max_levels = 10;
  //! Smallest allowed lattice spacing (unit of x, y): a level whose cells would be smaller
  //! in x or y is not added. Tie it to the input resolution (a few voxels, a few mean edge
  //! lengths) so that refinement averages a staircase instead of chasing it. Default 0 (off).
  double min_spacing = 0.0;
  //! Cells of the level-0 lattice along the rectangle's shorter side; the longer side gets
  //! proportionally more. Default 1.
  int base_cells = 1;
  //! Largest control lattice (coefficients) a level may have; a level above is not added.
  //! Default 2^22 (32 MiB per lattice).
  std::size_t max_control_points = std::size_t{1} << 22;
  //! Extra B-spline approximation passes on the finest lattice used when a limit (levels,
  //! spacing, size) stopped the refinement before the tolerance was met. Each pass fits the
  //! remaining residual on that same lattice and adds it; the passes converge towards a
  //! weighted least-squares fit at that resolution (so a capped lattice averages a staircase
  //! well instead of stopping at the first, smoothing pass). Default 8; 0 = plain MBA.
  int final_passes = 8;
  //! Conjugate-gradient iterations of a least-squares polish on the finest lattice used,
  //! after the final passes, when a limit stopped the refinement and the tolerance is still
  //! not met. The BA passes converge slowly where the data curve strongly at the lattice's
  //! scale (their smoothing bias is about h^2 f'' / 6 for spacing h: on a sphere patch at a
  //! 60 deg slope, f'' = 8 / radius); the polish minimises
  //! sum_c (f(x_c, y_c) - z_c)^2 + least_squares_smoothing * d * |D2 delta|^2 over the change
  //! delta of the coefficients, D2 the second differences of the lattice (thin plate) and d
  //! the mean data weight of a coefficient, so coefficients without data follow their
  //! neighbours. Jacobi-preconditioned, stops at a relative residual of 1e-8. Default 0 (off).
  int least_squares_iterations = 0;
  //! Weight of the second-difference term of the polish, relative to the mean data weight of
  //! a coefficient (see least_squares_iterations). Default 1e-3.
  double least_squares_smoothing = 1e-3;
  //! Second polish for smooth, well-sampled data (0 = off): when the first polish leaves
  //! every residual within least_squares_fine_below and there are at least as many points as
  //! coefficients with data (a point in their support), a second polish of
  //! least_squares_iterations follows with this (smaller) smoothing. The second-difference
  //! term of the first polish dominates the coefficients at the edge of the data (little
  //! data weight each), which keep the MBA levels' bias there: on a level-set sphere at 128 cells the fit sits 0.05 mean edges
  //! inside the sphere along the patch borders, 30 times its mean error. Rough or
  //! under-resolved data (residuals above the bound: folds, noise, a few points) keep the
  //! first polish's smoothing. Default 0.
  double least_squares_fine_smoothing = 0.0;
  //! Largest residual (unit of z) after the first polish for the second one. Default 0.
  double least_squares_fine_below = 0.0;
  //! Start from the least-squares bilinear function a + bx + cy + dxy (represented exactly by
  //! the bicubic lattice), so planar and bilinear data are reproduced to round-off and the
  //! levels only fit what is left. Default true.
  bool linear_precision = true;
  //! The rectangle the field covers. Default: the points' bounding box. Points outside it
  //! are fitted at their nearest rectangle point (FitResult::n_outside counts them).
  std::optional<Rectangle> domain;
  //! Progress and cancellation (stage "fit", one report per level). Default none.
  ProgressCallback progress;

  //! \throw InvalidInput for negative or non-finite tolerances or spacing, max_levels outside
  //!        [1, 20], base_cells outside [1, 4096], max_control_points < 16, final_passes
  //!        outside [0, 1000], least_squares_iterations outside [0, 100000], a negative
  //!        least_squares_smoothing, least_squares_fine_smoothing or least_squares_fine_below,
  //!        or an invalid domain.
  void validate() const;
};

//! Why fitting stopped adding levels.
enum class FitStop {
  kTolerance,     //!< the maximum residual reached the tolerance
  kLevelLimit,    //!< max_levels levels were used
  kSpacingLimit,  //!< the next level's spacing would be below min_spacing
  kSizeLimit,     //!< the next level's lattice would exceed max_control_points
};

//! Human-readable name of a FitStop ("tolerance", "level limit", ...).
[[nodiscard]] const char* to_string(FitStop stop);

//! Residuals at the points after one level was added.
struct FitLevel {
  int level = 0;             //!< 0 for the coarsest lattice
  int n_cells_x = 0;         //!< lattice cells along x
  int n_cells_y = 0;         //!< lattice cells along y
  double spacing_x = 0.0;    //!< cell width
  double spacing_y = 0.0;    //!< cell height
  double max_residual = 0.0; //!< max |z_c - f(x_c, y_c)| over the points
  double rms_residual = 0.0; //!< root mean square residual
};

//! The fitted field and its residual report.
struct FitResult {
  BicubicHeightField field;        //!< all levels merged into the finest lattice
  std::vector<FitLevel> levels;    //!< one entry per level used, coarsest first
  //! Max residual after each final pass on the finest lattice (see FitOptions::final_passes),
  //! then after the least-squares polish if it ran (FitOptions::least_squares_iterations).
  std::vector<double> final_pass_max_residual;
  double base_max_residual = 0.0;  //!< max residual of the bilinear start (or of 0 without it)
  double tolerance = 0.0;          //!< the absolute tolerance used
  FitStop stop = FitStop::kLevelLimit;  //!< why no further level was added
  std::size_t n_points = 0;        //!< points fitted
  std::size_t n_outside = 0;       //!< points outside the domain rectangle (fitted clamped)
  //! Max residual of the returned field at the points.
  [[nodiscard]] double max_residual() const {
    if (!final_pass_max_residual.empty()) return final_pass_max_residual.back();
    return levels.empty() ? base_max_residual : levels.back().max_residual;
  }
};

//! Fits z = f(x, y) to scattered points (x, y, z) by multilevel B-spline approximation.
//!
//! Algorithm:
//!  1. Validate; rectangle = options.domain or the points' bounding box.
//!  2. Optional linear-precision start: least-squares bilinear g(x, y); residuals r = z - g.
//!  3. Level k (k = 0, 1, ...) has base_cells * 2^k cells along the shorter side. The
//!     B-spline approximation (BA) of the paper: each point proposes, for the 16 coefficients
//!     around it, phi_c = w_c r / sum w^2 (w = tensor cubic B-spline weights); each coefficient
//!     takes the w^2-weighted mean of its proposals (0 where no point reaches). The level's
//!     values are subtracted from the residuals.
//!  4. The merged lattice is refined exactly to the next level's resolution and the level added.
//!  5. Stop when the max residual <= tolerance, or at max_levels, min_spacing or
//!     max_control_points; in the latter cases up to final_passes more BA passes on the
//!     finest lattice fit what is left (until the tolerance is met), then, if asked
//!     (least_squares_iterations), a conjugate-gradient least-squares polish on that lattice.
//! Duplicated points with different z are averaged; clusters and empty regions are fine.
//!
//! \param points  samples (x, y, z); at least 3, not all collinear in the xy-plane.
//! \param options see FitOptions.
//! \return the merged field and the residual after each level.
//! \throw InvalidInput for no points, non-finite coordinates, points that coincide or are
//!        collinear in the xy-plane, a zero-size rectangle or invalid options.
//! \throw Cancelled if the progress callback asks to stop.
//! \cite Lee, Wolberg, Shin 1997.
[[nodiscard]] FitResult fit_height_field(const std::vector<Eigen::Vector3d>& points, const FitOptions& options = {});

}  // namespace nurbsfront
