// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal: validation of a PSLG and the faces of its segment arrangement (not installed API).

#include <algorithm>
#include <array>
#include <cstddef>
#include <functional>
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
  std::size_t n_hull_edges_followed = 0;      //!< convex hull edges left out: the input follows them within the gap
  double hull_gap_area = 0.0;                 //!< area of the strips between those edges and the input
};

//! Euclidean distance from x to the closed segment uw (to u when u == w).
[[nodiscard]] inline double distance_to_segment(const Eigen::Vector2d& x, const Eigen::Vector2d& u, const Eigen::Vector2d& w) {
  const Eigen::Vector2d d = w - u;
  const double l2 = d.squaredNorm();
  const double t = l2 > 0 ? std::clamp((x - u).dot(d) / l2, 0.0, 1.0) : 0.0;
  return (u + t * d - x).norm();
}

//! Validates the PSLG and finds its domain (see Pslg). With enclose_convex_hull and a
//! hull_gap function, a convex hull edge ab is left out when the input segments join a to b
//! through points closer to ab than hull_gap(point), every input point that close to ab being
//! on such a path: the input is the domain's boundary there, and the strip between it and the
//! edge (narrower than the gap) is not part of the domain.
//! \throw InvalidInput with a message naming the problem.
[[nodiscard]] Domain build_domain(const Pslg& pslg, bool enclose_convex_hull,
                                  const std::function<double(const Eigen::Vector2d&)>& hull_gap = {});

}  // namespace nurbsfront::detail
