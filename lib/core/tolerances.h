// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Named tolerances. Geometric ones are relative and scaled by the bounding-box
//! diagonal of the data at hand: never write a bare 1e-9 in an algorithm.
//! Each constant says what it is relative to (its unit); the module-specific ones name the
//! function that uses them. Changing a value changes outputs.

#include <limits>

namespace nurbsfront::tolerance {

//! Points closer than this (times the bbox diagonal) are the same point when welding.
inline constexpr double kWeldRelative = 1e-10;
//! A triangle whose area is below this (times the squared bbox diagonal) is degenerate.
inline constexpr double kDegenerateAreaRelative = 1e-14;
//! A length below this (times the bbox diagonal) is zero.
inline constexpr double kZeroLengthRelative = 1e-12;
//! Relative tolerance of iterative solvers (Newton projection, line searches).
inline constexpr double kSolverRelative = 1e-12;
//! Points whose spread across their main direction is below this fraction of the spread along
//! it are collinear (ratio of standard deviations): no height field or frame over a line
//! (fit_height_field, patch frames).
inline constexpr double kCollinearRelative = 1e-6;

// ---- front2d (advancing front)
//! The Delaunay swap takes a quad only if its incircle determinant exceeds this times the
//! fourth power of the quad's longer diagonal (relative), so near-cocircular quads never
//! ping-pong.
inline constexpr double kIncircleRelative = 1e-12;
//! Slack of the clearance box filter of a new point (AdvancingFront::valid), relative to the
//! clearance plus the point's largest coordinate: far above the distances' rounding (~1e-15).
inline constexpr double kClearanceSlack = 1e-9;
//! Delaunay refinement splits no piece shorter than twice this times the domain's bbox diagonal.
inline constexpr double kRefineMinLengthRelative = 1e-9;

// ---- quality (report)
//! Margin (absolute, on sines and cosines of angles, unitless) by which a triangle's bounds
//! must clear the running angle extremes for the report to skip measuring its angles.
inline constexpr double kAngleBoundMargin = 1e-9;

// ---- io (clean)
//! Relative widening of clean()'s near-a-face band (in grid cells), against rounding in p / cell.
inline constexpr double kNearFaceMargin = 1e-6;

// ---- segment
//! Keeps a seed axis strictly inside the feasible range of slopes instead of on its edge (rad).
inline constexpr double kAngleMarginRad = 1e-6;
//! A face is on a patch's cone (its widest normal) when its normal's dot product with the
//! axis is within this (absolute, unitless) of the smallest one.
inline constexpr double kConeDotSlack = 1e-9;

// ---- nurbs
//! Mean of unit normals shorter than this (per normal, unitless) cancels out: no patch frame.
inline constexpr double kMinMeanNormalLength = 1e-6;
//! Projection onto a surface: a step raising the squared distance by no more than this
//! (relative) still counts as a descent, so it converges to full precision, not sqrt(eps).
inline constexpr double kDescentSlackRelative = 8.0 * std::numeric_limits<double>::epsilon();
//! Least-squares CG polish of the multilevel fit stops at this residual norm relative to
//! the right-hand side's.
inline constexpr double kLeastSquaresCgRelative = 1e-8;
//! A band's direction (band fit) counts as unit when its length is within this of 1 (relative).
inline constexpr double kUnitDirectionRelative = 1e-6;
//! The band fit's preconditioned conjugate gradients stop at this residual norm relative to
//! the right-hand side's.
inline constexpr double kBandPcgRelative = 1e-13;

// ---- surfmesh
//! How far (in lattice cells) a coordinate may be from an integer or a half-integer and still
//! count as one (cell bands: marching cubes puts occupancy vertices at exact midpoints).
inline constexpr double kLatticeCells = 1e-6;
//! A patch's meshed area must match the area inside its border to this (relative) tolerance.
inline constexpr double kMeshedAreaRelative = 1e-9;

// ---- stitch (optimise)
//! Margin (absolute, on sines, unitless) added to an angle floor's sine before a triangle's
//! alpha above sqrt(3) times it lets the optimiser skip computing its sine.
inline constexpr double kSineSkipMargin = 1e-9;
//! A feature node is on a crease piece when within this share of the piece's length of it
//! (slide_sweep).
inline constexpr double kSlideOnCurveRelative = 1e-9;
//! An obtuse split keeps the angles at the edge's ends (the new triangles on the obtuse side
//! have them): their sines, computed again, may fall below the old ones by this (relative)
//! share, a few ulps, and still count as kept (evaluate_split).
inline constexpr double kSplitSineRelative = 1e-9;

}  // namespace nurbsfront::tolerance
