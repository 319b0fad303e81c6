// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Named tolerances. Geometric ones are relative and scaled by the bounding-box
//! diagonal of the data at hand: never write a bare 1e-9 in an algorithm.

namespace nurbsfront::tolerance {

//! Points closer than this (times the bbox diagonal) are the same point when welding.
inline constexpr double kWeldRelative = 1e-10;
//! A triangle whose area is below this (times the squared bbox diagonal) is degenerate.
inline constexpr double kDegenerateAreaRelative = 1e-14;
//! A length below this (times the bbox diagonal) is zero.
inline constexpr double kZeroLengthRelative = 1e-12;
//! Relative tolerance of iterative solvers (Newton projection, line searches).
inline constexpr double kSolverRelative = 1e-12;

}  // namespace nurbsfront::tolerance
