// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Point in polygon in the plane (segment's projection checks, surfmesh's patch domains).

#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace nurbsfront {

//! Even-odd point-in-polygon test (floating point) of q against the closed polygon of the n
//! points point(0), ..., point(n - 1) (either orientation; point(i) returns an
//! Eigen::Vector2d or a reference to one). False for n < 3 (no crossing).
template <class PointAt>
[[nodiscard]] bool polygon_contains(std::size_t n, const PointAt& point, const Eigen::Vector2d& q) {
  if (n < 3) return false;
  bool inside = false;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Eigen::Vector2d& a = point(i);
    const Eigen::Vector2d& b = point(j);
    if ((a.y() > q.y()) != (b.y() > q.y()) && q.x() < a.x() + (q.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y()))
      inside = !inside;
  }
  return inside;
}

//! polygon_contains() of the polygon with these corners.
[[nodiscard]] inline bool polygon_contains(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& q) {
  return polygon_contains(polygon.size(), [&](std::size_t i) -> const Eigen::Vector2d& { return polygon[i]; }, q);
}

}  // namespace nurbsfront
