// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Exact geometric predicates on double coordinates: a floating-point evaluation with a
//! static error bound (Shewchuk's stage-A bounds) that falls back to exact expansion
//! arithmetic (error-free sums and products) when the sign is uncertain.
//! \cite Shewchuk 1997, "Adaptive precision floating-point arithmetic and fast robust
//! geometric predicates".

#include <Eigen/Core>

#include "nurbsfront/core/predicates.h"

namespace nurbsfront::quality_detail {

//! Sign of det[a - d; b - d; c - d]: +1 when d lies below the plane of (a, b, c) seen
//! with (a, b, c) counter-clockwise from above, -1 above, 0 exactly on it.
int orient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
             const Eigen::Vector3d& d);

//! Sign of det[a - c; b - c] in 2D: +1 if (a, b, c) turns counter-clockwise, 0 if collinear
//! (the front's exact orient2d, nurbsfront/core/predicates.h).
using nurbsfront::orient2d;

}  // namespace nurbsfront::quality_detail
