// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Exact triangle-triangle intersection tests (internal to the quality module).

#include <array>
#include <cstdint>

#include <Eigen/Core>

namespace nurbsfront::quality_detail {

//! True if the closed segment [a, b] meets the closed, non-degenerate triangle (p, q, r).
bool segment_meets_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& p,
                            const Eigen::Vector3d& q, const Eigen::Vector3d& r);

//! True if two non-degenerate triangles given by vertex ids and points intersect beyond
//! what they share: vertices with equal ids are shared. Triangles on the same three ids
//! are reported as not intersecting (they are duplicates, counted elsewhere).
bool triangles_intersect(const std::array<std::uint32_t, 3>& ids1, const std::array<Eigen::Vector3d, 3>& t1,
                         const std::array<std::uint32_t, 3>& ids2, const std::array<Eigen::Vector3d, 3>& t2);

}  // namespace nurbsfront::quality_detail
