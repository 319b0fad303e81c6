// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal: validation of a PSLG and the faces of its segment arrangement (not installed API).

#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/front2d/pslg.h"

namespace nurbsfront::detail {

//! A validated PSLG with its domain.
struct Domain {
  std::vector<std::array<int, 2>> segments;   //!< deduplicated input segments, then hull edges
  std::vector<int> input_segment;             //!< per Pslg segment: index into segments
  std::vector<std::array<bool, 2>> side_in;   //!< per segment: is the left of a->b / of b->a in the domain
  std::vector<std::array<int, 2>> side_marker;//!< region marker on each side
  std::vector<int> isolated_points;           //!< points on no segment, inside the domain
  std::size_t n_dropped_points = 0;           //!< points on no segment, outside the domain
};

//! Validates the PSLG and finds its domain (see Pslg).
//! \throw InvalidInput with a message naming the problem.
[[nodiscard]] Domain build_domain(const Pslg& pslg, bool enclose_convex_hull);

}  // namespace nurbsfront::detail
