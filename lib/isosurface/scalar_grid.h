// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! ScalarGrid: samples of a scalar field on a regular, axis-aligned 3D grid (the input of
//! marching cubes: CT volumes, level sets, occupancy voxels).

#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/soup.h"

namespace nurbsfront {

//! A scalar field sampled at the points origin + (i, j, k) .* spacing, 0 <= i < dims[0], ...
//! Values are stored x fastest: index = i + dims[0] * (j + dims[1] * k).
struct ScalarGrid {
  std::array<int, 3> dims{0, 0, 0};                      //!< number of samples along x, y, z
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();      //!< position of sample (0, 0, 0)
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones();     //!< distance between samples along x, y, z (> 0)
  std::vector<float> values;                             //!< dims[0] * dims[1] * dims[2] samples, x fastest

  //! Number of samples (product of dims, 0 if a dim is not positive).
  [[nodiscard]] std::size_t size() const;
  //! Linear index of sample (i, j, k). \pre 0 <= i < dims[0], ... (not checked).
  [[nodiscard]] std::size_t index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(dims[0]) * (static_cast<std::size_t>(j) + static_cast<std::size_t>(dims[1]) * static_cast<std::size_t>(k));
  }
  //! Value of sample (i, j, k). \pre indices in range (not checked).
  [[nodiscard]] float value(int i, int j, int k) const { return values[index(i, j, k)]; }
  //! Position of sample (i, j, k) (any integers; no range check).
  [[nodiscard]] Eigen::Vector3d point(int i, int j, int k) const {
    return origin + Eigen::Vector3d(i, j, k).cwiseProduct(spacing);
  }
  //! Box spanned by the sample points.
  [[nodiscard]] BoundingBox bounds() const;
  //! Smallest and largest value (both 0 for an empty grid).
  [[nodiscard]] std::array<float, 2> value_range() const;
  //! \throw InvalidInput unless every dim >= 1, values.size() equals the product of dims,
  //! spacing is finite and positive, origin is finite and every value is finite.
  void validate() const;
};

}  // namespace nurbsfront
